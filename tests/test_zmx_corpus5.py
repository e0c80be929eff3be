"""What the fifth round of real .zmx files of 2026-12-02 (/work/zmx_probe/corpus5, 31 files,
not committed: their sources are in its SOURCES5.txt) showed.

The files: Thorlabs stock lenses saved by Zemax 2012 (wagenadl/octave-wagenaarlab and
DCC-Lab/RayTracing: achromats, negative achromats with virtual images, B270 aspheric
condensers with the stop after the lens, N-BK7 and S-LAH64 aspheres up to r^16, catalogs
CORNING, HERAEUS and HOYA named in GCAT, ENVD 20 1 1), Zemax 2006 course files
(dragonleopardpig/Kraken-Optical-Simulator: a laser-tracking telescope of two off-axis
parabolas and two fold mirrors, two 90° parabolas with FLOA, two afocal beam expanders with
curvature pickups, a Cooke triplet with substitution-solved glasses, an f-theta lens, a
4-configuration zoom of stock lenses), PyZDDE's samples (a concentric two-mirror system with a
decentred stop mirror and 10 fields in x and y, a doublet with a marginal-ray-angle solve, a
Double Gauss in inches, OpticStudio's empty lens with ENPD 0) and a hand-written test file
that is not Zemax's format (piack97/zemax-lens-analyzer: two XFLN lines, refused so).

jaxlens opened 29 of 31, lenient and strict, and refused two with the line and the reason
(ENPD 0; XFLN given twice). Where the file or its design holds a value, jaxlens gives it:
PUPD's entrance pupil position and diameter in all seven files that have one (91.79893538 mm
for the Cooke triplet), the EFFL targets of the zoom (750, 1000, 1500, 2000 mm in
configurations 1-4: 749.997, 999.994, 1499.99, 1999.98), the Cooke's 150 mm (150.0001), the
doublet's marginal-ray-angle solve (10 mm / 0.100000001 = 99.999999 mm) and the Double
Gauss's 4 in (101.59995 mm). optiland 0.6.3 gives the same EFL with jaxlens's indices (to
3e-16 in the 26 focal files it reads, tools/check_corpus.py) and the same real rays (to
6e-13 mm in all 29, tools/check_rays.py); its own catalogs differ for old SCHOTT glasses
(B270, SF10: EFL 1e-4 apart) and it takes a substitution-solved glass from its stale nd.

One difference was the comparison tool's: optiland 0.6.3 reads a coordinate break's order
flag (``PARM 6 1``: tilt first, about z, y then x, then decenter along the tilted axes) as 0.
Kraken's laser-tracking telescope ends each fold mirror with such a break; optiland's rays
left it 52 mm from jaxlens's, its output beam 1° off axis with 1.2 mrad of angular spread,
where jaxlens's is afocal to 3e-12 rad (the design, optimised for RMS angular radius). The
tools now give optiland a copy with each such break written as order-0 breaks
(``check_corpus.split_order_flag_breaks``); optiland's rays then agree with jaxlens's to
4.5e-13 mm. The snippets below are hand-written after that file's fold; the reference is
jaxlens reading the original (the split copy must be the same lens) and, for the fold, the
geometry worked out in the docstring.
"""

import jax
import numpy as np
from helpers import check_corpus_tool

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.coordinates import frame_of
from jaxlens.optics.lens import unclipped
from jaxlens.tracing.forward import trace_path

jax.config.update("jax_enable_x64", True)


def _cb(n, parms, disz):
    lines = [f"SURF {n}", "  TYPE COORDBRK", "  CURV 0"]
    lines += [f"  PARM {i} {v}" for i, v in enumerate(parms, 1)]
    return lines + [f"  DISZ {disz}"]


# After Kraken's laser-tracking telescope (Class 16/Off axis parabola.ZMX, surfaces 5-7): a
# break that decentres 17 mm and tilts 45° about x, a flat mirror, and a break with the same
# tilt, the decentre undone (+17) and the order flag 1, then 100 mm to a flat image.
FOLD = (
    ["UNIT MM", "ENPD 4", "WAVM 1 0.55 1", "PWAV 1", "SURF 0", "  CURV 0", "  DISZ INFINITY"]
    + ["SURF 1", "  STOP", "  CURV 0", "  DISZ 50"]
    + _cb(2, [0, -17, 45, 0, 0, 0], 0)
    + ["SURF 3", "  CURV 0", "  DISZ 0", "  GLAS MIRROR"]
    + _cb(4, [0, 17, 45, 0, 0, 1], 100)
    + ["SURF 5", "  CURV 0", "  DISZ 0", "BLNK ", "MNUM 1 1"]
)


