"""Round 41c reference writer: random lenses of the classes rounds 36b/37b did not draw
(object-space telecentric, immersed telecentric objects, virtual objects, afocal image
space), traced by optiland 0.6.3 with its own ray generation.

Run with the optiland venv, never jaxlens's (jaxlens is not imported here)::

    /work/optenv/bin/python tools/fuzz41c_reference.py OUT_FOLDER [--n 32] [--seed 41]
        [--kind telecentric|telecentric_immersion|virtual|afocal|all]

and compare jaxlens with what it writes with ``tools/fuzz41c_compare.py`` (jaxlens's venv).

The prescriptions are drawn as ``tools/fuzz36b_reference.py`` draws them (its
``draw_system``, ``add_aspheres`` and ``Case``, reused: spheres, conics, even aspheres
A2..A12, Cauchy crowns / flints / plastics given as index tables, cemented pairs, glass
image space, curved image surfaces), then turned into one of the classes:

* ``telecentric``: a finite object (1.5 to 25 length scales away); optiland's optic gets an
  ``objectNA`` aperture (NA = n0 sin u, the cone filling 0.5 to 1.2 times the drawn EPD's
  radius on surface 1), ``object_height`` fields (0, 0.6 h, h on y and (0.6 h, -0.8 h)) and
  ``obj_space_telecentric = True``; h is halved from 0.05 to 0.4 length scales until every
  stored ray passes. jaxlens: ``Lens(object_na=NA)``, fields (x, y) heights.
* ``telecentric_immersion``: the same with an object-space medium (an index table of
  n_d 1.33 to 1.52, a water or oil like Cauchy law) set as optiland's object surface
  ``material_post`` (``updater.set_material``, with ``updater.set_thickness`` for its
  distance: setting ``surfaces[0].thickness`` leaves optiland's object where it was); the
  object distance d in it is drawn so that d / n0 is the air distance the image was solved
  for (the reduced distance: the paraxial image lies where
  it would for d / n0 in air). NA = n0 sin u.
* ``virtual``: a negative object distance (the object point after surface 1, the object
  space beam converging on it), fields as angles at the paraxial entrance pupil, EPD
  aperture; the object 0.2 to 3 length scales after surface 1, or (40 % of the draws: the
  stop moved to the last surface, and where the entrance pupil then lies 0.05 length scale
  or more after surface 1) 0.1 to 0.6 of the way to the pupil, so that the pupil lies
  before or behind the object point, 0.02 length scale or more from it (``make_case``).
  tests/data/fuzz41c adds draws 56 to 79 of ``--kind virtual`` (summary_virtual_56_79.json):
  the default run gave one draw with the pupil behind the object point.
* ``afocal``: an object at infinity; the last refracting surface's curvature is solved so
  that the paraxial marginal ray leaves parallel to the axis (Zemax's "afocal image space"),
  the image surface a plane 0.3 to 2 length scales behind the last vertex, air after the
  lens. jaxlens: ``Lens(afocal_image=True)``.

No surface has an A2 term (r² in the sag polynomial; rounds 36b/37b draw it): optiland
0.6.3's paraxial engine leaves A2 out of a surface's power (its ``f2``, ``EPL`` and paraxial
magnification), and its ray generation for an EPD aperture aims at that ``EPL``, so a lens
with A2 before the stop would get rays through a different pupil. jaxlens takes the paraxial
curvature as c + 2·A2 (the sag's r² coefficient is c/2 + A2), which is right: fuzz36b checks
its in-script y-nu trace with A2 folded in against optiland on a copy whose curvatures carry
A2, and ``fuzz41c_reference.py check-a2`` shows optiland's own real near-axis ray focusing
where c + 2·A2 puts it (f 48.4913 mm), not at its paraxial f2 (60.3286 mm). Drawn with
A2, 6 of 33 cases differed by this alone (EFL by up to 8x relative, rays by up to 4 mm),
each with A2 on a surface before the stop or in the paraxial data.

For each case: optiland's ``trace_generic`` (its own ray generation from the normalised
field and pupil coordinates) at 8 pupil points (fuzz36b's ``PUPIL``), every field and
wavelength, the image-surface intercept and direction cosines; paraxial data: optiland's
``f2`` (image-space focal length) and, by class, the paraxial magnification of a 1 mm object
height (telecentric), the entrance pupil position (virtual), the paraxial angular
magnification u'/u (afocal, from the in-script y-nu trace of fuzz36b). A draw is refused
(counted by reason in ``summary.json``) when a stored ray fails in optiland (NaN, total
internal reflection, backward between surfaces, an intercept off the sheet of the surface
through its vertex: ``on_vertex_sheet``), when a curvature exceeds 20 / length scale (the
solved last power can be absurd: a 0.011 mm radius hyperboloid whose far sheet optiland
met, where jaxlens, with ``negative_propagation``, went back to the vertex sheet) or the
Newton iteration of an asphere does not converge to 1e-12.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import platform
import sys
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import fuzz36b_reference as f36  # noqa: E402  (optiland is imported there)

KINDS = ("telecentric", "telecentric_immersion", "virtual", "afocal")
# the 8 pupil points of fuzz36b's real rays
PUPIL = f36.PUPIL


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:  # noqa: BLE001
        return None


def trace_generic(case, hx, hy, w):
    """optiland's own rays of normalised field (hx, hy) at PUPIL, wavelength w (nm):
    image data [N, 6]; refused when a ray fails."""
    op = case.op
    px = np.array([p[0] for p in PUPIL])
    py = np.array([p[1] for p in PUPIL])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = op.trace_generic(hx, hy, px, py, w / 1000.0)
    newton = [str(c.message) for c in caught if "converge" in str(c.message).lower()]
    if newton:
        raise f36.Refused("optiland_newton", newton[0][:120])
    out = np.stack([np.ravel(np.asarray(v)) for v in (r.x, r.y, r.z, r.L, r.M, r.N)], 1)
    if not np.all(np.isfinite(out)):
        raise f36.Refused("miss_or_tir", f"field {hx, hy} wl {w}")
    sg = op.surface_group
    z = np.asarray(sg.z)[1:]  # surfaces 1 .. image
    if not np.all(np.isfinite(z)) or np.any(np.diff(z, axis=0) <= 0):
        raise f36.Refused("backward", f"field {hx, hy} wl {w}")
    on_vertex_sheet(case, np.asarray(sg.x)[1:], np.asarray(sg.y)[1:], z, f"field {hx, hy} wl {w}")
    return out


def on_vertex_sheet(case, x, y, z, what):
    """Refuse a draw where a ray meets a surface away from the sheet through its vertex (a
    hyperboloid's far sheet, or a root the sag formula does not give): the sag formula
    c r² / (1 + sqrt(1 - (1 + k) c² r²)) + sum A_2j r^2j describes that sheet only."""
    rows = case.s["rows"]
    shapes = [(case.curv[i], r["k"], r["co"]) for i, r in enumerate(rows)]
    shapes.append((case.img["c"], case.img["k"], []))
    for i, (c, k, co) in enumerate(shapes):
        r2 = x[i] ** 2 + y[i] ** 2
        root = 1.0 - (1.0 + k) * c * c * r2
        if np.any(root < 0):
            raise f36.Refused("off_vertex_sheet", f"{what}: surface {i + 1} beyond its rim")
        sag = c * r2 / (1.0 + np.sqrt(root)) + sum(a * r2 ** (j + 1) for j, a in enumerate(co))
        if not np.all(np.abs(z[i] - case.z_v[i] - sag) <= 1e-7 * max(1.0, case.s["L"])):
            raise f36.Refused("off_vertex_sheet", f"{what}: surface {i + 1}")


def set_fields(op, kind, fields):
    op.fields.fields.clear()
    op.set_field_type("object_height" if kind.startswith("telecentric") else "angle")
    for f in fields:
        x, y = (f if isinstance(f, (list, tuple)) else (0.0, f))
        op.add_field(y=y, x=x)


def field_list(kind, top):
    if kind.startswith("telecentric"):
        return [(0.0, 0.0), (0.0, 0.6 * top), (0.0, top), (0.6 * top, -0.8 * top)]
    return [0.0, 0.6 * top, top]


def norm_field(kind, f, top):
    if kind.startswith("telecentric"):
        return f[0] / top, f[1] / top
    return 0.0, f / top


def all_rays(case, kind, fields, top):
    rows = []
    for f in fields:
        hx, hy = norm_field(kind, f, top)
        for w in case.wls:
            out = trace_generic(case, hx, hy, w)
            for k, (px, py) in enumerate(PUPIL):
                rows.append(
                    dict(
                        field=list(f) if isinstance(f, tuple) else f,
                        Hx=hx,
                        Hy=hy,
                        Px=px,
                        Py=py,
                        wavelength_nm=w,
                        image=dict(zip("x y z L M N".split(), map(float, out[k]), strict=True)),
                    )
                )
    return rows


def fit(case, kind, start):
    """The largest field (degrees or mm) halved from ``start`` until every ray passes."""
    top, last = start, None
    for _ in range(6):
        fields = field_list(kind, top)
        set_fields(case.op, kind, fields)
        try:
            return top, fields, all_rays(case, kind, fields, top)
        except f36.Refused as e:
            last = e
            top /= 2
    raise last


def solve_afocal(case):
    """The paraxial curvature of the last refracting surface that makes the marginal ray of
    an object at infinity leave parallel to the axis (nu = 0 after the lens)."""
    rows, n = case.s["rows"], [1.0] + case.n_after[case.prim]
    j = [i for i in range(case.m) if n[i + 1] != n[i]][-1]
    gaps = case.thick[:-1]

    def nu(cj):
        pc = list(case.pcurv)
        pc[j] = cj
        return f36.paraxial(pc, gaps, case.n_after[case.prim], case.stop, f36.INF)["nu_last"]

    e, f = nu(0.0), nu(1.0) - nu(0.0)
    if f == 0:
        raise f36.Refused("no_afocal_solution", "")
    cj = -e / f
    a2 = rows[j]["co"][0] if rows[j]["co"] else 0.0
    rows[j]["c"] = cj - 2 * a2
    case.curv[j], case.pcurv[j] = rows[j]["c"], cj
    if abs(cj) > 5.0 / case.s["L"]:
        raise f36.Refused("no_afocal_solution", f"curvature {cj:.3g} too strong")


def make_case(sys_, defocus):
    """fuzz36b's ``Case``; for a virtual object (negative distance) without its
    ``object_behind_pupil`` refusal (written for real objects: a virtual object may lie on
    either side of the entrance pupil), which is replaced by one that keeps the entrance
    pupil 0.02 length scale or more from the object point (the chief ray's angle there
    defines the field)."""
    if sys_["dist"] == f36.INF or sys_["dist"] > 0:
        return f36.Case(sys_, defocus)
    real = f36.paraxial

    def far_pupil(*a, **k):
        p = real(*a, **k)
        return dict(p, z_ep=math.inf)  # only Case's check reads it while it is set up

    f36.paraxial = far_pupil
    try:
        case = f36.Case(sys_, defocus)
    finally:
        f36.paraxial = real
    gaps = case.thick[:-1]
    case.p = real(case.pcurv, gaps, case.n_after[case.prim], case.stop, sys_["dist"])
    case.z_ep = case.p["z_ep"]
    if not abs(sys_["dist"] + case.z_ep) >= 0.02 * sys_["L"]:
        raise f36.Refused("object_at_pupil", f"d {sys_['dist']:.4g} z_ep {case.z_ep:.4g}")
    return case


def build(idx, seed, kind):
    t0 = time.time()
    rng = np.random.default_rng([seed, idx])
    sys_ = f36.draw_system(rng)
    sys_["after_image"] = None  # image space ends on the image surface
    L = sys_["L"]
    n0 = 1.0
    if kind.startswith("telecentric"):
        sys_["dist"] = float(rng.uniform(1.5, 25.0) * L)
    elif kind == "virtual":
        # 40 %: between surface 1 and an entrance pupil inside the lens (where it has one)
        rows, ip = sys_["rows"], sys_["wls"].index(sys_["prim"])
        near = rng.random() < 0.4
        if near:  # the stop on the last surface: an entrance pupil deep in the lens
            for r in rows:
                r["stop"] = False
            rows[-1]["stop"] = True
        z_ep = f36.paraxial(
            [r["c"] for r in rows], [r["gap"] for r in rows[:-1]],
            [r["after"]["n"][ip] if r["after"] is not f36.AIR else 1.0 for r in rows],
            next(i for i, r in enumerate(rows) if r["stop"]), f36.INF)["z_ep"]
        if near and z_ep > 0.05 * L:
            sys_["dist"] = -float(rng.uniform(0.1, 0.6) * z_ep)
        else:
            sys_["dist"] = -float(rng.uniform(0.2, 3.0) * L)
    else:
        sys_["dist"] = f36.INF
    if kind == "afocal":
        sys_["rows"][-1]["after"] = f36.AIR  # air after the lens
        sys_["img"] = dict(c=0.0, k=0.0)
    f36.add_aspheres(rng, sys_)
    for r in sys_["rows"]:  # no A2 (see the module notes): optiland's paraxial data ignore it
        if r["co"]:
            r["co"][0] = 0.0
    defocus = float(rng.uniform(-0.01, 0.01) * L)
    try:
        case = make_case(sys_, defocus)
    except f36.Refused:
        raise
    except Exception as e:  # noqa: BLE001
        raise f36.Refused("optiland_error", repr(e)[:200]) from e
    if kind == "afocal":
        solve_afocal(case)
    if max(abs(c) for c in case.pcurv) * L > 20.0:  # the solved last power, mostly
        raise f36.Refused("extreme_curvature", f"|c| {max(abs(c) for c in case.pcurv):.3g}")
    if kind == "afocal":
        case.thick[-1] = float(rng.uniform(0.3, 2.0) * L)
        case.z_v = np.concatenate([[0.0], np.cumsum(case.thick)])
        case.z_img = float(case.z_v[-1])
        rows = sys_["rows"]
        case.op = case._optic(
            case.curv, [r["co"] for r in rows], [r["k"] for r in rows], 0.0, 0.0, f36.AIR
        )
    obj_medium = None
    if kind == "telecentric_immersion":
        nd = float(rng.uniform(1.33, 1.52))
        obj_medium = dict(name=f"immersion_{nd:.4f}", nd=nd, vd=55.0,
                          n=f36.cauchy(nd, 55.0, case.wls))
        n0 = obj_medium["n"][case.ip]
        case.op.updater.set_material(f36.TableMaterial(case.wls, obj_medium["n"]), 0)
        # the image was solved for an air distance dist; the same paraxial image for d = n0 dist
        case.op.updater.set_thickness(sys_["dist"] * n0, 0)
        z0 = float(np.ravel(np.asarray(case.op.surface_group.positions))[0])
        assert abs(z0 + sys_["dist"] * n0) < 1e-9 * sys_["dist"], (z0, sys_["dist"] * n0)
    object_distance = sys_["dist"] * n0 if kind == "telecentric_immersion" else sys_["dist"]
    na = None
    if kind.startswith("telecentric"):
        # the cone fills about the drawn EPD on surface 1 (0.5 to 1.2 times its radius)
        u = math.atan(rng.uniform(0.5, 1.2) * case.s["epd"] / 2 / object_distance)
        na = float(n0 * math.sin(u))
        case.op.set_aperture(aperture_type="objectNA", value=na)
        case.op.obj_space_telecentric = True
        start = float(rng.uniform(0.05, 0.4) * L)
    else:
        start = float(rng.uniform(4.0, 30.0))
    try:
        top, fields, rays = fit(case, kind, start)
        if kind.startswith("telecentric"):
            case.op.obj_space_telecentric = True
        f2 = float(case.op.paraxial.f2())
        extra = {}
        if kind.startswith("telecentric"):
            y, u = case.op.paraxial.trace_generic(1.0, 0.0, -object_distance, case.prim / 1000)
            extra["paraxial_magnification"] = float(np.ravel(y[-1])[0])
            extra["paraxial_magnification_note"] = (
                "optiland's paraxial trace of a ray from object height 1 mm parallel to the "
                "axis: its height on the image surface (mm)")
        if kind == "virtual":
            extra["entrance_pupil_z"] = float(case.op.paraxial.EPL())
            extra["entrance_pupil_z_ynu"] = case.p["z_ep"]
        if kind == "afocal":
            p = f36.paraxial(case.pcurv, case.thick[:-1], case.n_after[case.prim], case.stop,
                             f36.INF)
            u = 1e-3
            _, nu = p["trace"](-p["z_ep"] * u, u)
            extra["angular_magnification"] = nu / p["n"][-1] / u
            extra["marginal_nu_after"] = p["nu_last"]
            f2 = None
    except f36.Refused:
        raise
    except Exception as e:  # noqa: BLE001
        raise f36.Refused("optiland_error", repr(e)[:200]) from e
    return dict(
        name=f"fuzz41c_{kind}_{idx:03d}",
        kind=kind,
        description=f"random system {idx} of tools/fuzz41c_reference.py ({kind}), seed {seed}",
        generator=dict(script="tools/fuzz41c_reference.py", seed=seed, draw=idx, kind=kind,
                       optiland=_version("optiland"), numpy=np.__version__,
                       python=platform.python_version(),
                       optiland_asphere_newton_tol=f36.NEWTON_TOL),
        surfaces=surfaces(case, obj_medium, object_distance),
        wavelengths_nm=case.wls,
        primary_wavelength_nm=case.prim,
        aperture=dict(EPD=case.s["epd"], object_na=na),
        afocal_image=kind == "afocal",
        fields=dict(type="object_height_xy_mm" if na else "angle_deg_y",
                    values=[list(f) if isinstance(f, tuple) else f for f in fields]),
        pupil=[list(p) for p in PUPIL],
        paraxial=dict(f2=f2, f2_note="optiland paraxial.f2(): image-space focal length n'/power",
                      **extra),
        real_rays=rays,
        build_seconds=round(time.time() - t0, 2),
    )


def surfaces(case, obj_medium, object_distance):
    """The refcase schema's surface list (tests/helpers.refcase_lens reads it)."""
    wls, rows = case.wls, case.s["rows"]

    def nd(vals):
        return {str(w): float(v) for w, v in zip(wls, vals, strict=True)}

    out = [dict(index=0, type="object", curvature=0.0,
                thickness="inf" if object_distance == f36.INF else object_distance,
                material="air" if obj_medium is None else obj_medium["name"],
                n=nd([1.0] * len(wls) if obj_medium is None else obj_medium["n"]))]
    for i, r in enumerate(rows):
        out.append(dict(index=i + 1, type="even_asphere" if r["co"] else "sphere",
                        curvature=case.curv[i], thickness=case.thick[i], conic=r["k"],
                        even_asphere_coeffs=list(r["co"]), material=r["after"]["name"],
                        n=nd(case.n_after[w][i] for w in wls), is_stop=r["stop"]))
    last = case.after_image
    out.append(dict(index=case.m + 1, type="image",
                    curvature=case.img["c"],
                    conic=case.img["k"], material=last["name"],
                    n=nd(case.n_after[w][-1] for w in wls), z_vertex=case.z_img))
    return out


def check_a2():
    """The A2 difference settled without jaxlens: optiland's paraxial ``f2`` of a thick lens
    whose first surface has A2 = 0.004 /mm, against optiland's own real trace of a ray
    1e-4 mm from the axis and the thick-lens formula with curvature c or c + 2·A2."""
    from optiland.rays import RealRays

    a2, r1, r2, t, wl = 0.004, 50.0, -80.0, 5.0, 0.5875618
    op = f36.Optic()
    op.add_surface(index=0, radius=f36.INF, thickness=f36.INF)
    op.add_surface(index=1, radius=r1, thickness=t, material="N-BK7", is_stop=True,
                   surface_type="even_asphere", conic=0.0, coefficients=[a2, 0.0])
    op.add_surface(index=2, radius=r2, thickness=60.0, material="air")
    op.add_surface(index=3)
    op.set_aperture(aperture_type="EPD", value=2.0)
    op.set_field_type("angle")
    op.add_field(y=0.0)
    op.add_wavelength(value=wl, is_primary=True)
    h = 1e-4
    one = np.array([1.0])
    rays = RealRays(0 * one, h * one, -one, 0 * one, 0 * one, one, one, wl * one)
    op.surface_group.trace(rays, skip=1)
    real = h / -(float(np.ravel(rays.M)[0]) / float(np.ravel(rays.N)[0]))
    n = float(np.ravel(op.surface_group.surfaces[1].material_post.n(wl))[0])

    def thick(c1):
        p1, p2 = (n - 1) * c1, (1 - n) / r2
        return 1 / (p1 + p2 - t / n * p1 * p2)

    print(f"optiland paraxial f2 {float(op.paraxial.f2()):.12g}; optiland real ray of height "
          f"{h} mm: {real:.12g}; thick lens, c + 2 A2: {thick(1 / r1 + 2 * a2):.12g}, c: "
          f"{thick(1 / r1):.12g}")


def lenses(out, n, seed, kinds, start):
    summary = dict(seed=seed, kinds=kinds, drawn=0, accepted=[], refused={})
    for i in range(start, start + n):
        kind = kinds[i % len(kinds)]
        summary["drawn"] += 1
        try:
            js = build(i, seed, kind)
        except f36.Refused as e:
            summary["refused"].setdefault(f"{kind}:{e.reason}", []).append(i)
            print(f"{i:3d} {kind} refused {e}"[:200], flush=True)
            continue
        (out / f"{js['name']}.json").write_text(json.dumps(js, indent=1) + "\n")
        summary["accepted"].append(js["name"])
        print(f"{i:3d} ok {js['build_seconds']:5.1f}s {js['name']} fields "
              f"{js['fields']['values']}", flush=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"drawn {summary['drawn']}, accepted {len(summary['accepted'])}, refused "
          + ", ".join(f"{k} {len(v)}" for k, v in summary["refused"].items()))


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz41c_reference.py", description=__doc__.splitlines()[0])
    ap.add_argument("out", help="folder for the files (created), or 'check-a2': print the A2 "
                    "check (check_a2) and stop")
    ap.add_argument("--n", type=int, default=32, help="lenses to draw (default 32)")
    ap.add_argument("--seed", type=int, default=41, help="seed (default 41)")
    ap.add_argument("--start", type=int, default=0, help="first draw index (default 0)")
    ap.add_argument("--kind", choices=(*KINDS, "all"), default="all",
                    help="the class (default all: draw i gets KINDS[i % 4])")
    args = ap.parse_args(argv)
    if args.out == "check-a2":
        check_a2()
        return
    if args.n < 1:
        ap.error(f"--n must be >= 1, got {args.n}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        ap.error(f"OUT {out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    lenses(out, args.n, args.seed, KINDS if args.kind == "all" else (args.kind,), args.start)


if __name__ == "__main__":
    main(sys.argv[1:])
