"""optiland 0.6.3 reference numbers for the decentered ``ZernikeSag`` (Zemax SZERNSAG/FZERNSAG
PARM 9, 10), for tests/test_zernike_decenter.py.

Run it with optiland's interpreter (it does not import jaxlens):

    /work/optiland_venv/bin/python tools/zernike_decenter_reference.py \
        tests/data/zernike_decenter_optiland.json

optiland's ``ZernikePolynomialGeometry`` has no decenter of its Zernike terms, so two
independent constructions stand in for it:

* ``shifted``: a geometry whose sag is optiland's even asphere (``EvenAsphere``: the base
  conic and r², r⁴, … terms, centred on the vertex) plus optiland's Zernike sum (a
  ``ZernikePolynomialGeometry`` with a flat base) evaluated at (x − dx, y − dy); its normal
  adds the two geometries' own slopes. Only the shift and the sum are written here; the
  polynomials, their derivatives, the Newton intersection and the refraction are optiland's.
  Sag and unit normal at scattered points, and image intercepts of a two-surface lens
  (surface 1 Noll terms on an even asphere, surface 2 Fringe terms on a sphere, each
  decentered in x and y).
* ``moved``: on a flat base (c = 0, no asphere terms) a decenter of the Zernike terms is a
  decenter of the whole surface; optiland's own surface decenter (``dx``, ``dy`` of the
  surface's coordinate system, which does not carry on to the next surface) places an
  undecentered Zernike surface there. Image intercepts of such a lens (a flat-base Noll
  surface, then a sphere): nothing of the decenter is written here.

Both use the convention of jaxlens.optics.freeform: the pattern's centre (ρ = 0) lies at
(dx, dy) in the surface's frame. Fields are (θx, θy) in degrees, rays travel along
(tan θx, tan θy, 1)/norm and are launched from the plane z = −5 mm through the points
(Px, Py)·4 mm of the plane z = 0; ideal media (n = 1.6 or 1.55 after surface 1, then air)
at 0.5875618 µm; no apertures; optiland's Newton tolerance 1e-13, 200 iterations.
"""

from __future__ import annotations

import json
import pathlib
import sys

import numpy as np
import optiland.backend as be
from optiland.coordinate_system import CoordinateSystem
from optiland.geometries import EvenAsphere, ZernikePolynomialGeometry
from optiland.materials import IdealMaterial
from optiland.optic import Optic
from xypolynomial_reference import launch, trace  # this folder's: the same rays and tracer

WAVELENGTH = 0.5875618
rng = np.random.default_rng(20261130)
NOLL = (rng.normal(size=15) * 2e-3).round(6).tolist()
FRINGE = (rng.normal(size=16) * 2e-3).round(6).tolist()
POINTS = [[0.0, 0.0], [0.8, -1.2], [1.3, 0.0], [0.0, -2.1], [2.2, 1.7], [-3.1, 2.6],
          [3.4, -3.3], [-0.4, -4.1], [-4.2, -1.1]]
# Surfaces of the ``shifted`` lens: base (radius, conic, even-asphere terms on r², r⁴),
# Zernike (kind, coefficients, normalisation radius, dx, dy), thickness after, index after.
SHIFTED = [
    dict(radius=40.0, conic=-0.6, asphere=[2e-4, -3e-6], kind="noll", zernike=NOLL,
         norm_radius=8.0, dx=0.8, dy=-1.2, thickness=4.0, n=1.6),
    dict(radius=-60.0, conic=0.0, asphere=[], kind="fringe", zernike=FRINGE,
         norm_radius=9.0, dx=-0.5, dy=0.7, thickness=45.0, n=1.0),
]
# The ``moved`` lens: a flat-base Noll surface decentered by (dx, dy), then a sphere.
MOVED = dict(zernike=NOLL[:10], norm_radius=8.0, dx=-0.9, dy=1.4, thickness=4.0, n=1.55,
             radius2=-50.0, thickness2=40.0)


