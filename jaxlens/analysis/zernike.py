"""Zernike polynomials over the unit disc and least-squares fits of a wavefront to them.

Conventions:
    Points are Cartesian (x, y) in the unit disc (for a wavefront: the normalised
    entrance-pupil coordinates (Px, Py)); ρ² = x² + y², θ = atan2(y, x) measured from +x
    toward +y. The term of radial order n and signed azimuthal order m is

        Z_n^m(ρ, θ) = N_n^m · R_n^|m|(ρ) · (cos mθ for m ≥ 0, sin |m|θ for m < 0),
        R_n^|m|(ρ) = Σ_{k=0}^{(n−|m|)/2} (−1)^k (n−k)! / (k! ((n+|m|)/2−k)! ((n−|m|)/2−k)!)
                     · ρ^(n−2k),

    evaluated as polynomials in x and y (ρ^|m| cos mθ = Re (x + iy)^|m|), so they are smooth
    at the centre. Three orderings (``indexing``):

    - ``"noll"`` (Zemax "Zernike Standard Coefficients"; Noll 1976): j = 1, 2, …; within an
      order n, j rises with |m|, even j carry cos mθ and odd j sin |m|θ. Normalised,
      N = sqrt(2(n+1)/(1+δ_m0)), so that the mean of Z_j² over the disc is 1 and a
      wavefront's RMS over the disc (piston removed) is sqrt(Σ_{j≥2} c_j²). This is the
      table an OpticStudio listing prints (Z2 = 4^½ ρ cos A, Z3 = 4^½ ρ sin A, Z5 = 6^½ ρ²
      sin 2A, Z6 = 6^½ ρ² cos 2A, …, A measured from +x toward +y: a field along +y gives
      the sin A terms), and optiland's ``"noll"``.
    - ``"ansi"`` (OSA/ANSI Z80.28): j = (n(n+2) + m)/2 = 0, 1, …, the same normalisation
      as Noll; the coefficients are returned in j order starting at j = 0. optiland calls
      this set ``"standard"``: it is not Zemax's Standard set (that is ``"noll"``).
    - ``"fringe"`` (University of Arizona, Zemax "Zernike Fringe Coefficients"): j = 1 … 37,
      j = (1 + (n+|m|)/2)² − 2|m| + (1 if m < 0), except Z37 = R_12^0 (Zemax's Z37, 924ρ¹²
      − … + 1); not normalised (N = 1, every term peaks at 1 on the edge), so Z4 = 2ρ² − 1
      and Z9 = 6ρ⁴ − 6ρ² + 1. optiland 0.6.3 continues the formula to its Z37 = ρ⁶ cos 6θ
      instead, so 37-term Fringe fits differ from optiland's; 36-term fits agree.

    Fits of the same OPD samples agree with optiland 0.6.3's ``ZernikeFit`` to 1e-9 wave in
    all three sets (``tests/test_conventions_vs_optiland.py``).

    ``zernike_fit`` fits by least squares over the given points (each point weighs the same;
    points off the mask, and NaN values, weigh nothing); on a dense uniform grid this is
    the fit over the disc's area. Coefficients carry the unit of the values (waves for
    ``jaxlens.analysis.wavefront_error``).
"""

from __future__ import annotations

import math
from functools import cache, partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from ..optics import checks

__all__ = ["INDEXINGS", "ZernikeFit", "zernike_nm", "zernike_terms", "zernike_fit"]

INDEXINGS = ("noll", "fringe", "ansi")
FRINGE_TERMS = 37
"""The Fringe set has 37 terms (Z37 = R_12^0, out of the formula's sequence)."""


def _noll_j(n: int, m: int) -> int:
    c = 0 if (m > 0 and n % 4 <= 1) or (m < 0 and n % 4 >= 2) else 1
    return n * (n + 1) // 2 + abs(m) + c


