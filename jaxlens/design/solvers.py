"""Solvers behind one interface: optax Adam, optimistix Levenberg–Marquardt, jaxopt LBFGS-B.

Every solver works on the order-1 design variables (``LensParams``, see
``jaxlens.design.params``) of one design and exposes

* ``init(params, args) -> state``
* ``step(params, state, args, lr_scale) -> (params, state, aux)``

Every state is a typed ``eqx.Module`` with a ``result`` field, a :class:`SolverResult` code
that says how the last step went (``successful``, ``rejected``, ``damping_limit``,
``solver_error``; the design loop adds ``nonfinite``). Result codes are an
``eqx.Enumeration``, as in optimistix, so they vmap and jit like arrays.

Both are pure and jittable, so a multi-start run vmaps them over seeds and a curriculum calls
``step`` from a plain Python loop (one jitted update per call). ``args`` carries everything
that changes between stages (``StageArgs``), so stages share one compiled update.
``lr_scale`` multiplies the learning rates (optax schedules are evaluated on the host and
passed in); solvers without a learning rate ignore it. ``aux`` is the objective's ``Aux``
at the parameters the step started from.

The objective is ``residual_fn(params, args) -> (residuals, aux)``; the loss is
``Σ residuals²``. Adam and LBFGS-B minimise that sum; Levenberg–Marquardt (damped least
squares, the classical lens-design workhorse) uses the residuals and their Jacobian
(forward mode). ``free`` says which parameter groups move (a ``LensParams`` of bools).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
import optimistix as optx

from ..optics import checks
from .params import LensParams

with warnings.catch_warnings():
    warnings.filterwarnings("ignore", message=".*JAXopt is no longer maintained.*")
    warnings.filterwarnings("ignore", message=".*jaxopt is no longer maintained.*")
    import jaxopt

ALL_FREE = LensParams(c=True, a=True, k=False, d=True)

# Damped least squares clips its damping to this range; at the top no step is accepted.
DAMPING_MAX = 1e9
DAMPING_MIN = 1e-9


class SolverResult(eqx.Enumeration):
    """How a design's last solver step went (one code per design under ``vmap``)."""

    successful = ""
    rejected = "the least-squares step did not lower the loss (damping raised)"
    damping_limit = "the damping reached its cap: the least-squares solver cannot make progress"
    solver_error = "the solver reported an error (optimistix result or failed line search)"
    nonfinite = "a loss or update became non-finite; the design is frozen at its last finite state"


def result_names(results: SolverResult) -> list[str]:
    """The member names of a batch (leading axis) or a single ``SolverResult``, on the host."""
    names = ("successful", "rejected", "damping_limit", "solver_error", "nonfinite")
    hits = np.stack([np.atleast_1d(np.asarray(results == getattr(SolverResult, n)))
                     for n in names])
    return [names[int(i)] for i in np.argmax(hits, axis=0)]


class AdamState(eqx.Module):
    """Adam's moment estimates."""

    moments: optax.OptState
    result: SolverResult


class LeastSquaresState(eqx.Module):
    """Damped least squares: the damping λ carried between steps (unused by optimistix)."""

    damping: jax.Array
    result: SolverResult


class LBFGSBState(eqx.Module):
    """L-BFGS-B: the box bounds and jaxopt's own state."""

    bounds: tuple
    inner: object
    result: SolverResult


def _merge(free, fixed):
    return eqx.combine(free, fixed)


MAX_HISTORY = 1000
"""Most L-BFGS memory pairs (``LBFGSB.history``): each holds two copies of the variables."""


def _check_params(p, arg: str, where: str, *, lo=None, inf_ok=False, unit="") -> None:
    """A ``LensParams`` whose concrete leaves are real numbers in range (traced ones pass)."""
    if not isinstance(p, LensParams):
        raise TypeError(f"{where}: {arg} must be a LensParams (one value or array per group "
                        f"c, a, k, d, m), got {type(p).__name__} {p!r}")
    for name in ("c", "a", "k", "d", "m"):
        v = getattr(p, name)
        if v is not None and not checks.is_traced(v):
            checks.real_values(v, f"{arg}.{name}", where, unit)
            checks.values(v, f"{arg}.{name}", where, lo=lo, inf_ok=inf_ok, unit=unit)


