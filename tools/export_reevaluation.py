"""Re-evaluate designs jaxlens exported (``.zmx`` and JSON) in optiland, beside jaxlens's report.

For each file: jaxlens opens it (``jaxlens.load``) and reports it (``analysis.report.report_data``,
the numbers of ``python -m jaxlens report FILE --json``); optiland 0.6.3 opens the ``.zmx``
(``optiland.fileio.load_zemax_file``, with optiland's own glass data: a glass that it resolves
to another material shows up here). A JSON file is saved by jaxlens as ``.zmx`` in a temporary
folder first (the export path under test); where a ``.zmx`` of the same stem lies beside it,
jaxlens's numbers of both must agree too. Compared, with the same definitions on both sides:

* EFL (image space, n′/Φ; optiland ``paraxial.f2()``), F/# (``paraxial.FNO()``), BFL (from the
  last vertex to the paraxial focus: the last gap + optiland's ``paraxial.F2()``), total track
  (surface 1 to the image surface; optiland ``total_track``), mm; the FoV (2 × the largest
  radial field, deg) and the fields each code read from the file as (θx, θy) (compared as
  sets: optiland's reader reorders them);
* per field (θy, or (θx, θy) from XFLN/YFLN: optiland's angle field (Hx, Hy)·F along
  (tan θx, tan θy, 1), F its largest radial field, is jaxlens's (θx, θy)), the real chief
  ray on the image surface (primary wavelength, pupil centre; optiland
  ``trace_generic(Hx, Hy, 0, 0)``): its x and y, mm, its height along the field's azimuth
  (``analysis.spots.field_heights``: y for a θy field), and the f-tanθ distortion made of
  it, 100 (h − EFL tanθ)/(EFL tanθ) %, tan²θ = tan²θx + tan²θy;
* per field and wavelength, the RMS spot radius about the centroid, µm, on the 21 × 21 square
  grid over the unit entrance pupil kept inside the disc (317 rays; optiland traces the same
  normalised pupil points with ``trace_generic``), each code aiming its own rays (paraxial
  pupil aiming); and per field the RMS radius of all wavelengths' rays pooled about their
  common centroid (the report's ``rms_spot_polychromatic``, the classical run's RMS).

Surface types optiland 0.6.3's reader lacks (XPOLYNOM, jaxlens's Hybrid among them; XASPHERE,
XOSPHERE, TILTSURF, BICONICX) are read here from the file's text by Zemax's definitions
(``own_surfaces``, ``own_geometry``) and given to optiland as its geometries. optiland reads
every length as mm: a file in other units (UNIT IN) is reported, not compared. optiland's
paraxial quantities use a surface's base radius only (an XY polynomial's x², y² terms add
power that jaxlens's paraxial trace includes): compare real rays there.

optiland 0.6.3's Newton search on an asphere or polynomial surface is mended here: where it
found no root from its start (the base conic's intersection) it runs again from the vertex
plane (``plane_seeded``), a later crossing found past an earlier one is replaced by the first
(``first_root``), and a ray whose recorded point lies off a surface (a search that did not
converge, which optiland keeps) counts as lost (``missed_surfaces``), as in Zemax and jaxlens.

``--resave`` saves each ``.zmx`` input again with ``jaxlens.save`` (``.zmx`` and JSON), checks
that both read back in jaxlens as the same lens (pytree and numbers), and gives optiland the
saved ``.zmx`` too (against jaxlens, and against optiland's numbers for the original).

``--summary RUN/summary.json`` re-evaluates every number a classical run
(``python -m jaxlens.experiments.classical``) wrote for its best design: EFL, F/#, BFL, total
track, the chief-ray height and distortion at half the diagonal FoV, and the mean, largest,
smallest and median of the pooled (F, d, C) RMS over its n × n sensor grid of (θx, θy) fields
and the on-axis RMS. ``RUN/lens.zmx`` is re-read by jaxlens (``jaxlens.design.evaluate``, the
run's own code and definitions) and by optiland (with its glass data, and with jaxlens's
media), each at the same fields, rebuilt from the spec in summary.json; every number's
relative difference from the summary's, and the grid's largest per-field RMS difference
between jaxlens's re-read and optiland, are printed, with the grid's and the axis's rays each
loses (``rays_lost``: jaxlens's re-read, optiland, optiland with jaxlens's media; a ray only
optiland loses is a clear aperture its glass data or aiming moved a rim ray past).

Run it with an interpreter that has optiland 0.6.3 and this checkout's jaxlens:

    PYTHONPATH=$PWD /work/optiland_venv/bin/python tools/export_reevaluation.py \
        /tmp/a14_smoke/lens.zmx /tmp/a14_smoke/lens.json jaxlens/data/lenses \
        experiments/classical/designs --summary /tmp/a14_smoke/summary.json --json out.json

tests/test_input_probes_round14.py stores numbers this script printed;
tools/export_fields_reference.py uses its functions for tests/test_export_fields.py.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import pathlib
import sys
import tempfile
import warnings

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.analysis.report import report_data  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402

# jaxlens's 21 × 21 grid inside the unit disc (317 points; optiland's own "uniform" grid drops
# the 4 points on the rim at (0, ±1), (±1, 0) in floating point, so its points are not used).
PUPIL = np.asarray(jl.sampling.pupil_grid(21))
SCALARS = ("efl_image_space", "fnum", "bfl", "total_track")
OPTILAND_NAME = {"efl_image_space": "efl", "fnum": "fnum", "bfl": "bfl",
                 "total_track": "total_track"}


def jaxlens_numbers(lens) -> dict:
    """jaxlens's report numbers, in the units of this script (mm, %, µm)."""
    d = report_data(lens)
    out = {k: d[k] for k in SCALARS}
    out["efl_air"] = d["efl"]
    out["fov"] = d["fov"]
    out["fields"] = [f["angle"] for f in d["fields"]]
    out["chief_y"] = [f["chief_ray_height"] for f in d["fields"]]  # along the field's azimuth
    out["chief_xy"] = [f["chief_ray_xy"] for f in d["fields"]]
    out["distortion"] = [f["distortion"] for f in d["fields"]]
    out["rms_um"] = [f["rms_spot"] for f in d["fields"]]
    out["rms_poly_um"] = [f["rms_spot_polychromatic"] for f in d["fields"]]
    out["wavelengths"] = d["wavelengths"]
    out["primary"] = d["primary_wavelength"]
    return out


