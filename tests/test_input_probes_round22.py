"""Bad input, round 22 (tools/audit22_probe.py): one test per class of gap fixed. Each names
what the bad value did before; all are refusals before any tracing or long work (or a check
against an analytic value), so the file is fast."""

import dataclasses
import math
import os
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics import checks
from jaxlens.optics import materials as M

COOKE = jl.zoo.cooke_triplet()
DESIGN = os.path.join(os.path.dirname(__file__), "..", "experiments", "classical", "designs",
                      "seed_13.zmx")


def one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


# ------------------------------------------------------- tolerance CLIs: --threshold, --out
@pytest.mark.parametrize(("value", "text"), [
    ("1e300", r"--threshold must be a finite number in \[0\.01, 1000\] µm \(the mean RMS spot "
              r"radius after refocusing a trial must meet; the designs have a few µm\), got "
              r"1e\+300$"),
    ("1e6", r"--threshold must be a finite number in \[0\.01, 1000\] µm .*got 1e\+06$"),
    ("0.006", r"got 0\.006 \(was it given in mm\? 0\.006 mm is 6 µm\)$"),
    ("nan", r"--threshold must be a finite number in \[0\.01, 1000\] µm .*got nan$"),
    ("0", r"--threshold must be a finite number in \[0\.01, 1000\] µm .*got 0$"),
])
def test_tolerance_cli_bounds_threshold(value, text, tmp_path, capsys):
    """Before: --threshold had no upper bound (1e300 µm, or 1e6, a metre of RMS, started the
    sensitivity pass and Monte-Carlo, and every trial passed: a yield of 1 that says nothing),
    and 0.006 (mm for µm) gave a yield of 0."""
    from jaxlens.experiments import tolerance

    assert tolerance.main([DESIGN, "--out", str(tmp_path / "o"), "--threshold", value]) == 2
    assert re.search(text, one_line(capsys))
    assert not (tmp_path / "o").exists()


def test_classical_cli_bounds_tolerance_threshold(tmp_path, capsys):
    """Before: --tolerance-threshold was only > 0: 1e300 reached the tolerance analysis after
    the designs."""
    from jaxlens.experiments import classical

    assert classical.main(["--tolerance-threshold", "1e300", "--out", str(tmp_path / "c"),
                           "--quiet"]) == 2
    assert re.search(r"--tolerance-threshold must be a finite number in \[0\.01, 1000\] µm .*"
                     r"got 1e\+300$", one_line(capsys))
    assert not (tmp_path / "c").exists()


def test_tolerance_threshold_range_keeps_the_default():
    from jaxlens.experiments import tolerance

    lo, hi = tolerance.THRESHOLD_RANGE_UM
    assert lo <= tolerance.DEFAULT_THRESHOLD_UM <= hi
    assert tolerance.check_threshold(lo, "x") is None and tolerance.check_threshold(hi, "x") is None
    assert isinstance(tolerance.check_threshold(math.nextafter(hi, math.inf), "x"), ValueError)


