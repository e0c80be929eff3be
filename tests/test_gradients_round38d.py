"""Round 38d: gradients against central differences (float64) of the render, the dispersion
formulas round 37e did not cover, the design regularizers at a finished design, the EDoF
PSF loss and the image objective. ``tools/grad38d_probe.py`` is the audit these come from."""

import dataclasses
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics import materials as mt
from jaxlens.optics import paraxial

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def _central(f, x, h):
    """Central differences of a scalar function of a vector, per element."""
    return np.array([(f(x.at[j].add(h[j])) - f(x.at[j].add(-h[j]))) / (2 * h[j])
                     for j in range(x.shape[0])])


# ---------------------------------------------------------------------------------- glass
_FORMULAS = {
    "herzberger": (mt.Herzberger, [1.5, 0.004, 1e-4, -0.002, 1e-4, -1e-6]),
    "sellmeier2": (mt.Sellmeier2, [0.0, 1.2, 0.1, -0.01, 3.0]),
    "conrady": (mt.Conrady, [1.49, 0.005, 4e-4]),
    "handbook1": (mt.Handbook1, [2.27, 0.01, 0.02, 0.01]),
    "handbook2": (mt.Handbook2, [1.0, 1.25, 0.01, 0.01]),
    "sellmeier4": (mt.Sellmeier4, [1.0, 1.2, 0.01, 0.05, 100.0]),
    "extended2": (lambda c: mt.Laurent(c, powers=mt.EXTENDED2_POWERS),
                  [2.9, -0.012, 0.03, 8e-4, -4e-5, 3e-6, 1e-4, -1e-5]),
}


@pytest.mark.parametrize("name", sorted(_FORMULAS))
def test_dispersion_formula_coefficients_efl_gradient(name):
    """EFL of a singlet at 0.55 µm (off the d line, so every term counts) with respect to
    each coefficient of a Zemax formula kind round 37e did not reach (the audit also traced
    image points, and the catalog's Extended, Extended 3, five-term Sellmeier and
    HullMaterials logits: all within 4e-7 of differences)."""
    make, c0 = _FORMULAS[name]
    c0 = jnp.asarray(c0)

    def efl(c):
        lens = jl.Lens((jl.Sphere(1 / 30), jl.Sphere(-1 / 40)), jnp.array([4.0, 40.0]),
                       (make(c), jl.Air()), stop=0, epd=8.0, fields=jnp.array([0.0, 8.0]))
        return paraxial.efl(lens, 0.55)

    g = jax.jit(jax.grad(efl))(c0)
    fd = _central(jax.jit(efl), c0, np.maximum(1e-4 * np.abs(np.asarray(c0)), 1e-7))
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-7 * np.max(np.abs(fd)))


# --------------------------------------------------------------------------------- render
def _render_setup():
    from jaxlens import zoo
    from jaxlens.imaging import render as R
    from jaxlens.imaging.psf import RGB_WAVELENGTHS

    lens = dataclasses.replace(zoo.cooke_triplet(), sensor=jl.Sensor((4, 4), 3.0))
    fp = R.footprints(lens, wavelengths=RGB_WAVELENGTHS)
    yy, xx = np.mgrid[0:4, 0:4] / 3.0
    scene = jnp.asarray(np.stack([0.2 + xx, 0.5 + 0.3 * yy, 0.1 + xx + yy], -1))
    wmap = jnp.asarray(np.random.default_rng(0).uniform(0.5, 1.5, (4, 4, 3)))
    return lens, R.RayRender(footprints=fp), scene, wmap


