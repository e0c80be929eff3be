"""Ab initio curriculum design of a classical lens, and the paper's Table 1 ablation.

``python -m jaxlens.experiments.classical`` with no arguments designs the paper's classical
lens (Yang, Fu & Heidrich, Nat. Commun. 15, 6572 (2024)): six plastic aspheric elements,
the stop first, an 80.8° diagonal field of view at F/2.0 on a 7.66 mm sensor diagonal,
from random, nearly flat starts. It writes an output folder (``--out``, default
``runs/classical``) with the best design as JSON and Zemax ``.zmx`` (plus ``.AGF`` catalogs
for glasses Zemax does not ship), every seed's design as JSON, figures (layout with rays,
spot diagrams, RMS map over the sensor, MTF curves, design progress, a rendered test
scene), the tolerance analysis of the best design (``tolerance.json``,
``tolerance_rms.png``: ``jaxlens.experiments.tolerance``; ``--tolerance-trials 0`` skips
it) and ``summary.json``, whose headline it also prints.

Convention (the paper's): f = (sensor half-diagonal)/tan(half FoV) = 3.83/tan(40.4°) ≈
4.50 mm and EPD = f/F# ≈ 2.25 mm. Distortion is free to move the paraxial EFL; the summary
reports the paraxial EFL and F-number too. The RMS statistics use 256 fields, a 16 × 16
grid over the whole (square) sensor, corners included (see ``jaxlens.design.evaluate``).

Recipe (default): multi-start (seeds vmapped and sharded over the CPU cores), Adam in an
order-1 parameter space through the curriculum (FoV and F-number along the paper's sine
path, ideal-image reference), fine-tuning at the full spec with the centroid reference,
the image-height pin, the re-weighting mask and 1/RMS field weights, then a
Levenberg–Marquardt polish on the spot residuals; the three regularizers throughout. The
default ``--recipe strong`` polishes for 240 steps; ``--recipe paper`` for 80, as Table 1's
paper-method columns (``experiments/classical/RECIPE.md`` has the measurements).

``--ablation`` runs the Table 1 columns (baseline; +curriculum; +regularization; +both;
+both+mask; +recipe, the strong recipe) over 20 random starts each and writes
``table1.md``, ``table1.json``, the designs of the +recipe and +both+mask columns as
``designs/seed_<n>.zmx`` and ``designs_paper_method/seed_<n>.zmx`` and the exact command
into ``--ablation-out`` (default ``experiments/classical``).

Examples:
    python -m jaxlens.experiments.classical
    python -m jaxlens.experiments.classical --seeds 8 --steps 2 --out runs/long
    python -m jaxlens.experiments.classical --smoke --out /tmp/smoke
    python -m jaxlens.experiments.classical --ablation --steps 0.5
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import shlex
import sys
import time

from jaxlens import compile_cache
from jaxlens.analysis.tolerance_spec import MAX_TRIALS
from jaxlens.design.spec import (
    FNUM_RANGE,
    FNUM_START,
    FOV_START,
    MAX_ASPHERE_TERMS,
    MAX_ELEMENTS,
    MAX_TRACK,
    SENSOR_DIAGONAL_RANGE,
)
from jaxlens.experiments.ablation_table import (
    build_table,
    check_columns,
    column_file,
    fmt,
    spec_data,
    write_column,
)
from jaxlens.experiments.classical_export import (
    CLEAR_APERTURE_MARGIN,
    evaluation_notes,
    with_clear_apertures,
)
from jaxlens.experiments.runfolder import (
    OneLineParser,
    RunFolder,
    UsageError,
    check_writable,
    comma_ints,
    fail,
    given_options,
)
from jaxlens.optics import checks

# Recipes of a single design run (--recipe): the paper's method as in Table 1's +both+mask
# column, or the stronger recipe of the +recipe column: a three times longer LM polish (the
# polish still lowers the RMS at 80 steps; measured in experiments/classical/RECIPE.md).
RECIPES = {"paper": {}, "strong": dict(polish_steps=240)}

ABLATION_COLUMNS = (
    ("baseline", dict(curriculum=False, regularize=False, mask=False)),
    ("+curriculum", dict(curriculum=True, regularize=False, mask=False)),
    ("+regularization", dict(curriculum=False, regularize=True, mask=False)),
    ("+both", dict(curriculum=True, regularize=True, mask=False)),
    ("+both+mask", dict(curriculum=True, regularize=True, mask=True)),
    # Issue 13's stronger recipe, a further column.
    ("+recipe", dict(curriculum=True, regularize=True, mask=True, **RECIPES["strong"])),
)
# Columns whose designs are exported (designs folder under --ablation-out).
EXPORTED_COLUMNS = {"+both+mask": "designs_paper_method", "+recipe": "designs"}


PAPER_TABLE1_FULL = {"valid_percent": 100.0, "rms_mean_um": 15.74, "rms_min_um": 12.50}

CONVENTION = (
    "f = (sensor half-diagonal)/tan(half FoV); EPD = f/F#; fields: 16x16 grid over the whole "
    "sensor rectangle (linspace(-1, 1, 16) per side, corners included), field angle tan(theta) "
    "= sensor position / f; RMS = polychromatic (F, d, C pooled) RMS radius about the centroid, "
    "21x21 pupil grid, rays aimed at the paraxial entrance pupil (ray aiming off); valid = no "
    "self-intersection over the clear apertures and >= 99% of the rays of every field reach "
    "the sensor; distortion = 100 (h - EFL tan theta)/(EFL tan theta) % of the real chief ray "
    "at theta_y = half FoV; exported clear apertures: the largest passing evaluated ray height "
    f"x (1 + {CLEAR_APERTURE_MARGIN:g}), the stop in front EPD/2")


MAX_DEVICES = 256  # XLA takes minutes to start 100 000 host devices


def _ensure_devices(n: int) -> None:
    """Ask XLA for ``n`` host devices (one per core) before the JAX backend starts.

    Importing jaxlens builds no arrays, so the backend is still unstarted here and
    ``XLA_FLAGS`` set now takes effect; a flag the user already set is kept.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if n <= 1 or "xla_force_host_platform_device_count" in flags:
        return
    if _backend_started():  # an embedding program started JAX first: use what is there
        import warnings

        warnings.warn(f"--devices {n}: JAX has already started, so the device count stays as "
                      f"it is (set XLA_FLAGS=--xla_force_host_platform_device_count={n})",
                      stacklevel=2)
        return
    os.environ["XLA_FLAGS"] = (flags + f" --xla_force_host_platform_device_count={n}").strip()


