"""Afocal image space: angular spot sizes and angular magnification.

A lens with ``Lens.afocal_image`` (a telescope, a beam expander; Zemax's "Afocal Image
Space") images to infinity: each field's image is a bundle of directions, not of points.

Conventions:
    Angles in radians in the arrays (the report gives mrad), field angles in degrees,
    wavelengths in µm. Image space looks along +z, or along −z after an odd number of
    mirrors (``Lens.mirrors``): that is the axis the output angles are measured from.
    A ray's angular coordinates about a reference direction c (a unit vector) are the
    tangents of its angles to c in two perpendicular planes through c:
    (d·e_x, d·e_y)/(d·c) for the ray's unit direction d, with e_x the unit vector along
    the part of +x normal to c and e_y = c × e_x (for c = +z: e_x = +x, e_y = +y). To
    first order they are the angles in radians, and they do not shrink a tangential
    spread by cos θ′ as direction-cosine differences would. The reference of each field
    is its primary-wavelength chief ray (the ray through the centre of the paraxial
    entrance pupil) after the last surface. RMS angular radius = sqrt(mean |a − a_ref|²)
    over the valid rays, a_ref the centroid of the same rays (default) or the chief ray
    (0); the pupil is the 21×21 grid of the spot analyses (317 rays).
    The paraxial angular magnification is u′/u for a ray from an object at infinity,
    with u, u′ the slopes in object and image space (signed as Zemax's: negative for an
    inverting telescope), = D·n/n′ from the system matrix (n, n′ the object- and
    image-space indices, n′ negative after an odd number of mirrors). Per field the real
    one is tan θ′/tan θ of the chief ray, along the field's direction (θ′ measured from
    the image-space axis above).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..imaging.sampling import field_rays, lens_depth, pupil_grid
from ..optics import checks, paraxial
from ..optics.lens import Lens
from ..optics.travel import travel_senses
from ..tracing.forward import trace
from .spots import PUPIL_GRID, check_inputs, fields_array, weighted_centroid, weighted_rms

REFERENCES = ("centroid", "chief")


class AngularSpot(eqx.Module):
    """Angular spot sizes (radians) of F fields and W wavelengths; NaN where no ray (or,
    for the chief-ray frame every value needs, no chief ray) gets through.

    ``chief_angle`` is the primary chief ray's direction in image space as angles (θx′, θy′)
    in degrees from the image-space axis (tan θx′ = d_x/|d_z|, tan θy′ = d_y/|d_z|), and
    ``magnification`` its tan θ′/tan θ along the field's direction (NaN on axis and for an
    object at a finite distance, which has no field angle at infinity to compare)."""

    per_wavelength: Float[Array, "F W"]
    polychromatic: Float[Array, " F"]
    valid_fraction: Float[Array, "F W"]
    chief_angle: Float[Array, "F 2"]
    magnification: Float[Array, " F"]


def image_axis_sign(lens: Lens) -> int:
    """+1 where light leaves along the image space's +z, −1 where toward −z (after an odd
    number of mirrors, unless coordinate breaks turn the frame round: ``travel_senses``)."""
    return travel_senses(lens)[-1]


def angular_magnification(lens: Lens, wavelength=None) -> Array:
    """The paraxial angular magnification u′/u (see the module notes); 1/(the beam's
    magnification) for a lens in air. Defined for any lens, meaningful for an afocal one
    (for a lens with power the output slope also depends on the ray's height)."""
    if not isinstance(lens, Lens):
        raise TypeError(f"angular_magnification: lens must be a jaxlens.Lens, got "
                        f"{type(lens).__name__}")
    checks.lens_intact(lens, "angular_magnification")
    wl = lens.primary_wavelength if wavelength is None else wavelength
    # Traced too (an error_if): under jit, 550 (nm) gave a magnification of -6.8 for -4.
    wl = checks.wavelengths(lens, wl, "angular_magnification", "wavelength")
    _, _, _, d = paraxial.system_matrix(lens, wl)
    n = paraxial.signed_indices(lens, wl)
    return d * n[0] / n[-1]


def angular_spot(
    lens: Lens,
    fields=None,
    wavelengths=None,
    *,
    pupil=None,
    reference: str = "centroid",
    depth=None,
) -> AngularSpot:
    """RMS angular spot radius per field and wavelength, and polychromatic (radians).

    Args:
        lens: the lens (an afocal one: ``lens.afocal_image``; the directions of any lens's
            rays can be measured, but a lens with an image at a finite distance is
            measured by ``rms_spot``).
        fields: field angles in degrees, ``[F]`` (y) or ``[F, 2]``; default ``lens.fields``.
        wavelengths: µm, ``[W]``; default ``lens.wavelengths``.
        pupil: ``[M, 2]`` unit-pupil points; default the 21×21 grid (317 rays).
        reference: "centroid" or "chief" (the primary-wavelength chief ray).
        depth: object distance in mm (``inf`` for infinity), or None for the lens's own.
    """
    where = "angular_spot"
    pupil = check_inputs(lens, where, fields=fields, wavelengths=wavelengths, pupil=pupil,
                         own="all")
    if reference not in REFERENCES:
        raise ValueError(f"{where}: reference must be one of {REFERENCES}, got {reference!r}")
    fields = lens.fields if fields is None else fields
    wavelengths = lens.wavelengths if wavelengths is None else wavelengths
    dtype = lens.epd.dtype
    f = fields_array(jnp.asarray(fields, dtype), where)
    w = jnp.atleast_1d(jnp.asarray(wavelengths, dtype))
    if w.ndim != 1 or w.size == 0:
        raise ValueError(f"{where}: wavelengths must be [W] µm with W >= 1, got shape {w.shape}")
    p = pupil_grid(PUPIL_GRID, dtype) if pupil is None else jnp.asarray(pupil, dtype)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] == 0:
        raise ValueError(f"{where}: pupil must be [M, 2] normalised pupil points (Px, Py) "
                         f"with M >= 1, got shape {p.shape}")
    return _angular_spot(lens, f, w, p,
                         reference=reference, depth=lens_depth(lens, depth, where))


