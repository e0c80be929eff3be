"""Reference relative illumination (round 43c) from optiland 0.6.3's real rays, for
tests/test_radiometry_round43c.py.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/ri43c_reference.py

optiland 0.6.3 has no relative-illumination analysis, so this script computes the irradiance
at the image of each field from optiland's traced rays, in a form that shares nothing with
jaxlens's method but the radiometry (jaxlens works in tangents with a cos⁴ factor, on a star-
shaped polygon of the pupil plane; this works in direction cosines, on optiland's own pupil
coordinates with its own ray aiming). For an object of uniform radiance L:

* object at infinity: a field's beam is a set of parallel rays of direction cosines
  (L0, M0); the flux it carries is L·A·dL0·dM0, A its cross-section on a plane z = const
  (cos θ·dΩ = dL0·dM0). A = Σ |det ∂(x, y)/∂(Px, Py)|·ΔP over the pupil points (Px, Py)
  whose rays reach the image, (x, y) the ray's crossing of the plane of surface 1's vertex,
  the Jacobian by central differences in (Px, Py) (δ = 1e-4; constant, EPD²/4, under
  paraxial aiming; varying under optiland's ray aiming).
* object at a finite distance (object heights): a patch dA_o sends L·Ω_p·dA_o, where
  Ω_p = Σ |det ∂(L, M)/∂(Px, Py)|·ΔP is the projected solid angle of the rays that reach the
  image (cos γ·dΩ = dL·dM), whatever the sign of the object distance (a virtual object's
  converging beam the same way).
* the image of the patch: the flux-weighted centroid x̄ of the passing rays on the image
  surface; its Jacobian by central differences in the normalised field (Hx, Hy), divided
  by that of (L0, M0) or of the object point (X, Y), with the passing set held at the
  rays that pass in all five traces. E = A / |det ∂x̄/∂(L0, M0)| or Ω_p / |det ∂x̄/∂(X, Y)|;
  the relative illumination is E over its value on the axis.

The pupil: optiland's unit circle of normalised pupil coordinates (Px² + Py² <= 1), i.e. the
EPD's disc on the paraxial entrance pupil's plane (paraxial aiming, ``aim: "paraxial"``) or
the stop's disc of the real marginal ray's height (optiland's ``robust`` aiming,
``aim: "real_marginal"``: Zemax's "Real" ray aiming, jaxlens's ``Lens.aim="real_marginal"``).
Sampling: K rings × J spokes of equal area in (Px, Py) (cell centres at ρ = sqrt((k + ½)/K),
φ = 2π(j + ½)/J; each ray stands for the area π/(K·J) of the unit disc), so the unvignetted
pupil's area is exact; where a spoke's rays change from passing to failing between two
rings, bisection along the spoke finds the edge and the ring cells' area is moved to it
(``edge_correction``), so a vignetting or stop edge costs O(1/J²) of the area, not O(1/K).

Each lens is written to tests/data/ri43c/NAME.zmx (surfaces with ``CLAP`` circular
apertures, which both programs clip at; the image surface at optiland's paraxial image,
``image_solve``), and tests/data/ri43c/ri43c_optiland.json holds, per lens, the fields
(angles in degrees: atan(M0/N0), atan(L0/N0) of optiland's launched direction; or the
object point, mm) and the relative illumination.

The lenses:

* ``triplet_stopwide``: a Cooke triplet (f ≈ 50 mm, EPD 10), stop in the air space after
  the negative lens with a clear aperture of 6 mm, wider than the EPD's beam there (about
  4.2 mm): the EPD, not the stop, is the aperture; the first and last lenses clip the
  oblique beams (vignetting). Fields 0–20°.
* ``triplet_stopsmall``: the same with the stop's aperture 3.4 mm, smaller than the EPD's
  beam: the stop clips every field's beam (the working beam, analysis/stop_clip.py).
* ``triplet_finite``: the wide-stop triplet with its object 300 mm in front (object heights
  to 90 mm, about 16°).
* ``converging_virtual``: a doublet fed by a converging beam whose virtual object lies
  60 mm behind surface 1 (object distance −60 mm; object heights to 14 mm), the stop at
  surface 1 wider than the EPD's beam.
* ``landscape_wide``: a landscape lens (a meniscus 6 mm behind a front stop, EPD 4,
  f ≈ 116 mm), fields to 65°, the meniscus's front aperture (14 mm) vignetting the widest.
* ``laikin_real``: Laikin's 100° wide-angle lens (tests/data/zmx/
  optiland_circular_aperture_example_with_aperture.zmx, inches), a retrofocus lens with
  strong pupil distortion, fields 0–49.5°, with optiland's ``robust`` ray aiming.
* ``laikin_paraxial``: ``laikin_real`` under paraxial aiming (the same file; the EPD's disc
  on the paraxial pupil plane, which the real rays' pupil distortion makes a different beam:
  past about 38° none of its rays reaches the image), fields 0–35°.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "tests", "data", "ri43c")
LAIKIN = os.path.join(ROOT, "tests", "data", "zmx",
                      "optiland_circular_aperture_example_with_aperture.zmx")
WL = 0.5875618
K_RINGS, J_SPOKES = 160, 320
D_PUPIL, D_FIELD = 1e-4, 1e-3
BISECT = 20
FIELD_MARGIN = 1.02
"""The written lens's largest field is this times the largest one evaluated (optiland refuses
normalised fields past 1, which the central differences at the largest field would need)."""

# (curvature 1/mm, thickness after mm, glass or "", clear semi-aperture mm or None, stop)
TRIPLET = [
    (1 / 21.48, 2.0, "N-SK16", 6.2, False),
    (-1 / 124.1, 5.26, "", 6.2, False),
    (-1 / 19.1, 1.25, "N-F2", 5.0, False),
    (1 / 22.0, 1.5, "", 5.0, False),
    (0.0, 3.19, "", 6.0, True),
    (1 / 328.9, 2.25, "N-SK16", 6.0, False),
    (-1 / 16.7, 40.0, "", 6.0, False),
]
DOUBLET = [
    (1 / 40.0, 5.0, "N-BK7", 12.0, True),
    (-1 / 30.0, 2.0, "N-F2", 12.0, False),
    (-1 / 90.0, 20.0, "", 12.0, False),
]
LANDSCAPE = [
    (0.0, 6.0, "", 10.0, True),
    (-1 / 30.0, 4.0, "N-BK7", 14.0, False),
    (-1 / 20.0, 110.0, "", 19.0, False),
]


def with_stop(surfs, r):
    return [(c, t, g, r if s else a, s) for c, t, g, a, s in surfs]


LENSES = {
    "triplet_stopwide": dict(surfs=TRIPLET, epd=10.0, obj=None, fields=[0, 5, 10, 14, 17, 20],
                             aim="paraxial"),
    "triplet_stopsmall": dict(surfs=with_stop(TRIPLET, 3.4), epd=10.0, obj=None,
                              fields=[0, 5, 10, 14, 17, 20], aim="paraxial"),
    "triplet_finite": dict(surfs=TRIPLET, epd=10.0, obj=300.0, fields=[0, 30, 60, 75, 90],
                           aim="paraxial"),
    "converging_virtual": dict(surfs=DOUBLET, epd=8.0, obj=-60.0, fields=[0, 4, 8, 11, 14],
                               aim="paraxial"),
    "landscape_wide": dict(surfs=LANDSCAPE, epd=4.0, obj=None,
                           fields=[0, 20, 35, 45, 55, 60, 65], aim="paraxial"),
}
FILE_LENSES = {
    "laikin_real": dict(file=LAIKIN, fields=[0, 15, 25, 35, 42, 49.5], aim="real_marginal"),
    "laikin_paraxial": dict(file=LAIKIN, fields=[0, 10, 15, 20, 25, 30, 35], aim="paraxial"),
}


def zmx_text(name, spec, image_gap):
    """The lens as a Zemax .zmx file (mm; one wavelength; CLAP and DIAM on every surface)."""
    obj = spec["obj"]
    fields = list(spec["fields"]) + [FIELD_MARGIN * max(spec["fields"])]
    lines = ["VERS 190513 80 123457 L123457", "MODE SEQ", f"NAME {name}",
             "NOTE 0 Written by tools/ri43c_reference.py (relative illumination, round 43c)",
             "UNIT MM X W X CM MR CPMM", f"ENPD {spec['epd']!r}", "ENVD 2.0E+1 1 0",
             "GFAC 0 0", "GCAT SCHOTT",
             f"FTYP {0 if obj is None else 1} 0 {len(fields)} 1 0 0 0",
             "XFLN " + " ".join("0.0" for _ in fields),
             "YFLN " + " ".join(repr(float(f)) for f in fields),
             "FWGN " + " ".join("1" for _ in fields),
             f"WAVM 1 {WL!r} 1", "PWAV 1",
             "SURF 0", "  TYPE STANDARD", "  CURV 0.0",
             f"  DISZ {'INFINITY' if obj is None else repr(float(obj))}"]
    n = len(spec["surfs"])
    for i, (c, t, g, a, stop) in enumerate(spec["surfs"], 1):
        lines += [f"SURF {i}"] + (["  STOP"] if stop else []) + [
            "  TYPE STANDARD", f"  CURV {c!r}",
            f"  DISZ {image_gap!r}" if i == n else f"  DISZ {t!r}"]
        if g:
            lines.append(f"  GLAS {g}")
        if a is not None:
            lines += [f"  DIAM {a!r} 1 0 0 1 \"\"", f"  CLAP 0 {a!r} 0"]
    lines += [f"SURF {n + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0"]
    return "\n".join(lines) + "\n"


def load(path, aim):
    from optiland.fileio import load_zemax_file

    op = load_zemax_file(path)
    if aim == "real_marginal":
        op.ray_tracer.set_aiming("robust")
    else:
        op.ray_tracer.set_aiming("paraxial")
    return op


def write_lens(name, spec):
    """Write the .zmx with the image at optiland's paraxial image; return its path."""
    path = os.path.join(OUT, name + ".zmx")
    with open(path, "w") as f:
        f.write(zmx_text(name, spec, spec["surfs"][-1][1]))
    op = load(path, "paraxial")
    op.image_solve()
    gap = float(op.surfaces[-2].thickness)
    with open(path, "w") as f:
        f.write(zmx_text(name, spec, gap))
    return path


