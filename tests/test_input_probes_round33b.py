"""Bad input, round 33b (tools/audit33b_probe.py): the file readers and the files the tools
write. One test per class of gap fixed; each names what main did with the input: a header
line given twice (one copy dropped without a word), a pickup of a surface the file lacks or
of a value not yet solved, an AGF glass named twice in two cases, a UTF-32 file, a TD record
of text, a .zmx-only option given with a .json lens, a results file cut by a stopped write."""

import json
import os
import pathlib
import re
import shutil
import warnings

import numpy as np
import pytest

import jaxlens as jl

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"
DESIGNS = ROOT / "experiments" / "classical" / "designs"
SEED0 = DESIGNS / "seed_0.zmx"
DATA = ROOT / "tests" / "data" / "zmx"
PPAR_FILE = DATA / "rayoptics_HoO-V2C18Ex46.zmx"
PZUP_FILE = DATA / "rayoptics_US00583336-2-scaled.zmx"


def _seed0_with(tmp_path, after: str, extra: str, name="d.zmx") -> pathlib.Path:
    """seed_0.zmx with the lines ``extra`` put after its first line starting ``after``."""
    lines = SEED0.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip().startswith(after))
    lines[i + 1:i + 1] = extra.splitlines()
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize("extra", [
    "GCAT SCHOTT", "ENVD 2.0E+1 1 0", "RAIM 0 0 1 1 0 0 0 0 0 1\nRAIM 0 0 1 1 0 0 0 0 0 1",
    "MNUM 1 1\nMNUM 1 1", "FWGN 1 1 1 1 2", "FWGT 1 1 1 1 1\nFWGT 1 1 1 1 1",
    "WWGT 1 1 1\nWWGT 1 1 1", "WWGN 1 1 1\nWWGN 1 2 1"])
def test_zmx_header_line_given_twice_is_refused(tmp_path, extra):
    """Main: the second GCAT (ENVD, RAIM, MNUM, FWGN, FWGT, WWGT, WWGN) replaced the first
    without a word (which catalogs, environment, weights the file meant was a guess)."""
    key = extra.split()[0]
    # seed_0 has GCAT, ENVD and FWGN lines of its own: one more line makes two
    p = _seed0_with(tmp_path, "FWGN", extra)
    lines = p.read_text().splitlines()
    at = [k + 1 for k, ln in enumerate(lines) if ln.split()[:1] == [key]]
    assert len(at) == 2
    with pytest.raises(ValueError, match=rf"d\.zmx:{at[1]}: {key} given twice \(first on "
                                         rf"line {at[0]}"):
        jl.load(p)


def test_zmx_fwgt_beside_fwgn_still_reads(tmp_path):
    """Control: Zemax 2006 writes FWGT and FWGN (and WWGT and WWGN) side by side, once each."""
    lens = jl.load(DATA / "zemax2006" / "kraken_pivoted_lens.ZMX")
    assert lens.surfaces


