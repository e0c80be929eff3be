# ruff: noqa: E501, B023, E731
"""Round-32b bad-input probes: what a user types or hands over, not the Python API (round
32a probes that): the table of ``tools/audit22_probe.py`` (probe | outcome | what happened)
for every command line (``python -m jaxlens report``, ``jaxlens.experiments.classical``,
``.tolerance``, ``.edof`` and ``.edof.design``/``.merge`` up to their work, ``python -m
benchmarks`` and its modules, the ``tools/*.py`` a user runs), for the options rounds 29-31
named least (``--recipe``, ``--no-curriculum``, ``--no-mask``, ``--loss``, ``--hold-focus``,
``--validation``, ``--depth-sampling``, ``--no-small-step-check``, ``--flag``, ``--dtype``,
``--expand``, ``--resave``/``--json``: 0-1 mentions each in the probe and test files), for
files (the JSON lens format, hand-edited ``.zmx`` lines, AGF catalogs, scene images) and
for writes interrupted by Ctrl-C.

Gaps found and fixed:
1. ``classical --ablation`` dropped without a word the options its columns override:
   ``--seeds 20`` (the columns ran --ablation-seeds' starts), ``--seed-list``, ``--recipe``,
   ``--no-mask``/``--no-curriculum``/``--no-regularize``, ``--loss image``, ``--out``,
   ``--no-plots``/``--no-render`` and ``--tolerance-trials``/``-threshold``; and
   ``--no-curriculum`` dropped ``--fov-start``/``--fnum-start`` (only the sine path reads
   them). Refused, naming the option (``_no_ignored_options``).
2. ``classical --ablation`` into an ``--ablation-out`` holding a column of another spec
   (``--fov 60``) put it into this run's 80.8° table, and a column cut by an interrupted
   write failed the table after this run's designs (JSONDecodeError). Both refused before
   the designs, naming the file (and the differing spec fields); each column now records
   its spec and is written whole (a temporary file renamed). The table code moved to
   ``jaxlens/experiments/ablation_table.py`` (classical.py was at 800 lines; now 744).
3. ``jaxlens.save`` wrote over a ``.json``/``.zmx`` lens in place: a Ctrl-C mid-write lost
   the lens it replaced (a half file; a ``.zmx`` cut at a block's end reads as a shorter
   lens). Now written whole or not at all (``json_values.write_whole``). A JSON lens cut
   short or empty says so ("the file does not end in '}' (cut short?)", "the file is
   empty"; before: "Unterminated string starting at", "Expecting value").
4. ``edof``: ``--hold-focus``/``--cubic-floor``/``--hybrid-floor`` without their lens in
   ``--lenses`` (dropped: ``LENS_ONLY``), ``--validation`` with ``--test-dir`` (the folder
   won), a ``--test-dir`` image smaller than one test crop (no crop, unnamed): refused
   before the run. A grey+alpha image is read as grey (before: "expected a grey or RGB
   image, got shape (8, 8, 2)", no file named).
5. ``edof.design --total-track 7000`` (µm) named ``total_track`` (the spec's field): now
   ``--total-track``.
6. ``benchmarks.grad_levers --flag nosuch`` ran the other settings, then failed in its
   child: refused (an XLA flag reads ``--xla_<name>=<value>``).
7. ``tools/export_reevaluation.py --json F`` wrote over a lens file or one of its own inputs
   (the records replaced the lens), ``--json FOLDER`` failed with IsADirectoryError after
   every file, and a folder without lenses wrote an empty record: refused before the work.
8. ``tools/zmx_config_reference.py``: a missing or ``.json`` file, and ``--expand`` of a file
   without an MNUM section (StopIteration), refused before optiland runs.
9. ``tools/make_agf.py DB --out EMPTY`` rewrote four catalogs, then stopped at SCHOTT with a
   FileNotFoundError (SCHOTT's glasses are added to the hand-kept SCHOTT.agf); a maker
   missing from the database likewise. Refused before any write; catalogs written whole.
10. ``.zmx``: ``PARM 3 -1.2E-004 5`` (a value in the wrong column, or a number split by a
    space) was read as -1.2E-004, as DISZ was before round 30: refused, naming the line
    (every one of the 21846 PARM lines of the 439 .zmx files here holds an index and one
    value; trailing zeros pass as padding).
11. JSON lens: ``"fields": {"weights": [1, 2, 1]}`` (or ``wavelength_weights``) passed as a
    comment: unequal weights warn, as the ``.zmx`` reader warns about FWGN (a ``Lens``
    holds no weights).
12. ``edof --seeds 0,,1`` ran seeds 0 and 1 (an empty entry dropped; also ``--enc``/
    ``--dec``): refused in argparse's one line.
13. ``python -m benchmarks.pareto`` (imaging, skipping, throughput) ran nothing and exited
    0: each runs ``python -m benchmarks --only NAME`` with its arguments; ``summary``,
    ``optiland_ref`` and ``common`` say they are helpers.

Controls of note: ``UNIT IN`` (converted to mm), ``FTYP`` announcing 4 fields with 5 YFLN
values (Zemax shows 4), ``VERS`` twice, UTF-16 BE without a BOM; a JSON material
``{"nd": 1.62}`` (documented: no dispersion), ``"n-sk16"``; an AGF ``LD 0.3 2500`` (a far-
infrared maximum is allowed), a glass given twice in one AGF (documented: the later
wins); ``render`` of a 1x1 scene (a uniform scene); ``--no-plots --no-render`` (the same
run); ``--fov -0`` is refused, ``--tilt -0`` is off.

Not fixed (not this round's modules, or left as is): an EDoF checkpoint is two files
replaced one after the other (``train.Trainer.save``): a stop between the two renames
leaves a new ``.eqx`` beside the old ``.json``, which ``--resume`` trusts (the training
code; a digest of the ``.eqx`` in the ``.json``, checked on load, would refuse it);
``load_agf`` keeps the later of two records of one name (documented; no shipped catalog
has one; jaxlens/optics/catalog.py is at 799 lines).

Before (main at f920cd8, an archive) and after (branch audit32b), the same probes,
``PYTHONPATH=<tree> python tools/audit32b_probe.py`` from the repository, 156 probes, about
two minutes each way (the zmx_config_reference and export_reevaluation rows use
/work/optiland_venv's Python where it exists):
    before: clear error: 81, crash: 8, ok: 40, silent wrong: 24, vague error: 3
    after:  clear error: 113, ok: 43

A row marked "(warns)" counts a warning as the answer; a command-line row "silent wrong"
with "started" or "accepted" passed every check and began its work (the probe stops it
there). A "Ctrl-C mid-write" row interrupts ``save`` halfway through its write and loads
the file again.

Probe (before -> after):
    classical --ablation --seeds 20 (ablation takes --ablation-seeds)                   silent wrong -> clear error
    classical --ablation --seed-list 3,4                                                silent wrong -> clear error
    classical --ablation --recipe strong (columns fix the recipe)                       silent wrong -> clear error
    classical --ablation --no-mask (columns set the mask)                               silent wrong -> clear error
    classical --ablation --no-curriculum                                                silent wrong -> clear error
    classical --ablation --out DIR (designs go to --ablation-out)                       silent wrong -> clear error
    classical --ablation --tolerance-trials 50 (no tolerancing)                         silent wrong -> clear error
    classical --ablation --ablation-seeds 3 (control)                                   ok           -> ok
    classical --no-curriculum --fov-start 40                                            silent wrong -> clear error
    classical --no-curriculum --fnum-start 4                                            silent wrong -> clear error
    classical --no-curriculum (control)                                                 ok           -> ok
    classical --no-plots --no-render (control: redundant, the same run)                 ok           -> ok
    classical --fov -0 (negative zero)                                                  clear error  -> clear error
    classical --fnum inf                                                                clear error  -> clear error
    classical --columns '' (empty list)                                                 clear error  -> clear error
    classical --out 'a folder with spaces' (control)                                    ok           -> ok
    classical --ablation --columns +curriculum beside a --fov 60 column                 silent wrong -> clear error
    classical --ablation --columns +recipe --overwrite over the shipped table (control) ok           -> ok
    classical --ablation beside a column cut mid-write (Ctrl-C)                         silent wrong -> clear error
    tolerance --tilt -0 (negative zero: off; control)                                   ok           -> ok
    tolerance --decenter inf                                                            clear error  -> clear error
    tolerance --no-small-step-check (control)                                           ok           -> ok
    tolerance an empty design file                                                      clear error  -> clear error
    report --wavelengths 587.6 (nm, read as nm; control)                                ok           -> ok
    report --wavelengths 0                                                              clear error  -> clear error
    report --fields -0 (control)                                                        ok           -> ok
    report --fields 1.2 rad? 95 deg                                                     clear error  -> clear error
    report a lens path with spaces (control)                                            ok           -> ok
    report a .ZMX (upper case; control)                                                 ok           -> ok
    report a lens named .txt                                                            clear error  -> clear error
    report --float32 after the command                                                  clear error  -> clear error
    report --plot DIR holding another lens's figures (control: kept)                    ok           -> ok
    edof.design --elements 0                                                            clear error  -> clear error
    edof.design --total-track 7000 (µm)                                                 vague error  -> clear error
    edof.design --scale 0                                                               clear error  -> clear error
    edof.design --seeds 0,0                                                             clear error  -> clear error
    edof.design --seeds ''                                                              clear error  -> clear error
    edof.merge one run given twice                                                      clear error  -> clear error
    edof --seeds 0,,1 (an empty entry)                                                  silent wrong -> clear error
    edof --depth-sampling dioptric (control)                                            ok           -> ok
    edof --hold-focus --lenses cubic (no hybrid to hold)                                silent wrong -> clear error
    edof --validation --test-dir DIR (which images?)                                    silent wrong -> clear error
    edof --test-dir DIR of a 300x300 image (control)                                    ok           -> ok
    edof --max-crops 10**9                                                              ok           -> ok
    edof --tile 10**5 (memory)                                                          clear error  -> clear error
    edof --batch 10**6 (memory)                                                         clear error  -> clear error
    edof --steps 10**9 (hours)                                                          clear error  -> clear error
    edof --time-limit nan                                                               clear error  -> clear error
    edof --photons inf                                                                  clear error  -> clear error
    edof --read-noise 2 (percent)                                                       clear error  -> clear error
    benchmarks --smoke --full                                                           clear error  -> clear error
    benchmarks --only nosuch                                                            clear error  -> clear error
    benchmarks --counts 0                                                               clear error  -> clear error
    benchmarks --lenses nosuch                                                          clear error  -> clear error
    render_speed --spp 10**7                                                            clear error  -> clear error
    render_speed --repeats 0                                                            clear error  -> clear error
    render_speed --size 1e4 (not whole)                                                 clear error  -> clear error
    python -m benchmarks.pareto --bogus (runs nothing?)                                 silent wrong -> clear error
    python -m benchmarks.summary (a helper)                                             silent wrong -> clear error
    vjp_probe --dtype float16                                                           clear error  -> clear error
    grad_levers --flag nosuch                                                           silent wrong -> clear error
    grad_levers --chunks 0                                                              clear error  -> clear error
    grad_levers --rays 0                                                                clear error  -> clear error
    check_corpus --strict a folder without .zmx                                         clear error  -> clear error
    zmx_config_reference a missing file                                                 crash        -> clear error
    zmx_config_reference a .json lens                                                   crash        -> clear error
    zmx_config_reference --expand a single-configuration file                           crash        -> clear error
    aim_compile_size --aims 0                                                           clear error  -> clear error
    make_agf --out over a lens file                                                     clear error  -> clear error
    export_reevaluation a missing path                                                  clear error  -> clear error
    export_reevaluation --json a lens file (written over)                               silent wrong -> clear error
    export_reevaluation --json one of its inputs                                        silent wrong -> clear error
    export_reevaluation --json a folder                                                 crash        -> clear error
    export_reevaluation a folder without lenses                                         silent wrong -> clear error
    zmx SURF 3 given twice (SURF 4 renumbered 3)                                        clear error  -> clear error
    zmx SURF numbers out of order (3 and 4 swapped)                                     clear error  -> clear error
    zmx SURF 5 missing (4 then 6)                                                       clear error  -> clear error
    zmx CURV with a trailing unit (0.1mm)                                               clear error  -> clear error
    zmx DISZ 2,5 (decimal comma)                                                        clear error  -> clear error
    zmx DISZ nan                                                                        clear error  -> clear error
    zmx DISZ -0 (control)                                                               ok           -> ok
    zmx a SURF line with no number                                                      clear error  -> clear error
    zmx a binary file (PNG bytes)                                                       clear error  -> clear error
    zmx cut mid-line (last line 'CURV 1.2')                                             clear error  -> clear error
    zmx UNIT MM X (control)                                                             ok           -> ok
    zmx UNIT IN (control: inches converted to mm)                                       ok           -> ok
    zmx UNIT mm (lower case)                                                            ok           -> ok
    zmx WAVM 2 587.6 (nm, in µm column)                                                 clear error  -> clear error
    zmx PARM 3 with a second value                                                      silent wrong -> clear error
    zmx PARM 3 padded with a 0 (control)                                                ok           -> ok
    zmx STOP on two surfaces                                                            clear error  -> clear error
    zmx PWAV 4 of 3 wavelengths                                                         clear error  -> clear error
    zmx ENPD 0                                                                          clear error  -> clear error
    zmx ENPD -2.25                                                                      clear error  -> clear error
    zmx FTYP 6 fields, YFLN lists 5 (warns)                                             clear error  -> clear error
    zmx FTYP 4 fields, YFLN lists 5 (control: Zemax shows FTYP's 4)                     ok           -> ok
    zmx YFLN given twice                                                                clear error  -> clear error
    zmx WAVM 2 given twice                                                              clear error  -> clear error
    zmx FWGN 1 1 (2 weights for 5 fields)                                               clear error  -> clear error
    zmx TYPE EVENASP (misspelt)                                                         clear error  -> clear error
    zmx PARM 0 on an asphere                                                            clear error  -> clear error
    zmx PARM 99 on an asphere                                                           clear error  -> clear error
    zmx GCAT NOTACAT (warns)                                                            clear error  -> clear error
    zmx UTF-16 BE without a BOM (control)                                               ok           -> ok
    zmx VERS given twice (control: harmless)                                            ok           -> ok
    zmx a .zmx file that is JSON                                                        clear error  -> clear error
    json lens file that is a .zmx                                                       clear error  -> clear error
    lens file NaN thickness (JSON NaN literal)                                          clear error  -> clear error
    lens file Infinity radius on a middle surface (control: flat)                       ok           -> ok
    lens file -0 thickness (control)                                                    ok           -> ok
    lens file cut mid-write (Ctrl-C)                                                    vague error  -> clear error
    lens file empty                                                                     vague error  -> clear error
    lens file a list, not an object                                                     clear error  -> clear error
    lens file surfaces []                                                               clear error  -> clear error
    lens file thickness '5 mm' (a unit)                                                 clear error  -> clear error
    lens file thickness '5,0' (decimal comma)                                           clear error  -> clear error
    lens file wavelengths [] (empty)                                                    clear error  -> clear error
    lens file is_stop on two surfaces                                                   clear error  -> clear error
    lens file aperture epd and fnum both                                                clear error  -> clear error
    lens file primary_wavelength_nm 550 (not listed)                                    clear error  -> clear error
    lens file primary_wavelength_nm 0.5876 (µm in the nm key)                           clear error  -> clear error
    lens file format jaxlens.lens/2 (a newer format)                                    clear error  -> clear error
    lens file radius 0                                                                  clear error  -> clear error
    lens file the object surface second                                                 clear error  -> clear error
    lens file material {nd: 1.62} without vd (control: documented, no dispersion)       ok           -> ok
    lens file material 'n-sk16' (lower case; control)                                   ok           -> ok
    lens file fields values []                                                          clear error  -> clear error
    lens file fields 95 deg                                                             clear error  -> clear error
    lens file fields weights [1, 2, 1] (warns)                                          silent wrong -> clear error
    lens file wavelength_weights [1, 2, 1] (warns)                                      silent wrong -> clear error
    lens file fields weights [1, 1, 1] (control: equal)                                 ok           -> ok
    lens file semi_diameter -1                                                          clear error  -> clear error
    agf a glass without its CD line                                                     clear error  -> clear error
    agf formula 14 (Zemax defines none)                                                 clear error  -> clear error
    agf LD in nm (300 2500)                                                             clear error  -> clear error
    agf LD 0.3 2500 (max in nm; control: a far-infrared maximum is allowed)             ok           -> ok
    agf a glass given twice (control: documented, the later wins)                       ok           -> ok
    agf CD with a comma decimal                                                         clear error  -> clear error
    agf CD cut short (2 of 6 Sellmeier terms)                                           clear error  -> clear error
    agf nd 0 Vd 0 (control: Zemax allows)                                               ok           -> ok
    agf as written (control)                                                            ok           -> ok
    agf UTF-16 without BOM (control)                                                    ok           -> ok
    read_png 16-bit grey (control)                                                      ok           -> ok
    read_png palette (control)                                                          ok           -> ok
    read_png RGBA half transparent (control: alpha dropped, documented)                 ok           -> ok
    read_png 1x1 (control)                                                              ok           -> ok
    edof load_images a grey+alpha PNG                                                   crash        -> ok
    render a grey PNG as read ([H, W])                                                  clear error  -> clear error
    render a PNG's 8-bit codes (not to_linear)                                          clear error  -> clear error
    render a 1x1 scene on an 8x8 sensor (control: a uniform scene)                      ok           -> ok
    edof --test-dir holding a 1x1 image                                                 silent wrong -> clear error
    edof load_images a 16-bit grey PNG (control)                                        ok           -> ok
    edof load_images a CMYK JPEG                                                        ok           -> ok
    jl.save over a .json lens, Ctrl-C mid-write (then load)                             crash        -> ok
    jl.save over a .zmx lens, Ctrl-C mid-write (then load)                              crash        -> ok
    make_agf --out without the hand-kept SCHOTT.agf                                     crash        -> clear error
"""

