"""Sharded rendering: tiles spread over 4 host devices give the single-device image.

``tests/conftest.py`` sets ``XLA_FLAGS=--xla_force_host_platform_device_count=4``.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.sharding import Mesh

import jaxlens
from jaxlens.imaging import render as R

KEY = jax.random.PRNGKey(0)
SENSOR = jaxlens.Sensor((12, 18), 2.0)  # as in test_render: its compiled render is reused


@pytest.fixture(scope="module")
def mesh():
    devices = jax.devices()
    if len(devices) < 4:
        pytest.skip("needs 4 devices (XLA_FLAGS=--xla_force_host_platform_device_count=4)")
    return Mesh(np.array(devices[:4]), ("tiles",))


def test_sharded_render_equals_single_device(mesh):
    """6 tiles over 4 devices (padded to 8): every tile draws the same random numbers."""
    lens = jaxlens.zoo.cooke_triplet()
    rng = np.random.default_rng(0)
    scene = jnp.asarray(rng.random((12, 18, 3)))
    one = R.render(lens, scene, spp=16, key=KEY, sensor=SENSOR, patch=6)
    sharded = R.render(lens, scene, spp=16, key=KEY, sensor=SENSOR, patch=6, mesh=mesh)
    np.testing.assert_allclose(sharded, one, rtol=1e-12, atol=1e-12)
    # The work went to the mesh: the result lives on all four of its devices (a render that
    # ignored the mesh would leave it on one).
    assert sharded.devices() == set(mesh.devices.flat)
    assert len(one.devices()) == 1


def test_sharded_mesh_must_be_a_mesh(mesh):
    lens = jaxlens.zoo.cooke_triplet()
    with pytest.raises(ValueError, match="mesh"):
        R.render(lens, jnp.ones((12, 18, 3)), spp=4, key=KEY, sensor=SENSOR, mesh="cpu")


@pytest.mark.slow
def test_sharded_gradient_equals_single_device(mesh):
    lens = jaxlens.zoo.cooke_triplet()
    scene = jnp.asarray(np.random.default_rng(0).random((12, 18, 3)))
    fp = R.footprints(lens, sensor=SENSOR)

    def loss(t, mesh):
        import equinox as eqx

        lens_t = eqx.tree_at(lambda m: m.thickness, lens, t)
        img = R.render(lens_t, scene, spp=4, key=KEY, sensor=SENSOR, patch=6, mesh=mesh,
                       method=R.RayRender(footprints=fp))
        return jnp.mean(img**2)

    g1 = jax.grad(loss)(lens.thickness, None)
    g4 = jax.grad(loss)(lens.thickness, mesh)
    np.testing.assert_allclose(g4, g1, rtol=1e-10, atol=1e-14)
