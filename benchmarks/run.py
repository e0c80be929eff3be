"""Run the jaxlens benchmark suite.

Usage::

    python -m benchmarks            # 1e3..1e6 rays, every study (tens of minutes on 2 cores)
    python -m benchmarks --full     # adds 1e7 rays to the throughput benchmark
    python -m benchmarks --smoke    # seconds: checks that the suite works (CI); no timings kept
    python -m benchmarks --only throughput skipping
    python -m benchmarks --only throughput --lenses cooke_triplet --counts 100000 1000000 \
        --tag headline          # a quick rerun, written beside the full results

Writes, into ``--out`` (default ``benchmarks/results/``; ``--smoke`` writes to a temporary
folder unless ``--out`` is given): ``<benchmark>.json`` (machine, versions, command and rows),
``README.md`` (markdown tables) and ``<benchmark>.png`` plots; ``--tag NAME`` writes
``<benchmark>_NAME.json`` / ``.png`` instead, so that a partial rerun (fewer lenses or ray
counts) sits beside the full results without overwriting them. Every JSON file states the
machine (CPU model, cores, memory), the versions (python, jax, jaxlib, equinox, numpy,
jaxlens, optiland) and the load average, because other work on a 2-core machine changes the
numbers; the rows also carry the load at the time of each measurement.

The render benchmarks (``benchmarks/render_speed.py``, ``benchmarks/render_memory.py``) belong
to the render module. They run here too (not in ``--smoke``), by default or under ``--only
render_speed render_memory``: through ``run(smoke) -> dict`` where they define it, else through
their ``main``, which writes their own result files (``<benchmark>.json`` in ``--out``, named by
``--tag`` as the others).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import pathlib
import re
import shlex
import sys
import tempfile
import time

import jax

from . import common

CORE = ("throughput", "pareto", "skipping", "imaging")
OPTIONAL = ("render_speed", "render_memory")


def _folder(text: str) -> pathlib.Path:
    """``--out``: a folder's path, not empty (``pathlib.Path("")`` is the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("needs a folder's path, got an empty one")
    return pathlib.Path(text)


