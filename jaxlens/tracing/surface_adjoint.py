"""The surface step with hand-written reverse rules, for faster gradients of the trace.

``conic_step`` is ``step.surface_step`` for a refracting (or, on the image surface, only
intersecting) ``Standard`` surface (plane, sphere, conic), ``sag_step`` for a surface with
polynomial terms (``SAG_KINDS``: even and odd aspheres, hybrids, toroids, tilted planes,
Forbes Q-type aspheres, biconics, Zernike sag surfaces); neither
a mirror nor with an obscuration or aperture. Their values are ``surface_step``'s bit for bit
(the same operations from ``step``, in the same order, Newton's intersection included); their
derivatives (``reverse_step``, ``reverse_sag_step``: ``jax.custom_vjp``s, first prototyped in
benchmarks/vjp_probe.py) are written out by hand from the saved root ``t`` and refraction gain
``g``:

    t     implicit root. Conic: F(o + t d) = 0 with F = c(x² + y²) + c(1+k)z² − 2z; ∇F = −2N
          (N the step's unnormalised normal), so dt = (F_c dc + F_k dk − 2N·(do + t dd))/(2 d·N).
          Polynomial: F = z − sag(x, y; θ), ∇F = N = (−s_x, −s_y, 1), so
          dt = (sag_θ·dθ − N·(do + t dd))/(d·N) at the returned root (``step.intersect``'s
          last, differentiable Newton step gives it at the iterate before, a ``step.settled``
          step away: the two agree to about eps^(3/4)), without re-running the Newton
          iterations
    g     refraction gain, g·nn = R − mu·dn with R = ±sqrt(nn − mu²(nn − dn²)); R is rebuilt
          as g·nn + mu·dn (no square root), dR = d(R²)/(2R)
    d'    mu·d + g·N,  p' = o + t d (+ z_vertex),  opl' = opl + n1·t

A polynomial normal depends on the point and on θ through ``sag_and_grad``: its cotangents
(the sag's second derivatives) and the root's θ term come from a ``jax.vjp`` of the per-ray
``sag_and_grad`` inside the backward. The shared per-ray adjoint scalars (the cotangents of d·N,
N·N and mu, and the root term) each end in a division, which XLA:CPU never duplicates, so each
is written once and the output passes stay short (benchmarks/SPEED.md, "A hand-written reverse
rule"). A ``custom_vjp`` has no forward mode, so ``trace(reverse_rule=True)`` is for callers
that only take reverse-mode gradients; a hand-written ``custom_jvp`` of the same formulas (which
keeps forward mode) measured 5-34 % slower than this rule, and not faster than JAX's own
derivative of ``surface_step`` on a quiet machine. Rays invalid on entry or lost here pass
their cotangents through unchanged, as in ``surface_step``; a ray grazing the surface (|d·N|
below eps·|N|₁) gets no root derivative, as in ``conic_root.conic_root_arrays``.

``go_back`` (static, ``Lens.negative_propagation``) takes the root as ``step.intersect`` does
with it (ahead of the ray, else behind it: ``conic_root.AHEAD_ELSE_BEHIND``, and for polynomial
surfaces a second Newton search where the first found nothing ahead); the reverse rules need no
change, since they start from the root taken, wherever it lies on the line.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from ..optics.freeform import Biconic, ZernikeSag
from ..optics.qtype import QTypeAsphere
from ..optics.surfaces import EvenAsphere, Hybrid, OddAsphere, Standard, TiltedPlane
from ..optics.toroidal import Toroidal
from ..optics.xypolynomial import XYPolynomial
from .conic_root import AHEAD_ELSE_BEHIND, T_MAX, conic_root_arrays, conic_root_near, unmark
from .step import (
    RayState,
    bounded_div,
    intersect,
    refraction_gain,
    surface_normal,
)

# Surfaces that ``sag_step`` takes: ``surface_step`` intersects them by Newton's method and
# refracts at the normal (−s_x, −s_y, 1) of ``sag_and_grad``, and nothing else (a listed kind,
# so a new kind with its own rules in ``surface_step`` is not taken by mistake).
SAG_KINDS = (EvenAsphere, OddAsphere, Hybrid, TiltedPlane, Toroidal, QTypeAsphere, Biconic,
             ZernikeSag, XYPolynomial)


def supported(surface, *, reflects=False, obscured=None, apertures=()) -> bool:
    """Whether ``rule_step`` can take this surface (static): a ``Standard`` surface
    (``conic_step``) or one with polynomial terms of ``SAG_KINDS`` (``sag_step``), not a
    mirror and with no obscuration or aperture."""
    if reflects or obscured is not None or apertures:
        return False
    return type(surface) is Standard or (type(surface) in SAG_KINDS and surface.has_polynomial)


def _advance(first, refracts, params, p, d, valid, opl, go_back=False):
    """((new p, new d, new valid, new opl), t, g): ``surface_step``'s operations, in order."""
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
        # Static: as step.intersect's go_back (ahead of t_min, else behind, in one pass).
        mode = AHEAD_ELSE_BEHIND if go_back else True
        t_m = conic_root_near(mode, c, k, o, d, t_min)
    t, ok = unmark(t_m)
    if not first and not go_back:
        ok = ok & ((t >= -1e3 * eps * (1 + jnp.abs(o[2]))) | bk)
    x, y, z = (oi + t * di for oi, di in zip(o, d, strict=True))
    rim = sd**2 * (1 + 64 * eps)
    ok = ok & (x * x + y * y <= rim)
    normal = (-c * x, -c * y, 1.0 - c * (1.0 + k) * z) if refracts else None
    return _refracted(refracts, p, d, valid, opl, ok, (x, y, z), normal, zv, n1, n2, t)


