# ruff: noqa: E501
"""The table that the bad-input probe scripts (tools/audit17_probe.py and later) print.

Each script calls ``probe`` for every input it throws at jaxlens, then ``run`` with its probe
areas, which prints one row per probe (probe | outcome | what happened) and the counts.
A filter word given as the script's first argument keeps the probes whose names hold it.
"""

import glob
import importlib
import inspect
import io
import os
import re
import subprocess
import sys
import tempfile
import warnings
from contextlib import redirect_stderr, redirect_stdout

import numpy as np

ROWS = []
# The paths the probe scripts (round 29 and later) share; TMP is a fresh folder a process.
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TMP = tempfile.mkdtemp()
COOKE = os.path.join(ROOT, "jaxlens", "data", "lenses", "cooke_triplet.json")
SEED0 = os.path.join(ROOT, "experiments", "classical", "designs", "seed_0.zmx")
FILTER = sys.argv[1] if len(sys.argv) > 1 else ""


def probe(name, fn, *words, good=False):
    """Run fn; classify. ``words``: what a clear message must hold (case-insensitive)."""
    if FILTER and FILTER not in name:
        return
    try:
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            r = fn()
    except SystemExit as e:  # argparse / a CLI's refusal
        msg = err.getvalue().strip().splitlines()
        text = msg[-1] if msg else f"exit {e.code}"
        ok = e.code == 2 and all(w.lower() in text.lower() for w in words)
        outcome = "ok" if good and e.code == 0 else ("clear error" if ok else "vague error")
        ROWS.append((name, outcome, text[:160]))
        return
    except (ValueError, TypeError) as e:
        text = str(e).split("\n")[0]
        ok = all(w.lower() in str(e).lower() for w in words)
        outcome = "crash" if good else ("clear error" if ok else "vague error")
        ROWS.append((name, outcome, f"{type(e).__name__}: {text[:150]}"))
        return
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {str(e).splitlines()[0][:150] if str(e) else ''}"))
        return
    if isinstance(r, int) and not isinstance(r, bool) and r != 0 and getattr(fn, "cli", False):
        msg = err.getvalue().strip().splitlines()
        text = msg[-1] if msg else f"exit {r}"
        ok = r == 2 and all(w.lower() in text.lower() for w in words)
        ROWS.append((name, "clear error" if ok else "vague error", text[:160]))
        return
    try:
        s = np.array2string(np.asarray(r), precision=5)[:100] if not isinstance(
            r, (str, dict, list, tuple)) else repr(r)[:100]
    except Exception:  # noqa: BLE001
        s = type(r).__name__
    ROWS.append((name, "ok" if good else "silent wrong", s.replace("\n", " ")))


def warned(fn):
    """A warning counts as the answer (raised as a ValueError holding its message)."""
    def go():
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            r = fn()
        w = [x for x in w if issubclass(x.category, UserWarning)]
        if w:
            raise ValueError(f"warned: {w[0].message}")
        return r
    go.cli = getattr(fn, "cli", False)
    return go


def checked(name, fn):
    """A row for an answer ``fn`` judges itself: ``fn`` returns (right, text); a wrong
    answer is "silent wrong", an exception a crash (as ``probe`` counts one)."""
    if FILTER and FILTER not in name:
        return
    try:
        right, text = fn()
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {str(e)[:150]}"))
        return
    ROWS.append((name, "ok" if right else "silent wrong", text[:160]))


def jitted(fn, *args):
    """``fn(*args)`` under ``jax.jit`` with every argument traced (a bad value must not pass):
    an ``eqx.error_if`` (a runtime error holding its message) counts as a ValueError."""
    def go():
        import jax

        try:
            return jax.block_until_ready(jax.jit(fn)(*args))
        except RuntimeError as e:
            said = [line.split("Error: ", 1)[1] for line in str(e).splitlines()
                    if "EquinoxRuntimeError: " in line]
            if said:
                raise ValueError(f"error_if under jit: {said[-1]}") from None
            raise
    return go


def cli(fn):
    """Mark ``fn`` as a command line's run (the table groups it apart)."""
    fn.cli = True
    return fn


def fresh(name):
    """A new empty folder under ``TMP`` named after ``name``."""
    d = os.path.join(TMP, f"{name}{len(os.listdir(TMP))}")
    os.makedirs(d)
    return d