def field_pair(f) -> tuple[float, float]:
    """A field (deg, θy or (θx, θy)) as (θx, θy)."""
    if isinstance(f, list | tuple | np.ndarray):
        return float(f[0]), float(f[1])
    return 0.0, float(f)


def field_direction(f) -> tuple[float, tuple[float, float]]:
    """(tan θ, unit (ux, uy)) of a field: tan²θ = tan²θx + tan²θy and the image-plane
    direction (tan θx, tan θy)/tan θ along which its chief-ray height is measured (+y on
    axis), as ``jaxlens.analysis.spots.field_heights``; a y field's is its signed tan θy
    along +y."""
    tx, ty = (math.tan(math.radians(a)) for a in field_pair(f))
    if not isinstance(f, list | tuple | np.ndarray):
        return ty, (0.0, 1.0)
    t = math.hypot(tx, ty)
    return t, ((tx / t, ty / t) if t > 0 else (0.0, 1.0))


def set_media(op, lens) -> None:
    """Give optiland's surfaces (after the object) jaxlens's media, dispersion included (each
    a material whose index at λ is jaxlens's ``material.index(λ)``), so that only the
    geometry, aperture, fields and tracing are optiland's."""
    from optiland.materials.base import BaseMaterial

    class Jaxlens(BaseMaterial):
        def __init__(self, m):
            super().__init__()
            self.m = m

        def _cache_state(self):
            return None

        def _calculate_n(self, wavelength, **kwargs):
            w = np.asarray(wavelength, float)
            own = table[id(self.m)]
            flat = [own.get(float(x)) or float(self.m.index(float(x))) for x in w.ravel()]
            return np.reshape(flat, w.shape)

        def _calculate_k(self, wavelength, **kwargs):
            return np.zeros_like(np.asarray(wavelength, float))

    table = {}  # the lens's own wavelengths, evaluated once
    for w in lens.wavelengths:
        for m in lens.materials:
            table.setdefault(id(m), {})[float(w)] = float(m.index(w))

    mats = list(lens.materials) + [lens.materials[-1]]
    for s, m in zip(op.surfaces.surfaces[1:], mats, strict=True):
        s.material_post = Jaxlens(m)


# Zemax surface types that optiland 0.6.3's reader lacks: read here from the file's own text,
# by Zemax's definitions (not jaxlens's reader), and given to optiland as its geometries.
# Each is written as a STANDARD surface (CURV, CONI) to a copy of the file that optiland opens;
# its geometry is then replaced. Units: the file must be in mm (UNIT MM).
OWN_TYPES = ("XPOLYNOM", "XASPHERE", "XOSPHERE", "TILTSURF", "BICONICX")


def xpoly_powers(j: int) -> tuple[int, int]:
    """Zemax's Extended Polynomial term j (1-based): (power of x, power of y); the terms run
    x, y, x², xy, y², x³, x²y, …, by degree, the power of x falling within a degree."""
    d = 1
    while j > d + 1:
        j -= d + 1
        d += 1
    return d - (j - 1), j - 1


def own_surfaces(text: str) -> tuple[str, dict]:
    """The file's text with OWN_TYPES surfaces written as STANDARD, and for each such
    surface number its type, CURV, CONI, PARM and XDAT values."""
    out, own, n = [], {}, None
    for ln in text.splitlines():
        t = ln.split()
        key = t[0] if t else ""
        if key == "UNIT" and t[1] != "MM":
            raise ValueError(f"the file's UNIT is {t[1]}; optiland 0.6.3 reads every length as "
                             f"mm, so its numbers for this file are not comparable")
        if key == "SURF":
            n = int(t[1])
        elif key == "TYPE" and t[1] in OWN_TYPES:
            own[n] = {"type": t[1], "c": 0.0, "k": 0.0, "parm": {}, "xdat": {}}
            out.append(ln.replace(t[1], "STANDARD"))
            continue
        elif n in own and key in ("CURV", "CONI"):
            own[n]["c" if key == "CURV" else "k"] = float(t[1])
        elif n in own and key in ("PARM", "XDAT"):
            own[n][key.lower()][int(t[1])] = float(t[2])
            continue
        out.append(ln)
    return "\n".join(out) + "\n", own


