"""Image files and test scenes: OpenEXR (float, linear) and PNG, skimage scenes, PSNR/SSIM.

Conventions:
    Images are numpy arrays ``[H, W]`` or ``[H, W, C]``, row 0 at the top. EXR files hold
    linear light as 32-bit floats. PNG files hold display-referred sRGB-encoded 8- or 16-bit
    values: ``read_png`` decodes them to linear light in [0, 1] unless ``linear=False``,
    and ``write_png`` encodes linear values with the sRGB curve (clipping to [0, 1]).
    Built-in scenes come from ``skimage.data`` (shipped with scikit-image, nothing is
    downloaded) and are returned linear.

This module works on the host (numpy, files); it is not jittable.
"""

from __future__ import annotations

import os
import pathlib
import struct
import zlib

import numpy as np

from ..optics import checks
from .json_values import output_file, whole_path, write_whole

__all__ = [
    "read_exr",
    "write_exr",
    "read_png",
    "write_png",
    "srgb_to_linear",
    "linear_to_srgb",
    "to_linear",
    "scene",
    "SCENES",
    "psnr",
    "ssim",
    "write_psf_stack",
    "read_psf_stack",
]

SCENES = ("astronaut", "chelsea", "coffee", "rocket", "camera", "immunohistochemistry",
          "hubble_deep_field", "colorwheel")
"""Names of the built-in scenes (functions of ``skimage.data`` bundled with scikit-image)."""


def srgb_to_linear(v):
    """Decode sRGB values in [0, 1] to linear light (IEC 61966-2-1). Integer images
    (uint8, uint16 codes) are refused: decode them with :func:`to_linear`."""
    v = checks.float_image(v, "srgb_to_linear", "v", lo=0, hi=1, unit="sRGB-encoded")
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(v):
    """Encode linear light in [0, 1] with the sRGB curve (finite values, clipped first)."""
    v = np.clip(checks.float_image(v, "linear_to_srgb", "v", unit="linear light"), 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def to_linear(img) -> np.ndarray:
    """An integer sRGB image (uint8/uint16) or a float image in [0, 1] as linear float32."""
    a = np.asarray(img)
    if np.issubdtype(a.dtype, np.integer) and a.dtype not in (np.uint8, np.uint16):
        # int64 300 / iinfo(int64).max is 3e-17: an integer image must be 8 or 16 bit.
        raise ValueError(f"to_linear: an integer image must be uint8 or uint16 sRGB, got "
                         f"{a.dtype}; give a float image in [0, 1] or convert it with "
                         f"img.astype(np.uint8)")
    if np.issubdtype(a.dtype, np.integer):
        a = a.astype(np.float64) / np.iinfo(a.dtype).max
        return srgb_to_linear(a).astype(np.float32)
    # A float image of 0…255 values passed through as radiance 255 (and NaN, complex or
    # bool pixels without a word).
    return checks.float_image(a, "to_linear", "img", lo=0, hi=1, unit="linear light",
                              hint="; a float image of 0…255 codes: divide it by 255 "
                                   "first").astype(np.float32)


def _check_readable(path, caller):
    p = pathlib.Path(os.fspath(path))
    if not p.exists():
        raise FileNotFoundError(f"{caller}: no such file: {p}")
    if not p.is_file():
        raise ValueError(f"{caller}: not a file: {p}")
    return p


def read_exr(path, *, channels=None) -> np.ndarray:
    """Read an OpenEXR image as float32 linear values.

    Args:
        path: the file.
        channels: channel names to read in order (default: R, G, B if present, else Y,
            else every channel in sorted order; an alpha channel A is left out, as
            ``read_png`` drops alpha).

    Returns:
        ``[H, W, C]`` float32 (``[H, W]`` for a single channel).

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: the file is not a readable OpenEXR image, or lacks a requested channel.
    """
    import OpenEXR

    p = _check_readable(path, "read_exr")
    try:
        with OpenEXR.File(str(p), separate_channels=True) as f:
            chans = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    except Exception as e:  # OpenEXR raises RuntimeError with a terse message
        raise ValueError(f"read_exr: {p} is not a readable OpenEXR file ({e})") from None
    if channels is None:
        # A grey+alpha file (Y, A) was read as [A, Y]: alpha first, as the image's grey.
        channels = ([c for c in ("R", "G", "B") if c in chans] or [c for c in ("Y",) if c in chans]
                    or sorted(set(chans) - {"A"}) or sorted(chans))
    elif isinstance(channels, str):  # "RGB" was read letter by letter, "R1" as R and 1
        channels = [channels]
    channels = list(channels)
    if not channels or len(set(channels)) != len(channels):  # [] failed in np.stack
        raise ValueError(f"read_exr: channels must be distinct channel names, at least one, "
                         f"got {channels!r}; {p} has {sorted(chans)}")
    missing = [c for c in channels if c not in chans]
    if missing:
        raise ValueError(f"read_exr: {p} has no channel(s) {missing}; it has {sorted(chans)}")
    arr = np.stack([chans[c].astype(np.float32) for c in channels], -1)
    return arr[..., 0] if arr.shape[-1] == 1 else arr


def write_exr(path, img, *, channels=None) -> None:
    """Write a float image to OpenEXR (32-bit float, ZIP compression).

    Args:
        path: the file.
        img: ``[H, W]`` or ``[H, W, C]`` linear values.
        channels: channel names (default Y for one channel, R, G, B for three, else
            C0, C1, ...).

    Values are rounded to the nearest float32: magnitudes below 1.4e-45 become 0 (float32's
    subnormals are kept); an image that would become all 0, or that holds a value beyond
    3.4e38, is refused.
    """
    path = pathlib.Path(output_file(path, "write_exr", ".exr"))
    a = _float32(img, "write_exr", "img", "linear values")
    _non_empty(a, "write_exr")
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"write_exr: image must be [H, W] or [H, W, C], got {a.shape}")
    c = a.shape[-1]
    if channels is None:
        channels = ("Y",) if c == 1 else ("R", "G", "B") if c == 3 else tuple(
            f"C{i}" for i in range(c))
    channels = _layer_names(channels, c, "write_exr", "channels", "channels")
    data = {name: np.ascontiguousarray(a[..., i]) for i, name in enumerate(channels)}
    _write_channels(path, data)


