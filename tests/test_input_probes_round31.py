"""Bad input, round 31 (tools/audit31_probe.py): one test per class of gap fixed. Each names
what main did with the input: wasted work, a file written over, a traceback, or a silent
answer."""

import dataclasses
import json
import pathlib

import jax
import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens import zoo
from jaxlens.io import lensfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"


class Started(Exception):
    """Raised where a command's work would begin: its checks have passed."""


def started(*a, **k):
    raise Started


def _tile_shapes(lens, patch):
    """The [rows, cols] of the tiles ``render`` maps over, read from its jaxpr (not run)."""
    scene = jnp.ones(lens.sensor.resolution + (3,))
    jaxpr = jax.make_jaxpr(lambda s: jl.render(lens, s, spp=1, key=jax.random.PRNGKey(0),
                                               patch=patch))(scene)
    shapes = set()

    def walk(jx):
        for e in jx.eqns:
            if e.primitive.name == "scan":
                shapes.update(tuple(v.aval.shape[1:3]) for v in e.outvars if v.aval.ndim == 4)
            for p in e.params.values():
                for sub in p if isinstance(p, (list, tuple)) else [p]:
                    inner = getattr(sub, "jaxpr", sub)
                    inner = getattr(inner, "jaxpr", inner)
                    if hasattr(inner, "eqns"):
                        walk(inner)
    walk(jaxpr.jaxpr)
    return shapes


def test_render_traces_no_pixels_past_the_image():
    """Main: ``patch=64`` (the default) on a 12 × 16 sensor traced a 64 × 64 tile, 21 times
    the image's pixels (the answer cropped, right). A tile now stops at the image's side
    where one tile spans it, with each pixel's samples drawn as before."""
    lens = dataclasses.replace(zoo.cooke_triplet(), sensor=jl.Sensor((12, 16), 0.05))
    shapes = _tile_shapes(lens, 64)  # also the footprint grid's scans, smaller
    assert (12, 16) in shapes and all(r <= 12 and c <= 16 for r, c in shapes), shapes


def test_benchmarks_refuse_to_write_over_a_foreign_plot(tmp_path, monkeypatch, capsys):
    """Main: ``python -m benchmarks --out DIR`` refused a foreign ``throughput.json`` (round
    30) but wrote its plot over a foreign ``throughput.png``."""
    import benchmarks.common as BC
    import benchmarks.run as BR

    monkeypatch.setattr(BC, "machine_info", started)  # the first thing after the checks
    (tmp_path / "throughput.png").write_bytes(b"my photograph")
    with pytest.raises(SystemExit):
        BR.main(["--only", "throughput", "--out", str(tmp_path)])
    assert ("throughput.png is not a throughput benchmark plot (no throughput.json beside "
            "it), and this run would write its throughput plot over it") in capsys.readouterr().err
    with pytest.raises(Started):  # control: no plot is written
        BR.main(["--only", "throughput", "--no-plots", "--out", str(tmp_path)])
    (tmp_path / "throughput.json").write_text(json.dumps(
        {"benchmark": "throughput", "command": "python -m benchmarks"}))
    with pytest.raises(Started):  # control: a result and its plot are replaced together
        BR.main(["--only", "throughput", "--out", str(tmp_path)])


def test_benchmark_modules_refuse_to_write_over_a_file_that_is_not_their_result(
        tmp_path, monkeypatch, capsys):
    """Main: ``render_speed --out my_lens.json`` (or ``render_memory --out``, ``vjp_probe
    --json``) wrote its timings over whatever file was there: a lens, notes, another
    benchmark's result."""
    import shutil

    import benchmarks.common as BC
    import benchmarks.render_memory as RM
    import benchmarks.render_speed as RS
    import benchmarks.vjp_probe as VJ

    monkeypatch.setattr(BC, "machine_info", started)
    monkeypatch.setattr(RM, "run_isolated", started)
    monkeypatch.setattr(VJ, "timing", started)
    lens = tmp_path / "my_lens.json"
    shutil.copy(COOKE, lens)
    speed = tmp_path / "speed.json"
    shutil.copy(ROOT / "benchmarks" / "results" / "render_speed.json", speed)
    for main, argv, msg in (
            (RS.main, ["--out", str(lens)], 'my_lens.json is not a render_speed result (it has '
                                            'no "command" entry), and this run would write '
                                            'over it'),
            (RM.main, ["--out", str(lens)], "my_lens.json is not a render_memory result"),
            (VJ.main, ["--json", str(speed)], "speed.json is not a vjp_probe result (it is a "
                                              "result of 'python -m benchmarks.render_speed')")):
        with pytest.raises(SystemExit):
            main(argv)
        assert msg in capsys.readouterr().err
    assert lens.read_text() == COOKE.read_text()
    with pytest.raises(Started):  # control: its own earlier result is replaced
        RS.main(["--out", str(speed)])


