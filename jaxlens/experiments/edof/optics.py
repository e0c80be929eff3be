"""Image formation for the EDoF experiment, through ``jaxlens.imaging``: PSFs, banks, noise.

Conventions:
    Lengths in mm, wavelengths in µm, depths in mm from the aperture stop
    (``lenses.object_depth`` converts them). Images are ``[H, W, 3]`` linear RGB in
    ``jaxlens.imaging.render``'s orientation, one wavelength per channel (``WAVELENGTHS_RGB``).

The sensor frame is cut into ``tile × tile`` pixel tiles (``jaxlens.imaging.tiled``); each tile
is blurred with the PSF of its centre, and a training patch is one tile. A PSF comes from
``jaxlens.imaging.tiled.psf_points`` with the model of ``psf_model``: geometric, rays on an
equal-area polar grid strictly inside the entrance pupil (a stop-first lens loses none of
them at the stop, so no invalid ray is traced and no gradient turns NaN), normalised by the
flux that enters the entrance pupil. A PSF's sum is therefore the fraction of that light
that lands in the kernel: light lost to vignetting or thrown outside the kernel is lost to
the image, and a lens cannot gain by spreading light beyond the kernel.

A lens that does not change has a PSF bank (``psf_bank``: 8 depths × all tiles), computed
once without gradients; a lens being trained gets its PSFs per batch (``patch_psfs``).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ...imaging import tiled
from ...imaging.psf import GeometricPSF
from ...optics import checks
from ...optics.lens import Lens
from .lenses import DEPTHS_M, WAVELENGTHS_RGB, object_depth


def psf_model(pupil: int) -> GeometricPSF:
    """The PSF model: ``pupil²`` rays on a polar grid inside the entrance pupil, splatted with
    the quadratic B-spline (integrated over the pixel), normalised by the entering light."""
    return GeometricPSF(pupil=pupil, overfill=1.0, order=2, grid="polar", normalize="pupil")


def patch_psfs(lens: Lens, xy, depths, *, kernel_size: int, pixel_size, pupil: int,
               key=None) -> Float[Array, "n 3 k k"]:
    """RGB PSFs at sensor points ``xy [N, 2]`` (mm) for objects ``depths [N]`` mm from the stop.

    Differentiable with respect to the lens (``jaxlens.imaging.tiled.psf_points``).
    """
    model = psf_model(pupil)
    # The stop-first lens's entrance pupil is its stop: the ray through the pupil centre is
    # the chief ray (traced with the beam, no aiming iterations to compile).
    center = "pupil" if lens.stop == 0 else "chief"
    keys = None if key is None else jax.random.split(key, xy.shape[0])

    def one(p, d, k):
        return tiled.psf_points(lens, p[None], object_depth(lens, d), wavelengths=WAVELENGTHS_RGB,
                                kernel_size=kernel_size, pixel_size=pixel_size, model=model,
                                key=k, center=center)[0]

    if keys is None:
        return jax.vmap(lambda p, d: one(p, d, None))(xy, depths)
    return jax.vmap(one)(xy, depths, keys)


@eqx.filter_jit
def psfs_nograd(lens: Lens, xy, depths, pixel_size, *, kernel_size: int, pupil: int):
    """``patch_psfs`` of a lens held constant: the forward trace only, no gradient."""
    return patch_psfs(jax.lax.stop_gradient(lens), xy, depths, kernel_size=kernel_size,
                      pixel_size=pixel_size, pupil=pupil)


def centers(lens: Lens, tile: int) -> np.ndarray:
    """Sensor points (mm) of the tile centres, ``[ty, tx, 2]``."""
    s = lens.sensor
    return np.asarray(tiled.tile_centers(s.resolution, s.pixel_size, tile))


def psf_bank(lens: Lens, *, tile: int, kernel_size: int, pupil: int, chunk: int,
             depths_m=DEPTHS_M) -> np.ndarray:
    """PSFs ``[D, ty, tx, 3, k, k]`` of every tile at every depth, without gradients.

    Computed ``chunk`` PSFs at a time through ``psfs_nograd``, so that a bank and the training
    steps (``2 × batch`` PSFs each) share one compiled program.
    """
    xy = centers(lens, tile)
    ty, tx = xy.shape[:2]
    dm = 1e3 * np.asarray(depths_m, np.float64)
    pts = np.tile(xy.reshape(-1, 2), (len(dm), 1))
    ds = np.repeat(dm, ty * tx)
    n = pts.shape[0]
    pad = (-n) % chunk
    pts = np.concatenate([pts, pts[:pad]])
    ds = np.concatenate([ds, ds[:pad]])
    dt = lens.epd.dtype
    pix = jnp.asarray(lens.sensor.pixel_size, dt)
    out = [np.asarray(psfs_nograd(lens, jnp.asarray(pts[i:i + chunk], dt),
                                  jnp.asarray(ds[i:i + chunk], dt), pix,
                                  kernel_size=kernel_size, pupil=pupil))
           for i in range(0, n + pad, chunk)]
    return np.concatenate(out)[:n].reshape((len(dm), ty, tx) + out[0].shape[1:])


def light_on_sensor(bank: np.ndarray) -> float:
    """Mean fraction of the light entering the entrance pupil that lands in the kernels."""
    return float(np.mean(np.sum(bank, axis=(-1, -2))))


def simulate(windows: Float[Array, "b n n 3"], kernels: Float[Array, "2 b 3 k k"]) -> Array:
    """``[2, B, P, P, 3]`` sensor patches: each scene window (patch plus a kernel's margin)
    blurred with its kernel at each of the two depths (``tiled.convolve_tiles``, 'valid')."""

    def one(w, k):
        return tiled.convolve_tiles(w, k[None, None], pad="valid")

    return jax.vmap(jax.vmap(one), in_axes=(None, 0))(windows, kernels)


def add_noise(x, key, *, photons: float, read: float):
    """Shot and read noise (Gaussian approximations): variance x / photons + read².

    ``photons`` is the number of photo-electrons of a pixel at the linear value 1 (the shot
    noise of a value x has variance x / photons); ``read`` is the read-noise standard deviation
    in the same units as x. The same key gives the same normal draws for every lens, so
    comparisons between lenses are paired.
    """
    if not checks.is_traced((photons, read)):  # photons 0 gave NaN, a negative one less noise
        checks.number(photons, "photons", "add_noise", lo=0, lo_open=True,
                      unit="electrons at the linear value 1")
        checks.number(read, "read", "add_noise", lo=0, unit="(linear units)")
    var = jnp.maximum(x, 0.0) / photons + read * read
    return x + jnp.sqrt(var) * jax.random.normal(key, x.shape, x.dtype)


# --------------------------------------------------------------------------------------
# PSF analysis
# --------------------------------------------------------------------------------------
def psf_depth_variation(stack: np.ndarray) -> dict:
    """How much PSFs change with depth: the paper's EDoF property, as numbers.

    For every field and every pair of depths (i < j) of ``stack`` ``[D, F, C, k, k]``, each
    PSF rescaled to unit sum (the shape, not the light lost, is compared), it takes the L1
    distance Σ|p_i − p_j| (0 for equal PSFs, 2 for disjoint ones) and the normalised
    cross-correlation ⟨p_i − p̄_i, p_j − p̄_j⟩ / (‖p_i − p̄_i‖‖p_j − p̄_j‖) at zero shift, per
    colour channel.

    Returns:
        ``{"l1": mean L1 over fields, depth pairs and channels, "ncc": mean NCC,
        "l1_per_field": [F], "ncc_per_field": [F]}``; a depth-invariant lens has a small
        ``l1`` and an ``ncc`` near 1.
    """
    s = np.asarray(stack, np.float64)
    s = s / np.maximum(s.sum(axis=(-1, -2), keepdims=True), 1e-30)
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


def bank_mtf(bank: np.ndarray, pixel_size: float):
    """Polychromatic MTF along x and y of each PSF of a bank ``[..., 3, k, k]``, from the
    pixel-sampled kernel (each rescaled to unit sum). Returns ``(cycles/mm [m], mtf_x [..., m],
    mtf_y [..., m])`` up to the Nyquist frequency."""
    b = np.asarray(bank, np.float64)
    b = b / np.maximum(b.sum(axis=(-1, -2), keepdims=True), 1e-30)
    k = b.shape[-1]
    f = np.abs(np.fft.rfft2(b, axes=(-2, -1)))  # [..., 3, k, k//2+1]
    m = k // 2 + 1
    mx = f[..., 0, :m].mean(axis=-2)
    my = np.abs(np.fft.rfft(b.sum(axis=-1), axis=-1))[..., :m].mean(axis=-2)
    freqs = np.arange(m) / (k * pixel_size)
    return freqs, mx, my
