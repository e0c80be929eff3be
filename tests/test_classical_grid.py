"""A committed classical design re-read and evaluated at the run's own fields, against
optiland 0.6.3 (tests/data/classical_grid_optiland.json, tools/classical_grid_reference.py).

The design: experiments/classical/designs/seed_1.zmx (Table 1's +recipe seed 1, the README's
best design). ``jaxlens.design.evaluate.evaluate`` (the numbers the classical run reports: the
16 × 16 sensor grid of (θx, θy) fields, F, d, C rays pooled about their centroid, paraxial EFL,
F/#, BFL, track, chief ray and distortion at half the diagonal FoV) of the file read by
``jaxlens.load``, against optiland tracing the same file at the same fields with jaxlens's
indices (only geometry, aperture, fields and tracing are optiland's).
"""

import json
import pathlib
import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.design.evaluate import evaluate
from jaxlens.design.spec import DesignSpec

ROOT = pathlib.Path(__file__).parent.parent
REF = json.loads((ROOT / "tests" / "data" / "classical_grid_optiland.json").read_text())


@pytest.mark.slow  # the 256-field evaluation: 40 s
def test_classical_design_evaluates_as_optiland_traces_it():
    """Per-field pooled RMS within 1e-9 µm (measured 1.9e-12; no ray lost in either); EFL,
    F/#, BFL, chief height and distortion relative 1e-12 (measured 3.8e-14); with optiland's
    own E48R/OKP4 data the EFL moves by 2.3e-3. The re-read file gives Table 1's reported
    numbers for the seed to 1e-6 relative (measured 2.3e-7: the export's asphere terms are
    rewritten on the closest conic, ``optics.rebase``; before its clear apertures were set on
    the rewritten lens, the file clipped 4 rim rays and its largest RMS read 8.3096 µm
    against the reported 8.3053)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(str(ROOT / REF["file"]))
    ev = evaluate(lens, DesignSpec(), n=REF["n"])
    o = REF["jaxlens_media"]
    np.testing.assert_allclose(ev.rms_um, o["rms_per_field_um"], rtol=0, atol=1e-9)
    for k in ("efl", "fnum", "bfl", "total_track", "chief_height_full_field",
              "distortion_percent", "rms_mean_um", "rms_max_um"):
        assert getattr(ev, k) == pytest.approx(o[k], rel=1e-12), k
    assert ev.efl == pytest.approx(REF["glass"]["efl"], rel=3e-3)
    assert abs(ev.efl - REF["glass"]["efl"]) / ev.efl > 1e-3  # glass data do differ
    table1 = json.loads((ROOT / "experiments" / "classical" / "table1.json").read_text())
    reported = next(s for s in table1["columns"]["+recipe"]["per_seed"] if s["seed"] == 1)
    for k in ("rms_mean_um", "rms_max_um", "efl", "fnum", "bfl", "chief_height_full_field",
              "distortion_percent"):
        assert getattr(ev, k) == pytest.approx(reported[k], rel=1e-6), k
    assert REF["jaxlens_media"]["rays_lost"] == 0
