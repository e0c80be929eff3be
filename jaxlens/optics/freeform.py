"""Freeform surfaces of Zemax files: the biconic (``BICONICX``) and the Zernike sag surfaces
(``SZERNSAG``, ``FZERNSAG``).

Conventions:
    Lengths in mm, local frame as in ``jaxlens.optics.surfaces`` (vertex at the origin, +z the
    axis, x and y the surface's own axes).

    ``Biconic`` (Zemax "Biconic"): a conic in x and a conic in y under one square root,

        z = (cx x² + cy y²) / (1 + sqrt(1 − (1+kx) cx² x² − (1+ky) cy² y²)).

    ``c``, ``k`` are the y–z section's curvature and conic (Zemax CURV, CONI), ``cx``, ``kx``
    the x–z section's (PARM 1 = the x radius 1/cx, 0 meaning flat in x; PARM 2 = kx). With
    cx = cy and kx = ky it is the rotationally symmetric conic of ``Standard``. It is not the
    sum of the two section conics except where one of them is a parabola (k = −1) or flat
    (optiland 0.6.3's ``BiconicGeometry`` takes that sum). It is defined where the square
    root's argument is positive.

    ``ZernikeSag`` (Zemax "Zernike Standard Sag" and "Zernike Fringe Sag"): an even asphere
    plus Zernike polynomials on a disc of radius R (the normalisation radius) centred at
    (dx, dy),

        z = c r² / (1 + sqrt(1 − (1+k) c² r²)) + Σ_i a_i r^{2i} + Σ_j A_j Z_j(ρ, φ),

    r² = x² + y², ρ = sqrt((x − dx)² + (y − dy)²)/R and φ the angle of (x − dx, y − dy)
    measured from +x toward +y (so Z_j ∝ cos φ are even in y − dy). ``coeffs`` a_1 … (a_1 on
    r², Zemax PARM 1…8), ``zernike`` A_1 … A_N (mm, Zemax XDAT 3…), ``norm_radius`` R (mm,
    XDAT 2), ``decenter_x``/``decenter_y`` dx, dy (mm, PARM 9, 10). ``ordering`` chooses the
    polynomials:

    * ``"standard"`` (Zemax Standard): Noll's order and normalisation, Z_j = N R_n^|m|(ρ) ×
      (cos mφ for even j, sin mφ for odd j; 1 for m = 0), N = sqrt(2(n+1)) (m ≠ 0) or
      sqrt(n+1) (m = 0): Z1 = 1, Z2 = 2ρ cos φ, Z3 = 2ρ sin φ, Z4 = √3(2ρ² − 1),
      Z5 = √6 ρ² sin 2φ, Z6 = √6 ρ² cos 2φ, … up to 231 terms (radial order 20).
    * ``"fringe"`` (Zemax Fringe, University of Arizona order): unnormalised, Z1 = 1,
      Z2 = ρ cos φ, Z3 = ρ sin φ, Z4 = 2ρ² − 1, Z5 = ρ² cos 2φ, Z6 = ρ² sin 2φ, …, the
      term (n, m) at j = (1 + (n+|m|)/2)² − 2|m| (+1 for sin |m|φ) up to Z36 = R_10^0, and
      Z37 = R_12^0 (the 12th-order spherical term, as in Zemax), 37 terms at most.

    The decenter's sign: the terms are evaluated at (x − dx, y − dy), so the Zernike pattern
    (only it, not the base asphere) moves to (dx, dy); a defocus term's vertex lies at
    (dx, dy) (tests/test_conventions_signs.py). OpticStudio's help defines the decenter as
    that "of the Zernike terms relative to the base asphere", with ρ and φ the decentered
    coordinates (its Zernike Surface object, parameters 5–6; the sequential Zernike sag
    page was not at hand); a decenter moves what it decenters toward +dx, as a surface
    decenter does. Checked against optiland 0.6.3 (its Zernike sum shifted by hand, and a
    flat-base surface moved by its own surface decenter; tests/test_zernike_decenter.py), not
    against a sag OpticStudio computed for a decentered surface (none at hand).

    With ``extrapolate=False`` (Zemax PARM 0 = 0) the Zernike part is zero where ρ > 1, as
    in Zemax (a step in the surface at ρ = 1); ``True`` (PARM 0 = 1) evaluates it everywhere.
    Piston (Z1) and the constant parts of the m = 0 terms move the surface off the vertex
    plane (z(0, 0) ≠ 0), as in Zemax.

    The polynomials are evaluated in Cartesian form: ρ^m cos mφ and ρ^m sin mφ are the real
    and imaginary parts of (u + iv)^m (u, v the normalised decentered coordinates) and
    R_n^m(ρ)/ρ^m is a polynomial in ρ², so the sag and its gradient are polynomials, finite
    with finite derivatives everywhere (no atan2, no division by ρ). Terms of the same m and
    kind are summed as one polynomial in ρ² (Horner), whose coefficients are a fixed linear
    map of the A_j (``zernike_basis``).

    Both surfaces are intersected by the tracer's Newton iteration (``has_polynomial``),
    started from the base conic (c, k) and the vertex plane.

    Paraxial optics works in the y–z section, as Zemax does: ``paraxial_curvature`` is the
    vertex curvature d²z/dy² at x = y = 0 (a biconic's c; for ``ZernikeSag`` c + 2a_1 plus
    the Zernike terms' y curvature there, e.g. 4√3 A4/R² from Standard Z4), and
    ``paraxial_curvature_x`` the x–z one (``paraxial.x_section``). Vertex slopes (the tilt
    terms Z2, Z3) and the vertex offset are seen by real rays only.
"""

