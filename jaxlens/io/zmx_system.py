"""System data of a ``.zmx`` file beyond surfaces: the object-space NA and paraxial working
F/# apertures (``OBNA``, ``FNUM x 1``), field types (``FTYP``; paraxial and real image heights
converted to angles), object-space telecentric systems (FTYP's second value 1: object
heights, or image heights converted to them, and ``Lens.object_na``), vignetting factors
(read into ``Lens.vignetting``), ray aiming (``RAIM``) and the environment (``ENVD``). The
format: ``jaxlens.io.zmx``."""

from __future__ import annotations

import math
import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..imaging import aiming, sampling
from ..optics import paraxial, symmetry
from ..optics.lens import Lens, unclipped
from ..optics.materials import Air
from ..tracing import forward
from .zmx_common import ZmxWarning, report


def epd_from_object_na(lens: Lens, value: float, cone_angle: bool) -> float:
    """Entrance pupil diameter (mm) of a finite-conjugate lens from its object-space
    numerical aperture n·sin(u) (``OBNA value 0``) or its object cone half-angle u in degrees
    (``OBNA value 1``).

    The paraxial marginal ray leaves the axial object point at slope tan(u) and reaches the
    paraxial entrance pupil at the pupil's edge, as in Zemax and optiland:
    EPD = 2·(z_EP − z_object)·tan(u).

    Raises:
        ValueError: for an object at infinity, or a value out of range (NA in (0, n),
            cone angle in (0, 90) deg).
    """
    if lens.object_distance is None:
        raise ValueError(
            "an object-space NA or cone angle needs a finite object distance "
            "(the object DISZ is INFINITY); use ENPD or FNUM"
        )
    wl = lens.primary_wavelength
    if cone_angle:
        if not 0.0 < value < 90.0:
            raise ValueError(f"object cone angle must be in (0, 90) deg, got {value:g}")
        u = math.radians(value)
    else:
        n0 = float(lens.object_material.index(wl))
        if not 0.0 < value < n0:
            raise ValueError(
                f"object-space NA must be in (0, n) with n = {n0:.6g} the object "
                f"space index, got {value:g}"
            )
        u = math.asin(value / n0)
    to_pupil = float(paraxial.entrance_pupil_z(lens, wl)) + float(lens.object_distance)
    if not to_pupil > 0:
        raise ValueError(
            f"the entrance pupil lies {-to_pupil:g} mm before the object; an "
            f"object-space NA does not define a pupil there"
        )
    return 2.0 * to_pupil * math.tan(u)


def epd_from_working_fnum(lens: Lens, fnum: float) -> float:
    """Entrance pupil diameter (mm) from the paraxial working F/# (``FNUM value 1``),
    1/(2·n′·u′) with u′ the paraxial marginal ray's slope in image space and n′ its index.
    n′u′ grows in proportion to the EPD, so one paraxial trace at the lens's EPD gives it.

    Raises:
        ValueError: for a value not > 0, or an image-space marginal ray parallel to the axis
            (an afocal lens), where no EPD gives the F/#.
    """
    if not fnum > 0:
        raise ValueError(f"paraxial working F/# must be > 0, got {fnum:g}")
    # The working F/# at the lens's EPD, +inf where the image-space slope is zero within its
    # rounding bound (``paraxial._over``): an exact-zero test let an afocal lens's rounding
    # residue (nu' ~ 1e-17) through, and the EPD came out as 1e14 mm.
    now = float(paraxial.paraxial_data(lens).working_fnum)
    if not (math.isfinite(now) and now > 0):
        raise ValueError("the paraxial marginal ray leaves the lens parallel to the axis (an "
                         "afocal lens, or an image at infinity): no entrance pupil gives a "
                         "working F/#; use ENPD")
    return float(lens.epd) * now / fnum


