"""Joint training of a lens and a reconstruction network, and the evaluation of Table 2.

Stage 1 trains the network together with the lens's free parameters (``HybridParams`` gated
by ``lenses.gates``: all for the hybrid lens, the tied cubic strength for the cubic plate,
none for the classical lens) on simulated patches with the paper's loss
(``losses.edof_loss``). Every batch draws two distinct depths of the 8 training depths and
renders all its patches at both, with the three wavelengths of ``WAVELENGTHS_RGB``. Stage 2
freezes the lens and refines the network on patches rendered through randomly perturbed
copies of it (``lenses.perturb``: manufacturing and registration errors), one copy per
patch, with ``L_rec`` alone.

Each step is one jitted function (``train_step``, shared by both stages and all three
lenses); the Python loop over steps syncs with the host only every ``log_every`` steps.
Gaussian read noise of standard deviation ``noise`` is added to the simulations before the
network sees them.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from ...nets import NAFNet
from ...optics.lens import Lens
from .lenses import DEPTHS_M, SPEC, Tolerances, apply_gates, dioptric_weights, gates, perturb
from .losses import edof_loss
from .optics import render_tiled, simulate_patch

STAGE2_LR_SCALE = 0.3
"""Stage 2's network learning rate relative to stage 1's."""


@dataclasses.dataclass(frozen=True)
class Config:
    """Options of the EDoF experiment (defaults: the CPU-scale run).

    Attributes:
        binning: sensor pixel binning of the paper's 1024² sensor of 4.97 µm pixels.
        patch: training patch side (pixels).
        kernel_size: PSF kernel side (pixels).
        batch: patches per batch (each rendered at two depths).
        pupil: rays per side of the pupil grid of a training PSF.
        steps: stage-1 steps (joint lens and network).
        steps2: stage-2 steps (network on perturbed lenses).
        lr_net, lr_lens: Adam learning rates (the lens parameters are scaled to order 1).
        lens_delay: fraction of the stage-1 steps during which the lens stays frozen and
            only the network trains (then the lens rate ramps up linearly over as many
            steps). Through a network that cannot yet reconstruct (a fresh NAFNet is the
            identity), the lens gradient only rewards a sharp raw image. Off (0) by
            default: at the CPU scale a delay of 0.25 did not keep the odd terms from
            shrinking and did not improve validation PSNR (``experiments/edof/NOTES.md``).
        depth_sampling: how a batch draws its two depths of the 8: "uniform" or
            "dioptric" (weights even in dioptres, ``lenses.dioptric_weights``).
        hold_focus: the hybrid lens keeps the classical lens's base curvature and sensor
            position (``lenses.gates`` "hybrid-held-focus"), so it cannot trade near for
            far depths by refocusing.
        w_sim, w_raw: ω1 and ω2 of the loss.
        noise: standard deviation of the Gaussian read noise (image range [0, 1]).
        width, enc_blocks, middle_blocks, dec_blocks: the NAFNet.
        n_odd: odd terms per axis of the hybrid surface (x³, x⁵, …).
        cubic_ratio: initial cubic strength, as a multiple of the defocus it hides
            (``lenses.cubic_strength_guess``); the hybrid starts at half of the plate's.
        eval_pupil: pupil samples per side of the evaluation PSFs.
        seed: random seed.
        log_every: host sync / progress-bar refresh interval (steps).
    """

    binning: int = 2
    patch: int = 64
    kernel_size: int = 41
    batch: int = 4
    pupil: int = 32
    steps: int = 400
    steps2: int = 100
    lr_net: float = 1e-3
    lr_lens: float = 2e-2
    lens_delay: float = 0.0
    depth_sampling: str = "uniform"
    hold_focus: bool = False
    w_sim: float = 0.1
    w_raw: float = 0.1
    noise: float = 0.01
    width: int = 16
    enc_blocks: tuple[int, ...] = (1, 1, 1)
    middle_blocks: int = 1
    dec_blocks: tuple[int, ...] = (1, 1, 1)
    n_odd: int = 3
    cubic_ratio: float = 1.5
    eval_pupil: int = 64
    seed: int = 0
    log_every: int = 10
    tolerances: Tolerances = dataclasses.field(default_factory=Tolerances)

    @property
    def window(self) -> int:
        """Side of a training scene window: the patch plus a kernel's margin (pixels)."""
        return self.patch + self.kernel_size - 1

    @property
    def pixel_size(self) -> float:
        """Binned pixel pitch (mm)."""
        return self.binning * SPEC["pixel_size_mm"]