@pytest.mark.parametrize("src, old, new, key", [
    (PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 6.0 1 0 0\n  PZUP 5.0 1 0 0", "PZUP"),
    (PPAR_FILE, "PPAR 3 2 1.000000000000E+00 0.000000000000E+00 0",
     "PPAR 3 2 1.000000000000E+00 0.000000000000E+00 0\n"
     "  PPAR 3 3 1.000000000000E+00 0.000000000000E+00 0", "PPAR 3")])
def test_zmx_surface_pickup_given_twice_is_refused(tmp_path, src, old, new, key):
    """Main: a second PZUP (PPAR of one parameter) in a surface replaced the first: a
    configuration that re-solves it read another surface than the file's first line."""
    text = src.read_text()
    assert old in text
    p = tmp_path / "d.zmx"
    p.write_text(text.replace(old, new, 1))
    with pytest.raises(ValueError, match=rf"d\.zmx:\d+: {key} given twice in surface \d+ "
                                         rf"\(first on line \d+"):
        jl.load(p)


@pytest.mark.parametrize("src, old, new, match", [
    (PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 40 1 0 0",
     r"thickness pickup \(PZUP\) of surface 7 reads surface 40, which the file does not have "
     r"\(surfaces 0\.\.\d+\)"),
    (PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 7 1 0 0",
     r"thickness pickup \(PZUP\) of surface 7 reads its own surface"),
    (PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 8 1 0 0",
     r"thickness pickup \(PZUP\) of surface 7 reads surface 8, whose thickness is itself a "
     r"pickup solved after surface 7's \(line \d+; pickups are solved in surface order\)"),
    (PZUP_FILE, "4 6.0 -1. 0", "4 9.0 -1. 0",
     r"curvature pickup \(CURV solve 4\) of surface 8 reads surface 9, whose curvature is "
     r"itself a pickup"),
    (PZUP_FILE, "4 6.0 -1. 0", "4 8 -1. 0",
     r"curvature pickup \(CURV solve 4\) of surface 8 reads its own surface"),
    (PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 99 1.0",
     r"parameter pickup \(PPAR 3\) of surface 4 reads surface 99, which the file does not"),
    (PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 4 1.0",
     r"parameter pickup \(PPAR 3\) of surface 4 reads its own surface"),
    (PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 8 1.0",
     r"parameter pickup \(PPAR 3\) of surface 4 reads surface 8, whose PARM 3 is itself a "
     r"pickup solved after surface 4's"),
])
def test_zmx_pickup_of_a_missing_own_or_unsolved_surface_is_refused(tmp_path, src, old, new,
                                                                    match):
    """Main: a pickup of surface 40 (of its own surface, of a later surface's pickup) read
    without a word: the file's solved value was taken, and a configuration changing the
    source kept it (surface 40, its own) or read a value not yet re-solved (stale)."""
    text = src.read_text()
    assert old in text
    p = tmp_path / "d.zmx"
    p.write_text(text.replace(old, new, 1))
    line = next(k for k, ln in enumerate(p.read_text().splitlines(), 1) if new in ln)
    with pytest.raises(ValueError, match=rf"d\.zmx:{line}: {match}"):
        jl.load(p)


def test_zmx_pickups_of_earlier_surfaces_read(tmp_path):
    """Control: the corpus's pickups (earlier surfaces, chains of them) read as before."""
    for src in (PZUP_FILE, PPAR_FILE, DATA / "zemax2006" / "kraken_pivoted_lens.ZMX"):
        assert jl.load(src).surfaces


def _side_catalog(tmp_path, extra: str) -> pathlib.Path:
    shutil.copy(SEED0, tmp_path / "seed_0.zmx")
    agf = (DESIGNS / "PLASTICS.AGF").read_text()
    (tmp_path / "PLASTICS.AGF").write_text(agf + extra)
    return tmp_path / "seed_0.zmx"


def test_side_catalog_glass_named_in_two_cases_is_refused_where_used(tmp_path):
    """Main: a side PLASTICS.AGF holding OKP4 and okp4 (two records; the lookup ignores
    case) gave the lens the later one, with only the AGF reader's warning."""
    agf = (DESIGNS / "PLASTICS.AGF").read_text()
    record = agf[agf.index("NM OKP4"):]
    p = _side_catalog(tmp_path, record.replace("NM OKP4 1 607270 1.607", "NM okp4 1 6072 1.6072")
                      .replace("2.4740105971476036E+000", "2.4745E+000"))
    n = len(agf.splitlines())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match=rf"seed_0\.zmx:\d+: glass 'OKP4': the side "
                                             rf"catalog .*PLASTICS\.AGF has two glasses of "
                                             rf"this name in two cases, OKP4 \(.*PLASTICS\.AGF:2\) "
                                             rf"and okp4 \(.*PLASTICS\.AGF:{n + 1}\)"):
            jl.load(p)


def test_side_catalog_case_pair_unused_by_the_lens_reads(tmp_path):
    """Control: a pair the lens does not use is the catalog's matter (the AGF reader warns)."""
    agf = (DESIGNS / "PLASTICS.AGF").read_text()
    record = agf[agf.index("NM OKP4"):]
    pair = (record.replace("NM OKP4", "NM XYZ1", 1) + record.replace("NM OKP4", "NM xyz1", 1))
    p = _side_catalog(tmp_path, pair)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert jl.load(p).name == jl.load(SEED0).name


@pytest.mark.parametrize("codec, bom", [("utf-32-le", b"\xff\xfe\x00\x00"),
                                        ("utf-32-be", b"\x00\x00\xfe\xff")])
def test_zmx_and_agf_with_a_utf32_bom_read(tmp_path, codec, bom):
    """Main: a UTF-32 LE file's BOM (FF FE 00 00) was taken for UTF-16 LE's (FF FE): the
    text came back with a NUL after every character ("not a Zemax keyword line"); a BE one
    was "binary data"."""
    from jaxlens.optics.agf import decode_zemax_text

    text = SEED0.read_text()
    (tmp_path / "seed_0.zmx").write_bytes(bom + text.encode(codec))
    agf = (DESIGNS / "PLASTICS.AGF").read_text()
    (tmp_path / "PLASTICS.AGF").write_bytes(bom + agf.encode(codec))
    assert decode_zemax_text(bom + text.encode(codec)) == text
    want = jl.load(SEED0)
    got = jl.load(tmp_path / "seed_0.zmx")
    assert got.name == want.name
    np.testing.assert_array_equal(np.asarray(got.materials[1].index(0.55)),
                                  np.asarray(want.materials[1].index(0.55)))


@pytest.mark.parametrize("key, line", [
    ("TD", "TD 0 0 abc 0 0 0 20"), ("TD", "TD 0 0 0 0 0 0 2O"), ("ED", "ED 0 0 O 0 0"),
    ("IT", "IT 0.4 x 10")])
