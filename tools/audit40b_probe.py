# ruff: noqa: E501, E731
"""Round-40b bad-input probes: the recent features (object-space telecentric lenses
``Lens(object_na=...)``, virtual objects, afocal image space, ``travel_senses`` folds,
multi-configuration ``.zmx`` files) given wrong types, NaN/inf, zero or negative sizes, empty
or misshapen arrays, wavelengths in nm, fields beyond 90°; the writers' missing folder; the
encircled-energy building blocks called directly; the real stop size of a virtual object;
``ImageObjective``'s sensor and scene; the report's refusal of a telecentric lens (and each
analysis it names instead, run as a control). The table of ``tools/probe_table.py`` (probe |
outcome | what happened).

Gaps found and fixed (one mechanism each):
1. A missing output folder: ``save`` raised ``FileNotFoundError``, ``save_json``,
   ``save_zmx``, ``plot.save`` and the image writers ``ValueError``, with other words.
   ``json_values.output_file`` (every writer's check) now raises ``MissingFolderError``,
   both a ``FileNotFoundError`` and a ``ValueError``, with one message; ``save`` uses it.
2. ``encircled.energy_within`` and ``radius_holding`` (public, used by ``plot``) took their
   radii and fractions unchecked: a radius −0.01 or NaN gave an energy of 0, no radii an
   empty curve, a fraction 1.5 NaN and −0.2 a radius. The checks of ``encircled_energy`` and
   ``radius_for_fraction`` moved into helpers both entry points call.
3. ``sampling.stop_radius(lens, "real", object_z=...)``: a real marginal ray lost on its way
   to the stop (a virtual object point 5 mm behind the Cooke triplet's surface 1) gave NaN,
   and ``field_rays(..., depth=-5, aim="real_marginal")`` then returned every ray invalid
   without a word. A concrete call now raises, naming the surface and the paraxial sizing.
4. ``field_rays`` took a depth of shape [2] (a TypeError from ``jnp.concatenate``); its
   docstring now says what a negative depth is (a virtual object; the analyses refuse one).
5. ``ImageObjective`` took any ``sensor`` (a string, None) and a scene of another size than
   the sensor: both failed at the run's first step, inside the render's difference.
6. ``checks.values`` (the array check of most arguments) read a string as its number
   (``np.asarray("4", float)``): a telecentric lens's field '4' (``chief_ray``,
   ``rms_spot``, ``spot_rays``; b'4' too) and ``stop_radius``'s object_z '50' traced.
   Refused now as ``checks.number`` refuses one.
7. Telecentric lenses: ``telecentric.source`` (so ``field_rays``) took a negative depth,
   a virtual object ``Lens`` refuses for such a lens, and launched the rays after surface 1;
   and the one-field analyses (``psf``, ``mtf``, ``encircled_energy``, ``wavefront``,
   ``ray_fan``, ``opd_fan``) checked the field as an angle: NaN was refused as "angles in
   (-90, 90) deg", a height of 95 mm as 95°. ``telecentric.lens_field`` checks one field in
   the lens's own unit for all of them (and ``field_rays``); ``ToleranceModel`` checked
   its fields as angles too (a 95 mm height refused as 95°), and so did the layout's fans
   (``semi_diameters_and_fans``) and ``vignetting_for_fields``: ``telecentric.lens_fields``.
   The MTF's tangential direction (``otf.mtf_directions``, for ``mtf`` and the tolerance
   model's MTF) took heights as angles: (3, 4) mm along (0.5997, 0.8002), and 95 mm
   refused inside the Monte-Carlo trials; ``heights=True`` for such a lens.
8. Multi-configuration ``.zmx``: a malformed numeric row (``THIC 2 1 abc``, a value
   ``1e999``) of a configuration not read let ``load(config=2)`` open the file without a
   word. ``zmx_config`` parses every numeric row of every configuration first.
9. A lens whose own virtual object lies on its entrance pupil's plane: ``rms_spot`` and
   ``psf`` failed with an ``EquinoxRuntimeError`` from inside the compiled trace; refused by
   name in ``sampling.lens_depth`` before tracing.

Also (not counted): ``tools/audit36a_probe.py`` expected "2%" in the AGF Vd refusal; the
tolerance is ``agf.VD_TOLERANCE`` (1 %), which the probe now reads.

The controls (``[control]`` or ``good=True``) are behaviours judged right: the analyses the
report's refusal names for a telecentric lens (rms_spot, spot_rays, chief_ray, ray_fan,
opd_fan, wavefront, encircled_energy, psf, mtf) run on one; a virtual object's paraxial
data, spots and ``field_rays(depth=-50)``; an afocal lens's angular spot, wavefront and
report; a fold's spots; configuration 2 of the zoom file; the classical command's defaults.
Since round 42a the distortion and the report of a telecentric lens (which refused it here)
are controls too: they take its object heights (tests/test_telecentric_analyses_round42a.py).

Before (base b927019) and after (branch probe40b), the same 185 probes,
``PYTHONPATH=<tree> python tools/audit40b_probe.py`` from the tree's root, 1 to 4 minutes
each on 2 busy cores (the compile cache warm or not):
    before: clear error: 117, crash: 4, ok: 26, silent wrong: 21, vague error: 17
    after:  clear error: 157, ok: 28
"""

