"""Bad input, round 35b (tools/audit35b_probe.py): the public names the probes named least,
and round 34b's leftovers. One test per gap fixed; each names what main did with the input:
a warning that named an inner function, a figure that traced each field twice, an EXR
image written as all 0, quoted numbers in a JSON lens read as numbers, AGF OD records not
checked, a weakly typed paraxial field, traced values that passed unchecked (a wavelength
in nm, a negative RMS), a field of 100° matched to nothing, an MTF slope halved at 0."""

import json
import math
import pathlib
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
import jaxlens.analysis as A
from jaxlens.analysis import encircled
from jaxlens.io import images as IM
from jaxlens.io.lensfile import lens_from_dict
from jaxlens.optics import agf

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"
KEPLER = ROOT / "tests" / "data" / "afocal_kepler.zmx"
R10 = math.radians(10.0)


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


def _user_warnings(fn):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        out = fn()
    return out, [str(x.message) for x in w if issubclass(x.category, UserWarning)]


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda L, p: A.encircled_energy(L, R10, jnp.array([0.01]), pupil=p), "encircled_energy"),
        (
            lambda L, p: A.radius_for_fraction(L, R10, 0.8, pupil=p, reference="chief"),
            "radius_for_fraction",
        ),
    ],
)
def test_radian_field_warning_names_the_function_called(cooke, call, name):
    """Before: the warning named spot_rays (the inner trace), once per wavelength."""
    _, said = _user_warnings(lambda: call(cooke, jl.sampling.pupil_grid(5)))
    assert len(said) == 1 and said[0].startswith(
        f"{name}: field 0.174533 look like angles in radians"
    ), said


def test_encircled_energy_figure_traces_each_field_once(cooke, monkeypatch):
    """Before: radius_for_fraction, then encircled_energy: 2 traces a field (4 here), and a
    radian field warned as spot_rays."""
    from jaxlens import plot

    calls = []

    def counted(lens, *a, **k):  # 3 rays at 0, 1 and 2 µm from the centre: no trace
        calls.append(1)
        d = jnp.array([0.0, 1e-3, 2e-3])
        return d, jnp.ones(3), jnp.asarray(3.0), jnp.zeros(2), jnp.zeros(())

    monkeypatch.setattr(encircled, "_geometric_samples", counted)
    fig, said = _user_warnings(lambda: plot.plot_encircled_energy(cooke, [0.0, R10]))
    assert len(calls) == 2
    assert said and all(s.startswith("plot_encircled_energy: field ") for s in said), said
    assert fig is not None


def test_energy_samples_give_what_the_two_analyses_give(cooke):
    lens, pupil = cooke, jl.sampling.pupil_grid(5)
    s = encircled.energy_samples(lens, 10.0, pupil=pupil)
    r = jnp.array([0.002, 0.005, 0.01], jnp.float32)
    np.testing.assert_array_equal(
        encircled.energy_within(s, r).energy, A.encircled_energy(lens, 10.0, r, pupil=pupil).energy
    )
    np.testing.assert_array_equal(
        encircled.radius_holding(s, jnp.array([0.5, 0.8])),
        A.radius_for_fraction(lens, 10.0, jnp.array([0.5, 0.8]), pupil=pupil),
    )


def test_exr_image_that_would_be_all_zero_is_refused(tmp_path):
    """Before: all 1e-50 was written as a black image (float32 holds nothing below 1.4e-45)."""
    for fn in (
        lambda v: IM.write_exr(tmp_path / "a.exr", v),
        lambda v: IM.write_psf_stack(tmp_path / "s.exr", v[None]),
    ):
        with pytest.raises(
            ValueError,
            match=r"below float32's least magnitude .*got at most "
            r"1e-50",
        ):
            fn(np.full((3, 3), 1e-50))
    IM.write_exr(tmp_path / "b.exr", np.array([[1.0, 1e-50, 1e-40]]))  # rounding, documented
    np.testing.assert_array_equal(IM.read_exr(tmp_path / "b.exr"), np.float32([[1.0, 0.0, 1e-40]]))


@pytest.mark.parametrize(
    "edit, where, given",
    [
        (lambda d: d["surfaces"][1].update(thickness="5"), "surface 1: thickness", "5"),
        (lambda d: d["surfaces"][1].update(conic=" -1 "), "surface 1: conic", " -1 "),
        (lambda d: d["fields"].update(values=["0", "14", "20"]), r"fields\[0\]", "0"),
        (lambda d: d.update(aperture={"epd": "10"}), r"aperture\.epd", "10"),
        (lambda d: d["surfaces"][1].update(material={"nd": "1.62", "vd": 60}), "nd", "1.62"),
        (
            lambda d: d.update(wavelengths_nm=["486.1327", 587.5618, 656.2725]),
            r"wavelengths_nm\[0\]",
            r"486\.1327",
        ),
    ],
)
def test_json_quoted_numbers_are_refused_with_their_key(edit, where, given):
    """Before: read as numbers (the format documents only "inf" strings)."""
    d = json.loads(COOKE.read_text())
    edit(d)
    with pytest.raises(
        ValueError,
        match=rf"{where}: expected a number, got the string "
        rf"'{given}'; write numbers without quotes",
    ):
        lens_from_dict(d, source="t.json")


def test_json_infinity_strings_and_n_table_keys_still_read():
    d = json.loads(COOKE.read_text())
    d["surfaces"][1]["semi_diameter"] = "Infinity"
    assert math.isinf(float(lens_from_dict(d).surfaces[0].semi_diameter))
    ref = jl.load(ROOT / "tests" / "refcases" / "cooke_triplet.json")  # "n": {"<nm>": n}
    assert float(jl.efl(ref)) == pytest.approx(50.02, abs=0.01)


