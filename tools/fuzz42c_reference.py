"""Round 42c reference writer: random systems of the surface kinds and frames that are not
rotationally symmetric (biconics, toroids, XY polynomials, Zernike sags with a decenter,
tilted and decentered elements between coordinate breaks, folds at 45° on plane and curved
mirrors) and Forbes Q-bfs aspheres, traced ray by ray by optiland 0.6.3.

Run with the optiland venv, never jaxlens's (jaxlens is not imported here)::

    /work/optenv/bin/python tools/fuzz42c_reference.py OUT_FOLDER [--n 49] [--seed 42]
        [--kind toric|freeform|tilted|folded|qbfs|grating|binary2|all] [--start 0]

and compare jaxlens with what it writes with ``tools/fuzz42c_compare.py`` (jaxlens's venv).

A system is a Zemax-like sequence (the file's ``surfaces``, surface 0 the object at
infinity, the last the image plane): refracting or reflecting surfaces and coordinate breaks,
each with the thickness after it and the medium after it (Cauchy index tables at the two
wavelengths, fuzz36b's ``cauchy``; after a mirror or a break, the medium before it). Each
class (``--kind``):

* ``toric``: singlets whose surfaces are biconics or toroids. The toroid is the general one
  (conic y–z profile with y², y⁴ terms, swept with radius 1/cx about an axis parallel to y:
  both programs define it as Zemax TOROIDAL). The biconic is drawn only where the two
  programs' definitions agree: jaxlens's is Zemax's (both sections under one square root),
  optiland 0.6.3's ``BiconicGeometry`` is the sum of the two section conics, and these are
  the same surface when one section is flat (c = 0 or cx = 0) or both are parabolas
  (k = kx = −1); a draw takes one of those three at random.
* ``freeform``: XY polynomials (Zemax extended polynomial: A_i on (x/R, y/R), degree 2 to 5,
  the linear and xy terms included; optiland's ``PolynomialGeometry`` takes C_mn =
  A_i / R^(m+n)) and Zernike sags (Noll, Zemax Standard, up to 28 terms, or Fringe up to 36:
  optiland's Fringe 37 is not Zemax's). Each is decentered: a Zernike sag on a flat base by
  its own decenter (jaxlens ``ZernikeSag(decenter_x, decenter_y)``; optiland has none, and on
  a flat base it is the whole surface moved, optiland's surface decenter, as
  tests/test_zernike_decenter.py established), an XY polynomial by a pair of coordinate
  breaks (decenter (dx, dy), the surface, decenter (−dx, −dy)).
* ``tilted``: a lens of singlets (spheres and even aspheres, or the toric or XY-polynomial
  surfaces above) with one or two elements tilted (up to 20° about each axis) and
  decentered (up to 0.3 of the pupil radius) between a break (order 0: decenter, then tilt
  about x, the new y, the new z; or order 1: tilt about z, the new y, the new x, then
  decenter) and its return break (order toggled, every parameter negated), and in half the
  draws an image plane tilted up to 15° about x and y.
* ``folded``: a singlet, a fold (a break tilted 45° about x or y, with up to ±5° more, a
  mirror: plane, sphere, conic, toroid or biconic, and the same break again, as in Zemax),
  negative thicknesses after it (a singlet in half the draws), and in a third of the draws
  a second fold (a periscope) that turns the light back to +z.
* ``qbfs``: Forbes Q-bfs aspheres on a conic base (jaxlens ``QTypeAsphere(qtype='bfs')``,
  optiland ``forbes_qbfs``, a_0 … a_M on its ``radial_terms``), with a decentered and tilted
  element in half the draws. optiland 0.6.3 has no Q-con (its Q-2D is another family). The
  two differ beyond the normalisation radius (u = r/ρ_n > 1): optiland sets the departure to
  0 there (a step in the surface), jaxlens evaluates the polynomials as they are (its
  docstring: ρ_n is meant to cover the clear aperture); the first draws of seed 42 met
  surfaces there (0.9 mm on the image), so a draw whose ray meets a Q-bfs surface at
  r >= ρ_n is refused (``beyond_qbfs_norm_radius``).

* ``grating``: a singlet, then a flat grating (jaxlens ``Grating(c=0)``, Zemax DGRATING: T
  lines/µm parallel to the local x axis, order M = ±1 or ±2, M·T 0.02 to 0.25 lines/µm;
  optiland ``grating`` with ``grating_period`` 1/T µm, ``groove_orientation_angle`` 0) on
  one face of a glass plate tilted (up to 15° about each axis) and decentered between a
  break and its return break. Only flat gratings: on a curved one optiland takes the local
  line spacing as Λ/|f_xy| (f the grating vector in the tangent plane), not the spacing of
  lines equally spaced in the x–y projection as Zemax and jaxlens (tools/
  grating_reference.py, tests/test_grating.py); on a plane the two are the same. No
  reflection gratings: optiland 0.6.3's flat reflection grating (``material="mirror"``)
  returns the reflected direction negated, through the mirror, at every tilt and order
  (order 0 included: a plain mirror's reflection, negated), which the first draws of this
  class (a reflection grating as a 45° fold mirror) met as rays going backward to the
  image; tests/test_fuzz_round42c.py checks jaxlens's reflection grating against the local
  grating equation in numpy instead.

* ``binary2``: singlets with one Zemax BINARY_2 face (jaxlens ``Binary2``: an even asphere
  carrying the phase Φ = M Σ A_i (r/R)^(2i), radians; A_1 that of a lens of focal length
  ±(1 … 5) L, A_2, A_3 5 % and 1 % of it, order −1, 1 or 2), half of them tilted and
  decentered between a break and its return break. optiland: the even asphere with a
  ``RadialPhaseProfile`` (``phase_profile``: Φ = Σ a_i r^(2i), r in mm, so
  a_i = M A_i / R^(2i)), its phase interaction (the tangential part of n·k0·d gains the
  surface gradient of Φ, k0 = 2π/λ with λ in mm: jaxlens's rule).

Not drawn: curved gratings and Q-con (above), a general biconic (above).

The frames: optiland places every surface by an absolute position and rotation
(``x, y, z, rx, ry, rz``; its rotation is R = Rz(rz)·Ry(ry)·Rx(rx), applied as optiland's
``RealRays.rotate_x`` etc.: right-handed, a positive rx turning +z toward −y). A break is
built as optiland's Zemax reader builds one, a chain of optiland ``CoordinateSystem`` objects
each referring to the one before (``get_effective_transform``), but one elementary step a
link, in Zemax's order (order 0: decenter, Rx, Ry, Rz; order 1: Rz, Ry, Rx, decenter), so
the chain's rotation is Zemax's Rx·Ry·Rz (optiland's reader puts all three tilts in one
CoordinateSystem, whose Rz·Ry·Rx is Zemax's order only for one tilt at a time); each
surface gets the chain's effective transform (as Euler angles, checked to rebuild the
rotation to 1e-14), the thickness after it a translation along the chain's current z.

Rays: no ray generation of either program is used (an entrance pupil of a folded or tilted
system is another question). Each field (θx, θy) in degrees gives the direction
(tan θx, tan θy, 1)/norm; each pupil point (Px, Py) the point (Px, Py)·EPD/2 of the plane
z = 0 (surface 1's vertex plane before any break); the ray starts one length scale L back
along its direction. Four fields (0, 0), (0, θ), (0.8θ, 0), (−0.6θ, 0.7θ), θ 3° to 20°
(halved where a ray fails, below), and nine pupil
points (``PUPIL``) at two wavelengths: 72 rays a case. optiland traces them
(``surface_group.trace(rays, skip=1)``, Newton tolerance 1e-13, 200 iterations, no
apertures); the image intercept and direction are stored in global coordinates (surface 1's
frame). A draw is refused (counted by reason in ``summary.json``) when a ray fails (NaN,
total internal reflection), goes backward along its line to a surface (a negative
propagation distance), or meets a surface where optiland's Newton residual |sag − z| in
the surface's frame exceeds 1e-10 mm; the field and the pupil are halved up to four times
first.
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
import optiland.backend as be  # noqa: E402
from optiland.coordinate_system import CoordinateSystem  # noqa: E402
from optiland.optic import Optic  # noqa: E402
from optiland.phase.radial import RadialPhaseProfile  # noqa: E402
from optiland.rays import RealRays  # noqa: E402

KINDS = ("toric", "freeform", "tilted", "folded", "qbfs", "grating", "binary2")
WLS = [587.5618, 486.1327]  # nm, the primary first
PUPIL = [(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.6, 0.6),
         (-0.7, 0.4), (0.3, -0.8), (-0.45, -0.55)]
NEWTON_TOL = 1e-13
RESIDUAL_MAX = 1e-10
Refused = f36.Refused


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:  # noqa: BLE001
        return None


# ---------------------------------------------------------------------------------- draws
def glass(rng):
    nd, vd = float(rng.uniform(1.46, 1.85)), float(rng.uniform(25.0, 70.0))
    return dict(material=f"cauchy_{nd:.4f}_{vd:.1f}", n=f36.cauchy(nd, vd, WLS))


AIR = dict(material="air", n=[1.0, 1.0])


def surf(kind, t, med, **p):
    return dict(type=kind, thickness=float(t), material=med["material"], n=list(med["n"]), **p)


def cbreak(t, med, dx=0.0, dy=0.0, tx=0.0, ty=0.0, tz=0.0, order=0):
    return surf("coordinate_break", t, med, decenter_x=float(dx), decenter_y=float(dy),
                tilt_x=float(tx), tilt_y=float(ty), tilt_z=float(tz), order=int(order))


def inverse(cb, t, med):
    """The return break: order toggled, every parameter negated."""
    return cbreak(t, med, -cb["decenter_x"], -cb["decenter_y"], -cb["tilt_x"], -cb["tilt_y"],
                  -cb["tilt_z"], 1 - cb["order"])


def curv(rng, L, top=1.2):
    return float(rng.uniform(-top, top) / L)


def std(rng, L, t, med, asphere=False, a=1.0):
    p = dict(curvature=curv(rng, L), conic=float(rng.uniform(-1.5, 1.0)))
    if asphere:
        p["even_asphere_coeffs"] = [0.0, float(rng.normal() * 2e-3 / a**3),
                                    float(rng.normal() * 5e-4 / a**5)]
        return surf("even_asphere", t, med, **p)
    return surf("standard", t, med, **p)


def toric_surface(rng, L, a, t, med):
    if rng.random() < 0.5:  # a toroid
        cx = float(rng.uniform(-0.8, 0.8) / (2.0 * a))
        return surf("toroidal", t, med, curvature=curv(rng, L), conic=float(rng.uniform(-1, 1)),
                    coeffs=[float(rng.normal() * 2e-3 / a), float(rng.normal() * 2e-4 / a**3)],
                    curvature_x=cx)
    mode = rng.choice(["flat_x", "flat_y", "parabolic"])
    c, cx = curv(rng, L), curv(rng, L)
    k, kx = float(rng.uniform(-1.5, 1.0)), float(rng.uniform(-1.5, 1.0))
    if mode == "flat_x":
        cx = 0.0
    elif mode == "flat_y":
        c = 0.0
    else:
        k = kx = -1.0
    return surf("biconic", t, med, curvature=c, conic=k, curvature_x=cx, conic_x=kx,
                biconic_mode=str(mode))


def xy_surface(rng, L, a, t, med):
    deg = int(rng.integers(2, 6))
    n_terms = (deg + 1) * (deg + 2) // 2 - 1
    co = (rng.normal(size=n_terms) * 6e-3 * a).tolist()
    co[0], co[1] = float(rng.normal() * 0.03 * a), float(rng.normal() * 0.03 * a)
    return surf("xy_polynomial", t, med, curvature=curv(rng, L), conic=float(rng.uniform(-1, 1)),
                coeffs=[float(v) for v in co], norm_radius=float(a * rng.uniform(1.3, 2.0)))


def zernike_surface(rng, L, a, t, med):
    ordering = "standard" if rng.random() < 0.5 else "fringe"
    n = int(rng.integers(6, 29 if ordering == "standard" else 37))
    z = (rng.normal(size=n) * 5e-3 * a).tolist()
    z[3] = float(rng.uniform(-0.08, 0.08) * a)  # defocus: some power
    dx, dy = (float(v) for v in rng.uniform(-0.3, 0.3, 2) * a)
    return surf("zernike", t, med, curvature=0.0, conic=0.0, ordering=ordering,
                zernike=[float(v) for v in z], norm_radius=float(a * rng.uniform(2.2, 3.0)),
                decenter_x=dx, decenter_y=dy)


def qbfs_surface(rng, L, a, t, med):
    m = int(rng.integers(1, 6))
    co = (rng.normal(size=m + 1) * 2e-3 * a).tolist()
    return surf("qbfs", t, med, curvature=curv(rng, L), conic=float(rng.uniform(-1.2, 0.8)),
                coeffs=[float(v) for v in co], norm_radius=float(a * rng.uniform(1.8, 2.6)))


def grating_surface(rng, t, med):
    """A flat grating (Zemax DGRATING on a plane): T lines/µm along local y, order ±1 or ±2."""
    order = int(rng.choice([-2, -1, -1, 1, 1, 2]))
    return surf("grating", t, med, curvature=0.0, conic=0.0,
                lines_per_um=float(rng.uniform(0.02, 0.25) / abs(order)), order=order)


def binary2_surface(rng, L, a, t, med):
    """Zemax BINARY_2: an even asphere with the phase M Σ A_i (r/R)^(2i), A_1 of a lens of
    focal length ±(1 … 5) L at the primary wavelength."""
    order = int(rng.choice([-1, 1, 1, 2]))
    rn = float(a * rng.uniform(1.0, 2.0))
    f = float(rng.choice([-1, 1]) * rng.uniform(1.0, 5.0) * L)
    a1 = -math.pi * rn * rn / (WLS[0] * 1e-6 * f) / order
    co = [a1, float(rng.normal() * 0.05 * abs(a1)), float(rng.normal() * 0.01 * abs(a1))]
    return surf("binary2", t, med, curvature=curv(rng, L), conic=float(rng.uniform(-1, 0.5)),
                even_asphere_coeffs=[0.0, float(rng.normal() * 1e-3 / a**3)], order=order,
                norm_radius=rn, phase_coeffs=co)


def singlet(rng, L, a, make, gap, glass_med, after=AIR):
    """Two surfaces made by ``make(rng, L, a, t, med)`` (None: a sphere or even asphere)."""
    t = float(rng.uniform(0.04, 0.12) * L)
    mk = make or (lambda r, L_, a_, t_, m_: std(r, L_, t_, m_, asphere=r.random() < 0.4, a=a_))
    return [mk(rng, L, a, t, glass_med), mk(rng, L, a, gap, after)]


def draw(rng, kind):
    L = float(rng.uniform(20.0, 80.0))
    epd = float(L * rng.uniform(0.1, 0.22))
    a = epd / 2
    rows = []
    gap = lambda: float(rng.uniform(0.05, 0.2) * L)  # noqa: E731
    if kind == "toric":
        for _ in range(int(rng.integers(1, 3))):
            rows += singlet(rng, L, a, toric_surface, gap(), glass(rng))
    elif kind == "qbfs":
        for _ in range(int(rng.integers(1, 3))):
            rows += singlet(rng, L, a, qbfs_surface, gap(), glass(rng))
        if rng.random() < 0.5:
            cb = cbreak(0.0, AIR, *(rng.uniform(-0.2, 0.2, 2) * a), *rng.uniform(-12, 12, 3),
                        order=int(rng.integers(0, 2)))
            rows = [cb] + rows[:2] + [inverse(cb, 0.0, AIR)] + rows[2:]
    elif kind == "freeform":
        makers = [xy_surface, zernike_surface]
        for _ in range(int(rng.integers(1, 3))):
            g = glass(rng)
            t = float(rng.uniform(0.05, 0.12) * L)
            first, second = (makers[int(rng.integers(0, 2))] for _ in range(2))
            for mk, tt, med in ((first, t, g), (second, gap(), AIR)):
                s = mk(rng, L, a, tt, med)
                if s["type"] == "xy_polynomial":  # decentered by a pair of breaks
                    dx, dy = rng.uniform(-0.3, 0.3, 2) * a
                    prev = rows[-1] if rows else AIR  # the medium before the break
                    cb = cbreak(0.0, dict(material=prev["material"], n=prev["n"]), dx, dy)
                    s_t = s["thickness"]
                    s["thickness"] = 0.0
                    rows += [cb, s, inverse(cb, s_t, med)]
                else:
                    rows.append(s)
    elif kind == "tilted":
        n_el = int(rng.integers(1, 4))
        tilted = set(rng.choice(n_el, size=int(rng.integers(1, min(2, n_el) + 1)), replace=False))
        for e in range(n_el):
            maker = [None, None, toric_surface, xy_surface][int(rng.integers(0, 4))]
            el = singlet(rng, L, a, maker, gap(), glass(rng))
            if e in tilted:
                cb = cbreak(0.0, AIR, *(rng.uniform(-0.3, 0.3, 2) * a),
                            *rng.uniform(-20, 20, 3), order=int(rng.integers(0, 2)))
                g = el[1]["thickness"]
                el[1]["thickness"] = 0.0
                el = [cb] + el + [inverse(cb, g, AIR)]
            rows += el
    elif kind == "grating":
        rows += singlet(rng, L, a, None, gap(), glass(rng))
        g = glass(rng)  # a tilted, decentered plate with a grating on one face
        t = float(rng.uniform(0.03, 0.08) * L)
        plate = [surf("standard", t, g, curvature=0.0, conic=0.0),
                 surf("standard", gap(), AIR, curvature=0.0, conic=0.0)]
        side = int(rng.integers(0, 2))
        plate[side] = grating_surface(rng, plate[side]["thickness"], g if side == 0 else AIR)
        cb = cbreak(0.0, AIR, *(rng.uniform(-0.3, 0.3, 2) * a), *rng.uniform(-15, 15, 3),
                    order=int(rng.integers(0, 2)))
        g_after = plate[1]["thickness"]
        plate[1]["thickness"] = 0.0
        rows += [cb, *plate, inverse(cb, g_after, AIR)]
    elif kind == "binary2":
        for _ in range(int(rng.integers(1, 3))):
            el = singlet(rng, L, a, None, gap(), glass(rng))
            side = int(rng.integers(0, 2))
            el[side] = binary2_surface(rng, L, a, el[side]["thickness"],
                                       dict(material=el[side]["material"], n=el[side]["n"]))
            if rng.random() < 0.5:
                cb = cbreak(0.0, AIR, *(rng.uniform(-0.3, 0.3, 2) * a),
                            *rng.uniform(-15, 15, 3), order=int(rng.integers(0, 2)))
                g_after = el[1]["thickness"]
                el[1]["thickness"] = 0.0
                el = [cb, *el, inverse(cb, g_after, AIR)]
            rows += el
    elif kind == "folded":
        rows += singlet(rng, L, a, None, float(rng.uniform(0.1, 0.3) * L), glass(rng))
        sense = 1.0
        for fold in range(1 if rng.random() < 0.67 else 2):
            axis = int(rng.integers(0, 2))
            tilt = [0.0, 0.0, 0.0]
            tilt[axis] = float(rng.choice([-45.0, 45.0]) + rng.uniform(-5, 5))
            cb = cbreak(0.0, AIR, tx=tilt[0], ty=tilt[1])
            m = rng.choice(["plane", "sphere", "conic", "toric"])
            if m == "plane":
                mirror = surf("standard", 0.0, AIR, curvature=0.0, conic=0.0)
            elif m == "toric":
                mirror = toric_surface(rng, L, a, 0.0, AIR)
                mirror["curvature"] *= 0.3
                mirror["curvature_x"] *= 0.3
            else:
                mirror = surf("standard", 0.0, AIR, curvature=curv(rng, L, 0.3),
                              conic=0.0 if m == "sphere" else float(rng.uniform(-1.5, 1)))
            mirror["mirror"] = True
            sense = -sense
            d = float(rng.uniform(0.15, 0.4) * L) * sense
            rows += [cb, mirror, cbreak(d, AIR, tx=tilt[0], ty=tilt[1])]
            if fold == 0 and rng.random() < 0.5:
                el = singlet(rng, L, a, None, float(rng.uniform(0.1, 0.3) * L) * sense,
                             glass(rng))
                el[0]["thickness"] *= sense
                rows += el
    img_tilt = kind == "tilted" and rng.random() < 0.5
    last = rows[-1]
    last["thickness"] = float(rng.uniform(0.4, 1.2) * L) * (
        np.sign(last["thickness"]) if last["thickness"] else 1.0)
    if img_tilt:
        rows.append(cbreak(0.0, AIR, tx=rng.uniform(-15, 15), ty=rng.uniform(-15, 15)))
    stop = next(i for i, r in enumerate(rows) if r["type"] != "coordinate_break")
    rows[stop]["is_stop"] = True
    theta = float(rng.uniform(3.0, 20.0))
    return dict(L=L, epd=epd, rows=rows, theta=theta)


# ------------------------------------------------------------------------ optiland model
class Chain:
    """The running frame: a chain of optiland CoordinateSystems, one step a link."""

    def __init__(self):
        self.cs = None

    def link(self, **kw):
        self.cs = CoordinateSystem(reference_cs=self.cs, **kw)

    def apply_break(self, r):
        d = dict(x=r["decenter_x"], y=r["decenter_y"])
        rots = [dict(rx=math.radians(r["tilt_x"])), dict(ry=math.radians(r["tilt_y"])),
                dict(rz=math.radians(r["tilt_z"]))]
        steps = [d, *rots] if r["order"] == 0 else [*rots[::-1], d]
        for s in steps:
            self.link(**s)

    def placement(self, dx=0.0, dy=0.0):
        """x, y, z, rx, ry, rz of a surface at the chain's frame (moved by (dx, dy) in it)."""
        cs = CoordinateSystem(x=dx, y=dy, reference_cs=self.cs)
        t, rot = cs.get_effective_transform()
        rx, ry, rz = cs.get_effective_rotation_euler()
        back = CoordinateSystem(rx=rx, ry=ry, rz=rz).get_rotation_matrix()
        assert np.abs(np.asarray(back) - np.asarray(rot)).max() < 1e-14
        t = np.asarray(t, float)
        return dict(x=float(t[0]), y=float(t[1]), z=float(t[2]), rx=float(rx), ry=float(ry),
                    rz=float(rz))


