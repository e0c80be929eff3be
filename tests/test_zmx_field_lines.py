"""Field lines of a ``.zmx`` file (``XFLN``, ``FWGN`` and the vignetting factors ``VDXN``,
``VDYN``, ``VCXN``, ``VCYN``, ``VANN``) with fewer values than the fields the y line
defines. Zemax writes one value a field, or 12 padded with zeros (every file of
tests/data/zmx does one or the other), so a shorter line was cut short: the values it
lacks are unknown, and the line is refused, naming it (they were read as 0 silently).
A ``YFLN`` shorter than FTYP's field count is reported (a warning, an error under
``strict``), as before; the lines of those missing fields may be as short as YFLN."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io.zmx import ZmxWarning

LINES = {"XFLN": "0 0 0", "YFLN": "0 5 10", "FWGN": "1 1 1", "VDXN": "0 0 0",
         "VDYN": "0 0.05 0.1", "VCXN": "0 0 0", "VCYN": "0 0.1 0.2", "VANN": "0 0 0"}


def _text(ftyp_fields=3, **lines) -> str:
    body = "".join(f"{k} {v}\n" for k, v in {**LINES, **lines}.items() if v is not None)
    return (f"UNIT MM\nENPD 10\nFTYP 0 0 {ftyp_fields} 1 0 0 0\n{body}WAVM 1 0.5875618 1\n"
            "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  CURV 0.02\n  DISZ 4\n"
            "  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\nSURF 2\n  CURV -0.005\n  DISZ 90\nSURF 3\n")


def _load(tmp_path, text, **kw):
    p = tmp_path / "f.zmx"
    p.write_text(text)
    return jl.load(p, **kw)


def _line(text, key):
    return 1 + [ln.split()[0] if ln.split() else "" for ln in text.splitlines()].index(key)


def test_full_lines_one_value_a_field_or_twelve(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ZmxWarning)
        lens = _load(tmp_path, _text(), strict=True)
        pad = {k: v + " 0" * 9 for k, v in LINES.items()}
        twelve = _load(tmp_path, _text(**pad), strict=True)
    np.testing.assert_array_equal(np.asarray(lens.fields), [0.0, 5.0, 10.0])
    np.testing.assert_array_equal(np.asarray(lens.vignetting[:, 1]), [0.0, 0.05, 0.1])
    np.testing.assert_array_equal(np.asarray(lens.vignetting[:, 3]), [0.0, 0.1, 0.2])
    np.testing.assert_array_equal(np.asarray(twelve.vignetting), np.asarray(lens.vignetting))


@pytest.mark.parametrize("key", ["VDXN", "VDYN", "VCXN", "VCYN", "VANN", "XFLN", "FWGN"])
def test_a_line_shorter_than_the_fields_is_refused(tmp_path, key):
    # A short vignetting line of zeros reads as no vignetting (Quadoa's 'VDXN 0':
    # test_zmx_round9); one with a factor is refused.
    short = {"VDXN": "0 0.05", "VCXN": "0 0.1", "VANN": "0 5"}.get(
        key, " ".join(LINES[key].split()[:2]))
    text = _text(**{key: short})
    with pytest.raises(ValueError) as e:
        _load(tmp_path, text)
    msg = str(e.value)
    assert f"f.zmx:{_line(text, key)}" in msg and f"{key} gives 2 values" in msg
    assert "for 3 fields; Zemax writes one a field" in msg
    assert f"{key} {short}" in msg  # the line's text


def test_an_empty_vignetting_line_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"VCYN gives 0 values \(vignetting factors\) for 3 "
                                         r"fields"):
        _load(tmp_path, _text(VCYN=""))


def test_no_vignetting_line_is_zemax_default_zero(tmp_path):
    """A line the file does not give at all is Zemax's default (0: no vignetting factor)."""
    lens = _load(tmp_path, _text(VDXN=None, VDYN=None, VCXN=None, VANN=None))
    np.testing.assert_array_equal(np.asarray(lens.vignetting[:, :3]), 0.0)
    np.testing.assert_array_equal(np.asarray(lens.vignetting[:, 3]), [0.0, 0.1, 0.2])


def test_fields_yfln_omits_are_reported_and_may_be_omitted_by_the_others(tmp_path):
    """FTYP says 4 fields, YFLN gives 3: the fourth is on axis with a warning (an error
    under strict); the other lines giving 3 values is not a second fault."""
    text = _text(ftyp_fields=4)
    with pytest.warns(ZmxWarning, match=r"FTYP announces 4 fields, YFLN gives 3"):
        lens = _load(tmp_path, text)
    np.testing.assert_array_equal(np.asarray(lens.fields), [0.0, 5.0, 10.0, 0.0])
    np.testing.assert_array_equal(np.asarray(lens.vignetting[:, 3]), [0.0, 0.1, 0.2, 0.0])
    with pytest.raises(ValueError, match=r"FTYP announces 4 fields, YFLN gives 3.*strict"):
        _load(tmp_path, text, strict=True)
