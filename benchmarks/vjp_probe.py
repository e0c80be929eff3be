"""Probe: a hand-written reverse rule (``jax.custom_vjp``) for the conic surface step.

Scratch benchmark (not used by the library). The step below is ``step.surface_step`` for a
conic (``Standard``) surface without mirrors, obscurations or apertures, written so that its
forward values are the library's bit for bit, with a backward pass written out by hand:

    t      implicit conic root, F(o + t d) = 0 with F = c(x² + y²) + c(1+k)z² − 2z;
           ∇F = −2N (N the library's unnormalised normal), so F_t = −2 d·N and
           dt = (F_c dc + F_k dk − 2N·(do + t dd)) / (2 d·N)
    g      refraction gain, g·nn = R − mu·dn with R = ±sqrt(nn − mu²(nn − dn²)),
           dR = dkk/(2R); R is rebuilt in the backward pass as g·nn + mu·dn (no sqrt)
    d'     mu·d + g·N,  p' = o + t d (+ zv),  opl' = opl + n1·t

Backward variants (``--split``): 0 ``_backward``, the adjoint as one expression (each of
the six ray cotangents then recomputes the whole chain, ~110-140 HLO ops per fusion); 1
``_backward_split`` (default), the shared per-ray adjoint scalars (cotangents of d·N, N·N, mu
and the root term bar_t/(2 d·N)) each end in a division, so XLA:CPU writes each once and the
output passes are short; 2 the same from one division Q = bar_g/(nn R) with an
``optimization_barrier``; -1 no adjoint at all (a floor: 2 forwards + residual writes).
Residuals (``--save``): "tg" the step's inputs, t and g; "in" inputs only (t, g recomputed).
Parameter sums: separate ``jnp.sum``s (a variadic ``lax.reduce``, ``OPTS["variadic"]``, was
slower: XLA:CPU emits it as one unvectorised loop).

Findings (2-core EPYC, load 4.6-5.4 from other jobs, so cpu/wall ~1.0 and times ~2x a quiet
machine's; Cooke triplet, 1e6 rays, float32, best of 9, old and new interleaved in one process):
jaxlens.trace f+g 490-511 ms (forward 106 ms, ratio 0.21); this step with chunks of 8 000 rays
f+g 302-309 ms (forward 96 ms, ratio 0.31-0.32), with jaxlens's 50 000-ray chunks 400-414 ms.
The custom backward is bound by cache traffic (21 per-ray fusions reading 6-17 arrays each per
surface), hence the smaller chunk; jaxlens.trace itself gains less from it (458-466 ms).

This rule is in the library since 2026-11-27: ``jaxlens.tracing.surface_adjoint`` (the
``--split 1`` backward, t and g saved), used by ``jaxlens.trace(..., reverse_rule=True)``;
"old" here stays ``jaxlens.trace``'s default. The root comes from ``step.conic_root_arrays``
(public since then).

    python -m benchmarks.vjp_probe --check            # values and gradients (float64), FD
    python -m benchmarks.vjp_probe --save tg --chunk 8192 65536 --old-chunk 8192 --repeats 9
    python -m benchmarks.vjp_probe --fusions --save tg --split 0 1 --chunk 8192
    python -m benchmarks.vjp_probe --save --library-rule --repeats 9   # the library's rule
"""

from __future__ import annotations

import argparse
import functools
import os
import time

import jax

jax.config.update("jax_enable_x64", True)  # as in the throughput benchmark: float64 setup

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.tracing.forward import CHUNK, _chunking  # noqa: E402
from jaxlens.tracing.step import (  # noqa: E402
    T_MAX,
    bounded_div,
    conic_root_arrays,
    refraction_gain,
    unmark,
)

from . import throughput  # noqa: E402

# ---------------------------------------------------------------------------------------------
# The step: forward (the library's operations, in its order) and the hand-written backward.


