"""Joint training of a lens and its decoder, in two stages, with checkpoints.

Stage 1 trains the decoder on every step and the lens's free parameters (``HybridParams``
gated by ``lenses.gates``: the sensor position of the classical lens, the cubic strength
(bounded below, ``lenses.project``) and sensor position of the cubic plate, everything of the
hybrid lens) on every ``lens_every``-th step, with the paper's loss (``losses.edof_loss``).
All three lenses get the same steps, the same lens updates and the same batches. A batch
is ``batch`` tiles of the sensor (random tiles, random scene windows) rendered at two
distinct depths of the 8 training depths.

Only a lens-update step differentiates through the ray tracer (``joint_step``). On the other
steps the PSFs of the batch come from a forward trace of the current lens
(``optics.psfs_nograd``) and only the decoder is differentiated (``net_step``); a lens that
cannot move (no free parameter) takes them from its cached PSF bank, with no tracing at all.
Stage 2 freezes the lens and refines the decoder on PSFs of randomly perturbed copies of it
(``lenses.perturb``: manufacturing and registration errors), one copy per step, with
``L_rec`` alone.

Sensor noise (``optics.add_noise``: shot noise of ``photons`` electrons at the value 1 and
read noise ``read_noise``) is added to the simulations before the decoder sees them. The
Wiener decoders' front end uses each tile's PSF stack (``Decoder.front_kernels``: the
depth-averaged PSF, and for "multiwiener" each depth's) from a bank that is refreshed every
``refresh_every`` steps; checkpoints are written at those steps too
(``Trainer.save``), so a resumed run continues exactly where the saved one was.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import os
import re
import secrets
import time
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from ...io.json_values import write_whole
from ...optics import checks as input_checks
from ...optics.lens import Lens
from .decoder import Decoder
from .lenses import (
    DEPTHS_M,
    SAG_SCALE,
    SPEC,
    HybridParameterization,
    Tolerances,
    apply_gates,
    dioptric_weights,
    gates,
    perturb,
    project,
)
from .losses import edof_loss
from .optics import add_noise, centers, patch_psfs, psf_bank, psfs_nograd, simulate

STAGE2_LR_SCALE = 0.3
"""Stage 2's network learning rate relative to stage 1's."""

EVAL_ONLY = ("eval_pupil",)
"""Config fields that only the evaluation reads: a checkpointed training resumes across them."""

PARAMS_VERSION = 2
"""Version of the ``HybridParams`` units in a checkpoint (2: the curvature as a sag at R, like
the other terms; 1, unmarked: curvature × R). A checkpoint of another version is refused."""

STATE_LAYOUT = 2
"""Layout of the optimizer states in a checkpoint (2: over the raveled parameters,
``optax.flatten``; 1, unmarked: one state per leaf). A checkpoint of another layout is
refused."""

LENS_ONLY = {"cubic_floor": "cubic", "hybrid_floor": "hybrid", "hold_focus": "hybrid"}
"""Config fields that only one lens's training reads: the others resume across them."""


MAX_READ_NOISE = 0.5
"""Largest read noise (a standard deviation in linear values, 1 = full signal): above it
the scene is mostly noise (an option written in electrons lands there)."""

PHOTONS_RANGE = (1.0, 1e12)
"""Accepted photo-electrons at the linear value 1 (``photons``): below one electron at full
signal the shot noise's standard deviation exceeds the signal itself (SNR < 1 at white;
``--photons 1e-300`` trained on noise alone); 10¹², a million times any sensor's full well,
is already noise-free (shot noise 10⁻⁶ at white, under float32's resolution of the values)
and the tests' setting for that; more only risks overflow (1e300 e⁻)."""


def check_noise(read_noise, photons, *, where: str = "edof Config",
                names: tuple[str, str] = ("read_noise", "photons")) -> None:
    """Refuses a noise model that is not physical or not in its units: ``photons`` (photo-
    electrons at the linear value 1) must be in ``PHOTONS_RANGE`` and ``read_noise`` (a standard
    deviation in linear values) in [0, ``MAX_READ_NOISE``]. ``names``: the two as the caller
    writes them (``Config`` fields, or the command line's ``--read-noise``/``--photons``)."""
    read, phot = names
    input_checks.number(photons, phot, where, lo=PHOTONS_RANGE[0], hi=PHOTONS_RANGE[1],
                        unit="photo-electrons at the linear value 1")
    input_checks.number(read_noise, read, where, lo=0)
    if read_noise > MAX_READ_NOISE:  # before: read noise 4 (electrons) trained on noise
        raise ValueError(f"{where}: {read} must be at most {MAX_READ_NOISE:g} (a standard "
                         f"deviation in linear values, 1 = full signal), got "
                         f"{read_noise:g} (was it in electrons? {read_noise:g} e⁻ at "
                         f"{phot} {photons:g} is {read_noise / photons:.3g})")


