# ruff: noqa: E501, E731
"""Round-35a bad-input probes: the command lines' options that earlier rounds touched least
(``python -m jaxlens.experiments.edof``'s image folders, ``--resume`` and scale options,
``python -m benchmarks`` and ``benchmarks.render_memory``, ``tolerance``, the ``jaxlens``
CLI's ``report``, ``classical``'s solver and loss options). The table of ``tools/probe_table.py`` (probe | outcome | what happened).

Each probe stops where the command's work would begin: the edof probes run the option
checks (``cli.check_args``) and then the run's first step that reads user files (the scene
loading, ``cli._scenes``; or ``cli.run`` up to the first lens's training), so a refusal
that came only there is a "crash" (a traceback after the run folder was started).

Gaps found and fixed:
1. edof ``--test-dir``/``--train-dir``: the option checks read each file's structure only
   (Pillow's ``verify``), so a float32 TIFF of HDR values, an int32 TIFF, a multi-page TIFF
   or a test image of which no crop is kept (all black) failed with a traceback in the run,
   after its folder was started (and without the file's name). Now decoded in the checks
   (``scenes.check_folder``), the file named; the no-crop message says why crops are dropped.
2. edof ``--resume`` over a checkpoint of other training options (or one with more stage-2
   steps done than ``--steps2``, or a .json that is not JSON) was refused at that lens's
   start, as a traceback saying "another configuration"; for seed 1's checkpoint, after seed
   0's whole training. Now every checkpoint the run would continue is checked first, and the
   message names each option that differs with both values (``train.check_resumable``).
3. edof ``--binning`` that leaves a frame smaller than a test crop was refused as "--tile
   must divide the 1-pixel frame"; ``--lens-every`` above ``--steps`` trained the lens once
   (step 0); ``--real-halo`` with the NAFNet decoder (the ``--smoke`` default) was dropped.
4. ``python -m benchmarks --only render_speed --out DIR`` wrote the render result to
   benchmarks/results/ (over the committed one) and never checked DIR's file; now into DIR
   (``--tag`` names it as the others), checked before the first benchmark. ``--smoke --only
   render_speed`` ran nothing: refused.
5. ``benchmarks.render_memory --trace-rays N`` or ``--checkpoint 0`` without ``--worker``
   ran the full study with the option dropped: refused.
6. ``classical --tolerance-aware K --loss image``: the image fine-tuning (the last stage: no
   polish follows it) is nominal, undoing the tolerance-aware stages: refused.

Before (base fd24690, an archive) and after (branch audit35a), the same 62 probes,
``PYTHONPATH=<tree> python tools/audit35a_probe.py`` from this tree's root, about 2 minutes
each way on 2 busy cores:
    before: clear error: 16, crash: 10, ok: 22, silent wrong: 11, vague error: 3
    after:  clear error: 39, ok: 23

Probe (before -> after):
    edof --smoke --binning 1024 (a 1-pixel frame)                                                vague error  -> clear error
    edof --smoke --binning 64 (a 16-pixel frame, crop 32)                                        vague error  -> clear error
    edof --smoke --binning 32 (control)                                                          ok           -> ok
    edof --smoke --lens-every 100 (--steps 60: one lens update)                                  silent wrong -> clear error
    edof --smoke --lens-every 60 (control)                                                       ok           -> ok
    edof --steps 100 --lens-every 100 (control)                                                  ok           -> ok
    edof --smoke --real-halo (decoder nafnet: no front end)                                      silent wrong -> clear error
    edof --real-halo --decoder nafnet                                                            silent wrong -> clear error
    edof --smoke --real-halo --decoder wiener (control)                                          ok           -> ok
    edof --seeds 0,1,0                                                                           clear error  -> clear error
    edof --seeds 0,-1                                                                            clear error  -> clear error
    edof --out a file                                                                            clear error  -> clear error
    edof --steps nan                                                                             clear error  -> clear error
    edof --time-limit nan                                                                        clear error  -> clear error
    edof --read-noise 0 (control: no read noise)                                                 ok           -> ok
    edof --photons inf                                                                           clear error  -> clear error
    edof --paper --binning 8 (a 128-pixel frame, crop 256)                                       vague error  -> clear error
    edof --test-dir a grey 8-bit PNG (control)                                                   ok           -> ok
    edof --test-dir an RGB 16-bit PNG (control)                                                  ok           -> ok
    edof --test-dir a grey 16-bit PNG (control)                                                  ok           -> ok
    edof --test-dir an RGBA PNG (control)                                                        ok           -> ok
    edof --test-dir a grey+alpha PNG (control)                                                   ok           -> ok
    edof --test-dir a palette PNG (control)                                                      ok           -> ok
    edof --test-dir a 1-bit PNG (control)                                                        ok           -> ok
    edof --test-dir a CMYK JPEG (control)                                                        ok           -> ok
    edof --test-dir a float32 TIFF in [0, 1] (control)                                           ok           -> ok
    edof --test-dir a float32 HDR TIFF (values to 5)                                             crash        -> clear error
    edof --test-dir an int32 TIFF                                                                crash        -> clear error
    edof --test-dir a 2-page TIFF                                                                crash        -> clear error
    edof --test-dir an all-black image (no crop kept)                                            crash        -> clear error
    edof --test-dir a 20x20 image (smaller than the 32-pixel crop)                               clear error  -> clear error
    edof --test-dir an empty folder                                                              clear error  -> clear error
    edof --train-dir a float32 HDR TIFF                                                          crash        -> clear error
    edof --train-dir a 2-page TIFF                                                               crash        -> clear error
    edof --train-dir a 16-bit RGB PNG (control)                                                  ok           -> ok
    edof --resume --steps 80 over a --steps 60 checkpoint                                        crash        -> clear error
    edof --resume over a checkpoint of another --lr-net                                          crash        -> clear error
    edof --resume --steps2 2 over a lens with 4 stage-2 steps done                               crash        -> clear error
    edof --resume --seeds 0,1, seed 1's checkpoint of another --steps (after seed 0's training?) silent wrong -> clear error
    edof --resume over a checkpoint .json that is not JSON                                       crash        -> clear error
    edof --resume, no checkpoint of the lens (control: starts, with a note)                      ok           -> ok
    render_memory --trace-rays 1000 without --worker (ignored?)                                  silent wrong -> clear error
    render_memory --checkpoint 0 without --worker (ignored?)                                     silent wrong -> clear error
    render_memory --size 256 (control: starts)                                                   ok           -> ok
    benchmarks --smoke --only render_speed (runs nothing?)                                       silent wrong -> clear error
    benchmarks --smoke --only render_memory skipping                                             silent wrong -> clear error
    benchmarks --only render_speed --out DIR (written to DIR?)                                   silent wrong -> ok
    benchmarks --only render_speed --out DIR holding a foreign render_speed.json                 silent wrong -> clear error
    benchmarks --only nosuch_bench                                                               clear error  -> clear error
    tolerance the Cooke triplet (not the classical spec)                                         clear error  -> clear error
    tolerance --trials 1e3 (not whole?)                                                          clear error  -> clear error
    tolerance --seed 2**40                                                                       clear error  -> clear error
    tolerance a design path that is a folder                                                     clear error  -> clear error
    jaxlens report --wavelengths -0.5876                                                         clear error  -> clear error
    jaxlens report --fields 10 --json (control)                                                  ok           -> ok
    jaxlens report --wavefront --plot FILE                                                       clear error  -> clear error
    jaxlens --float32 report --wavefront (control)                                               ok           -> ok
    classical --tolerance-aware 2 --loss image (image fine-tuning nominal)                       silent wrong -> clear error
    classical --tolerance-aware 2 (control)                                                      ok           -> ok
    classical --loss image --solver lm (control)                                                 ok           -> ok
    classical --solver lbfgsb --float32 --no-regularize (control)                                ok           -> ok
    classical --solver newton                                                                    clear error  -> clear error

Run from the tree's root: ``PYTHONPATH=. python tools/audit35a_probe.py [filter]``.
"""

