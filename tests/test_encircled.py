"""Encircled / ensquared energy: Airy pattern, uniform disc, monotonicity, inverse, errors."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.scipy.special import bessel_jn

import jaxlens as jl
from jaxlens.analysis.encircled import encircled_energy, radius_for_fraction
from jaxlens.optics.paraxial_surface import ParaxialSurface

F, EPD, WL = 50.0, 5.0, 0.55


def perfect(defocus=0.0):
    """An ideal thin lens (every conjugate imaged perfectly): F/10 at 0.55 µm."""
    return jl.Lens(surfaces=(ParaxialSurface(focal_length=F),),
                   thickness=jnp.array([F + defocus]), materials=(jl.Air(),), stop=0, epd=EPD,
                   wavelengths=jnp.array([WL]))


def airy_ee(r_mm):
    """1 − J0²(v) − J1²(v), v = 2π NA r/λ (J0, J1 from jax.scipy.special.bessel_jn)."""
    na = np.sin(np.arctan(EPD / 2 / F))  # the ideal lens bends slopes: tan u′ = h/f
    v = jnp.asarray(2 * np.pi * na * np.asarray(r_mm) / (WL * 1e-3))
    j = bessel_jn(jnp.where(v > 0, v, 1.0), v=1, n_iter=60)  # [2, …]: J0, J1 (NaN at 0)
    return np.where(np.asarray(v) > 0, np.asarray(1 - j[0] ** 2 - j[1] ** 2), 0.0)


def test_diffraction_limited_is_airy():
    """Measured: |EE − Airy| ≤ 2.4e-3 for r ≤ 20 µm with 0.5 µm pixels (8.1e-3 with 1 µm,
    1.0e-3 with 0.25 µm: the pixel's own width, see the module notes)."""
    r = np.linspace(0.0, 0.02, 41)
    ee = encircled_energy(perfect(), 0.0, r, method="diffraction", pixel_size=0.0005,
                          kernel_size=81)
    np.testing.assert_allclose(np.asarray(ee.energy), airy_ee(r), atol=3e-3)
    assert 0.0 < float(ee.truncated) < 0.06  # the kernel spans ±20 µm: 5 % lies beyond
    # The inverse: Airy's half-energy radius (by bisection) within 1 %.
    lo, hi = 0.0, 0.006
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(airy_ee(mid)) < 0.5 else (lo, mid)
    half = 0.5 * (lo + hi)
    r50 = radius_for_fraction(perfect(), 0.0, 0.5, method="diffraction", pixel_size=0.0005,
                              kernel_size=81)
    np.testing.assert_allclose(float(r50), half, rtol=0.01)
    # More than the kernel holds: NaN, never a silent radius.
    assert np.isnan(float(radius_for_fraction(
        perfect(), 0.0, 0.99, method="diffraction", pixel_size=0.0005, kernel_size=81)))


def test_uniform_disc_from_pure_defocus():
    """A perfect lens defocused by δ gives a uniformly filled disc of radius δ·h/f."""
    delta = 2.0
    lens = perfect(delta)
    big_r = delta * EPD / 2 / F
    r = np.linspace(0.0, 1.2 * big_r, 13)
    ee = encircled_energy(lens, 0.0, r)
    np.testing.assert_allclose(np.asarray(ee.energy), np.minimum(r / big_r, 1.0) ** 2,
                               atol=0.01)
    np.testing.assert_allclose(np.asarray(ee.center), 0.0, atol=1e-15)
    fr = jnp.array([0.25, 0.5, 0.8])
    np.testing.assert_allclose(np.asarray(radius_for_fraction(lens, 0.0, fr)),
                               big_r * np.sqrt(np.asarray(fr)), rtol=0.005)
    # Ensquared: a square of half-width a ≤ R/√2 holds 4a²/(πR²).
    a = np.array([0.3, 0.5, 0.7]) * big_r
    sq = encircled_energy(lens, 0.0, a, shape="square")
    np.testing.assert_allclose(np.asarray(sq.energy), 4 * a**2 / (np.pi * big_r**2), atol=0.01)


def test_d80_gradient_with_respect_to_defocus():
    """r80 = √0.8·δ·h/f, so d r80/dδ = √0.8·h/f; the interpolated inverse carries it."""
    lens = perfect(2.0)

    def r80(t):
        return radius_for_fraction(eqx.tree_at(lambda m: m.thickness, lens, t), 0.0, 0.8)

    g = jax.grad(lambda d: r80(lens.thickness + d)[()])(jnp.zeros(1))
    np.testing.assert_allclose(float(g[0]), np.sqrt(0.8) * EPD / 2 / F, rtol=0.01)


def test_monotone_zero_at_zero_and_one_at_large_radius():
    lens = jl.zoo.cooke_triplet()
    r = np.linspace(0.0, 0.2, 81)
    for reference in ("centroid", "chief"):
        ee = np.asarray(encircled_energy(lens, 14.0, r, reference=reference,
                                         wavelength=lens.wavelengths).energy)
        assert ee[0] == 0.0 and ee[-1] == 1.0
        assert np.all(np.diff(ee) >= 0)
    # The chief-ray reference is the chief ray; the centroid sits elsewhere for coma.
    c = encircled_energy(lens, 14.0, r, reference="chief").center
    cr = jl.analysis.chief_ray(lens, 14.0)
    np.testing.assert_allclose(np.asarray(c), np.asarray(cr.origin[:2]))


def test_bad_input_is_refused():
    lens = perfect(2.0)
    with pytest.raises(ValueError, match=r"radii must be .*\[0, inf\).*mm"):
        encircled_energy(lens, 0.0, [0.01, -0.01])
    with pytest.raises(ValueError, match="radii"):
        encircled_energy(lens, 0.0, [np.nan])
    for bad in (0.0, 1.0, 1.5, -0.2):
        with pytest.raises(ValueError, match=r"fraction must be .*\(0, 1\)"):
            radius_for_fraction(lens, 0.0, bad)
    with pytest.raises(ValueError, match="method must be one of"):
        encircled_energy(lens, 0.0, [0.01], method="wave")
    with pytest.raises(ValueError, match="reference must be one of"):
        encircled_energy(lens, 0.0, [0.01], reference="ideal")
    with pytest.raises(ValueError, match="shape must be one of"):
        encircled_energy(lens, 0.0, [0.01], shape="hexagon")
    with pytest.raises(ValueError, match="needs pixel_size"):
        encircled_energy(lens, 0.0, [0.01], method="diffraction")
    with pytest.raises(ValueError, match="field must be one field"):
        encircled_energy(lens, [0.0, 1.0, 2.0], [0.01])
    with pytest.raises(ValueError, match="wavelength"):
        encircled_energy(lens, 0.0, [0.01], wavelength=550.0)


@pytest.mark.parametrize("name, call", [
    ("encircled_energy", lambda lens, f: encircled_energy(lens, f, jnp.array([0.01, 0.02]))),
    ("opd", lambda lens, f: jl.analysis.opd(lens, f, jnp.array([[0.0, 0.5], [0.3, 0.0]]))),
    ("ray_fan", lambda lens, f: jl.analysis.ray_fan(lens, f, n=5).tangential),
    ("collimated", lambda lens, f: jl.sampling.collimated(lens, f, jnp.array([[0.0, 0.5]]))
     .direction)])
def test_one_field_is_read_alike_by_every_analysis(name, call):
    """A field of shape [1] (an array or a list) is θy, as a scalar is; a list of fields is
    refused with the same message everywhere (it was accepted by some and refused by others)."""
    lens = jl.zoo.cooke_triplet().astype(jnp.float64)
    one = jax.tree.leaves(call(lens, 10.0))
    for given in (jnp.array([10.0]), [10.0]):
        for a, b in zip(jax.tree.leaves(call(lens, given)), one, strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    with pytest.raises(ValueError, match=rf"{name}: field must be one field, θy or \(θx, θy\)"):
        call(lens, jnp.array([[0.0, 5.0], [0.0, 10.0]]))
    with pytest.raises(ValueError, match=rf"{name}: field must be finite angles in \(-90, 90\)"):
        call(lens, jnp.array([95.0]))
