# ruff: noqa: E501, B023, E731
"""Round-17 bad-input probes: throw malformed input at entry points added or changed lately
and print a table: probe | outcome | what happened.

Outcomes:
    clear error   ValueError/TypeError (or a CLI's exit 2 with one line) whose message holds
                  every expected word (the argument's name, the range, the unit).
    vague error   ValueError/TypeError that lacks an expected word.
    crash         another exception (from deep inside JAX, numpy, a KeyError…).
    silent wrong  bad input returned a value.
    ok            a control (good input) returned a value, as it should.

Areas: Lens(aim=) and the samplers' aim=, DesignSpec fov_start/fnum_start, DesignConfig,
Toroidal and Biconic domains, catalog wavelengths, Tolerances, marechal_strehl, rms_spot and
distortion with aim=, the JSON lens reader, the report/tolerance/classical/EDoF CLIs, image
helpers, nm wavelengths, fields >= 90°, pupil samples, integer arrays, 0-d vs 1-d.

Run: PYTHONPATH=$PWD python tools/audit17_probe.py [filter]
"""

import copy
import json
import os
import subprocess
import sys
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from probe_table import ROWS, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
cooke = zoo.cooke_triplet()


# ----------------------------------------------------------------------------- known gaps
def known_gaps():
    from jaxlens.analysis.tolerance import ToleranceModel, Tolerances
    probe("Biconic cx=1/3 sd=5", lambda: jl.Biconic(c=0.0, cx=1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Biconic cx=-1/3 kx=0 sd=5", lambda: jl.Biconic(cx=-1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Biconic c=1/3 sd=5", lambda: jl.Biconic(c=1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Biconic cx=1/3 sd=2.9 (control)", lambda: jl.Biconic(cx=1 / 3, semi_diameter=2.9), good=True)
    probe("Standard c=1/3 sd=5", lambda: jl.Standard(c=1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Toroidal cx=1/3 sd=5", lambda: jl.optics.toroidal.Toroidal(cx=1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Toroidal c=1/3 sd=5", lambda: jl.optics.toroidal.Toroidal(c=1 / 3, semi_diameter=5.0), "semi_diameter", "mm")
    probe("Toroidal coeffs 2-D", lambda: jl.optics.toroidal.Toroidal(coeffs=[[0.0]]), "coeffs")
    probe("Toroidal cx nan", lambda: jl.optics.toroidal.Toroidal(cx=float("nan")), "cx")
    probe("Toroidal cx '0.1'", lambda: jl.optics.toroidal.Toroidal(cx="0.1"), "cx")
    from jaxlens.io import lensfile
    d = json.loads(lensfile.dumps(cooke))
    d["surfaces"][1] = {"type": "biconic", "curvature": 0.0, "curvature_x": 0.4, "semi_diameter": 5.0, "thickness": 3.0, "material": "N-BK7"}
    probe("JSON biconic radius_x 2.5 sd 5", lambda: lensfile.lens_from_dict(copy.deepcopy(d)), "semi_diameter", "mm")
    bk7 = jl.get_material("N-BK7")
    probe("N-BK7.index(2.6) (range 0.3-2.5)", lambda: bk7.index(2.6), "0.3", "2.5", "µm")
    probe("N-BK7.index(0.2)", lambda: bk7.index(0.2), "0.3", "µm")
    probe("N-BK7.index([0.5, 3.0])", lambda: bk7.index(jnp.array([0.5, 3.0])), "µm")
    probe("N-BK7.index(587.6)", lambda: bk7.index(587.6), "nm", "µm")
    probe("N-BK7.index(0.5876) (control)", lambda: bk7.index(0.5876), good=True)
    probe("N-BK7.extrapolated_index(3.0) (control)", lambda: bk7.extrapolated_index(3.0), good=True)
    probe("jit N-BK7.index(traced 3.0) (control: checked at entry)", lambda: jax.jit(lambda w: bk7.index(w))(3.0), good=True)
    probe("abbe_number(SILICON) (control)", lambda: jl.optics.materials.abbe_number(jl.get_material("SILICON")), good=True)
    probe("Tolerances(thickness=1e6)", lambda: Tolerances(thickness=1e6), "thickness", "mm")
    probe("Tolerances(thickness=10)", lambda: Tolerances(thickness=10.0), "thickness", "mm")
    probe("ToleranceModel thickness 3 > glass 1 mm", lambda: ToleranceModel(cooke, tolerances=Tolerances(thickness=3.0)), "thickness", "mm")
    probe("Tolerances(thickness=0.05) (control)", lambda: Tolerances(thickness=0.05), good=True)
    probe("ToleranceModel decenter 1e6", lambda: ToleranceModel(cooke, tolerances=Tolerances(decenter=1e6)), "decenter", "mm")
    from jaxlens.imaging.psf import CoherentPSF, GeometricPSF
    from jaxlens.optics.paraxial import working_fnum
    probe("GeometricPSF(pupil=0)", lambda: GeometricPSF(pupil=0), "pupil")
    probe("CoherentPSF(pupil=-4)", lambda: CoherentPSF(pupil=-4), "pupil")
    probe("GeometricPSF(overfill=0)", lambda: GeometricPSF(overfill=0.0), "overfill")
    probe("paraxial_data wavelength [0.5, 0.6]", lambda: jl.paraxial_data(cooke, [0.5, 0.6]), "one value")
    probe("working_fnum depth 0", lambda: working_fnum(cooke, 0.0), "working_fnum: depth")
    probe("default_fields count 0", lambda: jl.analysis.aberrations.default_fields(cooke, 0), "count")
    from jaxlens.experiments.edof import cli as edof_cli
    for v in ("2", "1.5", "-0.1", "nan"):
        probe(f"edof --cubic-floor {v}", lambda: edof_cli.config_from_args(edof_cli.build_parser().parse_args(["--cubic-floor", v])), "--cubic-floor", "[0, 1]")
    probe("edof --hybrid-floor 3", lambda: edof_cli.config_from_args(edof_cli.build_parser().parse_args(["--hybrid-floor", "3"])), "--hybrid-floor", "[0, 1]")
    probe("edof --cubic-floor 0.5 (control)", lambda: edof_cli.config_from_args(edof_cli.build_parser().parse_args(["--cubic-floor", "0.5"])).cubic_floor, good=True)


# ----------------------------------------------------------------------------- aiming
def aiming():
    import dataclasses

    from jaxlens.analysis import distortion, rms_spot
    from jaxlens.imaging import sampling
    for v in ("Real", "off", "", None, 1, True, ("real",)):
        probe(f"Lens(aim={v!r})", lambda: dataclasses.replace(cooke, aim=v), "aim")
    probe("Lens(aim='real') (control)", lambda: dataclasses.replace(cooke, aim="real").aim, good=True)
    pts = jnp.zeros((1, 2))
    for v in ("Real", "chief", 0, True):
        probe(f"field_rays(aim={v!r})", lambda: sampling.field_rays(cooke, 0.0, pts, 0.5876, aim=v), "aim")
        probe(f"collimated(aim={v!r})", lambda: sampling.collimated(cooke, 0.0, pts, 0.5876, aim=v), "aim")
        probe(f"point_source(aim={v!r})", lambda: sampling.point_source(cooke, jnp.array([0.0, 1.0, -100.0]), pts, 0.5876, aim=v), "aim")
        probe(f"rms_spot(aim={v!r})", lambda: rms_spot(cooke, aim=v).polychromatic, "aim")
        probe(f"distortion(aim={v!r})", lambda: distortion(cooke, aim=v).percent_ftan, "aim")
    probe("rms_spot(aim='real') (control)", lambda: rms_spot(cooke, aim="real").polychromatic, good=True)
    probe("distortion(aim='real') (control)", lambda: distortion(cooke, aim="real").percent_ftan, good=True)
    probe("distortion fields [95]", lambda: distortion(cooke, [95.0]).percent_ftan, "field", "90")
    probe("distortion fields [[0,20,0]]", lambda: distortion(cooke, [[0.0, 20.0, 0.0]]).percent_ftan, "field")
    probe("distortion wavelength 587.6", lambda: distortion(cooke, wavelength=587.6).percent_ftan, "µm")
    probe("distortion wavelength [0.5, 0.6]", lambda: distortion(cooke, wavelength=[0.5, 0.6]).percent_ftan, "wavelength")
    probe("distortion fields int array", lambda: distortion(cooke, jnp.array([0, 10, 20])).percent_ftan, good=True)
    probe("rms_spot fields 0-d 10.0", lambda: rms_spot(cooke, 10.0).polychromatic, good=True)
    probe("rms_spot wavelengths 0-d", lambda: rms_spot(cooke, wavelengths=0.5876).polychromatic, good=True)
    probe("rms_spot wavelengths 587.6", lambda: rms_spot(cooke, wavelengths=[587.6]).polychromatic, "µm")
    probe("rms_spot pupil shape (0,2)", lambda: rms_spot(cooke, pupil=jnp.zeros((0, 2))).polychromatic, "pupil")
    probe("rms_spot pupil [[2,0]] (documented: overfilled points allowed; none passes: NaN, valid_fraction 0)", lambda: rms_spot(cooke, pupil=jnp.array([[2.0, 0.0]])).valid_fraction, good=True)
    probe("rms_spot pupil int [[0,1]] (control)", lambda: rms_spot(cooke, pupil=jnp.array([[0, 1]])).polychromatic, good=True)
    probe("rms_spot fields [91]", lambda: rms_spot(cooke, [91.0]).polychromatic, "field", "90")
    probe("rms_spot depth -10", lambda: rms_spot(cooke, depth=-10.0).polychromatic, "depth", "mm")
    probe("rms_spot reference 'Chief'", lambda: rms_spot(cooke, reference="Chief").polychromatic, "reference")
    probe("rms_spot newton_iters 0 (documented: >= 0, the base-conic start)", lambda: rms_spot(cooke, newton_iters=0).polychromatic, good=True)
    probe("rms_spot newton_iters 2.5", lambda: rms_spot(cooke, newton_iters=2.5).polychromatic, "newton_iters")


# ----------------------------------------------------------------------------- design
def design():
    from jaxlens.design import DesignConfig, DesignSpec
    for kw in [dict(fov_start=None, fnum_start=None), dict(fov_start=20.0), dict(fnum_start=4.0)]:
        probe(f"DesignSpec({kw}) (control)", lambda: (DesignSpec(**kw).fov_start, DesignSpec(**kw).fnum_start), good=True)
    for kw in [dict(fov_start=0.0), dict(fov_start=-5.0), dict(fov_start=np.nan), dict(fov_start="20"),
               dict(fov_start=True), dict(fnum_start=np.inf), dict(fnum_start="4"), dict(fnum_start=1.0),
               dict(fov_start=jnp.array([20.0, 30.0])), dict(fov=200.0), dict(fov=90.0, fov_start=95.0),
               dict(fnum=0.0), dict(wavelengths=(587.6,)), dict(wavelengths=()), dict(fov_start=jnp.array(20))]:
        probe(f"DesignSpec({kw})", lambda: DesignSpec(**kw), *[k for k in kw][:1])
    for kw in [dict(n_fields=0), dict(n_fields=2.5), dict(rings=0), dict(rings=-1), dict(curriculum_n=-1),
               dict(steps=-1), dict(lr_c=-1.0), dict(lr_c=np.nan), dict(epoch=0), dict(log_every=0),
               dict(float64="yes"), dict(irls=1), dict(image_pixels=0), dict(image_spp=0),
               dict(tolerance_trials=-1), dict(pin=-1.0), dict(efl_weight=np.inf),
               dict(steps=True), dict(reference="Ideal"), dict(lr_k=-0.1)]:
        probe(f"DesignConfig({kw})", lambda: DesignConfig(**kw), *[k for k in kw][:1])
    probe("DesignConfig(steps=np.int64(5)) (control)", lambda: DesignConfig(steps=np.int64(5)).steps, good=True)
    probe("DesignConfig(lr_m=0.0) (documented: a rate of 0 freezes the group)", lambda: DesignConfig(lr_m=0.0).lr_m, good=True)


# ----------------------------------------------------------------------------- wavefront
def wavefront():
    from jaxlens.analysis import marechal_strehl
    probe("marechal_strehl(jnp int [1, 2]) (control: 1 and 2 waves)", lambda: marechal_strehl(jnp.array([1, 2])), good=True)
    for v in (-0.1, "0.1", True, [0.1, -1], None, 1 + 0j):
        probe(f"marechal_strehl({v!r})", lambda: marechal_strehl(v), "rms_waves")
    probe("marechal_strehl(0.05) (control)", lambda: marechal_strehl(0.05), good=True)
    probe("marechal_strehl(int 0) (control)", lambda: marechal_strehl(0), good=True)
    probe("marechal_strehl(nan) (documented: NaN passes)", lambda: marechal_strehl(np.nan), good=True)
    probe("marechal_strehl(inf)", lambda: marechal_strehl(np.inf), "rms_waves")
    probe("marechal_strehl(5.0) (documented: poor above 0.1 wave, MARECHAL_MAX_RMS)", lambda: marechal_strehl(5.0), good=True)
    from jaxlens.analysis import wavefront as wf
    probe("wavefront field 95", lambda: wf(cooke, 95.0).rms, "field", "90")
    probe("wavefront wavelength 587.6", lambda: wf(cooke, 0.0, wavelength=587.6).rms, "µm")
    probe("wavefront grid 0", lambda: wf(cooke, 0.0, grid=0).rms, "grid")
    probe("wavefront grid -4", lambda: wf(cooke, 0.0, grid=-4).rms, "grid")


# ----------------------------------------------------------------------------- JSON reader
def json_reader():
    from jaxlens.io import lensfile
    base = json.loads(lensfile.dumps(cooke))

    def edit(f):
        d = copy.deepcopy(base)
        f(d)
        return d

    def load(d):
        return lensfile.lens_from_dict(d, source="t.json")

    def loads_text(text):
        p = os.path.join(tempfile.mkdtemp(), "t.json")
        with open(p, "w") as fh:
            fh.write(text)
        return lensfile.load_json(p)

    cases = {
        "epd string '10' (documented: numeric strings read)": (lambda d: d["aperture"].update(epd="10"), "epd"),
        "epd bool": (lambda d: d["aperture"].update(epd=True), "epd"),
        "epd NaN": (lambda d: d["aperture"].update(epd=float("nan")), "epd"),
        "epd list": (lambda d: d["aperture"].update(epd=[10.0]), "epd"),
        "epd negative": (lambda d: d["aperture"].update(epd=-1.0), "epd"),
        "aperture missing": (lambda d: d.pop("aperture"), "aperture"),
        "surfaces missing": (lambda d: d.pop("surfaces"), "surfaces"),
        "surfaces dict": (lambda d: d.update(surfaces={}), "surfaces"),
        "surfaces empty": (lambda d: d.update(surfaces=[]), "surfaces"),
        "fields values nested": (lambda d: d["fields"].update(values=[[[0.0]]]), "fields"),
        "fields values string": (lambda d: d["fields"].update(values="0, 14"), "fields"),
        "fields values 95": (lambda d: d["fields"].update(values=[0.0, 95.0]), "field"),
        "fields values bool": (lambda d: d["fields"].update(values=[True]), "fields"),
        "fields type unknown": (lambda d: d["fields"].update(type="height"), "type"),
        "wavelengths nm": (lambda d: d.update(wavelengths_um=[486.1, 587.6, 656.3]), "µm"),
        "wavelengths nested": (lambda d: d.update(wavelengths_um=[[0.5876]]), "wavelength"),
        "wavelengths strings (documented: numeric strings read)": (lambda d: d.update(wavelengths_um=["0.4861", "0.5876", "0.6563"]), "wavelength"),
        "wavelengths empty": (lambda d: d.update(wavelengths_um=[]), "wavelength"),
        "primary 3": (lambda d: d.update(primary=3), "primary"),
        "primary 1.0": (lambda d: d.update(primary=1.0), "primary"),
        "primary true": (lambda d: d.update(primary=True), "primary"),
        "primary -1": (lambda d: d.update(primary=-1), "primary"),
        "extra top-level key (documented: unknown keys ignored, near misses refused)": (lambda d: d.update(colour="red"), "colour"),
        "extra surface key (documented: unknown keys ignored)": (lambda d: d["surfaces"][1].update(radius_of_gyration=3.0), "radius_of_gyration"),
        "curvature string (documented: numeric strings read)": (lambda d: d["surfaces"][1].update(curvature="0.05"), "curvature"),
        "curvature bool": (lambda d: d["surfaces"][1].update(curvature=False), "curvature"),
        "curvature inf": (lambda d: d["surfaces"][1].update(curvature="inf"), "curvature"),
        "curvature list": (lambda d: d["surfaces"][1].update(curvature=[0.05]), "curvature"),
        "conic nan string": (lambda d: d["surfaces"][1].update(conic="nan"), "conic"),
        "thickness missing": (lambda d: d["surfaces"][1].pop("thickness"), "thickness"),
        "thickness string (documented: numeric strings read)": (lambda d: d["surfaces"][1].update(thickness="3"), "thickness"),
        "thickness null": (lambda d: d["surfaces"][1].update(thickness=None), "thickness"),
        "semi_diameter -1": (lambda d: d["surfaces"][1].update(semi_diameter=-1.0), "semi_diameter"),
        "semi_diameter '8' (documented: numeric strings read)": (lambda d: d["surfaces"][1].update(semi_diameter="8"), "semi_diameter"),
        "material number": (lambda d: d["surfaces"][1].update(material=1.5), "material"),
        "material unknown glass": (lambda d: d["surfaces"][1].update(material="N-BK77"), "N-BK7"),
        "material table nm": (lambda d: d["surfaces"][1]["material"].update(wavelengths_um=[486.1, 587.6, 656.3]), "µm"),
        "material table indices str (documented: numeric strings read)": (lambda d: d["surfaces"][1]["material"].update(indices=["1.6", "1.6", "1.6"]), "indices"),
        "material table short": (lambda d: d["surfaces"][1]["material"].update(indices=[1.6, 1.6]), "equal-length"),
        "type unknown": (lambda d: d["surfaces"][1].update(type="asphere9"), "type"),
        "type number": (lambda d: d["surfaces"][1].update(type=3), "type"),
        "is_stop string": (lambda d: d["surfaces"][1].update(is_stop="yes"), "is_stop"),
        "two stops": (lambda d: d["surfaces"][1].update(is_stop=True), "stop"),
        "surface is list": (lambda d: d["surfaces"].__setitem__(1, [0.05, 3.0]), "surface"),
        "format wrong": (lambda d: d.update(format="jaxlens.lens/9"), "format"),
        "units inch": (lambda d: d.update(units={"length": "in", "wavelength": "um", "angle": "deg"}), "units"),
        "units wavelength nm": (lambda d: d.update(units={"length": "mm", "wavelength": "nm", "angle": "deg"}), "wavelength"),
        "even_asphere_coeffs nested": (lambda d: d["surfaces"][1].update(type="even_asphere", even_asphere_coeffs=[[1e-5]]), "coeffs"),
        "even_asphere_coeffs strings (documented: numeric strings read)": (lambda d: d["surfaces"][1].update(type="even_asphere", even_asphere_coeffs=["1e-5"]), "coeffs"),
        "aim 'Real'": (lambda d: d.update(aim="Real"), "aim"),
        "ray_aiming 'Real'": (lambda d: d.update(ray_aiming="Real"), "aim"),
        "type asphere9": (lambda d: d["surfaces"][1].update(type="asphere9"), "evenasph"),
        "type extended asphere": (lambda d: d["surfaces"][1].update(type="extended asphere", even_asphere_coeffs=[1e-6]), "unknown surface type"),
        "ray_aiming 'real' (control)": (lambda d: d.update(ray_aiming="real"), "aim"),
        "name number": (lambda d: d.update(name=3), "name"),
    }
    for name, (f, word) in cases.items():
        good = "(documented" in name or "(control" in name
        probe(f"JSON {name}", lambda: load(edit(f)).name, *(() if good else (word,)), good=good)
    probe("JSON unchanged (control)", lambda: load(edit(lambda d: None)).name, good=True)
    probe("JSON text NaN literal", lambda: loads_text(lensfile.dumps(cooke).replace('"epd": 10.0', '"epd": NaN')), "epd")
    probe("JSON text Infinity literal", lambda: loads_text(lensfile.dumps(cooke).replace('"epd": 10.0', '"epd": Infinity')), "epd")
    probe("JSON text truncated", lambda: loads_text(lensfile.dumps(cooke)[:300]), "t.json:")
    probe("JSON text top-level list", lambda: loads_text("[1, 2]"), "object")
    probe("JSON text empty", lambda: loads_text(""), "json")
    probe("JSON text duplicate key", lambda: loads_text(lensfile.dumps(cooke).replace('"primary": 1', '"primary": 1, "primary": 0')), "primary")
    probe("lens_from_dict(list)", lambda: lensfile.lens_from_dict([1, 2]), "object")


# ----------------------------------------------------------------------------- CLIs
def clis():
    from jaxlens.experiments import classical
    from jaxlens.experiments import tolerance as tol_cli
    lens_path = os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx")
    tmp = tempfile.mkdtemp()
    from jaxlens import __main__ as cli_main

    def cli(f):
        f.cli = True
        return f

    rep = cli(lambda *a: cli_main.main(["report", *a]))
    probe("report --fields 95", cli(lambda: rep(lens_path, "--fields", "95")), "--fields", "90")
    probe("report --fields nan", cli(lambda: rep(lens_path, "--fields", "nan")), "--fields")
    probe("report --wavelengths 587.6 (documented: values above 100 are nm)", cli(lambda: rep(lens_path, "--wavelengths", "587.6")), good=True)
    probe("report --wavelengths 0", cli(lambda: rep(lens_path, "--wavelengths", "0")), "µm")
    probe("report --config 0", cli(lambda: rep(lens_path, "--config", "0")), "config", "from 1")
    probe("report --config 1.5", cli(lambda: rep(lens_path, "--config", "1.5")), "--config")
    probe("report --unknown-glass foo", cli(lambda: rep(lens_path, "--unknown-glass", "foo")), "--unknown-glass")
    probe("report missing file", cli(lambda: rep(os.path.join(tmp, "nope.json"))), "nope.json")
    probe("report directory", cli(lambda: rep(tmp)), "extension")
    probe("report .txt file", cli(lambda: rep(__file__)), "audit17_probe.py")
    probe("report --overwrite without --plot", cli(lambda: rep(lens_path, "--overwrite")), "--plot")
    t = cli(lambda *a: tol_cli.main([lens_path, "--out", os.path.join(tmp, "t"), *a]))
    for a in (("--trials", "0"), ("--trials", "-5"), ("--threshold", "-1"), ("--threshold", "nan"),
              ("--seed", "-1"), ("--decenter", "-0.1"), ("--tilt", "90"), ("--tilt", "inf"),
              ("--trials", "2.5")):
        probe(f"tolerance {' '.join(a)}", cli(lambda: t(*a)), a[0])
    c = cli(lambda *a: classical.main([*a, "--out", os.path.join(tmp, "c"), "--quiet"]))
    probe("classical --bfl 8", cli(lambda: c("--bfl", "8")), "bfl", "total_track")
    probe("classical --materials N-BK77 x6", cli(lambda: c("--materials", ",".join(["N-BK77"] * 6))), "N-BK7")
    for a in (("--fov", "180"), ("--fov", "-1"), ("--fnum", "0"), ("--elements", "0"), ("--track", "-7"),
              ("--stop", "9"), ("--fov-start", "100"), ("--fnum-start", "1"),
              ("--seeds", "0"), ("--seed-list", "1,a"), ("--steps", "-1"), ("--steps", "nan"),
              ("--devices", "0"), ("--tolerance-trials", "-1"), ("--tolerance-threshold", "0"),
              ("--sensor-diagonal", "0"), ("--asphere-terms", "-1"), ("--population", "0"),
              ("--material-catalogs", "NOPE")):
        probe(f"classical {' '.join(a)}", cli(lambda: c(*a)), a[0])
    r = subprocess.run([sys.executable, "-m", "jaxlens", "report", lens_path, "--fields", "95"],
                       capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PYTHONPATH": ROOT})
    ROWS.append(("python -m jaxlens report --fields 95 (fresh interpreter)",
                 "clear error" if r.returncode == 2 and "--fields" in r.stderr and len(r.stderr.strip().splitlines()) == 1 else "vague error",
                 (r.stderr.strip().splitlines() or ["(no stderr)"])[-1][:160]))


# ----------------------------------------------------------------------------- images
def images():
    from jaxlens.io import images as im
    tmp = tempfile.mkdtemp()
    probe("to_linear float image 0..255", lambda: im.to_linear(np.full((4, 4, 3), 200.0)), "255")
    probe("to_linear int64", lambda: im.to_linear(np.ones((4, 4, 3), np.int64)), "int64")
    probe("to_linear uint8 (control)", lambda: im.to_linear(np.full((4, 4, 3), 255, np.uint8)).max(), good=True)
    probe("write_png 5 channels", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((4, 4, 5))), "C<=4")
    probe("write_png bits 8.0", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((4, 4, 3)), bits=8.0), "bits")
    probe("read_png linear 'no'", lambda: im.read_png(os.path.join(tmp, "a.png"), linear="no"), "linear")
    probe("write_png 1-D", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros(16)), "[H, W]")
    probe("write_png 4-D", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((1, 4, 4, 3))), "[H, W]")
    probe("write_png uint8 image", lambda: im.write_png(os.path.join(tmp, "a.png"), np.full((4, 4, 3), 200, np.uint8)), "uint8")
    probe("write_png NaN", lambda: im.write_png(os.path.join(tmp, "a.png"), np.full((4, 4, 3), np.nan)), "nan")
    probe("write_png bits 12", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((4, 4, 3)), bits=12), "bits")
    probe("write_png linear 'yes'", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((4, 4, 3)), linear="yes"), "linear")
    probe("write_png jnp int32", lambda: im.write_png(os.path.join(tmp, "a.png"), jnp.zeros((4, 4, 3), jnp.int32)), "integer")
    probe("write_png 0x0", lambda: im.write_png(os.path.join(tmp, "a.png"), np.zeros((0, 0, 3))), "shape")
    probe("write_exr int", lambda: im.write_exr(os.path.join(tmp, "a.exr"), np.zeros((4, 4, 3), np.int32)), "integer")
    probe("write_exr channels mismatch", lambda: im.write_exr(os.path.join(tmp, "a.exr"), np.zeros((4, 4, 3)), channels=["R", "G"]), "channels")
    probe("psnr shapes differ", lambda: im.psnr(np.zeros((4, 4, 3)), np.zeros((4, 4))), "shape")
    probe("psnr uint8 vs float", lambda: im.psnr(np.zeros((4, 4), np.uint8), np.zeros((4, 4))), "dtype")
    probe("psnr data_range 0", lambda: im.psnr(np.zeros((4, 4)), np.ones((4, 4)) * 0.1, data_range=0), "data_range")
    probe("psnr data_range -1", lambda: im.psnr(np.zeros((4, 4)), np.ones((4, 4)) * 0.1, data_range=-1.0), "data_range")
    probe("ssim 2x2 image", lambda: im.ssim(np.zeros((2, 2)), np.zeros((2, 2))), "7")
    probe("ssim NaN", lambda: im.ssim(np.full((16, 16), np.nan), np.zeros((16, 16))), "nan")
    probe("scene size (0, 10)", lambda: im.scene("astronaut", (0, 10)), "size")
    probe("scene size 64 (int)", lambda: im.scene("astronaut", 64), "size")
    probe("scene unknown name", lambda: im.scene("astronot"), "astronaut")
    sensor = jl.Sensor(resolution=(8, 8), pixel_size=0.01)
    probe("render int image", lambda: jl.render(cooke, np.zeros((8, 8, 3), np.int32), sensor=sensor, spp=1, key=jax.random.key(0)), "int32")
    probe("render 2 channels", lambda: jl.render(cooke, np.zeros((8, 8, 2)), sensor=sensor, spp=1, key=jax.random.key(0)), "channel")