def own_geometry(old, d: dict):
    """The optiland geometry of one OWN_TYPES surface (``old``: the standard one in its place,
    whose coordinate system it keeps)."""
    from optiland.geometries import BiconicGeometry, EvenAsphere, OddAsphere, PolynomialGeometry

    cs, c, k, x = old.cs, d["c"], d["k"], d["xdat"]
    radius = math.inf if c == 0 else 1.0 / c
    kind = d["type"]
    if kind == "BICONICX":
        rx = d["parm"].get(1, 0.0)
        return BiconicGeometry(cs, rx if rx != 0 else math.inf, radius, d["parm"].get(2, 0.0), k)
    if kind == "TILTSURF":
        coeffs = [[0.0, d["parm"].get(2, 0.0)], [d["parm"].get(1, 0.0), 0.0]]
        return PolynomialGeometry(cs, math.inf, 0.0, coefficients=coeffs)
    n, r = int(x.get(1, 0)), x.get(2, 1.0)
    a = [x.get(j + 2, 0.0) for j in range(1, n + 1)]
    if kind == "XASPHERE":  # Σ α_i ρ^(2i), ρ = r/R
        return EvenAsphere(cs, radius, k, coefficients=[v / r ** (2 * i)
                                                        for i, v in enumerate(a, start=1)])
    if kind == "XOSPHERE":  # Σ β_i ρ^i
        return OddAsphere(cs, radius, k, coefficients=[v / r ** i
                                                       for i, v in enumerate(a, start=1)])
    deg = max((sum(xpoly_powers(j)) for j in range(1, n + 1)), default=0)
    coeffs = np.zeros((deg + 1, deg + 1))
    for j, v in enumerate(a, start=1):  # Σ A_j (x/R)^p (y/R)^q
        p, q = xpoly_powers(j)
        coeffs[p, q] += v / r ** (p + q)
    return PolynomialGeometry(cs, radius, k, coefficients=coeffs)


FIRST_ROOT_SAMPLES = 128


def first_root(residual, t) -> np.ndarray:
    """The first root along each ray of F (``residual``: t -> F(t), elementwise, mm) in
    [0, t], where the root ``t`` that a search found is a later one: F sampled at
    FIRST_ROOT_SAMPLES points of [0, t) changes sign before ``t``, and the first such bracket
    is bisected to rounding. optiland's Newton search from the base conic can go past a
    root (the EDoF lens's surface 8 at its 34.4° field: 4 pupil rays cross it twice, and it
    took the second crossing). ``t`` where no earlier sign change (NaN kept)."""
    t = np.asarray(t, float)
    ok = np.isfinite(t) & (t > 0)
    if not ok.any():
        return t
    span = np.where(ok, t, 0.0)
    k = np.arange(FIRST_ROOT_SAMPLES)[:, None] / FIRST_ROOT_SAMPLES
    with np.errstate(invalid="ignore"):
        f = np.asarray(residual(span * k), float)  # [samples, rays] in one pass
        flip = (np.sign(f[1:]) * np.sign(f[:1]) < 0) & ok
    has = flip.any(axis=0)
    if not has.any():
        return t
    j = np.argmax(flip, axis=0)  # the first sample of the other sign
    lo = np.where(has, span * k[j, 0], 0.0)  # k[j] precedes sample j + 1
    hi = np.where(has, span * k[j + 1, 0], 0.0)
    f_lo = np.asarray(residual(lo), float)
    for _ in range(64):  # 2⁻⁶⁴ of a bracket: rounding
        mid = 0.5 * (lo + hi)
        f_mid = np.asarray(residual(mid), float)
        left = np.sign(f_mid) * np.sign(f_lo) <= 0
        lo, hi, f_lo = np.where(left, lo, mid), np.where(left, mid, hi), np.where(left, f_lo,
                                                                                  f_mid)
    return np.where(has, 0.5 * (lo + hi), t)


def plane_seeded(cls):
    """optiland's Newton-searched geometry ``cls`` (an asphere, a polynomial) whose search,
    where it found no root from optiland's start (the base conic's intersection: NaN for a
    ray that misses the base conic, and far from the root where the polynomial terms move
    the surface far from it), is run again from the ray's crossing of the vertex plane.
    optiland keeps the first search's result; the EDoF lens's 34.4° field lost every ray
    so (surface 11, R 3.57 mm, the chief ray at 3.25 mm), and 8 of them at surface 8.
    A root is still checked by :func:`missed_surfaces`, like every other."""
    import dataclasses

    from optiland.geometries.standard import StandardGeometry

    class PlaneSeed(StandardGeometry):
        from_plane = False

        def distance(self, rays, aperture=None):
            with np.errstate(divide="ignore", invalid="ignore"):
                plane = -np.asarray(rays.z, float) / np.asarray(rays.N, float)
            if self.from_plane:
                return plane
            t = np.asarray(StandardGeometry.distance(self, rays, aperture), float)
            return np.where(np.isfinite(t), t, plane)

    class Seeded(cls, PlaneSeed):
        def _solve_distance_primal(self, rays, aperture=None):
            a = super()._solve_distance_primal(rays, aperture)
            found = np.asarray(a.converged, bool) & np.isfinite(np.asarray(a.t, float))
            if found.all():
                return a
            self.from_plane = True
            try:
                b = super()._solve_distance_primal(rays, aperture)
            finally:
                self.from_plane = False
            take = ~found & np.asarray(b.converged, bool)
            return dataclasses.replace(
                a, t=np.where(take, b.t, a.t), residual=np.where(take, b.residual, a.residual),
                converged=found | take)

        def distance(self, rays, aperture=None):
            return first_root(lambda t: self._surface_residual(t, rays),
                              np.asarray(super().distance(rays, aperture), float))

    Seeded.__name__ = "PlaneSeeded" + cls.__name__
    return Seeded


