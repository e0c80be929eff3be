# ruff: noqa: E501, B023
"""Round-16 bad-input probes: throw malformed input at the public API and the CLIs, and print
what each does (OK = returned without error: look for silent answers).

Areas: design specs and curricula that run the wrong way, a Lens edited with eqx.tree_at
(its constructor checks bypassed), the afocal analyses and the freeform surfaces' constructor
values, wavelengths/fields/depths/pupils out of range, images and PSF grids, tolerancing,
and the CLIs' options and output folders.

Run: PYTHONPATH=$PWD python tools/audit16_probe.py [filter]
"""

import os
import subprocess
import sys
import tempfile
import traceback

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

PROBES = []
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COOKE_ZMX = os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx")


def probe(fn):
    PROBES.append(fn)
    return fn


def show(name, f):
    try:
        r = f()
    except Exception as e:  # noqa: BLE001
        msg = str(e).split("\n")[0][:240]
        print(f"ERR  {name}: {type(e).__name__}: {msg}")
        return
    try:
        s = (np.array2string(np.asarray(r), precision=6)[:140]
             if not isinstance(r, (str, dict, list, tuple)) else repr(r)[:140])
    except Exception:  # noqa: BLE001
        s = type(r).__name__
    print(f"OK   {name}: {s}")


cooke = zoo.cooke_triplet()


@probe
def design_spec():
    from jaxlens.design import DesignConfig, DesignSpec, paper_stages, sine_path
    show("DesignSpec fnum_start < fnum", lambda: DesignSpec(fnum=2.0, fnum_start=1.2).fnum_start)
    show("DesignSpec fnum_start = fnum", lambda: DesignSpec(fnum=2.0, fnum_start=2.0).fnum_start)
    show("DesignSpec fnum_start 0.3 (faster than any lens)", lambda: DesignSpec(fnum=2.0, fnum_start=0.3).fnum_start)
    show("DesignSpec fnum_start inf", lambda: DesignSpec(fnum_start=np.inf).fnum_start)
    show("DesignSpec fov_start > fov", lambda: DesignSpec(fov=60.0, fov_start=70.0).fov_start)
    show("DesignSpec fov_start = fov", lambda: DesignSpec(fov=60.0, fov_start=60.0).fov_start)
    show("DesignSpec bfl > track", lambda: DesignSpec(bfl=8.0).bfl)
    show("DesignSpec stop = n", lambda: DesignSpec(stop=6).stop)
    show("DesignSpec wavelengths dup", lambda: DesignSpec(wavelengths=(0.55, 0.55, 0.55)).wavelengths)
    show("DesignSpec wavelengths nm", lambda: DesignSpec(wavelengths=(486.1, 587.6, 656.3)).wavelengths)
    show("DesignSpec sensor_aspect (0,1)", lambda: DesignSpec(sensor_aspect=(0.0, 1.0)))
    show("DesignSpec sensor_aspect (1,1000)", lambda: DesignSpec(sensor_aspect=(1.0, 1000.0)).sensor_resolution)
    show("DesignSpec sensor_pixels 1", lambda: DesignSpec(sensor_pixels=1).sensor_resolution)
    show("DesignSpec efl=focal*50", lambda: DesignSpec(efl=225.0).efl)
    show("DesignSpec efl=0.2*f", lambda: DesignSpec(efl=0.9).image_mapping())
    show("DesignSpec fov 179", lambda: DesignSpec(fov=179.0))
    show("DesignSpec name ''", lambda: DesignSpec(name="").name)
    show("DesignSpec name 'a/b'", lambda: DesignSpec(name="a/b").name)
    show("DesignSpec materials np.str_", lambda: DesignSpec(materials=tuple(np.array(["E48R", "OKP4"] * 3))).materials)
    show("DesignSpec primary -1", lambda: DesignSpec(primary=-1))
    s = DesignSpec()
    show("paper_stages n=0", lambda: [(st.fov, st.fnum) for st in paper_stages(s, n=0)])
    show("paper_stages steps=0 final=0", lambda: [(st.name, st.steps) for st in paper_stages(s, steps=0, final_steps=0)])
    show("paper_stages solver 'sgd'", lambda: paper_stages(s, solver="sgd"))
    show("paper_stages polish 'sgd' polish_steps 0", lambda: paper_stages(s, polish="sgd"))
    show("paper_stages final_loss 'foo'", lambda: paper_stages(s, final_loss="foo"))
    show("paper_stages curriculum 'no'", lambda: paper_stages(s, curriculum="no"))
    show("paper_stages regularize 0", lambda: paper_stages(s, regularize=0))
    show("sine_path(2.0, 2.8, 3)", lambda: sine_path(2.0, 2.8, 3))
    for kw in [dict(reg_weights=(-1.0, 1000.0, 40.0)), dict(reg_weights=(np.nan, 1.0, 1.0)),
               dict(reg_weights=(1.0, 1.0)), dict(reg_weights="abc"), dict(solver="sgd"),
               dict(polish="sgd"), dict(reference="chief"), dict(materials="free"),
               dict(material_catalogs=()), dict(material_catalogs=("NOPE",)),
               dict(material_catalogs="SCHOTT"), dict(steps=0, final_steps=0, polish_steps=0),
               dict(lr_c=0.0, lr_a=0.0, lr_d=0.0), dict(tolerance_nominal_weight=2.0),
               dict(tolerance_nominal_weight=1.0, tolerance_trials=0),
               dict(polish_rings=2, polish_steps=0), dict(population=2.0)]:
        show(f"DesignConfig({kw})", lambda: DesignConfig(**kw))
    from jaxlens.design import design
    show("design seeds []", lambda: design(s, [], DesignConfig(steps=1, final_steps=0, polish_steps=0), progress=False))
    show("design seeds [-1]", lambda: design(s, [-1], DesignConfig(steps=1, final_steps=0, polish_steps=0), progress=False))
    show("design seeds 3 (int)", lambda: design(s, 3, DesignConfig(steps=1, final_steps=0, polish_steps=0), progress=False))
    show("design config solver sgd", lambda: design(s, [0], DesignConfig(solver="sgd", steps=1, final_steps=0, polish_steps=0), progress=False))
    show("design config reg_weights (-1,...)", lambda: design(s, [0], DesignConfig(reg_weights=(-1.0, -1.0, -1.0), steps=1, final_steps=0, polish_steps=0), progress=False).params.c.shape)
    show("design config material_catalogs NOPE", lambda: design(s, [0], DesignConfig(materials="continuous", material_catalogs=("NOPE",), steps=1, final_steps=0, polish_steps=0), progress=False))


