"""End-to-end EDoF computational lens: hybrid odd-polynomial surface + reconstruction network.

``python -m jaxlens.experiments.edof`` reproduces, at CPU scale, the paper's second result
(Yang, Fu & Heidrich, Nat. Commun. 2024): a large-aperture (F/2.1), wide-field (68.8°)
cellphone-style lens whose first surface becomes a hybrid surface (even asphere plus odd
polynomial terms), trained jointly with a NAFNet so that images are restored from 10 cm to
10 m, against the classical lens (focused at 20 cm) and a cubic phase plate at the aperture,
each with its own network trained the same way.

For every lens it runs stage 1 (network and free lens parameters with
L = L_rec + ω1·L_sim + ω2·L_raw; two of the 8 training depths per batch, 486/587/656 nm),
then stage 2 (lens frozen, network refined on perturbed lenses), then evaluates PSNR and SSIM
of the raw simulation and the reconstruction on held-out test images at 10 cm, 20 cm and
10 m (the paper's Table 2). It also measures how much each lens's PSFs change with depth,
and writes PSF grids, MTF curves by depth, the odd polynomial's height profile and example
reconstructions.

Outputs (``--out``, default ``runs/edof``): ``table2.json``/``table2.md``, ``summary.json``
(config, timings, PSF-variation measures, loss histories), ``command.txt``, the trained
lenses (``lenses/<name>.json`` and ``.zmx``), the network weights (``nets/<name>.eqx``,
``eqx.tree_serialise_leaves``), and figures (``psf_grid_<name>.png``, ``mtf_by_depth.png``,
``odd_profile.png``, ``reconstructions.png``, ``loss.png``). ``--record DIR`` copies the
tables, summary and figures there (the committed copy is ``experiments/edof``).

Defaults are the CPU scale (2× binned 512² sensor, 64-pixel patches, a 16-wide NAFNet,
400 + 100 steps per lens); ``--paper`` selects the paper's scale for a GPU (full 1024²
sensor, 256-pixel patches, the 32-wide NAFNet with 28 deep blocks, many more steps).
``--smoke`` is a seconds-scale run for tests.

Examples:
    python -m jaxlens.experiments.edof
    python -m jaxlens.experiments.edof --steps 2000 --steps2 500 --out runs/edof_long
    python -m jaxlens.experiments.edof --paper --out runs/edof_paper
    python -m jaxlens.experiments.edof --smoke --out /tmp/edof_smoke
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shlex
import shutil
import sys
import time

from jaxlens.experiments.runfolder import OneLineParser, RunFolder, UsageError, fail
from jaxlens.optics import checks as input_checks

LENS_NAMES = ("classical", "cubic", "hybrid")


def _ints(text: str) -> tuple[int, ...]:
    return tuple(int(v) for v in text.split(",") if v.strip())


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="python -m jaxlens.experiments.edof",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default="runs/edof", help="output folder (default runs/edof)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an earlier run in --out (default: refuse)")
    p.add_argument(
        "--record", default=None, help="also copy tables, summary and figures to this folder"
    )
    p.add_argument(
        "--lenses",
        default=",".join(LENS_NAMES),
        help="lenses to train, from classical,cubic,hybrid",
    )
    p.add_argument("--smoke", action="store_true", help="tiny, seconds-scale run (tests)")
    p.add_argument("--paper", action="store_true", help="the paper's scale (GPU)")
    g = p.add_argument_group("training (defaults: CPU scale)")
    g.add_argument("--steps", type=int, help="stage-1 steps per lens (400)")
    g.add_argument("--steps2", type=int, help="stage-2 steps per lens (100)")
    g.add_argument("--batch", type=int, help="patches per batch (4)")
    g.add_argument("--patch", type=int, help="patch side, pixels (64)")
    g.add_argument("--kernel", type=int, help="PSF kernel side, pixels (41)")
    g.add_argument("--binning", type=int, help="sensor binning of the 1024² sensor (2)")
    g.add_argument("--pupil", type=int, help="pupil samples per side of a training PSF (32)")
    g.add_argument("--lr-net", type=float, help="network learning rate (1e-3)")
    g.add_argument("--lr-lens", type=float, help="lens learning rate, scaled units (2e-2)")
    g.add_argument(
        "--lens-delay",
        type=float,
        help="fraction of stage-1 steps with the lens frozen while the network warms up (0)",
    )
    g.add_argument(
        "--depth-sampling",
        choices=("uniform", "dioptric"),
        help="how a batch draws its 2 of the 8 training depths: uniformly, or with weights "
        "even in dioptres (uniform)",
    )
    g.add_argument(
        "--hold-focus",
        action=argparse.BooleanOptionalAction,
        help="the hybrid keeps the classical lens's base curvature and sensor position (off)",
    )
    g.add_argument("--w-sim", type=float, help="ω1, weight of L_sim (0.1)")
    g.add_argument("--w-raw", type=float, help="ω2, weight of L_raw (0.1)")
    g.add_argument("--noise", type=float, help="read-noise standard deviation (0.01)")
    g.add_argument("--width", type=int, help="NAFNet width (16)")
    g.add_argument("--enc", type=_ints, help="NAFNet encoder blocks per level (1,1,1)")
    g.add_argument("--middle", type=int, help="NAFNet middle blocks (1)")
    g.add_argument("--dec", type=_ints, help="NAFNet decoder blocks per level (1,1,1)")
    g.add_argument("--n-odd", type=int, help="odd terms per axis of the hybrid surface (3)")
    g.add_argument("--seed", type=int, default=0)
    d = p.add_argument_group("data")
    d.add_argument(
        "--train-dir",
        default=None,
        help="folder of training images (default: skimage.data; see edof.scenes)",
    )
    d.add_argument("--test-dir", default=None, help="folder of held-out test images")
    d.add_argument("--test-images", type=int, default=None, help="use only the first N tests")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    return p


def config_from_args(a):
    from jaxlens.experiments.edof.train import Config

    if a.paper:
        cfg = Config(
            binning=1,
            patch=256,
            kernel_size=81,
            batch=8,
            pupil=96,
            steps=20000,
            steps2=5000,
            width=32,
            enc_blocks=(1, 1, 1, 28),
            middle_blocks=1,
            dec_blocks=(1, 1, 1, 1),
            eval_pupil=128,
            log_every=50,
        )
    elif a.smoke:
        cfg = Config(
            binning=16,
            patch=16,
            kernel_size=9,
            batch=2,
            pupil=8,
            steps=8,
            steps2=2,
            width=4,
            enc_blocks=(1,),
            middle_blocks=1,
            dec_blocks=(1,),
            eval_pupil=12,
            lr_net=3e-3,
            log_every=2,
        )
    else:
        cfg = Config()
    over = {
        "steps": a.steps,
        "steps2": a.steps2,
        "batch": a.batch,
        "patch": a.patch,
        "kernel_size": a.kernel,
        "binning": a.binning,
        "pupil": a.pupil,
        "lr_net": a.lr_net,
        "lr_lens": a.lr_lens,
        "lens_delay": a.lens_delay,
        "depth_sampling": a.depth_sampling,
        "hold_focus": a.hold_focus,
        "w_sim": a.w_sim,
        "w_raw": a.w_raw,
        "noise": a.noise,
        "width": a.width,
        "enc_blocks": a.enc,
        "middle_blocks": a.middle,
        "dec_blocks": a.dec,
        "n_odd": a.n_odd,
    }
    cfg = dataclasses.replace(cfg, seed=a.seed, **{k: v for k, v in over.items() if v is not None})
    n, w = input_checks.number, "edof"
    for opt, v in (("--steps", cfg.steps), ("--batch", cfg.batch), ("--patch", cfg.patch),
                   ("--kernel", cfg.kernel_size), ("--binning", cfg.binning),
                   ("--width", cfg.width)):
        n(v, opt, w, lo=1, integer=True)
    for opt, v in (("--steps2", cfg.steps2), ("--middle", cfg.middle_blocks),
                   ("--n-odd", cfg.n_odd), ("--seed", cfg.seed)):
        n(v, opt, w, lo=0, integer=True)
    n(cfg.pupil, "--pupil", w, lo=2, integer=True, unit="samples per side")
    n(cfg.lr_net, "--lr-net", w, lo=0, lo_open=True)
    n(cfg.lr_lens, "--lr-lens", w, lo=0, lo_open=True)
    n(cfg.lens_delay, "--lens-delay", w, lo=0, hi=1, unit="(fraction of stage-1 steps)")
    for opt, v in (("--w-sim", cfg.w_sim), ("--w-raw", cfg.w_raw), ("--noise", cfg.noise)):
        n(v, opt, w, lo=0)
    for opt, blocks in (("--enc", cfg.enc_blocks), ("--dec", cfg.dec_blocks)):
        if not blocks or any(b < 0 for b in blocks):
            raise ValueError(f"edof: {opt} must be comma-separated whole numbers >= 0 (blocks "
                             f"per level), got {blocks!r}")
    if 1024 % cfg.binning:
        raise ValueError(f"edof: --binning must divide the 1024-pixel sensor side, got "
                         f"{cfg.binning}")
    if cfg.kernel_size % 2 == 0:
        raise ValueError(f"edof: --kernel must be an odd whole number >= 1 pixels, got "
                         f"{cfg.kernel_size}")
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
        if bad or not names:
            raise ValueError(f"edof: --lenses takes names from {LENS_NAMES}, got {a.lenses!r}")
        if a.test_images is not None:
            input_checks.number(a.test_images, "--test-images", "edof", lo=1, integer=True)
        for opt, d in (("--train-dir", a.train_dir), ("--test-dir", a.test_dir)):
            if d is not None and not os.path.isdir(d):
                raise ValueError(f"edof: {opt} {d} is not a folder")
        folder = RunFolder(a.out, overwrite=a.overwrite)
    except UsageError:
        raise
    except ValueError as e:
        raise UsageError(str(e)) from None
    return cfg, names, folder


def run(argv=None) -> dict:
    """Run the experiment (see the module docstring); returns the summary.

    Raises:
        UsageError: For a bad option or ``--out``, before any work.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    a = build_parser().parse_args(argv)
    cfg, names, folder = check_args(a)
    out = folder.start()  # written here, renamed to --out when the run is complete
    try:
        return _run_into(a, argv, cfg, names, folder, out)
    except BaseException:
        folder.abandon()
        raise