def _float32(img, where: str, arg: str, unit: str) -> np.ndarray:
    """A finite float image as the float32 an EXR file holds: a value beyond float32's range
    (3.4e38) was written as inf without a word. Values are rounded to the nearest float32,
    as any float32 store rounds them: float32's subnormals (down to 1.4e-45) are kept, and a
    smaller magnitude becomes 0 beside larger values (1e-50 beside 1 is 1e-50 of it). An
    image whose every nonzero value would become 0 (all 1e-50: data in another unit) is
    refused, as it would be written as a black image."""
    a = checks.float_image(img, where, arg, unit=unit)
    top = float(np.finfo(np.float32).max)
    if a.size and np.max(np.abs(a)) > top:
        raise ValueError(f"{where}: {arg} must be finite values within float32's range "
                         f"(|v| <= {top:.4g}), which an EXR file holds; got "
                         f"{checks.fmt(a[np.abs(a) > top][:1])} ({unit}); scale the image")
    out = a.astype(np.float32)
    if a.size and np.any(a != 0) and not np.any(out != 0):
        least = float(np.finfo(np.float32).smallest_subnormal)
        raise ValueError(f"{where}: every nonzero value of {arg} is below float32's least "
                         f"magnitude ({least:.2g}), which an EXR file holds, so the file "
                         f"would be all 0; got at most {float(np.max(np.abs(a))):.4g} "
                         f"({unit}); scale the image")
    return out


