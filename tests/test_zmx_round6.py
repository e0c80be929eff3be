"""What the sixth round of public .zmx files (/work/zmx_probe/corpus6, not committed: their
sources are in its SOURCES.txt) showed, and how round 5's refusals were judged.

Round 5 refused four kinds of line; each was judged again by what OpticStudio does:

* ``GLAS N15 0 0 1.5 40`` (PyZDDE's Fiber Coupling, ``GCAT SCHOTT MISC``): N15 is a glass of
  Zemax's own MISC catalog, "a simulated glass with index of 1.5 at all wavelengths"
  (Conrady 1.5, 0, 0), so OpticStudio opens the file: jaxlens's MISC catalog now holds it.
  A glass no catalog has, with those default numbers, is still refused (test_zmx_round5).
* A line starting with ``!`` (a hand-written sample): ``!`` opens a comment in Zemax's macro
  language; OpticStudio writes none in a lens file. The line is skipped with a warning that
  names it, and refused under ``strict``; any other line that is no keyword is refused.
* ``ENPD 0`` (OpticStudio's new, empty lens) and ``FLOA`` with no stop size (DeepLens's own
  exporter): OpticStudio opens such a file but traces no ray through a pupil of size 0;
  jaxlens keeps refusing them, naming the line (test_zmx_round5).

The new files (optiland 0.6.3's test folder, ray-optics, Kraken, PyZDDE, VendettaMask's
samples) all opened, lenient and strict, with optiland's EFL (tools/check_corpus.py) and
real rays (tools/check_rays.py); three small ones are shipped (tests/data/zmx/README.md).
"""

import math
import os
import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")


def _efl(lens, wavelength=None):
    return float(jl.paraxial_data(lens, wavelength).efl_image_space)


def _singlet_efl(n, c1, c2, t):
    """Thick-lens focal length in air."""
    return 1 / ((n - 1) * (c1 - c2) + (n - 1) ** 2 * t * c1 * c2 / n)


def _singlet(glas, gcat="SCHOTT MISC", wavelength="1", before_surf2=""):
    return ("VERS 140124 1 1\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 10\n"
            f"GCAT {gcat}\nFTYP 0 0 1 1 0 0 0\nXFLN 0\nYFLN 0\nWAVM 1 {wavelength} 1\nPWAV 1\n"
            "SURF 0\n  CURV 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  CURV 0.02\n  DISZ 5\n  {glas}\n{before_surf2}"
            "SURF 2\n  CURV -0.01\n  DISZ 60\nSURF 3\n  CURV 0\n  DISZ 0\n")


