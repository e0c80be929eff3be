"""Round 15 of bad-input and silent-answer probes (``tools/audit15_probe.py``).

An AGF glass record that disagrees with itself (its NM record's nd against its CD record's
formula, a CD or LD record given twice, a formula number 2.7), a number token that only
Python reads (``1_03961212``), ``is_stop`` on a JSON file's object or image row, a ``Lens``
with a sensor or name of the wrong type, ``register_catalog`` of something that is neither a
file nor a mapping, and the classical CLI's comma lists with an empty entry.
"""

import json
import os

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.experiments import classical
from jaxlens.io import zmx
from jaxlens.io.lensfile import lens_from_dict
from jaxlens.optics import checks
from jaxlens.optics.catalog import parse_agf

HERE = os.path.dirname(__file__)
ROOT = os.path.dirname(HERE)
LENSES = os.path.join(ROOT, "jaxlens", "data", "lenses")

# N-BK7's records (SCHOTT 2013): nd 1.5168, Sellmeier 1 (formula 2).
AGF = """CC test catalog
NM GA 2 517642.251 1.5168 64.17 0 1
CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653
LD 0.3 2.5
"""


def _agf(tmp_path, text, name="X.agf"):
    p = tmp_path / name
    p.write_text(text, newline="")
    return jl.load_agf(p)


def test_a_consistent_agf_record_still_loads(tmp_path):
    m = _agf(tmp_path, AGF)["GA"]
    assert float(m.index(0.5875618)) == pytest.approx(1.5168, abs=1e-5)


AGF_BAD = [
    # (what, old, new, message). Before: each loaded; the index is what the glass then had.
    ("nd of another glass", "1.5168 64.17", "1.9 20",  # n(d) stayed 1.5168, glass_info 1.9
     r"X\.agf:2: glass GA of catalog X: its NM record gives nd 1\.9, but its CD coefficients "
     r"with formula 2 \(Sellmeier 1\) give n = 1\.5168 at the d line"),
    ("wrong formula number", "NM GA 2 ", "NM GA 1 ",  # Schott formula: n(d) = 85.5
     r"X\.agf:2: .*formula 1 \(Schott\) give n = 85\.5"),
    ("formula 2.7", "NM GA 2 ", "NM GA 2.7 ",  # read as formula 2
     r"X\.agf:2: formula number of GA must be a whole number .*got '2\.7'"),
    ("underscore in a coefficient", "CD 1.03961212", "CD 1_03961212",  # n(d) = 10285.9
     r"X\.agf:3: CD coefficients must be finite numbers, got '1_03961212"),
    ("empty CD record", "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 "
     "103.560653", "CD",  # n = 1 at every wavelength
     r"X\.agf:3: CD record of glass GA holds no coefficients"),
    ("CD twice", "LD 0.3", "CD 2 0.1 0 0 0 0\nLD 0.3",  # the second won: n(d) = 1.9533
     r"X\.agf:4: CD record given twice for glass GA \(first on line 3\)"),
    ("LD twice", "LD 0.3 2.5", "LD 0.3 2.5\nLD 0.4 1.0",  # the second range won
     r"X\.agf:5: LD record given twice for glass GA \(first on line 4\)"),
    ("nd NaN", "1.5168 64.17", "nan 64.17",  # catalog_nd NaN
     r"X\.agf:2: nd and Vd of GA must be finite numbers, got 'nan 64\.17'"),
    ("nd below 1", "1.5168 64.17", "0.5 64.17",
     r"X\.agf:2: GA needs nd in \[1, 4\.5\] and Vd >= 0 .*got nd 0\.5, Vd 64\.17"),
    ("negative Vd", "1.5168 64.17", "1.5168 -5",
     r"X\.agf:2: GA needs nd in \[1, 4\.5\] and Vd >= 0 .*got nd 1\.5168, Vd -5"),
    ("LD to inf", "LD 0.3 2.5", "LD 0.3 inf",  # range (0.3, inf)
     r"X\.agf:4: LD wavelengths must be finite numbers, got '0\.3 inf'"),
]


@pytest.mark.parametrize(("what", "old", "new", "match"), AGF_BAD, ids=[c[0] for c in AGF_BAD])
def test_an_agf_record_that_disagrees_with_itself_is_refused_naming_the_line(
        tmp_path, what, old, new, match):
    assert old in AGF
    with pytest.raises(ValueError, match=match):
        _agf(tmp_path, AGF.replace(old, new, 1))


