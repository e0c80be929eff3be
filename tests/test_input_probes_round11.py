"""Bad-input probes, round 11: each case failed (or answered wrongly) before its fix."""

import math

import pytest

import jaxlens as jl
from jaxlens.imaging.psf import CoherentPSF, GeometricPSF


@pytest.mark.parametrize("model", [GeometricPSF, CoherentPSF])
def test_overfill_that_leaves_no_ray_in_the_pupil_is_refused(model):
    """An overfill of 1e6 put no ray of the 64² grid in the entrance pupil, and the error
    blamed the lens ("the field is vignetted or beyond the lens's coverage")."""
    lens = jl.zoo.cooke_triplet()
    # GeometricPSF/CoherentPSF: refused at construction since round 17
    with pytest.raises(ValueError, match=r"(psf|GeometricPSF|CoherentPSF): overfill 1000000.0 "
                                         r".* none may fall inside "
                                         r"the entrance pupil; use an overfill in "
                                         r"\(0, 45.25\]"):
        jl.psf(lens, 0.0, pixel_size=0.01, model=model(overfill=1e6))
    with pytest.raises(ValueError, match=r"overfill in \(0, 2.828\]"):
        jl.psf(lens, 0.0, pixel_size=0.01, model=model(pupil=4, overfill=3.0))
    if model is GeometricPSF:
        with pytest.raises(ValueError, match=r"overfill in \(0, 8\]"):
            jl.psf(lens, 0.0, pixel_size=0.01, model=model(grid="polar", overfill=9.0))


@pytest.mark.parametrize(("pupil", "grid"), [(2, "square"), (5, "polar"), (8, "square")])
def test_largest_allowed_overfill_still_gives_a_psf(pupil, grid):
    lens = jl.zoo.cooke_triplet()
    largest = math.sqrt(pupil) if grid == "polar" else pupil / math.sqrt(2)
    model = GeometricPSF(pupil=pupil, overfill=0.999 * largest, grid=grid)
    assert model.largest_overfill() == largest
    k = jl.psf(lens, 0.0, pixel_size=0.05, max_truncation=None, model=model)
    assert float(k.sum()) > 0
