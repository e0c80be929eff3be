"""Reference numbers for the analyses of object-space telecentric lenses (round 42a), from
optiland 0.6.3: distortion, field curvature and the Seidel sums.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/tele42a_reference.py

It writes three object-space telecentric test lenses as .zmx files (FTYP's second value 1,
an object-NA aperture) to tests/data/tele42a/ and, for each, tests/data/tele42a/NAME.json
with optiland's numbers. optiland builds each lens from the same prescription through its
own API (``obj_space_telecentric = True``, an ``objectNA`` aperture, ``object_height``
fields, the object medium as the object surface's material), as
``tools/telecentric38a_reference.py`` does. jaxlens is not imported here.

* ``tele_doublet_exact``: round 38a's doublet + singlet, the stop moved to the exact rear
  focus of the front doublet (solved here with optiland's paraxial trace), so that
  optiland's own paraxial chief ray (through the stop's centre) is the telecentric one; the
  image surface 1.5 mm before the paraxial image (``percent_ftan`` and ``percent_paraxial``
  then differ). Paraxial magnification about −0.86.
* ``tele_immersion``: the same doublet with the object in N-BK7 (an object on a glass
  plate in immersion: n0 = 1.5168), the object distance scaled by n0, NA = n0·sin u = 0.12;
  the image surface at the paraxial image. Its stop is not at the exact focus (3e-8 mm off).
* ``tele_triplet_far``: round 38a's triplet with its object at 120 mm (three times as far:
  m ≈ −0.67), NA 0.02, the image surface at the paraxial image; 9 % distortion at 10 mm.

For each lens and the object heights ``heights`` (mm, (x, y), primary wavelength unless
named):

* distortion: the real chief ray's image point (optiland's ``trace_generic`` with the pupil
  centre: its telecentric launch is parallel to the axis) and its height along the field's
  direction; the paraxial magnification m = n0·u0/(n′·u′) (optiland's ``paraxial.trace_generic``
  of the marginal ray from the axial object point at slope tan u, u = asin(NA/n0));
  ``paraxial_height``: the paraxial ray parallel to the axis at h, its height on the image
  surface; ``percent_ftan`` = 100·(y − m·h)/(m·h), ``percent_paraxial`` against
  ``paraxial_height``.
* field curvature: the tangential and sagittal foci (mm along z from the image surface),
  where pairs of optiland real rays at pupil points ±δ·a (tangential, a the field's
  azimuth) and ±δ·a⊥ (sagittal) about the chief ray cross in the plane of their direction
  and z, at δ = 1e-3 and 5e-4, extrapolated to δ → 0 (Richardson: (4 f(δ/2) − f(δ))/3;
  the pair's focus is even in δ); every wavelength. Also optiland's own ``FieldCurvature``
  analysis (its parabasal pair at ±1e-5, 3 fields 0, h_max/2, h_max along y), as given.
* Seidel: optiland's ``ThirdOrderAberrations`` per-surface transverse terms (TSC, CC, TAC,
  TPC, DC, TAchC, TchC) and ``seidels()``, with its paraxial marginal and chief rays
  replaced by the telecentric ones (the marginal ray above; the chief ray from the largest
  height parallel to the axis, both traced by optiland's ``paraxial.trace_generic``); for
  ``tele_doublet_exact`` also with optiland's own rays unchanged (``own_rays``).
* not used: optiland's own ``Distortion`` analysis, which reads object-height fields as
  degrees (its f-tan reference is scale·tan(H·h_max·π/180), the scale from a near-axis ray):
  on ``tele_triplet_far`` it gives 1.893 % and 7.913 % at 5 and 10 mm, where its own chief
  rays and paraxial magnification give (y − m·h)/(m·h) = 2.153 % and 9.022 % (the
  difference is tan(0.1745)/0.1745 = 1.0103 at 10 "degrees").
* relative illumination (no optiland analysis exists): ``ri_open``, of the lens with its
  semi-diameters removed (every ray of the NA cone passes), from optiland's rays
  (``relative_illumination_open``: the areal magnification of the cone's centroid, by
  central differences, the cone's projected solid angle the same at every height); and
  ``ri_chief_estimate``: the cos⁴ factor of a telecentric
  lens's chief rays is 1 at every field; ``ri_chief_estimate`` is the irradiance ratio that
  the real chief-ray mapping alone implies for an unvignetted cone, the axial areal
  magnification over the local one, m0² / ((dy/dh)·(y/h)), dy/dh by second-order
  differences of optiland's chief ray (steps of 1e-4 mm). It leaves out the beam's
  centroid shift from the chief ray (coma): 1e-3 to 1e-2 from jaxlens's; not used by the
  tests, kept for orientation.
"""

