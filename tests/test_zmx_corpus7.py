"""What the seventh corpus round of 2026-12-02 (round 37c) showed.

The stored code index's plain-text .zmx files are nearly exhausted (OpticStudio saves UTF-16,
which the index keeps as binary, and every such file of about 40 repositories checked this
round had no text). One new public file was found: DeepLens's EF 35 mm f/2 export
(singer-yang/DeepLens, lenses/camera/ef35mm_f2.0.zmx; tests/data/zmx_corpus7/SOURCES.md).
Like the DeepLens fork's file of round 9 it is written with FLOA and no DIAM on its STOP
surface: the pupil's size is not in the file, and it stays refused, naming both lines.

Fixed: a virtual object (a negative object thickness, Zemax's converging object-space beam:
the krishk97/Zemax-DLA-SLM bench of round 36c, ``DISZ -1000``) was refused. A ``Lens`` may
now hold a negative ``object_distance``: the object point lies that far after surface 1,
and its rays are the lines through it and the paraxial entrance pupil points, travelling
toward +z (``sampling.point_source``, the aiming at the real stop, ``stop_chief_ray``);
object-height fields become chief-ray angles as for a real object. The four hand-written
files of tests/data/zmx_corpus7 (a singlet with the stop on it and object heights or
angles; a stop behind the lens, its entrance pupil 16 mm after surface 1, the object 300 mm
after it, paraxial and real aiming) trace the rays optiland 0.6.3 generates and traces
itself (``trace_generic``), to 1e-13 mm (tools/corpus7_reference.py writes the reference).
A depth given to an analysis (``rms_spot(lens, depth=-5)``) is still refused: there a
negative number is far likelier a slip of sign; the lens's own object is used with None.

Object-space telecentric files stay refused (tests/test_zmx_round11.py, with the line and
the reason): a ``Lens`` has no pupil at infinity.
"""

import json
import pathlib

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import sampling
from jaxlens.io import zmx
from jaxlens.optics.lens import unclipped
from jaxlens.tracing.forward import trace_path

jax.config.update("jax_enable_x64", True)

DATA = pathlib.Path(__file__).parent / "data" / "zmx_corpus7"
REF = json.loads((DATA / "reference.json").read_text())
VIRTUAL = sorted(REF["files"])


def _fields(lens, text):
    """The field of each relative height Hy as optiland sets it: a fraction of the largest
    angle (FTYP 0) or of the largest object height (FTYP 1, linear in the angle's tangent)."""
    f = np.asarray(lens.fields)
    top = f[np.argmax(np.abs(f))]
    if "FTYP 0" in text:
        return [hy * top for hy in REF["hy"]]
    return [np.degrees(np.arctan(hy * np.tan(np.radians(top)))) for hy in REF["hy"]]


def _image_points(name):
    """jaxlens's image intercepts of the reference's rays; the aimed file's with the real
    stop's size (``aim="real_marginal"``): optiland's iterative aiming fills the real
    marginal ray's stop height, Zemax's "Real" aiming, where jaxlens reads RAIM type 1 as
    Zemax's "Paraxial" (``Lens.aim = "real"``; 4.0632 against 4.0562 mm here, the same
    difference as with the object 300 mm before surface 1)."""
    text = (DATA / name).read_text()
    lens = jl.load(DATA / name)
    pupil = np.array(REF["pupil"])
    depth = sampling.lens_depth(lens, None, "test")
    out = []
    aim = "real_marginal" if REF["files"][name]["ray_aiming"] == "iterative" else None
    for th in _fields(lens, text):
        rays = sampling.field_rays(lens, th, pupil, depth=depth, aim=aim)
        path = trace_path(unclipped(lens), rays)
        assert bool(np.all(np.asarray(path.valid[-1])))
        out.append(np.asarray(path.origin[-1]))
    return lens, np.array(out)


