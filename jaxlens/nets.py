"""Image-reconstruction networks: a NAFNet-style UNet in equinox.

The network follows the design of NAFNet (Chen, Chu, Zhang, Sun, "Simple Baselines for Image
Restoration", ECCV 2022): a UNet whose blocks use no nonlinear activation. Each block has a
LayerNorm over channels, a 1×1 expansion, a depthwise 3×3 convolution, a *SimpleGate* (the
channels split in two halves that are multiplied), *simplified channel attention* (a global
average pool followed by a 1×1 convolution that rescales the channels) and a gated
feed-forward branch. Both branches enter the residual stream through learned per-channel
scales that start at zero, so a fresh block is the identity; the last convolution starts at
zero too (``identity_init``), so a fresh network returns its input exactly (the global
residual) and training starts from the raw image rather than from a random correction.

Conventions:
    Images are channels-last ``[H, W, C]`` arrays, one image per call (``jax.vmap`` over a
    batch, as equinox does). Pixel values are linear intensities, nominally in [0, 1]. Sizes
    that are not multiples of ``2**depth`` are reflect-padded and cropped back.

The blocks are written with matrix products (1×1 convolutions) and shifted sums (the
depthwise 3×3), which XLA runs fast on CPU; only the 3×3 stem and head and the 2×2
downsampling use ``lax.conv_general_dilated``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, PRNGKeyArray

from .optics import checks

_DIMS = ("NHWC", "HWIO", "NHWC")

MAX_WIDTH = 1024
"""Most channels of NAFNet's first level (its widths are 16 to 64; the deepest level has
width · 2**levels channels and weights growing as their square)."""

MAX_LEVELS = 8
"""Most levels of NAFNet's UNet (``len(enc_blocks)``; the paper's has 4). Each level halves the
image and doubles the channels, so 20 levels of width 16 asked for 16·2**20 channels (a
MemoryError); an image needs a side of 2**levels pixels."""

MAX_BLOCKS = 256
"""Most NAFBlocks at one level or at the bottleneck (the paper's deepest level has 28)."""


def _generator(key) -> np.random.Generator:
    """A NumPy generator seeded from a JAX PRNG key (or the generator itself).

    Parameters are drawn on the host: a network has dozens of differently shaped arrays,
    and drawing each with ``jax.random`` would compile one small program per shape.
    """
    if isinstance(key, np.random.Generator):
        return key
    if isinstance(key, jax.core.Tracer):
        raise ValueError(
            "NAFNet: parameters are drawn on the host; build the network "
            "outside jit/eval_shape (it takes well under a second)"
        )
    if not isinstance(key, (jax.Array, np.ndarray)):  # an int 0 failed on key.dtype
        raise TypeError(f"NAFNet: key must be a JAX PRNG key (jax.random.PRNGKey(0) or "
                        f"jax.random.key(0)) or a numpy Generator, got {type(key).__name__} "
                        f"{key!r}")
    data = np.asarray(
        jax.random.key_data(key) if jax.dtypes.issubdtype(key.dtype, jax.dtypes.prng_key) else key,
        np.uint32,
    )
    return np.random.default_rng(data.ravel().tolist())


def _sizes(where: str, **sizes) -> None:
    """Channel counts and kernel sizes of a layer: whole numbers in [1, ``MAX_SAMPLES``]
    (before: a kernel of 0 was a ZeroDivisionError in the init's bound, a channel count of
    -4 a numpy error, and 10**6 channels a weight matrix of 8 TB)."""
    for arg, v in sizes.items():
        checks.number(v, arg, where, lo=1, hi=checks.MAX_SAMPLES, integer=True)


def _channels_last(x, channels: int, where: str) -> None:
    """An input ``[..., C]`` with the layer's C (a static shape: also under jit)."""
    if jnp.ndim(x) < 1 or jnp.shape(x)[-1] != channels:
        raise ValueError(f"{where}: expected an input with {channels} channels on its last "
                         f"axis, got shape {jnp.shape(x)}")


def _channels_in(x, channels: int, where: str) -> None:
    """An ``[H, W, C]`` input with the layer's C (a static shape: also under jit)."""
    if jnp.ndim(x) != 3 or jnp.shape(x)[-1] != channels:
        raise ValueError(f"{where}: expected an [H, W, {channels}] input (channels last), got "
                         f"shape {jnp.shape(x)}")


def _as_float(x, like):
    """``x`` as an array of a floating dtype (``like``'s where it has none): the layers cast
    their weights to the input's dtype, so an integer image (0 … 255) truncated them to
    integers and gave another answer than the same image as floats."""
    x = jnp.asarray(x)
    return x if jnp.issubdtype(x.dtype, jnp.inexact) else x.astype(like.dtype)


def _uniform(gen: np.random.Generator, shape, fan_in, dtype):
    """Uniform init with bound 1/sqrt(fan_in), as PyTorch's default for convolutions."""
    bound = 1.0 / math.sqrt(fan_in)
    return jnp.asarray(gen.uniform(-bound, bound, shape), dtype)


class Conv(eqx.Module):
    """A dense k×k convolution on ``[H, W, C_in]`` with 'SAME' padding (or stride = kernel).

    Args:
        c_in, c_out: channels.
        kernel: kernel size k (odd for 'SAME', or equal to ``stride``).
        stride: 1, or k for a non-overlapping downsampling convolution.
        key: PRNG key.
    """

    weight: Float[Array, "k k ci co"]
    bias: Float[Array, " co"]
    stride: int = eqx.field(static=True)

    def __init__(self, c_in: int, c_out: int, kernel: int, *, stride: int = 1, key, dtype=None):
        checks.float_dtype(dtype, "Conv")  # int32 made integer weights (all 0)
        _sizes("Conv", c_in=c_in, c_out=c_out, kernel=kernel)
        if isinstance(stride, bool) or stride not in (1, kernel):  # 0 ran a 0-stride conv
            raise ValueError(f"Conv: stride must be 1 or the kernel size {kernel} (pixels), got "
                             f"{stride!r}")
        if stride == 1 and kernel % 2 == 0:  # 'SAME' padding of an even kernel shifts the
            raise ValueError(f"Conv: kernel must be odd with stride 1 ('SAME' padding of an "
                             f"even kernel shifts the image by half a pixel), or equal to "
                             f"the stride; got kernel {kernel}")
        dtype = dtype or jnp.result_type(float)
        gen = _generator(key)
        fan_in = c_in * kernel * kernel
        self.weight = _uniform(gen, (kernel, kernel, c_in, c_out), fan_in, dtype)
        self.bias = _uniform(gen, (c_out,), fan_in, dtype)
        self.stride = stride

    def __call__(self, x: Float[Array, "H W ci"]) -> Float[Array, "h w co"]:
        _channels_in(x, self.weight.shape[-2], "Conv")
        x = _as_float(x, self.weight)
        w = self.weight.astype(x.dtype)
        pad = "VALID" if self.stride > 1 else "SAME"
        y = jax.lax.conv_general_dilated(
            x[None], w, (self.stride, self.stride), pad, dimension_numbers=_DIMS
        )[0]
        return y + self.bias.astype(x.dtype)


class Pointwise(eqx.Module):
    """A 1×1 convolution (a matrix product over the channel axis)."""

    weight: Float[Array, "ci co"]
    bias: Float[Array, " co"]

    def __init__(self, c_in: int, c_out: int, *, key, dtype=None):
        checks.float_dtype(dtype, "Pointwise")
        _sizes("Pointwise", c_in=c_in, c_out=c_out)
        dtype = dtype or jnp.result_type(float)
        gen = _generator(key)
        self.weight = _uniform(gen, (c_in, c_out), c_in, dtype)
        self.bias = _uniform(gen, (c_out,), c_in, dtype)

    def __call__(self, x: Float[Array, "*s ci"]) -> Float[Array, "*s co"]:
        _channels_last(x, self.weight.shape[0], "Pointwise")
        x = _as_float(x, self.weight)
        return x @ self.weight.astype(x.dtype) + self.bias.astype(x.dtype)


class Depthwise(eqx.Module):
    """A depthwise 3×3 convolution with zero padding, as nine shifted multiply-adds."""

    weight: Float[Array, "3 3 c"]
    bias: Float[Array, " c"]

    def __init__(self, channels: int, *, key, dtype=None):
        checks.float_dtype(dtype, "Depthwise")
        _sizes("Depthwise", channels=channels)
        dtype = dtype or jnp.result_type(float)
        gen = _generator(key)
        self.weight = _uniform(gen, (3, 3, channels), 9, dtype)
        self.bias = _uniform(gen, (channels,), 9, dtype)

    def __call__(self, x: Float[Array, "H W c"]) -> Float[Array, "H W c"]:
        _channels_in(x, self.weight.shape[-1], "Depthwise")  # 1 channel broadcast to c
        x = _as_float(x, self.weight)
        h, w, _ = x.shape
        xp = jnp.pad(x, ((1, 1), (1, 1), (0, 0)))
        k = self.weight.astype(x.dtype)
        out = self.bias.astype(x.dtype)
        for i in range(3):
            for j in range(3):
                out = out + xp[i : i + h, j : j + w] * k[i, j]
        return out


class LayerNorm2d(eqx.Module):
    """Layer normalisation over the channel axis of each pixel, with a learned affine map."""

    weight: Float[Array, " c"]
    bias: Float[Array, " c"]
    eps: float = eqx.field(static=True)

    def __init__(self, channels: int, *, eps: float = 1e-6, dtype=None):
        checks.float_dtype(dtype, "LayerNorm2d")  # int32 made integer weights
        _sizes("LayerNorm2d", channels=channels)
        # A negative eps made rsqrt(var + eps) NaN for near-constant pixels.
        eps = checks.number(eps, "eps", "LayerNorm2d", lo=0, lo_open=True, hi=1.0)
        dtype = dtype or jnp.result_type(float)
        self.weight = jnp.ones((channels,), dtype)
        self.bias = jnp.zeros((channels,), dtype)
        self.eps = eps

    def __call__(self, x: Float[Array, "*s c"]) -> Float[Array, "*s c"]:
        _channels_last(x, self.weight.shape[0], "LayerNorm2d")  # 1 channel broadcast to c
        x = _as_float(x, self.weight)
        mu = jnp.mean(x, axis=-1, keepdims=True)
        var = jnp.mean(jnp.square(x - mu), axis=-1, keepdims=True)
        y = (x - mu) * jax.lax.rsqrt(var + self.eps)
        return y * self.weight.astype(x.dtype) + self.bias.astype(x.dtype)


def simple_gate(x: Float[Array, "*s c2"]) -> Float[Array, "*s c"]:
    """SimpleGate: split the channels into two halves and multiply them."""
    c = jnp.shape(x)[-1] if jnp.ndim(x) else 0
    if c % 2 or c == 0:  # before: numpy's "array split does not result in an equal division"
        raise ValueError(f"simple_gate: x must have an even, non-zero number of channels (last "
                         f"axis), got shape {jnp.shape(x)}")
    a, b = jnp.split(x, 2, axis=-1)
    return a * b


class NAFBlock(eqx.Module):
    """One NAFNet block: a gated depthwise-conv branch with simplified channel attention and a
    gated feed-forward branch, each added to the input with a zero-initialised scale."""

    norm1: LayerNorm2d
    expand: Pointwise
    dw: Depthwise
    sca: Pointwise
    project: Pointwise
    norm2: LayerNorm2d
    ffn_in: Pointwise
    ffn_out: Pointwise
    beta: Float[Array, " c"]
    gamma: Float[Array, " c"]

    def __init__(self, channels: int, *, dw_expand: int = 2, ffn_expand: int = 2, key, dtype=None):
        # An int32 dtype made integer weights; an odd expanded width failed in simple_gate
        # at the first call.
        checks.float_dtype(dtype, "NAFBlock")
        _sizes("NAFBlock", channels=channels, dw_expand=dw_expand, ffn_expand=ffn_expand)
        for arg, v in (("dw_expand", dw_expand), ("ffn_expand", ffn_expand)):
            if channels * v % 2:
                raise ValueError(f"NAFBlock: channels · {arg} must be even (SimpleGate halves "
                                 f"it), got {channels} · {v}")
        dtype = dtype or jnp.result_type(float)
        g = _generator(key)  # one stream, drawn layer by layer in this order
        c, dw_c, ffn_c = channels, channels * dw_expand, channels * ffn_expand
        self.norm1 = LayerNorm2d(c, dtype=dtype)
        self.expand = Pointwise(c, dw_c, key=g, dtype=dtype)
        self.dw = Depthwise(dw_c, key=g, dtype=dtype)
        self.sca = Pointwise(dw_c // 2, dw_c // 2, key=g, dtype=dtype)
        self.project = Pointwise(dw_c // 2, c, key=g, dtype=dtype)
        self.norm2 = LayerNorm2d(c, dtype=dtype)
        self.ffn_in = Pointwise(c, ffn_c, key=g, dtype=dtype)
        self.ffn_out = Pointwise(ffn_c // 2, c, key=g, dtype=dtype)
        self.beta = jnp.zeros((c,), dtype)
        self.gamma = jnp.zeros((c,), dtype)

    def __call__(self, x: Float[Array, "H W c"]) -> Float[Array, "H W c"]:
        _channels_in(x, self.beta.shape[0], "NAFBlock")
        x = _as_float(x, self.beta)
        y = self.dw(self.expand(self.norm1(x)))
        y = simple_gate(y)
        y = y * self.sca(jnp.mean(y, axis=(0, 1)))  # simplified channel attention
        x = x + self.project(y) * self.beta.astype(x.dtype)
        y = self.ffn_out(simple_gate(self.ffn_in(self.norm2(x))))
        return x + y * self.gamma.astype(x.dtype)


def _pixel_shuffle(x: Float[Array, "H W c4"], r: int) -> Float[Array, "Hr Wr c"]:
    h, w, c = x.shape
    x = x.reshape(h, w, c // (r * r), r, r)
    return x.transpose(0, 3, 1, 4, 2).reshape(h * r, w * r, c // (r * r))


class Upsample(eqx.Module):
    """1×1 convolution to twice the channels, then a ×2 pixel shuffle (halves the channels)."""

    conv: Pointwise

    def __init__(self, c_in: int, *, key, dtype=None):
        checks.float_dtype(dtype, "Upsample")
        _sizes("Upsample", c_in=c_in)
        if c_in % 2:  # the ×2 shuffle takes 4 of the 2·c_in channels at a time
            raise ValueError(f"Upsample: c_in must be even (the pixel shuffle makes c_in / 2 "
                             f"channels), got {c_in}")
        self.conv = Pointwise(c_in, 2 * c_in, key=key, dtype=dtype)

    def __call__(self, x):
        _channels_in(x, self.conv.weight.shape[0], "Upsample")
        return _pixel_shuffle(self.conv(x), 2)


def _blocks(blocks: Sequence[NAFBlock], y):
    """Apply a run of same-shape blocks in turn; a longer run as one ``lax.scan`` over their
    stacked parameters, so that the compiled program holds one block, not 28 (the paper's
    deepest level): the paper-scale NAFNet's gradient compiled in 27 s instead of 214 s on
    the 2-core CPU (batch 8 of 128², under load)."""
    if len(blocks) < 2:
        for b in blocks:
            y = b(y)
        return y
    _, static = eqx.partition(blocks[0], eqx.is_array)
    arrays = (eqx.filter(b, eqx.is_array) for b in blocks)
    stacked = jax.tree.map(lambda *xs: jnp.stack(xs), *arrays)
    y, _ = jax.lax.scan(lambda y, p: (eqx.combine(p, static)(y), None), y, stacked)
    return y


class NAFNet(eqx.Module):
    """A NAFNet-style UNet for image restoration (deblurring, denoising).

    Args:
        in_channels, out_channels: image channels (3 for RGB). A global residual adds the
            first ``out_channels`` input channels to the output, so ``in_channels`` may not
            be smaller; extra input channels (e.g. other estimates of the image) only feed
            the network.
        width: channels at full resolution; level ``i`` has ``width·2**i``.
        enc_blocks: NAFBlocks at each encoder level; its length is the UNet depth (number of
            ×2 downsamplings).
        middle_blocks: NAFBlocks at the bottleneck.
        dec_blocks: NAFBlocks at each decoder level (same length as ``enc_blocks``),
            listed from the deepest level up.
        key: PRNG key.
        dtype: parameter dtype (default: JAX's default float).
        identity_init: start the last convolution at zero, so that the fresh network is the
            identity (default); False draws it like the other convolutions.

    The default (width 16, one block per level, depth 3) has about 0.1 M parameters and
    trains on CPU; the paper-scale NAFNet is ``width=32, enc_blocks=(1, 1, 1, 28),
    middle_blocks=1, dec_blocks=(1, 1, 1, 1)``.

    Example:
        >>> import jax, jax.numpy as jnp
        >>> net = NAFNet(key=jax.random.PRNGKey(0))
        >>> net(jnp.zeros((24, 20, 3))).shape
        (24, 20, 3)
    """

    intro: Conv
    encoders: tuple[tuple[NAFBlock, ...], ...]
    downs: tuple[Conv, ...]
    middle: tuple[NAFBlock, ...]
    ups: tuple[Upsample, ...]
    decoders: tuple[tuple[NAFBlock, ...], ...]
    ending: Conv

    def __init__(
        self,
        in_channels: int = 3,
        out_channels: int = 3,
        *,
        width: int = 16,
        enc_blocks: Sequence[int] = (1, 1, 1),
        middle_blocks: int = 1,
        dec_blocks: Sequence[int] = (1, 1, 1),
        key: PRNGKeyArray | np.random.Generator,
        dtype=None,
        identity_init: bool = True,
    ):
        if in_channels < out_channels:
            raise ValueError(
                f"NAFNet: the global residual needs in_channels >= out_channels, got "
                f"{in_channels} and {out_channels}"
            )
        for arg, v in (("enc_blocks", enc_blocks), ("dec_blocks", dec_blocks)):
            if not isinstance(v, Sequence | np.ndarray) or isinstance(v, str):  # 2: len()
                raise ValueError(f"NAFNet: {arg} must be a sequence of block counts per "
                                 f"level, e.g. (1, 1, 1), got {v!r}")
        checks.switch(identity_init, "identity_init", "NAFNet")  # "no" is truthy
        if len(enc_blocks) != len(dec_blocks):
            raise ValueError(
                f"NAFNet: enc_blocks and dec_blocks need the same length, got {tuple(enc_blocks)}"
                f" and {tuple(dec_blocks)}"
            )
        if width < 1 or any(n < 0 for n in (*enc_blocks, *dec_blocks, middle_blocks)):
            # The message gave the width only, whichever count was wrong.
            raise ValueError(f"NAFNet: width must be >= 1 and block counts >= 0, got width "
                             f"{width}, enc_blocks {tuple(enc_blocks)}, middle_blocks "
                             f"{middle_blocks}, dec_blocks {tuple(dec_blocks)}")
        # width 2.5 failed as "'float' object cannot be interpreted as an integer", 0
        # channels as a ZeroDivisionError, and an integer dtype made integer weights.
        # width 10**6 asked for terabytes of weights: NAFNet's widths are 16 to 64, and the
        # deepest level has width · 2**levels channels.
        for arg, v, lo, hi in (("in_channels", in_channels, 1, checks.MAX_SAMPLES),
                               ("out_channels", out_channels, 1, checks.MAX_SAMPLES),
                               ("width", width, 1, MAX_WIDTH),
                               ("middle_blocks", middle_blocks, 0, MAX_BLOCKS),
                               ("levels (len(enc_blocks))", len(enc_blocks), 0, MAX_LEVELS)):
            checks.number(v, arg, "NAFNet", lo=lo, hi=hi, integer=True)
        for arg, v in (("enc_blocks", enc_blocks), ("dec_blocks", dec_blocks)):
            for n in v:
                checks.number(n, arg, "NAFNet", lo=0, hi=MAX_BLOCKS, integer=True,
                              unit="blocks per level")
        checks.float_dtype(dtype, "NAFNet")
        dtype = dtype or jnp.result_type(float)
        gen = _generator(key)
        keys = iter(lambda: gen, None)  # one host generator, drawn from in order
        self.intro = Conv(in_channels, width, 3, key=next(keys), dtype=dtype)
        encoders, downs = [], []
        c = width
        for n in enc_blocks:
            encoders.append(tuple(NAFBlock(c, key=next(keys), dtype=dtype) for _ in range(n)))
            downs.append(Conv(c, 2 * c, 2, stride=2, key=next(keys), dtype=dtype))
            c *= 2
        self.encoders, self.downs = tuple(encoders), tuple(downs)
        self.middle = tuple(NAFBlock(c, key=next(keys), dtype=dtype) for _ in range(middle_blocks))
        ups, decoders = [], []
        for n in dec_blocks:
            ups.append(Upsample(c, key=next(keys), dtype=dtype))
            c //= 2
            decoders.append(tuple(NAFBlock(c, key=next(keys), dtype=dtype) for _ in range(n)))
        self.ups, self.decoders = tuple(ups), tuple(decoders)
        ending = Conv(width, out_channels, 3, key=next(keys), dtype=dtype)
        if identity_init:
            ending = eqx.tree_at(lambda m: (m.weight, m.bias), ending,
                                 (jnp.zeros_like(ending.weight), jnp.zeros_like(ending.bias)))
        self.ending = ending

    @property
    def depth(self) -> int:
        """Number of ×2 downsamplings."""
        return len(self.downs)

    def __call__(self, x: Float[Array, "H W Cin"]) -> Float[Array, "H W Cout"]:
        """Restore one float image ``[H, W, in_channels]``; returns ``[H, W, out_channels]``.
        An integer image (sRGB codes) is refused: decode it with ``io.images.to_linear``."""
        # One rule with render and io.images: an integer image (uint8 sRGB codes) is refused,
        # to be decoded with to_linear (before: its codes ran as radiance 0…255), and so are
        # bool and complex ones; a list of numbers is read as floats.
        checks.image_dtype(x, "NAFNet", "image", "linear light")
        checks.real_values(x, "image", "NAFNet")  # a list had no .ndim
        x = _as_float(x, self.intro.weight)
        if x.ndim != 3 or x.shape[0] == 0 or x.shape[1] == 0:
            raise ValueError(f"NAFNet: expected one [H, W, C] image with H, W >= 1, got shape "
                             f"{x.shape}")
        c_in = self.intro.weight.shape[-2]
        if x.shape[-1] != c_in:  # was a conv_general_dilated feature-dimension error
            raise ValueError(f"NAFNet: expected an [H, W, {c_in}] image (in_channels {c_in}), "
                             f"got shape {x.shape}")
        # One NaN or inf pixel spreads through the convolutions to every output pixel.
        x = checks.finite_array(x, "image", "NAFNet")
        h, w, _ = x.shape
        m = 2**self.depth
        ph, pw = (-h) % m, (-w) % m
        inp = jnp.pad(x, ((0, ph), (0, pw), (0, 0)), mode="reflect") if ph or pw else x
        y = self.intro(inp)
        skips = []
        for blocks, down in zip(self.encoders, self.downs, strict=True):
            y = _blocks(blocks, y)
            skips.append(y)
            y = down(y)
        y = _blocks(self.middle, y)
        for up, blocks, skip in zip(self.ups, self.decoders, reversed(skips), strict=True):
            y = _blocks(blocks, up(y) + skip)
        y = self.ending(y)
        y = y + inp[..., : y.shape[-1]]
        return y[:h, :w]


def num_parameters(model: eqx.Module) -> int:
    """Number of scalar parameters (floating-point array leaves) of a model, or of its
    ``eqx.filter_eval_shape`` skeleton."""
    if not isinstance(model, eqx.Module):  # before: None, a list or a number counted 0
        raise TypeError(f"num_parameters: model must be an equinox Module, got "
                        f"{type(model).__name__}")
    leaves = jax.tree_util.tree_leaves(model)
    return int(
        sum(x.size for x in leaves if hasattr(x, "dtype") and jnp.issubdtype(x.dtype, jnp.inexact))
    )
