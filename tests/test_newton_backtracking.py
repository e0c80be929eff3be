"""``newton_2d``'s damped Newton (``halvings`` > 0) as one loop of evaluations.

Each evaluation is the residual and its Jacobian at one point, so the residual function is
traced twice (the loop's forward-mode pass and the implicit step's residual) instead of four
times (the iteration's Jacobian, the trials' residual, the Jacobian at the root, the implicit
step): the aiming of every ray compiles about a quarter less. The iterates must be those of
the plain algorithm, an outer loop of Newton steps with an inner loop of halved trials,
written out here in numpy as the reference (to rounding; against the former loops the
aimed rays of the library were checked bit for bit, CHANGELOG).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.imaging.newton import newton_2d


def _fn(x, p):
    """arctan valleys (plain Newton overshoots), invalid beyond |x − p| = 5 or on a strip."""
    r = jnp.arctan(x - p) + 0.1 * jnp.sin(3.0 * x[::-1])
    ok = jnp.all(jnp.abs(x - p) < 5.0) & ~((x[0] > 1.2) & (x[0] < 1.4))
    return r, ok


def _reference(x0, p, iters, tol, halvings, max_step):
    """The damped Newton as nested loops, in numpy (float64), with the library's step rule."""
    fn = jax.jit(_fn)
    jac = jax.jit(jax.jacfwd(lambda x, p: _fn(x, p)[0]))

    def ev(x):
        f, ok = fn(x, p)
        return np.asarray(f), bool(ok)

    def step(x, f):
        j = np.asarray(jac(x, p))
        det = j[0, 0] * j[1, 1] - j[0, 1] * j[1, 0]
        det = 1.0 if det == 0 else det
        inv = np.array([[j[1, 1], -j[0, 1]], [-j[1, 0], j[0, 0]]]) / det
        dx = -(inv @ f)
        n = np.sqrt(np.sum(dx * dx))
        return dx * min(1.0, max_step / (n if n > 0 else 1.0))

    x = np.asarray(x0, np.float64)
    f, ok = np.full(2, np.inf), False
    i = 0
    while i < iters and not (i > 0 and ok and np.max(np.abs(f)) <= tol):
        f, ok = ev(x)
        dx = step(x, f)
        merit = np.sqrt(np.sum(f * f)) if ok else np.inf
        t, k = 1.0, 0
        while True:
            ft, okt = ev(x + t * dx)
            if k == 0:
                f1, ok1 = ft, okt
            if (okt and np.sqrt(np.sum(ft * ft)) < merit) or k >= halvings:
                break
            t, k = 0.5 * t, k + 1
        if not ok and not okt:
            t, ft, okt = 1.0, f1, ok1
        x, f, ok, i = x + t * dx, ft, okt, i + 1
    return x


@pytest.mark.parametrize("start, iters, halvings", [
    ((3.0, -3.0), 30, 8),  # overshooting valleys: halvings needed
    ((8.5, 7.0), 30, 8),  # an invalid start: the full (limited) step
    ((1.0, 0.0), 30, 2),  # the invalid strip in the way, few halvings
    ((3.0, -3.0), 2, 8),  # stopped by the iteration count
    ((3.0, -3.0), 0, 8),  # no iteration: x0
])
def test_the_damped_newton_takes_the_plain_algorithms_iterates(start, iters, halvings):
    p = jnp.array([0.5, -1.0])
    x0 = p + jnp.asarray(start)
    got = newton_2d(_fn, x0, p, iters, tol=1e-13, halvings=halvings, max_step=2.0,
                    has_valid=True, implicit_gradient=False)
    want = _reference(x0, p, iters, 1e-13, halvings, 2.0)
    # numpy's and XLA's roundings differ (5e-15 here); another path would differ by O(1).
    np.testing.assert_allclose(np.asarray(got), want, rtol=0, atol=1e-12)


def test_the_residual_is_traced_twice():
    """Before: four times (a copy of ``fn`` each in the compiled program)."""
    calls = []

    def fn(x, p):
        calls.append(1)
        return _fn(x, p)

    p = jnp.array([0.5, -1.0])
    jax.jit(lambda q: newton_2d(fn, q + 3.0, q, 30, tol=1e-13, halvings=8,
                                has_valid=True)).lower(p)
    assert len(calls) == 2


def test_the_implicit_gradient_is_unchanged():
    """The implicit step takes the Jacobian carried from the last trial: the root's dx/dp
    against central differences of the root."""
    p = jnp.array([0.5, -1.0])

    def root(q):
        return newton_2d(_fn, q + jnp.array([3.0, -3.0]), q, 40, tol=1e-14, halvings=8,
                         max_step=2.0, has_valid=True)

    jac = np.asarray(jax.jacrev(root)(p))
    h = 1e-6
    fd = np.stack([(np.asarray(root(p + h * e)) - np.asarray(root(p - h * e))) / (2 * h)
                   for e in np.eye(2)], -1)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-8)


def test_plain_newton_with_the_implicit_step_traces_the_residual_twice():
    """The undamped path (the distortion maps' aiming): its iterations, then one more
    evaluation whose Jacobian the implicit step takes, instead of a separate Jacobian pass at
    the root (before: three copies of ``fn``). Same result as the iterations and the
    implicit step written out."""
    calls = []

    def fn(x, p):
        calls.append(1)
        return jnp.arctan(x - p) + 0.1 * jnp.sin(3.0 * x[::-1])

    p = jnp.array([0.5, -1.0])
    x0 = p + 0.3
    jax.jit(lambda q: newton_2d(fn, x0, q, 6)).lower(p)
    assert len(calls) == 2
    got = newton_2d(fn, x0, p, 6)
    x = x0
    for _ in range(7):  # six steps and the implicit one
        x = x - jnp.linalg.solve(jax.jacfwd(fn)(x, p), fn(x, p))
    np.testing.assert_allclose(np.asarray(got), np.asarray(x), rtol=0, atol=1e-14)
