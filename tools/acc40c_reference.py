"""Wavefront-side reference numbers from optiland 0.6.3 for tests/test_accuracy_round40c.py:
an object-space telecentric lens, virtual objects, and a plastic even-asphere lens whose image
surface is curved and lies in glass.

Run with the optiland environment's interpreter, from the repository root (jaxlens is not
imported):

    /work/optenv/bin/python tools/acc40c_reference.py

writes tests/data/acc40c_optiland.json. The lenses:

- ``tele_doublet_obna``, ``tele_triplet_floa``: tests/data/zmx38a's object-space telecentric
  files, built through optiland's own telecentric API exactly as
  tools/telecentric38a_reference.py builds them (its ``build``; the NA and object heights
  are that tool's, stored in tests/data/zmx38a_optiland.json);
- ``virtual_singlet_angles``, ``virtual_stop_behind``: tests/data/zmx_corpus7's
  virtual-object files (negative object thickness), read by optiland's .zmx reader as
  tools/corpus7_reference.py reads them;
- ``plastic_curved_immersed_image``: tests/refcases_extra's case (E48R even aspheres with
  conics and A2..A12, an N-SF11 element in contact with an image surface of R = 12 mm), built
  from the case file with optiland's catalogue glasses the file names. The image surface's
  medium is given as N-SF11 too: the image lies in glass, and the reference sphere with it
  (the case file's air after the image surface is an artefact of its ray data; jaxlens ends
  its trace in image space, where that refraction does not happen).

For each lens, field and wavelength (every wavelength of the lens), with optiland's
"chief_ray" strategy (the reference sphere centred on the chief ray's image-surface
intercept, through the paraxial exit pupil at the primary wavelength; OPD positive where the
wavefront is ahead of the sphere; the chief ray traced at the wavelength analysed):

- ``opd``: OPD in waves at the pupil points ``POINTS`` (the tangential fan (0, t) and the
  sagittal fan (t, 0), t in ``FAN``, then a few skew points);
- ``grid``: the OPD over optiland's "uniform" grid of ``GRID`` × ``GRID`` points over
  [-1, 1]² cut to the unit disc (Px² + Py² <= 1): its RMS and P-V with the mean removed,
  with the least-squares plane a + b·Px + c·Py removed, the number of points, 15 Noll
  Zernike terms (``optiland.zernike.ZernikeFit``), at the primary wavelength;
- ``exit_pupil``: the paraxial exit pupil's global z and diameter (optiland's XPL, XPD; for
  the A2 lens an independent y-nu trace with paraxial curvature c + 2·A2, see below);
- ``mtf``: optiland's geometric MTF (``GeometricMTF``, its spot diagram's line spread, a
  uniform grid of ``MTF_GRID`` rays per side) at ``FREQS`` cycles/mm, tangential and
  sagittal, at the primary wavelength, for the telecentric doublet and the virtual singlet.

Two places where optiland's numbers are corrected here, each recorded beside the raw one:

- optiland's ``chief_ray`` strategy takes the image-space index at the primary wavelength
  for every wavelength (``ReferenceStrategy.n_image``). The path from the reference sphere
  to the image surface runs in image space at the wavelength analysed, so where image space
  is not air the OPD of another wavelength is computed with that wavelength's index
  (``opd`` is with n(λ); ``opd_optiland_primary_index`` is optiland's own);
- optiland's paraxial trace leaves the A2 (r²) term out, which moves the paraxial exit pupil
  of the A2 lens (global z = -7.428 mm instead of -7.252 mm; this tool's y-nu trace with
  A2 set to 0 gives optiland's value to 1e-15 mm). Its strategy's exit pupil point is
  replaced by the independent y-nu trace's (``exit_pupil.optiland_z``, ``optiland_xpl``
  and ``optiland_xpd`` keep optiland's).
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import warnings
from importlib.metadata import version

import numpy as np
from optiland import optic as optic_mod
from optiland.distribution import BaseDistribution, create_distribution
from optiland.fileio import load_zemax_file
from optiland.materials import Material
from optiland.wavefront.strategy import create_strategy
from optiland.zernike import ZernikeFit

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import telecentric38a_reference as tele  # noqa: E402

OUT = ROOT / "tests" / "data" / "acc40c_optiland.json"
FAN = tuple(round(-1.0 + 0.2 * i, 10) for i in range(11))
SKEW = ((0.6, 0.6), (-0.3, 0.7), (0.5, -0.8), (0.7071, 0.7071))
POINTS = tuple((0.0, t) for t in FAN) + tuple((t, 0.0) for t in FAN) + SKEW
GRID = 33
ZERNIKE_TERMS = 15
FREQS = (5.0, 10.0, 20.0, 40.0)
MTF_GRID = 201
NEWTON_TOL = 1e-15


class Points(BaseDistribution):
    """optiland distribution holding exactly ``POINTS``."""

    def generate_points(self, num_points):
        self.x = np.array([p[0] for p in POINTS])
        self.y = np.array([p[1] for p in POINTS])


def tight(op):
    for s in op.surface_group.surfaces:
        if hasattr(s.geometry, "tol"):
            s.geometry.tol = NEWTON_TOL


# --------------------------------------------------------------------------------------
# The lenses
# --------------------------------------------------------------------------------------
def telecentric(name):
    ref = json.loads((ROOT / "tests" / "data" / "zmx38a_optiland.json").read_text())
    s = tele.SYSTEMS[name]
    r = ref["systems"][name]
    heights = [tuple(h) for h in r["object_heights"]]
    op = tele.build(s, r["object_na"], heights)
    rmax = max(math.hypot(*h) for h in heights)
    fields = [[hx / rmax, hy / rmax] for hx, hy in heights]
    return op, fields, [list(h) for h in heights], "object heights (x, y), mm"


def virtual(name):
    path = ROOT / "tests" / "data" / "zmx_corpus7" / f"{name}.zmx"
    op = load_zemax_file(str(path))
    text = path.read_text()
    fy = [float(v) for v in next(ln for ln in text.splitlines()
                                 if ln.startswith("YFLN")).split()[1:]]
    top = max(fy, key=abs)
    hy = (0.0, 0.5, 1.0)
    if "FTYP 0" in text:  # angles: optiland's Hy scales the angle
        jl_fields = [h * top for h in hy]
        kind = "angle θy, degrees"
    else:  # object heights: the chief ray through the paraxial entrance pupil's centre
        # (optiland's ray generation) toward the object point after it (+z): its angle
        # atan(h / (z_object - z_EP)) in object space
        z_obj = float(np.ravel(op.surface_group.positions)[0])
        z_ep = float(op.paraxial.EPL())
        jl_fields = [math.degrees(math.atan(h * top / (z_obj - z_ep))) for h in hy]
        kind = "chief-ray angle θy, degrees (object heights by optiland's EP)"
    return op, [[0.0, h] for h in hy], jl_fields, kind


def immersed():
    case = json.loads((ROOT / "tests" / "refcases_extra" /
                       "plastic_curved_immersed_image.json").read_text())
    src = case["material_index_source"]

    def mat(name):
        if name == "air":
            return "air"
        key = next(k for k in src if k.partition(":")[0] == name)
        base, _, cat = key.partition(":")
        return Material(base, cat) if cat else Material(base)

    rows = case["surfaces"]
    op = optic_mod.Optic()
    op.add_surface(index=0, radius=np.inf, thickness=np.inf)
    for s in rows[1:-1]:
        kw = dict(index=s["index"], radius=s["radius"], thickness=s["thickness"],
                  conic=s["conic"], is_stop=s["is_stop"], material=mat(s["material"]))
        if s["even_asphere_coeffs"]:
            kw.update(surface_type="even_asphere", coefficients=list(s["even_asphere_coeffs"]))
        op.add_surface(**kw)
    img = rows[-1]
    op.add_surface(index=img["index"], radius=img["radius"], conic=img["conic"],
                   material=mat(rows[-2]["material"]))  # image space is glass
    op.set_aperture(aperture_type="EPD", value=case["aperture"]["EPD"])
    op.set_field_type(field_type="angle")
    fields = case["fields"]["values"]
    for f in fields:
        op.add_field(y=f)
    for w in case["wavelengths_nm"]:
        op.add_wavelength(value=w / 1000.0, is_primary=(w == case["primary_wavelength_nm"]))
    tight(op)
    top = max(fields)
    return op, [[0.0, f / top] for f in fields], list(fields), "angle θy, degrees", rows


def ynu_exit_pupil(rows, wl_nm):
    """(global z, diameter) of the paraxial exit pupil, from a y-nu trace with the paraxial
    curvature c + 2·A2 (object at infinity, stop ``is_stop``): the stop imaged backward by
    the surfaces after it, and the marginal ray's height there."""
    key = next(k for k in rows[1]["n"] if abs(float(k) - wl_nm) < 1e-9)
    surf = rows[1:-1]
    c = [s["curvature"] + 2 * (s["even_asphere_coeffs"][0] if s["even_asphere_coeffs"] else 0)
         for s in surf]
    n = [1.0] + [s["n"][key] for s in surf]
    z = np.concatenate([[0.0], np.cumsum([s["thickness"] for s in surf])])
    stop = next(i for i, s in enumerate(surf) if s["is_stop"])

    def trace(y, nu, start):
        for i in range(start, len(surf)):
            if i > start:
                y = y + (z[i] - z[i - 1]) * nu / n[i]
            nu = nu - y * c[i] * (n[i + 1] - n[i])
        return y, nu, z[len(surf) - 1]

    # chief ray: from the stop's centre, any slope; the exit pupil is where it crosses 0
    y, nu, zl = trace(0.0, 1e-3 * n[stop], stop)
    z_xp = zl - y * n[-1] / nu
    return z_xp, trace, zl, n