def edited(path, value, lens=cooke):
    return eqx.tree_at(path, lens, value)


@probe
def tree_at_lens():
    from jaxlens.analysis import angular_spot, rms_spot, seidel
    c = cooke
    cases = {
        "thickness[1] = -5": edited(lambda l: l.thickness, c.thickness.at[1].set(-5.0)),
        "thickness[2] = nan": edited(lambda l: l.thickness, c.thickness.at[2].set(jnp.nan)),
        "surface[1].c = nan": edited(lambda l: l.surfaces[1].c, jnp.asarray(jnp.nan)),
        "surface[1].k = inf": edited(lambda l: l.surfaces[1].k, jnp.asarray(jnp.inf)),
        "surface[1].semi_diameter = -2": edited(lambda l: l.surfaces[1].semi_diameter, jnp.asarray(-2.0)),
        "epd = -10": edited(lambda l: l.epd, jnp.asarray(-10.0)),
        "epd = 0": edited(lambda l: l.epd, jnp.asarray(0.0)),
        "fields = [0, 95]": edited(lambda l: l.fields, jnp.asarray([0.0, 95.0])),
        "wavelengths = [587.6]": edited(lambda l: l.wavelengths, jnp.asarray([0.4861, 587.6, 0.6563])),
        "thickness shape wrong": edited(lambda l: l.thickness, c.thickness[:-1]),
    }
    for name, lens in cases.items():
        show(f"efl [{name}]", lambda: jl.efl(lens))
        show(f"paraxial_data [{name}]", lambda: jl.paraxial_data(lens).efl)
        show(f"rms_spot [{name}]", lambda: rms_spot(lens).polychromatic)
        show(f"psf [{name}]", lambda: float(jl.psf(lens, 0.0, kernel_size=9, pixel_size=0.005).sum()))
        show(f"seidel [{name}]", lambda: seidel(lens).per_surface.sum(1))
        show(f"angular_spot [{name}]", lambda: angular_spot(lens).polychromatic)
        show(f"trace [{name}]", lambda: jl.trace(lens, jl.sampling.field_rays(lens, 0.0, jnp.zeros((1, 2)), 0.5876)).origin)
        show(f"save [{name}]", lambda: jl.save(lens, os.path.join(tempfile.mkdtemp(), "x.json")))


