# ruff: noqa: E501, E731, B023
"""Round-41b bad-input probes (second pass): what rounds 38b and 40b left open and the parts
they did not reach: the command lines' argument parsing and early checks (``python -m
jaxlens report``, ``jaxlens.experiments.classical``, ``.tolerance``, ``.edof``; each run only
up to where its work would start, or refused), hand-written JSON lens files, the design API
(``DesignSpec``, ``Stage``, ``paper_stages``, the solvers, ``random_starts``), ``Sensor`` and
``render``'s arguments, and glass lookups. The table of ``tools/probe_table.py``.

Gaps found and fixed (one mechanism each):
1. A field no ray reaches: ``wavefront``, ``encircled_energy`` and ``radius_for_fraction``
   returned NaN (``psf`` and ``mtf`` refused it). ``jaxlens.imaging.light`` holds the one
   rule: the one-field analyses raise ``NoLightError`` (a ValueError; ``psf``'s refusal is one
   too now) naming the field and its unit (deg, or mm for a telecentric lens); the batch
   ``rms_spot`` keeps its documented NaN radius with valid_fraction 0 and warns
   (``NoLightWarning``) naming the dark fields.
2. ``Plane``/``Sphere``/``Conic``/``Stop``: their refusals said ``Standard:``; now the factory.
3. ``load``, ``load_json``, ``load_zmx``, ``configurations`` and ``load_agf`` of a missing file:
   Python's bare ``[Errno 2]``; now ``optics.input_files.input_file`` names the function and
   the path (still a ``FileNotFoundError``).
4. A JSON lens's ``travel_senses`` ``[1, 1, 'x']`` (or 0, 2, true) "disagreed with the frames";
   now "each +1 or -1".
5. ``field_rays(depth=0)`` was refused naming ``object_point``; now ``field_rays``.

6. ``design.init.template_lens`` (and ``gap_kinds``, ``gap_bounds``, ``normalisation_radii``)
   given a dict: an AttributeError; now a TypeError naming the function and DesignSpec.
7. ``design.spec.aperture_field_limits(0)``: ZeroDivisionError (-2 gave a negative limit);
   now checked as a whole number >= 1.

Judged right (controls, ``good=True``): ``report --wavelengths 587.6`` (documented: values
above 100 are nm), ``classical --tolerance-trials 0`` (documented: skips it),
``get_material("")`` (documented: air), a JSON ``"sphere"`` type (an accepted alias), a JSON
lens without an image surface (optional: a flat image), ``paper_stages(n=0)`` (n + 1 = 1
stage), a render scene above 1 (linear radiance, HDR allowed); a negative thickness in glass
is a warning already (``lensfile._warn_inside_out``).

Left open (the one "silent wrong" after): a JSON stop whose semi_diameter is smaller than the
paraxial axial beam (1 mm on the Cooke triplet, whose beam is 3.8 mm there) loads without a
word. A warning was tried and dropped: tests/data's optiland_lens2.zmx has a 6.75 mm stop under
a 7.5 mm beam, so what a fixed stop smaller than the EPD's beam means (Zemax floats it) needs
a decision first.

Run from the tree's root: ``PYTHONPATH=. python tools/audit41b_probe.py`` (a filter word as
the first argument keeps the probes whose names hold it); 3 to 5 minutes on 2 busy cores.
The same 208 probes, before (base 090c064) and after (branch probe41b):
    before: clear error: 164, crash: 2, ok: 13, silent wrong: 9, vague error: 20
    after:  clear error: 194, ok: 13, silent wrong: 1
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

import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, cli, edof_check, fresh, module_cli, patched, probe, run, warned  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.design.curriculum  # noqa: E402, F401
import jaxlens.design.evaluate  # noqa: E402, F401
from jaxlens import analysis as A  # noqa: E402
from jaxlens.imaging import sampling as S  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data")
TELE = os.path.join(DATA, "zmx38a", "tele_doublet_obna.zmx")
cooke = jl.load(COOKE)
tele = jl.load(TELE)
COOKE_DICT = json.load(open(COOKE, encoding="utf-8"))


def missing(fn):
    """A missing file's ``FileNotFoundError`` (its class kept) judged by its message."""
    def go():
        try:
            return fn()
        except FileNotFoundError as e:
            raise ValueError(f"FileNotFoundError: {e}") from None
    return go


