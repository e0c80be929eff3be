"""Pieces of the optical transfer function shared by ``psf.mtf`` and the tolerance metric's
MTF (``analysis.tolerance_metric.field_mtf``): the diffraction-limited MTF of a circular
pupil and the tangential and sagittal directions of a field in the image plane.

Both are differentiable everywhere their value is: the square roots and the arccos see a
safe argument where their value is not used (a "double where"), so a frequency at or
beyond the cut-off and an on-axis field give a finite gradient, not NaN.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks
from . import telecentric
from .sampling import field_xy

WAVELENGTH_RANGE_MM = tuple(w * 1e-3 for w in checks.GENERIC_RANGE_UM)
"""The wavelengths (mm) ``diffraction_mtf`` takes: ``checks.GENERIC_RANGE_UM`` in mm."""


def _check_mtf_args(nu, lam_mm, fnum) -> None:
    """Refuse concrete arguments of ``diffraction_mtf`` out of range: a negative or NaN
    frequency gave 1 or 0, a wavelength in µm or nm (0.55, 550 for 5.5e-4 mm) an MTF of 0 at
    any frequency, and an F-number of 0 or below an MTF of 1 (its callers pass traced values,
    checked where they are made)."""
    where = "diffraction_mtf"
    if not checks.is_traced(nu):
        checks.real_values(nu, "nu", where, "cycles/mm")
        checks.values(nu, "nu", where, lo=0, unit="cycles/mm")
    if not checks.is_traced(lam_mm):
        checks.real_values(lam_mm, "lam_mm", where, "mm")
        a = np.asarray(lam_mm, dtype=float)
        lo, hi = WAVELENGTH_RANGE_MM
        bad = ~np.isfinite(a) | (a < lo) | (a > hi)
        if np.any(bad):
            v = float(a[bad].reshape(-1)[0])
            hint = (f" ({v:g} µm is {v * 1e-3:g} mm)" if 0.1 <= v <= 30
                    else f" ({v:g} nm is {v * 1e-6:g} mm)" if 100 <= v <= 30000 else "")
            raise ValueError(f"{where}: lam_mm must be a wavelength in mm, in [{lo:g}, {hi:g}] "
                             f"mm, got {v:g}{hint}")
    if not checks.is_traced(fnum):
        checks.real_values(fnum, "fnum", where)
        checks.values(fnum, "fnum (the working F-number)", where, lo=0, lo_open=True)


def diffraction_mtf(nu, lam_mm, fnum) -> Array:
    """MTF of an aberration-free circular pupil at ``nu`` cycles/mm, wavelength ``lam_mm``
    (mm) and working F-number ``fnum``: (2/π)(arccos s − s√(1 − s²)) with s = ν·λ·F#, and 0
    from the cut-off (s ≥ 1) on. Its gradient is 0 there (it was NaN: the unused branch's
    arccos and square root at s = 1 have infinite slopes). At ν = 0 it is the slope on
    ν ≥ 0, −4/(π ν_c) (``jnp.maximum``'s tie rule had given half of it).

    Concrete arguments are checked: ν ≥ 0, λ in ``WAVELENGTH_RANGE_MM`` and F# > 0, finite."""
    _check_mtf_args(nu, lam_mm, fnum)
    s = nu * lam_mm * fnum
    s = jnp.where(s < 0, 0.0, s)
    inside = s < 1
    s = jnp.where(inside, s, 0.0)
    value = (2 / jnp.pi) * (jnp.arccos(s) - s * jnp.sqrt(1.0 - s * s))
    return jnp.where(inside, value, 0.0)


def mtf_directions(field, *, heights: bool = False
                   ) -> tuple[Float[Array, "*b 2"], Float[Array, "*b 2"]]:
    """Unit tangential (radial) and sagittal directions in the image plane of fields θy or
    (θx, θy) in degrees (leading axes batch): the tangential one along (tan θx, tan θy),
    (0, 1) on axis; the sagittal one that turned by −90°. The gradient on axis is finite
    (the norm's square root of 0 had made it NaN).

    ``heights`` (an object-space telecentric lens, ``Lens.telecentric_object``): the
    fields are object heights in mm, y or (x, y), and the tangential direction is along
    (x, y) itself, the image of a radial line being radial in a rotationally symmetric lens
    (the magnification's sign only reverses it). Read as angles, (2, −4) mm had its
    direction off by 0.03° (tan 2°/tan 4° is not 1/2) and a height of 90 mm or more was
    refused as a field angle outside (−90°, 90°).
    """
    t = telecentric.height_xy(field, "mtf_directions") if heights else jnp.tan(
        field_xy(field))
    r2 = jnp.sum(t * t, -1, keepdims=True)
    on_axis = r2 == 0
    r = jnp.sqrt(jnp.where(on_axis, 1.0, r2))
    e_t = jnp.where(on_axis, jnp.asarray([0.0, 1.0], t.dtype), t / r)
    return e_t, jnp.stack([e_t[..., 1], -e_t[..., 0]], -1)


def check_cutoff(fnum, where: str) -> None:
    """Refuse, naming ``where``, a concrete paraxial working F-number ``fnum`` that is not
    finite: the image lies at infinity (an afocal lens, or the object in the front focal
    plane), so the diffraction cut-off 1/(λN) is 0: the diffraction MTF was 0 at every
    frequency, the default frequencies all 0 and the default pixel size inf."""
    if checks.is_traced(fnum) or np.all(np.isfinite(np.asarray(fnum, dtype=float))):
        return
    raise ValueError(
        f"{where}: the paraxial working F/# of the object traced is infinite (its image lies "
        f"at infinity: an afocal lens, or the object in the front focal plane), so there is "
        f"no diffraction cut-off 1/(λN) to scale the diffraction MTF, the default "
        f"frequencies or the default pixel_size by; pass diffraction=False, pixel_size (mm) "
        f"and frequencies (cycles/mm), or for an afocal lens mark its image space "
        f"(Lens(afocal_image=True)) and use analysis.angular_spot")
