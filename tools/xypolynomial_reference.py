"""optiland 0.6.3 reference numbers for ``jaxlens.optics.xypolynomial``.

Used by tests/test_xypolynomial.py. Run it with optiland's interpreter (it does not import
jaxlens):

    /work/optiland_venv/bin/python tools/xypolynomial_reference.py

It prints one Python literal, ``REF``, pasted into tests/test_xypolynomial.py. What it holds:

* ``sag``: sag and unit normal (+z at the vertex) of optiland's ``PolynomialGeometry`` (a
  conic plus Σ C_mn x^m y^n) at scattered points, for the 27 terms of degree 1 … 6 in
  ``terms`` (Zemax's order: x, y, x², xy, y², x³, …; A_i on the normalised coordinates
  x/R, y/R, so optiland's unnormalised coefficient is C_mn = A_i / R^(m+n)), on the base
  ``base``. The linear terms (a tilt) and the xy term are not zero.
* ``rays``: image intercepts (mm) of a small lens traced by optiland (Newton tolerance
  1e-13, 200 iterations, no apertures, ideal media) from ``launch``: surface 1 the first
  15 terms (degree 4) on a conic, R = 6 mm; surface 2 all 27 terms on a sphere, R = 6.5 mm.
"""

from __future__ import annotations

import math

import numpy as np
import optiland.backend as be
from optiland.coordinate_system import CoordinateSystem
from optiland.geometries import PolynomialGeometry
from optiland.materials import IdealMaterial
from optiland.optic import Optic
from optiland.rays import RealRays

rng = np.random.default_rng(20261130)
POINTS = [[0.0, 0.0], [1.3, 0.0], [0.0, -2.1], [2.2, 1.7], [-3.1, 2.6], [3.9, -3.3],
          [-0.4, -4.6], [-4.2, -1.1]]
TERMS = (rng.normal(size=27) * 2e-3).round(6).tolist()
TERMS[0], TERMS[1], TERMS[3] = 0.012, -0.021, 0.0047  # tilt x, tilt y, the xy term
BASE = {"radius": 40.0, "conic": -0.6, "norm_radius": 5.0}
SURFACES = [  # radius, conic, norm_radius, number of terms, thickness, index after
    (40.0, -0.6, 6.0, 15, 4.0, 1.6),
    (-60.0, 0.0, 6.5, 27, 45.0, 1.0),
]


def powers(i):
    """(m, n) of Zemax's term i >= 1 (by degree, then by falling power of x)."""
    d = (math.isqrt(8 * i + 1) - 1) // 2
    n = i - d * (d + 1) // 2
    return d - n, n


def matrix(terms, norm_radius):
    """optiland's C[m][n] (coefficient of x^m y^n, unnormalised) of A_1 … A_N."""
    top = sum(powers(len(terms)))
    c = np.zeros((top + 1, top + 1))
    for i, a in enumerate(terms, start=1):
        m, n = powers(i)
        c[m, n] = a / norm_radius ** (m + n)
    return c.tolist()


def _normal(geom, x, y):
    nx, ny, nz = geom._surface_normal(be.array(x), be.array(y))
    return [float(-nx), float(-ny), float(-nz)]  # optiland's normal points toward −z


def sag_table(geom):
    return [[float(geom.sag(be.array(x), be.array(y)))] + _normal(geom, x, y)
            for x, y in POINTS]


LAUNCH_FIELDS = [(0.0, 0.0), (0.0, 4.0), (3.0, 0.0), (2.5, -3.5)]  # (θx, θy) degrees
LAUNCH_PUPIL = [(0.0, 0.0), (0.7, 0.0), (0.0, -0.7), (0.5, 0.6), (-0.9, -0.3)]  # × 4 mm


def launch():
    """Rays through the points of the pupil grid on z = 0, started back at z = −5 mm."""
    o, d = [], []
    for tx, ty in LAUNCH_FIELDS:
        v = np.array([np.tan(np.radians(tx)), np.tan(np.radians(ty)), 1.0])
        v /= np.linalg.norm(v)
        for px, py in LAUNCH_PUPIL:
            p = np.array([4 * px, 4 * py, 0.0])
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


def lens():
    optic = Optic()
    optic.surfaces.add(index=0, radius=be.inf, thickness=be.inf)
    for i, (r, k, rn, n_terms, t, n) in enumerate(SURFACES, start=1):
        optic.surfaces.add(index=i, surface_type="polynomial", radius=r, conic=k,
                           coefficients=matrix(TERMS[:n_terms], rn), thickness=t,
                           material=IdealMaterial(n=n), is_stop=i == 1)
    optic.surfaces.add(index=len(SURFACES) + 1)
    optic.set_aperture(aperture_type="EPD", value=8.0)
    optic.fields.set_type(field_type="angle")
    optic.fields.add(y=0.0)
    optic.wavelengths.add(value=0.5875618, is_primary=True)
    return optic


def main():
    geom = PolynomialGeometry(CoordinateSystem(), radius=BASE["radius"], conic=BASE["conic"],
                              coefficients=matrix(TERMS, BASE["norm_radius"]), tol=1e-13,
                              max_iter=200)
    o, d = launch()
    ref = {"points": POINTS, "terms": TERMS, "base": BASE,
           "surfaces": [list(s) for s in SURFACES], "sag": sag_table(geom),
           "launch": {"origin": o.tolist(), "direction": d.tolist()},
           "rays": trace(lens(), o, d)}
    print("REF = " + repr(ref))


if __name__ == "__main__":
    main()
