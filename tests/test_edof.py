"""The EDoF experiment: losses, lens parameters, noise, evaluation, PSF measures, smoke run."""

import json
import os
import shutil

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.design.params import AbstractParameterization
from jaxlens.experiments.edof import evaluate as E
from jaxlens.experiments.edof import lenses as L
from jaxlens.experiments.edof import losses as LS
from jaxlens.experiments.edof import optics as O
from jaxlens.imaging import tiled
from jaxlens.optics.surfaces import Hybrid


@pytest.fixture(scope="module")
def classical():
    return L.classical_lens(binning=8)


# --- losses ------------------------------------------------------------------------------
def test_losses_on_known_values():
    # Three different term values (L_rec 0.1, L_sim 0.4, L_raw 0.2) and unequal weights, so a
    # swapped weight or a term computed from the wrong images changes the total.
    gt = jnp.full((2, 4, 4, 3), 0.5).at[0, 0, 0, 0].set(0.7)
    sim = jnp.stack([gt + 0.1, gt - 0.3])
    rec = jnp.stack([gt - 0.05, gt + 0.15])
    assert float(LS.l_sim(sim)) == pytest.approx(0.4)
    assert float(LS.l_raw(sim, gt)) == pytest.approx(0.2)
    assert float(LS.l_rec(rec, gt)) == pytest.approx(0.1)
    total, parts = LS.edof_loss(rec, sim, gt, w_sim=0.5, w_raw=0.25)
    assert float(total) == pytest.approx(0.1 + 0.5 * 0.4 + 0.25 * 0.2)
    assert {k: float(v) for k, v in parts.items()} == pytest.approx(
        {"rec": 0.1, "sim": 0.4, "raw": 0.2})
    # Simulations that agree across depths cost nothing in L_sim.
    assert float(LS.l_sim(jnp.stack([sim[0], sim[0]]))) == 0.0
    # The distances are L1: errors of ±0.2 on half the pixels cost 0.1, not 0.02 (L2).
    half = jnp.where(jnp.arange(3) % 2 == 0, 0.2, -0.2) * (jnp.arange(4)[:, None, None] < 2)
    assert float(LS.l_rec(jnp.stack([gt + half, gt + half]), gt)) == pytest.approx(0.1)


def test_table2_rec_metrics_come_from_the_reconstruction():
    """``evaluate``: "sim" scores the noisy simulation (the crop blurred by the bank at the
    depth, clipped to [0, 1]), "rec" the decoder's output clipped to [0, 1] and "wiener" the
    Wiener deconvolution of the same noisy image with the depth-averaged kernels."""
    from jaxlens.experiments.edof.train import Config
    from jaxlens.io.images import psnr

    cfg = Config(tile=8, kernel_size=3, crop=16, photons=1e12, read_noise=0.02)
    rng = np.random.default_rng(0)
    windows = rng.random((3, 18, 18, 3)).astype(np.float32)
    windows[0, :8, :8] = 1.0  # a white corner: noise goes above 1 there
    bank = np.zeros((8, 4, 4, 3, 3, 3), np.float32)
    bank[..., 1, 1] = 0.9  # 10 % of the light lost at every depth ...
    bank[:, :, :, :, 1, 2] = np.linspace(0.0, 0.1, 8)[:, None, None, None]  # ... blur by depth
    target = np.clip(rng.normal(0.5, 0.6, (16, 16, 3)), -0.5, 1.5).astype(np.float32)

    class Known:  # a "decoder" whose output is known: its PSNR is known in closed form
        wiener = False

        def __call__(self, x, kern):
            return jnp.asarray(target, x.dtype)

    dec = Known()

    vals, ex = E.evaluate(dec, bank, windows, cfg=cfg, key=jax.random.PRNGKey(0), nsr=1e-4,
                          depths_m=(0.1, 10.0), keep=0)
    v = vals["10"]
    sim, rec, wien = ex["10"]
    np.testing.assert_array_equal(rec, np.clip(target, 0.0, 1.0))
    gts = windows[:, 1:17, 1:17].astype(np.float64)
    want = [10 * np.log10(1.0 / np.mean((g - np.clip(target, 0, 1)) ** 2)) for g in gts]
    np.testing.assert_allclose(v["rec"]["psnr"], want, rtol=1e-6)
    # Crop 0 sits on the frame's first 2 × 2 tiles and is blurred by the 10 m kernels.
    clean = np.asarray(tiled.convolve_tiles(jnp.asarray(windows[0]), jnp.asarray(bank[7, :2, :2]),
                                            pad="valid"))
    inside = (clean > 0.1) & (clean < 0.85)
    noise = (sim - clean)[inside]
    assert abs(noise.mean()) < 5e-3 and np.std(noise) == pytest.approx(0.02, rel=0.15)
    assert sim.min() >= 0.0 and sim.max() == 1.0  # clipped, and the white corner reaches 1
    assert v["sim"]["psnr"][0] == pytest.approx(psnr(gts[0], sim, data_range=1.0), rel=1e-9)
    # The Wiener reference restores the lost 10 %: it is much closer to the scene than sim.
    assert v["wiener"]["psnr"][0] > v["sim"]["psnr"][0] + 1.0
    assert psnr(gts[0], wien, data_range=1.0) == pytest.approx(v["wiener"]["psnr"][0], rel=1e-9)
    # The 10 cm images differ from the 10 m ones (another kernel), the target does not.
    assert vals["0.1"]["sim"]["psnr"] != v["sim"]["psnr"]
    assert vals["0.1"]["rec"]["psnr"] == pytest.approx(v["rec"]["psnr"])


def test_image_balanced_gain_weights_every_image_equally():
    # 30 crops of one image at 0 dB and 2 crops of another at +2 dB: the crop mean is 0.125,
    # the image-balanced mean 1.0; drawing the images gives replicates 0, 1 or 2.
    images = ["big"] * 30 + ["small"] * 2
    diff = np.array([[0.0] * 30 + [2.0] * 2] * 3)
    crop = E.bootstrap_gain(diff)
    bal = E.bootstrap_gain_by_image(diff, images, n=2000)
    assert crop["mean"] == pytest.approx(0.125)
    assert bal["mean"] == pytest.approx(1.0)
    assert bal["ci95"] == pytest.approx([0.0, 2.0])
    # Within-image spread and seed offsets enter the interval; the mean is unchanged.
    rng = np.random.default_rng(1)
    noisy = diff + rng.normal(0, 0.5, diff.shape) + np.array([[-1.0], [0.0], [1.0]])
    b2 = E.bootstrap_gain_by_image(noisy, images)
    assert b2["mean"] == pytest.approx(np.mean([noisy[:, :30].mean(), noisy[:, 30:].mean()]))
    assert b2["ci95"][0] < b2["mean"] < b2["ci95"][1]
    with pytest.raises(ValueError, match="image labels"):
        E.bootstrap_gain_by_image(diff, images[:-1])