class AbstractSolver(eqx.Module):
    """A design solver: ``init`` and a jittable ``step`` (see module docstring).

    Every solver refuses, when built, options outside their range (a negative learning rate
    climbs the loss, ``inner=10**9`` ran a scan of that length per step) and a residual
    function that is not callable (before: a ``TypeError`` from inside the first jitted step).
    """

    residual_fn: eqx.AbstractVar[Callable]

    def __check_init__(self):
        where = type(self).__name__
        if not callable(self.residual_fn):
            raise TypeError(f"{where}: residual_fn must be a callable residual_fn(params, "
                            f"args) -> (residuals, aux), got {type(self.residual_fn).__name__}")
        free = getattr(self, "free", ALL_FREE)
        if not isinstance(free, LensParams):
            raise TypeError(f"{where}: free must be a LensParams of bools (which groups move), "
                            f"got {type(free).__name__} {free!r}")
        for name in ("c", "a", "k", "d", "m"):  # 'no' is truthy (moved); Adam scaled by 0.5
            flag = getattr(free, name)
            is_bool = isinstance(flag, (bool, np.bool_)) or (
                np.ndim(flag) == 0 and getattr(getattr(flag, "dtype", None), "kind", "") == "b")
            if not is_bool and not (name == "m" and flag is None):
                raise TypeError(f"{where}: free.{name} must be True or False (whether the "
                                f"group moves), got {type(flag).__name__} {flag!r}")
        if hasattr(self, "inner"):  # the iterations of one step (a scan of that length)
            checks.number(self.inner, "inner", where, lo=1, hi=checks.MAX_STEPS, integer=True,
                          unit="iterations per step")

    def loss_fn(self, params, args):
        res, aux = self.residual_fn(params, args)
        return jnp.sum(res**2), aux

    def init(self, params, args):
        raise NotImplementedError

    def step(self, params, state, args, lr_scale):
        raise NotImplementedError


class Adam(AbstractSolver):
    """Adam (optax ``scale_by_adam``) with one learning rate per parameter group.

    Args:
        residual_fn: the objective.
        lrs: learning rates per group as a ``LensParams`` of scalars or arrays that
            broadcast against the group (e.g. one rate per aspheric order for ``a``).
        free: which groups move; frozen groups get no update.
        b1, b2, eps: Adam's moment decays and epsilon.
    """

    residual_fn: Callable
    lrs: LensParams
    free: LensParams = eqx.field(static=True, default=ALL_FREE)
    b1: float = eqx.field(static=True, default=0.9)
    b2: float = eqx.field(static=True, default=0.999)
    eps: float = eqx.field(static=True, default=1e-12)

    def __check_init__(self):
        _check_params(self.lrs, "lrs", "Adam", lo=0, unit="(learning rate per step)")
        for arg in ("b1", "b2"):  # b = 1 never forgets (the moments never decay): NaN steps
            checks.number(getattr(self, arg), arg, "Adam", lo=0, hi=1, hi_open=True,
                          unit="(moment decay per step)")
        checks.number(self.eps, "eps", "Adam", lo=0, lo_open=True, unit="(added to sqrt(v))")

    @property
    def _tx(self):
        return optax.scale_by_adam(b1=self.b1, b2=self.b2, eps=self.eps)

    def init(self, params, args):
        return AdamState(self._tx.init(params), SolverResult.successful)

    def step(self, params, state, args, lr_scale):
        (_, aux), grads = jax.value_and_grad(self.loss_fn, has_aux=True)(params, args)
        updates, moments = self._tx.update(grads, state.moments, params)
        state = AdamState(moments, SolverResult.successful)
        mask = jax.tree.map(lambda f, x: jnp.full_like(x, float(f)), self.free, params,
                            is_leaf=lambda x: isinstance(x, bool))
        updates = jax.tree.map(lambda u, lr, m: -lr_scale * lr * m * u, updates, self.lrs, mask)
        return optax.apply_updates(params, updates), state, aux


