"""Bad input, round 23 (tools/audit23_probe.py): one test per class of gap fixed. Each names
what the bad value did before; all are refusals before any tracing or long work (or a value
inside the accepted range, which must still pass), so the file is fast."""

import json
import math
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import check_corpus_tool

import jaxlens as jl
from jaxlens.design import DesignSpec
from jaxlens.design.mask import reweighting_mask
from jaxlens.optics import diffractive

COOKE = jl.zoo.cooke_triplet()


# ------------------------------------------------------------------ Grating: lines per mm
def test_grating_refuses_lines_per_mm():
    """Before: Grating(lines_per_um=600), a density in lines per mm, was built (a 1.7 nm
    period: every order but 0 evanescent, each ray lost without a word)."""
    with pytest.raises(ValueError, match=r"^Grating: lines_per_um must be at most 20 lines per "
                       r"µm \(a 50 nm period: beyond it every order but 0 is evanescent\), got "
                       r"600 \(was it given in lines per mm\? 600 lines/mm is 0\.6 lines/µm\)$"):
        jl.Grating(lines_per_um=600.0, semi_diameter=5.0)
    # The bound and real gratings (3600 lines/mm) pass; at the bound, |M|·λ·T = 2 at 0.1 µm.
    assert float(jl.Grating(lines_per_um=diffractive.MAX_LINES_PER_UM).lines_per_um) == 20.0
    assert float(jl.Grating(lines_per_um=3.6).lines_per_um) == 3.6
    with pytest.raises(ValueError, match="lines_per_um"):
        jl.Grating(lines_per_um=math.nextafter(diffractive.MAX_LINES_PER_UM, math.inf))


# ------------------------------------------------------------------ Tabulated: stated range
def test_tabulated_refuses_a_bad_stated_range():
    """Before: Tabulated(..., wavelength_range=(0.7, 0.4)) was built, and every wavelength
    was then "outside 0.7–0.4 µm"; a NaN end let every wavelength through."""
    w, n = np.array([0.45, 0.55, 0.65]), np.array([1.52, 1.51, 1.50])
    for rng in [(0.7, 0.4), (0.5, 0.5), (0.0, 0.7), (0.4, math.nan), (0.4, math.inf),
                ("a", "b")]:
        with pytest.raises(ValueError, match=r"Tabulated: wavelength_range must be "
                           r"\(shortest, longest\) wavelength in µm with 0 < shortest < "
                           r"longest, got "):
            jl.Tabulated(w, n, wavelength_range=rng)
    t = jl.Tabulated(w, n, wavelength_range=(0.4, 0.7))  # a good one is kept and used
    assert t.wavelength_range == (0.4, 0.7)
    assert float(t.index(0.55)) == pytest.approx(1.51, abs=1e-12)


# ------------------------------------------------------------------ files and folders
def test_load_agf_of_a_folder(tmp_path):
    """Before: IsADirectoryError from open(), a traceback without advice."""
    with pytest.raises(ValueError, match=rf"^{re.escape(str(tmp_path))} is a folder; give a "
                       r"Zemax \.agf glass catalog file$"):
        jl.load_agf(tmp_path)


def test_check_corpus_refuses_a_missing_folder_or_a_file(tmp_path, capsys):
    """Before: FileNotFoundError / NotADirectoryError from os.listdir, with a traceback."""
    tool = check_corpus_tool()
    f = tmp_path / "a.zmx"
    f.write_text("")
    for path, what in ((tmp_path / "missing", "missing"), (f, "a file")):
        with pytest.raises(SystemExit) as e:
            tool.main([str(path)])
        assert e.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert err.endswith(f"error: folder {str(path)!r} is {what}; give a folder of .zmx "
                            f"files")


# ------------------------------------------------------------------ design
def test_reweighting_mask_refuses_nan_rms():
    """Before: a NaN RMS made the mean NaN, and the mask 1 for every field (no field dropped,
    the NaN field weighted like the others)."""
    with pytest.raises(ValueError, match=r"reweighting_mask: rms must be finite numbers in "
                       r"\[0, inf\) \(RMS spot error per field\), got nan$"):
        reweighting_mask(jnp.array([1.0, np.nan, 2.0]))
    with pytest.raises(ValueError, match=r"rms must be finite numbers in \[0, inf\) .*got -1$"):
        reweighting_mask(jnp.array([1.0, -1.0, 2.0]))
    np.testing.assert_allclose(reweighting_mask(jnp.array([1.0, 2.0, 3.0])), [0.0, 1.0, 1.5])


def test_design_spec_names_radians_for_a_small_fov():
    """Before: fov=1.41 (80.8° in radians) was refused for its track/focal-length ratio with
    "are all lengths in mm?", which does not say that fov is in degrees."""
    with pytest.raises(ValueError, match=r"are all lengths in mm \(sensor_diagonal 7\.66 mm\) "
                       r"and fov in degrees \(1\.41 rad would be 80\.79°\)\?$"):
        DesignSpec(fov=1.41)
    # A track too long for a wide field is not a radian slip: no hint.
    with pytest.raises(ValueError, match=r"are all lengths in mm \(sensor_diagonal 7\.66 mm\)\?$"):
        DesignSpec(fov=80.8, total_track=5000.0)


