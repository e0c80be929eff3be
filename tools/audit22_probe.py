# ruff: noqa: E501, B023, E731
"""Round-22 bad-input probes: the table of ``tools/audit21_probe.py`` (probe | outcome | what
happened) for what rounds 9-21 left: the tolerance CLI's options (``--threshold`` had no upper
bound, ``--out ''`` failed after the analysis), wavelengths beyond a dispersion formula's
poles (a Sellmeier glass past its infrared resonance gave a finite, meaningless index), and
the public entry points no round had probed (``analysis.afocal``, ``plot``'s sample counts,
``design.ImageObjective``/``Stage``, ``experiments.tolerance``'s functions, ``nets``, ``zoo``).

Before (main at 68be9c2, ``AUDIT22_BEFORE=1``: 73 probes) and after (branch audit22: 81),
``PYTHONPATH=<tree> python tools/audit22_probe.py`` under ``ulimit -v 16000000``, one 2-core
machine:
    before: clear error 38, crash 5, ok 6, silent wrong 20, vague error 4
    after:  clear error 67, ok 6, silent wrong 8   (the same 73 probes: clear 59, ok 6, silent 8)
(``AUDIT22_BEFORE=1`` leaves out the 8 probes that on main start minutes of work or a huge
allocation: ``--threshold 1e300``/``1e6``/``0.006`` and ``--out ''`` ran the whole tolerance
analysis, ``--tolerance-threshold 1e300`` a design run, ``plot_layout(n_rays=10**9)`` asked
for 8 GB.)

Left after (the 8 "silent wrong" rows): a bare dispersion formula's own ``index`` still
evaluates anywhere (past a resonance: N-BK7's Sellmeier gives 3.05 at 11 µm, NaN at its pole).
A lens refuses such wavelengths (``checks.material_range`` narrows a formula without a stated
range to the window between its poles around the d line), but ``index`` itself cannot: a
``CatalogMaterial`` calls its model's ``index`` inside its own stated range, and the shipped
SILICON's (1.36-11 µm) lies beyond its formula's 1.13 µm resonance (catalog.py, another
helper's: it would call the model's unchecked formula). And ``Lens(...)`` keeps wavelengths
outside its glasses' data (lens.py, another helper's; the analyses refuse them).

Run: PYTHONPATH=$PWD python tools/audit22_probe.py [filter]
"""

import os
import sys
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

cooke = zoo.cooke_triplet()
HUGE = 10**12
TMP = tempfile.mkdtemp()
BEFORE = os.environ.get("AUDIT22_BEFORE") == "1"


def long(name, fn, *words, **kw):
    """A probe that, on main, starts minutes to hours of work (an analysis or a design run
    that the bad value reaches) or a huge allocation: left out before."""
    if not BEFORE:
        probe(name, fn, *words, **kw)


def cli(f):
    f.cli = True
    return f