import json
import math
import pathlib
import sys

import numpy as np
from optiland import optic as optic_mod
from optiland.aberrations.third_order import ThirdOrderAberrations
from optiland.analysis.field_curvature import FieldCurvature
from optiland.materials import Material

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import telecentric38a_reference as t38  # noqa: E402  (its .zmx writer)

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT_DIR = ROOT / "tests" / "data" / "tele42a"
WAVELENGTHS = t38.WAVELENGTHS
PRIMARY = WAVELENGTHS[1]

DOUBLET = [(1 / 40, 8.0, "N-SK16", False, 16), (-1 / 30, 3.0, "F2", False, 16),
           (-1 / 120, None, None, False, 16), (0.0, 15.0, None, True, 6),
           (1 / 50, 6.0, "N-BK7", False, 16), (-1 / 50, None, None, False, 16)]
TRIPLET = [(1 / 60, 5.0, "N-BK7", False, 14), (-1 / 60, 57.21356, None, False, 14),
           (0.0, 12.0, None, True, 2.5), (1 / 40, 6.0, "N-BK7", False, 12),
           (-1 / 40, 2.0, None, False, 12), (-1 / 45, 3.0, "F2", False, 12),
           (1 / 100, None, None, False, 12)]

SYSTEMS = {
    "tele_doublet_exact": dict(object_distance=60.0, medium=None, na=0.08, solve_stop=True,
                               defocus=-1.5, surfaces=DOUBLET,
                               heights=[(0.0, 0.0), (0.0, 2.0), (0.0, 5.0), (0.0, 8.0),
                                        (3.0, -4.0)]),
    "tele_immersion": dict(object_distance=60.0 * 1.5168, medium="N-BK7", na=0.12,
                           solve_stop=False, stop_gap=44.41333, defocus=0.0,
                           surfaces=DOUBLET,
                           heights=[(0.0, 0.0), (0.0, 3.0), (0.0, 6.0), (-2.0, 4.0)]),
    "tele_triplet_far": dict(object_distance=120.0, medium=None, na=0.02,
                                  solve_stop=False, defocus=0.0, surfaces=TRIPLET,
                                  heights=[(0.0, 0.0), (0.0, 5.0), (0.0, 10.0),
                                           (6.0, 8.0)]),
}


def surfaces_with(s, stop_gap, image_gap):
    """The prescription with its open gaps (None) filled: the last is the image gap, an
    earlier one the gap before the stop."""
    last = max(i for i, r in enumerate(s["surfaces"]) if r[1] is None)
    return [(c, (image_gap if i == last else stop_gap) if t is None else t, glass, stop, sd)
            for i, (c, t, glass, stop, sd) in enumerate(s["surfaces"])]


def build(s, surfaces, heights):
    op = optic_mod.Optic()
    medium = Material(s["medium"], "schott") if s["medium"] else "air"
    op.add_surface(index=0, thickness=s["object_distance"], material=medium)
    for i, (c, t, glass, stop, _) in enumerate(surfaces):
        op.add_surface(index=i + 1, radius=(1 / c if c else np.inf), thickness=t,
                       material=Material(glass, "schott") if glass else "air", is_stop=stop)
    op.add_surface(index=len(surfaces) + 1)
    op.set_aperture(aperture_type="objectNA", value=s["na"])
    op.set_field_type("object_height")
    for x, y in heights:
        op.add_field(y=y, x=x)
    for w in WAVELENGTHS:
        op.add_wavelength(value=w, is_primary=(w == PRIMARY))
    op.obj_space_telecentric = True
    return op


def n_object(s, w=PRIMARY):
    return float(np.ravel(Material(s["medium"], "schott").n(w))[0]) if s["medium"] else 1.0


