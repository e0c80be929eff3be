"""Bad input to the paraxial, analysis and PSF entry points is refused with a clear message."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import spots
from jaxlens.imaging import psf as P
from jaxlens.imaging.radiometry import relative_illumination
from jaxlens.optics import paraxial

COOKE = jl.zoo.cooke_triplet()
SMALL = P.GeometricPSF(pupil=4)


def singlet(sd=np.inf):
    """The README's N-BK7 singlet (``sd``: semi-diameter of both surfaces, mm)."""
    return jl.Lens(
        surfaces=(jl.Sphere(1 / 30.0, semi_diameter=sd), jl.Sphere(-1 / 45.0, semi_diameter=sd)),
        thickness=jnp.array([6.0, 45.0]),
        materials=(jl.get_material("N-BK7"), jl.Air()),
        epd=10.0, fields=jnp.array([0.0, 10.0]),
    )


def test_paraxial_checks_wavelength_and_field():
    lens = singlet()
    with pytest.raises(ValueError, match=r"efl: wavelength 587.6 µm is outside 0.3–2.5 µm.*"
                                         r"587.6 nm is 0.5876 µm"):
        jl.efl(lens, 587.6)
    with pytest.raises(ValueError, match="paraxial_data: wavelength 0.2 µm is outside"):
        jl.paraxial_data(lens, 0.2)
    for wl in (0.0, -0.5, 5.0):
        with pytest.raises(ValueError, match="efl: wavelength"):
            jl.efl(COOKE, wl)
    with pytest.raises(ValueError, match="bfl: wavelength nan"):
        jl.bfl(COOKE, float("nan"))
    for field in (90.0, 180.0, float("nan")):
        with pytest.raises(ValueError, match=r"image_height: field_deg must be finite angles "
                                             r"in \(-90, 90\) deg"):
            paraxial.image_height(lens, field)
    with pytest.raises(ValueError, match="paraxial_chief_ray: field_deg .* got 135 deg"):
        paraxial.paraxial_chief_ray(lens, 135.0)


def test_paraxial_checks_jit_and_grad():
    """The checks stay inside jit and grad (design losses use these functions): good values
    differentiate as before, bad traced ones raise when the computation runs."""
    lens = singlet()
    f = jax.jit(jax.grad(lambda w: jl.efl(lens, w)))
    h = 1e-5
    fd = (jl.efl(lens, 0.55 + h) - jl.efl(lens, 0.55 - h)) / (2 * h)
    np.testing.assert_allclose(f(0.55), fd, rtol=1e-6)
    g = eqx.filter_jit(eqx.filter_grad(lambda lens: jl.efl(lens, 0.55)))(lens)
    assert np.all(np.isfinite(g.thickness)) and np.any(g.thickness != 0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="efl: wavelength outside"):
        eqx.filter_jit(lambda w: jl.efl(lens, w))(jnp.asarray(587.6))
    with pytest.raises(eqx.EquinoxRuntimeError, match="image_height: field_deg must be"):
        eqx.filter_jit(lambda a: paraxial.image_height(lens, a))(jnp.asarray(120.0))


def test_relative_illumination_checks_fields_and_pupil():
    for fields in ([0.0, 180.0], [120.0], [float("nan")], [[5.0, 95.0]]):
        with pytest.raises(ValueError, match=r"relative_illumination: fields must be finite "
                                             r"angles in \(-90, 90\) deg"):
            relative_illumination(COOKE, jnp.array(fields))
    for pupil in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match=r"relative_illumination: pupil must be a whole "
                                             r"number in \[1, inf\) cells per side"):
            relative_illumination(COOKE, jnp.array([10.0]), pupil=pupil)
    with pytest.raises(ValueError, match="relative_illumination: wavelength 587.6 µm"):
        relative_illumination(COOKE, 10.0, wavelength=587.6)