import contextlib
import io
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import COOKE, FILTER, ROWS, TMP, cli, fresh, patched, probe, run  # noqa: E402

SMOKE = ("--smoke", "--quiet")


def _image(folder, name, array=None, *, pil=None, **save):
    """Write an image file into ``folder`` (a numpy array through Pillow, or a Pillow image)."""
    from PIL import Image

    im = pil if pil is not None else Image.fromarray(array)
    im.save(os.path.join(folder, name), **save)
    return folder


def _rgb(side=64, seed=0):
    return (np.random.default_rng(seed).random((side, side, 3)) * 255).astype(np.uint8)


def edof_load(*argv):
    """``python -m jaxlens.experiments.edof --smoke ARGV`` up to its scenes: the option checks
    (a refusal: ValueError), then the scene loading of the run (a failure there: a crash)."""
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.runfolder import UsageError

    def go():
        a = E.build_parser().parse_args([*SMOKE, "--out", fresh("eo"), *argv])
        try:
            cfg, _, _ = E.check_args(a)
        except UsageError as e:
            raise ValueError(str(e)) from None
        try:
            _, windows, _, _, _ = E._scenes(a, cfg)
        except Exception as e:  # noqa: BLE001
            raise RuntimeError(f"after the checks, in the run: {e}") from None
        return f"loaded: {len(windows)} test crops"
    return cli(go)


