"""The EDoF experiment's base lens meets the paper's spec, and the command that designs it runs.

The shipped ``jaxlens/data/lenses/edof_classical.json`` must be the paper's EDoF lens (Yang,
Fu & Heidrich, Nat. Commun. 2024): paraxial EFL 5.55 mm, EPD 2.60 mm (F/2.1), the 34.4°
corner field on the 3.60 mm sensor corner, focused at 20 cm, 4–6 plastic elements. Every
number is computed here by the library's paraxial and real-ray functions.
"""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.analysis.spots import chief_ray, rms_spot
from jaxlens.design import DesignSpec, Objective, RayLoss, StageArgs
from jaxlens.design.init import gap_bounds, parameterization, random_params
from jaxlens.experiments.edof import design as D
from jaxlens.experiments.edof import lenses as L
from jaxlens.optics import paraxial

HALF_FOV = 34.4
RGB = jnp.asarray(L.WAVELENGTHS_RGB)

# Objectives evaluated compiled: one program per objective (and method), shared by the tests
# below; op-by-op, the first evaluation took longer than compiling.
_jit_call = eqx.filter_jit(lambda f, params, args: f(params, args))


@pytest.fixture(scope="module")
def lens():
    return L.classical_lens()


def _fields():
    """The 9 field angles of the spot tests, 0 … HALF_FOV (deg): one shape, so every spot
    test of this file runs one compiled program."""
    return jnp.asarray(np.linspace(0.0, HALF_FOV, 9))


def _mean_rms(lens, depth, fields=None):
    fields = _fields() if fields is None else fields
    # The depth as an array: a traced argument, so every depth and sensor shift of a test
    # runs one compiled program (a Python float is static: one compile per depth).
    r = rms_spot(lens, jnp.asarray(fields), RGB, depth=jnp.asarray(depth, jnp.float64))
    r = r.polychromatic
    return float(jnp.sqrt(jnp.mean(r**2)))


def test_paraxial_efl_and_f_number(lens):
    pd = paraxial.paraxial_data(lens)
    # The old 4-element lens had EFL 4.91 mm and F/1.89: both fail these tolerances.
    assert float(pd.efl) == pytest.approx(5.55, rel=0.01)
    assert float(lens.epd) == pytest.approx(2.60, abs=1e-9)
    assert float(pd.fnum) == pytest.approx(5.55 / 2.60, rel=0.01)
    assert float(paraxial.bfl(lens)) > 0.5


def test_corner_field_fills_the_sensor_diagonal(lens):
    half_diag = 0.5 * 1024 * 0.00497 * math.sqrt(2)
    assert half_diag == pytest.approx(3.60, abs=0.005)
    efl = float(paraxial.efl(lens))
    at_infinity = eqx.tree_at(lambda m: m.object_distance, lens, None,
                              is_leaf=lambda x: x is None)
    for lens_d, depth in ((at_infinity, None), (lens, L.FOCUS_DEPTH)):
        h = float(chief_ray(lens_d, HALF_FOV, 0.587, depth=depth).origin[1])
        assert 3.40 <= h <= 3.60, (depth, h)
        # Barrel distortion: the corner lands inside EFL·tanθ = 3.80 mm.
        assert h < efl * math.tan(math.radians(HALF_FOV)) - 0.1


def test_focused_at_20cm(lens):
    # The mean RMS at 20 cm is smallest with the sensor where the file puts it.
    shifts = np.linspace(-0.06, 0.06, 13)
    vals = [_mean_rms(D.with_back_gap(lens, dt), L.FOCUS_DEPTH) for dt in shifts]
    assert abs(shifts[int(np.argmin(vals))]) <= 0.011, vals
    # ... and focus at 20 cm beats 10 cm and 10 m clearly.
    at = {d: _mean_rms(lens, d) for d in (100.0, 200.0, 1e4)}
    assert at[200.0] < 0.5 * min(at[100.0], at[1e4]), at