from __future__ import annotations

import functools
import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .reciprocal import MIN_LENGTH_MM, NORMALISING, reciprocal_length
from .surfaces import MAX_CURVATURE, AbstractSurface, guarded_sqrt, number_field

ZERNIKE_ORDERINGS = ("standard", "fringe")
"""The ``ZernikeSag`` orderings: Zemax Standard (Noll, normalised) and Fringe (unnormalised)."""

MAX_ZERNIKE_TERMS = {"standard": 231, "fringe": 37}
"""The most Zernike terms of each ordering (Standard: radial orders 0…20; Fringe: Zemax's 37)."""


# ------------------------------------------------------------------------------ biconic


class Biconic(AbstractSurface):
    """Zemax's biconic: independent curvatures and conics in x and y (see the module docstring).

    Args:
        c: curvature of the y–z section (1/mm), Zemax CURV.
        k: conic constant of the y–z section, Zemax CONI.
        cx: curvature of the x–z section (1/mm), 1/(Zemax PARM 1); 0 is flat in x.
        kx: conic constant of the x–z section, Zemax PARM 2.
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    cx: Float[Array, ""] = number_field("cx", default=0.0)
    kx: Float[Array, ""] = number_field("kx", default=0.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        for name, bound, unit in (("cx", MAX_CURVATURE, f"1/mm (|R| >= {MIN_LENGTH_MM:g} mm)"),
                                  ("kx", None, "")):
            v = getattr(self, name)
            if not checks.is_traced(v):
                checks.values(v, name, "Biconic", unit=unit, hi=bound,
                              lo=None if bound is None else -bound)
        self._check_numbers()

    def _check_domain(self, where: str):
        """Both sections must exist out to the semi-diameter: on the circle r = sd the root's
        argument is smallest on an axis, so (1+k)c² sd² <= 1 and (1+kx)cx² sd² <= 1."""
        super()._check_domain(where)
        if checks.is_traced((self.cx, self.kx)):
            return
        sd = np.asarray(self.semi_diameter, float)
        q = (1.0 + np.asarray(self.kx, float)) * np.asarray(self.cx, float) ** 2
        with np.errstate(invalid="ignore", over="ignore"):
            bad = np.isfinite(sd) & (q > 0) & (q * sd * sd > 1.0 + 1e-6)
        if np.any(bad):
            r_max = float(np.min(1.0 / np.sqrt(np.where(bad, q, np.inf))))
            raise ValueError(
                f"{where}: the x–z section (cx = {float(np.max(self.cx)):g} 1/mm, kx = "
                f"{float(np.max(self.kx)):g}) is defined only out to r = 1/(|cx|·sqrt(1 + kx))"
                f" = {r_max:g} mm, but the semi_diameter is {float(np.max(sd)):g} mm; use a "
                f"semi_diameter <= {r_max:g} mm (or a flatter surface)")

    @property
    def has_polynomial(self) -> bool:
        return True  # not a conic about the axis: the Newton intersection

    @property
    def paraxial_curvature(self) -> Array:
        """c: the vertex curvature of the y–z section (the paraxial one)."""
        return self.c

    @property
    def paraxial_curvature_x(self) -> Array:
        """cx: the vertex curvature of the x–z section."""
        return self.cx

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        z, _, _, inside = self.sag_and_grad(x, y)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and (dz/dx, dz/dy), finite everywhere (zero gradient outside the domain)."""
        px = (1.0 + self.kx) * self.cx**2
        py = (1.0 + self.k) * self.c**2
        root, inside = guarded_sqrt(1.0 - px * x * x - py * y * y)
        den = 1.0 + root
        z = (self.cx * x * x + self.c * y * y) / den
        # z·den = B, d(root) = −(dA)/(2 root): dz/dx = (2 cx x + z px x/root)/den.
        over = jnp.where(inside, z / jnp.where(inside, root, 1.0), 0.0)
        gx = jnp.where(inside, (2.0 * self.cx + over * px) * x / den, 0.0)
        gy = jnp.where(inside, (2.0 * self.c + over * py) * y / den, 0.0)
        return z, gx, gy, inside