def tan_u(s):
    sn = s["na"] / n_object(s)
    return sn / math.sqrt(1 - sn * sn)


def para(op, s, y, u, w=PRIMARY):
    yy, uu = op.paraxial.trace_generic(y, u, -s["object_distance"], w)
    return np.ravel(np.asarray(yy, float)), np.ravel(np.asarray(uu, float))


def solve_gaps(s):
    """The stop gap (exact rear focus of the front group, or as given) and the image gap
    (the paraxial image plus ``defocus``)."""
    stop_gap = s.get("stop_gap", 44.41333)
    probe = lambda sg, ig: build(s, surfaces_with(s, sg, ig), [(0.0, 0.0), (0.0, 1.0)])  # noqa: E731
    if s["solve_stop"]:
        # a ray parallel to the axis crosses it at the stop: y(stop) linear in the gap
        def y_stop(g):
            y, _ = para(probe(g, 30.0), s, 1.0, 0.0)
            return y[4]  # object 0, surfaces 1..3, stop 4
        a, b = y_stop(40.0), y_stop(50.0)
        stop_gap = 40.0 - a * 10.0 / (b - a)
        for _ in range(2):
            a, b = y_stop(stop_gap), y_stop(stop_gap + 1.0)
            stop_gap -= a / (b - a)
    # the paraxial image: the marginal ray's height on the image surface linear in the gap
    def y_img(g):
        y, _ = para(probe(stop_gap, g), s, 0.0, tan_u(s))
        return y[-1]
    a, b = y_img(20.0), y_img(40.0)
    g = 20.0 - a * 20.0 / (b - a)
    for _ in range(2):
        a, b = y_img(g), y_img(g + 1.0)
        g -= a / (b - a)
    return stop_gap, g + s["defocus"]


def chief(op, h, hmax, w=PRIMARY):
    r = op.trace_generic(h[0] / hmax, h[1] / hmax, np.array([0.0]), np.array([0.0]), w)
    return float(np.ravel(r.x)[0]), float(np.ravel(r.y)[0])


def azimuth(h):
    r = math.hypot(*h)
    return (0.0, 1.0) if r == 0 else (h[0] / r, h[1] / r)


def pair_focus(op, h, hmax, e, w, delta, z_img):
    """z (from the image surface) where the real rays at pupil ±δ·e cross, in the plane of
    the field's azimuth-or-perpendicular ``e`` and z."""
    px = np.array([-delta * e[0], delta * e[0]])
    py = np.array([-delta * e[1], delta * e[1]])
    r = op.trace_generic(h[0] / hmax, h[1] / hmax, px, py, w)
    x, y, z = (np.ravel(np.asarray(v, float)) for v in (r.x, r.y, r.z))
    L, M, N = (np.ravel(np.asarray(v, float)) for v in (r.L, r.M, r.N))
    p = x * e[0] + y * e[1]
    d = L * e[0] + M * e[1]
    # p0 + t0 d0 = p1 + t1 d1 and z0 + t0 N0 = z1 + t1 N1 (2-D lines in (p, z))
    a = np.array([[d[0], -d[1]], [N[0], -N[1]]])
    t = np.linalg.solve(a, np.array([p[1] - p[0], z[1] - z[0]]))
    return float(z[0] + t[0] * N[0] - z_img)


def focus(op, h, hmax, e, w, z_img, delta=1e-3):
    f1 = pair_focus(op, h, hmax, e, w, delta, z_img)
    f2 = pair_focus(op, h, hmax, e, w, delta / 2, z_img)
    return (4 * f2 - f1) / 3


def seidel_terms(op, s, rays):
    """optiland's third-order terms, its paraxial rays replaced by ``rays`` (or its own)."""
    if rays is not None:
        marginal, chief_ray = rays
        op.paraxial.marginal_ray = lambda: marginal
        op.paraxial.chief_ray = lambda: chief_ray
    ab = ThirdOrderAberrations(op)
    out = ab.third_order()
    names = ("TSC", "SC", "CC", "TCC", "TAC", "AC", "TPC", "PC", "DC", "TAchC", "LchC", "TchC")
    terms = {k: np.asarray(v, float).tolist() for k, v in zip(names, out[:-1], strict=True)}
    if rays is not None:
        del op.paraxial.marginal_ray, op.paraxial.chief_ray
    return {"transverse": {k: terms[k] for k in ("TSC", "CC", "TAC", "TPC", "DC", "TAchC",
                                                 "TchC")},
            "seidels": np.ravel(np.asarray(out[-1], float)).tolist()}


