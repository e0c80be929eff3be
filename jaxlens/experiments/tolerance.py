"""Tolerance analysis of a classical design: ``tolerance.json`` and the RMS histogram.

``python -m jaxlens.experiments.tolerance DESIGN --out DIR`` analyses a design file (``.zmx``
or jaxlens JSON) of the classical spec (the CLI's defaults: 80.8°, F/2.0, 7.66 mm sensor
diagonal, F/d/C) with ``jaxlens.analysis.tolerance``: sensitivities from one reverse-mode
pass checked against finite differences, a vmapped Monte-Carlo with the back-focus
compensator, RMS percentiles, the MTF at the sensor's Nyquist frequency and the yield. It
writes ``DIR/tolerance.json`` and ``DIR/tolerance_rms.png`` (refusing, before any work, to
replace those of an earlier run unless ``--overwrite`` is given). ``python -m
jaxlens.experiments.classical`` calls :func:`analyse_design` for its best design.

The metric is Table 1's: the mean over the 16 × 16 sensor grid of the polychromatic RMS spot
radius (``jaxlens.design.evaluate``), computed on the grid's 36 distinct fields. ``--decenter
MM`` and ``--tilt DEG`` (default 0: off; at most 0.1 mm and 1°, ``FLAG_RANGES``) add element
decenter and tilt tolerances (``jaxlens.analysis.tolerance_rigid``); a moved element breaks
the rotational symmetry, so the metric is then computed on all 256 fields (about 7× the
tracing).

Example (the recorded ``experiments/classical/tolerance.json``):
    python -m jaxlens.experiments.tolerance experiments/classical/designs/seed_13.zmx \\
        --out experiments/classical --overwrite
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shlex
import sys
import time

from jaxlens.experiments.runfolder import OneLineParser, check_writable, fail
from jaxlens.optics import checks

DEFAULT_TRIALS = 200
DEFAULT_THRESHOLD_UM = 6.0
THRESHOLD_RANGE_UM = (0.01, 1000.0)
"""Accepted yield thresholds (µm of mean RMS spot radius after refocusing) of this CLI and of
the classical CLI's ``--tolerance-threshold``: a designed lens of these specs has a few µm;
below 0.01 µm no trial passes (0.006 is a threshold given in mm), and above 1000 µm (1 mm, a
blur across an eighth of a 7.66 mm sensor) every trial passes: the yield then says nothing
(``--threshold 1e300`` was analysed)."""


def check_threshold(value: float, option: str) -> ValueError | None:
    """The refusal of a yield threshold (µm) outside ``THRESHOLD_RANGE_UM``, or None."""
    lo, hi = THRESHOLD_RANGE_UM
    if math.isfinite(value) and lo <= value <= hi:
        return None
    hint = (f" (was it given in mm? {value:g} mm is {value * 1e3:g} µm)"
            if math.isfinite(value) and 0 < value < lo else "")
    return ValueError(f"{option} must be a finite number in [{lo:g}, {hi:g}] µm (the mean RMS "
                      f"spot radius after refocusing a trial must meet; the designs have a few "
                      f"µm), got {value:g}{hint}")

FLAG_RANGES = {
    "decenter": (0.1, "mm", "an element decenter tolerance: a lens of this spec, a few mm "
                 "across, is centred to 0.002-0.02 mm, more than 0.1 mm off is a misassembled "
                 "lens; 5 µm is 0.005 mm"),
    "tilt": (1.0, "deg", "an element tilt tolerance: 1-10 arcmin, 0.02-0.2 deg, is usual; "
             "more than 1 deg is a misassembled lens"),
}
"""Upper bounds (value, unit, reason) of the CLI's ``--decenter`` and ``--tilt``, stricter
than ``Tolerances``' (which takes any lens, tilt below 90°): this tool analyses designs of
the classical spec (a 7.66 mm-diagonal sensor)."""


def check_design(lens, spec) -> None:
    """Refuse a lens this analysis would misdescribe: it is run at the classical spec's
    entrance pupil, and the 16 × 16 grid is folded onto 36 fields by rotational symmetry."""
    from jaxlens.design.spec import DesignSpec
    from jaxlens.optics.lens import Lens
    from jaxlens.optics.surfaces import EvenAsphere, Standard

    for arg, v, kind in (("lens", lens, Lens), ("spec", spec, DesignSpec)):
        if not isinstance(v, kind):  # before: AttributeError 'NoneType' ... 'epd'
            raise TypeError(f"check_design: {arg} must be a {kind.__module__}.{kind.__name__}, "
                            f"got {type(v).__name__}")
    epd = float(lens.epd)
    if not math.isclose(epd, spec.epd, rel_tol=1e-6):
        raise ValueError(
            f"the design's entrance pupil is {epd:g} mm and the classical spec's "
            f"{spec.epd:g} mm (F/{spec.fnum:g}): this tool analyses designs of the classical "
            f"spec; jaxlens.analysis.tolerance.ToleranceModel takes any lens")
    kinds = {type(s).__name__ for s in (*lens.surfaces, lens.image)
             if type(s) not in (Standard, EvenAsphere)}
    if kinds or lens.apertures:
        what = ", ".join(sorted(kinds)) or "non-circular or decentered apertures"
        raise ValueError(
            f"the design has {what}: the analysis folds the sensor grid onto its distinct "
            f"fields by rotational symmetry, which needs standard and even-asphere surfaces "
            f"and circular apertures; jaxlens.analysis.tolerance.ToleranceModel takes any "
            f"lens with its own fields")


def design_model(lens, spec, grid: int = 16, tolerances=None):
    """The ``ToleranceModel`` of a design at the classical spec's pupil (``check_design``
    first): a ``ValueError`` here (a decenter beyond the lens's clear radius) comes before
    any analysis."""
    import equinox as eqx
    import jax.numpy as jnp
    import numpy as np

    from jaxlens.analysis import tolerance as tol_mod
    from jaxlens.design.evaluate import sensor_field_grid

    check_design(lens, spec)
    lens = lens.astype(jnp.float64)
    lens = eqx.tree_at(lambda x: x.epd, lens, jnp.asarray(spec.epd, jnp.float64))
    ang, _ = sensor_field_grid(spec, grid)
    moved = tolerances is not None and (tolerances.decenter > 0 or tolerances.tilt > 0)
    # Folding by symmetry is exact only for a rotationally symmetric lens: not with moved
    # elements (their metric is the mean over the full grid).
    fields, weights = (np.asarray(ang), None) if moved else tol_mod.symmetric_fields(ang)
    return tol_mod.ToleranceModel(lens, fields=fields, field_weights=weights,
                                  wavelengths=spec.wavelengths, tolerances=tolerances)


def analyse_design(lens, spec, *, trials: int = DEFAULT_TRIALS,
                   threshold_um: float = DEFAULT_THRESHOLD_UM, seed: int = 0,
                   grid: int = 16, small_step_check: bool = False, fd_check: int | None = None,
                   tolerances=None, log=print, model=None) -> dict:
    """The tolerance report of one design as a JSON-ready dict (see module docstring).
    ``model``: its ``design_model`` (built here if None)."""
    import jax
    import numpy as np

    from jaxlens.analysis import tolerance as tol_mod

    t0 = time.perf_counter()
    model = design_model(lens, spec, grid, tolerances) if model is None else model
    lens, fields, moved = model.lens, model.fields, model.elements
    pitch = spec.sensor_size[0] / spec.sensor_pixels
    nyquist = 0.5 / pitch
    sens = tol_mod.sensitivity(model, check=fd_check)
    t_sens = time.perf_counter() - t0
    mc = tol_mod.monte_carlo(model, trials=trials, key=jax.random.PRNGKey(seed),
                             threshold_um=threshold_um, mtf_frequency=nyquist)
    t_mc = time.perf_counter() - t0 - t_sens
    rows = sens["rows"]
    tols = np.asarray([r["tolerance"] for r in rows])
    g = np.asarray([r["gradient_um_per_unit"] for r in rows])
    done = [i for i, r in enumerate(rows) if r["fd_gradient_um_per_unit"] is not None]
    fd = np.asarray([rows[i]["fd_gradient_um_per_unit"] for i in done])
    err_um = np.abs(g[done] - fd) * tols[done]
    check = {
        "at_tolerance": {
            "what": "central difference over +-tolerance against the autodiff gradient, as "
                    "the difference of their first-order predictions |g - g_fd| x tolerance",
            "parameters_checked": len(done),
            "max_um": float(err_um.max()) if done else None,
            "worst_parameter": rows[done[int(err_um.argmax())]]["parameter"] if done else None,
            "max_second_order_um": (float(max(abs(rows[i]["second_order_um"]) for i in done))
                                    if done else None),
        }
    }
    if small_step_check:
        idx = np.nonzero(model.tolerance_vector(sensitivity=True))[0]
        h = 1e-3 * model.tolerance_vector(sensitivity=True)[idx]
        steps = np.zeros((idx.size, model.zero.size))
        steps[np.arange(idx.size), idx] = h
        res = model.evaluate(np.concatenate([steps, -steps]))["rms_um"]
        fd_small = (res[:idx.size] - res[idx.size:]) / (2 * h)
        scale = np.maximum(np.abs(g), np.abs(fd_small))
        rel = np.abs(g - fd_small) / np.where(scale > 0, scale, 1.0)
        big = np.abs(g) * tols > 1e-3  # parameters that move the RMS by > 1 nm per tolerance
        check["small_step"] = {
            "what": "central difference with step = 1e-3 x tolerance against autodiff",
            "max_relative": float(rel[big].max()), "median_relative": float(np.median(rel)),
            "parameters_compared": int(big.sum()),
            "max_abs_um_per_tolerance": float((np.abs(g - fd_small) * tols).max()),
        }
    def size(r):
        if r["delta_rms_plus_um"] is None:
            return abs(r["delta_rms_um"])
        return max(abs(r["delta_rms_plus_um"]), abs(r["delta_rms_minus_um"]))

    order = sorted(range(len(rows)), key=lambda i: -size(rows[i]))
    nominal = mc["nominal"]
    report = {
        "metric": (f"mean over the {grid}x{grid} sensor grid ("
                   + (f"{len(fields)} fields, not folded: moved elements break the symmetry"
                      if moved else f"{grid * grid} fields, folded onto {len(fields)} by "
                                    "symmetry") + ") "
                   "of the polychromatic (F, d, C pooled) RMS spot radius about the centroid, "
                   "21x21 pupil grid: Table 1's RMS (jaxlens.design.evaluate)"),
        "nominal_rms_um": sens["nominal_rms_um"],
        "tolerances": model.tolerances.describe(),
        "sensitivity": [{"parameter": rows[i]["parameter"], "tolerance": rows[i]["tolerance"],
                         "delta_rms_um": rows[i]["delta_rms_um"],
                         **{k: v for k, v in rows[i].items()
                            if k not in ("parameter", "tolerance", "delta_rms_um")}}
                        for i in order],
        "sensitivity_notes": (
            "delta_rms_um = autodiff gradient x tolerance (first order, one reverse-mode pass); "
            "delta_rms_plus_um/minus_um re-trace the lens at +-tolerance (no compensator); "
            "second_order_um = (r+ + r- - 2 r0)/2; delta_rms_compensated_um = worst of +- "
            "after refocusing the back focus, against the refocused nominal (null where not "
            "re-traced). Sorted by the larger re-traced change (first-order change where not "
            "re-traced). Apertures: every surface but the stop unclipped (floating "
            "semi-diameters). Radius tolerances are relative, conic absolute, asphere "
            "coefficients in mm^(1-2i) equivalent to the stated sag at the clear "
            "semi-diameter. Decenter and tilt: " + tol_mod.DECENTER_TILT
            + (". Their first-order change is 0 (the metric is even in them on the symmetric "
               "nominal lens and field grid): read the re-traced and second-order columns"
               if moved else "")),
        "gradient_check": check,
        "monte_carlo": {
            "trials": mc["trials"], "rms_p50_um": mc["rms_p50_um"],
            "rms_p90_um": mc["rms_p90_um"], "yield": mc["yield"],
            "threshold_um": mc["threshold_um"], "rms_mean_um": mc["rms_mean_um"],
            "rms_uncompensated_p50_um": mc["rms_uncompensated_p50_um"],
            "rms_uncompensated_p90_um": mc["rms_uncompensated_p90_um"],
            "yield_uncompensated": mc["yield_uncompensated"],
            "mtf_frequency_cycles_per_mm": mc["mtf_frequency_cycles_per_mm"],
            "mtf_frequency_is": f"the sensor's Nyquist frequency ({spec.sensor_pixels} pixels "
                                f"of {1e3 * pitch:.2f} um)",
            "mtf_nominal": nominal["mtf"], "mtf_p50": mc["mtf_p50"], "mtf_p10": mc["mtf_p10"],
            "mtf_definition": "geometric x diffraction limit, polychromatic, mean of T and S, "
                              "mean over the fields, after refocusing",
            "min_valid_fraction_min": float(np.min(mc["per_trial"]["min_valid_fraction"])),
            "yield_rule": f"RMS after refocusing <= threshold and >= {mc['min_valid']:.0%} of "
                          "every field's rays reach the image (the stop clips; the other "
                          "apertures float, as Zemax's automatic semi-diameters)",
            "perturbed": "radius, every thickness (the image distance too), index, Abbe, "
                         "irregularity" + (", element decenter x/y and tilt x/y" if moved
                                           else "") + "; conic and asphere coefficients "
                         "only through irregularity",
            "seed": seed,
        },
        "compensator": {
            "parameter": "back focus (last thickness: lens to image plane)",
            "method": "closed-form quadratic spot moments per field + damped Newton on the "
                      "mean RMS (exact for a plane image in homogeneous image space)",
            "nominal_refocus_mm": nominal["refocus_mm"],
            "nominal_rms_compensated_um": nominal["rms_compensated_um"],
            "refocus_p50_mm": mc["refocus_p50_mm"],
            "refocus_abs_p90_mm": mc["refocus_abs_p90_mm"],
        },
        "seconds": {"sensitivity": t_sens, "monte_carlo": t_mc,
                    "total": time.perf_counter() - t0},
    }
    log(f"tolerancing: nominal {report['nominal_rms_um']:.2f} µm; {mc['trials']} trials, RMS "
        f"p50 {mc['rms_p50_um']:.2f} / p90 {mc['rms_p90_um']:.2f} µm after refocusing "
        f"(without: {mc['rms_uncompensated_p50_um']:.2f} / "
        f"{mc['rms_uncompensated_p90_um']:.2f}), yield {100 * mc['yield']:.0f} % at "
        f"{threshold_um:g} µm; worst parameter {report['sensitivity'][0]['parameter']}; "
        f"{report['seconds']['total']:.1f} s")
    report["_mc"] = mc  # for the figure; dropped from the JSON
    return report


OUTPUT_FILES = ("tolerance.json", "tolerance_rms.png")


def write_report(report: dict, out: str, *, plots: bool = True) -> dict:
    """Write ``tolerance.json`` and (with ``plots``) ``tolerance_rms.png`` into ``out``;
    return the paths."""
    from jaxlens import plot
    from jaxlens.io.json_values import write_whole

    if not isinstance(out, str | os.PathLike) or not os.fspath(out).strip():
        raise ValueError(f"write_report: out must be a folder name, got {out!r}")
    os.makedirs(out, exist_ok=True)
    mc = report.get("_mc")
    data = {k: v for k, v in report.items() if k != "_mc"}
    path = os.path.join(out, OUTPUT_FILES[0])
    # whole or not at all: with --overwrite a stop mid-write cut the earlier run's file
    write_whole(path, json.dumps(data, indent=2, default=float))
    files = {"tolerance_json": path}
    if mc is not None and plots:
        files["tolerance_rms"] = plot.save(plot.plot_tolerance_histogram(mc),
                                           os.path.join(out, OUTPUT_FILES[1]))
    return files


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(prog="python -m jaxlens.experiments.tolerance",
                      description="Tolerance analysis of a classical design.")
    p.add_argument("design", help="design file (.zmx or jaxlens .json)")
    p.add_argument("--out", default=".", help="folder for tolerance.json and tolerance_rms.png")
    p.add_argument("--trials", type=checks.cli_int,
                   default=DEFAULT_TRIALS, help="Monte-Carlo trials")
    p.add_argument("--threshold", type=checks.cli_float, default=DEFAULT_THRESHOLD_UM,
                   help="yield threshold on the mean RMS after refocusing, µm")
    p.add_argument("--seed", type=checks.cli_int, default=0, help="Monte-Carlo random seed")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an earlier run's tolerance.json and tolerance_rms.png in --out")
    p.add_argument("--decenter", type=checks.cli_float, default=0.0,
                   help="element decenter tolerance, mm in x and in y, in [0, 0.1] "
                        "(default 0: off)")
    p.add_argument("--tilt", type=checks.cli_float, default=0.0,
                   help="element tilt tolerance, degrees about x and y, in [0, 1] "
                        "(default 0: off)")
    p.add_argument("--no-small-step-check", action="store_true",
                   help="skip the small-step finite-difference check of the gradient")
    return p


def main(argv: list[str] | None = None) -> int:
    """The command line (``argv`` None: ``sys.argv``, with the persistent compile cache of
    ``jaxlens.compile_cache``; a list: a call from Python, without it)."""
    command_line = argv is None
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser().parse_args(argv)
    prog = "python -m jaxlens.experiments.tolerance"
    from jaxlens.analysis.tolerance import MAX_TRIALS  # checked before the sensitivity pass

    if not 1 <= args.trials <= MAX_TRIALS:
        return fail(prog, ValueError(f"--trials must be a whole number >= 1 and <= "
                                     f"{MAX_TRIALS}, got {args.trials}"))
    bad = check_threshold(args.threshold, "--threshold")
    if bad is not None:  # before: no upper bound (1e300 µm was analysed, every trial passed)
        return fail(prog, bad)
    from jaxlens.design.init import MAX_SEED  # the design package, for its limit only

    if not 0 <= args.seed <= MAX_SEED:  # PRNGKey overflowed after the sensitivity pass
        return fail(prog, ValueError(f"--seed must be a whole number in [0, {MAX_SEED}], got "
                                     f"{args.seed}"))
    # Each tolerance flag has a physical range (before: --tilt 60 was analysed as a tolerance).
    for flag, v, (hi, unit, what) in (("--decenter", args.decenter, FLAG_RANGES["decenter"]),
                                       ("--tilt", args.tilt, FLAG_RANGES["tilt"])):
        if not (math.isfinite(v) and 0 <= v <= hi):
            return fail(prog, ValueError(f"{flag} must be a finite number >= 0 and <= {hi:g} "
                                         f"{unit} ({what}), got {v:g}"))
    if not os.path.isfile(args.design):
        what = "is a folder" if os.path.isdir(args.design) else "not found"
        return fail(prog, ValueError(f"design file {args.design!r} {what} (a .zmx or jaxlens "
                                     f".json file)"))
    if not args.out.strip():  # os.makedirs('') failed after the analysis
        return fail(prog, ValueError("--out needs a folder name, got an empty one"))
    if os.path.exists(args.out) and not os.path.isdir(args.out):  # found only when writing
        return fail(prog, ValueError(f"--out {args.out} is a file, not a folder"))
    try:  # a folder under a file, or an unwritable place, was found only when writing
        check_writable(args.out, "--out")
    except ValueError as e:
        return fail(prog, e)
    for f in OUTPUT_FILES:  # the report was written over the design it analysed
        if os.path.realpath(args.design) == os.path.realpath(os.path.join(args.out, f)):
            return fail(prog, ValueError(f"design file {args.design} is the {f} that the "
                                         f"report writes in --out {args.out}; choose another "
                                         f"--out"))
    earlier = [f for f in OUTPUT_FILES if os.path.exists(os.path.join(args.out, f))]
    if earlier and not args.overwrite:
        return fail(prog, ValueError(f"--out {args.out} already holds {', '.join(earlier)} of an "
                                     f"earlier run; give --overwrite to replace them, or choose "
                                     f"another folder"))
    import jax

    if command_line:
        from jaxlens import compile_cache

        compile_cache.enable()
    jax.config.update("jax_enable_x64", True)
    import jaxlens
    from jaxlens.design.spec import DesignSpec

    try:  # before any work: a file that does not open, or a lens of another kind
        lens = jaxlens.load(args.design)
        check_design(lens, DesignSpec())
    except ValueError as e:  # the reader's messages may start with the path already
        text = str(e) if str(e).startswith(args.design) else f"{args.design}: {e}"
        return fail(prog, ValueError(text))
    tolerances = None
    try:  # a decenter beyond the lens's clear radius was a traceback (mm, not µm?)
        if args.decenter > 0 or args.tilt > 0:  # default: the coaxial model, as recorded
            from jaxlens.analysis.tolerance import Tolerances

            tolerances = Tolerances(decenter=args.decenter, tilt=args.tilt)
        model = design_model(lens, DesignSpec(), tolerances=tolerances)
    except ValueError as e:
        text = str(e).replace("ToleranceModel: ", "").replace("Tolerances: ", "")
        for name in ("decenter", "tilt"):
            text = re.sub(rf"(Tolerances\.)?\b{name}\b ?±?", f"--{name} ", text, count=1)
        return fail(prog, ValueError(f"{args.design}: {text}"))
    report = analyse_design(lens, DesignSpec(), trials=args.trials,
                            threshold_um=args.threshold, seed=args.seed,
                            small_step_check=not args.no_small_step_check,
                            tolerances=tolerances, model=model)
    report = {"command": prog + " " + shlex.join(argv), "design": args.design, **report}
    files = write_report(report, args.out)
    print("wrote " + ", ".join(files.values()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