def test_placements_cycle_over_the_frame_blocks():
    assert E.placements(5, (8, 8), 4) == [(0, 0), (0, 4), (4, 0), (4, 4), (0, 0)]
    with pytest.raises(ValueError, match="does not fit"):
        E.placements(1, (2, 2), 4)


def test_bootstrap_gain_over_seeds_and_crops():
    rng = np.random.default_rng(0)
    flat = E.bootstrap_gain(np.full((3, 40), 0.7))
    assert flat["mean"] == pytest.approx(0.7) and flat["ci95"] == pytest.approx([0.7, 0.7])
    crops = rng.normal(1.0, 1.0, 40)
    one = E.bootstrap_gain(crops[None])
    # Seeds that disagree (offsets −1, 0, +1 dB) widen the interval: the seed level is drawn.
    three = E.bootstrap_gain(np.stack([crops - 1, crops, crops + 1]))
    assert one["mean"] == pytest.approx(three["mean"])
    assert one["ci95"][0] < one["mean"] < one["ci95"][1]
    assert three["ci95"][1] - three["ci95"][0] > 2 * (one["ci95"][1] - one["ci95"][0])
    # The crop-only interval is about ±1.96 σ/√n.
    assert one["ci95"][1] - one["ci95"][0] == pytest.approx(2 * 1.96 * crops.std() / 40**0.5,
                                                            rel=0.15)


def test_noise_model_has_shot_and_read_noise():
    x = jnp.concatenate([jnp.zeros(20000), jnp.full(20000, 0.5)])
    y = np.asarray(O.add_noise(x, jax.random.PRNGKey(1), photons=200.0, read=0.01)) - np.asarray(x)
    assert np.std(y[:20000]) == pytest.approx(0.01, rel=0.03)
    assert np.std(y[20000:]) == pytest.approx(np.sqrt(0.5 / 200 + 1e-4), rel=0.03)


def test_decoders_start_from_the_raw_image_or_its_wiener_estimate():
    from jaxlens.experiments.edof.decoder import make_decoder

    raw = jnp.asarray(np.random.default_rng(0).random((16, 16, 3)), jnp.float32)
    kern = np.zeros((2, 2, 3, 3, 3), np.float32)
    kern[..., 1, 1], kern[..., 1, 2] = 0.7, 0.2
    kw = dict(nsr=0.05, key=jax.random.PRNGKey(0), width=4, enc_blocks=(1,), middle_blocks=1,
              dec_blocks=(1,))
    plain = make_decoder("nafnet", **kw)
    wien = make_decoder("wiener", **kw)
    multi = make_decoder("multiwiener", **kw)
    # The multi-Wiener decoder weights each depth's estimate by the tile's depth posterior
    # and starts as that weighted estimate; it also sees the mean and per-depth estimates.
    by_depth = np.stack([np.roll(kern, s, axis=-1) for s in (-1, 0, 0, 0, 0, 0, 0, 1)])

    # Everything in one compiled program (op by op, about 280 small ones).
    @eqx.filter_jit
    def run(plain, wien, multi, raw, kern, by_depth):
        stack = multi.front_kernels(by_depth)
        front = multi.front(raw, stack)
        est = [tiled.wiener_tiles(raw, k, 0.05, prior="gradient") for k in by_depth]
        return (plain(raw, kern), wien(raw, kern[None]),
                tiled.wiener_tiles(raw, kern, 0.05, prior="gradient"), stack,
                wien.front_kernels(by_depth), front, est, multi(raw, stack))

    out = run(plain, wien, multi, raw, jnp.asarray(kern), jnp.asarray(by_depth))
    got_plain, got_wien, want, stack, wien_stack, front, est, got_multi = out
    np.testing.assert_array_equal(np.asarray(got_plain), np.asarray(raw))
    np.testing.assert_allclose(np.asarray(got_wien), np.asarray(want), atol=1e-6)
    assert float(jnp.max(jnp.abs(want - raw))) > 0.05
    assert stack.shape == (9,) + kern.shape
    np.testing.assert_allclose(np.asarray(stack[0]), by_depth.mean(0), atol=1e-7)
    np.testing.assert_array_equal(np.asarray(stack[1:]), by_depth)
    assert wien_stack.shape == (1,) + kern.shape
    assert front.shape == (16, 16, 38)
    np.testing.assert_allclose(np.asarray(front[..., 9:12]), np.asarray(est[1]), atol=1e-6)
    post = np.asarray(front[..., 30:])
    np.testing.assert_allclose(post.sum(-1), 1.0, atol=1e-5)
    np.testing.assert_array_equal(post[:8, :8], np.broadcast_to(post[0, 0], (8, 8, 8)))
    chosen = sum(post[..., d:d + 1] * np.asarray(est[d]) for d in range(8))
    np.testing.assert_allclose(np.asarray(front[..., :3]), chosen, atol=1e-5)
    np.testing.assert_allclose(np.asarray(got_multi), np.asarray(front[..., :3]), atol=1e-6)
    with pytest.raises(ValueError, match="kind must be one of"):
        make_decoder("unet", **kw)


@pytest.mark.parametrize("kind,real_halo,context", [
    pytest.param("nafnet", False, 8, marks=pytest.mark.slow), ("wiener", True, 0),
    pytest.param("wiener", True, 4, marks=pytest.mark.slow)])
