"""Round-37a bad-input fixes (tools/audit37a_probe.py): an AGF record's Vd is checked against
its dispersion formula, the side catalogs ``save_zmx`` writes agree with that check, and
``glass_info`` checks a registered AGF record before answering."""

import json
import os

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.design import DesignSpec
from jaxlens.design.evaluate import sensor_field_grid
from jaxlens.design.losses import radial_area_weights
from jaxlens.io import zmx
from jaxlens.optics import catalog

# N-BK7's Sellmeier 1 coefficients: nd 1.5168, Vd 64.17.
AGF = """CC test catalog
NM TESTG 2 517642 1.5168 64.17 0 0 0
CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653
LD 0.3 2.5
"""


def _agf(tmp_path, text, name="T37.agf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_agf_vd_disagreeing_with_its_formula_is_refused_with_the_line(tmp_path):
    """Vd 54.17 on N-BK7's coefficients (64.17) was kept and went to glass_info, the
    nearest-glass suggestions and GLAS lines; nd was already checked."""
    path = _agf(tmp_path, AGF.replace("1.5168 64.17", "1.5168 54.17"))
    with pytest.raises(ValueError, match=r"T37\.agf:2: .*Vd 54\.17.*Vd = .*64\.1.*1%"):
        jl.load_agf(path)


@pytest.mark.parametrize("vd", ["64.3", "0"])
def test_agf_vd_within_tolerance_or_unknown_is_read(tmp_path, vd):
    path = _agf(tmp_path, AGF.replace("1.5168 64.17", f"1.5168 {vd}"))
    assert jl.load_agf(path)["TESTG"].catalog_vd == float(vd)


def test_agf_vd_not_checked_where_f_or_c_lies_outside_the_record_range(tmp_path):
    text = AGF.replace("1.5168 64.17", "1.5168 30").replace("LD 0.3 2.5", "LD 0.9 2.5")
    assert jl.load_agf(_agf(tmp_path, text))["TESTG"].catalog_vd == 30.0


def test_shipped_catalog_records_pass_the_vd_check():
    """The glasses of the shipped catalogs with the largest gaps (0.33 %, 0.31 %, 0.22 %)."""
    for name, cat in (("K-LaSFn21", "SUMITA"), ("K-VC91", "SUMITA"), ("330R", "PLASTICS")):
        assert jl.get_material(name, cat).catalog_vd > 0


def test_save_zmx_fitted_glass_record_agrees_with_its_formula(tmp_path):
    """A table glass is written as a Schott fit; its NM record carried the table's own Vd
    (65.78, linear in 1/λ² between 0.45, 0.55 and 0.65 µm) beside the fit's 64.0, which
    load_agf now refuses: the record gets the fit's nd and Vd."""
    bk7 = jl.get_material("N-BK7")
    wl = np.array([0.45, 0.55, 0.65])
    table = jl.Tabulated(wl, np.asarray(bk7.index(wl)), name="TAB")
    lens = jl.Lens(
        surfaces=(jl.Standard(c=0.02), jl.Standard(c=-0.02)),
        thickness=[3.0, 40.0],
        materials=(table, jl.Air()),
        epd=5.0,
        wavelengths=(0.47, 0.55, 0.63),
    )
    zmx.save_zmx(lens, tmp_path / "t.zmx")  # (jl.save also loads the file back: 4 s)
    (agf,) = [f for f in os.listdir(tmp_path) if f.upper().endswith(".AGF")]
    vd = jl.load_agf(tmp_path / agf)["TAB"].catalog_vd
    assert vd == pytest.approx(64.0, abs=0.1)
    text = zmx.decode((tmp_path / "t.zmx").read_bytes())
    glas = [ln.split() for ln in text.splitlines() if "GLAS TAB" in ln]
    assert glas and all(float(g[5]) == pytest.approx(vd, rel=1e-12) for g in glas)


def test_glass_info_checks_a_registered_agf_record(tmp_path, monkeypatch):
    """register_catalog reads records lazily: glass_info gave the record's Vd 40 unchecked."""
    monkeypatch.setattr(catalog, "_user_catalogs", [])
    path = _agf(tmp_path, AGF.replace("1.5168 64.17", "1.5168 40"), "R37T.agf")
    cat = jl.register_catalog(path)
    with pytest.raises(ValueError, match=r"R37T\.agf:2: .*Vd 40"):
        jl.glass_info("TESTG", cat)


@pytest.mark.parametrize("arg", ["half_x", "half_y", "decenter_x", "decenter_y"])
def test_aperture_refuses_a_number_given_as_a_string(arg):
    """Aperture("rect", "2", 1.0) was read as 2 mm, where every surface refuses a string."""
    values = {"half_x": 2.0, "half_y": 1.0, "decenter_x": 0.0, "decenter_y": 0.0, arg: "2"}
    with pytest.raises(
        ValueError,
        match=rf"Aperture: {arg} must be a finite number.*\(mm\), "
        r"got '2'",
    ):
        jl.Aperture("rect", **values)


def test_json_primary_wavelength_not_among_the_wavelengths_lists_them(tmp_path):
    cooke = os.path.join(os.path.dirname(jl.__file__), "data", "lenses", "cooke_triplet.json")
    with open(cooke) as f:
        d = json.load(f)
    d["primary_wavelength_nm"] = 550.0
    path = tmp_path / "t.json"
    path.write_text(json.dumps(d))
    with pytest.raises(
        ValueError,
        match=r"primary_wavelength_nm 550\.0 is not one of the "
        r"wavelengths \(\[486\.1327, 587\.5618, 656\.2725\] nm\)",
    ):
        jl.load(path)


def test_a_one_field_grid_is_the_sensor_centre():
    """n = 1 evaluated the sensor's corner alone (linspace(-1, 1, 1) is [-1])."""
    ang, pts = sensor_field_grid(DesignSpec(), 1)
    np.testing.assert_array_equal(pts, [[0.0, 0.0]])
    np.testing.assert_array_equal(ang, [[0.0, 0.0]])
    ang, pts = sensor_field_grid(DesignSpec(), 3)  # corner to corner, centre in the middle
    np.testing.assert_array_equal(pts[4], [0.0, 0.0])
    assert pts[0, 0] < 0 and pts[8, 0] == -pts[0, 0]


def test_one_field_area_weights_match_the_one_field_grid():
    """radial_area_weights counts the evaluation grid's fields per radial bin: for n = 1 its
    one field is the centre, as sensor_field_grid's."""
    w = radial_area_weights(np.array([0.0, 0.5, 1.0]), (4.0, 6.0), 1)
    np.testing.assert_array_equal(w, [1.0, 0.0, 0.0])
