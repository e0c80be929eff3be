# ruff: noqa: E501, B023, E731
"""Round-31 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for round 30's four leftovers, the public names and parameters that the probe and
test files name least after round 30, the command lines and the tools a user runs, the JSON
lens format and the ``.zmx`` reader given hand-edited lines.

The count (``probe_table.mention_counts``, rerun on main at bf1f0a1 with every probe and
test file counted, round 30 included; ``AUDIT31_COUNT=1`` here prints it): after the result
containers (``AngularSpot``, ``Distortion``, ``ParaxialData``…, 0-4) and the names rounds
26-30 probed (up to ``Grating``, 30) come ``Schott``/``glass_info`` (31), ``seidel`` (31),
``field_curvature``/``marechal_strehl`` (33; ``rms_waves`` 0), ``clear_semi_diameters``,
``CatalogMaterial``, ``angular_spot``, ``paper_stages`` (34-35), ``wavefront``,
``zernike_nm``, ``Adam`` (39-40; ``b2`` 1), ``LBFGSB``, ``register_catalog`` (43),
``zernike_terms``, ``Stage`` (43; ``lr`` 2, ``regularize`` 1), ``self_intersection``,
``Air``, ``zernike_fit``, ``HullMaterials``, ``RayLoss`` (44-47), ``reweighting_mask``,
``bfl``, ``save`` (``options`` 1), ``encircled_energy`` (``radii`` 0), ``Sphere``, ``Rays``
(``opl`` 2), ``ModelGlass``, ``DesignConfig`` (``curriculum_n``/``lr_a`` 1), ``Tabulated``
(``indices`` 2), ``trace`` (``reverse_rule`` 0), and the parameters named 0-1 times:
``render``'s ``mesh``/``relative_illumination``, ``design``'s ``shard``/``image_loss``,
``run``'s ``objective``/``make_solver``/``mesh``, ``Lens``'s ``image``/``afocal_image``.
Most were guarded already (the clear rows and controls below).

Round 30's leftovers (each real, each settled):
1. ``render`` with a ``patch`` past the image traced a patch² tile: the default 64 on a
   12 × 16 sensor traced 4096 pixels for the image's 192 (21×; 1040 ms a call against
   181 ms now, Cooke triplet, spp 256, 2 cores). A tile now stops at the image's side where
   one tile spans it, its pixels' samples drawn from the same patch² draws, so the image
   is the same (ray method: max difference 1.5e-14 from XLA's other vector shapes; PSF
   method: bit-equal; 12 × 16 and 12 × 100 sensors). Refusing would have refused the
   default on every sensor under 64 pixels.
2. ``python -m benchmarks --out DIR`` wrote over a foreign ``<benchmark>.png``: a plot with
   no ``<benchmark>.json`` beside it is refused, as a foreign JSON is (``--no-plots``
   passes).
3. ``benchmarks.design_step``/``fast_path --baseline nosuchrev`` ended in git archive's
   ``CalledProcessError`` traceback: one line naming the revision (``baseline_problem``:
   unknown revision, no ``jaxlens`` in it, no git checkout, no git).
4. A JSON lens with a field given twice warns, as a repeated wavelength does
   (``_fields_of``). jaxlens/io/lensfile.py was at 798 lines: ``unique_keys`` (with
   ``RepeatedKey``) and ``pretty`` moved unchanged to jaxlens/io/json_values.py.

Gaps found and fixed:
5. JSON lens: a negative thickness in glass with no mirror or break before it (the Cooke
   triplet's 3.25896 typed -3) traced 0.58 mm RMS spots without a word; it warns now (an
   element inside out). In air it stays silent (a dummy surface); the 70 corpus .zmx files'
   negative thicknesses all follow mirrors.
6. JSON lens: a material's ``"catalog"`` was not read (a key far from every known key
   passes as a comment): ``{"name": "N-SK16", "catalog": "CDGM"}`` loaded SCHOTT's glass.
   It is read now (``get_material(name, catalogs=[catalog])``); a misspelt catalog lists the
   known ones, ``"catalgo"`` is named a near miss.
7. ``benchmarks.render_speed``/``render_memory --out FILE``, ``vjp_probe --json FILE`` and
   ``reevaluate --out FILE`` wrote over whatever file was there (a lens file, notes,
   another benchmark's result): refused unless its JSON ``command`` names the module
   (``common.foreign_result``).
8. ``design(shard="no")`` sharded and ``design(image_loss=5)`` fine-tuned on images
   (``bool("no")`` is True): must be True or False.
9. ``design.run``: ``make_solver="adam"`` ("'str' object is not callable"), ``objective=
   None`` (an AttributeError) and ``mesh="cpu"`` (passed on): refused before the stages.
10. ``save(lens, "x.json/")`` said "has extension ''", and ``x.json`` being a folder raised
    ``IsADirectoryError`` after the checks: "is a folder".
11. ``tools/make_refcase.py`` (optiland's venv): no arguments, an unknown case name (after
    the cases before it had been built and written) and ``OUT`` a file were tracebacks;
    refused by argparse before the first case, an unknown name with close matches.

Controls of note: ``register_catalog(..., name="SCHOTT")`` (a newer schott.agf goes ahead of
the shipped one), ``Tabulated`` with unsorted wavelengths (sorted with its indices),
``marechal_strehl(nan)`` (NaN is a field without rays), ``Stage(fov=1.4)`` (a narrow stage,
or 80.2° in radians: not a round angle, so not caught), ``DesignConfig(curriculum_n=0)``
(one stage), ``edof --context 0`` / ``--seeds 0`` (seed 0); the ``.zmx`` reader takes UTF-16
with or without a BOM, CRLF, latin-1 notes and tabs, and refuses a zip renamed ``.zmx``, an
empty file and every keyword given twice in one surface, naming the line.

Not fixed (another module's, or left as is): a user catalog registered as "SCHOTT" hides
the shipped SCHOTT from ``get_material(name, catalogs=["SCHOTT"])`` ("'N-BK7' is in catalog
SCHOTT, not searched here": jaxlens/optics/catalog.py); ``register_catalog`` of a missing
file is a ``FileNotFoundError`` naming it, as ``load``'s (counted clear).

Before (main at bf1f0a1, an archive) and after (branch audit31), the same probes,
``PYTHONPATH=<tree> python tools/audit31_probe.py`` from the repository, 167 probes, about
two minutes each way:
    before: clear error: 114, crash: 7, ok: 27, silent wrong: 17, vague error: 2
    after:  clear error: 137, ok: 30

A row marked "(warns)" counts a warning as the answer ("clear error" when it names the
slip); a command-line row "silent wrong" with "started" passed every check and began its
work (the probe stops it there). A render row reads the tile shape from ``render``'s jaxpr:
"silent wrong" when a tile computes more pixels than the image has.

Probe (before -> after):
    render patch 64 on a 12x16 sensor (ray)                                                    silent wrong -> ok
    render patch 64 on a 12x100 sensor (ray; 2 tiles across)                                   silent wrong -> ok
    render patch 64 on a 12x16 sensor (psf)                                                    silent wrong -> ok
    render patch 8 on a 12x16 sensor (control)                                                 ok           -> ok
    benchmarks --out over a foreign throughput.png                                             silent wrong -> clear error
    benchmarks --tag t over a foreign throughput_t.png                                         silent wrong -> clear error
    benchmarks --no-plots beside a foreign throughput.png (control: starts)                    ok           -> ok
    benchmarks over its own json and png (control: starts)                                     ok           -> ok
    design_step --baseline nosuchrev                                                           crash        -> clear error
    fast_path --baseline nosuchrev                                                             crash        -> clear error
    design_step --baseline HEAD (control: starts)                                              ok           -> ok
    lens file fields [0, 14, 14] (warns)                                                       silent wrong -> clear error
    lens file fields [[0, 5], [0, 5]] pairs (warns)                                            silent wrong -> clear error
    lens file fields [0, 14, 20] (control)                                                     ok           -> ok
    register_catalog a missing file (FileNotFoundError)                                        clear error  -> clear error
    register_catalog a folder                                                                  clear error  -> clear error
    register_catalog an AGF without glasses                                                    clear error  -> clear error
    register_catalog a text file (not AGF)                                                     clear error  -> clear error
    register_catalog name ''                                                                   clear error  -> clear error
    register_catalog name 'SCHOTT' (control: a newer schott.agf goes ahead of the shipped one) ok           -> ok
    register_catalog a dict holding a number                                                   clear error  -> clear error
    Adam b1 1.0                                                                                clear error  -> clear error
    Adam b2 1.5                                                                                clear error  -> clear error
    Adam eps -1                                                                                clear error  -> clear error
    Adam eps NaN                                                                               clear error  -> clear error
    Tabulated wavelengths in nm                                                                clear error  -> clear error
    Tabulated 3 wavelengths, 2 indices                                                         clear error  -> clear error
    Tabulated index 0.5                                                                        clear error  -> clear error
    Tabulated wavelengths unsorted (control: sorted with its indices)                          ok           -> ok
    Tabulated a wavelength twice                                                               clear error  -> clear error
    Rays wavelength in nm                                                                      clear error  -> clear error
    Rays opl shape (2,) for one ray                                                            clear error  -> clear error
    Rays direction (0, 0, 0)                                                                   clear error  -> clear error
    Rays direction (0, 0, 2) (not unit)                                                        clear error  -> clear error
    marechal_strehl rms_waves -0.1                                                             clear error  -> clear error
    marechal_strehl rms_waves NaN (control: NaN is a field without rays)                       ok           -> ok
    marechal_strehl 0.05 (control)                                                             ok           -> ok
    encircled_energy radii -0.01                                                               clear error  -> clear error
    encircled_energy radii NaN                                                                 clear error  -> clear error
    encircled_energy radii []                                                                  clear error  -> clear error
    jl.save options foo=1                                                                      clear error  -> clear error
    jl.save to a folder named x.json/                                                          vague error  -> clear error
    jl.save to a folder named x.json                                                           crash        -> clear error
    jl.save to .txt                                                                            clear error  -> clear error
    Stage lr -1                                                                                clear error  -> clear error
    Stage regularize 'no'                                                                      clear error  -> clear error
    Stage mask 'no'                                                                            clear error  -> clear error
    Stage loss 'rays'                                                                          clear error  -> clear error
    Stage fov 1.4 (control: 80.2° in radians, or a narrow curriculum stage)                    ok           -> ok
    Stage fov 200                                                                              clear error  -> clear error
    zernike_terms x (3,), y (4,)                                                               clear error  -> clear error
    zernike_terms terms 0                                                                      clear error  -> clear error
    zernike_fit values (4,) for 3 points                                                       clear error  -> clear error
    zernike_fit mask (2,) for 3 points                                                         clear error  -> clear error
    zernike_fit 2 points for 3 terms                                                           clear error  -> clear error
    self_intersection n_radial 0                                                               clear error  -> clear error
    self_intersection n_angle 10**7                                                            clear error  -> clear error
    self_intersection min_gap NaN                                                              clear error  -> clear error
    self_intersection semi_diameters of 2 for 7                                                clear error  -> clear error
    trace reverse_rule 'no'                                                                    clear error  -> clear error
    trace chunk 0                                                                              clear error  -> clear error
    trace chunk -5                                                                             clear error  -> clear error
    trace chunk 'big'                                                                          clear error  -> clear error
    render mesh 'cpu'                                                                          clear error  -> clear error
    render relative_illumination 'no'                                                          clear error  -> clear error
    design shard 'no'                                                                          silent wrong -> clear error
    design image_loss 5                                                                        silent wrong -> clear error
    design devices 0                                                                           clear error  -> clear error
    run make_solver 'adam'                                                                     vague error  -> clear error
    run objective None                                                                         crash        -> clear error
    run mesh 'cpu'                                                                             silent wrong -> clear error
    run objective and make_solver (control: starts)                                            ok           -> ok
    Lens afocal_image 'no'                                                                     clear error  -> clear error
    Lens negative_propagation 'no'                                                             clear error  -> clear error
    Lens description 5                                                                         clear error  -> clear error
    Lens image 'flat'                                                                          clear error  -> clear error
    DesignConfig curriculum_n 0 (control: one stage, N + 1)                                    ok           -> ok
    DesignConfig lr_a -1                                                                       clear error  -> clear error
    DesignConfig float64 'no'                                                                  clear error  -> clear error
    DesignSpec sensor_aspect 0                                                                 clear error  -> clear error
    DesignSpec sensor_diagonal 7660 (µm)                                                       clear error  -> clear error
    DesignSpec sensor_pixels (0, 0)                                                            clear error  -> clear error
    bfl wavelength 587.6 (nm)                                                                  clear error  -> clear error
    efl wavelength NaN                                                                         clear error  -> clear error
    Air name 5                                                                                 clear error  -> clear error
    HullMaterials corners 1-D                                                                  clear error  -> clear error
    lens file units 'm'                                                                        clear error  -> clear error
    lens file wavelengths_um [486.1, 587.6, 656.3] (nm)                                        clear error  -> clear error
    lens file material nd/vd swapped                                                           clear error  -> clear error
    lens file thickness -3 in glass (warns)                                                    silent wrong -> clear error
    lens file thickness -1 in air (control: air may go back, as to a dummy surface)            ok           -> ok
    lens file fields type 'angle_rad'                                                          clear error  -> clear error
    lens file surface kind 'sphere2'                                                           clear error  -> clear error
    lens file primary 3 of 3                                                                   clear error  -> clear error
    lens file aperture EPD '10mm'                                                              clear error  -> clear error
    lens file a UTF-16 file                                                                    clear error  -> clear error
    lens file a BOM (utf-8-sig; control)                                                       ok           -> ok
    lens file key 'thickness' twice                                                            clear error  -> clear error
    lens file fields {} (no values)                                                            clear error  -> clear error
    lens file material catalog 'SCHOT'                                                         silent wrong -> clear error
    lens file material N-SK16 catalog 'CDGM' (not there)                                       silent wrong -> clear error
    lens file material catalog without a name                                                  clear error  -> clear error
    lens file material N-SK16 catalog 'schott' (control)                                       ok           -> ok
    lens file as read (control)                                                                ok           -> ok
    zmx CURV twice in one surface                                                              clear error  -> clear error
    zmx DISZ twice in one surface                                                              clear error  -> clear error
    zmx GLAS twice in one surface                                                              clear error  -> clear error
    zmx ENPD twice                                                                             clear error  -> clear error
    zmx a UTF-16 file (Zemax's default; control)                                               ok           -> ok
    zmx CRLF line ends (control)                                                               ok           -> ok
    zmx latin-1 comment (control)                                                              ok           -> ok
    zmx cut inside SURF 3's block                                                              clear error  -> clear error
    zmx DISZ 'INFINITY' on a middle surface                                                    clear error  -> clear error
    zmx CURV in the DISZ column (DISZ 0.05 CURV 8)                                             clear error  -> clear error
    zmx WAVM weight 0 on the primary (warns)                                                   clear error  -> clear error
    zmx a .zar/zip archive named .zmx                                                          clear error  -> clear error
    zmx empty                                                                                  clear error  -> clear error
    zmx UTF-16 LE without a BOM (control)                                                      ok           -> ok
    zmx tabs between keyword and value (control)                                               ok           -> ok
    zmx as read (control)                                                                      ok           -> ok
    classical --sensor-diagonal 7660 (µm)                                                      clear error  -> clear error
    classical --sensor-diagonal 0.00766 (m)                                                    clear error  -> clear error
    classical --fov 1.41 (radians)                                                             clear error  -> clear error
    classical --seed-list 1,1,2 (a seed twice)                                                 clear error  -> clear error
    classical --seed-list '' (none)                                                            clear error  -> clear error
    classical --first-seed -1                                                                  clear error  -> clear error
    classical --material-catalogs schot                                                        clear error  -> clear error
    classical --tolerance-threshold 0                                                          clear error  -> clear error
    classical --tolerance-trials 10**9                                                         clear error  -> clear error
    classical --elements 0                                                                     clear error  -> clear error
    classical --bfl 0                                                                          clear error  -> clear error
    classical --ablation --ablation-seeds 0                                                    clear error  -> clear error
    classical --ablation --columns nosuch                                                      clear error  -> clear error
    classical --ablation --ablation-out a file                                                 clear error  -> clear error
    tolerance --decenter 10 (µm)                                                               clear error  -> clear error
    tolerance --decenter nan                                                                   clear error  -> clear error
    tolerance --threshold 0                                                                    clear error  -> clear error
    tolerance --threshold 6000 (nm)                                                            clear error  -> clear error
    tolerance --decenter 0.01 (control)                                                        ok           -> ok
    edof --batch 0                                                                             clear error  -> clear error
    edof --kernel 4 (even)                                                                     clear error  -> clear error
    edof --binning 0                                                                           clear error  -> clear error
    edof --pupil 10**6                                                                         clear error  -> clear error
    edof --lens-every 0                                                                        clear error  -> clear error
    edof --time-limit -1                                                                       clear error  -> clear error
    edof --width 0                                                                             clear error  -> clear error
    edof --n-odd -1                                                                            clear error  -> clear error
    edof --context 0 (control: no context)                                                     ok           -> ok
    edof --context -1                                                                          clear error  -> clear error
    edof --test-dir a missing folder                                                           clear error  -> clear error
    edof --seeds 0 (control: seed 0)                                                           ok           -> ok
    edof --seeds 0,0                                                                           clear error  -> clear error
    edof --cubic-floor 50 (percent)                                                            clear error  -> clear error
    edof --checkpoint a lens file                                                              clear error  -> clear error
    edof defaults (control)                                                                    ok           -> ok
    check_corpus a folder without .zmx                                                         clear error  -> clear error
    check_corpus a missing folder                                                              clear error  -> clear error
    check_corpus --unknown-glass modle                                                         clear error  -> clear error
    make_refcase without arguments                                                             crash        -> clear error
    make_refcase an unknown case name                                                          crash        -> clear error
    make_refcase OUT a file                                                                    crash        -> clear error
    make_agf a missing database                                                                clear error  -> clear error
    render_speed --out a lens file                                                             silent wrong -> clear error
    render_speed --out notes (not JSON)                                                        silent wrong -> clear error
    render_speed --out its own result (control: starts)                                        ok           -> ok
    render_memory --out a lens file                                                            silent wrong -> clear error
    vjp_probe --json a render_speed result                                                     silent wrong -> clear error

Run: PYTHONPATH=$PWD python tools/audit31_probe.py [filter]
"""