def _backend_started() -> bool:
    from jax._src import xla_bridge  # no public API tells whether the backend has started

    return xla_bridge.backends_are_initialized()


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="python -m jaxlens.experiments.classical",
        description="Ab initio curriculum design of the paper's classical lens (Table 1).")
    g = p.add_argument_group("design spec")
    g.add_argument("--fov", type=checks.cli_float, default=80.8, help="full diagonal FoV, degrees")
    g.add_argument("--fnum", type=checks.cli_float, default=2.0, help="F-number (EPD = f/F#)")
    g.add_argument("--sensor-diagonal", type=checks.cli_float, default=7.66, help="mm")
    g.add_argument("--elements", type=checks.cli_int, default=6, help="number of lens elements")
    g.add_argument("--materials", default=None,
                   help="comma-separated catalog names, one per element "
                        "(default E48R,OKP4 alternating); with --select-materials, the start")
    g.add_argument("--select-materials", default="fixed",
                   choices=("fixed", "continuous", "search"),
                   help="fixed: keep --materials; continuous: each element's (nd, Vd) is free "
                        "inside the hull of --material-catalogs until the polish, then snapped "
                        "to the nearest catalog material (glass-map metric) and polished; "
                        "search: the same, with each catalog material picked by the design "
                        "loss (geometry held) instead of the nearest")
    g.add_argument("--material-catalogs", default="PLASTICS",
                   help="comma-separated catalogs that --select-materials chooses from "
                        "(e.g. SCHOTT,CDGM for a glass design)")
    g.add_argument("--track", type=checks.cli_float, default=7.0, help="total track, mm (fixed)")
    g.add_argument("--bfl", type=checks.cli_float, default=0.8,
                   help="minimum last-surface-to-sensor clearance, mm")
    g.add_argument("--stop", type=checks.cli_int, default=0, help="elements in front of the stop")
    g.add_argument("--fov-start", type=checks.cli_float, default=None,
                   help=f"curriculum start FoV, at most --fov (default {FOV_START}°, or --fov "
                        f"if smaller)")
    g.add_argument("--fnum-start", type=checks.cli_float, default=None,
                   help=f"curriculum start F#, at least --fnum (default {FNUM_START}, or --fnum "
                        f"if larger)")
    g.add_argument("--asphere-terms", type=checks.cli_int,
                   default=6, help="even terms r^4 … per surface")
    r = p.add_argument_group("recipe")
    r.add_argument("--seeds", type=checks.cli_int, default=3, help="number of random starts")
    r.add_argument("--seed-list", default=None, help="explicit comma-separated seeds")
    r.add_argument("--first-seed", type=checks.cli_int, default=0, help="first seed of --seeds")
    r.add_argument("--recipe", default="strong", choices=tuple(RECIPES),
                   help="paper: the paper's method (Table 1's +both+mask column); strong: "
                        "with a 3x longer polish (the +recipe column)")
    r.add_argument("--steps", type=checks.cli_float,
                   default=1.0, help="scale every stage's step count")
    r.add_argument("--polish-steps", type=checks.cli_int, default=None,
                   help="polish iterations (overrides the --steps scaling of the polish)")
    r.add_argument("--solver", default="adam", choices=("adam", "lm", "lbfgsb"),
                   help="solver of the curriculum and fine-tuning stages")
    r.add_argument("--polish", default="lm", choices=("lm", "lm-optx", "lbfgsb", "none"),
                   help="polish solver after fine-tuning (lm: damped least squares with a "
                        "jacfwd Jacobian; lm-optx: optimistix LevenbergMarquardt)")
    r.add_argument("--loss", default="ray", choices=("ray", "image"),
                   help="fine-tuning loss: ray-based RMS spot, or image-based through "
                        "jaxlens.imaging.render with distortion relaxation")
    r.add_argument("--no-curriculum", action="store_true", help="stay at the full spec")
    r.add_argument("--no-regularize", action="store_true", help="switch the regularizers off")
    r.add_argument("--tolerance-aware", type=checks.cli_int, default=0, metavar="K",
                   help="design against the mean loss over K fixed manufacturing errors "
                        "(±0.5%% radius, ±0.02 mm gaps; jaxlens.design.robust); 0 = nominal")
    r.add_argument("--population", type=checks.cli_int, default=1, metavar="P",
                   help="random starts per design: all P run the curriculum and fine-tuning, "
                        "the best continues to the polish (design s draws starts s·P … "
                        "s·P+P−1)")
    r.add_argument("--no-mask", action="store_true", help="switch the re-weighting mask off")
    r.add_argument("--float32", action="store_true",
                   help="design in float32 (default float64: near-TIR rays rounded to valid in "
                        "float32 can overflow the gradient and lose a start)")
    r.add_argument("--devices", type=checks.cli_int, default=min(os.cpu_count() or 1, MAX_DEVICES),
                   help="XLA host devices to shard seeds over (default: CPU cores)")
    o = p.add_argument_group("output")
    o.add_argument("--out", default="runs/classical", help="output folder")
    o.add_argument("--overwrite", action="store_true",
                   help="replace an earlier run in --out, or with --ablation the columns "
                        "already in --ablation-out (default: refuse)")
    o.add_argument("--no-plots", action="store_true", help="skip figures and rendering")
    o.add_argument("--no-render", action="store_true", help="skip the rendered test scene")
    o.add_argument("--tolerance-trials", type=checks.cli_int, default=200,
                   help="Monte-Carlo trials of the tolerance analysis of the best design "
                        "(tolerance.json, tolerance_rms.png; 0 skips it)")
    o.add_argument("--tolerance-threshold", type=checks.cli_float, default=6.0,
                   help="yield threshold of the tolerance analysis: mean RMS after "
                        "refocusing, µm")
    o.add_argument("--smoke", action="store_true",
                   help="a few steps, one seed, coarse sampling (CI check of the pipeline)")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    a = p.add_argument_group("ablation (Table 1)")
    a.add_argument("--ablation", action="store_true", help="run the Table 1 columns")
    a.add_argument("--ablation-seeds", type=checks.cli_int,
                   default=20, help="random starts per column")
    a.add_argument("--ablation-out", default="experiments/classical", help="results folder")
    a.add_argument("--columns", default=None,
                   help="comma-separated subset of columns (default: all five)")
    return p


