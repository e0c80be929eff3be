"""Would JAX's persistent compilation cache speed up a second ``python -m jaxlens report``?

Runs ``report LENS --json [--plot DIR]`` twice, each in its own process, with a fresh
``JAX_COMPILATION_CACHE_DIR`` (the cold run writes it, the warm run reads it), and prints
each run's seconds, the cache entries written, the programs JAX did not write and why
(leaving out those compiled in under ``jax_persistent_cache_min_compile_time_secs``, 1 s),
and whether the two runs' ``--json`` are identical. JAX writes no program that holds a
host callback ("... because it uses host callbacks"), and every ``eqx.error_if`` traced
into a program is one. ``--eqx-on-error nan`` runs both with ``EQX_ON_ERROR=nan``, under
which ``error_if`` needs no callback (a failed check gives NaN instead of an error).

Measured (2-core AMD EPYC, shared, 2026-12-01): with equinox's default no program of
``report --plot`` is written (each holds an ``error_if``), so a second run is as slow as
the first; with ``nan`` the double Gauss (``rayoptics_US00583336-2-scaled.zmx``, real-ray
aiming) takes 135.8 s cold and 37.2 s warm, the Cooke triplet 34.1 and 19.8 s, ``--json``
the same. What stays is tracing, the small eager programs and the run itself.

Since the analyses' cores skip re-checks of inputs their entry points checked
(``jaxlens.optics.checked_inputs``, later the same day) every program is written with the
default ``raise`` too: with ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0`` (what the command
line now uses) the double Gauss takes 63.0 s cold and 28.5 s warm, against 73.4 and 60.5 s
before, when ten programs were not written.

    PYTHONPATH=. python tools/report_cache_probe.py jaxlens/data/lenses/cooke_triplet.json --plot
    PYTHONPATH=. python tools/report_cache_probe.py LENS --plot --eqx-on-error nan
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

# Run in the child: JAX's cache log on stderr, then the command itself.
_CHILD = """
import logging, runpy, sys
h = logging.StreamHandler(sys.stderr)
for n in ("jax._src.compiler", "jax._src.compilation_cache"):
    logging.getLogger(n).setLevel(logging.DEBUG)
    logging.getLogger(n).addHandler(h)
sys.argv = ["jaxlens"] + sys.argv[1:]
runpy.run_module("jaxlens", run_name="__main__")
"""


def run_once(lens: str, plot: str | None, env: dict) -> tuple[float, str, str]:
    """(seconds, stdout, stderr) of one ``report`` process."""
    cmd = [sys.executable, "-c", _CHILD, "report", lens, "--json"]
    if plot:
        cmd += ["--plot", plot, "--overwrite"]
    t = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(f"report {lens} failed: {p.stderr[-2000:]}")
    return time.perf_counter() - t, p.stdout, p.stderr


def not_written(log: str) -> dict[str, str]:
    """Programs JAX did not write, and why (those too quick to compile to be kept left out)."""
    return {m[1]: m[2].strip() for m in re.finditer(
        r"Not writing persistent cache entry for '(\S+)' because (.*)", log)
        if "seconds to compile" not in m[2]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("lens", help="lens file (.json or .zmx)")
    ap.add_argument("--plot", action="store_true", help="also write the figures (report --plot)")
    ap.add_argument("--eqx-on-error", choices=("raise", "nan"), default="raise",
                    help="EQX_ON_ERROR for both runs (default raise, equinox's own)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as figs:
        env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=cache, EQX_ON_ERROR=a.eqx_on_error)
        runs = [run_once(a.lens, figs if a.plot else None, env) for _ in range(2)]
        entries = [f for f in os.listdir(cache) if f.endswith("-cache")]
    (cold, out_cold, log_cold), (warm, out_warm, _) = runs
    print(f"{a.lens}{' --plot' if a.plot else ''}, EQX_ON_ERROR={a.eqx_on_error}: "
          f"cold {cold:.1f} s, warm {warm:.1f} s; {len(entries)} cache entries written; "
          f"--json of both runs identical: {out_cold == out_warm}")
    for name, why in sorted(not_written(log_cold).items()):
        print(f"  not written: {name}: {why}")


if __name__ == "__main__":
    main()
