"""Reference spots, intercepts and geometric |OTF| of real-ray-aimed beams (round 45a) from
optiland 0.6.3, for tests/test_aiming_round45a.py.

Run with the optiland environment's interpreter, from the repository root (jaxlens is not
imported):

    /work/optenv/bin/python tools/aim45a_reference.py

writes tests/data/aim45a/aim45a_optiland.json.

Ray aiming. optiland's robust aiming (``set_aiming("robust")``: its iterative Newton aim,
seeded from the chief ray; the plain "iterative" one fails on Laikin's 50° field) moves
each ray's launch point (an object at infinity: the beam's direction is the field's; a
finite object: the ray's direction from the object point) until the ray crosses the stop
at (Px, Py)·r_stop, the stop's centre for (0, 0). optiland sizes r_stop with the real
on-axis ray through the paraxial entrance pupil's rim (``RealReferenceStrategy``; from the
axial object point for a finite object): Zemax's "Real" aiming, jaxlens's
``aim="real_marginal"``. jaxlens's ``aim="real"`` (Zemax's "Paraxial" aiming) takes the
paraxial marginal ray's height at the stop instead; for those cases this tool makes
optiland's aimer use its own ``ParaxialReferenceStrategy`` (the paraxial marginal ray's
height at the stop, the same number), the one change made to optiland here.

Conventions shared with jaxlens (so no conversion is needed): normalised pupil coordinates
(Px, Py) on the unit disc are fractions of r_stop on the stop; fields are angles θy (deg) of
the beam's direction (0, sin θ, cos θ) for an object at infinity (optiland's Hy is θ over
its largest field: Hy = θ/θmax), and for a finite object the object point −tan θ·(z_EP −
z_object) on the object plane (optiland's ``AngleField``, jaxlens's
``sampling.object_point``: the paraxial chief ray makes the angle θ at the entrance pupil).
Laikin's file is in inches: optiland keeps them, jaxlens converts to mm (the test multiplies
by 25.4). Every lens is traced at its primary wavelength, its vignetting factors set to zero
(jaxlens's ``vignetting=None``), and, unless the case keeps them, with every aperture
removed (jaxlens's ``optics.lens.unclipped``): the beam is then bounded by the aim alone,
the unit disc of pupil points (``radiometry.in_pupil``).

For each field:

- ``spot``: on jaxlens's default spot grid (``sampling.pupil_grid(21)``: 21 points end to end
  over [-1, 1]², kept where Px² + Py² <= 1 + 1e-12, 317 rays), the rays that reach the image
  surface: their count, their centroid (x, y) and RMS radius about it;
- ``rays``: for the pupil points ``POINTS`` (chief, the four marginal rays, a skew one) the
  (x, y) on surface 1, on the stop and on the image surface, and the object-space direction
  cosines (L, M, N), and on the image surface its global z and the ray's direction cosines
  there (after the last surface);
- ``otf``: the |OTF| (tangential along y, sagittal along x; no pixel grid, no diffraction)
  of the rays of jaxlens's geometric-PSF grid (64² cell centres times the overfill 1.25, cut
  to the unit disc), ``acc40c_reference.ray_otf`` (each ray weighed cos⁴ of its launch
  direction for a finite object, as jaxlens's point source); the grid's points are aimed
  one by one as the spot's are.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import warnings
from importlib.metadata import version

import numpy as np
from optiland.distribution import BaseDistribution
from optiland.fileio import load_zemax_file
from optiland.rays.ray_aiming import initialization

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import acc40c_reference as acc  # noqa: E402

OUT = ROOT / "tests" / "data" / "aim45a"
LAIKIN = "tests/data/zmx/optiland_circular_aperture_example_with_aperture.zmx"
CASES = {
    # Laikin's 100° retrofocus lens (inches): strong pupil aberration, the stop deep inside.
    "laikin_real_marginal": dict(file=LAIKIN, aim="real_marginal", fields=[0.0, 35.0, 50.0],
                                 freqs=[100.0, 200.0, 400.0, 800.0]),
    "laikin_real": dict(file=LAIKIN, aim="real", fields=[0.0, 35.0, 50.0],
                        freqs=[100.0, 200.0, 400.0, 800.0]),
    # The same with the file's clear apertures (CLAP, optiland's RadialAperture): they clip
    # the aimed beam at 50°.
    "laikin_apertures": dict(file=LAIKIN, aim="real_marginal", fields=[0.0, 35.0, 50.0],
                             freqs=[100.0, 200.0, 400.0, 800.0], apertures=True),
    # A double Gauss (US 583336, scaled; its file aimed, "RAIM 0 2": Zemax's "Real"), 24°
    # half field, the stop the 7th of 13 surfaces; its vignetting factors set to zero.
    "dgauss_real_marginal": dict(file="tests/data/zmx/rayoptics_US00583336-2-scaled.zmx",
                                 aim="real_marginal", fields=[0.0, 17.0, 24.0],
                                 freqs=[10.0, 20.0, 40.0, 80.0]),
    "dgauss_real": dict(file="tests/data/zmx/rayoptics_US00583336-2-scaled.zmx", aim="real",
                        fields=[0.0, 17.0, 24.0], freqs=[10.0, 20.0, 40.0, 80.0]),
    # A Cooke triplet (round 43c's, f ≈ 50 mm, EPD 10), 20° half field.
    "triplet_real_marginal": dict(file="tests/data/ri43c/triplet_stopwide.zmx",
                                  aim="real_marginal", fields=[0.0, 14.0, 20.0],
                                  freqs=[10.0, 20.0, 40.0, 80.0]),
    # The triplet's object 400 mm before surface 1: its stop sized by the real ray from the
    # axial object point (not parallel to the axis); written to tests/data/aim45a/.
    "triplet_finite_real_marginal": dict(file="tests/data/aim45a/triplet_finite.zmx",
                                         aim="real_marginal", fields=[0.0, 10.0, 14.0],
                                         freqs=[10.0, 20.0, 40.0, 80.0]),
    # The triplet whose stop (3.4 mm, CLAP) is narrower than the aimed beam: it clips every
    # field's beam (the files' apertures kept).
    "triplet_stopsmall_real": dict(file="tests/data/ri43c/triplet_stopsmall.zmx", aim="real",
                                   fields=[0.0, 14.0, 20.0], freqs=[10.0, 20.0, 40.0, 80.0],
                                   apertures=True),
    # The triplet with its aperture given by the stop's size (FLOA, stop CLAP 4 mm, the other
    # surfaces' apertures removed) and Zemax's "Real" aiming (RAIM 0 2): optiland's
    # FloatByStopStrategy fills the stop's 4 mm whatever its aiming mode; jaxlens aims as
    # the file says (aim "file": as read). Written to tests/data/aim45a/.
    "triplet_floa_raim2": dict(file="tests/data/aim45a/triplet_floa_raim2.zmx", aim="file",
                               fields=[0.0, 14.0, 20.0], freqs=[10.0, 20.0, 40.0, 80.0],
                               apertures=True),
}
FINITE_MM = 400.0
FLOA_STOP = 4.0
POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (-1.0, 0.0), (0.6, -0.5))
SPOT_SIDE = 21


class Given(BaseDistribution):
    def __init__(self, x, y):
        self.x, self.y = np.asarray(x, float), np.asarray(y, float)

    def generate_points(self, num_points):
        pass


def spot_grid():
    u = np.linspace(-1.0, 1.0, SPOT_SIDE)
    px, py = np.meshgrid(u, u, indexing="xy")
    keep = px**2 + py**2 <= 1.0 + 1e-12
    return px[keep], py[keep]


def trace(op, hy, px, py, wl):
    """optiland's aimed trace of pupil points."""
    op.trace(0.0, hy, wl, None, Given(px, py))
    return op.surface_group


