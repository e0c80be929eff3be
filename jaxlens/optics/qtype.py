"""Forbes Q-type aspheres (Zemax ``QED_TYPE``): a conic deformed by Q-bfs or Q-con polynomials.

Conventions:
    Lengths in mm, local frame as in ``jaxlens.optics.surfaces`` (vertex at the origin, +z
    the axis). With r² = x² + y², the normalisation radius ρ_n (mm, > 0), u = r/ρ_n and
    x = u², the sag is a base conic plus a departure:

        z(r) = c r² / (1 + sqrt(1 − (1+k) c² r²)) + δ(r)

        Q-bfs:  δ = x (1 − x) · φ(r) · Σ_{m=0..M} a_m Q_m^bfs(x),
                φ = sqrt((1 − k c² r²) / (1 − (1+k) c² r²))
        Q-con:  δ = x² · Σ_{m=0..M} a_m Q_m^con(x)

    (G. W. Forbes, "Shape specification for axially symmetric optical surfaces", Opt.
    Express 15, 5218 (2007), with its Q_m polynomials). The coefficients a_m are lengths
    (mm); the polynomials are dimensionless. A positive a_m moves the surface toward +z
    where a_m Q_m is positive. Forbes's Q-bfs form has a sphere for base (k = 0, c the
    curvature of the best-fit sphere), where φ = 1/sqrt(1 − c² r²). With a conic base
    (k ≠ 0) the conic enters the base term, and φ is the conic's obliquity
    sqrt(1 + (dz_conic/dr)²), so that the polynomial is (to first order) the departure
    along the conic's normal; φ reduces to Forbes's factor at k = 0. This is how
    OpticStudio's Q-type surface reads a Q-bfs surface with a conic: the Thorlabs ASL5040-UV
    asphere (tests/data/zmx/rayoptics_ASL5040-UV.zmx: c = 0.0576/mm, k = −0.676, six Q-bfs
    terms over ρ_n = 27 mm, 22.86 mm clear radius) focuses a collimated 405 nm beam to an RMS
    spot of 0.10 µm at its file's focus (Airy radius 0.61 λ/NA = 0.38 µm, NA 0.65) with this
    φ, but to 125 µm with 1/sqrt(1 − (1+k) c² r²) and 1.5 mm with 1/sqrt(1 − c² r²), which
    is not even defined beyond r = 1/c = 17.4 mm (tests/test_qtype.py). The sag equals
    optiland 0.6.3's Forbes geometry with a conic (ForbesQNormalSlopeGeometry) to 1e-12.

    Q-bfs (Forbes 2007, sec. 3): orthonormal slopes, ⟨(dS_m/du)(dS_n/du)⟩ = δ_mn with
    S_m = u²(1 − u²) Q_m(u²) and the average ∫_0^1 f(u) (1 − u²)^(−1/2) du / (π/2).
    Q_0 = 1, Q_1 = (13 − 16x)/√19, Q_2 = 2(29 − 4x(25 − 19x))/√190. Q_0 contributes
    2 a_0/ρ_n² to the vertex curvature (``paraxial_curvature``), every Q_m with
    Q_m(0) ≠ 0 likewise: c_par = c + 2 Σ a_m Q_m(0)/ρ_n².

    Q-con (Forbes 2007, sec. 2): Q_m^con(x) = P_m^(0,4)(2x − 1), the Jacobi polynomials,
    orthogonal in ∫_0^1 Q_m Q_n x⁴ dx: Q_0 = 1, Q_1 = −(5 − 6x), Q_2 = 15 − 14x(3 − 2x).
    The departure starts at r⁴, so the vertex curvature is c.

    The sums are evaluated with the recurrences of Forbes, "Robust, efficient computational
    methods for axially symmetric optical aspheres", Opt. Express 18, 19700 (2010): Q-bfs
    through P_0 = 2, P_1 = 6 − 8x, P_m = (2 − 4x) P_(m−1) − P_(m−2) and
    Q_m = (P_m − g_(m−1) Q_(m−1) − h_(m−2) Q_(m−2))/f_m (f_0 = 2, g_0 = −1/2,
    f_1 = √19/2, h_(m−2) = −m(m−1)/(2 f_(m−2)), g_(m−1) = −(1 + g_(m−2) h_(m−2))/f_(m−1),
    f_m = sqrt(m(m+1) + 3 − g_(m−1)² − h_(m−2)²)): the sum Σ a_m Q_m is rewritten as
    Σ b_m P_m (back substitution) and summed with Clenshaw's algorithm, value and x
    derivative; Q-con through the Jacobi three-term recurrence, summed the same way. No
    monomial expansion is formed, so high orders keep their accuracy.

    The surface is defined where the base conic is (1 − (1+k) c² r² > 0). The
    polynomials are evaluated beyond u = 1 as they are, with no clipping (ρ_n is meant to
    be at or beyond the clear aperture).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from . import checks
from .reciprocal import NORMALISING, reciprocal_length
from .surfaces import AbstractSurface, number_field

QTYPES = ("bfs", "con")
"""The kinds of ``QTypeAsphere``: Forbes's Q-bfs and Q-con polynomials."""


