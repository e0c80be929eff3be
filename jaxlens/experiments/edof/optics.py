"""Image formation for the EDoF experiment: RGB PSFs, patch simulation, PSF analysis.

Conventions:
    Lengths in mm, wavelengths in µm, depths in mm from the aperture stop
    (``lenses.object_depth``). Images are ``[H, W, 3]`` linear RGB in ``jaxlens.imaging.render``'s
    orientation (read out rotated by 180°, see ``jaxlens.imaging.psf``), one wavelength per channel
    (``WAVELENGTHS_RGB``). A sensor position (x, y) in mm shows the field whose
    distortion-free image lies there (``jaxlens.imaging.aiming.ideal_to_field``); PSFs are
    centred on the chief ray, so distortion moves no content (the paper's distortion relaxation).

Training simulates patches: a ``P × P`` sensor patch centred at a sensor position is the
scene window of ``(P + k − 1)²`` pixels convolved ("valid") with the RGB PSF of that
position (``rgb_psf``: geometric, the model of ``jaxlens.imaging.psf``, jittered pupil samples).
Each patch is a ``jax.checkpoint``, so the backward pass re-traces its rays instead of
storing them and the memory of a gradient grows with the patch, as in ``jaxlens.imaging.render``.
Whole test images are rendered tile by tile with the same model (``render_tiled``);
``render_library`` renders them through ``jaxlens.imaging.render`` as a cross-check.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ...imaging import psf as _psf
from ...imaging import sampling
from ...imaging.aiming import ideal_to_field
from ...imaging.grid import pixel_positions, sensor_grid
from ...optics.lens import Lens
from ...tracing.forward import trace
from .lenses import DEPTHS_M, WAVELENGTHS_RGB, object_depth


def field_of(lens: Lens, xy) -> Float[Array, "*b 2"]:
    """Field angles (θx, θy), degrees, shown at sensor position(s) ``xy`` (mm)."""
    return ideal_to_field(lens, xy)


def pupil_disc(n_side: int, key=None, dtype=None) -> Float[Array, "m 2"]:
    """``n_side²`` points in the unit pupil disc, one per cell of a polar grid (equal areas).

    With a key each point is jittered inside its cell (stratified sampling); without one
    it sits at the cell centre. Radii stay below 1 so every ray clears the stop's rim.
    """
    dt = dtype or jnp.result_type(float)
    i, j = jnp.meshgrid(jnp.arange(n_side), jnp.arange(n_side), indexing="ij")
    u = (
        jnp.full((2, n_side, n_side), 0.5, dt)
        if key is None
        else jax.random.uniform(key, (2, n_side, n_side), dt)
    )
    r = jnp.sqrt((i + u[0]) / n_side) * (1.0 - 1e-4)
    a = 2 * jnp.pi * (j + u[1]) / n_side
    return jnp.stack([r * jnp.cos(a), r * jnp.sin(a)], -1).reshape(-1, 2)


def rgb_psf(
    lens: Lens,
    xy,
    depth,
    *,
    kernel_size: int,
    pixel_size: float,
    pupil: int,
    key=None,
    wavelengths=WAVELENGTHS_RGB,
) -> Float[Array, "3 k k"]:
    """The RGB geometric PSF at sensor position ``xy`` (mm) of an object ``depth`` mm from
    the stop, in ``jaxlens.imaging.psf``'s kernel orientation.

    The rays leave the object point for ``pupil²`` points of the entrance-pupil disc
    (``pupil_disc``, jittered by ``key``), aimed at the paraxial entrance pupil (exact for a
    stop-first lens, whose entrance pupil is the stop), weighted by cos⁴ of their launch
    angle and splatted bilinearly (``jaxlens.imaging.psf.splat``) around the chief ray of the middle
    channel (green, 587 nm), so lateral colour shows as a shift between the channels. Each
    channel is normalised to unit sum over the kernel.

    Only rays inside the pupil are launched: none fails at the stop, so no ray is carried
    invalid through the lens (where a stale far-away ray can make the gradient NaN).
    """
    dtype = lens.epd.dtype
    field = field_of(lens, xy)
    obj = sampling.object_point(lens, field, object_depth(lens, depth))
    # The chief ray rides along as the first ray of every channel (one trace to compile).
    pts = jnp.concatenate([jnp.zeros((1, 2), dtype), pupil_disc(pupil, key, dtype)])

    def one(wl):
        rays = sampling.point_source(lens, obj, pts, wl)
        out = trace(lens, rays)
        w = jnp.where(out.valid, rays.direction[:, 2] ** 4, 0.0).at[0].set(0.0)
        return out.origin[:, :2], w

    pos, w = jax.vmap(one)(jnp.asarray(wavelengths, dtype))  # [C, 1 + m, 2], [C, 1 + m]
    ref = pos[len(wavelengths) // 2, 0]  # chief ray of the middle (green) channel
    k = jax.vmap(lambda p, ww: _psf.splat(p - ref, ww, kernel_size, pixel_size))(pos, w)
    return k / jnp.maximum(jnp.sum(k, axis=(-1, -2), keepdims=True), 1e-12)


def conv_valid(window: Float[Array, "N N C"], kern: Float[Array, "C k k"]) -> Array:
    """'Valid' 2-D convolution of a window with per-channel kernels, by FFT.

    Returns ``[N − k + 1, N − k + 1, C]``; kernel pixel [i, j] is the energy landing i rows
    and j columns from the source pixel, offset by the kernel centre (a true convolution,
    as ``jaxlens.imaging.render`` applies PSFs).
    """
    n0, n1 = window.shape[0], window.shape[1]
    k = kern.shape[-1]
    kk = jnp.zeros((n0, n1, kern.shape[0]), window.dtype)
    kk = kk.at[:k, :k].set(jnp.transpose(kern, (1, 2, 0)).astype(window.dtype))
    y = jnp.fft.irfft2(
        jnp.fft.rfft2(window, axes=(0, 1)) * jnp.fft.rfft2(kk, axes=(0, 1)), s=(n0, n1), axes=(0, 1)
    )
    return y[k - 1 :, k - 1 :].astype(window.dtype)


def simulate_patch(
    lens: Lens,
    window: Float[Array, "N N 3"],
    xy,
    depth,
    key,
    *,
    kernel_size: int,
    pixel_size: float,
    pupil: int,
) -> Float[Array, "P P 3"]:
    """Sensor patch of a scene window at sensor position ``xy`` and object ``depth``.

    A ``jax.checkpoint``: its rays are traced again in the backward pass (same ``key``).
    """

    def run(lens, window, xy, depth, key):
        kern = rgb_psf(
            lens, xy, depth, kernel_size=kernel_size, pixel_size=pixel_size, pupil=pupil, key=key
        )
        return conv_valid(window, kern)

    return jax.checkpoint(run)(lens, window, xy, depth, key)


@eqx.filter_jit
def render_tiled(
    lens: Lens,
    scene: Float[Array, "S S 3"],
    depth,
    *,
    kernel_size: int,
    pixel_size: float,
    patch: int,
    pupil: int,
) -> Float[Array, "S S 3"]:
    """Whole-sensor image of ``scene`` at ``depth`` (mm from the stop), tile by tile.

    The sensor is cut into ``patch × patch`` tiles (the training patch size); each tile is
    its scene window convolved with the RGB PSF of its centre (``rgb_psf``, ``pupil²`` rays
    per channel, no jitter), exactly the training model. The scene is edge-padded by half a
    kernel. This is ``jaxlens.imaging.render``'s "psf" method without its distortion warp and
    relative-illumination shading: the PSFs are centred on the chief ray, so the image stays
    aligned with the scene (the paper's distortion relaxation), and a shift-invariant
    network could not undo shading that depends on the position in the frame.
    """
    res = lens.sensor.resolution
    if scene.shape[:2] != tuple(res):
        raise ValueError(f"render_tiled: scene {scene.shape[:2]} must match the sensor {res}")
    h = kernel_size // 2
    n_ty, n_tx = -(-res[0] // patch), -(-res[1] // patch)
    ph, pw = n_ty * patch - res[0], n_tx * patch - res[1]
    padded = jnp.pad(scene, ((h, h + ph), (h, h + pw), (0, 0)), mode="edge")
    win = patch + 2 * h

    def tile(t):
        ty, tx = t // n_tx, t % n_tx
        r0, c0 = ty * patch, tx * patch
        window = jax.lax.dynamic_slice(padded, (r0, c0, 0), (win, win, scene.shape[-1]))
        rc = (r0 + 0.5 * (patch - 1)).astype(scene.dtype)
        cc = (c0 + 0.5 * (patch - 1)).astype(scene.dtype)
        x, y = pixel_positions(res, pixel_size, rc, cc)
        kern = rgb_psf(
            lens,
            jnp.stack([x, y]),
            depth,
            kernel_size=kernel_size,
            pixel_size=pixel_size,
            pupil=pupil,
        )
        return conv_valid(window, kern)

    tiles = jax.lax.map(tile, jnp.arange(n_ty * n_tx))
    img = tiles.reshape(n_ty, n_tx, patch, patch, -1).transpose(0, 2, 1, 3, 4)
    return img.reshape(n_ty * patch, n_tx * patch, -1)[: res[0], : res[1]]


def render_library(
    lens: Lens, scene, depth, key, *, kernel_size: int, spp: int = 1, patch: int = 64
):
    """The same image through ``jaxlens.imaging.render`` (method "psf", checkpointed tiles) on the
    pre-warped scene (``jaxlens.imaging.render.relaxed_render``), without shading: a
    cross-check of ``render_tiled`` by an independent code path."""
    from ...imaging.render import PSFRender, relaxed_render

    img, _ = relaxed_render(
        lens,
        scene,
        spp=spp,
        key=key,
        depth=object_depth(lens, depth),
        method=PSFRender(kernel_size=kernel_size),
        patch=patch,
        checkpoint=True,
        relative_illumination=False,
    )
    return img


# --------------------------------------------------------------------------------------
# PSF analysis
# --------------------------------------------------------------------------------------
@eqx.filter_jit
def _psf_points(lens, pts, depth, *, kernel_size, pixel_size, pupil):
    return jax.vmap(
        lambda p: rgb_psf(
            lens, p, depth, kernel_size=kernel_size, pixel_size=pixel_size, pupil=pupil
        )
    )(pts)


def psf_stack(
    lens: Lens, points, depths_mm, *, kernel_size: int, pixel_size: float, pupil: int = 128
) -> np.ndarray:
    """RGB PSFs ``[D, F, 3, k, k]`` at ``depths_mm`` (from the stop) and sensor ``points``
    ``[F, 2]`` (mm), without jitter."""
    pts = jnp.asarray(points, lens.epd.dtype)
    return np.stack(
        [
            np.asarray(
                _psf_points(
                    lens,
                    pts,
                    jnp.asarray(d, pts.dtype),
                    kernel_size=kernel_size,
                    pixel_size=pixel_size,
                    pupil=pupil,
                )
            )
            for d in depths_mm
        ]
    )


def psf_depth_variation(stack: np.ndarray) -> dict:
    """How much PSFs change with depth: the paper's EDoF property, as numbers.

    For every field and every pair of depths (i < j) of ``stack`` ``[D, F, C, k, k]``
    (each PSF with unit sum), it takes the L1 distance Σ|p_i − p_j| (0 for equal PSFs,
    2 for disjoint ones) and the normalised cross-correlation
    ⟨p_i − p̄_i, p_j − p̄_j⟩ / (‖p_i − p̄_i‖‖p_j − p̄_j‖) at zero shift, per colour channel.

    Returns:
        ``{"l1": mean L1 over fields, depth pairs and channels, "ncc": mean NCC,
        "l1_per_field": [F], "ncc_per_field": [F]}``; a depth-invariant lens has a small
        ``l1`` and an ``ncc`` near 1.
    """
    s = np.asarray(stack, np.float64)
    d = s.shape[0]
    l1, ncc = [], []
    for i in range(d):
        for j in range(i + 1, d):
            a, b = s[i], s[j]  # [F, C, k, k]
            l1.append(np.abs(a - b).sum(axis=(-1, -2)))
            am = a - a.mean(axis=(-1, -2), keepdims=True)
            bm = b - b.mean(axis=(-1, -2), keepdims=True)
            num = (am * bm).sum(axis=(-1, -2))
            den = np.sqrt((am * am).sum(axis=(-1, -2)) * (bm * bm).sum(axis=(-1, -2)))
            ncc.append(num / np.maximum(den, 1e-30))
    l1a, ncca = np.stack(l1), np.stack(ncc)  # [pairs, F, C]
    return {
        "l1": float(l1a.mean()),
        "ncc": float(ncca.mean()),
        "l1_per_field": l1a.mean(axis=(0, 2)).tolist(),
        "ncc_per_field": ncca.mean(axis=(0, 2)).tolist(),
    }


def diagonal_points(lens: Lens, fractions=(0.0, 0.5, 1.0)) -> np.ndarray:
    """Sensor points (mm) along the sensor diagonal at fractions of the half-diagonal."""
    h, w = lens.sensor.size
    corner = 0.5 * np.array([float(w), float(h)])
    return np.array([f * corner for f in fractions])


def grid_points(lens: Lens, n: int = 3) -> np.ndarray:
    """An ``n × n`` grid of sensor points (mm), corner pixel to corner pixel."""
    s = lens.sensor
    return np.asarray(sensor_grid(s.resolution, s.pixel_size, (n, n))).reshape(-1, 2)


def mtf_by_depth(lens: Lens, xy, depths_mm, *, frequencies, pupil: int = 96):
    """Tangential and sagittal polychromatic MTF at sensor point ``xy`` for each depth.

    Returns ``(frequencies [F] cycles/mm, tangential [D, F], sagittal [D, F])`` from
    ``jaxlens.imaging.psf.mtf`` (geometric, exact ray Fourier transform, times the diffraction
    limit).
    """
    field = np.asarray(field_of(lens, jnp.asarray(xy, lens.epd.dtype)))
    tan, sag = [], []
    for d in depths_mm:
        f, t, s = _psf.mtf(
            lens,
            field,
            wavelengths=jnp.asarray(WAVELENGTHS_RGB),
            depth=float(object_depth(lens, d)),
            frequencies=jnp.asarray(frequencies),
            model=_psf.GeometricPSF(pupil=pupil),
        )
        tan.append(np.asarray(t))
        sag.append(np.asarray(s))
    return np.asarray(f), np.stack(tan), np.stack(sag)


def depths_mm(depths_m=DEPTHS_M) -> np.ndarray:
    """Depths in mm from depths in m."""
    return 1e3 * np.asarray(depths_m, np.float64)
