"""How the design loss is assembled: sampling weights, the launched rays, and the residual
vector (spot, pin and the three weighted regularizers), against direct computations."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxlens
from jaxlens.design import curriculum, init, losses, regularizers
from jaxlens.design.params import LensParams
from jaxlens.design.spec import DesignSpec
from jaxlens.tracing.forward import stacked_surfaces

SMALL = DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0,
                   fov_start=30.0, fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=3)


def test_radial_area_weights_count_the_nearest_evaluation_fields():
    fracs = np.array([0.0, 0.3, 0.6, 1.0])
    h, w = 3.0, 4.0
    got = losses.radial_area_weights(fracs, (h, w))
    counts = np.zeros(4)
    for x in np.linspace(-1, 1, 16) * w / 2:
        for y in np.linspace(-1, 1, 16) * h / 2:
            counts[np.argmin(np.abs(fracs - math.hypot(x, y) / math.hypot(h / 2, w / 2)))] += 1
    np.testing.assert_allclose(got, counts / 256, rtol=1e-12)
    assert counts[0] > 0 and counts[-1] > 0


def test_half_pupil_weights_stand_for_the_whole_hexapolar_pupil():
    p, wt = losses.half_pupil(2)
    full = np.asarray(losses.pupil_hexapolar(2))
    assert full.shape == (19, 2)  # the centre, 6 and 12
    on = np.abs(full[:, 0]) < 1e-9
    # Points on x = 0 count once, those with x > 0 twice (their mirror images are dropped).
    assert np.all(p[:, 0] >= 0)
    assert (wt == 1).sum() == on.sum() and (wt == 2).sum() == (full[:, 0] > 1e-9).sum()
    assert wt.sum() == 19
    # Weighted moments of the half pupil equal the full pupil's (x²: both sides count).
    np.testing.assert_allclose(np.sum(wt * p[:, 0] ** 2), np.sum(full[:, 0] ** 2), atol=1e-12)
    np.testing.assert_allclose(np.sum(wt * p[:, 1] ** 2), np.sum(full[:, 1] ** 2), atol=1e-12)
    samp = losses.RayLoss.make(3, 2, (0.5, 0.6), (3.0, 4.0), jnp.float64)
    np.testing.assert_allclose(samp.fracs, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(samp.pupil_weights, wt)
    np.testing.assert_allclose(samp.area, losses.radial_area_weights([0, 0.5, 1], (3.0, 4.0)))
    assert samp.n_fields == 3


def _design(bad=True):
    dt = jnp.float64
    pm = init.parameterization(SMALL, dt)
    p = init.random_params(SMALL, jax.random.PRNGKey(0), dt)
    d = jnp.asarray(init.gap_bounds(SMALL)[:-1] + 0.1, dt)
    p = LensParams(c=0.2 * p.c, a=0.0 * p.a, k=p.k, d=d)
    if bad:  # break all three bounds: a steep first surface, a squeezed gap, a steep r⁴
        p = eqx.tree_at(lambda q: (q.c, q.d, q.a), p,
                        (p.c.at[0].set(1.2), p.d.at[2].set(0.1), p.a.at[1, 0].set(0.5)))
    return pm, p


def _args(samp, scale=3.0, pin=0.5, beta=0.4, reg=(2.0, 3.0, 5.0)):
    st = curriculum.Stage("t", SMALL.fov, SMALL.fnum, 1, beta=beta, pin=pin)
    a = curriculum.stage_args(SMALL, st, jnp.asarray([[0.2, 0.3, 0.5]]), reg, jnp.float64)
    a = jax.tree.map(lambda x: x[0], a)
    return eqx.tree_at(lambda q: q.spot_scale, a, jnp.asarray(scale))


def test_launch_aims_every_field_at_the_entrance_pupil():
    pm, p = _design(bad=False)
    lens = pm.to_lens(p)
    samp = losses.RayLoss.make(3, 2, (0.5, 0.6), SMALL.sensor_size, jnp.float64)
    args = _args(samp)
    rays = losses.launch(lens, samp, args)
    K, W, P = 3, 2, samp.pupil.shape[0]
    assert rays.origin.shape == (K, W, P, 3)
    tan = np.asarray(samp.fracs) * float(args.tan_max)
    d = np.stack([np.zeros(K), tan, np.ones(K)], -1) / np.sqrt(1 + tan**2)[:, None]
    np.testing.assert_allclose(rays.direction, np.broadcast_to(d[:, None, None], (K, W, P, 3)),
                               rtol=1e-12)
    np.testing.assert_allclose(rays.origin[..., :2],
                               np.broadcast_to(np.asarray(samp.pupil) * float(args.epd) / 2,
                                               (K, W, P, 2)), rtol=1e-12)
    np.testing.assert_allclose(rays.origin[..., 2], 0.0)  # stop first: the pupil is at z = 0
    np.testing.assert_allclose(rays.wavelength, np.broadcast_to([[0.5], [0.6]], (K, W, P)))


@eqx.filter_jit
def _parts(p, pm, samp, args, gb):
    """Each part of the design loss, computed on its own."""
    lens = pm.to_lens(p)
    rays = losses.launch(lens, samp, args)
    path = jaxlens.trace_path(lens, rays, uniform=True)
    spot = losses.spot_errors(path, samp, args)
    stack = stacked_surfaces(lens.surfaces)
    radii = regularizers.clear_radii(path)
    regs = jnp.stack([
        jnp.sum(regularizers.obliquity(stack, lens.vertex_z(), lens.stop, rays, path) ** 2),
        jnp.sum(regularizers.spacing(lens, stack, radii, gb) ** 2),
        jnp.sum(regularizers.slope(stack, lens.stop, radii) ** 2),
    ])
    return spot, regs


def test_design_residuals_are_spot_pin_and_weighted_regularizers():
    pm, p = _design()
    samp = losses.RayLoss.make(3, 2, SMALL.wavelengths, SMALL.sensor_size, jnp.float64)
    args = _args(samp)
    gb = jnp.asarray(init.gap_bounds(SMALL))
    residuals = eqx.filter_jit(losses.design_residuals)
    res, aux = residuals(p, pm, samp, args, gb)
    spot, regs = _parts(p, pm, samp, args, gb)
    spot, regs = jax.tree.map(np.asarray, spot), np.asarray(regs)
    assert np.all(regs > 1e-6)  # all three bounds are broken
    np.testing.assert_allclose(aux.regs, regs, rtol=1e-9)
    w = np.array([0.2, 0.3, 0.5])
    spot_term = 3.0 * np.sum(w * np.asarray(spot.ms))
    pin_term = float(spot.pin) ** 2
    assert pin_term > 1e-6
    want = spot_term + pin_term + 2.0 * regs[0] + 3.0 * regs[1] + 5.0 * regs[2]
    np.testing.assert_allclose(aux.loss, want, rtol=1e-9)
    np.testing.assert_allclose(jnp.sum(res**2), want, rtol=1e-9)
    np.testing.assert_allclose(aux.spot, np.sum(np.asarray(samp.area) * np.asarray(spot.ms)),
                               rtol=1e-12)
    np.testing.assert_allclose(aux.rms, np.sqrt(np.asarray(spot.ms)), rtol=1e-12)
    np.testing.assert_allclose(aux.valid_fraction, spot.valid_fraction)
    # Zero regularizer weights leave the spot and pin only.
    r0, _ = residuals(p, pm, samp, _args(samp, reg=(0.0, 0.0, 0.0)), gb)
    np.testing.assert_allclose(jnp.sum(r0**2), spot_term + pin_term, rtol=1e-9)
