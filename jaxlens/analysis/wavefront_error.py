"""Wavefront error: optical path difference (OPD) to the exit-pupil reference sphere, the
wavefront map with its RMS and peak-to-valley, Zernike fits, Maréchal's Strehl ratio and
OPD fans.

Conventions (optiland's "chief_ray" reference, Zemax's definition of the reference sphere):
    Lengths in mm, wavelengths in µm, field angles in degrees (θy, or (θx, θy)); for an
    object-space telecentric lens (``Lens.object_na``) a field is an object height in mm,
    y or (x, y), checked as a height (no angle range). OPD in waves at the wavelength
    traced. Pupil points (Px, Py) are normalised to the paraxial
    entrance pupil (the unit disc), launched as ``jaxlens.imaging.sampling.field_rays``
    launches them (``aim="paraxial"``: through (Px, Py)·EPD/2 on the paraxial
    entrance-pupil plane; ``aim="real"``/``"real_marginal"``: through (Px, Py)·(stop
    radius) on the real stop, sized by the paraxial/real marginal ray).

    Each ray's optical path starts on the incoming wavefront: for an object at infinity the
    plane wave through the origin (the trace's path plus n₀ d·o for the launch point o and
    direction d), for a finite object the object point. The chief ray is the ray through the
    pupil centre (0, 0) at the same wavelength, traced without apertures or obscurations.
    The reference sphere is centred on the chief ray's intercept C with the image surface
    and passes through the paraxial exit pupil E = (0, 0, z_xp) (primary wavelength), radius
    R = |C − E|. Each ray is followed back from its image-surface intercept P along −d to
    the sphere (the root nearer the exit pupil, distance t > 0), so its path to the sphere
    is L = OPL(P) − n′·t with n′ the image-space index. Then

        OPD = (L_chief − L) / λ        (waves),

    positive where the ray reaches the reference sphere with less optical path than the
    chief ray, that is where the wavefront is ahead of the reference sphere. This is
    optiland's sign (``optiland.wavefront.OPD``, strategy "chief_ray"): OPD and Zernike
    fits agree with optiland 0.6.3's to 1e-9 wave on the Cooke triplet, the double Gauss
    (object at infinity and at 300 mm) and an even-asphere triplet
    (``tests/test_conventions_vs_optiland.py``). It is also Zemax's, as far as published
    material shows: OpticStudio's OPD is Welford's [Q Q̄] (the path from the reference
    sphere to the wavefront along the ray, Welford's W, positive ahead), and batoid's
    wavefront (chief-ray path minus ray path) reproduces an OpticStudio Zernike Standard
    listing (batoid's test of the HSC telescope) with no change of sign. No OpticStudio
    output was at hand to compare with directly. The chief ray's OPD is 0. A
    perfect wave converging to a focus that lies a distance dz before the image surface
    (dz > 0: the image surface is beyond the focus) has, for the ray at angle U to the
    chief ray,
    OPD = n′·(dz·(1 − cos U) + sqrt(R² − dz²·sin²U) − R)/λ ≈ n′·dz·(1 − cos U)/λ, positive
    (the paraxial W020 = n′·dz·NA²/(2λ) at the rim). ``reference="plane"`` (afocal image
    space) measures to the plane through C normal to the chief ray instead.

    The exit pupil may lie at infinity (image-space telecentric): the reference sphere is
    then of infinite radius, and the distance back to it is taken in a form that stays exact
    as R grows.

    Precision: an optical path of L mm carries rounding of about eps·L, a few hundredths of
    a wave in float32 for L ~ 100 mm. A float32 lens is therefore traced in float64 when
    ``jax_enable_x64`` is on (results are cast back to float32); with x64 off, float32 OPD
    is good to about 2⁻²⁴·L/λ waves only (0.02–0.08 wave measured on 100–200 mm paths).

    A ray that is vignetted (clipped, missed a surface, TIR) has OPD NaN and valid False;
    so has every ray when the chief ray fails. Lenses with coordinate breaks are refused
    (the exit pupil is found on the unfolded axis only).

Summary statistics (``wavefront``): the map is sampled on a ``grid × grid`` square grid over
[−1, 1]² cut to the unit disc (points with Px² + Py² <= 1), each point weighing the same, as
Zemax's wavefront map. ``rms`` and ``pv`` are taken with piston (the mean) removed and tilt
kept (Zemax's RMS "to chief": an OpticStudio Zernike listing says it is "the RMS of the
OPD after subtracting out piston"); ``rms_tilt_removed`` and ``pv_tilt_removed`` also
remove the least-squares tilt a + b·Px + c·Py (its "to centroid": "after subtracting out
both piston and tilt", the tilt that minimises the variance).
optiland's ``remove_tilt`` fits its plane in exit-pupil coordinates (mm on the reference
sphere) instead of (Px, Py); pupil distortion sets them apart (2.5e-5 wave of RMS on the
Cooke triplet at 14°). Zernike coefficients are fitted over the same points in (Px, Py)
(``Wavefront.zernike``, equal weights, as optiland's ``ZernikeFit``; "noll" is Zemax's
"Zernike Standard", whereas optiland's ``zernike_type="standard"`` is the OSA/ANSI set,
``indexing="ansi"`` here). ``strehl`` is
Maréchal's approximation exp(−(2π σ)²) with σ = ``rms_tilt_removed`` (the Strehl ratio at
the best lateral image position, best focus not sought); good to a few per cent for σ below
about 0.1 wave.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from ..imaging.light import refuse_dark
from ..imaging.sampling import field_rays, lens_aim, lens_depth, pupil_points
from ..imaging.telecentric import lens_field
from ..optics import checks, paraxial
from ..optics.coordinates import CoordinateBreak
from ..optics.lens import RAY_AIMING, Lens, unclipped
from ..tracing.forward import DEFAULT_NEWTON_ITERS, aimed_jit, trace
from .zernike import ZernikeFit, zernike_fit

__all__ = ["REFERENCES", "Wavefront", "OPDFan", "opd", "wavefront", "opd_fan",
           "marechal_strehl", "MARECHAL_MAX_RMS"]

REFERENCES = ("sphere", "plane")
AIMS = RAY_AIMING
DEFAULT_GRID = 65
"""Default wavefront-map samples per side (odd: the chief ray is a grid point)."""


# --------------------------------------------------------------------------------------
# Checks shared by the entry points
# --------------------------------------------------------------------------------------
def _precise(lens):
    """(the lens to trace, the dtype to return). A float32 lens is traced in float64 when
    ``jax_enable_x64`` is on: its optical paths (~100 mm, ~2e5 waves) carry float32
    rounding of ~1e-5 mm, a few hundredths of a wave, as large as the OPD of a good lens."""
    dtype = lens.epd.dtype if isinstance(lens, Lens) else None
    if dtype == jnp.float32 and jax.config.jax_enable_x64:
        return lens.astype(jnp.float64), dtype
    return lens, dtype


def _cast(tree, dtype):
    """Floating leaves of ``tree`` cast to ``dtype`` (None: unchanged)."""
    if dtype is None:
        return tree
    return jax.tree_util.tree_map(
        lambda x: x.astype(dtype) if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating)
        else x, tree)


def _common(lens, field, wavelength, depth, reference, aim, where: str):
    """Checked (field, wavelength, depth) as lens-dtype arrays, the reference and the ray
    aiming (None: the lens's own); raises ValueError naming ``where`` and the argument."""
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    if any(isinstance(s, CoordinateBreak) for s in lens.surfaces):
        raise ValueError(f"{where}: lenses with coordinate breaks are not supported (the "
                         f"paraxial exit pupil that sets the reference sphere is found on "
                         f"the unfolded axis only)")
    if reference is None:  # the lens's own image space
        reference = "plane" if lens.afocal_image else "sphere"
    if reference not in REFERENCES:
        raise ValueError(f"{where}: reference must be one of {REFERENCES} ('sphere': the "
                         f"exit-pupil reference sphere; 'plane': afocal image space), got "
                         f"{reference!r}")
    if reference == "sphere" and lens.afocal_image:
        raise ValueError(f"{where}: the lens has an afocal image space (Lens.afocal_image): "
                         f"its wavefront is referenced to a plane; pass reference='plane' "
                         f"(or None, the lens's own)")
    aim = lens_aim(lens, aim, where)
    dtype = lens.epd.dtype
    f = jnp.asarray(lens_field(lens, field, where), dtype)  # heights (mm) or angles (deg)
    wl = lens.primary_wavelength if wavelength is None else wavelength
    checks.real_values(wl, "wavelength", where, "µm")
    if jnp.shape(wl) != ():
        raise ValueError(f"{where}: wavelength must be one value in µm, got shape "
                         f"{jnp.shape(wl)} (analyse several wavelengths one at a time)")
    if not checks.is_traced(wl):
        checks.number(wl, "wavelength", where, lo=0, lo_open=True, unit="µm")
    wl = checks.wavelengths(lens, jnp.asarray(wl, dtype), where, "wavelength")
    checks.material_indices(lens, wl, where)
    checks.primary_wavelength(lens, where, "the chief ray's and exit pupil's")
    return f, wl, lens_depth(lens, depth, where), reference, aim



# --------------------------------------------------------------------------------------
# The optical path difference
# --------------------------------------------------------------------------------------
def _path_to_reference(lens, field, pts, wl, depth, reference, aim, newton_iters):
    """(OPD in waves [m], valid [m]) of the rays through the pupil points ``pts`` [m, 2]."""
    dtype = pts.dtype

    def launched(p, on):
        rays = field_rays(lens, field, p, wl, depth=depth, aim=aim)
        out = trace(on, rays, newton_iters=newton_iters, chunk=None)
        path = out.opl
        if depth is None:  # the plane wave through the origin: n₀ d·o at the launch point
            n0 = lens.object_material.index(wl)
            path = path + n0 * jnp.sum(rays.direction * rays.origin, -1)
        return out, path

    chief, chief_path = launched(jnp.zeros((1, 2), dtype), unclipped(lens))
    out, path = launched(pts, lens)
    n_img = lens.materials[-1].index(wl)
    c = chief.origin[0]
    if reference == "sphere":
        xp = paraxial.paraxial_data(lens).exit_pupil_z
        # An exit pupil at infinity (image-space telecentric) is a sphere of infinite
        # radius: R² = inf below, and the distance beyond R tends to b (double where: a
        # finite stand-in keeps the gradient finite).
        far = ~jnp.isfinite(xp)
        xs = jnp.where(far, 0.0, xp)
        e = jnp.stack([jnp.zeros_like(xs), jnp.zeros_like(xs), xs])
        r2 = jnp.where(far, jnp.inf, jnp.sum((c - e) ** 2))
        r = jnp.sqrt(r2)

        def back(p, d):
            """Distance back along −d from p to the sphere (the root toward the pupil),
            minus R (the chief ray's distance): b + (b² − |p − c|²)/(√disc + R), which
            stays exact when R is large or infinite (b + √disc − R cancels)."""
            b = jnp.sum(d * (p - c), -1)
            q = b * b - jnp.sum((p - c) ** 2, -1)
            disc = q + r2
            ok = disc > 0
            return b + q / (jnp.sqrt(jnp.where(ok, disc, 1.0)) + r), ok

        t_c, ok_c = back(c, chief.direction[0])
        t, ok = back(out.origin, out.direction)
    else:
        normal = chief.direction[0]

        def back(p, d):
            den = jnp.sum(d * normal, -1)
            ok = den != 0
            return jnp.sum((p - c) * normal, -1) / jnp.where(ok, den, 1.0), ok

        t_c, ok_c = jnp.zeros((), dtype), jnp.ones((), bool)
        t, ok = back(out.origin, out.direction)
    ref_c = chief_path[0] - n_img * t_c
    opd_mm = ref_c - (path - n_img * t)
    valid = out.valid & ok & chief.valid[0] & ok_c
    waves = opd_mm / (wl * 1e-3)
    return jnp.where(valid, waves, jnp.nan), valid


@checks.checked_core(aimed_jit)
def _opd_impl(lens, field, pts, wl, depth, *, reference, aim, newton_iters):
    return _path_to_reference(lens, field, pts, wl, depth, reference, aim, newton_iters)


def opd(
    lens: Lens,
    field: Float[ArrayLike, ""] | Float[ArrayLike, " 2"],
    pupil: Float[ArrayLike, "*m 2"],
    *,
    wavelength: Float[ArrayLike, ""] | None = None,
    depth=None,
    reference: str | None = None,
    aim: str | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, "*m"]:
    """Optical path difference (waves) of the rays through normalised pupil points.

    See the module notes for the reference sphere and the sign (optiland's: positive where
    the wavefront is ahead of the reference sphere).

    Args:
        lens: the lens.
        field: field angle in degrees, θy or (θx, θy); an object height in mm, y or
            (x, y), for an object-space telecentric lens.
        pupil: ``[..., 2]`` points (Px, Py) in the unit disc (normalised entrance pupil).
        wavelength: µm (default the primary wavelength); one value.
        depth: object distance in mm before surface 1 (inf for infinity); None (default)
            for the lens's own object.
        reference: "sphere" (exit-pupil reference sphere) or "plane" (afocal image space);
            None (the default): the lens's own, "plane" where ``lens.afocal_image``.
        aim: "paraxial", "real" or "real_marginal" (as
            ``jaxlens.imaging.sampling.field_rays``); None (the default): the lens's own ray
            aiming, ``lens.aim``.
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        ``[...]`` OPD in waves at ``wavelength``; NaN for rays that do not reach the image
        surface (``wavefront(...).valid`` has the mask).

    Example:
        >>> import jax.numpy as jnp, jaxlens
        >>> from jaxlens.analysis.wavefront_error import opd
        >>> lens = jaxlens.zoo.cooke_triplet()
        >>> w = opd(lens, 0.0, jnp.array([[0.0, 0.0], [0.0, 1.0]]))
        >>> float(w[0]), bool(abs(w[1]) < 2)
        (0.0, True)
    """
    lens, dtype = _precise(lens)
    f, wl, depth, reference, aim = _common(lens, field, wavelength, depth, reference, aim, "opd")
    checks.newton_iters(newton_iters, "opd")
    p = pupil_points(pupil, "opd", unit_disc=True)
    shape = p.shape[:-1]
    w, _ = _opd_impl(lens, f, p.reshape(-1, 2).astype(lens.epd.dtype), wl, depth,
                     reference=reference, aim=aim, newton_iters=int(newton_iters))
    return _cast(w.reshape(shape), dtype)


# --------------------------------------------------------------------------------------
# The wavefront map and its statistics
# --------------------------------------------------------------------------------------
MARECHAL_MAX_RMS = 0.1
"""Waves (RMS, tilt removed): above this Maréchal's approximation is no estimate of the Strehl
ratio; the report and ``plot_wavefront`` show none there."""


def marechal_strehl(rms_waves: Float[ArrayLike, "*b"]) -> Float[Array, "*b"]:
    """Maréchal's approximation of the Strehl ratio, exp(−(2π σ)²), σ the RMS wavefront
    error in waves (piston and tilt removed). Good to a few per cent for σ <~ 0.1 wave.

    Example:
        >>> round(float(marechal_strehl(0.0745)), 3)   # the λ/14 "diffraction limit"
        0.803
    """
    checks.real_values(rms_waves, "rms_waves", "marechal_strehl", "waves")
    a = None if checks.is_traced(rms_waves) else np.asarray(rms_waves, float)
    if a is not None and np.any((a < 0) | np.isinf(a)):
        # A negative RMS squared like a positive one: −1 wave gave 7e-18, not an error, and
        # an infinite one a Strehl ratio of 0. NaN passes (a field without rays has no
        # wavefront, and no Strehl ratio).
        raise ValueError(f"marechal_strehl: rms_waves must be an RMS wavefront error, >= 0 "
                         f"waves, got {checks.fmt(a[(a < 0) | np.isinf(a)])} waves (finite, "
                         f"or NaN for a field without rays)")
    s = jnp.asarray(rms_waves)
    if a is None:  # traced (a user's jit): -0.1 gave 0.674, as 0.1 does
        s = eqx.error_if(s, jnp.any((s < 0) | jnp.isinf(s)),
                         "marechal_strehl: rms_waves must be an RMS wavefront error, >= 0 "
                         "waves (finite, or NaN for a field without rays)")
    return _strehl(s)


def _strehl(rms_waves):
    """exp(−(2π σ)²) unchecked: ``Wavefront.strehl``'s RMS is one (no error_if there)."""
    return jnp.exp(-((2.0 * jnp.pi * rms_waves) ** 2))


class Wavefront(eqx.Module):
    """A wavefront map of one field at one wavelength (see the module notes).

    Attributes:
        map: ``[g, g]`` OPD in waves, row i at Py = ``pupil[i]``, column j at Px =
            ``pupil[j]`` (Py grows with the row index); NaN outside the disc and where a
            ray is vignetted. Not piston-removed: the chief ray's OPD is 0.
        valid: ``[g, g]`` the points inside the disc whose rays reach the image surface.
        pupil: ``[g]`` the grid's normalised pupil coordinates, −1 … 1.
        rms, pv: waves, piston removed, tilt kept.
        rms_tilt_removed, pv_tilt_removed: waves, piston and tilt removed.
        tilt: ``[3]`` the removed plane a + b·Px + c·Py (waves).
        field: degrees (mm: an object-space telecentric lens's object height);
            wavelength: µm.
    """

    map: Float[Array, "g g"]
    valid: Bool[Array, "g g"]
    pupil: Float[Array, " g"]
    rms: Float[Array, ""]
    pv: Float[Array, ""]
    rms_tilt_removed: Float[Array, ""]
    pv_tilt_removed: Float[Array, ""]
    tilt: Float[Array, " 3"]
    field: Float[Array, ""] | Float[Array, " 2"]
    wavelength: Float[Array, ""]

    @property
    def strehl(self) -> Float[Array, ""]:
        """Maréchal's Strehl ratio from ``rms_tilt_removed``."""
        return _strehl(self.rms_tilt_removed)

    def zernike(self, *, terms: int = 37, indexing: str = "noll") -> ZernikeFit:
        """Zernike coefficients (waves) of the map, fitted over its valid points in (Px, Py)
        (``jaxlens.analysis.zernike``; "noll" is Zemax's Standard, "fringe" its Fringe)."""
        px, py = jnp.meshgrid(self.pupil, self.pupil, indexing="xy")
        return zernike_fit(px, py, self.map, terms=terms, indexing=indexing, mask=self.valid)


def _rms_pv(w, valid):
    cnt = jnp.maximum(jnp.sum(valid), 1)
    wz = jnp.where(valid, w, 0.0)
    mean = jnp.sum(wz) / cnt
    dev = jnp.where(valid, wz - mean, 0.0)
    ms = jnp.sum(dev * dev) / cnt
    rms = jnp.where(ms > 0, jnp.sqrt(jnp.where(ms > 0, ms, 1.0)), 0.0)
    pv = jnp.max(jnp.where(valid, wz, -jnp.inf)) - jnp.min(jnp.where(valid, wz, jnp.inf))
    return rms, jnp.where(jnp.any(valid), pv, jnp.nan)


def _statistics(w, valid, px, py):
    rms, pv = _rms_pv(w, valid)
    a = jnp.stack([jnp.ones_like(px), px, py], -1) * valid[:, None]
    wz = jnp.where(valid, w, 0.0)
    plane = jnp.linalg.solve(a.T @ a, a.T @ wz)
    rms_t, pv_t = _rms_pv(wz - jnp.stack([jnp.ones_like(px), px, py], -1) @ plane, valid)
    nan = jnp.where(jnp.any(valid), 0.0, jnp.nan)  # no light: statistics NaN
    return rms + nan, pv, rms_t + nan, pv_t + nan, plane


@checks.checked_core(aimed_jit)
def _wavefront_impl(lens, field, wl, depth, *, grid, reference, aim, newton_iters):
    dtype = lens.epd.dtype
    g = jnp.linspace(-1.0, 1.0, grid, dtype=dtype)
    px, py = jnp.meshgrid(g, g, indexing="xy")
    inside = px * px + py * py <= 1.0
    # Points outside the disc are traced at the centre (finite, no clipping) and masked.
    pts = jnp.stack([jnp.where(inside, px, 0.0), jnp.where(inside, py, 0.0)], -1)
    w, valid = _path_to_reference(lens, field, pts.reshape(-1, 2), wl, depth, reference, aim,
                                  newton_iters)
    valid = valid & inside.reshape(-1)
    w = jnp.where(valid, w, jnp.nan)
    rms, pv, rms_t, pv_t, plane = _statistics(w, valid, px.reshape(-1), py.reshape(-1))
    return Wavefront(w.reshape(grid, grid), valid.reshape(grid, grid), g, rms, pv, rms_t, pv_t,
                     plane, field, wl)


def wavefront(
    lens: Lens,
    field: Float[ArrayLike, ""] | Float[ArrayLike, " 2"],
    *,
    wavelength: Float[ArrayLike, ""] | None = None,
    depth=None,
    grid: int = DEFAULT_GRID,
    reference: str | None = None,
    aim: str | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Wavefront:
    """The wavefront map of one field and its RMS, peak-to-valley and Strehl ratio.

    Args:
        lens: the lens.
        field: field angle in degrees, θy or (θx, θy); an object height in mm, y or
            (x, y), for an object-space telecentric lens.
        wavelength: µm (default the primary wavelength); one value.
        depth: object distance in mm (inf for infinity); None (default) for the lens's own.
        grid: samples per side of the square pupil grid (>= 3; odd keeps the chief ray on
            the grid).
        reference, aim, newton_iters: as :func:`opd`.

    Returns:
        A :class:`Wavefront` (jittable and differentiable in the lens).

    Raises:
        NoLightError: (a ValueError) no ray reaches the image surface, with concrete inputs
            (under ``jax.jit`` the statistics are NaN); see ``jaxlens.imaging.light``.

    Example:
        >>> import jaxlens
        >>> from jaxlens.analysis.wavefront_error import wavefront
        >>> wf = wavefront(jaxlens.zoo.cooke_triplet(), 0.0, grid=33)
        >>> wf.map.shape, bool(0 < float(wf.rms) < 1)
        ((33, 33), True)
    """
    lens, dtype = _precise(lens)
    f, wl, depth, reference, aim = _common(lens, field, wavelength, depth, reference, aim,
                                      "wavefront")
    # Bounded as a PSF grid is: grid=100000 asked for 80 GB after the lens was traced.
    grid = checks.number(grid, "grid", "wavefront", lo=3, hi=checks.MAX_KERNEL_SIZE,
                         integer=True, unit="pupil samples per side")
    checks.newton_iters(newton_iters, "wavefront")
    wf = _wavefront_impl(lens, f, wl, depth, grid=int(grid), reference=reference, aim=aim,
                         newton_iters=int(newton_iters))
    refuse_dark(jnp.any(wf.valid), "wavefront", lens, f, "wavefront")  # not a NaN map
    return _cast(wf, dtype)


# --------------------------------------------------------------------------------------
# OPD fans
# --------------------------------------------------------------------------------------
class OPDFan(eqx.Module):
    """OPD (waves) of one field along the pupil's y axis (tangential: (0, Py)) and x axis
    (sagittal: (Px, 0)), each wavelength against its own chief ray and reference sphere."""

    field: Float[Array, ""] | Float[Array, " 2"]  # θy, or (θx, θy), degrees (mm: telecentric)
    wavelengths: Float[Array, " W"]
    pupil: Float[Array, " n"]
    tangential: Float[Array, "W n"]
    sagittal: Float[Array, "W n"]


@checks.checked_core(aimed_jit)
def _opd_fan_impl(lens, field, wls, depth, *, n, reference, aim, newton_iters):
    t = jnp.linspace(-1.0, 1.0, n, dtype=wls.dtype)
    zero = jnp.zeros_like(t)
    pts = jnp.concatenate([jnp.stack([zero, t], -1), jnp.stack([t, zero], -1)])

    def one(wl):
        w, _ = _path_to_reference(lens, field, pts, wl, depth, reference, aim, newton_iters)
        return w[:n], w[n:]

    tan, sag = jax.vmap(one)(wls)
    return OPDFan(field, wls, t, tan, sag)


def opd_fan(
    lens: Lens,
    field: Float[ArrayLike, ""] | Float[ArrayLike, " 2"],
    wavelengths: Float[ArrayLike, "*W"] | None = None,
    *,
    n: int = 21,
    depth=None,
    reference: str | None = None,
    aim: str | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> OPDFan:
    """Tangential and sagittal OPD fans of one field (waves at each wavelength), beside
    ``jaxlens.analysis.ray_fan``; NaN where a ray is vignetted.

    Args:
        lens: the lens.
        field: θy, or (θx, θy), in degrees; an object height in mm, y or (x, y), for an
            object-space telecentric lens.
        wavelengths: µm, one value or ``[W]``; default the lens's wavelengths.
        n: pupil points per fan, evenly spaced over −1 … 1.
        depth, reference, aim, newton_iters: as :func:`opd`.

    Returns:
        An :class:`OPDFan`.
    """
    lens, dtype = _precise(lens)
    if wavelengths is not None:
        checks.real_values(wavelengths, "wavelengths", "opd_fan", "µm")
    wls = lens.wavelengths if wavelengths is None else jnp.asarray(wavelengths, lens.epd.dtype)
    if wls.ndim > 1 or wls.size == 0:
        raise ValueError(f"opd_fan: wavelengths must be µm, one value or [W], got shape "
                         f"{wls.shape}")
    wls = wls.reshape(-1)
    if not checks.is_traced(wls):
        checks.values(np.asarray(wls, float), "wavelengths", "opd_fan", lo=0, lo_open=True,
                      unit="µm")
    f, _, depth, reference, aim = _common(lens, field, wls[0], depth, reference, aim, "opd_fan")
    wls = checks.wavelengths(lens, wls, "opd_fan", "wavelengths")
    checks.material_indices(lens, wls, "opd_fan", "wavelengths")
    n = checks.number(n, "n", "opd_fan", lo=2, hi=checks.MAX_SAMPLES, integer=True,
                      unit="pupil points")
    checks.newton_iters(newton_iters, "opd_fan")
    return _cast(_opd_fan_impl(lens, f, wls, depth, n=int(n), reference=reference, aim=aim,
                               newton_iters=int(newton_iters)), dtype)
