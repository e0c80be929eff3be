"""Round 44b: the bad-input classes round 43b left (``tools/audit44b_probe.py``).

1. Paraxial quantities that are mathematically infinite came out as huge finite numbers
   (rounding left a denominator of 1e-17 instead of 0): the magnification of an object in
   the front focal plane (3.7e15), an afocal lens's EFL, BFL and F/# (-5.8e17 mm), an image
   or a pupil at infinity. Now a denominator within its rounding bound is zero
   (``paraxial._over``): the answer is inf. Checked against closed forms (thin lenses).
2. ``DesignSpec`` and the command lines took any positive F/#, sensor, track, element and
   pixel count (``--fnum 1e300``), and edof any positive photon count (``1e-300``), any
   learning rate and loss weight: now physical ranges, named with their unit.
3. ``write_psf_stack`` wrote negative "PSF" values.
4. ``python -m benchmarks.reevaluate`` reported a bad folder as "optiland is not installed".
5. The reports' cell helpers formatted a str as a number (``json_number("1.5")``) or failed
   in Python's words.
"""

import dataclasses
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import report_cells as RC
from jaxlens.design.spec import DesignSpec
from jaxlens.optics import paraxial as PX
from jaxlens.optics.paraxial_surface import ParaxialSurface

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"


def thin(f, s):
    """A thin lens of focal length f (mm) in air, its object s mm before it."""
    return jl.Lens((ParaxialSurface(focal_length=f),), jnp.array([100.0]), (jl.Air(),),
                   epd=10.0, object_distance=s)


def pair(f1, f2, gap, stop=0):
    """Two thin lenses ``gap`` mm apart (afocal for gap = f1 + f2)."""
    return jl.Lens((ParaxialSurface(focal_length=f1), ParaxialSurface(focal_length=f2)),
                   jnp.array([gap, 50.0]), (jl.Air(), jl.Air()), epd=10.0, stop=stop)


# ---------------------------------------------------------------- 1. infinite paraxial values


@pytest.mark.parametrize("s", [100.0 * (1 + 1e-9), 100.0 * (1 - 1e-9), 200.0, 50.0])
def test_thin_lens_magnification_near_the_focal_plane_is_the_closed_form(s):
    """m = f/(f − s) (s the object distance, f = 100 mm): ±1e9 at f(1 ± 1e-9) are real
    values, kept (the rule only zeroes a denominator without a significant digit)."""
    m = float(PX.magnification(thin(100.0, s)))
    assert m == pytest.approx(100.0 / (100.0 - s), rel=1e-6)


def test_an_object_in_the_front_focal_plane_has_an_infinite_magnification():
    """At f exactly (thin lens), and at the Cooke triplet's front focal plane found by a root
    finder (before: 3.7e15, rounding's answer)."""
    from scipy.optimize import brentq

    d = PX.paraxial_data(thin(100.0, 100.0))
    assert float(PX.magnification(thin(100.0, 100.0))) == np.inf
    assert float(d.working_fnum) == np.inf and np.isinf(float(d.paraxial_image_z))
    cooke = jl.load(COOKE)

    def at(z):
        return dataclasses.replace(cooke, object_distance=jnp.asarray(z, float))

    z = brentq(lambda z: float(PX.marginal_ray(at(z))[1][-1]), 1.0, 500.0)
    assert float(PX.magnification(at(z))) == np.inf
    assert float(PX.paraxial_data(at(z)).working_fnum) == np.inf
    # 0.1 mm away the image is finite again: m = -f/Δ to first order (f = EFL).
    f = float(PX.efl(cooke))
    assert float(PX.magnification(at(z + 0.1))) == pytest.approx(-f / 0.1, rel=0.01)


@pytest.mark.parametrize("f1, f2", [(100.0, 30.0), (0.1 + 0.2, 0.3), (100.0, 50.0)])
def test_an_afocal_pair_has_infinite_focal_lengths_and_fnumbers(f1, f2):
    """Thin lenses f1 + f2 apart (a Keplerian telescope): power 0, so EFL, BFL, F/#, the
    working F/# and the paraxial image are at infinity (before: -5.8e17 mm for 100 + 30)."""
    lens = pair(f1, f2, f1 + f2)
    d = PX.paraxial_data(lens)
    assert float(PX.efl(lens)) == np.inf and float(d.efl) == np.inf
    assert float(d.front_focal_length) == np.inf and float(d.fnum) == np.inf
    assert np.isinf(float(PX.bfl(lens))) and np.isinf(float(d.bfl))
    assert float(d.working_fnum) == np.inf and np.isinf(float(d.paraxial_image_z))
    assert float(jax.jit(PX.efl)(lens)) == np.inf  # the same under jit
    # The angular magnification of the pair is still -f1/f2, its finite-object one -f2/f1.
    near = dataclasses.replace(lens, object_distance=jnp.asarray(1000.0))
    assert float(PX.magnification(near)) == pytest.approx(-f2 / f1, rel=1e-9)


