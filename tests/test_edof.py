"""The EDoF experiment: losses, lens parameters, patch convolution, PSF measures, smoke run."""

import json
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.experiments.edof import lenses as L
from jaxlens.experiments.edof import losses as LS
from jaxlens.experiments.edof import optics as O
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


def test_table2_rec_metrics_come_from_the_reconstruction(classical):
    """``train.evaluate``: "sim" scores the noisy simulation at the depth in m (rendered at
    1000·d mm, clipped to [0, 1]), "rec" the network's output clipped to [0, 1]."""
    from jaxlens.experiments.edof import train
    from jaxlens.io.images import psnr, ssim

    cfg = train.Config(binning=8, patch=64, kernel_size=5, eval_pupil=4, noise=0.02)
    rng = np.random.default_rng(0)
    img = rng.random((128, 128, 3))
    img[:40, :40] = 1.0  # a white corner: blur plus noise goes above 1 there
    target = np.clip(rng.normal(0.5, 0.6, img.shape), -0.5, 1.5)

    def net(x):  # a "network" whose output is known: its PSNR is known in closed form
        return jnp.asarray(target, x.dtype)

    # Two images (the second the negative of the first); keep=0 returns the first.
    metrics, ex = train.evaluate(classical, net, [img, 1.0 - img], [0.2], cfg,
                                 key=jax.random.PRNGKey(0), keep=0)
    m = metrics["0.2"]
    sim, rec = ex["0.2"]
    np.testing.assert_array_equal(rec, np.clip(target, 0.0, 1.0))
    clean = np.asarray(O.render_tiled(classical, jnp.asarray(img), 200.0, kernel_size=5,
                                      pixel_size=cfg.pixel_size, patch=64, pupil=4))
    inside = (clean > 0.1) & (clean < 0.9)
    noise = (sim - clean)[inside]
    assert abs(noise.mean()) < 2e-3 and np.std(noise) == pytest.approx(0.02, rel=0.05)
    assert sim.min() >= 0.0 and sim.max() == 1.0  # clipped, and the white corner reaches 1
    want = [10 * np.log10(1.0 / np.mean((x - np.clip(target, 0, 1)) ** 2)) for x in (img,
                                                                                     1 - img)]
    assert m["rec"]["psnr"] == pytest.approx(np.mean(want), rel=1e-9)
    assert m["rec"]["ssim"] < 0.1  # noise against an image: no structure in common
    assert m["sim"]["psnr"] > m["rec"]["psnr"] + 5.0
    assert psnr(img, sim, data_range=1.0) > 20.0
    assert ssim(img, rec, data_range=1.0) < 0.1


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
    p = L.HybridParams.from_lens(hyb)
    back = p.apply(hyb)
    for a, b in zip(jax.tree_util.tree_leaves(back), jax.tree_util.tree_leaves(hyb), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-15)
    # Scaled odd parameter = sag at R over SAG_SCALE.
    r = 0.5 * float(hyb.epd)
    assert float(p.odd_x[0]) == pytest.approx(0.004 * r**3 / L.SAG_SCALE)
    # The odd profile is the analytic cubic a·(x³ + y³).
    xs, h = L.odd_profile(hyb, n=21)
    xx, yy = np.meshgrid(xs, xs)
    inside = ~np.isnan(h)
    np.testing.assert_allclose(h[inside], 0.004 * (xx**3 + yy**3)[inside], rtol=1e-9, atol=1e-15)


def test_gates_select_and_tie_parameters(classical):
    p = L.HybridParams.from_lens(L.to_hybrid(classical, n_odd=3, cubic=0.003))
    g = jax.tree_util.tree_map(lambda v: jnp.ones_like(v) * 2.0, p)
    g = g.__class__(
        c=g.c,
        k=g.k,
        even=g.even,
        odd_x=jnp.array([1.0, 2.0, 3.0]),
        odd_y=jnp.array([3.0, 4.0, 5.0]),
        focus=g.focus,
        radius=g.radius,
        index=g.index,
    )
    gate, tie = L.gates(p, "classical")
    out = L.apply_gates(g, gate, tie)
    assert all(float(jnp.sum(jnp.abs(v))) == 0 for v in jax.tree_util.tree_leaves(out))
    gate, tie = L.gates(p, "cubic")
    out = L.apply_gates(g, gate, tie)
    np.testing.assert_allclose(out.odd_x, [2.0, 0.0, 0.0])
    np.testing.assert_allclose(out.odd_y, [2.0, 0.0, 0.0])
    assert float(out.c) == 0 and float(out.focus) == 2.0 and float(out.radius) == 0
    gate, tie = L.gates(p, "hybrid")
    out = L.apply_gates(g, gate, tie)
    np.testing.assert_allclose(out.odd_x, [1.0, 2.0, 3.0])
    assert float(out.radius) == 0
    gate, tie = L.gates(p, "hybrid-held-focus")
    out = L.apply_gates(g, gate, tie)
    assert float(out.c) == 0 and float(out.focus) == 0 and float(out.k) == 2.0
    np.testing.assert_allclose(out.odd_y, [3.0, 4.0, 5.0])
    with pytest.raises(ValueError, match="kind"):
        L.gates(p, "other")


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


