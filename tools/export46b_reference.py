"""Round 46b: re-evaluate exported classical designs with optiland 0.6.3 and ray-optics 0.9.8,
from the exported ``.zmx`` alone, for tests/test_export_round46b.py.

    /work/optenv/bin/python tools/export46b_reference.py [FILE.zmx ...]

(default: tests/data/export46b/smoke/lens.zmx, a ``--smoke`` run's export, and the two
committed designs README names, experiments/classical/designs/seed_13.zmx and
designs_paper_method/seed_9.zmx); writes tests/data/export46b/export46b_reference.json. No
jaxlens and no JAX here: every definition is read from the file (Zemax keywords; the NOTE
lines of ``jaxlens.experiments.classical_export.evaluation_notes`` for the media's indices at
WAVM 1..3, the sensor grid and the focal length of its field angles).

Per file:

* ``open``: the warnings each reader emits on the file as written (optiland
  ``load_zemax_file``; ray-optics ``open_model``, and the glasses it could not find: ray-
  optics knows neither ZEON's E48R nor OKP4; optiland takes E48R from refractiveindex.info,
  nd 1.53052, where Zemax's ZEON catalog, the file's GLAS line and its side PLASTICS.AGF say
  1.53117). Every number below is traced with the NOTE lines' indices in both codes.
* paraxial, at PWAV: EFL (image space), F/# (EFL/EPD), BFL (last vertex to paraxial focus),
  total track (surface 1 to the image surface), the entrance pupil's position from surface 1
  and the exit pupil's from the image surface, mm; each code's own paraxial trace.
* ``rayoptics``: ``rayoptics_reevaluation.evaluate`` (round 37d's definitions: the NOTE's
  sensor grid of (θx, θy) fields, the 21 × 21 pupil grid inside the unit circle through the
  paraxial entrance pupil, RMS radius of all WAVM's surviving rays pooled about their
  centroid, µm; the real chief ray's f-tanθ distortion at the NOTE's θy).
* ``optiland``, per field θy of ``fields_deg`` (0 and fractions of the half-diagonal FoV the
  NOTE names), paraxial aiming (``set_aiming("paraxial")``, the file's RAIM 0), the lens's
  clear apertures (``CLAP``) clipping, each asphere's Newton search to a 1e-13 mm residual
  (optiland's reader sets 1e-6 mm, which moved the chief ray by up to 2e-7 mm):
  - the real chief ray (pupil centre, PWAV) on the image surface: y, mm; its f-tanθ
    distortion 100 (y − EFL tanθ)/(EFL tanθ) %; its angle to the axis after the last surface
    (the chief-ray angle, CRA), deg, atan(M/N);
  - the RMS spot: the 21 × 21 pupil grid, every WAVM's surviving rays pooled about their
    common centroid, µm (the classical run's RMS); the smallest fraction of a wavelength's
    rays that survive;
  - the geometric MTF without diffraction and without a pixel grid, polychromatic with equal
    weights (each wavelength's |OTF| term normalised by its own surviving rays, about the
    pooled centroid, the complex terms averaged, then the modulus: jaxlens's
    ``psf.mtf(model=GeometricPSF(), diffraction=False)`` definition), tangential along y and
    sagittal along x, at ``MTF_FREQS`` cycles/mm, on the pupil grid of jaxlens's default
    geometric PSF: the cell centres of a 64 × 64 grid over [-1, 1]² inside the unit circle
    (overfill 1, today's ``DEFAULT_OVERFILL``; the beam is the unit pupil, round 44a);
  - the relative illumination at PWAV by ``ri43c_reference``'s forward-traced irradiance
    (the pupil measure of the passing rays over the Jacobian of the beam's centroid in the
    field, normalised on the axis; 43c: the system aperture, the unit pupil, bounds the beam).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import pathlib
import sys
import warnings

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import rayoptics_reevaluation as rre  # noqa: E402

OUT = ROOT / "tests" / "data" / "export46b"
DEFAULT_FILES = [
    OUT / "smoke" / "lens.zmx",
    ROOT / "experiments" / "classical" / "designs" / "seed_13.zmx",
    ROOT / "experiments" / "classical" / "designs_paper_method" / "seed_9.zmx",
]
FIELD_FRACTIONS = (0.0, 0.5, 0.7, 0.85, 1.0)  # of the NOTE's half-diagonal θy
MTF_FREQS = (10.0, 25.0, 50.0, 100.0)  # cycles/mm
MTF_CELLS = 64
MTF_OVERFILL = 1.0
NEWTON_TOL = 1e-13  # mm of sag residual; optiland's .zmx reader gives its aspheres 1e-6


def rel(path: pathlib.Path) -> str:
    try:
        return str(path.resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def note_material(values, wavelengths):
    """An optiland material exact at the file's wavelengths (µm), NaN elsewhere."""
    from optiland.materials.base import BaseMaterial

    class NoteMaterial(BaseMaterial):
        def __init__(self):
            super().__init__()
            self.table = list(zip(wavelengths, values, strict=True))

        def _cache_state(self):
            return None

        def _calculate_n(self, wavelength, **kwargs):
            w = np.asarray(wavelength, float)
            out = np.full(w.shape, np.nan)
            for wl, n in self.table:
                out = np.where(np.abs(w - wl) < 1e-9, n, out)
            return out if out.ndim else float(out)

        def _calculate_k(self, wavelength, **kwargs):
            return np.zeros(np.shape(wavelength)) if np.ndim(wavelength) else 0.0

    return NoteMaterial()