def optiland_optic(path: str, primary: float, lens=None):
    """optiland's optic of a ``.zmx`` file (:data:`OWN_TYPES` surfaces read here) and the
    indices of its media at ``primary``; with ``lens``, its media replaced by jaxlens's
    (:func:`set_media`: glass data set aside). Newton tolerance 1e-13, 200 iterations."""
    from optiland.fileio import load_zemax_file

    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        with open(path, "rb") as fh:
            raw = fh.read()
        utf16 = raw[:2] in (b"\xff\xfe", b"\xfe\xff")
        text, own = own_surfaces(raw.decode("utf-16" if utf16 else "latin-1"))
        if own:  # a copy beside nothing: optiland reads no AGF file
            with tempfile.TemporaryDirectory() as tmp:
                copy = os.path.join(tmp, "own.zmx")
                with open(copy, "w", encoding="utf-8") as fh:  # temporary folder
                    fh.write(text)
                op = load_zemax_file(copy)
            for n, d in own.items():
                s = op.surfaces.surfaces[n]
                s.geometry = own_geometry(s.geometry, d)
        else:
            op = load_zemax_file(path)
        index_d = [float(np.asarray(s.material_post.n(primary)).ravel()[0])
                   for s in op.surfaces.surfaces[1:-1]]
        if lens is not None:
            set_media(op, lens)
        for s in op.surfaces.surfaces:  # optiland's Newton on aspheres stops at 1e-10 or so
            g = s.geometry
            if hasattr(g, "tol") and hasattr(g, "max_iter"):
                g.tol, g.max_iter = 1e-13, 200
                g.__class__ = plane_seeded(type(g))
    return op, index_d


def optiland_system(op) -> dict:
    """optiland's EFL (image space), F/#, BFL, total track, and the fields it read as (θx, θy)
    pairs (deg). ``fov``: twice the largest angle between a field's direction (tan θx,
    tan θy, 1) and the axis, jaxlens's report's definition; ``max_field``: optiland's own
    largest radial field, max √(θx² + θy²), its normalisation of (Hx, Hy) (the same for
    y fields, 20° against 19.64° for (−12°, 16°))."""
    par = op.paraxial
    last_gap = float(op.surfaces.positions[-1, 0] - op.surfaces.positions[-2, 0])
    fields = [[float(x), float(y)] for x, y in
              zip(np.ravel(op.fields.x_fields), np.ravel(op.fields.y_fields), strict=True)]
    return {"efl": float(par.f2()), "fnum": float(par.FNO()),
            "bfl": last_gap + float(par.F2()), "total_track": float(op.total_track),
            "fov": 2.0 * max(math.degrees(math.atan(field_direction(f)[0])) for f in fields),
            "max_field": float(op.fields.max_field), "file_fields": fields}


def optiland_numbers(path: str, wavelengths, primary, fields, lens=None) -> dict:
    """optiland's numbers for the same file, with the definitions of :func:`jaxlens_numbers`
    (``fields``: deg, θy or (θx, θy) each).

    With ``lens``, optiland's media are replaced by jaxlens's (:func:`set_media`): glass data
    set aside."""
    op, index_d = optiland_optic(path, primary, lens)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        out = optiland_system(op)
        out["index_d"] = index_d
        out.update(field_numbers(op, fields, wavelengths, primary, out["efl"]))
    return out


def normalised_field(op, f) -> tuple[float, float]:
    """optiland's (Hx, Hy) of a field (deg): its angle fields are Hx·F, Hy·F degrees along
    (tan, tan, 1) with F its largest radial field (``fields.max_field``), the direction
    jaxlens gives (θx, θy)."""
    tx, ty = field_pair(f)
    fmax = float(op.fields.max_field) or 1.0
    return tx / fmax, ty / fmax


# A ray point recorded on a surface farther than this from it along z (mm) is a ray that
# missed the surface: optiland 0.6.3's Newton search on an asphere keeps the rays it did not
# converge for (it warns, and traces them on from the last iterate), where Zemax and jaxlens
# report a miss.
OFF_SURFACE_MM = 1e-9


def off_surface(points, vertex_z, sag) -> np.ndarray:
    """Whether each ray's point ``points`` = (x, y, z) (global, mm) on a surface whose frame is
    only shifted along z to ``vertex_z`` (mm) lies off the surface ``z = vertex_z + sag(x,
    y)`` by more than :data:`OFF_SURFACE_MM`, or is not finite (bool, one per ray)."""
    x, y, z = (np.asarray(v, float).ravel() for v in points)
    with np.errstate(invalid="ignore"):
        gap = np.abs(z - vertex_z - np.asarray(sag(x, y), float).ravel())
        return ~(gap <= OFF_SURFACE_MM)


