"""Make reference cases for tests/test_trace.py with optiland (an independent tracer).

Run with the optiland venv, not jaxlens's (jaxlens is never imported here)::

    /work/optiland_venv/bin/python tools/make_refcase.py tests/refcases_extra [NAME ...]

Each case is written as NAME.json in the refcase schema of ../shared/refcases (see its
README and each file's ``conventions`` block): tabulated indices per wavelength, rays launched
from the paraxial entrance pupil at the primary wavelength, no aiming, no vignetting, no
clipping, the paraxial data from an in-script y-nu trace with the A2 (r²) term included.

Independent checks, stored under ``cross_check`` (the script stops if one fails):

* optiland's even-asphere Newton tolerance is tightened to 1e-12 (default 1e-10);
* every real ray is traced again with rayoptics' ``trace_raw`` (its own intersection and
  refraction code) from the same launch point; intercepts must agree to 1e-10 mm;
* the paraxial data are checked against optiland's paraxial module on a copy of the lens
  whose curvatures carry the A2 term (c + 2 A2) and whose A2 is zero, since optiland's own
  EFL leaves A2 out;
* the RMS spot at the primary wavelength is recomputed from the rayoptics rays.
"""

from __future__ import annotations

import json
import math
import platform
import sys
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")

from optiland.materials import Material  # noqa: E402
from optiland.optic import Optic  # noqa: E402
from optiland.rays import RealRays  # noqa: E402

NEWTON_TOL = 1e-12
F, D, C = 486.1327, 587.5618, 656.2725

# ---------------------------------------------------------------------------------------
# The cases. Surfaces: (R, t, material, k, [A2, A4, ...], is_stop); R = inf for a flat.
# "defocus" is the image position minus the paraxial focus (mm); the last thickness is
# set from the in-script BFL. Materials: "air", or "NAME" / "NAME:catalog" for optiland.
# ---------------------------------------------------------------------------------------
INF = math.inf

