"""Round 44a: one system-aperture rule across the imaging layer.

The beam of ``psf``/``mtf``/``psf_points``/``render``'s PSFs is the unit pupil of normalised
pupil coordinates (``radiometry.in_pupil``: under paraxial aiming the EPD's disc on the
paraxial entrance pupil's plane), as optiland and Zemax sample it; a stop without a
semi-diameter clips nothing. Before, ``aiming.apertured`` gave such a stop the paraxial
marginal ray's radius and let it clip a beam overfilled 1.25×: a different beam wherever the
real rays' crossing of the stop differs from the paraxial ray's (pupil aberration).

Reference: tools/aper44a_reference.py (optiland 0.6.3's rays on jaxlens's pupil grid, every
aperture removed; tests/data/aper44a/aper44a_optiland.json). The |OTF| of one ray set is
compared at atol 1e-6: the same rays through the same surfaces agree to ~1e-12 mm in their
image points (acc40c's like test holds 1e-9), and on the start commit the stop-clipped beam
differed by 0.002 to 0.43 (Laikin's lens at 35°: 1262 of 2056 rays passed the stop).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import radiometry
from jaxlens.imaging.psf import GeometricPSF, mtf
from jaxlens.optics.lens import unclipped

ROOT = pathlib.Path(__file__).resolve().parents[1]
REF = json.loads((ROOT / "tests" / "data" / "aper44a" / "aper44a_optiland.json").read_text())
# The reference's pupil grid (overfilled 1.25×, the default until 2026-12-03), which the
# unit pupil's cut must bound: the fault test below needs the ring beyond it.
REF_GRID = GeometricPSF(pupil=REF["mtf_cells"], overfill=REF["mtf_overfill"])
UNIT_MM = {"laikin": 25.4}  # Laikin's file is in inches (optiland keeps them); others mm


def _lens(name):
    """The file's lens under paraxial aiming; without its apertures unless the reference
    kept them (then its stop's semi-diameter is given)."""
    r = REF["lenses"][name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(str(ROOT / r["file"]))
    lens = dataclasses.replace(lens, aim="paraxial", vignetting=None)
    sd = float(lens.surfaces[lens.stop].semi_diameter)
    if r["apertures"]:
        assert np.isfinite(sd)
        return lens
    return unclipped(lens)


def _check(name, atol=1e-6, n=None):
    """``n``: the first n frequencies only (a new shape, so a new compiled program)."""
    r = REF["lenses"][name]
    lens = _lens(name)
    assert np.isfinite(float(lens.surfaces[lens.stop].semi_diameter)) == r["apertures"]
    nu = (np.asarray(r["freqs"]) / UNIT_MM.get(name, 1.0))[:n]  # cycles per mm
    for fr in r["fields"]:
        _, t, s = mtf(lens, fr["field_deg"], wavelengths=[r["primary_um"]], frequencies=nu,
                      diffraction=False, model=REF_GRID)
        np.testing.assert_allclose(np.asarray(t), fr["unit_pupil"]["tangential"][:n], rtol=0,
                                   atol=atol, err_msg=f"{name} {fr['field_deg']}°")
        np.testing.assert_allclose(np.asarray(s), fr["unit_pupil"]["sagittal"][:n], rtol=0,
                                   atol=atol, err_msg=f"{name} {fr['field_deg']}°")


@pytest.mark.parametrize("name", ["laikin", "triplet"])
def test_unbounded_stop_mtf_is_optilands_unit_pupil(name):
    """The geometric MTF of a lens whose stop has no semi-diameter is that of optiland's
    unit-pupil beam (no stop clip)."""
    _check(name)


@pytest.mark.parametrize("name", ["triplet_stopsmall", "triplet_stopwide"])
def test_given_stop_mtf_is_optilands(name):
    """A stop of given semi-diameter (the files' CLAP, optiland's RadialAperture): narrower
    than the EPD's beam (3.4 mm) it bounds the beam, unchanged from the start commit; wider
    (6 mm), the unit pupil bounds it, where on the start commit the overfilled beam passed
    the stop up to 6 mm (|OTF| up to 0.11 off optiland's)."""
    _check(name)


def test_reference_beams_differ():
    """The two beams (unit pupil; overfill clipped by the paraxial stop radius) differ on
    these lenses, so the test above tells the rules apart."""
    gap = max(np.max(np.abs(np.subtract(f["unit_pupil"]["tangential"],
                                        f["stop_clipped"]["tangential"])))
              for r in REF["lenses"].values() if not r["apertures"] for f in r["fields"])
    assert gap > 0.1


def test_injected_fault_is_caught(monkeypatch):
    """With the unit pupil's cut removed (``in_pupil`` passing the overfilled ring, the
    stop unbounded), the triplet's MTF leaves optiland's."""
    import jaxlens.imaging.psf as P

    monkeypatch.setattr(P, "in_pupil", lambda p: np.ones(np.shape(p)[:-1], bool))
    with pytest.raises(AssertionError):
        _check("triplet", n=3)  # a new shape: compiled with the fault


def test_in_pupil_is_the_unit_disc():
    pts = np.array([[0.0, 0.0], [0.6, 0.8], [0.6, 0.81], [1.25, 0.0]])
    np.testing.assert_array_equal(np.asarray(radiometry.in_pupil(pts)),
                                  [True, True, False, False])


def test_mtf_stays_differentiable_and_jits():
    """The unit pupil's cut is a constant mask of the launch grid: the MTF's gradient with
    respect to a curvature is finite and nonzero, and the same under jit."""
    import equinox as eqx
    import jax

    lens = _lens("triplet")
    nu = np.array([20.0, 40.0])

    def t40(c):
        m = eqx.tree_at(lambda x: x.surfaces[1].c, lens, c)
        return mtf(m, 14.0, wavelengths=[REF["lenses"]["triplet"]["primary_um"]],
                   frequencies=nu, diffraction=False)[1][-1]

    c0 = lens.surfaces[1].c
    g = float(jax.grad(t40)(c0))
    assert np.isfinite(g) and g != 0.0
    h = 1e-7
    fd = (float(t40(c0 + h)) - float(t40(c0 - h))) / (2 * h)
    assert abs(g - fd) <= 1e-3 * abs(fd) + 1e-6  # bilinear-free (no splat): smooth in c
    assert abs(float(jax.jit(jax.grad(t40))(c0)) - g) <= 1e-9 * abs(g)