def angles_from_paraxial_image_heights(lens: Lens, heights: np.ndarray) -> Lens:
    """The lens with ``heights`` (paraxial image heights in mm on the image surface, y or
    (x, y), at the primary wavelength) as field angles in degrees.

    The paraxial chief ray at field (θx, θy) meets the image surface at K·(tan θx, tan θy),
    K the height per unit tangent (linear), so θ = atan(h / K) exactly. With an afocal
    image space only zero heights are read (``afocal_zero_heights``).
    """
    on_axis = afocal_zero_heights(lens, heights, 2)
    if on_axis is not None:
        return on_axis
    k = float(paraxial.image_height(lens, 45.0) / jnp.tan(jnp.deg2rad(45.0)))
    if not (math.isfinite(k) and k != 0.0):
        raise ValueError(
            f"paraxial image heights cannot be converted to angles: the paraxial "
            f"image height per unit field tangent is {k:g} mm (an afocal or "
            f"telecentric image space)"
        )
    angles = np.degrees(np.arctan(np.asarray(heights, np.float64) / k))
    return eqx.tree_at(lambda m: m.fields, lens, jnp.asarray(angles))


def angles_from_object_heights(lens: Lens, heights: np.ndarray) -> Lens:
    """The lens with ``heights`` (object heights in mm, y or (x, y); a finite object) as
    field angles in degrees: the angles whose object points (``sampling.object_point``: the
    point at which the chief ray toward the paraxial entrance pupil's centre makes that
    angle) are those heights, θ = atan(−h / (D + z_ep)), D the object distance and z_ep the
    pupil's position from surface 1 (a positive angle looks at an object below the axis).
    """
    if lens.object_at_infinity:
        raise ValueError("object heights (FTYP 1) need a finite object distance")
    lever = float(lens.object_distance) + float(paraxial.entrance_pupil_z(
        lens, lens.primary_wavelength))
    # lever < 0: the pupil lies before the object point (a virtual object after it), and a
    # positive height is a positive angle. Where a real object lies behind the pupil, its
    # rays could not reach the pupil; on the pupil's plane no angle gives a height.
    if not (math.isfinite(lever) and (lever > 0.0 or float(lens.object_distance) < 0.0)
            and lever != 0.0):
        raise ValueError(f"object heights cannot be converted to angles: the entrance pupil "
                         f"lies {-lever:g} mm before the object")
    angles = np.degrees(np.arctan(-np.asarray(heights, np.float64) / lever))
    return eqx.tree_at(lambda m: m.fields, lens, jnp.asarray(angles))


REAL_HEIGHT_TOLERANCE = 1e-9
"""Largest accepted miss (mm, relative to 1 + |h|) of the solved chief ray at FTYP 3 fields,
in float64; in a lower precision, 64 times its machine epsilon (float32: 7.6e-6)."""