class LevenbergMarquardt(AbstractSolver):
    """optimistix Levenberg–Marquardt on the residuals, ``inner`` iterations per ``step``.

    Each ``step`` runs ``optx.least_squares`` for at most ``inner`` iterations from the
    current parameters (its trust region starts afresh; the solver state is not carried
    across jit boundaries, as optimistix keeps traced functions in it). A rejected step
    leaves the parameters unchanged.

    Args:
        residual_fn: the objective.
        free: which groups move.
        inner: Levenberg–Marquardt iterations per ``step``.
        rtol, atol: optimistix convergence tolerances.
    """

    residual_fn: Callable
    free: LensParams = eqx.field(static=True, default=ALL_FREE)
    inner: int = eqx.field(static=True, default=4)
    rtol: float = eqx.field(static=True, default=1e-6)
    atol: float = eqx.field(static=True, default=1e-12)

    def __check_init__(self):
        for arg in ("rtol", "atol"):
            checks.number(getattr(self, arg), arg, "LevenbergMarquardt", lo=0,
                          unit="(convergence tolerance)")

    def _split(self, params):
        mask = jax.tree.map(lambda f, x: f, self.free, params,
                            is_leaf=lambda x: isinstance(x, bool))
        return eqx.partition(params, mask)

    def init(self, params, args):
        return LeastSquaresState(jnp.zeros((), params.c.dtype), SolverResult.successful)

    def step(self, params, state, args, lr_scale):
        y, fixed = self._split(params)

        def fn(yy, a):
            return self.residual_fn(_merge(yy, fixed), a)

        fn = checks.trusted_within(fn, y)  # optimistix's loops nest: inherit reaches one

        _, aux = fn(y, args)
        # optimistix builds its damping in the default float type; match it (float64 under
        # jax_enable_x64) so its operator and vector structures agree.
        dt = jnp.result_type(float)
        y0 = jax.tree.map(lambda x: x.astype(dt), y)
        sol = optx.least_squares(
            fn, optx.LevenbergMarquardt(rtol=self.rtol, atol=self.atol), y0, args,
            has_aux=True, options={"jac": "fwd"}, max_steps=self.inner, throw=False)
        y1 = jax.tree.map(lambda a, b: a.astype(b.dtype), sol.value, y)
        # Running out of ``inner`` iterations is the normal end of a step, not a failure.
        ok = (sol.result == optx.RESULTS.successful) | (
            sol.result == optx.RESULTS.max_steps_reached)
        result = SolverResult.where(ok, SolverResult.successful, SolverResult.solver_error)
        return _merge(y1, fixed), LeastSquaresState(state.damping, result), aux


class DampedLeastSquares(AbstractSolver):
    """Levenberg–Marquardt with a materialised forward-mode Jacobian and a multi-λ search.

    The same damped least squares as ``LevenbergMarquardt`` (Marquardt's scaling: the
    damping is ``λ·diag(JᵀJ)``), organised for throughput: each iteration computes the
    Jacobian once with ``jax.jacfwd`` (one pass with all tangents batched), solves the
    normal equations for three damping values at once (λ/10, λ, 10λ, Cholesky, in the
    default float type), evaluates the three trial points together and keeps the best if
    it lowers the loss (λ moves to the damping that won; on rejection λ grows 10×). On this
    problem it is about ten times faster per iteration than optimistix's solver, which
    rebuilds the Jacobian from a ``jax.linearize``'d function inside its loop; the state
    (λ) is carried between ``step`` calls.

    Args:
        residual_fn: the objective.
        free: which groups move.
        inner: iterations per ``step``.
        lam0: initial damping.
    """

    residual_fn: Callable
    free: LensParams = eqx.field(static=True, default=ALL_FREE)
    inner: int = eqx.field(static=True, default=1)
    lam0: float = eqx.field(static=True, default=1e-2)

    def __check_init__(self):  # the damping is clipped to this range at every iteration
        checks.number(self.lam0, "lam0", "DampedLeastSquares", lo=DAMPING_MIN, hi=DAMPING_MAX,
                      unit="(initial damping λ, times diag(JᵀJ))")

    def _split(self, params):
        mask = jax.tree.map(lambda f, x: f, self.free, params,
                            is_leaf=lambda x: isinstance(x, bool))
        return eqx.partition(params, mask)

    def init(self, params, args):
        return LeastSquaresState(jnp.asarray(self.lam0, jnp.result_type(float)),
                                 SolverResult.successful)

    def step(self, params, state, args, lr_scale):
        from jax.flatten_util import ravel_pytree

        y, fixed = self._split(params)
        x0, unravel = ravel_pytree(y)
        dt = jnp.result_type(float)

        def res(x):
            r, aux = self.residual_fn(_merge(unravel(x), fixed), args)
            return r, aux

        @checks.inherit  # made on each call: trusted as the design step it runs in
        def one(carry, _):
            x, lam, _ = carry
            # The residuals and aux come with the Jacobian's primal pass (no second
            # evaluation); the first iteration's aux is the aux at the step's start.
            jac, (r, aux) = jax.jacfwd(lambda z: (lambda o: (o[0], o))(res(z)), has_aux=True)(x)
            jac = jac.astype(dt)
            r64 = r.astype(dt)
            h = jac.T @ jac
            g = jac.T @ r64
            dg = jnp.diag(h) + 1e-12 * jnp.max(jnp.diag(h)) + 1e-30
            mus = lam * jnp.asarray([0.1, 1.0, 10.0], dt)

            def trial(mu):
                a = h + mu * jnp.diag(dg)
                cho = jax.scipy.linalg.cho_factor(a)
                dx = -jax.scipy.linalg.cho_solve(cho, g)
                xn = x + dx.astype(x.dtype)
                rn, _ = res(xn)
                ln = jnp.sum(rn.astype(dt) ** 2)
                return xn, jnp.where(jnp.isfinite(ln), ln, jnp.inf)

            xs, ls = jax.vmap(trial)(mus)
            best = jnp.argmin(ls)
            l0 = jnp.sum(r64**2)
            accept = ls[best] < l0
            x = jnp.where(accept, xs[best], x)
            lam = jnp.where(accept, mus[best], 10.0 * lam)
            lam = jnp.clip(lam, DAMPING_MIN, DAMPING_MAX)
            return (x, lam, accept), aux

        (x, lam, accepted), auxs = jax.lax.scan(one, (x0, state.damping, jnp.asarray(True)),
                                                None, length=self.inner)
        aux0 = jax.tree.map(lambda a: a[0], auxs)
        result = SolverResult.where(
            accepted, SolverResult.successful,
            SolverResult.where(lam >= DAMPING_MAX, SolverResult.damping_limit,
                               SolverResult.rejected))
        return _merge(unravel(x), fixed), LeastSquaresState(lam, result), aux0