def test_ir_materials_without_d_line_data_still_load():
    """nd 1, Vd 0 is the catalogs' "no d-line data" mark: no nd to compare with."""
    znse = jl.get_material("ZNSE", "INFRARED")
    assert znse.catalog_nd == 1.0 and float(znse.index(10.0)) == pytest.approx(2.4, abs=0.01)


def test_a_record_with_nd_0_and_vd_0_is_read_as_without_d_line_data(tmp_path):
    """nd 0, Vd 0 is the other "no d-line data" mark (a user catalog's IR crystal): the
    record loads, its formula gives its index, and no nd is compared."""
    m = _agf(tmp_path, AGF.replace("1.5168 64.17", "0 0", 1))["GA"]
    assert float(m.index(0.5875618)) == pytest.approx(1.5168, abs=1e-5)


def test_a_bom_kept_by_a_text_read_is_no_part_of_the_first_line():
    """Before: parse_agf gave "CD record before any NM record" on line 2 (the BOM made the
    first NM line's key unknown), and zmx.loads "not a Zemax keyword line" on line 1."""
    assert [r.name for r in parse_agf("\ufeff" + AGF.split("\n", 1)[1])] == ["GA"]
    with open(os.path.join(LENSES, "cooke_triplet.zmx")) as fh:
        text = fh.read()
    lens = zmx.loads("\ufeff" + text, "t.zmx")
    assert float(jl.efl(lens)) == pytest.approx(50.0214, abs=1e-3)


@pytest.mark.parametrize("token", ["4_5e-2", "٤.5e-2", "0x10", "4,5e-2", "1e", "."])
def test_zmx_numbers_are_plain_decimals(token):
    """Before: CURV 4_5e-2 was read as 0.45 (Python's float takes underscores): the Cooke
    triplet's EFL became 4.82 mm instead of 50.02 mm."""
    with open(os.path.join(LENSES, "cooke_triplet.zmx")) as fh:
        text = fh.read()
    old = "CURV 4.5426484276303865E-002"
    assert old in text
    with pytest.raises(ValueError, match=r"t\.zmx:24: curvature is not a number"):
        zmx.loads(text.replace(old, f"CURV {token}"), "t.zmx")


def test_number_text_reads_what_optics_files_write():
    for tok, v in [("1", 1.0), ("-1.5", -1.5), ("+.5", 0.5), ("2.", 2.0), ("1E+001", 10.0),
                   ("1.5D-3", 1.5e-3), ("1.5d2", 150.0), ("INFINITY", np.inf), ("-inf", -np.inf)]:
        assert checks.number_text(tok) == v
    assert np.isnan(checks.number_text("NaN"))


@pytest.mark.parametrize("row", [0, -1], ids=["object", "image"])
def test_json_is_stop_on_the_object_or_image_row_is_refused(row):
    """Before: ignored; the stop stayed on surface 4 (or on surface 1 without another)."""
    with open(os.path.join(LENSES, "cooke_triplet.json")) as fh:
        d = json.load(fh)
    d["surfaces"][row]["is_stop"] = True
    where = "surface 0" if row == 0 else "image surface"
    with pytest.raises(ValueError, match=rf"^t\.json: {where}: the object or image surface "
                                         rf"cannot be the stop"):
        lens_from_dict(d, source="t.json")
    d["surfaces"][row]["is_stop"] = False  # false says nothing: still fine
    assert lens_from_dict(d, source="t.json").stop == 3


@pytest.mark.parametrize(("kw", "match"), [
    (dict(sensor=5), r"Lens: sensor must be None or a jaxlens\.Sensor, got int 5"),
    (dict(sensor=(100, 100)), r"Lens: sensor must be None or a jaxlens\.Sensor, got tuple"),
    (dict(name=5), r"Lens: name must be a string, got int 5"),
])
def test_lens_sensor_and_name_must_be_of_their_type(kw, match):
    """Before: accepted; render failed later on ``sensor.resolution`` of an int."""
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(TypeError, match=match):
        jl.Lens(surfaces=lens.surfaces, thickness=lens.thickness, materials=lens.materials,
                **kw)


