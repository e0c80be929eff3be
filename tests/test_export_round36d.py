"""Round 36d of the independent re-evaluation of exported designs: the clear apertures of the
classical run's export (``jaxlens.experiments.classical_export``) and the notes that say how the
run evaluated the file.

* Every non-stop clear semi-diameter was the largest evaluated ray height × (1 + 1e-9): a
  re-evaluator with other glass data moves the rim rays past it (optiland 0.6.3's CDGM data,
  2e-6 from jaxlens's, lost 20 rim rays of a CDGM smoke design; its plastics data, 6e-4 off,
  16 of experiments/classical/designs/seed_1.zmx's). The margin is now 1e-2 (the rim heights
  move by up to 10.6 × the index change, relative; classical_export's doc has the figures).
* A stop behind elements got EPD/2, a size in the entrance pupil's space: behind a negative
  front element the export clipped 20 % of the evaluated rays. It is now sized by its rays;
  the stop in front keeps EPD/2 (the entrance pupil, to 1e-9).
* A margin that would make the evaluation's geometry check fail is cut until it passes.
* lens.zmx (NOTE lines) and lens.json ("description") say how the run evaluated them.
"""

import json
import math
import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import analysis
from jaxlens.analysis.spots import rim_pupil
from jaxlens.design import evaluate as evaluate_mod
from jaxlens.design.spec import DesignSpec
from jaxlens.experiments import classical, classical_export
from jaxlens.imaging.sampling import pupil_grid
from jaxlens.optics.materials import AbstractMaterial, Air

SPEC = DesignSpec(
    fov=10.0,
    fnum=4.0,
    sensor_diagonal=1.0,
    n_elements=2,
    materials=("N-BK7", "N-BK7"),
    total_track=16.0,
    stop=1,
)


def _lens(tmp_path, stop: int):
    """A negative plano-concave element, a plane and a biconvex element, N-BK7, EPD 1.43 mm
    (the spec's); ``stop`` (0-based) is the first surface or the plane between them."""
    surfaces = [
        {"type": "object", "thickness": "inf", "material": "air"},
        {"type": "standard", "curvature": 0.0, "thickness": 1.0, "material": "N-BK7"},
        {"type": "standard", "curvature": 0.1, "thickness": 2.0, "material": "air"},
        {"type": "standard", "curvature": 0.0, "thickness": 1.0, "material": "air"},
        {"type": "standard", "curvature": 0.125, "thickness": 2.0, "material": "N-BK7"},
        {"type": "standard", "curvature": -0.125, "thickness": 10.0, "material": "air"},
        {"type": "image"},
    ]
    surfaces[stop + 1]["is_stop"] = True
    d = {
        "format": "jaxlens.lens/1",
        "name": "negative_front",
        "aperture": {"epd": SPEC.epd},
        "fields": {"type": "angle_deg_y", "values": [0.0, 5.0]},
        "wavelengths_um": list(SPEC.wavelengths),
        "primary": 1,
        "surfaces": surfaces,
    }
    p = tmp_path / f"lens_{stop}.json"
    p.write_text(json.dumps(d))
    return jl.load(p, dtype="float64")


@pytest.fixture
def corners(monkeypatch):
    """The export's field grid cut to the four sensor corners (2 × 2), which hold the largest
    heights: the same code, a fraction of the rays."""
    grid = evaluate_mod.sensor_field_grid
    monkeypatch.setattr(evaluate_mod, "sensor_field_grid", lambda spec, n=16: grid(spec, 2))
    return jnp.asarray(grid(SPEC, 2)[0])


class _Shifted(AbstractMaterial):
    """A medium whose index is another's plus dn (another tool's data for the same glass)."""

    base: AbstractMaterial
    dn: float

    def index(self, wavelength):
        return self.base.index(wavelength) + self.dn


def _lost(lens, angles, dn=0.0):
    """Rays lost at ``angles`` (all wavelengths), every glass's index moved by dn, of the rays
    the export sizes the apertures by: the pupil rim (64 points and the centre, where a
    re-evaluator's own pupil rings reach) and the 21 × 21 grid."""
    mats = tuple(m if isinstance(m, Air) else _Shifted(m, dn) for m in lens.materials)
    lens = eqx.tree_at(lambda x: x.materials, lens, mats)
    pupil = jnp.concatenate([rim_pupil(64, jnp.float64), pupil_grid(21, jnp.float64)])
    r = analysis.rms_spot(lens, angles, jnp.asarray(SPEC.wavelengths), pupil=pupil)
    return int(np.sum(np.rint((1.0 - np.asarray(r.valid_fraction)) * pupil.shape[0])))


