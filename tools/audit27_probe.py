# ruff: noqa: E501, B023, E731
"""Round-27 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for round 26's three leftovers and for the public names and parameters that the
probe and test files still name least.

The count (``count_mentions`` below, on main at c417ba1): each name exported by ``jaxlens``
and its sub-packages, and each of its parameters written ``name=``, counted in
tools/audit*_probe.py, tests/test_input_probes*.py, test_bad_input.py and
test_silent_answers*.py. Named 0 times are the result containers (``RayFan``, ``Wavefront``,
``Evaluation``…, outputs, not inputs); then ``AbstractMaterial`` and ``ZernikeFit`` (2,
round 26), ``OddAsphere``/``Plane`` (4), ``evaluate_design`` (4), ``Conic``/``Hybrid``/``Stop``
(6), ``TiltedPlane``/``CatalogRegion``/``TableMaterials`` (7), ``LevenbergMarquardt``/
``reversed_lens`` (8), ``DampedLeastSquares``/``random_params``/``opd`` (9), ``Binary2``/
``catalog_names`` (10), ``HullMaterials``/``sensor_field_grid`` (12), ``glass_info`` (15),
``zernike_nm`` (16), ``reweighting_mask`` (18); parameters named 0 times: ``area`` and
``rms`` of ``reweighting_mask``, ``corners`` of ``HullMaterials``, ``obsolete`` of
``catalog_names``, ``j`` of ``zernike_nm``, ``b2`` of ``Adam``, ``lower``/``upper``/``free``
of the solvers. Most of them were already guarded (the controls below); the gaps were in
``reweighting_mask(area=)``, ``HullMaterials`` (corners on a line, ``names``, the point of
``logits``), ``CatalogRegion`` built directly, ``Objective(efl_weight=)``, ``TableMaterials``
(repeated wavelengths) and ``glass_info("AIR")``.

Round 26's leftovers: a checkpoint folder (or photographs, or the record) inside the EDoF
run's ``--out`` was deleted when the run replaced ``--out`` at its end (with ``--overwrite``
an earlier run's, without it the run ended refused by its own checkpoint); the same for a
run to merge inside ``edof.merge --out``, a design file named ``tolerance.json`` in the
tolerance CLI's ``--out`` (written over by the report), and ``edof.design --out`` naming the
record's ``base_lens.json`` in ``--record-dir`` (written over by the record).
``python -m jaxlens.experiments.classical`` reads no file or folder (materials are names;
``--ablation-out`` holds only its own columns): nothing there to destroy.
``object_depth`` took a negative depth (and added the stop's distance behind surface 1
instead of subtracting it: 110.27 mm for 100 mm before the Cooke triplet's stop, not
89.73 mm; the EDoF lenses are stop-first, stop_z = 0, so no result changes); ``get_material`` given nd and vd swapped listed no
glass and did not say why.

Before (main at c417ba1, an archive) and after (branch audit27), the same probes,
``PYTHONPATH=<tree> python tools/audit27_probe.py``, 68 probes, about 5 s each way:
    before: clear error: 23, crash: 2, ok: 12, silent wrong: 23, vague error: 8
    after:  clear error: 55, ok: 13
The two "crash" rows on main are the work starting (the design, the tolerance analysis; the
probe stops it there): the run would then have written over the file named.

Probe (before -> after):
    edof --checkpoint inside --out, --overwrite (deleted at the end)         silent wrong -> clear error
    edof --checkpoint inside a new --out (run refused by its own checkpoint) silent wrong -> clear error
    edof --checkpoint = --out                                                silent wrong -> clear error
    edof --test-dir inside --out, --overwrite                                silent wrong -> clear error
    edof --train-dir inside --out, --overwrite                               silent wrong -> clear error
    edof --record = --out (copied onto itself after the run)                 silent wrong -> clear error
    edof --checkpoint beside --out (control)                                 ok           -> ok
    edof.merge runs inside --out, --overwrite                                vague error  -> clear error
    edof.design --out = the record's base_lens.json, --overwrite             crash        -> clear error
    tolerance design = --out/tolerance.json, --overwrite                     crash        -> clear error
    object_depth -200 mm                                                     silent wrong -> clear error
    object_depth 0                                                           silent wrong -> clear error
    object_depth nan                                                         silent wrong -> clear error
    object_depth '200'                                                       vague error  -> clear error
    object_depth (200, -5) array                                             silent wrong -> clear error
    object_depth inf (control: at infinity)                                  ok           -> ok
    object_depth 200 (control)                                               ok           -> ok
    object_depth 100 mm, Cooke triplet (stop 10.27 mm behind surface 1)      silent wrong -> ok
    object_depth traced -1 under jit (not checked)                           ok           -> ok
    get_material nd/vd swapped (64.17, 1.5168)                               vague error  -> clear error
    get_material nd/vd (1.5168, 64.17) (control: lists N-BK7)                clear error  -> clear error
    get_material nd 64.17, vd 30 (not a swap: no list)                       clear error  -> clear error
    reweighting_mask area all zeros                                          silent wrong -> clear error
    reweighting_mask area NaN                                                silent wrong -> clear error
    reweighting_mask area negative                                           silent wrong -> clear error
    reweighting_mask area (control)                                          ok           -> ok
    reweighting_mask traced area under jit (not checked)                     ok           -> ok
    reweighting_mask threshold 80 (percent)                                  clear error  -> clear error
    reweighting_mask rms NaN                                                 clear error  -> clear error
    HullMaterials corners on one line (logits)                               vague error  -> clear error
    HullMaterials a corner repeated (logits)                                 vague error  -> clear error
    HullMaterials 2 names for 3 corners                                      silent wrong -> clear error
    HullMaterials names a str                                                silent wrong -> clear error
    HullMaterials triangle (control)                                         ok           -> ok
    HullMaterials corners (Vd, nd) swapped                                   clear error  -> clear error
    HullMaterials.logits nd NaN                                              vague error  -> clear error
    HullMaterials.logits (Vd, nd) swapped                                    silent wrong -> clear error
    CatalogRegion a NaN point                                                silent wrong -> clear error
    CatalogRegion 1 name for 2 points                                        silent wrong -> clear error
    CatalogRegion catalogs a str                                             silent wrong -> clear error
    CatalogRegion.of SCHOTT (control)                                        ok           -> ok
    Objective efl_weight -1                                                  silent wrong -> clear error
    Objective efl NaN                                                        silent wrong -> clear error
    Objective efl -5 (control: a negative lens)                              ok           -> ok
    TableMaterials repeated wavelength                                       silent wrong -> clear error
    TableMaterials in nm                                                     clear error  -> clear error
    TableMaterials descending (control: any order)                           ok           -> ok
    glass_info 'AIR'                                                         vague error  -> clear error
    glass_info '' (air)                                                      vague error  -> clear error
    glass_info 'N-BK7' (control)                                             ok           -> ok
    catalog_names obsolete 'no'                                              clear error  -> clear error
    zernike_nm j 0 (noll)                                                    clear error  -> clear error
    zernike_nm j 1.5                                                         clear error  -> clear error
    zernike_nm j 38 fringe                                                   clear error  -> clear error
    zernike_nm j 0 ansi (control)                                            ok           -> ok
    Adam b2 1.5                                                              clear error  -> clear error
    LevenbergMarquardt rtol -1                                               clear error  -> clear error
    DampedLeastSquares lam0 0                                                clear error  -> clear error
    LBFGSB history 0                                                         clear error  -> clear error
    OddAsphere coeffs 2-D                                                    clear error  -> clear error
    Plane semi_diameter 0                                                    clear error  -> clear error
    Stop semi_diameter '2'                                                   clear error  -> clear error
    Conic k True                                                             clear error  -> clear error
    Hybrid odd_x NaN                                                         clear error  -> clear error
    TiltedPlane tan_x inf                                                    clear error  -> clear error
    sensor_field_grid n 0                                                    clear error  -> clear error
    evaluate_design min_valid 99 (percent)                                   clear error  -> clear error
    reversed_lens image_distance NaN                                         clear error  -> clear error

A CLI probe of ``edof`` runs the option checks only (``cli.check_args``): "silent wrong"
there means the options were accepted, and the run would have deleted the folder named.

Run: PYTHONPATH=$PWD python tools/audit27_probe.py [filter]
(``AUDIT27_COUNT=1`` prints the count instead.)
"""

