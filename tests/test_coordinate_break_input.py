"""What a coordinate break refuses or warns about: an aperture it cannot apply, and tilts that
look like radians (a fold typed as 1.5708 turns the frame by 1.6°, not 90°)."""

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.optics.coordinates import CoordinateBreak


@pytest.mark.parametrize("value", [0.785398, 1.5708, -3.1416, 2.35619, 4.71239, 6.28319])
def test_tilts_that_are_common_angles_in_radians_are_warned_about(value):
    with pytest.warns(UserWarning, match=r"in radians; tilts are in degrees"):
        CoordinateBreak(tilt_y=jnp.asarray(value))


@pytest.mark.parametrize("value", [0.0, 45.0, 90.0, -180.0, 0.79, 1.5, 3.2, 7.0, 1e-5])
def test_tilts_in_degrees_are_not_warned_about(value):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        CoordinateBreak(tilt_x=jnp.asarray(value), tilt_z=jnp.asarray(value))


def test_a_finite_semi_diameter_is_refused_and_traced_values_pass():
    with pytest.raises(ValueError, match="clips no ray"):
        CoordinateBreak(semi_diameter=jnp.asarray(5.0))
    assert np.isinf(CoordinateBreak().semi_diameter)

    @jax.jit
    def build(t):  # traced values are not checked, so programs do not change
        return CoordinateBreak(tilt_x=t, semi_diameter=t).tilt_x

    assert float(build(jnp.asarray(1.5708))) == pytest.approx(1.5708)
