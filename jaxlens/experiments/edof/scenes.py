"""Training and test scenes: images that ship with scikit-image, or a user's folder.

Nothing is downloaded: the images below are the ones ``skimage.data`` stores inside the
package. Training and test sets are disjoint.

* Training (10): astronaut, rocket, hubble_deep_field, immunohistochemistry, retina,
  motorcycle_left (left image of ``stereo_motorcycle``), colorwheel, brick, grass, gravel.
* Held-out test (3): chelsea, coffee, camera.

Pixel values are scaled to [0, 1] and used as linear intensities (as the paper's
simulation does with its sRGB training images); grey images are repeated on the three
channels. Images larger than ``max_side`` are downscaled (area averaging).
"""

from __future__ import annotations

import os
import pathlib

import numpy as np

TRAIN_IMAGES = (
    "astronaut",
    "rocket",
    "hubble_deep_field",
    "immunohistochemistry",
    "retina",
    "motorcycle_left",
    "colorwheel",
    "brick",
    "grass",
    "gravel",
)
TEST_IMAGES = ("chelsea", "coffee", "camera")
_EXTS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


def _to_float_rgb(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype == bool:
        a = a.astype(np.float32)
    elif np.issubdtype(a.dtype, np.integer):
        a = a.astype(np.float32) / float(np.iinfo(a.dtype).max)
    a = a.astype(np.float32)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.shape[-1] == 4:
        a = a[..., :3]
    if a.ndim != 3 or a.shape[-1] != 3:
        raise ValueError(f"scenes: expected a grey or RGB image, got shape {a.shape}")
    return np.clip(a, 0.0, 1.0)


def _downscale(a: np.ndarray, max_side: int | None) -> np.ndarray:
    if max_side is None or max(a.shape[:2]) <= max_side:
        return a
    from skimage.transform import resize

    s = max_side / max(a.shape[:2])
    shape = (max(1, round(a.shape[0] * s)), max(1, round(a.shape[1] * s)), 3)
    return resize(a, shape, anti_aliasing=True, preserve_range=True).astype(np.float32)


def skimage_image(name: str) -> np.ndarray:
    """One ``skimage.data`` image by name, as float32 RGB in [0, 1]."""
    import skimage.data as data

    if name == "motorcycle_left":
        return _to_float_rgb(data.stereo_motorcycle()[0])
    fn = getattr(data, name, None)
    if fn is None:
        raise ValueError(f"scenes: skimage.data has no image {name!r}")
    return _to_float_rgb(fn())


def load_images(
    names=None, *, folder: str | os.PathLike | None = None, max_side: int | None = 512
) -> list[np.ndarray]:
    """Images by ``skimage.data`` name, or every image file in ``folder``.

    Returns:
        float32 ``[H, W, 3]`` arrays in [0, 1], at most ``max_side`` pixels on a side.
    """
    if folder is not None:
        from skimage.io import imread

        paths = sorted(p for p in pathlib.Path(folder).iterdir() if p.suffix.lower() in _EXTS)
        if not paths:
            raise ValueError(f"scenes: no image files ({', '.join(_EXTS)}) in {folder}")
        return [_downscale(_to_float_rgb(imread(p)), max_side) for p in paths]
    return [_downscale(skimage_image(n), max_side) for n in names]


def square_crop(img: np.ndarray, size: int) -> np.ndarray:
    """Resize the shorter side to ``size`` and crop the centre ``size × size``."""
    from skimage.transform import resize

    h, w = img.shape[:2]
    s = size / min(h, w)
    shape = (max(size, round(h * s)), max(size, round(w * s)), 3)
    r = resize(img, shape, anti_aliasing=s < 1, preserve_range=True).astype(np.float32)
    y0, x0 = (r.shape[0] - size) // 2, (r.shape[1] - size) // 2
    return r[y0 : y0 + size, x0 : x0 + size]


class PatchSampler:
    """Random training windows with flips and 90° rotations, from a list of images.

    Args:
        images: float32 ``[H, W, 3]`` images (each at least ``window`` pixels on a side
            after padding; smaller ones are reflect-padded).
        window: window side (patch + kernel − 1).
        seed: NumPy seed.
    """

    def __init__(self, images, window: int, seed: int = 0):
        self.window = window
        self.images = []
        for a in images:
            ph, pw = max(0, window - a.shape[0]), max(0, window - a.shape[1])
            if ph or pw:
                a = np.pad(a, ((0, ph), (0, pw), (0, 0)), mode="reflect")
            self.images.append(a)
        area = np.array([a.shape[0] * a.shape[1] for a in self.images], np.float64)
        self.p = area / area.sum()
        self.rng = np.random.default_rng(seed)

    def sample(self, n: int) -> np.ndarray:
        """``[n, window, window, 3]`` float32 windows."""
        out = np.empty((n, self.window, self.window, 3), np.float32)
        for b in range(n):
            a = self.images[self.rng.choice(len(self.images), p=self.p)]
            y = self.rng.integers(0, a.shape[0] - self.window + 1)
            x = self.rng.integers(0, a.shape[1] - self.window + 1)
            w = a[y : y + self.window, x : x + self.window]
            w = np.rot90(w, self.rng.integers(4))
            if self.rng.integers(2):
                w = w[:, ::-1]
            out[b] = w
        return out
