"""Round 45b: held-out bad inputs (``tools/audit45b_probe.py``).

1. A lens whose primary wavelength lies past a glass formula's resonance was refused in the
   name of a function the user never called (``efl`` said ``signed_indices``,
   ``encircled_energy`` ``paraxial_chief_ray``, ``self_intersection``
   ``clear_semi_diameters``); just past the pole (2.0000001 µm, inside the checks' 1e-6
   slack) it gave efl = 0.0084 mm from n = 3162.
2. Rounding-level zeros: ``FNUM x 1`` of a lens whose image lies at infinity gave an EPD of
   1e14 mm; the PARAXIAL OPD-mode check refused a nearly collimated beam with 0.015 waves
   of rounding.
3. Radii and focal lengths below 1 nm: a focal length of 5e-324 mm gave efl = +inf (1/f
   overflows), a JSON radius of 1e-300 mm a curvature of 1e300.
4. ``object_slope``/``in_cone`` of a lens without an object NA: a TypeError about None.
"""

import copy
import functools
import json
import pathlib
import re
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_toroid_paraxial import ZMX
from test_zmx_paraxial_opd import TWO_LENSES

import jaxlens as jl
from jaxlens.analysis import encircled, spots
from jaxlens.imaging import aiming, sampling, telecentric
from jaxlens.optics import paraxial as PX
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.optics.toroidal import Toroidal

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"
# Resonances at sqrt(0.02) = 0.1414 µm and sqrt(4) = 2 µm: the d line's window.
RESONANT = jl.Sellmeier(B=(1.0, 0.2, 1.0), C=(0.006, 0.02, 4.0))


def resonant_lens(wavelengths=(3.0,)):
    return jl.Lens((jl.Sphere(c=0.02, semi_diameter=10.0), jl.Stop(semi_diameter=4.0),
                    jl.Sphere(c=-0.02, semi_diameter=10.0)), jnp.array([5.0, 1.0, 90.0]),
                   (RESONANT, RESONANT, jl.Air()), epd=8.0, wavelengths=wavelengths,
                   fields=(0.0, 5.0), stop=1)