import json
import os
import pathlib
import sys

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import (  # noqa: E402
    COOKE,
    OPTILAND_PYTHON,
    ROOT,
    ROWS,
    SEED0,
    TMP,
    edof_check,
    mention_counts,
    patched,
    probe,
    run,
    started,
    tool,
    until_started,
    warned,
)

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import zoo  # noqa: E402


def count_mentions(top=200):
    """The exported names named least in every probe and test file (round 30 included)."""
    mention_counts(lambda f: "31" in f, top)


def tile_traced(lens, patch, **kw):
    """The rows and columns of the tiles ``render`` maps over (from its jaxpr, not run)."""
    scene = jnp.ones(lens.sensor.resolution + (3,))
    jaxpr = jax.make_jaxpr(lambda s: jl.render(lens, s, spp=1, key=jax.random.PRNGKey(0), patch=patch, **kw))(scene)
    shapes = []

    def walk(jx):
        for e in jx.eqns:
            if e.primitive.name == "scan":
                shapes.extend(tuple(v.aval.shape[1:3]) for v in e.outvars if v.aval.ndim == 4)
            for p in e.params.values():
                for sub in (p if isinstance(p, (list, tuple)) else [p]):
                    if hasattr(sub, "jaxpr"):
                        walk(sub.jaxpr if hasattr(sub.jaxpr, "eqns") else sub.jaxpr.jaxpr)
                    elif hasattr(sub, "eqns"):
                        walk(sub)
    walk(jaxpr.jaxpr)
    return max(shapes, key=lambda s: s[0] * s[1])


