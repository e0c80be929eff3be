"""Ray aiming as a property of the lens (``Lens.aim``): "paraxial" (rays through the paraxial
entrance pupil, Zemax's aiming "Off"), "real" (aimed at the real stop, Zemax's "Paraxial"
ray aiming) or "real_marginal" (the stop sized by the real marginal ray, Zemax's "Real";
more in tests/test_ray_aiming_robust.py). The samplers and the analyses use the lens's own
where their ``aim`` is None; ``.zmx`` RAIM and the JSON key ``"ray_aiming"`` carry it.

The lens: the double Gauss of ``tests/refcases/double_gauss.json`` at its full field (14°),
whose entrance pupil is aberrated: paraxially aimed rim rays cross the stop at 1.037 and
−0.984 of its radius and the chief ray at 0.044 of it.
"""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import report_cells, spots
from jaxlens.imaging import sampling
from jaxlens.io.zmx import ZmxWarning
from jaxlens.tracing.forward import trace, trace_path

ROOT = Path(__file__).resolve().parents[1]
PUPIL = jnp.array(((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (0.6, 0.6), (-0.3, 0.7)))

# optiland 0.6.3, tools/ray_aiming_reference.py (run with /work/optiland_venv/bin/python):
# its iterative ray aiming on the same double Gauss, 14°, primary wavelength, the rays of
# PUPIL; (x, y) mm at the stop and on the image surface. optiland sizes the stop with a
# real marginal ray (Zemax's "Real" aiming, RAIM 2, jaxlens's "real_marginal"): its stop
# radius is OPTILAND_STOP_R, not the paraxial 6.3412410 mm that aim="real" aims at.
OPTILAND_STOP_R = 6.335001683687201
OPTILAND_IMAGE = [[0.0, 24.671377951752156], [0.0, 24.626093365780314],
                  [0.0, 24.714497681191762], [-0.060834585781464945, 24.669259778836533],
                  [-0.03684023273812276, 24.644777706725137],
                  [0.018233499493694127, 24.641627828791965]]


@pytest.fixture(scope="module")
def lenses():
    lens = jl.load(ROOT / "tests" / "refcases" / "double_gauss.json")
    return lens, dataclasses.replace(lens, aim="real")


def _at_stop(lens, rays):
    return np.asarray(trace_path(lens, rays, upto=lens.stop)[-1].origin[:, :2])


# In CI: the physics of the setting, in one compiled program (op by op, each call of the
# aiming compiled its Newton loop and each trace its scan again: 23 s of CPU).
def test_real_aiming_puts_the_rays_on_the_stop_and_the_lens_setting_chooses_it(lenses):
    lens, real = lenses
    assert lens.aim == "paraxial" and real.aim == "real"

    @jax.jit
    def stop_points(lens, real):
        def at_stop(rays):
            return trace_path(lens, rays, upto=lens.stop)[-1].origin[:, :2]

        return (jl.paraxial_data(lens).stop_semi_diameter,
                at_stop(sampling.field_rays(real, 14.0, PUPIL)),  # the lens's own: real
                at_stop(sampling.field_rays(lens, 14.0, PUPIL)))  # the lens's own: paraxial

    r_stop, aimed, par = (np.asarray(x) for x in stop_points(lens, real))
    r_stop = float(r_stop)
    want = np.asarray(PUPIL) * r_stop
    np.testing.assert_allclose(aimed, want, rtol=0, atol=1e-9)
    # Paraxial aiming misses the stop points by the pupil aberration (4 % of the radius).
    par = par / r_stop
    np.testing.assert_allclose(par[:3, 1], [0.0440189, 1.0372948, -0.9840120], atol=1e-6)

    # An explicit aim overrides the lens's: the same program (so the same rays) either way,
    # and not the other aim's. Compared as traced programs, which compile nothing.
    def program(lens, aim):
        return str(jax.make_jaxpr(lambda L: sampling.field_rays(L, 14.0, PUPIL, aim=aim))(lens))

    own_real, own_paraxial = program(real, None), program(lens, None)
    assert own_real != own_paraxial
    assert program(lens, "real") == own_real
    assert program(real, "paraxial") == own_paraxial


@pytest.mark.slow  # 10 s
def test_real_aiming_agrees_with_optiland(lenses):
    """optiland aims at a stop sized by a real marginal ray; aimed at the same points (the
    pupil scaled by its stop radius over the paraxial one), jaxlens's rays are optiland's
    to 1e-9 mm on the image surface. The chief ray does not depend on the stop's size."""
    lens, real = lenses
    r_stop = float(jl.paraxial_data(lens).stop_semi_diameter)
    rays = sampling.field_rays(real, 14.0, PUPIL * (OPTILAND_STOP_R / r_stop))
    out = trace(real, rays)
    assert bool(jnp.all(out.valid))
    np.testing.assert_allclose(np.asarray(out.origin[:, :2]), OPTILAND_IMAGE, rtol=0, atol=1e-9)
    chief = spots.chief_ray(real, 14.0)  # the lens's own aiming: through the stop centre
    assert float(chief.origin[1]) == pytest.approx(OPTILAND_IMAGE[0][1], abs=1e-9)
    # Zemax's "Real" aiming (aim="real_marginal") sizes the stop as optiland does: its rays
    # at the pupil points as given are optiland's.
    marginal = dataclasses.replace(lens, aim="real_marginal")
    assert float(sampling.stop_radius(marginal, "real")) == pytest.approx(OPTILAND_STOP_R,
                                                                          abs=1e-12)
    out = trace(marginal, sampling.field_rays(marginal, 14.0, PUPIL))
    assert bool(jnp.all(out.valid))
    np.testing.assert_allclose(np.asarray(out.origin[:, :2]), OPTILAND_IMAGE, rtol=0, atol=1e-9)
    # Paraxially aimed, the chief ray lands 1.6 µm lower (refcase: 24.669769973 mm).
    assert float(spots.chief_ray(lens, 14.0).origin[1]) == pytest.approx(24.66976997301721,
                                                                          abs=1e-9)


@pytest.mark.slow  # 28 s
def test_rms_spot_follows_the_lens_aiming(lenses):
    lens, real = lenses
    f, w = jnp.array([14.0]), jnp.array([lens.primary_wavelength])
    own = spots.rms_spot(real, f, w)
    forced = spots.rms_spot(lens, f, w, aim="real")
    par = spots.rms_spot(lens, f, w)
    np.testing.assert_array_equal(np.asarray(own.per_wavelength), np.asarray(forced.per_wavelength))
    np.testing.assert_array_equal(np.asarray(own.chief), np.asarray(forced.chief))
    # 36.336 µm aimed at the real stop against 36.656 µm (the refcase's) through the
    # paraxial pupil: −0.87 %.
    assert float(own.per_wavelength[0, 0]) == pytest.approx(0.03633629709364, abs=1e-12)
    assert float(par.per_wavelength[0, 0]) == pytest.approx(0.03665594259070562, abs=1e-12)
    assert float(own.chief[0, 1]) == pytest.approx(OPTILAND_IMAGE[0][1], abs=1e-9)


def test_bad_aiming_values_are_refused(lenses, tmp_path):
    lens, _ = lenses
    for bad in ("Real", "off", 1, None):
        with pytest.raises(ValueError, match=r"aim \(ray aiming\) must be one of "
                                             r"\('paraxial', 'real', 'real_marginal'\)"):
            dataclasses.replace(lens, aim=bad)
    with pytest.raises(ValueError, match=r"field_rays: aim must be one of \('paraxial', "
                                         r"'real', 'real_marginal'\) or None"):
        sampling.field_rays(lens, 0.0, PUPIL, aim="stop")
    with pytest.raises(ValueError, match=r"rms_spot: aim must be one of"):
        spots.rms_spot(lens, aim="REAL")
    p = tmp_path / "l.json"
    jl.save(lens, p)
    text = p.read_text()
    assert "ray_aiming" not in text  # paraxial: not written
    d = json.loads(text)
    for bad in ("Real", True, 1, "stop"):
        d["ray_aiming"] = bad
        p.write_text(json.dumps(d))
        with pytest.raises(ValueError, match=r"ray_aiming must be one of \['paraxial', 'real', "
                                             r"'real_marginal'\]"):
            jl.load(p)
    d.pop("ray_aiming")
    d["aiming"] = "real"  # a synonym is refused, naming the key
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match="ray_aiming"):
        jl.load(p)


