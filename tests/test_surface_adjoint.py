"""The hand-written reverse rules of the surface step (``tracing.surface_adjoint``).

``trace(reverse_rule=True)`` moves plane, sphere and conic surfaces with
``surface_adjoint.conic_step`` and surfaces with polynomial terms with ``sag_step``; the
reference is the same trace with ``step.surface_step``
everywhere (the default), whose derivative JAX takes itself. Values must be bit-identical,
gradients equal to rounding, and forward mode must refuse the rule clearly.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.optics.qtype import QTypeAsphere
from jaxlens.optics.toroidal import Toroidal
from jaxlens.tracing import forward, surface_adjoint
from jaxlens.tracing.step import RayState, state_from_rays, surface_step


def _trace(lens, rays, reverse_rule, path=False):
    """(origin, direction, valid, opl) on the image (every surface's if ``path``)."""
    states = forward._trace_states(lens, rays, 6, None, keep_path=path, uniform=False,
                                   reverse_rule=reverse_rule)
    if path:
        states = [jax.tree.map(lambda *x: jnp.stack(x), *states)]
    st = states[-1]
    return jnp.stack(st.p, -1), jnp.stack(st.d, -1), st.valid, st.opl


def _folded():
    """A singlet, a dummy plane 10 mm after it and a gap of -10 mm back (Zemax allows it)."""
    bk7 = jl.get_material("N-BK7")
    return jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.02), jl.Plane()),
                   thickness=jnp.array([5.0, 55.0, -10.0]),
                   materials=(bk7, jl.Air(), jl.Air()), epd=10.0)


def _rays(lens, n, scale, seed=0, per_ray_wl=False):
    """Rays over ``scale`` × the pupil at 80 % field (scale > 1: some are clipped), with
    some invalid on entry; per-ray wavelengths if asked."""
    pupil = scale * jl.sampling.pupil_random(jax.random.PRNGKey(seed), n, jnp.float64)
    r = jl.sampling.collimated(lens, 0.8 * float(lens.fields[-1]), pupil)
    wl = jnp.linspace(0.49, 0.65, n) if per_ray_wl else r.wavelength
    return jl.Rays(r.origin, r.direction, wl, jnp.arange(n) % 11 != 5)


def _freeform():
    """Every kind ``sag_step`` takes: an odd asphere with a cone term (a kink on the axis),
    a hybrid with odd x, y terms, a toroid and a tilted plane."""
    glass = jl.ModelGlass(1.6, 40.0)
    return jl.Lens(
        surfaces=(jl.Sphere(0.03),
                  jl.OddAsphere(c=-0.01, k=0.0, coeffs=jnp.array([2e-3, 3e-3, -1e-4])),
                  jl.Hybrid(c=0.02, k=-0.5, coeffs=jnp.array([1e-4, -1e-6]),
                            odd_x=jnp.array([1e-5]), odd_y=jnp.array([2e-5])),
                  Toroidal(c=-0.02, k=0.2, coeffs=jnp.array([1e-4]), cx=-0.015),
                  jl.TiltedPlane(tan_x=0.01, tan_y=-0.02), jl.Plane()),
        thickness=jnp.array([4.0, 3.0, 5.0, 3.0, 2.0, 40.0]),
        materials=(glass, jl.Air(), glass, jl.Air(), glass, jl.Air()), epd=8.0)


CASES = {
    "cooke": lambda: jl.zoo.cooke_triplet(),
    "double_gauss": lambda: jl.zoo.double_gauss(),
    "folded": _folded,
    "cellphone6": lambda: jl.zoo.cellphone6(),
    "freeform": _freeform,
}


def _loss(out):
    """Spot size, direction and optical path of the valid rays: every output leaf counts."""
    o, d, v, opl = out
    w = v.astype(o.dtype)
    nv = jnp.sum(w)
    c = jnp.sum(w[:, None] * o[:, :2], 0) / nv
    spot = jnp.sum(w * jnp.sum((o[:, :2] - c) ** 2, -1)) / nv
    return spot + jnp.sum(w * (d[:, 0] + 0.3 * d[:, 1])) / nv + 1e-3 * jnp.sum(w * opl) / nv


