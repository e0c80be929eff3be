"""Probe: the reversible trace's gradient against the per-surface reverse rule, interleaved.

``jaxlens.trace(..., reverse_rule="reversible")`` traces a lens of ``Standard`` surfaces as one
``jax.custom_vjp`` whose forward keeps only each surface's root t and refraction gain g and
whose backward rebuilds each surface's incident rays from the rays after it
(``jaxlens.tracing.reversible``): no stored rays per surface, no checkpointed chunk, no
forward recompute. This probe checks its value and float64 gradient against JAX's derivative
and the per-surface rule (``reverse_rule=True``) and central differences, and times, compiled
once each and interleaved in one process (best of N), the forward, f+g with the per-surface
rule (default chunk) and f+g reversible for each ``--chunk`` (0: one piece), with the
throughput benchmark's rays and spot loss.

    python -m benchmarks.reversible_probe --check
    python -m benchmarks.reversible_probe --repeats 9 --chunk 65536 262144 0 --json out.json
"""

from __future__ import annotations

import json
import os
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)  # as in the throughput benchmark: float64 setup

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.tracing.forward import CHUNK  # noqa: E402

from . import throughput  # noqa: E402
from .vjp_probe import _max_rel  # noqa: E402


def _loss(lens, rays, chunk, rule):
    out = jaxlens.trace(lens, rays, chunk=chunk, reverse_rule=rule)
    return throughput.spot_loss(out.origin[:, :2], out.valid)


def _grad(chunk, rule):
    return eqx.filter_jit(lambda lens, rays: eqx.filter_value_and_grad(_loss)(
        lens, rays, chunk, rule))


def check(n=20_000, chunk=4096, pupil_scale=1.3, lens_name="cooke_triplet"):
    """Float64, pupil overfilled so some rays are clipped: values, gradients (reversible
    against JAX's derivative and the per-surface rule), central differences; and float32
    gradients of each against float64."""
    lens = zoo.ZOO[lens_name]().astype(jnp.float64)
    rays = throughput.make_rays(lens, n, jnp.float64, pupil_scale=pupil_scale)
    out = {}
    got = {r: _grad(chunk, r)(lens, rays) for r in (False, True, "reversible")}
    out["rev_vs_jax"] = _max_rel(got[False], got["reversible"])
    out["rev_vs_rule"] = _max_rel(got[True], got["reversible"])
    out["rule_vs_jax"] = _max_rel(got[False], got[True])
    a = jaxlens.trace(lens, rays, chunk=chunk)
    b = jaxlens.trace(lens, rays, chunk=chunk, reverse_rule="reversible")
    out["values_identical"] = all(bool(jnp.all(x == y)) for x, y in
                                  zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True))
    print(f"{n} rays, pupil ×{pupil_scale} (valid {float(jnp.mean(a.valid)):.2f}), float64: "
          f"values identical {out['values_identical']}; gradient max |Δ|/max|·| per leaf: "
          f"reversible vs JAX {out['rev_vs_jax']:.1e}, vs rule {out['rev_vs_rule']:.1e}, "
          f"rule vs JAX {out['rule_vs_jax']:.1e}")
    loss = eqx.filter_jit(_loss)
    for name, where, h in (("surfaces[2].c", lambda m: m.surfaces[2].c, 1e-7),
                           ("surfaces[4].k", lambda m: m.surfaces[4].k, 1e-5),
                           ("thickness[1]", lambda m: m.thickness, 1e-6)):
        def at(delta, where=where):
            x = where(lens)
            return eqx.tree_at(where, lens, x.at[1].add(delta) if x.ndim else x + delta)

        central = (float(loss(at(h), rays, chunk, False))
                   - float(loss(at(-h), rays, chunk, False))) / (2 * h)
        pick = (lambda g, where=where: float(where(g[1]).reshape(-1)[
            1 if where(lens).ndim else 0]))
        out[name] = (central, pick(got["reversible"]), pick(got[False]))
        print(f"  d loss / d {name}: central {central:.10e}, reversible "
              f"{out[name][1]:.10e}, JAX {out[name][2]:.10e}")
    l32, r32 = lens.astype(jnp.float32), throughput.make_rays(lens, n, jnp.float32,
                                                               pupil_scale=pupil_scale)
    for r in (False, True, "reversible"):
        g32 = _grad(chunk, r)(l32, r32)
        out[f"f32_vs_f64_{r}"] = _max_rel(got[False], g32)
        print(f"  float32 gradient ({r}) against float64: {out[f'f32_vs_f64_{r}']:.2e}")
    return out


def timing(n=1_000_000, repeats=9, chunks=(CHUNK,), dtype=jnp.float32,
           lens_name="cooke_triplet"):
    """Forward, f+g rule (default chunk), f+g reversible per chunk: compiled first, then
    timed interleaved, best of ``repeats``."""
    lens = zoo.ZOO[lens_name]()
    rays = throughput.make_rays(lens, n, dtype)
    progs = {"forward": eqx.filter_jit(lambda lens, rays: jaxlens.trace(lens, rays)),
             "f+g rule": _grad("auto", True)}
    for c in chunks:
        progs[f"f+g reversible chunk={c or None}"] = _grad(c or None, "reversible")
    res = {}
    for name, f in progs.items():  # compile and warm
        res[name] = jax.block_until_ready(f(lens, rays))
        jax.block_until_ready(f(lens, rays))
    best = dict.fromkeys(progs, np.inf)
    loads = []
    for _ in range(repeats):
        loads.append(os.getloadavg()[0])
        for name, f in progs.items():
            t0 = time.perf_counter()
            jax.block_until_ready(f(lens, rays))
            best[name] = min(best[name], time.perf_counter() - t0)
    out = {"lens": lens_name, "rays": n, "dtype": jnp.dtype(dtype).name, "repeats": repeats,
           "load": [min(loads), max(loads)], "ms": {k: 1e3 * v for k, v in best.items()}}
    print(f"{lens_name}, {n} rays, {out['dtype']}, best of {repeats}, load "
          f"{min(loads):.1f}-{max(loads):.1f}")
    for name in progs:
        extra = ""
        if name != "forward":
            extra = (f"  f+g/forward rate {best['forward'] / best[name]:.3f}; gradient vs "
                     f"rule {_max_rel(res['f+g rule'], res[name]):.1e}")
        print(f"  {name}: {1e3 * best[name]:.1f} ms{extra}")
    out["ratio"] = {k: best["forward"] / v for k, v in best.items() if k != "forward"}
    return out


def main(argv=None):
    from jaxlens.experiments.runfolder import OneLineParser

    from .common import out_path, whole

    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="values, gradients and FD")
    ap.add_argument("--rays", type=whole(1, "rays"), default=1_000_000)
    ap.add_argument("--lens", choices=tuple(zoo.ZOO), default="cooke_triplet")
    ap.add_argument("--repeats", type=whole(1, "repeats"), default=9)
    ap.add_argument("--chunk", nargs="+", type=whole(0, "rays per chunk"), default=[CHUNK],
                    help="chunk sizes of the reversible trace to time (0: one piece)")
    ap.add_argument("--json", type=out_path(make_parents=False),
                    help="also write the results to this JSON file")
    a = ap.parse_args(argv)
    out = (check(lens_name=a.lens) if a.check
           else timing(a.rays, a.repeats, tuple(a.chunk), jnp.float32, a.lens))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(dict(out, command="python -m benchmarks.reversible_probe "
                           + " ".join(sys.argv[1:] if argv is None else argv)), fh, indent=1,
                      default=str)


if __name__ == "__main__":
    main()
