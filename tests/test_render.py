"""render: radiometry against independent forward tracing, geometry, gradients, bad input.

Most cases use the Cooke triplet (spherical surfaces compile fast) on a coarse sensor of
1 mm pixels, where its blur (tens of µm) and distortion (−0.4 %) are far below a pixel.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.imaging import distortion as DR
from jaxlens.imaging import radiometry as RAD
from jaxlens.imaging import render as R

KEY = jax.random.PRNGKey(0)
SENSOR = jaxlens.Sensor((12, 18), 2.0)  # 24 × 36 mm in 2 mm pixels


@pytest.fixture(scope="module")
def cooke():
    return jaxlens.zoo.cooke_triplet()


def ramp_scene(h, w):
    r = np.linspace(0.2, 0.8, h)[:, None] * np.ones((1, w))
    c = np.ones((h, 1)) * np.linspace(0.1, 0.9, w)[None, :]
    return jnp.asarray(np.stack([r, c, 0.5 + 0.3 * r * c], -1))


def radius_map(sensor):
    h, w = sensor.resolution
    rr, cc = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    x, y = R.pixel_positions(sensor.resolution, float(sensor.pixel_size), rr, cc)
    return np.hypot(x, y)


def test_white_scene_renders_to_relative_illumination(cooke):
    """A uniform scene of 1 renders to the relative-illumination curve that
    ``radiometry`` computes by forward tracing (vignetting, cos⁴, distortion)."""
    img = np.asarray(R.render(cooke, jnp.ones((12, 18, 3)), spp=256, key=KEY, sensor=SENSOR,
                              patch=6))
    fields = np.linspace(0.0, 25.0, 81)  # 81 fields and pupil=48, as render(method=PSFRender())
    ri = RAD.relative_illumination(cooke, fields, pupil=48)
    h = np.hypot(*np.asarray(ri.image_xy).T)
    curve = np.asarray(ri.ri)
    assert np.all(np.diff(h) > 0) and curve[0] == pytest.approx(1.0)
    assert curve[-1] < 0.75  # cos⁴ and vignetting at 25°
    r = radius_map(SENSOR)
    pred = np.interp(r, h, curve)
    rings = np.argsort(r.ravel()).reshape(6, -1)  # six rings of 36 pixels, inner to outer
    for c in range(3):
        # Per pixel within Monte-Carlo noise; averaged over rings within 1 %.
        np.testing.assert_allclose(img[..., c], pred, atol=0.05)
        for ring in rings:
            assert img[..., c].ravel()[ring].mean() == pytest.approx(pred.ravel()[ring].mean(),
                                                                     abs=0.01)


def test_render_is_upright_at_infinity_and_finite_depth(cooke):
    """Through a sharp, nearly distortion-free lens the scene comes out upright and
    unchanged, for an object at infinity and at 2 m (same field angles)."""
    scene = ramp_scene(12, 18)
    for depth in (jnp.inf, 2000.0):
        img = R.render(cooke, scene, spp=16, key=KEY, sensor=SENSOR, patch=6, depth=depth,
                       relative_illumination=False)
        np.testing.assert_allclose(img, scene, atol=0.02)


def wave_scene(h, w):
    rr, cc = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return jnp.asarray(np.stack([0.5 + 0.4 * np.sin(1.3 * rr + 0.4 * cc),
                                 0.5 + 0.4 * np.cos(1.1 * cc),
                                 0.5 + 0.3 * np.sin(0.9 * rr) * np.cos(0.7 * cc)], -1))


def test_psf_method_matches_ray_method(cooke):
    """Defocused by 20 mm the Cooke triplet blurs over two pixels; both methods agree."""
    lens = eqx.tree_at(lambda m: m.thickness, cooke, cooke.thickness.at[-1].add(20.0))
    scene = wave_scene(12, 18)
    ray = R.render(lens, scene, spp=256, key=KEY, sensor=SENSOR, patch=6)
    conv = R.render(lens, scene, spp=16, key=KEY, sensor=SENSOR, patch=6,
                    method=R.PSFRender(kernel_size=7))
    sharp = R.render(cooke, scene, spp=256, key=KEY, sensor=SENSOR, patch=6)
    psnr = jaxlens.io.images.psnr
    assert psnr(ray, conv, data_range=1.0) > 38.0
    assert psnr(ray, sharp, data_range=1.0) < 30.0


def _render_loss(theta, lens, scene, target, checkpoint, fp):
    lens = eqx.tree_at(lambda m: (m.surfaces[0].c, m.thickness), lens,
                       (theta[0], lens.thickness.at[-1].set(theta[1])))
    img = R.render(lens, scene, spp=16, key=KEY, sensor=SENSOR, patch=6,
                   checkpoint=checkpoint, method=R.RayRender(footprints=fp))
    return jnp.mean((img - target) ** 2)


def test_render_gradient_matches_finite_differences_and_checkpoint(cooke):
    """float64 central differences; the checkpointed gradient equals the plain one."""
    scene = wave_scene(12, 18)
    target = jnp.asarray(np.random.default_rng(1).random((12, 18, 3)))
    theta = jnp.array([float(cooke.surfaces[0].c), float(cooke.thickness[-1])])
    fp = R.footprints(cooke, sensor=SENSOR)  # the sampling is held fixed

    steps = jnp.array([1e-8, 1e-6])
    shifts = jnp.concatenate([jnp.diag(steps), -jnp.diag(steps)])  # θ ± h·e_i, i = 0, 1

    # Both gradients and the four shifted losses in one compiled program (the losses in a
    # loop over the shifts, so the loss is compiled once).
    @jax.jit
    def run(theta, fp):
        f = lambda th, ck: _render_loss(th, cooke, scene, target, ck, fp)  # noqa: E731
        g = jax.grad(f)(theta, True)
        g_plain = jax.grad(f)(theta, False)
        return g, g_plain, jax.lax.map(lambda e: f(theta + e, True), shifts)

    g, g_plain, v = run(theta, fp)
    np.testing.assert_allclose(g, g_plain, rtol=1e-12, atol=0)
    for i in range(2):
        fd = (v[i] - v[i + 2]) / (2 * steps[i])
        assert float(g[i]) == pytest.approx(float(fd), rel=2e-4)
    assert np.all(np.abs(np.asarray(g)) > 0)


def test_bad_input(cooke, tmp_path):
    ok = jnp.ones((12, 18, 3))
    with pytest.raises(ValueError, match="does not match the 12x18 sensor"):
        R.render(cooke, jnp.ones((12, 12, 3)), spp=4, key=KEY, sensor=SENSOR)
    with pytest.raises(ValueError, match=r"\[H, W, C\]"):
        R.render(cooke, jnp.ones((12, 18)), spp=4, key=KEY, sensor=SENSOR)
    for spp in (0, -3, 2.5):
        with pytest.raises(ValueError, match="spp must be a positive int"):
            R.render(cooke, ok, spp=spp, key=KEY, sensor=SENSOR)
    with pytest.raises(ValueError, match="linear float"):
        R.render(cooke, jnp.ones((12, 18, 3), jnp.uint8), spp=4, key=KEY, sensor=SENSOR)
    with pytest.raises(TypeError, match="not a string"):
        R.render(cooke, ok, spp=4, key=KEY, sensor=SENSOR, method="psf")
    with pytest.raises(ValueError, match="no sensor"):
        R.render(eqx.tree_at(lambda m: m.sensor, cooke, None, is_leaf=lambda x: x is None),
                 ok, spp=4, key=KEY)
    with pytest.raises(ValueError, match="wavelengths"):
        R.render(cooke, ok, spp=4, key=KEY, sensor=SENSOR, wavelengths=(0.55,))


def distorting_lens():
    """A biconvex singlet behind a remote stop: several per cent of pincushion distortion."""
    glass = jaxlens.ModelGlass(1.5168, 64.17)
    lens = jaxlens.Lens(
        surfaces=(jaxlens.Stop(1.5), jaxlens.Sphere(1 / 50.0), jaxlens.Sphere(-1 / 50.0)),
        thickness=jnp.array([25.0, 6.0, 50.0]),
        materials=(jaxlens.Air(), glass, jaxlens.Air()),
        stop=0,
        epd=3.0,
        sensor=jaxlens.Sensor((16, 16), 2.0),
    )
    bfl = jaxlens.bfl(lens)
    return eqx.tree_at(lambda m: m.thickness, lens, lens.thickness.at[-1].set(bfl))


@pytest.mark.slow
def test_distortion_relaxation_aligns_the_image():
    """A spot near the corner lands at D(v) in a plain render and at v after pre-warping."""
    lens = distorting_lens()
    h = w = 24
    p = 32.0 / 24
    sensor = jaxlens.Sensor((h, w), p)
    rr, cc = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    r0, c0 = 3.5, 19.5
    spot = np.exp(-((rr - r0) ** 2 + (cc - c0) ** 2) / (2 * 0.7**2))
    scene = jnp.asarray(np.repeat(spot[..., None], 3, -1))
    v = jnp.array(R.pixel_positions((h, w), p, r0, c0))  # ideal position of the spot, mm
    dv = DR._forward_map(lens, v[None], None, 6)[0][0]  # where its chief ray lands, mm
    pred = (float(dv[1]) / p + 11.5, -float(dv[0]) / p + 11.5)  # (row, col)
    assert np.hypot(pred[0] - r0, pred[1] - c0) > 0.6

    def centroid(img):
        g = np.asarray(img[..., 1])
        return (g * rr).sum() / g.sum(), (g * cc).sum() / g.sum()

    plain = R.render(lens, scene, spp=64, key=KEY, patch=8, sensor=sensor,
                     relative_illumination=False)
    img, pen = R.relaxed_render(lens, scene, spp=64, key=KEY, patch=8, alpha=0.5,
                                 sensor=sensor, relative_illumination=False)
    assert np.hypot(*np.subtract(centroid(plain), pred)) < 0.1
    assert np.hypot(*np.subtract(centroid(img), (r0, c0))) < 0.1
    assert float(pen) > 0


def test_prewarp_shows_at_each_pixel_the_scene_at_its_chief_ray_landing_point():
    """The CI version of the test above, on the definition: the pre-warped scene at ideal
    position v is the scene at D(v), where D(v) is where the chief ray of v's field lands.

    The scene is the linear ramp (row, col), which bilinear interpolation reproduces
    exactly, and the sensor has one pixel per distortion-grid node; D comes from
    ``analysis.chief_ray`` (the lens's stop is its first surface, so aiming at the paraxial
    entrance pupil is aiming at the stop), the field of v from ``v = K·tan θ``. A pre-warp
    the wrong way round (scene(D⁻¹(v)), or rows and columns swapped) moves every corner
    value by over a pixel."""
    lens = distorting_lens()
    n, p = 17, 32.0 / 17
    sensor = jaxlens.Sensor((n, n), p)
    rr, cc = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float), indexing="ij")
    ramp = jnp.asarray(np.stack([rr, cc, rr + 2 * cc], -1))
    got = np.asarray(DR.prewarp(lens, ramp, sensor=sensor, grid=(n, n)))
    x, y = R.pixel_positions((n, n), p, rr, cc)
    k = float(jaxlens.imaging.aiming.image_scale(lens))
    fields = np.degrees(np.arctan(np.stack([x, y], -1).reshape(-1, 2) / k))
    land = jax.vmap(lambda f: jaxlens.analysis.chief_ray(lens, f).origin[:2])(
        jnp.asarray(fields))
    land = np.asarray(land).reshape(n, n, 2)
    # Back to (row, col) with pixel_positions's frame: x = −(col − c₀)·p, y = (row − r₀)·p.
    want_r = land[..., 1] / p + 0.5 * (n - 1)
    want_c = -land[..., 0] / p + 0.5 * (n - 1)
    np.testing.assert_allclose(got[..., 0], want_r, atol=1e-6)
    np.testing.assert_allclose(got[..., 1], want_c, atol=1e-6)
    np.testing.assert_allclose(got[..., 2], want_r + 2 * want_c, atol=1e-6)
    # Barrel distortion pulls the corners in by about a pixel.
    assert want_r[0, 0] > 0.9 and want_c[0, 0] > 0.9


@pytest.mark.slow
def test_distortion_maps_are_inverse(cooke):
    """Forward chief rays (object side, aimed at the stop) and backward chief rays (sensor
    side, aimed at the stop) give inverse maps (grid as render(method=PSFRender()) uses)."""
    lens = cooke
    d = DR.distortion_map(lens, grid=(17, 17), sensor=SENSOR)
    inv = DR.inverse_distortion_map(lens, resolution=(12, 18),
                                    pixel_size=jnp.asarray(SENSOR.pixel_size), grid=(17, 17))
    shift = np.hypot(*(np.asarray(d.real) - np.asarray(d.ideal)).T)
    assert 0.02 < shift.max() < 0.2  # mm: −0.4 % distortion
    back, _ = DR._forward_map(lens, inv, None, 6)
    np.testing.assert_allclose(back, d.ideal, atol=1e-9)


@pytest.mark.slow
def test_distortion_penalty_is_differentiable():
    lens = distorting_lens()
    d = DR.distortion_map(lens, grid=(5, 5))
    assert np.hypot(*(np.asarray(d.real) - np.asarray(d.ideal)).T).max() > 2.0  # mm, −12 %
    g = jax.grad(lambda c: DR.alignment_penalty(
        eqx.tree_at(lambda m: m.surfaces[1].c, lens, c), alpha=1.0, grid=(5, 5)))(
        lens.surfaces[1].c)
    assert np.isfinite(float(g)) and float(g) != 0


def test_render_drops_vignetting_factors_in_both_methods(cooke):
    """Vignetting factors belong to a lens's few defined fields, a render to every pixel's:
    ``render`` drops them in both methods (before: PSFRender's PSFs at field points equal
    to a defined field took them, and 60 % of this image's pixels changed)."""
    lens = eqx.tree_at(lambda m: m.thickness, cooke, cooke.thickness.at[-1].add(20.0))
    factors = np.zeros((lens.fields.shape[0], 5))
    factors[:, 3] = 0.6  # VCY: the pupil squeezed to 40 % in y on every defined field
    vignetted = dataclasses.replace(lens, vignetting=jnp.asarray(factors))
    scene = wave_scene(12, 18)
    # Each method at the spp of the tests above (the ray method's with relative
    # illumination: 256): the compiled programs of those tests serve this one.
    for method, spp in ((R.PSFRender(kernel_size=7), 16), (R.RayRender(), 256)):
        a = R.render(vignetted, scene, spp=spp, key=KEY, sensor=SENSOR, patch=6, method=method)
        b = R.render(lens, scene, spp=spp, key=KEY, sensor=SENSOR, patch=6, method=method)
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
