"""Training, validation and test scenes: images that ship with scikit-image, or a user's folder.

Nothing is downloaded: the images below are the ones ``skimage.data`` stores inside the
package. The three sets share no image.

* Training (8): astronaut, immunohistochemistry, motorcycle_left (left image of
  ``stereo_motorcycle``), colorwheel, grass, logo, page, text.
* Validation (2, for choices made before a recorded run): cell, hubble_deep_field.
* Test (10): retina, camera, moon, brick, gravel, coffee, rocket, motorcycle_right, chelsea,
  coins; ``test_crops`` cuts them into disjoint 256² crops at native resolution (no
  resampling): 48 crops, 24 of them from retina, the largest image.

Pixel values are 8-bit sRGB and are decoded to linear light (``jaxlens.io.images.to_linear``)
before any simulation; grey images are repeated on the three channels.

``training_images`` can add, or put in their place, procedural dead-leaves images
(``dead_leaves``; ``TRAIN_SOURCES``).
"""

from __future__ import annotations

import os
import pathlib

import numpy as np

from ...optics import checks

TRAIN_IMAGES = (
    "astronaut",
    "immunohistochemistry",
    "motorcycle_left",
    "colorwheel",
    "grass",
    "logo",
    "page",
    "text",
)
VAL_IMAGES = ("cell", "hubble_deep_field")
TEST_IMAGES = ("retina", "camera", "moon", "brick", "gravel", "coffee", "rocket",
               "motorcycle_right", "chelsea", "coins")
TRAIN_SOURCES = ("images", "dead-leaves", "mixed")
"""Training sets: the photographs (``TRAIN_IMAGES`` or a folder), ``DEAD_LEAVES_COUNT``
dead-leaves images in their place, or both with half the training windows from each."""
DEAD_LEAVES_COUNT, DEAD_LEAVES_SIDE = 16, 512
"""The dead-leaves training set: images and their side (pixels)."""
DEAD_LEAVES_CONTRAST = 0.62
"""The dead-leaves discs' colour contrast (``dead_leaves``' ``contrast``): it matches the
mean square difference of neighbouring pixels of training windows (62² pixels, 256 of them,
linear light) to the training photographs' (0.0046; contrast 1 gives 0.0133, 0.6 gives
0.0043, 0.7 0.0060). With contrast 1 the mixed training set lost 1.7 dB on the test photographs
at 20 cm with the classical lens (``experiments/edof/NOTES.md``)."""
_EXTS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")
MIN_MEAN, MIN_STD = 0.02, 0.01
"""A test crop is kept when its linear mean and standard deviation reach these (a rule fixed
before any result: it drops crops of empty black background, where PSNR measures noise)."""


def _to_float_rgb(a: np.ndarray) -> np.ndarray:
    from ...io.images import to_linear

    a = np.asarray(a)
    if a.dtype == bool:
        a = a.astype(np.uint8) * 255
    if a.ndim == 3 and a.shape[-1] == 4:
        a = a[..., :3]
    if a.ndim == 3 and a.shape[-1] == 2:  # grey and alpha: the grey image
        a = a[..., 0]
    a = to_linear(a)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] != 3:
        raise ValueError(f"scenes: expected a grey or RGB image, got shape {a.shape}")
    return np.clip(a, 0.0, 1.0).astype(np.float32)


def _downscale(a: np.ndarray, max_side: int | None) -> np.ndarray:
    if max_side is None or max(a.shape[:2]) <= max_side:
        return a
    from skimage.transform import resize

    s = max_side / max(a.shape[:2])
    shape = (max(1, round(a.shape[0] * s)), max(1, round(a.shape[1] * s)), 3)
    return resize(a, shape, anti_aliasing=True, preserve_range=True).astype(np.float32)


def skimage_image(name: str) -> np.ndarray:
    """One ``skimage.data`` image by name, as float32 linear RGB in [0, 1]."""
    import skimage.data as data

    if name in ("motorcycle_left", "motorcycle_right"):
        return _to_float_rgb(data.stereo_motorcycle()[0 if name.endswith("left") else 1])
    fn = getattr(data, name, None)
    if fn is None:
        raise ValueError(f"scenes: skimage.data has no image {name!r}")
    return _to_float_rgb(fn())


