"""Dead-leaves images: a procedural training set with the statistics of natural images.

The dead-leaves model (Matheron, 1968; as a model of natural images: Lee, Mumford & Huang,
"Occlusion models for natural images", IJCV 41, 2001) stacks opaque discs of random colour
at uniformly random positions until the plane is covered, each disc hiding those below it.
With disc radii drawn from p(r) ∝ r⁻³ between ``r_min`` and ``r_max`` the image is close to
scale invariant, with a power spectrum near 1/f² and sharp occluding edges, as photographs
have. Restoration networks trained on such images come close to ones trained on photographs
(Achddou, Gousseau & Ladjal, "Synthetic images as a regularity prior for image restoration
neural networks", SSVM 2021). The EDoF experiment uses them because the eight photographs
of ``skimage.data`` that it trains on are few and unlike its test images (``NOTES.md``).

This generator's choices: radii from ``R_MIN_PX`` (its docstring says why) to a quarter of
the image side; colours uniform in a cube of sRGB values about mid-grey (``contrast``: 1 is
the whole cube), decoded to linear light; flat discs (no texture inside one); the discs
drawn front to back, each covering only what the ones in front left visible, until every
pixel is covered to within ``1e-3`` of its light (the exact model, not a fixed count); edges
anti-aliased by the pixel area a disc covers, approximated by a one-pixel ramp across its
rim.
"""

from __future__ import annotations

import numpy as np

from ...io.images import srgb_to_linear
from ...optics import checks

R_MIN_PX = 2.0
"""Smallest disc radius (pixels). It sets how much detail there is at the pixel scale, i.e.
the slope of the power spectrum: measured on 128² crops (Hann window, radial frequencies 3
to 50 cycles), the six photographs of the training and validation sets (``scenes``) have
median slopes −3.18, −2.89, −2.62, −1.87 (train), −4.18, −2.47 (validation), median −2.75;
dead leaves give −2.24 / −2.56 / −2.72 / −2.90 with r_min 1 / 1.5 / 2 / 3 pixels. The test
images were not looked at for this choice."""

MAX_SIDE = 4096
"""Largest image side (pixels) this generator takes (512² takes about 1 s on one core)."""

MAX_PIXELS = 2**28
"""Most pixels ``dead_leaves_images`` makes in one call (1024 images of 512², 16 of 4096²:
3 GiB of float32 RGB and about 1 s per 512² image)."""

_LEFT_OVER = 1e-3
"""Stop when no pixel has more than this fraction of its area left uncovered."""


def _radii(rng: np.random.Generator, n: int, r_min: float, r_max: float) -> np.ndarray:
    """Radii from p(r) ∝ r⁻³ on [r_min, r_max] (inverse of the CDF)."""
    u = rng.random(n)
    return (r_min**-2 - u * (r_min**-2 - r_max**-2)) ** -0.5