def _non_empty(a, where: str) -> None:
    """An image with pixels (OpenEXR raised RuntimeError on an empty one, write_png a
    reshape error)."""
    if a.size == 0:
        raise ValueError(f"{where}: img is empty (shape {a.shape}); an image needs at least "
                         f"one pixel")


def _layer_names(names, n: int, where: str, arg: str, what: str) -> list[str]:
    """``n`` distinct non-empty str names without '.' (EXR's layer separator): a repeated
    name kept only its last image, so fewer were written than given, without a word."""
    names = [names] if isinstance(names, str) and n == 1 else list(names)
    if len(names) != n:
        raise ValueError(f"{where}: {n} {what} need {n} names, got {len(names)}: {names!r}")
    bad = [x for x in names if not isinstance(x, str) or not x or "." in x]
    if bad:
        raise ValueError(f"{where}: {arg} must be non-empty str without '.', got {bad[0]!r}")
    if len(set(names)) != n:
        dup = sorted({x for x in names if names.count(x) > 1})
        raise ValueError(f"{where}: {arg} must be distinct (a repeated name keeps one of its "
                         f"{what}), got {dup} more than once")
    return names


def _write_channels(path, data):
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, data) as f, whole_path(path) as tmp:  # whole or not at all
        f.write(tmp)


def read_png(path, *, linear: bool = True) -> np.ndarray:
    """Read a PNG file (8 or 16 bits per channel) as float32.

    Args:
        path: the file.
        linear: decode sRGB to linear light (default); False returns the encoded values in
            [0, 1].

    Returns:
        ``[H, W, C]`` or ``[H, W]`` float32 in [0, 1] (an alpha channel is dropped).

    Raises:
        FileNotFoundError, ValueError: missing or unreadable file.
    """
    checks.switch(linear, "linear", "read_png")  # "no" is truthy: it decoded sRGB
    p = _check_readable(path, "read_png")
    with open(p, "rb") as f:
        if f.read(8) != b"\x89PNG\r\n\x1a\n":
            raise ValueError(f"read_png: {p} is not a readable image (no PNG signature)")
    try:
        a = _read_png16(p)
        if a is None:
            a = _read_png_pil(p)
    except Exception as e:
        raise ValueError(f"read_png: {p} is not a readable image ({e})") from None
    if a.ndim == 3 and a.shape[-1] in (2, 4):  # grey+alpha kept its alpha as a 2nd channel
        a = a[..., :-1]
    if a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if np.issubdtype(a.dtype, np.integer):
        v = a.astype(np.float64) / np.iinfo(a.dtype).max
    else:
        v = a.astype(np.float64)
    return (srgb_to_linear(v) if linear else v).astype(np.float32)


