"""Relative illumination by forward ray tracing, independently of ``render``.

Conventions:
    Field angles in degrees (θy, or (θx, θy)); lengths in mm; wavelengths in µm.

Method:
    The irradiance at the image of a field point is the flux that the lens passes from a
    small patch of object, divided by the area of the patch's image. For an object at
    infinity the patch is a solid angle around the direction t = (tanθx, tanθy); a beam of
    radiance L passes the flux L·A⊥·dΩ, where A⊥ = A·cosθ is the beam cross-section that
    reaches the sensor (the valid part A of an overfilled grid on the entrance-pupil plane,
    projected onto the beam's normal) and dΩ = cos³θ·dtx·dty. The patch's image has the area
    |det ∂x/∂t|·dtx·dty, with x the centroid of the beam on the image surface, so

        E = L·A·cos⁴θ / |det ∂x/∂t|.

    For an object at finite depth, a Lambertian patch dA_o sends L·Ω_p·dA_o through the lens
    (Ω_p the projected solid angle of the valid rays, Σ cos⁴γ·ΔA/z² over the pupil grid) and
    its image has the area |det ∂x/∂X|·dA_o, so E = L·Ω_p / |det ∂x/∂X|.

    The Jacobians come from forward-mode autodiff of the centroid with the valid set held
    fixed. Vignetting, the cos⁴ law, pupil aberrations and distortion all enter. The
    relative illumination is E divided by its value on axis.

    The valid part of the pupil is found in two stages: a coarse grid over a disc three times
    the paraxial entrance pupil, then a fine grid over the bounding box of the valid coarse
    cells (one cell of margin), so the count of valid fine cells measures the area.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import paraxial
from .lens import Lens
from .psf import _static_depth, apertured
from .rays import Rays
from .reverse import trace_scan as trace
from .trace import DEFAULT_NEWTON_ITERS

__all__ = ["RelativeIllumination", "relative_illumination", "box_search"]


def _cells(n: int, dtype):
    g = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    px, py = np.meshgrid(g, g, indexing="xy")
    return jnp.asarray(np.stack([px.ravel(), py.ravel()], -1), dtype)


def box_search(valid_fn, center, half, n_coarse: int, n_fine: int):
    """Find the region where ``valid_fn`` holds, in two grid stages (no gradient).

    Args:
        valid_fn: maps points ``[M, 2]`` to a bool mask ``[M]``.
        center: ``[2]`` centre of the coarse square search.
        half: half side of the coarse square.
        n_coarse, n_fine: cells per side of the two grids.

    Returns:
        ``(points [n_fine², 2], cell_area, any_valid)``: the cell centres of a fine grid over
        the bounding box of the valid coarse cells grown by one coarse cell (the whole coarse
        square if none is valid).
    """
    center = jax.lax.stop_gradient(center)
    half = jax.lax.stop_gradient(half)
    dtype = center.dtype
    coarse = center + half * _cells(n_coarse, dtype)
    v = jax.lax.stop_gradient(valid_fn(coarse))
    cell = 2.0 * half / n_coarse
    big = jnp.asarray(jnp.finfo(dtype).max, dtype)
    lo = jnp.min(jnp.where(v[:, None], coarse, big), 0) - cell
    hi = jnp.max(jnp.where(v[:, None], coarse, -big), 0) + cell
    anyv = jnp.any(v)
    lo = jnp.where(anyv, lo, center - half)
    hi = jnp.where(anyv, hi, center + half)
    mid, span = 0.5 * (lo + hi), 0.5 * (hi - lo)
    fine = mid + span * _cells(n_fine, dtype)
    area = jnp.prod(2.0 * span) / (n_fine * n_fine)
    return fine, area, anyv


class RelativeIllumination(eqx.Module):
    """Relative illumination of a set of fields.

    Attributes:
        field: ``[F, 2]`` (θx, θy) in degrees.
        image_xy: ``[F, 2]`` centroid of each field's image on the image surface (mm).
        ri: ``[F]`` irradiance relative to the on-axis irradiance.
        irradiance: ``[F]`` irradiance for unit object radiance (unit area/unit solid angle
            conventions as in the module docstring; only ratios are meaningful).
    """

    field: Float[Array, "F 2"]
    image_xy: Float[Array, "F 2"]
    ri: Float[Array, " F"]
    irradiance: Float[Array, " F"]


def _irradiance(lens: Lens, t, depth, wl, n_coarse, n_fine, newton_iters):
    """E and the image centroid for one field, given by t = tan(θ) (infinity) or the object
    point's (X, Y) (finite depth)."""
    zep = paraxial.entrance_pupil_z(lens)
    r_ep = 0.5 * lens.epd

    def launch(s, plane_xy):
        o_plane = jnp.concatenate([plane_xy, jnp.broadcast_to(zep, plane_xy.shape[:-1])[..., None]],
                                  -1)
        if depth is None:
            d = jnp.concatenate([s, jnp.ones_like(s[:1])])
            d = d / jnp.linalg.norm(d)
            return Rays(o_plane, jnp.broadcast_to(d, o_plane.shape), wl)
        p = jnp.concatenate([s, -depth[None]])
        v = o_plane - p
        d = v / jnp.linalg.norm(v, axis=-1, keepdims=True)
        return Rays(jnp.broadcast_to(p, o_plane.shape), d, wl)

    def valid_fn(pts):
        return trace(lens, launch(t, pts), newton_iters=newton_iters).valid

    # The beam through the entrance-pupil centre is near the chief ray.
    fine, area, _ = box_search(valid_fn, jnp.zeros(2, t.dtype), 3.0 * r_ep, n_coarse, n_fine)

    def centroid(s):
        rays = launch(s, fine)
        out = trace(lens, rays, newton_iters=newton_iters)
        w = out.valid.astype(t.dtype)
        if depth is not None:
            w = w * rays.direction[..., 2] ** 4
        tot = jnp.maximum(jnp.sum(w), jnp.finfo(t.dtype).tiny)
        cen = jnp.sum(w[:, None] * out.origin[:, :2], 0) / tot
        return cen, (jnp.sum(w), rays.direction)

    jac, (wsum, dirs) = jax.jacfwd(centroid, has_aux=True)(t)
    cen, _ = centroid(t)
    det = jnp.abs(jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0])
    det = jnp.where(det > 0, det, jnp.inf)
    if depth is None:
        cos4 = dirs[0, 2] ** 4
        e = wsum * area * cos4 / det
    else:
        e = wsum * area / (zep + depth) ** 2 / det
    return e, cen


