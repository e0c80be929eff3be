"""Point spread functions: geometric (ray splatting) and coherent (wave optics), PSF maps, MTF.

``jaxlens.psf(lens, field, ...)`` (re-exported from here) computes one PSF; ``psf_map`` and
``mtf`` are in this module; chief-ray aiming and the ideal image mapping are in ``aiming``.

Conventions:
    Lengths in mm, wavelengths in µm, field angles in degrees (θy, or (θx, θy)). An object
    at infinity is given by ``depth=inf``; a finite depth is the distance in mm from the
    object point to surface 1's vertex; ``depth=None`` (the default) is the lens's own
    object. The object point of a field at finite depth is placed so that its chief ray
    makes the field angle at the entrance pupil (as ``sampling.object_point``).

    A PSF is a ``[kernel_size, kernel_size]`` array of the energy per sensor pixel of side
    ``pixel_size`` (mm), normalised so that it sums to 1 when no energy falls outside the
    kernel (``truncated`` is the fraction that does). It is sampled in the orientation of
    ``jaxlens.imaging.render``'s output, which reads the sensor out rotated by 180° (as a camera
    does, so that a lens renders its scene upright): the pixel ``[i, j]`` is centred on the
    sensor point ``ref + (−(j − c)·p, (i − c)·p)`` with ``c = (kernel_size − 1)/2``, so
    convolving a rendered-orientation image with the kernel applies the PSF.

    ``center`` picks the reference point ``ref`` on the image surface: "chief" (the real
    chief ray through the centre of the stop, at the lens's primary wavelength, traced
    without clipping or obscurations, so a blocked chief ray still marks it), "centroid"
    (the energy centroid over all requested wavelengths) or "ideal" (the distortion-free
    image point ``K·tanθ``, ``K = image_scale(lens)``); the geometric model also takes
    "pupil" (where the ray through the centre of the paraxial entrance pupil lands, at the
    middle requested wavelength: traced with the beam, no aiming iterations; the real chief
    ray when the stop is the entrance pupil, as for a stop-first lens). One reference serves
    every wavelength, so lateral colour shows as a shift between the channels.

Models:
    geometric: rays from the object point fill the entrance pupil (the unit pupil, the
    system aperture of ``radiometry.in_pupil``, as optiland and Zemax sample it: a stop
    without a semi-diameter clips nothing), are traced to the image surface and splatted
    bilinearly onto the pixel grid. Bilinear splatting is piecewise linear in the ray
    positions, so the PSF is differentiable with respect to the lens.

    coherent: the field on the sensor is the ray-based Debye (angular-spectrum) integral.
    Each traced ray stands for a plane wave with its image-space direction d_j and the
    phase k·(OPL_j + n·d_j·(q − x_j)) at a sensor point q, where x_j is where the ray lands
    and OPL_j its optical path from the incoming wavefront (this is the angle eikonal, the
    optical path to the exit-pupil reference sphere). The amplitudes are
    sqrt(flux_j·ΔΩ_j), with ΔΩ_j the solid angle (in direction-cosine space) that the
    ray's pupil cell maps to, from forward-mode derivatives of the trace, so that energy is
    conserved (Parseval) and non-aplanatic pupils are apodised correctly. The sum is
    separable in x and y and evaluated as two matrix products. The pupil sampling must
    resolve the wavefront: the kernel must be smaller than the alias period λ/(n·ΔL) of
    the direction-cosine sampling, which ``max_truncation`` checks as well.

Vignetting factors:
    Both models launch their rays with ``sampling.field_rays``, so a field equal to one of
    the lens's fields takes that field's ``Lens.vignetting`` factors: its beam is the
    factors' image of the unit pupil (the overfilled ring beyond it launches no light), and
    ``normalize="pupil"`` counts the light of that vignetted pupil. Any other field (a
    ``psf_map`` grid point between the lens's fields) samples the whole pupil, clipped only
    by the apertures: pass ``dataclasses.replace(lens, vignetting=None)`` for PSFs free of
    the factors at every field. ``render`` drops them.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..optics import checks
from ..optics.lens import Lens, Sensor
from ..optics.materials import LAMBDA_C, LAMBDA_D, LAMBDA_F
from ..optics.paraxial import working_fnum
from ..optics.rays import Rays
from ..tracing.forward import DEFAULT_NEWTON_ITERS, forward_mode_jit, trace
from . import light, sampling, telecentric
from .aiming import chief_point, field_to_ideal, ideal_to_field
from .grid import kernel_side, pixel_pitch, pupil_cells, sensor_grid, splat
from .light import NoLightError
from .otf import check_cutoff, diffraction_mtf, mtf_directions
from .radiometry import in_pupil

__all__ = ["AbstractPSFModel", "CoherentPSF", "GeometricPSF", "RGB_WAVELENGTHS", "PSFResult",
           "PSFMap", "psf", "psf_info", "psf_rgb", "psf_map", "mtf"]

RGB_WAVELENGTHS = (LAMBDA_C, LAMBDA_D, LAMBDA_F)
"""Default (R, G, B) wavelengths in µm: the C, d and F lines."""

CENTERS = ("chief", "centroid", "ideal", "pupil")


def _launch(lens: Lens, field, depth, pupil, wavelength) -> Rays:
    """The beam's rays: those of pupil points outside the system aperture (the unit disc,
    ``radiometry.in_pupil``; an overfilled beam's ring) are launched invalid."""
    rays = sampling.field_rays(lens, field, pupil, wavelength, depth=depth)
    return eqx.tree_at(lambda r: r.valid, rays, rays.valid & in_pupil(pupil))


