"""Headline figures of the benchmark results, and the recommended defaults against the library's.

Every Pareto curve of ``pareto`` and ``imaging`` ends in a recommended default. This module reads
the library's actual defaults from the code (``jaxlens.tracing.forward.DEFAULT_NEWTON_ITERS``, the
signatures of ``jaxlens.imaging.psf`` / ``jaxlens.imaging.render``, the ``pupil=None`` fallback of
``jaxlens.analysis.spots.rms_spot``, the design losses' ``spp``) and sets them beside the
recommendations, so a drift between the two shows in ``results/README.md``.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import json
import pathlib

from . import common

F32_INTERCEPT_MM = 1e-4  # the bound documented in docs/stability.md (tests/test_stress.py)
F32_GRAD_REL = 1e-3  # relative deviation of the design gradient (curvatures, gaps)


def library_defaults() -> dict:
    """The defaults the library uses, each with the place that defines it."""
    # Take the modules (``jaxlens.render`` and ``jaxlens.trace`` are functions).
    analysis = importlib.import_module("jaxlens.analysis.spots")
    psf = importlib.import_module("jaxlens.imaging.psf")
    render = importlib.import_module("jaxlens.imaging.render")
    trace = importlib.import_module("jaxlens.tracing.forward")
    losses = importlib.import_module("jaxlens.design.losses")
    multistart = importlib.import_module("jaxlens.design.multistart")

    out = {
        "newton_iters": (
            trace.DEFAULT_NEWTON_ITERS,
            "jaxlens/tracing/forward.py DEFAULT_NEWTON_ITERS",
        )
    }
    out["rms_spot_pupil"] = (
        ("grid", analysis.PUPIL_GRID),
        "jaxlens/analysis/spots.py rms_spot(pupil=None) -> pupil_grid(PUPIL_GRID)",
    )
    sig = inspect.signature(psf.psf_info).parameters
    out["psf_kernel_size"] = (sig["kernel_size"].default,
                              "jaxlens/imaging/psf.py psf(kernel_size=...)")
    out["psf_pupil"] = (sig["model"].default.pupil,
                        "jaxlens/imaging/psf.py psf(model=GeometricPSF(pupil=...))")
    rsig = inspect.signature(render.render).parameters
    out["render_kernel_size"] = (
        render.PSFRender().kernel_size,
        "jaxlens/imaging/render.py PSFRender(kernel_size=...)",
    )
    spp = rsig["spp"].default
    out["render_spp"] = (
        None if spp is inspect.Parameter.empty else spp,
        "jaxlens/imaging/render.py render(spp=...) (required, no default)",
    )
    fields = {f.name: f for f in dataclasses.fields(losses.ImageObjective)}
    out["design_image_spp"] = (
        fields["spp"].default,
        "jaxlens/design/losses.py ImageObjective.spp",
    )
    cfg = {f.name: f for f in dataclasses.fields(multistart.DesignConfig)}
    out["design_multistart_image_spp"] = (
        cfg["image_spp"].default,
        "jaxlens/design/multistart.py DesignConfig.image_spp",
    )
    out["design_rings"] = (cfg["rings"].default, "jaxlens/design/multistart.py DesignConfig.rings")
    out["design_float64"] = (
        cfg["float64"].default,
        "jaxlens/design/multistart.py DesignConfig.float64",
    )
    return out


def _load(out: pathlib.Path, name: str):
    path = out / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def _verdict(recommended, library) -> str:
    if recommended is None or library is None:
        return "–"
    if recommended == library:
        return "agrees"
    if isinstance(recommended, int | float) and isinstance(library, int | float):
        return (
            "library spends more than needed"
            if library > recommended
            else "**library default below the recommendation**"
        )
    return "**differs**"


def defaults_table(out: pathlib.Path) -> str:
    """Markdown: each recommended default beside the library's, from the results in ``out``."""
    lib = library_defaults()
    rows = []
    pareto, imaging = _load(out, "pareto"), _load(out, "imaging")
    if pareto:
        rec = pareto["rms_spot"]["recommendation"]
        ew = rec["equal_weight"]
        spot_rows = [r for r in pareto["rms_spot"]["rows"] if "scheme" in r]
        lib_pupil = lib["rms_spot_pupil"][0]
        lib_err = None
        if lib_pupil is not None:
            sel = [r for r in spot_rows if (r["scheme"], r["n"]) == lib_pupil]
            if sel:
                lib_err = max(r["rel_error"] for r in sel)
        rows.append(
            [
                f"RMS spot pupil sampling (≤ {rec['target_rel_error']:.0%} error, every lens "
                "and field)",
                f"{ew['scheme']} {ew['n']} ({ew['rays']} rays, error "
                f"{common.fmt(ew['max_rel_error'])})"
                if ew
                else "none reached the target",
                f"{lib_pupil[0]} {lib_pupil[1]}"
                + (f" (error {common.fmt(lib_err)})" if lib_err is not None else "")
                if lib_pupil
                else "?",
                lib["rms_spot_pupil"][1],
                _verdict((ew["scheme"], ew["n"]) if ew else None, lib_pupil),
            ]
        )
        nrec = pareto["newton"]["recommendation"]
        lib_it = lib["newton_iters"][0]
        for dt in ("float32", "float64"):
            if dt in nrec:
                rows.append(
                    [
                        f"Newton iterations, {dt} (error ≤ {nrec[dt]['floor_mm']:g} mm, no "
                        "ray lost)",
                        str(nrec[dt]["newton_iters"]),
                        str(lib_it),
                        lib["newton_iters"][1],
                        _verdict(nrec[dt]["newton_iters"], lib_it),
                    ]
                )
        dt_rows = [r for r in pareto["dtype"]["rows"] if "rel_dev_grad_design" in r]
        if dt_rows:
            ok = all(
                r["max_intercept_dev_mm"] <= F32_INTERCEPT_MM
                and r["rel_dev_grad_design"] <= F32_GRAD_REL
                and r["valid_mismatch"] == 0
                for r in dt_rows
            )
            lib_f64 = lib["design_float64"][0]
            rec = "float32" if ok else "float64"
            rows.append(
                [
                    f"dtype (float32 where intercepts stay within {F32_INTERCEPT_MM:g} mm, the "
                    f"design gradient within {F32_GRAD_REL:g} relative and no validity flag "
                    "changes, on every sample lens)",
                    f"{rec} ({min(r['speedup_forward'] for r in dt_rows):.1f}–"
                    f"{max(r['speedup_forward'] for r in dt_rows):.1f}x forward, "
                    f"{min(r['speedup_grad'] for r in dt_rows):.1f}–"
                    f"{max(r['speedup_grad'] for r in dt_rows):.1f}x gradient; intercepts within "
                    f"{common.fmt(max(r['max_intercept_dev_mm'] for r in dt_rows))} mm, design "
                    f"gradient within {common.fmt(max(r['rel_dev_grad_design'] for r in dt_rows))}"
                    ")",
                    "trace follows the rays' dtype; design: "
                    + ("float64" if lib_f64 else "float32"),
                    lib["design_float64"][1],
                    _verdict(rec, "float64" if lib_f64 else "float32"),
                ]
            )
    if imaging:
        psf = imaging["psf"]
        k = psf.get("recommended_kernel_size")
        rows.append(
            [
                "PSF kernel size, cellphone6 at its pixel pitch (≤ 1 % energy outside)",
                str(k),
                str(lib["psf_kernel_size"][0]),
                lib["psf_kernel_size"][1] + "; " + lib["render_kernel_size"][1],
                _verdict(k, lib["psf_kernel_size"][0]),
            ]
        )
        if "recommended_pupil" in psf:
            p = psf["recommended_pupil"]
            rows.append(
                [
                    "PSF pupil rays per side (L1 ≤ 2 %)",
                    str(p),
                    str(lib["psf_pupil"][0]),
                    lib["psf_pupil"][1],
                    _verdict(p, lib["psf_pupil"][0]),
                ]
            )
        if "render" in imaging:
            r = imaging["render"]
            s = r["recommended_spp"]
            by = r.get("recommended_spp_by_target", {})
            rows.append(
                [
                    f"render spp, cellphone6 {r['size']}² (per-pixel rel. RMSE ≤ 2 % against "
                    f"{r['reference_spp']} spp)",
                    str(s) + (f" ({by['5%']} for ≤ 5 %)" if by.get("5%") else ""),
                    f"{lib['design_image_spp'][0]} (design image loss; render() itself "
                    "requires spp)",
                    lib["design_image_spp"][1] + "; " + lib["design_multistart_image_spp"][1],
                    _verdict(s, lib["design_image_spp"][0]),
                ]
            )
    if not rows:
        return ""
    return common.md_table(["curve", "recommended", "library default", "where", "verdict"], rows)