def edof_until_training(*argv):
    """``edof.run(--smoke ARGV)`` with training replaced by ``Started``: "started" when every
    check passed and the first lens reached its training; a refusal by the option checks is a
    ValueError, any error after them a crash."""
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.edof import train as T
    from jaxlens.experiments.runfolder import UsageError

    def go():
        try:
            return E.run([*SMOKE, "--out", fresh("eu"), *argv])
        except UsageError as e:
            raise ValueError(str(e)) from None
        except ValueError as e:
            raise RuntimeError(f"after the checks, in the run: {e}") from None
    return patched(T.Trainer, ["run"], go)


def edof_check(*argv):
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.runfolder import UsageError

    def go():
        try:
            E.check_args(E.build_parser().parse_args([*SMOKE, "--out", fresh("ec"), *argv]))
        except UsageError as e:
            raise ValueError(str(e)) from None
        return "accepted"
    return cli(go)


def edof_images():
    from PIL import Image

    from jaxlens.io.images import write_png

    rgb = _rgb()
    grey = rgb[..., 0]
    f = lambda name, arr=None, **k: _image(fresh("img"), name, arr, **k)
    probe("edof --test-dir a grey 8-bit PNG (control)", edof_load("--test-dir", f("a.png", grey)), good=True)
    d16 = fresh("img")
    write_png(os.path.join(d16, "a.png"), rgb / 255.0, linear=False, bits=16)
    probe("edof --test-dir an RGB 16-bit PNG (control)", edof_load("--test-dir", d16), good=True)
    probe("edof --test-dir a grey 16-bit PNG (control)", edof_load("--test-dir", f("a.png", grey.astype(np.uint16) * 257)), good=True)
    probe("edof --test-dir an RGBA PNG (control)", edof_load("--test-dir", f("a.png", np.dstack([rgb, np.full(grey.shape, 255, np.uint8)]))), good=True)
    probe("edof --test-dir a grey+alpha PNG (control)", edof_load("--test-dir", f("a.png", pil=Image.fromarray(grey).convert("LA"))), good=True)
    probe("edof --test-dir a palette PNG (control)", edof_load("--test-dir", f("a.png", pil=Image.fromarray(rgb).convert("P"))), good=True)
    probe("edof --test-dir a 1-bit PNG (control)", edof_load("--test-dir", f("a.png", grey > 128)), good=True)
    probe("edof --test-dir a CMYK JPEG (control)", edof_load("--test-dir", f("a.jpg", pil=Image.fromarray(rgb).convert("CMYK"))), good=True)
    probe("edof --test-dir a float32 TIFF in [0, 1] (control)", edof_load("--test-dir", f("a.tif", (grey / 255.0).astype(np.float32))), good=True)
    probe("edof --test-dir a float32 HDR TIFF (values to 5)", edof_load("--test-dir", f("a.tif", (grey / 51.0).astype(np.float32))), "--test-dir", "a.tif", "[0, 1]")
    probe("edof --test-dir an int32 TIFF", edof_load("--test-dir", f("a.tif", grey.astype(np.int32) * 100)), "--test-dir", "a.tif", "int32")
    dm = fresh("img")
    Image.fromarray(rgb).save(os.path.join(dm, "m.tif"), save_all=True, append_images=[Image.fromarray(rgb)])
    probe("edof --test-dir a 2-page TIFF", edof_load("--test-dir", dm), "--test-dir", "m.tif")
    probe("edof --test-dir an all-black image (no crop kept)", edof_load("--test-dir", f("a.png", np.zeros_like(rgb))), "--test-dir", "test crop", "mean")
    probe("edof --test-dir a 20x20 image (smaller than the 32-pixel crop)", edof_load("--test-dir", f("a.png", rgb[:20, :20])), "--test-dir", "20x20")
    probe("edof --test-dir an empty folder", edof_load("--test-dir", fresh("empty")), "--test-dir", "no image")
    probe("edof --train-dir a float32 HDR TIFF", edof_load("--train-dir", f("a.tif", (grey / 51.0).astype(np.float32))), "--train-dir", "a.tif", "[0, 1]")
    probe("edof --train-dir a 2-page TIFF", edof_load("--train-dir", dm), "--train-dir", "m.tif")
    probe("edof --train-dir a 16-bit RGB PNG (control)", edof_load("--train-dir", d16), good=True)


