"""Real-ray analysis: chief rays, spot diagrams, RMS spot size, distortion, geometry checks.

Conventions:
    Lengths in mm (RMS spot radii too), field angles in degrees, wavelengths in µm.
    Unless a pupil is given, spots use the 21×21 square grid over the unit pupil kept
    inside the disc (317 rays), with rays aimed as the lens says (``Lens.aim``: at the
    paraxial entrance pupil by default, at the real stop for ``"real"`` and
    ``"real_marginal"``; an ``aim``
    argument overrides it). The chief ray is the pupil-centre ray of the same aiming. RMS
    radius = sqrt(mean(|p − ref|²)) over the valid rays on the image surface, with ref
    the centroid of the same ray set or the primary-wavelength chief ray (pupil centre).
    Polychromatic values pool the rays of all wavelengths with equal weights.
    Distortion is given in percent against n·EFL·tanθ (n the object-space index: the front
    focal length, EFL itself in air) and against the paraxial chief ray height on the image
    surface; for an object-space telecentric lens (fields: object heights h in mm) against
    m·h, m the paraxial magnification.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from ..imaging.light import warn_dark
from ..imaging.sampling import field_rays, lens_aim, lens_depth, pupil_grid, unit_disc_limit
from ..imaging.telecentric import lens_fields, radial_heights
from ..optics import checks, paraxial, travel
from ..optics.lens import Lens
from ..optics.rays import Rays
from ..tracing.forward import DEFAULT_NEWTON_ITERS, aimed_jit, trace, trace_path

# The default pupil sampling of spot analyses: a 21 × 21 grid clipped to the disc (317 rays).
PUPIL_GRID = 21


def fields_array(fields, where: str) -> Array:
    """Fields as ``[F]`` (θy) or ``[F, 2]`` (θx, θy) degrees; refuses other shapes and F = 0."""
    f = jnp.asarray(fields)
    if f.ndim > 2 or (f.ndim == 2 and f.shape[-1] != 2) or f.size == 0:
        raise ValueError(f"{where}: fields must be [F] θy or [F, 2] (θx, θy) degrees with "
                         f"F >= 1, got shape {f.shape}")
    return f.reshape(-1) if f.ndim <= 1 else f


def check_inputs(lens: Lens, where: str, *, fields=None, wavelengths=None,
                 arg_f: str = "fields", arg_w: str = "wavelengths", pupil=None,
                 own: str = "primary"):
    """Check the field angles (deg), wavelengths (µm) and pupil points the caller gave,
    before the jitted body: inside it a constant array is a tracer, and the same checks
    became an ``EquinoxRuntimeError`` raised after the whole trace had run (a NaN pupil
    point was not refused at all: its ray counted as vignetted). Without ``wavelengths``
    the lens's own are checked: its primary one, or with ``own="all"`` all of them.
    Returns ``pupil`` (traced: with the unit-disc check attached; use it)."""
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    if fields is not None and not checks.is_traced(fields) and lens.telecentric_object:
        checks.values(fields, f"{arg_f} (object heights of an object-space telecentric "
                      f"lens)", where, unit="mm")
    elif fields is not None and not checks.is_traced(fields):
        checks.field_angles(fields, where, arg_f)
        checks.warn_if_radian_fields(fields, where, arg_f)  # as Lens does
    if wavelengths is None and not checks.is_traced(lens.wavelengths):
        wavelengths = lens.wavelengths if own == "all" else lens.primary_wavelength
        arg_w = f"the lens's {'wavelengths' if own == 'all' else 'primary wavelength'}"
    if wavelengths is not None and not checks.is_traced(wavelengths):
        checks.wavelengths(lens, wavelengths, where, arg_w)
        checks.material_indices(lens, wavelengths, where, arg_w)
    if pupil is not None and not checks.is_traced(pupil):
        checks.real_values(pupil, "pupil", where, "normalised pupil coordinates")
        checks.finite_array(pupil, "pupil", where, "normalised pupil coordinates")
    return None if pupil is None else unit_pupil(pupil, where)


def unit_pupil(pupil, where: str):
    """``pupil`` (normalised points ``[..., 2]``), refused outside the unit disc: the pupil of
    a spot is the beam itself, and a point at radius 1.5 traced a ray 0.75 EPD off axis
    into the spot (a larger spot, or a vignetted ray counted in ``valid_fraction``). The
    slack is a few ulps of the points' dtype (``pupil_hexapolar``'s float32 rim points lie
    at radius 1 + 2.3e-8). A traced pupil is returned with an ``eqx.error_if``."""
    p = jnp.asarray(pupil)
    limit = unit_disc_limit(p.dtype)
    msg = (f"{where}: pupil points must lie in the unit disc (Px² + Py² <= 1, normalised "
           f"to the entrance pupil)")
    if p.ndim < 1 or p.shape[-1] != 2:
        return pupil  # the shape is the ray sources' to refuse, as before
    if checks.is_traced(pupil):
        return eqx.error_if(pupil, jnp.any(jnp.sum(p * p, -1) > limit * limit), msg)
    r = np.sqrt(np.sum(np.asarray(pupil, float) ** 2, -1))
    if r.size and float(r.max()) > limit:
        raise ValueError(f"{msg}, got radius {float(r.max()):.6g}")
    return pupil


def _as_arrays(lens: Lens, *values):
    """Python numbers and lists of them as arrays of the lens's dtype (None and arrays as
    they are). ``filter_jit`` keeps a Python number static: a spot diagram that passed
    ``float(w)`` compiled one program per wavelength; as arrays, one program serves all."""
    return tuple(v if v is None or isinstance(v, (jax.Array, np.ndarray)) or checks.is_traced(v)
                 else jnp.asarray(v, lens.epd.dtype) for v in values)


def _own_fields(lens: Lens, fields):
    """``lens.fields`` where ``fields`` is None, so that a call with the lens's fields and
    one that passes them share one compiled program (None and an array would not)."""
    return lens.fields if fields is None else fields


def spot_rays(
    lens: Lens,
    field,
    wavelength=None,
    *,
    pupil=None,
    depth=None,
    aim: str | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Rays:
    """Rays of one field and wavelength on the image surface (a spot diagram as data).
    ``aim``: "paraxial", "real", "real_marginal" or None (the lens's own ray aiming,
    ``lens.aim``)."""
    pupil = check_inputs(lens, "spot_rays", fields=field, wavelengths=wavelength,
                         arg_f="field", arg_w="wavelength", pupil=pupil)
    checks.newton_iters(newton_iters, "spot_rays")
    field, wavelength = _as_arrays(lens, field, wavelength)
    return _spot_rays(lens, field, wavelength, pupil=pupil,
                      depth=lens_depth(lens, depth, "spot_rays"),
                      aim=lens_aim(lens, aim, "spot_rays"),
                      newton_iters=newton_iters)


@checks.checked_core(aimed_jit)
def _spot_rays(lens, field, wavelength, *, pupil, depth, aim, newton_iters) -> Rays:
    pupil = pupil_grid(PUPIL_GRID, lens.epd.dtype) if pupil is None else pupil
    rays = field_rays(lens, field, pupil, wavelength, depth=depth, aim=aim)
    return trace(lens, rays, newton_iters=newton_iters)


def chief_ray(lens: Lens, field, wavelength=None, *, depth=None, aim=None) -> Rays:
    """The chief ray on the image surface: through the paraxial entrance-pupil centre
    (``aim="paraxial"``) or the real stop's centre (``"real"``); None (the default): the
    lens's own ray aiming, ``lens.aim``."""
    check_inputs(lens, "chief_ray", fields=field, wavelengths=wavelength, arg_f="field",
                     arg_w="wavelength")
    field, wavelength = _as_arrays(lens, field, wavelength)
    centre = jnp.zeros((1, 2), lens.epd.dtype)
    return _spot_rays(lens, field, wavelength, pupil=centre,
                      depth=lens_depth(lens, depth, "chief_ray"),
                      aim=lens_aim(lens, aim, "chief_ray"),
                      newton_iters=DEFAULT_NEWTON_ITERS)[0]


