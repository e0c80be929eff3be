"""Rays of an object-space telecentric lens (``Lens.object_na``): the entrance pupil at
infinity, every chief ray leaving its object point parallel to the axis.

A field is an object height (mm): y, or (x, y), the object point's coordinates on the
object plane ``depth`` mm before surface 1. The ray of normalised pupil point (Px, Py) leaves
that point with the slopes (Px, Py)·tan u, u = asin(NA / n) the half-angle of the object
cone (n the object-space index at the primary wavelength): the limit of rays aimed at an
entrance pupil of diameter 2·L·tan u at a distance L → ∞, as optiland launches them
(its ``ParaxialRayAimer`` with an object-NA aperture; Zemax requires the object-space NA,
the object cone angle or float by stop size as the aperture of such a system). The samplers
of ``jaxlens.imaging.sampling`` call these for such a lens (``sampling.field_rays``).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks, paraxial
from ..optics.lens import Lens, check_object_distance
from ..optics.rays import Rays


def height_xy(field, where: str, arg: str = "field") -> Array:
    """Object heights (mm, y or (x, y), leading axes batch) as (x, y) pairs, checked finite."""
    checks.real_values(field, arg, where, "mm")
    f = jnp.asarray(field)
    if not checks.is_traced(f):
        checks.values(f, f"{arg} (object heights of an object-space telecentric lens)", where,
                      unit="mm")
    if f.ndim == 0 or f.shape[-1] != 2:
        f = jnp.stack([jnp.zeros_like(f), f], -1)
    return f


def one_height(field, where: str):
    """One field of an object-space telecentric lens: an object height y or (x, y) in mm,
    checked; a ``[1]`` array is y."""
    checks.real_values(field, "field", where, "mm")
    shape = np.shape(field)
    if shape not in ((), (1,), (2,)):
        raise ValueError(f"{where}: field must be one object height, y or (x, y) in mm (the "
                         f"lens is object-space telecentric), got shape {shape}")
    height_xy(field, where)
    return jnp.reshape(jnp.asarray(field), ()) if shape == (1,) else jnp.asarray(field)


def lens_field(lens: Lens, field, where: str,
               hint: str = "analyse several fields one at a time"):
    """One field of ``lens``, checked before tracing in the lens's own unit: an object
    height (mm, y or (x, y); :func:`one_height`) for an object-space telecentric lens, else
    an angle θy or (θx, θy) in degrees (``checks.one_field``; warned about where the angles
    look like radians). The one-field analyses (PSF, MTF, encircled energy, wavefront, the
    fans) checked every field as an angle: a telecentric lens's height of 95 mm was refused
    as "95 deg" outside (-90, 90)."""
    if lens.telecentric_object:
        return one_height(field, where)
    f = checks.one_field(field, where, hint)
    checks.warn_if_radian_fields(field, where, "field")  # 20° typed as 0.349
    return f


def lens_fields(lens: Lens, fields, where: str, arg: str = "fields"):
    """Fields of ``lens`` (any shape) checked in its own unit: finite object heights (mm) for
    an object-space telecentric lens, else angles in (-90°, 90°) (``checks.field_angles``).
    Returns ``fields`` (traced: with the check attached)."""
    if not lens.telecentric_object:
        return checks.field_angles(fields, where, arg)
    checks.real_values(fields, arg, where, "mm")
    return checks.values(fields, f"{arg} (object heights of an object-space telecentric lens)",
                         where, unit="mm")


def source(lens: Lens, field, pupil: Float[Array, "m 2"], wavelength, depth) -> Rays:
    """``[m]`` rays of an object-space telecentric ``lens`` from the object point at height
    ``field`` (mm, y or (x, y)) on the plane ``depth`` mm before surface 1 (> 0: a virtual
    object is refused, as ``Lens`` refuses one for such a lens), launched at that point
    (``opl`` 0) with the slopes (Px, Py)·tan u toward +z. ``pupil`` (normalised points)
    and ``wavelength`` (µm) are the caller's, checked."""
    if not lens.telecentric_object:
        raise ValueError("telecentric.source: the lens is not object-space telecentric "
                         "(Lens.object_na is None); use sampling.field_rays")
    if depth is None:
        raise ValueError("an object-space telecentric lens (Lens.object_na given) needs a "
                         "finite object distance (mm); got an object at infinity")
    depth = check_object_distance(depth, "depth", "telecentric.source")
    # A virtual object (depth < 0) launched its rays after surface 1, which they then missed
    # (Lens refuses one for a telecentric lens; field_rays(depth=-5) traced it).
    if checks.is_traced(depth):
        depth = eqx.error_if(depth, depth < 0, "telecentric.source: an object-space "
                             "telecentric lens needs a real object (depth > 0 mm)")
    elif float(depth) < 0:
        raise ValueError(f"telecentric.source: an object-space telecentric lens (object_na "
                         f"given) needs a real object before surface 1 (depth > 0 mm), got "
                         f"{float(depth):g} mm (a virtual object is not supported for it)")
    depth = jnp.asarray(depth)
    xy = height_xy(field, "telecentric.source").astype(pupil.dtype)
    point = jnp.concatenate([xy, -depth[None].astype(pupil.dtype)])
    slope = paraxial.object_slope(lens).astype(pupil.dtype)
    v = jnp.concatenate([pupil * slope, jnp.ones_like(pupil[..., :1])], -1)
    direction = v / jnp.linalg.norm(v, axis=-1, keepdims=True)
    origin = jnp.broadcast_to(point, direction.shape)
    return Rays(origin, direction, wavelength)