def left_open():
    """What round 40b noticed and left open."""
    for lens, f, u in ((cooke, 60.0, "deg"), (tele, 95.0, "mm")):
        n = "cooke 60 deg" if lens is cooke else "tele 95 mm"
        probe(f"wavefront {n} (no ray reaches)", lambda: float(A.wavefront(lens, f).rms), "no ray", "wavefront", u)
        probe(f"encircled_energy {n}", lambda: A.encircled_energy(lens, f, [0.01]).energy, "no ray", "encircled_energy", u)
        probe(f"radius_for_fraction {n}", lambda: A.radius_for_fraction(lens, f, 0.8), "no ray", "radius_for_fraction", u)
        probe(f"rms_spot {n} (batch: NaN + a warning naming the field)", warned(lambda: A.rms_spot(lens, f).polychromatic), "no ray", "rms_spot", u)
        probe(f"psf {n}", lambda: jl.imaging.psf.psf(lens, f, pixel_size=0.01), "no ray", "psf")
    probe("[control] rms_spot cooke [0, 14] (no warning)", warned(lambda: A.rms_spot(cooke, np.array([0.0, 14.0])).polychromatic), good=True)
    probe("[control] wavefront cooke 14 deg", lambda: float(A.wavefront(cooke, 14.0).rms), good=True)
    probe("Plane(-1)", lambda: jl.Plane(-1.0), "Plane:", "semi_diameter", "mm")
    probe("Stop(nan)", lambda: jl.Stop(float("nan")), "Stop:", "semi_diameter")
    probe("Stop('5')", lambda: jl.Stop("5"), "Stop:", "semi_diameter")
    probe("Sphere(1/3, 5) (no sag beyond 3 mm)", lambda: jl.Sphere(1 / 3, 5.0), "Sphere:", "semi_diameter")
    probe("Conic(0.1, nan)", lambda: jl.Conic(0.1, float("nan")), "Conic:", "k")
    probe("load missing .json", missing(lambda: jl.load(os.path.join(DATA, "nope.json"))), "load", "nope.json")
    probe("load missing .zmx", missing(lambda: jl.load(os.path.join(DATA, "nope.zmx"))), "load", "nope.zmx")
    probe("load_json missing", missing(lambda: jl.io.lensfile.load_json(os.path.join(DATA, "nope.json"))), "load_json", "nope.json")
    probe("load_zmx missing", missing(lambda: jl.io.zmx.load_zmx(os.path.join(DATA, "nope.zmx"))), "load_zmx", "nope.zmx")
    probe("configurations missing", missing(lambda: jl.io.zmx.configurations(os.path.join(DATA, "nope.zmx"))), "configurations", "nope.zmx")
    probe("load_agf missing", missing(lambda: jl.optics.agf.load_agf(os.path.join(DATA, "nope.agf"))), "load_agf", "nope.agf")
    for v in ([1, 1, "x"], [1, 0, 1], [1, 2, 1], [True, True, True], "1,1", [1.5]):
        probe(f"json travel_senses {v!r}", js(travel_senses=v), "travel_senses", "+1 or -1")
    probe("field_rays depth 0", lambda: S.field_rays(cooke, 0.0, S.pupil_polar(2), depth=0.0), "field_rays", "depth", "mm")
    probe("field_rays depth nan", lambda: S.field_rays(cooke, 0.0, S.pupil_polar(2), depth=float("nan")), "field_rays", "depth")
    probe("field_rays depth -inf", lambda: S.field_rays(cooke, 0.0, S.pupil_polar(2), depth=-np.inf), "field_rays", "depth")


