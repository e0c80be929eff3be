"""Reference numbers for round 40a's .zmx files (RPO molded glasses), from optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/zmx40a_reference.py

It writes two hand-made lens files that use Zemax's RPO catalog (tests/data/zmx40a/: a
Cooke triplet of three molded glasses, and a doublet of Vitron's IG6 and IG4 chalcogenides
at 8-12 µm) and, for those and the real file tests/data/zmx/rayoptics_US08427765-1.ZMX
(GLAS L-TIM28_MOLD, GCAT RPO), optiland's paraxial EFL and real rays at the image surface
to tests/data/zmx40a_optiland.json.

optiland knows no RPO glass, so every medium is given optiland's ``IdealMaterial`` of the
index computed here, at each wavelength, from the catalog records jaxlens ships
(jaxlens/data/glass/*.agf: the NM line's formula and the CD coefficients; Zemax's formulas 1
Schott, 2 Sellmeier 1 and 12 Extended 2, written out below in numpy, not jaxlens's code). The
indices are stored too, so the test first checks that jaxlens's are the same. The
hand-made files are built in optiland through its API from the same table that writes them;
the real file is read by optiland's own .zmx reader. Rays: for each field angle (deg, in the
y-z plane) and wavelength, a cross of pupil points launched from the plane 5 mm before
surface 1, traced with every aperture removed; a ray optiland loses is stored as null.
"""

import json
import math
import pathlib
import warnings

import numpy as np
from optiland import optic as optic_mod
from optiland.fileio import load_zemax_file
from optiland.materials import IdealMaterial
from optiland.rays import RealRays

ROOT = pathlib.Path(__file__).resolve().parents[1]
GLASS_DIR = ROOT / "jaxlens" / "data" / "glass"
OUT_DIR = ROOT / "tests" / "data" / "zmx40a"
OUT_JSON = ROOT / "tests" / "data" / "zmx40a_optiland.json"
REAL_FILE = ROOT / "tests" / "data" / "zmx" / "rayoptics_US08427765-1.ZMX"
LAUNCH = -5.0  # mm before surface 1
PUPIL = ((0.0, 0.0), (0.0, 0.9), (0.0, -0.9), (0.0, 0.5), (0.9, 0.0), (0.6, 0.6), (-0.4, 0.3))

# Each surface: (curvature 1/mm, thickness mm to the next, glass or None, is_stop).
SYSTEMS = {
    "rpo_molded_cooke.zmx": dict(
        gcat="RPO", epd=20.0, wavelengths=(0.4861327, 0.5875618, 0.6562725),
        fields=(0.0, 7.0, 10.0),
        surfaces=[(0.02019665437119806, 14.82389620733, "TAF3_MOLD", False),
                  (-0.009191260009826223, 3.116491119355, None, False),
                  (-0.01868424088622010, 2.999638141061, "L-TIM28_MOLD", False),
                  (0.02033479851238327, 6.980827603917, None, True),
                  (-0.01722581503292947, 6.858964409308, "N-BK7_MOLD", False),
                  (-0.02612836169571176, 121.8556200976, None, False)]),
    "rpo_ig_doublet.zmx": dict(
        gcat="RPO", epd=25.0, wavelengths=(8.0, 10.0, 12.0), fields=(0.0, 3.0, 5.0),
        surfaces=[(0.0, 2.0, None, True),
                  (0.012, 6.0, "IG6", False),
                  (0.004, 3.0, None, False),
                  (-0.006, 5.0, "IG4", False),
                  (-0.0025, 95.0, None, False)]),
}


def agf_records() -> dict:
    """Glass name (upper case) -> (catalog, formula, coefficients) from the shipped AGF files."""
    out = {}
    for path in sorted(GLASS_DIR.glob("*.agf")):
        name = None
        for line in path.read_text(encoding="latin-1").splitlines():
            t = line.split()
            if not t:
                continue
            if t[0] == "NM":
                name, formula = t[1].upper(), int(float(t[2]))
            elif t[0] == "CD" and name is not None:
                out.setdefault((path.stem, name), (formula, [float(v) for v in t[1:]]))
    return out


