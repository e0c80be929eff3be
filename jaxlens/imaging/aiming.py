"""Chief-ray aiming and the ideal (distortion-free) image mapping.

``stop_chief_ray`` aims the real chief ray at the centre of the stop with the library's one
2-D Newton solver (``newton.newton_2d``, implicit gradient; re-exported here as
``newton_2d``); ``image_scale``/``field_to_ideal``/``ideal_to_field`` map field angles
(degrees) to distortion-free sensor points ``K·tanθ`` (mm) and back, and the object heights
(mm) of an object-space telecentric lens to ``m·h`` (m its paraxial magnification).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks, paraxial
from ..optics.lens import Lens, Sensor, check_object_distance, unclipped
from ..optics.rays import Rays
from ..tracing.forward import DEFAULT_NEWTON_ITERS, forward_mode_jit, trace
from . import sampling
from .newton import newton_2d as newton_2d


def image_scale(lens: Lens, wavelength=None) -> Float[Array, ""]:
    """K: the scale of the distortion-free image, ideal image point per unit field coordinate.

    For field angles (degrees) K is in mm per unit tanθ: the distortion-free image of the
    field (θx, θy) lies at ``K·(tanθx, tanθy)``; for a lens focused at infinity K is the
    focal length. The paraxial chief ray is linear in tanθ, so one ray at 45° gives K.

    For an object-space telecentric lens (``Lens.object_na``; fields are object heights in
    mm) K is the paraxial magnification m = ``paraxial.magnification(lens)`` (image mm per
    object mm, no unit; m < 0 for an inverted image): the distortion-free image of the object
    point (x, y) lies at ``m·(x, y)``, whatever the object distance a render or analysis
    traces from (the lens's own conjugates set it, as its focal length does for angles).

    Raises:
        ValueError: for a lens with an afocal image space (no image surface positions), and
            for a telecentric lens whose m is not finite and nonzero (its image at infinity).
    """
    return _image_scale(lens, wavelength, "image_scale")


def _image_scale(lens: Lens, wavelength, where: str):
    """``image_scale`` with the name of the function the user called in its messages."""
    checks.focal_image(lens, where)
    if wavelength is None:  # was refused by image_height, a function the user never called
        checks.primary_wavelength(lens, where)
    if lens.telecentric_object:
        m = paraxial.magnification(lens, wavelength)
        if not checks.is_traced(m) and not (np.isfinite(float(m)) and float(m) != 0.0):
            raise ValueError(
                f"{where}: the paraxial magnification of this object-space telecentric "
                f"lens is {float(m):g} (image mm per object mm; it must be finite and "
                f"nonzero): its image of the object {float(lens.object_distance):g} mm before "
                f"surface 1 lies at infinity, so object heights have no image positions")
        return m
    return paraxial.image_height(lens, 45.0, wavelength) / jnp.tan(jnp.deg2rad(45.0))


def field_coordinates(lens: Lens, field) -> Float[Array, "*b 2"]:
    """The field coordinates that ``image_scale`` multiplies: (tanθx, tanθy) of field angles
    (degrees, θy or (θx, θy)), or the object point (x, y) in mm of an object-space
    telecentric lens's object heights (y or (x, y))."""
    if lens.telecentric_object:
        return sampling.telecentric.height_xy(field, "field_to_ideal")
    return jnp.tan(sampling.field_xy(field))


def field_to_ideal(lens: Lens, field, wavelength=None) -> Float[Array, "*b 2"]:
    """Distortion-free image position (mm) of a field: ``K·tanθ`` for angles (degrees, θy or
    (θx, θy)), ``m·(x, y)`` for the object heights (mm) of an object-space telecentric lens
    (``image_scale``)."""
    return _image_scale(lens, wavelength, "field_to_ideal") * field_coordinates(lens, field)


def ideal_to_field(lens: Lens, xy, wavelength=None) -> Float[Array, "*b 2"]:
    """Field whose distortion-free image lies at ``xy`` (mm): (θx, θy) in degrees, or the
    object point (x, y) in mm of an object-space telecentric lens (``xy / m``)."""
    t = jnp.asarray(xy) / _image_scale(lens, wavelength, "ideal_to_field")
    return t if lens.telecentric_object else jnp.rad2deg(jnp.arctan(t))


def scene_extent(lens: Lens, sensor=None) -> tuple[float, float]:
    """The half-width and half-height of the scene that ``render`` shows on ``sensor``
    (default ``lens.sensor``), in the lens's field unit: the fields whose distortion-free
    images lie at the sensor's edges (half its width and height from the centre).

    For field angles: degrees, atan(half side / K) (the half field of view). For an
    object-space telecentric lens: mm on the object plane, half side / |m| (the object
    heights a scene spans; Zemax's image simulation asks for this as the source's field
    height). The scene fills the sensor so; to show a smaller object, pad the scene.

    Raises:
        ValueError: for a missing sensor, a lens with an afocal image space, or a
            telecentric lens whose image lies at infinity (``image_scale``).
    """
    sensor = lens.sensor if sensor is None else sensor
    if not isinstance(sensor, Sensor):
        raise ValueError(f"scene_extent: sensor must be a jaxlens.Sensor (the lens has none: "
                         f"pass sensor=jaxlens.Sensor(resolution, pixel_size in mm)), got "
                         f"{sensor!r}")
    rows, cols = sensor.resolution
    half = 0.5 * float(sensor.pixel_size) * np.array([cols, rows], float)  # mm
    k = abs(float(image_scale(lens)))
    if lens.telecentric_object:
        return float(half[0] / k), float(half[1] / k)
    deg = np.rad2deg(np.arctan(half / k))
    return float(deg[0]), float(deg[1])


def stop_chief_ray(lens: Lens, field, depth=None, wavelength=None, *,
                   newton_iters: int = DEFAULT_NEWTON_ITERS,
                   iters: int = sampling.AIM_ITERS) -> Rays:
    """The real chief ray of a field: aimed by Newton's method at the centre of the stop (of
    an object-space telecentric lens, ``Lens.object_na``: the ray from the object point at
    height ``field`` (mm) parallel to the axis, not aimed).

    Args:
        lens: the lens.
        field: degrees, θy or (θx, θy).
        depth: None for infinity, else the object distance in mm.
        wavelength: µm (default primary).
        newton_iters: Newton iterations for aspheric surfaces.
        iters: the most aiming iterations.

    Returns:
        One ray (shape ``[1]``) in object space, launched from the entrance-pupil plane
        (infinity) or from the object point. Its ``valid`` reports the aim: False where the
        iterations did not bring the ray to the stop centre, i.e. where the aimed ray misses a
        surface before the stop or crosses the stop more than ``sampling.AIM_TOLERANCE``
        (relative to max(paraxial stop radius, 1 mm); 1e-6 in float64, 1e-3 in float32) from
        its centre, as ``sampling.aim_at_stop`` marks its rays. The ray is still the last
        aim (a trace of it as invalid stops at once; ``chief_point`` traces it through and
        reports the aim in its validity).

    The aiming is ``sampling.aim_at_stop``'s (``newton.newton_2d``): from the paraxial
    entrance pupil's centre, it iterates until the ray crosses the stop within
    ``sampling.AIM_CONVERGED`` (relative to max(paraxial stop radius, 1 mm)) of its centre, at
    most ``iters`` times, with steps at most the EPD long and halved (up to
    ``sampling.AIM_HALVINGS`` times) where they do not bring the ray closer or lose it; then one
    more Newton step, which carries the implicit-function gradient (with respect to the lens,
    the field, the object distance and the wavelength: the iterations carry none). Whether it
    converged is then checked by one more trace to the stop (no gradient) and reported in the
    ray's ``valid`` (see Returns). The lens's vignetting factors do not move it: it passes
    through the
    centre of the stop whatever they are. The ray that ``sampling.field_rays`` launches at
    pupil point (0, 0) of a vignetted field is the centre of the vignetted pupil, (VDX, VDY)
    rotated by VAN.
    """
    checks.number(iters, "iters", "stop_chief_ray", lo=0, integer=True,
                  unit="aiming iterations")  # -1 ran no iteration without a word
    _check_chief_args(lens, field, depth, wavelength, newton_iters)
    field, depth, wavelength = (_array(v) for v in (field, depth, wavelength))
    return _stop_chief_ray(lens, field, depth, wavelength, newton_iters=newton_iters,
                           iters=iters)


def _array(v):
    """A Python number or list as an array (None, arrays and tracers as they are): the
    compiled cores below keep a Python number static, one program per value."""
    if v is None or isinstance(v, (jax.Array, np.ndarray)) or checks.is_traced(v):
        return v
    return jnp.asarray(v)


def _check_chief_args(lens, field, depth, wavelength, newton_iters) -> None:
    """The arguments of ``stop_chief_ray``/``chief_point``, concrete ones checked before the
    compiled core (inside it they are traced, and the checks would be skipped or become
    ``EquinoxRuntimeError``s after the trace): the lens (type and its own checks), the field
    (deg), the object distance (mm), the wavelength (µm) against the lens's materials and
    ``newton_iters``."""
    where = "stop_chief_ray"
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    checks.newton_iters(newton_iters, where)
    checks.lens_intact(lens, where)
    if lens.telecentric_object:  # the field is an object height (mm)
        if not checks.is_traced(field):
            sampling.telecentric.one_height(field, where)
    elif not checks.is_traced(field):
        checks.real_values(field, "field", where, "deg")  # before np.asarray
        checks.field_angles(np.asarray(field), where, "field")
        if depth is not None:
            checks.one_field(field, where, "aim several fields one at a time, or vmap")
    if depth is not None and not checks.is_traced(depth):
        check_object_distance(depth, "depth", where)
    wl = lens.primary_wavelength if wavelength is None else wavelength
    if not checks.is_traced(wl):
        checks.real_values(wl, "wavelength", where, "µm")
        checks.wavelengths(lens, np.asarray(wl), where)


@checks.checked_core(forward_mode_jit)
def _stop_chief_ray(lens, field, depth, wavelength, *, newton_iters, iters) -> Rays:
    """``stop_chief_ray``'s compiled core: a module-level function of the lens and arrays
    (the sizes static), so that eager calls on lenses of one structure share one program."""
    wl = lens.primary_wavelength if wavelength is None else jnp.asarray(wavelength)
    if lens.telecentric_object:  # the ray parallel to the axis: nothing to aim
        return sampling.telecentric.source(lens, field, jnp.zeros((1, 2), lens.epd.dtype),
                                           wl, depth)
    zep = paraxial.entrance_pupil_z(lens)
    if depth is None:
        start = sampling.field_direction(field).astype(lens.epd.dtype)
    else:
        start = sampling.object_point(lens, field, depth)
    collimated = depth is None

    def launch(uv, zep, start, wl):
        # ``start``: the beam's direction (infinity) or the object point.
        q = jnp.concatenate([uv, zep[None]])
        if collimated:
            return Rays(q[None], start[None], wl)
        # Toward +z, also for a virtual object point after the pupil.
        return Rays(start[None], sampling.line_direction(start, q)[None], wl)

    @checks.inherit  # newton_2d's loop bodies are made on each call
    def at_stop(uv, params):
        aim_lens, zep, start, wl = params
        out = trace(aim_lens, launch(uv, zep, start, wl), newton_iters=newton_iters,
                    upto=lens.stop, uniform=True)
        return out.origin[0, :2], out.valid[0]

    f64 = jnp.dtype(lens.epd.dtype).itemsize >= 8
    stop_r = jax.lax.stop_gradient(paraxial.paraxial_data(lens).stop_semi_diameter)
    scale = jnp.where(jnp.isfinite(stop_r), jnp.maximum(stop_r, 1.0), 1.0)
    # Everything the ray depends on is a parameter, so the gradient is the implicit one.
    params = (unclipped(lens), zep, start, wl)
    uv = newton_2d(at_stop, jnp.zeros(2, lens.epd.dtype), params, iters, has_valid=True,
                   tol=sampling.AIM_CONVERGED[f64] * scale, max_step=lens.epd,
                   halvings=sampling.AIM_HALVINGS)
    # An aim that the iterations did not bring to the stop centre is reported, not returned
    # as valid (the check carries no gradient: validity has none).
    xy, passes = at_stop(jax.lax.stop_gradient(uv), jax.lax.stop_gradient(params))
    aimed = passes & jnp.all(jnp.abs(xy) <= sampling.AIM_TOLERANCE[f64] * scale)
    rays = launch(uv, zep, start, wl)
    return eqx.tree_at(lambda r: r.valid, rays, rays.valid & aimed)


def chief_point(lens, field, depth, newton_iters, *, with_valid: bool = False,
                with_ray: bool = False):
    """Image-surface (x, y) of the real chief ray (through the stop centre), primary λ.

    A reference point, so it is traced without clipping or obscurations: a blocked chief
    ray (a Cassegrain's, behind its secondary) would otherwise stop where it was blocked.
    With ``with_valid``, ``(xy, valid)``: a chief ray that misses a surface or is totally
    reflected stops where it failed, and ``valid`` is False; so is it where the aim at the
    stop centre did not converge (``stop_chief_ray``; the point is then that of the last aim,
    traced through). With ``with_ray``, the aimed ray (``stop_chief_ray``'s) comes last as
    well, so that a caller can trace it through another lens (the clipped one) without
    aiming it again."""
    _check_chief_args(lens, field, depth, None, newton_iters)
    return _chief_point(lens, _array(field), _array(depth), newton_iters=newton_iters,
                        with_valid=with_valid, with_ray=with_ray)


@checks.checked_core(forward_mode_jit)
def _chief_point(lens, field, depth, *, newton_iters, with_valid, with_ray=False):
    rays = _stop_chief_ray(lens, field, depth, None, newton_iters=newton_iters,
                           iters=sampling.AIM_ITERS)
    aimed = rays.valid[0]
    through = eqx.tree_at(lambda r: r.valid, rays, jnp.ones_like(rays.valid))
    out = trace(unclipped(lens), through, newton_iters=newton_iters, uniform=True)
    point = (out.origin[0, :2], out.valid[0] & aimed) if with_valid else (out.origin[0, :2],)
    point = point + ((rays,) if with_ray else ())
    return point if len(point) > 1 else point[0]