def check_args(args, given=None) -> None:
    """Refuse any option outside its range (ValueError naming option, value, range, unit)."""
    from jaxlens.design.materials import CatalogRegion
    from jaxlens.design.multistart import MAX_ROBUST_DRAWS, MAX_STEP_SCALE
    from jaxlens.experiments.tolerance import check_threshold

    w, n = "design", checks.number
    n(args.fov, "--fov", w, lo=0, hi=180, lo_open=True, hi_open=True, unit="deg")
    # The spec's ranges (jaxlens.design.spec says why), named by the flags the user typed.
    n(args.fnum, "--fnum", w, lo=FNUM_RANGE[0], hi=FNUM_RANGE[1], unit="(F-number f/EPD)")
    # An explicit curriculum start beyond the target is refused (defaults follow --fov/--fnum).
    if args.fov_start is not None:
        n(args.fov_start, "--fov-start", w, lo=0, hi=args.fov, lo_open=True,
          unit="deg (at most --fov)")
    if args.fnum_start is not None:
        n(args.fnum_start, "--fnum-start", w, lo=args.fnum, hi=FNUM_RANGE[1],
          unit="(F-number, at least --fnum)")
    n(args.sensor_diagonal, "--sensor-diagonal", w, lo=SENSOR_DIAGONAL_RANGE[0],
      hi=SENSOR_DIAGONAL_RANGE[1], unit="mm")
    n(args.elements, "--elements", w, lo=1, hi=MAX_ELEMENTS, integer=True, unit="lens elements")
    n(args.track, "--track", w, lo=0, hi=MAX_TRACK, lo_open=True, unit="mm")
    n(args.bfl, "--bfl", w, lo=0, lo_open=True, unit="mm")
    n(args.stop, "--stop", w, lo=0, hi=args.elements, integer=True, unit="elements")
    n(args.asphere_terms, "--asphere-terms", w, lo=0, hi=MAX_ASPHERE_TERMS, integer=True,
      unit="terms per surface")
    n(args.seeds, "--seeds", w, lo=1, hi=checks.MAX_DESIGNS, integer=True, unit="designs")
    n(args.first_seed, "--first-seed", w, lo=0, integer=True)
    n(args.steps, "--steps", w, lo=0, lo_open=True, hi=MAX_STEP_SCALE, unit="(scale of every "
      f"stage's steps, at most {checks.MAX_STEPS} steps a stage)")
    if args.polish_steps is not None:
        n(args.polish_steps, "--polish-steps", w, lo=0, hi=checks.MAX_STEPS, integer=True,
          unit="steps")
    n(args.devices, "--devices", w, lo=1, hi=MAX_DEVICES, integer=True, unit="host devices")
    n(args.ablation_seeds, "--ablation-seeds", w, lo=1, hi=checks.MAX_DESIGNS, integer=True,
      unit="designs per column")
    # Before: 10**7 trials were refused after the designs, and 10**6 draws ran out of memory.
    n(args.tolerance_trials, "--tolerance-trials", w, lo=0, hi=MAX_TRIALS, integer=True)
    n(args.tolerance_aware, "--tolerance-aware", w, lo=0, hi=MAX_ROBUST_DRAWS, integer=True)
    n(args.population, "--population", w, lo=1, hi=64, integer=True, unit="starts per design")
    if (bad := check_threshold(args.tolerance_threshold, "--tolerance-threshold")) is not None:
        raise ValueError(f"{w}: {bad}")  # before: > 0 only (1e300 µm: every trial passed)
    for flag, text in (("--materials", args.materials),
                       ("--material-catalogs", args.material_catalogs)):
        # An empty entry was dropped: "E48R,,OKP4" gave 2 materials for 3 elements.
        if text is not None and not all(p.strip() for p in text.split(",")):
            raise ValueError(f"{w}: {flag} must be comma-separated names without an empty "
                             f"one, got {text!r}")
    if args.seed_list is not None:
        try:  # ASCII digits (str.isdigit took "١", read as 1)
            parts = [p for p in comma_ints(args.seed_list) if p >= 0]
        except ValueError:
            parts = []
        if len(parts) != len(args.seed_list.split(",")):
            raise ValueError(f"{w}: --seed-list must be comma-separated whole numbers >= 0, got "
                             f"{args.seed_list!r}")
        if len(set(parts)) < len(parts):  # a repeat is the same design twice
            raise ValueError(f"{w}: --seed-list needs distinct seeds, got {args.seed_list!r}")
    from jaxlens.design.init import MAX_SEED  # the design package: imported by the spec check

    top = args.first_seed + args.ablation_seeds - 1 if args.ablation else max(_seeds(args))
    last = top * args.population + args.population - 1
    if last > MAX_SEED:  # design() refused it once the run folder existed
        given_by = ("--seed-list" if args.seed_list is not None and not args.ablation else
                    "--first-seed and --ablation-seeds" if args.ablation else
                    "--first-seed and --seeds")
        raise ValueError(f"{w}: the seeds ({given_by}, largest {top}; with --population "
                         f"{args.population}) draw random starts up to {last}; seeds must "
                         f"keep them in [0, {MAX_SEED}] (seed × --population + start)")
    try:  # checked even when unused (--select-materials fixed): a typo must not go unseen
        CatalogRegion.of(_catalogs(args))
    except ValueError as e:
        raise ValueError(f"{w}: --material-catalogs {args.material_catalogs!r}: {e}") from e
    _no_ignored_options(args, w, given)
    if args.tolerance_aware and args.loss == "image":
        # Before: the image fine-tuning (the last stage: no polish with it) was nominal, so
        # the design ended at the nominal optimum without a word.
        raise ValueError(f"{w}: --tolerance-aware {args.tolerance_aware} averages the ray loss "
                         f"over manufacturing errors, but --loss image fine-tunes on the "
                         f"nominal image loss (the last stage: no polish follows), undoing it; "
                         f"give one of them")
    if args.columns is not None:
        names = [c for c, _ in ABLATION_COLUMNS]
        given = [c.strip() for c in args.columns.split(",")]
        bad = [c for c in given if c not in names]
        if bad or not args.columns.strip():
            raise ValueError(f"{w}: --columns takes names from {names}, got {args.columns!r}")
        if len(set(given)) < len(given):  # one column designed twice, one table row
            raise ValueError(f"{w}: --columns names a column more than once: {args.columns!r}")


