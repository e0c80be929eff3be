"""A lens with x and oblique (θx, θy) fields, saved as ``.zmx`` and re-read: jaxlens's report
against optiland 0.6.3's numbers of the same file.

tests/data/export_fields.zmx is the Cooke triplet of ``jaxlens.zoo`` with six fields (on axis,
pure x, pure −y, three oblique) written by ``jaxlens.save``; tests/data/export_fields_optiland.json
holds optiland's numbers of that file (tools/export_fields_reference.py, with
tools/export_reevaluation.py's definitions): with every medium set to jaxlens's indices
(``jaxlens_media``: only geometry, aperture, fields and tracing are optiland's) and with
optiland's own glass data (``glass``).
"""

import json
import math
import pathlib
import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis.report import report_data

pytestmark = pytest.mark.slow  # jl.load of the file 6 s, the report's trace 20 s

DATA = pathlib.Path(__file__).parent / "data"
REF = json.loads((DATA / "export_fields_optiland.json").read_text())


@pytest.fixture(scope="module")
def lens():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return jl.load(str(DATA / REF["file"]))


def test_fields_read_back_as_written_and_as_optiland_reads_them(lens):
    """XFLN/YFLN come back as the (θx, θy) pairs written (exactly); optiland reads the same
    set (it reorders them); its FoV (2 × the largest angle from the axis) is the report's,
    2 atan √(tan² 12° + tan² 16°) = 39.29°, not twice optiland's normalising field
    √(θx² + θy²) = 20°."""
    got = np.asarray(lens.fields, float)
    np.testing.assert_array_equal(got, np.asarray(REF["fields"]))
    angle = 2 * math.degrees(math.atan(math.hypot(math.tan(math.radians(12.0)),
                                                  math.tan(math.radians(16.0)))))
    for k in ("glass", "jaxlens_media"):
        assert sorted(map(tuple, REF[k]["file_fields"])) == sorted(map(tuple, got.tolist()))
        assert REF[k]["fov"] == pytest.approx(angle, abs=1e-12)
        assert REF[k]["max_field"] == pytest.approx(20.0, abs=1e-12)


def test_report_numbers_equal_optilands_at_x_and_oblique_fields(lens):
    """Per field: chief ray (x, y) and its height along the field's azimuth within 1e-10 mm
    (measured 8.9e-15), f-tanθ distortion within 1e-8 percentage points (measured 5.7e-14),
    RMS spot per wavelength and pooled within 1e-8 µm (measured 1.4e-12, 8.5e-13); EFL, F/#,
    BFL relative 1e-12 (measured 1.8e-16): optiland with jaxlens's media. With optiland's own
    glass data (its SK16, F2) the EFL differs by 5.7e-7 relative and the RMS by up to 0.11 µm."""
    d = report_data(lens)
    o = REF["jaxlens_media"]
    f = d["fields"]
    assert d["fov"] == pytest.approx(o["fov"], abs=1e-12)
    for k, ok in (("efl_image_space", "efl"), ("fnum", "fnum"), ("bfl", "bfl")):
        assert d[k] == pytest.approx(o[ok], rel=1e-12)
    assert d["total_track"] == pytest.approx(o["total_track"], abs=1e-12)
    np.testing.assert_allclose([x["chief_ray_xy"] for x in f], o["chief_xy"], rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose([x["chief_ray_height"] for x in f], o["chief_y"], rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose([x["distortion"] for x in f], o["distortion"], rtol=0,
                               atol=1e-8)
    np.testing.assert_allclose([x["rms_spot"] for x in f], o["rms_um"], rtol=0, atol=1e-8)
    np.testing.assert_allclose([x["rms_spot_polychromatic"] for x in f], o["rms_poly_um"],
                               rtol=0, atol=1e-8)
    assert o["rays_lost"] == 0 and all(min(x["valid_fraction"]) == 1.0 for x in f)
    # The oblique fields are not y fields in disguise: x and y both move.
    assert min(abs(c[0]) for c in o["chief_xy"][3:]) > 1.0
    assert d["efl_image_space"] == pytest.approx(REF["glass"]["efl"], rel=1e-5)