def config_data(cfg: Config) -> dict:
    """A config as JSON data (tuples as lists), as checkpoints and caches store it."""
    return json.loads(json.dumps(dataclasses.asdict(cfg)))


def training_config(config: dict, lens: str | None = None) -> dict:
    """The part of a config (JSON data) that a lens's training reads: without the
    evaluation-only fields (``EVAL_ONLY``), without the fields of other lenses
    (``LENS_ONLY``; all of them are kept when ``lens`` is None), and with the defaults of
    fields added to ``Config`` after the config was written."""
    defaults = config_data(Config())
    return {k: v for k, v in {**defaults, **config}.items()
            if k not in EVAL_ONLY and (lens is None or LENS_ONLY.get(k, lens) == lens)}


@dataclasses.dataclass(frozen=True)
class Config:
    """Options of the EDoF experiment (defaults: the CPU-scale run).

    Attributes:
        binning: sensor pixel binning of the paper's 1024² sensor of 4.97 µm pixels.
        tile: tile side (pixels): one PSF per tile, and a training patch is one tile.
        kernel_size: PSF kernel side (pixels); light outside it is lost.
        batch: patches per batch (each rendered at two depths).
        pupil: rays per side of the polar pupil grid of a training PSF.
        eval_pupil: the same for the evaluation's PSF banks.
        steps: stage-1 steps (decoder every step, lens every ``lens_every``-th).
        steps2: stage-2 steps (decoder on perturbed lenses).
        lens_every: a lens update every this many stage-1 steps.
        refresh_every: steps between refreshes of the Wiener front end's PSF bank and
            between checkpoints.
        lr_net, lr_lens: Adam learning rates (the lens parameters are sags in units of
            ``lenses.SAG_SCALE``).
        depth_sampling: how a batch draws its two depths of the 8: "uniform" or
            "dioptric" (weights even in dioptres, ``lenses.dioptric_weights``).
        hold_focus: the hybrid lens keeps the classical lens's base curvature and sensor
            position (``lenses.gates`` "hybrid-held-focus").
        w_sim, w_raw: ω1 and ω2 of the loss.
        photons: photo-electrons at the linear value 1 (shot noise); read_noise: read-noise
            standard deviation (linear units).
        decoder: "nafnet", "wiener" or "multiwiener" (``decoder.DECODERS``).
        width, enc_blocks, middle_blocks, dec_blocks: the NAFNet.
        n_odd: odd terms per axis of the hybrid surface (x³, x⁵, …).
        cubic_ratio: the cubic plate's strength, as a multiple of the defocus it hides
            (``lenses.cubic_strength_guess``); the hybrid starts at half of it.
        cubic_floor: lower bound of the cubic plate's strength as a fraction of its start.
        hybrid_floor: lower bound of the hybrid's x³ and y³ terms as a fraction of their
            start (half the cubic plate's); ``None``: unbounded.
        live_front_end: on lens-update steps the Wiener front end's PSFs are the current
            lens's (traced at all 8 depths and differentiated) instead of the bank's.
        lens_accept: a lens update is kept only if it does not raise the reconstruction
            loss (``L_rec``, the updated decoder) on a fixed check batch of training
            windows at all 8 depths with fixed noise (``Trainer.check_loss``).
        real_halo: a training patch is simulated with the Wiener front end's halo (the kernel
            side) of real scene around it, which the front end reads (``pad="valid"``), as
            it reads the neighbouring tiles in a test image; otherwise the halo holds edge
            copies of the patch.
        context: pixels of simulated scene that the decoder also sees on each side of a
            training patch (the loss reads the patch only), as the network sees the rest of
            a test image beyond a tile.
        train_source: the training scenes, one of ``scenes.TRAIN_SOURCES``: "images" (the
            photographs), "dead-leaves" (procedural, ``dead_leaves``) or "mixed".
        crop: side of the test crops (pixels, native resolution).
        seed: random seed.
        log_every: host sync / progress-bar refresh interval (steps).
    """

    binning: int = 2
    tile: int = 32
    kernel_size: int = 31
    batch: int = 8
    pupil: int = 32
    eval_pupil: int = 64
    steps: int = 1200
    steps2: int = 60
    lens_every: int = 4
    refresh_every: int = 50
    lr_net: float = 1e-3
    lr_lens: float = 2e-2
    depth_sampling: str = "uniform"
    hold_focus: bool = False
    w_sim: float = 0.1
    w_raw: float = 0.1
    photons: float = 2000.0
    read_noise: float = 0.002
    decoder: str = "wiener"
    width: int = 16
    enc_blocks: tuple[int, ...] = (1, 1, 1)
    middle_blocks: int = 1
    dec_blocks: tuple[int, ...] = (1, 1, 1)
    n_odd: int = 3
    cubic_ratio: float = 1.5
    cubic_floor: float = 1.0
    hybrid_floor: float | None = None
    live_front_end: bool = False
    lens_accept: bool = False
    real_halo: bool = False
    context: int = 0
    train_source: str = "images"
    crop: int = 256
    seed: int = 0
    log_every: int = 10
    tolerances: Tolerances = dataclasses.field(default_factory=Tolerances)

    def __post_init__(self):
        # Before: only the command line checked the noise; Config(read_noise=4) trained on it.
        check_noise(self.read_noise, self.photons)

    @property
    def front_pad(self) -> str:
        """The Wiener front end's padding of a training patch (``wiener_tiles``' ``pad``)."""
        return "valid" if self.real_halo and self.decoder != "nafnet" else "edge"

    @property
    def patch(self) -> int:
        """Side of a simulated training patch (pixels): the tile, ``context`` on each side and
        (``real_halo``) the front end's halo of k on each side."""
        halo = self.kernel_size if self.front_pad == "valid" else 0
        return self.tile + 2 * (self.context + halo)

    @property
    def window(self) -> int:
        """Side of a training scene window: the patch plus a kernel's margin (pixels)."""
        return self.patch + self.kernel_size - 1

    @property
    def pixel_size(self) -> float:
        """Binned pixel pitch (mm)."""
        return self.binning * SPEC["pixel_size_mm"]

    @property
    def step_config(self) -> StepConfig:
        """What the compiled steps read of this config (their static argument)."""
        return StepConfig(tile=self.tile, kernel_size=self.kernel_size, pupil=self.pupil,
                          photons=self.photons, read_noise=self.read_noise, w_sim=self.w_sim,
                          w_raw=self.w_raw, live_front_end=self.live_front_end,
                          front_pad=self.front_pad)


