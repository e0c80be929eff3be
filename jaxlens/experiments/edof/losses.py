"""The losses of the end-to-end EDoF training (Yang, Fu & Heidrich, Nat. Commun. 2024).

Each training batch is simulated at two object depths d₁ ≠ d₂ drawn from the training depths.
With ``gt`` the sharp patches, ``sim[j]`` the (noise-free) simulated sensor patches at depth
d_j and ``rec[j]`` the network's reconstruction from the noisy ``sim[j]``:

* ``L_sim`` = mean |sim[0] − sim[1]|: the two simulations agree, so the blur does not depend
  on depth (the EDoF property the lens must learn);
* ``L_raw`` = mean_j mean |sim[j] − gt|: the raw simulations stay close to the sharp image
  (keeps the optics from spreading light more than needed);
* ``L_rec`` = mean_j mean |rec[j] − gt|: reconstruction quality.

The total is ``L = L_rec + ω1·L_sim + ω2·L_raw``. Means are over pixels and channels; the
distances are L1, which trains restoration networks better than L2 and is what PSNR-driven
restoration work (NAFNet included) commonly optimises early on.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float


def l_sim(sim: Float[Array, " 2 *b"]) -> Float[Array, ""]:
    """Mean absolute difference between the simulations at the two depths."""
    return jnp.mean(jnp.abs(sim[0] - sim[1]))


def l_raw(sim: Float[Array, " 2 *b"], gt: Float[Array, "*b"]) -> Float[Array, ""]:
    """Mean absolute error of the raw simulations against the sharp image."""
    return jnp.mean(jnp.abs(sim - gt[None]))


def l_rec(rec: Float[Array, " 2 *b"], gt: Float[Array, "*b"]) -> Float[Array, ""]:
    """Mean absolute error of the reconstructions against the sharp image."""
    return jnp.mean(jnp.abs(rec - gt[None]))


def edof_loss(rec, sim, gt, *, w_sim, w_raw) -> tuple[Array, dict[str, Array]]:
    """``L_rec + ω1·L_sim + ω2·L_raw`` and its parts.

    Args:
        rec: ``[2, *b]`` reconstructions at the two depths.
        sim: ``[2, *b]`` noise-free simulations at the two depths.
        gt: ``[*b]`` sharp images.
        w_sim: ω1, the weight of ``L_sim``.
        w_raw: ω2, the weight of ``L_raw``.

    Returns:
        ``(total, {"rec": L_rec, "sim": L_sim, "raw": L_raw})``.
    """
    if rec.shape != sim.shape or rec.shape[0] != 2 or rec.shape[1:] != gt.shape:
        raise ValueError(
            f"edof_loss: need rec and sim of shape [2, *b] and gt of shape [*b], got "
            f"{rec.shape}, {sim.shape}, {gt.shape}"
        )
    parts = {"rec": l_rec(rec, gt), "sim": l_sim(sim), "raw": l_raw(sim, gt)}
    return parts["rec"] + w_sim * parts["sim"] + w_raw * parts["raw"], parts
