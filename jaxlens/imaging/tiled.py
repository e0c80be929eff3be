"""Spatially varying blur by tiles: PSFs at tile centres, tiled convolution, Wiener deconvolution.

The sensor frame is cut into ``tile × tile`` pixel tiles; each tile is blurred with one PSF,
that of its centre (a piecewise-constant PSF, as ``render``'s ``PSFRender`` does). A PSF bank
(``psf_points`` at ``tile_centers``) can be computed once for a lens that does not change and
reused for any number of images, without tracing a ray again.

Conventions:
    Lengths in mm, wavelengths in µm. Images are ``[H, W, C]`` in ``render``'s orientation
    and kernels ``[C, k, k]`` in ``psf``'s (the kernel pixel [i, j] lies (i − c, j − c) pixels
    from the source, c = (k − 1)/2), so that ``convolve_tiles`` applies the PSF exactly as
    ``render`` does: out[n] = Σ_m image[n − m]·kernel[m + c].
    A sensor position (x, y) shows the field whose distortion-free image lies there
    (``aiming.ideal_to_field``) and its PSF is centred on that field's real chief ray, so
    distortion moves no content (the image stays registered with the scene).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks
from ..optics.lens import Lens
from ..tracing.forward import DEFAULT_NEWTON_ITERS
from .aiming import ideal_to_field
from .grid import kernel_side, pixel_pitch, pixel_positions
from .psf import CENTERS, DEFAULT_MODEL, AbstractPSFModel

__all__ = ["tile_counts", "tile_centers", "psf_points", "convolve_tiles", "wiener_tiles",
           "tile_evidence"]


def tile_counts(resolution, tile: int) -> tuple[int, int]:
    """Tiles per column and row, ``(n_rows, n_cols)``, of a frame cut into ``tile`` pixels.

    Raises:
        ValueError: unless ``tile`` is a positive int that divides both sides.
    """
    # Before: int() truncated 2.5 pixels and 10**9 per side passed.
    h, w = checks.grid(tuple(resolution) if isinstance(resolution, np.ndarray) else resolution,
                       "tile_counts", "resolution", "pixels", hi=checks.MAX_IMAGE_SIDE)
    tile = checks.static_int(tile)  # a numpy integer is a whole number too
    if isinstance(tile, bool) or not isinstance(tile, int) or tile < 1 or h % tile or w % tile:
        raise ValueError(f"tile_counts: tile must be a positive int dividing the frame "
                         f"{h}x{w} (pixels), got {tile!r}")
    return h // tile, w // tile


def tile_centers(resolution, pixel_size, tile: int) -> Float[Array, "ty tx 2"]:
    """Sensor (x, y) in mm of the centres of the ``tile × tile`` tiles of a frame."""
    n_ty, n_tx = tile_counts(resolution, tile)
    if not checks.is_traced(pixel_size):
        pixel_pitch(pixel_size, "tile_centers")
    rows = jnp.arange(n_ty) * tile + 0.5 * (tile - 1)
    cols = jnp.arange(n_tx) * tile + 0.5 * (tile - 1)
    rr, cc = jnp.meshgrid(rows, cols, indexing="ij")
    x, y = pixel_positions(resolution, jnp.asarray(pixel_size), rr, cc)
    return jnp.stack([x, y], -1)


def psf_points(
    lens: Lens,
    xy: Float[Array, "*b 2"],
    depth,
    *,
    wavelengths,
    kernel_size: int,
    pixel_size,
    model: AbstractPSFModel = DEFAULT_MODEL,
    key=None,
    center: str = "chief",
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, "*b w k k"]:
    """PSFs ``[*b, W, k, k]`` at sensor positions ``xy`` (mm) for an object ``depth`` mm in
    front of surface 1 (``inf`` for infinity), centred on each field's real chief ray
    (``center`` as in :func:`psf`; "pupil" saves the chief ray's aiming for a lens whose
    stop is its entrance pupil).

    Pure and traceable (``jit``, ``vmap``, ``grad`` with respect to the lens): unlike
    :func:`psf`, traced values are not checked on the host, so the lens, the positions and
    the depth may be traced; concrete positions (finite mm) and wavelengths (µm, inside the
    materials' range) are. ``model``, ``center`` and ``kernel_size`` (odd) are checked (they
    are static). Each position's field is
    ``ideal_to_field(lens, xy)``; with ``key`` every position gets its own jitter.
    """
    if not isinstance(model, AbstractPSFModel):
        raise TypeError(f"psf_points: model must be a PSF model object, got "
                        f"{type(model).__name__}")
    model.check("psf_points")
    checks.focal_image(lens, "psf_points")
    kernel_size = kernel_side(kernel_size, "psf_points")  # static: a Python int, odd
    if center not in CENTERS:  # "chef" reached the model's kernels, a KeyError or worse
        raise ValueError(f"psf_points: center must be one of {CENTERS}, got {center!r}")
    if np.ndim(xy) < 1 or np.shape(xy)[-1] != 2:
        raise ValueError(f"psf_points: xy must be sensor positions [..., 2] (x, y) in mm, got "
                         f"shape {np.shape(xy)}")
    checks.real_values(xy, "xy", "psf_points", "mm")
    checks.real_values(wavelengths, "wavelengths", "psf_points", "µm")
    if not checks.is_traced(xy):  # host checks of concrete values only (see above)
        checks.finite_array(xy, "xy", "psf_points", "mm")
    if not checks.is_traced(wavelengths):  # 550 for 0.55 µm: the nm hint
        checks.wavelengths(lens, jnp.atleast_1d(jnp.asarray(wavelengths)), "psf_points",
                           "wavelengths")
    checks.newton_iters(newton_iters, "psf_points")  # static, as kernel_size
    if not checks.is_traced(pixel_size):  # a traced pitch is not checked (see above)
        pixel_pitch(pixel_size, "psf_points")
    # Shapes only (known under jit too): every position's PSF is traced at once (vmap).
    points = math.prod(np.shape(xy)[:-1]) * np.size(wavelengths) * model.pupil ** 2
    checks.working_memory(points, len(lens.surfaces), jnp.dtype(lens.epd.dtype).itemsize,
                          "psf_points", "positions × wavelengths × pupil²",
                          "pass fewer positions per call (xy), or a smaller model pupil")
    dtype = lens.epd.dtype
    xy = jnp.asarray(xy, dtype)
    wls = jnp.atleast_1d(jnp.asarray(wavelengths, dtype))
    pix = jnp.asarray(pixel_size, dtype)
    if depth is not None and not isinstance(depth, jax.core.Tracer):
        depth = None if bool(np.all(np.isinf(np.asarray(depth)))) else depth
    depth = None if depth is None else jnp.asarray(depth, dtype)
    flat = xy.reshape(-1, 2)
    keys = None if key is None else jax.random.split(key, flat.shape[0])

    def one(p, k):
        kern, *_ = model.kernels(lens, ideal_to_field(lens, p), depth, wls,
                                 kernel_size=kernel_size, pixel_size=pix, center=center,
                                 key=k, newton_iters=newton_iters)
        return kern

    out = jax.vmap(one)(flat, keys) if keys is not None else jax.vmap(lambda p: one(p, None))(
        flat)
    return out.reshape(xy.shape[:-1] + out.shape[1:])


def _conv_valid(window, kern):
    """'Valid' convolution of a ``[P+k-1, P+k-1, C]`` window with ``[C, k, k]`` kernels.

    By FFT over the window: the circular wrap-around of a kernel placed at the window's
    corner only reaches the first k − 1 rows and columns, which 'valid' drops. (FFTs also
    compile and differentiate faster under ``vmap`` than grouped convolutions on CPU.)
    """
    n0, n1 = window.shape[0], window.shape[1]
    k = kern.shape[-1]
    kk = jnp.zeros((kern.shape[0], n0, n1), window.dtype)
    kk = kk.at[:, :k, :k].set(kern.astype(window.dtype))
    y = jnp.fft.irfft2(jnp.fft.rfft2(window.transpose(2, 0, 1)) * jnp.fft.rfft2(kk),
                       s=(n0, n1))
    return y[:, k - 1:, k - 1:].transpose(1, 2, 0).astype(window.dtype)


def _windows(image, n_ty, n_tx, tile, halo):
    """The ``[n_ty·n_tx, tile + 2·halo, tile + 2·halo, C]`` windows of a padded image."""
    win = tile + 2 * halo
    r0 = jnp.repeat(jnp.arange(n_ty) * tile, n_tx)
    c0 = jnp.tile(jnp.arange(n_tx) * tile, n_ty)
    zero = jnp.zeros((), r0.dtype)
    return jax.vmap(lambda r, c: jax.lax.dynamic_slice(
        image, (r, c, zero), (win, win, image.shape[-1])))(r0, c0)


def _assemble(tiles, n_ty, n_tx):
    t = tiles.reshape((n_ty, n_tx) + tiles.shape[1:])
    return t.transpose(0, 2, 1, 3, 4).reshape(n_ty * t.shape[2], n_tx * t.shape[3], -1)


def _bank_shape(kernels) -> str:
    """What sets the tile count of a tiling refusal: the kernel bank's shape (the message
    named a tile count without its source)."""
    return (f" (kernels is [ty, tx, C, k, k] = {list(kernels.shape)}: one kernel per tile; "
            f"give a bank of as many tiles as the frame holds)")


def _check_bank(image, kernels, caller):
    """The image and the kernel bank as arrays, checked: shapes, a float image (an integer
    one was blurred in integer arithmetic: the kernels truncated to 0), and finite values
    (one NaN kernel pixel made its whole tile NaN; concrete values only).
    Use the returned arrays."""
    checks.image_dtype(image, caller, "image", "linear pixel values")
    image, kernels = jnp.asarray(image), jnp.asarray(kernels)
    if not jnp.issubdtype(kernels.dtype, jnp.floating):
        kernels = kernels.astype(image.dtype)  # integer weights are exact as floats
    if image.ndim != 3:
        raise ValueError(f"{caller}: image must be [H, W, C], got shape {image.shape}")
    if kernels.ndim != 5 or kernels.shape[2] != image.shape[-1] or \
            kernels.shape[-1] != kernels.shape[-2] or kernels.shape[-1] % 2 == 0:
        raise ValueError(f"{caller}: kernels must be [tiles_y, tiles_x, C, k, k] with C = "
                         f"{image.shape[-1]} channels and k odd, got {kernels.shape}")
    # Concrete values only: a traced bank (a training step's) would carry host callbacks
    # into every step, where a NaN shows in the loss anyway.
    if not checks.is_traced(image):
        checks.finite_array(image, "image", caller, "linear pixel values")
    if not checks.is_traced(kernels):
        checks.finite_array(kernels, "kernels", caller, "PSF weights")
    return image, kernels


def convolve_tiles(
    image: Float[Array, "H W C"], kernels: Float[Array, "ty tx C k k"], *, pad: str = "edge"
) -> Float[Array, "h w C"]:
    """Blur an image tile by tile: tile (i, j) is convolved with ``kernels[i, j]``.

    Args:
        image: ``[H, W, C]``. With ``pad="edge"`` its sides are ``ty·P`` and ``tx·P`` (P the
            tile side) and it is edge-padded by k // 2 pixels; with ``pad="valid"`` it already
            holds that margin (sides ``ty·P + k − 1``), e.g. a scene window around a patch.
        kernels: ``[ty, tx, C, k, k]`` PSFs in ``psf``'s orientation, k odd. Their sums are
            kept: a kernel that holds 0.9 of the light darkens its tile by 10 %.
        pad: "edge" or "valid".

    Returns:
        ``[ty·P, tx·P, C]``, differentiable with respect to the image and the kernels.
    """
    image, kernels = _check_bank(image, kernels, "convolve_tiles")
    n_ty, n_tx, _, k, _ = kernels.shape
    h = k // 2
    if pad == "edge":
        image = jnp.pad(image, ((h, h), (h, h), (0, 0)), mode="edge")
    elif pad != "valid":
        raise ValueError(f"convolve_tiles: pad must be 'edge' or 'valid', got {pad!r}")
    rows, cols = image.shape[0] - 2 * h, image.shape[1] - 2 * h
    if rows % n_ty or cols % n_tx or rows // n_ty != cols // n_tx:
        raise ValueError(f"convolve_tiles: a {rows}x{cols} frame does not split into "
                         f"{n_ty}x{n_tx} square tiles{_bank_shape(kernels)}")
    tile = rows // n_ty
    wins = _windows(image, n_ty, n_tx, tile, h)
    out = jax.vmap(_conv_valid)(wins, kernels.reshape((-1,) + kernels.shape[2:]))
    return _assemble(out, n_ty, n_tx)


def _spectra(image, kernels, nsr, halo, prior, caller, pad, taper=False):
    """Each tile window's spectra for a Wiener filter: ``(K, Y, R, tile, halo)``, K and Y
    ``[T, C, win, win//2 + 1]`` (rfft2), R = nsr·P the filter's regulariser (see
    ``wiener_tiles``)."""
    image, kernels = _check_bank(image, kernels, caller)
    n_ty, n_tx, nc, k, _ = kernels.shape
    # int(2.5) was 2 and int(True) 1; a ratio of 0 divided 0 by 0 where |K| = 0 (NaN tiles),
    # a negative one flipped the filter's sign there, NaN or inf made every tile NaN or 0.
    halo = k if halo is None else checks.number(halo, "halo", caller, lo=0, integer=True,
                                                unit="pixels")
    checks.real_values(nsr, "nsr", caller, "noise-to-signal power ratio")
    if not checks.is_traced(nsr):  # a learned ratio (the EDoF decoder's) is its own param.
        checks.values(nsr, "nsr", caller, lo=0, lo_open=True,
                      unit="(noise-to-signal power ratio)")
    if halo < k // 2:
        raise ValueError(f"{caller}: halo must be at least k // 2 = {k // 2} pixels, got "
                         f"{halo}")
    if pad not in ("edge", "valid"):
        raise ValueError(f"{caller}: pad must be 'edge' or 'valid', got {pad!r}")
    margin = 2 * halo if pad == "valid" else 0
    rows, cols = image.shape[0] - margin, image.shape[1] - margin
    if rows <= 0 or rows % n_ty or cols % n_tx or rows // n_ty != cols // n_tx:
        extra = f" inside its {halo}-pixel margin" if margin else ""
        raise ValueError(f"{caller}: a {image.shape[0]}x{image.shape[1]} frame{extra} does "
                         f"not split into {n_ty}x{n_tx} square tiles{_bank_shape(kernels)}")
    tile = rows // n_ty
    win = tile + 2 * halo
    padded = (image if margin else
              jnp.pad(image, ((halo, halo), (halo, halo), (0, 0)), mode="edge"))
    wins = _windows(padded, n_ty, n_tx, tile, halo)  # [T, win, win, C]
    # The kernel's centre pixel goes to index 0 of the window (circular convolution).
    c = k // 2
    kk = jnp.zeros((kernels.shape[0] * n_tx, nc, win, win), image.dtype)
    kk = kk.at[:, :, :k, :k].set(kernels.reshape(-1, nc, k, k).astype(image.dtype))
    kk = jnp.roll(kk, (-c, -c), axis=(-2, -1))
    kf = jnp.fft.rfft2(kk)  # [T, C, win, win//2+1]
    if taper:
        # A Hann window, so that the circular model's wrap-around edge adds no false detail;
        # the mean goes first, or its leak would look like low-frequency signal.
        hann = jnp.sin(jnp.pi * (jnp.arange(win) + 0.5) / win).astype(image.dtype) ** 2
        wins = wins - wins.mean((1, 2), keepdims=True)
        wins = wins * (hann[:, None] * hann[None, :])[None, :, :, None]
    yf = jnp.fft.rfft2(wins.transpose(0, 3, 1, 2))
    reg = jnp.broadcast_to(jnp.asarray(nsr, image.dtype), (nc,))[None, :, None, None]
    if prior == "gradient":
        wy = 2 * jnp.pi * jnp.fft.fftfreq(win)[:, None]
        wx = 2 * jnp.pi * jnp.fft.rfftfreq(win)[None, :]
        reg = reg * (4.0 - 2.0 * jnp.cos(wy) - 2.0 * jnp.cos(wx)).astype(image.dtype)
    elif prior != "white":
        raise ValueError(f"{caller}: prior must be 'white' or 'gradient', got {prior!r}")
    return kf, yf, jnp.broadcast_to(reg, (1, nc, win, win // 2 + 1)), tile, halo


def wiener_tiles(
    image: Float[Array, "H W C"],
    kernels: Float[Array, "ty tx C k k"],
    nsr,
    *,
    halo: int | None = None,
    prior: str = "white",
    pad: str = "edge",
) -> Float[Array, "h w C"]:
    """Wiener deconvolution tile by tile with each tile's kernel.

    Each tile is deconvolved in a window of ``tile + 2·halo`` pixels (edge-padded at the frame
    border, or with ``pad="valid"`` taken from a margin that the image holds) by
    X = conj(K)·Y / (|K|² + nsr·P) in the Fourier domain, and its centre is kept; the halo
    (default the kernel side) holds the wrap-around of the circular deconvolution.
    ``prior`` sets P: "white" (P = 1, a flat signal spectrum) or "gradient" (P = |∇|², the
    power of the discrete gradient, 4 − 2·cos ωx − 2·cos ωy: a signal spectrum falling as
    1/f², as natural images do; then nsr is the noise variance over the variance of the
    image's pixel differences).
    A kernel that sums to s < 1 is inverted to a gain of about 1/s at low frequencies, so the
    light that the lens lost is restored on average.

    Args:
        image: ``[ty·P, tx·P, C]`` blurred image; with ``pad="valid"``, ``[ty·P + 2·halo,
            tx·P + 2·halo, C]``: the tiled area and a margin of real image around it (e.g. a
            training patch in its scene, so that no window holds edge copies).
        kernels: ``[ty, tx, C, k, k]`` PSFs (``psf`` orientation, k odd).
        nsr: noise-to-signal power ratio, a scalar or ``[C]`` (> 0), differentiable.
        halo: pixels around each tile (default k).
        prior: "white" or "gradient" (see above).
        pad: "edge" or "valid" (see ``image``).

    Returns:
        ``[ty·P, tx·P, C]``, differentiable with respect to the image, kernels and ``nsr``.
    """
    image = jnp.asarray(image)
    n_ty, n_tx = jnp.shape(kernels)[:2]
    kf, yf, nsr, tile, halo = _spectra(image, kernels, nsr, halo, prior, "wiener_tiles", pad)
    win = tile + 2 * halo
    xf = jnp.conj(kf) * yf / (kf.real**2 + kf.imag**2 + nsr)
    x = jnp.fft.irfft2(xf, s=(win, win)).transpose(0, 2, 3, 1)
    x = x[:, halo: halo + tile, halo: halo + tile]
    return _assemble(x, n_ty, n_tx).astype(image.dtype)


def tile_evidence(
    image: Float[Array, "H W C"],
    kernels: Float[Array, "ty tx C k k"],
    nsr,
    *,
    halo: int | None = None,
    prior: str = "gradient",
    pad: str = "edge",
) -> Float[Array, "ty tx"]:
    """How well each tile's kernel explains the image: a negative log-likelihood per tile.

    The model is ``wiener_tiles``'s, as a Gaussian process: in each tile's window the image is
    a Gaussian signal of spectrum S ∝ 1/P blurred by the kernel K plus white noise of power
    N = nsr·S·P, so each Fourier coefficient Y is complex normal with variance
    σ²·(|K|²/(nsr·P) + 1). The overall scale σ² (the noise power) is profiled out, so only
    ``nsr`` is needed: per channel, NLL = M·log Σ w·|Y|²/(g + 1) + Σ w·log(g + 1), g =
    |K|²/(nsr·P), summed over the independent frequencies where P > 0 (weights w, M = Σ w),
    then over channels. The window is Hann-tapered (its mean removed first) so that the
    wrap-around edge of the circular model does not look like detail. Compared across
    candidate kernels for the same image (e.g. the PSFs of several object depths), the
    smallest value marks the most likely blur, and exp(−NLL) normalised over the candidates
    is their posterior under this model with equal priors (depth from defocus by
    deconvolution, as in Levin et al., SIGGRAPH 2007).

    Args:
        image, kernels, nsr, halo, prior, pad: as for ``wiener_tiles`` (default prior
            "gradient").

    Returns:
        ``[ty, tx]``, differentiable; only differences between kernel sets are meaningful.
    """
    n_ty, n_tx = jnp.shape(kernels)[:2]
    kf, yf, reg, tile, halo = _spectra(image, kernels, nsr, halo, prior, "tile_evidence",
                                       pad, taper=True)
    win = tile + 2 * halo
    # A real image's spectrum holds each coefficient twice (Y(−ω) = Y(ω)*): count the rfft2
    # half once, and its columns 0 and win/2, which hold both members of their pairs, half.
    half = jnp.ones(win // 2 + 1).at[0].set(0.5)
    half = half.at[-1].set(0.5) if win % 2 == 0 else half
    w = jnp.where(reg > 0, half, 0.0).astype(reg.dtype)  # P = 0 (the mean) is unconstrained
    g = (kf.real**2 + kf.imag**2) / jnp.where(reg > 0, reg, 1.0)
    power = (yf.real**2 + yf.imag**2) / (g + 1.0)
    m = jnp.sum(w, (-2, -1))
    nll = m * jnp.log(jnp.sum(w * power, (-2, -1))) + jnp.sum(w * jnp.log1p(g), (-2, -1))
    return nll.sum(-1).reshape(n_ty, n_tx)
