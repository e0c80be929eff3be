"""Round 14 of bad-input and silent-answer probes: a keyword given twice in a ``.zmx`` file,
and exported designs re-evaluated by an independent tool (optiland 0.6.3).

A second ``CURV``/``DISZ``/``CONI``/``GLAS``/``TYPE``/``PARM i`` line in one SURF block, a
second system aperture (``ENPD`` twice, or ``FNUM`` beside ``ENPD``), or a repeated ``WAVM i``,
``PWAV`` or ``FTYP`` used to replace the first value without a word (the last one won); each
is now refused naming both lines. No real file in the corpus repeats one.
"""

import os
import re

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis.report import report_data
from jaxlens.io import zmx

HERE = os.path.dirname(__file__)
ROOT = os.path.dirname(HERE)
COOKE_ZMX = os.path.join(ROOT, "jaxlens", "data", "lenses", "cooke_triplet.zmx")
SEED0_ZMX = os.path.join(ROOT, "experiments", "classical", "designs", "seed_0.zmx")


def _text():
    with open(COOKE_ZMX) as fh:
        return fh.read()


# ---------------------------------------------------------------- keywords given twice
SURFACE_REPEATS = [
    # (what, old text, new text, line of the repeat, keyword named)
    ("CURV", 'CURV -2.2948388798212154E-003 0 0 0 0 ""',
     'CURV -2.2948388798212154E-003 0 0 0 0 ""\n  CURV 0.1', 32, "CURV"),
    ("DISZ", "DISZ 6.00755E+000", "DISZ 6.00755E+000\n  DISZ 7", 34, "DISZ"),
    ("CONI", "CONI 0\n  DISZ 3.25896E+000", "CONI 0\n  CONI -1\n  DISZ 3.25896E+000", 26,
     "CONI"),
    ("GLAS", "GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0",
     "GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0\n  GLAS N-BK7", 41, "GLAS"),
    ("TYPE", "SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE STANDARD\n  TYPE EVENASPH", 31,
     "TYPE"),
    ("PARM", "SURF 2\n  TYPE STANDARD",
     "SURF 2\n  TYPE EVENASPH\n  PARM 2 1e-5\n  PARM 2 2e-5", 32, "PARM 2"),
]


@pytest.mark.parametrize(("what", "old", "new", "line", "key"), SURFACE_REPEATS,
                         ids=[r[0] for r in SURFACE_REPEATS])
def test_a_surface_keyword_given_twice_is_refused_naming_both_lines(what, old, new, line, key):
    """The second line used to win silently: a second CURV 0.1 turned the Cooke triplet's
    EFL from 50.02 mm to -40.62 mm, a second GLAS N-BK7 to 39.28 mm."""
    text = _text()
    assert old in text
    with pytest.raises(ValueError, match=rf"^t\.zmx:{line}: {key} given twice in surface "
                                         rf"\d \(first on line {line - 1}: .*\); a \.zmx file "
                                         rf"gives it once"):
        zmx.loads(text.replace(old, new, 1), "t.zmx")


TOP_REPEATS = [
    ("ENPD twice", "ENPD 1.0E+001", "ENPD 1.0E+001\nENPD 20", 6,
     r"the system aperture \(ENPD, FNUM, FLOA or OBNA\) given twice \(first on line 5"),
    ("FNUM beside ENPD", "ENPD 1.0E+001", "ENPD 1.0E+001\nFNUM 3 0", 6,
     r"the system aperture \(ENPD, FNUM, FLOA or OBNA\) given twice \(first on line 5"),
    ("WAVM 1 twice", "WAVM 2 5.875618E-001 1", "WAVM 1 5.875618E-001 1\nWAVM 2 0.6 1", 14,
     r"WAVM 1 given twice \(first on line 13"),
    ("PWAV twice", "PWAV 2", "PWAV 2\nPWAV 1", 17, r"PWAV given twice \(first on line 16"),
    ("YFLN twice", "YFLN 0 1.4E+001 2.0E+001", "YFLN 0 1.4E+001 2.0E+001\nYFLN 0 1 2", 12,
     r"YFLN given twice \(first on line 11"),
]


@pytest.mark.parametrize(("what", "old", "new", "line", "match"), TOP_REPEATS,
                         ids=[r[0] for r in TOP_REPEATS])
def test_a_system_keyword_given_twice_is_refused_naming_both_lines(what, old, new, line, match):
    """ENPD 20 after ENPD 10 halved the F/# without a word; FNUM 3 after ENPD 10 made the
    EPD 16.7 mm; WAVM 1 given twice dropped the first wavelength."""
    text = _text()
    assert old in text
    with pytest.raises(ValueError, match=rf"^t\.zmx:{line}: {match}"):
        zmx.loads(text.replace(old, new, 1), "t.zmx")


