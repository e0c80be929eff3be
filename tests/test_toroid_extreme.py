"""The Newton intersection on an extreme toroid (Zemax TOROIDAL PARM 2 = 80 /mm: a sag of
80 mm at 1 mm height), against a brute-force root: the first sign change of
z(t) − sag(x(t), y(t)) on a fine grid of the ray parameter, bisected.

Rays that start far (in t) from the surface approach the root slowly: along a line the
cylinder's sag is convex, so F(t) = z(t) − sag is concave and Newton from before the root
climbs to it monotonically, but with a step ratio near 1 while the second root is close;
six steps (``DEFAULT_NEWTON_ITERS``) are then too few, and the ray was lost although the
root exists (the corpus4 file vendetta_optiland-0.5.8-zemax-reference.zmx: 6 of 270 rays),
until the rays not converged after them went on iterating (``step.continue_newton``).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.optics.toroidal import Toroidal
from jaxlens.tracing.step import DEFAULT_NEWTON_ITERS, intersect, unmark

C, A1 = 0.01, 80.0  # 1/mm: the profile z = C y²/(1 + sqrt(1 − C² y²)) + A1 y²
EXTREME = dict(c=C, k=0.0, coeffs=jnp.array([A1]), cx=0.0)


def _fan():
    """Rays from z = −2.3 mm (the previous surface) at heights −5…5 mm in y, a little off
    in x, with slopes toward and away from the axis: ``[m, 3]`` origins and directions."""
    y = np.linspace(-5.0, 5.0, 21)
    o, d = [], []
    for slope in (-0.28, -0.1, 0.0, 0.1, 0.28):
        for yi in y:
            v = np.array([0.025, slope - 0.05 * yi, 1.0])
            o.append([0.066, yi, -2.3])
            d.append(v / np.linalg.norm(v))
    return np.array(o), np.array(d)


def _first_root(o, d, a1=A1, t_max=2000.0, n=400_001):
    """The first forward root of F(t) = z − sag (t >= 0) on the surface's domain, or nan."""
    t = np.linspace(0.0, t_max, n)

    def f(tt):  # the swept profile written out (cx = 0: a cylinder along x)
        p = o + tt[:, None] * d
        y2 = p[:, 1] ** 2
        with np.errstate(invalid="ignore"):
            z = C * y2 / (1 + np.sqrt(1 - C * C * y2)) + a1 * y2
        return p[:, 2] - z

    v = f(t)
    s = np.sign(v)
    k = np.nonzero((s[:-1] * s[1:] <= 0) & np.isfinite(v[:-1]) & np.isfinite(v[1:]))[0]
    if not len(k):
        return np.nan
    lo, hi = t[k[0]], t[k[0] + 1]
    f_lo = f(np.array([lo]))[0]
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        f_mid = f(np.array([mid]))[0]
        if np.sign(f_mid) == np.sign(f_lo):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.fixture(scope="module")
def fan():
    surface = Toroidal(**EXTREME)
    o, d = _fan()
    roots = np.array([_first_root(oi, di) for oi, di in zip(o, d, strict=True)])
    return surface, o, d, roots


def _hits(surface, o, d, iters):
    t, ok = unmark(intersect(surface, tuple(jnp.asarray(o.T)), tuple(jnp.asarray(d.T)), iters))
    return np.asarray(t), np.asarray(ok)


def test_no_wrong_root_and_no_hit_without_a_root(fan):
    """Every intersection found is the first forward root (never a later one), and no ray
    without a root is given one, at every iteration count."""
    surface, o, d, roots = fan
    assert np.isfinite(roots).sum() > 50 and (~np.isfinite(roots)).sum() > 10  # both kinds
    for iters in (DEFAULT_NEWTON_ITERS, 12, 40):
        t, ok = _hits(surface, o, d, iters)
        assert not np.any(ok & ~np.isfinite(roots)), iters
        np.testing.assert_allclose(t[ok], roots[ok], rtol=0, atol=1e-9, err_msg=str(iters))


