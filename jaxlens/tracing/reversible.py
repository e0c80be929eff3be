"""A reversible trace: the gradient rebuilds each surface's input rays instead of storing them.

For a lens of plane, sphere and conic (``Standard``) surfaces only, with no mirror, coordinate
break, aperture or obscuration, ``trace_state`` moves rays through every surface and the image
with the operations of ``surface_adjoint.advance`` (``surface_step``'s values, bit for bit).
It is one ``jax.custom_vjp`` over the whole surface sequence: its forward keeps only the root
``t`` and the refraction gain ``g`` of each surface and, per ray, how many surfaces it passed
validly (validity only ever drops, so that count gives the validity after every surface); its
backward walks the surfaces in reverse and rebuilds each one's incident rays from the rays
after it, with no root solve and no square root:

    d_in = (d_out − g·N)/mu      (``step.unrefract``; N the normal at the point p_out)
    p_in = p_out − t·d_in        (global coordinates: the vertex shift cancels)

and applies the per-surface adjoint of ``surface_adjoint.conic_backward`` to them. So the
gradient needs neither a stored copy of every surface's rays nor a second forward pass (the
checkpointed chunk of ``trace``). Surface 1's incident rays are the trace's input, never
rebuilt (a distant object point would lose digits in p_out − t·d_in).

A ray that fails at a surface keeps its position and direction there (``surface_step``), so
its rays before that surface are exactly those after it: the rebuild takes them unchanged
wherever the ray is invalid after the surface, and only rays that are valid are rebuilt
(their t and g are finite, so no NaN or inf can arise). As in ``surface_step``'s own
derivative, an invalid ray passes its cotangents through the surfaces it failed at and the
parameters get nothing from it; the library's losses weight rays by validity, so failed rays
contribute zero gradient. The rebuild's rounding (float64 gradients within ~1e-13 relative of
JAX's derivative, tests/test_reversible_trace.py) is that of one forward step per surface.

Reverse mode only: ``jax.jvp``/``jax.jacfwd`` through it raise a TypeError, as through
``surface_adjoint``'s rules; ``trace(reverse_rule=True)`` uses it where ``supported``.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from ..optics.surfaces import Standard
from .step import unrefract
from .surface_adjoint import advance, backward_flag, conic_backward


def supported(lens, surfaces, upto) -> bool:
    """Whether ``trace_state`` can take this lens (static): every surface and the image a
    ``Standard`` surface, no mirror, aperture or obscuration, traced to the image."""
    if upto is not None or lens.mirrors or lens.apertures or lens.obscurations:
        return False
    kinds = [type(s) for s in surfaces] + [type(lens.image)]
    return len(surfaces) >= 2 and all(k is Standard for k in kinds)


def surface_params(lens, surfaces, zs, idx):
    """Per-surface (c, k, semi_diameter, z_vertex, n_before, n_after, backward), each stacked
    on a leading axis of num_surfaces + 1 (the image last, with n_after = n_before)."""
    every = list(surfaces) + [lens.image]
    m = len(every)
    shape = jnp.broadcast_shapes(*(jnp.shape(n) for n in idx))
    n = [jnp.broadcast_to(x, shape) for x in idx]
    n_in, n_out = n[: m - 1] + [n[-1]], n[1:] + [n[-1]]
    gaps = [None] + [lens.thickness[i] for i in range(m - 1)]
    bk = [backward_flag(gaps[i], i == 0, n_in[i], n_out[i]) for i in range(m)]
    return (jnp.stack([s.c for s in every]), jnp.stack([s.k for s in every]),
            jnp.stack([s.semi_diameter for s in every]),
            jnp.concatenate([zs, jnp.reshape(lens.image_z(), (1,))]),
            jnp.stack(n_in), jnp.stack(n_out), jnp.stack(bk))


def trace_rays(lens, surfaces, zs, idx, origin, direction, valid, opl):
    """(origin, direction, valid, opl) on the image surface, ``[n, 3]`` and ``[n]`` arrays
    (``supported`` lenses; surfaces, vertex positions and indices as ``forward`` prepares
    them), with the reversible reverse rule. The input and output arrays are the rule's
    residuals as they are, so a chunked trace saves no copy of them."""
    params = surface_params(lens, surfaces, zs, idx)
    return _reversible(params, origin, direction, valid, opl)


UNROLL = False
UNROLL_BACK = False


def _at(params, i):
    return tuple(a[i] for a in params)


def _split(x):
    return x[..., 0], x[..., 1], x[..., 2]


def _forward(params, origin, direction, valid, opl):
    """((origin, direction, valid, opl) on the image, residuals): ``advance``'s steps."""
    p, d = _split(origin), _split(direction)
    m = params[0].shape[0]
    count_t = jnp.int8 if m < 127 else jnp.int32
    (p, d, v, opl), t0, g0 = advance(True, True, _at(params, 0), p, d, valid, opl)
    count = v.astype(count_t)

    def body(carry, prm):
        (p, d, v, opl), count = carry
        out, t, g = advance(False, True, prm, p, d, v, opl)
        return (out, count + out[2].astype(count_t)), (t, g)

    mid = tuple(a[1:-1] for a in params)
    if UNROLL:
        carry, tg = ((p, d, v, opl), count), []
        for i in range(m - 2):
            carry, y = body(carry, _at(mid, i))
            tg.append(y)
        ((p, d, v, opl), count) = carry
        ts, gs = jnp.stack([y[0] for y in tg]), jnp.stack([y[1] for y in tg])
    else:
        ((p, d, v, opl), count), (ts, gs) = jax.lax.scan(body, ((p, d, v, opl), count), mid)
    (p, d, v, opl), t_img, _ = advance(False, False, _at(params, m - 1), p, d, v, opl)
    count = count + v.astype(count_t)
    return (jnp.stack(p, -1), jnp.stack(d, -1), v, opl), (t0, g0, ts, gs, t_img, count)


