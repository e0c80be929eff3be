"""The reconstruction of the EDoF experiment: a NAFNet, optionally behind a Wiener front end.

Three kinds (``DECODERS``):

- "nafnet", the paper's decoder: a NAFNet (``jaxlens.nets``) that starts as the identity (its
  last convolution is zero), so training starts from the raw image.
- "wiener": the raw image is first deconvolved tile by tile with the lens's depth-averaged
  PSF (``jaxlens.imaging.tiled.wiener_tiles``, gradient prior) and a learnable
  noise-to-signal ratio per channel; the same NAFNet refines the result. The network no
  longer has to learn the inverse of the blur, only to remove what the deconvolution leaves
  (noise, ringing, the depth-dependent part of the blur).
- "multiwiener": the network also sees the raw image deconvolved with the PSF of each of the
  8 training depths (27 input channels). The depth is unknown at test time, but one of the
  estimates is deconvolved with about the right PSF, and the wrong ones ring; the network
  learns to pick per region (the idea of multi-Wiener deconvolution networks, Yanny et al.,
  Optics Express 2022). Its global residual is the depth-averaged estimate, so it starts as
  the "wiener" decoder.

A decoder takes the front end's PSF stack ``[K, ty, tx, 3, k, k]`` (K = 1 or 9) that
``Decoder.front_kernels`` makes from PSFs at the 8 training depths.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ...imaging.tiled import wiener_tiles
from ...nets import NAFNet
from .lenses import DEPTHS_M

DECODERS = ("nafnet", "wiener", "multiwiener")


class Decoder(eqx.Module):
    """A NAFNet with an optional tiled Wiener front end.

    Attributes:
        net: the NAFNet.
        log_nsr: ``[3]`` log noise-to-signal ratio per channel of the front end (trained).
        kind: one of ``DECODERS`` (static).
    """

    net: NAFNet
    log_nsr: Float[Array, " 3"]
    kind: str = eqx.field(static=True)

    @property
    def wiener(self) -> bool:
        """Whether the decoder has a Wiener front end (and so reads PSFs)."""
        return self.kind != "nafnet"

    def __call__(self, raw: Float[Array, "H W 3"],
                 kernels: Float[Array, "K ty tx 3 k k"]) -> Float[Array, "H W 3"]:
        """Restore a raw image given its front-end PSF stack (``front_kernels``)."""
        return self.net(self.front(raw, kernels))

    def front_kernels(self, by_depth: Float[Array, "D *tiles 3 k k"]
                      ) -> Float[Array, "K *tiles 3 k k"]:
        """The front end's PSF stack from PSFs at the training depths (axis 0): their mean,
        then (multiwiener) each depth's."""
        by_depth = jnp.asarray(by_depth)
        mean = by_depth.mean(0, keepdims=True)
        return jnp.concatenate([mean, by_depth]) if self.kind == "multiwiener" else mean

    def front(self, raw, kernels):
        """The input the network sees: the raw image, or its Wiener estimates side by side
        (the depth-averaged one first)."""
        if not self.wiener:
            return raw
        nsr = jnp.exp(self.log_nsr)
        est = jax.vmap(lambda k: wiener_tiles(raw, k, nsr, prior="gradient"))(kernels)
        return jnp.concatenate(list(est), -1)


def make_decoder(kind: str, *, nsr: float, key, width: int, enc_blocks, middle_blocks: int,
                 dec_blocks, dtype=jnp.float32) -> Decoder:
    """A fresh decoder (``kind`` one of ``DECODERS``) whose front end starts at ``nsr``."""
    if kind not in DECODERS:
        raise ValueError(f"make_decoder: kind must be one of {DECODERS}, got {kind!r}")
    estimates = 1 + len(DEPTHS_M) if kind == "multiwiener" else 1
    net = NAFNet(3 * estimates, 3, width=width, enc_blocks=enc_blocks,
                 middle_blocks=middle_blocks, dec_blocks=dec_blocks, key=key, dtype=dtype)
    return Decoder(net, jnp.full((3,), jnp.log(nsr), dtype), kind)