def missed_surfaces(op) -> np.ndarray:
    """Rays of optiland's last trace that some surface after the object did not hold (a
    point :func:`off_surface` of it: a miss optiland traced on from its last Newton
    iterate). Surfaces of a tilted or decentered frame are not checked (bool, one per
    ray)."""
    surfaces = op.surfaces.surfaces
    bad = np.zeros(np.asarray(surfaces[-1].y).size, bool)
    for s in surfaces[1:]:
        cs = s.geometry.cs
        moved = [float(getattr(cs, a, 0.0) or 0.0) for a in ("x", "y", "rx", "ry", "rz")]
        if any(moved) or getattr(cs, "reference_cs", None) is not None:
            continue
        x, y = np.asarray(s.x, float).ravel(), np.asarray(s.y, float).ravel()
        sag = s.geometry.sag
        bad |= off_surface((x, y, s.z), float(cs.z), lambda u, v, sag=sag: np.asarray(sag(u, v)))
    return bad


def field_numbers(op, fields, wavelengths, primary, efl: float) -> dict:
    """optiland's chief rays, distortions and RMS spots of ``fields`` (deg, θy or (θx, θy),
    any angles, not only the file's), traced by ``op``: the definitions of
    :func:`jaxlens_numbers` (the chief ray through the pupil centre at the primary wavelength,
    its height along the field's azimuth, f-tanθ distortion against ``efl``; per field and
    wavelength the RMS radius about the centroid, and pooled over the wavelengths about their
    common centroid, of the 317-point grid)."""
    chief, chief_xy, dist = [], [], []
    for f in fields:
        hx, hy = normalised_field(op, f)
        r = op.trace_generic(hx, hy, 0.0, 0.0, primary)
        x, y = float(np.asarray(r.x).ravel()[0]), float(np.asarray(r.y).ravel()[0])
        if missed_surfaces(op)[0]:
            x = y = math.nan
        t, (ux, uy) = field_direction(f)
        h = x * ux + y * uy
        chief.append(h)
        chief_xy.append([x, y])
        ref = efl * t
        dist.append(0.0 if ref == 0 else 100.0 * (h - ref) / ref)
    rms = [[0.0] * len(wavelengths) for _ in fields]
    poly = [0.0] * len(fields)
    lost = 0  # rays of the grid optiland loses (all fields and wavelengths)
    for i, f in enumerate(fields):
        hx, hy = normalised_field(op, f)
        pooled = []
        for k, w in enumerate(wavelengths):
            r = op.trace_generic(hx, hy, PUPIL[:, 0], PUPIL[:, 1], w)
            x, yy = np.asarray(r.x).ravel(), np.asarray(r.y).ravel()
            ok = (np.asarray(r.i).ravel() > 0) & np.isfinite(x) & np.isfinite(yy)
            ok &= ~missed_surfaces(op)
            lost += int(len(PUPIL) - ok.sum())
            cx, cy = x[ok].mean(), yy[ok].mean()
            rms[i][k] = 1e3 * math.sqrt(np.mean((x[ok] - cx) ** 2 + (yy[ok] - cy) ** 2))
            pooled.append(np.stack([x[ok], yy[ok]], -1))
        p = np.concatenate(pooled)
        poly[i] = 1e3 * math.sqrt(np.mean(np.sum((p - p.mean(0)) ** 2, -1)))
    return {"chief_y": chief, "chief_xy": chief_xy, "distortion": dist, "rms_um": rms,
            "rms_poly_um": poly, "rays_lost": lost}


def compare(j: dict, o: dict) -> dict:
    """Largest differences: relative for the scalars, absolute for the FoV (deg), heights (mm:
    along the field's azimuth, and x and y apart), distortion (percentage points) and RMS (µm,
    and relative; per field and wavelength, and pooled over the wavelengths). ``fields_deg``:
    the largest difference between jaxlens's fields and those optiland read from the file
    (deg; None where the counts differ)."""
    d = {k: None if j[k] is None else abs(j[k] - o[OPTILAND_NAME[k]]) / abs(o[OPTILAND_NAME[k]])
         for k in SCALARS}  # None: jaxlens reports no value (a lens without power)
    d["fov_deg"] = abs(j["fov"] - o["fov"])
    if "file_fields" in o:
        # optiland's reader keeps the fields in another order (sorted): compared as sets
        jf = sorted(field_pair(f) for f in j["fields"])
        of = sorted(tuple(f) for f in o["file_fields"])
        d["fields_deg"] = None if len(jf) != len(of) else max(
            max(abs(a - b) for a, b in zip(p, q, strict=True))
            for p, q in zip(jf, of, strict=True))
    d["chief_y_mm"] = max(abs(a - b) for a, b in zip(j["chief_y"], o["chief_y"], strict=True))
    d["chief_xy_mm"] = float(np.max(np.abs(np.asarray(j["chief_xy"], float)
                                           - np.asarray(o["chief_xy"], float))))
    d["distortion_pp"] = max(abs(a - b) for a, b in
                             zip(j["distortion"], o["distortion"], strict=True))
    rj, ro = np.asarray(j["rms_um"], float), np.asarray(o["rms_um"], float)
    d["rms_um"] = float(np.max(np.abs(rj - ro)))
    d["rms_rel"] = float(np.max(np.abs(rj - ro) / ro))
    pj, po = np.asarray(j["rms_poly_um"], float), np.asarray(o["rms_poly_um"], float)
    d["rms_poly_um"] = float(np.max(np.abs(pj - po)))
    return d