def _caught(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn()
    return out, [str(w.message) for w in caught if issubclass(w.category, zmx.ZmxWarning)]


# ----------------------------------------------------------------- round 5's refusals, judged


@pytest.mark.parametrize("wavelength", ["0.4", "1"])
def test_zemax_misc_n15_is_a_constant_index_of_1_5(wavelength):
    """PyZDDE's Fiber Coupling: ``GLAS N15 0 0 1.5 4.0E+1`` with ``GCAT SCHOTT MISC`` is MISC's
    N15, index 1.5 at every wavelength: the singlet's EFL is the thick-lens formula's at
    n = 1.5, at 1 µm (the file's wavelength) as at 0.4 µm, and nothing is reported."""
    text = _singlet("GLAS N15 0 0 1.5 4.0E+1 0 0 0 0 0 0", wavelength=wavelength)
    lens, caught = _caught(lambda: zmx.loads(text, strict=True))
    assert caught == []
    assert lens.materials[0].catalog == "MISC"  # the medium after surface 1
    assert float(lens.materials[0].index(float(wavelength))) == 1.5
    assert _efl(lens) == pytest.approx(_singlet_efl(1.5, 0.02, -0.01, 5.0), rel=1e-12)


def test_n15_outside_the_files_catalogs_is_reported():
    """With only SCHOTT in GCAT, OpticStudio would not find N15: jaxlens takes MISC's and
    says so (an error under strict), as for any glass from a catalog the file does not name."""
    text = _singlet("GLAS N15 0 0 1.5 4.0E+1 0 0 0 0 0 0", gcat="SCHOTT")
    _, caught = _caught(lambda: zmx.loads(text))
    assert len(caught) == 1 and "<zmx>:18: glass 'N15' is not in the file's catalogs" in caught[0]
    with pytest.raises(ValueError, match=r"^<zmx>:18: glass 'N15' is not in the file's catal"):
        zmx.loads(text, strict=True)


def test_comment_lines_are_skipped_and_named():
    """'!' lines before the header and inside a surface block: the lens is the one without
    them (same EFL to the last bit), each line is named in a warning, and strict refuses
    the first; a line that is neither a keyword nor a comment is still refused."""
    plain = zmx.loads(_singlet("GLAS N-BK7 0 0 1.5168 64.17"))
    text = "! hand-written\n" + _singlet("GLAS N-BK7 0 0 1.5168 64.17",
                                         before_surf2="  !no space after the mark\n")
    lens, caught = _caught(lambda: zmx.loads(text))
    assert _efl(lens) == _efl(plain)
    assert [c.split(":")[1] for c in caught] == ["1", "20"]
    assert "'!no space after the mark'" in caught[1]
    with pytest.raises(ValueError, match=r"^<zmx>:1: a comment line .*strict mode"):
        zmx.loads(text, strict=True)
    with pytest.raises(ValueError, match=r"^<zmx>:20: not a Zemax keyword line: '// note'"):
        zmx.loads(text.replace("!no space after the mark", "// note"))


# --------------------------------------------------------------------- shipped real files


def test_inactive_wavelengths_are_not_read():
    """optiland's inactive_wavelengths (MIT): FTYP 1 0 1 1 announces one wavelength of the
    five WAVM lines; the lens has that one (0.78 µm), an object 10 mm away and its field as
    an object height (FTYP's first value 1)."""
    lens, caught = _caught(lambda: jl.load(os.path.join(DATA, "optiland_inactive_wavelengths.zmx"),
                                           strict=True))
    assert caught == []
    np.testing.assert_array_equal(np.asarray(lens.wavelengths), [0.78])
    assert math.isinf(_efl(lens))  # two flat surfaces in air


def test_even_asphere_plano_convex_efl_is_r_over_n_minus_1():
    """optiland's lens2 (MIT): an OHARA L-BAL35 even asphere, flat behind, its GLAS line the
    name alone. A plano-convex lens has EFL 1/(c (n − 1)) at any thickness (PARM 1, the r²
    term, is 0), n the catalog's at the primary wavelength 0.5876 µm."""
    lens, caught = _caught(lambda: jl.load(os.path.join(DATA, "optiland_lens2.zmx"), strict=True))
    assert caught == []
    n = float(jl.get_material("L-BAL35", "OHARA").index(0.5876))
    c = 7.544322897019992147e-02
    assert _efl(lens) == pytest.approx(1 / (c * (n - 1)), rel=1e-12)
    assert lens.materials[0].catalog == "OHARA"


def test_four_mirror_file_of_opticstudio_16_is_the_older_files_system():
    """ray-optics' HoO-V2C18Ex66NEW (BSD-3-Clause): the four tilted mirrors of
    HoO-V2C18Ex66 as OpticStudio 16 wrote them (PPAR pickups of coordinate-break angles,
    GLCB lines, MEMA, FIMP): the same mirrors, so the same EFL, back focus, pupils and F/# as
    the older file (one surface fewer), which tests/test_corpus.py checks against optiland."""
    new = jl.load(os.path.join(DATA, "rayoptics_HoO-V2C18Ex66NEW.zmx"), strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        old = jl.load(os.path.join(DATA, "rayoptics_HoO-V2C18Ex66.zmx"))
    assert _efl(new) == pytest.approx(_efl(old), rel=1e-12)
    assert _efl(new) == pytest.approx(90.05187904998931, rel=1e-9)  # optiland 0.6.3's
    assert new.mirrors == old.mirrors == (2, 6, 10, 14)
    pn, po = jl.paraxial_data(new), jl.paraxial_data(old)
    for name in ("bfl", "entrance_pupil_diameter", "exit_pupil_z", "fnum"):
        assert float(getattr(pn, name)) == pytest.approx(float(getattr(po, name)), rel=1e-9)
