# ruff: noqa: E501, B023, E731
"""Round-29 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for two leftovers of earlier rounds, the public names and parameters that the
probe and test files name least after round 28, the command lines and the JSON lens format.

The count (``count_mentions`` of tools/audit27_probe.py, rerun on main at 6bf2daf with every
probe and test file counted, rounds 27 and 28 included; ``AUDIT29_COUNT=1`` here prints it):
after the result containers (``ParaxialData``, ``RmsSpot``, ``DesignResult``…, 0-2) and the
names rounds 26-28 probed come ``Aperture`` (13; ``half_x``/``half_y`` 0), ``field_curvature``
(14), ``parameterization`` (15), ``EvenAsphere``/``random_params`` (16), ``Biconic`` (17),
``chief_ray``/``ImageObjective`` (18), ``spot_rays``/``random_starts`` (19; ``seeds`` 1),
``angular_magnification`` (20), ``ray_fan`` (22), ``QTypeAsphere``/``Standard`` (23),
``load_agf``/``sine_path`` (24), ``paraxial_data`` (25), ``Grating`` (26),
``clear_semi_diameters`` (27; ``reaching`` 2), ``marechal_strehl`` (29; ``rms_waves`` 0),
``seidel`` (30), ``paper_stages`` (31), ``angular_spot``/``bfl``/``wavefront`` (34-35),
``self_intersection`` (37; ``n_angle`` 3), ``Stage``, ``zernike_terms``/``zernike_fit``,
``CoordinateBreak`` (``tilt_y``/``tilt_z`` 1), ``save`` (``options`` 0),
``encircled_energy`` (``radii`` 0) and ``DesignConfig`` (``curriculum_n``, ``lr_a``,
``epoch``, ``log_every``, ``float64`` 1 each). Nearly all were guarded (the controls).

Gaps found and fixed:
1. (leftover) ``field_curvature`` given fields in radians traced them as 0.2° and 0.35° without
   a word, while ``Lens`` warns (``checks.warn_if_radian_fields``); so did ``ray_fan`` and the
   analyses of jaxlens/analysis/spots.py (``rms_spot``, ``distortion``, ``chief_ray``…). They
   warn now, as ``Lens`` does (a warning: 0.1745° may be meant).
2. (leftover) ``cubic_strength_guess`` (and ``dioptric_weights``) took depths in mm as m:
   (150, 300) gave a = 0.00543 mm⁻² for (0.15, 0.3) m's 0.00181, a plate 3× too strong (the
   paper's depths in mm happened to give nearly its own 0.00543: 0.1 m and infinity defocus
   alike from a 0.2 m focus). A nearest depth beyond 50 m is refused, naming mm.
3. ``python -m benchmarks --out DIR`` ended by writing its summary over ``DIR/README.md``,
   whatever that was (``--out .`` in the repository replaced the project's README). Refused
   before the first benchmark unless that README is a benchmark summary. ``--only``,
   ``--lenses`` and ``--counts`` given a name twice ran the benchmark twice, or gave a lens or
   ray count two table rows: refused.
4. ``DesignSpec(bfl=0.0005)`` (0.5 mm written in m; the classical CLI's ``--bfl 0.0005``)
   designed a lens 0.5 µm off the sensor: a clearance below 0.01 mm is refused, naming m.
5. ``python -m jaxlens.experiments.edof --read-noise 4`` (read noise in electrons; the option
   is a standard deviation in linear values, 0.002 = 4 e⁻ at 2000 photo-electrons) trained on
   noise twice the full signal: above 0.5 it is refused, with the value in linear units.
   ``--kernel 1001`` (binning 2: a 512-pixel frame) went on to PSF kernels wider than the
   frame: a kernel wider than the frame is refused.
6. A JSON lens file with a wavelength repeated (a copy-paste slip: it weighs twice in every
   polychromatic figure) was read, and one with both ``wavelengths_um`` and
   ``wavelengths_nm`` read the first and ignored the other: both named with the file, the
   repeat as a warning (changed in review: Zemax takes a repeat, and such a lens must load
   back from its own JSON), the two keys refused.

Controls of note: the JSON lens format already named a misspelled key (with the close
match), a duplicate key, nm in ``wavelengths_um`` and µm in ``wavelengths_nm``, a field past
90° and a radius written "22mm"; ``spot_rays`` takes pupil points outside the unit disc on
purpose (an overfilled beam, as the ray sources do); ``report --wavelengths`` reads each value
above 100 as nm (documented), so a mixed list is read right.

Before (main at 6bf2daf, an archive) and after (branch audit29), the same probes,
``PYTHONPATH=<tree> python tools/audit29_probe.py``, 103 probes, about a minute each way:
    before: clear error: 74, ok: 11, silent wrong: 18
    after:  clear error: 92, ok: 11

A row marked "(warns)" counts a warning as the answer ("clear error" when it names the
slip); a command-line row "silent wrong" with "started" passed every check and began its work
(the probe stops it there: the design, the analysis, the first benchmark).

Probe (before -> after):
    field_curvature fields in radians (warns)                      silent wrong -> clear error
    ray_fan field in radians (warns)                               silent wrong -> clear error
    rms_spot fields in radians (warns)                             silent wrong -> clear error
    distortion fields in radians (warns)                           silent wrong -> clear error
    field_curvature fields in degrees (control)                    ok           -> ok
    field_curvature fields 0.1, 0.5 deg (control: no warning)      ok           -> ok
    field_curvature traced radians under jit (not checked)         ok           -> ok
    cubic_strength_guess depths (150, 300) in mm                   silent wrong -> clear error
    cubic_strength_guess paper depths in mm                        silent wrong -> clear error
    dioptric_weights depths in mm                                  silent wrong -> clear error
    cubic_strength_guess (0.15, 0.3) m (control)                   ok           -> ok
    cubic_strength_guess far depths (0.2, 40) m (control)          ok           -> ok
    Aperture half_x negative                                       clear error  -> clear error
    Aperture shape 'rectangel'                                     clear error  -> clear error
    Aperture blocks 'no'                                           clear error  -> clear error
    EvenAsphere coeffs 2-D                                         clear error  -> clear error
    QTypeAsphere qtype 'qcon2'                                     clear error  -> clear error
    Grating lines_per_um 600 (lines/mm)                            clear error  -> clear error
    CoordinateBreak tilt_y NaN                                     clear error  -> clear error
    CoordinateBreak tilt_z '5'                                     clear error  -> clear error
    chief_ray wavelength in nm                                     clear error  -> clear error
    angular_magnification wavelength in nm                         clear error  -> clear error
    paraxial_data wavelength in nm                                 clear error  -> clear error
    bfl wavelength 0                                               clear error  -> clear error
    spot_rays pupil (2, 0) (control: overfilled beams are allowed) ok           -> ok
    clear_semi_diameters n_rim 10**9                               clear error  -> clear error
    clear_semi_diameters reaching 80                               clear error  -> clear error
    marechal_strehl rms_waves -0.05                                clear error  -> clear error
    wavefront grid 10**6                                           clear error  -> clear error
    self_intersection n_angle 10**9                                clear error  -> clear error
    self_intersection 2 semi_diameters for 6                       clear error  -> clear error
    zernike_terms terms 10**6                                      clear error  -> clear error
    zernike_fit 4 values for 3 points                              clear error  -> clear error
    encircled_energy radii NaN                                     clear error  -> clear error
    parameterization dtype int32                                   clear error  -> clear error
    random_starts seeds 1.5                                        clear error  -> clear error
    sine_path start NaN                                            clear error  -> clear error
    paper_stages steps -5                                          clear error  -> clear error
    Stage fov 200                                                  clear error  -> clear error
    DesignConfig epoch 0                                           clear error  -> clear error
    DesignConfig float64 'no'                                      clear error  -> clear error
    DesignConfig rings 10**6                                       clear error  -> clear error
    register_catalog name ''                                       clear error  -> clear error
    save options to .json                                          clear error  -> clear error
    DesignSpec bfl 0.0005 (0.5 mm in m)                            silent wrong -> clear error
    DesignSpec bfl 0.05 (control)                                  ok           -> ok
    lens file key 'radus'                                          clear error  -> clear error
    lens file key 'conic_constant'                                 clear error  -> clear error
    lens file 'epd' twice                                          clear error  -> clear error
    lens file wavelengths_um in nm                                 clear error  -> clear error
    lens file wavelengths_nm in µm                                 clear error  -> clear error
    lens file field 95 deg                                         clear error  -> clear error
    lens file fields in radians (warns)                            clear error  -> clear error
    lens file radius '22mm'                                        clear error  -> clear error
    lens file is_stop 'yes'                                        clear error  -> clear error
    lens file material 'N-SK61'                                    clear error  -> clear error
    lens file sensor pixel_size 5 (µm)                             clear error  -> clear error
    lens file sensor 10**6 × 10**6 pixels                          clear error  -> clear error
    lens file fields.type 'angle_rad'                              clear error  -> clear error
    lens file cut short                                            clear error  -> clear error
    lens file a wavelength repeated (warns)                        silent wrong -> clear error
    lens file wavelengths_um and wavelengths_nm                    silent wrong -> clear error
    lens file model glass nd/vd swapped                            clear error  -> clear error
    lens file n table keys in µm                                   clear error  -> clear error
    lens file obscuration [3, 1] (swapped)                         clear error  -> clear error
    lens file primary 3 of 3                                       clear error  -> clear error
    lens file units 'm'                                            clear error  -> clear error
    lens file coordinate_break 'tilt_x' (no _deg)                  clear error  -> clear error
    lens file vignetting 2 vdy for 3 fields                        clear error  -> clear error
    lens file semi_diameter past the sphere                        clear error  -> clear error
    lens file as written (control)                                 ok           -> ok
    classical --bfl 0.0005 (0.5 mm in m)                           silent wrong -> clear error
    classical --fov 1.4 (radians)                                  clear error  -> clear error
    classical --sensor-diagonal 7660 (µm)                          clear error  -> clear error
    classical --tolerance-threshold 0.007 (mm)                     clear error  -> clear error
    classical --out a lens file                                    clear error  -> clear error
    report --fields in radians (warns)                             clear error  -> clear error
    report --fields 95                                             clear error  -> clear error
    report --wavelengths 5876 (Å)                                  clear error  -> clear error
    report --plot a file                                           clear error  -> clear error
    tolerance --threshold 0.007 (mm)                               clear error  -> clear error
    tolerance --decenter 5 (µm)                                    clear error  -> clear error
    tolerance --trials 10**9                                       clear error  -> clear error
    benchmarks --out a folder with its own README.md               silent wrong -> clear error
    benchmarks --only pareto pareto                                silent wrong -> clear error
    benchmarks --counts 1000 1000                                  silent wrong -> clear error
    benchmarks --lenses cooke_triplet twice                        silent wrong -> clear error
    benchmarks --counts 0                                          clear error  -> clear error
    benchmarks --tag ../x                                          clear error  -> clear error
    benchmarks --out an earlier results folder (control: starts)   ok           -> ok
    edof --read-noise 4 (electrons)                                silent wrong -> clear error
    edof --read-noise 2                                            silent wrong -> clear error
    edof --read-noise 0.002 (control)                              ok           -> ok
    edof --kernel 1001 (the frame is 512 pixels)                   silent wrong -> clear error
    edof --kernel 255 --binning 4 (256-pixel frame; control)       ok           -> ok
    edof --kernel 100001                                           clear error  -> clear error
    edof --kernel 30                                               clear error  -> clear error
    edof --photons 0                                               clear error  -> clear error
    edof --cubic-floor 50 (percent)                                clear error  -> clear error
    edof --time-limit -5                                           clear error  -> clear error
    edof --seeds 0,0                                               clear error  -> clear error
    edof --lenses hybird                                           clear error  -> clear error
    edof --decoder nafnet --live-front-end                         clear error  -> clear error

Run: PYTHONPATH=$PWD python tools/audit29_probe.py [filter]
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
    ROOT,
    SEED0,
    TMP,
    edof_check,
    mention_counts,
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


def count_mentions(top=60):
    """The exported names named least in every probe and test file (rounds 27 and 28
    included), with their parameters' counts (``name=``)."""
    mention_counts(lambda f: "29" in f, top)