def index(record, wl: float) -> float:
    """Zemax's dispersion formulas 1 (Schott), 2 (Sellmeier 1) and 12 (Extended 2), λ in µm."""
    formula, c = record
    c = list(c) + [0.0] * (10 - len(c))
    w2 = wl * wl
    if formula == 1:
        n2 = c[0] + c[1] * w2 + c[2] / w2 + c[3] / w2**2 + c[4] / w2**3 + c[5] / w2**4
    elif formula == 2:
        n2 = 1.0 + sum(c[2 * i] * w2 / (w2 - c[2 * i + 1]) for i in range(3))
    elif formula == 12:
        powers = (0, 2, -2, -4, -6, -8, 4, 6)
        n2 = sum(ci * wl**p for ci, p in zip(c, powers, strict=False))
    else:
        raise ValueError(f"formula {formula} is not written out here")
    return math.sqrt(n2)


def write_zmx(name: str, s: dict) -> None:
    lines = ["VERS 190513 80 123457", "MODE SEQ", f"NAME round 40a {name}",
             "UNIT MM X W X CM MR CPMM", f"ENPD {s['epd']!r}", f"GCAT {s['gcat']}",
             f"FTYP 0 0 {len(s['fields'])} {len(s['wavelengths'])} 0 0 0",
             "XFLN " + " ".join("0" for _ in s["fields"]),
             "YFLN " + " ".join(repr(f) for f in s["fields"])]
    lines += [f"WAVM {i} {w!r} 1" for i, w in enumerate(s["wavelengths"], start=1)]
    lines += ["PWAV 2", "SURF 0", "  TYPE STANDARD", "  CURV 0.0", "  DISZ INFINITY"]
    for i, (c, t, glass, stop) in enumerate(s["surfaces"], start=1):
        lines += [f"SURF {i}"] + (["  STOP"] if stop else []) + [
            "  TYPE STANDARD", f"  CURV {c!r}", f"  DISZ {t!r}"]
        if glass:
            lines.append(f"  GLAS {glass} 0 0 0 0 0 0 0 0 0 0")
    lines += [f"SURF {len(s['surfaces']) + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0"]
    (OUT_DIR / name).write_text("\n".join(lines) + "\n")


def build(s: dict, media: list, wl: float):
    """optiland's optic of table ``s`` with the media (glass name or None per gap) at wl."""
    recs = agf_records()
    op = optic_mod.Optic()
    op.add_surface(index=0, thickness=np.inf)
    for i, (c, t, glass, stop) in enumerate(s["surfaces"]):
        n = 1.0 if glass is None else index(recs[("RPO", glass)], wl)
        op.add_surface(index=i + 1, radius=(1 / c if c else np.inf), thickness=t,
                       material=IdealMaterial(n=n), is_stop=stop)
    op.add_surface(index=len(s["surfaces"]) + 1)
    op.set_aperture(aperture_type="EPD", value=s["epd"])
    op.set_field_type(field_type="angle")
    op.fields.add(y=0.0)
    op.wavelengths.add(value=wl, is_primary=True)
    return op


def real_file_media(path) -> list:
    """(glass name, catalog) of the medium after each surface of the real file (None: air),
    and the file's GCAT list, read from its text."""
    text = path.read_bytes().decode("latin-1")
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


