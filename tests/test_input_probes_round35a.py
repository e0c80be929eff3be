"""Bad input, round 35a (tools/audit35a_probe.py): the command lines' options that earlier
rounds touched least. One test per class of gap fixed; each names what main did with the
input: a refusal after the run had started (a traceback), an option dropped without a word,
a message that blamed another option, results written outside ``--out``."""

import json
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


class Started(Exception):
    """Raised where a command's work would begin: its checks have passed."""


def started(*a, **k):
    raise Started


def _edof_check(tmp_path, *argv):
    """``edof``'s option checks (``cli.check_args``) of ``--smoke ARGV``."""
    from jaxlens.experiments.edof import cli

    return cli.check_args(
        cli.build_parser().parse_args(["--smoke", "--quiet", "--out", str(tmp_path / "run"), *argv])
    )


@pytest.mark.parametrize(
    "argv, match",
    [
        (
            ["--binning", "1024"],
            r"--binning must leave a frame of at least one 32-pixel test crop "
            r"\(1024 / --binning >= 32, so --binning <= 32\), got 1024",
        ),
        (["--lens-every", "100"], r"--lens-every must be at most --steps 60 steps .*got 100"),
        (
            ["--real-halo"],
            r"--real-halo .* needs a front end .*got --decoder nafnet \(the --smoke "
            r"default\)",
        ),
    ],
)
def test_edof_scale_options_name_the_option_at_fault(tmp_path, argv, match):
    """Main: ``--binning 1024`` was refused as "--tile must divide the 1-pixel frame" (the
    tile was fine); ``--lens-every 100`` with 60 steps trained the lens once, at step 0;
    ``--real-halo`` with the NAFNet decoder (no front end) was dropped (``front_pad``)."""
    from jaxlens.experiments.runfolder import UsageError

    with pytest.raises(UsageError, match=match):
        _edof_check(tmp_path, *argv)
    # controls
    _edof_check(tmp_path, "--binning", "32", "--lens-every", "60")
    _edof_check(tmp_path, "--real-halo", "--decoder", "wiener")


def _images(folder, name, array=None, pages=1):
    from PIL import Image

    folder.mkdir(parents=True, exist_ok=True)
    im = Image.fromarray(array)
    im.save(
        folder / name,
        **({"save_all": True, "append_images": [im] * (pages - 1)} if pages > 1 else {}),
    )
    return str(folder)


def test_edof_image_folders_are_decoded_before_the_run(tmp_path):
    """Main: a float HDR TIFF (values to 5), an int32 TIFF, a 2-page TIFF or a test image
    with no crop kept (all black) passed the option checks (Pillow's ``verify`` reads no
    pixels) and failed with a traceback in the run, after its folder was started, without
    the file's name."""
    from jaxlens.experiments.runfolder import UsageError

    grey = (np.random.default_rng(0).random((64, 64)) * 255).astype(np.uint8)
    for opt, name, array, pages, match in (
        (
            "--test-dir",
            "hdr.tif",
            (grey / 51.0).astype(np.float32),
            1,
            r"--test-dir: scenes: the image .*hdr\.tif: to_linear: img must be finite values "
            r"in \[0, 1\]",
        ),
        (
            "--test-dir",
            "i.tif",
            grey.astype(np.int32) * 100,
            1,
            r"--test-dir: scenes: the image .*i\.tif: .*got int32",
        ),
        (
            "--test-dir",
            "m.tif",
            np.dstack([grey] * 3),
            2,
            r"--test-dir: scenes: the image .*m\.tif: expected a grey or RGB image, got "
            r"shape \(2, 64, 64, 3\)",
        ),
        (
            "--test-dir",
            "black.png",
            np.zeros_like(grey),
            1,
            r"--test-dir: scenes: no 32x32 test crop in .*black\.png.*darker than a linear "
            r"mean of 0\.02",
        ),
        (
            "--train-dir",
            "hdr.tif",
            (grey / 51.0).astype(np.float32),
            1,
            r"--train-dir: scenes: the image .*hdr\.tif",
        ),
    ):
        folder = _images(tmp_path / f"{opt}{name}", name, array, pages)
        with pytest.raises(UsageError, match=match):
            _edof_check(tmp_path, opt, folder)
    # controls: a float TIFF in [0, 1] and a grey PNG
    _edof_check(
        tmp_path, "--test-dir", _images(tmp_path / "ok", "a.tif", (grey / 255.0).astype(np.float32))
    )
    _edof_check(tmp_path, "--test-dir", _images(tmp_path / "ok2", "a.png", grey))


def _checkpoint(folder, seed=0, lens="classical", stage=1, step=20, text=None, **changes):
    """A checkpoint's ``<lens>.json`` of the smoke configuration with ``changes``."""
    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.edof import train as T

    cfg = cli.config_from_args(cli.build_parser().parse_args(["--smoke"]))
    d = folder / f"seed{seed}"
    d.mkdir(parents=True, exist_ok=True)
    (d / f"{lens}.x.eqx").write_bytes(b"\0" * 16)
    (d / f"{lens}.json").write_text(
        text
        if text is not None
        else json.dumps(
            {
                "stage": stage,
                "step": step,
                "hist": {},
                "rng": {},
                "seconds": 1.0,
                "config": T.config_data(cfg) | changes,
                "params_version": 2,
                "state_layout": 2,
                "tree": f"{lens}.x.eqx",
            }
        )
    )
    return str(folder)


