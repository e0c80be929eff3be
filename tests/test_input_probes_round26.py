"""Bad input, round 26 (tools/audit26_probe.py): one test per class of gap fixed. Each names
what main did with the input: a silent answer, a run that never ended, a traceback, or a
message that named no argument. The checks run where concrete inputs enter.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import zernike
from jaxlens.experiments.edof import dead_leaves as DL
from jaxlens.experiments.edof import evaluate as EV
from jaxlens.experiments.edof import optics as EO
from jaxlens.experiments.edof import scenes as S

BK7_B = (1.03961212, 0.231792344, 1.01046945)
BK7_C = (0.00600069867, 0.0200179144, 103.560653)
PHOTO = np.full((40, 40, 3), 0.3, np.float32)


def test_sellmeier_with_b_and_c_swapped_is_refused_naming_both():
    """Main: built, and ``index(0.5876)`` was NaN (between the swapped formula's poles)."""
    with pytest.raises(ValueError, match=r"B and C look swapped.*1\.51680.*µm²"):
        jl.Sellmeier(BK7_C, BK7_B)
    assert float(jl.Sellmeier(BK7_B, BK7_C).index(0.5875618)) == pytest.approx(1.5168, abs=1e-4)
    # An infrared-only formula without a real index at the d line stays (germanium: a
    # constant as a C = 0 term, a pole at 0.66 µm).
    ge = jl.Sellmeier((8.28156, 6.72880, 0.21307), (0.0, 0.44105, 3870.1))
    assert float(ge.extrapolated_index(10.0)) == pytest.approx(4.00, abs=0.01)


def test_sellmeier_with_c_as_resonance_wavelengths_is_refused():
    """C typed as the resonance wavelengths in µm (√C) instead of µm²: N-BK7 became a glass
    of nd 1.642 and Vd 4.1 without a word. Every shipped Sellmeier glass as given passes, and
    so do infrared crystals (silicon, germanium, ZnSe) and rutile-like strong UV poles."""
    with pytest.raises(ValueError, match=r"resonance wavelengths in µm.*Vd 4\.06.*1\.51680"):
        jl.Sellmeier(BK7_B, tuple(np.sqrt(BK7_C)))
    jl.Sellmeier((10.6684293, 0.0030434748, 1.54133408),
                 (0.301516485**2, 1.13475115**2, 1104.0**2))  # silicon
    jl.Sellmeier((4.45813734, 0.467216334, 2.89566290),
                 (0.200859853**2, 0.391371166**2, 47.1362108**2))  # ZnSe
    # Rutile (ordinary ray, Devore 1951: n² = 5.913 + 0.2441/(λ² − 0.0803)) as Sellmeier
    # terms: nd 2.62 and Vd 9.9, the strongest dispersion of a transparent crystal.
    rutile = jl.Sellmeier((5.913 - 1 - 0.2441 / 0.0803, 0.2441 / 0.0803), (0.0, 0.0803))
    assert float(rutile.index(0.5875618)) == pytest.approx(2.62, abs=0.01)


def test_zernike_terms_refuses_coordinates_that_are_not_normalised():
    """Main: points 7 mm out were evaluated (Z37 ~ 7¹² there) without a word; complex points
    lost their imaginary part's meaning (ρ² < 0)."""
    x = jnp.linspace(-0.5, 0.5, 5)
    with pytest.raises(ValueError, match=r"unit disc.*radius 7\.07"):
        zernike.zernike_terms(x * 10, x * 10)
    with pytest.raises(TypeError, match="zernike_terms: x must be a real"):
        zernike.zernike_terms(jnp.array([0.1j]), jnp.array([0.0]))
    with pytest.raises(ValueError, match=r"zernike_terms: x and y .*\(3,\) and \(4,\)"):
        zernike.zernike_terms(jnp.zeros(3), jnp.zeros(4), terms=3)
    # The corners of a square grid over the disc (ρ = √2) are still evaluated, and traced
    # points are not checked.
    assert zernike.zernike_terms(jnp.array(1.0), jnp.array(1.0), terms=4).shape == (4,)
    z = jax.jit(lambda a: zernike.zernike_terms(a, a, terms=4))(jnp.array(5.0))
    assert z.shape == (4,)


def test_dead_leaves_radii_seeds_and_contrast():
    """Main: r_max beyond the image was taken (r_max 10**6 on a 16-pixel image ran for
    ever: almost no disc met it), a negative seed raised NumPy's message without its name,
    contrast True was 1 and a float32 contrast refused."""
    with pytest.raises(ValueError, match=r"r_max .*r_min <= r_max <= size"):
        DL.dead_leaves(16, r_max=17.0)
    with pytest.raises(ValueError, match="dead_leaves: seed must be a whole number >= 0"):
        DL.dead_leaves(16, -1)
    with pytest.raises(ValueError, match="dead_leaves_images: seed"):
        DL.dead_leaves_images(2, 16, 1.5)
    with pytest.raises(ValueError, match="contrast"):
        DL.dead_leaves(16, contrast=True)
    assert DL.dead_leaves(16, contrast=np.float32(0.5)).shape == (16, 16, 3)


def test_dead_leaves_images_refuses_a_set_beyond_its_pixel_budget(monkeypatch):
    """Main: 1024 images of 4096² (192 GiB) started to be drawn, one after another."""
    def drawn(*a, **k):
        raise AssertionError("an image was drawn before the request was refused")

    monkeypatch.setattr(DL, "dead_leaves", drawn)
    with pytest.raises(ValueError, match=r"dead_leaves_images: 1024 images of 4096² .*Mpixels"):
        DL.dead_leaves_images(1024, 4096)


def test_training_images_need_photographs_for_images_and_mixed():
    """Main: no photographs gave ([], None) for "images" and NaN window shares for "mixed"
    (refused later by PatchSampler as a bad ``weights``)."""
    for source in ("images", "mixed"):
        with pytest.raises(ValueError, match=f"training source '{source}' needs photographs"):
            S.training_images(source, [], count=1, side=16)


def test_patch_sampler_refuses_images_it_cannot_sample():
    """Main: 8-bit codes gave windows of 200, a grey or RGBA image failed inside ``sample``,
    window 0 gave empty windows, no images a message about weights."""
    with pytest.raises(ValueError,
                       match=r"images\[0\] must be finite values in \[0, 1\] \(linear RGB\)"):
        S.PatchSampler([np.full((40, 40, 3), 200.0, np.float32)], 16)
    with pytest.raises(ValueError, match=r"images\[1\] must be an \[H, W, 3\]"):
        S.PatchSampler([PHOTO, PHOTO[..., 0]], 16)
    with pytest.raises(ValueError, match="PatchSampler: window"):
        S.PatchSampler([PHOTO], 0)
    with pytest.raises(ValueError, match="at least one"):
        S.PatchSampler([], 16)
    with pytest.raises(TypeError, match="PatchSampler: weights"):
        S.PatchSampler([PHOTO], 16, weights="abc")
    with pytest.raises(ValueError, match="PatchSampler: seed"):
        S.PatchSampler([PHOTO], 16, seed=-1)
    with pytest.raises(ValueError, match=r"PatchSampler.sample: n .*memory"):
        S.PatchSampler([PHOTO], 16).sample(10**9)


def test_edof_cli_refuses_a_train_dir_that_dead_leaves_would_ignore(tmp_path):
    """Main: the folder's photographs were loaded and not used."""
    from PIL import Image

    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    (tmp_path / "imgs").mkdir()
    Image.fromarray(np.full((32, 32, 3), 100, np.uint8)).save(tmp_path / "imgs" / "a.png")
    a = cli.build_parser().parse_args(["--smoke", "--train-dir", str(tmp_path / "imgs"),
                                       "--train-source", "dead-leaves", "--out",
                                       str(tmp_path / "o")])
    with pytest.raises(UsageError, match="--train-dir .* --train-source dead-leaves"):
        cli.check_args(a)


def test_edof_statistics_and_noise_refuse_what_gave_nan_or_a_traceback():
    """Main: bootstrap_gain of 1-D differences failed to unpack, n=0 raised IndexError, NaN
    differences gave a NaN interval; wiener_nsr and add_noise with 0 photons gave inf and
    NaN, a negative count less noise; 8-bit windows a 255²-times smaller NSR; placements of
    -1 crops an empty list."""
    d = np.random.default_rng(0).normal(size=(2, 6))
    with pytest.raises(ValueError, match=r"bootstrap_gain: diff must be \[seeds, crops\]"):
        EV.bootstrap_gain(d[0])
    with pytest.raises(ValueError, match="bootstrap_gain_by_image: n must"):
        EV.bootstrap_gain_by_image(d, ["a"] * 6, n=0)
    with pytest.raises(ValueError, match="bootstrap_gain: diff must be finite"):
        EV.bootstrap_gain(np.full((2, 6), np.nan))
    w = np.random.default_rng(0).random((4, 16, 16, 3))
    with pytest.raises(ValueError, match="wiener_nsr: photons"):
        EV.wiener_nsr(w, photons=0.0, read=0.01)
    with pytest.raises(ValueError, match=r"wiener_nsr: windows .*\[0, 1\]"):
        EV.wiener_nsr(w * 255, photons=100.0, read=0.01)
    with pytest.raises(ValueError, match="add_noise: photons"):
        EO.add_noise(jnp.ones(4), jax.random.PRNGKey(0), photons=-1.0, read=0.0)
    with pytest.raises(ValueError, match="placements: n"):
        EV.placements(-1, (4, 4), 2)


def test_frames_refuse_counts_off_the_lens_and_non_lenses():
    """Main: frames_after(lens, -1) gave the frame before surface 1 alone, 99 an IndexError,
    frame_of("lens") an AttributeError; a numpy order (np.int64(1), as a file reader gives)
    was kept static as a numpy scalar, with equinox's warning about a static array."""
    from jaxlens import zoo
    from jaxlens.optics import coordinates as C

    cooke = zoo.cooke_triplet()
    for n in (-1, 99, 2.0):
        with pytest.raises(ValueError, match=r"frames_after: n must be a surface count in \[0"):
            C.frames_after(cooke, n)
    with pytest.raises(TypeError, match="frame_of: lens must be a jaxlens.Lens, got str"):
        C.frame_of("lens")
    assert type(C.CoordinateBreak(order=np.int64(1)).order) is int


def test_nets_layers_refuse_what_failed_at_the_first_call():
    """Main: NAFBlock took an int32 dtype (integer weights), an odd expanded width and a
    wrong channel count failed inside simple_gate or a broadcast; Upsample with an odd c_in
    failed in the pixel shuffle's reshape."""
    from jaxlens import nets

    key = jax.random.PRNGKey(0)
    with pytest.raises(ValueError, match="NAFBlock: dtype"):
        nets.NAFBlock(4, key=key, dtype=jnp.int32)
    with pytest.raises(ValueError, match=r"NAFBlock: channels · dw_expand must be even"):
        nets.NAFBlock(3, dw_expand=3, key=key)
    with pytest.raises(ValueError, match=r"NAFBlock: expected an \[H, W, 4\] input"):
        nets.NAFBlock(4, key=key)(jnp.ones((8, 8, 3)))
    with pytest.raises(ValueError, match="Upsample: c_in must be even"):
        nets.Upsample(3, key=key)


def test_edof_cli_names_an_unreadable_image_before_the_run(tmp_path):
    """Main: a truncated PNG in --train-dir passed the option checks and failed after the
    lens set-up as Pillow's "image file is truncated", without the file's name."""
    from PIL import Image

    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    (tmp_path / "imgs").mkdir()
    Image.fromarray(np.full((32, 32, 3), 100, np.uint8)).save(tmp_path / "a.png")
    whole = (tmp_path / "a.png").read_bytes()
    (tmp_path / "imgs" / "b.png").write_bytes(whole[: len(whole) // 2])
    a = cli.build_parser().parse_args(["--smoke", "--train-dir", str(tmp_path / "imgs"),
                                       "--out", str(tmp_path / "o")])
    with pytest.raises(UsageError, match=r"--train-dir: scenes: cannot read the image .*b\.png"):
        cli.check_args(a)
    with pytest.raises(ValueError, match=r"cannot read the image .*b\.png"):
        S.load_images(folder=tmp_path / "imgs")


def test_edof_lens_helpers_refuse_depths_indices_and_counts():
    """Main: dioptric_weights of one depth was an IndexError and of a 0 m depth NaN weights;
    cubic_strength_guess took a negative ratio (a negative strength); to_hybrid(index=-1)
    put the hybrid surface in front of every surface (a lens of 2N surfaces) and n_odd=0
    failed inside JAX; with_binning(True) was binning 1."""
    from jaxlens.experiments.edof import lenses as L

    lens = L.classical_lens(binning=8)
    with pytest.raises(ValueError, match=r"dioptric_weights: depths_m must be at least 2"):
        L.dioptric_weights((0.1,))
    with pytest.raises(ValueError, match=r"dioptric_weights: depths_m .*> 0 \(m"):
        L.dioptric_weights((0.0, 1.0))
    with pytest.raises(ValueError, match="cubic_strength_guess: ratio"):
        L.cubic_strength_guess(lens, ratio=-1.0)
    with pytest.raises(ValueError, match=r"to_hybrid: index must be a surface index in \[0, "):
        L.to_hybrid(lens, index=-1)
    with pytest.raises(ValueError, match="to_hybrid: n_odd"):
        L.to_hybrid(lens, n_odd=0)
    with pytest.raises(ValueError, match="with_binning: binning must be a whole number"):
        L.with_binning(lens, True)
    assert L.dioptric_weights((1.0, 0.1, 3.0)).sum() == pytest.approx(1.0)  # any order


def test_merge_refuses_an_out_folder_that_is_one_of_its_runs(tmp_path):
    """Main: ``merge runA runB --out runA --overwrite`` was accepted (runA holds a finished
    run), so the merge would replace one of the runs it read."""
    from jaxlens.experiments.edof import merge
    from jaxlens.experiments.runfolder import FINISHED, UsageError

    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / FINISHED).write_text("")
    runs = [str(tmp_path / "a"), str(tmp_path / "b")]
    with pytest.raises(UsageError, match=r"--out .* one of the runs to merge"):
        merge.run([*runs, "--out", str(tmp_path / "a"), "--overwrite"])
