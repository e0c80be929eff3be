"""The design loss, regularizers, mask and design loop against hand-computed answers.

Every expected value here is computed from the documented definition with NumPy, on inputs
small enough to check by hand (parabolic and spherical sags, synthetic ray positions on the
image surface, a toy objective whose diagnostics expose the weights the loop hands it).
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.design import curriculum, losses, mask, regularizers, solvers
from jaxlens.design.params import LensParams
from jaxlens.design.spec import DesignSpec
from jaxlens.tracing.forward import stacked_surfaces

SPEC = DesignSpec()
N_RADIAL = 16  # the regularizers' default radial samples
U = np.linspace(0.0, 1.0, N_RADIAL)


def _soft(excess):
    """The documented hinge: relu, growing as log(1 + h) beyond 1 (HINGE_SCALE = 1)."""
    return np.log1p(np.maximum(excess, 0.0))


def _sphere_sag(c, r):
    return c * r**2 / (1.0 + np.sqrt(1.0 - c**2 * r**2))


def _lens(surfaces, thickness, stop=0):
    n = len(surfaces)
    return jl.Lens(surfaces=tuple(surfaces), thickness=jnp.asarray(thickness, jnp.float64),
                   materials=(jl.Air(),) * n, stop=stop, epd=2.0)


# --- regularizers -------------------------------------------------------------------------


def test_slope_residuals_are_the_hinge_of_the_parabola_slope():
    # z = a1 r² has slope 2 a1 r: 0.45 at the rim of the first (inside the bound 0.5),
    # −0.8 at the rim of the second (outside from r = 0.625 R on, whatever the sign).
    radius = 1.5
    a_in, a_out = 0.45 / (2 * radius), -0.8 / (2 * radius)
    lens = _lens([jl.Stop(), jl.EvenAsphere(0.0, 0.0, (a_in, 0.0)),
                  jl.EvenAsphere(0.0, 0.0, (a_out, 0.0))], [1.0, 1.0, 1.0])
    stack = stacked_surfaces(lens.surfaces)
    h = np.asarray(regularizers.slope(stack, lens.stop, jnp.full(3, radius)))
    assert h.shape == (2 * N_RADIAL,)  # the stop has no slope residuals
    want = np.concatenate([_soft(0.45 * U - 0.5), _soft(0.8 * U - 0.5)]) / math.sqrt(N_RADIAL)
    np.testing.assert_allclose(h, want, rtol=1e-12, atol=1e-15)
    assert want[:N_RADIAL].max() == 0 and want[N_RADIAL:].max() > 0.05


def test_spacing_residuals_use_both_sags_and_the_image():
    # Two spheres bulging toward each other (sags +s and −s) with a flat third surface and
    # a flat image; gap i runs out to the larger clear radius of surfaces i and i + 1.
    c0, c1 = 0.2, -0.25
    radii = np.array([1.5, 1.2, 1.0])
    t = [1.0, 0.5, 2.0]
    c_img = -0.3  # a curved sensor
    lens = eqx.tree_at(lambda m: m.image, _lens(
        [jl.EvenAsphere(c0, 0.0, (0.0, 0.0)), jl.EvenAsphere(c1, 0.0, (0.0, 0.0)),
         jl.EvenAsphere(0.0, 0.0, (0.0, 0.0))], t), jl.Standard(c_img))
    stack = stacked_surfaces(lens.surfaces)
    bounds = np.array([0.8, 0.6, 2.5])
    h = np.asarray(regularizers.spacing(lens, stack, jnp.asarray(radii), jnp.asarray(bounds)))
    r0 = U * 1.5
    r1 = U * 1.2
    r2 = U * 1.0
    gaps = [t[0] + _sphere_sag(c1, r0) - _sphere_sag(c0, r0),
            t[1] + 0.0 - _sphere_sag(c1, r1),
            t[2] + _sphere_sag(c_img, r2) - 0.0]
    want = np.concatenate([_soft(b - g) for b, g in zip(bounds, gaps, strict=True)])
    np.testing.assert_allclose(h, want / math.sqrt(N_RADIAL), rtol=1e-12, atol=1e-15)
    # Each gap's hinge is active somewhere, and the first depends on both sags.
    assert all(w.max() > 0 for w in np.split(want, 3))
    assert (t[0] - _sphere_sag(c0, r0)).min() > gaps[0].min() + 0.1


def test_clear_radii_are_the_largest_valid_heights():
    # Two lens surfaces and the image row, three rays.
    o = np.zeros((3, 3, 3))
    o[0, :, :2] = [[0.3, 0.4], [3.0, 4.0], [-0.1, 0.2]]  # the second ray fails here
    o[1, :, :2] = [[1.0, 0.0], [0.0, -2.0], [1.5, 0.0]]
    o[2, :, :2] = 9.0  # the image row is ignored
    valid = np.array([[True, False, True], [True, True, True], [True, True, True]])
    path = jl.Rays(jnp.asarray(o), jnp.zeros((3, 3, 3)).at[..., 2].set(1.0), 0.55,
                   valid=jnp.asarray(valid))
    np.testing.assert_allclose(regularizers.clear_radii(path), [0.5, 2.0])


# --- the spot loss on synthetic rays at the image surface ------------------------------------


def _spot_setup(beta=0.0, valid_mask=None, focal=4.0, tan_max=0.5, pin=0.0, scale=2.0,
                distortion_k=0.0, fw=(0.2, 0.3, 0.5)):
    wl = (0.48, 0.59)
    samp = losses.RayLoss.make(3, 1, wl, (3.0, 3.0), jnp.float64)
    K, W, P = 3, 2, samp.pupil.shape[0]
    rng = np.random.default_rng(4)
    off = rng.normal(0.0, 0.01, (K, W, P, 2))
    tan = np.asarray(samp.fracs) * tan_max
    ideal = np.stack([np.zeros(K), focal * tan * (1 + distortion_k * tan**2)], -1)
    pts = ideal[:, None, None, :] + off
    valid = np.ones((K, W, P), bool) if valid_mask is None else valid_mask
    o = np.concatenate([pts, np.zeros((K, W, P, 1))], -1)
    d = np.zeros_like(o)
    d[..., 2] = 1.0
    img = jl.Rays(jnp.asarray(o), jnp.asarray(d), jnp.broadcast_to(jnp.asarray(wl)[None, :,
                  None], (K, W, P)), valid=jnp.asarray(valid))
    before = jl.Rays(jnp.asarray(o) + 5.0, jnp.asarray(d), img.wavelength,
                     valid=jnp.zeros((K, W, P), bool))
    path = jax.tree.map(lambda a, b: jnp.stack([a, a, b]), before, img)  # the image is last
    fw = np.asarray(fw)
    args = losses.StageArgs(
        tan_max=jnp.asarray(tan_max), epd=jnp.asarray(1.6), focal=jnp.asarray(focal),
        beta=jnp.asarray(beta), pin=jnp.asarray(pin), spot_scale=jnp.asarray(scale),
        field_weights=jnp.asarray(fw), reg_weights=jnp.ones(3),
        distortion_k=jnp.asarray(distortion_k))
    pw = np.asarray(samp.pupil_weights)
    return samp, args, path, pts, ideal, valid, pw, fw


def _expected_ms(pts, ref, valid, pw, miss):
    e2 = np.sum((pts - ref[:, None, None, :]) ** 2, -1)
    e2 = np.where(valid, e2, miss**2)
    w = np.broadcast_to(pw, valid.shape)
    return np.sum(w * e2, axis=(1, 2)) / np.sum(w, axis=(1, 2))


def test_spot_loss_is_measured_from_the_ideal_image_point_f_tan():
    samp, args, path, pts, ideal, valid, pw, fw = _spot_setup()
    res = losses.spot_errors(path, samp, args)
    ms = _expected_ms(pts, ideal, valid, pw, 0.8)
    np.testing.assert_allclose(res.ms, ms, rtol=1e-10)
    assert ms.max() < 1e-3  # rays sit within ~10 µm of f·tan θ: a misplaced point shows
    # Σ residuals² is spot_scale × the field-weighted mean square error.
    np.testing.assert_allclose(jnp.sum(res.residuals**2), 2.0 * np.sum(fw * ms), rtol=1e-10)
    np.testing.assert_allclose(res.valid_fraction, 1.0)


def test_ideal_image_height_follows_the_image_mapping_and_weights_are_normalised():
    """With DesignSpec.image_mapping's k the ideal height is f·t·(1 + k·t²) (t = tan θ), the
    pin aims at f·t_max·(1 + k·t_max²), and the field weights enter divided by their sum."""
    k, fw = -0.3, np.array([0.6, 0.9, 1.5])  # weights summing to 3
    samp, args, path, pts, ideal, valid, pw, _ = _spot_setup(distortion_k=k, fw=fw, beta=0.0,
                                                             pin=3.0)
    tan = np.asarray(samp.fracs) * 0.5
    np.testing.assert_allclose(ideal[:, 1], 4.0 * tan * (1 + k * tan**2), rtol=1e-15)
    res = losses.spot_errors(path, samp, args)
    ms = _expected_ms(pts, ideal, valid, pw, 0.8)
    np.testing.assert_allclose(res.ms, ms, rtol=1e-10)
    assert ms.max() < 1e-3
    np.testing.assert_allclose(jnp.sum(res.residuals**2), 2.0 * np.sum(fw / 3.0 * ms),
                               rtol=1e-10)
    cen = np.sum(pw * pts[-1, ..., 1]) / np.sum(np.broadcast_to(pw, pts.shape[1:3]))
    np.testing.assert_allclose(res.pin, math.sqrt(3.0 * 2.0) * (cen - 4.0 * 0.5 * (1 + k / 4)),
                               rtol=1e-10)


def test_failed_rays_cost_half_the_pupil():
    samp, args, path, pts, ideal, valid, pw, fw = _spot_setup()
    valid = valid.copy()
    valid[2, 0, :3] = False  # three rays of the full field fail at the first wavelength
    valid[1, 1, -1] = False
    _, args, path, *_ = _spot_setup(valid_mask=valid)
    res = losses.spot_errors(path, samp, args)
    ms = _expected_ms(pts, ideal, valid, pw, 0.8)  # miss = EPD/2
    np.testing.assert_allclose(res.ms, ms, rtol=1e-10)
    assert ms[2] > 100 * ms[0]
    w = np.broadcast_to(pw, valid.shape)
    np.testing.assert_allclose(res.valid_fraction,
                               np.sum(w * valid, (1, 2)) / np.sum(w, (1, 2)), rtol=1e-12)


def test_centroid_reference_and_pin():
    valid = np.ones((3, 2, 5), bool)
    valid[2, 1, 0] = False
    samp, args, path, pts, ideal, _, pw, fw = _spot_setup(beta=0.75, valid_mask=valid, pin=3.0)
    res = losses.spot_errors(path, samp, args)
    w = np.broadcast_to(pw, valid.shape) * valid
    cen = np.sum(w[..., None] * pts, (1, 2)) / np.sum(w, (1, 2))[:, None]
    ref = 0.75 * cen + 0.25 * ideal
    np.testing.assert_allclose(res.ms, _expected_ms(pts, ref, valid, pw, 0.8), rtol=1e-10)
    np.testing.assert_allclose(res.centroid_y, cen[:, 1], rtol=1e-12)
    # pin = sqrt(pin · spot_scale) · (full-field centroid height − f·tan_max)
    np.testing.assert_allclose(res.pin, math.sqrt(3.0 * 2.0) * (cen[-1, 1] - 4.0 * 0.5),
                               rtol=1e-10)


def test_launch_fields_and_stage_args():
    spec = DesignSpec()
    st = curriculum.Stage("s", 60.0, 2.5, 1, beta=0.5, pin=0.25)
    a = curriculum.stage_args(spec, st, jnp.ones((2, 4)), (1.0, 2.0, 3.0), jnp.float64)
    np.testing.assert_allclose(a.tan_max, math.tan(math.radians(30.0)))
    np.testing.assert_allclose(a.focal, spec.focal_length)
    np.testing.assert_allclose(a.epd, spec.focal_length / 2.5)
    np.testing.assert_allclose(a.beta, 0.5)
    np.testing.assert_allclose(a.pin, 0.25)
    np.testing.assert_allclose(a.reg_weights, [[1.0, 2.0, 3.0]] * 2)
    off = curriculum.stage_args(spec, curriculum.Stage("s", 60.0, 2.5, 1, regularize=False),
                                jnp.ones((2, 4)), (1.0, 2.0, 3.0), jnp.float64)
    np.testing.assert_array_equal(off.reg_weights, 0.0)
    # Every paper stage regularizes unless told not to; only the final ones use the mask.
    st = curriculum.paper_stages(spec, n=2, steps=1, final_steps=1, polish_steps=1)
    assert all(s.regularize for s in st)
    assert [s.mask for s in st] == [False] * 3 + [True] * 2
    assert [s.beta for s in st] == [0.0] * 3 + [1.0] * 2


# --- the mask and the design loop ------------------------------------------------------------

RMS = np.array([1.0, 2.0, 3.0, 4.0])
AREA = np.array([0.1, 0.1, 0.1, 0.7])  # area-weighted mean 3.4: only fields 3 and 4 stay


def test_field_weights_use_the_area_weighted_mean():
    w = mask.field_weights(jnp.asarray(RMS)[None], jnp.asarray(AREA), mask=True, irls=False)
    keep = np.array([0, 0, 3 / 3.4, 4 / 3.4])  # with a plain mean (2.5) field 2 would stay
    np.testing.assert_allclose(w[0], AREA * keep / np.sum(AREA * keep), rtol=1e-12)
    w = mask.field_weights(jnp.asarray(RMS)[None], jnp.asarray(AREA), mask=True, irls=True)
    np.testing.assert_allclose(w[0], [0, 0, 0.125, 0.875], rtol=1e-12)
    w = mask.field_weights(jnp.asarray(RMS)[None], jnp.asarray(AREA), mask=False, irls=False)
    np.testing.assert_allclose(w[0], AREA, rtol=1e-12)
    # Realistic RMS values (mm) and shares that do not sum to 1 (e.g. pixel counts), one
    # design (1-D) and a batch of three (3-D): the same answer.
    rms_mm = 2e-3 * RMS
    m = mask.reweighting_mask(jnp.asarray(rms_mm), jnp.asarray(70 * AREA))
    np.testing.assert_allclose(m, [0, 0, 3 / 3.4, 4 / 3.4], rtol=1e-12)
    w = mask.field_weights(jnp.asarray(rms_mm), jnp.asarray(70 * AREA), mask=True, irls=False)
    np.testing.assert_allclose(w, AREA * keep / np.sum(AREA * keep), rtol=1e-12)
    b = jnp.broadcast_to(jnp.asarray(rms_mm), (3, 1, 4))
    w = mask.field_weights(b, jnp.asarray(70 * AREA), mask=True, irls=True)
    np.testing.assert_allclose(w, np.broadcast_to([0, 0, 0.125, 0.875], (3, 1, 4)), rtol=1e-12)
    # A field exactly at the threshold stays; a perfect lens (zero mean) keeps every field.
    np.testing.assert_allclose(mask.reweighting_mask(jnp.asarray([0.8, 1.2]) * 1e-3),
                               [0.8, 1.2], rtol=1e-12)
    np.testing.assert_array_equal(mask.reweighting_mask(jnp.zeros(3), jnp.ones(3)), 1.0)
    # Weights of a batch row whose fields are all dropped stay finite (zero).
    w = mask.field_weights(jnp.zeros((1, 3)), jnp.zeros(3), mask=False, irls=False)
    np.testing.assert_array_equal(w, 0.0)


class _Probe(eqx.Module):
    """A stand-in objective whose diagnostics report the weights the loop gives it.

    Its RMS per field is fixed (``RMS``); ``Aux.spot`` is (Σ_k w_k·k)² so that the loop's
    recorded spot RMS reads back Σ_k w_k·k, and ``Aux.loss`` is Σ reg_weights·(1, 10, 100)
    plus 1000·spot_scale·Σ_k w_k·RMS_k²: the loop sets spot_scale to the inverse of the
    weighted mean square at each epoch start, so that term reads 1000.
    """

    sampling: object

    def __call__(self, params, args):
        fw = args.field_weights
        probe = jnp.sum(fw * jnp.arange(1.0, 5.0)) + 0.0 * params.c[0]
        loss = jnp.sum(args.reg_weights * jnp.asarray([1.0, 10.0, 100.0]))
        loss = loss + 1e3 * args.spot_scale * jnp.sum(fw * jnp.asarray(RMS) ** 2)
        aux = losses.Aux(loss, probe**2, jnp.asarray(RMS), jnp.ones(4), jnp.zeros(3))
        return jnp.concatenate([params.c * 0.0, jnp.sqrt(loss)[None]]), aux

    def field_rms(self, params, args):
        return jnp.asarray(RMS) + 0.0 * params.c[0]


class _Area(eqx.Module):
    area: jax.Array


@pytest.mark.parametrize("irls", [False, True])
def test_run_applies_mask_and_regularizers_per_stage(irls):
    p0 = LensParams(c=jnp.zeros((2, 3)), a=jnp.zeros((2, 3, 1)), k=jnp.zeros((2, 3)),
                    d=jnp.ones((2, 2)))
    obj = _Probe(_Area(jnp.asarray(AREA)))
    lrs = LensParams(c=jnp.asarray(0.0), a=jnp.asarray(0.0), k=jnp.asarray(0.0),
                     d=jnp.asarray(0.0))
    stages = [curriculum.Stage("plain", 50.0, 2.8, 2),
              curriculum.Stage("masked", 80.8, 2.0, 2, mask=True),
              curriculum.Stage("free", 80.8, 2.0, 1, regularize=False)]
    _, hist = curriculum.run(SPEC, stages, p0, obj, lambda n, lr, o: solvers.Adam(o, lrs),
                             reg_weights=(2.0, 3.0, 5.0), irls=irls, progress=False,
                             log_every=1)
    ks = np.arange(1.0, 5.0)

    def probe(w):
        w = w / np.sum(w)
        return np.sum(w * ks)

    div = RMS if irls else 1.0
    plain = probe(AREA / div)
    masked = probe(AREA * np.array([0, 0, 3 / 3.4, 4 / 3.4]) / div)
    np.testing.assert_allclose(hist.spot_rms[0], plain, rtol=1e-12)
    np.testing.assert_allclose(hist.spot_rms[1], masked, rtol=1e-12)
    np.testing.assert_allclose(hist.spot_rms[2], plain, rtol=1e-12)
    np.testing.assert_allclose(hist.loss[0], 2 + 30 + 500 + 1000, rtol=1e-12)
    np.testing.assert_allclose(hist.loss[1], 2 + 30 + 500 + 1000, rtol=1e-12)
    np.testing.assert_allclose(hist.loss[2], 1000, rtol=1e-12)


def test_obliquity_residuals_are_the_hinge_of_the_cosines_on_both_sides():
    # Surfaces: a flat face, the stop (no residuals) and a sphere; synthetic ray directions
    # before and after each surface, so that every cosine is known in closed form.
    c = 0.2
    lens = _lens([jl.EvenAsphere(0.0, 0.0, (0.0,)), jl.Stop(), jl.EvenAsphere(c, 0.0, (0.0,))],
                 [1.0, 1.0, 1.0], stop=1)
    stack = stacked_surfaces(lens.surfaces)
    rng = np.random.default_rng(7)
    K, P = 3, 5

    def unit(tilt):  # directions at up to `tilt` rad from the axis
        th = rng.uniform(0, tilt, (K, P))
        ph = rng.uniform(0, 2 * np.pi, (K, P))
        return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)

    d_in = unit(1.2)
    d = np.stack([unit(1.2), unit(1.2), unit(1.2), unit(0.1)])  # after each surface, image
    o = np.zeros((4, K, P, 3))
    o[..., :2] = rng.uniform(-2, 2, (4, K, P, 2))
    valid = np.ones((4, K, P), bool)
    valid[0, 0, 0] = False  # a failed ray costs no obliquity
    rays = jl.Rays(jnp.asarray(np.broadcast_to(o[0], (K, P, 3))), jnp.asarray(d_in), 0.55)
    path = jl.Rays(jnp.asarray(o), jnp.asarray(d), 0.55, valid=jnp.asarray(valid))
    got = np.asarray(regularizers.obliquity(stack, lens.vertex_z(), lens.stop, rays, path))

    def normal(i, xy):
        if i < 2:
            return np.broadcast_to([0.0, 0.0, 1.0], xy.shape[:-1] + (3,))
        r2 = np.sum(xy**2, -1, keepdims=True)
        g = c * xy / np.sqrt(1 - c**2 * r2)  # the sphere's sag gradient
        n = np.concatenate([-g, np.ones_like(r2)], -1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    want = []
    for i in (0, 2):
        n = normal(i, o[i, ..., :2])
        cos_in = np.abs(np.sum((d_in if i == 0 else d[i - 1]) * n, -1))
        cos_out = np.abs(np.sum(d[i] * n, -1))
        h = np.where(valid[i], np.maximum(0.7 - np.minimum(cos_in, cos_out), 0.0), 0.0)
        want.append(np.sqrt(np.sum(h**2, -1) / (K * P)))
    want = np.concatenate(want)
    assert np.all(want > 0)
    np.testing.assert_allclose(got, want, rtol=1e-10)
    # Rays without a leading axis: one residual per surface, the same sum of squares.
    flat = jax.tree.map(lambda x: x.reshape((x.shape[0], -1) + x.shape[3:]) if x.ndim > 2
                        else x, path)
    one = np.asarray(regularizers.obliquity(stack, lens.vertex_z(), lens.stop, jax.tree.map(
        lambda x: x.reshape((-1,) + x.shape[2:]) if x.ndim > 1 else x, rays), flat))
    assert one.shape == (2,)
    np.testing.assert_allclose(np.sum(one**2), np.sum(got**2), rtol=1e-10)


def test_stage_defaults_and_short_sine_paths():
    s = curriculum.Stage("x", 60.0, 2.5, 7)
    assert (s.solver, s.beta, s.pin, s.mask, s.regularize, s.lr, s.loss) == (
        "adam", 0.0, 0.0, False, True, 1.0, "ray")
    # n = 1: the start and the end; n = 0: the end only (no curriculum).
    np.testing.assert_allclose(curriculum.sine_path(2.8, 2.0, 1), [2.8, 2.0])
    np.testing.assert_allclose(curriculum.sine_path(2.8, 2.0, 0), [2.0])
    np.testing.assert_allclose(curriculum.sine_path(2.8, 2.0, 2),
                               [2.8, 2.8 - 0.8 * math.sqrt(0.5), 2.0])


def test_paper_stage_defaults_and_float32_sampling():
    st = curriculum.paper_stages(SPEC)
    # N = 3 (four stages on the sine path, 300 steps each), then 600 fine-tuning steps.
    assert [s.steps for s in st] == [300] * 4 + [600]
    assert [s.solver for s in st] == ["adam"] * 5 and st[-1].pin == 1.0
    assert [s.loss for s in st] == ["ray"] * 5
    # float32 designs stay float32 (the sampling and the launched rays).
    samp = losses.RayLoss.make(3, 2, (0.5, 0.6), (3.0, 3.0), jnp.float32)
    assert {x.dtype for x in jax.tree.leaves(samp)} == {jnp.dtype("float32")}
    lens = _lens([jl.Stop(), jl.EvenAsphere(0.1, 0.0, (0.0,))], [1.0, 4.0]).astype(jnp.float32)
    args = jax.tree.map(lambda x: x[0], curriculum.stage_args(
        SPEC, curriculum.Stage("s", 60.0, 2.5, 1), jnp.ones((1, 3)), (1.0, 1.0, 1.0),
        jnp.float32))
    rays = losses.launch(lens, samp, args)
    assert rays.origin.dtype == rays.direction.dtype == jnp.float32
