"""PSFs against analytic optics: Airy pattern, defocus blur circle, defocus Strehl, MTF.

The perfect lens is a single refracting ellipsoid, conic k = −1/n², from air into glass of
index n: it images an axial object at infinity onto its far focus without aberration
(a Cartesian oval), so every ray lands on the focus and every optical path is equal. The
image sits in the glass, where the Airy radius is 0.61·λ/(n·sin u') = 1.22·λ·F#w with the
working F-number F#w = 1/(2·n·u') that ``paraxial_data`` reports. At F/5 the difference
between sin u' and u' is 0.2 %.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.imaging import psf as P
from jaxlens.imaging.psf import CoherentPSF, GeometricPSF
from jaxlens.optics.materials import LAMBDA_D

N = 1.5
R = 20.0
F_REAR = N * R / (N - 1)  # far focus of the ellipsoid, 60 mm
FNUM = 5.0
H = F_REAR / (2 * N * FNUM)  # entrance pupil radius for F#w = 5
WL = LAMBDA_D


def perfect_lens(defocus=0.0):
    """The ellipsoid, with the image plane ``defocus`` mm behind its focus."""
    return jaxlens.Lens(
        surfaces=(jaxlens.Conic(1 / R, -1 / N**2, semi_diameter=H),),
        thickness=jnp.array([F_REAR + defocus]),
        materials=(jaxlens.ModelGlass(N, 60.0),),
        stop=0,
        epd=2 * H,
    )


def marginal_tan():
    """tan u' of the exact marginal ray, from the rim of the ellipsoid to its focus."""
    c, k = 1 / R, -1 / N**2
    sag = c * H**2 / (1 + np.sqrt(1 - (1 + k) * c**2 * H**2))
    return H / (F_REAR - sag)


def first_zero(profile):
    """Sub-pixel position of the first local minimum of a 1-D profile (parabola fit)."""
    i = next(i for i in range(1, len(profile) - 1)
             if profile[i] < profile[i - 1] and profile[i] <= profile[i + 1])
    a, b, c = profile[i - 1], profile[i], profile[i + 1]
    return i + 0.5 * (a - c) / (a - 2 * b + c)


def test_paraxial_setup():
    pd = jaxlens.paraxial_data(perfect_lens())
    assert float(pd.working_fnum) == pytest.approx(FNUM, rel=1e-12)
    assert float(pd.bfl) == pytest.approx(F_REAR, rel=1e-12)


# The coherent tests share one compiled PSF (same kernel, pupil and lens structure).
COHERENT = dict(wavelength=WL, kernel_size=41, model=CoherentPSF(pupil=64),
                max_truncation=None)
R_AIRY = 1.22 * WL * 1e-3 * FNUM  # mm


def test_airy_first_zero_and_strehl():
    pix = R_AIRY / 16
    res = P.psf_info(perfect_lens(), 0.0, pixel_size=pix, **COHERENT)
    k = np.asarray(res.psf)
    c = 20
    assert np.unravel_index(np.argmax(k), k.shape) == (c, c)
    for profile in (k[c, c:], k[c:, c], k[c, c::-1]):
        assert first_zero(profile) * pix == pytest.approx(R_AIRY, rel=0.01)
    assert float(res.strehl) == pytest.approx(1.0, abs=1e-6)
    assert not bool(res.aliased)
    # Peak energy per pixel of the Airy pattern: π·NA²·p²/λ² (NA = n·sin u').
    na = N * np.sin(np.arctan(marginal_tan()))
    assert k.max() == pytest.approx(np.pi * na**2 * pix**2 / (WL * 1e-3) ** 2, rel=0.01)
    # Energy: what is not in the kernel is reported as truncated (about 10 % beyond the
    # square of ±1.25 Airy radii).
    assert float(k.sum() + res.truncated) == pytest.approx(1.0, abs=1e-12)
    assert 0.05 < float(res.truncated) < 0.2


def test_defocus_strehl_matches_sinc():
    """A quarter wave of defocus: on-axis Strehl = sinc²(π·W020/λ) = 0.8106."""
    s_m = np.sin(np.arctan(marginal_tan()))
    w020 = WL * 1e-3 / 4
    delta = w020 / (N * (1 - np.sqrt(1 - s_m**2)))
    res = P.psf_info(perfect_lens(delta), 0.0, pixel_size=R_AIRY / 6, **COHERENT)
    x = np.pi / 4
    assert float(res.strehl) == pytest.approx((np.sin(x) / x) ** 2, abs=0.01)


# The geometric tests share one compiled PSF too.
GEOMETRIC = dict(wavelength=WL, kernel_size=51, model=GeometricPSF(pupil=96),
                 max_truncation=None)
DELTA = 0.5


def test_defocus_blur_circle():
    radius = DELTA * marginal_tan()  # analytic blur-circle radius, mm
    pix = radius / 20
    res = P.psf_info(perfect_lens(DELTA), 0.0, pixel_size=pix, **GEOMETRIC)
    k = np.asarray(res.psf)
    assert float(res.truncated) < 1e-12
    i = np.arange(51) - 25
    yy, xx = np.meshgrid(i, i, indexing="ij")
    m2 = (k * (xx**2 + yy**2)).sum() * pix**2
    # Uniform disc: <r²> = R²/2; bilinear splatting adds p²/6 per axis.
    assert np.sqrt(2 * (m2 - pix**2 / 3)) == pytest.approx(radius, rel=0.01)
    row = k[25]
    lit = np.nonzero(row > 1e-3 * row.max())[0]
    diameter_px = lit[-1] - lit[0]
    assert abs(diameter_px * pix - 2 * radius) <= 2 * pix


