"""Reference rays for tests/test_zmx_corpus7.py: optiland 0.6.3 traces the virtual-object
files of tests/data/zmx_corpus7 (hand-written; the object thickness is negative, the object
point after surface 1, the object-space beam converging on it).

For each file, each relative field Hy in ``HY`` and each normalised pupil point (Px, Py) in
``PUPIL``: optiland's ``trace_generic`` at the primary wavelength (its own ray generation:
the line through the object point and the paraxial entrance pupil point), the ray's
image-surface intercept (x, y, z) in mm. Also optiland's paraxial EFL, entrance pupil
position and its ray-aiming setting. Run with optiland's interpreter (jaxlens is not
imported; OPTILAND_ONLY in tests/test_input_probes_round33b.py):

    /work/optenv/bin/python tools/corpus7_reference.py

writes tests/data/zmx_corpus7/reference.json.
"""

import json
import pathlib
import warnings

FOLDER = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "zmx_corpus7"
FILES = (
    "virtual_singlet_heights.zmx",
    "virtual_singlet_angles.zmx",
    "virtual_stop_behind.zmx",
    "virtual_stop_behind_aimed.zmx",
)
HY = (0.0, 0.5, 1.0)
PUPIL = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (-1.0, 0.0), (0.5, 0.5), (0.0, 0.7))


def main():
    warnings.filterwarnings("ignore")
    from importlib.metadata import version

    from optiland.fileio import load_zemax_file

    out = {"optiland": version("optiland"), "hy": HY, "pupil": PUPIL, "files": {}}
    for name in FILES:
        op = load_zemax_file(str(FOLDER / name))
        # optiland 0.6.3 does not read RAIM: the aimed file (RAIM type 1, Zemax's
        # "Paraxial" aiming at the real stop) gets its iterative aiming by hand.
        aimed = any(
            ln.split()[:2] == ["RAIM", "0"] and ln.split()[2] == "1"
            for ln in (FOLDER / name).read_text().splitlines()
            if ln.startswith("RAIM")
        )
        if aimed:
            op.ray_tracer.set_aiming("iterative", max_iter=50, tol=1e-13)
        wl = op.primary_wavelength
        rows = []
        for hy in HY:
            row = []
            for px, py in PUPIL:
                r = op.trace_generic(0.0, hy, px, py, wl)
                row.append([float(r.x[0]), float(r.y[0]), float(r.z[0])])
            rows.append(row)
        aiming = "iterative" if aimed else "paraxial"
        out["files"][name] = {
            "image_xyz": rows,
            "efl": float(op.paraxial.f2()),
            "entrance_pupil_z": float(op.paraxial.EPL()),
            "ray_aiming": str(aiming),
        }
    text = json.dumps(out, indent=1) + "\n"
    (FOLDER / "reference.json").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
