"""Refracting surface shapes.

Conventions:
    Lengths in mm. Each surface is described in its local frame: the vertex at the
    origin, the optical axis along +z. The sag is

        z(x, y) = c r² / (1 + sqrt(1 − (1+k) c² r²)) + Σ_{i=1..m} a_i r^{2i}
                  + Σ_{i=1..q} β_i r^i + Σ_{j=1..p} (b_j x^{2j+1} + d_j y^{2j+1})

    with r² = x² + y², curvature c = 1/R (c = 0 is flat), conic constant k (k = 0
    sphere, k = −1 paraboloid). The even series starts at a_1 r² (Zemax EVENASPH
    PARM1 = A2). The radial series Σ β_i r^i, every power of r from r¹ on (β_i in
    mm^(1−i)), is ``OddAsphere``, Zemax's odd asphere (ODDASPHE, PARM i = β_i); its
    β_1 r term is a cone with its tip on the axis. The x, y odd terms are the hybrid
    surface of Yang et al. (2024); they start at the cubic (a linear term would only
    tilt the surface). ``TiltedPlane`` is that linear term alone: the plane
    z = tan θx·x + tan θy·y through the vertex (Zemax TILTSURF), c = k = 0.

    ``semi_diameter`` is the clear-aperture radius; rays beyond it are clipped. It is
    ``inf`` (no clipping) unless a file or the user sets it.

All surfaces are final ``eqx.Module``s; numbers are arrays so ``jax.grad`` reaches
them, and the number of polynomial terms is static (a shape), so a surface with no
odd terms evaluates none.
"""

from __future__ import annotations

import math
import warnings
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .reciprocal import MIN_LENGTH_MM


def guarded_sqrt(x):
    """(sqrt(x) where x > 0 else 0, x > 0): finite gradients everywhere ("double where")."""
    ok = x > 0
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, x, 1.0)), 0.0), ok


def _safe_sqrt(x):
    """sqrt with a finite gradient where x <= 0."""
    return guarded_sqrt(x)[0]


