"""Round 46a: degenerate but legal first-order systems, against thin- and thick-lens formulas.

Each lens below is legal (``Lens`` accepts it) but puts a paraxial quantity at infinity or
makes it undefined: an entrance pupil at infinity without ``object_na`` (the stop in the rear
focal plane of the surfaces before it), an exit pupil at infinity, both (a bitelecentric
relay), an afocal lens with a finite object, an object in the front focal plane (image at
infinity), a zero-power plate, an object on the entrance pupil's plane. Every public
first-order and analysis entry point must give the analytic finite answer, the documented
±inf, or a ValueError naming itself and why: never NaN, never a plausible wrong number.

Expectations come from Gaussian optics, not from jaxlens: for a thin lens of focal length f,
1/s' = 1/f + 1/s (s the object's signed position, negative before the lens) and m = s'/s; for
a thick lens in air (radii R1, R2, thickness t, index n) Φ = (n−1)(1/R1 − 1/R2) +
(n−1)² t/(n R1 R2), the back focal distance f(1 − (n−1)t/(n R1)), the front focal distance
f(1 + (n−1)t/(n R2)), and Newton's m = −f/x with x the object's distance before the front
focal point; a plate of thickness t and index n shifts an image by t(1 − 1/n) and has m = 1.
"""

from __future__ import annotations

import json
import math
import pathlib
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import analysis
from jaxlens.analysis import report
from jaxlens.imaging import radiometry
from jaxlens.imaging.psf import mtf
from jaxlens.optics import paraxial
from jaxlens.optics.paraxial_surface import ParaxialSurface

ROOT = pathlib.Path(__file__).resolve().parents[1]
WL = 0.5875618
GLASS = jl.ModelGlass(1.5, 64.0)  # n = 1.5 exactly at the primary wavelength
N = 1.5
R1, R2, T = 60.0, -40.0, 8.0  # a thick biconvex singlet
PHI = (N - 1) * (1 / R1 - 1 / R2) + (N - 1) ** 2 * T / (N * R1 * R2)
F = 1 / PHI
BFD = F * (1 - (N - 1) * T / (N * R1))  # last vertex to the rear focal point
FFD = F * (1 + (N - 1) * T / (N * R2))  # front focal point to the first vertex


def _lens(surfaces, thickness, materials, stop, od, fields=(0.0, 1.0), epd=4.0):
    return jl.Lens(surfaces=tuple(surfaces), thickness=jnp.array(thickness, float),
                   materials=tuple(materials), stop=stop, epd=epd, object_distance=od,
                   fields=fields)


def _thin(f):
    return ParaxialSurface(focal_length=f, semi_diameter=20.0)


def _plane():
    return jl.Plane(semi_diameter=20.0)


def _singlet():
    return [jl.Sphere(1 / R1, semi_diameter=15.0), jl.Sphere(1 / R2, semi_diameter=15.0)]


def _ep_at_infinity(od):
    """The thick singlet with its stop in its rear focal plane: the entrance pupil at
    infinity (object-space telecentric by geometry, without object_na)."""
    return _lens(_singlet() + [_plane()], [T, BFD, 60.0], [GLASS, jl.Air(), jl.Air()], 2, od)


def _xp_at_infinity(od):
    """The stop in the singlet's front focal plane: the exit pupil at infinity."""
    return _lens([_plane()] + _singlet(), [FFD, T, BFD], [jl.Air(), GLASS, jl.Air()], 0, od)


def _finite(x):
    return bool(np.all(np.isfinite(np.asarray(x, float))))


# --- the entrance pupil at infinity (no object_na) ------------------------------------------

def test_singlet_formulas_hold():
    """The thick-lens formulas above, against the y–nu trace (a test of the references)."""
    lens = _xp_at_infinity(None)
    assert float(jl.efl(lens)) == pytest.approx(F, rel=1e-13)
    assert float(jl.bfl(lens)) == pytest.approx(BFD, rel=1e-13)


