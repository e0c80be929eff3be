"""Round 43a: ``render`` and ``image_scale`` of object-space telecentric lenses
(``Lens(object_na=...)``: fields are object heights in mm).

Before, both refused such a lens ("needs an entrance pupil at a finite distance ...
paraxial.magnification"). Now the scene is the object plane: the scene point shown at sensor
position u (mm) is the object point u/m (mm), m = ``paraxial.magnification`` (``image_scale``
returns m for such a lens), so the scene spans the sensor's half-size over |m| on the object
plane; the rays of a pixel count where they leave into the object cone (|slope| <= tan u,
the NA's); the image is read out rotated by 180° as for every lens.

Independent answers:
* an ideal telecentric relay (paraxial lenses f1 = 50, f2 = 25 mm, the stop at their common
  focus: m = −f2/f1 = −0.5, no aberration, uniform illumination) renders a linear pattern
  given on the object plane (mm) as that pattern at X = x/m: inverted and half size in
  sensor millimetres, checked against the analytic values at each pixel's centre;
* the same relay with its first lens's rim clipping the cones renders a white object as the
  cone's share that passes (numpy quadrature, as round 42a's closed form);
* the flux-weighted centroids of rendered Gaussian blobs on round 42a's telecentric triplet
  (m ≈ −0.67, 9 % distortion at 10 mm) against optiland 0.6.3's
  (tools/tele43a_reference.py: Gauss–Hermite over the blob × a Gauss rule over the cone);
* the gradient of a render loss with respect to a lens parameter against central
  differences (float64, samples and footprints held fixed).
"""

from __future__ import annotations

import json
import pathlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import aiming, render
from jaxlens.optics import paraxial
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.optics.surfaces import Stop

DATA = pathlib.Path(__file__).parent / "data"
KEY = jax.random.PRNGKey(3)
WL = [0.5875618]


def _relay(f1=50.0, f2=25.0, na=0.05, rim=jnp.inf):
    air = jl.Air()
    return jl.Lens(surfaces=(ParaxialSurface(focal_length=f1, semi_diameter=rim), Stop(),
                             ParaxialSurface(focal_length=f2)),
                   thickness=jnp.array([f1, f2, f2]), materials=(air, air, air), stop=1,
                   object_distance=f1, object_na=na, fields=(0.0, 3.0, 6.0))


def _object_grid(shape, sensor, m):
    """Object-plane (X, Y) in mm of each scene pixel's centre (the documented mapping)."""
    hs, ws = shape
    (h, w), p = sensor.resolution, float(sensor.pixel_size)
    r, c = np.meshgrid(np.arange(hs), np.arange(ws), indexing="ij")
    x = -(c - 0.5 * (ws - 1)) * p * w / ws  # ideal sensor position of the scene pixel
    y = (r - 0.5 * (hs - 1)) * p * h / hs
    return x / m, y / m


def _sensor_points(sensor):
    (h, w), p = sensor.resolution, float(sensor.pixel_size)
    r, c = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return -(c - 0.5 * (w - 1)) * p, (r - 0.5 * (h - 1)) * p


def test_image_scale_is_the_magnification_and_maps_heights_both_ways():
    lens = _relay()
    assert float(aiming.image_scale(lens)) == pytest.approx(-0.5, rel=1e-15)
    np.testing.assert_allclose(aiming.field_to_ideal(lens, jnp.array([1.0, 2.0])),
                               [-0.5, -1.0], rtol=1e-15)
    np.testing.assert_allclose(aiming.field_to_ideal(lens, 4.0), [0.0, -2.0], rtol=1e-15)
    np.testing.assert_allclose(aiming.ideal_to_field(lens, jnp.array([-0.5, 3.0])),
                               [1.0, -6.0], rtol=1e-15)
    # The scene spans the sensor's half sides over |m| on the object plane (mm) ...
    sensor = jl.Sensor(resolution=(8, 12), pixel_size=0.05)
    np.testing.assert_allclose(aiming.scene_extent(lens, sensor), (0.6, 0.4), rtol=1e-14)
    # ... as an angle lens's spans atan(half side / K) (deg): an ideal f = 50 mm lens.
    air = jl.Air()
    camera = jl.Lens(surfaces=(Stop(), ParaxialSurface(focal_length=50.0)),
                     thickness=jnp.array([0.0, 50.0]), materials=(air, air), stop=0, epd=10.0)
    np.testing.assert_allclose(aiming.scene_extent(camera, sensor),
                               np.rad2deg(np.arctan([0.3 / 50.0, 0.2 / 50.0])), rtol=1e-12)
    with pytest.raises(ValueError, match=r"Sensor.*mm"):
        aiming.scene_extent(lens)  # the relay has no sensor