def js(surfaces=None, edit=None, **top):
    """A JSON lens file: the Cooke triplet's dict with ``top`` keys set (None: removed) and
    ``edit(d)`` applied; loaded by ``jl.load``."""
    d = json.loads(json.dumps(COOKE_DICT))
    for k, v in top.items():
        if v is None:
            d.pop(k, None)
        else:
            d[k] = v
    if edit:
        edit(d)
    p = os.path.join(fresh("js"), "lens.json")
    with open(p, "w", encoding="utf-8") as fh:
        json.dump(d, fh)
    return lambda: jl.load(p)


def surf(i, **kv):
    def e(d):
        for k, v in kv.items():
            if v is None:
                d["surfaces"][i].pop(k, None)
            else:
                d["surfaces"][i][k] = v
    return e


def json_files():
    probe("json thickness -3 through glass (a warning)", warned(js(edit=surf(1, thickness=-3.0))), "thickness", "inside out")
    probe("json thickness '3'", js(edit=surf(1, thickness="3")), "thickness")
    probe("json thickness null", js(edit=surf(1, thickness=None)), "thickness")
    probe("json radius 0", js(edit=surf(1, radius=0)), "radius")
    probe("json radius 'flat'", js(edit=surf(1, radius="flat")), "radius")
    probe("json radius nan (string)", js(edit=surf(1, radius="nan")), "radius")
    # Left open: a stop smaller than the axial beam (optiland_lens2.zmx has 6.75 mm under a 7.5 mm beam).
    probe("json stop semi_diameter 1 (the EPD 10 beam is 3.8 mm there; left open)", warned(js(edit=surf(4, semi_diameter=1.0))), "semi_diameter")
    probe("json semi_diameter -2", js(edit=surf(1, semi_diameter=-2.0)), "semi_diameter")
    probe("json material 'NSK16'", js(edit=surf(1, material="NSK16")), "N-SK16")
    probe("json material 5", js(edit=surf(1, material=5)), "material")
    probe("json type 'sphere' (an accepted alias; control)", js(edit=surf(1, type="sphere")), good=True)
    probe("json no surfaces", js(surfaces=None, edit=lambda d: d.pop("surfaces")), "surfaces")
    probe("json surfaces []", js(edit=lambda d: d.update(surfaces=[])), "surfaces")
    probe("json no image surface (optional: a flat image; control)", js(edit=lambda d: d["surfaces"].pop()), good=True)
    probe("json two stops", js(edit=surf(2, is_stop=True)), "stop")
    probe("json is_stop 'yes'", js(edit=surf(4, is_stop="yes")), "is_stop")
    probe("json aperture epd -10", js(aperture={"epd": -10}), "epd")
    probe("json aperture epd '10mm'", js(aperture={"epd": "10mm"}), "epd")
    probe("json aperture {}", js(aperture={}), "aperture")
    probe("json aperture fnum 0", js(aperture={"fnum": 0}), "aperture")
    probe("json fields type 'angle_rad_y'", js(fields={"type": "angle_rad_y", "values": [0, 0.2]}), "type")
    probe("json fields values [0, 95] deg", js(fields={"type": "angle_deg_y", "values": [0, 95]}), "field")
    probe("json fields values []", js(fields={"type": "angle_deg_y", "values": []}), "field")
    probe("json wavelengths_nm [0.5876] (µm)", js(wavelengths_nm=[0.5876], primary_wavelength_nm=0.5876), "wavelength")
    probe("json wavelengths_nm [-587]", js(wavelengths_nm=[-587.0], primary_wavelength_nm=-587.0), "wavelength")
    probe("json primary not among wavelengths", js(primary_wavelength_nm=550.0), "primary")
    probe("json format 'jaxlens.lens/9'", js(format="jaxlens.lens/9"), "format")
    probe("json unknown key 'aperature'", js(aperature={"epd": 10}), "aperature")
    probe("json surfaces a dict", js(edit=lambda d: d.update(surfaces={"a": 1})), "surfaces")
    probe("json conic 'x'", js(edit=surf(1, conic="x")), "conic")
    probe("json thickness 1e400 (inf)", js(edit=surf(1, thickness=1e308 * 10)), "thickness")
    probe("json object thickness -5 (a virtual object; control)", js(edit=surf(0, thickness=-50.0)), good=True)


