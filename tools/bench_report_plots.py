"""Wall time of ``python -m jaxlens report LENS --plot DIR``, whole and per figure, in two trees.

For each lens file and round, the trees take turns (old, new, then new, old in the next
round, so that a change of load hits both). Each turn runs, each in its own process:

- the command itself (``report LENS --json --plot DIR``), timed from outside;
- the same work step by step (``--child``): load, ``report_data``, then each figure of
  ``--plot`` drawn and saved, each timed, with the number of XLA compilations and their
  seconds (``jax.log_compiles``).

Usage (an archive of the old commit: ``git archive dce17dc | tar -x -C /tmp/old``)::

    PYTHONPATH=. python tools/bench_report_plots.py --old /tmp/old --new . \\
        tests/data/zmx/rayoptics_US00583336-2-scaled.zmx jaxlens/data/lenses/cooke_triplet.json
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import re
import subprocess
import sys
import tempfile
import time


def child(path: str) -> None:
    """Time each step of ``report --plot`` in this process; print one JSON line."""
    import jax

    jax.config.update("jax_enable_x64", True)  # as the CLI
    from jaxlens.analysis import report

    compiled: list[float] = []

    class Count(logging.Handler):
        def emit(self, record):
            m = re.match(r"Finished XLA compilation of .* in ([\d.e+-]+) sec", record.getMessage())
            if m:
                compiled.append(float(m.group(1)))

    handler = Count(logging.WARNING)
    logging.getLogger("jax").addHandler(handler)
    jax.config.update("jax_log_compiles", True)
    logging.getLogger("jax").propagate = False  # the counts, not the log, on stderr
    out: dict[str, list[float]] = {}

    def timed(key, fn):
        compiled.clear()
        t = time.perf_counter()
        r = fn()
        out[key] = [round(time.perf_counter() - t, 2), len(compiled), round(sum(compiled), 2)]
        return r

    from jaxlens.__main__ import build_parser

    args = build_parser().parse_args(["report", path])  # the command's defaults
    lens = timed("load", lambda: report._load_lens(args))
    lens = report.with_fields_and_wavelengths(lens)
    timed("report", lambda: report.report_data(lens))
    with tempfile.TemporaryDirectory() as d:
        paths = report.figure_paths(path, d, False)
        for key, p in paths.items():
            timed(key, lambda p=p, key=key: report._write_figures(lens, {key: p}))
    print(json.dumps(out))


def run_tree(tree: str, path: str) -> dict:
    env = dict(os.environ, PYTHONPATH=tree)
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        cli = subprocess.run([sys.executable, "-m", "jaxlens", "report", path, "--json",
                              "--plot", d], env=env, capture_output=True, text=True, cwd=tree)
        wall = time.perf_counter() - t
    if cli.returncode:
        raise SystemExit(f"{tree}: report {path} failed: {cli.stderr[-2000:]}")
    step = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", path], env=env,
                          capture_output=True, text=True, cwd=tree)
    if step.returncode:
        raise SystemExit(f"{tree}: --child {path} failed: {step.stderr[-2000:]}")
    return {"command": round(wall, 2), "json": cli.stdout,
            "steps": json.loads(step.stdout.strip().splitlines()[-1])}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", help="lens files, relative to the trees' roots")
    ap.add_argument("--old", help="root of the old tree")
    ap.add_argument("--new", default=".", help="root of the new tree (default .)")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        return child(a.files[0])
    if not a.old:
        ap.error("--old is needed")
    trees = {"old": os.path.abspath(a.old), "new": os.path.abspath(a.new)}
    for path in a.files:
        runs: dict[str, list[dict]] = {"old": [], "new": []}
        for r in range(a.rounds):
            for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
                runs[name].append(run_tree(trees[name], path))
                print(f"{path} round {r + 1} {name}: command {runs[name][-1]['command']} s, "
                      f"steps {runs[name][-1]['steps']}", file=sys.stderr, flush=True)
        same = all(x["json"] == runs["old"][0]["json"] for x in runs["old"] + runs["new"])
        print(f"\n{path}: --json output identical in every run: {same}")
        print(f"{'step':<10}{'old s':>8}{'new s':>8}   (s, compiles, compile s per run)")
        for key in ["command", *runs["old"][0]["steps"]]:
            o, n = (_column(runs[name], key) for name in ("old", "new"))
            print(f"{key:<10}{_mean(o):8.1f}{_mean(n):8.1f}   old {o}  new {n}")


def _column(rs: list[dict], key: str) -> list:
    """Each run's seconds of the whole command, or [s, compiles, compile s] of a step."""
    return [x["command"] if key == "command" else x["steps"][key] for x in rs]


def _mean(col: list) -> float:
    return sum(x if isinstance(x, float) else x[0] for x in col) / len(col)

if __name__ == "__main__":
    main()