def angles_from_real_image_heights(lens: Lens, heights: np.ndarray) -> Lens:
    """The lens with ``heights`` (real image heights in mm, y or (x, y), primary wavelength)
    as field angles in degrees: for each, the field whose real chief ray meets the image
    surface at that point.

    The chief ray is the one the lens's ray aiming traces (``_chief_ray``), as Zemax's is:
    with aiming off (``Lens.aim`` "paraxial", ``RAIM`` type 0 or no RAIM line) the ray
    through the centre of the paraxial entrance pupil, which Zemax and optiland also take for
    a real-image-height field; with aiming on, the ray aimed at the stop's centre. The two
    differ by the pupil aberration: for a double Gauss whose stop is between its groups (50
    mm, f/5), 0.002° and 0.02° at real heights of 6 and 12 mm; at the angles of the aimed
    rays, the chief ray through the paraxial pupil lands 5 and 40 µm short.

    The unknown is (tan θx, tan θy), solved by ``aiming.newton_2d`` from the paraxial guess
    h/K (K the paraxial height per unit tangent), so the angle stays inside (−90°, 90°).

    Raises:
        ValueError: when no valid real chief ray reaches a height (to
            ``REAL_HEIGHT_TOLERANCE``), naming the height.
    """
    on_axis = afocal_zero_heights(lens, heights, 3)
    if on_axis is not None:
        return on_axis
    h = np.asarray(heights, np.float64)
    xy = np.stack([np.zeros_like(h), h], -1) if h.ndim == 1 else h
    k = float(aiming.image_scale(lens))
    if not (math.isfinite(k) and k != 0.0):
        raise ValueError(f"real image heights cannot be converted to angles: the paraxial "
                         f"image height per unit field tangent is {k:g} mm")
    # A zero height on a rotationally symmetric lens is field 0 (its chief ray is the axis):
    # no solve, whose compile was most of such a file's load (ASL5040-UV, a Q-type asphere:
    # 9 s of 10).
    round_lens = symmetry.rotationally_symmetric(lens)
    angles = []
    for target in xy:
        t = jnp.asarray(target)
        if round_lens and not np.any(target):
            field, ray = jnp.zeros(2, t.dtype), _axial_ray(lens)
        else:
            field, ray = _real_height_field(lens, t, jnp.asarray(k))
        point, valid = _chief_ray_landing(lens, ray)
        err = float(jnp.max(jnp.abs(point - t)))
        tol = max(REAL_HEIGHT_TOLERANCE, 64 * float(jnp.finfo(point.dtype).eps))
        if not (bool(valid) and err <= tol * (1 + abs(target).max())):
            why = "" if bool(valid) else "; " + _where_it_stops(lens, field)
            raise ValueError(f"no real chief ray reaches the image height {target.tolist()} mm "
                             f"(closest: {err:.3g} mm away, valid: {bool(valid)}{why})")
        angles.append(np.asarray(field, np.float64))
    a = np.array(angles)
    return eqx.tree_at(lambda m: m.fields, lens, jnp.asarray(a[:, 1] if h.ndim == 1 else a))


def _axial_ray(lens: Lens):
    """The ray along the axis from the object (from the paraxial entrance pupil's centre for
    an object at infinity): the chief ray of field 0 of a rotationally symmetric lens."""
    return _pupil_centre_ray(lens, 0.0)


def _pupil_centre_ray(lens: Lens, field):
    """The ray of ``field`` (deg) through the centre of the paraxial entrance pupil: from
    the object point for a finite object, on the pupil's plane for one at infinity. Zemax's
    chief ray with ray aiming off."""
    pupil = jnp.zeros((1, 2), lens.epd.dtype)
    if lens.object_at_infinity:
        return sampling.collimated(lens, field, pupil, aim="paraxial")
    point = sampling.object_point(lens, field, lens.object_distance)
    return sampling.point_source(lens, point, pupil, aim="paraxial")


def _chief_ray(lens: Lens, field):
    """The real chief ray of ``field`` (deg) as the lens's ray aiming traces it (one ray, in
    object space): through the paraxial entrance pupil's centre with aiming off
    (``Lens.aim`` "paraxial"), else aimed at the stop's centre (``aiming.stop_chief_ray``,
    whose ``valid`` reports whether the aim converged)."""
    if lens.aim == "paraxial":
        return _pupil_centre_ray(lens, field)
    return aiming.stop_chief_ray(lens, field, lens.object_distance)


def _tangent_field(tan_xy):
    """Field angles (deg) of (tan θx, tan θy), kept finite and inside (−90°, 90°) while an
    iterate runs away (the final check then refuses it)."""
    t = jnp.clip(jnp.where(jnp.isfinite(tan_xy), tan_xy, 0.0), -1e6, 1e6)
    return jnp.rad2deg(jnp.arctan(t))


