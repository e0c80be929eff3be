"""Reference image intercepts for tests/test_vignetting.py, from optiland 0.6.3.

Run with optiland's interpreter (optiland is a reference, not a jaxlens dependency):

    /work/optiland_venv/bin/python tools/vignetting_reference.py \
        /work/zmx_probe/corpus/pyzdde_Tessar_lens_using_vignetting_factors.ZMX

optiland reads the file's VCXN/VCYN (it applies the compression only, about the pupil
centre, to the nearest field's factors) but drops VDXN/VDYN (it prints "Vignette
decentering is not supported") and VANN. So the script clears optiland's vignetting
factors and maps each pupil point by hand with OpticStudio's definition,
Px' = VDX + Px·(1 − VCX), Py' = VDY + Py·(1 − VCY) (VAN is 0 in this file), then traces
the unvignetted real ray at (Px', Py'): the ray OpticStudio traces at (Px, Py). Prints the
image-surface (x, y) in mm at the primary wavelength, paraxial ray aiming (the file's RAIM
0), one line per (field, Px, Py), as Python literals for the test file.

The glasses: optiland resolves this file's BAF4 and KF9 to other catalogs' glasses (HIKARI
BAF4, N-KF9 by a fuzzy match), whose indices differ from the SCHOTT ones jaxlens reads in
the 5th decimal. The comparison is of the ray geometry and the vignetting map, not of
glass data, so every medium gets the index jaxlens takes at the primary wavelength
(``INDICES``, printed by ``float(m.index(0.589))`` for ``lens.materials``).
"""

import contextlib
import io
import sys
from importlib.metadata import version

import numpy as np
from optiland.fileio import load_zemax_file

INDICES = [1.6126428468576401, 1.0, 1.6055197471525104, 1.0, 1.0, 1.5233373744874135,
           1.6126428468576401, 1.0]  # after lens surfaces 1..8 at 0.589 µm (SK4, BAF4, KF9)
PUPIL = [(0.0, 1.0), (0.0, -1.0), (0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.6, -0.5)]


def factors(path: str) -> dict:
    """VDXN..VANN of the file, read here by hand (one list per keyword)."""
    raw = open(path, "rb").read()
    text = raw.decode("utf-16") if raw[:2] in (b"\xff\xfe", b"\xfe\xff") else raw.decode()
    out = {}
    for line in text.splitlines():
        tok = line.split()
        if tok and tok[0] in ("VDXN", "VDYN", "VCXN", "VCYN", "VANN", "YFLN"):
            out[tok[0]] = [float(t) for t in tok[1:]]
    return out


def main(path: str) -> None:
    assert version("optiland") == "0.6.3", version("optiland")
    with contextlib.redirect_stdout(io.StringIO()):
        optic = load_zemax_file(path)
    v = factors(path)
    for i, n in enumerate(INDICES, start=1):
        optic.set_index(n, i)
    assert not any(v["VANN"]), "this script maps without the rotation (VAN = 0 only)"
    ys = [f.y for f in optic.fields.fields]
    for f in optic.fields.fields:  # clear optiland's own (compression-only) factors
        f.vx = 0.0
        f.vy = 0.0
    fmax = max(abs(y) for y in ys)
    wl = optic.primary_wavelength
    print(f"# optiland 0.6.3, primary wavelength {wl} um, fields {ys}")
    for i, y in enumerate(ys):
        for px, py in PUPIL:
            qx = v["VDXN"][i] + px * (1.0 - v["VCXN"][i])
            qy = v["VDYN"][i] + py * (1.0 - v["VCYN"][i])
            rays = optic.trace_generic(0.0, y / fmax, qx, qy, wl)
            x, yy = float(np.ravel(rays.x)[0]), float(np.ravel(rays.y)[0])
            print(f"    ({i}, {px!r}, {py!r}, {x!r}, {yy!r}),")


if __name__ == "__main__":
    main(sys.argv[1])
