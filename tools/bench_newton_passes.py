"""Old against new in one process: the residual (sag) passes of the Newton search on surfaces
with polynomial terms (``tracing.step._polynomial_root`` and ``continue_newton``).

    python tools/bench_newton_passes.py [--baseline REV] [--repeats N] [--compiles N]
                                        [--only CASE ...]
    python tools/bench_newton_passes.py --bit-for-bit [--baseline REV]

Imports the ``jaxlens`` of git revision REV (default: ``main``) side by side with the working
tree's (``benchmarks.design_step.import_baseline``) and, for each case,

* checks that both give the same numbers bit for bit (every output leaf);
* compiles each ``--compiles`` times, alternating old and new, each time from cleared caches
  (``jax.clear_caches``: trace, lower and compile, as a fresh process would), and counts the
  optimized HLO's instructions, fusions and while loops (``Compiled.as_text()``);
* times the calls, interleaved (the order swapped every call), wall and process-CPU time:
  median per call and the median of the paired new/old ratios.

Cases (float32):

* ``cellphone6_forward``: cellphone6's forward trace of 262143 rays (a third each at fields
  0/20/40°, uniform in the pupil disc), chunk 65536: image points and validity;
* ``cellphone6_grad``: the same rays, value and gradient (with respect to the lens) of the
  summed squared image radius of the valid rays, ``trace(..., reverse_rule=True)``;
* ``design_step``: the classical design step, ``jit(vmap(value_and_grad))`` over 4 seeds
  (``benchmarks.design_step.step_fn``).

Prints one JSON object (and writes it to ``--out`` if given).

``--bit-for-bit`` (float64 enabled, no timing) instead compares, leaf for leaf: cellphone6's
image points, validity and optical path at 0/20/40° (3000 rays each) and the gradient of its
summed squared image radius at 40°, with and without ``reverse_rule``; the classical design's
loss and gradient (4 seeds) at every curriculum stage; the EDoF lens (its ``Hybrid``
surface with a cubic term) at 0 and 15°, points, validity and gradient; each in float32 and
float64. Takes about 7 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import jaxlens  # noqa: E402
from benchmarks.design_step import import_baseline, step_fn  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from bench_newton_acceptance import (  # noqa: E402
    cellphone6_rays,
    same_leaves,
    time_call,
)


def forward_case(pkg, chunk=65_536):
    lens, rays = cellphone6_rays(pkg)

    def fn(lens, rays):
        out = pkg.trace(lens, rays, chunk=chunk)
        return out.origin, out.valid

    return fn, lens, rays


def grad_case(pkg, chunk=65_536):
    lens, rays = cellphone6_rays(pkg)

    def loss(lens, rays):
        out = pkg.trace(lens, rays, chunk=chunk, reverse_rule=True)
        r2 = out.origin[:, 0] ** 2 + out.origin[:, 1] ** 2
        return jnp.sum(jnp.where(out.valid, r2, 0.0))

    return jax.value_and_grad(loss), lens, rays


def design_case(pkg):
    fn, params, args = step_fn(pkg, 4)
    return fn.__wrapped__, params, args  # compile_fresh jits it


CASES = {"cellphone6_forward": forward_case, "cellphone6_grad": grad_case,
         "design_step": design_case}


def hlo_counts(text: str) -> dict:
    """Instructions, fusions and while loops of an optimized HLO module's text."""
    ins = [line for line in text.splitlines() if re.match(r"\s+(ROOT )?%\S+ = ", line)]
    return {"instructions": len(ins),
            "fusions": sum(" fusion(" in line for line in ins),
            "whiles": sum(" while(" in line for line in ins),
            "chars": len(text)}


def compile_fresh(fn, x, y):
    """(executable, seconds to trace, lower and compile from cleared caches)."""
    jax.clear_caches()
    t0 = time.perf_counter()
    exe = jax.jit(fn).lower(x, y).compile()
    return exe, time.perf_counter() - t0


def _summary(old, new, scale=1.0):
    """Medians (times ``scale``), their ratio new/old and the median of paired ratios."""
    mo, mn = statistics.median(old), statistics.median(new)
    paired = statistics.median([b / a for a, b in zip(old, new, strict=True)])
    return {"old": scale * mo, "new": scale * mn, "new_over_old_median": mn / mo,
            "new_over_old_paired": paired}


def run_case(name, make, old, repeats, compiles):
    versions = {"old": make(old), "new": make(jaxlens)}
    exes, compile_s, counts = {}, {"old": [], "new": []}, {}
    for k in range(compiles):
        for tag in (("old", "new") if k % 2 == 0 else ("new", "old")):
            exe, secs = compile_fresh(*versions[tag])
            exes[tag] = exe
            compile_s[tag].append(secs)
            counts[tag] = hlo_counts(exe.as_text())
    args = {tag: versions[tag][1:] for tag in versions}
    outs = {tag: exes[tag](*args[tag]) for tag in exes}
    jax.block_until_ready(outs)
    res = {"bit_for_bit": same_leaves(outs["old"], outs["new"]), "hlo": counts,
           "compile_s": _summary(compile_s["old"], compile_s["new"]) | {"all": compile_s}}
    wall, cpu = {"old": [], "new": []}, {"old": [], "new": []}
    for k in range(repeats):
        for tag in (("old", "new") if k % 2 == 0 else ("new", "old")):
            w, c = time_call(exes[tag], *args[tag])
            wall[tag].append(w)
            cpu[tag].append(c)
    if repeats:
        res["calls"] = repeats
        res["wall_ms"] = _summary(wall["old"], wall["new"], 1e3)
        res["cpu_ms"] = _summary(cpu["old"], cpu["new"], 1e3)
    res["first_output_sum"] = float(np.sum(np.asarray(jax.tree.leaves(outs["new"])[0],
                                                      np.float64)))
    return res