# ----------------------------------------------------------------------------- leftovers
def leftovers():
    lens = zoo.cooke_triplet()
    rad = [0.0, 0.2443, 0.3491]  # np.radians([0, 14, 20])
    probe("field_curvature fields in radians (warns)", warned(lambda: A.field_curvature(lens, rad)), "radians", "deg")
    probe("ray_fan field in radians (warns)", warned(lambda: A.ray_fan(lens, 0.3491)), "radians", "field")
    probe("rms_spot fields in radians (warns)", warned(lambda: A.rms_spot(lens, rad)), "radians")
    probe("distortion fields in radians (warns)", warned(lambda: A.distortion(lens, rad)), "radians")
    probe("field_curvature fields in degrees (control)", warned(lambda: A.field_curvature(lens, [0.0, 14.0, 20.0])), good=True)
    probe("field_curvature fields 0.1, 0.5 deg (control: no warning)", warned(lambda: A.field_curvature(lens, [0.1, 0.5])), good=True)
    probe("field_curvature traced radians under jit (not checked)", lambda: jax.jit(lambda f: A.field_curvature(lens, f).tangential)(jnp.array(rad)).shape, good=True)

    from jaxlens.experiments.edof import lenses as L
    ed = L.classical_lens(binning=8)
    probe("cubic_strength_guess depths (150, 300) in mm", lambda: L.cubic_strength_guess(ed, depths_m=[150.0, 300.0]), "depths_m", "mm")
    probe("cubic_strength_guess paper depths in mm", lambda: L.cubic_strength_guess(ed, depths_m=[1e3 * d for d in L.DEPTHS_M]), "depths_m", "mm")
    probe("dioptric_weights depths in mm", lambda: L.dioptric_weights([1e3 * d for d in L.DEPTHS_M]), "depths_m", "mm")
    probe("cubic_strength_guess (0.15, 0.3) m (control)", lambda: L.cubic_strength_guess(ed, depths_m=[0.15, 0.3]), good=True)
    probe("cubic_strength_guess far depths (0.2, 40) m (control)", lambda: L.cubic_strength_guess(ed, depths_m=[0.2, 40.0]), good=True)


