"""Bad input, round 30 (tools/audit30_probe.py): one test per class of gap fixed. Each names
what main did with the input: a silent answer, a file written over, or an option ignored."""

import json
import pathlib

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


def test_edof_config_checks_the_noise_as_the_command_line_does():
    """Main: only ``--read-noise`` was checked; ``Config(read_noise=4)`` (electrons) trained
    on noise four times the full signal, and ``Config(photons=0)`` divided by zero."""
    from jaxlens.experiments.edof.train import Config

    with pytest.raises(ValueError, match=r"edof Config: read_noise must be at most 0\.5 \(a "
                                         r"standard deviation in linear values, 1 = full "
                                         r"signal\), got 4 \(was it in electrons\? 4 e⁻ at "
                                         r"photons 2000 is 0\.002\)"):
        Config(read_noise=4.0)
    with pytest.raises(ValueError, match=r"edof Config: read_noise must be a finite number in "
                                         r"\[0, inf\), got -0\.01"):
        Config(read_noise=-0.01)
    with pytest.raises(ValueError, match=r"edof Config: photons must be a finite number in "
                                         r"\[1, 1e\+12\] photo-electrons at the linear value 1"):
        Config(photons=0.0)
    assert Config(read_noise=0.01).read_noise == 0.01


def test_curriculum_run_checks_its_schedule_and_switches():
    """Main: ``run(warmup=5)`` (5 % written as 5) ramped the rate over the whole stage and
    never reached the peak, ``end_lr=5`` raised it fivefold, ``irls="no"`` read as True,
    ``epoch=0`` and ``log_every=0`` divided by zero; all only after the set-up."""
    import types

    import jax.numpy as jnp

    import jaxlens.design as D

    stage = D.Stage("x", fov=40.0, fnum=4.0, steps=10)
    params = types.SimpleNamespace(c=jnp.zeros((1, 3)))  # read for its dtype and batch only
    obj = types.SimpleNamespace(sampling=types.SimpleNamespace(area=jnp.ones(3)))

    def run(**kw):
        D.run(D.DesignSpec(), [stage], params, obj, started, progress=False, **kw)

    for kw, msg in (
            (dict(warmup=5.0), r"run: warmup must be a finite number in \[0, 1\] \(a "
                               r"fraction of each stage's steps, not a percent\), got 5\.0"),
            (dict(end_lr=5.0), r"run: end_lr must be .* \(a fraction of the peak rate"),
            (dict(epoch=0), r"run: epoch must be a whole number in \[1, inf\) steps"),
            (dict(log_every=0), r"run: log_every must be"),
            (dict(irls="no"), r"run: irls must be True or False, got 'no'"),
            (dict(reg_weights=(40.0, 1000.0)), r"run: reg_weights must be three weights"),
            (dict(callback="print"), r"run: callback must be callable")):
        with pytest.raises((ValueError, TypeError), match=msg):
            run(**kw)
    with pytest.raises(Started):  # control: the defaults reach the first stage's solver
        run(reg_weights=jnp.array([40.0, 1000.0, 40.0]))


@pytest.mark.parametrize("text, what", [
    (json.dumps({"my": "numbers"}), 'it has no "benchmark" entry'),
    ("my notes, not JSON\n", "it is not JSON"),
    (json.dumps([1, 2]), "it holds a JSON list"),
    (json.dumps({"benchmark": "pareto", "command": "python -m benchmarks"}),
     "it is a result of 'pareto'"),
])
def test_benchmarks_refuse_to_write_over_a_file_that_is_not_their_result(
        tmp_path, monkeypatch, capsys, text, what):
    """Main: a ``throughput.json`` in ``--out`` that was no throughput result was written over
    by a full run, or (a partial run) refused as "a full run's results"."""
    import benchmarks.common as BC
    import benchmarks.run as BR

    monkeypatch.setattr(BC, "machine_info", started)  # the first thing after the checks
    (tmp_path / "throughput.json").write_text(text)
    for extra in ([], ["--lenses", "cooke_triplet"]):
        with pytest.raises(SystemExit):
            BR.main(["--only", "throughput", *extra, "--out", str(tmp_path)])
        err = capsys.readouterr().err
        assert (f"throughput.json is not a throughput benchmark result ({what}), and this run "
                f"would write its throughput results over it") in err
    # Control: an earlier smoke result of the benchmark is replaced by a full run.
    (tmp_path / "throughput.json").write_text(json.dumps(
        {"benchmark": "throughput", "command": "python -m benchmarks --smoke"}))
    with pytest.raises(Started):
        BR.main(["--only", "throughput", "--out", str(tmp_path)])


def _zmx(tmp_path, old, new):
    text = SEED0.read_text()
    assert old in text
    path = tmp_path / "lens.zmx"
    path.write_text(text.replace(old, new, 1))
    return path


