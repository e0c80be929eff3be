# ruff: noqa: E501, E731, B023
"""Round-43b bad-input probes: the newest APIs (``paraxial.magnification``,
``analysis.stop_clipping``, the telecentric report and ``Lens(object_na=...)``, SCHOTT's IRG
glasses in the INFRARED catalog, ``report_cells``), every flag of the command lines
(``python -m jaxlens.experiments.classical``, ``.edof``, ``.tolerance``, ``.ablation_table``,
``python -m benchmarks``, ``python -m benchmarks.reevaluate``, ``python -m jaxlens report``)
given wrong types, values out of range, NaN/inf, empty strings and output folders that hold
an earlier run, the image inputs of the library (``render``, ``NAFNet``, ``psnr``/``ssim``,
``io.images``): dtypes, channels, NaN pixels, value ranges, shapes; and the lens-file writers
on unusual but valid lenses (object-space telecentric, afocal image space, a virtual object):
what is written must read back the same, or be refused. The table of ``tools/probe_table.py``.

The command lines are called in-process through their ``main(argv)`` (``check_args`` for
edof) with the function that starts the long work replaced (``probe_table.patched``): a
probe ends "started" (a silent wrong for a bad value) when every check passed.

Gaps found and fixed (one mechanism per class):
1. Comma lists of the command lines read by ``str.isdigit``: ``classical --seed-list ١`` and
   ``edof --seeds ١`` / ``--enc ١,1,1`` ran as 1 (Arabic-Indic digits); now
   ``runfolder.comma_ints`` (each entry ``checks.cli_int``: ASCII digits). ``--columns
   baseline,baseline`` designed one column twice: refused.
2. Output and input paths checked late: ``python -m benchmarks --out FILE/x`` passed every
   check and ended in a NotADirectoryError traceback (now ``runfolder.check_writable``, every
   command's folder check); ``python -m benchmarks.reevaluate`` read its .zmx files one by
   one inside the work, so a broken file stopped it midway (now all are read first, the
   broken one named); ``python -m jaxlens.experiments.ablation_table`` ran, printed nothing
   and exited 0 (now exit 2, pointing to ``classical --ablation``).
3. The telecentric report and ``stop_clipping`` took any argument: a focal lens failed as
   float(None), an afocal one inside ``distortion``; ``wavefront="yes"``, ``notes="a note"``
   and ``notes=[5]`` ran; ``format_telecentric_report({})`` was a KeyError;
   ``stop_clipping(None)``/``note(None)`` AttributeErrors, and a primary wavelength outside
   the glasses' data gave None ("no clipping") from a NaN rim ray
   (``checks.primary_wavelength``).
4. Integer images: one rule now, as ``render``, ``srgb_to_linear`` and the writers had it:
   a library function that takes linear light refuses an integer image
   (``checks.image_dtype``, naming ``to_linear``, the explicit conversion). ``NAFNet`` ran a
   uint8/uint16/int32 image as radiance 0…255 (round 26 had made it convert the codes to
   floats), a bool or complex one failed naming no dtype. The layers (Conv, NAFBlock) still
   take integer feature maps as floats.
5. Image metrics on two scales: ``psnr`` of uint8 against uint16 codes gave 0.03 dB (and
   uint8 against int64), two bool images 0 dB, two numbers 15.6 dB, 0…255 float images with
   ``data_range=1`` −8.1 dB; ``ssim`` of 4-d images failed in skimage's words. Integer
   images must share one dtype, bool and 0-d ones are refused, a ``data_range`` below half
   the values' span is refused (a restored image may overshoot [0, 1] a little), ``ssim``
   takes [H, W] or [H, W, C].

Judged right (controls, ``good=True``): magnification at several wavelengths (one each), of
an afocal system at a finite distance (−f2/f1 at any distance), ``stop_clipping`` under jit
(documented None), a dark field of a telecentric report (None cells, a warning), IRG22's
nd=/vd= (only for an unknown name's hint), a traced wavelength out of a glass's range
(not checked under jit, as everywhere), ``wavefront_summary``'s "refused" entry, NAFNet on
floats of any range and on float16, ssim of 1-d signals, ``write_png`` of grey+alpha and of
linear values above 1 (clipped, documented), edof ``--steps2 0``, ``--middle 0``,
``--context 0``, a ``--record`` folder to be created, ``--resume`` with an empty checkpoint
folder, and the writers' round trips (.json and .zmx) of telecentric, immersion, afocal,
virtual-object, finite-object, real-aimed and (x, y)-field lenses: every one reads back the
same (the .zmx reader sets ``negative_propagation``, documented).

Left (noted): ``report_cells``' formatting helpers (``json_number``, ``cell``,
``seidel_lines``, ``wavefront_lines``, ``aiming_line``) and ``ablation_table.fmt`` given
foreign types (internal: the reports call them with their own data); magnification of an
object in the front focal plane (3.7e15 for an image at infinity, not inf); ``--fnum 1e300``
and edof ``--photons 1e-300`` (no upper or useful lower bound); ``write_psf_stack`` of
negative values.

Before (base b3da160) and after (branch probe43b), the same 572 probes, 3 to 5 minutes on 2
busy cores:
    before: clear error: 436, crash: 7, ok: 88, silent wrong: 29, vague error: 12
    after:  clear error: 470, ok: 88, silent wrong: 8, vague error: 6

Run from the tree's root: ``PYTHONPATH=. python tools/audit43b_probe.py [filter]``.
"""

import dataclasses
import json
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import (  # noqa: E402
    COOKE,
    ROOT,
    SEED0,
    TMP,
    checked,
    cli,
    edof_check,
    fresh,
    jitted,
    patched,
    probe,
    run,
)

import jaxlens as jl  # noqa: E402
from jaxlens import analysis as A  # noqa: E402
from jaxlens.analysis import report as REP  # noqa: E402
from jaxlens.analysis import report_cells as RC  # noqa: E402
from jaxlens.analysis import report_telecentric as RT  # noqa: E402
from jaxlens.optics import paraxial as PX  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data")
cooke = jl.load(COOKE)
TELE = os.path.join(DATA, "tele42a", "tele_triplet_far.zmx")
TELE_IMM = os.path.join(DATA, "tele42a", "tele_immersion.zmx")
KEPLER = os.path.join(DATA, "afocal_kepler.zmx")
tele = jl.load(TELE)
kepler = jl.load(KEPLER)
R = dataclasses.replace

BAD_FLOATS = ("", "nan", "inf", "-inf", "abc", "1e400", "1_0", "0x10", "١٢")
BAD_INTS = ("", "2.5", "1e3", "nan", "abc", "1_0", "-1", "99999999999999999999")


def finite(lens, z):
    """``lens`` with its object at ``z`` mm before the first surface (negative: virtual)."""
    return R(lens, object_distance=jnp.asarray(z, float))