import copy
import dataclasses
import json
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, cli, fresh, jitted, module_cli, patched, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import analysis as A  # noqa: E402
from jaxlens import plot as P  # noqa: E402
from jaxlens.analysis import encircled as E  # noqa: E402
from jaxlens.analysis import report as REP  # noqa: E402
from jaxlens.imaging import psf as PSF  # noqa: E402
from jaxlens.imaging import sampling as S  # noqa: E402
from jaxlens.io import images as IM  # noqa: E402
from jaxlens.io import lensfile as LF  # noqa: E402
from jaxlens.io import zmx as ZMX  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data")
TELE = os.path.join(DATA, "zmx38a", "tele_doublet_obna.zmx")
KEPLER = os.path.join(DATA, "afocal_kepler.zmx")
ZOOM = os.path.join(DATA, "zmx_config", "zoom.zmx")
VIRT = os.path.join(DATA, "zmx_corpus7", "virtual_singlet_angles.zmx")

cooke = jl.load(COOKE)
tele = jl.load(TELE)
kepler = jl.load(KEPLER)
virt = jl.load(VIRT)
L = lambda lens, **k: dataclasses.replace(lens, **k)


def os_error(fn):
    """A missing folder's ``FileNotFoundError`` judged by its message as a ValueError is."""
    def go():
        try:
            return fn()
        except FileNotFoundError as e:
            if isinstance(e, ValueError):
                raise
            raise ValueError(f"FileNotFoundError (not a ValueError): {e}") from None
    return go


def value_error_only(fn):
    """The same missing-folder refusal must be a ValueError AND a FileNotFoundError."""
    def go():
        try:
            fn()
        except Exception as e:  # noqa: BLE001
            both = isinstance(e, ValueError) and isinstance(e, FileNotFoundError)
            raise ValueError(("both " if both else "one class only ") + str(e)) from None
        return "written"
    return go


