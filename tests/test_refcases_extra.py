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