def bfs_constants(n: int) -> tuple[list[float], list[float], list[float]]:
    """Forbes 2010's f_m (m < n), g_m and h_m for the Q-bfs recurrence, as floats."""
    f, g, h = [2.0], [-0.5], []
    if n > 1:
        f.append(math.sqrt(19.0) / 2.0)
    for m in range(2, n):
        h.append(-m * (m - 1) / (2.0 * f[m - 2]))
        g.append(-(1.0 + g[m - 2] * h[m - 2]) / f[m - 1])
        f.append(math.sqrt(m * (m + 1) + 3.0 - g[m - 1] ** 2 - h[m - 2] ** 2))
    return f, g, h


def qbfs_sum(a, x):
    """Σ_m a_m Q_m^bfs(x) and its derivative in x (Forbes 2010: P basis and Clenshaw)."""
    n = a.shape[0]
    zero = jnp.zeros_like(x * a[0]) if n else jnp.zeros_like(x)
    if not n:
        return zero, zero
    f, g, h = bfs_constants(n)
    # Σ a_m Q_m = Σ b_m P_m with f_m b_m + g_m b_(m+1) + h_m b_(m+2) = a_m.
    b = [None] * n
    for m in range(n - 1, -1, -1):
        v = a[m]
        if m + 1 < n:
            v = v - g[m] * b[m + 1]
        if m + 2 < n:
            v = v - h[m] * b[m + 2]
        b[m] = v / f[m]
    # Clenshaw on P_m = A P_(m−1) − P_(m−2), A = 2 − 4x: Σ b_m P_m = 2 (α_0 + α_1).
    A = 2.0 - 4.0 * x
    al1 = al2 = zero  # α_(m+1), α_(m+2)
    d1 = d2 = zero  # their x derivatives
    for m in range(n - 1, -1, -1):
        al, d = b[m] + A * al1 - al2, A * d1 - 4.0 * al1 - d2
        al1, al2, d1, d2 = al, al1, d, d1
    # After the loop al1 = α_0, al2 = α_1.
    return 2.0 * (al1 + al2), 2.0 * (d1 + d2)


def _con_recurrence(m: int) -> tuple[float, float, float]:
    """(p, q, s) with Q_m^con = (p + q x) Q_(m−1) − s Q_(m−2): the Jacobi P^(0,4) recurrence
    in t = 2x − 1, m(m+1)(m+4) P_m = (2m+3)((m+1)(m+2) t − 4) P_(m−1)
    − (m−1)(m+2)(m+3) P_(m−2)."""
    den = m * (m + 1) * (m + 4)
    p = -(2 * m + 3) * ((m + 1) * (m + 2) + 4) / den
    q = 2 * (2 * m + 3) * (m + 1) * (m + 2) / den
    s = (m - 1) * (m + 2) * (m + 3) / den
    return p, q, s


def qcon_sum(a, x):
    """Σ_m a_m Q_m^con(x) and its derivative in x (Jacobi recurrence, Clenshaw)."""
    n = a.shape[0]
    zero = jnp.zeros_like(x * a[0]) if n else jnp.zeros_like(x)
    if not n:
        return zero, zero
    # β_m = a_m + A_(m+1) β_(m+1) − s_(m+2) β_(m+2); the sum is β_0 (Q_0 = 1).
    be1 = be2 = zero
    d1 = d2 = zero
    for m in range(n - 1, -1, -1):
        be, d = a[m] + zero, zero
        if m + 1 < n:
            p, q, _ = _con_recurrence(m + 1)
            be = be + (p + q * x) * be1
            d = d + (p + q * x) * d1 + q * be1
        if m + 2 < n:
            s = _con_recurrence(m + 2)[2]
            be, d = be - s * be2, d - s * d2
        be1, be2, d1, d2 = be, be1, d, d1
    return be1, d1


def qbfs_polynomials(n: int, x):
    """Q_0^bfs … Q_(n−1)^bfs at x (the recurrence itself; for tests and plots)."""
    f, g, h = bfs_constants(n)
    P = [2.0 + 0.0 * x, 6.0 - 8.0 * x]
    for m in range(2, n):
        P.append((2.0 - 4.0 * x) * P[m - 1] - P[m - 2])
    Q = []
    for m in range(n):
        v = P[m]
        if m >= 1:
            v = v - g[m - 1] * Q[m - 1]
        if m >= 2:
            v = v - h[m - 2] * Q[m - 2]
        Q.append(v / f[m])
    return jnp.stack(Q)


