"""Which .zmx lines vignette rays, as in Zemax OpticStudio: surface apertures (CLAP, FLAP,
OBSC, SQAP, ELAP, SQOB, ELOB) do; a semi-diameter (DIAM) alone does not.

Each lens here is a window or a singlet with the aperture on surface 1, the first surface,
so a ray parallel to the axis meets it at the height it starts at: which rays pass is
known by hand.
"""

from __future__ import annotations

import pathlib
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx

WL = 0.5875618


def _lens_text(surface1: str, *, curv: float = 0.02, head: str = "ENPD 20\n") -> str:
    """A singlet (model glass n = 1.5) with ``surface1``'s lines on its first surface, the
    stop; ``curv`` 0 makes surface 1 a plane (a surface without power)."""
    return (
        f"UNIT MM\n{head}WAVM 1 {WL} 1\nSURF 0\n  DISZ INFINITY\n"
        f"SURF 1\n  STOP\n  CURV {curv!r}\n  DISZ 5\n"
        f"  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n{surface1}"
        f"SURF 2\n  CURV -0.02\n  DISZ 40\nSURF 3\n"
    )


def _passes(lens, points):
    """Which rays parallel to the axis, starting at these (x, y) points (mm), reach the
    image (each meets surface 1 at its own (x, y))."""
    xy = jnp.asarray(points, dtype=float)  # [n 2]
    o = jnp.concatenate([xy, jnp.full_like(xy[:, :1], -1.0)], -1)  # [n 3]
    d = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), o.shape)
    return np.asarray(jl.trace(lens, jl.Rays(o, d, WL)).valid).tolist()


def _on_y(heights):
    return [(0.0, h) for h in heights]


HEIGHTS = [0.0, 3.0, 4.99, 5.01, 7.0, 9.9]


@pytest.mark.parametrize("curv", [0.02, 0.0])
@pytest.mark.parametrize("diam", ['DIAM 5 1 0 0 1 ""', "DIAM 5", 'DIAM 5 0 0 0 1 ""'])
def test_a_semi_diameter_alone_clips_nothing(curv, diam):
    """Zemax: the semi-diameter sizes the drawing; only a surface aperture vignettes. A fixed
    ("U", flag 1, or bare) and an automatic (flag 0) DIAM of 5 mm pass rays out to 9.9 mm,
    on a surface with power and on one without."""
    lens = zmx.loads(_lens_text(f"  {diam}\n", curv=curv))
    assert float(lens.surfaces[0].semi_diameter) == np.inf
    assert lens.apertures == () and lens.obscurations == ()
    assert _passes(lens, _on_y(HEIGHTS)) == [True] * len(HEIGHTS)


def test_a_floating_aperture_clips_at_the_fixed_semi_diameter():
    """FLAP (the floating aperture Zemax puts on a powered surface given a fixed
    semi-diameter) clips at the DIAM value; the radius written on FLAP is a copy."""
    lens = zmx.loads(_lens_text('  DIAM 5 1 0 0 1 ""\n  FLAP 0 5 0\n'))
    assert float(lens.surfaces[0].semi_diameter) == 5.0
    assert _passes(lens, _on_y(HEIGHTS)) == [True, True, True, False, False, False]
    # Off the y axis too: a circle of radius 5 mm.
    assert _passes(lens, [(3.0, 3.9), (3.0, 4.1), (-4.9, 0.0), (-5.1, 0.0)]) == [
        True, False, True, False]
    # The semi-diameter is the radius (a pickup, solve flag 2, is a fixed value too).
    lens = zmx.loads(_lens_text('  DIAM 4 2 0 0 1 ""\n  FLAP 0 4 0\n'))
    assert _passes(lens, _on_y([3.99, 4.01])) == [True, False]


def test_a_floating_aperture_on_an_automatic_semi_diameter_clips_nothing():
    """An automatic semi-diameter (flag 0) is the height of the file's outermost ray, so
    its floating aperture passes the file's beam; jaxlens does not clip there."""
    lens = zmx.loads(_lens_text('  DIAM 5 0 0 0 1 ""\n  FLAP 0 5 0\n'))
    assert float(lens.surfaces[0].semi_diameter) == np.inf
    assert _passes(lens, _on_y(HEIGHTS)) == [True] * len(HEIGHTS)


def test_a_floating_aperture_without_diam_clips_at_its_own_radius():
    lens = zmx.loads(_lens_text("  FLAP 0 6 0\n"))
    assert _passes(lens, _on_y([5.99, 6.01])) == [True, False]


