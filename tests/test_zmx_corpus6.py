"""What the sixth corpus round of 2026-12-02 (round 36c; /work/zmx_probe/corpus6, not committed:
its sources are in its SOURCES6.txt) showed.

The stored index holds few .zmx files as text (OpticStudio saves UTF-16, which it keeps as
binary); most of the text ones were read in earlier rounds. New here: two Zemax 5.2 files
(``VERS 50203``) of a pulse-front-tilt bench for a spatial light modulator
(krishk97/Zemax-DLA-SLM): a 600 lines/mm grating between coordinate breaks, fold mirrors
with tilt pickups, toroidal cylinders, an empty grid-phase SLM, four and five configurations
and a virtual object; two Zemax 2006 course files (Kraken-Optical-Simulator: a doublet
pivoted 5° about a point by breaks with pickups and negative thicknesses, its entrance
pupil PUPD's 33.86421929753 mm to 2e-13; a Galilean expander in afocal mode) and three lens
forms of the generator round 9 read. Those five opened, lenient and strict, and trace the
rays optiland 0.6.3 traces (to 7e-14 mm, tools/check_rays.py). The bench showed three
classes:

* ``PPAR 3 -1 1 0`` on the break after the grating: a parameter solve whose source is -1, no
  surface, so not a pickup (the reader refused the line: "source surface must be >= 0"). Its
  PARM 3, -3.52674995222e-4°, is the grating equation's angle, asin(sin 28.685° − 0.6 ×
  0.8) = -3.5267499522834e-4° (to 6e-15°): the break turns the axis onto the diffracted
  chief ray (Zemax's chief-ray solve, by its value). The file's value is kept, with a
  warning naming the line; under ``strict`` it is refused (the solve is not re-solved).
* ``TYPE GRID_PHA`` with a grid of zeros (``COMM START SLM (EMPTY)``, ``GDAT 5 5`` and 25
  ``GARR`` lines of 0): a phase interpolated on a grid, here no phase at all, so the surface
  is the STANDARD one of its CURV and CONI (it was refused as an unsupported type); its
  configurations flip a parameter (``PRAM 22``), which acts on that zero phase only, so
  they open too. A nonzero grid is still refused, naming the GARR line.
* An object thickness below 0 (``DISZ -1000``: a virtual object, the beam converging on a
  point after surface 1) was refused as "object distance must be > 0"; it was then refused
  saying why, and from round 37c it is read (tests/test_zmx_corpus7.py).

Object-space telecentric files stay refused (tests/test_zmx_round11.py): a ``Lens`` holds
its fields as chief-ray angles (deg) toward an entrance pupil at a finite distance and its
aperture as that pupil's diameter (mm); a telecentric object space needs fields as object
heights with every chief ray parallel to the axis and the aperture as an object-space cone
(NA), another pupil model that the sampling, aiming and paraxial code read throughout.

The snippets below are hand-written after the bench's lines; the references are the grating
equation and the files' own values.
"""

import math

import equinox as eqx
import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.lens import unclipped
from jaxlens.tracing.forward import trace_path

jax.config.update("jax_enable_x64", True)

SOLVED_TILT = "-3.526749952220E-004"  # the bench's PARM 3 after the grating, degrees


def _cb(n, tilt_x, ppar=None, disz="0"):
    lines = [
        f"SURF {n}",
        "  TYPE COORDBRK",
        "  CURV 0.0",
        "  PARM 1 0",
        "  PARM 2 0",
        f"  PARM 3 {tilt_x}",
    ]
    lines += [f"  PPAR 3 {ppar}"] if ppar else []
    return lines + ["  PARM 4 0", "  PARM 5 0", "  PARM 6 0", f"  DISZ {disz}"]


def _grid(n, value="0.000000000000E+000", points=4):
    z = "0.000000000000E+000"
    lines = [
        f"SURF {n}",
        "  COMM START SLM (EMPTY)",
        "  TYPE GRID_PHA",
        "  CURV 0.0",
        "  PARM 0 -1",
        "  PARM 1 0",
        "  PARM 2 1",
        f"  GDAT 2 2 1 1 {z} {z}",
    ]
    lines += [f"  GARR {i} {value if i == 3 else z} {z} {z} {z} 0" for i in range(points)]
    return lines + ["  DISZ 50", "  DIAM 5.5 1 0"]


