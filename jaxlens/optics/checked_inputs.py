"""Inputs checked once, at the entry point: what lets a compiled core skip its re-checks.

An entry point (``rms_spot``, ``psf``, ``curriculum.run``) checks its concrete inputs at
once, then calls its compiled core, which runs the same helpers (sampling, tracing) on
traced copies of them: each helper attached an ``eqx.error_if`` that could no longer fire.
Each is a host callback, and JAX's persistent compilation cache keeps no program that has
one, so every run compiled the core again. A core compiled with :func:`checked_core` skips
those re-checks where its arguments were concrete (so checked) or come from another such
core's body; traced by a user's own ``jit`` it keeps them. Loop and branch bodies are
traced apart: :func:`inherit` trusts one level of them, :func:`trusted_within` every level of
a function handed to a solver library. Result checks (a PSF with no light) stay.
``checks.wavelengths``, ``field_angles``, ``finite_array`` and ``sampling.static_depth``
consult :func:`checked_by_caller`.
"""

from __future__ import annotations

import contextvars
import functools
import inspect

import jax

# The jit-level traces of the bodies being traced now whose inputs their callers checked.
_CHECKED_BODIES: contextvars.ContextVar[tuple] = contextvars.ContextVar(
    "jaxlens_checked_bodies", default=())


def _jaxpr_trace(t):
    """``t`` or the first trace above it that is JAX's ``DynamicJaxprTrace`` (a jit's, a
    loop body's), through vmap and JVP traces; None if there is none."""
    while t is not None and type(t).__name__ != "DynamicJaxprTrace":
        t = getattr(t, "parent_trace", None)
    return t


def _jit_trace(x):
    """The jit-level trace (JAX's ``DynamicJaxprTrace``) of the first tracer in ``x``,
    through the vmap and JVP traces above it; None for concrete values or an unknown JAX."""
    for leaf in jax.tree_util.tree_leaves(x):
        if isinstance(leaf, jax.core.Tracer):
            return _jaxpr_trace(getattr(leaf, "_trace", None))
    return None


def checked_by_caller(x) -> bool:
    """True for a value traced in the body of a :func:`checked_core` called with checked
    inputs (under its vmap, grad or JVP; not inside a jit, scan or loop nested in it, except
    a loop body given to :func:`inherit`): its entry point checked it, so a re-check would
    only add an ``eqx.error_if``."""
    bodies = _CHECKED_BODIES.get()
    if not bodies:
        return False
    t = _jit_trace(x)
    return t is not None and any(t is b for b in bodies)


def inherit(fn):
    """``fn``, trusted as the body it is called from: where its arguments are traced in a
    loop body (``fori_loop``, ``while_loop``, ``scan``, ``lax.map``) traced directly inside a
    checked core's body, that loop body is trusted too while ``fn`` runs. Only for loops
    whose body function is made anew on each call (a closure, as ``radiometry.star_region``'s
    and ``render``'s tile loop are): JAX caches a loop body's trace by its function, and a
    trace made here must not serve a call from elsewhere."""
    @functools.wraps(fn)
    def run(*args, **kwargs):
        inner = _jit_trace((args, kwargs))
        outer = _jaxpr_trace(getattr(inner, "parent_trace", None))
        if not any(outer is b for b in _CHECKED_BODIES.get()):
            inner = None
        return _trusting(inner, fn, args, kwargs)

    return run


def trusted_within(fn, like):
    """``fn`` trusted in every trace it runs in, where ``like`` (a value of the body that
    makes ``fn``) is traced in a checked core's trusted body; else ``fn`` itself. For an
    objective made anew in such a body and handed to a solver library (optimistix, jaxopt)
    whose loops and branches nest, where :func:`inherit` (one loop level) does not reach.
    The wrapper is a new function on each call, and JAX caches traces by the function, so
    its traces serve that body's program only."""
    if not checked_by_caller(like):
        return fn

    @functools.wraps(fn)
    def run(*args, **kwargs):
        return _trusting(_jit_trace((args, kwargs)), fn, args, kwargs)

    return run


def _trusting(trace, fn, args, kwargs):
    """``fn(*args, **kwargs)`` with ``trace`` (None: no trace) trusted while it runs."""
    if trace is None:
        return fn(*args, **kwargs)
    token = _CHECKED_BODIES.set(_CHECKED_BODIES.get() + (trace,))
    try:
        return fn(*args, **kwargs)
    finally:
        _CHECKED_BODIES.reset(token)


def is_traced(x) -> bool:
    """True for a JAX tracer (inside jit, grad or vmap): its value is not known."""
    return any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def checked_core(jit, *, concrete_checked: bool = True):
    """Decorator: ``jit(fn)`` for a private core whose callers check its inputs, compiled so
    that the input checks inside it are skipped where those inputs were checked already.

    That is where every argument is concrete (the caller checked them at once; with
    ``concrete_checked=False``, for a function that checks inside its own jit, never), or
    where they are traced in the body of another such core (:func:`checked_by_caller`).
    Traced by a user's own ``jit`` they are not known to be checked: the body keeps its
    checks. Each case has its own compiled function, so a program cached from one never
    serves the other.

    The checks skipped add nothing, and each is an ``eqx.error_if``, a host callback: JAX's
    persistent compilation cache keeps no program that has one, so every run compiled the
    core again. Result checks (a PSF with no light) stay. The body's own trace is the one
    trusted (and the vmap, grad and JVP traces under it): a jit, scan or loop nested in it
    is traced apart and keeps its checks.
    """
    def decorate(fn):
        def trusting(*args, **kwargs):
            return _trusting(_jit_trace((args, kwargs)), fn, args, kwargs)

        # Named as ``fn`` (compile logs), not wrapping it: jit binds fn's signature from it.
        trusting.__name__, trusting.__qualname__ = fn.__name__, fn.__qualname__
        trusting.__signature__ = inspect.signature(fn)
        checked, plain = jit(trusting), jit(fn)

        @functools.wraps(fn)
        def call(*args, **kwargs):
            trusted = checked_by_caller((args, kwargs)) or (
                concrete_checked and not is_traced((args, kwargs)))
            return (checked if trusted else plain)(*args, **kwargs)

        for name in ("loop_emitters",):  # what the jit decorator tells the tests
            if hasattr(plain, name):
                setattr(call, name, getattr(plain, name))
        call.inputs_checked = checked  # for a caller that checked them itself
        return call

    return decorate
