"""Numerics, round 34a: silent wrong answers of a numerical kind (dtype mixing, jit against
eager against vmap, gradients at special points, extreme but valid values). One test per
gap fixed; each names what main returned."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxlens import zoo
from jaxlens.analysis import tolerance_metric as TM
from jaxlens.imaging import psf as P
from jaxlens.imaging import sampling as S

LENS = zoo.cooke_triplet(clip=False)  # no clipping: finite differences see no ray lost
C0 = LENS.surfaces[0].c


def _with_c(c):
    return eqx.tree_at(lambda lens: lens.surfaces[0].c, LENS, c)


def _mtf_sum(c, freqs, field=14.0):
    _, t, s = P.mtf(_with_c(c), field, frequencies=jnp.asarray(freqs))
    return jnp.sum(t) + jnp.sum(s)


def test_mtf_gradient_beyond_the_diffraction_cutoff_is_finite():
    """A frequency past the cut-off 1/(λ·F#) (305 to 411 cycles/mm for C to F here) has an
    MTF of 0; main's gradient of the MTF in a curvature was NaN there (the unused branch's arccos
    and square root at s = 1), which poisoned every other frequency's gradient."""
    g_low = jax.grad(_mtf_sum)(C0, [50.0])
    for high in (500.0, 1000.0):
        g = jax.grad(_mtf_sum)(C0, [50.0, high])
        assert np.isfinite(float(g)), high
        np.testing.assert_allclose(float(g), float(g_low), rtol=1e-12)
    h = 1e-7
    fd = (_mtf_sum(C0 + h, [50.0, 500.0]) - _mtf_sum(C0 - h, [50.0, 500.0])) / (2 * h)
    np.testing.assert_allclose(float(jax.grad(_mtf_sum)(C0, [50.0, 500.0])), float(fd),
                               rtol=1e-4)


def test_mtf_gradient_in_the_field_on_axis_is_finite():
    """On axis the tangential direction is (0, 1) by convention; main's gradient of the MTF
    in the field angle was NaN there (the norm's square root of 0), the finite-difference
    one 0 (the MTF is even in θy). Off axis the gradient is unchanged."""
    f = lambda th: _mtf_sum(C0, [50.0, 100.0], th)  # noqa: E731
    for field in (0.0, jnp.array([0.0, 0.0])):
        g = jax.grad(lambda a, fd=field: f(fd + a))(0.0)
        assert np.isfinite(float(g)) and abs(float(g)) < 1e-9, field
    g = float(jax.grad(f)(1e-3))
    fd = float((f(1e-3 + 1e-4) - f(1e-3 - 1e-4)) / 2e-4)  # 1e-5 was rounding-noisy (1e-3)
    np.testing.assert_allclose(g, fd, rtol=1e-3)


def test_tolerance_field_mtf_gradients_on_axis_and_past_the_cutoff():
    """The tolerance metric's MTF (``field_mtf``) had both traps: a gradient in the
    F-number NaN at 500 cycles/mm (past the cut-off), and NaN in the fields with an on-axis
    field among them. Now 0 past the cut-off and equal to finite differences in the fields."""
    fields = jnp.array([[0.0, 0.0], [0.0, 14.0]])
    wls = LENS.wavelengths

    def metric(fnum, scale, freq):
        f = fields * scale
        return jnp.sum(TM.field_mtf(TM.spot_data(LENS, f, wls, S.pupil_grid(7)), f, wls,
                                    freq, fnum))

    assert float(jax.grad(metric)(5.0, 1.0, 500.0)) == 0.0
    g = float(jax.grad(metric, 1)(5.0, 1.0, 30.0))
    fd = float((metric(5.0, 1 + 1e-6, 30.0) - metric(5.0, 1 - 1e-6, 30.0)) / 2e-6)
    assert np.isfinite(g)
    np.testing.assert_allclose(g, fd, rtol=1e-4)


def test_diffraction_mtf_values_unchanged():
    """The closed form (2/π)(arccos s − s√(1 − s²)): 1 at 0, 0 from the cut-off on."""
    from jaxlens.imaging.otf import diffraction_mtf
    s = np.array([0.0, 0.25, 0.5, 0.999, 1.0, 1.5])
    want = np.where(s < 1, (2 / np.pi) * (np.arccos(np.minimum(s, 1))
                                          - s * np.sqrt(np.maximum(1 - s * s, 0))), 0.0)
    got = diffraction_mtf(jnp.asarray(s), 1e-3, 1000.0)
    np.testing.assert_allclose(np.asarray(got), want, atol=1e-15)