def _no_ignored_options(args, w: str, given=None) -> None:
    """Refuse an option that another option overrides: it would be ignored without a word.
    ``given``: the options the command line gives (``runfolder.given_options``); without
    it, those whose values differ from the defaults (an option given at its default value,
    ``--seeds 3``, then passes)."""
    default = vars(build_parser().parse_args([]))
    rules = (  # --ablation: its columns set the recipe and switches, --ablation-seeds the seeds
        (args.ablation, "--ablation", ("seeds", "seed_list", "recipe", "no_curriculum",
                                       "no_regularize", "no_mask", "loss", "out", "no_plots",
                                       "no_render", "tolerance_trials", "tolerance_threshold")),
        (args.no_curriculum and not args.ablation, "--no-curriculum (no sine path)",
         ("fov_start", "fnum_start")),
        (args.seed_list is not None, "--seed-list", ("seeds", "first_seed")),
        # --recipe sets the polish's steps only (RECIPES): with no polish, or its steps
        # given, the recipe asked for was dropped ("--recipe strong --polish none").
        (args.smoke and not args.ablation, "--smoke", ("seeds", "steps", "polish_steps",
                                                        "recipe")),
        (args.polish == "none", "--polish none", ("polish_steps", "recipe")),
        (args.polish_steps is not None, "--polish-steps (the recipe's only setting)",
         ("recipe",)),
        # the catalogs are read only when materials are chosen (continuous or search)
        (args.select_materials == "fixed", "--select-materials fixed", ("material_catalogs",)),
        (args.loss == "image", "--loss image", ("polish_steps", "recipe")),
        (not args.ablation, "no --ablation", ("columns", "ablation_seeds", "ablation_out")),
    )
    for active, why, names in rules:
        ignored = ["--" + n.replace("_", "-") for n in names
                   if (n in given if given is not None else getattr(args, n) != default[n])]
        if active and ignored:
            raise ValueError(f"{w}: {', '.join(ignored)} would be ignored with {why}; leave "
                             f"{'it' if len(ignored) == 1 else 'them'} out")


