"""Round 36b: random lenses traced by optiland (tools/fuzz36b_reference.py), against jaxlens.

tests/data/fuzz36b holds a few of the generated cases, chosen for distinct features (finite
object, curved image, image space of glass with air after the image surface, A2..A12
aspheres with conics, plastics, the stop in front, inside, on the last face). Each file is in
the refcase schema and names its generator, seed, draw and the optiland version. The checks
of tests/test_trace.py run over them, imported, not copied: float64 intercepts and the
paraxial data in CI, the RMS spots and distortion with -m slow (15 to 40 s each). A seventh
case, tests/data/fuzz36b/crossing, has surfaces that cross: the references trace its rim
rays back along their lines, as the refcase loader's lenses do (``negative_propagation``)."""

import dataclasses
import json
import pathlib
import warnings

import numpy as np
import pytest
import test_trace
from helpers import refcase_lens, refcase_rays

import jaxlens as jl

FOLDER = pathlib.Path(__file__).parent / "data" / "fuzz36b"
CASES = sorted(p.stem for p in FOLDER.glob("fuzz36b_*.json"))
SLOW = [pytest.param(c, marks=pytest.mark.slow, id=c) for c in CASES]
# CI traces two of them (a finite object with glass image space; strong A2..A12 aspheres on a
# fast beam): each case compiles its own programs (3 s a case); -m slow runs all six.
IN_CI = ("fuzz36b_036", "fuzz36b_hard_007")
SOME = [pytest.param(c, id=c, marks=() if c in IN_CI else pytest.mark.slow) for c in CASES]


def test_cases_present():
    assert len(CASES) >= 4, CASES
    for c in CASES:
        gen = json.loads((FOLDER / f"{c}.json").read_text())["generator"]
        assert gen["script"] == "tools/fuzz36b_reference.py" and gen["optiland"], gen


@pytest.mark.parametrize("case", SOME)
def test_fuzz_intercepts_float64(case):
    test_trace.test_refcase_intercepts_float64(FOLDER, case)


@pytest.mark.parametrize("case", SOME)
def test_fuzz_paraxial(case):
    test_trace.test_refcase_paraxial(FOLDER, case)
    lens, d = refcase_lens(FOLDER / f"{case}.json")
    want = d["paraxial"]["paraxial_chief_ray_y_at_image_vertex"]
    got = jl.paraxial.image_height(lens, np.array([float(f) for f in want]))
    np.testing.assert_allclose(np.asarray(got), list(want.values()), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("case", SLOW)
def test_fuzz_rms_and_distortion(case):
    test_trace.test_refcase_rms_and_distortion(FOLDER, case)


def test_a_finite_object_is_read():
    """The test loader reads a finite object's distance (surface 0's thickness): it left it
    out, and the analyses traced the fields from infinity (RMS spots off by a factor of 9
    on a random finite-conjugate case)."""
    finite = [
        c
        for c in CASES
        if json.loads((FOLDER / f"{c}.json").read_text())["object"]["distance"] != "infinity"
    ]
    assert finite
    for c in finite:
        lens, d = refcase_lens(FOLDER / f"{c}.json")
        assert lens.object_distance is not None
        assert float(lens.object_distance) == d["surfaces"][0]["thickness"]
        with warnings.catch_warnings():  # a case with air after its image surface says so
            warnings.filterwarnings("ignore", ".*the medium after the image surface")
            loaded = jl.load(FOLDER / f"{c}.json")
        assert float(loaded.object_distance) == float(lens.object_distance)
    lens, _ = refcase_lens(test_trace.find_refcase_dir() / "cooke_triplet.json")
    assert lens.object_at_infinity


def test_surfaces_that_cross_are_traced_as_the_references_do():
    """A random draw whose flat stop cuts the next surface's sag at the rim (see the file's
    note): optiland (and rayoptics) trace the rim rays back to that surface. The refcase
    loader gives its lens ``negative_propagation`` (Zemax's rule), so every ray agrees; a lens
    with jaxlens's default flags the rim rays and keeps the others."""
    lens, d = refcase_lens(FOLDER / "crossing" / "fuzz36b_040.json")
    assert lens.negative_propagation
    rays, ref = refcase_rays(d)
    back = jl.trace(lens, rays)
    assert bool(back.valid.all())
    assert np.abs(np.asarray(back.origin) - ref[:, :3]).max() < 1e-9
    assert np.abs(np.asarray(back.direction) - ref[:, 3:]).max() < 1e-12
    rim = np.isclose(
        np.hypot([r["Px"] for r in d["real_rays"]], [r["Py"] for r in d["real_rays"]]), 1.0
    )
    out = jl.trace(dataclasses.replace(lens, negative_propagation=False), rays)
    np.testing.assert_array_equal(np.asarray(out.valid), ~rim)
    assert np.abs(np.asarray(out.origin)[~rim] - ref[~rim, :3]).max() < 1e-9