def _cellphone6_checked(pkg, dtype, reverse_rule, n=3000):
    lens = pkg.zoo.cellphone6().astype(dtype)
    rng = np.random.default_rng(0)
    r, a = np.sqrt(rng.uniform(0, 1, n)), rng.uniform(0, 2 * np.pi, n)
    pupil = jnp.asarray(np.stack([r * np.cos(a), r * np.sin(a)], -1), dtype)
    points = []
    for field in (0.0, 20.0, 40.0):
        rays = pkg.sampling.collimated(lens, field, pupil)
        out = jax.jit(lambda lens, rays: pkg.trace(lens, rays))(lens, rays)
        points.append((out.origin, out.valid, out.opl))

    def loss(lens, rays):
        out = pkg.trace(lens, rays, reverse_rule=reverse_rule)
        return jnp.sum(jnp.where(out.valid, out.origin[:, 0] ** 2 + out.origin[:, 1] ** 2, 0.0))

    return points, jax.jit(jax.value_and_grad(loss))(lens, rays)


def _design_checked(pkg, dtype, seeds=4):
    import importlib

    mod = lambda name: importlib.import_module(f"{pkg.__name__}.design{name}")  # noqa: E731
    design, ms, cur = mod(""), mod(".multistart"), mod(".curriculum")
    losses, init = mod(".losses"), mod(".init")
    spec, config = design.DesignSpec(), ms.DesignConfig()
    sampling = losses.RayLoss.make(config.n_fields, config.rings, spec.wavelengths,
                                   spec.sensor_size, dtype)
    objective = losses.Objective(init.parameterization(spec, dtype), sampling,
                                 jnp.asarray(init.gap_bounds(spec), dtype))
    objective = ms.make_solver_factory(config, spec, dtype)("adam", 1.0, objective).residual_fn
    params = init.random_starts(spec, list(range(seeds)), dtype)

    def loss(p, a):
        return jnp.sum(objective(p, a)[0] ** 2)

    step = jax.jit(jax.vmap(jax.value_and_grad(loss)))
    weights = jnp.ones((seeds, config.n_fields), dtype)
    return [step(params, cur.stage_args(spec, stage, weights, config.reg_weights, dtype))
            for stage in config.stages(spec)]


def _edof_checked(pkg, dtype):
    import importlib

    lenses = importlib.import_module(pkg.__name__ + ".experiments.edof.lenses")
    lens = lenses.to_hybrid(lenses.classical_lens(), cubic=2e-4).astype(dtype)
    pupil = jnp.asarray(np.random.default_rng(1).uniform(-0.7, 0.7, (2000, 2)), dtype)

    def loss(lens, rays):
        out = pkg.trace(lens, rays)
        return jnp.sum(jnp.where(out.valid, out.origin[:, 1] ** 2, 0.0))

    outs = []
    for field in (0.0, 15.0):
        rays = pkg.sampling.collimated(lens, field, pupil)
        out = jax.jit(lambda lens, rays: pkg.trace(lens, rays))(lens, rays)
        outs.append(((out.origin, out.valid), jax.jit(jax.grad(loss))(lens, rays)))
    return outs


def bit_for_bit(old) -> dict:
    """{check: whether old and new agree leaf for leaf} (see the module notes)."""
    jax.config.update("jax_enable_x64", True)
    res = {}
    for dtype in (jnp.float32, jnp.float64):
        tag = jnp.dtype(dtype).name
        for rr in (False, True):
            res[f"cellphone6_{tag}_reverse_rule_{rr}"] = same_leaves(
                _cellphone6_checked(old, dtype, rr), _cellphone6_checked(jaxlens, dtype, rr))
        res[f"design_{tag}"] = same_leaves(_design_checked(old, dtype),
                                           _design_checked(jaxlens, dtype))
        res[f"edof_{tag}"] = same_leaves(_edof_checked(old, dtype), _edof_checked(jaxlens, dtype))
    return res


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default="main")
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--compiles", type=int, default=3)
    ap.add_argument("--only", nargs="*", choices=sorted(CASES), default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--bit-for-bit", action="store_true")
    a = ap.parse_args(argv)
    old = import_baseline(a.baseline)
    if a.bit_for_bit:
        out = {"baseline": a.baseline, "bit_for_bit": bit_for_bit(old)}
        print(json.dumps(out, indent=1))
        return out
    out = {"baseline": a.baseline, "cpu_count": os.cpu_count(),
           "load_start": os.getloadavg()[0], "cases": {}}
    for name in a.only or CASES:
        out["cases"][name] = run_case(name, CASES[name], old, a.repeats, a.compiles)
        out["cases"][name]["load_after"] = os.getloadavg()[0]
    out["load_end"] = os.getloadavg()[0]
    text = json.dumps(out, indent=1)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    return out


if __name__ == "__main__":
    main()
