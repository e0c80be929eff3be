"""The reconstruction of the EDoF experiment: a NAFNet, optionally behind a Wiener front end.

Three kinds (``DECODERS``):

- "nafnet", the paper's decoder: a NAFNet (``jaxlens.nets``) that starts as the identity (its
  last convolution is zero), so training starts from the raw image.
- "wiener": the raw image is first deconvolved tile by tile with the lens's depth-averaged
  PSF (``jaxlens.imaging.tiled.wiener_tiles``, gradient prior) and a learnable
  noise-to-signal ratio per channel; the same NAFNet refines the result. The network no
  longer has to learn the inverse of the blur, only to remove what the deconvolution leaves
  (noise, ringing, the depth-dependent part of the blur).
- "multiwiener": the raw image is also deconvolved with the PSF of each of the 8 training
  depths, and each tile's estimates are weighted by the posterior of its depth
  (``jaxlens.imaging.tiled.tile_evidence``: the Gaussian likelihood of the tile under each
  depth's blur, the same model as the Wiener filter). The depth is unknown at test time, but
  the blur of the right depth explains the tile best (depth from defocus). The network sees
  the posterior-weighted estimate (its global residual, so it starts as that estimate), the
  depth-averaged one, the 8 per-depth ones and the 8 posteriors: 38 channels. The idea of
  giving a network several Wiener estimates is that of multi-Wiener deconvolution networks
  (Yanny et al., Optics Express 2022).

A decoder takes the front end's PSF stack ``[K, ty, tx, 3, k, k]`` (K = 1, or 9 for
multiwiener: the mean, then each depth's) that
``Decoder.front_kernels`` makes from PSFs at the 8 training depths.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ...imaging.tiled import tile_evidence, wiener_tiles
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

    def __call__(self, raw: Float[Array, "H W 3"], kernels: Float[Array, "K ty tx 3 k k"],
                 pad: str = "edge") -> Float[Array, "h w 3"]:
        """Restore a raw image given its front-end PSF stack (``front_kernels``).

        With ``pad="valid"`` (Wiener kinds) ``raw`` holds a margin of real scene around the
        tiled area, as wide as the front end's halo (``kernel side``), which the front end
        reads and the result drops (``jaxlens.imaging.tiled.wiener_tiles``)."""
        return self.net(self.front(raw, kernels, pad))

    def front_kernels(self, by_depth: Float[Array, "D *tiles 3 k k"]
                      ) -> Float[Array, "K *tiles 3 k k"]:
        """The front end's PSF stack from PSFs at the training depths (axis 0): their mean,
        then (multiwiener) each depth's."""
        by_depth = jnp.asarray(by_depth)
        mean = by_depth.mean(0, keepdims=True)
        return jnp.concatenate([mean, by_depth]) if self.kind == "multiwiener" else mean

    def front(self, raw, kernels, pad="edge"):
        """The input the network sees: the raw image, its Wiener estimate, or (multiwiener)
        the posterior-weighted estimate, the depth-averaged one, each depth's and the depth
        posteriors, as channels."""
        if not self.wiener:
            if pad != "edge":
                raise ValueError("Decoder: a decoder without a front end takes pad='edge'")
            return raw
        nsr = jnp.exp(self.log_nsr)
        est = jax.vmap(lambda k: wiener_tiles(raw, k, nsr, prior="gradient", pad=pad))(kernels)
        if self.kind == "wiener":
            return est[0]
        post = depth_posterior(raw, kernels[1:], nsr, pad)
        tile = est.shape[1] // kernels.shape[1]
        post = jnp.repeat(jnp.repeat(post, tile, 1), tile, 2)  # [D, H, W], per pixel
        chosen = jnp.sum(post[..., None] * est[1:], 0)
        return jnp.concatenate([chosen, *est, jnp.moveaxis(post, 0, -1)], -1)


def depth_posterior(raw: Float[Array, "H W 3"], by_depth: Float[Array, "D ty tx 3 k k"],
                    nsr, pad: str = "edge") -> Float[Array, "D ty tx"]:
    """Each tile's posterior over the D depths whose PSFs are ``by_depth`` (equal priors;
    ``tile_evidence``'s Gaussian model; ``pad`` as for ``tile_evidence``)."""
    # A loop, not a vmap: the vmapped form, under the training's nested vmaps and grad,
    # crashes XLA:CPU (segmentation fault, jaxlib 0.10.2).
    nll = jnp.stack([tile_evidence(raw, k, nsr, pad=pad) for k in by_depth])
    return jax.nn.softmax(-nll, axis=0)


def make_decoder(kind: str, *, nsr: float, key, width: int, enc_blocks, middle_blocks: int,
                 dec_blocks, dtype=jnp.float32) -> Decoder:
    """A fresh decoder (``kind`` one of ``DECODERS``) whose front end starts at ``nsr``."""
    if kind not in DECODERS:
        raise ValueError(f"make_decoder: kind must be one of {DECODERS}, got {kind!r}")
    n = len(DEPTHS_M)
    channels = 3 * (2 + n) + n if kind == "multiwiener" else 3
    net = NAFNet(channels, 3, width=width, enc_blocks=enc_blocks,
                 middle_blocks=middle_blocks, dec_blocks=dec_blocks, key=key, dtype=dtype)
    return Decoder(net, jnp.full((3,), jnp.log(nsr), dtype), kind)
