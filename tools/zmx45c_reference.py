"""Reference numbers for round 45c's .zmx files (public stock-lens and design files), from
optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/zmx45c_reference.py

It reads the eleven files of tests/data/zmx45c/ (SOURCES.md names them) with optiland's own
.zmx reader, sets every medium to optiland's ``IdealMaterial`` of the index computed here, at
each wavelength, from the catalog records jaxlens ships (the numpy formulas of
``tools/zmx40a_reference.py``, not jaxlens's code). A glass is looked up in the file's
``GCAT`` catalogs in their order, as Zemax does (in SCHOTT, Zemax's default, for a file
without a GCAT line); a glass none of them holds (the microscope
form's ``J-LLF2`` under ``GCAT SCHOTT``) is taken from the first shipped catalog that holds
the name, and the JSON says so (``"foreign"``). The indices are stored so that the test
first checks that jaxlens's are the same. Written to tests/data/zmx45c/optiland_reference.json:

* optiland's first-order data at each wavelength: EFL ``f2``, the rear focal point ``F2``
  (from the image surface), the entrance pupil's position ``EPL`` (from surface 1) and
  diameter ``EPD``, the exit pupil's position ``XPL`` (from the image surface) and diameter
  ``XPD``, and ``FNO``. For the file whose aperture is ``FNUM`` (image-space F/#), optiland
  sizes the pupil from the EFL at each wavelength: only the primary wavelength's ``EPD``
  and ``FNO`` are the file's (Zemax and jaxlens keep that EPD at every wavelength);
* real rays at the image surface: a pupil pattern (``PUPIL``, fractions of half the traced
  beam, rim points at 0.99 included) per field angle, launched 5 mm before surface 1, every
  aperture removed (a ray optiland loses is stored as null). The traced beam is the file's
  EPD (``ENPD``), or for ``FNUM`` the EPD optiland finds at the primary wavelength.

Two program-written files state their fields otherwise (``CONJUGATES``), and their rays are
built here, not by optiland's field handling:

* object heights (``FTYP 1``) of a finite object: each pupil ray goes from the object point
  (0, h) on the object plane to the point (px, py)·EPD/2 of the paraxial entrance pupil's
  plane (optiland's ``EPL``); the field angle Zemax gives such a field is that of the ray to
  the pupil's centre, atan(−h / (object distance + EPL)), stored too;
* real image heights (``FTYP 3``, x and y): the field (θx, θy) whose real chief ray meets the
  image surface at (x, y), solved here by Newton's method on optiland's trace (the chief ray
  through the stop's centre: the stop is surface 1, the entrance pupil's centre its vertex,
  so no aiming question arises); stored in degrees, direction ∝ (tan θx, tan θy, 1), and its
  collimated pupil rays traced as for the angle fields.

One file is written here (``dg50_ftyp3.zmx``): VendettaMask's double-gauss-50mm sample
(``samples/lenses/double-gauss-50mm.zmx`` of the same repository, its stop between the
groups) with its fields changed to real image heights (``FTYP 3``, 0, 6 and 12 mm) and no
RAIM line (ray aiming off). optiland 0.6.3 reads FTYP 3 as its own ``real_image_height``
field, whose chief ray goes through the paraxial entrance pupil's centre, as Zemax's does
with ray aiming off; its object-space chief-ray angles are stored (``DG50_FTYP3``).
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
import zmx43d_reference as z43  # noqa: E402  (file_media, trace, first_order, PUPIL)

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "zmx45c"
OUT_JSON = DATA / "optiland_reference.json"
FDC = (0.4861, 0.5876, 0.6563)
NIR = (0.7065, 0.855, 1.015)
FDC6 = (0.4861327, 0.5875618, 0.6562725)
# file: (field angles in degrees, wavelengths in µm (the file's active ones, primary first
# listed as the file's PWAV says in the test), primary wavelength)
FILES = {
    "thorlabs_AC254-100-A.zmx": ((0.0, 1.5, 3.0), FDC, 0.5876),
    "dcclab_AC254-125-A.zmx": ((0.0, 1.5, 3.0), FDC, 0.5876),
    "thorlabs_AC508-075-B.zmx": ((0.0, 2.0, 5.0), NIR, 0.855),
    "thorlabs_ACN127-030-B.zmx": ((0.0, 2.0, 5.0), NIR, 0.855),
    "thorlabs_AL1210-A.zmx": ((0.0, 1.0, 3.0), (0.78,), 0.78),
    "thorlabs_AL50100-A.zmx": ((0.0, 1.0, 3.0), (0.78,), 0.78),
    # The stop behind the lens (its flat back face), the EPD its image through the asphere.
    "thorlabs_ACL108-A.zmx": ((0.0, 2.0, 5.0), (0.55,), 0.55),
    "tangericm_microscope-objective-60x.zmx": ((0.0, 0.7, 1.0), FDC, 0.5876),
    # No GCAT line: Zemax's default catalog (SCHOTT) is searched.
    "tangericm_oct-semi-plossl-scan-lens.zmx": ((0.0, 4.2, 6.0), (0.8, 0.84, 0.9), 0.84),
}


# file: (object heights (mm, y) or real image heights (mm, (x, y))), wavelengths, primary
CONJUGATES = {
    "vendettamask_finite-conjugate-macro.zmx": ("object", (0.0, 10.0, 20.0), FDC6, 0.5875618),
    "vendettamask_real-image-height-demo.zmx": ("image", ((0.0, 0.0), (1.5, 2.0), (2.5, 4.0)),
                                                FDC6, 0.5875618),
}


DG50 = DATA / "dg50_ftyp3.zmx"
DG50_SURFACES = (  # (comment, curvature 1/mm, thickness mm, glass, semi-diameter mm)
    ("Front positive 1", "0.0263157894736842", "4", "N-BK7", "11"),
    ("Front positive 2", "0.00833333333333333", "1", "AIR", "11"),
    ("Front negative 1", "0.04", "5", "N-SF5", "9"),
    ("Front negative 2", "-0.04", "4", "AIR", "8"),
    ("Aperture stop", "0", "4", "AIR", "5"),
    ("Rear negative 1", "-0.04", "5", "N-SF5", "8"),
    ("Rear negative 2", "0.04", "1", "AIR", "9"),
    ("Rear positive 1", "-0.00833333333333333", "4", "N-BK7", "11"),
    ("Rear positive 2", "-0.0263157894736842", "45", "AIR", "11"),
)


def write_dg50():
    """The double Gauss with real-image-height fields (see the module notes)."""
    lines = ["VERS 190513 42 0", "MODE SEQ", "NAME Symmetric Double Gauss 50 mm, FTYP 3",
             "NOTE 0 Written by tools/zmx45c_reference.py after VendettaMask/opticalsystem "
             "samples/lenses/double-gauss-50mm.zmx, its fields made real image heights",
             "GCAT SCHOTT", "ENPD 10", "FTYP 3 0 3 3 0 0 0", "XFLN 0 0 0", "YFLN 0 6 12",
             "FWGN 1 1 1", "WAVM 1 0.4861327 1", "WAVM 2 0.5875618 1", "WAVM 3 0.6562725 1",
             "PWAV 2", "SURF 0", "  TYPE STANDARD", "  CURV 0", "  DISZ INFINITY"]
    for k, (comm, curv, disz, glas, diam) in enumerate(DG50_SURFACES, 1):
        lines += [f"SURF {k}", "  TYPE STANDARD", f"  COMM {comm}", f"  CURV {curv}",
                  f"  DISZ {disz}", f"  GLAS {glas}"] + (["  STOP"] if k == 5 else []) + [
                  f"  DIAM {diam}"]
    lines += [f"SURF {len(DG50_SURFACES) + 1}", "  TYPE STANDARD", "  CURV 0", "  DISZ 0"]
    DG50.write_text("\n".join(lines) + "\n")


def dg50_reference(recs) -> dict:
    """optiland's real-image-height chief rays of ``dg50_ftyp3.zmx`` at the primary
    wavelength: object-space angle (deg), image height, and height at the stop (mm)."""
    gcat, media = z43.file_media(DG50)
    media = [None if g == "AIR" else g for g in media]
    glasses = {g: catalog_of(g, gcat, recs)[0] for g in media if g is not None}
    op = load(DG50)
    set_media(op, media, glasses, recs, 0.5875618)
    fo = z43.first_order(op)
    out = {"heights": [0.0, 6.0, 12.0], "angles_deg": [], "image_y": [], "stop_y": [],
           "EPL": fo["EPL"], "f2": fo["f2"]}
    for hy in (0.0, 0.5, 1.0):
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            rays = op.trace_generic(0.0, hy, 0.0, 0.0, 0.5875618)
        m, n = float(np.ravel(op.surfaces.M)[0]), float(np.ravel(op.surfaces.N)[0])
        out["angles_deg"].append(math.degrees(math.atan2(m, n)))
        out["image_y"].append(float(np.ravel(rays.y)[0]))
        out["stop_y"].append(float(np.asarray(op.surfaces.y)[5, 0]))
    return out


FC_FTYP3 = (("FTYP 1 0 3 3 0 0 0", "FTYP 3 0 3 3 0 0 0"), ("YFLN 0 10 20", "YFLN 0 -1.5 -3"))
"""The finite-conjugate file's lines changed for ``fc_ftyp3_reference``: its fields made
real image heights (0, −1.5 and −3 mm), ray aiming off."""


def fc_ftyp3_reference(recs) -> dict:
    """optiland's real-image-height chief rays of the finite-conjugate file with FTYP 3
    fields (``FC_FTYP3``, a copy in a temporary folder): the object height (mm) of each."""
    text = (DATA / "vendettamask_finite-conjugate-macro.zmx").read_text()
    for old, new in FC_FTYP3:
        assert old in text
        text = text.replace(old, new)
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "fc_ftyp3.zmx"
        path.write_text(text)  # temporary
        gcat, media = z43.file_media(path)
        media = [None if g == "AIR" else g for g in media]
        glasses = {g: catalog_of(g, gcat, recs)[0] for g in media if g is not None}
        op = load(path)
    set_media(op, media, glasses, recs, 0.5875618)
    out = {"lines": FC_FTYP3, "image_y": [], "object_y": []}
    for hy in (0.5, 1.0):  # optiland's max field is 3 mm: +1.5 and +3 (the file's mirror)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            rays = op.trace_generic(0.0, hy, 0.0, 0.0, 0.5875618)
        out["image_y"].append(float(np.ravel(rays.y)[0]))
        out["object_y"].append(float(np.asarray(op.surfaces.y)[0, 0]))
    return out


def catalog_of(name, gcat, recs):
    """The catalog Zemax would take ``name`` from: the first GCAT catalog holding it, else
    (a foreign glass) the first shipped catalog holding it, alphabetically."""
    for c in gcat:
        if (c, name) in recs:
            return c, False
    return min(c for c, g in recs if g == name), True


def set_media(op, media, glasses, recs, wl):
    """optiland's media set to the catalog indices at ``wl``; returns them (after surface 0)."""
    ns = [1.0 if g is None else z40.index(recs[(glasses[g], g)], wl) for g in media[:-1]]
    for k, n in enumerate(ns):
        op.surfaces.surfaces[k].material_post = IdealMaterial(n=n)
    op.surfaces.surfaces[len(media) - 1].material_post = IdealMaterial(n=ns[-1])
    return ns[1:]


