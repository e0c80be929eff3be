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
    assert checks.material_range(raw) == (0.15, pytest.approx(math.sqrt(c[2])))
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
    assert 2.9 < float(raw.index(11.0)) < 3.1  # what the formula gives there
    with pytest.raises(ValueError, match=r"system_matrix: wavelength 11 µm is outside "
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
    with pytest.raises(ValueError, match=r"outside 0\.301516–1\.13475 µm, the range of SILICON "
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
