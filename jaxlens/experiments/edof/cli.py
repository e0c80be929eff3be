"""End-to-end EDoF computational lens: hybrid odd-polynomial surface + reconstruction network.

``python -m jaxlens.experiments.edof`` reproduces, at CPU scale, the paper's second result
(Yang, Fu & Heidrich, Nat. Commun. 2024): a large-aperture (F/2.1), wide-field (68.8°)
cellphone-style lens whose first surface becomes a hybrid surface (even asphere plus odd
polynomial terms), trained jointly with a decoder so that images are restored from 10 cm to
10 m, against the classical lens (focused at 20 cm, its sensor position trainable) and a
cubic phase plate at the aperture (its strength bounded below, its sensor position
trainable). All three get the same decoder, batches, steps and lens updates.

Image formation goes through ``jaxlens.imaging`` (``edof.optics``): PSFs normalised by the
light entering the entrance pupil, one per 32-pixel tile (16 × 16 per frame), shot and read
noise. For every seed and lens it trains (``edof.train``), then scores the raw image, the
reconstruction and a Wiener-deconvolution reference on held-out native-resolution test
crops at 10 cm, 20 cm and 10 m (``edof.evaluate``).

Outputs (``--out``, default ``runs/edof``): ``table2.json`` / ``table2.md`` (the schema of
issue 10), ``table2_per_image.json`` (every crop's numbers), ``summary.json`` (config,
timings, histories, PSF measures), ``command.txt``, the trained lenses
(``lenses/<name>_s<seed>.json``), decoders (``nets/<name>_s<seed>.eqx``) and figures.
``--record DIR`` copies tables, summary and figures there (the committed copy is
``experiments/edof``).

Defaults are the CPU scale (2× binned 512² sensor of 9.94 µm pixels, so a 256² test crop
fills a quarter of the frame and the defocus blur is half its full-resolution width in
pixels; 31² PSF kernels; a 16-wide NAFNet behind a Wiener front end (``--decoder``:
``edof.decoder``); 1200 + 60 steps per lens; one seed); ``--seeds 0,1,2`` gives the 3-seed
table. ``--paper`` selects the paper's scale for a GPU; with ``--checkpoint DIR`` a run saves its
state every ``refresh_every`` steps, ``--time-limit S`` stops it at the first checkpoint
after S seconds (exit status 3) and ``--resume`` continues it, so it can go in pieces.
A resumed lens may get a longer ``--steps2`` (its stage 2 goes on where it stopped, as in
one run with the longer stage); any other training option must stay the same.
``--smoke`` is a seconds-scale run for tests.

Examples:
    python -m jaxlens.experiments.edof
    python -m jaxlens.experiments.edof --seeds 0,1,2 --out runs/edof3
    python -m jaxlens.experiments.edof --paper --checkpoint ck --time-limit 540 --out runs/p
    python -m jaxlens.experiments.edof --paper --checkpoint ck --resume --out runs/p
    python -m jaxlens.experiments.edof --smoke --out /tmp/edof_smoke
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import shlex
import shutil
import sys
import time

from jaxlens.experiments.edof.report import (
    base_lens_data,
    checks,
    table2,
    table2_markdown,
    write_figures,
)
from jaxlens.experiments.runfolder import (
    OneLineParser,
    RunFolder,
    UsageError,
    check_writable,
    comma_ints,
    fail,
    refuse_inside_out,
)
from jaxlens.io.json_values import write_whole
from jaxlens.optics import checks as input_checks

LENS_NAMES = ("classical", "cubic", "hybrid")
MAX_LEARNING_RATE = 1.0
"""Largest ``--lr-net``/``--lr-lens`` (Adam's step size: see ``config_from_args``)."""
MAX_LOSS_WEIGHT = 1000.0
"""Largest ``--w-sim``/``--w-raw`` (ω1, ω2; 0.1 by default): above it the auxiliary terms
outweigh the image loss a thousandfold and the decoder no longer learns to restore images
(1e300 overflowed the float32 loss to inf)."""
MAX_BATCH = 1024  # patches per batch (8 by default): each holds the tile's PSFs and features
MAX_BLOCKS = 64  # NAFNet blocks per level or in the middle (the paper's deepest level has 28)
MAX_LEVELS = 6  # NAFNet levels (the paper's 4); each doubles the channels
MAX_ODD_TERMS = 10  # the hybrid surface's odd terms per axis: x³, x⁵, …, x²¹
OUT_OF_TIME = 3
"""Exit status of a run stopped by ``--time-limit`` at a checkpoint."""
COMPILE_CACHE = "compile_cache"
"""Folder in ``--checkpoint`` where JAX keeps compiled programs for the resumed pieces."""


def _ints(text: str) -> tuple[int, ...]:
    """``--seeds``: comma-separated whole numbers (an empty entry was dropped: "0,,1" ran
    seeds 0 and 1, a seed typed between them lost)."""
    try:  # ASCII digits only (str.isdigit took "١" and int() read it as 1)
        return comma_ints(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated whole numbers without an "
                                         f"empty one, got {text!r} (ASCII digits)") from None


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="python -m jaxlens.experiments.edof",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default="runs/edof", help="output folder (default runs/edof)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an earlier run in --out and in --record (default: refuse)")
    p.add_argument("--record", default=None,
                   help="also copy tables, summary and figures to this folder (refused where "
                        "an earlier run's are, unless --overwrite)")
    p.add_argument("--lenses", default=",".join(LENS_NAMES),
                   help="lenses to train, from classical,cubic,hybrid")
    p.add_argument("--seeds", type=_ints, default=(0,), help="training seeds, e.g. 0,1,2 (0)")
    scale = p.add_mutually_exclusive_group()
    scale.add_argument("--smoke", action="store_true", help="tiny, seconds-scale run (tests)")
    scale.add_argument("--paper", action="store_true", help="the paper's scale (GPU)")
    p.add_argument("--checkpoint", default=None, help="folder for checkpoints (none)")
    p.add_argument("--resume", action="store_true", help="continue from --checkpoint")
    p.add_argument("--time-limit", type=input_checks.cli_float, default=None,
                   help="stop at the first checkpoint after this many seconds (exit 3)")
    g = p.add_argument_group("training (defaults: CPU scale)")
    g.add_argument("--decoder", choices=("nafnet", "wiener", "multiwiener"),
                   help="NAFNet alone, or behind a Wiener front end with the depth-averaged "
                   "PSF (wiener) or with it and each depth's PSF (multiwiener) (wiener)")
    g.add_argument("--steps", type=input_checks.cli_int, help="stage-1 steps per lens (1200)")
    g.add_argument("--steps2", type=input_checks.cli_int,
                   help="stage-2 steps per lens (60); may grow on --resume")
    g.add_argument("--batch", type=input_checks.cli_int, help="patches per batch (8)")
    g.add_argument("--tile", type=input_checks.cli_int, help="tile and patch side, pixels (32)")
    g.add_argument("--kernel", type=input_checks.cli_int, help="PSF kernel side, pixels (31)")
    g.add_argument("--binning", type=input_checks.cli_int,
                   help="sensor binning of the 1024² sensor (2)")
    g.add_argument("--pupil", type=input_checks.cli_int,
                   help="pupil rays per side of a training PSF (32)")
    g.add_argument("--eval-pupil", type=input_checks.cli_int,
                   help="pupil rays per side at evaluation (64)")
    g.add_argument("--lens-every", type=input_checks.cli_int,
                   help="a lens update every N steps (4)")
    g.add_argument("--lr-net", type=input_checks.cli_float, help="network learning rate (1e-3)")
    g.add_argument("--lr-lens", type=input_checks.cli_float,
                   help="lens learning rate, scaled units (2e-2)")
    g.add_argument("--depth-sampling", choices=("uniform", "dioptric"),
                   help="how a batch draws its 2 of the 8 training depths (uniform)")
    g.add_argument("--hold-focus", action=argparse.BooleanOptionalAction,
                   help="the hybrid keeps the classical lens's base curvature and sensor "
                   "position (off)")
    g.add_argument("--w-sim", type=input_checks.cli_float, help="ω1, weight of L_sim (0.1)")
    g.add_argument("--w-raw", type=input_checks.cli_float, help="ω2, weight of L_raw (0.1)")
    g.add_argument("--photons", type=input_checks.cli_float,
                   help="photo-electrons at the value 1 (2000)")
    g.add_argument("--read-noise", type=input_checks.cli_float,
                   help="read-noise standard deviation (0.002)")
    g.add_argument("--width", type=input_checks.cli_int, help="NAFNet width (16)")
    g.add_argument("--enc", type=_ints, help="NAFNet encoder blocks per level (1,1,1)")
    g.add_argument("--middle", type=input_checks.cli_int, help="NAFNet middle blocks (1)")
    g.add_argument("--dec", type=_ints, help="NAFNet decoder blocks per level (1,1,1)")
    g.add_argument("--n-odd", type=input_checks.cli_int,
                   help="odd terms per axis of the hybrid surface (3)")
    g.add_argument("--cubic-floor", type=input_checks.cli_float,
                   help="lower bound of the cubic strength, fraction of its start in [0, 1] "
                   "(1)")
    g.add_argument("--hybrid-floor", type=input_checks.cli_float,
                   help="lower bound of the hybrid's x³ and y³ terms, fraction of their "
                   "start in [0, 1] (none)")
    g.add_argument("--live-front-end", action=argparse.BooleanOptionalAction,
                   help="lens-update steps differentiate the Wiener front end's PSFs too "
                   "(all 8 depths traced; off)")
    g.add_argument("--lens-accept", action=argparse.BooleanOptionalAction,
                   help="keep a lens update only if L_rec on a fixed check batch (8 depths) "
                   "does not rise (off)")
    g.add_argument("--real-halo", action=argparse.BooleanOptionalAction,
                   help="training patches carry the Wiener front end's halo of real scene (off)")
    g.add_argument("--context", type=input_checks.cli_int,
                   help="scene pixels the decoder sees around a patch (0)")
    d = p.add_argument_group("data")
    d.add_argument("--train-dir", default=None,
                   help="folder of training images (default: skimage.data; see edof.scenes)")
    d.add_argument("--train-source", choices=("images", "dead-leaves", "mixed"), default=None,
                   help="training scenes: the photographs (images), procedural dead-leaves "
                   "images in their place, or both, half the windows from each (images; see "
                   "edof.dead_leaves)")
    d.add_argument("--test-dir", default=None, help="folder of held-out test images")
    d.add_argument("--validation", action="store_true",
                   help="score the validation images instead of the test images")
    d.add_argument("--max-crops", type=input_checks.cli_int,
                   default=None, help="use only the first N crops")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    return p


