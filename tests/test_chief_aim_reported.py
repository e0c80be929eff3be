"""``aiming.stop_chief_ray`` reports an aim that did not converge (its ray's ``valid``), and
``aiming.chief_point(..., with_valid=True)`` passes that on, where before an unconverged aim
was returned as a valid chief ray.

Laikin's wide-angle lens at 50° (its real entrance pupil lies 1.55 EPD above the paraxial
one, tests/test_newton_aiming.py): one aiming step from the paraxial pupil's centre leaves the
ray lost, three leave it 1.8e-4 mm from the stop centre (it was returned as valid), the
default iterations bring it there (to 1e-11 mm). The lens traces as its file says, with
``negative_propagation`` (Zemax's rule, set by the reader since 2026-11-30): there four
steps already converge; under the default rule they left it 4.7e-5 mm off.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import aiming, sampling
from jaxlens.io.zmx import ZmxWarning
from jaxlens.optics.lens import unclipped
from jaxlens.tracing.forward import trace, trace_path

LAIKIN = (Path(__file__).resolve().parent / "data" / "zmx"
          / "optiland_circular_aperture_example_with_aperture.zmx")


@pytest.fixture(scope="module")
def laikin():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ZmxWarning)
        return dataclasses.replace(jl.load(LAIKIN), aim="paraxial")


def _miss(lens, rays):
    """How far (mm) the ray crosses the stop from its centre (traced as valid)."""
    rays = dataclasses.replace(rays, valid=jnp.ones_like(rays.valid))
    at = trace_path(unclipped(lens), rays, upto=lens.stop, uniform=True)[-1]
    return float(jnp.max(jnp.abs(at.origin[0, :2]))), bool(at.valid[0])


@pytest.mark.slow  # about 20 s: the aiming of a wide-angle lens, op by op, four times
def test_an_aim_that_did_not_converge_is_reported(laikin):
    scale = max(float(jl.paraxial_data(laikin).stop_semi_diameter), 1.0)
    tol = sampling.AIM_TOLERANCE[True] * scale
    lost = aiming.stop_chief_ray(laikin, 50.0, iters=0)  # one step: the ray is lost
    assert not _miss(laikin, lost)[1] and not bool(lost.valid[0])
    assert laikin.negative_propagation  # the file's rule: the counts below are its
    short = aiming.stop_chief_ray(laikin, 50.0, iters=2)  # three: close, not there
    miss, passes = _miss(laikin, short)
    assert passes and miss > 4 * tol  # 1.8e-4 mm from the stop centre, tol 1.1e-5 mm
    assert not bool(short.valid[0])
    done = aiming.stop_chief_ray(laikin, 50.0)
    miss, _ = _miss(laikin, done)
    assert bool(done.valid[0]) and miss <= tol
    # chief_point: the point of the last aim, traced through, and the aim in its validity
    free = unclipped(laikin)
    aimed = dataclasses.replace(done, valid=jnp.ones_like(done.valid))
    want = trace(free, aimed, uniform=True).origin[0, :2]
    xy, ok = aiming.chief_point(laikin, 50.0, None, jl.tracing.forward.DEFAULT_NEWTON_ITERS,
                                with_valid=True)
    assert bool(ok)
    np.testing.assert_array_equal(np.asarray(xy), np.asarray(want))