# ----------------------------------------------------------------------------- least-named names
def least_named():
    lens = zoo.cooke_triplet()
    probe("Aperture half_x negative", lambda: jl.Aperture("rect", half_x=-1.0, half_y=2.0), "half_x")
    probe("Aperture shape 'rectangel'", lambda: jl.Aperture("rectangel", half_x=1.0, half_y=2.0), "rect")
    probe("Aperture blocks 'no'", lambda: jl.Aperture("rect", half_x=1.0, half_y=2.0, blocks="no"), "blocks")
    probe("EvenAsphere coeffs 2-D", lambda: jl.EvenAsphere(c=0.01, coeffs=[[0.0, 1e-5]]), "coeffs")
    probe("QTypeAsphere qtype 'qcon2'", lambda: jl.QTypeAsphere(c=0.01, coeffs=[1e-3], norm_radius=5.0, qtype="qcon2"), "qtype")
    probe("Grating lines_per_um 600 (lines/mm)", lambda: jl.Grating(lines_per_um=600.0), "lines_per_um")
    probe("CoordinateBreak tilt_y NaN", lambda: jl.CoordinateBreak(tilt_y=np.nan), "tilt_y")
    probe("CoordinateBreak tilt_z '5'", lambda: jl.CoordinateBreak(tilt_z="5"), "tilt_z")
    probe("chief_ray wavelength in nm", lambda: A.chief_ray(lens, 10.0, 587.6), "587.6 nm")
    probe("angular_magnification wavelength in nm", lambda: A.angular_magnification(lens, 587.6), "nm")
    probe("paraxial_data wavelength in nm", lambda: jl.paraxial_data(lens, 587.6), "nm")
    probe("bfl wavelength 0", lambda: jl.bfl(lens, 0.0), "wavelength")
    # A control here; refused since round 32a (a spot's pupil is the beam; field_rays and
    # trace take overfilled points).
    probe("spot_rays pupil (2, 0) (refused since round 32a)", lambda: A.spot_rays(lens, 0.0, 0.5876, pupil=jnp.array([[2.0, 0.0]])).valid.shape, "unit disc")
    probe("clear_semi_diameters n_rim 10**9", lambda: A.clear_semi_diameters(lens, n_rim=10**9), "n_rim")
    probe("clear_semi_diameters reaching 80", lambda: A.clear_semi_diameters(lens, reaching=80), "reaching")
    probe("marechal_strehl rms_waves -0.05", lambda: A.marechal_strehl(-0.05), "rms_waves")
    probe("wavefront grid 10**6", lambda: A.wavefront(lens, 0.0, grid=10**6), "grid")
    probe("self_intersection n_angle 10**9", lambda: A.self_intersection(lens, n_angle=10**9), "n_angle")
    probe("self_intersection 2 semi_diameters for 6", lambda: A.self_intersection(lens, semi_diameters=[1.0, 2.0]), "semi_diameters")
    probe("zernike_terms terms 10**6", lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(3), terms=10**6), "terms")
    probe("zernike_fit 4 values for 3 points", lambda: A.zernike_fit(jnp.zeros(3), jnp.zeros(3), jnp.zeros(4), terms=3), "values")
    probe("encircled_energy radii NaN", lambda: A.encircled_energy(lens, 0.0, jnp.array([np.nan])), "radii")
    spec = D.DesignSpec()
    probe("parameterization dtype int32", lambda: D.parameterization(spec, dtype=jnp.int32), "dtype")
    probe("random_starts seeds 1.5", lambda: D.random_starts(spec, 1.5), "seeds")
    probe("sine_path start NaN", lambda: D.sine_path(np.nan, 2.0, 5), "start")
    probe("paper_stages steps -5", lambda: D.paper_stages(spec, steps=-5), "steps")
    probe("Stage fov 200", lambda: D.Stage("x", fov=200.0, fnum=4.0, steps=10), "fov")
    probe("DesignConfig epoch 0", lambda: D.DesignConfig(epoch=0), "epoch")
    probe("DesignConfig float64 'no'", lambda: D.DesignConfig(float64="no"), "float64")
    probe("DesignConfig rings 10**6", lambda: D.DesignConfig(rings=10**6), "rings")
    probe("register_catalog name ''", lambda: jl.register_catalog(os.path.join(ROOT, "jaxlens", "data"), name=""), "name")
    probe("save options to .json", lambda: jl.save(lens, os.path.join(TMP, "x.json"), options={"indent": 2}), "options")
    probe("DesignSpec bfl 0.0005 (0.5 mm in m)", lambda: D.DesignSpec(bfl=0.0005), "bfl", "in m")
    probe("DesignSpec bfl 0.05 (control)", lambda: D.DesignSpec(bfl=0.05).bfl, good=True)