def tile_row(name, lens, patch, **kw):
    """A row: "silent wrong" when a tile computes more pixels than the image has."""
    if len(sys.argv) > 1 and sys.argv[1] not in name:
        return
    rows, cols = lens.sensor.resolution
    try:
        th, tw = tile_traced(lens, patch, **kw)
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {e}"[:150]))
        return
    waste = th > rows or tw > cols
    ROWS.append((name, "silent wrong" if waste else "ok",
                 f"tiles of {th}x{tw} pixels for a {rows}x{cols} image"))




# ----------------------------------------------------------------------------- leftovers
def leftovers():
    import dataclasses

    cooke = zoo.cooke_triplet()
    small = dataclasses.replace(cooke, sensor=jl.Sensor((12, 16), 0.05))
    wide = dataclasses.replace(cooke, sensor=jl.Sensor((12, 100), 0.05))
    tile_row("render patch 64 on a 12x16 sensor (ray)", small, 64)
    tile_row("render patch 64 on a 12x100 sensor (ray; 2 tiles across)", wide, 64)
    tile_row("render patch 64 on a 12x16 sensor (psf)", small, 64, method=jl.imaging.render.PSFRender(kernel_size=5))
    tile_row("render patch 8 on a 12x16 sensor (control)", small, 8)

    import benchmarks.common as BC
    import benchmarks.design_step as DS
    import benchmarks.fast_path as FP
    import benchmarks.run as BR

    def folder(name, files):
        d = os.path.join(TMP, name)
        os.makedirs(d)
        for f, text in files.items():
            pathlib.Path(d, f).write_text(text)
        return d
    bench = lambda *a: patched(BC, ["machine_info"], lambda: BR.main(list(a)))
    mine = json.dumps({"benchmark": "throughput", "command": "python -m benchmarks"})
    d1 = folder("png1", {"throughput.png": "my photograph"})
    probe("benchmarks --out over a foreign throughput.png", bench("--only", "throughput", "--out", d1), "throughput.png")
    probe("benchmarks --tag t over a foreign throughput_t.png", bench("--only", "throughput", "--tag", "t", "--out", folder("png2", {"throughput_t.png": "x"})), "throughput_t.png")
    probe("benchmarks --no-plots beside a foreign throughput.png (control: starts)", bench("--only", "throughput", "--no-plots", "--out", d1), good=True)
    probe("benchmarks over its own json and png (control: starts)", bench("--only", "throughput", "--out", folder("png3", {"throughput.png": "x", "throughput.json": mine})), good=True)
    probe("design_step --baseline nosuchrev", patched(DS, ["step_fn"], lambda: DS.main(["--baseline", "nosuchrev"])), "--baseline", "nosuchrev")
    probe("fast_path --baseline nosuchrev", patched(FP, ["trace_fns"], lambda: FP.main(["--baseline", "nosuchrev"])), "--baseline", "nosuchrev")
    probe("design_step --baseline HEAD (control: starts)", patched(DS, ["import_baseline"], lambda: DS.main(["--baseline", "HEAD"])), good=True)

    d = json.loads(pathlib.Path(COOKE).read_text())
    def with_fields(values):
        e = json.loads(json.dumps(d))
        e["fields"]["values"] = values
        p = os.path.join(TMP, f"f{len(os.listdir(TMP))}.json")
        pathlib.Path(p).write_text(json.dumps(e))
        return lambda: jl.load(p).fields
    probe("lens file fields [0, 14, 14] (warns)", warned(with_fields([0.0, 14.0, 14.0])), "field is given twice")
    probe("lens file fields [[0, 5], [0, 5]] pairs (warns)", warned(with_fields([[0.0, 5.0], [0.0, 5.0]])), "field is given twice")
    probe("lens file fields [0, 14, 20] (control)", warned(with_fields([0.0, 14.0, 20.0])), good=True)