class ShiftedZernike(EvenAsphere):
    """optiland's even asphere plus optiland's Zernike sum centred at (dx, dy)."""

    def __init__(self, cs, s: dict):
        super().__init__(cs, s["radius"], s["conic"], tol=1e-13, max_iter=200,
                         coefficients=s["asphere"])
        self.part = ZernikePolynomialGeometry(CoordinateSystem(), radius=be.inf, conic=0.0,
                                              coefficients=s["zernike"],
                                              zernike_type=s["kind"],
                                              norm_radius=s["norm_radius"])
        self.dx, self.dy = s["dx"], s["dy"]
        self.is_symmetric = False

    def sag(self, x=0, y=0):
        x, y = be.asarray(x), be.asarray(y)
        return super().sag(x, y) + self.part.sag(x - self.dx, y - self.dy)

    def _surface_normal(self, x, y):
        x, y = be.asarray(x), be.asarray(y)
        slopes = []
        for nx, ny, nz in (super()._surface_normal(x, y),
                           self.part._surface_normal(x - self.dx, y - self.dy)):
            slopes.append((nx / -nz, ny / -nz))  # optiland's normal: (z_x, z_y, −1)/norm
        fx = slopes[0][0] + slopes[1][0]
        fy = slopes[0][1] + slopes[1][1]
        mag = be.sqrt(fx**2 + fy**2 + 1)
        return fx / mag, fy / mag, -1 / mag


def sag_table(geom):
    """[sag, unit normal toward +z] at POINTS."""
    out = []
    for x, y in POINTS:
        nx, ny, nz = geom._surface_normal(be.array(x), be.array(y))
        out.append([float(geom.sag(be.array(x), be.array(y))),
                    float(-nx), float(-ny), float(-nz)])
    return out


def new_optic():
    optic = Optic()
    optic.surfaces.add(index=0, radius=be.inf, thickness=be.inf)
    return optic


def finish(optic, n_surfaces):
    optic.surfaces.add(index=n_surfaces + 1)
    optic.set_aperture(aperture_type="EPD", value=8.0)
    optic.fields.set_type(field_type="angle")
    optic.fields.add(y=0.0)
    optic.wavelengths.add(value=WAVELENGTH, is_primary=True)
    return optic


def shifted_lens():
    optic = new_optic()
    for i, s in enumerate(SHIFTED, start=1):
        optic.surfaces.add(index=i, radius=s["radius"], thickness=s["thickness"],
                           material=IdealMaterial(n=s["n"]), is_stop=i == 1)
    finish(optic, len(SHIFTED))
    for i, s in enumerate(SHIFTED, start=1):
        surf = optic.surfaces.surfaces[i]
        surf.geometry = ShiftedZernike(surf.geometry.cs, s)
    return optic


def moved_lens():
    m = MOVED
    optic = new_optic()
    optic.surfaces.add(index=1, surface_type="zernike", radius=be.inf, conic=0.0,
                       coefficients=m["zernike"], zernike_type="noll",
                       norm_radius=m["norm_radius"], thickness=m["thickness"],
                       material=IdealMaterial(n=m["n"]), is_stop=True, dx=m["dx"], dy=m["dy"])
    optic.surfaces.add(index=2, radius=m["radius2"], thickness=m["thickness2"],
                       material=IdealMaterial(n=1.0))
    return finish(optic, 2)


def main(argv):
    if len(argv) != 1:
        raise SystemExit("usage: zernike_decenter_reference.py OUT.json")
    o, d = launch()
    ref = {
        "computed_by": "optiland 0.6.3 via tools/zernike_decenter_reference.py",
        "wavelength": WAVELENGTH, "points": POINTS, "shifted_surfaces": SHIFTED,
        "moved": MOVED, "launch": {"origin": o.tolist(), "direction": d.tolist()},
        "sag": [sag_table(ShiftedZernike(CoordinateSystem(), s)) for s in SHIFTED],
        "rays": {"shifted": trace(shifted_lens(), o, d), "moved": trace(moved_lens(), o, d)},
    }
    pathlib.Path(argv[0]).write_text(json.dumps(ref, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
