"""Re-evaluate designs jaxlens exported (``.zmx`` and JSON) in optiland, beside jaxlens's report.

For each file: jaxlens opens it (``jaxlens.load``) and reports it (``analysis.report.report_data``,
the numbers of ``python -m jaxlens report FILE --json``); optiland 0.6.3 opens the ``.zmx``
(``optiland.fileio.load_zemax_file``, with optiland's own glass data: a glass that it resolves
to another material shows up here). A JSON file is saved by jaxlens as ``.zmx`` in a temporary
folder first (the export path under test); where a ``.zmx`` of the same stem lies beside it,
jaxlens's numbers of both must agree too. Compared, with the same definitions on both sides:

* EFL (image space, n′/Φ; optiland ``paraxial.f2()``), F/# (``paraxial.FNO()``), BFL (from the
  last vertex to the paraxial focus: the last gap + optiland's ``paraxial.F2()``), total track
  (surface 1 to the image surface; optiland ``total_track``), mm;
* per field, the real chief-ray height on the image surface (primary wavelength, pupil centre;
  optiland ``trace_generic(0, Hy, 0, 0)``), mm, and the f-tanθ distortion made of it,
  100 (y − EFL tanθ)/(EFL tanθ) %;
* per field and wavelength, the RMS spot radius about the centroid, µm, on the 21 × 21 square
  grid over the unit entrance pupil kept inside the disc (317 rays; optiland traces the same
  normalised pupil points with ``trace_generic``), each code aiming its own rays (paraxial
  pupil aiming).

Surface types optiland 0.6.3's reader lacks (XPOLYNOM, jaxlens's Hybrid among them; XASPHERE,
XOSPHERE, TILTSURF, BICONICX) are read here from the file's text by Zemax's definitions
(``own_surfaces``, ``own_geometry``) and given to optiland as its geometries. optiland reads
every length as mm: a file in other units (UNIT IN) is reported, not compared. optiland's
paraxial quantities use a surface's base radius only (an XY polynomial's x², y² terms add
power that jaxlens's paraxial trace includes): compare real rays there.

``--resave`` saves each ``.zmx`` input again with ``jaxlens.save`` (``.zmx`` and JSON), checks
that both read back in jaxlens as the same lens (pytree and numbers), and gives optiland the
saved ``.zmx`` too (against jaxlens, and against optiland's numbers for the original).

``--summary RUN/summary.json`` also checks the numbers the classical experiment itself wrote for
its best design (efl, fnum, bfl, total_track, chief_height_full_field, distortion_percent)
against jaxlens's report and optiland on ``RUN/lens.zmx``.

Run it with an interpreter that has optiland 0.6.3 and this checkout's jaxlens:

    PYTHONPATH=$PWD /work/optiland_venv/bin/python tools/export_reevaluation.py \
        /tmp/a14_smoke/lens.zmx /tmp/a14_smoke/lens.json jaxlens/data/lenses \
        experiments/classical/designs --summary /tmp/a14_smoke/summary.json --json out.json

tests/test_input_probes_round14.py stores numbers this script printed.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import pathlib
import sys
import tempfile
import warnings

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.analysis.report import report_data  # noqa: E402

# jaxlens's 21 × 21 grid inside the unit disc (317 points; optiland's own "uniform" grid drops
# the 4 points on the rim at (0, ±1), (±1, 0) in floating point, so its points are not used).
PUPIL = np.asarray(jl.sampling.pupil_grid(21))
SCALARS = ("efl_image_space", "fnum", "bfl", "total_track")
OPTILAND_NAME = {"efl_image_space": "efl", "fnum": "fnum", "bfl": "bfl",
                 "total_track": "total_track"}


def jaxlens_numbers(lens) -> dict:
    """jaxlens's report numbers, in the units of this script (mm, %, µm)."""
    d = report_data(lens)
    out = {k: d[k] for k in SCALARS}
    out["fields"] = [f["angle"] for f in d["fields"]]
    out["chief_y"] = [f["chief_ray_height"] for f in d["fields"]]
    out["distortion"] = [f["distortion"] for f in d["fields"]]
    out["rms_um"] = [f["rms_spot"] for f in d["fields"]]
    out["wavelengths"] = d["wavelengths"]
    out["primary"] = d["primary_wavelength"]
    return out