@dataclasses.dataclass(frozen=True)
class StepConfig:
    """The options that the compiled steps (``joint_step``, ``net_step``, the probe and
    check losses) read: they take this as a static argument instead of the whole
    ``Config``, so runs that differ in seeds, step counts, learning rates, logging or
    evaluation options share one compiled program (in memory, and in the command line's
    compilation cache). A step that read any other option would fail when traced."""

    tile: int
    kernel_size: int
    pupil: int
    photons: float
    read_noise: float
    w_sim: float
    w_raw: float
    live_front_end: bool
    front_pad: str


def net_learning_rate(step: int, steps: int, peak: float) -> float:
    """The network's learning rate at ``step`` of a stage: a linear warm-up from 0 over
    ``min(20, steps // 10)`` steps (at least 1), then a cosine decay to 5 % of ``peak`` at
    ``steps`` (optax's ``warmup_cosine_decay_schedule``, computed on the host: the compiled
    steps take it as an argument, so a run of another length reuses them)."""
    warmup = max(1, min(20, steps // 10))
    if step < warmup:
        return peak * step / warmup
    span = max(steps, warmup + 1) - warmup  # optax needs a decay phase after the warm-up
    cosine = 0.5 * (1.0 + math.cos(math.pi * min(step - warmup, span) / span))
    return peak * (0.95 * cosine + 0.05)


@functools.lru_cache(maxsize=8)
def _optimizers(lr_lens: float):
    # The network's learning rate multiplies its updates in ``_apply`` (a traced argument,
    # ``net_learning_rate``); the unit schedule keeps the optimizer state's layout (its step
    # count is not read). Both optimizers work on the parameters raveled into one vector: per
    # leaf, XLA compiles a handful of tiny kernels for each of the network's ~100 leaves, which
    # took 60 % of the compile time of the smoke run's steps (joint_step 37 -> 22 s, net_step
    # 18 -> 7 s on 2 cores).
    net = optax.chain(optax.clip_by_global_norm(1.0), optax.adam(lambda count: 1.0))
    return optax.flatten(net), optax.flatten(optax.adam(lr_lens))


def optimizers(cfg: Config):
    """(network, lens) optimizers: Adam, the network's gradients clipped to norm 1. Cached
    so that the jitted steps compile once; the network's learning rate is not part of them
    (``net_learning_rate``). Stage 2 restarts the network's state."""
    return _optimizers(float(cfg.lr_lens))


def _centre(x, cfg: StepConfig):
    """The central ``tile × tile`` pixels of ``[..., n, n, C]`` images."""
    m = (x.shape[-2] - cfg.tile) // 2
    return x[..., m: m + cfg.tile, m: m + cfg.tile, :]


def _sim_loss(dec: Decoder, kernels, windows, wkern, key, cfg: StepConfig):
    """The loss of a batch whose PSFs are ``kernels [2, B, 3, k, k]`` and whose front-end
    PSF stacks are ``wkern [K, B, 3, k, k]`` (``Decoder.front_kernels``)."""
    sims = simulate(windows, kernels)
    noisy = add_noise(sims, key, photons=cfg.photons, read=cfg.read_noise)
    per_patch = jax.vmap(lambda x, k: dec(x, k[:, None, None], cfg.front_pad), in_axes=(0, 1))
    recs = jax.vmap(per_patch, in_axes=(0, None))(noisy, wkern)
    return edof_loss(_centre(recs, cfg), _centre(sims, cfg), _centre(windows, cfg),
                     w_sim=cfg.w_sim, w_raw=cfg.w_raw)


def _finite(loss, tree):
    # One reduction over the concatenated leaves: a reduction per leaf compiles a kernel each.
    leaves = [g for g in jax.tree_util.tree_leaves(tree) if eqx.is_inexact_array(g)]
    flat = jnp.concatenate([jnp.ravel(g) for g in leaves])
    return jnp.isfinite(loss) & jnp.all(jnp.isfinite(flat))


def _apply(opt, grads, state, params, ok, scale=1.0):
    """An optimizer step (updates times ``scale``, e.g. the network's learning rate) that
    is skipped (parameters and state kept) where ``ok`` is False."""
    grads = jax.tree_util.tree_map(lambda g: jnp.where(ok, g, 0.0), grads)
    upd, new = opt.update(grads, state, params)
    upd = jax.tree_util.tree_map(lambda u: u * ok * scale, upd)
    state = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b) if eqx.is_array(a) else a,
                                   new, state)
    return eqx.apply_updates(params, upd), state