# ----------------------------------------------------------------------------- least-named names
def least_named():
    lens = zoo.cooke_triplet()
    agf = os.path.join(TMP, "empty.agf")
    pathlib.Path(agf).write_text("CC my catalog\n")
    notes = os.path.join(TMP, "notes.agf")
    pathlib.Path(notes).write_text("these are my notes\nnot a catalog\n")
    def missing():  # a FileNotFoundError naming the file, as load's: counted clear
        try:
            return jl.register_catalog(os.path.join(TMP, "nope.agf"))
        except FileNotFoundError as e:
            raise ValueError(str(e)) from None
    probe("register_catalog a missing file (FileNotFoundError)", missing, "nope.agf")
    probe("register_catalog a folder", lambda: jl.register_catalog(TMP), "folder")
    probe("register_catalog an AGF without glasses", lambda: jl.register_catalog(agf), "empty.agf")
    probe("register_catalog a text file (not AGF)", lambda: jl.register_catalog(notes), "notes.agf")
    probe("register_catalog name '' ", lambda: jl.register_catalog({"G1": jl.ModelGlass(1.5, 60.0)}, name=""), "name")
    probe("register_catalog name 'SCHOTT' (control: a newer schott.agf goes ahead of the shipped one)", lambda: jl.register_catalog({"G1": jl.ModelGlass(1.5, 60.0)}, name="SCHOTT"), good=True)
    import jaxlens.optics.catalog as CAT
    CAT._user_catalogs[:] = [c for c in CAT._user_catalogs if c[0] != "SCHOTT"]  # it hides the shipped SCHOTT from catalogs=["SCHOTT"]
    probe("register_catalog a dict holding a number", lambda: jl.register_catalog({"G1": 1.5}, name="MINE1"), "G1")
    lrs = D.LensParams(c=0.01, a=0.01, k=0.0, d=0.01)
    probe("Adam b1 1.0", lambda: D.Adam(lambda p: p, lrs, b1=1.0), "b1")
    probe("Adam b2 1.5", lambda: D.Adam(lambda p: p, lrs, b2=1.5), "b2")
    probe("Adam eps -1", lambda: D.Adam(lambda p: p, lrs, eps=-1.0), "eps")
    probe("Adam eps NaN", lambda: D.Adam(lambda p: p, lrs, eps=np.nan), "eps")
    probe("Tabulated wavelengths in nm", lambda: jl.Tabulated([486.1, 587.6, 656.3], [1.52, 1.517, 1.514]), "nm")
    probe("Tabulated 3 wavelengths, 2 indices", lambda: jl.Tabulated([0.4861, 0.5876, 0.6563], [1.52, 1.517]), "indices")
    probe("Tabulated index 0.5", lambda: jl.Tabulated([0.4861, 0.5876, 0.6563], [1.52, 0.5, 1.514]), "ind")
    probe("Tabulated wavelengths unsorted (control: sorted with its indices)", lambda: jl.Tabulated([0.5876, 0.4861, 0.6563], [1.517, 1.52, 1.514]).index(0.4861), good=True)
    probe("Tabulated a wavelength twice", lambda: jl.Tabulated([0.5876, 0.5876, 0.6563], [1.517, 1.52, 1.514]).n(0.6), "wavelength")
    probe("Rays wavelength in nm", lambda: jl.trace(lens, jl.Rays(jnp.zeros(3), jnp.array([0.0, 0.0, 1.0]), 587.6)).valid, "nm")
    probe("Rays opl shape (2,) for one ray", lambda: jl.Rays(jnp.zeros(3), jnp.array([0.0, 0.0, 1.0]), 0.5876, opl=jnp.zeros(2)), "opl")
    probe("Rays direction (0, 0, 0)", lambda: jl.trace(lens, jl.Rays(jnp.array([0.0, 1.0, -5.0]), jnp.zeros(3), 0.5876)).origin, "direction")
    probe("Rays direction (0, 0, 2) (not unit)", lambda: jl.trace(lens, jl.Rays(jnp.array([0.0, 1.0, -5.0]), jnp.array([0.0, 0.0, 2.0]), 0.5876)).origin, "direction")
    probe("marechal_strehl rms_waves -0.1", lambda: A.marechal_strehl(-0.1), "rms_waves")
    probe("marechal_strehl rms_waves NaN (control: NaN is a field without rays)", lambda: A.marechal_strehl(np.nan), good=True)
    probe("marechal_strehl 0.05 (control)", lambda: A.marechal_strehl(0.05), good=True)
    probe("encircled_energy radii -0.01", lambda: A.encircled_energy(lens, 0.0, [-0.01, 0.01]).energy, "radii")
    probe("encircled_energy radii NaN", lambda: A.encircled_energy(lens, 0.0, [np.nan]).energy, "radii")
    probe("encircled_energy radii []", lambda: A.encircled_energy(lens, 0.0, []).energy, "radii")
    probe("jl.save options foo=1", lambda: jl.save(lens, os.path.join(TMP, "o.json"), foo=1), "foo")
    os.makedirs(os.path.join(TMP, "sub.json"))
    probe("jl.save to a folder named x.json/", lambda: jl.save(lens, os.path.join(TMP, "sub.json") + "/"), "folder")
    probe("jl.save to a folder named x.json", lambda: jl.save(lens, os.path.join(TMP, "sub.json")), "folder")
    probe("jl.save to .txt", lambda: jl.save(lens, os.path.join(TMP, "o.txt")), ".txt")
    probe("Stage lr -1", lambda: D.Stage("s", fov=40.0, fnum=4.0, steps=10, lr=-1.0), "lr")
    probe("Stage regularize 'no'", lambda: D.Stage("s", fov=40.0, fnum=4.0, steps=10, regularize="no"), "regularize")
    probe("Stage mask 'no'", lambda: D.Stage("s", fov=40.0, fnum=4.0, steps=10, mask="no"), "mask")
    probe("Stage loss 'rays'", lambda: D.Stage("s", fov=40.0, fnum=4.0, steps=10, loss="rays"), "loss")
    probe("Stage fov 1.4 (control: 80.2° in radians, or a narrow curriculum stage)", lambda: D.Stage("s", fov=1.4, fnum=4.0, steps=10).fov, good=True)
    probe("Stage fov 200", lambda: D.Stage("s", fov=200.0, fnum=4.0, steps=10), "fov")
    probe("zernike_terms x (3,), y (4,)", lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(4)), "x", "y")
    probe("zernike_terms terms 0", lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(3), terms=0), "terms")
    probe("zernike_fit values (4,) for 3 points", lambda: A.zernike_fit(jnp.zeros(3), jnp.zeros(3), jnp.zeros(4), terms=3), "values")
    probe("zernike_fit mask (2,) for 3 points", lambda: A.zernike_fit(jnp.zeros(3), jnp.zeros(3), jnp.zeros(3), terms=3, mask=jnp.ones(2, bool)), "mask")
    xs = jnp.linspace(-0.5, 0.5, 4)
    probe("zernike_fit 2 points for 3 terms", lambda: A.zernike_fit(xs[:2], xs[:2], xs[:2], terms=3).coefficients, "terms")
    probe("self_intersection n_radial 0", lambda: A.self_intersection(lens, n_radial=0).ok, "n_radial")
    probe("self_intersection n_angle 10**7", lambda: A.self_intersection(lens, n_angle=10**7).ok, "n_angle")
    probe("self_intersection min_gap NaN", lambda: A.self_intersection(lens, min_gap=np.nan).ok, "min_gap")
    probe("self_intersection semi_diameters of 2 for 7", lambda: A.self_intersection(lens, semi_diameters=[5.0, 5.0]).ok, "semi_diameters")
    rays = jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(3))
    probe("trace reverse_rule 'no'", lambda: jl.trace(lens, rays, reverse_rule="no").valid, "reverse_rule")
    probe("trace chunk 0", lambda: jl.trace(lens, rays, chunk=0).valid, "chunk")
    probe("trace chunk -5", lambda: jl.trace(lens, rays, chunk=-5).valid, "chunk")
    probe("trace chunk 'big'", lambda: jl.trace(lens, rays, chunk="big").valid, "chunk")
    import dataclasses
    small = dataclasses.replace(lens, sensor=jl.Sensor((8, 8), 0.05))
    img = jnp.ones((8, 8, 3))
    probe("render mesh 'cpu'", lambda: jl.render(small, img, spp=1, key=jax.random.PRNGKey(0), mesh="cpu"), "mesh")
    probe("render relative_illumination 'no'", lambda: jl.render(small, img, spp=1, key=jax.random.PRNGKey(0), relative_illumination="no"), "relative_illumination")
    spec = D.DesignSpec()
    probe("design shard 'no'", patched(D.multistart if hasattr(D, "multistart") else D, ["run"], lambda: D.design(spec, [0], shard="no", progress=False)), "shard")
    probe("design image_loss 5", patched(D.multistart if hasattr(D, "multistart") else D, ["run"], lambda: D.design(spec, [0], image_loss=5, progress=False)), "image_loss")
    probe("design devices 0", patched(D.multistart if hasattr(D, "multistart") else D, ["run"], lambda: D.design(spec, [0], devices=0, progress=False)), "devices")
    import types
    stage = D.Stage("x", fov=40.0, fnum=4.0, steps=10)
    params = types.SimpleNamespace(c=jnp.zeros((1, 3)))  # read for its dtype and batch only
    obj = types.SimpleNamespace(sampling=types.SimpleNamespace(area=jnp.ones(3)))
    drun = lambda *a, **k: until_started(lambda: D.run(D.DesignSpec(), [stage], params, *a, progress=False, **k))
    probe("run make_solver 'adam'", drun(obj, "adam"), "make_solver")
    probe("run objective None", drun(None, started), "objective")
    probe("run mesh 'cpu'", drun(obj, started, mesh="cpu"), "mesh")
    probe("run objective and make_solver (control: starts)", drun(obj, started), good=True)
    probe("Lens afocal_image 'no'", lambda: dataclasses.replace(lens, afocal_image="no").afocal_image, "afocal_image")
    probe("Lens negative_propagation 'no'", lambda: dataclasses.replace(lens, negative_propagation="no").negative_propagation, "negative_propagation")
    probe("Lens description 5", lambda: dataclasses.replace(lens, description=5).description, "description")
    probe("Lens image 'flat'", lambda: dataclasses.replace(lens, image="flat").image, "image")
    probe("DesignConfig curriculum_n 0 (control: one stage, N + 1)", lambda: D.DesignConfig(curriculum_n=0).curriculum_n, good=True)
    probe("DesignConfig lr_a -1", lambda: D.DesignConfig(lr_a=-1.0), "lr_a")
    probe("DesignConfig float64 'no'", lambda: D.DesignConfig(float64="no"), "float64")
    probe("DesignSpec sensor_aspect 0", lambda: D.DesignSpec(sensor_aspect=0.0), "sensor_aspect")
    probe("DesignSpec sensor_diagonal 7660 (µm)", lambda: D.DesignSpec(sensor_diagonal=7660.0), "sensor_diagonal")
    probe("DesignSpec sensor_pixels (0, 0)", lambda: D.DesignSpec(sensor_pixels=(0, 0)), "sensor_pixels")
    probe("bfl wavelength 587.6 (nm)", lambda: jl.bfl(lens, wavelength=587.6), "nm")
    probe("efl wavelength NaN", lambda: jl.efl(lens, wavelength=np.nan), "wavelength")
    probe("Air name 5", lambda: jl.Air(name=5), "name")
    probe("HullMaterials corners 1-D", lambda: D.HullMaterials(corners=[1.5, 60.0]), "corners")


