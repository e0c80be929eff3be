"""Ninth round of bad-input probes: each case used to give a silent wrong answer (a NaN pupil
point counted as a vignetted ray, an MTF of 0 for a field without light, a string read as
a number, a switch "no" read as True) or an error from deep inside a compiled trace; each is
now refused before the work starts, naming the argument, the value, the range and the unit.
"""

from __future__ import annotations

import pathlib
import re

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import analysis
from jaxlens.analysis.report import report_data
from jaxlens.imaging import psf as P

NAN = float("nan")
DATA = pathlib.Path(jl.__file__).parent / "data" / "lenses"
SMALL = P.GeometricPSF(pupil=8)


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


# ---------------------------------------------------------------- spot analyses: the pupil


@pytest.mark.parametrize("call", [
    lambda l, p: analysis.rms_spot(l, pupil=p),
    lambda l, p: analysis.spot_rays(l, 5.0, pupil=p),
    lambda l, p: analysis.clear_semi_diameters(l, pupil=p),
], ids=["rms_spot", "spot_rays", "clear_semi_diameters"])
@pytest.mark.parametrize("bad", [NAN, np.inf])
def test_spot_analyses_refuse_a_pupil_point_that_is_not_finite(cooke, call, bad):
    """The pupil reached the compiled trace as a tracer, where its finite check is skipped: a
    NaN point's ray failed and counted as vignetted (rms_spot's valid_fraction fell to 0.5,
    its radius came from the other rays)."""
    pupil = jnp.array([[0.0, 0.0], [bad, 0.5]])
    with pytest.raises(ValueError, match=r"pupil \(normalised pupil coordinates\) holds 1 NaN or "
                                         r"infinite value\(s\), first at index \(1, 0\)"):
        call(cooke, pupil)


def test_spot_analyses_refuse_a_pupil_of_strings_or_the_wrong_shape(cooke):
    with pytest.raises(TypeError, match=r"rms_spot: pupil must be a real number or an array of "
                                        r"real numbers \(normalised pupil coordinates\), got str"):
        analysis.rms_spot(cooke, pupil="abc")
    # was a TypeError from jnp.concatenate about shapes (65, 2) and (3, 3)
    with pytest.raises(ValueError, match=r"clear_semi_diameters: pupil must be \[M, 2\] "
                                         r"normalised pupil points \(Px, Py\), got shape \(3, 3\)"):
        analysis.clear_semi_diameters(cooke, pupil=jnp.zeros((3, 3)))
    # finite pupils still work, as lists too
    r = analysis.rms_spot(cooke, pupil=[[0.0, 0.0], [0.1, 0.5]])
    assert np.all(np.isfinite(np.asarray(r.polychromatic)))


# ---------------------------------------------------------------- the lens's own wavelengths


def _wavelengths(lens, wl):
    return eqx.tree_at(lambda x: x.wavelengths, lens, jnp.asarray(wl))


@pytest.mark.parametrize("call, where", [
    (lambda l: analysis.rms_spot(l), "rms_spot"),
    (lambda l: analysis.clear_semi_diameters(l), "clear_semi_diameters"),
    (lambda l: report_data(l), "report"),
])
def test_the_lens_wavelengths_are_checked_before_the_trace(cooke, call, where):
    """A lens whose wavelengths lie outside its glasses' data (eqx.tree_at skips the Lens's
    checks) failed with an EquinoxRuntimeError from inside the compiled trace, after the
    work."""
    lens = _wavelengths(cooke, [0.25, 0.5875618, 0.6562725])
    with pytest.raises(ValueError, match=rf"{where}: the lens's wavelengths 0.25 µm is outside "
                                         rf"0.48\d*–0.65\d* µm, the data range of SK16"):
        call(lens)


def test_the_primary_wavelength_alone_is_checked_where_only_it_is_used(cooke):
    lens = _wavelengths(cooke, [0.25, 0.5875618, 0.6562725])
    d = analysis.distortion(lens)  # the primary wavelength is in range: still computed
    assert np.all(np.isfinite(np.asarray(d.percent_ftan)))
    lens = eqx.tree_at(lambda x: x.wavelengths, cooke, jnp.array([0.48, 0.25, 0.6]))
    with pytest.raises(ValueError, match=r"chief_ray: the lens's primary wavelength 0.25 µm is "
                                         r"outside"):
        analysis.chief_ray(lens, 5.0)