def telecentric():
    na = tele.object_na
    probe("Lens object_na NaN", lambda: L(tele, object_na=float("nan")), "object_na")
    probe("Lens object_na -0.1", lambda: L(tele, object_na=-0.1), "object_na")
    probe("Lens object_na 0", lambda: L(tele, object_na=0.0), "object_na")
    probe("Lens object_na 1.5 (> n = 1 in air)", lambda: L(tele, object_na=1.5), "object_na")
    probe("Lens object_na '0.1'", lambda: L(tele, object_na="0.1"), "object_na")
    probe("Lens object_na [0.1, 0.2]", lambda: L(tele, object_na=np.array([0.1, 0.2])), "object_na")
    probe("Lens object_na with an object at infinity", lambda: L(tele, object_distance=np.inf), "object")
    probe("Lens object_na with a virtual object", lambda: L(tele, object_distance=-50.0), "virtual")
    probe("Lens object_na with aim 'real'", lambda: L(tele, aim="real"), "aim")
    probe("Lens object_na float16", lambda: L(tele, object_na=np.float16(0.15)), "object_na", "float16")
    probe("field_rays telecentric height NaN", lambda: S.field_rays(tele, float("nan"), S.pupil_polar(2)), "field")
    probe("field_rays telecentric height inf", lambda: S.field_rays(tele, float("inf"), S.pupil_polar(2)), "field")
    probe("field_rays telecentric heights [2, 3, 4] (3 values)", lambda: S.field_rays(tele, np.array([2.0, 3.0, 4.0]), S.pupil_polar(2)), "field")
    probe("field_rays telecentric depth -5", lambda: S.field_rays(tele, 4.0, S.pupil_polar(2), depth=-5.0), "depth")
    probe("field_rays telecentric depth inf", lambda: S.field_rays(tele, 4.0, S.pupil_polar(2), depth=np.inf), "depth")
    probe("field_rays telecentric wavelength 550 (nm)", lambda: S.field_rays(tele, 4.0, S.pupil_polar(2), 550.0), "wavelength")
    probe("rms_spot telecentric field NaN", lambda: A.rms_spot(tele, float("nan")), "field")
    probe("rms_spot telecentric depth 0", lambda: A.rms_spot(tele, 4.0, depth=0.0), "depth")
    probe("chief_ray telecentric field '4'", lambda: A.chief_ray(tele, "4"), "field")
    probe("psf telecentric pixel_size -0.01", lambda: PSF.psf(tele, 4.0, pixel_size=-0.01, kernel_size=15), "pixel_size")
    probe("psf telecentric kernel_size 0", lambda: PSF.psf(tele, 4.0, pixel_size=0.03, kernel_size=0), "kernel_size")
    probe("encircled_energy telecentric radii -1", lambda: A.encircled_energy(tele, 4.0, -1.0), "radii")
    probe("rms_spot telecentric field '4' (a string)", lambda: A.rms_spot(tele, "4"), "field")
    probe("spot_rays telecentric field b'4'", lambda: A.spot_rays(tele, b"4"), "field")
    probe("field_rays telecentric depth -5 under jit", jitted(lambda d: S.field_rays(tele, 4.0, S.pupil_polar(2), depth=d).origin, -5.0), "real object")
    probe("telecentric.source depth -5", lambda: jl.imaging.telecentric.source(tele, 4.0, S.pupil_polar(2), 0.55, -5.0), "virtual")
    probe("psf telecentric height 95 mm (beyond coverage, not an angle)", lambda: PSF.psf(tele, 95.0, pixel_size=0.1, kernel_size=31), "no ray")
    probe("mtf telecentric height 95 mm", lambda: PSF.mtf(tele, 95.0, kernel_size=32), "no ray", "95 mm")
    probe("wavefront telecentric height NaN", lambda: A.wavefront(tele, float("nan")), "field", "mm")
    probe("ray_fan telecentric heights [1, 2, 3]", lambda: A.ray_fan(tele, np.array([1.0, 2.0, 3.0])), "field", "height")
    probe("opd_fan telecentric height NaN", lambda: A.opd_fan(tele, float("nan")), "field", "mm")
    probe("encircled_energy telecentric height NaN", lambda: A.encircled_energy(tele, float("nan"), [0.5]), "field", "mm")
    probe("ToleranceModel telecentric fields [0, 95] mm (heights, not angles)", lambda: np.asarray(jl.tolerance.ToleranceModel(tele, fields=np.array([0.0, 95.0])).fields).tolist(), good=True)
    probe("ToleranceModel telecentric fields [NaN]", lambda: jl.tolerance.ToleranceModel(tele, fields=np.array([np.nan])), "fields", "mm")
    probe("semi_diameters_and_fans telecentric fan_fields NaN", lambda: A.spots.semi_diameters_and_fans(tele, np.array([0.0, np.nan]), np.zeros((3, 2))), "fan_fields", "mm")
    probe("semi_diameters_and_fans telecentric fan_fields [0, 95] mm (control)", lambda: np.asarray(A.spots.semi_diameters_and_fans(tele, np.array([0.0, 95.0]), np.zeros((3, 2)))[0]), good=True)
    probe("vignetting_for_fields telecentric fields inf", lambda: S.vignetting_for_fields(L(tele, vignetting=np.zeros((3, 5))), np.array([np.inf])), "fields", "mm")
    probe("entrance_pupil_z telecentric", lambda: jl.paraxial.entrance_pupil_z(tele), "telecentric")
    # Round 42a: distortion and the report take a telecentric lens's object heights (controls).
    probe("[control] distortion telecentric", lambda: A.distortion(tele).percent_ftan, good=True)
    probe("render telecentric", lambda: jl.render(tele, np.ones((8, 8, 3)), spp=4, key=jax.random.key(0), sensor=jl.Sensor((8, 8), 0.01)), "telecentric", "paraxial.magnification")
    probe("[control] report telecentric", lambda: REP.report_data(tele)["fields"], good=True)
    # What the report's refusal names instead, each run on the telecentric lens (controls).
    f = float(np.max(np.abs(np.asarray(tele.fields))))
    probe("[control] rms_spot telecentric", lambda: A.rms_spot(tele, f).polychromatic, good=True)
    probe("[control] spot_rays telecentric", lambda: A.spot_rays(tele, f).shape, good=True)
    probe("[control] chief_ray telecentric", lambda: A.chief_ray(tele, f).origin, good=True)
    probe("[control] ray_fan telecentric", lambda: A.ray_fan(tele, f).tangential.shape, good=True)
    probe("[control] opd_fan telecentric", lambda: A.opd_fan(tele, f).tangential.shape, good=True)
    probe("[control] wavefront telecentric", lambda: float(A.wavefront(tele, f).rms), good=True)
    probe("[control] encircled_energy telecentric", lambda: A.encircled_energy(tele, f, [0.01, 0.05]).energy, good=True)
    probe("[control] psf telecentric", lambda: float(jnp.sum(PSF.psf(tele, f, pixel_size=0.1, kernel_size=31))), good=True)
    probe("[control] mtf telecentric", lambda: jax.tree.map(np.shape, PSF.mtf(tele, f, kernel_size=32)), good=True)
    del na


