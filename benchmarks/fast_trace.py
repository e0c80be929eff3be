"""Prototype of a faster forward trace: the same physics as ``jaxlens.trace``, laid out for XLA:CPU.

This is a benchmark-side proof of concept for the lead (who owns ``jaxlens/trace.py``). It
computes exactly what ``jaxlens.trace`` computes (first-hit conic root on the vertex sheet,
Newton with an implicit-function last step for polynomial surfaces, vector Snell refraction,
clipping, TIR and t < 0 masks, optical path), but:

1. **Structure of arrays.** Each ray component (x, y, z, L, M, N) is its own ``[*batch]``
   array. ``jaxlens.trace`` works on ``[*batch, 3]`` arrays; its ``jnp.sum(d * normal, -1)``
   lowers to a YNNPACK custom call (a fusion barrier), and every ``jnp.stack``/slice of the last
   axis splits XLA's loop fusions. The compiled Cooke-triplet trace has ~137 separate loop
   fusions, each one a full pass over memory; this layout gives a handful.
2. **Chunking** (optional): ``jax.lax.map`` over chunks of rays keeps each chunk's
   intermediates in cache.
3. **One sag evaluation per Newton step** and a single ``sag_and_grad`` at the hit point for
   both the implicit step and the normal.

The gradient path is the same (IFT step with F' held fixed).

Status: ``jaxlens/trace.py`` adopted points 1 and 3 and the closed-form conic step (commits
a51b4ba, 4c71e74) and then moved to a ``lax.scan`` over runs of same-kind surfaces (7521ab7).
What this prototype still adds is point 2 (chunking with ``lax.map``) and no scan; the
throughput benchmark keeps its forward rows to measure what that is worth.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxlens.lens import Lens
from jaxlens.rays import Rays
from jaxlens.trace import DEFAULT_NEWTON_ITERS


def _nz(x):
    return jnp.where(x == 0, 1.0, x)


def _conic_root(c, k, ox, oy, oz, dx, dy, dz, t_min):
    a = c * (dx * dx + dy * dy + (1 + k) * dz * dz)
    b = c * (ox * dx + oy * dy + (1 + k) * oz * dz) - dz
    cc = c * (ox * ox + oy * oy + (1 + k) * oz * oz) - 2 * oz
    disc = b * b - a * cc
    real = disc >= 0
    root = jnp.sqrt(jnp.where(real, disc, 0.0))
    q = -b + jnp.where(b <= 0, root, -root)
    t1 = cc / _nz(q)
    t2 = jnp.where(a != 0, q / _nz(a), jnp.inf)

    def usable(t, exists):
        z = oz + t * dz
        return exists & real & jnp.isfinite(t) & (t >= t_min) & (1 - c * (1 + k) * z >= 0)

    u1, u2 = usable(t1, q != 0), usable(t2, a != 0)
    t = jnp.where(u1 & u2, jnp.minimum(t1, t2), jnp.where(u1, t1, t2))
    return jnp.where(u1 | u2, t, 0.0), u1 | u2


def _conic_step(surface, lz, ox, oy, dx, dy, dz, first):
    """Closed-form, directly differentiable intersection with a conic and its unit normal."""
    c, k = surface.c, surface.k
    eps = jnp.finfo(ox.dtype).eps
    t_min = -jnp.inf if first else -1e3 * eps * (1 + jnp.abs(lz))
    a = c * (dx * dx + dy * dy + (1 + k) * dz * dz)
    b = c * (ox * dx + oy * dy + (1 + k) * lz * dz) - dz
    cc = c * (ox * ox + oy * oy + (1 + k) * lz * lz) - 2 * lz
    disc = b * b - a * cc
    real = disc > 0
    root = jnp.where(real, jnp.sqrt(jnp.where(real, disc, 1.0)), 0.0)
    q = -b + jnp.where(b <= 0, root, -root)
    t1 = cc / _nz(q)
    t2 = q / _nz(a)

    def usable(t, exists):
        z = lz + t * dz
        return exists & (disc >= 0) & (t >= t_min) & (1 - c * (1 + k) * z >= 0)

    u1, u2 = usable(t1, q != 0), usable(t2, a != 0)
    t = jnp.where(u1 & u2, jnp.minimum(t1, t2), jnp.where(u1, t1, t2))
    ok = u1 | u2
    t = jnp.where(ok, t, 0.0)
    px, py, pz = ox + t * dx, oy + t * dy, lz + t * dz
    # Normal from the gradient of F = c(x² + y² + (1+k)z²) − 2z (pointing toward −z).
    gx, gy, gz = c * px, c * py, 1.0 - c * (1 + k) * pz
    inv = jax.lax.rsqrt(gx * gx + gy * gy + gz * gz)
    return t, ok, px, py, pz, -gx * inv, -gy * inv, gz * inv


def _finish(surface, st, zv, lz, t, ok, px, py, pz, nx, ny, nzz, n1, n2, refracts):
    ox, oy, oz, dx, dy, dz, valid, opl = st
    ok = ok & (px * px + py * py <= surface.semi_diameter**2)
    if refracts:
        mu = n1 / n2
        cos_i = dx * nx + dy * ny + dz * nzz
        kk = 1.0 - mu * mu * (1.0 - cos_i * cos_i)
        no_tir = kk >= 0
        root = jnp.sqrt(jnp.where(no_tir, kk, 1.0))
        root = jnp.where(cos_i < 0, -root, root)
        g = root - mu * cos_i
        ndx = jnp.where(no_tir, mu * dx + g * nx, dx)
        ndy = jnp.where(no_tir, mu * dy + g * ny, dy)
        ndz = jnp.where(no_tir, mu * dz + g * nzz, dz)
        ok = ok & no_tir
    else:
        ndx, ndy, ndz = dx, dy, dz
    v = valid & ok
    return (
        jnp.where(v, px, ox),
        jnp.where(v, py, oy),
        jnp.where(v, pz + zv, oz),
        jnp.where(v, ndx, dx),
        jnp.where(v, ndy, dy),
        jnp.where(v, ndz, dz),
        v,
        opl + jnp.where(v, n1 * t, 0.0),
    )


def _surface_step(surface, zv, st, n1, n2, *, first, refracts, newton_iters, closed_form=False):
    ox, oy, oz, dx, dy, dz, valid, opl = st
    lz = oz - zv
    if closed_form and not surface.has_polynomial:
        t, ok, px, py, pz, nx, ny, nzz = _conic_step(surface, lz, ox, oy, dx, dy, dz, first)
        return _finish(surface, st, zv, lz, t, ok, px, py, pz, nx, ny, nzz, n1, n2, refracts)
    s_s = jax.lax.stop_gradient(surface)
    oxs, oys, ozs, dxs, dys, dzs = jax.lax.stop_gradient((ox, oy, lz, dx, dy, dz))
    eps = jnp.finfo(ox.dtype).eps
    t_min = -jnp.inf if first else -1e3 * eps * (1 + jnp.abs(ozs))
    t0, hit = _conic_root(s_s.c, s_s.k, oxs, oys, ozs, dxs, dys, dzs, t_min)
    if surface.has_polynomial:
        t0 = jnp.where(hit, t0, -ozs / _nz(dzs))

        def body(_, t):
            z, gx, gy, _ = s_s.sag_and_grad(oxs + t * dxs, oys + t * dys)
            f = ozs + t * dzs - z
            df = dzs - gx * dxs - gy * dys
            return t - f / _nz(df)

        t0 = jax.lax.fori_loop(0, newton_iters, body, t0)
    # Residual and derivative at t0 without gradient, then one differentiable IFT step.
    z0, gx0, gy0, _ = s_s.sag_and_grad(oxs + t0 * dxs, oys + t0 * dys)
    f0 = ozs + t0 * dzs - z0
    df0 = _nz(dzs - gx0 * dxs - gy0 * dys)
    zt, _ = surface.sag(ox + t0 * dx, oy + t0 * dy)
    f = lz + t0 * dz - zt
    t = t0 - f / df0
    converged = jnp.abs(f0) <= 64 * jnp.sqrt(eps) * (1.0 + jnp.abs(ozs) + jnp.abs(t0))
    px, py = ox + t * dx, oy + t * dy
    z, gx, gy, inside = surface.sag_and_grad(px, py)
    ok = inside & converged & jnp.isfinite(t0)
    if not surface.has_polynomial:
        ok = ok & hit
    t = jnp.where(ok, t, 0.0)
    if not first:
        ok = ok & (t >= -1e3 * eps * (1 + jnp.abs(lz)))
    px, py, pz = ox + t * dx, oy + t * dy, lz + t * dz
    ok = ok & (px * px + py * py <= surface.semi_diameter**2)
    if refracts:
        inv = jax.lax.rsqrt(1.0 + gx * gx + gy * gy)
        nx, ny, nzz = -gx * inv, -gy * inv, inv
        mu = n1 / n2
        cos_i = dx * nx + dy * ny + dz * nzz
        kk = 1.0 - mu * mu * (1.0 - cos_i * cos_i)
        no_tir = kk >= 0
        root = jnp.sqrt(jnp.where(no_tir, kk, 1.0))
        root = jnp.where(cos_i < 0, -root, root)
        g = root - mu * cos_i
        ndx = jnp.where(no_tir, mu * dx + g * nx, dx)
        ndy = jnp.where(no_tir, mu * dy + g * ny, dy)
        ndz = jnp.where(no_tir, mu * dz + g * nzz, dz)
        ok = ok & no_tir
    else:
        ndx, ndy, ndz = dx, dy, dz
    v = valid & ok
    return (
        jnp.where(v, px, ox),
        jnp.where(v, py, oy),
        jnp.where(v, pz + zv, oz),
        jnp.where(v, ndx, dx),
        jnp.where(v, ndy, dy),
        jnp.where(v, ndz, dz),
        v,
        opl + jnp.where(v, n1 * t, 0.0),
    )


def trace_soa(
    lens: Lens,
    state,
    wavelength,
    *,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    closed_form: bool = False,
):
    """Trace an SoA ray state ``(x, y, z, L, M, N, valid, opl)`` to the image surface.

    With ``closed_form=True`` surfaces without polynomial terms are intersected in closed form
    with gradients through the formula (no residual evaluations) and take their normal from
    the conic's implicit equation (no square root of the sag).
    """
    dtype = state[0].dtype
    lens = lens.astype(dtype)
    zs = lens.vertex_z()
    n = [jnp.asarray(v, dtype) for v in lens.indices(wavelength)]
    for i, s in enumerate(lens.surfaces):
        state = _surface_step(
            s,
            zs[i],
            state,
            n[i],
            n[i + 1],
            first=i == 0,
            refracts=True,
            newton_iters=newton_iters,
            closed_form=closed_form,
        )
    return _surface_step(
        lens.image,
        lens.image_z(),
        state,
        n[-1],
        n[-1],
        first=False,
        refracts=False,
        newton_iters=newton_iters,
        closed_form=closed_form,
    )


def rays_to_state(rays: Rays):
    o, d = rays.origin, rays.direction
    return (o[..., 0], o[..., 1], o[..., 2], d[..., 0], d[..., 1], d[..., 2], rays.valid, rays.opl)


def trace_soa_chunked(
    lens: Lens,
    state,
    wavelength,
    *,
    chunk: int = 1 << 14,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    closed_form: bool = False,
):
    """``trace_soa`` over chunks of ``chunk`` rays with ``jax.lax.map`` (1-D batches)."""
    m = state[0].shape[0]
    kw = dict(newton_iters=newton_iters, closed_form=closed_form)
    if m <= chunk:
        return trace_soa(lens, state, wavelength, **kw)
    n_chunks = -(-m // chunk)
    pad = n_chunks * chunk - m

    def split(a):
        # Pad with copies of the first ray (sliced off again below).
        a = jnp.concatenate([a, jnp.broadcast_to(a[:1], (pad,))]) if pad else a
        return a.reshape(n_chunks, chunk)

    out = jax.lax.map(
        lambda s: trace_soa(lens, s, wavelength, **kw), jax.tree_util.tree_map(split, state)
    )
    return jax.tree_util.tree_map(lambda a: a.reshape(-1)[:m], out)
