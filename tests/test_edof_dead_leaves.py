"""The EDoF experiment's procedural training scenes (dead leaves) and how a run takes them."""

import json

import numpy as np
import pytest

from jaxlens.experiments.edof import cli
from jaxlens.experiments.edof import scenes as S
from jaxlens.experiments.edof.dead_leaves import dead_leaves, dead_leaves_images


def _spectral_slope(img, n=128):
    """Median slope of the radial power spectrum of ``n²`` grey crops (Hann window, 3 to 50
    cycles per crop), as ``dead_leaves.R_MIN_PX`` was chosen."""
    y, x = np.indices((n, n)) - n // 2
    f = np.hypot(x, y).astype(int)
    k = np.arange(3, 50)
    w = np.hanning(n)[:, None] * np.hanning(n)[None]
    g = img.mean(-1)
    slopes = []
    for i in range(0, g.shape[0] - n + 1, n):
        for j in range(0, g.shape[1] - n + 1, n):
            c = g[i:i + n, j:j + n]
            p = np.abs(np.fft.fftshift(np.fft.fft2((c - c.mean()) * w))) ** 2
            ps = np.bincount(f.ravel(), p.ravel()) / np.bincount(f.ravel())
            slopes.append(np.polyfit(np.log(k), np.log(ps[k]), 1)[0])
    return float(np.median(slopes))


def test_dead_leaves_are_reproducible_covered_and_in_range():
    a, b, c = dead_leaves(96, 3), dead_leaves(96, 3), dead_leaves(96, 4)
    assert a.shape == (96, 96, 3) and a.dtype == np.float32
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.min() >= 0.0 and a.max() <= 1.0
    # Opaque flat discs: most pixels equal their right-hand neighbour exactly (inside a
    # disc); anti-aliased rims and small discs make the rest.
    same = np.all(a[:, 1:] == a[:, :-1], axis=-1).mean()
    assert 0.4 < same < 0.98, same


def test_disc_colours_are_uniform_srgb_decoded_to_linear():
    """The mean of uniform sRGB values decoded to linear light is ∫((v + a)/(1 + a))^2.4 dv
    (a = 0.055; the linear toe below 0.04045 adds 6e-5): about 0.310, not 0.5."""
    imgs = dead_leaves_images(8, 128, seed=1)
    mean = float(np.mean([im.mean() for im in imgs]))
    a = 0.055
    want = (1 + a) / 3.4 * (1 - (a / (1 + a)) ** 3.4)
    assert abs(mean - want) < 0.05, (mean, want)


def test_the_spectrum_slope_follows_the_smallest_disc():
    """Smaller discs put more detail at the pixel scale (a flatter spectrum); the default
    smallest disc lands near the training photographs' median slope (−2.75)."""
    default = _spectral_slope(dead_leaves(256, 0))
    fine = _spectral_slope(dead_leaves(256, 0, r_min=0.75))
    assert -3.0 < default < -2.45, default
    assert fine > default + 0.2, (fine, default)


def test_bad_sizes_and_radii_are_refused():
    for size in (4, 10**5, 64.0, True):
        with pytest.raises(ValueError, match="size"):
            dead_leaves(size)
    for r_min, r_max in ((0.1, 10.0), (5.0, 2.0), (np.nan, 3.0), (1.0, np.inf)):
        with pytest.raises(ValueError, match="r_min"):
            dead_leaves(32, r_min=r_min, r_max=r_max)
    with pytest.raises(ValueError, match="count"):
        dead_leaves_images(0, 32)


def test_training_sets_and_their_window_shares():
    photos = [np.full((40, 40, 3), 0.2, np.float32), np.full((20, 80, 3), 0.4, np.float32)]
    imgs, w = S.training_images("images", photos)
    assert len(imgs) == 2 and w is None
    imgs, w = S.training_images("dead-leaves", photos, count=3, side=32)
    assert len(imgs) == 3 and w is None and imgs[0].shape == (32, 32, 3)
    imgs, w = S.training_images("mixed", photos, count=4, side=32)
    assert len(imgs) == 6
    np.testing.assert_allclose(w, [0.25, 0.25, 0.125, 0.125, 0.125, 0.125])
    with pytest.raises(ValueError, match="training source"):
        S.training_images("leaves", photos)
    # A share of 0 is never drawn; shares that do not sum to 1 are refused.
    sampler = S.PatchSampler(photos, 16, seed=0, weights=[0.0, 1.0])
    assert np.all(sampler.sample(20) == np.float32(0.4))
    with pytest.raises(ValueError, match="weights"):
        S.PatchSampler(photos, 16, weights=[0.5, 0.6])
    with pytest.raises(ValueError, match="weights"):
        S.PatchSampler(photos, 16, weights=[1.0])
    # Without shares, windows follow the images' areas, as before.
    assert S.PatchSampler(photos, 16).p == pytest.approx([0.5, 0.5])


def test_the_command_line_option_reaches_the_config_and_a_resume_sees_it():
    from jaxlens.experiments.edof.train import config_data, training_config

    a = cli.build_parser().parse_args(["--train-source", "mixed"])
    cfg = cli.config_from_args(a)
    assert cfg.train_source == "mixed"
    assert cli.config_from_args(cli.build_parser().parse_args([])).train_source == "images"
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(["--train-source", "leaves"])
    # A checkpoint trained on other scenes is not resumed as if it were the same training.
    old = config_data(cli.config_from_args(cli.build_parser().parse_args([])))
    assert training_config(old, "hybrid") != training_config(config_data(cfg), "hybrid")
    older = json.loads(json.dumps(old))
    del older["train_source"]  # written before the option existed: the photographs
    assert training_config(older, "hybrid") == training_config(old, "hybrid")


def test_contrast_scales_the_steps_between_discs():
    """Same seed, same discs: only the colours move toward mid-grey, so neighbouring pixel
    differences shrink (in sRGB exactly by the contrast; in linear light about so), and the
    training set's contrast keeps its pixel differences near the photographs' (0.0046)."""
    full, half = dead_leaves(128, 5), dead_leaves(128, 5, contrast=0.5)
    grey = dead_leaves(128, 5, contrast=0.0)
    d = lambda a: float(np.mean(np.diff(a, axis=1) ** 2))  # noqa: E731
    assert d(grey) < 1e-12 and 0.1 < d(half) / d(full) < 0.45
    imgs, _ = S.training_images("dead-leaves", [], count=2, side=256)
    assert 0.002 < np.mean([d(a) for a in imgs]) < 0.008
    for bad in (-0.1, 1.5, np.nan, "1"):
        with pytest.raises(ValueError, match="contrast"):
            dead_leaves(32, contrast=bad)
