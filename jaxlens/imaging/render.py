"""Image simulation: ``render(lens, scene, ...)`` by backward ray tracing or by PSF convolution.

``jaxlens.render(lens, scene, ...)`` is re-exported from here.

Conventions:
    Lengths in mm, wavelengths in µm. ``scene`` is a linear-light ``[H, W, 3]`` float image
    of the object. It fills the sensor's field of view as a distortion-free lens would image
    it: the scene point shown at sensor position u (mm) is the object point of field
    tanθ = u / K, with K = ``aiming.image_scale(lens)`` (the paraxial chief-ray height per unit
    tanθ; the focal length for a lens focused at infinity). At a finite ``depth`` the object
    plane lies ``depth`` mm in front of surface 1 and the same field angles are measured at
    the entrance pupil, so the scene spans the same angles. Scene pixels are looked up with
    bilinear interpolation; beyond the scene's border its edge pixels extend.

    An object-space telecentric lens (``Lens.object_na``; fields are object heights in mm):
    the scene is the object plane ``depth`` mm before surface 1 (finite; default the lens's
    own), and the scene point shown at sensor position u is the object point X = u / m (mm),
    m = ``image_scale(lens)`` = ``paraxial.magnification(lens)`` at the lens's own object
    distance (image mm per object mm, m < 0 inverted). The scene so spans the sensor's
    half-width and half-height over |m| on the object plane (scene pixel (i, j) of an
    [Hs, Ws] scene shows X = (x, y)/m with x = −(j − (Ws−1)/2)·p·cols/Ws,
    y = (i − (Hs−1)/2)·p·rows/Hs), as Zemax's image simulation scales an object-height source
    bitmap by its field height; for m < 0 (an inverted image) the scene is the object as a
    picture, row 0 at +Y, and the 180° read-out shows it upright, as for a camera lens.
    A pixel's rays count where they leave into the object cone (slope at most tan u,
    u = asin(NA/n): the NA is the system aperture), so the radiometry below gives the
    relative illumination of ``radiometry.relative_illumination`` for heights: vignetting
    and the local areal magnification, no cos⁴ law (every chief ray is parallel to the axis).

    The output is ``[rows, cols, 3]`` for the sensor (``lens.sensor`` or the ``sensor``
    argument), read out rotated by 180° as a camera does, so that a lens renders its scene
    upright: output pixel (r, c) is centred on the sensor point
    x = −(c − (cols−1)/2)·p, y = (r − (rows−1)/2)·p. The scene must have the sensor's
    aspect ratio (any resolution).

Radiometry:
    With ``relative_illumination=True`` a pixel is the sensor irradiance relative to the
    on-axis irradiance of a uniform scene of value 1: vignetting, the cos⁴ law, pupil
    aberrations and distortion all show, so a uniform white scene renders to the lens's
    relative-illumination curve (``radiometry.relative_illumination`` computes it
    independently by forward tracing). With ``False`` each pixel averages the scene over
    the rays that pass (no falloff), as in DeepLens.

Vignetting factors:
    ``Lens.vignetting`` (Zemax's VDX … VAN of the lens's own fields) is not applied by
    either method, nor by the relative illumination (``radiometry``): factors belong to a
    few defined fields, and a render covers every pixel's field, so ``render`` drops them
    (``PSFRender``'s tiles would otherwise take them only where a tile's centre field
    equals a defined field exactly). The image is that of the lens with its apertures;
    for a lens whose factors stand in for apertures it lacks, add the apertures.

Methods (``method=``):
    ``RayRender``: backward tracing. Each pixel sends ``spp`` rays per wavelength from random
    points inside the pixel, uniformly over a disc in image-space direction-cosine space (L, M)
    that covers the exit pupil as seen from that pixel. Uniform samples in (L, M) are
    uniform in projected solid angle, so the irradiance estimate is
    L_scene·(π R²)·(valid fraction) with no further weights. The discs are found once per
    call on a coarse grid of sensor points by tracing (``footprint_grid``; a search grid,
    then bisection of the boundary along 128 directions), without gradients, and
    interpolated with a margin for the interpolation error. The on-axis irradiance that
    normalises the image is the area of the on-axis footprint. spp samples are stratified
    when spp is a perfect square. The same samples serve the three channels.

    ``PSFRender``: the scene is first warped by the lens's distortion (real chief rays, D⁻¹ on
    a 17 × 17 grid), then each ``patch × patch`` tile is convolved with the RGB geometric PSF
    of its centre field (centred on the chief ray, from ``spp·kernel_size²`` jittered pupil
    rays per channel, splatted with the quadratic B-spline so that it is integrated over
    the pixel as in ``RayRender``), and multiplied by the relative-illumination map
    (``radiometry``, on a 9 × 9 grid, interpolated). For a scene at the sensor's resolution
    the two methods then compute the same image, up to Monte-Carlo noise and the
    piecewise-constant PSF.

Gradients:
    ``render`` is differentiable with respect to the lens and the scene. The gradient is
    that of the Monte-Carlo estimate with its samples held fixed (the same PRNG key): it
    follows where each ray lands in the scene. The sampling footprints and the on-axis
    normalisation are held fixed (``footprints`` lets a caller fix them explicitly, as a
    finite-difference check must), and a ray crossing an aperture edge changes the image
    in a jump that carries no gradient (as in DeepLens). With ``PSFRender`` and
    ``relative_illumination=True`` the vignetted pupil area of the illumination map
    (``radiometry.star_region``, found by bisection) is held likewise: the map's gradient
    is that of its cos⁴ and image-scale terms, and its differences are step-like.

Memory and scale-out:
    The sensor is cut into ``patch × patch`` tiles computed one after another by
    ``lax.map``. With ``checkpoint=True`` each tile is a ``jax.checkpoint``: the backward
    pass recomputes the tile's rays from the same PRNG key (``fold_in(key, tile index)``)
    instead of storing them, so the memory of a gradient grows with the tile, not with the
    image or spp. With ``mesh`` the tiles are sharded over the mesh's devices with
    ``jax.shard_map``; every tile draws the same random numbers as in a single-device
    render, so the result is the same.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, PartitionSpec
from jaxtyping import Array, Float

from ..optics import checks, paraxial
from ..optics.lens import Lens, Sensor
from ..optics.rays import Rays
from ..tracing.backward import trace_backward
from ..tracing.forward import DEFAULT_NEWTON_ITERS
from . import sampling, telecentric
from .aiming import ideal_to_field, image_scale
from .distortion import alignment_penalty, inverse_distortion_map, prewarp
from .grid import (
    bilinear,
    grid_coords,
    interp_grid,
    pixel_positions,
    scene_coords,
    sensor_grid,
)
from .psf import RGB_WAVELENGTHS, GeometricPSF
from .radiometry import (
    beam_bounded,
    in_entrance_pupil,
    relative_illumination_samples,
    star_region,
)

__all__ = ["render", "relaxed_render", "footprints", "Footprints", "RayRender", "PSFRender",
           "bilinear", "pixel_positions"]

# The PSF method's grids: D⁻¹ (the distortion map) on a 17 × 17 grid over the sensor, and the
# relative illumination on every other point of it (9 × 9), from 16² coarse and 48² fine
# footprint samples per field (radiometry.relative_illumination_samples).
DISTORTION_GRID = (17, 17)
RI_GRID = (9, 9)
RI_SAMPLES = (16, 48)


# --------------------------------------------------------------------------------------
# Exit-pupil footprints seen from the sensor
# --------------------------------------------------------------------------------------
def _sensor_origin(lens: Lens, x, y):
    z, _ = lens.image.sag(x, y)
    return jnp.stack([x, y, lens.image_z() + z], -1)


def _backward_valid(lens, origin, lm, wl, newton_iters):
    n = jnp.sqrt(jnp.clip(1.0 - jnp.sum(lm * lm, -1), 1e-12, None))
    d = jnp.concatenate([lm, -n[..., None]], -1)
    o = jnp.broadcast_to(origin, d.shape)
    ok = jnp.sum(lm * lm, -1) < 1.0
    out = trace_backward(lens, Rays(o, d, wl, ok), newton_iters=newton_iters)
    ok = out.valid & in_entrance_pupil(lens, out)  # the system aperture (radiometry)
    if lens.telecentric_object:  # the object cone (its NA) is the system aperture
        ok = ok & telecentric.in_cone(lens, out.direction)
    return ok


def _footprint(lens, origin, wl, lm0, half, newton_iters):
    """Disc (centre, radius) in (L, M) covering the valid backward directions from a point,
    and the area of the valid region (the projected solid angle)."""
    fn = lambda pts: _backward_valid(lens, origin, pts, wl, newton_iters)  # noqa: E731
    c0, poly, area, anyv = star_region(fn, lm0, half)
    cen = jnp.mean(poly, 0)
    rad = jnp.max(jnp.sqrt(jnp.sum((poly - cen) ** 2, -1)))
    # The boundary between the polygon's vertices bulges by at most r·(1 − cos(π/128)).
    rad = jnp.where(anyv, 1.001 * rad + 1e-6, 1e-3)
    return jnp.where(anyv, cen, lm0), rad, area


@checks.checked_core(eqx.filter_jit)
def _footprints(lens, wls, pts, *, newton_iters):
    """Footprint discs at a grid of sensor points ``pts [g, g, 2]`` (union over wavelengths),
    the margin for interpolating them, and the on-axis projected solid angle per wavelength.
    No gradients. The grid has odd sides, so that its centre point is the sensor centre.

    A jitted function of its own: it depends on the lens and the grid only, so one compiled
    program serves renders of every sensor size, scene and spp.
    """
    lens = jax.lax.stop_gradient(lens)
    grid = pts.shape[:2]
    pd = paraxial.paraxial_data(lens)
    z_img = lens.image_z()
    xp = pd.exit_pupil_z
    n_img = lens.materials[-1].index(lens.primary_wavelength)
    u = 1.0 / (2.0 * pd.working_fnum * n_img)
    half = jnp.minimum(3.0 * u + 0.05, 0.95)

    def guess(xy):
        origin = _sensor_origin(lens, xy[0], xy[1])
        sgn = jnp.where(z_img >= xp, 1.0, -1.0)
        far = ~jnp.isfinite(xp) | (jnp.abs(z_img - xp) > 1e6)
        to_xp = jnp.stack([-origin[0], -origin[1], jnp.where(far, -1.0, xp - origin[2])])
        v = jnp.where(far, jnp.array([0.0, 0.0, -1.0], origin.dtype), sgn * to_xp)
        v = v / jnp.linalg.norm(v)
        return origin, v[:2]

    def at_point(xy):
        origin, lm0 = guess(xy)
        cen, rad, area = jax.vmap(
            lambda wl: _footprint(lens, origin, wl, lm0, half, newton_iters))(wls)
        c = jnp.mean(cen, 0)
        r = jnp.max(jnp.sqrt(jnp.sum((cen - c) ** 2, -1)) + rad)
        return c, r, area

    cen, rad, area = jax.vmap(jax.vmap(at_point))(pts)
    e0 = area[grid[0] // 2, grid[1] // 2]
    # Margin for bilinear interpolation between grid points: the discrete Laplacian of the
    # centres and radii bounds (about 4x) the interpolation error of a smooth map.
    vals = jnp.concatenate([cen, rad[..., None]], -1)
    pad = jnp.pad(vals, ((1, 1), (1, 1), (0, 0)), mode="edge")
    lap = (pad[:-2, 1:-1] + pad[2:, 1:-1] + pad[1:-1, :-2] + pad[1:-1, 2:]) / 4 - vals
    margin = jnp.max(jnp.sqrt(jnp.sum(lap[..., :2] ** 2, -1)) + jnp.abs(lap[..., 2]))
    return cen, rad, margin, e0


class Footprints(eqx.Module):
    """Exit-pupil footprints seen from a grid of sensor points (method "ray").

    Attributes:
        center: ``[g, g, 2]`` disc centres in image-space direction cosines (L, M).
        radius: ``[g, g]`` disc radii (union over the wavelengths).
        margin: scalar added to interpolated radii between grid points.
        e0: ``[W]`` on-axis projected solid angle per wavelength (the normalisation).
    """

    center: Float[Array, "g g 2"]
    radius: Float[Array, "g g"]
    margin: Float[Array, ""]
    e0: Float[Array, " w"]


def footprints(
    lens: Lens,
    *,
    sensor: Sensor | None = None,
    wavelengths=RGB_WAVELENGTHS,
    grid: int = 9,
    dtype=None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    depth=None,
) -> Footprints:
    """The sampling footprints that ``render(method=RayRender())`` computes for a lens and sensor.

    Pass them to ``render(..., footprints=...)`` to reuse them (for example across the steps
    of an optimisation where the lens changes little), or to hold them fixed while
    differentiating. They carry no gradient.

    The footprint is the beam that the render traces: the directions from a sensor point
    whose backward rays pass the lens's apertures and the system aperture
    (``radiometry.in_pupil``'s rule: under paraxial aiming the EPD's disc on the paraxial
    entrance pupil's plane, ``radiometry.in_entrance_pupil``; under ray aiming the stop
    bounded at the radius the aim fills, ``radiometry.beam_bounded``, which for
    ``aim="real_marginal"`` depends on the object distance). Before round 45a the stop was
    sized for an object at infinity whatever the object: the footprints of a lens aimed at
    a finite object missed part of the beam that ``render`` traces (or spent rays beyond it).

    Args:
        lens: the lens.
        sensor: default ``lens.sensor``.
        wavelengths: one per channel (µm).
        grid: points per side (made odd, so that the sensor centre is one).
        dtype: float dtype (default the default float dtype).
        newton_iters: Newton iterations for aspheric surfaces.
        depth: the object distance of the render (mm before surface 1, ``inf`` for
            infinity; None, the default: the lens's own object, as ``render``'s). Footprints
            made for one depth are those of that depth's beam only.
    """
    sensor = lens.sensor if sensor is None else sensor
    if sensor is None:
        raise ValueError("footprints: the lens has no sensor; pass sensor=jaxlens.Sensor(...)")
    if not isinstance(sensor, Sensor):
        raise TypeError(f"footprints: sensor must be a jaxlens.Sensor, got "
                        f"{type(sensor).__name__} {sensor!r}")
    checks.newton_iters(newton_iters, "footprints")
    dtype = jnp.result_type(float) if dtype is None else checks.float_dtype(dtype, "footprints")
    # int() took 0 or 2.5 silently; wavelengths are checked here, not inside the jitted trace.
    checks.number(grid, "grid", "footprints", lo=2, hi=checks.MAX_MAP_GRID, integer=True,
                  unit="points per side")
    checks.wavelengths(lens, wavelengths, "footprints", "wavelengths")
    checks.primary_wavelength(lens, "footprints", "the paraxial pupils'")
    if np.size(wavelengths) == 0:  # "zero-size array to reduction operation max" otherwise
        raise ValueError("footprints: wavelengths is empty; give at least one wavelength (µm), "
                         "one per channel")
    g = int(grid) + 1 - int(grid) % 2
    pts = sensor_grid(sensor.resolution, jnp.asarray(sensor.pixel_size), (g, g)).astype(dtype)
    wls = jnp.atleast_1d(jnp.asarray(wavelengths, dtype))
    depth = sampling.lens_depth(lens, depth, "footprints")
    cen, rad, margin, e0 = _footprints(beam_bounded(lens, depth).astype(dtype), wls, pts,
                                       newton_iters=newton_iters)
    return Footprints(cen, rad, margin, e0)


_compute_footprints = footprints  # render's argument of the same name shadows it


# --------------------------------------------------------------------------------------
# Tiling, checkpointing and sharding
# --------------------------------------------------------------------------------------
def _run_tiles(tile_fn, n_tiles, args, *, checkpoint, mesh):
    """Map ``tile_fn(index, *args)`` over tile indices, checkpointed and optionally sharded."""
    # The tile loop's bodies are made on each call: in a checked core they are trusted too.
    tile_fn = checks.inherit(tile_fn)
    body = jax.checkpoint(tile_fn) if checkpoint else tile_fn

    def local(idx, *a):
        return jax.lax.map(checks.inherit(lambda i: body(i, *a)), idx)

    idx = jnp.arange(n_tiles, dtype=jnp.int32)
    if mesh is None:
        return local(idx, *args)
    ndev = mesh.size
    pad = (-n_tiles) % ndev
    idx = jnp.concatenate([idx, idx[:pad]]) if pad else idx
    axes = tuple(mesh.axis_names)
    spec = PartitionSpec(axes)
    rep = PartitionSpec()
    out = jax.shard_map(local, mesh=mesh, in_specs=(spec,) + (rep,) * len(args),
                        out_specs=spec)(idx, *args)
    return out[:n_tiles]


def _assemble(tiles, n_ty, n_tx, tile, resolution):
    th, tw = tile
    t = tiles.reshape(n_ty, n_tx, th, tw, tiles.shape[-1])
    img = t.transpose(0, 2, 1, 3, 4).reshape(n_ty * th, n_tx * tw, tiles.shape[-1])
    return img[: resolution[0], : resolution[1]]


def _tile_shape(resolution, patch):
    """The rows and columns a tile computes: ``patch``, or the image's side where one tile
    spans it (a patch past the image traced patch² pixels for the image's few)."""
    h, w = resolution
    return (h if patch >= h else patch), (w if patch >= w else patch)


def _unit_disc(key, shape, spp, dtype):
    """``[*shape, spp, 2]`` uniform points in the unit disc, stratified if spp is a square."""
    n = math.isqrt(spp)
    u = jax.random.uniform(key, shape + (spp, 2), dtype)
    if n * n == spp:
        s = jnp.arange(spp)
        i, j = (s // n).astype(dtype), (s % n).astype(dtype)
        r = jnp.sqrt((i + u[..., 0]) / n)
        a = 2 * jnp.pi * (j + u[..., 1]) / n
    else:
        r = jnp.sqrt(u[..., 0])
        a = 2 * jnp.pi * u[..., 1]
    return jnp.stack([r * jnp.cos(a), r * jnp.sin(a)], -1)


# --------------------------------------------------------------------------------------
# Backward ray tracing
# --------------------------------------------------------------------------------------
@checks.checked_core(eqx.filter_jit)
def _render_ray(lens, scene, key, depth, wls, pixel_size, footprints, *, resolution, spp, patch,
                checkpoint, mesh, ri, newton_iters):
    dtype = scene.dtype
    pixel_size = pixel_size.astype(dtype)
    lens = lens.astype(dtype)
    wls = wls.astype(dtype)
    k_scale = image_scale(lens)  # mm per tanθ, or m (image mm per object mm)
    tele = lens.telecentric_object
    zep = jnp.zeros((), dtype) if tele else paraxial.entrance_pupil_z(lens)
    fp_cen, fp_rad, fp_margin, e0 = jax.lax.stop_gradient(
        (footprints.center, footprints.radius, footprints.margin, footprints.e0))
    fp_cen, fp_rad, fp_margin, e0 = (a.astype(dtype) for a in (fp_cen, fp_rad, fp_margin, e0))
    grid = fp_cen.shape[:2]
    h, w = resolution
    n_ty, n_tx = -(-h // patch), -(-w // patch)
    th, tw = _tile_shape(resolution, patch)
    nc = scene.shape[-1]
    params, static = eqx.partition(lens, eqx.is_array)

    def tile_fn(t, params, scene, key, fp_cen, fp_rad, fp_margin, e0, k_scale, zep, wls,
                depth):
        lens = eqx.combine(params, static)
        ty, tx = t // n_tx, t % n_tx
        tkey = jax.random.fold_in(key, t)
        k1, k2 = jax.random.split(tkey)
        rows = (ty * patch).astype(dtype) + jnp.arange(th, dtype=dtype)
        cols = (tx * patch).astype(dtype) + jnp.arange(tw, dtype=dtype)
        rr, cc = jnp.meshgrid(rows, cols, indexing="ij")  # [P, P]
        # Samples: a position inside the pixel and a direction over its footprint disc,
        # drawn for the whole patch so that a tile cut to the image keeps its pixels' draws.
        jit = jax.random.uniform(k1, (patch, patch, spp, 2), dtype)[:th, :tw] - 0.5
        sr, sc = rr[..., None] + jit[..., 0], cc[..., None] + jit[..., 1]  # [P, P, S]
        x, y = pixel_positions(resolution, pixel_size, sr, sc)
        # Footprint disc at each sample point: bilinear in the grid, grown by the margin
        # that covers the interpolation error.
        gy, gx = grid_coords(resolution, grid, sr, sc)
        cen = interp_grid(fp_cen, gy, gx)  # [P, P, S, 2]
        rad = jnp.minimum(interp_grid(fp_rad, gy, gx) + fp_margin, 0.999)
        disc = _unit_disc(k2, (patch, patch), spp, dtype)[:th, :tw]
        lm = cen + rad[..., None] * disc  # [P, P, S, 2]
        inside = jnp.sum(lm * lm, -1) < 1.0
        nz = jnp.sqrt(jnp.where(inside, 1.0 - jnp.sum(lm * lm, -1), 1.0))
        d = jnp.concatenate([lm, -nz[..., None]], -1)
        o = _sensor_origin(lens, x, y)

        def channel(wl, img):
            out = trace_backward(lens, Rays(o, d, wl, inside), newton_iters=newton_iters)
            bz = out.direction[..., 2]
            ok = out.valid & (bz < 0) & in_entrance_pupil(lens, out)
            if tele:  # only rays inside the object cone carry light
                ok = ok & telecentric.in_cone(lens, out.direction)
            bz = jnp.where(ok, bz, -1.0)
            if depth is None:
                tx_, ty_ = out.direction[..., 0] / bz, out.direction[..., 1] / bz
            else:
                s = (-depth - out.origin[..., 2]) / bz
                xo = out.origin[..., 0] + s * out.direction[..., 0]
                yo = out.origin[..., 1] + s * out.direction[..., 1]
                # Field coordinates (aiming.field_coordinates): the object point itself for
                # a telecentric lens, else tanθ seen from the entrance pupil.
                tx_, ty_ = (xo, yo) if tele else (-xo / (zep + depth), -yo / (zep + depth))
            r_sc, c_sc = scene_coords(scene.shape[:2], resolution, pixel_size,
                                       k_scale * tx_, k_scale * ty_)
            val = bilinear(img, r_sc, c_sc)
            okf = ok.astype(dtype)
            if ri:
                okf = okf * (jnp.pi * rad * rad)
            return jnp.sum(okf * val, -1), jnp.sum(okf, -1)

        sums, counts = jax.vmap(channel, in_axes=(0, 2), out_axes=-1)(wls, scene)
        if ri:
            return sums / (spp * e0)
        return sums / jnp.maximum(counts, jnp.finfo(dtype).tiny)

    args = (params, scene, key, fp_cen, fp_rad, fp_margin, e0, k_scale, zep, wls, depth)
    tiles = _run_tiles(tile_fn, n_ty * n_tx, args, checkpoint=checkpoint, mesh=mesh)
    return _assemble(tiles, n_ty, n_tx, (th, tw), resolution)[..., :nc]


# --------------------------------------------------------------------------------------
# Patch-wise PSF convolution
# --------------------------------------------------------------------------------------
def _conv_rgb(window, kern):
    """Valid convolution of a ``[P+k-1, P+k-1, C]`` window with ``[C, k, k]`` kernels."""
    x = window.transpose(2, 0, 1)[None]  # [1, C, H, W]
    f = kern[:, None, ::-1, ::-1]  # correlation with the flipped kernel = convolution
    y = jax.lax.conv_general_dilated(x, f, (1, 1), "VALID",
                                     feature_group_count=kern.shape[0])
    return y[0].transpose(1, 2, 0)


def _psf_setup(lens, depth, pixel_size, *, resolution, ri, newton_iters):
    """D⁻¹ on a 17 × 17 sensor grid and the relative illumination on its 9 × 9 subgrid.

    Not jitted itself: its two parts are, and their compiled programs are shared with
    ``inverse_distortion_map`` and ``relative_illumination`` calls of the same shapes.
    """
    inv = inverse_distortion_map(lens, resolution=resolution, pixel_size=pixel_size,
                                 grid=DISTORTION_GRID, depth=depth, newton_iters=newton_iters)
    if not ri:
        return inv, None
    fields = ideal_to_field(lens, inv[::2, ::2]).reshape(-1, 2)  # the RI_GRID points
    ri_vals, _, _ = relative_illumination_samples(
        lens, fields, depth, lens.primary_wavelength, n_coarse=RI_SAMPLES[0],
        n_fine=RI_SAMPLES[1], newton_iters=newton_iters)
    return inv, ri_vals.reshape(RI_GRID)


@checks.checked_core(eqx.filter_jit)
def _render_psf(lens, scene, key, depth, wls, pixel_size, inv, ri_map, *, resolution, spp,
                patch, checkpoint, mesh, kernel_size, newton_iters):
    dtype = scene.dtype
    pixel_size = pixel_size.astype(dtype)
    lens = lens.astype(dtype)
    wls = wls.astype(dtype)
    inv = inv.astype(dtype)
    h, w = resolution
    # 1. Distortion: the sensor pixel u shows the scene at the ideal point D^-1(u).
    rr, cc = jnp.meshgrid(jnp.arange(h, dtype=dtype), jnp.arange(w, dtype=dtype), indexing="ij")
    gy, gx = grid_coords(resolution, DISTORTION_GRID, rr, cc)
    ideal = interp_grid(inv, gy, gx)  # [h, w, 2]
    r_sc, c_sc = scene_coords(scene.shape[:2], resolution, pixel_size, ideal[..., 0],
                               ideal[..., 1])
    warped = bilinear(scene, r_sc, c_sc)  # [h, w, C]
    # 2. Relative illumination, interpolated from the 9 × 9 grid.
    if ri_map is not None:
        gy9, gx9 = grid_coords(resolution, RI_GRID, rr, cc)
        warped = warped * interp_grid(ri_map.astype(dtype), gy9, gx9)[..., None]
    # 3. Tiles with a halo of half a kernel.
    n_ty, n_tx = -(-h // patch), -(-w // patch)
    th, tw = _tile_shape(resolution, patch)
    half = kernel_size // 2
    ph, pw = (n_ty - 1) * patch + th - h, (n_tx - 1) * patch + tw - w
    padded = jnp.pad(warped, ((half, half + ph), (half, half + pw), (0, 0)), mode="edge")
    pupil = max(2, math.isqrt(spp * kernel_size * kernel_size))
    nc = scene.shape[-1]
    params, static = eqx.partition(lens, eqx.is_array)

    def tile_fn(t, params, padded, key, wls, depth, inv):
        lens = eqx.combine(params, static)
        ty, tx = t // n_tx, t % n_tx
        r0, c0 = ty * patch, tx * patch
        win = jax.lax.dynamic_slice(padded, (r0, c0, jnp.zeros((), r0.dtype)),
                                    (th + 2 * half, tw + 2 * half, nc))
        # The tile centre (kept on the sensor) and the field whose chief ray lands there.
        rc = jnp.minimum((r0 + 0.5 * (patch - 1)).astype(dtype), h - 1.0)
        ccen = jnp.minimum((c0 + 0.5 * (patch - 1)).astype(dtype), w - 1.0)
        gy, gx = grid_coords(resolution, DISTORTION_GRID, rc, ccen)
        field = ideal_to_field(lens, interp_grid(inv, gy, gx))
        ref = jnp.stack(pixel_positions(resolution, pixel_size, rc, ccen))
        model = GeometricPSF(pupil=pupil, order=2)
        kern, _, _, _, _ = model.kernels(lens, field, depth, wls, kernel_size=kernel_size,
                                         pixel_size=pixel_size, center=ref,
                                         key=jax.random.fold_in(key, t),
                                         newton_iters=newton_iters)
        kern = kern / jnp.maximum(jnp.sum(kern, (-1, -2), keepdims=True), 1e-30)
        return _conv_rgb(win, kern[:nc])

    args = (params, padded, key, wls, depth, inv)
    tiles = _run_tiles(tile_fn, n_ty * n_tx, args, checkpoint=checkpoint, mesh=mesh)
    return _assemble(tiles, n_ty, n_tx, (th, tw), resolution)


# --------------------------------------------------------------------------------------
# Public entry point
# --------------------------------------------------------------------------------------
class RayRender(eqx.Module):
    """The "ray" method: backward tracing from the sensor pixels (see Methods).

    Attributes:
        footprint_grid: sensor grid (per side) for the exit-pupil discs the rays aim at.
        footprints: precomputed :func:`footprints` for this sensor and these wavelengths;
            ``None`` computes them from the lens at each call.
    """

    footprint_grid: int = 9
    footprints: Footprints | None = None


class PSFRender(eqx.Module):
    """The "psf" method: patch-wise convolution with a spatially varying geometric PSF.

    Attributes:
        kernel_size: PSF kernel side in pixels (odd: the kernel is centred on a pixel).
    """

    kernel_size: int = 31


RAY = RayRender()
"""The default render method."""


def _check_working_memory(lens, method, spp, patch, tile, channels, itemsize):
    """Refuse a render whose tile would not fit (``checks.working_memory``): a tile traces
    patch² × spp rays per channel ("ray"), or a PSF of about spp × kernel_size² rays per
    channel ("psf"). A gradient without ``checkpoint`` keeps every tile's rays, which is not
    bounded here (a forward render with it needs one tile at a time)."""
    if isinstance(method, PSFRender):
        k = int(method.kernel_size)
        rays = max(2, math.isqrt(spp * k * k)) ** 2 * channels
        what, fix = f"spp × kernel_size² × {channels} channels", "lower spp or kernel_size"
    else:
        rays = tile[0] * tile[1] * spp * channels
        what = f"patch² × spp × {channels} channels"
        per_ray = checks.working_memory(1, len(lens.surfaces), itemsize, "render", "", "")
        best = math.isqrt(checks.MAX_WORKING_BYTES // per_ray // (spp * channels))
        fix = (f"lower patch (the tile side, {patch} pixels) to at most {best}" if best
               else "lower spp")
    checks.working_memory(rays, len(lens.surfaces), itemsize, "render", what, fix)


def render(
    lens: Lens,
    scene: Float[Array, "H W 3"],
    *,
    spp: int,
    key,
    depth=None,
    method: RayRender | PSFRender = RAY,
    wavelengths=RGB_WAVELENGTHS,
    sensor: Sensor | None = None,
    patch: int = 64,
    checkpoint: bool = True,
    mesh: Mesh | None = None,
    relative_illumination: bool = True,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, "rows cols 3"]:
    """Simulate the sensor image of a scene through a lens (see the module docstring).

    Pure and jittable (the options after ``*`` other than ``key`` and ``depth`` are static),
    differentiable with respect to the lens and the scene.

    Args:
        lens: the lens.
        scene: ``[H, W, C]`` linear float image (C = 3 for RGB, one wavelength per channel),
            with the sensor's aspect ratio.
        spp: rays per pixel per wavelength (``RayRender``); for ``PSFRender``, rays per
            kernel pixel in each patch's PSF (spp·kernel_size² per channel).
        key: PRNG key (``jax.random.PRNGKey``); the same key gives the same image.
        depth: object distance in mm in front of surface 1, ``inf`` for infinity; None
            (default) for the lens's own object (``lens.object_distance``). Finite for an
            object-space telecentric lens (its scene is the object plane, in mm).
        method: ``RayRender(footprint_grid, footprints)`` (backward tracing, the default)
            or ``PSFRender(kernel_size)`` (patch-wise PSF convolution).
        wavelengths: one wavelength (µm) per channel, default the C, d, F lines for R, G, B.
        sensor: the sensor; default ``lens.sensor``.
        patch: tile side in pixels (memory of a gradient grows with patch²·spp); a tile
            stops at the image's side where one tile spans it.
        checkpoint: recompute each tile in the backward pass (``jax.checkpoint``).
        mesh: a ``jax.sharding.Mesh`` to spread the tiles over its devices.
        relative_illumination: include vignetting and the cos⁴ falloff (see Radiometry).
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        ``[rows, cols, C]`` sensor image in the scene's dtype.

    Raises:
        ValueError: for a scene that is not ``[H, W, C]`` float, finite and non-negative,
            with C matching the wavelengths, an aspect ratio unlike the sensor's, a
            non-positive spp, a missing sensor, an unknown method or a non-positive depth;
            for an object-space telecentric lens an object at infinity, or a paraxial
            magnification that is not finite and nonzero (its image at infinity).
    """
    checks.focal_image(lens, "render")
    if isinstance(method, str):
        raise TypeError(f"render: method is a render method object, not a string: use "
                        f"RayRender(...) or PSFRender(kernel_size=...), got {method!r}")
    if not isinstance(method, RayRender | PSFRender):
        raise TypeError(f"render: method must be RayRender(...) or PSFRender(...), got "
                        f"{type(method).__name__}")
    if (not isinstance(spp, (int, np.integer)) or isinstance(spp, bool) or spp <= 0
            or spp > checks.MAX_SAMPLES):
        # Before: no upper bound; spp=10**9 asked XLA for 1.4 PB after the checks.
        raise ValueError(f"render: spp must be a positive int, at most {checks.MAX_SAMPLES} "
                         f"rays per pixel (noise falls as 1/sqrt(spp): 0.4 % there), got "
                         f"{spp!r}")
    if isinstance(patch, bool) or not isinstance(patch, (int, np.integer)) or patch < 1:
        raise ValueError(f"render: patch must be a positive int, got {patch!r}")
    if mesh is not None and not isinstance(mesh, Mesh):
        raise ValueError(f"render: mesh must be a jax.sharding.Mesh or None, got {mesh!r}")
    # bool("no") is True: a switch is a bool, never read from another type.
    checks.switch(checkpoint, "checkpoint", "render")
    checks.switch(relative_illumination, "relative_illumination", "render")
    checks.prng_key(key, "render")
    if isinstance(method, PSFRender):
        kernel_size = method.kernel_size
        if checks.number(kernel_size, "kernel_size", "render", lo=1,
                         hi=checks.MAX_KERNEL_SIZE, unit="pixels", integer=True) % 2 == 0:
            raise ValueError(f"render: kernel_size must be odd (a kernel centred on a pixel), "
                             f"in [1, {checks.MAX_KERNEL_SIZE}] pixels, got {kernel_size!r}")
    else:
        checks.number(method.footprint_grid, "footprint_grid", "render", lo=2,
                      hi=checks.MAX_MAP_GRID, unit="points per side", integer=True)
        if method.footprints is not None and not isinstance(method.footprints, Footprints):
            raise TypeError(f"render: RayRender's footprints must be None or the result of "
                            f"jaxlens.imaging.render.footprints(...), got "
                            f"{type(method.footprints).__name__} {method.footprints!r}")
    checks.number(newton_iters, "newton_iters", "render", lo=0, integer=True)
    checks.newton_iters(newton_iters, "render")
    sensor = lens.sensor if sensor is None else sensor
    if sensor is None:
        raise ValueError("render: the lens has no sensor; pass sensor=jaxlens.Sensor(...)")
    if not isinstance(sensor, Sensor):
        raise TypeError(f"render: sensor must be a jaxlens.Sensor, got {type(sensor).__name__} "
                        f"{sensor!r}")
    checks.real_values(wavelengths, "wavelengths", "render", "µm")  # before jnp.asarray
    scene = jnp.asarray(scene)
    wls = jnp.atleast_1d(jnp.asarray(wavelengths, jnp.result_type(float)))
    if scene.ndim != 3:
        raise ValueError(f"render: scene must be [H, W, C], got shape {scene.shape}")
    if not jnp.issubdtype(scene.dtype, jnp.floating):
        raise ValueError(
            f"render: scene must be a linear float image, got dtype {scene.dtype} "
            "(convert with jaxlens.io.images.to_linear)"
        )
    if jnp.finfo(scene.dtype).bits < 32:  # float16 failed later, naming "footprints: dtype"
        raise ValueError(f"render: scene must be float32 or float64, got dtype {scene.dtype} "
                         f"(convert with scene.astype(jnp.float32))")
    if wls.ndim != 1 or wls.shape[0] != scene.shape[-1]:
        raise ValueError(
            f"render: {scene.shape[-1]} scene channels need as many wavelengths, got "
            f"{wls.shape}"
        )
    if scene.size == 0:
        raise ValueError(f"render: scene is empty (shape {scene.shape}); it needs at least one "
                         f"pixel and channel")
    scene = checks.finite_array(scene, "scene", "render", "linear pixel values")
    # Radiance is never negative: e.g. an image in [-1, 1] (an error_if where traced).
    scene = checks.values(scene, "scene", "render", lo=0.0, unit="(linear radiance)")
    wls = checks.wavelengths(lens, wls, "render", "wavelengths")
    checks.material_indices(lens, wls, "render", "wavelengths")
    checks.primary_wavelength(lens, "render", "the paraxial pupils'")
    rows, cols = sensor.resolution
    hs, ws = scene.shape[:2]
    if abs(hs * cols - ws * rows) >= max(rows, cols):
        raise ValueError(
            f"render: scene of {hs}x{ws} pixels does not match the {rows}x{cols} sensor "
            "(the aspect ratios differ; resize or crop the scene)"
        )
    _check_working_memory(lens, method, int(spp), int(patch),
                          _tile_shape(sensor.resolution, int(patch)), scene.shape[-1],
                          scene.dtype.itemsize)
    given_depth = depth  # the footprints' (their beam is the render's)
    depth = sampling.lens_depth(lens, depth, "render")
    telecentric.object_plane(lens, depth, "render")  # its scene: object heights (mm)
    if lens.telecentric_object:
        image_scale(lens)  # its m: finite and nonzero, checked before tracing
    # "Vignetting factors"; the beam the system aperture admits, as radiometry bounds it
    lens = eqx.tree_at(lambda m: m.vignetting, beam_bounded(lens, depth), None,
                       is_leaf=lambda x: x is None)
    key = jnp.asarray(key) if not isinstance(key, jax.Array) else key
    common = dict(resolution=(int(rows), int(cols)), spp=int(spp), patch=int(patch),
                  checkpoint=bool(checkpoint), mesh=mesh, ri=bool(relative_illumination),
                  newton_iters=int(newton_iters))
    pixel_size = jnp.asarray(sensor.pixel_size)
    if depth is not None:
        depth = jnp.asarray(depth, scene.dtype)
    if isinstance(method, RayRender):
        footprints = method.footprints
        if footprints is None:
            footprints = _compute_footprints(
                lens, sensor=sensor, wavelengths=wls, grid=method.footprint_grid,
                dtype=scene.dtype, newton_iters=common["newton_iters"], depth=given_depth)
        elif footprints.e0.shape != wls.shape:
            raise ValueError(
                f"render: footprints for {footprints.e0.shape[0]} wavelengths, the scene has "
                f"{wls.shape[0]} channels"
            )
        return _render_ray(lens, scene, key, depth, wls, pixel_size, footprints, **common)
    ri = common.pop("ri")
    inv, ri_map = _psf_setup(lens, depth, pixel_size, resolution=common["resolution"], ri=ri,
                             newton_iters=common["newton_iters"])
    # The PSFs' beams are the system aperture's (``psf``'s, ``radiometry.in_pupil``).
    return _render_psf(lens, scene, key, depth, wls, pixel_size, inv, ri_map,
                       kernel_size=int(method.kernel_size), **common)


def relaxed_render(
    lens: Lens,
    scene,
    *,
    spp: int,
    key,
    alpha=0.0,
    depth=None,
    grid: tuple[int, int] = DISTORTION_GRID,
    **render_kwargs,
):
    """Render the pre-warped scene and return ``(image, alignment_penalty)``.

    The image lines up with ``scene``, so an image loss against ``scene`` sees blur but not
    distortion; add the penalty (weight ``alpha``) to the loss to keep distortion bounded.

    Args:
        lens, scene, spp, key, depth, render_kwargs: as :func:`render`.
        alpha: weight of :func:`alignment_penalty`.
        grid: grid of the distortion map.
    """
    checks.focal_image(lens, "relaxed_render")
    grid = checks.grid(grid, "relaxed_render", "grid", "points", lo=2)  # interpolated
    sensor = render_kwargs.get("sensor")
    warped = prewarp(lens, scene, depth=depth, sensor=sensor, grid=grid)
    img = render(lens, warped, spp=spp, key=key, depth=depth, **render_kwargs)
    pen = alignment_penalty(lens, alpha=alpha, depth=depth, sensor=sensor)
    return img, pen
