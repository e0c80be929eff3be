"""Re-evaluate the committed classical designs with ray-optics 0.9.8, from the files alone.

    /work/optenv/bin/python tools/rayoptics_reevaluation.py experiments/classical/designs \
        experiments/classical/designs_paper_method --json tests/data/export_round37d_rayoptics.json

A second tracer beside round 36d's optiland (``tools/export_reevaluation.py``). It needs no
jaxlens and no JAX: every definition it uses is read from the ``.zmx`` file, from its NOTE
lines (``jaxlens.experiments.classical_export.evaluation_notes``) where Zemax has no keyword:

* the media: ray-optics 0.9.8 resolves neither ZEON's E48R nor OKP4 (the file's side
  ``PLASTICS.AGF``) and puts a constant n = 1.5 in their place, ignoring the GLAS line's nd
  and Vd; each medium here gets the indices the NOTE lines give at WAVM 1..3 (an
  ``InterpolatedMedium`` through exactly those points, traced only at them);
* the fields: the NOTE's n × n grid over the sensor (width, height and focal length as the
  NOTE writes them), tan θx = x/f, tan θy = y/f, direction (tan θx, tan θy, 1) normalised;
  the grid's 8-fold symmetry (a rotationally symmetric lens, a symmetric pupil grid) gives
  every field's RMS from the fields with 0 <= x <= y;
* the rays: the 21 × 21 square grid inside the unit circle (317), through the paraxial
  entrance pupil (ray-optics's own paraxial ``enp_dist`` and ENPD/2), at WAVM 1..3; the
  intersections and refractions are ray-optics's ``raytrace.trace``; a ray is lost where
  ray-optics fails it (miss, TIR) or where it passes a surface farther from the axis than
  the surface's clear aperture (CLAP, equal to DIAM in these files);
* RMS: the radius about the centroid of all wavelengths' surviving rays pooled, µm, on the
  image surface (the last DISZ); per field the smallest fraction of a wavelength's rays
  that survive (the NOTE's vignetting rule, >= 99 % at every wavelength);
* EFL, F/# (EFL/ENPD) and BFL: ray-optics's paraxial model at PWAV; distortion
  100 (h − EFL tan θ)/(EFL tan θ) % with h the real chief ray's y at the NOTE's θy; the FoV
  2 × the largest YFLN.

Writes one JSON record per design; ``tests/test_export_round37d.py`` compares it with
table1.json's per-seed claims and with jaxlens's re-read of the same files.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import re
import sys
import tempfile
import warnings

import numpy as np

NOTE_INDEX = re.compile(r"NOTE 0 jaxlens: the medium after SURF (\d+) \((.*)\) has n = (.*) at")
NOTE_GRID = re.compile(r"a (\d+) x (\d+) grid over the ([\d.eE+-]+) x ([\d.eE+-]+) mm sensor")
NOTE_F = re.compile(r"tan = sensor position / ([\d.eE+-]+) mm")
NOTE_THETA = re.compile(r"at thetay = ([\d.eE+-]+) deg")


def pupil_points() -> np.ndarray:
    """The 21 × 21 square grid over [-1, 1]² kept inside the unit circle (317 points)."""
    i = np.arange(-10, 11)
    x, y = np.meshgrid(i, i, indexing="xy")
    keep = x**2 + y**2 <= 100
    return np.stack([x[keep], y[keep]], -1) / 10.0


def read_notes(text: str) -> dict:
    idx = {
        int(m.group(1)): [float(v) for v in m.group(3).split()] for m in NOTE_INDEX.finditer(text)
    }
    g, f, t = NOTE_GRID.search(text), NOTE_F.search(text), NOTE_THETA.search(text)
    return {
        "indices": idx,
        "grid": int(g.group(1)),
        "sensor_w": float(g.group(3)),
        "sensor_h": float(g.group(4)),
        "focal": float(f.group(1)),
        "theta_full": float(t.group(1)),
    }


def open_file(path: pathlib.Path):
    from rayoptics.environment import open_model

    # From a copy: ray-optics may leave a "<name>_tmpl.smx" beside the file it opens.
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for f in [path, *path.parent.glob("*.AGF")]:
            (pathlib.Path(tmp) / f.name).write_bytes(f.read_bytes())  # temporary
        opm, info = open_model(str(pathlib.Path(tmp) / path.name), info=True)
    return opm, info


def mend_intersections() -> None:
    """ray-optics 0.9.8 intersects an asphere by Newton's method (Spencer and Murty) from the
    ray's start, up to 1000 steps; on these lenses' steep aspheres a step lands where the base
    conic has no sag (k > -1) and the ray is failed (``TraceMissedSurfaceError``) though it
    meets the surface, and a long search is slow. Here the Newton search runs 60 steps; where
    it fails, the ray's first crossing is found by a scan of the sag residual along the ray
    (401 points over ± 4 mm about the vertex plane, the same sag formula in numpy) and refined
    by ray-optics's own residual ``f`` with Brent's method. The root is ray-optics's surface."""
    from rayoptics.elem import profiles
    from rayoptics.raytr.traceerror import TraceMissedSurfaceError
    from scipy.optimize import brentq

    def sag_np(prof, r2):
        with np.errstate(invalid="ignore"):
            z = prof.cv * r2 / (1.0 + np.sqrt(1.0 - (prof.cc + 1.0) * prof.cv**2 * r2))
        rp = r2.copy()
        for a in prof.coefs[: prof.max_nonzero_coef]:
            z = z + a * rp
            rp = rp * r2
        return z

    def intersect(self, p0, d, eps, z_dir):
        try:
            s1 = -self.f(p0) / np.dot(d, self.df(p0))
            for _ in range(60):
                s2 = s1 - self.f(p0 + s1 * d) / np.dot(d, self.df(p0 + s1 * d))
                if abs(s2 - s1) <= eps:
                    return s2, p0 + s2 * d
                s1 = s2
        except (TraceMissedSurfaceError, ValueError, ZeroDivisionError):
            pass
        s0 = -p0[2] / d[2]
        s = s0 + np.linspace(-4.0, 4.0, 401) / abs(d[2])
        pts = p0[None, :] + s[:, None] * d[None, :]
        f = pts[:, 2] - sag_np(self, pts[:, 0] ** 2 + pts[:, 1] ** 2)
        good = np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (f[:-1] * f[1:] <= 0)
        if not good.any():
            raise TraceMissedSurfaceError
        k = int(np.argmax(good))
        root = brentq(lambda t: self.f(p0 + t * d), s[k], s[k + 1], xtol=1e-15, rtol=4e-16)
        return root, p0 + root * d

    profiles.EvenPolynomial.intersect = intersect