@pytest.mark.slow
@pytest.mark.parametrize("name", VIRTUAL)
def test_virtual_object_rays_equal_optilands(name):
    lens, got = _image_points(name)
    ref = REF["files"][name]
    assert float(lens.object_distance) < 0
    assert lens.aim == ("real" if ref["ray_aiming"] == "iterative" else "paraxial")
    assert float(jl.efl(lens)) == pytest.approx(ref["efl"], rel=1e-12)
    assert float(jl.paraxial_data(lens).entrance_pupil_z) == pytest.approx(
        ref["entrance_pupil_z"], abs=1e-9
    )
    assert np.abs(got - np.array(ref["image_xyz"])).max() < 1e-9


@pytest.mark.slow
def test_virtual_object_marginal_ray_converges():
    """The singlet (stop on surface 1, EPD 10 mm, object 100 mm after it): the axial beam
    leaves the pupil rim heading for the virtual point (slope −5/100), which the paraxial
    marginal ray gives; the image intercept is optiland's."""
    lens = jl.load(DATA / "virtual_singlet_heights.zmx")
    with jax.disable_jit():  # one ray through a singlet: faster than compiling
        rays = sampling.field_rays(
            lens, 0.0, np.array([[0.0, 1.0]]), depth=sampling.lens_depth(lens, None, "test")
        )
        y = float(trace_path(unclipped(lens), rays).origin[-1][0, 1])
    d = np.asarray(rays.direction)[0]
    assert d[1] / d[2] == pytest.approx(-0.05, rel=1e-12)
    assert float(rays.opl[0]) == pytest.approx(-np.hypot(5.0, 100.0), rel=1e-12)
    assert y == pytest.approx(
        REF["files"]["virtual_singlet_heights.zmx"]["image_xyz"][0][1][1], abs=1e-9
    )
    ym, _ = jl.paraxial.marginal_ray(lens)
    assert float(ym[0]) == pytest.approx(5.0, rel=1e-12)


def test_virtual_point_source_converges_and_the_pupil_plane_is_refused():
    """The rim ray toward a virtual point 100 mm after the pupil (on surface 1): slope
    −5/100, toward +z, its optical path to the point still ahead (negative)."""
    lens = jl.load(DATA / "virtual_singlet_heights.zmx")
    rays = sampling.point_source(lens, np.array([0.0, 0.0, 100.0]), np.array([[0.0, 1.0]]))
    d = np.asarray(rays.direction)[0]
    assert d[2] > 0 and d[1] / d[2] == pytest.approx(-0.05, rel=1e-12)
    assert float(rays.opl[0]) == pytest.approx(-np.hypot(5.0, 100.0), rel=1e-12)
    lens = jl.load(DATA / "virtual_stop_behind.zmx")
    zep = float(jl.paraxial.entrance_pupil_z(lens, lens.primary_wavelength))
    with pytest.raises(ValueError, match=r"point_source: the point's z must be .*virtual object"):
        sampling.point_source(lens, np.array([0.0, 1.0, zep]), np.zeros((1, 2)))


def test_analysis_depth_argument_still_refuses_a_negative_number():
    lens = jl.load(DATA / "virtual_singlet_heights.zmx")
    with pytest.raises(ValueError, match=r"^test: depth must be finite numbers in \(0, inf\)"):
        sampling.lens_depth(lens, -100.0, "test")
    assert float(sampling.lens_depth(lens, None, "test")) == -100.0


def test_virtual_object_saves_and_loads(tmp_path):
    lens = jl.load(DATA / "virtual_singlet_angles.zmx")
    for ext in ("json", "zmx"):
        jl.save(lens, tmp_path / f"v.{ext}")
        back = jl.load(tmp_path / f"v.{ext}")
        assert float(back.object_distance) == -100.0
    with pytest.raises(ValueError, match=r"object thickness must be nonzero .*'DISZ 0'"):
        zmx.loads((DATA / "virtual_singlet_angles.zmx").read_text().replace("DISZ -100", "DISZ 0"))


def test_deeplens_export_without_a_stop_size_is_refused_naming_the_lines():
    with pytest.raises(
        ValueError,
        match=r"ef35mm_f2\.0\.zmx:7: FLOA needs a DIAM or CLAP .*"
        r"surface 6, line 59",
    ):
        jl.load(DATA / "deeplens_ef35mm_f2.0.zmx")