CASES = {
    "plastic_asphere_front_stop": dict(
        description=("Two plastic singlets (Zeonex E48R, polycarbonate) behind a flat front "
                     "stop, every lens face an even asphere with a conic and A2..A12 "
                     "(A2 nonzero), EPD 2, fields 0/20/30 deg, F/d/C"),
        wavelengths=[F, D, C], primary=D, epd=2.0, fields=[0.0, 20.0, 30.0], defocus=-0.01,
        surfaces=[
            (INF, 0.3, "air", 0.0, [], True),
            (2.2, 1.1, "E48R", -0.8,
             [0.004, -0.012, 0.0035, -0.0021, 6.0e-4, -8.0e-5], False),
            (-8.0, 0.45, "air", 5.0, [-0.006, 0.021, -0.009, 0.0031, -6.0e-4, 5.0e-5], False),
            (-2.1, 0.7, "POLYCARB", -1.6, [0.01, -0.03, 0.018, -0.006, 0.0011, -9.0e-5],
             False),
            (-3.5, None, "air", -4.0, [0.008, -0.011, 0.0042, -0.0009, 1.1e-4, -6.0e-6],
             False),
        ],
        image=dict(R=INF),
    ),
    "wide_angle_curved_image": dict(
        description=("Wide-angle (fields 0/25/38 deg) lens with a strongly bent front "
                     "meniscus of large sag, stop inside, a conic on the rear face, and a "
                     "curved (spherical, R = -60 mm) image surface, 4 wavelengths with the "
                     "primary first"),
        wavelengths=[546.074, 486.1327, 587.5618, 656.2725], primary=546.074, epd=3.0,
        fields=[0.0, 25.0, 38.0], defocus=0.02,
        surfaces=[
            (14.0, 1.2, "N-BK7:schott", 0.0, [], False),
            (4.2, 4.5, "air", 0.0, [], False),
            (12.0, 2.6, "N-LASF9:schott", 0.0, [], False),
            (-40.0, 1.0, "air", 0.0, [], False),
            (INF, 1.2, "air", 0.0, [], True),
            (-30.0, 0.8, "SF6:schott", 0.0, [], False),
            (9.0, 3.0, "N-LAK22:schott", 0.0, [], False),
            (-7.5, None, "air", -0.6, [], False),
        ],
        image=dict(R=-60.0),
    ),
    "immersion_image_space": dict(
        description=("Image space is glass (N-LASF9): the last element is in contact with "
                     "the sensor. Even asphere with conic and A2..A8 on the first face; "
                     "stop between the elements; fields 0/12/18 deg"),
        wavelengths=[F, D, C], primary=D, epd=6.0, fields=[0.0, 12.0, 18.0], defocus=-0.03,
        surfaces=[
            (18.0, 3.0, "N-BK7:schott", -0.5, [-0.002, -2.0e-5, 1.5e-7, -4.0e-9], False),
            (-60.0, 2.0, "air", 0.0, [], False),
            (INF, 2.0, "air", 0.0, [], True),
            (14.0, None, "N-LASF9:schott", 0.0, [], False),
        ],
        image=dict(R=INF),
    ),
    "stop_at_last_surface": dict(
        description=("Cemented doublet whose last surface is the aperture stop (entrance "
                     "pupil far inside the lens), PMMA/polycarbonate plastics, fields "
                     "0/10/20 deg"),
        wavelengths=[F, D, C], primary=D, epd=8.0, fields=[0.0, 10.0, 20.0], defocus=0.05,
        surfaces=[
            (25.0, 4.0, "PMMA", 0.0, [], False),
            (-18.0, 1.5, "POLYCARB", 0.0, [], False),
            (-90.0, None, "air", 0.0, [], True),
        ],
        image=dict(R=INF),
    ),
    "negative_radii_rim_asphere": dict(
        description=("Every radius negative (including a curved conic image surface R = -35 mm, "
                     "k = 0.3), "
                     "a meniscus of large sag, aspheres whose A8..A12 terms dominate near the "
                     "rim and a hyperbolic conic, A2 nonzero, stop in front; fields 0/8/15 deg"),
        wavelengths=[F, D, C], primary=D, epd=5.0, fields=[0.0, 8.0, 15.0], defocus=0.0,
        surfaces=[
            (INF, 1.0, "air", 0.0, [], True),
            (-7.0, 2.5, "N-BK7:schott", 0.0, [], False),
            (-5.5, 0.3, "air", -0.4, [3.0e-3, 1.0e-4, -2.0e-5, 3.0e-6, -1.5e-7, 4.0e-9],
             False),
            (-60.0, 3.0, "N-LASF9:schott", -3.0,
             [-2.0e-3, 2.0e-4, 3.0e-5, -6.0e-6, 4.0e-7, -1.0e-8], False),
            (-14.0, None, "air", 0.0, [], False),
        ],
        image=dict(R=-35.0, k=0.3),
    ),
    "plastic_curved_immersed_image": dict(
        description=("Stop on the first lens face; plastic aspheres (E48R, conics and "
                     "A2..A12) and a glass field element (N-SF11) in contact with a curved "
                     "image surface (R = 12 mm), so image space is glass and the image is "
                     "curved; the image surface's medium is air, so the stored directions are "
                     "after a refraction at the image surface; fields 0/20/30 deg"),
        wavelengths=[F, D, C], primary=D, epd=1.6, fields=[0.0, 20.0, 30.0], defocus=0.0,
        surfaces=[
            (2.5, 1.0, "E48R", -0.5, [0.006, -0.004, 0.0012, -2.0e-4, 1.0e-5, 2.0e-7], True),
            (-12.0, 0.8, "air", 0.0, [0.003, 0.004, -0.001, 2.0e-4, -2.0e-5, 1.0e-6], False),
            (-1.6, 0.7, "E48R", 0.0, [-0.004, 0.002, -4.0e-4, 6.0e-5, -5.0e-6, 2.0e-7],
             False),
            (-2.2, 0.5, "air", -0.7, [0.002, 0.0015, 2.0e-4, -1.0e-4, 1.5e-5, -6.0e-7],
             False),
            (4.0, None, "N-SF11:schott", 0.0, [], False),
        ],
        image=dict(R=12.0, material="air"),
    ),
    "flat_base_a2_rim_asphere": dict(
        description=("A flat-based even asphere whose power is all A2 (c = 0, A2 = 0.04), a "
                     "paraboloid (k = -1), a hyperboloid (k = -2.5) and high-order terms "
                     "that dominate near the rim (about 0.1 mm from the base conic), "
                     "PMMA/polycarbonate, stop between, fields 0/15/25 deg"),
        wavelengths=[F, D, C], primary=D, epd=4.0, fields=[0.0, 15.0, 25.0], defocus=0.1,
        surfaces=[
            (INF, 2.5, "PMMA", 0.0, [0.04, -1.0e-4, 2.0e-6, 0.0, 0.0, 0.0], False),
            (-15.0, 1.0, "air", -1.0, [0.0, 5.0e-4, 2.0e-5, -1.0e-6, 0.0, 0.0], False),
            (INF, 1.0, "air", 0.0, [], True),
            (10.0, 3.0, "POLYCARB", -2.5, [-0.01, 2.0e-3, -4.0e-4, 6.0e-5, -3.0e-6, 1.0e-7],
             False),
            (-8.0, None, "air", 0.0, [0.0, -3.0e-3, 8.0e-4, -1.0e-4, 8.0e-6, -2.0e-7],
             False),
        ],
        image=dict(R=INF),
    ),
}