def _checkpoint(folder, seed=0, lens="classical", stage=1, step=20, **changes):
    """A checkpoint's ``<lens>.json`` (and a stand-in arrays file) of the smoke config with
    ``changes``, in ``folder/seed<seed>``."""
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.edof import train as T

    cfg = E.config_from_args(E.build_parser().parse_args(list(SMOKE)))
    config = T.config_data(cfg) | changes
    d = os.path.join(folder, f"seed{seed}")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, f"{lens}.x.eqx"), "wb") as f:
        f.write(b"\0" * 16)
    with open(os.path.join(d, f"{lens}.json"), "w") as f:
        json.dump({"stage": stage, "step": step, "hist": {"stage1": [], "stage2": []},
                   "rng": {}, "seconds": 1.0, "config": config, "params_version": 2,
                   "state_layout": 2, "tree": f"{lens}.x.eqx"}, f)
    return folder


def edof_resume():
    one = ("--lenses", "classical")
    ck = _checkpoint(fresh("ck"))
    probe("edof --resume --steps 80 over a --steps 60 checkpoint", edof_until_training(*one, "--checkpoint", ck, "--resume", "--steps", "80"), "--resume", "--steps", "60", "80")
    ck = _checkpoint(fresh("ck"), lr_net=1e-3)
    probe("edof --resume over a checkpoint of another --lr-net", edof_until_training(*one, "--checkpoint", ck, "--resume"), "--resume", "--lr-net", "0.001")
    ck = _checkpoint(fresh("ck"), stage=3, step=0, steps2=4)
    probe("edof --resume --steps2 2 over a lens with 4 stage-2 steps done", edof_until_training(*one, "--checkpoint", ck, "--resume"), "--steps2", "4")
    ck = _checkpoint(fresh("ck"), seed=1, steps=80)
    probe("edof --resume --seeds 0,1, seed 1's checkpoint of another --steps (after seed 0's training?)", edof_until_training(*one, "--seeds", "0,1", "--checkpoint", ck, "--resume"), "--resume", "seed1", "--steps")
    ck = fresh("ck")
    os.makedirs(os.path.join(ck, "seed0"))
    with open(os.path.join(ck, "seed0", "classical.json"), "w") as f:
        f.write("{not json")
    probe("edof --resume over a checkpoint .json that is not JSON", edof_until_training(*one, "--checkpoint", ck, "--resume"), "--resume", "classical.json")
    ck = _checkpoint(fresh("ck"), lens="cubic")  # no classical checkpoint: it starts over
    probe("edof --resume, no checkpoint of the lens (control: starts, with a note)", edof_until_training(*one, "--checkpoint", ck, "--resume"), good=True)