class RmsSpot(eqx.Module):
    """RMS spot radii (mm) for F fields and W wavelengths; ``centroid`` and ``chief`` (the
    primary-wavelength chief ray's intercept) are image-plane (x, y) in mm, NaN where no
    ray (or no chief ray) reaches the image."""

    per_wavelength: Float[Array, "F W"]
    polychromatic: Float[Array, " F"]
    valid_fraction: Float[Array, "F W"]
    centroid: Float[Array, "F W 2"]
    chief: Float[Array, "F 2"]


def weighted_rms(p, w, ref=None):
    """RMS distance of points ``p [..., M, 2]`` (weights ``w [..., M]``) from ``ref [..., 2]``.

    ``ref`` defaults to the weighted centroid. NaN where no ray is valid (never 0, which
    looks perfect); the one RMS definition of the library (spots, report, tolerancing).

    Both square roots and the NaN are "double where"s, so the gradient is finite
    everywhere: 0 for a field without rays and for a perfect point.
    """
    ref = weighted_centroid(p, w) if ref is None else ref
    d2 = jnp.sum((p - ref[..., None, :]) ** 2, axis=-1)
    total = jnp.sum(w, axis=-1)
    ms = jnp.sum(w * d2, axis=-1) / jnp.maximum(total, 1.0)
    pos = ms > 0
    rms = jnp.where(pos, jnp.sqrt(jnp.where(pos, ms, 1.0)), 0.0)
    return jnp.where(total > 0, rms, jnp.nan)