def _forward(first, refracts, params, p, d, valid, opl):
    """(new p, new d, new valid, new opl), t, g: ``surface_step`` on a conic surface."""
    c, k, sd, zv, n1, n2, bk = params
    o = (p[0], p[1], p[2] - zv)
    eps = jnp.finfo(o[2].dtype).eps
    if first:
        t_plane, _ = bounded_div(-o[2], d[2])
        o1 = tuple(oi + t_plane * di for oi, di in zip(o, d, strict=True))
        t_m = conic_root_arrays(False, c, k, *o1, *d, jnp.zeros_like(o[2])) + t_plane
    else:
        t_min = -1e3 * (eps * (1 + jnp.abs(o[2])))
        t_min = jnp.where(bk, -T_MAX, t_min)
        t_m = conic_root_arrays(True, c, k, *o, *d, t_min)
    t, ok = unmark(t_m)
    if not first:
        fwd = t >= -1e3 * eps * (1 + jnp.abs(o[2]))
        ok = ok & (fwd | bk)
    x, y, z = (oi + t * di for oi, di in zip(o, d, strict=True))
    rim = sd**2 * (1 + 64 * eps)
    ok = ok & (x * x + y * y <= rim)
    g = None
    dn_ = d
    if refracts:
        normal = (-c * x, -c * y, 1.0 - c * (1.0 + k) * z)
        mu = n1 / n2
        g, no_tir = unmark(refraction_gain(d, normal, mu))
        dn_ = tuple(jnp.where(no_tir, mu * di + g * ni, di) for di, ni in zip(d, normal,
                                                                               strict=True))
        ok = ok & no_tir
    v = valid & ok
    keep = lambda new, old: jnp.where(v, new, old)  # noqa: E731
    p2 = (keep(x, p[0]), keep(y, p[1]), keep(z + zv, p[2]))
    d2 = tuple(keep(a, b) for a, b in zip(dn_, d, strict=True))
    return (p2, d2, v, opl + jnp.where(v, n1 * t, 0.0)), t, g


OPTS = {"variadic": False, "split": 1}


def _backward(refracts, params, p, d, v, t, g, cts):
    c, k, sd, zv, n1, n2, bk = params
    P, D, _, L = cts
    dt = p[0].dtype
    eps = jnp.finfo(dt).eps
    zero = jnp.zeros((), dt)
    o = (p[0], p[1], p[2] - zv)
    x, y, z = (oi + t * di for oi, di in zip(o, d, strict=True))
    ck = c * (1.0 + k)
    N = (-c * x, -c * y, 1.0 - ck * z)
    dn = d[0] * N[0] + d[1] * N[1] + d[2] * N[2]
    good = v & (jnp.abs(dn) > eps * (jnp.abs(N[0]) + jnp.abs(N[1]) + jnp.abs(N[2])))
    dn_s = jnp.where(good, dn, 1.0)
    if refracts:
        mu = n1 / n2
        nn = N[0] * N[0] + N[1] * N[1] + N[2] * N[2]
        R = g * nn + mu * dn
        inv = 1.0 / jnp.where(v, nn * R * dn_s, 1.0)  # one division for 1/nn, 1/R, 1/dn
        inv_nn, inv_r, inv_dn = R * dn_s * inv, nn * dn_s * inv, nn * R * inv
        A = (D[0] * N[0] + D[1] * N[1] + D[2] * N[2]) * inv_nn
        mu2 = mu * mu
        b_nn = A * ((0.5 * (1.0 - mu2)) * inv_r - g)
        b_dn = A * (mu2 * dn * inv_r - mu)
        b_mu = A * (-mu * (nn - dn * dn) * inv_r - dn) + (D[0] * d[0] + D[1] * d[1]
                                                         + D[2] * d[2])
        bN = tuple(g * Di + b_dn * di + 2.0 * b_nn * Ni for Di, di, Ni in zip(D, d, N,
                                                                               strict=True))
        bx = (P[0] - c * bN[0], P[1] - c * bN[1], P[2] - ck * bN[2])
    else:
        inv_dn = 1.0 / dn_s
        bx = P
    b_t = jnp.where(v, n1 * L, 0.0) + bx[0] * d[0] + bx[1] * d[1] + bx[2] * d[2]
    T = jnp.where(good, (0.5 * b_t) * inv_dn, 0.0)
    bo = tuple(bxi - 2.0 * T * Ni for bxi, Ni in zip(bx, N, strict=True))
    if refracts:
        bd = tuple(mu * Di + b_dn * Ni + t * boi for Di, Ni, boi in zip(D, N, bo, strict=True))
    else:
        bd = tuple(Di + t * boi for Di, boi in zip(D, bo, strict=True))
    out_p = tuple(jnp.where(v, a, b) for a, b in zip(bo, P, strict=True))
    out_d = tuple(jnp.where(v, a, b) for a, b in zip(bd, D, strict=True))
    # Per-ray parameter terms, summed by one variadic reduce.
    r2 = x * x + y * y
    if refracts:
        bc = T * (r2 + (1.0 + k) * z * z) - (x * bN[0] + y * bN[1] + (1.0 + k) * z * bN[2])
        bk_ = c * z * (T * z - bN[2])
        bmu = b_mu
    else:
        bc = T * (r2 + (1.0 + k) * z * z)
        bk_ = T * (c * z * z)
        bmu = jnp.zeros_like(x)
    terms = (bc, bk_, P[2] - bo[2], bmu, t * L)
    terms = tuple(jnp.where(v, a, 0.0) for a in terms)
    if OPTS["variadic"]:
        sums = jax.lax.reduce(terms, (zero,) * 5,
                              lambda a, b: tuple(ai + bi for ai, bi in zip(a, b, strict=True)),
                              tuple(range(x.ndim)))
    else:
        sums = tuple(jnp.sum(a) for a in terms)
    s_c, s_k, s_zv, s_mu, s_tl = sums
    g_n1 = s_mu / n2 + s_tl
    g_n2 = -s_mu * n1 / (n2 * n2)
    gp = (s_c, s_k, jnp.zeros_like(sd), s_zv, g_n1, g_n2, None)
    gp = tuple(None if b is None else b.astype(a.dtype) for a, b in zip(params, gp,
                                                                       strict=True))
    return gp, out_p, out_d, None, L


