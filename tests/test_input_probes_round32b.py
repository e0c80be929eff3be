"""Bad input, round 32b (tools/audit32b_probe.py): what a user types or hands over. One test
per class of gap fixed; each names what main did with the input: an option dropped without
a word, a table that mixed specs, a file cut by an interrupted write, a late failure."""

import builtins
import importlib.util
import json
import pathlib
import shutil
import sys

import numpy as np
import pytest

import jaxlens as jl

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"
SEED0 = ROOT / "experiments" / "classical" / "designs" / "seed_0.zmx"


class Started(Exception):
    """Raised where a command's work would begin: its checks have passed."""


def started(*a, **k):
    raise Started


@pytest.fixture
def classical(monkeypatch, capsys):
    """``classical.main`` up to its work: (exit code, last stderr line), or "started"."""
    from jaxlens.experiments import classical as C

    monkeypatch.setattr(C, "run_design", started)
    monkeypatch.setattr(C, "run_ablation", started)

    def go(*argv):
        try:
            code = C.main(list(argv))
        except Started:
            return "started"
        return code, capsys.readouterr().err.strip().splitlines()[-1]
    return go


@pytest.mark.parametrize("extra, ignored", [
    (["--seeds", "20"], "--seeds"), (["--seed-list", "3,4"], "--seed-list"),
    (["--recipe", "strong"], "--recipe"), (["--no-mask"], "--no-mask"),
    (["--loss", "image"], "--loss"), (["--tolerance-trials", "50"], "--tolerance-trials")])
def test_classical_ablation_refuses_the_options_its_columns_override(classical, tmp_path,
                                                                     extra, ignored):
    """Main: ``--ablation --seeds 20`` designed --ablation-seeds' 20 starts per column (the
    default, not the 20 asked for: the same here, but ``--seeds 5`` also gave 20), and the
    recipe, mask, loss and tolerancing options were dropped; the columns fix them."""
    code, err = classical("--ablation", "--ablation-out", str(tmp_path / "ab"), *extra)
    assert code == 2 and f"{ignored} would be ignored with --ablation" in err, err
    assert classical("--ablation", "--ablation-out", str(tmp_path / "ab2"),
                     "--ablation-seeds", "3") == "started"


def test_classical_no_curriculum_refuses_a_curriculum_start(classical, tmp_path):
    """Main: ``--no-curriculum --fov-start 40`` designed at the full spec; the start, which
    only the sine path reads, was dropped."""
    code, err = classical("--out", str(tmp_path / "r"), "--no-curriculum", "--fov-start", "40")
    assert code == 2 and "--fov-start would be ignored with --no-curriculum" in err, err
    assert classical("--out", str(tmp_path / "r2"), "--no-curriculum") == "started"


def test_classical_ablation_refuses_a_column_of_another_spec_or_cut_short(classical, tmp_path):
    """Main: a column designed at ``--fov 60`` went into this run's (80.8°) table beside its
    own, and a column cut by an interrupted write failed the table after this run's designs
    (a JSONDecodeError). Both are refused before the designs; the shipped folder passes."""
    from jaxlens.experiments.classical import ABLATION_COLUMNS

    shipped = json.loads((ROOT / "experiments" / "classical" / "table1.json").read_text())
    other = tmp_path / "other"
    (other / "columns").mkdir(parents=True)
    (other / "table1.json").write_text(json.dumps({"spec": dict(shipped["spec"], fov=60.0)}))
    (other / "columns" / "baseline.json").write_text(json.dumps(
        {"command": "x", "switches": dict(ABLATION_COLUMNS)["baseline"], "seeds": [0]}))
    code, err = classical("--ablation", "--ablation-out", str(other), "--columns", "+curriculum")
    assert code == 2 and "baseline.json is a column of another spec (fov 60.0, this run 80.8" \
        in err, err
    cut = tmp_path / "cut"
    (cut / "columns").mkdir(parents=True)
    (cut / "columns" / "baseline.json").write_text('{"command": "python -m jaxlens.exp')
    code, err = classical("--ablation", "--ablation-out", str(cut), "--columns", "+curriculum")
    assert code == 2 and "baseline.json is not a readable ablation column" in err, err
    copy = tmp_path / "shipped"
    shutil.copytree(ROOT / "experiments" / "classical" / "columns", copy / "columns")
    shutil.copy(ROOT / "experiments" / "classical" / "table1.json", copy)
    assert classical("--ablation", "--ablation-out", str(copy), "--columns", "+recipe",
                     "--overwrite") == "started"