@eqx.filter_jit
def joint_step(dec, params, net_state, lens_state, pmap, windows, xy, depths, pair, wkern,
               key, gate, tie, floor, lr, *, cfg: StepConfig, net_opt, lens_opt):
    """A lens-update step: the loss is differentiated through the ray tracer.

    ``xy [B, 2]`` are the tiles' centres (mm), ``depths [D]`` the training depths (mm from
    the stop), ``pair [2]`` the indices of the batch's two, ``wkern [K, B, 3, k, k]`` the
    front end's PSF stacks from the bank. With ``cfg.live_front_end`` (and a Wiener
    decoder) the PSFs at all D depths are traced and their stacks replace ``wkern``, so the
    gradient also sees the front end follow the lens. Returns
    ``(dec, params, net_state, lens_state, loss, parts)``; a step whose loss or gradient is not
    finite is skipped and counted in ``parts["skipped"]``.
    """
    b = windows.shape[0]
    k_sim, k_psf = jax.random.split(key)
    live = cfg.live_front_end and dec.wiener
    traced = depths if live else depths[pair]

    def loss_fn(trainable):
        d, p = trainable
        lens = pmap.to_lens(p)
        n = traced.shape[0]
        kern = patch_psfs(lens, jnp.tile(xy, (n, 1)), jnp.repeat(traced, b),
                          kernel_size=cfg.kernel_size, pixel_size=lens.sensor.pixel_size,
                          pupil=cfg.pupil, key=k_psf)
        kern = kern.reshape((n, b) + kern.shape[1:])
        front = d.front_kernels(kern).astype(wkern.dtype) if live else wkern
        return _sim_loss(d, kern[pair] if live else kern, windows, front, k_sim, cfg)

    net_p, net_static = eqx.partition(dec, eqx.is_inexact_array)
    (loss, parts), (g_net, g_lens) = eqx.filter_value_and_grad(loss_fn, has_aux=True)(
        (dec, params))
    g_lens = apply_gates(g_lens, gate, tie)
    ok = _finite(loss, (g_net, g_lens))
    net_p, net_state = _apply(net_opt, eqx.filter(g_net, eqx.is_inexact_array), net_state,
                              net_p, ok, lr)
    lp, lens_static = eqx.partition(params, eqx.is_inexact_array)
    lp, lens_state = _apply(lens_opt, eqx.filter(g_lens, eqx.is_inexact_array), lens_state, lp,
                            ok)
    params = project(eqx.combine(lp, lens_static), floor)
    parts = dict(parts, skipped=1.0 - ok.astype(loss.dtype))
    return eqx.combine(net_p, net_static), params, net_state, lens_state, loss, parts


@eqx.filter_jit
def net_step(dec, net_state, kernels, windows, wkern, key, lr, *, cfg: StepConfig, net_opt):
    """A decoder-only step on given PSFs ``kernels [2, B, 3, k, k]`` (no ray tracing) at
    the learning rate ``lr`` (an array: both stages share the compiled step)."""
    net_p, net_static = eqx.partition(dec, eqx.is_inexact_array)

    def loss_fn(p):
        return _sim_loss(eqx.combine(p, net_static), kernels, windows, wkern, key, cfg)

    (loss, parts), g = eqx.filter_value_and_grad(loss_fn, has_aux=True)(net_p)
    ok = _finite(loss, g)
    net_p, net_state = _apply(net_opt, g, net_state, net_p, ok, lr)
    parts = dict(parts, skipped=1.0 - ok.astype(loss.dtype))
    return eqx.combine(net_p, net_static), net_state, loss, parts


