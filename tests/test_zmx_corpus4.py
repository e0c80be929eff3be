"""What the fourth round of public .zmx files (/work/zmx_probe/corpus4, not committed: their
sources are in its SOURCES4.txt) showed, as minimal hand-written files.

* Zemax 2006 headers (``VERS 60801``) carry single-value lines beside the newer ones
  (``XFLD``/``YFLD``/``FWGT``, ``ZVDX``…``ZVAN``, ``WAVL``/``WAVN``/``WWGT``/``WWGN``, ``PUPD``):
  the fields and wavelengths are ``XFLN``/``YFLN``/``WAVM``'s, as many as ``FTYP`` says.
* A ``GLAS`` line whose glass is a substitution solve (second value 3) carries another
  glass's nd and Vd from an earlier optimisation (Kraken's 400mmLensV1k: ``N-SF66 3 0
  1.5168 64.17``): the glass is the named catalog glass (the stale numbers warned about);
  with it that file's EFL is its design target, 400 mm (399.99999694; optiland 0.6.3 on
  the same glasses: 399.99999694, tools/check_corpus.py).
* ``GLAS AIR`` is air of index 1, the unit of every index (as a surface without GLAS);
  optiland 0.6.3 reads it as air of index 1.000277, so its EFL of such a file differs by
  ~2e-4 (tools/check_corpus.py gives optiland a copy without those lines).
"""

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx

Z12 = " ".join(["0"] * 12)


def _old_header(ftyp="FTYP 0 0 3 1 0 0 0"):
    return ("VERS 60801 390 3948\nMODE SEQ\nNAME \nUNIT MM X W X CM MR\nENPD 10\n"
            "PUPD 6.07E+001 1.0E+001\nENVD 2.0E+001 1 0\nGCAT SCHOTT\n"
            f"{ftyp}\nXFLD 0 0 0\nXFLN {Z12}\nYFLD 0 2 3\n"
            "YFLN 0 2 3 7 7 7 7 7 7 7 7 7\nFWGT 1 1 1\nFWGN 1 1 1 1 1 1 1 1 1 1 1 1\n"
            "ZVDX 0 0 0\nVDXN " + Z12 + "\nWAVL 5.5E-001\n"
            "WAVN 5.5E-001 4.861327E-001 6.562725E-001 0.55 0.55 0.55 0.55 0.55 0.55 0.55 0.55 "
            "0.55\nWWGT 1\nWWGN 1 1 1 1 1 1 1 1 1 1 1 1\n"
            "WAVM 1 5.5E-001 1\nWAVM 2 4.861327E-001 1\nWAVM 3 6.562725E-001 1\n"
            "WAVM 4 5.5E-001 1\nPWAV 1\n")


def _singlet(glas, glas_back="", curv=(0.02, -0.01)):
    return ("SURF 0\n  TYPE STANDARD\n  CURV 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  TYPE STANDARD\n  CURV {curv[0]}\n  DISZ 5\n  {glas}\n"
            f"SURF 2\n  TYPE STANDARD\n  CURV {curv[1]}\n  DISZ 60\n{glas_back}"
            "SURF 3\n  TYPE STANDARD\n  CURV 0\n  DISZ 0\n")


def _efl(lens):
    return float(jl.paraxial_data(lens).efl_image_space)


def _singlet_efl(n, c1=0.02, c2=-0.01, t=5.0):
    """Thick-lens focal length in air."""
    phi = (n - 1) * (c1 - c2) + (n - 1) ** 2 * t * c1 * c2 / n
    return 1 / phi


def test_zemax_2006_header_lines():
    lens = zmx.loads(_old_header() + _singlet("GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0"),
                     strict=True)
    np.testing.assert_array_equal(np.asarray(lens.fields), [0.0, 2.0, 3.0])  # 3 of YFLN, in y
    # FTYP's fourth value (1 wavelength) is not what WAVM lists; jaxlens reads the WAVM lines
    # up to the last one Zemax names by PWAV / its count: the primary is WAVM 1.
    assert float(lens.wavelengths[lens.primary]) == 0.55
    n = float(jl.get_material("N-BK7").index(0.55))
    assert _efl(lens) == pytest.approx(_singlet_efl(n), rel=1e-12)


def test_a_substituted_glass_is_the_named_catalog_glass():
    """``GLAS N-SF66 3 0 1.5168 64.17 …``: N-SF66 (nd 1.923), not a model glass of nd 1.5168;
    the stale nd and Vd are pointed out (a warning), as on any line naming a catalog glass."""
    line = "GLAS N-SF66 3 0 1.51680003 64.16733624 -0.00090000 1 1 1 0.00000000 0.00000000"
    with pytest.warns(zmx.ZmxWarning, match=r"GLAS N-SF66 gives nd 1\.5168, Vd 64\.1673, but "
                                            r"catalog SCHOTT has nd 1\.92286"):
        lens = zmx.loads(_old_header() + _singlet(line), strict=True)
    n = float(jl.get_material("N-SF66").index(0.55))
    assert n > 1.9
    assert _efl(lens) == pytest.approx(_singlet_efl(n), rel=1e-12)
    assert abs(_efl(lens) - _singlet_efl(1.5168)) > 10  # the model glass would be far off


def test_glas_air_is_index_1():
    head = "UNIT MM\nENPD 10\nWAVM 1 0.5875618 1\nPWAV 1\n"
    with_air = zmx.loads(head + _singlet("GLAS N-BK7", "  GLAS AIR\n"), strict=True)
    without = zmx.loads(head + _singlet("GLAS N-BK7"), strict=True)
    assert _efl(with_air) == _efl(without)
    assert float(with_air.materials[-1].index(0.5875618)) == 1.0