def config_from_args(a):
    from jaxlens.experiments.edof.train import Config, check_noise
    from jaxlens.nets import MAX_WIDTH

    if a.paper:
        cfg = Config(binning=1, tile=128, kernel_size=81, batch=8, pupil=64, eval_pupil=96,
                     steps=20000, steps2=5000, lens_every=4, refresh_every=250, width=32,
                     enc_blocks=(1, 1, 1, 28), middle_blocks=1, dec_blocks=(1, 1, 1, 1),
                     log_every=50, crop=256)
    elif a.smoke:
        cfg = Config(binning=16, tile=16, kernel_size=9, batch=2, pupil=8, eval_pupil=8,
                     steps=60, steps2=2, lens_every=4, refresh_every=20, width=4,
                     enc_blocks=(1,), middle_blocks=1, dec_blocks=(1,), lr_net=5e-3,
                     log_every=10, crop=32, decoder="nafnet", photons=100.0)
    else:
        cfg = Config()
    over = {
        "decoder": a.decoder, "steps": a.steps, "steps2": a.steps2, "batch": a.batch,
        "tile": a.tile, "kernel_size": a.kernel, "binning": a.binning, "pupil": a.pupil,
        "eval_pupil": a.eval_pupil, "lens_every": a.lens_every, "lr_net": a.lr_net,
        "lr_lens": a.lr_lens, "depth_sampling": a.depth_sampling, "hold_focus": a.hold_focus,
        "w_sim": a.w_sim, "w_raw": a.w_raw, "photons": a.photons, "read_noise": a.read_noise,
        "width": a.width, "enc_blocks": a.enc, "middle_blocks": a.middle,
        "dec_blocks": a.dec, "n_odd": a.n_odd, "cubic_floor": a.cubic_floor,
        "hybrid_floor": a.hybrid_floor, "live_front_end": a.live_front_end,
        "lens_accept": a.lens_accept, "real_halo": a.real_halo, "context": a.context,
        "train_source": a.train_source,
    }
    # The noise is checked first, in the options' names (Config checks it again, in its own).
    check_noise(cfg.read_noise if a.read_noise is None else a.read_noise,
                cfg.photons if a.photons is None else a.photons, where="edof",
                names=("--read-noise", "--photons"))
    cfg = dataclasses.replace(cfg, **{k: v for k, v in over.items() if v is not None})
    n, w = input_checks.number, "edof"
    # Upper bounds too (before: --steps 10**12 ran for ever, --pupil 10**5 and --batch 10**9
    # ran out of memory after the lens work, and --n-odd 0 dropped the cubic term silently).
    steps, side, pupil = input_checks.MAX_STEPS, input_checks.MAX_IMAGE_SIDE, math.isqrt(
        input_checks.MAX_PUPIL_POINTS)
    for opt, v, lo, hi, unit in (
            ("--steps", cfg.steps, 1, steps, "steps"), ("--steps2", cfg.steps2, 0, steps, "steps"),
            ("--lens-every", cfg.lens_every, 1, steps, "steps"),
            ("--batch", cfg.batch, 1, MAX_BATCH, "patches"),
            ("--tile", cfg.tile, 1, side, "pixels"),
            ("--kernel", cfg.kernel_size, 1, input_checks.MAX_KERNEL_SIZE, "pixels"),
            ("--binning", cfg.binning, 1, 1024, "sensor pixels per side of a binned pixel"),
            ("--width", cfg.width, 1, MAX_WIDTH, "channels"),
            ("--middle", cfg.middle_blocks, 0, MAX_BLOCKS, "blocks"),
            ("--n-odd", cfg.n_odd, 1, MAX_ODD_TERMS, "odd terms per axis, x³ to x²¹"),
            ("--context", cfg.context, 0, side, "pixels"),
            ("--pupil", cfg.pupil, 2, pupil, "rays per side"),
            ("--eval-pupil", cfg.eval_pupil, 2, pupil, "rays per side"),
            ("--seeds count", len(a.seeds), 1, input_checks.MAX_DESIGNS, "training runs")):
        n(v, opt, w, lo=lo, hi=hi, integer=True, unit=unit)
    from jaxlens.design.init import MAX_SEED  # the design package, for its limit only

    for s in a.seeds:
        n(s, "--seeds", w, lo=0, integer=True)
        if s > MAX_SEED:  # PRNGKey: 2**32 was seed 0 again in float32, 2**63 overflowed
            raise ValueError(f"edof: --seeds must be whole numbers in [0, {MAX_SEED}] (seeds "
                             f"of JAX's PRNG), got {s}")
    if not a.seeds or len(set(a.seeds)) < len(a.seeds):  # a repeat would count twice
        raise ValueError(f"edof: --seeds needs distinct seeds, got {a.seeds}")
    # Adam moves each parameter by about the learning rate a step: above 1 (the scale of the
    # NAFNet's weights, and of the lens's sags in lenses.SAG_SCALE units) it diverges
    # (--lr-net 1e300 gave NaN weights after the lens work).
    n(cfg.lr_net, "--lr-net", w, lo=0, hi=MAX_LEARNING_RATE, lo_open=True,
      unit="(Adam step size)")
    n(cfg.lr_lens, "--lr-lens", w, lo=0, hi=MAX_LEARNING_RATE, lo_open=True,
      unit="(Adam step size, sags in lenses.SAG_SCALE units)")
    # A floor is a fraction of the start strength in [0, 1]: above 1 the first projection
    # (lenses.project) raised the strength past its start, which --cubic-floor 2 did silently.
    n(cfg.cubic_floor, "--cubic-floor", w, lo=0, hi=1, unit="(fraction of the start strength)")
    if cfg.live_front_end and cfg.decoder == "nafnet":
        raise ValueError("edof: --live-front-end needs a Wiener front end (--decoder wiener "
                         "or multiwiener), got --decoder nafnet")
    if cfg.real_halo and cfg.decoder == "nafnet":  # before: dropped (Config.front_pad)
        raise ValueError("edof: --real-halo gives the Wiener front end its halo of real scene; "
                         "it needs a front end (--decoder wiener or multiwiener), got --decoder "
                         "nafnet" + (" (the --smoke default)" if a.decoder is None else ""))
    if cfg.hybrid_floor is not None:
        n(cfg.hybrid_floor, "--hybrid-floor", w, lo=0, hi=1,
          unit="(fraction of the start strength)")
    for opt, v in (("--w-sim", cfg.w_sim), ("--w-raw", cfg.w_raw)):
        n(v, opt, w, lo=0, hi=MAX_LOSS_WEIGHT, unit="(weight relative to the image loss)")
    for opt, blocks in (("--enc", cfg.enc_blocks), ("--dec", cfg.dec_blocks)):
        # Each level doubles the channels: 20 levels asked for 4 GiB weights of one layer.
        if (not blocks or len(blocks) > MAX_LEVELS
                or any(not 0 <= b <= MAX_BLOCKS for b in blocks)):
            raise ValueError(f"edof: {opt} must be 1 to {MAX_LEVELS} comma-separated whole "
                             f"numbers in [0, {MAX_BLOCKS}] (blocks per level), got {blocks!r}")
    if 1024 % cfg.binning:
        raise ValueError(f"edof: --binning must divide the 1024-pixel sensor side, got "
                         f"{cfg.binning}")
    side = 1024 // cfg.binning
    if cfg.crop > side:  # before: blamed --tile ("must divide the 1-pixel frame")
        raise ValueError(f"edof: --binning must leave a frame of at least one "
                         f"{cfg.crop}-pixel test crop (1024 / --binning >= {cfg.crop}, so "
                         f"--binning <= {1024 // cfg.crop}), got {cfg.binning}")
    if cfg.lens_every > cfg.steps:  # before: one lens update (step 0), without a word
        raise ValueError(f"edof: --lens-every must be at most --steps {cfg.steps} steps (a "
                         f"lens update every N stage-1 steps; more leaves one update, at "
                         f"step 0), got {cfg.lens_every}")
    if side % cfg.tile or cfg.crop % cfg.tile or cfg.crop > side:
        raise ValueError(f"edof: --tile must divide the {side}-pixel frame and the "
                         f"{cfg.crop}-pixel test crops, got {cfg.tile}")
    if cfg.kernel_size % 2 == 0:
        raise ValueError(f"edof: --kernel must be an odd whole number >= 1 pixels, got "
                         f"{cfg.kernel_size}")
    if cfg.kernel_size > side:  # before: 1001 (binning 2) went on to PSF banks of 1001² each
        raise ValueError(f"edof: --kernel must be at most the {side}-pixel frame side "
                         f"(1024 / --binning {cfg.binning}), got {cfg.kernel_size}")
    if len(cfg.enc_blocks) != len(cfg.dec_blocks):
        raise ValueError("edof: --enc and --dec need the same number of levels")
    return cfg


