"""NAFNet building blocks and shapes (jaxlens.nets)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.nets import (
    Conv,
    Depthwise,
    LayerNorm2d,
    NAFBlock,
    NAFNet,
    _pixel_shuffle,
    num_parameters,
    simple_gate,
)

KEY = jax.random.PRNGKey(0)


@pytest.fixture(scope="module")
def small_net():
    return NAFNet(
        width=4, enc_blocks=(1, 1), middle_blocks=1, dec_blocks=(1, 1), key=KEY, dtype=jnp.float32
    )


@eqx.filter_jit
def _apply(net, x):
    return net(x)


@pytest.mark.parametrize("shape", [(16, 16, 3), (13, 22, 3)])
def test_nafnet_keeps_shape_and_pads_odd_sizes(small_net, shape):
    x = jax.random.uniform(KEY, shape, jnp.float32)
    y = _apply(small_net, x)
    assert y.shape == shape and y.dtype == jnp.float32
    assert bool(jnp.all(jnp.isfinite(y)))


def test_nafnet_batches_with_vmap_and_has_gradients(small_net):
    x = jax.random.uniform(KEY, (2, 8, 8, 3), jnp.float32)

    def loss(net):
        return jnp.mean((jax.vmap(net)(x) - 0.5 * x) ** 2)  # a fresh net returns x

    # One compiled gradient, checked in NumPy (op by op: two programs, and four small ones
    # per leaf shape for the checks).
    g = eqx.filter_jit(eqx.filter_grad(loss))(small_net)
    leaves = [np.asarray(v) for v in jax.tree_util.tree_leaves(eqx.filter(g, eqx.is_inexact_array))]
    assert all(np.all(np.isfinite(v)) for v in leaves)
    assert sum(float(np.sum(np.abs(v))) for v in leaves) > 0


def test_default_is_small_and_options_scale_it():
    n_default = num_parameters(NAFNet(key=KEY))
    n_wide = num_parameters(NAFNet(width=32, key=KEY))
    assert 5e4 < n_default < 5e5
    assert n_wide > 3 * n_default


def test_bad_options_raise():
    with pytest.raises(ValueError, match="same length"):
        NAFNet(enc_blocks=(1, 1), dec_blocks=(1,), key=KEY)
    with pytest.raises(ValueError, match="in_channels"):
        NAFNet(in_channels=1, out_channels=3, key=KEY)


def test_extra_input_channels_feed_the_network_but_not_the_residual():
    net = NAFNet(in_channels=5, out_channels=3, width=4, enc_blocks=(1,), dec_blocks=(1,),
                 key=KEY)
    x = jax.random.normal(KEY, (12, 10, 5))
    np.testing.assert_array_equal(np.asarray(net(x)), np.asarray(x[..., :3]))  # fresh: identity
    w = net.ending.weight
    trained = eqx.tree_at(lambda m: m.ending.weight, net, 0.1 * jax.random.normal(KEY, w.shape))
    other = x.at[..., 3:].set(0.0)
    assert trained(x).shape == (12, 10, 3)
    assert float(jnp.max(jnp.abs(trained(x) - trained(other)))) > 1e-3  # the extras count


def test_fresh_block_is_identity():
    # beta and gamma start at zero: a new block adds nothing to its input.
    blk = NAFBlock(6, key=KEY)
    x = jax.random.normal(KEY, (5, 7, 6))
    np.testing.assert_array_equal(np.asarray(blk(x)), np.asarray(x))


def test_fresh_network_is_exactly_the_identity():
    """The last convolution starts at zero (and every block's scales do), so a fresh network
    returns its input bit for bit; ``identity_init=False`` draws the last layer at random."""
    x = jax.random.uniform(KEY, (13, 22, 3), jnp.float32)
    net = NAFNet(width=4, enc_blocks=(1, 1), dec_blocks=(1, 1), key=KEY, dtype=jnp.float32)
    np.testing.assert_array_equal(np.asarray(_apply(net, x)), np.asarray(x))
    rand = NAFNet(width=4, enc_blocks=(1, 1), dec_blocks=(1, 1), key=KEY, dtype=jnp.float32,
                  identity_init=False)
    assert float(jnp.max(jnp.abs(_apply(rand, x) - x))) > 1e-3


def test_layernorm2d_normalises_each_pixel_over_channels():
    x = jax.random.normal(KEY, (4, 5, 8)) * 3.0 + 1.5
    y = LayerNorm2d(8)(x)
    np.testing.assert_allclose(np.asarray(jnp.mean(y, -1)), 0.0, atol=1e-5)
    np.testing.assert_allclose(np.asarray(jnp.var(y, -1)), 1.0, rtol=1e-3)


def test_simple_gate_multiplies_the_two_halves():
    x = jnp.arange(12.0).reshape(1, 2, 6)
    np.testing.assert_array_equal(np.asarray(simple_gate(x)), np.asarray(x[..., :3] * x[..., 3:]))


def test_depthwise_matches_grouped_convolution():
    dw = Depthwise(3, key=KEY)
    x = jax.random.normal(KEY, (6, 5, 3))
    ref = (
        jax.lax.conv_general_dilated(
            x[None],
            dw.weight[:, :, None, :],
            (1, 1),
            "SAME",
            dimension_numbers=("NHWC", "HWIO", "NHWC"),
            feature_group_count=3,
        )[0]
        + dw.bias
    )
    np.testing.assert_allclose(np.asarray(dw(x)), np.asarray(ref), rtol=1e-5, atol=1e-6)


def test_strided_conv_halves_and_pixel_shuffle_doubles():
    down = Conv(2, 4, 2, stride=2, key=KEY)
    x = jax.random.normal(KEY, (6, 8, 2))
    assert down(x).shape == (3, 4, 4)
    # Pixel shuffle (PyTorch's order): channel 4·ch + 2a + b of pixel (i, j) becomes
    # channel ch of pixel (2i + a, 2j + b).
    y = jnp.arange(2 * 3 * 8.0).reshape(2, 3, 8)
    z = _pixel_shuffle(y, 2)
    assert z.shape == (4, 6, 2)
    for a in range(2):
        for b in range(2):
            for ch in range(2):
                np.testing.assert_array_equal(
                    np.asarray(z[a::2, b::2, ch]), np.asarray(y[..., 4 * ch + 2 * a + b])
                )


# --- the block and the whole network against a direct NumPy computation -----------------------
# NAFNet (Chen et al., ECCV 2022), written out with NumPy loops from the paper's definition:
# x1 = x + β·Proj(SCA(SG(DW(Expand(LN1(x)))))), out = x1 + γ·FFNout(SG(FFNin(LN2(x1)))),
# SCA(y) = y · (W·mean_{hw}(y) + b); the UNet adds each encoder level's output to the
# decoder input of that level, and the global residual adds the (padded) input.


def _np_ln(x, w, b, eps=1e-6):
    mu = x.mean(-1, keepdims=True)
    var = ((x - mu) ** 2).mean(-1, keepdims=True)
    return (x - mu) / np.sqrt(var + eps) * w + b


def _np_conv(x, w, b, stride=1):
    """Dense convolution ``[H, W, ci]`` × ``[k, k, ci, co]``, 'SAME' zero padding (stride 1) or
    non-overlapping windows (stride = k)."""
    k = w.shape[0]
    if stride == 1:
        p = k // 2
        x = np.pad(x, ((p, p), (p, p), (0, 0)))
        h, wd = x.shape[0] - k + 1, x.shape[1] - k + 1
    else:
        h, wd = x.shape[0] // k, x.shape[1] // k
    out = np.zeros((h, wd, w.shape[3]))
    for i in range(h):
        for j in range(wd):
            patch = x[i * stride : i * stride + k, j * stride : j * stride + k]
            out[i, j] = np.einsum("abc,abcd->d", patch, w)
    return out + b


def _np_block(blk, x):
    g = {k: np.asarray(v, np.float64) for k, v in {
        "n1w": blk.norm1.weight, "n1b": blk.norm1.bias, "ew": blk.expand.weight,
        "eb": blk.expand.bias, "dw": blk.dw.weight, "db": blk.dw.bias, "sw": blk.sca.weight,
        "sb": blk.sca.bias, "pw": blk.project.weight, "pb": blk.project.bias,
        "n2w": blk.norm2.weight, "n2b": blk.norm2.bias, "fiw": blk.ffn_in.weight,
        "fib": blk.ffn_in.bias, "fow": blk.ffn_out.weight, "fob": blk.ffn_out.bias,
        "beta": blk.beta, "gamma": blk.gamma}.items()}
    y = _np_ln(x, g["n1w"], g["n1b"]) @ g["ew"] + g["eb"]
    dw = g["dw"][:, :, None, :] * np.eye(y.shape[-1])[None, None]  # depthwise as dense
    y = _np_conv(y, dw, g["db"])
    c = y.shape[-1] // 2
    y = y[..., :c] * y[..., c:]
    y = y * (y.mean(axis=(0, 1)) @ g["sw"] + g["sb"])
    x = x + (y @ g["pw"] + g["pb"]) * g["beta"]
    y = _np_ln(x, g["n2w"], g["n2b"]) @ g["fiw"] + g["fib"]
    c = y.shape[-1] // 2
    y = y[..., :c] * y[..., c:]
    return x + (y @ g["fow"] + g["fob"]) * g["gamma"]


def _randomise(model, seed):
    """Every floating-point leaf drawn at random (β, γ and the norms' affine maps too)."""
    rng = np.random.default_rng(seed)
    leaves, tree = jax.tree.flatten(model)
    new = [jnp.asarray(rng.normal(0.0, 0.5, x.shape), x.dtype)
           if eqx.is_inexact_array(x) else x for x in leaves]
    return jax.tree.unflatten(tree, new)


def test_block_with_nonzero_scales_matches_numpy():
    blk = _randomise(NAFBlock(4, key=KEY, dtype=jnp.float64), 1)
    assert np.all(np.abs(np.asarray(blk.beta)) > 0) and np.all(np.abs(np.asarray(blk.gamma)) > 0)
    x = np.random.default_rng(2).normal(size=(5, 6, 4))
    got = np.asarray(blk(jnp.asarray(x)))
    want = _np_block(blk, x)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10)
    assert np.abs(want - x).max() > 0.1  # the block does something


def _np_shuffle(x, r=2):
    """PyTorch's pixel shuffle: channel c·r² + a·r + b of (i, j) → channel c of (ri+a, rj+b)."""
    h, w, c4 = x.shape
    c = c4 // (r * r)
    out = np.zeros((h * r, w * r, c))
    for ch in range(c):
        for a in range(r):
            for b in range(r):
                out[a::r, b::r, ch] = x[..., ch * r * r + a * r + b]
    return out


def _np_net(net, x):
    h, w, _ = x.shape
    m = 2 ** len(net.downs)
    inp = np.pad(x, ((0, (-h) % m), (0, (-w) % m), (0, 0)), mode="reflect")
    y = _np_conv(inp, np.asarray(net.intro.weight), np.asarray(net.intro.bias))
    skips = []
    for blocks, down in zip(net.encoders, net.downs, strict=True):
        for b in blocks:
            y = _np_block(b, y)
        skips.append(y)
        y = _np_conv(y, np.asarray(down.weight), np.asarray(down.bias), stride=2)
    for b in net.middle:
        y = _np_block(b, y)
    for up, blocks, skip in zip(net.ups, net.decoders, skips[::-1], strict=True):
        y = _np_shuffle(y @ np.asarray(up.conv.weight) + np.asarray(up.conv.bias)) + skip
        for b in blocks:
            y = _np_block(b, y)
    y = _np_conv(y, np.asarray(net.ending.weight), np.asarray(net.ending.bias)) + inp
    return y[:h, :w]


def test_network_with_nonzero_scales_matches_numpy():
    net = NAFNet(width=4, enc_blocks=(1, 1), middle_blocks=1, dec_blocks=(1, 1), key=KEY,
                 dtype=jnp.float64)
    net = _randomise(net, 3)
    x = np.random.default_rng(4).random((7, 6, 3))  # odd size: reflect-padded to 8 × 8
    got = np.asarray(_apply(net, jnp.asarray(x)))
    np.testing.assert_allclose(got, _np_net(net, x), rtol=1e-9, atol=1e-9)


def test_runs_of_several_blocks_match_numpy_and_have_gradients():
    """Runs of two or more blocks go through one ``lax.scan`` (the paper's 28-block level
    compiles as one block); they still apply every block in turn, gradients included."""
    net = NAFNet(width=4, enc_blocks=(1, 3), middle_blocks=2, dec_blocks=(2, 1), key=KEY,
                 dtype=jnp.float64)
    net = _randomise(net, 5)
    x = np.random.default_rng(6).random((8, 8, 3))
    xj = jnp.asarray(x)
    # Compiled once each: op by op, the network and its gradient took 1.5x as long (and
    # jax.jit of the gradient longer still).
    loss = eqx.filter_jit(lambda n: jnp.sum(n(xj) ** 2))
    apply = eqx.filter_jit(_apply)
    got = np.asarray(apply(net, xj))
    np.testing.assert_allclose(got, _np_net(net, x), rtol=1e-9, atol=1e-9)
    g = eqx.filter_grad(loss)(net)
    w = net.encoders[1][2].ffn_out.weight  # in the third block of the scanned run
    eps, i = 1e-6, (0, 1)

    def loss_at(delta):  # the loss of the network's compiled output (no third program)
        out = apply(eqx.tree_at(lambda n: n.encoders[1][2].ffn_out.weight, net,
                                w.at[i].add(delta)), xj)
        return float(np.sum(np.asarray(out) ** 2))

    fd = (loss_at(eps) - loss_at(-eps)) / (2 * eps)
    np.testing.assert_allclose(float(g.encoders[1][2].ffn_out.weight[i]), fd, rtol=1e-6)
    assert abs(fd) > 1e-3


def test_initialisation_is_pytorch_default_and_keeps_the_dtype():
    """Weights and biases uniform in ±1/√fan_in (fan_in = c_in·k·k; 9 for the depthwise
    3×3), as PyTorch initialises convolutions; the requested dtype is kept."""
    conv = Conv(8, 64, 3, key=KEY, dtype=jnp.float32)
    dw = Depthwise(256, key=KEY, dtype=jnp.float32)
    for w, fan_in in ((conv.weight, 72), (conv.bias, 72), (dw.weight, 9), (dw.bias, 9)):
        bound = 1 / np.sqrt(fan_in)
        w = np.asarray(w)
        assert w.dtype == np.float32
        tight = 1 - 8 / w.size  # the extremes of n uniform draws lie within ~1/n of the bound
        assert np.abs(w).max() <= bound and np.abs(w).max() > tight * bound
        assert w.min() < -tight * bound and abs(w.mean()) < 0.2 * bound
    net = NAFNet(width=4, enc_blocks=(1,), dec_blocks=(1,), key=KEY, dtype=jnp.float32)
    assert {x.dtype for x in jax.tree.leaves(net) if eqx.is_array(x)} == {jnp.dtype("float32")}


def test_building_under_jit_is_refused():
    with pytest.raises(ValueError, match=r"^NAFNet: parameters are drawn on the host; build the "
                       r"network outside jit/eval_shape \(it takes well under a second\)"):
        jax.jit(lambda k: NAFNet(width=4, enc_blocks=(1,), dec_blocks=(1,), key=k))(KEY)


def test_block_widths_are_the_papers_expansions():
    """NAFNet's block expands to 2c channels in both branches (DW_Expand = FFN_Expand = 2);
    the gates halve them back to c."""
    c = 8
    b = NAFBlock(c, key=jax.random.PRNGKey(0))
    shapes = {n: getattr(b, n).weight.shape for n in
              ("expand", "sca", "project", "ffn_in", "ffn_out")}
    assert shapes == {"expand": (c, 2 * c), "sca": (c, c), "project": (c, c),
                      "ffn_in": (c, 2 * c), "ffn_out": (c, c)}
    assert b.dw.weight.shape[-1] == 2 * c


def test_default_architecture_and_its_bounds():
    """The default is width 16 with three levels of one block, one middle block, and a zero
    last layer; it pads to a multiple of 2³. Width ≥ 1 and block counts ≥ 0 are the limits."""
    net = NAFNet(key=KEY)
    assert net.depth == 3 and net.intro.weight.shape[-1] == 16
    assert [len(e) for e in net.encoders] == [1, 1, 1] and len(net.middle) == 1
    assert [len(d) for d in net.decoders] == [1, 1, 1]
    assert not np.any(np.asarray(net.ending.weight)) and not np.any(np.asarray(net.ending.bias))
    x = jax.random.uniform(KEY, (16, 21, 3), jnp.float32)  # pads the width only, by 3
    np.testing.assert_allclose(np.asarray(_apply(net, x)), np.asarray(x), atol=1e-6)
    net = NAFNet(width=1, enc_blocks=(0,), middle_blocks=0, dec_blocks=(0,), key=KEY,
                 identity_init=False)
    assert np.any(np.asarray(net.ending.weight))
    with pytest.raises(ValueError, match="width must be >= 1"):
        NAFNet(width=0, key=KEY)
    with pytest.raises(ValueError, match="block counts >= 0"):
        NAFNet(middle_blocks=-1, key=KEY)
    with pytest.raises(ValueError, match="block counts >= 0"):
        NAFNet(dec_blocks=(1, 1, -1), key=KEY)
    with pytest.raises(ValueError, match=r"one \[H, W, C\] image"):
        net(jnp.zeros((2, 8, 8, 3)))
