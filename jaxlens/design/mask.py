"""The paper's re-weighting mask over the field, and per-field loss weights.

Before each epoch an RMS spot error grid is computed from rays at infinity (for a
rotationally symmetric lens, the loss's radial fields stand for the grid). The grid is
normalised by its (area-weighted) mean, and fields below ``threshold`` × the mean (0.8 in
the paper) are dropped, so the next epoch works on the fields that are worse than average,
each in proportion to its error.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks

MASK_THRESHOLD = 0.8


def reweighting_mask(
    rms: Float[Array, "*b K"], area: Float[Array, " K"] | None = None, *,
    threshold: float = MASK_THRESHOLD,
) -> Float[Array, "*b K"]:
    """Normalised RMS error per field with the fields below ``threshold`` dropped.

    Args:
        rms: RMS spot error per field (any unit), batch axes first.
        area: optional share of the sensor area of each field, for the mean.
        threshold: fields whose normalised error is below this get weight 0.

    Returns:
        ``rms / mean(rms)`` where that is ≥ ``threshold``, else 0. A field grid with a zero
        mean (a perfect lens) gives all ones.
    """
    # Above 1 every field can be dropped (a uniform grid: zero loss); at most 1 keeps the
    # worst field, whose normalised error is >= 1.
    checks.number(threshold, "threshold", "reweighting_mask", lo=0, hi=1,
                  unit="(fraction of the mean RMS)")
    checks.real_values(rms, "rms", "reweighting_mask")
    if not checks.is_traced(rms):  # a NaN made the mean NaN, and every weight 1
        checks.values(rms, "rms", "reweighting_mask", lo=0, unit="(RMS spot error per field)")
    rms = jnp.asarray(rms)
    if rms.ndim == 0 or rms.shape[-1] == 0:  # before: [] gave [] and 0.5 gave 1.0, no fields
        raise ValueError(f"reweighting_mask: rms must be [..., K] with K >= 1 fields (RMS spot "
                         f"error per field), got shape {rms.shape}")
    if area is not None and not checks.is_traced(area) and \
            jnp.shape(area) != jnp.shape(rms)[-1:]:
        raise ValueError(f"reweighting_mask: area must be [K] = {jnp.shape(rms)[-1:]} (one "
                         f"share per field of rms), got shape {jnp.shape(area)}")
    if area is not None and not checks.is_traced(area):
        # NaN, negative or all-zero shares made the mean NaN or meaningless: every weight 1.
        checks.values(area, "area", "reweighting_mask", lo=0, unit="(share of the sensor area)")
        if not float(np.sum(np.asarray(area))) > 0:  # np.sum of a jax array is traced under jit
            raise ValueError(f"reweighting_mask: area must have a share > 0 for at least one "
                             f"field (the weights of the mean), got all zeros {jnp.shape(area)}")
    w = jnp.ones_like(rms) if area is None else jnp.broadcast_to(area, rms.shape)
    mean = jnp.sum(w * rms, -1, keepdims=True) / jnp.sum(w, -1, keepdims=True)
    ok = mean > 0
    norm = jnp.where(ok, rms / jnp.where(ok, mean, 1.0), 1.0)
    return jnp.where(norm >= threshold, norm, 0.0)


def field_weights(
    rms: Float[Array, "*b K"], area: Float[Array, " K"], *, mask: bool, irls: bool,
    floor: float = 1e-4,
) -> Float[Array, "*b K"]:
    """Loss weight of every field: sensor area × (mask) × (1/RMS re-weighting).

    With ``irls`` the weights are divided by each field's current RMS (floored at
    ``floor``, mm), so that Σ w_k·MS_k approximates the area-weighted mean RMS (the
    evaluation metric) rather than the mean square. The result is normalised to sum 1.
    """
    if not checks.is_traced(floor):  # a floor <= 0 divided by a field's RMS of 0
        checks.number(floor, "floor", "field_weights", lo=0, lo_open=True, unit="mm")
    w = jnp.broadcast_to(area, rms.shape)
    if mask:
        w = w * reweighting_mask(rms, area)
    if irls:
        w = w / jnp.maximum(rms, floor)
    return w / jnp.maximum(jnp.sum(w, -1, keepdims=True), 1e-30)