def _refracted(refracts, p, d, valid, opl, ok, point, normal, zv, n1, n2, t):
    """((new p, new d, new valid, new opl), t, g) after Snell's law at ``point`` (as in
    ``surface_step``: TIR loses the ray); without ``refracts`` the rays only move (g = 0)."""
    g = jnp.zeros((), t.dtype)
    d_new = d
    if refracts:
        mu = n1 / n2
        g, no_tir = unmark(refraction_gain(d, normal, mu))
        d_new = tuple(jnp.where(no_tir, mu * di + g * ni, di)
                      for di, ni in zip(d, normal, strict=True))
        ok = ok & no_tir
    return _moved(p, d, valid, opl, ok, point, d_new, zv, n1, t), t, g


def _moved(p, d, valid, opl, ok, point, d_new, zv, n1, t):
    """(p, d, valid, opl) after the surface: rays that fail here keep their p and d."""
    v = valid & ok
    keep = lambda new, old: jnp.where(v, new, old)  # noqa: E731
    p2 = (keep(point[0], p[0]), keep(point[1], p[1]), keep(point[2] + zv, p[2]))
    d2 = tuple(keep(a, b) for a, b in zip(d_new, d, strict=True))
    return p2, d2, v, opl + jnp.where(v, n1 * t, 0.0)


def _geometry(params, p, d, v, t):
    """Point, normal N, d·N and where the root has a derivative (|d·N| > eps·|N|₁)."""
    c, k, _, zv, _, _, _ = params
    eps = jnp.finfo(p[0].dtype).eps
    o = (p[0], p[1], p[2] - zv)
    x = tuple(oi + t * di for oi, di in zip(o, d, strict=True))
    N = (-c * x[0], -c * x[1], 1.0 - c * (1.0 + k) * x[2])
    dn = d[0] * N[0] + d[1] * N[1] + d[2] * N[2]
    good = v & (jnp.abs(dn) > eps * (jnp.abs(N[0]) + jnp.abs(N[1]) + jnp.abs(N[2])))
    return x, N, dn, good