def test_training_patch_context_is_read_and_the_loss_sees_the_tile(kind, real_halo, context):
    """With real scene around a training patch (``real_halo``, ``context``) the simulated
    patch grows, the decoder reads all of it and the loss reads the central tile: with a
    decoder that starts as (nearly) the identity (a sharp kernel, a tiny NSR), L_rec is the
    noise's error on that tile and agrees with L_raw; a misaligned crop would not."""
    from jaxlens.experiments.edof.decoder import make_decoder
    from jaxlens.experiments.edof.train import Config, _sim_loss

    cfg = Config(tile=16, kernel_size=5, batch=2, decoder=kind, real_halo=real_halo,
                 context=context, photons=1e7, read_noise=1e-5, w_sim=0.0, w_raw=0.0)
    halo = 5 if real_halo else 0
    assert cfg.patch == 16 + 2 * (context + halo) and cfg.window == cfg.patch + 4
    assert cfg.front_pad == ("valid" if real_halo else "edge")
    rng = np.random.default_rng(0)
    windows = jnp.asarray(rng.random((2, cfg.window, cfg.window, 3)), jnp.float32)
    k = np.zeros((3, 5, 5), np.float32)
    k[:, 2, 2] = 1.0
    kern = jnp.asarray(np.broadcast_to(k, (2, 2, 3, 5, 5)))
    dec = make_decoder(kind, nsr=1e-9, key=jax.random.PRNGKey(0), width=4, enc_blocks=(1,),
                       middle_blocks=1, dec_blocks=(1,))
    # Compiled (op by op, the loss compiled about 190 small programs).
    _, parts = eqx.filter_jit(_sim_loss)(dec, kern, windows, kern[:1], jax.random.PRNGKey(1),
                                         cfg.step_config)
    gt = windows[:, cfg.window // 2 - 8: cfg.window // 2 + 8, cfg.window // 2 - 8:
                 cfg.window // 2 + 8]
    sims = jax.jit(O.simulate)(windows, kern)
    m = (cfg.patch - 16) // 2
    np.testing.assert_allclose(float(parts["raw"]),
                               float(jnp.mean(jnp.abs(sims[:, :, m:m + 16, m:m + 16] - gt))),
                               atol=1e-7)
    assert float(parts["raw"]) < 1e-6  # a delta kernel: the centre crop is the ground truth
    assert float(parts["rec"]) < 2e-4


def test_loss_shape_errors():
    gt = jnp.zeros((2, 4, 4, 3))
    # The message names the function, the shapes it needs and the shapes it got.
    with pytest.raises(ValueError, match=r"^edof_loss: need rec and sim of shape \[2, \*b\] and "
                       r"gt of shape \[\*b\], got \(3, 2, 4, 4, 3\), \(3, 2, 4, 4, 3\), "
                       r"\(2, 4, 4, 3\)$"):
        LS.edof_loss(jnp.zeros((3, 2, 4, 4, 3)), jnp.zeros((3, 2, 4, 4, 3)), gt, w_sim=1, w_raw=1)


# --- lenses and parameters -----------------------------------------------------------------
def test_classical_lens_meets_the_spec(classical):
    from jaxlens.analysis.spots import chief_ray, rms_spot

    assert classical.stop == 0
    assert float(classical.epd) == pytest.approx(2.60)
    # 68.8° diagonal field on the 7.20 mm sensor diagonal: the chief ray of the corner field
    # lands on the sensor corner.
    y = float(chief_ray(classical, 34.4, 0.5876, depth=200.0).origin[1])
    assert y == pytest.approx(3.60, rel=0.04)  # 3.71 mm: the sensor sits 0.1 mm back for 20 cm
    assert classical.sensor.resolution == (128, 128)
    assert float(classical.sensor.pixel_size) == pytest.approx(8 * 0.00497)
    # Focused at 20 cm: the on-axis spot there beats those at 10 cm and 10 m.
    rms = [
        float(rms_spot(classical, jnp.array([0.0]), jnp.array([0.5876]), depth=d).polychromatic[0])
        for d in (100.0, 200.0, 1e4)
    ]
    assert rms[1] < 0.5 * min(rms[0], rms[2])


def test_hybrid_params_round_trip_and_odd_terms(classical):
    hyb = L.to_hybrid(classical, n_odd=3, cubic=0.004)
    s = hyb.surfaces[1]
    assert isinstance(s, Hybrid)
    # With zero odd terms the hybrid surface has the sag of the original asphere.
    flat = L.to_hybrid(classical, n_odd=3)
    x, y = jnp.array([0.3, -0.7, 1.1]), jnp.array([0.5, 0.2, -0.4])
    np.testing.assert_allclose(
        flat.surfaces[1].sag(x, y)[0], classical.surfaces[1].sag(x, y)[0], rtol=1e-12, atol=1e-15
    )
    pmap = L.HybridParameterization.of(hyb)
    p = pmap.from_lens(hyb)
    back = pmap.to_lens(p)
    for a, b in zip(jax.tree_util.tree_leaves(back), jax.tree_util.tree_leaves(hyb), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-15)
    # The same protocol as the classical design: a lens of the template's structure with a
    # moved sensor and other odd terms comes back as itself.
    assert isinstance(pmap, AbstractParameterization)
    moved = pmap.to_lens(eqx.tree_at(lambda q: (q.focus, q.odd_y), p,
                                     (jnp.asarray(3.0), p.odd_y.at[1].set(0.5))))
    again = pmap.to_lens(pmap.from_lens(moved))
    for a, b in zip(jax.tree_util.tree_leaves(again), jax.tree_util.tree_leaves(moved),
                    strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-15)
    assert float(moved.thickness[-1] - hyb.thickness[-1]) == pytest.approx(3.0 * L.SAG_SCALE)
    with pytest.raises(ValueError, match="not Hybrid"):
        L.HybridParameterization.of(classical)
    # Scaled odd parameter = sag at R over SAG_SCALE.
    r = 0.5 * float(hyb.epd)
    assert float(p.odd_x[0]) == pytest.approx(0.004 * r**3 / L.SAG_SCALE)
    # Every parameter in the same sag unit: c as the paraxial sag c·R²/2 at R, so that a
    # step of 1 in c moves the sag at R by SAG_SCALE, like a step of 1 in an odd term.
    c = float(hyb.surfaces[1].c)
    assert float(p.c) == pytest.approx(c * r * r / 2 / L.SAG_SCALE)
    step = pmap.to_lens(eqx.tree_at(lambda q: q.c, p, p.c + 1.0)).surfaces[1]
    assert (float(step.c) - c) * r * r / 2 == pytest.approx(L.SAG_SCALE)
    # The odd profile is the analytic cubic a·(x³ + y³).
    xs, h = L.odd_profile(hyb, n=21)
    xx, yy = np.meshgrid(xs, xs)
    inside = ~np.isnan(h)
    np.testing.assert_allclose(h[inside], 0.004 * (xx**3 + yy**3)[inside], rtol=1e-9, atol=1e-15)


def test_gates_select_and_tie_parameters(classical):
    hyb = L.to_hybrid(classical, n_odd=3, cubic=0.003)
    p = L.HybridParameterization.of(hyb).from_lens(hyb)
    g = jax.tree_util.tree_map(lambda v: jnp.ones_like(v) * 2.0, p)
    g = g.__class__(
        c=g.c,
        k=g.k,
        even=g.even,
        odd_x=jnp.array([1.0, 2.0, 3.0]),
        odd_y=jnp.array([3.0, 4.0, 5.0]),
        focus=g.focus,
    )
    gate, tie = L.gates(p, "frozen")
    out = L.apply_gates(g, gate, tie)
    assert all(float(jnp.sum(jnp.abs(v))) == 0 for v in jax.tree_util.tree_leaves(out))
    gate, tie = L.gates(p, "classical")  # a trainable focus and nothing else
    out = L.apply_gates(g, gate, tie)
    assert float(out.focus) == 2.0
    assert sum(float(jnp.sum(jnp.abs(v))) for v in jax.tree_util.tree_leaves(out)) == 2.0
    gate, tie = L.gates(p, "cubic")
    out = L.apply_gates(g, gate, tie)
    np.testing.assert_allclose(out.odd_x, [2.0, 0.0, 0.0])
    np.testing.assert_allclose(out.odd_y, [2.0, 0.0, 0.0])
    assert float(out.c) == 0 and float(out.focus) == 2.0
    gate, tie = L.gates(p, "hybrid")
    out = L.apply_gates(g, gate, tie)
    np.testing.assert_allclose(out.odd_x, [1.0, 2.0, 3.0])
    gate, tie = L.gates(p, "hybrid-held-focus")
    out = L.apply_gates(g, gate, tie)
    assert float(out.c) == 0 and float(out.focus) == 0 and float(out.k) == 2.0
    np.testing.assert_allclose(out.odd_y, [3.0, 4.0, 5.0])
    with pytest.raises(ValueError, match="kind"):
        L.gates(p, "other")


def test_project_holds_the_cubic_strength_above_its_floor(classical):
    hyb = L.to_hybrid(classical, n_odd=2, cubic=0.003)
    p = L.HybridParameterization.of(hyb).from_lens(hyb)
    low = L.project(p, 2.0 * float(p.odd_x[0]))
    np.testing.assert_allclose([low.odd_x[0], low.odd_y[0]], 2.0 * float(p.odd_x[0]))
    np.testing.assert_array_equal(low.odd_x[1:], p.odd_x[1:])
    same = L.project(p, -np.inf)
    np.testing.assert_array_equal(same.odd_x, p.odd_x)


def test_dioptric_depth_weights():
    w = L.dioptric_weights()
    assert w.shape == (8,) and w.sum() == pytest.approx(1.0)
    assert np.all(np.diff(w) < 0)  # depths are listed near to far; near ones stand for more
    # Each depth stands for the dioptric interval halfway to its neighbours; the end ones
    # mirror their one gap, so 10 cm (10 D) stands for 10 - 6.67 = 3.33 D of the total.
    d = 1 / np.asarray(L.DEPTHS_M)
    raw = [d[0] - d[1]] + [(d[i - 1] - d[i + 1]) / 2 for i in range(1, 7)] + [d[-2] - d[-1]]
    np.testing.assert_allclose(w, np.array(raw) / sum(raw), rtol=1e-12)
    np.testing.assert_allclose(L.dioptric_weights(L.DEPTHS_M[::-1]), w[::-1])


def test_cubic_strength_guess_matches_formula(classical):
    a = L.cubic_strength_guess(classical, depths_m=(0.1,), ratio=2.0)
    r = 1.3
    w = 0.5 * (1 / 100.0 - 1 / 200.0) * r * r
    n = float(classical.materials[1].index(0.5876))
    assert a == pytest.approx(2.0 * w / ((n - 1) * r**3))


def test_perturb_changes_lens_and_zero_tolerance_keeps_it(classical):
    lens = L.to_hybrid(classical, n_odd=2, cubic=0.003)
    same = L.perturb(lens, jax.random.PRNGKey(0), L.Tolerances(0, 0, 0, 0, 0))
    for a, b in zip(jax.tree_util.tree_leaves(same), jax.tree_util.tree_leaves(lens), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b))
    moved = L.perturb(lens, jax.random.PRNGKey(0))
    dt = np.asarray(moved.thickness - lens.thickness)
    assert 0 < np.max(np.abs(dt)) < 0.1
    assert float(moved.surfaces[0].c) == 0.0  # the stop stays flat


