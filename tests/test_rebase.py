"""Rebasing an even asphere on its closest conic keeps the surface and the paraxial data."""

import pathlib

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.rebase import SAG_TOLERANCE, rebase_conic, rebase_conics
from jaxlens.optics.surfaces import EvenAsphere


def _sag(surface, r):
    return np.asarray(surface.sag(jnp.zeros_like(r), r)[0])


def test_a_conic_written_as_sphere_plus_polynomial_is_found_again():
    """A k = −2.5 conic, written as a sphere plus fitted r⁴ … r¹⁴ terms, rebases to a conic
    near −2.5 with far smaller polynomial terms and the same sag."""
    c, R = 0.2, 2.0
    r = np.linspace(0.0, R, 400)
    conic = c * r**2 / (1 + np.sqrt(1 - (1 - 2.5) * c**2 * r**2))
    sphere = c * r**2 / (1 + np.sqrt(1 - c**2 * r**2))
    u = r / R
    powers = 2 * np.arange(2, 8)
    coef, *_ = np.linalg.lstsq(u[:, None] ** powers, conic - sphere, rcond=None)
    a = np.concatenate([[0.0], coef / R**powers])
    surface = EvenAsphere(c=c, k=0.0, coeffs=jnp.asarray(a), semi_diameter=R)
    out = rebase_conic(surface)
    assert float(out.k) == pytest.approx(-2.5, abs=0.06)
    assert float(out.c) == c and float(out.coeffs[0]) == 0.0
    assert np.max(np.abs(np.asarray(out.coeffs[1:]) * R ** powers)) < 0.02 * np.max(
        np.abs(coef))
    rr = jnp.asarray(r)
    assert np.max(np.abs(_sag(out, rr) - _sag(surface, rr))) < 2 * SAG_TOLERANCE


def test_shipped_design_keeps_its_sag_paraxial_data_and_evaluation():
    from jaxlens.design.evaluate import evaluate
    from jaxlens.design.spec import DesignSpec

    root = pathlib.Path(__file__).resolve().parents[1]
    lens = jl.load(root / "experiments" / "classical" / "designs" / "seed_13.zmx")
    new = rebase_conics(lens)
    for a, b in zip(lens.surfaces, new.surfaces, strict=True):
        if not np.isfinite(float(a.semi_diameter)):
            continue
        r = jnp.linspace(0.0, float(a.semi_diameter), 301)
        assert np.max(np.abs(_sag(a, r) - _sag(b, r))) < 2 * SAG_TOLERANCE
        assert float(a.c) == float(b.c)
    pa, pb = jl.paraxial.paraxial_data(lens), jl.paraxial.paraxial_data(new)
    assert float(pb.efl) == pytest.approx(float(pa.efl), rel=1e-12)
    assert float(pb.bfl) == pytest.approx(float(pa.bfl), rel=1e-12)
    spec = DesignSpec()
    assert evaluate(new, spec).rms_mean_um == pytest.approx(evaluate(lens, spec).rms_mean_um,
                                                            rel=1e-4)


def test_surfaces_without_an_aperture_or_polynomial_terms_are_kept():
    sphere = EvenAsphere(c=0.1, k=0.0, coeffs=jnp.zeros(7), semi_diameter=2.0)
    assert rebase_conic(sphere) is sphere
    open_aperture = EvenAsphere(c=0.1, k=0.0, coeffs=jnp.asarray([0, 1e-3, 0, 0, 0, 0, 0.0]))
    assert rebase_conic(open_aperture) is open_aperture