SPEC_WORDS = {r"^DesignSpec: ": "", r"\btotal_track\b": "--track",
              r"\bsensor_diagonal\b": "--sensor-diagonal", r"(?<![-\w])(fov|fnum|bfl)\b": r"--\1",
              r"^(\d+) elements need (\d+) materials": r"--elements \1 needs \2 --materials",
              r"^materials\[(\d+)\]": lambda m: f"--materials entry {int(m[1]) + 1}",
              r"(\d+) element\(s\)": r"\1 element(s) (--elements)", "° field": "° field (--fov)",
              r"(F/[\d.]+)(?= is| \(tan)": r"\1 (--fnum)"}


def spec_message(text: str) -> str:
    """A ``DesignSpec`` refusal in the command line's words: the flags the user typed, not
    the spec's fields (``total_track`` → ``--track``, ``F/2`` → ``F/2 (--fnum)``)."""
    for pattern, new in SPEC_WORDS.items():
        text = re.sub(pattern, new, text)
    return text


def spec_from_args(args):
    from jaxlens.design.spec import DesignSpec

    kw = dict(fov=args.fov, fnum=args.fnum, sensor_diagonal=args.sensor_diagonal,
              n_elements=args.elements, total_track=args.track, bfl=args.bfl, stop=args.stop,
              fov_start=args.fov_start, fnum_start=args.fnum_start,  # None: DesignSpec's rule
              asphere_terms=args.asphere_terms)
    if args.materials:
        kw["materials"] = tuple(m.strip() for m in args.materials.split(",") if m.strip())
    elif args.elements != 6:
        kw["materials"] = tuple(("E48R", "OKP4")[i % 2] for i in range(args.elements))
    try:
        return DesignSpec(**kw)
    except (ValueError, TypeError) as e:  # quoted total_track where the user typed --track
        raise ValueError(f"design: {spec_message(str(e))}") from e


def _catalogs(args) -> tuple[str, ...]:
    return tuple(c.strip() for c in args.material_catalogs.split(",") if c.strip())


def config_from_args(args, recipe: str | None = None):
    """The design recipe of the options (``recipe`` overrides ``--recipe``)."""
    from jaxlens.design.multistart import DesignConfig

    cfg = DesignConfig(**RECIPES[args.recipe if recipe is None else recipe],
        curriculum=not args.no_curriculum, regularize=not args.no_regularize,
        mask=not args.no_mask, solver=args.solver,
        polish="lm" if args.polish == "none" else args.polish, float64=not args.float32,
        materials=args.select_materials, material_catalogs=_catalogs(args),
        tolerance_trials=args.tolerance_aware, population=args.population)
    if args.polish == "none":
        cfg = dataclasses.replace(cfg, polish_steps=0)
    if args.smoke:
        cfg = dataclasses.replace(cfg, n_fields=5, rings=2, steps=6, final_steps=6,
                                  polish_steps=0, epoch=6, log_every=3)
    elif args.steps != 1.0:
        cfg = cfg.scaled(args.steps)
    if args.polish_steps is not None and not args.smoke and args.polish != "none":
        cfg = dataclasses.replace(cfg, polish_steps=args.polish_steps)
    return cfg


def _seeds(args) -> list[int]:
    if args.seed_list:
        return list(comma_ints(args.seed_list))  # checked by check_args
    n = 1 if args.smoke else args.seeds
    return list(range(args.first_seed, args.first_seed + n))


def finished_lens(result, i: int, spec, grid: int = 16):
    """Design i as a float64 lens for export: each asphere on its closest conic (``optics.
    rebase``: the sag to 1e-8 mm, for tools that start Newton at the base conic), then that
    lens's clear semi-diameters (set only before it, they clipped rim rays the refit moved;
    ``classical_export``: with a margin), and the notes that say how the run evaluates it
    (on a ``grid`` × ``grid`` field grid)."""
    from jaxlens.optics.rebase import rebase_conics

    lens = with_clear_apertures(rebase_conics(with_clear_apertures(result.lens(i), spec)), spec)
    return dataclasses.replace(lens, description=evaluation_notes(spec, grid))


def write_design_outputs(lens, ev, spec, out, *, history=None, plots=True, render=True,
                         smoke=False, log=print) -> dict:
    """Lens files, figures and the rendered scene of one design; returns the file list."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    import jaxlens
    from jaxlens import plot
    from jaxlens.io import images

    files = {}
    os.makedirs(out, exist_ok=True)
    files["lens_json"] = jaxlens.save(lens, os.path.join(out, "lens.json"))
    files["lens_zmx"] = jaxlens.save(lens, os.path.join(out, "lens.zmx"))
    if not plots:
        return files
    t0 = time.perf_counter()
    figs = {
        "layout": lambda: plot.plot_layout(lens, title=f"{lens.name}: {spec.fov}°, "
                                           f"F/{spec.fnum}"),
        "spots": lambda: plot.plot_spots(lens, rings=4 if smoke else 12),
        "rms_map": lambda: plot.plot_rms_map(ev.rms_um, spec.sensor_size),
        "mtf": lambda: plot.plot_mtf(
            lens, frequencies=np.linspace(0, 250, 6 if smoke else 26)),
    }
    if history is not None:
        figs["progress"] = lambda: plot.plot_progress(history)
    for name, make in figs.items():
        files[name] = plot.save(make(), os.path.join(out, f"{name}.png"))
    if render:
        rows = 64 if smoke else 256
        sensor = jaxlens.Sensor(resolution=(rows, rows),
                                pixel_size=jnp.asarray(spec.sensor_size[0] / rows))
        scene = images.scene("astronaut", (rows, rows))  # linear light
        img = jaxlens.render(lens.astype(jnp.float32), jnp.asarray(scene),
                             spp=4 if smoke else 32, key=jax.random.PRNGKey(0),
                             sensor=sensor, relative_illumination=False)
        shown = [images.linear_to_srgb(np.clip(x, 0, 1)) for x in (scene, np.asarray(img))]
        both = np.concatenate(shown, axis=1)
        files["render"] = plot.save(plot.plot_image(both, title="scene | rendered through "
                                                    "the design (with its distortion)"),
                                    os.path.join(out, "render.png"))
    log(f"figures and render: {time.perf_counter() - t0:.1f} s")
    return files


def _on_axis_rms_um(lens, spec, n_fields: int = 1) -> float:
    """On-axis polychromatic RMS spot radius (µm) as ``evaluate`` defines it, from n_fields
    copies of the field and a float64 EPD: the evaluation's compiled ``rms_spot`` serves."""
    import equinox as eqx
    import jax.numpy as jnp

    from jaxlens.analysis import spots

    lens = eqx.tree_at(lambda x: x.epd, lens.astype(jnp.float64), jnp.float64(spec.epd))
    r = spots.rms_spot(lens, jnp.zeros((n_fields, 2)), jnp.asarray(spec.wavelengths))
    return float(r.polychromatic[0]) * 1e3