def test_zmx_refuses_a_second_value_and_names_a_decimal_comma(tmp_path):
    """Main: ``DISZ 0.8 0.06`` (a hand edit's value in the wrong column) was read as 0.8, and
    ``CONI``/``ENPD`` likewise; a decimal comma was "not a number" without the reason."""
    for old, new, msg in (
            ("DISZ 8.059597441026024E-001", "DISZ 0.8 0.06",
             r"lens\.zmx:54: DISZ takes one value \(the thickness\), got 2"),
            ("CONI -4.849999999999994E+000", "CONI -4.85 0.5",
             r"lens\.zmx:46: CONI takes one value \(the conic constant\), got 2"),
            ("ENPD 2.2501173880645875E+000", "ENPD 2 25",
             r"lens\.zmx:18: ENPD takes one value \(the entrance pupil diameter\)"),
            ("CURV 2.971822823221517E-001", "CURV 2,971822823221517E-001",
             r"lens\.zmx:45: curvature is not a number \('2,971822823221517E-001'; a decimal "
             r"comma\? \.zmx numbers take a point: 2\.971822823221517E-001\)")):
        with pytest.raises(ValueError, match=msg):
            jl.load(_zmx(tmp_path, old, new))


def test_zmx_takes_trailing_zeros_after_a_single_value(tmp_path):
    """Zeros after the one value (another writer's padding, as CURV's solve columns) change
    nothing and are read; only a nonzero or non-numeric second value is refused."""
    plain = jl.load(SEED0)
    for old, new in (("DISZ 8.059597441026024E-001", "DISZ 8.059597441026024E-001 0 0"),
                     ("CONI -4.849999999999994E+000", "CONI -4.849999999999994E+000 0")):
        padded = jl.load(_zmx(tmp_path, old, new))
        assert np.array_equal(padded.thickness, plain.thickness)
        assert padded.surfaces[2].k == plain.surfaces[2].k


def test_load_refuses_a_zmx_option_for_json_and_names_a_folder(tmp_path):
    """Main: ``unknown_glass='model'`` (``report --unknown-glass model``) was ignored for a
    .json lens, and a folder was refused as "has extension ''"."""
    with pytest.raises(ValueError, match=r"load: unknown_glass='model' opens a \.zmx .* so it "
                                         r"does not apply to .*cooke_triplet\.json"):
        jl.load(COOKE, unknown_glass="model")
    with pytest.raises(ValueError, match=r"load: '.*' is a folder; give a lens file"):
        jl.load(tmp_path)


def test_vjp_probe_refuses_options_its_mode_does_not_read(monkeypatch, capsys, tmp_path):
    """Main: ``--check --json out.json`` ran the check and wrote no file; ``--fusions``
    ignored ``--lens`` and ``--repeats``; ``--chunk 4096 4096`` timed the chunk twice."""
    import benchmarks.vjp_probe as VJ

    for name in ("check", "count_fusions", "timing"):
        monkeypatch.setattr(VJ, name, started)
    for argv, msg in (
            (["--check", "--json", str(tmp_path / "v.json")],
             "--check does not read --json (those set the timing run)"),
            (["--fusions", "--lens", "cellphone6", "--repeats", "3"],
             "--fusions does not read --lens, --repeats"),
            (["--check", "--fusions"], "--check and --fusions are two runs; give one"),
            (["--chunk", "4096", "4096"], "--chunk names a chunk size more than once")):
        with pytest.raises(SystemExit):
            VJ.main(argv)
        assert msg in capsys.readouterr().err
    with pytest.raises(Started):  # control: the timing reads them all
        VJ.main(["--repeats", "3", "--chunk", "4096", "--json", str(tmp_path / "v.json")])


def test_benchmark_modules_refuse_a_path_in_a_tag_and_a_patch_past_the_frame(
        monkeypatch, capsys, tmp_path):
    """Main: ``design_step --tag ../x`` wrote its result outside ``--out-dir``;
    ``render_speed --patch 1000`` (a 512-pixel frame) timed one 1000² tile, recorded as
    patch 1000, and ``render_memory --patch 200`` did so for its 128-pixel runs."""
    import benchmarks.common as BC
    import benchmarks.design_step as DS
    import benchmarks.render_memory as RM
    import benchmarks.render_speed as RS

    monkeypatch.setattr(DS, "import_baseline", started)
    monkeypatch.setattr(BC, "machine_info", started)
    monkeypatch.setattr(RM, "run_isolated", started)  # its first work: a worker process
    for main, argv, msg in (
            (DS.main, ["--tag", "../x"], "--tag: letters, digits, '_' and '-' only"),
            (RS.main, ["--patch", "1000", "--out", str(tmp_path / "r.json")],
             "--patch 1000 must be at most --size 512 pixels"),
            (RM.main, ["--patch", "200"],
             "--patch 200 must be at most the smallest frame side, 128 pixels")):
        with pytest.raises(SystemExit):
            main(argv)
        assert msg in capsys.readouterr().err
    # The control's default --baseline must not depend on the clone's history.
    monkeypatch.setattr(DS, "baseline_problem", lambda ref: None)
    with pytest.raises(Started):  # controls
        DS.main(["--tag", "new_rule"])
    with pytest.raises(Started):
        RS.main(["--out", str(tmp_path / "r.json")])


def test_report_refuses_lenient_for_json_and_a_repeated_field(capsys):
    """Main: ``report x.json --lenient`` did nothing without a word (strict is a .zmx
    reading), and ``--fields 0 0`` reported the same field twice."""
    from jaxlens.__main__ import main

    cooke = str(ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json")
    for argv, msg in (([cooke, "--lenient"], "--lenient reads a .zmx file"),
                      ([cooke, "--fields", "0", "0"], "--fields gives a field more than once")):
        assert main(["report", *argv]) == 2
        assert msg in capsys.readouterr().err