def compare_optiland(a: dict, b: dict) -> dict:
    """Largest differences of optiland's numbers for two files (:func:`compare`'s units)."""
    d = {k: abs(a[k] - b[k]) / abs(a[k]) if a[k] else abs(a[k] - b[k])
         for k in OPTILAND_NAME.values()}
    d["fov_deg"] = abs(a["fov"] - b["fov"])
    d["chief_y_mm"] = max(abs(x - y) for x, y in zip(a["chief_y"], b["chief_y"], strict=True))
    d["chief_xy_mm"] = float(np.max(np.abs(np.asarray(a["chief_xy"]) - b["chief_xy"])))
    ra, rb = np.asarray(a["rms_um"]), np.asarray(b["rms_um"])
    d["rms_um"] = float(np.max(np.abs(ra - rb)))
    d["rms_poly_um"] = float(np.max(np.abs(np.asarray(a["rms_poly_um"]) - b["rms_poly_um"])))
    d["index_d"] = max((abs(x - y) for x, y in zip(a["index_d"], b["index_d"], strict=True)),
                       default=0.0)
    return d


def resaved(path: str, lens, j: dict, o: dict | None, tmp: str) -> dict:
    """``lens`` (opened from ``path``) saved by ``jaxlens.save`` as ``.zmx`` and as JSON in a
    folder of its own: each must read back in jaxlens as the same lens (pytree structure and
    every number equal), and optiland must give the saved ``.zmx`` the numbers it gives the
    original ``.zmx`` (``o``; with optiland's own glass data on both)."""
    import jax.tree_util as tu

    folder = tempfile.mkdtemp(dir=tmp)
    out: dict = {}
    for ext in (".zmx", ".json"):
        saved = os.path.join(folder, pathlib.Path(path).stem + "_saved" + ext)
        jl.save(lens, saved)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            back = jl.load(saved)
        same = tu.tree_structure(back) == tu.tree_structure(lens) and all(
            np.array_equal(np.asarray(x, np.float64), np.asarray(y, np.float64), equal_nan=True)
            for x, y in zip(tu.tree_leaves(back), tu.tree_leaves(lens), strict=True))
        out[f"reloads_identical{ext}"] = bool(same)
        if ext == ".zmx":
            try:
                o3 = optiland_numbers(saved, j["wavelengths"], j["primary"], j["fields"])
                out["diff_saved_vs_jaxlens"] = compare(j, o3)
                if o is not None:
                    out["diff_saved_vs_original"] = compare_optiland(o, o3)
            except Exception as e:  # noqa: BLE001
                out["optiland_saved_error"] = f"{type(e).__name__}: {e}"
    return out


def evaluate(path: str, tmp: str, resave: bool = False) -> dict:
    """One file: jaxlens's and optiland's numbers and their differences (with ``resave``,
    and a ``.zmx`` file: :func:`resaved` too)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(path)
    rec = {"file": path}
    zmx = path
    if path.endswith(".json"):
        zmx = os.path.join(tmp, pathlib.Path(path).stem + ".zmx")
        jl.save(lens, zmx)
        twin = path[:-5] + ".zmx"
        if os.path.exists(twin):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                jt = jaxlens_numbers(jl.load(twin))
            rec["twin_zmx"] = twin
            rec["jaxlens_twin"] = jt
    j = jaxlens_numbers(lens)
    rec["jaxlens"] = j
    if "jaxlens_twin" in rec:
        jt = rec["jaxlens_twin"]
        rec["twin_max_rel"] = max(
            [abs(j[k] - jt[k]) / abs(jt[k]) for k in SCALARS if jt[k] is not None]
            + [float(np.max(np.abs(np.asarray(j["rms_um"]) - jt["rms_um"])))])
    try:
        o = optiland_numbers(zmx, j["wavelengths"], j["primary"], j["fields"])
    except Exception as e:  # noqa: BLE001  (report whatever optiland raises)
        rec["optiland_error"] = f"{type(e).__name__}: {e}"
        o = None
    if resave and path.lower().endswith(".zmx"):
        rec["resaved"] = resaved(path, lens, j, o, tmp)
    if o is None:
        return rec
    rec["optiland"] = o
    rec["diff"] = compare(j, o)
    o2 = optiland_numbers(zmx, j["wavelengths"], j["primary"], j["fields"], lens=lens)
    rec["optiland_jaxlens_media"] = o2
    rec["diff_jaxlens_media"] = compare(j, o2)
    rec["jaxlens_index_d"] = [float(n) for n in lens.indices(j["primary"])[1:]]
    return rec


SUMMARY_NUMBERS = ("efl", "fnum", "bfl", "total_track", "chief_height_full_field",
                   "distortion_percent", "rms_mean_um", "rms_max_um", "rms_min_um",
                   "rms_median_um", "rms_on_axis_um")
"""The numbers of summary.json's ``best`` that :func:`summary_check` re-evaluates."""