class AbstractSurface(eqx.Module):
    """A rotationally symmetric base conic plus optional polynomial terms."""

    c: eqx.AbstractVar[Float[Array, ""]]
    k: eqx.AbstractVar[Float[Array, ""]]
    # Every subclass also has ``semi_diameter`` as its last field (not an AbstractVar
    # here, so that it stays last in the positional order).

    # Polynomial terms; zero-length arrays mean "none" and cost nothing.
    def even_coeffs(self) -> Float[Array, " m"]:
        return jnp.zeros((0,), jnp.result_type(self.c))

    def odd_coeffs(self) -> tuple[Float[Array, " p"], Float[Array, " p"]]:
        z = jnp.zeros((0,), jnp.result_type(self.c))
        return z, z

    def radial_coeffs(self) -> Float[Array, " q"]:
        """β_1 … β_q of Σ β_i r^i (``[i - 1]`` multiplies r^i)."""
        return jnp.zeros((0,), jnp.result_type(self.c))

    def _check_numbers(self):
        """Shapes always; concrete values: finite c and k, a semi-diameter > 0 (inf: none)."""
        where = type(self).__name__
        arrays = [(n, getattr(self, n)) for n in ("coeffs", "odd_x", "odd_y") if hasattr(self, n)]
        for name, a in arrays:
            if not 1 <= a.ndim <= jnp.ndim(self.c) + 1:
                raise ValueError(f"{where}: {name} must be a 1-D array of coefficients (one "
                                 f"per term), got shape {a.shape}")
        # |c| at most 1/MIN_LENGTH_MM (R >= 1 nm): c = 1e300 passed where no semi-diameter
        # bounded the surface, a sphere of radius 1e-300 mm that no ray but the axis meets.
        for name, bound, unit in (("c", MAX_CURVATURE, f"1/mm (|R| >= {MIN_LENGTH_MM:g} mm)"),
                                  ("k", None, "")):
            v = getattr(self, name)
            if not checks.is_traced(v):
                checks.values(v, name, where, unit=unit, hi=bound,
                              lo=None if bound is None else -bound)
        for name, a in arrays:
            if not checks.is_traced(a):
                checks.values(a, name, where)
        sd = self.semi_diameter
        if not checks.is_traced(sd):
            checks.values(sd, "semi_diameter", where, lo=0, lo_open=True, inf_ok=True,
                          unit="mm (inf: no clipping)")
        if not checks.is_traced((self.c, self.k, sd)):
            self._check_domain(where)

    def _check_domain(self, where: str):
        """The conic must exist out to the semi-diameter: (1 + k) c² r² <= 1 (+ 1e-6 for
        float32 rounding). A sphere of radius 3 mm with a 5 mm semi-diameter has no sag
        beyond 3 mm; every ray there was lost without a word."""
        c, k, sd = (np.asarray(v, float) for v in (self.c, self.k, self.semi_diameter))
        c, k, sd = np.broadcast_arrays(c, k, sd)
        with np.errstate(invalid="ignore", over="ignore"):  # c = 1e308: q = inf, no warning
            q = (1.0 + k) * c * c
            bad = np.isfinite(sd) & (q > 0) & (q * sd * sd > 1.0 + 1e-6)
        if np.any(bad):
            i = np.argwhere(bad)[0] if bad.ndim else ()
            ci, ki, si = float(c[tuple(i)]), float(k[tuple(i)]), float(sd[tuple(i)])
            r_max = 1.0 / math.sqrt((1.0 + ki) * ci * ci)
            raise ValueError(
                f"{where}: the surface (c = {ci:g} 1/mm, R = {1 / ci:g} mm, k = {ki:g}) is "
                f"defined only out to r = 1/(|c|·sqrt(1 + k)) = {r_max:g} mm, but its "
                f"semi_diameter is {si:g} mm; use a semi_diameter <= {r_max:g} mm (or a "
                f"flatter surface)")

    # --- geometry -----------------------------------------------------------------
    def conic_sag_and_slope(self, r2):
        """The base conic's sag, its (dz/dr)/r = c/sqrt(1 − (1+k)c²r²), and whether r² lies
        inside its domain; both finite (with finite gradients) outside it."""
        root, inside = guarded_sqrt(1.0 - (1.0 + self.k) * self.c**2 * r2)
        return self.c * r2 / (1.0 + root), self.c / jnp.where(inside, root, 1.0), inside

    def conic_sag(self, r2):
        """Sag of the base conic, and whether r² lies inside its domain."""
        z, _, inside = self.conic_sag_and_slope(r2)
        return z, inside

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        r2 = x * x + y * y
        z, inside = self.conic_sag(r2)
        a = self.even_coeffs()
        if a.shape[0]:
            z = z + r2 * jnp.polyval(a[::-1], r2)
        b = self.radial_coeffs()
        if b.shape[0]:
            z = z + _radial(b, r2)[0]
        bx, by = self.odd_coeffs()
        if bx.shape[0]:
            x2, y2 = x * x, y * y
            z = z + x * x2 * jnp.polyval(bx[::-1], x2) + y * y2 * jnp.polyval(by[::-1], y2)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and its partial derivatives (dz/dx, dz/dy), finite at r = 0 and c = 0."""
        r2 = x * x + y * y
        z, dr_over_r, inside = self.conic_sag_and_slope(r2)
        a = self.even_coeffs()
        if a.shape[0]:
            z = z + r2 * jnp.polyval(a[::-1], r2)
            i = jnp.arange(1, a.shape[0] + 1, dtype=a.dtype)
            dr_over_r = dr_over_r + jnp.polyval((2 * i * a)[::-1], r2)
        b = self.radial_coeffs()
        if b.shape[0]:
            zb, db = _radial(b, r2)
            z, dr_over_r = z + zb, dr_over_r + db
        gx = x * dr_over_r
        gy = y * dr_over_r
        bx, by = self.odd_coeffs()
        if bx.shape[0]:
            x2, y2 = x * x, y * y
            z = z + x * x2 * jnp.polyval(bx[::-1], x2) + y * y2 * jnp.polyval(by[::-1], y2)
            j = jnp.arange(bx.shape[0], dtype=bx.dtype)
            gx = gx + x2 * jnp.polyval(((2 * j + 3) * bx)[::-1], x2)
            gy = gy + y2 * jnp.polyval(((2 * j + 3) * by)[::-1], y2)
        return z, gx, gy, inside

    @property
    def has_polynomial(self) -> bool:
        """True if the surface needs Newton refinement beyond the closed-form conic."""
        bx, _ = self.odd_coeffs()
        return bool(self.even_coeffs().shape[0] or self.radial_coeffs().shape[0] or bx.shape[0])

    @property
    def paraxial_curvature(self) -> Array:
        """c + 2·a_1 + 2·β_2: the curvature the paraxial trace sees (includes the r² terms).

        A radial β_1 r term has no paraxial power: it is a cone, which tilts a ray by an angle
        that does not shrink with its height, so the linear y–nu trace cannot hold it; real
        rays see it.
        """
        a, b = self.even_coeffs(), self.radial_coeffs()
        c = self.c + 2.0 * a[0] if a.shape[0] else self.c
        return c + 2.0 * b[1] if b.shape[0] >= 2 else c


def _radial(b, r2):
    """Σ β_i r^i and its (dz/dr)/r = β_1/r + Σ_{i≥2} i β_i r^(i−2), with r = sqrt(r²).

    Both and their gradients are finite at r = 0 ("double where" on r and on β_1/r): there
    the β_1 cone's tip has no slope, so a ray on the axis gets the rest of the surface's
    normal (the base conic's), and the r^i terms from r² on keep their limit (2 β_2).
    """
    r = _safe_sqrt(r2)
    off_axis = r2 > 0
    i = jnp.arange(1, b.shape[0] + 1, dtype=b.dtype)
    rest = jnp.polyval((i * b)[:0:-1], r)  # Σ_{i≥2} i β_i r^(i−2)
    cone = jnp.where(off_axis, b[0] / jnp.where(off_axis, r, 1.0), 0.0)
    return r * jnp.polyval(b[::-1], r), cone + rest


_inf = lambda: jnp.asarray(jnp.inf)  # noqa: E731

_UNITS = {"c": "curvature, 1/mm", "cx": "curvature, 1/mm", "k": "conic constant",
          "semi_diameter": "mm", "focal_length": "mm", "decenter_x": "mm", "decenter_y": "mm",
          "tilt_x": "deg", "tilt_y": "deg", "tilt_z": "deg"}


def number_field(name: str, **default):
    """A numeric surface field: one converter for every surface class, so a string or bool
    is a TypeError naming the field and an integer becomes a float."""
    return checks.float_field(name, "surface", _UNITS.get(name, ""), **default)


class Standard(AbstractSurface):
    """Plane, sphere or conic (Zemax STANDARD)."""

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    semi_diameter: Float[Array, ""] = number_field("semi_diameter", default_factory=_inf)

    def __check_init__(self):
        self._check_numbers()


class EvenAsphere(AbstractSurface):
    """Conic plus an even series a_1 r² + a_2 r⁴ + … (Zemax EVENASPH, PARM1 = a_1)."""

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=(0.0,) * 8)
    semi_diameter: Float[Array, ""] = number_field("semi_diameter", default_factory=_inf)

    def __check_init__(self):
        self._check_numbers()

    def even_coeffs(self):
        return self.coeffs


class OddAsphere(AbstractSurface):
    """Conic plus the radial series β_1 r + β_2 r² + β_3 r³ + … (Zemax ODDASPHE, PARM i = β_i).

    ``coeffs[i - 1]`` multiplies r^i (mm^(1−i)); every power of r counts, odd and even. β_1
    is a cone (a kink on the axis) and β_2 adds 2·β_2 to the paraxial curvature.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " q"] = number_field("coeffs", default=(0.0,) * 8)
    semi_diameter: Float[Array, ""] = number_field("semi_diameter", default_factory=_inf)

    def __check_init__(self):
        self._check_numbers()

    def radial_coeffs(self):
        return self.coeffs


