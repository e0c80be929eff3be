"""Round 40a (real lens files): molded glasses of Zemax's RPO catalog, and the GCAT order
jaxlens writes.

* ``GLAS L-TIM28_MOLD`` with ``GCAT … RPO …`` (the ray-optics test file US08427765-1, a
  patent's f/2.1 lens) was refused as an unknown glass: RPO, Zemax's catalog of Rochester
  Precision Optics molded glasses (``<glass>_MOLD``: the maker's glass with its index after
  molding) and Vitron's IG chalcogenides, was not shipped. It is now
  (``jaxlens/data/glass/RPO.agf``, 43 records, from Zemax's rpo.agf as the public repository
  nzhagen/zemaxglass holds it), searched last so that no older name changes meaning.
* Writing that lens showed a writer bug of its own: GCAT listed the Zemax catalogs in the
  order the lens first used them (HIKARI for J-LAK14, then SCHOTT for SF11), and Zemax and
  the reader take a name from the first GCAT catalog holding it: SF11 came back as HIKARI's
  SF11. The writer now orders GCAT so that every glass written by name is read back from its
  own catalog.

References: tests/data/zmx40a_optiland.json, written by ``tools/zmx40a_reference.py``
(optiland 0.6.3's paraxial EFL and real rays, every medium set to the index the script
computes from the catalog's dispersion formula in numpy).
"""

import json
import os
import warnings

import jax
import numpy as np
import pytest
from helpers import image_xy, load_recording

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.catalog import get_material, glass_info

jax.config.update("jax_enable_x64", True)

HERE = os.path.dirname(__file__)
DATA = os.path.join(HERE, "data")
with open(os.path.join(DATA, "zmx40a_optiland.json")) as fh:
    REF = json.load(fh)
FILES = {"rpo_molded_cooke.zmx": os.path.join(DATA, "zmx40a", "rpo_molded_cooke.zmx"),
         "rpo_ig_doublet.zmx": os.path.join(DATA, "zmx40a", "rpo_ig_doublet.zmx"),
         "rayoptics_US08427765-1.ZMX": os.path.join(DATA, "zmx", "rayoptics_US08427765-1.ZMX")}


def _load(path, **kw):
    lens, caught = load_recording(path, **kw)
    return lens, [str(w.message) for w in caught if issubclass(w.category, zmx.ZmxWarning)]


def _image_xy(lens, ref, wl):
    """jaxlens's image intercepts (x, y) of the reference's rays (NaN where lost)."""
    return image_xy(lens, ref["fields_deg"], ref["epd"], REF["pupil"],
                    REF["launch_mm_before_surface_1"], wl)


@pytest.mark.parametrize("name", sorted(FILES))
def test_rpo_files_trace_as_optiland_does(name):
    lens, caught = _load(FILES[name])
    assert caught == []
    ref = REF["files"][name]
    assert float(lens.image_z()) == pytest.approx(ref["image_z_from_surface_1"], abs=1e-12)
    for wl in ref["wavelengths"]:
        key = repr(float(wl))
        # The same media (the reference computed them from the catalog's formula).
        n = [abs(float(v)) for v in lens.indices(wl)][1:]
        np.testing.assert_allclose(n, ref["indices"][key], rtol=2e-15, atol=0)
        efl = float(jl.paraxial_data(lens, wl).efl_image_space)
        assert efl == pytest.approx(ref["efl"][key], rel=1e-12)
        ours = _image_xy(lens, ref, wl)
        for got, want in zip(ours, ref["rays"][key], strict=True):
            want = np.array([[np.nan, np.nan] if w is None else w for w in want])
            assert np.array_equal(np.isnan(got[:, 0]), np.isnan(want[:, 0]))
            np.testing.assert_allclose(got, want, atol=1e-12, rtol=0)


def test_the_real_file_reads_each_glass_from_its_gcat_catalog():
    """US08427765-1: GCAT SCHOTT HIKARI RPO HOYA; SF11 is SCHOTT's (HIKARI has one too)."""
    lens, _ = _load(FILES["rayoptics_US08427765-1.ZMX"])
    got = {m.name: m.catalog for m in lens.materials if not isinstance(m, jl.Air)}
    assert got == REF["files"]["rayoptics_US08427765-1.ZMX"]["glasses"]
    molded = next(m for m in lens.materials if getattr(m, "name", "") == "L-TIM28_MOLD")
    # RPO's molded L-TIM28: its index after molding, 0.0054 below OHARA's L-TIM28.
    assert (molded.catalog_nd, molded.catalog_vd) == (1.684030, 30.856565)
    assert glass_info("L-TIM28")[:2] == ("OHARA", 1.689479)