def test_json_and_zmx_round_trips_keep_the_aiming(lenses, tmp_path):
    lens, real = lenses
    marginal = dataclasses.replace(lens, aim="real_marginal")
    for ext in ("json", "zmx"):
        for lz in (lens, real, marginal):
            p = tmp_path / f"r_{lz.aim}.{ext}"
            jl.save(lz, p)
            with warnings.catch_warnings():
                warnings.simplefilter("error", ZmxWarning)  # RAIM 1 and 2 are read silently
                assert jl.load(p).aim == lz.aim
    assert "RAIM 0 1 " in (tmp_path / "r_real.zmx").read_text()
    assert "RAIM 0 2 " in (tmp_path / "r_real_marginal.zmx").read_text()
    assert "RAIM" not in (tmp_path / "r_paraxial.zmx").read_text()


def _singlet(raim: str) -> str:
    return (f"UNIT MM\nENPD 10\n{raim}WAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\n"
            "SURF 1\n  STOP\n  CURV 0.02\n  DISZ 4\n  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"
            "SURF 2\n  CURV -0.005\n  DISZ 90\nSURF 3\n")


def test_zmx_raim_types(tmp_path):
    p = tmp_path / "s.zmx"
    for raim, aim in (("", "paraxial"), ("RAIM 0 0 1 1 0 0 0 0 0\n", "paraxial"),
                      ("RAIM 0 1 1 1 0 0 0 0 0\n", "real")):
        p.write_text(_singlet(raim))
        with warnings.catch_warnings():
            warnings.simplefilter("error", ZmxWarning)
            assert jl.load(p, strict=True).aim == aim
    p.write_text(_singlet("RAIM 0 2 1 1 0 0 0 0 0\n"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ZmxWarning)  # Zemax's "Real": exactly real_marginal
        assert jl.load(p, strict=True).aim == "real_marginal"
    p.write_text(_singlet("RAIM 0 3 1 1 0 0 0 0 0\n"))
    with pytest.raises(ValueError, match=r"s\.zmx:3.*ray aiming type 3 .RAIM's second value. "
                                         r"is not one of 0"):
        jl.load(p)


def test_the_report_says_which_aiming_it_used():
    assert report_cells.aiming_line({"ray_aiming": "real"}).endswith(
        "real (rays aimed at the real stop)")
    assert "paraxial entrance pupil" in report_cells.aiming_line({})


@pytest.mark.slow  # 10 s
def test_a_ray_the_aiming_does_not_bring_to_its_stop_point_is_invalid():
    """A singlet 10 mm before its stop at 25°: no ray of the beam reaches the stop's centre,
    its lower rim or the sagittal point (in the meridian the stop height has a minimum,
    about 0.5 mm above the axis: the pupil folds). Those rays were launched valid, crossing
    the stop at 0.27, −3.85 and (0.66, 2.12) of its radius; they are invalid
    (``sampling.AIM_TOLERANCE``), whatever the iterations. The upper rim ray is aimed."""
    lens = jl.Lens(surfaces=(jl.Standard(c=1 / 30.0), jl.Standard(c=-1 / 80.0), jl.Standard()),
                   thickness=jnp.array([6.0, 10.0, 40.0]),
                   materials=(jl.get_material("N-BK7"), jl.Air(), jl.Air()),
                   stop=2, epd=12.0, fields=(0.0, 25.0), aim="real")
    pupil = jnp.array([[0.0, 0.0], [0.0, 1.0], [0.0, -1.0], [1.0, 0.0]])
    rays = sampling.field_rays(lens, 25.0, pupil)
    np.testing.assert_array_equal(np.asarray(rays.valid), [False, True, False, False])
    r_stop = float(jl.paraxial_data(lens).stop_semi_diameter)
    np.testing.assert_allclose(_at_stop(lens, rays)[1], [0.0, r_stop], rtol=0, atol=1e-9)


@pytest.mark.slow  # 30 s each: the aimed spot differentiated through the Newton aiming
@pytest.mark.parametrize("aim", ["real", "real_marginal"])
def test_gradient_of_a_real_aimed_spot_matches_central_differences(aim):
    """d(RMS about the chief ray)/dc of the Cooke triplet's third surface, 15°, the rays
    aimed at the real stop (sized by the paraxial or the real marginal ray): automatic
    differentiation (the implicit-function gradient of ``aim_at_stop``'s Newton solve, and
    for "real_marginal" the marginal ray's trace) against central differences
    (h = 1e-6 1/mm)."""
    import equinox as eqx
    import jax

    lens = dataclasses.replace(jl.zoo.cooke_triplet(), aim=aim)
    f, w = jnp.array([15.0]), jnp.array([lens.primary_wavelength])

    def loss(c):
        edited = eqx.tree_at(lambda x: x.surfaces[2].c, lens, c)
        return spots.rms_spot(edited, f, w, reference="chief").polychromatic[0]

    c0, h = lens.surfaces[2].c, 1e-6
    ad = float(jax.grad(loss)(c0))
    fd = float((loss(c0 + h) - loss(c0 - h)) / (2 * h))
    assert abs(ad) > 1.0
    assert ad == pytest.approx(fd, rel=1e-4)
