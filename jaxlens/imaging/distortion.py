"""Distortion relaxation: let the network, not the lens, undo distortion.

Yang, Fu and Heidrich (Nat. Commun. 2024, Methods) relax the distortion requirement of the
lens: distortion moves image points without blurring them, so it costs no information and
can be corrected after capture. Instead of penalising it through the image loss, the
object is pre-warped by the lens's own distortion, so that the simulated image lines up
with the undistorted scene, and an optional alignment penalty with weight α keeps the
distortion from growing without bound.

Conventions:
    Sensor positions in mm on the image surface, in the frame of ``render``: the ideal
    (distortion-free) image of the field (θx, θy) is ``K·(tanθx, tanθy)`` with
    ``K = aiming.image_scale(lens)`` (of an object-space telecentric lens's object point
    (x, y), in mm, ``m·(x, y)``, m its paraxial magnification). The distortion map D sends
    an ideal position v to the position where the real chief ray (through the centre of
    the stop, primary wavelength) of that field lands. Grids span the sensor corner to corner
    (``grid.sensor_grid``: row 0 / column 0 is the top-left pixel of the rendered image).

Pre-warp:
    A scene is shown at ideal positions. The simulated image at u shows the object whose
    real image is u, the object at D⁻¹(u). Rendering the pre-warped object
    ``scene'(v) = scene(D(v))`` therefore shows ``scene(u)`` at u: the distortion is gone
    from the simulated image (blur and vignetting remain).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks, paraxial
from ..optics.lens import Lens, Sensor, unclipped
from ..optics.rays import Rays
from ..tracing.backward import trace_backward
from ..tracing.forward import DEFAULT_NEWTON_ITERS
from . import sampling
from .aiming import chief_point, ideal_to_field, image_scale, newton_2d
from .grid import bilinear, grid_coords, pixel_pitch, sensor_grid

__all__ = [
    "DistortionMap",
    "distortion_map",
    "inverse_distortion_map",
    "prewarp",
    "alignment_penalty",
]


class DistortionMap(eqx.Module):
    """Ideal and real chief-ray image positions on a grid (mm), ``[gr, gc, 2]`` each."""

    ideal: Float[Array, "gr gc 2"]
    real: Float[Array, "gr gc 2"]


def _sensor(lens: Lens, sensor, where: str):
    sensor = lens.sensor if sensor is None else sensor
    if sensor is None:
        raise ValueError(f"{where}: the lens has no sensor; pass sensor=Sensor(...)")
    if not isinstance(sensor, Sensor):
        raise TypeError(f"{where}: sensor must be a jaxlens.Sensor, got "
                        f"{type(sensor).__name__} {sensor!r}")
    return sensor


@checks.checked_core(eqx.filter_jit)
def _forward_map(lens, ideal, depth, newton_iters):
    fields = ideal_to_field(lens, ideal.reshape(-1, 2))
    real, valid = jax.vmap(lambda f: chief_point(lens, f, depth, newton_iters,
                                                 with_valid=True))(fields)
    return real.reshape(ideal.shape), valid.reshape(ideal.shape[:-1])


def distortion_map(
    lens: Lens,
    *,
    grid: tuple[int, int] = (17, 17),
    depth=None,
    sensor: Sensor | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> DistortionMap:
    """The distortion map D on a grid of ideal positions spanning the sensor.

    Args:
        lens: the lens.
        grid: (rows, cols) of the grid.
        depth: object distance in mm in front of surface 1 (``inf`` for infinity); None
            (default) for the lens's own object (``lens.object_distance``).
        sensor: default ``lens.sensor``.
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        A :class:`DistortionMap` (differentiable with respect to the lens).
    """
    checks.focal_image(lens, "distortion_map")
    checks.lens_intact(lens, "distortion_map")
    s = _sensor(lens, sensor, "distortion_map")
    grid = checks.grid(grid, "distortion_map", "grid", "points", lo=2)  # interpolated
    checks.number(newton_iters, "newton_iters", "distortion_map", lo=0, integer=True,
                  unit="iterations")
    checks.newton_iters(newton_iters, "distortion_map")
    depth = sampling.lens_depth(lens, depth, "distortion_map")
    checks.primary_wavelength(lens, "distortion_map", "the chief rays'")
    ideal = sensor_grid(s.resolution, s.pixel_size, grid).astype(lens.epd.dtype)
    real, valid = _forward_map(lens, ideal, depth, newton_iters)
    if not checks.is_traced(valid) and not np.all(np.asarray(valid)):
        # Such a chief ray stops where it failed: its "image point" was a plausible number.
        r, c = np.argwhere(~np.asarray(valid))[0]
        x, y = np.asarray(ideal)[r, c]
        raise ValueError(
            f"distortion_map: the real chief ray of grid point (row {r}, col {c}) (first of "
            f"{int(np.sum(~np.asarray(valid)))}), ideal image point ({x:.4g}, {y:.4g}) mm, does "
            f"not reach the image surface (the sensor reaches beyond the lens's coverage); use "
            f"a smaller sensor")
    return DistortionMap(ideal, real)


def inverse_distortion_map(
    lens: Lens,
    *,
    resolution,
    pixel_size,
    grid: tuple[int, int] = (17, 17),
    depth=None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    iters: int = 6,
) -> Float[Array, "gr gc 2"]:
    """D⁻¹ on a grid of sensor points: the ideal position whose chief ray lands there.

    Each sensor point sends a ray backward through the lens, aimed by Newton's method (with
    a forward-mode Jacobian, apertures ignored) at the centre of the stop (for an
    object-space telecentric lens: so that it leaves into object space parallel to the axis,
    its real chief ray); where it leaves into object space gives the field, hence the ideal
    position (``aiming.field_to_ideal``: K·tanθ, or m·h for object heights h in mm).

    Args:
        lens: the lens.
        resolution, pixel_size: the sensor (rows, cols) and pitch (mm).
        grid: (rows, cols) of sensor points, corner to corner.
        depth: object distance in mm (``inf`` for infinity); None (default) for the
            lens's own object (``lens.object_distance``).
        newton_iters: Newton iterations for aspheric surfaces.
        iters: aiming iterations.

    Returns:
        ``[gr, gc, 2]`` ideal positions (mm), differentiable with respect to the lens.
    """
    checks.focal_image(lens, "inverse_distortion_map")
    checks.lens_intact(lens, "inverse_distortion_map")
    where = "inverse_distortion_map"
    resolution = checks.grid(resolution, where, "resolution", "pixels",
                             hi=checks.MAX_IMAGE_SIDE)
    grid = checks.grid(grid, where, "grid", "points", lo=2)  # interpolated
    # A sensor's pitch, as in distortion_map (render's PSF method passes its Sensor's): not
    # bounded above, as a Sensor's own pitch is not.
    pixel_size = pixel_pitch(pixel_size, where, bounded=False)
    if not checks.is_traced(pixel_size):  # bounded as a Sensor's: its longer side at most
        side = float(pixel_size) * max(resolution)  # MAX_SENSOR_SIZE_MM (5 for 5 µm: 2.6 m)
        if side > checks.MAX_SENSOR_SIZE_MM:
            raise ValueError(
                f"{where}: pixel_size must be a pitch in mm with pixel_size × max(resolution) "
                f"<= {checks.MAX_SENSOR_SIZE_MM:g} mm (a sensor's longest side, as Sensor "
                f"bounds it), got {checks.fmt(pixel_size)} mm × {max(resolution)} = "
                f"{side:g} mm (a pitch in µm? 5 µm is 0.005 mm)")
    checks.number(newton_iters, "newton_iters", where, lo=0, integer=True, unit="iterations")
    checks.newton_iters(newton_iters, where)
    # At least one: with 0 every sensor point kept the first guess (no ray was aimed at all).
    checks.number(iters, "iters", where, lo=1, hi=checks.MAX_NEWTON_ITERS, integer=True,
                  unit="aiming iterations")
    depth = sampling.lens_depth(lens, depth, where)
    sampling.telecentric.object_plane(lens, depth, where)
    checks.primary_wavelength(lens, where, "the chief rays'")
    return _inverse_map(lens, jnp.asarray(pixel_size), depth, resolution=resolution,
                        grid=grid, newton_iters=newton_iters, iters=iters)


@checks.checked_core(eqx.filter_jit)
def _inverse_map(lens, pixel_size, depth, *, resolution, grid, newton_iters, iters):
    dtype = lens.epd.dtype
    pts = sensor_grid(resolution, pixel_size, grid).astype(dtype)
    k_scale = image_scale(lens)  # mm per tanθ, or m (image mm per object mm)
    tele = lens.telecentric_object
    pd = paraxial.paraxial_data(lens)
    zep = pd.entrance_pupil_z
    z_img = lens.image_z()
    xp = pd.exit_pupil_z
    wl = lens.primary_wavelength

    def origin_of(xy):
        z, _ = lens.image.sag(xy[0], xy[1])
        return jnp.stack([xy[0], xy[1], z_img + z])

    def ray(lm, o):
        n = jnp.sqrt(jnp.clip(1.0 - jnp.sum(lm * lm), 1e-12, None))
        return Rays(o[None], jnp.concatenate([lm, -n[None]])[None], wl)

    aim_lens = unclipped(lens)

    def solve(xy):
        o = origin_of(xy)
        sgn = jnp.where(z_img >= xp, 1.0, -1.0)
        to_xp = jnp.stack([-o[0], -o[1], xp - o[2]]) * sgn
        lm0 = jax.lax.stop_gradient(to_xp[:2] / jnp.linalg.norm(to_xp))

        @checks.inherit  # newton_2d's loop bodies are made on each call
        def at_stop(lm, aim_lens):
            if tele:  # the chief ray leaves the object parallel to the axis
                out = trace_backward(aim_lens, ray(lm, o), newton_iters=newton_iters)
                return out.direction[0, :2]
            out = trace_backward(aim_lens, ray(lm, o), newton_iters=newton_iters,
                                 upto=lens.stop)
            return out.origin[0, :2]

        lm = newton_2d(at_stop, lm0, aim_lens, iters)
        out = trace_backward(lens, ray(lm, o), newton_iters=newton_iters)
        d = out.direction[0]
        bz = jnp.where(d[2] < 0, d[2], -1.0)
        if depth is None:
            t = d[:2] / bz
        else:
            s = (-depth - out.origin[0, 2]) / bz
            p = out.origin[0, :2] + s * d[:2]
            t = p if tele else -p / (zep + depth)  # aiming.field_coordinates
        return k_scale * t

    return jax.vmap(jax.vmap(solve))(pts)


def _ideal_of_pixels(shape, resolution, pixel_size, dtype):
    hs, ws = shape
    h, w = resolution
    pr, pc = pixel_size * h / hs, pixel_size * w / ws
    r = jnp.arange(hs, dtype=dtype)
    c = jnp.arange(ws, dtype=dtype)
    rr, cc = jnp.meshgrid(r, c, indexing="ij")
    return -(cc - 0.5 * (ws - 1)) * pc, (rr - 0.5 * (hs - 1)) * pr, pr, pc


def prewarp(
    lens: Lens,
    scene: Float[Array, "H W C"],
    *,
    depth=None,
    sensor: Sensor | None = None,
    grid: tuple[int, int] = (17, 17),
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, "H W C"]:
    """Pre-warp a scene by the lens's distortion: ``scene'(v) = scene(D(v))``.

    Rendering the result with ``jaxlens.imaging.render`` gives an image aligned with ``scene``.
    D is computed on ``grid`` and interpolated bilinearly; positions beyond the grid
    extend its edge values. Differentiable with respect to the lens and the scene.

    Args:
        lens: the lens.
        scene: ``[H, W, C]`` linear image with the sensor's aspect ratio.
        depth: object distance in mm (``inf`` for infinity); None (default) for the
            lens's own object.
        sensor: default ``lens.sensor``.
        grid: grid of the distortion map.
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        The pre-warped scene, same shape.
    """
    s = _sensor(lens, sensor, "prewarp")
    # An int scene warped in its own dtype: the map's positions were truncated to whole mm.
    checks.image_dtype(scene, "prewarp", "scene", "linear pixel values")
    scene = jnp.asarray(scene)
    if scene.ndim != 3:
        raise ValueError(f"prewarp: scene must be [H, W, C], got {scene.shape}")
    if not checks.is_traced(scene):
        checks.finite_array(scene, "scene", "prewarp", "linear pixel values")
    (rows, cols), (hs, ws) = s.resolution, scene.shape[:2]
    if abs(hs * cols - ws * rows) >= max(rows, cols):  # as render: the warp would misalign it
        raise ValueError(f"prewarp: scene of {hs}x{ws} pixels does not match the {rows}x{cols} "
                         f"sensor (the aspect ratios differ; resize or crop the scene)")
    grid = checks.grid(grid, "prewarp", "grid", "points", lo=2)
    dmap = distortion_map(lens, grid=grid, depth=depth, sensor=s, newton_iters=newton_iters)
    return _prewarp(scene, dmap.real.astype(scene.dtype), jnp.asarray(s.pixel_size),
                    resolution=tuple(s.resolution), grid=tuple(grid))


@eqx.filter_jit
def _prewarp(scene, real, pixel_size, *, resolution, grid):
    dtype = scene.dtype
    hs, ws = scene.shape[:2]
    x, y, pr, pc = _ideal_of_pixels((hs, ws), resolution, pixel_size, dtype)
    # Fractional sensor-pixel coordinates of the ideal positions, then grid coordinates.
    h, w = resolution
    rows = y / pixel_size + 0.5 * (h - 1)
    cols = -x / pixel_size + 0.5 * (w - 1)
    gy, gx = grid_coords(resolution, grid, rows, cols)
    dv = bilinear(real, gy, gx)  # [H, W, 2]
    r_sc = 0.5 * (hs - 1) + dv[..., 1] / pr
    c_sc = 0.5 * (ws - 1) - dv[..., 0] / pc
    return bilinear(scene, r_sc, c_sc)


def alignment_penalty(
    lens: Lens,
    *,
    alpha,
    grid: tuple[int, int] = (9, 9),
    depth=None,
    sensor: Sensor | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, ""]:
    """α times the mean squared chief-ray displacement |D(v) − v|², in pixels².

    Args:
        lens: the lens.
        alpha: weight α (0 turns the penalty off).
        grid: grid of ideal positions over the sensor.
        depth: object distance in mm (``inf`` for infinity); None (default) for the
            lens's own object.
        sensor: default ``lens.sensor`` (its pitch sets the unit).
        newton_iters: Newton iterations for aspheric surfaces.
    """
    # A negative weight would reward distortion (a traced one gets an error_if).
    alpha = checks.number(alpha, "alpha", "alignment_penalty", lo=0, unit="(weight)")
    s = _sensor(lens, sensor, "alignment_penalty")
    d = distortion_map(lens, grid=grid, depth=depth, sensor=s, newton_iters=newton_iters)
    err = jnp.sum((d.real - d.ideal) ** 2, -1) / s.pixel_size**2
    return jnp.asarray(alpha) * jnp.mean(err)


