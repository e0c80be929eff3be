"""Round 38a: object-space telecentric .zmx files (FTYP's second value 1) open and trace.

``Lens.object_na`` marks such a lens: the entrance pupil at infinity, every chief ray parallel
to the axis, fields that are object heights (mm) and an object-space NA for its aperture.
Before, the reader refused the flag. The three files in tests/data/zmx38a/ (an OBNA doublet
with object heights, a FLOA triplet with (x, y) object heights, a cone-angle doublet with
paraxial image heights) are compared with optiland 0.6.3 built through its own telecentric
API (tools/telecentric38a_reference.py; numbers in tests/data/zmx38a_optiland.json).
"""

import json
import pathlib
import warnings

import jax
import numpy as np
import pytest

from jaxlens import analysis
from jaxlens.imaging import aiming, psf, radiometry, sampling
from jaxlens.io import lensfile, zmx
from jaxlens.optics import paraxial
from jaxlens.tracing import forward

jax.config.update("jax_enable_x64", True)

DATA = pathlib.Path(__file__).resolve().parent / "data"
REF = json.loads((DATA / "zmx38a_optiland.json").read_text())
# One file in the fast suite; the others compile their own traces (3-6 s each): slow.
NAMES = [pytest.param(n, marks=() if n == "tele_doublet_obna" else pytest.mark.slow)
         for n in sorted(REF["systems"])]


