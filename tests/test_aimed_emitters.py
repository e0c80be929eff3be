"""Aimed analyses of folded lenses compile with XLA:CPU's loop emitters (``forward.aimed_jit``).

The aiming's Newton steps take forward-mode derivatives of the trace to the stop; with the
fusion emitters those ran in time that grows steeply with the unscanned surfaces (the folded
Ex66 file: 709 aimed rays of one field 0.84 s against 0.3 ms for the trace itself, and one of
this repository's slow tests 40 minutes at -O0; benchmarks/SPEED.md). These tests pin the
rule and that the aimed programs use it; the values are checked by the aiming and report tests.
"""

from __future__ import annotations

import pathlib

import jax
import pytest

import jaxlens
from jaxlens.analysis import aberrations, spots, wavefront_error
from jaxlens.imaging import aiming, psf
from jaxlens.tracing.forward import loop_emitters_wanted

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def folded():
    lens = jaxlens.load(ROOT / "tests" / "data" / "zmx" / "rayoptics_HoO-V2C18Ex66.zmx")
    assert lens.aim == "real_marginal"  # the file's RAIM
    return lens


def test_the_rule_takes_aimed_calls_of_folded_lenses_at_the_top_level(folded):
    cooke = jaxlens.load(ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json")
    cpu = jax.default_backend() == "cpu"
    assert loop_emitters_wanted(folded, aimed_only=True) == cpu
    assert loop_emitters_wanted(folded, kwargs={"aim": "real"}, aimed_only=True) == cpu
    assert not loop_emitters_wanted(folded, kwargs={"aim": "paraxial"}, aimed_only=True)
    assert loop_emitters_wanted(folded, kwargs={"aim": "paraxial"}) == cpu  # forward_mode_jit
    assert not loop_emitters_wanted(cooke, kwargs={"aim": "real"}, aimed_only=True)
    seen = []

    @jax.jit
    def inside(c):  # a traced argument: the outer program's options hold
        seen.append(loop_emitters_wanted(folded, (c,), aimed_only=True))
        return c

    inside(1.0)
    assert seen == [False]


def test_the_aimed_programs_follow_the_rule():
    aimed = (spots._spot_rays, spots._rms_spot, spots._distortion,
             spots._clear_semi_diameters, spots._semi_diameters_and_fans,
             aberrations._ray_fan, wavefront_error._opd_impl, wavefront_error._wavefront_impl,
             wavefront_error._opd_fan_impl)
    assert [getattr(f, "loop_emitters", None) for f in aimed] == ["aimed"] * len(aimed)
    # They aim whatever Lens.aim is (the PSF and MTF at the real chief ray).
    always = (aiming._stop_chief_ray, aiming._chief_point, psf._psf_impl, psf._mtf_impl)
    assert [getattr(f, "loop_emitters", None) for f in always] == ["unscanned"] * len(always)