class LBFGSB(AbstractSolver):
    """jaxopt L-BFGS-B with bounds on the gaps (thicknesses), one iteration per ``step``.

    Args:
        residual_fn: the objective.
        lower, upper: bounds as ``LensParams`` (use ±inf for unbounded groups).
        free: which groups move (frozen groups are pinned by equal bounds at ``init``).
        history: L-BFGS memory.
    """

    residual_fn: Callable
    lower: LensParams
    upper: LensParams
    free: LensParams = eqx.field(static=True, default=ALL_FREE)
    history: int = eqx.field(static=True, default=10)

    def __check_init__(self):
        checks.number(self.history, "history", "LBFGSB", lo=1, hi=MAX_HISTORY, integer=True,
                      unit="(L-BFGS memory pairs)")
        for arg in ("lower", "upper"):  # ±inf: an unbounded group
            _check_params(getattr(self, arg), arg, "LBFGSB", inf_ok=True, unit="bound")
        for name in ("c", "a", "k", "d", "m"):  # swapped bounds: every step clipped to upper
            lo, hi = getattr(self.lower, name), getattr(self.upper, name)
            if lo is None or hi is None or checks.is_traced(lo) or checks.is_traced(hi):
                continue
            try:
                lo, hi = np.broadcast_arrays(np.asarray(lo, float), np.asarray(hi, float))
            except ValueError:
                raise ValueError(f"LBFGSB: lower.{name} {np.shape(lo)} and upper.{name} "
                                 f"{np.shape(hi)} do not broadcast together") from None
            above = lo > hi
            if above.any():
                i = tuple(int(j) for j in np.unravel_index(np.argmax(above), above.shape))
                lo_i, hi_i = lo[i], hi[i]
                raise ValueError(f"LBFGSB: lower.{name} must be <= upper.{name} (are they "
                                 f"swapped?), got lower {checks.fmt(lo_i)} > upper "
                                 f"{checks.fmt(hi_i)}" + (f" at index {i}" if i else ""))

    def _solver(self, params):
        # A new objective each call, trusted as the design step it runs in where that is
        # (jaxopt's line search nests its loops and branches).
        fun = checks.trusted_within(lambda p, a: self.loss_fn(p, a), params)
        return jaxopt.LBFGSB(fun=fun, has_aux=True, maxiter=1, history_size=self.history)

    def _bounds(self, params):
        def pick(f, x, b):
            return jnp.broadcast_to(b, x.shape).astype(x.dtype) if f else x

        def is_flag(x):
            return isinstance(x, bool)

        lo = jax.tree.map(pick, self.free, params, self.lower, is_leaf=is_flag)
        hi = jax.tree.map(pick, self.free, params, self.upper, is_leaf=is_flag)
        return lo, hi

    def init(self, params, args):
        bounds = self._bounds(params)
        return LBFGSBState(bounds, self._solver(params).init_state(params, bounds, args),
                           SolverResult.successful)

    def step(self, params, state, args, lr_scale):
        params, st = self._solver(params).update(params, state.inner, state.bounds, args)
        result = SolverResult.where(st.failed_linesearch, SolverResult.solver_error,
                                    SolverResult.successful)
        return params, LBFGSBState(state.bounds, st, result), st.aux