def test_lens_rate_waits_for_the_network():
    from jaxlens.experiments.edof.train import Config, make_optimizer

    cfg = Config(steps=8, lens_delay=0.25, lr_net=1e-2, lr_lens=1e-1)
    opt = make_optimizer(cfg, cfg.steps)
    trainable = ({"w": jnp.ones(3)}, {"c": jnp.ones(2)})
    grads = ({"w": jnp.ones(3)}, {"c": jnp.ones(2)})
    state = opt.init(trainable)
    lens_steps, net_steps = [], []
    for _ in range(6):
        (u_net, u_lens), state = opt.update(grads, state, trainable)
        lens_steps.append(float(jnp.abs(u_lens["c"][0])))
        net_steps.append(float(jnp.abs(u_net["w"][0])))
    # Frozen for 2 steps (the network trains), then a linear ramp over 2 steps to the rate.
    assert lens_steps[:3] == [0.0, 0.0, 0.0]
    assert lens_steps[3] == pytest.approx(0.5 * 0.1, rel=1e-3)
    assert lens_steps[4] == pytest.approx(0.1, rel=1e-3)
    assert all(v > 0 for v in net_steps[1:])
    # With no delay the lens moves from the first step.
    opt0 = make_optimizer(Config(steps=8, lens_delay=0.0, lr_lens=1e-1), 8)
    (_, u_lens), _ = opt0.update(grads, opt0.init(trainable), trainable)
    assert float(jnp.abs(u_lens["c"][0])) == pytest.approx(0.1, rel=1e-3)


# --- image formation helpers -----------------------------------------------------------------
def test_conv_valid_is_a_true_convolution():
    rng = np.random.default_rng(0)
    win = rng.random((9, 9, 2))
    ker = rng.random((2, 3, 3))
    out = np.asarray(O.conv_valid(jnp.asarray(win), jnp.asarray(ker)))
    ref = np.zeros((7, 7, 2))
    for c in range(2):
        for i in range(7):
            for j in range(7):
                # y[n] = Σ_m x[n − m] k[m], in 'valid' coordinates.
                ref[i, j, c] = np.sum(win[i : i + 3, j : j + 3, c] * ker[c, ::-1, ::-1])
    np.testing.assert_allclose(out, ref, rtol=1e-10)


def test_pupil_disc_fills_the_disc_evenly():
    p = np.asarray(O.pupil_disc(16))
    r = np.hypot(p[:, 0], p[:, 1])
    assert p.shape == (256, 2) and r.max() < 1.0
    # Equal-area cells: half the points inside radius 1/sqrt(2).
    assert np.mean(r < 2**-0.5) == pytest.approx(0.5, abs=1 / 16)


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


# --- the experiment, end to end ------------------------------------------------------------------
def test_smoke_run_writes_outputs_and_loss_falls(tmp_path):
    from jaxlens.experiments.edof import cli as edof

    out = tmp_path / "edof"
    summary = edof.run(
        [
            "--smoke",
            "--quiet",
            "--lenses",
            "classical,hybrid",
            "--out",
            str(out),
            "--record",
            str(tmp_path / "rec"),
        ]
    )
    for name in (
        "table2.json",
        "table2.md",
        "summary.json",
        "command.txt",
        "loss.png",
        "psf_grid_hybrid.png",
        "mtf_by_depth.png",
        "odd_profile.png",
        "reconstructions.png",
        "lenses/hybrid.json",
        "lenses/hybrid.zmx",
        "nets/hybrid.eqx",
    ):
        assert (out / name).is_file(), name
        assert os.path.getsize(out / name) > 0
    table = json.loads((out / "table2.json").read_text())
    assert set(table) == {"classical", "hybrid"}
    for row in table.values():
        assert set(row) == {"0.1", "0.2", "10"}
        for d in row.values():
            assert set(d) == {"sim", "rec"}
            assert all(np.isfinite(d[t][m]) for t in d for m in ("psnr", "ssim"))
    for name in ("classical", "hybrid"):
        h = summary["history"][name]["stage1"]
        assert h[-1]["loss"] < h[0]["loss"], name
    assert (tmp_path / "rec" / "table2.md").is_file()
    # PSFs at 10 cm, 20 cm and 10 m differ (the smoke lenses are far from depth-invariant,
    # about 0.25 in L1 of unit-sum PSFs), and the summary is the mean over the 3 fields.
    for name, v in summary["psf_depth_variation"].items():
        assert len(v["l1_per_field"]) == len(v["ncc_per_field"]) == 3, name
        assert v["l1"] == pytest.approx(np.mean(v["l1_per_field"]), rel=1e-9)
        assert 0.05 < v["l1"] < 1.0 and 0.5 < v["ncc"] < 1.0, (name, v)
