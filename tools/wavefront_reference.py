"""Reference OPD, wavefront statistics and Zernike coefficients from optiland, for
tests/test_wavefront.py.

optiland 0.6.3 (not a jaxlens dependency) analyses the Cooke triplet (jaxlens.zoo,
``jaxlens/data/lenses/cooke_triplet.json``) rebuilt at the d line by
``benchmarks.optiland_ref.build_optic`` (the same geometry, jaxlens's indices there), fields
θy = 0, 14, 20 deg (optiland's Hy = θ/20), with its "chief_ray" strategy (reference sphere on
the chief ray's image point through the paraxial exit pupil):

- ``optiland.wavefront.OPD`` at a few pupil points (a distribution holding exactly those
  points), in waves;
- the same on the uniform 33 × 33 grid cut to the disc (optiland's "uniform"
  distribution; jaxlens ``wavefront(..., grid=33)`` samples the same points): optiland's own
  ``OPD.rms()`` (to the chief ray, no piston removed), the RMS and P-V with the mean
  removed, and with piston and tilt removed by ``Wavefront.fit_and_remove_tilt(...,
  remove_piston=True)``;
- ``optiland.zernike.ZernikeFit`` of that grid's OPD: 37 Noll terms and 36 Fringe terms
  (optiland's Fringe numbering follows the formula past Z36; the Fringe Z37 is R_12^0);
- the OPD at the same points for an object 500 mm before surface 1 (optiland's object
  thickness set to 500 mm, the same angle fields; jaxlens ``depth=500``).

Run it with optiland's interpreter from the repository root and paste its output into the
test file:

    /work/optiland_venv/bin/python tools/wavefront_reference.py
"""

from __future__ import annotations

import os
import sys
import textwrap
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

FIELDS = (0.0, 14.0, 20.0)
POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.0, 0.5), (0.0, -0.5), (1.0, 0.0),
          (0.5, 0.0), (0.6, 0.6), (-0.3, 0.7))
GRID = 33
FINITE_DEPTH = 500.0


def main() -> None:
    import jax

    jax.config.update("jax_enable_x64", True)
    from importlib.metadata import version

    from optiland.distribution import BaseDistribution
    from optiland.wavefront import OPD, Wavefront
    from optiland.zernike import ZernikeFit

    import jaxlens
    from benchmarks import optiland_ref

    class Points(BaseDistribution):
        def generate_points(self, num_points):
            self.x = np.array([p[0] for p in POINTS])
            self.y = np.array([p[1] for p in POINTS])

    lens = jaxlens.zoo.cooke_triplet()
    wl = float(lens.primary_wavelength)
    top = max(FIELDS)
    op = optiland_ref.build_optic(lens, wl)
    for surf in op.surfaces:  # Newton to round-off, as tools/aberrations_reference.py
        if hasattr(surf.geometry, "tol"):
            surf.geometry.tol = 1e-15
    op.fields.add(y=top)
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for th in FIELDS:
            f = (0.0, th / top)
            pts = Points()
            pts.generate_points(0)
            at = OPD(op, f, wl, distribution=pts)
            opd_pts = np.asarray(at.get_data(at.fields[0], at.wavelengths[0]).opd)
            g = OPD(op, f, wl, num_rays=GRID, distribution="uniform")
            d = g.get_data(g.fields[0], g.wavelengths[0])
            keep = np.asarray(d.intensity) > 0
            w = np.asarray(d.opd)[keep]
            x = np.asarray(g.distribution.x)[keep]
            y = np.asarray(g.distribution.y)[keep]
            # Tilt as jaxlens removes it: a least-squares plane in (Px, Py).
            a = np.stack([np.ones_like(x), x, y], -1)
            wt = w - a @ np.linalg.lstsq(a, w, rcond=None)[0]
            # optiland's own fit is a plane in the exit-pupil coordinates (mm on the
            # reference sphere), which pupil distortion bends against (Px, Py).
            wx = np.asarray(Wavefront.fit_and_remove_tilt(d, remove_piston=True))[keep]
            noll = np.asarray(ZernikeFit(x, y, w, "noll", 37).coeffs)
            fringe = np.asarray(ZernikeFit(x, y, w, "fringe", 36).coeffs)
            out[th] = dict(
                opd=opd_pts.tolist(), count=int(keep.sum()), rms_chief=float(g.rms()),
                rms=float(np.std(w)), pv=float(np.ptp(w)), rms_tilt_removed=float(np.std(wt)),
                pv_tilt_removed=float(np.ptp(wt)), rms_tilt_removed_exit_pupil=float(np.std(wx)),
                noll=noll.tolist(), fringe=fringe.tolist())
    print(f"# optiland {version('optiland')}, tools/wavefront_reference.py "
          f"(Cooke triplet, {wl} µm, uniform grid {GRID})")
    print(textwrap.fill(f"OPTILAND_POINTS = {POINTS!r}", 98, subsequent_indent=" " * 19))
    print("OPTILAND = {")
    for th, v in out.items():
        print(f"    {th!r}: {{")
        for k, val in v.items():
            if isinstance(val, list):
                body = ", ".join(f"{a:.12g}" for a in val)
                print(textwrap.fill(f"{k!r}: [{body}],", 98, initial_indent=" " * 8,
                                    subsequent_indent=" " * 12))
            else:
                print(f"        {k!r}: {val!r},")
        print("    },")
    print("}")
    op.updater.set_thickness(FINITE_DEPTH, 0)
    print(f"# the object {FINITE_DEPTH} mm before surface 1: OPD (waves) at OPTILAND_POINTS")
    print("OPTILAND_FINITE = {")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for th in FIELDS:
            pts = Points()
            pts.generate_points(0)
            at = OPD(op, (0.0, th / top), wl, distribution=pts)
            body = ", ".join(f"{a:.12g}" for a in at.get_data(at.fields[0], at.wavelengths[0]).opd)
            print(textwrap.fill(f"{th!r}: [{body}],", 98, initial_indent=" " * 4,
                                subsequent_indent=" " * 8))
    print("}")


if __name__ == "__main__":
    main()