def _backward_split(refracts, params, p, d, v, t, g, cts):
    """The same adjoint, written so that XLA:CPU materialises a few shared per-ray scalars.

    Each of b_dn, b_nn, b_mu (the cotangents of d·N, N·N and mu) and T (the implicit-root
    term, bar_t/(2 d·N)) ends in a division, which XLA never duplicates, so each is written
    once by its own pass; the six ray cotangents and the parameter terms are then short
    passes over few arrays instead of each recomputing the whole chain.
    """
    c, k, sd, zv, n1, n2, bk = params
    P, D, _, L = cts
    dt = p[0].dtype
    eps = jnp.finfo(dt).eps
    o = (p[0], p[1], p[2] - zv)
    x, y, z = (oi + t * di for oi, di in zip(o, d, strict=True))
    ck = c * (1.0 + k)
    N = (-c * x, -c * y, 1.0 - ck * z)
    dn = d[0] * N[0] + d[1] * N[1] + d[2] * N[2]
    good = v & (jnp.abs(dn) > eps * (jnp.abs(N[0]) + jnp.abs(N[1]) + jnp.abs(N[2])))
    if refracts and OPTS["split"] == 2:
        # One division Q = bar_g/(nn R); b_dn, b_nn from it, pinned in memory by a barrier.
        mu = n1 / n2
        mu2 = mu * mu
        nn = N[0] * N[0] + N[1] * N[1] + N[2] * N[2]
        R = g * nn + mu * dn
        bg = D[0] * N[0] + D[1] * N[1] + D[2] * N[2]
        Q = jnp.where(v, bg, 0.0) / jnp.where(v, nn * R, 1.0)
        b_dn, b_nn = jax.lax.optimization_barrier(
            (Q * (mu2 * dn - mu * R), Q * (0.5 * (1.0 - mu2) - g * R)))
        b_mu = Q * (-mu * (nn - dn * dn) - dn * R) + jnp.where(
            v, D[0] * d[0] + D[1] * d[1] + D[2] * d[2], 0.0)
        bN = tuple(g * Di + b_dn * di + 2.0 * b_nn * Ni for Di, di, Ni in zip(D, d, N,
                                                                               strict=True))
        bx = (P[0] - c * bN[0], P[1] - c * bN[1], P[2] - ck * bN[2])
    elif refracts:
        mu = n1 / n2
        mu2 = mu * mu
        nn = N[0] * N[0] + N[1] * N[1] + N[2] * N[2]
        R = g * nn + mu * dn
        bg = D[0] * N[0] + D[1] * N[1] + D[2] * N[2]
        den = jnp.where(v, nn * R, 1.0)
        b_dn = jnp.where(v, bg * (mu2 * dn - mu * R), 0.0) / den
        b_nn = jnp.where(v, bg * (0.5 * (1.0 - mu2) - g * R), 0.0) / den
        b_mu = jnp.where(v, bg * (-mu * (nn - dn * dn) - dn * R)
                         + (D[0] * d[0] + D[1] * d[1] + D[2] * d[2]) * den, 0.0) / den
        bN = tuple(g * Di + b_dn * di + 2.0 * b_nn * Ni for Di, di, Ni in zip(D, d, N,
                                                                               strict=True))
        bx = (P[0] - c * bN[0], P[1] - c * bN[1], P[2] - ck * bN[2])
    else:
        bx = P
        b_mu = None
    b_t = n1 * L + bx[0] * d[0] + bx[1] * d[1] + bx[2] * d[2]
    T = jnp.where(good, 0.5 * b_t, 0.0) / jnp.where(good, dn, 1.0)
    bo = tuple(bxi - 2.0 * T * Ni for bxi, Ni in zip(bx, N, strict=True))
    if refracts:
        bd = tuple(mu * Di + b_dn * Ni + t * boi for Di, Ni, boi in zip(D, N, bo, strict=True))
    else:
        bd = tuple(Di + t * boi for Di, boi in zip(D, bo, strict=True))
    out_p = tuple(jnp.where(v, a, b) for a, b in zip(bo, P, strict=True))
    out_d = tuple(jnp.where(v, a, b) for a, b in zip(bd, D, strict=True))
    r2 = x * x + y * y
    if refracts:
        bc = T * (r2 + (1.0 + k) * z * z) - (x * bN[0] + y * bN[1] + (1.0 + k) * z * bN[2])
        bk_ = c * z * (T * z - bN[2])
    else:
        bc = T * (r2 + (1.0 + k) * z * z)
        bk_ = T * (c * z * z)
    # T and b_mu are zero on invalid rays already; bzv = P2 - out_p2 is too.
    s_c = jnp.sum(jnp.where(v, bc, 0.0))
    s_k = jnp.sum(jnp.where(v, bk_, 0.0))
    s_zv = jnp.sum(P[2] - out_p[2])
    s_tl = jnp.sum(jnp.where(v, t * L, 0.0))
    s_mu = jnp.sum(b_mu) if refracts else jnp.zeros((), dt)
    g_n1 = s_mu / n2 + s_tl
    g_n2 = -s_mu * n1 / (n2 * n2)
    gp = (s_c, s_k, jnp.zeros_like(sd), s_zv, g_n1, g_n2, None)
    gp = tuple(None if b is None else b.astype(a.dtype) for a, b in zip(params, gp,
                                                                       strict=True))
    return gp, out_p, out_d, None, L