def test_good_spots_and_every_ray_through(lens):
    r = rms_spot(lens, _fields(), RGB, depth=L.FOCUS_DEPTH)
    # At 20 cm a few rim rays of the outer fields miss (3 % at worst; at infinity none).
    assert float(jnp.min(r.valid_fraction)) >= 0.95
    rms_um = 1e3 * np.asarray(r.polychromatic)
    assert np.all(np.isfinite(rms_um))
    assert float(np.sqrt(np.mean(rms_um**2))) < 8.0, rms_um  # about 1.5 pixels of 4.97 µm
    assert float(np.max(rms_um)) < 15.0, rms_um


def test_structure_sensor_and_plastics(lens):
    from jaxlens.optics.catalog import get_material

    assert lens.stop == 0
    n_elements = (lens.num_surfaces - 1) // 2
    assert 4 <= n_elements <= 6
    names = [m.name for m in lens.materials[1:-1:2]]
    assert len(names) == n_elements
    for name in names:  # plastics: catalog materials with nd < 1.70
        assert float(get_material(name).index(0.5876)) < 1.70, name
    for m in lens.materials[2:-1:2]:  # air between the elements
        assert float(m.index(0.5876)) == 1.0
    assert lens.sensor.resolution == (1024, 1024)
    assert float(lens.sensor.pixel_size) == pytest.approx(0.00497)
    assert float(lens.object_distance) == pytest.approx(200.0)


def test_spec_efl_checks_and_objective_residual():
    with pytest.raises(ValueError, match="efl"):
        DesignSpec(efl=-1.0)
    spec = D.classical_spec(n_elements=4)
    assert spec.efl == pytest.approx(5.55)
    assert spec.epd == pytest.approx(2.60)
    corner = spec.focal_length * math.tan(math.radians(HALF_FOV))
    assert corner == pytest.approx(D.DESIGN_DIAGONAL / 2)
    pmap = parameterization(spec, jnp.float64)
    params = random_params(spec, jax.random.PRNGKey(3), jnp.float64)
    sampling = RayLoss.make(3, 2, spec.wavelengths, spec.sensor_size, jnp.float64)
    gb = jnp.asarray(gap_bounds(spec))
    args = StageArgs(*(jnp.asarray(x, jnp.float64) for x in (
        math.tan(math.radians(HALF_FOV)), spec.epd, spec.focal_length, 1.0, 1.0, 2.5)),
        field_weights=jnp.ones(3), reg_weights=jnp.asarray([40.0, 1000.0, 40.0]),
        distortion_k=jnp.asarray(0.0, jnp.float64))  # an array, as in the test below
    free = Objective(pmap, sampling, gb)
    held = Objective(pmap, sampling, gb, efl=5.55, efl_weight=4.0)
    r0, a0 = _jit_call(free, params, args)
    r1, a1 = _jit_call(held, params, args)
    efl = float(paraxial.efl(pmap.to_lens(params)))
    assert r1.shape[0] == r0.shape[0] + 1
    np.testing.assert_allclose(np.asarray(r1[:-1]), np.asarray(r0))
    assert float(r1[-1]) == pytest.approx(math.sqrt(4.0 * 2.5) * (efl - 5.55))
    assert float(a1.loss) == pytest.approx(float(jnp.sum(r1**2)))
    np.testing.assert_allclose(np.asarray(_jit_call(held.field_rms, params, args)),
                               np.asarray(a1.rms))
    # The residual scales with sqrt(efl_weight · beta · spot_scale); the weight defaults to 1.
    half = eqx.tree_at(lambda a: a.beta, args, jnp.asarray(0.5, jnp.float64))
    assert float(_jit_call(held, params, half)[0][-1]) == pytest.approx(
        math.sqrt(4.0 * 0.5 * 2.5) * (efl - 5.55))
    plain = Objective(pmap, sampling, gb, efl=5.55)
    assert float(_jit_call(plain, params, args)[0][-1]) == pytest.approx(
        math.sqrt(2.5) * (efl - 5.55))
    # With the ideal reference (beta = 0) the ideal image points carry the EFL: no residual.
    args0 = eqx.tree_at(lambda a: a.beta, args, jnp.asarray(0.0, jnp.float64))
    assert float(_jit_call(held, params, args0)[0][-1]) == 0.0


