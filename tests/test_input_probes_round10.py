"""Tenth round of bad-input probes: each case used to give a silent wrong answer (a NaN glass-map
point snapped to the first material, a string read as a field angle, one NaN pixel turning a
whole restored image to NaN, a repeated layer name dropping a PSF), an error from deep inside
the work, or a refusal of valid input (numpy integers); each is now refused before the work
starts, naming the argument, the value, the range and the unit, or accepted.
"""

from __future__ import annotations

import pathlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import tolerance
from jaxlens.analysis.report import report_data
from jaxlens.design.materials import CatalogRegion
from jaxlens.design.spec import DesignSpec
from jaxlens.imaging import psf as P
from jaxlens.imaging import tiled
from jaxlens.io import images
from jaxlens.nets import NAFNet

NAN = float("nan")


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


# ---------------------------------------------------------------- numpy integers are integers


def test_psf_models_take_numpy_integers(cooke):
    """GeometricPSF(pupil=np.int64(64)) was refused ("must be an int >= 2"), and
    order=np.int64(2) passed the check but reached the compiled PSF as a tracer
    (TracerBoolConversionError)."""
    m = P.GeometricPSF(pupil=np.int64(8), order=np.int64(2))
    assert type(m.pupil) is int and type(m.order) is int
    assert type(P.CoherentPSF(pupil=np.int64(16)).pupil) is int
    k = P.psf(cooke, 5.0, model=m, kernel_size=9)
    ref = P.psf(cooke, 5.0, model=P.GeometricPSF(pupil=8, order=2), kernel_size=9)
    np.testing.assert_array_equal(k, ref)
    for bad in (2.5, True, "64", 1):  # still refused
        with pytest.raises(ValueError, match=r"(psf|GeometricPSF): pupil \(rays per side\) "
                                             r"must be an int >= 2"):
            P.psf(cooke, 5.0, model=P.GeometricPSF(pupil=bad), kernel_size=9)


def test_tiles_take_numpy_integers():
    """tile_counts(…, np.int64(16)) was refused as not "a positive int"; True passed as 1."""
    assert tiled.tile_counts((64, 32), np.int64(16)) == (4, 2)
    assert tiled.tile_centers((64, 32), 0.01, np.int64(16)).shape == (4, 2, 2)
    with pytest.raises(ValueError, match=r"tile_counts: tile must be a positive int dividing "
                                         r"the frame 64x32 \(pixels\), got True"):
        tiled.tile_counts((64, 32), True)


# ---------------------------------------------------------------- design spec: lengths in one unit


@pytest.mark.parametrize("kwargs, match", [
    (dict(total_track=7000.0), r"total_track 7000 mm is 1.56e\+03 times the focal length 4.5 mm"),
    # Round 44b: 7660 (µm) is now refused by the diagonal's own range ([0.1, 1000] mm).
    (dict(sensor_diagonal=766.0), r"total_track 7 mm is 0.0156 times the focal length 450 mm"),
    (dict(efl=5550.0), r"total_track 7 mm is 0.00126 times the efl 5550 mm"),
    (dict(fov=1e-6, fov_start=1e-6),
     r"total_track 7 mm is 1.59e-08 times the focal length 4.389e\+08 mm"),
], ids=["track in um", "diagonal in um", "efl in um", "no field"])
def test_design_spec_refuses_lengths_in_different_units(kwargs, match):
    """A 7 m track for a 4.5 mm focal length (or a sensor diagonal in µm) built a spec, and
    the design ran for hours on it."""
    with pytest.raises(ValueError, match=r"DesignSpec: " + match + r".*it must be 0\.1 to 100 "
                                         r"times it \(mm\): are all lengths in mm"):
        DesignSpec(**kwargs)


def test_design_specs_in_use_still_build():
    DesignSpec()
    DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0, fov_start=30.0,
               fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=3)  # ratio 0.29
    DesignSpec(efl=5.55, total_track=7.6)


# ---------------------------------------------------------------- catalog region


def test_catalog_region_takes_one_name_and_refuses_points_off_the_glass_map():
    """CatalogRegion.of("SCHOTT") looked for catalogs 'S', 'C', 'H', ...; nearest(NaN, 30)
    was material 0 (argmin of NaN distances), nearest("1.5", 30) read the string as 1.5 and
    nearest(64.2, 1.5168) (nd and Vd swapped) snapped to a glass without a word."""
    region = CatalogRegion.of("PLASTICS")
    assert region.catalogs == ("PLASTICS",)
    assert region.names == CatalogRegion.of(["PLASTICS"]).names
    with pytest.raises(ValueError, match=r"CatalogRegion.nearest: nd must be finite numbers in "
                                         r"\(1, 4.5\] \(the d-line index.*got nan"):
        region.nearest(NAN, 30.0)
    with pytest.raises(ValueError, match=r"nd and vd swapped\?\), got 64.2"):
        region.nearest(64.2, 1.5168)
    with pytest.raises(ValueError, match=r"CatalogRegion.distances: vd must be finite numbers "
                                         r"in \(0, inf\) \(Abbe number\)"):
        region.distances([1.5, 1.6], [30.0, -1.0])
    with pytest.raises(TypeError, match=r"CatalogRegion.nearest: nd must be a real number"):
        region.nearest("1.5", 30.0)
    i = region.nearest(*region.points[2])
    assert region.names[int(i)] == region.names[2]