def dead_leaves(size: int, seed: int = 0, *, r_min: float = R_MIN_PX,
                r_max: float | None = None, contrast: float = 1.0) -> np.ndarray:
    """One dead-leaves image.

    Args:
        size: side of the square image (pixels), 8 to ``MAX_SIDE``.
        seed: NumPy seed (a whole number >= 0, or None for fresh entropy); the same seed
            gives the same image.
        r_min, r_max: smallest and largest disc radius (pixels, 0.5 <= r_min <= r_max <=
            size); ``r_max`` defaults to ``size / 4``, so a few discs span much of the image.
        contrast: sRGB colour values are 0.5 + contrast·(u − 0.5), u uniform in [0, 1]
            per channel; 1 spans the whole cube, smaller values give smaller steps between
            discs (0 to 1).

    Returns:
        float32 ``[size, size, 3]`` linear RGB in [0, 1].
    """
    if not isinstance(size, (int, np.integer)) or not 8 <= size <= MAX_SIDE:
        raise ValueError(f"dead_leaves: size must be a whole number of pixels in [8, "
                         f"{MAX_SIDE}], got {size!r}")
    r_max = size / 4 if r_max is None else r_max
    where = "dead_leaves"
    # Up to the image side: disc centres are drawn over the image grown by r_max on each
    # side, so with r_max = 10**6 on a 16-pixel image almost no disc met it (it ran for ever).
    r_min = checks.number(r_min, "r_min", where, lo=0.5, hi=size, unit="pixels")
    r_max = checks.number(r_max, "r_max", where, lo=0.5, hi=size,
                          unit="pixels (r_min <= r_max <= size)")
    if r_min > r_max:
        raise ValueError(f"dead_leaves: need 0.5 <= r_min <= r_max (pixels, finite), got "
                         f"r_min={r_min}, r_max={r_max}")
    contrast = checks.number(contrast, "contrast", where, lo=0.0, hi=1.0,
                             unit="(a fraction: 1 spans the whole sRGB cube)")
    rng = np.random.default_rng(checks.numpy_seed(seed, where, allow_none=True))
    light = np.zeros((size, size, 3))
    left = np.ones((size, size))  # area of each pixel that no disc has covered yet
    yy = np.arange(size, dtype=np.float64)[:, None] + 0.5  # pixel centres
    xx = np.arange(size, dtype=np.float64)[None, :] + 0.5
    block = 4096
    while True:
        # Centres over the image grown by r_max, so discs cut by the border are as likely
        # as inside ones (a stationary image).
        r = _radii(rng, block, r_min, r_max)
        c = rng.uniform(-r_max, size + r_max, (block, 2))
        colour = srgb_to_linear(0.5 + contrast * (rng.random((block, 3)) - 0.5))
        for (cy, cx), ri, col in zip(c, r, colour, strict=True):
            y0, y1 = max(0, int(cy - ri - 1)), min(size, int(cy + ri + 2))
            x0, x1 = max(0, int(cx - ri - 1)), min(size, int(cx + ri + 2))
            if y0 >= y1 or x0 >= x1:
                continue
            d = np.hypot(yy[y0:y1] - cy, xx[:, x0:x1] - cx)
            cover = np.clip(ri + 0.5 - d, 0.0, 1.0) * left[y0:y1, x0:x1]
            light[y0:y1, x0:x1] += cover[..., None] * col
            left[y0:y1, x0:x1] -= cover
        if left.max() <= _LEFT_OVER:
            break
    light += left[..., None] * colour[-1]  # the last sliver: the last disc's colour
    return np.clip(light, 0.0, 1.0).astype(np.float32)


def dead_leaves_images(count: int, size: int, seed: int = 0, *,
                       contrast: float = 1.0) -> list[np.ndarray]:
    """``count`` dead-leaves images of ``size²`` pixels (``contrast`` as for
    ``dead_leaves``), image ``i`` from seed ``(seed, i)``, so a set is reproducible and its
    images differ; at most ``MAX_PIXELS`` pixels in all."""
    if not isinstance(count, (int, np.integer)) or isinstance(count, bool) or \
            not 1 <= count <= 1024:
        raise ValueError(f"dead_leaves_images: count must be a whole number in [1, 1024], "
                         f"got {count!r}")
    seed = checks.numpy_seed(seed, "dead_leaves_images")
    if isinstance(size, (int, np.integer)) and count * size * size > MAX_PIXELS:
        pixels = count * size * size
        raise ValueError(f"dead_leaves_images: {count} images of {size}² pixels are "
                         f"{pixels / 2**20:.0f} Mpixels ({pixels * 12 / 2**30:.0f} GiB), more "
                         f"than the {MAX_PIXELS / 2**20:.0f} Mpixels made in one call; give "
                         f"fewer or smaller images")
    return [dead_leaves(size, int(np.random.SeedSequence([seed, i]).generate_state(1)[0]),
                        contrast=contrast) for i in range(count)]
