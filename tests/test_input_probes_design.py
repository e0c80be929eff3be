"""Bad input to the design entry points found by a probe: each case is refused at once with a
message naming the argument, the value, the range and the unit, where it used to pass
silently (NaN through ``<=``, nm taken as µm, a float truncated to an int, an explicit
flag quietly changed) or leave a half-written run folder behind.
"""

from __future__ import annotations

import math
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest

from jaxlens.design.spec import DesignSpec
from jaxlens.experiments import classical, runfolder

ROOT = pathlib.Path(__file__).parent.parent
NAN, INF = math.nan, math.inf


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(wavelengths=(486.1, 587.6, 656.3)), ValueError, r"486.1 nm is 0.4861 µm"),
    (dict(wavelengths=(0.2, 0.5876)), ValueError, r"wavelengths 0.2 µm is outside 0.4–0.7 µm, "
                                                  r"the data range of E48R"),
    (dict(wavelengths=(NAN, 0.5876, 0.6563)), ValueError, r"wavelengths must be a finite"),
    (dict(wavelengths=0.55), TypeError, r"wavelengths must be a tuple"),
    (dict(fnum=NAN), ValueError, r"fnum must be a finite number in \[0.5, 64\] \(F-number "
                                 r"f/EPD\), got nan"),
    (dict(fnum=INF), ValueError, r"fnum must be a finite number"),
    (dict(fnum_start=NAN), ValueError, r"fnum_start must be a finite number"),
    (dict(total_track=NAN), ValueError, r"total_track must be a finite number in \(0, 10000\] mm"),
    (dict(total_track=INF), ValueError, r"total_track must be a finite number"),
    (dict(bfl=NAN), ValueError, r"bfl must be a finite number in \(0, inf\) mm, got nan"),
    (dict(sensor_diagonal=NAN), ValueError, r"sensor_diagonal must be a finite number"),
    (dict(sensor_diagonal=INF), ValueError, r"sensor_diagonal must be a finite number"),
    (dict(sensor_pixels=0), ValueError, r"sensor_pixels must be a whole number in \[1, 8192\] "
                                        r"pixels, got 0"),
    (dict(sensor_pixels=-5), ValueError, r"sensor_pixels must be a whole number"),
    (dict(sensor_pixels=10.5), TypeError, r"sensor_pixels must be an int in \[1, 8192\] pixels, "
                                          r"got float 10.5"),
    (dict(stop=1.5), TypeError, r"stop must be an int in \[0, 6\]"),
    (dict(stop=True), TypeError, r"stop must be an int .*got bool True"),
    (dict(primary=1.0), TypeError, r"primary must be an int in \[0, 2\]"),
    (dict(asphere_terms=2.5), TypeError, r"asphere_terms must be an int"),
    (dict(asphere_terms=1000), ValueError, r"asphere_terms must be a whole number in \[0, 12\]"),
    (dict(efl=INF), ValueError, r"efl must be a finite number in \(0, inf\) mm"),
    (dict(sensor_aspect=(1, NAN)), ValueError, r"sensor_aspect must be a finite number"),
    (dict(fov="80"), TypeError, r"fov must be a number in \(0, 180\) deg, got str '80'"),
    (dict(fov_start=NAN), ValueError, r"fov_start must be a finite number in \(0, 80.8\] deg"),
    (dict(n_elements=6.0), TypeError, r"n_elements must be an int"),
    (dict(materials="E48R"), TypeError, r"materials must be a tuple of catalog names"),
    (dict(name=None), TypeError, r"name must be a str"),
])
def test_design_spec_refuses_every_bad_field(kwargs, error, match):
    with pytest.raises(error, match=match) as e:
        DesignSpec(**kwargs)
    assert str(e.value).startswith("DesignSpec: ")