@eqx.filter_jit
def _real_height_field(lens: Lens, target, k):
    """The field (deg) whose real chief ray meets the image surface at ``target`` (mm), and
    that chief ray (``_chief_ray``: through the paraxial entrance pupil's centre with ray
    aiming off, else aimed at the stop centre) in object space.

    The ray comes from the solve's own last evaluation: aiming it again for the final check
    compiled a second copy of the aiming and its traces (with a polynomial surface, the
    Q-type asphere of rayoptics_ASL5040-UV.zmx, 3-4 s of its 10 s load)."""
    free = _geometry_only(lens)  # a clipped iterate would stop short of the image

    if lens.aim == "paraxial":  # Zemax's chief ray with ray aiming off (``_chief_ray``)
        def miss(tan_xy, target):
            ray = _pupil_centre_ray(free, _tangent_field(tan_xy))
            out = forward.trace(free, ray, uniform=True)
            return out.origin[0, :2] - target, ray
    else:
        def miss(tan_xy, target):
            point, ray = aiming.chief_point(free, _tangent_field(tan_xy),
                                            lens.object_distance,
                                            forward.DEFAULT_NEWTON_ITERS, with_ray=True)
            return point - target, ray

    tan_xy, ray = aiming.newton_2d(miss, target / k, target, 12, implicit_gradient=False,
                                   has_aux=True)
    return _tangent_field(tan_xy), ray


@eqx.filter_jit
def _chief_ray_landing(lens: Lens, ray):
    """(x, y) on the image surface of the aimed chief ``ray`` (``_real_height_field``'s), and
    its validity through the lens as it is (clipping apertures included; False also where
    the aim did not converge)."""
    out = forward.trace(lens, ray, uniform=True)
    return out.origin[0, :2], out.valid[0]


def _geometry_only(lens: Lens) -> Lens:
    """The lens with no semi-diameter clipping, the image surface's included."""
    free = unclipped(lens)
    return eqx.tree_at(lambda m: m.image.semi_diameter, free,
                       jnp.full_like(free.image.semi_diameter, jnp.inf))


@eqx.filter_jit
def _chief_ray_paths(lens: Lens, field):
    """The real chief ray's path through the lens as it is and without any clipping (one
    compiled program: op by op, the aiming and the two traces took about 9 s)."""
    rays = _chief_ray(lens, field)
    aimed = rays.valid[0]  # False: the aim at the stop centre did not converge
    rays = eqx.tree_at(lambda r: r.valid, rays, jnp.ones_like(rays.valid))
    paths = tuple(forward.trace_path(m, rays, uniform=True) for m in (lens, _geometry_only(lens)))
    return paths + (aimed,)


def _where_it_stops(lens: Lens, field) -> str:
    """Where the chief ray of ``field`` becomes invalid, in words (Zemax surface numbers):
    clipped by a semi-diameter, or lost (a miss or total internal reflection)."""
    path, free_path, aimed = _chief_ray_paths(lens, field)
    if not bool(aimed):
        return ("its aim at the centre of the stop did not converge (no launch point found "
                "whose ray crosses the stop at its centre)")
    valid = np.asarray(path.valid).reshape(len(path.valid), -1)[:, 0]
    i = int(np.argmin(valid))  # the first invalid entry: surface i (the last: the image)
    surface = lens.surfaces[i] if i < lens.num_surfaces else lens.image
    name = f"surface {i + 1}" if i < lens.num_surfaces else "the image surface"
    if not bool(np.asarray(free_path.valid).reshape(len(valid), -1)[i, 0]):
        return f"it is lost at {name} (a miss or total internal reflection)"
    r = float(np.hypot(*np.asarray(free_path.origin).reshape(len(valid), -1, 3)[i, 0, :2]))
    return (f"it is clipped at {name}, which it meets {r:.4g} mm from the axis, outside its "
            f"semi-diameter {float(surface.semi_diameter):.4g} mm (a surface aperture, "
            f"CLAP or FLAP, clips rays)")


FIELD_TYPES = {
    0: "angles",
    1: "object heights",
    2: "paraxial image heights",
    3: "real image heights",
    4: "theodolite angles",
}
"""Zemax's field types (FTYP's first value)."""


def field_type(ln) -> int:
    """FTYP's field type: 0 (angles, degrees), 1 (object heights), 2 (paraxial image heights)
    or 3 (real image heights); others refused.

    Args:
        ln: the file's FTYP line (the reader's line object) or None.
    """
    if ln is None:
        return 0
    kind = ln.int(1, "field type")
    if kind not in (0, 1, 2, 3):
        raise ln.error(
            f"field type {kind} ({FIELD_TYPES.get(kind, 'unknown')}) is not supported; use "
            f"angles (FTYP 0), object heights (FTYP 1), paraxial (FTYP 2) or real (FTYP 3) "
            f"image heights")
    # Image heights with an afocal image space (FTYP's seventh value 1) are read only where
    # every one is 0, the axis whatever the field type (``afocal_zero_heights``).
    return kind


