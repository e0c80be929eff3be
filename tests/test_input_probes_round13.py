"""Round 13 of bad-input and silent-answer probes: multi-configuration ``.zmx`` files and
Zemax vignetting factors (``Lens.vignetting``). Each test pins one finding; each failed
before its fix."""

import dataclasses
import os

import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens import zoo
from jaxlens.imaging import psf, sampling
from jaxlens.io import zmx_read
from jaxlens.tracing.forward import trace

ZOOM = os.path.join(os.path.dirname(__file__), "data", "zmx_config", "zoom.zmx")
ROWS = np.array([[0.0, 0.0, 0.0, 0.0, 0.0],
                 [0.0, 0.1, 0.2, 0.3, 0.0],
                 [0.0, 0.2, 0.3, 0.4, 10.0]])


def _zoom() -> str:
    with open(ZOOM) as fh:
        return fh.read()


# --------------------------------------------------------------------------- vignetting


def test_float32_lens_gets_the_factors_of_its_fields_given_as_python_floats():
    """A float32 lens's field 19.7 is float32(19.7), 7.6e-7 deg from the float64 19.7 a
    caller passes: the 1e-9 deg match found no field and the factors were silently zero
    (the whole pupil traced instead of the vignetted one)."""
    lens = dataclasses.replace(zoo.cooke_triplet(clip=False), fields=jnp.array([0.0, 14.1, 19.7]),
                               vignetting=ROWS).astype(jnp.float32)
    for field, row in ((14.1, 1), (19.7, 2), ((0.0, 19.7), 2), ([14.1], 1)):
        np.testing.assert_allclose(sampling.field_vignetting(lens, field), ROWS[row], atol=1e-7)
    # a field that is none of the lens's still gets none
    np.testing.assert_array_equal(sampling.field_vignetting(lens, 19.69), np.zeros(5))
    # and the rays follow: the launched y of pupil point (0, 1) is VDY + (1 - VCY) = 0.8
    rays = sampling.field_rays(lens, 14.1, jnp.array([[0.0, 1.0]], jnp.float32))
    h = 0.5 * float(lens.epd)
    assert abs(float(rays.origin[0, 1]) - 0.8 * h) < 1e-4 * h


@pytest.mark.parametrize("bad", [[np.nan, 20.0], [95.0, 20.0]])
def test_vignetting_for_fields_refuses_bad_fields_by_name(bad):
    """A NaN or 95 deg field failed inside vmap with an EquinoxRuntimeError and a JIT stack."""
    lens = dataclasses.replace(zoo.cooke_triplet(clip=False), vignetting=ROWS)
    with pytest.raises(ValueError, match=r"vignetting_for_fields: fields must be finite angles "
                                         r"in \(-90, 90\) deg"):
        sampling.vignetting_for_fields(lens, np.array(bad))


def test_overfilled_pupil_points_of_a_vignetted_field_launch_invalid_rays():
    """The vignetted pupil is the image of the unit disc. A PSF's overfilled beam (1.25)
    mapped by VCY = 0.5 fell inside the stop, so rays OpticStudio never traces passed: a
    ``normalize="pupil"`` PSF held 1.44 of the pupil's energy."""
    plain = zoo.cooke_triplet(clip=True)
    rows = np.zeros((3, 5))
    rows[2, 3] = 0.5  # VCY 0.5 at 20 deg
    lens = dataclasses.replace(plain, vignetting=rows)
    pts = jnp.array([[0.0, 0.9], [0.0, 1.2], [0.0, -1.2], [1.0, 0.0]])
    np.testing.assert_array_equal(trace(lens, sampling.field_rays(lens, 20.0, pts)).valid,
                                  [True, False, False, True])
    # a field without factors: the overfilled points are the stop's to clip, as before
    np.testing.assert_array_equal(sampling.field_rays(lens, 14.0, pts).valid, [True] * 4)