def test_psf_depth_variation_measure():
    rng = np.random.default_rng(1)
    p = rng.random((1, 2, 3, 5, 5))
    p /= p.sum(axis=(-1, -2), keepdims=True)
    same = O.psf_depth_variation(np.concatenate([p, p, p]))
    assert same["l1"] == pytest.approx(0.0, abs=1e-12)
    assert same["ncc"] == pytest.approx(1.0)
    a = np.zeros((1, 1, 1, 5, 5))
    b = np.zeros((1, 1, 1, 5, 5))
    a[..., 0, 0] = 1.0
    b[..., 4, 4] = 1.0
    apart = O.psf_depth_variation(np.concatenate([a, b]))
    assert apart["l1"] == pytest.approx(2.0)
    assert apart["ncc"] < 0
    # Shapes are compared, not sums: a PSF that loses half its light is the same shape.
    dim = O.psf_depth_variation(np.concatenate([p, 0.5 * p]))
    assert dim["l1"] == pytest.approx(0.0, abs=1e-12)


# --- the experiment, end to end ------------------------------------------------------------------
def test_smoke_run_writes_outputs_loss_falls_and_resumes(tmp_path):
    """The smoke run (NAFNet decoder) writes every output with the issue-10 schema and its
    loss falls; a run
    stopped by its time limit at a checkpoint and resumed gives the same table as one run
    straight through (compiled programs are shared, so the second and third runs are cheap)."""
    from jaxlens.experiments.edof import cli as edof
    from jaxlens.experiments.edof.train import OutOfTime

    common = ["--smoke", "--quiet", "--lenses", "classical,hybrid", "--max-crops", "4"]
    out = tmp_path / "edof"
    summary = edof.run(common + ["--out", str(out), "--record", str(tmp_path / "rec")])
    for name in ("table2.json", "table2.md", "table2_per_image.json", "summary.json",
                 "command.txt", "loss.png", "psf_grid_hybrid.png", "mtf_by_depth.png",
                 "odd_profile.png", "reconstructions.png", "lenses/hybrid_s0.json",
                 "nets/hybrid_s0.eqx"):
        assert (out / name).is_file(), name
        assert os.path.getsize(out / name) > 0
    table = json.loads((out / "table2.json").read_text())
    assert set(table["lenses"]) == {"classical", "hybrid", "wiener_classical", "wiener_hybrid"}
    for row in table["lenses"].values():
        assert set(row) == {"0.1", "0.2", "10"}
        for d in row.values():
            assert set(d) == {"sim", "rec"}
            assert all(np.isfinite(d[t][m]) for t in d for m in ("psnr", "ssim"))
    assert set(table["gain_vs_classical"]) == {"hybrid"}
    g = table["gain_vs_classical"]["hybrid"]["0.1"]
    assert g["ci95"][0] <= g["mean"] <= g["ci95"][1]
    assert table["test"]["crops"] == 4 and table["seeds"] == [0]
    assert set(table["base_lens"]) == {"efl_mm", "fov_deg", "fnum", "image_diagonal_mm",
                                       "elements"}
    assert all(0.0 < v <= 1.0 + 1e-6 for v in table["light_on_sensor"].values())
    per = json.loads((out / "table2_per_image.json").read_text())
    assert len(per["crops"]) == 4
    assert len(per["values"]["0"]["hybrid"]["0.1"]["rec"]["psnr"]) == 4
    # The table's rec row is the mean of the per-crop reconstruction values.
    assert table["lenses"]["hybrid"]["0.1"]["rec"]["psnr"] == pytest.approx(
        np.mean(per["values"]["0"]["hybrid"]["0.1"]["rec"]["psnr"]))
    for name in ("classical_s0", "hybrid_s0"):  # on a fixed batch, so batches add no noise
        p = summary["history"][name]["probe"]
        assert p["after"] < 0.97 * p["before"], (name, p)
    assert (tmp_path / "rec" / "table2.md").is_file()

    # Stopped at the first checkpoint, then resumed: the same numbers as straight through.
    ck, out2 = tmp_path / "ck", tmp_path / "edof2"
    with pytest.raises(OutOfTime):
        edof.run(common + ["--out", str(out2), "--checkpoint", str(ck), "--time-limit", "1e-6"])
    assert not out2.exists() and (ck / "seed0" / "classical.json").is_file()
    edof.run(common + ["--out", str(out2), "--checkpoint", str(ck), "--resume"])
    again = json.loads((out2 / "table2.json").read_text())
    assert again["lenses"] == table["lenses"]
    # Resumed once more after the end: nothing is trained or evaluated again (the
    # evaluations are kept in the checkpoint folder), and the table is the same.
    assert (ck / "seed0" / "eval_hybrid.json").is_file()
    third = edof.run(common + ["--out", str(tmp_path / "edof3"), "--checkpoint", str(ck),
                               "--resume"])
    assert json.loads((tmp_path / "edof3" / "table2.json").read_text())["lenses"] == \
        table["lenses"]
    assert third["timings_s"]["train_hybrid_s0_s"] < 5.0
    # edof.merge at smoke cost: the resumed run and a copy relabelled as seed 1 (the merge's
    # equality with a two-seed run is checked by the slow test below); its refusals.
    from jaxlens.experiments.edof import merge
    from jaxlens.experiments.runfolder import UsageError

    _relabelled(out2, tmp_path / "s1", seed=1)
    merged = merge.run(["--out", str(tmp_path / "merged"), str(out2), str(tmp_path / "s1")])
    m = json.loads((tmp_path / "merged" / "table2.json").read_text())
    assert m["seeds"] == [0, 1] and _flat(m["lenses"]) == pytest.approx(
        _flat(table["lenses"]), rel=1e-14)  # the mean of two equal seeds, to rounding
    assert m["gain_per_seed"]["hybrid"]["0.1"] == 2 * table["gain_per_seed"]["hybrid"]["0.1"]
    assert "seeds [1]" in (tmp_path / "merged" / "table2.md").read_text()
    with pytest.raises(UsageError, match="seed 0 is in both"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(tmp_path / "edof3")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsageError, match="has no table2_per_image.json"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(tmp_path / "empty")])
    bad = tmp_path / "bad"
    shutil.copytree(tmp_path / "s1", bad)
    (bad / "summary.json").write_text('{"config": {},\n "command": ')
    with pytest.raises(UsageError, match=r"bad/summary.json:2: not valid JSON"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(bad)])
    (bad / "summary.json").write_text('{"config": {}}')
    with pytest.raises(UsageError, match=r"summary.json is not an EDoF run's summary: it has "
                                         r"no command, psf_depth_variation, odd_terms"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(bad)])
    shutil.copy(tmp_path / "s1" / "summary.json", bad / "summary.json")
    per = json.loads((bad / "table2_per_image.json").read_text())
    per["values"]["1"]["hybrid"]["0.1"]["rec"]["psnr"].pop()
    (bad / "table2_per_image.json").write_text(json.dumps(per))
    with pytest.raises(UsageError, match=r"seed 1, lens hybrid, 0.1 m, rec psnr: 3 values for "
                                         r"4 crops"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(bad)])
    del per["values"]["1"]["hybrid"]
    (bad / "table2_per_image.json").write_text(json.dumps(per))
    with pytest.raises(UsageError, match=r"per-crop values of seed 1, lens hybrid are missing"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(bad)])
    shutil.copy(tmp_path / "s1" / "table2_per_image.json", bad / "table2_per_image.json")
    summ = json.loads((tmp_path / "s1" / "summary.json").read_text())
    summ["config"]["steps2"] += 2
    (bad / "summary.json").write_text(json.dumps(summ))
    with pytest.raises(UsageError, match=r"other options \(steps2\)"):
        merge.run(["--out", str(tmp_path / "m2"), str(out2), str(bad)])
    # Runs written by a version with an option this one lacks still merge with each other.
    for name, src in (("f0", out2), ("f1", tmp_path / "s1")):
        shutil.copytree(src, tmp_path / name)
        summ = json.loads((tmp_path / name / "summary.json").read_text())
        summ["config"]["future_option"] = 1
        (tmp_path / name / "summary.json").write_text(json.dumps(summ))
    future = merge.run(["--out", str(tmp_path / "mf"), str(tmp_path / "f0"),
                        str(tmp_path / "f1")])
    assert future["checks"] == merged["checks"]
    with pytest.raises(UsageError, match="holds an earlier run"):
        merge.run(["--out", str(tmp_path / "merged"), str(out2), str(tmp_path / "s1")])
    assert not (tmp_path / "m2").exists()