def set_media(op, lens) -> None:
    """Give optiland's surfaces (after the object) jaxlens's media, dispersion included (each
    a material whose index at λ is jaxlens's ``material.index(λ)``), so that only the
    geometry, aperture, fields and tracing are optiland's."""
    from optiland.materials.base import BaseMaterial

    class Jaxlens(BaseMaterial):
        def __init__(self, m):
            super().__init__()
            self.m = m

        def _cache_state(self):
            return None

        def _calculate_n(self, wavelength, **kwargs):
            w = np.asarray(wavelength, float)
            own = table[id(self.m)]
            flat = [own.get(float(x)) or float(self.m.index(float(x))) for x in w.ravel()]
            return np.reshape(flat, w.shape)

        def _calculate_k(self, wavelength, **kwargs):
            return np.zeros_like(np.asarray(wavelength, float))

    table = {}  # the lens's own wavelengths, evaluated once
    for w in lens.wavelengths:
        for m in lens.materials:
            table.setdefault(id(m), {})[float(w)] = float(m.index(w))

    mats = list(lens.materials) + [lens.materials[-1]]
    for s, m in zip(op.surfaces.surfaces[1:], mats, strict=True):
        s.material_post = Jaxlens(m)


# Zemax surface types that optiland 0.6.3's reader lacks: read here from the file's own text,
# by Zemax's definitions (not jaxlens's reader), and given to optiland as its geometries.
# Each is written as a STANDARD surface (CURV, CONI) to a copy of the file that optiland opens;
# its geometry is then replaced. Units: the file must be in mm (UNIT MM).
OWN_TYPES = ("XPOLYNOM", "XASPHERE", "XOSPHERE", "TILTSURF", "BICONICX")


def xpoly_powers(j: int) -> tuple[int, int]:
    """Zemax's Extended Polynomial term j (1-based): (power of x, power of y); the terms run
    x, y, x², xy, y², x³, x²y, …, by degree, the power of x falling within a degree."""
    d = 1
    while j > d + 1:
        j -= d + 1
        d += 1
    return d - (j - 1), j - 1


def own_surfaces(text: str) -> tuple[str, dict]:
    """The file's text with OWN_TYPES surfaces written as STANDARD, and for each such
    surface number its type, CURV, CONI, PARM and XDAT values."""
    out, own, n = [], {}, None
    for ln in text.splitlines():
        t = ln.split()
        key = t[0] if t else ""
        if key == "UNIT" and t[1] != "MM":
            raise ValueError(f"the file's UNIT is {t[1]}; optiland 0.6.3 reads every length as "
                             f"mm, so its numbers for this file are not comparable")
        if key == "SURF":
            n = int(t[1])
        elif key == "TYPE" and t[1] in OWN_TYPES:
            own[n] = {"type": t[1], "c": 0.0, "k": 0.0, "parm": {}, "xdat": {}}
            out.append(ln.replace(t[1], "STANDARD"))
            continue
        elif n in own and key in ("CURV", "CONI"):
            own[n]["c" if key == "CURV" else "k"] = float(t[1])
        elif n in own and key in ("PARM", "XDAT"):
            own[n][key.lower()][int(t[1])] = float(t[2])
            continue
        out.append(ln)
    return "\n".join(out) + "\n", own


def own_geometry(old, d: dict):
    """The optiland geometry of one OWN_TYPES surface (``old``: the standard one in its place,
    whose coordinate system it keeps)."""
    from optiland.geometries import BiconicGeometry, EvenAsphere, OddAsphere, PolynomialGeometry

    cs, c, k, x = old.cs, d["c"], d["k"], d["xdat"]
    radius = math.inf if c == 0 else 1.0 / c
    kind = d["type"]
    if kind == "BICONICX":
        rx = d["parm"].get(1, 0.0)
        return BiconicGeometry(cs, rx if rx != 0 else math.inf, radius, d["parm"].get(2, 0.0), k)
    if kind == "TILTSURF":
        coeffs = [[0.0, d["parm"].get(2, 0.0)], [d["parm"].get(1, 0.0), 0.0]]
        return PolynomialGeometry(cs, math.inf, 0.0, coefficients=coeffs)
    n, r = int(x.get(1, 0)), x.get(2, 1.0)
    a = [x.get(j + 2, 0.0) for j in range(1, n + 1)]
    if kind == "XASPHERE":  # Σ α_i ρ^(2i), ρ = r/R
        return EvenAsphere(cs, radius, k, coefficients=[v / r ** (2 * i)
                                                        for i, v in enumerate(a, start=1)])
    if kind == "XOSPHERE":  # Σ β_i ρ^i
        return OddAsphere(cs, radius, k, coefficients=[v / r ** i
                                                       for i, v in enumerate(a, start=1)])
    deg = max((sum(xpoly_powers(j)) for j in range(1, n + 1)), default=0)
    coeffs = np.zeros((deg + 1, deg + 1))
    for j, v in enumerate(a, start=1):  # Σ A_j (x/R)^p (y/R)^q
        p, q = xpoly_powers(j)
        coeffs[p, q] += v / r ** (p + q)
    return PolynomialGeometry(cs, radius, k, coefficients=coeffs)


