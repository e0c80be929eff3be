"""The reconstruction of the EDoF experiment: a NAFNet, optionally behind a Wiener front end.

``Decoder(wiener=False)`` is the paper's decoder: a NAFNet (``jaxlens.nets``) that starts as
the identity (its last convolution is zero), so training starts from the raw image.
``Decoder(wiener=True)`` first deconvolves the raw image tile by tile with the lens's
depth-averaged PSF (``jaxlens.imaging.tiled.wiener_tiles``, gradient prior) and a learnable
noise-to-signal ratio per channel, then refines the result with the same NAFNet: the network no
longer has to learn the inverse of the blur, only to remove what the deconvolution leaves (noise,
ringing, the depth-dependent part of the blur). The depth is unknown at test time, so the
front end uses the PSF averaged over the 8 training depths.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ...imaging.tiled import wiener_tiles
from ...nets import NAFNet

DECODERS = ("nafnet", "wiener")


class Decoder(eqx.Module):
    """A NAFNet with an optional tiled Wiener front end.

    Attributes:
        net: the NAFNet.
        log_nsr: ``[3]`` log noise-to-signal ratio per channel of the front end (trained).
        wiener: whether the front end is used (static).
    """

    net: NAFNet
    log_nsr: Float[Array, " 3"]
    wiener: bool = eqx.field(static=True)

    def __call__(self, raw: Float[Array, "H W 3"],
                 kernels: Float[Array, "ty tx 3 k k"]) -> Float[Array, "H W 3"]:
        """Restore a raw image whose tiles have the depth-averaged PSFs ``kernels``."""
        return self.net(self.front(raw, kernels))

    def front(self, raw, kernels):
        """The input the network sees (the Wiener estimate, or the raw image)."""
        if not self.wiener:
            return raw
        return wiener_tiles(raw, kernels, jnp.exp(self.log_nsr), prior="gradient")


def make_decoder(kind: str, *, nsr: float, key, width: int, enc_blocks, middle_blocks: int,
                 dec_blocks, dtype=jnp.float32) -> Decoder:
    """A fresh decoder (``kind`` "nafnet" or "wiener") whose front end starts at ``nsr``."""
    if kind not in DECODERS:
        raise ValueError(f"make_decoder: kind must be one of {DECODERS}, got {kind!r}")
    net = NAFNet(width=width, enc_blocks=enc_blocks, middle_blocks=middle_blocks,
                 dec_blocks=dec_blocks, key=key, dtype=dtype)
    return Decoder(net, jnp.full((3,), jnp.log(nsr), dtype), kind == "wiener")
