"""Classes of real ``.zmx`` files found by a wider probe corpus (about 50 public files: the
test folders of optiland and ray-optics, Zemax class files of an optical-design course in
the old 2006-era format, vendors' stock lenses, patent lenses), each checked against a
known answer: optiland's EFL of the same file, an analytic value, or the pupil that Zemax
itself computed and wrote into the file (PUPD)."""

import os
import warnings

import numpy as np
import pytest
from helpers import check_corpus_tool

import jaxlens as jl
from jaxlens.optics import paraxial

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
INCH_FILE = os.path.join(DATA, "optiland_circular_aperture_example_with_aperture.zmx")
OPTILAND_F2_INCHES = 0.7300916303992044  # optiland 0.6.3 optic.paraxial.f2() of INCH_FILE


# ------------------------------------------------------------- lens units in the corpus tool


def test_corpus_tool_reads_the_lens_unit(tmp_path):
    """optiland reports a file's EFL in its lens units, jaxlens in mm: the corpus tool
    converts with the file's UNIT line (it compared 18.54 mm with 0.730 in and flagged a
    Laikin wide-angle lens in inches as a 96 % EFL difference)."""
    tool = check_corpus_tool()
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
    rec = check_corpus_tool().check_file(INCH_FILE)
    assert rec["status"] == "loaded"
    assert rec["optiland_efl"] == pytest.approx(OPTILAND_F2_INCHES * 25.4, rel=1e-12)
    assert rec["rel_diff"] < 1e-12


# ------------------------------------------------- the extended odd asphere (TYPE XOSPHERE)

XO_TERMS = "  XDAT 1 4\n  XDAT 2 5\n  XDAT 3 1E-2\n  XDAT 4 0.2\n  XDAT 5 -5E-2\n  XDAT 6 2E-2\n"
A_OVER_R = [1e-2 / 5, 0.2 / 5**2, -5e-2 / 5**3, 2e-2 / 5**4]  # β_i = A_i / R^i


def _xo(lines, unit="MM"):
    """A plano-convex singlet whose first surface is ``lines``: a dispersionless model glass
    n = 1.5 and a flat back, so 1/EFL = (n − 1)·(paraxial curvature of surface 1)."""
    return (f"VERS 190513 80 123457\nUNIT {unit} X W X CM MR CPMM\nENPD 10\n"
            "WAVM 1 0.5875618 1\nSURF 0\n  TYPE STANDARD\n  CURV 0.0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n{lines}  DISZ 5\n  GLAS ___BLANK 1 0 1.5 0\nSURF 2\n"
            "  TYPE STANDARD\n  CURV 0.0\n  DISZ 40\nSURF 3\n  TYPE STANDARD\n  CURV 0.0\n"
            "  DISZ 0\n")


def test_xosphere_is_the_odd_asphere_of_its_normalised_terms():
    """Zemax's extended odd asphere: conic + Σ A_i (r/R)^i, XDAT 1 = N, XDAT 2 = R, XDAT 3… =
    A_1 … A_N. It is the odd asphere β_i = A_i / R^i (refused before as an unknown type)."""
    xo = jl.io.zmx.loads(_xo(f"  TYPE XOSPHERE\n  CURV 0.02\n  CONI -0.5\n{XO_TERMS}"))
    odd = jl.io.zmx.loads(_xo("  TYPE ODDASPHE\n  CURV 0.02\n  CONI -0.5\n" + "".join(
        f"  PARM {i} {b!r}\n" for i, b in enumerate(A_OVER_R, start=1))))
    s = xo.surfaces[0]
    assert type(s) is jl.OddAsphere and float(s.c) == 0.02 and float(s.k) == -0.5
    np.testing.assert_allclose(np.asarray(s.coeffs), A_OVER_R, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(s.coeffs), np.asarray(odd.surfaces[0].coeffs),
                               rtol=1e-15)
    # β_2 r² adds 2 β_2 to the paraxial curvature: analytic EFL of the plano-convex lens.
    efl = float(jl.paraxial_data(xo).efl_image_space)
    assert efl == pytest.approx(1 / (0.5 * (0.02 + 2 * A_OVER_R[1])), rel=1e-13)


