"""The surface step: intersection, vector Snell refraction (or reflection at a mirror),
validity and optical path.

Every trace (forward, backward from the sensor, the design loss) moves rays with
``surface_step``; it is the only place in jaxlens that refracts, reflects or diffracts
(``refract_diffract``: the local grating equation of the diffractive surfaces, ``Binary2``
and ``Grating``, in transmission and, for a ``Grating`` mirror, in reflection).

Conventions:
    Global coordinates in mm, light toward +z, surface 1's vertex at z = 0 (see
    ``jaxlens.optics.lens``). Rays start in object space: a ray is the whole line through its
    origin, so its intersection with surface 1 may lie behind the origin (a pupil
    point given on an entrance-pupil plane inside the lens is fine). After surface 1,
    a ray that would have to travel backward (t < 0) is invalid, except across a
    negative gap (a surface whose vertex lies before the previous one, legal in Zemax
    files) or to a dummy surface (same index on both sides) on the previous vertex plane,
    such as a reference plane at a mirror: there the ray goes back along its line to the
    surface where it must, as in a sequential trace. With ``go_back`` (a lens's
    ``negative_propagation``, set for lenses read from Zemax files) every surface after the
    first is reached the way Zemax reaches it: the first root ahead of the ray if there is
    one, else the nearest behind it (t < 0: the first point met going back along its line),
    on the surface's sheet through its vertex; a ray the default rule traces takes the same
    root.

Intersections:
    Planes, spheres and conics are intersected in closed form (the numerically stable
    roots of the quadratic, solved from the ray's point nearest the vertex after surface 1:
    ``conic_root_near``), which is exact; its derivative is the implicit-function one,
    dt = −dF/F_t on the implicit conic F (a ``custom_jvp``, so forward and reverse mode
    both work and neither differentiates the root selection). Surfaces
    with polynomial terms take ``newton_iters`` Newton steps on F(t) = z(t) − sag(x(t),
    y(t)), from the base conic's root or the vertex plane, whichever gives the shorter
    first step, kept at t ≥ t_min (projected Newton); a ray whose iterate is then not yet
    ``settled`` (``converged`` and a next step of at most eps^(3/4)·(1 + |t|) mm) goes on,
    alone, until it is, or gives up (``continue_newton``: a ``while_loop`` whose body does not
    run when every ray is settled, the common case). A ray is a hit where its last iterate is
    ``converged``: |F| ≤ τ and a next step |F/F'| ≤ τ, τ = 64·sqrt(eps)·(1 + |t|) mm, so the
    point returned lies within about τ of a root along the ray (1e-6 mm in float64), also
    for a grazing ray (near a double root), and a ray with no root is a miss unless it
    touches the surface to about |F''|·τ²/2 (see ``converged``). Those iterations carry no
    gradient. One last Newton step is taken with gradients switched on and the derivative
    F'(t) held fixed; at the converged root its derivative is exactly the implicit-function
    theorem result dt/dθ = −(∂F/∂θ)/(∂F/∂t), so the backward pass never unrolls the
    iterations.

Fusion:
    Each expensive per-ray result (the root t, the refraction gain) is returned as one
    array that also carries its validity: an invalid entry holds the marker ``MISS``.
    XLA's CPU backend fuses a computation into one pass over the rays only when it
    has a single output, so a (value, flag) pair would cost extra passes over memory
    per surface (benchmarks/SPEED.md). A finite marker, not NaN, keeps
    ``jax_debug_nans`` usable.

Validity:
    A ray is invalid once it misses a surface (no real root, outside the conic's
    domain, or Newton did not converge), is clipped by a semi-diameter, undergoes
    total internal reflection, or would travel backward. Invalid rays keep finite
    values (they stop where they failed), and every guard is a "double where", so
    gradients are finite everywhere.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ..optics.apertures import passes_all
from ..optics.diffractive import DIFFRACTIVE, Grating
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.rays import Rays
from ..optics.surfaces import AbstractSurface
from .conic_root import (
    AHEAD_ELSE_BEHIND,
    MISS,
    T_MAX,
    conic_root_arrays,
    conic_root_near,
    unmark,
)

DEFAULT_NEWTON_ITERS = 6

# Past the fixed steps, a ray whose iterate is not yet ``settled`` takes up to this many more
# (``continue_newton``); a hit needs |F| and the next step |F/F'| both at most
# NEWTON_TOL·sqrt(eps)·(1 + |t|) mm (``converged``).
NEWTON_EXTRA_ITERS = 40
NEWTON_TOL = 64.0


def bounded_div(num, den):
    """num/den where |num/den| < T_MAX (tested without dividing), else 0; and that flag.

    Guarding by size, not only by zero, keeps the unselected branch's derivative
    (−num/den²) finite, so a tiny denominator never puts NaN into a gradient.
    """
    ok = jnp.abs(num) < T_MAX * jnp.abs(den)
    return jnp.where(ok, num / jnp.where(ok, den, 1.0), 0.0), ok


def _conic_root(surface: AbstractSurface, o, d, t_min, go_back=False):
    """The first intersection with the base conic: ``conic_root_arrays`` on a surface (after
    surface 1 from the ray's point nearest the vertex, ``conic_root_near``)."""
    if t_min is None:
        return conic_root_arrays(False, surface.c, surface.k, *o, *d, jnp.zeros_like(o[2]))
    return conic_root_near(AHEAD_ELSE_BEHIND if go_back else True, surface.c, surface.k, o, d,
                           t_min)


def converged(f, df, t):
    """Whether the Newton iterate ``t`` (mm) is accepted as a root of F (a hit): with
    τ = 64·sqrt(eps)·(1 + |t|) mm (``NEWTON_TOL``), |F(t)| ≤ τ and the next Newton step
    |F/F'| ≤ τ, F finite and F'(t) ≠ 0. The accepted iterate then takes one more
    (differentiable) Newton step, of at most τ, which squares its error at a simple root.

    The bound on the step is what makes the test honest near a double root (a ray grazing
    the surface, F' small): |F| ≤ τ alone accepted iterates up to sqrt(2τ/|F''|), about
    1e-3 mm in float64, from the root, and rays that miss the surface by up to τ (1e-6 mm)
    as hits, whose last step, divided by the small F', then landed anywhere. With it an
    accepted iterate is within about τ of a root along the ray (a rounding-limited
    near-double root is found to its rounding), and a ray that has no root is accepted only
    where it passes within about |F''|·τ²/2 of the surface (F's minimum; 1e-12 mm in
    float64 for |F''| ~ 0.1 /mm), i.e. touches it at rounding. Implied by ``settled``."""
    eps = jnp.finfo(jnp.result_type(f)).eps
    tol = NEWTON_TOL * jnp.sqrt(eps) * (1.0 + jnp.abs(t))
    return (jnp.abs(f) <= tol * jnp.minimum(1.0, jnp.abs(df))) & jnp.isfinite(f) & (df != 0)


def _small_residual(f, df, t):
    """|F| ≤ τ (``converged`` without its bound on the step, which ``settled`` implies), F
    finite and F' ≠ 0: the test inside ``continue_newton``, kept as lean as it was."""
    eps = jnp.finfo(jnp.result_type(f)).eps
    return (jnp.abs(f) <= NEWTON_TOL * jnp.sqrt(eps) * (1.0 + jnp.abs(t))) & jnp.isfinite(f) & (
        df != 0)


def settled(f, df, t):
    """Whether the iterate ``t`` is ``converged`` and its next Newton step, |F/F'|, is at most
    eps^(3/4)·(1 + |t|) mm: then it lies at rounding from the root (up to the square of that,
    times the curvature), and the implicit derivative that the last step takes there is the
    root's (``surface_adjoint``'s reverse rule takes it at the root), to about eps^(3/4)."""
    eps = jnp.finfo(jnp.result_type(f)).eps
    small = jnp.abs(f) <= eps**0.75 * (1.0 + jnp.abs(t)) * jnp.abs(df)
    return _small_residual(f, df, t) & small  # = converged & small (small bounds the step)


def continue_newton(residual, t, project=lambda t: t, max_iters: int = NEWTON_EXTRA_ITERS):
    """Newton steps past the fixed ones, only on the rays not yet ``settled``.

    A ``jax.lax.while_loop`` that runs while some ray is still iterating: where every ray is
    settled at ``t`` (after six steps on an ordinary asphere, every ray is: the next step is at
    rounding) its body never runs, so the common case costs one residual pass and a reduction,
    and the result is ``t`` itself, bit for bit, with that pass's F and F'. A ray iterates until
    it is ``settled``. It gives up (it is then a miss, unless already ``converged``) when its
    step does not shrink (Newton from a good start shrinks it, by at least half per step even at
    a double root; with no root F has no zero to approach and the steps jump about), is zero
    (held at ``project``'s bound with F of the wrong sign, or at rounding) or cannot be taken
    (F' too small to divide, F not finite); at most ``max_iters`` more steps. It carries no
    gradient (stop the gradients of its inputs): the caller differentiates the root by the
    implicit function theorem.

    Args:
        residual: t -> (F(t), F'(t)), elementwise on ``t``.
        t: the iterates ``[*batch]`` after the fixed steps.
        project: t -> the admissible t (projected Newton), elementwise.
        max_iters: the most extra steps (static).

    Returns:
        (t, F(t), F'(t)) of the final iterates ``[*batch]``: t unchanged where already
        settled.
    """
    f, df = residual(t)
    # The loop's test is a scalar: whether any ray iterates. Per ray, one array: the length
    # of the step that reached its iterate (inf before the first), −1 once it has stopped;
    # a settled ray stops in the first pass (a flag and a length would be two arrays, and
    # one computed from the residual here would be a second pass over the rays).
    last = jnp.full_like(t, jnp.inf)
    going0 = jnp.any(~settled(f, df, t))

    def going(state):
        k, _, _, _, _, more = state
        return (k < max_iters) & more

    def body(state):
        # F and F' at t come in with it (evaluated where t was set), so the caller gets
        # them for the final iterates without another residual pass.
        k, t, f, df, last, _ = state
        dt, ok = bounded_div(f, df)
        t_new = project(t - dt)
        size = jnp.abs(t_new - t)
        go = (last >= 0) & ~settled(f, df, t) & ok & jnp.isfinite(f) & (size < last) & (
            size > 0)
        t = jnp.where(go, t_new, t)
        return k + 1, t, *residual(t), jnp.where(go, size, -1.0), jnp.any(go)

    return jax.lax.while_loop(going, body, (0, t, f, df, last, going0))[1:4]


def first_of_a_pair(residual, t, f, df, ok):
    """The first root ahead of each ray where Newton found a later one (roots ``t``, with
    F(t) = ``f`` and F'(t) = ``df``; ``ok`` where ``t`` is a hit that must be the first
    root with t > 0). Returns (t, F(t), F'(t)).

    A ray that starts close to a near-double root (it grazes the surface, entering and
    leaving it a short way apart) can converge to the second root of the pair. F keeps the
    sign of F(0) (the start) up to the first root, so at the first root F' has the other
    sign; a root whose F' has F(0)'s sign had a root before it, and F changes sign between
    the start and just before it: bisection finds that root there. The test needs F(0),
    two more residual passes, taken only where some hit has F' < 0 (the sign of every first
    root from a start before the surface, F(0) < 0; always after a mirror, where rays
    travel toward −z); bisection runs only where some ray needs it. Forward values only
    (no gradient): the caller's last step takes the implicit derivative at the root."""
    eps = jnp.finfo(jnp.result_type(t)).eps
    steps = BISECTION_STEPS[jnp.result_type(t) == jnp.float32]
    suspect = ok & (df < 0)

    def check(args):
        t, f, df = args
        f_start = residual(jnp.zeros_like(t))[0]
        tol = NEWTON_TOL * jnp.sqrt(eps)
        # Just before t, F has the sign of −F'(t): the bracket's end, a few tolerances back.
        hi = t - 16 * tol * (1 + jnp.abs(t))
        skipped = (suspect & (jnp.sign(f_start) == jnp.sign(df)) & (jnp.abs(f_start) > tol)
                   & (hi > 0) & (jnp.sign(residual(hi)[0]) == -jnp.sign(f_start)))

        def bisect(_, bracket):
            lo, up = bracket
            mid = 0.5 * (lo + up)
            same = jnp.sign(residual(mid)[0]) == jnp.sign(f_start)
            return jnp.where(same, mid, lo), jnp.where(same, up, mid)

        def search(args):
            t, f, df = args
            lo, up = jax.lax.fori_loop(0, steps, bisect, (jnp.zeros_like(t), hi))
            found = continue_newton(residual, jnp.where(skipped, 0.5 * (lo + up), t))
            return tuple(jnp.where(skipped, a, b) for a, b in
                         zip(found, (t, f, df), strict=True))

        return run_if_any(skipped, search, (t, f, df))

    return run_if_any(suspect, check, (t, f, df))


# Bisection steps that take a bracket of up to 1e4 mm to rounding (float64, float32).
BISECTION_STEPS = (80, 40)


def run_if_any(flags, fn, x):
    """``fn(x)`` where any of ``flags`` is set, else ``x``: a ``while_loop`` of at most one
    pass, because under ``vmap`` a ``lax.cond`` on a batched predicate becomes a select that
    always runs ``fn``, while a batched ``while_loop`` runs only while some member needs
    it. Forward values only (``while_loop`` has no reverse-mode derivative)."""
    def body(state):
        return jnp.zeros((), bool), fn(state[1])

    return jax.lax.while_loop(lambda state: state[0], body, (jnp.any(flags), x))[1]


def _residual(surface: AbstractSurface, o, d, t):
    px, py, pz = (oi + t * di for oi, di in zip(o, d, strict=True))
    z, gx, gy, inside = surface.sag_and_grad(px, py)
    return pz - z, d[2] - gx * d[0] - gy * d[1], inside


def intersect(
    surface: AbstractSurface, o, d, newton_iters: int = DEFAULT_NEWTON_ITERS, *, first=False,
    backward=None, go_back: bool = False,
):
    """Intersect rays with a surface in its local frame (vertex at the origin).

    With ``first=False`` the first intersection along the ray with t ≥ 0 (up to rounding)
    is taken; with ``first=True`` (object space) the whole line counts and the intersection
    nearest the vertex plane is taken.
    On the first surface each ray is first carried along its line to the vertex plane, so
    the quadratic is solved from a point near the surface: a distant origin (an object at
    10 m) then loses no digits to cancellation. Later surfaces start from the previous
    surface, a few mm away, and skip that step.

    Args:
        surface: the surface.
        o, d: (x, y, z) tuples of ``[*batch]`` arrays: ray points and unit directions.
        newton_iters: Newton iterations that every ray takes on a surface with polynomial
            terms; a ray not yet ``settled`` then takes up to ``NEWTON_EXTRA_ITERS`` more.
            0: none at all, the last step is taken from the start.
        first: whether this is the first surface (object space).
        backward: bool array, True where the gap to this surface is negative (its vertex
            lies before the previous one, as Zemax files allow): there the ray may travel
            back along its line to reach the surface (t < 0 counts, the first root along
            the line is taken). ``None``: no negative gaps.
        go_back: (static; ignored on the first surface) the ray may go back along its
            line to the surface anywhere (Zemax's negative propagation): the root found
            with the rules above where there is one (so such rays are unchanged), else the
            nearest root behind the ray (t ≥ −``T_MAX``, the vertex sheet), where the ray
            going back along its line first meets the surface:
            for a conic both from one quadratic (``AHEAD_ELSE_BEHIND``); on a polynomial
            surface the Newton search (one compiled program) runs a second time, with
            t ≥ −``T_MAX``, only where some ray found no root ahead.

    Returns:
        The ray parameter t of the intersection (from ``o``), ``[*batch]``, holding the
        ``MISS`` marker where no valid intersection was found (see ``unmark``).
    """
    eps = jnp.finfo(o[2].dtype).eps
    if first:
        t_min = None
        t_plane, _ = bounded_div(-o[2], d[2])  # 0 for rays parallel to the plane
        o = tuple(oi + t_plane * di for oi, di in zip(o, d, strict=True))
    else:
        t_min = -1e3 * jax.lax.stop_gradient(eps * (1 + jnp.abs(o[2])))
        if backward is not None:
            t_min = jnp.where(backward, -T_MAX, t_min)
        t_plane = 0.0
    if go_back and not first:  # static: Zemax's rule (see above)
        if not surface.has_polynomial:  # both roots from one quadratic
            return _conic_root(surface, o, d, t_min, go_back=True)
    if not surface.has_polynomial:
        # Conics: the closed form is exact (its derivative: ``_conic_root_jvp``).
        return _conic_root(surface, o, d, t_min) + t_plane
    o_s, d_s = jax.lax.stop_gradient((o, d))
    surf_s = jax.lax.stop_gradient(surface)
    if go_back and not first:  # static: the search ahead, then behind where it found nothing
        def more(state):
            k, _, _, _, ok = state
            return (k == 0) | ((k == 1) & jnp.any(~ok))

        def search(state):  # one compiled search, run once or twice
            k, t, f, df, ok = state
            behind = k == 1
            found = _polynomial_root(surf_s, o_s, d_s, jnp.where(behind, -T_MAX, t_min),
                                     newton_iters, False, backward, behind, t_min)
            take = ~ok  # pass 0: every ray; pass 1: the rays without a root ahead
            return (k + 1, *(jnp.where(take, a, b) for a, b in
                             zip(found, (t, f, df, ok), strict=True)))

        zeros = jnp.zeros_like(o_s[2])
        _, t0, f0, df0, ok = jax.lax.while_loop(
            more, search, (0, zeros, zeros, zeros, jnp.zeros(zeros.shape, bool)))
    else:
        t0, f0, df0, ok = _polynomial_root(surf_s, o_s, d_s, t_min, newton_iters, first,
                                           backward)
    # Flagged rays take the last step at a harmless point, so their gradient stays finite.
    t0 = jnp.where(ok, t0, 0.0)
    df0 = jax.lax.stop_gradient(jnp.where(ok, df0, 1.0))
    # One differentiable step with F' held fixed: the implicit-function gradient.
    f, _, inside = _residual(surface, o, d, t0)
    # That step's root t1 has exact first derivatives only (t0 and F' are constants to it).
    # A second step from t1 with F' live makes the second derivatives exact too (Newton's
    # map has zero slope at a root): a gradient of a derivative of the trace (such as
    # ``field_curvature``'s differential rays) was wrong on every surface with polynomial
    # terms without it (round 36e).
    t1 = t0 - f / df0
    f1, df1, inside = _residual(surface, o, d, t1)
    df1 = jnp.where(ok, df1, 1.0)
    ok = ok & inside
    # t1 + t_plane − f1/df1, written as one division (one fused pass, see the module notes).
    return jnp.where(ok, (t1 + t_plane) * df1 - f1, MISS) / jnp.where(ok, df1, 1.0)


def _polynomial_root(surf_s, o_s, d_s, t_min, newton_iters, first, backward, behind=None,
                     ahead_min=None):
    """(t, F(t), F'(t), hit) of the Newton search on a surface with polynomial terms
    (``intersect``; forward values only): the first root with t ≥ ``t_min`` (None: on the
    first surface, the root nearest the vertex plane); for rays searching ahead (not
    ``backward``, not ``behind``) the first of a near-double pair. Searching ``behind``
    (``intersect``'s ``go_back``, ``t_min`` then −``T_MAX``), Newton starts from the base
    conic's root nearest behind ``ahead_min`` (``AHEAD_ELSE_BEHIND``), as a conic's own
    go-back root is taken."""
    # Two starts: the base conic's root and the vertex plane (t = 0 on surface 1, where the
    # rays already are). Newton begins at the one whose first step is shorter: where the
    # polynomial terms move the surface far from its base conic, the ray can graze the
    # surface at the conic root (F' ≈ 0) and the first step would throw it kilometres away.
    if behind is None:
        t_conic, hit = unmark(_conic_root(surf_s, o_s, d_s, t_min))
    else:
        marked = jnp.where(behind, _conic_root(surf_s, o_s, d_s, ahead_min, go_back=True),
                           _conic_root(surf_s, o_s, d_s, t_min))
        t_conic, hit = unmark(marked)
    t_vertex = jnp.zeros_like(t_conic) if first else bounded_div(-o_s[2], d_s[2])[0]

    def project(t):
        # Projected Newton: a root before t_min is invalid anyway, so an overshoot behind
        # the ray's start restarts from t_min instead of wandering back.
        return t if t_min is None else jnp.maximum(t, t_min)

    def newton_step(t, f, df):
        """The next iterate and the step's length (inf where F' is too small to divide)."""
        dt, ok = bounded_div(f, df)
        return project(t - dt), jnp.where(ok, jnp.abs(dt), jnp.inf)

    f_c, df_c, _ = _residual(surf_s, o_s, d_s, t_conic)
    f_v, df_v, _ = _residual(surf_s, o_s, d_s, t_vertex)
    t_c, step_c = newton_step(t_conic, f_c, df_c)
    t_v, step_v = newton_step(t_vertex, f_v, df_v)
    from_conic = hit & (step_c <= step_v)
    if newton_iters == 0:
        t0 = jnp.where(from_conic, t_conic, t_vertex)
    else:  # the first iteration, taken from the chosen start
        t0 = jnp.where(from_conic, t_c, t_v)

    def step(_, t):
        f, df, _ = _residual(surf_s, o_s, d_s, t)
        return newton_step(t, f, df)[0]

    t0 = jax.lax.fori_loop(0, max(newton_iters - 1, 0), step, t0)
    if newton_iters > 0:
        t0, f0, df0 = continue_newton(lambda t: _residual(surf_s, o_s, d_s, t)[:2], t0,
                                      project)
    else:
        f0, df0, _ = _residual(surf_s, o_s, d_s, t0)
    ok = converged(f0, df0, t0)
    if t_min is not None:
        ok = ok & (t0 >= t_min)
        ahead_only = True if backward is None else ~backward
        if behind is not None:
            ahead_only = ahead_only & ~behind
        t0, f0, df0 = first_of_a_pair(lambda t: _residual(surf_s, o_s, d_s, t)[:2], t0, f0,
                                      df0, ok & ahead_only)
        ok = converged(f0, df0, t0) & (t0 >= t_min)
    return t0, f0, df0, ok


def refraction_gain(d, normal, mu):
    """Vector Snell's law: the gain g such that the refracted direction is mu·d + g·normal.

    Args:
        d: unit incident directions, an (x, y, z) tuple of arrays.
        normal: surface normals of any length and either orientation.
        mu: n_before / n_after.

    Returns:
        g, marked ``MISS`` where the ray undergoes total internal reflection.
    """
    # With |n|² = nn and d·n = dn (cos_i = dn/|n|), the unit-normal result
    # mu·d + (±sqrt(1 − mu²(1 − cos_i²)) − mu·cos_i)·n/|n| has the gain
    # (±sqrt(nn − mu²(nn − dn²)) − mu·dn)/nn: one division, no rsqrt.
    nn = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]
    dn = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]
    k = nn - mu * mu * (nn - dn * dn)
    ok = (k >= 0) & (nn > 0)
    # At the critical angle (k = 0) the square root's slope is infinite: there the root is a
    # constant 0, so no 0·inf reaches a gradient (the slope is taken one-sided, as zero).
    above = ok & (k > 0)
    root = jnp.where(above, jnp.sqrt(jnp.where(above, k, 1.0)), 0.0)
    g = jnp.where(dn < 0, -root, root) - mu * dn
    return jnp.where(ok, g, MISS) / jnp.where(ok, nn, 1.0)