def test_rpo_keeps_older_names_and_is_searched_last():
    # D-LAK70 is also CDGM's: a lookup without a catalog still finds CDGM's first.
    assert glass_info("D-LAK70")[0] == "CDGM"
    assert get_material("D-LAK70", catalogs="RPO").catalog_nd == 1.669104
    # Vitron's IG glasses carry Zemax's "no d-line data" (nd 1, Vd 0), data at 3-12 µm.
    ig6 = get_material("IG6")
    assert (ig6.catalog, ig6.catalog_nd, ig6.wavelength_range) == ("RPO", 1.0, (3.0, 12.0))
    # As2Se3 (IG6) at 10 µm: 2.7775 in the catalog's fit (Vitron's data sheet: 2.7775).
    assert float(ig6.index(10.0)) == pytest.approx(2.7776, abs=2e-4)


def test_a_molded_name_outside_rpo_is_still_refused_with_the_note():
    with open(FILES["rpo_molded_cooke.zmx"]) as fh:
        cooke = fh.read()
    text = cooke.replace("GLAS N-BK7_MOLD", "GLAS S-LAH64_MOLD")
    with pytest.raises(ValueError, match=r"S-LAH64_MOLD is S-LAH64 as a molded lens .*OHARA "
                                         r"S-LAH64, but a molded glass's index differs"):
        zmx.loads(text)
    # Without RPO in GCAT the molded glass is still found, in the shipped RPO, and reported.
    with pytest.warns(zmx.ZmxWarning, match=r"is not in the file's catalogs \(SCHOTT\); using "
                                            r"RPO (TAF3|L-TIM28|N-BK7)_MOLD"):
        lens = zmx.loads(cooke.replace("GCAT RPO", "GCAT SCHOTT"))
    assert {m.catalog for m in lens.materials if not isinstance(m, jl.Air)} == {"RPO"}


def test_round_trip_of_the_real_file_keeps_every_catalog(tmp_path):
    lens, _ = _load(FILES["rayoptics_US08427765-1.ZMX"])
    out = tmp_path / "w.zmx"
    jl.save(lens, out)
    gcat = next(ln.split()[1:] for ln in out.read_text().splitlines() if ln.startswith("GCAT"))
    assert gcat.index("SCHOTT") < gcat.index("HIKARI")  # SF11 must be read from SCHOTT
    again, caught = _load(out)
    assert caught == []
    for a, b in zip(jax.tree_util.tree_leaves(lens), jax.tree_util.tree_leaves(again), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert [getattr(m, "catalog", "") for m in again.materials] == \
        [getattr(m, "catalog", "") for m in lens.materials]


def _pair(first: str, second: str) -> str:
    """A two-glass lens as text: ``first`` then ``second`` (``name`` with GCAT SCHOTT HIKARI)."""
    return "\n".join([
        "UNIT MM", "ENPD 10", "GCAT SCHOTT HIKARI", "WAVM 1 0.5875618 1",
        "SURF 0", "  DISZ INFINITY", "SURF 1", "  STOP", "  CURV 0.02", "  DISZ 4",
        f"  GLAS {first}", "SURF 2", "  CURV -0.01", "  DISZ 2", "SURF 3", "  CURV 0.01",
        "  DISZ 3", f"  GLAS {second}", "SURF 4", "  CURV -0.005", "  DISZ 90", "SURF 5",
        "  DISZ 0"]) + "\n"


def test_gcat_puts_a_glass_catalog_before_others_holding_its_name(tmp_path):
    """J-LAK14 (HIKARI's only) first, then SF11 (SCHOTT's, and a name HIKARI has too): the
    file used to say GCAT HIKARI SCHOTT, and SF11 came back as HIKARI's."""
    lens = zmx.loads(_pair("J-LAK14", "SF11"))
    assert [m.catalog for m in lens.materials if not isinstance(m, jl.Air)] == ["HIKARI",
                                                                                 "SCHOTT"]
    text = zmx.dumps(lens)[0]
    assert "GCAT SCHOTT HIKARI" in text
    again = zmx.loads(text)
    assert [getattr(m, "catalog", "") for m in again.materials] == \
        [getattr(m, "catalog", "") for m in lens.materials]
    # Where no name is shared, the lens's own order stays (HIKARI first).
    assert "GCAT HIKARI SCHOTT" in zmx.dumps(zmx.loads(_pair("J-LAK14", "N-BK7")))[0]


def test_arton_polymers_read_by_name_and_written_back():
    """Zemax's ARTON catalog (JSR cyclo-olefin polymers of molded lenses) is shipped too: a
    GCAT ARTON file's DX4900 opens (nd 1.530803 from its Schott formula) and is written by name."""
    text = _pair("DX4900", "N-BK7").replace("GCAT SCHOTT HIKARI", "GCAT ARTON SCHOTT")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no report: both glasses are in the file's catalogs
        lens = zmx.loads(text)
    m = lens.materials[0]
    assert (m.catalog, m.name, m.catalog_nd) == ("ARTON", "DX4900", 1.530803)
    assert float(m.index(0.5875618)) == pytest.approx(1.530803, abs=1e-6)
    written = zmx.dumps(lens)[0]
    assert "GCAT ARTON SCHOTT" in written and "GLAS DX4900 0 0 1.530803" in written
    assert zmx.loads(written).materials[0].catalog == "ARTON"