def optic_of(sys_):
    op = Optic()
    op.surfaces.add(index=0, radius=be.inf, thickness=be.inf)
    chain = Chain()
    chain.link()  # surface 1's frame: the global one
    idx = 1
    nr = dict(tol=NEWTON_TOL, max_iter=200)
    for r in sys_["rows"]:
        if r["type"] == "coordinate_break":
            chain.apply_break(r)
            chain.link(z=r["thickness"])
            continue
        mat = "mirror" if r.get("mirror") else (
            "air" if r["material"] == "air" else f36.TableMaterial(WLS, r["n"]))
        t = r["type"]
        c = r.get("curvature", 0.0)
        radius = be.inf if c == 0 else 1.0 / c
        kw = dict(index=idx, material=mat, is_stop=bool(r.get("is_stop")))
        if t == "standard":
            kw.update(surface_type="standard", radius=radius, conic=r["conic"])
        elif t == "even_asphere":
            kw.update(surface_type="even_asphere", radius=radius, conic=r["conic"],
                      coefficients=list(r["even_asphere_coeffs"]), **nr)
        elif t == "biconic":
            cx = r["curvature_x"]
            kw.update(surface_type="biconic", radius_y=radius,
                      radius_x=be.inf if cx == 0 else 1.0 / cx, conic_y=r["conic"],
                      conic_x=r["conic_x"], **nr)
        elif t == "toroidal":
            cx = r["curvature_x"]
            kw.update(surface_type="toroidal", radius_y=radius,
                      radius_x=be.inf if cx == 0 else 1.0 / cx, conic=r["conic"],
                      toroidal_coeffs_poly_y=list(r["coeffs"]), **nr)
        elif t == "xy_polynomial":
            kw.update(surface_type="polynomial", radius=radius, conic=r["conic"],
                      coefficients=xy_matrix(r["coeffs"], r["norm_radius"]), **nr)
        elif t == "zernike":
            assert c == 0 and r["conic"] == 0  # a flat base: the decenter moves the surface
            kw.update(surface_type="zernike", radius=be.inf, conic=0.0,
                      coefficients=list(r["zernike"]), norm_radius=r["norm_radius"],
                      zernike_type="noll" if r["ordering"] == "standard" else "fringe", **nr)
        elif t == "grating":
            kw.update(surface_type="grating", radius=be.inf, conic=0.0,
                      grating_period=1.0 / r["lines_per_um"], grating_order=r["order"],
                      groove_orientation_angle=0.0)
        elif t == "binary2":
            rn, m = r["norm_radius"], r["order"]
            kw.update(surface_type="even_asphere", radius=radius, conic=r["conic"],
                      coefficients=list(r["even_asphere_coeffs"]), **nr,
                      phase_profile=RadialPhaseProfile(
                          [m * v / rn ** (2 * i) for i, v in enumerate(r["phase_coeffs"], 1)]))
        elif t == "qbfs":
            kw.update(surface_type="forbes_qbfs", radius=radius, conic=r["conic"],
                      radial_terms=dict(enumerate(r["coeffs"])), norm_radius=r["norm_radius"],
                      **nr)
        else:
            raise ValueError(t)
        place = chain.placement(r.get("decenter_x", 0.0), r.get("decenter_y", 0.0)) \
            if t == "zernike" else chain.placement()
        op.surfaces.add(**kw, **place)
        chain.link(z=r["thickness"])
        idx += 1
    op.surfaces.add(index=idx, **chain.placement())  # the image plane
    for s in op.surfaces.surfaces:
        s.aperture = None
        g = s.geometry
        if hasattr(g, "tol"):
            g.tol, g.max_iter = NEWTON_TOL, 200
    return op


