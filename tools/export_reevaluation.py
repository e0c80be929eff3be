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


def optiland_numbers(path: str, wavelengths, primary, fields, lens=None) -> dict:
    """optiland's numbers for the same file, with the definitions of :func:`jaxlens_numbers`.

    With ``lens``, optiland's media are replaced by jaxlens's (:func:`set_media`): glass data
    set aside."""
    from optiland.fileio import load_zemax_file

    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
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
    d = {k: abs(j[k] - o[OPTILAND_NAME[k]]) / abs(o[OPTILAND_NAME[k]]) for k in SCALARS}
    d["chief_y_mm"] = max(abs(a - b) for a, b in zip(j["chief_y"], o["chief_y"], strict=True))
    d["distortion_pp"] = max(abs(a - b) for a, b in
                             zip(j["distortion"], o["distortion"], strict=True))
    rj, ro = np.asarray(j["rms_um"]), np.asarray(o["rms_um"])
    d["rms_um"] = float(np.max(np.abs(rj - ro)))
    d["rms_rel"] = float(np.max(np.abs(rj - ro) / ro))
    return d


def evaluate(path: str, tmp: str) -> dict:
    """One file: jaxlens's and optiland's numbers and their differences."""
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
            [abs(j[k] - jt[k]) / abs(jt[k]) for k in SCALARS]
            + [float(np.max(np.abs(np.asarray(j["rms_um"]) - jt["rms_um"])))])
    try:
        o = optiland_numbers(zmx, j["wavelengths"], j["primary"], j["fields"])
    except Exception as e:  # noqa: BLE001  (report whatever optiland raises)
        rec["optiland_error"] = f"{type(e).__name__}: {e}"
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("paths", nargs="+", help=".zmx / .json files or folders of them")
    p.add_argument("--summary", help="an experiment's summary.json (its lens.zmx among paths)")
    p.add_argument("--json", help="write every record to this file")
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
                r = evaluate(f, tmp)
            except Exception as e:  # noqa: BLE001
                r = {"file": f, "jaxlens_error": f"{type(e).__name__}: {e}"}
            recs.append(r)
            if "diff" in r:
                d = r["diff"]
                print(f"{f}: " + " ".join(f"{k}={v:.2e}" for k, v in d.items())
                      + (f" twin={r['twin_max_rel']:.1e}" if "twin_max_rel" in r else ""))
                print("  with jaxlens's indices: " + " ".join(
                    f"{k}={v:.2e}" for k, v in r["diff_jaxlens_media"].items()))
            else:
                print(f"{f}: {r.get('optiland_error') or r.get('jaxlens_error')}")
    out = {"computed_by": "optiland 0.6.3 via tools/export_reevaluation.py", "files": recs}
    if a.summary:
        out["summary"] = summary_check(a.summary, recs)
        print(json.dumps(out["summary"], indent=1))
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