_perturb = eqx.filter_jit(perturb)


@eqx.filter_jit
def _probe_loss(dec, kernels, windows, wkern, key, *, cfg: StepConfig):
    return _sim_loss(dec, kernels, windows, wkern, key, cfg)[0]


@eqx.filter_jit
def _check_rec_loss(dec, kernels, windows, key, *, cfg: StepConfig):
    """``L_rec`` of windows ``[B, ...]`` at every depth of ``kernels [D, B, 3, k, k]`` (D
    even), the front end fed each tile's PSF stack over the D depths."""
    d, b = kernels.shape[:2]
    front = jnp.tile(dec.front_kernels(kernels), (1, d // 2, 1, 1, 1))
    if not dec.wiener:
        front = jnp.zeros(front.shape[:3] + (1, 1), front.dtype)
    pairs = kernels.reshape((2, d // 2 * b) + kernels.shape[2:])
    windows = jnp.tile(windows, (d // 2, 1, 1, 1))
    return _sim_loss(dec, pairs, windows, front, key, cfg)[1]["rec"]


class BatchSource:
    """Host-side batches: scene windows, tile indices and the depth pair."""

    def __init__(self, sampler, n_tiles: tuple[int, int], cfg: Config, seed: int):
        self.sampler = sampler
        self.cfg = cfg
        self.n_tiles = n_tiles
        self.rng = np.random.default_rng(seed)
        if cfg.depth_sampling not in ("uniform", "dioptric"):
            raise ValueError(
                f"depth_sampling must be 'uniform' or 'dioptric', got {cfg.depth_sampling!r}")
        self.weights = dioptric_weights(DEPTHS_M) if cfg.depth_sampling == "dioptric" else None

    def __call__(self):
        """``(windows [B, W, W, 3], tiles [B, 2] (row, col), depth indices [2])``."""
        cfg = self.cfg
        windows = self.sampler.sample(cfg.batch)
        tiles = np.stack([self.rng.integers(0, self.n_tiles[0], cfg.batch),
                          self.rng.integers(0, self.n_tiles[1], cfg.batch)], -1)
        pair = self.rng.choice(len(DEPTHS_M), 2, replace=False, p=self.weights)
        return windows, tiles, pair

    def state(self) -> dict:
        """The random states (JSON), to resume the same stream."""
        return {"source": self.rng.bit_generator.state,
                "sampler": self.sampler.rng.bit_generator.state}

    def set_state(self, s: dict) -> None:
        self.rng.bit_generator.state = s["source"]
        self.sampler.rng.bit_generator.state = s["sampler"]


def _option(field: str) -> str:
    """A ``Config`` field as the command line writes it (the scale's fields: its flag)."""
    named = {"kernel_size": "--kernel", "enc_blocks": "--enc", "dec_blocks": "--dec",
             "middle_blocks": "--middle"}
    if field in named:
        return named[field]
    if field in ("crop", "refresh_every", "log_every", "cubic_ratio", "seed", "tolerances"):
        return f"{field} (set by --smoke or --paper)"
    return "--" + field.replace("_", "-")


def check_resumable(meta: str, info: dict, cfg: Config, name: str) -> int:
    """Refuses a checkpoint (``meta``, its data ``info``) that ``cfg`` cannot continue: a
    training option that differs (each named, with the checkpoint's value and this run's)
    or fewer ``steps2`` than the checkpoint has done. Returns the stage-2 steps done.
    Called by ``Trainer.load`` and, before any work, by the command line's ``--resume``."""
    saved = training_config(info["config"], name)
    current = dict(training_config(config_data(cfg), name), steps2=saved["steps2"])
    if saved != current:
        # Before: "written with another configuration", after the scenes and the lens set-up.
        diff = "; ".join(f"{_option(k)} {json.dumps(saved.get(k))} there, "
                         f"{json.dumps(current.get(k))} here"
                         for k in sorted(set(saved) | set(current))
                         if saved.get(k) != current.get(k))
        raise ValueError(f"resume: the checkpoint {meta} of the {name} lens was written with "
                         f"other training options ({diff}); use the same options, or another "
                         f"--checkpoint")
    stage, step = info["stage"], info["step"]
    done2 = saved["steps2"] if stage == 3 else step if stage == 2 else 0
    if done2 > cfg.steps2:
        raise ValueError(f"resume: the checkpoint {meta} has {done2} stage-2 steps, "
                         f"more than --steps2 {cfg.steps2}; use --steps2 "
                         f">= {done2}, or another --checkpoint")
    return done2


class OutOfTime(Exception):
    """Raised when a time limit stops training at a checkpoint."""


@dataclasses.dataclass
class Trainer:
    """Trains one lens and its decoder (``run``), with checkpoints in ``folder``.

    Attributes:
        name: "classical", "cubic" or "hybrid" (also the ``gates`` kind).
        pmap: the lens's ``HybridParameterization`` (its template: the starting lens).
        params: the starting ``HybridParams``.
        dec: the decoder.
        source: the batch stream.
        cfg: the configuration.
        key: PRNG key of the run.
        floor: lower bound of the cubic strength (scaled units; ``-inf`` for none).
        folder: checkpoint folder (None: no checkpoints).
        deadline: ``time.time()`` after which training stops at the next checkpoint.
    """

    name: str
    pmap: HybridParameterization
    params: object
    dec: Decoder
    source: BatchSource
    cfg: Config
    key: jax.Array
    floor: float = -math.inf
    folder: str | None = None
    deadline: float | None = None

    def __post_init__(self):
        cfg = self.cfg
        opt1, lens_opt = optimizers(cfg)
        kind = "hybrid-held-focus" if self.name == "hybrid" and cfg.hold_focus else self.name
        self.gate, self.tie = gates(self.params, kind)
        self.movable = any(float(jnp.sum(jnp.abs(g))) > 0
                           for g in jax.tree_util.tree_leaves(self.gate))
        self.stage, self.step = 1, 0
        self.net_state = opt1.init(eqx.filter(self.dec, eqx.is_inexact_array))
        self.lens_state = lens_opt.init(eqx.filter(self.params, eqx.is_inexact_array))
        self.hist: dict[str, list] = {"stage1": [], "stage2": []}
        self.xy = centers(self.pmap.template, cfg.tile)
        self.bank = None  # [8, ty, tx, 3, k, k] of the current lens, when one is needed
        self.front_bank = None  # [K, ty, tx, 3, k, k]: the front end's PSF stacks
        self.seconds = 0.0
        self._check = None  # the fixed check batch of ``check_loss``, made on first use

    # -- checkpoints ---------------------------------------------------------------------
    def _meta_path(self) -> str:
        return os.path.join(self.folder, f"{self.name}.json")

    def save(self) -> None:
        """Write the state (a finished lens, or one in progress) to ``folder``.

        The arrays go to a new ``<name>.<token>.eqx`` first; replacing ``<name>.json``, which
        names that file, is the one step that commits the checkpoint. (Two renames, the
        ``.eqx`` and then the ``.json``, left a new ``.eqx`` beside the old ``.json`` when
        stopped between them, and ``--resume`` took the new weights at the old step.)
        """
        if self.folder is None:
            return
        os.makedirs(self.folder, exist_ok=True)
        tree_name = f"{self.name}.{secrets.token_hex(4)}.eqx"
        eqx.tree_serialise_leaves(os.path.join(self.folder, tree_name),
                                  (self.dec, self.params, self.net_state, self.lens_state,
                                   self.key))
        info = {"stage": self.stage, "step": self.step, "hist": self.hist,
                "rng": self.source.state(), "seconds": self.seconds,
                "config": dataclasses.asdict(self.cfg), "params_version": PARAMS_VERSION,
                "state_layout": STATE_LAYOUT, "tree": tree_name}
        write_whole(self._meta_path(), json.dumps(info))
        # Earlier checkpoints' arrays (and those of a save stopped before its commit).
        stale = re.compile(rf"{re.escape(self.name)}(\.[0-9a-f]{{8}})?\.eqx")
        for f in os.listdir(self.folder):
            if f != tree_name and stale.fullmatch(f):
                os.remove(os.path.join(self.folder, f))

    def load(self) -> bool:
        """Resume from ``folder`` if it holds this lens; returns whether it did."""
        if self.folder is None:
            return False
        meta = self._meta_path()
        if not os.path.isfile(meta):
            return False
        with open(meta) as f:
            info = json.load(f)
        # Checkpoints written before the .json named its arrays kept them in <name>.eqx.
        tree = os.path.join(self.folder, info.get("tree", f"{self.name}.eqx"))
        if not os.path.isfile(tree):
            raise ValueError(f"resume: the checkpoint {meta} names its arrays "
                             f"{os.path.basename(tree)}, which is not in {self.folder}; use "
                             f"another --checkpoint")
        version = info.get("params_version", 1)
        # Version 1 wrote c as c·R; a lens that never trains c converts exactly.
        convertible = version == 1 and float(jnp.sum(jnp.abs(self.gate.c))) == 0
        if version != PARAMS_VERSION and not convertible:
            raise ValueError(f"resume: the checkpoint {meta} stores its lens parameters in "
                             f"the units of version {version}, this code reads version "
                             f"{PARAMS_VERSION}; use another --checkpoint")
        layout = info.get("state_layout", 1)
        if layout != STATE_LAYOUT:
            raise ValueError(f"resume: the checkpoint {meta} stores its optimizer states in "
                             f"layout {layout} (one per parameter leaf), this code reads "
                             f"layout {STATE_LAYOUT} (raveled parameters); use another "
                             f"--checkpoint")
        done2 = check_resumable(meta, info, self.cfg, self.name)
        self.stage, self.step = info["stage"], info["step"]
        # A longer stage 2 extends a lens exactly (its schedule does not depend on steps2);
        # a finished lens goes back into stage 2 where it stopped.
        if self.stage == 3 and done2 < self.cfg.steps2:
            self.stage, self.step = 2, done2
            info["hist"].get("probe", {}).pop("after", None)
        like = (self.dec, self.params, self.net_state, self.lens_state, self.key)
        self.dec, self.params, self.net_state, self.lens_state, self.key = \
            eqx.tree_deserialise_leaves(tree, like)
        if version == 1:
            r = self.pmap.radius.astype(self.params.c.dtype)
            self.params = eqx.tree_at(lambda p: p.c, self.params,
                                      self.params.c * r / (2 * SAG_SCALE))
        self.hist, self.seconds = info["hist"], info["seconds"]
        self.source.set_state(info["rng"])
        return True

    @property
    def done(self) -> bool:
        return self.stage == 3

    # -- training ------------------------------------------------------------------------
    def lens(self) -> Lens:
        return self.pmap.to_lens(self.params)

    def _banks(self, lens, *, full: bool):
        cfg = self.cfg
        bank = psf_bank(lens, tile=cfg.tile, kernel_size=cfg.kernel_size, pupil=cfg.pupil,
                        chunk=2 * cfg.batch)
        dt = self.pmap.template.epd.dtype
        self.front_bank = jnp.asarray(self.dec.front_kernels(bank), dt)
        self.bank = jnp.asarray(bank, dt) if full else None

    def _wkern(self, tiles):
        if not self.dec.wiener:
            return jnp.zeros((1, len(tiles), 3, 1, 1), self.pmap.template.epd.dtype)
        return self.front_bank[:, tiles[:, 0], tiles[:, 1]]

    def _fixed_batch(self, seed: int):
        """Scene windows, tile indices and tile centres (mm) of a fixed batch drawn from its
        own random stream ``seed`` (the same batch on every call and after a resume)."""
        from .scenes import PatchSampler

        cfg = self.cfg
        dt = self.pmap.template.epd.dtype
        rng = np.random.default_rng(seed)
        windows = PatchSampler(self.source.sampler.images, cfg.window, seed=seed,
                               weights=self.source.sampler.p).sample(cfg.batch)
        tiles = np.stack([rng.integers(0, n, cfg.batch) for n in self.xy.shape[:2]], -1)
        return (jnp.asarray(windows, dt), tiles,
                jnp.asarray(self.xy[tiles[:, 0], tiles[:, 1]], dt))

    def _depth_psfs(self, lens, xy, depths):
        """Forward-traced PSFs ``[D, B, 3, k, k]`` at tile centres ``xy [B, 2]`` for every
        object depth of ``depths [D]`` (mm from the stop)."""
        cfg = self.cfg
        n, b = depths.shape[0], xy.shape[0]
        kern = psfs_nograd(lens, jnp.tile(xy, (n, 1)), jnp.repeat(depths, b),
                           jnp.asarray(lens.sensor.pixel_size, xy.dtype),
                           kernel_size=cfg.kernel_size, pupil=cfg.pupil)
        return kern.reshape((n, b) + kern.shape[1:])

    def probe(self) -> float:
        """The loss of the current lens and decoder on a fixed batch (its own random stream:
        scene windows, tiles, the depths 10 cm and 10 m, noise), recorded before and after
        training as ``hist["probe"]``: a measure of learning free of batch-to-batch noise."""
        windows, tiles, xy = self._fixed_batch(4242)
        depths = jnp.asarray([1e3 * DEPTHS_M[0], 1e3 * DEPTHS_M[-1]], xy.dtype)
        lens = self.lens()
        kern = self._depth_psfs(lens, xy, depths)
        if self.dec.wiener:
            self._banks(lens, full=False)
        loss = _probe_loss(self.dec, kern, windows, self._wkern(tiles),
                           jax.random.PRNGKey(4242), cfg=self.cfg.step_config)
        return float(loss)

    def check_loss(self, params) -> float:
        """``L_rec`` of the lens ``params`` with the current decoder on the fixed check batch
        (``Config.lens_accept``): its own random stream of training windows and tiles, all
        8 depths, fixed noise."""
        if self._check is None:
            windows, _, xy = self._fixed_batch(777)
            self._check = (windows, xy)
        windows, xy = self._check
        depths = jnp.asarray(1e3 * np.asarray(DEPTHS_M), xy.dtype)
        kern = self._depth_psfs(self.pmap.to_lens(params), xy, depths)
        return float(_check_rec_loss(self.dec, kern, windows, jax.random.PRNGKey(777),
                                     cfg=self.cfg.step_config))

    def run(self, progress: Callable | None = None):
        """Train to the end (or to the deadline: ``OutOfTime`` after a checkpoint)."""
        cfg = self.cfg
        if "probe" not in self.hist:
            self.hist["probe"] = {"before": self.probe()}
            self.front_bank = None  # the training's own refresh schedule
        opt1, lens_opt = optimizers(cfg)
        dt = self.pmap.template.epd.dtype
        depths = jnp.asarray(1e3 * np.asarray(DEPTHS_M), dt)
        total = cfg.steps + cfg.steps2
        bar = progress(total=total, desc=self.name) if progress else None
        if bar is not None:
            bar.update(self.step + (cfg.steps if self.stage == 2 else 0))
        acc = []
        floor = jnp.asarray(self.floor, dt)
        while self.stage < 3:
            steps = cfg.steps if self.stage == 1 else cfg.steps2
            if self.step >= steps:
                self.stage, self.step = self.stage + 1, 0
                if self.stage == 2:
                    self.net_state = opt1.init(eqx.filter(self.dec, eqx.is_inexact_array))
                continue
            t0 = time.perf_counter()
            lens = self.lens()
            frozen = self.stage == 2 or not self.movable
            if self.step % cfg.refresh_every == 0 or self.front_bank is None:
                if self.step % cfg.refresh_every == 0 and self.step > 0:
                    self.save()
                    if self.deadline is not None and time.time() > self.deadline:
                        raise OutOfTime(f"{self.name}: stopped at stage {self.stage} step "
                                        f"{self.step}")
                if self.dec.wiener or (frozen and self.stage == 1):
                    # In stage 2 the bank only feeds the front end: the PSFs are perturbed.
                    self._banks(lens, full=frozen and self.stage == 1)
            self.key, sub = jax.random.split(self.key)
            windows, tiles, pair = self.source()
            windows = jnp.asarray(windows, dt)
            wk = self._wkern(tiles)
            xy = jnp.asarray(self.xy[tiles[:, 0], tiles[:, 1]], dt)
            peak = cfg.lr_net * (1.0 if self.stage == 1 else STAGE2_LR_SCALE)
            # Stage 2 restarts the schedule, which keeps the stage-1 length.
            lr = jnp.asarray(net_learning_rate(self.step, cfg.steps, peak), dt)
            if self.stage == 1 and self.movable and self.step % cfg.lens_every == 0:
                before = (self.params, self.lens_state)
                self.dec, self.params, self.net_state, self.lens_state, loss, parts = joint_step(
                    self.dec, self.params, self.net_state, self.lens_state, self.pmap,
                    windows, xy, depths, jnp.asarray(pair), wk, sub, self.gate, self.tie, floor,
                    lr, cfg=cfg.step_config, net_opt=opt1, lens_opt=lens_opt)
                if cfg.lens_accept:
                    kept = self.check_loss(self.params) <= self.check_loss(before[0])
                    if not kept:
                        self.params, self.lens_state = before
                    counts = self.hist.setdefault("lens_steps", {"kept": 0, "undone": 0})
                    counts["kept" if kept else "undone"] += 1
            else:
                if self.stage == 1 and frozen:
                    kern = self.bank[pair][:, tiles[:, 0], tiles[:, 1]]
                else:
                    k_pert, sub = jax.random.split(sub)
                    src = lens if self.stage == 1 else _perturb(lens, k_pert, cfg.tolerances)
                    kern = self._depth_psfs(src, xy, depths[pair])
                self.dec, self.net_state, loss, parts = net_step(
                    self.dec, self.net_state, kern, windows, wk, sub, lr,
                    cfg=cfg.step_config, net_opt=opt1)
            acc.append((loss, parts))
            self.step += 1
            if self.step % cfg.log_every == 0 or self.step == steps:
                self._log(acc, steps)
                if bar is not None:
                    last = self.hist[f"stage{self.stage}"][-1]
                    bar.set_postfix(stage=self.stage, loss=f"{last['loss']:.4f}")
                    bar.update(len(acc))
                acc = []
            self.seconds += time.perf_counter() - t0
        if bar is not None:
            bar.close()
        if "after" not in self.hist["probe"]:
            self.hist["probe"]["after"] = self.probe()
        self.save()
        return self.dec, self.params, self.hist

    def _log(self, acc, steps):
        vals = jax.device_get(acc)
        # Training seconds so far (this lens, all pieces of a resumed run): the step rate.
        rec = {"step": self.step, "loss": float(np.mean([v[0] for v in vals])),
               "seconds": round(self.seconds, 2)}
        for k in ("rec", "sim", "raw"):
            rec[k] = float(np.mean([v[1][k] for v in vals]))
        rec["skipped"] = int(round(sum(float(v[1]["skipped"]) for v in vals)))
        if not math.isfinite(rec["loss"]):
            raise FloatingPointError(f"train[{self.name}]: non-finite loss at stage "
                                     f"{self.stage} step {self.step}")
        self.hist[f"stage{self.stage}"].append(rec)