def xy_powers(i):
    """(m, n) of Zemax's extended-polynomial term i >= 1 (by degree, falling power of x)."""
    d = (math.isqrt(8 * i + 1) - 1) // 2
    n = i - d * (d + 1) // 2
    return d - n, n


def xy_matrix(terms, norm_radius):
    """optiland's C[m][n] (coefficient of x^m y^n, unnormalised) of A_1 … A_N."""
    top = sum(xy_powers(len(terms)))
    c = np.zeros((top + 1, top + 1))
    for i, a in enumerate(terms, start=1):
        m, n = xy_powers(i)
        c[m, n] = a / norm_radius ** (m + n)
    return c.tolist()


# ---------------------------------------------------------------------------- the rays
def fields_of(theta):
    return [(0.0, 0.0), (0.0, theta), (0.8 * theta, 0.0), (-0.6 * theta, 0.7 * theta)]


def launch(fields, radius, back):
    o, d = [], []
    for tx, ty in fields:
        v = np.array([math.tan(math.radians(tx)), math.tan(math.radians(ty)), 1.0])
        v /= np.linalg.norm(v)
        for px, py in PUPIL:
            o.append(np.array([px * radius, py * radius, 0.0]) - back * v)
            d.append(v)
    return np.array(o), np.array(d)


