"""Bad input, round 32a (tools/audit32a_probe.py, the Python API): one test per class of gap
fixed. Each names what main did with the input: a silent answer, a vague error or a false
alarm."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
import jaxlens.analysis as A
import jaxlens.design as D
from jaxlens import nets, zoo

KEY = jax.random.PRNGKey(0)


@pytest.mark.parametrize("make", [
    lambda dt: nets.Conv(3, 4, 3, key=KEY, dtype=dt),
    lambda dt: nets.Pointwise(3, 4, key=KEY, dtype=dt),
    lambda dt: nets.Depthwise(3, key=KEY, dtype=dt),
    lambda dt: nets.LayerNorm2d(3, dtype=dt),
], ids=["Conv", "Pointwise", "Depthwise", "LayerNorm2d"])
def test_net_layers_refuse_an_integer_dtype(make):
    """Main: int32 made integer weights (a Conv's uniform draws all truncated to 0)."""
    with pytest.raises(ValueError, match=r"dtype must be None, float32 or float64"):
        make(jnp.int32)
    assert make(jnp.float32).weight.dtype == jnp.float32  # control


def test_net_layers_refuse_an_input_with_other_channels():
    """Main: a Depthwise or LayerNorm2d built for 3 channels broadcast a 1-channel image to
    3 channels without a word; a Conv given [H, W] failed inside lax ("lhs and rhs ndim")."""
    x1 = jnp.ones((8, 8, 1))
    with pytest.raises(ValueError, match=r"Depthwise: expected an \[H, W, 3\] input"):
        nets.Depthwise(3, key=KEY)(x1)
    with pytest.raises(ValueError, match=r"LayerNorm2d: expected an input with 3 channels"):
        nets.LayerNorm2d(3)(x1)
    with pytest.raises(ValueError, match=r"Conv: expected an \[H, W, 1\] input"):
        nets.Conv(1, 4, 3, key=KEY)(jnp.ones((8, 8)))
    assert nets.LayerNorm2d(3)(jnp.ones((2, 3))).shape == (2, 3)  # control: any leading axes


def test_nets_give_an_integer_image_the_float_images_answer():
    """Main: the layers cast their weights to the input's dtype, so an image of 0 … 191 as
    ints ran with integer weights: NAFNet's answer differed by 108, a Conv's by 178. The
    layers take integer feature maps as floats; NAFNet, an image's restorer, refuses an
    integer image since round 43b (one rule with render: decode sRGB codes with to_linear)."""
    net = nets.NAFNet(width=4, enc_blocks=(1,), dec_blocks=(1,), key=KEY, identity_init=False)
    ramp = jnp.arange(192).reshape(8, 8, 3)
    with pytest.raises(ValueError, match="NAFNet: image must be a float image.*to_linear"):
        net(ramp)
    np.testing.assert_allclose(net.intro(ramp), net.intro(ramp.astype(float)), rtol=0,
                               atol=1e-12)
    block = eqx.tree_at(lambda b: (b.beta, b.gamma), nets.NAFBlock(4, key=KEY),
                        (jnp.full(4, 0.7), jnp.full(4, 0.3)))  # trained scales, not 0
    x = ramp[:, :, :1].repeat(4, -1)
    np.testing.assert_allclose(block(x), block(x.astype(float)), rtol=0, atol=1e-12)


def test_conv_and_nafnet_constructor_slips():
    """Main: an even kernel with stride 1 built a 'SAME' conv that shifts the image by half
    a pixel; identity_init="no" (truthy) zeroed the head; enc_blocks=2 failed on len()."""
    with pytest.raises(ValueError, match=r"Conv: kernel must be odd with stride 1"):
        nets.Conv(3, 4, 4, key=KEY)
    assert nets.Conv(3, 4, 2, stride=2, key=KEY).stride == 2  # control: the downsampler
    with pytest.raises(ValueError, match=r"NAFNet: identity_init must be True or False"):
        nets.NAFNet(width=4, key=KEY, identity_init="no")
    with pytest.raises(ValueError, match=r"NAFNet: enc_blocks must be a sequence"):
        nets.NAFNet(width=4, enc_blocks=2, dec_blocks=2, key=KEY)


COOKE = zoo.cooke_triplet()
OUT = jnp.array([[0.0, 0.0], [1.5, 0.0]])


@pytest.mark.parametrize("call", [
    lambda p: A.spot_rays(COOKE, 5.0, pupil=p),
    lambda p: A.rms_spot(COOKE, pupil=p),
    lambda p: A.clear_semi_diameters(COOKE, pupil=p),
    lambda p: A.angular_spot(COOKE, pupil=p),
], ids=["spot_rays", "rms_spot", "clear_semi_diameters", "angular_spot"])
def test_spot_pupils_outside_the_unit_disc_are_refused(call):
    """Main: a pupil point at radius 1.5 traced a ray 0.75 EPD off axis into the spot (a
    larger spot, or a ray counted vignetted), where opd and encircled_energy refused it."""
    with pytest.raises(ValueError, match=r"pupil points must lie in the unit disc"):
        call(OUT)


def test_spot_pupil_outside_the_disc_is_refused_under_jit_and_float32_rims_pass():
    with pytest.raises(Exception, match=r"spot_rays: pupil points must lie in the unit disc"):
        jax.block_until_ready(jax.jit(lambda p: A.spot_rays(COOKE, 5.0, pupil=p).valid)(OUT))
    rim = jl.sampling.pupil_hexapolar(3, jnp.float32)  # radius 1 + 2.3e-8 in float32
    assert A.spot_rays(COOKE, 5.0, pupil=rim).valid.shape == (rim.shape[0],)


def test_seidel_per_surface_must_be_a_bool():
    """Main: per_surface="no" (truthy) gave the [7, n] per-surface table for the sums."""
    s = A.seidel(COOKE)
    for bad in ("no", 0):
        with pytest.raises(ValueError, match=r"Seidel: per_surface must be True or False"):
            s.wavefront(per_surface=bad)
    assert s.wavefront().shape == (7,)  # control


def test_paper_stages_names_final_loss():
    """Main: final_loss="imag" was refused as the fine-tune Stage's ``loss``."""
    with pytest.raises(ValueError, match=r"paper_stages: final_loss must be 'ray' or 'image', "
                                         r"got 'imag'"):
        D.paper_stages(D.DesignSpec(), final_loss="imag")


def _mirror(t):
    return jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0),), thickness=jnp.array([t]),
                   materials=(jl.Air(),), epd=20.0, fields=jnp.array([0.0, 0.5]), mirrors=(0,))