def _flux(rays: Rays, depth) -> Array:
    """Relative flux of each launched ray: 1 for a plane wave, cos⁴ for a point source."""
    if depth is None:
        return jnp.ones(rays.shape, rays.dtype)
    return rays.direction[..., 2] ** 4


def _reference(lens, field, depth, center, newton_iters, pos=None, w=None) -> Array:
    if not isinstance(center, str):
        return center  # a given point (x, y), mm
    if center == "chief":
        return chief_point(lens, field, depth, newton_iters)
    if center == "ideal":
        return field_to_ideal(lens, field)
    # centroid over all wavelengths; pos [W, M, 2], w [W, M]
    tot = jnp.maximum(jnp.sum(w), jnp.finfo(w.dtype).tiny)
    return jnp.sum(w[..., None] * pos, axis=(0, 1)) / tot


# --------------------------------------------------------------------------------------
# Geometric PSF
# --------------------------------------------------------------------------------------
def _trace_beam(lens, field, depth, wl, pupil, mask, newton_iters):
    rays = _launch(lens, field, depth, pupil, wl)
    out = trace(lens, rays, newton_iters=newton_iters, uniform=True)
    w = jnp.where(out.valid & mask, _flux(rays, depth), 0.0)
    return rays, out, w


# The launched grid's radius over the entrance pupil's: the beam is the unit pupil
# (``radiometry.in_pupil``), so rays beyond it carry no light; 1.25, the default until
# 2026-12-03, spent 36 % of the rays there.
DEFAULT_OVERFILL = 1.0


class AbstractPSFModel(eqx.Module):
    """How a PSF is computed: a small, final strategy object passed as ``model=``.

    ``pupil`` is the number of rays per side of the square pupil grid (about 0.62·pupil²
    rays are launched after the disc cut) and ``overfill`` the radius of the launched grid
    over the paraxial entrance-pupil radius; its rays beyond the unit pupil carry no light
    (``radiometry.in_pupil``), so overfill > 1 only spends rays. Both are static.
    """

    pupil: eqx.AbstractVar[int]
    overfill: eqx.AbstractVar[float]

    def __check_init__(self):
        # At construction too: GeometricPSF(pupil=0) was built without a word (psf refused it).
        if not checks.is_traced(self.overfill):
            self.check(type(self).__name__)

    def check(self, caller: str) -> None:
        """Refuse a pupil or overfill outside their range, naming the caller."""
        side = math.isqrt(checks.MAX_PUPIL_POINTS)  # pupil² rays are traced at once
        if not isinstance(self.pupil, int) or not 2 <= self.pupil <= side:
            raise ValueError(f"{caller}: pupil (rays per side) must be an int >= 2, got "
                             f"{self.pupil!r} (at most {side}: pupil² rays are traced at once)")
        checks.number(self.overfill, "overfill", caller, lo=0, lo_open=True,
                      unit="(beam radius over the entrance-pupil radius)")
        largest = self.largest_overfill()
        if self.overfill > largest:
            raise ValueError(
                f"{caller}: overfill {self.overfill!r} spreads the {self.pupil}² launched rays "
                f"so wide that none may fall inside the entrance pupil; use an overfill in "
                f"(0, {largest:.4g}] (beam radius over the entrance-pupil radius, "
                f"{DEFAULT_OVERFILL} by default) or more rays per side")

    def largest_overfill(self) -> float:
        """The largest overfill that keeps a ray inside the entrance pupil (radius 1): the
        cell-centred square grid's nearest point to the centre lies within half a cell
        diagonal, overfill·√2/pupil, of it."""
        return self.pupil / math.sqrt(2.0)

    def kernels(self, lens, field, depth, wls, *, kernel_size, pixel_size, center, key,
                newton_iters):
        """PSFs ``[W, k, k]`` of one field at wavelengths ``wls`` (the beam: the unit
        pupil, ``radiometry.in_pupil``).

        Returns (kernels, truncated fraction [W] (NaN where no ray got through), reference
        point [2], Strehl ratio [W] (NaN for ray models), aliased [W]).
        """
        raise NotImplementedError


def _model(model, caller: str) -> AbstractPSFModel:
    if isinstance(model, str):
        raise TypeError(f"{caller}: model is a PSF model object, not a string: use "
                        f"GeometricPSF(pupil=..., overfill=...) or CoherentPSF(...), got "
                        f"{model!r}")
    if not isinstance(model, AbstractPSFModel):
        raise TypeError(f"{caller}: model must be GeometricPSF(...) or CoherentPSF(...), got "
                        f"{type(model).__name__}")
    model.check(caller)
    return model