def _run_into(a, argv, cfg, names, folder, out) -> dict:
    import equinox as eqx
    import jax
    import jax.numpy as jnp
    import numpy as np
    from tqdm.auto import tqdm

    import jaxlens
    from jaxlens.experiments.edof import lenses as L
    from jaxlens.experiments.edof import optics as O
    from jaxlens.experiments.edof import scenes as S
    from jaxlens.experiments.edof import train as T

    os.makedirs(os.path.join(out, "lenses"), exist_ok=True)
    os.makedirs(os.path.join(out, "nets"), exist_ok=True)
    command = "python -m jaxlens.experiments.edof " + shlex.join(argv)
    with open(os.path.join(out, "command.txt"), "w") as f:
        f.write(command + "\n")
    progress = None if a.quiet else tqdm
    t_all = time.perf_counter()
    cpu_all = time.process_time()
    timings = {}
    dtype = jnp.float32

    # Lenses: the classical lens, as a Hybrid-first lens with zero odd terms.
    classical = L.classical_lens(binning=cfg.binning)
    base = L.to_hybrid(classical, n_odd=cfg.n_odd).astype(dtype)
    cubic0 = L.cubic_strength_guess(classical, ratio=cfg.cubic_ratio)
    start_cubic = {"classical": 0.0, "cubic": cubic0, "hybrid": 0.5 * cubic0}
    pix = float(base.sensor.pixel_size)
    size = base.sensor.resolution[0]

    # Scenes.
    t0 = time.perf_counter()
    max_side = 2 * size if not a.smoke else 4 * cfg.window
    train_imgs = S.load_images(
        None if a.train_dir else S.TRAIN_IMAGES,
        folder=a.train_dir,
        max_side=max(max_side, cfg.window),
    )
    test_raw = S.load_images(
        None if a.test_dir else S.TEST_IMAGES, folder=a.test_dir, max_side=None
    )
    if a.test_images:
        test_raw = test_raw[: a.test_images]
    if a.smoke:
        test_raw = test_raw[:1]
    tests = [S.square_crop(img, size) for img in test_raw]
    timings["scenes_s"] = time.perf_counter() - t0

    # Training.
    key = jax.random.PRNGKey(cfg.seed)
    k_net, k_train, k_eval = jax.random.split(key, 3)
    trained, histories = {}, {}
    for i, name in enumerate(names):
        lens0 = L.to_hybrid(classical, n_odd=cfg.n_odd, cubic=start_cubic[name]).astype(dtype)
        params = L.HybridParams.from_lens(lens0)
        net = T.make_net(cfg, k_net, dtype)  # the same initial network for every lens
        sampler = S.PatchSampler(train_imgs, cfg.window, seed=cfg.seed + 17)
        source = T.BatchSource(sampler, lens0, cfg, seed=cfg.seed + 29)
        t0 = time.perf_counter()
        net, params, hist = T.train(
            name,
            lens0,
            params,
            net,
            source,
            cfg,
            kind=name,
            key=jax.random.fold_in(k_train, i),
            progress=progress,
        )
        timings[f"train_{name}_s"] = time.perf_counter() - t0
        lens = params.apply(lens0)
        trained[name] = (lens, net, params)
        histories[name] = hist
        jaxlens.save(lens, os.path.join(out, "lenses", f"{name}.json"))
        jaxlens.save(lens, os.path.join(out, "lenses", f"{name}.zmx"))
        eqx.tree_serialise_leaves(os.path.join(out, "nets", f"{name}.eqx"), net)

    # Table 2.
    t0 = time.perf_counter()
    depths_eval = L.TEST_DEPTHS_M
    table, examples = {}, {}
    for name in names:
        lens, net, _ = trained[name]
        m, ex = T.evaluate(lens, net, tests, depths_eval, cfg, key=k_eval, keep=0)
        table[name] = m
        examples[name] = ex
    timings["evaluate_s"] = time.perf_counter() - t0
    consistency = None
    if not a.smoke and "classical" in names:
        # Cross-check of the tiled renderer against jaxlens.imaging.render on one test image.
        t0 = time.perf_counter()
        lens = trained["classical"][0]
        scene = jnp.asarray(tests[0], dtype)
        consistency = {}
        for d in (0.1, 0.2):
            mine = O.render_tiled(
                lens,
                scene,
                jnp.asarray(1e3 * d, dtype),
                kernel_size=cfg.kernel_size,
                pixel_size=pix,
                patch=cfg.patch,
                pupil=cfg.eval_pupil,
            )
            lib = O.render_library(
                lens, scene, 1e3 * d, k_eval, kernel_size=cfg.kernel_size, spp=4, patch=cfg.patch
            )
            err = float(jnp.mean((mine - lib) ** 2))
            consistency[f"{d:g}"] = {"psnr_db": float(10 * np.log10(1.0 / max(err, 1e-20)))}
        timings["render_crosscheck_s"] = time.perf_counter() - t0

    # PSF analysis.
    t0 = time.perf_counter()
    pts = O.diagonal_points(base, (0.0, 0.5, 1.0))
    dmm = O.depths_mm()
    pupil_a = 24 if a.smoke else 128
    stacks, variation = {}, {}
    for name in names:
        lens = trained[name][0]
        stacks[name] = O.psf_stack(
            lens, pts, dmm, kernel_size=cfg.kernel_size, pixel_size=pix, pupil=pupil_a
        )
        variation[name] = O.psf_depth_variation(stacks[name])
    freqs = np.linspace(0.0, 0.5 / pix, 9 if a.smoke else 26)
    mtfs = {}
    for name in names:
        lens = trained[name][0]
        mtfs[name] = {
            f"{frac:g}": O.mtf_by_depth(
                lens, p, dmm, frequencies=freqs, pupil=24 if a.smoke else 96
            )
            for frac, p in ((0.0, pts[0]), (0.7, 0.7 * pts[2]))
        }
    timings["psf_analysis_s"] = time.perf_counter() - t0

    # Files.
    t0 = time.perf_counter()
    files = write_figures(
        out, names, trained, stacks, mtfs, examples, tests, histories, cfg, smoke=a.smoke
    )
    table_md = table2_markdown(table, variation, command, cfg)
    with open(os.path.join(out, "table2.json"), "w") as f:
        json.dump(table, f, indent=2)
    with open(os.path.join(out, "table2.md"), "w") as f:
        f.write(table_md)
    timings["figures_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_all
    timings["process_cpu_s"] = time.process_time() - cpu_all
    summary = {
        "command": command,
        "config": dataclasses.asdict(cfg),
        "train_images": list(S.TRAIN_IMAGES) if a.train_dir is None else a.train_dir,
        "test_images": list(S.TEST_IMAGES[: len(tests)]) if a.test_dir is None else a.test_dir,
        "sensor": {"resolution": [size, size], "pixel_size_mm": pix},
        "cubic_start_strength_per_mm2": cubic0,
        "table2": table,
        "psf_depth_variation": {n: {k: v for k, v in variation[n].items()} for n in names},
        "checks": checks(table, variation),
        "render_crosscheck_classical_vs_jaxlens_render": consistency,
        "history": histories,
        "timings_s": timings,
        "devices": [str(d) for d in jax.devices()],
        "files": {k: folder.final_path(v) for k, v in files.items()},
    }
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    out = folder.finish()
    files = summary["files"]
    if a.record:
        record(out, a.record, files)
    print(table_md)
    print(f"total {timings['total_s']:.0f} s; outputs in {out}")
    return summary


def checks(table: dict, variation: dict) -> dict:
    """The issue's pass/fail criteria, evaluated on the results."""
    out = {}
    if "hybrid" in table and "classical" in table:
        h, c = table["hybrid"], table["classical"]
        d = {k: h[k]["rec"]["psnr"] - c[k]["rec"]["psnr"] for k in h}
        out["rec_psnr_gain_hybrid_vs_classical_db"] = d
        out["beats_by_1db_at_0.1m"] = bool(d.get("0.1", -1e9) >= 1.0)
        out["beats_by_1db_at_10m"] = bool(d.get("10", -1e9) >= 1.0)
        out["within_0.5db_at_0.2m"] = bool(abs(d.get("0.2", 1e9)) <= 0.5 or d["0.2"] > 0)
    if "hybrid" in variation and "classical" in variation:
        out["psf_l1_hybrid_below_classical"] = bool(
            variation["hybrid"]["l1"] < variation["classical"]["l1"]
        )
    return out


def table2_markdown(table: dict, variation: dict, command: str, cfg) -> str:
    depths = list(next(iter(table.values())).keys())
    lines = [
        "# EDoF lens: Table 2 analogue (held-out test images)",
        "",
        f"Command: `{command}`",
        "",
        "PSNR (dB) / SSIM of the raw simulation (sim, with read noise σ = "
        f"{cfg.noise:g}) and of the network's reconstruction (rec), averaged over the test "
        "images, per object distance from the stop.",
        "",
        "| lens | " + " | ".join(f"{d} m sim | {d} m rec" for d in depths) + " |",
        "|---|" + "---|---|" * len(depths),
    ]
    for name, row in table.items():
        cells = []
        for d in depths:
            for t in ("sim", "rec"):
                cells.append(f"{row[d][t]['psnr']:.2f} / {row[d][t]['ssim']:.3f}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "PSF variation with depth (8 training depths, 3 fields along the diagonal, "
        "RGB): mean L1 distance Σ|p_i − p_j| over depth pairs (0 = identical, 2 = "
        "disjoint) and mean normalised cross-correlation (1 = identical).",
        "",
        "| lens | L1 | NCC |",
        "|---|---|---|",
    ]
    for name, v in variation.items():
        lines.append(f"| {name} | {v['l1']:.3f} | {v['ncc']:.3f} |")
    c = checks(table, variation)
    if "rec_psnr_gain_hybrid_vs_classical_db" in c:
        g = c["rec_psnr_gain_hybrid_vs_classical_db"]
        lines += [
            "",
            "Reconstruction PSNR gain of the hybrid lens over the classical lens: "
            + ", ".join(f"{d} m: {v:+.2f} dB" for d, v in g.items())
            + " (the paper reports +1.2 dB at 10 cm and +2.4 dB at 10 m).",
        ]
    return "\n".join(lines) + "\n"


def write_figures(
    out, names, trained, stacks, mtfs, examples, tests, histories, cfg, *, smoke=False
) -> dict:
    """PSF grids, MTF curves, odd-polynomial profile, reconstructions and loss curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from jaxlens.experiments.edof import lenses as L

    files = {}
    dpi = 60 if smoke else 110
    depths = L.DEPTHS_M
    fracs = (0.0, 0.5, 1.0)
    for name in names:
        st = stacks[name]  # [D, F, 3, k, k]
        fig, axes = plt.subplots(
            len(depths), len(fracs), figsize=(1.6 * len(fracs) + 1, 1.5 * len(depths))
        )
        for i, d in enumerate(depths):
            for j, fr in enumerate(fracs):
                ax = axes[i, j]
                img = np.transpose(st[i, j], (1, 2, 0))
                ax.imshow(np.sqrt(img / max(img.max(), 1e-12)), interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                if j == 0:
                    ax.set_ylabel(f"{d:g} m", fontsize=8)
                if i == 0:
                    ax.set_title(f"field {fr:g}", fontsize=8)
        fig.suptitle(f"{name}: RGB PSFs by depth (rows) and field (cols), √ scale", fontsize=9)
        fig.tight_layout()
        path = os.path.join(out, f"psf_grid_{name}.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        files[f"psf_grid_{name}"] = path

    fig, axes = plt.subplots(2, len(names), figsize=(4 * len(names), 6.5), squeeze=False)
    cmap = plt.get_cmap("viridis")
    for j, name in enumerate(names):
        for i, (frac, (f, tan, sag)) in enumerate(mtfs[name].items()):
            ax = axes[i, j]
            for k, d in enumerate(depths):
                ax.plot(
                    f, 0.5 * (tan[k] + sag[k]), color=cmap(k / (len(depths) - 1)), label=f"{d:g} m"
                )
            ax.set_ylim(0, 1.02)
            ax.set_title(f"{name}, field {frac}", fontsize=9)
            ax.set_xlabel("cycles/mm")
            if j == 0:
                ax.set_ylabel("MTF (mean of T and S)")
    axes[0, -1].legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(out, "mtf_by_depth.png")
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    files["mtf_by_depth"] = path

    odd = [n for n in names if n in ("hybrid", "cubic")]
    if odd:
        fig, axes = plt.subplots(2, len(odd), figsize=(4.2 * len(odd), 7), squeeze=False)
        for j, name in enumerate(odd):
            x, h = L.odd_profile(trained[name][0])
            im = axes[0, j].imshow(
                1e3 * h, extent=(x[0], x[-1], x[0], x[-1]), origin="lower", cmap="RdBu_r"
            )
            fig.colorbar(im, ax=axes[0, j], label="µm")
            axes[0, j].set_title(f"{name}: odd-polynomial height", fontsize=9)
            axes[0, j].set_xlabel("x (mm)")
            axes[0, j].set_ylabel("y (mm)")
            mid = len(x) // 2
            axes[1, j].plot(x, 1e3 * h[mid, :], label="along x (y = 0)")
            axes[1, j].plot(x, 1e3 * h[:, mid], label="along y (x = 0)")
            axes[1, j].set_xlabel("mm")
            axes[1, j].set_ylabel("height (µm)")
            axes[1, j].legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out, "odd_profile.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        files["odd_profile"] = path

    if examples and tests:
        gt = tests[0]
        s = gt.shape[0]
        c = min(s, 192)
        y0 = (s - c) // 2
        crop = lambda im: np.clip(im[y0 : y0 + c, y0 : y0 + c], 0, 1)  # noqa: E731
        keys = list(next(iter(examples.values())).keys())
        fig, axes = plt.subplots(
            len(names),
            1 + 2 * len(keys),
            figsize=(1.9 * (1 + 2 * len(keys)), 2.0 * len(names)),
            squeeze=False,
        )
        for i, name in enumerate(names):
            axes[i, 0].imshow(crop(gt))
            axes[i, 0].set_ylabel(name)
            axes[i, 0].set_title("ground truth", fontsize=8)
            for k, d in enumerate(keys):
                sim, rec = examples[name][d]
                axes[i, 1 + 2 * k].imshow(crop(sim))
                axes[i, 1 + 2 * k].set_title(f"sim {d} m", fontsize=8)
                axes[i, 2 + 2 * k].imshow(crop(rec))
                axes[i, 2 + 2 * k].set_title(f"rec {d} m", fontsize=8)
        for ax in axes.ravel():
            ax.set_xticks([])
            ax.set_yticks([])
        fig.tight_layout()
        path = os.path.join(out, "reconstructions.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        files["reconstructions"] = path

    fig, ax = plt.subplots(1, 2, figsize=(10, 3.5))
    for name in names:
        h1 = histories[name]["stage1"]
        ax[0].plot([r["step"] for r in h1], [r["loss"] for r in h1], label=f"{name} L")
        ax[0].plot([r["step"] for r in h1], [r["rec"] for r in h1], "--", label=f"{name} L_rec")
        h2 = histories[name]["stage2"]
        ax[1].plot([r["step"] for r in h2], [r["rec"] for r in h2], label=name)
    ax[0].set_title("stage 1 (joint)", fontsize=9)
    ax[1].set_title("stage 2 (perturbed lenses), L_rec", fontsize=9)
    for x in ax:
        x.set_xlabel("step")
        x.legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(out, "loss.png")
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    files["loss"] = path
    return files


def record(out: str, dest: str, files: dict) -> None:
    """Copy the tables, summary, command, trained lenses and figures to ``dest``."""
    os.makedirs(dest, exist_ok=True)
    for name in ("table2.md", "table2.json", "summary.json", "command.txt"):
        shutil.copy2(os.path.join(out, name), os.path.join(dest, name))
    for path in files.values():
        shutil.copy2(path, os.path.join(dest, os.path.basename(path)))
    lens_dir = os.path.join(dest, "lenses")
    os.makedirs(lens_dir, exist_ok=True)
    for name in os.listdir(os.path.join(out, "lenses")):
        shutil.copy2(os.path.join(out, "lenses", name), os.path.join(lens_dir, name))


def main() -> None:
    try:
        run()
    except UsageError as e:
        sys.exit(fail("python -m jaxlens.experiments.edof", e))


if __name__ == "__main__":
    main()