@probe
def afocal_and_surfaces():
    from jaxlens.analysis import angular_magnification, angular_spot
    tel = zoo.keplerian_telescope() if hasattr(zoo, "keplerian_telescope") else None
    show("zoo names", lambda: [n for n in dir(zoo) if not n.startswith("_")])
    lens = tel if tel is not None else cooke
    show("angular_magnification wl=10", lambda: angular_magnification(lens, 10.0))
    show("angular_magnification wl=[0.5,0.6]", lambda: angular_magnification(lens, [0.5, 0.6]))
    show("angular_magnification wl=[[0.5]]", lambda: angular_magnification(lens, [[0.5]]))
    show("angular_magnification wl='0.5'", lambda: angular_magnification(lens, "0.5"))
    show("angular_spot reference='Chief'", lambda: angular_spot(lens, reference="Chief"))
    show("angular_spot pupil outside disc", lambda: angular_spot(lens, pupil=jnp.array([[2.0, 0.0]])).polychromatic)
    show("angular_spot depth -5", lambda: angular_spot(lens, depth=-5.0).polychromatic)
    show("angular_spot depth 0", lambda: angular_spot(lens, depth=0.0).polychromatic)
    show("angular_spot fields 95", lambda: angular_spot(lens, fields=[95.0]).polychromatic)
    show("angular_spot fields []", lambda: angular_spot(lens, fields=[]).polychromatic)
    show("angular_spot wl []", lambda: angular_spot(lens, wavelengths=[]).polychromatic)
    for kw in [dict(norm_radius=0.0), dict(norm_radius=-1.0), dict(norm_radius=np.nan),
               dict(norm_radius=np.inf), dict(coeffs=np.zeros(231)), dict(coeffs=[np.nan]),
               dict(coeffs=np.zeros((2, 2))), dict(semi_diameter=-1.0), dict(c=np.nan),
               dict(k=np.inf)]:
        show(f"XYPolynomial({kw})", lambda: jl.XYPolynomial(**kw))
    for kw in [dict(norm_radius=0.0), dict(norm_radius=np.inf), dict(zernike=np.zeros(300)),
               dict(ordering="noll"), dict(extrapolate=1), dict(decenter_x=np.nan),
               dict(coeffs=[np.nan]), dict(semi_diameter=0.0)]:
        show(f"ZernikeSag({kw})", lambda: jl.ZernikeSag(**kw))
    for kw in [dict(norm_radius=0.0), dict(norm_radius=np.inf), dict(qtype="q"),
               dict(coeffs=[np.inf]), dict(coeffs=np.zeros((2, 2))), dict(c=np.nan)]:
        show(f"QTypeAsphere({kw})", lambda: jl.QTypeAsphere(**kw))
    from jaxlens.optics.toroidal import Toroidal
    for kw in [dict(c=np.nan), dict(k=np.inf), dict(cx=np.nan), dict(cx=np.inf),
               dict(coeffs=[np.nan]), dict(semi_diameter=-1.0), dict(semi_diameter=0.0),
               dict(c=0.5, semi_diameter=5.0), dict(cx=0.5, semi_diameter=5.0), dict(coeffs=())]:
        show(f"Toroidal({kw})", lambda: Toroidal(**kw))
    for kw in [dict(cx=np.nan), dict(kx=np.inf), dict(cx=0.5, semi_diameter=5.0),
               dict(semi_diameter=-1.0), dict(c=np.nan)]:
        show(f"Biconic({kw})", lambda: jl.Biconic(**kw))
    for kw in [dict(tan_x=np.nan), dict(tan_x=np.inf), dict(tan_y=1e9)]:
        show(f"TiltedPlane({kw})", lambda: jl.TiltedPlane(**kw))


