"""The jaxtyping annotations of the public API hold at run time (checked with beartype).

The library is imported under jaxtyping's import hook in a fresh process, so every annotated
function and ``eqx.Module`` of ``jaxlens`` checks its arguments' dtypes and shapes. The script
runs the public entry points on the Cooke triplet with correct inputs (no check may fire) and
with a wrongly shaped input to each (the check must fire, so the hook is really on).

The correct calls run under ``jax.eval_shape``: every annotated function is called as usual
and checks the shapes and dtypes of what it gets and returns (tracers carry both), but nothing
is compiled (the script took 40 s with the compiles, 9 s without).
"""

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import jax
    jax.config.update("jax_enable_x64", True)
    from jaxtyping import TypeCheckError, install_import_hook
    with install_import_hook("jaxlens", "beartype.beartype"):
        import jaxlens as jl
    import jax.numpy as jnp

    lens = jl.zoo.cooke_triplet()
    n = 16
    y = jnp.linspace(-1.0, 1.0, n)
    origin = jnp.stack([jnp.zeros(n), y, jnp.full(n, -5.0)], -1)
    direction = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), (n, 3))
    rays = jl.Rays(origin, direction, 0.5876)
    out = jax.eval_shape(lambda: jl.trace(lens, rays))
    path = jax.eval_shape(lambda: jl.trace_path(lens, rays))
    assert out.origin.shape == (n, 3) and path.origin.shape[-2:] == (n, 3)
    jax.eval_shape(lambda: jl.paraxial_data(lens))
    spot = jax.eval_shape(lambda: jl.analysis.angular_spot(lens))
    assert spot.per_wavelength.shape == (3, 3) and spot.chief_angle.shape == (3, 2)
    k = jax.eval_shape(lambda: jl.psf(lens, jnp.asarray([0.0, 5.0]), kernel_size=9,
                                      pixel_size=0.01))
    assert k.shape[-2:] == (9, 9)
    jax.eval_shape(lambda: jl.psf(lens, 5.0, kernel_size=9, pixel_size=0.01))  # a bare θy
    scene = jnp.ones((8, 8, 3))
    sensor = jl.Sensor(resolution=(8, 8), pixel_size=0.05)
    img = jax.eval_shape(lambda: jl.render(lens, scene, spp=1, key=jax.random.key(0),
                                           sensor=sensor, patch=8))
    assert img.shape == (8, 8, 3)

    def fires(fn):
        try:
            fn()
        except TypeCheckError:
            return True
        return False

    assert fires(lambda: jl.psf(lens, jnp.asarray([0.0, 5.0, 1.0]), kernel_size=9))
    assert fires(lambda: jl.render(lens, jnp.ones((8, 8)), spp=1, key=jax.random.key(0),
                                   sensor=sensor, patch=8))
    assert fires(lambda: jl.Rays(origin, direction, 0.5876, valid=jnp.ones(n + 1, bool)))
    print("SIGNATURES OK")
    """
)


def test_public_annotations_hold_under_the_jaxtyping_hook():
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0 and "SIGNATURES OK" in r.stdout, r.stdout[-3000:] + r.stderr[-3000:]