import os
import sys
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import mention_counts, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import zoo  # noqa: E402

TMP = tempfile.mkdtemp()


def count_mentions(top=40):
    """The exported names named least in the probe and test files (this round's own left
    out), with their parameters' counts; printed with ``AUDIT27_COUNT=1``."""
    mention_counts(lambda f: f in ("audit27_probe.py", "test_input_probes_round27.py"), top)


# ----------------------------------------------------------------------------- round 26's leftovers: CLIs
def cli_folders():
    from PIL import Image

    from jaxlens.experiments import tolerance as TOL
    from jaxlens.experiments.edof import cli, merge
    from jaxlens.experiments.edof import design as EDD
    from jaxlens.experiments.runfolder import FINISHED, UsageError

    def finished_run(path):
        os.makedirs(path, exist_ok=True)
        open(os.path.join(path, FINISHED), "w").close()
        return path

    def check(*argv):
        def go():
            try:
                cli.check_args(cli.build_parser().parse_args(["--smoke", *argv]))
            except UsageError as e:
                raise ValueError(str(e)) from None
            return "accepted"
        return go

    out = finished_run(os.path.join(TMP, "edof_out"))
    probe("edof --checkpoint inside --out, --overwrite (deleted at the end)", check("--out", out, "--overwrite", "--checkpoint", os.path.join(out, "ck")), "--checkpoint", "--out")
    new = os.path.join(TMP, "edof_new")
    probe("edof --checkpoint inside a new --out (run refused by its own checkpoint)", check("--out", new, "--checkpoint", os.path.join(new, "ck")), "--checkpoint", "--out")
    probe("edof --checkpoint = --out", check("--out", new, "--checkpoint", new), "--checkpoint", "--out")
    photos = os.path.join(out, "photos")
    os.makedirs(photos, exist_ok=True)
    Image.fromarray(np.full((32, 32, 3), 100, np.uint8)).save(os.path.join(photos, "a.png"))
    probe("edof --test-dir inside --out, --overwrite", check("--out", out, "--overwrite", "--test-dir", photos), "--test-dir", "--out")
    probe("edof --train-dir inside --out, --overwrite", check("--out", out, "--overwrite", "--train-dir", photos, "--train-source", "mixed"), "--train-dir", "--out")
    probe("edof --record = --out (copied onto itself after the run)", check("--out", new, "--record", new), "--record", "--out")
    probe("edof --checkpoint beside --out (control)", check("--out", os.path.join(TMP, "edof_b"), "--checkpoint", os.path.join(TMP, "ck_b")), good=True)

    def merged(*argv):
        def go():
            try:
                merge.run(list(argv))
            except UsageError as e:
                raise ValueError(str(e)) from None
            return "merged"
        return go
    mo = finished_run(os.path.join(TMP, "merge_out"))
    ra, rb = finished_run(os.path.join(mo, "run_a")), finished_run(os.path.join(mo, "run_b"))
    probe("edof.merge runs inside --out, --overwrite", merged(ra, rb, "--out", mo, "--overwrite"), "run_a", "--out")

    rec = os.path.join(TMP, "rec")
    os.makedirs(rec, exist_ok=True)
    open(os.path.join(rec, "base_lens.json"), "w").write("{}")
    real = EDD.design_classical

    def no_design(**k):  # the record then writes base_lens.json over the lens saved there
        raise RuntimeError("the design started (the record would write over --out)")
    EDD.design_classical = no_design
    try:
        probe("edof.design --out = the record's base_lens.json, --overwrite", lambda: EDD.main(["--smoke", "--quiet", "--overwrite", "--out", os.path.join(rec, "base_lens.json"), "--record-dir", rec]), "--out", "base_lens.json")
    finally:
        EDD.design_classical = real

    tdir = os.path.join(TMP, "tol")
    os.makedirs(tdir, exist_ok=True)
    design = os.path.join(tdir, "tolerance.json")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    jl.save(jl.load(os.path.join(root, "experiments", "classical", "designs", "seed_0.zmx")), design)
    real_analyse = TOL.analyse_design

    def no_analysis(*a, **k):  # the report is then written over the design file
        raise RuntimeError("the analysis started (its report replaces the design file)")
    TOL.analyse_design = no_analysis
    tol = lambda: TOL.main([design, "--out", tdir, "--overwrite", "--trials", "1"])
    tol.cli = True
    try:
        probe("tolerance design = --out/tolerance.json, --overwrite", tol, "tolerance.json", "--out")
    finally:
        TOL.analyse_design = real_analyse