def exit_pupil_of(op, rows=None):
    wl = op.primary_wavelength
    z_img = float(np.ravel(op.surface_group.positions)[-1])
    out = {"optiland_xpl": float(op.paraxial.XPL()), "optiland_xpd": float(op.paraxial.XPD()),
           "optiland_z": z_img + float(op.paraxial.XPL())}
    if rows is None:
        out["z"] = out["optiland_z"]
        out["diameter"] = out["optiland_xpd"]
        out["source"] = "optiland paraxial XPL, XPD"
        return out, None
    z_xp, trace, zl, n = ynu_exit_pupil(rows, wl * 1000.0)
    h = float(op.paraxial.EPD()) / 2
    y, nu, _ = trace(h, 0.0, 0)
    out["z"] = float(z_xp)
    out["diameter"] = float(2 * abs(y + (z_xp - zl) * nu / n[-1]))
    out["source"] = "y-nu trace with paraxial curvature c + 2*A2 (this tool)"
    return out, (0.0, 0.0, float(z_xp))


# --------------------------------------------------------------------------------------
# Analyses
# --------------------------------------------------------------------------------------
def wave_data(op, field, wl, dist, xp_point, n_image):
    st = create_strategy(strategy_name="chief_ray", optic=op, distribution=dist,
                         reference_type="sphere")
    if xp_point is not None:
        st.exit_pupil_point = xp_point
    if n_image is not None:
        st.n_image = n_image
    return st.compute_wavefront_data(tuple(field), wl)


