"""Old against new in one process: the residual (sag) passes of the Newton search on surfaces
with polynomial terms (``tracing.step._polynomial_root`` and ``continue_newton``).

    python tools/bench_newton_passes.py [--baseline REV] [--repeats N] [--compiles N]
                                        [--only CASE ...]

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


def _cellphone6_rays(pkg, n=262_144):
    lens = pkg.zoo.cellphone6().astype(jnp.float32)
    rng = np.random.default_rng(0)
    r = np.sqrt(rng.uniform(0, 1, n))
    a = rng.uniform(0, 2 * np.pi, n)
    pupil = jnp.asarray(np.stack([r * np.cos(a), r * np.sin(a)], -1), jnp.float32)
    third = n // 3
    rays = [pkg.sampling.collimated(lens, float(f), pupil[i * third:(i + 1) * third])
            for i, f in enumerate((0.0, 20.0, 40.0))]
    origin = jnp.concatenate([q.origin for q in rays])
    direction = jnp.concatenate([q.direction for q in rays])
    return lens, pkg.Rays(origin, direction, lens.primary_wavelength)


def forward_case(pkg, chunk=65_536):
    lens, rays = _cellphone6_rays(pkg)

    def fn(lens, rays):
        out = pkg.trace(lens, rays, chunk=chunk)
        return out.origin, out.valid

    return fn, lens, rays


def grad_case(pkg, chunk=65_536):
    lens, rays = _cellphone6_rays(pkg)

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


def _time(fn, x, y):
    c0, t0 = time.process_time(), time.perf_counter()
    jax.block_until_ready(fn(x, y))
    return time.perf_counter() - t0, time.process_time() - c0


def _same(a, b):
    la, lb = jax.tree.leaves(a), jax.tree.leaves(b)
    return len(la) == len(lb) and all(
        np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True)
        for x, y in zip(la, lb, strict=True))


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
    res = {"bit_for_bit": _same(outs["old"], outs["new"]), "hlo": counts,
           "compile_s": _summary(compile_s["old"], compile_s["new"]) | {"all": compile_s}}
    wall, cpu = {"old": [], "new": []}, {"old": [], "new": []}
    for k in range(repeats):
        for tag in (("old", "new") if k % 2 == 0 else ("new", "old")):
            w, c = _time(exes[tag], *args[tag])
            wall[tag].append(w)
            cpu[tag].append(c)
    if repeats:
        res["calls"] = repeats
        res["wall_ms"] = _summary(wall["old"], wall["new"], 1e3)
        res["cpu_ms"] = _summary(cpu["old"], cpu["new"], 1e3)
    res["first_output_sum"] = float(np.sum(np.asarray(jax.tree.leaves(outs["new"])[0],
                                                      np.float64)))
    return res


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default="main")
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--compiles", type=int, default=3)
    ap.add_argument("--only", nargs="*", choices=sorted(CASES), default=None)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    old = import_baseline(a.baseline)
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