def _sum_like(x, like):
    """x summed over the axes that ``like`` (an index: a scalar or per ray) broadcast along."""
    shape = jnp.shape(like)
    x = jnp.sum(x, axis=tuple(range(x.ndim - len(shape))))
    axes = tuple(i for i, (a, b) in enumerate(zip(x.shape, shape, strict=True)) if b == 1 != a)
    return (jnp.sum(x, axis=axes, keepdims=True) if axes else x).astype(jnp.result_type(like))


def _index_cotangents(refracts, b_mu, t, L, v, n1, n2):
    """Cotangents of n_before and n_after: through mu = n1/n2 (``b_mu``) and the path n1·t."""
    tl = jnp.where(v, t * L, 0.0)
    if refracts:
        return _sum_like(b_mu / n2 + tl, n1), _sum_like(-b_mu * (n1 / (n2 * n2)), n2)
    return _sum_like(tl, n1), jnp.zeros_like(n2)


def _snell_adjoint(d, N, dn, g, mu, v, D):
    """Cotangents (of N, of d·N, of mu) of d' = mu·d + g·N from that of d' (``D``); zero on
    invalid rays."""
    mu2 = mu * mu
    nn = N[0] * N[0] + N[1] * N[1] + N[2] * N[2]
    R = g * nn + mu * dn
    # At the critical angle (R = 0, rebuilt to within rounding of mu·dn) the root's
    # slope, carried by the 1/R terms, is taken as zero, as in step.refraction_gain:
    # m drops those terms and R is replaced by 1.
    critical = jnp.abs(R) <= 4 * jnp.finfo(R.dtype).eps * jnp.abs(mu * dn)
    m = jnp.where(critical, 0.0, 1.0).astype(R.dtype)
    R = jnp.where(critical, 1.0, R)
    bg = D[0] * N[0] + D[1] * N[1] + D[2] * N[2]
    den = jnp.where(v, nn * R, 1.0)
    # Each shared adjoint scalar ends in a division: written once (see the module notes).
    b_dn = jnp.where(v, bg * (m * mu2 * dn - mu * R), 0.0) / den
    b_nn = jnp.where(v, bg * (m * 0.5 * (1.0 - mu2) - g * R), 0.0) / den
    b_mu = jnp.where(v, bg * (-m * mu * (nn - dn * dn) - dn * R)
                     + (D[0] * d[0] + D[1] * d[1] + D[2] * d[2]) * den, 0.0) / den
    bN = tuple(g * Di + b_dn * di + 2.0 * b_nn * Ni for Di, di, Ni in zip(D, d, N, strict=True))
    return bN, b_dn, b_mu


def _backward(refracts, params, p, d, v, t, g, cts):
    """Cotangents of (params, p, d, valid, opl) from those of the outputs."""
    c, k, sd, zv, n1, n2, _ = params
    P, D, _, L = cts
    (x, y, z), N, dn, good = _geometry(params, p, d, v, t)
    ck = c * (1.0 + k)
    mu = b_mu = None
    if refracts:
        mu = n1 / n2
        bN, b_dn, b_mu = _snell_adjoint(d, N, dn, g, mu, v, D)
        bx = (P[0] - c * bN[0], P[1] - c * bN[1], P[2] - ck * bN[2])
    else:
        bx = P
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
    # T and b_mu are zero on invalid rays already; so is P[2] − out_p[2] (the vertex's term).
    s_c = _sum_like(jnp.where(v, bc, 0.0), c)
    s_k = _sum_like(jnp.where(v, bk_, 0.0), k)
    s_zv = _sum_like(P[2] - out_p[2], zv)
    g_n1, g_n2 = _index_cotangents(refracts, b_mu, t, L, v, n1, n2)
    return (s_c, s_k, jnp.zeros_like(sd), s_zv, g_n1, g_n2, None), out_p, out_d, None, L


@functools.partial(jax.custom_vjp, nondiff_argnums=(0, 1, 2))
def reverse_step(first, refracts, go_back, params, p, d, valid, opl):
    """(p, d, valid, opl) after the surface; ``params`` = (c, k, semi_diameter, z_vertex,
    n_before, n_after, backward), ``backward`` where the ray may go back along its line
    (everywhere, ahead first, with the static ``go_back``).
    Reverse mode only (``jvp``/``jacfwd`` raise a TypeError)."""
    return _advance(first, refracts, params, p, d, valid, opl, go_back)[0]