def _at_front_focus(lens):
    """``lens`` with its object in its front focal plane (the image at infinity): the
    paraxial ray from the axial object point leaves parallel to the axis."""
    from scipy.optimize import brentq

    u_out = lambda z: float(PX.marginal_ray(finite(lens, z), lens.wavelengths[lens.primary])[1][-1])
    return finite(lens, brentq(u_out, 1.0, 500.0))


def newest_apis():
    """magnification, stop_clipping, the telecentric report, object_na, IRG, report_cells."""
    mag = PX.magnification
    fin = finite(cooke, 500.0)
    probe("magnification wavelength 550 (nm)", lambda: mag(fin, 550.0), "magnification", "wavelength")
    probe("magnification wavelength 'd'", lambda: mag(fin, "d"), "magnification", "wavelength")
    probe("magnification wavelength [0.55, 0.65] (documented: one per wavelength; control)", lambda: mag(fin, [0.55, 0.65]), good=True)
    probe("magnification wavelength nan", lambda: mag(fin, float("nan")), "wavelength")
    probe("magnification wavelength True", lambda: mag(fin, True), "wavelength")
    probe("magnification wavelength np.True_", lambda: mag(fin, np.True_), "wavelength")
    probe("magnification wavelength 0.55+0j", lambda: mag(fin, 0.55 + 0j), "wavelength")
    probe("magnification wavelength -0.55", lambda: mag(fin, -0.55), "wavelength")
    probe("magnification wavelength 0", lambda: mag(fin, 0.0), "wavelength")
    probe("magnification wavelength 30 (beyond the glasses' data)", lambda: mag(fin, 30.0), "wavelength")
    probe("magnification lens a dict", lambda: mag(json.load(open(COOKE))), "magnification", "lens")
    probe("magnification lens a path", lambda: mag(COOKE), "magnification", "lens")
    probe("magnification lens None", lambda: mag(None), "magnification", "lens")
    probe("magnification object at infinity (documented 0; control)", lambda: float(mag(cooke)), good=True)
    probe("magnification afocal Kepler, finite object (an afocal system: m = -f2/f1 at any distance; control)", lambda: float(mag(finite(kepler, 500.0))), good=True)
    probe("magnification object at the front focal plane (image at infinity)", lambda: float(mag(_at_front_focus(cooke))), "magnification")
    checked("magnification telecentric lens = its paraxial ratio (control)", lambda: (
        np.isfinite(float(mag(tele))), f"{float(mag(tele)):.6g}"))
    checked("magnification virtual object (object -200 mm: m finite)", lambda: (
        np.isfinite(float(mag(finite(cooke, -200.0)))), f"{float(mag(finite(cooke, -200.0))):.6g}"))
    probe("magnification traced wavelength under jit (control)", lambda: jax.jit(lambda w: mag(fin, w))(0.55), good=True)
    # stop_clipping
    sc = A.stop_clipping
    probe("stop_clipping lens None", lambda: sc(None), "stop_clipping", "lens")
    probe("stop_clipping lens a path", lambda: sc(COOKE), "stop_clipping", "lens")
    probe("stop_clipping lens a dict", lambda: sc({"surfaces": []}), "stop_clipping", "lens")
    probe("stop_clipping cooke (no clip; control)", lambda: sc(cooke), good=True)
    probe("stop_clipping telecentric (control)", lambda: sc(tele), good=True)
    probe("stop_clipping afocal (control)", lambda: sc(kepler), good=True)
    probe("stop_clipping lens epd nan", lambda: sc(R(cooke, epd=jnp.asarray(np.nan))), "epd")
    probe("stop_clipping lens with a primary wavelength its glasses lack", lambda: sc(R(cooke, wavelengths=jnp.array([30.0]), primary=0)), "wavelength")
    probe("stop_clipping under jit (documented: None; control)", lambda: jax.jit(lambda e: sc(R(cooke, epd=e)) is None)(10.0), good=True)
    probe("stop_clip.note lens None", lambda: A.stop_clip.note(None), "lens")
    # object_na
    for kind, v, word in (("-0.1", -0.1, "object_na"), ("0", 0.0, "object_na"), ("1.5 (beyond n=1)", 1.5, "object_na"),
                          ("nan", float("nan"), "object_na"), ("inf", float("inf"), "object_na"), ("'0.1'", "0.1", "object_na"),
                          ("True", True, "object_na"), ("np.True_", np.True_, "object_na"), ("0.1+0j", 0.1 + 0j, "object_na"),
                          ("[0.1, 0.2]", jnp.array([0.1, 0.2]), "object_na"), ("1.0 (n sin u = n)", 1.0, "object_na")):
        probe(f"Lens object_na {kind}", lambda: R(tele, object_na=v), word)
    probe("Lens object_na on an object at infinity", lambda: R(cooke, object_na=0.1), "object_na", "finite")
    probe("Lens object_na with aim 'real'", lambda: R(tele, aim="real"), "aim")
    probe("Lens object_na with a virtual object (-50 mm)", lambda: finite(tele, -50.0), "object")
    probe("Lens object_na 0.05 at 0.55 µm (control)", lambda: float(R(tele, object_na=0.05).object_na), good=True)
    probe("telecentric_report_data on a focal lens (not telecentric)", lambda: RT.telecentric_report_data(cooke), "telecentric")
    probe("telecentric_report_data on an afocal lens", lambda: RT.telecentric_report_data(kepler), "telecentric")
    probe("telecentric_report_data wavefront 'yes'", lambda: RT.telecentric_report_data(tele, wavefront="yes"), "wavefront")
    probe("telecentric_report_data notes 'a note' (a string, not a list)", lambda: RT.telecentric_report_data(tele, notes="a note"), "notes")
    probe("telecentric_report_data notes [5]", lambda: RT.telecentric_report_data(tele, notes=[5]), "notes")
    probe("telecentric_report_data lens a path", lambda: RT.telecentric_report_data(TELE), "lens")
    probe("format_telecentric_report data {}", lambda: RT.format_telecentric_report({}), "format_telecentric_report", "data")
    probe("format_telecentric_report data None", lambda: RT.format_telecentric_report(None), "format_telecentric_report", "data")
    probe("format_telecentric_report of an ordinary report's data", lambda: RT.format_telecentric_report(REP.report_data(cooke)), "telecentric")
    probe("report_data fields 95 mm on a telecentric lens (documented: a dark field's cells are None, warned; control)", lambda: REP.report_data(REP.with_fields_and_wavelengths(tele, [95.0]))["fields"][0]["rms_spot"], good=True)
    probe("report_data fields -1e6 mm on a telecentric lens (dark: None cells; control)", lambda: REP.report_data(REP.with_fields_and_wavelengths(tele, [-1e6]))["fields"][0]["rms_spot"], good=True)
    probe("with_fields_and_wavelengths fields [nan] telecentric", lambda: REP.with_fields_and_wavelengths(tele, [float("nan")]), "field")
    probe("with_fields_and_wavelengths wavelengths [0.55, 0.55] (repeated)", lambda: REP.with_fields_and_wavelengths(cooke, None, [0.55, 0.55]), "wavelength")
    probe("with_fields_and_wavelengths fields [0, 0] (repeated)", lambda: REP.with_fields_and_wavelengths(cooke, [0.0, 0.0]), "field")
    # IRG glasses
    gm = jl.get_material
    probe("get_material IRG22 (control)", lambda: float(gm("IRG22", "INFRARED").index(4.0)), good=True)
    probe("get_material irg22 lowercase (control)", lambda: float(gm("irg22").index(4.0)), good=True)
    probe("get_material IRG22 n(0.55) (outside 1–12 µm)", lambda: float(gm("IRG22").index(0.55)), "IRG22", "µm")
    probe("get_material IRG22 n(14) (beyond 12 µm)", lambda: float(gm("IRG22").index(14.0)), "IRG22", "µm")
    probe("get_material IRG22 n(4000) (nm)", lambda: float(gm("IRG22").index(4000.0)), "µm")
    probe("get_material 'IRG 22' (a space)", lambda: gm("IRG 22"), "IRG22")
    probe("get_material IRG29 (unknown, close matches)", lambda: gm("IRG29"), "IRG2")
    probe("get_material IRG22 catalog 'INFRA'", lambda: gm("IRG22", "INFRA"), "INFRARED")
    probe("get_material IRG22 catalog 'schott' (not there)", lambda: gm("IRG22", "SCHOTT"), "INFRARED")
    probe("get_material IRG100 (nd 1, vd 0 record)", lambda: float(gm("IRG100").index(4.0)), good=True)
    probe("get_material IRG22 nd= given (documented: nd, vd only for an unknown name's hint; control)", lambda: gm("IRG22", nd=2.6, vd=100.0), good=True)
    probe("nearest_glasses catalogs INFRARED nd 2.6 vd 100 (IRG no d-line data; control)", lambda: jl.catalog.nearest_glasses(2.6, 100.0, catalogs="INFRARED"), good=True)
    probe("nearest_glasses catalogs 'INFRAROT'", lambda: jl.catalog.nearest_glasses(1.6, 40.0, catalogs="INFRAROT"), "INFRARED")
    probe("IRG22 index under jit at 0.5 µm (documented: a traced wavelength is not range-checked; control)", lambda: jax.jit(gm("IRG22").index)(0.5), good=True)
    # report_cells
    probe("json_number '1.5'", lambda: RC.json_number("1.5"), "json_number")
    probe("json_number nan (documented None; control)", lambda: RC.json_number(float("nan")), good=True)
    probe("json_number [1, 2]", lambda: RC.json_number([1.0, 2.0]), "json_number")
    probe("json_number complex", lambda: RC.json_number(1 + 2j), "json_number")
    probe("cell 'abc'", lambda: RC.cell("abc"), "cell")
    probe("cell width -1", lambda: RC.cell(1.0, width=-1), "width")
    probe("cell width 2.5", lambda: RC.cell(1.0, width=2.5), "width")
    probe("cell prec -1", lambda: RC.cell(1.0, prec=-1), "prec")
    probe("cell None (documented 'failed'; control)", lambda: RC.cell(None), good=True)
    probe("cell inf", lambda: RC.cell(float("inf")), good=True)
    probe("seidel_lines sd 5", lambda: RC.seidel_lines(5, "x"), "seidel_lines")
    probe("wavefront_lines reference 5", lambda: RC.wavefront_lines([], 5), "reference")
    probe("wavefront_summary field 95 deg (documented: a 'refused' entry, the report's row; control)", lambda: RC.wavefront_summary(cooke, 95.0)["refused"], good=True)
    probe("wavefront_summary field 'x'", lambda: RC.wavefront_summary(cooke, "x"), "field")
    probe("bucketed_field_curvature fields []", lambda: RC.bucketed_field_curvature(cooke, []), "fields")
    probe("bucketed_field_curvature wavelengths 550 (nm)", lambda: RC.bucketed_field_curvature(cooke, [0.0, 10.0], [550.0]), "wavelength")
    probe("system_lines data {}", lambda: RC.system_lines({}, "t", [], "l"), "system_lines")
    probe("aiming_line data {}", lambda: RC.aiming_line({}), "aiming_line")


