"""Encircled and ensquared energy: the fraction of a point image's energy within a radius.

Conventions:
    Lengths in mm (radii, the reference point), field angles in degrees (θy or (θx, θy);
    object heights in mm, y or (x, y), for an object-space telecentric lens), wavelengths
    in µm. ``shape="circle"`` counts the energy within distance r of the
    reference point (encircled energy); ``shape="square"`` within the square of half-width r
    centred on it, sides along x and y (ensquared energy). ``radius_for_fraction`` is the
    inverse: the r that holds a given fraction (0.8 gives the D80 radius; the diameter is
    twice it).

Methods:
    ``"geometric"`` (the default, as Zemax's geometric encircled energy): rays from the object
    point fill the entrance pupil uniformly (by default ``pupil_polar(64)``, 4096 rays on cells
    of equal area, so every ray carries the same energy), are traced to the image surface
    (``jaxlens.analysis.spots.spot_rays``), and each ray that arrives carries equal energy.
    The fraction is of the transmitted energy (the rays that reach the image), so
    vignetting does not lower the curve's end: it reaches 1. Several wavelengths pool
    their rays with equal weights. The reference is the energy centroid (``"centroid"``,
    the default) or the primary-wavelength chief ray (``"chief"``). The curve is a step
    function of r (one step per ray): its derivative with respect to the lens is 0 almost
    everywhere. ``radius_for_fraction`` interpolates between the sorted ray distances (the
    k-th of N valid rays at the cumulative fraction (k − ½)/N), so it is continuous and
    differentiable with respect to the lens through the ray positions. Given the same
    pupil points (``pupil=``, e.g. optiland's hexapolar grid), the fractions equal
    optiland 0.6.3's traced rays counted about their centroid exactly
    (``tests/test_conventions_vs_optiland.py``).

    ``"diffraction"``: the coherent PSF (``jaxlens.imaging.psf.psf_info`` with
    ``CoherentPSF(pupil)``, the ray-based Debye integral) on a ``kernel_size``² grid of
    ``pixel_size`` (mm) centred on the reference point (``"centroid"``: the PSF's energy
    centroid; ``"chief"``: the real chief ray), integrated radially. The kernel is the
    energy per pixel, that is the PSF already integrated over each pixel: each pixel's
    energy is spread uniformly over ``subsamples``² points inside it, so the curve is that of
    the PSF convolved with one pixel (it rises a little early at r below about a pixel, and
    its error against the true PSF's curve shrinks as the pixel does: measured on a
    diffraction-limited F/10 beam at 0.55 µm with 0.5 µm pixels, |EE − Airy| ≤ 2e-3). The
    fraction is of the whole beam's energy: energy that falls outside the kernel
    (``truncated``) is never counted, so the curve ends at 1 − truncated; make the kernel
    wide enough for the radii asked.

Errors: radii must be finite and ≥ 0 mm; a fraction must lie in (0, 1); a fraction the
kernel cannot hold (above 1 − truncated) gives NaN; a field no ray reaches raises
``NoLightError`` (NaN under ``jax.jit``; see ``jaxlens.imaging.light``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..imaging.light import refuse_dark
from ..imaging.psf import CoherentPSF, psf_info
from ..imaging.sampling import pupil_points, pupil_polar
from ..imaging.telecentric import lens_field
from ..optics import checks, paraxial
from ..optics.lens import Lens
from .spots import chief_ray, spot_rays, weighted_centroid

METHODS = ("geometric", "diffraction")
REFERENCES = ("centroid", "chief")
SHAPES = ("circle", "square")
MAX_SUBSAMPLES = 64
"""Most sub-samples per pixel side of the diffraction method: the curve of a pixel's energy
spread uniformly over s² points converges long before (the default is 8); 10**6 asked for
(kernel_size·10**6)² points."""
PUPIL_SIDE = 64  # default geometric pupil: pupil_polar(64), 4096 equal-area cells


class EncircledEnergy(eqx.Module):
    """Encircled (or ensquared) energy of one field.

    Attributes:
        radii: ``[R]`` radii (mm; half-widths for squares).
        energy: ``[R]`` fraction of the energy within each radius (0 … 1).
        center: ``[2]`` reference point (x, y) on the image surface (mm).
        truncated: fraction of the beam's energy outside the PSF kernel (diffraction; 0 for
            the geometric method).
    """

    radii: Float[Array, " R"]
    energy: Float[Array, " R"]
    center: Float[Array, " 2"]
    truncated: Float[Array, ""]


RADII_IMAGE_FACTOR = 2.0
"""``encircled_energy`` refuses radii that all exceed this many image diagonals (mm): every
one encircles the whole image with room to spare, so the answer is 1 at every radius; such
radii are µm given as mm (100 µm typed as 100 on a 43 mm diagonal)."""


def _radii_unit(lens, r, where: str) -> None:
    """Refuse concrete radii (mm) that all exceed ``RADII_IMAGE_FACTOR`` image diagonals:
    the sensor's, else twice the paraxial image height of the lens's largest field."""
    if lens.sensor is not None:
        diag, what = 2.0 * float(lens.sensor.half_diagonal), "the sensor's diagonal"
    else:
        f = np.abs(np.asarray(lens.fields, float))
        t = np.hypot(*np.tan(np.radians(f)).T) if f.ndim == 2 else np.tan(np.radians(f))
        theta = float(np.degrees(np.arctan(np.max(t, initial=0.0))))
        diag = 2.0 * abs(float(paraxial.image_height(lens, theta)))
        what = "the image diagonal (twice the paraxial image height of the largest field)"
    if math.isfinite(diag) and diag > 0 and float(np.min(r)) > RADII_IMAGE_FACTOR * diag:
        raise ValueError(f"{where}: radii are in mm, and every one given (smallest "
                         f"{float(np.min(r)):g} mm) exceeds {RADII_IMAGE_FACTOR:g} times "
                         f"{what}, {diag:.4g} mm: each encircles the whole image. Radii in "
                         f"µm? 20 µm is 0.02 mm")


def _checked_radii(radii, where: str, dtype=None) -> Array:
    """``radii`` (mm) flattened: real, at least one, each finite and >= 0 (an
    ``error_if`` where traced). Every entry point of radii checks here: ``energy_within``
    called directly counted a negative or NaN radius as holding nothing (0)."""
    checks.real_values(radii, "radii", where, "mm")
    r = jnp.reshape(jnp.asarray(radii, dtype), (-1,))
    if r.size == 0:
        raise ValueError(f"{where}: radii must hold at least one radius (mm)")
    return checks.values(r, "radii", where, lo=0, unit="mm")


def _checked_fractions(fraction, where: str, dtype=None) -> Array:
    """``fraction`` (of the energy) as an array: real, each in (0, 1) (an ``error_if`` where
    traced; 1.5 gave NaN and -0.5 a radius)."""
    checks.real_values(fraction, "fraction", where, "(fraction of the energy)")
    f = jnp.asarray(fraction, dtype)
    return checks.values(f, "fraction", where, lo=0, hi=1, lo_open=True, hi_open=True,
                         unit="(fraction of the energy)")


def _check_common(lens, where, field, wavelength, method, reference, shape):
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    for arg, value, allowed in (("method", method, METHODS), ("reference", reference, REFERENCES),
                                ("shape", shape, SHAPES)):
        if value not in allowed:
            raise ValueError(f"{where}: {arg} must be one of {allowed}, got {value!r}")
    paraxial.check_launchable(lens, where)  # a pupil at infinity: before the field's chief ray
    field = lens_field(lens, field, where)  # here: the inner traces are quiet
    wl = lens.primary_wavelength if wavelength is None else wavelength
    if jnp.ndim(wl) > 1 or jnp.size(wl) == 0:
        raise ValueError(f"{where}: wavelength must be a scalar or [W] µm with W >= 1, got "
                         f"shape {jnp.shape(wl)}")
    if not checks.is_traced(wl):
        checks.wavelengths(lens, wl, where)
        checks.material_indices(lens, wl, where)
    dtype = lens.epd.dtype
    return jnp.asarray(field, dtype), jnp.atleast_1d(jnp.asarray(wl, dtype))


def _metric(dxy, shape):
    """Distance of offsets ``[..., 2]`` from the reference: Euclidean or Chebyshev (square)."""
    if shape == "square":
        return jnp.max(jnp.abs(dxy), axis=-1)
    d2 = jnp.sum(dxy * dxy, axis=-1)
    pos = d2 > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, d2, 1.0)), 0.0)  # double where: grad at 0


def _geometric_samples(lens, field, wls, *, reference, shape, pupil, depth):
    """Distances (mm), weights and the reference point of the traced rays, pooled over wls."""
    pts = pupil_polar(PUPIL_SIDE, dtype=lens.epd.dtype) if pupil is None else pupil
    ps, ws = [], []
    for w in wls:
        r = spot_rays(lens, field, w, pupil=pts, depth=depth)
        ps.append(r.origin[..., :2])
        ws.append(r.valid.astype(r.origin.dtype))
    p, wt = jnp.concatenate(ps), jnp.concatenate(ws)
    if reference == "centroid":
        ref = weighted_centroid(p, wt)
        ok = jnp.sum(wt) > 0
    else:
        cr = chief_ray(lens, field, depth=depth)
        ref, ok = cr.origin[:2], cr.valid & (jnp.sum(wt) > 0)
    d = _metric(p - ref, shape)
    total = jnp.sum(wt)
    return d, wt, jnp.maximum(total, 1.0), jnp.where(ok, ref, jnp.nan), jnp.zeros(())


def _diffraction_samples(lens, field, wls, *, reference, shape, depth, pixel_size, kernel_size,
                         pupil_side, subsamples):
    """Sub-pixel points of the coherent PSF: distances, energies, reference, truncation."""
    res = psf_info(lens, field, depth=depth, wavelength=wls, kernel_size=kernel_size,
                   pixel_size=pixel_size, model=CoherentPSF(pupil=pupil_side), center=reference,
                   max_truncation=1.0)
    kern = jnp.mean(res.psf, axis=0)  # [k, k], wavelengths pooled with equal weights
    k, s = kernel_size, subsamples
    c = (k - 1) / 2
    sub = (np.arange(s) + 0.5) / s - 0.5  # sub-sample offsets inside a pixel (pixels)
    off = (np.arange(k)[:, None] - c + sub[None, :]).reshape(-1)  # [k·s]
    yy, xx = np.meshgrid(off, off, indexing="ij")
    dxy = jnp.asarray(np.stack([xx, yy], -1), kern.dtype) * pixel_size  # [k·s, k·s, 2]
    e = jnp.repeat(jnp.repeat(kern, s, axis=0), s, axis=1) / (s * s)
    return (_metric(dxy, shape).reshape(-1), e.reshape(-1), jnp.ones((), kern.dtype),
            res.center, jnp.mean(jnp.atleast_1d(res.truncated)))


def _samples(lens, field, where, *, wavelength, method, reference, shape,
             pupil, depth, pixel_size, kernel_size, pupil_side, subsamples):
    field, wls = _check_common(lens, where, field, wavelength, method, reference, shape)
    # The diffraction settings are checked whatever the method (before: pupil_side=1 or
    # subsamples=0 passed without a word when the method was geometric).
    checks.number(kernel_size, "kernel_size", where, lo=1, hi=checks.MAX_KERNEL_SIZE,
                  integer=True, unit="pixels per side")
    # Upper bounds: pupil_side² rays are traced at once (CoherentPSF's bound, which named
    # its own "pupil" for pupil_side), and (kernel_size·subsamples)² sub-pixel points kept.
    checks.number(pupil_side, "pupil_side", where, lo=2, hi=math.isqrt(checks.MAX_PUPIL_POINTS),
                  integer=True, unit="rays per side")
    checks.number(subsamples, "subsamples", where, lo=1, hi=MAX_SUBSAMPLES, integer=True,
                  unit="sub-samples per pixel side")
    if method == "geometric":
        if pupil is not None:
            pupil = pupil_points(pupil, where, unit_disc=True)
            if pupil.ndim != 2:
                raise ValueError(f"{where}: pupil must be [M, 2] normalised pupil points with "
                                 f"M >= 1, got shape {pupil.shape}")
        with checks.fields_warned_by(where):  # spot_rays would warn under its name
            return _geometric_samples(lens, field, wls, reference=reference, shape=shape,
                                      pupil=pupil, depth=depth)
    if pixel_size is None:
        raise ValueError(f"{where}: method='diffraction' needs pixel_size (mm), the PSF grid "
                         f"pitch: a few per Airy radius 1.22·λ·F#")
    checks.number(pixel_size, "pixel_size", where, lo=0, lo_open=True, unit="mm")
    with checks.fields_warned_by(where):  # psf and chief_ray would too
        return _diffraction_samples(lens, field, wls, reference=reference, shape=shape,
                                    depth=depth, pixel_size=pixel_size,
                                    kernel_size=int(kernel_size), pupil_side=int(pupil_side),
                                    subsamples=int(subsamples))


def encircled_energy(lens: Lens, field, radii, *, wavelength=None, method: str = "geometric",
                     reference: str = "centroid", shape: str = "circle", pupil=None,
                     depth=None, pixel_size=None, kernel_size: int = 63,
                     pupil_side: int = 64, subsamples: int = 8) -> EncircledEnergy:
    """Fraction of a field's energy within each radius of the reference point.

    Args:
        lens: the lens.
        field: θy, or (θx, θy), in degrees; an object height in mm, y or (x, y), for an
            object-space telecentric lens.
        radii: radii in mm (half-widths for ``shape="square"``), finite and ≥ 0, any shape
            (returned flattened).
        wavelength: µm, a scalar or ``[W]`` (pooled with equal weights); default primary.
        method: ``"geometric"`` (traced rays) or ``"diffraction"`` (coherent PSF).
        reference: ``"centroid"`` (default, as Zemax) or ``"chief"`` (the chief ray).
        shape: ``"circle"`` (encircled) or ``"square"`` (ensquared).
        pupil: geometric: ``[M, 2]`` normalised pupil points, each carrying equal energy
            (default ``pupil_polar(64)``: equal-area cells).
        depth: object distance (mm), ``inf`` for infinity; default the lens's own object.
        pixel_size, kernel_size, pupil_side, subsamples: diffraction: PSF pitch (mm, needed),
            kernel side (pixels), coherent pupil rays per side, sub-samples per pixel side.

    Returns:
        An :class:`EncircledEnergy`.

    Raises:
        NoLightError: (a ValueError) no ray reaches the image surface, with concrete inputs
            (under ``jax.jit`` the energies are NaN); see ``jaxlens.imaging.light``.

    Example:
        >>> import jax.numpy as jnp, jaxlens
        >>> ee = encircled_energy(jaxlens.zoo.cooke_triplet(), 0.0, jnp.array([0.0, 1.0]))
        >>> [round(float(e), 3) for e in ee.energy]
        [0.0, 1.0]
    """
    checks.focal_image(lens, "encircled_energy")
    where = "encircled_energy"
    if wavelength is None:  # before the image size (``_radii_unit``) traces it paraxially
        checks.primary_wavelength(lens, where)
    paraxial.check_launchable(lens, where)  # before the largest field's chief ray (image size)
    r = _checked_radii(radii, where, lens.epd.dtype)
    if not checks.is_traced((r, lens)):  # a traced lens has no concrete image size
        _radii_unit(lens, np.asarray(r), where)
    samples = EnergySamples(*_samples(
        lens, field, where, wavelength=wavelength, method=method, reference=reference,
        shape=shape, pupil=pupil, depth=depth, pixel_size=pixel_size, kernel_size=kernel_size,
        pupil_side=pupil_side, subsamples=subsamples))
    _refuse_dark(samples, where, lens, field)
    return energy_within(samples, r)


def radius_for_fraction(lens: Lens, field, fraction, *, wavelength=None,
                        method: str = "geometric", reference: str = "centroid",
                        shape: str = "circle", pupil=None, depth=None, pixel_size=None,
                        kernel_size: int = 63, pupil_side: int = 64,
                        subsamples: int = 8) -> Array:
    """The radius (mm) holding ``fraction`` of the energy (0.8: the D80 radius).

    Args: as :func:`encircled_energy`, with ``fraction`` (a number or array, each in (0, 1))
    in place of the radii.

    Returns:
        Radii (mm), the shape of ``fraction``: interpolated between the sorted sample
        distances (see the module notes); NaN above what the kernel holds (diffraction).
        A field no ray reaches raises ``NoLightError`` (concrete inputs; NaN under jit).
    """
    checks.focal_image(lens, "radius_for_fraction")
    where = "radius_for_fraction"
    f = _checked_fractions(fraction, where, lens.epd.dtype)
    samples = EnergySamples(*_samples(
        lens, field, where, wavelength=wavelength, method=method,
        reference=reference, shape=shape, pupil=pupil, depth=depth, pixel_size=pixel_size,
        kernel_size=kernel_size, pupil_side=pupil_side, subsamples=subsamples))
    _refuse_dark(samples, where, lens, field)
    return radius_holding(samples, f)


def _refuse_dark(samples, where, lens, field):
    """A field no ray reaches has no energy curve: NoLightError (concrete), NaN (traced)."""
    refuse_dark(jnp.any(samples.weight > 0), where, lens, field, "encircled energy")


class EnergySamples(NamedTuple):
    """The points one field's energy is counted over (:func:`energy_samples`).

    Attributes:
        distance: ``[N]`` distances from the reference point (mm; the larger of |dx|, |dy|
            for ``shape="square"``).
        weight: ``[N]`` the energy of each (0 for a ray that does not arrive).
        total: the energy the fractions are of (the arriving rays', or 1: the beam's).
        center: ``[2]`` the reference point (mm); NaN where no ray reaches the image.
        truncated: the beam's energy outside the PSF kernel (diffraction; else 0).
    """

    distance: Array
    weight: Array
    total: Array
    center: Array
    truncated: Array


def energy_samples(lens: Lens, field, *, wavelength=None, method: str = "geometric",
                   reference: str = "centroid", shape: str = "circle", pupil=None,
                   depth=None, pixel_size=None, kernel_size: int = 63, pupil_side: int = 64,
                   subsamples: int = 8, where: str = "energy_samples") -> EnergySamples:
    """One field's samples, checked and traced once, for both :func:`energy_within` (the
    encircled-energy curve) and :func:`radius_holding` (D80 and the like): what a caller
    that wants both uses (``plot_encircled_energy`` traced each field twice before).
    Arguments as :func:`encircled_energy`; ``where`` names the caller in messages."""
    checks.focal_image(lens, where)
    return EnergySamples(*_samples(
        lens, field, where, wavelength=wavelength, method=method, reference=reference,
        shape=shape, pupil=pupil, depth=depth, pixel_size=pixel_size, kernel_size=kernel_size,
        pupil_side=pupil_side, subsamples=subsamples))


def energy_within(samples: EnergySamples, radii) -> EncircledEnergy:
    """The fraction of ``samples``' energy within each of ``radii`` (mm, flattened to
    ``[R]``; each finite and >= 0, else a ``ValueError``)."""
    d, w, total, center, trunc = samples
    r = _checked_radii(radii, "energy_within", d.dtype)
    inside = (d[None, :] <= r[:, None]).astype(w.dtype)
    energy = jnp.sum(inside * w[None, :], axis=-1) / total
    energy = jnp.where(jnp.all(jnp.isfinite(center)), energy, jnp.nan)
    return EncircledEnergy(r, energy, center, trunc)


def radius_holding(samples: EnergySamples, fraction) -> Array:
    """The radius (mm) holding each ``fraction`` (each in (0, 1), else a ``ValueError``)
    of ``samples``' energy; the shape of ``fraction`` (see :func:`radius_for_fraction`)."""
    d, w, total, center, _ = samples
    f = _checked_fractions(fraction, "radius_holding", d.dtype)
    # Sort by distance; samples without energy sit at the far end and add nothing.
    key = jnp.where(w > 0, d, jnp.inf)
    order = jnp.argsort(jax.lax.stop_gradient(key))
    ds, ws = d[order], w[order]
    cum = (jnp.cumsum(ws) - 0.5 * ws) / total  # midpoint cumulative fraction
    held = jnp.sum(ws) / total
    # Flat stretches (no energy) keep the first distance: interp needs increasing xp.
    cum = jnp.where(ws > 0, cum, jnp.inf)
    radius = jnp.interp(f.reshape(-1), cum, ds).reshape(f.shape)
    ok = jnp.all(jnp.isfinite(center)) & (f <= held)
    return jnp.where(ok, radius, jnp.nan)