def design_api():
    D = jl.design
    Spec = D.spec.DesignSpec
    probe("DesignSpec fov 0", lambda: Spec(fov=0), "fov", "deg")
    probe("DesignSpec fov 190", lambda: Spec(fov=190), "fov")
    probe("DesignSpec fov nan", lambda: Spec(fov=float("nan")), "fov")
    probe("DesignSpec fnum -2", lambda: Spec(fnum=-2), "fnum")
    probe("DesignSpec fnum 0.1", lambda: Spec(fnum=0.1), "F/0.1")
    probe("DesignSpec n_elements 0", lambda: Spec(n_elements=0, materials=()), "n_elements")
    probe("DesignSpec n_elements 2.5", lambda: Spec(n_elements=2.5), "n_elements")
    probe("DesignSpec materials 3 for 6 elements", lambda: Spec(materials=("E48R",) * 3), "materials")
    probe("DesignSpec materials 'NBK7'", lambda: Spec(n_elements=1, materials=("NBK7",), stop=0), "N-BK7")
    probe("DesignSpec total_track -7", lambda: Spec(total_track=-7), "total_track")
    probe("DesignSpec sensor_diagonal 7660 (µm)", lambda: Spec(sensor_diagonal=7660), "sensor_diagonal")
    probe("DesignSpec sensor_pixels 0", lambda: Spec(sensor_pixels=0), "sensor_pixels")
    probe("DesignSpec wavelengths (486, 588, 656) nm", lambda: Spec(wavelengths=(486.1, 587.6, 656.3)), "wavelength")
    probe("DesignSpec primary 3", lambda: Spec(primary=3), "primary")
    probe("DesignSpec stop 9", lambda: Spec(stop=9), "stop")
    probe("DesignSpec efl nan", lambda: Spec(efl=float("nan")), "efl")
    probe("DesignSpec efl -5", lambda: Spec(efl=-5.0), "efl")
    probe("DesignSpec bfl 10 > total_track 7", lambda: Spec(bfl=10.0), "bfl")
    probe("DesignSpec fov_start 100 > fov 80.8", lambda: Spec(fov_start=100.0), "fov_start")
    probe("DesignSpec sensor_aspect (0, 1)", lambda: Spec(sensor_aspect=(0.0, 1.0)), "sensor_aspect")
    probe("DesignSpec asphere_terms -1", lambda: Spec(asphere_terms=-1), "asphere_terms")
    St = D.curriculum.Stage
    probe("Stage fov nan", lambda: St("s", float("nan"), 2.0, 10), "fov")
    probe("Stage fnum 0", lambda: St("s", 60.0, 0.0, 10), "fnum")
    probe("Stage steps -1", lambda: St("s", 60.0, 2.0, -1), "steps")
    probe("Stage steps 2.5", lambda: St("s", 60.0, 2.0, 2.5), "steps")
    probe("Stage solver 'sgd'", lambda: St("s", 60.0, 2.0, 10, solver="sgd"), "solver")
    probe("Stage beta 2", lambda: St("s", 60.0, 2.0, 10, beta=2.0), "beta")
    probe("Stage pin -1 (negative weight)", lambda: St("s", 60.0, 2.0, 10, pin=-1.0), "pin")
    probe("Stage lr nan", lambda: St("s", 60.0, 2.0, 10, lr=float("nan")), "lr")
    probe("Stage loss 'l2'", lambda: St("s", 60.0, 2.0, 10, loss="l2"), "loss")
    spec = Spec()
    probe("paper_stages n 0 (n + 1 = 1 stage, documented; control)", lambda: len(D.curriculum.paper_stages(spec, n=0)), good=True)
    probe("paper_stages steps -5", lambda: D.curriculum.paper_stages(spec, steps=-5), "steps")
    probe("paper_stages pin nan", lambda: D.curriculum.paper_stages(spec, pin=float("nan")), "pin")
    probe("paper_stages solver 'newton'", lambda: D.curriculum.paper_stages(spec, solver="newton"), "solver")
    probe("paper_stages reference 'best'", lambda: D.curriculum.paper_stages(spec, reference="best"), "reference")
    probe("random_starts seeds []", lambda: D.init.random_starts(spec, []), "seeds")
    probe("random_starts seeds [-1]", lambda: D.init.random_starts(spec, [-1]), "seed")
    probe("random_starts seeds [1.5]", lambda: D.init.random_starts(spec, [1.5]), "seed")
    probe("random_starts seeds 'abc'", lambda: D.init.random_starts(spec, "abc"), "seeds")
    probe("template_lens spec a dict", lambda: D.init.template_lens({"fov": 60}), "spec")
    probe("evaluate n 0", lambda: D.evaluate.evaluate(D.init.template_lens(spec), spec, n=0), "n")
    probe("evaluate min_valid 2", lambda: D.evaluate.evaluate(D.init.template_lens(spec), spec, min_valid=2.0), "min_valid")
    probe("aperture_field_limits 0 elements", lambda: D.spec.aperture_field_limits(0), "n_elements")


