"""With ``depth=None`` (the default) every analysis and imaging function traces from the
lens's own object.

``rms_spot`` did so, while ``spot_rays``, ``chief_ray``, ``ray_fan`` and ``field_curvature``
(documented as "default the lens's object") traced an object at infinity for a lens with a
finite object distance: ray fans off by 0.5 mm, foci by 5 mm on the Cooke triplet below.
``psf``, ``mtf``, ``render``, ``distortion_map`` and ``relative_illumination`` defaulted to
``depth=inf`` whatever the lens's object.
"""

import equinox as eqx
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import aberrations as ab
from jaxlens.analysis import spots
from jaxlens.imaging.radiometry import relative_illumination

DEPTH = 500.0  # mm, object to surface 1
FAR = 1e9  # mm


@pytest.fixture(scope="module")
def lenses():
    far = jl.zoo.cooke_triplet()
    near = eqx.tree_at(lambda lens: lens.object_distance, far, DEPTH,
                       is_leaf=lambda x: x is None)
    assert not near.object_at_infinity
    return far, near


@pytest.mark.parametrize("analysis", [
    lambda lens, **kw: ab.ray_fan(lens, 14.0, **kw).tangential,
    lambda lens, **kw: ab.field_curvature(lens, **kw).tangential,
    lambda lens, **kw: spots.spot_rays(lens, 14.0, **kw).origin,
    lambda lens, **kw: spots.rms_spot(lens, **kw).per_wavelength,
    lambda lens, **kw: jl.psf(lens, 14.0, pixel_size=0.002, kernel_size=15,
                              max_truncation=None, **kw),
    pytest.param(lambda lens, **kw: relative_illumination(lens, [0.0, 20.0], pupil=16, **kw).ri,
                 marks=pytest.mark.slow),  # 12 s
], ids=["ray_fan", "field_curvature", "spot_rays", "rms_spot", "psf", "relative_illumination"])
def test_default_depth_is_the_lens_object(lenses, analysis):
    _, near = lenses
    default = np.asarray(analysis(near))
    explicit = np.asarray(analysis(near, depth=DEPTH))
    # An object 1000 km away (infinity to 3e-6 mm of focus on this 50 mm lens): the same
    # compiled programs as the two calls above, where the object at infinity of ``far``
    # compiled each analysis a second time (psf: 11 s).
    distant = np.asarray(analysis(near, depth=FAR))
    np.testing.assert_array_equal(default, explicit)
    # The object distance matters here, so the check above can fail.
    assert np.nanmax(np.abs(default - distant)) > 1e-5


def test_explicit_infinity_still_means_infinity(lenses):
    far, near = lenses
    np.testing.assert_array_equal(np.asarray(ab.ray_fan(near, 14.0, depth=np.inf).tangential),
                                  np.asarray(ab.ray_fan(far, 14.0).tangential))


@pytest.mark.parametrize("call", [
    lambda lens: ab.ray_fan(lens, 5.0, depth=-5.0),
    lambda lens: ab.field_curvature(lens, depth=float("nan")),
], ids=["ray_fan", "field_curvature"])
def test_bad_depth_names_the_analysis(lenses, call):
    with pytest.raises(ValueError, match=r"^(ray_fan|field_curvature): depth must be"):
        call(lenses[0])
