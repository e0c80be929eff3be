"""Reference numbers for object-space telecentric .zmx files (round 38a), from optiland 0.6.3.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/telecentric38a_reference.py

It writes three hand-made object-space telecentric lens files (FTYP's second value 1) to
tests/data/zmx38a/ and, for each, optiland's real rays at the image surface (several object
heights, pupil points and wavelengths), EFL, paraxial working F/# and image-space NA, and
the paraxial marginal ray's height at the stop to tests/data/zmx38a_optiland.json. optiland
is built from the same prescription through its own API (``obj_space_telecentric = True``,
an ``objectNA`` aperture, ``object_height`` fields), not from the files: its .zmx reader
drops the telecentric flag. The files' apertures that optiland does not take with a
telecentric object (FLOA, OBNA x 1) and paraxial image-height fields are converted here,
independently of jaxlens: the NA from the object cone angle, n·sin u; float by stop size from
optiland's paraxial marginal ray (tan u scaled so that it meets the stop at the file's
semi-diameter); object heights from paraxial image heights by optiland's paraxial
magnification (its marginal and chief rays traced from the object, the chief ray parallel
to the axis).
"""

import json
import math
import pathlib

import numpy as np
from optiland import optic as optic_mod
from optiland.materials import Material

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT_DIR = ROOT / "tests" / "data" / "zmx38a"
OUT_JSON = ROOT / "tests" / "data" / "zmx38a_optiland.json"
WAVELENGTHS = (0.4861327, 0.5875618, 0.6562725)
PUPIL = ((0.0, 0.0), (0.0, 1.0), (0.0, -0.7), (0.5, 0.5), (1.0, 0.0), (-0.3, 0.8))

# Each surface: (curvature 1/mm, thickness mm to the next, glass or None, is_stop, semi-dia).
SYSTEMS = {
    "tele_doublet_obna": dict(
        object_distance=60.0, aperture=("OBNA", 0.08, 0), ftyp=1,
        fields=[(0.0, 0.0), (0.0, 4.0), (0.0, 8.0)],
        surfaces=[(1 / 40, 8.0, "N-SK16", False, 16), (-1 / 30, 3.0, "F2", False, 16),
                  (-1 / 120, 44.41333, None, False, 16), (0.0, 15.0, None, True, 6),
                  (1 / 50, 6.0, "N-BK7", False, 16), (-1 / 50, 37.0301, None, False, 16)]),
    "tele_triplet_floa": dict(
        object_distance=40.0, aperture=("FLOA",), stop_sd=2.5, ftyp=1,
        fields=[(0.0, 0.0), (3.0, 0.0), (2.0, -4.0)],
        surfaces=[(1 / 60, 5.0, "N-BK7", False, 14), (-1 / 60, 57.21356, None, False, 14),
                  (0.0, 12.0, None, True, 2.5), (1 / 40, 6.0, "N-BK7", False, 12),
                  (-1 / 40, 2.0, None, False, 12), (-1 / 45, 3.0, "F2", False, 12),
                  (1 / 100, 391.776, None, False, 12)]),
    "tele_doublet_cone_parimage": dict(
        object_distance=80.0, aperture=("OBNA", 4.0, 1), ftyp=2,
        fields=[(0.0, 0.0), (0.0, -2.0), (0.0, -4.0)],
        surfaces=[(1 / 40, 8.0, "N-SK16", False, 16), (-1 / 30, 3.0, "F2", False, 16),
                  (-1 / 120, 44.41333, None, False, 16), (0.0, 15.0, None, True, 6),
                  (1 / 50, 6.0, "N-BK7", False, 16), (-1 / 50, 25.0168, None, False, 16)]),
    "tele_doublet_realimage": dict(
        object_distance=70.0, aperture=("OBNA", 0.1, 0), ftyp=3,
        fields=[(0.0, 0.0), (0.0, -3.0), (0.0, -7.5)],
        surfaces=[(1 / 40, 8.0, "N-SK16", False, 16), (-1 / 30, 3.0, "F2", False, 16),
                  (-1 / 120, 44.41333, None, False, 16), (0.0, 15.0, None, True, 6),
                  (1 / 50, 6.0, "N-BK7", False, 16), (-1 / 50, 30.0, None, False, 16)]),
}