def object_telecentric(ln) -> bool:
    """FTYP's second value: 1 for an object-space telecentric system (``Lens.object_na``),
    0 (or absent) otherwise; other values refused.

    Args:
        ln: the file's FTYP line (the reader's line object) or None.
    """
    return _ftyp_flag(ln, 2, "object-space telecentric flag (FTYP's second value)")


def _ftyp_flag(ln, i: int, name: str) -> bool:
    """FTYP's ``i``-th value as a 0/1 flag (False where the line or the value is absent)."""
    if ln is None or len(ln.tokens) <= i:
        return False
    flag = ln.int(i, name)
    if flag not in (0, 1):
        raise ln.error(f"the {name} must be 0 or 1, got {flag}")
    return flag == 1


TELECENTRIC_APERTURES = ("obna", "cone", "float")
"""The apertures of an object-space telecentric system (``.zmx`` aperture kinds): the
object-space NA (OBNA x 0), the object cone angle (OBNA x 1) and float by stop size (FLOA).
OpticStudio allows only these with "Telecentric Object Space" (an entrance pupil at
infinity has no diameter, and an F/# would not fix the object-space cone); optiland's
apertures that support telecentric object space are the same (ObjectNA, FloatByStop)."""


def check_telecentric(ftyp, kind: int, aperture, dist: float, aim: str) -> str:
    """Refuse what an object-space telecentric system (FTYP's second value 1) cannot have:
    field angles (FTYP 0 or 4; object heights, FTYP 1, and paraxial image heights, FTYP 2,
    are read), real image heights (FTYP 3, not implemented for it), an entrance-pupil
    diameter or F/# aperture (``TELECENTRIC_APERTURES``), an object at infinity. Ray aiming
    (RAIM) does not apply: returns the ``Lens.aim`` to use ("paraxial"), warning where the
    file turns it on."""
    if kind in (0, 4):
        raise ftyp.error(f"an object-space telecentric system (FTYP's second value 1) has "
                         f"every chief ray parallel to the axis, so its fields cannot be "
                         f"{FIELD_TYPES[kind]} (FTYP {kind}); OpticStudio requires object "
                         f"heights (FTYP 1) or image heights")
    if aperture is not None and aperture[0] not in TELECENTRIC_APERTURES:
        what = {"epd": "entrance pupil diameter (ENPD)", "fnum": "image-space F/# (FNUM)",
                "wfno": "paraxial working F/# (FNUM x 1)"}.get(aperture[0], aperture[0])
        raise aperture[2].error(
            f"an object-space telecentric system (FTYP's second value 1) cannot take an "
            f"{what} aperture: its entrance pupil lies at infinity; OpticStudio allows the "
            f"object-space NA (OBNA x 0), the object cone angle (OBNA x 1) or float by stop "
            f"size (FLOA)")
    if math.isinf(dist):
        raise ftyp.error("an object-space telecentric system (FTYP's second value 1) needs "
                         "an object at a finite distance; the object DISZ is INFINITY")
    if aim != "paraxial":
        warnings.warn(f"{ftyp.path}:{ftyp.number}: ray aiming (RAIM) is ignored in an "
                      f"object-space telecentric system: every chief ray leaves its object "
                      f"point parallel to the axis", ZmxWarning, stacklevel=4)
    return "paraxial"