def test_a_bad_value_on_a_repeated_line_is_still_named_first():
    """The value check comes before the repeat check: an infinite DISZ after a surface's own
    is refused as an infinite thickness, as before; a bad number as a bad number."""
    text = _text()
    with pytest.raises(ValueError, match=r"^t\.zmx:34: only the object surface may have an "
                                         r"infinite thickness"):
        zmx.loads(text.replace("DISZ 6.00755E+000", "DISZ 6.00755E+000\n  DISZ INFINITY"),
                  "t.zmx")
    with pytest.raises(ValueError, match=r"^t\.zmx:32: curvature is not a number"):
        zmx.loads(text.replace('CURV -2.2948388798212154E-003 0 0 0 0 ""',
                               'CURV -2.2948388798212154E-003 0 0 0 0 ""\n  CURV 1x'), "t.zmx")


def test_repeated_keywords_that_zemax_writes_still_load():
    """PARM and WAVM once per index, several SURF blocks' CURV, COMM and STOP: unchanged."""
    text = _text()
    lens = zmx.loads(text, "t.zmx")
    assert float(jl.paraxial_data(lens).efl) == pytest.approx(50.02135071940371, rel=1e-14)
    asph = text.replace("SURF 2\n  TYPE STANDARD",
                        "SURF 2\n  TYPE EVENASPH\n  PARM 1 0\n  PARM 2 1e-7\n  COMM a\n  COMM b")
    assert zmx.loads(asph, "t.zmx").surfaces[1].coeffs.shape == (2,)


# ------------------------------------------------------------- exported designs, optiland
# optiland 0.6.3's numbers for the same files, from
#   PYTHONPATH=$PWD /work/optiland_venv/bin/python tools/export_reevaluation.py \
#       jaxlens/data/lenses experiments/classical/designs --json out.json
# (EFL = paraxial.f2(), F/# = paraxial.FNO(), BFL = last gap + paraxial.F2(), total track,
# real chief-ray heights from trace_generic(0, Hy, 0, 0), f-tanθ distortion of them, RMS
# spot radius about the centroid of jaxlens's 21 × 21 pupil grid, µm, [field][wavelength]).
OPTILAND_COOKE = {  # the shipped .zmx, optiland's own SCHOTT data (N-SK16, F2)
    "efl": 50.021350719403664, "fnum": 5.0021350719403666, "bfl": 42.436440197528285,
    "total_track": 60.17675,
    "chief_y": [0.0, 12.419842759798975, 18.136103852552097],
    "distortion": [0.0, -0.4159867294587282, -0.3854652160722294],
    "rms_um": [[3.9353041912516904, 4.822262858276877, 6.975567210493434],
               [13.657777975289346, 15.248884186133798, 16.956358236588596],
               [13.287237077470175, 10.288516091991585, 10.5311742005171]],
}
# The classical experiment's exported seed 0, optiland given jaxlens's media (the tool's
# set_media): optiland 0.6.3 resolves the name E48R to refractiveindex.info's Sultanova 2009
# measurement, nd 1.5305159 (``OPTILAND_E48R_ND``), where Zemax's ZEON catalog and jaxlens
# give 1.53117, so with its own data its EFL is 5.38603 mm, 0.19 % longer, and its RMS spots
# differ by up to 24 %: the glass data differ, not the export.
OPTILAND_SEED0 = {
    "efl": 5.375596831401597, "fnum": 2.3890295057118576, "bfl": 1.207420627173206,
    "total_track": 7.0,
    "chief_y": [0.0, 0.9300607051094651, 1.9238708049453632, 3.027712381584738,
                3.831496781863851],
    "distortion": [0.0, -2.869743493663415, -2.7284245473968745, -3.6142604038797974,
                   -16.251280926218193],
    "rms_um": [[7.971285603515813, 12.712246447208717, 14.652598498949473],
               [4.286463727101111, 8.512948246870614, 10.306466716740767],
               [6.224589742057768, 4.173286966251582, 4.180509208831185],
               [11.154045083700517, 8.134238517716284, 7.078674584710904],
               [10.607272673507058, 10.492756722660184, 10.742223507384338]],
}  # [4][2] recomputed 2026-12-01: the file was re-exported with its clear apertures (096565d),
#    which clip one corner-field rim ray (10.749534174373895 before, from the file without)
OPTILAND_E48R_ND = 1.5305159356328049