def zmx_text(name: str, s: dict) -> str:
    """The system as a .zmx file (UTF-8; the reader takes UTF-8 or UTF-16)."""
    ap = s["aperture"]
    n = len(s["fields"])
    lines = ["VERS 190513 80 123457 L123457", "MODE SEQ", f"NAME {name}",
             "NOTE 0 Written by tools/telecentric38a_reference.py: an object-space "
             "telecentric test lens", "UNIT MM X W X CM MR CPMM",
             "FLOA" if ap[0] == "FLOA" else f"OBNA {ap[1]!r} {ap[2]}",
             "ENVD 2.0E+1 1 0", "GFAC 0 0", "GCAT SCHOTT",
             f"FTYP {s['ftyp']} 1 {n} {len(WAVELENGTHS)} 0 0 0",
             "XFLN " + " ".join(repr(f[0]) for f in s["fields"]),
             "YFLN " + " ".join(repr(f[1]) for f in s["fields"]),
             "FWGN " + " ".join("1" for _ in s["fields"])]
    lines += [f"WAVM {i + 1} {w!r} 1" for i, w in enumerate(WAVELENGTHS)]
    lines += ["PWAV 2", "SURF 0", "  TYPE STANDARD", "  CURV 0.0",
              f"  DISZ {s['object_distance']!r}"]
    for i, (c, t, glass, stop, sd) in enumerate(s["surfaces"]):
        lines += [f"SURF {i + 1}"] + (["  STOP"] if stop else [])
        lines += ["  TYPE STANDARD", f"  CURV {c!r}", f"  DISZ {t!r}"]
        if glass:
            lines.append(f"  GLAS {glass}")
        lines.append(f"  DIAM {sd!r} 1 0 0 1 \"\"")
    lines += [f"SURF {len(s['surfaces']) + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0"]
    return "\n".join(lines) + "\n"


def build(s: dict, na: float, heights) -> optic_mod.Optic:
    """optiland's optic of the system: telecentric object space, object-NA aperture, object
    heights (mm, (x, y) pairs)."""
    op = optic_mod.Optic()
    op.add_surface(index=0, thickness=s["object_distance"])
    for i, (c, t, glass, stop, _) in enumerate(s["surfaces"]):
        op.add_surface(index=i + 1, radius=(1 / c if c else np.inf), thickness=t,
                       material=Material(glass, "schott") if glass else "air",
                       is_stop=stop)
    op.add_surface(index=len(s["surfaces"]) + 1)
    op.set_aperture(aperture_type="objectNA", value=na)
    op.set_field_type("object_height")
    for x, y in heights:
        op.add_field(y=y, x=x)
    for w in WAVELENGTHS:
        op.add_wavelength(value=w, is_primary=(w == WAVELENGTHS[1]))
    op.obj_space_telecentric = True
    return op


def marginal_height_at_stop(op, s) -> float:
    y, _ = op.paraxial.marginal_ray()
    stop = next(i for i, e in enumerate(s["surfaces"]) if e[3]) + 1  # optiland: object is 0
    return float(np.ravel(y[stop])[0])


def telecentric_magnification(op, s) -> float:
    """The paraxial image height (mm) of a 1 mm object height, its chief ray parallel to the
    axis (optiland's ``paraxial.chief_ray`` passes the stop's centre whatever the
    telecentric flag: 3e-8 off here, the stop not exactly at the front group's focus)."""
    y, _ = op.paraxial.trace_generic(1.0, 0.0, -s["object_distance"], op.primary_wavelength)
    return float(np.ravel(y[-1])[0])


