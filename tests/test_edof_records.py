"""The committed EDoF records (experiments/edof/**) agree with their own per-crop values.

Each record folder holds table2.json (issue 10's schema), table2_per_image.json (every crop's
PSNR/SSIM per seed, lens and depth) and summary.json (the bar checks). A table edited by hand,
or re-made from other runs than its per-crop file, fails here. JSON only: no training.
"""

import json
import pathlib

import numpy as np
import pytest

EDOF = pathlib.Path(__file__).resolve().parents[1] / "experiments" / "edof"
RECORDS = sorted(p.parent for p in EDOF.rglob("table2_per_image.json"))
DEPTHS = ("0.1", "0.2", "10")


def _load(folder):
    return (json.loads((folder / "table2.json").read_text()),
            json.loads((folder / "table2_per_image.json").read_text()))


def _crop_mean(per, seeds, lens, depth, kind, metric):
    """Mean over seeds of the mean over crops (how the tables average)."""
    return float(np.mean([np.mean(per["values"][s][lens][depth][kind][metric]) for s in seeds]))


def test_records_are_found():
    # The main CPU record, the paper-scale H200 records and the merged table at least.
    names = {str(r.relative_to(EDOF)) for r in RECORDS}
    assert {".", "gpu_h200/merged", "gpu_h200/seed0_steps1600"} <= names


@pytest.mark.parametrize("folder", RECORDS, ids=lambda p: str(p.relative_to(EDOF)))
def test_table_follows_the_issue_schema(folder):
    table, per = _load(folder)
    assert {"seeds", "test", "base_lens", "lenses", "gain_vs_classical",
            "light_on_sensor"} <= set(table)
    assert {"crops", "images", "source"} <= set(table["test"])
    assert set(table["base_lens"]) >= {"efl_mm", "fov_deg", "fnum", "image_diagonal_mm",
                                       "elements"}
    assert "classical" in table["lenses"]
    for rows in table["lenses"].values():
        assert set(rows) == set(DEPTHS)
    for lens, frac in table["light_on_sensor"].items():
        assert 0.0 < frac <= 1.0 + 1e-6, (lens, frac)
    assert sorted(per["values"]) == sorted(str(s) for s in table["seeds"])
    assert len(per["crops"]) == table["test"]["crops"]


@pytest.mark.parametrize("folder", RECORDS, ids=lambda p: str(p.relative_to(EDOF)))
def test_table_means_are_the_per_crop_means(folder):
    table, per = _load(folder)
    seeds = [str(s) for s in table["seeds"]]
    for lens, rows in table["lenses"].items():
        base = lens.removeprefix("wiener_")
        for depth, row in rows.items():
            for kind in ("sim", "rec"):
                # A wiener_<lens> row's "rec" is that lens's Wiener reconstruction.
                src = "wiener" if lens.startswith("wiener_") and kind == "rec" else kind
                for metric in ("psnr", "ssim"):
                    want = _crop_mean(per, seeds, base, depth, src, metric)
                    assert row[kind][metric] == pytest.approx(want, abs=1e-9), \
                        (lens, depth, kind, metric)


@pytest.mark.parametrize("folder", RECORDS, ids=lambda p: str(p.relative_to(EDOF)))
def test_gains_are_paired_crop_differences_and_checks_follow_them(folder):
    table, per = _load(folder)
    seeds = [str(s) for s in table["seeds"]]
    for lens, rows in table["gain_vs_classical"].items():
        for depth, gain in rows.items():
            diff = [np.mean(np.subtract(per["values"][s][lens][depth]["rec"]["psnr"],
                                        per["values"][s]["classical"][depth]["rec"]["psnr"]))
                    for s in seeds]
            assert gain["mean"] == pytest.approx(float(np.mean(diff)), abs=1e-9), (lens, depth)
            lo, hi = gain["ci95"]
            assert lo <= gain["mean"] <= hi, (lens, depth)
    summary = json.loads((folder / "summary.json").read_text())
    checks = summary["checks"]
    if "hybrid" in table["gain_vs_classical"]:
        hyb = table["gain_vs_classical"]["hybrid"]
        for depth in DEPTHS:
            assert checks["hybrid_gain_db"][depth] == pytest.approx(hyb[depth]["mean"], abs=1e-9)
        assert checks["beats_by_1db_at_10m_ci_above_0"] == (
            hyb["10"]["mean"] >= 1.0 and hyb["10"]["ci95"][0] > 0)
        assert checks["beats_by_1db_at_0.1m_ci_above_0"] == (
            hyb["0.1"]["mean"] >= 1.0 and hyb["0.1"]["ci95"][0] > 0)
    classical = table["lenses"]["classical"]
    for depth in DEPTHS:
        want = classical[depth]["rec"]["psnr"] - classical[depth]["sim"]["psnr"]
        assert checks["classical_rec_minus_sim_db"][depth] == pytest.approx(want, abs=1e-9)
    assert checks["classical_deblurs_3db_at_0.1m"] == (
        checks["classical_rec_minus_sim_db"]["0.1"] >= 3.0)