def telecentric_files():
    text = open(TELE, encoding="utf-8", errors="replace").read()

    def zf(new):
        p = os.path.join(fresh("tz"), "t.zmx")
        with open(p, "w", encoding="utf-8") as fh:
            fh.write(new)
        return lambda: float(jl.load(p).object_na)

    line = next(ln for ln in text.splitlines() if ln.startswith("OBNA"))
    probe("zmx OBNA -0.15", zf(text.replace(line, line.replace("OBNA ", "OBNA -", 1))), "OBNA")
    probe("zmx OBNA 0", zf(text.replace(line, "OBNA 0 0")), "OBNA")
    probe("zmx OBNA 1.5", zf(text.replace(line, "OBNA 1.5 0")), "OBNA")
    probe("zmx OBNA abc", zf(text.replace(line, "OBNA abc 0")), "OBNA")
    d = LF.lens_to_dict(tele) if hasattr(LF, "lens_to_dict") else json.loads(LF.dumps(tele))

    def jf(mut):
        dd = copy.deepcopy(d)
        mut(dd)
        p = os.path.join(fresh("tj"), "t.json")
        with open(p, "w", encoding="utf-8") as fh:
            json.dump(dd, fh)
        return lambda: float(jl.load(p).object_na)

    key = "aperture"
    probe("json telecentric round trip (control)", jf(lambda dd: None), good=True)
    probe("json aperture object_na -0.1", jf(lambda dd: dd[key].update(object_na=-0.1)), "object_na")
    probe("json aperture object_na '0.1'", jf(lambda dd: dd[key].update(object_na="0.1")), "object_na")
    probe("json aperture object_na null", jf(lambda dd: dd[key].update(object_na=None)), "object_na")
    probe("json telecentric fields type angle", jf(lambda dd: dd["fields"].update(type="angle_deg_y")), "field")