def grid_stats(op, field, wl, xp_point):
    dist = create_distribution("uniform")
    dist.generate_points(GRID)
    d = wave_data(op, field, wl, dist, xp_point, None)
    keep = np.asarray(d.intensity) > 0
    w = np.asarray(d.opd)[keep]
    x = np.asarray(dist.x)[keep]
    y = np.asarray(dist.y)[keep]
    a = np.stack([np.ones_like(x), x, y], -1)
    plane = np.linalg.lstsq(a, w, rcond=None)[0]
    wt = w - a @ plane
    noll = np.asarray(ZernikeFit(x, y, w, "noll", ZERNIKE_TERMS).coeffs)
    return {"count": int(keep.sum()), "rms": float(np.std(w)), "pv": float(np.ptp(w)),
            "rms_tilt_removed": float(np.std(wt)), "pv_tilt_removed": float(np.ptp(wt)),
            "tilt": plane.tolist(), "noll": noll.tolist()}


def mtf_of(op, field):
    from optiland.mtf import GeometricMTF

    m = GeometricMTF(op, fields=[tuple(field)], wavelength="primary", num_rays=MTF_GRID,
                     distribution="uniform", num_points=512, max_freq=max(FREQS) * 1.25,
                     scale=False)
    f = np.asarray(m.freq)
    t = np.interp(FREQS, f, np.asarray(m.mtf[0][0]))
    s = np.interp(FREQS, f, np.asarray(m.mtf[0][1]))
    return {"tangential": t.tolist(), "sagittal": s.tolist()}