def sensor_render():
    probe("Sensor pixel_size 5 (µm) on 4000 px", lambda: jl.Sensor((4000, 3000), 5.0), "pixel_size", "mm")
    probe("Sensor pixel_size 0", lambda: jl.Sensor((8, 8), 0.0), "pixel_size")
    probe("Sensor pixel_size -0.01", lambda: jl.Sensor((8, 8), -0.01), "pixel_size")
    probe("Sensor pixel_size nan", lambda: jl.Sensor((8, 8), float("nan")), "pixel_size")
    probe("Sensor resolution (0, 8)", lambda: jl.Sensor((0, 8), 0.01), "resolution")
    probe("Sensor resolution (8.5, 8)", lambda: jl.Sensor((8.5, 8), 0.01), "resolution")
    probe("Sensor resolution 8 (not a pair)", lambda: jl.Sensor(8, 0.01), "resolution")
    probe("Sensor resolution (8, 8, 3)", lambda: jl.Sensor((8, 8, 3), 0.01), "resolution")
    probe("Sensor resolution ('8', '8')", lambda: jl.Sensor(("8", "8"), 0.01), "resolution")
    probe("Sensor pixel_size '0.01'", lambda: jl.Sensor((8, 8), "0.01"), "pixel_size")
    sen = jl.Sensor((8, 8), 0.01)
    key = jax.random.key(0)
    img = np.ones((8, 8, 3))
    probe("render spp 0", lambda: jl.render(cooke, img, spp=0, key=key, sensor=sen), "spp")
    probe("render spp -4", lambda: jl.render(cooke, img, spp=-4, key=key, sensor=sen), "spp")
    probe("render spp 2.5", lambda: jl.render(cooke, img, spp=2.5, key=key, sensor=sen), "spp")
    probe("render scene 8x8 (no channels)", lambda: jl.render(cooke, np.ones((8, 8)), spp=4, key=key, sensor=sen), "scene")
    probe("render scene 255 (linear radiance >= 0, HDR allowed; control)", lambda: jl.render(cooke, img * 255, spp=4, key=key, sensor=sen).shape, good=True)
    probe("render patch 0", lambda: jl.render(cooke, img, spp=4, key=key, sensor=sen, patch=0), "patch")
    probe("render wavelengths nm", lambda: jl.render(cooke, img, spp=4, key=key, sensor=sen, wavelengths=(450.0, 550.0, 650.0)), "wavelength")
    probe("render depth 0", lambda: jl.render(cooke, img, spp=4, key=key, sensor=sen, depth=0.0), "depth")
    probe("render key 0 (an int)", lambda: jl.render(cooke, img, spp=4, key=0, sensor=sen), "key")
    probe("render no sensor on a lens without one", lambda: jl.render(cooke, img, spp=4, key=key), "sensor")