def _bench(
    *, ppar="-1 1 0", grid_value="0.000000000000E+000", grid_points=4, obj="INFINITY", configs=True
):
    """After krishk97's pft_slm_v1.ZMX (Zemax 5.2): the stop, a break tilting 28.685° about
    x, a 0.6 lines/µm grating in order 1 at 0.8 µm, the break whose tilt is solved (PPAR -1),
    100 mm to an empty grid-phase SLM, 50 mm to the image; two configurations flip the
    SLM's parameter as the file's PRAM 22 rows do."""
    head = [
        "VERS 50203 266 6789",
        "MODE SEQ",
        "UNIT MM X W X CM",
        "ENPD 10",
        "FTYP 0 0 1 1",
        "XFLN 0",
        "YFLN 0",
        "WAVM 1 0.8 1",
        "PWAV 1",
        "GCAT SCHOTT",
        "SURF 0",
        "  TYPE STANDARD",
        "  CURV 0.0",
        f"  DISZ {obj}",
        "SURF 1",
        "  STOP",
        "  TYPE STANDARD",
        "  CURV 0.0",
        "  DISZ 0",
        "  DIAM 25 1 0",
    ]
    body = _cb(2, "-2.868500000000E+001")
    body += [
        "SURF 3",
        "  COMM GRATING",
        "  TYPE DGRATING",
        "  CURV 0.0",
        "  PARM 1 0.6",
        "  PARM 2 1",
        "  DISZ 0",
        "  DIAM 25 1 0",
    ]
    body += _cb(4, SOLVED_TILT, ppar=ppar, disz="100")
    body += _grid(5, grid_value, grid_points)
    body += ["SURF 6", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0"]
    tail = []
    if configs:
        tail = [
            "MNUM 2",
            "PRAM  5   1 -1.0 0 0 0 1 1 1.0 0.0 2",
            "PRAM  5   2 0.0 0 0 0 1 1 1.0 0.0 2",
        ]
    return "\n".join(head + body + tail) + "\n"


def _axis_ray_on_image(lens):
    """The image intercept (the image surface's local x, y, mm) of the ray along the axis."""
    rays = jl.Rays(np.array([[0.0, 0.0, -1.0]]), np.array([[0.0, 0.0, 1.0]]), 0.8)
    with jax.disable_jit():  # one small lens: faster than compiling
        path = trace_path(unclipped(lens), rays)
    return np.asarray(path.origin[-1])[0, :2]


# ------------------------------------------------------------------ PPAR with source -1


def test_solved_tilt_is_the_grating_equations_angle():
    """The reference: the bench's saved tilt is the order-1 diffraction angle at 0.8 µm."""
    angle = math.degrees(math.asin(math.sin(math.radians(28.685)) - 0.6 * 0.8))
    assert angle == pytest.approx(float(SOLVED_TILT), abs=1e-13)


def test_parameter_solve_without_a_source_keeps_the_files_value():
    with pytest.warns(
        zmx.ZmxWarning,
        match=r"<zmx>:\d+: 'PPAR 3 -1 1 0' on surface 4 is a "
        r"solve of its PARM 3 that reads no surface .*is kept",
    ):
        lens = zmx.loads(_bench())
    brk = lens.surfaces[3]
    assert float(brk.tilt_x) == float(SOLVED_TILT)
    # The break turns the axis onto the diffracted chief ray: the axial ray meets the image
    # at its centre (without the solved tilt it would land 150 mm × 6.2e-6 = 9e-4 mm off).
    assert np.abs(_axis_ray_on_image(lens)).max() < 1e-9


def test_parameter_solve_without_a_source_is_refused_under_strict():
    with pytest.raises(
        ValueError,
        match=r"<zmx>:\d+: 'PPAR 3 -1 1 0' on surface 4 .*"
        r"strict mode",
    ):
        zmx.loads(_bench(), strict=True)


def test_parameter_pickup_still_checks_its_source():
    """A pickup (source >= 0) is still checked against the file's surfaces."""
    with pytest.raises(ValueError, match=r"reads surface 9, which the file does not have"):
        zmx.loads(_bench(ppar="9 1 0"))


# ------------------------------------------------------------------ GRID_PHA of zeros


def test_empty_grid_phase_reads_as_its_standard_surface():
    lens = zmx.loads(_bench(ppar=None))
    plain = _bench(ppar=None).split("SURF 5")
    rest = plain[1].split("SURF 6")[1]
    plain = zmx.loads(
        plain[0] + "SURF 5\n  TYPE STANDARD\n  CURV 0.0\n  DISZ 50\n  DIAM 5.5 1 0\nSURF 6" + rest
    )
    assert type(lens.surfaces[4]) is jl.Standard
    assert eqx.tree_equal(lens.surfaces, plain.surfaces)
    assert lens.apertures == plain.apertures


def test_grid_phase_configurations_open():
    """PRAM rows of the grid surface (its order, -1 then 0) change nothing the lens holds."""
    one = zmx.loads(_bench(ppar=None), config=1)
    two = zmx.loads(_bench(ppar=None), config=2)
    assert np.array_equal(_axis_ray_on_image(one), _axis_ray_on_image(two))


def test_nonzero_grid_phase_is_refused_naming_the_point():
    with pytest.raises(
        ValueError,
        match=r"<zmx>:\d+: GRID_PHA with a nonzero phase grid is "
        r"not supported.*'GARR 3 0.25 ",
    ):
        zmx.loads(_bench(ppar=None, grid_value="0.25"))


def test_grid_phase_missing_points_is_refused():
    with pytest.raises(ValueError, match=r"2 × 2 grid needs GARR lines 0..3 once each, got 3"):
        zmx.loads(_bench(ppar=None, grid_points=3))


# ------------------------------------------------------------------ a virtual object


def test_virtual_object_opens():
    """Round 37c: a virtual object is read (tests/test_zmx_corpus7.py traces such files
    against optiland); before, 'DISZ -1000' was refused."""
    lens = zmx.loads(_bench(ppar=None, obj="-1000", configs=False))
    assert float(lens.object_distance) == -1000.0