def grid_numbers(rms_um, on_axis_um: float) -> dict:
    """The classical run's RMS statistics of a field grid's pooled RMS radii (µm)."""
    r = np.asarray(rms_um, float)
    return {"rms_mean_um": float(np.mean(r)), "rms_max_um": float(np.max(r)),
            "rms_min_um": float(np.min(r)), "rms_median_um": float(np.median(r)),
            "rms_on_axis_um": float(on_axis_um)}


def reread_numbers(zmx: str, spec, n: int) -> tuple[dict, np.ndarray]:
    """The classical run's numbers of its exported ``lens.zmx`` re-read by ``jaxlens.load``:
    ``jaxlens.design.evaluate.evaluate`` (the run's own definitions: the n × n sensor grid of
    (θx, θy) fields, pooled F, d, C RMS; paraxial EFL, F/#, BFL, track; the chief ray at
    half the diagonal FoV) and the on-axis pooled RMS (``spots.rms_spot`` at (0, 0));
    ``rays_lost``: the grid's and the axis's rays (317 a field and wavelength) that jaxlens
    loses, counted as :func:`optiland_grid_numbers` counts optiland's."""
    import equinox as eqx
    import jax.numpy as jnp

    from jaxlens.analysis import spots
    from jaxlens.design.evaluate import evaluate as evaluate_design
    from jaxlens.design.evaluate import sensor_field_grid

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(zmx)
    ev = evaluate_design(lens, spec, n=n)
    lens = eqx.tree_at(lambda x: x.epd, lens.astype(jnp.float64), jnp.asarray(spec.epd))
    axis = spots.rms_spot(lens, jnp.zeros((1, 2)), jnp.asarray(spec.wavelengths))
    out = {k: getattr(ev, k) for k in SUMMARY_NUMBERS[:6]}
    out.update(grid_numbers(ev.rms_um, float(axis.polychromatic[0]) * 1e3))
    angles, _ = sensor_field_grid(spec, n)
    grid = spots.rms_spot(lens, jnp.asarray(angles), jnp.asarray(spec.wavelengths))
    vf = np.concatenate([np.asarray(grid.valid_fraction), np.asarray(axis.valid_fraction)])
    out["rays_lost"] = int(np.sum(np.rint((1.0 - vf) * len(PUPIL))))
    return out, np.asarray(ev.rms_um, float)


def optiland_grid_numbers(zmx: str, spec, angles, lens=None) -> tuple[dict, np.ndarray]:
    """optiland's numbers of the same file at the same fields and definitions as
    :func:`reread_numbers` (with ``lens``: jaxlens's media, :func:`set_media`). The EFL of
    the distortion is optiland's (image space; the run's is 1/Φ: the same in air)."""
    wl = [float(w) for w in spec.wavelengths]
    primary = wl[spec.primary]
    op, _ = optiland_optic(zmx, primary, lens)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        system = optiland_system(op)
        grid = field_numbers(op, [list(a) for a in angles], wl, primary, system["efl"])
        axis = field_numbers(op, [[0.0, 0.0]], wl, primary, system["efl"])
        # the run's chief height: y at θy = half the diagonal FoV (beyond the sensor's
        # y edge, a field whose rim rays the clear apertures may clip: its chief ray only)
        hx, hy = normalised_field(op, [0.0, spec.half_fov])
        r = op.trace_generic(hx, hy, 0.0, 0.0, primary)
        h = math.nan if missed_surfaces(op)[0] else float(np.asarray(r.y).ravel()[0])
    ftan = system["efl"] * math.tan(math.radians(spec.half_fov))
    out = {k: system[k] for k in ("efl", "fnum", "bfl", "total_track")}
    out["chief_height_full_field"] = h
    out["distortion_percent"] = 100.0 * (h - ftan) / ftan
    out.update(grid_numbers(grid["rms_poly_um"], axis["rms_poly_um"][0]))
    out["rays_lost"] = grid["rays_lost"] + axis["rays_lost"]  # of the grid and the axis
    return out, np.asarray(grid["rms_poly_um"], float)


