"""Probe: the reversible trace's gradient against the per-surface reverse rule, interleaved.

``reversible_trace`` (here, not in the library) traces a lens of ``Standard`` surfaces as one
``jax.custom_vjp`` whose forward keeps only each surface's root t and refraction gain g and
whose backward walks the surfaces in reverse, rebuilds each surface's incident rays from the
rays after it with no root solve and no square root,

    d_in = (d_out − g·N)/mu   (N the conic normal at p_out),   p_in = p_out − t·d_in,

and applies the existing rule's per-surface adjoint (``surface_adjoint._backward``) to them:
no stored rays per surface, no checkpointed chunk, no forward recompute. Surface 1's incident
rays are the trace's input (never rebuilt). Validity only drops along a ray, so one int8 per
ray (how many surfaces it passed) gives the validity after every surface; a ray invalid after
a surface kept its rays there (``surface_step``), so its incident rays are taken unchanged and
only valid rays are rebuilt (finite t and g: no NaN or inf can arise). Failed rays pass their
cotangents through and give the parameters nothing, as in JAX's derivative of ``trace``
(values bit for bit ``trace``'s, float64 gradients equal to ~1e-14, ``--check``).

Measured slower than, or level with, ``trace(reverse_rule=True)`` at 1e6 rays and dropped
(benchmarks/SPEED.md, "A reversible backward pass"). This probe checks its value and float64
gradient against JAX's derivative and the per-surface rule (``reverse_rule=True``) and central
differences, and times, compiled once each and interleaved in one process (best of N), the
forward, f+g with the per-surface rule (default chunk) and f+g reversible for each ``--chunk``
(0: one piece), with the throughput benchmark's rays and spot loss.

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

# The per-surface forward and adjoint of the existing rule, reused as they are (not copied):
# private names, since this prototype was not moved into the library (SPEED.md).
from jaxlens.tracing.surface_adjoint import (  # noqa: E402
    _advance,
    _backward,
    _backward_flag,
)

from . import throughput  # noqa: E402
from .vjp_probe import _max_rel  # noqa: E402


def _unrefract(d_out, normal, mu, g):
    """The incident direction of a refracted ray: d_out = mu·d + g·normal (``step``'s
    ``refraction_gain`` relation) solved for d, with no square root."""
    inv = 1.0 / mu
    return tuple((do - g * ni) * inv for do, ni in zip(d_out, normal, strict=True))


def surface_params(lens, surfaces, zs, idx):
    """Per-surface (c, k, semi_diameter, z_vertex, n_before, n_after, backward), each stacked
    on a leading axis of num_surfaces + 1 (the image last, with n_after = n_before)."""
    every = list(surfaces) + [lens.image]
    m = len(every)
    shape = jnp.broadcast_shapes(*(jnp.shape(n) for n in idx))
    n = [jnp.broadcast_to(x, shape) for x in idx]
    n_in, n_out = n[: m - 1] + [n[-1]], n[1:] + [n[-1]]
    gaps = [None] + [lens.thickness[i] for i in range(m - 1)]
    bk = [_backward_flag(gaps[i], i == 0, n_in[i], n_out[i]) for i in range(m)]
    return (jnp.stack([s.c for s in every]), jnp.stack([s.k for s in every]),
            jnp.stack([s.semi_diameter for s in every]),
            jnp.concatenate([zs, jnp.reshape(lens.image_z(), (1,))]),
            jnp.stack(n_in), jnp.stack(n_out), jnp.stack(bk))


UNROLL = False  # forward surfaces as a Python loop instead of a scan (measured: no gain)
UNROLL_BACK = False  # the same for the backward


def _at(params, i):
    return tuple(a[i] for a in params)


def _split(x):
    return x[..., 0], x[..., 1], x[..., 2]


def _forward(params, origin, direction, valid, opl):
    """((origin, direction, valid, opl) on the image, residuals): ``advance``'s steps."""
    p, d = _split(origin), _split(direction)
    m = params[0].shape[0]
    count_t = jnp.int8 if m < 127 else jnp.int32
    (p, d, v, opl), t0, g0 = _advance(True, True, _at(params, 0), p, d, valid, opl)
    count = v.astype(count_t)

    def body(carry, prm):
        (p, d, v, opl), count = carry
        out, t, g = _advance(False, True, prm, p, d, v, opl)
        return (out, count + out[2].astype(count_t)), (t, g)

    mid = tuple(a[1:-1] for a in params)
    if UNROLL:
        carry, tg = ((p, d, v, opl), count), []
        for i in range(m - 2):
            carry, y = body(carry, _at(mid, i))
            tg.append(y)
        ((p, d, v, opl), count) = carry
        ts, gs = jnp.stack([y[0] for y in tg]), jnp.stack([y[1] for y in tg])
    else:
        ((p, d, v, opl), count), (ts, gs) = jax.lax.scan(body, ((p, d, v, opl), count), mid)
    (p, d, v, opl), t_img, _ = _advance(False, False, _at(params, m - 1), p, d, v, opl)
    count = count + v.astype(count_t)
    return (jnp.stack(p, -1), jnp.stack(d, -1), v, opl), (t0, g0, ts, gs, t_img, count)