def optiland_numbers(path: str, wavelengths, primary, fields, lens=None) -> dict:
    """optiland's numbers for the same file, with the definitions of :func:`jaxlens_numbers`.

    With ``lens``, optiland's media are replaced by jaxlens's (:func:`set_media`): glass data
    set aside."""
    from optiland.fileio import load_zemax_file

    if any(isinstance(f, list | tuple) for f in fields):
        raise ValueError("fields with an x component (angle_deg_xy) are not compared by this "
                         "script (it traces y fields, Hx = 0)")
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        with open(path, "rb") as fh:
            raw = fh.read()
        utf16 = raw[:2] in (b"\xff\xfe", b"\xfe\xff")
        text, own = own_surfaces(raw.decode("utf-16" if utf16 else "latin-1"))
        if own:  # a copy beside nothing: optiland reads no AGF file
            with tempfile.TemporaryDirectory() as tmp:
                copy = os.path.join(tmp, "own.zmx")
                with open(copy, "w", encoding="utf-8") as fh:
                    fh.write(text)
                op = load_zemax_file(copy)
            for n, d in own.items():
                s = op.surfaces.surfaces[n]
                s.geometry = own_geometry(s.geometry, d)
        else:
            op = load_zemax_file(path)
        index_d = [float(np.asarray(s.material_post.n(primary)).ravel()[0])
                   for s in op.surfaces.surfaces[1:-1]]
        if lens is not None:
            set_media(op, lens)
        for s in op.surfaces.surfaces:  # optiland's Newton on aspheres stops at 1e-10 or so
            g = s.geometry
            if hasattr(g, "tol") and hasattr(g, "max_iter"):
                g.tol, g.max_iter = 1e-13, 200
        par = op.paraxial
        efl = float(par.f2())
        last_gap = float(op.surfaces.positions[-1, 0] - op.surfaces.positions[-2, 0])
        out = {"efl": efl, "fnum": float(par.FNO()), "bfl": last_gap + float(par.F2()),
               "total_track": float(op.total_track)}
        fmax = max(abs(float(f)) for f in fields) or 1.0
        chief, dist = [], []
        for f in fields:
            hy = float(f) / fmax
            r = op.trace_generic(0.0, hy, 0.0, 0.0, primary)
            y = float(np.asarray(r.y).ravel()[0])
            chief.append(y)
            ref = efl * math.tan(math.radians(float(f)))
            dist.append(0.0 if ref == 0 else 100.0 * (y - ref) / ref)
        rms = [[0.0] * len(wavelengths) for _ in fields]
        lost = 0  # rays of the grid optiland loses (all fields and wavelengths)
        for k, w in enumerate(wavelengths):
            for i, f in enumerate(fields):
                hy = float(f) / fmax
                r = op.trace_generic(0.0, hy, PUPIL[:, 0], PUPIL[:, 1], w)
                x, yy = np.asarray(r.x).ravel(), np.asarray(r.y).ravel()
                ok = (np.asarray(r.i).ravel() > 0) & np.isfinite(x) & np.isfinite(yy)
                lost += int(len(PUPIL) - ok.sum())
                cx, cy = x[ok].mean(), yy[ok].mean()
                rms[i][k] = 1e3 * math.sqrt(np.mean((x[ok] - cx) ** 2 + (yy[ok] - cy) ** 2))
        out.update(chief_y=chief, distortion=dist, rms_um=rms, index_d=index_d,
                   rays_lost=lost)
    return out