import json
import os
import pathlib
import subprocess
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore", DeprecationWarning)

from probe_table import (  # noqa: E402
    COOKE,
    OPTILAND_PYTHON,
    ROOT,
    SEED0,
    TMP,
    CutWriter,
    cli,
    edof_check,
    patched,
    probe,
    run,
    started,
    tool,
    until_started,
    warned,
)

import jaxlens as jl  # noqa: E402


def new(name):
    return os.path.join(TMP, f"{name}{len(os.listdir(TMP))}")


# ----------------------------------------------------------------------------- classical
def classical_cli():
    from jaxlens.experiments import classical as C

    real = (C.run_design, C.run_ablation)
    C.run_design, C.run_ablation = started, started
    try:
        c = lambda *a: until_started(cli(lambda: C.main(["--out", new("c"), *a])))
        ab = lambda *a: until_started(cli(lambda: C.main(["--ablation", "--ablation-out", new("ab"), *a])))
        probe("classical --ablation --seeds 20 (ablation takes --ablation-seeds)", ab("--seeds", "20"), "--seeds")
        probe("classical --ablation --seed-list 3,4", ab("--seed-list", "3,4"), "--seed-list")
        probe("classical --ablation --recipe strong (columns fix the recipe)", ab("--recipe", "strong"), "--recipe")
        probe("classical --ablation --no-mask (columns set the mask)", ab("--no-mask"), "--no-mask")
        probe("classical --ablation --no-curriculum", ab("--no-curriculum"), "--no-curriculum")
        probe("classical --ablation --out DIR (designs go to --ablation-out)", ab("--out", new("o")), "--out")
        probe("classical --ablation --tolerance-trials 50 (no tolerancing)", ab("--tolerance-trials", "50"), "--tolerance-trials")
        probe("classical --ablation --ablation-seeds 3 (control)", ab("--ablation-seeds", "3"), good=True)
        probe("classical --no-curriculum --fov-start 40", c("--no-curriculum", "--fov-start", "40"), "--fov-start")
        probe("classical --no-curriculum --fnum-start 4", c("--no-curriculum", "--fnum-start", "4"), "--fnum-start")
        probe("classical --no-curriculum (control)", c("--no-curriculum"), good=True)
        probe("classical --no-plots --no-render (control: redundant, the same run)", c("--no-plots", "--no-render"), good=True)
        probe("classical --fov -0 (negative zero)", c("--fov", "-0"), "--fov")
        probe("classical --fnum inf", c("--fnum", "inf"), "--fnum")
        probe("classical --columns '' (empty list)", ab("--columns", ""), "--columns")
        probe("classical --out 'a folder with spaces' (control)", until_started(cli(lambda: C.main(["--out", os.path.join(TMP, "with spaces", "run")]))), good=True)
        ro = os.path.join(TMP, "readonly")
        os.makedirs(ro, exist_ok=True)
        os.chmod(ro, 0o555)
        if os.access(ro, os.W_OK):  # root writes anywhere
            ROWS_SKIP.append("classical --out in a read-only folder (root: skipped)")
        else:
            probe("classical --out in a read-only folder", until_started(cli(lambda: C.main(["--out", os.path.join(ro, "run")]))), "writable")
        # columns of an earlier run at another spec, merged into this run's table
        d = new("abspec")
        os.makedirs(os.path.join(d, "columns"))
        col = {"command": "python -m jaxlens.experiments.classical --ablation --fov 60 --columns baseline",
               "switches": dict(C.ABLATION_COLUMNS)["baseline"], "seeds": [0]}
        pathlib.Path(d, "columns", "baseline.json").write_text(json.dumps(col))
        spec60 = dict(json.loads(pathlib.Path(ROOT, "experiments", "classical", "table1.json").read_text())["spec"], fov=60.0)
        pathlib.Path(d, "table1.json").write_text(json.dumps({"spec": spec60}))
        probe("classical --ablation --columns +curriculum beside a --fov 60 column", until_started(cli(lambda: C.main(["--ablation", "--ablation-out", d, "--columns", "+curriculum"]))), "baseline.json", "fov 60.0")
        shipped = os.path.join(TMP, "shipped_ablation")
        import shutil
        shutil.copytree(os.path.join(ROOT, "experiments", "classical"), shipped)
        probe("classical --ablation --columns +recipe --overwrite over the shipped table (control)", until_started(cli(lambda: C.main(["--ablation", "--ablation-out", shipped, "--columns", "+recipe", "--overwrite"]))), good=True)
        d2 = new("abcut")
        os.makedirs(os.path.join(d2, "columns"))
        pathlib.Path(d2, "columns", "baseline.json").write_text('{"command": "python -m jaxlens.exp')  # Ctrl-C mid-write
        probe("classical --ablation beside a column cut mid-write (Ctrl-C)", until_started(cli(lambda: C.main(["--ablation", "--ablation-out", d2, "--columns", "+curriculum"]))), "baseline.json")
    finally:
        C.run_design, C.run_ablation = real