def refract(d, normal, mu):
    """Vector Snell's law on (x, y, z) tuples of arrays.

    Args:
        d: unit incident directions.
        normal: surface normals of any length and either orientation.
        mu: n_before / n_after.

    Returns:
        (refracted unit directions, ok) with ok False on total internal reflection (those
        rays keep their direction).
    """
    g, ok = unmark(refraction_gain(d, normal, mu))
    out = tuple(jnp.where(ok, mu * di + g * ni, di) for di, ni in zip(d, normal, strict=True))
    return out, ok


def refract_diffract(d, normal, mu, kick, *, reflects=False):
    """The local grating equation: refraction (or reflection) with a tangential kick.

    The outgoing direction is a + g·normal with a = mu·d + kick, the gain g chosen so that it
    has unit length and lies on the side of the surface that d travels to (transmission) or,
    with ``reflects`` (static), on the side d comes from (reflection: pass mu = 1 and the
    kick divided by the incident index). The two roots of |a + g·normal| = 1 are the
    transmitted and the reflected wave of the same tangential component. Only the part of
    ``kick`` tangent to the surface matters: a normal part is absorbed by g. With kick = 0
    this is ``refract`` (same roots, evaluated without assuming |a| = 1), or ``reflect``.

    Args:
        d: unit incident directions, an (x, y, z) tuple of arrays.
        normal: surface normals of any length and either orientation.
        mu: n_before / n_after (1 when ``reflects``).
        kick: (λ/2π)∇Φ / n_after, an (x, y, z) tuple (dimensionless).
        reflects: take the reflected root (a diffracting mirror).

    Returns:
        (outgoing unit directions, ok) with ok False where no real direction exists (an
        evanescent order, or total internal reflection); those rays keep their direction.
    """
    a = tuple(mu * di + ki for di, ki in zip(d, kick, strict=True))
    nn = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]
    dn = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]
    an = a[0] * normal[0] + a[1] * normal[1] + a[2] * normal[2]
    aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    # |a + g·N|² = 1: nn·g² + 2·an·g + aa − 1 = 0, the root on d's side of the surface.
    disc = an * an - nn * (aa - 1.0)
    ok = (disc >= 0) & (nn > 0)
    above = ok & (disc > 0)  # the root's slope is infinite at disc = 0 (as in refraction_gain)
    root = jnp.where(above, jnp.sqrt(jnp.where(above, disc, 1.0)), 0.0)
    # d′·normal = an + g·nn = ±root: the sign of d·normal (transmitted), or the other one.
    onward = (dn >= 0) if reflects else (dn < 0)
    g = jnp.where(ok, jnp.where(onward, -root, root) - an, 0.0) / jnp.where(ok, nn, 1.0)
    out = tuple(jnp.where(ok, ai + g * ni, di) for ai, ni, di in zip(a, normal, d, strict=True))
    return out, ok