@pytest.mark.parametrize("od", [250.0, None])
def test_pupil_at_infinity_first_order(od):
    lens = _ep_at_infinity(od)
    assert math.isinf(float(paraxial.entrance_pupil_z(lens)))  # documented: ±inf
    assert float(jl.efl(lens)) == pytest.approx(F, rel=1e-13)
    assert abs(float(jl.bfl(lens))) < 1e-12  # from the last vertex, the stop in the focus
    # The EPD sets no marginal ray: refused by name, not the axis (stop size 0, F/# inf).
    for where, call in (("marginal_ray", paraxial.marginal_ray),
                        ("paraxial_data", paraxial.paraxial_data)):
        with pytest.raises(ValueError, match=rf"^{where}: .*entrance pupil lies at infinity"):
            call(lens)
    with pytest.raises(ValueError, match="entrance pupil lies at infinity"):
        paraxial.working_fnum(lens, 300.0)
    # The axis is a chief ray; no other field angle has one (round 45a).
    y, nu = paraxial.paraxial_chief_ray(lens, 0.0)
    assert np.all(np.asarray(y) == 0) and np.all(np.asarray(nu) == 0)
    with pytest.raises(ValueError, match="paraxial_chief_ray: .*entrance pupil lies at"):
        paraxial.image_height(lens, 1.0)


def test_pupil_at_infinity_magnification():
    """m does not depend on the aperture: Newton's −f/x, finite (was 0/0: the marginal ray was
    the axis)."""
    od = 250.0
    x = od - FFD  # the object's distance before the front focal point
    m = float(paraxial.magnification(_ep_at_infinity(od)))
    assert m == pytest.approx(-F / x, rel=1e-12)
    assert float(paraxial.magnification(_ep_at_infinity(None))) == 0.0  # documented


ANALYSES = {
    "rms_spot": lambda lens: analysis.rms_spot(lens),
    "chief_ray": lambda lens: analysis.chief_ray(lens, 0.0),
    "distortion": lambda lens: analysis.distortion(lens),
    "field_curvature": lambda lens: analysis.field_curvature(lens),
    "ray_fan": lambda lens: analysis.ray_fan(lens, 0.0),
    "wavefront": lambda lens: analysis.wavefront(lens, 0.0),
    "encircled_energy": lambda lens: analysis.encircled_energy(lens, 0.0, radii=[0.01]),
    "relative_illumination": lambda lens: radiometry.relative_illumination(lens, [0.0]),
    "psf": lambda lens: jl.psf(lens, 0.0, pixel_size=0.002),
    "mtf": lambda lens: mtf(lens, 0.0),
    "report": lambda lens: report.report_data(lens),
    "render": lambda lens: jl.render(lens, jnp.zeros((8, 8, 3)), spp=1, key=jax.random.key(0),
                                     sensor=jl.Sensor(pixel_size=0.01, resolution=(8, 8))),
}


@pytest.mark.parametrize("name", list(ANALYSES))
@pytest.mark.parametrize("od", [250.0, None])
def test_pupil_at_infinity_analyses_refuse_by_name(name, od):
    """Every analysis launches its beams on the entrance pupil's plane: refused at entry,
    naming itself (spots, fans and the relative illumination were NaN, the report an
    EquinoxRuntimeError from inside its compiled trace)."""
    with pytest.raises(ValueError, match=rf"^{name}: .*entrance pupil lies at infinity"):
        ANALYSES[name](_ep_at_infinity(od))


def test_seidel_pupil_at_infinity_refused():
    for od in (250.0, None):
        with pytest.raises(ValueError, match="^seidel: .*entrance pupil lies at infinity"):
            analysis.seidel(_ep_at_infinity(od))


def test_bitelecentric_relay():
    """f1 = 50, f2 = 100 sharing a focal plane (the stop), the object in f1's front focal
    plane: m = −f2/f1 = −2, finite (the object in a focal plane of the first lens only), the
    lens afocal, both pupils at infinity."""
    lens = _lens([_thin(50.0), _plane(), _thin(100.0)], [50.0, 100.0, 100.0],
                 [jl.Air()] * 3, 1, 50.0)
    assert float(paraxial.magnification(lens)) == pytest.approx(-2.0, rel=1e-14)
    assert float(jl.efl(lens)) == math.inf
    assert math.isinf(float(paraxial.entrance_pupil_z(lens)))
    with pytest.raises(ValueError, match="^paraxial_data: .*entrance pupil lies at infinity"):
        paraxial.paraxial_data(lens)
    with pytest.raises(ValueError, match="^rms_spot: .*entrance pupil lies at infinity"):
        analysis.rms_spot(lens)