def disc_rule(n_r=24, n_phi=48):
    """Gauss–Legendre in r² and equal steps in φ over the unit disc: points and weights
    (summing to π), exact for polynomials of high degree on the disc."""
    x, w = np.polynomial.legendre.leggauss(n_r)
    r = np.sqrt(0.5 * (x + 1.0))  # r² uniform on [0, 1]: r dr = d(r²)/2
    phi = 2 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    R, P = np.meshgrid(r, phi, indexing="ij")
    W = np.repeat(0.5 * w[:, None], n_phi, 1) * (2 * np.pi / n_phi) * 0.5
    return R * np.cos(P), R * np.sin(P), W


def relative_illumination_open(s, surfaces, heights, hmax, step=1e-3):
    """The relative illumination of the lens without semi-diameters (every ray of the NA
    cone passes): E = Ω_p / |det ∂c/∂X|, Ω_p the same at every field (the cone is the same
    set of slopes), c the cos⁴γ-weighted centroid of the cone's rays on the image surface
    (optiland rays at a Gauss rule over the pupil disc: slopes (Px, Py)·tan u), ∂c/∂X by
    central differences of ±``step`` mm in x and y. Returns E(h)/E(0) per height."""
    top = hmax + 4 * step  # the optic's largest field: normalised heights stay within 1
    extra = [(0.0, top)]
    op = build(s, surfaces, list(heights) + extra)
    px, py, wt = disc_rule()
    px, py, wt = px.ravel(), py.ravel(), wt.ravel()
    tu = tan_u(s)
    cos4 = 1.0 / (1.0 + tu * tu * (px * px + py * py)) ** 2
    w = wt * cos4

    def centroid(x, y):
        r = op.trace_generic(x / top, y / top, px, py, PRIMARY)
        rx, ry = np.ravel(np.asarray(r.x, float)), np.ravel(np.asarray(r.y, float))
        return np.array([np.sum(w * rx), np.sum(w * ry)]) / np.sum(w)

    def det(x, y):
        jx = (centroid(x + step, y) - centroid(x - step, y)) / (2 * step)
        jy = (centroid(x, y + step) - centroid(x, y - step)) / (2 * step)
        return abs(jx[0] * jy[1] - jx[1] * jy[0])

    d0 = det(0.0, 0.0)
    return [float(d0 / det(x, y)) for x, y in heights]