def test_xosphere_in_inches():
    """R is in lens units like the sag: in inches, β_i (mm^(1−i)) = A_i / R^i · 25.4^(1−i)."""
    s = jl.io.zmx.loads(_xo(f"  TYPE XOSPHERE\n  CURV 0.02\n{XO_TERMS}", unit="IN")).surfaces[0]
    assert float(s.c) == pytest.approx(0.02 / 25.4, rel=1e-15)
    np.testing.assert_allclose(np.asarray(s.coeffs),
                               np.array(A_OVER_R) * 25.4 ** (1 - np.arange(1, 5)), rtol=1e-14)


def test_xosphere_round_trip(tmp_path):
    """Four terms are written back as ODDASPHE (PARM 1..4 = β_i) and read to the same lens."""
    lens = jl.io.zmx.loads(_xo(f"  TYPE XOSPHERE\n  CURV 0.02\n  CONI -0.5\n{XO_TERMS}"))
    jl.save(lens, tmp_path / "w.zmx")
    back = jl.load(tmp_path / "w.zmx")
    assert type(back.surfaces[0]) is jl.OddAsphere
    np.testing.assert_array_equal(np.asarray(back.surfaces[0].coeffs),
                                  np.asarray(lens.surfaces[0].coeffs))


@pytest.mark.parametrize("lines, line, reason", [
    ("  XDAT 1 4\n  XDAT 3 1E-2\n", 11, r"XOSPHERE needs XDAT 1 \(the number of terms\) and "
     r"XDAT 2 \(the normalisation radius, lens units\); XDAT 2 is missing"),
    ("  XDAT 1 241\n  XDAT 2 5\n", 13, r"XDAT 1 \(the number of terms\) must be a whole number "
     r"in 0\.\.240, got 241"),
    ("  XDAT 1 2\n  XDAT 2 0\n", 14, r"XDAT 2 \(the normalisation radius, lens units\) must be "
     r"> 0, got 0"),
    ("  XDAT 1 1\n  XDAT 2 5\n  XDAT 4 1E-3\n", 15, r"coefficient beyond the 1 terms of XDAT 1 "
     r"\(XDAT 3 … XDAT 3\)"),
    ("  PARM 1 1E-3\n  XDAT 1 1\n  XDAT 2 5\n", 13, r"XOSPHERE has no parameters \(PARM\)"),
])
def test_xosphere_malformed_is_refused_with_its_line(tmp_path, lines, line, reason):
    p = tmp_path / "xo.zmx"
    p.write_text(_xo(f"  TYPE XOSPHERE\n  CURV 0.02\n{lines}"))
    with pytest.raises(ValueError, match=f"^{p}:{line}: {reason}"):
        jl.load(p)


# ------------------------------------- Zemax's own pupil in a 2006-era file (PUPD, VERS 60801)

PIVOTED = os.path.join(DATA, "zemax2006", "kraken_pivoted_lens.ZMX")


def test_old_zemax_file_pupil_is_the_one_zemax_wrote():
    """A course file saved by Zemax in 2006 (VERS 60801: XFLD/YFLD, FWGT, WAVL beside the
    padded XFLN/YFLN/WAVN lines, PZUP and PPAR pickups): a doublet tilted 5° about a point by
    two coordinate breaks, object heights 0, 7, 10 mm at 200 mm, the pupil given as a working
    F/# (FNUM 6 1). Zemax computed the entrance pupil and wrote it on its PUPD line (position
    0, diameter 33.86421929753): jaxlens's pupil, from the paraxial working F/#, is the same
    to the 13 digits written, and the object heights become the chief-ray angles through
    the pupil at the stop."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every keyword of the file is known
        lens = jl.load(PIVOTED)
    assert float(lens.epd) == pytest.approx(3.386421929753e1, rel=1e-12)
    assert float(paraxial.entrance_pupil_z(lens)) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(np.abs(np.asarray(lens.fields)),
                               np.degrees(np.arctan(np.array([0.0, 7.0, 10.0]) / 200.0)),
                               rtol=1e-12, atol=1e-15)
