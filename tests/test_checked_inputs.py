"""Compiled cores whose entry points checked their inputs skip the re-checks
(``jaxlens.optics.checked_inputs``): no ``eqx.error_if`` (a host callback, which JAX's
persistent cache refuses) in a program called with concrete inputs, and every check still
fires where a user's own ``jit`` traces the inputs, whichever program was compiled first.

Each call below uses shapes no other test compiles (odd pupil sizes), so that it is traced
here and the ``error_if`` calls made while tracing can be counted."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import spots
from jaxlens.optics import checks
from jaxlens.optics.checked_inputs import checked_by_caller, checked_core


@pytest.fixture(scope="module")
def lens():
    return jl.load("jaxlens/data/lenses/cooke_triplet.json")


@pytest.fixture
def error_ifs(monkeypatch):
    """The messages of the ``eqx.error_if`` calls made from now on."""
    seen, real = [], eqx.error_if

    def record(x, pred, msg):
        seen.append(msg)
        return real(x, pred, msg)

    monkeypatch.setattr(eqx, "error_if", record)
    return seen


def _pupil(n, seed):
    r = np.sqrt(np.random.default_rng(seed).uniform(0, 1, n))
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return jnp.asarray(np.stack([r * np.cos(a), r * np.sin(a)], -1))


def test_concrete_calls_trace_no_input_check(lens, error_ifs):
    spots.rms_spot(lens, jnp.array([0.0, 5.0, 10.0]), pupil=_pupil(13, 0))
    spots.spot_rays(lens, jnp.asarray(7.0), pupil=_pupil(11, 1))
    spots.distortion(lens, jnp.array([1.0, 2.0, 3.0, 4.0, 5.0]))
    spots.clear_semi_diameters(lens, n_rim=37)
    spots.semi_diameters_and_fans(lens, jnp.array([0.0, 4.0, 14.0]), _pupil(9, 2), n_rim=39)
    assert error_ifs == []


def test_traced_inputs_are_checked_after_the_concrete_program_is_cached(lens, error_ifs):
    pupil = _pupil(15, 3)
    good = spots.rms_spot(lens, jnp.array([0.0, 10.0]), pupil=pupil)  # the trusting program
    assert np.all(np.isfinite(np.asarray(good.polychromatic))) and error_ifs == []
    run = jax.jit(lambda f: spots.rms_spot(lens, f, pupil=pupil).polychromatic)
    with pytest.raises(Exception, match="finite angles"):
        run(jnp.array([0.0, jnp.nan])).block_until_ready()
    assert error_ifs
    run_w = jax.jit(lambda w: spots.rms_spot(lens, wavelengths=w, pupil=pupil).polychromatic)
    with pytest.raises(Exception, match="µm"):
        run_w(jnp.array([587.6])).block_until_ready()  # nm for µm


def test_concrete_bad_inputs_still_raise_at_once(lens):
    with pytest.raises(ValueError, match="finite angles"):
        spots.rms_spot(lens, [0.0, np.nan])
    with pytest.raises(ValueError, match="fan_fields"):  # before: only the core's error_if
        spots.semi_diameters_and_fans(lens, jnp.array([0.0, 120.0]), jnp.zeros((2, 2)))
    with pytest.raises(ValueError, match="pupil"):
        spots.semi_diameters_and_fans(lens, jnp.array([0.0, 10.0]),
                                      jnp.array([[0.0, np.nan], [0.0, 0.5]]))


def test_trace_checks_its_wavelengths_whatever_was_compiled_before(lens):
    pupil = _pupil(17, 4)
    spots.rms_spot(lens, jnp.array([10.0]), pupil=pupil)  # traces ``trace`` trusted inside
    rays = jl.sampling.field_rays(lens, 10.0, pupil)
    bad = eqx.tree_at(lambda r: r.wavelength, rays, jnp.asarray(587.6, rays.origin.dtype))
    with pytest.raises(Exception, match="µm"):
        jax.block_until_ready(jl.trace(lens, bad))


SEEN = []  # (where, checked_by_caller) while the toy core below is traced


def _angle(x):
    return checks.field_angles(x, "probe")


@jax.jit
def _nested(x):
    return _angle(x) * 2.0


@checked_core(jax.jit)
def _core(x):
    SEEN.append(("body", checked_by_caller(x)))
    jax.vmap(lambda v: SEEN.append(("vmap", checked_by_caller(v))) or v)(x)
    return _angle(x) + 0.0 * jnp.sum(jax.vmap(_angle)(x))


@checked_core(jax.jit)
def _core_with_nested_jit(x):
    return _nested(x)


def test_only_the_body_of_a_core_called_with_checked_inputs_is_trusted(error_ifs):
    x = jnp.array([1.0, 2.0])
    SEEN.clear()
    np.testing.assert_allclose(_core(x), x)
    assert SEEN == [("body", True), ("vmap", True)] and error_ifs == []
    # A jit nested in a trusting body is traced apart and keeps its check ...
    np.testing.assert_allclose(_core_with_nested_jit(x), 2 * x)
    assert len(error_ifs) == 1
    # ... so the program cached there still checks where it is called on its own.
    with pytest.raises(Exception, match="finite angles"):
        _nested(jnp.array([jnp.nan, 1.0])).block_until_ready()
    # Traced by the caller's own jit, the core keeps every check.
    SEEN.clear()
    with pytest.raises(Exception, match="finite angles"):
        jax.jit(_core)(jnp.array([95.0, 1.0])).block_until_ready()
    assert SEEN == [("body", False), ("vmap", False)]


def test_checked_by_caller_is_false_outside_any_core():
    assert not checked_by_caller(jnp.ones(2))
    flags = []
    jax.jit(lambda v: flags.append(checked_by_caller(v)) or v)(jnp.ones(2))
    assert flags == [False]


def test_a_design_with_the_ray_loss_compiles_its_steps_without_input_checks(error_ifs):
    """The design steps skip the trace's re-check of the loss's wavelengths, which ``run``
    checks concretely against the fixed materials first."""
    from jaxlens import design as D

    cfg = D.DesignConfig(n_fields=3, rings=1, steps=3, final_steps=3, polish_steps=0,
                         epoch=3, log_every=3)
    res = D.design(D.DesignSpec(), [0], cfg, progress=False, shard=False)
    assert not any("wavelength" in m for m in error_ifs), error_ifs
    assert np.all(np.isfinite(np.asarray(res.history.loss[-1])))


def test_the_design_checks_the_loss_wavelengths_before_any_step(monkeypatch):
    from jaxlens.design import curriculum, multistart
    from jaxlens.design import design as run_design
    from jaxlens.design.spec import DesignSpec

    seen = {}

    def capture(spec, stages, params, objectives, *a, **k):
        seen.update(objectives)
        raise KeyboardInterrupt  # stop before any step

    monkeypatch.setattr(multistart, "run", capture)
    cfg = multistart.DesignConfig(n_fields=3, rings=1, steps=3, final_steps=3, polish_steps=0)
    with pytest.raises(KeyboardInterrupt):
        run_design(DesignSpec(), [0], cfg, progress=False, shard=False)
    ray = seen["ray"]
    assert curriculum._loss_inputs_checked(ray)
    # The plastics' data end at 0.4 µm: a loss at 0.38 µm is refused before the steps (it
    # was an error from inside the first compiled step).
    bad = eqx.tree_at(lambda o: o.sampling.wavelengths, ray, jnp.array([0.38, 0.55]))
    with pytest.raises(ValueError, match="run: the loss's wavelengths"):
        curriculum._loss_inputs_checked(bad)
    # Any other objective, or a solver that is not the library's, keeps the checks.
    assert not curriculum._loss_inputs_checked((ray,))
    adam = multistart.make_solver_factory(cfg, DesignSpec(), jnp.float64)("adam", 1.0, ray)
    assert curriculum._solver_inputs_checked(adam)

    class Mine(eqx.Module):
        residual_fn: object

    assert not curriculum._solver_inputs_checked(Mine(ray))


@pytest.fixture
def traced_error_ifs(monkeypatch):
    """The messages of the ``eqx.error_if`` calls traced into a compiled program from now on
    (eager ones run at once and are no callback in a program)."""
    seen, real = [], eqx.error_if

    def record(x, pred, msg):
        if checks.is_traced((x, pred)):
            seen.append(msg)
        return real(x, pred, msg)

    monkeypatch.setattr(eqx, "error_if", record)
    return seen


def test_imaging_cores_called_with_checked_inputs_trace_no_input_check(lens, traced_error_ifs):
    """psf (its chief-ray aiming, a jit of its own), psf_map (vmapped eagerly before),
    relative_illumination, the distortion maps and the PSF render method kept re-checks of
    the fields and wavelengths in their compiled programs, which the cache then refused."""
    from jaxlens.imaging import distortion, psf, radiometry, render

    sensor = jl.Sensor((26, 38), 0.6)
    lens_s = eqx.tree_at(lambda m: m.sensor, lens, sensor, is_leaf=lambda x: x is None)
    psf.psf(lens, 7.5, kernel_size=13, pixel_size=0.0047)
    psf.psf_map(lens, grid=(2, 3), kernel_size=11, sensor=sensor)
    radiometry.relative_illumination(lens, jnp.array([3.0, 6.0, 9.0, 12.0, 15.0]), pupil=41)
    distortion.distortion_map(lens, grid=(3, 5), sensor=sensor)
    distortion.inverse_distortion_map(lens, resolution=(26, 38), pixel_size=0.6, grid=(3, 4))
    scene = jnp.asarray(np.random.default_rng(0).random((26, 38, 3)), jnp.float32)
    render.render(lens_s, scene, method=render.PSFRender(kernel_size=7), spp=1,
                  key=jax.random.PRNGKey(0))
    assert traced_error_ifs == []


def test_the_chief_ray_core_keeps_its_checks_under_a_users_jit(lens):
    from jaxlens.imaging.aiming import stop_chief_ray

    stop_chief_ray(lens, 6.25)  # the trusting program first
    run = jax.jit(lambda f: stop_chief_ray(lens, f).origin)
    with pytest.raises(Exception, match="finite angles"):
        jax.block_until_ready(run(jnp.asarray(jnp.nan)))


@pytest.mark.parametrize(
    "polish",
    ["lm", pytest.param("lm-optx", marks=pytest.mark.slow),
     pytest.param("lbfgsb", marks=pytest.mark.slow)],
)
def test_the_polish_step_traces_no_input_check(polish, traced_error_ifs):
    """The polish solvers make their objective inside the step (optimistix's and jaxopt's
    loops nest it, the damped least squares scans it): each is trusted as the step, so the
    polish program has no host callback and the persistent cache keeps it."""
    from jaxlens import design as D

    cfg = D.DesignConfig(n_fields=3, rings=1, steps=2, final_steps=0, polish_steps=2,
                         polish=polish, epoch=2, log_every=2)
    res = D.design(D.DesignSpec(), [0], cfg, progress=False, shard=False)
    assert not any("wavelength" in m for m in traced_error_ifs), traced_error_ifs
    assert np.all(np.isfinite(np.asarray(res.history.loss[-1])))


def test_trusted_within_trusts_only_inside_a_checked_core(error_ifs):
    def angle(x):
        return checks.field_angles(x, "probe")

    assert checks.trusted_within(angle, jnp.ones(2)) is angle  # concrete: nothing to trust
    seen = []

    def looped(f, x):  # loops and branches nest f's traces below the core's body
        return jax.lax.fori_loop(0, 2, lambda i, y: jax.lax.cond(i > 0, f, f, y), x)

    @checked_core(jax.jit)
    def core(x):
        f = checks.trusted_within(angle, x)
        seen.append(f is angle)
        return looped(f, x)

    @checked_core(jax.jit)
    def core_untrusting(x):
        return looped(angle, x)

    x = jnp.array([1.0, 2.0])
    np.testing.assert_allclose(core(x), x)
    assert seen == [False] and error_ifs == []
    np.testing.assert_allclose(core_untrusting(x), x)  # the nested traces kept their checks
    assert error_ifs
    # Under a user's jit the core is not trusted: the wrapper is the function itself.
    with pytest.raises(Exception, match="finite angles"):
        jax.block_until_ready(jax.jit(core)(jnp.array([1.0, jnp.nan])))
    assert seen[-1] is True