def load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_zemax_file(str(path))


def trace_rays(op, origins, dirs, wl):
    """Image intercepts (x, y) of rays (origins, unit directions), None where lost; every
    aperture removed."""
    for s in op.surfaces.surfaces:
        s.aperture = None
        g = s.geometry
        if hasattr(g, "tol") and hasattr(g, "max_iter"):
            g.tol, g.max_iter = 1e-13, 200
    o, d = np.asarray(origins, float), np.asarray(dirs, float)
    m = len(o)
    rays = RealRays(o[:, 0].copy(), o[:, 1].copy(), o[:, 2].copy(), d[:, 0].copy(),
                    d[:, 1].copy(), d[:, 2].copy(), np.ones(m), np.full(m, wl))
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        op.surfaces.trace(rays, skip=1)
    x, y, i = np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.i)
    return [[float(a), float(b)] if np.isfinite(a) and np.isfinite(b) and c > 0 else None
            for a, b, c in zip(x, y, i, strict=True)]


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def solve_real_height(op, target, z1, wl):
    """(tan θx, tan θy) of the ray through surface 1's vertex that meets the image at
    ``target`` (Newton's method, central differences)."""
    def land(t):
        d = unit([t[0], t[1], 1.0])
        return np.array(trace_rays(op, [np.array([0.0, 0.0, z1]) + z40.LAUNCH * d], [d],
                                   wl)[0])

    t = np.zeros(2)
    for _ in range(30):
        miss = land(t) - target
        if np.max(np.abs(miss)) < 1e-13:
            break
        h = 1e-6
        jac = np.stack([(land(t + h * e) - land(t - h * e)) / (2 * h) for e in np.eye(2)], 1)
        t = t - np.linalg.solve(jac, miss)
    assert np.max(np.abs(land(t) - target)) < 1e-12, (target, land(t))
    return t