def compare(j: dict, o: dict) -> dict:
    """Largest differences: relative for the scalars, absolute for heights (mm), distortion
    (percentage points) and RMS (µm, and relative)."""
    d = {k: None if j[k] is None else abs(j[k] - o[OPTILAND_NAME[k]]) / abs(o[OPTILAND_NAME[k]])
         for k in SCALARS}  # None: jaxlens reports no value (a lens without power)
    d["chief_y_mm"] = max(abs(a - b) for a, b in zip(j["chief_y"], o["chief_y"], strict=True))
    d["distortion_pp"] = max(abs(a - b) for a, b in
                             zip(j["distortion"], o["distortion"], strict=True))
    rj, ro = np.asarray(j["rms_um"]), np.asarray(o["rms_um"])
    d["rms_um"] = float(np.max(np.abs(rj - ro)))
    d["rms_rel"] = float(np.max(np.abs(rj - ro) / ro))
    return d


def compare_optiland(a: dict, b: dict) -> dict:
    """Largest differences of optiland's numbers for two files (:func:`compare`'s units)."""
    d = {k: abs(a[k] - b[k]) / abs(a[k]) if a[k] else abs(a[k] - b[k])
         for k in OPTILAND_NAME.values()}
    d["chief_y_mm"] = max(abs(x - y) for x, y in zip(a["chief_y"], b["chief_y"], strict=True))
    ra, rb = np.asarray(a["rms_um"]), np.asarray(b["rms_um"])
    d["rms_um"] = float(np.max(np.abs(ra - rb)))
    d["index_d"] = max((abs(x - y) for x, y in zip(a["index_d"], b["index_d"], strict=True)),
                       default=0.0)
    return d


def resaved(path: str, lens, j: dict, o: dict | None, tmp: str) -> dict:
    """``lens`` (opened from ``path``) saved by ``jaxlens.save`` as ``.zmx`` and as JSON in a
    folder of its own: each must read back in jaxlens as the same lens (pytree structure and
    every number equal), and optiland must give the saved ``.zmx`` the numbers it gives the
    original ``.zmx`` (``o``; with optiland's own glass data on both)."""
    import jax.tree_util as tu

    folder = tempfile.mkdtemp(dir=tmp)
    out: dict = {}
    for ext in (".zmx", ".json"):
        saved = os.path.join(folder, pathlib.Path(path).stem + "_saved" + ext)
        jl.save(lens, saved)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            back = jl.load(saved)
        same = tu.tree_structure(back) == tu.tree_structure(lens) and all(
            np.array_equal(np.asarray(x, np.float64), np.asarray(y, np.float64), equal_nan=True)
            for x, y in zip(tu.tree_leaves(back), tu.tree_leaves(lens), strict=True))
        out[f"reloads_identical{ext}"] = bool(same)
        if ext == ".zmx":
            try:
                o3 = optiland_numbers(saved, j["wavelengths"], j["primary"], j["fields"])
                out["diff_saved_vs_jaxlens"] = compare(j, o3)
                if o is not None:
                    out["diff_saved_vs_original"] = compare_optiland(o, o3)
            except Exception as e:  # noqa: BLE001
                out["optiland_saved_error"] = f"{type(e).__name__}: {e}"
    return out