def _load(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return zmx.load_zmx(DATA / "zmx38a" / f"{name}.zmx")


@pytest.mark.parametrize("name", NAMES)
def test_rays_and_first_order_data_match_optiland(name):
    """Main: real rays at the image (3 heights × 3 wavelengths × 6 pupil points), EFL,
    working F/#, image-space NA, the NA (from OBNA, the cone angle or FLOA) and the object
    heights (from paraxial image heights) agree with optiland to 1e-12."""
    ref = REF["systems"][name]
    lens = _load(name)
    assert lens.telecentric_object
    np.testing.assert_allclose(float(lens.object_na), ref["object_na"], rtol=1e-12)
    f = np.asarray(lens.fields)
    heights = np.asarray(ref["object_heights"])
    np.testing.assert_allclose(f if f.ndim == 2 else f, heights if f.ndim == 2 else heights[:, 1],
                               atol=1e-12)
    pd = paraxial.paraxial_data(lens)
    np.testing.assert_allclose(float(pd.efl_image_space), ref["efl"], rtol=1e-12)
    np.testing.assert_allclose(float(pd.working_fnum), ref["working_fnum"], rtol=1e-12)
    np.testing.assert_allclose(float(pd.stop_semi_diameter), ref["marginal_height_at_stop"],
                               rtol=1e-12)
    u = 1.0 / (2.0 * float(pd.working_fnum))
    np.testing.assert_allclose(np.sin(np.arctan(u)), ref["image_na"], rtol=1e-12)
    m = float(paraxial.image_height(lens, 1.0))
    np.testing.assert_allclose(m, ref["paraxial_magnification"], rtol=1e-12)
    pupil = np.asarray(REF["pupil"])
    for r in ref["rays"]:
        h = np.asarray(r["height"])
        rays = sampling.field_rays(lens, h if f.ndim == 2 else h[1], pupil, r["wavelength"],
                                   depth=lens.object_distance)
        out = forward.trace(lens, rays)
        assert bool(np.all(out.valid))
        np.testing.assert_allclose(np.asarray(out.origin), r["xyz"], atol=1e-12)
        np.testing.assert_allclose(np.asarray(out.direction), r["lmn"], atol=1e-12)


def test_chief_rays_leave_parallel_to_the_axis():
    lens = _load("tele_doublet_obna")
    rays = sampling.field_rays(lens, 8.0, np.zeros((1, 2)), depth=lens.object_distance)
    np.testing.assert_array_equal(np.asarray(rays.direction), [[0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(np.asarray(rays.origin), [[0.0, 8.0, -60.0]])


def test_pupil_position_refused_and_paraxial_data_say_infinity():
    """The entrance pupil's position has no finite value: refused, never the stop's image
    (which sits near, not at, infinity in these files); paraxial_data gives -inf, an infinite
    diameter and an F/# (EFL/EPD) of NaN."""
    lens = _load("tele_doublet_obna")
    with pytest.raises(ValueError, match="object-space telecentric"):
        paraxial.entrance_pupil_z(lens)
    pd = paraxial.paraxial_data(lens)
    assert float(pd.entrance_pupil_z) == -np.inf and float(pd.entrance_pupil_diameter) == np.inf
    assert np.isnan(float(pd.fnum))


def test_analyses_that_need_field_angles_refuse_clearly():
    """A collimated beam and a point source aimed at the entrance pupil need field angles
    toward a finite entrance pupil: each refuses, before tracing, naming what to use.
    (Distortion, Seidel sums, field curvature, the report and the relative illumination
    refused here until round 42a, which gave them object heights:
    tests/test_telecentric_analyses_round42a.py; the image scale and the render until round
    43a, which maps the object plane by m: tests/test_telecentric_render_round43a.py.)"""
    lens = _load("tele_doublet_obna")
    for f in (lambda: sampling.collimated(lens, 0.0, np.zeros((1, 2))),
              lambda: sampling.point_source(lens, np.array([0.0, 4.0, -50.0]), np.zeros((1, 2)))):
        with pytest.raises(ValueError, match="object-space telecentric.*paraxial.magnification"):
            f()
    assert float(aiming.image_scale(lens)) == float(paraxial.magnification(lens))
    assert np.isfinite(float(analysis.seidel(lens).sums[0]))
    assert np.isfinite(np.asarray(radiometry.relative_illumination(lens, np.array([4.0]),
                                                                   pupil=16).ri)).all()
    with pytest.raises(ValueError, match="ray aiming does not apply"):
        sampling.field_rays(lens, 4.0, np.zeros((1, 2)), depth=lens.object_distance,
                            aim="real")


@pytest.mark.slow
def test_analyses_on_object_heights_work():
    """RMS spot, chief ray (parallel to the axis: not aimed) and a PSF centred on it."""
    lens = _load("tele_doublet_obna")
    spot = analysis.rms_spot(lens, 8.0)
    assert np.all(np.isfinite(np.asarray(spot.polychromatic)))
    chief = analysis.chief_ray(lens, 8.0)
    assert abs(float(chief.origin[1]) - 8.0 * REF["systems"]["tele_doublet_obna"][
        "paraxial_magnification"]) < 0.5
    kern = psf.psf(lens, 4.0, pixel_size=0.03, kernel_size=31)  # centred on the chief ray
    assert abs(float(np.sum(kern)) - 1.0) < 0.05


def _edited(name, old, new):
    text = (DATA / "zmx38a" / f"{name}.zmx").read_text()
    assert old in text
    return text.replace(old, new)


@pytest.mark.parametrize("old,new,match", [
    ("FTYP 1 1", "FTYP 0 1", "cannot be angles"),
    ("FTYP 1 1", "FTYP 4 1", "theodolite angles"),
    ("FTYP 1 1", "FTYP 1 2", "must be 0 or 1"),
    ("OBNA 0.08 0", "ENPD 10", "entrance pupil diameter"),
    ("OBNA 0.08 0", "FNUM 4 0", "F/#"),
    ("DISZ 60.0", "DISZ INFINITY", "finite distance"),
])
def test_what_a_telecentric_file_cannot_have_is_refused(old, new, match):
    text = _edited("tele_doublet_obna", old, new)
    with pytest.raises(ValueError, match=match):
        zmx.loads(text, "t.zmx")


def test_ray_aiming_is_ignored_with_a_warning():
    text = _edited("tele_doublet_obna", "PWAV 2", "PWAV 2\nRAIM 0 1 1 1 0 0 0 0 0")
    with pytest.warns(UserWarning, match="ray aiming \\(RAIM\\) is ignored"):
        lens = zmx.loads(text, "t.zmx")
    assert lens.aim == "paraxial" and lens.telecentric_object


def test_virtual_object_refused():
    text = _edited("tele_doublet_obna", "DISZ 60.0", "DISZ -60.0")
    with pytest.raises(ValueError, match="virtual object is not supported"):
        zmx.loads(text, "t.zmx")


def test_zmx_and_json_round_trips_keep_it():
    lens = _load("tele_triplet_floa")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = zmx.loads(zmx.dumps(lens)[0], "again.zmx")
    back = lensfile.lens_from_dict(json.loads(lensfile.dumps(lens)))
    for other in (again, back):
        assert other.telecentric_object
        np.testing.assert_allclose(float(other.object_na), float(lens.object_na), rtol=1e-15)
        np.testing.assert_array_equal(np.asarray(other.fields), np.asarray(lens.fields))


def test_json_refuses_mixed_telecentric_data():
    d = json.loads(lensfile.dumps(_load("tele_doublet_obna")))
    d["fields"]["type"] = "angle_deg_y"
    with pytest.raises(ValueError, match="object heights"):
        lensfile.lens_from_dict(d)
    d = json.loads(lensfile.dumps(_load("tele_doublet_obna")))
    d["aperture"] = {"epd": 5.0}
    with pytest.raises(ValueError, match="takes one aperture"):
        lensfile.lens_from_dict(d)


def test_json_height_type_against_pairs_names_heights():
    """The mismatch message of an object-height field type speaks of heights in mm and names
    the pairs' height type (it said "one value y" and suggested "angle_deg_xy")."""
    d = json.loads(lensfile.dumps(_load("tele_doublet_obna")))
    d["fields"]["values"] = [[0.0, 1.0], [0.0, 2.0]]
    with pytest.raises(ValueError, match=r"'object_height_mm_y' declares one object height y "
                       r"\(mm\) per field, but fields\.values holds pairs .*"
                       r"type \"object_height_mm_xy\" for pairs"):
        lensfile.lens_from_dict(d)
