"""Reference numbers for round 43d's .zmx files (UTF-16 stock-lens files), from optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/zmx43d_reference.py

It reads the three real files of tests/data/zmx43d/ (SOURCES.md names them; all three are
UTF-16LE with a byte-order mark and CRLF line ends, as OpticStudio saves) with optiland's own
.zmx reader, sets every medium to optiland's ``IdealMaterial`` of the index computed here, at
each wavelength, from the catalog records jaxlens ships (the numpy formulas of
``tools/zmx40a_reference.py``, not jaxlens's code; the catalogs are searched in the file's
``GCAT`` order, as Zemax does; the indices are stored so that the test first checks that
jaxlens's are the same), and writes to tests/data/zmx43d/optiland_reference.json:

* optiland's first-order data at each wavelength: EFL ``f2``, the rear focal point ``F2``
  (from the image surface), the entrance pupil's position ``EPL`` (from surface 1) and
  diameter ``EPD``, the exit pupil's position ``XPL`` (from the image surface) and diameter
  ``XPD``, and ``FNO``;
* real rays at the image surface: a pupil pattern (``PUPIL``, fractions of half the traced
  beam, rim points at 0.99 included) per field angle, launched 5 mm before surface 1, every
  aperture removed (a ray optiland loses is stored as null).
"""

import json
import math
import pathlib
import sys
import tempfile
import warnings

import numpy as np
from optiland.fileio import load_zemax_file
from optiland.materials import IdealMaterial
from optiland.rays import RealRays

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import zmx40a_reference as z40  # noqa: E402  (agf_records, index, surface_z, LAUNCH)

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "zmx43d"
OUT_JSON = DATA / "optiland_reference.json"
FDC = (0.4861327, 0.5875618, 0.6562725)
PUPIL = ((0.0, 0.0), (0.0, 0.5), (0.0, -0.5), (0.0, 0.99), (0.0, -0.99), (0.99, 0.0),
         (0.7, 0.7), (-0.5, 0.3), (0.3, -0.8))
# file: (field angles in degrees, beam diameter traced in mm, wavelengths in µm)
FILES = {
    # Thorlabs 354710-C: a 1.49 mm molded asphere of LightPath's D-ZK3M at 1.55 µm, a BK7
    # window after it; the file's EPD is 1.5 mm.
    "rayoptics_354710-C.zmx": ((0.0, 1.0, 2.0), 1.5, (0.5875618, 1.55)),
    # Thorlabs ACL3026U: a B270 aspheric condenser, EPD 27 mm under a 30 mm stop.
    "rayoptics_ACL3026U.zmx": ((0.0, 2.0, 4.0), 27.0, FDC),
    # Edmund 55278: two SF5/BK7 achromats face to face, EPD 22 mm.
    "rayoptics_zmax_55278.zmx": ((0.0, 2.0, 4.0), 22.0, FDC),
}


def file_media(path: pathlib.Path):
    """The file's GCAT catalogs and the glass (upper case; None: air) after each surface,
    read from its text (UTF-16 with a byte-order mark, or 8-bit)."""
    raw = path.read_bytes()
    text = raw.decode("utf-16") if raw[:2] in (b"\xff\xfe", b"\xfe\xff") else raw.decode(
        "latin-1")
    gcat, media, cur, started = [], [], None, False
    for line in text.splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "GCAT":
            gcat = t[1:]
        elif t[0] == "SURF":
            if started:
                media.append(cur)
            cur, started = None, True
        elif t[0] == "GLAS":
            cur = t[1].upper()
    media.append(cur)
    return gcat, media


def trace(op, fields, wl, z1, beam):
    """Image intercepts (x, y) of the PUPIL points at each field angle, or None where lost."""
    out = []
    r = 0.5 * beam
    for s in op.surfaces.surfaces:
        s.aperture = None
        g = s.geometry
        if hasattr(g, "tol") and hasattr(g, "max_iter"):
            g.tol, g.max_iter = 1e-13, 200
    for f in fields:
        t = math.tan(math.radians(f))
        d = np.array([0.0, t, 1.0]) / math.sqrt(1 + t * t)
        o = np.array([[px * r, py * r - z40.LAUNCH * t, z1 + z40.LAUNCH] for px, py in PUPIL])
        m = len(PUPIL)
        rays = RealRays(o[:, 0].copy(), o[:, 1].copy(), o[:, 2].copy(),
                        np.full(m, d[0]), np.full(m, d[1]), np.full(m, d[2]),
                        np.ones(m), np.full(m, wl))
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            op.surfaces.trace(rays, skip=1)
        x, y, i = np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.i)
        out.append([[float(a), float(b)] if np.isfinite(a) and np.isfinite(b) and c > 0
                    else None for a, b, c in zip(x, y, i, strict=True)])
    return out


def first_order(op) -> dict:
    p = op.paraxial
    return {k: float(np.ravel(getattr(p, k)())[0])
            for k in ("f2", "F2", "EPL", "EPD", "XPL", "XPD", "FNO")}


def main():
    recs = z40.agf_records()
    ref = {"launch_mm_before_surface_1": z40.LAUNCH, "pupil": PUPIL, "files": {}}
    for name, (fields, beam, wavelengths) in FILES.items():
        path = DATA / name
        gcat, media = file_media(path)
        glasses = {}
        for g in media:
            if g is not None:  # the first GCAT catalog holding the name, as Zemax searches
                glasses[g] = next(c for c in gcat if (c, g) in recs)
        entry = {"fields_deg": fields, "beam": beam, "wavelengths": wavelengths,
                 "glasses": glasses, "indices": {}, "rays": {}, "first_order": {}}
        for wl in wavelengths:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                op = load_zemax_file(str(path))
            ns = [1.0 if g is None else z40.index(recs[(glasses[g], g)], wl)
                  for g in media[:-1]]
            for k, n in enumerate(ns):
                op.surfaces.surfaces[k].material_post = IdealMaterial(n=n)
            op.surfaces.surfaces[len(media) - 1].material_post = IdealMaterial(n=ns[-1])
            entry["indices"][repr(wl)] = ns[1:]
            entry["first_order"][repr(wl)] = first_order(op)
            z1 = z40.surface_z(op, 1)
            entry["rays"][repr(wl)] = trace(op, fields, wl, z1, beam)
        entry["file_epd"] = float(op.aperture.value)
        entry["stop_surface"] = int(op.surfaces.stop_index)
        entry["image_z_from_surface_1"] = z40.surface_z(op, len(media) - 1) - z1
        ref["files"][name] = entry
    # Written whole: a stop mid-write leaves the old file, not a cut one.
    with tempfile.NamedTemporaryFile("w", dir=OUT_JSON.parent, delete=False,
                                     suffix=".tmp") as fh:  # temporary
        fh.write(json.dumps(ref, indent=1) + "\n")
    pathlib.Path(fh.name).replace(OUT_JSON)
    print("wrote", OUT_JSON, {k: round(v["first_order"][repr(v["wavelengths"][0])]["f2"], 9)
                              for k, v in ref["files"].items()})


if __name__ == "__main__":
    main()