@pytest.mark.slow  # three render compiles of the Cooke triplet (~40 s on 2 cores)
def test_render_gradient_matches_differences_with_fixed_samples():
    """The ray render's gradient in a curvature and the back focus, with the PRNG key and
    the footprints fixed (the held quantities), an affine scene (bilinear interpolation of
    it is exact: no kinks) and a linear functional. Well-posed: a uniform scene with
    relative illumination is Σ valid·πr², a step function of the lens, and it is equal at
    x ± h bit for bit, so no ray changes validity in the step and the function is smooth
    there. Central differences then agree to 1e-7 (the audit: 2e-9); the checkpointed and
    non-checkpointed gradients agree to rounding, and ``jvp`` with ``grad``."""
    lens, method, scene, wmap = _render_setup()
    key = jax.random.PRNGKey(1)
    x0 = jnp.array([float(lens.surfaces[0].c), float(lens.thickness[5])])

    def with_x(x):
        return eqx.tree_at(lambda L: (L.surfaces[0].c, L.thickness),
                           lens, (x[0], lens.thickness.at[5].set(x[1])))

    def f(x, ckpt=True, img=scene):
        out = jl.render(with_x(x), img, spp=4, key=key, method=method, checkpoint=ckpt,
                        patch=8)
        return jnp.sum(wmap * out)

    h = np.array([1e-6, 1e-3])
    ones = jnp.ones_like(scene)
    cert = jax.jit(lambda x: jl.render(with_x(x), ones, spp=4, key=key, method=method,
                                       patch=8))
    base = np.asarray(cert(x0))
    for j in range(2):
        for s in (-1, 1):
            assert np.array_equal(np.asarray(cert(x0.at[j].add(s * h[j]))), base)
    g = jax.jit(jax.grad(f))(x0)
    fj = jax.jit(f)
    fd = _central(fj, x0, h)
    np.testing.assert_allclose(g, fd, rtol=1e-7)
    g2 = jax.jit(jax.grad(lambda x: f(x, ckpt=False)))(x0)
    np.testing.assert_allclose(g, g2, rtol=1e-12)
    jv = jax.jit(lambda t: jax.jvp(f, (x0,), (t,))[1])
    np.testing.assert_allclose([jv(jnp.eye(2)[j]) for j in range(2)], g, rtol=1e-12)


# ----------------------------------------------------------------------------- regularizers
def _design(finished):
    """The classical experiment's objective at its last stage with the regularizers on, and
    the parameters of a random start (seed 0) or of the finished design seed_0.zmx."""
    from jaxlens.design import curriculum, init, losses, multistart

    spec, config = jl.design.DesignSpec(), multistart.DesignConfig()
    dt = jnp.float64
    pmap = init.parameterization(spec, dt)
    sampling = losses.RayLoss.make(config.n_fields, 2, spec.wavelengths, spec.sensor_size, dt)
    objective = losses.Objective(pmap, sampling, jnp.asarray(init.gap_bounds(spec), dt))
    if finished:
        lens = jl.load(os.path.join(ROOT, "experiments/classical/designs/seed_0.zmx"))
        surf = tuple(
            jl.EvenAsphere(s.c, s.k, jnp.pad(s.coeffs, (0, pmap.n_terms + 1 - s.coeffs.shape[0])))
            if i in pmap.optical else s for i, s in enumerate(lens.surfaces))
        params = pmap.from_lens(dataclasses.replace(lens, surfaces=surf))
        pmap = dataclasses.replace(pmap, template=dataclasses.replace(
            pmap.template, materials=lens.materials))
        objective = dataclasses.replace(objective, pmap=pmap)
    else:
        params = jax.tree.map(lambda x: x[0], init.random_starts(spec, [0], dt))
    stage = config.stages(spec)[-1]
    args = curriculum.stage_args(spec, stage, jnp.ones((1, config.n_fields), dt),
                                 config.reg_weights, dt)
    return objective, params, jax.tree.map(lambda x: x[0], args)


def _radii(objective, params, args):
    from jaxlens.design import losses, regularizers
    from jaxlens.tracing.forward import trace_path

    lens = objective.pmap.to_lens(params)
    path = trace_path(lens, losses.launch(lens, objective.sampling, args), uniform=True)
    return regularizers.clear_radii(path)