def _reverse_fwd(first, refracts, go_back, params, p, d, valid, opl):
    out, t, g = _advance(first, refracts, params, p, d, valid, opl, go_back)
    return out, (params, p, d, out[2], t, g)


def _reverse_bwd(first, refracts, _go_back, res, cts):
    params, p, d, v, t, g = res
    return _backward(refracts, params, p, d, v, t, g, cts)


reverse_step.defvjp(_reverse_fwd, _reverse_bwd)


def conic_step(surface, z_vertex, st: RayState, n_before, n_after, *, first, refracts,
               gap=None, go_back=False) -> RayState:
    """``surface_step`` on a ``supported`` surface (same arguments, same values), with the
    hand-written reverse rule ``reverse_step`` (no forward mode)."""
    params = (surface.c, surface.k, surface.semi_diameter, z_vertex, n_before, n_after,
              _backward_flag(gap, first, n_before, n_after))
    p, d, v, opl = reverse_step(first, refracts, bool(go_back) and not first, params, st.p,
                                st.d, st.valid, st.opl)
    return RayState(p, d, v, opl)


def _advance_sag(first, refracts, iters, params, p, d, valid, opl, go_back=False):
    """((new p, new d, new valid, new opl), t, g): ``surface_step``'s operations, in order,
    on a surface with polynomial terms (Newton intersection, normal from ``sag_and_grad``)."""
    surface, zv, n1, n2, bk = params
    o = (p[0], p[1], p[2] - zv)
    t, ok = unmark(intersect(surface, o, d, iters, first=first, backward=None if first else bk,
                             go_back=go_back))
    if not first and not go_back:
        ok = ok & ((t >= -1e3 * jnp.finfo(t.dtype).eps * (1 + jnp.abs(o[2]))) | bk)
    x, y, z = (oi + t * di for oi, di in zip(o, d, strict=True))
    rim = surface.semi_diameter**2 * (1 + 64 * jnp.finfo(x.dtype).eps)
    ok = ok & (x * x + y * y <= rim)
    normal = surface_normal(surface, x, y, z) if refracts else None
    return _refracted(refracts, p, d, valid, opl, ok, (x, y, z), normal, zv, n1, n2, t)


def _shape(x, y, surface):
    """(sag, s_x, s_y) at (x, y): differentiated in the backward for the normal's
    derivatives (the sag's Hessian) and the root's derivative in the coefficients."""
    z, gx, gy, _ = surface.sag_and_grad(x, y)
    return z, gx, gy