def test_register_catalog_names_its_argument():
    """Before: "expected str, bytes or os.PathLike object, not int" from inside open()."""
    with pytest.raises(TypeError, match=r"register_catalog: source must be an \.agf file"):
        jl.register_catalog(5)
    air = jl.Air()
    with pytest.raises(ValueError, match=r"register_catalog: every key must be a glass name"):
        jl.register_catalog({5: air})
    # Before: "GX" silently replaced "gx" (lookups ignore case).
    with pytest.raises(ValueError, match=r"'GX' and another spelling of it differ only in "
                                         r"case"):
        jl.register_catalog({"gx": air, "GX": jl.ModelGlass(nd=1.5, vd=60.0)})


@pytest.mark.parametrize("argv", [["--materials", "E48R,,OKP4", "--elements", "2"],
                                  ["--material-catalogs", "SCHOTT,,CDGM"]])
def test_classical_cli_refuses_an_empty_entry_of_a_list(argv, tmp_path, capsys):
    """Before: the empty entry was dropped, so "E48R,,OKP4" designed 2 elements."""
    assert classical.main(["--smoke", "--out", str(tmp_path / "run"), *argv]) == 2
    err = capsys.readouterr().err
    assert "must be comma-separated names without an empty one" in err
    assert not (tmp_path / "run").exists()


def test_an_optimised_catalog_glass_is_written_with_its_own_nd(tmp_path):
    """A catalog glass whose coefficients were changed (optimised) kept its catalog nd on
    export: the written AGF record said nd 1.5168 beside coefficients giving 1.5254 (and
    the GLAS line too), which load_agf now refuses; the writer gives the model's nd."""
    import equinox as eqx

    agf = tmp_path / "MYCAT.agf"
    agf.write_text(AGF.replace("NM GA", "NM ONE"))
    m = eqx.tree_at(lambda g: g.model.B, jl.load_agf(agf)["ONE"],
                    jl.load_agf(agf)["ONE"].model.B * 1.02)
    lens = jl.Lens(surfaces=(jl.Standard(c=0.02), jl.Standard(c=-0.02), jl.Standard(c=0.0)),
                   thickness=[3.0, 40.0, 0.0], materials=(m, jl.Air(), jl.Air()), epd=5.0)
    out = tmp_path / "out"
    out.mkdir()
    jl.save(lens, out / "u.zmx")
    back = jl.load(out / "u.zmx")
    nd = float(m.index(0.5875618))
    assert nd == pytest.approx(1.52535, abs=1e-5)
    assert float(back.materials[0].index(0.5875618)) == pytest.approx(nd, abs=1e-12)
    assert back.materials[0].catalog_nd == pytest.approx(nd, abs=1e-9)


# ------------------------------------------------ checks that jit, grad and vmap skipped
def _cooke_with_sensor():
    import equinox as eqx

    lens = jl.zoo.cooke_triplet()
    return eqx.tree_at(lambda m: m.sensor, lens, jl.Sensor((16, 16), 0.01),
                       is_leaf=lambda x: x is None)


def _traced_calls():
    import jax
    import jax.numpy as jnp

    from jaxlens.analysis.encircled import encircled_energy, radius_for_fraction
    from jaxlens.imaging import distortion

    lens = _cooke_with_sensor()
    scene = jnp.ones((16, 16, 3))
    # (id, function of one traced argument, its bad value, message). Before: each returned
    # a number without a word, noted beside it.
    return [
        ("radius_for_fraction", lambda f: radius_for_fraction(lens, 0.0, f), 1.5,  # NaN
         r"radius_for_fraction: fraction must be finite numbers in \(0, 1\)"),
        ("radius_for_fraction_negative", lambda f: radius_for_fraction(lens, 0.0, f), -0.5,
         r"radius_for_fraction: fraction must be finite numbers in \(0, 1\)"),  # 9.8e-5 mm
        ("encircled_energy", lambda r: encircled_energy(lens, 0.0, r).energy,
         np.array([-1.0, 0.01]), r"encircled_energy: radii must be finite numbers in "
                                 r"\[0, inf\) mm"),  # energy 0 within -1 mm
        ("psf", lambda p: jl.psf(lens, 0.0, pixel_size=p, kernel_size=7), -1e-3,
         r"psf: pixel_size must be finite numbers in \(0, inf\) mm"),  # a PSF summing to 1
        # A negative penalty, which rewards distortion:
        ("alignment_penalty", lambda a: distortion.alignment_penalty(lens, alpha=a,
                                                                     grid=(3, 3)), -1.0,
         r"alignment_penalty: alpha must be finite numbers in \[0, inf\) \(weight\)"),
        ("inverse_distortion_map", lambda p: distortion.inverse_distortion_map(
            lens, resolution=(8, 8), pixel_size=p, grid=(3, 3)), -0.01,
         r"inverse_distortion_map: pixel_size must be finite numbers in \(0, inf\) mm"),
        ("render", lambda s: jl.render(lens, s, spp=1, key=jax.random.key(0)), -scene,
         r"render: scene must be finite numbers in \[0, inf\) \(linear radiance\)"),
    ]