# ----------------------------------------------------------------------------- JSON lens files
def lens_files():
    base = json.loads(pathlib.Path(COOKE).read_text())

    def lf(edit, text=None):
        d = json.loads(json.dumps(base))
        edit(d)
        p = os.path.join(TMP, f"l{len(os.listdir(TMP))}.json")
        pathlib.Path(p).write_text(text if text is not None else json.dumps(d))
        return lambda: jl.load(p).thickness
    probe("lens file units 'm'", lf(lambda d: d.update(units="m")), "units")
    probe("lens file wavelengths_um [486.1, 587.6, 656.3] (nm)", lf(lambda d: (d.pop("wavelengths_nm", None), d.pop("wavelengths", None), d.update(wavelengths_um=[486.1, 587.6, 656.3]))), "nm")
    probe("lens file material nd/vd swapped", lf(lambda d: d["surfaces"][1].update(material={"nd": 60.3, "vd": 1.62})), "nd")
    probe("lens file thickness -3 in glass (warns)", warned(lf(lambda d: d["surfaces"][1].update(thickness=-3.0))), "thickness -3", "inside")
    probe("lens file thickness -1 in air (control: air may go back, as to a dummy surface)", warned(lf(lambda d: d["surfaces"][2].update(thickness=-1.0))), good=True)
    probe("lens file fields type 'angle_rad'", lf(lambda d: d["fields"].update(type="angle_rad")), "type")
    probe("lens file surface kind 'sphere2'", lf(lambda d: d["surfaces"][1].update(type="sphere2")), "sphere2")
    probe("lens file primary 3 of 3", lf(lambda d: d.update(primary=3)), "primary")
    probe("lens file aperture EPD '10mm'", lf(lambda d: d.update(aperture={"EPD": "10mm"})), "EPD")
    probe("lens file a UTF-16 file", lambda: (pathlib.Path(TMP, "u16.json").write_text(json.dumps(base), encoding="utf-16"), jl.load(os.path.join(TMP, "u16.json")))[1], "UTF")
    probe("lens file a BOM (utf-8-sig; control)", lambda: (pathlib.Path(TMP, "bom.json").write_text(json.dumps(base), encoding="utf-8-sig"), jl.load(os.path.join(TMP, "bom.json")).epd)[1], good=True)
    probe("lens file key 'thickness' twice", lf(lambda d: None, json.dumps(base).replace('"thickness": ', '"thickness": 3.0, "thickness": ', 1)), "twice")
    probe("lens file fields {} (no values)", lf(lambda d: d.update(fields={"type": "angle_deg_y"})), "fields")
    mat = lambda m: lf(lambda d: d["surfaces"][1].update(material=m))
    probe("lens file material catalog 'SCHOT'", mat({"name": "N-SK16", "catalog": "SCHOT"}), "SCHOT", "SCHOTT")
    probe("lens file material N-SK16 catalog 'CDGM' (not there)", mat({"name": "N-SK16", "catalog": "CDGM"}), "N-SK16", "CDGM")
    probe("lens file material catalog without a name", mat({"catalog": "SCHOTT"}), "name")
    probe("lens file material N-SK16 catalog 'schott' (control)", mat({"name": "N-SK16", "catalog": "schott"}), good=True)
    probe("lens file as read (control)", lf(lambda d: None), good=True)