def test_circular_aperture_and_obscurations_clip_as_drawn():
    # CLAP 0 5: a disc of radius 5 passes; a fixed DIAM beside it does not matter.
    lens = zmx.loads(_lens_text('  DIAM 8 1 0 0 1 ""\n  CLAP 0 5 0\n'))
    assert _passes(lens, _on_y(HEIGHTS)) == [True, True, True, False, False, False]
    # An annulus 2..5: the centre is blocked too.
    lens = zmx.loads(_lens_text("  CLAP 2 5 0\n"))
    assert _passes(lens, _on_y([0.0, 1.99, 2.01, 4.99, 5.01])) == [
        False, False, True, True, False]
    # OBSC 0 2: a central disc blocks, everything else passes.
    lens = zmx.loads(_lens_text("  OBSC 0 2 0\n"))
    assert _passes(lens, _on_y([0.0, 1.99, 2.01, 9.9])) == [False, False, True, True]


def test_rectangular_and_elliptical_apertures_clip_as_drawn():
    # SQAP 4 2: |x| <= 4 and |y| <= 2 pass.
    lens = zmx.loads(_lens_text("  SQAP 4 2 0\n"))
    assert _passes(lens, [(3.9, 1.9), (4.1, 0.0), (0.0, 2.1), (-3.9, -1.9)]) == [
        True, False, False, True]
    # ELAP 4 2: (x/4)² + (y/2)² <= 1 passes; the rectangle's corner does not.
    lens = zmx.loads(_lens_text("  ELAP 4 2 0\n"))
    assert _passes(lens, [(3.9, 0.0), (0.0, 1.9), (3.9, 1.9), (0.0, 2.1)]) == [
        True, True, False, False]
    # SQOB 1 1: a central square blocks.
    lens = zmx.loads(_lens_text("  SQOB 1 1 0\n"))
    assert _passes(lens, [(0.9, 0.9), (1.1, 0.0), (0.0, 5.0)]) == [False, True, True]
    # A fixed DIAM beside a shaped aperture does not clip either.
    lens = zmx.loads(_lens_text('  DIAM 1 1 0 0 1 ""\n  SQAP 4 2 0\n'))
    assert _passes(lens, [(3.9, 1.9)]) == [True]


def test_aperture_decenters():
    # A decenter moves a CLAP: a disc of radius 3 about (0, 2).
    lens = zmx.loads(_lens_text("  CLAP 0 3 0\n  OBDC 0 2\n"))
    assert _passes(lens, _on_y([-0.99, -1.01, 4.99, 5.01])) == [True, False, True, False]
    # On a surface whose semi-diameter clips nothing, a decenter has nothing to move.
    lens = zmx.loads(_lens_text('  DIAM 5 1 0 0 1 ""\n  OBDC 0 2\n'))
    assert _passes(lens, _on_y(HEIGHTS)) == [True] * len(HEIGHTS)
    # A decentered floating aperture is refused (jaxlens would have to guess).
    with pytest.raises(ValueError, match=r"<zmx>:\d+: a decenter \(OBDC\) of a floating "
                                         r"aperture .*: 'OBDC 0 2'"):
        zmx.loads(_lens_text('  DIAM 5 1 0 0 1 ""\n  FLAP 0 5 0\n  OBDC 0 2\n'))


def test_a_floating_aperture_survives_the_round_trip(tmp_path):
    """jaxlens writes a clipping semi-diameter as DIAM r 1 and CLAP 0 r 0: Zemax, optiland
    and jaxlens all clip the written file where the original clipped."""
    lens = zmx.loads(_lens_text('  DIAM 5 1 0 0 1 ""\n  FLAP 0 5 0\n'))
    jl.save(lens, tmp_path / "again.zmx")
    text = (tmp_path / "again.zmx").read_text()
    assert "CLAP 0 5.0E+000 0" in text
    again = jl.load(tmp_path / "again.zmx")
    assert _passes(again, _on_y(HEIGHTS)) == _passes(lens, _on_y(HEIGHTS))


def test_float_by_stop_size_reads_the_stop_semi_diameter_which_clips_nothing():
    """FLOA sizes the pupil from the stop's semi-diameter (the EPD of a stop on surface 1
    is its diameter); without an aperture the stop itself clips nothing."""
    lens = zmx.loads(_lens_text('  DIAM 4 1 0 0 1 ""\n', curv=0.0, head="FLOA\n"))
    assert float(lens.epd) == pytest.approx(8.0)
    assert _passes(lens, _on_y([3.99, 4.01])) == [True, True]


DATA = pathlib.Path(__file__).parent / "data" / "zmx"


def test_real_files_clip_at_their_apertures_only():
    """optiland's Thorlabs asphere (OpticStudio output): FLAP on a fixed DIAM 9 clips at 9
    mm, FLAP on an automatic DIAM clips nothing. optiland's FLOA file: the stop's fixed DIAM
    8.5 sets the pupil and, with no aperture on it, clips nothing."""
    lens = jl.load(DATA / "optiland_lens_thorlabs_iso_8859_1.zmx")
    assert [float(s.semi_diameter) for s in lens.surfaces] == [9.0, np.inf]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", zmx.ZmxWarning)  # FTYP announces 3 fields, YFLN 1
        lens = jl.load(DATA / "optiland_lens_floa.zmx")
    assert [float(s.semi_diameter) for s in lens.surfaces] == [np.inf] * 3