@jax.custom_vjp
def _reversible(params, origin, direction, valid, opl):
    return _forward(params, origin, direction, valid, opl)[0]


def _fwd(params, origin, direction, valid, opl):
    out, (t0, g0, ts, gs, t_img, count) = _forward(params, origin, direction, valid, opl)
    return out, (params, origin, direction, out[0], out[1], t0, g0, ts, gs, t_img, count)


def _unstep(refracts, prm, p, d, t, g, v):
    """The rays before a surface, from those after it (valid after it: rebuilt; else
    unchanged, as ``surface_step`` leaves a failed ray)."""
    c, k, _, zv, n1, n2, _ = prm
    if refracts:
        normal = (-c * p[0], -c * p[1], 1.0 - c * (1.0 + k) * (p[2] - zv))
        d_in = unrefract(d, normal, n1 / n2, g)
    else:
        d_in = d
    p_in = tuple(pi - t * di for pi, di in zip(p, d_in, strict=True))
    keep = lambda new, old: jnp.where(v, new, old)  # noqa: E731
    return (tuple(keep(a, b) for a, b in zip(p_in, p, strict=True)),
            tuple(keep(a, b) for a, b in zip(d_in, d, strict=True)))


def _bwd(res, cts):
    params, p0, d0, p, d, t0, g0, ts, gs, t_img, count = res
    p0, d0, p, d = _split(p0), _split(d0), _split(p), _split(d)
    P, D, _, L = cts
    P, D = _split(P), _split(D)
    m = params[0].shape[0]
    last = _at(params, m - 1)
    v = count >= m
    p, d = _unstep(False, last, p, d, t_img, None, v)
    g_last, P, D, _, L = conic_backward(False, last, p, d, v, t_img,
                                        jnp.zeros((), t_img.dtype), (P, D, None, L))

    def body(carry, xs):
        p, d, P, D, L = carry
        prm, t, g, i = xs
        v = count > i
        p, d = _unstep(True, prm, p, d, t, g, v)
        gp, P, D, _, L = conic_backward(True, prm, p, d, v, t, g, (P, D, None, L))
        return (p, d, P, D, L), gp

    mid = tuple(a[1:-1] for a in params)
    xs = (mid, ts, gs, jnp.arange(1, m - 1, dtype=count.dtype))
    if UNROLL_BACK:
        carry, gm = (p, d, P, D, L), []
        for i in reversed(range(m - 2)):
            carry, y = body(carry, (_at(mid, i), ts[i], gs[i], i + 1))
            gm.append(y)
        (_, _, P, D, L) = carry
        g_mid = jax.tree.map(lambda *x: jnp.stack(x[::-1]), *gm)
    else:
        (_, _, P, D, L), g_mid = jax.lax.scan(body, (p, d, P, D, L), xs, reverse=True)
    g_first, P, D, _, L = conic_backward(True, _at(params, 0), p0, d0, count > 0, t0, g0,
                                         (P, D, None, L))
    g_params = tuple(
        None if a is None else jnp.concatenate([a[None], b, c[None]])
        for a, b, c in zip(g_first, g_mid, g_last, strict=True)
    )
    return g_params, jnp.stack(P, -1), jnp.stack(D, -1), None, L


_reversible.defvjp(_fwd, _bwd)