def write_png(path, img, *, linear: bool = True, bits: int = 8) -> None:
    """Write an image to PNG (8 or 16 bits per channel, grey, grey+alpha, RGB or RGBA).

    Args:
        path: the file.
        img: ``[H, W]`` or ``[H, W, C]`` (C = 1…4) values in [0, 1] (clipped).
        linear: the values are linear light and get the sRGB curve (default); False writes
            them as they are. An alpha channel (C = 2 or 4, the last) is coverage, written
            as it is either way.
        bits: 8 or 16.
    """
    # Both checked before the file is touched: linear="no" is truthy (the sRGB curve was
    # applied), and bits=8.0 passed ``in (8, 16)`` and failed in struct.pack.
    checks.switch(linear, "linear", "write_png")
    if isinstance(bits, bool) or not isinstance(bits, (int, np.integer)) or bits not in (8, 16):
        raise ValueError(f"write_png: bits must be 8 or 16 (bits per channel), got {bits!r}")
    path = pathlib.Path(output_file(path, "write_png", ".png"))
    # An integer image (uint8 codes) was clipped to 1: a white file; NaN would be cast to
    # an arbitrary integer (0 on most machines): a silent black pixel.
    a = checks.float_image(img, "write_png", "img", unit="values in [0, 1], clipped")
    _non_empty(a, "write_png")
    if a.max() > 1.0 and np.all(a == np.round(a)):  # 0…255 codes as floats: a white file
        raise ValueError(f"write_png: img must be values in [0, 1] (clipped), got whole "
                         f"numbers up to {a.max():g}: 0…255 or 0…65535 codes given as "
                         f"floats? Divide by 255 (or 65535) first")
    if a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[-1] > 4):
        raise ValueError(f"write_png: image must be [H, W] or [H, W, C<=4], got {a.shape}")
    v = np.clip(a, 0.0, 1.0)
    if linear:  # the colour channels only: alpha 0.5 was written as 0.735 (code 188)
        colour = slice(None, -1) if a.ndim == 3 and a.shape[-1] in (2, 4) else slice(None)
        v[..., colour] = linear_to_srgb(v[..., colour])
    top = 2**bits - 1
    q = np.round(v * top).astype(">u2" if bits == 16 else np.uint8)
    h, w = q.shape[:2]
    c = 1 if q.ndim == 2 else q.shape[-1]
    color_type = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    rows = q.reshape(h, -1).view(np.uint8).reshape(h, -1)
    data = b"".join(b"\x00" + r.tobytes() for r in rows)  # filter type 0 on every row

    def chunk(tag, payload):
        crc = zlib.crc32(tag + payload) & 0xFFFFFFFF
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", crc)

    ihdr = struct.pack(">IIBBBBB", w, h, bits, color_type, 0, 0, 0)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(data, 6))
           + chunk(b"IEND", b""))
    write_whole(path, png)  # whole or not at all: a stop mid-write left a cut file


def _unfilter(raw: bytes, h: int, stride: int, bpp: int) -> np.ndarray:
    """Undo the PNG row filters (types 0–4) of a non-interlaced image."""
    buf = np.frombuffer(raw, np.uint8).reshape(h, stride + 1)
    out = np.zeros((h, stride), np.uint8)
    prior = np.zeros(stride, np.int32)
    for y in range(h):
        ftype, row = buf[y, 0], buf[y, 1:].astype(np.int32)
        if ftype == 0:
            cur = row
        elif ftype == 1:  # Sub: running sum along each byte lane
            cur = np.concatenate([np.cumsum(row[k::bpp]) for k in range(bpp)])
            cur = cur.reshape(bpp, -1).T.reshape(-1) if stride % bpp == 0 else cur
        elif ftype == 2:
            cur = row + prior
        elif ftype in (3, 4):
            cur = np.zeros(stride, np.int32)
            for i in range(0, stride, bpp):
                left = cur[i - bpp : i] if i else np.zeros(bpp, np.int32)
                up = prior[i : i + bpp]
                if ftype == 3:
                    pred = (left + up) // 2
                else:
                    ul = prior[i - bpp : i] if i else np.zeros(bpp, np.int32)
                    p = left + up - ul
                    pa, pb, pc = np.abs(p - left), np.abs(p - up), np.abs(p - ul)
                    pred = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, ul))
                cur[i : i + bpp] = (row[i : i + bpp] + pred) & 0xFF
        else:
            raise ValueError(f"unknown PNG filter type {ftype}")
        cur = cur & 0xFF
        out[y] = cur
        prior = cur.astype(np.int32)
    return out


def _read_png_pil(p: pathlib.Path) -> np.ndarray:
    """An 8-bit (or interlaced 16-bit) PNG's codes, ``[H, W]`` or ``[H, W, C]`` (C = 2…4).
    skimage's reader gave a grey+alpha PNG of 4x4 pixels the shape (4, 2, 4)."""
    from PIL import Image

    with Image.open(p) as im:
        if im.mode in ("P", "PA", "1"):  # palette and 1-bit: their colours, 8 bits
            alpha = im.mode == "PA" or "transparency" in im.info
            im = im.convert("L" if im.mode == "1" else "RGBA" if alpha else "RGB")
        a = np.asarray(im)
        if im.mode.startswith("I"):  # 16-bit grey as int32 codes 0…65535
            a = a.astype(np.uint16)
    return a