# ----------------------------------------------------------------------------- round 26's leftovers: depth, nd/vd
def leftovers():
    from jaxlens.experiments.edof import lenses as L
    lens = L.classical_lens(binning=8)
    probe("object_depth -200 mm", lambda: float(L.object_depth(lens, -200.0)), "depth", "mm")
    probe("object_depth 0", lambda: float(L.object_depth(lens, 0.0)), "depth", "mm")
    probe("object_depth nan", lambda: float(L.object_depth(lens, np.nan)), "depth")
    probe("object_depth '200'", lambda: float(L.object_depth(lens, "200")), "depth")
    probe("object_depth (200, -5) array", lambda: L.object_depth(lens, jnp.array([200.0, -5.0])), "depth")
    probe("object_depth inf (control: at infinity)", lambda: float(L.object_depth(lens, np.inf)), good=True)
    probe("object_depth 200 (control)", lambda: float(L.object_depth(lens, 200.0)), good=True)
    cooke = zoo.cooke_triplet()
    got = float(L.object_depth(cooke, 100.0))
    want = 100.0 - float(cooke.vertex_z()[cooke.stop])
    probe("object_depth 100 mm, Cooke triplet (stop 10.27 mm behind surface 1)", lambda: got, good=abs(got - want) < 1e-9)
    probe("object_depth traced -1 under jit (not checked)", lambda: float(jax.jit(lambda d: L.object_depth(lens, d))(-1.0)), good=True)

    def unknown(**k):
        def go():
            jl.get_material("X-UNKNOWN", **k)
        return go
    probe("get_material nd/vd swapped (64.17, 1.5168)", unknown(nd=64.17, vd=1.5168), "swapped", "N-BK7")
    probe("get_material nd/vd (1.5168, 64.17) (control: lists N-BK7)", unknown(nd=1.5168, vd=64.17), "N-BK7")
    probe("get_material nd 64.17, vd 30 (not a swap: no list)", unknown(nd=64.17, vd=30.0), "unknown material")