@pytest.fixture(scope="module")
def compiled():
    """One compiled trace, path and value-and-gradient per setting of ``reverse_rule``."""
    fns = {}
    for hand in (True, False):
        fns["trace", hand] = jax.jit(lambda lens, rays, h=hand: _trace(lens, rays, h))
        fns["path", hand] = jax.jit(lambda lens, rays, h=hand: _trace(lens, rays, h, True))
        fns["grad", hand] = jax.jit(jax.value_and_grad(
            lambda lens, rays, h=hand: _loss(_trace(lens, rays, h))))
    return fns


@pytest.mark.parametrize("case, scale, per_ray_wl", [
    # Spheres and planes with per-ray wavelengths (so per-ray indices) in CI: the folded
    # singlet (a negative gap too). The Cooke triplet has the same step kinds, and
    # test_public_entry_points_and_forward_mode takes it through the rule in CI (CI time).
    pytest.param("cooke", 1.3, True, marks=pytest.mark.slow), ("folded", 1.2, True),
    # 12 even aspheres: the kind test_design_loss_gradient_with_and_without_the_rule takes
    # through the rule in CI (CI time).
    pytest.param("cellphone6", 1.1, False, marks=pytest.mark.slow),
    # Every sag kind: test_polynomial_gradient_matches_central_differences takes the same lens
    # through the rule in CI (CI time: 36 s).
    pytest.param("freeform", 1.1, True, marks=pytest.mark.slow),
    # 11 surfaces with a flat stop: the same step kinds as the Cooke triplet's (CI time).
    pytest.param("double_gauss", 0.999, False, marks=pytest.mark.slow)])
def test_values_and_gradients_match_the_library_step(compiled, case, scale,
                                                                per_ray_wl):
    lens = CASES[case]()
    rays = _rays(lens, 257, scale, per_ray_wl=per_ray_wl)
    for kind in ("trace", "path"):
        new, old = compiled[kind, True](lens, rays), compiled[kind, False](lens, rays)
        for a, b in zip(new, old, strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    v = np.asarray(compiled["trace", True](lens, rays)[2])
    assert 0 < v.sum() < v.size  # some rays are lost (on entry at least)
    (ln, gn), (lo, go) = compiled["grad", True](lens, rays), compiled["grad", False](lens, rays)
    assert float(ln) == pytest.approx(float(lo), rel=1e-14)  # fused differently under AD
    checked = 0
    # Each leaf to 1e-10 of its largest entry; leaves that are rounding noise (a flat
    # surface's k, say, ~1e-18) to 1e-14 of the largest gradient.
    top = max(float(np.max(np.abs(b), initial=0.0)) for b in jax.tree.leaves(go))
    for a, b in zip(jax.tree.leaves(gn), jax.tree.leaves(go), strict=True):
        a, b = np.asarray(a), np.asarray(b)
        scl = float(np.max(np.abs(b), initial=0.0))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * scl + 1e-14 * top)
        checked += bool(np.any(b != 0))
    assert checked >= 5


def test_public_entry_points_and_forward_mode():
    """grad through ``trace(reverse_rule=True)`` (chunked) equals the default's; the path of
    ``trace_path(uniform=True, reverse_rule=True)`` (the design loss's trace) is identical;
    jvp refuses the rule with a TypeError, and the default trace keeps forward mode."""
    lens = jl.zoo.cooke_triplet()
    rays = _rays(lens, 200, 1.1)

    def loss(L, rr):
        out = jl.trace(L, rays, chunk=64, reverse_rule=rr)
        return jnp.sum(jnp.where(out.valid, out.origin[:, 1] ** 2 + out.opl, 0.0))

    grad = jax.jit(jax.grad(loss), static_argnums=1)
    g, g_ref = grad(lens, True), grad(lens, False)
    for a, b in zip(jax.tree.leaves(g), jax.tree.leaves(g_ref), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)
    path_of = jax.jit(lambda L, rr: jl.trace_path(L, rays, uniform=True, reverse_rule=rr),
                      static_argnums=1)  # one compile each, not op by op
    path, ref = path_of(lens, True), path_of(lens, False)
    for a, b in zip(jax.tree.leaves(path), jax.tree.leaves(ref), strict=True):
        np.testing.assert_array_equal(a, b)

    def curv(c, rr):
        L = eqx.tree_at(lambda x: x.surfaces[2].c, lens, c)
        return jl.trace(L, rays, reverse_rule=rr).origin[:, :2]

    c0 = lens.surfaces[2].c
    assert np.all(np.isfinite(jax.jacfwd(curv)(c0, False)))
    with pytest.raises(TypeError, match="custom_vjp"):
        jax.jvp(lambda c: curv(c, True), (c0,), (jnp.ones_like(c0),))
    with pytest.raises(TypeError, match="reverse_rule must be True or False"):
        jl.trace(lens, rays, reverse_rule="yes")


