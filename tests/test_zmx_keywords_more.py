"""OpticStudio 2024 header keywords (IWDP, STUD, EERA) and the messages for glasses jaxlens has
no data for (a GLAS line with Zemax's placeholder nd/Vd, a molded-glass catalog entry)."""

import re
import warnings

import pytest

from jaxlens.io import zmx


def _lens(head="", glass="N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0"):
    return (f"VERS 240823 193 1055371 1055371\nMODE SEQ\n{head}UNIT MM\nENPD 10\n"
            f"WAVM 1 0.55 1\nSURF 0\n  CURV 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  CURV 0.02\n"
            f"  DISZ 5\n  GLAS {glass}\nSURF 2\n  CURV -0.02\n  DISZ 45\nSURF 3\n  CURV 0\n"
            f"  DISZ 0\n")


SEEN = "IWDP 0\nSTUD 1\nEERA 0 0 0 10 10\nEERA 0 0 0 10\nTELE 0\nAFOC 0\n"


def test_header_keywords_with_the_values_seen_read_in_strict_mode_without_a_word():
    plain = zmx.loads(_lens(), strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lens = zmx.loads(_lens(SEEN), strict=True)
    assert float(lens.epd) == float(plain.epd)
    assert float(lens.thickness[1]) == float(plain.thickness[1])


@pytest.mark.parametrize("line", ["IWDP 1", "STUD 0", "STUD", "EERA 1 0 0 10 10",
                                  "EERA 0 0", "IWDP X", "AFOC 1", "TELE 1"])
def test_other_values_are_reported_as_undocumented(line):
    text = _lens(line + "\n")
    with pytest.raises(ValueError, match=rf"<zmx>:3: {line.split()[0]} with a value jaxlens "
                                         rf"has not seen .*may change the lens.*strict mode"):
        zmx.loads(text, strict=True)
    with pytest.warns(zmx.ZmxWarning, match=re.escape(repr(line))):
        zmx.loads(text)


def test_a_truly_unknown_keyword_is_still_reported():
    with pytest.raises(ValueError, match=r"unknown keyword 'QWXZ'.*strict mode"):
        zmx.loads(_lens("QWXZ 0\n"), strict=True)


def test_placeholder_nd_vd_is_not_offered_as_a_model_glass():
    """GLAS N16 0 0 1.5 4.0E+1 … (a glass in no catalog) — 1.5 and 40 are Zemax's defaults.
    (pyzdde's Fiber_Coupling names N15 so, which round 6 found in Zemax's MISC catalog:
    tests/test_zmx_round6.py.)"""
    text = _lens(glass="N16 0 0 1.5 4.0E+1 0 0 0 0 0 0")
    with pytest.raises(ValueError, match=r"<zmx>:\d+: glass 'N16': .*nd 1\.5, Vd 40, Zemax's "
                                         r"defaults .*not this glass's data"):
        zmx.loads(text)
    with pytest.raises(ValueError, match=r"no model glass can stand in"):
        zmx.loads(text, unknown_glass="model")  # the placeholders are never used
    # With a real nd/Vd on the line the model glass is offered, as before.
    real = _lens(glass="N16 0 0 1.62 45 0 0 0 0 0 0")
    with pytest.raises(ValueError, match=r"load it with unknown_glass='model'"):
        zmx.loads(real)


def test_a_molded_glass_is_not_replaced_by_its_catalog_namesake():
    """A molded glass that no shipped catalog has (rayoptics US08427765-1's L-TIM28_MOLD, GCAT
    RPO, which this note was written for, reads RPO's from round 40a)."""
    text = _lens(glass="S-LAH64_MOLD 0 0 1.5 4.0E+1 0 0 0 0 0 0")
    with pytest.raises(ValueError, match=r"S-LAH64_MOLD is S-LAH64 as a molded lens .*OHARA "
                                         r"S-LAH64, but a molded glass's index differs"):
        zmx.loads(text)
    with pytest.raises(ValueError, match=r"glass 'NOSUCH_MOLD': Unknown material") as e:
        zmx.loads(_lens(glass="NOSUCH_MOLD 0 0 1.5 4.0E+1 0 0 0 0 0 0"))
    assert "as a molded lens" not in str(e.value)  # no namesake: no note
