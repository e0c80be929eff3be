"""Reference aberration numbers from optiland 0.6.3, for tests/test_conventions_vs_optiland.py.

optiland (not a jaxlens dependency; it follows Zemax OpticStudio's conventions in most places)
analyses four lenses, each built here from the reference-case files in ``tests/refcases/``
(the same as ``/work/shared/refcases/``) as their README describes: the same radii,
thicknesses, conics and even-asphere terms, with each glass taken from optiland's catalogs
under the name the file's ``material_index_source`` gives, so the indices are the files'
tables at every wavelength. optiland's Newton tolerance for aspheres is tightened to
round-off. The lenses:

- ``cooke_triplet``: the Cooke triplet, object at infinity, fields 0, 14, 20 deg;
- ``double_gauss``: the double Gauss, object at infinity, fields 0, 10, 14 deg;
- ``double_gauss_finite``: the double Gauss with its object 300 mm before surface 1 (angle
  fields: the chief ray's angle in object space, as jaxlens's ``depth``);
- ``cooke_asphere``: the Cooke triplet with even aspheres on surfaces 1 and 6 (a conic and
  r⁴, r⁶ terms; no r² term, which optiland's paraxial trace leaves out).

For each lens, at the primary (d) wavelength unless said otherwise:

- ``seidel``: optiland's per-surface third-order transverse terms TSC, CC, TAC, TPC, DC,
  TAchC, TchC (mm), its ``seidels()`` sums and the image-space marginal ray's n′u′;
- ``opd``: ``optiland.wavefront.OPD`` (strategy "chief_ray": the reference sphere on the
  chief ray's image point through the paraxial exit pupil) at the pupil points ``POINTS``
  for each field, in waves; for the Cooke triplet also at the F line, full field;
- ``fans``: ``optiland.analysis.RayFan`` (tangential e_y, sagittal e_x, mm, every
  wavelength against the primary chief ray) at the full and half field, ``FAN_POINTS``
  points over −1 … 1;
- ``field_curvature``: ``optiland.analysis.FieldCurvature`` (mm along z from the image
  surface, every wavelength), ``CURVE_FIELDS`` fields linear in angle from 0 to the largest;
- ``distortion``: ``optiland.analysis.Distortion`` (%, signed; its default "paraxial"
  method: the ideal height is s·tanθ ("f-tan") or s·θ ("f-theta"), the scale s from a real
  chief ray at 1e-10 of the field, that is the paraxial chief ray on the image surface, as
  Zemax's "reference ray height"), at Hy = 1e-10, 0.25, 0.5, 0.75, 1;
- ``zernike``: ``optiland.wavefront.ZernikeOPD`` at the full field over its hexapolar grid
  of ``RINGS`` rings (``hexapolar``: the points, 1 + 3R(R+1) of them), 36 and 37 Fringe,
  37 Noll and 36 OSA/ANSI terms, in waves (optiland's ``"standard"`` is the OSA/ANSI set,
  whereas Zemax's "Zernike Standard" is Noll's; optiland's Fringe Z37 continues the
  formula, R_6^6 cos 6θ, whereas Zemax's Fringe Z37 is R_12^0, so only 36 terms compare);
- ``encircled``: the geometric encircled energy at the full field: the fraction of the
  rays of optiland's hexapolar grid of ``EE_RINGS`` rings that land within r of their
  centroid (equal weights, Zemax's geometric definition), at ``EE_RADII`` × the largest
  distance.

Run with optiland's interpreter from the repository root; it writes the JSON the test reads:

    /work/optiland_venv/bin/python tools/conventions_reference.py \
        --out tests/data/conventions_optiland.json
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import re
import warnings
from importlib.metadata import version

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.0, 0.5), (1.0, 0.0), (0.5, 0.0),
          (0.6, 0.6), (-0.3, 0.7), (0.0, -0.7))
FAN_POINTS = 11
CURVE_FIELDS = 5
DISTORTION_HY = (1e-10, 0.25, 0.5, 0.75, 1.0)
RINGS = 6
EE_RINGS = 10
EE_RADII = (0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 0.95)
FINITE_DISTANCE = 300.0
ASPHERES = {  # surface index -> (conic, [A2, A4, A6])
    1: (-0.3, [0.0, -2.0e-6, 1.5e-9]),
    6: (0.6, [0.0, 4.0e-6, -2.0e-8]),
}


def _material(spec: str):
    from optiland.materials import Material

    if spec.startswith("n = 1"):
        return "air"
    m = re.search(r"Material\('([^']+)'(?:, '([^']+)')?\)", spec)
    if m is None:
        raise ValueError(f"cannot read the material source {spec!r}")
    return Material(m.group(1), m.group(2)) if m.group(2) else Material(m.group(1))


def build(case: dict, *, object_distance: float | None = None):
    """An optiland ``Optic`` of a reference-case file's lens (its fields and wavelengths)."""
    from optiland import optic

    src = case["material_index_source"]
    op = optic.Optic()
    surfs = case["surfaces"]
    op.surfaces.add(index=0, radius=np.inf,
                    thickness=np.inf if object_distance is None else object_distance)
    for s in surfs[1:-1]:
        i = s["index"]
        c = float(s["curvature"])
        kw = dict(index=i, radius=math.inf if c == 0 else 1.0 / c,
                  thickness=float(s["thickness"]), conic=float(s.get("conic") or 0.0),
                  is_stop=bool(s.get("is_stop")), material=_material(src[s["material"]]))
        coeffs = s.get("even_asphere_coeffs") or []
        if coeffs:
            kw.update(surface_type="even_asphere", coefficients=[float(a) for a in coeffs])
        op.surfaces.add(**kw)
    op.surfaces.add(index=len(surfs) - 1)
    op.set_aperture(aperture_type="EPD", value=float(case["aperture"]["EPD"]))
    op.fields.set_type(field_type="angle")
    for th in case["fields"]["values"]:
        op.fields.add(y=float(th))
    for wl in case["wavelengths_nm"]:
        op.wavelengths.add(value=wl / 1000.0,
                           is_primary=wl == case["primary_wavelength_nm"])
    for surf in op.surfaces:
        if hasattr(surf.geometry, "tol"):
            surf.geometry.tol = 1e-15
    return op