def _frame(c):
    """(e_x, e_y) normal to the unit vector c: e_x along the part of +x normal to c (+y's
    where c is along x), e_y = c × e_x."""
    x = jnp.array([1.0, 0.0, 0.0], c.dtype)
    y = jnp.array([0.0, 1.0, 0.0], c.dtype)
    along_x = jnp.abs(c[0]) > 0.9
    a = jnp.where(along_x, y, x)
    ex = a - jnp.dot(a, c) * c
    ex = ex / jnp.linalg.norm(ex)
    ey = jnp.cross(c, ex)
    return ex, ey


@eqx.filter_jit
def _angular_spot(lens, fields, wavelengths, pupil, *, reference, depth) -> AngularSpot:
    centre = jnp.zeros((1, 2), pupil.dtype)
    s = image_axis_sign(lens)

    def per_field(field):
        chief = trace(lens, field_rays(lens, field, centre, lens.primary_wavelength,
                                       depth=depth))
        c, c_ok = chief.direction[0], chief.valid[0]
        ex, ey = _frame(c)

        def per_wl(wl):
            r = trace(lens, field_rays(lens, field, pupil, wl, depth=depth))
            dc = r.direction @ c
            ok = r.valid & (dc > 0)
            safe = jnp.where(ok, dc, 1.0)
            a = jnp.stack([r.direction @ ex, r.direction @ ey], -1) / safe[:, None]
            return jnp.where(ok[:, None], a, 0.0), ok.astype(a.dtype), r.valid

        a, wgt, valid = jax.vmap(per_wl)(wavelengths)  # [W, M, 2], [W, M], [W, M]
        ref = (weighted_centroid(a, wgt) if reference == "centroid"
               else jnp.zeros(a.shape[:1] + (2,), a.dtype))
        per = weighted_rms(a, wgt, ref)
        poly = weighted_rms(a.reshape(-1, 2), wgt.reshape(-1),
                            None if reference == "centroid" else jnp.zeros(2, a.dtype))
        per = jnp.where(c_ok, per, jnp.nan)
        poly = jnp.where(c_ok, poly, jnp.nan)
        axial = s * c[2]
        tan_out = c[:2] / jnp.where(axial > 0, axial, 1.0)
        angle = jnp.where(c_ok & (axial > 0), jnp.rad2deg(jnp.arctan(tan_out)), jnp.nan)
        t = jnp.tan(jnp.deg2rad(jnp.atleast_1d(field)))
        t = jnp.concatenate([jnp.zeros(1, t.dtype), t]) if t.shape[0] == 1 else t
        t2 = jnp.dot(t, t)
        mag = jnp.dot(tan_out, t) / jnp.where(t2 > 0, t2, 1.0)
        mag = jnp.where(c_ok & (axial > 0) & (t2 > 0) & (depth is None), mag, jnp.nan)
        return per, poly, jnp.mean(valid, -1, dtype=a.dtype), angle, mag

    per, poly, frac, angle, mag = jax.vmap(per_field)(fields)
    return AngularSpot(per, poly, frac, angle, mag)