@pytest.mark.slow  # the design objective's compile (~20 s per lens on 2 cores)
@pytest.mark.parametrize("finished", [False, True], ids=["random_start", "seed_0_design"])
def test_design_loss_with_regularizers_gradient_matches_differences(finished, monkeypatch):
    """The classical design loss (last stage, regularizers on with the experiment's weights)
    at a random start and at the finished design seed_0 (where the obliquity, spacing and
    slope penalties are all active): with the clear radii frozen at x (the code holds them
    without gradient, documented in ``regularizers``; left live, the differences move them
    and disagree by up to 100 %), ``grad`` is that of the function the differences see. The
    audit found c, a, d within 2e-8 and k within 5e-7 (steps 1e-2 … 1e-4 for k)."""
    from jax.flatten_util import ravel_pytree

    from jaxlens.design import regularizers

    objective, params, args = _design(finished)
    radii = np.asarray(_radii(objective, params, args))
    monkeypatch.setattr(regularizers, "clear_radii",
                        lambda path: jnp.asarray(radii, path.origin.dtype))
    x0, unravel = ravel_pytree(params)
    marks = dataclasses.replace(jax.tree.map(jnp.zeros_like, params), k=jnp.ones_like(params.k))
    is_k = np.asarray(ravel_pytree(marks)[0]) > 0

    def loss(x):
        return jnp.sum(objective(unravel(x), args)[0] ** 2)

    g = np.asarray(jax.jit(jax.grad(loss))(x0))
    fj = jax.jit(loss)
    idx = np.arange(0, x0.shape[0], 5)
    for j in idx:
        steps = (1e-3, 1e-4) if is_k[j] else (1e-6, 1e-7)  # best of two (truncation, noise)
        err = min(abs(g[j] - float((fj(x0.at[j].add(h)) - fj(x0.at[j].add(-h))) / (2 * h)))
                  for h in steps)
        assert err <= 1e-6 * abs(g[j]) + 1e-9 * np.max(np.abs(g)), (j, g[j], err)
    # the three penalties are live at the finished design (so their hinges are exercised)
    regs = np.asarray(objective(params, args)[1].regs)
    active = regs > 0
    assert active.all() if finished else active[:2].all(), regs


# ------------------------------------------------------------------------------------ EDoF
@pytest.mark.slow  # PSFs of the EDoF lens through a hybrid surface (~30 s compile)
def test_edof_psf_loss_gradient_in_odd_coefficients():
    """The EDoF loss ω1·L_sim + ω2·L_raw of simulated patches through ``patch_psfs`` (fixed
    key, polar pupil grid strictly inside the stop: no ray changes validity) with respect
    to the hybrid surface's odd coefficients (x³, x⁵, x⁷ and y's) of ``HybridParams``:
    within 1e-7 of central differences (the audit: 5e-11, and c, k, even, focus 4e-10)."""
    from jaxlens.experiments.edof import lenses as el
    from jaxlens.experiments.edof import losses as elo
    from jaxlens.experiments.edof import optics as eo

    lens = el.to_hybrid(el.classical_lens(binning=16), n_odd=3, cubic=0.0)
    pmap = el.HybridParameterization.of(lens)
    p0 = pmap.from_lens(lens)
    tile, ks = 4, 9
    n = tile + ks - 1
    windows = jnp.asarray(np.random.default_rng(3).uniform(0, 1, (2, n, n, 3)))
    xy = jnp.array([[0.0, 0.0], [1.2, -0.8]])
    depths = jnp.array([300.0, 1500.0])
    key = jax.random.PRNGKey(5)
    m = (n - tile) // 2

    def loss(odd):
        p = dataclasses.replace(p0, odd_x=odd[:3], odd_y=odd[3:])
        L = pmap.to_lens(p)
        kern = eo.patch_psfs(L, jnp.tile(xy, (2, 1)), jnp.repeat(depths, 2), kernel_size=ks,
                             pixel_size=L.sensor.pixel_size, pupil=8, key=key)
        sims = eo.simulate(windows, kern.reshape((2, 2) + kern.shape[1:]))
        gt = windows[:, m:m + tile, m:m + tile]
        return elo.edof_loss(sims, sims, gt, w_sim=1.0, w_raw=0.5)[0]

    x0 = jnp.array([0.8, -0.2, 0.05, 0.7, 0.1, -0.04])
    g = jax.jit(jax.grad(loss))(x0)
    fd = _central(jax.jit(loss), x0, np.full(6, 1e-5))
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-9 * np.max(np.abs(fd)))