def analyse(op, fields, jl_fields, kind, xp, xp_point, with_mtf):
    wls = [float(w.value) for w in op.wavelengths.wavelengths]
    prim = float(op.primary_wavelength)
    n_img = {w: float(np.ravel(op.surface_group.n(w))[-1]) for w in wls}
    res = {"field_kind": kind, "optiland_fields": fields, "jaxlens_fields": jl_fields,
           "wavelengths_um": wls, "primary_um": prim, "image_space_index": n_img,
           "exit_pupil": xp, "fields": []}
    for f in fields:
        one = {"opd": {}, "opd_optiland_primary_index": {}}
        for w in wls:
            pts = Points()
            pts.generate_points(0)
            d = wave_data(op, f, w, pts, xp_point, n_img[w])
            one["opd"][repr(w)] = np.asarray(d.opd).tolist()
            if n_img[w] != n_img[prim]:
                d0 = wave_data(op, f, w, pts, xp_point, None)
                one["opd_optiland_primary_index"][repr(w)] = np.asarray(d0.opd).tolist()
        one["grid"] = grid_stats(op, f, prim, xp_point)
        if with_mtf:
            one["mtf"] = mtf_of(op, f)
        res["fields"].append(one)
    return res


def main() -> None:
    warnings.filterwarnings("ignore")
    out = {"source": "optiland 0.6.3 (tools/acc40c_reference.py)",
           "optiland": version("optiland"),
           "settings": {
               "strategy": "chief_ray: sphere centred on the chief ray's image-surface "
                           "intercept, through the paraxial exit pupil (primary wavelength); "
                           "OPD = (chief path - ray path)/λ to that sphere, waves",
               "points": [list(p) for p in POINTS], "fan": list(FAN), "grid": GRID,
               "grid_note": "uniform grid linspace(-1, 1, GRID)² cut to Px²+Py² <= 1, equal "
                            "weights; rms/pv with the mean removed, *_tilt_removed with the "
                            "least-squares plane in (Px, Py) removed; Noll Zernike fit",
               "zernike_terms": ZERNIKE_TERMS, "mtf_freqs_cyc_per_mm": list(FREQS),
               "mtf_grid": MTF_GRID,
               "mtf_note": "optiland GeometricMTF (spot line spread, uniform grid, no "
                           "diffraction scaling), primary wavelength",
               "image_index_note": "opd uses the image-space index at the wavelength "
                                   "analysed; opd_optiland_primary_index is optiland's own "
                                   "(primary index), stored where they differ"},
           "lenses": {}}
    for name in ("tele_doublet_obna", "tele_triplet_floa"):
        op, fields, jl, kind = telecentric(name)
        xp, pt = exit_pupil_of(op)
        out["lenses"][name] = analyse(op, fields, jl, kind, xp, pt,
                                      with_mtf=name == "tele_doublet_obna")
        print(name, "done", flush=True)
    for name in ("virtual_singlet_angles", "virtual_stop_behind"):
        op, fields, jl, kind = virtual(name)
        xp, pt = exit_pupil_of(op)
        out["lenses"][name] = analyse(op, fields, jl, kind, xp, pt,
                                      with_mtf=name == "virtual_singlet_angles")
        print(name, "done", flush=True)
    op, fields, jl, kind, rows = immersed()
    xp, pt = exit_pupil_of(op, rows)
    out["lenses"]["plastic_curved_immersed_image"] = analyse(op, fields, jl, kind, xp, pt,
                                                             with_mtf=False)
    print("immersed done", flush=True)
    OUT.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