# ---------------------------------------------------------------- tolerancing


def test_tolerance_model_checks_wavelengths_and_pupil_types(cooke):
    """wavelengths="0.55" was read as 0.55 µm, [] was accepted (no wavelength to trace) and a
    pupil of strings failed with numpy's 'could not convert string to float'."""
    with pytest.raises(TypeError, match=r"ToleranceModel: wavelengths must be a real number or "
                                        r"an array of real numbers \(µm\), got str '0.55'"):
        tolerance.ToleranceModel(cooke, wavelengths="0.55")
    for bad in ([], [[0.5, 0.6]]):
        with pytest.raises(ValueError, match=r"ToleranceModel: wavelengths must be µm, one value "
                                             r"or \[W\] with W >= 1, got shape"):
            tolerance.ToleranceModel(cooke, wavelengths=bad)
    with pytest.raises(TypeError, match=r"ToleranceModel: pupil must be a real number"):
        tolerance.ToleranceModel(cooke, pupil="abc")


@pytest.mark.parametrize("kw, match", [
    (dict(threshold_um="5"), r"monte_carlo: threshold_um must be a finite number > 0 µm, got '5'"),
    (dict(threshold_um=True), r"threshold_um must be a finite number > 0 µm, got True"),
])
def test_monte_carlo_refuses_a_string_or_bool_threshold(cooke, kw, match):
    """float("5") read the string as 5 µm (and True as 1 µm), after which every trial ran."""
    model = tolerance.ToleranceModel(cooke, fields=[0.0], pupil=[[0.0, 0.0], [0.0, 0.5]])
    with pytest.raises(ValueError, match=match):
        tolerance.monte_carlo(model, trials=2, mtf_frequency=10.0, **kw)


def test_yield_fraction_of_no_trials_is_refused():
    """np.mean of nothing: NaN and a RuntimeWarning."""
    with pytest.raises(ValueError, match=r"yield_fraction: rms_um must hold at least one"):
        tolerance.yield_fraction([], 5.0)


# ---------------------------------------------------------------- report


@pytest.mark.parametrize("kw, error, match", [
    (dict(fields="5"), TypeError, r"report: --fields must be a real number or an array of real "
                                  r"numbers \(deg\), got str '5'"),
    (dict(fields=True), TypeError, r"--fields must be a real number .* got bool True"),
    (dict(wavelengths="550"), TypeError, r"--wavelengths must be a real number .* \(µm\), got "
                                         r"str '550'"),
    (dict(fields=[]), ValueError, r"report: --fields must be θy angles in degrees, one value or "
                                  r"\[F\], or \(θx, θy\) pairs \[F, 2\], with F >= 1, got shape "
                                  r"\(0,\)"),
    (dict(fields=[[0.0, 1.0, 2.0]]), ValueError, r"pairs \[F, 2\], with F >= 1, got shape "
                                                 r"\(1, 3\)"),
], ids=["str field", "bool field", "str wavelength", "no field", "F x 3 fields"])
def test_report_refuses_fields_and_wavelengths_that_are_not_numbers(cooke, kw, error, match):
    """"5" was read as 5° and True as 1°, "550" as 0.55 µm; no fields failed with
    ZeroDivisionError and [F, 3] fields in a trace ('collimated: field must be one field')."""
    with pytest.raises(error, match=match):
        report_data(cooke, **kw)


def test_report_wants_a_lens():
    with pytest.raises(TypeError, match=r"report: lens must be a jaxlens.Lens, got str"):
        report_data("cooke.json")


# ---------------------------------------------------------------- the reconstruction network


@pytest.fixture(scope="module")
def net():
    return NAFNet(key=jax.random.PRNGKey(0), width=4)


@pytest.mark.parametrize("bad", [NAN, np.inf])
def test_nafnet_refuses_an_image_that_is_not_finite(net, bad):
    """One NaN or inf pixel made all 192 output values NaN."""
    x = jnp.zeros((8, 8, 3)).at[2, 3, 1].set(bad)
    with pytest.raises(ValueError, match=r"NAFNet: image holds 1 NaN or infinite value\(s\), "
                                         r"first at index \(2, 3, 1\)"):
        net(x)
    with pytest.raises(Exception, match=r"NAFNet: image holds NaN or inf"):  # under jit
        jax.block_until_ready(eqx.filter_jit(net)(x))


