"""Third-order (Seidel) aberrations and first-order colour from a paraxial marginal and chief ray.

Source and normalisation: W. T. Welford, *Aberrations of Optical Systems* (Adam Hilger,
1986), chapter 8 (the Seidel sums) and §8.4 (aspheric surfaces); the formulas below are
written from the book in jaxlens's paraxial convention, which is Welford's: u is the slope
dy/dz (a ray rising toward +z has u > 0), c = 1/R > 0 with the centre of curvature toward
+z, and a surface refracts as n′u′ = nu − y c (n′ − n).

Per surface (y, u: marginal ray; ȳ, ū: chief ray; n, n′ the indices before and after,
signed: they change sign after a mirror, as in ``jaxlens.optics.paraxial``; c the paraxial
curvature c + 2·a_1, so the r² term of an even asphere counts as it does in the paraxial
trace)::

    A = n(y c + u),  Ā = n(ȳ c + ū)              refraction invariants (n i)
    H = n(u ȳ − ū y)                             Lagrange invariant (mm)
    S_I   = −A² y Δ(u/n)                         spherical
    S_II  = −A Ā y Δ(u/n)                        coma
    S_III = −Ā² y Δ(u/n)                         astigmatism
    S_IV  = −H² c Δ(1/n)                         Petzval (= H² φ/(n n′), φ = c(n′ − n))
    S_V   = (Ā/A)(S_III + S_IV), evaluated as −Ā³ y Δ(1/n²) + Ā ȳ c Δ(1/n)(A ȳ − 2H)
            (the same number, with no division by A: a surface the marginal ray meets
            normally, A = 0, is fine)
    C_L   = A y Δ(δn/n)                          axial colour  (Welford's C_I)
    C_T   = Ā y Δ(δn/n)                          lateral colour (Welford's C_II)

with Δ(x) = x′ − x across the surface and δn = n(λ_short) − n(λ_long) over the lens's
shortest and longest wavelengths (0 for a lens with one wavelength; as Zemax and optiland).
Aspheric terms: a surface whose r⁴ sag coefficient departs from that of the sphere of its
paraxial curvature, z₄ = (1 + k)c_b³/8 + a_2 − c³/8 (c_b the base curvature, a_2 the r⁴
coefficient: EVENASPH PARM 2, ``EvenAsphere.coeffs[1]``, ``OddAsphere`` β_4), adds
δS_I = 8 z₄ (n′ − n) y⁴, δS_II = δS_I ȳ/y, δS_III = δS_I (ȳ/y)², δS_IV = 0,
δS_V = δS_I (ȳ/y)³ (Welford §8.4; for a conic, 8 z₄ = k c³). Higher terms (r⁶ …) are of
higher order and do not enter.

Units: every S and C is a length (mm), for the marginal ray of the full entrance pupil and
the chief ray of the field ``field`` (default the lens's largest). An object-space
telecentric lens (``Lens.object_na``; ``paraxial.marginal_ray`` and
``paraxial.paraxial_chief_ray`` trace its rays): the marginal ray leaves the axial object
point at the slope tan u of its NA, the chief ray the object height ``field`` (mm) parallel
to the axis, so H = n u h (n u from the NA, h the height: the Lagrange invariant of the
object plane). Welford's sign: S_I > 0
for a positive singlet (under-corrected spherical aberration). The wavefront aberration
(Welford's W, the optical path of the reference sphere minus that of the wavefront) is

    W = S_I/8 ρ⁴ + S_II/2 h ρ³ cos φ + S_III/2 h² ρ² cos² φ + (S_III + S_IV)/4 h² ρ²
        + S_V/2 h³ ρ cos φ + C_L/2 ρ² + C_T h ρ cos φ

(ρ the normalised pupil radius, h the normalised field). ``Seidel.wavefront`` gives the
terms as Zemax's "Seidel Diagram"/"Seidel Coefficients" list them, in waves of the
wavelength: W040 = S_I/8, W131 = S_II/2, W222 = S_III/2, W220P = S_IV/4, W311 = S_V/2,
W020 = C_L/2, W111 = C_T. ``Seidel.transverse`` gives the transverse ray aberrations on
the paraxial image plane (mm), ε_y = (1/n′u′) ∂W/∂ρ_y at ρ = 1 with n′u′ the image-space
marginal ray's reduced slope: TSPH = S_I/(2n′u′), TSCO = S_II/(2n′u′), TTCO = 3 S_II/(2n′u′),
TAST = S_III/(n′u′), TPFC = S_IV/(2n′u′), TSFC = (S_III + S_IV)/(2n′u′),
TTFC = (3 S_III + S_IV)/(2n′u′), TDIS = S_V/(2n′u′), TAXC = C_L/(n′u′), TLAC = C_T/(n′u′).
They are the third-order parts of a real ray's error: TSPH is y − y_paraxial of the ray
through the top of the pupil (negative for an under-corrected positive singlet, whose
marginal rays cross the axis before the paraxial focus), TDIS the chief ray's height minus
the paraxial image height, TLAC the short-wavelength chief ray's height minus the long one's
(``tests/test_seidel.py`` checks all of these signs against real rays; the names are
Zemax's, but its sign conventions were not available to check against).

Compared with optiland 0.6.3 (``optiland.aberrations``, ``tests/test_seidel.py``,
``tools/seidel_reference.py``, ``tests/test_conventions_vs_optiland.py``): its
``seidels()`` are −(these sums) (opposite sign convention); its per-surface transverse
terms TSC, CC, TPC, DC, TAchC, TchC are TSPH, TSCO, TPFC, TDIS, TAXC, TLAC here, and its
TAC is TAST/2 (S_III/(2n′u′)). With the same glasses they agree to 3e-15 mm per surface on
the Cooke triplet, the double Gauss and the double Gauss with its object at 300 mm. It
ignores the polynomial terms of an even asphere (A4 …), which are included here: the
difference is exactly the δS terms above (checked on a triplet with r⁴ and r⁶ terms).
Zemax: OpticStudio's "Seidel Coefficients" listing names the sums SPHA (S_I), COMA (S_II),
ASTI (S_III), FCUR (S_IV), DIST (S_V), CLA (C_L), CTR (C_T), in lens units, and the
wavefront and transverse terms by the names used here; its manual cites Welford for the
formulas, whose sign is the one kept here (optiland's is the opposite). No OpticStudio
output was at hand to check the signs against directly.

Handled surfaces: ``Standard`` (planes, spheres, conics, the stop), ``EvenAsphere``, and
``OddAsphere``/``Hybrid`` whose odd terms (β_1 r, β_3 r³; the hybrid's x³, y³ … series)
are zero. Refused with a ``ValueError`` naming the surface: coordinate breaks and tilted
planes (not rotationally symmetric about one axis), toroids, hybrid surfaces with odd terms,
odd aspheres with β_1 or β_3 (not analytic at the axis: no ρ⁴ expansion), Q-type aspheres,
ideal paraxial surfaces, diffractive (Binary 2) surfaces and gratings (their aberrations
are not those of a refracting surface). Everything is differentiable and jittable; under a
trace, the odd terms that must be zero are checked with ``eqx.error_if``.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..imaging.telecentric import largest_height, lens_fields
from ..optics import checks, paraxial
from ..optics.lens import Lens
from ..optics.surfaces import EvenAsphere, Hybrid, OddAsphere, Standard

SEIDEL_TERMS = ("S_I", "S_II", "S_III", "S_IV", "S_V", "C_L", "C_T")
"""Row names of ``Seidel.per_surface``: spherical, coma, astigmatism, Petzval, distortion,
axial colour, lateral colour (mm)."""

WAVEFRONT_TERMS = ("W040", "W131", "W222", "W220P", "W311", "W020", "W111")
"""Row names of ``Seidel.wavefront`` (waves), Zemax's names."""