# ----------------------------------------------------------------------------- JSON lens files
def lens_files():
    with open(COOKE) as f:
        base = json.load(f)

    def lf(edit=None, raw=None):
        def go():
            path = os.path.join(TMP, f"lens{len(os.listdir(TMP))}.json")
            if raw is None:
                d = json.loads(json.dumps(base))
                edit(d)
                text = json.dumps(d)
            else:
                text = raw
            with open(path, "w") as f:
                f.write(text)
            return jl.load(path)
        return go
    s1 = lambda d: d["surfaces"][1]
    probe("lens file key 'radus'", lf(lambda d: s1(d).update(radus=s1(d).pop("radius"))), "radus", "radius")
    probe("lens file key 'conic_constant'", lf(lambda d: s1(d).update(conic_constant=-1.0)), "conic_constant", "conic")
    probe("lens file 'epd' twice", lf(raw=json.dumps(base).replace('"epd": 10.0', '"epd": 10.0, "epd": 20.0')), "epd", "twice")
    probe("lens file wavelengths_um in nm", lf(lambda d: d.update(wavelengths_um=d.pop("wavelengths_nm"))), "wavelength")
    probe("lens file wavelengths_nm in µm", lf(lambda d: d.update(wavelengths_nm=[0.486, 0.5876, 0.6563], primary_wavelength_nm=0.5876)), "wavelengths_nm", "µm")
    probe("lens file field 95 deg", lf(lambda d: d["fields"].update(values=[0.0, 14.0, 95.0])), "95", "deg")
    probe("lens file fields in radians (warns)", warned(lf(lambda d: d["fields"].update(values=[0.0, 0.2443, 0.3491]))), "radians")
    probe("lens file radius '22mm'", lf(lambda d: s1(d).update(radius="22mm")), "radius", "22mm")
    probe("lens file is_stop 'yes'", lf(lambda d: d["surfaces"][4].update(is_stop="yes")), "is_stop")
    probe("lens file material 'N-SK61'", lf(lambda d: s1(d).update(material="N-SK61")), "N-SK16")
    probe("lens file sensor pixel_size 5 (µm)", lf(lambda d: d.update(sensor={"resolution": [480, 640], "pixel_size": 5.0})), "pixel_size", "µm")
    probe("lens file sensor 10**6 × 10**6 pixels", lf(lambda d: d.update(sensor={"resolution": [10**6, 10**6], "pixel_size": 0.005})), "resolution")
    probe("lens file fields.type 'angle_rad'", lf(lambda d: d["fields"].update(type="angle_rad")), "fields.type")
    probe("lens file cut short", lf(raw=json.dumps(base)[:-40]), ":1:")
    probe("lens file a wavelength repeated (warns)", warned(lf(lambda d: d.update(wavelengths_nm=[587.5618, 587.5618, 656.2725]))), "twice")
    probe("lens file wavelengths_um and wavelengths_nm", lf(lambda d: (d.pop("primary_wavelength_nm"), d.update(wavelengths_um=[0.5876]))), "wavelengths_um", "wavelengths_nm")
    probe("lens file model glass nd/vd swapped", lf(lambda d: s1(d).update(material={"nd": 64.17, "vd": 1.5168})), "swapped")
    probe("lens file n table keys in µm", lf(lambda d: s1(d).update(material={"n": {"0.4861": 1.52, "0.5876": 1.517, "0.6563": 1.514}})), "µm")
    probe("lens file obscuration [3, 1] (swapped)", lf(lambda d: s1(d).update(obscuration=[3.0, 1.0])), "obscuration", "r_min < r_max")
    probe("lens file primary 3 of 3", lf(lambda d: (d.pop("primary_wavelength_nm"), d.update(primary=3))), "primary", "0..2")
    probe("lens file units 'm'", lf(lambda d: d.update(units="m")), "units.length")
    probe("lens file coordinate_break 'tilt_x' (no _deg)", lf(lambda d: d["surfaces"].insert(2, {"type": "coordinate_break", "tilt_x": 5.0, "thickness": 0})), "tilt_x_deg")
    probe("lens file vignetting 2 vdy for 3 fields", lf(lambda d: d["fields"].update(vignetting={"vdy": [0.0, 0.1]})), "vdy")
    probe("lens file semi_diameter past the sphere", lf(lambda d: s1(d).update(semi_diameter=30.0)), "defined only out to")
    probe("lens file as written (control)", lf(lambda d: None), good=True)