# --- the exit pupil at infinity ------------------------------------------------------------

def test_exit_pupil_at_infinity():
    lens = _xp_at_infinity(None)
    pd = paraxial.paraxial_data(lens)
    assert math.isinf(float(pd.exit_pupil_z)) and float(pd.exit_pupil_diameter) == math.inf
    assert float(pd.entrance_pupil_z) == 0.0
    assert float(pd.stop_semi_diameter) == pytest.approx(2.0, rel=1e-14)
    assert float(pd.working_fnum) == pytest.approx(F / 4.0, rel=1e-12)
    assert float(pd.paraxial_image_z) == pytest.approx(FFD + T + BFD, rel=1e-12)
    y, nu = paraxial.paraxial_chief_ray(lens, 1.0)  # telecentric in image space
    assert abs(float(nu[-1])) < 1e-15
    # image height F·tanθ (the chief ray parallel to the axis after the lens)
    assert float(y[-1]) == pytest.approx(F * math.tan(math.radians(1.0)), rel=1e-12)
    spot = analysis.rms_spot(lens)
    assert _finite(spot.polychromatic) and _finite(analysis.distortion(lens).percent_ftan)
    w = analysis.wavefront(lens, 1.0)
    assert _finite(w.rms) and _finite(w.pv)
    assert _finite(jl.psf(lens, 0.0, pixel_size=0.01))


# --- an image at infinity, an afocal lens, a plate -----------------------------------------

def test_object_in_front_focal_plane():
    """Thin f = 50 with the object 50 mm before it, and the thick singlet with its object at
    its front focal point: the image at infinity; m and the working F/# +inf (documented)."""
    for lens in (_lens([_thin(50.0)], [100.0], [jl.Air()], 0, 50.0),
                 _lens(_singlet(), [T, 80.0], [GLASS, jl.Air()], 0, FFD)):
        pd = paraxial.paraxial_data(lens)
        assert float(paraxial.magnification(lens)) == math.inf
        assert math.isinf(float(pd.paraxial_image_z))
        assert float(pd.working_fnum) == math.inf
        assert _finite(analysis.rms_spot(lens).polychromatic)
        with pytest.raises(ValueError, match=r"^mtf: .*working F/# .* is infinite"):
            mtf(lens, 0.0)
    # Given frequencies and pixel size without the diffraction factor, the MTF is finite.
    f, t, s = mtf(lens, 0.0, frequencies=[0.0, 1.0], pixel_size=0.01, diffraction=False)
    assert _finite(t) and _finite(s) and float(t[0]) == pytest.approx(1.0)


def test_afocal_lens_with_finite_object():
    """Keplerian f1 = 100, f2 = 50: object 500 before lens 1 → image 125 after it, a virtual
    object 25 before lens 2 → image 50 before lens 2 (z = 100); m = (−1/4)(2) = −f2/f1."""
    lens = _lens([_thin(100.0), _thin(50.0)], [150.0, 100.0], [jl.Air()] * 2, 0, 500.0)
    pd = paraxial.paraxial_data(lens)
    assert float(pd.efl) == math.inf and math.isinf(float(pd.bfl))
    assert float(pd.paraxial_image_z) == pytest.approx(100.0, rel=1e-13)
    assert float(paraxial.magnification(lens)) == pytest.approx(-0.5, rel=1e-14)
    # u = 2/500, u' = u/m: working F/# 1/(2|u'|) = 62.5; the stop (lens 1) imaged by lens 2
    assert float(pd.working_fnum) == pytest.approx(62.5, rel=1e-12)
    assert float(pd.exit_pupil_z) == pytest.approx(225.0, rel=1e-13)
    assert float(pd.exit_pupil_diameter) == pytest.approx(2.0, rel=1e-13)
    d = analysis.distortion(lens)  # f·tanθ of an infinite f: 0 on the axis, inf off it
    assert float(d.f_tan[0]) == 0.0 and math.isinf(float(d.f_tan[1]))
    assert np.asarray(d.percent_ftan).tolist() == [0.0, -100.0]
    assert _finite(d.percent_paraxial) and _finite(d.percent_ftheta)
    data = report.report_data(lens)
    assert data["fields"][0]["distortion"] == 0.0  # was NaN ("failed")