@jax.custom_vjp
def _reversible(params, origin, direction, valid, opl):
    return _forward(params, origin, direction, valid, opl)[0]


def _fwd(params, origin, direction, valid, opl):
    out, (t0, g0, ts, gs, t_img, count) = _forward(params, origin, direction, valid, opl)
    return out, (params, origin, direction, out[0], out[1], t0, g0, ts, gs, t_img, count)


def _unstep(refracts, prm, p, d, t, g, v):
    """The rays before a surface, from those after it (valid after it: rebuilt; else
    unchanged, as ``surface_step`` leaves a failed ray)."""
    c, k, _, zv, n1, n2, _ = prm
    if refracts:
        normal = (-c * p[0], -c * p[1], 1.0 - c * (1.0 + k) * (p[2] - zv))
        d_in = _unrefract(d, normal, n1 / n2, g)
    else:
        d_in = d
    p_in = tuple(pi - t * di for pi, di in zip(p, d_in, strict=True))
    keep = lambda new, old: jnp.where(v, new, old)  # noqa: E731
    return (tuple(keep(a, b) for a, b in zip(p_in, p, strict=True)),
            tuple(keep(a, b) for a, b in zip(d_in, d, strict=True)))


def _bwd(res, cts):
    params, p0, d0, p, d, t0, g0, ts, gs, t_img, count = res
    p0, d0, p, d = _split(p0), _split(d0), _split(p), _split(d)
    P, D, _, L = cts
    P, D = _split(P), _split(D)
    m = params[0].shape[0]
    last = _at(params, m - 1)
    v = count >= m
    p, d = _unstep(False, last, p, d, t_img, None, v)
    g_last, P, D, _, L = _backward(False, last, p, d, v, t_img,
                                        jnp.zeros((), t_img.dtype), (P, D, None, L))

    def body(carry, xs):
        p, d, P, D, L = carry
        prm, t, g, i = xs
        v = count > i
        p, d = _unstep(True, prm, p, d, t, g, v)
        gp, P, D, _, L = _backward(True, prm, p, d, v, t, g, (P, D, None, L))
        return (p, d, P, D, L), gp

    mid = tuple(a[1:-1] for a in params)
    xs = (mid, ts, gs, jnp.arange(1, m - 1, dtype=count.dtype))
    if UNROLL_BACK:
        carry, gm = (p, d, P, D, L), []
        for i in reversed(range(m - 2)):
            carry, y = body(carry, (_at(mid, i), ts[i], gs[i], i + 1))
            gm.append(y)
        (_, _, P, D, L) = carry
        g_mid = jax.tree.map(lambda *x: jnp.stack(x[::-1]), *gm)
    else:
        (_, _, P, D, L), g_mid = jax.lax.scan(body, (p, d, P, D, L), xs, reverse=True)
    g_first, P, D, _, L = _backward(True, _at(params, 0), p0, d0, count > 0, t0, g0,
                                         (P, D, None, L))
    g_params = tuple(
        None if a is None else jnp.concatenate([a[None], b, c[None]])
        for a, b, c in zip(g_first, g_mid, g_last, strict=True)
    )
    return g_params, jnp.stack(P, -1), jnp.stack(D, -1), None, L