def test_a_relay_renders_the_object_inverted_at_half_size():
    """The linear object radiance a + b·X + c·Y (X, Y in mm on the object plane): the pixel
    at sensor point (x, y) shows X = x/m, Y = y/m with m = −0.5 (f2/f1), i.e. the object's
    +Y side lands at sensor −y, at half its size. A linear pattern is reproduced exactly by
    the scene's bilinear lookup and by the pixel average (the pixel's samples are uniform
    in it), so the only error is the Monte-Carlo mean of the jitter (averaged over the
    passing rays, ``relative_illumination=False``): |∇|·p/|m|/sqrt(12·spp), 1.3e-3 per pixel;
    5e-3 is 4 of it. The PSF method samples the scene at the pixel centres: exact."""
    lens = _relay()
    sensor = jl.Sensor(resolution=(8, 12), pixel_size=0.05)
    m = -0.5
    a, b, c = 1.0, 0.3, -0.2
    X, Y = _object_grid((16, 24), sensor, m)
    scene = jnp.asarray((a + b * X + c * Y)[..., None])
    x, y = _sensor_points(sensor)
    want = a + b * x / m + c * y / m
    img = render.render(lens, scene, spp=64, key=KEY, sensor=sensor, wavelengths=WL,
                        relative_illumination=False)  # its count noise: the next test's
    inner = np.s_[1:-1, 1:-1]  # the border pixels' jitter reaches past the scene's edge
    np.testing.assert_allclose(np.asarray(img)[..., 0][inner], want[inner], atol=5e-3)
    # Not upright-at-half (m = +0.5) nor full size: the pattern's slopes tell.
    assert np.max(np.abs(want - (a + b * x / 0.5 + c * y / 0.5))) > 0.1


@pytest.mark.slow
def test_the_psf_method_renders_the_relay_the_same():
    """The PSF method (distortion map, PSFs at object heights, the illumination map) samples
    the linear pattern at the pixel centres: exact."""
    lens = _relay()
    sensor = jl.Sensor(resolution=(8, 12), pixel_size=0.05)
    X, Y = _object_grid((16, 24), sensor, -0.5)
    scene = jnp.asarray((1.0 + 0.3 * X - 0.2 * Y)[..., None])
    x, y = _sensor_points(sensor)
    want = 1.0 + 0.3 * x / -0.5 - 0.2 * y / -0.5
    inner = np.s_[1:-1, 1:-1]
    psf = render.render(lens, scene, spp=4, key=KEY, sensor=sensor, wavelengths=WL,
                        method=render.PSFRender(kernel_size=3))
    np.testing.assert_allclose(np.asarray(psf)[..., 0][inner], want[inner], atol=1e-9)


@pytest.mark.slow  # 15 s; the next test checks the illumination against optiland
def test_a_white_object_renders_the_share_of_the_cone_the_first_lens_passes():
    """Round 42a's closed form: the first lens (rim R) keeps the slopes within R/f1 of
    −h/f1 of the cone |s| <= tan u; the irradiance is the cone's projected solid angle there
    (cos⁴γ over the slopes, numpy quadrature) relative to the axis's; no cos⁴ falloff of the
    field. The pixel (1 mm on the object plane) averages it: 8 × 8 points over each pixel.
    Monte-Carlo: spp = 256 stratified rays per pixel, about 1e-2."""
    f1, na, rim = 50.0, 0.05, 3.5
    lens = _relay(f1=f1, na=na, rim=rim)
    sensor = jl.Sensor(resolution=(5, 5), pixel_size=0.5)  # heights to 2√2 mm
    img = np.asarray(render.render(lens, jnp.ones((5, 5, 1)), spp=256, key=KEY,
                                   sensor=sensor, wavelengths=WL))[..., 0]
    x, y = _sensor_points(sensor)
    tu = na / np.sqrt(1 - na * na)
    g = np.linspace(-tu, tu, 801)
    sx, sy = np.meshgrid(g, g)
    cone = sx**2 + sy**2 <= tu * tu
    w = 1.0 / (1.0 + sx**2 + sy**2) ** 2

    def omega(hh):
        return np.sum(w * (cone & (sx**2 + (sy + hh / f1) ** 2 <= (rim / f1) ** 2)))

    q = (np.arange(8) + 0.5) / 8 - 0.5  # pixel-average points (fractions of a pixel)
    want = np.array([[np.mean([omega(np.hypot(xx + a * 0.5, yy + b * 0.5) / 0.5)
                               for a in q for b in q]) for xx, yy in zip(xr, yr, strict=True)]
                     for xr, yr in zip(x, y, strict=True)]) / omega(0.0)
    assert want.min() < 0.6
    # Per pixel the valid share's Monte-Carlo noise reaches 3.5e-2 (measured); the pixels of
    # one |x|, |y| pair (the lens is round) average it down.
    np.testing.assert_allclose(img, want, atol=5e-2)
    sym = lambda a: (a + a[::-1] + a[:, ::-1] + a[::-1, ::-1]) / 4  # noqa: E731
    np.testing.assert_allclose(sym(img), sym(want), atol=3e-2)