def main(argv: list[str] | None = None) -> dict:
    from jaxlens.experiments.runfolder import OneLineParser

    p = OneLineParser(prog="python -m benchmarks", description=__doc__.split("\n")[0])
    p.add_argument("--smoke", action="store_true", help="tiny sizes; checks the suite works")
    p.add_argument("--full", action="store_true", help="include 1e7 rays in the throughput run")
    p.add_argument("--only", nargs="+", choices=CORE + OPTIONAL, help="run only these")
    p.add_argument("--out", type=_folder, default=None, help="output folder")
    p.add_argument("--no-plots", action="store_true", help="skip the matplotlib figures")
    p.add_argument("--lenses", nargs="+", help="throughput: only these zoo lenses")
    p.add_argument("--counts", nargs="+", type=common.checks.cli_int,
                   help="throughput: only these ray counts")
    p.add_argument(
        "--tag",
        default=None,
        help="write <benchmark>_<tag>.json/.png instead of <benchmark>.json (a partial rerun "
        "beside the full results)",
    )
    args = p.parse_args(argv)
    if args.tag is not None and not re.fullmatch(r"[A-Za-z0-9_-]+", args.tag):
        p.error("--tag: letters, digits, '_' and '-' only")
    if args.full and (args.smoke or args.counts):
        p.error("--full adds 1e7 rays to the default ray counts; it does not go with "
                + ("--smoke" if args.smoke else "--counts (list 10000000 there instead)"))
    from .throughput import MAX_RAYS

    for n in args.counts or ():
        if not 1 <= n <= MAX_RAYS:  # 10**12 aborted in XLA after the lens was built
            p.error(f"--counts must be whole numbers in [1, {MAX_RAYS}] rays, got {n}")
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        p.error(f"--out {args.out} is a file, not a folder")  # before the first benchmark
    if args.out is not None:  # under a file: NotADirectoryError after the checks
        from jaxlens.experiments.runfolder import UsageError, check_writable

        try:
            check_writable(str(args.out), "--out")
        except UsageError as e:
            p.error(str(e))
    readme = (args.out or common.RESULTS) / "README.md"
    if readme.is_file() and not readme.read_text(errors="replace").startswith(README_TITLE):
        # Before: the summary was written over it at the end (--out . replaced the project's).
        p.error(f"--out {readme.parent}: its README.md is not a benchmark summary (it does not "
                f"start with {README_TITLE!r}), and the run ends by writing one there; choose "
                f"another folder")
    for flag, values in (("--only", args.only), ("--lenses", args.lenses),
                         ("--counts", args.counts)):
        repeated = sorted({v for v in values or () if list(values).count(v) > 1}, key=str)
        if repeated:  # the benchmark ran twice, or a ray count or lens got two table rows
            p.error(f"{flag} names {', '.join(map(str, repeated))} more than once")
    if (args.lenses or args.counts) and args.only and "throughput" not in args.only:
        p.error("--lenses and --counts apply to the throughput benchmark only; add throughput "
                "to --only")
    if args.lenses:
        import difflib

        from jaxlens import zoo

        for name in args.lenses:
            if name not in zoo.ZOO:
                close = difflib.get_close_matches(name, sorted(zoo.ZOO), n=3, cutoff=0.5)
                hint = f"; closest: {', '.join(close)}" if close else ""
                p.error(f"--lenses: unknown zoo lens {name!r} (known: "
                        f"{', '.join(sorted(zoo.ZOO))}){hint}")

    render = [n for n in args.only or () if n in OPTIONAL]
    if args.smoke and render:  # before: --smoke skipped them, and the run did nothing else
        p.error(f"--only {' '.join(render)}: --smoke does not run the render benchmarks "
                f"(each takes minutes); leave --smoke out, or choose from {', '.join(CORE)}")
    # Before the first benchmark: the folder written is --out, else the committed results
    # (a smoke run without --out writes to a new temporary folder).
    target = args.out if args.out is not None else None if args.smoke else common.RESULTS
    for name in (args.only or CORE + OPTIONAL) if target is not None else ():
        if name in OPTIONAL and not args.smoke:  # its result file (before: checked late)
            stem = f"{name}_{args.tag}" if args.tag else name
            try:
                common.out_path(result_of=name)(str(target / f"{stem}.json"))
            except argparse.ArgumentTypeError as e:
                p.error(f"--out {target}: {e}")
        if name in CORE:
            stem = f"{name}_{args.tag}" if args.tag else name
            clash = _replaces_fuller_run(target / f"{stem}.json", target, args, name)
            if clash:
                p.error(clash)
            png = target / f"{stem}.png"
            if not args.no_plots and png.exists() and not (target / f"{stem}.json").exists():
                # Before: written over; a plot of ours has its result file beside it.
                p.error(f"--out {target}: {png.name} is not a {name} benchmark plot (no "
                        f"{stem}.json beside it), and this run would write its {name} plot "
                        f"over it; move it away, choose another --out or give --no-plots")

    jax.config.update("jax_enable_x64", True)  # float64 runs next to float32
    out = args.out
    if out is None:
        out = (
            pathlib.Path(tempfile.mkdtemp(prefix="jaxlens-bench-"))
            if args.smoke
            else common.RESULTS
        )
    out.mkdir(parents=True, exist_ok=True)
    command = "python -m benchmarks " + " ".join(shlex.quote(a) for a in (argv or sys.argv[1:]))
    machine = common.machine_info()
    print(
        f"jaxlens benchmarks -> {out}\n  {machine['cpu_model']}, {machine['logical_cores']} "
        f"cores, jax {machine['jax']}, load {machine['load_average_at_start']}"
    )

    selected = args.only or (CORE + OPTIONAL)
    results = {}
    for name in selected:
        try:
            mod = importlib.import_module(f"{__package__}.{name}")
        except ModuleNotFoundError:
            if name in OPTIONAL:
                continue
            raise
        if not hasattr(mod, "run"):
            # The render benchmarks expose main(argv) and write their own result files.
            if name in OPTIONAL and hasattr(mod, "main") and not args.smoke:
                # Into --out, named by --tag (before: always benchmarks/results/<name>.json).
                stem = f"{name}_{args.tag}" if args.tag else name
                print(f"[{name}] (writes its own results)")
                mod.main(["--out", str(out / f"{stem}.json")])
            continue
        print(f"[{name}]")
        t0 = time.perf_counter()
        kwargs = {"smoke": args.smoke}
        if name == "throughput":
            kwargs["full"] = args.full
            if args.lenses:
                kwargs["lenses"] = tuple(args.lenses)
            if args.counts:
                kwargs["counts"] = list(args.counts)
        res = mod.run(**kwargs)
        wall = time.perf_counter() - t0
        results[name] = res
        if name in CORE:
            payload = {
                "benchmark": name,
                "command": command,
                "machine": machine,
                "load_average_at_end": os.getloadavg(),
                "wall_s": wall,
                **res,
            }
            stem = f"{name}_{args.tag}" if args.tag else name
            common.write_json(stem, payload, out)
            if not args.no_plots and hasattr(mod, "plot"):
                mod.plot(res, out / f"{stem}.png")
        print(f"  ({wall:.0f} s)")

    write_readme(out)
    return results