def _flat(tree: dict, path: str = "") -> dict:
    """A nested dict of numbers as ``{"a/b/c": number}``."""
    out = {}
    for k, v in tree.items():
        out.update(_flat(v, f"{path}{k}/") if isinstance(v, dict) else {f"{path}{k}": v})
    return out


def _relabelled(src, dst, *, seed):
    """A copy of a one-seed run folder whose per-crop values are filed under ``seed``."""
    shutil.copytree(src, dst)
    per = json.loads((dst / "table2_per_image.json").read_text())
    (old,) = per["seeds"]
    per["seeds"], per["values"] = [seed], {str(seed): per["values"][str(old)]}
    (dst / "table2_per_image.json").write_text(json.dumps(per))


@pytest.mark.slow
def test_merge_extension_and_evaluation_options_of_the_smoke_run(tmp_path, capsys):
    """Slow (CI runs the smoke above): a second seed run on its own and merged with the
    first gives the table of one run over both seeds; an evaluation-only option resumes the
    trained lenses; a longer stage 2 extends them, a shorter one is refused."""
    from jaxlens.experiments.edof import cli as edof

    common = ["--smoke", "--quiet", "--lenses", "classical,hybrid", "--max-crops", "4"]
    out2, ck = tmp_path / "edof2", tmp_path / "ck"
    edof.run(common + ["--out", str(out2), "--checkpoint", str(ck)])
    table = json.loads((out2 / "table2.json").read_text())
    # A second seed run on its own, merged with the first (edof.merge), gives the table of
    # one run over both seeds; the merge refuses runs that share a seed or differ otherwise.
    from jaxlens.experiments.edof import merge
    from jaxlens.experiments.runfolder import UsageError

    capsys.readouterr()
    edof.run(common + ["--seeds", "1", "--out", str(tmp_path / "s1"), "--checkpoint", str(ck),
                       "--resume"])
    # A lens that --resume finds no checkpoint of is said to start over (a mistyped folder).
    assert "no checkpoint of the hybrid lens (seed 1)" in capsys.readouterr().err
    edof.run(common + ["--seeds", "0,1", "--out", str(tmp_path / "s01"), "--checkpoint",
                       str(ck), "--resume"])
    assert "no checkpoint" not in capsys.readouterr().err
    merged = merge.run(["--out", str(tmp_path / "merged"), str(out2), str(tmp_path / "s1")])
    m, both = (json.loads((tmp_path / f / "table2.json").read_text()) for f in ("merged", "s01"))
    assert m["seeds"] == both["seeds"] == [0, 1]
    for key in ("lenses", "gain_vs_classical", "gain_per_seed", "light_on_sensor",
                "gain_vs_classical_image_balanced", "rec_psnr_by_image", "psf_depth_variation",
                "test", "base_lens"):
        assert m[key] == both[key], key
    assert merged["checks"] == json.loads((tmp_path / "s01" / "summary.json").read_text())[
        "checks"]
    # An evaluation-only option (--eval-pupil) resumes the trained lenses and evaluates them
    # anew; an option that changes the training refuses the checkpoint.
    fourth = edof.run(common + ["--out", str(tmp_path / "edof4"), "--checkpoint", str(ck),
                                "--resume", "--eval-pupil", "12"])
    assert fourth["timings_s"]["train_hybrid_s0_s"] < 5.0
    settings = json.loads((ck / "seed0" / "eval_hybrid_settings.json").read_text())
    assert settings["eval_pupil"] == 12 and settings["crops"] == 4
    assert settings["training"]["steps2"] == 2
    with pytest.raises(ValueError, match=r"other training options \(--steps 60 there, 61 here\)"):
        edof.run(common + ["--out", str(tmp_path / "edof5"), "--checkpoint", str(ck),
                           "--resume", "--steps", "61"])
    # A longer stage 2 extends the finished lenses and evaluates them anew (its cached
    # evaluation was made with the shorter training): the same table as a run straight
    # through with it. A shorter one than the lenses have done is refused.
    # (The classical lens only, to keep the test short: the mechanism is the same for every lens.
    # The straight run goes first: the extension then reuses its compiled programs.)
    longer = ["--smoke", "--quiet", "--lenses", "classical", "--max-crops", "4", "--steps2", "4"]
    edof.run(longer + ["--out", str(tmp_path / "edof7")])
    with pytest.raises(UsageError, match=r"other options \(steps2\)"):
        merge.run(["--out", str(tmp_path / "m2"), str(tmp_path / "s1"), str(tmp_path / "edof7")])
    extended = edof.run(longer + ["--out", str(tmp_path / "edof6"), "--checkpoint", str(ck),
                                  "--resume"])
    assert [r["step"] for r in extended["history"]["classical_s0"]["stage2"]] == [2, 4]
    assert "after" in extended["history"]["classical_s0"]["probe"]
    table6 = json.loads((tmp_path / "edof6" / "table2.json").read_text())
    assert table6["lenses"] == json.loads((tmp_path / "edof7" / "table2.json").read_text())[
        "lenses"]
    assert table6["lenses"]["classical"] != table["lenses"]["classical"]
    with pytest.raises(ValueError, match="stage-2 steps"):
        edof.run(common + ["--out", str(tmp_path / "edof8"), "--checkpoint", str(ck),
                           "--resume", "--steps2", "3"])