# ----------------------------------------------------------------------------- Zernikes


def noll_to_nm(j: int) -> tuple[int, int]:
    """(n, m) of Noll's (Zemax Standard) term j >= 1; m > 0 is cos mφ, m < 0 sin |m|φ."""
    if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or j < 1:
        raise ValueError(f"noll_to_nm: j must be a whole number >= 1, got {j!r}")
    n = 0
    while (n + 1) * (n + 2) // 2 < j:
        n += 1
    first = n * (n + 1) // 2 + 1  # Noll's first index of order n
    ms = [abs_m for abs_m in range(n % 2, n + 1, 2) for _ in range(1 if abs_m == 0 else 2)]
    abs_m = ms[j - first]
    if abs_m == 0:
        return n, 0
    return n, abs_m if j % 2 == 0 else -abs_m


def fringe_to_nm(j: int) -> tuple[int, int]:
    """(n, m) of the Fringe (Zemax Fringe, University of Arizona) term j in 1…37; m > 0 is
    cos mφ, m < 0 sin |m|φ. Term 37 is R_12^0, as in Zemax."""
    if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or not 1 <= j <= 37:
        raise ValueError(f"fringe_to_nm: j must be a whole number in [1, 37], got {j!r}")
    if j == 37:
        return 12, 0
    q = math.isqrt(j - 1)  # j in q² + 1 … (q+1)², q = (n + |m|)/2
    d = (q + 1) ** 2 - j  # 2|m| (cos) or 2|m| − 1 (sin)
    abs_m = (d + 1) // 2
    n = 2 * q - abs_m
    return n, abs_m if d % 2 == 0 else -abs_m


