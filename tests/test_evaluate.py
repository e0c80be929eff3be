"""The Table 1 evaluation (``jaxlens.design.evaluate``) on a lens with analytic spots.

A plane-parallel plate behind a stop at the first surface: a collimated beam at field
direction d stays collimated, so every ray of it lands at its pupil point plus a shift
common to the beam, and the plate moves the beam sideways by t·d'_xy/d'_z, with
d'_xy = d_xy/n(λ) (Snell at a flat face). The spot of one wavelength is the pupil grid
itself; pooling F, d and C adds the spread of the chromatic shifts. A semi-diameter on the
plate's back face clips the outer rays of the corner fields, by a count that follows from
the same straight lines. Everything below is computed from these lines with NumPy, from
the documented definition in ``experiments/classical/table1.md``: a 16 × 16 grid over the
whole sensor rectangle (corners included), tan θ = sensor position / f, RMS radius of the
F, d and C rays pooled about their common centroid with the 21 × 21 pupil grid, and valid
= no self-intersection and ≥ 99 % of the rays of every field reach the sensor.
"""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.design import evaluate as ev
from jaxlens.design.spec import DesignSpec

# A 3:4 sensor, so that swapping height and width changes the field grid.
SPEC = DesignSpec(sensor_aspect=(3.0, 4.0))
GLASS = jl.ModelGlass(1.75, 25.0)  # strong dispersion: a large chromatic shift
T_GAP, T_PLATE, T_BACK = 0.5, 2.0, 3.0


def _plate(back_sd=np.inf):
    return jl.Lens(
        surfaces=(jl.Stop(), jl.Sphere(0.0), jl.Sphere(0.0, semi_diameter=back_sd)),
        thickness=jnp.array([T_GAP, T_PLATE, T_BACK]),
        materials=(jl.Air(), GLASS, jl.Air()),
        stop=0, epd=1.0, wavelengths=jnp.asarray(SPEC.wavelengths), primary=SPEC.primary,
    )


def _grid(n=16):
    """The documented field grid: sensor points, x fastest (mm)."""
    h, w = SPEC.sensor_size
    x, y = np.meshgrid(np.linspace(-1, 1, n) * w / 2, np.linspace(-1, 1, n) * h / 2)
    return np.stack([x.ravel(), y.ravel()], -1)


def _pupil():
    u = np.linspace(-1.0, 1.0, 21)
    px, py = np.meshgrid(u, u)
    keep = px**2 + py**2 <= 1.0 + 1e-12
    return np.stack([px[keep], py[keep]], -1)


def _analytic(back_sd=np.inf):
    """RMS radius (µm) and the smallest per-wavelength valid fraction of every field."""
    f, r = SPEC.focal_length, 0.5 * SPEC.epd
    q = _pupil() * r  # ray positions on the stop plane (z = 0)
    rms, frac = [], []
    for pt in _grid():
        d = np.array([pt[0] / f, pt[1] / f, 1.0])
        d /= np.linalg.norm(d)
        pts, ok = [], []
        for wl in SPEC.wavelengths:
            n = float(GLASS.index(wl))
            dp_xy = d[:2] / n
            dp_z = np.sqrt(1.0 - dp_xy @ dp_xy)
            # Heights on the back face, and on the image (the plate's shift t·d'/d'_z).
            back = q + T_GAP * d[:2] / d[2] + T_PLATE * dp_xy / dp_z
            img = back + T_BACK * d[:2] / d[2]
            inside = np.hypot(*back.T) <= back_sd
            pts.append(img)
            ok.append(inside)
        pts, ok = np.stack(pts), np.stack(ok)
        c = pts[ok].mean(0)
        rms.append(1e3 * np.sqrt(np.mean(np.sum((pts[ok] - c) ** 2, -1))))
        frac.append(ok.mean(-1).min())
    return np.array(rms), np.array(frac)


@pytest.fixture(scope="module")
def clear():
    return ev.evaluate(_plate(), SPEC), _analytic()


def test_pupil_grid_and_field_grid_are_the_documented_ones():
    assert _pupil().shape == (317, 2)
    ang, pts = ev.sensor_field_grid(SPEC)
    np.testing.assert_allclose(pts, _grid(), atol=1e-15)
    np.testing.assert_allclose(np.tan(np.radians(ang)), _grid() / SPEC.focal_length,
                               rtol=1e-12, atol=1e-15)
    # The corners are the full diagonal field.
    assert np.degrees(np.arctan(np.hypot(*pts[0]) / SPEC.focal_length)) == pytest.approx(
        SPEC.fov / 2)


def test_rms_of_every_field_matches_the_analytic_plate(clear):
    got, (rms, _) = clear
    # Each wavelength's spot is the pupil grid (RMS 0.795 mm); pooling F, d and C adds the
    # chromatic shifts in quadrature: under 0.6 µm near the centre, over 6 µm at the corners.
    pupil_only = 1e3 * np.sqrt(np.mean(np.sum((_pupil() * SPEC.epd / 2) ** 2, -1)))
    chroma = np.sqrt(rms**2 - pupil_only**2)  # the spread of the chromatic shifts
    assert chroma.min() < 0.6 and chroma.max() > 6.0
    np.testing.assert_allclose(got.rms_um, rms, rtol=1e-9)
    np.testing.assert_allclose(np.sqrt(got.rms_um**2 - pupil_only**2), chroma, rtol=1e-3)
    assert got.rms_mean_um == pytest.approx(rms.mean(), rel=1e-7)
    assert got.rms_max_um == pytest.approx(rms.max(), rel=1e-7)
    np.testing.assert_array_equal(got.valid_fraction, 1.0)
    assert got.valid and got.rays_ok and not got.self_intersection