def _backward_sag(refracts, params, p, d, v, t, g, cts):
    """Cotangents of (params, p, d, valid, opl): the root of F = z − sag(x, y; θ) on the ray
    has ∇F = N = (−s_x, −s_y, 1), so dt = −(N·(do + t dd) − sag_θ·dθ)/(d·N)."""
    surface, zv, n1, n2, _ = params
    P, D, _, L = cts
    x, y, _ = (oi + t * di for oi, di in zip((p[0], p[1], p[2] - zv), d, strict=True))
    (_, gx, gy), pull = jax.vjp(_shape, x, y, surface)
    N = (-gx, -gy, jnp.ones_like(gx))
    dn = d[0] * N[0] + d[1] * N[1] + d[2] * N[2]
    eps = jnp.finfo(dn.dtype).eps
    good = v & (jnp.abs(dn) > eps * (jnp.abs(N[0]) + jnp.abs(N[1]) + jnp.abs(N[2])))
    zero = jnp.zeros_like(gx)
    mu = b_mu = None
    if refracts:
        mu = n1 / n2
        bN, b_dn, b_mu = _snell_adjoint(d, N, dn, g, mu, v, D)
        # bN = g·D on rays lost before this surface: masked, or it would reach θ.
        bN = tuple(jnp.where(v, b, 0.0) for b in bN[:2])
        bx, by, _ = pull((zero, -bN[0], -bN[1]))  # through the normal's x, y dependence
        bX = (P[0] + bx, P[1] + by, P[2])
    else:
        bN, bX = (zero, zero), P
    b_t = n1 * L + bX[0] * d[0] + bX[1] * d[1] + bX[2] * d[2]
    T = jnp.where(good, b_t, 0.0) / jnp.where(good, dn, 1.0)
    bo = tuple(bxi - T * Ni for bxi, Ni in zip(bX, N, strict=True))
    if refracts:
        bd = tuple(mu * Di + b_dn * Ni + t * boi for Di, Ni, boi in zip(D, N, bo, strict=True))
    else:
        bd = tuple(Di + t * boi for Di, boi in zip(D, bo, strict=True))
    out_p = tuple(jnp.where(v, a, b) for a, b in zip(bo, P, strict=True))
    out_d = tuple(jnp.where(v, a, b) for a, b in zip(bd, D, strict=True))
    _, _, b_surface = pull((T, -bN[0], -bN[1]))  # the root's and the normal's θ terms
    s_zv = _sum_like(P[2] - out_p[2], zv)
    g_n1, g_n2 = _index_cotangents(refracts, b_mu, t, L, v, n1, n2)
    return (b_surface, s_zv, g_n1, g_n2, None), out_p, out_d, None, L


@functools.partial(jax.custom_vjp, nondiff_argnums=(0, 1, 2, 3))
def reverse_sag_step(first, refracts, iters, go_back, params, p, d, valid, opl):
    """``reverse_step`` for a surface with polynomial terms; ``params`` = (surface,
    z_vertex, n_before, n_after, backward), ``iters`` Newton iterations."""
    return _advance_sag(first, refracts, iters, params, p, d, valid, opl, go_back)[0]


def _sag_fwd(first, refracts, iters, go_back, params, p, d, valid, opl):
    out, t, g = _advance_sag(first, refracts, iters, params, p, d, valid, opl, go_back)
    return out, (params, p, d, out[2], t, g)


def _sag_bwd(first, refracts, iters, _go_back, res, cts):
    params, p, d, v, t, g = res
    return _backward_sag(refracts, params, p, d, v, t, g, cts)


reverse_sag_step.defvjp(_sag_fwd, _sag_bwd)


def _backward_flag(gap, first, n_before, n_after):
    """Where the ray may go back along its line (as in ``surface_step``; never a mirror)."""
    if gap is None or first:
        return jnp.zeros((), bool)
    return (gap < 0) | ((gap == 0) & jnp.all(n_before == n_after))


def sag_step(surface, z_vertex, st: RayState, n_before, n_after, *, first, refracts,
             newton_iters, gap=None, go_back=False) -> RayState:
    """``surface_step`` on a ``supported`` surface with polynomial terms (same arguments,
    same values), with the hand-written reverse rule ``reverse_sag_step``."""
    params = (surface, z_vertex, n_before, n_after,
              _backward_flag(gap, first, n_before, n_after))
    p, d, v, opl = reverse_sag_step(first, refracts, newton_iters,
                                    bool(go_back) and not first, params, st.p, st.d,
                                    st.valid, st.opl)
    return RayState(p, d, v, opl)


def rule_step(surface, z_vertex, st: RayState, n_before, n_after, *, first, refracts,
              newton_iters, gap=None, go_back=False) -> RayState:
    """``conic_step`` or ``sag_step``, whichever takes this ``supported`` surface;
    ``go_back`` (static) as in ``step.surface_step``."""
    if type(surface) is Standard:
        return conic_step(surface, z_vertex, st, n_before, n_after, first=first,
                          refracts=refracts, gap=gap, go_back=go_back)
    return sag_step(surface, z_vertex, st, n_before, n_after, first=first, refracts=refracts,
                    newton_iters=newton_iters, gap=gap, go_back=go_back)