TRANSVERSE_TERMS = ("TSPH", "TSCO", "TTCO", "TAST", "TPFC", "TSFC", "TTFC", "TDIS", "TAXC",
                    "TLAC")
"""Row names of ``Seidel.transverse`` (mm), Zemax's names."""


class Seidel(eqx.Module):
    """Seidel sums of a lens, per surface (see the module notes for every formula).

    Attributes:
        per_surface: ``[7, n]`` S_I, S_II, S_III, S_IV, S_V, C_L, C_T of each of the n
            surfaces (mm; ``SEIDEL_TERMS``).
        field: the field angle (deg) of the chief ray (an object height in mm for an
            object-space telecentric lens).
        wavelength: the wavelength (µm) of the monochromatic sums.
        lagrange: the Lagrange invariant H = n(u ȳ − ū y) (mm).
        image_nu: n′u′, the image-space marginal ray's reduced slope.
    """

    per_surface: Float[Array, "7 n"]
    field: Float[Array, ""]
    wavelength: Float[Array, ""]
    lagrange: Float[Array, ""]
    image_nu: Float[Array, ""]

    @property
    def sums(self) -> Float[Array, " 7"]:
        """S_I … S_V, C_L, C_T of the whole lens (mm)."""
        return jnp.sum(self.per_surface, axis=-1)

    def _pick(self, per_surface: bool) -> Array:
        # "no" is truthy: it gave the [7, n] table where the sums were asked for.
        checks.switch(per_surface, "per_surface", "Seidel")
        return self.per_surface if per_surface else self.sums

    def wavefront(self, *, per_surface: bool = False) -> Array:
        """W040, W131, W222, W220P, W311, W020, W111 in waves at ``wavelength``.

        Returns ``[7]`` (sums) or ``[7, n]`` (per surface); rows ``WAVEFRONT_TERMS``.
        """
        s = self._pick(per_surface)
        w = jnp.stack([s[0] / 8, s[1] / 2, s[2] / 2, s[3] / 4, s[4] / 2, s[5] / 2, s[6]])
        return w / (self.wavelength * 1e-3)

    def transverse(self, *, per_surface: bool = False) -> Array:
        """TSPH, TSCO, TTCO, TAST, TPFC, TSFC, TTFC, TDIS, TAXC, TLAC on the paraxial image
        plane (mm). Returns ``[10]`` or ``[10, n]``; rows ``TRANSVERSE_TERMS``."""
        s = self._pick(per_surface)
        k = 1.0 / (2.0 * self.image_nu)
        return jnp.stack([
            s[0] * k, s[1] * k, 3 * s[1] * k, 2 * s[2] * k, s[3] * k, (s[2] + s[3]) * k,
            (3 * s[2] + s[3]) * k, s[4] * k, 2 * s[5] * k, 2 * s[6] * k])