def test_reported_fov_is_the_real_chief_ray_to_the_sensor_corner():
    """The stop at an ideal thin lens, then a flat plate (thickness t, index n) before the
    image: the chief ray of θ lands at h(θ) = (d1 + d2)·tanθ + t·tanθ_p, sinθ_p = sinθ/n
    (barrel distortion). The reported FoV is 2θ with h(θ) = the sensor half-diagonal, solved
    here by bisection in numpy; the paraxial 2·atan(half/f) would be over 1° less."""
    import jaxlens as jl
    from jaxlens.experiments.edof import report
    from jaxlens.optics.lens import Sensor
    from jaxlens.optics.paraxial_surface import ParaxialSurface

    f, t, d1 = 5.0, 1.5, 0.5
    glass = jl.ModelGlass(1.6, 1e9)
    n = float(glass.index(0.5876))
    d2 = f - d1 - t / n
    lens = jl.Lens(surfaces=(jl.Stop(), ParaxialSurface(focal_length=f), jl.Sphere(0.0),
                             jl.Sphere(0.0)),
                   thickness=jnp.array([0.0, d1, t, d2]),
                   materials=(jl.Air(), jl.Air(), glass, jl.Air()), stop=0, epd=1.0,
                   sensor=Sensor((600, 800), 0.01))
    half = 0.5 * np.hypot(6.0, 8.0)
    lo, hi = 0.0, np.pi / 2 - 1e-9
    for _ in range(200):
        th = 0.5 * (lo + hi)
        h = (d1 + d2) * np.tan(th) + t * np.tan(np.arcsin(np.sin(th) / n))
        lo, hi = (th, hi) if h < half else (lo, th)
    want = 2 * np.degrees(lo)
    assert want - 2 * np.degrees(np.arctan(half / f)) > 1.0
    assert report._fov(lens) == pytest.approx(want, abs=1e-8)


def test_training_config_keeps_only_what_a_lens_reads():
    """A lens resumes across options of other lenses and evaluation-only options, and a
    checkpoint written before a field existed reads as that field's default."""
    import dataclasses

    from jaxlens.experiments.edof.train import Config, training_config

    old = json.loads(json.dumps(dataclasses.asdict(Config())))
    new = dict(old, hybrid_floor=1.0, eval_pupil=12)
    assert training_config(old, "classical") == training_config(new, "classical")
    assert training_config(old, "cubic") == training_config(new, "cubic")
    assert training_config(old, "hybrid") != training_config(new, "hybrid")
    assert training_config(old) != training_config(new)  # no lens: every training field
    del old["hybrid_floor"]  # written before the field existed
    assert training_config(old, "hybrid") == training_config(dict(new, hybrid_floor=None),
                                                             "hybrid")
    assert training_config(old, "cubic") != training_config(dict(new, steps=61), "cubic")