class GeometricPSF(AbstractPSFModel):
    """Ray splatting: rays fill the overfilled pupil, are traced and splatted bilinearly
    (``order=1``, a one-pixel tent; ``order=2``, a smoother quadratic B-spline).

    ``grid`` places the rays: "square" (a cell-centred square grid cut to the disc of
    ``overfill``) or "polar" (``pupil²`` equal-area polar cells strictly inside that disc,
    ``sampling.pupil_polar``; with ``overfill < 1`` no ray of a stop-first lens fails at the
    stop). ``normalize`` sets what a kernel's sum counts: "transmitted" (the default) divides
    by the flux of the rays that reach the image surface, so the kernel sums to 1 less the
    light outside it; "pupil" divides by the flux that enters the paraxial entrance pupil
    (launched rays with pupil radius <= 1, passed or not), so light lost to vignetting
    counts as lost too and the kernel's sum is the fraction of that light on the kernel.
    """

    pupil: int = eqx.field(default=64, converter=checks.static_int)
    overfill: float = DEFAULT_OVERFILL
    order: int = eqx.field(default=1, converter=checks.static_int)
    grid: str = "square"
    normalize: str = "transmitted"

    def largest_overfill(self) -> float:
        # The polar grid's innermost ring of cells ends at radius overfill/√pupil.
        return math.sqrt(self.pupil) if self.grid == "polar" else super().largest_overfill()

    def check(self, caller: str) -> None:
        super().check(caller)
        if self.order not in (1, 2) or isinstance(self.order, bool):
            raise ValueError(f"{caller}: order must be 1 (tent) or 2 (quadratic B-spline), "
                             f"got {self.order!r}")
        if self.grid not in ("square", "polar"):
            raise ValueError(f"{caller}: grid must be 'square' or 'polar', got {self.grid!r}")
        if self.normalize not in ("transmitted", "pupil"):
            raise ValueError(f"{caller}: normalize must be 'transmitted' or 'pupil', got "
                             f"{self.normalize!r}")

    def kernels(self, lens, field, depth, wls, *, kernel_size, pixel_size, center, key,
                newton_iters):
        return _geometric(lens, field, depth, wls, kernel_size=kernel_size,
                          pixel_size=pixel_size, center=center, pupil=self.pupil,
                          overfill=self.overfill, key=key, newton_iters=newton_iters,
                          order=self.order, grid=self.grid, normalize=self.normalize)


class CoherentPSF(AbstractPSFModel):
    """Wave optics: the ray-based Debye integral over the traced optical paths (see the
    module notes); ``pupil`` must resolve the wavefront over the kernel."""

    pupil: int = eqx.field(default=64, converter=checks.static_int)
    overfill: float = DEFAULT_OVERFILL

    def kernels(self, lens, field, depth, wls, *, kernel_size, pixel_size, center, key,
                newton_iters):
        del key  # the coherent sum uses the regular grid
        return _coherent(lens, field, depth, wls, kernel_size=kernel_size,
                         pixel_size=pixel_size, center=center, pupil=self.pupil,
                         overfill=self.overfill, newton_iters=newton_iters)


DEFAULT_MODEL = GeometricPSF()
"""The default PSF model: ray splatting, 64 rays per pupil side, launched over the unit pupil."""