# ---------------------------------------------------------------------------------------
def material(name):
    if name == "air":
        return None
    base, _, cat = name.partition(":")
    return Material(base, cat) if cat else Material(base)


def index_of(mat, wl_nm):
    return 1.0 if mat is None else float(np.ravel(mat.n(wl_nm / 1000.0))[0])


def ynu_system(curv, thick, n_after, n0=1.0):
    """Paraxial y-nu data (curvature with A2 folded in) in plain numpy, object at infinity.

    curv[i], thick[i], n_after[i] for the lens surfaces; thick[-1] is the image gap."""
    m = len(curv)
    n = [n0] + list(n_after)

    def trace(y, nu, upto=None, to_image=False):
        ys = []
        for i in range(m):
            if i > 0:
                y = y + thick[i - 1] * nu / n[i]
            nu = nu - y * curv[i] * (n[i + 1] - n[i])
            ys.append(y)
            if upto is not None and i == upto:
                return y, nu, ys
        if to_image:
            y = y + thick[-1] * nu / n[-1]
        return y, nu, ys

    return n, trace


def paraxial(spec, curv, thick, n_after, stop):
    n, trace = ynu_system(curv, thick, n_after)
    # Marginal ray from infinity, height 1.
    y, nu, ys = trace(1.0, 0.0)
    power = -nu / 1.0
    efl = 1.0 / power
    bfl = -y * n[-1] / nu
    # EP: chief ray with u = 1 through (0, z_ep): y1 = -z_ep, nu = 1; y at the stop is linear.
    def y_at_stop(y1):
        if stop == 0:
            return y1
        y, nu, ys = trace(y1, 1.0, upto=stop - 1)
        return y + thick[stop - 1] * nu / n[stop]
    a0, a1 = y_at_stop(0.0), y_at_stop(1.0)
    y1 = -a0 / (a1 - a0)
    z_ep = -y1
    return dict(n=n, trace=trace, efl=efl, bfl=bfl, z_ep=z_ep, power=power)


def image_gap(spec, curv, thick_known, n_after, stop):
    """The last thickness: paraxial BFL + defocus."""
    th = list(thick_known) + [0.0]
    p = paraxial(spec, curv, th, n_after, stop)
    return p["bfl"] + spec["defocus"]