def _odd_terms(surface) -> Array | None:
    """The odd terms that must vanish for third-order theory (None if the kind has none)."""
    if isinstance(surface, Hybrid):
        ox, oy = surface.odd_coeffs()
        return jnp.concatenate([ox, oy])
    if isinstance(surface, OddAsphere):
        b = surface.radial_coeffs()
        return b[jnp.array([i for i in (0, 2) if i < b.shape[0]], int)]
    return None


def _check_surfaces(lens: Lens, where: str) -> list:
    """Refuse surfaces that third-order theory does not cover; returns the arrays of odd
    terms that are traced (to be checked under the trace)."""
    handled = (Standard, EvenAsphere, OddAsphere, Hybrid)
    traced = []
    for i, s in enumerate(lens.surfaces):
        kind = type(s).__name__
        if not isinstance(s, handled):
            why = {
                "CoordinateBreak": "a coordinate break (decenter/tilt) breaks the rotational "
                                   "symmetry",
                "TiltedPlane": "a tilted plane is not rotationally symmetric",
                "Toroidal": "a toroid is not rotationally symmetric",
                "QTypeAsphere": "Q-type aspheres are not handled",
                "XYPolynomial": "an XY polynomial (Zemax XPOLYNOM) is not rotationally "
                                "symmetric",
                "ParaxialSurface": "an ideal paraxial surface has no surface aberrations of "
                                   "its own",
                "Binary2": "a diffractive surface's aberrations are not a refracting "
                           "surface's",
                "Grating": "a grating is not rotationally symmetric",
            }.get(kind, "its kind is not handled")
            raise ValueError(
                f"{where}: surface {i} ({kind}): {why}; third-order (Seidel) theory here "
                f"handles Standard, EvenAsphere, and OddAsphere/Hybrid without odd terms")
        odd = _odd_terms(s)
        if odd is None or odd.size == 0:
            continue
        if checks.is_traced(odd):
            traced.append((i, kind, odd))
        elif bool(jnp.any(odd != 0)):
            what = ("odd x/y terms (not rotationally symmetric)" if isinstance(s, Hybrid)
                    else "β_1 r or β_3 r³ terms (not analytic at the axis)")
            raise ValueError(f"{where}: surface {i} ({kind}) has nonzero {what}; third-order "
                             f"(Seidel) theory does not apply")
    return traced