def open_optiland(path: pathlib.Path):
    from optiland.fileio import load_zemax_file

    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(
        io.StringIO()
    ) as out:
        warnings.simplefilter("always")
        op = load_zemax_file(str(path))
    said = [f"{w.category.__name__}: {w.message}" for w in caught]
    said += [ln for ln in out.getvalue().splitlines() if ln.strip()]
    return op, said


def open_rayoptics(path: pathlib.Path):
    import tempfile

    from rayoptics.environment import open_model

    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings(
        record=True
    ) as caught, contextlib.redirect_stdout(io.StringIO()) as out:
        warnings.simplefilter("always")
        for f in [path, *path.parent.glob("*.AGF")]:
            (pathlib.Path(tmp) / f.name).write_bytes(f.read_bytes())  # temporary
        opm, info = open_model(str(pathlib.Path(tmp) / path.name), info=True)
    said = [f"{w.category.__name__}: {w.message}" for w in caught]
    said += [ln for ln in out.getvalue().splitlines() if ln.strip()]
    return opm, info, said


def optiland_paraxial(op) -> dict:
    p = op.paraxial
    wl = float(op.primary_wavelength)
    efl = float(np.ravel(p.f2())[0])
    epd = float(np.ravel(p.EPD())[0])
    z = [float(np.ravel(s.geometry.cs.z)[0]) for s in op.surface_group.surfaces]
    bfl = z[-1] - z[-2] + float(np.ravel(p.F2())[0])
    return {
        "efl": efl,
        "fnum": float(np.ravel(p.FNO())[0]),
        "epd": epd,
        "bfl": bfl,
        "total_track": float(z[-1] - z[1]),
        "entrance_pupil_z": float(np.ravel(p.EPL())[0]),  # from surface 1
        "exit_pupil_from_image": float(np.ravel(p.XPL())[0]),
        "wavelength_um": wl,
    }


class Cells:
    """The cell centres of an n x n grid over [-1, 1]² inside the unit circle, times the
    overfill (1): jaxlens's default geometric-PSF pupil."""

    def __init__(self, n=MTF_CELLS, overfill=MTF_OVERFILL):
        g = (np.arange(n) + 0.5) / n * 2.0 - 1.0
        px, py = np.meshgrid(g, g, indexing="xy")
        r2 = px * px + py * py
        keep = (r2 <= 1.0) & (r2 * overfill**2 <= 1.0)
        self.x, self.y = px[keep] * overfill, py[keep] * overfill


def trace_points(op, hy, px, py, wl):
    op.trace_generic(0.0, hy, np.asarray(px, float), np.asarray(py, float), wl)
    sg = op.surface_group
    ok = np.asarray(sg.intensity[-1]) > 0
    x, y = np.asarray(sg.x)[-1], np.asarray(sg.y)[-1]
    ok = ok & np.isfinite(x) & np.isfinite(y)
    return np.stack([x, y], -1), ok, np.asarray(sg.M)[-1], np.asarray(sg.N)[-1]