def heights_from_paraxial_image_heights(lens: Lens, heights: np.ndarray) -> Lens:
    """An object-space telecentric lens with ``heights`` (paraxial image heights in mm, y or
    (x, y), primary wavelength) as object heights: the paraxial chief ray (parallel to the
    axis) is linear in the object height, so h_obj = h_img / m, m the image height per mm
    of object height (the paraxial magnification)."""
    m = float(paraxial.image_height(lens, 1.0))
    if not (math.isfinite(m) and m != 0.0):
        raise ValueError(f"paraxial image heights cannot be converted to object heights: the "
                         f"paraxial magnification is {m:g}")
    h = np.asarray(heights, np.float64) / m
    return eqx.tree_at(lambda l: l.fields, lens, jnp.asarray(h))


def heights_from_real_image_heights(lens: Lens, heights: np.ndarray) -> Lens:
    """An object-space telecentric lens with ``heights`` (real image heights in mm, y or
    (x, y), primary wavelength) as object heights: for each, the object point whose real
    chief ray (parallel to the axis) meets the image surface there, by Newton's method with a
    central-difference Jacobian from the paraxial guess h / m.

    Raises:
        ValueError: where no valid chief ray reaches a height (to ``REAL_HEIGHT_TOLERANCE``).
    """
    m = float(paraxial.image_height(lens, 1.0))
    if not (math.isfinite(m) and m != 0.0):
        raise ValueError(f"real image heights cannot be converted to object heights: the "
                         f"paraxial magnification is {m:g}")
    h = np.asarray(heights, np.float64)
    xy = np.stack([np.zeros_like(h), h], -1) if h.ndim == 1 else h
    free = _geometry_only(lens)
    centre = jnp.zeros((1, 2))

    def land(p):
        rays = sampling.field_rays(free, jnp.asarray(p), centre, depth=lens.object_distance)
        out = forward.trace(free, rays)
        return np.asarray(out.origin[0, :2]), bool(out.valid[0])

    found = []
    for target in xy:
        p = target / m
        for _ in range(12):
            at, _ = land(p)
            miss = at - target
            if np.max(np.abs(miss)) <= 1e-13 * (1 + np.max(np.abs(target))):
                break
            step = 1e-6 * (1.0 + np.max(np.abs(p)))
            jac = np.stack([(land(p + e)[0] - land(p - e)[0]) / (2 * step)
                            for e in np.eye(2) * step], -1)
            p = p - np.linalg.solve(jac, miss)
        at, valid = land(p)
        err = float(np.max(np.abs(at - target)))
        if not (valid and err <= REAL_HEIGHT_TOLERANCE * (1 + np.max(np.abs(target)))):
            raise ValueError(f"no real chief ray reaches the image height {target.tolist()} mm "
                             f"(closest: {err:.3g} mm away, valid: {valid})")
        found.append(p)
    f = np.array(found)
    return eqx.tree_at(lambda m_: m_.fields, lens, jnp.asarray(f[:, 1] if h.ndim == 1 else f))


def afocal_zero_heights(lens: Lens, heights: np.ndarray, kind: int) -> Lens | None:
    """Image heights (FTYP 2 or 3, ``kind``) of a lens with an afocal image space
    (``Lens.afocal_image``): all 0 mm reads as on axis (field angle 0°, the same field
    whatever the field type), returned as the lens with zero fields; ``None`` when the image
    space is not afocal (convert the heights as usual).

    Raises:
        ValueError: for a nonzero height: an image at infinity has no heights.
    """
    if not lens.afocal_image:
        return None
    h = np.asarray(heights, np.float64)
    if np.any(h != 0.0):
        raise ValueError(
            f"field type {kind} ({FIELD_TYPES[kind]}) with an afocal image space (FTYP's "
            f"seventh value 1): an image at infinity has no heights, and the file gives "
            f"{float(np.max(np.abs(h))):g} mm (only 0, the axis, is read); use angles "
            f"(FTYP 0) or object heights (FTYP 1)")
    return eqx.tree_at(lambda m: m.fields, lens, jnp.zeros_like(jnp.asarray(h)))


def afocal_image_space(ln) -> bool:
    """FTYP's seventh value: 1 for an afocal image space (``Lens.afocal_image``), 0 (or
    absent) for an image at a finite distance; other values refused.

    Args:
        ln: the file's FTYP line (the reader's line object) or None.
    """
    return _ftyp_flag(ln, 7, "afocal image space flag (FTYP's seventh value)")