CALLS = {
    "efl": lambda L: PX.efl(L),
    "bfl": lambda L: PX.bfl(L),
    "magnification": lambda L: PX.magnification(L),
    "marginal_ray": lambda L: PX.marginal_ray(L),
    "paraxial_data": lambda L: PX.paraxial_data(L),
    "system_matrix": lambda L: PX.system_matrix(L),
    "image_height": lambda L: PX.image_height(L, 1.0),
    "encircled_energy": lambda L: encircled.encircled_energy(L, 0.0, jnp.array([0.01])),
    "self_intersection": lambda L: spots.self_intersection(L),
    "semi_diameters_and_fans": lambda L: spots.semi_diameters_and_fans(
        L, jnp.array([0.0]), jnp.zeros((1, 2))),
    "stop_radius": lambda L: sampling.stop_radius(L),
    "image_scale": lambda L: aiming.image_scale(L),
    "field_to_ideal": lambda L: aiming.field_to_ideal(L, 1.0),
    "ideal_to_field": lambda L: aiming.ideal_to_field(L, jnp.array([0.0, 1.0])),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_primary_wavelength_past_a_resonance_is_named_by_the_call(name):
    with pytest.raises(ValueError, match=rf"^{name}: the lens's (primary wavelength|wavelengths) "
                                         r"3 µm is outside 0\.15–2 µm, .*resonances \(poles\)"):
        CALLS[name](resonant_lens())


def test_no_slack_across_a_pole():
    """n = 3162 at 2.0000001 µm, 1e-7 past the pole: efl 0.0084 mm before."""
    with pytest.raises(ValueError, match=r"^efl: the lens's primary wavelength 2 µm is outside"):
        PX.efl(resonant_lens((2.0000001,)))
    # A wavelength given at the call is checked, not the primary one it replaces.
    lens = resonant_lens((3.0, 0.5))
    assert float(PX.efl(lens, 0.5)) == pytest.approx(float(PX.efl(resonant_lens((0.5,)))),
                                                     rel=1e-14)


def _zmx_with(lens, aperture, tmp_path):
    p = tmp_path / "a.zmx"
    jl.save(lens, p)
    text = p.read_text()
    line = next(t for t in text.splitlines() if t.startswith("ENPD"))
    p.write_text(text.replace(line, aperture))
    return p


def _thin(f, s):
    return jl.Lens((ParaxialSurface(focal_length=f),), jnp.array([100.0]), (jl.Air(),),
                   epd=10.0, object_distance=s)


@pytest.mark.parametrize("lens", [
    jl.Lens((ParaxialSurface(focal_length=0.3), ParaxialSurface(focal_length=0.3)),
            jnp.array([0.1 + 0.2 + 0.3, 50.0]), (jl.Air(), jl.Air()), epd=10.0),
    _thin(0.3, 0.1 * 3), _thin(100.0, 100.0 * (1 + 1e-15))])
def test_working_fnum_of_an_image_at_infinity(lens, tmp_path):
    with pytest.raises(ValueError, match=r"a\.zmx:\d+: the paraxial marginal ray leaves the "
                                         r"lens parallel to the axis .*'FNUM 5 1'"):
        jl.load(_zmx_with(lens, "FNUM 5 1", tmp_path))


def test_working_fnum_at_finite_conjugates(tmp_path):
    """Object at 300 mm, f = 100: image at 150 mm, u' = (EPD/2)/150, F/#w = 1/(2u') =
    150/EPD = 5 at EPD 30 mm."""
    lens = jl.load(_zmx_with(_thin(100.0, 300.0), "FNUM 5 1", tmp_path))
    assert float(lens.epd) == pytest.approx(30.0, rel=1e-12)


@pytest.mark.parametrize("f1", ["5e10", "-5e10", "1e10"])
def test_opd_mode_check_of_a_nearly_collimated_beam(f1, tmp_path):
    """The difference falls as 1/z_O (1.1e-5 waves at f1 = -2000 mm, so ~4e-13 here):
    rounding in the subtraction of two 5e10 mm lengths gave 0.015 waves, and a refusal."""
    p = tmp_path / "t.zmx"
    p.write_text(TWO_LENSES.format(f1=f1, sd=1.0, opd="PARM 2 0", flap="", epd=0.02, field=0.0))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        jl.load(p)
    said = " ".join(str(x.message) for x in w)
    waves = float(re.search(r"differ by at most ([0-9.e+-]+) waves", said).group(1))
    assert waves < 1e-9


@pytest.mark.parametrize("f", [1e-300, 5e-324, -1e-320, 1e-12, float("nan")])
def test_paraxial_surface_focal_length_floor(f):
    with pytest.raises(ValueError, match=r"ParaxialSurface: focal_length must be finite and at "
                                         r"least 1e-09 mm in size"):
        ParaxialSurface(focal_length=f)
    with pytest.raises(ValueError, match=r"focal_length .* got 5e-324"):
        ParaxialSurface(focal_length=np.array([100.0, 5e-324]))
    assert float(jl.efl(jl.Lens((ParaxialSurface(focal_length=1e-6),), jnp.array([1.0]),
                                (jl.Air(),), epd=1e-7))) == pytest.approx(1e-6, rel=1e-12)


@pytest.mark.parametrize("make", [lambda c: jl.Standard(c=c), lambda c: Toroidal(c=0.01, cx=c),
                                  lambda c: jl.Biconic(c=0.01, cx=c)])
def test_curvature_bound(make):
    for c in (1e300, -1e300, 1e10):
        with pytest.raises(ValueError, match=r"c(x)? must be finite numbers in \[-1e\+09, "
                                             r"1e\+09\] 1/mm \(\|R\| >= 1e-09 mm\)"):
            make(c)
    make(1e9)
    make(-1e9)


@pytest.mark.parametrize("r", [5e-324, -1e-320, 1e-300, 1e-10])
def test_json_radius_floor(r, tmp_path):
    d = json.loads(COOKE.read_text())
    for extra in ({}, {"curvature": 1.0 / r if abs(r) > 1e-300 else 1e300}):
        c = copy.deepcopy(d)
        c["surfaces"][1].update(radius=r, **extra)
        p = tmp_path / "c.json"
        p.write_text(json.dumps(c))
        with pytest.raises(ValueError, match=r"c\.json: surface 1: radius must be finite and at "
                                             r"least 1e-09 mm in size"):
            jl.load(p)
    c = copy.deepcopy(d)
    c["surfaces"][1]["radius"] = 1e300  # nearly flat: accepted
    p.write_text(json.dumps(c))
    assert float(jl.load(p).surfaces[0].c) == 1e-300


@pytest.mark.parametrize(("old", "new", "line"), [
    ("  PARM 1 60\n", "  PARM 1 {v}\n", 34), ("  PARM 1 25\n", "  PARM 1 {v}\n", 18)])
@pytest.mark.parametrize("v", ["1e-300", "5e-324", "-1e-320", "1e-12"])
def test_zmx_radius_and_focal_length_floor(old, new, line, v, tmp_path):
    p = tmp_path / "t.zmx"
    p.write_text(ZMX.format(unit="MM", opd="PARM 2 2").replace(old, new.format(v=v)))
    with pytest.raises(ValueError, match=rf"t\.zmx:{line}: .*\(PARM 1\) must be finite and at "
                                         rf"least 1e-09 mm in size.*'PARM 1 {v}'"):
        jl.load(p)


def test_zmx_units_scale_the_floor(tmp_path):
    p = tmp_path / "t.zmx"
    p.write_text(ZMX.format(unit="CM", opd="PARM 2 2").replace("  PARM 1 60\n",
                                                               "  PARM 1 5e-11\n"))
    with pytest.raises(ValueError, match=r"got 5e-10 mm: 'PARM 1 5e-11'"):
        jl.load(p)
    p.write_text(ZMX.format(unit="MM", opd="PARM 2 2").replace("  PARM 1 25\n", "  PARM 1 0\n"))
    assert float(jl.load(p).surfaces[0].cx) == 0.0  # PARM 1 0: a cylinder, as in Zemax


def test_object_cone_of_a_lens_without_one():
    cooke = jl.load(COOKE)
    with pytest.raises(ValueError, match=r"^object_slope: the lens is not object-space "
                                         r"telecentric \(Lens\.object_na is None\)"):
        PX.object_slope(cooke)
    with pytest.raises(ValueError, match=r"^in_cone: the lens is not object-space telecentric"):
        telecentric.in_cone(cooke, jnp.array([0.0, 0.0, 1.0]))
    with pytest.raises(TypeError, match=r"object_slope: lens must be a jaxlens\.Lens, got str"):
        PX.object_slope("cooke")


@functools.cache
def _cooke():
    return jl.load(COOKE)


@pytest.mark.parametrize("name", ["XYPolynomial", "ZernikeSag", "QTypeAsphere", "Binary2"])
def test_norm_radius_floor(name):
    """1e-300 mm gave a NaN sag and EFL (every ray lost) without a word."""
    make = {
        "XYPolynomial": lambda r: jl.XYPolynomial(c=0.02, coeffs=jnp.array([0.0, 0.0, 1e-3]),
                                                  norm_radius=r, semi_diameter=5.0),
        "ZernikeSag": lambda r: jl.ZernikeSag(c=0.02, zernike=jnp.array([0.0, 0.0, 0.0, 1e-3]),
                                              norm_radius=r, semi_diameter=5.0),
        "QTypeAsphere": lambda r: jl.QTypeAsphere(c=0.02, coeffs=jnp.array([1e-3]),
                                                  norm_radius=r, semi_diameter=5.0),
        "Binary2": lambda r: jl.Binary2(c=0.02, phase_coeffs=jnp.array([-10.0]), norm_radius=r,
                                        semi_diameter=5.0),
    }[name]
    for r in (1e-300, 5e-324, 1e-10):
        with pytest.raises(ValueError, match=rf"^{name}: norm_radius must be finite and at "
                                             rf"least 1e-09 mm in size .*got {r!r} mm"):
            make(r)
    make(1e-9)
    # 0 and NaN keep their message (the range (0, inf))
    with pytest.raises(ValueError, match=r"norm_radius must be finite numbers in \(0, inf\)"):
        make(0.0)


def test_epd_and_pixel_floor():
    """A Lens's epd of 5e-324 mm gave F/# = inf (a lens file's EPD was floored at 1e-9 mm, the
    Lens's own was not); a Sensor of 5e-324 mm pixels rendered."""
    c = _cooke()
    for e in (5e-324, 1e-300, 1e-10):
        with pytest.raises(ValueError, match=r"^Lens: epd \(entrance pupil diameter\) must be "
                                             r"finite and at least 1e-09 mm"):
            jl.Lens(c.surfaces, c.thickness, c.materials, epd=e)
    for ps in (5e-324, 1e-300):
        with pytest.raises(ValueError, match=r"^Sensor: pixel_size must be finite and at least "
                                             r"1e-09 mm"):
            jl.Sensor(resolution=(32, 32), pixel_size=ps)
    lens = jl.Lens(c.surfaces, c.thickness, c.materials, epd=1e-9)
    assert float(jl.paraxial_data(lens).fnum) == pytest.approx(float(jl.efl(c)) / 1e-9,
                                                              rel=1e-12)


@pytest.mark.parametrize("ext", ["zmx", "json", "agf"])
def test_readers_refuse_fifos_and_devices(ext, tmp_path):
    """A FIFO under a lens file's name blocked open() for ever; /dev/zero read until the
    memory ran out. Refused before anything is opened."""
    import os

    from jaxlens.io import lensfile, zmx

    fifo, zero = tmp_path / f"fifo.{ext}", tmp_path / f"zero.{ext}"
    os.mkfifo(fifo)
    zero.symlink_to("/dev/zero")
    readers = {"zmx": [("load", jl.load), ("load_zmx", zmx.load_zmx),
                       ("configurations", zmx.configurations)],
               "json": [("load", jl.load), ("load_json", lensfile.load_json)],
               "agf": [("load_agf", jl.load_agf)]}[ext]
    for name, read in readers:
        for p in (fifo, zero):
            with pytest.raises(ValueError, match=rf"^{name}: '.*{p.name}' is not a regular file "
                                                 r"\(a FIFO, socket or device"):
                read(p)


def test_yield_fraction_refuses_a_negative_rms():
    from jaxlens.analysis import tolerance as TL

    with pytest.raises(ValueError, match=r"yield_fraction: rms_um must be RMS radii >= 0 µm, "
                                         r"got -1 µm"):
        TL.yield_fraction([-1.0, 2.0], 1.0)
    assert TL.yield_fraction([-0.0, 2.0], 1.0) == 0.5
    assert TL.yield_fraction([np.nan, 2.0], 3.0) == 0.5  # NaN: a failed trial


def test_writers_name_themselves(tmp_path):
    """A lens past its glass's resonance was refused by ``Sellmeier.index`` (a str lens: an
    AttributeError) in the writers below ``save``."""
    from jaxlens.io import lensfile, zmx

    lens = resonant_lens()
    calls = {"save_zmx": lambda: zmx.save_zmx(lens, tmp_path / "a.zmx"),
             "save_json": lambda: lensfile.save_json(lens, tmp_path / "a.json"),
             "dumps": lambda: lensfile.dumps(lens),
             "lens_to_dict": lambda: lensfile.lens_to_dict(lens)}
    for name, call in calls.items():
        with pytest.raises(ValueError, match=rf"^{name}: Lens: wavelengths 3 µm is outside "
                                             r"0\.15–2 µm.*nothing written"):
            call()
    with pytest.raises(ValueError, match=r"^dumps: Lens: wavelengths 3 µm"):
        zmx.dumps(lens)
    with pytest.raises(TypeError, match=r"^save_zmx: lens must be a jaxlens Lens, got str"):
        zmx.save_zmx("lens", tmp_path / "b.zmx")
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize("name", ["marginal_ray", "system_matrix", "entrance_pupil_z",
                                  "entrance_pupil_magnification", "signed_indices"])
def test_paraxial_entry_points_check_an_edited_lens(name):
    """A NaN thickness set with eqx.tree_at (which skips Lens's checks) gave NaN here, while
    efl and paraxial_data refused it."""
    import equinox as eqx

    c = _cooke()
    call = {"signed_indices": lambda L: PX.signed_indices(L, 0.55)}.get(
        name, lambda L: getattr(PX, name)(L))
    for bad in (eqx.tree_at(lambda m: m.thickness, c, c.thickness.at[2].set(jnp.nan)),
                eqx.tree_at(lambda m: m.surfaces[2].k, c, jnp.asarray(jnp.inf))):
        with pytest.raises(ValueError, match=rf"^{name}: the lens fails its own checks"):
            call(bad)
    assert np.all(np.isfinite(np.asarray(jax.tree.leaves(call(c))[0])))