def _r4_coefficient(surface) -> Array:
    """The r⁴ sag coefficient of the polynomial part (0 for a plain conic)."""
    if isinstance(surface, (EvenAsphere, Hybrid)):
        a = surface.even_coeffs()
        return a[1] if a.shape[0] >= 2 else jnp.zeros_like(surface.c)
    if isinstance(surface, OddAsphere):
        b = surface.radial_coeffs()
        return b[3] if b.shape[0] >= 4 else jnp.zeros_like(surface.c)
    return jnp.zeros_like(surface.c)


def _field(lens: Lens, field, where: str) -> Array:
    """The chief ray's field angle (deg): given, or the lens's largest (radial for pairs);
    for an object-space telecentric lens its object height (mm), given or the largest."""
    if lens.telecentric_object:
        if field is None:
            return jnp.asarray(largest_height(lens), lens.epd.dtype)
        if jnp.ndim(field) != 0:
            raise ValueError(f"{where}: field must be one object height y in mm (a scalar; "
                             f"the lens is object-space telecentric), got shape "
                             f"{np.shape(field)}")
        return jnp.asarray(lens_fields(lens, field, where, "field"), lens.epd.dtype)
    if field is None:
        f = jnp.asarray(lens.fields)
        t = jnp.tan(jnp.deg2rad(f))
        t = jnp.sqrt(jnp.sum(t * t, axis=-1)) if f.ndim == 2 else jnp.abs(t)
        return jnp.rad2deg(jnp.arctan(jnp.max(t)))
    if jnp.ndim(field) != 0:
        raise ValueError(f"{where}: field must be one angle θy in degrees (a scalar), got "
                         f"shape {np.shape(field)}")
    field = checks.field_angles(field, where, "field")
    checks.warn_if_radian_fields(field, where, "field")  # 20° typed as 0.349
    return jnp.asarray(field, lens.epd.dtype)


def _incoming(lens: Lens, y, nu, n, wl) -> Array:
    """The reduced slopes before each surface, from the heights and the slopes after."""
    p0 = paraxial.surface_power(lens.surfaces[0], n[0], n[1], wl)
    first = nu[0] + y[0] * p0
    return jnp.concatenate([first[None], nu[:-1]])


