"""Round-42b bad-input fixes (tools/audit42b_probe.py): argument types across the public API
(a numpy bool or a complex number where a number is wanted, numbers written as strings),
run folders a second run cannot destroy, every design entry point's spec, the tolerance
functions' model, image-metric options and a JSON lens's bare-number aperture. Each test
says what main did."""

import json
import os

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import design as D
from jaxlens import plot
from jaxlens.analysis import tolerance as TL
from jaxlens.analysis import zernike
from jaxlens.design import losses, multistart
from jaxlens.experiments import classical
from jaxlens.experiments.runfolder import FINISHED, RunFolder, UsageError
from jaxlens.io import images
from jaxlens.optics import checks

COOKE = os.path.join(os.path.dirname(jl.__file__), "data", "lenses", "cooke_triplet.json")


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


def _finished(tmp_path):
    d = tmp_path / "run"
    d.mkdir()
    (d / FINISHED).write_text("finished\n")
    (d / "result.txt").write_text("an earlier run's result\n")
    return d


@pytest.mark.parametrize("overwrite", ["no", "False", 1, 0, None, np.True_])
def test_run_folder_overwrite_must_be_a_bool(tmp_path, overwrite):
    """Main: overwrite="no" (or 1) replaced a finished run: a truthy string is not a yes."""
    d = _finished(tmp_path)
    with pytest.raises(UsageError, match=r"--out: overwrite must be True or False"):
        RunFolder(str(d), overwrite=overwrite)
    assert (d / "result.txt").exists()


@pytest.mark.parametrize("path", ["", "   ", None, 5])
def test_run_folder_needs_a_folder_name(path):
    """Main: "" was the working folder (the classical command ran there), None and 5 raised
    os.path's TypeError."""
    with pytest.raises(UsageError, match=r"--out needs a folder name, got"):
        RunFolder(path)


def test_classical_refuses_an_empty_out(tmp_path, capsys, monkeypatch):
    """Main: ``--out ''`` passed every check and started a design in the working folder."""
    monkeypatch.chdir(tmp_path)
    assert classical.main(["--out", ""]) == 2
    assert "--out needs a folder name, got ''" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("value, shown", [(np.True_, "np.True_"), (2 + 0j, "(2+0j)"),
                                          (np.complex128(2 + 1j), "np.complex128(2+1j)"),
                                          (None, "None")])
def test_number_refuses_numpy_bools_and_complex_numbers(value, shown):
    """Main: np.True_ passed as 1 (only Python's bool was refused), 2+1j as 2 (numpy dropped
    the imaginary part with a warning), and None failed in the message's own formatting (a
    TypeError from float(None))."""
    with pytest.raises(ValueError) as e:
        checks.number(value, "steps", "where", lo=1, unit="steps")
    assert str(e.value) == f"where: steps must be a finite number in [1, inf) steps, got {shown}"


@pytest.mark.parametrize("make, arg", [
    (lambda: D.DesignConfig(steps=np.True_), "steps"),
    (lambda: D.DesignConfig(lr_c=0.005 + 0j), "lr_c"),
    (lambda: D.sine_path(0.0, np.True_, 5), "end"),
    (lambda: D.sine_path(0.0, np.complex128(5 + 1j), 5), "end"),
    (lambda: zernike.zernike_nm(np.True_), "j"),
    (lambda: D.Stage("s", 60.0, 2.0, np.True_), "steps"),
])
def test_public_numbers_refuse_numpy_bools_and_complex(make, arg):
    """Main: each was read as 1 or as its real part (sine_path(0, np.True_, 5) ran to 1)."""
    with pytest.raises(ValueError, match=rf"\b{arg} must be a (finite|whole) number"):
        make()


def test_tolerance_model_fields_must_be_numbers(cooke):
    """Main: ["0", "5"] was read as 0° and 5° (np.asarray(fields, float)), field weights
    [False, True] as 0 and 1."""
    with pytest.raises(TypeError, match=r"ToleranceModel: fields must be a real number .*"
                                        r"\(degrees\), got list \['0', '5'\]"):
        TL.ToleranceModel(cooke, fields=["0", "5"])
    with pytest.raises(TypeError, match=r"ToleranceModel: field_weights must be a real "
                                        r"number .*\(relative weights\), got ndarray"):
        TL.ToleranceModel(cooke, fields=[0.0, 5.0], field_weights=np.array([False, True]))