def test_gradient_matches_central_differences(compiled):
    lens = _folded()
    rays = _rays(lens, 300, 1.2)
    # The loss and its gradient from the one compiled value-and-gradient program (a jitted
    # loss and jax.grad of it compiled three programs).
    g = compiled["grad", True](lens, rays)[1]

    def fn(L):
        return compiled["grad", True](L, rays)[0]
    for get, j, h in ((lambda L: L.surfaces[0].c, None, 1e-7),
                      (lambda L: L.surfaces[1].c, None, 1e-7),
                      (lambda L: L.thickness, 0, 1e-6),
                      (lambda L: L.thickness, 1, 1e-6)):
        def at(dx, get=get, j=j):
            new = get(lens) + dx if j is None else get(lens).at[j].add(dx)
            return float(fn(eqx.tree_at(get, lens, new)))

        fd = (at(h) - at(-h)) / (2 * h)
        ad = float(get(g) if j is None else get(g)[j])
        assert ad == pytest.approx(fd, rel=2e-6, abs=1e-9)


def _floats(st):
    return [x for x in jax.tree.leaves(st) if x.dtype != bool]


@pytest.mark.parametrize("first, refracts", [(True, True), (False, True), (False, False)])
def test_one_step_equals_surface_step(first, refracts):
    """The step alone, including a ray behind a negative gap, a clipped one and TIR."""
    glass = jl.ModelGlass(1.5, 60.0)
    surface = jl.Conic(-0.04, -0.5, semi_diameter=6.0)
    o = jnp.array([[0.0, 0.0, -3.0], [0.3, 1.0, 2.0], [0.0, 7.0, -1.0], [0.0, 5.9, -1.0]])
    d = jnp.array([[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0], [0.0, 0.8, 0.6]])
    st = state_from_rays(jl.Rays(o, d, 0.55))
    n1, n2 = glass.index(0.55), jnp.asarray(1.0)
    assert surface_adjoint.supported(surface)
    assert not surface_adjoint.supported(surface, reflects=True)
    assert surface_adjoint.supported(jl.EvenAsphere(c=0.01))
    assert not surface_adjoint.supported(jl.EvenAsphere(c=0.01, coeffs=jnp.zeros(0)))
    assert not surface_adjoint.supported(ParaxialSurface(focal_length=50.0))

    def both(c, z, gap):
        s = eqx.tree_at(lambda x: x.c, surface, c)
        kw = dict(first=first, refracts=refracts, gap=None if first else gap)
        a = surface_adjoint.conic_step(s, z, st, n1, n2, **kw)
        b = surface_step(s, z, st, n1, n2, newton_iters=6, **kw)
        return a, b

    # One compiled Jacobian for both gaps (the gap an argument, not a constant of a new
    # function per gap: that compiled it twice).
    jac = jax.jit(jax.jacrev(lambda c, z, gap: (_floats(both(c, z, gap)[0]),
                                                _floats(both(c, z, gap)[1])), argnums=(0, 1)))
    for gap in (jnp.asarray(-4.0), jnp.asarray(2.0)):
        a, b = both(surface.c, jnp.asarray(1.0), gap)
        assert isinstance(a, RayState)
        for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
            np.testing.assert_array_equal(x, y)
        ja, jb = jac(surface.c, jnp.asarray(1.0), gap)
        for x, y in zip(jax.tree.leaves(ja), jax.tree.leaves(jb), strict=True):
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-13)