def _read_png16(p: pathlib.Path):
    """Decode a non-interlaced 16-bit PNG (imageio/Pillow reduce 16-bit colour to 8 bits)."""
    data = p.read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    pos, idat, hdr = 8, [], None
    while pos + 8 <= len(data):
        n, tag = struct.unpack(">I4s", data[pos : pos + 8])
        payload = data[pos + 8 : pos + 8 + n]
        if tag == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", payload)
        elif tag == b"IDAT":
            idat.append(payload)
        pos += 12 + n
    if hdr is None:
        return None
    w, h, bits, color_type, _, _, interlace = hdr
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(color_type)
    if bits != 16 or channels is None or interlace:
        return None
    raw = zlib.decompress(b"".join(idat))
    bpp = 2 * channels
    rows = _unfilter(raw, h, w * bpp, bpp)
    a = rows.reshape(h, w * channels * 2).view(">u2").reshape(h, w, channels).astype(np.uint16)
    return a[..., 0] if channels == 1 else a


def scene(name: str = "astronaut", size: tuple[int, int] | None = None) -> np.ndarray:
    """A built-in test scene from ``skimage.data``, linear float32 ``[H, W, 3]``.

    Args:
        name: one of ``SCENES``.
        size: (rows, cols) to resize to (anti-aliased); default the native size.

    Returns:
        The scene in linear light, values in [0, 1]; grey images are repeated to 3 channels.
    """
    import skimage.data
    import skimage.transform

    if name not in SCENES:
        raise ValueError(f"scene: unknown scene {name!r}; choose from {SCENES}")
    a = getattr(skimage.data, name)()
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, -1)
    a = a[..., :3]
    lin = to_linear(a)
    if size is not None:
        size = checks.grid(size, "scene", "size", "pixels", hi=checks.MAX_IMAGE_SIDE)
        lin = skimage.transform.resize(lin, tuple(size), order=1, anti_aliasing=True,
                                       preserve_range=True).astype(np.float32)
    return lin


def _images(reference, test, where):
    """Two float64 images of one shape, non-empty and finite: NaN pixels made the score NaN
    and two empty images scored inf (identical)."""
    dts = [np.asarray(x).dtype for x in (reference, test)]
    kinds = [d.kind for d in dts]
    if any(k not in "iuf" for k in kinds):  # complex pixels lost their imaginary part, and
        # bool images scored 0 dB (True - False as numbers)
        raise ValueError(f"{where}: reference and test must be real images, got dtypes "
                         f"{dts[0]} and {dts[1]}")
    if all(k in "iu" for k in kinds) and dts[0] != dts[1]:  # uint8 against uint16 codes:
        # 0…255 against 0…65535 scored 0.03 dB
        raise ValueError(f"{where}: integer images must be of one dtype (one code range), got "
                         f"{dts[0]} and {dts[1]}; convert both with "
                         f"jaxlens.io.images.to_linear")
    if len(set(k in "iu" for k in kinds)) > 1:  # a [0, 1] float image against 0…255 scored
        raise ValueError(f"{where}: reference and test must be on one scale, got dtypes "
                         f"{np.asarray(reference).dtype} and {np.asarray(test).dtype} (an "
                         f"integer image is 0…255 or 0…65535, a float image 0…1); convert "
                         f"the integer one with jaxlens.io.images.to_linear or astype")
    a, b = np.asarray(reference, np.float64), np.asarray(test, np.float64)
    if a.shape != b.shape:
        raise ValueError(f"{where}: shapes differ: {a.shape} and {b.shape}")
    if a.size == 0 or a.ndim == 0:  # two numbers scored as 1-pixel images
        raise ValueError(f"{where}: the images are empty or not arrays of pixels, shape "
                         f"{a.shape}")
    checks.finite_array(a, "reference", where)
    checks.finite_array(b, "test", where)
    return a, b


