"""Tolerance-aware design (``jaxlens.design.robust``): the averaged loss and its gradient."""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.design import curriculum, init, losses
from jaxlens.design.params import LensParams
from jaxlens.design.robust import RobustObjective, draw_perturbations, perturbed
from jaxlens.design.spec import DesignSpec

SMALL = DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0,
                   fov_start=30.0, fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=2)
DT = jnp.float64


def _setup():
    pm = init.parameterization(SMALL, DT)
    samp = losses.RayLoss.make(3, 2, SMALL.wavelengths, SMALL.sensor_size, DT)
    base = losses.Objective(pm, samp, jnp.asarray(init.gap_bounds(SMALL), DT))
    st = curriculum.Stage("t", SMALL.fov, SMALL.fnum, 1)
    args = curriculum.stage_args(SMALL, st, samp.area[None], (1.0, 1.0, 1.0), DT)
    args = jax.tree.map(lambda x: x[0], args)
    p = init.random_params(SMALL, jax.random.PRNGKey(0), DT)
    d = jnp.asarray(init.gap_bounds(SMALL)[:-1] + 0.1, DT)
    p = LensParams(c=0.4 * jnp.asarray([1.0, -0.6, -0.7, 0.5]), a=0.0 * p.a, k=p.k, d=d)
    draws = draw_perturbations(p.c.shape[0], p.d.shape[0], 5, radius_rel=0.02,
                               thickness=0.03, seed=1, dtype=DT)
    return base, args, p, draws


def test_robust_loss_is_the_weighted_mean_of_the_perturbed_losses():
    base, args, p, draws = _setup()
    robust = RobustObjective(base, draws, nominal_weight=0.3)
    _, aux = eqx.filter_jit(robust)(p, args)
    base_loss = eqx.filter_jit(lambda q: base(q, args)[1].loss)
    l0 = float(base_loss(p))
    one_draw = [jax.tree.map(lambda x, i=i: x[i], draws) for i in range(5)]
    lk = [float(base_loss(perturbed(p, dr))) for dr in one_draw]
    assert float(aux.loss) == pytest.approx(0.3 * l0 + 0.7 * np.mean(lk), rel=1e-12)
    assert np.std(lk) > 1e-3 * np.mean(lk)  # the draws really change the lens
    # A draw of a relative radius error ε scales the radius by 1 + ε.
    one = jax.tree.map(lambda x: x[0], draws)
    q = perturbed(p, one)
    np.testing.assert_allclose(1 / q.c, (1 / p.c) * (1 + one.radius_rel), rtol=1e-13)
    np.testing.assert_allclose(q.d - p.d, one.gap, rtol=1e-13)


def test_robust_gradient_matches_finite_differences():
    base, args, p, draws = _setup()
    # Without the regularizers: they hold the clear radii constant for the gradient by
    # design (jaxlens.design.regularizers), which finite differences do not.
    args = eqx.tree_at(lambda a: a.reg_weights, args, jnp.zeros_like(args.reg_weights))
    robust = RobustObjective(base, draws, nominal_weight=0.5)

    @jax.jit
    def loss(c):
        return robust(LensParams(c=c, a=p.a, k=p.k, d=p.d), args)[1].loss

    g = jax.jit(jax.grad(loss))(p.c)
    h = 1e-6
    for i in range(p.c.shape[0]):
        e = jnp.zeros_like(p.c).at[i].set(h)
        fd = (loss(p.c + e) - loss(p.c - e)) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-5, abs=1e-9)


def test_bad_robust_options_are_refused():
    base, _, p, draws = _setup()
    with pytest.raises(ValueError, match="nominal_weight"):
        RobustObjective(base, draws, nominal_weight=0.0)
    with pytest.raises(ValueError, match="trials"):
        draw_perturbations(4, 3, 0, radius_rel=0.01, thickness=0.01)
    with pytest.raises(ValueError, match="thickness"):
        draw_perturbations(4, 3, 2, radius_rel=0.01, thickness=-0.01)


@pytest.mark.slow  # a design run (about 30 s); the loss itself is tested above
def test_design_with_tolerance_aware_loss_runs_and_differs():
    from jaxlens.design.multistart import DesignConfig, design

    cfg = DesignConfig(n_fields=3, rings=2, curriculum_n=1, steps=3, final_steps=3,
                       polish_steps=0, epoch=3, log_every=3, float64=True)
    nominal = design(SMALL, [0], cfg, progress=False, shard=False)
    robust = design(SMALL, [0], dataclasses.replace(cfg, tolerance_trials=3), progress=False,
                    shard=False)
    assert np.all(np.isfinite(robust.params.c))
    # Same start, same steps: only the objective differs, so the designs do too.
    assert not np.allclose(robust.params.c, nominal.params.c)


def test_tolerance_aware_option_is_checked_before_work(capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--tolerance-aware", "-1", "--out", "/nonexistent/x"]) == 2
    assert "--tolerance-aware" in capsys.readouterr().err
