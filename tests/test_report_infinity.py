"""A report's first-order values at infinity: the string "inf"/"-inf" in the JSON and
"Infinity" in the text, not null and "failed" (which say that a computation failed).

The lens: a thick singlet with its stop in its front focal plane, so the exit pupil lies at
infinity (image-space telecentric) while everything else is finite (round 46a's lens).
"""

from __future__ import annotations

import json
import math

import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.analysis.report_cells import cell, json_extent

GLASS = jl.ModelGlass(1.5, 64.0)
N, R1, R2, T = 1.5, 60.0, -40.0, 8.0
PHI = (N - 1) * (1 / R1 - 1 / R2) + (N - 1) ** 2 * T / (N * R1 * R2)
F = 1 / PHI
BFD = F * (1 - (N - 1) * T / (N * R1))
FFD = F * (1 + (N - 1) * T / (N * R2))


def _xp_at_infinity():
    surfaces = (jl.Plane(semi_diameter=20.0), jl.Sphere(1 / R1, semi_diameter=15.0),
                jl.Sphere(1 / R2, semi_diameter=15.0))
    return jl.Lens(surfaces=surfaces, thickness=jnp.array([FFD, T, BFD]),
                   materials=(jl.Air(), GLASS, jl.Air()), stop=0, epd=4.0,
                   object_distance=None, fields=(0.0, 1.0))


def test_json_extent():
    assert json_extent(math.inf) == "inf" and json_extent(-math.inf) == "-inf"
    assert json_extent(math.nan) is None and json_extent(2.5) == 2.5
    assert cell("inf", 10).strip() == "Infinity" and cell("-inf", 10).strip() == "-Infinity"
    assert cell(None, 10).strip() == "failed"
    with pytest.raises(TypeError, match="json_extent"):
        json_extent("inf")


def test_exit_pupil_at_infinity_is_reported_as_infinity():
    lens = _xp_at_infinity()
    data = report.report_data(lens)
    text = json.dumps(data, allow_nan=False)  # strict JSON, as `report --json` writes it
    back = json.loads(text)["exit_pupil"]
    assert back["z"] in ("inf", "-inf") and back["diameter"] == "inf"
    assert back["from_image"] in ("inf", "-inf")
    assert data["efl"] == pytest.approx(F, rel=1e-12)  # finite values stay numbers
    assert data["working_fnum"] == pytest.approx(F / 4.0, rel=1e-12)
    lines = report.format_report(data).splitlines()
    row = [ln for ln in lines if "Exit pupil diameter" in ln]
    assert len(row) == 1 and row[0].split(":")[1].split()[0] == "Infinity"
    row = [ln for ln in lines if "Exit pupil position" in ln]
    assert len(row) == 1 and "Infinity" in row[0] and "failed" not in row[0]
