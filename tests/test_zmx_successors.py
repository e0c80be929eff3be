"""Discontinued SCHOTT glasses that no shipped catalog holds (SCHOTT's catalogs before 2008:
SSK4, LAF21, LASF9, SF56, KZFS4): a file naming them under ``GCAT SCHOTT`` opens with
SCHOTT's successor glass and a warning naming it; without a successor rule the refusal
lists the close matches, the successor first."""

from __future__ import annotations

import warnings

import pytest

from jaxlens.io import zmx

TEXT = ("UNIT MM\nGCAT {cat}\nENPD 10\nWAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\n"
        "SURF 1\n  STOP\n  CURV 0.02\n  DISZ 5\n  GLAS {glass} 0 0 {nd} {vd} 0 0 0 0 0 0\n"
        "SURF 2\n  CURV -0.02\n  DISZ 40\nSURF 3\n")


@pytest.mark.parametrize(("old", "nd", "vd", "new"), [
    ("SSK4", 1.61765, 55.14, "SSK4A"),
    ("LAF21", 1.788, 47.49, "N-LAF21"),
    ("LASF9", 1.85025, 32.17, "N-LASF9"),
    ("SF56", 1.7847, 26.08, "N-SF56"),
    ("KZFS4", 1.6134, 44.3, "N-KZFS4"),
])
def test_discontinued_schott_glass_opens_as_its_successor(old, nd, vd, new):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lens = zmx.loads(TEXT.format(cat="SCHOTT", glass=old, nd=nd, vd=vd))
    m = lens.materials[0]
    assert (m.name, m.catalog) == (new, "SCHOTT")
    said = [str(w.message) for w in caught if issubclass(w.category, zmx.ZmxWarning)]
    assert len(said) == 1 and f"glass {old!r} is not in the shipped SCHOTT catalog" in said[0]
    assert f"successor {new} " in said[0]
    with pytest.raises(ValueError, match=f"successor {new} "):
        zmx.loads(TEXT.format(cat="SCHOTT", glass=old, nd=nd, vd=vd), strict=True)


def test_without_schott_in_gcat_the_refusal_lists_the_successor():
    with pytest.raises(ValueError, match=r"<zmx>:11: glass 'SSK4': Unknown material 'SSK4'\. "
                                         r"Closest catalog matches: SSK4A, .*Optically closest "
                                         r"to nd 1\.61765, Vd 55\.14: SCHOTT SSK4A "):
        zmx.loads(TEXT.format(cat="OHARA", glass="SSK4", nd=1.61765, vd=55.14))