def diffract(surface, d, p, n_before, n_after, wavelength, *, reflects=False):
    """A diffractive surface's ray rule (``Binary2``, ``Grating``): ``refract_diffract``
    with its phase, and the path.

    Args:
        surface: the diffractive surface (any of ``optics.diffractive.DIFFRACTIVE``: a
            surface with ``phase(x, y)`` returning Φ, ∂Φ/∂x, ∂Φ/∂y).
        d: unit directions, an (x, y, z) tuple of arrays.
        p: the points of incidence (local frame, mm), an (x, y, z) tuple.
        n_before, n_after: refractive indices n and n′ (``n_after`` unused when
            ``reflects``: the ray stays in n).
        wavelength: λ in µm (a scalar or one per ray, shaped like the indices).
        reflects: the surface is a mirror (static): the diffracted ray is reflected.

    Returns:
        (new unit directions, ok, added optical path (λ/2π)Φ in mm).
    """
    x, y, z = p
    phi, px, py = surface.phase(x, y)
    scale = wavelength * 1e-3 / (2.0 * jnp.pi)  # µm -> mm, per radian
    n_out = n_before if reflects else n_after
    kick = (scale * px / n_out, scale * py / n_out, jnp.zeros_like(px))
    out, ok = refract_diffract(d, surface_normal(surface, x, y, z), n_before / n_out, kick,
                               reflects=reflects)
    return out, ok, scale * phi


