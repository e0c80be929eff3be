"""The extra data (XDAT) of BINARY_2, SZERNSAG, FZERNSAG, QED_TYPE, XPOLYNOM (and jaxlens's
hybrid, an XPOLYNOM with its comment), XASPHERE and XOSPHERE surfaces, read through one checked
accessor (``zmx_surfaces.ExtraData``) under one rule, from what OpticStudio writes: every line
from XDAT 1 to the last the surface uses, zeros included (tests/data/zmx/
optiland_thorlabs_lj1598l1.zmx: a TOROIDAL with no Zernike terms writes XDAT 1 = 0 and
XDAT 2 = 100, its default radius; rayoptics_ASL5040-UV.zmx: a QED_TYPE writes every term).
A missing header line (count, radius, QED type) is refused naming the TYPE line and the
index, since its default is the surface type's own; a missing term line reads as 0, as a
missing PARM does; a value that is not a number names its line; nonzero data before XDAT 1
or beyond the N terms are refused."""

from __future__ import annotations

import re

import jax
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
# kind: the header the message lists, and how many header lines it has
REQUIRED = {"BINARY_2": "XDAT2", "SZERNSAG": "ZERN", "FZERNSAG": "ZERN", "QED_TYPE": "QED",
            "XPOLYNOM": "XDAT2", "XASPHERE": "XDAT2", "XOSPHERE": "XDAT2"}
HEADER_LINES = [(k, i) for k in sorted(KINDS) for i in range(1, KINDS[k][2])]


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


@pytest.mark.parametrize("kind, i", HEADER_LINES)
def test_a_missing_header_line_names_the_type_line_and_index(tmp_path, kind, i):
    """Each header line left out in turn (XDAT 1 and 2; QED_TYPE's 1, 2 and 3)."""
    data = {j: v for j, v in KINDS[kind][1].items() if j != i}
    _refused(tmp_path, _text(kind, data), TYPE_LINE,
             f"{kind} needs {HEADERS[REQUIRED[kind]]}; XDAT {i} is missing")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_block_without_extra_data_is_refused(tmp_path, kind):
    """No XDAT line at all: the count is not known either (OpticStudio writes XDAT 1 even
    for no terms), so the first header line is named."""
    _refused(tmp_path, _text(kind, {}), TYPE_LINE,
             f"{kind} needs {HEADERS[REQUIRED[kind]]}; XDAT 1 is missing")


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("which", ["first", "last"])
def test_a_missing_term_line_reads_as_0(tmp_path, kind, which):
    """The first or the last of the two terms left out: the surface is the one with a zero
    there, leaf for leaf, for every kind (strict reading says nothing)."""
    _, data, first = KINDS[kind]
    gone = first if which == "first" else first + 1
    short = {j: v for j, v in data.items() if j != gone}
    _, lens = _load(tmp_path, _text(kind, short), strict=True)
    _, full = _load(tmp_path, _text(kind, {**short, gone: "0"}), strict=True)
    _, orig = _load(tmp_path, _text(kind))
    for a, b in zip(jax.tree_util.tree_leaves(lens.surfaces[0]),
                    jax.tree_util.tree_leaves(full.surfaces[0]), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    # and the term is really there: the whole file's surface differs
    assert any(not np.array_equal(np.asarray(a), np.asarray(b)) for a, b in zip(
        jax.tree_util.tree_leaves(lens.surfaces[0]), jax.tree_util.tree_leaves(orig.surfaces[0]),
        strict=True))


def test_zero_terms_need_no_term_lines(tmp_path):
    """N = 0: the header alone is whole (what OpticStudio writes for no terms)."""
    for kind, (_, data, first) in KINDS.items():
        head = {j: v for j, v in data.items() if j < first}
        head[first - 2 if kind == "QED_TYPE" else 1] = "0"
        _load(tmp_path, _text(kind, head), strict=True)


def test_a_hybrid_reads_a_missing_term_line_as_0(tmp_path):
    """jaxlens's hybrid (an XPOLYNOM with its comment; terms x, y, x², xy, y²) follows the same
    rule: its zero x and y lines may be left out; its x² line left out reads as 0, which no
    longer fits the hybrid's r² term (x² and y² equal), so the file is refused saying so."""
    hybrid = "  COMM jaxlens hybrid even=1 odd=0\n"
    data = {1: "5", 2: "1", 3: "0", 4: "0", 5: "1e-3", 6: "0", 7: "1e-3"}
    _, lens = _load(tmp_path, _text("XPOLYNOM", data, extra=hybrid), strict=True)
    assert type(lens.surfaces[0]).__name__ == "Hybrid"
    sparse = {j: v for j, v in data.items() if v != "0"}
    _, again = _load(tmp_path, _text("XPOLYNOM", sparse, extra=hybrid), strict=True)
    np.testing.assert_array_equal(np.asarray(again.surfaces[0].coeffs),
                                  np.asarray(lens.surfaces[0].coeffs))
    text = _text("XPOLYNOM", {j: v for j, v in data.items() if j != 5}, extra=hybrid)
    _refused(tmp_path, text, _line_of(text, "XDAT 7 "),
             r"XPOLYNOM term x\^0 y\^2 = 0\.001 does not fit the hybrid surface .*expected 0\.0")


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