def optiland_field(op, hy, theta, efl, wls, prim) -> dict:
    zero = np.zeros(1)
    xy, ok, m, n = trace_points(op, hy, zero, zero, prim)
    h = float(xy[0, 1])
    ideal = efl * math.tan(math.radians(theta))
    pts = rre.pupil_points()
    pool, frac = [], []
    for wl in wls:
        p, good, _, _ = trace_points(op, hy, pts[:, 0], pts[:, 1], wl)
        pool.append(p[good])
        frac.append(float(good.mean()))
    allp = np.concatenate(pool)
    c = allp.mean(0)
    rms = 1e3 * math.sqrt(float(np.mean(np.sum((allp - c) ** 2, -1))))
    cells = Cells()
    pos, keep = [], []
    for wl in wls:
        p, good, _, _ = trace_points(op, hy, cells.x, cells.y, wl)
        pos.append(np.nan_to_num(p))
        keep.append(good)
    pos, keep = np.stack(pos), np.stack(keep)  # [W, M, 2], [W, M]
    w = keep.astype(float)
    ref = np.sum(w[..., None] * pos, (0, 1)) / np.sum(w)
    wn = w / np.sum(w, -1, keepdims=True)
    freqs = np.asarray(MTF_FREQS)
    mtf = {}
    for key, axis in (("tangential", 1), ("sagittal", 0)):
        proj = pos[..., axis] - ref[axis]  # [W, M]
        o = np.sum(wn[:, None, :] * np.exp(-2j * np.pi * freqs[None, :, None] * proj[:, None, :]),
                   -1)
        mtf[key] = np.abs(o.mean(0)).tolist()
    return {
        "theta_deg": theta,
        "chief_y": h,
        "distortion_percent": 100.0 * (h - ideal) / ideal if ideal else 0.0,
        "cra_deg": math.degrees(math.atan2(float(m[0]), float(n[0]))),
        "rms_um": rms,
        "min_valid_fraction": min(frac),
        "mtf_rays": [int(k.sum()) for k in keep],
        "mtf": mtf,
    }


def evaluate(path: pathlib.Path) -> dict:
    text = path.read_text(errors="replace")
    notes = rre.read_notes(text)
    out = {"file": rel(path)}
    # ray-optics: open as written (warnings), then round 37d's evaluation with NOTE media
    _, info, ro_said = open_rayoptics(path)
    ro = rre.evaluate(path, grid=True)
    opm, _, _ = open_rayoptics(path)
    rre.set_media(opm, notes)
    fod = opm["analysis_results"]["parax_data"].fod
    out["rayoptics_open"] = {"messages": ro_said, "info": {k: v for k, v in info[0].items()}}
    out["rayoptics"] = ro | {
        "entrance_pupil_z": float(fod.enp_dist),
        "exit_pupil_from_image": float(fod.exp_dist),
        "img_dist": float(fod.img_dist),
    }
    # optiland: open as written (warnings), then the NOTE media
    op, said = open_optiland(path)
    out["optiland_open"] = {"messages": said}
    out["optiland_own_media_paraxial"] = optiland_paraxial(op)
    wls = [float(w) for w in op.wavelengths.get_wavelengths()]
    prim = float(op.primary_wavelength)
    for k, vals in notes["indices"].items():
        op.surface_group.surfaces[k].material_post = note_material(vals, wls)
    op.ray_tracer.set_aiming("paraxial")
    for s in op.surface_group.surfaces:  # the reader's 1e-6 mm Newton tolerance moved the
        if hasattr(s.geometry, "tol"):  # chief ray by up to 2e-7 mm
            s.geometry.tol = NEWTON_TOL
    par = optiland_paraxial(op)
    theta_max = notes["theta_full"]
    # ri43c's irradiance differentiates in the normalised field: a field beyond the file's
    # largest keeps the full field's central differences inside optiland's [-1, 1]
    op.add_field(y=1.02 * theta_max)
    fmax = float(op.fields.max_field)
    fields = []
    for frac in FIELD_FRACTIONS:
        theta = frac * theta_max
        hy = theta / fmax  # optiland's angle field: direction (0, tan(Hy·F), 1)
        fields.append(optiland_field(op, hy, theta, par["efl"], wls, prim))
    import ri43c_reference as ri

    ri.WL = prim
    e = [ri.irradiance(op, f["theta_deg"] / fmax, False)[0] for f in fields]
    for f, v in zip(fields, e, strict=True):
        f["relative_illumination"] = v / e[0]
    out["optiland"] = {"paraxial": par, "wavelengths_um": wls, "fields": fields,
                       "max_field_deg": fmax}
    return out


def main(argv=None) -> int:
    from importlib.metadata import version

    warnings.filterwarnings("ignore")
    files = [pathlib.Path(a) for a in (argv or sys.argv[1:])] or DEFAULT_FILES
    data = {
        "source": "tools/export46b_reference.py",
        "optiland": version("optiland"),
        "rayoptics": version("rayoptics"),
        "field_fractions": FIELD_FRACTIONS,
        "mtf_freqs": MTF_FREQS,
        "mtf_cells": MTF_CELLS,
        "mtf_overfill": MTF_OVERFILL,
        "files": [],
    }
    for path in files:
        r = evaluate(path)
        print(json.dumps({"file": r["file"], "optiland": r["optiland"]["paraxial"],
                          "rayoptics_efl": r["rayoptics"]["efl"]}), flush=True)
        data["files"].append(r)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "export46b_reference.json").write_text(json.dumps(data, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