def _agrees(path, ref, *, rms_rtol):
    d = report_data(jl.load(path))
    for k, jk in (("efl", "efl_image_space"), ("fnum", "fnum"), ("bfl", "bfl"),
                  ("total_track", "total_track")):
        assert d[jk] == pytest.approx(ref[k], rel=1e-12), k
    f = d["fields"]
    np.testing.assert_allclose([x["chief_ray_height"] for x in f], ref["chief_y"], atol=1e-12)
    np.testing.assert_allclose([x["distortion"] for x in f], ref["distortion"], atol=1e-10)
    np.testing.assert_allclose([x["rms_spot"] for x in f], ref["rms_um"], rtol=rms_rtol)


@pytest.mark.parametrize(("path", "ref"), [(COOKE_ZMX, OPTILAND_COOKE),
                                           (SEED0_ZMX, OPTILAND_SEED0)], ids=["cooke", "seed0"])
def test_paraxial_numbers_of_exported_files_match_optiland(path, ref):
    """EFL (image space), F/#, BFL and total track, without the report's compile."""
    p = jl.paraxial_data(jl.load(path))
    for k, v in (("efl", p.efl_image_space), ("fnum", p.fnum), ("bfl", p.bfl),
                 ("total_track", p.total_track)):
        assert float(v) == pytest.approx(ref[k], rel=1e-12), k


@pytest.mark.slow
def test_shipped_cooke_zmx_reads_the_same_in_optiland():
    """EFL, F/#, BFL, track, chief rays, distortion and RMS spots of the shipped file agree
    with optiland's (its own glass data) to rounding."""
    _agrees(COOKE_ZMX, OPTILAND_COOKE, rms_rtol=1e-11)


@pytest.mark.slow
def test_exported_classical_design_reads_the_same_in_optiland():
    """Aspheres (A4…A14 with conics of -50…30, written on their closest conic), the stop in
    front, the E48R/OKP4 plastics: with the same media, optiland agrees to rounding."""
    _agrees(SEED0_ZMX, OPTILAND_SEED0, rms_rtol=1e-11)


def test_exported_e48r_is_zemax_catalog_data_and_its_glas_line_says_so(tmp_path):
    """The written GLAS line carries jaxlens's nd and Vd of E48R (Zemax's ZEON data), which
    differs from optiland's E48R by 6.4e-4: a re-evaluation there needs jaxlens's media
    (tools/export_reevaluation.py does both)."""
    e48r = jl.get_material("E48R")
    nd = float(e48r.index(0.5875618))
    assert nd == pytest.approx(1.53117, abs=2e-5)
    assert nd - OPTILAND_E48R_ND == pytest.approx(6.5e-4, abs=2e-5)
    with open(SEED0_ZMX) as fh:
        glas = [ln.split() for ln in fh if ln.strip().startswith("GLAS E48R")]
    assert glas and all(float(g[4]) == pytest.approx(nd, abs=1e-5) for g in glas)


