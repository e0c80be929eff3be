"""Multi-configuration .zmx files: ``config=N`` applies configuration N's operands.

Checks: each configuration of a 3-configuration file equals the same configuration written by
hand as a single-configuration file, leaf for leaf, and their EFL and BFL equal optiland's
(numbers stored below); a 2-configuration singlet pair against a hand paraxial (ABCD)
calculation; the active configuration reads without complaint in strict mode, and a file
whose rows contradict its surfaces is reported; every operand that cannot be applied, a bad
configuration number and malformed rows are refused with the line.
"""

import dataclasses
import os
import re
import warnings

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics import paraxial
from jaxlens.optics.lens import VIGNETTING_COLUMNS

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx_config")
ZOOM = os.path.join(DATA, "zoom.zmx")

# optiland 0.6.3, f2 (n'/Phi) and BFL (F2 + the last DISZ) in mm of the hand-written
# single-configuration files: ``/work/optiland_venv/bin/python tools/zmx_config_reference.py
# tests/data/zmx_config/zoom_c*.zmx``.
OPTILAND = {
    1: (209.08599911864115, 114.26279024207429),
    2: (-1043.1549330693965, -786.3003407059571),
    3: (-1420.410862407141, -1215.0183785241304),
}


def _quiet_load(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # strict reading must not even warn
        return zmx.load_zmx(path, strict=True, **kw)


def _same_optics(a, b):
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    for x, y in zip(la, lb, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


@pytest.mark.parametrize("config", [1, 2, 3])
def test_each_configuration_is_the_hand_written_file(config):
    lens = _quiet_load(ZOOM, config=config)
    single = _quiet_load(os.path.join(DATA, f"zoom_c{config}.zmx"))
    _same_optics(_unnamed(lens), _unnamed(single))
    efl, bfl = OPTILAND[config]
    assert float(jl.paraxial_data(lens).efl_image_space) == pytest.approx(efl, rel=1e-9)
    assert float(paraxial.bfl(lens)) == pytest.approx(bfl, rel=1e-9)


def _unnamed(lens):
    return dataclasses.replace(lens, name="")  # the name is static, not a leaf


def test_the_default_is_the_active_configuration_the_surfaces_hold():
    _same_optics(_quiet_load(ZOOM), _quiet_load(ZOOM, config=1))
    info = zmx.configurations(ZOOM)
    assert (info["count"], info["active"]) == (3, 1)
    rows = {(o["operand"], o["param"]): o["values"] for o in info["operands"]}
    assert rows[("THIC", 2)] == ["20", "10", "5"]
    assert rows[("GLSS", 3)] == ["N-SF5", "N-SF5", "N-F2"]
    assert ("MOFF", 0) not in rows


def _pair(mnum="MNUM 2 1", gap=10.0, rows=None, extra=""):
    """Two singlets of a dispersion-free model glass (nd 1.5) with a gap of ``gap`` mm,
    configuration 2's gap 30 mm."""
    rows = rows if rows is not None else ("THIC 2 1 10 0 0 0 1 1 1 0 0\n"
                                          "THIC 2 2 30 0 0 0 1 1 1 0 0\n")
    glass = "  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"
    return (f"UNIT MM\nENPD 10\nWAVM 1 0.55 1\nSURF 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  CURV 0.01\n  DISZ 4\n{glass}"
            f"SURF 2\n  CURV 0\n  DISZ {gap}\n"
            f"SURF 3\n  CURV 0.02\n  DISZ 3\n{glass}"
            f"SURF 4\n  CURV -0.005\n  DISZ 50\nSURF 5\n  DISZ 0\n{extra}{mnum}\n{rows}")


def _abcd(gap):
    """EFL and BFL of the pair by hand: refraction [[1, 0], [-(n'-n)c/n', n/n']] and transfer
    [[1, t], [0, 1]] on (y, u), in air between the lenses and behind them."""
    n = 1.5
    def refr(c, n1, n2):
        return np.array([[1.0, 0.0], [-(n2 - n1) * c / n2, n1 / n2]])
    def move(t):
        return np.array([[1.0, t], [0.0, 1.0]])
    m = refr(-0.005, n, 1) @ move(3) @ refr(0.02, 1, n) @ move(gap) @ refr(0.0, n, 1) \
        @ move(4) @ refr(0.01, 1, n)
    (a, _), (c, _) = m
    return -1 / c, -a / c


@pytest.mark.parametrize("config, gap", [(1, 10.0), (2, 30.0)])
def test_two_configurations_against_a_hand_calculation(config, gap):
    lens = zmx.loads(_pair(), strict=True, config=config)
    assert float(lens.thickness[1]) == gap
    efl, bfl = _abcd(gap)
    assert float(jl.paraxial_data(lens).efl_image_space) == pytest.approx(efl, rel=1e-12)
    assert float(paraxial.bfl(lens)) == pytest.approx(bfl, rel=1e-12)
    assert abs(_abcd(10.0)[0] - _abcd(30.0)[0]) > 1  # the two configurations differ


def test_the_surfaces_contradicting_the_active_rows_are_reported():
    """MNUM 2 2 says the surfaces hold configuration 2 (gap 30), but they hold 10."""
    text = _pair(mnum="MNUM 2 2")
    with pytest.raises(ValueError, match=r"<zmx>:\d+: THIC 2 of configuration 2, the active "
                                         r"one \(MNUM\), is 30, but surface 2 holds 10"):
        zmx.loads(text, strict=True)
    with pytest.warns(zmx.ZmxWarning, match="jaxlens reads the surfaces"):
        lens = zmx.loads(text)
    assert float(lens.thickness[1]) == 10.0
    # Read as configuration 1, the rows apply: 10.
    assert float(zmx.loads(text, strict=True, config=1).thickness[1]) == 10.0


def test_mnum_without_the_active_number_means_configuration_1():
    lens = zmx.loads(_pair(mnum="MNUM 2"), strict=True)
    assert float(lens.thickness[1]) == 10.0


@pytest.mark.parametrize("config, msg", [
    (0, r"config must be one of the file's configurations 1\.\.2 .*got 0"),
    (3, r"configurations 1\.\.2 .*got 3"),
    (True, r"config must be a whole configuration number"),
    (1.0, r"config must be a whole configuration number"),
])
def test_a_bad_configuration_number_is_refused(config, msg):
    with pytest.raises(ValueError, match=msg):
        zmx.loads(_pair(), config=config)


def test_a_single_configuration_file_has_only_configuration_1():
    text = _pair(mnum="", rows="")
    assert float(zmx.loads(text, config=1).thickness[1]) == 10.0
    with pytest.raises(ValueError, match=r"the file's one configuration .*got 2"):
        zmx.loads(text, config=2)


@pytest.mark.parametrize("row, msg, active", [
    ("PRAM 1 2 0.5 0 0 0 1 1 1 0 0",
     r"<zmx>:\d+: configuration 2 sets PRAM 1 to 0\.5 .*a surface parameter", "0"),
    # The active configuration's TEMP row at Zemax's default 20 °C (the file has no ENVD):
    # a row at another temperature is refused for the active configuration too.
    ("TEMP 0 2 35 0 0 0 1 1 1 0 0", r"sets TEMP 0 to 35 .*the temperature", "20"),
    ("ZPHS 1 2 3 0 0 0 1 1 1 0 0", r"ZPHS is an operand jaxlens does not apply", "0"),
])
def test_an_operand_that_cannot_be_applied_is_refused_with_its_line(row, msg, active):
    same = row.split()[0] + " " + row.split()[1] + f" 1 {active} 0 0 0 1 1 1 0 0"
    rows = "THIC 2 1 10 0 0 0 1 1 1 0 0\nTHIC 2 2 30 0 0 0 1 1 1 0 0\n"
    text = _pair(rows=rows + same + "\n" + row + "\n")
    with pytest.raises(ValueError, match=msg):
        zmx.loads(text, config=2)  # refused with or without strict: never another lens
    assert float(zmx.loads(text, strict=True).thickness[1]) == 10.0  # the active one reads
    # The same operand with equal values in both configurations changes nothing.
    equal = text.replace(row, row.split()[0] + " " + row.split()[1] + " 2"
                         + f" {active} 0 0 0 1 1 1 0 0")
    assert float(zmx.loads(equal, config=2).thickness[1]) == 30.0


def test_malformed_rows():
    rows = "THIC 2 1 10 0 0 0 1 1 1 0 0\nTHIC 2 3 30 0 0 0 1 1 1 0 0\n"
    with pytest.raises(ValueError, match=r"configuration number must be 1\.\.2 \(MNUM\), got 3"):
        zmx.loads(_pair(rows=rows), config=2)
    # For the active configuration they are not needed: a warning (strict: an error).
    with pytest.warns(zmx.ZmxWarning, match="operand table jaxlens cannot read"):
        zmx.loads(_pair(rows=rows))
    with pytest.raises(ValueError, match=r"operand table .*\(strict mode\)"):
        zmx.loads(_pair(rows=rows), strict=True)
    missing = "THIC 2 1 10 0 0 0 1 1 1 0 0\n"
    with pytest.raises(ValueError, match=r"THIC 2 has no line for configuration 2"):
        zmx.loads(_pair(rows=missing), config=2)
    bad = "THIC 7 1 10 0 0 0 1 1 1 0 0\nTHIC 7 2 30 0 0 0 1 1 1 0 0\n"
    with pytest.raises(ValueError, match=r"THIC names surface 7; the file has surfaces 0\.\.5"):
        zmx.loads(_pair(rows=bad), config=2)


def test_stop_aperture_field_and_wavelength_operands():
    rows = ("STPS 0 1 1 0 0 0 1 1 1 0 0\nSTPS 0 2 3 0 0 0 1 1 1 0 0\n"
            "APER 0 1 10 0 0 0 1 1 1 0 0\nAPER 0 2 6 0 0 0 1 1 1 0 0\n"
            "WAVE 1 1 0.55 0 0 0 1 1 1 0 0\nWAVE 1 2 0.65 0 0 0 1 1 1 0 0\n"
            "YFIE 2 1 0 0 0 0 1 1 1 0 0\nYFIE 2 2 7 0 0 0 1 1 1 0 0\n")
    text = _pair(rows=rows).replace("WAVM 1 0.55 1\n", "WAVM 1 0.55 1\nYFLN 0 3\n")
    one, two = zmx.loads(text, strict=True), zmx.loads(text, strict=True, config=2)
    assert (one.stop, two.stop) == (0, 2)
    assert float(two.epd) == 6.0 and float(one.epd) == 10.0
    np.testing.assert_array_equal(np.asarray(two.wavelengths), [0.65])
    np.testing.assert_array_equal(np.asarray(two.fields), [0.0, 7.0])
    np.testing.assert_array_equal(np.asarray(one.fields), [0.0, 3.0])


def test_report_cli_config_and_list(capsys, tmp_path):
    from jaxlens.__main__ import main

    assert main(["report", ZOOM, "--list-configs"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"3 configurations; active \(the surfaces\): 1", out)
    assert re.search(r"THIC 2 +20 +10 +5", out)
    assert main(["report", ZOOM, "--config", "4"]) == 2
    assert "configurations 1..3" in capsys.readouterr().err
    json_lens = tmp_path / "l.json"
    jl.save(_quiet_load(ZOOM), json_lens)
    assert main(["report", str(json_lens), "--config", "2"]) == 2
    assert "config selects a configuration of a multi-configuration .zmx file" in (
        capsys.readouterr().err)


@pytest.mark.slow
def test_report_cli_reads_the_chosen_configuration(capsys):
    import json

    from jaxlens.__main__ import main

    assert main(["report", ZOOM, "--config", "3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["efl_image_space"] == pytest.approx(OPTILAND[3][0], rel=1e-9)


def test_load_passes_config_and_refuses_it_for_json(tmp_path):
    """``jaxlens.load(config=N)`` is the .zmx reader's configuration N; a .json lens has one
    configuration, so a config for it is refused rather than ignored."""
    import jaxlens

    for c in (1, 2, 3):
        a = jaxlens.load(ZOOM, config=c)
        b = zmx.load_zmx(ZOOM, config=c)
        assert jax.tree.all(jax.tree.map(lambda x, y: bool(np.array_equal(x, y)), a, b))
    # THIC 2 (Zemax's surface 2, jaxlens's thickness[1]) is 20 / 10 / 5 mm.
    assert [float(jaxlens.load(ZOOM, config=c).thickness[1]) for c in (1, 2, 3)] == [20, 10, 5]
    with pytest.raises(ValueError, match=r"load: config selects a configuration .* a \.json"):
        jaxlens.load(jaxlens.__path__[0] + "/data/lenses/cooke_triplet.json", config=1)


def test_vignetting_operands_set_that_configurations_factors():
    """FVCY/FVDY of field 2 in configuration 2 become that field's VCYN/VDYN values
    (``Lens.vignetting``); configuration 1 keeps the file's lines; a field never named keeps 0."""
    fields = "FTYP 0 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 3\nVCYN 0 0.1\n"
    rows = ("FVCY 2 1 0.1 0 0 0 1 1 1 0 0\nFVCY 2 2 0.4 0 0 0 1 1 1 0 0\n"
            "FVDY 2 1 0 0 0 0 1 1 1 0 0\nFVDY 2 2 -0.05 0 0 0 1 1 1 0 0\n")
    text = _pair(rows=rows).replace("ENPD 10\n", "ENPD 10\n" + fields)
    one = zmx.loads(text, strict=True, config=1)
    two = zmx.loads(text, strict=True, config=2)
    cols = VIGNETTING_COLUMNS  # VDX, VDY, VCX, VCY, VAN
    v1, v2 = np.asarray(one.vignetting), np.asarray(two.vignetting)
    assert v1.shape == v2.shape == (2, len(cols))
    np.testing.assert_array_equal(v1, [[0, 0, 0, 0, 0], [0, 0, 0, 0.1, 0]])
    np.testing.assert_array_equal(v2, [[0, 0, 0, 0, 0], [0, -0.05, 0, 0.4, 0]])
    with pytest.raises(ValueError, match=r"VCYN of field 2 must be below 1"):
        zmx.loads(text.replace("FVCY 2 2 0.4", "FVCY 2 2 1.2"), config=2)


def test_an_unknown_glass_of_a_glss_row_is_reported_with_the_row_itself():
    # The message quoted a made-up 'GLAS NAME' line, and with unknown_glass="model" said
    # nothing of why no model glass stood in (a GLSS row has no nd, Vd).
    with open(ZOOM) as fh:
        text = fh.read().replace("GLSS 3 3 N-F2", "GLSS 3 3 NOSUCHGLASS9")
    for kw in ({}, {"unknown_glass": "model"}):
        with pytest.raises(ValueError, match=r"<zmx>:\d+: glass 'NOSUCHGLASS9'.*GLSS row gives "
                                             r"the glass's name only.*'GLSS 3 3 NOSUCHGLASS9 "):
            zmx.loads(text, config=3, **kw)