RUN_KINDS = ("smoke", "partial", "full")
"""Benchmark runs by how much of the study they hold: ``--smoke`` (tiny sizes, no timings
kept), a partial throughput run (``--lenses``/``--counts``), and the full study."""


def run_kind(command: str) -> str:
    """The kind (``RUN_KINDS``) of the run that a result file's ``command`` states."""
    words = command.split()
    if "--smoke" in words:
        return "smoke"
    return "partial" if {"--lenses", "--counts"} & set(words) else "full"


def _replaces_fuller_run(path: pathlib.Path, out: pathlib.Path, args,
                         name: str) -> str | None:
    """The refusal message when writing ``path`` would replace a file that is not a result
    of the benchmark ``name``, or a result file of a fuller run (a smoke run over a full one,
    a partial rerun over the full study), else None.

    Before: ``--smoke --out benchmarks/results`` replaced every committed result with the
    smoke sizes, and ``--only throughput --counts 1000`` the full throughput table, each
    without a word (``--tag`` is the documented way to write beside them); a file of the
    same name that was no benchmark result (not JSON, or other JSON) was written over, or
    refused as "a full run's results"."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        data = None
    if not isinstance(data, dict) or data.get("benchmark") != name:
        what = ("is not JSON" if data is None else f"holds a JSON {type(data).__name__}"
                if not isinstance(data, dict) else "has no \"benchmark\" entry"
                if "benchmark" not in data else f"is a result of {data['benchmark']!r}")
        return (f"--out {out}: {path.name} is not a {name} benchmark result (it {what}), and "
                f"this run would write its {name} results over it; move it away or choose "
                f"another --out")
    old = run_kind(str(data.get("command", "")))
    new = "smoke" if args.smoke else "partial" if (args.lenses or args.counts) else "full"
    if RUN_KINDS.index(new) >= RUN_KINDS.index(old):
        return None
    return (f"--out {out}: {path.name} holds a {old} run's results, which this {new} "
            f"run would replace; give --tag NAME (writes {path.stem}_NAME.json beside it) or "
            f"another --out")


README_TITLE = "# jaxlens benchmark results"
"""The first line of the ``README.md`` that ``write_readme`` writes (and may replace)."""


def write_readme(out: pathlib.Path) -> None:
    """(Re)write ``out/README.md`` from every benchmark JSON in ``out``.

    It opens with the headline figures and the recommended defaults beside the library's
    (``benchmarks/summary.py``). Each section states the command that made it, the git commit
    and the machine, so results of separate runs (``--only``, ``--tag``) can sit side by side.
    """
    from . import summary

    parts = [README_TITLE, ""]
    head = summary.headline(out)
    if head:
        parts += ["## Headline", "", head]
    table = summary.defaults_table(out)
    if table:
        parts += [
            "## Recommended defaults against the library's",
            "",
            "Each time-against-error curve below ends in a recommended default; the library's "
            "value is read from the code when this file is written.",
            "",
            table,
            "",
        ]
    for name in CORE:
        paths = [out / f"{name}.json"] + sorted(out.glob(f"{name}_*.json"))
        for path in paths:
            if not path.exists():
                continue
            parts += _section(name, path)
    parts += _other_files(out)
    from jaxlens.io.json_values import write_whole

    write_whole(out / "README.md", "\n".join(parts) + "\n")


# Result files that the studies above do not make: what each holds (benchmarks/SPEED.md
# discusses them).
STANDALONE = {
    "design_step": "one design-loss gradient step (Adam's `value_and_grad`), a baseline commit "
                   "against this one in one process (`benchmarks/design_step.py`)",
    "fast_path": "a lens without optional features: same jaxpr and bit-equal results as a "
                 "baseline commit (`benchmarks/fast_path.py`)",
    "vjp_probe": "the trace's forward + gradient with JAX's derivative and with the "
                 "hand-written reverse rule, interleaved (`benchmarks/vjp_probe.py`)",
    "render_speed": "forward render time (`benchmarks/render_speed.py`)",
    "render_memory": "peak memory and rate of the checkpointed render gradient "
                     "(`benchmarks/render_memory.py`)",
    "gpu": "raw log of a run on a lent GPU; the commands are its `==` lines",
    "reversible_probe": "a reversible backward pass (incident rays rebuilt in reverse) against "
                        "the reverse rule; its script left the tree after the measurement "
                        "(`benchmarks/SPEED.md`, \"A reversible backward pass\", names the commit)",
}


def _other_files(out: pathlib.Path) -> list[str]:
    """A table of the result files in ``out`` that no ``CORE`` section shows."""
    rows = []
    for path in sorted(out.iterdir()):
        stem = path.stem
        if path.name == "README.md" or any(
                stem == n or stem.startswith(f"{n}_") for n in CORE):
            continue
        key = next((k for k in STANDALONE if stem == k or stem.startswith(f"{k}_")), None)
        what = STANDALONE[key] if key else "(not described)"
        command = ""
        if path.suffix == ".json":
            command = json.loads(path.read_text()).get("command") or ""
        rows.append(f"| `{path.name}` | {what} | {f'`{command}`' if command else '–'} |")
    if not rows:
        return []
    return ["## Other result files", "",
            "Made by the standalone benchmarks; `benchmarks/SPEED.md` gives their figures and "
            "the commands of the files without one here.", "",
            "| file | what | command |", "|---|---|---|", *rows, ""]


def _section(name: str, path: pathlib.Path) -> list[str]:
    data = json.loads(path.read_text())
    m = data["machine"]
    mod = importlib.import_module(f"{__package__}.{name}")
    load = m["load_average_at_start"]
    return [
        f"## {path.stem}" if path.stem != name else f"## {name}",
        "",
        f"Made by `{data['command']}` at git commit {m['git_commit']} on "
        f"{m['cpu_model']}, {m['logical_cores']} logical cores, {m.get('memory_gib')} GiB "
        f"({m['platform']}); python {m['python']}, jax {m['jax']}, jaxlib {m['jaxlib']}, "
        f"equinox {m['equinox']}, numpy {m['numpy']}, jaxlens {m['jaxlens']}, optiland "
        f"{m['optiland'] or 'not installed'}. 1-minute load average at the start "
        f"{load[0]:.1f}, at the end {data['load_average_at_end'][0]:.1f} (2 cores; other work "
        f"shared the machine; every row records its own load), wall time "
        f"{data['wall_s']:.0f} s.",
        "",
        mod.markdown(data),
        "",
    ]


if __name__ == "__main__":
    main()