def run_design(args, argv) -> dict:
    t_start = time.perf_counter()
    spec = spec_from_args(args)
    config = config_from_args(args)
    seeds = _seeds(args)
    folder = RunFolder(args.out, overwrite=args.overwrite)
    out = folder.start()  # written here, renamed to --out when the run is complete
    try:
        return _design_into(args, argv, spec, config, seeds, folder, out, t_start)
    except BaseException:
        folder.abandon()
        raise


def _design_into(args, argv, spec, config, seeds, folder, out, t_start) -> dict:
    import jax
    import numpy as np

    from jaxlens.design import evaluate, multistart

    log = print
    log(f"design: {spec.n_elements} elements {spec.materials}, {spec.fov}° FoV, F/{spec.fnum},"
        f" sensor diagonal {spec.sensor_diagonal} mm -> f = {spec.focal_length:.4f} mm, "
        f"EPD = {spec.epd:.4f} mm; seeds {seeds} on {len(jax.devices())} device(s)")
    if args.loss == "image":
        config = dataclasses.replace(config, polish_steps=0)
        log("image-based loss: fine-tuning renders the test scene through the lens")
    t0 = time.perf_counter()
    result = multistart.design(spec, seeds, config, progress=not args.quiet,
                               devices=jax.devices()[: max(1, args.devices)],
                               image_loss=args.loss == "image", on_nonfinite="drop")
    t_design = time.perf_counter() - t0
    t0 = time.perf_counter()
    grid = 4 if args.smoke else 16
    evals = [evaluate.evaluate(result.lens(i), spec, n=grid)
             for i in range(len(seeds))]
    t_eval = time.perf_counter() - t0
    os.makedirs(os.path.join(out, "seeds"), exist_ok=True)
    import jaxlens

    for i, s in enumerate(seeds):
        jaxlens.save(finished_lens(result, i, spec, grid),
                     os.path.join(out, "seeds", f"seed_{s}.json"))
    failed = result.history.failed
    # A start that went non-finite is frozen at its last finite state; it never wins.
    order = sorted(range(len(seeds)), key=lambda i: (seeds[i] in failed, not evals[i].valid,
                                                     evals[i].rms_mean_um))
    best = order[0]
    lens = finished_lens(result, best, spec, grid)
    # The summary's numbers are the exported lens's (lens.json, lens.zmx), which the conic
    # rebase moved from the design's by up to 1e-8 mm in sag (the chief ray by 2e-7 mm):
    # every number of "best" is then what a re-read of lens.zmx gives. per_seed keeps the
    # designs' own evaluations, which ranked them.
    exported = evaluate.evaluate(lens, spec, n=grid)
    files = write_design_outputs(lens, exported, spec, out, history=result.history,
                                 plots=not args.no_plots, render=not args.no_render,
                                 smoke=args.smoke, log=log)
    t_tol = 0.0
    tolerance = None
    if args.tolerance_trials > 0:
        from jaxlens.experiments import tolerance as tol_exp

        t0 = time.perf_counter()
        # Sensitivities for every parameter from one gradient; the ±tolerance re-trace
        # check only for the 16 largest (python -m jaxlens.experiments.tolerance checks all).
        rep = tol_exp.analyse_design(
            lens, spec, trials=min(args.tolerance_trials, 4) if args.smoke
            else args.tolerance_trials, threshold_um=args.tolerance_threshold,
            grid=4 if args.smoke else 16, fd_check=4 if args.smoke else 16, log=log)
        files.update(tol_exp.write_report(rep, out, plots=not args.no_plots))
        t_tol = time.perf_counter() - t0
        tolerance = {**{k: rep["monte_carlo"][k] for k in (
            "trials", "rms_p50_um", "rms_p90_um", "yield", "threshold_um", "mtf_p50",
            "mtf_frequency_cycles_per_mm")}, "worst_parameter": rep["sensitivity"][0]["parameter"],
            "nominal_refocus_mm": rep["compensator"]["nominal_refocus_mm"]}
    on_axis_um = _on_axis_rms_um(lens, spec, exported.rms_um.size)
    loss_first = [float(np.nanmean(h[0])) for h in result.history.loss if len(h)]
    rms_hist = [h for h in result.history.spot_rms if len(h)]
    ev = exported
    v_rms = [e.rms_mean_um for e in evals if e.valid]
    summary = {
        "command": "python -m jaxlens.experiments.classical " + shlex.join(argv),
        "convention": CONVENTION,
        "spec": dataclasses.asdict(spec),
        "nominal_focal_length_mm": spec.focal_length, "epd_mm": spec.epd,
        "config": dataclasses.asdict(config),
        "seeds": seeds, "best_seed": seeds[best],
        "best": {**ev.summary(), "rms_min_um": float(np.min(ev.rms_um)),
                 "rms_on_axis_um": on_axis_um,
                 "rms_median_um": float(np.median(ev.rms_um)), "n_fields": int(ev.rms_um.size),
                 # per field of the grid, (θx, θy) deg: what a re-evaluation compares field by field
                 "field_angles_deg": evaluate.sensor_field_grid(spec, grid)[0].tolist(),
                 "rms_um_per_field": ev.rms_um.tolist(),
                 "valid_fraction_per_field": ev.valid_fraction.tolist()},
        "material_selection": {
            "mode": config.materials,
            "catalogs": list(config.material_catalogs) if config.materials != "fixed" else None,
            "best": list(result.material_names(best)),
            "continuous_nd_vd": (None if result.continuous_materials is None else
                                 np.asarray(result.continuous_materials).tolist()),
        },
        "per_seed": [{"seed": s, "start": result.starts[i], "solver_status": result.status[i],
                      **e.summary(), "rms_min_um": float(np.min(e.rms_um)),
                      "materials": list(result.material_names(i))}
                     for i, (s, e) in enumerate(zip(seeds, evals, strict=True))],
        "valid_designs": int(sum(e.valid for e in evals)),
        "valid_designs_rms_mean_um": float(sum(v_rms) / len(v_rms)) if v_rms else None,
        "valid_designs_rms_min_um": float(min(v_rms)) if v_rms else None,
        "loss_first_step": loss_first[0] if loss_first else None,
        "spot_rms_first_um": float(np.min(rms_hist[0][0]) * 1e3) if rms_hist else None,
        "spot_rms_last_um": float(np.min(rms_hist[-1][-1]) * 1e3) if rms_hist else None,
        "tolerance": tolerance,
        "stage_seconds": dict(zip(result.history.stages, result.history.seconds, strict=True)),
        "seconds": {"design": t_design, "evaluation": t_eval, "tolerance": t_tol,
                    "total": time.perf_counter() - t_start}, "devices": len(jax.devices()),
        "files": {k: (folder.final_path(v) if isinstance(v, str)
                      else [folder.final_path(x) for x in v]) for k, v in files.items()},
    }
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2, default=float)
    out = folder.finish()
    b = summary["best"]
    log(f"best seed {seeds[best]}: {b['n_fields']}-field RMS mean {b['rms_mean_um']:.2f} µm, "
        f"min {b['rms_min_um']:.2f} µm, max {b['rms_max_um']:.2f} µm, on axis "
        f"{b['rms_on_axis_um']:.2f} µm; "
        f"{'valid' if ev.valid else 'INVALID'} ({ev.geometry}; min ray fraction "
        f"{b['min_valid_fraction']:.3f})")
    log(f"materials ({config.materials}): {', '.join(result.material_names(best))}")
    log(f"paraxial EFL {ev.efl:.4f} mm (nominal f {spec.focal_length:.4f}), paraxial F/"
        f"{ev.fnum:.3f} (nominal F/{spec.fnum}), BFL {ev.bfl:.3f} mm, track "
        f"{ev.total_track:.3f} mm, distortion at {spec.half_fov}° {ev.distortion_percent:.1f} %")
    avg = fmt(summary["valid_designs_rms_mean_um"])
    low = fmt(summary["valid_designs_rms_min_um"])
    log(f"{summary['valid_designs']}/{len(seeds)} seeds valid (their average RMS {avg} µm, "
        f"best {low} µm); per seed mean RMS (µm): " +
        ", ".join(f"{s}:{e.rms_mean_um:.2f}{'' if e.valid else '(invalid)'}"
                  for s, e in zip(seeds, evals, strict=True)))
    log(f"wall time {summary['seconds']['total']:.1f} s (design {t_design:.1f} s); "
        f"outputs in {out}")
    return summary


