"""Aberration curves: transverse ray fans and field curvature (the astigmatic focal lines).

Conventions (those of Zemax and optiland):
    Fields are angles θy in degrees (a field along +y), so for a rotationally symmetric
    lens the tangential plane is the y–z plane and the sagittal plane the x–z plane. A ray
    fan also takes a field (θx, θy); its fans stay along the pupil's y and x axes, as in
    Zemax.
    Pupil coordinates Px, Py are normalised to the paraxial entrance pupil (−1 … 1).
    Lengths are mm, wavelengths µm.

    Ray fan: the tangential fan traces the pupil points (0, Py) and gives
    e_y = y − y_chief on the image surface; the sagittal fan traces (Px, 0) and gives
    e_x = x − x_chief. The reference is the chief ray (pupil centre) of the primary
    wavelength for every wavelength, so lateral colour shows as an offset of the others.

    Field curvature: for each field and wavelength, where the rays next to the chief ray
    cross it, in the y–z plane (tangential focus) and in the x–z plane (sagittal focus),
    given as the z distance from the chief ray's intercept with the image surface, along +z
    as in Zemax and optiland (negative: toward −z; that is before the image surface, toward
    the lens, where light travels toward +z, and beyond it where light leaves an odd number
    of mirrors toward −z). A field (θx, θy) has its tangential plane along its
    azimuth a = (tan θx, tan θy)/|…| (the meridional plane of a rotationally symmetric lens):
    the tangential neighbours leave the pupil along a and are met in the plane of a and z,
    the sagittal ones along a⊥ = (a_y, −a_x); on axis a = (0, 1), so a θy field and the field
    (0, θy) give the same foci. The neighbours are exact differential rays: the derivative
    of the image-space ray with respect to Py (Px) is taken by forward-mode differentiation
    of the trace (``jax.jvp``), which is the limit of optiland's finite parabasal pair. With
    P the chief ray's intercept, D its direction and dP, dD their derivatives, the neighbour
    meets the chief ray at P + s·D with s = −(dP × D)/(dD × D) (the 2-D cross product in the
    plane of e and z, e the plane's unit vector in x, y: u × v = (u·e) v_z − u_z (v·e)), and
    the focus is s·D_z from the image surface. Astigmatism is tangential −
    sagittal. A focus at infinity (image space afocal for that fan) is ±inf; a field whose
    chief ray does not reach the image is NaN. An object-space telecentric lens's fields
    are object heights (mm), y or (x, y), its chief rays parallel to the axis (pupil centre,
    ``sampling.field_rays``) and its azimuth a = (x, y)/|(x, y)|; the foci are found alike.

    Against optiland 0.6.3 (``tests/test_conventions_vs_optiland.py``: the Cooke triplet,
    the double Gauss at infinity and at 300 mm, a triplet with even aspheres; F, d and C
    lines): ray fans agree to 2e-13 mm at every wavelength, sagittal foci to 5e-11 mm and
    tangential foci to 5e-8 mm (optiland's parabasal pair at ±1e-5 of the pupil is a finite
    difference).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from ..imaging.sampling import field_rays, lens_aim, lens_depth
from ..imaging.telecentric import azimuth, largest_height, lens_field, lens_fields
from ..optics import checks
from ..optics.lens import Lens
from ..tracing.forward import DEFAULT_NEWTON_ITERS, aimed_jit, forward_mode_jit, trace

# Default number of points across the pupil in a fan, and of fields in a curvature curve.
FAN_POINTS = 21
CURVE_FIELDS = 11


class RayFan(eqx.Module):
    """Transverse ray errors (mm) of one field for W wavelengths at n pupil coordinates."""

    field: Float[Array, ""] | Float[Array, " 2"]  # θy, or (θx, θy), degrees (mm: telecentric)
    wavelengths: Float[Array, " W"]
    pupil: Float[Array, " n"]
    tangential: Float[Array, "W n"]  # e_y of the rays (0, Py)
    sagittal: Float[Array, "W n"]  # e_x of the rays (Px, 0)
    valid_tangential: Bool[Array, "W n"]
    valid_sagittal: Bool[Array, "W n"]


class FieldCurvature(eqx.Module):
    """Tangential and sagittal foci (mm from the image surface along z) of F fields."""

    fields: Float[Array, " F"] | Float[Array, "F 2"]  # θy, or (θx, θy), deg (mm: telecentric)
    wavelengths: Float[Array, " W"]
    tangential: Float[Array, "W F"]
    sagittal: Float[Array, "W F"]

    @property
    def astigmatism(self) -> Float[Array, "W F"]:
        """Tangential minus sagittal focus (mm)."""
        return self.tangential - self.sagittal


def _inputs(lens, where: str, fields, wavelengths, *, pairs: bool = False, arg: str = "fields"):
    """Checked fields (θy, deg, ``[F]``; with ``pairs`` also (θx, θy), ``[F, 2]``) and
    wavelengths (µm, ``[W]``) as lens-dtype arrays."""
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    dtype = lens.epd.dtype
    # Before jnp.asarray, which reads the string "5" as 5°.
    checks.real_values(fields, "fields", where, "deg")
    if wavelengths is not None:
        checks.real_values(wavelengths, "wavelengths", where, "µm")
    f = jnp.asarray(fields, dtype)
    if (f.ndim > 1 and not (pairs and f.ndim == 2 and f.shape[1] == 2)) or f.size == 0:
        also = ", or (θx, θy) pairs [F, 2]" if pairs else " (these curves are for fields along y)"
        raise ValueError(f"{where}: fields must be θy angles in degrees, one value or [F]"
                         f"{also}, got shape {f.shape}")
    if not lens.telecentric_object:  # else object heights (mm), checked by field_rays
        checks.field_angles(f, where, "field")
    # As Lens does: np.radians([0, 14, 20]) traced as 0.35° at most.
    if not checks.is_traced(f) and not lens.telecentric_object:
        checks.warn_if_radian_fields(f, where, arg)
    wl = lens.wavelengths if wavelengths is None else jnp.asarray(wavelengths, dtype)
    if wl.ndim > 1 or wl.size == 0:
        raise ValueError(f"{where}: wavelengths must be µm, one value or [W], got shape "
                         f"{wl.shape}")
    checks.wavelengths(lens, wl, where, "wavelengths")
    checks.material_indices(lens, wl, where, "wavelengths")
    return (f if f.ndim == 2 else f.reshape(-1)), wl.reshape(-1)


def _image_rays(lens, field, wavelength, pupil, depth, aim):
    rays = field_rays(lens, field, pupil, wavelength, depth=depth, aim=aim)
    return trace(lens, rays, newton_iters=DEFAULT_NEWTON_ITERS, chunk=None)


def ray_fan(lens: Lens, field, wavelengths=None, *, n: int = FAN_POINTS, depth=None,
            aim: str | None = None) -> RayFan:
    """Tangential and sagittal ray fans of one field (see the module notes).

    Args:
        lens: the lens.
        field: θy, or (θx, θy), in degrees; an object height in mm, y or (x, y), for an
            object-space telecentric lens.
        wavelengths: µm, one value or ``[W]``; default the lens's wavelengths.
        n: pupil points per fan, evenly spaced over −1 … 1.
        depth: object distance (mm) for a finite object; default the lens's object.
        aim: ``"paraxial"`` (the paraxial entrance pupil), ``"real"`` or
            ``"real_marginal"`` (the real stop, as ``sampling.field_rays``);
            None (the default): the lens's own ray aiming, ``lens.aim``.

    Returns:
        A ``RayFan``; errors of rays that do not reach the image (and all errors where the
        chief ray does not) are NaN, with the validity flags beside them.
    """
    checks.focal_image(lens, "ray_fan")
    lens_field(lens, field, "ray_fan")  # an object height (mm) or an angle (deg)
    shape = np.shape(field)
    f, wl = _inputs(lens, "ray_fan", jnp.reshape(jnp.asarray(field, float), (-1,)),
                    wavelengths, arg="field")
    n = checks.number(n, "n", "ray_fan", lo=2, hi=checks.MAX_SAMPLES, integer=True,
                      unit="pupil points")
    checks.primary_wavelength(lens, "ray_fan", "the chief ray's")
    return _ray_fan(lens, f if shape == (2,) else f[0], wl, n=int(n),
                    depth=lens_depth(lens, depth, "ray_fan"), aim=lens_aim(lens, aim, "ray_fan"))


@checks.checked_core(aimed_jit)
def _ray_fan(lens, field, wl, *, n, depth, aim) -> RayFan:
    t = jnp.linspace(-1.0, 1.0, n, dtype=wl.dtype)
    zero = jnp.zeros_like(t)
    chief = _image_rays(lens, field, lens.primary_wavelength, jnp.zeros((1, 2), wl.dtype),
                        depth, aim)
    ref = jnp.where(chief.valid[0], chief.origin[0, :2], jnp.nan)

    def one(w):
        tan = _image_rays(lens, field, w, jnp.stack([zero, t], -1), depth, aim)
        sag = _image_rays(lens, field, w, jnp.stack([t, zero], -1), depth, aim)
        vt, vs = tan.valid & chief.valid[0], sag.valid & chief.valid[0]
        return (jnp.where(vt, tan.origin[:, 1] - ref[1], jnp.nan),
                jnp.where(vs, sag.origin[:, 0] - ref[0], jnp.nan), vt, vs)

    et, es, vt, vs = jax.vmap(one)(wl)
    return RayFan(field, wl, t, et, es, vt, vs)


def default_fields(lens: Lens, count: int = CURVE_FIELDS) -> Array:
    """``count`` θy angles from 0 to the lens's largest field (deg): for ``[F, 2]`` fields
    (θx, θy) the largest radial angle, tan²θ = tan²θx + tan²θy. For an object-space
    telecentric lens ``count`` object heights y from 0 to its largest (radial) height (mm)."""
    checks.number(count, "count", "default_fields", lo=1, hi=checks.MAX_SAMPLES, integer=True,
                  unit="fields")
    if lens.telecentric_object:
        return jnp.linspace(0.0, largest_height(lens), count)
    f = jnp.asarray(lens.fields)
    t = jnp.tan(jnp.deg2rad(f))
    tmax = jnp.max(jnp.abs(t)) if f.ndim <= 1 else jnp.max(jnp.sqrt(jnp.sum(t * t, -1)))
    return jnp.linspace(0.0, jnp.rad2deg(jnp.arctan(tmax)), count)


def field_curvature(lens: Lens, fields=None, wavelengths=None, *, depth=None,
                    aim: str | None = None) -> FieldCurvature:
    """Tangential and sagittal focus positions over the field (see the module notes).

    Args:
        lens: the lens.
        fields: θy angles in degrees, ``[F]``, or (θx, θy) pairs, ``[F, 2]`` (tangential
            plane along each field's azimuth); default ``default_fields(lens)`` (θy from 0 to
            the largest field in 11 steps). For an object-space telecentric lens object
            heights in mm, y ``[F]`` or (x, y) ``[F, 2]`` (tangential plane along (x, y)),
            their chief rays parallel to the axis; default 0 to its largest height.
        wavelengths: µm, one value or ``[W]``; default the lens's wavelengths.
        depth: object distance (mm) for a finite object; default the lens's object.
        aim: ``"paraxial"``, ``"real"`` or ``"real_marginal"`` (chief ray through the
            paraxial entrance pupil's centre or the real stop's); None (the default): the
            lens's own, ``lens.aim``.

    Returns:
        A ``FieldCurvature`` (mm from the image surface, along z; ``astigmatism`` is their
        difference).
    """
    checks.focal_image(lens, "field_curvature")
    if not isinstance(lens, Lens):
        raise TypeError(f"field_curvature: lens must be a jaxlens.Lens, got "
                        f"{type(lens).__name__}")
    if fields is None:
        fields = default_fields(lens)
    elif lens.telecentric_object:  # object heights (mm): finite, checked before the trace
        lens_fields(lens, fields, "field_curvature")
    f, wl = _inputs(lens, "field_curvature", fields, wavelengths, pairs=True)
    return _field_curvature(lens, f, wl, depth=lens_depth(lens, depth, "field_curvature"),
                            aim=lens_aim(lens, aim, "field_curvature"))


def _cross(a, b, e):
    """(a × b) in the plane of the unit vector e = (e_x, e_y) and z."""
    along = lambda v: v[..., 0] * e[0] + v[..., 1] * e[1]  # noqa: E731
    return along(a) * b[..., 2] - a[..., 2] * along(b)


def _azimuth(field):
    """Unit (x, y) direction of a field's tangential plane: (0, 1) for a θy field and on
    axis, else (tan θx, tan θy) normalised."""
    if field.ndim == 0:
        return jnp.array([0.0, 1.0], field.dtype)
    t = jnp.tan(jnp.deg2rad(field))
    r = jnp.sqrt(t[0] * t[0] + t[1] * t[1])
    on_axis = r == 0
    return jnp.where(on_axis, jnp.array([0.0, 1.0], t.dtype), t / jnp.where(on_axis, 1.0, r))


@checks.checked_core(forward_mode_jit)
def _field_curvature(lens, fields, wl, *, depth, aim) -> FieldCurvature:
    # Two copies of the chief ray; the first is differentiated along the field's azimuth a
    # (tangential), the second along a⊥ (sagittal): along Py and Px for a θy field.
    centre = jnp.zeros((2, 2), wl.dtype)

    def one(field, w):
        a = azimuth(field) if lens.telecentric_object else _azimuth(field)
        planes = (a, jnp.stack([a[1], -a[0]]))

        def image_ray(pupil):
            out = _image_rays(lens, field, w, pupil, depth, aim)
            return out.origin, out.direction, out.valid

        (p, d, v), (dp, dd, _) = jax.jvp(image_ray, (centre,), (jnp.stack(planes),))
        foci = []
        for row, e in enumerate(planes):
            num = -_cross(dp[row], d[row], e)
            den = _cross(dd[row], d[row], e)
            s = jnp.where(den != 0, num / jnp.where(den != 0, den, 1.0), jnp.inf * jnp.sign(num))
            foci.append(jnp.where(v[row], s * d[row, 2], jnp.nan))
        return foci[0], foci[1]

    tan, sag = jax.vmap(lambda w: jax.vmap(lambda f: one(f, w))(fields))(wl)
    return FieldCurvature(fields, wl, tan, sag)

