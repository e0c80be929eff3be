"""Reference ray fans and field curves from optiland, for tests/test_aberrations.py.

optiland (not a jaxlens dependency) computes them on the same geometry, rebuilt at the primary
wavelength by ``benchmarks.optiland_ref.build_optic`` (its indices are jaxlens's there):
``optiland.analysis.FieldCurvature`` (parabasal ray pairs at Py, Px = ±1e-5) and ``RayFan``
(tangential e_y and sagittal e_x against the primary chief ray), with optiland's Newton
tolerance for aspheres tightened from 1e-10 to round-off. Fields are along y, linear in
angle from 0 to each lens's largest field. Writes the JSON named by ``--out``.

    OPTILAND_PYTHON tools/aberrations_reference.py --out tests/data/aberrations_optiland.json
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

LENSES = {  # name -> lens file (repository-relative)
    "cooke_triplet": "jaxlens/data/lenses/cooke_triplet.json",
    "double_gauss": "tests/refcases/double_gauss.json",
    "cellphone6": None,  # jaxlens.zoo
}
FIELDS = 5
FAN_POINTS = 11


def main(argv=None) -> None:
    import jax

    jax.config.update("jax_enable_x64", True)
    from importlib.metadata import version

    from optiland.analysis import FieldCurvature, RayFan

    import jaxlens
    from benchmarks import optiland_ref

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    cases = {}
    for name, path in LENSES.items():
        lens = jaxlens.zoo.ZOO[name]() if path is None else jaxlens.load(path)
        wl = float(lens.primary_wavelength)
        top = float(np.max(np.abs(np.asarray(lens.fields))))
        op = optiland_ref.build_optic(lens, wl)
        for surf in op.surfaces:  # Newton to round-off (default 1e-10), as for the refcases
            if hasattr(surf.geometry, "tol"):
                surf.geometry.tol = 1e-15
        op.fields.add(y=top)  # the bridge's on-axis field stays first: Hy = θ / top
        fc = FieldCurvature(op, wavelengths=[wl], num_points=FIELDS)
        tan, sag = (np.asarray(v).tolist() for v in fc.data[0])
        fans = {}
        for hy in (0.5, 1.0):
            rf = RayFan(op, fields=[(0.0, hy)], wavelengths=[wl], num_points=FAN_POINTS)
            d = rf.data[f"{(0.0, hy)}"][f"{wl}"]
            fans[str(hy * top)] = {"tangential": np.asarray(d["y"]).tolist(),
                                   "sagittal": np.asarray(d["x"]).tolist()}
        cases[name] = {"source": path or f"jaxlens.zoo.ZOO[{name!r}]", "wavelength_um": wl,
                       "fields_deg": np.linspace(0.0, top, FIELDS).tolist(),
                       "tangential_mm": tan, "sagittal_mm": sag,
                       "fan_points": FAN_POINTS, "fans_mm": fans}
    out = {"computed_by": f"optiland {version('optiland')} via tools/aberrations_reference.py",
           "conventions": __doc__.split("\n\n")[1].replace("\n", " "), "cases": cases}
    from jaxlens.io.json_values import write_whole

    write_whole(a.out, json.dumps(out, indent=1))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