def folder_images(folder: str | os.PathLike, *, verify: bool = False,
                  min_side: int = 1) -> list[pathlib.Path]:
    """The image files of a folder, sorted by name; ``verify``: each file's structure is
    checked too (Pillow's ``verify``, without decoding), so that a truncated or mislabelled
    file is named before a run's work, not after its lens set-up; and each must be at least
    ``min_side`` pixels on a side (a test image smaller than one crop gives no crop)."""
    paths = sorted(p for p in pathlib.Path(folder).iterdir() if p.suffix.lower() in _EXTS)
    if not paths:
        raise ValueError(f"scenes: no image files ({', '.join(_EXTS)}) in {folder}")
    if verify:
        from PIL import Image

        for p in paths:
            try:
                with Image.open(p) as im:
                    size = im.size
                    im.verify()
            except Exception as e:  # noqa: BLE001  (Pillow raises many kinds)
                raise ValueError(f"scenes: cannot read the image {p}: {e}".splitlines()[0]
                                 ) from None
            if min(size) < min_side:
                raise ValueError(f"scenes: the image {p} is {size[0]}x{size[1]} pixels, "
                                 f"smaller than one {min_side}x{min_side} test crop")
    return paths


def check_folder(folder: str | os.PathLike, *, min_side: int = 1,
                 crop: int | None = None) -> None:
    """Refuses, before a run's work, a folder of images that ``load_images`` or, with
    ``crop``, ``test_crops`` (``crop``-pixel crops) would refuse: each file's structure and
    size (``folder_images`` with ``verify``), then its pixels decoded."""
    folder_images(folder, verify=True, min_side=min_side)
    images = load_images(folder=folder, max_side=None)
    if crop is not None:
        test_crops(images, [str(p) for p in folder_images(folder)], size=crop, margin=0)


def load_images(
    names=None, *, folder: str | os.PathLike | None = None, max_side: int | None = 512
) -> list[np.ndarray]:
    """Images by ``skimage.data`` name, or every image file in ``folder``.

    Returns:
        float32 ``[H, W, 3]`` arrays in [0, 1], at most ``max_side`` pixels on a side.
    """
    if folder is not None:
        from skimage.io import imread

        out = []
        for p in folder_images(folder):
            try:
                a = imread(p)
            except (OSError, ValueError, SyntaxError) as e:  # truncated, not an image, …
                raise ValueError(f"scenes: cannot read the image {p}: {e}".splitlines()[0]
                                 ) from None
            try:  # a float HDR, int32 or multi-page image: the message names the file
                out.append(_downscale(_to_float_rgb(a), max_side))
            except ValueError as e:
                raise ValueError(f"scenes: the image {p}: {str(e).removeprefix('scenes: ')}"
                                 ) from None
        return out
    return [_downscale(skimage_image(n), max_side) for n in names]


def training_images(source: str, photos: list[np.ndarray], *, count: int = DEAD_LEAVES_COUNT,
                    side: int = DEAD_LEAVES_SIDE, seed: int = 0):
    """The training images of ``source`` (one of ``TRAIN_SOURCES``) and the share of
    training windows each gets (``PatchSampler``'s ``weights``; None: by area).

    Args:
        source: "images" (``photos``), "dead-leaves" (``count`` dead-leaves images of
            ``side²`` pixels from ``seed``) or "mixed" (both, half the windows from each).
        photos: the photographs (``load_images``).
    """
    from .dead_leaves import dead_leaves_images

    if source not in TRAIN_SOURCES:
        raise ValueError(f"scenes: training source must be one of {TRAIN_SOURCES}, got "
                         f"{source!r}")
    if source != "dead-leaves" and not any(np.size(a) for a in photos):
        raise ValueError(f"scenes: training source {source!r} needs photographs, got "
                         f"{len(photos)} image(s) with no pixels; give images or use "
                         f"'dead-leaves'")
    if source == "images":
        return list(photos), None
    leaves = dead_leaves_images(count, side, seed, contrast=DEAD_LEAVES_CONTRAST)
    if source == "dead-leaves":
        return leaves, None
    area = np.array([a.shape[0] * a.shape[1] for a in photos], np.float64)
    weights = np.concatenate([0.5 * area / area.sum(), np.full(len(leaves), 0.5 / len(leaves))])
    return list(photos) + leaves, weights