# ----------------------------------------------------------------------------- command lines
def command_lines():
    import benchmarks.common as BC
    import benchmarks.run as BR
    from jaxlens.__main__ import main as jaxlens_main
    from jaxlens.experiments import classical as C
    from jaxlens.experiments import tolerance as TOL

    real = (C.run_design, TOL.analyse_design, BC.machine_info)
    C.run_design, TOL.analyse_design, BC.machine_info = started, started, started
    try:
        def cli(fn):
            fn.cli = True
            return until_started(fn)
        classical = lambda *a: cli(lambda: C.main(["--out", os.path.join(TMP, f"c{len(os.listdir(TMP))}"), *a]))
        probe("classical --bfl 0.0005 (0.5 mm in m)", classical("--bfl", "0.0005"), "--bfl", "in m")
        probe("classical --fov 1.4 (radians)", classical("--fov", "1.4"), "--fov")
        probe("classical --sensor-diagonal 7660 (µm)", classical("--sensor-diagonal", "7660"), "--sensor-diagonal")
        probe("classical --tolerance-threshold 0.007 (mm)", classical("--tolerance-threshold", "0.007"), "mm")
        probe("classical --out a lens file", cli(lambda: C.main(["--out", COOKE])), "--out")
        report = lambda *a: cli(lambda: jaxlens_main(["report", *a]))
        probe("report --fields in radians (warns)", warned(report(COOKE, "--fields", "0.2443", "0.3491")), "radians")
        probe("report --fields 95", report(COOKE, "--fields", "95"), "--fields")
        probe("report --wavelengths 5876 (Å)", report(COOKE, "--wavelengths", "5876"), "--wavelengths")
        probe("report --plot a file", report(COOKE, "--plot", COOKE), "--plot")
        tol = lambda *a: cli(lambda: TOL.main([SEED0, "--out", os.path.join(TMP, f"t{len(os.listdir(TMP))}"), *a]))
        probe("tolerance --threshold 0.007 (mm)", tol("--threshold", "0.007"), "mm")
        probe("tolerance --decenter 5 (µm)", tol("--decenter", "5"), "--decenter")
        probe("tolerance --trials 10**9", tol("--trials", "1000000000"), "--trials")

        bench = lambda *a: until_started(lambda: BR.main(list(a)))
        mine = os.path.join(TMP, "project")
        os.makedirs(mine)
        pathlib.Path(mine, "README.md").write_text("# My project\n")
        probe("benchmarks --out a folder with its own README.md", bench("--smoke", "--only", "skipping", "--out", mine), "README.md")
        probe("benchmarks --only pareto pareto", bench("--smoke", "--only", "pareto", "pareto", "--out", os.path.join(TMP, "b1")), "--only", "pareto")
        probe("benchmarks --counts 1000 1000", bench("--smoke", "--counts", "1000", "1000", "--out", os.path.join(TMP, "b2")), "--counts", "1000")
        probe("benchmarks --lenses cooke_triplet twice", bench("--smoke", "--lenses", "cooke_triplet", "cooke_triplet", "--out", os.path.join(TMP, "b3")), "--lenses")
        probe("benchmarks --counts 0", bench("--counts", "0"), "--counts")
        probe("benchmarks --tag ../x", bench("--tag", "../x"), "--tag")
        ours = os.path.join(TMP, "b4")
        os.makedirs(ours)
        pathlib.Path(ours, "README.md").write_text("# jaxlens benchmark results\n")
        probe("benchmarks --out an earlier results folder (control: starts)", bench("--smoke", "--only", "skipping", "--out", ours), good=True)
    finally:
        C.run_design, TOL.analyse_design, BC.machine_info = real