def check_args(a):
    """The configuration, the lens names and the run folder of valid options.

    Raises:
        UsageError: For an option out of range or an unusable ``--out`` (nothing has been
            computed or written yet).
    """
    try:
        cfg = config_from_args(a)
        names = tuple(n.strip() for n in a.lenses.split(",") if n.strip())
        bad = [n for n in names if n not in LENS_NAMES]
        if bad or not names or len(set(names)) < len(names):
            raise ValueError(f"edof: --lenses takes distinct names from {LENS_NAMES}, got "
                             f"{a.lenses!r}")
        # An option of a lens not trained was dropped without a word (LENS_ONLY's rule).
        unused = [f"{opt} (the {lens} lens's)" for opt, lens, v in (
            ("--cubic-floor", "cubic", a.cubic_floor), ("--hybrid-floor", "hybrid",
            a.hybrid_floor), ("--hold-focus", "hybrid", a.hold_focus or None))
            if v is not None and lens not in names]
        if unused:
            raise ValueError(f"edof: {', '.join(unused)} would be ignored: --lenses "
                             f"{a.lenses!r} trains no such lens; leave it out or add the lens")
        if a.validation and a.test_dir is not None:  # --test-dir won: --validation was dropped
            raise ValueError(f"edof: --validation scores skimage's validation images and "
                             f"--test-dir {a.test_dir} the folder's images; give one of them")
        if a.max_crops is not None:
            input_checks.number(a.max_crops, "--max-crops", "edof", lo=1, integer=True)
        if a.time_limit is not None:
            input_checks.number(a.time_limit, "--time-limit", "edof", lo=0, lo_open=True, unit="s")
        if (a.resume or a.time_limit is not None) and a.checkpoint is None:
            raise ValueError("edof: --resume and --time-limit need --checkpoint (the folder "
                             "to resume from, or to save to before the time is up)")
        if a.train_dir is not None and cfg.train_source == "dead-leaves":
            # The photographs of the folder were loaded and then not used, without a word.
            raise ValueError(f"edof: --train-dir {a.train_dir} gives photographs, but "
                             f"--train-source dead-leaves trains on dead-leaves images only; "
                             f"drop one, or use --train-source mixed for both")
        for opt, d in (("--train-dir", a.train_dir), ("--test-dir", a.test_dir)):
            if d is not None and not os.path.isdir(d):
                raise ValueError(f"edof: {opt} {d} is not a folder")
        # A checkpoint or photographs inside --out were deleted when the run replaced it.
        refuse_inside_out(a.out, (("--checkpoint", a.checkpoint), ("--record", a.record),
                                  ("--train-dir", a.train_dir), ("--test-dir", a.test_dir)),
                          "edof")
        for opt, d in (("--train-dir", a.train_dir), ("--test-dir", a.test_dir)):
            if d is not None:  # a folder without images fails here, not after the lens work
                from jaxlens.experiments.edof import scenes

                try:  # decoded too: a float HDR, int32 or multi-page image failed at run time
                    scenes.check_folder(d, min_side=cfg.crop if opt == "--test-dir" else 1,
                                        crop=cfg.crop if opt == "--test-dir" else None)
                except ValueError as e:
                    raise ValueError(f"edof: {opt}: {e}") from None
        if a.resume:  # before: refused at the lens's start, after the scenes and set-up
            _check_resumable(a, cfg, names)
        # A file there would fail only when the first checkpoint or the record is written.
        for opt, d in (("--checkpoint", a.checkpoint), ("--record", a.record)):
            if d is not None and os.path.exists(d) and not os.path.isdir(d):
                raise ValueError(f"edof: {opt} {d} is a file, not a folder")
            if d is not None:
                check_writable(os.path.join(d, "x") if os.path.isdir(d) else d, opt)
        earlier = [n for n in RECORD_TABLES if a.record is not None and
                   os.path.exists(os.path.join(a.record, n))]
        if earlier and not a.overwrite:  # the record was replaced at the end without a word
            raise ValueError(f"edof: --record {a.record} already holds {', '.join(earlier)} of "
                             f"an earlier run; give --overwrite to replace them, or choose "
                             f"another folder")
        if a.checkpoint and not a.resume and os.path.isdir(a.checkpoint) and \
                os.listdir(a.checkpoint):
            raise ValueError(f"edof: --checkpoint {a.checkpoint} is not empty; give --resume "
                             f"to continue from it, or choose another folder")
        folder = RunFolder(a.out, overwrite=a.overwrite)
    except UsageError:
        raise
    except ValueError as e:
        raise UsageError(str(e)) from None
    return cfg, names, folder