def _agf(od: str) -> str:
    return (
        "CC t\nNM G1 2 0 1.5168 64.17 0 0 0\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
        f"TD 0 0 0 0 0 0 20\n{od}\nLD 0.3 2.5\n"
    )


@pytest.mark.parametrize(
    "od, match",
    [
        ("OD 1.0 x 0 1 1 1", r"t\.agf:5: OD values \(other data: .*\) must be finite numbers"),
        ("OD 1,2 1 0 1 1 1", r"t\.agf:5: OD values"),
        ("OD -1 -1 -1 -1 -1 -1 0.3 2.5", r"t\.agf:5: OD holds at most 6 values .*got 8"),
    ],
)
def test_agf_od_records_are_checked(od, match):
    """Before: skipped whatever they held."""
    with pytest.raises(ValueError, match=match):
        agf.parse_agf(_agf(od), "t.agf")
    for good in ("OD -1 -1 -1 -1 -1 -1", "OD 1.2 1"):
        assert len(agf.parse_agf(_agf(good), "t.agf")) == 1


def test_paraxial_data_fields_are_all_strongly_typed(cooke):
    """Before: entrance_pupil_diameter (the lens's weak epd) alone took bfloat16 from
    a bfloat16 operand; the other fields kept float32."""
    pd = jl.paraxial_data(cooke)
    assert not any(getattr(pd, k).weak_type for k in pd.__dataclass_fields__)
    x = jnp.ones(2, jnp.bfloat16)
    assert (x * pd.entrance_pupil_diameter).dtype == (x * pd.efl).dtype


def _jit_error(fn, *args):
    with pytest.raises(Exception) as e:  # noqa: PT011 (an EquinoxRuntimeError or XlaRuntimeError)
        jax.block_until_ready(jax.jit(fn)(*args))
    return str(e.value)


def test_angular_magnification_checks_a_traced_wavelength():
    """Before: under jit, 550 (nm) gave -6.8 for the 4x telescope's -4."""
    kep = jl.load(KEPLER)
    said = _jit_error(lambda w: A.angular_magnification(kep, w), jnp.asarray(550.0))
    assert "angular_magnification: wavelength outside" in said
    assert float(jax.jit(lambda w: A.angular_magnification(kep, w))(0.55)) == pytest.approx(
        float(A.angular_magnification(kep, 0.55))
    )


def test_marechal_strehl_checks_a_traced_rms():
    """Before: under jit, -0.1 waves gave 0.674 (as 0.1 does)."""
    said = _jit_error(A.marechal_strehl, jnp.asarray(-0.1))
    assert "marechal_strehl: rms_waves must be an RMS wavefront error, >= 0" in said
    assert math.isnan(float(jax.jit(A.marechal_strehl)(jnp.nan)))  # a field without rays


def test_wavefront_strehl_adds_no_error_if(monkeypatch):
    seen = []
    monkeypatch.setattr(eqx, "error_if", lambda x, *a, **k: (seen.append(a), x)[1])
    wf = A.Wavefront(*(jnp.zeros(()) for _ in range(10)))
    jax.jit(lambda r: eqx.tree_at(lambda w: w.rms_tilt_removed, wf, r).strehl)(0.05)
    assert seen == []


def test_field_vignetting_refuses_a_field_out_of_range(cooke):
    """Before: 100° (or three fields) matched no field and gave zeros."""
    with pytest.raises(ValueError, match=r"field_vignetting: field must be .*got 100 deg"):
        jl.sampling.field_vignetting(cooke, 100.0)
    with pytest.raises(
        ValueError,
        match=r"field_vignetting: field must be one field, .*got "
        r"shape \(3,\)",
    ):
        jl.sampling.field_vignetting(cooke, jnp.array([0.0, 10.0, 20.0]))


def test_diffraction_mtf_slope_at_zero_frequency():
    """Before: −2/(π ν_c), half the slope (jnp.maximum's tie rule at s = 0)."""
    from jaxlens.imaging import otf

    lam, fnum = 0.5e-3, 4.0
    cut = 1.0 / (lam * fnum)
    g = jax.grad(lambda v: otf.diffraction_mtf(v, lam, fnum))(0.0)
    assert float(g) == pytest.approx(-4.0 / (math.pi * cut), rel=1e-6)
    assert float(jax.grad(lambda v: otf.diffraction_mtf(v, lam, fnum))(-1.0)) == 0.0


def test_trace_path_and_trace_backward_refuse_under_their_own_names(cooke):
    """Before: their upto, newton_iters, lens and rays were refused as trace's."""
    rays = jl.sampling.collimated(cooke, 0.0, jl.sampling.pupil_grid(3))
    with pytest.raises(
        ValueError,
        match=r"^trace_path: upto must be a surface index in "
        r"\[0, 5\] \(0-based\), got 99",
    ):
        jl.trace_path(cooke, rays, upto=99)
    with pytest.raises(
        ValueError,
        match=r"^trace_backward: newton_iters must be a whole "
        r"number in \[0, inf\) iterations, got -1",
    ):
        jl.trace_backward(cooke, rays, newton_iters=-1)
    with pytest.raises(
        TypeError,
        match=r"^trace_backward: lens must be a jaxlens\.Lens, "
        r"got str",
    ):
        jl.trace_backward("cooke", rays)