def _data_range(a, b, data_range, where):
    if data_range is not None:  # before: "1" failed as numpy's TypeError of isfinite
        data_range = checks.number(data_range, "data_range", where, lo=0, lo_open=True,
                                   unit="(the peak-to-peak range of pixel values, 1 for "
                                        "[0, 1] images)")
        peak = float(max(np.max(np.abs(a)), np.max(np.abs(b))))
        if data_range >= 255 and peak <= 1:  # 255 for [0, 1] images: 48 dB too good
            raise ValueError(f"{where}: data_range {data_range:g} for images whose values lie "
                             f"in [-1, 1] (largest |value| {peak:g}): the range of 0…255 codes "
                             f"given for float images? Use 1 for [0, 1] images")
        span = float(max(np.max(a), np.max(b)) - min(np.min(a), np.min(b)))
        if span > 2 * data_range:  # 0…255 floats with data_range 1 scored -8 dB (a restored
            # image may overshoot its range a little: up to twice it is taken)
            raise ValueError(f"{where}: data_range {data_range:g} for images whose values span "
                             f"{span:g}, more than twice it: the range of [0, 1] images given "
                             f"for 0…255 values? data_range is the peak-to-peak range of pixel "
                             f"values (1 for [0, 1] images, 255 for 0…255)")
        return float(data_range)
    return float(max(np.max(a), np.max(b)) - min(np.min(a), np.min(b), 0.0)) or 1.0


def psnr(reference, test, *, data_range=None) -> float:
    """Peak signal-to-noise ratio (dB), ``skimage.metrics.peak_signal_noise_ratio``.

    ``data_range`` defaults to the span of the two images (1 for [0, 1] images); a given
    one may not be less than half their values' span. The images are float (linear or
    encoded, in [0, 1]) or both integer codes of one dtype (uint8 against uint8); bool and
    complex images, and an integer image against a float one or against another integer
    dtype, are refused.
    """
    from skimage.metrics import peak_signal_noise_ratio

    a, b = _images(reference, test, "psnr")
    if np.array_equal(a, b):
        return float("inf")
    return float(peak_signal_noise_ratio(a, b, data_range=_data_range(a, b, data_range, "psnr")))


def ssim(reference, test, *, data_range=None) -> float:
    """Structural similarity, ``skimage.metrics.structural_similarity`` (channels last)."""
    from skimage.metrics import structural_similarity

    a, b = _images(reference, test, "ssim")
    if a.ndim > 3:  # skimage spoke of win_size
        raise ValueError(f"ssim: images must be [H, W] or [H, W, C] (channels last), got shape "
                         f"{a.shape}")
    kw = {"channel_axis": -1} if a.ndim == 3 else {}
    side = min(a.shape[:2]) if a.ndim >= 2 else a.shape[0]
    if side < 7:  # skimage's own message spoke of win_size and channel_axis, not given here
        raise ValueError(f"ssim: images must be at least 7x7 pixels (the 7-pixel window), got "
                         f"shape {a.shape}")
    return float(structural_similarity(a, b, data_range=_data_range(a, b, data_range, "ssim"),
                                      **kw))


PSF_ROUNDING = 1e-6
"""Negative PSF values down to this fraction of their PSF's peak are float rounding
(float32's ε is 1.2·10⁻⁷): ``write_psf_stack`` writes them as 0 and refuses larger ones."""


