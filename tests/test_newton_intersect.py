"""The Newton iterations of ``tracing.step.intersect`` past its fixed steps
(``continue_newton``): where they stop, when a ray gives up, and that the common case is left
as it was.

A ray's iterate is accepted once |F(t)| and the next step |F/F'| are both at most
NEWTON_TOL·sqrt(eps)·(1 + |t|) (``converged``); the
extra steps run only on the rays not yet accepted, each stopping at the first accepted
iterate, and give up (a miss) where the step does not shrink. References: Newton's iteration
written out step by step here, on functions whose roots are known.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.tracing import step
from jaxlens.tracing.step import (
    NEWTON_EXTRA_ITERS,
    continue_newton,
    converged,
    intersect,
    settled,
    unmark,
)

DELTA = 1e-8  # F(t) = (t − 1)² − DELTA: two roots 1 ± 1e-4, nearly a double one


def near_double(t):
    """F and F' of (t − 1)² − DELTA: Newton from the left halves the distance to 1 per step
    until it is near the root 1 − 1e-4, so a start far away needs many steps."""
    return (t - 1.0) ** 2 - DELTA, 2.0 * (t - 1.0)


def no_root(t):
    """F and F' of (t − 1)² + 1, which has no real root."""
    return (t - 1.0) ** 2 + 1.0, 2.0 * (t - 1.0)


def _newton_reference(residual, t, limit=200):
    """Newton's iteration one step at a time (float64 scalars) with ``continue_newton``'s
    rule: (the iterate where it stops, the steps to it, the steps to the first iterate that
    is ``converged``). It stops at the first ``settled`` iterate: ``converged`` and with a
    next step of at most eps^(3/4)·(1 + |t|)."""
    first = None
    for k in range(limit):
        f, df = residual(jnp.asarray(t))
        if bool(converged(f, df, jnp.asarray(t))) and first is None:
            first = k
        if abs(float(f)) <= np.finfo(np.float64).eps ** 0.75 * (1 + abs(t)) * abs(float(df)):
            assert first is not None
            return t, k, first
        t = float(t - f / df)
    raise AssertionError("no accepted iterate")


def test_the_iteration_stops_at_the_tolerance():
    starts = np.array([-30.0, -3.0, 0.5, 1.0 - 1e-4])  # the last one is a root already
    want = [_newton_reference(near_double, s) for s in starts]
    steps = [k for _, k, _ in want]
    assert steps[0] > 10 and steps[1] > 5 and steps[-1] == 0  # slow rays and a converged one
    got = np.asarray(jax.jit(lambda t: continue_newton(near_double, t)[0])(jnp.asarray(starts)))
    np.testing.assert_allclose(got, [t for t, _, _ in want], rtol=1e-15, atol=0)
    assert got[-1] == starts[-1]  # a settled start is returned bit for bit
    # The first accepted iterate (|F| ≤ 64·sqrt(eps)·(1 + |t|), about 2e-6 here) is still
    # 1e-3 from the root, F' being small at this near-double root: it goes on to the root.
    for _, k, first in want[:3]:
        assert k > first
    np.testing.assert_allclose(got[:3], 1.0 - 1e-4, rtol=0, atol=1e-14)
    # One step fewer than the slowest ray needs leaves it unsettled; the others are settled.
    short = continue_newton(near_double, jnp.asarray(starts), max_iters=steps[0] - 1)[0]
    assert np.all(np.asarray(short)[1:] == got[1:]) and np.asarray(short)[0] != got[0]
    f_s, df_s = near_double(short)
    assert not bool(settled(f_s, df_s, short)[0])


def test_without_a_root_the_iteration_gives_up_early_and_is_not_accepted():
    starts = jnp.array([-3.0, 0.2, 7.0, 40.0])
    out = continue_newton(no_root, starts)[0]
    f, df = no_root(out)
    assert not bool(jnp.any(converged(f, df, out)))
    # It gave up long before the cap: eight allowed steps end where forty do.
    np.testing.assert_array_equal(np.asarray(continue_newton(no_root, starts, max_iters=8)[0]),
                                  np.asarray(out))
    assert NEWTON_EXTRA_ITERS >= 32