def test_edof_resume_checks_every_checkpoint_before_any_work(tmp_path):
    """Main: ``--resume`` over a checkpoint of other training options was refused only at
    that lens's start, after the scenes and the lens set-up (for seed 1's checkpoint after
    seed 0's whole training), as a traceback saying "another configuration" without naming
    the option; a checkpoint .json that was not JSON failed with json's message alone."""
    from jaxlens.experiments.runfolder import UsageError

    one = ("--lenses", "classical", "--resume", "--checkpoint")
    for i, (kw, extra, match) in enumerate(
        (
            (
                {},
                ("--steps", "80"),
                r"--resume: the checkpoint .*seed0.classical\.json of the "
                r"classical lens was written with other training options "
                r"\(--steps 60 there, 80 here\)",
            ),
            ({"lr_net": 1e-3}, (), r"\(--lr-net 0\.001 there, 0\.005 here\)"),
            (
                {"seed": 1, "steps": 80},
                ("--seeds", "0,1"),
                r"seed1.classical\.json .*--steps 80 "
                r"there, 60 here",
            ),
            (
                {"stage": 3, "step": 0, "steps2": 4},
                (),
                r"has 4 stage-2 steps, more than "
                r"--steps2 2",
            ),
            (
                {"text": "{not json"},
                (),
                r"--resume: .*classical\.json is not a readable "
                r"checkpoint",
            ),
        )
    ):
        ck = _checkpoint(tmp_path / f"ck{i}", **kw)
        with pytest.raises(UsageError, match=match):
            _edof_check(tmp_path, *one, ck, *extra)
    # controls: the same options, and a checkpoint of another lens only (it starts over)
    _edof_check(tmp_path, *one, _checkpoint(tmp_path / "same"))
    _edof_check(tmp_path, *one, _checkpoint(tmp_path / "other", lens="cubic", steps=5))


def test_benchmarks_render_runs_write_into_out_and_refuse_smoke(monkeypatch, capsys, tmp_path):
    """Main: ``python -m benchmarks --only render_speed --out DIR`` wrote the render result
    to benchmarks/results/ (the committed one), not DIR, without checking what DIR held;
    ``--smoke --only render_speed`` ran nothing at all."""
    import benchmarks.common as BC
    import benchmarks.render_speed as RS
    import benchmarks.run as BR

    monkeypatch.setattr(
        BC,
        "machine_info",
        lambda: {"cpu_model": "x", "logical_cores": 1, "jax": "x", "load_average_at_start": 0},
    )
    seen = []
    monkeypatch.setattr(RS, "main", lambda argv: seen.append(argv) or started())
    with pytest.raises(Started):
        BR.main(["--only", "render_speed", "--tag", "t", "--out", str(tmp_path / "b")])
    assert seen == [["--out", str(tmp_path / "b" / "render_speed_t.json")]]
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "render_speed.json").write_text("my notes")
    for argv, msg in (
        (
            ["--smoke", "--only", "render_speed", "skipping"],
            "--only render_speed: --smoke does not run the render benchmarks",
        ),
        (
            ["--only", "render_speed", "--out", str(tmp_path / "c")],
            "render_speed.json is not a render_speed result (it is not JSON)",
        ),
    ):
        with pytest.raises(SystemExit) as e:
            BR.main(argv)
        assert e.value.code == 2 and msg in capsys.readouterr().err
    assert len(seen) == 1


def test_render_memory_refuses_worker_options_without_worker(monkeypatch, capsys, tmp_path):
    """Main: ``render_memory --trace-rays 1000`` or ``--checkpoint 0`` without ``--worker``
    ran the full study (with and without checkpointing, and its own 10**6-ray reference),
    the option dropped."""
    import benchmarks.render_memory as RM

    monkeypatch.setattr(RM, "run_isolated", started)
    out = str(tmp_path / "r.json")
    for argv, msg in (
        (["--trace-rays", "1000"], "--trace-rays 1000 sets what one --worker"),
        (["--checkpoint", "0"], "--checkpoint 0 sets one --worker's render"),
    ):
        with pytest.raises(SystemExit) as e:
            RM.main([*argv, "--out", out])
        assert e.value.code == 2 and msg in capsys.readouterr().err
    with pytest.raises(Started):  # control
        RM.main(["--size", "256", "--out", out])


def test_classical_refuses_tolerance_aware_with_the_image_loss(monkeypatch, capsys, tmp_path):
    """Main: ``--tolerance-aware 2 --loss image`` fine-tuned, as the last stage (no polish
    follows the image loss), on the nominal image loss: the design ended at the nominal
    optimum, the tolerance-aware option undone without a word."""
    from jaxlens.experiments import classical as C

    monkeypatch.setattr(C, "run_design", started)
    assert C.main(["--out", str(tmp_path / "c"), "--tolerance-aware", "2", "--loss", "image"]) == 2
    assert "--tolerance-aware 2 averages the ray loss" in capsys.readouterr().err
    with pytest.raises(Started):  # control
        C.main(["--out", str(tmp_path / "c2"), "--tolerance-aware", "2"])