def trace(op, o, d, w):
    n = len(o)
    rays = RealRays(*o.T.copy(), *d.T.copy(), np.ones(n), np.full(n, w / 1000.0))
    try:
        op.surfaces.trace(rays, skip=1)
    except ValueError as e:  # optiland's Zernike refuses a point beyond its square
        raise Refused("optiland_domain", str(e)[:100]) from e
    out = np.stack([np.asarray(v, float) for v in (rays.x, rays.y, rays.z, rays.L, rays.M,
                                                   rays.N)], 1)
    if not np.all(np.isfinite(out)):
        raise Refused("miss_or_tir", "")
    sg = op.surfaces
    pts = np.stack([np.asarray(sg.x, float), np.asarray(sg.y, float),
                    np.asarray(sg.z, float)], -1)  # surfaces 1 .. image, [S, N, 3]
    dirs = np.stack([np.asarray(sg.L, float), np.asarray(sg.M, float),
                     np.asarray(sg.N, float)], -1)
    assert len(pts) == len(sg.surfaces) - 1  # skip=1: the object surface is not recorded
    if not (np.all(np.isfinite(pts)) and np.all(np.isfinite(dirs))):
        raise Refused("miss_or_tir", "")
    # forward along every segment: the launch point to surface 1, then surface to surface
    prev_p, prev_d = o, d
    for i in range(len(pts)):
        step = np.sum((pts[i] - prev_p) * prev_d, -1)
        if np.any(step < -1e-9):
            raise Refused("backward", f"surface {i + 1}")
        prev_p, prev_d = pts[i], dirs[i]
    # optiland's Newton residual, in each surface's own frame
    for i, s in enumerate(sg.surfaces[1:]):
        p = RealRays(*pts[i].T.copy(), *dirs[i].T.copy(), np.ones(n), np.full(n, w / 1000))
        s.geometry.cs.localize(p)
        x, y, z = (np.asarray(v, float) for v in (p.x, p.y, p.z))
        res = np.abs(np.asarray(s.geometry.sag(be.array(x), be.array(y)), float) - z)
        if not np.all(res <= RESIDUAL_MAX):
            raise Refused("newton_residual", f"surface {i + 1}: {res.max():.2e}")
        if type(s.geometry).__name__ == "ForbesQNormalSlopeGeometry" and not np.all(
                x * x + y * y < float(s.geometry.norm_radius) ** 2):
            raise Refused("beyond_qbfs_norm_radius", f"surface {i + 1}")
    return out