def summary_check(summary: str) -> dict:
    """The classical run's own numbers for its best design (RUN/summary.json's ``best``)
    against its exported RUN/lens.zmx re-read by jaxlens (:func:`reread_numbers`) and by
    optiland (:func:`optiland_grid_numbers`, with optiland's glass data and with jaxlens's
    media), at the run's own field definitions (the spec in summary.json: its n × n sensor
    grid of (θx, θy) fields, n² = ``best.n_fields``). ``diff``: per number, the largest
    relative difference of the three from the summary's value, and ``rms_per_field_um``
    the largest per-field difference of the grid's pooled RMS between jaxlens's re-read
    and optiland (µm)."""
    from jaxlens.design.evaluate import sensor_field_grid
    from jaxlens.design.spec import DesignSpec

    data = json.loads(pathlib.Path(summary).read_text())
    s, spec = data["best"], DesignSpec(**data["spec"])
    n = math.isqrt(int(s["n_fields"]))
    if n * n != int(s["n_fields"]):
        raise ValueError(f"{summary}: best.n_fields = {s['n_fields']} is not a square grid")
    zmx = str(pathlib.Path(summary).parent / "lens.zmx")
    angles, _ = sensor_field_grid(spec, n)
    j, j_grid = reread_numbers(zmx, spec, n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(zmx)
    o, o_grid = optiland_grid_numbers(zmx, spec, angles)
    m, m_grid = optiland_grid_numbers(zmx, spec, angles, lens=lens)
    out: dict = {"file": zmx, "n_fields": n * n, "numbers": {}, "diff": {}}
    for k in SUMMARY_NUMBERS:
        row = {"summary": s.get(k),
               "jaxlens_reread": j[k], "optiland": o[k], "optiland_jaxlens_media": m[k]}
        out["numbers"][k] = row
        ref = row["summary"]
        out["diff"][k] = None if ref is None else {
            w: abs(row[w] - ref) / max(abs(ref), 1e-300)
            for w in ("jaxlens_reread", "optiland", "optiland_jaxlens_media")}
    out["diff"]["rms_per_field_um"] = {
        "optiland": float(np.max(np.abs(j_grid - o_grid))),
        "optiland_jaxlens_media": float(np.max(np.abs(j_grid - m_grid)))}
    out["rays_lost"] = {"jaxlens_reread": j["rays_lost"], "optiland": o["rays_lost"],
                        "optiland_jaxlens_media": m["rays_lost"]}
    return out


def _e(v) -> str:
    return "None" if v is None else f"{v:.2e}" if isinstance(v, float) else str(v)


def check_json_out(p, path: str, files: list[str]) -> None:
    """Refuse a ``--json`` that this run would write over and is not its to replace: a
    folder (found at the end, after the files), an input (a lens given as ``--json`` was
    replaced by the records), or a file that is not an earlier record of this tool."""
    if os.path.isdir(path):
        p.error(f"--json {path} is a folder; give the file to write the records to")
    if any(os.path.realpath(path) == os.path.realpath(f) for f in files):
        p.error(f"--json {path} is one of the files to evaluate; choose another file")
    if os.path.isfile(path):
        try:
            with open(path, encoding="utf-8") as fh:
                old = json.load(fh)
            ours = "export_reevaluation" in str(old.get("computed_by", ""))
        except (OSError, ValueError, AttributeError):
            ours = False
        if not ours:
            p.error(f"--json {path} exists and is not an export_reevaluation record (no "
                    f"'computed_by' naming it); this run would write over it: choose "
                    f"another file")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("paths", nargs="+", help=".zmx / .json files or folders of them")
    p.add_argument("--summary", help="a classical run's summary.json: its numbers re-evaluated "
                                     "on RUN/lens.zmx at the run's own fields")
    p.add_argument("--json", help="write every record to this file")
    p.add_argument("--resave", action="store_true",
                   help="save each .zmx file again with jaxlens.save (.zmx and JSON), check "
                        "that both reload as the same lens and that optiland gives the saved "
                        ".zmx the original's numbers")
    a = p.parse_args(argv)
    # Checked before the files are evaluated (minutes): a missing --json folder or --summary
    # failed with a traceback after all of them, a missing path was one line of the report.
    for q in a.paths:
        if not os.path.exists(q):
            p.error(f"paths: no such file or folder {q!r}")
    if a.summary is not None and not os.path.isfile(a.summary):
        p.error(f"--summary: no such file {a.summary!r} (a classical run's summary.json)")
    if a.json is not None and not os.path.isdir(os.path.dirname(os.path.abspath(a.json))):
        p.error(f"--json: no such folder for {a.json!r}")
    files = []
    for q in a.paths:
        if os.path.isdir(q):
            files += sorted(str(f) for f in pathlib.Path(q).iterdir()
                            if f.suffix in (".zmx", ".json"))
        else:
            files.append(q)
    if not files:  # the report was empty, and --json an empty record, without a word
        p.error(f"paths: no .zmx or .json file in {', '.join(a.paths)}")
    if a.json is not None:
        check_json_out(p, a.json, files)
    recs = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            try:
                r = evaluate(f, tmp, a.resave)
            except Exception as e:  # noqa: BLE001
                r = {"file": f, "jaxlens_error": f"{type(e).__name__}: {e}"}
            recs.append(r)
            if "diff" in r:
                d = r["diff"]
                print(f"{f}: " + " ".join(f"{k}={_e(v)}" for k, v in d.items())
                      + (f" twin={r['twin_max_rel']:.1e}" if "twin_max_rel" in r else ""))
                print("  with jaxlens's indices: " + " ".join(
                    f"{k}={_e(v)}" for k, v in r["diff_jaxlens_media"].items()))
            else:
                print(f"{f}: {r.get('optiland_error') or r.get('jaxlens_error')}")
            if "resaved" in r:
                print("  saved again: " + " ".join(
                    f"{k}={_e(v)}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in r["resaved"].items() if not isinstance(v, dict))
                    + "".join(f" {w}: " + " ".join(f"{k}={_e(v)}" for k, v in d.items())
                              for w in ("diff_saved_vs_jaxlens", "diff_saved_vs_original")
                              for d in [r["resaved"].get(w)] if d))
    out = {"computed_by": "optiland 0.6.3 via tools/export_reevaluation.py", "files": recs}
    if a.summary:
        out["summary"] = summary_check(a.summary)
        print(json.dumps(out["summary"], indent=1))
    if a.json:
        write_whole(a.json, json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