def seidel(lens: Lens, *, field=None, wavelength=None) -> Seidel:
    """Seidel aberration sums S_I … S_V and first-order colour C_L, C_T, per surface.

    Args:
        lens: the lens (surfaces of the kinds listed in the module notes).
        field: the chief ray's field angle θy in degrees; default the lens's largest field
            (for (θx, θy) fields the largest radial angle). For an object-space telecentric
            lens (``Lens.object_na``) an object height y in mm, default its largest (radial)
            height: the paraxial chief ray leaves it parallel to the axis (ū = 0) and the
            marginal ray leaves the axial object point at tan u, u = asin(NA/n).
        wavelength: µm; default the lens's primary wavelength. Colour uses the lens's
            shortest and longest wavelengths whatever this is.

    Returns:
        A :class:`Seidel`; ``.sums``, ``.wavefront()`` (waves), ``.transverse()`` (mm).

    Raises:
        ValueError: a surface that third-order theory does not cover (named, with why), a
            wavelength outside the materials' range, a field outside (−90°, 90°).

    Example:
        >>> import jaxlens
        >>> s = seidel(jaxlens.zoo.cooke_triplet())
        >>> s.per_surface.shape
        (7, 6)
    """
    checks.focal_image(lens, "seidel")
    where = "seidel"
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    checks.lens_intact(lens, where)
    traced_odd = _check_surfaces(lens, where)
    wl = lens.primary_wavelength if wavelength is None else wavelength
    if jnp.ndim(wl) != 0:
        raise ValueError(f"{where}: wavelength must be one value (µm), got shape "
                         f"{jnp.shape(wl)}")
    wl = jnp.asarray(checks.wavelengths(lens, wl, where), lens.epd.dtype)
    if not checks.is_traced((wl, lens.wavelengths)):  # colour reads the lens's too
        # A formula material of index 0.71 (or NaN) there gave plausible sums, or NaN.
        checks.material_indices(lens, np.unique(np.append(wl, lens.wavelengths)), where,
                                "wavelength (or the lens's wavelengths)", intact=True)
    if not lens.telecentric_object and not checks.is_traced((lens, wl)):
        # Its marginal ray, traced in the compiled core, was the axis (every sum 0).
        paraxial.check_marginal_pupil(paraxial.compiled_entrance_pupil_z(lens, wl), None if
                                      lens.object_at_infinity else lens.object_distance, where)
    fld = _field(lens, field, where)
    out = _seidel(lens, fld, wl)
    for i, kind, odd in traced_odd:
        out = eqx.error_if(out, jnp.any(odd != 0),
                           f"{where}: surface {i} ({kind}) has nonzero odd terms; third-order "
                           f"(Seidel) theory does not apply")
    return out


@checks.checked_core(eqx.filter_jit)
def _seidel(lens: Lens, fld, wl) -> Seidel:
    """``seidel``'s compiled core (its arguments checked before it): a second call on a lens
    of the same structure reuses the program, where op-by-op dispatch took 60-90 ms."""
    n = paraxial.signed_indices(lens, wl)
    y, nu_out = paraxial.marginal_ray(lens, wl)
    yb, nub_out = paraxial.paraxial_chief_ray(lens, fld, wl)
    nu_in = _incoming(lens, y, nu_out, n, wl)
    nub_in = _incoming(lens, yb, nub_out, n, wl)
    n1, n2 = jnp.stack(n[:-1]), jnp.stack(n[1:])  # [n] before, after each surface
    c = jnp.stack([s.paraxial_curvature for s in lens.surfaces])
    cb = jnp.stack([s.c for s in lens.surfaces])
    k = jnp.stack([s.k for s in lens.surfaces])
    a4 = jnp.stack([_r4_coefficient(s) for s in lens.surfaces])

    big_a = nu_in + n1 * y * c
    big_ab = nub_in + n1 * yb * c
    h = nu_in[0] * yb[0] - nub_in[0] * y[0]
    d_u_n = nu_out / n2**2 - nu_in / n1**2
    d_inv_n = 1.0 / n2 - 1.0 / n1
    d_inv_n2 = 1.0 / n2**2 - 1.0 / n1**2

    # Aspheric departure of the r⁴ sag from the sphere of the paraxial curvature.
    q = ((1.0 + k) * cb**3 + 8.0 * a4 - c**3) * (n2 - n1)
    s1 = -big_a**2 * y * d_u_n + q * y**4
    s2 = -big_a * big_ab * y * d_u_n + q * y**3 * yb
    s3 = -big_ab**2 * y * d_u_n + q * y**2 * yb**2
    s4 = -h**2 * c * d_inv_n
    s5 = (-big_ab**3 * y * d_inv_n2 + big_ab * yb * c * d_inv_n * (big_a * yb - 2.0 * h)
          + q * y * yb**3)

    wls = lens.wavelengths
    short, long = jnp.min(wls), jnp.max(wls)
    dn = [a - b for a, b in zip(paraxial.signed_indices(lens, short),
                                paraxial.signed_indices(lens, long), strict=True)]
    dn1, dn2 = jnp.stack(dn[:-1]), jnp.stack(dn[1:])
    d_dn_n = dn2 / n2 - dn1 / n1
    cl = big_a * y * d_dn_n
    ct = big_ab * y * d_dn_n
    per = jnp.stack([s1, s2, s3, s4, s5, cl, ct])
    return Seidel(per, fld, wl, h, nu_out[-1])