def build(name, spec):
    t0 = time.time()
    wls = spec["wavelengths"]
    prim = spec["primary"]
    rows = spec["surfaces"]
    mats = {r[2]: material(r[2]) for r in rows}
    m = len(rows)
    stop = [i for i, r in enumerate(rows) if r[5]][0]
    curv = [0.0 if r[0] == INF else 1.0 / r[0] for r in rows]
    a2 = [(r[4][0] if r[4] else 0.0) for r in rows]
    pcurv = [c + 2 * a for c, a in zip(curv, a2, strict=True)]
    n_after = {w: [index_of(mats[r[2]], w) for r in rows] for w in wls}
    thick = [r[1] for r in rows[:-1]]
    thick.append(image_gap(spec, pcurv, thick, n_after[prim], stop))
    p = paraxial(spec, pcurv, thick, n_after[prim], stop)
    z_v = np.concatenate([[0.0], np.cumsum(thick)])
    z_img = float(z_v[-1])
    R_img = spec["image"]["R"]
    c_img = 0.0 if R_img == INF else 1.0 / R_img
    k_img = spec["image"].get("k", 0.0)

    # ---------------- optiland model -------------------------------------------------
    op = Optic()
    op.add_surface(index=0, radius=INF, thickness=INF)
    for i, (R, _, mat, k, co, is_stop) in enumerate(rows):
        kw = dict(index=i + 1, radius=R, thickness=thick[i], conic=k, is_stop=is_stop,
                  material=mats[mat] if mats[mat] is not None else "air")
        if co:
            kw.update(surface_type="even_asphere", coefficients=list(co))
        op.add_surface(**kw)
    # The medium after the image surface: image space's unless the case names another,
    # and then optiland refracts into it there (the "last refraction" of the directions).
    img_mat = spec["image"].get("material", rows[-1][2])
    mats.setdefault(img_mat, material(img_mat))
    last = mats[img_mat]
    n_after_img = {w: index_of(last, w) for w in wls}
    op.add_surface(index=m + 1, radius=R_img, conic=k_img,
                   material=last if last is not None else "air")
    op.set_aperture(aperture_type="EPD", value=spec["epd"])
    op.set_field_type(field_type="angle")
    for f in spec["fields"]:
        op.add_field(y=f)
    for w in wls:
        op.add_wavelength(value=w / 1000.0, is_primary=(w == prim))
    for s in op.surface_group.surfaces[1:]:
        g = s.geometry
        if hasattr(g, "tol"):
            g.tol = NEWTON_TOL
            assert g.tol == NEWTON_TOL
    pos = np.ravel(np.asarray(op.surface_group.positions))[1:]
    assert np.allclose(pos, z_v, atol=1e-12), (pos, z_v)

    def trace_optiland(o, d, wl_nm):
        o, d = np.atleast_2d(o), np.atleast_2d(d)
        rays = RealRays(o[:, 0].copy(), o[:, 1].copy(), o[:, 2].copy(), d[:, 0].copy(),
                        d[:, 1].copy(), d[:, 2].copy(), np.ones(len(o)),
                        np.full(len(o), wl_nm / 1000.0))
        op.surface_group.trace(rays, skip=1)
        out = np.stack([np.ravel(np.asarray(v)) for v in
                        (rays.x, rays.y, rays.z, rays.L, rays.M, rays.N)], 1)
        hx = np.asarray(op.surface_group.x)
        hy = np.asarray(op.surface_group.y)
        return out, np.hypot(hx, hy)

    def launch(field, px, py):
        th = math.radians(field)
        o = np.array([px * spec["epd"] / 2, py * spec["epd"] / 2, p["z_ep"]])
        d = np.array([0.0, math.sin(th), math.cos(th)])
        return o, d

    # ---------------- rayoptics (second tracer) -------------------------------------
    from rayoptics.elem import profiles
    from rayoptics.elem.surface import Surface as RoSurface
    from rayoptics.raytr.raytrace import trace_raw

    def ro_path(wl_nm):
        eye = np.eye(3)
        ifcs = [RoSurface(profile=profiles.Spherical(c=0.0), interact_mode="dummy")]
        tfrm = [(eye, np.array([0.0, 0.0, 0.0 - p["z_ep"]]))]
        idx = [1.0]
        for i, (_, _, _, k, co, _) in enumerate(rows):
            if co:
                prof = profiles.EvenPolynomial(c=curv[i], cc=k, coefs=list(co))
            else:
                prof = profiles.Conic(c=curv[i], cc=k)
            ifcs.append(RoSurface(profile=prof, interact_mode="transmit"))
            tfrm.append((eye, np.array([0.0, 0.0, thick[i]])))
            idx.append(n_after[wl_nm][i])
        mode = "dummy" if n_after_img[wl_nm] == idx[-1] else "transmit"
        ifcs.append(RoSurface(profile=profiles.Conic(c=c_img, cc=k_img), interact_mode=mode))
        tfrm.append((eye, np.zeros(3)))
        idx.append(n_after_img[wl_nm])
        return [[ifc, None, tf, nn, 1] for ifc, tf, nn in zip(ifcs, tfrm, idx, strict=True)]

    def trace_ro(o, d, wl_nm):
        ray, _, _ = trace_raw(iter(ro_path(wl_nm)), np.array([o[0], o[1], 0.0]), d, wl_nm,
                              eps=1e-14, intersect_obj=False)
        pt, dr = ray[-1][0], ray[-1][1]
        return np.array([pt[0], pt[1], pt[2] + z_img, *dr])

    # ---------------- real rays ------------------------------------------------------
    pupil = [(0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.0, 0.5), (0.0, -0.5), (1.0, 0.0),
             (math.sqrt(0.5), math.sqrt(0.5))]
    real_rays, ro_diff, ro_ddir = [], 0.0, 0.0
    for f in spec["fields"]:
        for w in wls:
            for px, py in pupil:
                o, d = launch(f, px, py)
                out, _ = trace_optiland(o, d, w)
                out = out[0]
                ref = trace_ro(o, d, w)
                ro_diff = max(ro_diff, float(np.abs(out[:3] - ref[:3]).max()))
                ro_ddir = max(ro_ddir, float(np.abs(out[3:] - ref[3:]).max()))
                real_rays.append(dict(
                    field_angle_deg=f, Hy=f / max(spec["fields"]), Px=px, Py=py,
                    wavelength_nm=w,
                    launch=dict(point_on_EP_plane=o.tolist(), direction_cosines=d.tolist()),
                    image=dict(zip("x y z L M N".split(), map(float, out), strict=True))))
    assert np.isfinite(ro_diff) and ro_diff < 1e-10, (name, ro_diff)
    assert ro_ddir < 1e-12, (name, ro_ddir)

    # ---------------- RMS spot and distortion ----------------------------------------
    g = np.linspace(-1, 1, 21)
    PX, PY = np.meshgrid(g, g, indexing="xy")
    keep = PX**2 + PY**2 <= 1 + 1e-12
    grid = np.stack([PX[keep], PY[keep]], 1)
    assert len(grid) == 317
    rms, dist, ro_rms = [], [], []
    chief_y = {}
    for f in spec["fields"]:
        o, d = launch(f, 0.0, 0.0)
        chief = trace_optiland(o, d, prim)[0][0]
        chief_y[f] = float(chief[1])
        per, allxy = {}, []
        for w in wls:
            th = math.radians(f)
            o = np.stack([grid[:, 0] * spec["epd"] / 2, grid[:, 1] * spec["epd"] / 2,
                          np.full(len(grid), p["z_ep"])], 1)
            d = np.tile([0.0, math.sin(th), math.cos(th)], (len(grid), 1))
            out, h = trace_optiland(o, d, w)
            bad = ~np.isfinite(h)
            lost = bad.any(0)
            assert not lost.any(), (name, f, w, "rays lost at surfaces",
                                    np.unique(bad.argmax(0)[lost] + 1).tolist(),
                                    grid[lost].tolist()[:4], h[:, lost][:, 0].tolist())
            xy = out[:, :2]
            allxy.append(xy)
            cen = xy.mean(0)
            per[str(w)] = dict(
                n_rays=len(xy),
                rms_vs_centroid=float(np.sqrt(np.mean(np.sum((xy - cen) ** 2, 1)))),
                rms_vs_chief=float(np.sqrt(np.mean(np.sum((xy - chief[:2]) ** 2, 1)))),
                centroid=cen.tolist())
            if w == prim:
                rxy = np.array([trace_ro(oo, dd, w)[:2] for oo, dd in zip(o, d, strict=True)])
                assert np.abs(rxy - xy).max() < 1e-10, (name, np.abs(rxy - xy).max())
                rc = rxy.mean(0)
                ro_rms.append(dict(
                    field_angle_deg=f,
                    rms_vs_centroid=float(np.sqrt(np.mean(np.sum((rxy - rc) ** 2, 1)))),
                    rms_vs_chief=float(np.sqrt(np.mean(np.sum((rxy - chief[:2]) ** 2, 1))))))
        allxy = np.concatenate(allxy)
        cen = allxy.mean(0)
        rms.append(dict(
            field_angle_deg=f, chief_ray_primary=chief[:2].tolist(), per_wavelength=per,
            polychromatic_equal_weights=dict(
                n_rays=len(allxy),
                rms_vs_centroid=float(np.sqrt(np.mean(np.sum((allxy - cen) ** 2, 1)))),
                rms_vs_chief=float(np.sqrt(np.mean(np.sum((allxy - chief[:2]) ** 2, 1)))))))
    par_h = {}
    for f in spec["fields"]:
        u = math.tan(math.radians(f))
        y_img, _, _ = p["trace"](-p["z_ep"] * u, 1.0 * u, to_image=True)
        par_h[f] = y_img
        if f == 0.0:
            continue
        ftan = p["efl"] * u
        dist.append(dict(
            field_angle_deg=f, chief_ray_y_real=chief_y[f], f_tan_theta=ftan,
            paraxial_chief_ray_y_at_image_plane=y_img,
            distortion_pct_ftan=100 * (chief_y[f] - ftan) / ftan,
            distortion_pct_vs_paraxial_chief_at_image=100 * (chief_y[f] - y_img) / y_img))

    # ---------------- semi-diameters (informational) ---------------------------------
    rim = np.array([[math.cos(a), math.sin(a)] for a in np.linspace(0, 2 * math.pi, 72,
                                                                         endpoint=False)])
    sd = np.zeros(m + 1)
    for f in spec["fields"]:
        th = math.radians(f)
        for w in wls:
            o = np.stack([rim[:, 0] * spec["epd"] / 2, rim[:, 1] * spec["epd"] / 2,
                          np.full(len(rim), p["z_ep"])], 1)
            d = np.tile([0.0, math.sin(th), math.cos(th)], (len(rim), 1))
            _, h = trace_optiland(o, d, w)
            sd = np.maximum(sd, h.max(1))

    # ---------------- paraxial cross-check with optiland (A2 folded into c) ----------
    op2 = Optic()
    op2.add_surface(index=0, radius=INF, thickness=INF)
    for i, (_, _, mat, _, _, is_stop) in enumerate(rows):
        R2 = INF if pcurv[i] == 0 else 1.0 / pcurv[i]
        op2.add_surface(index=i + 1, radius=R2, thickness=thick[i], is_stop=is_stop,
                        material=mats[mat] if mats[mat] is not None else "air")
    space = mats[rows[-1][2]]  # optiland's f2 is n/power with n the image surface's medium
    op2.add_surface(index=m + 1, radius=R_img, material=space if space is not None else "air")
    op2.set_aperture(aperture_type="EPD", value=spec["epd"])
    op2.set_field_type(field_type="angle")
    for f in spec["fields"]:
        op2.add_field(y=f)
    for w in wls:
        op2.add_wavelength(value=w / 1000.0, is_primary=(w == prim))
    n_img = n_after[prim][-1]
    ol_f2 = float(op2.paraxial.f2())
    ol_epl = float(op2.paraxial.EPL())
    ol_bfl = float(np.ravel(op2.paraxial.marginal_ray()[0])[-2] * 0 + 0)  # unused
    del ol_bfl
    assert abs(ol_f2 - n_img * p["efl"]) < 1e-9 * abs(ol_f2), (name, ol_f2, p["efl"])
    assert abs(ol_epl - p["z_ep"]) < 1e-9 * max(1, abs(ol_epl)), (name, ol_epl, p["z_ep"])
    xpl_a2 = float(op2.paraxial.XPL())
    xpl_own = float(op.paraxial.XPL())

    # ---------------- JSON ---------------------------------------------------------------
    def nd(vals):
        return {str(w): v for w, v in zip(wls, vals, strict=True)}

    surfaces = [dict(index=0, type="object", radius="inf", curvature=0.0, thickness="inf",
                     material="air", n=nd([1.0] * len(wls)))]
    for i, (R, _, mat, k, co, is_stop) in enumerate(rows):
        surfaces.append(dict(
            index=i + 1, comment="", type="even_asphere" if co else "sphere",
            radius="inf" if R == INF else R, curvature=curv[i], thickness=thick[i], conic=k,
            even_asphere_coeffs=list(co), material=mat.partition(":")[0],
            n=nd([n_after[w][i] for w in wls]), is_stop=is_stop, semi_diameter_source=None,
            semi_diameter_real_rays=float(sd[i])))
    surfaces.append(dict(
        index=m + 1, type="image", radius="inf" if R_img == INF else R_img, curvature=c_img,
        conic=k_img, material=img_mat.partition(":")[0],
        n=nd([n_after_img[w] for w in wls]), z_vertex=z_img,
        semi_diameter_real_rays=float(sd[m])))
    fno = p["efl"] / spec["epd"]
    case = dict(
        name=name, description=spec["description"],
        source="jaxlens tools/make_refcase.py (prescription invented to stress the tracer)",
        generator=dict(script="tools/make_refcase.py", optiland=_version("optiland"),
                       rayoptics=_version("rayoptics"), numpy=np.__version__,
                       python=platform.python_version(),
                       optiland_asphere_newton_tol=NEWTON_TOL),
        conventions=CONVENTIONS,
        object=dict(distance="infinity"),
        wavelengths_nm=wls, primary_wavelength_nm=prim, stop_surface_index=stop + 1,
        aperture=dict(spec_in_source=["EPD", spec["epd"]], EPD=spec["epd"],
                      FNO_paraxial_infinite=fno,
                      FNO_note="EFL/EPD with EFL = 1/power (= 1/(2 n' u') of the marginal "
                               "ray); not n'/power/EPD when image space is not air"),
        fields=dict(type="angle_deg_y", values=spec["fields"]),
        surfaces=surfaces,
        material_index_source={
            k: ("n = 1 exactly" if v is None else f"optiland {_version('optiland')} "
                f"Material({k.partition(':')[0]!r}"
                + (f", {k.partition(':')[2]!r})" if ':' in k else ")")
                + f" -> {getattr(v, 'filename', '')}".split("data-nk/")[-1])
            for k, v in mats.items()},
        paraxial=dict(
            wavelength_nm=prim, EFL=p["efl"],
            EFL_note="EFL = 1/power (object space is air), power from a y-nu trace with "
                     "paraxial curvature c + 2*A2",
            rear_focal_length_nprime_over_power=n_img * p["efl"],
            BFL=p["bfl"], BFL_note="paraxial rear focus from the last lens vertex (y-nu)",
            entrance_pupil_z=p["z_ep"], entrance_pupil_diameter=spec["epd"],
            exit_pupil_optiland_XPL=xpl_own,
            exit_pupil_note="optiland paraxial.XPL() of the lens as given: exit pupil "
                            "relative to the image surface vertex; ignores A2",
            exit_pupil_with_A2_XPL=xpl_a2,
            FNO=fno,
            paraxial_image_height_ftan={str(f): p["efl"] * math.tan(math.radians(f))
                                        for f in spec["fields"]},
            paraxial_chief_ray_y_at_image_vertex={str(f): h for f, h in par_h.items()},
            image_surface_z=z_img,
            image_plane_minus_paraxial_focus=thick[-1] - p["bfl"]),
        real_rays=real_rays, rms_spot=rms, distortion=dist,
        cross_check=dict(
            rayoptics_real_rays=dict(
                n_rays=len(real_rays), max_abs_intercept_diff_mm=ro_diff,
                max_abs_dircos_diff=ro_ddir,
                method="rayoptics trace_raw (its own intersection and refraction) from the "
                       "same EP-plane launch point, with the same tabulated indices"),
            rayoptics_rms_primary=ro_rms,
            optiland_paraxial_with_A2_folded=dict(f2=ol_f2, EPL=ol_epl,
                                                  note="optiland on a copy with c + 2*A2"),
        ),
        build_seconds=round(time.time() - t0, 2))
    return case


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:  # noqa: BLE001
        return None


