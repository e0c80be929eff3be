"""The reference-case checks of test_trace.py over tests/refcases_extra (made by
tools/make_refcase.py with optiland, cross-checked with rayoptics; see its README).

The same test functions run, imported, not copied. Each case compiles its own programs
(about 3 s for the float64 intercepts and the paraxial data, 4 s for float32, 10 s for the
spots and distortion), so CI runs the float64 intercepts and paraxial data of every case;
float32, spots and distortion run with -m slow."""

import pathlib

import pytest
import test_trace

EXTRA = pathlib.Path(__file__).parent / "refcases_extra"
CASES = sorted(p.stem for p in EXTRA.glob("*.json"))
SLOW = [pytest.param(c, marks=pytest.mark.slow, id=c) for c in CASES]


@pytest.fixture(scope="module")
def refcase_dir():
    return EXTRA


def test_cases_present():
    assert len(CASES) >= 5, CASES


@pytest.mark.parametrize("case", CASES)
def test_extra_intercepts_float64(refcase_dir, case):
    test_trace.test_refcase_intercepts_float64(refcase_dir, case)


@pytest.mark.parametrize("case", CASES)
def test_extra_paraxial(refcase_dir, case):
    test_trace.test_refcase_paraxial(refcase_dir, case)


@pytest.mark.parametrize("case", SLOW)
def test_extra_intercepts_float32(refcase_dir, case):
    test_trace.test_refcase_intercepts_float32(refcase_dir, case)


@pytest.mark.parametrize("case", SLOW)
def test_extra_rms_and_distortion(refcase_dir, case):
    test_trace.test_refcase_rms_and_distortion(refcase_dir, case)


def test_a_medium_after_the_image_surface_is_named():
    """jaxlens ends a trace in image space; a case whose image surface has another medium
    after it (optiland refracts there) loads with a warning that says so."""
    import warnings

    import jaxlens as jl

    with pytest.warns(UserWarning, match=r"medium after the image surface \(n = 1\) is not "
                                         r"image space \(n = 1\.78"):
        jl.load(EXTRA / "plastic_curved_immersed_image.json")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        jl.load(EXTRA / "immersion_image_space.json")  # the same medium on both sides