def _check_resumable(a, cfg, names) -> None:
    """``--resume``: every checkpoint of ``--checkpoint`` that this run would continue was
    written with its training options (``train.check_resumable``), checked before any work."""
    from jaxlens.experiments.edof.train import check_resumable

    for seed in a.seeds:
        for name in names:
            meta = os.path.join(a.checkpoint, f"seed{seed}", f"{name}.json")
            if not os.path.isfile(meta):
                continue
            try:
                with open(meta) as f:
                    info = json.load(f)
                if not isinstance(info, dict) or not isinstance(info.get("config"), dict):
                    raise ValueError("not a checkpoint's data")
                info["stage"], info["step"]  # noqa: B018  (both must be there)
            except (OSError, ValueError, KeyError) as e:
                raise ValueError(f"edof: --resume: {meta} is not a readable checkpoint "
                                 f"({e}); use another --checkpoint") from None
            try:
                check_resumable(meta, info, cfg, name)
            except ValueError as e:
                raise ValueError(f"edof: --{e}") from None


def use_compile_cache(checkpoint: str) -> str:
    """Keep JAX's compiled programs in ``checkpoint/compile_cache`` (``jaxlens.compile_cache``),
    unless ``JAX_COMPILATION_CACHE_DIR`` names a cache already; returns the folder used
    (None where ``JAXLENS_COMPILE_CACHE=0`` turns it off). Every piece of a resumed run
    compiles the same programs (over 3 minutes at the paper's scale on an H100), so the next
    piece loads them instead. A process-wide setting: the command line uses it, ``run``
    called from Python does not by default."""
    from jaxlens import compile_cache

    return compile_cache.enable(os.path.join(checkpoint, COMPILE_CACHE))


