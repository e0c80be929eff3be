"""Command-line audit: a bad option of `edof.design`, `classical --devices` and the benchmark
modules exits with status 2 and one line naming the option, the range and the unit, before
any design or benchmark starts. Option checks only: no test here runs a design."""

from __future__ import annotations

import importlib
import re

import pytest


def _refused(main, argv, capsys) -> str:
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    return err


# ------------------------------------------------------------------ edof.design
@pytest.mark.parametrize("args, match", [
    (["--scale", "nan"], r"--scale must be a finite number in \(0, 1000\] \(step-count"),
    (["--scale", "inf"], r"--scale must be a finite number in \(0, 1000\]"),
    (["--scale", "1e300"], r"--scale must be a finite number in \(0, 1000\]"),
    (["--elements", "0"], r"--elements must be a whole number in \[4, 6\] elements"),
    (["--elements", "1000"], r"--elements must be a whole number in \[4, 6\] elements"),
    (["--total-track", "nan"], r"--total-track must be a finite number in \(0, inf\) mm"),
    (["--total-track", "-5"], r"--total-track must be a finite number in \(0, inf\) mm"),
    (["--seeds", "-1"], r"--seeds must be distinct comma-separated whole numbers >= 0"),
    (["--seeds", "1,1"], r"--seeds must be distinct comma-separated whole numbers >= 0"),
    (["--polish-steps", "-1"], r"--polish-steps must be a whole number in \[0, inf\) steps"),
])
def test_edof_design_refuses_bad_numbers(args, match, tmp_path, capsys, monkeypatch):
    from jaxlens.experiments.edof import design

    monkeypatch.setattr(design, "design_classical", _never)
    err = _refused(design.main, ["--smoke", "--out", str(tmp_path / "l.json"), "--record-dir",
                                 str(tmp_path / "rec"), *args], capsys)
    assert re.search(match, err), err


def _never(*a, **k):
    raise AssertionError("the design started")


@pytest.mark.parametrize("out, rec, match", [
    ("missing/l.json", "rec", r"--out .*missing/l.json: the folder .* does not exist"),
    ("l.txt", "rec", r"--out .*l.txt must end in .json or .zmx"),
    ("l.json", "file", r"--record-dir .*file is a file, not a folder"),
])
def test_edof_design_refuses_bad_paths(out, rec, match, tmp_path, capsys, monkeypatch):
    from jaxlens.experiments.edof import design

    monkeypatch.setattr(design, "design_classical", _never)
    (tmp_path / "file").write_text("x")
    err = _refused(design.main, ["--out", str(tmp_path / out), "--record-dir",
                                 str(tmp_path / rec)], capsys)
    assert re.search(match, err), err


# ------------------------------------------------------------- classical --devices
def test_classical_refuses_a_huge_device_count(tmp_path, capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--devices", "100000", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "--devices must be a whole number in [1, 256] host devices, got 100000" in err
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------- benchmarks
@pytest.mark.parametrize("module, args, match", [
    ("design_step", ["--rays", "0"], r"--rays: must be a whole number in \[1, 100000000\] rays"),
    ("design_step", ["--seeds", "1.5"], r"--seeds: must be a whole number in \[1, 1024\] seeds"),
    ("design_step", ["--out-dir", "FILE"], r"--out-dir: .*FILE is a file, not a folder"),
    ("fast_path", ["--repeats", "-1"], r"--repeats: must be a whole number in \[1, 1000\] repeats"),
    ("grad_levers", ["--chunks", "0"],
     r"--chunks: must be a whole number in \[1, 100000000\] rays"),
    ("render_speed", ["--spp", "nan"], r"--spp: must be a whole number in \[1, 65536\] samples"),
    ("render_speed", ["--out", "DIR"], r"--out: .* is a folder; give a file's path"),
    ("render_memory", ["--cap-gib", "inf"], r"--cap-gib must be a positive number of GiB"),
    ("render_memory", ["--size", "0"], r"--size must be a whole number >= 1, got 0"),
    ("render_memory", ["--out", "FILE/x.json"], r"--out: .*FILE is not an existing folder"),
    ("vjp_probe", ["--chunk", "1.5"], r"--chunk: must be a whole number in \[1, 100000000\] rays"),
    ("vjp_probe", ["--json", "DIR/missing/x.json"], r"--json: .* is not an existing folder"),
    ("run", ["--counts", "1.5"], r"--counts: invalid int value"),
    ("run", ["--counts", "1_0"], r"--counts: invalid int value"),  # int() reads 10
    ("design_step", ["--seeds", "1_0"], r"--seeds: must be a whole number in \[1, 1024\]"),
    ("render_memory", ["--size", "1_0"],
     r"--size: must be a whole number in \[0, 16384\] pixels, got '1_0'"),
    ("reevaluate", ["DIR/missing"], r"folder .*missing is not a folder"),
    ("reevaluate", ["DIR"], r"folder .* holds no .zmx files"),
    ("reevaluate", ["ZMX", "--out", "DIR"], r"--out .* must be a file in an existing folder"),
])
def test_benchmark_options_are_one_line_before_any_run(module, args, match, tmp_path, capsys,
                                                      monkeypatch):
    from benchmarks import optiland_ref

    monkeypatch.setattr(optiland_ref, "available", lambda: True)  # reevaluate checks it first
    (tmp_path / "FILE").write_text("x")
    (tmp_path / "ZMX").mkdir()
    (tmp_path / "ZMX" / "a.zmx").write_text("")
    args = [a.replace("FILE", str(tmp_path / "FILE")).replace("DIR", str(tmp_path))
            .replace("ZMX", str(tmp_path / "ZMX")) for a in args]
    main = importlib.import_module(f"benchmarks.{module}").main
    err = _refused(main, args, capsys)
    assert re.search(match, err), err