def test_a_focal_pair_keeps_its_closed_form_efl():
    """1/f = 1/f1 + 1/f2 − d/(f1 f2); the afocal rule leaves a small real power alone."""
    for gap in (129.0, 130.0 + 1e-6):
        f = 1.0 / (1 / 100.0 + 1 / 30.0 - gap / 3000.0)
        assert float(PX.efl(pair(100.0, 30.0, gap))) == pytest.approx(f, rel=1e-6)


def test_pupils_at_infinity_are_infinite():
    """A stop in a thin lens's front focal plane puts the exit pupil at infinity, one in its
    rear focal plane the entrance pupil (before: 1.6e15 mm for f = 0.1·3, t = 0.3)."""
    for f, t in ((100.0, 100.0), (0.1 * 3, 0.3)):
        tele = jl.Lens((jl.Stop(), ParaxialSurface(focal_length=f)), jnp.array([t, 2 * t]),
                       (jl.Air(), jl.Air()), epd=0.1)
        assert np.isinf(float(PX.paraxial_data(tele).exit_pupil_z))
        front = jl.Lens((ParaxialSurface(focal_length=f), jl.Stop(semi_diameter=0.05)),
                        jnp.array([t, 2 * t]), (jl.Air(), jl.Air()), epd=0.1, stop=1)
        assert np.isinf(float(PX.entrance_pupil_z(front)))
    # Off the focal plane by 1e-9 of f: z = t·f/(f − t), a real (large) value.
    t = 100.0 * (1 + 1e-9)
    front = jl.Lens((ParaxialSurface(focal_length=100.0), jl.Stop(semi_diameter=0.05)),
                    jnp.array([t, 2 * t]), (jl.Air(), jl.Air()), epd=0.1, stop=1)
    assert float(PX.entrance_pupil_z(front)) == pytest.approx(t * 100.0 / (100.0 - t), rel=1e-6)


# ---------------------------------------------------------------- 2. ranges of the design numbers


@pytest.mark.parametrize("kwargs, match", [
    (dict(fnum=1e300), r"fnum must be a finite number in \[0\.5, 64\] \(F-number"),
    (dict(fnum=65.0), r"fnum must be a finite number in \[0\.5, 64\]"),
    (dict(fnum_start=1e300), r"fnum_start must be a finite number in \[2, 64\]"),
    (dict(sensor_diagonal=1e300), r"sensor_diagonal must be a finite number in \[0\.1, 1000\] mm"),
    (dict(sensor_diagonal=1e-300), r"sensor_diagonal must be a finite number in \[0\.1, 1000\] mm"),
    (dict(total_track=1e300), r"total_track must be a finite number in \(0, 10000\] mm"),
    (dict(sensor_pixels=10**6), r"sensor_pixels must be a whole number in \[1, 8192\] pixels"),
    (dict(n_elements=31, materials=("E48R",) * 31),
     r"n_elements must be a whole number in \[1, 30\] lens elements"),
])
def test_design_spec_numbers_have_physical_ranges(kwargs, match):
    with pytest.raises(ValueError, match=r"DesignSpec: " + match):
        DesignSpec(**kwargs)


@pytest.mark.parametrize("argv, match", [
    (["--fnum", "1e300"], r"--fnum must be a finite number in \[0\.5, 64\]"),
    (["--fnum-start", "1e300"], r"--fnum-start must be a finite number in \[2, 64\]"),
    (["--sensor-diagonal", "1e300"], r"--sensor-diagonal must be .* \[0\.1, 1000\] mm"),
    (["--track", "1e300"], r"--track must be a finite number in \(0, 10000\] mm"),
    (["--elements", "31"], r"--elements must be a whole number in \[1, 30\] lens elements"),
])
def test_classical_cli_refuses_numbers_out_of_range(argv, match):
    from jaxlens.experiments import classical

    with pytest.raises(ValueError, match=match):
        classical.check_args(classical.build_parser().parse_args(argv))