def virtual():
    zep = float(jl.paraxial.entrance_pupil_z(cooke))
    probe("stop_radius real, virtual object 5 mm after surface 1 (marginal ray lost)", lambda: S.stop_radius(cooke, "real", object_z=5.0), "stop_radius", "surface", "paraxial")
    probe("stop_radius real, virtual object 50 mm after (control)", lambda: S.stop_radius(cooke, "real", object_z=50.0), good=True)
    probe("field_rays depth -5 aim real_marginal (every ray invalid)", lambda: S.field_rays(cooke, 10.0, S.pupil_polar(2), depth=-5.0, aim="real_marginal").valid, "marginal", "paraxial")
    probe("field_rays depth [-5, 5]", lambda: S.field_rays(cooke, 5.0, S.pupil_polar(2), depth=np.array([-5.0, 5.0])), "depth", "one")
    probe("field_rays depth on the pupil plane", lambda: S.field_rays(cooke, 5.0, S.pupil_polar(2), depth=-zep), "pupil")
    probe("field_rays depth -50 (control: a virtual object, documented)", lambda: S.field_rays(cooke, 5.0, S.pupil_polar(2), depth=-50.0).valid, good=True)
    probe("field_rays depth 0", lambda: S.field_rays(cooke, 5.0, S.pupil_polar(2), depth=0.0), "depth")
    probe("field_rays depth '100'", lambda: S.field_rays(cooke, 5.0, S.pupil_polar(2), depth="100"), "depth")
    probe("rms_spot depth -100 (an analysis: refused)", lambda: A.rms_spot(cooke, 5.0, depth=-100.0), "depth")
    probe("psf depth -100", lambda: PSF.psf(cooke, 5.0, pixel_size=0.005, kernel_size=15, depth=-100.0), "depth")
    probe("Lens object_distance -0.0", lambda: L(cooke, object_distance=-0.0), "object_distance")
    probe("Lens object_distance -1e12 (beyond infinity, negative)", lambda: L(cooke, object_distance=-1e12), "object_distance")
    probe("Lens object_distance on the entrance pupil", lambda: A.rms_spot(L(cooke, object_distance=-zep), 0.0).polychromatic, "pupil")
    probe("Lens object_distance on the entrance pupil, psf", lambda: PSF.psf(L(cooke, object_distance=-zep), 0.0, pixel_size=0.005, kernel_size=15), "pupil")
    probe("stop_radius object_z '50' (a string)", lambda: S.stop_radius(cooke, "real", object_z="50"), "object_z")
    probe("[control] virtual object paraxial_data", lambda: float(jl.paraxial_data(virt).efl), good=True)
    probe("[control] virtual object rms_spot (its own object)", lambda: A.rms_spot(virt, 0.0).polychromatic, good=True)
    probe("point_source virtual on the pupil plane", lambda: S.point_source(cooke, np.array([0.0, 0.0, zep]), S.pupil_polar(2)), "point")
    probe("object_point depth NaN", lambda: S.object_point(cooke, 5.0, float("nan")), "depth")


def afocal():
    probe("rms_spot afocal", lambda: A.rms_spot(kepler, 0.5), "afocal")
    probe("psf afocal", lambda: PSF.psf(kepler, 0.5, pixel_size=0.005, kernel_size=15), "afocal")
    probe("encircled_energy afocal", lambda: A.encircled_energy(kepler, 0.5, [0.01]), "afocal")
    probe("angular_spot afocal fields [95]", lambda: A.angular_spot(kepler, [95.0]), "field")
    probe("angular_spot afocal fields NaN", lambda: A.angular_spot(kepler, [float("nan")]), "field")
    probe("angular_spot afocal wavelengths [550] (nm)", lambda: A.angular_spot(kepler, wavelengths=[550.0]), "wavelength")
    probe("angular_spot afocal reference 'chef'", lambda: A.angular_spot(kepler, reference="chef"), "reference")
    probe("angular_spot afocal fields []", lambda: A.angular_spot(kepler, []), "field")
    probe("angular_spot afocal pupil [3]", lambda: A.angular_spot(kepler, pupil=np.zeros(3)), "pupil")
    probe("angular_magnification wavelength 550", lambda: A.angular_magnification(kepler, 550.0), "wavelength")
    probe("angular_magnification of a string", lambda: A.angular_magnification("kepler"), "lens")
    probe("Lens afocal_image 'yes'", lambda: L(kepler, afocal_image="yes"), "afocal_image")
    probe("[control] angular_spot afocal", lambda: A.angular_spot(kepler).polychromatic, good=True)
    probe("[control] wavefront afocal", lambda: float(A.wavefront(kepler, 0.5).rms), good=True)
    probe("report afocal (control: the afocal report)", lambda: type(REP.report_data(kepler)).__name__, good=True)