# ----------------------------------------------------------------------------- .zmx files
def zmx_files():
    text = pathlib.Path(SEED0).read_text(encoding="utf-8")

    def write_load(body, suffix=".zmx", encoding="utf-8"):
        p = os.path.join(TMP, f"z{len(os.listdir(TMP))}{suffix}")
        pathlib.Path(p).write_text(body, encoding=encoding)
        return lambda: jl.load(p).thickness

    def z(old, new, count=1):
        assert old in text, old
        return write_load(text.replace(old, new, count))
    lines = text.splitlines()
    curv = next(line for line in lines if line.strip().startswith("CURV") and float(line.split()[1]) != 0)
    disz = next(line for line in lines if line.strip().startswith("DISZ") and line.split()[1] != "INFINITY")
    surf_lines = [i for i, line in enumerate(lines) if line.startswith("SURF ")]
    probe("zmx CURV twice in one surface", z(curv + "\n", curv + "\n" + curv.replace(curv.split()[1], "0.05") + "\n"), "CURV")
    probe("zmx DISZ twice in one surface", z(disz + "\n", disz + "\n" + disz.replace(disz.split()[1], "7.5") + "\n"), "DISZ")
    glas = next(line for line in lines if line.strip().startswith("GLAS"))
    probe("zmx GLAS twice in one surface", z(glas + "\n", glas + "\n" + "  GLAS N-BK7 0 0 1.5168 64.17\n"), "GLAS")
    enpd = next(line for line in lines if line.startswith("ENPD "))
    probe("zmx ENPD twice", z(enpd + "\n", enpd + "\nENPD 3\n"), "ENPD")
    probe("zmx a UTF-16 file (Zemax's default; control)", write_load(text, encoding="utf-16"), good=True)
    probe("zmx CRLF line ends (control)", write_load(text.replace("\n", "\r\n")), good=True)
    probe("zmx latin-1 comment (control)", write_load(text.replace("\nSURF 1\n", "\nNOTE 0 Lentille d'essai à °µ\nSURF 1\n", 1), encoding="latin-1"), good=True)
    cut = "\n".join(lines[:surf_lines[3] + 2]) + "\n"
    probe("zmx cut inside SURF 3's block", write_load(cut), "SURF")
    probe("zmx DISZ 'INFINITY' on a middle surface", z(disz, disz.replace(disz.split()[1], "INFINITY")), "DISZ")
    probe("zmx CURV in the DISZ column (DISZ 0.05 CURV 8)", z(disz, disz.replace("DISZ", "CURV")), "CURV")
    probe("zmx WAVM weight 0 on the primary (warns)", warned(z("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 0")), "weigh")
    def raw(data):
        p = os.path.join(TMP, f"z{len(os.listdir(TMP))}.zmx")
        pathlib.Path(p).write_bytes(data)
        return lambda: jl.load(p).thickness
    import io
    import zipfile
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("lens.zmx", text)
    probe("zmx a .zar/zip archive named .zmx", raw(buf.getvalue()), "binary")
    probe("zmx empty", raw(b""), "no SURF")
    probe("zmx UTF-16 LE without a BOM (control)", raw(text.encode("utf-16-le")), good=True)
    probe("zmx tabs between keyword and value (control)", write_load(text.replace("  DISZ ", "\tDISZ\t")), good=True)
    probe("zmx as read (control)", write_load(text), good=True)