def note_medium(label: str, table: dict):
    """A ray-optics medium with the given index at each of the file's wavelengths (nm) and
    nowhere else (a wavelength off the table is an error, never an interpolation)."""
    from opticalglass.opticalmedium import ConstantIndex

    class NoteIndex(ConstantIndex):
        def rindex(self, wv_nm):
            return table[float(wv_nm)]

    return NoteIndex(table[sorted(table)[len(table) // 2]], label)


def set_media(opm, notes: dict) -> list[str]:
    """Give every glass gap the NOTE's indices; returns what ray-optics had put there."""
    sm = opm["seq_model"]
    wl = list(opm["optical_spec"].spectral_region.wavelengths)
    own = []
    for k, n in notes["indices"].items():
        g = sm.gaps[k]
        own.append(f"SURF {k}: {g.medium.name()} n(d) {g.medium.rindex(wl[1]):.6f}")
        g.medium = note_medium(f"note{k}", dict(zip(wl, n, strict=True)))
    opm.update_model()
    return own


def trace_bundle(sm, dirs, pts, wvl, clap):
    """Trace rays starting at points ``pts`` on the plane 1 mm before surface 1 (the object
    gap set to 1 mm) along ``dirs``; returns (x, y) on the image surface and validity."""
    from rayoptics.raytr import raytrace as rt
    from rayoptics.raytr.traceerror import TraceError

    out = np.full((len(pts), 2), np.nan)
    ok = np.zeros(len(pts), bool)
    for k, (p, d) in enumerate(zip(pts, dirs, strict=True)):
        try:
            ray, _, _ = rt.trace(sm, np.array([p[0], p[1], 0.0]), np.array(d), wvl)
        except TraceError:
            continue
        hits = [seg[0] for seg in ray]
        if any(math.hypot(h[0], h[1]) > r for h, r in zip(hits[1:-1], clap[1:-1], strict=True)):
            continue
        out[k] = hits[-1][:2]
        ok[k] = True
    return out, ok


def spot(sm, wl, launch, tx, ty, pupil, clap) -> tuple[float, float]:
    """Pooled RMS radius (µm) of one field and the smallest surviving fraction of a
    wavelength's rays."""
    pts_all, fr = [], []
    for w in wl:
        dirs, pts = launch(tx, ty, pupil)
        xy, ok = trace_bundle(sm, dirs, pts, w, clap)
        pts_all.append(xy[ok])
        fr.append(ok.mean())
    pall = np.concatenate(pts_all)
    if not len(pall):
        return math.nan, 0.0
    c = pall.mean(0)
    return 1e3 * math.sqrt(np.mean(np.sum((pall - c) ** 2, -1))), float(min(fr))


def evaluate(path: pathlib.Path, grid: bool = False, symmetric_only: bool = True) -> dict:
    text = path.read_text(errors="replace")
    notes = read_notes(text)
    mend_intersections()
    opm, info = open_file(path)
    own = set_media(opm, notes)
    sm, osp = opm["seq_model"], opm["optical_spec"]
    fod = opm["analysis_results"]["parax_data"].fod
    wl = list(osp.spectral_region.wavelengths)
    ref = osp.spectral_region.reference_wvl
    epd = osp.pupil.value
    efl, fno, bfl = float(fod.efl), float(fod.efl) / epd, float(fod.bfl)
    enp_z = float(fod.enp_dist)  # entrance pupil from surface 1, mm
    fov = 2 * max(abs(f.y) for f in osp.field_of_view.fields)
    clap = [float(ifc.max_aperture) if ifc.clear_apertures else math.inf for ifc in sm.ifcs]
    clap[0] = clap[-1] = math.inf
    sm.gaps[0].thi = 1.0  # launch 1 mm before surface 1 (1e10 mm would cost 1e-6 mm)
    opm.update_model()  # the surfaces' frames (the paraxial numbers above are kept)

    def launch(tx, ty, pupil):
        d = np.array([tx, ty, 1.0]) / math.sqrt(tx * tx + ty * ty + 1.0)
        ep = pupil * (epd / 2)
        # the point of the pupil plane (z = enp_z) back along d to the plane z = -1
        s = (enp_z + 1.0) / d[2]
        pts = ep - s * d[:2]
        return np.broadcast_to(d, (len(pupil), 3)), pts

    pupil = pupil_points()
    n = notes["grid"]
    u = np.linspace(-1, 1, n)
    half_w, half_h = notes["sensor_w"] / 2, notes["sensor_h"] / 2
    if not math.isclose(half_w, half_h):
        symmetric_only = False
    yfln = [f.y for f in osp.field_of_view.fields]
    per = [spot(sm, wl, launch, 0.0, math.tan(math.radians(t)), pupil, clap) for t in yfln]
    rms, frac = np.full((n, n), np.nan), np.full((n, n), np.nan)
    for iy in range(n if grid else 0):
        for ix in range(n):
            a, b = abs(u[ix]), abs(u[iy])
            if symmetric_only and not (u[ix] >= 0 and u[iy] >= 0 and a <= b):
                continue
            tx, ty = u[ix] * half_w / notes["focal"], u[iy] * half_h / notes["focal"]
            rms[iy, ix], frac[iy, ix] = spot(sm, wl, launch, tx, ty, pupil, clap)
    if grid and symmetric_only:  # fill by the grid's symmetry: |x| and |y| swap, signs flip
        m = n - 1
        for iy in range(n):
            for ix in range(n):
                jx, jy = (ix if u[ix] >= 0 else m - ix), (iy if u[iy] >= 0 else m - iy)
                if abs(u[jx]) > abs(u[jy]):
                    jx, jy = jy, jx
                rms[iy, ix], frac[iy, ix] = rms[jy, jx], frac[jy, jx]
    th = math.radians(notes["theta_full"])
    dirs, pts = launch(0.0, math.tan(th), np.zeros((1, 2)))
    xy, ok = trace_bundle(sm, dirs, pts, wl[ref], [math.inf] * len(clap))
    h = float(xy[0, 1])
    ideal = efl * math.tan(th)
    return {
        "design": f"{path.parent.name}/{path.name}",
        "rayoptics_media_before_notes": own,
        "glass_not_found": int(info[0].get("glass not found", 0)),
        "efl": efl,
        "fnum": fno,
        "bfl": bfl,
        "fov": fov,
        "chief_height_full_field": h,
        "distortion_percent": 100.0 * (h - ideal) / ideal,
        "yfln_deg": yfln,
        "yfln_rms_um": [r for r, _ in per],
        "yfln_min_valid_fraction": [f for _, f in per],
    } | (
        {
            "grid_rms_um": rms.reshape(-1).tolist(),
            "rms_mean_um": float(np.mean(rms)),
            "rms_max_um": float(np.max(rms)),
            "min_valid_fraction": float(np.min(frac)),
            "rays_ok": bool(np.all(frac >= 0.99)),
        }
        if grid
        else {}
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=pathlib.Path)
    p.add_argument("--json", type=pathlib.Path)
    p.add_argument("--seeds", default=None, help="comma list of seeds (default all)")
    p.add_argument(
        "--grid-seeds",
        default="",
        help="seeds evaluated on the whole n x n grid too (about 2 minutes each)",
    )
    a = p.parse_args(argv)
    seeds = None if a.seeds is None else {int(s) for s in a.seeds.split(",")}
    grid_seeds = {int(s) for s in a.grid_seeds.split(",") if s}
    out = []
    for folder in a.folders:
        for path in sorted(folder.glob("seed_*.zmx"), key=lambda q: int(q.stem.split("_")[1])):
            if seeds is not None and int(path.stem.split("_")[1]) not in seeds:
                continue
            seed = int(path.stem.split("_")[1])
            r = evaluate(path, grid=seed in grid_seeds)
            print(
                f"{r['design']}: EFL {r['efl']:.9f} F/{r['fnum']:.6f} BFL {r['bfl']:.6f} "
                f"dist {r['distortion_percent']:.6f} % RMS {r['yfln_rms_um']} "
                f"grid mean {r.get('rms_mean_um')}",
                flush=True,
            )
            out.append(r)
    if a.json:
        text = json.dumps({"tool": "rayoptics 0.9.8", "designs": out}, indent=1)
        with tempfile.NamedTemporaryFile("w", dir=a.json.parent, delete=False) as f:
            f.write(text)  # temporary
        os.chmod(f.name, 0o644)
        os.replace(f.name, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
