"""Reference EFL and BFL of .zmx files from optiland (run with optiland's Python, not jaxlens's).

optiland 0.6.3 reads a multi-configuration file as its surfaces give it (the active
configuration). For the others, ``--expand`` writes each configuration of a file whose
operands are all ``THIC`` as a single-configuration file (the DISZ lines replaced by the
configuration's values, the MNUM section left out) and measures those.

    /work/optiland_venv/bin/python tools/zmx_config_reference.py tests/data/zmx_config/zoom_c*.zmx
    /work/optiland_venv/bin/python tools/zmx_config_reference.py --expand FILE.zmx

Prints, for each file (or configuration): optiland's f2 (n'/Phi) and BFL (its F2, the focus
from the image surface, plus the last lens surface's DISZ), both in mm.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import warnings

import numpy as np

UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}


def _text(path: str) -> str:
    with open(path, "rb") as fh:
        raw = fh.read()
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return raw.decode("utf-16")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _unit(text: str) -> float:
    for line in text.splitlines():
        t = line.split()
        if len(t) > 1 and t[0] == "UNIT":
            return UNITS.get(t[1].upper(), 1.0)
    return 1.0


def measure(path: str) -> tuple[float, float]:
    """optiland's (f2, BFL) of a file, in mm."""
    from optiland.fileio import load_zemax_file

    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        optic = load_zemax_file(path)
        u = _unit(_text(path))
        f2 = float(np.ravel(np.asarray(optic.paraxial.f2()))[0]) * u
        # F2 is the focus measured from the image surface: add the last lens surface's DISZ
        back = float(np.ravel(np.asarray(optic.paraxial.F2()))[0]) + _last_gap(path)
    return f2, back * u


def _last_gap(path: str) -> float:
    """The DISZ of the last lens surface (the one before the image), in lens units."""
    disz, surf = {}, None
    for line in _text(path).splitlines():
        t = line.split()
        if t[:1] == ["SURF"]:
            surf = int(t[1])
        elif t[:1] == ["DISZ"] and surf is not None:
            disz[surf] = float(t[1]) if t[1].upper() != "INFINITY" else float("inf")
    return disz[max(disz) - 1]


def expand(path: str, folder: str) -> list[str]:
    """One single-configuration file per configuration of a THIC-only multi-config file."""
    lines = _text(path).splitlines()
    mnum = next(i for i, ln in enumerate(lines) if ln.split()[:1] == ["MNUM"])
    t = lines[mnum].split()
    n = int(t[1])
    thic: dict = {}
    for ln in lines[mnum + 1:]:
        tok = ln.split()
        if not tok or tok[0] in ("MOFF",):
            continue
        if tok[0] != "THIC":
            raise SystemExit(f"{path}: --expand handles THIC operands only, found {tok[0]}")
        thic.setdefault(int(tok[1]), {})[int(tok[2])] = tok[3]
    out = []
    for c in range(1, n + 1):
        surf, body = None, []
        for ln in lines[:mnum]:
            tok = ln.split()
            if tok[:1] == ["SURF"]:
                surf = int(tok[1])
            if tok[:1] == ["DISZ"] and surf in thic:
                ln = f"  DISZ {thic[surf][c]}"
            if tok[:1] == ["WAVL"]:
                continue  # optiland 0.6.3 fails on a one-value WAVL beside WAVM lines
            body.append(ln)
        p = os.path.join(folder, f"config{c}.zmx")
        with open(p, "w", encoding="utf-8") as fh:  # temporary folder (main's)
            fh.write("\n".join(body) + "\n")
        out.append(p)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--expand", action="store_true",
                    help="measure every configuration of a THIC-only multi-config file")
    args = ap.parse_args(argv)
    for f in args.files:  # before optiland's import and the first file's work
        if not os.path.isfile(f):
            ap.error(f"{f}: no such file")
        if os.path.splitext(f)[1].lower() != ".zmx":
            ap.error(f"{f}: not a .zmx file (optiland reads Zemax files)")
        if args.expand and not any(ln.split()[:1] == ["MNUM"] for ln in _text(f).splitlines()):
            ap.error(f"{f}: --expand needs a multi-configuration file (an MNUM section); "
                     f"measure a single-configuration file without --expand")
    for f in args.files:
        if args.expand:
            with tempfile.TemporaryDirectory() as d:
                for c, p in enumerate(expand(f, d), start=1):
                    f2, bfl = measure(p)
                    print(f"{os.path.basename(f)} config {c}: f2 {f2!r} BFL {bfl!r}")
        else:
            f2, bfl = measure(f)
            print(f"{os.path.basename(f)}: f2 {f2!r} BFL {bfl!r}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