def make_step(save: str):
    """The custom_vjp step; ``save="tg"`` keeps t and g as residuals, ``"in"`` recomputes."""

    @functools.partial(jax.custom_vjp, nondiff_argnums=(0, 1))
    def step(first, refracts, params, p, d, valid, opl):
        return _forward(first, refracts, params, p, d, valid, opl)[0]

    def fwd(first, refracts, params, p, d, valid, opl):
        out, t, g = _forward(first, refracts, params, p, d, valid, opl)
        res = (params, p, d, out[2]) + ((t, g) if save == "tg" else (valid,))
        return out, res

    def bwd(first, refracts, res, cts):
        params, p, d, v = res[:4]
        if save == "tg":
            t, g = res[4:]
        else:
            (out, t, g) = _forward(first, refracts, params, p, d, res[4], jnp.zeros_like(p[0]))
        if OPTS["split"] == -1:  # a floor: the cotangents passed through, no adjoint work
            P, D, _, L = cts
            t, g = (res[4:] if save == "tg" else (p[0], d[0]))
            g = jnp.zeros_like(t) if g is None else g
            s = jnp.sum(jnp.where(v, t * L + g + p[0] + p[1] + p[2] + d[0] + d[1] + d[2], 0.0))
            gp = tuple(None if a is params[-1] else s.astype(a.dtype) for a in params)
            return gp, P, D, None, L
        b = _backward_split if OPTS["split"] else _backward
        return b(refracts, params, p, d, v, t, g, cts)

    step.defvjp(fwd, bwd)
    return step


