"""Round 21: a design jaxlens exports says what it describes to an independent tool.

A catalog glass is written by name, and another tool (optiland 0.6.3 reads E48R as nd
1.53055; jaxlens's, from Zemax's ZEON catalog, is 1.53117) or another catalog version can read
a name as other data. So a JSON file records each medium's index at the file's wavelengths
(``index_at_wavelengths``), which the reader checks, and a ``.zmx`` file carries them (and the
units, conventions and stop) in ``NOTE`` lines, which Zemax, optiland and jaxlens do not
interpret. tools/export_reevaluation.py reads the surface types optiland's reader lacks
(XPOLYNOM: jaxlens's Hybrid) by Zemax's own definitions; checked here against jaxlens's sag.
"""

import importlib.util
import json
import os
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import material_spec
from jaxlens.optics.materials import Air
from jaxlens.optics.surfaces import Hybrid
from jaxlens.optics.xypolynomial import xy_term_powers

LENSES = os.path.join(os.path.dirname(jl.__file__), "data", "lenses")
TOOL = os.path.join(os.path.dirname(__file__), os.pardir, "tools", "export_reevaluation.py")


def _cooke():
    return jl.load(os.path.join(LENSES, "cooke_triplet.json"), dtype="float64")


def _same(a, b):
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(np.asarray(x, np.float64), np.asarray(y, np.float64))


def _indices(m, lens):
    return np.asarray(m.index(jnp.asarray(np.asarray(lens.wavelengths, np.float64))),
                      np.float64)


def test_json_records_each_medium_index_at_the_file_wavelengths(tmp_path):
    lens = _cooke()
    p = tmp_path / "c.json"
    jl.save(lens, p)
    d = json.loads(p.read_text())
    body = d["surfaces"][1:-1]
    assert len(body) == len(lens.materials)
    glasses = 0
    for s, m in zip(body, lens.materials, strict=True):
        if isinstance(m, Air):
            assert material_spec.INDEX_RECORD not in s
        else:
            glasses += 1
            np.testing.assert_array_equal(s[material_spec.INDEX_RECORD], _indices(m, lens))
    assert glasses == 3
    _same(jl.load(p, dtype="float64"), lens)  # the record changes nothing read back


def _tampered(tmp_path, edit):
    lens = _cooke()
    p = tmp_path / "c.json"
    jl.save(lens, p)
    d = json.loads(p.read_text())
    edit(d, lens)
    q = tmp_path / "t.json"
    q.write_text(json.dumps(d))
    return q


def test_json_refuses_a_name_that_reads_as_other_glass_data(tmp_path):
    # The file names N-SK16 but its record is F2's: a reader whose N-SK16 is other data.
    def edit(d, lens):
        f2 = next(m for m in lens.materials if getattr(m, "name", "") == "F2")
        d["surfaces"][1][material_spec.INDEX_RECORD] = [float(v) for v in _indices(f2, lens)]

    q = _tampered(tmp_path, edit)
    with pytest.raises(ValueError, match=r"surface 1: material 'N-SK16' has n = .*"
                                         r"index_at_wavelengths; off by 0\.0"):
        jl.load(q)


def test_json_index_record_needs_one_index_per_wavelength(tmp_path):
    def edit(d, lens):
        d["surfaces"][1][material_spec.INDEX_RECORD] = [1.6]

    with pytest.raises(ValueError, match="surface 1: index_at_wavelengths must hold one index "
                                         "per wavelength"):
        jl.load(_tampered(tmp_path, edit))


def test_json_index_record_within_float32_rounding_is_accepted(tmp_path):
    def edit(d, lens):
        rec = d["surfaces"][1][material_spec.INDEX_RECORD]
        d["surfaces"][1][material_spec.INDEX_RECORD] = [v + 2e-7 for v in rec]

    jl.load(_tampered(tmp_path, edit))


def test_json_index_record_synonym_is_refused(tmp_path):
    def edit(d, lens):
        d["surfaces"][1]["n_at_wavelengths"] = d["surfaces"][1].pop(material_spec.INDEX_RECORD)

    with pytest.raises(ValueError, match="index_at_wavelengths"):
        jl.load(_tampered(tmp_path, edit))


NOTE = re.compile(r"^NOTE 0 jaxlens: the medium after SURF (\d+) \((.*)\) has n = (.*) at "
                  r"WAVM 1\.\.(\d+)$", re.M)


def test_zmx_notes_state_each_medium_index_the_units_and_the_stop(tmp_path):
    lens = _cooke()
    p = tmp_path / "c.zmx"
    jl.save(lens, p)
    text = p.read_text().replace("\r\n", "\n")
    found = NOTE.findall(text)
    media = [lens.object_material, *lens.materials]
    want = [k for k, m in enumerate(media) if not isinstance(m, Air)]
    assert [int(k) for k, *_ in found] == want
    for k, name, values, count in found:
        m = media[int(k)]
        assert name == m.name and int(count) == len(lens.wavelengths)
        np.testing.assert_array_equal([float(v) for v in values.split()], _indices(m, lens))
    assert f"the stop is SURF {lens.stop + 1}" in text and "lengths mm" in text
    assert "NOTE 0 Cooke triplet" in text  # the description, as a file note
    # Zemax's NAME and surfaces follow; the notes change nothing jaxlens reads back.
    back = jl.load(p, dtype="float64")
    assert back.description == ""  # .zmx has no field jaxlens reads it from
    _same(back, jl.load(os.path.join(LENSES, "cooke_triplet.zmx"), dtype="float64"))


def _tool():
    spec = importlib.util.spec_from_file_location("export_reevaluation", TOOL)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow  # 6-8 s (the tool's import, a JSON load and a Hybrid sag compiled)
def test_reevaluation_tool_reads_a_hybrid_surface_by_zemax_definitions(tmp_path):
    tool = _tool()
    # Zemax's Extended Polynomial order: x, y, x², xy, y², x³, x²y, xy², y³, …
    assert [tool.xpoly_powers(j) for j in range(1, 10)] == [
        (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3)]
    assert all(tool.xpoly_powers(j) == xy_term_powers(j) for j in range(1, 231))
    lens = jl.load(os.path.join(LENSES, "hybrid_singlet.json"), dtype="float64")
    i = next(i for i, s in enumerate(lens.surfaces) if isinstance(s, Hybrid))
    s = lens.surfaces[i]
    p = tmp_path / "h.zmx"
    jl.save(lens, p)
    text, own = tool.own_surfaces(p.read_text())
    assert list(own) == [i + 1] and own[i + 1]["type"] == "XPOLYNOM"
    assert "XPOLYNOM" not in text and "XDAT" not in text
    d = own[i + 1]
    n, r = int(d["xdat"][1]), d["xdat"][2]
    x, y = np.meshgrid(np.linspace(-0.7, 0.7, 9) * 2.0, np.linspace(-0.6, 0.8, 9) * 2.0)
    r2 = x**2 + y**2
    z = d["c"] * r2 / (1 + np.sqrt(1 - (1 + d["k"]) * d["c"] ** 2 * r2))
    for j in range(1, n + 1):
        a, b = tool.xpoly_powers(j)
        z = z + d["xdat"].get(j + 2, 0.0) * (x / r) ** a * (y / r) ** b
    sag, inside = s.sag(jnp.asarray(x), jnp.asarray(y))
    assert bool(np.all(inside))
    want = np.asarray(sag, np.float64)
    assert np.max(np.abs(want)) > 1e-3  # a real sag, with its odd terms
    np.testing.assert_allclose(z, want, rtol=0, atol=1e-13)
