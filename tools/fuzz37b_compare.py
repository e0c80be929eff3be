"""Compare jaxlens with the round-37b references of tools/fuzz37b_reference.py.

Run with jaxlens's venv, from the repository root::

    PYTHONPATH=. python tools/fuzz37b_compare.py lenses FOLDER [NAME ...] [--rays-only]
    PYTHONPATH=. python tools/fuzz37b_compare.py glasses FOLDER/glasses.json

``lenses``: every ``fuzz37b_*.json`` in FOLDER is compared by ``tools/fuzz36b_compare.py``'s
``compare`` (the checks of ``tests/test_trace.py``: float64 intercepts and directions of all
real rays, the x-field skew rays included, paraxial data, RMS spots, distortion), one line a
case, the largest error of each quantity over all cases and over each class; the intercept
error is also given relative to the case's size (``ray_pos_rel``: mm over the largest
coordinate), which is what the scale classes test. ``--rays-only`` leaves out the RMS spots
and distortion (most of a case's time). Writes ``compare_37b.json`` in FOLDER.

``glasses``: for every glass of the file, jaxlens's index (``get_material(name, [CATALOG])``,
the formula's value: ``extrapolated_index``) against optiland's at the same wavelengths, and
both against an independent numpy evaluation of each side's own published coefficients
(jaxlens's AGF ``CD`` record, the refractiveindex.info file's formula), so a disagreement is
put down to a wrong evaluation or to different catalog data. Glasses that differ beyond
1e-6 are listed with their catalog nd and Vd, each side's computed nd and Vd, and whether
each side reproduces its own listed values. Writes ``compare_glasses.json`` beside the file.
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

import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from fuzz36b_compare import BAR, compare  # noqa: E402
from helpers import refcase_lens, refcase_rays  # noqa: E402  (fuzz36b_compare put tests/ on the path)

LD, LF, LC = 0.5875618, 0.4861327, 0.6562725


# ------------------------------------------------------------------------------ glasses
def rii_formula(kind, c, w):
    """refractiveindex.info formulas 1, 2 and 3 (λ in µm), evaluated here in numpy."""
    c, w2 = np.asarray(c, float), np.asarray(w, float) ** 2
    if kind == "formula 1":
        n2 = 1 + c[0] + sum(c[i] * w2 / (w2 - c[i + 1] ** 2) for i in range(1, len(c) - 1, 2))
    elif kind == "formula 2":
        n2 = 1 + c[0] + sum(c[i] * w2 / (w2 - c[i + 1]) for i in range(1, len(c) - 1, 2))
    elif kind == "formula 3":
        n2 = c[0] + sum(c[i] * np.asarray(w, float) ** c[i + 1] for i in range(1, len(c) - 1, 2))
    else:
        raise ValueError(f"formula {kind!r} not evaluated here")
    return np.sqrt(n2)


AGF_POWERS = {
    1: (0, 2, -2, -4, -6, -8),
    10: (0, 2, -2, -4, -6, -8, -10, -12),
    12: (0, 2, -2, -4, -6, -8, 4, 6),
    13: (0, 2, 4, -2, -4, -6, -8, -10, -12),
}


def agf_formula(formula, cd, w):
    """Zemax AGF formulas 1, 2, 6, 10, 11, 12, 13 (λ in µm), evaluated here in numpy."""
    w = np.asarray(w, float)
    if formula in AGF_POWERS:
        p = AGF_POWERS[formula]
        c = list(cd) + [0.0] * (len(p) - len(cd))
        return np.sqrt(sum(a * w**k for a, k in zip(c, p, strict=False)))
    terms = {2: 3, 6: 4, 11: 5}.get(formula)
    if terms is None:
        raise ValueError(f"AGF formula {formula} not evaluated here")
    c = list(cd) + [0.0] * (2 * terms - len(cd))
    return np.sqrt(1 + sum(c[2 * i] * w**2 / (w**2 - c[2 * i + 1]) for i in range(terms)))


def _agf_cd(catalog):
    """Name → (formula, CD coefficients, nd, Vd) of a shipped catalog, read here."""
    path = pathlib.Path(jl.__file__).parent / "data" / "glass" / f"{catalog}.agf"
    out, name = {}, None
    for line in path.read_text(encoding="latin-1").splitlines():
        t = line.split()
        if t and t[0] == "NM":
            name = t[1].upper()
            out[name] = [int(float(t[2])), [], float(t[4]), float(t[5])]
        elif t and t[0] == "CD" and name:
            out[name][1] = [float(x) for x in t[1:]]
    return out


def compare_glasses(path):
    d = json.loads(pathlib.Path(path).read_text())
    rows, worst, missing = [], {}, []
    for cat, glasses in d["glasses"].items():
        cds = _agf_cd(cat)
        for name, g in glasses.items():
            try:
                m = jl.get_material(name, catalogs=[cat])
            except Exception as e:  # noqa: BLE001
                missing.append([cat, name, str(e)[:120]])
                continue
            w = np.array(g["wavelengths_um"])
            mine = np.asarray(m.extrapolated_index(w))
            theirs = np.array(g["n"])
            own_rii = rii_formula(g["formula_type"], g["coefficients"], w)
            formula, cd, nd, vd = cds[m.name.upper()]
            own_agf = agf_formula(formula, cd, w)
            lo, hi = m.wavelength_range or (0, math.inf)
            both = (w >= max(lo, g["range_um"][0])) & (w <= min(hi, g["range_um"][1]))
            diff = np.abs(mine - theirs)
            e = float(diff[both].max()) if both.any() else 0.0
            worst[cat] = max(worst.get(cat, 0.0), e)
            row = dict(
                catalog=cat,
                name=name,
                max_diff_in_both_ranges=e,
                at_um=float(w[both][np.argmax(diff[both])]) if both.any() else None,
                jaxlens_vs_own_agf=float(np.abs(mine - own_agf).max()),
                optiland_vs_own_formula=float(np.abs(theirs - own_rii).max()),
                jaxlens_formula=formula,
                optiland_formula=g["formula_type"],
                jaxlens_range=[lo, hi],
                optiland_range=g["range_um"],
                references=g["references"][:140],
            )
            nds = [agf_formula(formula, cd, x) for x in (LD, LF, LC)]
            nro = [rii_formula(g["formula_type"], g["coefficients"], x) for x in (LD, LF, LC)]
            row.update(
                agf_nd_vd=[nd, vd],
                agf_formula_nd_vd=[float(nds[0]), float((nds[0] - 1) / (nds[1] - nds[2]))],
                rii_specs_nd_vd=[g["specs"].get("nd"), g["specs"].get("Vd")],
                rii_formula_nd_vd=[float(nro[0]), float((nro[0] - 1) / (nro[1] - nro[2]))],
            )
            rows.append(row)
    bad = sorted(
        (r for r in rows if r["max_diff_in_both_ranges"] > 1e-6),
        key=lambda r: -r["max_diff_in_both_ranges"],
    )
    for r in bad:
        print(
            f"{r['catalog']} {r['name']}: {r['max_diff_in_both_ranges']:.2e} at {r['at_um']} µm;"
            f" AGF formula {r['jaxlens_formula']} nd/Vd listed {r['agf_nd_vd']} computed "
            f"{np.round(r['agf_formula_nd_vd'], 6).tolist()}; rii {r['optiland_formula']} listed"
            f" {r['rii_specs_nd_vd']} computed {np.round(r['rii_formula_nd_vd'], 6).tolist()}"
        )
    own = (
        max(r["jaxlens_vs_own_agf"] for r in rows),
        max(r["optiland_vs_own_formula"] for r in rows),
    )
    print(f"glasses compared: {len(rows)}, not found in jaxlens: {len(missing)}")
    print(
        "largest |jaxlens - optiland| within both ranges per catalog:",
        {k: float(f"{v:.2e}") for k, v in worst.items()},
    )
    print(
        f"over 1e-6: {len(bad)} ({sorted({r['catalog'] for r in bad})}); each side against "
        f"its own coefficients evaluated here: jaxlens {own[0]:.1e}, optiland {own[1]:.1e}"
    )
    out = pathlib.Path(path).with_name("compare_glasses.json")
    out.write_text(json.dumps(dict(worst=worst, over_1e6=bad, missing=missing), indent=1) + "\n")


# ------------------------------------------------------------------------------ lenses
def compare_rays(path):
    """``--rays-only``: the real rays and the paraxial data of ``compare``, without the RMS
    spots and distortion (their compiled programs take most of a case's time)."""
    lens, d = refcase_lens(path)
    rays, ref = refcase_rays(d)
    out = jl.trace(lens, rays)
    p, r = jl.paraxial_data(lens), d["paraxial"]
    fields = [float(f) for f in r["paraxial_chief_ray_y_at_image_vertex"]]
    h = np.asarray(jl.paraxial.image_height(lens, np.array(fields)))
    err = dict(
        valid=float(np.mean(~np.asarray(out.valid))),
        ray_pos=float(np.abs(np.asarray(out.origin) - ref[:, :3]).max()),
        ray_dir=float(np.abs(np.asarray(out.direction) - ref[:, 3:]).max()),
        paraxial_rel=max(
            abs(float(p.efl) / r["EFL"] - 1),
            abs(float(p.bfl) / r["BFL"] - 1),
            abs(float(p.fnum) / r["FNO"] - 1),
            abs(float(p.entrance_pupil_z) - r["entrance_pupil_z"])
            / max(1.0, abs(r["entrance_pupil_z"])),
        ),
        parax_height=max(
            abs(float(h[i]) - v)
            for i, v in enumerate(r["paraxial_chief_ray_y_at_image_vertex"].values())
        ),
    )
    return err, d


def compare_lenses(folder, names, rays_only=False):
    folder = pathlib.Path(folder)
    paths = [folder / f"{n}.json" for n in names] or sorted(folder.glob("fuzz37b_*.json"))
    if not paths:
        raise SystemExit(f"no fuzz37b_*.json in {folder}")
    worst, by_kind, rows = {}, {}, {}
    for path in paths:
        t0 = time.time()
        try:
            err, d = compare_rays(path) if rays_only else compare(path)
        except Exception as exc:  # noqa: BLE001  reported, and the others still run
            print(f"{path.stem}: ERROR {exc!r}"[:300], flush=True)
            rows[path.stem] = {"error": repr(exc)[:300]}
            continue
        size = max(
            abs(v)
            for r in d["real_rays"]
            for v in (r["image"]["x"], r["image"]["y"], r["image"]["z"])
        )
        err["ray_pos_rel"] = err["ray_pos"] / size
        rows[path.stem] = err
        kind = d["generator"].get("kind", "?")
        bad = [
            k
            for k, v in err.items()
            if (k.startswith("valid") and v > 0) or (k in BAR and not v <= BAR[k])
        ]
        for table in (worst, by_kind.setdefault(kind, {})):
            for k, v in err.items():
                if math.isnan(v) or v >= table.get(k, (-1, ""))[0]:
                    table[k] = (v, path.stem)
        print(
            f"{path.stem}: {time.time() - t0:5.1f}s "
            + " ".join(f"{k} {v:.1e}" for k, v in err.items())
            + (f"  OVER {bad}" if bad else ""),
            flush=True,
        )
    for kind, table in sorted(by_kind.items()):
        print(f"largest ({kind}):", " ".join(f"{k} {v[0]:.2e}" for k, v in table.items()))
    print("largest:", " ".join(f"{k} {v[0]:.2e} ({v[1]})" for k, v in worst.items()))
    (folder / "compare_37b.json").write_text(
        json.dumps({"rows": rows, "worst": worst, "by_kind": by_kind}, indent=1) + "\n"
    )


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz37b_compare.py", description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("lenses", "glasses"))
    ap.add_argument("path", help="lenses: the folder of fuzz37b_*.json; glasses: glasses.json")
    ap.add_argument("names", nargs="*", help="lenses: only these cases")
    ap.add_argument(
        "--rays-only",
        action="store_true",
        help="lenses: real rays and paraxial data only, no RMS spots or distortion",
    )
    args = ap.parse_args(argv)
    if not pathlib.Path(args.path).exists():
        ap.error(f"{args.path} does not exist")
    if args.what == "glasses":
        compare_glasses(args.path)
    else:
        compare_lenses(args.path, args.names, args.rays_only)


if __name__ == "__main__":
    main(sys.argv[1:])
