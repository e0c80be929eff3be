"""Sequential real-ray tracing: intersection, vector Snell refraction, validity masks.

Conventions:
    Global coordinates in mm, light toward +z, surface 1's vertex at z = 0 (see
    ``jaxlens.lens``). Rays start in object space: a ray is the whole line through its
    origin, so its intersection with surface 1 may lie behind the origin (a pupil
    point given on an entrance-pupil plane inside the lens is fine). After surface 1,
    a ray that would have to travel backward (t < 0) is invalid.

Intersections:
    The base conic is intersected in closed form (the numerically stable root of the
    quadratic). Surfaces with polynomial terms then take ``newton_iters`` Newton steps
    on F(t) = z(t) − sag(x(t), y(t)). Those iterations carry no gradient. One last
    Newton step is taken with gradients switched on and the derivative F'(t) held
    fixed; at the converged root its derivative is exactly the implicit-function
    theorem result dt/dθ = −(∂F/∂θ)/(∂F/∂t), so the backward pass never unrolls the
    iterations.

Validity:
    A ray is invalid once it misses a surface (no real root, outside the conic's
    domain, or Newton did not converge), is clipped by a semi-diameter, undergoes
    total internal reflection, or would travel backward. Invalid rays keep finite
    values (they stop where they failed), and every guard is a "double where", so
    gradients are finite everywhere.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .lens import Lens
from .rays import Rays
from .surfaces import AbstractSurface

DEFAULT_NEWTON_ITERS = 6


def _where_nonzero(x):
    return jnp.where(x == 0, 1.0, x)


def _conic_root(surface: AbstractSurface, o, d, t_min):
    """Closed-form intersection with the base conic; returns (t, hit).

    Of the two roots of c(x² + y²) + c(1+k)z² − 2z = 0, only those on the sheet through
    the vertex (1 − c(1+k)z ≥ 0) and with t ≥ t_min count; the first of them along the
    ray is taken.
    """
    c, k = surface.c, surface.k
    ox, oy, oz = o[..., 0], o[..., 1], o[..., 2]
    dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
    a = c * (dx * dx + dy * dy + (1 + k) * dz * dz)
    b = c * (ox * dx + oy * dy + (1 + k) * oz * dz) - dz
    cc = c * (ox * ox + oy * oy + (1 + k) * oz * oz) - 2 * oz
    disc = b * b - a * cc
    real = disc >= 0
    root = jnp.sqrt(jnp.where(real, disc, 0.0))
    # Stable pair of roots: t1 = cc/q stays finite as c -> 0, t2 = q/a.
    q = -b + jnp.where(b <= 0, root, -root)
    t1 = cc / _where_nonzero(q)
    t2 = jnp.where(a != 0, q / _where_nonzero(a), jnp.inf)

    def usable(t, exists):
        z = oz + t * dz
        return exists & real & jnp.isfinite(t) & (t >= t_min) & (1 - c * (1 + k) * z >= 0)

    u1, u2 = usable(t1, q != 0), usable(t2, a != 0)
    t = jnp.where(u1 & u2, jnp.minimum(t1, t2), jnp.where(u1, t1, t2))
    return jnp.where(u1 | u2, t, 0.0), u1 | u2


def _residual(surface: AbstractSurface, o, d, t):
    p = o + t[..., None] * d
    z, gx, gy, inside = surface.sag_and_grad(p[..., 0], p[..., 1])
    f = p[..., 2] - z
    df = d[..., 2] - gx * d[..., 0] - gy * d[..., 1]
    return f, df, inside


def intersect(
    surface: AbstractSurface, o, d, newton_iters: int = DEFAULT_NEWTON_ITERS, *, first=False
):
    """Intersect rays (local frame, vertex at the origin) with a surface.

    The first intersection along the ray is taken; with ``first=False`` only t ≥ 0
    (up to rounding) counts, with ``first=True`` (object space) the whole line does.

    Returns:
        t: ray parameter of the intersection, ``[*batch]``.
        ok: ``[*batch]`` bool, True where a valid intersection was found.
    """
    o_s, d_s = jax.lax.stop_gradient((o, d))
    surf_s = jax.lax.stop_gradient(surface)
    t_min = -jnp.inf if first else -1e3 * jnp.finfo(o.dtype).eps * (1 + jnp.abs(o_s[..., 2]))
    t0, hit = _conic_root(surf_s, o_s, d_s, t_min)
    if surface.has_polynomial:
        # Rays that miss the base conic start Newton from the vertex plane.
        plane_t = -o_s[..., 2] / _where_nonzero(d_s[..., 2])
        t0 = jnp.where(hit, t0, plane_t)

        def step(_, t):
            f, df, _ = _residual(surf_s, o_s, d_s, t)
            return t - f / _where_nonzero(df)

        t0 = jax.lax.fori_loop(0, newton_iters, step, t0)
    # One differentiable step with F' held fixed: the implicit-function gradient.
    f0, df0, _ = _residual(surf_s, o_s, d_s, t0)
    df0 = jax.lax.stop_gradient(_where_nonzero(df0))
    f, _, inside = _residual(surface, o, d, t0)
    t = t0 - f / df0
    eps = jnp.finfo(t.dtype).eps
    scale = 1.0 + jnp.abs(o_s[..., 2]) + jnp.abs(t0)
    converged = jnp.abs(f0) <= 64 * jnp.sqrt(eps) * scale
    ok = inside & converged & (df0 != 0) & jnp.isfinite(t0)
    if not surface.has_polynomial:
        ok = ok & hit
    return jnp.where(ok, t, 0.0), ok


def refract(d, normal, mu):
    """Vector Snell's law.

    Args:
        d: unit incident directions ``[*b, 3]``.
        normal: unit surface normals ``[*b, 3]`` (either orientation).
        mu: n_before / n_after, ``[*b]``.

    Returns:
        (refracted unit directions, ok) with ok False on total internal reflection.
    """
    cos_i = jnp.sum(d * normal, axis=-1)
    k = 1.0 - mu * mu * (1.0 - cos_i * cos_i)
    ok = k >= 0
    root = jnp.sqrt(jnp.where(ok, k, 1.0))
    root = jnp.where(cos_i < 0, -root, root)
    out = mu[..., None] * d + (root - mu * cos_i)[..., None] * normal
    return jnp.where(ok[..., None], out, d), ok


def _surface_normal(surface: AbstractSurface, x, y):
    _, gx, gy, _ = surface.sag_and_grad(x, y)
    n = jnp.stack([-gx, -gy, jnp.ones_like(gx)], axis=-1)
    return n / jnp.sqrt(1.0 + gx * gx + gy * gy)[..., None]


def _step(surface, z_vertex, rays: Rays, n_before, n_after, *, first, refracts, newton_iters):
    """Move rays to one surface and refract them there."""
    shift = jnp.stack([jnp.zeros_like(z_vertex), jnp.zeros_like(z_vertex), z_vertex])
    o_local = rays.origin - shift
    t, ok = intersect(surface, o_local, rays.direction, newton_iters, first=first)
    if not first:
        ok = ok & (t >= -1e3 * jnp.finfo(t.dtype).eps * (1 + jnp.abs(o_local[..., 2])))
    p_local = o_local + t[..., None] * rays.direction
    r2 = p_local[..., 0] ** 2 + p_local[..., 1] ** 2
    ok = ok & (r2 <= surface.semi_diameter**2)
    d = rays.direction
    if refracts:
        normal = _surface_normal(surface, p_local[..., 0], p_local[..., 1])
        d_new, no_tir = refract(d, normal, n_before / n_after)
        ok = ok & no_tir
    else:
        d_new = d
    valid = rays.valid & ok
    origin = jnp.where(valid[..., None], p_local + shift, rays.origin)
    direction = jnp.where(valid[..., None], d_new, rays.direction)
    opl = rays.opl + jnp.where(valid, n_before * t, 0.0)
    return Rays(origin, direction, rays.wavelength, valid, opl)


def _broadcast_index(n, shape):
    return jnp.broadcast_to(n, shape)


def trace_path(
    lens: Lens,
    rays: Rays,
    *,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    upto: int | None = None,
) -> list[Rays]:
    """Trace rays and return them after every surface.

    Args:
        lens: the lens.
        rays: rays in object space.
        newton_iters: Newton iterations for surfaces with polynomial terms.
        upto: stop after ``surfaces[upto]`` (0-based); ``None`` traces to the image.

    Returns:
        A list with the rays at each surface (after refraction) and, last, at the
        image surface (when ``upto`` is None).
    """
    lens = lens.astype(rays.dtype)
    zs = lens.vertex_z()
    idx = lens.indices(rays.wavelength)
    shape = rays.shape
    out = []
    last = lens.num_surfaces - 1 if upto is None else upto
    for i in range(last + 1):
        rays = _step(
            lens.surfaces[i],
            zs[i],
            rays,
            _broadcast_index(idx[i], shape),
            _broadcast_index(idx[i + 1], shape),
            first=i == 0,
            refracts=True,
            newton_iters=newton_iters,
        )
        out.append(rays)
    if upto is None:
        n_img = _broadcast_index(idx[-1], shape)
        rays = _step(
            lens.image,
            lens.image_z(),
            rays,
            n_img,
            n_img,
            first=False,
            refracts=False,
            newton_iters=newton_iters,
        )
        out.append(rays)
    return out


@eqx.filter_jit
def trace(lens: Lens, rays: Rays, *, newton_iters: int = DEFAULT_NEWTON_ITERS) -> Rays:
    """Trace rays from object space to the image surface.

    Pure, jittable, vmappable and differentiable. The result follows the dtype of
    ``rays`` (the lens is cast to it).

    Args:
        lens: the lens.
        rays: rays in object space (global coordinates, surface 1 vertex at z = 0).
        newton_iters: Newton iterations for aspheric and hybrid surfaces.

    Returns:
        The rays on the image surface: intercepts in ``origin``, direction cosines
        after the last surface in ``direction``, ``valid`` and ``opl``.

    Example:
        >>> import jaxlens, jax.numpy as jnp
        >>> lens = jaxlens.Lens(surfaces=(jaxlens.Sphere(0.02), jaxlens.Sphere(-0.02)),
        ...     thickness=jnp.array([5.0, 45.0]),
        ...     materials=(jaxlens.ModelGlass(1.5168, 64.17), jaxlens.Air()))
        >>> rays = jaxlens.Rays(jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.5876)
        >>> bool(jaxlens.trace(lens, rays).valid[0])
        True
    """
    return trace_path(lens, rays, newton_iters=newton_iters)[-1]
