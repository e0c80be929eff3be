"""Compare jaxlens with the round-42c references of tools/fuzz42c_reference.py.

Run with jaxlens's venv, from the repository root::

    PYTHONPATH=. python tools/fuzz42c_compare.py FOLDER [NAME ...]

Every ``fuzz42c_*.json`` in FOLDER (or the NAMEs) is compared by
``tests/test_fuzz_round42c.py``'s ``case_errors`` (jaxlens's trace of each stored launch ray
against optiland's image intercept and direction, global frame), one line a case, then the
largest error of each quantity per class and over all. Writes ``compare_42c.json`` in FOLDER.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from test_fuzz_round42c import DIR_ABS, POS_ABS, case_errors  # noqa: E402


def over(err):
    bad = []
    if err["valid"] > 0:
        bad.append("valid")
    if not err["ray_pos"] <= POS_ABS:
        bad.append("ray_pos")
    if not err["ray_dir"] <= DIR_ABS:
        bad.append("ray_dir")
    return bad


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz42c_compare.py", description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="the folder of fuzz42c_*.json")
    ap.add_argument("names", nargs="*", help="only these cases")
    args = ap.parse_args(argv)
    folder = pathlib.Path(args.folder)
    if not folder.is_dir():
        ap.error(f"{folder} is not a folder")
    paths = [folder / f"{n}.json" for n in args.names] or sorted(folder.glob("fuzz42c_*.json"))
    if not paths:
        raise SystemExit(f"no fuzz42c_*.json in {folder}")
    rows, by_kind, failed = {}, {}, 0
    for path in paths:
        t0 = time.time()
        kind = path.stem.split("_")[1]
        try:
            err, _ = case_errors(path)
        except Exception as exc:  # noqa: BLE001  reported, and the others still run
            print(f"{path.stem}: ERROR {exc!r}"[:300], flush=True)
            rows[path.stem] = {"error": repr(exc)[:300]}
            by_kind.setdefault(kind, {"cases": 0})["errors"] = (
                by_kind.get(kind, {}).get("errors", 0) + 1)
            failed += 1
            continue
        rows[path.stem] = err
        for key in (kind, "all"):
            table = by_kind.setdefault(key, {"cases": 0})
            table["cases"] += 1
            for k, v in err.items():
                if math.isnan(v) or v >= table.get(k, -1.0):
                    table[k] = v
        bad = over(err)
        failed += bool(bad)
        print(f"{path.stem}: {time.time() - t0:5.1f}s "
              + " ".join(f"{k} {v:.1e}" for k, v in err.items())
              + (f"  OVER {bad}" if bad else ""), flush=True)
    print("\n| class | cases | max |Δ| position (mm) | max |Δ| direction | rays lost | "
          "largest coordinate (mm) |")
    print("|---|---|---|---|---|---|")
    for kind, t in sorted(by_kind.items(), key=lambda kv: (kv[0] == "all", kv[0])):
        if "ray_pos" not in t:
            print(f"| {kind} | errors {t} |")
            continue
        print(f"| {kind} | {t['cases']} | {t['ray_pos']:.1e} | {t['ray_dir']:.1e} | "
              f"{t['valid']:.0%} | {t['size']:.0f} |")
    print(f"\n{failed} of {len(paths)} over the tolerances or in error")
    (folder / "compare_42c.json").write_text(
        json.dumps({"rows": rows, "by_kind": by_kind}, indent=1) + "\n")
    return failed


if __name__ == "__main__":
    sys.exit(1 if main(sys.argv[1:]) else 0)
