"""Silent wrong answers found by an audit of the public API: two functions that should agree
on the same quantity did not, or a result contradicted its documentation. Each test named a
failure of the code before its fix, except the two field-curvature tests, which pin a
convention (float64, as every accuracy test)."""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import analysis
from jaxlens.optics.paraxial_surface import ParaxialSurface


def _mirror(k=0.0, *, defocus=0.0, dummy=False, fields=(0.0, 1.0)):
    """A concave mirror of focal length 50 mm (R = −100, conic k), stop on it, EPD 10 mm, the
    image plane ``defocus`` mm beyond its paraxial focus; with ``dummy`` a plane 10 mm in
    front of it is surface 1."""
    surfaces, thickness, mirrors = (jl.Standard(c=-1 / 100.0, k=k),), [-50.0 - defocus], (0,)
    if dummy:
        surfaces, thickness, mirrors = (jl.Standard(),) + surfaces, [10.0] + thickness, (1,)
    return jl.Lens(surfaces=surfaces, thickness=jnp.array(thickness),
                   materials=(jl.Air(),) * len(surfaces), mirrors=mirrors,
                   stop=len(surfaces) - 1, epd=10.0, fields=jnp.array(fields))


def _perfect(defocus=0.0):
    """An ideal thin lens of focal length 50 mm, EPD 10 mm, image ``defocus`` mm beyond focus."""
    return jl.Lens(surfaces=(ParaxialSurface(50.0),), thickness=jnp.array([50.0 + defocus]),
                   materials=(jl.Air(),), epd=10.0, fields=jnp.array([0.0, 1.0]))


