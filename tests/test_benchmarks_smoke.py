"""The benchmark suite still runs (``python -m benchmarks --smoke``); timings are not checked.

Runs in-process on tiny sizes (one lens, 1e3/1e4 rays), writes into a temporary folder and
checks that every result file exists and holds sane, finite numbers, and that every shortcut
in the skipping benchmark gives the same answer as the full computation.
"""

import json
import math
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def smoke_results(tmp_path_factory):
    from benchmarks import throughput
    from benchmarks.run import main

    out = tmp_path_factory.mktemp("bench")
    # optiland (if installed) is exercised by the full suite; the smoke run stays fast.
    original = throughput.run

    def quick(**kw):
        return original(with_optiland=False, **kw)

    throughput.run = quick
    try:
        res = main(
            [
                "--smoke",
                "--out",
                str(out),
                "--no-plots",
                "--only",
                "throughput",
                "pareto",
                "skipping",
            ]
        )
    finally:
        throughput.run = original
    return out, res


def test_files_written(smoke_results):
    out, _ = smoke_results
    for name in ("throughput", "pareto", "skipping"):
        data = json.loads((out / f"{name}.json").read_text())
        assert data["machine"]["cpu_model"]
        assert data["machine"]["jax"]
        assert "--smoke" in data["command"]
    assert (out / "README.md").read_text().startswith("# jaxlens benchmark results")


def test_throughput_rows(smoke_results):
    _, res = smoke_results
    rows = res["throughput"]["rows"]
    modes = {(r["engine"], r["dtype"], r["mode"]) for r in rows}
    assert ("jaxlens", "float32", "forward") in modes
    assert ("jaxlens", "float64", "forward+grad") in modes
    for r in rows:
        assert r["rate"] > 0 and math.isfinite(r["rate"])
        # rate = ray·surfaces per second of the best run; the best run is no slower than
        # the median; the first call (trace, compile and one run) is slower than a warm run.
        assert r["rate"] == pytest.approx(r["rays"] * r["surfaces"] / r["run_s"], rel=1e-12)
        assert 0 < r["run_s"] <= r["median_s"] and r["repeats"] >= 1
        if r["engine"] == "jaxlens":
            assert r["compile_s"] > r["run_s"]


def test_pareto_recommends(smoke_results):
    _, res = smoke_results
    p = res["pareto"]
    assert p["rms_spot"]["recommendation"]["equal_weight"] is not None
    assert "float64" in p["newton"]["recommendation"]
    for r in p["dtype"]["rows"]:
        assert r["max_intercept_dev_mm"] < 1e-3


def test_shortcuts_give_the_same_answer(smoke_results):
    _, res = smoke_results
    for r in res["skipping"]["rows"]:
        assert r["same_answer"], r


def test_readme_lists_defaults_and_tagged_runs(smoke_results):
    """The README sets every recommendation beside the library's default, and a ``--tag``
    rerun's file gets its own section without replacing the full one."""
    import shutil

    from benchmarks.run import write_readme
    from benchmarks.summary import library_defaults

    out, _ = smoke_results
    lib = library_defaults()
    assert lib["newton_iters"][0] >= 1
    assert lib["rms_spot_pupil"][0] is not None  # the rms_spot fallback is still found
    shutil.copy(out / "throughput.json", out / "throughput_quick.json")
    write_readme(out)
    text = (out / "README.md").read_text()
    assert "## Recommended defaults against the library's" in text
    assert "Newton iterations, float64" in text
    assert "## throughput\n" in text and "## throughput_quick\n" in text


def test_defaults_name_files_that_exist(tmp_path):
    """Each library default's "where" names a module of today's tree (after the layout
    move, the table still pointed at jaxlens/trace.py and jaxlens/psf.py), and a result file
    that no study makes is listed with its command rather than left out."""
    import json
    import pathlib

    from benchmarks.run import write_readme
    from benchmarks.summary import library_defaults

    root = pathlib.Path(__file__).resolve().parent.parent
    for key, (_, where) in library_defaults().items():
        path = where.split(" ", 1)[0]
        assert (root / path).is_file(), (key, where)
    (tmp_path / "vjp_probe_x.json").write_text(json.dumps({"command": "python -m x --y"}))
    write_readme(tmp_path)
    text = (tmp_path / "README.md").read_text()
    assert "| `vjp_probe_x.json` |" in text and "`python -m x --y`" in text


