"""Reference ray-aimed intercepts from optiland 0.6.3, for tests/test_ray_aiming.py.

optiland's iterative ray aiming (``optic.ray_tracer.set_aiming("iterative")``: Newton on
the launch point until the ray crosses the stop at (Px, Py)·(paraxial stop radius), as
Zemax's "Paraxial" ray aiming and jaxlens's ``aim="real"``) on the double Gauss of
``tests/refcases/double_gauss.json``, built as ``tools/conventions_reference.py`` builds it
(optiland's own glasses under the file's names). At the full field (14°, Hy = 1) and the
primary wavelength it prints, for each pupil point of ``POINTS``, the ray's (x, y) at the
stop surface and on the image surface (mm), and the RMS spot radius about the centroid of
the 21×21 square pupil grid kept inside the disc (mm).

Run with optiland's interpreter from the repository root:

    /work/optiland_venv/bin/python tools/ray_aiming_reference.py
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (0.6, 0.6), (-0.3, 0.7))


def main() -> None:
    from conventions_reference import build

    case = json.load(open(os.path.join(ROOT, "tests", "refcases", "double_gauss.json")))
    op = build(case)
    op.ray_tracer.set_aiming("iterative", max_iter=50, tol=1e-14)
    wl = case["primary_wavelength_nm"] / 1000.0
    stop = case["stop_surface_index"]
    px = np.array([p[0] for p in POINTS])
    py = np.array([p[1] for p in POINTS])
    op.trace_generic(0.0, 1.0, px, py, wl)
    sg = op.surface_group
    at_stop = np.stack([sg.x[stop], sg.y[stop]], -1)
    image = np.stack([sg.x[-1], sg.y[-1]], -1)
    g = np.linspace(-1.0, 1.0, 21)
    gx, gy = np.meshgrid(g, g)
    keep = gx * gx + gy * gy <= 1.0 + 1e-12
    op.trace_generic(0.0, 1.0, gx[keep], gy[keep], wl)
    x, y = np.asarray(sg.x[-1]), np.asarray(sg.y[-1])
    rms = float(np.sqrt(np.mean((x - x.mean()) ** 2 + (y - y.mean()) ** 2)))
    print(json.dumps({"points": POINTS, "stop": at_stop.tolist(), "image": image.tolist(),
                      "rms_spot_primary_14deg": rms, "n_grid": int(keep.sum())}, indent=1))


if __name__ == "__main__":
    main()