@probe
def ranges():
    from jaxlens.analysis import encircled_energy, rms_spot, seidel, zernike_fit
    from jaxlens.imaging.psf import mtf
    c = cooke
    f2 = jl.get_material("F2")
    show("F2 range", lambda: f2.wavelength_range)
    show("F2.index(3.0)", lambda: f2.index(3.0))
    show("efl wl 3.0 (outside F2's LD)", lambda: jl.efl(c, 3.0))
    show("seidel wl 3.0", lambda: seidel(c, wavelength=3.0).per_surface.sum(1))
    show("seidel wl 0.2", lambda: seidel(c, wavelength=0.2).per_surface.sum(1))
    show("zernike_fit wl 3.0", lambda: zernike_fit(c, 0.0, wavelength=3.0).coefficients)
    show("rms_spot fields 25 (max 20)", lambda: rms_spot(c, fields=[25.0]).polychromatic)
    show("rms_spot fields 80 (max 20)", lambda: rms_spot(c, fields=[80.0]).polychromatic)
    show("psf field 80", lambda: float(jl.psf(c, 80.0, kernel_size=9, pixel_size=0.005).sum()))
    show("encircled field 80", lambda: encircled_energy(c, 80.0, [0.01]).fraction)
    show("psf depth 1 mm (inside?)", lambda: float(jl.psf(c, 0.0, depth=1.0, kernel_size=9, pixel_size=0.005).sum()))
    show("rms_spot depth 0.001", lambda: rms_spot(c, depth=0.001).polychromatic)
    show("rms_spot pupil outside disc", lambda: rms_spot(c, pupil=jnp.array([[0.0, 2.0]])).polychromatic)
    show("psf wavelength 3.0", lambda: float(jl.psf(c, 0.0, wavelength=3.0, kernel_size=9).sum()))
    show("psf kernel 1", lambda: jl.psf(c, 0.0, kernel_size=1).shape)
    show("psf kernel 100001", lambda: jl.psf(c, 0.0, kernel_size=100001).shape)
    show("psf pixel_size 10 (mm, huge)", lambda: float(jl.psf(c, 0.0, kernel_size=9, pixel_size=10.0).sum()))
    show("psf pixel_size 1e-9", lambda: float(jl.psf(c, 0.0, kernel_size=9, pixel_size=1e-9).sum()))
    show("mtf freqs negative", lambda: mtf(c, 0.0, frequencies=[-10.0, 10.0]))
    show("mtf freqs nan", lambda: mtf(c, 0.0, frequencies=[np.nan]))
    show("mtf freqs huge", lambda: mtf(c, 0.0, frequencies=[1e6]))
    show("mtf pixel_size 0", lambda: mtf(c, 0.0, pixel_size=0.0))


