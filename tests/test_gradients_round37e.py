"""Round 37e: gradients of the design machinery and of the surface kinds round 36e did not
cover, against central differences (float64). ``tools/grad37e_probe.py`` is the audit these
cases come from."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.design import mask


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def test_reweighting_mask_jits_and_differentiates_with_a_concrete_area():
    """The mask with the sensor-area shares closed over (as ``field_weights`` passes them):
    under ``jit`` the all-zero check summed the shares with ``np.sum``, which calls the jax
    array's own ``sum`` and so gave a tracer, and ``float`` of it raised
    ConcretizationTypeError. Its gradient in the RMS equals central differences."""
    rms = jnp.array([0.01, 0.03, 0.02, 0.05])
    area = jnp.array([0.1, 0.2, 0.3, 0.4])
    eager = mask.reweighting_mask(rms, area)
    np.testing.assert_allclose(
        jax.jit(lambda r: mask.reweighting_mask(r, area))(rms), eager, rtol=1e-15
    )

    def loss(r):
        return jnp.sum(mask.reweighting_mask(r, area) ** 2)

    g = jax.jit(jax.grad(loss))(rms)
    h = 1e-7
    fd = [(loss(rms.at[i].add(h)) - loss(rms.at[i].add(-h))) / (2 * h) for i in range(4)]
    np.testing.assert_allclose(g, fd, rtol=1e-7)
    zeros = jnp.zeros(4)  # concrete, closed over: still refused under jit
    with pytest.raises(ValueError, match="area must have a share > 0"):
        jax.jit(lambda r: mask.reweighting_mask(r, zeros))(rms)


def _singlet(back):
    return jl.Lens(
        (jl.Sphere(1 / 30), back),
        jnp.array([4.0, 40.0]),
        (jl.ModelGlass(1.5168, 64.17), jl.Air()),
        stop=0,
        epd=8.0,
        fields=jnp.array([0.0, 8.0]),
    )


def _grid_loss(lens, reverse_rule):
    u = jnp.linspace(-0.9, 0.9, 5)
    X, Y = jnp.meshgrid(u, u)
    d = jnp.array([0.04, 0.12, 1.0])
    d = d / jnp.linalg.norm(d)
    o = jnp.stack([X.ravel() * 4.0, Y.ravel() * 4.0, jnp.full(25, -5.0)], -1)
    out = jl.trace(lens, jl.Rays(o, jnp.broadcast_to(d, o.shape), 0.55), reverse_rule=reverse_rule)
    x, y = out.origin[:, 0], out.origin[:, 1]
    s = x**2 + 0.7 * y**2 + 0.3 * x + 0.2 * y + 1e-3 * out.opl + out.direction[:, 0]
    return jnp.sum(jnp.where(out.valid, s, 0.0))


@pytest.mark.slow  # two compiles of a Newton trace through an XY polynomial (~10 s)
@pytest.mark.parametrize("reverse_rule", [False, True])
def test_xy_polynomial_coefficient_gradients_match_differences(reverse_rule):
    """Every XY-polynomial coefficient (x, y, x², xy, y², x³ …: the asymmetric terms round
    36e's rotationally symmetric lenses never had), with and without the hand-written
    reverse rule: within 1e-7 of central differences (the audit found 1e-9 or better)."""
    coeffs = jnp.array([0.0, 0.001, 0.01, 0.002, 0.012, 1e-3, -5e-4, 2e-4, 1e-4])
    lens = _singlet(jl.XYPolynomial(c=-1 / 40, k=0.1, norm_radius=5.0, coeffs=coeffs))

    def f(a):
        return _grid_loss(eqx.tree_at(lambda L: L.surfaces[1].coeffs, lens, a), reverse_rule)

    g = jax.jit(jax.grad(f))(coeffs)
    fj = jax.jit(f)
    h = 1e-5
    fd = np.array(
        [
            (fj(coeffs.at[j].add(h)) - fj(coeffs.at[j].add(-h))) / (2 * h)
            for j in range(coeffs.shape[0])
        ]
    )
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-7 * np.max(np.abs(fd)))