def test_clipped_corners_fail_the_99_percent_rule():
    # The back face clips the outer rays of the outermost fields only.
    sd = 2.2
    got = ev.evaluate(_plate(sd), SPEC)
    rms, frac = _analytic(sd)
    np.testing.assert_allclose(got.valid_fraction, frac, atol=1e-12)
    np.testing.assert_allclose(got.rms_um, rms, rtol=1e-7)
    assert 0.5 < frac.min() < 0.99 and np.mean(frac == 1.0) > 0.5
    assert not got.rays_ok and not got.valid
    assert not got.self_intersection  # only the rays fail
    # The rule is "at least min_valid of the rays of every field".
    lowest = float(frac.min())
    assert ev.evaluate(_plate(sd), SPEC, min_valid=lowest - 1e-9).valid
    assert not ev.evaluate(_plate(sd), SPEC, min_valid=lowest + 1e-6).valid


def test_summary_drops_the_per_field_arrays(clear):
    got, _ = clear
    s = got.summary()
    assert "rms_um" not in s and "valid_fraction" not in s
    assert s["min_valid_fraction"] == 1.0 and s["rms_mean_um"] == got.rms_mean_um
    assert s["valid"] is True and set(s) >= {"efl", "fnum", "bfl", "geometry", "min_gap"}



def test_an_ideal_lens_has_no_distortion_and_its_chief_ray_at_f_tan():
    """An ideal thin lens (f = spec's focal length) behind the stop images a direction θ at
    f·tanθ, so the full-field chief ray lands at f·tan(FoV/2) and the distortion is 0."""
    from jaxlens.optics.paraxial_surface import ParaxialSurface

    f = SPEC.focal_length
    lens = jl.Lens(
        surfaces=(jl.Stop(), ParaxialSurface(focal_length=f)),
        thickness=jnp.array([0.7, f]), materials=(jl.Air(), jl.Air()), stop=0, epd=1.0,
        wavelengths=jnp.asarray(SPEC.wavelengths), primary=SPEC.primary,
    )
    got = ev.evaluate(lens, SPEC)
    assert got.efl == pytest.approx(f, rel=1e-12)
    assert got.chief_height_full_field == pytest.approx(f * np.tan(np.radians(SPEC.fov / 2)),
                                                        rel=1e-10)
    assert abs(got.distortion_percent) < 1e-8
    np.testing.assert_allclose(got.rms_um, 0.0, atol=1e-9)  # a perfect lens: point images
    assert got.valid


def test_distortion_of_an_ideal_lens_with_a_plate_before_the_image():
    """The stop at an ideal lens: the chief ray leaves it undeviated at θ. A flat plate
    (thickness t, index n) between lens and image bends it to sinθ_p = sinθ/n, while the
    paraxial focus moves by t(1 − 1/n) and the EFL stays f. By hand:
    h = (d1 + d2)·tanθ + t·tanθ_p with d1 + t/n + d2 = f, distortion = 100 (h − f tanθ)/(f tanθ)."""
    from jaxlens.optics.paraxial_surface import ParaxialSurface

    f, t, d1 = SPEC.focal_length, 1.5, 0.5
    glass = jl.ModelGlass(1.6, 1e9)  # no dispersion: one index at every wavelength
    n = float(glass.index(0.5876))
    d2 = f - d1 - t / n
    lens = jl.Lens(
        surfaces=(jl.Stop(), ParaxialSurface(focal_length=f), jl.Sphere(0.0), jl.Sphere(0.0)),
        thickness=jnp.array([0.0, d1, t, d2]), materials=(jl.Air(), jl.Air(), glass, jl.Air()),
        stop=0, epd=1.0, wavelengths=jnp.asarray(SPEC.wavelengths), primary=SPEC.primary,
    )
    th = np.radians(SPEC.fov / 2)
    h = (d1 + d2) * np.tan(th) + t * np.tan(np.arcsin(np.sin(th) / n))
    got = ev.evaluate(lens, SPEC)
    assert got.efl == pytest.approx(f, rel=1e-12)
    assert got.chief_height_full_field == pytest.approx(h, rel=1e-10)
    expected = 100 * (h - f * np.tan(th)) / (f * np.tan(th))
    assert expected < -1.0  # a plate in a converging beam: barrel distortion of over 1 %
    assert got.distortion_percent == pytest.approx(expected, rel=1e-8)


def test_the_valid_rule_is_at_least_min_valid_and_crossing_faces_are_invalid():
    sd = 2.2
    got = ev.evaluate(_plate(sd), SPEC)
    # Exactly the smallest field's fraction still passes ("at least").
    assert ev.evaluate(_plate(sd), SPEC, min_valid=float(got.valid_fraction.min())).rays_ok
    # A biconvex element 0.2 mm thick with 3 mm radii: its faces cross inside the beam
    # (each face's sag is 0.1 mm at r = 0.77 mm; the spec's EPD is 2.25 mm).
    assert SPEC.epd / 2 > 0.77
    lens = jl.Lens(
        surfaces=(jl.Stop(), jl.Sphere(1 / 3), jl.Sphere(-1 / 3)),
        thickness=jnp.array([0.2, 0.2, 4.0]), materials=(jl.Air(), GLASS, jl.Air()),
        stop=0, epd=1.0, wavelengths=jnp.asarray(SPEC.wavelengths), primary=SPEC.primary,
    )
    bad = ev.evaluate(lens, SPEC)
    assert bad.self_intersection is True and not bad.valid and bad.min_gap < 0