_reversible.defvjp(_fwd, _bwd)


def _chunks(n, chunk, lanes=16):
    """(chunks, rays per chunk): equal chunks of a multiple of ``lanes`` where one divides n
    (as ``trace`` chunks), else the last one padded."""
    m0 = -(-n // chunk)
    for m in range(m0, 2 * m0 + 1):
        if n % (m * lanes) == 0:
            return m, n // m
    size = -(-n // m0)
    return m0, -(-size // lanes) * lanes


def reversible_trace(lens, rays, chunk=None):
    """``jaxlens.trace(lens, rays)`` for a lens of ``Standard`` surfaces (no mirrors,
    apertures, obscurations), with the reversible rule; chunks of ``chunk`` rays through
    ``jax.lax.map``, not checkpointed (the rule keeps t and g instead). Returns (origin,
    direction, valid, opl) on the image surface."""
    if not all(type(s) is jaxlens.Standard for s in (*lens.surfaces, lens.image)) or (
            lens.mirrors or lens.apertures or lens.obscurations):
        raise ValueError("reversible_trace: Standard surfaces only, no mirrors, apertures "
                         "or obscurations")
    lens = lens.astype(rays.dtype)
    params = surface_params(lens, lens.surfaces, lens.vertex_z(), lens.indices(rays.wavelength))
    args = (rays.origin, rays.direction, rays.valid, rays.opl)
    n = rays.origin.shape[0]
    if chunk is None or n <= chunk:
        return _reversible(params, *args)
    m, size = _chunks(n, chunk)

    def split(x):
        if m * size != n:
            x = jnp.pad(x, [(0, m * size - n)] + [(0, 0)] * (x.ndim - 1), mode="edge")
        return x.reshape(m, size, *x.shape[1:])

    out = jax.lax.map(lambda xs: _reversible(params, *xs), tuple(split(x) for x in args))
    return tuple(x.reshape(m * size, *x.shape[2:])[:n] for x in out)


def _loss(lens, rays, chunk, rule):
    """The throughput benchmark's spot loss; ``rule``: False (JAX's derivative), True (the
    per-surface rule) or "reversible" (this probe's trace)."""
    if rule == "reversible":
        origin, _, valid, _ = reversible_trace(lens, rays, None if chunk == "auto" else chunk)
        return throughput.spot_loss(origin[:, :2], valid)
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
    b = reversible_trace(lens, rays, chunk)
    out["values_identical"] = all(bool(jnp.all(x == y)) for x, y in
                                  zip((a.origin, a.direction, a.valid, a.opl), b, strict=True))
    print(f"{n} rays, pupil ×{pupil_scale} (valid {float(jnp.mean(a.valid)):.2f}), float64: "
          f"values identical {out['values_identical']}; gradient max |Δ|/max|·| per leaf: "
          f"reversible vs JAX {out['rev_vs_jax']:.1e}, vs rule {out['rev_vs_rule']:.1e}, "
          f"rule vs JAX {out['rule_vs_jax']:.1e}")
    # The rays that fail: a loss on their stopped positions only (what a validity-masked loss
    # never sees) has the same finite gradient as with JAX's derivative.
    def lost(lens, rule):
        if rule == "reversible":
            origin, _, valid, _ = reversible_trace(lens, rays, chunk)
        else:
            out = jaxlens.trace(lens, rays, chunk=chunk)
            origin, valid = out.origin, out.valid
        return jnp.sum(jnp.where(valid[:, None], 0.0, origin) ** 2)

    g_lost = {r: eqx.filter_jit(eqx.filter_grad(lost))(lens, r) for r in (False, "reversible")}
    out["failed_rays_rel"] = _max_rel(g_lost[False], g_lost["reversible"])
    out["failed_rays_finite"] = all(bool(jnp.all(jnp.isfinite(x)))
                                    for x in jax.tree.leaves(g_lost["reversible"]))
    print(f"  failed rays' positions: gradient vs JAX {out['failed_rays_rel']:.1e}, finite "
          f"{out['failed_rays_finite']}")
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
