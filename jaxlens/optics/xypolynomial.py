"""Zemax's extended polynomial surface (``TYPE XPOLYNOM``): a conic plus an XY polynomial.

Conventions:
    Lengths in mm, local frame as in ``jaxlens.optics.surfaces`` (vertex at the origin, +z
    the axis, x and y the surface's own axes). The sag is

        z(x, y) = c r² / (1 + sqrt(1 − (1+k) c² r²)) + Σ_{i=1..N} A_i E_i(x/R, y/R),

    r² = x² + y², with c the base curvature (1/mm, Zemax CURV), k the conic constant (CONI),
    R the normalisation radius (mm, > 0, Zemax XDAT 2), N the number of terms (XDAT 1) and
    A_i the coefficients (mm of sag on dimensionless coordinates, XDAT 2+i). E_i are the
    monomials u^m v^n (u = x/R, v = y/R) ordered by total degree d = m + n and, within a
    degree, by falling power of x, as in OpticStudio's manual:

        E_1 = u, E_2 = v, E_3 = u², E_4 = uv, E_5 = v², E_6 = u³, E_7 = u²v, E_8 = uv², …

    so term (m, n) is number i = d(d+1)/2 + n (``xy_term_index``) and degree d holds d + 1
    terms. There is no constant term. Degree 20 (230 terms) is Zemax's limit and jaxlens's.
    In unnormalised form the coefficient of x^m y^n is A_i / R^(m+n) (mm^(1−m−n)); that is
    what optiland's ``PolynomialGeometry`` takes.

    Linear terms (E_1, E_2) tilt the surface: its vertex is still at the origin, but its slope
    there is (A_1, A_2)/R. There is no constant term, so z(0, 0) = 0 always.

    Paraxial optics works in the y–z and x–z sections, as for ``ZernikeSag``:
    ``paraxial_curvature`` is the vertex curvature d²z/dy² = c + 2 A_5/R² (the y² term) and
    ``paraxial_curvature_x`` is d²z/dx² = c + 2 A_3/R² (the x² term; used by
    ``paraxial.x_section``). The xy term A_4 (d²z/dx dy = A_4/R² at the vertex) turns the
    principal directions of the vertex astigmatism away from x and y; the sections' paraxial
    trace does not see it, and neither does it see the vertex slope of the linear terms
    (A_1, A_2): both are seen by real rays only, as ZernikeSag's tilt (Z2, Z3) and oblique
    astigmatism terms are. ``vertex_hessian`` gives the whole second-order part.

    The sag is defined where the base conic is (1 − (1+k) c² r² > 0); the tracer's Newton
    iteration (``has_polynomial``) intersects it, started from the base conic and the vertex
    plane. With no terms (N = 0) the surface is traced by the closed-form conic, exactly as
    a ``Standard`` surface.

The polynomial is evaluated by Horner's rule in u for each power of v and in v over those
(``xy_polynomial_sum``), with its partial derivatives, using elementwise operations only.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .reciprocal import NORMALISING, reciprocal_length
from .surfaces import AbstractSurface, number_field

MAX_XY_DEGREE = 20
"""The highest total degree of an extended polynomial (Zemax's limit)."""

MAX_XY_TERMS = (MAX_XY_DEGREE + 1) * (MAX_XY_DEGREE + 2) // 2 - 1
"""The most terms of an extended polynomial: 230, all monomials of degree 1 … 20."""


def xy_term_index(m: int, n: int) -> int:
    """The 1-based number i of the monomial x^m y^n (m + n >= 1) in Zemax's order."""
    for v, name in ((m, "m"), (n, "n")):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
            raise ValueError(f"xy_term_index: {name} must be a whole number >= 0, got {v!r}")
    d = m + n
    if d < 1:
        raise ValueError("xy_term_index: the extended polynomial has no constant term (m + n "
                         "must be >= 1)")
    return d * (d + 1) // 2 + int(n)


def xy_term_powers(i: int) -> tuple[int, int]:
    """(m, n), the powers of x and y of term i >= 1 in Zemax's order (``xy_term_index``'s
    inverse): (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), …"""
    if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or i < 1:
        raise ValueError(f"xy_term_powers: i must be a whole number >= 1, got {i!r}")
    d = (math.isqrt(8 * int(i) + 1) - 1) // 2  # the largest d with d(d+1)/2 <= i
    n = int(i) - d * (d + 1) // 2
    return d - n, n


def xy_term_count(degree: int) -> int:
    """The number of terms up to total degree ``degree``: (d + 1)(d + 2)/2 − 1."""
    # -1 gave -1 terms, 2.5 gave 6.0 and 25 gave 350 (beyond the 230 a surface holds).
    degree = checks.number(degree, "degree", "xy_term_count", lo=0, hi=MAX_XY_DEGREE,
                           integer=True, unit="(total degree)")
    return (degree + 1) * (degree + 2) // 2 - 1


def xy_polynomial_sum(a, u, v):
    """Σ_i a_i u^m v^n over the first ``a.shape[0]`` monomials (Zemax's order), and its
    partial derivatives in u and v. ``a``: the coefficients, 1-D; ``u``, ``v``: the
    normalised coordinates (any shape, broadcast together).

    P = Σ_n v^n Q_n(u) is summed by Horner's rule in v, each Q_n(u) = Σ_m a_(m,n) u^m by
    Horner's rule in u, each with its derivative."""
    count = a.shape[0]
    zero = jnp.zeros_like(u * v * (a[0] if count else 1.0))
    if not count:
        return zero, zero, zero
    cols: dict[int, dict[int, int]] = {}  # power of v -> {power of u: index into a}
    for i in range(count):
        m, n = xy_term_powers(i + 1)
        cols.setdefault(n, {})[m] = i
    p = dp_u = dp_v = zero
    for n in range(max(cols), -1, -1):
        q = dq = zero  # Q_n(u) and Q_n'(u)
        col = cols.get(n, {})
        for m in range(max(col, default=-1), -1, -1):
            dq = dq * u + q
            q = q * u + a[col[m]] if m in col else q * u
        dp_v = dp_v * v + p
        p = p * v + q
        dp_u = dp_u * v + dq
    return p, dp_u, dp_v


class XYPolynomial(AbstractSurface):
    """Zemax's extended polynomial: a conic plus Σ A_i E_i(x/R, y/R) (the formula, the term
    order, units and the paraxial conventions are in the module docstring).

    Args:
        c: vertex curvature of the base conic (1/mm), Zemax CURV.
        k: conic constant of the base (Zemax CONI).
        coeffs: A_1 … A_N (mm), the coefficients of the monomials E_1 … E_N (x, y, x², xy,
            y², x³, …) of the normalised coordinates, Zemax XDAT 3 … N+2; N <= 230.
        norm_radius: the normalisation radius R (mm, > 0), Zemax XDAT 2.
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.

    Example:
        >>> import jax.numpy as jnp
        >>> s = XYPolynomial(c=0.0, coeffs=jnp.array([0.0, 0.0, 0.5, 0.0, 0.0]),
        ...                  norm_radius=2.0)   # 0.5 (x/2)²: a cylinder along y
        >>> float(s.sag(jnp.asarray(1.0), jnp.asarray(3.0))[0])
        0.125
        >>> float(s.paraxial_curvature_x), float(s.paraxial_curvature)
        (0.25, 0.0)
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " n"] = number_field("coeffs", default=())
    norm_radius: Float[Array, ""] = number_field("norm_radius", default=1.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        where = "XYPolynomial"
        if self.coeffs.ndim != 1:
            raise ValueError(f"{where}: coeffs must be a 1-D array of the coefficients A_1, "
                             f"A_2, … (mm) of x, y, x², xy, y², …, got shape "
                             f"{self.coeffs.shape}")
        if self.coeffs.shape[0] > MAX_XY_TERMS:
            raise ValueError(f"{where}: {self.coeffs.shape[0]} coefficients given; the "
                             f"extended polynomial holds at most {MAX_XY_TERMS} (degree "
                             f"{MAX_XY_DEGREE})")
        if not checks.is_traced(self.norm_radius):
            checks.values(self.norm_radius, "norm_radius", where, lo=0, lo_open=True,
                          unit="mm")
            reciprocal_length(self.norm_radius, "norm_radius", where, why=NORMALISING)
        if not checks.is_traced(self.coeffs):
            checks.values(self.coeffs, "coeffs", where, unit="mm")
        self._check_numbers()

    @property
    def has_polynomial(self) -> bool:
        """True when it has terms (the Newton intersection); without, the closed-form conic."""
        return bool(self.coeffs.shape[0])

    def _coefficient(self, m: int, n: int):
        """A_i of x^m y^n (0 when the surface has fewer terms)."""
        i = xy_term_index(m, n)
        return self.coeffs[i - 1] if self.coeffs.shape[0] >= i else jnp.zeros_like(self.c)

    def vertex_hessian(self) -> tuple[Array, Array, Array]:
        """(d²z/dx², d²z/dx dy, d²z/dy²) at the vertex (1/mm): (c + 2A_3/R², A_4/R²,
        c + 2A_5/R²)."""
        inv2 = 1.0 / (self.norm_radius * self.norm_radius)
        return (self.c + 2.0 * self._coefficient(2, 0) * inv2,
                self._coefficient(1, 1) * inv2,
                self.c + 2.0 * self._coefficient(0, 2) * inv2)

    @property
    def paraxial_curvature(self) -> Array:
        """d²z/dy² at the vertex (1/mm): c + 2A_5/R², the y–z section's (paraxial) one."""
        return self.vertex_hessian()[2]

    @property
    def paraxial_curvature_x(self) -> Array:
        """d²z/dx² at the vertex (1/mm): c + 2A_3/R², the x–z section's."""
        return self.vertex_hessian()[0]

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        z, _, _, inside = self.sag_and_grad(x, y)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and (dz/dx, dz/dy), finite everywhere (zero gradient outside the domain)."""
        r2 = x * x + y * y
        z, dr_over_r, inside = self.conic_sag_and_slope(r2)
        gx, gy = x * dr_over_r, y * dr_over_r
        if self.coeffs.shape[0]:
            inv = 1.0 / self.norm_radius
            p, pu, pv = xy_polynomial_sum(self.coeffs, x * inv, y * inv)
            z, gx, gy = z + p, gx + pu * inv, gy + pv * inv
        gx = jnp.where(inside, gx, 0.0)
        gy = jnp.where(inside, gy, 0.0)
        return z, gx, gy, inside
