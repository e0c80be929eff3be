"""Bad input, round 24 (tools/audit24_probe.py): one test per class of gap fixed. Each names
what main did with the input: a silent answer, a traceback, or a message that named the wrong
argument. All checks run where concrete inputs enter, before any tracing.
"""

import copy
import importlib.util
import pathlib
import sys

import jax
import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens.imaging import render as R
from jaxlens.io import lensfile

# The Quadoa form of a 45-degree fold (tests/test_travel_senses.py): a -45 deg break, the
# mirror with its -10 mm along its own axis, a +135 deg break with a decenter, a singlet.
AIR = "air"
FOLD = {
    "format": "jaxlens.lens/1",
    "aperture": {"epd": 10.0},
    "fields": {"type": "angle_deg_y", "values": [0.0]},
    "wavelengths_um": [0.55], "primary": 0,
    "surfaces": [
        {"type": "object", "thickness": "inf", "material": AIR},
        {"type": "standard", "curvature": 0.0, "thickness": 10.0, "material": AIR,
         "is_stop": True},
        {"type": "coordinate_break", "tilt_x_deg": -45.0, "thickness": 0.0, "material": AIR},
        {"type": "standard", "curvature": 0.0, "thickness": -10.0, "material": AIR,
         "mirror": True},
        {"type": "coordinate_break", "decenter_y": -10.0, "tilt_x_deg": 135.0,
         "thickness": 0.0, "material": AIR},
        {"type": "standard", "curvature": 0.02, "thickness": 4.0,
         "material": {"nd": 1.5, "vd": 60.0}},
        {"type": "standard", "curvature": -0.02, "thickness": 50.0, "material": AIR},
        {"type": "image"},
    ],
}
QUADOA = [1, 1, 1, -1, 1, 1, 1]


def _tool(name):
    """A script of tools/ (not part of the package)."""
    path = pathlib.Path(__file__).resolve().parents[1] / "tools" / f"{name}.py"
    if name not in sys.modules:  # registered first: its dataclasses look their module up
        spec = importlib.util.spec_from_file_location(name, path)
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    return sys.modules[name]


def test_a_json_travel_senses_key_that_disagrees_with_the_frames_is_refused():
    # main: the key was not read, so a file saying Zemax's mirror-count senses for a fold
    # whose breaks turn the frame (or a -1 where nothing turns) loaded as if it were absent.
    d = copy.deepcopy(FOLD)
    d["travel_senses"] = QUADOA
    assert lensfile.lens_from_dict(d).travel_senses == tuple(QUADOA)
    d["travel_senses"] = [1, 1, 1, -1, -1, -1, -1]
    with pytest.raises(ValueError, match=r"travel_senses \[1, 1, 1, -1, -1, -1, -1\] "
                                         r"disagrees with the frames.*give \[1, 1, 1, -1, 1, "
                                         r"1, 1\]"):
        lensfile.lens_from_dict(d, source="fold.json")


def test_a_json_obscuration_on_a_coordinate_break_is_refused():
    # main: read, then ignored by the tracer (every ray of a 1e9 mm obscuration got through).
    d = copy.deepcopy(FOLD)
    d["surfaces"][2]["obscuration"] = [0.0, 1e9]
    with pytest.raises(ValueError, match="surface 2: a coordinate break has no aperture, so "
                                         "its obscuration"):
        lensfile.lens_from_dict(d, source="fold.json")


@pytest.fixture(scope="module")
def camera():
    lens = jl.zoo.cooke_triplet()
    return lens if lens.sensor is not None else pytest.skip("the triplet has no sensor")


def test_render_checks_the_ray_methods_footprints_and_grid_by_name(camera):
    scene = jnp.zeros((*camera.sensor.resolution, 3))
    key = jax.random.PRNGKey(0)
    # main: AttributeError 'str' object has no attribute 'e0'.
    with pytest.raises(TypeError, match="RayRender's footprints must be None or the result "
                                        "of jaxlens.imaging.render.footprints"):
        R.render(camera, scene, spp=1, key=key, method=R.RayRender(footprints="auto"))
    # main: refused by footprints() as "grid", an argument the caller never gave.
    with pytest.raises(ValueError, match=r"render: footprint_grid .*\[2, 257\]"):
        R.render(camera, scene, spp=1, key=key, method=R.RayRender(footprint_grid=10**6))


def test_empty_wavelengths_are_named(camera):
    # main: "zero-size array to reduction operation max which has no identity".
    with pytest.raises(ValueError, match="footprints: wavelengths is empty; give at least one "
                                         r"wavelength \(µm\)"):
        R.footprints(camera, wavelengths=())


def test_tolerance_batch_and_threshold_are_refused_before_the_trials():
    from jaxlens.analysis import tolerance as T
    lens = jl.zoo.cooke_triplet()
    # main: accepted; monte_carlo then padded each chunk to a billion lenses.
    with pytest.raises(ValueError, match=r"ToleranceModel: batch × fields × wavelengths × "
                                         r"pupil points = .* rays.*lower batch"):
        T.ToleranceModel(lens, batch=10**9)
    # main: the trials ran and every one failed the 6 nm requirement: yield 0. (The check
    # comes first, so no model needs building to reach it; the bound is the CLIs'.)
    from jaxlens.experiments.tolerance import THRESHOLD_RANGE_UM
    assert T.MIN_THRESHOLD_UM == THRESHOLD_RANGE_UM[0]
    with pytest.raises(ValueError, match=r"threshold_um 0.006 µm is below 0.01 µm.*0.006 mm "
                                         r"is 6 µm"):
        T.monte_carlo(None, trials=2, threshold_um=0.006, mtf_frequency=30.0)


def test_make_agf_names_a_missing_folder_before_reading(tmp_path, capsys):
    make_agf = _tool("make_agf")
    # main: "no folder for 'ohara' under ..." (exit 1), and a missing --out a traceback
    # after the first maker's glasses were read.
    for argv, arg in (([str(tmp_path / "none")], "database"),
                      ([str(tmp_path), "--out", str(tmp_path / "none")], "--out")):
        with pytest.raises(SystemExit) as e:
            make_agf.main(argv)
        assert e.value.code == 2
        assert f"{arg}: no such folder" in capsys.readouterr().err



def test_export_reevaluation_names_a_missing_path_before_evaluating(tmp_path, capsys):
    tool = _tool("export_reevaluation")
    lens = str(pathlib.Path(jl.__file__).parent / "data" / "lenses" / "cooke_triplet.json")
    # main: a missing path was one line of the report (exit 0); a missing --json folder or
    # --summary file a traceback after every file had been evaluated.
    for argv, words in (([str(tmp_path / "none.zmx")], "paths: no such file or folder"),
                        ([lens, "--json", str(tmp_path / "no" / "out.json")],
                         "--json: no such folder"),
                        ([lens, "--summary", str(tmp_path / "none.json")],
                         "--summary: no such file")):
        with pytest.raises(SystemExit) as e:
            tool.main(argv)
        assert e.value.code == 2
        assert words in capsys.readouterr().err
