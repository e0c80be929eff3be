"""Bad input found by the input audit: each refused with a message naming the argument, the
range and the unit, before any long work (and no silent wrong answer)."""

from __future__ import annotations

import copy
import json
import pathlib

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import plot, zoo
from jaxlens.analysis import tolerance as T
from jaxlens.design import (
    DesignConfig,
    DesignSpec,
    Stage,
    evaluate_design,
    paper_stages,
    random_starts,
    reweighting_mask,
    sensor_field_grid,
    sine_path,
)
from jaxlens.imaging import aiming, distortion, psf, render
from jaxlens.io import images

DATA = pathlib.Path(jl.__file__).parent / "data"
GOOD_AGF = ("NM MYG 2 0 1.5168 64.17 0 0 0\n"
            "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
            "LD 0.3 2.5\n")


@pytest.fixture(scope="module")
def cooke():
    return zoo.cooke_triplet()


# ------------------------------------------------------------------------ design helpers
@pytest.mark.parametrize("call, match", [
    (lambda: sine_path(0.0, 1.0, -2), r"sine_path: n must be a whole number in \[0, 65536\] steps"),
    (lambda: sine_path(0.0, 1.0, 2.5), r"sine_path: n must be a whole number .*got 2.5"),
    (lambda: sine_path(float("nan"), 1.0, 3), r"sine_path: start must be a finite number"),
    (lambda: Stage("s", 200.0, 2.0, 10), r"Stage 's': fov must be .* in \(0, 180\) deg"),
    (lambda: Stage("s", 40.0, 0.0, 10), r"Stage 's': fnum must be .* in \(0, inf\)"),
    (lambda: Stage("s", 40.0, 2.0, -1), r"Stage 's': steps must be a whole number in \[0"),
    (lambda: Stage("s", 40.0, 2.0, 1, solver="sgd"), r"solver must be one of .*'sgd'"),
    (lambda: Stage("s", 40.0, 2.0, 1, loss="l2"),
     r"loss must be one of \('ray', 'image', 'polish'\)"),
    (lambda: Stage("s", 40.0, 2.0, 1, lr=-1.0), r"lr must be .* in \(0, inf\)"),
    (lambda: paper_stages(DesignSpec(), steps=-1), r"paper_stages: steps must be a whole"),
    (lambda: paper_stages(DesignSpec(), pin=float("nan")), r"paper_stages: pin must be"),
    (lambda: DesignConfig(n_fields=0), r"DesignConfig: n_fields must be a whole number in "
                                       r"\[1, 257\], got 0"),
    (lambda: DesignConfig(steps=-1), r"DesignConfig: steps must be a whole number"),
    (lambda: DesignConfig(rings=2.5), r"DesignConfig: rings must be a whole number"),
    (lambda: DesignConfig(curriculum="no"), r"DesignConfig: curriculum must be True or False"),
    (lambda: DesignConfig(lr_c=float("nan")), r"DesignConfig: lr_c must be a finite number"),
    (lambda: DesignConfig(population=0), r"population must be at least 1"),
    (lambda: random_starts(DesignSpec(), []), r"random_starts: seeds must be a non-empty"),
    (lambda: random_starts(DesignSpec(), [1.5]), r"random_starts: seeds must be a whole "
                                                 r"number in \[0, inf\), got 1.5"),
    (lambda: random_starts(DesignSpec(), 3), r"random_starts: seeds must be a non-empty"),
    (lambda: random_starts(DesignSpec(), [0], dtype=jnp.int32),
     r"random_starts: dtype must be None, float32 or float64"),
    (lambda: sensor_field_grid(DesignSpec(), 0), r"sensor_field_grid: n must be a whole "
                                                 r"number in \[1, 257\] fields per side"),
    (lambda: sensor_field_grid(DesignSpec(), 2.5), r"sensor_field_grid: n must be"),
    (lambda: reweighting_mask(jnp.ones(4), threshold=2.0),
     r"reweighting_mask: threshold must be a finite number in \[0, 1\]"),
    (lambda: reweighting_mask(jnp.ones(4), jnp.ones(3)), r"area must be \[K\] = \(4,\)"),
    (lambda: reweighting_mask("abc"), r"reweighting_mask: rms must be a real number"),
])
def test_design_helpers_refuse_bad_counts_and_numbers(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_design_helpers_still_take_good_values():
    assert sine_path(0.0, 1.0, 0).tolist() == [1.0]
    assert len(paper_stages(DesignSpec(), n=0)) == 2
    assert DesignConfig().scaled(0.1).steps == 45
    assert random_starts(DesignSpec(), [np.int64(0), 1]).c.shape[0] == 2
    assert np.allclose(reweighting_mask(jnp.array([1.0, 2.0]), threshold=0.0), [2 / 3, 4 / 3])
    # multistart.design gives the polish this loss when DesignConfig.polish_rings is set.
    assert [Stage("s", 40.0, 2.0, 1, loss=k).loss for k in ("ray", "image", "polish")] == [
        "ray", "image", "polish"]


def test_evaluate_design_checks_its_arguments(cooke):
    with pytest.raises(ValueError, match=r"evaluate: min_valid must be a finite number in "
                                         r"\[0, 1\] \(fraction of rays\), got 2"):
        evaluate_design(cooke, DesignSpec(), n=2, min_valid=2.0)
    with pytest.raises(ValueError, match=r"evaluate: n must be a whole number in \[1, 257\]"):
        evaluate_design(cooke, DesignSpec(), n=0)
    with pytest.raises(TypeError, match=r"evaluate: lens must be a jaxlens Lens, got str"):
        evaluate_design("lens", DesignSpec())


# ------------------------------------------------------------------------------- images
@pytest.mark.parametrize("call, match", [
    (lambda: images.psnr(np.full((4, 4), np.nan), np.ones((4, 4))),
     r"psnr: reference holds 16 NaN or infinite"),
    (lambda: images.ssim(np.ones((16, 16)), np.full((16, 16), np.inf)),
     r"ssim: test holds 256 NaN or infinite"),
    (lambda: images.psnr(np.ones((0,)), np.ones((0,))), r"psnr: the images are empty"),
    (lambda: images.to_linear(np.full((2, 2, 3), 300, np.int64)),
     r"to_linear: an integer image must be uint8 or uint16 sRGB, got int64"),
    (lambda: images.scene(size=(0, 10)), r"scene: size must be \(rows, cols\), whole numbers "
                                         r">= 1 pixels \(at most 16384 per side\), got \(0, 10\)"),
    (lambda: images.scene(size=(2.5, 10)), r"scene: size must be \(rows, cols\)"),
])
def test_image_helpers_refuse_nan_empty_and_wrong_types(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_write_png_refuses_nan_and_writes_nothing(tmp_path):
    out = tmp_path / "x.png"
    with pytest.raises(ValueError, match=r"write_png: img must be finite values \(values in "
                                         r"\[0, 1\], clipped\), got nan \(3 bad of 4\)"):
        images.write_png(out, np.array([[0.5, np.nan], [np.nan, np.nan]]))
    assert not out.exists()
    assert images.to_linear(np.full((1, 1, 3), 65535, np.uint16)).max() == 1.0


# --------------------------------------------------------------------------------- plots
def test_plots_check_counts_sizes_and_inputs(cooke):
    with pytest.raises(ValueError, match=r"plot_layout: n_rays must be a whole number in "
                                         r"\[1, inf\) rays per fan, got 0"):
        plot.plot_layout(cooke, n_rays=0)
    with pytest.raises(ValueError, match=r"plot_rms_map: sensor_size must be a finite number "
                                         r"in \(0, inf\) mm, got -3"):
        plot.plot_rms_map(np.ones((3, 3)), (-3.0, 3.0))
    with pytest.raises(ValueError, match=r"plot_rms_map: sensor_size must be \(height, width\)"):
        plot.plot_rms_map(np.ones((3, 3)), 3.0)
    with pytest.raises(ValueError, match=r"plot_rms_map: rms_um must be \[n, n\] or \[n²\]"):
        plot.plot_rms_map(np.ones(5), (3.0, 3.0))
    with pytest.raises(TypeError, match=r"plot_progress: history must be a design History"):
        plot.plot_progress([])
    with pytest.raises(ValueError, match=r"plot_tolerance_histogram: mc must be the dict"):
        plot.plot_tolerance_histogram({})


def test_zoo_clip_must_be_a_bool():
    with pytest.raises(ValueError, match=r"zoo: clip must be True or False, got 'no'"):
        zoo.cooke_triplet(clip="no")
    with pytest.raises(ValueError, match=r"zoo: clip must be True or False, got None"):
        zoo.cellphone6(clip=None)


# ----------------------------------------------------------------------------- tolerance
def test_tolerance_checks_fields_wavelengths_and_pupil_up_front(cooke):
    with pytest.raises(ValueError, match=r"symmetric_fields: fields must be finite angles in "
                                         r"\(-90, 90\) deg, got 95 deg"):
        T.symmetric_fields([95.0])
    with pytest.raises(ValueError, match=r"ToleranceModel: fields must be finite angles"):
        T.ToleranceModel(cooke, fields=[0.0, 95.0])
    with pytest.raises(ValueError, match=r"ToleranceModel: wavelengths 587 µm is outside "
                                         r".*587 nm is 0.587 µm"):
        T.ToleranceModel(cooke, wavelengths=[587.0])
    with pytest.raises(ValueError, match=r"ToleranceModel: pupil must be \[M, 2\]"):
        T.ToleranceModel(cooke, pupil=0)
    with pytest.raises(ValueError, match=r"ToleranceModel: pupil must be finite numbers in "
                                         r"\[-1, 1\]"):
        T.ToleranceModel(cooke, pupil=[[0.0, 2.0]])


# ------------------------------------------------------------------------------- imaging
def test_imaging_helpers_check_before_the_jitted_work(cooke):
    lens = eqx.tree_at(lambda x: x.sensor, cooke, jl.Sensor((16, 16), 0.02),
                       is_leaf=lambda x: x is None)
    with pytest.raises(ValueError, match=r"footprints: grid must be a whole number in "
                                         r"\[2, 257\] points per side, got 0"):
        render.footprints(lens, grid=0)
    with pytest.raises(ValueError, match=r"footprints: wavelengths 587 µm is outside"):
        render.footprints(lens, grid=3, wavelengths=(587.0,))
    with pytest.raises(ValueError, match=r"footprints: dtype must be None, float32 or float64"):
        render.footprints(lens, grid=3, dtype=jnp.int32)
    with pytest.raises(ValueError, match=r"alignment_penalty: alpha must be a finite number "
                                         r"in \[0, inf\) \(weight\), got -1"):
        distortion.alignment_penalty(lens, alpha=-1.0, grid=(3, 3))
    with pytest.raises(ValueError, match=r"alignment_penalty: alpha must be"):
        distortion.alignment_penalty(lens, alpha=float("nan"), grid=(3, 3))
    with pytest.raises(ValueError, match=r"stop_chief_ray: iters must be a whole number in "
                                         r"\[0, inf\) aiming iterations, got -1"):
        aiming.stop_chief_ray(cooke, 5.0, iters=-1)
    with pytest.raises(ValueError, match=r"(psf|GeometricPSF): order must be 1 \(tent\) or 2"):
        jl.psf(cooke, 0.0, kernel_size=9, pixel_size=0.005, model=psf.GeometricPSF(order=5))


# ----------------------------------------------------------------------- files, catalogs
def _json(tmp_path, edit):
    d = json.loads((DATA / "lenses" / "cooke_triplet.json").read_text())
    d = copy.deepcopy(d)
    edit(d)
    p = tmp_path / "lens.json"
    p.write_text(json.dumps(d))
    return p


def test_json_object_distance_given_twice_must_agree(tmp_path):
    p = _json(tmp_path, lambda d: d.update(object={"distance": -100}))
    with pytest.raises(ValueError, match=r"lens.json: object.distance -100 disagrees with "
                                         r"surface 0's thickness 'inf' \(mm\)"):
        jl.load(p)
    p = _json(tmp_path, lambda d: d.update(object={"distance": "inf"}))
    d = jl.load(p).object_distance  # agreeing values load: an object at infinity
    assert d is None or np.isinf(float(d))


def test_load_and_save_check_their_options(tmp_path, cooke):
    path = DATA / "lenses" / "cooke_triplet.json"
    with pytest.raises(ValueError, match=r"load: strict must be True or False, got 'yes'"):
        jl.load(path, strict="yes")
    with pytest.raises(ValueError, match=r"load: unknown_glass must be 'error' or 'model', "
                                         r"got 'ignore'"):
        jl.load(path, unknown_glass="ignore")
    with pytest.raises(TypeError, match=r"load: path must be a file name .*got int 5"):
        jl.load(5)
    with pytest.raises(TypeError, match=r"save: lens must be a jaxlens Lens, got str"):
        jl.save("lens", tmp_path / "x.json")
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize("ld, match", [
    ("LD 2.5 0.3", r"bad.agf:3: LD needs 0 < min < max with min < 100 µm \(wavelengths in "
                   r"µm\), got 2.5 0.3"),
    ("LD -0.3 2.5", r"bad.agf:3: LD needs 0 < min < max with min < 100 µm"),
    ("LD 300 2500", r"bad.agf:3: LD needs 0 < min < max with min < 100 µm .*got 300 2500"),
])
def test_agf_ld_record_out_of_range_names_the_line(tmp_path, ld, match):
    p = tmp_path / "bad.agf"
    p.write_text(GOOD_AGF.replace("LD 0.3 2.5", ld))
    with pytest.raises(ValueError, match=match):
        jl.load_agf(p)


def test_agf_ld_record_may_reach_the_far_infrared(tmp_path):
    """A maximum beyond 100 µm (a far-infrared material) is a range in µm, not nm."""
    p = tmp_path / "ir.agf"
    p.write_text(GOOD_AGF.replace("LD 0.3 2.5", "LD 0.3 200"))
    (glass,) = jl.load_agf(p).values()
    assert glass.wavelength_range == pytest.approx((0.3, 200.0))


def test_agf_without_glass_and_bad_registrations_are_refused(tmp_path):
    p = tmp_path / "empty.agf"
    p.write_text("hello world\n")
    with pytest.raises(ValueError, match=r"empty.agf: no glass in the file \(no NM record\)"):
        jl.load_agf(p)
    with pytest.raises(ValueError, match=r"empty.agf: no glass in the file"):
        jl.register_catalog(p)
    with pytest.raises(ValueError, match=r"register_catalog: every value must be a material "
                                         r"\(jaxlens.AbstractMaterial\), got int for 'A'"):
        jl.register_catalog({"A": 5}, name="AUDIT_BAD")
    with pytest.raises(ValueError, match=r"register_catalog: name must be a non-empty string"):
        jl.register_catalog({"A": jl.ModelGlass(1.5, 60.0)}, name=5)
    with pytest.raises(ValueError, match=r"register_catalog: the mapping holds no material"):
        jl.register_catalog({}, name="AUDIT_EMPTY")
    good = tmp_path / "good.agf"
    good.write_text(GOOD_AGF)
    assert set(jl.load_agf(good)) == {"MYG"}


# ------------------------------------------------------------------------ command lines
def test_classical_cli_refuses_repeated_seeds(tmp_path, capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--seed-list", "1,1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--seed-list needs distinct seeds, got '1,1'" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("opt", ["--checkpoint", "--record"])
def test_edof_cli_refuses_a_file_for_a_folder_option(tmp_path, opt):
    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    f = tmp_path / "afile"
    f.write_text("x")
    a = cli.build_parser().parse_args(["--smoke", opt, str(f), "--out", str(tmp_path / "o")])
    with pytest.raises(UsageError, match=rf"edof: {opt} .*afile is a file, not a folder"):
        cli.check_args(a)


@pytest.mark.parametrize("opt", ["--train-dir", "--test-dir"])
def test_edof_cli_refuses_an_image_folder_without_images(tmp_path, opt):
    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    (tmp_path / "imgs").mkdir()
    (tmp_path / "imgs" / "notes.txt").write_text("x")
    a = cli.build_parser().parse_args(["--smoke", opt, str(tmp_path / "imgs"), "--out",
                                       str(tmp_path / "o")])
    with pytest.raises(UsageError, match=rf"edof: {opt}: scenes: no image files .* in .*imgs"):
        cli.check_args(a)


def test_benchmarks_cli_refuses_a_file_out_and_ignored_options(tmp_path, capsys):
    from benchmarks.run import main

    f = tmp_path / "afile"
    f.write_text("x")
    with pytest.raises(SystemExit) as e:
        main(["--smoke", "--only", "throughput", "--out", str(f)])
    assert e.value.code == 2
    assert f"--out {f} is a file, not a folder" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        main(["--smoke", "--only", "pareto", "--counts", "10", "--out", str(tmp_path / "o")])
    assert e.value.code == 2
    assert "--lenses and --counts apply to the throughput benchmark only" in \
        capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("spec, key, right", [
    ({"nd": 1.5168, "Vd": 64.17}, "Vd", "vd"),  # read as no dispersion before
    ({"type": "model", "nd": 1.5168, "vd": 64.17}, "type", "class"),
    ({"nd": 1.5168, "abbe": 64.17}, "abbe", "vd"),
])
def test_material_object_refuses_near_miss_keys(spec, key, right):
    from jaxlens.io import lensfile

    with pytest.raises(ValueError, match=rf"f.json: surface 1: material: unknown key '{key}'; "
                                         rf"did you mean '{right}'\?"):
        lensfile.material_from_spec(spec, "f.json: surface 1")
    good = lensfile.material_from_spec({"nd": 1.5168, "vd": 64.17, "note": "x"}, "f.json")
    assert float(good.vd) == pytest.approx(64.17)
