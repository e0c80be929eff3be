"""``Lens.travel_senses``: a fold whose coordinate breaks turn the frame round with the light.

The fold of tests/test_zmx_round9.py written as Quadoa exports a prism (a −45° break, the
mirror with its thickness along its own axis, a +135° break with a decenter, positive
thicknesses after it): light travels toward +z after one mirror, against Zemax's rule. The
senses are static data set where a lens is built from concrete values (the readers) and
checked by ``Lens`` against the frames, so a lens built without them is refused rather than
given paraxial data of the wrong sign, and a lens that follows the mirror count carries None.
"""

import dataclasses
import json
import math

import equinox as eqx
import jax
import numpy as np
import pytest
from test_zmx_round9 import _fold, _unfolded

import jaxlens as jl
from jaxlens.io import lensfile, zmx
from jaxlens.optics import travel


@pytest.fixture(scope="module")
def quadoa():
    return zmx.loads(_fold(quadoa=True), strict=True)


def test_the_reader_sets_the_senses_only_where_frames_turn_with_the_light(quadoa):
    # Object space, then after the stop, the −45° break, the mirror (its −10 mm along its own
    # axis), the +135° break and the two lens faces.
    assert quadoa.travel_senses == (1, 1, 1, -1, 1, 1, 1)
    assert travel.mirror_count_senses(quadoa.num_surfaces, quadoa.mirrors) == (
        1, 1, 1, -1, -1, -1, -1)
    zemax = zmx.loads(_fold(quadoa=False), strict=True)
    assert zemax.travel_senses is None
    assert travel.travel_senses(zemax) == (1, 1, 1, -1, -1, -1, -1)
    np.testing.assert_array_equal(travel.axial_thicknesses(zemax), zemax.thickness)
    # The Quadoa form's paraxial path: 10 mm from the stop to the mirror, 10·√2 mm along the
    # light from the mirror's vertex to the lens's frame (its −10 mm along the mirror's own
    # axis and the −10 mm decenter), then the lens's 4 and 50 mm.
    # Each gap is signed as its medium's sense (the mirror's gap −7.07 mm, toward −z).
    axial = np.asarray(travel.axial_thicknesses(quadoa))
    path = axial * np.asarray(quadoa.travel_senses[1:])
    assert path.sum() == pytest.approx(10 + 10 * math.sqrt(2) + 4 + 50, rel=1e-12)
    assert (path >= -1e-12).all()


def test_a_lens_built_without_its_senses_is_refused_with_the_value_it_needs(quadoa):
    with pytest.raises(ValueError, match=r"travel_senses must be \(1, 1, 1, -1, 1, 1, 1\) "
                                         r"for these mirrors and coordinate breaks.*got None"):
        dataclasses.replace(quadoa, travel_senses=None)
    plain = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match="travel_senses must be None"):
        dataclasses.replace(plain, travel_senses=(1,) * (plain.num_surfaces + 1))
    with pytest.raises(ValueError, match="needs 7 entries"):
        dataclasses.replace(quadoa, travel_senses=(1, 1))
    with pytest.raises(TypeError, match=r"tuple of \+1 and -1"):
        dataclasses.replace(quadoa, travel_senses=(1, 0, 1, 1, 1, 1, 1))


def test_the_senses_survive_json_zmx_tree_at_and_jit(quadoa):
    efl = float(jl.paraxial_data(quadoa).efl)
    again = lensfile.lens_from_dict(json.loads(lensfile.dumps(quadoa)))
    assert again.travel_senses == quadoa.travel_senses
    assert float(jl.paraxial_data(again).efl) == pytest.approx(efl, rel=1e-12)
    reread = zmx.loads(zmx.dumps(quadoa)[0])
    assert reread.travel_senses == quadoa.travel_senses
    assert float(jl.paraxial_data(reread).efl) == pytest.approx(efl, rel=1e-12)
    moved = eqx.tree_at(lambda x: x.thickness, quadoa, quadoa.thickness * 1.0)
    assert moved.travel_senses == quadoa.travel_senses
    jitted = jax.jit(lambda x: jl.paraxial_data(x).efl)(quadoa)
    assert float(jitted) == pytest.approx(efl, rel=1e-12)


def test_the_tracer_gaps_follow_the_senses(quadoa):
    # A marginal ray of the Quadoa form meets the image plane where the unfolded lens's
    # does (up to the fold's mirror image in y), so its gaps after the mirror go forward.
    flat = _unfolded(10 + 10 * math.sqrt(2))
    grid = np.array([[0.0, 0.9], [0.6, -0.3]])
    hits = [np.asarray(jl.trace(x, jl.sampling.field_rays(x, np.array([0.0, 1.0]), grid,
                                                          0.55)).origin) for x in (quadoa, flat)]
    np.testing.assert_allclose(np.abs(hits[0][:, :2]), np.abs(hits[1][:, :2]), atol=1e-9)


def test_an_obscuration_on_a_coordinate_break_is_refused(quadoa):
    # The tracer gives a break no aperture: a 1e9 mm obscuration there let every ray through.
    with pytest.raises(ValueError, match="surface 1 is a coordinate break; it has no aperture"):
        dataclasses.replace(quadoa, obscurations=((1, 0.0, 1e9),))
    text = _fold(quadoa=False).replace("SURF 2\n  TYPE COORDBRK\n",
                                       "SURF 2\n  TYPE COORDBRK\n  OBSC 0 3\n")
    assert "OBSC" in text
    with pytest.raises(ValueError, match=r"<zmx>:\d+: a coordinate break has no aperture"):
        zmx.loads(text)


def test_the_travel_helpers_refuse_what_is_not_a_lens_or_its_mirrors():
    with pytest.raises(ValueError, match="number of surfaces must be a whole number >= 1"):
        travel.mirror_count_senses(-1, ())
    with pytest.raises(ValueError, match=r"mirrors must be surface indices in \[0, 2\]"):
        travel.mirror_count_senses(3, (7,))
    with pytest.raises(TypeError, match="surfaces must be a sequence"):
        travel.frame_senses(None, ())
    with pytest.raises(TypeError, match="expected a Lens, got dict"):
        travel.axial_thicknesses({})


def test_the_axial_path_gradient_matches_finite_differences(quadoa):
    # The exit pupil's place depends on the stop-to-lens path, which runs through the mirror's
    # gap along its own axis; the derivative through axial_thicknesses against central
    # differences, per thickness.
    def exit_pupil(t):
        return jl.paraxial_data(eqx.tree_at(lambda x: x.thickness, quadoa, t)).exit_pupil_z

    t0 = quadoa.thickness
    grad = np.asarray(jax.grad(exit_pupil)(t0))
    h = 1e-5
    for i in range(t0.shape[0]):
        step = np.zeros(t0.shape[0])
        step[i] = h
        fd = (float(exit_pupil(t0 + step)) - float(exit_pupil(t0 - step))) / (2 * h)
        assert grad[i] == pytest.approx(fd, rel=1e-6, abs=1e-8), i
    assert abs(grad[2]) > 1e-3  # the mirror's gap moves the exit pupil
