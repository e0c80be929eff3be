"""The library's one 2-D Newton solver (``newton_2d``), with an implicit-function gradient.

Used to aim rays: the chief ray at the stop centre (``aiming.stop_chief_ray``), every ray of
a beam at its stop point (``sampling.aim_at_stop``), the ideal-image map of ``distortion``
and the real-image-height fields of a ``.zmx`` file. It sits below ``sampling`` and
``aiming`` so that both import it (``aiming`` imports ``sampling``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..optics import checks


def _inverse(jac):
    """The inverse of a 2×2 Jacobian (a singular one is divided by 1, not by 0)."""
    det = jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0]
    det = jnp.where(det == 0, 1.0, det)
    return jnp.array([[jac[1, 1], -jac[0, 1]], [-jac[1, 0], jac[0, 0]]]) / det


def newton_2d(fn, x0, params, iters: int, *, implicit_gradient: bool = True, tol=None,
              max_step=None, halvings: int = 0, has_valid: bool = False, has_aux: bool = False):
    """Solve fn(x, params) = 0 for x in R² by Newton's method with an implicit gradient.

    The iterations run without gradients; one last step with the Jacobian held fixed gives
    the implicit-function derivative dx/dparams = −J⁻¹·∂fn/∂params, so reverse mode never
    unrolls the loop. In value that last step is one more Newton step. Without
    ``implicit_gradient`` that step is left out and the result has no gradient (the zmx
    FTYP 3 solve, never differentiated, compiles in less than half the time).

    Args:
        fn: ``fn(x, params)``, the residual ``[2]``; with ``has_valid``, ``(residual,
            valid)``, valid a bool scalar (False: ``x`` is no admissible point, such as a
            launch point whose ray misses a surface).
        x0: the start ``[2]``.
        params: the pytree the gradient flows to.
        iters: the most Newton iterations (all of them when ``tol`` is None).
        implicit_gradient: see above.
        tol: stop once max|fn| ≤ tol (units of fn; an array is fine) at a valid point;
            None: run all ``iters``.
        max_step: the longest step ``|Δx|`` (Euclidean, units of x); a longer Newton step
            is shortened to it, keeping its direction. None: no limit.
        halvings: backtracking: a step that does not reduce ``|fn|`` (or, with
            ``has_valid``, lands on an invalid point) is halved, up to this many times; the
            last, shortest one is taken anyway, except from an invalid point, where the
            full step is. 0: every step is the full (or limited) one.
        has_valid: see ``fn``.
        has_aux: ``fn`` returns ``(out, aux)`` (``out`` as above); the result is then ``(x,
            aux at x)``, aux from one more evaluation inside the loop (so a caller that
            needs something computed at the root, such as the aimed ray, gets it without a
            second copy of ``fn`` in its program). Only for plain Newton without the implicit
            step (no ``tol``, ``halvings`` or ``implicit_gradient``).

    Returns:
        x ``[2]`` (with ``has_aux``, ``(x, aux)``). With the defaults (no ``tol``,
        ``max_step`` or ``halvings``), plain Newton: ``iters`` undamped steps and the
        implicit step. Whether the root was found is for the caller to check (evaluate
        ``fn`` at the result).
    """
    iters = checks.number(iters, "iters", "newton_2d", lo=0, integer=True,
                          unit="Newton iterations")
    halvings = checks.number(halvings, "halvings", "newton_2d", lo=0, integer=True,
                             unit="step halvings")
    search = halvings > 0
    if has_aux and (tol is not None or search or implicit_gradient):
        raise ValueError("newton_2d: has_aux=True needs plain Newton without the implicit "
                         f"step (tol=None, halvings=0, implicit_gradient=False); got tol={tol}, "
                         f"halvings={halvings}, implicit_gradient={implicit_gradient}")

    def ev_aux(x, p):
        out, aux = fn(x, p) if has_aux else (fn(x, p), None)
        return (out if has_valid else (out, jnp.bool_(True))), aux

    def ev(x, p):
        return ev_aux(x, p)[0]

    def norm(f):
        return jnp.sqrt(jnp.sum(f * f))

    p_s = jax.lax.stop_gradient(params)

    def inv_step_aux(x, p):
        # One forward-mode pass gives the residual and validity (as aux) and the Jacobian.
        def f_aux(y):
            (f, ok), aux = ev_aux(y, p)
            return f, (f, ok, aux)

        jac, (f, ok, aux) = jax.jacfwd(f_aux, has_aux=True)(x)
        return f, ok, _inverse(jac), aux

    def inv_step(x, p):
        return inv_step_aux(x, p)[:3]

    def newton_dx(inv, f):
        dx = -(inv @ f)
        if max_step is not None:
            n = norm(dx)
            dx = dx * jnp.minimum(1.0, max_step / jnp.where(n > 0, n, 1.0))
        return dx

    def body(state):
        i, x, _, _ = state
        f, ok, inv = inv_step(x, p_s)
        dx = newton_dx(inv, f)
        if not search:
            x_new = x + dx
            if tol is None:
                return i + 1, x_new, f, ok
            f_new, ok_new = ev(x_new, p_s)
            return i + 1, x_new, f_new, ok_new
        merit = jnp.where(ok, norm(f), jnp.inf)
        one = jnp.ones((), x.dtype)

        def trying(s):
            k, _, ft, okt, _, _ = s
            return (k == 0) | ((k <= halvings) & (~okt | ~(norm(ft) < merit)))

        def trial(s):
            k, t, _, _, f1, ok1 = s
            t = jnp.where(k == 0, one, 0.5 * t)
            ft, okt = ev(x + t * dx, p_s)
            # The full step's residual, kept for a step from an invalid point.
            return (k + 1, t, ft, okt, jnp.where(k == 0, ft, f1), jnp.where(k == 0, okt, ok1))

        _, t, f_new, ok_new, f1, ok1 = jax.lax.while_loop(
            trying, trial, (0, one, f, jnp.bool_(False), f, jnp.bool_(False)))
        # From an invalid point (no merit to compare with) no shorter step was valid
        # either: take the full one (creeping on by the shortest step never got out).
        lost = ~ok & ~ok_new
        t = jnp.where(lost, one, t)
        return i + 1, x + t * dx, jnp.where(lost, f1, f_new), jnp.where(lost, ok1, ok_new)

    x0 = jax.lax.stop_gradient(jnp.asarray(x0))
    if has_aux:
        # iters steps, then one more pass whose step is not taken: its aux is the root's.
        def aux_body(i, carry):
            x, _ = carry
            f, _, inv, aux = inv_step_aux(x, p_s)
            return jnp.where(i < iters, x + newton_dx(inv, f), x), aux

        aux0 = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype),
                            jax.eval_shape(lambda x: ev_aux(x, p_s)[1], x0))
        x, aux = jax.lax.fori_loop(0, iters + 1, aux_body, (x0, aux0))
        return jax.lax.stop_gradient(x), aux
    if tol is None and not search:
        x = jax.lax.fori_loop(0, iters, lambda _, x: body((0, x, None, None))[1], x0)
    else:
        def going(state):
            i, _, f, ok = state
            done = ok & (jnp.max(jnp.abs(f)) <= tol) if tol is not None else False
            return (i < iters) & ~done

        # Not known yet: the first iteration evaluates it (every call runs at least one).
        f0 = jnp.full(x0.shape, jnp.inf, x0.dtype)
        x = jax.lax.while_loop(going, body, (0, x0, f0, jnp.bool_(False)))[1]
    if not implicit_gradient:
        return jax.lax.stop_gradient(x)
    x = jax.lax.stop_gradient(x)
    inv = jax.lax.stop_gradient(inv_step(x, p_s)[2])
    return x - inv @ ev(x, params)[0]
