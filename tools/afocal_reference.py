"""Reference output directions and angular spot sizes for tests/test_afocal.py, from
optiland 0.6.3 (a reference, not a jaxlens dependency):

    /work/optiland_venv/bin/python tools/afocal_reference.py \
        tests/data/afocal_kepler.zmx

optiland has no afocal analysis, but its real rays leave the telescope with the same
directions whatever the mode, so the script traces them (primary wavelength, paraxial ray
aiming at the entrance pupil as the file's RAIM 0 asks) and computes the angular spot here
with numpy, by the definition of ``jaxlens.analysis.afocal`` (the tangents of each ray's
angles to the chief ray in two perpendicular planes, e_x along the part of +x normal to
the chief ray, e_y = chief × e_x; RMS about their centroid) on the 21×21 pupil grid kept
inside the unit disc. Both media get the index jaxlens takes for N-BK7 at the primary
wavelength, so that glass data do not enter. Prints Python literals for the test file.
"""

import contextlib
import io
import sys
from importlib.metadata import version

import numpy as np
from optiland.fileio import load_zemax_file

N_BK7 = 1.5168000345005883  # float(jaxlens.load(FILE).materials[0].index(0.5875618)): SCHOTT
PUPIL = [(0.0, 0.0), (0.0, 1.0), (0.0, -0.7), (1.0, 0.0), (0.5, 0.5)]


def grid(n: int = 21) -> np.ndarray:
    u = np.linspace(-1.0, 1.0, n)
    px, py = np.meshgrid(u, u, indexing="xy")
    keep = px**2 + py**2 <= 1.0 + 1e-12
    return np.stack([px[keep], py[keep]], -1)


def directions(optic, hy, pts, wl) -> np.ndarray:
    rays = optic.trace_generic(0.0, hy, pts[:, 0], pts[:, 1], wl)
    return np.stack([np.ravel(rays.L), np.ravel(rays.M), np.ravel(rays.N)], -1)


def rms_angle(d: np.ndarray, c: np.ndarray) -> float:
    a = np.array([1.0, 0.0, 0.0])
    ex = a - a.dot(c) * c
    ex /= np.linalg.norm(ex)
    ey = np.cross(c, ex)
    t = np.stack([d @ ex, d @ ey], -1) / (d @ c)[:, None]
    return float(np.sqrt(np.mean(np.sum((t - t.mean(0)) ** 2, -1))))


def main(path: str) -> None:
    assert version("optiland") == "0.6.3", version("optiland")
    with contextlib.redirect_stdout(io.StringIO()):
        optic = load_zemax_file(path)
    for i in (1, 3):
        optic.updater.set_index(N_BK7, i)
    wl = optic.primary_wavelength
    ys = [f.y for f in optic.fields.fields]
    fmax = max(abs(y) for y in ys)
    print(f"# optiland 0.6.3, primary wavelength {wl} um, fields {ys}")
    print("DIRECTIONS = [  # (field, Px, Py, L, M, N)")
    for y in ys:
        d = directions(optic, y / fmax, np.array(PUPIL), wl)
        for (px, py), (L, M, N) in zip(PUPIL, d.tolist(), strict=True):
            print(f"    ({y!r}, {px!r}, {py!r}, {L!r}, {M!r}, {N!r}),")
    print("]")
    print("RMS_ANGLE = [  # (field, RMS angular radius in rad about the centroid)")
    for y in ys:
        c = directions(optic, y / fmax, np.zeros((1, 2)), wl)[0]
        print(f"    ({y!r}, {rms_angle(directions(optic, y / fmax, grid(), wl), c)!r}),")
    print("]")


if __name__ == "__main__":
    main(sys.argv[1])
