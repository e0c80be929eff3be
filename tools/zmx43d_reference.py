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
* for the shipped patent lens tests/data/zmx/rayoptics_US08427765-1.ZMX (round 40a), whose
  surfaces 7 and 8 cross 7.325 mm off the axis (between their clear apertures, 7.0 and
  7.53 mm), a fan of steep rays (``CROSSING``) that meet surface 7 beyond the crossing:
  optiland's point on surface 8 (reached by going back along the ray) and at the image,
  every aperture removed, and whether optiland's trace with the file's apertures passes;
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
PATENT = ROOT / "tests" / "data" / "zmx" / "rayoptics_US08427765-1.ZMX"
# Field angles (degrees) and ray heights (mm) on the plane 5 mm before surface 1, x = 0.
CROSSING = {"fields_deg": (20.0, 24.0), "heights": tuple(round(-6.0 + 0.5 * k, 1)
                                                          for k in range(31)),
            "wavelengths": (0.4861327, 0.5875618)}
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


def patent_media(op, recs, wl):
    """optiland's media of the patent lens set to the catalog indices at ``wl``."""
    gcat, media = file_media(PATENT)
    ns = []
    for g in media[:-1]:
        cat = None if g is None else next(c for c in gcat if (c, g) in recs)
        ns.append(1.0 if g is None else z40.index(recs[(cat, g)], wl))
    for k, n in enumerate(ns):
        op.surfaces.surfaces[k].material_post = IdealMaterial(n=n)
    op.surfaces.surfaces[len(media) - 1].material_post = IdealMaterial(n=ns[-1])
    return len(media)


def crossing(recs) -> dict:
    """optiland's rays of ``CROSSING`` through the patent lens (see the module notes)."""
    out = {**CROSSING, "launch_mm_before_surface_1": z40.LAUNCH, "rays": {}}
    for wl in CROSSING["wavelengths"]:
        rows = []
        for clipped in (False, True):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                op = load_zemax_file(str(PATENT))
            m = patent_media(op, recs, wl)
            z1 = z40.surface_z(op, 1)
            for s in op.surfaces.surfaces:
                if not clipped:
                    s.aperture = None
                g = s.geometry
                if hasattr(g, "tol") and hasattr(g, "max_iter"):  # the even asphere
                    g.tol, g.max_iter = 1e-13, 200
            for f in CROSSING["fields_deg"]:
                t = math.tan(math.radians(f))
                d = np.array([0.0, t, 1.0]) / math.sqrt(1 + t * t)
                hs = np.asarray(CROSSING["heights"], float)
                n = len(hs)
                rays = RealRays(np.zeros(n), hs.copy(), np.full(n, z1 + z40.LAUNCH),
                                np.full(n, d[0]), np.full(n, d[1]), np.full(n, d[2]),
                                np.ones(n), np.full(n, wl))
                with warnings.catch_warnings(), np.errstate(all="ignore"):
                    warnings.simplefilter("ignore")
                    op.surfaces.trace(rays, skip=1, record=True)
                i = np.asarray(rays.i)
                ok = np.isfinite(np.asarray(rays.x)) & np.isfinite(i) & (i > 0)
                if clipped:
                    rows.append([bool(v) for v in ok])
                    continue
                sy, sz = np.asarray(op.surfaces.y), np.asarray(op.surfaces.z)
                rows.append([{"image": [float(rays.x[k]), float(rays.y[k])],
                              # surface 8: row 7 of the record (row 0: surface 1)
                              "surface_8": [float(sy[7, k]), float(sz[7, k] - z1)]}
                             if ok[k] else None for k in range(n)])
        half = len(CROSSING["fields_deg"])
        out["rays"][repr(wl)] = {"free": rows[:half], "clipped_passes": rows[half:]}
        assert m == 13  # SURF 0 to 12
    return out


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
    ref["crossing_us08427765"] = crossing(recs)
    # Written whole: a stop mid-write leaves the old file, not a cut one.
    with tempfile.NamedTemporaryFile("w", dir=OUT_JSON.parent, delete=False,
                                     suffix=".tmp") as fh:  # temporary
        fh.write(json.dumps(ref, indent=1) + "\n")
    pathlib.Path(fh.name).replace(OUT_JSON)
    print("wrote", OUT_JSON, {k: round(v["first_order"][repr(v["wavelengths"][0])]["f2"], 9)
                              for k, v in ref["files"].items()})


if __name__ == "__main__":
    main()