ROWS_SKIP = []


# ----------------------------------------------------------------------------- tolerance, report
def tolerance_report():
    from jaxlens.__main__ import main as jaxlens_main
    from jaxlens.experiments import tolerance as TOL

    real = TOL.analyse_design
    TOL.analyse_design = started
    pathlib.Path(TMP, "empty.zmx").write_text("")
    try:
        tol = lambda *a: until_started(cli(lambda: TOL.main([SEED0, "--out", new("t"), *a])))
        probe("tolerance --tilt -0 (negative zero: off; control)", tol("--tilt", "-0"), good=True)
        probe("tolerance --decenter inf", tol("--decenter", "inf"), "--decenter")
        probe("tolerance --no-small-step-check (control)", tol("--no-small-step-check"), good=True)
        probe("tolerance an empty design file", until_started(cli(lambda: TOL.main([str(pathlib.Path(TMP, "empty.zmx")), "--out", new("t")]))), "empty.zmx")
    finally:
        TOL.analyse_design = real
    pathlib.Path(TMP, "empty.zmx").write_text("")
    report = lambda *a: cli(lambda: jaxlens_main(["report", *a]))
    probe("report --wavelengths 587.6 (nm, read as nm; control)", report(COOKE, "--wavelengths", "587.6", "--json"), good=True)
    probe("report --wavelengths 0 ", report(COOKE, "--wavelengths", "0", "--json"), "--wavelengths")
    probe("report --fields -0 (control)", report(COOKE, "--fields", "-0", "--json"), good=True)
    probe("report --fields 1.2 rad? 95 deg", report(COOKE, "--fields", "95", "--json"), "95")
    sp = os.path.join(TMP, "a folder with spaces")
    os.makedirs(sp, exist_ok=True)
    import shutil
    shutil.copy(COOKE, os.path.join(sp, "my lens.json"))
    probe("report a lens path with spaces (control)", report(os.path.join(sp, "my lens.json"), "--json"), good=True)
    shutil.copy(SEED0, os.path.join(TMP, "UPPER.ZMX"))
    probe("report a .ZMX (upper case; control)", report(os.path.join(TMP, "UPPER.ZMX"), "--json"), good=True)
    shutil.copy(COOKE, os.path.join(TMP, "lens.txt"))
    probe("report a lens named .txt", report(os.path.join(TMP, "lens.txt")), ".txt")
    probe("report --float32 after the command", report(COOKE, "--float32"), "--float32")
    probe("report --plot DIR holding another lens's figures (control: kept)", report(COOKE, "--json", "--plot", new("plot")), good=True)