def run_ablation(args, argv) -> dict:
    import jax
    import numpy as np

    import jaxlens
    from jaxlens.design import evaluate, multistart

    spec = spec_from_args(args)
    base = config_from_args(args, recipe="paper")  # the columns say what they add
    seeds = list(range(args.first_seed, args.first_seed + args.ablation_seeds))
    out = args.ablation_out
    os.makedirs(os.path.join(out, "columns"), exist_ok=True)
    names = [c for c, _ in ABLATION_COLUMNS]
    wanted = wanted_columns(args)
    unknown = [c for c in wanted if c not in names]
    if unknown:
        raise ValueError(f"--columns: unknown column(s) {unknown}; use {names}")
    command = "python -m jaxlens.experiments.classical " + shlex.join(argv)
    for name in wanted:  # in the order asked for
        switches = dict(ABLATION_COLUMNS)[name]
        cfg = dataclasses.replace(base, **switches)
        if args.smoke:  # the smoke's sampling and steps, one polish step where there is one
            cfg = dataclasses.replace(cfg, n_fields=base.n_fields, polish_steps=min(
                cfg.polish_steps, 1))
        elif "polish_steps" in switches and args.steps != 1.0:  # --steps scales it too
            cfg = dataclasses.replace(cfg, polish_steps=max(1, round(switches["polish_steps"] *
                                                                     args.steps)))
        print(f"== {name}: {switches}, {len(seeds)} seeds", flush=True)
        t0 = time.perf_counter()
        res = multistart.design(spec, seeds, cfg, progress=not args.quiet,
                                devices=jax.devices()[: max(1, args.devices)],
                                on_nonfinite="drop")
        wall = time.perf_counter() - t0
        evs = [evaluate.evaluate(res.lens(i), spec) for i in range(len(seeds))]
        failed = res.history.failed
        for s, e in zip(seeds, evs, strict=True):
            if s in failed:  # a start that went non-finite is a failed design
                e.valid = False
                e.geometry = f"{failed[s]}; frozen there ({e.geometry})"
        no_si = [not e.self_intersection and s not in failed
                 for s, e in zip(seeds, evs, strict=True)]
        valid = [e.valid for e in evs]
        rms = [e.rms_mean_um for e, v in zip(evs, valid, strict=True) if v]
        col = {
            "command": command, "switches": switches, "spec": spec_data(spec),
            "config": dataclasses.asdict(cfg),
            "seeds": seeds, "devices": len(jax.devices()),
            "no_self_intersection_percent": 100.0 * float(np.mean(no_si)),
            "valid_percent": 100.0 * float(np.mean(valid)),
            "rms_mean_um": float(np.mean(rms)) if rms else None,
            "rms_min_um": float(np.min(rms)) if rms else None,
            "rms_max_um": float(np.max(rms)) if rms else None,
            "non_finite_seeds": {str(k): v for k, v in failed.items()},
            "wall_seconds": wall, "seconds_per_design": wall / len(seeds),
            "load_average": os.getloadavg()[0],
            "stage_seconds": dict(zip(res.history.stages, res.history.seconds, strict=True)),
            "per_seed": [{"seed": s, "solver_status": st, **e.summary()}
                         for s, st, e in zip(seeds, res.status, evs, strict=True)],
        }
        if name in EXPORTED_COLUMNS:
            folder = os.path.join(out, EXPORTED_COLUMNS[name])
            os.makedirs(folder, exist_ok=True)
            for i, s in enumerate(seeds):
                jaxlens.save(finished_lens(res, i, spec), os.path.join(folder, f"seed_{s}.zmx"))
        print(f"{name}: no self-intersection {col['no_self_intersection_percent']:.0f} %, valid "
              f"{col['valid_percent']:.0f} %, RMS mean {col['rms_mean_um']} µm, min "
              f"{col['rms_min_um']} µm, {col['seconds_per_design']:.1f} s/design", flush=True)
        write_column(out, name, col)
        build_table(out, spec, ABLATION_COLUMNS, CONVENTION, PAPER_TABLE1_FULL)
    return build_table(out, spec, ABLATION_COLUMNS, CONVENTION, PAPER_TABLE1_FULL)