def paraxial_bend(d, x, y, focal_length, n_before, n_after):
    """The ideal thin lens of ``ParaxialSurface``: bend rays on its plane and add their path.

    Slopes u = L/N, v = M/N change by n′u′ = nu − x/f, n′v′ = nv − y/f (the paraxial
    refraction equation with power 1/f, exact for real slopes), and the direction becomes
    (u′, v′, 1)/sqrt(1 + u′² + v′²). The optical path added is that of a perfect lens at
    infinite conjugates, φ = sgn(f)·n′(|P′| − |P′ − Q|) − n·d·Q with P′ = (n f u, n f v, n′ f),
    written without cancellation as (2n·(u, v)·Q − |Q|²/f)/(s0 + s1) − n·d·Q, where
    s0 = sqrt(1 + |n(u, v)/n′|²) and s1 = sqrt(1 + u′² + v′²) (derivation:
    ``jaxlens.optics.paraxial_surface``).

    Args:
        d: unit directions, an (x, y, z) tuple of arrays.
        x, y: points of incidence on the plane (local frame, mm).
        focal_length: f (mm), nonzero.
        n_before, n_after: refractive indices n and n′.

    Returns:
        (new unit directions, ok, added optical path in mm); ok is False where the ray
        does not travel toward +z (its slope is undefined); those rays keep their direction.
    """
    u, ok_u = bounded_div(d[0], d[2])
    v, ok_v = bounded_div(d[1], d[2])
    ok = ok_u & ok_v & (d[2] > 0)
    u2 = (n_before * u - x / focal_length) / n_after
    v2 = (n_before * v - y / focal_length) / n_after
    s1 = jnp.sqrt(1.0 + u2 * u2 + v2 * v2)
    out = tuple(jnp.where(ok, a / s1, di) for a, di in zip((u2, v2, 1.0), d, strict=True))
    m = n_before / n_after
    s0 = jnp.sqrt(1.0 + (m * u) ** 2 + (m * v) ** 2)
    path = (2 * n_before * (u * x + v * y) - (x * x + y * y) / focal_length) / (s0 + s1)
    path = path - n_before * (d[0] * x + d[1] * y)
    return out, ok, jnp.where(ok, path, 0.0)


