"""optiland 0.6.3 reference numbers for ``jaxlens.optics.freeform`` (tests/test_freeform.py).

Run it with optiland's interpreter (it does not import jaxlens):

    /work/optiland_venv/bin/python tools/freeform_reference.py

It prints one Python literal, ``REF``, pasted into tests/test_freeform.py. What it holds:

* ``zernike_sag``: sag and unit normal of optiland's ``ZernikePolynomialGeometry`` (a conic
  plus Zernike terms, φ = atan2(y, x)) at scattered points, for Noll ("standard" in jaxlens,
  Zemax Standard) and Fringe coefficients. optiland's Fringe numbering follows
  j = (1 + (n+|m|)/2)² − 2|m| (+1 for sin) for every j, so its term 37 is ρ⁶ cos 6φ, not
  Zemax's R_12^0: 36 Fringe terms are compared.
* ``biconic_sag``: sag and unit normal of optiland's ``BiconicGeometry``. optiland's biconic
  is the sum of the two section conics, which is Zemax's biconic only where a section is a
  parabola (k = −1) or flat (c = 0); the cases here are such ones, and a general one
  (``general``) whose difference the test shows.
* ``rays``: image intercepts of two small lenses traced by optiland (Newton tolerance
  1e-13, 200 iterations, apertures none, ideal media): ``biconic`` (surface 1 a biconic
  with parabolic sections, surface 2 a conic cylinder) and ``zernike`` (surface 1 Noll
  Zernike terms on a conic, surface 2 Fringe terms on a sphere). ``biconic_general`` is a
  lens with a general biconic traced by optiland's Newton intersection and refraction with
  the geometry's sag and normal replaced by Zemax's biconic formula (optiland has none):
  it checks jaxlens's intersection and refraction, not the formula.
"""

from __future__ import annotations

import numpy as np
import optiland.backend as be
from optiland.coordinate_system import CoordinateSystem
from optiland.geometries import BiconicGeometry, ZernikePolynomialGeometry
from optiland.materials import IdealMaterial
from optiland.optic import Optic
from optiland.rays import RealRays

rng = np.random.default_rng(20261129)
POINTS = [[0.0, 0.0], [1.3, 0.0], [0.0, -2.1], [2.2, 1.7], [-3.1, 2.6], [3.9, -3.3],
          [-0.4, -4.6], [-4.2, -1.1]]
NOLL = (rng.normal(size=45) * 2e-3).round(6).tolist()
FRINGE = (rng.normal(size=36) * 2e-3).round(6).tolist()
Z_BASE = {"radius": 40.0, "conic": -0.6, "norm_radius": 6.0}
BICONICS = {  # radius_x, radius_y, conic_x, conic_y
    "parabolic": (60.0, 40.0, -1.0, -1.0),
    "cylinder_x_flat": (np.inf, 35.0, 0.0, -0.7),
    "cylinder_y_flat": (-45.0, np.inf, 1.3, 0.0),
    "general": (60.0, 40.0, -0.4, 0.8),
}


def _normal(geom, x, y):
    nx, ny, nz = geom._surface_normal(be.array(x), be.array(y))
    return [float(-nx), float(-ny), float(-nz)]  # optiland's normal points toward −z


def sag_table(geom):
    out = []
    for x, y in POINTS:
        out.append([float(geom.sag(be.array(x), be.array(y)))] + _normal(geom, x, y))
    return out


def zernike_geometry(kind, coeffs, base=Z_BASE):
    return ZernikePolynomialGeometry(CoordinateSystem(), radius=base["radius"],
                                     conic=base["conic"], coefficients=coeffs,
                                     zernike_type=kind, norm_radius=base["norm_radius"],
                                     tol=1e-13, max_iter=200)


class ZemaxBiconic(BiconicGeometry):
    """optiland's Newton geometry with Zemax's biconic sag and normal (see the module notes)."""

    def sag(self, x=0, y=0):
        x, y = be.asarray(x), be.asarray(y)
        cx, cy = self.cx, self.cy
        root = be.sqrt(1 - (1 + self.kx) * cx**2 * x**2 - (1 + self.ky) * cy**2 * y**2)
        return (cx * x**2 + cy * y**2) / (1 + root)

    def _surface_normal(self, x, y):
        x, y = be.asarray(x), be.asarray(y)
        px, py = (1 + self.kx) * self.cx**2, (1 + self.ky) * self.cy**2
        root = be.sqrt(1 - px * x**2 - py * y**2)
        z = self.sag(x, y)
        fx = (2 * self.cx + z * px / root) * x / (1 + root)
        fy = (2 * self.cy + z * py / root) * y / (1 + root)
        mag = be.sqrt(fx**2 + fy**2 + 1)
        return fx / mag, fy / mag, -1 / mag


