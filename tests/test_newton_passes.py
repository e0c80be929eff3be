"""The residual (sag) passes of ``tracing.step``'s Newton search: ``continue_newton`` hands
back F and F' at its final iterates, carried through its loop, so its callers
(``_polynomial_root``, ``first_of_a_pair``) do not evaluate them again.

References: F evaluated directly at the returned iterates (equal bit for bit) and Newton's
iteration written out step by step.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxlens.tracing.step import continue_newton

DELTA = 1e-8


def near_double(t):
    """F and F' of (t − 1)² − DELTA (roots 1 ± 1e-4): from far away Newton halves the
    distance per step, so these rays iterate many times."""
    return (t - 1.0) ** 2 - DELTA, 2.0 * (t - 1.0)


def newton(t, steps):
    """``steps`` plain Newton steps, one at a time (float64 scalars)."""
    for _ in range(steps):
        f, df = near_double(jnp.asarray(t))
        t = float(t - f / df)
    return t


STARTS = jnp.asarray([-30.0, -3.0, 0.5, 1.0 - 1e-4])  # the last one is settled already


def test_continue_newton_returns_the_residual_at_its_final_iterates():
    run = jax.jit(continue_newton, static_argnums=(0, 2, 3))
    for max_iters in (1, 3, 40):
        t, f, df = run(near_double, STARTS, lambda t: t, max_iters)
        f_at, df_at = jax.jit(near_double)(t)
        # Carried F, F' are those of the returned t: a stale (start's) F fails this.
        np.testing.assert_array_equal(np.asarray(f), np.asarray(f_at))
        np.testing.assert_array_equal(np.asarray(df), np.asarray(df_at))
        assert float(t[-1]) == float(STARTS[-1])  # a settled ray is left as it was
        if max_iters < 40:  # the unsettled rays took exactly max_iters Newton steps
            for i in range(2):
                np.testing.assert_allclose(float(t[i]), newton(float(STARTS[i]), max_iters),
                                           rtol=1e-15, atol=0)
    assert abs(float(t[0]) - float(STARTS[0])) > 30  # the loop ran: the slow ray moved
    np.testing.assert_allclose(np.asarray(t[:3]), 1.0 - 1e-4, rtol=0, atol=1e-14)