def test_distortion_of_xy_fields_is_radial():
    """(θx, θy) fields: the radial distortion of a rotationally symmetric lens matches the
    y-field result at the same radial angle, in every direction."""
    lens = singlet(sd=8.0)
    t = np.tan(np.deg2rad(10.0))
    diag = float(np.rad2deg(np.arctan(np.hypot(t, t))))  # the radial angle of (10°, 10°)
    d1 = spots.distortion(lens, fields=jnp.array([0.0, 7.0, 14.0, diag]))
    d2 = spots.distortion(lens, fields=jnp.array(
        [[0.0, 0.0], [0.0, 7.0], [14.0, 0.0], [0.0, -14.0], [-14.0, 0.0], [10.0, 10.0]]))
    pick = [0, 1, 2, 2, 2, 3]
    for name in ("chief_height", "f_tan", "paraxial_height", "percent_ftan", "percent_paraxial"):
        np.testing.assert_allclose(getattr(d2, name), np.asarray(getattr(d1, name))[pick],
                                   rtol=1e-9, atol=1e-12, err_msg=name)
    # The x field's chief ray lands near its paraxial image point (-100 % when x was lost).
    assert abs(float(d2.percent_paraxial[2])) < 1.0
    with pytest.raises(ValueError, match=r"distortion: fields must be \[F\] θy or \[F, 2\].*"
                                         r"got shape \(3, 3\)"):
        spots.distortion(COOKE, fields=jnp.zeros((3, 3)))


def test_rms_spot_checks_pupil_shape_first():
    for pupil in (jnp.zeros((5, 3)), jnp.zeros(5)):
        with pytest.raises(ValueError, match=r"rms_spot: pupil must be \[M, 2\] normalised "
                                             r"pupil points"):
            spots.rms_spot(COOKE, pupil=pupil)


def test_psf_checks_key():
    for key in (3, jnp.array(3), jnp.zeros(3, jnp.uint32), jax.random.split(jax.random.key(0))):
        with pytest.raises(ValueError, match=r"psf: key must be None or one PRNG key"):
            P.psf(COOKE, 0.0, kernel_size=3, pixel_size=0.01, model=SMALL, key=key)
        with pytest.raises(ValueError, match=r"render: key must be one PRNG key"):
            jl.render(COOKE, jnp.zeros((8, 8, 3)), spp=1, key=key,
                      sensor=jl.Sensor((8, 8), 0.01))


def test_yield_fraction_refuses_a_threshold_that_is_not_a_length():
    from jaxlens.analysis.tolerance import yield_fraction

    assert yield_fraction([1.0, 3.0], 2.0) == 0.5
    for bad in (-1.0, 0.0, float("nan")):
        with pytest.raises(ValueError, match=r"yield_fraction: threshold_um must be"):
            yield_fraction([1.0, 3.0], bad)


def test_psf_map_refuses_a_dark_grid_field():
    """A sensor far beyond the lens's coverage: psf_map names the field that gets no light
    (it returned all-zero kernels with truncated NaN)."""
    huge = jl.Sensor((100, 100), 10.0)  # 1 m wide: the grid's edge fields are at ±84°
    with pytest.raises(ValueError, match=r"psf_map: no ray of the beam reaches the image "
                                         r"surface at grid point \(row 0, col 0\).*84.26, 0\) "
                                         r"deg"):
        P.psf_map(COOKE, grid=(1, 2), kernel_size=3, pixel_size=0.01, model=SMALL,
                  sensor=huge, center="ideal", newton_iters=0)


def test_mtf_diffraction_must_be_a_bool():
    for value in ("no", 0, None):
        with pytest.raises(ValueError, match="mtf: diffraction must be True or False"):
            P.mtf(COOKE, 0.0, frequencies=jnp.array([0.0, 10.0]), model=SMALL,
                  diffraction=value)


EMPTY = jnp.zeros((0,))


@pytest.mark.parametrize("call, message", [
    (lambda: spots.rms_spot(COOKE, fields=EMPTY), r"rms_spot: fields must be .* F >= 1"),
    (lambda: spots.rms_spot(COOKE, wavelengths=EMPTY), r"rms_spot: wavelengths .* W >= 1"),
    (lambda: spots.distortion(COOKE, fields=jnp.zeros((0, 2))), r"distortion: fields .* F >= 1"),
    (lambda: spots.clear_semi_diameters(COOKE, fields=EMPTY), "clear_semi_diameters: fields"),
    (lambda: relative_illumination(COOKE, EMPTY), r"relative_illumination: fields .* F >= 1"),
    (lambda: P.mtf(COOKE, 0.0, wavelengths=EMPTY), r"mtf: wavelengths .* W >= 1"),
    (lambda: P.psf(COOKE, 0.0, wavelength=EMPTY, pixel_size=0.01), "psf: wavelength must be"),
], ids=["rms_spot-fields", "rms_spot-wavelengths", "distortion", "clear_semi_diameters",
        "relative_illumination", "mtf", "psf"])
def test_empty_fields_and_wavelengths_are_refused(call, message):
    with pytest.raises(ValueError, match=message):
        call()