STEPS = {s: make_step(s) for s in ("tg", "in")}


# ---------------------------------------------------------------------------------------------
# A whole-lens trace with that step (conic lenses without mirrors; chunked like jaxlens.trace).


def trace_new(lens, rays, *, save="tg", chunk=CHUNK, ckpt_chunk=True, ckpt_body=False):
    """Image intercepts of ``rays`` (a ``Rays`` [N, 3]): ``jaxlens.trace`` for a conic lens."""
    step = STEPS[save]
    lens = lens.astype(rays.dtype)
    s = lens.surfaces
    zs, idx = lens.vertex_z(), lens.indices(rays.wavelength)
    gaps = lens.thickness
    false = jnp.zeros((), bool)

    def params(i, n1, n2, bk):
        return (s[i].c, s[i].k, s[i].semi_diameter, zs[i], n1, n2, bk)

    p0 = params(0, idx[0], idx[1], false)
    m = len(s)
    mid = (
        jnp.stack([si.c for si in s[1:]]), jnp.stack([si.k for si in s[1:]]),
        jnp.stack([si.semi_diameter for si in s[1:]]), zs[1:],
        jnp.stack([jnp.asarray(n, rays.dtype) for n in idx[1:m]]),
        jnp.stack([jnp.asarray(n, rays.dtype) for n in idx[2:m + 1]]),
    )
    g_mid = gaps[0:m - 1]
    bks = (g_mid < 0) | ((g_mid == 0) & (mid[4] == mid[5]))
    im = lens.image
    p_im = (im.c, im.k, im.semi_diameter, lens.image_z(), idx[-1], idx[-1],
            (gaps[-1] < 0) | (gaps[-1] == 0))

    def whole(o, dd, v, opl):
        st = step(True, True, p0, (o[:, 0], o[:, 1], o[:, 2]), (dd[:, 0], dd[:, 1], dd[:, 2]),
                  v, opl)

        def body(carry, xs):
            return step(False, True, xs, *carry), None

        if ckpt_body:
            body = jax.checkpoint(body)
        st, _ = jax.lax.scan(body, st, mid + (bks,))
        return step(False, False, p_im, *st)

    n = rays.origin.shape[0]
    valid, opl = rays.valid, rays.opl
    if n <= chunk:
        p, d, v, L = whole(rays.origin, rays.direction, valid, opl)
    else:
        mc, size = _chunking(n, chunk)
        assert mc * size == n
        split = lambda x: x.reshape(mc, size, *x.shape[1:])  # noqa: E731
        one = (lambda xs: whole(*xs))
        if ckpt_chunk:
            one = jax.checkpoint(one)
        p, d, v, L = jax.lax.map(one, tuple(split(x) for x in (rays.origin, rays.direction,
                                                              valid, opl)))
        p, d = (tuple(a.reshape(n) for a in q) for q in (p, d))
        v, L = v.reshape(n), L.reshape(n)
    return jnp.stack(p, -1), jnp.stack(d, -1), v, L


# ---------------------------------------------------------------------------------------------


def _loss_old(lens, rays):
    out = jaxlens.trace(lens, rays)
    return throughput.spot_loss(out.origin[:, :2], out.valid)


def _loss_new(lens, rays, **kw):
    p, _, v, _ = trace_new(lens, rays, **kw)
    return throughput.spot_loss(p[:, :2], v)