def test_enough_newton_steps_find_every_root(fan):
    surface, o, d, roots = fan
    t, ok = _hits(surface, o, d, 40)
    np.testing.assert_array_equal(ok, np.isfinite(roots))


def test_the_default_newton_steps_find_every_root(fan):
    """With the tracer's default iteration count, a ray is a miss only where no root exists."""
    surface, o, d, roots = fan
    t, ok = _hits(surface, o, d, DEFAULT_NEWTON_ITERS)
    np.testing.assert_array_equal(ok, np.isfinite(roots))
    np.testing.assert_allclose(t[ok], roots[ok], rtol=0, atol=1e-9)


def test_the_root_of_a_slow_ray_has_the_implicit_gradient(fan):
    """dt/da_1 and dt/dy0 at the root of a ray that needs more than six Newton steps, against
    central differences of the brute-force root."""
    import jax

    surface, o, d, roots = fan
    j = 17  # y0 = 3.5 mm toward the axis: six steps from the vertex plane are too few
    assert np.isfinite(roots[j])

    def t_of(a1, y0):
        s = Toroidal(c=C, k=0.0, coeffs=jnp.stack([a1]), cx=0.0)
        oo = (jnp.asarray(o[j, 0]), y0, jnp.asarray(o[j, 2]))
        return intersect(s, oo, tuple(jnp.asarray(d[j])))

    g = jax.grad(t_of, argnums=(0, 1))(jnp.asarray(A1), jnp.asarray(o[j, 1]))
    assert float(t_of(jnp.asarray(A1), jnp.asarray(o[j, 1]))) == pytest.approx(roots[j],
                                                                               abs=1e-9)
    h = 1e-6
    up, down = (_first_root(o[j], d[j], a1=A1 + e) for e in (h, -h))
    shift = np.array([0.0, h, 0.0])
    dy = (_first_root(o[j] + shift, d[j]) - _first_root(o[j] - shift, d[j])) / (2 * h)
    assert float(g[0]) == pytest.approx((up - down) / (2 * h), rel=1e-5)
    assert float(g[1]) == pytest.approx(dy, rel=1e-5)


def test_the_reverse_rule_takes_the_slow_rays_as_the_step_does(fan):
    """``surface_adjoint.sag_step`` (the hand-written reverse rule) against ``surface_step``
    on the fan refracted into glass: values bit for bit (the slow rays and the misses too) and
    gradients in the coefficient, the curvature and the rays' heights equal."""
    import equinox as eqx
    import jax

    import jaxlens as jl
    from jaxlens.tracing import surface_adjoint
    from jaxlens.tracing.step import RayState, state_from_rays, surface_step

    surface, o, d, roots = fan
    st = state_from_rays(jl.Rays(jnp.asarray(o), jnp.asarray(d), 0.55))
    n1, n2 = jnp.asarray(1.0), jnp.asarray(1.5)
    assert surface_adjoint.supported(surface)

    def both(a1, c, y0):
        s = eqx.tree_at(lambda x: (x.coeffs, x.c), surface, (jnp.stack([a1]), c))
        st2 = RayState((st.p[0], y0, st.p[2]), st.d, st.valid, st.opl)
        kw = dict(first=False, refracts=True, gap=jnp.asarray(2.3), newton_iters=6)
        return (surface_adjoint.sag_step(s, jnp.asarray(0.0), st2, n1, n2, **kw),
                surface_step(s, jnp.asarray(0.0), st2, n1, n2, **kw))

    args = (jnp.asarray(A1), jnp.asarray(C), st.p[1])
    a, b = both(*args)
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(np.asarray(a.valid), np.isfinite(roots))

    def loss(which):
        def f(*args):
            out = both(*args)[which]
            w = jnp.where(out.valid, 1.0, 0.0)
            return jnp.sum(w * (out.p[1] ** 2 + out.d[1] + out.opl))
        return jax.jit(jax.grad(f, argnums=(0, 1, 2)))

    ga, gb = loss(0)(*args), loss(1)(*args)
    for x, y in zip(ga, gb, strict=True):
        np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=1e-10, atol=1e-12)