def glasses():
    C = jl.optics.catalog
    probe("get_material 'NBK7'", lambda: C.get_material("NBK7"), "N-BK7")
    probe("get_material 'bk7 ' (case and blanks ignored; control)", lambda: C.get_material("bk7 ").name, good=True)
    probe("get_material 'N-SF66X'", lambda: C.get_material("N-SF66X"), "N-SF66")
    probe("get_material 5", lambda: C.get_material(5), "name")
    probe("get_material '' (documented: air; control)", lambda: type(C.get_material("")).__name__, good=True)
    probe("get_material catalogs 'SHOTT'", lambda: C.get_material("N-BK7", catalogs="SHOTT"), "SCHOTT")
    probe("glass_info 'F 2'", lambda: C.glass_info("F 2"), "F2")
    probe("nearest_glasses nd 0.5", lambda: C.nearest_glasses(0.5, 60.0), "nd")
    probe("nearest_glasses vd -3", lambda: C.nearest_glasses(1.5, -3.0), "vd")
    probe("nearest_glasses count 0", lambda: C.nearest_glasses(1.5, 60.0, count=0), "count")
    bk7 = C.get_material("N-BK7")
    probe("N-BK7 index at 5 µm (beyond its range)", lambda: float(bk7.index(5.0)), "wavelength", "µm")
    probe("N-BK7 index at 587.6 (nm)", lambda: float(bk7.index(587.6)), "wavelength", "µm")
    probe("N-BK7 index at 0.1 µm", lambda: float(bk7.index(0.1)), "wavelength", "µm")
    probe("N-BK7 index at -0.5", lambda: float(bk7.index(-0.5)), "wavelength")
    probe("N-BK7 index at nan", lambda: float(bk7.index(float("nan"))), "wavelength")
    probe("[control] N-BK7 index at 0.5876 µm", lambda: float(bk7.index(0.5875618)), good=True)
    probe("lens with N-BK7 traced at 3 µm", lambda: A.rms_spot(dataclasses.replace(cooke, wavelengths=np.array([3.0]), primary=0), 0.0), "wavelength")


def clis():
    def cmd(*args, module="jaxlens"):
        return module_cli(*args, module=module, timeout=240)

    probe("cli no subcommand", cmd(), "command")
    probe("cli bogus subcommand", cmd("frobnicate"), "frobnicate")
    probe("cli report no file", cmd("report"), "lens")
    probe("cli report --fields abc", cmd("report", COOKE, "--fields", "abc"), "--fields")
    probe("cli report --fields nan", cmd("report", COOKE, "--fields", "nan"), "field")
    probe("cli report --wavelengths 587.6 (documented: > 100 read as nm; control)", cmd("report", COOKE, "--wavelengths", "587.6"), good=True)
    probe("cli report --wavelengths ''", cmd("report", COOKE, "--wavelengths", ""), "wavelength")
    probe("cli report --config 1.5", cmd("report", COOKE, "--config", "1.5"), "config")
    probe("cli report --unknown-glass maybe", cmd("report", COOKE, "--unknown-glass", "maybe"), "unknown-glass")
    probe("cli report a .txt file", cmd("report", os.path.join(DATA, "x.txt")), ".txt")
    probe("cli report --nope flag", cmd("report", COOKE, "--nope"), "--nope")
    T = "jaxlens.experiments.tolerance"
    probe("cli tolerance --trials 0", cmd(SEED, "--trials", "0", module=T), "--trials")
    probe("cli tolerance --trials -5", cmd(SEED, "--trials", "-5", module=T), "--trials")
    probe("cli tolerance --trials 2.5", cmd(SEED, "--trials", "2.5", module=T), "--trials")
    probe("cli tolerance --threshold nan", cmd(SEED, "--threshold", "nan", module=T), "--threshold")
    probe("cli tolerance --threshold -1", cmd(SEED, "--threshold", "-1", module=T), "--threshold")
    probe("cli tolerance --decenter -0.01", cmd(SEED, "--decenter", "-0.01", module=T), "--decenter")
    probe("cli tolerance --tilt 90", cmd(SEED, "--tilt", "90", module=T), "--tilt")
    probe("cli tolerance --seed -1", cmd(SEED, "--seed", "-1", module=T), "--seed")
    probe("cli tolerance missing lens", cmd(os.path.join(DATA, "nope.zmx"), module=T), "nope.zmx")
    probe("cli tolerance --out a file", cmd(SEED, "--out", COOKE, module=T), "--out")
    probe("cli tolerance no lens", cmd(module=T), "lens")