MAX_CURVATURE = 1e9  # 1 / MIN_LENGTH_MM, exactly (1/1e-9 is 999999999.9999999)
"""Largest |c| (1/mm) of a surface: a radius of at least ``reciprocal.MIN_LENGTH_MM``."""

STEEP_SLOPE = 5.0
"""A ``TiltedPlane`` slope at least this steep (a tilt of 78.7° or more) that is a whole
multiple of 5 is warned about as an angle in degrees given for its tangent."""


def _warn_if_degrees(name: str, slope: float) -> None:
    """``tan_x = 45`` is an 88.7° tilt that rays barely meet, not 45°."""
    if not (STEEP_SLOPE <= abs(slope) <= 90 and slope == round(slope) and slope % 5 == 0):
        return
    msg = (f"TiltedPlane: {name} = {slope:g} is a slope (tan θ), a tilt of "
           f"{math.degrees(math.atan(slope)):.2f}°")
    if abs(slope) < 90:
        msg += (f"; for {slope:g}° give {name} = tan({slope:g}°) = "
                f"{math.tan(math.radians(slope)):.6g}")
    warnings.warn(msg, stacklevel=2)


class TiltedPlane(AbstractSurface):
    """A plane through the vertex tilted against the x and y axes (Zemax TILTSURF).

    The sag is z = tan_x·x + tan_y·y (mm), so ``tan_x = tan θx`` is the slope dz/dx
    (dimensionless, Zemax PARM 1) and ``tan_y = tan θy`` the slope dz/dy (PARM 2); its normal
    is (−tan_x, −tan_y, 1)/norm. A positive ``tan_y`` moves the plane towards +z above the
    axis (y > 0). Unlike a coordinate break it leaves the frame of the surfaces after it
    unchanged. It has no paraxial power (c = k = 0): its tilt, which deviates rays as a prism
    face does, is seen by real rays only. Rays meet it by the generic Newton step, which
    lands on a plane in one iteration.

    Args:
        tan_x, tan_y: the slopes, finite.
        semi_diameter: clear-aperture radius (mm) of the projection onto the x–y plane,
            ``inf`` for none.
    """

    # c and k are fixed (a plane through the vertex): see ``ParaxialSurface``.
    c: ClassVar[property]
    k: ClassVar[property]
    tan_x: Float[Array, ""] = number_field("tan_x", default=0.0)
    tan_y: Float[Array, ""] = number_field("tan_y", default=0.0)
    semi_diameter: Float[Array, ""] = number_field("semi_diameter", default_factory=_inf)

    def __check_init__(self):
        for name in ("tan_x", "tan_y"):
            v = getattr(self, name)
            if not checks.is_traced(v):
                checks.values(v, name, "TiltedPlane")
                _warn_if_degrees(name, float(np.asarray(v)))
        self._check_numbers()

    @property
    def c(self) -> Array:
        return jnp.zeros_like(self.tan_x)

    @property
    def k(self) -> Array:
        return jnp.zeros_like(self.tan_x)

    @property
    def has_polynomial(self) -> bool:
        return True  # not a conic about the axis: the Newton step finds the plane

    def sag(self, x, y):
        z = self.tan_x * x + self.tan_y * y
        return z, jnp.ones(jnp.shape(z), bool)

    def sag_and_grad(self, x, y):
        z, inside = self.sag(x, y)
        zero = jnp.zeros_like(z)
        return z, zero + self.tan_x, zero + self.tan_y, inside