# ----------------------------------------------------------------------------- tolerance CLI
def tolerance_cli():
    from jaxlens.experiments import classical
    from jaxlens.experiments import tolerance as tol
    design = os.path.join(os.path.dirname(__file__), "..", "experiments", "classical", "designs", "seed_13.zmx")
    t = lambda *a, out=None: cli(lambda: tol.main([design, "--out", os.path.join(TMP, "t") if out is None else out, *a]))
    long("tolerance --threshold 1e300", t("--threshold", "1e300"), "--threshold", "µm")
    long("tolerance --threshold 1e6 (a metre of RMS)", t("--threshold", "1e6"), "--threshold", "µm")
    long("tolerance --threshold 0.006 (mm given for µm)", t("--threshold", "0.006"), "--threshold", "µm")
    probe("tolerance --threshold nan", t("--threshold", "nan"), "--threshold")
    probe("tolerance --threshold ''", t("--threshold", ""), "--threshold")
    probe("tolerance --trials ''", t("--trials", ""), "--trials")
    probe("tolerance --trials 1.5", t("--trials", "1.5"), "--trials")
    probe("tolerance --seed -1", t("--seed", "-1"), "--seed")
    probe("tolerance --decenter=-1e-300", t("--decenter=-1e-300"), "--decenter", "mm")
    long("tolerance --out '' (found after the analysis)", t(out=""), "--out")
    f = os.path.join(TMP, "afile")
    open(f, "w").close()
    probe("tolerance --out under a file", t(out=os.path.join(f, "sub")), "--out")
    probe("tolerance design '' (empty)", cli(lambda: tol.main(["", "--out", os.path.join(TMP, "t")])), "design")
    probe("tolerance design a folder", cli(lambda: tol.main([TMP, "--out", os.path.join(TMP, "t")])), "design")
    probe("tolerance design (no extension)", cli(lambda: tol.main([f, "--out", os.path.join(TMP, "t2")])), "extension", ".zmx")
    c = lambda *a: cli(lambda: classical.main([*a, "--out", os.path.join(TMP, "c"), "--quiet"]))
    long("classical --tolerance-threshold 1e300", c("--tolerance-threshold", "1e300"), "--tolerance-threshold", "µm")
    long("classical --tolerance-threshold 0.006", c("--tolerance-threshold", "0.006"), "--tolerance-threshold", "µm")
    from jaxlens.design.spec import DesignSpec
    probe("check_design(None)", lambda: tol.check_design(None, DesignSpec()), "lens")
    probe("check_design(lens, None)", lambda: tol.check_design(cooke, None), "spec")
    seed = jl.load(design)
    probe("design_model grid 10**6", lambda: tol.design_model(seed, DesignSpec(), grid=10**6), "grid", "257")
    probe("design_model(cooke) (another spec)", lambda: tol.design_model(cooke, DesignSpec()), "entrance pupil", "mm")
    long("analyse_design trials 0", lambda: tol.analyse_design(seed, DesignSpec(), trials=0), "trials")
    probe("write_report(out='')", lambda: tol.write_report({"a": 1}, ""), "out")


# ----------------------------------------------------------------------------- glass ranges
def glass_ranges():
    import dataclasses

    from jaxlens.optics import materials as M
    bk7 = jl.get_material("N-BK7")
    raw = bk7.model  # N-BK7's Sellmeier, poles at 0.0775, 0.142 and 10.18 µm
    probe("Sellmeier(N-BK7).index(11 µm) (past its 10.2 µm pole)", lambda: raw.index(11.0), "11", "µm", "pole")
    probe("Sellmeier(N-BK7).index(10.18 µm) (at its pole)", lambda: raw.index(10.176), "µm", "pole")
    probe("Sellmeier(N-BK7).index(0.12 µm) (between UV poles)", lambda: raw.index(0.16), "µm")
    probe("Sellmeier(N-BK7).index(2.0) (control)", lambda: float(raw.index(2.0)), good=True)
    probe("Herzberger index 0.16 µm (its pole 0.167 µm)", lambda: M.Herzberger(np.array([1.5, 0.005, 0, 0, 0, 0])).index(0.16), "µm", "pole")
    probe("Handbook1 index beyond its pole", lambda: M.Handbook1(np.array([2.3, 0.01, 0.05, 0.01])).index(0.2), "µm", "pole")
    probe("Sellmeier2 index at its pole", lambda: M.Sellmeier2(np.array([0.0, 1.0, 0.1, 0.0, 5.0])).index(5.0), "µm", "pole")
    probe("Sellmeier4 index beyond its pole", lambda: M.Sellmeier4(np.array([1.0, 1.0, 0.01, 1.0, 25.0])).index(6.0), "µm", "pole")
    lens_raw = dataclasses.replace(cooke, materials=[raw if isinstance(m, M.Tabulated) else m for m in cooke.materials], wavelengths=(11.0,), primary=0)
    probe("efl(lens of raw Sellmeier N-BK7 at 11 µm)", lambda: jl.efl(lens_raw), "11", "µm")
    lens_cat = dataclasses.replace(cooke, materials=[bk7 if isinstance(m, M.Tabulated) else m for m in cooke.materials])
    probe("Lens(N-BK7, wavelengths (2.6,)) built (lens.py: not this round's)", lambda: dataclasses.replace(lens_cat, wavelengths=(2.6,), primary=0).wavelengths, "2.6", "µm")
    probe("efl(Lens(N-BK7) at 2.6 µm)", lambda: jl.efl(dataclasses.replace(lens_cat, wavelengths=(2.6,), primary=0)), "2.6", "0.3", "2.5")
    probe("ModelGlass(1.5, 60).index(25 µm) (generic range)", lambda: float(M.ModelGlass(1.5, 60.0).index(25.0)), good=True)
    probe("jit(raw.index)(11.0) (control: traced, unchecked)", lambda: float(jax.jit(raw.index)(jnp.asarray(11.0))), good=True)
    probe("abbe_number(Sellmeier with an IR pole at 0.5 µm)", lambda: M.abbe_number(M.Sellmeier(np.array([1.0]), np.array([0.25]))), "no finite index", "Abbe")


