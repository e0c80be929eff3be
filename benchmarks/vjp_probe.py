"""Probe: the trace's gradient with and without the hand-written reverse rule, chunk by chunk.

``jaxlens.trace(..., reverse_rule=True)`` moves plane, sphere and conic surfaces with
``jaxlens.tracing.surface_adjoint.reverse_step`` and surfaces with polynomial terms with
``reverse_sag_step``: ``jax.custom_vjp``s whose backward is written out by hand (the implicit
root and the Snell adjoint, from the saved root t and refraction gain g). This probe
compiles, for each chunk size, the forward trace, its forward + gradient with JAX's own
derivative, and with the rule, and times them interleaved in one process (best of N), on a
zoo lens (``--lens``, the Cooke triplet by default; ``cellphone6`` has 12 even aspheres,
``sag_step``'s case) with the throughput benchmark's rays and spot loss.
It also checks that the rule's values and gradients are JAX's (float64) and counts the fused
kernels per loop body, the measure that explained the rule's speed (benchmarks/SPEED.md).

    python -m benchmarks.vjp_probe --check                       # values, gradients, FD
    python -m benchmarks.vjp_probe --repeats 9 --chunk 65536 16384 --json out.json
    python -m benchmarks.vjp_probe --fusions --chunk 65536
    python -m benchmarks.vjp_probe --lens cellphone6 --repeats 9
"""

from __future__ import annotations

import json
import os
import re
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)  # as in the throughput benchmark: float64 setup

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402
from jaxlens.tracing.forward import CHUNK  # noqa: E402

from . import throughput  # noqa: E402


def _loss(lens, rays, chunk, reverse_rule):
    out = jaxlens.trace(lens, rays, chunk=chunk, reverse_rule=reverse_rule)
    return throughput.spot_loss(out.origin[:, :2], out.valid)


def programs(chunk):
    """{name: compiled-on-first-call function (lens, rays)}: forward, f+g default, f+g rule."""
    def grad(rule):
        return eqx.filter_jit(lambda lens, rays: eqx.filter_value_and_grad(_loss)(
            lens, rays, chunk, rule))

    return {
        f"forward chunk={chunk}": eqx.filter_jit(
            lambda lens, rays: jaxlens.trace(lens, rays, chunk=chunk)),
        f"f+g default chunk={chunk}": grad(False),
        f"f+g reverse_rule chunk={chunk}": grad(True),
    }


def _max_rel(ref, other):
    """max over leaves of max |Δ| / max |ref|; a leaf below 1e-6 of the largest (rounding
    noise, such as a flat stop's curvature at ~1e-10) is measured against 1e-6 of it."""
    leaves = [(np.asarray(a, np.float64), np.asarray(b, np.float64))
              for a, b in zip(jax.tree.leaves(ref), jax.tree.leaves(other), strict=True)]
    top = max((float(np.max(np.abs(a), initial=0.0)) for a, _ in leaves), default=0.0)
    worst = 0.0
    for a, b in leaves:
        scale = max(float(np.max(np.abs(a), initial=0.0)), 1e-6 * top)
        if scale > 0:
            worst = max(worst, float(np.max(np.abs(a - b), initial=0.0)) / scale)
    return worst


