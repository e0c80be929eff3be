"""Numbers for the extreme-toroid intersection (tests/test_toroid_extreme.py, the report).

    PYTHONPATH=$PWD python tools/toroid_extreme_reference.py OUT.npz

1. The synthetic extreme toroid of the test (c = 0.01 /mm, a_1 = 80 /mm, a cylinder): rays
   with a forward root (brute force: first sign change on a grid, bisected) that
   ``intersect`` misses at 6, 7, 8 Newton steps, and the largest |t − root| of its hits.
2. An ordinary toroid (c = 0.025 /mm, k = −0.4, a_1 = 1e-3, a_2 = −2e-6, cx = 0.04 /mm,
   the lens of tests/test_toroid_paraxial.py's files) traced by ``jaxlens.trace``: 200 000
   rays; the median of 20 timed runs (jit compiled before), and the image points and
   optical paths saved to OUT.npz, to compare two versions of the tracer bit for bit.
No third-party tool: the reference is the brute-force root.
"""

from __future__ import annotations

import io
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402
from jaxlens.optics.toroidal import Toroidal  # noqa: E402
from jaxlens.tracing.step import intersect, unmark  # noqa: E402


def extreme():
    sys.path.insert(0, "tests")
    import test_toroid_extreme as t  # the test's fan and brute-force root

    surface = Toroidal(**t.EXTREME)
    o, d = t._fan()
    roots = np.array([t._first_root(oi, di) for oi, di in zip(o, d, strict=True)])
    for iters in (6, 7, 8):
        tt, ok = unmark(intersect(surface, tuple(jnp.asarray(o.T)), tuple(jnp.asarray(d.T)),
                                  iters))
        tt, ok = np.asarray(tt), np.asarray(ok)
        print(f"extreme toroid, {iters} Newton steps: {np.isfinite(roots).sum()} rays with a "
              f"root, {ok.sum()} hits, {(np.isfinite(roots) & ~ok).sum()} missed with a root, "
              f"{(ok & ~np.isfinite(roots)).sum()} hit without one, max |t - root| "
              f"{np.max(np.abs(tt[ok] - roots[ok])):.2e} mm")


def ordinary(out: str):
    tor = Toroidal(c=0.025, k=-0.4, coeffs=jnp.array([1e-3, -2e-6]), cx=0.04)
    lens = jl.Lens((tor, jl.Plane()), jnp.array([4.0, 60.0]),
                   (jl.ModelGlass(1.5, np.inf), jl.Air()), epd=8.0)
    rng = np.random.default_rng(0)
    m = 200_000
    xy = rng.uniform(-3.5, 3.5, (m, 2))
    o = np.concatenate([xy, np.full((m, 1), -1.0)], 1)
    v = np.concatenate([rng.uniform(-0.05, 0.05, (m, 2)), np.ones((m, 1))], 1)
    rays = jl.Rays(jnp.asarray(o), jnp.asarray(v / np.linalg.norm(v, axis=1, keepdims=True)),
                   0.5876)
    run = jax.jit(lambda r: jl.trace(lens, r))
    res = run(rays)
    jax.block_until_ready(res)
    times = []
    for _ in range(20):
        t0 = time.perf_counter()
        jax.block_until_ready(run(rays))
        times.append(time.perf_counter() - t0)
    print(f"ordinary toroid, {m} rays through jl.trace: median {np.median(times) * 1e3:.1f} ms "
          f"(min {np.min(times) * 1e3:.1f}), valid {int(np.asarray(res.valid).sum())}")
    npz = io.BytesIO()
    np.savez(npz, origin=np.asarray(res.origin), opl=np.asarray(res.opl),  # in memory
             direction=np.asarray(res.direction), valid=np.asarray(res.valid))
    write_whole(out if out.endswith(".npz") else out + ".npz", npz.getvalue())  # as np.savez
    # A tenth of the rays with no root (outside the sweep: |x| > 1/cx = 25 mm on the
    # toroid): they cannot converge, and must not make the others wait.
    o2 = o.copy()
    o2[: m // 10, 0] = 30.0
    rays2 = jl.Rays(jnp.asarray(o2), rays.direction, 0.5876)
    res2 = run(rays2)
    jax.block_until_ready(res2)
    times = []
    for _ in range(20):
        t0 = time.perf_counter()
        jax.block_until_ready(run(rays2))
        times.append(time.perf_counter() - t0)
    print(f"ordinary toroid, {m} rays, a tenth with no root: median "
          f"{np.median(times) * 1e3:.1f} ms (min {np.min(times) * 1e3:.1f}), valid "
          f"{int(np.asarray(res2.valid).sum())}")


if __name__ == "__main__":
    extreme()
    ordinary(sys.argv[1] if len(sys.argv) > 1 else "/tmp/toroid_ordinary.npz")
