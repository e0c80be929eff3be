# ruff: noqa: E501, B023, E731
"""Round-30 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for two leftovers of round 29, the public names and parameters that the probe and
test files name least after round 29, the command lines (``jaxlens report``, classical,
tolerance, EDoF, ``python -m benchmarks`` and its modules), the JSON lens format and the
``.zmx`` reader given hand-edited lines.

The count (``probe_table.mention_counts``, rerun on main at dce17dc with every probe and
test file counted, round 29 included; ``AUDIT30_COUNT=1`` here prints it): after the result
containers (``ParaxialData``, ``RmsSpot``, ``Wavefront``…, 0-2) come the names rounds 26-29
did not reach: ``OddAsphere``/``Plane`` (9), ``evaluate_design`` (9; ``min_valid`` 8),
``trace_path`` (10; ``uniform`` and ``reverse_rule`` 0), ``Conic``/``Hybrid``/``Stop``/
``TiltedPlane``/``trace_backward``/``opd`` (11), ``LevenbergMarquardt``/``reversed_lens``
(12), ``XYPolynomial`` (13), ``ZernikeSag``/``catalog_names``/``opd_fan`` (15),
``DampedLeastSquares``/``sensor_field_grid`` (16), ``random_params`` (17), ``Binary2``/
``TableMaterials`` (20), and the parameters named 0-1 times: ``radius_for_fraction``'s
``fraction``, ``zernike_nm``'s ``j``, ``run``'s ``warmup``, ``end_lr`` and ``callback``.
Of the command-line options, the least named: ``report --lenient``/``--config``/
``--list-configs``/``--unknown-glass``, ``tolerance --tilt``/``--seed``, ``edof --steps2``/
``--w-sim``/``--w-raw``/``--lr-lens``/``--max-crops``, the benchmark modules' ``--patch``,
``--chunk``, ``--json``, ``--tag`` and ``--cap-gib`` (0-5 each).

Gaps found and fixed:
1. (leftover) ``edof.train.Config`` took any read noise and photon count: ``Config(read_noise=
   4)`` (electrons) trained on noise four times the full signal, ``photons=0`` divided by 0.
   ``Config`` now runs ``check_noise`` (read noise in [0, 0.5] linear units, photons > 0),
   which the command line also calls, in its option names, with the round-29 message.
2. (leftover) ``python -m benchmarks --out DIR`` over a ``throughput.json`` that was no
   throughput result: a full run wrote over it (other JSON, a file that was not JSON, another
   benchmark's result), a partial run refused it as "a full run's results". Both refuse it
   now, saying what the file is ("it is not JSON", "it has no "benchmark" entry", "it is a
   result of 'pareto'") and that the run would write over it.
3. ``.zmx``: ``DISZ 0.8 0.06`` (a value in the wrong column, or a number split by a space)
   was read as 0.8, and ``CONI``/``ENPD`` likewise; Zemax writes one value on each (1120
   DISZ, 593 CONI and 77 ENPD lines of the test corpora). Refused, naming the line. A
   decimal comma (``CURV 2,97E-001``) is now named as such in the "not a number" message.
4. ``load(x.json, unknown_glass="model")`` (``jaxlens report x.json --unknown-glass model``)
   ignored the option: refused, as ``config`` already was. A folder given as the lens is
   named a folder (was: "has extension ''").
5. ``jaxlens.design.run`` (public; ``DesignConfig`` checks its own copies) took
   ``warmup=5`` (5 % as 5: the rate ramped over the whole stage and never reached its peak),
   ``end_lr=5`` (the rate rose fivefold), ``irls="no"`` (read as True), ``epoch=0`` and
   ``log_every=0`` (a division by zero after the set-up), two regulariser weights and a
   callback that was not callable. All refused before the first stage.
6. Benchmark modules: ``vjp_probe --check --json out.json`` ran the check and wrote no file,
   ``--fusions`` ignored ``--lens``/``--repeats``/``--dtype``, ``--check --fusions`` ran the
   check only, and ``--chunk 4096 4096`` timed a chunk twice: refused. ``design_step --tag
   ../x`` wrote its result outside ``--out-dir``: a tag is letters, digits, '_' and '-' (as
   ``python -m benchmarks --tag``). ``render_speed --patch 1000`` (a 512-pixel frame) timed
   one 1000² tile and recorded it as patch 1000; ``render_memory --patch 200`` did so in its
   128-pixel runs: a patch past the smallest frame is refused.

Controls of note: ``Binary2(order=1.5)`` (Zemax takes a real diffraction order); ``trace``/
``trace_path`` with ``uniform="no"`` (the same rays either way: the option only changes the
compiled program); a JSON lens with ``epd`` 0.01 (F/5000 is a lens) or ``fnum`` 0.2 (rays
past the surfaces come back invalid), ``conic`` "-1" (a number in a string), no image
surface (the same lens); a ``.zmx`` GLAS line with nd and Vd swapped warns (the catalog's
glass is used, as Zemax does); ``tolerance --tilt 0.0175`` (1° in radians) is within the
tilt range; ``edof --lr-net 10`` (no upper bound on a learning rate).

Not fixed here (``jaxlens/analysis/report.py`` is another helper's this session):
``report --lenient`` on a ``.json`` lens is ignored (``load``'s ``strict`` is .zmx-only and
``report`` passes it always), and ``report --fields 0 0`` reports the field twice.

Before (main at dce17dc, an archive) and after (branch audit30), the same probes,
``PYTHONPATH=<tree> python tools/audit30_probe.py``, 155 probes, under a
minute each way:
    before: clear error: 101, ok: 21, silent wrong: 28, vague error: 5
    after:  clear error: 134, ok: 21 (the two report rows fixed after the merge)

A row marked "(warns)" counts a warning as the answer ("clear error" when it names the
slip); a command-line row "silent wrong" with "started" passed every check and began its work
(the probe stops it there: the design, the analysis, the first benchmark or worker).

Probe (before -> after):
    edof Config read_noise 4 (electrons)                             silent wrong -> clear error
    edof Config read_noise -0.01                                     silent wrong -> clear error
    edof Config photons 0                                            silent wrong -> clear error
    edof Config read_noise 0.01 (control)                            ok           -> ok
    benchmarks --lenses over a foreign throughput.json               vague error  -> clear error
    benchmarks full run over a foreign throughput.json               silent wrong -> clear error
    benchmarks over a throughput.json that is not JSON               silent wrong -> clear error
    benchmarks over a pareto result named throughput.json            silent wrong -> clear error
    benchmarks over a smoke throughput.json (control: starts)        ok           -> ok
    OddAsphere coeffs NaN                                            clear error  -> clear error
    OddAsphere coeffs 2-D                                            clear error  -> clear error
    Plane semi_diameter -5                                           clear error  -> clear error
    Stop semi_diameter NaN                                           clear error  -> clear error
    Conic k NaN                                                      clear error  -> clear error
    Hybrid odd_y 2-D                                                 clear error  -> clear error
    TiltedPlane tan_x inf                                            clear error  -> clear error
    XYPolynomial norm_radius 0                                       clear error  -> clear error
    ZernikeSag ordering 'nol'                                        clear error  -> clear error
    ZernikeSag decenter_x NaN                                        clear error  -> clear error
    Binary2 norm_radius -5                                           clear error  -> clear error
    Binary2 order 1.5 (control: Zemax takes a real order)            ok           -> ok
    evaluate_design min_valid 99 (percent)                           clear error  -> clear error
    evaluate_design min_valid -0.1                                   clear error  -> clear error
    evaluate_design n 10**6                                          clear error  -> clear error
    trace_path upto 99                                               clear error  -> clear error
    trace_path uniform 'no' (control: the same rays either way)      ok           -> ok
    trace uniform 'no' (control: the same rays either way)           ok           -> ok
    trace_backward upto -9                                           clear error  -> clear error
    opd reference 'chef'                                             clear error  -> clear error
    opd wavelength in nm                                             clear error  -> clear error
    opd pupil shape (3,)                                             clear error  -> clear error
    opd_fan n 10**9                                                  clear error  -> clear error
    opd_fan n 0                                                      clear error  -> clear error
    LevenbergMarquardt rtol -1                                       clear error  -> clear error
    LevenbergMarquardt atol NaN                                      clear error  -> clear error
    LevenbergMarquardt inner 0                                       clear error  -> clear error
    DampedLeastSquares lam0 -0.01                                    clear error  -> clear error
    reversed_lens image_distance NaN                                 clear error  -> clear error
    catalog_names catalog 'schot'                                    clear error  -> clear error
    catalog_names obsolete 'no'                                      clear error  -> clear error
    sensor_field_grid n 10**6                                        clear error  -> clear error
    sensor_field_grid n 0                                            clear error  -> clear error
    radius_for_fraction fraction 80 (percent)                        clear error  -> clear error
    radius_for_fraction fraction 0                                   clear error  -> clear error
    radius_for_fraction fraction NaN                                 clear error  -> clear error
    radius_for_fraction 0.8 (control)                                ok           -> ok
    zernike_nm j 0 (Noll starts at 1)                                clear error  -> clear error
    zernike_nm j 2.5                                                 clear error  -> clear error
    zernike_nm indexing 'nol'                                        clear error  -> clear error
    random_params dtype int32                                        clear error  -> clear error
    TableMaterials wavelengths in nm                                 clear error  -> clear error
    glass_info 'N-BK77'                                              clear error  -> clear error
    reweighting_mask threshold 80 (percent)                          clear error  -> clear error
    run warmup 5 (percent)                                           silent wrong -> clear error
    run end_lr 5 (percent)                                           silent wrong -> clear error
    run epoch 0                                                      silent wrong -> clear error
    run log_every 0                                                  silent wrong -> clear error
    run irls 'no'                                                    silent wrong -> clear error
    run reg_weights of 2                                             silent wrong -> clear error
    run callback 'print'                                             silent wrong -> clear error
    run defaults (control: starts)                                   ok           -> ok
    reweighting_mask threshold 0.8 (control)                         ok           -> ok
    lens file thickness '3,25' (comma decimal)                       clear error  -> clear error
    lens file radius '22,01'                                         clear error  -> clear error
    lens file thickness NaN (JSON NaN)                               clear error  -> clear error
    lens file thickness Infinity                                     clear error  -> clear error
    lens file radius 0                                               clear error  -> clear error
    lens file surfaces []                                            clear error  -> clear error
    lens file fields []                                              clear error  -> clear error
    lens file wavelengths_nm []                                      clear error  -> clear error
    lens file epd 0.01 (control: F/5000, a pinhole, is a lens)       ok           -> ok
    lens file epd 0                                                  clear error  -> clear error
    lens file fnum 0.2 (control: rays past the surfaces are invalid) ok           -> ok
    lens file conic '-1' (control: a number in a string)             ok           -> ok
    lens file curvature and radius disagree                          clear error  -> clear error
    lens file material 'n-sk16' (control: case)                      ok           -> ok
    lens file stop_surface_index 9 of 8                              clear error  -> clear error
    lens file semi_diameter -3                                       clear error  -> clear error
    lens file two is_stop                                            clear error  -> clear error
    lens file object distance -50                                    clear error  -> clear error
    lens file no image surface (control: the same lens)              ok           -> ok
    lens file fields 2-D pairs of 3                                  clear error  -> clear error
    lens file even_asphere_coeffs a string                           clear error  -> clear error
    lens file as written (control)                                   ok           -> ok
    zmx CURV with a comma decimal                                    vague error  -> clear error
    zmx DISZ with a comma decimal                                    vague error  -> clear error
    zmx PARM value in the index column                               clear error  -> clear error
    zmx GLAS nd/vd columns swapped (warns)                           clear error  -> clear error
    zmx WAVM in nm                                                   clear error  -> clear error
    zmx YFLN in radians (warns)                                      clear error  -> clear error
    zmx ENPD 0                                                       clear error  -> clear error
    zmx cut after SURF 3                                             clear error  -> clear error
    zmx SURF 3 twice (SURF 4 renumbered)                             clear error  -> clear error
    zmx DISZ with two numbers                                        silent wrong -> clear error
    zmx CONI missing its value                                       clear error  -> clear error
    zmx CONI with two numbers                                        silent wrong -> clear error
    zmx ENPD with two numbers                                        silent wrong -> clear error
    load a .json with unknown_glass='model'                          silent wrong -> clear error
    load a folder                                                    vague error  -> clear error
    zmx as written (control)                                         ok           -> ok
    report --config 2 on a .json lens                                clear error  -> clear error
    report --list-configs on a .json lens                            clear error  -> clear error
    report --lenient on a .json lens                                 silent wrong -> clear error
    report --unknown-glass model on a .json lens                     silent wrong -> clear error
    report --config 0 on a .zmx                                      clear error  -> clear error
    report --overwrite without --plot                                clear error  -> clear error
    report a folder as the lens                                      vague error  -> clear error
    report --wavelengths 0.5876 0.5876                               clear error  -> clear error
    report --fields 0 0                                              silent wrong -> clear error
    report --fields nan                                              clear error  -> clear error
    classical --track 7000 (µm)                                      clear error  -> clear error
    classical --track 0.007 (m)                                      clear error  -> clear error
    classical --stop 7 of 6 elements                                 clear error  -> clear error
    classical --fov-start 100 (above --fov)                          clear error  -> clear error
    classical --fnum-start 1.5 (faster than --fnum)                  clear error  -> clear error
    classical --materials PMMA,PMMA,... (one glass)                  clear error  -> clear error
    classical --population 0                                         clear error  -> clear error
    classical --tolerance-aware -1                                   clear error  -> clear error
    classical --steps 0                                              clear error  -> clear error
    classical --polish-steps -1                                      clear error  -> clear error
    classical --devices 0                                            clear error  -> clear error
    classical --asphere-terms 100                                    clear error  -> clear error
    tolerance --tilt 0.0175 (1° in radians; control: allowed)        ok           -> ok
    tolerance --tilt 60 (arcmin)                                     clear error  -> clear error
    tolerance --seed -1                                              clear error  -> clear error
    tolerance --trials 0                                             clear error  -> clear error
    tolerance a folder as the design                                 clear error  -> clear error
    tolerance --out a file                                           clear error  -> clear error
    edof --steps2 -1                                                 clear error  -> clear error
    edof --w-sim -0.1                                                clear error  -> clear error
    edof --w-raw nan                                                 clear error  -> clear error
    edof --lr-lens 0                                                 clear error  -> clear error
    edof --lr-net 10 (control: no upper bound)                       ok           -> ok
    edof --max-crops 0                                               clear error  -> clear error
    edof --tile 33                                                   clear error  -> clear error
    edof --train-dir a missing folder                                clear error  -> clear error
    edof --hybrid-floor 50 (percent)                                 clear error  -> clear error
    edof --photons 2000 --read-noise 0.002 (control)                 ok           -> ok
    render_speed --patch 1000 (frame 512)                            silent wrong -> clear error
    render_speed --size 0                                            clear error  -> clear error
    render_memory --cap-gib 8000 (MiB)                               clear error  -> clear error
    render_memory --patch 0                                          clear error  -> clear error
    vjp_probe --check --json FILE (json ignored)                     silent wrong -> clear error
    vjp_probe --fusions --repeats 3 (repeats ignored)                silent wrong -> clear error
    vjp_probe --chunk 0                                              clear error  -> clear error
    vjp_probe --chunk 4096 4096                                      silent wrong -> clear error
    design_step --tag ../x                                           silent wrong -> clear error
    design_step --out-dir a file                                     clear error  -> clear error
    fast_path --repeats 0                                            clear error  -> clear error
    vjp_probe --fusions --lens cellphone6 (lens ignored)             silent wrong -> clear error
    vjp_probe --check --fusions                                      silent wrong -> clear error
    vjp_probe --repeats 3 --json FILE (control: starts)              ok           -> ok
    render_memory --patch 200 (the 128-pixel runs)                   silent wrong -> clear error
    render_speed --patch 64 (control: starts)                        ok           -> ok
    design_step --tag new_rule (control: starts)                     ok           -> ok
Run: PYTHONPATH=$PWD python tools/audit30_probe.py [filter]
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
    SEED0,
    TMP,
    edof_check,
    mention_counts,
    patched,
    probe,
    run,
    started,
    until_started,
    warned,
)

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import zoo  # noqa: E402


def count_mentions(top=120):
    """The exported names named least in every probe and test file (round 29 included)."""
    mention_counts(lambda f: "30" in f, top)


# ----------------------------------------------------------------------------- leftovers
def leftovers():
    from jaxlens.experiments.edof.train import Config
    probe("edof Config read_noise 4 (electrons)", lambda: Config(read_noise=4.0), "read_noise", "electrons")
    probe("edof Config read_noise -0.01", lambda: Config(read_noise=-0.01), "read_noise")
    probe("edof Config photons 0", lambda: Config(photons=0.0), "photons")
    probe("edof Config read_noise 0.01 (control)", lambda: Config(read_noise=0.01).read_noise, good=True)

    import benchmarks.common as BC
    import benchmarks.run as BR

    def folder(name, text):
        d = os.path.join(TMP, name)
        os.makedirs(d)
        pathlib.Path(d, "throughput.json").write_text(text)
        return d
    bench = lambda *a: patched(BC, ["machine_info"], lambda: BR.main(list(a)))
    d1 = folder("bt1", json.dumps({"my": "numbers"}))
    probe("benchmarks --lenses over a foreign throughput.json", bench("--only", "throughput", "--lenses", "cooke_triplet", "--out", d1), "not a throughput benchmark result")
    probe("benchmarks full run over a foreign throughput.json", bench("--only", "throughput", "--out", d1), "not a throughput benchmark result")
    d2 = folder("bt2", "my notes, not JSON\n")
    probe("benchmarks over a throughput.json that is not JSON", bench("--only", "throughput", "--out", d2), "not JSON")
    d3 = folder("bt3", json.dumps({"benchmark": "pareto", "command": "python -m benchmarks"}))
    probe("benchmarks over a pareto result named throughput.json", bench("--only", "throughput", "--out", d3), "pareto")
    d4 = folder("bt4", json.dumps({"benchmark": "throughput", "command": "python -m benchmarks --smoke"}))
    probe("benchmarks over a smoke throughput.json (control: starts)", bench("--only", "throughput", "--out", d4), good=True)


# ----------------------------------------------------------------------------- least-named names
def least_named():
    lens = zoo.cooke_triplet()
    spec = D.DesignSpec()
    probe("OddAsphere coeffs NaN", lambda: jl.OddAsphere(c=0.01, coeffs=[0.0, np.nan]), "coeffs")
    probe("OddAsphere coeffs 2-D", lambda: jl.OddAsphere(c=0.01, coeffs=[[0.0, 1e-5]]), "coeffs")
    probe("Plane semi_diameter -5", lambda: jl.Plane(semi_diameter=-5.0), "semi_diameter")
    probe("Stop semi_diameter NaN", lambda: jl.Stop(semi_diameter=np.nan), "semi_diameter")
    probe("Conic k NaN", lambda: jl.Conic(0.01, np.nan), "k")
    probe("Hybrid odd_y 2-D", lambda: jl.Hybrid(c=0.01, odd_y=[[1e-4, 0.0]]), "odd_y")
    probe("TiltedPlane tan_x inf", lambda: jl.TiltedPlane(tan_x=np.inf), "tan_x")
    probe("XYPolynomial norm_radius 0", lambda: jl.XYPolynomial(c=0.01, coeffs=[0.0, 1e-3], norm_radius=0.0), "norm_radius")
    probe("ZernikeSag ordering 'nol'", lambda: jl.ZernikeSag(c=0.01, zernike=[0.0, 1e-3], norm_radius=5.0, ordering="nol"), "ordering")
    probe("ZernikeSag decenter_x NaN", lambda: jl.ZernikeSag(c=0.01, zernike=[0.0, 1e-3], norm_radius=5.0, decenter_x=np.nan), "decenter_x")
    probe("Binary2 norm_radius -5", lambda: jl.Binary2(c=0.01, phase_coeffs=[1.0], norm_radius=-5.0), "norm_radius")
    probe("Binary2 order 1.5 (control: Zemax takes a real order)", lambda: float(jl.Binary2(c=0.01, phase_coeffs=[1.0], norm_radius=5.0, order=1.5).order), good=True)
    probe("evaluate_design min_valid 99 (percent)", lambda: D.evaluate_design(lens, spec, n=2, min_valid=99.0).valid, "min_valid")
    probe("evaluate_design min_valid -0.1", lambda: D.evaluate_design(lens, spec, n=2, min_valid=-0.1).valid, "min_valid")
    probe("evaluate_design n 10**6", lambda: D.evaluate_design(lens, spec, n=10**6).valid, "n")
    rays = jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(3))
    probe("trace_path upto 99", lambda: jl.trace_path(lens, rays, upto=99).origin.shape, "upto")
    # A control here; refused since round 32a (a switch takes True or False only).
    probe("trace_path uniform 'no' (refused since round 32a)", lambda: jl.trace_path(lens, rays, uniform="no").origin.shape, "uniform")
    probe("trace uniform 'no' (refused since round 32a)", lambda: jl.trace(lens, rays, uniform="no").origin.shape, "uniform")
    probe("trace_backward upto -9", lambda: jl.trace_backward(lens, rays, upto=-9).origin.shape, "upto")
    pupil = jnp.array([[0.0, 0.5]])
    probe("opd reference 'chef'", lambda: A.opd(lens, 0.0, pupil, reference="chef"), "reference", "sphere")
    probe("opd wavelength in nm", lambda: A.opd(lens, 0.0, pupil, wavelength=587.6), "nm")
    probe("opd pupil shape (3,)", lambda: A.opd(lens, 0.0, jnp.zeros(3)), "pupil")
    probe("opd_fan n 10**9", lambda: A.opd_fan(lens, 0.0, n=10**9).tangential.shape, "n")
    probe("opd_fan n 0", lambda: A.opd_fan(lens, 0.0, n=0).tangential.shape, "n")
    probe("LevenbergMarquardt rtol -1", lambda: D.LevenbergMarquardt(lambda p: p, rtol=-1.0), "rtol")
    probe("LevenbergMarquardt atol NaN", lambda: D.LevenbergMarquardt(lambda p: p, atol=np.nan), "atol")
    probe("LevenbergMarquardt inner 0", lambda: D.LevenbergMarquardt(lambda p: p, inner=0), "inner")
    probe("DampedLeastSquares lam0 -0.01", lambda: D.DampedLeastSquares(lambda p: p, lam0=-0.01), "lam0")
    probe("reversed_lens image_distance NaN", lambda: jl.tracing.reversed_lens(lens, image_distance=np.nan).thickness, "image_distance")
    probe("catalog_names catalog 'schot'", lambda: jl.catalog_names("schot")[:3], "SCHOTT")
    probe("catalog_names obsolete 'no'", lambda: len(jl.catalog_names("SCHOTT", obsolete="no")), "obsolete")
    probe("sensor_field_grid n 10**6", lambda: D.sensor_field_grid(spec, n=10**6)[0].shape, "n")
    probe("sensor_field_grid n 0", lambda: D.sensor_field_grid(spec, n=0)[0].shape, "n")
    probe("radius_for_fraction fraction 80 (percent)", lambda: A.radius_for_fraction(lens, 0.0, 80.0), "fraction")
    probe("radius_for_fraction fraction 0", lambda: A.radius_for_fraction(lens, 0.0, 0.0), "fraction")
    probe("radius_for_fraction fraction NaN", lambda: A.radius_for_fraction(lens, 0.0, np.nan), "fraction")
    probe("radius_for_fraction 0.8 (control)", lambda: A.radius_for_fraction(lens, 0.0, 0.8), good=True)
    probe("zernike_nm j 0 (Noll starts at 1)", lambda: A.zernike_nm(0), "j")
    probe("zernike_nm j 2.5", lambda: A.zernike_nm(2.5), "j")
    probe("zernike_nm indexing 'nol'", lambda: A.zernike_nm(3, indexing="nol"), "indexing")
    probe("random_params dtype int32", lambda: D.random_params(spec, jax.random.PRNGKey(0), dtype=jnp.int32).c.dtype, "dtype")
    probe("TableMaterials wavelengths in nm", lambda: D.TableMaterials(wavelengths=[486.1, 587.6, 656.3]), "nm")
    probe("glass_info 'N-BK77'", lambda: jl.glass_info("N-BK77"), "N-BK7")
    probe("reweighting_mask threshold 80 (percent)", lambda: D.reweighting_mask(jnp.ones((1, 3)), threshold=80.0), "threshold")
    import types
    stage = D.Stage("x", fov=40.0, fnum=4.0, steps=10)
    fake = types.SimpleNamespace(c=jnp.zeros((1, 3)))  # run reads only c's dtype and shape first
    obj = types.SimpleNamespace(sampling=types.SimpleNamespace(area=jnp.ones(3)))
    crun = lambda **kw: until_started(lambda: D.run(spec, [stage], fake, obj, started, progress=False, **kw))
    probe("run warmup 5 (percent)", crun(warmup=5.0), "warmup", "fraction")
    probe("run end_lr 5 (percent)", crun(end_lr=5.0), "end_lr", "fraction")
    probe("run epoch 0", crun(epoch=0), "epoch")
    probe("run log_every 0", crun(log_every=0), "log_every")
    probe("run irls 'no'", crun(irls="no"), "irls")
    probe("run reg_weights of 2", crun(reg_weights=(40.0, 1000.0)), "reg_weights")
    probe("run callback 'print'", crun(callback="print"), "callback")
    probe("run defaults (control: starts)", crun(), good=True)
    probe("reweighting_mask threshold 0.8 (control)", lambda: D.reweighting_mask(jnp.ones((1, 3)), threshold=0.8), good=True)


# ----------------------------------------------------------------------------- JSON lens files
def write_load(text, ext=".json", **kw):
    def go():
        path = os.path.join(TMP, f"lens{len(os.listdir(TMP))}{ext}")
        with open(path, "w") as f:
            f.write(text)
        return jl.load(path, **kw)
    return go


def lens_files():
    with open(COOKE) as f:
        base = json.load(f)

    def lf(edit=None, raw=None):
        d = json.loads(json.dumps(base))
        if raw is None:
            edit(d)
        return write_load(raw if raw is not None else json.dumps(d))
    s1 = lambda d: d["surfaces"][1]
    probe("lens file thickness '3,25' (comma decimal)", lf(lambda d: s1(d).update(thickness="3,25896")), "thickness")
    probe("lens file radius '22,01'", lf(lambda d: s1(d).update(radius="22,01359")), "radius")
    probe("lens file thickness NaN (JSON NaN)", lf(raw=json.dumps(base).replace('"thickness": 3.25896', '"thickness": NaN')), "thickness")
    probe("lens file thickness Infinity", lf(raw=json.dumps(base).replace('"thickness": 3.25896', '"thickness": Infinity')), "thickness")
    probe("lens file radius 0", lf(lambda d: s1(d).update(radius=0.0)), "radius")
    probe("lens file surfaces []", lf(lambda d: d.update(surfaces=[])), "surfaces")
    probe("lens file fields []", lf(lambda d: d["fields"].update(values=[])), "fields")
    probe("lens file wavelengths_nm []", lf(lambda d: (d.pop("primary_wavelength_nm"), d.update(wavelengths_nm=[]))), "wavelength")
    probe("lens file epd 0.01 (control: F/5000, a pinhole, is a lens)", lf(lambda d: d.update(aperture={"epd": 0.01})), good=True)
    probe("lens file epd 0", lf(lambda d: d.update(aperture={"epd": 0.0})), "epd")
    probe("lens file fnum 0.2 (control: rays past the surfaces are invalid)", lf(lambda d: d.update(aperture={"fnum": 0.2})), good=True)
    probe("lens file conic '-1' (control: a number in a string)", lf(lambda d: s1(d).update(conic="-1")), good=True)
    probe("lens file curvature and radius disagree", lf(lambda d: s1(d).update(curvature=1 / 20.0)), "curvature")
    probe("lens file material 'n-sk16' (control: case)", lf(lambda d: s1(d).update(material="n-sk16")), good=True)
    probe("lens file stop_surface_index 9 of 8", lf(lambda d: (d["surfaces"][4].pop("is_stop"), d.update(stop_surface_index=9))), "stop")
    probe("lens file semi_diameter -3", lf(lambda d: s1(d).update(semi_diameter=-3.0)), "semi_diameter")
    probe("lens file two is_stop", lf(lambda d: s1(d).update(is_stop=True)), "stop")
    probe("lens file object distance -50", lf(lambda d: d["surfaces"][0].update(thickness=-50.0)), "object distance")
    probe("lens file no image surface (control: the same lens)", lf(lambda d: d["surfaces"].pop()), good=True)
    probe("lens file fields 2-D pairs of 3", lf(lambda d: d["fields"].update(values=[[0.0, 0.0, 0.0], [0.0, 14.0, 0.0]])), "fields")
    probe("lens file even_asphere_coeffs a string", lf(lambda d: s1(d).update(even_asphere_coeffs="0, 1e-5")), "even_asphere_coeffs")
    probe("lens file as written (control)", lf(lambda d: None), good=True)


def zmx_text(**edits):
    with open(SEED0) as f:
        text = f.read()
    for old, new in edits.items():
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def zmx_files():
    with open(SEED0) as f:
        text = f.read()
    z = lambda old, new: write_load(text.replace(old, new, 1), ".zmx")
    cut = text.index("SURF 3")
    probe("zmx CURV with a comma decimal", z("CURV 2.971822823221517E-001", "CURV 2,971822823221517E-001"), ":39:", "decimal comma")
    probe("zmx DISZ with a comma decimal", z("DISZ 8.059597441026024E-001", "DISZ 8,059597441026024E-001"), ":48:", "decimal comma")
    probe("zmx PARM value in the index column", z("PARM 2 9.622381685046057E-003", "PARM 9.622381685046057E-003 2"), ":42:", "PARM index")
    probe("zmx GLAS nd/vd columns swapped (warns)", warned(z("GLAS E48R 0 0 1.53117 5.6E+001", "GLAS E48R 0 0 5.6E+001 1.53117")), "nd 56", "catalog")
    probe("zmx WAVM in nm", z("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E+002 1"), "WAVM")
    probe("zmx YFLN in radians (warns)", warned(z("YFLN 0 1.01E+001 2.02E+001 3.0299999999999997E+001 4.04E+001", "YFLN 0 0.1745 0.3491 0.5236 0.6981")), "radians")
    probe("zmx ENPD 0", z("ENPD 2.2501173880645875E+000", "ENPD 0"), "ENPD")
    probe("zmx cut after SURF 3", write_load(text[:cut + len("SURF 3\n")], ".zmx"), "SURF 3")
    probe("zmx SURF 3 twice (SURF 4 renumbered)", z("SURF 4\n", "SURF 3\n"), "SURF")
    probe("zmx DISZ with two numbers", z("DISZ 8.059597441026024E-001", "DISZ 0.8 0.06"), ":48:", "DISZ takes one value")
    probe("zmx CONI missing its value", z("CONI -4.849999999999994E+000", "CONI"), ":40:", "conic")
    probe("zmx CONI with two numbers", z("CONI -4.849999999999994E+000", "CONI -4.85 0.5"), ":40:", "CONI takes one value")
    probe("zmx ENPD with two numbers", z("ENPD 2.2501173880645875E+000", "ENPD 2 25"), ":12:", "ENPD takes one value")
    probe("load a .json with unknown_glass='model'", lambda: jl.load(COOKE, unknown_glass="model"), "unknown_glass", ".json")
    probe("load a folder", lambda: jl.load(TMP), "is a folder")
    probe("zmx as written (control)", write_load(text, ".zmx"), good=True)


# ----------------------------------------------------------------------------- command lines
def command_lines():
    from jaxlens.__main__ import main as jaxlens_main
    from jaxlens.experiments import classical as C
    from jaxlens.experiments import tolerance as TOL

    def cli(fn):
        fn.cli = True
        return fn
    real = (C.run_design, TOL.analyse_design)
    C.run_design, TOL.analyse_design = started, started
    try:
        report = lambda *a: until_started(cli(lambda: jaxlens_main(["report", *a])))
        probe("report --config 2 on a .json lens", report(COOKE, "--config", "2"), "config")
        probe("report --list-configs on a .json lens", report(COOKE, "--list-configs"), "--list-configs")
        probe("report --lenient on a .json lens", report(COOKE, "--lenient", "--json"), "--lenient")
        probe("report --unknown-glass model on a .json lens", report(COOKE, "--unknown-glass", "model", "--json"), "unknown_glass", ".json")
        probe("report --config 0 on a .zmx", report(SEED0, "--config", "0"), "--config")
        probe("report --overwrite without --plot", report(COOKE, "--overwrite", "--json"), "--overwrite")
        probe("report a folder as the lens", report(TMP), "is a folder")
        probe("report --wavelengths 0.5876 0.5876", report(COOKE, "--wavelengths", "0.5876", "0.5876", "--json"), "--wavelengths")
        probe("report --fields 0 0", report(COOKE, "--fields", "0", "0", "--json"), "--fields")
        probe("report --fields nan", report(COOKE, "--fields", "nan"), "--fields")
        classical = lambda *a: until_started(cli(lambda: C.main(["--out", os.path.join(TMP, f"c{len(os.listdir(TMP))}"), *a])))
        probe("classical --track 7000 (µm)", classical("--track", "7000"), "--track")
        probe("classical --track 0.007 (m)", classical("--track", "0.007"), "--track")
        probe("classical --stop 7 of 6 elements", classical("--stop", "7"), "--stop")
        probe("classical --fov-start 100 (above --fov)", classical("--fov-start", "100"), "--fov-start")
        probe("classical --fnum-start 1.5 (faster than --fnum)", classical("--fnum-start", "1.5"), "--fnum-start")
        probe("classical --materials PMMA,PMMA,... (one glass)", classical("--materials", "PMMA"), "--materials")
        probe("classical --population 0", classical("--population", "0"), "--population")
        probe("classical --tolerance-aware -1", classical("--tolerance-aware", "-1"), "--tolerance-aware")
        probe("classical --steps 0", classical("--steps", "0"), "--steps")
        probe("classical --polish-steps -1", classical("--polish-steps", "-1"), "--polish-steps")
        probe("classical --devices 0", classical("--devices", "0"), "--devices")
        probe("classical --asphere-terms 100", classical("--asphere-terms", "100"), "--asphere-terms")
        tol = lambda *a: until_started(cli(lambda: TOL.main([SEED0, "--out", os.path.join(TMP, f"t{len(os.listdir(TMP))}"), *a])))
        probe("tolerance --tilt 0.0175 (1° in radians; control: allowed)", tol("--tilt", "0.0175"), good=True)
        probe("tolerance --tilt 60 (arcmin)", tol("--tilt", "60"), "--tilt")
        probe("tolerance --seed -1", tol("--seed", "-1"), "--seed")
        probe("tolerance --trials 0", tol("--trials", "0"), "--trials")
        probe("tolerance a folder as the design", until_started(cli(lambda: TOL.main([TMP, "--out", os.path.join(TMP, "t_dir")]))), "design")
        probe("tolerance --out a file", until_started(cli(lambda: TOL.main([SEED0, "--out", COOKE]))), "--out")
    finally:
        C.run_design, TOL.analyse_design = real


def edof_cli():
    check = edof_check
    probe("edof --steps2 -1", check("--steps2", "-1"), "--steps2")
    probe("edof --w-sim -0.1", check("--w-sim", "-0.1"), "--w-sim")
    probe("edof --w-raw nan", check("--w-raw", "nan"), "--w-raw")
    probe("edof --lr-lens 0", check("--lr-lens", "0"), "--lr-lens")
    probe("edof --lr-net 10 (control: no upper bound)", check("--lr-net", "10"), good=True)
    probe("edof --max-crops 0", check("--max-crops", "0"), "--max-crops")
    probe("edof --tile 33", check("--tile", "33"), "--tile")
    probe("edof --train-dir a missing folder", check("--train-dir", os.path.join(TMP, "nope")), "--train-dir")
    probe("edof --hybrid-floor 50 (percent)", check("--hybrid-floor", "50"), "--hybrid-floor")
    probe("edof --photons 2000 --read-noise 0.002 (control)", check("--photons", "2000", "--read-noise", "0.002"), good=True)


def bench_modules():
    import benchmarks.common as BC
    import benchmarks.design_step as DS
    import benchmarks.fast_path as FP
    import benchmarks.render_memory as RM
    import benchmarks.render_speed as RS
    import benchmarks.vjp_probe as VJ

    m = lambda mod, names, *a: patched(mod, names, lambda: mod.main(list(a)))
    probe("render_speed --patch 1000 (frame 512)", patched(BC, ["machine_info"], lambda: RS.main(["--patch", "1000", "--out", os.path.join(TMP, "rs.json")])), "--patch")
    probe("render_speed --size 0", patched(BC, ["machine_info"], lambda: RS.main(["--size", "0"])), "--size")
    probe("render_memory --cap-gib 8000 (MiB)", patched(RM, ["run_isolated"], lambda: RM.main(["--cap-gib", "8000"])), "--cap-gib")
    probe("render_memory --patch 0", patched(RM, ["run_isolated"], lambda: RM.main(["--patch", "0"])), "--patch")
    probe("vjp_probe --check --json FILE (json ignored)", m(VJ, ["check", "count_fusions", "timing"], "--check", "--json", os.path.join(TMP, "v.json")), "--json")
    probe("vjp_probe --fusions --repeats 3 (repeats ignored)", m(VJ, ["check", "count_fusions", "timing"], "--fusions", "--repeats", "3"), "--repeats")
    probe("vjp_probe --chunk 0", m(VJ, ["check", "count_fusions", "timing"], "--chunk", "0"), "--chunk")
    probe("vjp_probe --chunk 4096 4096", m(VJ, ["check", "count_fusions", "timing"], "--chunk", "4096", "4096"), "--chunk")
    probe("design_step --tag ../x", m(DS, ["import_baseline"], "--tag", "../x"), "--tag")
    probe("design_step --out-dir a file", m(DS, ["import_baseline"], "--out-dir", COOKE), "--out-dir")
    probe("fast_path --repeats 0", m(FP, ["import_baseline"], "--repeats", "0"), "--repeats")
    probe("vjp_probe --fusions --lens cellphone6 (lens ignored)", m(VJ, ["check", "count_fusions", "timing"], "--fusions", "--lens", "cellphone6"), "--lens")
    probe("vjp_probe --check --fusions", m(VJ, ["check", "count_fusions", "timing"], "--check", "--fusions"), "--check")
    probe("vjp_probe --repeats 3 --json FILE (control: starts)", m(VJ, ["check", "count_fusions", "timing"], "--repeats", "3", "--json", os.path.join(TMP, "v.json")), good=True)
    probe("render_memory --patch 200 (the 128-pixel runs)", patched(RM, ["run_isolated"], lambda: RM.main(["--patch", "200"])), "--patch", "128")
    probe("render_speed --patch 64 (control: starts)", patched(BC, ["machine_info"], lambda: RS.main(["--out", os.path.join(TMP, "rs.json")])), good=True)
    probe("design_step --tag new_rule (control: starts)", m(DS, ["import_baseline"], "--tag", "new_rule"), good=True)


if os.environ.get("AUDIT30_COUNT"):
    count_mentions()
else:
    run([leftovers, least_named, lens_files, zmx_files, command_lines, edof_cli, bench_modules])
