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

    @eqx.filter_jit
    def loss(net):
        return jnp.mean((jax.vmap(net)(x) - x) ** 2)

    g = eqx.filter_grad(loss)(small_net)
    leaves = jax.tree_util.tree_leaves(eqx.filter(g, eqx.is_inexact_array))
    assert all(bool(jnp.all(jnp.isfinite(v))) for v in leaves)
    assert sum(float(jnp.sum(jnp.abs(v))) for v in leaves) > 0


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


def test_fresh_block_is_identity():
    # beta and gamma start at zero: a new block adds nothing to its input.
    blk = NAFBlock(6, key=KEY)
    x = jax.random.normal(KEY, (5, 7, 6))
    np.testing.assert_array_equal(np.asarray(blk(x)), np.asarray(x))


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