def folds():
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from test_input_probes_round24 import FOLD, QUADOA
    d = copy.deepcopy(FOLD)
    lens = LF.lens_from_dict(d)
    probe("Lens travel_senses of 3 for 7 media", lambda: L(lens, travel_senses=(1, 1, 1)), "travel_senses")
    probe("Lens travel_senses holding 2", lambda: L(lens, travel_senses=(1, 1, 1, 2, 1, 1, 1)), "travel_senses")
    probe("Lens travel_senses 'yes'", lambda: L(lens, travel_senses="yes"), "travel_senses")
    probe("Lens travel_senses holding 0", lambda: L(lens, travel_senses=(1, 1, 1, 0, 1, 1, 1)), "travel_senses")
    probe("Lens travel_senses floats (1.0, ...)", lambda: L(lens, travel_senses=tuple(float(x) for x in QUADOA)).travel_senses, "travel_senses")
    probe("Lens travel_senses disagreeing with the frames", lambda: L(lens, travel_senses=(1, 1, 1, -1, -1, -1, -1)), "travel_senses")
    probe("[control] fold rms_spot", lambda: A.rms_spot(lens, 0.0).polychromatic, good=True)
    dd = copy.deepcopy(FOLD)
    dd["travel_senses"] = [1, 1, "x", -1, 1, 1, 1]
    probe("json travel_senses holding 'x'", lambda: LF.lens_from_dict(dd), "travel_senses")
    de = copy.deepcopy(FOLD)
    de["travel_senses"] = []
    probe("json travel_senses []", lambda: LF.lens_from_dict(de), "travel_senses")


def configs():
    probe("load zoom config 0", lambda: jl.load(ZOOM, config=0), "config")
    probe("load zoom config 4 (of 3)", lambda: jl.load(ZOOM, config=4), "config", "3")
    probe("load zoom config -1", lambda: jl.load(ZOOM, config=-1), "config")
    probe("load zoom config 1.5", lambda: jl.load(ZOOM, config=1.5), "config")
    probe("load zoom config '2'", lambda: jl.load(ZOOM, config="2"), "config")
    probe("load zoom config True", lambda: jl.load(ZOOM, config=True), "config")
    probe("load json config 2", lambda: jl.load(COOKE, config=2), "config")
    probe("load single-configuration zmx config 2", lambda: jl.load(VIRT, config=2), "config")
    probe("[control] load zoom config 2", lambda: float(jl.efl(jl.load(ZOOM, config=2))), good=True)
    text = open(ZOOM, encoding="utf-8", errors="replace").read()

    def zf(new):
        p = os.path.join(fresh("cz"), "z.zmx")
        with open(p, "w", encoding="utf-8") as fh:
            fh.write(new)
        return lambda: float(jl.efl(jl.load(p, config=2)))

    thic = next(ln for ln in text.splitlines() if ln.startswith("THIC"))
    parts = thic.split()
    probe("zmx config THIC value abc in configuration 1, reading 2", zf(text.replace(thic, " ".join(parts[:3] + ["abc"] + parts[4:]))), "THIC")
    probe("zmx config THIC surface 99", zf(text.replace(thic, " ".join(parts[:1] + ["99"] + parts[2:]))), "THIC")
    probe("zmx config THIC config 9 (of 3)", zf(text.replace(thic, " ".join(parts[:2] + ["9"] + parts[3:]))), "THIC")
    probe("zmx config YFIE value 1e999 in configuration 3, reading 2", zf(text.replace("YFIE 2 3 3 ", "YFIE 2 3 1e999 ")), "YFIE")
    probe("zmx config WAVE value x in configuration 1, reading 2", zf(text.replace("WAVE 1 1 0.5875618 ", "WAVE 1 1 x ")), "WAVE")
    probe("zmx MNUM 0", zf(text.replace("MNUM 3 1", "MNUM 0 1")), "MNUM")
    probe("zmx MNUM 3 7 (active 7 of 3)", zf(text.replace("MNUM 3 1", "MNUM 3 7")), "MNUM")