def test_design_step_smoke(tmp_path):
    """The old-against-new benchmark runs end to end (this commit against itself). The
    baseline's programs are traced and lowered from the extracted copy; where one lowers to
    the new version's program it runs that executable on its own inputs (no second compile)."""
    from benchmarks import design_step

    r = design_step.main(["--baseline", "HEAD", "--seeds", "1", "--repeats", "1", "--rays",
                          "512", "--out-dir", str(tmp_path)])
    assert json.loads((tmp_path / "design_step.json").read_text())["loss_sum"] == r["loss_sum"]
    # The same code on both sides computes the same loss, to the last bit.
    assert r["loss_sum"]["new"] == r["loss_sum"]["baseline"] and r["loss_sum"]["new"] > 0
    assert set(r["shared_compile"]) <= {k for k in r["median_s"] if k.endswith("baseline")}
    assert len(r["median_s"]) == 6 and all(v > 0 for v in r["median_s"].values())
    assert all(v > 0 for v in r["compile_s"].values())


def test_render_memory_smoke():
    """One checkpointed render gradient and the bare-trace reference, each in its own process,
    on tiny sizes and the smallest zoo lens (the phone lens's render gradient alone compiles in
    about a minute); the per-ray residual note is the slope between the plain runs."""
    from benchmarks import render_memory

    cap = 8 * 2**30
    run = render_memory.run_isolated(32, 1, True, 16, cap, lens="cooke_triplet")
    assert run["lens"] == "cooke_triplet" and run["checkpoint"] and run["patch"] == 16
    assert run["gradient_finite"] and run["run_s"] > 0 and run["rays"] == 32 * 32 * 3
    assert math.isfinite(run["loss"]) and run["loss"] > 0
    assert run["peak_rss_bytes"] > 10**8  # a Python process with JAX: the RSS was read
    ref = render_memory.run_isolated(0, 0, False, 0, cap, trace_rays=4096, lens="cooke_triplet")
    assert ref["surfaces"] == 6 and math.isfinite(ref["rate"]) and ref["rate"] > 0
    runs = [dict(rays=100, checkpoint=False, peak_rss_bytes=10_000),
            dict(rays=300, checkpoint=False, peak_rss_bytes=50_000),
            dict(rays=300, checkpoint=True, peak_rss_bytes=1)]
    assert "about 200 bytes per ray" in render_memory.residual_note(runs, 10, 1)
    assert "bytes per ray" not in render_memory.residual_note(runs[:1], 10, 1)


def test_reevaluate_without_optiland_says_so(monkeypatch, capsys, tmp_path):
    import shutil

    from benchmarks import optiland_ref, reevaluate

    monkeypatch.setattr(optiland_ref, "available", lambda: False)
    # Valid arguments (a folder of readable .zmx designs): round 44b checks them first.
    designs = tmp_path / "designs"
    designs.mkdir()
    shutil.copy(pathlib.Path(__file__).parents[1] / "experiments" / "classical" / "designs"
                / "seed_0.zmx", designs)
    assert reevaluate.main([str(designs)]) == 2
    assert "optiland is not installed" in capsys.readouterr().err


def test_reevaluate_agrees_with_jaxlens_on_an_exported_design(tmp_path):
    """The independent tracer reproduces jaxlens's Table 1 evaluation of a shipped design."""
    pytest.importorskip("optiland")
    import shutil

    from benchmarks import reevaluate

    src = ROOT / "experiments" / "classical" / "designs" / "seed_0.zmx"
    (tmp_path / "designs").mkdir()
    shutil.copy(src, tmp_path / "designs" / src.name)
    assert reevaluate.main([str(tmp_path / "designs")]) == 0
    out = json.loads((tmp_path / "reevaluation.json").read_text())
    row = out["per_design"][0]
    assert row["jaxlens_valid"] and row["optiland_rays_ok"]
    assert abs(row["relative_difference"]) < 1e-5  # optiland stops its Newton earlier


