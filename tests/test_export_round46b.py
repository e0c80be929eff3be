"""Round 46b of the independent re-evaluation of exported designs, after the library changes
of rounds 43c-45c (one system-aperture rule: the PSF/MTF beam and the relative illumination's
are the unit pupil; the PSF's default overfill 1; FTYP 3 and FLOA+RAIM 2 on reading).

The files: a ``--smoke`` run's export (``python -m jaxlens.experiments.classical --smoke
--out /tmp/e46b/smoke --overwrite --devices 1``; its lens.zmx, lens.json, PLASTICS.AGF and
summary.json are in tests/data/export46b/smoke/) and the two committed designs README names
(experiments/classical/designs/seed_13.zmx, Table 1's best, 4.67 µm; designs_paper_method/
seed_9.zmx, 5.31 µm). ``tools/export46b_reference.py`` (optiland 0.6.3 and ray-optics 0.9.8,
from the ``.zmx`` alone, the media from its NOTE lines) wrote
tests/data/export46b/export46b_reference.json; its docstring gives every definition.

What was measured (the tolerances below are these figures with a margin):

* both readers open the exports without a warning about the file (ray-optics: only pandas'
  deprecation warnings of its own glass catalogs, and E48R/OKP4 not found, which the NOTE
  media replace); jaxlens reads .zmx and .json without a warning;
* lens.json reloads bit for bit (re-saved byte-identical; every array equal to the .zmx's);
* paraxial EFL, F/#, BFL, total track and the pupils' positions: 7e-16 relative to both
  readers (the exit pupil 9e-16 mm);
* every number of the smoke run's summary.json from the file alone: EFL, F/#, BFL, track
  4.4e-16 relative; the full-field chief ray 1.8e-15 mm and its distortion 3.6e-14 points;
  the 4 x 4 grid's RMS per field 4.7e-11 relative to ray-optics (its mean, largest,
  smallest and median 2.5e-11, 9.9e-12, 1.4e-12, 4.7e-11), the on-axis RMS 4.4e-16
  (ray-optics) and 4.8e-15 (optiland);
* per field (0, 0.5, 0.7, 0.85, 1 of the half-diagonal), all three files, against optiland:
  chief ray 1.7e-14 mm, distortion 6.5e-13 points, chief-ray angle after the last surface
  3.6e-13 deg, RMS 7.1e-13 relative; the geometric MTF (no diffraction, 10-100 cycles/mm)
  on jaxlens's default geometric-PSF pupil cells (64, overfill 1) 1.5e-12; the relative
  illumination (two methods: round 43c's ring-spoke irradiance from optiland's rays against
  jaxlens's pupil polygon) 1.5e-5, 4.8e-6, 5.7e-7 (smoke, seed 13, seed 9) at 256 cells
  (at the default 128: 2.2e-4, seed 13's corner field, a sampling error 256 cells remove);
* the committed designs' Table 1 RMS (16 x 16 grid, ray-optics): seed 13 4.668217 µm,
  paper seed 9 5.307858 µm, README's 4.67 and 5.31, table1.json's per-seed values within
  1.5e-6 (the export's conic rebase, README: within 0.0013 %).

An optiland Newton tolerance: its ``.zmx`` reader gives each asphere a 1e-6 mm residual
tolerance, which moved the smoke lens's chief ray by up to 2.3e-7 mm (and RMS by 8e-8
relative) from jaxlens's and ray-optics's (which agreed to 1e-15 mm); the tool tightens it.
"""

from __future__ import annotations

import json
import math
import pathlib
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.analysis import report, spots
from jaxlens.imaging import psf, radiometry
from jaxlens.optics import paraxial

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "export46b"
REF = json.loads((DATA / "export46b_reference.json").read_text())
FILES = {r["file"]: r for r in REF["files"]}
SMOKE = "tests/data/export46b/smoke/lens.zmx"
COMMITTED = [f for f in FILES if f != SMOKE]
# relative_illumination's pupil cells: its default 128 left 2.2e-4 of sampling error at seed
# 13's corner field (0.99972; 256: 0.999948, optiland 0.999943; 64: 1.00102)
RI_PUPIL = 256


def _load(rel: str):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return jaxlens.load(str(ROOT / rel))


def test_readers_open_the_exports_without_warnings():
    """optiland says nothing about any file; ray-optics only pandas deprecations (its own
    glass tables) and the two plastics it lacks; jaxlens reads .zmx and .json silently."""
    for rel, r in FILES.items():
        assert r["optiland_open"]["messages"] == [], rel
        assert all(m.startswith("Pandas4Warning") for m in r["rayoptics_open"]["messages"]), rel
        assert r["rayoptics_open"]["info"]["glass not found"] == 6, rel  # E48R, OKP4 x 3
        _load(rel)
    _load(SMOKE.replace(".zmx", ".json"))