def trace(op, fields, wl, z1, epd):
    """Image intercepts (x, y) of the PUPIL cross at each field angle, or None where lost."""
    out = []
    r = 0.5 * epd
    for f in fields:
        t = math.tan(math.radians(f))
        d = np.array([0.0, t, 1.0]) / math.sqrt(1 + t * t)
        o = np.array([[px * r, py * r + LAUNCH * -t, z1 + LAUNCH] for px, py in PUPIL])
        m = len(PUPIL)
        rays = RealRays(o[:, 0].copy(), o[:, 1].copy(), o[:, 2].copy(),
                        np.full(m, d[0]), np.full(m, d[1]), np.full(m, d[2]),
                        np.ones(m), np.full(m, wl))
        for s in op.surfaces.surfaces:
            s.aperture = None
            g = s.geometry
            if hasattr(g, "tol") and hasattr(g, "max_iter"):
                g.tol, g.max_iter = 1e-13, 200
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            op.surfaces.trace(rays, skip=1)
        x, y, i = np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.i)
        out.append([[float(a), float(b)] if np.isfinite(a) and np.isfinite(b) and c > 0
                    else None for a, b, c in zip(x, y, i, strict=True)])
    return out


def surface_z(op, k: int) -> float:
    return float(np.ravel(np.asarray(op.surfaces.surfaces[k].geometry.cs.z))[0])


def main():
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    recs = agf_records()
    ref = {"launch_mm_before_surface_1": LAUNCH, "pupil": PUPIL, "files": {}}
    for name, s in SYSTEMS.items():
        write_zmx(name, s)
        entry = {"fields_deg": s["fields"], "epd": s["epd"], "wavelengths": s["wavelengths"],
                 "indices": {}, "rays": {}, "efl": {}}
        for wl in s["wavelengths"]:
            op = build(s, None, wl)
            entry["indices"][repr(wl)] = [1.0 if g is None else index(recs[("RPO", g)], wl)
                                          for (_, _, g, _) in s["surfaces"]]
            entry["efl"][repr(wl)] = float(op.paraxial.f2())
            z1 = surface_z(op, 1)
            entry["rays"][repr(wl)] = trace(op, s["fields"], wl, z1, s["epd"])
        entry["image_z_from_surface_1"] = surface_z(op, len(s["surfaces"]) + 1) - z1
        ref["files"][name] = entry
    # The real file: optiland's reader, the media set to the catalogs' indices.
    gcat, media = real_file_media(REAL_FILE)
    order = {c: k for k, c in enumerate(gcat)}
    # Field angles up to 11° and a beam 12 mm wide (the file: EPD 14.6 mm at f/2.1, real
    # image heights up to 13.6 mm, about 24°). A ray 6.3 mm off the axis at 13.6° passes
    # where the rims of surfaces 7 and 8 cross (surface 8 lies before surface 7 there), which
    # jaxlens and optiland resolve differently: jaxlens takes the root ahead of the ray on
    # the far rim, optiland the one behind it (tools/check_rays.py sets such rays apart,
    # "crossed surfaces outside the clear aperture").
    entry = {"fields_deg": (0.0, 6.0, 11.0), "epd": 12.0, "wavelengths": (0.4861327, 0.5875618,
                                                                          0.6562725),
             "indices": {}, "rays": {}, "efl": {}, "glasses": {}}
    for wl in entry["wavelengths"]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            op = load_zemax_file(str(REAL_FILE))
        ns = []
        for k, g in enumerate(media[:-1]):
            if g is None:
                n = 1.0
            else:  # the first GCAT catalog holding the name, as Zemax searches
                cats = sorted((c for (c, nm) in recs if nm == g and c in order), key=order.get)
                entry["glasses"][g] = cats[0]
                n = index(recs[(cats[0], g)], wl)
            ns.append(n)
            op.surfaces.surfaces[k].material_post = IdealMaterial(n=n)
        op.surfaces.surfaces[len(media) - 1].material_post = IdealMaterial(n=ns[-1])
        entry["indices"][repr(wl)] = ns[1:]
        entry["efl"][repr(wl)] = float(op.paraxial.f2())
        z1 = surface_z(op, 1)
        entry["rays"][repr(wl)] = trace(op, entry["fields_deg"], wl, z1, entry["epd"])
    entry["image_z_from_surface_1"] = surface_z(op, len(media) - 1) - z1
    ref["files"][REAL_FILE.name] = entry
    OUT_JSON.write_text(json.dumps(ref, indent=1) + "\n")
    print("wrote", OUT_JSON)


if __name__ == "__main__":
    main()
