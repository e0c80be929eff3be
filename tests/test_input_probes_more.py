"""Bad input found by a probe sweep: each case gets a clear error before any work, naming the
argument, the range and the unit, where it used to give a silent wrong answer (NaN output,
a clipped or defaulted value, an empty result) or an internal traceback.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import pathlib
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging.psf import GeometricPSF
from jaxlens.io import zmx
from jaxlens.optics import checks
from jaxlens.optics import materials as mat

DATA = pathlib.Path(jl.__file__).parent / "data" / "lenses"
ROOT = pathlib.Path(__file__).parent.parent
BK7 = jl.get_material("N-BK7")


def _lens(**kw):
    base = dict(surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
                thickness=jnp.array([6.0, 45.0]), materials=(BK7, jl.Air()), epd=10.0,
                fields=jnp.array([0.0, 10.0]))
    base.update(kw)
    return jl.Lens(**base)


@pytest.fixture(scope="module")
def cooke():
    return jl.load(DATA / "cooke_triplet.zmx")


# ---------------------------------------------------------------- checks.values


def test_checks_values_names_argument_range_unit_and_first_bad_value():
    with pytest.raises(ValueError, match=r"^f: x must be finite numbers in \(0, inf\) mm, got "
                                         r"-2 mm \(first of 2 bad values\)$"):
        checks.values(np.array([1.0, -2.0, np.nan]), "x", "f", lo=0, lo_open=True, unit="mm")
    assert checks.values(np.array([1.0, np.inf]), "x", "f", lo=0, lo_open=True,
                         inf_ok=True) is not None
    with pytest.raises(ValueError, match=r"numbers in \(0, inf\]"):
        checks.values(np.array([np.nan]), "x", "f", lo=0, lo_open=True, inf_ok=True)
    # Under jit the check becomes an error_if.
    f = jax.jit(lambda x: checks.values(x, "x", "f", lo=0, lo_open=True, unit="mm"))
    assert float(f(1.0)) == 1.0
    with pytest.raises(Exception, match=r"f: x must be finite numbers in \(0, inf\) mm"):
        f(-1.0)


# ---------------------------------------------------------------- Lens


@pytest.mark.parametrize("kw, match", [
    (dict(epd=float("nan")), r"Lens: epd \(entrance pupil diameter\) must be finite numbers "
                             r"in \(0, inf\) mm, got nan"),
    (dict(epd=0.0), r"Lens: epd .* in \(0, inf\) mm, got 0 mm"),
    (dict(epd=-5.0), r"Lens: epd .* got -5 mm"),
    (dict(thickness=jnp.array([np.nan, 45.0])), r"Lens: thickness must be finite numbers "
                                                r"\(mm\), got nan"),
    (dict(thickness=jnp.array([6.0, np.inf])), r"Lens: thickness must be finite"),
    (dict(thickness=jnp.ones((2, 3))), r"Lens: 2 surfaces need 2 thicknesses \(mm\), got "
                                       r"shape \(2, 3\)"),
    (dict(thickness=6.0), r"Lens: 2 surfaces need 2 thicknesses \(mm\), got shape \(\)"),
    (dict(fields=jnp.array([0.0, 120.0])), r"Lens: fields must be finite angles in \(-90, 90\) "
                                           r"deg, got 120"),
    (dict(fields=jnp.array([np.nan])), r"Lens: fields must be finite angles"),
    (dict(wavelengths=jnp.array([587.6])), r"Lens: wavelengths 587\.6 µm is outside "
                                           r"0\.15–30 µm.*587\.6 nm is 0\.5876 µm"),
    (dict(wavelengths=jnp.array([-0.5])), r"Lens: wavelengths -0\.5 µm is outside"),
    (dict(object_distance=0.0), r"Lens: object_distance must be finite, nonzero and below "
                                r"1e\+10 in size \(mm .*got 0 mm"),  # < 0: a virtual object
    (dict(object_distance=float("nan")), r"Lens: object_distance must be finite"),
])
def test_lens_refuses_meaningless_numbers(kw, match):
    with pytest.raises(ValueError, match=match):
        _lens(**kw)


def test_lens_refuses_wrong_kinds_of_parts():
    with pytest.raises(TypeError, match=r"Lens: materials\[0\] must be a material .*got str "
                                        r"'N-BK7'"):
        _lens(materials=("N-BK7", jl.Air()))
    with pytest.raises(TypeError, match=r"Lens: surfaces\[0\] must be a surface .*got float"):
        _lens(surfaces=(0.1, jl.Sphere(-1 / 45.0)))
    with pytest.raises(TypeError, match=r"Lens: description must be a string, got list"):
        _lens(description=["not", "text"])


def test_lens_checks_do_not_break_jit_grad_or_vmap():
    lens = _lens()
    rays = jl.sampling.collimated(lens, 5.0, jl.sampling.pupil_grid(5))

    def loss(t, epd):
        L = jl.Lens(surfaces=lens.surfaces, thickness=t, materials=lens.materials, epd=epd,
                    fields=lens.fields)
        return jnp.sum(jl.trace(L, rays).origin[:, 1] ** 2)

    g = jax.jit(jax.grad(loss))(lens.thickness, lens.epd)
    assert np.all(np.isfinite(np.asarray(g)))
    v = jax.vmap(loss, in_axes=(0, None))(jnp.stack([lens.thickness, lens.thickness + 1]),
                                          lens.epd)
    assert v.shape == (2,)
    # A traced thickness is not checked (its value is unknown here): jit of a NaN runs.
    float(jax.jit(loss)(jnp.array([np.nan, 45.0]), 10.0))
    with pytest.raises(ValueError, match=r"Lens: thickness must be finite"):
        loss(jnp.array([np.nan, 45.0]), 10.0)


# ---------------------------------------------------------------- surfaces


@pytest.mark.parametrize("make, match", [
    (lambda: jl.Sphere(float("nan")), r"Sphere: c must be finite numbers in \[-1e\+09.*, got nan"),
    (lambda: jl.Conic(0.1, float("inf")), r"Conic: k must be finite numbers, got inf"),
    (lambda: jl.Sphere(0.1, -1.0), r"Sphere: semi_diameter must be numbers in \(0, inf\] mm "
                                   r"\(inf: no clipping\), got -1 mm"),
    (lambda: jl.Sphere(0.1, 0.0), r"semi_diameter must be numbers in \(0, inf\] mm"),
    (lambda: jl.Stop(float("nan")), r"semi_diameter must be numbers in \(0, inf\]"),
    (lambda: jl.EvenAsphere(0.1, 0.0, jnp.zeros((2, 3))),
     r"EvenAsphere: coeffs must be a 1-D array of coefficients \(one per term\), got shape "
     r"\(2, 3\)"),
    (lambda: jl.EvenAsphere(0.1, 0.0, 1e-3), r"coeffs must be a 1-D array.*shape \(\)"),
    (lambda: jl.EvenAsphere(0.1, 0.0, jnp.array([0.0, np.nan])),
     r"EvenAsphere: coeffs must be finite numbers, got nan"),
    (lambda: jl.Hybrid(odd_x=jnp.ones((2, 2)), odd_y=jnp.ones((2, 2))),
     r"Hybrid: odd_x must be a 1-D array"),
])
def test_surfaces_refuse_bad_numbers_and_shapes(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_surface_checks_skip_traced_values():
    f = jax.jit(lambda c: jl.Sphere(c).c * 2)
    assert float(f(0.5)) == 1.0
    assert jl.Sphere(0.1, jnp.inf).semi_diameter == jnp.inf


# ---------------------------------------------------------------- materials


@pytest.mark.parametrize("make, match", [
    # JAX clamps an out-of-range index: a[2] of a 2-coefficient Schott read a[1].
    (lambda: jl.Schott(jnp.array([2.3, -0.01])), r"Schott: coeffs must hold 6 coefficients, "
                                                 r"got shape \(2,\)"),
    (lambda: mat.Conrady(jnp.ones(4)), r"Conrady: coeffs must hold 3 coefficients"),
    (lambda: mat.Sellmeier2(jnp.ones(3)), r"Sellmeier2: coeffs must hold 5 coefficients"),
    (lambda: mat.Herzberger(jnp.ones(5)), r"Herzberger: coeffs must hold 6"),
    (lambda: mat.Handbook1(jnp.ones(3)), r"Handbook1: coeffs must hold 4"),
    (lambda: mat.Sellmeier4(jnp.ones(6)), r"Sellmeier4: coeffs must hold 5"),
    (lambda: jl.Sellmeier(jnp.array([np.nan, 0.2, 1.0]), jnp.array([0.006, 0.02, 100.0])),
     r"Sellmeier: B must be finite numbers, got nan"),
    (lambda: jl.Tabulated(jnp.array([0.5, 0.6]), jnp.array([1.5, 1.51, 1.49])),
     r"Tabulated: wavelengths \(µm\) and indices must be 1-D arrays of the same non-zero "
     r"length, got shapes \(2,\) and \(3,\)"),
    (lambda: jl.Tabulated(jnp.array([0.5, 0.5]), jnp.array([1.5, 1.51])),
     r"Tabulated: wavelengths must be distinct"),
    (lambda: jl.Tabulated(jnp.array([0.5, -0.6]), jnp.array([1.5, 1.51])),
     r"Tabulated: wavelengths must be finite numbers in \(0, inf\) µm, got -0\.6 µm"),
    (lambda: jl.Tabulated(jnp.array([0.5, 0.6]), jnp.array([0.5, 1.51])),
     r"Tabulated: indices must be finite numbers in \[1, inf\)"),
])
def test_materials_refuse_wrong_coefficients(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_catalog_materials_still_build_and_get_material_wants_a_name():
    for name in ("N-BK7", "F2", "PMMA", "E48R", "H-ZF52", "CAF2"):
        n = float(jl.get_material(name).index(0.5875618))
        assert 1.2 < n < 2.1
    with pytest.raises(TypeError, match=r"get_material: name must be a glass name \(str\), got "
                                        r"int 5"):
        jl.get_material(5)


# ---------------------------------------------------------------- sampling and rays


@pytest.mark.parametrize("make, match", [
    (lambda: jl.sampling.pupil_grid(0), r"pupil_grid: n must be a whole number in \[1, 4096\] "
                                        r"points per side \(n² ≤ 16777216 points\), got 0"),
    (lambda: jl.sampling.pupil_grid(2.5), r"pupil_grid: n must be a whole number"),
    (lambda: jl.sampling.pupil_hexapolar(-1), r"pupil_hexapolar: rings must be a whole number "
                                              r"in \[0, 2364\] rings"),
    (lambda: jl.sampling.pupil_random(jax.random.PRNGKey(0), -5),
     r"pupil_random: n must be a whole number in \[1, 16777216\] points"),
    (lambda: jl.sampling.pupil_stratified(jax.random.PRNGKey(0), 0),
     r"pupil_stratified: n_side must be a whole number in \[1, 4096\]"),
    (lambda: jl.sampling.pupil_samples("grid", -1), r"pupil_grid: n must be"),
])
def test_pupil_sample_counts_are_checked(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_ray_sources_refuse_bad_pupils_depths_and_points(cooke):
    pg = jl.sampling.pupil_grid(5)
    with pytest.raises(ValueError, match=r"collimated: pupil must be \[m, 2\] normalised pupil "
                                         r"points \(Px, Py\), got shape \(5,\)"):
        jl.sampling.collimated(cooke, 0.0, jnp.ones(5))
    with pytest.raises(ValueError, match=r"collimated: pupil must be \[m, 2\].*\(0, 2\)"):
        jl.sampling.collimated(cooke, 0.0, jnp.zeros((0, 2)))
    with pytest.raises(ValueError, match=r"collimated: pupil \(normalised pupil coordinates\) "
                                         r"holds 1 NaN"):
        jl.sampling.collimated(cooke, 0.0, jnp.array([[0.0, np.nan]]))
    with pytest.raises(ValueError, match=r"point_source: point must be \(x, y, z\) in mm"):
        jl.sampling.point_source(cooke, jnp.array([0.0, 0.0]), pg)
    with pytest.raises(ValueError, match=r"point_source: point must be finite numbers \(mm\)"):
        jl.sampling.point_source(cooke, jnp.array([0.0, np.nan, -100.0]), pg)
    for bad in (0.0, float("nan")):  # -5.0: a virtual object 5 mm after surface 1
        with pytest.raises(ValueError, match=r"object_point: depth must be finite, nonzero "):
            jl.sampling.object_point(cooke, 0.0, bad)
    with pytest.raises(ValueError, match=r"sampling: depth must be finite numbers in \(0, inf\)"
                                         r" mm from the object to surface 1"):
        jl.sampling.static_depth(float("nan"))
    assert jl.sampling.static_depth(float("inf")) is None


def test_rays_refuse_mismatched_shapes_and_nan_origins(cooke):
    o = jnp.zeros((4, 3))
    d = jnp.tile(jnp.array([0.0, 0.0, 1.0]), (4, 1))
    with pytest.raises(ValueError, match=r"Rays: wavelength must be a scalar or one value per ray"
                                         r" \(shape \(4,\)\), got shape \(3,\)"):
        jl.Rays(o, d, jnp.array([0.5, 0.6, 0.55]))
    with pytest.raises(ValueError, match=r"Rays: opl must be a scalar or one value per ray"):
        jl.Rays(o, d, 0.55, opl=jnp.zeros(3))
    with pytest.raises(ValueError, match=r"Rays: origin \(mm\) of 1 valid ray\(s\) holds NaN"):
        jl.Rays(o.at[2, 1].set(np.nan), d, 0.55)
    with pytest.raises(ValueError, match=r"Rays: opl \(optical path length, mm\) of 1 valid"):
        jl.Rays(o, d, 0.55, opl=jnp.array([0.0, np.inf, 0.0, 0.0]))
    # An invalid ray may carry anything.
    r = jl.Rays(o.at[2, 1].set(np.nan), d, 0.55, valid=jnp.array([True, True, False, True]))
    assert r.shape == (4,)


# ---------------------------------------------------------------- trace, psf, analysis


def test_iteration_counts_and_psf_options_are_checked(cooke):
    rays = jl.sampling.collimated(cooke, 0.0, jl.sampling.pupil_grid(3))
    with pytest.raises(ValueError, match=r"trace: newton_iters must be a whole number in "
                                         r"\[0, inf\) iterations, got -1"):
        jl.trace(cooke, rays, newton_iters=-1)
    with pytest.raises(ValueError, match=r"trace_path: newton_iters"):  # round 35b: its name
        jl.trace_path(cooke, rays, newton_iters=-1)
    kw = dict(pixel_size=0.005, kernel_size=9, model=GeometricPSF(pupil=8))
    with pytest.raises(ValueError, match=r"psf: newton_iters must be a whole number"):
        jl.psf(cooke, 0.0, newton_iters=-1, **kw)
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match=r"psf: max_truncation must be a finite number in "
                                             r"\[0, 1\] \(fraction of the PSF energy"):
            jl.psf(cooke, 0.0, max_truncation=bad, **kw)
    with pytest.raises(ValueError, match=r"psf: depth must be finite numbers"):
        jl.psf(cooke, 0.0, depth=float("nan"), **kw)
    lens8 = dataclasses.replace(cooke, sensor=jl.Sensor((8, 8), 0.01))
    with pytest.raises(ValueError, match=r"render: depth must be finite numbers"):
        jl.render(lens8, jnp.ones((8, 8, 3)), spp=1, key=jax.random.PRNGKey(0),
                  depth=float("nan"))
    for grid in (0, (0, 3), (2.5, 3)):
        with pytest.raises(ValueError, match=r"psf_map: grid must be \(rows, cols\), whole "
                                             r"numbers >= 1"):
            jl.imaging.psf.psf_map(lens8, grid=grid, **kw)
    with pytest.raises(ValueError, match=r"mtf: frequencies \(cycles/mm\) holds 1 NaN"):
        jl.imaging.psf.mtf(cooke, 0.0, frequencies=jnp.array([10.0, np.nan]),
                           pixel_size=0.005)
    for n in (0, 2, -4):
        with pytest.raises(ValueError, match=r"clear_semi_diameters: n_rim must be a whole "
                                             r"number in \[4, 65536\] rim rays"):
            jl.analysis.clear_semi_diameters(cooke, n_rim=n)


# ---------------------------------------------------------------- .zmx


def _zmx(old, new):
    text = zmx.decode((DATA / "cooke_triplet.zmx").read_bytes()).replace("\r\n", "\n")
    assert old in text
    return text.replace(old, new, 1)


@pytest.mark.parametrize("old, new, match", [
    # FTYP announcing 0 fields gave a lens without fields, -1 dropped the last one.
    ("FTYP 0 0 3 3 0 0 0", "FTYP 0 0 0 3 0 0 0", r"<zmx>:9: number of fields \(FTYP's fourth "
                                                 r"value\) must be >= 1, got 0"),
    ("FTYP 0 0 3 3 0 0 0", "FTYP 0 0 -1 3 0 0 0", r"number of fields .* got -1"),
    ("FTYP 0 0 3 3 0 0 0", "FTYP 0 0 3 0 0 0 0", r"<zmx>:9: number of wavelengths \(FTYP's "
                                                 r"fifth value\) must be >= 1, got 0"),
    # A negative CLAP radius was read as "no aperture".
    ('DIAM 0 0 0 0 1 ""', "CLAP 0 -1 0", r"<zmx>:21: circular aperture maximum radius \(lens "
                                         r"units\) must be >= 0, got -1"),
    # The Lens constructor refuses these too; the reader's message must still name the file.
    ("WAVM 2 5.875618E-001", "WAVM 2 587.5618", r"^<zmx>:\d+: WAVM: wavelength 587\.562 µm is "
                                                r"outside .*587\.562 nm is 0\.587562 µm"),
    # Outside the glasses' range (not only the Lens's): the WAVM line is named too.
    ("WAVM 2 5.875618E-001", "WAVM 2 5.0", r"^<zmx>:\d+: WAVM: wavelength 5 µm is outside "),
    ("YFLN 0 1.4E+001 2.0E+001", "YFLN 0 1.4E+001 95", r"^<zmx>:\d+: YFLN: field angles must "
                                                       r"be finite angles in \(-90, 90\) deg"),
])
def test_zmx_counts_and_apertures(old, new, match):
    with pytest.raises(ValueError, match=match):
        zmx.loads(_zmx(old, new))


# ---------------------------------------------------------------- JSON lens files


@pytest.fixture(scope="module")
def cooke_json():
    return json.loads((DATA / "cooke_triplet.json").read_text())


def _load(d, tmp_path):
    p = tmp_path / "x.json"
    p.write_text(json.dumps(d))
    return jl.load(p)


def test_json_misspelled_keys_are_refused_not_ignored(cooke_json, tmp_path):
    d = copy.deepcopy(cooke_json)
    d["wavelength_nm"] = d.pop("wavelengths_nm")  # would have fallen back to the d line
    with pytest.raises(ValueError, match=r"x\.json: unknown key 'wavelength_nm'; did you mean "
                                         r"'wavelengths_nm'\?"):
        _load(d, tmp_path)
    d = copy.deepcopy(cooke_json)
    d["surfaces"][1]["radus"] = d["surfaces"][1].pop("radius")  # would have been flat
    with pytest.raises(ValueError, match=r"x\.json: surface 1: unknown key 'radus'; did you "
                                         r"mean 'radius'"):
        _load(d, tmp_path)
    d = copy.deepcopy(cooke_json)
    d["surfaces"][2]["Thickness"] = d["surfaces"][2].pop("thickness")
    with pytest.raises(ValueError, match=r"unknown key 'Thickness'; did you mean 'thickness'"):
        _load(d, tmp_path)
    d = copy.deepcopy(cooke_json)
    d["aperture"] = {"epd": 10.0, "fnumm": 4}
    with pytest.raises(ValueError, match=r"x\.json: aperture: unknown key 'fnumm'"):
        _load(d, tmp_path)
    # Informational keys far from every known key stay allowed.
    d = copy.deepcopy(cooke_json)
    d["generator"] = "me"
    d["surfaces"][1]["comment"] = "front"
    d["surfaces"][1]["semi_diameter_source"] = "real rays"
    d["surfaces"][1]["nd"] = 1.5168  # not a typo of "n"
    # Longer than "conic" and 3 edits from "conic_x" (a biconic key since the freeform kinds;
    # "conic_k" is now 1 from it and refused as a near miss).
    d["surfaces"][1]["conic_src"] = 0.0
    assert _load(d, tmp_path).num_surfaces == 6


def test_reference_files_have_no_near_miss_keys():
    files = [*ROOT.glob("tests/refcases/*.json"), *DATA.glob("*.json")]
    assert files
    for f in files:
        jl.load(f)


def test_json_numbers_the_reader_used_to_let_through(cooke_json, tmp_path):
    d = copy.deepcopy(cooke_json)
    del d["aperture"]
    for v in (-5.0, 0):
        d["epd"] = v
        with pytest.raises(ValueError, match=r"x\.json: epd \(entrance pupil diameter\) must "
                                             r"be > 0 mm"):
            _load(d, tmp_path)
    d = copy.deepcopy(cooke_json)
    d["sensor"] = {"resolution": [2.5, 8], "pixel_size": 0.01}  # was read as 2 rows
    with pytest.raises(ValueError, match=r"x\.json: sensor needs resolution \[rows, cols\]"):
        _load(d, tmp_path)
    d["sensor"] = {"resolution": [8.0, 8], "pixel_size": 0.01}
    assert _load(d, tmp_path).sensor.resolution == (8, 8)
    d = copy.deepcopy(cooke_json)
    d["fields"] = {"type": "angle_deg_y", "values": [[0, 1, 2], [3, 4, 5]]}
    with pytest.raises(ValueError, match=r"x\.json: fields must be a list of angles θy or of "
                                         r"\[θx, θy\] pairs \(deg\), got an array of shape "
                                         r"\(2, 3\)"):
        _load(d, tmp_path)
    d = copy.deepcopy(cooke_json)
    d["surfaces"][1]["material"] = {"class": "Schott", "coeffs": [2.3, -0.01]}
    with pytest.raises(ValueError, match=r"x\.json: surface 1: cannot build Schott: Schott: "
                                         r"coeffs must hold 6 coefficients"):
        _load(d, tmp_path)
    d["surfaces"][1]["material"] = {"wavelengths_um": [0.5, 0.6], "indices": [0.5, 1.51]}
    with pytest.raises(ValueError, match=r"x\.json: surface 1: index table needs|x\.json: "
                                         r"surface 1: Tabulated: indices must be"):
        _load(d, tmp_path)


# ---------------------------------------------------------------- benchmarks CLI


@pytest.mark.parametrize("args, match", [
    (["--lenses", "cook_triplet"], r"--lenses: unknown zoo lens 'cook_triplet' .*closest: "
                                   r"cooke_triplet"),
    (["--counts", "0"], r"--counts must be whole numbers in \[1, 100000000\] rays, got 0"),
])
def test_benchmarks_cli_refuses_bad_lenses_and_counts(args, match, capsys):
    from benchmarks.run import main

    with pytest.raises(SystemExit) as e:
        main(["--only", "throughput", "--out", "/nonexistent/never", *args])
    assert e.value.code == 2
    assert re.search(match, capsys.readouterr().err)


def test_point_source_behind_the_lens_is_refused():
    import jaxlens
    from jaxlens.imaging import sampling

    lens = jaxlens.zoo.cooke_triplet()
    pupil = jnp.zeros((1, 2))
    assert sampling.point_source(lens, jnp.array([0.0, 1.0, -500.0]), pupil).direction[0, 2] > 0
    # z = 5 mm, after surface 1, is a virtual object; the pupil's own plane gives no direction.
    zep = float(jaxlens.paraxial.entrance_pupil_z(lens, lens.primary_wavelength))
    with pytest.raises(ValueError, match=r"point_source: the point's z must be .* mm \(global z"):
        sampling.point_source(lens, jnp.array([0.0, 1.0, zep]), pupil)


def test_tabulated_glass_refuses_wavelengths_beyond_its_table():
    """A table's index is held constant past its end nodes: a silent wrong answer, so the
    trace refuses wavelengths outside the table (a rounded F line is still accepted)."""
    import jaxlens
    from jaxlens.imaging import sampling
    from jaxlens.optics.materials import Tabulated

    lens = jaxlens.zoo.cooke_triplet()
    pupil = sampling.pupil_grid(3)
    assert bool(jnp.all(jaxlens.trace(lens, sampling.collimated(lens, 0.0, pupil, 0.4861)).valid))
    with pytest.raises(Exception, match=r"outside 0\.48.*–0\.65.* µm, the data range of SK16"):
        jaxlens.trace(lens, sampling.collimated(lens, 0.0, pupil, 5.0))
    assert Tabulated([0.55], [1.5]).wavelength_range is None  # one node: no dispersion
    lo, hi = Tabulated([0.5, 0.6], [1.51, 1.50]).wavelength_range
    assert lo == pytest.approx(0.5 * (1 - 1e-3)) and hi == pytest.approx(0.6 * (1 + 1e-3))
    # eqx.tree_at replaces the table without refreshing the static range: the checks made
    # before a jit (analyses, psf) use the table as it is now.
    sk16 = lens.materials[0]
    assert isinstance(sk16, Tabulated)
    short = eqx.tree_at(lambda m: (m.wavelengths, m.indices), sk16,
                        (sk16.wavelengths[1:], sk16.indices[1:]))
    edited = eqx.tree_at(lambda lz: lz.materials[0], lens, short)
    assert short.wavelength_range == sk16.wavelength_range  # stale
    with pytest.raises(ValueError, match=r"0\.4861 µm is outside 0\.58.*the data range of SK16"):
        jaxlens.analysis.rms_spot(edited, wavelengths=[0.4861])


def test_checks_on_constants_hold_inside_jit():
    """Under jit, jnp.asarray of a Python constant is a tracer: a check made after the
    conversion was skipped (rms_spot at a negative depth gave NaN, a jitted psf took a zero
    pixel). The checks now look at the value as given."""
    import jaxlens

    lens = jaxlens.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"rms_spot: depth must be .* \(0, inf\) mm"):
        jaxlens.analysis.rms_spot(lens, depth=-100.0)
    with pytest.raises(ValueError, match=r"psf: pixel_size must be .* \(0, inf\) mm"):
        jax.jit(lambda: jaxlens.psf(lens, 0.0, pixel_size=0.0))()


def test_an_object_1e10_mm_away_or_more_is_at_infinity():
    """Zemax's rule, also for a Lens built in code: a 1e20 mm object (as some programs
    write infinity) gave NaN spots in float32 (its square overflows when rays are aimed)."""
    base = jl.load(DATA / "cooke_triplet.json")

    def at(distance):
        return jl.Lens(surfaces=base.surfaces, thickness=base.thickness,
                       materials=base.materials, stop=base.stop, epd=base.epd,
                       fields=base.fields, wavelengths=base.wavelengths,
                       object_distance=distance)

    assert at(1e20).object_at_infinity and at(1e10).object_at_infinity
    assert not at(9.9e9).object_at_infinity
    spot = jl.analysis.rms_spot(at(1e20))
    np.testing.assert_array_equal(np.asarray(spot.valid_fraction), 1.0)


@pytest.mark.parametrize("name", ["lens.zmx", "lens.json"])
def test_save_into_a_missing_folder_names_the_folder_and_writes_nothing(cooke, tmp_path, name):
    """A lens saved into a folder that does not exist is refused before anything is
    written (a .zmx used to fail on its glass catalog's name, not the folder's)."""
    import jaxlens

    target = tmp_path / "missing" / name
    with pytest.raises(FileNotFoundError, match="missing.*does not exist"):
        jaxlens.save(cooke, target)
    assert list(tmp_path.iterdir()) == []


def test_spot_analyses_compile_once_for_every_finite_depth(cooke, caplog):
    """A finite depth reaches the compiled spot programs as an argument (one program for
    every depth; a Python float was static and compiled one per value), is still checked
    before them, and inf still means an object at infinity."""
    import logging

    from jaxlens.analysis import spots

    pupil = jnp.array([[0.0, 0.5], [0.5, 0.0], [0.0, -0.5]])
    near = spots.rms_spot(cooke, pupil=pupil, depth=800.0)  # compiles
    with jax.log_compiles(), caplog.at_level(logging.WARNING):
        caplog.clear()
        far = spots.rms_spot(cooke, pupil=pupil, depth=1600.0)
        assert not [r for r in caplog.records if "_rms_spot" in r.getMessage()]
    assert not np.allclose(np.asarray(near.polychromatic), np.asarray(far.polychromatic))
    at_inf = spots.rms_spot(cooke, pupil=pupil, depth=np.inf)
    very_far = spots.rms_spot(cooke, pupil=pupil, depth=1e9)
    np.testing.assert_allclose(np.asarray(at_inf.polychromatic),
                               np.asarray(very_far.polychromatic), rtol=1e-4)
    with pytest.raises(ValueError, match="rms_spot: depth must be"):
        spots.rms_spot(cooke, pupil=pupil, depth=-5.0)
    with pytest.raises(ValueError, match="chief_ray: depth must be"):
        spots.chief_ray(cooke, 10.0, depth=float("nan"))
    chief = spots.chief_ray(cooke, 10.0, depth=500.0)
    assert chief.origin.dtype == cooke.epd.dtype and bool(chief.valid)