def wanted_columns(args) -> list[str]:
    """The ablation columns this run designs, in the order asked for (all by default)."""
    if not args.columns:
        return [c for c, _ in ABLATION_COLUMNS]
    return [c.strip() for c in args.columns.split(",")]


def check_ablation_out(args, spec) -> None:
    """Refuse an unusable ``--ablation-out``, or one that holds a column this run would
    replace (unless ``--overwrite``): columns run separately share the folder and its table,
    so a column already there is kept unless asked; it must be readable and of ``spec``."""
    out = args.ablation_out
    if os.path.exists(out) and not os.path.isdir(out):
        raise UsageError(f"--ablation-out {out} is a file, not a folder")
    check_writable(out, "--ablation-out")
    there = [c for c in wanted_columns(args) if os.path.exists(column_file(out, c))]
    if there and not args.overwrite:
        raise UsageError(f"--ablation-out {args.ablation_out} holds the column(s) "
                         f"{', '.join(there)} of an earlier run; give --overwrite to replace "
                         f"them, or choose another folder")
    try:
        check_columns(out, spec, [os.path.abspath(column_file(out, c)) for c in there])
    except ValueError as e:
        raise UsageError(f"--ablation-out: {e}") from None


def main(argv: list[str] | None = None) -> int:
    command_line = argv is None  # then compiled programs are kept (jaxlens.compile_cache)
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    # Validate every option, the spec and the output folder before anything heavy. The
    # device count is set once the options are known and before any array exists.
    try:
        check_args(args, given_options(build_parser, argv))
        _ensure_devices(args.devices)
        spec = spec_from_args(args)
        if args.ablation:
            check_ablation_out(args, spec)
        else:
            RunFolder(args.out, overwrite=args.overwrite)
    except ValueError as e:
        return fail(parser.prog, e)
    import jax

    jax.config.update("jax_enable_x64", True)
    if command_line:
        compile_cache.enable()
    try:
        if args.ablation:
            run_ablation(args, argv)
        else:
            run_design(args, argv)
    except UsageError as e:  # e.g. --out refused by the file system when the run starts
        return fail(parser.prog, e)
    return 0


if __name__ == "__main__":
    sys.exit(main())