# ----------------------------------------------------------------------------- least-named names
def least_named():
    rms = jnp.array([1.0, 1.0, 2.0])
    probe("reweighting_mask area all zeros", lambda: D.reweighting_mask(rms, jnp.zeros(3)), "area")
    probe("reweighting_mask area NaN", lambda: D.reweighting_mask(rms, jnp.array([1.0, np.nan, 1.0])), "area")
    probe("reweighting_mask area negative", lambda: D.reweighting_mask(rms, jnp.array([1.0, -1.0, 1.0])), "area")
    probe("reweighting_mask area (control)", lambda: D.reweighting_mask(rms, jnp.array([1.0, 2.0, 1.0])), good=True)
    probe("reweighting_mask traced area under jit (not checked)", lambda: jax.jit(lambda a: D.reweighting_mask(rms, a))(jnp.zeros(3)), good=True)
    probe("reweighting_mask threshold 80 (percent)", lambda: D.reweighting_mask(rms, threshold=80), "threshold")
    probe("reweighting_mask rms NaN", lambda: D.reweighting_mask(jnp.array([1.0, np.nan])), "rms")
    tri = [[1.5, 60.0], [1.7, 30.0], [1.7, 55.0]]
    probe("HullMaterials corners on one line (logits)", lambda: D.HullMaterials([[1.5, 60.0], [1.6, 50.0], [1.7, 40.0]]).logits(1.6, 50.0), "corners", "line")
    probe("HullMaterials a corner repeated (logits)", lambda: D.HullMaterials([[1.5, 60.0], [1.5, 60.0], [1.7, 40.0]]).logits(1.6, 50.0), "corners")
    probe("HullMaterials 2 names for 3 corners", lambda: D.HullMaterials(tri, names=("a", "b")).names, "names")
    probe("HullMaterials names a str", lambda: D.HullMaterials(tri, names="abc").names, "names")
    probe("HullMaterials triangle (control)", lambda: D.HullMaterials(tri, names=("a", "b", "c")).logits(1.65, 50.0), good=True)
    probe("HullMaterials corners (Vd, nd) swapped", lambda: D.HullMaterials([[60.0, 1.5], [30.0, 1.7], [55.0, 1.7]]), "nd")
    probe("HullMaterials.logits nd NaN", lambda: D.HullMaterials(tri).logits(np.nan, 50.0), "nd")
    probe("HullMaterials.logits (Vd, nd) swapped", lambda: D.HullMaterials(tri).logits(50.0, 1.6), "nd", "swapped")
    probe("CatalogRegion a NaN point", lambda: D.CatalogRegion(("SCHOTT",), ("A", "B"), np.array([[1.5, np.nan], [1.6, 40.0]])), "vd")
    probe("CatalogRegion 1 name for 2 points", lambda: D.CatalogRegion(("SCHOTT",), ("A",), np.array([[1.5, 60.0], [1.6, 40.0]])), "points", "names")
    probe("CatalogRegion catalogs a str", lambda: D.CatalogRegion("SCHOTT", ("A",), np.array([[1.5, 60.0]])), "catalogs")
    probe("CatalogRegion.of SCHOTT (control)", lambda: len(D.CatalogRegion.of(("SCHOTT",)).names) > 3, good=True)
    probe("Objective efl_weight -1", lambda: D.Objective(None, None, jnp.zeros(2), efl=5.0, efl_weight=-1.0), "efl_weight")
    probe("Objective efl NaN", lambda: D.Objective(None, None, jnp.zeros(2), efl=np.nan), "efl")
    probe("Objective efl -5 (control: a negative lens)", lambda: D.Objective(None, None, jnp.zeros(2), efl=-5.0).efl, good=True)
    probe("TableMaterials repeated wavelength", lambda: D.TableMaterials([0.5876, 0.5876, 0.6563]), "distinct")
    probe("TableMaterials in nm", lambda: D.TableMaterials([486.1, 587.6]), "nm")
    probe("TableMaterials descending (control: any order)", lambda: D.TableMaterials([0.6563, 0.5876]).wavelengths, good=True)
    probe("glass_info 'AIR'", lambda: jl.glass_info("AIR"), "is air")
    probe("glass_info '' (air)", lambda: jl.glass_info(""), "is air")
    probe("glass_info 'N-BK7' (control)", lambda: jl.glass_info("N-BK7"), good=True)
    probe("catalog_names obsolete 'no'", lambda: jl.catalog_names(obsolete="no"), "obsolete")
    probe("zernike_nm j 0 (noll)", lambda: A.zernike_nm(0), "j")
    probe("zernike_nm j 1.5", lambda: A.zernike_nm(1.5), "j")
    probe("zernike_nm j 38 fringe", lambda: A.zernike_nm(38, indexing="fringe"), "j", "37")
    probe("zernike_nm j 0 ansi (control)", lambda: A.zernike_nm(0, indexing="ansi"), good=True)
    lrs = D.LensParams(c=1e-3, a=1e-3, k=1e-3, d=1e-3)
    probe("Adam b2 1.5", lambda: D.Adam(lambda p, a: p, lrs=lrs, b2=1.5), "b2")
    probe("LevenbergMarquardt rtol -1", lambda: D.LevenbergMarquardt(lambda p, a: p, rtol=-1.0), "rtol")
    probe("DampedLeastSquares lam0 0", lambda: D.DampedLeastSquares(lambda p, a: p, lam0=0.0), "lam0")
    probe("LBFGSB history 0", lambda: D.LBFGSB(lambda p, a: p, lower=lrs, upper=lrs, history=0), "history")
    probe("OddAsphere coeffs 2-D", lambda: jl.OddAsphere(c=0.01, coeffs=[[0.0, 1.0]]), "coeffs")
    probe("Plane semi_diameter 0", lambda: jl.Plane(0.0), "semi_diameter")
    probe("Stop semi_diameter '2'", lambda: jl.Stop("2"), "semi_diameter")
    probe("Conic k True", lambda: jl.Conic(0.01, True), "k")
    probe("Hybrid odd_x NaN", lambda: jl.Hybrid(odd_x=(np.nan,) * 4), "odd_x")
    probe("TiltedPlane tan_x inf", lambda: jl.TiltedPlane(tan_x=np.inf), "tan_x")
    spec = D.DesignSpec()
    probe("sensor_field_grid n 0", lambda: D.sensor_field_grid(spec, 0), "n")
    probe("evaluate_design min_valid 99 (percent)", lambda: D.evaluate_design(zoo.cooke_triplet(), spec, n=2, min_valid=99), "min_valid")
    probe("reversed_lens image_distance NaN", lambda: jl.tracing.reversed_lens(zoo.cooke_triplet(), image_distance=np.nan), "image_distance")


if os.environ.get("AUDIT27_COUNT"):
    count_mentions()
else:
    run([cli_folders, leftovers, least_named])