@pytest.mark.parametrize("steps", [1, 7, 60, 1200])
def test_network_learning_rate_is_optax_warmup_cosine(steps):
    """The host-side schedule (an argument of the compiled steps) is optax's warm-up and
    cosine decay to 5 % at ``steps``, and holds its end value after it."""
    import optax

    from jaxlens.experiments.edof.train import net_learning_rate

    warmup = max(1, min(20, steps // 10))
    want = optax.warmup_cosine_decay_schedule(0.0, 3e-3, warmup, max(steps, warmup + 1),
                                              1.5e-4)
    for step in sorted({0, 1, warmup - 1, warmup, warmup + 1, steps // 2, steps - 1, steps,
                        steps + 5}):
        assert net_learning_rate(step, steps, 3e-3) == pytest.approx(float(want(step)),
                                                                     rel=1e-6, abs=1e-12)


def test_compiled_steps_see_only_what_they_read():
    """Configs that differ in seeds, step counts, learning rates, logging or evaluation get
    the same static step options and optimizers (so one compiled program serves them); an
    option the steps read changes them."""
    import dataclasses

    from jaxlens.experiments.edof import train as T

    base = T.Config()
    other = dataclasses.replace(base, seed=3, steps=61, steps2=4, lr_net=3e-3, log_every=5,
                                refresh_every=7, eval_pupil=12, crop=64, lens_every=2,
                                cubic_floor=0.5, hybrid_floor=1.0, lens_accept=True)
    assert other.step_config == base.step_config
    assert hash(other.step_config) == hash(base.step_config)
    assert T.optimizers(other) == T.optimizers(base)
    for change in ({"photons": 100.0}, {"tile": 16}, {"live_front_end": True},
                   {"real_halo": True}):
        assert dataclasses.replace(base, **change).step_config != base.step_config, change
    assert T.optimizers(dataclasses.replace(base, lr_lens=1e-3)) != T.optimizers(base)
    with pytest.raises(AttributeError):
        base.step_config.seed  # noqa: B018


@pytest.mark.slow  # a non-default option (about 30-40 s on 2 cores); CI time
def test_live_front_end_differentiates_the_wiener_psfs(classical):
    """With ``live_front_end`` the lens step traces all 8 depths and the front end's PSFs are
    their mean (the bank's ``wkern`` [K=1, B, 3, k, k] is not read); without it the bank's
    PSFs are used."""
    import dataclasses

    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.edof.decoder import make_decoder

    cfg = dataclasses.replace(T.Config(), tile=8, kernel_size=5, batch=2, pupil=6, width=4,
                              enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,))
    lens = L.to_hybrid(classical, n_odd=2, cubic=0.003).astype(jnp.float32)
    pmap = L.HybridParameterization.of(lens)
    params = pmap.from_lens(lens)
    dec = make_decoder("wiener", nsr=0.05, key=jax.random.PRNGKey(0), width=4,
                       enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,))
    gate, tie = L.gates(params, "hybrid")
    windows = jnp.asarray(np.random.default_rng(1).random((2, 12, 12, 3)), jnp.float32)
    xy = jnp.asarray([[0.0, 0.0], [0.3, -0.2]], jnp.float32)
    depths = jnp.asarray(1e3 * np.asarray(L.DEPTHS_M), jnp.float32)
    pair = jnp.asarray([0, 7])
    delta = jnp.zeros((1, 2, 3, 5, 5), jnp.float32).at[..., 2, 2].set(1.0)
    box = jnp.full((1, 2, 3, 5, 5), 1 / 25, jnp.float32)

    def step(live, wkern):
        c = dataclasses.replace(cfg, live_front_end=live)
        net_opt, lens_opt = T.optimizers(c)
        out = T.joint_step(dec, params, net_opt.init(eqx.filter(dec, eqx.is_inexact_array)),
                           lens_opt.init(eqx.filter(params, eqx.is_inexact_array)), pmap,
                           windows, xy, depths, pair, wkern, jax.random.PRNGKey(2), gate, tie,
                           -jnp.inf, jnp.float32(1e-3), cfg=c.step_config, net_opt=net_opt,
                           lens_opt=lens_opt)
        return float(out[4]), out[1]

    live_a, p_live = step(True, delta)
    live_b, _ = step(True, box)
    stale_a, _ = step(False, delta)
    stale_b, _ = step(False, box)
    assert live_a == live_b and stale_a != stale_b
    assert np.isfinite(live_a) and live_a != stale_a
    moved = jax.tree_util.tree_map(lambda u, v: float(jnp.max(jnp.abs(u - v))), p_live, params)
    assert max(jax.tree_util.tree_leaves(moved)) > 0  # the lens took a finite step


@pytest.mark.slow  # a non-default option (about 30-40 s on 2 cores); CI time
def test_lens_accept_undoes_a_lens_step_that_raises_the_check_loss(classical, monkeypatch):
    """With ``lens_accept`` a lens update is kept or undone (parameters and optimizer state)
    by comparing ``Trainer.check_loss`` of the new and the old lens; both outcomes are
    counted in ``hist["lens_steps"]``."""
    import dataclasses

    from jaxlens.experiments.edof import scenes as S
    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.edof.decoder import make_decoder

    cfg = dataclasses.replace(T.Config(), tile=8, kernel_size=5, batch=2, pupil=6, steps=1,
                              steps2=0, lens_every=1, width=4, enc_blocks=(1,),
                              middle_blocks=0, dec_blocks=(1,), decoder="nafnet",
                              lens_accept=True)
    lens = L.to_hybrid(classical, n_odd=2, cubic=0.003).astype(jnp.float32)
    pmap = L.HybridParameterization.of(lens)
    images = [np.random.default_rng(3).random((24, 24, 3)).astype(np.float32)]
    start = pmap.from_lens(lens)

    def train(new_minus_old):
        dec = make_decoder("nafnet", nsr=0.05, key=jax.random.PRNGKey(0), width=4,
                           enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,))
        src = T.BatchSource(S.PatchSampler(images, cfg.window, seed=1), (2, 2), cfg, seed=2)
        tr = T.Trainer("hybrid", pmap, start, dec, src, cfg, jax.random.PRNGKey(4))
        real = tr.check_loss
        calls = []

        def fake(params):  # first call: the new lens, second: the old one
            calls.append(real(params))
            return calls[-1] + (new_minus_old if len(calls) % 2 == 1 else 0.0)

        monkeypatch.setattr(tr, "check_loss", fake)
        _, params, hist = tr.run()
        assert len(calls) == 2 and np.all(np.isfinite(calls))
        return params, hist["lens_steps"]

    params, counts = train(+1.0)
    assert counts == {"kept": 0, "undone": 1}
    assert all(bool(jnp.all(a == b)) for a, b in zip(jax.tree_util.tree_leaves(params),
                                                     jax.tree_util.tree_leaves(start),
                                                     strict=True))
    params, counts = train(-1.0)
    assert counts == {"kept": 1, "undone": 0}
    assert any(bool(jnp.any(a != b)) for a, b in zip(jax.tree_util.tree_leaves(params),
                                                     jax.tree_util.tree_leaves(start),
                                                     strict=True))


