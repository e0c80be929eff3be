"""Round 37d of the independent re-evaluation of exported designs: the 40 committed classical
designs (experiments/classical/designs*, Table 1's ``+recipe`` and ``+both+mask`` columns)
re-read by a second tracer, ray-optics 0.9.8 (``tools/rayoptics_reevaluation.py``, run with
/work/optenv's interpreter; its numbers are in tests/data/export_round37d_rayoptics.json),
from the files alone: the media from the NOTE index lines (ray-optics finds neither E48R nor
OKP4 and would put n = 1.5 there), the field grid, sensor, focal length and distortion angle
from the evaluation NOTE lines, everything else from the Zemax keywords.

* The NOTE gave the sensor's width and height to 6 significant digits (5.41644 mm for
  5.416437941…): a re-evaluation from the file moved every grid field by 4e-7 (relative).
  Written now to 10, as the focal length.
* The NOTE's vignetting rule said ">= 99 % of each field's rays"; ``design.evaluate`` takes
  the smallest fraction over the wavelengths (``min_valid_fraction``): it says so now.
* The committed designs carry the new notes (tools/reexport_designs.py: only NOTE lines
  change, the evaluation is unchanged).
"""

import json
import math
import pathlib
import re

import numpy as np
import pytest

from jaxlens.design.evaluate import sensor_field_grid
from jaxlens.design.spec import DesignSpec
from jaxlens.experiments import classical_export

ROOT = pathlib.Path(__file__).resolve().parents[1]
RAYOPTICS = ROOT / "tests" / "data" / "export_round37d_rayoptics.json"
TABLE1 = ROOT / "experiments" / "classical" / "table1.json"
COLUMN = {"designs": "+recipe", "designs_paper_method": "+both+mask"}
# The tool's own note parsing, so that what it read is what these tests read.
NOTE_GRID = re.compile(r"a (\d+) x (\d+) grid over the ([\d.eE+-]+) x ([\d.eE+-]+) mm sensor")
NOTE_F = re.compile(r"tan = sensor position / ([\d.eE+-]+) mm")


def _grid_from_notes(text: str) -> np.ndarray:
    g, f = NOTE_GRID.search(text), NOTE_F.search(text)
    n, w, h, fl = int(g.group(1)), float(g.group(3)), float(g.group(4)), float(f.group(1))
    u = np.linspace(-1, 1, n)
    x, y = np.meshgrid(u * w / 2, u * h / 2, indexing="xy")
    return np.degrees(np.arctan(np.stack([x.ravel(), y.ravel()], -1) / fl))


def test_notes_give_the_field_grid_to_1e9():
    """Main: a re-evaluation that builds the fields from the NOTE lines gets the run's grid
    (the sensor's size was written to 6 digits: 4e-7 relative off)."""
    spec = DesignSpec()
    want, _ = sensor_field_grid(spec)
    got = _grid_from_notes(classical_export.evaluation_notes(spec))
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=0)


def test_notes_name_the_vignetting_rule():
    notes = classical_export.evaluation_notes(DesignSpec())
    assert "at every WAVM" in notes and "smallest fraction over the wavelengths" in notes


@pytest.mark.parametrize("folder", sorted(COLUMN))
def test_committed_designs_carry_the_notes(folder):
    """Every committed design's NOTE lines are today's notes (re-exported in place)."""
    notes = classical_export.evaluation_notes(DesignSpec(), 16).splitlines()
    paths = sorted((ROOT / "experiments" / "classical" / folder).glob("seed_*.zmx"))
    assert len(paths) == 20
    for p in paths:
        lines = [
            ln[len("NOTE 0 ") :]
            for ln in p.read_text().splitlines()
            if ln.startswith("NOTE 0 ") and not ln.startswith("NOTE 0 jaxlens:")
        ]
        assert lines == notes, p.name


def _rayoptics():
    return json.loads(RAYOPTICS.read_text())["designs"]


def _claims(design: str) -> dict:
    folder, name = design.split("/")
    seed = int(name.split("_")[1].split(".")[0])
    col = json.loads(TABLE1.read_text())["columns"][COLUMN[folder]]
    (rec,) = [r for r in col["per_seed"] if r["seed"] == seed]
    return rec


