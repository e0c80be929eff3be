"""Sensor and pupil grids, bilinear interpolation on them and splatting onto them (mm).

Rendered orientation: row 0 / column 0 is the top-left pixel of ``render``'s output, which
reads the sensor out rotated by 180° (sensor x grows to the left, y downward), as a camera
does, so that a lens renders its scene upright.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks

MAX_PIXEL_SIZE_MM = 1.0
"""Pixel pitches (mm) of a PSF grid or a rendered sensor must be below this: image sensors'
pixels are 0.5 to about 100 µm, and a pitch of 5 given for 5 µm (a unit mix-up) made a PSF
1000 times too coarse (one lit pixel) without a word."""


def pixel_pitch(value, where: str, arg: str = "pixel_size", bounded: bool = True):
    """A pixel pitch in (0, ``MAX_PIXEL_SIZE_MM``) mm: ``checks.number`` (a traced value gets
    its ``eqx.error_if`` of (0, inf) mm), then, for a concrete value, the upper bound (not
    with ``bounded=False``: a ``Sensor``'s own pitch, which the Sensor bounds by its
    size, ``checks.MAX_SENSOR_SIZE_MM``).
    Returns the value as ``checks.number`` does."""
    value = checks.number(value, arg, where, lo=0, lo_open=True, unit="mm")
    if bounded and not checks.is_traced(value):
        checks.number(value, arg, where, lo=0, lo_open=True, hi=MAX_PIXEL_SIZE_MM,
                      hi_open=True, unit="mm (a pixel pitch: 5 µm is 0.005 mm)")
    return value


def kernel_side(value, where: str, odd: bool = True) -> int:
    """A PSF kernel's side: a whole number in [1, ``checks.MAX_KERNEL_SIZE``] pixels, odd
    where the kernel is centred on its reference (``odd``; ``mtf``'s FFT grid may be even):
    an even kernel has no centre pixel, its reference fell on a pixel corner and the PSF
    sat half a pixel off the point it was drawn for (``render`` refuses it already)."""
    k = checks.number(checks.static_int(value), "kernel_size", where, lo=1,
                      hi=checks.MAX_KERNEL_SIZE, integer=True, unit="pixels per side")
    if odd and k % 2 == 0:
        raise ValueError(f"{where}: kernel_size must be odd (a kernel centred on a pixel: an "
                         f"even one has no centre pixel, so the PSF would sit half a pixel "
                         f"off its reference point), in [1, {checks.MAX_KERNEL_SIZE}] pixels "
                         f"per side, got {value!r}; use {k + 1}")
    return k


def sensor_grid(resolution, pixel_size, grid) -> Float[Array, "gr gc 2"]:
    """Sensor points (x, y) in mm of a ``grid = (rows, cols)`` in rendered orientation.

    Row 0 / column 0 are the top-left corner pixel centres of ``render``'s output, the last
    row / column the opposite corner; a grid of 1 gives the centre. Sensor x grows to the
    left of the rendered image and y downward (the 180° readout, see the module docstring).
    """
    rows, cols = resolution
    gr, gc = grid
    p = jnp.asarray(pixel_size)
    r = jnp.linspace(0.0, rows - 1.0, gr) if gr > 1 else jnp.full((1,), 0.5 * (rows - 1))
    c = jnp.linspace(0.0, cols - 1.0, gc) if gc > 1 else jnp.full((1,), 0.5 * (cols - 1))
    y = (r - 0.5 * (rows - 1)) * p
    x = -(c - 0.5 * (cols - 1)) * p
    xx, yy = jnp.meshgrid(x, y, indexing="xy")
    return jnp.stack([xx, yy], -1)


def pixel_positions(resolution, pixel_size, rows, cols):
    """Sensor (x, y) in mm of fractional pixel coordinates (rendered orientation)."""
    h, w = resolution
    return -(cols - 0.5 * (w - 1)) * pixel_size, (rows - 0.5 * (h - 1)) * pixel_size


# --------------------------------------------------------------------------------------
# Small helpers
# --------------------------------------------------------------------------------------
def bilinear(img: Float[Array, "H W *C"], row, col) -> Array:
    """Bilinear lookup of ``img`` at fractional (row, col); edge pixels extend outward.

    Differentiable with respect to the image and the coordinates. Shapes are checked (they
    are static): an image of other than 2 or 3 axes, or coordinates that do not broadcast.
    """
    if jnp.ndim(img) not in (2, 3):  # a [W] row indexed its pixels as rows of nothing
        raise ValueError(f"bilinear: img must be [H, W] or [H, W, C], got shape "
                         f"{jnp.shape(img)}")
    try:
        np.broadcast_shapes(jnp.shape(row), jnp.shape(col))
    except ValueError:
        raise ValueError(f"bilinear: row and col (fractional pixel coordinates) must have "
                         f"broadcastable shapes, got {jnp.shape(row)} and {jnp.shape(col)}"
                         ) from None
    h, w = img.shape[0], img.shape[1]
    r = jnp.clip(row, 0.0, h - 1.0)
    c = jnp.clip(col, 0.0, w - 1.0)
    r0 = jnp.clip(jnp.floor(jax.lax.stop_gradient(r)), 0, max(h - 2, 0)).astype(jnp.int32)
    c0 = jnp.clip(jnp.floor(jax.lax.stop_gradient(c)), 0, max(w - 2, 0)).astype(jnp.int32)
    fr = (r - r0)[..., None] if img.ndim == 3 else r - r0
    fc = (c - c0)[..., None] if img.ndim == 3 else c - c0
    r1 = jnp.minimum(r0 + 1, h - 1)
    c1 = jnp.minimum(c0 + 1, w - 1)
    top = img[r0, c0] * (1 - fc) + img[r0, c1] * fc
    bot = img[r1, c0] * (1 - fc) + img[r1, c1] * fc
    return top * (1 - fr) + bot * fr


def interp_grid(grid_vals, gy, gx):
    """Bilinear interpolation on a regular grid given fractional grid coordinates."""
    return bilinear(grid_vals, gy, gx)


def grid_coords(resolution, grid, rows, cols):
    """Fractional coordinates on a ``grid`` spanning corner to corner pixel centres."""
    h, w = resolution
    gr, gc = grid
    gy = rows * (gr - 1) / max(h - 1, 1) if gr > 1 else jnp.zeros_like(rows)
    gx = cols * (gc - 1) / max(w - 1, 1) if gc > 1 else jnp.zeros_like(cols)
    return gy, gx


def scene_coords(scene_shape, resolution, pixel_size, x, y):
    """Fractional scene (row, col) shown at ideal sensor position (x, y)."""
    hs, ws = scene_shape
    h, w = resolution
    pr = pixel_size * h / hs
    pc = pixel_size * w / ws
    return 0.5 * (hs - 1) + y / pr, 0.5 * (ws - 1) - x / pc


def pupil_cells(n: int, overfill: float, dtype, key=None):
    """Cell-centred n×n grid over the disc of radius ``overfill`` (normalised pupil units).

    Returns the points ``[n*n, 2]``, a mask ``[n*n]`` (inside the disc) and the cell side.
    With a key, each point is jittered uniformly inside its cell (stratified sampling).
    """
    # n = 0 divided by zero (NaN points), 2.5 made 3 cells of side 0.8: a grid of nothing.
    n = checks.number(checks.static_int(n), "n", "pupil_cells", lo=1,
                      hi=checks.MAX_KERNEL_SIZE, integer=True, unit="cells per side")
    overfill = checks.number(overfill, "overfill", "pupil_cells", lo=0, lo_open=True,
                             unit="(pupil radii)")
    g = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    px, py = np.meshgrid(g, g, indexing="xy")
    pts = jnp.asarray(np.stack([px.ravel(), py.ravel()], -1), dtype)
    cell = 2.0 / n
    if key is not None:
        pts = pts + (jax.random.uniform(key, pts.shape, dtype) - 0.5) * cell
    mask = jnp.sum(pts * pts, -1) <= 1.0
    return pts * overfill, mask, cell * overfill


def splat(pos, weight, kernel_size: int, pixel_size, order: int = 1) -> Float[Array, "k k"]:
    """Splat weighted points (sensor offsets in mm from the reference) onto the kernel grid.

    The grid is in rendered orientation (see the module docstring) and centred on the
    reference; points outside it are dropped. ``order=1`` splats bilinearly (a tent of one
    pixel); ``order=2`` with the quadratic B-spline (a tent convolved with a one-pixel box),
    which also integrates the PSF over the pixel's area as ``render`` does. Both are
    piecewise polynomial in the positions, hence differentiable. Shapes and the kernel size
    are checked (static): ``pos`` ``[..., 2]`` (mm), ``weight`` of ``pos``'s leading shape.
    """
    k = kernel_side(kernel_size, "splat", odd=False)
    if jnp.ndim(pos) < 1 or jnp.shape(pos)[-1] != 2:  # [5, 3] splatted x, y and dropped z
        raise ValueError(f"splat: pos must be sensor offsets [..., 2] (x, y) in mm, got shape "
                         f"{jnp.shape(pos)}")
    if jnp.shape(weight) != jnp.shape(pos)[:-1]:  # a [4] weight broadcast or failed in .at
        raise ValueError(f"splat: weight must have pos's leading shape {jnp.shape(pos)[:-1]} "
                         f"(one weight a point), got shape {jnp.shape(weight)}")
    c = 0.5 * (k - 1)
    col = c - pos[..., 0] / pixel_size
    row = c + pos[..., 1] / pixel_size
    if order == 1:
        i0 = jax.lax.stop_gradient(jnp.floor(row))
        j0 = jax.lax.stop_gradient(jnp.floor(col))
        fr, fc = row - i0, col - j0
        wr = ((0, 1 - fr), (1, fr))
        wc = ((0, 1 - fc), (1, fc))
    elif order == 2:
        i0 = jax.lax.stop_gradient(jnp.round(row))
        j0 = jax.lax.stop_gradient(jnp.round(col))
        fr, fc = row - i0, col - j0

        def b2(f):
            return ((-1, 0.5 * (0.5 - f) ** 2), (0, 0.75 - f * f), (1, 0.5 * (0.5 + f) ** 2))

        wr, wc = b2(fr), b2(fc)
    else:
        raise ValueError(f"splat: order must be 1 or 2, got {order}")
    i0 = i0.astype(jnp.int32)
    j0 = j0.astype(jnp.int32)
    out = jnp.zeros((k * k,), weight.dtype)
    for di, a in wr:
        for dj, b in wc:
            ii, jj = i0 + di, j0 + dj
            inside = (ii >= 0) & (ii < k) & (jj >= 0) & (jj < k)
            flat = jnp.where(inside, ii * k + jj, 0)
            out = out.at[flat.reshape(-1)].add(jnp.where(inside, a * b * weight, 0.0).reshape(-1))
    return out.reshape(k, k)