def weighted_centroid(p, w):
    """Weighted centroid, 0 (finite, so gradients stay finite) where no ray is valid."""
    return jnp.sum(w[..., None] * p, axis=-2) / jnp.maximum(jnp.sum(w, axis=-1), 1.0)[..., None]


def rms_spot(
    lens: Lens,
    fields=None,
    wavelengths=None,
    *,
    pupil=None,
    reference: str = "centroid",
    depth=None,
    aim: str | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> RmsSpot:
    """RMS spot radius per field and wavelength, and polychromatic (mm).

    Args:
        lens: the lens.
        fields: field angles in degrees, ``[F]`` (y) or ``[F, 2]``; default ``lens.fields``.
        wavelengths: µm, ``[W]``; default ``lens.wavelengths``.
        pupil: ``[M, 2]`` unit-pupil points; default the 21×21 grid (317 rays).
        reference: "centroid" or "chief" (primary-wavelength chief ray).
        depth: object distance in mm (``inf`` for infinity), or None for the lens's own
            object (``lens.object_distance``; infinity where it has none).
        aim: "paraxial" (rays through the paraxial entrance pupil), "real" or
            "real_marginal" (aimed at the real stop, sized by the paraxial or the real
            marginal ray; the chief ray through its centre); None (the default): the lens's
            own ray aiming, ``lens.aim``.

    Returns:
        An ``RmsSpot``. Only valid rays count; ``valid_fraction`` says how many those were.
        A field and wavelength that no ray gets through has NaN radius (and centroid),
        with ``valid_fraction`` 0; its gradient is 0, never NaN.
        A field no ray of any wavelength gets through is a ``NoLightWarning`` naming it
        (concrete inputs; see ``jaxlens.imaging.light``): this is the many-field (batch)
        API, so the other fields' radii stay; the one-field analyses raise instead.
    """
    checks.focal_image(lens, "rms_spot")
    checks.newton_iters(newton_iters, "rms_spot")
    pupil = check_inputs(lens, "rms_spot", fields=fields, wavelengths=wavelengths,
                         pupil=pupil, own="all")
    checks.primary_wavelength(lens, "rms_spot", "the chief ray's")
    fields, wavelengths = _as_arrays(lens, _own_fields(lens, fields), wavelengths)
    r = _rms_spot(lens, fields, wavelengths, pupil=pupil, reference=reference,
                  depth=lens_depth(lens, depth, "rms_spot"),
                  aim=lens_aim(lens, aim, "rms_spot"), newton_iters=newton_iters)
    warn_dark(r.valid_fraction, fields, "rms_spot", lens)
    return r


@checks.checked_core(aimed_jit)
def _rms_spot(lens, fields, wavelengths, *, pupil, reference, depth, aim,
              newton_iters) -> RmsSpot:
    if reference not in ("centroid", "chief"):
        raise ValueError(f"rms_spot: reference must be 'centroid' or 'chief', got {reference!r}")
    fields = fields_array(fields, "rms_spot")
    # With the lens's own wavelengths the chief ray is one more pupil point (the centre)
    # of the primary-wavelength trace, so one trace serves both.
    own_wavelengths = wavelengths is None
    wls = lens.wavelengths if own_wavelengths else jnp.atleast_1d(jnp.asarray(wavelengths))
    if wls.ndim != 1 or wls.size == 0:
        raise ValueError(f"rms_spot: wavelengths must be [W] µm with W >= 1, got shape "
                         f"{wls.shape}")
    pupil = pupil_grid(PUPIL_GRID, lens.epd.dtype) if pupil is None else jnp.asarray(pupil)
    if pupil.ndim != 2 or pupil.shape[1] != 2 or pupil.shape[0] == 0:  # before the concatenate
        raise ValueError(f"rms_spot: pupil must be [M, 2] normalised pupil points (Px, Py) "
                         f"with M >= 1, got shape {pupil.shape}")
    m = pupil.shape[0]
    pupil_ext = jnp.concatenate([pupil, jnp.zeros((1, 2), pupil.dtype)])
    primary = lens.primary_wavelength

    def per_field(field):
        def per_wl(wl):
            r = _spot_rays(lens, field, wl, pupil=pupil_ext, depth=depth, aim=aim,
                           newton_iters=newton_iters)
            return r.origin[..., :2], r.valid.astype(r.origin.dtype)

        p_ext, w_ext = jax.vmap(per_wl)(wls)  # [W, M+1, 2], [W, M+1]
        p, w = p_ext[:, :m], w_ext[:, :m]
        if own_wavelengths:
            chief, chief_valid = p_ext[lens.primary, m], w_ext[lens.primary, m]
        else:
            cr = _spot_rays(lens, field, primary, pupil=jnp.zeros((1, 2), pupil.dtype),
                            depth=depth, aim=aim, newton_iters=newton_iters)
            chief, chief_valid = cr.origin[0, :2], cr.valid[0].astype(cr.origin.dtype)
        cen = weighted_centroid(p, w)  # [W, 2]
        ref = cen if reference == "centroid" else jnp.broadcast_to(chief, cen.shape)
        per = weighted_rms(p, w, ref)
        pall, wall = p.reshape(-1, 2), w.reshape(-1)
        poly = weighted_rms(pall, wall, None if reference == "centroid" else chief)
        if reference == "chief":  # no chief ray, no radius about it (never a silent value)
            chief_ok = chief_valid > 0
            per, poly = jnp.where(chief_ok, per, jnp.nan), jnp.where(chief_ok, poly, jnp.nan)
        cen_out = jnp.where(jnp.sum(w, axis=-1)[:, None] > 0, cen, jnp.nan)
        # An invalid chief ray stops where it failed: its last position is not an intercept.
        chief_out = jnp.where(chief_valid > 0, chief, jnp.nan)
        return per, poly, jnp.mean(w, axis=-1), cen_out, chief_out

    per, poly, frac, cen, chief = jax.vmap(per_field)(fields)
    return RmsSpot(per, poly, frac, cen, chief)


class Distortion(eqx.Module):
    """Real chief-ray distortion per field (heights in mm, distortion in %).

    For ``[F, 2]`` fields (θx, θy) the heights are radial: components along the field's
    direction (tanθx, tanθy) in the image plane, and ``f_tan`` is n·EFL·tanθ of the field's
    radial angle θ (tan²θ = tan²θx + tan²θy), n the object-space index (1 in air): the image
    height of a distortion-free lens, whose front focal length is n·EFL.

    Which is Zemax's: OpticStudio's "F-Tan(Theta)" distortion (Field Curvature and
    Distortion) takes its reference height from a real ray traced at a very small field,
    scaled to the field; on the image surface that is the paraxial chief ray's height, so
    it is ``percent_paraxial`` here (optiland 0.6.3's ``Distortion(distortion_type="f-tan")``
    computes it so, its scale taken from a real ray at 1e-10 of the field, and equals
    ``percent_paraxial`` to 3e-10 %; ``tests/test_conventions_vs_optiland.py``). Its
    "F-Theta" distortion is ``percent_ftheta``: reference s·θ, θ in radians, s =
    ``paraxial_height``/tanθ the same near-axis scale (optiland's
    ``distortion_type="f-theta"``, equal to 3e-10 %; that OpticStudio takes the same scale
    for F-Theta was not checked against its output). ``percent_ftan`` measures against
    n·EFL·tanθ instead, the ideal height at the paraxial focus: it equals
    ``percent_paraxial`` only when the image surface lies at the paraxial focus, and in
    general 1 + ``percent_ftan``/100 = (1 + ``percent_paraxial``/100) ·
    ``paraxial_height``/``f_tan`` (the Cooke triplet of the reference cases, its image
    surface 0.23 mm before the paraxial focus: −0.386 % against +0.062 % at 20°).
    An afocal lens (EFL infinite) has ``f_tan`` 0 on the axis and ±inf off it, and
    ``percent_ftan`` −100 there (the limit; ``distortion_percent``): measure it against
    ``percent_paraxial``.

    An object-space telecentric lens (``Lens.object_na``): ``field`` holds object heights
    (mm, y or (x, y); the heights radial as above, along (x, y)), the chief ray leaves
    each object point parallel to the axis, and ``f_tan`` holds the distortion-free height
    m·h, m the paraxial magnification (``paraxial.magnification``: where the paraxial chief
    ray meets the paraxial image plane), so ``percent_ftan`` = 100·(y_real − m·h)/(m·h);
    ``paraxial_height`` is that chief ray's height on the image surface, as above.
    ``f_theta`` and ``percent_ftheta`` are NaN: there is no field angle.
    """

    field: Float[Array, " F"] | Float[Array, "F 2"]
    chief_height: Float[Array, " F"]
    f_tan: Float[Array, " F"]
    paraxial_height: Float[Array, " F"]
    percent_ftan: Float[Array, " F"]
    percent_paraxial: Float[Array, " F"]
    f_theta: Float[Array, " F"]
    percent_ftheta: Float[Array, " F"]


def field_heights(fields, xy):
    """Image heights of points ``xy`` [F, 2] (mm) along their fields' directions.

    Returns ``(tan θ, θ, height)`` per field: for ``[F]`` fields (θy) the signed tangent,
    the angle and the y coordinate; for ``[F, 2]`` fields (θx, θy) the radial angle θ
    (tan²θ = tan²θx + tan²θy), its tangent and the component of ``xy`` along the field's
    direction (tanθx, tanθy) (+y for the on-axis field), so the ideal image point of a
    distortion-free lens of focal length f is at height f·tanθ.
    """
    if fields.ndim == 1:
        return jnp.tan(jnp.deg2rad(fields)), fields, xy[:, 1]
    t = jnp.tan(jnp.deg2rad(fields))
    s = jnp.sum(t * t, axis=-1)
    tr = jnp.where(s > 0, jnp.sqrt(jnp.where(s > 0, s, 1.0)), 0.0)  # grad-safe at 0
    nz = (tr > 0)[:, None]
    u = jnp.where(nz, t / jnp.where(nz, tr[:, None], 1.0), jnp.array([0.0, 1.0], t.dtype))
    return tr, jnp.rad2deg(jnp.arctan(tr)), jnp.sum(xy * u, axis=-1)


def distortion(lens: Lens, fields=None, wavelength=None, *, aim=None) -> Distortion:
    """Distortion of the real chief ray at ``wavelength`` (default primary), traced from the
    lens's own object (``lens.object_distance``; at a finite distance a field angle is the
    chief ray's angle at the entrance pupil, as in ``sampling.object_point``).

    ``fields`` are degrees, ``[F]`` (θy) or ``[F, 2]`` (θx, θy); default ``lens.fields``
    (object heights in mm, y or (x, y), for an object-space telecentric lens, whose
    distortion is measured against m·h: see :class:`Distortion`).
    ``percent_ftan`` = 100·(y_real − n·EFL·tanθ)/(n·EFL·tanθ), n the object-space index (1
    in air; an ideal lens behind water had 33 % against EFL·tanθ); ``percent_paraxial`` uses the
    paraxial chief-ray height on the image surface instead (Zemax's "F-Tan(Theta)"
    distortion), ``percent_ftheta`` the paraxial scale times θ (Zemax's "F-Theta"); see
    :class:`Distortion` for the relation between them. Heights are along y for
    ``[F]`` fields and radial for ``[F, 2]`` (see :class:`Distortion`). Zero fields give 0.
    A field whose real chief ray does not reach the image (vignetted, or beyond the lens's
    coverage) has NaN height and distortion (its height was 0: a plausible −100 %).
    The chief ray passes the paraxial entrance pupil's centre (``aim="paraxial"``) or the
    real stop's (``"real"``); None (the default): the lens's own ray aiming, ``lens.aim``.
    """
    checks.focal_image(lens, "distortion")
    check_inputs(lens, "distortion", fields=fields, wavelengths=wavelength,
                     arg_w="wavelength")
    fields, wavelength = _as_arrays(lens, _own_fields(lens, fields), wavelength)
    return _distortion(lens, fields, wavelength, lens_depth(lens, None, "distortion"),
                       aim=lens_aim(lens, aim, "distortion"))


@checks.checked_core(aimed_jit)
def _distortion(lens, fields, wavelength, depth, *, aim) -> Distortion:
    fields = fields_array(fields, "distortion")
    wl = lens.primary_wavelength if wavelength is None else wavelength
    if jnp.ndim(wl) != 0:
        raise ValueError(f"distortion: wavelength must be one value (µm), got shape "
                         f"{jnp.shape(wl)}")
    chief = jax.vmap(lambda th: _spot_rays(
        lens, th, wl, pupil=jnp.zeros((1, 2), lens.epd.dtype), depth=depth, aim=aim,
        newton_iters=DEFAULT_NEWTON_ITERS)[0])(fields)
    p = jnp.where(chief.valid[:, None], chief.origin[:, :2], jnp.nan)

    pct = distortion_percent
    if lens.telecentric_object:  # object heights h (mm): the ideal image is m·h
        h, y = radial_heights(fields, p)
        ideal = paraxial.magnification(lens, wl) * h
        ypar = jax.vmap(lambda r: paraxial.image_height(lens, r, wl))(h)
        nan = jnp.full_like(h, jnp.nan)  # no field angle: no f-θ reference
        return Distortion(fields, y, ideal, ypar, pct(y, ideal), pct(y, ypar), nan, nan)
    # The front focal length n·EFL: a field angle is measured in object space.
    f = lens.object_material.index(wl) * paraxial.efl(lens, wl)
    tr, radial, y = field_heights(fields, p)
    ftan = reference_heights(f, tr)
    ypar = jax.vmap(lambda th: paraxial.image_height(lens, th, wl))(radial)

    # Zemax's F-Theta reference: the near-axis (paraxial) scale per tanθ, times θ (rad).
    nz = tr != 0
    scale = ypar / jnp.where(nz, tr, 1.0)
    ftheta = jnp.where(nz, scale * jnp.deg2rad(radial), 0.0)
    return Distortion(fields, y, ftan, ypar, pct(y, ftan), pct(y, ypar), ftheta,
                      pct(y, ftheta))


def reference_heights(f, tan):
    """The distortion-free heights f·tanθ (mm) of a focal length ``f`` (mm; the front focal
    length n·EFL) and field tangents ``tan``: 0 on the axis whatever f (an afocal lens's
    infinite f gave inf·0 = NaN there), ±inf off it for an infinite f."""
    return jnp.where(tan == 0, 0.0 * tan, f * tan)


def distortion_percent(a, b, xp=jnp):
    """100·(a − b)/b: the distortion (%) of heights ``a`` against reference heights ``b``;
    0 where b = 0 (the axis), and −100, the limit, where b is infinite and a finite (an
    afocal lens's f·tanθ: inf/inf was NaN). ``xp``: ``jax.numpy``, or ``numpy`` for host
    arrays (the report's table, made on the host)."""
    nz = b != 0
    inf = xp.isinf(b) & xp.isfinite(a)
    safe = xp.where(nz & ~inf, b, 1.0)
    return xp.where(inf, -100.0, xp.where(nz, 100.0 * (a - b) / safe, 0.0))


def clear_semi_diameters(lens: Lens, fields=None, n_rim: int = 64, *,
                         reaching: bool = False, pupil=None) -> Float[Array, " n"]:
    """Clear semi-diameter of every surface (mm).

    A finite ``semi_diameter`` is used as is; otherwise the largest radial height of the
    rim and chief rays over the lens's fields and wavelengths (the lens's ray aiming,
    ``Lens.aim``) among the
    rays that pass the whole lens, or, with ``reaching=True``, among the rays that reach
    that surface (the beam footprint: a ray lost further on, say where two surfaces cross,
    still lights every surface before). ``pupil`` (``[M, 2]`` unit-pupil points) adds
    interior rays: where rim rays fail, a ray inside the pupil can pass higher than any
    rim ray that passes, and an aperture sized from the rim alone would clip it.
    """
    pupil = check_inputs(lens, "clear_semi_diameters", fields=fields, pupil=pupil, own="all")
    if pupil is not None and (jnp.ndim(pupil) != 2 or jnp.shape(pupil)[-1] != 2):
        raise ValueError(f"clear_semi_diameters: pupil must be [M, 2] normalised pupil points "
                         f"(Px, Py), got shape {jnp.shape(pupil)}")
    if not isinstance(reaching, (bool, np.bool_)):
        raise TypeError(f"clear_semi_diameters: reaching must be True or False, got {reaching!r}")
    # ``reaching`` is an array, so that both kinds of height share one compiled program.
    (fields,) = _as_arrays(lens, _own_fields(lens, fields))
    return _clear_semi_diameters(lens, fields, n_rim, reaching=jnp.asarray(reaching),
                                 pupil=pupil)


@checks.checked_core(aimed_jit)
def _clear_semi_diameters(lens, fields, n_rim, *, reaching, pupil) -> Float[Array, " n"]:
    checks.number(n_rim, "n_rim", "clear_semi_diameters", lo=4, hi=checks.MAX_SAMPLES, integer=True,
                  unit="rim rays per beam (fewer miss the rim in x or y)")
    fields = fields_array(fields, "clear_semi_diameters")
    rim = rim_pupil(n_rim, lens.epd.dtype)
    pupil = rim if pupil is None else jnp.concatenate([rim, jnp.asarray(pupil, rim.dtype)])
    depth = None if lens.object_at_infinity else lens.object_distance

    def heights(field, wl):
        rays = field_rays(lens, field, pupil, wl, depth=depth)
        path = trace_path(lens, rays, upto=lens.num_surfaces - 1)
        return _ray_heights(path.origin, jnp.where(reaching, path.valid, path[-1].valid[None]))

    h = jax.vmap(lambda f: jax.vmap(lambda w: heights(f, w))(lens.wavelengths))(fields)
    return _given_or_traced(lens, jnp.max(h, axis=(0, 1)))


def _ray_heights(origin, valid):
    """The largest radial height of the ``valid`` rays (last axis), 0 where none is."""
    r = jnp.hypot(origin[..., 0], origin[..., 1])
    return jnp.max(jnp.where(valid, r, 0.0), axis=-1)


def _given_or_traced(lens, traced):
    """Each surface's finite ``semi_diameter`` as given, else the traced height."""
    given = jnp.stack([s.semi_diameter for s in lens.surfaces])
    return jnp.where(jnp.isfinite(given), given, traced)


def rim_pupil(n_rim: int, dtype) -> Float[Array, "m 2"]:
    """``clear_semi_diameters``' pupil: the centre and ``n_rim`` points on the unit circle."""
    a = np.linspace(0, 2 * np.pi, n_rim, endpoint=False)
    return jnp.asarray(np.concatenate([[[0.0, 0.0]], np.stack([np.cos(a), np.sin(a)], -1)]),
                       dtype)


def semi_diameters_and_fans(lens: Lens, fan_fields, fan_pupil, n_rim: int = 64):
    """``clear_semi_diameters(lens)`` and the rays of ``fan_fields`` (as the lens's fields:
    ``[F]`` θy or ``[F, 2]`` (θx, θy), deg) through ``fan_pupil`` (``[M, 2]``) at the
    primary wavelength, from one compiled program: the rim rays of every field and
    wavelength and the fans are aimed in one batch. With ray aiming each program of aimed
    rays takes seconds to compile (rayoptics_US00583336: 8 s for the semi-diameters, 5 s
    for the layout's fans); each ray is aimed and traced alone (vmap), so the numbers are
    those of the two separate calls.

    Returns:
        (semi-diameters ``[n]`` mm, launch points ``[F, M, 3]``, launch directions ``[F, M,
        3]``, the fans' ``trace_path`` ``[F, n + 1, M]``).
    """
    check_inputs(lens, "semi_diameters_and_fans", own="all")
    # The fans as the lens's fields are (their core trusts what its caller checked); their
    # pupil may be overfilled, so it is not held to the unit disc.
    if not checks.is_traced((fan_fields, fan_pupil)):
        lens_fields(lens, fan_fields, "semi_diameters_and_fans", "fan_fields")  # mm or deg
        checks.finite_array(fan_pupil, "fan_pupil", "semi_diameters_and_fans",
                            "normalised pupil coordinates")
    checks.number(n_rim, "n_rim", "semi_diameters_and_fans", lo=4, hi=checks.MAX_SAMPLES,
                  integer=True, unit="rim rays per beam (fewer miss the rim in x or y)")
    (fields,) = _as_arrays(lens, _own_fields(lens, None))
    fan_fields = jnp.asarray(fan_fields, lens.epd.dtype)
    if fan_fields.ndim != jnp.ndim(fields):
        raise ValueError(f"semi_diameters_and_fans: fan_fields must have the shape of the "
                         f"lens's fields ([F] or [F, 2]), got {fan_fields.shape} against "
                         f"{jnp.shape(fields)}")
    starts, dirs, path, traced = _semi_diameters_and_fans(
        lens, fields, fan_fields, jnp.asarray(fan_pupil, lens.epd.dtype), n_rim)
    return traced, starts, dirs, path


@checks.checked_core(aimed_jit)
def _semi_diameters_and_fans(lens, fields, fan_fields, fan_pupil, n_rim):
    n, dt = lens.num_surfaces, lens.epd.dtype
    rim = rim_pupil(n_rim, dt)
    m = max(rim.shape[0], fan_pupil.shape[0])

    def padded(p):  # the centre ray fills up: it changes no height and no fan ray
        return jnp.concatenate([p, jnp.zeros((m - p.shape[0], 2), dt)])

    W, F, Ff = lens.wavelengths.shape[0], fields.shape[0], fan_fields.shape[0]
    # One (field, wavelength, pupil) per beam: every field at every wavelength (rim), then
    # the fans (primary wavelength).
    beam_f = jnp.concatenate([jnp.repeat(fields, W, axis=0), fan_fields])
    beam_w = jnp.concatenate([jnp.tile(lens.wavelengths, F),
                              jnp.full((Ff,), lens.primary_wavelength)])
    beam_p = jnp.concatenate([jnp.broadcast_to(padded(rim), (F * W, m, 2)),
                              jnp.broadcast_to(padded(fan_pupil), (Ff, m, 2))])
    depth = lens_depth(lens, None, "plot_layout")

    def beam(f, w, p):
        rays = field_rays(lens, f, p, w, depth=depth)
        return rays.origin, rays.direction, trace_path(lens, rays)

    starts, dirs, path = jax.vmap(beam)(beam_f, beam_w, beam_p)
    # As clear_semi_diameters: the rays that pass the last surface (reaching=False).
    h = _ray_heights(path.origin[:F * W, :n], path.valid[:F * W, n - 1][:, None])  # [FW, n]
    traced = _given_or_traced(lens, jnp.max(h, axis=0))
    k = fan_pupil.shape[0]
    fans = jax.tree.map(lambda a: a[F * W:, :, :k] if a.ndim >= 3 else a, path)
    return starts[F * W:, :k], dirs[F * W:, :k], fans, traced


class GeometryCheck(eqx.Module):
    """Self-intersection and edge-thickness check over the whole clear aperture."""

    min_gap: Float[Array, " n"]  # min axial gap from surface i to i+1 (last: to image), mm
    edge_gap: Float[Array, " n"]  # the gap at the rim of the clear aperture, mm
    sag_defined: Bool[Array, " n"]  # the sag exists over the clear aperture
    ok: Bool[Array, ""]

    def summary(self) -> str:
        bad = np.flatnonzero(~np.asarray(self.sag_defined) | (np.asarray(self.min_gap) <= 0))
        if bad.size == 0:
            return f"no self-intersection (min gap {float(np.min(self.min_gap)):.4f} mm)"
        return "self-intersection or undefined sag after surfaces " + ", ".join(
            str(i + 1) for i in bad
        )


def self_intersection(
    lens: Lens,
    semi_diameters=None,
    *,
    min_gap: float = 0.0,
    n_radial: int = 64,
    n_angle: int = 24,
) -> GeometryCheck:
    """Check every pair of neighbouring surfaces for overlap over the whole clear aperture.

    The axial gap z_{i+1} + sag_{i+1}(x, y) − z_i − sag_i(x, y) (negated where light
    travels toward −z, after a mirror: ``Lens.travel_senses``) is sampled on a polar grid
    out to the larger of the two clear semi-diameters (the element's outer edge), so
    aspheres that cross away from the centre are caught. The default semi-diameters are the
    beam footprints (``clear_semi_diameters(..., reaching=True)``): rays lost where two
    surfaces cross still count on the surfaces they reached, so the crossing lies inside the
    checked aperture. The last surface is checked against the image surface. ``ok`` is True
    when every gap exceeds ``min_gap`` and every sag is defined. The check is independent of
    any design regularizer.
    """
    where = "self_intersection"
    checks.number(n_radial, "n_radial", where, lo=2, hi=checks.MAX_SAMPLES, integer=True,
                  unit="radii")
    checks.number(n_angle, "n_angle", where, lo=1, hi=checks.MAX_SAMPLES, integer=True,
                  unit="azimuths")
    if not checks.is_traced(min_gap):
        # A negative clearance passed surfaces that cross by up to |min_gap| (ok True).
        checks.number(min_gap, "min_gap", where, lo=0, unit="mm (the smallest clearance "
                      "allowed between neighbouring surfaces)")
    n = lens.num_surfaces
    if semi_diameters is None:
        check_inputs(lens, where, own="all")  # as the user called it, not clear_semi_diameters
        sd = clear_semi_diameters(lens, reaching=True)
    else:
        if not checks.is_traced(semi_diameters):
            checks.real_values(semi_diameters, "semi_diameters", where, "mm")
            checks.values(semi_diameters, "semi_diameters", where, lo=0, unit="mm")
        sd = jnp.asarray(semi_diameters)
        if sd.shape != (n,):
            raise ValueError(f"{where}: semi_diameters must hold one value per surface, shape "
                             f"({n},) (mm), got shape {sd.shape}")
    min_gap = min_gap if checks.is_traced(min_gap) else jnp.asarray(min_gap)
    return _self_intersection(lens, sd, min_gap, n_radial=n_radial, n_angle=n_angle)


@eqx.filter_jit
def _self_intersection(lens, sd, min_gap, *, n_radial, n_angle) -> GeometryCheck:
    """``self_intersection``'s compiled core (op-by-op it took 30-120 ms a call)."""
    n = lens.num_surfaces
    senses = travel.travel_senses(lens)  # static: a lens without mirrors compiles as before
    surfs = list(lens.surfaces) + [lens.image]
    zs = jnp.concatenate([lens.vertex_z(), lens.image_z()[None]])
    sd_all = jnp.concatenate([sd, sd[-1:]])
    rho = jnp.linspace(0.0, 1.0, n_radial)
    ang = jnp.linspace(0.0, 2 * jnp.pi, n_angle, endpoint=False)
    ux = (rho[:, None] * jnp.cos(ang)[None]).reshape(-1)
    uy = (rho[:, None] * jnp.sin(ang)[None]).reshape(-1)
    gaps, edges, defined = [], [], []
    for i in range(n):
        r = jnp.maximum(sd_all[i], sd_all[i + 1])
        x, y = ux * r, uy * r
        z1, in1 = surfs[i].sag(x, y)
        z2, in2 = surfs[i + 1].sag(x, y)
        g = zs[i + 1] + z2 - zs[i] - z1
        if senses[i + 1] < 0:  # light travels toward -z (after a mirror): the gap is -Δz
            g = -g
        # Each surface must be defined over its own clear aperture.
        own1 = jnp.hypot(x, y) <= sd_all[i] * (1 + 1e-9)
        own2 = jnp.hypot(x, y) <= sd_all[i + 1] * (1 + 1e-9)
        defined.append(jnp.all(in1 | ~own1) & jnp.all(in2 | ~own2))
        gaps.append(jnp.min(g))
        edges.append(jnp.min(g.reshape(n_radial, n_angle)[-1]))
    gaps, edges, defined = jnp.stack(gaps), jnp.stack(edges), jnp.stack(defined)
    ok = jnp.all(defined) & jnp.all(gaps > min_gap)
    return GeometryCheck(gaps, edges, defined, ok)