def test_truncation_detected():
    lens = perfect_lens(DELTA)
    pix = DELTA * marginal_tan() / 100  # the blur circle is 200 pixels wide
    res = P.psf_info(lens, 0.0, pixel_size=pix, **GEOMETRIC)
    assert float(res.truncated) > 0.9
    kw = {**GEOMETRIC, "max_truncation": 0.05}
    # Concrete inputs: a ValueError with the measured fraction and the kernel's width.
    want = float(res.truncated)
    with pytest.raises(ValueError, match=rf"outside the 51x51 kernel; enlarge kernel_size or "
                                         rf"pixel_size \({want:.3g} falls outside; the kernel "
                                         rf"spans {51 * pix * 1e3:.4g} µm at {WL:g} µm\)"):
        jaxlens.psf(lens, 0.0, pixel_size=pix, **kw)
    # Under a trace the same check raises when the program runs.
    with pytest.raises(Exception, match="outside the 51x51 kernel") as err:
        jax.jit(lambda p: jaxlens.psf(lens, 0.0, pixel_size=p, **kw))(pix)
    assert not isinstance(err.value, ValueError)


def test_bad_arguments():
    lens = perfect_lens()
    with pytest.raises(TypeError, match="PSF model object, not a string"):
        jaxlens.psf(lens, 0.0, model="coherent", pixel_size=0.001)
    with pytest.raises(ValueError, match="pupil"):
        jaxlens.psf(lens, 0.0, model=CoherentPSF(pupil=1), pixel_size=0.001)
    with pytest.raises(ValueError, match="pixel_size"):
        jaxlens.psf(lens, 0.0)  # no sensor
    with pytest.raises(ValueError, match="depth"):
        jaxlens.psf(lens, 0.0, pixel_size=0.001, depth=-5.0)


def test_geometric_psf_gradient_matches_finite_differences():
    """d/dδ of a smooth functional of the defocused PSF (float64, central differences)."""
    pix = DELTA * marginal_tan() / 10
    wgt = jnp.asarray(np.random.default_rng(0).random((51, 51)))

    def f(delta):
        lens = eqx_tree_thickness(perfect_lens(0.0), delta)
        k = P.psf_info(lens, 0.0, pixel_size=pix, center="centroid", **GEOMETRIC).psf
        return jnp.sum(wgt * k)

    d0, h = 0.4, 1e-6
    g = jax.grad(f)(d0)
    fd = (f(d0 + h) - f(d0 - h)) / (2 * h)
    assert float(g) == pytest.approx(float(fd), rel=1e-4)


def eqx_tree_thickness(lens, delta):
    import equinox as eqx

    return eqx.tree_at(lambda m: m.thickness, lens, jnp.array([F_REAR]) + delta)


def test_mtf_of_perfect_lens_is_diffraction_limited():
    lens = perfect_lens()
    cutoff = 1 / (WL * 1e-3 * FNUM)
    freqs = jnp.array([0.0, 0.1, 0.3, 0.5, 0.7]) * cutoff
    s = np.asarray(freqs) * WL * 1e-3 * FNUM
    ideal = 2 / np.pi * (np.arccos(s) - s * np.sqrt(1 - s**2))
    f, t, sg = jaxlens.imaging.psf.mtf(lens, 0.0, wavelengths=[WL], frequencies=freqs,
                                            model=GeometricPSF(pupil=16))
    np.testing.assert_allclose(t, ideal, atol=1e-9)
    np.testing.assert_allclose(sg, ideal, atol=1e-9)
    _, tc, sc = jaxlens.imaging.psf.mtf(lens, 0.0, wavelengths=[WL], frequencies=freqs,
                                model=CoherentPSF(pupil=48), kernel_size=96)
    np.testing.assert_allclose(tc, ideal, atol=0.03)
    np.testing.assert_allclose(sc, ideal, atol=0.03)


def test_psf_map_orientation_and_rgb():
    """Corner PSFs of a rotationally symmetric lens are 180° rotations of each other, the
    centre PSF is on axis and symmetric, and RGB maps stack three wavelengths."""
    lens = jaxlens.zoo.cooke_triplet()
    m = P.psf_map(lens, grid=(3, 3), kernel_size=15, pixel_size=0.01, model=GeometricPSF(pupil=24),
                  wavelength=jnp.asarray(P.RGB_WAVELENGTHS), center="ideal")
    assert m.psf.shape == (3, 3, 3, 15, 15)
    np.testing.assert_allclose(m.psf[0, 0], m.psf[2, 2][..., ::-1, ::-1], atol=1e-9)
    np.testing.assert_allclose(m.psf[0, 2], m.psf[2, 0][..., ::-1, ::-1], atol=1e-9)
    np.testing.assert_allclose(m.psf[1, 1], m.psf[1, 1][..., ::-1, ::-1], atol=1e-9)
    np.testing.assert_allclose(m.field[1, 1], 0.0, atol=1e-12)
    # Top-left of the rendered image is sensor (+x, −y): the ideal image point lies there.
    assert float(m.center[0, 0, 0]) > 0 and float(m.center[0, 0, 1]) < 0
    np.testing.assert_allclose(m.center, m.sensor_xy, atol=1e-12)
    np.testing.assert_allclose(m.psf.sum((-1, -2)) + m.truncated, 1.0, atol=1e-12)
    np.testing.assert_allclose(m.truncated[1, 1], 0.0, atol=1e-12)
    # Lateral colour: the corner PSF centroids differ between red and blue.
    i = np.arange(15) - 7
    cx = [(np.asarray(m.psf[0, 0, c]) * i[None, :]).sum() / np.asarray(m.psf[0, 0, c]).sum()
          for c in (0, 2)]
    assert abs(cx[0] - cx[1]) > 0.05