class Hybrid(AbstractSurface):
    """Even asphere plus the odd polynomial Σ_j (b_j x^{2j+1} + d_j y^{2j+1}), j = 1…p.

    ``odd_x[0]`` multiplies x³ (the cubic phase-plate term), ``odd_x[1]`` x⁵, and so on.

    This is the paper's hybrid surface for end-to-end design (no rotational symmetry).
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=(0.0,) * 8)
    odd_x: Float[Array, " p"] = number_field("odd_x", default=(0.0,) * 4)
    odd_y: Float[Array, " p"] = number_field("odd_y", default=(0.0,) * 4)
    semi_diameter: Float[Array, ""] = number_field("semi_diameter", default_factory=_inf)

    def __check_init__(self):
        if self.odd_x.shape != self.odd_y.shape:
            raise ValueError(
                f"Hybrid: odd_x and odd_y need the same length, got {self.odd_x.shape} "
                f"and {self.odd_y.shape}"
            )
        self._check_numbers()

    def even_coeffs(self):
        return self.coeffs

    def odd_coeffs(self):
        return self.odd_x, self.odd_y


def _factory(name: str, **fields) -> Standard:
    """``Standard(**fields)``, its refusals naming the factory the user called (``Plane``,
    ``Sphere``, ``Conic``, ``Stop``), not the class it builds."""
    try:
        return Standard(**fields)
    except (ValueError, TypeError) as e:
        msg = str(e)
        for said in ("Standard:", "surface:"):
            if msg.startswith(said):
                raise type(e)(f"{name}:{msg[len(said):]}") from None
        raise


def Plane(semi_diameter=jnp.inf) -> Standard:
    """A flat surface (c = 0)."""
    return _factory("Plane", c=0.0, k=0.0, semi_diameter=semi_diameter)


def Sphere(c, semi_diameter=jnp.inf) -> Standard:
    """A sphere of curvature c = 1/R (1/mm)."""
    return _factory("Sphere", c=c, k=0.0, semi_diameter=semi_diameter)


def Conic(c, k, semi_diameter=jnp.inf) -> Standard:
    """A conic of curvature c and conic constant k."""
    return _factory("Conic", c=c, k=k, semi_diameter=semi_diameter)


def Stop(semi_diameter=jnp.inf) -> Standard:
    """A flat circular aperture stop of the given radius (mark it with ``Lens.stop``)."""
    return _factory("Stop", c=0.0, k=0.0, semi_diameter=semi_diameter)