def _image_points(text, y0=(0.0, 1.5)):
    """Global image intercepts of rays parallel to the axis at heights ``y0``."""
    lens = zmx.loads(text)
    o = np.array([[0.0, y, -1.0] for y in y0])
    d = np.tile([0.0, 0.0, 1.0], (len(y0), 1))
    with jax.disable_jit():  # three small lenses: faster than compiling each
        path = trace_path(unclipped(lens), jl.Rays(o, d, 0.55))
    r, t = (np.asarray(a) for a in frame_of(lens))
    local = np.asarray(path.origin[-1])
    return local, local @ r.T + t


def test_an_order_flag_break_is_written_as_order_0_breaks():
    """The copy optiland reads: the order-1 break (surface 4) becomes a tilt-only break and a
    decentre break with the thickness; the surfaces after it are renumbered, the order-0
    break before it is kept as it is."""
    lines, changed = check_corpus_tool().split_order_flag_breaks(FOLD)
    assert changed
    text = "\n".join(lines)
    assert "PARM 6 1" not in text
    assert [ln for ln in lines if ln.startswith("SURF")] == [f"SURF {k}" for k in range(7)]
    assert lines[lines.index("SURF 4") :][:10] == [
        "SURF 4", "  TYPE COORDBRK", "  CURV 0", "  PARM 1 0.0", "  PARM 2 0.0",
        "  PARM 3 45.0", "  PARM 4 0.0", "  PARM 5 0.0", "  PARM 6 0.0", "  DISZ 0",
    ]  # fmt: skip
    assert lines[lines.index("SURF 5") :][:10] == [
        "SURF 5", "  TYPE COORDBRK", "  CURV 0", "  PARM 1 0.0", "  PARM 2 17.0",
        "  PARM 3 0.0", "  PARM 4 0.0", "  PARM 5 0.0", "  PARM 6 0.0", "  DISZ 100",
    ]  # fmt: skip
    assert lines[-5:] == ["SURF 6", "  CURV 0", "  DISZ 0", "BLNK ", "MNUM 1 1"]
    order0 = [ln.replace("PARM 6 1", "PARM 6 0") for ln in FOLD]
    assert check_corpus_tool().split_order_flag_breaks(order0) == (order0, False)


def test_the_split_copy_is_the_same_lens():
    """jaxlens reads the copy as the original: the same global image intercepts (1e-12 mm).
    The fold keeps the axial ray on the axis: the mirror plane, 17 mm below the axis at 45°,
    meets the axial ray 17 mm along it, where the ray turns through 90°; the second break
    tilts another 45° and moves the origin 17 mm along its tilted y axis, onto that reflected
    ray, so the ray meets the image at its local origin, 100 mm on. Read with order 0 (as
    optiland 0.6.3 reads the file), the break decentres along the y axis tilted 45° only, and
    the axial ray lands 17 (1 − cos 45°) = 4.98 mm from the image's origin."""
    original = "\n".join(FOLD) + "\n"
    lines, _ = check_corpus_tool().split_order_flag_breaks(FOLD)
    local, glob = _image_points(original)
    _, glob_split = _image_points("\n".join(lines) + "\n")
    np.testing.assert_allclose(glob_split, glob, rtol=0, atol=1e-12)
    np.testing.assert_allclose(local[0, :2], [0.0, 0.0], atol=1e-12)  # x, y in its frame
    assert abs(abs(local[1, 1]) - 1.5) < 1e-12  # a parallel ray keeps its height
    order0 = original.replace("  PARM 6 1", "  PARM 6 0")
    local0, _ = _image_points(order0)
    assert abs(np.hypot(local0[0, 0], local0[0, 1]) - 17 * (1 - np.sqrt(0.5))) < 1e-9
