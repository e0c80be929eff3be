"""Bad input to the public API found by a second probe sweep: each case now gets a clear error
before any work (naming the argument, the range and the unit) where it used to give a silent
wrong answer, an error raised only after the jitted work had run, or a traceback from deep
inside JAX. Every case raises before anything large is compiled.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import distortion as dist
from jaxlens.imaging import sampling
from jaxlens.imaging.psf import GeometricPSF, mtf, psf_map
from jaxlens.optics import checks, paraxial


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


# ---------------------------------------------------------------- numbers given as strings


def test_strings_bools_and_none_are_not_numbers(cooke):
    """np.asarray("10", float) is 10: a string field was traced as 10°, while JAX refused the
    same string deep inside (dtype <U2 is not a valid JAX array type)."""
    pg = sampling.pupil_grid(3)
    with pytest.raises(TypeError, match=r"collimated: field must be a real number or an array "
                                        r"of real numbers \(deg\), got str '10'"):
        sampling.collimated(cooke, "10", pg)
    with pytest.raises(TypeError, match=r"psf: field must be a real number .*\(deg\), got str"):
        jl.psf(cooke, "5", pixel_size=0.005, kernel_size=9)
    with pytest.raises(TypeError, match=r"efl: wavelength must be a real number .*\(µm\), got "
                                        r"str '0\.5'"):
        jl.efl(cooke, "0.5")
    with pytest.raises(TypeError, match=r"Rays: wavelength must be a real number .*got str"):
        jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), "0.55")
    with pytest.raises(TypeError, match=r"paraxial_chief_ray: field_deg must be a real number"):
        paraxial.paraxial_chief_ray(cooke, True)
    with pytest.raises(TypeError, match=r"field_rays: depth must be a real number .*\(mm\)"):
        sampling.field_rays(cooke, 0.0, pg, depth="100")
    checks.real_values(jnp.ones(2, jnp.bfloat16), "x", "f")  # any real dtype passes


# ---------------------------------------------------------------- ray sources


def test_collimated_takes_one_field(cooke):
    pg = sampling.pupil_grid(3)
    for field in (jnp.array([1.0, 2.0, 3.0]), jnp.ones((2, 2))):
        with pytest.raises(ValueError, match=r"collimated: field must be one field, θy or "
                                             r"\(θx, θy\) in degrees, got shape"):
            sampling.collimated(cooke, field, pg)
    assert sampling.collimated(cooke, jnp.array([1.0, 2.0]), pg).shape == (pg.shape[0],)


@pytest.mark.parametrize("make, where", [
    (lambda: sampling.pupil_random(0, 10), "pupil_random"),
    (lambda: sampling.pupil_stratified(5, 3), "pupil_stratified"),
    (lambda: sampling.pupil_polar(3, key=1), "pupil_polar"),
    (lambda: sampling.pupil_samples("random", 3, key=5), "pupil_random"),
])
def test_pupil_samplers_check_the_key(make, where):
    with pytest.raises(ValueError, match=rf"{where}: key must be .*one PRNG key"):
        make()


def test_pupil_samplers_want_float_dtypes_and_whole_counts():
    # An int dtype truncated the grid to -1, 0, 1.
    for make in (lambda: sampling.pupil_grid(3, dtype=jnp.int32),
                 lambda: sampling.pupil_hexapolar(2, dtype="int32"),
                 lambda: sampling.pupil_random(jax.random.PRNGKey(0), 4, dtype=jnp.int32),
                 lambda: sampling.pupil_polar(2, dtype=np.int64)):
        with pytest.raises(ValueError, match=r"dtype must be None, float32 or float64"):
            make()
    assert sampling.pupil_polar(np.int64(3)).shape == (9, 2)  # was refused: not an int
    with pytest.raises(ValueError, match=r"pupil_polar: n_side must be a whole number in "
                                         r"\[1, 4096\] cells per side \(n² ≤ 16777216\), got True"):
        sampling.pupil_polar(True)
    with pytest.raises(ValueError, match=r"pupil_polar: radius must be a finite number in "
                                         r"\(0, 1\] \(pupil radii\), got nan"):
        sampling.pupil_polar(3, radius=float("nan"))


def test_aim_at_stop_checks_iterations_and_one_point_per_ray(cooke):
    pg = sampling.pupil_grid(3)
    rays = sampling.collimated(cooke, 0.0, pg)
    with pytest.raises(ValueError, match=r"aim_at_stop: iters must be a whole number in "
                                         r"\[0, inf\) Newton iterations, got -1"):
        sampling.aim_at_stop(cooke, rays, pg, iters=-1)  # ran no iteration, unaimed
    with pytest.raises(ValueError, match=r"aim_at_stop: pupil needs one point per ray: rays of "
                                         r"shape \(5,\) need pupil of shape \(5, 2\), got "
                                         r"\(3, 2\)"):
        sampling.aim_at_stop(cooke, rays, pg[:3])


def test_minus_infinity_is_not_an_object_at_infinity(cooke):
    assert sampling.static_depth(float("inf")) is None
    with pytest.raises(ValueError, match=r"sampling: depth must be finite numbers in "
                                         r"\(0, inf\) mm"):
        sampling.static_depth(-np.inf)
    with pytest.raises(ValueError, match=r"depth must be finite numbers in \(0, inf\) mm"):
        jl.psf(cooke, 0.0, depth=-np.inf, pixel_size=0.005, kernel_size=9)
    with pytest.raises(ValueError, match=r"^field_rays: depth must be finite"):
        sampling.field_rays(cooke, 0.0, sampling.pupil_grid(3), depth=-np.inf)


# ---------------------------------------------------------------- Rays


def test_rays_valid_is_a_bool_mask_of_the_batch_shape():
    o = jnp.zeros((2, 3))
    d = jnp.tile(jnp.array([0.0, 0.0, 1.0]), (2, 1))
    r = jl.Rays(o, d, 0.55, valid=jnp.array([1, 0]))
    assert r.valid.dtype == jnp.bool_ and r.valid.tolist() == [True, False]
    # An int mask stayed int: valid & ok was a bitwise and (2 & True == 0).
    with pytest.raises(TypeError, match=r"Rays: valid must be a bool mask .*got dtype "
                                        r"int(32|64) \[2, 0\]"):
        jl.Rays(o, d, 0.55, valid=jnp.array([2, 0]))
    with pytest.raises(TypeError, match=r"Rays: valid must be a bool mask .*float(32|64)"):
        jl.Rays(o, d, 0.55, valid=jnp.array([0.5, 1.0]))
    with pytest.raises(ValueError, match=r"Rays: valid must be a scalar or one flag per ray "
                                         r"\(shape \(2,\)\), got shape \(3,\)"):
        jl.Rays(o, d, 0.55, valid=jnp.array([True, False, True]))


# ---------------------------------------------------------------- paraxial helpers


@pytest.mark.parametrize("fn", [paraxial.entrance_pupil_z, paraxial.marginal_ray,
                                paraxial.entrance_pupil_magnification, paraxial.signed_indices,
                                paraxial.system_matrix])
def test_paraxial_helpers_check_a_given_wavelength(cooke, fn):
    """587.6 (nm) gave a plausible entrance pupil 11.497 mm (11.506 at 0.5876 µm)."""
    with pytest.raises(ValueError, match=rf"{fn.__name__}: wavelength 587\.6 µm is outside "
                                         r".*587\.6 nm is 0\.5876 µm"):
        fn(cooke, 587.6)
    fn(cooke, 0.5876)
    jax.jit(lambda w: fn(cooke, w))(0.5876)  # traced: not checked here, no error_if added


@pytest.mark.parametrize("kw, arg", [
    (dict(start=9), "start"), (dict(start=-1), "start"), (dict(end=99), "end"),
    (dict(start=4, end=2), "end"), (dict(start=1.0), "start"),
])
def test_system_matrix_checks_its_surface_range(cooke, kw, arg):
    """start=9 gave the identity, start=-1 wrapped to the last surface, end=99 IndexError."""
    with pytest.raises(ValueError, match=rf"system_matrix: {arg} must be a surface index in "
                                         r"\[\d, 5\] \(0-based; start <= end\)"):
        paraxial.system_matrix(cooke, **kw)


# ---------------------------------------------------------------- surfaces


@pytest.mark.parametrize("make, r_max", [
    (lambda: jl.Sphere(1 / 3.0, 5.0), 3.0),
    (lambda: jl.Sphere(-1 / 3.0, 5.0), 3.0),
    (lambda: jl.Conic(0.5, 3.0, 5.0), 1.0),
    (lambda: jl.EvenAsphere(1 / 3.0, 0.0, jnp.zeros(2), 3.5), 3.0),
    (lambda: jl.Standard(c=jnp.array([0.1, 1 / 3.0]), semi_diameter=5.0), 3.0),
])
def test_a_surface_must_exist_out_to_its_semi_diameter(make, r_max):
    """Rays beyond r = 1/(|c| sqrt(1 + k)) were lost without a word."""
    with pytest.raises(ValueError, match=rf"is defined only out to r = 1/\(\|c\|·sqrt\(1 \+ k\)\)"
                                         rf" = {r_max:g} mm, but its semi_diameter is"):
        make()


def test_surfaces_that_exist_out_to_their_semi_diameter_still_build():
    jl.Sphere(1 / 3.0, 3.0)  # a hemisphere, in float32
    jl.Conic(0.5, -1.0, 100.0)  # a paraboloid exists everywhere
    jl.Conic(0.5, -3.0, 100.0)  # so does a hyperboloid
    jl.Sphere(1 / 3.0)  # no semi-diameter: no clipping
    assert float(jax.jit(lambda c: jl.Sphere(c, 5.0).c)(1 / 3.0)) > 0  # traced: not checked


# ---------------------------------------------------------------- analyses


@pytest.mark.parametrize("call, match", [
    (lambda L: jl.analysis.rms_spot(L, fields=jnp.array([95.0])),
     r"rms_spot: fields must be finite angles in \(-90, 90\) deg, got 95"),
    (lambda L: jl.analysis.rms_spot(L, wavelengths=jnp.array([587.6])),
     r"rms_spot: wavelengths 587\.6 µm is outside .*587\.6 nm is 0\.5876 µm"),
    (lambda L: jl.analysis.spot_rays(L, 0.0, 587.6), r"spot_rays: wavelength 587\.6 µm"),
    (lambda L: jl.analysis.spot_rays(L, jnp.array(95.0)), r"spot_rays: field must be finite"),
    (lambda L: jl.analysis.chief_ray(L, 0.0, jnp.array(587.6)), r"chief_ray: wavelength 587"),
    (lambda L: jl.analysis.distortion(L, fields=jnp.array([95.0])),
     r"distortion: fields must be finite angles"),
    (lambda L: jl.analysis.clear_semi_diameters(L, fields=jnp.array([95.0])),
     r"clear_semi_diameters: fields must be finite angles"),
])
def test_analyses_check_arrays_before_the_jitted_work(cooke, call, match):
    """A jnp array is a tracer inside the jitted body: these raised an EquinoxRuntimeError
    ("Above is the stack outside of JIT") after the whole trace had run."""
    with pytest.raises(ValueError, match=match):
        call(cooke)


def test_analyses_want_a_lens(cooke):
    with pytest.raises(TypeError, match=r"rms_spot: lens must be a jaxlens\.Lens, got str"):
        jl.analysis.rms_spot("cooke")


def test_distortion_of_a_field_without_a_chief_ray_is_nan_not_minus_100_percent(cooke):
    d = jl.analysis.distortion(cooke, fields=jnp.array([0.0, 5.0, 60.0]))
    assert np.all(np.isfinite(np.asarray(d.percent_ftan[:2])))
    assert np.isnan(float(d.chief_height[2])) and np.isnan(float(d.percent_ftan[2]))
    assert np.isnan(float(d.percent_paraxial[2]))


def test_self_intersection_checks_its_sampling(cooke):
    for kw, match in ((dict(n_radial=0), r"n_radial must be a whole number in \[2, 65536\] radii"),
                      (dict(n_angle=0), r"n_angle must be a whole number in \[1, 65536\] azimuths"),
                      (dict(min_gap=float("nan")), r"min_gap must be a finite number"),
                      (dict(semi_diameters=jnp.ones(3)),
                       r"semi_diameters must hold one value per surface, shape \(6,\)"),
                      (dict(semi_diameters=-jnp.ones(6)), r"semi_diameters must be finite")):
        with pytest.raises(ValueError, match=rf"self_intersection: {match}"):
            jl.analysis.self_intersection(cooke, **kw)


# ---------------------------------------------------------------- distortion maps, PSF, MTF


@pytest.mark.parametrize("call, match", [
    (lambda L: dist.distortion_map(L, grid=(0, 3)), r"distortion_map: grid must be \(rows, "
                                                    r"cols\), whole numbers >= 2 points"),
    (lambda L: dist.distortion_map(L, grid=(2.5, 3)), r"distortion_map: grid must be"),
    (lambda L: dist.distortion_map(L, sensor="x"), r"sensor must be a jaxlens\.Sensor"),
    (lambda L: dist.prewarp(L, jnp.ones((4, 6, 3)), grid=(0, 3)), r"prewarp: grid must be"),
    (lambda L: dist.inverse_distortion_map(L, resolution=(0, 8), pixel_size=0.01),
     r"inverse_distortion_map: resolution must be \(rows, cols\), whole numbers >= 1 pixels"),
    (lambda L: dist.inverse_distortion_map(L, resolution=(8, 8), pixel_size=-0.01),
     r"inverse_distortion_map: pixel_size must be a finite number in \(0, inf\) mm"),
    (lambda L: dist.inverse_distortion_map(L, resolution=(8, 8), pixel_size=0.01, grid=(0, 3)),
     r"inverse_distortion_map: grid must be"),
    (lambda L: dist.inverse_distortion_map(L, resolution=(8, 8), pixel_size=0.01, iters=-1),
     r"inverse_distortion_map: iters must be a whole number in \[1, 1000\] aiming "
     r"iterations"),
    (lambda L: dist.inverse_distortion_map(L, resolution=(8, 8), pixel_size=0.01, depth=-5.0),
     r"depth must be finite numbers in \(0, inf\) mm"),
    (lambda L: psf_map(L, grid=(2, 2), sensor="x", pixel_size=0.005),
     r"psf_map: sensor must be a jaxlens\.Sensor"),
])
def test_sensor_grids_and_maps_check_their_arguments(cooke, call, match):
    """grid (0, 3) gave a 1x3 map and (8, 8) pixels of -0.01 mm a mirrored one, silently."""
    with pytest.raises((ValueError, TypeError), match=match):
        call(cooke)


def test_psf_kernel_size_is_a_whole_number(cooke):
    for k in (True, 9.5, 0):
        with pytest.raises(ValueError, match=r"psf: kernel_size must be a whole number in "
                                             r"\[1, 4096\] pixels per side"):
            jl.psf(cooke, 0.0, pixel_size=0.005, kernel_size=k, model=GeometricPSF(pupil=4))


@pytest.mark.parametrize("freqs, match", [
    (jnp.array([-10.0]), r"mtf: frequencies must be finite numbers in \[0, inf\) cycles/mm"),
    (jnp.array([]), r"mtf: frequencies must be \[F\] cycles/mm with F >= 1, got shape \(0,\)"),
    (jnp.ones((2, 2)), r"mtf: frequencies must be \[F\] cycles/mm with F >= 1, got shape"),
])
def test_mtf_frequencies_are_a_list_of_non_negative_numbers(cooke, freqs, match):
    with pytest.raises(ValueError, match=match):
        mtf(cooke, 0.0, frequencies=freqs)


# ---------------------------------------------------------------- materials and catalogs


def test_model_glass_and_nearest_glasses_refuse_swapped_nd_and_vd():
    with pytest.raises(ValueError, match=r"ModelGlass: nd must be a finite index >= 1 and <= "
                                         r"4\.5 \(the d-line index\), got 60 \(were nd and vd "
                                         r"swapped\?\)"):
        jl.ModelGlass(60.0, 1.5)
    with pytest.raises(ValueError, match=r"nearest_glasses: nd must be a finite number in "
                                         r"\(1, 4\.5\]"):
        jl.catalog.nearest_glasses(60.0, 1.5)
    with pytest.raises(ValueError, match=r"nearest_glasses: count must be a whole number"):
        jl.catalog.nearest_glasses(1.5, 60.0, count=2.5)
    # An unknown glass with a nonsense nd still gets its name suggestions.
    with pytest.raises(ValueError, match=r"Unknown material 'N-BK8'\. Closest catalog matches"):
        jl.get_material("N-BK8", nd=60.0, vd=1.5)


def test_glass_info_wants_a_name():
    with pytest.raises(TypeError, match=r"glass_info: name must be a glass name \(str\), got "
                                        r"int 5"):
        jl.glass_info(5)


def test_tabulated_glass_in_nanometres_is_refused():
    with pytest.raises(ValueError, match=r"Tabulated: wavelengths .* µm is outside 0\.15–30 µm"
                                         r".*500 nm is 0\.5 µm"):
        jl.Tabulated(jnp.array([500.0, 600.0]), jnp.array([1.5, 1.51]))
    jl.Tabulated(jnp.array([0.1, 0.5, 60.0]), jnp.array([1.6, 1.5, 1.4]))  # wide, in µm


# ---------------------------------------------------------------- Lens structure


def test_lens_static_lists_give_clear_errors():
    base = dict(surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
                thickness=jnp.array([6.0, 45.0]),
                materials=(jl.get_material("N-BK7"), jl.Air()), epd=10.0)
    with pytest.raises(TypeError, match=r"Lens: mirrors must be a tuple of surface indices, "
                                        r"got int 1"):
        jl.Lens(**base, mirrors=1)
    for bad in (((0, "a", 1.0),), ((0, 1.0),), ((0.0, 0.0, 1.0),)):
        with pytest.raises(ValueError, match=r"Lens: obscurations must be \(i, r_min, r_max\) "
                                             r"triples"):
            jl.Lens(**base, obscurations=bad)
    with pytest.raises(ValueError, match=r"Sensor: resolution must be \(rows, columns\)"):
        jl.Sensor(10, 0.01)


@pytest.mark.parametrize(("kw", "match"), [
    (dict(upto=True), r"upto must be a surface index in \[0, 5\]"),
    (dict(upto=1.0), r"upto must be a surface index"),
    (dict(chunk=2.5), r"chunk must be a whole number in \[1, inf\) rays"),
    (dict(chunk="8"), r"chunk must be a whole number"),
])
def test_trace_refuses_a_bool_or_fractional_upto_and_chunk(kw, match):
    """``upto=True`` traced to surface 1 and ``chunk=2.5`` failed inside the chunking."""
    lens = jl.zoo.cooke_triplet()
    rays = jl.Rays(jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.5876)
    with pytest.raises(ValueError, match=match):
        jl.trace(lens, rays, **kw)


def test_trace_names_a_lens_or_rays_of_the_wrong_type():
    lens = jl.zoo.cooke_triplet()
    rays = jl.Rays(jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.5876)
    with pytest.raises(TypeError, match="trace: lens must be a jaxlens.Lens, got Rays"):
        jl.trace(rays, lens)
    with pytest.raises(TypeError, match="trace_path: rays must be a jaxlens.Rays, got ndarray"):
        jl.trace_path(lens, np.zeros((1, 3)))


def _every_material():
    from jaxlens.analysis.tolerance import PerturbedMaterial

    glass = jl.get_material("N-BK7")
    return [jl.Air(), jl.ModelGlass(1.5168, 64.17), glass, jl.get_material("ZNSE", "INFRARED"),
            jl.Tabulated(jnp.array([0.4, 0.6, 0.8]), jnp.array([1.53, 1.52, 1.51])),
            *(jl.get_material(n) for n in ("PMMA", "POLYCARB")),
            PerturbedMaterial(glass, jnp.asarray(0.001), jnp.asarray(0.0))]


@pytest.mark.parametrize("material", _every_material(), ids=lambda m: type(m).__name__)
def test_material_index_refuses_a_wavelength_in_nm(material):
    """Every material's ``index`` takes µm; 587.6 (nm) would give a plausible wrong index
    from any dispersion formula, so a concrete value that cannot be in µm is refused. An
    in-µm value outside the data range still gives a number (infrared materials' nd)."""
    with pytest.raises(ValueError, match="587.6 nm is 0.5876 µm"):
        material.index(587.6)
    with pytest.raises(ValueError, match="not a wavelength in µm"):
        material.index(jnp.array([0.5, -0.5]))
    n = float(material.index(0.5876))
    assert 1.0 <= n < 3.0
    assert float(jax.jit(lambda w: material.index(w))(0.5876)) == pytest.approx(n, rel=1e-6)


def test_a_new_material_class_gets_the_unit_check():
    class Constant(jl.AbstractMaterial):
        name: str = "constant"

        def index(self, wavelength):
            return jnp.full_like(jnp.asarray(wavelength, float), 1.4)

    assert float(Constant().index(0.55)) == pytest.approx(1.4)
    with pytest.raises(ValueError, match="Constant.index"):
        Constant().index(550.0)