def test_nafnet_refuses_complex_bool_and_empty_images_and_takes_lists(net):
    """A complex image ran (complex output), a bool one gave float32, an empty one an empty
    result, and a nested list failed with "'list' object has no attribute 'ndim'". (Round
    43b: one rule for images, ``checks.image_dtype``, names the dtype.)"""
    for x, dt in ((jnp.zeros((8, 8, 3), complex), "complex"), (jnp.zeros((8, 8, 3), bool), "bool")):
        with pytest.raises(ValueError, match=rf"NAFNet: image must be a float image \(linear "
                                             rf"light\), got dtype {dt}"):
            net(x)
    with pytest.raises(ValueError, match=r"NAFNet: expected one \[H, W, C\] image with H, W >= "
                                         r"1, got shape \(0, 8, 3\)"):
        net(jnp.zeros((0, 8, 3)))
    assert net(np.zeros((8, 8, 3)).tolist()).shape == (8, 8, 3)


# ---------------------------------------------------------------- EXR layers


def test_psf_stack_refuses_repeated_names_and_another_suffix(tmp_path):
    """A repeated name kept only its last PSF (two given, one written); names with '.' split
    into other layers on reading; a .png path got EXR bytes."""
    psfs = np.random.default_rng(0).random((2, 5, 5))
    with pytest.raises(ValueError, match=r"write_psf_stack: names must be distinct \(a repeated "
                                         r"name keeps one of its PSFs\), got \['a'\] more than"):
        images.write_psf_stack(tmp_path / "s.exr", psfs, names=["a", "a"])
    with pytest.raises(ValueError, match=r"write_psf_stack: names must be non-empty str "
                                         r"without '.', got 'a.b'"):
        images.write_psf_stack(tmp_path / "s.exr", psfs, names=["a.b", "c"])
    with pytest.raises(ValueError, match=r"write_psf_stack: writes EXR files; the path must "
                                         r"end in .exr"):
        images.write_psf_stack(tmp_path / "s.png", psfs)
    with pytest.raises(ValueError, match=r"write_psf_stack: psfs must be \[N, k, k\] or \[N, C, "
                                         r"k, k\] with N, C, k >= 1, got \(0, 1, 5, 5\)"):
        images.write_psf_stack(tmp_path / "s.exr", np.zeros((0, 5, 5)))
    with pytest.raises(ValueError, match=r"write_exr: channels must be distinct"):
        images.write_exr(tmp_path / "i.exr", np.zeros((4, 4, 3)), channels=("R", "R", "B"))
    assert not list(tmp_path.iterdir())
    images.write_psf_stack(tmp_path / "s.exr", psfs, names=["on", "off"])
    back, names = images.read_psf_stack(tmp_path / "s.exr")
    assert names == ["off", "on"] and back.shape == (2, 1, 5, 5)


# ---------------------------------------------------------------- huge trial counts


def test_monte_carlo_refuses_a_trial_count_it_cannot_hold(cooke, tmp_path, capsys):
    """--trials 10000000000 passed, the sensitivity pass ran, and then the [trials, P]
    perturbations could not be allocated."""
    from jaxlens.experiments import tolerance as cli

    model = tolerance.ToleranceModel(cooke, fields=[0.0], pupil=[[0.0, 0.0], [0.0, 0.5]])
    with pytest.raises(ValueError, match=r"monte_carlo: trials must be a whole number >= 1 and "
                                         r"<= 1000000, got 10000000000"):
        tolerance.monte_carlo(model, trials=10**10, threshold_um=5.0, mtf_frequency=10.0)
    design = pathlib.Path(jl.__file__).parent / "data" / "lenses" / "cooke_triplet.json"
    assert cli.main([str(design), "--trials", "10000000000", "--out", str(tmp_path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "--trials must be a whole number >= 1 and <= 1000000, got " \
                               "10000000000" in lines[0], lines
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------- JSON lens files


def test_json_lens_file_refuses_a_key_given_twice(cooke, tmp_path):
    """json keeps the last of two equal keys: "thickness": 3.26, "thickness": 30 loaded a lens
    30 mm thick there, without a word."""
    path = tmp_path / "c.json"
    jl.save(cooke, path)
    text = path.read_text()
    assert text.count('"thickness": 3.25896,') == 1
    path.write_text(text.replace('"thickness": 3.25896,', '"thickness": 3.25896, '
                                                          '"thickness": 30.0,'))
    with pytest.raises(ValueError, match=r"c.json: key 'thickness' appears twice in one object "
                                         r"\(3.25896 and 30.0\); keep one"):
        jl.load(path)