CONVENTIONS = {
    "units": "mm; wavelengths in nm; angles in degrees",
    "coordinates": "surface 1 vertex at z=0, +z along the axis; 'z' values are global",
    "sag": "z = c r^2/(1+sqrt(1-(1+k)c^2 r^2)) + sum_i A_{2i} r^{2i}; even_asphere_coeffs = "
           "[A2, A4, A6, ...] (first multiplies r^2)",
    "thickness": "distance from this surface vertex to the next surface vertex",
    "material": "medium AFTER the surface; n given at every wavelength; image space is the "
                "medium after the last lens surface",
    "field": "angle in the y-z plane; object-space direction (0, sin th, cos th)",
    "pupil": "ray through (Px*EPD/2, Py*EPD/2) on the plane z=z_EP (paraxial entrance pupil "
             "at the primary wavelength, used for all wavelengths); no ray aiming, no "
             "vignetting, no clipping",
    "image_intercept": "x, y, z of the ray on the image surface (global z, sag included for "
                       "a curved image), L M N = direction cosines after the last refraction; "
                       "when the image surface's own medium (its material and n) differs from "
                       "image space, that last refraction is at the image surface",
    "rms_spot": "square grid 21x21 over [-1,1]^2 kept where Px^2+Py^2<=1+1e-12 (317 rays), "
                "equal weights; RMS radius = sqrt(mean(dx^2+dy^2)) of the x, y intercepts on "
                "the image surface; 'vs_centroid' about the centroid of the same ray set, "
                "'vs_chief' about the primary-wavelength chief ray (Px=Py=0)",
    "distortion": "distortion_pct_ftan = 100*(y_chief_real - EFL*tan(theta))/(EFL*tan(theta)); "
                  "distortion_pct_vs_paraxial_chief_at_image = 100*(y_chief_real - "
                  "y_parax_chief)/y_parax_chief, y_parax_chief the paraxial chief ray height "
                  "at the image surface vertex plane",
}