def test_classical_cli_names_radians_for_a_small_fov(tmp_path, capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--fov", "1.41", "--out", str(tmp_path / "c"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.endswith("and --fov in degrees (1.41 rad would be 80.79°)?")
    assert not (tmp_path / "c").exists()


# ------------------------------------------------------------------ encircled energy
@pytest.mark.parametrize(("kw", "text"), [
    (dict(pupil_side=10**6), r"encircled_energy: pupil_side must be a whole number in "
                             r"\[2, 4096\] rays per side, got 1000000$"),
    (dict(subsamples=10**6), r"encircled_energy: subsamples must be a whole number in "
                             r"\[1, 64\] sub-samples per pixel side, got 1000000$"),
])
def test_encircled_energy_bounds_its_diffraction_sizes(kw, text):
    """Before: pupil_side=10**6 was refused by CoherentPSF as its "pupil" (an argument
    encircled_energy has not), and subsamples=10**6 had no bound: (63·10**6)² sub-pixel
    points."""
    with pytest.raises(ValueError, match=text):
        jl.analysis.encircled_energy(COOKE, 0.0, jnp.array([0.01]), method="diffraction",
                                     pixel_size=0.002, **kw)
    with pytest.raises(ValueError, match=text):  # whatever the method
        jl.analysis.encircled_energy(COOKE, 0.0, jnp.array([0.01]), **kw)


# ------------------------------------------------------------------ JSON, sampling, tolerancing
def test_json_field_type_lists_the_supported_ones(tmp_path):
    """Before: "field type 'angle_rad_y' is not supported (angles in deg)", which named no
    type that is."""
    path = tmp_path / "cooke.json"
    jl.save(COOKE, path)
    d = json.loads(path.read_text())
    d["fields"]["type"] = "angle_rad_y"
    path.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"field type 'angle_rad_y' is not supported; "
                       r"fields\.type must be one of angle_deg_y, angle_deg, angle, "
                       r"angle_deg_xy, object_height_mm_y, object_height_mm_xy \(angles in deg: "
                       r"convert radians or image heights to degrees; object heights in mm for "
                       r"an object-space telecentric lens\)$"):
        jl.load(path)


def test_vignetting_map_refuses_nonfinite_factors():
    """Before: a NaN factor mapped every pupil point to NaN (every ray of the field lost)."""
    pupil = jnp.array([[0.0, 1.0], [0.5, 0.0]])
    for bad in (jnp.array([0.0, np.nan, 0.0, 0.5, 0.0]), jnp.array([0.0, 0.0, 0.0, 0.0, np.inf])):
        with pytest.raises(ValueError, match=r"vignetting_map: factors (VDY|VAN) must be "
                           r"finite numbers \((pupil radii|deg)\), got (nan|inf)"):
            jl.sampling.vignetting_map(bad, pupil)
    out = jl.sampling.vignetting_map(jnp.array([0.0, 0.25, 0.0, 0.5, 0.0]), pupil)
    np.testing.assert_allclose(out, [[0.0, 0.75], [0.5, 0.25]], atol=1e-15)


def test_sample_perturbations_checks_its_key():
    """Before: a key of "x" (or an int) failed inside jax.random with a message that named no
    argument of sample_perturbations. The key is checked with the trial count, before the
    model is used (a ToleranceModel takes seconds to build, so none is built here)."""
    from jaxlens import tolerance as T

    for key in ("x", 0, None):
        with pytest.raises(ValueError, match=r"sample_perturbations: key must be one PRNG key "
                           r"\(jax\.random\.key\(0\) or jax\.random\.PRNGKey\(0\)\), got "):
            T.sample_perturbations(None, 4, key)


# ------------------------------------------------------------------ a formula past its poles
def test_a_formula_refuses_a_wavelength_past_its_poles():
    """Before: N-BK7's bare Sellmeier gave n = 3.05 at 11 µm and 2.42 at 12 µm, past its
    10.18 µm resonance (a lens refused such wavelengths, the formula's own index did not)."""
    from jaxlens.optics import materials as M

    raw = jl.get_material("N-BK7").model
    with pytest.raises(ValueError, match=r"^Sellmeier\.index: wavelength 11 µm is outside "
                       r"0\.15–10\.1765 µm, the range of N-BK7 between the resonances \(poles\) "
                       r"of its Sellmeier formula at 0\.1415 µm and 10\.18 µm, .*; "
                       r"extrapolated_index gives the formula's value anywhere$"):
        raw.index(np.array([0.5, 11.0]))
    with pytest.raises(ValueError, match=r"^Handbook2\.index: wavelength 0\.2 µm is outside "
                       r"0\.223607–30 µm"):
        M.Handbook2(np.array([2.3, 0.01, 0.05, 0.01])).index(0.2)
    # The formula itself, inside its window and through extrapolated_index, is unchanged.
    n = float(raw.index(0.5875618))
    assert n == pytest.approx(1.5168, abs=1e-4)
    assert 3.0 < float(raw.extrapolated_index(11.0)) < 3.1
    # A catalog range beyond the formula's pole still holds (SILICON: 1.36-11 µm, pole 1.13).
    si = jl.get_material("SILICON")
    assert float(si.index(5.0)) == pytest.approx(float(si.model.extrapolated_index(5.0)),
                                                 rel=1e-15)
    with pytest.raises(ValueError, match=r"Sellmeier\.index: wavelength 5 µm is outside"):
        si.model.index(5.0)
    # Traced wavelengths are not checked (jit/grad programs unchanged).
    assert 3.0 < float(jax.jit(raw.index)(jnp.asarray(11.0))) < 3.1