def write_finite() -> None:
    """tests/data/ri43c/triplet_stopwide.zmx with its object ``FINITE_MM`` before surface 1."""
    text = (ROOT / "tests" / "data" / "ri43c" / "triplet_stopwide.zmx").read_text()
    head, sep, rest = text.partition("SURF 0")
    rest = rest.replace("DISZ INFINITY", f"DISZ {FINITE_MM}", 1)
    head = head.replace("NOTE 0 Written by tools/ri43c_reference.py (relative illumination, "
                        "round 43c)", "NOTE 0 tools/aim45a_reference.py: ri43c's "
                        f"triplet_stopwide, object at {FINITE_MM} mm")
    (OUT / "triplet_finite.zmx").write_text(head + sep + rest)


def write_floa() -> None:
    """tests/data/ri43c/triplet_stopwide.zmx with FLOA, RAIM 0 2 and a stop CLAP of
    ``FLOA_STOP`` (its other CLAPs removed)."""
    lines = (ROOT / "tests" / "data" / "ri43c" / "triplet_stopwide.zmx").read_text().splitlines()
    out, in_stop = [], False
    for ln in lines:
        key = ln.split()[0] if ln.split() else ""
        if key == "ENPD":
            out += ["FLOA", "RAIM 0 2 1 1 0 0 0 0 0"]
            continue
        if key == "NOTE":
            ln = "NOTE 0 tools/aim45a_reference.py: ri43c's triplet_stopwide, FLOA, RAIM 2"
        if key == "SURF":
            in_stop = False
        if key == "STOP":
            in_stop = True
        if key in ("CLAP", "DIAM") and in_stop:
            ln = (f"  CLAP 0 {FLOA_STOP} 0" if key == "CLAP"
                  else f'  DIAM {FLOA_STOP} 1 0 0 1 ""')
        elif key == "CLAP":
            continue
        out.append(ln)
    (OUT / "triplet_floa_raim2.zmx").write_text("\n".join(out) + "\n")