def test_crops(images, names, *, size: int, margin: int):
    """Disjoint ``size × size`` crops at native resolution, each with a margin of scene around it.

    Every image is cut on a grid from its top-left corner (``⌊H/size⌋ × ⌊W/size⌋`` crops);
    a crop is kept if its linear mean and standard deviation reach ``MIN_MEAN`` and
    ``MIN_STD``. Each crop comes as a window of ``size + 2·margin`` pixels (the image
    reflect-padded where the margin leaves it), so a blur sees real scene beyond the crop.

    Returns:
        ``(windows [N, size + 2·margin, size + 2·margin, 3], info)``, ``info`` a list of
        ``{"image", "row", "col"}`` (the crop's top-left pixel in its image).
    """
    wins, info = [], []
    for img, name in zip(images, names, strict=True):
        pad = np.pad(img, ((margin, margin), (margin, margin), (0, 0)), mode="reflect")
        for r in range(img.shape[0] // size):
            for c in range(img.shape[1] // size):
                crop = img[r * size:(r + 1) * size, c * size:(c + 1) * size]
                if crop.mean() < MIN_MEAN or crop.std() < MIN_STD:
                    continue
                y, x = r * size, c * size
                wins.append(pad[y:y + size + 2 * margin, x:x + size + 2 * margin])
                info.append({"image": name, "row": y, "col": x})
    if not wins:
        raise ValueError(f"scenes: no {size}x{size} test crop in {list(names)}: every crop "
                         f"is darker than a linear mean of {MIN_MEAN} or flatter than a "
                         f"standard deviation of {MIN_STD} (empty background is dropped)")
    return np.stack(wins).astype(np.float32), info


def _check_image(a, where: str, arg: str) -> None:
    """A training image: real ``[H, W, 3]`` linear values in [0, 1] (8-bit codes 0…255 made
    windows of 200, a grey or RGBA image failed deep in ``sample``)."""
    shape = np.shape(a)
    if len(shape) != 3 or shape[-1] != 3 or 0 in shape:
        raise ValueError(f"{where}: {arg} must be an [H, W, 3] RGB image (scenes.load_images "
                         f"gives them), got shape {shape}")
    checks.float_image(a, where, arg, lo=0.0, hi=1.0, unit="linear RGB",
                       hint=" (8-bit codes? decode with io.images.to_linear)")


class PatchSampler:
    """Random training windows with flips and 90° rotations, from a list of images.

    Args:
        images: float32 ``[H, W, 3]`` images (each at least ``window`` pixels on a side
            after padding; smaller ones are reflect-padded).
        window: window side (patch + kernel − 1).
        seed: NumPy seed.
        weights: the share of windows drawn from each image (summing to 1); None: in
            proportion to the images' areas.
    """

    def __init__(self, images, window: int, seed: int = 0, weights=None):
        where = "PatchSampler"
        self.window = checks.number(window, "window", where, lo=1, hi=checks.MAX_IMAGE_SIDE,
                                    integer=True, unit="pixels")
        window = self.window
        images = list(images)
        if not images:
            raise ValueError(f"{where}: images must hold at least one [H, W, 3] image, got none")
        for i, a in enumerate(images):
            _check_image(a, where, f"images[{i}]")
        self.images = []
        for a in images:
            ph, pw = max(0, window - a.shape[0]), max(0, window - a.shape[1])
            if ph or pw:
                a = np.pad(a, ((0, ph), (0, pw), (0, 0)), mode="reflect")
            self.images.append(a)
        if weights is None:
            area = np.array([a.shape[0] * a.shape[1] for a in self.images], np.float64)
            weights = area / area.sum()
        checks.real_values(weights, "weights", where, "shares summing to 1")
        self.p = np.asarray(weights, np.float64)
        if self.p.shape != (len(self.images),) or not (
                np.all(self.p >= 0) and abs(self.p.sum() - 1.0) < 1e-9):
            raise ValueError(f"PatchSampler: weights must be {len(self.images)} shares >= 0 "
                             f"summing to 1, got {weights!r}")
        self.rng = np.random.default_rng(checks.numpy_seed(seed, where))

    def sample(self, n: int) -> np.ndarray:
        """``[n, window, window, 3]`` float32 windows (at most ``checks.MAX_WORKING_BYTES``)."""
        most = max(1, checks.MAX_WORKING_BYTES // (12 * self.window**2))
        n = checks.number(n, "n", "PatchSampler.sample", lo=0, hi=most, integer=True,
                          unit=f"windows of {self.window}² pixels (memory)")
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