def all_rays(op, fields, radius, L):
    o, d = launch(fields, radius, L)
    ims = [trace(op, o, d, w) for w in WLS]
    return o, d, ims


def build(idx, seed, kind):
    t0 = time.time()
    rng = np.random.default_rng([seed, idx])
    sys_ = draw(rng, kind)
    try:
        op = optic_of(sys_)
    except Refused:
        raise
    except Exception as e:  # noqa: BLE001
        raise Refused("optiland_error", repr(e)[:200]) from e
    theta, radius, last = sys_["theta"], sys_["epd"] / 2, None
    for _ in range(5):
        fields = fields_of(theta)
        try:
            o, d, ims = all_rays(op, fields, radius, sys_["L"])
            break
        except Refused as e:
            last = e
            theta, radius = theta / 2, radius / 2
    else:
        raise last
    rays = []
    for w, im in zip(WLS, ims, strict=True):
        for k in range(len(o)):
            f = fields[k // len(PUPIL)]
            p = PUPIL[k % len(PUPIL)]
            rays.append(dict(field=list(f), pupil=list(p), wavelength_nm=w,
                             launch=[*o[k].tolist(), *d[k].tolist()], image=im[k].tolist()))
    rows = [dict(index=0, type="object", thickness="inf", material="air", n=wl_map([1.0, 1.0]))]
    for i, r in enumerate(sys_["rows"], start=1):
        rows.append(dict(index=i, **{k: (wl_map(v) if k == "n" else v) for k, v in r.items()}))
    rows.append(dict(index=len(rows), type="image", curvature=0.0))
    return dict(
        name=f"fuzz42c_{kind}_{idx:03d}",
        kind=kind,
        description=f"random system {idx} of tools/fuzz42c_reference.py ({kind}), seed {seed}",
        generator=dict(script="tools/fuzz42c_reference.py", seed=seed, draw=idx, kind=kind,
                       optiland=_version("optiland"), numpy=np.__version__,
                       python=platform.python_version(), optiland_newton_tol=NEWTON_TOL),
        length_scale_mm=sys_["L"],
        surfaces=rows,
        wavelengths_nm=WLS,
        primary_wavelength_nm=WLS[0],
        aperture=dict(EPD=sys_["epd"]),
        launch=dict(pupil_radius_mm=radius, start_back_mm=sys_["L"],
                    note="origin (Px, Py)·pupil_radius on z = 0 minus start_back along the "
                         "direction (tan θx, tan θy, 1)/norm; global frame (surface 1's)"),
        fields=dict(type="angle_deg_xy", values=[list(f) for f in fields]),
        pupil=[list(p) for p in PUPIL],
        ray_columns="launch: x y z L M N; image: x y z L M N (global, optiland)",
        real_rays=rays,
        build_seconds=round(time.time() - t0, 2),
    )


def wl_map(vals):
    return {str(w): float(v) for w, v in zip(WLS, vals, strict=True)}


def lenses(out, n, seed, kinds, start):
    summary = dict(seed=seed, kinds=list(kinds), drawn=0, accepted=[], refused={})
    for i in range(start, start + n):
        kind = kinds[i % len(kinds)]
        summary["drawn"] += 1
        try:
            js = build(i, seed, kind)
        except Refused as e:
            summary["refused"].setdefault(f"{kind}:{e.reason}", []).append(i)
            print(f"{i:3d} {kind} refused {e}"[:200], flush=True)
            continue
        (out / f"{js['name']}.json").write_text(json.dumps(js, separators=(",", ":")) + "\n")
        summary["accepted"].append(js["name"])
        print(f"{i:3d} ok {js['build_seconds']:5.1f}s {js['name']} "
              f"{len(js['surfaces']) - 2} surfaces, θ {js['fields']['values'][1][1]:.2f}°",
              flush=True)
    (out / f"summary_{start}_{start + n - 1}.json").write_text(json.dumps(summary, indent=1)
                                                              + "\n")
    print(f"drawn {summary['drawn']}, accepted {len(summary['accepted'])}, refused "
          + ", ".join(f"{k} {len(v)}" for k, v in summary["refused"].items()))


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz42c_reference.py", description=__doc__.splitlines()[0])
    ap.add_argument("out", help="folder for the files (created)")
    ap.add_argument("--n", type=int, default=49, help="systems to draw (default 49)")
    ap.add_argument("--seed", type=int, default=42, help="seed (default 42)")
    ap.add_argument("--start", type=int, default=0, help="first draw index (default 0)")
    ap.add_argument("--kind", choices=(*KINDS, "all"), default="all",
                    help="the class (default all: draw i gets KINDS[i % 7])")
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error(f"--n must be >= 1, got {args.n}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        ap.error(f"OUT {out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    lenses(out, args.n, args.seed, KINDS if args.kind == "all" else (args.kind,), args.start)


if __name__ == "__main__":
    main(sys.argv[1:])