def writers():
    d = fresh("w")
    miss = os.path.join(d, "nope")
    img = np.zeros((4, 4, 3), np.float32)
    for name, fn in (("save .json", lambda p: jl.save(cooke, p + ".json")),
                     ("save .zmx", lambda p: jl.save(cooke, p + ".zmx")),
                     ("save_json", lambda p: LF.save_json(cooke, p + ".json")),
                     ("save_zmx", lambda p: ZMX.save_zmx(cooke, p + ".zmx")),
                     ("plot.save", lambda p: P.save(P.plot_image(img), p + ".png")),
                     ("write_png", lambda p: IM.write_png(p + ".png", img))):
        probe(f"{name} into a missing folder (ValueError and FileNotFoundError)",
              value_error_only(lambda fn=fn: fn(os.path.join(miss, "a"))), "both", "no such folder", "nope")


def encircled():
    s = E.energy_samples(cooke, 0.0)
    probe("energy_within radius -0.01", lambda: E.energy_within(s, -0.01).energy, "radii", "mm")
    probe("energy_within radius NaN", lambda: E.energy_within(s, float("nan")).energy, "radii")
    probe("energy_within radii []", lambda: E.energy_within(s, []).energy, "radii")
    probe("energy_within radii 'a'", lambda: E.energy_within(s, "a").energy, "radii")
    probe("radius_holding fraction 1.5", lambda: E.radius_holding(s, 1.5), "fraction")
    probe("radius_holding fraction -0.2", lambda: E.radius_holding(s, -0.2), "fraction")
    probe("radius_holding fraction 80 (percent)", lambda: E.radius_holding(s, 80.0), "fraction")
    probe("[control] energy_within 1 mm", lambda: E.energy_within(s, 1.0).energy, good=True)
    probe("energy_samples method 'wave'", lambda: E.energy_samples(cooke, 0.0, method="wave"), "method")
    probe("radius_for_fraction fraction 0.8 in a list of 2 (control)", lambda: A.radius_for_fraction(cooke, 0.0, [0.5, 0.8]), good=True)


def image_objective():
    from jaxlens.design import DesignSpec, ImageObjective, RayLoss, parameterization
    from jaxlens.design.losses import Objective
    spec = DesignSpec()
    ray = Objective(parameterization(spec), RayLoss.make(3, 2, [0.5876], spec.sensor_size), jnp.ones((12, 2)))
    probe("ImageObjective scene 8x8 on a 4x4 sensor", lambda: ImageObjective(ray, jnp.ones((8, 8, 3)), jl.Sensor((4, 4), 0.01)), "scene", "resolution")
    probe("ImageObjective sensor 'abc'", lambda: ImageObjective(ray, jnp.ones((8, 8, 3)), "abc"), "sensor")
    probe("ImageObjective sensor None", lambda: ImageObjective(ray, jnp.ones((8, 8, 3)), None), "sensor")
    probe("[control] ImageObjective 8x8 on 8x8", lambda: ImageObjective(ray, jnp.ones((8, 8, 3)), jl.Sensor((8, 8), 0.01)).spp, good=True)


