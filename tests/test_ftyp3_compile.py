"""FTYP 3 (real image heights): the conversion to field angles compiles the chief-ray aiming once.

``zmx_system.angles_from_real_image_heights`` solves for each height's field with a Newton
whose miss function aims the chief ray at the stop (``aiming.stop_chief_ray``: its own Newton,
four or five traces) and traces it to the image; then it checks the solved chief ray through
the clipped lens. That check aimed the chief ray again, in a second compiled program: with a
polynomial surface every trace holds the Newton intersection (about eight sag evaluations),
and the Q-type asphere of rayoptics_ASL5040-UV.zmx took 4 s to compile the check alone (of
its 10 s load). The check now traces the ray that the solve aimed. Counted in operations (the
compiled programs' while loops and functions), not seconds.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx_system


def _singlet(aim: str = "real") -> jl.Lens:
    """A spherical singlet with its stop on surface 1 (cheap to compile); ``aim="real"`` (ray
    aiming on): the FTYP 3 chief ray is aimed at the stop centre (with it off, "paraxial",
    it is the ray through the paraxial entrance pupil's centre, not aimed: round 45c)."""
    return jl.Lens(
        surfaces=(jl.Sphere(1 / 40.0, 8.0), jl.Sphere(-1 / 40.0, 8.0)),
        thickness=jnp.array([4.0, 38.0]),
        materials=(jl.ModelGlass(1.5168, 64.17), jl.Air()),
        stop=0,
        epd=8.0,
        fields=jnp.array([0.0]),
        wavelengths=jnp.array([0.5875618]),
        aim=aim,
    )


def _solved_with_programs(lens, folder):
    """The FTYP 3 conversion of heights 0 and 2 mm, and the compiled programs it dumped
    into ``folder`` (file name -> text)."""
    jax.config.update("jax_dump_ir_to", str(folder))
    try:
        out = zmx_system.angles_from_real_image_heights(lens, np.array([0.0, 2.0]))
    finally:
        jax.config.update("jax_dump_ir_to", "")
    return out, {p.name: p.read_text() for p in folder.iterdir()}


def test_the_ftyp3_check_traces_the_solved_ray_without_aiming_it_again(tmp_path):
    out, modules = _solved_with_programs(_singlet(), tmp_path)
    check = [t for n, t in modules.items() if "_chief_ray_landing" in n]
    solve = [t for n, t in modules.items() if "_real_height_field" in n]
    assert len(check) == 1 and len(solve) == 1, sorted(modules)
    # The solve aims (the aiming's core is in its program); the check only traces.
    assert "@_stop_chief_ray" in solve[0]
    assert "@_stop_chief_ray" not in check[0]
    # Its loops are those of one trace (the aiming added a Newton loop and a halving loop,
    # and its traces theirs: 12 in all on main for this lens, 2 now).
    assert check[0].count("stablehlo.while") <= 2
    # The solved field lands where asked (the check itself passed: no ValueError).
    field = np.asarray(out.fields)
    assert field[0] == 0.0 and 0.0 < field[1] < 10.0


def test_with_ray_aiming_off_the_ftyp3_solve_aims_nothing(tmp_path):
    """Ray aiming off: the chief ray is the ray through the paraxial entrance pupil's
    centre, so neither the solve nor the check holds the stop aiming. The stop is surface 1
    here: the two chief rays are the same ray, and so is the field."""
    out, modules = _solved_with_programs(_singlet("paraxial"), tmp_path)
    solve = [t for n, t in modules.items() if "_real_height_field" in n]
    assert len(solve) == 1 and "@_stop_chief_ray" not in solve[0]
    aimed = zmx_system.angles_from_real_image_heights(_singlet("real"), np.array([0.0, 2.0]))
    np.testing.assert_allclose(np.asarray(out.fields), np.asarray(aimed.fields), rtol=0,
                               atol=1e-10)


def test_an_unreachable_height_is_still_refused():
    """3 m is beyond any real chief ray of the singlet (the field would pass 90°): the check
    on the solved ray refuses it, naming the height."""
    with pytest.raises(ValueError, match=r"no real chief ray reaches the image height "
                                         r"\[0\.0, 3000\.0\] mm"):
        zmx_system.angles_from_real_image_heights(_singlet(), np.array([3000.0]))


def test_newton_aux_is_taken_at_the_returned_root_and_the_steps_are_unchanged():
    """``newton_2d(has_aux=True)``: the same iterate as without aux, bit for bit, and the
    aux evaluated there (not at the iterate before the last step)."""
    from jaxlens.imaging.newton import newton_2d

    def miss(x, p):
        return jnp.array([x[0] ** 3 + x[1] - p, x[1] ** 3 - x[0] + 0.5])

    def miss_aux(x, p):
        return miss(x, p), x  # the aux: the point it was evaluated at

    for iters in (0, 1, 3, 12):
        plain = newton_2d(miss, jnp.array([0.3, 0.2]), 1.5, iters, implicit_gradient=False)
        x, at = newton_2d(miss_aux, jnp.array([0.3, 0.2]), 1.5, iters,
                          implicit_gradient=False, has_aux=True)
        assert np.array_equal(np.asarray(x), np.asarray(plain))
        assert np.array_equal(np.asarray(at), np.asarray(x))
    with pytest.raises(ValueError, match=r"has_aux=True needs plain Newton"):
        newton_2d(miss_aux, jnp.zeros(2), 1.5, 3, has_aux=True)
