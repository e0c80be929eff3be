"""Reference numbers for round 45c's .zmx files (public stock-lens and design files), from
optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/zmx45c_reference.py

It reads the eight files of tests/data/zmx45c/ (SOURCES.md names them) with optiland's own
.zmx reader, sets every medium to optiland's ``IdealMaterial`` of the index computed here, at
each wavelength, from the catalog records jaxlens ships (the numpy formulas of
``tools/zmx40a_reference.py``, not jaxlens's code). A glass is looked up in the file's
``GCAT`` catalogs in their order, as Zemax does; a glass none of them holds (the microscope
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

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import zmx40a_reference as z40  # noqa: E402  (agf_records, index, surface_z, LAUNCH)
import zmx43d_reference as z43  # noqa: E402  (file_media, trace, first_order, PUPIL)

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "zmx45c"
OUT_JSON = DATA / "optiland_reference.json"
FDC = (0.4861, 0.5876, 0.6563)
NIR = (0.7065, 0.855, 1.015)
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
}


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


def main():
    recs = z40.agf_records()
    ref = {"launch_mm_before_surface_1": z40.LAUNCH, "pupil": z43.PUPIL, "files": {}}
    for name, (fields, wavelengths, primary) in FILES.items():
        path = DATA / name
        gcat, media = z43.file_media(path)
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
    # Written whole: a stop mid-write leaves the old file, not a cut one.
    with tempfile.NamedTemporaryFile("w", dir=OUT_JSON.parent, delete=False,
                                     suffix=".tmp") as fh:  # temporary
        fh.write(json.dumps(ref, indent=1) + "\n")
    pathlib.Path(fh.name).replace(OUT_JSON)
    print("wrote", OUT_JSON, {k: round(v["first_order"][repr(v["primary"])]["f2"], 9)
                              for k, v in ref["files"].items()})


if __name__ == "__main__":
    main()
