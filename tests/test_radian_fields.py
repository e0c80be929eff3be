"""Field angles given in radians (``np.radians([0, 10, 20])``) are traced as fractions of a
degree: ``Lens`` warns when every nonzero field is a whole number of degrees written in
radians (``checks.warn_if_radian_fields``); real field sets do not trip it."""

import glob
import os
import warnings

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics import checks


def _lens(fields):
    t = jl.zoo.cooke_triplet()
    return jl.Lens(surfaces=t.surfaces, thickness=t.thickness, materials=t.materials,
                   stop=t.stop, epd=t.epd, fields=fields, wavelengths=t.wavelengths)


@pytest.mark.parametrize("fields", [np.radians([0.0, 10.0, 20.0]), [0.0, 0.1745, 0.349],
                                    [[0.0, 0.0], [0.0873, 0.2618]], [0.7854]])
def test_fields_in_radians_are_warned_about(fields):
    with pytest.warns(UserWarning, match=r"look like angles in radians .* field angles are "
                                         r"in degrees"):
        _lens(fields)


@pytest.mark.parametrize("fields", [[0.0], [0.0, 14.0, 20.0], [0.0, 0.5, 0.7],
                                    [0.0, 0.01745, 0.0349], [0.0, 0.1745, 0.36],
                                    [0.0, 1.6, 3.0]])
def test_fields_in_degrees_are_not(fields):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _lens(fields)


def test_no_shipped_lens_has_radian_like_fields():
    """Every field set of the zoo and the shipped lens files passes (the real .zmx files of
    tests/data/zmx too: checked once by hand, 2026-11-30; their loads run in test_corpus)."""
    here = os.path.dirname(__file__)
    paths = glob.glob(os.path.join(here, "..", "jaxlens", "data", "lenses", "*.json"))
    fields = [np.asarray(getattr(jl.zoo, n)().fields) for n in ("cooke_triplet", "cellphone6")]
    fields += [np.asarray(jl.load(p).fields) for p in paths]
    assert len(fields) >= 5
    for f in fields:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            checks.warn_if_radian_fields(f, "test")