@eqx.filter_jit
def _ri_impl(lens, fields, depth, wl, *, n_coarse, n_fine, newton_iters):
    dtype = fields.dtype
    lens = apertured(lens.astype(dtype))
    th = jnp.deg2rad(fields)
    if depth is None:
        s = jnp.tan(th)
    else:
        zep = paraxial.entrance_pupil_z(lens)
        s = -jnp.tan(th) * (zep + depth)

    def one(si):
        return _irradiance(lens, si, depth, wl, n_coarse, n_fine, newton_iters)

    e, cen = jax.vmap(one)(s)
    e0, _ = one(jnp.zeros(2, dtype))
    return e / e0, e, cen


def relative_illumination(
    lens: Lens,
    fields,
    *,
    depth=math.inf,
    wavelength=None,
    pupil: int = 128,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> RelativeIllumination:
    """Relative illumination at a set of fields, by forward tracing (see the module docstring).

    Args:
        lens: the lens.
        fields: ``[F]`` θy or ``[F, 2]`` (θx, θy), degrees.
        depth: object distance in mm in front of surface 1, ``inf`` for infinity.
        wavelength: µm (default the primary wavelength).
        pupil: cells per side of the fine pupil grid (the coarse grid has a third of that,
            at least 16).
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        A :class:`RelativeIllumination`; ``image_xy`` tells where on the sensor each value
        applies.
    """
    dtype = jnp.result_type(float)
    f = jnp.asarray(fields, dtype)
    if f.ndim == 0:
        f = f[None]
    if f.ndim == 1:
        f = jnp.stack([jnp.zeros_like(f), f], -1)
    if f.ndim != 2 or f.shape[-1] != 2:
        raise ValueError(f"relative_illumination: fields must be [F] or [F, 2], got {f.shape}")
    wl = jnp.asarray(lens.primary_wavelength if wavelength is None else wavelength, dtype)
    ri, e, cen = _ri_impl(lens, f, _static_depth(depth), wl, n_coarse=max(16, pupil // 3),
                          n_fine=int(pupil), newton_iters=newton_iters)
    return RelativeIllumination(f, cen, ri, e)