# ----------------------------------------------------------------------------- edof
def edof_cli():
    from jaxlens.experiments.edof import cli as E

    check = edof_check
    from jaxlens.experiments.edof import design as ED
    from jaxlens.experiments.edof import merge as EM

    ed = lambda *a: patched(ED, ["design_classical"], cli(lambda: ED.main(["--out", new("ed") + ".json", "--record-dir", new("rec"), *a])))
    probe("edof.design --elements 0", ed("--elements", "0"), "--elements")
    probe("edof.design --total-track 7000 (µm)", ed("--total-track", "7000"), "--total-track")
    probe("edof.design --scale 0", ed("--scale", "0"), "--scale")
    probe("edof.design --seeds 0,0", ed("--seeds", "0,0"), "--seeds")
    probe("edof.design --seeds ''", ed("--seeds", ""), "--seeds")
    probe("edof.merge one run given twice", lambda: EM.run([os.path.join(TMP, "r1"), os.path.join(TMP, "r1"), "--out", new("m")]), "r1")
    probe("edof --seeds 0,,1 (an empty entry)", lambda: E.build_parser().parse_args(["--seeds", "0,,1"]).seeds, "--seeds", "empty")
    probe("edof --depth-sampling dioptric (control)", check("--depth-sampling", "dioptric"), good=True)
    probe("edof --hold-focus --lenses cubic (no hybrid to hold)", check("--hold-focus", "--lenses", "cubic"), "--hold-focus")
    import numpy as np
    from PIL import Image

    photos = os.path.join(TMP, "photos")
    os.makedirs(photos, exist_ok=True)
    Image.fromarray(np.full((300, 300, 3), 120, np.uint8)).save(os.path.join(photos, "a.png"))
    probe("edof --validation --test-dir DIR (which images?)", check("--validation", "--test-dir", photos), "--validation")
    probe("edof --test-dir DIR of a 300x300 image (control)", check("--test-dir", photos), good=True)
    probe("edof --max-crops 10**9", check("--max-crops", str(10**9)), good=True)
    probe("edof --tile 10**5 (memory)", check("--tile", str(10**5)), "--tile")
    probe("edof --batch 10**6 (memory)", check("--batch", str(10**6)), "--batch")
    probe("edof --steps 10**9 (hours)", check("--steps", str(10**9)), "--steps")
    probe("edof --time-limit nan", check("--time-limit", "nan"), "--time-limit")
    probe("edof --photons inf", check("--photons", "inf"), "--photons")
    probe("edof --read-noise 2 (percent)", check("--read-noise", "2"), "--read-noise")


