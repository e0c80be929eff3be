"""Ray fans and field curvature (jaxlens.analysis.aberrations): against optiland's own
analyses on the same geometry (tests/data/aberrations_optiland.json, written by
tools/aberrations_reference.py), the third-order thin lens, and a perfect lens."""

import json
import pathlib

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import aberrations as ab
from jaxlens.optics.paraxial_surface import ParaxialSurface

ROOT = pathlib.Path(__file__).resolve().parents[1]
REFERENCE = json.loads((ROOT / "tests/data/aberrations_optiland.json").read_text())


def _lens(case):
    src = case["source"]
    return jl.zoo.ZOO[src.split("'")[1]]() if src.startswith("jaxlens.zoo") else \
        jl.load(ROOT / src)


@pytest.mark.parametrize("name", sorted(REFERENCE["cases"]))
def test_field_curves_and_fans_match_optiland(name):
    """optiland's parabasal pairs (Py, Px = ±1e-5) differ from the exact differential rays by
    O(δ²) (a few 1e-9 mm where the field has coma); its fans are plain traces."""
    case = REFERENCE["cases"][name]
    lens = _lens(case)
    fc = jl.analysis.field_curvature(lens, case["fields_deg"], case["wavelength_um"])
    np.testing.assert_allclose(fc.tangential[0], case["tangential_mm"], rtol=0, atol=2e-8)
    np.testing.assert_allclose(fc.sagittal[0], case["sagittal_mm"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(fc.astigmatism[0],
                               np.subtract(case["tangential_mm"], case["sagittal_mm"]),
                               rtol=0, atol=2e-8)
    for field, fan in case["fans_mm"].items():
        rf = jl.analysis.ray_fan(lens, float(field), case["wavelength_um"], n=case["fan_points"])
        assert bool(jnp.all(rf.valid_tangential)) and bool(jnp.all(rf.valid_sagittal))
        np.testing.assert_allclose(rf.tangential[0], fan["tangential"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(rf.sagittal[0], fan["sagittal"], rtol=0, atol=1e-12)


def _thin_lens(f=100.0, n=1.5, t=0.02):
    """An equiconvex lens of focal length f (index n, thickness t), stop on its first
    surface, image plane at the paraxial focus."""
    # 1/f = (n − 1)·2c − (n − 1)² t c²/n, solved for c.
    a, b = (n - 1) ** 2 * t / n, -2 * (n - 1)
    c = (-b - np.sqrt(b * b - 4 * a / f)) / (2 * a)
    lens = jl.Lens(surfaces=(jl.Sphere(c), jl.Sphere(-c)), thickness=jnp.array([t, f]),
                   materials=(jl.ModelGlass(n, 60.0), jl.Air()), stop=0, epd=2.0,
                   fields=jnp.array([0.0, 3.0]), wavelengths=jnp.array([0.5875618]))
    bfl = float(jl.paraxial_data(lens).bfl)
    return jl.Lens(surfaces=lens.surfaces, thickness=jnp.array([t, bfl]),
                   materials=lens.materials, stop=0, epd=2.0, fields=lens.fields,
                   wavelengths=lens.wavelengths)


def test_thin_lens_with_the_stop_at_it_has_third_order_field_curves():
    """Third order, stop at a thin lens: sagittal focus −(h²/2f)(1 + 1/n), tangential
    −(h²/2f)(3 + 1/n) from the paraxial image plane (Petzval −h²/(2nf), the tangential
    focal line three times as far from it as the sagittal), h = f·tanθ."""
    f, n = 100.0, 1.5
    lens = _thin_lens(f, n)
    # Within 1°: the higher orders (∝ θ²) and the thickness (t/f = 2e-4) stay below 1e-3.
    theta = np.array([0.25, 0.5, 1.0])
    fc = jl.analysis.field_curvature(lens, theta)
    h2 = (f * np.tan(np.radians(theta))) ** 2
    np.testing.assert_allclose(fc.sagittal[0], -h2 / (2 * f) * (1 + 1 / n), rtol=1e-3)
    np.testing.assert_allclose(fc.tangential[0], -h2 / (2 * f) * (3 + 1 / n), rtol=1e-3)
    np.testing.assert_allclose(fc.astigmatism[0], -h2 / f, rtol=1e-3)
    # On axis both foci are on the paraxial image plane.
    on_axis = jl.analysis.field_curvature(lens, [0.0])
    assert abs(float(on_axis.tangential[0, 0])) < 1e-9
    assert abs(float(on_axis.sagittal[0, 0])) < 1e-9


def test_a_perfect_lens_has_flat_field_and_no_transverse_errors():
    """An ideal thin lens images every direction onto its focal plane without aberration."""
    f = 20.0
    lens = jl.Lens(surfaces=(jl.Stop(), ParaxialSurface(focal_length=f)),
                   thickness=jnp.array([1.0, f]), materials=(jl.Air(), jl.Air()), stop=0,
                   epd=4.0, fields=jnp.array([0.0, 15.0]),
                   wavelengths=jnp.array([0.48, 0.5875618, 0.65]), primary=1)
    fc = jl.analysis.field_curvature(lens)
    assert fc.tangential.shape == fc.sagittal.shape == (3, ab.CURVE_FIELDS)
    np.testing.assert_allclose(fc.tangential, 0.0, atol=1e-9)
    np.testing.assert_allclose(fc.sagittal, 0.0, atol=1e-9)
    rf = jl.analysis.ray_fan(lens, 15.0, n=9)
    assert rf.tangential.shape == (3, 9)
    np.testing.assert_allclose(rf.tangential, 0.0, atol=1e-12)
    np.testing.assert_allclose(rf.sagittal, 0.0, atol=1e-12)


def test_fans_are_referred_to_the_primary_chief_ray_and_show_lateral_colour():
    """Every wavelength's fan is measured from the primary wavelength's chief ray: at the
    pupil centre the primary fan is 0 and another wavelength's is its lateral colour."""
    lens = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    rf = jl.analysis.ray_fan(lens, 20.0, n=5)
    p = lens.primary
    assert float(rf.pupil[2]) == 0.0
    assert float(rf.tangential[p, 2]) == 0.0 and float(rf.sagittal[p, 2]) == 0.0
    chief = [float(jl.analysis.chief_ray(lens, 20.0, w).origin[1])
             for w in np.asarray(lens.wavelengths)]
    for i in range(len(chief)):
        assert float(rf.tangential[i, 2]) == pytest.approx(chief[i] - chief[p], abs=1e-12)
    # The sagittal fan of a symmetric lens is odd in Px.
    np.testing.assert_allclose(rf.sagittal[:, ::-1], -rf.sagittal, atol=1e-12)
    # A (θx, θy) field along y is the θy field; along x its fans swap roles.
    same = jl.analysis.ray_fan(lens, [0.0, 20.0], n=5)
    np.testing.assert_allclose(same.tangential, rf.tangential, atol=1e-13)
    turned = jl.analysis.ray_fan(lens, [20.0, 0.0], n=5)
    np.testing.assert_allclose(turned.sagittal, rf.tangential, atol=1e-12)


def test_lost_rays_are_nan_and_flagged():
    """Rays clipped by a semi-diameter have no error (NaN), and say so."""
    lens = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    s = lens.surfaces[0]
    clipped = jl.Lens(surfaces=(jl.Sphere(s.c, semi_diameter=3.0),) + lens.surfaces[1:],
                      thickness=lens.thickness, materials=lens.materials, stop=lens.stop,
                      epd=lens.epd, fields=lens.fields, wavelengths=lens.wavelengths,
                      primary=lens.primary)
    rf = jl.analysis.ray_fan(clipped, 0.0, n=11)
    lost = ~np.asarray(rf.valid_tangential)
    assert lost[:, 0].all() and lost[:, -1].all() and not lost[:, 5].any()
    assert np.isnan(np.asarray(rf.tangential)[lost]).all()
    assert np.isfinite(np.asarray(rf.tangential)[~lost]).all()


@pytest.mark.parametrize("call, match", [
    (lambda lens: jl.analysis.field_curvature(lens, [[0.0, 5.0, 1.0]]), r"\(θx, θy\) pairs"),
    (lambda lens: jl.analysis.field_curvature(lens, [95.0]), r"\(-90, 90\) deg"),
    (lambda lens: jl.analysis.ray_fan(lens, [0.0, 5.0, 1.0]), "one field"),
    (lambda lens: jl.analysis.ray_fan(lens, [95.0, 5.0]), r"\(-90, 90\) deg"),
    (lambda lens: jl.analysis.ray_fan(lens, 5.0, n=1), "n must be"),
    (lambda lens: jl.analysis.ray_fan(lens, 5.0, 550.0), "550 nm is 0.55 µm"),
    (lambda lens: jl.analysis.field_curvature(lens, [], 0.55), "fields must be"),
])
def test_bad_input_is_refused_with_its_reason(call, match):
    lens = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    with pytest.raises(ValueError, match=match):
        call(lens)


# 45–50 s of compiling a 19-surface folded system: slow (CI time).
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*aims rays at the stop")
def test_folded_mirror_system_field_curves_equal_parabasal_pairs():
    """A 19-surface folded system (four mirrors, coordinate breaks): the differential rays
    agree with finite parabasal pairs at Py, Px = ±1e-6 (optiland's construction), and the
    forward-mode trace that gives them runs in seconds (see aberrations._field_curvature)."""
    from jaxlens.imaging.sampling import field_rays

    lens = jl.load(ROOT / "tests/data/zmx/rayoptics_HoO-V2C18Ex66.zmx")
    # Its own fields: on axis, (0, ±1°) and (±9°, 0), whose tangential plane is x–z.
    fields = np.asarray(lens.fields)
    fc = jl.analysis.field_curvature(lens, fields)
    w, h = lens.primary_wavelength, 1e-6
    for k, th in enumerate(fields):
        t = np.tan(np.deg2rad(th))
        a = t / np.hypot(*t) if t.any() else np.array([0.0, 1.0])
        for row, e in enumerate((a, np.array([a[1], -a[0]]))):
            out = jl.trace(lens, field_rays(lens, jnp.asarray(th), jnp.array([-h * e, h * e]), w))
            (p1, p2), (d1, d2) = np.asarray(out.origin), np.asarray(out.direction)
            # Where ray 2 crosses ray 1 in the plane of e and z, along ray 1, as z.
            def cross(u, v, e=e):
                return (u[:2] @ e) * v[2] - u[2] * (v[:2] @ e)

            s = cross(p2 - p1, d2) / cross(d1, d2)
            want = [fc.tangential, fc.sagittal][row][0, k]
            assert float(want) == pytest.approx(s * d1[2], abs=1e-6)


@pytest.mark.parametrize("azimuth", [0.0, 35.0, 90.0, 200.0])
def test_a_field_off_the_y_axis_has_its_foci_along_its_azimuth(azimuth):
    """On a rotationally symmetric lens, a (θx, θy) field has the tangential and sagittal
    foci of the θy field of the same radial angle: its tangential plane turns with it. Read
    in the fixed y–z and x–z planes, a 90° field would swap them (0.05–0.28 mm apart here)."""
    lens = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    radial = np.array([5.0, 14.0, 20.0])
    tan_r = np.tan(np.deg2rad(radial))
    phi = np.deg2rad(azimuth)
    pairs = np.rad2deg(np.arctan(np.stack([tan_r * np.sin(phi), tan_r * np.cos(phi)], -1)))
    along_y = jl.analysis.field_curvature(lens, radial)
    turned = jl.analysis.field_curvature(lens, pairs)
    np.testing.assert_allclose(np.asarray(turned.tangential), np.asarray(along_y.tangential),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.asarray(turned.sagittal), np.asarray(along_y.sagittal),
                               rtol=0, atol=1e-9)
    assert np.abs(np.asarray(along_y.astigmatism)).min() > 0.04  # a swap would show


def test_a_theta_y_field_and_the_pair_zero_theta_y_agree_exactly():
    lens = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    theta = np.array([0.0, 10.0, -15.0])
    one = jl.analysis.field_curvature(lens, theta)
    two = jl.analysis.field_curvature(lens, np.stack([np.zeros(3), theta], -1))
    np.testing.assert_array_equal(np.asarray(one.tangential), np.asarray(two.tangential))
    np.testing.assert_array_equal(np.asarray(one.sagittal), np.asarray(two.sagittal))


# 45–50 s of compiling a 19-surface folded system: slow (CI time).
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*aims rays at the stop")
def test_forward_mode_analyses_of_a_folded_lens_use_the_loop_emitters():
    """Only lenses with surfaces outside the scans get XLA's loop emitters (forward.
    LOOP_EMITTERS): relative illumination of the folded system finishes (it did not in
    minutes) and is 1 on axis; a plain lens keeps the default compile."""
    from jaxlens.imaging import radiometry
    from jaxlens.tracing import forward

    folded = jl.load(ROOT / "tests/data/zmx/rayoptics_HoO-V2C18Ex66.zmx")
    plain = jl.load(ROOT / "jaxlens/data/lenses/cooke_triplet.json")
    assert forward.has_unscanned_surfaces(folded)
    assert not forward.has_unscanned_surfaces(plain)
    ri = radiometry.relative_illumination(folded, jnp.array([[0.0, 0.0], [0.0, 1.0]]), pupil=24)
    assert float(ri.ri[0]) == pytest.approx(1.0, abs=1e-9)
    assert 0.5 < float(ri.ri[1]) <= 1.0 + 1e-9