def _radial_over_rho_m(n: int, m: int) -> np.ndarray:
    """Ascending coefficients in s = ρ² of R_n^m(ρ)/ρ^m (m >= 0)."""
    p = (n - m) // 2
    out = np.zeros(p + 1)
    for k in range(p + 1):
        out[p - k] = (-1) ** k * math.factorial(n - k) / (
            math.factorial(k) * math.factorial((n + m) // 2 - k) * math.factorial(p - k))
    return out


@functools.lru_cache(maxsize=64)
def zernike_basis(n_terms: int, ordering: str) -> np.ndarray:
    """W [P+1, 2M+2, n_terms]: Σ_j A_j Z_j = Σ_(p,t) (W A)_(p,t) ρ^(2p) T_t, with
    T = (Re (u + iv)^0, …, Re (u + iv)^M, Im (u + iv)^0, …, Im (u + iv)^M) and M the largest
    |m| of the first ``n_terms`` terms (R_n^m(ρ)/ρ^m is a polynomial in ρ²)."""
    if ordering not in ZERNIKE_ORDERINGS:
        raise ValueError(f"zernike_basis: ordering must be one of {ZERNIKE_ORDERINGS}, got "
                         f"{ordering!r}")
    # 0 gave "max() arg is an empty sequence", 2.5 a TypeError from range.
    n_terms = checks.number(n_terms, "n_terms", "zernike_basis", lo=1,
                            hi=MAX_ZERNIKE_TERMS[ordering], integer=True, unit="terms")
    to_nm = noll_to_nm if ordering == "standard" else fringe_to_nm
    nms = [to_nm(j) for j in range(1, n_terms + 1)]
    top = max(abs(m) for _, m in nms)
    w = np.zeros((max(n - abs(m) for n, m in nms) // 2 + 1, 2 * top + 2, n_terms))
    for j, (n, m) in enumerate(nms):
        am = abs(m)
        norm = 1.0
        if ordering == "standard":
            norm = math.sqrt(n + 1) if m == 0 else math.sqrt(2 * (n + 1))
        radial = norm * _radial_over_rho_m(n, am)
        w[: len(radial), am + (top + 1 if m < 0 else 0), j] = radial
    return w


def zernike_sum(a, u, v, ordering: str):
    """Σ_j a_j Z_j at normalised coordinates (u, v) (ρ² = u² + v², φ from +u toward +v), and
    its partial derivatives in u and v. ``a``: the coefficients, 1-D; ``ordering``:
    ``"standard"`` or ``"fringe"`` (see the module docstring).

    Each azimuthal function T_t (Re or Im of (u + iv)^m) is multiplied by its polynomial in
    s = ρ², summed by Horner's rule with its s derivative. Elementwise operations only:
    measured on XLA:CPU, the gradient of 45 terms compiles in 0.36 s this way, 1.1 s with the
    T_t stacked on an axis and 1.2 s as matrix products (231 terms: 2.8, 5.1 s)."""
    n = a.shape[0]
    zero = jnp.zeros_like(u * v * (a[0] if n else 1.0))
    if not n:
        return zero, zero, zero
    w = zernike_basis(n, ordering)
    coef = jnp.asarray(w, a.dtype) @ a  # [P+1, 2M+2]
    used = np.any(w != 0, axis=-1)  # which (p, t) occur
    top = w.shape[1] // 2 - 1
    s = u * u + v * v
    cm, sm = [1.0 + zero], [zero]  # Re, Im of (u + iv)^m, m = 0 … M
    for _ in range(top):
        cm.append(u * cm[-1] - v * sm[-1])
        sm.append(u * sm[-1] + v * cm[-2])
    # d/du (u + iv)^m = m (u + iv)^(m−1), d/dv = i m (u + iv)^(m−1)
    cu = [zero] + [k * cm[k - 1] for k in range(1, top + 1)]
    su = [zero] + [k * sm[k - 1] for k in range(1, top + 1)]
    t_val, t_u, t_v = cm + sm, cu + su, [-x for x in su] + cu
    z = du = dv = zero
    for t in range(w.shape[1]):
        ps = np.flatnonzero(used[:, t])
        if not ps.size:
            continue
        poly = dpoly = zero  # Horner: the polynomial in s and its s derivative
        for p in range(int(ps[-1]), -1, -1):
            dpoly = dpoly * s + poly
            poly = poly * s + coef[p, t]
        z = z + poly * t_val[t]
        du = du + 2.0 * u * dpoly * t_val[t] + poly * t_u[t]
        dv = dv + 2.0 * v * dpoly * t_val[t] + poly * t_v[t]
    return z, du, dv


def zernike_curvatures(a, u, v, ordering: str, xp=jnp):
    """(∂²/∂u², ∂²/∂v²) of Σ_j a_j Z_j at one point (u, v), exactly (the vertex curvature of a
    ``ZernikeSag``); ``xp`` is ``numpy`` for concrete values (fast outside ``jit``) or
    ``jax.numpy`` (differentiable)."""
    n = a.shape[0]
    if not n:
        return 0.0 * u, 0.0 * u
    w = zernike_basis(n, ordering)
    coef = xp.asarray(w) @ a
    used = np.any(w != 0, axis=-1)
    top = w.shape[1] // 2 - 1
    s = u * u + v * v
    cm, sm = [1.0 + 0.0 * u], [0.0 * u]
    for _ in range(top):
        cm.append(u * cm[-1] - v * sm[-1])
        sm.append(u * sm[-1] + v * cm[-2])
    zero = 0.0 * u
    cu = [zero] + [k * cm[k - 1] for k in range(1, top + 1)]
    su = [zero] + [k * sm[k - 1] for k in range(1, top + 1)]
    cuu = [zero, zero] + [k * (k - 1) * cm[k - 2] for k in range(2, top + 1)]
    suu = [zero, zero] + [k * (k - 1) * sm[k - 2] for k in range(2, top + 1)]
    t_val, t_u, t_v = cm + sm, cu + su, [-x for x in su] + cu
    t_uu = cuu + suu  # T_vv = −T_uu (harmonic)
    huu = hvv = zero
    for t in range(w.shape[1]):
        ps = np.flatnonzero(used[:, t])
        if not ps.size:
            continue
        p0 = p1 = p2 = zero  # the polynomial in s and its first two s derivatives
        for p in range(int(ps[-1]), -1, -1):
            p2 = p2 * s + 2.0 * p1
            p1 = p1 * s + p0
            p0 = p0 * s + coef[p, t]
        base = 2.0 * p1 * t_val[t]
        huu = huu + 4.0 * u * u * p2 * t_val[t] + base + 4.0 * u * p1 * t_u[t] + p0 * t_uu[t]
        hvv = hvv + 4.0 * v * v * p2 * t_val[t] + base + 4.0 * v * p1 * t_v[t] - p0 * t_uu[t]
    return huu, hvv


class ZernikeSag(AbstractSurface):
    """An even asphere plus Zernike polynomials (Zemax SZERNSAG, FZERNSAG; the formulas, units
    and conventions are in the module docstring).

    Args:
        c: vertex curvature of the base conic (1/mm), Zemax CURV.
        k: conic constant of the base (Zemax CONI).
        coeffs: a_1 … a_m on r², r⁴, … (mm^(1−2i)), Zemax PARM 1…8.
        zernike: A_1 … A_N (mm), the coefficients of Z_1 … Z_N, Zemax XDAT 3…N+2.
        norm_radius: the normalisation radius R (mm, > 0), Zemax XDAT 2.
        decenter_x, decenter_y: the centre (dx, dy) of the Zernike disc (mm), Zemax PARM 9, 10.
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.
        ordering: ``"standard"`` (SZERNSAG, Noll) or ``"fringe"`` (FZERNSAG). Static.
        extrapolate: whether the Zernike terms apply beyond ρ = 1 (Zemax PARM 0). Static.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=())
    zernike: Float[Array, " n"] = number_field("zernike", default=())
    norm_radius: Float[Array, ""] = number_field("norm_radius", default=1.0)
    decenter_x: Float[Array, ""] = number_field("decenter_x", default=0.0)
    decenter_y: Float[Array, ""] = number_field("decenter_y", default=0.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))
    ordering: str = eqx.field(static=True, default="standard")
    extrapolate: bool = eqx.field(static=True, default=True)

    def __check_init__(self):
        where = "ZernikeSag"
        if not isinstance(self.ordering, str) or self.ordering not in ZERNIKE_ORDERINGS:
            raise ValueError(f"{where}: ordering must be 'standard' (Zemax Zernike Standard "
                             f"Sag, Noll) or 'fringe' (Zernike Fringe Sag), got "
                             f"{self.ordering!r}")
        checks.switch(self.extrapolate, "extrapolate", where)
        if self.zernike.ndim != 1:
            raise ValueError(f"{where}: zernike must be a 1-D array of the coefficients of "
                             f"Z_1, Z_2, … (mm), got shape {self.zernike.shape}")
        most = MAX_ZERNIKE_TERMS[self.ordering]
        if self.zernike.shape[0] > most:
            raise ValueError(f"{where}: {self.zernike.shape[0]} Zernike terms given; the "
                             f"{self.ordering} ordering holds at most {most}")
        for name, lo in (("norm_radius", 0), ("decenter_x", None), ("decenter_y", None),
                         ("zernike", None)):
            v = getattr(self, name)
            if not checks.is_traced(v):
                checks.values(v, name, where, lo=lo, lo_open=lo is not None, unit="mm")
        if not checks.is_traced(self.norm_radius):
            reciprocal_length(self.norm_radius, "norm_radius", where, why=NORMALISING)
        self._check_numbers()

    @property
    def has_polynomial(self) -> bool:
        return True  # the Zernike terms need the Newton intersection

    def _vertex_curvature(self, axis: int) -> Array:
        """d²z/dx² (axis 0) or d²z/dy² (axis 1) at x = y = 0: c + 2a_1 + the Zernike part's;
        in numpy for concrete values (an eager JAX evaluation of many terms is slow)."""
        traced = checks.is_traced(self)
        xp = jnp if traced else np
        get = (lambda v: v) if traced else (lambda v: np.asarray(v, np.float64))
        c, a, z = get(self.c), get(self.coeffs), get(self.zernike)
        out = c + 2.0 * a[0] if a.shape[0] else c
        if z.shape[0]:
            inv = 1.0 / get(self.norm_radius)
            u, v = -get(self.decenter_x) * inv, -get(self.decenter_y) * inv
            h = zernike_curvatures(z, u, v, self.ordering, xp)[axis] * inv * inv
            if not self.extrapolate:
                h = xp.where(u * u + v * v <= 1.0, h, 0.0)
            out = out + h
        return out if traced else jnp.asarray(out, jnp.result_type(self.c))

    @property
    def paraxial_curvature(self) -> Array:
        """d²z/dy² at the vertex (1/mm): c + 2a_1 plus the Zernike terms' y curvature there."""
        return self._vertex_curvature(1)

    @property
    def paraxial_curvature_x(self) -> Array:
        """d²z/dx² at the vertex (1/mm): the x–z section's vertex curvature."""
        return self._vertex_curvature(0)

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        z, _, _, inside = self.sag_and_grad(x, y)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and (dz/dx, dz/dy), finite everywhere (zero gradient outside the domain)."""
        r2 = x * x + y * y
        z, dr_over_r, inside = self.conic_sag_and_slope(r2)
        a = self.coeffs
        if a.shape[0]:
            z = z + r2 * jnp.polyval(a[::-1], r2)
            i = jnp.arange(1, a.shape[0] + 1, dtype=a.dtype)
            dr_over_r = dr_over_r + jnp.polyval((2 * i * a)[::-1], r2)
        gx, gy = x * dr_over_r, y * dr_over_r
        if self.zernike.shape[0]:
            inv = 1.0 / self.norm_radius
            u, v = (x - self.decenter_x) * inv, (y - self.decenter_y) * inv
            zz, zu, zv = zernike_sum(self.zernike, u, v, self.ordering)
            if not self.extrapolate:
                disc = u * u + v * v <= 1.0
                zz, zu, zv = (jnp.where(disc, t, 0.0) for t in (zz, zu, zv))
            z, gx, gy = z + zz, gx + zu * inv, gy + zv * inv
        gx = jnp.where(inside, gx, 0.0)
        gy = jnp.where(inside, gy, 0.0)
        return z, gx, gy, inside
