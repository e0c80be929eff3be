"""The closed-form intersection of a ray with a conic, and the ``MISS`` marker that carries a
root's validity in its value.

The surface step (``step.intersect``) takes its conic roots here: the numerically stable
pair of the quadratic, chosen on numerators and denominators so that the result is one
division, with the implicit-function derivative dt = −dF/F_t (a ``custom_jvp``); the
hand-written reverse rule (``surface_adjoint``) takes the same roots. Units: mm; o and d
in the surface's local frame (z along its axis, vertex at the origin).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

# No lens needs a ray parameter beyond this (mm); larger roots are treated as misses, which
# also keeps every division below bounded, so gradients stay finite.
T_MAX = 1e12


# Marker for "no valid result" in a ray parameter or a refraction gain; valid values are
# far smaller (|t| < 2 T_MAX), so |x| < MISS_BELOW tells them apart in float32 and float64.
MISS = 1e30
MISS_BELOW = 1e29


def unmark(x):
    """(x with marked entries set to 0, validity)."""
    ok = jnp.abs(x) < MISS_BELOW
    return jnp.where(ok, x, 0.0), ok


# ``conic_root_arrays``'s mode for ``intersect``'s ``go_back``: the first root at or past
# t_min, else the nearest root behind it, the first met going back along the line (both
# from one quadratic).
AHEAD_ELSE_BEHIND = "ahead_else_behind"


def conic_root_near(mode, c, k, o, d, t_min):
    """``conic_root_arrays(mode, ...)`` solved from the ray's point nearest the vertex: t from
    ``o`` (marked ``MISS`` on a miss). ``o``, ``d``: (x, y, z) tuples in the surface's frame.

    The quadratic's coefficients hold c·|o|² and |o|, which cancel to the root's size: from a
    point L mm away the root loses about (1 + |c|·L)² ulps (1e-8 mm at 1e5 mm before a
    50 mm radius, round 43e). Carried first along its line by t_n = −o·d (no division), the
    ray starts no farther from the vertex than it was, usually within the surface's own
    size, and the carry costs one rounding of t_n, which any point o + t·d carries anyway.
    Surface 1 is solved from the vertex plane instead (``intersect``): its root is the one
    nearest that plane.
    """
    return conic_root_arrays(mode, c, k, *o, *d, t_min, True)


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 10))
def conic_root_arrays(bounded_below, c, k, ox, oy, oz, dx, dy, dz, t_min, near=False):
    """Closed-form intersection with the base conic; returns t, marked MISS on a miss.

    ``o`` and ``d`` are (x, y, z) tuples of arrays in the surface's local frame, with ``o``
    near the surface (see ``intersect``). Of the two roots of
    c(x² + y²) + c(1+k)z² − 2z = 0, only those on the sheet through the vertex
    (1 − c(1+k)z ≥ 0) and with t_min ≤ t count; the first along the ray is taken. With
    ``bounded_below=False`` (object space, ``o`` on the vertex plane) any t counts and the
    root nearer to ``o`` is taken: a paraboloid concave toward the object meets a tilted
    line a second time far behind its vertex (1° off axis, 6.6e5 mm away), which the first
    root along the line would pick. The roots are the stable pair t1 = cc/q (finite as c -> 0) and
    t2 = q/a; which one is chosen is decided on numerators and denominators, so the
    result is a single division (one fused pass over the rays, see the module notes).
    With ``bounded_below=AHEAD_ELSE_BEHIND`` (``intersect``'s ``go_back``) the root is the
    first past t_min if there is one, else the nearest one behind it (the larger t of the
    roots on the sheet): the point where the ray, going back along its line, first meets
    the surface. (A steep ray can meet a sphere's vertex sheet twice behind it; the first
    root along the whole line, taken before round 43d, lay on the far side of the sheet,
    40 mm back and across the axis on a real patent lens, where optiland and Zemax's
    vertex-sheet root take the near one.)
    With ``near`` (static) the quadratic is solved from the ray's point nearest the vertex
    (``conic_root_near``); t is still measured from ``o``, in the same one division.
    """
    if near:
        t_n = -(ox * dx + oy * dy + oz * dz)
        ox, oy, oz = ox + t_n * dx, oy + t_n * dy, oz + t_n * dz
        # t_min shifted with the start, less the shift's rounding (a root at t_min stays in).
        t_min = t_min - t_n - 4 * jnp.finfo(t_n.dtype).eps * jnp.abs(t_n)
    ck = c * (1 + k)
    a = c * (dx * dx + dy * dy) + ck * dz * dz
    b = c * (ox * dx + oy * dy) + ck * oz * dz - dz
    cc = c * (ox * ox + oy * oy) + ck * oz * oz - 2 * oz
    disc = b * b - a * cc
    real = disc >= 0
    pos = disc > 0
    root = jnp.where(pos, jnp.sqrt(jnp.where(pos, disc, 1.0)), 0.0)
    q = -b + jnp.where(b <= 0, root, -root)

    def usable(num, den, past_t_min=bool(bounded_below)):
        """Whether the root num/den is bounded, on the vertex sheet and (if asked) past t_min."""
        sign, size = jnp.sign(den), jnp.abs(den)
        ok = real & (jnp.abs(num) < T_MAX * size)
        ok = ok & (ck * (oz * den + num * dz) * sign <= size)
        if past_t_min:
            ok = ok & (num * sign >= t_min * size)
        return ok

    u1, u2 = usable(cc, q), usable(q, a)
    if bounded_below == AHEAD_ELSE_BEHIND:  # static: ahead of t_min, else anywhere on the line
        sign = jnp.sign(q) * jnp.sign(a)
        t1_first = cc * a * sign <= q * q * sign
        # The roots anywhere on the line: on the sheet and bounded (|t| < T_MAX).
        w1, w2 = usable(cc, q, False), usable(q, a, False)
        ahead = u1 | u2
        # Ahead: the first root past t_min; behind: the last root before it (nearest).
        first_is_t1 = jnp.where(ahead, u1 & (~u2 | t1_first), w1 & (~w2 | ~t1_first))
        u1, u2 = u1 | w1, u2 | w2
    elif bounded_below:  # the first root along the ray
        # t1 <= t2  <=>  cc·a <= q² when q·a > 0 (the inequality flips when q·a < 0).
        sign = jnp.sign(q) * jnp.sign(a)
        first_is_t1 = u1 & (~u2 | (cc * a * sign <= q * q * sign))
    else:  # object space, o on the vertex plane: the root nearer to it, |t1| <= |t2|
        first_is_t1 = u1 & (~u2 | (jnp.abs(cc * a) <= q * q))
    hit = u1 | u2
    num = jnp.where(first_is_t1, cc, q)
    den = jnp.where(first_is_t1, q, a)
    if near:  # t from o: t_n + num/den
        num = num + t_n * den
    return jnp.where(hit, num, MISS) / jnp.where(hit, den, 1.0)


@conic_root_arrays.defjvp
def _conic_root_jvp(bounded_below, near, primals, tangents):
    """Implicit-function derivative dt = −dF/F_t of F = c(x² + y²) + c(1+k)z² − 2z on the ray.

    It reuses the root, so the gradient costs a few multiplies instead of the derivative
    of the quadratic formula and its root selection.
    """
    c, k, ox, oy, oz, dx, dy, dz, _ = primals
    tc, tk, tox, toy, toz, tdx, tdy, tdz, _ = tangents
    t_marked = conic_root_arrays(bounded_below, *primals, near)
    t, hit = unmark(t_marked)
    x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
    fx, fy, fz = 2 * c * x, 2 * c * y, 2 * c * (1 + k) * z - 2  # ∇F
    f_t = fx * dx + fy * dy + fz * dz
    df = (
        (x * x + y * y + (1 + k) * z * z) * tc
        + c * z * z * tk
        + fx * (tox + t * tdx)
        + fy * (toy + t * tdy)
        + fz * (toz + t * tdz)
    )
    # A ray tangent to the surface (cos of incidence below eps) gets zero derivative; the
    # guard must not look at the tangents (they enter linearly).
    eps = jnp.finfo(f_t.dtype).eps
    good = hit & (jnp.abs(f_t) > eps * (jnp.abs(fx) + jnp.abs(fy) + jnp.abs(fz)))
    return t_marked, jnp.where(good, -df / jnp.where(good, f_t, 1.0), 0.0)