def test_baseline_revision_git_does_not_know_is_one_line(monkeypatch, capsys):
    """Main: ``design_step``/``fast_path --baseline nosuchrev`` ended in git archive's
    CalledProcessError traceback."""
    import benchmarks.design_step as DS
    import benchmarks.fast_path as FP

    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(DS, "step_fn", started)
    monkeypatch.setattr(FP, "trace_fns", started)
    for main in (DS.main, FP.main):
        with pytest.raises(SystemExit) as e:
            main(["--baseline", "nosuchrev"])
        assert e.value.code == 2
        assert "--baseline 'nosuchrev': " in capsys.readouterr().err


def test_lens_file_warns_of_a_repeated_field_and_an_inside_out_element():
    """Main: a field given twice weighed twice in every field average without a word (a
    wavelength twice was warned about), and the Cooke triplet's first thickness typed -3
    (in N-SK16, no mirror) traced 0.58 mm RMS spots without a word."""
    d = json.loads(COOKE.read_text())
    d["fields"]["values"] = [0.0, 14.0, 14.0]
    with pytest.warns(UserWarning, match=r"x\.json: a field is given twice \(\[ 0\., 14\., "
                                         r"14\.\] deg\); it weighs twice"):
        lensfile.lens_from_dict(d, source="x.json")
    d = json.loads(COOKE.read_text())
    d["surfaces"][1]["thickness"] = -3.0
    with pytest.warns(UserWarning, match=r"x\.json: surface 1: thickness -3 mm inside N-SK16, "
                                         r"with no mirror before it"):
        lensfile.lens_from_dict(d, source="x.json")
    d["surfaces"][1]["thickness"] = 3.25896
    d["surfaces"][2]["thickness"] = -1.0  # control: in air (as to a dummy surface)
    lensfile.lens_from_dict(d, source="x.json")


def test_lens_file_reads_a_material_catalog():
    """Main: ``{"name": "N-SK16", "catalog": "CDGM"}`` (or ``"SCHOT"``) loaded SCHOTT's
    N-SK16 without a word: the catalog was not read (a key far from every known one passes
    as a comment)."""
    d = json.loads(COOKE.read_text())
    for cat, msg in (("SCHOT", r"surface 1: catalog 'SCHOT': Unknown catalog\(s\) "
                               r"\['SCHOT'\]"),
                     ("CDGM", r"surface 1: catalog 'CDGM': Unknown material 'N-SK16'.*in "
                              r"catalog SCHOTT, not searched here")):
        d["surfaces"][1]["material"] = {"name": "N-SK16", "catalog": cat}
        with pytest.raises(ValueError, match=msg):
            lensfile.lens_from_dict(d, source="x.json")
    d["surfaces"][1]["material"] = {"name": "N-SK16", "catalog": "schott"}  # control
    assert lensfile.lens_from_dict(d, source="x.json").materials[0].catalog == "SCHOTT"


def test_design_refuses_switches_that_are_not_bools(monkeypatch):
    """Main: ``design(shard="no")`` sharded (bool("no") is True) and ``image_loss=5``
    fine-tuned on rendered images, both found only after the set-up."""
    from jaxlens.design import multistart

    monkeypatch.setattr(multistart, "run", started)
    spec = jl.design.DesignSpec()
    for kw in (dict(shard="no"), dict(image_loss=5)):
        (name, value), = kw.items()
        with pytest.raises(ValueError, match=f"design: {name} must be True or False, got "
                                             f"{value!r}"):
            multistart.design(spec, [0], progress=False, **kw)


def test_curriculum_run_checks_its_solver_factory_objective_and_mesh():
    """Main: ``run(..., make_solver="adam")`` failed as "'str' object is not callable",
    ``objective=None`` as an AttributeError, and ``mesh="cpu"`` reached the first stage."""
    import types

    import jaxlens.design as D

    stage = D.Stage("x", fov=40.0, fnum=4.0, steps=10)
    params = types.SimpleNamespace(c=jnp.zeros((1, 3)))  # read for its dtype and batch only
    obj = types.SimpleNamespace(sampling=types.SimpleNamespace(area=jnp.ones(3)))

    def run(*args, **kw):
        D.run(D.DesignSpec(), [stage], params, *args, progress=False, **kw)

    for args, kw, msg in (((obj, "adam"), {}, r"run: make_solver must be callable"),
                          ((None, started), {}, r"run: objective must be an Objective"),
                          ((obj, started), dict(mesh="cpu"), r"run: mesh must be a "
                                                             r"jax\.sharding\.Mesh")):
        with pytest.raises(TypeError, match=msg):
            run(*args, **kw)
    with pytest.raises(Started):  # control: reaches the first stage's solver
        run(obj, started)


def test_save_names_a_folder(tmp_path):
    """Main: ``save(lens, "x.json/")`` said "has extension ''", and ``save(lens, "x.json")``
    with x.json a folder raised IsADirectoryError after the checks."""
    (tmp_path / "x.json").mkdir()
    for path in (str(tmp_path / "x.json") + "/", tmp_path / "x.json"):
        with pytest.raises(ValueError, match=r"save: .*x\.json/?' is a folder; give a file"):
            jl.save(zoo.cooke_triplet(), path)
