"""Pieces of the optical transfer function shared by ``psf.mtf`` and the tolerance metric's
MTF (``analysis.tolerance_metric.field_mtf``): the diffraction-limited MTF of a circular
pupil and the tangential and sagittal directions of a field in the image plane.

Both are differentiable everywhere their value is: the square roots and the arccos see a
safe argument where their value is not used (a "double where"), so a frequency at or
beyond the cut-off and an on-axis field give a finite gradient, not NaN.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from .sampling import field_xy


def diffraction_mtf(nu, lam_mm, fnum) -> Array:
    """MTF of an aberration-free circular pupil at ``nu`` cycles/mm, wavelength ``lam_mm``
    (mm) and working F-number ``fnum``: (2/π)(arccos s − s√(1 − s²)) with s = ν·λ·F#, and 0
    from the cut-off (s ≥ 1) on. Its gradient is 0 there (it was NaN: the unused branch's
    arccos and square root at s = 1 have infinite slopes). At ν = 0 it is the slope on
    ν ≥ 0, −4/(π ν_c) (``jnp.maximum``'s tie rule had given half of it)."""
    s = nu * lam_mm * fnum
    s = jnp.where(s < 0, 0.0, s)
    inside = s < 1
    s = jnp.where(inside, s, 0.0)
    value = (2 / jnp.pi) * (jnp.arccos(s) - s * jnp.sqrt(1.0 - s * s))
    return jnp.where(inside, value, 0.0)


def mtf_directions(field) -> tuple[Float[Array, "*b 2"], Float[Array, "*b 2"]]:
    """Unit tangential (radial) and sagittal directions in the image plane of fields θy or
    (θx, θy) in degrees (leading axes batch): the tangential one along (tan θx, tan θy),
    (0, 1) on axis; the sagittal one that turned by −90°. The gradient on axis is finite
    (the norm's square root of 0 had made it NaN)."""
    t = jnp.tan(field_xy(field))
    r2 = jnp.sum(t * t, -1, keepdims=True)
    on_axis = r2 == 0
    r = jnp.sqrt(jnp.where(on_axis, 1.0, r2))
    e_t = jnp.where(on_axis, jnp.asarray([0.0, 1.0], t.dtype), t / r)
    return e_t, jnp.stack([e_t[..., 1], -e_t[..., 0]], -1)