def test_tolerance_cli_checks_out_and_design_before_the_analysis(tmp_path, capsys):
    """Before: --out '' and --out under a file failed in os.makedirs after the whole analysis
    (minutes), with a traceback; a folder as the design file was 'not found'."""
    from jaxlens.experiments import tolerance

    assert tolerance.main([DESIGN, "--out", ""]) == 2
    assert one_line(capsys).endswith("error: --out needs a folder name, got an empty one")
    f = tmp_path / "afile"
    f.write_text("")
    assert tolerance.main([DESIGN, "--out", str(f / "sub")]) == 2
    assert re.search(r"--out .*sub: cannot create or write there \(.*afile is not a writable "
                     r"folder\)$", one_line(capsys))
    assert tolerance.main([str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert re.search(r"design file '.*' is a folder \(a \.zmx or jaxlens \.json file\)$",
                     one_line(capsys))


# ------------------------------------------------------- formulas past their resonances
BK7 = jl.get_material("N-BK7")


def with_glass(glass, wavelengths):
    mats = [glass if isinstance(m, M.Tabulated) else m for m in COOKE.materials]
    return dataclasses.replace(COOKE, materials=mats, wavelengths=wavelengths, primary=0)


def test_pole_window_of_the_formulas():
    """The poles are where each formula's denominator vanishes; the window is the span
    between them that holds the d line."""
    raw = BK7.model  # Sellmeier 1: poles at √C_i
    c = np.asarray(raw.C)
    np.testing.assert_allclose(raw.poles(), np.sqrt(c), rtol=1e-15)
    lo, hi = raw.pole_window()
    assert lo == pytest.approx(math.sqrt(c[1])) and hi == pytest.approx(math.sqrt(c[2]))
    # Less twice the checks' relative slack (1e-6): a wavelength 1e-7 past a pole passed.
    assert checks.material_range(raw) == (0.15, pytest.approx(math.sqrt(c[2]) * (1 - 2e-6),
                                                              rel=1e-12))
    assert BK7.pole_window() is None  # a catalog glass states its range
    assert checks.material_range(BK7) == (0.3, 2.5)
    assert M.Herzberger(np.array([1.5, 0.005, 0, 0, 0, 0])).pole_window() == (
        pytest.approx(math.sqrt(0.028)), math.inf)
    assert M.Herzberger(np.array([1.5, 0, 0, 0, 0, 0])).pole_window() is None  # L unused
    assert M.Sellmeier2(np.array([0.0, 1.0, 0.1, 0.0, 5.0])).pole_window() == (0.1, math.inf)
    assert M.Sellmeier4(np.array([1.0, 1.0, 0.01, 1.0, 25.0])).pole_window() == (
        pytest.approx(0.1), pytest.approx(5.0))
    assert M.Handbook2(np.array([2.0, 0.5, 0.04, 0.0])).pole_window() == (
        pytest.approx(0.2), math.inf)
    for no_poles in (M.ModelGlass(1.5, 60.0), M.Schott(np.array([2.2, 0, 0.01, 0, 0, 0])),
                     M.Conrady(np.array([1.5, 0.01, 0.0])), M.Air()):
        assert no_poles.pole_window() is None
    # An infrared formula with a resonance above the d line (no valid index there): no window.
    ir = M.Sellmeier(np.array([10.0]), np.array([0.6**2]))
    assert not np.isfinite(float(ir.index(0.5876)))
    assert ir.pole_window() is None


def test_lens_refuses_a_wavelength_past_a_formula_resonance():
    """Before: a lens of N-BK7's Sellmeier (built from its coefficients, without the catalog's
    0.3-2.5 µm range) traced at 11 µm, past the formula's 10.18 µm resonance, where it gives
    n = 3.0, a finite and plausible index that is not the glass's."""
    raw = BK7.model
    assert 2.9 < float(raw.extrapolated_index(11.0)) < 3.1  # what the formula gives there
    with pytest.raises(ValueError, match=r"efl: the lens's primary wavelength 11 µm is outside "
                       r"0\.15–10\.1765 µm, .*the range of N-BK7 after surface 1 between the "
                       r"resonances \(poles\) of its Sellmeier formula at 0\.1415 µm and 10\.18 "
                       r"µm, beyond which the formula gives no index of the material"):
        jl.efl(with_glass(raw, (11.0,)))
    # Inside the window the formula is the catalog glass's.
    assert jl.efl(with_glass(raw, (0.5876,))) == pytest.approx(
        float(jl.efl(with_glass(BK7, (0.5876,)))), rel=1e-12)


def test_a_stated_range_overrides_the_pole_window():
    """The shipped SILICON's catalog range (1.36-11 µm) lies beyond its formula's resonance
    at 1.13 µm: the catalog glass is used at 4 µm; its bare formula is refused there, and
    wrapping it with a stated range is the way to use it."""
    si = jl.get_material("SILICON")
    assert np.isfinite(float(jl.efl(with_glass(si, (4.0,)))))
    with pytest.raises(ValueError, match=r"outside 0\.301517–1\.13475 µm, the range of SILICON "
                       r"after surface 1 between the resonances"):
        jl.efl(with_glass(si.model, (4.0,)))
    wrapped = jl.CatalogMaterial(model=si.model, name="Si", wavelength_range=(1.36, 11.0))
    assert float(jl.efl(with_glass(wrapped, (4.0,)))) == pytest.approx(
        float(jl.efl(with_glass(si, (4.0,)))), rel=1e-12)


def test_pole_window_skips_traced_materials():
    """Inside jit a material's coefficients are not known: no window, no check, same program."""
    raw = BK7.model

    def f(b):
        m = M.Sellmeier(b, raw.C)
        assert m.poles() is None and m.pole_window() is None
        assert checks.material_range(m) == checks.GENERIC_RANGE_UM
        return m.index(jnp.asarray(0.5876))

    assert float(jax.jit(f)(raw.B)) == pytest.approx(float(raw.index(0.5876)), rel=1e-14)


def test_abbe_number_refuses_a_nan_index():
    """Before: NaN, for a formula with a resonance between the F and C lines."""
    m = M.Sellmeier(np.array([1.0]), np.array([0.25]), name="x")  # pole at 0.5 µm
    with pytest.raises(ValueError, match=r"abbe_number: Sellmeier 'x' gives no finite index at "
                       r"the d, F and C lines .* so it has no Abbe number"):
        M.abbe_number(m)
    assert float(M.abbe_number(M.ModelGlass(1.5, 60.0))) == pytest.approx(60.0, rel=1e-12)


# ------------------------------------------------------- plot, design, nets, helpers
def test_plot_bounds_and_checks_its_inputs(tmp_path):
    """Before: plot_layout(n_rays=10**9) asked for 8 GB of pupil points; plot_image clipped a
    uint8 image to white and drew NaN as nothing; save(fig, '') wrote nothing and returned ''."""
    from jaxlens import plot

    with pytest.raises(ValueError, match=r"plot_layout: n_rays must be at most 1024 rays per "
                       r"fan \(plot\.MAX_LAYOUT_RAYS: .*\), got 1000000000$"):
        plot.plot_layout(COOKE, n_rays=10**9)
    with pytest.raises(ValueError, match=r"plot_image: img must be a float image, got an "
                       r"integer image of dtype uint8"):
        plot.plot_image(np.full((4, 4, 3), 200, np.uint8))
    with pytest.raises(ValueError, match=r"plot_image: img must be finite values, got nan"):
        plot.plot_image(np.full((4, 4, 3), np.nan))
    for shape in ((0, 0, 3), (4, 4, 4), (4,)):
        with pytest.raises(ValueError, match=r"img must be an \[H, W, 3\] or \[H, W\] image"):
            plot.plot_image(np.zeros(shape))
    fig = plot.plot_image(np.full((4, 4), 0.5))
    with pytest.raises(ValueError, match=r"save: path must be a file name .*got ''"):
        plot.save(fig, "")
    with pytest.raises(ValueError, match=r"save: path must be a file name"):
        plot.save(fig, tmp_path)
    with pytest.raises(TypeError, match=r"save: fig must be a matplotlib Figure, got NoneType"):
        plot.save(None, tmp_path / "x.png")
    assert os.path.getsize(plot.save(fig, tmp_path / "x.png")) > 0
    # An RMS map of lost fields: before, a blank map titled "mean nan µm, max nan µm".
    with pytest.raises(ValueError, match=r"plot_rms_map: rms_um has no finite value \(all 4 "
                       r"fields without an RMS"):
        plot.plot_rms_map(np.full((2, 2), np.nan), (4.0, 3.0))
    title = plot.plot_rms_map(np.array([np.nan, 1.0, 2.0, 3.0]), (4.0, 3.0)).axes[0].get_title()
    assert title == "RMS over 4 fields: mean 2.00 µm, max 3.00 µm; 1 fields without an RMS (blank)"


def test_design_stage_and_image_objective_check_their_counts():
    """Before: Stage(steps=10**12) was built (a run that never ends), and ImageObjective took
    spp=0 (renders of no rays: a zero image) or a NaN scene (a NaN loss at the first step)."""
    from jaxlens.design import DesignSpec, ImageObjective, RayLoss, Stage, parameterization
    from jaxlens.design.losses import Objective

    with pytest.raises(ValueError, match=r"Stage 'a': steps must be a whole number in "
                       r"\[0, 100000\] solver steps, got 1000000000000"):
        Stage("a", fov=60.0, fnum=2.0, steps=10**12)
    assert Stage("a", fov=60.0, fnum=2.0, steps=checks.MAX_STEPS).steps == checks.MAX_STEPS
    spec = DesignSpec()
    pm = parameterization(spec)
    ray = Objective(pm, RayLoss.make(3, 2, [0.5876], spec.sensor_size), jnp.ones((12, 2)))
    sensor = jl.Sensor((8, 8), 0.01)
    scene = jnp.ones((8, 8, 3))
    for kw, text in ((dict(spp=0), r"spp must be a whole number in \[1, 65536\] rays per pixel"),
                     (dict(weight=0.0), r"weight must be a finite number in \(0, inf\)"),
                     (dict(alpha=float("nan")), r"alpha must be a finite number in \[0, inf\)")):
        with pytest.raises(ValueError, match=rf"ImageObjective: {text}"):
            ImageObjective(ray, scene, sensor, **kw)
    with pytest.raises(ValueError, match=r"ImageObjective: scene must be finite values, got nan"):
        ImageObjective(ray, scene.at[0, 0, 0].set(jnp.nan), sensor)
    with pytest.raises(ValueError, match=r"scene must be an \[H, W, 3\] linear image, got shape "
                       r"\(8, 8\)"):
        ImageObjective(ray, jnp.ones((8, 8)), sensor)
    with pytest.raises(TypeError, match=r"ImageObjective: ray must be a ray Objective .*NoneType"):
        ImageObjective(None, scene, sensor)
    assert ImageObjective(ray, scene, sensor, spp=2).spp == 2


def test_nets_helpers_refuse_bad_input():
    """Before: simple_gate of 3 channels failed in numpy's split ("does not result in an equal
    division"), and num_parameters(None) was 0."""
    from jaxlens import nets

    with pytest.raises(ValueError, match=r"simple_gate: x must have an even, non-zero number of "
                       r"channels \(last axis\), got shape \(2, 3\)"):
        nets.simple_gate(jnp.ones((2, 3)))
    np.testing.assert_array_equal(nets.simple_gate(jnp.arange(4.0)), [0.0, 3.0])
    with pytest.raises(TypeError, match=r"num_parameters: model must be an equinox Module, got "
                       r"NoneType"):
        nets.num_parameters(None)


def test_tolerance_helpers_refuse_none_and_an_empty_folder():
    """Before: AttributeError ('NoneType' object has no attribute 'epd'), and os.makedirs('')
    (FileNotFoundError) after the analysis."""
    from jaxlens.design.spec import DesignSpec
    from jaxlens.experiments import tolerance

    with pytest.raises(TypeError, match=r"check_design: lens must be a "
                       r"jaxlens\.optics\.lens\.Lens, got NoneType"):
        tolerance.check_design(None, DesignSpec())
    with pytest.raises(TypeError, match=r"check_design: spec must be a .*DesignSpec, got "
                       r"NoneType"):
        tolerance.check_design(COOKE, None)
    with pytest.raises(ValueError, match=r"write_report: out must be a folder name, got ''"):
        tolerance.write_report({"a": 1}, "")


@pytest.mark.parametrize(("module", "argv", "kind"), [
    ("benchmarks.run", ["--out", "", "--smoke"], "folder"),
    ("benchmarks.render_speed", ["--out", ""], "file"),
])
def test_benchmark_clis_refuse_an_empty_out(module, argv, kind, capsys):
    """Before: pathlib.Path('') is '.', so `python -m benchmarks --out ''` wrote into the
    current folder."""
    import importlib

    with pytest.raises(SystemExit) as e:
        importlib.import_module(module).main(argv)
    assert e.value.code == 2
    assert re.search(rf"argument --out: needs a {kind}'s path, got an empty one$",
                     one_line(capsys))


@pytest.mark.parametrize("cap", ["1e-12", "0.1", "1e6"])
def test_render_memory_cap_outside_its_range_is_refused(cap):
    """--cap-gib 1e-12 was rounded to a 0-byte cap, which stops every worker at once."""
    from benchmarks import render_memory
    with pytest.raises(SystemExit) as e:
        render_memory.main(["--cap-gib", cap])
    assert e.value.code == 2