# ----------------------------------------------------------------------------- afocal, plot
def afocal_plot():
    from jaxlens import plot as P
    from jaxlens.analysis import afocal as A
    probe("angular_magnification(cooke) (documented: defined for any lens)", lambda: float(A.angular_magnification(cooke)), good=True)
    probe("angular_spot(cooke, reference='x')", lambda: A.angular_spot(cooke, reference="x"), "reference")
    long("plot_layout n_rays 10**9", lambda: P.plot_layout(cooke, n_rays=10**9), "n_rays")
    probe("plot_layout n_rays 0", lambda: P.plot_layout(cooke, n_rays=0), "n_rays")
    probe("plot_spots rings 10**6", lambda: P.plot_spots(cooke, rings=10**6), "rings")
    probe("plot_ray_fans n 10**9", lambda: P.plot_ray_fans(cooke, n=10**9), "n")
    probe("plot_opd_fans n 1", lambda: P.plot_opd_fans(cooke, n=1), "n")
    probe("plot_wavefront grid 10**5", lambda: P.plot_wavefront(cooke, grid=10**5), "grid")
    probe("plot_rms_map all nan", lambda: P.plot_rms_map(np.full((4, 4), np.nan), (4.0, 3.0)), "rms_um", "no finite")
    probe("plot_rms_map one nan (control: drawn, counted)", lambda: P.plot_rms_map(np.r_[np.nan, np.ones(3)], (4.0, 3.0)).axes[0].get_title(), good=True)
    probe("plot_rms_map sensor_size (-1, 1)", lambda: P.plot_rms_map(np.ones((4, 4)), (-1.0, 1.0)), "sensor_size", "mm")
    probe("plot_rms_map 5 values (not n²)", lambda: P.plot_rms_map(np.ones(5), (4.0, 3.0)), "rms_um", "[n, n]")
    probe("plot_image uint8 (sRGB codes)", lambda: P.plot_image(np.full((4, 4, 3), 200, np.uint8)), "img", "integer")
    probe("plot_image [4, 4, 4]", lambda: P.plot_image(np.zeros((4, 4, 4))), "img", "[H, W, 3]")
    probe("plot_tolerance_histogram({})", lambda: P.plot_tolerance_histogram({}), "mc")
    probe("plot_progress([])", lambda: P.plot_progress([]), "history")
    probe("plot_image(empty)", lambda: P.plot_image(np.zeros((0, 0, 3))), "img")
    probe("plot_image(nan)", lambda: P.plot_image(np.full((4, 4, 3), np.nan)), "img")
    probe("plot_mtf frequencies [-1]", lambda: P.plot_mtf(cooke, frequencies=[-1.0, 10.0]), "frequencies")
    probe("plot_encircled_energy max_radius -1", lambda: P.plot_encircled_energy(cooke, max_radius=-1.0), "max_radius")
    probe("plot_layout fields [95]", lambda: P.plot_layout(cooke, [95.0]), "field")
    probe("save(fig, '')", lambda: P.save(P.plot_image(np.zeros((4, 4, 3))), ""), "path")
    probe("save(None, 'x.png')", lambda: P.save(None, os.path.join(TMP, "x.png")), "fig", "Figure")