def main() -> None:
    warnings.filterwarnings("ignore")
    OUT.mkdir(parents=True, exist_ok=True)
    write_finite()
    write_floa()
    out = {"source": "optiland 0.6.3 (tools/aim45a_reference.py)",
           "optiland": version("optiland"), "points": POINTS, "spot_side": SPOT_SIDE,
           "mtf_cells": acc.MTF_CELLS, "mtf_overfill": acc.MTF_OVERFILL, "cases": {}}
    real_strategy = initialization.RealReferenceStrategy.calculate_stop_radius
    for name, spec in CASES.items():
        if spec["aim"] == "real":  # Zemax's "Paraxial" aiming: the paraxial stop size
            initialization.RealReferenceStrategy.calculate_stop_radius = (
                lambda self: initialization.ParaxialReferenceStrategy(
                    self.optic).calculate_stop_radius())
        else:
            initialization.RealReferenceStrategy.calculate_stop_radius = real_strategy
        op = load_zemax_file(str(ROOT / spec["file"]))
        for f in op.fields.fields:
            f.vx = f.vy = 0.0
        if not spec.get("apertures"):
            for s in op.surface_group.surfaces:
                s.aperture = None
        acc.tight(op)
        op.ray_tracer.set_aiming("robust", max_iter=50, tol=1e-13)
        wl = float(op.primary_wavelength)
        stop = int(op.surface_group.stop_index)
        r_stop = initialization.get_stop_radius_strategy(op, "robust").calculate_stop_radius()
        hmax = float(op.fields.max_field)
        # Under FLOA the aimed rim lands on the stop's edge (4 mm): which rim rays pass it is
        # rounding, so the spot grid's rim points are not compared there.
        res = {"file": spec["file"], "aim": spec["aim"], "apertures": bool(spec.get("apertures")),
               "rim_on_stop_edge": spec["aim"] == "file",
               "primary_um": wl, "stop_surface": stop, "stop_radius": float(r_stop),
               "freqs": spec["freqs"], "fields": []}
        for fdeg in spec["fields"]:
            hy = fdeg / hmax
            gx, gy = spot_grid()
            sg = trace(op, hy, gx, gy, wl)
            alive = (np.asarray(sg.intensity[-1]) > 0) & np.isfinite(np.asarray(sg.x[-1]))
            xy = np.stack([np.asarray(sg.x[-1]), np.asarray(sg.y[-1])], -1)[alive]
            cen = xy.mean(0)
            rms = math.sqrt(float(np.mean(np.sum((xy - cen) ** 2, -1))))
            px = np.array([p[0] for p in POINTS])
            py = np.array([p[1] for p in POINTS])
            sg = trace(op, hy, px, py, wl)
            launch = op.ray_tracer.ray_generator.generate_rays(0.0, hy, px, py, wl)
            rays = {key: np.stack([np.asarray(sg.x[i]), np.asarray(sg.y[i])], -1).tolist()
                    for key, i in (("surface1", 1), ("stop", stop), ("image", -1))}
            rays["direction"] = np.stack([np.asarray(launch.L), np.asarray(launch.M),
                                          np.asarray(launch.N)], -1).tolist()
            rays["image_direction"] = np.stack([np.asarray(sg.L[-1]), np.asarray(sg.M[-1]),
                                                np.asarray(sg.N[-1])], -1).tolist()
            rays["image_z"] = np.asarray(sg.z[-1]).tolist()
            rays["alive"] = (np.asarray(sg.intensity[-1]) > 0).tolist()
            otf = acc.ray_otf(op, (0.0, hy), (0.0, fdeg), wl, spec["freqs"], stop, math.inf,
                              not op.object_surface.is_infinite)
            res["fields"].append({"field_deg": fdeg, "hy": hy,
                                  "spot": {"rays": int(alive.sum()), "centroid": cen.tolist(),
                                           "rms": rms},
                                  "rays": rays, "otf": otf})
        out["cases"][name] = res
    initialization.RealReferenceStrategy.calculate_stop_radius = real_strategy
    (OUT / "aim45a_optiland.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