def pupil_points():
    k = (np.arange(K_RINGS) + 0.5) / K_RINGS
    phi = 2 * np.pi * (np.arange(J_SPOKES) + 0.5) / J_SPOKES
    rho = np.sqrt(k)[:, None]
    return (rho * np.cos(phi)).ravel(), (rho * np.sin(phi)).ravel(), math.pi / (K_RINGS * J_SPOKES)


def trace(op, hx, hy, px, py):
    """Image (x, y), pass mask, launch directions (L, M), launch points (x, y) on the plane of
    surface 1's vertex (infinite object) or the object point (finite)."""
    op.trace_generic(hx, hy, px, py, WL)
    sg = op.surface_group
    ok = np.asarray(sg.intensity[-1]) > 0 if hasattr(sg, "intensity") else None
    x, y, z = (np.asarray(v) for v in (sg.x, sg.y, sg.z))
    L, M, N = (np.asarray(v) for v in (sg.L, sg.M, sg.N))
    if ok is None:
        ok = np.asarray(op.surface_group.i[-1]) > 0
    ok = ok & np.isfinite(x[-1]) & np.isfinite(y[-1])
    # the incoming direction: recorded on the object surface (index 0)
    l0, m0, n0 = L[0], M[0], N[0]
    z1 = float(np.asarray(op.surfaces[1].geometry.cs.z))
    s = (z1 - z[1]) / n0
    plane = np.stack([x[1] + l0 * s, y[1] + m0 * s], -1)
    return dict(img=np.stack([x[-1], y[-1]], -1), ok=ok, lm=np.stack([l0, m0], -1),
                plane=plane, obj=np.stack([x[0], y[0]], -1))