def test_ablation_column_is_written_whole(tmp_path, monkeypatch):
    """A column interrupted mid-write leaves no column file (the table reads only whole
    ones)."""
    from jaxlens.experiments import ablation_table as T

    (tmp_path / "columns").mkdir()

    def cut(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(T.os, "replace", cut)
    with pytest.raises(KeyboardInterrupt):
        T.write_column(str(tmp_path), "+both", {"command": "c", "switches": {}})
    assert not (tmp_path / "columns" / "plus_both.json").exists()


def _edof_check(tmp_path, *argv):
    from jaxlens.experiments.edof import cli

    return cli.check_args(cli.build_parser().parse_args(["--out", str(tmp_path / "run"),
                                                         *argv]))


@pytest.mark.parametrize("argv, match", [
    (["--hold-focus", "--lenses", "cubic"], r"--hold-focus \(the hybrid lens's\) would be "
                                            r"ignored: --lenses 'cubic'"),
    (["--cubic-floor", "0.5", "--lenses", "classical,hybrid"], r"--cubic-floor \(the cubic "
                                                               r"lens's\) would be ignored"),
])
def test_edof_refuses_an_option_of_a_lens_it_does_not_train(tmp_path, argv, match):
    """Main: the option was dropped (``LENS_ONLY``: only its lens's training reads it)."""
    from jaxlens.experiments.runfolder import UsageError

    with pytest.raises(UsageError, match=match):
        _edof_check(tmp_path, *argv)
    _edof_check(tmp_path, "--hold-focus", "--lenses", "hybrid")


def test_edof_test_images_validation_and_sizes(tmp_path):
    """Main: ``--validation --test-dir D`` scored D's images (the flag dropped), and a test
    image smaller than one crop gave no crop, unnamed; a grey+alpha image failed with its
    shape and no file name."""
    from PIL import Image

    from jaxlens.experiments.edof import scenes
    from jaxlens.experiments.runfolder import UsageError

    tiny = tmp_path / "tiny"
    tiny.mkdir()
    Image.fromarray(np.zeros((1, 1, 3), np.uint8)).save(tiny / "one.png")
    with pytest.raises(UsageError, match=r"--validation scores skimage's validation images "
                                         r"and --test-dir"):
        _edof_check(tmp_path, "--validation", "--test-dir", str(tiny))
    with pytest.raises(UsageError, match=r"--test-dir: scenes: the image .*one\.png is 1x1 "
                                         r"pixels, smaller than one 256x256 test crop"):
        _edof_check(tmp_path, "--test-dir", str(tiny))
    la = tmp_path / "la"
    la.mkdir()
    grey = np.arange(64, dtype=np.uint8).reshape(8, 8)
    Image.fromarray(np.dstack([grey, np.full_like(grey, 128)]), "LA").save(la / "a.png")
    (img,) = scenes.load_images(folder=la)
    assert img.shape == (8, 8, 3) and np.array_equal(img[..., 0], img[..., 2])


def test_edof_design_names_the_total_track_option(tmp_path, capsys, monkeypatch):
    """Main: "DesignSpec: total_track 7000 mm is 1.37e+03 times the focal length" named no
    option (the track typed in µm)."""
    from jaxlens.experiments.edof import design

    monkeypatch.setattr(design, "design_classical", started)
    with pytest.raises(SystemExit) as e:
        design.main(["--total-track", "7000", "--out", str(tmp_path / "l.json"),
                     "--record-dir", str(tmp_path / "rec")])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert e.value.code == 2 and "error: --total-track 7000 mm is" in err, err


def test_grad_levers_refuses_a_flag_that_is_no_xla_flag(capsys, monkeypatch):
    """Main: ``--flag nosuch`` ran every other setting first and then failed in its child
    process."""
    import benchmarks.grad_levers as GL

    monkeypatch.setattr(GL, "measure", started)
    monkeypatch.setattr(GL.subprocess, "run", started)
    with pytest.raises(SystemExit) as e:
        GL.main(["--flag", "nosuch"])
    assert e.value.code == 2
    assert "'nosuch' is not an XLA flag" in capsys.readouterr().err
    with pytest.raises(Started):
        GL.main(["--flag=--xla_cpu_use_fusion_emitters=false"])


def test_zmx_config_reference_refuses_before_optiland(capsys):
    """Main: ``--expand`` of a file without an MNUM section ended in StopIteration, and a
    missing file in optiland's import or its reader."""
    spec = importlib.util.spec_from_file_location("zcr", ROOT / "tools" / "zmx_config_reference.py")
    zcr = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(zcr)
    for argv, words in ((["--expand", str(SEED0)], "MNUM"), ([str(COOKE)], "not a .zmx"),
                        (["nope.zmx"], "no such file")):
        with pytest.raises(SystemExit) as e:
            zcr.main(argv)
        assert e.value.code == 2 and words in capsys.readouterr().err


class _CutWriter:
    """A file that takes half of what is written, then is interrupted (Ctrl-C)."""

    def __init__(self, f):
        self.f = f

    def write(self, text):
        self.f.write(text[: len(text) // 2])
        self.f.flush()
        raise KeyboardInterrupt

    def __enter__(self):
        return self

    def __exit__(self, *a):
        self.f.close()


def _cut_open(path, mode="r", *a, **k):
    f = builtins.open(path, mode, *a, **k)
    return _CutWriter(f) if "w" in mode else f


@pytest.mark.parametrize("src, name", [(COOKE, "lens.json"), (SEED0, "lens.zmx")])
def test_an_interrupted_save_keeps_the_lens_it_would_replace(tmp_path, monkeypatch, src, name):
    """Main: ``save`` wrote over the file in place; Ctrl-C mid-write left half a lens (the
    old one lost; a ``.zmx`` cut at a surface's end read as a shorter lens)."""
    from jaxlens.io import json_values, lensfile, zmx_write

    path = tmp_path / name
    shutil.copy(src, path)
    before = path.read_bytes()
    lens = jl.load(COOKE)
    for mod in (lensfile, zmx_write, json_values):
        monkeypatch.setattr(mod, "open", _cut_open, raising=False)
    with pytest.raises(KeyboardInterrupt):
        jl.save(lens, path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [name]  # no partial file left


def test_a_json_lens_cut_short_or_empty_says_so(tmp_path):
    """Main: "not valid JSON: Unterminated string starting at" for a file cut by an
    interrupted write, "Expecting value" for an empty one."""
    text = COOKE.read_text()
    (tmp_path / "cut.json").write_text(text[: len(text) // 2])
    with pytest.raises(ValueError, match=r"cut\.json:\d+: not valid JSON: .*; the file does "
                                         r"not end in '\}' \(cut short\?\)"):
        jl.load(tmp_path / "cut.json")
    (tmp_path / "empty.json").write_text("")
    with pytest.raises(ValueError, match=r"empty\.json:1: not valid JSON: .*; the file is empty"):
        jl.load(tmp_path / "empty.json")


def test_make_agf_refuses_an_out_without_the_hand_kept_catalogs(tmp_path, capsys, monkeypatch):
    """Main: ``make_agf.py DB --out EMPTY`` rewrote the OHARA, HOYA, HIKARI and SUMITA
    catalogs, then stopped at SCHOTT with a FileNotFoundError (its glasses are added to the
    hand-kept SCHOTT.agf); a maker missing from the database stopped it likewise."""
    spec = importlib.util.spec_from_file_location("make_agf", ROOT / "tools" / "make_agf.py")
    make_agf = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "make_agf", make_agf)  # its dataclass looks itself up
    spec.loader.exec_module(make_agf)
    db = tmp_path / "db"
    for maker in make_agf.MAKERS:
        (db / "data-nk" / "glass" / maker).mkdir(parents=True)
    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(SystemExit) as e:
        make_agf.main([str(db), "--out", str(out)])
    assert e.value.code == 2 and "has no SCHOTT.agf" in capsys.readouterr().err
    assert list(out.iterdir()) == []  # nothing written
    for kept in ("SCHOTT.agf", "CDGM.agf"):
        (out / kept).write_text("CC hand-kept\n")
    shutil.rmtree(db / "data-nk" / "glass" / "cdgm")
    with pytest.raises(SystemExit) as e:
        make_agf.main([str(db), "--out", str(out)])
    assert e.value.code == 2 and "no folder for 'cdgm'" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["CDGM.agf", "SCHOTT.agf"]


def test_export_reevaluation_refuses_a_json_it_would_write_over(tmp_path, capsys):
    """Main: ``--json my_lens.json`` (or one of the inputs) replaced the lens by the records,
    ``--json FOLDER`` failed with IsADirectoryError after every file, and a folder without
    lenses wrote an empty record without a word."""
    spec = importlib.util.spec_from_file_location("export_reevaluation",
                                                  ROOT / "tools" / "export_reevaluation.py")
    er = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(er)
    lens = tmp_path / "my_lens.json"
    shutil.copy(COOKE, lens)
    (tmp_path / "empty").mkdir()
    for argv, words in (([str(SEED0), "--json", str(lens)], "not an export_reevaluation record"),
                        ([str(lens), "--json", str(lens)], "one of the files to evaluate"),
                        ([str(SEED0), "--json", str(tmp_path)], "is a folder"),
                        ([str(tmp_path / "empty")], "no .zmx or .json file")):
        with pytest.raises(SystemExit) as e:
            er.main(argv)
        assert e.value.code == 2 and words in capsys.readouterr().err, argv
    assert lens.read_bytes() == COOKE.read_bytes()


def test_edof_seeds_refuse_an_empty_entry(capsys):
    """Main: ``--seeds 0,,1`` ran seeds 0 and 1 (an empty entry dropped: a seed typed
    between them lost), as ``classical --materials E48R,,OKP4`` once did."""
    from jaxlens.experiments.edof import cli

    with pytest.raises(SystemExit) as e:
        cli.build_parser().parse_args(["--seeds", "0,,1"])
    assert e.value.code == 2
    assert "--seeds: must be comma-separated whole numbers without an empty one, got '0,,1'" \
        in capsys.readouterr().err
    assert cli.build_parser().parse_args(["--seeds", "0, 1,2"]).seeds == (0, 1, 2)


def test_zmx_parm_takes_one_value(tmp_path):
    """Main: ``PARM 3 -1.2E-004 5`` (a value in the wrong column, or a number split by a
    space) was read as -1.2E-004, as DISZ once was; every PARM line of the 439 corpus files
    holds an index and one value."""
    text = SEED0.read_text(encoding="utf-8")
    parm = next(line for line in text.splitlines() if line.strip().startswith("PARM 3"))
    (tmp_path / "p.zmx").write_text(text.replace(parm, parm + " 5", 1))
    with pytest.raises(ValueError, match=r"p\.zmx:\d+: PARM takes an index and one value "
                                         r"\(PARM 3's value\), got 3"):
        jl.load(tmp_path / "p.zmx")
    (tmp_path / "z.zmx").write_text(text.replace(parm, parm + " 0", 1))  # padding passes
    assert jl.load(tmp_path / "z.zmx").name == jl.load(SEED0).name


def test_json_lens_weights_warn_as_the_zmx_reader_does(tmp_path):
    """Main: ``"fields": {"values": [0, 14, 20], "weights": [1, 2, 1]}`` passed as a comment
    (a key far from every known key); the .zmx reader warns about FWGN's unequal weights."""
    d = json.loads(COOKE.read_text())
    d["fields"]["weights"] = [1, 2, 1]
    (tmp_path / "w.json").write_text(json.dumps(d))
    with pytest.warns(UserWarning, match=r"w\.json: fields\.weights \[1, 2, 1\] is not read: "
                                         r"a jaxlens Lens holds no weights"):
        jl.load(tmp_path / "w.json")
    d["fields"]["weights"] = [1, 1, 1]  # equal weights change nothing
    (tmp_path / "e.json").write_text(json.dumps(d))
    jl.load(tmp_path / "e.json")


# runpy warns that a module imported before (by another test) runs again as __main__
@pytest.mark.filterwarnings("ignore:'benchmarks.*' found in sys.modules:RuntimeWarning")
@pytest.mark.parametrize("module", ["pareto", "imaging", "skipping", "throughput"])
def test_python_m_a_benchmark_module_runs_that_benchmark(module, monkeypatch):
    """Main: ``python -m benchmarks.pareto --smoke`` ran nothing and exited 0 without a
    word (the module has no ``__main__`` block): now ``python -m benchmarks --only pareto
    --smoke``."""
    import runpy

    import benchmarks.run

    calls = []
    monkeypatch.setattr(benchmarks.run, "main", lambda argv: calls.append(argv))
    monkeypatch.setattr(sys, "argv", ["x", "--smoke"])
    runpy.run_module(f"benchmarks.{module}", run_name="__main__")
    assert calls == [["--only", module, "--smoke"]]


@pytest.mark.filterwarnings("ignore:'benchmarks.*' found in sys.modules:RuntimeWarning")
def test_python_m_a_benchmark_helper_says_so():
    """Main: ``python -m benchmarks.summary`` ran nothing and exited 0."""
    import runpy

    with pytest.raises(SystemExit, match=r"benchmarks\.summary is a helper of the "
                                         r"benchmarks, not one: run python -m benchmarks"):
        runpy.run_module("benchmarks.summary", run_name="__main__")