@pytest.mark.slow
def test_pupil_normalised_psf_of_a_vignetted_field_holds_at_most_the_pupil_energy():
    """The same finding seen in the PSF (about 10 s)."""
    rows = np.zeros((3, 5))
    rows[2, 3] = 0.5
    lens = dataclasses.replace(zoo.cooke_triplet(clip=True), vignetting=rows)
    model = psf.GeometricPSF(pupil=24, overfill=1.25, normalize="pupil")  # the ring beyond 1
    k = psf.psf(lens, 20.0, kernel_size=65, pixel_size=0.01, model=model, max_truncation=1.0)
    assert float(jnp.sum(k)) <= 1.0 + 1e-9


# --------------------------------------------------------------------------- configurations


def test_numpy_integer_config_is_a_configuration_number():
    """np.int64(2) (from np.arange, a loop over configurations) was refused as 'not a whole
    configuration number'; bools stay refused."""
    a = zmx_read.loads(_zoom(), config=np.int64(2))
    b = zmx_read.loads(_zoom(), config=2)
    np.testing.assert_array_equal(a.thickness, b.thickness)
    with pytest.raises(ValueError, match="config must be a whole configuration number"):
        zmx_read.loads(_zoom(), config=np.bool_(True))


def test_a_configuration_given_two_values_is_refused_naming_both_lines():
    """Two THIC 4 rows for configuration 3: the later one silently won."""
    text = _zoom().replace("THIC 4 3 50 0 0 0 1 1 1 0 0\n",
                           "THIC 4 3 50 0 0 0 1 1 1 0 0\nTHIC 4 3 60 0 0 0 1 1 1 0 0\n")
    with pytest.raises(ValueError, match=r":61: a second THIC 4 line for configuration 3 "
                                         r"\(the first is line 60\)"):
        zmx_read.loads(text, config=3)


def test_active_configuration_vignetting_rows_checked_against_the_file_lines():
    """The active configuration's FVCY says 0.5 where the file's VCYN says 0.2: the THIC,
    CRVT and CONN rows were checked against the surfaces, the factor rows not at all, so the
    active number's mismatch passed silently (strict too)."""
    text = _zoom().replace("PWAV 1", "PWAV 1\nVCYN 0.1 0.2").replace(
        "MOFF 0 1", "FVCY 2 1 0.5\nFVCY 2 2 0.2\nFVCY 2 3 0.6\nMOFF 0 1", 1)
    with pytest.raises(ValueError, match=r"FVCY 2 of configuration 1, the active one \(MNUM\), "
                                         r"is 0\.5, but the file's VCYN gives field 2 0\.2"):
        zmx_read.loads(text, strict=True)
    with pytest.warns(UserWarning, match="FVCY 2 of configuration 1"):
        lens = zmx_read.loads(text)
    np.testing.assert_allclose(lens.vignetting[:, 3], [0.1, 0.2])  # the file's VCYN
    # consistent rows read without a word, and another configuration takes its own
    ok = text.replace("FVCY 2 1 0.5", "FVCY 2 1 0.2")
    assert zmx_read.loads(ok, strict=True).vignetting is not None
    np.testing.assert_allclose(zmx_read.loads(ok, config=3).vignetting[:, 3], [0.1, 0.6])


def test_mnum_1_with_rows_for_other_configurations_is_reported():
    """MNUM 1 above rows for configurations 2 and 3 (a count cut short) was read without a
    word, while ``configurations()`` refused the same file."""
    text = _zoom().replace("MNUM 3 1", "MNUM 1")
    with pytest.raises(ValueError, match=r":39: a file of 1 configuration \(MNUM\) whose "
                                         r"operand table .*configuration number must be 1\.\.1"):
        zmx_read.loads(text, strict=True)
    with pytest.warns(UserWarning, match="a file of 1 configuration"):
        lens = zmx_read.loads(text)
    np.testing.assert_array_equal(lens.thickness, [5.0, 20.0, 2.0, 40.0])  # the surfaces
    # MNUM 1 with its own rows only reads silently, strict too
    rows = ("APER", "YFIE", "WAVE", "THIC", "GLSS", "CRVT", "MOFF")
    ok = "\n".join(ln for ln in text.splitlines()
                   if not (ln[:4] in rows and ln.split()[2] != "1"))
    zmx_read.loads(ok, strict=True)