LAUNCH_FIELDS = [(0.0, 0.0), (0.0, 4.0), (3.0, 0.0), (2.5, -3.5)]  # (θx, θy) degrees
LAUNCH_PUPIL = [(0.0, 0.0), (0.7, 0.0), (0.0, -0.7), (0.5, 0.6), (-0.9, -0.3)]  # × 4 mm


def launch():
    o, d = [], []
    for tx, ty in LAUNCH_FIELDS:
        v = np.array([np.tan(np.radians(tx)), np.tan(np.radians(ty)), 1.0])
        v /= np.linalg.norm(v)
        for px, py in LAUNCH_PUPIL:
            p = np.array([4 * px, 4 * py, 0.0])  # on the plane z = 0, then back to z = −5
            o.append(p - 5.0 / v[2] * v)
            d.append(v)
    return np.array(o), np.array(d)


def trace(optic, o, d):
    rays = RealRays(*o.T.copy(), *d.T.copy(), np.ones(len(o)), np.full(len(o), 0.5875618))
    for s in optic.surfaces.surfaces:
        s.aperture = None
        g = s.geometry
        if hasattr(g, "tol"):
            g.tol, g.max_iter = 1e-13, 200
    optic.surfaces.trace(rays, skip=1)
    return np.stack([np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.z)], -1).tolist()


def lens(surfaces):
    """An optic from (geometry factory, thickness, index after) per surface; image plane."""
    optic = Optic()
    optic.surfaces.add(index=0, radius=be.inf, thickness=be.inf)
    for i, (kw, t, n) in enumerate(surfaces, start=1):
        optic.surfaces.add(index=i, thickness=t, material=IdealMaterial(n=n), is_stop=i == 1,
                           **kw)
    optic.surfaces.add(index=len(surfaces) + 1)
    optic.set_aperture(aperture_type="EPD", value=8.0)
    optic.fields.set_type(field_type="angle")
    optic.fields.add(y=0.0)
    optic.wavelengths.add(value=0.5875618, is_primary=True)
    return optic


def biconic_kw(name):
    rx, ry, kx, ky = BICONICS[name]
    return dict(surface_type="biconic", radius_x=rx, radius_y=ry, conic_x=kx, conic_y=ky)


def main():
    ref = {"points": POINTS, "noll": NOLL, "fringe": FRINGE, "z_base": Z_BASE,
           "biconics": {k: [float(v) for v in t] for k, t in BICONICS.items()}}
    ref["zernike_sag"] = {"standard": sag_table(zernike_geometry("noll", NOLL)),
                          "fringe": sag_table(zernike_geometry("fringe", FRINGE))}
    ref["biconic_sag"] = {k: sag_table(BiconicGeometry(CoordinateSystem(), *v))
                          for k, v in BICONICS.items()}
    o, d = launch()
    ref["launch"] = {"origin": o.tolist(), "direction": d.tolist()}
    rays = {}
    rays["biconic"] = trace(lens([(biconic_kw("parabolic"), 5.0, 1.5),
                                  (biconic_kw("cylinder_x_flat"), 40.0, 1.0)]), o, d)
    zl = lens([(dict(surface_type="zernike", radius=40.0, conic=-0.6, coefficients=NOLL[:15],
                     zernike_type="noll", norm_radius=6.0), 4.0, 1.6),
               (dict(surface_type="zernike", radius=-60.0, conic=0.0,
                     coefficients=FRINGE[:16], zernike_type="fringe", norm_radius=6.5),
                45.0, 1.0)])
    rays["zernike"] = trace(zl, o, d)
    gl = lens([(biconic_kw("general"), 5.0, 1.5), (biconic_kw("cylinder_y_flat"), 40.0, 1.0)])
    for s in gl.surfaces.surfaces[1:3]:
        g = s.geometry
        s.geometry = ZemaxBiconic(g.cs, float(g.Rx), float(g.Ry), float(g.kx), float(g.ky))
    rays["biconic_general"] = trace(gl, o, d)
    ref["rays"] = rays
    print("REF = " + repr(ref))


if __name__ == "__main__":
    main()