@probe
def images():
    from jaxlens.io import images as im
    show("images names", lambda: [n for n in dir(im) if not n.startswith("_")])
    d = tempfile.mkdtemp()
    for name, arr in [("nan", np.full((4, 4, 3), np.nan)), ("neg", -np.ones((4, 4, 3))),
                      ("2ch", np.ones((4, 4, 2))), ("1d", np.ones(4)), ("bool", np.ones((4, 4, 3), bool)),
                      ("complex", np.ones((4, 4, 3), complex)), ("uint16", np.full((4, 4, 3), 65535, np.uint16)),
                      ("float>1", np.full((4, 4, 3), 5.0)), ("empty", np.ones((0, 4, 3)))]:
        for fn in ("save_image", "write_image", "save"):
            if hasattr(im, fn):
                show(f"images.{fn} {name}", lambda: getattr(im, fn)(os.path.join(d, f"{name}.png"), arr))
        for fn in ("to_srgb", "srgb_to_linear", "linear_to_srgb"):
            if hasattr(im, fn):
                show(f"images.{fn} {name}", lambda: getattr(im, fn)(arr))
    show("scene unknown", lambda: im.scene("astronautt", (8, 8)))
    show("scene (0,8)", lambda: im.scene("astronaut", (0, 8)))
    show("scene (8.5,8)", lambda: im.scene("astronaut", (8.5, 8)))
    sensor = jl.Sensor((8, 8), 0.01)
    key = jax.random.key(0)
    for name, scene in [("nan", jnp.full((8, 8, 3), jnp.nan)), ("wrong shape", jnp.ones((9, 8, 3))),
                        ("2d", jnp.ones((8, 8))), ("4d", jnp.ones((1, 8, 8, 3))), ("bool", jnp.ones((8, 8, 3), bool)),
                        ("complex", jnp.ones((8, 8, 3), complex)), ("float16", jnp.ones((8, 8, 3), jnp.float16))]:
        show(f"render scene {name}", lambda: float(jl.render(cooke, scene, spp=1, key=key, sensor=sensor).sum()))


@probe
def tolerance():
    from jaxlens.analysis.tolerance import ToleranceModel, Tolerances
    for kw in [dict(radius_rel=-0.01), dict(radius_rel=np.nan), dict(thickness=-0.02), dict(decenter=-1.0),
               dict(tilt=90.0), dict(tilt=-1.0), dict(radius_rel=2.0), dict(thickness=1e6)]:
        show(f"Tolerances({kw})", lambda: Tolerances(**kw))
    for kw in [dict(field_weights=[1.0, -1.0, 1.0]), dict(field_weights=[0.0, 0.0, 0.0]),
               dict(field_weights=[1.0, 1.0]), dict(field_weights=[np.nan, 1, 1]),
               dict(fields=[95.0]), dict(fields=[25.0]), dict(wavelengths=[3.0]), dict(batch=0),
               dict(pupil=jnp.array([[2.0, 0.0]])), dict(apertures="none")]:
        show(f"ToleranceModel({kw})", lambda: ToleranceModel(cooke, **kw))
    m = ToleranceModel(cooke)
    for name in ("monte_carlo", "sensitivity"):
        fn = getattr(m, name, None)
        show(f"{name} signature", lambda: __import__("inspect").signature(fn))


def cli(args, cwd=None):
    r = subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd or ROOT,
                       env={**os.environ, "PYTHONPATH": ROOT}, timeout=600)
    tail = (r.stderr.strip().splitlines() or [""])[-1][:240]
    return f"rc={r.returncode} {tail}"


@probe
def clis():
    d = tempfile.mkdtemp()
    f = os.path.join(d, "afile")
    open(f, "w").write("x")
    ro = os.path.join(d, "ro")
    os.mkdir(ro)
    os.chmod(ro, 0o500)
    for args in [
        ["-m", "jaxlens", "report", COOKE_ZMX, "--fields", "95"],
        ["-m", "jaxlens", "report", COOKE_ZMX, "--wavelengths", "587.6"],
        ["-m", "jaxlens", "report", COOKE_ZMX, "--fields", "nan"],
        ["-m", "jaxlens", "report", os.path.join(d, "none.zmx")],
        ["-m", "jaxlens.experiments.classical", "--smoke", "--fnum", "-1", "--out", os.path.join(d, "c1")],
        ["-m", "jaxlens.experiments.classical", "--smoke", "--out", f],
        ["-m", "jaxlens.experiments.classical", "--smoke", "--out", os.path.join(ro, "x")],
        ["-m", "jaxlens.experiments.classical", "--help"],
        ["-m", "jaxlens.experiments.edof", "--help"],
        ["-m", "jaxlens.experiments.tolerance", COOKE_ZMX, "--trials", "0", "--out", os.path.join(d, "t")],
        ["-m", "jaxlens.experiments.tolerance", COOKE_ZMX, "--out", f],
        ["-m", "jaxlens.experiments.tolerance", COOKE_ZMX, "--out", os.path.join(ro, "x")],
        ["-m", "benchmarks", "--help"],
    ]:
        show(" ".join(a if not a.startswith(d) else a.replace(d, "$D") for a in args), lambda: cli(args))