def edof_options():
    probe("edof --smoke --binning 1024 (a 1-pixel frame)", edof_check("--binning", "1024"), "--binning", "1024", "32")
    probe("edof --smoke --binning 64 (a 16-pixel frame, crop 32)", edof_check("--binning", "64"), "--binning", "64")
    probe("edof --smoke --binning 32 (control)", edof_check("--binning", "32"), good=True)
    probe("edof --smoke --lens-every 100 (--steps 60: one lens update)", edof_check("--lens-every", "100"), "--lens-every", "100", "60")
    probe("edof --smoke --lens-every 60 (control)", edof_check("--lens-every", "60"), good=True)
    probe("edof --steps 100 --lens-every 100 (control)", edof_check("--steps", "100", "--lens-every", "100"), good=True)
    probe("edof --smoke --real-halo (decoder nafnet: no front end)", edof_check("--real-halo"), "--real-halo", "nafnet")
    probe("edof --real-halo --decoder nafnet", edof_check_plain("--real-halo", "--decoder", "nafnet"), "--real-halo", "nafnet")
    probe("edof --smoke --real-halo --decoder wiener (control)", edof_check("--real-halo", "--decoder", "wiener"), good=True)
    probe("edof --seeds 0,1,0", edof_check("--seeds", "0,1,0"), "--seeds")
    probe("edof --seeds 0,-1", edof_check("--seeds", "0,-1"), "--seeds", "-1")
    a_file = os.path.join(TMP, "a_file")
    open(a_file, "w").close()
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.runfolder import UsageError

    def out_file():
        try:
            E.check_args(E.build_parser().parse_args([*SMOKE, "--out", a_file]))
        except UsageError as e:
            raise ValueError(str(e)) from None
        return "accepted"
    probe("edof --out a file", out_file, "--out", "file")
    probe("edof --steps nan", edof_check("--steps", "nan"), "--steps", "nan")
    probe("edof --time-limit nan", edof_check("--checkpoint", fresh("ck"), "--time-limit", "nan"), "--time-limit", "nan")
    probe("edof --read-noise 0 (control: no read noise)", edof_check("--read-noise", "0"), good=True)
    probe("edof --photons inf", edof_check("--photons", "inf"), "--photons", "inf")
    probe("edof --paper --binning 8 (a 128-pixel frame, crop 256)", cli(lambda: edof_check_plain("--paper", "--binning", "8")()), "--binning", "8")


def edof_check_plain(*argv):
    """``check_args`` without ``--smoke``."""
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.runfolder import UsageError

    def go():
        try:
            E.check_args(E.build_parser().parse_args(["--quiet", "--out", fresh("ep"), *argv]))
        except UsageError as e:
            raise ValueError(str(e)) from None
        return "accepted"
    return go