def _finished(name, files):
    d = fresh(name)
    for f in files:
        open(os.path.join(d, f), "w").write("earlier run\n")
    return d


def classical_cli():
    from jaxlens.experiments import classical as CL

    def c(*a, out=None):
        return cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--out", out or os.path.join(fresh("c"), "o"), *a])))

    floats = ("--fov", "--fnum", "--sensor-diagonal", "--track", "--bfl", "--fov-start", "--fnum-start", "--steps", "--tolerance-threshold")
    ints = ("--elements", "--stop", "--asphere-terms", "--seeds", "--first-seed", "--polish-steps", "--tolerance-aware", "--population", "--devices", "--tolerance-trials", "--ablation-seeds")
    for f in floats:
        for v in ("", "nan", "inf", "abc", "-1"):
            probe(f"classical {f} {v!r}", c(f, v), f)
    for f in ints:
        for v in ("", "2.5", "-1", "abc", "99999999999999999999"):
            probe(f"classical {f} {v!r}", c(f, v), f)
    probe("classical --fov 180", c("--fov", "180"), "--fov")
    probe("classical --fov 1e-300", c("--fov", "1e-300"), "--fov")
    probe("classical --fnum 1e300", c("--fnum", "1e300"), "--fnum")
    probe("classical --track 1e6 (1 km)", c("--track", "1e6"), "--track")
    probe("classical --bfl 10 beyond --track 7", c("--bfl", "10"), "--bfl")
    probe("classical --sensor-diagonal 1e6 mm", c("--sensor-diagonal", "1e6"), "--sensor-diagonal")
    probe("classical --fov-start 100 beyond --fov", c("--fov-start", "100"), "--fov-start")
    probe("classical --fnum-start 1 below --fnum", c("--fnum-start", "1"), "--fnum-start")
    probe("classical --seed-list ''", c("--seed-list", ""), "--seed-list")
    probe("classical --seed-list '1,,2'", c("--seed-list", "1,,2"), "--seed-list")
    probe("classical --seed-list '-1'", c("--seed-list=-1"), "--seed-list")
    probe("classical --seed-list '1.5'", c("--seed-list", "1.5"), "--seed-list")
    probe("classical --seed-list '١'", c("--seed-list", "١"), "--seed-list")
    probe("classical --materials ''", c("--materials", ""), "--materials")
    probe("classical --materials 'NOPE'", c("--materials", "NOPE"), "NOPE")
    probe("classical --materials 'E48R' for 6 elements", c("--materials", "E48R"), "--materials")
    probe("classical --material-catalogs ''", c("--select-materials", "continuous", "--material-catalogs", ""), "--material-catalogs")
    probe("classical --select-materials bogus", c("--select-materials", "bogus"), "--select-materials")
    probe("classical --recipe bogus", c("--recipe", "bogus"), "--recipe")
    probe("classical --solver sgd", c("--solver", "sgd"), "--solver")
    probe("classical --polish bfgs", c("--polish", "bfgs"), "--polish")
    probe("classical --loss l1", c("--loss", "l1"), "--loss")
    probe("classical --out a file", c(out=COOKE), "--out")
    probe("classical --out under a file", c(out=os.path.join(COOKE, "o")), "--out")
    probe("classical --out an earlier run's folder (a second run must not destroy it)", c(out=_finished("cl", ["RUN_FINISHED", "designs.json"])), "--overwrite")
    probe("classical --out a folder holding other files", c(out=_finished("cl", ["notes.txt"])), "--out")
    probe("classical --out ' '", c(out=" "), "--out")
    probe("classical --ablation-out a file", cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--ablation", "--ablation-out", COOKE]))), "--ablation-out")
    probe("classical --ablation-out ' '", cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--ablation", "--ablation-out", " "]))), "--ablation-out")
    probe("classical --columns ''", cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--ablation", "--ablation-out", os.path.join(fresh("ab"), "a"), "--columns", ""]))), "--columns")
    probe("classical --columns 'baseline,baseline' (repeated)", cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--ablation", "--ablation-out", os.path.join(fresh("ab"), "a"), "--columns", "baseline,baseline"]))), "--columns")
    probe("classical an unknown flag --fovv", c("--fovv", "60"), "--fovv")
    probe("classical a positional argument", c("extra"), "extra")
    probe("classical --smoke (control)", c("--smoke"), good=True)


def edof_cli():
    e = edof_check
    flags_int = ("--steps", "--steps2", "--batch", "--tile", "--kernel", "--binning", "--pupil", "--eval-pupil", "--lens-every", "--width", "--middle", "--n-odd", "--context", "--max-crops")
    flags_float = ("--lr-net", "--lr-lens", "--w-sim", "--w-raw", "--photons", "--read-noise", "--cubic-floor", "--hybrid-floor", "--time-limit")
    zero_ok = ("--steps2", "--middle", "--context")  # documented: 0 stage-2 steps, middle blocks, context pixels
    for f in flags_int:
        for v in ("0", "-1", "2.5", ""):
            if f in zero_ok and v == "0":
                probe(f"edof {f} '0' (documented; control)", e(f, v), good=True)
                continue
            probe(f"edof {f} {v!r}", e(f, v), f)
    for f in flags_float:
        for v in ("nan", "inf", "-1", ""):
            extra = ("--checkpoint", os.path.join(TMP, "ck")) if f == "--time-limit" else ()
            probe(f"edof {f} {v!r}", e(f, v, *extra), f)
    probe("edof --seeds ''", e("--seeds", ""), "--seeds")
    probe("edof --seeds '-1'", e("--seeds=-1"), "--seeds")
    probe("edof --seeds '0,0'", e("--seeds", "0,0"), "--seeds")
    probe("edof --seeds '0,,1'", e("--seeds", "0,,1"), "--seeds")
    probe("edof --enc '1,-1,1'", e("--enc", "1,-1,1"), "--enc")
    probe("edof --enc '1,1' with --dec '1,1,1'", e("--enc", "1,1", "--dec", "1,1,1"), "--dec")
    probe("edof --lenses ''", e("--lenses", ""), "--lenses")
    probe("edof --lenses 'cubic,nope'", e("--lenses", "cubic,nope"), "--lenses")
    probe("edof --decoder unet", e("--decoder", "unet"), "--decoder")
    probe("edof --depth-sampling log", e("--depth-sampling", "log"), "--depth-sampling")
    probe("edof --train-source web", e("--train-source", "web"), "--train-source")
    probe("edof --train-dir missing", e("--train-dir", os.path.join(TMP, "nope")), "--train-dir")
    probe("edof --train-dir a file", e("--train-dir", COOKE), "--train-dir")
    probe("edof --test-dir missing", e("--test-dir", os.path.join(TMP, "nope")), "--test-dir")
    probe("edof --test-dir empty folder", e("--test-dir", fresh("td")), "--test-dir")
    probe("edof --record in a missing folder (created, as --out; control)", e("--record", os.path.join(TMP, "nope", "r")), good=True)
    probe("edof --checkpoint a file", e("--checkpoint", COOKE), "--checkpoint")
    probe("edof --resume with an empty checkpoint folder (documented: every piece of a run may say --resume; control)", e("--checkpoint", fresh("ck"), "--resume"), good=True)
    probe("edof --seeds '١'", e("--seeds", "١"), "--seeds")
    probe("edof --enc '١,1,1'", e("--enc", "١,1,1"), "--enc")
    probe("edof --smoke and --paper", e("--smoke", "--paper"), "--paper")
    probe("edof --tile 1e9", e("--tile", "1000000000"), "--tile")
    probe("edof --kernel 32 (even)", e("--kernel", "32"), "--kernel")
    probe("edof --photons 1e-300", e("--photons", "1e-300"), "--photons")

    from jaxlens.experiments.edof import cli as ECLI
    from jaxlens.experiments.runfolder import UsageError

    def out_check(out, *argv):
        def go():
            try:
                ECLI.check_args(ECLI.build_parser().parse_args(["--out", out, *argv]))
            except UsageError as ex:
                raise ValueError(str(ex)) from None
            return "accepted"
        return go
    probe("edof --out an earlier run's folder", out_check(_finished("ed", ["RUN_FINISHED", "results.json"])), "--overwrite")
    probe("edof --out a file", out_check(COOKE), "--out")
    probe("edof --out ''", out_check(""), "--out")
    probe("edof --out ' '", out_check(" "), "--out")


def tolerance_cli():
    from jaxlens.experiments import tolerance as TC

    def t(*a, design=SEED0, out=None):
        return cli(patched(TC, ["analyse_design"], lambda: TC.main([design, "--out", out or fresh("t"), *a])))
    for f, vals in (("--trials", ("", "0", "-5", "2.5", "nan")), ("--threshold", ("", "0", "-1", "nan", "-inf", "abc")),
                    ("--seed", ("", "-1", "2.5", "99999999999999999999")), ("--decenter", ("", "-0.01", "inf", "1e9")),
                    ("--tilt", ("", "-1", "nan", "1e9"))):
        for v in vals:
            probe(f"tolerance {f} {v!r}", t(f, v), f)
    probe("tolerance design missing", t(design=os.path.join(TMP, "nope.zmx")), "nope.zmx")
    probe("tolerance design ''", t(design=""), "design")
    probe("tolerance design an empty .zmx", t(design=_empty("e.zmx")), "e.zmx")
    probe("tolerance design a .txt", t(design=_empty("e.txt", "hello")), "e.txt")
    probe("tolerance design a telecentric lens (another kind)", t(design=TELE), "tele_triplet_far")
    probe("tolerance design an afocal lens", t(design=KEPLER), "afocal")
    probe("tolerance --out a file", t(out=COOKE), "--out")
    probe("tolerance --out ' '", t(out=" "), "--out")
    probe("tolerance --out an earlier run's folder", t(out=_finished("to", ["tolerance.json"])), "--overwrite")
    probe("tolerance --out holding only the plot", t(out=_finished("to", ["tolerance_rms.png"])), "--overwrite")
    probe("tolerance --decenter 0.01 (control)", t("--decenter", "0.01"), good=True)


def _empty(name, text=""):
    p = os.path.join(fresh("f"), name)
    open(p, "w").write(text)
    return p


def ablation_cli():
    from jaxlens.design import DesignSpec
    from jaxlens.experiments import ablation_table as AT

    probe("python -m jaxlens.experiments.ablation_table (no command: must say so)", cli(lambda: _module("jaxlens.experiments.ablation_table")), "ablation")
    probe("python -m jaxlens.experiments.ablation_table --help", cli(lambda: _module("jaxlens.experiments.ablation_table", "--help")), "ablation")
    probe("read_column a missing file", lambda: AT.read_column(os.path.join(TMP, "nope.json")), "nope.json")
    probe("read_column a half-written file", lambda: AT.read_column(_empty("c.json", '{"switches": ')), "c.json")
    probe("read_column a list", lambda: AT.read_column(_empty("c.json", "[]")), "column")
    probe("read_column a folder", lambda: AT.read_column(TMP), "column")
    d = fresh("abt")
    os.makedirs(os.path.join(d, "columns"))
    open(os.path.join(d, "columns", "baseline.json"), "w").write('{"switches": {}, "command": "x", "spec": {"fov": 1}}')
    probe("check_columns a column of another spec", lambda: AT.check_columns(d, DesignSpec(), []), "spec")
    d2 = fresh("abt")
    os.makedirs(os.path.join(d2, "columns"))
    open(os.path.join(d2, "columns", "baseline.json"), "w").write("not json")
    probe("check_columns a column cut short", lambda: AT.check_columns(d2, DesignSpec(), []), "baseline.json")
    probe("column_file name ''", lambda: AT.column_file(TMP, ""), good=True)
    probe("fmt x 'a'", lambda: AT.fmt("a"), "fmt")
    probe("fmt x nan (the table shows nan; control)", lambda: AT.fmt(float("nan")), good=True)


def _module(module, *args):
    import subprocess

    p = subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True, cwd=fresh("m"),
                       timeout=120, env=dict(os.environ, PYTHONPATH=ROOT))
    last = (p.stderr.strip().splitlines() or [""])[-1]
    print(last, file=sys.stderr)
    if p.returncode == 0 and not p.stdout.strip() and not p.stderr.strip():
        return "exit 0, printed nothing"
    if p.returncode == 0:
        return p.stdout.strip()[-80:]
    if p.returncode == 2:
        raise SystemExit(2)
    raise RuntimeError(f"exit {p.returncode}: {last}")


def benchmarks_cli():
    import benchmarks.common as BC
    import benchmarks.run as BR

    def b(*a):
        def go():
            r = BR.main(list(a))
            return r
        return cli(patched(BC, ["machine_info"], go))
    out = lambda: os.path.join(fresh("b"), "o")
    for v in ("", "0", "-1", "2.5", "nan", "1e3", "abc"):
        probe(f"benchmarks --counts {v!r}", b("--only", "throughput", "--counts", v, "--out", out()), "--counts")
    probe("benchmarks --counts 10**13", b("--only", "throughput", "--counts", str(10**13), "--out", out()), "--counts")
    probe("benchmarks --only bogus", b("--only", "bogus", "--out", out()), "--only")
    probe("benchmarks --only (nothing)", b("--only", "--out", out()), "--only")
    probe("benchmarks --only throughput throughput", b("--only", "throughput", "throughput", "--out", out()), "--only")
    probe("benchmarks --lenses nope", b("--only", "throughput", "--lenses", "nope", "--out", out()), "--lenses")
    probe("benchmarks --lenses ''", b("--only", "throughput", "--lenses", "", "--out", out()), "--lenses")
    probe("benchmarks --lenses with --only pareto", b("--only", "pareto", "--lenses", "cooke_triplet", "--out", out()), "--lenses")
    probe("benchmarks --tag 'a b'", b("--smoke", "--tag", "a b", "--out", out()), "--tag")
    probe("benchmarks --tag ''", b("--smoke", "--tag", "", "--out", out()), "--tag")
    probe("benchmarks --tag '../x'", b("--smoke", "--tag", "../x", "--out", out()), "--tag")
    probe("benchmarks --out ''", b("--smoke", "--out", ""), "--out")
    probe("benchmarks --out ' '", b("--smoke", "--out", " "), "--out")
    probe("benchmarks --out a file", b("--smoke", "--out", COOKE), "--out")
    probe("benchmarks --out under a file", b("--smoke", "--out", os.path.join(COOKE, "x")), "--out")
    probe("benchmarks --out a folder with a foreign README.md", b("--smoke", "--out", _finished("bm", ["README.md"])), "README.md")
    probe("benchmarks --full --smoke", b("--full", "--smoke", "--out", out()), "--full")
    probe("benchmarks --smoke --only render_speed", b("--smoke", "--only", "render_speed", "--out", out()), "--smoke")
    probe("benchmarks --out a folder with a foreign throughput.json", b("--only", "throughput", "--out", _finished("bm", ["throughput.json"])), "throughput.json")
    probe("benchmarks --out a folder with a foreign throughput.png", b("--only", "throughput", "--out", _finished("bm", ["throughput.png"])), "throughput.png")
    probe("benchmarks --smoke --out fresh (control)", b("--smoke", "--out", out()), good=True)
    probe("benchmarks an unknown flag --fast", b("--fast"), "--fast")

    import benchmarks.optiland_ref as OR
    import benchmarks.reevaluate as RE

    def r(*a):
        def go():
            real = OR.available
            OR.available = lambda: True
            try:
                return RE.main(list(a))
            finally:
                OR.available = real
        return cli(patched(RE, ["reevaluate"], go))
    designs = os.path.dirname(SEED0)
    probe("reevaluate folder missing", r(os.path.join(TMP, "nope")), "nope")
    probe("reevaluate folder a file", r(COOKE), "folder")
    probe("reevaluate folder ''", r(""), "folder")
    probe("reevaluate folder without .zmx", r(fresh("re")), ".zmx")
    probe("reevaluate --out a folder", r(designs, "--out", TMP), "--out")
    probe("reevaluate --out in a missing folder", r(designs, "--out", os.path.join(TMP, "nope", "r.json")), "--out")
    probe("reevaluate --out ''", r(designs, "--out", ""), "--out")
    probe("reevaluate --out a foreign JSON file", r(designs, "--out", _empty("other.json", '{"a": 1}')), "--out")
    probe("reevaluate --out a lens file (.json)", r(designs, "--out", _copy(COOKE)), "--out")
    probe("reevaluate --out the .zmx it reads", r(designs, "--out", SEED0), "--out")
    probe("reevaluate a folder of broken .zmx", r(_broken_folder()), "zmx")


def _copy(path):
    import shutil

    d = os.path.join(fresh("cp"), os.path.basename(path))
    shutil.copy(path, d)
    return d


def _broken_folder():
    d = fresh("bz")
    open(os.path.join(d, "a.zmx"), "w").write("VERS 1\nSURF 0\n  CURV abc\n")
    return d


def report_cli():
    from jaxlens import __main__ as M
    from jaxlens.analysis import report as RP

    def rp(*a):
        return cli(patched(RP, ["report_data"], lambda: M.main(list(a))))
    for v in ("nan", "inf", "", "abc", "1_0"):
        probe(f"report telecentric --fields {v!r}", rp("report", TELE, "--fields", v), "--fields")
    probe("report --wavelengths 0", rp("report", COOKE, "--wavelengths", "0"), "wavelength")
    probe("report --wavelengths '' ", rp("report", COOKE, "--wavelengths", ""), "--wavelengths")
    probe("report --wavelengths 550 (nm, documented: read as nm; control)", rp("report", COOKE, "--wavelengths", "550"), good=True)
    probe("report --wavelengths 1e5 (nm? 100 µm)", rp("report", COOKE, "--wavelengths", "1e5"), "wavelength")
    probe("report --unknown-glass maybe", rp("report", SEED0, "--unknown-glass", "maybe"), "--unknown-glass")
    probe("report --unknown-glass on a .json", rp("report", COOKE, "--unknown-glass", "model"), "--unknown-glass")
    probe("report --lenient on a .json", rp("report", COOKE, "--lenient"), "--lenient")
    probe("report lens ''", rp("report", ""), "report")
    probe("report lens a .txt", rp("report", _empty("x.txt", "hi")), "x.txt")
    probe("report no lens", rp("report"), "lens")
    probe("report unknown command", rp("reprot", COOKE), "reprot")
    probe("report --plot under a file", rp("report", COOKE, "--plot", os.path.join(COOKE, "p")), "--plot")
    probe("report --plot ' '", rp("report", COOKE, "--plot", " "), "--plot")
    probe("report --plot a folder holding an earlier figure", rp("report", COOKE, "--plot", _finished("pl", ["cooke_triplet_spots.png"])), "--overwrite")
    probe("report a telecentric lens (control)", rp("report", TELE), good=True)
    probe("report an afocal lens (control)", rp("report", KEPLER), good=True)
    probe("report a telecentric immersion lens --fields 0 1 (control)", rp("report", TELE_IMM, "--fields", "0", "1"), good=True)


def images():
    """Image inputs: render, NAFNet, psnr/ssim, io.images."""
    from jaxlens.io import images as I

    key = jax.random.key(0)
    net = jl.nets.NAFNet(3, 3, width=8, enc_blocks=(1,), middle_blocks=1, dec_blocks=(1,), key=key)
    f8 = jnp.full((8, 8, 3), 0.5)
    probe("NAFNet uint8 image (0…255 codes)", lambda: net(jnp.full((8, 8, 3), 128, jnp.uint8)), "NAFNet", "uint8", "to_linear")
    probe("NAFNet uint16 image", lambda: net(jnp.full((8, 8, 3), 128, jnp.uint16)), "NAFNet", "to_linear")
    probe("NAFNet int32 image", lambda: net(jnp.full((8, 8, 3), 1, jnp.int32)), "NAFNet", "int32")
    probe("NAFNet bool image", lambda: net(jnp.ones((8, 8, 3), bool)), "NAFNet", "bool")
    probe("NAFNet complex image", lambda: net(jnp.ones((8, 8, 3), jnp.complex64)), "NAFNet", "complex")
    probe("NAFNet a numpy uint8 image", lambda: net(np.full((8, 8, 3), 128, np.uint8)), "NAFNet", "uint8")
    probe("NAFNet a list of lists", lambda: net([[[0.5] * 3] * 8] * 8).shape, good=True)
    probe("NAFNet NaN pixel", lambda: net(f8.at[0, 0, 0].set(jnp.nan)), "NAFNet", "NaN")
    probe("NAFNet inf pixel", lambda: net(f8.at[0, 0, 0].set(jnp.inf)), "NAFNet")
    probe("NAFNet (1, 8, 8, 3) batch", lambda: net(f8[None]), "NAFNet", "[H, W")
    probe("NAFNet (3, 8, 8) channels first", lambda: net(jnp.ones((3, 8, 8))), "NAFNet", "[H, W, 3]")
    probe("NAFNet (0, 8, 3) empty", lambda: net(jnp.ones((0, 8, 3))), "NAFNet", ">= 1")
    probe("NAFNet float16 image", lambda: net(f8.astype(jnp.float16)).dtype, good=True)
    probe("NAFNet values 0…255 as floats (linear floats of any range; control)", lambda: net(f8 * 255).shape, good=True)
    probe("NAFNet uint8 image under jit", lambda: eqx.filter_jit(net)(jnp.full((8, 8, 3), 128, jnp.uint8)), "NAFNet", "uint8")
    probe("NAFNet under jit NaN pixel", jitted(lambda x: net(x), f8.at[0, 0, 0].set(jnp.nan)), "NAFNet", "NaN")
    # render
    from jaxlens.imaging.render import render
    sensor = jl.Sensor((8, 8), 0.005)
    sc = jnp.full((8, 8, 3), 0.5, jnp.float32)
    rk = dict(sensor=sensor, spp=4, key=key)
    probe("render uint8 scene (control: refused)", lambda: render(cooke, jnp.full((8, 8, 3), 128, jnp.uint8), **rk), "render", "to_linear")
    probe("render bool scene", lambda: render(cooke, jnp.ones((8, 8, 3), bool), **rk), "render", "bool")
    probe("render NaN pixel", lambda: render(cooke, sc.at[0, 0, 0].set(jnp.nan), **rk), "render", "NaN")
    probe("render inf pixel", lambda: render(cooke, sc.at[0, 0, 0].set(jnp.inf), **rk), "render")
    probe("render negative radiance", lambda: render(cooke, sc.at[0, 0, 0].set(-1.0), **rk), "render", "scene")
    probe("render values 0…255 as floats (sRGB codes?)", lambda: render(cooke, sc * 255, **rk), good=True)
    probe("render complex scene", lambda: render(cooke, sc.astype(jnp.complex64), **rk), "render", "complex")
    probe("render (8, 8) grey scene, no channel axis", lambda: render(cooke, sc[..., 0], **rk), "render", "[H, W, C]")
    probe("render (3, 8, 8) channels first", lambda: render(cooke, jnp.transpose(sc, (2, 0, 1)), **rk), "render")
    probe("render 4 channels, 3 wavelengths", lambda: render(cooke, jnp.ones((8, 8, 4), jnp.float32), **rk), "render", "wavelength")
    probe("render a numpy uint8 scene", lambda: render(cooke, np.full((8, 8, 3), 128, np.uint8), **rk), "render", "to_linear")
    probe("render a list scene", lambda: render(cooke, sc.tolist(), **rk), good=True)
    # psnr / ssim
    a = np.full((8, 8, 3), 0.5)
    b = a + 0.01
    probe("psnr NaN pixel", lambda: jl.images.psnr(a, np.where(np.arange(a.size).reshape(a.shape) == 0, np.nan, b)), "psnr")
    probe("psnr uint8 and uint8 (one scale; control)", lambda: jl.images.psnr(np.full((8, 8), 100, np.uint8), np.full((8, 8), 101, np.uint8)), good=True)
    probe("psnr uint8 against int64 (0…255 against int64's range)", lambda: jl.images.psnr(np.full((8, 8), 100, np.uint8), np.full((8, 8), 101, np.int64)), "psnr", "int64")
    probe("psnr uint8 against uint16 (0…255 vs 0…65535)", lambda: jl.images.psnr(np.full((8, 8), 100, np.uint8), np.full((8, 8), 25700, np.uint16)), "psnr", "uint16")
    probe("psnr bool images", lambda: jl.images.psnr(np.ones((8, 8), bool), np.zeros((8, 8), bool)), "psnr", "bool")
    probe("psnr (8, 8, 3) against (8, 8)", lambda: jl.images.psnr(a, a[..., 0]), "psnr", "shape")
    probe("psnr float images of 0…255 values, data_range 1", lambda: jl.images.psnr(a * 255, b * 255, data_range=1.0), "psnr", "data_range")
    probe("psnr string images", lambda: jl.images.psnr(np.array(["a"]), np.array(["b"])), "psnr")
    probe("psnr scalars", lambda: jl.images.psnr(0.5, 0.6), "psnr")
    probe("ssim NaN pixel", lambda: jl.images.ssim(a, np.where(np.arange(a.size).reshape(a.shape) == 0, np.nan, b)), "ssim")
    probe("ssim (8, 8, 3, 2) 4-d images", lambda: jl.images.ssim(np.ones((8, 8, 3, 2)), np.ones((8, 8, 3, 2)) * 0.9), "ssim")
    probe("ssim (8, 8, 40) 40 channels (channels last; control)", lambda: jl.images.ssim(np.ones((8, 8, 40)) * 0.5, np.ones((8, 8, 40)) * 0.4), good=True)
    probe("ssim (3, 8, 8) channels first", lambda: jl.images.ssim(np.ones((3, 8, 8)) * 0.5, np.ones((3, 8, 8)) * 0.4), "ssim")
    probe("ssim uint8 against float", lambda: jl.images.ssim(np.full((8, 8), 100, np.uint8), np.full((8, 8), 0.4)), "ssim")
    probe("ssim 1-d signals (skimage's 1-d SSIM; control)", lambda: jl.images.ssim(np.ones(64) * 0.5, np.ones(64) * 0.4), good=True)
    probe("ssim data_range 0", lambda: jl.images.ssim(a, b, data_range=0), "data_range")
    probe("ssim data_range nan", lambda: jl.images.ssim(a, b, data_range=float("nan")), "data_range")
    # io.images
    probe("to_linear NaN pixel", lambda: I.to_linear(np.array([[0.5, np.nan]])), "to_linear")
    probe("to_linear float 1.2 (>1)", lambda: I.to_linear(np.array([[0.5, 1.2]])), "to_linear")
    probe("to_linear int8 image", lambda: I.to_linear(np.array([[1, 2]], np.int8)), "to_linear", "int8")
    probe("to_linear bool image", lambda: I.to_linear(np.array([[True, False]])), "to_linear")
    probe("to_linear a jax uint8 image (control)", lambda: I.to_linear(jnp.full((2, 2, 3), 128, jnp.uint8)).dtype, good=True)
    probe("to_linear float16 in [0, 1] (control)", lambda: I.to_linear(np.full((2, 2), 0.5, np.float16)).dtype, good=True)
    probe("srgb_to_linear uint8", lambda: I.srgb_to_linear(np.array([128], np.uint8)), "srgb_to_linear", "to_linear")
    probe("srgb_to_linear 1.5", lambda: I.srgb_to_linear(np.array([1.5])), "srgb_to_linear")
    probe("linear_to_srgb NaN", lambda: I.linear_to_srgb(np.array([np.nan])), "linear_to_srgb")
    probe("linear_to_srgb uint8", lambda: I.linear_to_srgb(np.array([200], np.uint8)), "linear_to_srgb", "uint8")
    probe("linear_to_srgb 2.0 (documented: clipped; control)", lambda: I.linear_to_srgb(np.array([2.0])), good=True)
    png = lambda: os.path.join(fresh("png"), "a.png")
    probe("write_png uint8 image", lambda: I.write_png(png(), np.full((4, 4, 3), 200, np.uint8)), "write_png", "uint8")
    probe("write_png NaN pixel", lambda: I.write_png(png(), np.array([[0.5, np.nan]])), "write_png")
    probe("write_png 2 channels (grey and alpha; control)", lambda: I.write_png(png(), np.ones((4, 4, 2)) * 0.5), good=True)
    probe("write_png 5 channels", lambda: I.write_png(png(), np.ones((4, 4, 5)) * 0.5), "write_png", "C<=4")
    probe("write_png (4,) 1-d", lambda: I.write_png(png(), np.ones(4) * 0.5), "write_png")
    probe("write_png (0, 4) empty", lambda: I.write_png(png(), np.ones((0, 4))), "write_png")
    probe("write_png values 1.5 (documented: linear light clipped to white; control)", lambda: I.write_png(png(), np.full((4, 4), 1.5)), good=True)
    probe("write_png linear 'no'", lambda: I.write_png(png(), np.full((4, 4), 0.5), linear="no"), "linear")
    probe("write_png bits 12", lambda: I.write_png(png(), np.full((4, 4), 0.5), bits=12), "bits")
    probe("write_png over an existing file of another kind (a lens)", lambda: I.write_png(_copy(COOKE), np.full((4, 4), 0.5)), "write_png")
    exr = lambda: os.path.join(fresh("exr"), "a.exr")
    probe("write_exr uint8", lambda: I.write_exr(exr(), np.full((4, 4, 3), 200, np.uint8)), "write_exr", "uint8")
    probe("write_exr NaN (documented? EXR holds NaN)", lambda: I.write_exr(exr(), np.array([[0.5, np.nan]])), "write_exr")
    probe("write_exr channels ['R'] for 3 channels", lambda: I.write_exr(exr(), np.ones((4, 4, 3)), channels=["R"]), "channels")
    probe("write_exr channels ['R', 'R', 'B'] (repeated)", lambda: I.write_exr(exr(), np.ones((4, 4, 3)), channels=["R", "R", "B"]), "channels")
    probe("read_exr a PNG", lambda: I.read_exr(_png_file()), "read_exr")
    probe("read_png an EXR", lambda: I.read_png(_exr_file()), "read_png")
    probe("read_png a truncated PNG", lambda: I.read_png(_cut(_png_file())), "read_png")
    probe("read_png linear 'yes'", lambda: I.read_png(_png_file(), linear="yes"), "linear")
    probe("scene size (0, 8)", lambda: I.scene("astronaut", (0, 8)), "size")
    probe("scene size (8,)", lambda: I.scene("astronaut", (8,)), "size")
    probe("scene size (8.5, 8)", lambda: I.scene("astronaut", (8.5, 8)), "size")
    probe("scene size '8x8'", lambda: I.scene("astronaut", "8x8"), "size")
    probe("scene name 'Astronaut' (case)", lambda: I.scene("Astronaut"), "astronaut")
    probe("scene name ''", lambda: I.scene(""), "scene")
    probe("scene name 5", lambda: I.scene(5), "scene")
    probe("write_psf_stack uint8 PSFs", lambda: I.write_psf_stack(os.path.join(fresh("ps"), "p.exr"), np.ones((2, 5, 5), np.uint8)), "write_psf_stack")
    probe("write_psf_stack names 2 for 3 PSFs", lambda: I.write_psf_stack(os.path.join(fresh("ps"), "p.exr"), np.ones((3, 5, 5)), names=["a", "b"]), "names")
    probe("write_psf_stack negative PSF values", lambda: I.write_psf_stack(os.path.join(fresh("ps"), "p.exr"), -np.ones((2, 5, 5))), "write_psf_stack")


def _png_file():
    p = os.path.join(fresh("pf"), "a.png")
    jl.images.write_png(p, np.full((4, 4, 3), 0.5))
    return p


def _exr_file():
    p = os.path.join(fresh("ef"), "a.exr")
    jl.images.write_exr(p, np.full((4, 4, 3), 0.5))
    return p


def _cut(p):
    b = open(p, "rb").read()
    open(p, "wb").write(b[: len(b) // 2])
    return p


def _summary(lens):
    d = {}
    for k in ("object_na", "afocal_image", "stop", "aim", "primary", "negative_propagation"):
        v = getattr(lens, k, None)
        d[k] = None if v is None else np.asarray(v).tolist()
    for k in ("epd", "fields", "wavelengths", "thickness"):
        d[k] = np.round(np.asarray(getattr(lens, k), float), 9).tolist()
    d["materials"] = [getattr(m, "name", type(m).__name__) for m in lens.materials]
    return d


def round_trips():
    """Writers on unusual but valid lenses: read back the same, or refuse."""
    lenses = {
        "telecentric triplet": tele,
        "telecentric immersion": jl.load(TELE_IMM),
        "telecentric doublet": jl.load(os.path.join(DATA, "tele42a", "tele_doublet_exact.zmx")),
        "afocal Kepler": kepler,
        "afocal Kepler, finite object": finite(kepler, 1000.0),
        "virtual object (Cooke, -200 mm)": finite(cooke, -200.0),
        "virtual object (Cooke, -5 mm)": finite(cooke, -5.0),
        "finite object (Cooke, 300 mm)": finite(cooke, 300.0),
        "Cooke with aim 'real'": R(cooke, aim="real"),
        "Cooke with aim 'real_marginal'": R(cooke, aim="real_marginal"),
        "Cooke with negative_propagation": R(cooke, negative_propagation=True),
        "Cooke, one wavelength 10 µm? no: 0.7 µm": R(cooke, wavelengths=jnp.array([0.7]), primary=0),
        "Cooke, fields (x, y)": R(cooke, fields=jnp.array([[0.0, 0.0], [5.0, 3.0]])),
        "telecentric, object_na 0.01": R(tele, object_na=0.01),
        "telecentric, fields (x, y) mm": R(tele, fields=jnp.array([[0.0, 0.0], [1.0, 2.0]])),
        "Cooke, object 1e9 mm (nearly infinite)": finite(cooke, 1e9),
    }
    for name, lens in lenses.items():
        want = _summary(lens)
        for ext in (".json", ".zmx"):
            def go(lens=lens, ext=ext, want=want):
                p = os.path.join(fresh("rt"), "lens" + ext)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    jl.save(lens, p)
                    got = _summary(jl.load(p))
                # The .zmx reader sets negative_propagation (Zemax traces through; documented).
                diff = {k: (want[k], got[k]) for k in want if want[k] != got[k]
                        and not (ext == ".zmx" and k == "negative_propagation")}
                if diff:
                    return f"read back differs: {str(diff)[:140]}"
                return "same"
            def judged(go=go):
                try:
                    r = go()
                except ValueError as e:  # a clear refusal is right too
                    return True, f"refused: {str(e)[:140]}"
                return r == "same", r
            checked(f"round trip {ext} {name}", judged)
    # paraxial agreement after a round trip of the telecentric and virtual lenses
    for name, lens in (("telecentric", tele), ("virtual object", finite(cooke, -200.0)), ("afocal finite object", finite(kepler, 1000.0))):
        for ext in (".json", ".zmx"):
            def pm(lens=lens, ext=ext):
                p = os.path.join(fresh("rt"), "lens" + ext)
                try:
                    jl.save(lens, p)
                except ValueError as e:
                    return True, f"refused: {str(e)[:120]}"
                a, b = float(PX.magnification(lens)), float(PX.magnification(jl.load(p)))
                return (a == b or abs(a - b) <= 1e-9 * max(1.0, abs(a))), f"{a:.12g} -> {b:.12g}"
            checked(f"round trip {ext} {name}: magnification", pm)


if __name__ == "__main__":
    run([newest_apis, classical_cli, edof_cli, tolerance_cli, ablation_cli, benchmarks_cli, report_cli, images, round_trips])