def test_self_intersection_measures_gaps_along_the_light_after_a_mirror():
    """Main: the gap was Δz whichever way the light went, so every mirror lens read as
    crossed: a concave mirror with its focus 100 mm before it had gap -100 mm, ok False, and
    a Cassegrain's primary-to-secondary gap was -60.4 mm."""
    g = A.self_intersection(_mirror(-100.0))
    assert bool(g.ok) and float(g.min_gap[0]) == pytest.approx(99.75, abs=0.01)
    cass = jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0), jl.Sphere(-1 / 80.0)),
                   thickness=jnp.array([-60.0, 90.0]), materials=(jl.Air(), jl.Air()),
                   epd=20.0, fields=jnp.array([0.0, 0.2]), mirrors=(0, 1))
    assert bool(A.self_intersection(cass).ok)
    # Control: an image plane 0.01 mm before the vertex cuts the rim (sag -0.25 mm there).
    assert not bool(A.self_intersection(_mirror(-0.01)).ok)


@pytest.mark.parametrize("call", [
    lambda f: A.wavefront(COOKE, f, wavelength=587.6),
    lambda f: A.opd(COOKE, f, jnp.zeros(2), wavelength=587.6),
    lambda f: A.opd_fan(COOKE, f, 587.6),
], ids=["wavefront", "opd", "opd_fan"])
def test_wavefront_analyses_warn_on_a_field_in_radians(call):
    """Main: 20° typed as 0.349 (radians) traced a 0.35° field without a word, where
    rms_spot, chief_ray and ray_fan warn. (The wavelength in nm stops the call after the
    field check.)"""
    with pytest.warns(UserWarning, match=r"field 0.349066 look like angles in radians"), \
            pytest.raises(ValueError, match=r"nm"):
        call(float(np.radians(20.0)))


def test_an_empty_catalog_list_is_refused():
    """Main: catalog_names(catalogs=[]) listed no glass, silently."""
    with pytest.raises(TypeError, match=r"catalogs must be a catalog name .* \(not \[\]\)"):
        jl.catalog_names(catalogs=[])
    with pytest.raises(TypeError, match=r"\(not \[\]\)"):
        jl.get_material("N-BK7", catalogs=())


# Round 32a's leftovers in the lead's files (tracing.forward, imaging.psf, imaging.sampling).
def test_trace_switches_refuse_non_booleans():
    """Main: ``uniform="no"`` traced as True (a string is truthy)."""
    lens = zoo.cooke_triplet()
    rays = jl.sampling.field_rays(lens, 5.0, jl.sampling.pupil_grid(3))
    for fn in (jl.trace, jl.trace_path):
        with pytest.raises(TypeError, match="uniform must be True or False"):
            fn(lens, rays, uniform="no")
    assert bool(jnp.all(jl.trace_path(lens, rays, uniform=True).valid[-1]))  # control


def test_psf_warns_on_a_field_in_radians():
    """Main: psf(lens, 0.349) (20° in radians) traced a 0.35° PSF without a word, where
    rms_spot and the wavefront analyses warn."""
    lens = zoo.cooke_triplet()
    with pytest.warns(UserWarning, match="look like angles in radians"):
        jl.psf(lens, float(np.radians(20.0)), pixel_size=0.005, kernel_size=15)


def test_opd_takes_float32_rim_points():
    """Main: pupil_hexapolar's float32 rim points (radius 1 + 2.3e-8) were refused as outside
    the unit disc ("radius 1")."""
    lens = zoo.cooke_triplet()
    p = jl.sampling.pupil_hexapolar(8, jnp.float32)
    assert float(np.max(np.sum(np.asarray(p, np.float64) ** 2, -1))) > 1.0
    w = A.opd(lens, 5.0, p)
    assert w.shape == p.shape[:1] and bool(jnp.isfinite(w).any())
    with pytest.raises(ValueError, match="unit disc"):  # control: a point well outside
        A.opd(lens, 5.0, jnp.array([[0.0, 1.001]], jnp.float32))