def write_psf_stack(path, psfs, *, names=None) -> None:
    """Save a stack of PSFs to one EXR file, one layer per PSF.

    Args:
        path: the file.
        psfs: ``[N, k, k]`` (one channel, written as ``psfNNN.Y``) or ``[N, C, k, k]``
            (C = 3 written as ``psfNNN.R/G/B``, else ``psfNNN.C0``...). A PSF map
            ``[rows, cols, ...]`` can be flattened first.
        names: layer names (default ``psf000``, ``psf001``, ...).

    A PSF is an intensity, so it is non-negative: a value below −``PSF_ROUNDING`` (10⁻⁶)
    times its own PSF's peak (each PSF and channel apart) is refused, naming the PSF; the
    values between that and 0 (float rounding, e.g. of an FFT or a resampling) are written
    as 0. A stack with larger negative values (the ringing of an interpolation, or a
    difference of PSFs) must be clipped or fixed by the caller, who knows which it is.
    """
    path = pathlib.Path(output_file(path, "write_psf_stack", ".exr"))
    # NaN PSFs were written as they were (and complex or integer ones cast).
    a = _float32(psfs, "write_psf_stack", "psfs", "PSF values")
    if a.ndim == 3:
        a = a[:, None]
    if a.ndim != 4 or 0 in a.shape:
        raise ValueError(f"write_psf_stack: psfs must be [N, k, k] or [N, C, k, k] with N, C, "
                         f"k >= 1, got {a.shape}")
    n, c = a.shape[:2]
    peak = np.maximum(a.max(axis=(2, 3), keepdims=True), 0.0)
    bad = a < -PSF_ROUNDING * peak
    if bad.any():  # before: written as they were (a PSF with negative intensities)
        i, j, y, x = np.argwhere(bad)[0]
        v, top = float(a[i, j, y, x]), float(peak[i, j, 0, 0])
        raise ValueError(
            f"write_psf_stack: a PSF is an intensity, non-negative; psfs[{i}]"
            f"{f' channel {j}' if c > 1 else ''} has {v:.4g} at pixel ({y}, {x}), "
            f"{f'{-v / top:.3g} of its peak {top:.4g}' if top > 0 else 'and no positive peak'}"
            f" (values down to -{PSF_ROUNDING:g} of each PSF's peak are float rounding and "
            f"written as 0); clip the stack (np.clip(psfs, 0, None)) if the negatives are "
            f"ringing, or fix what made them ({int(bad.sum())} such value(s))")
    a = np.maximum(a, 0.0)
    names = [f"psf{i:03d}" for i in range(n)] if names is None else names
    names = _layer_names(names, n, "write_psf_stack", "names", "PSFs")
    chans = ("Y",) if c == 1 else ("R", "G", "B") if c == 3 else tuple(f"C{i}" for i in range(c))
    data = {f"{names[i]}.{ch}": np.ascontiguousarray(a[i, j])
            for i in range(n) for j, ch in enumerate(chans)}
    _write_channels(path, data)


def read_psf_stack(path) -> tuple[np.ndarray, list[str]]:
    """Read a PSF stack written by :func:`write_psf_stack`: ``([N, C, k, k], names)``."""
    import OpenEXR

    p = _check_readable(path, "read_psf_stack")
    try:
        with OpenEXR.File(str(p), separate_channels=True) as f:
            chans = {k: np.asarray(v.pixels, np.float32) for k, v in f.channels().items()}
    except Exception as e:
        raise ValueError(f"read_psf_stack: {p} is not a readable OpenEXR file ({e})") from None
    layers: dict[str, dict[str, np.ndarray]] = {}
    for key, val in chans.items():
        layer, _, ch = key.rpartition(".")
        if not layer:  # an RGB image read as one PSF named ''
            raise ValueError(f"read_psf_stack: {p} is not a PSF stack written by "
                             f"write_psf_stack: channel {key!r} has no layer name (layer.channel)"
                             f"; read an image with read_exr")
        layers.setdefault(layer, {})[ch] = val
    names = sorted(layers)
    order = lambda chs: [c for c in ("R", "G", "B") if c in chs] or sorted(chs)  # noqa: E731
    stack = np.stack([np.stack([layers[n][c] for c in order(layers[n])]) for n in names])
    return stack, names