@pytest.mark.parametrize("call", [
    lambda lens: TL.sensitivity(lens),
    lambda lens: TL.monte_carlo(lens, trials=4, threshold_um=20.0, mtf_frequency=30.0),
    lambda lens: TL.sample_perturbations(lens, 4, jax.random.key(0)),
])
def test_tolerance_functions_refuse_a_lens_for_the_model(cooke, call):
    """Main: an AttributeError ('Lens' object has no attribute 'gradient')."""
    with pytest.raises(TypeError, match=r"model must be a ToleranceModel \(ToleranceModel"
                                        r"\(lens, \.\.\.\)\), got Lens"):
        call(cooke)


@pytest.mark.parametrize("where, call", [
    ("evaluate", lambda s: D.evaluate_design(jl.zoo.cooke_triplet(), s)),
    ("paper_stages", lambda s: D.paper_stages(s)),
    ("run", lambda s: D.run(s, [], None, None, None)),
    ("random_starts", lambda s: D.random_starts(s, [0])),
    ("make_solver_factory", lambda s: multistart.make_solver_factory(D.DesignConfig(), s,
                                                                     float)),
    ("sensor_field_grid", lambda s: D.sensor_field_grid(s)),
])
def test_design_entry_points_refuse_a_dict_spec(where, call):
    """Main: evaluate, paper_stages and make_solver_factory raised AttributeErrors ('dict'
    object has no attribute 'epd'/'fov_start'/'asphere_terms'), random_starts named
    random_params; now each names itself (design.spec.require_spec)."""
    with pytest.raises(TypeError, match=rf"^{where}: spec must be a "
                                        rf"jaxlens\.design\.DesignSpec, got dict"):
        call({"fov": 60})


@pytest.mark.parametrize("data_range", ["1", np.True_, [1.0, 2.0], 0.0])
@pytest.mark.parametrize("metric", [images.psnr, images.ssim])
def test_image_metrics_check_data_range(metric, data_range):
    """Main: "1" failed as numpy's TypeError of isfinite; np.True_ scored as a range of 1."""
    a, b = np.ones((16, 16)), np.zeros((16, 16))
    with pytest.raises(ValueError, match=r"data_range must be a finite number in \(0, inf\) "
                                         r"\(the peak-to-peak range of pixel values"):
        metric(a, b, data_range=data_range)


def test_hull_corners_must_be_numbers():
    """Main: strings failed as JAX's "Error interpreting argument to stage", naming no
    argument; bools became 0/1 corners refused as an nd below 1."""
    with pytest.raises(TypeError, match=r"HullMaterials: corners must be a real number .*"
                                        r"\(\(nd, Vd\)\)"):
        D.HullMaterials(np.array([["1.5", "60"], ["1.7", "30"], ["1.6", "50"]]))


def test_rms_map_values_must_be_numbers():
    """Main: a map of strings was drawn (np.asarray(rms_um, float) read them)."""
    with pytest.raises(TypeError, match=r"plot_rms_map: rms_um must be a real number .*"
                                        r"\(µm\), got ndarray"):
        plot.plot_rms_map(np.array([["5", "6"], ["7", "8"]]), (3.0, 4.0))


@pytest.mark.parametrize("rms", [np.zeros(0), np.zeros((3, 0)), 0.5])
def test_reweighting_mask_needs_fields(rms):
    """Main: [] gave [] and a scalar 0.5 a weight 1.0: a mask over no fields."""
    with pytest.raises(ValueError, match=r"reweighting_mask: rms must be \[\.\.\., K\] with "
                                         r"K >= 1 fields"):
        D.reweighting_mask(rms)


@pytest.mark.parametrize("efl", [-50.0, 0.0])
def test_objective_efl_target_must_be_positive(efl):
    """Main: -50 was taken (DesignSpec refuses it): the loss steered toward a diverging
    lens."""
    with pytest.raises(ValueError, match=r"Objective: efl must be a finite number in "
                                         r"\(0, inf\) mm"):
        losses.Objective(None, None, np.zeros(3), efl=efl)


@pytest.mark.parametrize("aperture", [2.8, 10, "10", [10.0]])
def test_json_aperture_must_be_an_object(tmp_path, aperture):
    """Main: a bare number was read as the EPD in mm (2.8 meant as F/2.8 gave a 2.8 mm
    pupil without a word); a string or a list was refused with "must be an object"."""
    with open(COOKE, encoding="utf-8") as f:
        d = json.load(f)
    d["aperture"] = aperture
    p = tmp_path / "lens.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"aperture must be an object, \{\"epd\": mm\}, "
                                         r"\{\"fnum\": F\} or \{\"stop_semi_diameter\": mm\}"):
        jl.load(str(p))