@pytest.mark.parametrize("od", [100.0, None])
def test_zero_power_plate(od):
    t, gap = 10.0, 20.0
    lens = _lens([_plane(), _plane()], [t, gap], [GLASS, jl.Air()], 0, od)
    pd = paraxial.paraxial_data(lens)
    assert float(pd.efl) == math.inf and math.isinf(float(pd.bfl))
    assert float(pd.fnum) == math.inf
    # the stop (surface 1) seen through the rear face: apparent depth t/n before it
    assert float(pd.exit_pupil_z) == pytest.approx(t - t / N, rel=1e-13)
    if od is None:
        assert float(paraxial.magnification(lens)) == 0.0
        assert math.isinf(float(pd.paraxial_image_z)) and float(pd.working_fnum) == math.inf
    else:
        assert float(paraxial.magnification(lens)) == pytest.approx(1.0, rel=1e-14)
        assert float(pd.paraxial_image_z) == pytest.approx(-(od - t * (1 - 1 / N)), rel=1e-13)
        assert float(pd.working_fnum) == pytest.approx(od / 4.0, rel=1e-13)
    assert _finite(analysis.rms_spot(lens).polychromatic)
    assert _finite(analysis.distortion(lens).percent_paraxial)


# --- the object on the entrance pupil's plane, or on surface 1 -----------------------------

def test_object_on_entrance_pupil_plane():
    """Thin f = 50, stop 25 after it: the pupil at z = 50 (virtual); a virtual object there
    has a marginal ray of infinite slope (refused), but its image is finite: s = +50 →
    s' = 25, m = 0.5."""
    lens = _lens([_thin(50.0), _plane()], [25.0, 50.0], [jl.Air()] * 2, 1, -50.0)
    assert float(paraxial.entrance_pupil_z(lens)) == pytest.approx(50.0, rel=1e-14)
    for where, call in (("marginal_ray", paraxial.marginal_ray),
                        ("paraxial_data", paraxial.paraxial_data)):
        with pytest.raises(ValueError, match=rf"^{where}: .*on its entrance pupil's plane"):
            call(lens)
    assert float(paraxial.magnification(lens)) == pytest.approx(0.5, rel=1e-14)
    with pytest.raises(ValueError, match="^rms_spot: .*entrance pupil"):
        analysis.rms_spot(lens)


def test_object_on_surface_one_refused():
    """An object on surface 1 (object_distance 0; the stop there too) is refused by Lens."""
    with pytest.raises(ValueError, match="object_distance"):
        _lens([_thin(50.0)], [60.0], [jl.Air()], 0, 0.0)


# --- JSON: a stop-sized (FLOA) aperture and its aim --------------------------------------

def test_json_round_trips_stop_sized_aperture(tmp_path):
    """A .zmx lens whose aperture is its stop's size (FLOA, RAIM 2 → aim "real") keeps its
    aim and the EPD that fills the stop through a JSON file: its paraxial marginal ray still
    meets the 4 mm stop at 4 mm (the aperture type itself is not a Lens field: the EPD and
    the aim are what trace)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(str(ROOT / "tests" / "data" / "aim45a" / "triplet_floa_raim2.zmx"))
        path = tmp_path / "floa.json"
        jl.save(lens, str(path))
        back = jl.load(str(path))
    assert lens.aim == back.aim == "real"
    assert json.loads(path.read_text())["ray_aiming"] == "real"
    assert float(back.epd) == float(lens.epd)
    sd = float(lens.surfaces[lens.stop].semi_diameter)
    assert float(paraxial.paraxial_data(back).stop_semi_diameter) == pytest.approx(sd, rel=1e-12)
