"""The diffractive surface (Zemax ``BINARY_2``): an even asphere carrying a radial phase.

Conventions:
    Lengths in mm, phase in radians, wavelengths in µm (as everywhere in the API). The sag is
    the even asphere's (``jaxlens.optics.surfaces``): the base conic of curvature c and conic
    constant k plus Σ a_i r^{2i} (Zemax PARM 1…8). The surface also carries the phase

        Φ(x, y) = M Σ_{i=1..N} A_i ρ^{2i},        ρ = r / R,   r² = x² + y²,

    with M the diffraction order (Zemax PARM 0), R the normalisation radius (mm, XDAT 2) and
    A_i the phase coefficients (radians, dimensionless; XDAT 3…). Φ is a function of the x, y
    of the point where the ray meets the surface.

    A ray meets the surface with unit direction d in index n and leaves with unit direction d′
    in index n′ by the local grating equation: the component of n′d′ tangent to the surface
    equals that of n·d + (λ/2π)∇Φ, with λ the wavelength in mm and ∇Φ = (∂Φ/∂x, ∂Φ/∂y, 0)
    (whose tangential part is the surface gradient of Φ, as Φ depends on x and y only); the
    normal part of d′ follows from |d′| = 1 on the side the ray was going. Where no real d′
    exists (the diffracted wave is evanescent, or totally reflected) the ray is lost, as at
    total internal reflection. The optical path gains (λ/2π)Φ, so the optical path stays an
    eikonal (∇S = n·d on both sides). With M = 0 the surface is the plain even asphere.
    The rule is ``jaxlens.tracing.step.diffract``.

    Signs: a positive ∂Φ/∂x pushes the ray toward +x. A phase A_1 < 0 (with M = 1) converges
    a beam: its paraxial power is

        P = −M λ A_1 / (π R²)            (1/mm, λ in mm)

    added to the base surface's c_par (n′ − n), whatever the media; it scales with the
    wavelength (a diffractive lens has an Abbe number of λ_d/(λ_F − λ_C) ≈ −3.45). The ideal
    focusing phase of a lens of focal length f at λ is −(2π/λ)(sqrt(r² + f²) − f), so
    A_1 = −π R²/(λ f) to leading order.

    The surface cannot be a mirror (refused when traced), has no JSON form (save it as
    ``.zmx``) and is refused by tolerancing, the design parameterisation and
    ``rebase_conic``.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from . import checks
from .surfaces import AbstractSurface, number_field

_UM_TO_MM = 1e-3


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
