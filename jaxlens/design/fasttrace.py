"""A ``lax.scan`` ray trace over a stack of same-kind surfaces, for short compile times.

``jaxlens.trace_path`` unrolls a Python loop over the surfaces. That is the clearest form,
but the compiled program (and its gradient) grows with the surface count: a 13-surface design
loss with its gradient takes about a minute to compile on a small CPU. Design lenses have one
surface kind (``EvenAsphere`` with the same number of terms; the flat stop is a flat asphere),
so here the surfaces are stacked into one pytree and traced with ``lax.scan``: the loop body is
compiled once.

The physics and validity rules are those of ``jaxlens.tracing.forward`` (and ``tests/test_design.py``
checks the two against each other): the first intersection with the base conic in closed
form, then Newton's method on the polynomial sag without gradient and one last Newton step
with gradient and a frozen derivative (the implicit-function gradient); vector Snell
refraction. A ray becomes invalid when it misses a surface (no root, outside the conic's
domain, Newton not converged), is clipped by a finite semi-diameter, is totally internally
reflected, or would travel backward after the first surface. Invalid rays keep finite values.

Conventions are those of ``jaxlens.tracing.forward``: mm, light toward +z, surface 1's vertex at z = 0.
Rays are handled as (x, y, z) component arrays, which vectorise better than ``[..., 3]``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..optics.lens import Lens
from ..optics.rays import Rays
from ..optics.surfaces import EvenAsphere

NEWTON_ITERS = 6


def stacked_surfaces(lens: Lens) -> EvenAsphere:
    """All lens surfaces as one ``EvenAsphere`` with a leading surface axis.

    Every surface must be an ``EvenAsphere`` with the same number of terms, except flat or
    conic ``Standard`` surfaces (the stop), which become aspheres with zero coefficients.
    """
    m = next((s.coeffs.shape[0] for s in lens.surfaces if isinstance(s, EvenAsphere)), None)
    if m is None:
        raise ValueError("stacked_surfaces: the lens has no EvenAsphere surface")
    surfs = []
    for i, s in enumerate(lens.surfaces):
        if isinstance(s, EvenAsphere):
            if s.coeffs.shape[0] != m:
                raise ValueError(f"stacked_surfaces: surface {i} has {s.coeffs.shape[0]} "
                                 f"aspheric terms, expected {m}")
            surfs.append(s)
            continue
        if s.has_polynomial:
            raise ValueError(f"stacked_surfaces: surface {i} ({type(s).__name__}) is neither "
                             "an EvenAsphere nor a plain conic")
        c = jnp.asarray(s.c)
        surfs.append(EvenAsphere(c=c, k=s.k, coeffs=jnp.zeros((m,), c.dtype),
                                 semi_diameter=s.semi_diameter))
    dtype = jnp.result_type(*[s.c for s in surfs])
    return jax.tree.map(lambda *x: jnp.stack([jnp.asarray(v, dtype) for v in x]), *surfs)


def _nz(x):
    return jnp.where(x == 0, 1.0, x)


def _sag_grad(s: EvenAsphere, x, y):
    """Sag, dz/dx, dz/dy and domain flag of a (possibly stacked-slice) even asphere."""
    r2 = x * x + y * y
    arg = 1.0 - (1.0 + s.k) * s.c**2 * r2
    inside = arg > 0
    root = jnp.sqrt(jnp.where(inside, arg, 1.0))
    root = jnp.where(inside, root, 0.0)
    z = s.c * r2 / (1.0 + root)
    dr = s.c / jnp.where(inside, root, 1.0)
    a = s.coeffs
    m = a.shape[-1]
    if m:
        i = jnp.arange(1, m + 1, dtype=a.dtype)
        z = z + r2 * jnp.polyval(a[::-1], r2)
        dr = dr + jnp.polyval((2 * i * a)[::-1], r2)
    return z, x * dr, y * dr, inside


def _conic_first_root(s: EvenAsphere, o, d, t_min):
    """First root t ≥ t_min of the base conic on the sheet through the vertex."""
    ox, oy, oz = o
    dx, dy, dz = d
    ck = s.c * (1 + s.k)
    a = s.c * (dx * dx + dy * dy) + ck * dz * dz
    b = s.c * (ox * dx + oy * dy) + ck * oz * dz - dz
    cc = s.c * (ox * ox + oy * oy) + ck * oz * oz - 2 * oz
    disc = b * b - a * cc
    real = disc >= 0
    root = jnp.sqrt(jnp.where(real, disc, 0.0))
    q = -b + jnp.where(b <= 0, root, -root)
    t1 = jnp.where(q != 0, cc / _nz(q), jnp.inf)
    t2 = jnp.where(a != 0, q / _nz(a), jnp.inf)

    def usable(t, exists):
        return exists & real & (t >= t_min) & (ck * (oz + t * dz) <= 1)

    u1, u2 = usable(t1, q != 0), usable(t2, a != 0)
    t = jnp.where(u1 & u2, jnp.minimum(t1, t2), jnp.where(u1, t1, t2))
    hit = u1 | u2
    return jnp.where(hit, t, 0.0), hit


def _residual(s, o, d, t):
    px, py, pz = (oi + t * di for oi, di in zip(o, d, strict=True))
    z, gx, gy, inside = _sag_grad(s, px, py)
    return pz - z, d[2] - gx * d[0] - gy * d[1], inside


def _intersect(s: EvenAsphere, o, d, *, first: bool, newton_iters: int):
    o_s, d_s = jax.lax.stop_gradient((o, d))
    s_s = jax.lax.stop_gradient(s)
    eps = jnp.finfo(o[2].dtype).eps
    t_min = -jnp.inf if first else -1e3 * eps * (1 + jnp.abs(o_s[2]))
    t0, hit = _conic_first_root(s_s, o_s, d_s, t_min)
    t0 = jnp.where(hit, t0, -o_s[2] / _nz(d_s[2]))

    def newton(_, t):
        f, df, _ = _residual(s_s, o_s, d_s, t)
        return t - f / _nz(df)

    t0 = jax.lax.fori_loop(0, newton_iters, newton, t0)
    f0, df0, _ = _residual(s_s, o_s, d_s, t0)
    scale = 1.0 + jnp.abs(o_s[2]) + jnp.abs(t0)
    ok = (jnp.abs(f0) <= 64 * jnp.sqrt(eps) * scale) & jnp.isfinite(t0) & jnp.isfinite(df0)
    # Failed rays take the differentiable step at a harmless point (their own origin), so
    # no inf or NaN enters the backward pass (a zero cotangent times NaN is NaN).
    t0 = jnp.where(ok, t0, 0.0)
    df0 = jax.lax.stop_gradient(jnp.where(ok, _nz(df0), 1.0))
    f, _, inside = _residual(s, o, d, t0)
    t = t0 - f / df0
    ok = ok & inside
    return jnp.where(ok, t, 0.0), ok


def _refract(d, n, mu):
    cos_i = d[0] * n[0] + d[1] * n[1] + d[2] * n[2]
    k = 1.0 - mu * mu * (1.0 - cos_i * cos_i)
    ok = k >= 0
    root = jnp.sqrt(jnp.where(ok, k, 1.0))
    g = jnp.where(cos_i < 0, -root, root) - mu * cos_i
    return tuple(jnp.where(ok, mu * di + g * ni, di) for di, ni in zip(d, n, strict=True)), ok


def _normal(s, x, y):
    _, gx, gy, _ = _sag_grad(s, x, y)
    inv = jax.lax.rsqrt(1.0 + gx * gx + gy * gy)
    return -gx * inv, -gy * inv, inv


def _step(s, z, state, n_before, n_after, *, first: bool, refracts: bool, newton_iters: int):
    p, d, valid = state
    o = (p[0], p[1], p[2] - z)
    t, ok = _intersect(s, o, d, first=first, newton_iters=newton_iters)
    if not first:
        ok = ok & (t >= -1e3 * jnp.finfo(t.dtype).eps * (1 + jnp.abs(o[2])))
    q = tuple(oi + t * di for oi, di in zip(o, d, strict=True))
    ok = ok & (q[0] * q[0] + q[1] * q[1] <= s.semi_diameter**2)
    if refracts:
        d_new, no_tir = _refract(d, _normal(s, q[0], q[1]), n_before / n_after)
        ok = ok & no_tir
    else:
        d_new = d
    valid = valid & ok
    p = tuple(jnp.where(valid, qi, pi) for qi, pi in zip((q[0], q[1], q[2] + z), p, strict=True))
    d = tuple(jnp.where(valid, a, b) for a, b in zip(d_new, d, strict=True))
    return p, d, valid


def trace_path_scan(lens: Lens, rays: Rays, *, newton_iters: int = NEWTON_ITERS) -> Rays:
    """Trace rays and return them after every surface and, last, on the image surface.

    Args:
        lens: a lens whose surfaces ``stacked_surfaces`` accepts; its image surface must be
            a ``Standard`` (plane or conic) or an ``EvenAsphere``.
        rays: rays in object space (``[*batch]``).
        newton_iters: Newton iterations per surface.

    Returns:
        ``Rays`` with a leading axis of ``num_surfaces + 1``: after each surface (after
        refraction), then on the image surface. ``opl`` is not accumulated (zero).
    """
    lens = lens.astype(rays.dtype)
    stack = stacked_surfaces(lens)
    m = stack.coeffs.shape[-1]
    img = lens.image
    if not isinstance(img, EvenAsphere):
        img = EvenAsphere(c=img.c, k=img.k, coeffs=jnp.zeros((m,), rays.dtype),
                          semi_diameter=img.semi_diameter)
    zs = lens.vertex_z()
    shape = rays.shape
    nidx = [jnp.broadcast_to(x, shape) for x in lens.indices(rays.wavelength)]
    n = jnp.stack(nidx)
    state = (tuple(rays.origin[..., i] for i in range(3)),
             tuple(rays.direction[..., i] for i in range(3)), rays.valid)
    first = jax.tree.map(lambda x: x[0], stack)
    state = _step(first, zs[0], state, n[0], n[1], first=True, refracts=True,
                  newton_iters=newton_iters)
    rest = jax.tree.map(lambda x: x[1:], stack)

    def body(st, xs):
        s, z, nb, na = xs
        st = _step(s, z, st, nb, na, first=False, refracts=True, newton_iters=newton_iters)
        return st, st

    last, path = jax.lax.scan(body, state, (rest, zs[1:], n[1:-1], n[2:]))
    final = _step(img, lens.image_z(), last, n[-1], n[-1], first=False, refracts=False,
                  newton_iters=newton_iters)

    def cat(a, b, c):
        return jnp.concatenate([a[None], b, c[None]])

    p, d, valid = jax.tree.map(cat, state, path, final)
    wl = jnp.broadcast_to(rays.wavelength, (len(zs) + 1,) + shape)
    return Rays(jnp.stack(p, -1), jnp.stack(d, -1), wl, valid)