def run(argv=None, *, compile_cache: bool = False) -> dict:
    """Run the experiment (see the module docstring); returns the summary. With
    ``compile_cache`` (the command line) and ``--checkpoint``, ``use_compile_cache``.

    Raises:
        UsageError: For a bad option or ``--out``, before any work.
        jaxlens.experiments.edof.train.OutOfTime: when ``--time-limit`` stopped the run at a
            checkpoint (``--out`` is left as it was).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    a = build_parser().parse_args(argv)
    cfg, names, folder = check_args(a)
    out = folder.start()  # written here, renamed to --out when the run is complete
    try:
        return _run_into(a, argv, cfg, names, folder, out, compile_cache)
    except BaseException:
        folder.abandon()
        raise


def _scenes(a, cfg):
    from jaxlens.experiments.edof import scenes as S

    photos = S.load_images(None if a.train_dir else S.TRAIN_IMAGES, folder=a.train_dir,
                           max_side=None)
    small = {"count": 2, "side": 64} if a.smoke else {}
    train_imgs, weights = S.training_images(cfg.train_source, photos, **small)
    if a.test_dir:
        paths = S.folder_images(a.test_dir)
        names = [p.stem for p in paths]
        imgs = S.load_images(folder=a.test_dir, max_side=None)
        source = f"every image file in {a.test_dir}"
    else:
        names = list(S.VAL_IMAGES if a.validation else S.TEST_IMAGES)
        imgs = S.load_images(names, max_side=None)
        source = ("skimage.data " + ("validation" if a.validation else "test") +
                  " images (jaxlens.experiments.edof.scenes), sRGB decoded to linear")
    windows, info = S.test_crops(imgs, names, size=cfg.crop, margin=cfg.kernel_size // 2)
    most = a.max_crops or (8 if a.smoke else None)
    if most:
        windows, info = windows[:most], info[:most]
    return (train_imgs, weights), windows, info, names, source


def _run_into(a, argv, cfg, names, folder, out, compile_cache=False) -> dict:
    import equinox as eqx
    import jax
    import jax.numpy as jnp
    import numpy as np
    from tqdm.auto import tqdm

    import jaxlens
    from jaxlens.experiments.edof import evaluate as E
    from jaxlens.experiments.edof import lenses as L
    from jaxlens.experiments.edof import optics as O
    from jaxlens.experiments.edof import scenes as S
    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.edof.decoder import make_decoder
    from jaxlens.imaging.tiled import tile_counts

    if compile_cache and a.checkpoint is not None:
        use_compile_cache(a.checkpoint)
    deadline = None if a.time_limit is None else time.time() + a.time_limit
    os.makedirs(os.path.join(out, "lenses"), exist_ok=True)
    os.makedirs(os.path.join(out, "nets"), exist_ok=True)
    command = "python -m jaxlens.experiments.edof " + shlex.join(argv)
    with open(os.path.join(out, "command.txt"), "w") as f:
        f.write(command + "\n")
    progress = None if a.quiet else tqdm
    t_all, cpu_all = time.perf_counter(), time.process_time()
    timings = {}
    dtype = jnp.float32

    classical = L.classical_lens(binning=cfg.binning)
    base = L.to_hybrid(classical, n_odd=cfg.n_odd).astype(dtype)
    cubic0 = L.cubic_strength_guess(classical, ratio=cfg.cubic_ratio)
    start_cubic = {"classical": 0.0, "cubic": cubic0, "hybrid": 0.5 * cubic0}
    pix = float(base.sensor.pixel_size)
    n_tiles = tile_counts(base.sensor.resolution, cfg.tile)

    t0 = time.perf_counter()
    (train_imgs, weights), windows, crop_info, test_names, source = _scenes(a, cfg)
    # Base-size windows: --real-halo and --context leave the Wiener NSR as it is.
    base_windows = S.PatchSampler(train_imgs, cfg.tile + cfg.kernel_size - 1, seed=12345,
                                  weights=weights)
    nsr = E.wiener_nsr(base_windows.sample(64), photons=cfg.photons, read=cfg.read_noise)
    timings["scenes_s"] = time.perf_counter() - t0

    per_image = {}  # seed -> lens -> depth -> kind -> metric -> [crops]
    light, variation, histories, examples, banks, trained = {}, {}, {}, {}, {}, {}
    for seed in a.seeds:
        key = jax.random.PRNGKey(seed)
        k_net, k_train, k_eval = jax.random.split(key, 3)
        k_eval = jax.random.PRNGKey(10_000)  # the same noise for every seed and lens
        ck = None if a.checkpoint is None else os.path.join(a.checkpoint, f"seed{seed}")
        for i, name in enumerate(names):
            tag = f"{name}_s{seed}"
            lens0 = L.to_hybrid(classical, n_odd=cfg.n_odd,
                                cubic=start_cubic[name]).astype(dtype)
            pmap = L.HybridParameterization.of(lens0)
            params = pmap.from_lens(lens0)
            fraction = {"cubic": cfg.cubic_floor, "hybrid": cfg.hybrid_floor}.get(name)
            floor = -math.inf if fraction is None else fraction * float(params.odd_x[0])
            dec = make_decoder(cfg.decoder, nsr=nsr, key=k_net, width=cfg.width,
                               enc_blocks=cfg.enc_blocks, middle_blocks=cfg.middle_blocks,
                               dec_blocks=cfg.dec_blocks, dtype=dtype)
            sampler = S.PatchSampler(train_imgs, cfg.window, seed=seed + 17, weights=weights)
            src = T.BatchSource(sampler, n_tiles, cfg, seed=seed + 29)
            trainer = T.Trainer(name, pmap, params, dec, src, cfg,
                                jax.random.fold_in(k_train, i), floor=floor, folder=ck,
                                deadline=deadline)
            if a.resume and not trainer.load():  # a mistyped --checkpoint must not pass unseen
                print(f"edof: --resume: no checkpoint of the {name} lens (seed {seed}) in "
                      f"{a.checkpoint}; it trains from the start", file=sys.stderr)
            t0 = time.perf_counter()
            dec, params, hist = trainer.run(progress)
            timings[f"train_{tag}_s"] = time.perf_counter() - t0
            lens = pmap.to_lens(params)
            histories[tag] = hist
            jaxlens.save(lens, os.path.join(out, "lenses", f"{tag}.json"))
            eqx.tree_serialise_leaves(os.path.join(out, "nets", f"{tag}.eqx"), dec)
            t0 = time.perf_counter()
            # A resumed run does not evaluate a lens twice with the same settings.
            settings = {"eval_pupil": cfg.eval_pupil, "crops": int(len(windows)),
                        "training": T.training_config(T.config_data(cfg), name)}
            cached = _load_eval(ck, name, settings)
            if cached is None:
                bank = O.psf_bank(lens, tile=cfg.tile, kernel_size=cfg.kernel_size,
                                  pupil=cfg.eval_pupil, chunk=2 * cfg.batch)
                vals, ex = E.evaluate(dec, bank, windows, cfg=cfg, key=k_eval, nsr=nsr,
                                      keep=0 if seed == a.seeds[0] else None)
                _save_eval(ck, name, bank, vals, ex, settings)
            else:
                bank, vals, ex = cached
            timings[f"evaluate_{tag}_s"] = time.perf_counter() - t0
            per_image.setdefault(str(seed), {})[name] = vals
            light.setdefault(name, []).append(O.light_on_sensor(bank))
            ty, tx = bank.shape[1:3]
            sub = bank[:, ::max(1, ty // 3), ::max(1, tx // 3)]
            variation.setdefault(name, []).append(
                O.psf_depth_variation(sub.reshape((sub.shape[0], -1) + sub.shape[3:])))
            if seed == a.seeds[0]:
                examples[name], banks[name], trained[name] = ex, bank, (lens, params)
            if deadline is not None and time.time() > deadline and (
                    name != names[-1] or seed != a.seeds[-1]):
                raise T.OutOfTime(f"stopped after {tag}")

    table = table2(per_image, names, a.seeds, crop_info, test_names, source,
                   base_lens_data(classical), light, nsr)
    summary_extra = {
        "psf_depth_variation": {n: {"l1": float(np.mean([v["l1"] for v in variation[n]])),
                                    "ncc": float(np.mean([v["ncc"] for v in variation[n]])),
                                    "per_seed_l1": [v["l1"] for v in variation[n]]}
                                for n in names},
        "odd_terms": {n: {"odd_x_scaled": np.asarray(trained[n][1].odd_x).tolist(),
                          "focus_scaled": float(trained[n][1].focus)} for n in names},
        "wiener_reference_nsr": nsr,
        "noise": {"photons_at_1": cfg.photons, "read_noise": cfg.read_noise},
    }
    table["psf_depth_variation"] = summary_extra["psf_depth_variation"]
    t0 = time.perf_counter()
    files = write_figures(out, names, trained, banks, examples, windows, histories, cfg, pix,
                          smoke=a.smoke)
    table_md = table2_markdown(table, command, cfg)
    with open(os.path.join(out, "table2.json"), "w") as f:
        json.dump(table, f, indent=2)
    with open(os.path.join(out, "table2_per_image.json"), "w") as f:
        json.dump({"crops": crop_info, "seeds": list(a.seeds), "values": per_image}, f)
    with open(os.path.join(out, "table2.md"), "w") as f:
        f.write(table_md)
    timings["figures_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_all
    timings["process_cpu_s"] = time.process_time() - cpu_all
    summary = {
        "command": command,
        "config": dataclasses.asdict(cfg),
        "train_images": (None if cfg.train_source == "dead-leaves" else
                         list(S.TRAIN_IMAGES) if a.train_dir is None else a.train_dir),
        "train_source": cfg.train_source,
        "sensor": {"resolution": list(base.sensor.resolution), "pixel_size_mm": pix,
                   "tiles": list(n_tiles)},
        "cubic_start_strength_per_mm2": cubic0,
        **summary_extra,
        "checks": checks(table),
        "history": histories,
        "timings_s": timings,
        "devices": [str(d) for d in jax.devices()],
        "files": {k: folder.final_path(v) for k, v in files.items()},
    }
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    out = folder.finish()
    if a.record:
        record(out, a.record, summary["files"])
    print(table_md)
    print(f"total {timings['total_s']:.0f} s; outputs in {out}")
    return summary


def _save_eval(ck, name, bank, vals, examples, settings: dict) -> None:
    """Keep a lens's evaluation in the checkpoint folder (bank, per-crop values, examples,
    and the evaluation settings they were made with)."""
    import numpy as np

    if ck is None:
        return
    os.makedirs(ck, exist_ok=True)
    # The settings file commits the others: gone while they are written, so a write stopped
    # half way is never read as this evaluation.
    marker = os.path.join(ck, f"eval_{name}_settings.json")
    if os.path.exists(marker):
        os.remove(marker)
    np.save(os.path.join(ck, f"eval_{name}_bank.npy"), bank)
    ex = {f"{d}|{i}": x for d, xs in examples.items() for i, x in enumerate(xs)}
    np.savez(os.path.join(ck, f"eval_{name}_examples.npz"), **ex)
    with open(os.path.join(ck, f"eval_{name}.json"), "w") as f:
        json.dump(vals, f)
    write_whole(marker, json.dumps(settings))


def _load_eval(ck, name, settings: dict):
    """``(bank, values, examples)`` saved by ``_save_eval`` with these settings, or None."""
    import numpy as np

    if ck is None or not os.path.isfile(os.path.join(ck, f"eval_{name}.json")):
        return None
    path = os.path.join(ck, f"eval_{name}_settings.json")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        if json.load(f) != settings:
            return None
    with open(os.path.join(ck, f"eval_{name}.json")) as f:
        vals = json.load(f)
    bank = np.load(os.path.join(ck, f"eval_{name}_bank.npy"))
    with np.load(os.path.join(ck, f"eval_{name}_examples.npz")) as z:
        ex = {}
        for k in sorted(z.files, key=lambda k: (k.split("|")[0], int(k.split("|")[1]))):
            ex.setdefault(k.split("|")[0], []).append(z[k])
    return bank, vals, {d: tuple(v) for d, v in ex.items()}


RECORD_TABLES = ("table2.md", "table2.json", "table2_per_image.json", "summary.json",
                 "command.txt")
"""The files ``record`` copies besides the figures and lenses."""


def record(out: str, dest: str, files: dict) -> None:
    """Copy the tables, summary, command, trained lenses and figures to ``dest``."""
    os.makedirs(dest, exist_ok=True)
    for name in RECORD_TABLES:
        shutil.copy2(os.path.join(out, name), os.path.join(dest, name))
    for path in files.values():
        shutil.copy2(path, os.path.join(dest, os.path.basename(path)))
    lens_dir = os.path.join(dest, "lenses")
    os.makedirs(lens_dir, exist_ok=True)
    for name in os.listdir(os.path.join(out, "lenses")):
        shutil.copy2(os.path.join(out, "lenses", name), os.path.join(lens_dir, name))


def main() -> None:
    try:
        run(compile_cache=True)
    except UsageError as e:
        sys.exit(fail("python -m jaxlens.experiments.edof", e))
    except Exception as e:
        from jaxlens.experiments.edof.train import OutOfTime

        if not isinstance(e, OutOfTime):
            raise
        print(f"python -m jaxlens.experiments.edof: time limit: {e}; run the same command "
              f"with --resume to continue", file=sys.stderr)
        sys.exit(OUT_OF_TIME)


if __name__ == "__main__":
    main()