def evaluate(path: str, tmp: str, resave: bool = False) -> dict:
    """One file: jaxlens's and optiland's numbers and their differences (with ``resave``,
    and a ``.zmx`` file: :func:`resaved` too)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(path)
    rec = {"file": path}
    zmx = path
    if path.endswith(".json"):
        zmx = os.path.join(tmp, pathlib.Path(path).stem + ".zmx")
        jl.save(lens, zmx)
        twin = path[:-5] + ".zmx"
        if os.path.exists(twin):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                jt = jaxlens_numbers(jl.load(twin))
            rec["twin_zmx"] = twin
            rec["jaxlens_twin"] = jt
    j = jaxlens_numbers(lens)
    rec["jaxlens"] = j
    if "jaxlens_twin" in rec:
        jt = rec["jaxlens_twin"]
        rec["twin_max_rel"] = max(
            [abs(j[k] - jt[k]) / abs(jt[k]) for k in SCALARS if jt[k] is not None]
            + [float(np.max(np.abs(np.asarray(j["rms_um"]) - jt["rms_um"])))])
    try:
        o = optiland_numbers(zmx, j["wavelengths"], j["primary"], j["fields"])
    except Exception as e:  # noqa: BLE001  (report whatever optiland raises)
        rec["optiland_error"] = f"{type(e).__name__}: {e}"
        o = None
    if resave and path.lower().endswith(".zmx"):
        rec["resaved"] = resaved(path, lens, j, o, tmp)
    if o is None:
        return rec
    rec["optiland"] = o
    rec["diff"] = compare(j, o)
    o2 = optiland_numbers(zmx, j["wavelengths"], j["primary"], j["fields"], lens=lens)
    rec["optiland_jaxlens_media"] = o2
    rec["diff_jaxlens_media"] = compare(j, o2)
    rec["jaxlens_index_d"] = [float(n) for n in lens.indices(j["primary"])[1:]]
    return rec


def summary_check(summary: str, recs: list[dict]) -> dict:
    """The experiment's own numbers for its best design against jaxlens's report of RUN/lens.zmx
    and optiland's (the full field is the largest field of the written file)."""
    s = json.loads(pathlib.Path(summary).read_text())["best"]
    zmx = str(pathlib.Path(summary).parent / "lens.zmx")
    rec = next(r for r in recs if r["file"] == zmx)
    j, o = rec["jaxlens"], rec.get("optiland", {})
    pairs = {"efl": ("efl_image_space", "efl"), "fnum": ("fnum", "fnum"), "bfl": ("bfl", "bfl"),
             "total_track": ("total_track", "total_track")}
    out = {}
    for k, (jk, ok) in pairs.items():
        out[k] = {"summary": s[k], "jaxlens_report": j[jk], "optiland": o.get(ok)}
    i = int(np.argmax(np.abs(j["fields"])))
    out["chief_height_full_field"] = {"summary": s["chief_height_full_field"],
                                      "jaxlens_report": j["chief_y"][i],
                                      "optiland": o.get("chief_y", [None] * (i + 1))[i]}
    out["distortion_percent"] = {"summary": s["distortion_percent"],
                                 "jaxlens_report": j["distortion"][i],
                                 "optiland": o.get("distortion", [None] * (i + 1))[i]}
    return out


def _e(v) -> str:
    return "None" if v is None else f"{v:.2e}" if isinstance(v, float) else str(v)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("paths", nargs="+", help=".zmx / .json files or folders of them")
    p.add_argument("--summary", help="an experiment's summary.json (its lens.zmx among paths)")
    p.add_argument("--json", help="write every record to this file")
    p.add_argument("--resave", action="store_true",
                   help="save each .zmx file again with jaxlens.save (.zmx and JSON), check "
                        "that both reload as the same lens and that optiland gives the saved "
                        ".zmx the original's numbers")
    a = p.parse_args(argv)
    files = []
    for q in a.paths:
        if os.path.isdir(q):
            files += sorted(str(f) for f in pathlib.Path(q).iterdir()
                            if f.suffix in (".zmx", ".json"))
        else:
            files.append(q)
    recs = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            try:
                r = evaluate(f, tmp, a.resave)
            except Exception as e:  # noqa: BLE001
                r = {"file": f, "jaxlens_error": f"{type(e).__name__}: {e}"}
            recs.append(r)
            if "diff" in r:
                d = r["diff"]
                print(f"{f}: " + " ".join(f"{k}={_e(v)}" for k, v in d.items())
                      + (f" twin={r['twin_max_rel']:.1e}" if "twin_max_rel" in r else ""))
                print("  with jaxlens's indices: " + " ".join(
                    f"{k}={_e(v)}" for k, v in r["diff_jaxlens_media"].items()))
            else:
                print(f"{f}: {r.get('optiland_error') or r.get('jaxlens_error')}")
            if "resaved" in r:
                print("  saved again: " + " ".join(
                    f"{k}={_e(v)}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in r["resaved"].items() if not isinstance(v, dict))
                    + "".join(f" {w}: " + " ".join(f"{k}={_e(v)}" for k, v in d.items())
                              for w in ("diff_saved_vs_jaxlens", "diff_saved_vs_original")
                              for d in [r["resaved"].get(w)] if d))
    out = {"computed_by": "optiland 0.6.3 via tools/export_reevaluation.py", "files": recs}
    if a.summary:
        out["summary"] = summary_check(a.summary, recs)
        print(json.dumps(out["summary"], indent=1))
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
