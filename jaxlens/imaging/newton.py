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
        x_new = x + newton_dx(inv, f)
        if tol is None:
            return i + 1, x_new, f, ok
        f_new, ok_new = ev(x_new, p_s)
        return i + 1, x_new, f_new, ok_new

    x0 = jax.lax.stop_gradient(jnp.asarray(x0))
    if search:
        x, inv = _backtracking(inv_step, newton_dx, norm, x0, p_s, iters, tol, halvings)
        if not implicit_gradient:
            return jax.lax.stop_gradient(x)
        x, inv = jax.lax.stop_gradient((x, inv))
        return x - inv @ ev(x, params)[0]
    if tol is None and (has_aux or implicit_gradient):
        # iters steps, then one more pass whose step is not taken: its aux and its Jacobian
        # are the root's (the implicit step needs no second copy of fn's forward-mode pass).
        def last_body(i, carry):
            x, _, _ = carry
            f, _, inv, aux = inv_step_aux(x, p_s)
            return jnp.where(i < iters, x + newton_dx(inv, f), x), inv, aux

        aux0 = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype),
                            jax.eval_shape(lambda x: ev_aux(x, p_s)[1], x0)) if has_aux else None
        inv0 = jnp.zeros((2, 2), x0.dtype)
        x, inv, aux = jax.lax.fori_loop(0, iters + 1, last_body, (x0, inv0, aux0))
        if has_aux:
            return jax.lax.stop_gradient(x), aux
        x, inv = jax.lax.stop_gradient((x, inv))
        return x - inv @ ev(x, params)[0]
    if tol is None:
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


def _backtracking(inv_step, newton_dx, norm, x0, p, iters, tol, halvings):
    """``newton_2d``'s damped Newton (``halvings`` > 0): the final iterate and the inverse
    Jacobian there (for the implicit step).

    Each Newton iteration at x takes the step dx = −J⁻¹f and tries x + t·dx for t = 1, 1/2,
    … (at most ``halvings`` + 1 trials) until a trial is valid and lowers |f|; the last one is
    taken anyway, except from an invalid x, where the full step is. It stops after ``iters``
    iterations, or once an iterate after the first step is valid with max|f| ≤ ``tol``.

    One ``while_loop`` of evaluations, each the residual *and* its Jacobian (``inv_step``,
    one forward-mode pass) at one point: x0, then each trial. The trial that is taken already
    holds what the next iteration and the implicit step need, so ``fn`` has one copy in the
    compiled program instead of three (the Jacobian in the iteration, the residual in the
    trials, the Jacobian again at the root): the report of a file with ray aiming
    (rayoptics_US00583336, ``aim="real"``) compiles 21 329 lines of program instead of
    28 481, in 5.8 s of CPU instead of 7.1 (``tools/aim_compile_size.py``). The points
    evaluated, the steps and the result are those of a loop of iterations with an inner loop
    of plain trials and a last Jacobian at the root, bit for bit (float32 and float64).
    """
    inf = jnp.full(x0.shape, jnp.inf, x0.dtype)
    eye = jnp.zeros((2, 2), x0.dtype)
    one = jnp.ones((), x0.dtype)
    false = jnp.bool_(False)
    # (x, f, ok, inv): a point and its evaluation. The base is the current iterate; "first"
    # the full step's trial, kept for a step from an invalid base.
    start = (x0, inf, false, eye)

    def done(base):
        _, f, ok, _ = base
        return ok & (jnp.max(jnp.abs(f)) <= tol) if tol is not None else false

    def going(state):
        i, evaluated, base, *_ = state
        # The first iteration always runs (as a loop that tests |f| after each step).
        return ~evaluated | ((i < iters) & ((i == 0) | ~done(base)))

    def body(state):
        i, evaluated, base, dx, k, t, first = state
        x, f, ok, _ = base
        point = jnp.where(evaluated, x + t * dx, x)
        trial = (point, *inv_step(point, p))
        f_c, ok_c = trial[1], trial[2]

        def pick(flag, a, b):
            return jax.tree.map(lambda u, v: jnp.where(flag, u, v), a, b)

        first = pick(evaluated & (k == 0), trial, first)
        good = ok_c & (norm(f_c) < jnp.where(ok, norm(f), jnp.inf))
        # A step ends with a good trial or with the last one (k = halvings). From an invalid
        # base no shorter step was valid either: the full one is taken.
        ends = evaluated & (good | (k >= halvings))
        taken = pick(~ok & ~ok_c, first, trial)
        # x0's own evaluation (not yet ``evaluated``) becomes the base and starts a step.
        new = ~evaluated | ends
        base = pick(~evaluated, trial, pick(ends, taken, base))
        dx = jnp.where(new, newton_dx(base[3], base[1]), dx)
        return (i + ends.astype(i.dtype), jnp.bool_(True), base, dx,
                jnp.where(new, 0, k + 1), jnp.where(new, one, 0.5 * t), first)

    state = (jnp.int32(0), false, start, jnp.zeros_like(x0), jnp.int32(0), one, start)
    _, _, (x, _, _, inv), *_ = jax.lax.while_loop(going, body, state)
    return x, inv