def beam(op, hx, hy, finite):
    """One field's beam: its pupil measure (see the module notes) and the measure-weighted
    centroid of its rays on the image surface, over the rays that pass for this field; where
    a spoke's rays change from passing to failing between two rings, bisection along the
    spoke (``BISECT`` steps in u = ρ²) finds the edge and the ring cells' share moves to it
    (the cell of sample k covers u in [k/K, (k + 1)/K]; the area element is π·du/J), with
    the landing point of the edge ray."""
    px, py, dp = pupil_points()
    key = "lm" if finite else "plane"

    def measure(qx, qy):
        ax = trace(op, hx, hy, qx + D_PUPIL, qy)[key] - trace(op, hx, hy, qx - D_PUPIL, qy)[key]
        ay = trace(op, hx, hy, qx, qy + D_PUPIL)[key] - trace(op, hx, hy, qx, qy - D_PUPIL)[key]
        return np.abs(ax[:, 0] * ay[:, 1] - ax[:, 1] * ay[:, 0]) / (2 * D_PUPIL) ** 2

    c = trace(op, hx, hy, px, py)
    jac = measure(px, py)
    w = np.where(c["ok"], jac * dp, 0.0)
    tot, mom = np.sum(w), np.sum(w[:, None] * np.nan_to_num(c["img"]), 0)
    okg = c["ok"].reshape(K_RINGS, J_SPOKES)
    kk, jj = np.nonzero(okg[:-1] != okg[1:])
    if kk.size:
        first = okg[kk, jj]
        lo, hi = (kk + 0.5) / K_RINGS, (kk + 1.5) / K_RINGS
        phi = 2 * np.pi * (jj + 0.5) / J_SPOKES
        for _ in range(BISECT):
            mid = 0.5 * (lo + hi)
            rho = np.sqrt(mid)
            same = trace(op, hx, hy, rho * np.cos(phi), rho * np.sin(phi))["ok"] == first
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        u = np.where(first, lo, hi)  # the last passing point
        rho = np.sqrt(u)
        ex, ey = rho * np.cos(phi), rho * np.sin(phi)
        edge_img = trace(op, hx, hy, ex, ey)["img"]
        jg = jac.reshape(K_RINGS, J_SPOKES)
        cell = (kk + 1) / K_RINGS
        corr = np.where(first, (u - cell) * jg[kk, jj], (cell - u) * jg[kk + 1, jj])
        corr = corr * np.pi / J_SPOKES
        tot = tot + np.sum(corr)
        mom = mom + np.sum(corr[:, None] * edge_img, 0)
    return float(tot), mom / tot, c


