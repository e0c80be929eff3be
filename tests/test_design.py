"""Unit tests of jaxlens.design: schedule, spec validation, regularizers, mask, solvers, tracer."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.design import curriculum, init, losses, mask, regularizers, solvers
from jaxlens.design.params import LensParams
from jaxlens.design.spec import DesignSpec
from jaxlens.tracing.forward import stacked_surfaces

SPEC = DesignSpec()


# --- curriculum schedule ------------------------------------------------------------------


def test_sine_path_paper_schedule():
    # Four stages (N = 3) from 47.5°/F2.8 to 80.8°/F2.0.
    fnum = curriculum.sine_path(2.8, 2.0, 3)
    fov = curriculum.sine_path(47.5, 80.8, 3)
    # The paper's F-numbers 2.8 → 2.4 → 2.1 → 2.0.
    np.testing.assert_allclose(np.round(fnum, 1), [2.8, 2.4, 2.1, 2.0])
    np.testing.assert_allclose(fnum, 2.8 - 0.8 * np.sin(np.arange(4) * np.pi / 6), rtol=1e-12)
    # FoV endpoints are the paper's; the sine path in angle gives 64.15° and 76.34° between
    # them (the paper lists 62.8° and 74.1°, measured on its evolving lens; see curriculum).
    np.testing.assert_allclose(fov[[0, -1]], [47.5, 80.8])
    np.testing.assert_allclose(fov[1:3], [47.5 + 33.3 * 0.5, 47.5 + 33.3 * math.sqrt(3) / 2])
    assert np.all(np.diff(fov) > 0) and np.all(np.diff(np.diff(fov)) < 0)  # fast, then slow


def test_paper_stages():
    stages = curriculum.paper_stages(SPEC, n=3, steps=10, final_steps=20, polish_steps=5)
    assert [round(s.fnum, 1) for s in stages[:4]] == [2.8, 2.4, 2.1, 2.0]
    assert stages[3].fov == pytest.approx(80.8) and stages[0].fov == pytest.approx(47.5)
    assert [s.solver for s in stages] == ["adam"] * 5 + ["lm"]
    assert stages[4].mask and stages[4].beta == 1.0 and not stages[0].mask
    flat = curriculum.paper_stages(SPEC, n=3, steps=10, curriculum=False, regularize=False)
    assert all(s.fov == 80.8 and s.fnum == 2.0 and not s.regularize for s in flat)


# --- spec validation ----------------------------------------------------------------------


def test_spec_convention():
    assert SPEC.focal_length == pytest.approx(3.83 / math.tan(math.radians(40.4)))
    assert SPEC.focal_length == pytest.approx(4.50, abs=0.005)
    assert SPEC.epd == pytest.approx(SPEC.focal_length / 2.0)
    h, w = SPEC.sensor_size
    assert math.hypot(h, w) == pytest.approx(7.66)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(total_track=0.5, bfl=0.8), "not longer than the back focal length"),
        (dict(total_track=3.0), "cannot hold 6 elements"),
        (dict(n_elements=1, materials=("E48R",), fnum=1.0, total_track=5.0), "faster than"),
        (dict(n_elements=2, materials=("E48R", "OKP4"), fov=120.0, fnum=2.0), "more than 2"),
        (dict(fov=180.0), r"fov must be a finite number in \(0, 180\) deg"),
        (dict(fnum=-1.0), r"fnum must be a finite number in \[0.5, 64\]"),
        (dict(materials=("E48R",) * 5), "need 6 materials"),
        (dict(materials=("E48R",) * 5 + ("NOT-A-GLASS",)), "NOT-A-GLASS"),
        (dict(stop=9), r"stop must be a whole number in \[0, 6\]"),
    ],
)
def test_spec_rejects_impossible(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DesignSpec(**kwargs)


def test_cli_rejects_spec_before_compute(capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--track", "0.5", "--bfl", "0.8"]) == 2
    assert "back focal length" in capsys.readouterr().err


# --- geometry helpers ---------------------------------------------------------------------


def test_gap_kinds_and_bounds():
    kinds = init.gap_kinds(SPEC)
    assert kinds[0] == "stop" and kinds[-1] == "back"
    assert kinds[1:12] == ("glass", "air") * 5 + ("glass",)
    b = init.gap_bounds(SPEC)
    assert b[1] == 0.4 and b[2] == 0.2 and b[-1] == SPEC.bfl
    mid = DesignSpec(stop=2)  # two elements in front of the stop
    assert init.gap_kinds(mid)[:6] == ("glass", "air", "glass", "stop", "stop", "glass")


SMALL = DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0,
                   fov_start=30.0, fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=3)


def _design_lens(spec=SMALL, seed=3, dtype=jnp.float64, curv=0.3):
    pm = init.parameterization(spec, dtype)
    p = init.random_params(spec, jax.random.PRNGKey(seed), dtype)
    # Give it real power and aspheres so the trace is a meaningful test.
    c = curv * jnp.asarray(np.resize([1.0, -0.5, -0.8, 0.6], p.c.shape[0]), dtype)
    a = p.a.at[:, 0].set(0.02 * jnp.sign(c))
    return pm, LensParams(c=c, a=a, k=p.k, d=p.d)


def test_params_roundtrip():
    pm, p = _design_lens()
    lens = pm.to_lens(p)
    assert float(lens.total_track()) == pytest.approx(SMALL.total_track)
    back = pm.from_lens(lens)
    for x, y in zip(jax.tree.leaves(back), jax.tree.leaves(p), strict=True):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-15)


def test_uniform_trace_matches_trace():
    """One scan over padded surfaces (the design loss's trace) agrees with the per-kind runs."""
    pm, p = _design_lens()
    lens = pm.to_lens(p)
    pupil = jaxlens.imaging.sampling.pupil_hexapolar(3, jnp.float64)
    rays = jaxlens.imaging.sampling.collimated(lens, 18.0, pupil)
    ref = jaxlens.trace_path(lens, rays)
    got = jaxlens.trace_path(lens, rays, uniform=True)
    assert got.origin.shape == ref.origin.shape == (lens.num_surfaces + 1, *rays.shape, 3)
    np.testing.assert_array_equal(got.valid, ref.valid)
    v = np.asarray(ref.valid)
    for field in ("origin", "direction"):
        np.testing.assert_allclose(np.asarray(getattr(got, field))[v],
                                   np.asarray(getattr(ref, field))[v], atol=1e-12)
    np.testing.assert_allclose(np.asarray(got.opl)[v], np.asarray(ref.opl)[v], atol=1e-12)
    assert np.asarray(ref[-1].valid).mean() > 0.9


# --- regularizers -------------------------------------------------------------------------


def _geometry_penalties(p, pm, radii, gb):
    lens = pm.to_lens(p)
    stack = stacked_surfaces(lens.surfaces)
    return jnp.stack([jnp.sum(regularizers.spacing(lens, stack, radii, gb) ** 2),
                      jnp.sum(regularizers.slope(stack, lens.stop, radii) ** 2)])


_geometry_jac = jax.jit(jax.jacrev(_geometry_penalties))


def _gentle(spec, dt):
    """A weak lens well inside every bound (gaps 0.1 mm over their minimum)."""
    p = init.random_params(spec, jax.random.PRNGKey(0), dt)
    d = jnp.asarray(init.gap_bounds(spec)[:-1] + 0.1, dt)
    return LensParams(c=0.2 * p.c, a=0.0 * p.a, k=p.k, d=d)


def test_spacing_and_slope_zero_inside_and_pull_back_outside():
    dt = jnp.float64
    pm = init.parameterization(SMALL, dt)
    gb = jnp.asarray(init.gap_bounds(SMALL), dt)
    radii = jnp.full((SMALL.num_surfaces,), 1.5, dt)  # about the normalisation radii
    p = _gentle(SMALL, dt)
    np.testing.assert_array_equal(np.asarray(_geometry_penalties(p, pm, radii, gb)), 0.0)
    for leaf in jax.tree.leaves(_geometry_jac(p, pm, radii, gb)):
        np.testing.assert_array_equal(np.asarray(leaf), 0.0)
    # Squeeze the air gap between the elements below 0.2 mm: the spacing penalty turns on
    # and its gradient asks to widen the gap.
    q = eqx.tree_at(lambda q: q.d, p, p.d.at[2].set(0.1))
    assert float(_geometry_penalties(q, pm, radii, gb)[0]) > 0
    assert float(_geometry_jac(q, pm, radii, gb).d[0, 2]) < 0
    # A steep r⁴ term on one surface: the slope penalty turns on and pushes it back.
    s = eqx.tree_at(lambda q: q.a, p, p.a.at[1, 0].set(0.5))
    assert float(_geometry_penalties(s, pm, radii, gb)[1]) > 0
    assert float(_geometry_jac(s, pm, radii, gb).a[1, 1, 0]) > 0


def _obliquity(c, pm, p, samp, args):
    lens = pm.to_lens(eqx.tree_at(lambda q: q.c, p, c))
    rays = losses.launch(lens, samp, args)
    path = jaxlens.trace_path(lens, rays, uniform=True)
    stack = stacked_surfaces(lens.surfaces)
    return jnp.sum(regularizers.obliquity(stack, lens.vertex_z(), lens.stop, rays, path) ** 2)


_obliquity_grad = jax.jit(jax.value_and_grad(_obliquity))


def test_obliquity_zero_inside_and_pull_back_outside():
    dt = jnp.float64
    pm = init.parameterization(SMALL, dt)
    samp = losses.RayLoss.make(2, 2, SMALL.wavelengths[1:2], SMALL.sensor_size, dt)
    st = curriculum.Stage("t", SMALL.fov, SMALL.fnum, 1)
    args = curriculum.stage_args(SMALL, st, samp.area[None], (1.0, 1.0, 1.0), dt)
    args = jax.tree.map(lambda x: x[0], args)
    p = _gentle(SMALL, dt)
    val, grad = _obliquity_grad(p.c, pm, p, samp, args)
    assert float(val) == 0.0
    np.testing.assert_array_equal(np.asarray(grad), 0.0)
    # A strongly curved first surface bends the rim rays past 45.6° from its normal.
    c = p.c.at[0].set(1.6)
    val, grad = _obliquity_grad(c, pm, p, samp, args)
    assert float(val) > 0
    assert float(grad[0]) > 0  # less curvature, less obliquity


# --- mask ---------------------------------------------------------------------------------


def test_reweighting_mask():
    rms = jnp.asarray([1.0, 2.0, 3.0, 4.0])  # mean 2.5 → normalised 0.4, 0.8, 1.2, 1.6
    np.testing.assert_allclose(mask.reweighting_mask(rms), [0.0, 0.8, 1.2, 1.6])
    # Area-weighted mean: most area on the good fields lowers the mean, keeping more fields.
    area = jnp.asarray([0.7, 0.1, 0.1, 0.1])
    m = mask.reweighting_mask(rms, area)  # mean 1.6
    np.testing.assert_allclose(m, [0.0, 2 / 1.6, 3 / 1.6, 4 / 1.6])
    np.testing.assert_allclose(mask.reweighting_mask(jnp.zeros(3)), 1.0)
    # Batched, and the loss weights: dropped fields get zero weight, the rest sum to 1.
    w = mask.field_weights(jnp.stack([rms, rms[::-1]]), jnp.full(4, 0.25), mask=True, irls=False)
    np.testing.assert_allclose(w[0], np.array([0, 0.8, 1.2, 1.6]) / 3.6 * 1.0, rtol=1e-6)
    np.testing.assert_allclose(w[1], w[0][::-1], rtol=1e-6)
    w = mask.field_weights(rms[None], jnp.full(4, 0.25), mask=False, irls=True)
    np.testing.assert_allclose(w[0] * rms, (w[0] * rms)[0], rtol=1e-6)  # w ∝ 1/RMS


# --- solvers and the design loop ----------------------------------------------------------


class _Quadratic(eqx.Module):
    """A cheap stand-in objective: residuals params − target (and a ``sampling.area``)."""

    target: LensParams
    sampling: object
    nan_above: float | None = eqx.field(static=True, default=None)  # NaN where d[0] > this

    def __call__(self, params, args):
        r = jnp.concatenate([(x - t).ravel() for x, t in zip(
            jax.tree.leaves(params), jax.tree.leaves(self.target), strict=True)])
        r = r * (1.0 + 0.5 * jnp.tanh(r))  # mildly nonlinear
        if self.nan_above is not None:
            r = jnp.where(params.d[0] > self.nan_above, jnp.nan, r)
        loss = jnp.sum(r**2)
        aux = losses.Aux(loss, loss, jnp.full((3,), jnp.sqrt(loss)), jnp.ones(3), jnp.zeros(3))
        return r, aux

    def field_rms(self, params, args):
        return self(params, args)[1].rms


class _Sampling(eqx.Module):
    area: jax.Array


def _toy(nan_above=None):
    key = jax.random.PRNGKey(1)
    p0 = LensParams(c=jnp.zeros(4), a=jnp.zeros((4, 2)), k=jnp.zeros(4), d=jnp.ones(3))
    tgt = jax.tree.map(lambda x: x + 0.3 * jax.random.normal(key, x.shape), p0)
    tgt = eqx.tree_at(lambda t: t.k, tgt, p0.k)  # k is frozen
    return p0, _Quadratic(tgt, _Sampling(jnp.full(3, 1 / 3)), nan_above)


@pytest.mark.parametrize("name", ["adam", "lm", "lm-optx", "lbfgsb"])
def test_solvers_lower_the_loss(name):
    p0, obj = _toy()
    free = LensParams(c=True, a=True, k=False, d=True)
    lrs = LensParams(c=jnp.asarray(0.05), a=jnp.asarray(0.05), k=jnp.asarray(0.0),
                     d=jnp.asarray(0.05))
    inf = jnp.inf
    make = {
        "adam": lambda: solvers.Adam(obj, lrs, free=free),
        "lm": lambda: solvers.DampedLeastSquares(obj, free=free),
        "lm-optx": lambda: solvers.LevenbergMarquardt(obj, free=free),
        "lbfgsb": lambda: solvers.LBFGSB(
            obj, jax.tree.map(lambda x: jnp.full_like(x, -inf), p0),
            jax.tree.map(lambda x: jnp.full_like(x, inf), p0), free=free),
    }[name]
    sol = make()
    args = None
    state = sol.init(p0, args)
    step = eqx.filter_jit(sol.step)
    p = p0
    for _ in range(15):
        p, state, _ = step(p, state, args, jnp.asarray(1.0))
    l0 = float(obj(p0, args)[1].loss)
    l1 = float(obj(p, args)[1].loss)
    assert l1 < 0.5 * l0
    np.testing.assert_array_equal(p.k, p0.k)  # frozen group untouched
    assert isinstance(state.result, solvers.SolverResult)


def test_least_squares_result_codes_say_when_a_step_is_rejected():
    # At the minimum no damped step lowers the loss: the step is rejected, λ grows, and at
    # the cap the code says the solver cannot make progress.
    p0, obj = _toy()
    at_min = obj.target
    sol = solvers.DampedLeastSquares(obj, free=LensParams(c=True, a=True, k=False, d=True))
    step = eqx.filter_jit(sol.step)
    state = sol.init(p0, None)
    p, state, aux = step(p0, state, None, jnp.asarray(1.0))
    assert solvers.result_names(state.result) == ["successful"]
    # The aux is the objective's at the step's start (as for every solver), not at its end.
    assert float(aux.loss) == pytest.approx(float(obj(p0, None)[1].loss), rel=1e-12)
    assert float(obj(p, None)[1].loss) < float(aux.loss)
    state = solvers.LeastSquaresState(jnp.asarray(1.0), state.result)
    _, state, _ = step(at_min, state, None, jnp.asarray(1.0))
    assert solvers.result_names(state.result) == ["rejected"]
    state = solvers.LeastSquaresState(jnp.asarray(solvers.DAMPING_MAX), state.result)
    _, state, _ = step(at_min, state, None, jnp.asarray(1.0))
    assert solvers.result_names(state.result) == ["damping_limit"]


def test_run_stops_on_nonfinite_loss():
    p0, obj = _toy(nan_above=0.0)
    params = jax.tree.map(lambda x: jnp.stack([x, x]), p0)
    stages = [curriculum.Stage("warm", 60.0, 2.4, 4), curriculum.Stage("bad", 80.8, 2.0, 4)]
    lrs = LensParams(c=jnp.asarray(0.01), a=jnp.asarray(0.01), k=jnp.asarray(0.0),
                     d=jnp.asarray(0.01))

    def make(name, lr, objective):
        return solvers.Adam(objective, lrs)

    with pytest.raises(FloatingPointError, match=r"stage 0 \(warm\) at step 0 for seed 7"):
        curriculum.run(SPEC, stages, params, obj, make, progress=False, log_every=2,
                       seeds=[7, 8])


def test_run_drops_nonfinite_designs():
    p0, obj = _toy(nan_above=1.5)
    bad = eqx.tree_at(lambda p: p.d, p0, p0.d.at[0].set(2.0))  # its loss is NaN from step 0
    params = jax.tree.map(lambda x, y: jnp.stack([x, y]), p0, bad)
    stages = [curriculum.Stage("bad", 80.8, 2.0, 3)]
    lrs = LensParams(c=jnp.asarray(0.01), a=jnp.asarray(0.01), k=jnp.asarray(0.0),
                     d=jnp.asarray(0.01))

    def make(name, lr, objective):
        return solvers.Adam(objective, lrs)

    out, hist = curriculum.run(SPEC, stages, params, obj, make, progress=False, log_every=3,
                               seeds=[3, 4], on_nonfinite="drop")
    assert list(hist.failed) == [4] and "stage 0 (bad) at step 0" in hist.failed[4]
    assert hist.results == [["successful", "nonfinite"]]
    for x, y in zip(jax.tree.leaves(out), jax.tree.leaves(params), strict=True):
        np.testing.assert_array_equal(x[1], y[1])  # frozen at the last finite parameters
    assert not np.array_equal(out.c[0], params.c[0])  # the healthy design moved on
    # When every design has failed, the run stops and names the stage and step.
    both = jax.tree.map(lambda x: jnp.stack([x, x]), bad)
    with pytest.raises(FloatingPointError, match=r"every design.*stage 0 \(bad\) at step 0"):
        curriculum.run(SPEC, stages, both, obj, make, progress=False, log_every=3,
                       seeds=[5, 6], on_nonfinite="drop")


def test_soft_hinge_is_a_hinge_near_the_bound_and_never_overflows():
    from jaxlens.design.regularizers import _soft_hinge

    x = jnp.asarray([-1.0, 0.0, 1e-3, 1e30], jnp.float32)
    h = _soft_hinge(x)
    assert h[0] == 0 and h[1] == 0
    np.testing.assert_allclose(h[2], 1e-3, rtol=1e-3)
    assert np.isfinite(np.asarray(h[3] ** 2))  # a plain hinge squared overflows float32 here
    g = jax.vmap(jax.grad(_soft_hinge))(x)
    assert g[0] == 0 and 0 < g[3] < 1e-20 and abs(g[2] - 1) < 1e-2
