"""Reference numbers for round 42d's .zmx files (Edmund Optics stock lenses), from optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/zmx42d_reference.py

It reads the three real files of tests/data/zmx42d/ (SOURCES.md names them) with optiland's
own .zmx reader, sets every medium to optiland's ``IdealMaterial`` of the index computed
here, at each wavelength, from the catalog records jaxlens ships (the numpy formulas of
``tools/zmx40a_reference.py``, not jaxlens's code; the indices are stored so that the test
first checks jaxlens's are the same), and writes to tests/data/zmx42d/optiland_reference.json:

* the paraxial EFL, the image surface's z from surface 1, and real rays at the image
  surface (a cross of pupil points per field angle, launched 5 mm before surface 1, every
  aperture removed; a ray optiland loses is stored as null), at the F, d and C lines;
* the paraxial marginal ray's height at the stop for the file's EPD (d line), which the
  stop-clipping note of ``jaxlens.analysis.stop_clip`` compares with the stop's radius;
* for the Cooke triplet of jaxlens/data/lenses/cooke_triplet.json, built here through
  optiland's API from that file's radii and thicknesses, that height and the real height at
  the stop of the on-axis ray through the rim of the entrance pupil (round 42d's test gives
  its stop a fixed 1 mm semi-diameter), and the working EPD of that stop: twice the pupil
  radius whose real ray meets the stop 1 mm high (bisection on optiland's real rays).
"""

import json
import pathlib
import sys
import tempfile
import warnings

import numpy as np
from optiland import optic as optic_mod
from optiland.fileio import load_zemax_file
from optiland.materials import IdealMaterial
from optiland.rays import RealRays

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import zmx40a_reference as z40  # noqa: E402  (agf_records, index, trace, surface_z)

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "zmx42d"
OUT_JSON = ROOT / "tests" / "data" / "zmx42d" / "optiland_reference.json"
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"
WAVELENGTHS = (0.4861327, 0.5875618, 0.6562725)
# file: (field angles in degrees, beam diameter traced, mm; the catalogs searched, in order)
FILES = {
    "optictrace_edmund_38398.zmx": ((0.0, 3.0, 6.0), 11.0, ("SCHOTT",)),
    "optictrace_edmund_68001.zmx": ((0.0, 3.0, 6.0), 23.0, ("SCHOTT",)),
    "raysim_edmund_16979.zmx": ((0.0, 2.0, 4.0), 24.0, ("SCHOTT",)),
}


def set_media(op, media, recs, cats, wl):
    """Every medium of optiland's optic set to the catalog index at ``wl``; returns them."""
    ns = []
    for k, g in enumerate(media[:-1]):
        n = 1.0 if g is None else z40.index(
            next(recs[(c, g)] for c in cats if (c, g) in recs), wl)
        ns.append(n)
        op.surfaces.surfaces[k].material_post = IdealMaterial(n=n)
    op.surfaces.surfaces[len(media) - 1].material_post = IdealMaterial(n=ns[-1])
    return ns


def marginal_height_at_stop(op) -> float:
    y, _ = op.paraxial.marginal_ray()
    return float(np.ravel(y)[op.surfaces.stop_index])


def cooke_heights(recs) -> dict:
    """optiland's marginal-ray height at the Cooke triplet's stop, d line."""
    spec = json.loads(COOKE.read_text())
    wl = 0.5875618
    op = optic_mod.Optic()
    op.add_surface(index=0, thickness=np.inf)
    rows = spec["surfaces"][1:-1]
    for i, s in enumerate(rows, start=1):
        glass = s.get("material")
        n = 1.0 if glass is None else z40.index(recs[("SCHOTT", glass.upper())], wl)
        op.add_surface(index=i, radius=s["radius"], thickness=s["thickness"],
                       material=IdealMaterial(n=n), is_stop=bool(s.get("is_stop")))
    op.add_surface(index=len(rows) + 1)
    op.set_aperture(aperture_type="EPD", value=spec["aperture"]["epd"])
    op.set_field_type(field_type="angle")
    op.fields.add(y=0.0)
    op.wavelengths.add(value=wl, is_primary=True)
    # The real on-axis ray through the rim of the entrance pupil (parallel to the axis: the
    # object is at infinity), traced without apertures to the stop.
    for s in op.surfaces.surfaces:
        s.aperture = None
    z1 = z40.surface_z(op, 1)

    def height(h):
        rays = RealRays([0.0], [h], [z1 + z40.LAUNCH], [0.0], [0.0], [1.0], [1.0], [wl])
        op.surfaces.trace(rays, skip=1)
        # The trace skipped the object surface: row k holds surface k + 1.
        return float(np.ravel(np.asarray(op.surfaces.y))[op.surfaces.stop_index - 1])

    epd = spec["aperture"]["epd"]
    real = height(0.5 * epd)
    # The pupil radius whose real ray meets a 1 mm stop's rim: bisection on optiland's rays.
    lo, hi = 0.0, 0.5 * epd
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if height(mid) < 1.0 else (lo, mid)
    return {"epd": epd, "stop_surface": op.surfaces.stop_index,
            "marginal_height_at_stop": marginal_height_at_stop(op),
            "real_rim_ray_height_at_stop": real,
            "working_epd_1mm_stop_real_rays": lo + hi, "wavelength": wl}


def main():
    recs = z40.agf_records()
    ref = {"launch_mm_before_surface_1": z40.LAUNCH, "pupil": z40.PUPIL, "files": {}}
    for name, (fields, beam, cats) in FILES.items():
        path = DATA / name
        _, media = z40.real_file_media(path)
        entry = {"fields_deg": fields, "epd": beam, "wavelengths": WAVELENGTHS,
                 "catalogs": cats, "indices": {}, "rays": {}, "efl": {}}
        for wl in WAVELENGTHS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                op = load_zemax_file(str(path))
            ns = set_media(op, media, recs, cats, wl)
            entry["indices"][repr(wl)] = ns[1:]
            entry["efl"][repr(wl)] = float(op.paraxial.f2())
            if wl == 0.5875618:
                entry["file_epd"] = float(op.aperture.value)
                entry["stop_surface"] = int(op.surfaces.stop_index)
                entry["marginal_height_at_stop"] = marginal_height_at_stop(op)
            z1 = z40.surface_z(op, 1)
            entry["rays"][repr(wl)] = z40.trace(op, fields, wl, z1, beam)
        entry["image_z_from_surface_1"] = z40.surface_z(op, len(media) - 1) - z1
        ref["files"][name] = entry
    ref["cooke_triplet"] = cooke_heights(recs)
    # Written whole: a stop mid-write leaves the old file, not a cut one.
    with tempfile.NamedTemporaryFile("w", dir=OUT_JSON.parent, delete=False,
                                     suffix=".tmp") as fh:  # temporary
        fh.write(json.dumps(ref, indent=1) + "\n")
    pathlib.Path(fh.name).replace(OUT_JSON)
    print("wrote", OUT_JSON, "; beams at the stop:",
          {k: round(v["marginal_height_at_stop"], 9) for k, v in ref["files"].items()},
          round(ref["cooke_triplet"]["marginal_height_at_stop"], 9))


if __name__ == "__main__":
    main()