# ----------------------------------------------------------------------------- command lines
def command_lines():
    from jaxlens.experiments import classical as C
    from jaxlens.experiments import tolerance as TOL

    def cli(fn):
        fn.cli = True
        return fn
    real = (C.run_design, TOL.analyse_design, getattr(C, "run_ablation", None))
    C.run_design, TOL.analyse_design = started, started
    if real[2] is not None:
        C.run_ablation = started
    try:
        classical = lambda *a: until_started(cli(lambda: C.main(["--out", os.path.join(TMP, f"c{len(os.listdir(TMP))}"), *a])))
        probe("classical --sensor-diagonal 7660 (µm)", classical("--sensor-diagonal", "7660"), "--sensor-diagonal")
        probe("classical --sensor-diagonal 0.00766 (m)", classical("--sensor-diagonal", "0.00766"), "--sensor-diagonal")
        probe("classical --fov 1.41 (radians)", classical("--fov", "1.41"), "--fov")
        probe("classical --seed-list 1,1,2 (a seed twice)", classical("--seed-list", "1,1,2"), "--seed-list")
        probe("classical --seed-list '' (none)", classical("--seed-list", ""), "--seed-list")
        probe("classical --first-seed -1", classical("--first-seed", "-1"), "--first-seed")
        probe("classical --material-catalogs schot", classical("--select-materials", "continuous", "--material-catalogs", "schot"), "SCHOTT")
        probe("classical --tolerance-threshold 0", classical("--tolerance-threshold", "0"), "--tolerance-threshold")
        probe("classical --tolerance-trials 10**9", classical("--tolerance-trials", str(10**9)), "--tolerance-trials")
        probe("classical --elements 0", classical("--elements", "0"), "--elements")
        probe("classical --bfl 0", classical("--bfl", "0"), "--bfl")
        # --ablation refuses --out since round 32b: these run without it.
        ablation = lambda *a: until_started(cli(lambda: C.main(["--ablation", *a])))
        probe("classical --ablation --ablation-seeds 0", ablation("--ablation-seeds", "0"), "--ablation-seeds")
        probe("classical --ablation --columns nosuch", ablation("--columns", "nosuch"), "--columns")
        probe("classical --ablation --ablation-out a file", ablation("--ablation-out", COOKE), "--ablation-out")
        tol = lambda *a: until_started(cli(lambda: TOL.main([SEED0, "--out", os.path.join(TMP, f"t{len(os.listdir(TMP))}"), *a])))
        probe("tolerance --decenter 10 (µm)", tol("--decenter", "10"), "--decenter")
        probe("tolerance --decenter nan", tol("--decenter", "nan"), "--decenter")
        probe("tolerance --threshold 0", tol("--threshold", "0"), "--threshold")
        probe("tolerance --threshold 6000 (nm)", tol("--threshold", "6000"), "--threshold")
        probe("tolerance --decenter 0.01 (control)", tol("--decenter", "0.01"), good=True)
    finally:
        C.run_design, TOL.analyse_design = real[:2]
        if real[2] is not None:
            C.run_ablation = real[2]