def conjugate_entry(name, kind, fields, wavelengths, primary, recs):
    path = DATA / name
    gcat, media = z43.file_media(path)
    media = [None if g == "AIR" else g for g in media]  # the files' GLAS AIR lines
    glasses = {g: catalog_of(g, gcat, recs)[0] for g in media if g is not None}
    op = load(path)
    set_media(op, media, glasses, recs, primary)
    fo = z43.first_order(op)
    z1, z0 = z40.surface_z(op, 1), z40.surface_z(op, 0)
    entry = {"kind": kind, "fields": fields, "wavelengths": wavelengths, "primary": primary,
             "glasses": glasses, "first_order_primary": fo, "indices": {}, "rays": {},
             "stop_surface": int(op.surfaces.stop_index),
             "image_z_from_surface_1": z40.surface_z(op, len(media) - 1) - z1}
    r = 0.5 * fo["EPD"]
    if kind == "object":  # the rays from each object point to the paraxial entrance pupil
        entry["object_z_from_surface_1"] = z0 - z1
        entry["field_angles_deg"] = [math.degrees(math.atan(-h / (z1 - z0 + fo["EPL"])))
                                     for h in fields]
    else:
        entry["field_angles_deg"] = [[math.degrees(math.atan(v)) for v in
                                      solve_real_height(op, np.array(t), z1, primary)]
                                     for t in fields]
    for wl in wavelengths:
        op = load(path)
        entry["indices"][repr(wl)] = set_media(op, media, glasses, recs, wl)
        rows = []
        for k, f in enumerate(fields):
            if kind == "object":
                o = np.array([[0.0, f, z0]] * len(z43.PUPIL))
                p = np.array([[px * r, py * r, z1 + fo["EPL"]] for px, py in z43.PUPIL])
                d = unit(p - o)
            else:
                tx, ty = np.tan(np.radians(entry["field_angles_deg"][k]))
                d = np.tile(unit([tx, ty, 1.0]), (len(z43.PUPIL), 1))
                p = np.array([[px * r, py * r, z1] for px, py in z43.PUPIL])
                o = p + z40.LAUNCH * d
            rows.append(trace_rays(op, o, d, wl))
        entry["rays"][repr(wl)] = rows
    return entry