def _refused(capsys, tmp_path, *args) -> str:
    assert classical.main([*args, "--out", str(tmp_path / "run")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def test_classical_cli_refuses_flags_it_used_to_change_or_ignore(capsys, tmp_path, monkeypatch):
    def started(*a):
        raise AssertionError("the run started")

    monkeypatch.setattr(classical, "run_design", started)
    assert re.search(r"--fov-start must be a finite number in \(0, 80\] deg \(at most --fov\), "
                     r"got 100", _refused(capsys, tmp_path, "--fov", "80", "--fov-start", "100"))
    assert re.search(r"--fnum-start must be a finite number in \[2, 64\] \(F-number, at least "
                     r"--fnum\), got 1.5",
                     _refused(capsys, tmp_path, "--fnum", "2", "--fnum-start", "1.5"))
    assert "--material-catalogs 'FOO'" in _refused(capsys, tmp_path, "--material-catalogs", "FOO")
    # An option that another one overrides is refused, not ignored.
    for args, msg in ((("--seed-list", "1,2", "--seeds", "5"), "--seeds would be ignored with "
                                                                 "--seed-list"),
                      (("--smoke", "--steps", "2", "--polish-steps", "9"),
                       "--steps, --polish-steps would be ignored with --smoke"),
                      (("--polish", "none", "--polish-steps", "9"), "with --polish none"),
                      (("--loss", "image", "--polish-steps", "9"), "with --loss image"),
                      (("--columns", "+recipe",), "--columns would be ignored with no --ablation")):
        assert msg in _refused(capsys, tmp_path, *args), args
    # Only the defaults follow the target.
    args = classical.build_parser().parse_args(["--fov", "40", "--fnum", "4", "--elements", "4"])
    spec = classical.spec_from_args(args)
    assert (spec.fov_start, spec.fnum_start) == (40.0, 4.0)


def test_sigterm_removes_the_partial_run_folder(tmp_path):
    # The CLIs' pattern (classical.run_design, edof.cli.run), with runfolder.py loaded alone
    # so that the subprocess starts in well under a second.
    script = ("import importlib.util, sys, time\n"
              f"s = importlib.util.spec_from_file_location('rf', {runfolder.__file__!r})\n"
              "rf = importlib.util.module_from_spec(s)\n"
              "s.loader.exec_module(rf)\n"
              f"folder = rf.RunFolder({str(tmp_path / 'run')!r})\n"
              "folder.start()\n"
              "try:\n"
              "    time.sleep(60)  # a run in progress\n"
              "except BaseException:\n"
              "    folder.abandon()\n"
              "    raise\n")
    p = subprocess.Popen([sys.executable, "-c", script])
    try:
        t0 = time.perf_counter()
        while not list(tmp_path.glob(".run.partial-*")):
            assert p.poll() is None and time.perf_counter() - t0 < 10, "no run folder"
            time.sleep(0.01)
        p.send_signal(signal.SIGTERM)
        t0 = time.perf_counter()
        assert p.wait(timeout=10) == 128 + signal.SIGTERM
        assert time.perf_counter() - t0 < 1
    finally:
        p.kill()
    assert list(tmp_path.iterdir()) == []


def test_a_run_finishing_late_keeps_the_run_finished_meanwhile(tmp_path):
    out = tmp_path / "run"
    first, second = runfolder.RunFolder(str(out)), runfolder.RunFolder(str(out))
    (pathlib.Path(first.start()) / "lens.json").write_text("first")
    kept = pathlib.Path(second.start())
    first.finish()
    with pytest.raises(runfolder.UsageError, match=r"holds an earlier run.*this run is "
                                                   r"finished in "):
        second.finish()
    second.abandon()  # the caller's cleanup on any exception: removes nothing now
    assert (out / "lens.json").read_text() == "first"
    assert (kept / runfolder.FINISHED).exists()


@pytest.mark.parametrize("args, match", [
    (["--seeds", "0,0"], r"--seeds needs distinct seeds"),
    (["--lenses", "hybrid,hybrid"], r"--lenses takes distinct names"),
    (["--time-limit", "60"], r"--resume and --time-limit need --checkpoint"),
])
def test_edof_cli_refuses_repeats_and_a_time_limit_with_nothing_to_save(args, match, tmp_path):
    """A repeated seed or lens would count twice in the table's means (their results are
    stored per seed and lens); a time limit without a checkpoint would stop with nothing
    saved."""
    from jaxlens.experiments.edof import cli

    a = cli.build_parser().parse_args([*args, "--out", str(tmp_path / "run")])
    with pytest.raises(runfolder.UsageError, match=match):
        cli.check_args(a)
    with pytest.raises(SystemExit):  # argparse: --smoke and --paper exclude each other
        cli.build_parser().parse_args(["--smoke", "--paper"])