def _geometric(lens, field, depth, wls, *, kernel_size, pixel_size, center, pupil, overfill,
               key, newton_iters, order, grid="square", normalize="transmitted"):
    dtype = lens.epd.dtype
    if grid == "polar":
        pts = sampling.pupil_polar(pupil, key, dtype) * overfill
        mask = jnp.ones(pts.shape[:1], bool)
    else:
        pts, mask, _ = pupil_cells(pupil, overfill, dtype, key)
    if center == "pupil":  # the pupil-centre ray rides along with no weight
        pts = jnp.concatenate([jnp.zeros((1, 2), dtype), pts])
        mask = jnp.concatenate([jnp.zeros((1,), bool), mask])
    in_pupil = mask & (jnp.sum(pts * pts, -1) <= 1.0)

    def one(wl):
        rays, out, w = _trace_beam(lens, field, depth, wl, pts, mask, newton_iters)
        entering = jnp.sum(jnp.where(in_pupil, _flux(rays, depth), 0.0))
        return out.origin[..., :2], w, entering

    pos, w, entering = jax.vmap(one)(wls)  # [W, M, 2], [W, M], [W]
    if center == "pupil":
        ref = pos[wls.shape[0] // 2, 0]
    else:
        ref = _reference(lens, field, depth, center, newton_iters, pos, w)
    total = entering if normalize == "pupil" else jnp.sum(w, -1)
    total = jnp.maximum(total, jnp.finfo(dtype).tiny)  # [W]
    kern = jax.vmap(lambda p, ww: splat(p - ref, ww, kernel_size, pixel_size, order))(pos, w)
    kern = kern / total[:, None, None]
    nan = jnp.full(wls.shape, jnp.nan, dtype)
    return kern, _truncation(kern, w), ref, nan, jnp.zeros(wls.shape, bool)


def _truncation(kern, flux):
    """Energy fraction outside the kernel, NaN where no ray got through (nothing to lose)."""
    return jnp.where(jnp.sum(flux, -1) > 0, 1.0 - jnp.sum(kern, (-1, -2)), jnp.nan)


# --------------------------------------------------------------------------------------
# Coherent PSF
# --------------------------------------------------------------------------------------
def _coherent(lens, field, depth, wls, *, kernel_size, pixel_size, center, pupil, overfill,
              newton_iters):
    if center == "pupil":
        raise ValueError("psf: center='pupil' is for the geometric model; use 'chief'")
    dtype = lens.epd.dtype
    pts, mask, cell = pupil_cells(pupil, overfill, dtype, None)
    k = kernel_size
    c = 0.5 * (k - 1)
    idx = jnp.arange(k, dtype=dtype)
    dx_cols = -(idx - c) * pixel_size  # sensor x offset of each column
    dy_rows = (idx - c) * pixel_size  # sensor y offset of each row

    def beam(uv, wl):
        rays = _launch(lens, field, depth, uv, wl)
        out = trace(lens, rays, newton_iters=newton_iters, uniform=True)
        return out.direction[..., :2], (rays, out)

    def one(wl):
        ex = jnp.zeros_like(pts).at[:, 0].set(1.0)
        ey = jnp.zeros_like(pts).at[:, 1].set(1.0)
        lm, dlm_du, (rays, out) = jax.jvp(lambda uv: beam(uv, wl), (pts,), (ex,),
                                          has_aux=True)
        _, dlm_dv = jax.jvp(lambda uv: beam(uv, wl)[0], (pts,), (ey,))
        det = jnp.abs(dlm_du[:, 0] * dlm_dv[:, 1] - dlm_du[:, 1] * dlm_dv[:, 0])
        d_omega = det * cell * cell
        flux = jnp.where(out.valid & mask, _flux(rays, depth), 0.0)
        # Optical path from the incoming wavefront: a plane wave adds n0·d·origin.
        opl = out.opl
        if depth is None:
            n0 = lens.object_material.index(wl)
            opl = opl + n0 * jnp.sum(rays.direction * rays.origin, -1)
        n_img = lens.materials[-1].index(wl)
        return out.origin[..., :2], lm, opl, flux, d_omega, n_img

    pos, lm, opl, flux, d_omega, n_img = jax.vmap(one)(wls)
    ref = _reference(lens, field, depth, center, newton_iters, pos, flux)

    def field_at(pos, lm, opl, flux, d_omega, n_img, wl):
        lam = wl * 1e-3  # mm
        kw = 2.0 * jnp.pi / lam
        amp = jnp.sqrt(jnp.where(flux > 0, flux * d_omega, 0.0))
        tot = jnp.maximum(jnp.sum(flux), jnp.finfo(dtype).tiny)
        opl0 = jax.lax.stop_gradient(jnp.sum(flux * opl) / tot)
        rel = pos - ref
        psi = kw * ((opl - opl0) - n_img * jnp.sum(lm * rel, -1))
        coef = amp * jnp.exp(1j * psi)
        ex = jnp.exp(1j * kw * n_img * lm[:, 0:1] * dx_cols[None, :])  # [M, k]
        ey = jnp.exp(1j * kw * n_img * lm[:, 1:2] * dy_rows[None, :])  # [M, k]
        u = (ey * coef[:, None]).T @ ex  # [rows, cols]
        scale = (pixel_size * n_img / lam) ** 2 / tot
        inten = (u.real**2 + u.imag**2) * scale
        ideal_peak = jnp.sum(amp) ** 2 * scale
        strehl = jnp.max(inten) / jnp.maximum(ideal_peak, jnp.finfo(dtype).tiny)
        # Alias period of the plane-wave sum along each axis, against the kernel width.
        dl = jnp.sqrt(jnp.max(jnp.where(flux > 0, d_omega, 0.0)))
        aliased = k * pixel_size * n_img * dl >= lam
        return inten, strehl, aliased

    kern, strehl, aliased = jax.vmap(field_at)(pos, lm, opl, flux, d_omega, n_img, wls)
    return kern, _truncation(kern, flux), ref, strehl, aliased


# --------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------
class PSFResult(eqx.Module):
    """A PSF with its diagnostics.

    Attributes:
        psf: ``[*W, k, k]`` energy per pixel (leading axis when several wavelengths).
        truncated: ``[*W]`` fraction of the energy outside the kernel; NaN where no ray
            reaches the image (the PSF is then all zeros).
        center: ``[2]`` reference point (x, y) on the image surface, mm.
        strehl: ``[*W]`` peak of the coherent PSF on the kernel grid over the peak of the
            unaberrated PSF with the same pupil (NaN for the geometric model).
        aliased: ``[*W]`` True where the kernel is wider than the alias period of the
            coherent pupil sampling (always False for the geometric model).
    """

    psf: Float[Array, "*w k k"]
    truncated: Float[Array, "*w"]
    center: Float[Array, " 2"]
    strehl: Float[Array, "*w"]
    aliased: Array


@checks.checked_core(forward_mode_jit)
def _psf_impl(lens, field, depth, wls, pixel_size, key, *, kernel_size, model, center,
              newton_iters):
    dtype = jnp.result_type(pixel_size)
    lens = lens.astype(dtype)
    return model.kernels(lens, field, depth, wls, kernel_size=kernel_size,
                         pixel_size=pixel_size, center=center, key=key,
                         newton_iters=newton_iters)


def _prepare(lens, field, depth, wavelength, kernel_size, pixel_size, model, center, caller,
             newton_iters=DEFAULT_NEWTON_ITERS, given=True):
    checks.focal_image(lens, caller)
    _model(model, caller)
    checks.number(newton_iters, "newton_iters", caller, lo=0, integer=True, unit="iterations")
    checks.newton_iters(newton_iters, caller)
    if center not in CENTERS:
        raise ValueError(f"{caller}: center must be one of {CENTERS}, got {center!r}")
    kernel_size = kernel_side(kernel_size, caller, odd=caller != "mtf")  # static
    given = given and pixel_size is not None  # a Sensor's own pitch: any mm (Sensor checks it)
    if pixel_size is None:
        if lens.sensor is None:
            raise ValueError(f"{caller}: give pixel_size (mm); the lens has no sensor")
        pixel_size = lens.sensor.pixel_size
    dtype = jnp.result_type(float)
    # Before jnp.asarray (it traces constants under jit); a traced one gets an error_if.
    pixel_size = jnp.asarray(pixel_pitch(pixel_size, caller, bounded=given), dtype)
    wl = lens.primary_wavelength if wavelength is None else wavelength
    checks.real_values(wl, "wavelength", caller, "µm")  # jnp.asarray reads "0.55" as 0.55
    wl = checks.wavelengths(lens, jnp.asarray(wl, dtype), caller, "wavelength")
    checks.material_indices(lens, wl, caller)
    checks.primary_wavelength(lens, caller, "the chief ray's and paraxial pupils'")
    field = telecentric.lens_field(lens, field, caller)  # heights (mm) or angles (deg)
    if wl.ndim > 1 or wl.size == 0:
        raise ValueError(f"{caller}: wavelength must be a scalar or 1-D (µm) with at least one "
                         f"value, got shape {wl.shape}")
    field = jnp.asarray(field, dtype)
    if field.ndim > 1 or (field.ndim == 1 and field.shape[0] != 2):
        raise ValueError(f"{caller}: field must be θy or (θx, θy) in degrees, got {field.shape}")
    return field, sampling.lens_depth(lens, depth, caller), wl, pixel_size, kernel_size


def psf_info(
    lens: Lens,
    field: Float[ArrayLike, ""] | Float[ArrayLike, " 2"],
    *,
    depth=None,
    wavelength: Float[ArrayLike, "*w"] | None = None,
    kernel_size: int = 31,
    pixel_size=None,
    model: AbstractPSFModel = DEFAULT_MODEL,
    center: str = "chief",
    key=None,
    max_truncation: float | None = None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> PSFResult:
    """A PSF with its diagnostics (truncation, reference point, Strehl ratio).

    Args: as :func:`psf`.

    Returns: a :class:`PSFResult`.
    """
    field, depth, wl, pixel_size, kernel_size = _prepare(
        lens, field, depth, wavelength, kernel_size, pixel_size, model, center, "psf",
        newton_iters)
    checks.prng_key(key, "psf", optional=True)
    if max_truncation is not None:
        # A fraction above 1 never triggers: the check was off without a word.
        checks.number(max_truncation, "max_truncation", "psf", lo=0, hi=1,
                      unit="(fraction of the PSF energy; None to skip the check)")
    wls = jnp.atleast_1d(wl)
    kern, trunc, ref, strehl, aliased = _psf_impl(
        lens, field, depth, wls, pixel_size, key, kernel_size=kernel_size, model=model,
        center=center, newton_iters=newton_iters)
    if max_truncation is not None:
        dark = (light.message("psf", lens, field, "PSF") if not checks.is_traced(field) else
                "psf: no ray of the beam reaches the image surface (the field is vignetted or "
                "beyond the lens's coverage), so there is no PSF")
        kern = _refuse_bad_kernels(kern, trunc, aliased, max_truncation, kernel_size,
                                   pixel_size, wls, dark)
    if wl.ndim == 0:
        kern, trunc, strehl, aliased = kern[0], trunc[0], strehl[0], aliased[0]
    return PSFResult(kern, trunc, ref, strehl, aliased)


def _refuse_bad_kernels(kern, trunc, aliased, max_truncation, kernel_size, pixel_size, wls,
                        dark):
    """Refuse a PSF that is not one (no light: ``dark``, the message; energy lost outside the
    kernel or over-counted, an aliased coherent kernel): a ValueError (``NoLightError`` for
    no light) at the worst wavelength, or an error_if."""
    conditions = [
        (jnp.isnan(trunc), dark, None),
        (trunc < -max_truncation, f"psf: the kernel holds more than 1 + {max_truncation:g} of "
         f"the beam's energy: the coherent sum is too coarse for this pixel pitch; raise pupil "
         f"(rays per side)", lambda t: f"it holds {1 - t:.3g}"),
        (trunc > max_truncation, f"psf: more than {max_truncation:g} of the PSF energy falls "
         f"outside the {kernel_size}x{kernel_size} kernel; enlarge kernel_size or pixel_size",
         lambda t: f"{t:.3g} falls outside; the kernel spans "
                   f"{kernel_size * float(pixel_size) * 1e3:.4g} µm"),
        (aliased, "psf: the coherent kernel is wider than the alias period of the pupil "
         "sampling; raise pupil (rays per side) or shrink the kernel", None),
    ]
    if checks.is_traced((trunc, aliased, pixel_size)):
        for bad, message, _ in conditions:
            kern = eqx.error_if(kern, jnp.any(bad), message)
        return kern
    t = np.asarray(trunc, np.float64)
    for k, (bad, message, detail) in enumerate(conditions):
        bad = np.asarray(bad)
        if np.any(bad):
            i = int(np.argmax(np.where(bad, np.abs(np.nan_to_num(t, nan=np.inf)), -1.0)))
            where = f"at {float(np.asarray(wls)[i]):g} µm"
            cls = NoLightError if k == 0 else ValueError  # k = 0: no light
            raise cls(f"{message} ({detail(t[i]) + ' ' if detail else ''}{where})")
    return kern


def psf(
    lens: Lens,
    field: Float[ArrayLike, ""] | Float[ArrayLike, " 2"],
    *,
    depth=None,
    wavelength: Float[ArrayLike, "*w"] | None = None,
    kernel_size: int = 31,
    pixel_size=None,
    model: AbstractPSFModel = DEFAULT_MODEL,
    center: str = "chief",
    key=None,
    max_truncation: float | None = 0.05,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> Float[Array, "*w k k"]:
    """The PSF of a point at ``field`` and ``depth`` on the sensor, as energy per pixel.

    Args:
        lens: the lens.
        field: field angle in degrees, θy or (θx, θy); an object height in mm, y or
            (x, y), for an object-space telecentric lens.
        depth: object distance in mm in front of surface 1; ``inf`` for an object at
            infinity; None (default) for the lens's own object (``lens.object_distance``).
        wavelength: µm, a scalar or ``[W]`` (an RGB PSF is ``RGB_WAVELENGTHS``); default the
            primary wavelength.
        kernel_size: kernel side in pixels (odd keeps the reference on a pixel centre).
        pixel_size: pixel pitch in mm; default the lens's sensor pitch.
        model: ``GeometricPSF(pupil, overfill, order)`` (ray splatting, the default) or
            ``CoherentPSF(pupil, overfill)`` (wave optics).
        center: "chief", "centroid" or "ideal" (see the module docstring).
        key: PRNG key to jitter the geometric pupil grid (stratified sampling); None for the
            regular grid.
        max_truncation: raise (``eqx.error_if``) when more than this fraction of the energy
            falls outside the kernel, when a coherent kernel aliases, or when no ray reaches
            the image; None skips all three checks (``psf_info`` then reports them: a NaN
            ``truncated`` for no light, ``aliased``).
        newton_iters: Newton iterations for aspheric surfaces.

    Returns:
        ``[k, k]``, or ``[W, k, k]`` for several wavelengths; see ``psf_info`` for the
        diagnostics.

    Example:
        >>> import jax, jax.numpy as jnp, jaxlens
        >>> lens = jaxlens.zoo.cooke_triplet()
        >>> k = jaxlens.psf(lens, 0.0, wavelength=0.5876, kernel_size=15, pixel_size=0.005)
        >>> k.shape, bool(abs(k.sum() - 1) < 1e-3)
        ((15, 15), True)
    """
    return psf_info(
        lens, field, depth=depth, wavelength=wavelength, kernel_size=kernel_size,
        pixel_size=pixel_size, model=model, center=center, key=key,
        max_truncation=max_truncation, newton_iters=newton_iters,
    ).psf


def psf_rgb(lens: Lens, field, *, wavelengths=RGB_WAVELENGTHS, **kwargs) -> Float[Array, "3 k k"]:
    """RGB PSF: ``psf`` at three wavelengths (default the C, d, F lines), ``[3, k, k]``."""
    checks.real_values(wavelengths, "wavelengths", "psf_rgb", "µm")  # two gave a [2, k, k]
    if np.shape(wavelengths) != (3,):
        raise ValueError(f"psf_rgb: wavelengths must be 3 values (R, G, B) in µm, got shape "
                         f"{np.shape(wavelengths)}; use psf(wavelength=...) for other counts")
    return psf(lens, field, wavelength=jnp.asarray(wavelengths), **kwargs)


class PSFMap(eqx.Module):
    """PSFs over a grid of sensor positions.

    Attributes:
        psf: ``[gr, gc, *W, k, k]``.
        truncated: ``[gr, gc, *W]``.
        sensor_xy: ``[gr, gc, 2]`` distortion-free image points (mm) of the grid fields.
        field: ``[gr, gc, 2]`` field angles (θx, θy), degrees.
        center: ``[gr, gc, 2]`` reference points of the PSFs (mm).
    """

    psf: Array
    truncated: Array
    sensor_xy: Array
    field: Array
    center: Array


# _psf_impl over fields [n, 2] in one compiled body: vmapped eagerly, the core saw batch
# tracers, kept its input checks and so never entered the compile cache.
@checks.checked_core(forward_mode_jit)
def _psf_grid(lens, fields, depth, wls, pixel_size, **kw):
    return jax.vmap(lambda f: _psf_impl(lens, f, depth, wls, pixel_size, None, **kw))(fields)


def psf_map(
    lens: Lens,
    *,
    grid: tuple[int, int] = (5, 5),
    depth=None,
    wavelength=None,
    kernel_size: int = 31,
    pixel_size=None,
    model: AbstractPSFModel = DEFAULT_MODEL,
    center: str = "chief",
    sensor=None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
) -> PSFMap:
    """PSFs at a ``grid = (rows, cols)`` of fields whose ideal images span the sensor.

    Grid row 0 / column 0 is the top-left corner of the rendered image (``sensor_grid``).

    Args:
        lens: the lens.
        grid: (rows, cols) of PSFs.
        sensor: a ``Sensor`` (default ``lens.sensor``) that sets the extent and, unless
            ``pixel_size`` is given, the pitch.
        others: as :func:`psf`.

    Returns:
        A :class:`PSFMap`.
    """
    sensor = lens.sensor if sensor is None else sensor
    if sensor is None:
        raise ValueError("psf_map: the lens has no sensor; pass sensor=Sensor(...)")
    if not isinstance(sensor, Sensor):
        raise TypeError(f"psf_map: sensor must be a jaxlens.Sensor, got "
                        f"{type(sensor).__name__} {sensor!r}")
    given = pixel_size is not None  # else the sensor's own pitch (any mm)
    pixel_size = sensor.pixel_size if pixel_size is None else pixel_size
    grid = checks.grid(grid, "psf_map", "grid", "PSFs")
    _, depth, wl, pixel_size, kernel_size = _prepare(
        lens, 0.0, depth, wavelength, kernel_size, pixel_size, model, center, "psf_map",
        newton_iters, given)
    xy = sensor_grid(sensor.resolution, sensor.pixel_size, grid)
    fields = ideal_to_field(lens, xy)
    wls = jnp.atleast_1d(wl)
    kern, trunc, ref, _, _ = _psf_grid(lens, fields.reshape(-1, 2), depth, wls, pixel_size,
                                       kernel_size=kernel_size, model=model, center=center,
                                       newton_iters=newton_iters)
    g = tuple(grid)
    # A field without light has an all-zero kernel (truncated NaN): refuse it, as psf does.
    dark = jnp.any(jnp.isnan(trunc), axis=-1)
    msg = ("psf_map: no ray of the beam reaches the image surface at {}, so there is no PSF "
           "there (the field is vignetted or beyond the lens's coverage); use a smaller sensor")
    if checks.is_traced(dark):
        kern = eqx.error_if(kern, jnp.any(dark), msg.format("a grid point"))
    elif np.any(dark):
        r, col = divmod(int(np.argmax(np.asarray(dark))), g[1])
        fx, fy = np.asarray(fields)[r, col]
        x, y = np.asarray(xy)[r, col]
        raise ValueError(msg.format(
            f"grid point (row {r}, col {col}) (first of {int(np.sum(dark))}), field (θx, θy) = "
            f"({fx:.4g}, {fy:.4g}) deg, sensor point ({x:.4g}, {y:.4g}) mm"))
    if wl.ndim == 0:
        kern, trunc = kern[:, 0], trunc[:, 0]
    return PSFMap(kern.reshape(g + kern.shape[1:]), trunc.reshape(g + trunc.shape[1:]), xy,
                  fields, ref.reshape(g + (2,)))


# --------------------------------------------------------------------------------------
# MTF
# --------------------------------------------------------------------------------------
@checks.checked_core(forward_mode_jit)
def _mtf_impl(lens, field, depth, wls, freqs, pixel_size, *, model, kernel_size, diffraction,
              newton_iters):
    dtype = freqs.dtype
    lens = lens.astype(dtype)
    e_t, e_s = mtf_directions(field, heights=lens.telecentric_object)
    fnum = working_fnum(lens, depth)
    nw = wls.shape[0]
    if isinstance(model, GeometricPSF):
        pts, mask, _ = pupil_cells(model.pupil, model.overfill, dtype)

        def otf(wl):
            _, out, w = _trace_beam(lens, field, depth, wl, pts, mask, newton_iters)
            return out.origin[..., :2], w

        pos, w = jax.vmap(otf)(wls)  # [W, M, 2]
        tot = jnp.maximum(jnp.sum(w, -1, keepdims=True), jnp.finfo(dtype).tiny)
        ref = jnp.sum(w[..., None] * pos, (0, 1)) / jnp.maximum(jnp.sum(w), 1e-30)
        rel = pos - ref
        wn = w / tot

        def along(e):
            proj = rel @ e  # [W, M]
            ph = -2 * jnp.pi * freqs[None, :, None] * proj[:, None, :]  # [W, F, M]
            o = jnp.sum(wn[:, None, :] * jnp.exp(1j * ph), -1)  # [W, F]
            if diffraction:
                o = o * jax.vmap(lambda wl: diffraction_mtf(freqs, wl * 1e-3, fnum))(wls)
            return jnp.abs(jnp.sum(o, 0) / nw)

        return along(e_t), along(e_s), jnp.sum(w, -1) > 0
    kern, trunc, _, _, _ = model.kernels(lens, field, depth, wls, kernel_size=kernel_size,
                                     pixel_size=pixel_size, center="centroid", key=None,
                                     newton_iters=newton_iters)
    k = kernel_size
    c = 0.5 * (k - 1)
    idx = jnp.arange(k, dtype=dtype)
    qx = jnp.broadcast_to(-(idx - c)[None, :] * pixel_size, (k, k))
    qy = jnp.broadcast_to((idx - c)[:, None] * pixel_size, (k, k))
    q = jnp.stack([qx, qy], -1).reshape(-1, 2)
    wgt = kern.reshape(nw, -1)
    wgt = wgt / jnp.maximum(jnp.sum(wgt, -1, keepdims=True), 1e-30)

    def along(e):
        ph = -2 * jnp.pi * freqs[:, None] * (q @ e)[None, :]  # [F, P]
        o = wgt @ jnp.exp(1j * ph).T  # [W, F]
        return jnp.abs(jnp.sum(o, 0) / nw)

    return along(e_t), along(e_s), ~jnp.isnan(trunc)


def mtf(
    lens: Lens,
    field,
    *,
    wavelengths=None,
    depth=None,
    frequencies=None,
    model: AbstractPSFModel = DEFAULT_MODEL,
    diffraction: bool = True,
    kernel_size: int = 64,
    pixel_size=None,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
):
    """Tangential and sagittal MTF of one field, polychromatic with equal weights.

    The optical transfer function is the Fourier transform of the PSF. The geometric model
    evaluates it exactly from the traced ray positions (the Fourier transform of the ray
    density, no pixel grid), optionally times the diffraction-limited MTF of a circular
    pupil at the paraxial working F-number of the object at ``depth`` (``diffraction=True``,
    the usual geometric-MTF
    approximation). The coherent model transforms the wave-optics intensity PSF computed
    on a ``kernel_size`` grid of ``pixel_size`` (default λ_min·F#/4). Tangential means
    along the image-plane radius of the field point (y on axis); sagittal is perpendicular.

    Args:
        lens: the lens.
        field: field angle in degrees, θy or (θx, θy); an object height in mm, y or
            (x, y), for an object-space telecentric lens (tangential along the height).
        wavelengths: µm, ``[W]``; default ``lens.wavelengths``.
        depth: object distance in mm (``inf`` for infinity); None (default) for the
            lens's own object.
        frequencies: spatial frequencies in cycles/mm; default 33 points from 0 to the
            sensor's Nyquist frequency, or to the diffraction cut-off 1/(λ·F#) without a
            sensor.
        model: ``GeometricPSF(...)`` (exact OTF of the ray positions) or
            ``CoherentPSF(...)``, as in :func:`psf`.
        newton_iters: Newton iterations for aspheric surfaces.
        diffraction: scale the geometric MTF by the diffraction limit.
        kernel_size, pixel_size: PSF grid of the coherent model.

    Returns:
        ``(frequencies [F] cycles/mm, mtf_tangential [F], mtf_sagittal [F])``.
    """
    _model(model, "mtf")
    if not isinstance(diffraction, (bool, np.bool_)):  # a string such as "no" is truthy
        raise ValueError(f"mtf: diffraction must be True or False, got {diffraction!r}")
    dtype = jnp.result_type(float)
    for arg, v in (("wavelengths", wavelengths), ("pixel_size", pixel_size)):
        if v is not None:  # before jnp.asarray, which reads "0.55" as 0.55
            checks.real_values(v, arg, "mtf", "µm" if arg == "wavelengths" else "mm")
    wls = jnp.atleast_1d(jnp.asarray(lens.wavelengths if wavelengths is None else wavelengths,
                                     dtype))
    if wls.ndim != 1 or wls.size == 0:
        raise ValueError(f"mtf: wavelengths must be [W] µm with W >= 1, got shape {wls.shape}")
    wls = checks.wavelengths(lens, wls, "mtf", "wavelengths")
    # The working F-number of the object traced (``depth``), not of the lens's own object.
    fnum = working_fnum(lens.astype(dtype), sampling.lens_depth(lens, depth, "mtf"))
    if diffraction or pixel_size is None or (frequencies is None and lens.sensor is None):
        check_cutoff(fnum, "mtf")  # a cut-off 1/(λN) of 0 (every MTF 0), a pixel of inf
    lam_min = jnp.min(wls) * 1e-3
    if frequencies is None:
        if lens.sensor is not None:
            top = 0.5 / lens.sensor.pixel_size
        else:
            top = 1.0 / (lam_min * fnum)
        frequencies = jnp.linspace(0.0, 1.0, 33, dtype=dtype) * top
    if not checks.is_traced(frequencies):  # before jnp.asarray: it traces constants under jit
        checks.real_values(frequencies, "frequencies", "mtf", "cycles/mm")
        checks.finite_array(np.asarray(frequencies), "frequencies", "mtf", "cycles/mm")
        checks.values(np.asarray(frequencies, float), "frequencies", "mtf", lo=0,
                      unit="cycles/mm")
    freqs = jnp.atleast_1d(jnp.asarray(frequencies, dtype))
    if freqs.ndim != 1 or freqs.size == 0:
        raise ValueError(f"mtf: frequencies must be [F] cycles/mm with F >= 1, got shape "
                         f"{freqs.shape}")
    pix = lam_min * fnum / 4.0 if pixel_size is None else jnp.asarray(pixel_size, dtype)
    field, depth, _, pix, kernel_size = _prepare(lens, field, depth, None, kernel_size, pix,
                                                 model, "centroid", "mtf", newton_iters)
    t, s, lit = _mtf_impl(lens, field, depth, wls, freqs, pix, model=model,
                          kernel_size=kernel_size,
                          diffraction=bool(diffraction), newton_iters=newton_iters)
    # A wavelength without light had an MTF of 0 at every frequency (0 at 0 cycles/mm, and
    # a dark wavelength pulled the polychromatic MTF down): refuse it, as psf does.
    msg = ("mtf: no ray of the beam reaches the image surface (the field is vignetted or "
           "beyond the lens's coverage), so there is no MTF")
    if checks.is_traced(lit):
        t = eqx.error_if(t, ~jnp.all(lit), msg)
    elif not np.all(np.asarray(lit)):
        dark = np.asarray(wls)[~np.asarray(lit)]
        unit = "mm" if lens.telecentric_object else "deg"  # an object height, or an angle
        raise NoLightError(f"{msg} (field {checks.fmt(field)} {unit}, at {checks.fmt(dark)} µm)")
    return freqs, t, s
