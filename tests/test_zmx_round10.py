"""What the tenth round of public .zmx files (/work/zmx_probe/corpus10, not committed: their
sources are in its SOURCES.txt) showed.

Six files: an OpticStudio 17 save of an Edmund UV singlet, a Thorlabs plano-convex lens, an
Edmund achromat twice (once with catalog-qualified glass names, ``GLAS SCHOTT-BK|N-BK7``), a
Zemax 2003 full-frame zoom (MNUM 3 with the object distance and five gaps in THIC rows, FLOA,
paraxial-image-height fields) and an OpTaliX export of an aspheric singlet. jaxlens read all
six to the lens optiland traces (real rays to 3e-13 mm; the zoom in each configuration, the
OpTaliX and Zemax 2003 files from copies mended in form for optiland). One class of problem:

* OpTaliX writes the fields' vignetting factors only as configuration rows (``MNUM 1`` and
  ``FVDX``/``FVDY``/``FVCX``/``FVCY`` rows), with no ``VDXN`` … ``VANN`` line. jaxlens
  compared the active configuration's rows with the missing lines (read as 0), warned that
  they differ, and read 0: the file's factors were dropped (under ``strict`` the file was
  refused). A row whose factor the file has no line for now gives the active
  configuration's factor, as the rows of any other configuration always did; a row that
  contradicts a line the file does give is reported as before.

The snippets below are hand-written after the OpTaliX export; the reference is the same lens
written with the factors on ``VDYN``/``VCXN``/``VCYN`` lines instead of rows.
"""

import warnings

import numpy as np
import pytest

from jaxlens.io import zmx_read
from jaxlens.optics.lens import VIGNETTING_COLUMNS

# ------------------------------------------------- vignetting factors in operand rows only


def _optalix(rows="", lines=""):
    """After OpTaliX's export (every line indented by one space, no VERS, old single-line
    field and wavelength keywords, the object at 1e20 mm): a BK7 singlet with the stop on
    its front face, two fields; ``rows`` follow ``MNUM``, ``lines`` the field lines."""
    body = f"""NAME singlet (exported from OpTaliX)
UNIT MM
ENPD      10.0000
GCAT SCHOTT
ROPD 2
PICB 1
FTYP 0 0
XFLN   0.0000000E+00   0.0000000E+00
YFLN   0.0000000E+00   5.0000000E+00
FWGT 1 1
{lines}WAVL    0.5875618
WWGT    1
PWAV  1
SURF   0
  TYPE STANDARD
  CURV   0.00000000000       0  0  0
  DISZ  0.1000000000E+21
SURF   1
  STOP
  TYPE STANDARD
  CURV   0.0200000000       0  0  0
  GLAS N-BK7
  DIAM   6.000000      1  0
  DISZ   4.000000000
SURF   2
  TYPE STANDARD
  CURV  -0.0200000000       0  0  0
  DIAM   6.000000      1  0
  DISZ   47.00000000
SURF   3
  TYPE STANDARD
  CURV   0.00000000000       0  0  0
  DISZ   0.000000000
MNUM {rows}"""
    return "".join(" " + ln + "\n" for ln in body.split("\n"))


_ROWS_ONE = """1
FVDX   2   1  0.00000000 0 0 0  1 1.0 0.0
FVDY   2   1 -0.05000000 0 0 0  2 1.0 0.0
FVCX   2   1  0.10000000 0 0 0  3 1.0 0.0
FVCY   2   1  0.30000000 0 0 0  4 1.0 0.0"""

_COLS = list(VIGNETTING_COLUMNS)  # VDX, VDY, VCX, VCY, VAN


def test_vignetting_rows_without_the_files_lines_give_the_factors():
    """OpTaliX's ``MNUM 1`` rows are the file's only statement of field 2's factors: they
    were compared with absent VDYN/VCXN/VCYN lines (0), warned about and dropped (refused
    under strict). They read as the same factors written on the lines."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no word: nothing contradicts the rows
        rows = zmx_read.loads(_optalix(_ROWS_ONE), strict=True)
    ref = zmx_read.loads(_optalix("1", "VDYN 0 -0.05\nVCXN 0 0.1\nVCYN 0 0.3\n"), strict=True)
    want = np.zeros((2, len(_COLS)))
    want[1, _COLS.index("VDY")] = -0.05
    want[1, _COLS.index("VCX")] = 0.1
    want[1, _COLS.index("VCY")] = 0.3
    np.testing.assert_array_equal(np.asarray(ref.vignetting), want)
    np.testing.assert_array_equal(np.asarray(rows.vignetting), want)
    assert rows.object_distance is None  # DISZ 1e20: Zemax's infinity


def test_a_row_that_contradicts_a_line_the_file_gives_is_still_reported():
    """Where the file gives VCYN and the active configuration's FVCY says otherwise, the
    line stays what jaxlens reads (with a warning; strict refuses), as before."""
    text = _optalix(_ROWS_ONE, "VCYN 0 0.2\n")
    with pytest.raises(ValueError, match=r"FVCY 2 of configuration 1, the active one \(MNUM\), "
                                         r"is 0\.30000000, but the file's VCYN gives field 2 "
                                         r"0\.2"):
        zmx_read.loads(text, strict=True)
    with pytest.warns(UserWarning, match="FVCY 2 of configuration 1"):
        lens = zmx_read.loads(text)
    assert float(lens.vignetting[1, _COLS.index("VCY")]) == 0.2


def test_rows_without_lines_give_each_configurations_factors():
    """Two configurations, FVCY rows only: the active one (MNUM 2 1) reads its row as
    configuration 2 always read its own (before: 0 for the active one, with a warning)."""
    rows = """2 1
FVCY   2   1  0.20000000 0 0 0  1 1.0 0.0
FVCY   2   2  0.40000000 0 0 0  1 1.0 0.0"""
    text = _optalix(rows)
    j = _COLS.index("VCY")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one = zmx_read.loads(text, strict=True)
        two = zmx_read.loads(text, strict=True, config=2)
    np.testing.assert_array_equal(np.asarray(one.vignetting)[:, j], [0.0, 0.2])
    np.testing.assert_array_equal(np.asarray(two.vignetting)[:, j], [0.0, 0.4])
    assert float(zmx_read.loads(text, config=1).vignetting[1, j]) == 0.2