def headline(out: pathlib.Path) -> str:
    """Markdown of the headline figures (throughput against optiland, render memory)."""
    parts = []
    for stem in sorted(p.stem for p in out.glob("throughput*.json")):
        data = _load(out, stem)
        rows = data["rows"]
        counts = sorted({r["rays"] for r in rows if "ratio_vs_optiland" in r})
        if not counts:
            continue
        n = 1_000_000 if 1_000_000 in counts else counts[-1]
        body = []
        for r in rows:
            if r["rays"] != n or r["mode"] != "forward":
                continue
            per_core = r["rays"] * r["surfaces"] / r["cpu_s"] if r.get("cpu_s") else None
            body.append(
                [
                    r["lens"],
                    r["engine"],
                    r["dtype"],
                    float(r["rate"]),
                    per_core,
                    f"{r['ratio_vs_optiland']:.2f}x" if "ratio_vs_optiland" in r else "–",
                    f"{r['load_before']:.1f}",
                ]
            )
        parts += [
            f"**Forward trace against optiland, {n:.0e} rays** (`{stem}.json`, made by "
            f"`{data['command']}`, load average at the start "
            f"{data['machine']['load_average_at_start'][0]:.1f} on "
            f"{data['machine']['logical_cores']} cores)",
            "",
            common.md_table(
                ["lens", "engine", "dtype", "ray·surf/s", "per core", "vs optiland", "load"],
                body,
            ),
            "",
        ]
    mem = _load(out, "render_memory")
    if mem:
        body = []
        for r in mem.get("runs", []):
            if r.get("peak_rss_bytes"):
                outcome = f"{r['peak_rss_bytes'] / 2**30:.2f} GiB"
            elif r.get("exceeded_cap"):
                outcome = f"> {r['cap_bytes'] / 2**30:.0f} GiB (stopped at the cap)"
            elif r.get("failed_allocation_bytes"):
                outcome = (
                    f"out of memory (one {r['failed_allocation_bytes'] / 1e9:.1f} GB "
                    "allocation failed)"
                )
            else:
                outcome = "failed"
            body.append(
                [
                    f"{r['size']}²",
                    r["spp"],
                    f"{r['rays']:.2e}",
                    "yes" if r["checkpoint"] else "no",
                    outcome,
                    float(r["run_s"]) if r.get("run_s") else None,
                ]
            )
        parts += [
            f"**Render gradient memory** (`render_memory.json`, made by `{mem['command']}`): "
            f"{mem['benchmark']}; peak resident memory",
            "",
            common.md_table(["image", "spp", "rays", "checkpoint", "peak RSS", "run s"], body),
            "",
            mem.get("note", ""),
            "",
        ]
        if mem.get("render_over_trace_gradient"):
            parts += [
                f"Gradient rate: the checkpointed {mem['size']}² render gradient took "
                f"{mem['render_gradient_s']:.1f} s, {mem['render_gradient_rate']:.3g} "
                f"ray·surfaces/s, **{mem['render_over_trace_gradient']:.2f}×** the bare trace's "
                f"forward+gradient rate on the same lens in the same run "
                f"({mem['trace_gradient_rate']:.3g} ray·surfaces/s, 1e6 rays, float32).",
                "",
            ]
    speed = _load(out, "render_speed")
    if speed:
        parts += [
            f"**Render speed** (`render_speed.json`, made by `{speed['command']}`): "
            f"{speed['benchmark']}, {speed['size']}² × {speed['spp']} spp: "
            f"{speed['rays_per_s_best']:.3g} rays/s ({speed['run_s_best']:.1f} s per render, "
            f"compile {speed['compile_s']:.1f} s) at load "
            f"{speed['machine']['load_average_at_start'][0]:.1f}.",
            "",
        ]
    return "\n".join(parts)


if __name__ == "__main__":  # ran nothing, without a word
    raise SystemExit("benchmarks.summary is a helper of the benchmarks, not one: run "
                     "python -m benchmarks (--only NAME for one benchmark)")