# ---------------------------------------------------------------- ray fans, field curvature


def test_fans_and_curvature_refuse_strings_for_numbers(cooke):
    """jnp.asarray("5", float) is 5.0: a field given as a string was traced."""
    with pytest.raises(TypeError, match=r"ray_fan: field must be a real number or an array of "
                                        r"real numbers \(deg\), got str '5'"):
        analysis.ray_fan(cooke, "5")
    with pytest.raises(TypeError, match=r"field_curvature: fields must be a real number .* "
                                        r"\(deg\), got str 'abc'"):  # was "could not convert"
        analysis.field_curvature(cooke, fields="abc")
    with pytest.raises(TypeError, match=r"ray_fan: wavelengths must be a real number .*\(µm\)"):
        analysis.ray_fan(cooke, 5.0, wavelengths="0.55")


# ---------------------------------------------------------------- MTF and PSF


@pytest.mark.parametrize("model", [SMALL, P.CoherentPSF(pupil=8)], ids=["geometric", "coherent"])
def test_mtf_of_a_field_without_light_is_refused_not_zero(cooke, model):
    """60° is far beyond the triplet's coverage: the MTF was 0 at every frequency (0 even at
    0 cycles/mm), where psf refuses the same field."""
    with pytest.raises(P.NoLightError, match=r"mtf: no ray of the beam reaches the image surface "
                                         r"\(the field is vignetted or beyond the lens's "
                                         r"coverage\), so there is no MTF \(field 60 deg"):
        P.mtf(cooke, 60.0, model=model, kernel_size=16)
    f, t, s = P.mtf(cooke, 10.0, model=SMALL)
    assert abs(float(t[0]) - 1.0) < 1e-6 and abs(float(s[0]) - 1.0) < 1e-6


def test_psf_and_mtf_refuse_strings_for_numbers(cooke):
    with pytest.raises(TypeError, match=r"psf: wavelength must be a real number .*\(µm\), got "
                                        r"str '0.55'"):
        jl.psf(cooke, 0.0, wavelength="0.55", kernel_size=15, pixel_size=0.005, model=SMALL)
    with pytest.raises(TypeError, match=r"mtf: wavelengths must be a real number .*\(µm\)"):
        P.mtf(cooke, 0.0, wavelengths="0.55", model=SMALL)
    with pytest.raises(TypeError, match=r"mtf: pixel_size must be a real number .*\(mm\), got "
                                        r"str '0.001'"):
        P.mtf(cooke, 0.0, pixel_size="0.001", model=P.CoherentPSF(pupil=8), kernel_size=8)


# ---------------------------------------------------------------- render and distortion maps


@pytest.fixture(scope="module")
def small_sensor(cooke):
    return eqx.tree_at(lambda x: x.sensor, cooke, jl.Sensor((8, 8), 0.01),
                       is_leaf=lambda x: x is None)


@pytest.mark.parametrize("kw, error, match", [
    (dict(relative_illumination="no"), ValueError,
     r"render: relative_illumination must be True or False, got 'no'"),  # "no" read as True
    (dict(checkpoint=None), ValueError, r"render: checkpoint must be True or False, got None"),
    (dict(sensor=(8, 8)), TypeError, r"render: sensor must be a jaxlens.Sensor, got tuple"),
    (dict(wavelengths=["0.5", "0.55", "0.6"]), TypeError,
     r"render: wavelengths must be a real number or an array of real numbers \(µm\)"),
])
def test_render_refuses_switches_sensors_and_wavelengths_of_the_wrong_type(small_sensor, kw,
                                                                          error, match):
    import jax

    with pytest.raises(error, match=match):
        jl.render(small_sensor, jnp.ones((8, 8, 3)), spp=1, key=jax.random.PRNGKey(0), **kw)


