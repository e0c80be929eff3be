"""``optics.symmetry.rotationally_symmetric`` and the shortcut it allows: a real image height
of 0 mm (FTYP 3) on a rotationally symmetric lens is field 0, with no Newton solve (whose
compile was 9 of the 10 s that rayoptics_ASL5040-UV.zmx took to open)."""

from __future__ import annotations

import dataclasses
import os

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import zoo
from jaxlens.io import zmx_system
from jaxlens.optics.symmetry import rotationally_symmetric
from jaxlens.optics.toroidal import Toroidal

ASL = os.path.join(os.path.dirname(__file__), "data", "zmx", "rayoptics_ASL5040-UV.zmx")


def _singlet(**kw) -> jl.Lens:
    surfaces = kw.pop("surfaces", (jl.Sphere(1 / 40.0, 8.0), jl.Sphere(-1 / 40.0, 8.0)))
    return jl.Lens(surfaces=surfaces, thickness=jnp.array([4.0, 38.0]),
                   materials=(jl.ModelGlass(1.5168, 64.17), jl.Air()), stop=0, epd=8.0,
                   fields=jnp.array([0.0]), wavelengths=jnp.array([0.5875618]), **kw)


def test_round_lenses_are_symmetric():
    for lens in (zoo.cooke_triplet(), zoo.double_gauss(), zoo.cellphone6(), _singlet()):
        assert rotationally_symmetric(lens), lens.name
    hybrid = jl.Hybrid(c=0.02, k=0.0, coeffs=jnp.zeros(2), odd_x=jnp.zeros(2),
                       odd_y=jnp.zeros(2), semi_diameter=8.0)
    assert rotationally_symmetric(_singlet(surfaces=(hybrid, jl.Sphere(-1 / 40.0, 8.0))))
    centred = _singlet(apertures=((1, jl.Aperture.circle(7.0)),))
    assert rotationally_symmetric(centred)


@pytest.mark.parametrize("what", ["cubic", "toroid", "decentered", "ellipse", "break"])
def test_what_breaks_the_symmetry_is_seen(what):
    back = jl.Sphere(-1 / 40.0, 8.0)
    if what == "cubic":  # the paper's odd terms: a cubic phase plate is not round
        lens = _singlet(surfaces=(jl.Hybrid(c=0.02, k=0.0, coeffs=jnp.zeros(2),
                                            odd_x=jnp.array([1e-4, 0.0]),
                                            odd_y=jnp.array([1e-4, 0.0]), semi_diameter=8.0),
                                  back))
    elif what == "toroid":  # the kind is read, not the numbers
        lens = _singlet(surfaces=(Toroidal(c=0.025, k=0.0, coeffs=jnp.zeros(1), cx=0.025,
                                           semi_diameter=8.0), back))
    elif what == "decentered":
        lens = _singlet(apertures=((1, jl.Aperture.circle(7.0, decenter_y=0.5)),))
    elif what == "ellipse":
        circle = jl.Aperture.circle(7.0)
        lens = _singlet(apertures=((1, dataclasses.replace(circle, shape="ellipse",
                                                            half_y=6.0)),))
    else:
        lens = jl.Lens(
            surfaces=(jl.Sphere(1 / 40.0, 8.0), jl.CoordinateBreak(decenter_y=0.1),
                      jl.Sphere(-1 / 40.0, 8.0)),
            thickness=jnp.array([4.0, 0.0, 38.0]),
            materials=(jl.ModelGlass(1.5168, 64.17),) * 2 + (jl.Air(),), stop=0, epd=8.0)
    assert not rotationally_symmetric(lens)


def _no_solve(*args, **kwargs):
    raise AssertionError("the Newton solve ran")


def test_a_zero_height_on_a_round_lens_is_field_0_without_a_solve(monkeypatch):
    """Before: the Newton solve (aiming at the stop inside it) ran for 0 mm too."""
    lens = _singlet()
    with monkeypatch.context() as m:
        m.setattr(zmx_system, "_real_height_field", _no_solve)
        out = zmx_system.angles_from_real_image_heights(lens, np.array([0.0]))
        assert np.asarray(out.fields).tolist() == [0.0]
        xy = zmx_system.angles_from_real_image_heights(lens, np.zeros((1, 2)))
        assert np.asarray(xy.fields).tolist() == [[0.0, 0.0]]
    # The solve finds the same field (to its rounding), and a nonzero height still solves.
    solved = zmx_system._real_height_field(lens, jnp.zeros(2), jnp.asarray(1.0))[0]
    assert np.max(np.abs(np.asarray(solved))) < 1e-12
    both = zmx_system.angles_from_real_image_heights(lens, np.array([0.0, 2.0]))
    assert np.asarray(both.fields)[0] == 0.0 and 0.0 < np.asarray(both.fields)[1] < 10.0


def test_a_lens_that_is_not_round_still_solves_its_zero_height(monkeypatch):
    lens = _singlet(apertures=((1, jl.Aperture.circle(7.0, decenter_y=0.5)),))
    monkeypatch.setattr(zmx_system, "_real_height_field", _no_solve)
    with pytest.raises(AssertionError, match="the Newton solve ran"):
        zmx_system.angles_from_real_image_heights(lens, np.array([0.0]))


def test_a_finite_object_takes_the_axial_ray_from_the_object_point(monkeypatch):
    lens = _singlet(object_distance=500.0)
    monkeypatch.setattr(zmx_system, "_real_height_field", _no_solve)
    out = zmx_system.angles_from_real_image_heights(lens, np.array([0.0]))
    assert np.asarray(out.fields).tolist() == [0.0]


def test_an_axis_that_is_blocked_is_still_refused():
    """A central obscuration stops the axial chief ray: the check after the shortcut refuses
    the field as it refused the solved one."""
    lens = _singlet(obscurations=((1, 0.0, 2.0),))
    with pytest.raises(ValueError, match=r"no real chief ray reaches the image height"):
        zmx_system.angles_from_real_image_heights(lens, np.array([0.0]))


def test_the_thorlabs_asphere_opens_with_its_field_at_0(monkeypatch):
    monkeypatch.setattr(zmx_system, "_real_height_field", _no_solve)
    lens = jl.load(ASL)
    assert np.asarray(lens.fields).tolist() == [0.0]
    assert rotationally_symmetric(lens)