def test_json_export_reloads_bit_for_bit(tmp_path):
    lj = _load(SMOKE.replace(".zmx", ".json"))
    lz = _load(SMOKE)
    a, b = jax.tree_util.tree_leaves(lj), jax.tree_util.tree_leaves(lz)
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(np.asarray(x), np.asarray(y))
    jaxlens.save(lj, str(tmp_path / "again.json"))
    want = (ROOT / SMOKE).with_suffix(".json").read_bytes()
    assert (tmp_path / "again.json").read_bytes() == want
    jaxlens.save(lj, str(tmp_path / "again.zmx"))  # the JSON keeps the run's notes
    assert (tmp_path / "again.zmx").read_text() == (ROOT / SMOKE).read_text()


@pytest.mark.parametrize("rel", sorted(FILES))
def test_paraxial_data_against_both_readers(rel):
    lens = _load(rel)
    pd = paraxial.paraxial_data(lens)
    r = FILES[rel]
    ol, ro = r["optiland"]["paraxial"], r["rayoptics"]
    got = {"efl": pd.efl_image_space, "fnum": pd.fnum, "bfl": pd.bfl,
           "total_track": pd.total_track}
    for k, v in got.items():
        np.testing.assert_allclose(float(v), ol[k], rtol=1e-13, err_msg=f"{rel} {k} optiland")
        if k in ro:
            np.testing.assert_allclose(float(v), ro[k], rtol=1e-13, err_msg=f"{rel} {k} rayoptics")
    np.testing.assert_allclose(float(pd.entrance_pupil_z), ol["entrance_pupil_z"], atol=1e-12)
    np.testing.assert_allclose(float(pd.entrance_pupil_z), ro["entrance_pupil_z"], atol=1e-12)
    xp = float(pd.exit_pupil_z - pd.image_z)
    np.testing.assert_allclose(xp, ol["exit_pupil_from_image"], atol=1e-12)
    # ray-optics gives the exit pupil from the last surface, its image from the same
    np.testing.assert_allclose(xp, ro["exit_pupil_from_image"] - ro["img_dist"], atol=1e-8)


def test_smoke_summary_numbers_from_the_file_alone():
    """Every number summary.json gives for the best design, from lens.zmx by both tracers."""
    best = json.loads((DATA / "smoke" / "summary.json").read_text())["best"]
    r = FILES[SMOKE]
    ol, ro = r["optiland"], r["rayoptics"]
    for k in ("efl", "fnum", "bfl", "total_track"):
        np.testing.assert_allclose(best[k], ol["paraxial"][k], rtol=1e-13, err_msg=k)
    np.testing.assert_allclose(best["chief_height_full_field"], ro["chief_height_full_field"],
                               rtol=1e-13)
    np.testing.assert_allclose(best["chief_height_full_field"], ol["fields"][-1]["chief_y"],
                               rtol=1e-13)
    np.testing.assert_allclose(best["distortion_percent"], ro["distortion_percent"], atol=1e-11)
    np.testing.assert_allclose(best["distortion_percent"],
                               ol["fields"][-1]["distortion_percent"], atol=1e-11)
    grid = np.asarray(ro["grid_rms_um"])
    np.testing.assert_allclose(best["rms_um_per_field"], grid, rtol=1e-9)
    for k, v in (("rms_mean_um", grid.mean()), ("rms_max_um", grid.max()),
                 ("rms_min_um", grid.min()), ("rms_median_um", np.median(grid))):
        np.testing.assert_allclose(best[k], v, rtol=1e-9, err_msg=k)
    np.testing.assert_allclose(best["rms_on_axis_um"], ro["yfln_rms_um"][0], rtol=1e-9)
    np.testing.assert_allclose(best["rms_on_axis_um"], ol["fields"][0]["rms_um"], rtol=1e-9)
    assert best["valid"] and ro["rays_ok"]
    assert best["min_valid_fraction"] == ro["min_valid_fraction"]


def test_committed_claims_from_the_files_alone():
    """README's Table 1 figures of the two bests (4.67 and 5.31 µm), table1.json's per-seed
    RMS and validity, re-evaluated by ray-optics on the whole 16 x 16 grid."""
    table = json.loads((ROOT / "experiments" / "classical" / "table1.json").read_text())
    claims = {"experiments/classical/designs/seed_13.zmx": ("+recipe", 13, 4.67),
              "experiments/classical/designs_paper_method/seed_9.zmx": ("+both+mask", 9, 5.31)}
    for rel, (col, seed, readme) in claims.items():
        ro = FILES[rel]["rayoptics"]
        per = {s["seed"]: s for s in table["columns"][col]["per_seed"]}[seed]
        # the table holds the designs before the conic rebase of the export (README: 0.0013 %)
        np.testing.assert_allclose(per["rms_mean_um"], ro["rms_mean_um"], rtol=1.3e-5, err_msg=rel)
        assert round(ro["rms_mean_um"], 2) == readme
        assert per["valid"] and ro["rays_ok"]