# ----------------------------------------------------------------------------- units and shapes
def units_and_shapes():
    from jaxlens.analysis import encircled_energy, seidel
    from jaxlens.imaging import sampling
    pts = jnp.zeros((1, 2))
    probe("psf field 95", lambda: jl.psf(cooke, 95.0, kernel_size=9, pixel_size=0.005), "field", "90")
    probe("psf field 90", lambda: jl.psf(cooke, 90.0, kernel_size=9, pixel_size=0.005), "field", "90")
    probe("psf wavelength 587.6", lambda: jl.psf(cooke, 0.0, wavelength=587.6, kernel_size=9, pixel_size=0.005), "µm")
    probe("psf kernel_size 0", lambda: jl.psf(cooke, 0.0, kernel_size=0, pixel_size=0.005), "kernel_size")
    probe("psf kernel_size jnp int", lambda: jl.psf(cooke, 0.0, kernel_size=jnp.array(9), pixel_size=0.005), good=True)
    probe("psf pixel_size jnp int 0", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=jnp.array(0)), "pixel_size")
    probe("mtf wavelengths 587.6", lambda: jl.imaging.psf.mtf(cooke, 0.0, wavelengths=[587.6]), "µm")
    probe("mtf frequencies negative", lambda: jl.imaging.psf.mtf(cooke, 0.0, frequencies=[-10.0]), "frequencies")
    probe("field_rays wavelength 587.6", lambda: sampling.field_rays(cooke, 0.0, pts, 587.6), "µm")
    probe("field_rays field 120", lambda: sampling.field_rays(cooke, 120.0, pts, 0.5876), "field", "90")
    probe("field_rays pupil shape (2,) (one point, one ray)", lambda: sampling.field_rays(cooke, 0.0, jnp.zeros(2), 0.5876).origin.shape, good=True)
    probe("field_rays pupil (0,2) (empty)", lambda: sampling.field_rays(cooke, 0.0, jnp.zeros((0, 2)), 0.5876).origin.shape, "pupil")
    probe("field_rays field int 0 (control)", lambda: sampling.field_rays(cooke, jnp.array(0), pts, 0.5876).origin, good=True)
    probe("collimated wavelength 587.6", lambda: sampling.collimated(cooke, 0.0, pts, 587.6), "µm")
    probe("collimated field 90", lambda: sampling.collimated(cooke, 90.0, pts, 0.5876), "90")
    probe("point_source wavelength 587.6", lambda: sampling.point_source(cooke, jnp.array([0.0, 1.0, -100.0]), pts, 587.6), "µm")
    probe("point_source point behind lens", lambda: sampling.point_source(cooke, jnp.array([0.0, 1.0, 100.0]), pts, 0.5876).origin, "z")
    probe("point_source point shape (2,)", lambda: sampling.point_source(cooke, jnp.array([0.0, 1.0]), pts, 0.5876), "point")
    probe("pupil_grid 0", lambda: sampling.pupil_grid(0), "pupil_grid")
    probe("pupil_grid -3", lambda: sampling.pupil_grid(-3), "pupil_grid")
    probe("pupil_grid 2.5", lambda: sampling.pupil_grid(2.5), "pupil_grid")
    probe("pupil_grid jnp int 5 (control)", lambda: sampling.pupil_grid(jnp.array(5)).shape, good=True)
    probe("seidel wavelength 587.6", lambda: seidel(cooke, wavelength=587.6).per_surface, "µm")
    probe("seidel field 95", lambda: seidel(cooke, field=95.0).per_surface, "field")
    probe("efl wavelength 587.6", lambda: jl.efl(cooke, 587.6), "µm")
    probe("bfl wavelength 587.6", lambda: jl.bfl(cooke, 587.6), "µm")
    probe("paraxial_data wavelength 587.6", lambda: jl.paraxial_data(cooke, 587.6), "µm")
    probe("encircled_energy radii negative", lambda: encircled_energy(cooke, 0.0, [-0.01, 0.01]), "radii")
    probe("encircled_energy wavelength nm", lambda: encircled_energy(cooke, 0.0, [0.01], wavelength=587.6), "µm")
    probe("Lens wavelengths jnp int [1] (valid µm; materials checked by analyses)", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=jnp.array([1])).wavelengths.dtype, good=True)
    from jaxlens.analysis import rms_spot
    probe("rms_spot of that lens (1 µm outside its tables)", lambda: rms_spot(jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=jnp.array([1]))).polychromatic, "µm")
    probe("Lens fields jnp int (control)", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, stop=cooke.stop, epd=10, fields=jnp.array([0, 10, 20]), wavelengths=cooke.wavelengths, primary=1).fields.dtype, good=True)
    probe("Lens fields [0, 90]", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, fields=[0.0, 90.0], wavelengths=cooke.wavelengths), "fields", "90")
    probe("Lens epd 0-d vs [1]", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, epd=[10.0], wavelengths=cooke.wavelengths), "epd")
    probe("Lens thickness 0-d", lambda: jl.Lens(cooke.surfaces[:1], 3.0, cooke.materials[:1], wavelengths=cooke.wavelengths), "thickness")
    probe("Lens wavelengths 0-d 0.5876", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=0.5876).wavelengths, "wavelengths")
    probe("Lens wavelengths 0-d 587.6", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=587.6), "µm")
    probe("Lens primary 1.0", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=cooke.wavelengths, primary=1.0), "primary")
    probe("Lens stop -1", lambda: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, wavelengths=cooke.wavelengths, stop=-1), "stop")
    probe("ModelGlass nd 1.5 vd 0", lambda: jl.ModelGlass(1.5, 0.0), "vd")
    probe("ModelGlass.index 587.6", lambda: jl.ModelGlass(1.5, 60.0).index(587.6), "µm")
    probe("Tabulated.index 2.0 outside table (documented: held constant)", lambda: jl.Tabulated([0.5, 0.6], [1.51, 1.50]).index(2.0), good=True)
    probe("get_material 'N-BK77'", lambda: jl.get_material("N-BK77"), "N-BK7")
    probe("get_material 3", lambda: jl.get_material(3), "name")


run((known_gaps, aiming, design, wavefront, json_reader, clis, images, units_and_shapes))