def test_agf_numeric_record_of_text_is_refused(key, line):
    """Main: a TD (thermal data) record of text was skipped without a word, as were ED and
    IT (every one the AGF format holds numbers)."""
    from jaxlens.optics.agf import parse_agf

    agf = (DESIGNS / "PLASTICS.AGF").read_text()
    assert "TD 0 0 0 0 0 0 20" in agf
    if key == "IT":
        bad = agf.rstrip("\n") + "\n" + line + "\n"
    else:
        bad = agf.replace(f"{key} 0 0 0 0 0" + (" 0 20" if key == "TD" else ""), line, 1)
    at = next(k for k, ln in enumerate(bad.splitlines(), 1) if ln == line)
    with pytest.raises(ValueError, match=rf"P\.AGF:{at}: {key} .* must be finite numbers"):
        parse_agf(bad, source="P.AGF")
    assert parse_agf(agf, source="P.AGF")[0].name == "OKP4"  # control


@pytest.mark.parametrize("argv, option", [
    (["--unknown-glass", "model"], "--unknown-glass"),
    (["--unknown-glass", "error"], "--unknown-glass"),
    (["--config", "1"], "--config"), (["--lenient"], "--lenient")])
def test_report_refuses_zmx_options_with_a_json_lens(capsys, argv, option):
    """Main: ``report LENS.json --unknown-glass error`` ran (the option dropped), and with
    ``model`` or ``--config 1`` the error named the load function's argument
    (``unknown_glass='model'``, ``config=1``), not the option given."""
    from jaxlens.__main__ import main

    code = main(["report", str(COOKE), *argv])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and err.startswith(f"jaxlens report: error: {option} ") and (
        "so it applies to a .zmx lens only; " in err), err


def test_report_list_configs_refuses_unknown_glass(capsys, tmp_path):
    """Main: ``--list-configs --unknown-glass model`` listed (the option did nothing)."""
    from jaxlens.__main__ import main

    code = main(["report", str(SEED0), "--list-configs", "--unknown-glass", "model"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and "--unknown-glass would be ignored" in err, err


def test_benchmark_result_is_written_whole(tmp_path, monkeypatch):
    """Main: ``benchmarks.common.write_json`` wrote over the result in place: a run stopped
    mid-write left a cut JSON file that the summary read later (a JSONDecodeError)."""
    from benchmarks import common

    old = tmp_path / "speed.json"
    old.write_text('{"old": 1}\n')

    def cut(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(os, "replace", cut)
    with pytest.raises(KeyboardInterrupt):
        common.write_json("speed", {"new": list(range(10000))}, tmp_path)
    assert json.loads(old.read_text()) == {"old": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["speed.json"]  # no partial file left
    monkeypatch.undo()
    common.write_json("speed", {"new": 2}, tmp_path)
    assert json.loads(old.read_text()) == {"new": 2}


IN_PLACE = re.compile(r"\.write_text\(|json\.dump\(|open\([^)]*,\s*[\"']w[b]?[\"']|np\.savez\(")


# Run with optiland's interpreter, where jaxlens (and jax) may be missing: they keep their
# plain writes (each writes a reference file by hand, read back by a person, not a run).
OPTILAND_ONLY = {"tools/make_refcase.py", "tools/conventions_reference.py",
                 "tools/zernike_decenter_reference.py", "tools/fuzz36b_reference.py",
                 "tools/corpus7_reference.py", "tools/fuzz37b_reference.py",
                 "tools/rayoptics_reevaluation.py", "tools/telecentric38a_reference.py",
                 "tools/acc40c_reference.py", "tools/zmx40a_reference.py",
                 "tools/fuzz41c_reference.py", "tools/zmx42d_reference.py",
                 "tools/fuzz42c_reference.py", "tools/tele42a_reference.py",
                 "tools/tele43a_reference.py", "tools/zmx43d_reference.py",
                 "tools/ri43c_reference.py", "tools/stress43e_reference.py",
                 "tools/aper44a_reference.py", "tools/zmx45c_reference.py",
                 "tools/aim45a_reference.py", "tools/export46b_reference.py"}


@pytest.mark.parametrize("path", sorted(
    {str(p.relative_to(ROOT)) for p in (ROOT / "benchmarks").glob("*.py")}
    | {"tools/export_reevaluation.py"}
    | {str(p.relative_to(ROOT)) for p in (ROOT / "tools").glob("*_reference.py")}
    - OPTILAND_ONLY))
def test_results_writers_write_whole(path):
    """Main: the benchmarks, export_reevaluation and the reference tools wrote their results
    in place (``write_text``, ``json.dump`` into an open file): a stop mid-write left a cut
    file a later run or test read. Each now writes through ``json_values.write_whole``; the
    lines left write into temporary folders or memory, marked ``# temporary`` or ``# in
    memory``."""
    lines = (ROOT / path).read_text().splitlines()
    bad = [f"{path}:{k}: {ln.strip()}" for k, ln in enumerate(lines, 1)
           if IN_PLACE.search(ln) and "# temporary" not in ln and "# in memory" not in ln]
    assert not bad, bad