def test_design_command_smoke(tmp_path):
    out = tmp_path / "lens.json"
    D.main(["--smoke", "--seeds", "0", "--elements", "4", "--out", str(out),
            "--record-dir", str(tmp_path), "--quiet"])
    for name in ("base_lens.json", "base_lens_spots.png", "base_lens_command.txt"):
        assert (tmp_path / name).stat().st_size > 0, name
    from jaxlens import load

    lens = load(str(out))
    assert lens.sensor.resolution == (1024, 1024)
    assert float(lens.epd) == pytest.approx(2.60)
    with open(tmp_path / "base_lens.json") as f:
        rec = json.load(f)
    assert rec["paraxial"]["efl_mm"] == pytest.approx(float(paraxial.efl(lens)))
    assert set(rec["rms_map"]["mean_um"]) == {"0.1", "0.2", "10"}
    assert rec["design"]["spec"]["efl_target"] == pytest.approx(5.55)
    assert "--smoke" in (tmp_path / "base_lens_command.txt").read_text()


def test_design_command_refuses_to_replace_a_lens_or_record(tmp_path, capsys):
    """Before any design work: an existing --out (by default the lens jaxlens ships) or
    record file is kept unless --overwrite is given, and a folder as --out is refused."""
    out = tmp_path / "lens.json"
    out.write_text("{}")
    for args, words in ((["--out", str(out)], "--overwrite"),
                        (["--out", str(tmp_path / "new.json")], "base_lens.json"),
                        (["--out", str(tmp_path)], "is a folder")):
        (tmp_path / "base_lens.json").write_text("{}")
        with pytest.raises(SystemExit) as e:
            D.main(["--smoke", "--seeds", "0", "--record-dir", str(tmp_path), "--quiet",
                    *args])
        assert e.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0], err
    assert out.read_text() == "{}" and not (tmp_path / "new.json").exists()


def test_image_mapping_puts_the_full_field_on_the_sensor_corner():
    spec = D.classical_spec(n_elements=4)
    f, k = spec.image_mapping()
    t = math.tan(math.radians(HALF_FOV))
    assert f == pytest.approx(5.55)
    assert f * t * (1 + k * t * t) == pytest.approx(spec.half_diagonal, rel=1e-12)
    assert k < 0  # barrel: 5.55 mm · tan 34.4° overfills the sensor
    free = DesignSpec()
    assert free.image_mapping() == (free.focal_length, 0.0)
    # In the loss: with the centroid reference only the pin sees k, and it moves by the
    # change of the full-field target height, −sqrt(pin · scale) · f · tan³θ · k.
    pmap = parameterization(spec, jnp.float64)
    params = random_params(spec, jax.random.PRNGKey(1), jnp.float64)
    sampling = RayLoss.make(3, 2, spec.wavelengths, spec.sensor_size, jnp.float64)
    obj = Objective(pmap, sampling, jnp.asarray(gap_bounds(spec)))

    def residuals(beta, kk):
        args = StageArgs(*(jnp.asarray(x, jnp.float64) for x in (t, spec.epd, f, beta, 1.0, 2.0)),
                         field_weights=jnp.ones(3), reg_weights=jnp.zeros(3),
                         distortion_k=jnp.asarray(kk, jnp.float64))
        return np.asarray(_jit_call(obj, params, args)[0])

    n_spot = 3 * len(spec.wavelengths) * sampling.pupil.shape[0] * 2
    r0, r1 = residuals(1.0, 0.0), residuals(1.0, k)
    np.testing.assert_allclose(r1[:n_spot], r0[:n_spot])
    assert r1[n_spot] - r0[n_spot] == pytest.approx(-math.sqrt(2.0) * f * t**3 * k)
    # With the ideal reference the spot residuals change (the ideal points move).
    assert not np.allclose(residuals(0.0, k)[:n_spot], residuals(0.0, 0.0)[:n_spot])