def test_a_ray_at_the_critical_angle_has_finite_equal_gradients():
    """A ray leaving glass of index 1.25 through a plane at exactly the critical angle
    (direction (0, 0.8, 0.6): nn − mu²(nn − dn²) = 0 in floating point). The square root's
    slope is infinite there; both steps take it as zero, so the gradients are finite and
    agree. Op by op (no jit), so no fused multiply-add moves the ray off the critical angle."""
    plane = jl.Plane()
    o = jnp.array([[0.0, 0.0, -1.0]])
    d = jnp.array([[0.0, 0.8, 0.6]])
    n2 = jnp.asarray(1.0)

    def out(step, d, n1):
        st = state_from_rays(jl.Rays(o, d, 0.55))
        kw = dict(first=False, refracts=True, gap=jnp.asarray(1.0))
        if step is surface_step:
            kw["newton_iters"] = 6
        new = step(plane, jnp.asarray(0.0), st, n1, n2, **kw)
        return jnp.stack(new.d, -1), new.opl

    with jax.disable_jit():
        n1 = jnp.asarray(1.25)
        (d_out, _), (d_ref, _) = out(surface_adjoint.conic_step, d, n1), out(surface_step, d, n1)
        np.testing.assert_array_equal(d_out, d_ref)
        assert float(d_ref[0, 2]) == 0.0  # refracted along the surface: the critical angle
        jac = {s: jax.jacrev(lambda d, n1, s=s: out(s, d, n1), argnums=(0, 1))(d, n1)
               for s in (surface_adjoint.conic_step, surface_step)}
    for a, b in zip(jax.tree.leaves(jac[surface_adjoint.conic_step]),
                    jax.tree.leaves(jac[surface_step]), strict=True):
        assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)


def test_polynomial_gradient_matches_central_differences(compiled):
    """The sag rule's gradient in coefficients of every kind against central differences."""
    lens = _freeform()
    rays = _rays(lens, 300, 1.1)
    # One compiled program for the loss and its gradient, as in the test above.
    g = compiled["grad", True](lens, rays)[1]

    def fn(L):
        return compiled["grad", True](L, rays)[0]
    for get, j, h in ((lambda L: L.surfaces[1].coeffs, 0, 1e-7),
                      (lambda L: L.surfaces[1].c, None, 1e-7),
                      (lambda L: L.surfaces[2].odd_y, 0, 1e-7),
                      (lambda L: L.surfaces[2].k, None, 1e-6),
                      (lambda L: L.surfaces[3].cx, None, 1e-7),
                      (lambda L: L.surfaces[4].tan_y, None, 1e-7),
                      (lambda L: L.thickness, 2, 1e-6)):
        def at(dx, get=get, j=j):
            new = get(lens) + dx if j is None else get(lens).at[j].add(dx)
            return float(fn(eqx.tree_at(get, lens, new)))

        fd = (at(h) - at(-h)) / (2 * h)
        ad = float(get(g) if j is None else get(g)[j])
        assert ad != 0.0
        assert ad == pytest.approx(fd, rel=2e-6, abs=1e-9)