class CutWriter:
    """A file that takes half of what is written, then is interrupted (Ctrl-C)."""

    def __init__(self, f):
        self.f = f

    def write(self, text):
        self.f.write(text[: len(text) // 2])
        self.f.flush()
        raise KeyboardInterrupt

    def __enter__(self):
        return self

    def __exit__(self, *a):
        self.f.close()


class Started(Exception):
    """Raised where a command's work would begin: its checks have passed."""


def started(*a, **k):
    raise Started


def until_started(fn):
    """``fn`` (a command) run up to its work: "started" when every check passed."""
    def go():
        try:
            return fn()
        except Started:
            return "started"
    go.cli = getattr(fn, "cli", False)
    return go


def patched(module, names, fn):
    """``fn`` run with ``module``'s functions ``names`` replaced by ``started``."""
    def go():
        real = {n: getattr(module, n) for n in names}
        for n in names:
            setattr(module, n, started)
        try:
            return fn()
        finally:
            for n, f in real.items():
                setattr(module, n, f)
    return until_started(go)


OPTILAND_PYTHON = "/work/optiland_venv/bin/python"
"""The interpreter of the optiland venv the probes of optiland-backed tools run in."""


def _run(argv, *, cwd, timeout: float, tail: int):
    """``argv`` run as a user runs it (this tree's jaxlens first on the path): its stdout's
    last ``tail`` characters, or its exit code and the last line of its stderr (exit 2, a
    refusal, is printed and re-raised as ``SystemExit(2)``; no answer in ``timeout`` s is a
    hang)."""
    try:
        p = subprocess.run(argv, capture_output=True, text=True, cwd=cwd, timeout=timeout,
                           env=dict(os.environ, PYTHONPATH=ROOT))
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"hang: no answer in {timeout} s") from None
    last = (p.stderr.strip().splitlines() or [""])[-1]
    if p.returncode == 2:
        print(last, file=sys.stderr)
        raise SystemExit(2)
    if p.returncode:
        raise RuntimeError(f"exit {p.returncode}: {last}")
    return p.stdout.strip()[-tail:]


def tool(script, *args, python=None):
    """A ``tools/`` script run as a user runs it (see ``_run``)."""
    return lambda: _run([python or sys.executable, os.path.join(ROOT, "tools", script), *args],
                        cwd=TMP, timeout=300, tail=100)


def module_cli(*args, module="jaxlens", timeout=600):
    """``python -m module args`` run as a user runs it, in a fresh folder (see ``_run``);
    wrapped by ``cli`` so that exit 2 counts as a clear refusal."""
    return cli(lambda: _run([sys.executable, "-m", module, *args], cwd=fresh("cli"),
                            timeout=timeout, tail=80))


def edof_check(*argv):
    """A probe of ``python -m jaxlens.experiments.edof``'s argument checks with ``argv`` (and
    ``--out`` under ``TMP``): "accepted", or the command's refusal as a ValueError."""
    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    def go():
        try:
            cli.check_args(cli.build_parser().parse_args(["--out", os.path.join(TMP, "edof"),
                                                          *argv]))
        except UsageError as e:
            raise ValueError(str(e)) from None
        return "accepted"
    return go


def run(areas):
    """Run each probe area (a function of ``probe`` calls), then print the table."""
    for area in areas:
        try:
            area()
        except Exception as e:  # noqa: BLE001  (a probe area that fails to set up)
            ROWS.append((f"[{area.__name__} setup]", "crash", f"{type(e).__name__}: {e}"[:160]))
    w = max(len(r[0]) for r in ROWS) if ROWS else 10
    print(f"{'probe':<{w}} | {'outcome':<12} | detail")
    print("-" * (w + 60))
    for name, outcome, detail in ROWS:
        print(f"{name:<{w}} | {outcome:<12} | {detail}")
    counts = {}
    for _, o, _ in ROWS:
        counts[o] = counts.get(o, 0) + 1
    print("\n" + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items())))


PACKAGES = ("jaxlens", "jaxlens.analysis", "jaxlens.design", "jaxlens.imaging", "jaxlens.io",
            "jaxlens.optics", "jaxlens.tracing", "jaxlens.zoo", "jaxlens.nets",
            "jaxlens.experiments.edof")
"""The packages whose exported names ``mention_counts`` counts."""


def mention_counts(skip, top):
    """Print the ``top`` exported names of ``PACKAGES`` named least in the probe scripts and
    bad-input tests (files for which ``skip(basename)`` is true left out: a round's own), each
    with its package and its parameters' counts (``name=``): how later rounds choose what to
    probe next."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    files = (glob.glob(f"{root}/tools/audit*_probe.py") + glob.glob(f"{root}/tests/test_input_probes*.py")
             + [f"{root}/tests/test_bad_input.py"] + glob.glob(f"{root}/tests/test_silent_answers*.py")
             + glob.glob(f"{root}/tests/test_numerics_*.py"))
    text = "\n".join(open(f).read() for f in files if not skip(os.path.basename(f)))
    seen = {}
    for pk in PACKAGES:
        m = importlib.import_module(pk)
        for n in getattr(m, "__all__", [n for n in dir(m) if not n.startswith("_")]):
            obj = getattr(m, n, None)
            if obj is not None and not inspect.ismodule(obj):
                seen.setdefault(n, (pk, obj))
    rows = []
    for n, (pk, obj) in seen.items():
        try:
            params = [q for q in inspect.signature(obj).parameters if q != "self"]
        except (TypeError, ValueError):
            params = []
        rows.append((len(re.findall(rf"\b{n}\b", text)), pk, n,
                     {q: len(re.findall(rf"\b{q}\s*=", text)) for q in params}))
    for r in sorted(rows, key=lambda r: r[0])[:top]:
        print(*r)
