"""Numerical stress, round 35c (tools/stress35c_probe.py): extreme scales, fast and wide
lenses, rays at the rim, the critical angle and tangent to a sphere, huge aspheric terms,
nearly concentric surfaces, folded mirrors and odd batch sizes. One test per gap fixed; each
names what main returned."""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.materials import ModelGlass

R = 0.005  # a 10 µm ball micro-lens (mm)


def _micro(a12):
    """The micro-lens with an r^24 term a12 (mm^-23): 1e45 is 2.4e-10 mm of sag at r = 5 µm."""
    s = jl.EvenAsphere(1 / R, 0.0, jnp.array([0.0] * 11 + [a12]))
    return jl.Lens(
        surfaces=(s, jl.Plane()),
        thickness=jnp.array([R, 1.0]),
        materials=(ModelGlass(1.5, 60.0), jl.Air()),
        epd=0.005,
    )


def test_float32_cast_refuses_a_coefficient_beyond_float32_range():
    """``Lens.astype(float32)`` of a micro-lens whose r^24 coefficient (1e45 mm^-23, finite in
    float64) is beyond float32's 3.4e38: main returned a lens holding inf there, on which
    every ray missed the surface (valid_fraction 0, no word why). Now a ValueError naming the
    surface, the value and the range; a coefficient that fits casts as before."""
    with pytest.raises(
        ValueError,
        match=r"Lens\.astype: .*surfaces\[0\]\.coeffs.*1e\+45.*"
        r"float32's range \(\|x\| <= 3\.40?3e\+38\)",
    ):
        _micro(1e45).astype(jnp.float32)
    fits = _micro(1e30).astype(jnp.float32)
    assert fits.surfaces[0].coeffs.dtype == jnp.float32
    assert np.isfinite(np.asarray(fits.surfaces[0].coeffs)).all()
    assert _micro(1e45).astype(jnp.float64).surfaces[0].coeffs[-1] == 1e45