def _per_field(rel):
    lens = _load(rel)
    r = FILES[rel]["optiland"]
    th = np.array([f["theta_deg"] for f in r["fields"]])
    d = report.report_data(lens, fields=th)
    wl = lens.wavelengths[lens.primary]
    cra = []
    for t in th:
        ray = spots.spot_rays(lens, float(t), wl, pupil=jnp.zeros((1, 2)))
        u = np.asarray(ray.direction)[0]
        cra.append(math.degrees(math.atan2(u[1], u[2])))
    mtf = [psf.mtf(lens, (0.0, float(t)), frequencies=REF["mtf_freqs"],
                   model=psf.GeometricPSF(pupil=REF["mtf_cells"], overfill=REF["mtf_overfill"]),
                   diffraction=False)[1:] for t in th]
    return r, d, cra, mtf


def _check_per_field(rel):
    r, d, cra, mtf = _per_field(rel)
    assert REF["mtf_overfill"] == psf.DEFAULT_OVERFILL  # the grid a default MTF uses
    for f, df, c, (t, s) in zip(r["fields"], d["fields"], cra, mtf, strict=True):
        what = f"{rel} at {f['theta_deg']:.3f} deg"
        np.testing.assert_allclose(df["chief_ray_height"], f["chief_y"], atol=1e-12, err_msg=what)
        np.testing.assert_allclose(df["distortion"], f["distortion_percent"], atol=1e-11,
                                   err_msg=what)
        np.testing.assert_allclose(c, f["cra_deg"], atol=1e-11, err_msg=what)
        np.testing.assert_allclose(df["rms_spot_polychromatic"], f["rms_um"], rtol=1e-10,
                                   err_msg=what)
        np.testing.assert_allclose(np.asarray(t), f["mtf"]["tangential"], atol=1e-10, err_msg=what)
        np.testing.assert_allclose(np.asarray(s), f["mtf"]["sagittal"], atol=1e-10, err_msg=what)


def test_smoke_per_field_against_optiland():
    _check_per_field(SMOKE)


@pytest.mark.slow
@pytest.mark.parametrize("rel", COMMITTED)
def test_committed_per_field_against_optiland(rel):
    _check_per_field(rel)


@pytest.mark.slow  # about 30 s of CPU a lens at 256 cells
@pytest.mark.parametrize("rel", sorted(FILES))
def test_relative_illumination_against_optiland(rel):
    """The irradiance of the beam the unit pupil admits (round 43c), normalised on the axis."""
    fields = FILES[rel]["optiland"]["fields"]
    th = np.array([f["theta_deg"] for f in fields])
    ri = np.asarray(radiometry.relative_illumination(_load(rel), th, pupil=RI_PUPIL).ri)
    want = [f["relative_illumination"] for f in fields]
    np.testing.assert_allclose(ri, want, atol=3e-5, err_msg=rel)


@pytest.mark.slow  # 36 fields' MTF, about 30 s of CPU
def test_tolerance_record_mtf_against_today_psf_mtf():
    """README: tolerance.json's nominal MTF at the sensor's Nyquist frequency (tolerance's own
    spot-data MTF) is within 0.008 of ``psf.mtf`` on the design. Measured with today's MTF
    (overfill 1, the unit pupil's beam): 0.57444 against the record's 0.57406 (0.57438 at the
    former overfill 1.25): the record still holds."""
    from jaxlens.design.evaluate import sensor_field_grid
    from jaxlens.design.spec import DesignSpec

    rec = json.loads((ROOT / "experiments" / "classical" / "tolerance.json").read_text())
    mc = rec["monte_carlo"]
    lens = _load(rec["design"])
    fields = np.asarray(sensor_field_grid(DesignSpec(), 16)[0])
    folded = {}
    for fx, fy in fields:  # the 8-fold symmetric grid: |x|, |y| sorted
        key = tuple(sorted((round(abs(fx), 9), round(abs(fy), 9))))
        folded[key] = folded.get(key, 0) + 1
    nu = mc["mtf_frequency_cycles_per_mm"]
    got = 0.0
    for (a, b), m in folded.items():
        _, t, s = psf.mtf(lens, (a, b), frequencies=[nu])
        got += m * 0.5 * (float(t[0]) + float(s[0]))
    got /= len(fields)
    assert abs(got - mc["mtf_nominal"]) < 0.008