def test_paper_stages_checks_the_polish_name_without_a_polish_stage():
    """Main: polish="bfgs" was taken when polish_steps=0 (DesignConfig refuses it always)."""
    with pytest.raises(ValueError, match=r"paper_stages: polish must be one of \('adam', "
                                         r"'lm', 'lm-optx', 'lbfgsb'\), got 'bfgs'"):
        D.paper_stages(D.DesignSpec(), polish="bfgs")


def test_stage_name_must_be_text():
    """Main: Stage(5, ...) was taken: the label of its logs and messages."""
    with pytest.raises(TypeError, match=r"Stage 5: name must be a str, got int"):
        D.Stage(5, 60.0, 2.0, 10)


@pytest.mark.parametrize("seeds", [{0, 1}, frozenset({3}), {0: "a"}])
def test_seeds_must_be_in_order(seeds):
    """Main: a set of seeds was taken in the set's own order, so the seed labels of the
    messages and the starts need not pair up."""
    with pytest.raises(ValueError, match=r"random_starts: seeds must be a non-empty list .*"
                                         r"\(a list or tuple, in order: not a set\)"):
        D.random_starts(D.DesignSpec(), seeds)


@pytest.mark.parametrize("value", [np.True_, np.array([True, False]), np.array([5 + 1j])])
def test_array_check_refuses_bools_and_complex(value):
    """Main: checks.values (the array check of most arguments) read True as 1 and 5+1j as 5
    (stop_radius(lens, "real", object_z=np.True_) traced from 1 mm)."""
    with pytest.raises(ValueError, match=r"^where: object_z must be finite numbers \(mm\), "
                                         r"got "):
        checks.values(value, "object_z", "where", unit="mm")


def test_stop_radius_refuses_a_bool_object_z(cooke):
    """Main: np.True_ was an object 1 mm from the first vertex."""
    with pytest.raises(ValueError, match=r"stop_radius: object_z must be finite numbers"):
        jl.sampling.stop_radius(cooke, "real", object_z=np.True_)


def test_zernike_fit_points_must_share_one_shape():
    """Main: x [25] and y [5, 5] were paired by ravel order, as were values [5, 5] with a
    mask [25]: a meshgrid's x with another ordering's y fitted without a word."""
    g = np.linspace(-0.6, 0.6, 5)
    x, y = np.meshgrid(g, g)
    with pytest.raises(ValueError, match=r"zernike_fit: x, y and values must have the same "
                                         r"shape \(one value per point\), got shapes \(25,\), "
                                         r"\(5, 5\) and \(5, 5\)"):
        zernike.zernike_fit(x.ravel(), y, np.ones((5, 5)), terms=3)
    with pytest.raises(ValueError, match=r"zernike_fit: mask must have the points' shape "
                                         r"\(5, 5\) \(one entry per point\), got shape \(25,\)"):
        zernike.zernike_fit(x, y, np.ones((5, 5)), terms=3, mask=np.ones(25, bool))


@pytest.mark.parametrize("where, write", [
    ("write_png", lambda p: images.write_png(p, np.ones((4, 4, 3)))),
    ("write_exr", lambda p: images.write_exr(p, np.ones((4, 4, 3)))),
    ("save_json", lambda p: jl.io.lensfile.save_json(jl.zoo.cooke_triplet(), p)),
    ("save", lambda p: plot.save(plot.plot_image(np.zeros((4, 4, 3))), p)),
])
def test_writers_name_themselves_for_a_path_that_is_none(where, write):
    """Main: os.fspath's "expected str, bytes or os.PathLike object, not NoneType", naming
    neither the writer nor the argument (json_values.output_file checks every writer's)."""
    with pytest.raises(TypeError, match=rf"^{where}: path must be a file name \(a str or "
                                        rf"os\.PathLike\), got NoneType None"):
        write(None)


def test_classical_refuses_an_empty_ablation_out(tmp_path, capsys, monkeypatch):
    """Main: ``--ablation --ablation-out ''`` passed every check: the columns would be written
    into the working folder (runfolder.check_writable now refuses an empty name)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(classical, "run_ablation", lambda *a, **k: pytest.fail("it ran"))
    assert classical.main(["--ablation", "--ablation-out", ""]) == 2
    assert "--ablation-out needs a folder name, got ''" in capsys.readouterr().err
