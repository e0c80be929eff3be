"""The tolerance metric and its compensator: rays on the image plane per field, wavelength
and pupil point (``SpotData``), the field-weighted polychromatic RMS spot (``mean_rms_um``),
the back-focus compensator (``best_focus``) and the geometric × diffraction MTF
(``field_mtf``). See ``jaxlens.analysis.tolerance`` for the definitions.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..imaging.otf import diffraction_mtf, mtf_directions
from ..optics import checks
from ..optics.lens import Lens
from .spots import spot_rays, weighted_rms


class SpotData(eqx.Module):
    """Rays on the image plane, per field F, wavelength W and pupil point M."""

    position: Float[Array, "F W M 2"]  # mm
    slope: Float[Array, "F W M 2"]  # (dx/dz, dy/dz) in image space
    weight: Float[Array, "F W M"]  # 1 for a valid ray, 0 otherwise


def spot_data(lens: Lens, fields, wavelengths, pupil) -> SpotData:
    """Trace every field and wavelength (jittable, vmappable over lenses).

    The slopes are dx/dz, dy/dz whichever way along z the light travels: after an odd
    number of mirrors it reaches the image toward −z (dz < 0), and the image plane moved
    by Δz (mm, along z, as the last thickness changes) meets the ray at p + Δz · slope.
    Before, only rays with dz > 0 had slopes: every ray of a mirror lens had slope 0, so
    ``best_focus`` could not refocus it (Δz = 0, the defocused RMS kept)."""

    def one(field, wl):
        r = spot_rays(lens, field, wl, pupil=pupil)
        dz = r.direction[..., 2:3]
        ok = jnp.abs(dz) > 1e-12  # a ray along the image plane has no slope
        slope = r.direction[..., :2] / jnp.where(ok, dz, 1.0)
        return r.origin[..., :2], jnp.where(ok, slope, 0.0), r.valid.astype(r.origin.dtype)

    per_field = jax.vmap(lambda f: jax.vmap(lambda w: one(f, w))(wavelengths))
    return SpotData(*per_field(fields))


def pooled(data: SpotData):
    f = data.weight.shape[0]
    return data.position.reshape(f, -1, 2), data.slope.reshape(f, -1, 2), \
        data.weight.reshape(f, -1)


def field_rms(data: SpotData, dz=0.0) -> Float[Array, " F"]:
    """Polychromatic RMS radius per field (mm) with the image plane moved by ``dz`` mm."""
    p, u, w = pooled(data)
    return weighted_rms(p + dz * u, w)


def normalised_weights(weights):
    """Weights scaled to sum to 1; concrete ones must be finite, >= 0 and not all 0."""
    if not checks.is_traced(weights):
        # Before: a list was a TypeError from jnp.sum, and [0, 0] gave NaN weights. NumPy:
        # a jnp.sum of constants is a tracer inside the jitted metric.
        a = np.asarray(weights, dtype=float)
        checks.values(a, "weights", "normalised_weights", lo=0, unit="(relative)")
        if a.size == 0 or not float(np.sum(a)) > 0:
            raise ValueError(f"normalised_weights: weights must hold a positive value "
                             f"(relative), got {checks.fmt(a) if a.size else '[]'}")
    w = jnp.asarray(weights)
    return w / jnp.sum(w)


def mean_rms_um(data: SpotData, weights, dz=0.0) -> Float[Array, ""]:
    """The metric: field-weighted mean polychromatic RMS radius (µm)."""
    return 1e3 * jnp.sum(normalised_weights(weights) * field_rms(data, dz))


def best_focus(data: SpotData, weights, *, iters: int = 8) -> Float[Array, ""]:
    """Image-plane shift Δz (mm) that minimises the metric (the back-focus compensator).

    Fields without valid rays are ignored. See the module docstring for the method.
    """
    p, u, w = pooled(data)
    total = jnp.sum(w, -1)
    alpha = jnp.where(total > 0, normalised_weights(weights), 0.0)
    tot = jnp.maximum(total, 1.0)[:, None]
    dp = p - (jnp.sum(w[..., None] * p, 1) / tot)[:, None, :]
    du = u - (jnp.sum(w[..., None] * u, 1) / tot)[:, None, :]
    a = jnp.sum(w * jnp.sum(dp * dp, -1), -1) / tot[:, 0]
    b = jnp.sum(w * jnp.sum(dp * du, -1), -1) / tot[:, 0]
    c = jnp.sum(w * jnp.sum(du * du, -1), -1) / tot[:, 0]
    tiny = jnp.finfo(p.dtype).tiny

    def metric(z):
        return jnp.sum(alpha * jnp.sqrt(jnp.maximum(a + 2 * b * z + c * z * z, 0.0)))

    z0 = -jnp.sum(alpha * b) / jnp.maximum(jnp.sum(alpha * c), tiny)
    scales = jnp.asarray([1.0, 0.5, 0.25, 0.125, 0.0], p.dtype)

    def step(_, z):
        ms = jnp.maximum(a + 2 * b * z + c * z * z, tiny)
        r = jnp.sqrt(ms)
        g = jnp.sum(alpha * (b + c * z) / r)
        h = jnp.sum(alpha * jnp.maximum(a * c - b * b, 0.0) / (r * ms))
        full = jnp.where(h > 0, -g / jnp.where(h > 0, h, 1.0), 0.0)
        cand = z + scales * full
        return cand[jnp.argmin(jax.vmap(metric)(cand))]

    return jax.lax.fori_loop(0, iters, step, z0)


def field_mtf(data: SpotData, fields, wavelengths, frequency, fnum, dz=0.0, heights=False
              ) -> Float[Array, " F"]:
    """Geometric × diffraction MTF at ``frequency`` (cycles/mm), mean of T and S, per field
    (``heights``: the fields are a telecentric lens's object heights in mm, not angles)."""
    q = data.position + dz * data.slope  # [F, W, M, 2]
    w = data.weight
    tot_w = jnp.maximum(jnp.sum(w, -1, keepdims=True), jnp.finfo(q.dtype).tiny)
    ref = jnp.sum(w[..., None] * q, (1, 2)) / jnp.maximum(jnp.sum(w, (1, 2)), 1e-30)[:, None]
    rel = q - ref[:, None, None, :]
    wn = w / tot_w
    lam = wavelengths * 1e-3
    diff = diffraction_mtf(frequency, lam, fnum)  # [W]
    e_t, e_s = mtf_directions(fields, heights=heights)

    def along(e):
        proj = jnp.sum(rel * e[:, None, None, :], -1)  # [F, W, M]
        o = jnp.sum(wn * jnp.exp(-2j * jnp.pi * frequency * proj), -1)  # [F, W]
        return jnp.abs(jnp.mean(o * diff, -1))

    return 0.5 * (along(e_t) + along(e_s))
