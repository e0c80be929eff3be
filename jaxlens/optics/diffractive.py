"""Diffractive surfaces: ``Binary2`` (Zemax ``BINARY_2``), an even asphere carrying a radial
phase, and ``Grating`` (Zemax ``DGRATING``), a conic carrying straight, equally spaced lines.

Conventions:
    Lengths in mm, phase in radians, wavelengths in µm (as everywhere in the API). Each
    diffractive surface has a sag (its base surface) and a phase Φ(x, y), a function of the
    x, y of the point where the ray meets the surface (local frame); ``phase(x, y)`` returns
    Φ, ∂Φ/∂x and ∂Φ/∂y. Both kinds share one ray rule, ``jaxlens.tracing.step.diffract``:

    A ray meets the surface with unit direction d in index n and leaves with unit direction d′
    in index n′ by the local grating equation: the component of n′d′ tangent to the surface
    equals that of n·d + (λ/2π)∇Φ, with λ the wavelength in mm and ∇Φ = (∂Φ/∂x, ∂Φ/∂y, 0)
    (whose tangential part is the surface gradient of Φ, as Φ depends on x and y only); the
    normal part of d′ follows from |d′| = 1: on the side the ray was going (transmission) or,
    at a mirror, on the side it came from (reflection, n′ = n). Where no real d′ exists (the
    diffracted wave is evanescent, or totally reflected) the ray is lost, as at total
    internal reflection. The optical path gains (λ/2π)Φ, so the optical path stays an eikonal
    (∇S = n·d on both sides). With order M = 0 the surface is its plain base surface (a
    mirror at a mirror).

    Signs: a positive ∂Φ/∂x (∂Φ/∂y) pushes the ray toward +x (+y), in transmission and in
    reflection alike (the tangential components of n·d gain (λ/2π)∇Φ).

Binary2:
    The sag is the even asphere's (``jaxlens.optics.surfaces``): the base conic of curvature c
    and conic constant k plus Σ a_i r^{2i} (Zemax PARM 1…8). The phase is

        Φ(x, y) = M Σ_{i=1..N} A_i ρ^{2i},        ρ = r / R,   r² = x² + y²,

    with M the diffraction order (Zemax PARM 0), R the normalisation radius (mm, XDAT 2) and
    A_i the phase coefficients (radians, dimensionless; XDAT 3…).

    A phase A_1 < 0 (with M = 1) converges a beam: its paraxial power is

        P = −M λ A_1 / (π R²)            (1/mm, λ in mm)

    added to the base surface's c_par (n′ − n), whatever the media; it scales with the
    wavelength (a diffractive lens has an Abbe number of λ_d/(λ_F − λ_C) ≈ −3.45). The ideal
    focusing phase of a lens of focal length f at λ is −(2π/λ)(sqrt(r² + f²) − f), so
    A_1 = −π R²/(λ f) to leading order.

    A Binary2 cannot be a mirror (refused when traced), and is refused by tolerancing, the
    design parameterisation and ``rebase_conic``.

Grating:
    The sag is the base conic's (curvature c, conic constant k, as ``Standard``). The lines
    are parallel to the local x axis and equally spaced in y, the spacing measured in the
    projection on the local x–y plane (on a curved surface the lines are the surface's cuts
    by the planes y = j/T, so their spacing along the surface grows where the surface is
    steep in y): T lines per µm, diffraction order M. The phase is linear in y,

        Φ(x, y) = 2π M T y          (T in lines/µm, y in µm: 2π·M·(1000 T)·y with y in mm),

    zero on the local x axis (y = 0). On a flat grating between media n and n′, a ray whose
    direction has components (L, M_d, N) leaves with n′M_d′ = n·M_d + M λ T (λ in µm) and
    n′L′ = n·L: in the y–z plane, n′ sin θ′ = n sin θ + M λ/Λ with Λ = 1/T the line
    spacing (µm) and θ, θ′ measured from +z toward +y. A positive order therefore bends
    rays toward +y; this is the sign Zemax OpticStudio uses for its DGRATING surface (PARM 1
    = T, PARM 2 = M). Evidence (tests/test_grating.py): the direction cosines that optiland's
    tests quote to 10 decimals for a skew ray through its flat and curved transmission
    gratings are reproduced to 1e-10, which the projected spacing does and optiland 0.6.3's
    own kernel (local spacing Λ/|f_xy|) does not (3.5e-7 off on the curved one); optiland's
    intercepts with the order's sign flipped are millimetres away. At a mirror the same
    holds with n′ = n and the normal component reversed (the reflected order obeys
    n sin θ′ = n sin θ + M λ/Λ with θ′ measured from the reflected axis −z toward +y: its
    tangential component gains M λ T/n). A grating
    has no paraxial power of its own (its power is the base conic's, c(n′ − n), or −2nc as
    a mirror); it deflects the chief ray by M λ T, which the y–nu trace cannot hold, so
    paraxial data (EFL, BFL, …) are those of the lens with the grating's lines removed (its
    order-0 system), see ``jaxlens.optics.paraxial``. Its order must be a whole number and
    its line density ≥ 0 (0: no lines).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .reciprocal import NORMALISING, reciprocal_length
from .surfaces import AbstractSurface, number_field

_UM_TO_MM = 1e-3

MAX_LINES_PER_UM = 20.0
"""Most lines per µm of a ``Grating``: at 20 lines/µm (a 50 nm period) every order but 0
is evanescent for wavelengths above 0.1 µm (|M|·λ·T > 2); ruled and holographic gratings
have at most about 6 lines/µm. A density in lines per mm (600) was taken as 600 lines/µm."""


class Binary2(AbstractSurface):
    """An even asphere with a rotationally symmetric diffractive phase (Zemax BINARY_2).

    Args:
        c: vertex curvature (1/mm).
        k: conic constant.
        coeffs: a_1, a_2, … on r², r⁴, … (mm^(1−2i)), as ``EvenAsphere`` (Zemax PARM 1…8).
        order: the diffraction order M (Zemax PARM 0); 0 turns the phase off.
        norm_radius: the normalisation radius R (mm, > 0; Zemax XDAT 2).
        phase_coeffs: A_1 … A_N (radians) on ρ², ρ⁴, …, ρ^{2N} (Zemax XDAT 3…).
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.

    See the module docstring for the phase, the ray rule and the signs.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=())
    order: Float[Array, ""] = number_field("order", default=1.0)
    norm_radius: Float[Array, ""] = number_field("norm_radius", default=1.0)
    phase_coeffs: Float[Array, " n"] = number_field("phase_coeffs", default=())
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        a = self.phase_coeffs
        if not 1 <= a.ndim <= jnp.ndim(self.c) + 1:
            raise ValueError(f"Binary2: phase_coeffs must be a 1-D array of coefficients (one "
                             f"per term), got shape {a.shape}")
        for name, lo, unit in (("phase_coeffs", None, "radians"), ("order", None, ""),
                               ("norm_radius", 0, "mm")):
            v = getattr(self, name)
            if not checks.is_traced(v):
                checks.values(v, name, "Binary2", lo=lo, lo_open=lo is not None, unit=unit)
        if not checks.is_traced(self.norm_radius):
            reciprocal_length(self.norm_radius, "norm_radius", "Binary2", why=NORMALISING)
        self._check_numbers()

    def even_coeffs(self):
        return self.coeffs

    def phase(self, x, y):
        """Φ(x, y) (radians) and its partial derivatives ∂Φ/∂x, ∂Φ/∂y (rad/mm)."""
        a = self.phase_coeffs
        if not a.shape[0]:
            zero = jnp.zeros_like(x * y * self.order)
            return zero, zero, zero
        inv_r2 = 1.0 / (self.norm_radius * self.norm_radius)
        u = (x * x + y * y) * inv_r2  # ρ²
        i = jnp.arange(1, a.shape[0] + 1, dtype=a.dtype)
        phi = self.order * u * jnp.polyval(a[::-1], u)
        # dΦ/dx = M (2x/R²) Σ i A_i ρ^{2(i−1)}: finite on the axis.
        slope = 2.0 * self.order * inv_r2 * jnp.polyval((i * a)[::-1], u)
        return phi, x * slope, y * slope

    def paraxial_power(self, wavelength) -> Array:
        """The phase's paraxial power −M λ A_1/(π R²) (1/mm) at ``wavelength`` (µm)."""
        a = self.phase_coeffs
        if not a.shape[0]:
            return jnp.zeros_like(self.order)
        lam = jnp.asarray(wavelength) * _UM_TO_MM
        return -self.order * lam * a[0] / (jnp.pi * self.norm_radius * self.norm_radius)


