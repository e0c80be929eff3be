"""Paraxial data of aspheres with an r² term (A2 ≠ 0), against an independent y-nu trace.

The sag z = c r²/(1 + √(1 − (1+k)c²r²)) + a₁r² + a₂r⁴ + … has vertex curvature c + 2a₁
(the r² term's second derivative), so a surface's paraxial power is (n' − n)(c + 2a₁); the
conic constant and a₂, a₃, … do not enter. The y-nu trace below is written from the
textbook refraction and transfer equations, n'u' = nu − yφ and y' = y + t·u'.
"""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl

WL = 0.5875618


def _lens():
    glass1, glass2 = jl.ModelGlass(1.62, 40.0), jl.ModelGlass(1.52, 60.0)
    surfaces = (
        jl.EvenAsphere(1 / 25.0, -0.8, (0.004, -2e-5, 1e-7)),
        jl.EvenAsphere(-1 / 60.0, 1.5, (-0.006, 3e-5, 0.0)),
        jl.Stop(3.0),
        jl.EvenAsphere(0.0, 0.0, (0.01, 0.0, 0.0)),  # a flat base: all power from a₁
        jl.EvenAsphere(-1 / 40.0, 0.0, (0.0025, -1e-5, 0.0)),
    )
    return jl.Lens(surfaces=surfaces, thickness=jnp.array([4.0, 2.0, 1.5, 3.0, 30.0]),
                   materials=(glass1, jl.Air(), jl.Air(), glass2, jl.Air()), stop=2, epd=6.0)


def _ynu(lens):
    """EFL and BFL (mm) from a marginal ray y = 1, u = 0 at infinity."""
    n = 1.0
    y, nu = 1.0, 0.0
    t = np.asarray(lens.thickness, float)
    for i, s in enumerate(lens.surfaces):
        coeffs = np.asarray(getattr(s, "coeffs", [0.0]), float)
        cv = float(s.c) + 2.0 * (coeffs[0] if coeffs.size else 0.0)
        n2 = float(lens.materials[i].index(WL))
        nu = nu - y * (n2 - n) * cv
        n = n2
        if i < len(lens.surfaces) - 1:
            y = y + t[i] * nu / n
    u = nu / n  # image space is air
    return -1.0 / u, -y / u


def test_efl_and_bfl_with_a2_match_an_independent_ynu_trace():
    lens = _lens()
    efl, bfl = _ynu(lens)
    pd = jl.paraxial_data(lens)
    assert float(pd.efl) == pytest.approx(efl, rel=1e-10)
    assert float(pd.bfl) == pytest.approx(bfl, rel=1e-10)
    assert float(pd.fnum) == pytest.approx(efl / 6.0, rel=1e-10)
    # Without the r² terms the lens is a different lens: the test can tell.
    flat = _ynu(jl.Lens(
        surfaces=tuple(jl.EvenAsphere(s.c, 0.0, (0.0,)) if hasattr(s, "coeffs") else s
                       for s in lens.surfaces),
        thickness=lens.thickness, materials=lens.materials, stop=2, epd=6.0))
    assert abs(flat[0] - efl) > 0.1 * abs(efl)


def test_a_near_axis_real_ray_focuses_at_the_paraxial_bfl():
    """The tracer's sag agrees: a ray at 1 µm height crosses the axis at the y-nu BFL."""
    lens = _lens()
    _, bfl = _ynu(lens)
    pupil = jnp.array([[0.0, 1e-3 / 3.0]])  # 1 µm of the 3 mm pupil radius
    rays = jl.sampling.collimated(lens, 0.0, pupil, WL)
    out = jl.trace(lens, rays)
    o, d = np.asarray(out.origin[0]), np.asarray(out.direction[0])
    last = float(lens.vertex_z()[-1])
    z_cross = o[2] - o[1] * d[2] / d[1]
    assert z_cross - last == pytest.approx(bfl, abs=1e-6)


def test_an_afocal_lens_has_an_infinite_positive_focal_length():
    """A plane-parallel plate has zero power: its EFL is +inf, never −inf (the sign of a
    zero from the system matrix must not decide it)."""
    glass = jl.ModelGlass(1.52, 60.0)
    plate = jl.Lens(surfaces=(jl.Stop(3.0), jl.EvenAsphere(0.0, 0.0, ()),
                              jl.EvenAsphere(0.0, 0.0, ())),
                    thickness=jnp.array([1.0, 5.0, 10.0]),
                    materials=(jl.Air(), glass, jl.Air()), stop=0, epd=4.0)
    pd = jl.paraxial_data(plate)
    assert float(pd.efl) == np.inf and float(jl.efl(plate)) == np.inf
    assert float(pd.fnum) == np.inf
