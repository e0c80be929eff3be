"""Malformed lens files, as a fuzzer makes them: every one is refused with a ValueError that
names the file (and, for .zmx, the line), or loads as a lens with finite numbers. Never a
crash of another type, a hang, or a lens that traces to NaN."""

import json
import pathlib
import random
import re
import warnings

import numpy as np
import pytest

import jaxlens as jl

LENSES = pathlib.Path(jl.__file__).parent / "data" / "lenses"
HYBRID_ZMX = (LENSES / "hybrid_singlet.zmx").read_text()
HYBRID_JSON = (LENSES / "hybrid_singlet.json").read_text()
COOKE_ZMX = (LENSES / "cooke_triplet.zmx").read_text()
OPTILAND_ZMX = (pathlib.Path(__file__).parent / "data" / "zmx" / "optiland_lens1.zmx").read_text()


def _sub(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


def _json(edit):
    d = json.loads(HYBRID_JSON)
    edit(d)
    return json.dumps(d)


def _set(i, key, value):
    return lambda d: d["surfaces"][i].__setitem__(key, value)


# One mutant per bug class the fuzzer found; each crashed, hung or loaded a lens that
# traced to NaN before. (name, suffix, text, line of the message or None)
CASES = [
    # arithmetic on a normalisation radius: 1e-300**d is 0 (ZeroDivisionError), 1e300**d
    # overflows (OverflowError)
    ("xdat_norm_tiny", ".zmx", _sub(HYBRID_ZMX, "XDAT 2 1.0 ", "XDAT 2 1e-300 "), 30),
    ("xdat_norm_huge", ".zmx", _sub(HYBRID_ZMX, "XDAT 2 1.0 ", "XDAT 2 1e300 "), 30),
    # counts with no bound: the reader looped to them (a hang)
    ("ftyp_wavelengths", ".zmx", _sub(HYBRID_ZMX, "FTYP 0 0 3 3", "FTYP 0 0 3 1e9"), 9),
    ("ftyp_fields", ".zmx", _sub(HYBRID_ZMX, "FTYP 0 0 3 3", "FTYP 0 0 1e9 3"), 9),
    ("hybrid_comment", ".zmx", _sub(HYBRID_ZMX, "even=3 odd=1", "even=99999999 odd=1"), 29),
    # a length that overflows once scaled to mm, or traces to inf/NaN
    ("thickness_huge", ".zmx", _sub(HYBRID_ZMX, "DISZ 3.0E+000", "DISZ 1e308"), 63),
    ("thickness_unit", ".zmx", _sub(_sub(HYBRID_ZMX, "UNIT MM", "UNIT METER"),
                                    "DISZ 3.0E+000", "DISZ 1e306"), 63),
    ("epd_subnormal", ".zmx", _sub(HYBRID_ZMX, "ENPD 5.0E+000", "ENPD 1e-320"), 5),
    # a curvature of 1e308 with no aperture to refuse it: refused on its CURV line (since
    # round 45b's |c| <= 1e9 per mm; before, at the aperture line, where the paraxial work
    # traced it to NaN)
    ("curvature_no_aperture", ".zmx", _sub(OPTILAND_ZMX, "CURV -0.0055170138366520405",
                                           "CURV 1e308"), 27),
    # a material class's refusal without the line (ModelGlass: nd <= 4.5)
    ("model_glass_nd", ".zmx", _sub(COOKE_ZMX, "GLAS N-SK16 0 0 1.62041 6.032E+001",
                                    "GLAS ___BLANK 1 0 1e308 50"), 27),
    # JSON: the same classes, and errors of the classes the reader calls
    ("json_thickness", ".json", _json(_set(2, "thickness", 1e308)), None),
    ("json_epd", ".json", _json(lambda d: d["aperture"].__setitem__("epd", 1e-320)), None),
    ("json_coefficient", ".json", _json(_set(2, "even_asphere_coeffs", [1e308])), None),
    ("json_index_table", ".json", _json(_set(2, "n", {"587.5618": 1e308})), None),
    ("json_model_glass", ".json", _json(_set(2, "material", {"nd": 1e308, "vd": 50})), None),
    ("json_fnum", ".json", _json(lambda d: d.__setitem__("aperture", {"fnum": 1e-320})), None),
    ("json_long_int", ".json", HYBRID_JSON.replace("14.95", "1" + "0" * 400), None),
    ("json_longer_int", ".json", HYBRID_JSON.replace("14.95", "1" + "0" * 5000), None),
]


@pytest.mark.parametrize("name, suffix, text, line", CASES, ids=[c[0] for c in CASES])
def test_bug_class_refused_at_its_line(tmp_path, name, suffix, text, line):
    path = tmp_path / f"{name}{suffix}"
    path.write_text(text)
    where = re.escape(str(path)) + (f":{line}:" if line else r"(:\d+)?:")
    with pytest.raises(ValueError, match=where):
        jl.load(path)


# ----------------------------------------------------------------------- a seeded sweep

_NUMBER = re.compile(r"(?<![A-Za-z_])[-+]?(\d+\.?\d*|\.\d+)([eEdD][-+]?\d+)?")
_VALUES = ["abc", "nan", "inf", "-inf", "1e999", "-0", "0", "1e300", "-1e300", "1e-300", "-1",
           "99999999999999999999", "2.5"]
_JSON_VALUES = ["abc", None, True, [], {}, [1.0, 2.0], "nan", "inf", 0, -1, 1e308, 1e-320,
                [[[1.0]]]]


def _mutate_text(text, rng):
    lines = text.splitlines(keepends=True)
    i = rng.randrange(len(lines))
    op = rng.choice(["number", "number", "number", "token", "delete", "duplicate", "swap",
                     "truncate"])
    if op == "number":
        spots = [(j, m) for j, ln in enumerate(lines) for m in _NUMBER.finditer(ln)]
        j, m = rng.choice(spots)
        lines[j] = lines[j][:m.start()] + rng.choice(_VALUES) + lines[j][m.end():]
    elif op == "token" and len(lines[i].split()) > 1:
        tokens = lines[i].split()
        del tokens[rng.randrange(len(tokens))]
        lines[i] = "  " + " ".join(tokens) + "\n"
    elif op == "delete":
        del lines[i]
    elif op == "duplicate":
        lines.insert(i, lines[i])
    elif op == "swap" and i + 1 < len(lines):
        lines[i], lines[i + 1] = lines[i + 1], lines[i]
    elif op == "truncate":
        lines = lines[:i]
    return "".join(lines)


def _paths(o, path=()):
    yield path
    items = o.items() if isinstance(o, dict) else enumerate(o) if isinstance(o, list) else ()
    for k, v in items:
        yield from _paths(v, path + (k,))


def _mutate_json(text, rng):
    d = json.loads(text)
    path = rng.choice(list(_paths(d))[1:])
    parent = d
    for k in path[:-1]:
        parent = parent[k]
    if rng.random() < 0.2:
        del parent[path[-1]]
    else:
        parent[path[-1]] = rng.choice(_JSON_VALUES)
    return json.dumps(d)


def _finite_lens(lens):
    parts = [lens.thickness, lens.epd, lens.fields, lens.wavelengths]
    parts += [getattr(s, n) for s in lens.surfaces for n in ("c", "k", "coeffs")
              if hasattr(s, n)]
    for w in np.asarray(lens.wavelengths).reshape(-1):
        parts += lens.indices(w)
    return all(np.all(np.isfinite(np.asarray(p))) for p in parts) and float(lens.epd) > 0


@pytest.mark.parametrize("suffix", [".zmx", ".json"])
def test_seeded_sweep(tmp_path, suffix):
    source, mutate = ((HYBRID_ZMX, _mutate_text) if suffix == ".zmx" else
                      (HYBRID_JSON, _mutate_json))
    outcomes = {"loaded": 0, "refused": 0}
    for k in range(100):
        rng = random.Random(f"sweep-{suffix}-{k}")
        path = tmp_path / f"m{k}{suffix}"
        path.write_text(mutate(source, rng))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                lens = jl.load(path)
        except ValueError as e:
            assert str(path) in str(e), (k, str(e))
            outcomes["refused"] += 1
            continue
        assert _finite_lens(lens), (k, path.read_text())
        outcomes["loaded"] += 1
    assert outcomes["refused"] > 10 and outcomes["loaded"] > 10, outcomes