class Grating(AbstractSurface):
    """A conic carrying a ruled diffraction grating (Zemax DGRATING); transmissive, or
    reflective as a mirror.

    Args:
        c: vertex curvature (1/mm).
        k: conic constant.
        lines_per_um: line density T (lines per µm, >= 0; Zemax PARM 1), measured in the
            projection on the local x–y plane; the lines are parallel to the local x axis.
        order: the diffraction order M (a whole number; Zemax PARM 2); 0 turns the grating
            off. A positive order bends rays toward +y.
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.

    The phase is Φ = 2π M T y (y in µm), zero on the local x axis; see the module docstring
    for the ray rule, the signs and the paraxial data.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    lines_per_um: Float[Array, ""] = number_field("lines_per_um", default=0.0)
    order: Float[Array, ""] = number_field("order", default=1.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        if not checks.is_traced(self.lines_per_um):
            checks.values(self.lines_per_um, "lines_per_um", "Grating", lo=0,
                          unit="lines per µm")
            t = np.asarray(self.lines_per_um, float)
            if np.any(t > MAX_LINES_PER_UM):
                big = float(t[t > MAX_LINES_PER_UM].reshape(-1)[0])
                raise ValueError(
                    f"Grating: lines_per_um must be at most {MAX_LINES_PER_UM:g} lines per µm "
                    f"(a {1000 / MAX_LINES_PER_UM:g} nm period: beyond it every order but 0 is "
                    f"evanescent), got {big:g} (was it given in lines per mm? {big:g} lines/mm "
                    f"is {big / 1000:g} lines/µm)")
        if not checks.is_traced(self.order):
            checks.values(self.order, "order", "Grating", unit="a whole number")
            o = np.asarray(self.order, float)
            if np.any(o != np.round(o)):
                raise ValueError(f"Grating: order must be a whole number (the diffraction "
                                 f"order), got {checks.fmt(o[o != np.round(o)][:1])}")
        self._check_numbers()

    def phase(self, x, y):
        """Φ(x, y) = 2π M T y (radians, y in mm converted to µm) and ∂Φ/∂x, ∂Φ/∂y (rad/mm)."""
        slope = (2.0 * jnp.pi / _UM_TO_MM) * self.order * self.lines_per_um  # rad/mm
        phi = slope * y
        dy = jnp.broadcast_to(slope, jnp.broadcast_shapes(jnp.shape(x), jnp.shape(phi)))
        return phi, jnp.zeros_like(dy), dy

    def paraxial_power(self, wavelength) -> Array:
        """Zero (1/mm): a linear grating has no power (it only deflects; see the module
        docstring). ``wavelength`` (µm) is accepted for symmetry with ``Binary2``."""
        del wavelength
        return jnp.zeros_like(self.order * self.lines_per_um)


DIFFRACTIVE = (Binary2, Grating)
"""The surface kinds that carry a phase (``phase(x, y)``) and take the diffractive ray rule."""
