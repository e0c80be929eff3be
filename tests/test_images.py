"""Image files: EXR and PNG round trips, built-in scenes, PSNR/SSIM, PSF stacks, bad files."""

import numpy as np
import pytest

from jaxlens import images


def test_exr_round_trip_is_exact_float32(tmp_path):
    rng = np.random.default_rng(0)
    img = (rng.random((7, 5, 3)) * 10).astype(np.float32)  # linear HDR values above 1
    p = tmp_path / "a.exr"
    images.write_exr(p, img)
    back = images.read_exr(p)
    assert back.dtype == np.float32 and back.shape == (7, 5, 3)
    np.testing.assert_array_equal(back, img)
    grey = rng.random((4, 6)).astype(np.float32)
    images.write_exr(tmp_path / "g.exr", grey)
    np.testing.assert_array_equal(images.read_exr(tmp_path / "g.exr"), grey)


def test_png_round_trip(tmp_path):
    lin = np.linspace(0.0, 1.0, 4 * 6 * 3).reshape(4, 6, 3)
    for bits, tol in ((8, 0.5 / 255), (16, 0.5 / 65535)):
        p = tmp_path / f"a{bits}.png"
        images.write_png(p, lin, bits=bits)
        enc = images.read_png(p, linear=False)
        np.testing.assert_allclose(enc, images.linear_to_srgb(lin), atol=tol + 1e-7)
        back = images.read_png(p)
        np.testing.assert_allclose(back, lin, atol=20 * tol)


def test_srgb_curve_inverts():
    v = np.linspace(0, 1, 101)
    np.testing.assert_allclose(images.srgb_to_linear(images.linear_to_srgb(v)), v, atol=1e-12)
    assert images.srgb_to_linear(0.5) == pytest.approx(0.21404, abs=1e-5)


def test_unreadable_files_give_clear_errors(tmp_path):
    bad = tmp_path / "bad.exr"
    bad.write_text("not an exr")
    with pytest.raises(ValueError, match="not a readable OpenEXR file"):
        images.read_exr(bad)
    with pytest.raises(FileNotFoundError, match="no such file"):
        images.read_exr(tmp_path / "missing.exr")
    with pytest.raises(ValueError, match="not a readable image"):
        images.read_png(bad)
    with pytest.raises(ValueError, match="not a file"):
        images.read_exr(tmp_path)
    images.write_exr(tmp_path / "y.exr", np.zeros((2, 2), np.float32))
    with pytest.raises(ValueError, match="no channel"):
        images.read_exr(tmp_path / "y.exr", channels=("R",))


def test_scenes_psnr_ssim():
    s = images.scene("astronaut", (32, 48))
    assert s.shape == (32, 48, 3) and s.dtype == np.float32
    assert 0.0 <= s.min() and s.max() <= 1.0
    assert images.scene("camera").shape == (512, 512, 3)
    with pytest.raises(ValueError, match="unknown scene"):
        images.scene("lena")
    noisy = np.clip(s + 0.01 * np.random.default_rng(0).standard_normal(s.shape), 0, 1)
    # PSNR of Gaussian noise of σ = 0.01 on a [0, 1] image is about 40 dB.
    assert images.psnr(s, noisy, data_range=1.0) == pytest.approx(40.0, abs=0.5)
    assert images.psnr(s, s, data_range=1.0) == np.inf
    assert images.ssim(s, s, data_range=1.0) == pytest.approx(1.0)
    assert images.ssim(s, noisy, data_range=1.0) < 1.0
    with pytest.raises(ValueError, match=r"^psnr: shapes differ: \(32, 48, 3\) and \(31, 48, 3\)$"):
        images.psnr(s, s[:-1])
    with pytest.raises(ValueError, match=r"^ssim: shapes differ: \(32, 48, 3\) and \(31, 48, 3\)$"):
        images.ssim(s, s[:-1])


