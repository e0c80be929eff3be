"""Image-height field types (FTYP 2, 3) with an afocal image space (FTYP's seventh value 1):
zero heights read as on axis (0°, the same field whatever the field type), a nonzero height
is refused (an image at infinity has no heights), with the FTYP line named."""

from __future__ import annotations

import pathlib
import warnings

import numpy as np
import pytest

import jaxlens as jl

KEPLER = pathlib.Path(__file__).parent / "data" / "afocal_kepler.zmx"
ZEROS = "YFLN 0 0 0 0 0 0 0 0 0 0 0 0"


def _variant(tmp_path, kind, yfln):
    text = KEPLER.read_text()
    text = text.replace("FTYP 0 0 3 3 0 0 1", f"FTYP {kind} 0 3 3 0 0 1")
    text = text.replace("YFLN 0 0.5 1.0 0 0 0 0 0 0 0 0 0", yfln)
    path = tmp_path / f"k{kind}.zmx"
    path.write_text(text)
    return path


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the file's ENVD note, not the subject here
        return jl.load(path)


@pytest.mark.parametrize("kind", [2, 3])
def test_zero_image_heights_read_as_on_axis_in_afocal_mode(tmp_path, kind):
    lens = _load(_variant(tmp_path, kind, ZEROS))
    angles = _load(_variant(tmp_path, 0, ZEROS))  # the same file given in angles
    assert lens.afocal_image
    assert np.asarray(lens.fields).shape == np.asarray(angles.fields).shape == (3,)
    assert not np.any(np.asarray(lens.fields))
    np.testing.assert_array_equal(np.asarray(lens.fields), np.asarray(angles.fields))
    assert float(jl.paraxial_data(lens).efl) == float(jl.paraxial_data(angles).efl)


@pytest.mark.parametrize("kind", [2, 3])
def test_a_nonzero_image_height_in_afocal_mode_is_refused_naming_the_line(tmp_path, kind):
    path = _variant(tmp_path, kind, "YFLN 0 0.5 0 0 0 0 0 0 0 0 0 0")
    with pytest.raises(ValueError, match=rf"field type {kind} \(.*image heights\) with an "
                                         r"afocal image space .*has no heights.*0\.5 mm") as e:
        _load(path)
    assert f"'FTYP {kind} 0 3 3 0 0 1'" in str(e.value)