def check(n=20_000, chunk=4096, pupil_scale=1.3, lens_name="cooke_triplet"):
    """Float64, some rays clipped (pupil overfilled by ``pupil_scale``): the rule's value and
    gradient against JAX's derivative, and both against central differences.

    Returns {"grad_rel": ..., "fd": {parameter: (central difference, rule, default)}}."""
    lens = zoo.ZOO[lens_name]().astype(jnp.float64)
    rays = throughput.make_rays(lens, n, jnp.float64, pupil_scale=pupil_scale)
    rule = eqx.filter_jit(eqx.filter_value_and_grad(_loss))(lens, rays, chunk, True)
    default = eqx.filter_jit(eqx.filter_value_and_grad(_loss))(lens, rays, chunk, False)
    rel = _max_rel(default, rule)
    print(f"{n} rays, pupil ×{pupil_scale}, float64: value and gradient, rule against "
          f"default, max |Δ|/max|·| per leaf {rel:.2e}")
    loss = eqx.filter_jit(_loss)
    fd = {}
    for name, where, h in (("surfaces[2].c", lambda m: m.surfaces[2].c, 1e-7),
                           ("surfaces[4].k", lambda m: m.surfaces[4].k, 1e-5),
                           ("thickness", lambda m: m.thickness, 1e-6)):
        def at(delta, where=where):
            x = where(lens)
            return eqx.tree_at(where, lens, x.at[1].add(delta) if x.ndim else x + delta)

        central = (float(loss(at(h), rays, chunk, False))
                   - float(loss(at(-h), rays, chunk, False))) / (2 * h)
        pick = (lambda g, where=where: float(where(g[1]).reshape(-1)[
            1 if where(lens).ndim else 0]))
        fd[name] = (central, pick(rule), pick(default))
        print(f"  d loss / d {name}{'[1]' if where(lens).ndim else ''}: central "
              f"{central:.10e}, rule {fd[name][1]:.10e}, default {fd[name][2]:.10e}")
    return {"grad_rel": rel, "fd": fd}


def timing(n=1_000_000, repeats=7, chunks=(CHUNK,), dtype=jnp.float32, lens_name="cooke_triplet"):
    """Each chunk's three programs, compiled first, then timed interleaved, best of
    ``repeats``. Returns {program: {ms, cpu_over_wall}} plus, per chunk, the f+g / forward
    ratios and the rule's gradient against the default's (max |Δ|/max|·| per leaf)."""
    lens = zoo.ZOO[lens_name]()
    rays = throughput.make_rays(lens, n, dtype)
    progs = {}
    for c in chunks:
        progs.update(programs(c))
    results = {}
    for name, f in progs.items():  # compile and warm
        results[name] = jax.block_until_ready(f(lens, rays))
        jax.block_until_ready(f(lens, rays))
    best = dict.fromkeys(progs, np.inf)
    cpu = dict(best)
    for _ in range(repeats):
        for name, f in progs.items():
            c0, t0 = time.process_time(), time.perf_counter()
            jax.block_until_ready(f(lens, rays))
            wall = time.perf_counter() - t0
            if wall < best[name]:
                best[name], cpu[name] = wall, time.process_time() - c0
    out = {"lens": lens_name, "rays": n, "dtype": jnp.dtype(dtype).name, "repeats": repeats,
           "load": os.getloadavg()[0], "programs": {}, "chunks": {}}
    print(f"{lens_name}, {n} rays, {out['dtype']}, best of {repeats}, load {out['load']:.1f}")
    for name in progs:
        out["programs"][name] = {"ms": 1e3 * best[name],
                                 "cpu_over_wall": cpu[name] / best[name]}
        print(f"  {name}: {1e3 * best[name]:.1f} ms (cpu/wall {cpu[name] / best[name]:.2f})")
    for c in chunks:
        fwd = best[f"forward chunk={c}"]
        default, rule = best[f"f+g default chunk={c}"], best[f"f+g reverse_rule chunk={c}"]
        rel = _max_rel(results[f"f+g default chunk={c}"], results[f"f+g reverse_rule chunk={c}"])
        out["chunks"][str(c)] = {"forward_over_fg_default": fwd / default,
                                 "forward_over_fg_rule": fwd / rule, "rule_grad_rel": rel}
        print(f"  chunk {c}: forward / (f+g) default {fwd / default:.3f}, rule "
              f"{fwd / rule:.3f}; rule's value and gradient against default {rel:.1e}")
    return out