def test_psnr_default_range_is_the_span_of_both_images_and_zero():
    a = np.full((8, 8), 0.2)
    b = a.copy()
    b[0, 0] = 0.7  # MSE 0.25/64; span max(0.7) − min(0.2, 0) = 0.7
    mse = 0.25 / 64
    assert images.psnr(a, b) == pytest.approx(10 * np.log10(0.7**2 / mse), rel=1e-12)
    # A negative value widens the span below zero.
    assert images.psnr(a - 0.5, b - 0.5) == pytest.approx(10 * np.log10(0.5**2 / mse),
                                                          rel=1e-12)
    # An explicit range wins.
    assert images.psnr(a, b, data_range=4.0) == pytest.approx(10 * np.log10(16 / mse),
                                                              rel=1e-12)
    for bad in (0, -1.0, float("nan"), float("inf")):
        for metric in (images.psnr, images.ssim):
            with pytest.raises(ValueError,
                               match=r"data_range must be a finite number in \(0, inf\)"):
                metric(a, b, data_range=bad)


def test_psf_stack_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    rgb = rng.random((3, 3, 9, 9)).astype(np.float32)  # [N, C, k, k]
    images.write_psf_stack(tmp_path / "rgb.exr", rgb)
    back, names = images.read_psf_stack(tmp_path / "rgb.exr")
    np.testing.assert_array_equal(back, rgb)
    assert names == ["psf000", "psf001", "psf002"]
    mono = rng.random((2, 5, 5)).astype(np.float32)
    images.write_psf_stack(tmp_path / "m.exr", mono, names=["on_axis", "corner"])
    back, names = images.read_psf_stack(tmp_path / "m.exr")
    assert sorted(names) == ["corner", "on_axis"]
    np.testing.assert_array_equal(back[names.index("corner"), 0], mono[1])


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else (b if pb <= pc else c)


def test_png16_decoder_undoes_every_filter(tmp_path):
    """A 16-bit RGB PNG whose rows use filter types 0–4 (Pillow would read it as 8 bits)."""
    import struct
    import zlib

    rng = np.random.default_rng(2)
    h, w, bpp = 5, 4, 6
    img = rng.integers(0, 65536, (h, w, 3), dtype=np.uint16)
    rows = img.astype(">u2").reshape(h, -1).view(np.uint8).reshape(h, -1).astype(int)
    out, prior = b"", np.zeros(w * bpp, int)
    for y in range(h):
        ft, cur = y % 5, rows[y]
        enc = []
        for i, x in enumerate(cur):
            a = cur[i - bpp] if i >= bpp else 0
            b, c = prior[i], (prior[i - bpp] if i >= bpp else 0)
            pred = (0, a, b, (a + b) // 2, _paeth(a, b, c))[ft]
            enc.append((x - pred) % 256)
        out += bytes([ft]) + bytes(enc)
        prior = cur

    def chunk(tag, d):
        return struct.pack(">I", len(d)) + tag + d + struct.pack(">I", zlib.crc32(tag + d))

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(out)) + chunk(b"IEND", b""))
    (tmp_path / "f.png").write_bytes(png)
    back = images.read_png(tmp_path / "f.png", linear=False)
    np.testing.assert_allclose(back, img / 65535.0, atol=1e-7)


def test_writers_refuse_another_suffix_and_a_folder(tmp_path):
    """PNG bytes under a .jpg name, or an EXR named .png, would be unreadable as what the name
    says; a folder gave a raw IsADirectoryError."""
    img = np.full((2, 2, 3), 0.5)
    with pytest.raises(ValueError, match=r"write_png: writes PNG files; the path must end in "
                                         r"\.png, got '.*x\.jpg'"):
        images.write_png(tmp_path / "x.jpg", img)
    with pytest.raises(ValueError, match=r"write_exr: writes EXR files; the path must end in "
                                         r"\.exr"):
        images.write_exr(tmp_path / "x.png", img)
    folder = tmp_path / "d.png"
    folder.mkdir()
    with pytest.raises(ValueError, match="is a folder, not a file"):
        images.write_png(folder, img)
    assert not (tmp_path / "x.jpg").exists() and not (tmp_path / "x.png").exists()
    images.write_png(tmp_path / "UPPER.PNG", img)  # the suffix in any case
    np.testing.assert_allclose(images.read_png(tmp_path / "UPPER.PNG"), img, atol=5e-3)