def fns(old_chunk="auto", reverse_rule=False, **kw):
    fwd_old = eqx.filter_jit(lambda lens, rays: jaxlens.trace(lens, rays, chunk=old_chunk))

    def loss_old(lens, rays):
        out = jaxlens.trace(lens, rays, chunk=old_chunk, reverse_rule=reverse_rule)
        return throughput.spot_loss(out.origin[:, :2], out.valid)

    fwd_new = eqx.filter_jit(lambda lens, rays: trace_new(lens, rays, **kw))
    g_old = eqx.filter_jit(lambda lens, rays: eqx.filter_value_and_grad(loss_old)(lens, rays))
    g_new = eqx.filter_jit(lambda lens, rays: eqx.filter_value_and_grad(
        functools.partial(_loss_new, **kw))(lens, rays))
    return fwd_old, fwd_new, g_old, g_new


def make_rays(lens, n, dtype, pupil_scale=0.999, seed=0):
    """``throughput.make_rays`` with another pupil scale (above 1: some rays are clipped)."""
    from jaxlens import sampling

    lens64 = lens.astype(jnp.float64)
    pupil = pupil_scale * sampling.pupil_random(jax.random.PRNGKey(seed), n, jnp.float64)
    r = sampling.collimated(lens64, 0.7 * float(lens.fields[-1]), pupil)
    return jaxlens.Rays(r.origin.astype(dtype), r.direction.astype(dtype),
                        jnp.asarray(r.wavelength, dtype))


def check(n=20000, chunk_rays=4096):
    """Values (float32 and float64) and float64 gradients against jaxlens.trace, then FD."""
    lens = zoo.cooke_triplet()
    lens64 = lens.astype(jnp.float64)
    out = {}
    for scale in (0.999, 1.3):
        for dtype in (jnp.float32, jnp.float64):
            rays = make_rays(lens, n, dtype, scale)
            old = jaxlens.trace(lens, rays, chunk=chunk_rays)
            for save in ("tg", "in"):
                p, d, v, L = jax.jit(functools.partial(trace_new, save=save, chunk=chunk_rays))(
                    lens, rays)
                same = all(bool(jnp.array_equal(a, b)) for a, b in
                           ((old.origin, p), (old.direction, d), (old.valid, v), (old.opl, L)))
                print(f"pupil {scale} {jnp.dtype(dtype).name} save={save}: values identical to "
                      f"jaxlens.trace: {same} (valid {int(v.sum())}/{n})")
        rays = make_rays(lens, n, jnp.float64, scale)

        def loss_old(lens, rays=rays):
            out = jaxlens.trace(lens, rays, chunk=chunk_rays)
            return throughput.spot_loss(out.origin[:, :2], out.valid)

        vo, gro = eqx.filter_jit(eqx.filter_value_and_grad(loss_old))(lens64)
        for split in (0, 1, 2):
            OPTS["split"] = split
            for save in ("tg", "in"):
                gn = eqx.filter_jit(eqx.filter_value_and_grad(
                    functools.partial(_loss_new, rays=rays, save=save, chunk=chunk_rays)))
                vn, grn = gn(lens64)
                worst, worst_el = 0.0, 0.0
                for a, b in zip(jax.tree.leaves(gro), jax.tree.leaves(grn), strict=True):
                    a, b = np.asarray(a), np.asarray(b)
                    scl = np.max(np.abs(a))
                    if scl > 0:
                        worst = max(worst, float(np.max(np.abs(a - b)) / scl))
                    big = np.abs(a) > 1e-6 * max(scl, 1e-300)
                    if big.any():
                        worst_el = max(worst_el,
                                       float(np.max(np.abs(a - b)[big] / np.abs(a)[big])))
                print(f"pupil {scale} float64 grad split={split} save={save}: loss "
                      f"{float(vn):.15e} vs {float(vo):.15e}; max |Δgrad|/max|grad| per leaf "
                      f"{worst:.2e}, max elementwise rel {worst_el:.2e}")
                out[(scale, split, save)] = worst
    OPTS["split"] = 1
    rays = make_rays(lens, n, jnp.float64, 1.3)
    # Central finite differences on two parameters (float64).
    loss = eqx.filter_jit(functools.partial(_loss_new, rays=rays, chunk=chunk_rays))
    _, grn = eqx.filter_jit(eqx.filter_value_and_grad(
        functools.partial(_loss_new, rays=rays, chunk=chunk_rays)))(lens64)
    for name, get, h in (
        ("surfaces[2].c", lambda L: L.surfaces[2].c, 1e-7),
        ("surfaces[4].k", lambda L: L.surfaces[4].k, 1e-5),
        ("thickness[1]", lambda L: L.thickness[1], 1e-6),
    ):
        def at(delta, get=get, name=name):
            if name.startswith("thickness"):
                return eqx.tree_at(lambda L: L.thickness, lens64,
                                   lens64.thickness.at[1].add(delta))
            return eqx.tree_at(get, lens64, get(lens64) + delta)

        fd = (float(loss(at(h))) - float(loss(at(-h)))) / (2 * h)
        ad = float(get(grn))
        ado = float(get(gro))
        print(f"FD {name}: central {fd:.10e}, custom_vjp {ad:.10e}, jaxlens {ado:.10e}, "
              f"rel {abs(fd - ad) / abs(fd):.2e}")
    return out