def general():
    probe("get_material 'NBK7' (close match)", lambda: jl.get_material("NBK7"), "N-BK7")
    probe("get_material 'N-BK7 ' trailing space (control)", lambda: jl.get_material("N-BK7 ").index(0.5876), good=True)
    probe("get_material 5", lambda: jl.get_material(5), "material")
    probe("glass_info 'SF-11'", lambda: jl.glass_info("SF-11"), "SF11")
    probe("Lens epd '10' (a string)", lambda: L(cooke, epd="10"), "epd")
    probe("image_height field '5'", lambda: jl.paraxial.image_height(cooke, "5"), "field")
    probe("diffraction_mtf nu '50'", lambda: jl.imaging.otf.diffraction_mtf("50", 0.00055, 4.0), "nu")
    probe("Sellmeier index at 550 (nm)", lambda: jl.get_material("N-BK7").index(550.0), "µm")
    probe("Lens wavelengths [486.1, 587.6, 656.3] (nm)", lambda: L(cooke, wavelengths=np.array([486.1, 587.6, 656.3])), "wavelength")
    probe("Lens fields [0, 95]", lambda: L(cooke, fields=np.array([0.0, 95.0])), "field")
    probe("Lens epd 0", lambda: L(cooke, epd=0.0), "epd")
    probe("Lens fields []", lambda: L(cooke, fields=np.zeros(0)), "field")
    probe("trace rays of a string", lambda: jl.trace(cooke, "rays"), "rays")
    probe("spot_rays field 95", lambda: A.spot_rays(cooke, 95.0), "field")
    probe("ray_fan field NaN", lambda: A.ray_fan(cooke, float("nan")), "field")
    probe("opd_fan n_points 0", lambda: A.opd_fan(cooke, 0.0, n_points=0), "n")
    probe("wavefront wavelength 0.0005876 (mm)", lambda: A.wavefront(cooke, 0.0, wavelength=0.0005876), "wavelength")
    probe("psf pixel_size 5 (µm)", lambda: PSF.psf(cooke, 0.0, pixel_size=5.0, kernel_size=15), "pixel_size")
    probe("distortion fields [[0, 1, 2]]", lambda: A.distortion(cooke, fields=np.array([[0.0, 1.0, 2.0]])), "field")
    probe("tolerance zero_perturbation of a string", lambda: jl.tolerance.zero_perturbation("cooke"), "lens")
    probe("render scene NaN", lambda: jl.render(cooke, np.full((8, 8, 3), np.nan), spp=4, key=jax.random.key(0), sensor=jl.Sensor((8, 8), 0.01)), "scene")
    probe("load a folder", lambda: jl.load(DATA), "folder")
    probe("load a .txt", lambda: jl.load(os.path.join(DATA, "x.txt")), ".txt")


def clis():
    cmd = module_cli

    probe("cli report telecentric file (control: round 42a)", cmd("report", TELE), good=True)
    probe("cli report config 0 of the zoom file", cmd("report", ZOOM, "--config", "0"), "config")
    probe("cli report --config 2 of a .json", cmd("report", COOKE, "--config", "2"), "config")
    probe("cli report --wavelengths 0.0005876 (mm)", cmd("report", COOKE, "--wavelengths", "0.0005876"), "wavelength")
    probe("cli report --fields 95", cmd("report", COOKE, "--fields", "95"), "field")
    probe("cli report a virtual object (control)", cmd("report", VIRT), good=True)
    probe("cli report --list-configs zoom (control)", cmd("report", ZOOM, "--list-configs"), good=True)
    probe("cli report a missing file", cmd("report", os.path.join(DATA, "nope.zmx")), "nope.zmx")


def classical_cli():
    from jaxlens.experiments import classical as C

    c = lambda *a: cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", fresh("c"), *a])))
    probe("classical --fov 200", c("--fov", "200"), "--fov")
    probe("classical --fov nan", c("--fov", "nan"), "--fov")
    probe("classical --fnum 0", c("--fnum", "0"), "--fnum")
    probe("classical --sensor-diagonal 43000 (µm)", c("--sensor-diagonal", "43000"), "--sensor-diagonal")
    probe("classical --elements 0", c("--elements", "0"), "--elements")
    probe("classical --elements 2.5", c("--elements", "2.5"), "--elements")
    probe("classical --materials NBK7,OKP4,E48R", c("--materials", "NBK7,OKP4,E48R", "--elements", "3"), "NBK7", "N-BK7")
    probe("classical --material-catalogs NOPE --select-materials continuous", c("--material-catalogs", "NOPE", "--select-materials", "continuous"), "NOPE")
    probe("classical --tolerance-threshold -1", c("--tolerance-threshold", "-1"), "--tolerance-threshold")
    probe("classical --seeds 0", c("--seeds", "0"), "--seeds")
    probe("classical --track -5", c("--track", "-5"), "--track")
    probe("classical --bfl inf", c("--bfl", "inf"), "--bfl")
    probe("classical --stop 9 (of 4 elements)", c("--stop", "9"), "--stop")
    probe("classical --asphere-terms -1", c("--asphere-terms", "-1"), "--asphere-terms")
    probe("classical --fov-start 90 --fov 60 (start beyond the goal)", c("--fov-start", "90", "--fov", "60"), "--fov-start")
    probe("classical defaults (control)", c(), good=True)


if __name__ == "__main__":
    run([telecentric, telecentric_files, virtual, afocal, folds, configs, writers, encircled,
         image_objective, general, clis, classical_cli])
