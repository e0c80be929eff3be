"""Wavefront-side reference numbers from optiland 0.6.3 for tests/test_accuracy_round40c.py:
an object-space telecentric lens, virtual objects, and a plastic even-asphere lens whose image
surface is curved and lies in glass.

Run with the optiland environment's interpreter, from the repository root (jaxlens is not
imported):

    /work/optenv/bin/python tools/acc40c_reference.py

writes tests/data/acc40c_optiland.json. The lenses:

- ``tele_doublet_obna``, ``tele_triplet_floa``: tests/data/zmx38a's object-space telecentric
  files, built through optiland's own telecentric API exactly as
  tools/telecentric38a_reference.py builds them (its ``build``; the NA and object heights
  are that tool's, stored in tests/data/zmx38a_optiland.json);
- ``tele_doublet_x20``: tele_doublet_obna with every length times 20 and NA 0.01, object
  heights (0, 0), (0, 100) and (60, 100) mm (heights past 90 mm, one off both axes), written
  here to tests/data/acc40c/tele_doublet_x20.zmx;
- ``virtual_singlet_angles``, ``virtual_stop_behind``: tests/data/zmx_corpus7's
  virtual-object files (negative object thickness), read by optiland's .zmx reader as
  tools/corpus7_reference.py reads them;
- ``virtual_stop_behind_aimed``: the same with real ray aiming (optiland's iterative aiming,
  jaxlens's ``aim="real_marginal"``): OPD and grid statistics only;
- ``plastic_curved_immersed_image``: tests/refcases_extra's case (E48R even aspheres with
  conics and A2..A12, an N-SF11 element in contact with an image surface of R = 12 mm), built
  from the case file with optiland's catalogue glasses the file names. The image surface's
  medium is given as N-SF11 too: the image lies in glass, and the reference sphere with it
  (the case file's air after the image surface is an artefact of its ray data; jaxlens ends
  its trace in image space, where that refraction does not happen).

For each lens, field and wavelength (every wavelength of the lens), with optiland's
"chief_ray" strategy (the reference sphere centred on the chief ray's image-surface
intercept, through the paraxial exit pupil at the primary wavelength; OPD positive where the
wavefront is ahead of the sphere; the chief ray traced at the wavelength analysed):

- ``opd``: OPD in waves at the pupil points ``POINTS`` (the tangential fan (0, t) and the
  sagittal fan (t, 0), t in ``FAN``, then a few skew points);
- ``grid``: the OPD over optiland's "uniform" grid of ``GRID`` × ``GRID`` points over
  [-1, 1]² cut to the unit disc (Px² + Py² <= 1): its RMS and P-V with the mean removed,
  with the least-squares plane a + b·Px + c·Py removed, the number of points, 15 Noll
  Zernike terms (``optiland.zernike.ZernikeFit``), at the primary wavelength;
- ``exit_pupil``: the paraxial exit pupil's global z and diameter (optiland's XPL, XPD; for
  the A2 lens an independent y-nu trace with paraxial curvature c + 2·A2, see below); the
  working F/# 1/(2 n′u′) and the paraxial marginal ray's height at the stop;
- ``ray_fan``: image-surface (x, y) of the fan rays minus the chief ray's (primary);
- ``mtf``: the |OTF| of optiland's rays (``ray_otf``) on jaxlens's geometric-PSF pupil grid
  cut to the unit pupil (Px² + Py² <= 1, optiland's and Zemax's beam, no stop clipping: the
  system aperture bounds the beam, ``imaging.radiometry.in_pupil``, round 44a; before it the
  stop clipped the overfilled beam at the paraxial marginal ray's height, jaxlens's former
  ``aiming.apertured``), at ``MTF_FREQS`` cycles/mm; ``optiland_geometric_mtf`` is optiland's
  own GeometricMTF (the same unit-pupil beam, histogram line spread), for comparison only;
- ``coherent_centre_strehl`` (x20 doublet, immersed lens): the coherent PSF at the chief
  ray's image point over the unaberrated peak by jaxlens's ray-based Debye sum on optiland's
  rays (``coherent_centre_strehl``), and the geometric encircled energy of the rays
  through ``POINTS`` about their centroid (``encircled``).

Two places where optiland's numbers are corrected here, each recorded beside the raw one:

- optiland's ``chief_ray`` strategy takes the image-space index at the primary wavelength
  for every wavelength (``ReferenceStrategy.n_image``). The path from the reference sphere
  to the image surface runs in image space at the wavelength analysed, so where image space
  is not air the OPD of another wavelength is computed with that wavelength's index
  (``opd`` is with n(λ); ``opd_optiland_primary_index`` is optiland's own);
- optiland's paraxial trace leaves the A2 (r²) term out, which moves the paraxial exit pupil
  of the A2 lens (global z = -7.428 mm instead of -7.252 mm; this tool's y-nu trace with
  A2 set to 0 gives optiland's value to 1e-15 mm). Its strategy's exit pupil point is
  replaced by the independent y-nu trace's (``exit_pupil.optiland_z``, ``optiland_xpl``
  and ``optiland_xpd`` keep optiland's).
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import warnings
from importlib.metadata import version

import numpy as np
from optiland import optic as optic_mod
from optiland.distribution import BaseDistribution, create_distribution
from optiland.fileio import load_zemax_file
from optiland.materials import Material
from optiland.mtf import GeometricMTF
from optiland.physical_apertures import RadialAperture
from optiland.wavefront.strategy import create_strategy
from optiland.zernike import ZernikeFit

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import telecentric38a_reference as tele  # noqa: E402

OUT = ROOT / "tests" / "data" / "acc40c_optiland.json"
ZMX_DIR = ROOT / "tests" / "data" / "acc40c"
SCALE = 20.0
FAN = tuple(round(-1.0 + 0.2 * i, 10) for i in range(11))
SKEW = ((0.6, 0.6), (-0.3, 0.7), (0.5, -0.8), (0.7071, 0.7071))
POINTS = tuple((0.0, t) for t in FAN) + tuple((t, 0.0) for t in FAN) + SKEW
GRID = 33
ZERNIKE_TERMS = 15
MTF_CELLS = 64
MTF_FREQS = {"tele_doublet_obna": (1.0, 2.0, 5.0, 10.0),
             "tele_triplet_floa": (5.0, 10.0, 20.0, 50.0),
             "virtual_singlet_angles": (0.25, 0.5, 1.0, 2.0),
             "virtual_stop_behind": (0.1, 0.25, 0.5, 1.0),
             "tele_doublet_x20": (0.5, 1.0, 2.0, 5.0),
             "plastic_curved_immersed_image": (10.0, 25.0, 50.0, 100.0)}
MTF_OVERFILL = 1.25
NEWTON_TOL = 1e-15


class Points(BaseDistribution):
    """optiland distribution holding exactly ``POINTS``."""

    def generate_points(self, num_points):
        self.x = np.array([p[0] for p in POINTS])
        self.y = np.array([p[1] for p in POINTS])


def tight(op):
    for s in op.surface_group.surfaces:
        if hasattr(s.geometry, "tol"):
            s.geometry.tol = NEWTON_TOL


# --------------------------------------------------------------------------------------
# The lenses
# --------------------------------------------------------------------------------------
def telecentric(name):
    ref = json.loads((ROOT / "tests" / "data" / "zmx38a_optiland.json").read_text())
    s = tele.SYSTEMS[name]
    r = ref["systems"][name]
    heights = [tuple(h) for h in r["object_heights"]]
    op = tele.build(s, r["object_na"], heights)
    rmax = max(math.hypot(*h) for h in heights)
    fields = [[hx / rmax, hy / rmax] for hx, hy in heights]
    return op, fields, [list(h) for h in heights], "object heights (x, y), mm"


def scaled_telecentric():
    """tele_doublet_obna with every length times ``SCALE`` and NA 0.01: object heights of
    100 mm and more, an (x, y) height off both axes. Written to tests/data/acc40c/ as a .zmx
    file (tools/telecentric38a_reference.py's writer) for jaxlens to read."""
    base = tele.SYSTEMS["tele_doublet_obna"]
    s = dict(base, object_distance=base["object_distance"] * SCALE,
             aperture=("OBNA", 0.01, 0), fields=[(0.0, 0.0), (0.0, 100.0), (60.0, 100.0)],
             surfaces=[(c / SCALE, t * SCALE, g, stop, sd * SCALE)
                       for c, t, g, stop, sd in base["surfaces"]])
    ZMX_DIR.mkdir(parents=True, exist_ok=True)
    text = tele.zmx_text("tele_doublet_x20", s).replace(
        "Written by tools/telecentric38a_reference.py",
        "Written by tools/acc40c_reference.py (tele_doublet_obna x 20, NA 0.01)")
    (ZMX_DIR / "tele_doublet_x20.zmx").write_text(text, encoding="utf-8")
    heights = s["fields"]
    op = tele.build(s, 0.01, heights)
    rmax = max(math.hypot(*h) for h in heights)
    fields = [[hx / rmax, hy / rmax] for hx, hy in heights]
    return op, fields, [list(h) for h in heights], "object heights (x, y), mm"


def virtual(name):
    path = ROOT / "tests" / "data" / "zmx_corpus7" / f"{name}.zmx"
    op = load_zemax_file(str(path))
    text = path.read_text()
    fy = [float(v) for v in next(ln for ln in text.splitlines()
                                 if ln.startswith("YFLN")).split()[1:]]
    top = max(fy, key=abs)
    hy = (0.0, 0.5, 1.0)
    if "FTYP 0" in text:  # angles: optiland's Hy scales the angle
        jl_fields = [h * top for h in hy]
        kind = "angle θy, degrees"
    else:  # object heights: the chief ray through the paraxial entrance pupil's centre
        # (optiland's ray generation) toward the object point after it (+z): its angle
        # atan(h / (z_object - z_EP)) in object space
        z_obj = float(np.ravel(op.surface_group.positions)[0])
        z_ep = float(op.paraxial.EPL())
        jl_fields = [math.degrees(math.atan(h * top / (z_obj - z_ep))) for h in hy]
        kind = "chief-ray angle θy, degrees (object heights by optiland's EP)"
    return op, [[0.0, h] for h in hy], jl_fields, kind


def immersed():
    case = json.loads((ROOT / "tests" / "refcases_extra" /
                       "plastic_curved_immersed_image.json").read_text())
    src = case["material_index_source"]

    def mat(name):
        if name == "air":
            return "air"
        key = next(k for k in src if k.partition(":")[0] == name)
        base, _, cat = key.partition(":")
        return Material(base, cat) if cat else Material(base)

    rows = case["surfaces"]
    op = optic_mod.Optic()
    op.add_surface(index=0, radius=np.inf, thickness=np.inf)
    for s in rows[1:-1]:
        kw = dict(index=s["index"], radius=s["radius"], thickness=s["thickness"],
                  conic=s["conic"], is_stop=s["is_stop"], material=mat(s["material"]))
        if s["even_asphere_coeffs"]:
            kw.update(surface_type="even_asphere", coefficients=list(s["even_asphere_coeffs"]))
        op.add_surface(**kw)
    img = rows[-1]
    op.add_surface(index=img["index"], radius=img["radius"], conic=img["conic"],
                   material=mat(rows[-2]["material"]))  # image space is glass
    op.set_aperture(aperture_type="EPD", value=case["aperture"]["EPD"])
    op.set_field_type(field_type="angle")
    fields = case["fields"]["values"]
    for f in fields:
        op.add_field(y=f)
    for w in case["wavelengths_nm"]:
        op.add_wavelength(value=w / 1000.0, is_primary=(w == case["primary_wavelength_nm"]))
    tight(op)
    top = max(fields)
    return op, [[0.0, f / top] for f in fields], list(fields), "angle θy, degrees", rows


def ynu_exit_pupil(rows, wl_nm):
    """(global z, diameter) of the paraxial exit pupil, from a y-nu trace with the paraxial
    curvature c + 2·A2 (object at infinity, stop ``is_stop``): the stop imaged backward by
    the surfaces after it, and the marginal ray's height there."""
    key = next(k for k in rows[1]["n"] if abs(float(k) - wl_nm) < 1e-9)
    surf = rows[1:-1]
    c = [s["curvature"] + 2 * (s["even_asphere_coeffs"][0] if s["even_asphere_coeffs"] else 0)
         for s in surf]
    n = [1.0] + [s["n"][key] for s in surf]
    z = np.concatenate([[0.0], np.cumsum([s["thickness"] for s in surf])])
    stop = next(i for i, s in enumerate(surf) if s["is_stop"])

    def trace(y, nu, start):
        for i in range(start, len(surf)):
            if i > start:
                y = y + (z[i] - z[i - 1]) * nu / n[i]
            nu = nu - y * c[i] * (n[i + 1] - n[i])
        return y, nu, z[len(surf) - 1]

    # chief ray: from the stop's centre, any slope; the exit pupil is where it crosses 0
    y, nu, zl = trace(0.0, 1e-3 * n[stop], stop)
    z_xp = zl - y * n[-1] / nu
    return z_xp, trace, zl, n


def exit_pupil_of(op, rows=None):
    wl = op.primary_wavelength
    z_img = float(np.ravel(op.surface_group.positions)[-1])
    out = {"optiland_xpl": float(op.paraxial.XPL()), "optiland_xpd": float(op.paraxial.XPD()),
           "optiland_z": z_img + float(op.paraxial.XPL())}
    if rows is None:
        out["z"] = out["optiland_z"]
        out["diameter"] = out["optiland_xpd"]
        out["source"] = "optiland paraxial XPL, XPD"
        return out, None
    z_xp, trace, zl, n = ynu_exit_pupil(rows, wl * 1000.0)
    h = float(op.paraxial.EPD()) / 2
    y, nu, _ = trace(h, 0.0, 0)
    out["z"] = float(z_xp)
    out["diameter"] = float(2 * abs(y + (z_xp - zl) * nu / n[-1]))
    out["source"] = "y-nu trace with paraxial curvature c + 2*A2 (this tool)"
    return out, (0.0, 0.0, float(z_xp))


# --------------------------------------------------------------------------------------
# Analyses
# --------------------------------------------------------------------------------------
def wave_data(op, field, wl, dist, xp_point, n_image):
    st = create_strategy(strategy_name="chief_ray", optic=op, distribution=dist,
                         reference_type="sphere")
    if xp_point is not None:
        st.exit_pupil_point = xp_point
    if n_image is not None:
        st.n_image = n_image
    return st.compute_wavefront_data(tuple(field), wl)


def grid_stats(op, field, wl, xp_point):
    dist = create_distribution("uniform")
    dist.generate_points(GRID)
    d = wave_data(op, field, wl, dist, xp_point, None)
    keep = np.asarray(d.intensity) > 0
    w = np.asarray(d.opd)[keep]
    x = np.asarray(dist.x)[keep]
    y = np.asarray(dist.y)[keep]
    a = np.stack([np.ones_like(x), x, y], -1)
    plane = np.linalg.lstsq(a, w, rcond=None)[0]
    wt = w - a @ plane
    noll = np.asarray(ZernikeFit(x, y, w, "noll", ZERNIKE_TERMS).coeffs)
    return {"count": int(keep.sum()), "rms": float(np.std(w)), "pv": float(np.ptp(w)),
            "rms_tilt_removed": float(np.std(wt)), "pv_tilt_removed": float(np.ptp(wt)),
            "tilt": plane.tolist(), "noll": noll.tolist()}


class Cells(BaseDistribution):
    """jaxlens's geometric-PSF pupil grid (``GeometricPSF(pupil=MTF_CELLS, overfill=
    MTF_OVERFILL)``): cell centres of an n x n grid over [-1, 1]², kept inside the unit
    disc, scaled by the overfill, and of those the points inside the unit pupil (the system
    aperture: the ring beyond it carries no light)."""

    def generate_points(self, num_points):
        g = (np.arange(num_points) + 0.5) / num_points * 2.0 - 1.0
        px, py = np.meshgrid(g, g, indexing="xy")
        r2 = px * px + py * py
        keep = (r2 <= 1.0) & (r2 * MTF_OVERFILL**2 <= 1.0)
        self.x = px[keep] * MTF_OVERFILL
        self.y = py[keep] * MTF_OVERFILL


def ray_otf(op, field, heights, wl, freqs, stop, stop_r, finite):
    """|OTF| of the ray set (no pixel grid, no diffraction): tangential along the field's
    radial direction in the image (the object height's direction, or y on axis; the image
    of a radial line is radial in a rotationally symmetric lens), sagittal perpendicular.
    Each ray weighs cos⁴ of its launch direction for a finite object (a Lambertian point
    source over the launch plane's equal-area cells), 1 for an object at infinity; rays
    that miss the stop's circle of radius ``stop_r`` (inf: no clip) weigh 0."""
    given = op.surface_group.surfaces[stop].aperture  # the lens's own, put back after
    if math.isfinite(stop_r):
        op.surface_group.surfaces[stop].aperture = RadialAperture(r_max=stop_r)
    try:
        dist = Cells()
        dist.generate_points(MTF_CELLS)
        rays = op.trace(*field, wl, None, dist)
        alive = np.asarray(op.surface_group.intensity[-1]) > 0
        launch = op.ray_tracer.ray_generator.generate_rays(*field, dist.x, dist.y, wl)
    finally:
        op.surface_group.surfaces[stop].aperture = given
    w = np.where(alive, np.asarray(launch.N) ** 4 if finite else 1.0, 0.0)
    pos = np.stack([np.ravel(rays.x), np.ravel(rays.y)], -1)
    h = np.asarray(heights, float)
    e_t = np.array([0.0, 1.0]) if not np.any(h) else h / np.linalg.norm(h)
    e_s = np.array([e_t[1], -e_t[0]])
    out = {"rays": int(alive.sum())}
    for key, e in (("tangential", e_t), ("sagittal", e_s)):
        proj = pos[alive] @ e
        ph = np.exp(-2j * np.pi * np.asarray(freqs)[:, None] * proj[None, :])
        out[key] = np.abs(ph @ w[alive] / w[alive].sum()).tolist()
    return out


def coherent_centre_strehl(op, field, wl, stop, stop_r, finite, h=1e-5):
    """The coherent PSF's value at the chief ray's image point over the unaberrated peak,
    by jaxlens's definition (``CoherentPSF``: the ray-based Debye integral) evaluated on
    optiland's rays: |Σ a_j exp(iψ_j)|² / (Σ a_j)², over jaxlens's pupil grid (``Cells``,
    the stop clipping at ``stop_r``), ψ_j = k (OPL_j − n′ (L_j, M_j)·((x_j, y_j) − c)), c
    the chief ray's (x, y) on the image surface (primary wavelength, unclipped), OPL_j from
    the object point (finite object) or from the plane wave through the origin (object at
    infinity: optiland's path from the launch point o_j plus n₀ d_j·o_j), a_j =
    sqrt(w_j |∂(L, M)/∂(Px, Py)|), w_j as in ``ray_otf``, the Jacobian by central
    differences (step ``h``) of optiland's image-space direction cosines."""
    dist = Cells()
    dist.generate_points(MTF_CELLS)
    px, py = np.asarray(dist.x), np.asarray(dist.y)

    class At(BaseDistribution):
        def __init__(self, x, y):
            self.x, self.y = x, y

        def generate_points(self, num_points):
            pass

    def lm(x, y):
        r = op.trace(*field, wl, None, At(x, y))
        return np.ravel(r.L), np.ravel(r.M)

    given = op.surface_group.surfaces[stop].aperture  # the lens's own, put back after
    if math.isfinite(stop_r):
        op.surface_group.surfaces[stop].aperture = RadialAperture(r_max=stop_r)
    try:
        rays = op.trace(*field, wl, None, At(px, py))
        alive = np.asarray(op.surface_group.intensity[-1]) > 0
    finally:
        op.surface_group.surfaces[stop].aperture = given
    launch = op.ray_tracer.ray_generator.generate_rays(*field, px, py, wl)
    lx1, mx1 = lm(px + h, py)
    lx0, mx0 = lm(px - h, py)
    ly1, my1 = lm(px, py + h)
    ly0, my0 = lm(px, py - h)
    det = np.abs((lx1 - lx0) * (my1 - my0) - (mx1 - mx0) * (ly1 - ly0)) / (4 * h * h)
    w = np.where(alive, np.asarray(launch.N) ** 4 if finite else 1.0, 0.0)
    a = np.sqrt(w * det)
    opl = np.ravel(rays.opd)
    if not finite:
        n0 = float(np.ravel(op.surface_group.surfaces[0].material_post.n(wl))[0])
        opl = opl + n0 * (np.asarray(launch.L) * np.asarray(launch.x) + np.asarray(launch.M)
                          * np.asarray(launch.y) + np.asarray(launch.N) * np.asarray(launch.z))
    c = op.trace_generic(*field, 0.0, 0.0, op.primary_wavelength)
    cx, cy = float(np.ravel(c.x)[0]), float(np.ravel(c.y)[0])
    n_img = float(np.ravel(op.surface_group.n(wl))[-1])
    psi = 2 * np.pi / (wl * 1e-3) * (opl - n_img * (np.ravel(rays.L) * (np.ravel(rays.x) - cx)
                                                     + np.ravel(rays.M) * (np.ravel(rays.y) - cy)))
    psi = psi - psi[alive][0]  # a common phase: large paths kept accurate in the exponent
    u = np.sum(np.where(alive, a * np.exp(1j * psi), 0.0))
    return float(np.abs(u) ** 2 / np.sum(a) ** 2)


def optiland_geometric_mtf(op, field, freqs):
    """optiland's own GeometricMTF (its beam: the unit pupil on the paraxial entrance pupil,
    no stop clipping; line spread from a 2048-bin histogram; tangential y, sagittal x),
    for comparison only."""
    m = GeometricMTF(op, fields=[tuple(field)], wavelength="primary", num_rays=201,
                     distribution="uniform", num_points=2048, max_freq=max(freqs),
                     scale=False)
    sd = m.data[0][0]
    v = np.asarray(freqs, float)
    return {"tangential": np.asarray(m._compute_field_data(sd.y, v, 1)).tolist(),
            "sagittal": np.asarray(m._compute_field_data(sd.x, v, 1)).tolist()}


def ray_fan(op, field, wl):
    """Image-surface (x, y) of the fan rays (0, t) and (t, 0), t in ``FAN``, minus the
    chief ray's (mm, primary wavelength): optiland's ``trace_generic``."""
    t = np.asarray(FAN)
    z = np.zeros_like(t)
    c = op.trace_generic(*field, 0.0, 0.0, wl)
    c = np.array([float(np.ravel(c.x)[0]), float(np.ravel(c.y)[0])])
    out = {}
    for key, (px, py) in (("tangential", (z, t)), ("sagittal", (t, z))):
        r = op.trace_generic(*field, px, py, wl)
        out[key] = (np.stack([np.ravel(r.x), np.ravel(r.y)], -1) - c).tolist()
    return out


def encircled(op, field, wl):
    """Geometric encircled energy of the rays through ``POINTS`` (equal energy each) about
    their centroid, primary wavelength: radii half-way between consecutive distances, at or
    after the 6th/7th, 13th/14th and 21st/22nd smallest, where they differ by more than 1e-6
    of the largest (no ray near a radius), and the fraction within each."""
    pts = Points()
    pts.generate_points(0)
    r = op.trace(*field, wl, None, pts)
    xy = np.stack([np.ravel(r.x), np.ravel(r.y)], -1)
    d = np.sort(np.linalg.norm(xy - xy.mean(0), axis=-1))
    gap = 1e-6 * d[-1]  # distances closer than this (mirror-image rays) are not split
    ks = [next(j for j in range(k, len(d)) if d[j] - d[j - 1] > gap) for k in (6, 13, 21)]
    radii = [(d[k - 1] + d[k]) / 2 for k in ks]
    return {"radii": radii, "energy": [float(np.mean(d <= x)) for x in radii]}


def working_fnum(op, rows=None):
    """1/(2 n′u′) of the paraxial marginal ray in image space: optiland's marginal ray (air
    image space), or for the A2 lens this tool's y-nu trace (n′u′ directly)."""
    if rows is None:
        _, u = op.paraxial.marginal_ray()
        return 1.0 / (2.0 * abs(float(np.ravel(u[-1])[0])))
    _, trace, _, _ = ynu_exit_pupil(rows, op.primary_wavelength * 1000.0)
    _, nu, _ = trace(float(op.paraxial.EPD()) / 2, 0.0, 0)
    return 1.0 / (2.0 * abs(nu))


def analyse(op, fields, jl_fields, kind, xp, xp_point, freqs, rows=None, strehl_fields=None):
    wls = [float(w.value) for w in op.wavelengths.wavelengths]
    prim = float(op.primary_wavelength)
    n_img = {w: float(np.ravel(op.surface_group.n(w))[-1]) for w in wls}
    stop = int(op.surface_group.stop_index)
    stop_r = abs(float(np.ravel(op.paraxial.marginal_ray()[0][stop])[0]))
    finite = not op.object_surface.is_infinite
    res = {"field_kind": kind, "optiland_fields": fields, "jaxlens_fields": jl_fields,
           "wavelengths_um": wls, "primary_um": prim, "image_space_index": n_img,
           "exit_pupil": xp, "working_fnum": working_fnum(op, rows),
           "mtf_freqs_cyc_per_mm": list(freqs), "stop_surface": stop,
           "stop_semi_diameter": stop_r, "fields": []}
    for f in fields:
        one = {"opd": {}, "opd_optiland_primary_index": {}}
        for w in wls:
            pts = Points()
            pts.generate_points(0)
            d = wave_data(op, f, w, pts, xp_point, n_img[w])
            one["opd"][repr(w)] = np.asarray(d.opd).tolist()
            if n_img[w] != n_img[prim]:
                d0 = wave_data(op, f, w, pts, xp_point, None)
                one["opd_optiland_primary_index"][repr(w)] = np.asarray(d0.opd).tolist()
        one["ray_fan"] = ray_fan(op, f, prim)
        one["grid"] = grid_stats(op, f, prim, xp_point)
        one["mtf"] = ray_otf(op, f, f, prim, freqs, stop, math.inf, finite)
        one["optiland_geometric_mtf"] = optiland_geometric_mtf(op, f, freqs)
        if strehl_fields is not None and len(res["fields"]) in strehl_fields:
            one["coherent_centre_strehl"] = coherent_centre_strehl(op, f, prim, stop, math.inf,
                                                                   finite)
            one["encircled"] = encircled(op, f, prim)
        res["fields"].append(one)
    return res


def main() -> None:
    warnings.filterwarnings("ignore")
    out = {"source": "optiland 0.6.3 (tools/acc40c_reference.py)",
           "optiland": version("optiland"),
           "settings": {
               "strategy": "chief_ray: sphere centred on the chief ray's image-surface "
                           "intercept, through the paraxial exit pupil (primary wavelength); "
                           "OPD = (chief path - ray path)/λ to that sphere, waves",
               "points": [list(p) for p in POINTS], "fan": list(FAN), "grid": GRID,
               "grid_note": "uniform grid linspace(-1, 1, GRID)² cut to Px²+Py² <= 1, equal "
                            "weights; rms/pv with the mean removed, *_tilt_removed with the "
                            "least-squares plane in (Px, Py) removed; Noll Zernike fit",
               "zernike_terms": ZERNIKE_TERMS, "mtf_cells": MTF_CELLS,
               "mtf_overfill": MTF_OVERFILL,
               "mtf_note": "|OTF| of optiland's rays on jaxlens's geometric-PSF pupil grid "
                           "(mtf_cells² cell centres in the disc, times mtf_overfill), cut "
                           "to the unit pupil (no stop clipping; round 44a), cos⁴ "
                           "launch weights for a finite object, primary wavelength, no "
                           "diffraction factor; tangential along the field's radial "
                           "direction. optiland_geometric_mtf: optiland's own "
                           "GeometricMTF (unit pupil, no stop clipping, histogram), "
                           "for comparison only",
               "image_index_note": "opd uses the image-space index at the wavelength "
                                   "analysed; opd_optiland_primary_index is optiland's own "
                                   "(primary index), stored where they differ"},
           "lenses": {}}
    for name in ("tele_doublet_obna", "tele_triplet_floa"):
        op, fields, jl, kind = telecentric(name)
        xp, pt = exit_pupil_of(op)
        out["lenses"][name] = analyse(op, fields, jl, kind, xp, pt, MTF_FREQS[name])
        print(name, "done", flush=True)
    op, fields, jl, kind = scaled_telecentric()
    xp, pt = exit_pupil_of(op)
    out["lenses"]["tele_doublet_x20"] = analyse(op, fields, jl, kind, xp, pt,
                                                MTF_FREQS["tele_doublet_x20"],
                                                strehl_fields=(0, 1, 2))
    print("tele_doublet_x20 done", flush=True)
    for name in ("virtual_singlet_angles", "virtual_stop_behind"):
        op, fields, jl, kind = virtual(name)
        xp, pt = exit_pupil_of(op)
        out["lenses"][name] = analyse(op, fields, jl, kind, xp, pt, MTF_FREQS[name])
        print(name, "done", flush=True)
    # Real ray aiming with a virtual object: optiland's iterative aiming fills the real
    # stop with the real marginal ray (jaxlens's aim="real_marginal"; tools/corpus7_reference
    # aims the same file the same way). OPD and grid statistics only.
    op, fields, jl, kind = virtual("virtual_stop_behind_aimed")
    op.ray_tracer.set_aiming("iterative", max_iter=50, tol=1e-13)
    xp, pt = exit_pupil_of(op)
    prim = float(op.primary_wavelength)
    res = {"field_kind": kind, "optiland_fields": fields, "jaxlens_fields": jl,
           "jaxlens_aim": "real_marginal", "wavelengths_um": [prim], "primary_um": prim,
           "exit_pupil": xp, "fields": []}
    for f in fields:
        pts = Points()
        pts.generate_points(0)
        d = wave_data(op, f, prim, pts, pt, None)
        res["fields"].append({"opd": {repr(prim): np.asarray(d.opd).tolist()},
                              "grid": grid_stats(op, f, prim, pt)})
    out["lenses"]["virtual_stop_behind_aimed"] = res
    print("virtual_stop_behind_aimed done", flush=True)
    name = "plastic_curved_immersed_image"
    op, fields, jl, kind, rows = immersed()
    xp, pt = exit_pupil_of(op, rows)
    out["lenses"][name] = analyse(op, fields, jl, kind, xp, pt, MTF_FREQS[name], rows,
                                  strehl_fields=(0, 1))
    print(name, "done", flush=True)
    OUT.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