def quick(args, limit=25):
    """rc and the last stderr line, or STARTED when the run was still going after ``limit``
    seconds (the option was not refused before the work)."""
    try:
        r = subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=ROOT,
                           env={**os.environ, "PYTHONPATH": ROOT}, timeout=limit)
    except subprocess.TimeoutExpired:
        return "STARTED (not refused within the limit)"
    tail = (r.stderr.strip().splitlines() or [""])[-1][:240]
    return f"rc={r.returncode} {tail}"


@probe
def cli_options():
    d = tempfile.mkdtemp()
    c = ["-m", "jaxlens.experiments.classical", "--smoke", "--quiet", "--out"]
    for i, opts in enumerate([
        ["--fov", "200"], ["--fov", "0"], ["--elements", "0"], ["--elements", "40"],
        ["--sensor-diagonal", "-1"], ["--track", "0.5"], ["--bfl", "nan"], ["--stop", "-1"],
        ["--stop", "9"], ["--fov-start", "100"], ["--asphere-terms", "50"], ["--seeds", "0"],
        ["--seed-list", "1,1"], ["--seed-list", "a"], ["--first-seed", "-3"],
        ["--steps", "-1"], ["--steps", "nan"], ["--steps", "0"], ["--polish-steps", "-1"],
        ["--tolerance-aware", "-1"], ["--population", "0"], ["--devices", "0"],
        ["--devices", "99"], ["--tolerance-trials", "-5"], ["--tolerance-threshold", "0"],
        ["--ablation-seeds", "0"], ["--columns", "nope"], ["--materials", "E48R"],
        ["--materials", "N-BK7X,OKP4,E48R,OKP4,E48R,OKP4"], ["--select-materials", "free"],
        ["--material-catalogs", "NOPE"], ["--no-plots", "--no-render"],
    ]):
        show("classical " + " ".join(opts), lambda: quick([*c, os.path.join(d, f"c{i}"), *opts]))
    e = ["-m", "jaxlens.experiments.edof", "--smoke", "--quiet", "--out"]
    for i, opts in enumerate([
        ["--lenses", "nope"], ["--lenses", ""], ["--seeds", "-1"], ["--seeds", "1,1"],
        ["--time-limit", "-5"], ["--time-limit", "0"], ["--steps", "-1"], ["--batch", "0"],
        ["--tile", "0"], ["--tile", "7"], ["--kernel", "0"], ["--kernel", "30"],
        ["--binning", "0"], ["--pupil", "0"], ["--eval-pupil", "1"], ["--lens-every", "0"],
        ["--lr-net", "-1"], ["--lr-lens", "nan"], ["--w-sim", "-1"], ["--w-raw", "inf"],
        ["--photons", "0"], ["--read-noise", "-1"], ["--width", "0"], ["--enc", "1,-1"],
        ["--middle", "-1"], ["--dec", "1"], ["--n-odd", "-1"], ["--cubic-floor", "2"],
        ["--hybrid-floor", "-1"], ["--context", "-1"], ["--max-crops", "0"],
        ["--train-dir", d + "/none"], ["--test-dir", d + "/none"], ["--resume"],
        ["--checkpoint", d + "/ck", "--resume"], ["--record", d + "/none.json"],
    ]):
        show("edof " + " ".join(o.replace(d, "$D") for o in opts),
             lambda: quick([*e, os.path.join(d, f"e{i}"), *opts]))


if __name__ == "__main__":
    for p in PROBES:
        if len(sys.argv) < 2 or sys.argv[1] in p.__name__:
            print(f"== {p.__name__}")
            try:
                p()
            except Exception:  # noqa: BLE001
                traceback.print_exc()