CALLS = ["radius_for_fraction", "radius_for_fraction_negative", "encircled_energy", "psf",
         "alignment_penalty", "inverse_distortion_map",
         pytest.param("render", marks=pytest.mark.slow)]  # 6.6 s here


@pytest.mark.parametrize("which", CALLS)
def test_a_traced_argument_gets_the_range_check_a_concrete_one_gets(which):
    import equinox as eqx
    import jax.numpy as jnp

    _, fn, bad, match = next(c for c in _traced_calls() if c[0] == which)
    with pytest.raises(Exception, match=match):  # EquinoxRuntimeError, raised at run time
        out = eqx.filter_jit(fn)(jnp.asarray(bad))
        np.asarray(out)


def test_number_of_a_traced_value_keeps_its_range():
    import jax
    import jax.numpy as jnp

    def f(p):
        return checks.number(p, "pixel_size", "probe", lo=0, lo_open=True, unit="mm") * 2.0

    assert float(jax.jit(f)(jnp.asarray(0.5))) == 1.0
    assert float(jax.grad(f)(0.5)) == 2.0
    with pytest.raises(Exception, match=r"probe: pixel_size must be finite numbers in "
                                        r"\(0, inf\) mm"):
        np.asarray(jax.jit(f)(jnp.asarray(-0.5)))
    with pytest.raises(ValueError, match=r"probe: n must be one concrete whole number"):
        jax.jit(lambda n: checks.number(n, "n", "probe", lo=0, integer=True))(3)


@pytest.mark.parametrize("bad", [1.5, 2.0])
def test_psf_max_truncation_is_a_fraction(bad):
    """Before: 2 was taken and could never trigger, the check off without a word."""
    with pytest.raises(ValueError, match=r"psf: max_truncation must be a finite number in "
                                         r"\[0, 1\] \(fraction of the PSF energy"):
        jl.psf(jl.zoo.cooke_triplet(), 0.0, pixel_size=0.005, kernel_size=9,
               max_truncation=bad)


def _sampling_calls():
    import jax.numpy as jnp

    from jaxlens import sampling

    lens = jl.zoo.cooke_triplet()
    grid = sampling.pupil_grid(3)
    # Before, under jit: NaN rays; a depth of -5 mm and a point behind surface 1 launched
    # rays from behind the lens (directions -0.61, 0.79), each without a word.
    return {
        "collimated_nan_pupil": (lambda p: sampling.collimated(lens, 0.0, p).origin,
                                 jnp.full((2, 2), jnp.nan),
                                 r"collimated: pupil \(normalised pupil coordinates\) holds NaN"),
        "field_rays_negative_depth": (
            lambda d: sampling.field_rays(lens, 0.0, grid, depth=d).direction,
            jnp.asarray(0.0), r"field_rays: depth must be finite, nonzero"),  # -5: virtual
        "point_source_behind": (lambda p: sampling.point_source(lens, p, grid).direction,
                                jnp.array([0.0, 0.0, 0.0]),  # z = 5: a virtual object
                                r"point_source: point must be finite \(mm\) with its global z "
                                r"in front of surface 1"),
    }


@pytest.mark.parametrize("which", ["collimated_nan_pupil", "field_rays_negative_depth",
                                   "point_source_behind"])
def test_ray_sources_check_traced_pupils_depths_and_points(which):
    import equinox as eqx

    fn, bad, match = _sampling_calls()[which]
    with pytest.raises(Exception, match=match):
        np.asarray(eqx.filter_jit(fn)(bad))