def _while_bodies(txt):
    """{while-loop body: (fusions, HLO ops inside those fusions)} of a compiled HLO text."""
    comps, cur = {}, None
    for line in txt.splitlines():
        m = re.match(r"^(ENTRY )?%?([\w.\-]+) .*\{\s*$", line)
        if m and not line.startswith(" "):
            cur = m.group(2)
            comps[cur] = []
        elif cur:
            comps[cur].append(line)
    bodies = {re.search(r"body=%?([\w.\-]+)", ln).group(1)
              for lines in comps.values() for ln in lines if " while(" in ln}
    out = {}
    for name in bodies:
        calls = [re.search(r"calls=%?([\w.\-]+)", ln) for ln in comps[name]
                 if re.search(r"= \S+ fusion\(", ln)]
        ops = sum(sum(1 for x in comps.get(c.group(1), []) if " = " in x) for c in calls if c)
        out[name] = (len(calls), ops)
    return out


def count_fusions(n=1_000_000, chunk=CHUNK):
    """Print the fusions per loop body (chunk map, surface scan, their backward passes)."""
    lens = zoo.cooke_triplet()
    rays = throughput.make_rays(lens, n, jnp.float32)
    for name, f in programs(chunk).items():
        txt = jax.jit(f.__wrapped__).lower(lens, rays).compile().as_text()
        big = sorted((v for v in _while_bodies(txt).values() if v[0] > 3), reverse=True)
        print(f"{name}: loop bodies with >3 fusions (fusions, fused HLO ops): "
              + ", ".join(map(str, big)))


def main(argv=None):
    from jaxlens.experiments.runfolder import OneLineParser

    from .common import MAX_REPEATS, out_path, whole

    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="values, gradients and FD (float64)")
    ap.add_argument("--fusions", action="store_true", help="count fusions per loop body")
    # Defaults filled in below, so that an option the chosen mode does not read is refused.
    defaults = {"rays": 1_000_000, "lens": "cooke_triplet", "repeats": 7, "chunk": [CHUNK],
                "dtype": "float32", "json": None}
    ap.add_argument("--rays", type=whole(1, "rays", throughput.MAX_RAYS),
                    help="rays (default 1000000)")
    ap.add_argument("--lens", choices=tuple(zoo.ZOO),
                    help="zoo lens of --check and the timing (default cooke_triplet)")
    ap.add_argument("--repeats", type=whole(1, "repeats", MAX_REPEATS), help="(default 7)")
    ap.add_argument("--chunk", nargs="+", type=whole(1, "rays per chunk", throughput.MAX_RAYS),
                    help=f"chunk sizes to time (rays; the CPU default is {CHUNK})")
    ap.add_argument("--dtype", choices=("float32", "float64"),
                    help="the rays' dtype (the lens is cast to it; default float32)")
    ap.add_argument("--json", type=out_path(make_parents=False, result_of="vjp_probe"),
                    help="also write the timings to this JSON file")
    a = ap.parse_args(argv)
    if a.check and a.fusions:
        ap.error("--check and --fusions are two runs; give one")
    mode, reads = (("--check", {"lens"}) if a.check else ("--fusions", {"rays", "chunk"})
                   if a.fusions else (None, set(defaults)))
    unread = [f"--{k}" for k in defaults if getattr(a, k) is not None and k not in reads]
    if unread:  # before: --check --json out.json ran the check and wrote no file
        ap.error(f"{mode} does not read {', '.join(unread)} (those set the timing run)")
    if a.chunk is not None and len(set(a.chunk)) < len(a.chunk):
        ap.error(f"--chunk names a chunk size more than once: {a.chunk}")
    for k, v in defaults.items():
        if getattr(a, k) is None:
            setattr(a, k, v)
    if a.check:
        check(lens_name=a.lens)
    elif a.fusions:
        for c in a.chunk:
            count_fusions(a.rays, c)
    else:
        out = timing(a.rays, a.repeats, tuple(a.chunk), jnp.dtype(a.dtype), a.lens)
        if a.json:
            write_whole(a.json, json.dumps(dict(out, command="python -m benchmarks.vjp_probe "
                        + " ".join(sys.argv[1:] if argv is None else argv)), indent=1))


if __name__ == "__main__":
    main()
