"""Classes of real ``.zmx`` files found by a wider probe corpus (about 50 public files: the
test folders of optiland and ray-optics, Zemax class files of an optical-design course in
the old 2006-era format, vendors' stock lenses, patent lenses), each checked against a
known answer: optiland's EFL of the same file, an analytic value, or the pupil that Zemax
itself computed and wrote into the file (PUPD)."""

import importlib.util
import os
import pathlib
import sys
import warnings

import pytest

import jaxlens as jl

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
INCH_FILE = os.path.join(DATA, "optiland_circular_aperture_example_with_aperture.zmx")
OPTILAND_F2_INCHES = 0.7300916303992044  # optiland 0.6.3 optic.paraxial.f2() of INCH_FILE


def _check_corpus():
    """tools/check_corpus.py (not part of the package), loaded from the repository."""
    path = pathlib.Path(__file__).resolve().parents[1] / "tools" / "check_corpus.py"
    spec = importlib.util.spec_from_file_location("check_corpus", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("check_corpus", module)
    spec.loader.exec_module(sys.modules["check_corpus"])
    return sys.modules["check_corpus"]


# ------------------------------------------------------------- lens units in the corpus tool


def test_corpus_tool_reads_the_lens_unit(tmp_path):
    """optiland reports a file's EFL in its lens units, jaxlens in mm: the corpus tool
    converts with the file's UNIT line (it compared 18.54 mm with 0.730 in and flagged a
    Laikin wide-angle lens in inches as a 96 % EFL difference)."""
    tool = _check_corpus()
    assert tool.lens_unit_mm(INCH_FILE) == 25.4  # UTF-16, UNIT IN X W X CM MR CPMM
    for unit, mm in (("MM", 1.0), ("CM", 10.0), ("METER", 1000.0), ("IN", 25.4)):
        p = tmp_path / f"{unit}.zmx"
        p.write_text(f"VERS 1\nUNIT {unit} X W X CM MR CPMM\nSURF 0\n")
        assert tool.lens_unit_mm(str(p)) == mm
    p = tmp_path / "none.zmx"
    p.write_text("SURF 0\n  DISZ INFINITY\n")
    assert tool.lens_unit_mm(str(p)) == 1.0  # Zemax's default lens unit


def test_inch_file_efl_is_optilands_in_mm():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(INCH_FILE)
    efl = float(jl.paraxial_data(lens).efl_image_space)
    assert efl == pytest.approx(OPTILAND_F2_INCHES * 25.4, rel=1e-12)
    assert float(lens.epd) == pytest.approx(0.36 * 25.4, rel=1e-15)  # ENPD 0.36 (in)


def test_corpus_tool_agrees_with_optiland_on_the_inch_file():
    pytest.importorskip("optiland")
    rec = _check_corpus().check_file(INCH_FILE)
    assert rec["status"] == "loaded"
    assert rec["optiland_efl"] == pytest.approx(OPTILAND_F2_INCHES * 25.4, rel=1e-12)
    assert rec["rel_diff"] < 1e-12