def test_traced_ray_sources_still_trace_good_input_and_differentiate():
    import jax
    import jax.numpy as jnp

    from jaxlens import sampling

    lens = jl.zoo.cooke_triplet()
    grid = sampling.pupil_grid(3)

    def f(d):
        return sampling.field_rays(lens, 1.0, grid, depth=d).direction[0, 1]

    d0 = 500.0
    want = sampling.field_rays(lens, 1.0, grid, depth=d0).direction[0, 1]
    assert float(jax.jit(f)(jnp.asarray(d0))) == pytest.approx(float(want), abs=1e-14)
    fd = (f(d0 + 1e-3) - f(d0 - 1e-3)) / 2e-3
    assert float(jax.grad(f)(d0)) == pytest.approx(float(fd), rel=1e-5)


@pytest.mark.parametrize(("old", "new", "line", "what"), [
    ("FWGN 1 1 1", "FWGN -1 1 1", 12, "field weight"),
    ("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 -1", 14, "wavelength weight"),
])
def test_zmx_negative_weights_are_refused(old, new, line, what):
    """Before: read, and only reported as unequal weights (a weight is never negative)."""
    with open(os.path.join(LENSES, "cooke_triplet.zmx")) as fh:
        text = fh.read()
    assert old in text
    with pytest.raises(ValueError, match=rf"t\.zmx:{line}: {what} must be >= 0, got -1"):
        zmx.loads(text.replace(old, new), "t.zmx")


@pytest.mark.parametrize("name", ["", "AIR", "air"])
def test_design_spec_refuses_an_element_of_air(name):
    """Before: accepted; "" and "AIR" are air to get_material, an element without power."""
    from jaxlens.design.spec import DesignSpec

    with pytest.raises(ValueError, match=rf"DesignSpec: materials\[1\] '{name}' is air; each "
                                         rf"element needs a glass or plastic"):
        DesignSpec(materials=("E48R", name, "E48R", "OKP4", "E48R", "OKP4"))


def _cooke_dict():
    with open(os.path.join(LENSES, "cooke_triplet.json")) as fh:
        return json.load(fh)


def test_json_image_thickness_other_than_zero_is_refused():
    """Before: ignored (nothing follows the image surface)."""
    d = _cooke_dict()
    d["surfaces"][-1]["thickness"] = 5
    with pytest.raises(ValueError, match=r"^t\.json: image surface: thickness 5 is not read"):
        lens_from_dict(d, source="t.json")
    d["surfaces"][-1]["thickness"] = 0
    assert lens_from_dict(d, source="t.json").num_surfaces == 6


def test_json_number_strings_are_plain_decimals():
    """Before: "2_2.01359" was read as 22.01359 (Python's float takes underscores)."""
    d = _cooke_dict()
    d["surfaces"][1]["radius"] = "2_2.01359"
    with pytest.raises(ValueError, match=r"t\.json: surface 1: radius: expected a number, got "
                                         r"'2_2\.01359'"):
        lens_from_dict(d, source="t.json")
    d["surfaces"][1]["radius"] = "22.01359"  # refused too since round 35b (quoted number)
    with pytest.raises(ValueError, match=r"surface 1: radius: expected a number, got the "
                                         r"string '22\.01359'"):
        lens_from_dict(d, source="t.json")


def test_cli_numbers_are_plain_decimals(tmp_path, capsys):
    """Before: argparse's float and int took "1_0" as 10 (--fov 1_0 designed a 10° lens)."""
    from jaxlens.__main__ import main as jaxlens_main
    from jaxlens.experiments import tolerance

    assert checks.cli_float(" -1.5e-3 ") == -1.5e-3 and checks.cli_int("+12") == 12
    for argv, main, arg, kind in [
        (["--fov", "1_0"], classical.main, "--fov", "float"),
        (["--seeds", "1_0"], classical.main, "--seeds", "int"),
        (["report", os.path.join(LENSES, "cooke_triplet.zmx"), "--fields", "1_0"],
         jaxlens_main, "--fields", "float"),
        ([os.path.join(LENSES, "cooke_triplet.zmx"), "--trials", "1_0"], tolerance.main,
         "--trials", "int"),
    ]:
        out = [] if main is jaxlens_main else ["--out", str(tmp_path / "o")]
        with pytest.raises(SystemExit):
            main([*argv, *out])
        err = capsys.readouterr().err
        assert f"argument {arg}: invalid {kind} value: '1_0'" in err
        assert not (tmp_path / "o").exists()
