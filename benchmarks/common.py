"""Shared pieces of the benchmark suite: timing, machine description, result files.

Timing rules (as in optimistix and DiffeRT): every function is jitted, called once to
compile and warm up (the compile time is reported on its own), then run ``repeats`` times
with ``jax.block_until_ready``; the best run is reported, with the median beside it. The
machine's 1-minute load average is recorded before and after each measurement so a busy
machine can be recognised in the results.
"""

from __future__ import annotations

import json
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

import jax
import numpy as np

from jaxlens.io.json_values import whole_path, write_whole
from jaxlens.optics import checks

RESULTS = pathlib.Path(__file__).resolve().parent / "results"


def cpu_model() -> str:
    """The CPU model name (from /proc/cpuinfo or lscpu), or platform.processor()."""
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info() -> dict[str, Any]:
    """CPU, core count, memory and the versions of everything that affects the numbers."""
    import equinox

    import jaxlens

    info: dict[str, Any] = {
        "cpu_model": cpu_model(),
        "logical_cores": os.cpu_count(),
        "affinity_cores": len(os.sched_getaffinity(0))
        if hasattr(os, "sched_getaffinity")
        else None,
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "jax": jax.__version__,
        "jaxlib": getattr(jax.lib, "__version__", None) or _pkg_version("jaxlib"),
        "equinox": equinox.__version__,
        "numpy": np.__version__,
        "jaxlens": jaxlens.__version__,
        "optiland": _pkg_version("optiland"),
        "jax_backend": jax.default_backend(),
        "jax_devices": [str(d) for d in jax.devices()],
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
        "git_commit": _git_commit(),
        "load_average_at_start": os.getloadavg(),
    }
    try:
        mem = pathlib.Path("/proc/meminfo").read_text().splitlines()[0].split()[1]
        info["memory_gib"] = round(int(mem) / 2**20, 1)
    except (OSError, IndexError, ValueError):
        pass
    return info


def _pkg_version(name: str) -> str | None:
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def _git_commit() -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=pathlib.Path(__file__).parent,
            timeout=5,
        )
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def block(x):
    """``jax.block_until_ready`` on every array leaf of a pytree."""
    return jax.block_until_ready(x)


def time_jitted(
    fn: Callable,
    *args,
    repeats: int = 5,
    min_total_s: float = 0.5,
    max_repeats: int = 50,
    warmup: bool = True,
) -> dict[str, float]:
    """Time an already-jitted function.

    The first call (trace + compile + one run) is reported as ``compile_s``; a second call
    warms caches. Then the function runs at least ``repeats`` times and until
    ``min_total_s`` seconds have passed (at most ``max_repeats`` runs). ``warmup=False``
    skips the second call (for the largest sizes, where the first call already warmed up).

    Returns:
        ``compile_s`` (first call), ``run_s`` (best run), ``median_s``, ``repeats``,
        ``cpu_s`` (process CPU time of the best run, all threads), ``load_before`` and
        ``load_after`` (1-minute load averages).
    """
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    block(fn(*args))
    compile_s = time.perf_counter() - t0
    if warmup:
        block(fn(*args))  # a second call warms caches and allocator pools
    runs, cpus = [], []
    total = 0.0
    while len(runs) < max_repeats and (len(runs) < repeats or total < min_total_s):
        c0, w0 = time.process_time(), time.perf_counter()
        block(fn(*args))
        w = time.perf_counter() - w0
        cpus.append(time.process_time() - c0)
        runs.append(w)
        total += w
    best = int(np.argmin(runs))
    return {
        "compile_s": compile_s,
        "run_s": runs[best],
        "median_s": statistics.median(runs),
        "repeats": len(runs),
        "cpu_s": cpus[best],
        "load_before": load0,
        "load_after": os.getloadavg()[0],
    }


def time_python(
    fn: Callable, *args, repeats: int = 3, min_total_s: float = 0.5, max_repeats: int = 20
) -> dict[str, float]:
    """Time a plain Python/numpy callable the same way (first call reported as warm-up)."""
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    fn(*args)
    first = time.perf_counter() - t0
    runs, cpus = [], []
    total = 0.0
    while len(runs) < max_repeats and (len(runs) < repeats or total < min_total_s):
        c0, w0 = time.process_time(), time.perf_counter()
        fn(*args)
        w = time.perf_counter() - w0
        cpus.append(time.process_time() - c0)
        runs.append(w)
        total += w
    best = int(np.argmin(runs))
    return {
        "compile_s": first,
        "run_s": runs[best],
        "median_s": statistics.median(runs),
        "repeats": len(runs),
        "cpu_s": cpus[best],
        "load_before": load0,
        "load_after": os.getloadavg()[0],
    }