def _fringe_j(n: int, m: int) -> int:
    if (n, m) == (12, 0):
        return 37
    return (1 + (n + abs(m)) // 2) ** 2 - 2 * abs(m) + (1 if m < 0 else 0)


@cache
def _table(indexing: str, terms: int) -> tuple[tuple[int, int], ...]:
    """(n, m) of the first ``terms`` terms in ``indexing`` order."""
    number = {"noll": _noll_j, "fringe": _fringe_j,
              "ansi": lambda n, m: (n * (n + 2) + m) // 2 + 1}[indexing]
    found: dict[int, tuple[int, int]] = {}
    n = 0
    while not all(j in found for j in range(1, terms + 1)):
        for m in range(-n, n + 1, 2):
            j = number(n, m)
            # Fringe stops at 36 by its formula; Z37 is R_12^0 (set apart in _fringe_j).
            if indexing != "fringe" or j < FRINGE_TERMS or (n, m) == (12, 0):
                found[j] = (n, m)
        n += 1
    return tuple(found[j] for j in range(1, terms + 1))


def _check(indexing, terms, where: str) -> int:
    if indexing not in INDEXINGS:
        raise ValueError(f"{where}: indexing must be one of {INDEXINGS} ('noll' is Zemax's "
                         f"Standard), got {indexing!r}")
    hi = FRINGE_TERMS if indexing == "fringe" else 231
    return checks.number(terms, "terms", where, lo=1, hi=hi, integer=True,
                         unit=f"Zernike terms ({indexing})")


def zernike_nm(j: int, *, indexing: str = "noll") -> tuple[int, int]:
    """(n, m) of term ``j`` (1-based for Noll and Fringe, 0-based for ANSI); m < 0 is the
    sin |m|θ term.

    Example:
        >>> zernike_nm(4), zernike_nm(9, indexing="fringe"), zernike_nm(4, indexing="ansi")
        ((2, 0), (4, 0), (2, 0))
    """
    first = 0 if indexing == "ansi" else 1
    _check(indexing, 1, "zernike_nm")
    # Bounded (before: j = 10**30 built a table of that many terms, for ever): term 65536 is
    # of radial order about 360, beyond any wavefront fit.
    j = checks.number(j, "j", "zernike_nm", lo=first,
                      hi=FRINGE_TERMS if indexing == "fringe" else checks.MAX_SAMPLES,
                      integer=True, unit=f"term number ({indexing})")
    return _table(indexing, j - first + 1)[-1]


def _radial_coefficients(n: int, m: int) -> list[tuple[float, int]]:
    """R_n^|m| as (coefficient, power of ρ²) pairs, divided by ρ^|m|."""
    a = abs(m)
    out = []
    for k in range((n - a) // 2 + 1):
        c = (-1) ** k * math.factorial(n - k) / (
            math.factorial(k) * math.factorial((n + a) // 2 - k)
            * math.factorial((n - a) // 2 - k))
        out.append((c, (n - a) // 2 - k))
    return out


def _norm(n: int, m: int, indexing: str) -> float:
    if indexing == "fringe":
        return 1.0
    return math.sqrt(2.0 * (n + 1) / (2.0 if m == 0 else 1.0))


def zernike_terms(x: Float[ArrayLike, "*p"], y: Float[ArrayLike, "*p"], *, terms: int = 37,
                  indexing: str = "noll") -> Float[Array, "*p J"]:
    """The first ``terms`` Zernike polynomials at the points (x, y) (see the module notes).

    Points outside the unit disc are evaluated as the polynomials continue there, up to
    ``MAX_RADIUS`` (2; beyond it the coordinates are not normalised, e.g. in mm: refused).

    Example:
        >>> import jax.numpy as jnp
        >>> z = zernike_terms(jnp.array(0.0), jnp.array(1.0), terms=4)
        >>> [round(float(v), 6) for v in z]   # piston, x tilt, y tilt, defocus at (0, 1)
        [1.0, 0.0, 2.0, 1.732051]
    """
    terms = _check(indexing, terms, "zernike_terms")
    for arg, v in (("x", x), ("y", y)):
        checks.real_values(v, arg, "zernike_terms", "normalised pupil coordinate")
    if jnp.shape(x) != jnp.shape(y):
        try:
            jnp.broadcast_shapes(jnp.shape(x), jnp.shape(y))
        except ValueError:
            raise ValueError(f"zernike_terms: x and y must have the same (or broadcastable) "
                             f"shapes, got {jnp.shape(x)} and {jnp.shape(y)}") from None
    x, y = jnp.broadcast_arrays(jnp.asarray(x), jnp.asarray(y))
    if not checks.is_traced((x, y)):
        _check_radius(x, y, "zernike_terms")
    if not jnp.issubdtype(x.dtype, jnp.floating):
        x, y = x.astype(float), y.astype(float)
    r2 = x * x + y * y
    table = _table(indexing, terms)
    top = max(abs(m) for _, m in table)
    # (x + iy)^a as real and imaginary parts, a = 0 … top.
    re, im = [jnp.ones_like(x)], [jnp.zeros_like(x)]
    for _ in range(top):
        re, im = re + [re[-1] * x - im[-1] * y], im + [re[-1] * y + im[-1] * x]
    out = []
    for n, m in table:
        radial = jnp.zeros_like(x)
        for c, _ in _radial_coefficients(n, m):  # Horner in ρ², highest power first
            radial = radial * r2 + c
        ang = re[abs(m)] if m >= 0 else im[abs(m)]
        out.append(_norm(n, m, indexing) * radial * ang)
    return jnp.stack(out, -1)


MAX_RADIUS = 2.0
"""Largest ρ that ``zernike_terms`` evaluates. The polynomials continue beyond the unit
disc (a square grid over it reaches ρ = √2, and a Zernike sag may hold a little past its
normalisation radius), but at twice that radius a term of order n is ~2ⁿ times its edge
value (4096 for Z37): points so far out are coordinates in mm or pixels, not normalised."""


def _check_radius(x, y, where: str) -> None:
    with np.errstate(invalid="ignore"):
        r2 = np.asarray(x, float) ** 2 + np.asarray(y, float) ** 2
    if r2.size and np.nanmax(r2, initial=0.0) > MAX_RADIUS**2:
        i = int(np.nanargmax(r2))
        raise ValueError(
            f"{where}: points must be normalised to the unit disc (divide by the pupil or "
            f"normalisation radius, e.g. in mm); got radius {float(np.sqrt(r2.flat[i])):.6g} "
            f"at ({float(np.asarray(x).flat[i]):g}, {float(np.asarray(y).flat[i]):g}), "
            f"beyond the {MAX_RADIUS:g} where the polynomials are evaluated")


class ZernikeFit(eqx.Module):
    """Zernike coefficients of a least-squares fit (see the module notes).

    Attributes:
        coefficients: ``[J]`` in the unit of the fitted values (waves for a wavefront),
            in ``indexing`` order: ``coefficients[0]`` is Z1 (Noll, Fringe) or Z0 (ANSI).
        residual_rms: RMS of the values minus the fit over the fitted points.
        indexing: "noll", "fringe" or "ansi" (static).
    """

    coefficients: Float[Array, " J"]
    residual_rms: Float[Array, ""]
    indexing: str = eqx.field(static=True, default="noll")

    @property
    def nm(self) -> tuple[tuple[int, int], ...]:
        """(n, m) of each coefficient."""
        return _table(self.indexing, self.coefficients.shape[-1])

    def __call__(self, x: Float[ArrayLike, "*p"], y: Float[ArrayLike, "*p"]
                 ) -> Float[Array, "*p"]:
        """The fitted surface at the points (x, y)."""
        z = zernike_terms(x, y, terms=self.coefficients.shape[-1], indexing=self.indexing)
        return z @ self.coefficients


def zernike_fit(x: Float[ArrayLike, "*p"], y: Float[ArrayLike, "*p"],
                values: Float[ArrayLike, "*p"], *, terms: int = 37, indexing: str = "noll",
                mask: Bool[ArrayLike, "*p"] | None = None) -> ZernikeFit:
    """Least-squares Zernike coefficients of ``values`` at the points (x, y) of the unit disc.

    Args:
        x, y: point coordinates (any matching shapes; flattened), inside the unit disc.
        values: the values there (NaN where there is none: such points weigh nothing).
        terms: number of terms (Fringe: at most 37).
        indexing: "noll" (Zemax Standard), "fringe" or "ansi".
        mask: points to fit (default: every point with a finite value).

    Returns:
        A :class:`ZernikeFit`. Jittable; differentiable in ``values``.

    Example:
        >>> import jax.numpy as jnp
        >>> g = jnp.linspace(-1, 1, 41)
        >>> x, y = jnp.meshgrid(g, g)
        >>> keep = x**2 + y**2 <= 1
        >>> w = jnp.where(keep, 0.25 * (2 * (x**2 + y**2) - 1), jnp.nan)
        >>> fit = zernike_fit(x, y, w, terms=9, indexing="fringe")
        >>> round(float(fit.coefficients[3]), 5)
        0.25
    """
    where = "zernike_fit"
    terms = _check(indexing, terms, where)
    for arg, v in (("x", x), ("y", y), ("values", values)):
        checks.real_values(v, arg, where, "")
    shapes = [jnp.shape(a) for a in (x, y, values)]
    x, y, v = (jnp.ravel(jnp.asarray(a)) for a in (x, y, values))
    if not (shapes[0] == shapes[1] == shapes[2]):  # a [25] x, a [5, 5] y: paired by ravel
        raise ValueError(f"{where}: x, y and values must have the same shape (one value per "
                         f"point), got shapes {shapes[0]}, {shapes[1]} and {shapes[2]}")
    if not jnp.issubdtype(v.dtype, jnp.floating):
        v = v.astype(float)
    ok = jnp.isfinite(v)
    if mask is not None:
        # A 0/1 (or any numeric) mask means nonzero = fit; ``ok & 2`` was bitwise (0).
        if jnp.shape(mask) != shapes[2]:
            raise ValueError(f"{where}: mask must have the points' shape {shapes[2]} (one entry "
                             f"per point), got shape {jnp.shape(mask)}")
        mask = jnp.ravel(jnp.asarray(mask)).astype(bool)
        ok = ok & mask
    if not checks.is_traced((x, y)):
        r2 = np.asarray(x, float) ** 2 + np.asarray(y, float) ** 2
        sel = np.asarray(ok) if not checks.is_traced(ok) else np.ones(r2.shape, bool)
        if not np.all(np.isfinite(r2[sel])):  # NaN > 1 is False: the fit came out NaN
            i = int(np.flatnonzero(sel & ~np.isfinite(r2))[0])
            raise ValueError(f"{where}: x and y must be finite at every fitted point (a "
                             f"finite value, in the mask), got ({float(np.asarray(x)[i]):g}, "
                             f"{float(np.asarray(y)[i]):g}) at point {i}")
        if np.any(r2[sel] > 1.0 + 1e-9):
            raise ValueError(f"{where}: points must lie in the unit disc (x² + y² <= 1), got "
                             f"radius {float(np.sqrt(np.max(r2[sel]))):.6g}")
        if not checks.is_traced(ok) and int(np.sum(sel)) < terms:
            raise ValueError(f"{where}: {int(np.sum(sel))} valid points cannot determine "
                             f"{terms} terms; give more points or fewer terms")
        if not checks.is_traced(ok):
            _check_rank(x, y, jnp.asarray(sel), terms, indexing, where)
    return _fit(x, y, v, ok, terms=terms, indexing=indexing)


MIN_CONDITION = 1e-14
"""Smallest accepted ratio of the least and greatest eigenvalues of a fit's normal matrix
AᵀA (the square of the design matrix's condition): below it the points cannot tell the terms
apart (all at one spot, on a line or a ring) and the solve gave NaN or noise."""


def _check_rank(x, y, sel, terms, indexing, where) -> None:
    """Refuse points (those where ``sel``) that cannot determine ``terms`` terms."""
    e = np.linalg.eigvalsh(np.asarray(_normal_matrix(x, y, sel, terms=terms,
                                                     indexing=indexing), float))
    if not e[-1] > 0 or e[0] < MIN_CONDITION * e[-1]:
        count = int(np.sum(np.asarray(sel)))
        raise ValueError(
            f"{where}: the {count} fitted points cannot determine {terms} terms (eigenvalue "
            f"ratio {max(e[0], 0.0) / e[-1] if e[-1] > 0 else 0.0:.3g} of the normal matrix, "
            f"below {MIN_CONDITION:g}): points at one spot, on a line or a ring, or a patch "
            f"too small for the order; spread them over the unit disc or fit fewer terms")


@partial(jax.jit, static_argnames=("terms", "indexing"))
def _normal_matrix(x, y, sel, *, terms, indexing):
    """AᵀA of the design matrix over the points where ``sel`` (the others weigh nothing), one
    compiled program for every call with as many points (not one per count of valid ones)."""
    x, y = jnp.where(sel, x, 0.0), jnp.where(sel, y, 0.0)
    a = zernike_terms(x, y, terms=terms, indexing=indexing)
    return (a * sel[:, None].astype(a.dtype)).T @ a


@partial(jax.jit, static_argnames=("terms", "indexing"))
def _fit(x, y, v, ok, *, terms, indexing) -> ZernikeFit:
    # Compiled: eager op-by-op dispatch of the ~37 terms' polynomials took ~0.1 s a fit.
    # A point that weighs nothing is read at the centre: its NaN coordinates (a wavefront
    # grid's outside points) made a NaN row, and NaN·0 made every coefficient NaN.
    x, y = jnp.where(ok, x, 0.0), jnp.where(ok, y, 0.0)
    a = zernike_terms(x, y, terms=terms, indexing=indexing)  # [p, J]
    w = ok.astype(a.dtype)
    vz = jnp.where(ok, v, 0.0)
    aw = a * w[:, None]
    coef = jnp.linalg.solve(aw.T @ a, aw.T @ vz)
    res = jnp.where(ok, vz - a @ coef, 0.0)
    cnt = jnp.maximum(jnp.sum(w), 1.0)
    ms = jnp.sum(res * res) / cnt
    safe = jnp.where(ms > 0, ms, 1.0)
    return ZernikeFit(coef, jnp.where(ms > 0, jnp.sqrt(safe), 0.0), indexing)