def irradiance(op, hy, finite):
    """E for the field (0, hy): the pupil measure over |det ∂x̄/∂(L0, M0)| (infinity) or
    |det ∂x̄/∂(X, Y)| (finite), x̄ each field's own centroid (its own passing rays), by
    central differences in the normalised field."""
    meas, cen, c = beam(op, 0.0, hy, finite)
    fkey = "obj" if finite else "lm"
    one = (np.zeros(1), np.zeros(1))
    st = {}
    for name, (dx, dy) in {"x+": (D_FIELD, 0), "x-": (-D_FIELD, 0), "y+": (0, D_FIELD),
                           "y-": (0, -D_FIELD)}.items():
        st[name] = (beam(op, dx, hy + dy, finite)[1], trace(op, dx, hy + dy, *one)[fkey][0])
    di = np.stack([st["x+"][0] - st["x-"][0], st["y+"][0] - st["y-"][0]], 1)
    ds = np.stack([st["x+"][1] - st["x-"][1], st["y+"][1] - st["y-"][1]], 1)
    det = abs(np.linalg.det(di)) / abs(np.linalg.det(ds))
    chief = trace(op, 0.0, hy, *one)
    return meas / det, meas, None, chief, cen


def run_lens(name, op, fields, finite, aim, path, fmax):
    out = dict(file=os.path.relpath(path, ROOT), aim=aim, finite=finite, fields=[], ri=[],
               irradiance=[], pupil_measure=[], image_xy=[], wavelength_um=WL)
    e0 = None
    for f in fields:
        e, meas, _, chief, c = irradiance(op, f / fmax if fmax else 0.0, finite)
        if finite:
            fld = [float(v) for v in chief["obj"][0]]
        else:
            lm = chief["lm"][0]
            n = math.sqrt(max(0.0, 1 - lm[0] ** 2 - lm[1] ** 2))
            fld = [math.degrees(math.atan2(lm[0], n)), math.degrees(math.atan2(lm[1], n))]
        e0 = e if e0 is None else e0
        out["fields"].append(fld)
        out["irradiance"].append(e)
        out["ri"].append(e / e0)
        out["pupil_measure"].append(meas)
        out["image_xy"].append([float(v) for v in c])
        print(f"{name:20s} field {fld} ri {e / e0:.6f}", flush=True)
    return out


def main() -> None:
    os.makedirs(OUT, exist_ok=True)
    data = {}
    for name, spec in LENSES.items():
        path = write_lens(name, spec)
        op = load(path, spec["aim"])
        data[name] = run_lens(name, op, spec["fields"], spec["obj"] is not None, spec["aim"],
                              path, FIELD_MARGIN * max(spec["fields"]))
    for name, spec in FILE_LENSES.items():
        path = spec["file"]
        op = load(path, spec["aim"])
        # the file's fields are 0, 35 and 50°: normalised by 50°
        data[name] = run_lens(name, op, spec["fields"], False, spec["aim"], path, 50.0)
    data["_about"] = ("optiland 0.6.3 rays; see tools/ri43c_reference.py: K rings x J spokes "
                      f"= {K_RINGS} x {J_SPOKES}, edges bisected, central differences "
                      f"{D_PUPIL} (pupil), "
                      f"{D_FIELD} (normalised field)")
    with open(os.path.join(OUT, "ri43c_optiland.json"), "w") as f:
        json.dump(data, f, indent=1)


if __name__ == "__main__":
    main()