def edof_cli():
    check = edof_check
    probe("edof --read-noise 4 (electrons)", check("--read-noise", "4"), "--read-noise", "electrons")
    probe("edof --read-noise 2", check("--read-noise", "2"), "--read-noise")
    probe("edof --read-noise 0.002 (control)", check("--read-noise", "0.002"), good=True)
    probe("edof --kernel 1001 (the frame is 512 pixels)", check("--kernel", "1001"), "--kernel", "512")
    probe("edof --kernel 255 --binning 4 (256-pixel frame; control)", check("--kernel", "255", "--binning", "4"), good=True)
    probe("edof --kernel 100001", check("--kernel", "100001"), "--kernel")
    probe("edof --kernel 30", check("--kernel", "30"), "--kernel", "odd")
    probe("edof --photons 0", check("--photons", "0"), "--photons")
    probe("edof --cubic-floor 50 (percent)", check("--cubic-floor", "50"), "--cubic-floor")
    probe("edof --time-limit -5", check("--time-limit", "-5"), "--time-limit")
    probe("edof --seeds 0,0", check("--seeds", "0,0"), "--seeds")
    probe("edof --lenses hybird", check("--lenses", "hybird"), "--lenses")
    probe("edof --decoder nafnet --live-front-end", check("--decoder", "nafnet", "--live-front-end"), "--live-front-end")


if os.environ.get("AUDIT29_COUNT"):
    count_mentions()
else:
    run([leftovers, least_named, lens_files, command_lines, edof_cli])