def test_render_names_a_half_precision_scene(small_sensor):
    import jax

    # was "footprints: dtype must be None, float32 or float64"
    with pytest.raises(ValueError, match=r"render: scene must be float32 or float64, got dtype "
                                         r"float16"):
        jl.render(small_sensor, jnp.ones((8, 8, 3), jnp.float16), spp=1,
                  key=jax.random.PRNGKey(0))


def test_distortion_map_refuses_chief_rays_that_miss_the_image(cooke):
    """A 160 mm sensor behind the 50 mm triplet: the corner chief rays (66°) miss a surface and
    stopped there, so the map gave a plausible (9.6, 9.6) mm for the ideal point (70, 70)."""
    from jaxlens.imaging import distortion as D

    big = eqx.tree_at(lambda x: x.sensor, cooke, jl.Sensor((8, 8), 20.0),
                      is_leaf=lambda x: x is None)
    msg = (r"distortion_map: the real chief ray of grid point \(row 0, col 0\) \(first of "
           r"\d+\), ideal image point \(70, -70\) mm, does not reach the image surface")
    with pytest.raises(ValueError, match=msg):
        D.distortion_map(big, grid=(3, 3))
    with pytest.raises(ValueError, match=msg):
        D.prewarp(big, jnp.ones((8, 8, 3)), grid=(3, 3))
    ok = eqx.tree_at(lambda x: x.sensor, cooke, jl.Sensor((8, 8), 2.0),
                     is_leaf=lambda x: x is None)
    assert np.all(np.isfinite(np.asarray(D.distortion_map(ok, grid=(3, 3)).real)))


def test_prewarp_refuses_a_nan_scene_and_another_aspect_ratio(small_sensor):
    from jaxlens.imaging import distortion as D

    with pytest.raises(ValueError, match=r"prewarp: scene \(linear pixel values\) holds 1 NaN"):
        D.prewarp(small_sensor, jnp.ones((8, 8, 3)).at[1, 2, 0].set(NAN), grid=(3, 3))
    with pytest.raises(ValueError, match=r"prewarp: scene of 8x80 pixels does not match the 8x8 "
                                         r"sensor"):
        D.prewarp(small_sensor, jnp.ones((8, 80, 3)), grid=(3, 3))


# ---------------------------------------------------------------- design seeds


@pytest.mark.parametrize("seeds, kw, match", [
    ("12", {}, r"design: seeds must be a non-empty list of whole numbers >= 0, got '12'"),
    ([1.5], {}, r"design: seeds must be a whole number in \[0, inf\), got 1.5"),
    ([1, 1], {}, r"design: seeds must be distinct \(a repeated seed designs the same lens "
                 r"twice\), got \[1, 1\]"),
    ([2**32], {}, r"design: seeds must be whole numbers in \[0, 4294967295\] \(seeds of JAX's "
                    r"PRNG\), got 4294967296"),
    ([0], dict(on_nonfinite="ignore"), r"design: on_nonfinite must be 'raise' or 'drop'"),
    ([0], dict(devices=[]), r"design: devices must be a non-empty list of JAX devices"),
])
def test_design_checks_its_seeds_before_any_work(seeds, kw, match):
    """design() took int(s) of every seed: "12" was seeds 1 and 2, 1.5 was 1; a repeat
    designed the same lens twice; 2**32 was seed 0 again without x64 (and 2**63 overflowed
    with it); devices=[] divided by zero."""
    from jaxlens.design import DesignSpec, design

    with pytest.raises(ValueError, match=match):
        design(DesignSpec(), seeds, progress=False, **kw)


def test_random_starts_refuses_a_seed_beyond_uint32():
    from jaxlens.design import DesignSpec, random_starts

    with pytest.raises(ValueError, match=r"random_starts: seeds must be whole numbers in "
                                         r"\[0, 4294967295\] \(seeds of JAX's PRNG\), got "
                                         r"4294967296"):
        random_starts(DesignSpec(), [2**32])
    assert random_starts(DesignSpec(), np.arange(2)).c.shape[0] == 2


