"""Round 37b reference writer: catalog glass indices and random lenses of classes round 36b
did not draw, computed by optiland 0.6.3 (cross-checked by rayoptics 0.9.8).

Run with the optiland venv, never jaxlens's (jaxlens is not imported here)::

    /work/optenv/bin/python tools/fuzz37b_reference.py glasses OUT_FOLDER
    /work/optenv/bin/python tools/fuzz37b_reference.py lenses OUT_FOLDER [--n 40] [--seed 37]
        [--kind wide|scale_small|scale_large|far_wavelengths|high_order|all]

and compare jaxlens with what it writes with ``tools/fuzz37b_compare.py`` (jaxlens's venv).

``glasses`` writes ``glasses.json``: for every glass file of the SCHOTT, OHARA, HOYA, CDGM,
SUMITA and HIKARI folders of optiland's copy of the refractiveindex.info database, optiland's
index (``MaterialFile.n``, no temperature: the catalog formula itself) at 15 wavelengths from
0.365 to 1.064 µm (those inside the file's stated range), the file's formula type,
coefficients and range, so a disagreement can be settled from the published coefficients.

``lenses`` writes random lenses in the refcase schema (``../shared/refcases``, each file's
``conventions``), drawn and traced as ``tools/fuzz36b_reference.py`` draws and traces them
(its functions are reused), in classes it did not draw:

* ``wide``: an object at infinity with half the drawn EPD and a largest field of 60 to 85
  degrees, lowered by 10 % steps until every stored ray passes (a draw that does not reach
  45 degrees is redrawn with sub-seeds 1 to 11);
* ``scale_small`` / ``scale_large``: fuzz36b's draws with every length scaled so that the
  length scale is 0.5 to 1.5 mm, or 800 to 2000 mm;
* ``far_wavelengths``: wavelengths 587.5618 (primary), 365.0, 404.6565 and 1013.98 nm;
* ``high_order``: even aspheres with A2..A14 or A2..A16 on most surfaces.

Every case also stores skew rays: each non-zero field turned into the x-z plane (direction
(sin th, 0, cos th)) at five pupil points, marked ``field_axis: "x"`` among the real rays,
traced by optiland and checked against rayoptics like the others.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import platform
import sys
import time
import warnings
from importlib import resources

import numpy as np

warnings.filterwarnings("ignore")

MAKERS = ("schott", "ohara", "hoya", "cdgm", "sumita", "hikari")
GLASS_WLS_UM = (
    0.365,
    0.4046565,
    0.4358343,
    0.4799914,
    0.4861327,
    0.5460740,
    0.5875618,
    0.6438469,
    0.6562725,
    0.7065188,
    0.7800,
    0.8521101,
    0.9000,
    1.0139750,
    1.0642,
)


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:  # noqa: BLE001
        return None


# ------------------------------------------------------------------------------------------
def glasses(out):
    """optiland's catalog indices of every glass file of MAKERS, in ``out/glasses.json``."""
    import yaml
    from optiland.materials.material_file import MaterialFile

    root = pathlib.Path(str(resources.files("optiland.database"))) / "data-nk" / "glass"
    rows, skipped = {}, {}
    for maker in MAKERS:
        for path in sorted((root / maker).glob("*.yml")):
            raw = yaml.safe_load(path.read_text(encoding="utf-8"))
            formula = next(
                (d for d in raw.get("DATA", []) if str(d.get("type", "")).startswith("formula")),
                None,
            )
            if formula is None:
                skipped[f"{maker}/{path.stem}"] = "no formula (tabulated only)"
                continue
            lo, hi = map(float, str(formula["wavelength_range"]).split())
            wls = [w for w in GLASS_WLS_UM if lo <= w <= hi]
            try:
                mat = MaterialFile(str(path))
                n = [float(np.asarray(mat.n(np.array([w])))[0]) for w in wls]
            except Exception as e:  # noqa: BLE001
                skipped[f"{maker}/{path.stem}"] = repr(e)[:200]
                continue
            rows.setdefault(maker.upper(), {})[path.stem] = dict(
                formula_type=str(formula["type"]).strip(),
                coefficients=[float(c) for c in str(formula["coefficients"]).split()],
                range_um=[lo, hi],
                wavelengths_um=wls,
                n=n,
                file=f"optiland/database/data-nk/glass/{maker}/{path.name}",
                references=str(raw.get("REFERENCES", ""))[:300],
                specs={k: raw.get("SPECS", {}).get(k) for k in ("nd", "Vd")},
            )
    js = dict(
        generator=dict(
            script="tools/fuzz37b_reference.py glasses",
            optiland=_version("optiland"),
            numpy=np.__version__,
            python=platform.python_version(),
        ),
        note="n = optiland MaterialFile(file).n(wavelength in µm), no temperature or pressure "
        "(the catalog formula relative to air)",
        glasses=rows,
        skipped=skipped,
    )
    (out / "glasses.json").write_text(json.dumps(js, indent=1) + "\n")
    # the sample kept in tests/data/fuzz37b: per catalog and formula type, the first two
    # names in sorted order and the glass of the highest index at 0.365 µm or the shortest
    # wavelength it has
    sample = {}
    for cat, gl in rows.items():
        for kind in sorted({g["formula_type"] for g in gl.values()}):
            names = sorted(k for k, g in gl.items() if g["formula_type"] == kind)
            top = max(names, key=lambda k: gl[k]["n"][0])
            for k in dict.fromkeys([*names[:2], top]):
                sample.setdefault(cat, {})[k] = gl[k]
    (out / "glasses_sample.json").write_text(
        json.dumps(dict(js, glasses=sample, skipped={}), indent=1) + "\n"
    )
    print(
        "glasses:",
        {k: len(v) for k, v in rows.items()},
        "skipped",
        len(skipped),
    )