def test_first_crossing_scan_accepts_a_correct_trace_and_rejects_a_wrong_root(monkeypatch):
    """The brute-force check behind the re-evaluation: jaxlens's intersections on a shipped
    +recipe design are first crossings; the same path checked against a lens with one gap
    0.05 mm longer (its points now off the surfaces) is rejected."""
    import equinox as eqx
    import jax.numpy as jnp
    import numpy as np

    import jaxlens as jl
    import jaxlens.tracing.forward as fwd
    from benchmarks import reevaluate
    from jaxlens.imaging.sampling import field_rays, pupil_grid

    lens = jl.load(ROOT / "experiments" / "classical" / "designs" / "seed_11.zmx")
    rays = field_rays(lens, jnp.array([31.0, 31.0]), pupil_grid(9), 0.4861327)
    valid = np.asarray(jl.trace(lens, rays).valid)
    assert valid.sum() > 10
    assert np.array_equal(reevaluate.first_crossings(lens, rays), valid)
    path = fwd.trace_path(lens, rays)
    monkeypatch.setattr(fwd, "trace_path", lambda *_: path)
    moved = eqx.tree_at(lambda x: x.thickness, lens, lens.thickness.at[4].add(0.05))
    assert not reevaluate.first_crossings(moved, rays)[valid].any()


@pytest.mark.parametrize("args", [["--trace-rays", "-3"], ["--size", "0"], ["--cap-gib", "nan"],
                                  ["--spp", "-1"]])
def test_render_memory_refuses_bad_arguments(args, capsys):
    """Bad sizes are refused with the option's name before any worker starts."""
    from benchmarks import render_memory

    with pytest.raises(SystemExit):
        render_memory.main(args)
    assert args[0] in capsys.readouterr().err


def test_grad_levers_smoke():
    """The gradient-lever probe (benchmarks/SPEED.md): a flag setting that XLA refuses is
    reported and skipped (its child process dies at start-up), a chunk size is measured."""
    from benchmarks import grad_levers

    rows = grad_levers.main(["--rays", "2000", "--flag=--xla_cpu_no_such_flag=1",
                             "--chunks", "1024"])
    assert len(rows) == 1 and rows[0]["chunk"] == 1024
    # A timing ratio on a shared machine: only its being measured is checked here; the
    # figures are the benchmark's (benchmarks/SPEED.md), never a unit test's.
    assert math.isfinite(rows[0]["ratio"]) and rows[0]["ratio"] > 0


def test_vjp_probe_smoke(tmp_path):
    """The reverse-rule probe from its command line, float64 rays, 2048 in chunks of 512 (the
    chunked, checkpointed path): the three programs timed, the rule's value and gradient equal
    to JAX's to rounding, the JSON file written with its command."""
    import json

    from benchmarks import vjp_probe

    path = tmp_path / "probe.json"
    vjp_probe.main(["--rays", "2048", "--repeats", "1", "--chunk", "512", "--dtype", "float64",
                    "--json", str(path)])
    out = json.loads(path.read_text())
    assert out["rays"] == 2048 and "--json" in out["command"]
    assert len(out["programs"]) == 3
    assert all(math.isfinite(r["ms"]) and r["ms"] > 0 for r in out["programs"].values())
    row = out["chunks"]["512"]
    assert row["rule_grad_rel"] < 1e-10
    # A timing ratio: measured, not bounded (a loaded CI machine gave 5.8 once).
    assert math.isfinite(row["forward_over_fg_rule"]) and row["forward_over_fg_rule"] > 0


@pytest.mark.parametrize("args, match", [
    (["--smoke", "--full"], "does not go with --smoke"),
    (["--full", "--counts", "1000"], "does not go with --counts"),
])
def test_run_refuses_full_where_it_would_be_ignored_or_heavy(args, match, capsys):
    from benchmarks.run import main

    with pytest.raises(SystemExit):
        main(args)
    assert match in capsys.readouterr().err


def test_smoke_throughput_runs_every_lens_asked_for():
    """A smoke run keeps one lens only by default; lenses named are all run (only the first
    one was, silently)."""
    from benchmarks.throughput import LENSES, chosen_lenses

    assert chosen_lenses(True) == LENSES[:1] and chosen_lenses(False) == LENSES
    asked = ("cooke_triplet", "double_gauss")
    assert chosen_lenses(True, asked) == asked == chosen_lenses(False, list(asked))
