"""The paper's three optical regularizers, as squared hinges with zero gradient inside bounds.

Conventions:
    Lengths in mm. Each regularizer returns a vector of hinge residuals ``h`` with
    ``h = 0`` (and a zero gradient) wherever the lens is inside the bound; its penalty is
    ``Σ h²``. The bounds are the published ones (Yang, Fu & Heidrich 2024, Methods):

    * ray obliquity: the cosine between every ray and the surface normal, on both sides of
      every refracting surface, stays ≥ ε = 0.7 (angles ≤ 45.6°);
    * surface spacing: the axial distance between neighbouring surfaces, sampled over the
      radius out to the larger clear semi-diameter of the pair, stays ≥ 0.4 mm within an
      element and ≥ 0.2 mm between elements (and ≥ ``bfl`` to the sensor, ≥ a small stop
      clearance next to the stop);
    * surface slope: |dz/dr| over each surface's clear aperture stays ≤ ε = 0.5.

    Clear semi-diameters are the largest ray heights of the traced design rays on each
    surface (held constant for the gradient).

    Each penalty is a mean over its samples per surface (or gap), summed over surfaces, so a
    bound violated by v everywhere on one surface costs v², independent of the sampling
    density.

    The spacing and slope hinges grow logarithmically beyond ``HINGE_SCALE`` (``h ↦
    H·log(1 + h/H)``): a random start's high-order asphere evaluated out at the larger clear
    radius of a pair can violate a bound by 1e19 mm, whose square overflows float32 and
    made the whole design loss infinite. Small violations (h ≪ H) are unchanged to first
    order, and the gradient never vanishes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..optics.lens import Lens
from ..optics.rays import Rays
from ..tracing.step import surface_normal

OBLIQUITY_BOUND = 0.7
SLOPE_BOUND = 0.5
HINGE_SCALE = 1.0  # mm for spacing, dimensionless for slope


def _soft_hinge(excess):
    """``relu(excess)``, growing as ``H·log(1 + excess/H)`` beyond ``H`` (no overflow)."""
    h = jax.nn.relu(excess)
    return HINGE_SCALE * jnp.log1p(h / HINGE_SCALE)


def clear_radii(path: Rays) -> Float[Array, " n"]:
    """Largest valid ray height on each lens surface (mm), without gradient.

    Args:
        path: stacked rays ``[n + 1, ...]`` from ``trace_path`` (the image row is
            ignored).
    """
    h = jnp.hypot(path.origin[:-1, ..., 0], path.origin[:-1, ..., 1])
    h = jnp.where(path.valid[:-1], h, 0.0)
    return jax.lax.stop_gradient(jnp.max(h.reshape(h.shape[0], -1), axis=-1))


def _unit_normal(surface, x, y, z):
    n = jnp.stack(surface_normal(surface, x, y, z), -1)
    return n / jnp.linalg.norm(n, axis=-1, keepdims=True)


def obliquity(stack, z_vertex, stop: int, rays_in: Rays, path: Rays, *,
              bound: float = OBLIQUITY_BOUND):
    """Hinge residuals of ray obliquity, one per refracting surface and leading ray axis.

    Args:
        stack: the lens surfaces stacked on a leading axis (``stacked_surfaces``).
        z_vertex: ``[n]`` global z of the surface vertices (mm).
        stop: index of the stop (not a refracting surface).
        rays_in: the launched rays (their directions are the incident directions at surface 1).
        path: stacked rays ``[n + 1, ...]`` from ``trace_path``.
        bound: the cosine bound ε.
    """
    n_surf = path.origin.shape[0] - 1
    d_in = jnp.concatenate([rays_in.direction[None], path.direction[: n_surf - 1]])
    p = path.origin[:n_surf]
    z_local = p[..., 2] - z_vertex.reshape((-1,) + (1,) * (p.ndim - 2))
    n = jax.vmap(_unit_normal)(stack, p[..., 0], p[..., 1], z_local)
    cos_in = jnp.abs(jnp.sum(d_in * n, -1))
    cos_out = jnp.abs(jnp.sum(path.direction[:n_surf] * n, -1))
    h = jax.nn.relu(bound - jnp.minimum(cos_in, cos_out))
    h = jnp.where(path.valid[:n_surf], h, 0.0)
    h = jnp.delete(h, stop, axis=0, assume_unique_indices=True)
    # One residual per (surface, leading ray axis): the root sum of squares of its hinges,
    # which keeps Σ residuals² = mean hinge² with far fewer residuals for least squares.
    per_surface = h[0].size
    h = h.reshape(h.shape[0], h.shape[1] if h.ndim > 2 else 1, -1)
    ss = jnp.sum(h * h, -1) / per_surface
    ok = ss > 0
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, ss, 1.0)), 0.0).reshape(-1)


def _sag_r(surface, r):
    z, _ = surface.sag(jnp.zeros_like(r), r)
    return z


def spacing(lens: Lens, stack, radii, bounds, *, n_radial: int = 16):
    """Hinge residuals of the axial spacing of every neighbouring pair (mm).

    Args:
        lens: the lens (for vertex positions and the image surface).
        stack: the lens surfaces stacked on a leading axis.
        radii: ``[n]`` clear semi-diameters of the lens surfaces (mm).
        bounds: ``[n]`` minimum spacing of gap i (surface i to i+1; last: to the image).
        n_radial: radial samples per gap (from the axis to the larger clear radius).
    """
    zs = jnp.concatenate([lens.vertex_z(), lens.image_z()[None]])
    rr = jnp.concatenate([radii, radii[-1:]])
    u = jnp.linspace(0.0, 1.0, n_radial, dtype=zs.dtype)
    r = u[None, :] * jnp.maximum(rr[:-1], rr[1:])[:, None]  # [n, R]
    z_this = jax.vmap(_sag_r)(stack, r)
    z_next_lens = jax.vmap(_sag_r)(jax.tree.map(lambda x: x[1:], stack), r[:-1])
    z_img = _sag_r(lens.image, r[-1])
    z_next = jnp.concatenate([z_next_lens, z_img[None]])
    gap = zs[1:, None] + z_next - zs[:-1, None] - z_this
    h = _soft_hinge(bounds[:, None] - gap).reshape(-1)
    return h / jnp.sqrt(n_radial)


def slope(stack, stop: int, radii, *, bound: float = SLOPE_BOUND, n_radial: int = 16):
    """Hinge residuals of the surface slope |dz/dr| over each clear aperture."""
    u = jnp.linspace(0.0, 1.0, n_radial, dtype=radii.dtype)
    r = u[None, :] * radii[:, None]

    def grad_r(surface, rr):
        _, _, gy, _ = surface.sag_and_grad(jnp.zeros_like(rr), rr)
        return gy

    g = jax.vmap(grad_r)(stack, r)
    h = _soft_hinge(jnp.abs(g) - bound)
    h = jnp.delete(h, stop, axis=0, assume_unique_indices=True).reshape(-1)
    return h / jnp.sqrt(n_radial)
