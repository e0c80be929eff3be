"""Rewrite an even asphere on the conic closest to it, with the same sag (for export).

An even asphere is a base conic (vertex curvature c, conic constant k) plus polynomial terms,
and one surface has many such forms: changing k changes the conic's sag only from r⁴ on,
which the r⁴ … terms can take up. A design optimised from a sphere can end far from its
base conic (on Table 1's designs the polynomial terms move the surface up to 1 mm from it at
the clear aperture). The sag is the same in every form, but a tracer that starts Newton at
the base conic's root (optiland 0.6.3; jaxlens before its two-start Newton) then starts far
from the surface and, for steep rays near the rim, can stop at a wrong point. The export
therefore writes each asphere on the conic constant that keeps the base conic closest to the
surface over the clear aperture (the area-weighted RMS of their sag difference), with its
polynomial terms refitted; the vertex curvature and the r² term are kept, so the paraxial
data are unchanged. A nearly flat base (c ≈ 0) cannot be helped by k: such a surface keeps
its form.

Conventions: lengths in mm; sag z(r) = c r²/(1 + √(1 − (1 + k) c² r²)) + Σ_j a_j r^(2j)
(``EvenAsphere``, ``coeffs[0]`` the r² term).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import checks
from .lens import Lens
from .surfaces import EvenAsphere, Standard

# Refitted sag may differ from the original by at most this much over the aperture (mm).
SAG_TOLERANCE = 1e-8
# Conic constants tried (the conic must stay defined out to 1.05 × the clear aperture).
CONIC_GRID = np.linspace(-50.0, 50.0, 2001)
# A new form must bring the base conic at least this much closer (relative RMS departure).
MIN_GAIN = 0.1


def _conic_sags(c: float, ks: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``[K, n]`` sags of the base conics (curvature c, conic constants ``ks``) at radii r."""
    r = jnp.asarray(r)

    def one(k):
        return Standard(c=c, k=k).sag(jnp.zeros_like(r), r)[0]

    return np.asarray(jax.vmap(one)(jnp.asarray(ks, r.dtype)), float)


def rebase_conic(surface: EvenAsphere, semi_diameter: float | None = None,
                 *, n: int = 512) -> EvenAsphere:
    """The surface written on the conic constant closest to it over its clear aperture.

    Args:
        surface: an ``EvenAsphere``.
        semi_diameter: clear semi-diameter (mm); default the surface's own.
        n: radial samples of the fit.

    Returns:
        The same surface (sag within ``SAG_TOLERANCE`` over the aperture, same c and r²
        term) with a new k and refitted r⁴ … terms; the surface itself where no conic
        brings the base closer by ``MIN_GAIN`` or the refit misses the tolerance.

    Raises:
        ValueError: for a surface that is not an ``EvenAsphere`` (an ``OddAsphere``'s
            r, r³, … terms have no even-series form).
    """
    if not isinstance(surface, EvenAsphere):
        raise ValueError(f"rebase_conic: only an EvenAsphere can be rebased, got a "
                         f"{type(surface).__name__}")
    # Before: n = 0 or 10**9 and a negative or NaN semi_diameter returned the surface as it
    # was (or tried 10**9 samples), as if it had been checked and kept.
    n = checks.number(n, "n", "rebase_conic", lo=16, hi=checks.MAX_SAMPLES, integer=True,
                      unit="radial samples")
    if semi_diameter is not None:
        semi_diameter = checks.number(semi_diameter, "semi_diameter", "rebase_conic", lo=0,
                                      lo_open=True, unit="mm")
    r_max = float(surface.semi_diameter if semi_diameter is None else semi_diameter)
    a = np.asarray(surface.coeffs, float)
    if not np.isfinite(r_max) or r_max <= 0 or a.shape[0] < 2:
        return surface
    c, k = float(surface.c), float(surface.k)
    u = np.linspace(0.0, 1.0, n)
    r = u * r_max
    z, *_ = surface.sag_and_grad(jnp.zeros(n), jnp.asarray(r))
    z = np.asarray(z, float)
    # Polynomial terms from r⁴ on, in the normalised radius u = r / r_max (conditioning).
    powers = 2 * np.arange(2, a.shape[0] + 1)
    basis = u[:, None] ** powers[None, :]
    target = z - a[0] * r**2

    ok = 1.0 - (1.0 + CONIC_GRID) * c**2 * (1.05 * r_max) ** 2 > 0.0
    candidates = CONIC_GRID[ok]
    bases = _conic_sags(c, np.concatenate([[k], candidates]), r)
    # Area-weighted RMS distance of each base conic from the surface.
    deps = np.sqrt(np.sum(u * (z - bases) ** 2, -1) / np.sum(u))
    now, bases, deps = deps[0], bases[1:], deps[1:]
    best_k, best_coef = k, None
    for i in np.argsort(deps):  # closest conic first; the first whose refit is exact wins
        if deps[i] >= (1.0 - MIN_GAIN) * now:
            break
        rest = target - bases[i]
        coef, *_ = np.linalg.lstsq(basis, rest, rcond=None)
        if np.max(np.abs(basis @ coef - rest)) <= SAG_TOLERANCE:
            best_k, best_coef = float(candidates[i]), coef
            break
    if best_coef is None:
        return surface
    new = np.concatenate([a[:1], best_coef / r_max ** powers])
    return EvenAsphere(c=surface.c, k=jnp.asarray(best_k, surface.c.dtype),
                       coeffs=jnp.asarray(new, surface.coeffs.dtype),
                       semi_diameter=surface.semi_diameter)


def rebase_conics(lens: Lens) -> Lens:
    """Every even asphere of the lens with a finite clear aperture, rebased (module docstring);
    other surfaces (odd aspheres too) are kept as they are."""
    surfaces = tuple(rebase_conic(s) if isinstance(s, EvenAsphere) else s for s in lens.surfaces)
    return eqx.tree_at(lambda x: x.surfaces, lens, surfaces)