def _open(lens):
    return eqx.tree_at(lambda m: [s.semi_diameter for s in m.surfaces], lens,
                       [jnp.inf for _ in lens.surfaces])


@pytest.mark.slow
def test_blob_centroids_match_optiland():
    """A Gaussian object blob (σ = 0.45 mm) on round 42a's triplet: the first moment of the
    rendered irradiance against optiland's flux-weighted mean landing point of the blob's
    light. The blob's image spans ~2 sensor pixels (σ), so the pixel-sum first moment equals
    the continuous one to e^(−2π²·4); the scene's bilinear lookup adds Δ²/6 to the blob's
    variance (1e-6 mm through the map's curvature). What remains is the Monte-Carlo noise
    of the ray render: 1.5e-3 mm measured at spp = 64 (about 800 rays over the blob's
    core), so 2e-3 mm at spp = 256. The chief ray lies 5e-3 to 8e-3 mm from the centroid
    and m·X0 up to 1.4e-2 mm: the test tells them apart."""
    ref = json.loads((DATA / "tele43a" / "tele_triplet_far_blobs.json").read_text())
    lens = _open(jl.load(DATA / "tele42a" / "tele_triplet_far.zmx"))
    m = float(paraxial.magnification(lens))
    np.testing.assert_allclose(m, ref["paraxial_magnification"], rtol=1e-12)
    sensor = jl.Sensor(resolution=(48, 48), pixel_size=0.15)
    X, Y = _object_grid((192, 192), sensor, m)
    x, y = _sensor_points(sensor)
    for blob in ref["blobs"]:
        (x0, y0), s = blob["centre"], blob["sigma"]
        f = np.exp(-((X - x0) ** 2 + (Y - y0) ** 2) / (2 * s * s))
        img = np.asarray(render.render(lens, jnp.asarray(f[..., None]), spp=256, key=KEY,
                                       sensor=sensor, wavelengths=[ref["wavelength_um"]]))
        e = img[..., 0]
        got = np.array([np.sum(e * x), np.sum(e * y)]) / np.sum(e)
        np.testing.assert_allclose(got, blob["centroid"], rtol=0, atol=2e-3)
        if x0 or y0:
            assert np.max(np.abs(np.array(blob["chief_xy"]) - blob["centroid"])) > 4.5e-3


def test_the_render_gradient_matches_central_differences():
    """d/df2 of a weighted sum of the image (f2: the relay's second focal length, which
    moves the focus and the scale), samples and footprints held fixed, float64."""
    lens = _relay()
    sensor = jl.Sensor(resolution=(6, 6), pixel_size=0.1)
    X, Y = _object_grid((6, 6), sensor, -0.5)
    scene = jnp.asarray((1.0 + 0.5 * np.sin(X) + 0.3 * Y * Y)[..., None])
    fp = render.footprints(lens, sensor=sensor, wavelengths=WL, grid=3)
    wts = jnp.asarray(np.random.default_rng(0).uniform(size=(6, 6, 1)))
    method = render.RayRender(footprint_grid=3, footprints=fp)

    def loss(f2):
        ln = eqx.tree_at(lambda m: m.surfaces[2].focal_length, lens, f2)
        return jnp.sum(wts * render.render(ln, scene, spp=9, key=KEY, sensor=sensor,
                                           wavelengths=WL, method=method))

    g = float(jax.grad(loss)(jnp.asarray(25.0)))
    e = 1e-4
    fd = (float(loss(jnp.asarray(25.0 + e))) - float(loss(jnp.asarray(25.0 - e)))) / (2 * e)
    assert abs(g) > 1e-3
    np.testing.assert_allclose(g, fd, rtol=1e-5)