def with_aspheres(case: dict) -> dict:
    """The case with ``ASPHERES`` put on its surfaces (a copy)."""
    out = copy.deepcopy(case)
    for s in out["surfaces"]:
        if s["index"] in ASPHERES:
            k, a = ASPHERES[s["index"]]
            s["type"], s["conic"], s["even_asphere_coeffs"] = "even_asphere", k, list(a)
    return out


def _opd_at(op, hy, wl, pts):
    from optiland.distribution import BaseDistribution
    from optiland.wavefront import OPD

    class Points(BaseDistribution):
        def generate_points(self, num_points):
            self.x = np.array([p[0] for p in pts])
            self.y = np.array([p[1] for p in pts])

    d = Points()
    d.generate_points(0)
    w = OPD(op, (0.0, hy), wl, distribution=d)
    return np.asarray(w.get_data(w.fields[0], w.wavelengths[0]).opd, float).tolist()


def analyse(op, case: dict) -> dict:
    from optiland.analysis import Distortion, FieldCurvature, RayFan
    from optiland.wavefront import ZernikeOPD

    fields = [float(v) for v in case["fields"]["values"]]
    top = max(fields)
    wls = [w / 1000.0 for w in case["wavelengths_nm"]]
    prim = case["primary_wavelength_nm"] / 1000.0
    ab = op.aberrations
    seidel = {t: np.asarray(getattr(ab, t)(), float).tolist()
              for t in ("TSC", "CC", "TAC", "TPC", "DC", "TAchC", "TchC")}
    seidel["seidels"] = np.asarray(ab.seidels(), float).tolist()
    _, ua = op.paraxial.marginal_ray()
    seidel["image_u"] = float(np.asarray(ua).reshape(-1)[-1])
    out = {"fields_deg": fields, "wavelengths_um": wls, "primary_um": prim, "seidel": seidel}
    out["opd"] = {str(th): _opd_at(op, th / top, prim, POINTS) for th in fields}
    if case["name"].startswith("cooke_triplet"):
        out["opd_F_line_full_field"] = _opd_at(op, 1.0, min(wls), POINTS)
    fans = {}
    for hy in (0.5, 1.0):
        rf = RayFan(op, fields=[(0.0, hy)], wavelengths=wls, num_points=FAN_POINTS)
        d = rf.data[f"{(0.0, hy)}"]
        fans[str(hy * top)] = {str(w): {"tangential": np.asarray(d[f"{w}"]["y"]).tolist(),
                                        "sagittal": np.asarray(d[f"{w}"]["x"]).tolist()}
                               for w in wls}
    out["fans"] = fans
    fc = FieldCurvature(op, wavelengths=wls, num_points=CURVE_FIELDS)
    out["field_curvature"] = {
        "fields_deg": np.linspace(0.0, top, CURVE_FIELDS).tolist(),
        "tangential": [np.asarray(v[0]).tolist() for v in fc.data],
        "sagittal": [np.asarray(v[1]).tolist() for v in fc.data]}
    dist = {}
    for kind in ("f-tan", "f-theta"):
        d = Distortion(op, wavelengths=[prim], num_points=len(DISTORTION_HY),
                       distortion_type=kind)
        dist[kind] = np.asarray(d.data[0]).tolist()
    out["distortion"] = {"hy": list(DISTORTION_HY), **dist}
    zern = {}
    for key, kind, terms in (("fringe36", "fringe", 36), ("fringe37", "fringe", 37),
                             ("noll", "noll", 37), ("standard", "standard", 36)):
        z = ZernikeOPD(op, (0.0, 1.0), prim, num_rings=RINGS, zernike_type=kind,
                       num_terms=terms)
        zern[key] = np.asarray(z.coeffs, float).tolist()
    out["zernike"] = zern
    # Geometric encircled energy (Zemax's: the fraction of equal-energy rays within r of
    # their centroid) of optiland's traced hexapolar rays at the full field.
    op.trace(0.0, 1.0, prim, EE_RINGS, "hexapolar")
    x = np.asarray(op.surfaces.x[-1, :], float)
    y = np.asarray(op.surfaces.y[-1, :], float)
    keep = np.asarray(op.surfaces.intensity[-1, :], float) > 0
    r = np.hypot(x[keep] - x[keep].mean(), y[keep] - y[keep].mean())
    radii = np.asarray(EE_RADII) * r.max()
    out["encircled"] = {"rings": EE_RINGS, "radii_mm": radii.tolist(),
                        "energy": [float(np.mean(r <= q)) for q in radii],
                        "rays": int(keep.sum())}
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    load = lambda name: json.load(open(os.path.join(ROOT, "tests", "refcases", name)))  # noqa: E731
    cooke, dg = load("cooke_triplet.json"), load("double_gauss.json")
    lenses = {
        "cooke_triplet": (cooke, None),
        "double_gauss": (dg, None),
        "double_gauss_finite": (dg, FINITE_DISTANCE),
        "cooke_asphere": (with_aspheres(cooke), None),
    }
    from optiland.distribution import HexagonalDistribution

    hexa = HexagonalDistribution()
    hexa.generate_points(RINGS)
    cases = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, (case, dist) in lenses.items():
            case = dict(case, name=name)
            base = "cooke_triplet" if "cooke" in name else "double_gauss"
            cases[name] = {"source": f"tests/refcases/{base}.json",
                           "object_distance_mm": dist,
                           "aspheres": {str(k): v for k, v in ASPHERES.items()}
                           if name == "cooke_asphere" else None,
                           **analyse(build(case, object_distance=dist), case)}
            print("done", name)
    out = {"computed_by": f"optiland {version('optiland')} via tools/conventions_reference.py",
           "points": [list(p) for p in POINTS], "fan_points": FAN_POINTS,
           "hexapolar": {"rings": RINGS, "x": np.asarray(hexa.x).tolist(),
                         "y": np.asarray(hexa.y).tolist()},
           "cases": cases}
    with open(a.out, "w") as f:
        json.dump(out, f, indent=None, separators=(",", ":"))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