def chief_landing(s, na, h) -> float:
    """y on the image surface of the real chief ray from object height h (mm), primary λ."""
    if h == 0.0:
        return 0.0
    op = build(s, na, [(0.0, h)])
    r = op.trace_generic(0.0, 1.0 if h > 0 else -1.0, np.array([0.0]), np.array([0.0]),
                         WAVELENGTHS[1])
    return float(np.ravel(r.y)[0])


def real_height_object(s, na, target, h) -> float:
    """The object height whose real chief ray meets the image surface at ``target`` (mm)."""
    for _ in range(30):
        miss = chief_landing(s, na, h) - target
        if abs(miss) <= 1e-14 * (1 + abs(target)):
            break
        d = 1e-6 * (1 + abs(h))
        slope = (chief_landing(s, na, h + d) - chief_landing(s, na, h - d)) / (2 * d)
        h -= miss / slope
    return h


def main() -> None:
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    out = {"source": "optiland 0.6.3 (tools/telecentric38a_reference.py)",
           "wavelengths_um": list(WAVELENGTHS), "pupil": [list(p) for p in PUPIL],
           "systems": {}}
    for name, s in SYSTEMS.items():
        (OUT_DIR / f"{name}.zmx").write_text(zmx_text(name, s), encoding="utf-8")
        n0 = 1.0
        ap = s["aperture"]
        if ap[0] == "OBNA":
            na = ap[1] if ap[2] == 0 else n0 * math.sin(math.radians(ap[1]))
        else:  # float by stop size: scale tan u so the marginal ray meets the stop at its sd
            na0 = 0.01
            probe = build(s, na0, [(0.0, 0.0), (0.0, 1.0)])
            t0 = na0 / math.sqrt(1 - na0 ** 2)
            t = t0 * s["stop_sd"] / abs(marginal_height_at_stop(probe, s))
            na = n0 * t / math.sqrt(1 + t * t)
        heights = s["fields"]
        if s["ftyp"] == 2:  # paraxial image heights -> object heights: h / magnification
            m = telecentric_magnification(build(s, na, [(0.0, 0.0), (0.0, 1.0)]), s)
            heights = [(x / m, yy / m) for x, yy in heights]
        if s["ftyp"] == 3:  # real image heights -> object heights: Newton on the real
            # chief ray (parallel to the axis), from the paraxial guess
            m = telecentric_magnification(build(s, na, [(0.0, 0.0), (0.0, 1.0)]), s)
            heights = [(0.0, real_height_object(s, na, yy, yy / m)) for _, yy in heights]
        op = build(s, na, heights)
        rmax = max(math.hypot(*h) for h in heights)
        rays = []
        for (hx, hy) in heights:
            for w in WAVELENGTHS:
                px = np.array([p[0] for p in PUPIL])
                py = np.array([p[1] for p in PUPIL])
                r = op.trace_generic(hx / rmax, hy / rmax, px, py, w)
                rays.append({"height": [hx, hy], "wavelength": w,
                             "xyz": np.stack([np.ravel(r.x), np.ravel(r.y), np.ravel(r.z)],
                                             -1).tolist(),
                             "lmn": np.stack([np.ravel(r.L), np.ravel(r.M), np.ravel(r.N)],
                                             -1).tolist()})
        y_m, u_m = op.paraxial.marginal_ray()
        u_img = abs(float(np.ravel(u_m[-1])[0]))
        hmax = max(heights, key=lambda h: math.hypot(*h))
        out["systems"][name] = {
            "object_na": na, "object_heights": [list(h) for h in heights],
            "efl": float(op.paraxial.f2()),
            "working_fnum": 1.0 / (2.0 * u_img),
            "image_na": math.sin(math.atan(u_img)),
            "marginal_height_at_stop": abs(marginal_height_at_stop(op, s)),
            "paraxial_magnification": telecentric_magnification(op, s),
            "max_height": list(hmax),
            "rays": rays,
        }
        print(name, "NA", na, "EFL", out["systems"][name]["efl"], "Fw",
              out["systems"][name]["working_fnum"])
    OUT_JSON.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