VIGNETTING_KEYS = ("VDXN", "VDYN", "VCXN", "VCYN", "VANN")
"""The file's vignetting lines, in the column order of ``Lens.vignetting``."""


def values_for_fields(ln, given: int, defined: int, what: str) -> None:
    """Refuse a field line (``XFLN``, ``FWGN``, ``VDXN``, …) with fewer values than the
    ``defined`` fields (those the y field line gives): Zemax writes one value a field, or
    12 padded with zeros, so a shorter line was cut short and the values it lacks are not
    known (0 would be a silent guess)."""
    if given < defined:
        raise ln.error(f"{ln.tokens[0]} gives {given} value{'s' * (given != 1)} ({what}) for "
                       f"{defined} fields; Zemax writes one a field")


def vignetting(lines, count: int, *, defined: int | None = None) -> np.ndarray | None:
    """The vignetting factors of the first ``count`` (used) fields, ``[count, 5]`` in the
    column order of ``Lens.vignetting`` (VDX, VDY, VCX, VCY in fractions of the
    entrance-pupil radius, VAN in degrees), or None where every one is 0 (or no line gives
    them).

    They reshape each field's pupil, Zemax's stand-in for the clipping of the surface
    apertures (``jaxlens.imaging.sampling.vignetting_map``); a line the file does not
    give is 0 (Zemax's default: no vignetting factor), and so are the fields beyond the
    ``defined`` ones (default ``count``: those the y field line gives; the reader reports
    the others). A line with fewer values than the ``defined`` fields is read where all
    it gives is 0 (``VDXN 0``, as Quadoa's export writes for any number of fields: no
    vignetting whether the value is meant for every field or the rest take the default 0)
    and refused otherwise; a line given twice,
    a value that is not finite, or a compression (VCXN, VCYN) of 1 or more is refused,
    naming the line. Paraxial data and the EFL do not depend on them. VANN's direction
    (counter-clockwise, from +x toward +y, after the compression and decenter) is jaxlens's
    documented convention, which no OpticStudio text at hand confirms (``vignetting_map``).
    """
    defined = count if defined is None else defined
    out = np.zeros((count, len(VIGNETTING_KEYS)))
    seen: dict[str, object] = {}
    for ln in lines:
        key = ln.tokens[0].upper()
        if key in seen:
            raise ln.error(f"{key} given twice (first on line {seen[key].number})")
        seen[key] = ln
        j = VIGNETTING_KEYS.index(key)
        vals = [ln.float(i, f"{key} value") for i in range(1, len(ln.tokens))]
        if 0 < len(vals) < defined and all(v == 0.0 for v in vals):
            # Quadoa's export writes 'VDXN 0' whatever the number of fields: the factor for
            # every field, or those it lacks at Zemax's default (0), read the same.
            continue
        values_for_fields(ln, len(vals), defined, "vignetting factors")
        vals = vals[:count]
        for i, v in enumerate(vals):
            unit = "deg" if key == "VANN" else "fractions of the entrance-pupil radius"
            if not math.isfinite(v):
                raise ln.error(f"{key} of field {i + 1} must be a finite number ({unit}), "
                               f"got {v!r}")
            if key in ("VCXN", "VCYN") and not v < 1.0:
                raise ln.error(f"{key} of field {i + 1} must be below 1 ({unit}: 1 shrinks "
                               f"the pupil to a line), got {v:g}")
            out[i, j] = v
    return out if np.any(out != 0) else None


def unequal_weights(ln, what: str, weights: list) -> None:
    """Warn where the file weighs its fields or wavelengths unequally: a ``Lens`` holds no
    weights, and jaxlens's figures over several of them weigh each equally."""
    if len(set(weights)) < 2:
        return
    shown = ", ".join(f"{w:g}" for w in weights)
    warnings.warn(f"{ln.path}:{ln.number}: the file weighs its {len(weights)} {what} "
                  f"({shown}); a jaxlens Lens holds no weights, so its figures over several "
                  f"{what} weigh each equally (Zemax's weighted figures differ)", ZmxWarning,
                  stacklevel=5)