# --------------------------------------------------------------------------- image objective
@pytest.mark.slow  # the design objective plus a render and a distortion map (~60 s compile)
def test_image_objective_gradient_with_held_quantities_frozen(monkeypatch):
    """``ImageObjective`` (render of the pre-warped scene, alignment penalty, the ray
    objective's regularizers) at a random start on a 6 × 6 sensor. Three things are held
    without gradient by design: the pre-warp (distortion relaxation), the render's
    footprints and the clear radii. Frozen at x, the differences see the function ``grad``
    differentiates (fixed key, affine scene: bilinear interpolation of it has no kinks)
    and agree within 1e-7 (the audit: 5e-8 over c, k, d and a); ``jvp`` agrees with
    ``grad`` to rounding."""
    from jax.flatten_util import ravel_pytree

    from jaxlens.design import losses, regularizers
    from jaxlens.imaging import distortion
    from jaxlens.imaging import render as R
    from jaxlens.imaging.psf import RGB_WAVELENGTHS

    objective, params, args = _design(False)
    n = 6
    spec = jl.design.DesignSpec()
    sensor = jl.Sensor((n, n), jnp.asarray(spec.sensor_size[0] / n, jnp.float64))
    yy, xx = np.mgrid[0:n, 0:n] / (n - 1.0)
    scene = jnp.asarray(np.stack([0.2 + 0.5 * xx, 0.3 + 0.4 * yy, 0.5 + 0.2 * (xx - yy)], -1))
    io = losses.ImageObjective(objective, scene, sensor, spp=4)
    lens = objective.pmap.to_lens(params)
    stop = eqx.tree_at(lambda x: x.semi_diameter, lens.surfaces[lens.stop], 0.5 * args.epd)
    surfaces = tuple(stop if i == lens.stop else x for i, x in enumerate(lens.surfaces))
    lens = eqx.tree_at(lambda x: (x.surfaces, x.epd), lens, (surfaces, args.epd))
    warped = distortion.prewarp(lens, scene, sensor=sensor)
    fp = R.footprints(lens, sensor=sensor, wavelengths=RGB_WAVELENGTHS)
    radii = np.asarray(_radii(objective, params, args))
    monkeypatch.setattr(distortion, "prewarp", lambda *a, **k: warped)
    monkeypatch.setattr(R, "_compute_footprints", lambda *a, **k: fp)
    monkeypatch.setattr(regularizers, "clear_radii",
                        lambda path: jnp.asarray(radii, path.origin.dtype))
    x0, unravel = ravel_pytree(params)

    def loss(x):
        return jnp.sum(io(unravel(x), args)[0] ** 2)

    g = np.asarray(jax.jit(jax.grad(loss))(x0))
    fj = jax.jit(loss)
    for j in range(0, x0.shape[0], 11):
        # the best of two steps: the high aspheric orders curve the loss enough that h = 1e-6
        # leaves a truncation error of 2e-7 (a[65]: 5.8056873 at 1e-6, 5.80568626 at 1e-7,
        # grad 5.80568627)
        err = min(abs(g[j] - float((fj(x0.at[j].add(h)) - fj(x0.at[j].add(-h))) / (2 * h)))
                  for h in (1e-6, 1e-7))
        assert err <= 1e-7 * abs(g[j]) + 1e-9 * np.max(np.abs(g)), (j, g[j], err)
    t = jnp.asarray(np.random.default_rng(1).normal(size=x0.shape))
    jv = jax.jit(lambda t: jax.jvp(loss, (x0,), (t,))[1])(t)
    np.testing.assert_allclose(jv, g @ np.asarray(t), rtol=1e-10)