# ------------------------------------------------------------------------------------------
KINDS = ("wide", "scale_small", "scale_large", "far_wavelengths", "high_order")
FAR_WLS = [587.5618, 365.0, 404.6565, 1013.98]


def _f36():
    """tools/fuzz36b_reference.py (the draws and the optiland and rayoptics traces)."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import fuzz36b_reference as f36

    return f36


def add_aspheres_high(f36, rng, sys_):
    """As fuzz36b's ``add_aspheres``, with seven or eight terms (A2..A14 or A2..A16) on every
    aspheric surface, each adding about 1 % of the beam radius of sag at 1.6x the beam."""
    rows = sys_["rows"]
    ip = sys_["wls"].index(sys_["prim"])
    n_after = [r["after"]["n"][ip] if r["after"] is not f36.AIR else 1.0 for r in rows]
    stop = next(i for i, r in enumerate(rows) if r["stop"])
    p = f36.paraxial(
        [r["c"] for r in rows], [r["gap"] for r in rows[:-1]], n_after, stop, sys_["dist"]
    )
    h = np.abs(np.array(p["heights"])) * sys_["epd"] / 2
    for i, r in enumerate(rows):
        if (
            r["stop"]
            and r["c"] == 0.0
            and r["after"] is f36.AIR
            and (i == 0 or rows[i - 1]["after"] is f36.AIR)
        ):
            continue
        if rng.random() < 0.3:
            continue
        rmax = max(1.6 * h[i], 0.05 * sys_["L"])
        r["k"] = float(rng.uniform(-3.0, 1.0)) if rng.random() < 0.6 else 0.0
        nco = int(rng.integers(7, 9))
        r["co"] = [
            float(rng.normal(0.0, 0.01 * rmax)) / 1.5 ** (j - 1) / rmax ** (2 * j)
            for j in range(1, nco + 1)
        ]
        if rng.random() < 0.4:
            r["co"][0] = 0.0


def rescale(f36, sys_, s):
    """Every length of a drawn system times ``s`` (curvatures / s, A_2j times s^(1 - 2j))."""
    for r in sys_["rows"]:
        r["c"] /= s
        r["co"] = [a * s ** (1 - 2 * j) for j, a in enumerate(r["co"], start=1)]
        if r["gap"] is not None:
            r["gap"] *= s
    sys_["img"]["c"] /= s
    for k in ("L", "epd", "gap"):
        sys_[k] *= s
    if sys_["dist"] != f36.INF:
        sys_["dist"] *= s


def fit_wide(f36, rng, case):
    """Fields 0, 0.6 θ, θ with θ from 60 to 85 degrees, lowered by 10 % steps (not below 45)
    until every stored ray passes."""
    theta = float(rng.uniform(60.0, 85.0))
    last = None
    while theta >= 45.0:
        try:
            f36.all_pass(case, theta)
            f36.all_pass(case, 0.6 * theta)
            return [0.0, round(0.6 * theta, 3), round(theta, 3)]
        except f36.Refused as e:
            last = e
            theta *= 0.9
    raise f36.Refused("wide_field_fails", str(last)[:150])


XPUPIL = [(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.6, -0.8)]


def x_field_rays(f36, case, fields):
    """Skew rays: each non-zero field turned into the x-z plane (direction (sin th, 0, cos th),
    or from the object point (-(d + z_EP) tan th, 0, -d)), at the XPUPIL points; traced by
    optiland and checked against rayoptics."""
    out_rays, worst = [], 0.0
    for f in fields:
        if f == 0.0:
            continue
        o, d = case.launch(f, [q[1] for q in XPUPIL], [q[0] for q in XPUPIL])
        o, d = o[:, [1, 0, 2]], d[:, [1, 0, 2]]  # the y-field's ray set turned by 90 degrees
        for w in case.wls:
            res, z, _, newton = case.trace(o, d, w)
            case.check_rays(res, z, newton, f"x field {f} {w}")
            if f36.trace_raw is not None:
                ref = case.ro_trace(o, d, w)
                worst = max(worst, float(np.abs(res[:, :3] - ref[:, :3]).max()))
            for k, (px, py) in enumerate(XPUPIL):
                out_rays.append(
                    dict(
                        field_angle_deg=f,
                        field_axis="x",
                        Hx=f / max(fields),
                        Hy=0.0,
                        Px=px,
                        Py=py,
                        wavelength_nm=w,
                        launch=dict(
                            point_on_EP_plane=o[k].tolist(), direction_cosines=d[k].tolist()
                        ),
                        image=dict(zip("x y z L M N".split(), map(float, res[k]), strict=True)),
                    )
                )
    return out_rays, worst


def build_lens(f36, idx, seed, kind):
    """One accepted draw of ``kind``; a wide-field draw is redrawn (sub-seeds 1 to 11) until
    one reaches 45 degrees."""
    tries = 12 if kind == "wide" else 1
    for attempt in range(tries):
        try:
            return _build_lens(f36, idx, seed, kind, attempt)
        except f36.Refused:
            if attempt == tries - 1:
                raise
    raise AssertionError("unreachable")


def _build_lens(f36, idx, seed, kind, attempt):
    t0 = time.time()
    rng = np.random.default_rng([seed, idx] + ([attempt] if attempt else []))
    f36.WAVELENGTH_SETS = (
        (FAR_WLS,) if kind == "far_wavelengths" else ([f36.F, f36.D, f36.C], [450.0, 550.0, 650.0])
    )
    f36.PRIMARY = (f36.D,) if kind == "far_wavelengths" else (f36.D, 550.0)
    sys_ = f36.draw_system(rng)
    if kind == "wide":
        sys_["dist"] = f36.INF
        sys_["epd"] *= 0.5
    if kind == "high_order":
        add_aspheres_high(f36, rng, sys_)
    else:
        f36.add_aspheres(rng, sys_)
    if kind.startswith("scale"):
        target = rng.uniform(0.5, 1.5) if kind == "scale_small" else rng.uniform(800.0, 2000.0)
        rescale(f36, sys_, float(target / sys_["L"]))
    defocus = float(rng.uniform(-0.01, 0.01) * sys_["L"])
    try:
        case = f36.Case(sys_, defocus)
        fields = fit_wide(f36, rng, case) if kind == "wide" else f36.fit_fields(rng, case)
        fields = sorted(set(fields))
        js = f36.make_json(case, fields, idx, seed, t0)
        extra, worst = x_field_rays(f36, case, fields)
    except f36.Refused:
        raise
    except Exception as e:  # noqa: BLE001
        raise f36.Refused("optiland_error", repr(e)[:200]) from e
    if f36.trace_raw is not None and not worst < 1e-10 * max(1.0, sys_["L"] / 100):
        raise f36.Refused("rayoptics_disagrees", f"x field {worst:.3g}")
    js["real_rays"] += extra
    js["cross_check"]["rayoptics_x_field_max_abs_intercept_diff_mm"] = worst
    js["name"] = f"fuzz37b_{kind}_{idx:03d}"
    js["features"] = [kind, "x_field_rays"] + js["features"]
    js["description"] = (
        f"random system {idx} of tools/fuzz37b_reference.py ({kind}), seed {seed}: "
        + ", ".join(js["features"])
    )
    js["source"] = "jaxlens tools/fuzz37b_reference.py (random prescription)"
    js["generator"].update(script="tools/fuzz37b_reference.py", kind=kind, attempt=attempt)
    js["conventions"] = dict(
        js["conventions"],
        x_field_rays=(
            "real rays with field_axis 'x' have the field turned into the x-z plane: direction"
            " (sin th, 0, cos th) (object at infinity), Px/Py as for the y fields"
        ),
    )
    js["build_seconds"] = round(time.time() - t0, 2)
    return js


def lenses(out, n, seed, kinds, start):
    f36 = _f36()
    summary = dict(seed=seed, kinds=kinds, drawn=0, accepted=[], refused={})
    for i in range(start, start + n):
        kind = kinds[i % len(kinds)]
        summary["drawn"] += 1
        try:
            js = build_lens(f36, i, seed, kind)
        except f36.Refused as e:
            summary["refused"].setdefault(f"{kind}:{e.reason}", []).append(i)
            print(f"{i:3d} {kind} refused {e}"[:200], flush=True)
            continue
        (out / f"{js['name']}.json").write_text(json.dumps(js, indent=1) + "\n")
        summary["accepted"].append(js["name"])
        print(
            f"{i:3d} ok {js['build_seconds']:5.1f}s fields {js['fields']['values']} "
            f"{' '.join(js['features'])}",
            flush=True,
        )
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(
        f"drawn {summary['drawn']}, accepted {len(summary['accepted'])}, refused "
        + ", ".join(f"{k} {len(v)}" for k, v in summary["refused"].items())
    )


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz37b_reference.py", description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("glasses", "lenses"))
    ap.add_argument("out", help="folder for the files (created)")
    ap.add_argument("--n", type=int, default=40, help="lenses to draw (default 40)")
    ap.add_argument("--seed", type=int, default=37, help="seed (default 37)")
    ap.add_argument("--start", type=int, default=0, help="first draw index (default 0)")
    ap.add_argument(
        "--kind",
        choices=(*KINDS, "all"),
        default="all",
        help="the class of lenses (default all: draw i gets KINDS[i % 5])",
    )
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error(f"--n must be >= 1, got {args.n}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        ap.error(f"OUT {out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    if args.what == "glasses":
        glasses(out)
    else:
        lenses(out, args.n, args.seed, KINDS if args.kind == "all" else (args.kind,), args.start)


if __name__ == "__main__":
    main(sys.argv[1:])