def qcon_polynomials(n: int, x):
    """Q_0^con … Q_(n−1)^con at x (the recurrence itself; for tests and plots)."""
    Q = [1.0 + 0.0 * x]
    for m in range(1, n):
        p, q, s = _con_recurrence(m)
        Q.append((p + q * x) * Q[m - 1] - (s * Q[m - 2] if m >= 2 else 0.0))
    return jnp.stack(Q[:n])


class QTypeAsphere(AbstractSurface):
    """A Forbes Q-type asphere: conic plus Q-bfs or Q-con polynomials (Zemax ``QED_TYPE``;
    the formulas, units and signs are in the module docstring).

    Args:
        c: vertex curvature of the base conic (1/mm); for Q-bfs, the best-fit sphere's.
        k: conic constant of the base (Zemax CONI); for Q-bfs it also sets φ.
        coeffs: a_0 … a_M (mm), Zemax XDAT 4 … XDAT M+4.
        norm_radius: the normalisation radius ρ_n (mm, > 0), Zemax XDAT 3.
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.
        qtype: ``"bfs"`` (Zemax XDAT 1 = 0) or ``"con"`` (XDAT 1 = 1). Static.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=())
    norm_radius: Float[Array, ""] = number_field("norm_radius", default=1.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))
    qtype: str = eqx.field(static=True, default="bfs")

    def __check_init__(self):
        if not isinstance(self.qtype, str) or self.qtype not in QTYPES:
            raise ValueError(f"QTypeAsphere: qtype must be 'bfs' (Q-bfs polynomials) or 'con' "
                             f"(Q-con polynomials), got {self.qtype!r}")
        if not checks.is_traced(self.norm_radius):
            checks.values(self.norm_radius, "norm_radius", "QTypeAsphere", lo=0, lo_open=True,
                          unit="mm")
            reciprocal_length(self.norm_radius, "norm_radius", "QTypeAsphere", why=NORMALISING)
        if not checks.is_traced(self.coeffs):
            checks.values(self.coeffs, "coeffs", "QTypeAsphere", unit="mm")
        self._check_numbers()

    @property
    def has_polynomial(self) -> bool:
        return True  # the departure needs the Newton intersection

    @property
    def paraxial_curvature(self) -> Array:
        """c + 2 Σ a_m Q_m^bfs(0)/ρ_n² for Q-bfs (its departure has an r² part); c for Q-con."""
        if self.qtype == "con" or not self.coeffs.shape[0]:
            return self.c
        s0, _ = qbfs_sum(self.coeffs, jnp.zeros_like(self.norm_radius))
        return self.c + 2.0 * s0 / (self.norm_radius * self.norm_radius)

    def departure_factor(self, r2):
        """(φ, (dφ/dr)/r) of the Q-bfs departure's factor
        φ = sqrt((1 − k c² r²)/(1 − (1+k) c² r²)) (1/sqrt(1 − c² r²) for k = 0), finite
        where the base conic is defined (1 for r² outside it)."""
        q = self.c**2 * r2
        den = 1.0 - (1.0 + self.k) * q
        ok = den > 0
        den = jnp.where(ok, den, 1.0)
        phi = jnp.sqrt(jnp.where(ok, (1.0 - self.k * q) / den, 1.0))
        # dφ/dq = 1/(2 φ den²), dq/dr = 2 c² r.
        return phi, self.c**2 / (phi * den * den)

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        z, _, _, inside = self.sag_and_grad(x, y)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and (dz/dx, dz/dy), finite at r = 0 (zero gradient outside the domain)."""
        r2 = x * x + y * y
        z, dr_over_r, inside = self.conic_sag_and_slope(r2)
        inv_n2 = 1.0 / (self.norm_radius * self.norm_radius)
        u2 = r2 * inv_n2
        a = self.coeffs
        if a.shape[0] and self.qtype == "bfs":
            s, ds = qbfs_sum(a, u2)
            phi, dphi = self.departure_factor(r2)
            poly = u2 * (1.0 - u2) * s
            dpoly = (1.0 - 2.0 * u2) * s + u2 * (1.0 - u2) * ds  # d(poly)/d(u²)
            z = z + poly * phi
            # d/dr = 2 r/ρ_n² d/d(u²).
            dr_over_r = dr_over_r + 2.0 * inv_n2 * dpoly * phi + poly * dphi
        elif a.shape[0]:
            s, ds = qcon_sum(a, u2)
            z = z + u2 * u2 * s
            dr_over_r = dr_over_r + 2.0 * inv_n2 * (2.0 * u2 * s + u2 * u2 * ds)
        gx = jnp.where(inside, x * dr_over_r, 0.0)
        gy = jnp.where(inside, y * dr_over_r, 0.0)
        return z, gx, gy, inside
