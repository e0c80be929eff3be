"""Ray sources: pupil sampling patterns and object-space ray bundles.

Conventions:
    Normalised pupil coordinates (Px, Py) lie in the unit disc. Field angles are in
    degrees: ``field = (θx, θy)`` or a scalar θy. A collimated beam at field (θx, θy)
    travels along (tan θx, tan θy, 1)/norm, which is (0, sin θ, cos θ) for a y field.
    Rays are aimed at the paraxial entrance pupil: the ray through pupil point
    (Px, Py) passes through (Px·EPD/2, Py·EPD/2, z_EP). With ``aim="real"`` the launch
    points are corrected by Newton's method so that the rays cross the real stop at
    (Px, Py)·(stop radius): the paraxial marginal ray's height at the stop, or with
    ``aim="real_marginal"`` the real marginal ray's (``stop_radius``; the table of Zemax's
    ray-aiming modes is in ``optics.lens``).

Vignetting factors:
    A lens's ``vignetting`` (Zemax VDX, VDY, VCX, VCY, VAN, one row per field) reshapes the
    pupil of each of its fields: ``field_rays`` maps the normalised pupil point (Px, Py) to
    ``vignetting_map`` (Px', Py') and launches the ray there (aimed there too with
    ``aim="real"`` or ``"real_marginal"``). The factors belong to the lens's defined fields:
    they apply to a field equal to one of ``lens.fields`` (within ``FIELD_MATCH_DEG``), and
    to no other field (no interpolation between fields: a PSF at a field between the defined
    fields samples the whole pupil, and ``render`` drops the factors). For a field with
    nonzero factors, pupil points outside the unit disc (an overfilled beam) launch invalid
    rays: the vignetted pupil is the image of the unit disc. ``collimated`` and
    ``point_source`` take the pupil points as given and never apply them.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks, paraxial
from ..optics.lens import (
    INFINITE_OBJECT_MM,
    RAY_AIMING,
    Lens,
    check_object_distance,
    check_vignetting,
    unclipped,
)
from ..optics.rays import Rays
from . import telecentric
from .newton import newton_2d

_MAX_SIDE = math.isqrt(checks.MAX_PUPIL_POINTS)  # 4096 points or cells per side
_MAX_RINGS = 2364  # the most hexapolar rings with 3r(r+1) + 1 ≤ MAX_PUPIL_POINTS


def grid_axis(n: int) -> np.ndarray:
    """``n`` points over [−1, 1] end to end; one point is the centre (``linspace(-1, 1, 1)``
    is the edge alone). The axis of every square grid of pupil points or fields."""
    return np.linspace(-1.0, 1.0, n) if n > 1 else np.zeros(1)


def pupil_grid(n: int = 21, dtype=None) -> Float[Array, "m 2"]:
    """Square grid of n×n points over [−1, 1]², kept inside the unit disc (r² ≤ 1 + 1e-12)."""
    n = checks.number(n, "n", "pupil_grid", lo=1, hi=_MAX_SIDE, integer=True,
                      unit=f"points per side (n² ≤ {checks.MAX_PUPIL_POINTS} points)")
    checks.float_dtype(dtype, "pupil_grid")
    u = grid_axis(n)
    px, py = np.meshgrid(u, u, indexing="xy")
    keep = px**2 + py**2 <= 1.0 + 1e-12
    pts = np.stack([px[keep], py[keep]], axis=-1)
    return jnp.asarray(pts, dtype=dtype)


def pupil_hexapolar(rings: int = 6, dtype=None) -> Float[Array, "m 2"]:
    """Hexapolar pattern: the centre plus ring i (1..rings) of 6·i equally spaced points."""
    rings = checks.number(rings, "rings", "pupil_hexapolar", lo=0, hi=_MAX_RINGS, integer=True,
                          unit=f"rings (3r(r+1) + 1 ≤ {checks.MAX_PUPIL_POINTS} points)")
    checks.float_dtype(dtype, "pupil_hexapolar")
    ring = np.repeat(np.arange(1, rings + 1), 6 * np.arange(1, rings + 1))  # ring i, 6i times
    first = 3 * ring * (ring - 1)  # index of ring i's first point among the ring points
    a = 2 * np.pi * (np.arange(ring.size) - first) / (6 * ring)
    r = ring / max(rings, 1)
    pts = np.concatenate([np.zeros((1, 2)), np.stack([r * np.sin(a), r * np.cos(a)], -1)])
    return jnp.asarray(pts, dtype=dtype)


def pupil_random(key, n: int, dtype=None) -> Float[Array, "n 2"]:
    """n points uniform over the unit disc."""
    n = checks.number(n, "n", "pupil_random", lo=1, hi=checks.MAX_PUPIL_POINTS, integer=True,
                      unit="points")
    checks.prng_key(key, "pupil_random")
    checks.float_dtype(dtype, "pupil_random")
    k1, k2 = jax.random.split(key)
    dt = dtype or jnp.result_type(float)
    r = jnp.sqrt(jax.random.uniform(k1, (n,), dt))
    a = jax.random.uniform(k2, (n,), dt, 0.0, 2 * jnp.pi)
    return jnp.stack([r * jnp.cos(a), r * jnp.sin(a)], -1)


def pupil_stratified(key, n_side: int, dtype=None) -> Float[Array, "m 2"]:
    """Jittered (stratified) samples: one random point per cell of an n_side² polar grid."""
    n_side = checks.number(n_side, "n_side", "pupil_stratified", lo=1, hi=_MAX_SIDE,
                           integer=True, unit=f"cells per side (n² ≤ {checks.MAX_PUPIL_POINTS})")
    checks.prng_key(key, "pupil_stratified")
    dt = checks.float_dtype(dtype, "pupil_stratified") or jnp.result_type(float)
    i, j = jnp.meshgrid(jnp.arange(n_side), jnp.arange(n_side), indexing="ij")
    u = jax.random.uniform(key, (2, n_side, n_side), dt)
    r = jnp.sqrt((i + u[0]) / n_side)
    a = 2 * jnp.pi * (j + u[1]) / n_side
    return jnp.stack([r * jnp.cos(a), r * jnp.sin(a)], -1).reshape(-1, 2)


def pupil_polar(n_side: int, key=None, dtype=None, *, radius: float = 1.0 - 1e-4
                ) -> Float[Array, "m 2"]:
    """``n_side²`` points, one per cell of an equal-area polar grid of the disc of ``radius``.

    Without a key each point sits at its cell's centre (in r² and angle); with one it is
    jittered uniformly inside its cell (stratified sampling). Every point lies strictly
    inside the disc, so a beam aimed at a stop-first lens's entrance pupil with
    ``radius < 1`` loses no ray at the stop: no ray is carried invalid through the lens, and
    no stale ray can make a gradient NaN.
    """
    n_side = checks.number(n_side, "n_side", "pupil_polar", lo=1, hi=_MAX_SIDE, integer=True,
                           unit=f"cells per side (n² ≤ {checks.MAX_PUPIL_POINTS})")
    checks.number(radius, "radius", "pupil_polar", lo=0, hi=1, lo_open=True,
                  unit="(pupil radii)")
    checks.prng_key(key, "pupil_polar", optional=True)
    dt = checks.float_dtype(dtype, "pupil_polar") or jnp.result_type(float)
    i, j = jnp.meshgrid(jnp.arange(n_side), jnp.arange(n_side), indexing="ij")
    if key is None:
        u = jnp.full((2, n_side, n_side), 0.5, dt)
    else:
        u = jax.random.uniform(key, (2, n_side, n_side), dt)
    r = jnp.sqrt((i + u[0]) / n_side) * radius
    a = 2 * jnp.pi * (j + u[1]) / n_side
    return jnp.stack([r * jnp.cos(a), r * jnp.sin(a)], -1).reshape(-1, 2)


def pupil_samples(scheme: str, n: int, key=None, dtype=None) -> Float[Array, "m 2"]:
    """Pupil points by scheme name: "grid" (n per side), "hexapolar" (n rings),
    "random" (n points) or "stratified" (n per side). The last two draw with ``key``
    (a ``jax.random`` key), ``PRNGKey(0)`` where none is given: the same points on every
    call, so pass a key per call for independent draws."""
    if scheme == "grid":
        return pupil_grid(n, dtype)
    if scheme == "hexapolar":
        return pupil_hexapolar(n, dtype)
    if scheme in ("random", "stratified"):
        key = jax.random.PRNGKey(0) if key is None else key
        fn = pupil_random if scheme == "random" else pupil_stratified
        return fn(key, n, dtype)
    raise ValueError(
        f"pupil_samples: unknown scheme {scheme!r}; use grid, hexapolar, random or stratified"
    )


UNIT_DISC_TOLERANCE = 1e-9
"""Pupil points may lie this far outside the unit disc (rounding) where it is required; more
in float32 (``unit_disc_limit``)."""


def unit_disc_limit(dtype) -> float:
    """The largest radius accepted for unit-pupil points of ``dtype``: 1 plus
    ``UNIT_DISC_TOLERANCE`` or a few ulps (``pupil_hexapolar``'s float32 rim points lie at
    1 + 2.3e-8)."""
    dt = dtype if jnp.issubdtype(dtype, jnp.floating) else jnp.result_type(float)
    return 1.0 + max(UNIT_DISC_TOLERANCE, 4 * float(jnp.finfo(dt).eps))


def pupil_points(pupil, where: str, *, unit_disc: bool = False) -> Array:
    """Checked normalised pupil points ``[..., 2]`` (Px, Py): real, finite (when concrete),
    shaped as pairs, and with ``unit_disc`` inside the unit disc (the analyses whose pupil is
    the beam itself; the ray sources also take overfilled points). Raises naming ``where``."""
    checks.real_values(pupil, "pupil", where, "normalised pupil coordinates")
    pupil = jnp.asarray(pupil)
    if pupil.ndim < 1 or pupil.shape[-1] != 2 or pupil.size == 0:
        raise ValueError(f"{where}: pupil must be [m, 2] normalised pupil points (Px, Py), got "
                         f"shape {pupil.shape}")
    if checks.is_traced(pupil):  # under jit a NaN pupil point launched NaN rays silently
        pupil = checks.finite_array(pupil, "pupil", where, "normalised pupil coordinates")
        if unit_disc:
            r2 = jnp.sum(pupil * pupil, -1)
            pupil = eqx.error_if(pupil, jnp.any(r2 > unit_disc_limit(pupil.dtype) ** 2),
                                 f"{where}: pupil points must lie in the unit disc (Px² + Py² "
                                 f"<= 1, normalised to the entrance pupil)")
    else:
        checks.finite_array(pupil, "pupil", where, "normalised pupil coordinates")
        r = np.sqrt(np.sum(np.asarray(pupil, float) ** 2, -1)) if unit_disc else 0.0
        if np.any(r > unit_disc_limit(pupil.dtype)):
            # A point outside the disc is no part of the beam.
            raise ValueError(f"{where}: pupil points must lie in the unit disc "
                             f"(Px² + Py² <= 1, normalised to the entrance pupil), got "
                             f"radius {float(np.max(r)):.6g}")
    return pupil


def _field_deg(field) -> Array:
    """A field (deg, θy or (θx, θy), leading axes batch) as (θx, θy) pairs in degrees."""
    checks.real_values(field, "field", "sampling", "deg")  # before jnp.asarray
    f = checks.field_angles(jnp.asarray(field), "sampling", "field")
    if f.ndim == 0 or f.shape[-1] != 2:
        f = jnp.stack([jnp.zeros_like(f), f], -1)
    return f


def field_xy(field) -> Array:
    """A field (deg, θy or (θx, θy)) as (θx, θy) pairs in radians."""
    return jnp.deg2rad(_field_deg(field))


def field_direction(field) -> Float[Array, "*b 3"]:
    """Unit direction of a collimated beam at field (θx, θy) or θy (degrees); concrete
    angles that look like radians are warned about (``checks.warn_if_radian_fields``)."""
    checks.real_values(field, "field", "field_direction", "deg")
    checks.warn_if_radian_fields(field, "field_direction", "field")
    return _direction(field)


def _direction(field) -> Float[Array, "*b 3"]:
    """``field_direction`` without the radians warning (its callers warned)."""
    th = field_xy(field)
    v = jnp.concatenate([jnp.tan(th), jnp.ones_like(th[..., :1])], -1)
    return v / jnp.linalg.norm(v, axis=-1, keepdims=True)


def _checked_wavelength(lens: Lens, wavelength, where: str):
    """The rays' wavelength (µm; None: the lens's primary one), a concrete one checked
    against the lens's materials as the analyses check theirs: a table glass's lens at 1 µm
    gave rays that ``trace`` then refused from inside its jit (an EquinoxRuntimeError).
    Traced values pass unchecked (the entry points check theirs before tracing)."""
    if wavelength is not None:
        checks.real_values(wavelength, "wavelength", where, "µm")  # before jnp.asarray
    wl = lens.primary_wavelength if wavelength is None else jnp.asarray(wavelength)
    if not checks.is_traced(wl):
        checks.wavelengths(lens, wl, where)
        # A formula material of index 0.71 there launched rays a trace took as valid.
        checks.material_indices(lens, wl, where, intact=True)  # the callers check the lens
    return wl


def collimated(
    lens: Lens,
    field,
    pupil: Float[Array, "m 2"],
    wavelength=None,
    *,
    aim: str | None = None,
) -> Rays:
    """A collimated beam for an object at infinity, sampled over the entrance pupil.

    Args:
        lens: the lens (its EPD and paraxial entrance pupil are used).
        field: field angle in degrees, θy or (θx, θy).
        pupil: ``[m, 2]`` normalised pupil points.
        wavelength: µm (default: the lens's primary wavelength).
        aim: "paraxial", "real" (aim at the real stop, sized by the paraxial marginal ray)
            or "real_marginal" (sized by the real marginal ray; ``Lens.aim``); None (the
            default): the lens's own, ``lens.aim``.

    Returns:
        ``[m]`` rays launched on the entrance-pupil plane.

    The pupil points are used as given: the lens's vignetting factors are not applied here
    (``field_rays`` applies them for the lens's own fields). A concrete field that looks
    like radians (0.349 for 20°) is warned about, as by ``field_rays`` and the analyses.
    """
    checks.one_field(field, "collimated", "trace several fields one at a time, or vmap")
    checks.warn_if_radian_fields(field, "collimated", "field")
    return _collimated(lens, field, pupil, wavelength, aim=aim)


def _collimated(lens: Lens, field, pupil, wavelength=None, *, aim=None) -> Rays:
    """``collimated`` without the field's checks and radians warning (its callers made them)."""
    paraxial.finite_pupil(lens, "collimated")
    wl = _checked_wavelength(lens, wavelength, "collimated")
    pupil = pupil_points(pupil, "collimated")
    d = _direction(field)
    zep = paraxial.entrance_pupil_plane(lens, "collimated")
    h = 0.5 * lens.epd
    xy = pupil * h
    origin = jnp.concatenate([xy, jnp.broadcast_to(zep, xy.shape[:-1])[..., None]], -1)
    direction = jnp.broadcast_to(d, origin.shape).astype(origin.dtype)
    rays = Rays(origin, direction, wl)
    aim = lens_aim(lens, aim, "collimated")
    if aim != "paraxial":
        rays = aim_at_stop(lens, rays, pupil, stop_size=AIM_STOP_SIZE[aim])
    return rays


def point_source(
    lens: Lens,
    point: Float[Array, 3],
    pupil: Float[Array, "m 2"],
    wavelength=None,
    *,
    aim: str | None = None,
) -> Rays:
    """Rays from an object point (global mm, z < 0) through the paraxial entrance pupil, or
    toward a virtual one (z > 0: after surface 1, where the object-space beam converges).

    Each ray is the line through the point and its pupil point, travelling toward +z; its
    ``opl`` at the pupil is the path from the point, negative where the pupil comes first
    (the light has yet to reach the virtual point).

    The entrance pupil diameter is the lens's EPD. ``aim`` as for :func:`collimated` (None:
    the lens's own, ``lens.aim``). The rays are launched at their
    entrance-pupil points, with ``opl`` already holding the path from the object point.
    The pupil points are used as given: the lens's vignetting factors are not applied here
    (``field_rays`` applies them for the lens's own fields).
    """
    paraxial.finite_pupil(lens, "point_source")
    wl = _checked_wavelength(lens, wavelength, "point_source")
    pupil = pupil_points(pupil, "point_source")
    checks.real_values(point, "point", "point_source", "mm")
    # Checked before jnp.asarray, which makes a tracer of a constant under jit.
    concrete = not checks.is_traced(point)
    given = np.asarray(point, float) if concrete else point
    point = jnp.asarray(point)
    if point.shape[-1:] != (3,):
        raise ValueError(f"point_source: point must be (x, y, z) in mm, got shape {point.shape}")
    zep = paraxial.entrance_pupil_plane(lens, "point_source")
    if concrete:
        checks.values(given, "point", "point_source", unit="mm")
        # A real point behind the entrance pupil would launch its rays backwards, and a point
        # on the pupil's plane has no ray direction (the pupil's position is known only for
        # a concrete lens).
        if not checks.is_traced(zep) and np.any(_bad_point_z(given[..., 2],
                                                             np.asarray(zep), np)):
            raise ValueError(f"point_source: the point's z must be {POINT_Z_RANGE}, got "
                             f"{checks.fmt(given[..., 2])} mm (global z: surface 1 at 0, the "
                             f"entrance pupil at {checks.fmt(np.asarray(zep))})")
    else:  # traced: the same checks at run time (a point behind the lens launched rays back)
        point = eqx.error_if(
            point, ~jnp.all(jnp.isfinite(point)) | jnp.any(_bad_point_z(point[..., 2], zep, jnp)),
            f"point_source: point must be finite (mm) with its global z {POINT_Z_RANGE}")
    xy = pupil * (0.5 * lens.epd)
    target = jnp.concatenate([xy, jnp.broadcast_to(zep, xy.shape[:-1])[..., None]], -1)
    v = target - point
    # +1 where the pupil follows the point, -1 for a virtual point after the pupil.
    sense = jnp.sign(v[..., 2:])
    dist = sense * jnp.linalg.norm(v, axis=-1, keepdims=True)
    # Launch on the entrance-pupil plane (near the lens, so float32 keeps its digits for a
    # distant object); the optical path starts at the object point.
    n_obj = lens.object_material.index(wl)
    rays = Rays(target, v / dist, wl, opl=n_obj * dist[..., 0])
    aim = lens_aim(lens, aim, "point_source")
    if aim != "paraxial":
        rays = aim_at_stop(lens, rays, pupil, source_point=point, stop_size=AIM_STOP_SIZE[aim])
    return rays


POINT_Z_RANGE = ("in front of surface 1 and the entrance pupil (a real object), or after "
                 "surface 1 off the pupil's plane (a virtual object, on which the beam "
                 "converges)")
"""Where ``point_source``'s object point may be."""


def _bad_point_z(z, zep, xp):
    """True where an object point at global ``z`` (mm) cannot launch rays toward an entrance
    pupil at ``zep``: on surface 1's plane or the pupil's, or a real point behind the pupil."""
    return (z == 0) | (z == zep) | ((z < 0) & (z > zep))


def line_direction(frm, to):
    """The unit direction of the line from point ``frm`` to point ``to`` (``[..., 3]``, mm),
    turned to travel toward +z: rays in object space are whole lines, and a virtual object
    point lies after the pupil points its rays pass."""
    v = to - frm
    return jnp.sign(v[..., 2:]) * v / jnp.linalg.norm(v, axis=-1, keepdims=True)


AIM_STOP_SIZE = {"real": "paraxial", "real_marginal": "real"}
"""The ``stop_size`` of ``aim_at_stop`` for each aimed ``Lens.aim``."""


def lens_aim(lens: Lens, aim: str | None, where: str) -> str:
    """The ray aiming a sampler or an analysis uses: ``aim`` if given (one of
    ``RAY_AIMING``), else the lens's own (``Lens.aim``). Anything else is refused, naming ``where``
    (a typo such as "Real" aimed paraxially without a word)."""
    if aim is None:
        return lens.aim
    if not isinstance(aim, str) or aim not in RAY_AIMING:
        raise ValueError(f"{where}: aim must be one of {RAY_AIMING} or None (the lens's own, "
                         f"Lens.aim), got {type(aim).__name__} {aim!r}")
    return aim


def object_point(lens: Lens, field, depth) -> Array:
    """The object point (global mm) at a field angle (deg) and distance ``depth`` in front of
    surface 1 (mm; negative: a virtual object, that far after surface 1). The chief ray, the
    line through the point and the entrance pupil's centre, makes the angle θ with the axis:
    the point is at −tan θ·(z_ep − z) (below the axis for θ > 0 where the pupil follows the
    point, above it for a virtual object after the pupil)."""
    paraxial.finite_pupil(lens, "object_point")
    checks.one_field(field, "object_point", "trace several fields one at a time, or vmap")
    th = field_xy(field)
    # Checked before jnp.asarray, which traces a constant under jit. Beyond
    # INFINITE_OBJECT_MM the first surface is more than the tracer's largest ray parameter
    # away (every ray was lost: a PSF of zeros, an RMS of NaN).
    depth = check_object_distance(depth, "depth", "object_point")
    depth = jnp.asarray(depth)
    z = -depth
    zep = paraxial.entrance_pupil_plane(lens, "object_point")
    xy = jnp.tan(th) * (zep - z)
    return jnp.concatenate([-xy, z[..., None] * jnp.ones_like(xy[..., :1])], -1)


FIELD_MATCH_DEG = 1e-9
"""A field within this (degrees, in θx and θy) of one of the lens's fields is that field,
and gets its vignetting factors. The comparison is made in the lens's float type, with at
least 4 units in the last place of the angle as the tolerance (a float32 lens's 19.7° is
19.7° to float32's precision only, 1.9e-6 deg per unit in the last place)."""


def vignetting_map(factors, pupil) -> Float[Array, "*m 2"]:
    """Zemax's vignetted pupil: the normalised pupil points (Px, Py) ``[..., 2]`` mapped by
    the vignetting factors ``factors = (VDX, VDY, VCX, VCY, VAN)`` ``[5]`` of one field.

    First compression and decenter, ``Px' = VDX + Px·(1 − VCX)`` and
    ``Py' = VDY + Py·(1 − VCY)`` (VDX, VDY, VCX, VCY in pupil radii; OpticStudio's
    definition), then a rotation of (Px', Py') about the pupil centre by VAN degrees,
    counter-clockwise (from +x toward +y): ``Px'' = Px'·cos VAN − Py'·sin VAN``,
    ``Py'' = Px'·sin VAN + Py'·cos VAN``; zeros map every point to itself.

    The direction of the rotation (and that it follows the compression and decenter) is this
    library's convention, not a verified one: OpticStudio's own pages at hand (the help's
    "Vignetting", the knowledge-base "How to use vignetting factors", Zemax staff answers on
    its forum) say only that VAN ("TAN", the tangential angle, in newer versions) rotates
    the vignetted pupil's axes relative to object-space x, y, and give no formula or sign;
    optiland 0.6.3 reads VANN but ignores it (it applies VCX, VCY only), and no other open
    tracer found applies it against OpticStudio. So a file with VAN ≠ 0 is read with the
    counter-clockwise rotation stated here (tests/test_conventions_signs.py pins it: VCX =
    0.5 with VAN = 30° puts the pupil's short axis at +30°); check such a file's spot
    diagrams against OpticStudio before relying on them.

    >>> import jax.numpy as jnp
    >>> vignetting_map(jnp.array([0.0, 0.25, 0.0, 0.5, 0.0]), jnp.array([[0.0, 1.0]])).tolist()
    [[0.0, 0.75]]
    """
    v = jnp.asarray(factors)
    pupil = jnp.asarray(pupil)
    if v.shape != (5,):
        raise ValueError(f"vignetting_map: factors must be (VDX, VDY, VCX, VCY, VAN) of shape "
                         f"[5] (pupil radii, VAN in deg), got shape {v.shape}")
    if pupil.ndim < 1 or pupil.shape[-1] != 2:  # a [3] pupil was read as 1.5 points
        raise ValueError(f"vignetting_map: pupil must be normalised pupil points [..., 2] "
                         f"(Px, Py), got shape {pupil.shape}")
    if not checks.is_traced(v):
        # The Lens's own rule: a NaN factor mapped every pupil point to NaN (every ray of
        # the field lost); VCX = 1.5 turned the pupil over.
        check_vignetting(v, "vignetting_map", "factors")
    x = v[0] + pupil[..., 0] * (1.0 - v[2])
    y = v[1] + pupil[..., 1] * (1.0 - v[3])
    a = jnp.deg2rad(v[4])
    c, s = jnp.cos(a), jnp.sin(a)
    return jnp.stack([c * x - s * y, s * x + c * y], -1)


def field_vignetting(lens: Lens, field) -> Float[Array, " 5"]:
    """The vignetting factors (VDX, VDY, VCX, VCY, VAN) of ``field`` (deg, θy or (θx, θy)):
    the row of ``lens.vignetting`` of the lens's field equal to it (the first such, within
    ``FIELD_MATCH_DEG`` in θx and θy), else zeros (a field between the defined fields gets
    none: OpticStudio's rule for such fields was not verified, so none is guessed). Jittable:
    the field and the lens may be traced."""
    tele = lens.telecentric_object  # fields are object heights (mm)
    if not checks.is_traced(field):  # 100° or 3 angles matched no field: zeros, no word
        if tele:
            telecentric.one_height(field, "field_vignetting")
        else:
            checks.one_field(field, "field_vignetting", "one field's factors at a time")
    v = lens.vignetting
    if v is None:
        return jnp.zeros(5, lens.epd.dtype)
    n = lens.fields.shape[0]
    if v.shape != (n, 5):  # eqx.tree_at on the fields skips the Lens's checks
        raise ValueError(f"field_vignetting: the lens has {n} field(s) but vignetting factors "
                         f"of shape {v.shape}; replace Lens.vignetting ([{n}, 5], or None) "
                         f"with the fields")
    # Compared in degrees, in the lens's float type: a float64 field against a float32 lens's
    # own field (19.7 against float32(19.7), 7.6e-7 deg apart) matched none, and the
    # radian round trip moved float32 angles by an ulp or two.
    pairs = (lambda f: telecentric.height_xy(f, "field_vignetting")) if tele else _field_deg
    defined = pairs(lens.fields)  # [F, 2]
    given = pairs(field).reshape(1, 2).astype(defined.dtype)
    ulp = 4 * jnp.finfo(defined.dtype).eps * jnp.abs(defined)
    tol = jnp.maximum(FIELD_MATCH_DEG, ulp)
    match = jnp.all(jnp.abs(defined - given) <= tol, -1)  # [F]
    row = v[jnp.argmax(match)]
    return jnp.where(jnp.any(match), row, jnp.zeros_like(row))


def vignetting_for_fields(lens: Lens, fields) -> Array | None:
    """The ``Lens.vignetting`` rows for other ``fields`` (deg, ``[F]`` θy or ``[F, 2]``):
    the factors of each field that equals one of the lens's fields, zeros for a new one;
    None for a lens without factors. For replacing a lens's fields (``eqx.tree_at`` on
    ``fields`` alone leaves stale rows, which ``field_rays`` refuses)."""
    if lens.vignetting is None:
        return None
    checks.real_values(fields, "fields", "vignetting_for_fields", "deg")
    f = jnp.asarray(fields)
    if f.ndim not in (1, 2) or (f.ndim == 2 and f.shape[1] != 2) or f.size == 0:
        raise ValueError(f"vignetting_for_fields: fields must be [F] angles θy or [F, 2] "
                         f"pairs (θx, θy) in deg, F >= 1, got shape {f.shape}")
    if not checks.is_traced(f):  # a NaN or 95° field failed inside vmap (EquinoxRuntimeError)
        telecentric.lens_fields(lens, f, "vignetting_for_fields")  # heights (mm) or angles
    return jax.vmap(lambda g: field_vignetting(lens, g))(f)


def field_rays(lens: Lens, field, pupil, wavelength=None, *, depth=None, aim=None) -> Rays:
    """Rays for a field angle at infinity (``depth=None``, inf, or ``INFINITE_OBJECT_MM`` =
    1e10 mm and more, as for ``Lens.object_distance``) or from a finite depth (one number,
    mm to surface 1; < 0: a virtual object that far after surface 1, as a Lens's own
    ``object_distance`` may be; the analyses' ``depth`` must be > 0).

    The chief ray of a finite-depth field point makes the angle θ with the axis at the
    entrance pupil, as for an object at infinity. ``aim``: "paraxial", "real",
    "real_marginal" or None (the default: the lens's own, ``lens.aim``), as for
    :func:`collimated`.

    Where the lens has vignetting factors and ``field`` is one of its fields (within
    ``FIELD_MATCH_DEG``), the ray of pupil point (Px, Py) is the ray of
    ``vignetting_map(factors, (Px, Py))``, launched (and, with ``aim="real"``, aimed at
    the stop) there, as OpticStudio traces it; other fields sample the pupil unchanged.
    The vignetted pupil is the image of the unit disc: for a field with nonzero factors a
    pupil point outside the unit disc (an overfilled beam, as the PSF's ``overfill``)
    launches an invalid ray (``valid`` False), so the factors, not the stop, bound the
    beam. Factors that map points beyond the unit disc (a negative compression VCX, VCY,
    which expands the pupil, or a decenter) launch those rays as given; the lens's
    apertures clip them.
    """
    if depth is not None:
        checks.real_values(depth, "depth", "field_rays", "mm")
        if jnp.ndim(depth) != 0:  # [2] failed in jnp.concatenate, naming no argument
            raise ValueError(f"field_rays: depth must be one distance (mm), got shape "
                             f"{jnp.shape(depth)}; trace several depths one at a time, or "
                             f"vmap")
    field = telecentric.lens_field(lens, field, "field_rays",  # heights (mm) or angles
                                   "trace several fields one at a time, or vmap")
    aim = lens_aim(lens, aim, "field_rays")
    if lens.telecentric_object and aim != "paraxial":
        raise ValueError(f"field_rays: the lens is object-space telecentric (its chief rays "
                         f"leave parallel to the axis): ray aiming does not apply, so aim "
                         f"must be 'paraxial' or None, got {aim!r}")
    wavelength = _checked_wavelength(lens, wavelength, "field_rays")
    beyond = None
    if lens.vignetting is not None:
        pupil = pupil_points(pupil, "field_rays")
        factors = field_vignetting(lens, field)
        # The vignetted pupil is the image of the unit disc: a point of an overfilled beam
        # (a PSF's 1.25) mapped inside it passed the stop, light OpticStudio never traces
        # (a "pupil"-normalised PSF held 1.44 of the pupil's energy).
        outside = jnp.sum(pupil * pupil, -1) > (1.0 + UNIT_DISC_TOLERANCE) ** 2
        beyond = outside & jnp.any(factors != 0)
        pupil = vignetting_map(factors, pupil)
    if lens.telecentric_object:
        pupil = pupil_points(pupil, "field_rays")
        rays = telecentric.source(lens, field, pupil, wavelength, depth)
    elif depth is None or (not isinstance(depth, jax.core.Tracer)
                           and np.all(np.asarray(depth) >= INFINITE_OBJECT_MM)):
        rays = _collimated(lens, field, pupil, wavelength, aim=aim)
    else:  # named here: depth 0 or NaN was refused as object_point's
        depth = check_object_distance(depth, "depth", "field_rays")
        rays = point_source(lens, object_point(lens, field, depth), pupil, wavelength, aim=aim)
    if beyond is not None:
        rays = eqx.tree_at(lambda r: r.valid, rays, rays.valid & ~beyond)
    return rays


AIM_TOLERANCE = {True: 1e-6, False: 1e-3}
"""How far (relative to the stop radius, mm) an aimed ray may cross the stop from its aim
point and stay valid, in float64 (True) and float32 (False)."""

AIM_ITERS = 20
"""``aim_at_stop``'s most Newton iterations per ray. Each ray stops as soon as it crosses
the stop within ``AIM_CONVERGED`` of its point, so the limit costs only where a ray needs
it. Measured with a 6-ring hexapolar pupil (127 rays), counting the rays within
``AIM_TOLERANCE``: the double Gauss at 14° needs 1 iteration (and the implicit step),
Laikin's wide-angle lens at 50° 5 (47 rays after 3, 126 after 4)."""

AIM_CONVERGED = {True: 1e-12, False: 1e-5}
"""The Newton iterations of ``aim_at_stop`` stop at a ray that crosses the stop this close
to its point (relative to max(stop radius, 1 mm)), float64 (True) and float32 (False); one
more Newton step then follows (the implicit-gradient step of ``newton.newton_2d``)."""

AIM_HALVINGS = 8
"""Backtracking in ``aim_at_stop``: a Newton step that does not bring the ray closer to its
stop point, or that loses the ray (it misses a surface or is totally reflected), is halved
up to this many times."""

STOP_SIZES = ("paraxial", "real")
"""``aim_at_stop``'s ``stop_size``: the stop radius that the pupil coordinates are
fractions of, from the paraxial marginal ray or from the real one (``stop_radius``)."""


def stop_radius(lens: Lens, stop_size: str = "paraxial", *, object_z=None) -> Float[Array, ""]:
    """The stop radius (mm) that aimed rays fill: the height at the stop of the on-axis
    marginal ray at the primary wavelength.

    ``stop_size="paraxial"``: the paraxial marginal ray's (``paraxial_data``'s
    ``stop_semi_diameter``; Zemax's "Paraxial" ray aiming). ``"real"``: the real ray from the
    on-axis object point through the rim of the paraxial entrance pupil, (0, EPD/2) on its
    plane (parallel to the axis for an object at infinity; from (0, 0, ``object_z``), mm
    global, for a finite one), traced without apertures to the stop: its distance from the
    stop's axis there (Zemax's "Real" ray aiming). A marginal ray that misses a surface or
    is totally reflected on the way is a ``ValueError`` naming the surface (was NaN, and
    every ray aimed with it invalid, without a word); traced (jit), NaN.
    """
    from ..tracing.forward import trace_path

    if stop_size not in STOP_SIZES:
        raise ValueError(f"stop_radius: stop_size must be one of {STOP_SIZES}, got "
                         f"{type(stop_size).__name__} {stop_size!r}")
    checks.primary_wavelength(lens, "stop_radius")  # was refused by paraxial_data
    if stop_size == "paraxial":
        return paraxial.paraxial_data(lens).stop_semi_diameter
    dt = lens.epd.dtype
    zep = paraxial.entrance_pupil_z(lens, lens.primary_wavelength)
    if object_z is not None and not checks.is_traced(object_z) and not checks.is_traced(zep):
        # NaN failed in Rays (a direction of length NaN), 0 gave a radius (3.83 mm)
        z = np.asarray(checks.values(object_z, "object_z", "stop_radius", unit="mm"), float)
        if np.any(_bad_point_z(z, np.asarray(zep), np)):
            raise ValueError(f"stop_radius: object_z must be {POINT_Z_RANGE}, got "
                             f"{checks.fmt(z)} mm (the entrance pupil at "
                             f"{checks.fmt(np.asarray(zep))})")
    rim = jnp.stack([jnp.zeros((), dt), 0.5 * lens.epd, zep.astype(dt)])
    if object_z is None:
        d = jnp.array([0.0, 0.0, 1.0], dt)
    else:
        d = line_direction(jnp.stack([jnp.zeros((), dt), jnp.zeros((), dt),
                                      jnp.asarray(object_z, dt)]), rim)
    path = trace_path(unclipped(lens), Rays(rim[None], d[None], lens.primary_wavelength),
                      upto=lens.stop, uniform=True)
    out = path[-1]
    if not checks.is_traced((lens, object_z)) and not bool(out.valid[0]):  # was NaN
        z = "" if object_z is None else f" from (0, 0, {checks.fmt(np.asarray(object_z))}) mm"
        raise ValueError(f"stop_radius: the real marginal ray{z} through the entrance pupil's "
                         f"rim misses surface {1 + int(np.argmin(path.valid[:, 0]))} or is "
                         f"totally reflected there: no real ray sizes the stop for this "
                         f"object; use stop_size='paraxial' (Lens.aim='real')")
    xy = out.origin[0, :2]
    r2 = jnp.sum(xy * xy)
    r = jnp.sqrt(jnp.where(r2 > 0, r2, 1.0))  # double where: no NaN gradient on the axis
    return jnp.where(out.valid[0], jnp.where(r2 > 0, r, 0.0), jnp.nan)


def aim_at_stop(
    lens: Lens,
    rays: Rays,
    pupil: Float[Array, "m 2"],
    *,
    source_point: Float[Array, 3] | None = None,
    iters: int = AIM_ITERS,
    stop_size: str = "paraxial",
) -> Rays:
    """Move launch points so that each ray crosses the real stop at pupil·(stop radius).

    Newton's method (``newton.newton_2d``) on the 2D launch point in the entrance-pupil
    plane, with the Jacobian from forward-mode autodiff of a partial trace to the stop and
    the implicit-function gradient (reverse mode never unrolls the iterations). A collimated
    beam keeps its direction; rays from ``source_point`` (a finite object) are re-aimed
    from that point. The stop radius is ``stop_radius(lens, stop_size)``: ``"paraxial"``
    (Zemax's "Paraxial" ray aiming, ``Lens.aim="real"``) or ``"real"`` (Zemax's "Real",
    ``Lens.aim="real_marginal"``).

    Each ray iterates until it crosses the stop within ``AIM_CONVERGED`` of its point, at
    most ``iters`` times. A step is at most the entrance pupil's diameter long, and a step
    that does not bring the ray closer, or that loses it (a missed surface, total internal
    reflection), is halved (up to ``AIM_HALVINGS`` times): undamped, the iterates of a
    strongly aberrated pupil or a wide field jump where no ray passes and never come back.

    The aiming traces the lens without its apertures (``optics.lens.unclipped``): an aperture
    that clips a Newton iterate stops that ray where it was clipped, which leaves the
    iterate short of the stop point, and the real trace may then pass the wrong ray. Which
    of the aimed rays the apertures stop is for the caller's trace of the real lens.
    The pupil points are aimed at as given (the lens's vignetting factors are applied
    before, by ``field_rays``). A ray that the iterations leave farther from its stop
    point than ``AIM_TOLERANCE`` × max(stop radius, 1 mm) (a point no ray reaches, a pupil
    too aberrated for ``iters``) is returned invalid (``valid`` False), as is a ray given
    invalid, and all of them where the real marginal ray that sizes the stop is lost.
    """
    from ..tracing.forward import trace_path

    checks.number(iters, "iters", "aim_at_stop", lo=0, integer=True, unit="Newton iterations")
    if not isinstance(stop_size, str) or stop_size not in STOP_SIZES:
        raise ValueError(f"aim_at_stop: stop_size must be one of {STOP_SIZES}, got "
                         f"{type(stop_size).__name__} {stop_size!r}")
    pupil = pupil_points(pupil, "aim_at_stop")
    if pupil.shape[:-1] != rays.shape:
        raise ValueError(f"aim_at_stop: pupil needs one point per ray: rays of shape "
                         f"{rays.shape} need pupil of shape {rays.shape + (2,)}, got "
                         f"{pupil.shape}")
    object_z = None if source_point is None else jnp.asarray(source_point)[..., 2]
    par = paraxial.paraxial_data(lens).stop_semi_diameter
    stop_r = par if stop_size == "paraxial" else stop_radius(lens, stop_size, object_z=object_z)
    sized = jnp.isfinite(stop_r)
    stop_r = jnp.where(sized, stop_r, par)
    target = pupil * stop_r
    zep = paraxial.entrance_pupil_z(lens)
    n_obj = lens.object_material.index(rays.wavelength)
    free = unclipped(lens)
    f64 = jnp.dtype(target.dtype).itemsize >= 8
    scale = jnp.maximum(stop_r, 1.0)

    def launch(uv, d):
        p = jnp.stack([uv[0], uv[1], zep])
        if source_point is None:
            return p, d
        return p, line_direction(source_point, p)

    def at_stop(uv, d, w, lens_=free):
        o2, d2 = launch(uv, d)
        r = trace_path(lens_, Rays(o2[None], d2[None], w), upto=lens.stop, uniform=True)[-1]
        return r.origin[0, :2], r.valid[0]

    def solve(uv0, d, tgt, w):
        def residual(uv, params):
            lens_, d_, tgt_, w_ = params
            xy, ok = at_stop(uv, d_, w_, lens_)
            return xy - tgt_, ok

        return newton_2d(residual, uv0, (free, d, tgt, w), iters, has_valid=True,
                         tol=AIM_CONVERGED[f64] * scale, max_step=lens.epd,
                         halvings=AIM_HALVINGS)

    # Start from each ray's crossing of the entrance-pupil plane.
    start = rays.propagate_to_z(zep).origin[..., :2]
    w = jnp.broadcast_to(rays.wavelength, rays.shape)
    uv = jax.vmap(solve)(start, rays.direction, target, w)
    o, d = jax.vmap(launch)(uv, rays.direction)
    opl = None
    if source_point is not None:
        # Negative where the pupil comes before a virtual point (as point_source's).
        opl = n_obj * jnp.sign(o[..., 2] - source_point[..., 2]) * jnp.linalg.norm(
            o - source_point, axis=-1)
    # A ray that Newton's method did not bring to its stop point (a stop point no ray
    # reaches, a pupil too aberrated for the iterations) is invalid: it was launched as
    # valid, crossing the stop far from where it was aimed, without a word.
    xy, ok = jax.vmap(at_stop)(uv, rays.direction, w)
    tol = AIM_TOLERANCE[f64] * scale
    hit = ok & jnp.all(jnp.abs(xy - target) <= tol, axis=-1) & sized
    return Rays(o, d, rays.wavelength, opl=opl, valid=rays.valid & hit)


def lens_depth(lens: Lens, depth, where: str):
    """The object distance an imaging or analysis function traces from: ``depth`` (mm from
    the object to surface 1; inf, or 1e10 and more, for an object at infinity, as a Lens's
    ``object_distance``) or, for None, the lens's own
    object (``lens.object_distance``). Checked, with errors naming ``where``. Returns None
    for an object at infinity, else an array of the lens's dtype, so that compiled programs
    take it as an argument (one program serves every depth)."""
    own = depth is None and not lens.object_at_infinity
    paraxial.check_launchable(lens, where)  # its beams start on the entrance pupil's plane
    if own:
        depth = lens.object_distance  # negative for a virtual object
        if not checks.is_traced((lens, depth)) and float(depth) < 0:  # traced: an error_if
            zep = float(paraxial.entrance_pupil_z(lens, lens.primary_wavelength))
            if _bad_point_z(-float(depth), zep, np):  # was an error_if after the whole trace
                raise ValueError(f"{where}: the lens's object must be {POINT_Z_RANGE}; its "
                                 f"object_distance {float(depth):g} mm puts it on the entrance "
                                 f"pupil's plane (z = {zep:g} mm)")
    given = static_depth(depth, where, virtual_ok=own)
    if given is None or isinstance(given, jax.core.Tracer):
        return given
    return given.astype(lens.epd.dtype)


def static_depth(depth, where: str = "sampling", *, virtual_ok: bool = False):
    """None for an object at infinity (a concrete inf), else the depth as an array (checked,
    errors naming ``where``). A depth given to an analysis is > 0 (a negative one is far
    likelier a slip of sign than a virtual object); ``virtual_ok`` also takes a negative one,
    a virtual object after surface 1, as a Lens's own ``object_distance`` may be."""
    if depth is None:
        return None
    if isinstance(depth, jax.core.Tracer):
        # Traced (a depth that a jitted function passes on): its value is unknown here, so
        # it cannot pick the collimated beam of an object at infinity; an infinite depth made
        # every ray NaN, and a negative one traced an object behind the lens, silently.
        if checks.checked_by_caller(depth):
            return depth
        if virtual_ok:
            return check_object_distance(depth, "depth", where)
        return eqx.error_if(
            depth, ~(jnp.isfinite(depth) & (depth > 0) & (depth < INFINITE_OBJECT_MM)),
            f"{where}: a traced depth must be finite and in (0, inf) mm from the object to "
            f"surface 1, below {INFINITE_OBJECT_MM:g} mm (farther is an object at infinity); "
            f"for an object at infinity pass inf or None outside the traced arguments")
    checks.real_values(depth, "depth", where, "mm")
    given = np.asarray(depth)
    # At or beyond INFINITE_OBJECT_MM (and inf) the object is at infinity, as a Lens's
    # object_distance is: traced from there, every ray was lost (a PSF of zeros at 1e12 mm,
    # an RMS of NaN at 1e300 mm, and in float32 already at 1e30 mm).
    if given.dtype.kind in "iuf" and np.all(given >= INFINITE_OBJECT_MM):
        return None
    if virtual_ok:
        return jnp.asarray(check_object_distance(depth, "depth", where))
    checks.values(depth, "depth", where, lo=0, lo_open=True,
                  unit="mm from the object to surface 1 (inf: an object at infinity)")
    checks.values(depth, "depth", where, lo=0, lo_open=True, hi=INFINITE_OBJECT_MM, hi_open=True,
                  unit=f"mm from the object to surface 1 (inf, or all of them "
                  f"{INFINITE_OBJECT_MM:g} and more: an object at infinity)")
    return jnp.asarray(depth)
