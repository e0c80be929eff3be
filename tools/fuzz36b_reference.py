"""Randomized reference cases (round 36b): random lenses traced by optiland, in the refcase schema.

Run with the optiland venv, never jaxlens's (jaxlens is not imported here)::

    /work/optenv/bin/python tools/fuzz36b_reference.py OUT_FOLDER [--n 60] [--seed 36] [--hard]

and compare jaxlens with the cases it writes with ``tools/fuzz36b_compare.py`` (jaxlens's venv).

Each draw (seeded: system i uses ``numpy.random.default_rng([seed, i])``) is a random but
physically sensible sequential lens: 2 to 8 surfaces (spheres, conics, even aspheres with
conic and A2..A12, A2 included), glasses given as indices at three wavelengths from an
(nd, Vd) pair through a two-term Cauchy law n = A + B/λ² (crowns, flints, and plastics such
as n ≈ 1.53 / Vd ≈ 56 and n ≈ 1.64 / Vd ≈ 22), cemented pairs, a stop on a lens face or on a
flat surface of its own (front, between elements, behind), an object at infinity or at a
finite distance, a curved (conic) image surface sometimes, and image space that is glass
sometimes (then and then only, sometimes air after the image surface, where optiland
refracts once more). The image is put at the paraxial image of the object plus a small
defocus. The largest field is halved from a random start until every ray the case stores
passes in optiland: finite, no total internal reflection, moving forward (+z) between
consecutive surfaces. ``--hard`` draws fast beams (F/0.9 to F/2.5 before the last power is
solved), mostly strong aspheres (5 % of the beam radius of sag per term, high orders
undamped) and fields halved from 20 to 60 degrees.

Each accepted draw is written as ``fuzz36b_NNN.json`` in the schema of
``../shared/refcases`` (see its README and each file's ``conventions`` block), computed
the same way as ``tools/make_refcase.py``: optiland 0.6.3's even-asphere Newton tolerance
tightened to 1e-12 (the default is 1e-10), rays started on the entrance-pupil plane and
traced with ``surface_group.trace(rays, skip=1)``, paraxial data from an in-script y-nu trace
with curvature c + 2·A2 (checked against optiland's paraxial module on a copy with A2 folded
into c), and every stored real ray and the primary-wavelength spot grid traced again by
rayoptics' ``trace_raw`` when rayoptics is installed (the draw is refused unless they agree to
1e-10 mm). A finite object is surface 0's ``thickness`` (and ``object.distance``); a field is
then the chief ray's angle at the paraxial entrance pupil, so field θ's object point is at
y = −(d + z_EP)·tanθ, and every ray of the field starts from it (``launch`` still stores the
point on the entrance-pupil plane and the direction).

Draws that fail are counted by reason and written to ``summary.json`` with the accepted ones.
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

# tools/ is on the path when this script runs: make_refcase.py shares the schema.
from make_refcase import CONVENTIONS as REFCASE_CONVENTIONS  # noqa: E402
from optiland.materials.base import BaseMaterial  # noqa: E402
from optiland.optic import Optic  # noqa: E402
from optiland.rays import RealRays  # noqa: E402

try:  # the second tracer (optional)
    from rayoptics.elem import profiles
    from rayoptics.elem.surface import Surface as RoSurface
    from rayoptics.raytr.raytrace import trace_raw
except ImportError:  # pragma: no cover
    trace_raw = None

NEWTON_TOL = 1e-12
INF = math.inf
F, D, C = 486.1327, 587.5618, 656.2725
WAVELENGTH_SETS = ([F, D, C], [D, F, C], [450.0, 550.0, 650.0], [546.074, 479.9914, 643.8469])
PRIMARY = (D, D, 550.0, 546.074)

# (name, nd, Vd) ranges: (lo, hi) pairs drawn uniformly.
GLASSES = {
    "crown": ((1.46, 1.62), (50.0, 70.0)),
    "flint": ((1.60, 1.92), (20.0, 40.0)),
    "lanthanum": ((1.65, 1.90), (35.0, 55.0)),
    "plastic_e48r": ((1.525, 1.535), (55.0, 57.0)),
    "plastic_pc": ((1.58, 1.59), (29.0, 31.0)),
    "plastic_okp": ((1.63, 1.645), (20.0, 23.0)),
}


class TableMaterial(BaseMaterial):
    """An optiland material given as indices at a few wavelengths (nm), exact there and
    refused (NaN) elsewhere: the reference never interpolates."""

    def __init__(self, wls_nm, n):
        super().__init__()
        self.table = [(w / 1000.0, float(v)) for w, v in zip(wls_nm, n, strict=True)]

    def _calculate_n(self, wavelength, **kwargs):
        w = np.asarray(wavelength, float)
        out = np.full(w.shape, np.nan)
        for wl, n in self.table:
            out = np.where(np.abs(w - wl) < 1e-12, n, out)
        return out if out.ndim else float(out)

    def _calculate_k(self, wavelength, **kwargs):
        return np.zeros(np.shape(wavelength)) if np.ndim(wavelength) else 0.0


class Refused(Exception):
    """A draw that is discarded, with its reason (a short key)."""

    def __init__(self, reason, detail=""):
        super().__init__(f"{reason}: {detail}")
        self.reason = reason


# ------------------------------------------------------------------------------------------
def cauchy(nd, vd, wls):
    """Indices at ``wls`` (nm) of n = A + B/λ² with n(d) = nd and nF − nC = (nd − 1)/Vd."""
    lf, ld, lc = F / 1000, D / 1000, C / 1000
    b = (nd - 1) / vd / (1 / lf**2 - 1 / lc**2)
    a = nd - b / ld**2
    return [a + b / (w / 1000) ** 2 for w in wls]


def draw_glass(rng, wls):
    kind = rng.choice(list(GLASSES))
    (n0, n1), (v0, v1) = GLASSES[kind]
    nd, vd = float(rng.uniform(n0, n1)), float(rng.uniform(v0, v1))
    return dict(name=f"{kind}_{nd:.4f}_{vd:.1f}", nd=nd, vd=vd, n=cauchy(nd, vd, wls))


AIR = dict(name="air", nd=1.0, vd=INF)


def ynu(curv, thick, n_after, n0=1.0):
    """Trace helper: y-nu through the lens surfaces (curvatures with A2 folded in)."""
    n = [n0] + list(n_after)

    def trace(y, nu, upto=None):
        for i in range(len(curv)):
            if i > 0:
                y = y + thick[i - 1] * nu / n[i]
            nu = nu - y * curv[i] * (n[i + 1] - n[i])
            if upto is not None and i == upto:
                return y, nu
        return y, nu

    return n, trace


def paraxial(curv, thick, n_after, stop, dist):
    """EFL, BFL, z_EP, the image distance for object distance ``dist`` (inf allowed) and the
    marginal-ray heights (for an EPD of 2), all at one wavelength. ``thick`` has the lens gaps
    (the image gap is not needed)."""
    n, trace = ynu(curv, thick, n_after)
    y, nu = trace(1.0, 0.0)
    power = -nu
    efl = 1.0 / power if power != 0 else INF
    bfl = -y * n[-1] / nu if nu != 0 else INF

    def y_at_stop(y1):
        if stop == 0:
            return y1
        y, nu = trace(y1, 1.0, upto=stop - 1)
        return y + thick[stop - 1] * nu / n[stop]

    a0, a1 = y_at_stop(0.0), y_at_stop(1.0)
    z_ep = a0 / (a1 - a0)  # y1 = -z_ep*u with u = 1 crosses the stop centre
    if dist == INF:
        y1, nu1 = 1.0, 0.0
    else:
        u = 1.0 / (dist + z_ep)
        y1, nu1 = dist * u, u
    heights = []
    y, nu = y1, nu1
    for i in range(len(curv)):
        if i > 0:
            y = y + thick[i - 1] * nu / n[i]
        nu = nu - y * curv[i] * (n[i + 1] - n[i])
        heights.append(y)
    img = -y * n[-1] / nu if nu != 0 else INF
    return dict(
        efl=efl, bfl=bfl, z_ep=z_ep, image_gap=img, heights=heights, nu_last=nu, n=n, trace=trace
    )


# ------------------------------------------------------------------------------------------
HARD = False  # --hard: fast beams (F/0.9 to F/2.5), strong aspheres, fields from up to 60 deg


def draw_system(rng):
    """A random prescription (before the fields are fitted)."""
    k_set = int(rng.integers(len(WAVELENGTH_SETS)))
    wls, prim = WAVELENGTH_SETS[k_set], PRIMARY[k_set]
    L = float(rng.uniform(4.0, 60.0))  # a length scale (mm): about the focal length
    m = int(rng.integers(2, 9))  # surfaces, a flat stop surface included
    stop_kind = rng.choice(
        ["lens_face", "front_flat", "inner_flat", "last_face"], p=[0.35, 0.25, 0.25, 0.15]
    )
    flat_stop_at = None
    if stop_kind == "front_flat":
        flat_stop_at = 0
    elif stop_kind == "inner_flat" and m >= 4:
        flat_stop_at = int(rng.integers(1, m - 1))
    elif stop_kind == "inner_flat":
        stop_kind = "lens_face"
    image_glass = rng.random() < 0.25
    rows, glass, medium = [], None, AIR
    for i in range(m):
        last = i == m - 1
        if i == flat_stop_at and medium is AIR:
            rows.append(dict(c=0.0, k=0.0, co=[], after=AIR, stop=True, gap=None))
            continue
        # the medium after this surface
        if medium is AIR:
            after = draw_glass(rng, wls) if (not last or image_glass) else AIR
            if last and image_glass:
                after = draw_glass(rng, wls)
        elif last:
            after = draw_glass(rng, wls) if image_glass else AIR
        else:
            after = draw_glass(rng, wls) if rng.random() < 0.25 else AIR
        c = float(rng.normal(0.0, 1.0 / L)) * (1.5 if after is AIR or medium is AIR else 0.7)
        if rng.random() < 0.12:
            c = 0.0
        rows.append(dict(c=c, k=0.0, co=[], after=after, stop=False, gap=None))
        medium = after
        glass = after if after is not AIR else glass
    del glass
    if not any(r["stop"] for r in rows):
        if stop_kind == "last_face":
            rows[-1]["stop"] = True
        else:
            rows[int(rng.integers(len(rows)))]["stop"] = True
    for i, r in enumerate(rows[:-1]):
        glass_gap = r["after"] is not AIR
        r["gap"] = (
            float(rng.uniform(0.06, 0.22) * L) if glass_gap else float(rng.uniform(0.01, 0.3) * L)
        )
        if r["stop"] and r["c"] == 0.0 and i == 0:
            r["gap"] = float(rng.uniform(0.0, 0.15) * L)
    fno = float(rng.uniform(0.9, 2.5) if HARD else rng.uniform(2.0, 8.0))
    epd = L / fno
    dist = INF if rng.random() < 0.6 else float(rng.uniform(1.5, 25.0) * L)
    curved = rng.random() < 0.3
    img = dict(c=0.0, k=0.0)
    if curved:
        img["c"] = float(rng.choice([-1, 1]) / (rng.uniform(1.0, 6.0) * L))
        if rng.random() < 0.4:
            img["k"] = float(rng.uniform(-2.0, 1.0))
    after_image = None
    if image_glass and rng.random() < 0.35:
        after_image = AIR  # optiland refracts into air at the image surface
    gap = float(rng.uniform(0.3, 2.0) * L)
    return dict(
        wls=wls,
        prim=prim,
        L=L,
        rows=rows,
        epd=epd,
        dist=dist,
        img=img,
        gap=gap,
        after_image=after_image,
        stop_kind=str(stop_kind),
        fno_draw=fno,
    )


def add_aspheres(rng, sys_):
    """Conics and A2..A12 on some surfaces, sized by the paraxial beam there."""
    rows = sys_["rows"]
    wls, prim = sys_["wls"], sys_["prim"]
    ip = wls.index(prim)
    curv = [r["c"] for r in rows]
    n_after = [r["after"]["n"][ip] if r["after"] is not AIR else 1.0 for r in rows]
    stop = next(i for i, r in enumerate(rows) if r["stop"])
    gaps = [r["gap"] for r in rows[:-1]]
    p = paraxial(curv, gaps, n_after, stop, sys_["dist"])
    h = np.abs(np.array(p["heights"])) * sys_["epd"] / 2
    for i, r in enumerate(rows):
        if (
            r["stop"]
            and r["c"] == 0.0
            and r["after"] is AIR
            and (i == 0 or rows[i - 1]["after"] is AIR)
        ):
            continue  # a flat stop in air stays a plane
        u = rng.random()
        rmax = max(1.6 * h[i], 0.05 * sys_["L"])
        if u < 0.25:
            r["k"] = float(rng.uniform(-3.0, 1.0))
        elif u < 0.65:
            r["k"] = float(rng.uniform(-3.0, 1.0)) if rng.random() < 0.7 else 0.0
            nco = int(rng.integers(2, 7))  # A2..A(2*nco)
            co = []
            # each term adds about 1 % (a strong asphere: 5 %, its high orders undamped) of
            # the beam radius of sag at 1.6x the beam
            strong = rng.random() < (0.8 if HARD else 0.3)
            for j in range(1, nco + 1):
                dz = float(rng.normal(0.0, (0.05 if strong else 0.01) * rmax)) / (
                    1.3 if strong else 2
                ) ** (j - 1)
                co.append(dz / rmax ** (2 * j))
            if rng.random() < 0.35:
                co[0] = 0.0
            r["co"] = co


# ------------------------------------------------------------------------------------------
class Case:
    """A drawn system made concrete: thicknesses, paraxial data, the optiland model."""

    def __init__(self, sys_, defocus):
        self.s = sys_
        rows = sys_["rows"]
        self.wls, self.prim = sys_["wls"], sys_["prim"]
        self.ip = self.wls.index(self.prim)
        self.m = len(rows)
        self.stop = next(i for i, r in enumerate(rows) if r["stop"])
        self.curv = [r["c"] for r in rows]
        self.pcurv = [r["c"] + 2 * (r["co"][0] if r["co"] else 0.0) for r in rows]
        self.n_after = {
            w: [r["after"]["n"][j] if r["after"] is not AIR else 1.0 for r in rows]
            for j, w in enumerate(self.wls)
        }
        gaps = [r["gap"] for r in rows[:-1]]
        self.solve_last_power(gaps)
        p = paraxial(self.pcurv, gaps, self.n_after[self.prim], self.stop, sys_["dist"])
        if not (np.isfinite(p["image_gap"]) and 0.08 * sys_["L"] < p["image_gap"] < 6 * sys_["L"]):
            raise Refused("no_real_image", f"image gap {p['image_gap']:.4g}, L {sys_['L']:.4g}")
        if not np.isfinite(p["efl"]) or abs(p["efl"]) > 50 * sys_["L"]:
            raise Refused("no_real_image", f"EFL {p['efl']}")
        if sys_["dist"] != INF and sys_["dist"] + p["z_ep"] < 0.5 * sys_["L"]:
            raise Refused("object_behind_pupil", f"d {sys_['dist']:.4g} z_ep {p['z_ep']:.4g}")
        self.thick = gaps + [p["image_gap"] + defocus]
        if self.thick[-1] <= 0.02 * sys_["L"]:
            raise Refused("no_real_image", "image gap after defocus")
        self.p = paraxial(self.pcurv, gaps, self.n_after[self.prim], self.stop, sys_["dist"])
        self.z_ep = self.p["z_ep"]
        self.z_v = np.concatenate([[0.0], np.cumsum(self.thick)])
        self.z_img = float(self.z_v[-1])
        self.img = sys_["img"]
        last = sys_["after_image"] if sys_["after_image"] is not None else rows[-1]["after"]
        self.after_image = last
        self.n_img_after = {
            w: (last["n"][j] if last is not AIR else 1.0) for j, w in enumerate(self.wls)
        }
        self.op = self._optic(
            self.curv,
            [r["co"] for r in rows],
            [r["k"] for r in rows],
            self.img["c"],
            self.img["k"],
            last,
        )

    def solve_last_power(self, gaps):
        """The base curvature of the last refracting surface set so that the paraxial image
        of the object falls ``gap`` behind the last vertex (a random lens mostly had none)."""
        rows, n = self.s["rows"], [1.0] + self.n_after[self.prim]
        powered = [i for i in range(self.m) if n[i + 1] != n[i]]
        if not powered:
            raise Refused("no_real_image", "no refracting surface")
        j = powered[-1]

        def final(cj):
            pc = list(self.pcurv)
            pc[j] = cj
            p = paraxial(pc, gaps, self.n_after[self.prim], self.stop, self.s["dist"])
            return p["heights"][-1], p["nu_last"]

        # (y, nu) after the last surface are linear in the paraxial curvature of surface j;
        # the image gap g = -y n'/nu: -(a + b c) n' = g (e + f c)
        (y0, nu0), (y1, nu1) = final(0.0), final(1.0)
        a, b, e, f = y0, y1 - y0, nu0, nu1 - nu0
        g = self.s["gap"]
        den = b * n[-1] + g * f
        if den == 0:
            raise Refused("no_real_image", "the last power cannot place the image")
        cj = -(a * n[-1] + g * e) / den
        a2 = rows[j]["co"][0] if rows[j]["co"] else 0.0
        rows[j]["c"] = cj - 2 * a2
        self.curv[j] = rows[j]["c"]
        self.pcurv[j] = cj

    # -------------------------------------------------------------- optiland
    def _optic(self, curv, coefs, conics, c_img, k_img, img_medium):
        rows = self.s["rows"]
        op = Optic()
        op.add_surface(index=0, radius=INF, thickness=self.s["dist"])
        mats = {}

        def mat(g):
            if g is AIR:
                return "air"
            if g["name"] not in mats:
                mats[g["name"]] = TableMaterial(self.wls, g["n"])
            return mats[g["name"]]

        for i, r in enumerate(rows):
            kw = dict(
                index=i + 1,
                radius=INF if curv[i] == 0 else 1.0 / curv[i],
                thickness=self.thick[i],
                conic=conics[i],
                is_stop=r["stop"],
                material=mat(r["after"]),
            )
            if coefs[i]:
                kw.update(surface_type="even_asphere", coefficients=list(coefs[i]))
            op.add_surface(**kw)
        op.add_surface(
            index=self.m + 1,
            radius=INF if c_img == 0 else 1.0 / c_img,
            conic=k_img,
            material=mat(img_medium),
        )
        op.set_aperture(aperture_type="EPD", value=self.s["epd"])
        op.set_field_type(field_type="angle")
        op.add_field(y=0.0)
        for w in self.wls:
            op.add_wavelength(value=w / 1000.0, is_primary=(w == self.prim))
        for s in op.surface_group.surfaces[1:]:
            g = s.geometry
            if hasattr(g, "tol"):
                g.tol = NEWTON_TOL
                assert g.tol == NEWTON_TOL
        pos = np.ravel(np.asarray(op.surface_group.positions))[1:]
        assert np.allclose(pos, self.z_v, atol=1e-12), (pos, self.z_v)
        return op

    def launch(self, field, px, py):
        """Launch points on the EP plane and directions, [N, 3] each."""
        px, py = np.atleast_1d(px).astype(float), np.atleast_1d(py).astype(float)
        o = np.stack(
            [px * self.s["epd"] / 2, py * self.s["epd"] / 2, np.full(px.shape, self.z_ep)], 1
        )
        th = math.radians(field)
        if self.s["dist"] == INF:
            d = np.tile([0.0, math.sin(th), math.cos(th)], (len(px), 1))
        else:
            obj = np.array([0.0, -math.tan(th) * (self.z_ep + self.s["dist"]), -self.s["dist"]])
            d = o - obj
            d = d / np.linalg.norm(d, axis=1, keepdims=True)
        return o, d

    def trace(self, o, d, wl_nm):
        """optiland: image data [N, 6] and per-surface (z, r) [S, N] (surface 1 .. image)."""
        rays = RealRays(
            o[:, 0].copy(),
            o[:, 1].copy(),
            o[:, 2].copy(),
            d[:, 0].copy(),
            d[:, 1].copy(),
            d[:, 2].copy(),
            np.ones(len(o)),
            np.full(len(o), wl_nm / 1000.0),
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            self.op.surface_group.trace(rays, skip=1)
        newton = [
            str(w.message)
            for w in caught
            if "tol" in str(w.message).lower()
            or "converge" in str(w.message).lower()
            or "reject" in str(w.message).lower()
        ]
        out = np.stack(
            [np.ravel(np.asarray(v)) for v in (rays.x, rays.y, rays.z, rays.L, rays.M, rays.N)], 1
        )
        sg = self.op.surface_group
        # with skip=1 optiland records the surfaces it traced only (surface 1 .. image)
        z, r = np.asarray(sg.z), np.hypot(np.asarray(sg.x), np.asarray(sg.y))
        assert len(z) == len(sg.surfaces) - 1, (z.shape, len(sg.surfaces))
        return out, z, r, newton

    def check_rays(self, out, z, newton, what):
        if newton:
            raise Refused("optiland_newton", f"{what}: {newton[0][:120]}")
        if not np.all(np.isfinite(out)) or not np.all(np.isfinite(z)):
            raise Refused("miss_or_tir", what)
        # forward between consecutive surfaces after surface 1 (jaxlens refuses backward rays)
        if np.any(np.diff(z, axis=0) <= 0):
            raise Refused("backward", what)

    # -------------------------------------------------------------- rayoptics
    def ro_trace(self, o, d, wl_nm):
        j = self.wls.index(wl_nm)
        rows = self.s["rows"]
        eye = np.eye(3)
        ifcs = [RoSurface(profile=profiles.Spherical(c=0.0), interact_mode="dummy")]
        tfrm = [(eye, np.array([0.0, 0.0, 0.0 - self.z_ep]))]
        idx = [1.0]
        for i, r in enumerate(rows):
            if r["co"]:
                prof = profiles.EvenPolynomial(c=self.curv[i], cc=r["k"], coefs=list(r["co"]))
            else:
                prof = profiles.Conic(c=self.curv[i], cc=r["k"])
            ifcs.append(RoSurface(profile=prof, interact_mode="transmit"))
            tfrm.append((eye, np.array([0.0, 0.0, self.thick[i]])))
            idx.append(self.n_after[wl_nm][i])
        n_last = self.n_img_after[wl_nm]
        mode = "dummy" if n_last == idx[-1] else "transmit"
        ifcs.append(
            RoSurface(profile=profiles.Conic(c=self.img["c"], cc=self.img["k"]), interact_mode=mode)
        )
        tfrm.append((eye, np.zeros(3)))
        idx.append(n_last)
        path = [[ifc, None, tf, nn, 1] for ifc, tf, nn in zip(ifcs, tfrm, idx, strict=True)]
        res = []
        for oo, dd in zip(o, d, strict=True):
            ray, _, _ = trace_raw(
                iter(path), np.array([oo[0], oo[1], 0.0]), dd, wl_nm, eps=1e-14, intersect_obj=False
            )
            pt, dr = ray[-1][0], ray[-1][1]
            res.append([pt[0], pt[1], pt[2] + self.z_img, *dr])
        del j
        return np.array(res)


PUPIL = [
    (0.0, 0.0),
    (0.0, 1.0),
    (0.0, -1.0),
    (0.0, 0.5),
    (0.0, -0.5),
    (1.0, 0.0),
    (math.sqrt(0.5), math.sqrt(0.5)),
    (-0.3, 0.9),
]


def spot_grid():
    g = np.linspace(-1, 1, 21)
    PX, PY = np.meshgrid(g, g, indexing="xy")
    keep = PX**2 + PY**2 <= 1 + 1e-12
    grid = np.stack([PX[keep], PY[keep]], 1)
    assert len(grid) == 317
    return grid


GRID = spot_grid()


def all_pass(case, field):
    """Every stored ray of ``field`` (the spot grid, the rim, the real-ray pupil points) passes."""
    px = np.concatenate([GRID[:, 0], [p[0] for p in PUPIL], np.cos(np.linspace(0, 2 * np.pi, 24))])
    py = np.concatenate([GRID[:, 1], [p[1] for p in PUPIL], np.sin(np.linspace(0, 2 * np.pi, 24))])
    o, d = case.launch(field, px, py)
    for w in case.wls:
        out, z, _, newton = case.trace(o, d, w)
        case.check_rays(out, z, newton, f"field {field} wl {w}")


def fit_fields(rng, case):
    """Fields 0, ~0.6 θ, θ with θ halved from a random start until every ray passes."""
    theta = float(rng.uniform(20.0, 60.0) if HARD else rng.uniform(4.0, 40.0))
    last = None
    for _ in range(6):
        try:
            all_pass(case, theta)
            all_pass(case, 0.6 * theta)
            return [0.0, round(0.6 * theta, 3), round(theta, 3)]
        except Refused as e:
            last = e
            theta /= 2
    all_pass(case, 0.0)  # raises the field-0 reason
    raise last


# ------------------------------------------------------------------------------------------
def build(idx, seed):
    t0 = time.time()
    rng = np.random.default_rng([seed, idx])
    sys_ = draw_system(rng)
    add_aspheres(rng, sys_)
    defocus = float(rng.uniform(-0.01, 0.01) * sys_["L"])
    try:
        case = Case(sys_, defocus)
    except Refused:
        raise
    except Exception as e:  # noqa: BLE001  optiland failed to build the model
        raise Refused("optiland_error", repr(e)[:200]) from e
    try:
        fields = fit_fields(rng, case)
        fields = [0.0, round(0.6 * fields[2], 3), fields[2]]
        fields = sorted(set(fields))
        return case, fields, make_json(case, fields, idx, seed, t0)
    except Refused:
        raise
    except Exception as e:  # noqa: BLE001
        raise Refused("optiland_error", repr(e)[:200]) from e


def make_json(case, fields, idx, seed, t0):
    s, wls, prim, p = case.s, case.wls, case.prim, case.p
    rows = s["rows"]
    # ---------------- real rays
    real_rays = []
    ro_diff = ro_ddir = 0.0
    for f in fields:
        o, d = case.launch(f, [q[0] for q in PUPIL], [q[1] for q in PUPIL])
        for w in wls:
            out, z, _, newton = case.trace(o, d, w)
            case.check_rays(out, z, newton, f"real rays {f} {w}")
            if trace_raw is not None:
                ref = case.ro_trace(o, d, w)
                ro_diff = max(ro_diff, float(np.abs(out[:, :3] - ref[:, :3]).max()))
                ro_ddir = max(ro_ddir, float(np.abs(out[:, 3:] - ref[:, 3:]).max()))
            for k, (px, py) in enumerate(PUPIL):
                real_rays.append(
                    dict(
                        field_angle_deg=f,
                        Hy=f / max(fields),
                        Px=px,
                        Py=py,
                        wavelength_nm=w,
                        launch=dict(
                            point_on_EP_plane=o[k].tolist(), direction_cosines=d[k].tolist()
                        ),
                        image=dict(zip("x y z L M N".split(), map(float, out[k]), strict=True)),
                    )
                )
    if trace_raw is not None and not (ro_diff < 1e-10 and ro_ddir < 1e-12):
        raise Refused("rayoptics_disagrees", f"{ro_diff:.3g} {ro_ddir:.3g}")
    # ---------------- spots and distortion
    rms, dist, ro_rms, chief_y = [], [], [], {}
    for f in fields:
        o, d = case.launch(f, 0.0, 0.0)
        chief = case.trace(o, d, prim)[0][0]
        chief_y[f] = float(chief[1])
        per, allxy = {}, []
        o, d = case.launch(f, GRID[:, 0], GRID[:, 1])
        for w in wls:
            out, z, _, newton = case.trace(o, d, w)
            case.check_rays(out, z, newton, f"spot {f} {w}")
            xy = out[:, :2]
            allxy.append(xy)
            cen = xy.mean(0)
            per[str(w)] = dict(
                n_rays=len(xy),
                rms_vs_centroid=float(np.sqrt(np.mean(np.sum((xy - cen) ** 2, 1)))),
                rms_vs_chief=float(np.sqrt(np.mean(np.sum((xy - chief[:2]) ** 2, 1)))),
                centroid=cen.tolist(),
            )
            if w == prim and trace_raw is not None:
                rxy = case.ro_trace(o, d, w)[:, :2]
                if not np.abs(rxy - xy).max() < 1e-10:
                    raise Refused("rayoptics_disagrees", f"spot {np.abs(rxy - xy).max():.3g}")
                rc = rxy.mean(0)
                ro_rms.append(
                    dict(
                        field_angle_deg=f,
                        rms_vs_centroid=float(np.sqrt(np.mean(np.sum((rxy - rc) ** 2, 1)))),
                        rms_vs_chief=float(np.sqrt(np.mean(np.sum((rxy - chief[:2]) ** 2, 1)))),
                    )
                )
        allxy = np.concatenate(allxy)
        cen = allxy.mean(0)
        rms.append(
            dict(
                field_angle_deg=f,
                chief_ray_primary=chief[:2].tolist(),
                per_wavelength=per,
                polychromatic_equal_weights=dict(
                    n_rays=len(allxy),
                    rms_vs_centroid=float(np.sqrt(np.mean(np.sum((allxy - cen) ** 2, 1)))),
                    rms_vs_chief=float(np.sqrt(np.mean(np.sum((allxy - chief[:2]) ** 2, 1)))),
                ),
            )
        )
    n_list, trace = p["n"], p["trace"]
    par_h = {}
    for f in fields:
        u = math.tan(math.radians(f))
        y, nu = trace(-p["z_ep"] * u, u)
        y_img = y + case.thick[-1] * nu / n_list[-1]
        par_h[f] = y_img
        if f == 0.0:
            continue
        ftan = p["efl"] * u
        dist.append(
            dict(
                field_angle_deg=f,
                chief_ray_y_real=chief_y[f],
                f_tan_theta=ftan,
                paraxial_chief_ray_y_at_image_plane=y_img,
                distortion_pct_ftan=100 * (chief_y[f] - ftan) / ftan,
                distortion_pct_vs_paraxial_chief_at_image=100 * (chief_y[f] - y_img) / y_img,
            )
        )
    # ---------------- paraxial cross-check with optiland (A2 folded into c, n at primary)
    op2 = case._optic(
        case.pcurv, [[] for _ in rows], [0.0] * len(rows), case.img["c"], 0.0, rows[-1]["after"]
    )
    op2.surface_group.surfaces[0].thickness = INF
    n_img = case.n_after[prim][-1]
    try:
        ol_f2 = float(op2.paraxial.f2())
        ol_epl = float(op2.paraxial.EPL())
    except Exception as e:  # noqa: BLE001
        raise Refused("optiland_error", f"paraxial: {e!r}"[:200]) from e
    if not abs(ol_f2 - n_img * p["efl"]) < 1e-9 * abs(ol_f2):
        raise Refused("optiland_paraxial_disagrees", f"f2 {ol_f2} vs {n_img * p['efl']}")
    if not abs(ol_epl - p["z_ep"]) < 1e-9 * max(1, abs(ol_epl)):
        raise Refused("optiland_paraxial_disagrees", f"EPL {ol_epl} vs {p['z_ep']}")

    # ---------------- JSON
    def nd(vals):
        return {str(w): float(v) for w, v in zip(wls, vals, strict=True)}

    dval = s["dist"]
    surfaces = [
        dict(
            index=0,
            type="object",
            radius="inf",
            curvature=0.0,
            thickness="inf" if dval == INF else dval,
            material="air",
            n=nd([1.0] * len(wls)),
        )
    ]
    for i, r in enumerate(rows):
        g = r["after"]
        surfaces.append(
            dict(
                index=i + 1,
                comment="",
                type="even_asphere" if r["co"] else "sphere",
                radius="inf" if r["c"] == 0 else 1.0 / r["c"],
                curvature=r["c"],
                thickness=case.thick[i],
                conic=r["k"],
                even_asphere_coeffs=list(r["co"]),
                material=g["name"],
                n=nd(case.n_after[w][i] for w in wls),
                is_stop=r["stop"],
                semi_diameter_source=None,
            )
        )
    g = case.after_image
    surfaces.append(
        dict(
            index=case.m + 1,
            type="image",
            radius="inf" if case.img["c"] == 0 else 1 / case.img["c"],
            curvature=case.img["c"],
            conic=case.img["k"],
            material=g["name"],
            n=nd(case.n_img_after[w] for w in wls),
            z_vertex=case.z_img,
        )
    )
    glasses = {r["after"]["name"]: r["after"] for r in rows if r["after"] is not AIR}
    if g is not AIR:
        glasses[g["name"]] = g
    fno = p["efl"] / s["epd"]
    features = []
    if any(r["co"] for r in rows):
        features.append("even_asphere")
    if any(r["co"] and r["co"][0] for r in rows):
        features.append("A2")
    if any(r["k"] for r in rows):
        features.append("conic")
    if any("plastic" in n for n in glasses):
        features.append("plastic")
    if case.img["c"]:
        features.append("curved_image")
    if rows[-1]["after"] is not AIR:
        features.append("image_space_glass")
    if s["after_image"] is not None:
        features.append("air_after_image_surface")
    if dval != INF:
        features.append("finite_object")
    features.append(f"stop_{s['stop_kind']}")
    features.append(f"{len(rows)}_surfaces")
    return dict(
        name=f"fuzz36b_{'hard_' if HARD else ''}{idx:03d}",
        description=f"random system {idx} of tools/fuzz36b_reference.py, seed {seed}: "
        + ", ".join(features),
        features=features,
        source="jaxlens tools/fuzz36b_reference.py (random prescription)",
        generator=dict(
            script="tools/fuzz36b_reference.py",
            seed=seed,
            draw=idx,
            hard=HARD,
            optiland=_version("optiland"),
            rayoptics=_version("rayoptics"),
            numpy=np.__version__,
            python=platform.python_version(),
            optiland_asphere_newton_tol=NEWTON_TOL,
        ),
        conventions=CONVENTIONS,
        object=dict(distance="infinity" if dval == INF else dval),
        wavelengths_nm=wls,
        primary_wavelength_nm=prim,
        stop_surface_index=case.stop + 1,
        aperture=dict(
            spec_in_source=["EPD", s["epd"]],
            EPD=s["epd"],
            FNO_paraxial_infinite=fno,
            FNO_note="EFL/EPD with EFL = 1/power",
        ),
        fields=dict(type="angle_deg_y", values=fields),
        surfaces=surfaces,
        material_index_source={
            k: f"two-term Cauchy n = A + B/lambda^2 with nd = {v['nd']!r}, Vd = {v['vd']!r} "
            "(F, d, C lines)"
            for k, v in glasses.items()
        }
        | {"air": "n = 1 exactly"},
        paraxial=dict(
            wavelength_nm=prim,
            EFL=p["efl"],
            EFL_note="EFL = 1/power (object space is air), y-nu with curvature c + 2*A2",
            rear_focal_length_nprime_over_power=n_img * p["efl"],
            BFL=p["bfl"],
            BFL_note="paraxial rear focus of an object at infinity, from the last "
            "lens vertex (y-nu)",
            entrance_pupil_z=p["z_ep"],
            entrance_pupil_diameter=s["epd"],
            FNO=fno,
            paraxial_image_height_ftan={
                str(f): p["efl"] * math.tan(math.radians(f)) for f in fields
            },
            paraxial_chief_ray_y_at_image_vertex={str(f): h for f, h in par_h.items()},
            image_surface_z=case.z_img,
            paraxial_image_gap_of_the_object=case.thick[-1] - defocus_of(case),
            image_plane_minus_paraxial_image=defocus_of(case),
        ),
        real_rays=real_rays,
        rms_spot=rms,
        distortion=dist,
        cross_check=dict(
            rayoptics_real_rays=None
            if trace_raw is None
            else dict(
                n_rays=len(real_rays),
                max_abs_intercept_diff_mm=ro_diff,
                max_abs_dircos_diff=ro_ddir,
                method="rayoptics trace_raw from the same EP-plane launch point and direction",
            ),
            rayoptics_rms_primary=ro_rms,
            optiland_paraxial_with_A2_folded=dict(f2=ol_f2, EPL=ol_epl),
        ),
        build_seconds=round(time.time() - t0, 2),
    )


def defocus_of(case):
    gaps = case.thick[:-1]
    p = paraxial(case.pcurv, gaps, case.n_after[case.prim], case.stop, case.s["dist"])
    return case.thick[-1] - p["image_gap"]


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:  # noqa: BLE001
        return None


# make_refcase.py's conventions (the same schema), with what finite objects add.
CONVENTIONS = {
    **REFCASE_CONVENTIONS,
    "thickness": (
        "distance from this surface vertex to the next surface vertex; surface 0's is the"
        " object distance ('inf' for an object at infinity)"
    ),
    "field": (
        "angle in the y-z plane. Object at infinity: object-space direction (0, sin th, "
        "cos th). Finite object at distance d: the chief ray's angle at the paraxial "
        "entrance pupil, object point (0, -(d + z_EP) tan th, -d); every ray of the field"
        " starts there"
    ),
    "distortion": (
        "distortion_pct_ftan = 100*(y_chief_real - EFL*tan(theta))/(EFL*tan(theta)); "
        "distortion_pct_vs_paraxial_chief_at_image = 100*(y_chief_real - "
        "y_parax_chief)/y_parax_chief, y_parax_chief the paraxial chief ray (through the "
        "EP centre at angle theta) height at the image surface vertex plane"
    ),
}


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz36b_reference.py", description=__doc__.splitlines()[0])
    ap.add_argument("out", help="folder for fuzz36b_NNN.json and summary.json (created)")
    ap.add_argument("--n", type=int, default=60, help="systems to draw (default 60)")
    ap.add_argument("--seed", type=int, default=36, help="seed (default 36)")
    ap.add_argument("--start", type=int, default=0, help="first draw index (default 0)")
    ap.add_argument(
        "--hard",
        action="store_true",
        help="fast beams (F/0.9 to F/2.5), mostly strong aspheres, wider fields",
    )
    args = ap.parse_args(argv)
    global HARD
    HARD = args.hard
    if args.n < 1:
        ap.error(f"--n must be >= 1, got {args.n}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        ap.error(f"OUT {out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    summary = dict(seed=args.seed, hard=args.hard, drawn=0, accepted=[], refused={})
    for i in range(args.start, args.start + args.n):
        summary["drawn"] += 1
        try:
            _, _, js = build(i, args.seed)
        except Refused as e:
            summary["refused"].setdefault(e.reason, []).append(i)
            print(f"{i:3d} refused {e}", flush=True)
            continue
        (out / f"{js['name']}.json").write_text(json.dumps(js, indent=1) + "\n")
        summary["accepted"].append(js["name"])
        print(
            f"{i:3d} ok {js['build_seconds']:5.1f}s fields {js['fields']['values']} "
            f"{' '.join(js['features'])}",
            flush=True,
        )
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(
        f"drawn {summary['drawn']}, accepted {len(summary['accepted'])}, refused "
        + ", ".join(f"{k} {len(v)}" for k, v in summary["refused"].items())
    )


if __name__ == "__main__":
    main(sys.argv[1:])