def edof_cli():
    check = edof_check
    probe("edof --batch 0", check("--batch", "0"), "--batch")
    probe("edof --kernel 4 (even)", check("--kernel", "4"), "--kernel")
    probe("edof --binning 0", check("--binning", "0"), "--binning")
    probe("edof --pupil 10**6", check("--pupil", str(10**6)), "--pupil")
    probe("edof --lens-every 0", check("--lens-every", "0"), "--lens-every")
    probe("edof --time-limit -1", check("--time-limit", "-1"), "--time-limit")
    probe("edof --width 0", check("--width", "0"), "--width")
    probe("edof --n-odd -1", check("--n-odd", "-1"), "--n-odd")
    probe("edof --context 0 (control: no context)", check("--context", "0"), good=True)
    probe("edof --context -1", check("--context", "-1"), "--context")
    probe("edof --test-dir a missing folder", check("--test-dir", os.path.join(TMP, "nope")), "--test-dir")
    probe("edof --seeds 0 (control: seed 0)", check("--seeds", "0"), good=True)
    probe("edof --seeds 0,0", check("--seeds", "0,0"), "--seeds")
    probe("edof --cubic-floor 50 (percent)", check("--cubic-floor", "50"), "--cubic-floor")
    probe("edof --checkpoint a lens file", check("--checkpoint", COOKE), "--checkpoint")
    probe("edof defaults (control)", check(), good=True)


def tools_cli():
    pathlib.Path(TMP, "empty_dir").mkdir(exist_ok=True)
    probe("check_corpus a folder without .zmx", tool("check_corpus.py", os.path.join(TMP, "empty_dir")), "no .zmx")
    probe("check_corpus a missing folder", tool("check_corpus.py", os.path.join(TMP, "nope")), "folder")
    probe("check_corpus --unknown-glass modle", tool("check_corpus.py", TMP, "--unknown-glass", "modle"), "--unknown-glass")
    if os.path.exists(OPTILAND_PYTHON):
        probe("make_refcase without arguments", tool("make_refcase.py", python=OPTILAND_PYTHON), "required: out")
        probe("make_refcase an unknown case name", tool("make_refcase.py", os.path.join(TMP, "rc"), "wide_angle_curvd_image", python=OPTILAND_PYTHON), "wide_angle_curved_image")
        probe("make_refcase OUT a file", tool("make_refcase.py", COOKE, "stop_at_last_surface", python=OPTILAND_PYTHON), "folder")
    probe("make_agf a missing database", tool("make_agf.py", os.path.join(TMP, "nope")), "database")


def bench_outputs():
    import shutil

    import benchmarks.common as BC
    import benchmarks.render_memory as RM
    import benchmarks.render_speed as RS
    import benchmarks.vjp_probe as VJ

    lens_copy = os.path.join(TMP, "my_lens.json")
    shutil.copy(COOKE, lens_copy)
    notes = os.path.join(TMP, "notes.txt")
    pathlib.Path(notes).write_text("my notes\n")
    speed = os.path.join(TMP, "speed.json")
    shutil.copy(os.path.join(ROOT, "benchmarks", "results", "render_speed.json"), speed)
    rs = lambda out: patched(BC, ["machine_info"], lambda: RS.main(["--out", out]))
    probe("render_speed --out a lens file", rs(lens_copy), "not a render_speed result")
    probe("render_speed --out notes (not JSON)", rs(notes), "not JSON")
    probe("render_speed --out its own result (control: starts)", rs(speed), good=True)
    probe("render_memory --out a lens file", patched(RM, ["run_isolated"], lambda: RM.main(["--out", lens_copy])), "not a render_memory result")
    probe("vjp_probe --json a render_speed result", patched(VJ, ["check", "count_fusions", "timing"], lambda: VJ.main(["--json", speed])), "render_speed")


if os.environ.get("AUDIT31_COUNT"):
    count_mentions()
else:
    run([leftovers, least_named, lens_files, zmx_files, command_lines, edof_cli, tools_cli, bench_outputs])
