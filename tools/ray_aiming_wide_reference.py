"""Reference ray-aimed intercepts from optiland 0.6.3 on a wide-angle lens, for
tests/test_ray_aiming_robust.py.

The lens: Laikin's 100° wide-angle lens, ``tests/data/zmx/
optiland_circular_aperture_example_with_aperture.zmx`` (UNIT IN; fields 0, 35, 50°), read by
optiland's own ``.zmx`` reader. At its full field (50°, Hy = 1), with optiland's iterative
ray aiming (``set_aiming("iterative")``: Newton on the launch point until the ray crosses
the stop at (Px, Py) times a stop radius that optiland sizes with the real on-axis marginal
ray, as Zemax's "Real" ray aiming and jaxlens's ``aim="real_marginal"``), it prints, for
each pupil point of ``POINTS`` at the primary wavelength, the ray's (x, y) at the stop and
on the image surface in optiland's lens units, and the stop radius it aims at.

Run with optiland's interpreter from the repository root:

    /work/optiland_venv/bin/python tools/ray_aiming_wide_reference.py
"""

from __future__ import annotations

import json
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FILE = os.path.join(ROOT, "tests", "data", "zmx",
                    "optiland_circular_aperture_example_with_aperture.zmx")
POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (0.6, 0.6), (-0.3, 0.7))


def main() -> None:
    from optiland.fileio import load_zemax_file
    from optiland.rays.ray_aiming.initialization import get_stop_radius_strategy

    op = load_zemax_file(FILE)
    op.ray_tracer.set_aiming("robust")
    wl = float(op.primary_wavelength)
    stop = op.surfaces.stop_index
    r_stop = get_stop_radius_strategy(op, "robust").calculate_stop_radius()
    px = np.array([p[0] for p in POINTS])
    py = np.array([p[1] for p in POINTS])
    op.trace_generic(0.0, 1.0, px, py, wl)
    sg = op.surface_group
    print(json.dumps({"points": POINTS, "wavelength_um": wl, "stop_index": int(stop),
                      "stop_radius": float(r_stop),
                      "stop": np.stack([sg.x[stop], sg.y[stop]], -1).tolist(),
                      "image": np.stack([sg.x[-1], sg.y[-1]], -1).tolist()}, indent=1))


if __name__ == "__main__":
    main()