def _while_bodies(txt):
    """{while-loop body: (fusions, HLO ops inside those fusions)} of a compiled HLO text."""
    import re

    comps, cur = {}, None
    for line in txt.splitlines():
        m = re.match(r"^(ENTRY )?%?([\w.\-]+) .*\{\s*$", line)
        if m and not line.startswith(" "):
            cur = m.group(2)
            comps[cur] = []
        elif cur:
            comps[cur].append(line)
    bodies = {re.search(r"body=%?([\w.\-]+)", ln).group(1)
              for lines in comps.values() for ln in lines if " while(" in ln}
    out = {}
    for name in bodies:
        calls = [re.search(r"calls=%?([\w.\-]+)", ln) for ln in comps[name]
                 if re.search(r"= \S+ fusion\(", ln)]
        ops = sum(sum(1 for x in comps.get(c.group(1), []) if " = " in x) for c in calls if c)
        out[name] = (len(calls), ops)
    return out


def count_fusions(n=1_000_000, **kw):
    """Fusions per while-loop body (chunk map, surface scan, their backward passes)."""
    lens = zoo.cooke_triplet()
    rays = throughput.make_rays(lens, n, jnp.float32)
    for name, f in zip(("fwd old", "fwd new", "f+g old", "f+g new"), fns(**kw), strict=True):
        txt = jax.jit(f.__wrapped__).lower(lens, rays).compile().as_text()
        bodies = _while_bodies(txt)
        big = sorted(((v, k) for k, v in bodies.items() if v[0] > 3), reverse=True)
        print(f"{name}: loop bodies with >3 fusions (fusions, fused HLO ops): "
              + ", ".join(f"{v}" for v, _ in big))
        if os.environ.get("DUMP"):
            with open(f"/tmp/vjp_probe_{name.replace(' ', '_').replace('+', '')}.hlo", "w") as fh:
                fh.write(txt)


def _values(out):
    """(origin, direction, valid, opl) of a ``jaxlens.trace`` result or ``trace_new``'s."""
    if isinstance(out, jaxlens.Rays):
        return out.origin, out.direction, out.valid, out.opl
    return out