def make_net(cfg: Config, key, dtype=jnp.float32) -> NAFNet:
    """The reconstruction network of the configuration."""
    return NAFNet(
        width=cfg.width,
        enc_blocks=cfg.enc_blocks,
        middle_blocks=cfg.middle_blocks,
        dec_blocks=cfg.dec_blocks,
        key=key,
        dtype=dtype,
    )


def _labels(trainable):
    net, params = trainable
    return (
        jax.tree_util.tree_map(lambda _: "net", net),
        jax.tree_util.tree_map(lambda _: "lens", params),
    )


@functools.lru_cache(maxsize=16)
def make_optimizer(cfg: Config, steps: int):
    """Adam with a cosine-decayed rate for the network and a delayed one for the lens.

    The lens rate is 0 for the first ``lens_delay · cfg.steps`` steps, ramps linearly to
    ``lr_lens`` over as many steps again and then stays constant (``Config.lens_delay``).

    Cached, so that equal configurations give the same (hashable) optimizer and the jitted
    steps, which take it as a static argument, compile once.
    """
    sched = optax.warmup_cosine_decay_schedule(
        0.0, cfg.lr_net, max(1, min(20, steps // 10)), max(steps, 1), cfg.lr_net * 0.05
    )
    net_opt = optax.chain(optax.clip_by_global_norm(1.0), optax.adam(sched))
    delay = int(round(cfg.lens_delay * cfg.steps))
    lens_sched = optax.linear_schedule(0.0, cfg.lr_lens, max(delay, 1), transition_begin=delay)
    lens_opt = optax.adam(lens_sched if delay > 0 else cfg.lr_lens)
    return optax.multi_transform({"net": net_opt, "lens": lens_opt}, _labels)


def _simulate_batch(lens, windows, xy, depths, key, cfg: Config, perturbation=None):
    """``[2, B, P, P, 3]`` patches at the two depths (one PSF per patch and depth).

    With ``perturbation`` (an array scale of ``cfg.tolerances``), every patch is rendered
    through its own randomly perturbed copy of the lens (``lenses.perturb``).
    """
    b = windows.shape[0]
    k_sim, k_pert = jax.random.split(key)
    keys = jax.random.split(k_sim, 2 * b).reshape(2, b, -1)

    def one(ln, window, p, d, k):
        return simulate_patch(
            ln,
            window,
            p,
            d,
            k,
            kernel_size=cfg.kernel_size,
            pixel_size=cfg.pixel_size,
            pupil=cfg.pupil,
        )

    if perturbation is None:
        per_depth = jax.vmap(one, in_axes=(None, 0, 0, None, 0))
        return jax.vmap(per_depth, in_axes=(None, None, None, 0, 0))(
            lens, windows, xy, depths, keys
        )
    lenses = jax.vmap(lambda k: perturb(lens, k, cfg.tolerances, scale=perturbation))(
        jax.random.split(k_pert, b)
    )
    per_depth = jax.vmap(one, in_axes=(0, 0, 0, None, 0))
    return jax.vmap(per_depth, in_axes=(None, None, None, 0, 0))(lenses, windows, xy, depths, keys)


def _gt(windows, cfg: Config):
    h = cfg.kernel_size // 2
    return windows[:, h : h + cfg.patch, h : h + cfg.patch]


def _reconstruct(net, sims, key, noise):
    noisy = sims + noise * jax.random.normal(key, sims.shape, sims.dtype)
    flat = noisy.reshape((-1,) + sims.shape[2:])
    return jax.vmap(net)(flat).reshape(sims.shape)


@eqx.filter_jit
def train_step(
    net,
    params,
    opt_state,
    base_lens,
    windows,
    xy,
    depths,
    key,
    gate,
    tie,
    perturbation,
    net_scale,
    *,
    cfg: Config,
    optimizer,
):
    """One training step of either stage; returns (net, params, opt_state, loss, parts).

    Stage 1 (joint): ``gate`` and ``tie`` (``lenses.gates``) say which lens parameters move,
    ``perturbation = 0``. Stage 2: ``gate`` all zero (the lens is frozen, so L_sim and L_raw
    do not reach the network and only L_rec trains it) and ``perturbation = 1`` (each patch
    through a randomly perturbed lens). ``net_scale`` scales the network's updates. All of
    these are arrays, so the three lenses and both stages share one compiled step.
    """
    k_sim, k_noise = jax.random.split(key)

    def loss_fn(trainable):
        net, params = trainable
        lens = params.apply(base_lens)
        sims = _simulate_batch(lens, windows, xy, depths, k_sim, cfg, perturbation)
        recs = _reconstruct(net, sims, k_noise, cfg.noise)
        return edof_loss(recs, sims, _gt(windows, cfg), w_sim=cfg.w_sim, w_raw=cfg.w_raw)

    trainable = (net, params)
    (loss, parts), grads = eqx.filter_value_and_grad(loss_fn, has_aux=True)(trainable)
    g_net, g_lens = grads
    grads = (g_net, apply_gates(g_lens, gate, tie))
    # A step whose loss or gradient is not finite (a rare ray-tracing failure) is skipped:
    # one NaN update would make the lens NaN for good, and a NaN lens renders black
    # patches with a finite loss. ``parts["skipped"]`` counts such steps.
    leaves = [g for g in jax.tree_util.tree_leaves(grads) if eqx.is_inexact_array(g)]
    ok = jnp.isfinite(loss) & jnp.all(jnp.stack([jnp.all(jnp.isfinite(g)) for g in leaves]))
    grads = jax.tree_util.tree_map(
        lambda g: jnp.where(ok, g, 0.0) if eqx.is_inexact_array(g) else g, grads
    )
    new_updates, new_state = optimizer.update(
        grads, opt_state, eqx.filter(trainable, eqx.is_inexact_array)
    )
    opt_state = jax.tree_util.tree_map(
        lambda a, b: jnp.where(ok, a, b) if eqx.is_array(a) else a, new_state, opt_state
    )
    u_net, u_lens = new_updates
    u_net = jax.tree_util.tree_map(lambda u: u * net_scale.astype(u.dtype) * ok, u_net)
    u_lens = jax.tree_util.tree_map(lambda u: u * ok, u_lens)
    net, params = eqx.apply_updates(trainable, (u_net, u_lens))
    parts = dict(parts, skipped=1.0 - ok.astype(loss.dtype))
    return net, params, opt_state, loss, parts


class BatchSource:
    """Host-side batches: scene windows, sensor positions and the depth pair."""

    def __init__(self, sampler, lens: Lens, cfg: Config, seed: int):
        self.sampler = sampler
        self.cfg = cfg
        self.rng = np.random.default_rng(seed)
        h, w = lens.sensor.size
        self.half = 0.5 * np.array([float(w), float(h)])
        self.depths = 1e3 * np.asarray(DEPTHS_M)
        if cfg.depth_sampling not in ("uniform", "dioptric"):
            raise ValueError(
                f"depth_sampling must be 'uniform' or 'dioptric', got {cfg.depth_sampling!r}"
            )
        self.weights = dioptric_weights(DEPTHS_M) if cfg.depth_sampling == "dioptric" else None

    def __call__(self, dtype=np.float32):
        cfg = self.cfg
        windows = self.sampler.sample(cfg.batch)
        xy = self.rng.uniform(-1.0, 1.0, (cfg.batch, 2)) * self.half
        pair = self.rng.choice(len(self.depths), 2, replace=False, p=self.weights)
        return (
            jnp.asarray(windows, dtype),
            jnp.asarray(xy, dtype),
            jnp.asarray(self.depths[pair], dtype),
        )


def train(
    name: str,
    base_lens: Lens,
    params,
    net: NAFNet,
    source: BatchSource,
    cfg: Config,
    *,
    kind: str,
    key,
    progress: Callable | None = None,
):
    """Stage 1 then stage 2 for one lens; returns ``(net, params, history)``.

    ``kind`` ("classical", "cubic" or "hybrid") selects the free lens parameters
    (``lenses.gates``). Stage 2 restarts the network's Adam state with its learning rate
    scaled by ``STAGE2_LR_SCALE``. ``history`` holds the loss parts every ``log_every``
    steps (``stage1``: dicts with ``step``, ``loss``, ``rec``, ``sim``, ``raw`` and
    ``skipped``, the number of steps skipped for a non-finite gradient since the last
    record; ``stage2``: dicts with ``step``, ``rec`` and ``skipped``).
    """
    dtype = params.c.dtype
    opt = make_optimizer(cfg, max(cfg.steps, cfg.steps2))
    gate, tie = gates(params, "hybrid-held-focus" if kind == "hybrid" and cfg.hold_focus else kind)
    frozen, _ = gates(params, "classical")
    stages = (
        (1, cfg.steps, gate, tie, 0.0, 1.0),
        (2, cfg.steps2, frozen, jnp.zeros((), dtype), 1.0, STAGE2_LR_SCALE),
    )
    hist: dict[str, list] = {"stage1": [], "stage2": []}
    bar = progress(total=cfg.steps + cfg.steps2, desc=name) if progress else None
    for stage, steps, g, t, pert, scale in stages:
        state = opt.init(eqx.filter((net, params), eqx.is_inexact_array))
        pert, scale = jnp.asarray(pert, dtype), jnp.asarray(scale, dtype)
        acc = []
        for step in range(steps):
            key, sub = jax.random.split(key)
            windows, xy, depths = source()
            net, params, state, loss, parts = train_step(
                net,
                params,
                state,
                base_lens,
                windows,
                xy,
                depths,
                sub,
                g,
                t,
                pert,
                scale,
                cfg=cfg,
                optimizer=opt,
            )
            acc.append((loss, parts))
            if (step + 1) % cfg.log_every and step + 1 != steps:
                continue
            vals = jax.device_get(acc)
            acc = []
            rec = {"step": step + 1, "loss": float(np.mean([v[0] for v in vals]))}
            for k in ("rec", "sim", "raw"):
                rec[k] = float(np.mean([v[1][k] for v in vals]))
            rec["skipped"] = int(round(sum(float(v[1]["skipped"]) for v in vals)))
            if not math.isfinite(rec["loss"]):
                raise FloatingPointError(
                    f"train[{name}]: non-finite loss at stage {stage} step {step + 1}"
                )
            hist[f"stage{stage}"].append(
                rec
                if stage == 1
                else {"step": rec["step"], "rec": rec["rec"], "skipped": rec["skipped"]}
            )
            if bar is not None:
                bar.set_postfix(stage=stage, loss=f"{rec['loss']:.4f}", rec=f"{rec['rec']:.4f}")
                bar.update(len(vals))
    if bar is not None:
        bar.close()
    return net, params, hist


# --------------------------------------------------------------------------------------
# Evaluation (Table 2)
# --------------------------------------------------------------------------------------
@eqx.filter_jit
def _restore(net, img):
    return jnp.clip(net(img), 0.0, 1.0)


def evaluate(lens: Lens, net: NAFNet, images, depths_m, cfg: Config, *, key, keep=None):
    """PSNR and SSIM of simulation and reconstruction on whole test images.

    Each test image fills the sensor; it is rendered tile by tile (``optics.render_tiled``:
    one RGB PSF per ``patch × patch`` tile, the training model on the whole frame), read
    noise is added, and the network restores the whole frame at once.

    Args:
        lens: the (trained) lens with its sensor.
        net: the network.
        images: test scenes ``[S, S, 3]`` at the sensor resolution.
        depths_m: depths (m from the stop).
        key: PRNG key for the noise (the same for every lens).
        keep: index of a test image whose images to return.

    Returns:
        ``(metrics, examples)``: metrics[str(depth)] = {"sim": {"psnr", "ssim"},
        "rec": {...}} averaged over the images; examples[str(depth)] = (sim, rec) of the
        kept image (NumPy, clipped to [0, 1]).
    """
    from ...io.images import psnr, ssim

    metrics, examples = {}, {}
    for d in depths_m:
        vals = {"sim": {"psnr": [], "ssim": []}, "rec": {"psnr": [], "ssim": []}}
        for i, img in enumerate(images):
            scene = jnp.asarray(img, lens.epd.dtype)
            sim = render_tiled(
                lens,
                scene,
                jnp.asarray(1e3 * d, scene.dtype),
                kernel_size=cfg.kernel_size,
                pixel_size=cfg.pixel_size,
                patch=cfg.patch,
                pupil=cfg.eval_pupil,
            )
            noise = jax.random.normal(jax.random.fold_in(key, i), sim.shape, sim.dtype)
            sim = sim + cfg.noise * noise
            rec = np.asarray(_restore(net, sim), np.float64)
            sim = np.clip(np.asarray(sim, np.float64), 0.0, 1.0)
            gt = np.asarray(img, np.float64)
            for tag, x in (("sim", sim), ("rec", rec)):
                vals[tag]["psnr"].append(psnr(gt, x, data_range=1.0))
                vals[tag]["ssim"].append(ssim(gt, x, data_range=1.0))
            if keep is not None and i == keep:
                examples[_depth_key(d)] = (sim, rec)
        metrics[_depth_key(d)] = {
            t: {m: float(np.mean(v)) for m, v in vals[t].items()} for t in vals
        }
    return metrics, examples


def _depth_key(d) -> str:
    """'0.1', '0.2', '10' for depths in m."""
    return f"{float(d):g}"