# ----------------------------------------------------------------------- report CLI
def _report(capsys, *args):
    from jaxlens.__main__ import main

    code = main(["report", COOKE_ZMX, *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("wl", [("0.5875618", "587.5618"), ("0.5", "0.5")])
def test_report_refuses_a_wavelength_given_twice(capsys, wl):
    """0.5875618 and 587.5618 (nm) are one wavelength: it was reported twice and weighed
    twice in the polychromatic RMS spot, without a word."""
    code, out, err = _report(capsys, "--wavelengths", *wl)
    assert code == 2 and out == ""
    assert re.search(r"report: --wavelengths gives 0\.5\d* µm twice \(values above 100 are "
                     r"read as nm\)", err), err


@pytest.mark.parametrize("extra", [("--json",), ("--config", "1"), ("--config", "0"),
                                   ("--fields", "5"), ("--wavefront",)])
def test_report_list_configs_refuses_options_it_would_ignore(capsys, extra):
    """--list-configs --json printed the text listing: the --json was dropped silently."""
    code, out, err = _report(capsys, "--list-configs", *extra)
    assert code == 2 and out == ""
    assert f"--list-configs lists the configurations and stops; {extra[0]} would be " \
           f"ignored: leave it out" in err
    assert _report(capsys, "--list-configs")[0] == 0


# ------------------------------------------------------------ side AGF catalogs on save
def _singlet(glass):
    import jax.numpy as jnp

    return jl.Lens(surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
                   thickness=jnp.array([4.0, 45.0]),
                   materials=(jl.get_material(glass), jl.Air()), epd=8.0,
                   fields=jnp.array([0.0, 5.0]))


def test_save_zmx_never_replaces_a_catalog_it_did_not_write(tmp_path):
    """A PLASTICS.AGF of the user's own beside the file was replaced by a one-glass catalog
    without a word; now the save is refused before anything is written."""
    own = tmp_path / "PLASTICS.AGF"
    own.write_text("CC my catalog\nNM MYGLASS 1 500600 1.5 60 0 0 0\n")
    with pytest.raises(ValueError, match=r"save_zmx: .*PLASTICS\.AGF exists and was not "
                                         r"written by jaxlens"):
        jl.save(_singlet("OKP4"), tmp_path / "a.zmx")
    assert own.read_text() == "CC my catalog\nNM MYGLASS 1 500600 1.5 60 0 0 0\n"
    assert not (tmp_path / "a.zmx").exists()


def test_lens_files_of_one_folder_share_its_side_catalog(tmp_path):
    """b.zmx (OKP4HT) saved after a.zmx (OKP4) rewrote PLASTICS.AGF with OKP4HT alone, so
    a.zmx no longer found its glass in its folder; the catalog now keeps both."""
    written = jl.save(_singlet("OKP4"), tmp_path / "a.zmx")
    assert [os.path.basename(w) for w in written[1:]] == ["PLASTICS.AGF"]
    jl.save(_singlet("OKP4HT"), tmp_path / "b.zmx")
    jl.save(_singlet("OKP4"), tmp_path / "a.zmx")  # saved again: the same record, kept once
    cat = jl.load_agf(tmp_path / "PLASTICS.AGF")
    assert sorted(cat) == ["OKP4", "OKP4HT"]
    for name, glass in (("a.zmx", "OKP4"), ("b.zmx", "OKP4HT")):
        lens = jl.load(tmp_path / name)
        assert float(lens.materials[0].index(0.5875618)) == pytest.approx(
            float(jl.get_material(glass).index(0.5875618)), abs=1e-12)


# ------------------------------------------------------- JSON lens files (lead, round 14)


def _cooke_json():
    import json

    path = os.path.join(os.path.dirname(jl.__file__), "data", "lenses", "cooke_triplet.json")
    with open(path) as fh:
        return json.load(fh)


def _load_json(tmp_path, d):
    import json

    p = tmp_path / "l.json"
    p.write_text(json.dumps(d))
    return jl.load(p)


def test_a_null_curvature_is_refused_not_read_flat(tmp_path):
    # "curvature": null read as absent: the Cooke triplet's EFL became -935.5 mm.
    for key in ("curvature", "radius"):
        d = _cooke_json()
        d["surfaces"][1].pop("curvature", None)
        d["surfaces"][1].pop("radius", None)
        d["surfaces"][1][key] = None
        with pytest.raises(ValueError, match=rf"surface 1: {key} is null; give a number"):
            _load_json(tmp_path, d)


def test_an_aperture_given_twice_must_agree(tmp_path):
    d = _cooke_json()
    d.pop("epd", None)
    d["aperture"] = {"epd": 10.0}
    efl = float(jl.efl(_load_json(tmp_path, d)))
    d["aperture"] = {"epd": 10.0, "fnum": efl / 10.0}  # the same pupil: accepted
    assert float(_load_json(tmp_path, d).epd) == 10.0
    d["aperture"] = {"epd": 10.0, "fnum": 4.0}  # fnum was ignored without a word
    with pytest.raises(ValueError, match=r"aperture\.epd 10 and aperture\.fnum 4 disagree: they "
                                         r"give entrance pupil diameters of 10 and 12\.5"):
        _load_json(tmp_path, d)


def test_a_declared_wavelength_unit_must_be_the_keys(tmp_path):
    d = _cooke_json()
    d["wavelengths_um"] = [w / 1000.0 for w in d.pop("wavelengths_nm")]
    d["units"] = {"length": "mm", "wavelength": "nm"}
    with pytest.raises(ValueError, match=r"units\.wavelength is 'nm', but the wavelengths are "
                                         r"given as 'wavelengths_um', which is read in µm"):
        _load_json(tmp_path, d)
    d["units"] = {"length": "mm", "wavelength": "um"}
    _load_json(tmp_path, d)


@pytest.mark.parametrize(("argv", "msg"), [
    (["--seed-list", "1,2", "--seeds", "3"], "--seeds would be ignored with --seed-list"),
    (["--seed-list", "1,2", "--first-seed", "0"],
     "--first-seed would be ignored with --seed-list"),
    (["--smoke", "--seeds", "3"], "--seeds would be ignored with --smoke"),
])
def test_an_overridden_option_given_at_its_default_value_is_refused(argv, msg, tmp_path, capsys):
    # Compared with the defaults, "--seeds 3" (the default) looked not given and was ignored.
    from jaxlens.experiments import classical

    assert classical.main([*argv, "--out", str(tmp_path / "o")]) == 2
    assert msg in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
