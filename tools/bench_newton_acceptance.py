"""Old against new in one process: the Newton acceptance of ``tracing.step.intersect``
(|F| ≤ τ and now also |F/F'| ≤ τ) on the hot path, and that the common case is unchanged.

    python tools/bench_newton_acceptance.py [--baseline REV] [--repeats N]

Imports the ``jaxlens`` of git revision REV (default: ``main``) side by side with the working
tree's (``benchmarks.design_step.import_baseline``) and times, interleaved, per call (wall and
process-CPU time, median and paired median of new/old):

* the classical design step, ``jit(vmap(value_and_grad))`` over 4 seeds, float32
  (``benchmarks.design_step.step_fn``);
* cellphone6's forward trace, 262143 float32 rays (a third each at fields 0/20/40°, uniform
  in the pupil disc), chunk 65536.

Before timing it checks that both give the same numbers bit for bit (loss, gradient, image
points and validity). Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import jaxlens  # noqa: E402
from benchmarks.design_step import import_baseline, step_fn  # noqa: E402


def cellphone6_rays(pkg, n=262_144):
    """cellphone6 in float32 and ``n`` rays over its pupil (a fixed random disc), a third each
    at 0, 20 and 40 degrees, built with ``pkg`` (this tree's jaxlens or a baseline's)."""
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


def forward_fn(pkg, n=262_144, chunk=65_536):
    lens, rays = cellphone6_rays(pkg, n)
    fn = jax.jit(lambda lens, rays: (lambda o: (o.origin, o.valid))(
        pkg.trace(lens, rays, chunk=chunk)))
    return fn, lens, rays


def time_call(fn, x, y):
    """(wall s, process CPU s) of one call of ``fn(x, y)``, to its results."""
    c0, t0 = time.process_time(), time.perf_counter()
    jax.block_until_ready(fn(x, y))
    return time.perf_counter() - t0, time.process_time() - c0


def same_leaves(a, b):
    """Whether two pytrees hold equal arrays leaf for leaf, bit for bit (NaNs equal)."""
    la, lb = jax.tree.leaves(a), jax.tree.leaves(b)
    return len(la) == len(lb) and all(
        np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True)
        for x, y in zip(la, lb, strict=True))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default="main")
    ap.add_argument("--repeats", type=int, default=40)
    ap.add_argument("--forward-repeats", type=int, default=15)
    args = ap.parse_args()
    old = import_baseline(args.baseline)
    out = {"baseline": args.baseline, "load_start": os.getloadavg()[0]}
    cases = {}
    for name, make, reps in (("design_step", lambda p: step_fn(p, 4), args.repeats),
                             ("cellphone6_forward", forward_fn, args.forward_repeats)):
        fo, xo, yo = make(old)
        fn, xn, yn = make(jaxlens)
        ro, rn = fo(xo, yo), fn(xn, yn)
        jax.block_until_ready((ro, rn))
        same = same_leaves(ro, rn)
        wall = {"old": [], "new": []}
        cpu = {"old": [], "new": []}
        for k in range(reps):
            order = (("old", fo, xo, yo), ("new", fn, xn, yn))
            for tag, f, x, y in (order if k % 2 == 0 else order[::-1]):
                w, c = time_call(f, x, y)
                wall[tag].append(w)
                cpu[tag].append(c)
        res = {"bit_for_bit": same, "calls": reps}
        for kind, d in (("wall", wall), ("cpu", cpu)):
            mo, mn = statistics.median(d["old"]), statistics.median(d["new"])
            paired = statistics.median([b / a for a, b in zip(d["old"], d["new"], strict=True)])
            res[kind] = {"old_ms": 1e3 * mo, "new_ms": 1e3 * mn, "new_over_old_median": mn / mo,
                         "new_over_old_paired": paired}
        if name == "design_step":
            res["loss_sum"] = [float(jnp.sum(ro[0])), float(jnp.sum(rn[0]))]
        else:
            res["valid"] = [int(ro[1].sum()), int(rn[1].sum())]
        cases[name] = res
    out["cases"] = cases
    out["load_end"] = os.getloadavg()[0]
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