def test_margin_keeps_the_rim_rays_under_another_tools_index(tmp_path, corners):
    """Indices 1e-5 off (either sign) lose no ray through the exported apertures; the exact
    ray heights (the former 1e-9) lose rim rays for one of the signs."""
    lens = _lens(tmp_path, stop=2)
    out = classical_export.with_clear_apertures(lens, SPEC)
    assert [_lost(out, corners, dn) for dn in (0.0, 1e-5, -1e-5)] == [0, 0, 0]
    assert classical_export.CLEAR_APERTURE_MARGIN == 1e-2
    exact = classical_export.with_clear_apertures(lens, SPEC, margin=1e-9)
    assert _lost(exact, corners) == 0
    assert max(_lost(exact, corners, dn) for dn in (1e-5, -1e-5)) > 0
    ratio = [
        float(a.semi_diameter / b.semi_diameter)
        for a, b in zip(out.surfaces, exact.surfaces, strict=True)
    ]
    np.testing.assert_allclose(ratio, (1 + 1e-2) / (1 + 1e-9), rtol=1e-12)


def test_a_stop_behind_elements_is_sized_by_its_rays(tmp_path, corners):
    """Behind the negative element the beam is wider than the entrance pupil: EPD/2 at the
    stop (the former export) clipped 20 % of the corner rays; now none is clipped."""
    lens = _lens(tmp_path, stop=2)
    out = classical_export.with_clear_apertures(lens, SPEC)
    r = float(out.surfaces[2].semi_diameter)
    assert r > 1.1 * SPEC.epd / 2
    old = eqx.tree_at(
        lambda x: x.surfaces[2].semi_diameter, out, jnp.asarray(SPEC.epd / 2 * (1 + 1e-9))
    )
    assert _lost(old, corners) > 0.15 * 4 * 3 * 382
    assert _lost(out, corners) == 0


def test_the_stop_in_front_stays_the_entrance_pupil(tmp_path, corners):
    """The first surface as the stop keeps EPD/2 (to 1e-9), no margin: a tool that floats the
    aperture by the stop's size reads the file's ENPD."""
    out = classical_export.with_clear_apertures(_lens(tmp_path, stop=0), SPEC)
    assert float(out.surfaces[0].semi_diameter) == SPEC.epd / 2 * (1 + 1e-9)
    assert float(out.surfaces[1].semi_diameter) > SPEC.epd / 2 * (1 + 1e-4)
    assert _lost(out, corners) == 0


def test_a_margin_that_would_cross_surfaces_is_cut(tmp_path, monkeypatch):
    """Ray heights 0.05 % inside the radius where the two faces of the second element meet
    (its edge thickness 0 at 3.87 mm): the full margin would put the crossing inside the
    checked aperture (self-intersection, the evaluation's own criterion), so a smaller one is
    used and the geometry check passes as it does at the exact heights."""
    lens = _lens(tmp_path, stop=2)
    c, t = 0.125, 2.0
    # both faces have sag c r² / (1 + √(1 − c² r²)); they meet where 2 · sag = t
    sag = t / 2
    edge = math.sqrt(2 * sag / c - sag * sag)
    heights = jnp.full((5,), edge / (1 + 5e-4))
    monkeypatch.setattr(analysis, "clear_semi_diameters", lambda *a, **k: heights)
    exact = classical_export.with_clear_apertures(lens, SPEC, margin=0.0)
    assert bool(analysis.self_intersection(exact).ok)
    full = eqx.tree_at(
        lambda x: x.surfaces,
        exact,
        tuple(
            eqx.tree_at(
                lambda s: s.semi_diameter,
                s,
                s.semi_diameter * (1 + classical_export.CLEAR_APERTURE_MARGIN),
            )
            for s in exact.surfaces
        ),
    )
    assert not bool(analysis.self_intersection(full).ok)
    out = classical_export.with_clear_apertures(lens, SPEC)
    assert bool(analysis.self_intersection(out).ok)
    got = float(out.surfaces[3].semi_diameter / exact.surfaces[3].semi_diameter) - 1
    assert 1e-5 < got < 5e-4


def test_the_export_says_how_the_run_evaluated_it(tmp_path):
    """The notes (NOTE lines of lens.zmx, "description" of lens.json) and the summary's
    convention name the ray aiming, the field grid, the distortion and the apertures."""
    spec = DesignSpec()
    notes = classical_export.evaluation_notes(spec)
    for text in (
        "ray aiming off",
        "16 x 16 grid",
        f"{spec.focal_length:.10g} mm",
        f"thetay = {spec.half_fov:.10g} deg",
        "x (1 + 0.01)",
        "ENPD/2",
        "weighted equally",
        "no refocus",
    ):
        assert text in notes, text
    for text in ("ray aiming off", "distortion"):
        assert text in classical.CONVENTION, text
    lens = _lens(tmp_path, stop=0)
    import dataclasses

    lens = dataclasses.replace(lens, description=notes)
    jl.save(lens, tmp_path / "lens.zmx")
    jl.save(lens, tmp_path / "lens.json")
    zmx = (tmp_path / "lens.zmx").read_text()
    assert all(f"NOTE 0 {ln}" in zmx for ln in notes.splitlines())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert jl.load(tmp_path / "lens.json").description == notes