# ----------------------------------------------------------------------------- benchmarks, tools
def bench_tools():
    import benchmarks.common as BC
    import benchmarks.grad_levers as GL
    import benchmarks.run as BR
    import benchmarks.vjp_probe as VJ

    bench = lambda *a: patched(BC, ["machine_info"], lambda: BR.main(list(a)))
    probe("benchmarks --smoke --full", bench("--smoke", "--full", "--out", new("b")), "--full")
    probe("benchmarks --only nosuch", bench("--only", "nosuch", "--out", new("b")), "nosuch")
    probe("benchmarks --counts 0", bench("--only", "throughput", "--counts", "0", "--out", new("b")), "--counts")
    probe("benchmarks --lenses nosuch", bench("--only", "throughput", "--lenses", "nosuch", "--out", new("b")), "nosuch")
    import benchmarks.render_speed as RS
    rs = lambda *a: patched(BC, ["machine_info"], lambda: RS.main([*a, "--out", os.path.join(TMP, "rs.json")]))
    probe("render_speed --spp 10**7", rs("--spp", str(10**7)), "--spp")
    probe("render_speed --repeats 0", rs("--repeats", "0"), "--repeats")
    probe("render_speed --size 1e4 (not whole)", rs("--size", "1e4"), "--size")
    def python_m(module, *a):
        def go():
            p = subprocess.run([sys.executable, "-m", f"benchmarks.{module}", *a], capture_output=True, text=True,
                               cwd=ROOT, timeout=120, env=dict(os.environ, PYTHONPATH=ROOT))
            last = (p.stderr.strip().splitlines() or [""])[-1]
            if p.returncode == 0:
                return f"exit 0, stdout {p.stdout.strip()[-60:]!r}" if p.stdout.strip() else "exit 0, nothing run"
            print(last, file=sys.stderr)
            raise SystemExit(2)
        return go
    probe("python -m benchmarks.pareto --bogus (runs nothing?)", python_m("pareto", "--bogus"), "--bogus")
    probe("python -m benchmarks.summary (a helper)", python_m("summary"), "helper")
    probe("vjp_probe --dtype float16", patched(VJ, ["check", "count_fusions", "timing"], lambda: VJ.main(["--dtype", "float16"])), "--dtype")
    probe("grad_levers --flag nosuch", patched(GL, ["measure", "run_child"] if hasattr(GL, "run_child") else ["measure"], lambda: GL.main(["--flag", "nosuch"])), "nosuch")
    probe("grad_levers --chunks 0", patched(GL, ["measure"], lambda: GL.main(["--chunks", "0"])), "--chunks")
    probe("grad_levers --rays 0", patched(GL, ["measure"], lambda: GL.main(["--rays", "0"])), "--rays")
    pathlib.Path(TMP, "nozmx").mkdir(exist_ok=True)
    probe("check_corpus --strict a folder without .zmx", tool("check_corpus.py", "--strict", os.path.join(TMP, "nozmx")), "no .zmx")
    if os.path.exists(OPTILAND_PYTHON):
        zc = lambda *a: tool("zmx_config_reference.py", *a, python=OPTILAND_PYTHON)
        probe("zmx_config_reference a missing file", zc(os.path.join(TMP, "nope.zmx")), "nope.zmx")
        probe("zmx_config_reference a .json lens", zc(COOKE), "cooke_triplet.json", ".zmx")
        probe("zmx_config_reference --expand a single-configuration file", zc("--expand", SEED0), "seed_0.zmx", "MNUM")
    probe("aim_compile_size --aims 0", tool("aim_compile_size.py", SEED0, "--aims", "0"), "--aims")
    probe("make_agf --out over a lens file", tool("make_agf.py", os.path.join(TMP, "nozmx"), "--out", COOKE), "--out")
    probe("export_reevaluation a missing path", tool("export_reevaluation.py", os.path.join(TMP, "nope")), "nope")
    import shutil
    lens_copy = os.path.join(TMP, "my lens.json")
    shutil.copy(COOKE, lens_copy)
    before = pathlib.Path(lens_copy).read_text()

    def er(*a):
        def go():
            try:
                return tool("export_reevaluation.py", *a, python=OPTILAND_PYTHON if os.path.exists(OPTILAND_PYTHON) else None)()
            finally:
                if pathlib.Path(lens_copy).read_text() != before:
                    print("the lens file was written over", file=sys.stderr)
                    shutil.copy(COOKE, lens_copy)
        return go
    probe("export_reevaluation --json a lens file (written over)", er(SEED0, "--json", lens_copy), "--json", "not an export_reevaluation record")
    probe("export_reevaluation --json one of its inputs", er(lens_copy, "--json", lens_copy), "--json", "one of the files")
    probe("export_reevaluation --json a folder", er(SEED0, "--json", TMP), "--json", "folder")
    probe("export_reevaluation a folder without lenses", er(os.path.join(TMP, "nozmx")), "no .zmx or .json")


