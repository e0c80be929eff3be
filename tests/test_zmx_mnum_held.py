"""``MNUM n`` without the active configuration (Zemax 2006 files, VERS 60801, write it so):
the active one is the configuration whose THIC/CRVT/CONN rows the surfaces hold.

The corpus file that showed it (Kraken's ``2_6 Zoom_Conf4_stp2.ZMX``: ``MNUM 4``, the surfaces
holding position 4) read as configuration 1 before: ``load(path, config=1)`` returned position
4's lens with a warning, and ``strict=True`` refused the file. Here a two-singlet pair of a
dispersion-free glass whose surfaces hold configuration 2's gap; the EFLs are checked against
a hand ABCD calculation.
"""

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx

GLASS = "  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"


def _pair(gap_held, mnum, rows=None):
    """Two singlets (nd 1.5), surface 2's gap ``gap_held`` mm on the surfaces; configuration
    1 has a 10 mm gap, configuration 2 a 30 mm one (or ``rows``)."""
    rows = rows if rows is not None else ("THIC 2 1 10 0 0 0 1 1 1 0 0\n"
                                          "THIC 2 2 30 0 0 0 1 1 1 0 0\n")
    return (f"UNIT MM\nENPD 10\nWAVM 1 0.55 1\nSURF 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  CURV 0.01\n  DISZ 4\n{GLASS}"
            f"SURF 2\n  CURV 0\n  DISZ {gap_held}\n"
            f"SURF 3\n  CURV 0.02\n  DISZ 3\n{GLASS}"
            f"SURF 4\n  CURV -0.005\n  DISZ 50\nSURF 5\n  DISZ 0\n{mnum}\n{rows}")


def _efl(gap):
    """The pair's EFL by hand: refraction [[1, 0], [-(n'-n)c/n', n/n']], transfer [[1, t],
    [0, 1]] on (y, u)."""
    def refr(c, n1, n2):
        return np.array([[1.0, 0.0], [-(n2 - n1) * c / n2, n1 / n2]])

    def move(t):
        return np.array([[1.0, t], [0.0, 1.0]])
    n = 1.5
    m = refr(-0.005, n, 1) @ move(3) @ refr(0.02, 1, n) @ move(gap) @ refr(0.0, n, 1) \
        @ move(4) @ refr(0.01, 1, n)
    return -1 / m[1, 0]


def test_the_active_configuration_is_the_one_the_surfaces_hold():
    text = _pair(30, "MNUM 2")
    for config, gap in ((None, 30.0), (2, 30.0), (1, 10.0)):
        lens = zmx.loads(text, strict=True, config=config)  # no contradiction to report
        assert float(lens.thickness[1]) == gap
        assert float(jl.paraxial_data(lens).efl_image_space) == pytest.approx(_efl(gap),
                                                                              rel=1e-12)
    assert abs(_efl(10.0) - _efl(30.0)) > 1  # the two configurations differ


def test_configurations_names_the_held_one(tmp_path):
    p = tmp_path / "z.zmx"
    p.write_text(_pair(30, "MNUM 2"))
    assert jl.io.zmx_read.configurations(p)["active"] == 2
    p.write_text(_pair(10, "MNUM 2"))
    assert jl.io.zmx_read.configurations(p)["active"] == 1


def test_configuration_1_wins_a_tie_and_no_match_falls_back_to_1():
    """Both configurations hold 30 (a tie): 1, as before; neither holds the surfaces' 20:
    1, and the contradiction is reported (an error under strict), as before."""
    tie = _pair(30, "MNUM 2", "THIC 2 1 30 0 0 0 1 1 1 0 0\nTHIC 2 2 30 0 0 0 1 1 1 0 0\n")
    assert float(zmx.loads(tie, strict=True).thickness[1]) == 30.0
    none = _pair(20, "MNUM 2")
    with pytest.raises(ValueError, match=r"THIC 2 of configuration 1, the active one \(MNUM\), "
                                         r"is 10, but surface 2 holds 20"):
        zmx.loads(none, strict=True)
    with pytest.warns(zmx.ZmxWarning, match="jaxlens reads the surfaces"):
        assert float(zmx.loads(none).thickness[1]) == 20.0


def test_an_explicit_active_number_is_kept():
    """MNUM 2 1 over surfaces holding configuration 2: the file's own word is kept, and the
    contradiction reported, as before."""
    with pytest.raises(ValueError, match=r"THIC 2 of configuration 1, the active one"):
        zmx.loads(_pair(30, "MNUM 2 1"), strict=True)