@pytest.mark.parametrize("args", [["--first-seed", "99999999999999999999"],
                                  ["--seed-list", "4294967296"],
                                  ["--first-seed", "2147483648", "--population", "2"]])
def test_classical_cli_refuses_seeds_beyond_uint32_before_the_run(tmp_path, capsys,
                                                                  monkeypatch, args):
    from jaxlens.experiments import classical

    def started(*a):
        raise AssertionError("the run started")

    monkeypatch.setattr(classical, "run_design", started)
    assert classical.main([*args, "--out", str(tmp_path / "run")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "seeds must keep them in [0, 4294967295]" in lines[0], lines
    assert not (tmp_path / "run").exists()


# ---------------------------------------------------------------- tolerancing


@pytest.mark.parametrize("kw, error, match", [
    (dict(min_valid=2.0), ValueError, r"monte_carlo: min_valid must be a finite number in "
                                      r"\[0, 1\] \(fraction of a field's rays\), got 2.0"),
    (dict(min_valid=NAN), ValueError, r"monte_carlo: min_valid must be a finite number"),
    (dict(key=5), ValueError, r"monte_carlo: key must be None or one PRNG key"),
    (dict(mtf_frequency="10"), TypeError, r"monte_carlo: mtf_frequency must be a real number "
                                          r".*\(cycles/mm\), got str '10'"),
])
def test_monte_carlo_checks_its_options_before_the_trials(kw, error, match):
    """min_valid was checked by yield_fraction only after every trial had been traced."""
    from jaxlens.analysis import tolerance as T

    class NoModel:  # any use of the model would be the trials starting
        def __getattr__(self, name):
            raise AssertionError("the trials started")

    args = dict(trials=3, threshold_um=5.0, mtf_frequency=10.0) | kw
    with pytest.raises(error, match=match):
        T.monte_carlo(NoModel(), **args)


@pytest.mark.parametrize("args, match", [
    (["--seed", "-1"], r"--seed must be a whole number in \[0, 4294967295\], got -1"),
    (["--seed", "99999999999999999999"], r"--seed must be a whole number in \[0, 4294967295\]"),
    (["--out", "FILE"], r"--out .*out.txt is a file, not a folder"),
])
def test_tolerance_cli_refuses_a_bad_seed_and_a_file_for_out_first(tmp_path, capsys, args,
                                                                    match):
    """Both were found only after the sensitivity analysis (the seed) or the whole analysis
    (--out, when writing)."""
    from jaxlens.experiments import tolerance as cli

    out = tmp_path / "out.txt"
    out.write_text("x")
    args = [str(out) if a == "FILE" else a for a in args]
    assert cli.main([str(DATA / "cooke_triplet.json"), *args]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and re.search(match, lines[0]), lines


# ---------------------------------------------------------------- relative illumination, edof


def test_relative_illumination_takes_one_wavelength_as_a_number(cooke):
    from jaxlens.imaging.radiometry import relative_illumination

    # was "Rays: wavelength must be a scalar or one value per ray (shape (256,))"
    with pytest.raises(ValueError, match=r"relative_illumination: wavelength must be one value "
                                         r"\(µm\), got shape \(2,\)"):
        relative_illumination(cooke, [0.0, 5.0], wavelength=[0.55, 0.6], pupil=8)
    with pytest.raises(TypeError, match=r"relative_illumination: wavelength must be a real "
                                        r"number .*\(µm\), got str '0.55'"):
        relative_illumination(cooke, [0.0, 5.0], wavelength="0.55", pupil=8)


def _one_line_refusal(main, argv, capsys, monkeypatch) -> str:
    import sys

    monkeypatch.setattr(sys, "argv", ["python -m ...", *argv])
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:
        main()
    assert e.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def test_edof_clis_refuse_seeds_beyond_uint32_before_the_run(tmp_path, capsys, monkeypatch):
    """Without x64 PRNGKey(2**32) is PRNGKey(0): the second seed repeated the first."""
    from jaxlens.experiments.edof import cli, design

    def started(*a, **k):
        raise AssertionError("the run started")

    monkeypatch.setattr(design, "design_classical", started)
    err = _one_line_refusal(cli.main, ["--seeds", "0,4294967296", "--out", str(tmp_path / "r")],
                            capsys, monkeypatch)
    assert "edof: --seeds must be whole numbers in [0, 4294967295] (seeds of JAX's PRNG), got " \
           "4294967296" in err
    assert not (tmp_path / "r").exists()
    err = _one_line_refusal(design.main, ["--smoke", "--seeds", "4294967296", "--out",
                                          str(tmp_path / "l.json"), "--record-dir",
                                          str(tmp_path / "rec")], capsys, monkeypatch)
    assert "--seeds must be whole numbers in [0, 4294967295]" in err


# ---------------------------------------------------------------- image metrics


def test_image_metrics_refuse_images_on_two_scales_and_name_small_images():
    from jaxlens.io import images

    a = np.random.default_rng(0).random((8, 8, 3))
    # a [0, 1] float image against the same image in 0…255 scored 4.6 dB
    with pytest.raises(ValueError, match=r"psnr: reference and test must be on one scale, got "
                                         r"dtypes float64 and uint8"):
        images.psnr(a, (a * 255).astype(np.uint8))
    with pytest.raises(ValueError, match=r"ssim: reference and test must be on one scale"):
        images.ssim((a * 255).astype(np.uint8), a)
    # skimage's message spoke of win_size and channel_axis, which were not given
    with pytest.raises(ValueError, match=r"ssim: images must be at least 7x7 pixels \(the "
                                         r"7-pixel window\), got shape \(3, 3\)"):
        images.ssim(a[:3, :3, 0], a[:3, :3, 1])
    with pytest.raises(ValueError, match=r"psnr: data_range must be a finite number in \(0, inf\)"):
        images.psnr(a, a * 0.9, data_range=0)
    u = (a * 255).astype(np.uint8)
    assert images.psnr(u, u // 2 * 2) > 40  # one scale, integers: still scored


# ---------------------------------------------------------------- glass catalogs


def test_unknown_glass_messages_name_the_catalog_spelling_and_the_catalog_it_is_in():
    # "SCHOTT:N-BK7" listed close names but not how to ask for a glass of one catalog
    with pytest.raises(ValueError, match=r"Unknown material 'SCHOTT:N-BK7'\. Closest catalog "
                                         r"matches: N-BK7.*A catalog is its own argument: "
                                         r"get_material\('N-BK7', 'SCHOTT'\)"):
        jl.get_material("SCHOTT:N-BK7")
    # a glass of another catalog was "unknown", with only that catalog's names as matches
    with pytest.raises(ValueError, match=r"Unknown material 'N-BK7'\. Closest catalog matches: "
                                         r".*'N-BK7' is in catalog SCHOTT, not searched here"):
        jl.get_material("N-BK7", "OHARA")
    assert jl.get_material("N-BK7", "schott").name == "N-BK7"


def test_catalog_helpers_refuse_ignored_or_non_numeric_arguments():
    with pytest.raises(ValueError, match=r"catalog_names: give catalog or catalogs, not both"):
        jl.catalog_names("SCHOTT", catalogs=["OHARA"])  # catalogs was ignored
    with pytest.raises(TypeError, match=r"get_material: nd must be a real number .*got str "
                                        r"'1.5'"):  # was "'<' not supported ..."
        jl.get_material("XYZ", nd="1.5", vd=60)


def test_lens_astype_takes_float32_or_float64(cooke):
    """astype(jnp.int32) truncated every curvature (0.045/mm) and thickness to whole numbers."""
    for dtype in (jnp.int32, jnp.float16):
        with pytest.raises(ValueError, match=r"Lens.astype: dtype must be None, float32 or "
                                             r"float64"):
            cooke.astype(dtype)
    assert cooke.astype(jnp.float32).thickness.dtype == jnp.float32


def test_plot_mtf_marks_a_field_without_light_instead_of_drawing_zero(cooke):
    from jaxlens import plot

    fig = plot.plot_mtf(cooke, [0.0, 60.0], frequencies=[0.0, 10.0])
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "60.0°: no light" in labels and not any(x.startswith("60.0° ") for x in labels)
    assert sum(len(line.get_xdata()) > 0 for line in fig.axes[0].get_lines()) == 2  # 0°: T, S


def test_edof_cli_keeps_an_earlier_record_without_overwrite(tmp_path, capsys, monkeypatch):
    """--record replaced an earlier run's table2.md, summary.json, … at the end of the run,
    where --out and edof.design's --record-dir refuse to without --overwrite."""
    from jaxlens.experiments.edof import cli

    rec = tmp_path / "rec"
    rec.mkdir()
    (rec / "table2.md").write_text("the earlier run")
    err = _one_line_refusal(cli.main, ["--smoke", "--out", str(tmp_path / "r"), "--record",
                                       str(rec)], capsys, monkeypatch)
    assert re.search(r"edof: --record .*rec already holds table2.md of an earlier run; give "
                     r"--overwrite to replace them", err), err
    assert (rec / "table2.md").read_text() == "the earlier run"
    assert not (tmp_path / "r").exists()


def test_curriculum_run_checks_every_stage_and_the_seed_labels_first():
    """A later stage's missing objective was found only after the stages before it had run."""
    import types

    from jaxlens.design import DesignSpec, Stage, run

    params = types.SimpleNamespace(c=jnp.zeros((2, 3)))
    stages = [Stage("ray first", 80.8, 2.0, 5), Stage("image next", 80.8, 2.0, 5, loss="image")]
    kw = dict(progress=False)
    with pytest.raises(ValueError, match=r"run: stage 'image next' needs a 'image' objective"):
        run(DesignSpec(), stages, params, object(), None, **kw)
    with pytest.raises(TypeError, match=r"run: stages must be Stage objects, got dict"):
        run(DesignSpec(), [{"fov": 80.8}], params, object(), None, **kw)
    with pytest.raises(ValueError, match=r"run: seeds must label the 2 designs of params, got 1"):
        run(DesignSpec(), stages[:1], params, object(), None, seeds=[7], **kw)


# ---------------------------------------------------------------- the reconstruction network


def test_nafnet_names_bad_sizes_dtypes_and_channel_counts():
    import jax

    from jaxlens.nets import NAFNet

    key = jax.random.PRNGKey(0)
    cases = [
        (dict(width=2.5), r"NAFNet: width must be a whole number in \[1, 1024\], got 2.5"),
        (dict(in_channels=0, out_channels=0), r"NAFNet: in_channels must be a whole number in "
                                              r"\[1, 65536\], got 0"),  # was ZeroDivisionError
        (dict(dtype=jnp.int32), r"NAFNet: dtype must be None, float32 or float64"),
    ]
    for kw, match in cases:
        with pytest.raises(ValueError, match=match):
            NAFNet(key=key, **{"width": 4, **kw})
    net = NAFNet(key=key, width=4, enc_blocks=(1,), dec_blocks=(1,))
    # was a conv_general_dilated feature-dimension error
    with pytest.raises(ValueError, match=r"NAFNet: expected an \[H, W, 3\] image \(in_channels "
                                         r"3\), got shape \(8, 8, 4\)"):
        net(jnp.ones((8, 8, 4)))


# ---------------------------------------------------------------- numpy integers and strings


def test_numpy_integers_count_as_whole_numbers_and_strings_do_not_as_tolerances():
    """A count from numpy (np.int64(4), e.g. from an array shape) was refused as not an
    int; a tolerance of "0.02" was read as 0.02 mm."""
    from jaxlens.analysis import tolerance

    lens = jl.zoo.cooke_triplet()
    model = tolerance.ToleranceModel(lens, batch=np.int64(4))
    assert model.batch == 4 and type(model.batch) is int
    with pytest.raises(ValueError, match=r"Tolerances: thickness must be a finite number >= 0 "
                                         r"mm, got '0.02'"):
        tolerance.Tolerances(thickness="0.02")
    with pytest.raises(ValueError, match="Tolerances: index must be a finite number >= 0"):
        tolerance.Tolerances(index=True)
