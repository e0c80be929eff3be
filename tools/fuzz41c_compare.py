"""Compare jaxlens with the round-41c references of tools/fuzz41c_reference.py.

Run with jaxlens's venv, from the repository root::

    PYTHONPATH=. python tools/fuzz41c_compare.py FOLDER [NAME ...]

Every ``fuzz41c_*.json`` in FOLDER (or the NAMEs) is compared by
``tests/test_fuzz_round41c.py``'s ``case_errors`` (jaxlens's own rays of each field, pupil
point and wavelength against optiland's; the paraxial data), one line a case, then the
largest error of each quantity per class and over all. Writes ``compare_41c.json`` in FOLDER.
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
from test_fuzz_round41c import DIR_ABS, PARAX_REL, POS_ABS, POS_REL, case_errors  # noqa: E402


def over(err):
    bad = []
    if err["valid"] > 0:
        bad.append("valid")
    if not err["ray_pos"] <= POS_ABS + POS_REL * err["size"]:
        bad.append("ray_pos")
    if not err["ray_dir"] <= DIR_ABS:
        bad.append("ray_dir")
    if not err["parax_rel"] <= PARAX_REL:
        bad.append("parax_rel")
    return bad


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz41c_compare.py", description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="the folder of fuzz41c_*.json")
    ap.add_argument("names", nargs="*", help="only these cases")
    args = ap.parse_args(argv)
    folder = pathlib.Path(args.folder)
    if not folder.is_dir():
        ap.error(f"{folder} is not a folder")
    paths = [folder / f"{n}.json" for n in args.names] or sorted(folder.glob("fuzz41c_*.json"))
    if not paths:
        raise SystemExit(f"no fuzz41c_*.json in {folder}")
    rows, by_kind = {}, {}
    for path in paths:
        t0 = time.time()
        try:
            err, d = case_errors(path)
        except Exception as exc:  # noqa: BLE001  reported, and the others still run
            print(f"{path.stem}: ERROR {exc!r}"[:300], flush=True)
            rows[path.stem] = {"error": repr(exc)[:300]}
            by_kind.setdefault(path.stem.split("_", 1)[1].rsplit("_", 1)[0], {})["errors"] = (
                by_kind.get("errors", 0) + 1)
            continue
        rows[path.stem] = err
        table = by_kind.setdefault(d["kind"], {"cases": 0})
        table["cases"] += 1
        for k, v in err.items():
            if k != "size" and (math.isnan(v) or v >= table.get(k, -1.0)):
                table[k] = v
        bad = over(err)
        print(f"{path.stem}: {time.time() - t0:5.1f}s "
              + " ".join(f"{k} {v:.1e}" for k, v in err.items() if k != "size")
              + (f"  OVER {bad}" if bad else ""), flush=True)
    print("\n| class | cases | max ray_pos (mm) | max ray_pos_rel | max ray_dir | lost | "
          "max parax_rel |")
    print("|---|---|---|---|---|---|---|")
    for kind, t in sorted(by_kind.items()):
        if "ray_pos" not in t:
            print(f"| {kind} | errors {t} |")
            continue
        print(f"| {kind} | {t['cases']} | {t['ray_pos']:.1e} | {t['ray_pos_rel']:.1e} | "
              f"{t['ray_dir']:.1e} | {t['valid']:.0%} | {t['parax_rel']:.1e} |")
    (folder / "compare_41c.json").write_text(
        json.dumps({"rows": rows, "by_kind": by_kind}, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