@pytest.mark.slow  # 16 s of compilation; the rule is checked on the other surface kinds in CI
def test_qtype_aspheres_take_the_rule_with_equal_values_and_gradients(compiled):
    """Forbes Q-bfs (on a conic) and Q-con surfaces go through ``sag_step``: values
    identical to ``surface_step``'s, gradients equal to rounding and, in a coefficient of
    each, to central differences."""
    glass = jl.ModelGlass(1.6, 40.0)
    lens = jl.Lens(
        surfaces=(QTypeAsphere(c=0.04, k=-0.7, coeffs=jnp.array([0.05, -0.02, 0.01]),
                               norm_radius=5.0),
                  QTypeAsphere(c=-0.01, k=0.3, coeffs=jnp.array([2e-3, -1e-3]),
                               norm_radius=5.0, qtype="con")),
        thickness=jnp.array([4.0, 30.0]), materials=(glass, jl.Air()), epd=8.0,
        fields=jnp.array([0.0, 5.0]))
    assert all(surface_adjoint.supported(s) for s in lens.surfaces)
    rays = _rays(lens, 200, 1.05)
    for a, b in zip(compiled["trace", True](lens, rays), compiled["trace", False](lens, rays),
                    strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    (_, gn), (_, go) = compiled["grad", True](lens, rays), compiled["grad", False](lens, rays)
    for a, b in zip(jax.tree.leaves(gn), jax.tree.leaves(go), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-10, atol=1e-14)
    for i, j, h in ((0, 0, 1e-7), (0, 2, 1e-7), (1, 1, 1e-7)):
        def at(dx, i=i, j=j):
            L = eqx.tree_at(lambda t: t.surfaces[i].coeffs, lens,
                            lens.surfaces[i].coeffs.at[j].add(dx))
            return float(compiled["grad", True](L, rays)[0])  # the loss of the program above

        fd = (at(h) - at(-h)) / (2 * h)
        ad = float(gn.surfaces[i].coeffs[j])
        assert ad != 0.0
        assert ad == pytest.approx(fd, rel=2e-6, abs=1e-9)


@pytest.mark.parametrize("first, refracts", [(True, True), (False, True), (False, False)])
def test_one_sag_step_equals_surface_step(first, refracts):
    """``sag_step`` alone on an odd asphere with a cone term: a ray on the axis (r = 0,
    where the cone's slope is cut off), one behind a negative gap, one clipped, one at TIR
    and one invalid on entry; values identical, Jacobians equal."""
    glass = jl.ModelGlass(1.5, 60.0)
    surface = jl.OddAsphere(c=-0.04, k=-0.5, coeffs=jnp.array([0.05, 2e-3, -1e-3]),
                            semi_diameter=6.0)
    o = jnp.array([[0.0, 0.0, -3.0], [0.3, 1.0, 2.0], [0.0, 7.0, -1.0], [0.0, 5.0, -1.0],
                   [0.2, 0.1, -1.0]])
    d = jnp.array([[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0], [0.0, 0.8, 0.6],
                   [0.0, 0.0, 1.0]])
    st = state_from_rays(jl.Rays(o, d, 0.55, jnp.array([True] * 4 + [False])))
    n1, n2 = glass.index(0.55), jnp.asarray(1.0)

    def both(coeffs, z, gap):
        s = eqx.tree_at(lambda x: x.coeffs, surface, coeffs)
        kw = dict(first=first, refracts=refracts, gap=None if first else gap, newton_iters=6)
        return (surface_adjoint.sag_step(s, z, st, n1, n2, **kw),
                surface_step(s, z, st, n1, n2, **kw))

    # Values and Jacobians each one compiled program for both gaps (op by op, the Newton
    # loops of the two steps compiled anew at every call; a new function per gap compiled
    # the Jacobian twice).
    value = jax.jit(both)
    jac = jax.jit(jax.jacrev(lambda c, z, gap: (_floats(both(c, z, gap)[0]),
                                                _floats(both(c, z, gap)[1])), argnums=(0, 1)))
    for gap in (jnp.asarray(-4.0), jnp.asarray(2.0)):
        a, b = value(surface.coeffs, jnp.asarray(1.0), gap)
        for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
            np.testing.assert_array_equal(x, y)
        if refracts and not first:
            assert not bool(a.valid[3])  # TIR leaving the glass
        ja, jb = jac(surface.coeffs, jnp.asarray(1.0), gap)
        for x, y in zip(jax.tree.leaves(ja), jax.tree.leaves(jb), strict=True):
            assert np.all(np.isfinite(x))
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-13)


@pytest.mark.slow  # 17 s: the design loss compiled twice; the rule itself is checked in CI
def test_design_loss_gradient_with_and_without_the_rule():
    """The design loss (uniform trace of the stacked even aspheres) with the rule: the same
    value and gradient; the solver factory gives it to Adam and L-BFGS-B, not to LM."""
    from jaxlens.design import curriculum, init, losses, multistart

    spec, config = jl.design.DesignSpec(), multistart.DesignConfig()
    dt = jnp.float64
    pmap = init.parameterization(spec, dt)
    sampling = losses.RayLoss.make(config.n_fields, 2, spec.wavelengths, spec.sensor_size, dt)
    objective = losses.Objective(pmap, sampling, jnp.asarray(init.gap_bounds(spec), dt))
    params = jax.tree.map(lambda x: x[0], init.random_starts(spec, [3], dt))
    stage = config.stages(spec)[0]
    args = curriculum.stage_args(spec, stage, jnp.ones((1, config.n_fields), dt),
                                 config.reg_weights, dt)
    args = jax.tree.map(lambda x: x[0], args)  # one seed
    fast = losses.reverse_mode({"ray": objective})["ray"]
    assert fast.reverse_rule and not objective.reverse_rule

    def vg(obj):
        return jax.jit(jax.value_and_grad(lambda p: jnp.sum(obj(p, args)[0] ** 2)))(params)

    (l1, g1), (l0, g0) = vg(fast), vg(objective)
    assert float(l1) == pytest.approx(float(l0), rel=1e-14)
    for a, b in zip(jax.tree.leaves(g1), jax.tree.leaves(g0), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-13 * float(np.max(np.abs(b))))
    make = multistart.make_solver_factory(config, spec, dt)
    assert make("adam", 1.0, objective).residual_fn.reverse_rule
    assert make("lbfgsb", 1.0, objective).residual_fn.reverse_rule
    assert not make("lm", 1.0, objective).residual_fn.reverse_rule
