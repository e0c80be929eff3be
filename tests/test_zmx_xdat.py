"""The extra data (XDAT) of BINARY_2, SZERNSAG, FZERNSAG, QED_TYPE, XPOLYNOM, XASPHERE and
XOSPHERE surfaces, read through one checked accessor (``zmx_surfaces.ExtraData``): a
missing required line names the surface's TYPE line and the XDAT index, a value that is not
a number names its line, nonzero data before XDAT 1 are refused. Which lines each surface
requires is its own: a missing term line is refused for BINARY_2, QED_TYPE and XPOLYNOM and
reads as 0 for the Zernike sags and the extended aspheres (as before)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import jaxlens as jl

TYPE_LINE = 8
# kind: (extra lines, XDAT index -> value, the index of the first term)
KINDS = {
    "BINARY_2": ("  PARM 0 1\n", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
    "SZERNSAG": ("", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
    "FZERNSAG": ("", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
    "QED_TYPE": ("", {1: "0", 2: "2", 3: "5", 4: "1e-3", 5: "-2e-4"}, 4),
    "XPOLYNOM": ("", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
    "XASPHERE": ("", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
    "XOSPHERE": ("", {1: "2", 2: "5", 3: "1e-3", 4: "-2e-4"}, 3),
}
HEADERS = {  # the header each kind requires, as its message lists it
    "XDAT2": r"XDAT 1 \(the number of terms\) and XDAT 2 \(the normalisation radius, lens "
             r"units\)",
    "ZERN": r"XDAT 1 \(the number of terms\) and XDAT 2 \(the Zernike normalisation radius, "
            r"lens units\)",
    "QED": r"XDAT 1 \(the polynomial type: 0 Q-bfs, 1 Q-con\), XDAT 2 \(the number of terms\) "
           r"and XDAT 3 \(the normalisation radius, lens units\)",
}
# kind: (the XDAT line removed, the header the message lists)
REQUIRED = {"BINARY_2": (2, "XDAT2"), "SZERNSAG": (2, "ZERN"), "FZERNSAG": (2, "ZERN"),
            "QED_TYPE": (1, "QED"), "XPOLYNOM": (2, "XDAT2"), "XASPHERE": (1, "XDAT2"),
            "XOSPHERE": (2, "XDAT2")}
TERMS_REQUIRED = ("BINARY_2", "QED_TYPE", "XPOLYNOM")


def _text(kind, xdat=None, extra=None) -> str:
    ex, data, _ = KINDS[kind]
    data = data if xdat is None else xdat
    lines = "".join(f"  XDAT {i} {v}\n" for i, v in data.items())
    return ("UNIT MM\nENPD 10\nWAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  TYPE {kind}\n  CURV 0.02\n{ex if extra is None else extra}"
            f"{lines}  DISZ 4\n  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"
            "SURF 2\n  CURV -0.005\n  DISZ 90\nSURF 3\n")


def _load(tmp_path, text, **kw):
    p = tmp_path / "x.zmx"
    p.write_text(text)
    return p, jl.load(p, **kw)


def _refused(tmp_path, text, line, match):
    p = tmp_path / "x.zmx"
    p.write_text(text)
    with pytest.raises(ValueError, match=f"^{re.escape(str(p))}:{line}: {match}"):
        jl.load(p)


def _line_of(text, start):
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.strip().startswith(start))


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_whole_extra_data_load(tmp_path, kind):
    _, lens = _load(tmp_path, _text(kind), strict=True)
    assert lens.surfaces[0] is not None


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_missing_header_line_names_the_type_line_and_index(tmp_path, kind):
    i, header = REQUIRED[kind]
    data = {j: v for j, v in KINDS[kind][1].items() if j != i}
    _refused(tmp_path, _text(kind, data), TYPE_LINE,
             f"{kind} needs {HEADERS[header]}; XDAT {i} is missing")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_missing_term_line(tmp_path, kind):
    """The second term's line left out: refused at the count line where the surface needs
    every term, read as 0 where it always did."""
    _, data, first = KINDS[kind]
    gone = first + 1
    short = {j: v for j, v in data.items() if j != gone}
    text = _text(kind, short)
    if kind in TERMS_REQUIRED:
        ci = first - 2 if kind == "QED_TYPE" else 1
        _refused(tmp_path, text, _line_of(text, f"XDAT {ci} "),
                 rf"XDAT {ci} gives 2 .*terms, so XDAT {first} … XDAT {gone} are needed, but "
                 rf"XDAT {gone} is missing")
    else:
        _, lens = _load(tmp_path, text)
        _, full = _load(tmp_path, _text(kind, {**data, gone: "0"}))
        s, f = lens.surfaces[0], full.surfaces[0]
        name = "zernike" if "ZERN" in kind else "coeffs"
        np.testing.assert_array_equal(np.asarray(getattr(s, name)), np.asarray(getattr(f, name)))


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("bad, message", [("abc", r"XDAT 3 value is not a number \('abc'\)"),
                                          ("1e999", r"XDAT 3 value must be finite")])
def test_a_value_that_is_not_a_number_names_its_line(tmp_path, kind, bad, message):
    _, data, _ = KINDS[kind]
    text = _text(kind, {**data, 3: bad})
    _refused(tmp_path, text, _line_of(text, "XDAT 3 "), message)


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_extra_data_before_xdat_1_are_refused(tmp_path, kind):
    """XASPHERE and XOSPHERE read a nonzero XDAT 0 without a word before."""
    _, data, _ = KINDS[kind]
    text = _text(kind, {0: "1", **data})
    _refused(tmp_path, text, _line_of(text, "XDAT 0 "), f"{kind} extra data start at XDAT 1")
    _load(tmp_path, _text(kind, {0: "0", **data}))  # a zero there is what Zemax may write


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_nonzero_value_beyond_the_terms_is_refused(tmp_path, kind):
    _, data, first = KINDS[kind]
    text = _text(kind, {**data, first + 3: "1e-5"})
    ci = first - 2 if kind == "QED_TYPE" else 1
    _refused(tmp_path, text, _line_of(text, f"XDAT {first + 3} "),
             rf"coefficient beyond the 2 .*terms of XDAT {ci} \(XDAT {first} … XDAT {first + 1}\)")