def test_bad_input_names_the_range_and_unit():
    lens = _relay()
    sensor = jl.Sensor(resolution=(4, 4), pixel_size=0.1)
    with pytest.raises(ValueError, match=r"object heights \(mm\).*finite object distance in mm"):
        render.render(lens, jnp.ones((4, 4, 1)), spp=1, key=KEY, sensor=sensor,
                      wavelengths=WL, depth=jnp.inf)
    with pytest.raises(ValueError, match=r"depth.*> 0|positive|mm"):
        render.render(lens, jnp.ones((4, 4, 1)), spp=1, key=KEY, sensor=sensor,
                      wavelengths=WL, depth=-10.0)
    # The image at infinity (the object at the front focus of one lens): no image scale.
    air = jl.Air()
    single = jl.Lens(surfaces=(Stop(), ParaxialSurface(focal_length=50.0)),
                     thickness=jnp.array([25.0, 50.0]), materials=(air, air), stop=0,
                     object_distance=25.0, object_na=0.05)  # at its focus
    with pytest.raises(ValueError, match=r"image mm per object mm.*finite and nonzero"):
        aiming.image_scale(single)
    with pytest.raises(ValueError, match=r"finite and nonzero"):
        render.render(single, jnp.ones((4, 4, 1)), spp=1, key=KEY, sensor=sensor,
                      wavelengths=WL)
    # A lens with an afocal image space has no image positions, hence no image scale.
    import dataclasses
    afocal = dataclasses.replace(_relay(), afocal_image=True)
    with pytest.raises(ValueError, match=r"afocal image space"):
        aiming.image_scale(afocal)
    # Object heights given as NaN to the mapping are refused, naming mm.
    with pytest.raises(ValueError, match="mm"):
        aiming.field_to_ideal(lens, jnp.array([0.0, jnp.nan]))


def test_the_distortion_figure_of_a_telecentric_relay_reads_zero():
    """Before: the ideal relay's distortion (1e-14 %, rounding) was drawn as noise on an
    axis with an offset "1e−14", and the dashed curve's legend named OpticStudio's F-Tan,
    which has no meaning without a field angle; a field label of −0.0 printed "-0.0"."""
    import matplotlib

    matplotlib.use("Agg")
    from jaxlens import plot

    fig = plot.plot_field_curvature(_relay())
    fig.canvas.draw()
    ax = fig.axes[1]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["against m·h", "against the paraxial chief ray (parallel to the axis "
                      "at h)"]
    assert not any("Tan" in t for t in labels)
    assert ax.xaxis.get_offset_text().get_text() == ""
    for line in ax.get_lines()[:2]:
        x = np.asarray(line.get_xdata())
        assert np.all(x == 0.0) and not np.any(np.signbit(x))
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    assert not any(t.lstrip("−-").strip("0.") == "" and t[0] in "−-" for t in ticks), ticks
    assert plot._field_label(-0.0, _relay()) == "0.0 mm"
    assert plot._field_label(np.array([-0.0, 2.0])) == "(0.0°, 2.0°)"


def test_a_white_object_renders_optilands_point_irradiance():
    """Round 42a's triplet without semi-diameters (every ray of the NA cone passes): its
    illumination falls to 0.72 at 10 mm only by the change of the local areal magnification
    (distortion), no cos⁴ law. A white render's pixels at the images of the heights 5 and
    10 mm (a one-column sensor with a pixel centre there, and its mirror image; 0.09 to 0.18
    mm pixels, whose average differs from the point value by 2e-5) against optiland's
    irradiance at those points (tools/tele43a_reference.py: L·Σ 1/|det ∂x/∂X| over the
    pupil rays that land there, relative to the axis's). Monte-Carlo: 1024 rays per pixel,
    ±8e-3 per pixel measured over 3 keys; the mean of the two mirror pixels to 1e-2.

    Round 42a's ``relative_illumination`` (the flux of an object patch over the area of its
    beam centroid's image) gives 0.7140 at 10 mm, optiland's 0.7140 by the same definition:
    the two differ where the per-ray magnification varies over the pupil (defocus off axis),
    0.7 % here. Before this round's ``apertured`` change the render read 0.59 at 10 mm: the
    stop, unbounded in this lens, got the paraxial marginal ray's radius and clipped the
    off-axis cones."""
    ref = json.loads((DATA / "tele43a" / "tele_triplet_far_blobs.json").read_text())
    lens = _open(jl.load(DATA / "tele42a" / "tele_triplet_far.zmx"))
    for point in ref["ri_point"]:
        y = point["image_xy"][1]  # m < 0: below the axis
        sensor = jl.Sensor(resolution=(81, 1), pixel_size=abs(y) / 40)
        img = np.asarray(render.render(lens, jnp.ones((81, 1, 1)), spp=1024, key=KEY,
                                       sensor=sensor, wavelengths=[ref["wavelength_um"]]))
        np.testing.assert_allclose(0.5 * (img[0, 0, 0] + img[80, 0, 0]), point["ri"],
                                   atol=1e-2, err_msg=str(y))
        np.testing.assert_allclose(img[40, 0, 0], 1.0, atol=1e-2)
    assert ref["ri_point"][1]["ri"] < 0.75