def reflect(d, normal):
    """The law of reflection, d − 2 (d·n̂) n̂, on (x, y, z) tuples of arrays.

    Args:
        d: unit incident directions.
        normal: surface normals of any length and either orientation.

    Returns:
        The reflected unit directions (unchanged where the normal has zero length).
    """
    nn = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]
    dn = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]
    ok = nn > 0
    g = jnp.where(ok, -2.0 * dn / jnp.where(ok, nn, 1.0), 0.0)
    return tuple(di + g * ni for di, ni in zip(d, normal, strict=True))


def surface_normal(surface: AbstractSurface, x, y, z):
    """A normal (+z at the vertex, not of unit length) at a point on the surface (local frame)."""
    if surface.has_polynomial:
        _, gx, gy, _ = surface.sag_and_grad(x, y)
        return -gx, -gy, jnp.ones_like(gx)
    # Gradient of the implicit conic c(x² + y²) + c(1+k)z² − 2z: no square root needed.
    c = surface.c
    return -c * x, -c * y, 1.0 - c * (1.0 + surface.k) * z


class RayState(eqx.Module):
    """Rays as separate x, y, z component arrays (vectorises better than [N, 3])."""

    p: tuple
    d: tuple
    valid: jax.Array
    opl: jax.Array


def surface_step(surface, z_vertex, st: RayState, n_before, n_after, *, first, refracts,
                 newton_iters, gap=None, reflects=False, obscured=None, apertures=(),
                 wavelength=None, go_back=False):
    """Move rays to one surface (vertex at global ``z_vertex``) and refract them there.

    ``n_before``/``n_after`` are the refractive indices on either side; ``first`` applies the
    object-space rules of surface 1; ``refracts=False`` only intersects (the image surface);
    ``reflects=True`` (static) makes the surface a mirror (``n_after`` is then unused);
    ``obscured=(r_min, r_max)`` (static, mm) blocks the rays that meet it in that annulus;
    ``apertures`` (static, a tuple of ``optics.apertures.Aperture``) clip or block the rays
    that meet it outside or inside each of them.
    Rays that fail keep their last position and direction and become invalid; ``opl`` adds
    n·t for valid rays. ``gap`` is the thickness before this surface: where it is negative
    (or zero, for a dummy surface) the surface may lie behind the ray's start and the ray
    reaches it by going back along its line; it is measured along the direction of travel
    (after an odd number of mirrors the caller passes minus the Zemax thickness).
    ``wavelength`` (µm, shaped like the indices) is needed by a diffractive (``Binary2``,
    ``Grating``) surface only, which adds (λ/2π)Φ to ``opl``; other surfaces ignore it. A
    ``Grating`` may be a mirror (it then reflects the diffracted order); a ``Binary2`` may not.
    ``go_back`` (static, ``Lens.negative_propagation``): wherever the surface lies nowhere
    ahead of the ray, the ray goes back along its line to it, as in Zemax (``intersect``);
    ignored on the first surface.
    """
    if isinstance(surface, DIFFRACTIVE) and (refracts or reflects):  # static, refused early
        kind = type(surface).__name__
        if reflects and not isinstance(surface, Grating):
            raise ValueError(f"surface_step: a {kind} (diffractive) surface cannot be a mirror")
        if wavelength is None:
            raise ValueError(f"surface_step: a {kind} (diffractive) surface needs the "
                             f"wavelength (µm) of the rays")
    o_local = (st.p[0], st.p[1], st.p[2] - z_vertex)
    backward = None
    if gap is not None and not first:
        # A dummy surface (same index on both sides, not a mirror) on the previous vertex
        # plane, e.g. a reference plane at a mirror, may lie behind where the ray starts; a
        # refracting one there would make a lens of negative thickness, and stays refused.
        dummy = jnp.all(n_before == n_after) & (not reflects)  # a scalar, as gap is
        backward = (gap < 0) | ((gap == 0) & dummy)
    t, ok = unmark(intersect(surface, o_local, st.d, newton_iters, first=first,
                             backward=backward, go_back=go_back))
    if not first and not go_back:
        forward = t >= -1e3 * jnp.finfo(t.dtype).eps * (1 + jnp.abs(o_local[2]))
        ok = ok & (forward if backward is None else forward | backward)
    x, y, z = (oi + t * di for oi, di in zip(o_local, st.d, strict=True))
    # A ray exactly on the rim stays in despite rounding.
    rim = surface.semi_diameter**2 * (1 + 64 * jnp.finfo(x.dtype).eps)
    ok = ok & (x * x + y * y <= rim)
    if obscured is not None:  # static: a central (or annular) obscuration
        r2 = x * x + y * y
        ok = ok & ((r2 < obscured[0] ** 2) | (r2 > obscured[1] ** 2))
    ok = passes_all(apertures, x, y, ok)
    d, phase = st.d, None
    if reflects and isinstance(surface, Grating):  # static: a diffracting mirror
        d, bent, phase = diffract(surface, d, (x, y, z), n_before, n_after, wavelength,
                                  reflects=True)
        ok = ok & bent
    elif reflects:
        d = reflect(d, surface_normal(surface, x, y, z))
    elif refracts and isinstance(surface, ParaxialSurface):  # static: the ideal thin lens
        d, bent, phase = paraxial_bend(d, x, y, surface.focal_length, n_before, n_after)
        ok = ok & bent
    elif refracts and isinstance(surface, DIFFRACTIVE):  # static: a diffractive surface
        d, bent, phase = diffract(surface, d, (x, y, z), n_before, n_after, wavelength)
        ok = ok & bent
    elif refracts:
        d, no_tir = refract(d, surface_normal(surface, x, y, z), n_before / n_after)
        ok = ok & no_tir
    valid = st.valid & ok
    keep = lambda new, old: jnp.where(valid, new, old)  # noqa: E731
    p = (keep(x, st.p[0]), keep(y, st.p[1]), keep(z + z_vertex, st.p[2]))
    d = tuple(keep(a, b) for a, b in zip(d, st.d, strict=True))
    path = n_before * t if phase is None else n_before * t + phase
    return RayState(p, d, valid, st.opl + jnp.where(valid, path, 0.0))




def state_from_rays(rays: Rays) -> RayState:
    o, d = rays.origin, rays.direction
    return RayState((o[..., 0], o[..., 1], o[..., 2]), (d[..., 0], d[..., 1], d[..., 2]),
                    rays.valid, rays.opl)


def rays_from_state(st: RayState, wavelength) -> Rays:
    return Rays(jnp.stack(st.p, -1), jnp.stack(st.d, -1), wavelength, st.valid, st.opl)