def benchmarks_cli():
    import benchmarks.render_memory as RM
    import benchmarks.run as BR

    rm = lambda *argv: cli(patched(RM, ["run_isolated"], lambda: RM.main([*argv, "--out", os.path.join(fresh("rm"), "r.json")])))
    probe("render_memory --trace-rays 1000 without --worker (ignored?)", rm("--trace-rays", "1000"), "--trace-rays", "--worker")
    probe("render_memory --checkpoint 0 without --worker (ignored?)", rm("--checkpoint", "0"), "--checkpoint", "--worker")
    probe("render_memory --size 256 (control: starts)", rm("--size", "256"), good=True)

    def bench(*argv, stop=("machine_info",)):
        import benchmarks.common as BC

        return cli(patched(BC, list(stop), lambda: BR.main(list(argv))))
    probe("benchmarks --smoke --only render_speed (runs nothing?)", bench("--smoke", "--only", "render_speed", "--out", fresh("b")), "--smoke", "render_speed")
    probe("benchmarks --smoke --only render_memory skipping", bench("--smoke", "--only", "render_memory", "skipping", "--out", fresh("b")), "--smoke", "render_memory")

    # --out for the render benchmarks: where does render_speed write? (its main stopped)
    import benchmarks.render_speed as RS

    seen = {}

    def fake_main(argv):
        seen["argv"] = list(argv)
        raise SystemExit(0)

    def where(*argv):
        def go():
            real = RS.main
            RS.main = fake_main
            try:
                BR.main(list(argv))
            except SystemExit:
                pass
            finally:
                RS.main = real
            out = seen.get("argv", [])
            target = out[out.index("--out") + 1] if "--out" in out else "its default, benchmarks/results/render_speed.json"
            if os.path.dirname(str(target)) != str(argv[argv.index("--out") + 1]):
                return f"render_speed writes to {target}"
            return "started"
        return cli(go)
    name = "benchmarks --only render_speed --out DIR (written to DIR?)"
    if not FILTER or FILTER in name:  # a wrong place is an answer: a row of its own
        with contextlib.redirect_stdout(io.StringIO()):
            said = where("--only", "render_speed", "--no-plots", "--out", fresh("b"))()
        ROWS.append((name, "ok" if said == "started" else "silent wrong", said))
    d2 = fresh("b")
    with open(os.path.join(d2, "render_speed.json"), "w") as f:
        f.write("my notes")
    probe("benchmarks --only render_speed --out DIR holding a foreign render_speed.json", bench("--only", "render_speed", "--out", d2), "render_speed.json", "not")
    probe("benchmarks --only nosuch_bench", bench("--only", "nosuch_bench", "--out", fresh("b")), "nosuch_bench")


def tolerance_cli():
    from jaxlens.experiments import tolerance as TL

    t = lambda *argv: cli(lambda: TL.main(list(argv)))
    probe("tolerance the Cooke triplet (not the classical spec)", t(COOKE, "--trials", "1", "--out", fresh("t")), "cooke")
    probe("tolerance --trials 1e3 (not whole?)", t(COOKE, "--trials", "1e3", "--out", fresh("t")), "--trials")
    probe("tolerance --seed 2**40", t(COOKE, "--seed", str(2**40), "--out", fresh("t")), "--seed")
    probe("tolerance a design path that is a folder", t(TMP, "--out", fresh("t")), "folder")


def report_cli():
    from jaxlens.__main__ import main as jl

    r = lambda *argv: cli(lambda: jl(["report", *argv]))
    probe("jaxlens report --wavelengths -0.5876", r(COOKE, "--wavelengths", "-0.5876"), "wavelength")
    probe("jaxlens report --fields 10 --json (control)", r(COOKE, "--fields", "10", "--json"), good=True)
    probe("jaxlens report --wavefront --plot FILE", r(COOKE, "--wavefront", "--plot", COOKE), "--plot")
    probe("jaxlens --float32 report --wavefront (control)", cli(lambda: jl(["--float32", "report", COOKE, "--wavefront", "--json"])), good=True)


def classical_cli():
    from jaxlens.experiments import classical as C

    c = lambda *a: cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", fresh("c"), *a])))
    probe("classical --tolerance-aware 2 --loss image (image fine-tuning nominal)", c("--tolerance-aware", "2", "--loss", "image"), "--tolerance-aware", "--loss image")
    probe("classical --tolerance-aware 2 (control)", c("--tolerance-aware", "2"), good=True)
    probe("classical --loss image --solver lm (control)", c("--loss", "image", "--solver", "lm"), good=True)
    probe("classical --solver lbfgsb --float32 --no-regularize (control)", c("--solver", "lbfgsb", "--float32", "--no-regularize"), good=True)
    probe("classical --solver newton", c("--solver", "newton"), "--solver", "newton")


if __name__ == "__main__":
    run([edof_options, edof_images, edof_resume, benchmarks_cli, tolerance_cli, report_cli,
         classical_cli])