SEED = os.path.join(ROOT, "experiments", "classical", "designs", "seed_0.zmx")


def classical_cli():
    from jaxlens.experiments import classical as C

    c = lambda *a: cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", fresh("c"), *a])))
    probe("classical --seeds -2", c("--seeds", "-2"), "--seeds")
    probe("classical --seeds 2.5", c("--seeds", "2.5"), "--seeds")
    probe("classical --seed-list 1,x", c("--seed-list", "1,x"), "--seed-list")
    probe("classical --seed-list 1,1", c("--seed-list", "1,1"), "--seed-list")
    probe("classical --seed-list ''", c("--seed-list", ""), "--seed-list")
    probe("classical --first-seed -1", c("--first-seed", "-1"), "--first-seed")
    probe("classical --steps 0", c("--steps", "0"), "--steps")
    probe("classical --steps -3", c("--steps", "-3"), "--steps")
    probe("classical --steps nan", c("--steps", "nan"), "--steps")
    probe("classical --steps inf", c("--steps", "inf"), "--steps")
    probe("classical --polish-steps -1", c("--polish-steps", "-1"), "--polish-steps")
    probe("classical --recipe fast", c("--recipe", "fast"), "--recipe")
    probe("classical --solver sgd", c("--solver", "sgd"), "--solver")
    probe("classical --population 0", c("--population", "0"), "--population")
    probe("classical --tolerance-aware -1", c("--tolerance-aware", "-1"), "--tolerance-aware")
    probe("classical --devices 0", c("--devices", "0"), "--devices")
    probe("classical --tolerance-trials 0 (documented: skips it; control)", c("--tolerance-trials", "0"), good=True)
    probe("classical --fnum-start 1 (faster than --fnum 2)", c("--fnum-start", "1"), "--fnum-start")
    probe("classical --out an existing file", cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", COOKE]))), "--out")
    probe("classical --fov 80.8x", c("--fov", "80.8x"), "--fov")
    probe("classical --materials E48R (1 for 6)", c("--materials", "E48R"), "--materials")


def edof_cli():
    probe("edof --seeds -1", edof_check("--seeds", "-1"), "--seeds")
    probe("edof --seeds 1,x", edof_check("--seeds", "1,x"), "--seeds")
    probe("edof --steps 0", edof_check("--steps", "0"), "--steps")
    probe("edof --batch 0", edof_check("--batch", "0"), "--batch")
    probe("edof --tile 7", edof_check("--tile", "7"), "--tile")
    probe("edof --kernel 0", edof_check("--kernel", "0"), "--kernel")
    probe("edof --lr-net -1", edof_check("--lr-net", "-1"), "--lr-net")
    probe("edof --lr-lens nan", edof_check("--lr-lens", "nan"), "--lr-lens")
    probe("edof --w-sim -0.1 (negative weight)", edof_check("--w-sim", "-0.1"), "--w-sim")
    probe("edof --photons 0", edof_check("--photons", "0"), "--photons")
    probe("edof --read-noise -1", edof_check("--read-noise", "-1"), "--read-noise")
    probe("edof --lenses nope", edof_check("--lenses", "nope"), "--lenses")
    probe("edof --time-limit -5", edof_check("--time-limit", "-5"), "--time-limit")
    probe("edof --width 0", edof_check("--width", "0"), "--width")
    probe("edof --enc 1,1", edof_check("--enc", "1,1"), "--enc")
    probe("edof --max-crops 0", edof_check("--max-crops", "0"), "--max-crops")
    probe("edof --resume without --checkpoint", edof_check("--resume"), "--checkpoint")
    probe("edof --train-dir missing", edof_check("--train-dir", os.path.join(DATA, "nope")), "--train-dir")
    probe("edof --context -1", edof_check("--context", "-1"), "--context")
    probe("edof --n-odd 0", edof_check("--n-odd", "0"), "--n-odd")
    probe("[control] edof --smoke", edof_check("--smoke"), good=True)


if __name__ == "__main__":
    run([left_open, json_files, design_api, sensor_render, glasses, clis, classical_cli, edof_cli])