def timing(n=1_000_000, repeats=7, variants=({},), dtype=jnp.float32):
    """Old and each new variant, forward and f+g, interleaved in one process, best of N.

    Returns {variant: forward_ms, grad_ms, grad_rel (value and gradient against jaxlens.trace's,
    max |Δ|/max|·| per leaf), same_values (forward outputs bit-identical to jaxlens.trace's)}.
    """
    lens = zoo.cooke_triplet()
    rays = throughput.make_rays(lens, n, dtype)
    dname = jnp.dtype(dtype).name
    fs = {}
    fo, _, go, _ = fns()
    fs["old"] = (fo, go)
    for i, var in enumerate(variants):
        if var.get("library"):  # the library's own rule: jaxlens.trace(reverse_rule=True)
            fo, _, go, _ = fns(reverse_rule=True)
            name = "jaxlens.trace reverse_rule=True"
            fs[name] = (fo, go)
        elif var.get("old"):  # jaxlens.trace with another chunk
            fo, _, go, _ = fns(old_chunk=var["chunk"])
            name = f"old chunk={var['chunk']}"
            fs[name] = (fo, go)
        else:
            kw = {k: v for k, v in var.items() if k not in OPTS}
            OPTS.update({k: v for k, v in var.items() if k in OPTS})
            _, fn, _, gn = fns(**kw)
            name = f"new {var}"
            fs[name] = (fn, gn)
        for f in fs[name] + (fs["old"] if i == 0 else ()):  # trace, compile, warm
            jax.block_until_ready(f(lens, rays))
            jax.block_until_ready(f(lens, rays))
    best = {(k, j): np.inf for k in fs for j in (0, 1)}
    cpu = dict(best)
    for _ in range(repeats):
        for k, pair in fs.items():
            for j, f in enumerate(pair):
                c0, t0 = time.process_time(), time.perf_counter()
                jax.block_until_ready(f(lens, rays))
                w = time.perf_counter() - t0
                if w < best[k, j]:
                    best[k, j], cpu[k, j] = w, time.process_time() - c0
    print(f"{n} rays, {dname}, best of {repeats}, load {os.getloadavg()[0]:.1f}")
    g_ref = jax.tree.leaves(fs["old"][1](lens, rays))
    rel, same = {}, {}
    ref = _values(fs["old"][0](lens, rays))
    for k in fs:  # gradients of each variant against jaxlens.trace's
        same[k] = all(bool(jnp.array_equal(a, b))
                      for a, b in zip(ref, _values(fs[k][0](lens, rays)), strict=True))
        worst = 0.0
        for a, b in zip(g_ref, jax.tree.leaves(fs[k][1](lens, rays)), strict=True):
            a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
            if np.max(np.abs(a)) > 0:
                worst = max(worst, float(np.max(np.abs(a - b)) / np.max(np.abs(a))))
        rel[k] = worst
        if k != "old" and "split': -1" not in k:
            print(f"  {k}: {dname} value and gradient vs old, max |Δ|/max|·| per leaf "
                  f"{worst:.1e}; forward values identical: {same[k]}")
    out = {}
    for k in fs:
        f, g = 1e3 * best[k, 0], 1e3 * best[k, 1]
        out[k] = dict(forward_ms=f, grad_ms=g, grad_rel=rel[k], same_values=same[k])
        print(f"  {k}: forward {f:.1f} ms, f+g {g:.1f} ms (cpu/wall {cpu[k, 1] / best[k, 1]:.2f}),"
              f" forward/(f+g) {f / g:.3f}")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--fusions", action="store_true")
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--save", nargs="*", default=["tg", "in"])
    ap.add_argument("--ckpt-chunk", nargs="*", type=int, default=[1])
    ap.add_argument("--ckpt-body", nargs="*", type=int, default=[0])
    ap.add_argument("--chunk", nargs="*", type=int, default=[CHUNK],
                    help="largest chunk of the new trace (jaxlens.trace keeps its default)")
    ap.add_argument("--old-chunk", nargs="*", type=int, default=[],
                    help="also time jaxlens.trace with these chunks")
    ap.add_argument("--library-rule", action="store_true",
                    help="also time jaxlens.trace(reverse_rule=True), the rule in the library "
                         "(give --save with no value to time only it against jaxlens.trace)")
    ap.add_argument("--split", nargs="*", type=int, default=[1],
                    help="0: _backward; 1: _backward_split (adjoint scalars as divisions); "
                         "2: the same with one division and an optimization barrier")
    a = ap.parse_args(argv)
    if a.check:
        check()
        return
    variants = [dict(save=save, ckpt_chunk=bool(cc), ckpt_body=bool(cb), split=sp)
                for save in a.save for cc in a.ckpt_chunk for cb in a.ckpt_body
                for sp in a.split]
    variants = [dict(v, chunk=c) if c != CHUNK else v for v in variants for c in a.chunk]
    variants += [dict(old=True, chunk=c) for c in a.old_chunk]
    variants += [dict(library=True)] if a.library_rule else []
    if a.fusions:
        for var in variants:
            print(var)
            OPTS.update({k: v for k, v in var.items() if k in OPTS})
            count_fusions(a.rays, **{k: v for k, v in var.items() if k not in OPTS})
    else:
        timing(a.rays, a.repeats, variants)


if __name__ == "__main__":
    main()
