"""Evaluation of the EDoF experiment (Table 2): per-crop metrics, the Wiener reference, gains.

Every test crop (``scenes.test_crops``: native resolution, with a margin of real scene) is
placed on the sensor frame at one of its ``crop / tile``-tile blocks, in turn (crop i at
block i mod n_blocks), so the crops together sample the whole field. It is blurred tile by
tile with the lens's PSF bank at the test depth (``jaxlens.imaging.tiled.convolve_tiles``),
noise is added (the same draws for every lens: paired comparisons), and three images are
scored against the crop: the raw simulation ("sim"), the decoder's reconstruction ("rec")
and, as a non-learned reference, the raw image deconvolved by a Wiener filter with the
lens's depth-averaged PSF, a gradient prior and the noise-model NSR ("wiener"). Images are
clipped to [0, 1] and scored in linear light (PSNR, SSIM of ``jaxlens.io.images``).

Gains against the classical lens are paired differences of reconstruction PSNR on the same
crops, averaged over the training seeds; their 95 % interval is a two-level bootstrap
(seeds and crops drawn with replacement), so it carries both the seed-to-seed and the
crop-to-crop spread.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...imaging.tiled import convolve_tiles, wiener_tiles
from ...optics import checks
from .lenses import DEPTHS_M
from .optics import add_noise


@eqx.filter_jit
def _one(dec, window, kern, front_kern, mean_kern, key, nsr, photons, read):
    sim = convolve_tiles(window, kern, pad="valid")
    noisy = add_noise(sim, key, photons=photons, read=read)
    rec = dec(noisy, front_kern)
    wien = wiener_tiles(noisy, mean_kern, nsr, prior="gradient")
    return tuple(jnp.clip(x, 0.0, 1.0) for x in (noisy, rec, wien))


def placements(n: int, frame_tiles: tuple[int, int], crop_tiles: int) -> list[tuple[int, int]]:
    """Top-left tile of crop i: the frame's disjoint blocks of ``crop_tiles`` tiles in turn."""
    n = checks.number(n, "n", "placements", lo=0, integer=True, unit="crops")
    br, bc = frame_tiles[0] // crop_tiles, frame_tiles[1] // crop_tiles
    if br < 1 or bc < 1:
        raise ValueError(f"placements: a crop of {crop_tiles} tiles does not fit the frame of "
                         f"{frame_tiles} tiles")
    return [((i % (br * bc)) // bc * crop_tiles, (i % (br * bc)) % bc * crop_tiles)
            for i in range(n)]


def evaluate(dec, bank: np.ndarray, windows: np.ndarray, *, cfg, key, nsr: float,
             depths_m=(0.1, 0.2, 10.0), keep: int | None = None):
    """Per-crop PSNR/SSIM of the raw image, the reconstruction and the Wiener reference.

    Args:
        dec: the trained decoder.
        bank: the lens's PSF bank ``[8, ty, tx, 3, k, k]`` (``optics.psf_bank``, the 8
            training depths).
        windows: test crops with their margin (``scenes.test_crops``), ``[N, S, S, 3]``.
        key: PRNG key of the noise (use the same for every lens).
        nsr: the Wiener reference's noise-to-signal ratio.
        depths_m: test depths, among the training depths (m from the stop).
        keep: index of a crop whose images to return.

    Returns:
        ``(values, examples)``: values[depth][kind][metric] = list over crops (kind "sim",
        "rec", "wiener"; metric "psnr", "ssim"); examples[depth] = (sim, rec, wiener) of
        crop ``keep``.
    """
    from ...io.images import psnr, ssim

    k = bank.shape[-1]
    m = k // 2
    size = windows.shape[1] - 2 * m
    ct = size // cfg.tile
    if ct * cfg.tile != size:
        raise ValueError(f"evaluate: crops of {size} pixels are not whole tiles of {cfg.tile}")
    place = placements(len(windows), bank.shape[1:3], ct)
    mean = bank.mean(0)
    front = np.asarray(dec.front_kernels(bank)) if dec.wiener else mean[None]
    dt = jnp.float32
    values, examples = {}, {}
    for d in depths_m:
        di = list(DEPTHS_M).index(d)
        v = {t: {"psnr": [], "ssim": []} for t in ("sim", "rec", "wiener")}
        for i, w in enumerate(windows):
            r, c = place[i]
            kern = jnp.asarray(bank[di, r:r + ct, c:c + ct], dt)
            mk = jnp.asarray(mean[r:r + ct, c:c + ct], dt)
            fk = jnp.asarray(front[:, r:r + ct, c:c + ct], dt)
            outs = _one(dec, jnp.asarray(w, dt), kern, fk, mk,
                        jax.random.fold_in(jax.random.fold_in(key, i), di),
                        jnp.asarray(nsr, dt), cfg.photons, cfg.read_noise)
            gt = np.asarray(w[m:m + size, m:m + size], np.float64)
            outs = [np.asarray(x, np.float64) for x in outs]
            for tag, x in zip(("sim", "rec", "wiener"), outs, strict=True):
                v[tag]["psnr"].append(psnr(gt, x, data_range=1.0))
                v[tag]["ssim"].append(ssim(gt, x, data_range=1.0))
            if keep is not None and i == keep:
                examples[depth_key(d)] = tuple(outs)
        values[depth_key(d)] = v
    return values, examples


def depth_key(d) -> str:
    """'0.1', '0.2', '10' for depths in m."""
    return f"{float(d):g}"


MAX_REPLICATES = 10**6
"""Most bootstrap replicates (4000 give the 95 % interval's ends to about 1 %)."""


def _paired_differences(diff, n, seed, where: str) -> np.ndarray:
    """``diff [seeds, crops]`` as finite float64, with ``n`` replicates and ``seed`` checked
    (before: a 1-D diff failed to unpack, ``n=0`` raised IndexError, NaN gave a NaN interval)."""
    checks.real_values(diff, "diff", where, "dB")
    d = np.asarray(diff, np.float64)
    if d.ndim != 2 or 0 in d.shape:
        raise ValueError(f"{where}: diff must be [seeds, crops] with at least one of each (a "
                         f"single seed as [1, crops]), got shape {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError(f"{where}: diff must be finite, got {int(np.sum(~np.isfinite(d)))} "
                         f"NaN or infinite value(s)")
    checks.number(n, "n", where, lo=1, hi=MAX_REPLICATES, integer=True, unit="replicates")
    checks.numpy_seed(seed, where)
    return d


def bootstrap_gain(diff: np.ndarray, *, n: int = 4000, seed: int = 0) -> dict:
    """Mean and two-level bootstrap 95 % interval of paired differences ``diff [seeds, crops]``.

    Each replicate draws the seeds and then the crops with replacement and averages; with
    one seed only the crops are resampled.
    """
    diff = _paired_differences(diff, n, seed, "bootstrap_gain")
    s, c = diff.shape
    rng = np.random.default_rng(seed)
    si = rng.integers(0, s, (n, s)) if s > 1 else np.zeros((n, 1), int)
    ci = rng.integers(0, c, (n, c))
    reps = diff[si[:, :, None], ci[:, None, :]].mean(axis=(1, 2))
    lo, hi = np.percentile(reps, [2.5, 97.5])
    return {"mean": float(diff.mean()), "ci95": [float(lo), float(hi)]}


def bootstrap_gain_by_image(diff: np.ndarray, images, *, n: int = 4000, seed: int = 0) -> dict:
    """Like ``bootstrap_gain``, but every test image weighs the same, whatever its crop count.

    The mean is that of the per-image means (crops of one image averaged first, then seeds).
    Each replicate draws the seeds, then the images, then the crops within each drawn image,
    all with replacement. A test set with most crops from one large image (``scenes``:
    24 of 48 from retina) is then not summarised by that image alone.
    """
    diff = _paired_differences(diff, n, seed, "bootstrap_gain_by_image")
    images = np.asarray(images)
    if images.shape != (diff.shape[1],):
        raise ValueError(f"bootstrap_gain_by_image: {diff.shape[1]} crops but "
                         f"{images.shape} image labels")
    groups = [np.flatnonzero(images == name) for name in dict.fromkeys(images.tolist())]
    s, g = diff.shape[0], len(groups)
    rng = np.random.default_rng(seed)
    reps = np.empty(n)
    for r in range(n):
        rows = diff[rng.integers(0, s, s)] if s > 1 else diff
        picks = rng.integers(0, g, g)
        reps[r] = np.mean([rows[:, groups[i][rng.integers(0, len(groups[i]),
                                                           len(groups[i]))]].mean()
                           for i in picks])
    lo, hi = np.percentile(reps, [2.5, 97.5])
    mean = float(np.mean([diff[:, idx].mean() for idx in groups]))
    return {"mean": mean, "ci95": [float(lo), float(hi)]}


NSR_SCALE = 3.0
"""The Wiener filters' NSR over the noise-model value (``wiener_nsr``): chosen from
{0.1, 0.3, 1, 3} on the validation images (``scenes.VAL_IMAGES``) for the classical lens,
before any training run (the noise model's value under-regularises: the shot noise varies
over the image and the depth-averaged PSF is not the PSF of any one depth)."""


def wiener_nsr(windows: np.ndarray, *, photons: float, read: float) -> float:
    """The noise-to-signal ratio of a gradient-prior Wiener filter from the noise model and
    training windows: ``NSR_SCALE`` times the mean noise variance over the mean square of the
    scene's pixel differences (horizontal and vertical, averaged)."""
    where = "wiener_nsr"
    photons = checks.number(photons, "photons", where, lo=0, lo_open=True,
                            unit="electrons at the linear value 1")
    read = checks.number(read, "read", where, lo=0, unit="(linear units)")
    if np.ndim(windows) < 3 or min(np.shape(windows)[-3:-1]) < 2:
        raise ValueError(f"{where}: windows must be [..., H, W, 3] with H, W >= 2, got shape "
                         f"{np.shape(windows)}")
    w = checks.float_image(windows, where, "windows", lo=0.0, hi=1.0, unit="linear values")
    noise = np.mean(np.maximum(w, 0.0) / photons + read * read)
    dx = np.diff(w, axis=-2)
    dy = np.diff(w, axis=-3)
    grad = 0.5 * (np.mean(dx * dx) + np.mean(dy * dy))
    return float(NSR_SCALE * noise / max(grad, 1e-12))