def radial_heights(fields, xy):
    """Object and image heights of an object-space telecentric lens's fields along their
    directions, as ``spots.field_heights`` gives them for angles.

    ``fields`` are ``[F]`` object heights y or ``[F, 2]`` (x, y) (mm), ``xy`` ``[F, 2]``
    image points (mm). Returns ``(h, xy·a)``: for ``[F]`` fields the signed height y and
    the points' y; for ``[F, 2]`` the radial height |(x, y)| and the component of each point
    along its field's direction a = (x, y)/|(x, y)| (+y on axis), so that the ideal image of
    a distortion-free lens of magnification m lies at m·h."""
    if fields.ndim == 1:
        return fields, xy[:, 1]
    a = azimuth(fields)
    s = jnp.sum(fields * fields, axis=-1)
    h = jnp.where(s > 0, jnp.sqrt(jnp.where(s > 0, s, 1.0)), 0.0)  # grad-safe at 0
    return h, jnp.sum(xy * a, axis=-1)


def azimuth(field):
    """Unit (x, y) direction of object heights ``field`` (``[..., 2]`` mm, or a scalar y):
    (0, 1) for a y height and on axis, else (x, y)/|(x, y)| (the meridional plane)."""
    f = jnp.asarray(field)
    if f.ndim == 0:
        return jnp.array([0.0, 1.0], f.dtype)
    r = jnp.sqrt(jnp.sum(f * f, axis=-1, keepdims=True))
    on_axis = r == 0
    return jnp.where(on_axis, jnp.array([0.0, 1.0], f.dtype), f / jnp.where(on_axis, 1.0, r))


def largest_height(lens: Lens) -> Array:
    """The lens's largest object height (mm): radial for (x, y) fields."""
    f = jnp.asarray(lens.fields)
    return jnp.max(jnp.sqrt(jnp.sum(f * f, -1)) if f.ndim == 2 else jnp.abs(f))


def in_cone(lens: Lens, direction: Float[Array, "*b 3"]) -> Array:
    """Whether object-space ray directions (``[..., 3]``, either sense along z, as a backward
    trace leaves them) lie in the object cone of an object-space telecentric lens: slope
    |(dx, dy)/dz| at most tan u, u = asin(NA / n) (``paraxial.object_slope``), the cone that
    ``source`` launches. The object NA is such a lens's system aperture: a ray from the object
    outside the cone carries no light into the system, whichever stop it would pass
    (``radiometry`` bounds the cone the same way)."""
    paraxial.telecentric_only(lens, "in_cone")
    t = paraxial.object_slope(lens).astype(direction.dtype)
    return jnp.sum(direction[..., :2] ** 2, -1) <= (t * direction[..., 2]) ** 2


def object_plane(lens: Lens, depth, where: str) -> None:
    """Refuse an object at infinity (``depth`` None, as ``sampling.lens_depth`` returns it)
    for an object-space telecentric lens in ``where``, whose scene is the object plane in
    object heights (mm). Other lenses pass."""
    if lens.telecentric_object and depth is None:
        raise ValueError(f"{where}: the lens is object-space telecentric (Lens.object_na): its "
                         f"object is a plane of object heights (mm), so depth must be a "
                         f"finite object distance in mm (> 0, before surface 1); got an object "
                         f"at infinity")