def main() -> None:
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    for name, s in SYSTEMS.items():
        stop_gap, image_gap = (float(g) for g in solve_gaps(s))
        surfaces = surfaces_with(s, stop_gap, image_gap)
        heights = s["heights"]
        hmax = max(math.hypot(*h) for h in heights)
        spec = dict(object_distance=s["object_distance"], aperture=("OBNA", s["na"], 0),
                    ftyp=1, fields=heights, surfaces=surfaces)
        text = t38.zmx_text(name, spec).replace("telecentric38a_reference", "tele42a_reference")
        if s["medium"]:  # the object surface's glass
            text = text.replace(f"  DISZ {s['object_distance']!r}\n",
                                f"  DISZ {s['object_distance']!r}\n  GLAS {s['medium']}\n", 1)
        (OUT_DIR / f"{name}.zmx").write_text(text, encoding="utf-8")
        op = build(s, surfaces, heights)
        n0 = n_object(s)
        tu = tan_u(s)
        ym, um = para(op, s, 0.0, tu)
        n_img = 1.0
        m = n0 * tu / (n_img * um[-1])
        z_img = float(np.sum([r[1] for r in surfaces]))
        dist = []
        for h in heights:
            a = azimuth(h)
            r = math.hypot(*h)
            xy = chief(op, h, hmax)
            y = xy[0] * a[0] + xy[1] * a[1]
            ypar = para(op, s, r, 0.0)[0][-1]
            dist.append(dict(height=list(h), chief_xy=list(xy), chief_height=y,
                             ideal=m * r, paraxial_height=float(ypar),
                             percent_ftan=(100 * (y - m * r) / (m * r)) if r else 0.0,
                             percent_paraxial=(100 * (y - ypar) / ypar) if r else 0.0))
        fc = {"heights": [list(h) for h in heights], "wavelengths": list(WAVELENGTHS),
              "tangential": [], "sagittal": []}
        for w in WAVELENGTHS:
            tan_row, sag_row = [], []
            for h in heights:
                a = azimuth(h)
                tan_row.append(focus(op, h, hmax, a, w, z_img))
                sag_row.append(focus(op, h, hmax, (a[1], -a[0]), w, z_img))
            fc["tangential"].append(tan_row)
            fc["sagittal"].append(sag_row)
        # optiland's own FieldCurvature at 0, hmax/2, hmax along y (its fields' max_field)
        yfields = [(0.0, 0.0), (0.0, hmax / 2), (0.0, hmax)]
        op_y = build(s, surfaces, yfields)
        own = FieldCurvature(op_y, wavelengths=[PRIMARY], num_points=3).data[0]
        fc_optiland = {"heights": [list(h) for h in yfields], "wavelength": PRIMARY,
                       "tangential": np.ravel(np.asarray(own[0], float)).tolist(),
                       "sagittal": np.ravel(np.asarray(own[1], float)).tolist()}
        # Seidel at the largest height along y
        marg = op.paraxial.trace_generic(0.0, tu, -s["object_distance"], PRIMARY)
        chf = op.paraxial.trace_generic(hmax, 0.0, -s["object_distance"], PRIMARY)
        seidel = {"field": hmax, "telecentric_rays": seidel_terms(build(s, surfaces, [
            (0.0, 0.0), (0.0, hmax)]), s, (marg, chf)), "image_u": float(um[-1])}
        if s["solve_stop"]:
            seidel["own_rays"] = seidel_terms(build(s, surfaces, [(0.0, 0.0), (0.0, hmax)]),
                                              s, None)
        ri_open = relative_illumination_open(s, surfaces, heights, hmax)
        # chief-ray estimate of the relative illumination (see the module notes)
        ri = []
        for h in heights:
            r = math.hypot(*h)
            if r == 0:
                ri.append(1.0)
                continue
            a = azimuth(h)
            step = 1e-4

            def yr(rr, a=a, op=op, hmax=hmax):
                xy = chief(op, (a[0] * rr, a[1] * rr), hmax)
                return xy[0] * a[0] + xy[1] * a[1]
            # second-order backward difference (optiland refuses |H| > 1 beyond h_max)
            dy = (3 * yr(r) - 4 * yr(r - step) + yr(r - 2 * step)) / (2 * step)
            d0 = (yr(step) - yr(-step)) / (2 * step)
            ri.append(float(d0 * d0 / (dy * yr(r) / r)))
        out = {"source": "optiland 0.6.3 (tools/tele42a_reference.py)", "name": name,
               "zmx": f"{name}.zmx", "object_na": s["na"], "object_medium": s["medium"],
               "object_index": n0, "tan_u": tu, "stop_gap": stop_gap,
               "image_gap": image_gap, "paraxial_magnification": m,
               "optiland_magnification": float(np.ravel(op.paraxial.magnification())[0])
               if s["solve_stop"] else None,
               "wavelengths_um": list(WAVELENGTHS), "primary_um": PRIMARY,
               "distortion": dist, "field_curvature": fc,
               "field_curvature_optiland_analysis": fc_optiland, "seidel": seidel,
               "ri_chief_estimate": {"heights": [list(h) for h in heights], "ri": ri},
               "ri_open": {"heights": [list(h) for h in heights], "ri": ri_open}}
        (OUT_DIR / f"{name}.json").write_text(json.dumps(out, indent=1) + "\n")
        print(name, "m", m, "stop gap", stop_gap, "image gap", image_gap,
              "dist %", [round(d["percent_ftan"], 6) for d in dist])


if __name__ == "__main__":
    main()
