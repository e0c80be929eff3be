"""The real chief ray (``aiming.stop_chief_ray``) iterated to convergence at the stop centre.

Laikin's wide-angle lens (tests/test_ray_aiming_robust.py) at its full field, 50°: its real
entrance pupil lies 1.55 EPD above the paraxial one. Five plain Newton steps from the paraxial
pupil's centre (the former aiming) leave the chief ray about 1e-6 mm off the stop centre; the
converged aiming puts it there to rounding, 1e-12 mm in float64. References: the trace to the
stop of the returned ray (the definition of the chief ray) and central differences.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import aiming, sampling
from jaxlens.imaging.newton import newton_2d
from jaxlens.io.zmx import ZmxWarning
from jaxlens.optics.lens import unclipped
from jaxlens.tracing.forward import trace, trace_path

ROOT = Path(__file__).resolve().parents[1]
LAIKIN = ROOT / "tests" / "data" / "zmx" / "optiland_circular_aperture_example_with_aperture.zmx"


@pytest.fixture(scope="module")
def laikin():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ZmxWarning)
        return dataclasses.replace(jl.load(LAIKIN), aim="paraxial")


def _at_stop(lens, rays):
    return trace_path(unclipped(lens), rays, upto=lens.stop, uniform=True)[-1]


@pytest.mark.slow  # about 20 s: the aiming compiled twice (values, gradient)
def test_the_chief_ray_of_a_wide_angle_lens_crosses_the_stop_centre(laikin):
    lens = laikin
    rays = aiming.stop_chief_ray(lens, 50.0)
    at = _at_stop(lens, rays)
    assert bool(at.valid[0])
    np.testing.assert_allclose(np.asarray(at.origin[0, :2]), 0.0, rtol=0, atol=1e-12)
    # The former aiming: five plain Newton steps from the paraxial pupil's centre.
    zep = jl.paraxial.entrance_pupil_z(lens)
    d = sampling.field_direction(50.0)

    def miss(uv, _):
        o = jnp.stack([uv[0], uv[1], zep])
        return _at_stop(lens, jl.Rays(o[None], d[None], lens.primary_wavelength)).origin[0, :2]

    plain = newton_2d(miss, jnp.zeros(2), None, 5, implicit_gradient=False)
    assert float(jnp.max(jnp.abs(miss(plain, None)))) > 1e-8  # what the convergence fixes
    # The launch point lies on the paraxial entrance-pupil plane, 1.55 EPD above its centre.
    assert float(rays.origin[0, 2]) == pytest.approx(float(zep), abs=1e-12)
    assert float(rays.origin[0, 1]) / float(lens.epd) == pytest.approx(1.5547, abs=1e-4)

    # The gradient of the chief ray's image height in the field angle, and in the first
    # refracting surface's curvature (surface 0 is a dummy in air, whose derivative is 0 and
    # whose differences are round-off), is the implicit one: central differences of
    # converged aims.
    assert not isinstance(lens.materials[1], jl.Air)

    def image_y(field, c1):
        m = eqx.tree_at(lambda q: q.surfaces[1].c, lens, c1)
        out = trace(unclipped(m), aiming.stop_chief_ray(m, field), uniform=True)
        return out.origin[0, 1]

    c1 = lens.surfaces[1].c
    f = jax.jit(image_y)
    g_field, g_c = jax.jit(jax.grad(image_y, argnums=(0, 1)))(jnp.asarray(50.0), c1)
    h_f, h_c = 1e-4, 1e-7 * max(1.0, abs(float(c1)))
    fd_field = (f(50.0 + h_f, c1) - f(50.0 - h_f, c1)) / (2 * h_f)
    fd_c = (f(jnp.asarray(50.0), c1 + h_c) - f(jnp.asarray(50.0), c1 - h_c)) / (2 * h_c)
    assert float(g_field) == pytest.approx(float(fd_field), rel=1e-6)
    assert float(g_c) == pytest.approx(float(fd_c), rel=1e-5)