# ----------------------------------------------------------------------------- design, nets, zoo
def design_nets_zoo():
    from jaxlens import nets as N
    from jaxlens.design import ImageObjective, Stage, sensor_field_grid
    from jaxlens.design.spec import DesignSpec
    probe("Stage fov 200", lambda: Stage("a", fov=200.0, fnum=2.0, steps=10), "fov", "deg")
    probe("Stage fnum 0", lambda: Stage("a", fov=60.0, fnum=0.0, steps=10), "fnum")
    probe("Stage steps 10**12", lambda: Stage("a", fov=60.0, fnum=2.0, steps=HUGE), "steps")
    probe("Stage solver 'x'", lambda: Stage("a", fov=60.0, fnum=2.0, steps=10, solver="x"), "solver")
    probe("Stage lr nan", lambda: Stage("a", fov=60.0, fnum=2.0, steps=10, lr=float("nan")), "lr")
    probe("Stage beta -1", lambda: Stage("a", fov=60.0, fnum=2.0, steps=10, beta=-1.0), "beta")
    probe("sensor_field_grid(spec, 10**6)", lambda: sensor_field_grid(DesignSpec(), 10**6), "257")
    from jaxlens.design import RayLoss, parameterization
    from jaxlens.design.losses import Objective
    spec = DesignSpec()
    ray = Objective(parameterization(spec), RayLoss.make(3, 2, [0.5876], spec.sensor_size), jnp.ones((12, 2)))
    probe("ImageObjective spp 0", lambda: ImageObjective(ray, jnp.ones((8, 8, 3)), jl.Sensor((8, 8), 0.01), spp=0), "spp", "65536")
    probe("ImageObjective ray None", lambda: ImageObjective(None, jnp.ones((8, 8, 3)), jl.Sensor((8, 8), 0.01)), "ray", "Objective")
    probe("ImageObjective scene nan", lambda: ImageObjective(ray, jnp.full((8, 8, 3), jnp.nan), jl.Sensor((8, 8), 0.01)), "scene", "finite")
    probe("nets.simple_gate odd channels", lambda: N.simple_gate(jnp.ones((2, 3))), "channels")
    probe("nets.num_parameters(None)", lambda: N.num_parameters(None), "model")
    probe("Stage steps 10**5 (control)", lambda: Stage("a", fov=60.0, fnum=2.0, steps=10**5).steps, good=True)
    probe("zoo.cooke_triplet(clip='no')", lambda: zoo.cooke_triplet(clip="no"), "clip")


# ----------------------------------------------------------------------------- report CLI
def report_cli():
    from jaxlens import __main__ as MM
    f = os.path.join(TMP, "c.json")
    jl.save(cooke, f)
    r = lambda *a: cli(lambda: MM.main(["report", f, *a]))
    probe("report --wavelengths 2.6 (the glass tables end at 0.657)", r("--wavelengths", "2.6"), "2.6", "µm")
    probe("report --wavelengths 0", r("--wavelengths", "0"), "--wavelengths")
    probe("report --fields 90", r("--fields", "90"), "--fields")
    probe("report --fields nan", r("--fields", "nan"), "--fields")
    probe("report --plot ''", r("--plot", ""), "--plot")
    import benchmarks.render_speed as RS
    import benchmarks.run as BR
    probe("python -m benchmarks --out '' (Path('') is the cwd)", cli(lambda: BR.main(["--out", "", "--smoke"])), "--out", "empty")
    probe("benchmarks.render_speed --out ''", cli(lambda: RS.main(["--out", ""])), "--out", "empty")
    probe("report lens ''", cli(lambda: MM.main(["report", ""])), "lens")


run((tolerance_cli, glass_ranges, afocal_plot, design_nets_zoo, report_cli))
