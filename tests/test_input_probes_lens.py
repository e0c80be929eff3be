"""Bad input to lens files and the Lens constructor is refused at once, with a clear message."""

import dataclasses
import json
import pathlib

import jax
import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens.io.lensfile import lens_from_dict
from jaxlens.optics.coordinates import CoordinateBreak
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.optics.toroidal import Toroidal

COOKE = pathlib.Path(jl.__file__).parent / "data" / "lenses" / "cooke_triplet.json"


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


def _edited(edit):
    d = json.loads(COOKE.read_text())
    edit(d)
    return d


def _rename(d, old, new):
    d[new] = d.pop(old)


@pytest.mark.parametrize("edit, match", [
    # synonyms of surface keys: each loaded as a wrong lens (air, flat, no stop, ...)
    (lambda d: _rename(d["surfaces"][1], "material", "glass"),
     r"surface 1: unknown key 'glass'; did you mean 'material'"),
    (lambda d: _rename(d["surfaces"][1], "radius", "R"), r"'R'; did you mean 'radius'"),
    (lambda d: _rename(d["surfaces"][1], "radius", "roc"), r"'roc'; did you mean 'radius'"),
    (lambda d: d["surfaces"][1].update(k=-1.0), r"'k'; did you mean 'conic'"),
    (lambda d: d["surfaces"][1].update(asphere_coeffs=[0, 1e-5]),
     r"'asphere_coeffs'; did you mean 'even_asphere_coeffs'"),
    (lambda d: d["surfaces"][1].update(diameter=20.0), r"did you mean 'semi_diameter'"),
    (lambda d: d["surfaces"][1].update(stop=True), r"'stop'; did you mean 'is_stop'"),
    (lambda d: d["surfaces"][-1].update(R=-100.0), r"image surface: unknown key 'R'"),
    # synonyms and incomplete objects at the system level
    (lambda d: d.update(fields={"type": "angle_deg_y", "vals": [0, 14, 20]}),
     r"fields: unknown key 'vals'; did you mean 'values'"),
    (lambda d: d.update(fields={"type": "angle_deg_y"}), r"fields needs 'values'"),
    (lambda d: _rename(d, "fields", "field_angles"), r"'field_angles'; did you mean 'fields'"),
    (lambda d: _rename(d, "wavelengths_nm", "lambda_nm"),
     r"'lambda_nm'; did you mean 'wavelengths_nm'"),
    (lambda d: d.update(object_distance=500), r"did you mean 'object'.*distance"),
    (lambda d: d.update(object={"dist": 500}), r"object: unknown key 'dist'"),
    (lambda d: d.update(object={}), r"object needs 'distance'"),
    (lambda d: d.update(units="inch"), r"units\.length 'inch' is not supported"),
    (lambda d: d.update(units={"length": "cm"}), r"units\.length 'cm' is not supported"),
])
def test_json_synonyms_incomplete_objects_and_units_are_refused(edit, match):
    with pytest.raises(ValueError, match=match):
        lens_from_dict(_edited(edit), source="x.json")


def test_json_unrelated_keys_and_mm_units_still_load():
    def edit(d):
        d.update(comment="metadata", units="mm; wavelengths in nm; angles in degrees")
        d["surfaces"][1].update(index=1, semi_diameter_real_rays=9.0)
    lens = lens_from_dict(_edited(edit), source="x.json")
    assert lens.materials[0].name == "N-SK16" and float(lens.surfaces[0].c) > 0


@pytest.mark.parametrize("kw, err, match", [
    (dict(fields=jnp.array([[0.0], [14.0]])), ValueError, r"fields must be .* shape \(2, 1\)"),
    (dict(fields=jnp.zeros((3, 3))), ValueError, r"\[F, 2\] \(deg\), got shape \(3, 3\)"),
    (dict(epd=jnp.array([10.0, 20.0])), ValueError, r"epd must be a scalar \(mm\), got shape"),
    (dict(wavelengths=0.55), ValueError, r"wavelengths must be a 1-D array"),
    (dict(stop=1.0), TypeError, r"Lens: stop must be an int .* got float 1\.0"),
    (dict(stop=True), TypeError, r"stop must be an int .* got bool True"),
    (dict(primary=0.0), TypeError, r"Lens: primary must be an int .* got float 0\.0"),
    (dict(object_distance=0.0), ValueError, r"object_distance must be finite, nonzero"),
    (dict(thickness=["3", 6, 1, 4.75, 2.95, 42.2]), TypeError,
     r"Lens: thickness must be a real number .* \(mm\), got list"),
])
def test_lens_refuses_bad_shapes_and_indices(cooke, kw, err, match):
    with pytest.raises(err, match=match):
        dataclasses.replace(cooke, **kw)


def test_lens_integer_arrays_become_floats_so_grad_reaches_them(cooke):
    t = jnp.round(cooke.thickness).astype(jnp.int32)
    lens = dataclasses.replace(cooke, thickness=t, epd=10, object_distance=500)
    assert lens.thickness.dtype == lens.epd.dtype == jnp.float64
    g = jax.grad(lambda t: dataclasses.replace(cooke, thickness=t).total_track())(
        lens.thickness)
    assert g.dtype == jnp.float64 and bool(jnp.all(g == 1.0))
    # a lens built under jit (traced values) is still accepted
    f = jax.jit(lambda t: dataclasses.replace(cooke, thickness=t, epd=t[0]).total_track())
    assert float(f(t)) == float(jnp.sum(t))


@pytest.mark.parametrize("dtype", [jnp.int32, "float16", "foo"])
def test_load_dtype_is_float32_or_float64(dtype):
    with pytest.raises(ValueError, match=r"load: dtype must be float32 or float64"):
        jl.load(COOKE, dtype=dtype)
    assert jl.load(COOKE, dtype="float32").thickness.dtype == jnp.float32


def test_save_zmx_names_the_options_it_takes(cooke, tmp_path):
    with pytest.raises(ValueError, match=r"save: \.zmx takes the options \['model_glass'\], "
                                         r"got \['foo'\]"):
        jl.save(cooke, tmp_path / "x.zmx", foo=1)
    assert not (tmp_path / "x.zmx").exists()


@pytest.mark.parametrize("make, match", [
    (lambda: jl.Sphere("0.1"), r"Sphere: c must be a real number .*1/mm\), got str '0\.1'"),
    (lambda: jl.Standard(c=0.01, k=True), r"surface: k must be .* got bool True"),
    (lambda: jl.EvenAsphere(coeffs=["0", 1e-5]), r"surface: coeffs must be"),
    (lambda: jl.Hybrid(odd_x=[1j], odd_y=[0.0]), r"surface: odd_x must be .* got list"),
    (lambda: jl.Sphere(0.02, semi_diameter="10"), r"Sphere: semi_diameter must be .*\(mm\)"),
    (lambda: CoordinateBreak(tilt_x="5"), r"surface: tilt_x must be .*\(deg\), got str"),
    (lambda: Toroidal(cx="0.1"), r"surface: cx must be .*1/mm\), got str"),
    (lambda: ParaxialSurface(focal_length="50"), r"surface: focal_length must be .*\(mm\)"),
    (lambda: jl.ModelGlass("1.5", 50.0), r"ModelGlass: nd must be a real number"),
    (lambda: jl.Sellmeier([1.0, "0"], [0.01, 0.02]), r"Sellmeier: B must be"),
])
def test_surface_parameters_of_the_wrong_type_are_type_errors(make, match):
    with pytest.raises(TypeError, match=match):
        make()
    assert jl.Sphere(0).c.dtype == jnp.float64  # an integer is a float curvature