def test_rayoptics_reproduces_the_claims_of_all_40():
    """ray-optics, from the files alone, reproduces table1.json's per-seed EFL, F/#, BFL,
    FoV, full-field chief-ray height and distortion of all 40 committed designs, and the
    grid's mean and largest RMS and its vignetting where it traced the whole grid."""
    recs = _rayoptics()
    assert len(recs) == 40
    spec = DesignSpec()
    for r in recs:
        c = _claims(r["design"])
        assert r["glass_not_found"] == 6  # ray-optics's own media: n = 1.5 (not used)
        for k in ("efl", "fnum", "bfl"):
            assert math.isclose(r[k], c[k], rel_tol=1e-9), (r["design"], k, r[k], c[k])
        assert math.isclose(r["fov"], spec.fov, rel_tol=1e-12)
        # The claims are of the lens the run evaluated before it wrote the file: its chief
        # ray at 40.4° lands up to 1.3e-7 mm (3.2e-8 relative) from the file's, where
        # ray-optics and jaxlens's re-read of the file agree to 1e-13.
        assert math.isclose(
            r["chief_height_full_field"], c["chief_height_full_field"], rel_tol=1e-7
        ), r["design"]
        assert abs(r["distortion_percent"] - c["distortion_percent"]) < 1e-5, r["design"]
        if "rms_mean_um" in r:
            assert math.isclose(r["rms_mean_um"], c["rms_mean_um"], rel_tol=1e-5), r["design"]
            assert math.isclose(r["rms_max_um"], c["rms_max_um"], rel_tol=1e-5), r["design"]
            assert r["min_valid_fraction"] == c["min_valid_fraction"]
            assert r["rays_ok"] == c["rays_ok"]


@pytest.mark.slow
def test_rayoptics_matches_jaxlens_reread_per_field():
    """Per file field (YFLN), ray-optics's pooled RMS and vignetting equal jaxlens's re-read
    of the same file (``analysis.rms_spot``), and the full-field chief ray
    (``spots.chief_ray``) to 1e-9 mm, all 40 designs."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    import jaxlens as jl

    for r in _rayoptics():
        lens = jl.load(ROOT / "experiments" / "classical" / r["design"]).astype(jnp.float64)
        chief = jl.analysis.spots.chief_ray(lens, r["yfln_deg"][-1])
        assert abs(float(chief.origin[1]) - r["chief_height_full_field"]) < 1e-9, r["design"]
        res = jl.analysis.rms_spot(lens, jnp.asarray(r["yfln_deg"]))
        np.testing.assert_allclose(
            np.asarray(res.polychromatic) * 1e3, r["yfln_rms_um"], rtol=1e-5, err_msg=r["design"]
        )
        np.testing.assert_array_equal(
            np.min(np.asarray(res.valid_fraction), -1),
            r["yfln_min_valid_fraction"],
            err_msg=r["design"],
        )


def _tabulated_lens(wavelengths):
    import jax.numpy as jnp

    import jaxlens as jl

    wl = np.array([0.40, 0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.8])
    n = 1.5 + 0.004 / wl**2 + 0.0003 * np.sin(7 * wl)  # a measured-looking table, 8 points
    tab = jl.Tabulated(jnp.asarray(wl), jnp.asarray(n))
    lens = jl.Lens(
        surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
        thickness=jnp.array([6.0, 33.4]),
        materials=(tab, jl.Air()),
        epd=10.0,
        fields=jnp.array([0.0, 10.0]),
        wavelengths=jnp.asarray(wavelengths),
    )
    return lens, tab


def _agf_schott_index(folder: pathlib.Path, wl: np.ndarray) -> np.ndarray:
    """The index Zemax computes from the side AGF's Schott formula (formula 1)."""
    (agf,) = folder.glob("*.AGF")
    (nm,) = [ln.split() for ln in agf.read_text().splitlines() if ln.startswith("NM ")]
    assert nm[2] == "1"
    (cd,) = [ln.split()[1:] for ln in agf.read_text().splitlines() if ln.startswith("CD ")]
    a0, a1, a2, a3, a4, a5 = (float(v) for v in cd)
    return np.sqrt(a0 + a1 * wl**2 + a2 * wl**-2 + a3 * wl**-4 + a4 * wl**-6 + a5 * wl**-8)


def test_tabulated_glass_is_exact_for_zemax_at_the_files_wavelengths(tmp_path):
    """Main: a Tabulated glass of more than 6 points went into the side AGF as a least-squares
    Schott fit of its table, 2.7e-6 off its own index at the file's F, d, C (jaxlens read it
    back exactly from the GC record, Zemax traced the fit): now exact at the file's
    wavelengths."""
    import jaxlens as jl

    wl = np.array([0.4861327, 0.5875618, 0.6562725])
    lens, tab = _tabulated_lens(wl)
    jl.save(lens, tmp_path / "t.zmx")
    want = np.asarray(tab.index(wl))
    np.testing.assert_allclose(_agf_schott_index(tmp_path, wl), want, rtol=0, atol=1e-12)
    back = jl.load(tmp_path / "t.zmx")
    np.testing.assert_allclose(np.asarray(back.materials[0].index(wl)), want, rtol=0, atol=0)


def test_tabulated_glass_at_more_than_6_wavelengths_warns(tmp_path):
    """Seven wavelengths: no 6-term Schott formula holds the table exactly there; the
    writer says how far off Zemax's index is."""
    import jaxlens as jl
    from jaxlens.io.zmx_common import ZmxWarning

    wl = np.array([0.42, 0.46, 0.5, 0.55, 0.6, 0.66, 0.75])
    lens, _ = _tabulated_lens(wl)
    with pytest.warns(ZmxWarning, match=r"glass .* \(Tabulated\) has no Zemax formula.* off"):
        jl.save(lens, tmp_path / "t.zmx")
