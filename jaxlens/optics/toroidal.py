"""The toroidal surface (Zemax ``TOROIDAL``): a y–z profile swept about an axis parallel to y.

Conventions:
    Lengths in mm, local frame as in ``jaxlens.optics.surfaces`` (vertex at the origin, +z
    the axis). The profile in the y–z plane is a conic plus an even series in y,

        z_y(y) = c y² / (1 + sqrt(1 − (1+k) c² y²)) + Σ_{i=1..m} a_i y^{2i}

    (``a_1`` multiplies y², Zemax TOROIDAL PARM 2; ``a_i`` is PARM i+1). The profile is
    swept about the line parallel to y through z = R_x on the axis, R_x = 1/``cx`` the
    radius of rotation (Zemax PARM 1; ``cx = 0``, Zemax's R = 0, is the cylinder that
    extrudes the profile along x). A point at height y lies at distance R_x − z_y from
    that axis, so

        z(x, y) = R_x − sqrt((R_x − z_y)² − x²)
                = z_y + cx x² / (w + sqrt(w² − cx² x²)),    w = 1 − cx·z_y,

    the second form being finite at cx = 0 and free of cancellation. The surface is
    defined where the profile is (the conic's domain), where the point lies before the
    rotation axis (w > 0) and where w² > cx² x².

    The vertex curvatures are c + 2·a_1 in the y–z section and cx in the x–z section:
    paraxial optics (``jaxlens.optics.paraxial``) works in the y–z section, as Zemax
    does; ``paraxial.x_section(lens)`` gives the lens as the x–z section sees it.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .reciprocal import MIN_LENGTH_MM
from .surfaces import MAX_CURVATURE, AbstractSurface, guarded_sqrt, number_field


class Toroidal(AbstractSurface):
    """A toroid: a conic-plus-even-series profile in y–z, swept with radius 1/``cx`` about
    an axis parallel to y (Zemax TOROIDAL; see the module docstring).

    Args:
        c: curvature of the y–z profile (1/mm), Zemax CURV.
        k: conic constant of the profile, Zemax CONI.
        coeffs: a_1…a_m on y², y⁴, … (mm^{1−2i}), Zemax PARM 2…9.
        cx: curvature of rotation 1/R_x (1/mm); 0 is a cylinder (Zemax PARM 1 = 0).
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    coeffs: Float[Array, " m"] = number_field("coeffs", default=(0.0,))
    cx: Float[Array, ""] = number_field("cx", default=0.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        if self.coeffs.ndim != 1:
            raise ValueError(f"Toroidal: coeffs must be a 1-D array of a_1, a_2, … (on y², "
                             f"y⁴, …), got shape {self.coeffs.shape}")
        # Before: no value was checked; a NaN c or cx, an infinite conic or a semi-diameter of
        # -1 mm built a surface whose every ray was lost (or NaN) without a word.
        if not checks.is_traced(self.cx):
            checks.values(self.cx, "cx", "Toroidal", lo=-MAX_CURVATURE, hi=MAX_CURVATURE,
                          unit=f"1/mm (|R| >= {MIN_LENGTH_MM:g} mm)")
        self._check_numbers()

    def _check_domain(self, where: str):
        """The profile must exist out to the semi-diameter in y (the conic's domain), and the
        sweep out to it in x: on the x axis (z_y = 0, w = 1) that needs |cx|·sd <= 1, the
        radius of rotation at least the semi-diameter."""
        super()._check_domain(where)
        if checks.is_traced(self.cx):
            return
        sd = np.asarray(self.semi_diameter, float)
        cx = np.abs(np.asarray(self.cx, float))
        with np.errstate(invalid="ignore", over="ignore"):
            bad = np.isfinite(sd) & (cx * sd > 1.0 + 1e-6)
        if np.any(bad):
            r_max = float(np.min(1.0 / np.where(bad, cx, np.inf)))
            raise ValueError(
                f"{where}: the sweep about the rotation axis (cx = {float(np.max(cx)):g} 1/mm, "
                f"radius of rotation {r_max:g} mm) is defined only out to |x| = 1/|cx| = "
                f"{r_max:g} mm, but the semi_diameter is {float(np.max(sd)):g} mm; use a "
                f"semi_diameter <= {r_max:g} mm (or a smaller cx)")

    # The even series is in y only: it is not the rotationally symmetric ``even_coeffs``
    # (which code such as ``uniform_surfaces`` and tolerancing reads as a series in r²).
    @property
    def has_polynomial(self) -> bool:
        return True  # never a rotationally symmetric conic: always the Newton intersection

    @property
    def paraxial_curvature(self) -> Array:
        """c + 2·a_1: the vertex curvature of the y–z section (the paraxial one)."""
        return self.c + 2.0 * self.coeffs[0] if self.coeffs.shape[0] else self.c

    @property
    def paraxial_curvature_x(self) -> Array:
        """cx: the vertex curvature of the x–z section."""
        return self.cx

    def _profile(self, y):
        """z_y, dz_y/dy and whether y is inside the profile's domain."""
        y2 = y * y
        z, slope, inside = self.conic_sag_and_slope(y2)
        dz = y * slope
        a = self.coeffs
        if a.shape[0]:
            z = z + y2 * jnp.polyval(a[::-1], y2)
            i = jnp.arange(1, a.shape[0] + 1, dtype=a.dtype)
            dz = dz + y * jnp.polyval((2 * i * a)[::-1], y2)
        return z, dz, inside

    def sag(self, x, y):
        """Sag z(x, y) in mm; returns (sag, inside_domain)."""
        z, _, _, inside = self._sag_parts(x, y)
        return z, inside

    def sag_and_grad(self, x, y):
        """Sag and (dz/dx, dz/dy), finite everywhere (zero gradient outside the domain)."""
        return self._sag_parts(x, y)

    def _sag_parts(self, x, y):
        zy, dzy, inside = self._profile(y)
        w = 1.0 - self.cx * zy
        root, ok = guarded_sqrt(w * w - (self.cx * x) ** 2)
        inside = inside & ok & (w > 0)
        den = jnp.where(inside, w + root, 1.0)
        z = zy + self.cx * x * x / den
        # dz/dx = cx·x/root and dz/dy = z_y'·w/root (see the module docstring).
        safe_root = jnp.where(inside, root, 1.0)
        gx = jnp.where(inside, self.cx * x / safe_root, 0.0)
        gy = jnp.where(inside, dzy * w / safe_root, dzy)
        return z, gx, gy, inside