@pytest.mark.parametrize("argv, match", [
    (["--photons", "1e-300"], r"--photons must be a finite number in \[1, 1e\+12\] "
                              r"photo-electrons"),
    (["--photons", "0.5"], r"--photons must be"),
    (["--photons", "1e300"], r"--photons must be"),
    (["--lr-net", "1e300"], r"--lr-net must be a finite number in \(0, 1\] \(Adam"),
    (["--lr-lens", "2"], r"--lr-lens must be a finite number in \(0, 1\]"),
    (["--w-sim", "1e300"], r"--w-sim must be a finite number in \[0, 1000\]"),
    (["--w-raw", "1e4"], r"--w-raw must be a finite number in \[0, 1000\]"),
])
def test_edof_cli_refuses_numbers_out_of_range(tmp_path, argv, match):
    from jaxlens.experiments.edof import cli

    with pytest.raises(ValueError, match=match):
        cli.check_args(cli.build_parser().parse_args(["--out", str(tmp_path / "e"), *argv]))


def test_edof_config_takes_the_photon_range_too():
    from jaxlens.experiments.edof.train import Config

    with pytest.raises(ValueError, match=r"photons must be a finite number in \[1, 1e\+12\]"):
        Config(photons=1e-300)
    Config(photons=1.0)
    Config(photons=1e12)


# ---------------------------------------------------------------- 3. negative PSFs


def test_write_psf_stack_refuses_negative_values_beyond_rounding(tmp_path):
    from jaxlens.io import images

    with pytest.raises(ValueError, match=r"write_psf_stack: a PSF is an intensity, "
                                         r"non-negative; psfs\[0\] has -1"):
        images.write_psf_stack(tmp_path / "a.exr", -np.ones((2, 5, 5)))
    psf = np.zeros((2, 3, 5, 5))
    psf[:, :, 2, 2] = 1.0
    psf[1, 2, 0, 0] = -1e-4  # 1e-4 of its peak: ringing, not rounding
    with pytest.raises(ValueError, match=r"psfs\[1\] channel 2 has -0\.0001 at pixel \(0, 0\)"):
        images.write_psf_stack(tmp_path / "b.exr", psf)
    psf[1, 2, 0, 0] = -1e-7  # float rounding: written as 0
    images.write_psf_stack(tmp_path / "c.exr", psf)
    back, _ = images.read_psf_stack(tmp_path / "c.exr")
    assert back.min() == 0.0 and back[1, 2, 2, 2] == 1.0


# ---------------------------------------------------------------- 4. reevaluate's arguments first


def test_reevaluate_checks_its_arguments_before_optiland(monkeypatch, capsys, tmp_path):
    from benchmarks import optiland_ref, reevaluate

    monkeypatch.setattr(optiland_ref, "available", lambda: False)
    for folder, said in ((tmp_path / "nope", "is not a folder"), (tmp_path, "holds no .zmx")):
        with pytest.raises(SystemExit) as e:
            reevaluate.main([str(folder)])
        assert e.value.code == 2 and said in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "x.zmx").write_text("SURF 0\n  CURV abc\n")
    with pytest.raises(SystemExit):
        reevaluate.main([str(broken)])
    err = capsys.readouterr().err
    assert "x.zmx" in err and "optiland" not in err


# ---------------------------------------------------------------- 5. the reports' cell helpers


@pytest.mark.parametrize("call, match", [
    (lambda: RC.json_number("1.5"), r"json_number: x must be one real number, got str"),
    (lambda: RC.json_number(True), r"json_number: x must be one real number, got bool"),
    (lambda: RC.cell("abc"), r"cell: v must be one real number, got str"),
    (lambda: RC.cell(1.0, width=2.5), r"cell: width must be a whole number >= 1"),
    (lambda: RC.cell(1.0, prec=-1), r"cell: prec must be a whole number >= 0"),
    (lambda: RC.seidel_lines(5, "x"), r"seidel_lines: sd must be the report's data \(a dict\)"),
    (lambda: RC.wavefront_lines([], 5), r"wavefront_lines: reference must be a str"),
    (lambda: RC.aiming_line(None), r"aiming_line: data must be the report's data"),
])
def test_report_cells_refuse_foreign_kinds(call, match):
    with pytest.raises(TypeError, match=match):
        call()


def test_report_cells_take_their_own_data():
    from jaxlens.experiments.ablation_table import fmt

    assert RC.json_number(np.float32(2.5)) == 2.5 and RC.json_number(jnp.asarray(3.0)) == 3.0
    assert RC.json_number(float("nan")) is None
    assert RC.cell(None).strip() == "failed" and RC.cell(np.inf).strip() == "Infinity"
    assert "paraxial" in RC.aiming_line({})  # documented: a report before the key existed
    assert fmt(None) == "–" and fmt(1.234) == "1.23" and fmt(float("nan")) == "nan"
    with pytest.raises(TypeError, match=r"fmt: x must be one real number, got str 'a'"):
        fmt("a")