# ------------------------------------- field curvature behind a mirror: the z convention
def test_field_curvature_behind_a_mirror_is_a_z_distance():
    """The foci are z distances from the image surface, as in Zemax and optiland (optiland:
    t·N with N the z direction cosine). Behind a concave mirror light travels toward −z, so
    an image plane 1 mm beyond the focus gives +1 mm, where a lens gives −1 mm. The
    docstring said "negative: before it, toward the lens", true only without mirrors; it now
    names the convention (this test pins it, so that neither is changed alone)."""
    np.testing.assert_allclose(analysis.field_curvature(_perfect(defocus=1.0), [0.0]).tangential,
                               [[-1.0]], rtol=0, atol=1e-9)
    fc = analysis.field_curvature(_mirror(defocus=1.0), [0.0])
    np.testing.assert_allclose(fc.tangential[0], [1.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fc.sagittal[0], [1.0], rtol=0, atol=1e-9)


def test_field_curvature_of_a_concentric_mirror_off_axis():
    """A spherical mirror (R = −100) with its stop at its centre of curvature images every
    field on the sphere of radius 50 about that centre, free of astigmatism: on a flat image
    plane 50 mm from the centre the 5° foci lie 50·(1 − cos 5°) = 0.190 mm beyond it, toward
    −z, so at z distance −0.190 mm (an independent check of the differential rays behind a
    mirror)."""
    r = -100.0
    lens = jl.Lens(surfaces=(jl.Standard(), jl.Standard(c=1 / r)),
                   thickness=jnp.array([-r, r / 2]), materials=(jl.Air(), jl.Air()),
                   mirrors=(1,), stop=0, epd=2.0, fields=jnp.array([0.0, 5.0]))
    fc = analysis.field_curvature(lens, [0.0, 5.0])
    z = -50.0 * (1 - np.cos(np.radians(5.0)))
    np.testing.assert_allclose(fc.tangential[0], [0.0, z], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fc.sagittal[0], [0.0, z], rtol=0, atol=1e-9)


# ------------------------------- a paraboloid as surface 1: the far root of the whole line
def test_parabolic_mirror_as_surface_one_traces_like_behind_a_dummy_plane():
    """A parabolic primary (k = −1, concave toward the object) as surface 1: every off-axis
    ray took the paraboloid's second intersection with its line, about 6.6e5 mm behind the
    vertex, and was marked valid. The 1° chief ray landed at y = −11457 mm (0.873 mm behind a
    dummy plane, and for k = −0.5 or −2) and the 1° RMS spot was 7.106 mm instead of
    0.00197 mm; on axis (rays parallel to the axis, one root) all was right."""
    alone, behind = _mirror(-1.0), _mirror(-1.0, dummy=True)
    np.testing.assert_allclose(analysis.chief_ray(alone, 1.0).origin[1],
                               analysis.chief_ray(behind, 1.0).origin[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(analysis.rms_spot(alone).polychromatic,
                               analysis.rms_spot(behind).polychromatic, rtol=1e-9, atol=1e-12)


# ------------------------------------------ f-tanθ distortion with an object in a medium
def test_an_ideal_lens_behind_water_has_no_ftan_distortion():
    """A field angle is measured in object space, where a distortion-free lens of EFL f (1/Φ)
    images a collimated beam at n·f·tanθ (its front focal length times tanθ). With the
    object in water (n = 1.333) an ideal thin lens, whose image is exactly that, showed
    ``percent_ftan`` 33.3 % at every field (against f·tanθ); now 0, as ``percent_paraxial``
    always was."""
    water = jl.ModelGlass(1.333, 55.0)
    lens = jl.Lens(surfaces=(ParaxialSurface(50.0),), thickness=jnp.array([50.0]),
                   materials=(jl.Air(),), epd=5.0, fields=jnp.array([0.0, 10.0, 20.0]),
                   object_material=water)
    d = analysis.distortion(lens)
    n = float(water.index(lens.primary_wavelength))
    np.testing.assert_allclose(d.f_tan, n * 50.0 * np.tan(np.radians([0.0, 10.0, 20.0])),
                               rtol=1e-12)
    np.testing.assert_allclose(d.chief_height, d.f_tan, rtol=1e-12)
    np.testing.assert_allclose(d.percent_ftan, 0.0, atol=1e-10)
    np.testing.assert_allclose(d.percent_paraxial, 0.0, atol=1e-10)
    # In air nothing changes: f·tanθ.
    air = jl.Lens(surfaces=lens.surfaces, thickness=lens.thickness, materials=lens.materials,
                  epd=5.0, fields=lens.fields)
    np.testing.assert_allclose(analysis.distortion(air).f_tan,
                               50.0 * np.tan(np.radians([0.0, 10.0, 20.0])), rtol=1e-12)


def test_report_distortion_with_an_object_in_water_agrees_with_distortion():
    """``report`` used EFL·tanθ as its f-tanθ reference where ``distortion`` uses n·EFL·tanθ:
    with the object in water the report still showed 33.3 % for an ideal lens."""
    from jaxlens.analysis.report import report_data

    water = jl.ModelGlass(1.333, 55.0)
    lens = jl.Lens(surfaces=(ParaxialSurface(50.0),), thickness=jnp.array([50.0]),
                   materials=(jl.Air(),), epd=5.0, fields=jnp.array([0.0, 10.0, 20.0]),
                   object_material=water)
    rows = report_data(lens)["fields"]
    d = analysis.distortion(lens)
    np.testing.assert_allclose([r["distortion"] for r in rows], d.percent_ftan, atol=1e-10)
    np.testing.assert_allclose([r["distortion"] for r in rows], 0.0, atol=1e-10)


# -------------------------------------- mtf at a depth: the working F-number of that object
def test_mtf_at_a_depth_uses_the_working_fnumber_of_that_object():
    """An ideal lens (f = 50 mm, EPD 10 mm) with its image plane 100 mm behind it images an
    object 100 mm in front at 1:1, working F/10. ``mtf(lens, depth=100)`` of the lens made
    for infinity multiplied the (perfect) geometric MTF by the diffraction MTF at F/5, the
    working F-number of its own object: 0.814 instead of 0.631 at 50 cycles/mm, 0.458
    instead of 0.048 at 150, and its default frequencies ran to twice the cut-off. The same
    lens with its own object at 100 mm gave the right values; the two now agree."""
    from jaxlens.imaging.psf import GeometricPSF, mtf

    def lens(obj):
        return jl.Lens(surfaces=(ParaxialSurface(50.0),), thickness=jnp.array([100.0]),
                       materials=(jl.Air(),), epd=10.0, object_distance=obj)

    freqs = jnp.array([0.0, 50.0, 100.0, 150.0])
    model = GeometricPSF(pupil=16)
    own = mtf(lens(100.0), 0.0, frequencies=freqs, model=model)
    given = mtf(lens(None), 0.0, frequencies=freqs, model=model, depth=100.0)
    s = np.asarray(freqs) * 0.5875618e-3 * 10.0  # ν·λ·F#, working F/10
    ideal = 2 / np.pi * (np.arccos(s) - s * np.sqrt(1 - s * s))
    for _, t, sag in (own, given):
        np.testing.assert_allclose(t, ideal, rtol=0, atol=1e-9)
        np.testing.assert_allclose(sag, ideal, rtol=0, atol=1e-9)
    # Default frequencies: 0 to the cut-off 1/(λ·F#) of the working F-number.
    top = 1 / (0.5875618e-3 * 10.0)
    assert float(mtf(lens(None), 0.0, model=model, depth=100.0)[0][-1]) == pytest.approx(top)
    # And the other way: a lens made for 100 mm, asked about infinity, is at F/5.
    inf = mtf(lens(100.0), 0.0, frequencies=freqs, model=model, depth=float("inf"),
              diffraction=True)
    assert float(inf[1][1]) < 1.0  # defocused (its image of infinity is at 50 mm)
    assert float(mtf(lens(100.0), 0.0, model=model, depth=float("inf"))[0][-1]) == \
        pytest.approx(2 * top)


# ------------------------------------------ a depth traced by jit, with a closed-over lens
def test_a_jitted_function_of_depth_over_a_closed_over_lens():
    """``jax.jit(lambda d: rms_spot(lens, depth=d))`` with a concrete lens closed over: the
    material check evaluated the lens's indices inside the trace and raised a
    TracerArrayConversionError (valid input refused). Once past that, a traced depth could
    not be checked: inf gave NaN radii where eager calls trace the collimated beam, and −5 mm
    gave 17.6 mm radii where eager calls refuse it. Now the finite depth gives the eager
    answer and the others raise at run time, naming the range and unit."""
    import equinox as eqx

    lens = jl.zoo.cooke_triplet()
    spot = eqx.filter_jit(lambda d: analysis.rms_spot(lens, depth=d).polychromatic)
    np.testing.assert_allclose(spot(jnp.asarray(1e4)),
                               analysis.rms_spot(lens, depth=1e4).polychromatic, rtol=1e-12)
    for bad in (jnp.inf, -5.0, jnp.nan):
        with pytest.raises(Exception, match=r"rms_spot: a traced depth must be finite and in "
                                            r"\(0, inf\) mm"):
            spot(jnp.asarray(bad))