def test_an_ordinary_asphere_is_intersected_as_without_the_extra_steps(monkeypatch):
    """cellphone6's aspheres (conics −224 … 147, terms to A12), every ray of a wide fan: every
    iterate is settled after the fixed steps, so the result is the one without the extra
    steps, bit for bit."""
    lens = jl.zoo.cellphone6()
    rng = np.random.default_rng(1)
    m = 400
    o = (jnp.asarray(rng.uniform(-1.5, 1.5, m)), jnp.asarray(rng.uniform(-1.5, 1.5, m)),
         jnp.full(m, -0.4))
    v = np.stack([rng.uniform(-0.6, 0.6, m), rng.uniform(-0.6, 0.6, m), np.ones(m)])
    v /= np.linalg.norm(v, axis=0)
    d = tuple(jnp.asarray(x) for x in v)
    surfaces = [s for s in lens.surfaces if s.has_polynomial]
    assert len(surfaces) == 12
    surfaces = surfaces[::3]  # four of them (op by op, each costs a second)
    with_extra = [np.asarray(intersect(s, o, d)) for s in surfaces]
    bare = continue_newton
    monkeypatch.setattr(step, "continue_newton",
                        lambda r, t, p=lambda t: t, max_iters=0: bare(r, t, p, 0))
    for s, t in zip(surfaces, with_extra, strict=True):
        t0 = np.asarray(intersect(s, o, d))
        np.testing.assert_array_equal(t, t0)
        assert unmark(jnp.asarray(t))[1].sum() > m // 2  # mostly hits: not a vacuous check


@pytest.mark.parametrize("dtype", [pytest.param(jnp.float32, marks=pytest.mark.slow),
                                   jnp.float64])
def test_the_extra_steps_work_under_jit_vmap_and_forward_and_reverse_mode(dtype):
    """A ray that the fixed steps leave short of the root (``test_toroid_extreme``'s y0 = 3.5 mm,
    toward the axis, on a cylinder of 80 /mm): jit, vmap over the coefficient, grad and
    jacfwd agree, in float32 and float64."""
    from jaxlens.optics.toroidal import Toroidal

    o = (jnp.asarray(0.066, dtype), jnp.asarray(3.5, dtype), jnp.asarray(-2.3, dtype))
    v = np.array([0.025, -0.28 - 0.05 * 3.5, 1.0])
    d = tuple(jnp.asarray(x, dtype) for x in v / np.linalg.norm(v))

    def t_of(a1):
        s = Toroidal(c=jnp.asarray(0.01, dtype), k=jnp.asarray(0.0, dtype),
                     coeffs=jnp.stack([a1]), cx=jnp.asarray(0.0, dtype))
        return intersect(s, o, d)

    a1 = jnp.asarray(80.0, dtype)
    t = t_of(a1)  # op by op: the reference
    assert t.dtype == dtype and abs(float(t)) < 1e3  # a hit, not the MISS marker
    a1s = jnp.asarray([79.0, 80.0, 81.0], dtype)

    # The transformed versions in one compiled program (op by op, each eager call of the
    # while loops compiled them again: 255 programs, 17 s of CPU).
    @jax.jit
    def transformed(a1, a1s):
        return (t_of(a1), jax.vmap(t_of)(a1s), jax.grad(t_of)(a1), jax.jacfwd(t_of)(a1),
                jax.jvp(t_of, (a1,), (jnp.ones_like(a1),))[1])

    jitted, mapped, g, jf, tangent = transformed(a1, a1s)
    assert float(jitted) == pytest.approx(float(t), rel=10 * float(jnp.finfo(dtype).eps))
    # Each member of the vmap against its own call (op by op for the first: ``t`` above).
    one = jax.jit(t_of)
    np.testing.assert_allclose(np.asarray(mapped), [float(one(a)) for a in a1s],
                               rtol=10 * float(jnp.finfo(dtype).eps))
    np.testing.assert_allclose(float(mapped[1]), float(t), rtol=10 * float(jnp.finfo(dtype).eps))
    assert np.isfinite(float(g)) and float(g) != 0.0
    assert float(jf) == pytest.approx(float(g), rel=10 * float(jnp.finfo(dtype).eps))
    assert float(tangent) == pytest.approx(float(g), rel=10 * float(jnp.finfo(dtype).eps))