def environment(ln, materials, strict: bool) -> None:
    """Check the file's environment (``ENVD`` temperature °C, pressure atm, and a flag, 1 where
    Zemax adjusts the glass indices to them). jaxlens takes catalog indices relative to air
    at 20 °C and 1 atm: another environment with the flag set changes every refracting
    surface's index (1 atm of air alone is 3e-4), so it is refused; with the flag 0 it is
    reported. Systems of mirrors in air do not depend on it."""
    if ln is None or len(ln.tokens) < 3 or all(isinstance(m, Air) for m in materials):
        return
    t, p = ln.float(1, "temperature (°C)"), ln.float(2, "pressure (atm)")
    if (t, p) == (20.0, 1.0):
        return
    if len(ln.tokens) > 3 and ln.int(3, "ENVD's index adjustment flag") != 0:
        raise ln.error(f"glass indices adjusted to {t:g} °C and {p:g} atm (ENVD's third value 1) "
                       f"are not supported; jaxlens uses catalog indices relative to air at "
                       f"20 °C and 1 atm")
    report(strict, f"{ln.path}:{ln.number}: the file's environment ({t:g} °C, {p:g} atm) is "
                   f"ignored; jaxlens uses catalog indices relative to air at 20 °C and 1 atm: "
                   f"{ln.text.strip()!r}")


RAY_AIMING_TYPES = {0: "off", 1: "paraxial", 2: "real"}
"""Zemax's ray-aiming types (RAIM's second value): 0 "Off" (rays through the paraxial
entrance pupil), 1 "Paraxial" (real rays aimed at the stop, its size from the paraxial
marginal ray), 2 "Real" (the same, the stop's size from a real marginal ray)."""


RAIM_AIM = {0: "paraxial", 1: "real", 2: "real_marginal"}
"""``Lens.aim`` for each RAIM ray-aiming type (and the type ``save_zmx`` writes for each)."""


def ray_aiming(ln) -> str:
    """``Lens.aim`` from RAIM's ray-aiming type (``RAIM_AIM``): 0 (Zemax's "Off", or no RAIM
    line) is ``"paraxial"``; 1 (Zemax's "Paraxial" ray aiming: real rays aimed at the stop,
    whose size the paraxial marginal ray sets) ``"real"``; 2 (Zemax's "Real" ray aiming, the
    stop's size from the real on-axis marginal ray) ``"real_marginal"``. Other types are
    refused."""
    if ln is None or len(ln.tokens) < 3:
        return "paraxial"
    kind = ln.int(2, "ray aiming type")
    if kind not in RAY_AIMING_TYPES:
        raise ln.error(f"ray aiming type {kind} (RAIM's second value) is not one of 0 (off), "
                       f"1 (paraxial) or 2 (real)")
    return RAIM_AIM[kind]


def float_by_stop_aim(aim: str) -> str:
    """``Lens.aim`` of a file whose aperture is the stop's size (FLOA): the rays fill the
    stop's semi-diameter whatever RAIM's type, as OpticStudio aims them (the stop's size is
    given, not found from a marginal ray; optiland 0.6.3's ``FloatByStopStrategy`` does the
    same for every aiming mode). The reader sets the EPD whose paraxial marginal ray fills
    that stop, so ``"real"`` (the stop sized by the paraxial marginal ray) is that aim; the
    real marginal ray of Zemax's "Real" aiming (``"real_marginal"``) lands elsewhere (4.06
    mm against the 4 mm stop of tests/data/aim45a/triplet_floa_raim2.zmx: the stop clipped
    the aimed beam at pupil radius 0.985 and the geometric |OTF| left optiland's by up to
    0.019; where the real ray lands inside the paraxial one, the beam was narrower than the
    stop). Other aims are returned as they are."""
    return "real" if aim == "real_marginal" else aim