def test_checkpoints_of_the_old_curvature_units_convert_only_where_exact(classical, tmp_path):
    """A version-1 checkpoint (c stored as c·R) resumes a lens that never trains c with c
    converted to its sag unit; a lens that trains c (the hybrid) refuses it."""
    import dataclasses

    from jaxlens.experiments.edof import scenes as S
    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.edof.decoder import make_decoder

    cfg = dataclasses.replace(T.Config(), tile=8, kernel_size=5, batch=2, width=4,
                              enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,),
                              decoder="nafnet")
    lens = L.to_hybrid(classical, n_odd=2).astype(jnp.float32)
    pmap = L.HybridParameterization.of(lens)
    start = pmap.from_lens(lens)
    r = float(pmap.radius)
    images = [np.random.default_rng(3).random((24, 24, 3)).astype(np.float32)]

    def trainer(name):
        dec = make_decoder("nafnet", nsr=0.05, key=jax.random.PRNGKey(0), width=4,
                           enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,))
        src = T.BatchSource(S.PatchSampler(images, cfg.window, seed=1), (2, 2), cfg, seed=2)
        return T.Trainer(name, pmap, start, dec, src, cfg, jax.random.PRNGKey(4),
                         folder=str(tmp_path / name))

    for name in ("classical", "hybrid"):
        old = trainer(name)
        old.params = eqx.tree_at(lambda p: p.c, old.params, jnp.asarray(
            float(lens.surfaces[1].c) * r, jnp.float32))  # version 1: c·R
        old.save()
        meta = tmp_path / name / f"{name}.json"
        info = json.loads(meta.read_text())
        info["params_version"] = 1
        meta.write_text(json.dumps(info))
    new = trainer("classical")
    assert new.load()
    assert float(new.params.c) == pytest.approx(float(start.c), rel=1e-6)
    with pytest.raises(ValueError, match="units of version 1"):
        trainer("hybrid").load()
    # A checkpoint whose optimizer states are per leaf (before optax.flatten) is refused.
    meta = tmp_path / "classical" / "classical.json"
    info = json.loads(meta.read_text())
    del info["state_layout"]
    meta.write_text(json.dumps(info))
    with pytest.raises(ValueError, match="optimizer states in layout 1"):
        trainer("classical").load()


def test_the_command_line_keeps_compiled_programs_beside_the_checkpoints(tmp_path):
    """A resumed piece loads what the last piece compiled: ``use_compile_cache`` points JAX's
    persistent cache into ``--checkpoint`` (a process-wide setting, so checked in a fresh
    process), and defers to a cache the user named in the environment."""
    import os
    import subprocess
    import sys

    code = ("import jax, sys\n"
            "from jaxlens.experiments.edof import cli\n"
            "print(cli.use_compile_cache(sys.argv[1]))\n"
            "print(jax.config.jax_compilation_cache_dir)\n")
    env = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "ck")], env=env,
                         capture_output=True, text=True, check=True).stdout.split()
    assert out == [str(tmp_path / "ck" / "compile_cache")] * 2
    env["JAX_COMPILATION_CACHE_DIR"] = str(tmp_path / "mine")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "ck")], env=env,
                         capture_output=True, text=True, check=True).stdout.split()
    assert out == [str(tmp_path / "mine")] * 2


def test_a_checkpoint_save_stopped_before_its_commit_resumes_the_previous_one(
        classical, tmp_path, monkeypatch):
    """The .json names the .eqx it belongs to and is replaced last: a save stopped after the
    arrays were written (Ctrl-C) leaves the previous checkpoint whole, where before the new
    arrays were resumed at the old step. A checkpoint of the old layout (<name>.eqx, no name
    in the .json) still resumes."""
    import dataclasses

    from jaxlens.experiments.edof import scenes as S
    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.edof.decoder import make_decoder

    cfg = dataclasses.replace(T.Config(), tile=8, kernel_size=5, batch=2, width=4,
                              enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,),
                              decoder="nafnet")
    lens = L.to_hybrid(classical, n_odd=2).astype(jnp.float32)
    pmap = L.HybridParameterization.of(lens)
    images = [np.random.default_rng(3).random((24, 24, 3)).astype(np.float32)]
    folder = tmp_path / "ck"

    def trainer():
        dec = make_decoder("nafnet", nsr=0.05, key=jax.random.PRNGKey(0), width=4,
                           enc_blocks=(1,), middle_blocks=0, dec_blocks=(1,))
        src = T.BatchSource(S.PatchSampler(images, cfg.window, seed=1), (2, 2), cfg, seed=2)
        return T.Trainer("classical", pmap, pmap.from_lens(lens), dec, src, cfg,
                         jax.random.PRNGKey(4), folder=str(folder))

    first = trainer()
    first.step = 7
    first.save()
    saved_focus = float(first.params.focus)
    second = trainer()
    second.step = 9
    second.params = eqx.tree_at(lambda p: p.focus, second.params, second.params.focus + 1)

    def stopped(path, text, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(T, "write_whole", stopped)
    with pytest.raises(KeyboardInterrupt):
        second.save()
    monkeypatch.undo()
    resumed = trainer()
    assert resumed.load()
    assert resumed.step == 7 and float(resumed.params.focus) == saved_focus
    # The next save removes the arrays of the stopped one and of the one it replaces.
    resumed.save()
    assert len(list(folder.glob("*.eqx"))) == 1
    # The layout before: <name>.eqx beside a .json that names no file.
    info = json.loads((folder / "classical.json").read_text())
    (folder / info.pop("tree")).rename(folder / "classical.eqx")
    (folder / "classical.json").write_text(json.dumps(info))
    old = trainer()
    assert old.load() and old.step == 7
    (folder / "classical.eqx").unlink()
    with pytest.raises(ValueError, match="names its arrays classical.eqx, which is not in"):
        trainer().load()