def main(argv):
    import argparse
    import difflib
    import pathlib

    p = argparse.ArgumentParser(prog="make_refcase.py", description=__doc__.splitlines()[0])
    p.add_argument("out", help="folder of the NAME.json files (created)")
    p.add_argument("names", nargs="*", default=[],
                   help=f"cases (default: all): {', '.join(CASES)}")
    args = p.parse_args(argv)
    # Checked before the first case is built (minutes each): was a KeyError or
    # FileExistsError traceback, after the cases before it were written.
    for name in args.names:
        if name not in CASES:
            close = difflib.get_close_matches(name, list(CASES), n=3, cutoff=0.5)
            p.error(f"unknown case {name!r}" + (f" (did you mean {', '.join(close)}?)"
                                                if close else "") + f"; cases: {', '.join(CASES)}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        p.error(f"OUT {out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    names = args.names or list(CASES)
    for name in names:
        case = build(name, CASES[name])
        (out / f"{name}.json").write_text(json.dumps(case, indent=1) + "\n")
        cc = case["cross_check"]["rayoptics_real_rays"]
        print(f"{name}: EFL {case['paraxial']['EFL']:.6f} BFL {case['paraxial']['BFL']:.6f} "
              f"zEP {case['paraxial']['entrance_pupil_z']:.6f} rayoptics dpos "
              f"{cc['max_abs_intercept_diff_mm']:.2e} ddir {cc['max_abs_dircos_diff']:.2e} "
              f"({case['build_seconds']} s)")


if __name__ == "__main__":
    main(sys.argv[1:])