# ----------------------------------------------------------------------------- .zmx files
def zmx_files():
    text = pathlib.Path(SEED0).read_text(encoding="utf-8")
    lines = text.splitlines()

    def write_load(body, suffix=".zmx", encoding="utf-8"):
        p = os.path.join(TMP, f"z{len(os.listdir(TMP))}{suffix}")
        pathlib.Path(p).write_text(body, encoding=encoding)
        return lambda: jl.load(p).thickness

    def z(old, new_, count=1):
        assert old in text, old
        return write_load(text.replace(old, new_, count))
    curv = next(line for line in lines if line.strip().startswith("CURV") and float(line.split()[1]) != 0)
    disz = next(line for line in lines if line.strip().startswith("DISZ") and line.split()[1] != "INFINITY")
    probe("zmx SURF 3 given twice (SURF 4 renumbered 3)", z("SURF 4\n", "SURF 3\n"), "SURF")
    probe("zmx SURF numbers out of order (3 and 4 swapped)", write_load(text.replace("SURF 3\n", "SURF X\n").replace("SURF 4\n", "SURF 3\n").replace("SURF X\n", "SURF 4\n")), "SURF")
    probe("zmx SURF 5 missing (4 then 6)", write_load(text.replace("SURF 5\n", "SURF 6X\n").replace("SURF 6\n", "SURF 7X\n").replace("SURF 6X\n", "SURF 6\n")), "SURF")
    probe("zmx CURV with a trailing unit (0.1mm)", z(curv, curv.split()[0] + " " + curv.split()[1] + "mm"), "CURV")
    probe("zmx DISZ 2,5 (decimal comma)", z(disz, "  DISZ 2,5"), "DISZ")
    probe("zmx DISZ nan", z(disz, "  DISZ nan"), "DISZ")
    probe("zmx DISZ -0 (control)", z(disz, "  DISZ -0"), good=True)
    probe("zmx a SURF line with no number", z("SURF 2\n", "SURF\n"), "SURF")
    probe("zmx a binary file (PNG bytes)", lambda: (pathlib.Path(TMP, "bin.zmx").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 4), jl.load(os.path.join(TMP, "bin.zmx")))[1], "bin.zmx")
    probe("zmx cut mid-line (last line 'CURV 1.2')", write_load(text[: text.index(curv) + len(curv) - 3]), "cut")
    probe("zmx UNIT MM X (control)", write_load(text), good=True)
    unit = next((line for line in lines if line.startswith("UNIT ")), None)
    if unit:
        probe("zmx UNIT IN (control: inches converted to mm)", z(unit, unit.replace("MM", "IN")), good=True)
        probe("zmx UNIT mm (lower case)", z(unit, unit.replace("MM", "mm")), good=True)
    probe("zmx WAVM 2 587.6 (nm, in µm column)", z("WAVM 2 5.875618E-001", "WAVM 2 587.5618"), "WAVM")
    parm = next(line for line in lines if line.strip().startswith("PARM 3"))
    probe("zmx PARM 3 with a second value", z(parm, parm + " 5"), "PARM", "one value")
    probe("zmx PARM 3 padded with a 0 (control)", z(parm, parm + " 0"), good=True)
    probe("zmx STOP on two surfaces", z("SURF 3\n", "SURF 3\n  STOP\n"), "STOP")
    probe("zmx PWAV 4 of 3 wavelengths", z("PWAV 2", "PWAV 4"), "PWAV")
    probe("zmx ENPD 0", z(next(x for x in lines if x.startswith("ENPD ")), "ENPD 0"), "ENPD")
    probe("zmx ENPD -2.25", z(next(x for x in lines if x.startswith("ENPD ")), "ENPD -2.25"), "ENPD")
    probe("zmx FTYP 6 fields, YFLN lists 5 (warns)", warned(z("FTYP 0 0 5 3", "FTYP 0 0 6 3")), "FTYP")
    probe("zmx FTYP 4 fields, YFLN lists 5 (control: Zemax shows FTYP's 4)", z("FTYP 0 0 5 3", "FTYP 0 0 4 3"), good=True)
    probe("zmx YFLN given twice", z("YFLN ", "YFLN 0 5 10 15 20\nYFLN "), "YFLN")
    probe("zmx WAVM 2 given twice", z("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 1\nWAVM 2 5.5E-001 1"), "WAVM")
    probe("zmx FWGN 1 1 (2 weights for 5 fields)", z("FWGN 1 1 1 1 1", "FWGN 1 1"), "FWGN")
    probe("zmx TYPE EVENASP (misspelt)", z("TYPE EVENASPH", "TYPE EVENASP"), "EVENASP")
    probe("zmx PARM 0 on an asphere", z("  PARM 3 ", "  PARM 0 "), "PARM")
    probe("zmx PARM 99 on an asphere", z("  PARM 3 ", "  PARM 99 "), "PARM")
    probe("zmx GCAT NOTACAT (warns)", warned(z("GCAT PLASTICS ZEON", "GCAT NOTACAT")), "NOTACAT")
    probe("zmx UTF-16 BE without a BOM (control)", lambda: (pathlib.Path(TMP, "be.zmx").write_bytes(text.encode("utf-16-be")), jl.load(os.path.join(TMP, "be.zmx")).thickness)[1], good=True)
    probe("zmx VERS given twice (control: harmless)", z("MODE SEQ", "VERS 190513 80 123457 L123457\nMODE SEQ"), good=True)
    probe("zmx a .zmx file that is JSON", lambda: (pathlib.Path(TMP, "json.zmx").write_text(pathlib.Path(COOKE).read_text()), jl.load(os.path.join(TMP, "json.zmx")))[1], "json.zmx")
    probe("json lens file that is a .zmx", lambda: (pathlib.Path(TMP, "zmx.json").write_text(text), jl.load(os.path.join(TMP, "zmx.json")))[1], "zmx.json")