def main():
    recs = z40.agf_records()
    ref = {"launch_mm_before_surface_1": z40.LAUNCH, "pupil": z43.PUPIL, "files": {}}
    for name, (fields, wavelengths, primary) in FILES.items():
        path = DATA / name
        gcat, media = z43.file_media(path)
        gcat = gcat or ["SCHOTT"]  # no GCAT line: Zemax's default catalog
        glasses, foreign = {}, []
        for g in media:
            if g is not None and g not in glasses:
                glasses[g], alien = catalog_of(g, gcat, recs)
                if alien:
                    foreign.append(g)
        op = load(path)
        set_media(op, media, glasses, recs, primary)
        beam = float(np.ravel(op.paraxial.EPD())[0])
        entry = {"fields_deg": fields, "beam": beam, "wavelengths": wavelengths,
                 "primary": primary, "aperture": op.aperture.ap_type,
                 "aperture_value": float(op.aperture.value), "glasses": glasses,
                 "foreign": foreign, "indices": {}, "rays": {}, "first_order": {}}
        for wl in wavelengths:
            op = load(path)
            entry["indices"][repr(wl)] = set_media(op, media, glasses, recs, wl)
            entry["first_order"][repr(wl)] = z43.first_order(op)
            z1 = z40.surface_z(op, 1)
            entry["rays"][repr(wl)] = z43.trace(op, fields, wl, z1, beam)
        entry["stop_surface"] = int(op.surfaces.stop_index)
        entry["image_z_from_surface_1"] = z40.surface_z(op, len(media) - 1) - z1
        ref["files"][name] = entry
        assert math.isfinite(beam)
    ref["conjugates"] = {name: conjugate_entry(name, *spec, recs)
                         for name, spec in CONJUGATES.items()}
    write_dg50()
    ref["dg50_ftyp3"] = dg50_reference(recs)
    ref["fc_ftyp3"] = fc_ftyp3_reference(recs)
    # Written whole: a stop mid-write leaves the old file, not a cut one.
    with tempfile.NamedTemporaryFile("w", dir=OUT_JSON.parent, delete=False,
                                     suffix=".tmp") as fh:  # temporary
        fh.write(json.dumps(ref, indent=1) + "\n")
    pathlib.Path(fh.name).replace(OUT_JSON)
    print("wrote", OUT_JSON, {k: round(v["first_order"][repr(v["primary"])]["f2"], 9)
                              for k, v in ref["files"].items()})


if __name__ == "__main__":
    main()