def write_json(name: str, payload: dict, out: pathlib.Path = RESULTS) -> pathlib.Path:
    """Write ``payload`` to ``out/name.json`` (numbers made JSON-safe), whole or not at all
    (``json_values.write_whole``): a run stopped mid-write left a cut file that the summary
    read later."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.json"
    write_whole(path, json.dumps(_jsonable(payload), indent=1) + "\n")
    return path


def save_figure(fig, path) -> None:
    """Write a benchmark's figure (110 dpi) whole or not at all (``json_values.whole_path``):
    ``savefig`` in place left a cut PNG where the earlier run's was when stopped mid-write."""
    with whole_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray | jax.Array):
        return _jsonable(np.asarray(x).tolist())
    if isinstance(x, np.floating | float):
        v = float(x)
        return v if np.isfinite(v) else str(v)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def fmt(x: float, digits: int = 3) -> str:
    """Compact number formatting for the markdown tables."""
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    if x == 0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-2:
        return f"{x:.{digits - 1}e}"
    return f"{x:.{digits}g}"


def md_table(header: list[str], rows: list[list]) -> str:
    """A GitHub markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in rows:
        lines.append(
            "| "
            + " | ".join(fmt(v) if isinstance(v, float) or v is None else str(v) for v in r)
            + " |"
        )
    return "\n".join(lines)


MAX_REPEATS = 1000
"""Most timed repeats of one benchmark (``--repeats``): 20 is the most a default asks for."""


def whole(lo: int = 1, unit: str = "", hi: int | None = None):
    """An argparse ``type=`` for a whole-number option in [lo, hi] (``hi`` None: no upper
    bound): a bad value is one line naming the range and the unit (with ``OneLineParser``),
    exit status 2, before any benchmark runs. Counts of rays, pixels or repeats take an upper
    bound (before: ``--rays 10**12`` aborted in XLA, ``--repeats 10**9`` ran for ever)."""
    import argparse

    def parse(text: str) -> int:
        try:
            v = checks.cli_int(text)  # ASCII digits: int() also took "1_0" as 10
        except ValueError:
            v = None
        if v is None or v < lo or (hi is not None and v > hi):
            u = f" {unit}" if unit else ""
            top = "inf)" if hi is None else f"{hi}]"
            raise argparse.ArgumentTypeError(f"must be a whole number in [{lo}, {top}{u}, got "
                                             f"{text!r}")
        return v

    return parse


def foreign_result(path: pathlib.Path, module: str) -> str | None:
    """Why the existing file ``path`` is not a result of ``benchmarks.<module>`` (its JSON
    ``command`` names the module), else None: a run would write over it."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        return "it is not JSON"
    command = data.get("command") if isinstance(data, dict) else None
    if not isinstance(command, str):
        return "it has no \"command\" entry"
    if command.split()[:3] != ["python", "-m", f"benchmarks.{module}"]:
        return f"it is a result of {command[:60]!r}"
    return None


def out_path(kind: str = "file", *, make_parents: bool = True, result_of: str | None = None):
    """An argparse ``type=`` for an output ``kind`` ("file" or "folder"): refuses, before any
    benchmark runs, a folder given for a file, a file given for a folder, a path whose
    folder could not be created (``make_parents``) or does not exist, and an existing file
    that is no result of the benchmark module ``result_of``."""
    import argparse

    def parse(text: str) -> pathlib.Path:
        if not text.strip():  # pathlib.Path("") is ".": a folder run wrote into the cwd
            raise argparse.ArgumentTypeError(f"needs a {kind}'s path, got an empty one")
        p = pathlib.Path(text)
        if kind == "file" and p.is_dir():
            raise argparse.ArgumentTypeError(f"{text} is a folder; give a file's path")
        why = foreign_result(p, result_of) if result_of and p.is_file() else None
        if why:  # before: written over (a lens file, notes, another benchmark's result)
            raise argparse.ArgumentTypeError(
                f"{text} is not a {result_of} result ({why}), and this run would write over "
                f"it; move it away or give another path")
        if kind == "folder" and p.exists() and not p.is_dir():
            raise argparse.ArgumentTypeError(f"{text} is a file, not a folder")
        parent = p.absolute().parent
        while make_parents and not parent.exists():
            parent = parent.parent
        if not parent.is_dir():
            raise argparse.ArgumentTypeError(f"{text}: {parent} is not an existing folder")
        return p

    return parse


if __name__ == "__main__":  # ran nothing, without a word
    raise SystemExit("benchmarks.common is a helper of the benchmarks, not one: run "
                     "python -m benchmarks (--only NAME for one benchmark)")