# ----------------------------------------------------------------------------- JSON lens files
def lens_files():
    base = json.loads(pathlib.Path(COOKE).read_text())

    def lf(edit=None, text=None):
        d = json.loads(json.dumps(base))
        if edit:
            edit(d)
        p = os.path.join(TMP, f"l{len(os.listdir(TMP))}.json")
        pathlib.Path(p).write_text(text if text is not None else json.dumps(d))
        return lambda: jl.load(p).thickness
    s = json.dumps(base)
    probe("lens file NaN thickness (JSON NaN literal)", lf(lambda d: d["surfaces"][1].update(thickness=float("nan"))), "thickness")
    probe("lens file Infinity radius on a middle surface (control: flat)", lf(lambda d: d["surfaces"][2].update(radius=float("inf"))), good=True)
    probe("lens file -0 thickness (control)", lf(lambda d: d["surfaces"][2].update(thickness=-0.0)), good=True)
    probe("lens file cut mid-write (Ctrl-C)", lf(text=s[: len(s) // 2]), "not valid JSON", "cut short")
    probe("lens file empty", lf(text=""), "empty")
    probe("lens file a list, not an object", lf(text="[1, 2]"), "object")
    probe("lens file surfaces []", lf(lambda d: d.update(surfaces=[])), "surfaces")
    probe("lens file thickness '5 mm' (a unit)", lf(lambda d: d["surfaces"][1].update(thickness="5 mm")), "thickness")
    probe("lens file thickness '5,0' (decimal comma)", lf(lambda d: d["surfaces"][1].update(thickness="5,0")), "thickness")
    wl_key = next(k for k in base if k.startswith("wavelengths"))
    probe("lens file wavelengths [] (empty)", lf(lambda d: d.update({wl_key: []})), "wavelength")
    probe("lens file is_stop on two surfaces", lf(lambda d: d["surfaces"][2].update(is_stop=True)), "stop")
    probe("lens file aperture epd and fnum both", lf(lambda d: d.update(aperture={"epd": 10.0, "fnum": 5.0})), "aperture")
    probe("lens file primary_wavelength_nm 550 (not listed)", lf(lambda d: d.update(primary_wavelength_nm=550.0)), "550")
    probe("lens file primary_wavelength_nm 0.5876 (µm in the nm key)", lf(lambda d: d.update(primary_wavelength_nm=0.5875618)), "primary")
    probe("lens file format jaxlens.lens/2 (a newer format)", lf(lambda d: d.update(format="jaxlens.lens/2")), "jaxlens.lens/2")
    probe("lens file radius 0", lf(lambda d: d["surfaces"][2].update(radius=0.0)), "radius")
    probe("lens file the object surface second", lf(lambda d: d["surfaces"].insert(1, d["surfaces"].pop(0))), "object")
    probe("lens file material {nd: 1.62} without vd (control: documented, no dispersion)", lf(lambda d: d["surfaces"][1].update(material={"nd": 1.62})), good=True)
    probe("lens file material 'n-sk16' (lower case; control)", lf(lambda d: d["surfaces"][1].update(material="n-sk16")), good=True)
    probe("lens file fields values [] ", lf(lambda d: d["fields"].update(values=[])), "fields")
    probe("lens file fields 95 deg", lf(lambda d: d["fields"].update(values=[0.0, 95.0])), "95")
    probe("lens file fields weights [1, 2, 1] (warns)", warned(lf(lambda d: d["fields"].update(weights=[1, 2, 1]))), "weights", "not read")
    probe("lens file wavelength_weights [1, 2, 1] (warns)", warned(lf(lambda d: d.update(wavelength_weights=[1, 2, 1]))), "weights", "not read")
    probe("lens file fields weights [1, 1, 1] (control: equal)", warned(lf(lambda d: d["fields"].update(weights=[1, 1, 1]))), good=True)
    probe("lens file semi_diameter -1", lf(lambda d: d["surfaces"][1].update(semi_diameter=-1.0)), "semi")


# ----------------------------------------------------------------------------- AGF catalogs
AGF_OK = """CC test catalog
NM G1 2 0 1.5168 64.17 0 0
ED 0 0 0 2.5 0 0 0
CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0
LD 0.3 2.5
"""


def agf_files():
    import jaxlens.optics.catalog as CAT

    def agf(text, name):
        p = os.path.join(TMP, name)
        pathlib.Path(p).write_text(text)
        return lambda: jl.load_agf(p)["G1"].index(0.5876) if hasattr(jl, "load_agf") else CAT.load_agf(p)["G1"].index(0.5876)
    probe("agf a glass without its CD line", agf(AGF_OK.replace(AGF_OK.splitlines()[3] + "\n", ""), "nocd.agf"), "CD")
    probe("agf formula 14 (Zemax defines none)", agf(AGF_OK.replace("NM G1 2", "NM G1 14"), "f14.agf"), "14")
    probe("agf LD in nm (300 2500)", agf(AGF_OK.replace("LD 0.3 2.5", "LD 300 2500"), "ldnm.agf"), "LD")
    probe("agf LD 0.3 2500 (max in nm; control: a far-infrared maximum is allowed)", agf(AGF_OK.replace("LD 0.3 2.5", "LD 0.3 2500"), "ldmax.agf"), good=True)
    second = AGF_OK.replace("CC test catalog\n", "").replace("LD 0.3 2.5", "LD 0.5 1.0")
    probe("agf a glass given twice (control: documented, the later wins)", lambda: (pathlib.Path(TMP, "dup.agf").write_text(AGF_OK + second), CAT.load_agf(os.path.join(TMP, "dup.agf"))["G1"].wavelength_range)[1], good=True)
    probe("agf CD with a comma decimal", agf(AGF_OK.replace("1.03961212", "1,03961212"), "comma.agf"), "CD")
    probe("agf CD cut short (2 of 6 Sellmeier terms)", agf(AGF_OK.replace(AGF_OK.splitlines()[3], "CD 1.03961212 0.00600069867"), "short.agf"), "CD")
    probe("agf nd 0 Vd 0 (control: Zemax allows)", agf(AGF_OK.replace("1.5168 64.17", "0 0"), "nd0.agf"), good=True)
    probe("agf as written (control)", agf(AGF_OK, "ok.agf"), good=True)
    probe("agf UTF-16 without BOM (control)", lambda: (pathlib.Path(TMP, "u16.agf").write_bytes(AGF_OK.encode("utf-16-le")), CAT.load_agf(os.path.join(TMP, "u16.agf"))["G1"].index(0.5876))[1], good=True)


# ----------------------------------------------------------------------------- images
def images():
    import numpy as np
    from PIL import Image

    from jaxlens.experiments.edof import scenes as S
    from jaxlens.io import images as IM

    d = os.path.join(TMP, "imgs")
    os.makedirs(d, exist_ok=True)

    def save(name, im, folder=None):
        f = folder or d
        os.makedirs(f, exist_ok=True)
        p = os.path.join(f, name)
        im.save(p)
        return p
    rgb = (np.arange(8 * 8 * 3).reshape(8, 8, 3) * 1).astype(np.uint8)
    p16 = save("g16.png", Image.fromarray((np.arange(64).reshape(8, 8) * 1000).astype(np.uint16)))
    probe("read_png 16-bit grey (control)", lambda: IM.read_png(p16, linear=False).max(), good=True)
    pp = save("pal.png", Image.fromarray(rgb).convert("P"))
    probe("read_png palette (control)", lambda: IM.read_png(pp).shape, good=True)
    pa = save("rgba.png", Image.fromarray(np.dstack([rgb, np.full((8, 8), 128, np.uint8)]), "RGBA"))
    probe("read_png RGBA half transparent (control: alpha dropped, documented)", lambda: IM.read_png(pa).shape, good=True)
    p1 = save("one.png", Image.fromarray(np.zeros((1, 1, 3), np.uint8)))
    probe("read_png 1x1 (control)", lambda: IM.read_png(p1).shape, good=True)
    la = os.path.join(TMP, "la_dir")
    save("la.png", Image.fromarray(np.dstack([rgb[..., 0], rgb[..., 1]]), "LA"), la)
    probe("edof load_images a grey+alpha PNG", lambda: [a.shape for a in S.load_images(folder=la)], good=True)
    import dataclasses

    import jax

    lens8 = dataclasses.replace(jl.load(COOKE), sensor=jl.Sensor((8, 8), 0.05))
    rend = lambda sc: lambda: float(jl.render(lens8, sc, spp=1, key=jax.random.PRNGKey(0)).max())
    probe("render a grey PNG as read ([H, W])", rend(IM.read_png(p16)), "[H, W, C]")
    probe("render a PNG's 8-bit codes (not to_linear)", rend(np.asarray(Image.open(pp).convert("RGB"))), "to_linear")
    probe("render a 1x1 scene on an 8x8 sensor (control: a uniform scene)", rend(IM.read_png(p1)), good=True)
    tiny = os.path.join(TMP, "tiny_dir")
    save("one.png", Image.fromarray(np.zeros((1, 1, 3), np.uint8)), tiny)
    from jaxlens.experiments.edof import cli as E
    from jaxlens.experiments.runfolder import UsageError

    def check(*argv):
        def go():
            try:
                E.check_args(E.build_parser().parse_args(["--out", os.path.join(TMP, "edof2"), *argv]))
            except UsageError as e:
                raise ValueError(str(e)) from None
            return "accepted"
        return go
    probe("edof --test-dir holding a 1x1 image", check("--test-dir", tiny), "one.png")
    g16 = os.path.join(TMP, "g16_dir")
    save("g16.png", Image.fromarray((np.arange(64).reshape(8, 8) * 1000).astype(np.uint16)), g16)
    probe("edof load_images a 16-bit grey PNG (control)", lambda: float(S.load_images(folder=g16)[0].max()), good=True)
    npal = os.path.join(TMP, "cmyk_dir")
    save("c.jpg", Image.fromarray(rgb).convert("CMYK"), npal)
    probe("edof load_images a CMYK JPEG", lambda: float(S.load_images(folder=npal)[0].max()), good=True)


# ----------------------------------------------------------------------------- interrupted writes
def interrupted():
    import builtins
    import importlib
    import shutil

    def cut_open(path, mode="r", *a, **k):
        f = builtins.open(path, mode, *a, **k)
        return CutWriter(f) if "w" in mode else f

    def save_cut(src, name):
        def go():
            path = os.path.join(TMP, name)
            shutil.copy(src, path)
            before = jl.load(path)
            mods = [importlib.import_module(m) for m in ("jaxlens.io.lensfile", "jaxlens.io.zmx_write", "jaxlens.io.json_values")]
            for m in mods:
                m.open = cut_open
            try:
                jl.save(jl.load(COOKE), path)
            except KeyboardInterrupt:
                pass
            finally:
                for m in mods:
                    m.__dict__.pop("open", None)
            after = jl.load(path)  # a cut file: an error here (the old lens is lost)
            if len(after.surfaces) != len(before.surfaces):
                return f"silently a {len(after.surfaces)}-surface lens for {len(before.surfaces)}"
            return "the lens it replaced, intact"
        return go
    def lost(fn):
        def go():
            try:
                r = fn()
            except ValueError as e:  # the old lens is lost: a clear refusal is still a loss
                raise RuntimeError(f"old lens lost; load says: {str(e)[:100]}") from None
            if r.startswith("silently"):
                raise RuntimeError(r)
            return r
        return go
    probe("jl.save over a .json lens, Ctrl-C mid-write (then load)", lost(save_cut(COOKE, "cut_me.json")), good=True)
    probe("jl.save over a .zmx lens, Ctrl-C mid-write (then load)", lost(save_cut(SEED0, "cut_me.zmx")), good=True)
    db = os.path.join(TMP, "agfdb")
    for maker in ("ohara", "hoya", "hikari", "sumita", "schott", "cdgm"):
        os.makedirs(os.path.join(db, "data-nk", "glass", maker), exist_ok=True)
    out = os.path.join(TMP, "agf_out")
    os.makedirs(out, exist_ok=True)
    def make_agf_empty_out():
        try:
            return tool("make_agf.py", db, "--out", out)()
        finally:
            left = sorted(os.listdir(out))
            if left:
                print(f"wrote {left}", file=sys.stderr)
    probe("make_agf --out without the hand-kept SCHOTT.agf", make_agf_empty_out, "SCHOTT.agf")


if __name__ == "__main__":
    run([classical_cli, tolerance_report, edof_cli, bench_tools, zmx_files, lens_files, agf_files, images, interrupted])
    for r in ROWS_SKIP:
        print("skipped:", r)
