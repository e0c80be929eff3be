# ruff: noqa: E501, B023, E731
"""Round-21 bad-input probes: throw malformed input at what rounds 9-20 did not reach and print
a table: probe | outcome | what happened (the outcomes of ``tools/audit20_probe.py``: clear
error, vague error, crash, silent wrong, ok).

Areas: two of the three gaps left by round 20 (the classical CLI's ``--steps 1e12``, render
tiles whose memory grows as patch² × spp without bound; the third, ``Lens(...)`` keeping a
primary wavelength outside its glasses' data, is left: the .zmx and JSON loaders build the
Lens before they refuse such a wavelength with the file's line, and a refusal in ``Lens``
would take the line from their messages), then what no round had probed: the design solvers' options
(``Adam``, ``LevenbergMarquardt``, ``DampedLeastSquares``, ``LBFGSB``), the design helpers
(``HullMaterials``, ``TableMaterials``, ``RayLoss.make``, ``random_params``,
``parameterization``, ``DesignConfig`` step counts), ``zernike_nm``, ``tolerance.perturb``, the
report CLI's field and wavelength counts and ``--config``, the EDoF CLI's sizes and counts,
and the benchmark CLIs' counts (rays, chunks, repeats, seeds, sizes, spp).

Before (main at 4218c6b, ``AUDIT21_BEFORE=1``: 37 probes) and after (branch audit21: 73),
``PYTHONPATH=$PWD python tools/audit21_probe.py`` under ``ulimit -v 16000000`` (so that
a huge allocation fails fast), one 2-core machine:
    before: clear error 1, crash 6, ok 4, silent wrong 20, vague error 6
    after:  clear error 67, ok 4, vague error 2   (the same 37 probes: clear 31, ok 4, vague 2)
(``AUDIT21_BEFORE=1`` leaves out the 36 probes that on main start hours of work, exhaust
memory after the work has begun, or abort the process: a design, training or benchmark run
that the bad count reaches, render tiles of hundreds of GiB, ``zernike_nm(10**30)``, 100 000
report fields; each of them was seen to pass main's checks by parsing or building alone.
Left after: ``stop_radius(lens, 587.6)`` takes the wavelength for its ``stop_size``
argument (imaging/sampling.py, another helper's), and the tolerance CLI's ``--threshold``
has no upper bound, so 1e300 µm reaches the design file, refused for its own reason.)

Run: PYTHONPATH=$PWD python tools/audit21_probe.py [filter]
"""

import os
import sys
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

cooke = zoo.cooke_triplet()
BEFORE = os.environ.get("AUDIT21_BEFORE") == "1"
HUGE = 10**12


def cli(f):
    f.cli = True
    return f


def long(name, fn, *words, **kw):
    """A probe that, on main, starts hours of work or aborts the process: left out before."""
    if not BEFORE:
        probe(name, fn, *words, **kw)


def argv_main(main, argv):
    """Run a ``main()`` that reads sys.argv (the EDoF CLI)."""
    def call():
        old = sys.argv
        sys.argv = ["edof", *argv]
        try:
            return main()
        finally:
            sys.argv = old
    return cli(call)


# ----------------------------------------------------------------------------- round 20's gaps
def round20_gaps():
    import dataclasses

    from jaxlens.experiments import classical
    from jaxlens.imaging import render, tiled
    # Lens(...) keeps a primary wavelength outside its glasses' data: the loaders build the
    # Lens first and then refuse such a wavelength naming the file's line (zmx WAVM), which a
    # check in Lens would pre-empt (see the round-21 report). The analyses refuse it.
    probe("Lens wavelengths (486.1, 587.6, 656.3) (nm)", lambda: dataclasses.replace(cooke, wavelengths=(486.1, 587.6, 656.3)), "wavelengths", "µm", "nm")
    probe("jit(Lens wavelengths) (control: traced, unchecked)",
          lambda: jax.jit(lambda w: dataclasses.replace(cooke, wavelengths=w).primary_wavelength)(jnp.array([0.4861, 0.5876, 0.6563])), good=True)
    tmp = tempfile.mkdtemp()
    c = cli(lambda *a: classical.main([*a, "--out", os.path.join(tmp, "c"), "--quiet"]))
    long("classical --steps 1e12", cli(lambda: c("--steps", "1e12")), "--steps", "100000 steps")
    long("classical --steps 51", cli(lambda: c("--steps", "51")), "--steps", "50")
    probe("classical --seeds 10**12 (a list of 10**12 seeds)", cli(lambda: c("--seeds", str(HUGE))), "--seeds", "1024", "designs")
    long("classical --polish-steps 10**9", cli(lambda: c("--polish-steps", str(10**9))), "--polish-steps", "100000", "steps")
    long("classical --ablation --ablation-seeds 10**8", cli(lambda: c("--ablation", "--ablation-seeds", str(10**8))), "--ablation-seeds", "1024")
    s = jl.Sensor((64, 64), 0.005)
    scene = np.ones((64, 64, 3))
    key = jax.random.key(0)
    long("render spp 65536 patch 64 (516 GiB a tile)", lambda: jl.render(cooke, scene, sensor=s, spp=65536, key=key), "patch", "spp", "GiB", "at most")
    long("render spp 16 patch 4096", lambda: jl.render(cooke, scene, sensor=s, spp=16, patch=4096, key=key), "patch", "GiB")
    long("render PSFRender(4095) spp 256", lambda: jl.render(cooke, scene, sensor=s, spp=256, method=render.PSFRender(kernel_size=4095), key=key), "kernel_size", "spp", "GiB")
    long("psf_points 10**6 positions", lambda: tiled.psf_points(cooke, np.zeros((1000, 1000, 2)), None, wavelengths=[0.5876], kernel_size=9, pixel_size=0.005), "positions", "GiB")
    probe("render spp 4 patch 16 (control)", lambda: jl.render(cooke, np.ones((16, 16, 3)), sensor=jl.Sensor((16, 16), 0.02), spp=4, patch=16, key=key).shape, good=True)


# ----------------------------------------------------------------------------- solvers
def solvers():
    from jaxlens.design import solvers as S
    from jaxlens.design.params import LensParams
    lrs = LensParams(c=jnp.asarray(0.05), a=jnp.asarray(0.05), k=jnp.asarray(0.0), d=jnp.asarray(0.05))
    f = lambda p, a: (p.c, None)
    probe("Adam lrs.c -1 (ascent)", lambda: S.Adam(f, LensParams(c=-1.0, a=0.1, k=0.0, d=0.1)), "lrs.c", "learning rate")
    probe("Adam b1 1.0", lambda: S.Adam(f, lrs, b1=1.0), "b1", "[0, 1)")
    probe("Adam eps 0", lambda: S.Adam(f, lrs, eps=0.0), "eps")
    probe("Adam residual_fn None", lambda: S.Adam(None, lrs), "residual_fn")
    probe("Adam lrs 0.1 (not a LensParams)", lambda: S.Adam(f, 0.1), "lrs", "LensParams")
    probe("DampedLeastSquares inner 10**9", lambda: S.DampedLeastSquares(f, inner=10**9), "inner", "100000")
    probe("DampedLeastSquares lam0 -1", lambda: S.DampedLeastSquares(f, lam0=-1.0), "lam0", "damping")
    probe("LevenbergMarquardt rtol nan", lambda: S.LevenbergMarquardt(f, rtol=float("nan")), "rtol")
    probe("LevenbergMarquardt inner 0", lambda: S.LevenbergMarquardt(f, inner=0), "inner")
    probe("LBFGSB history 0", lambda: S.LBFGSB(f, lrs, lrs, history=0), "history")
    probe("LBFGSB lower nan", lambda: S.LBFGSB(f, LensParams(c=np.nan, a=0.0, k=0.0, d=0.0), lrs), "lower.c")
    probe("Adam (control)", lambda: type(S.Adam(f, lrs)).__name__, good=True)


# ----------------------------------------------------------------------------- design helpers
def design_helpers():
    from jaxlens.design import DesignSpec
    from jaxlens.design import init as I
    from jaxlens.design import losses as L
    from jaxlens.design import materials as M
    from jaxlens.design.multistart import DesignConfig
    spec = DesignSpec()
    probe("HullMaterials corner Vd nan", lambda: M.HullMaterials(jnp.array([[1.5, np.nan], [1.6, 40.0], [1.7, 30.0]])), "corners", "Vd")
    probe("HullMaterials corners shape (3,)", lambda: M.HullMaterials(jnp.array([1.5, 1.6, 1.7])).nd_vd(jnp.zeros((2, 3))), "corners", "[V, 2]")
    probe("HullMaterials corner nd 0.5", lambda: M.HullMaterials(jnp.array([[0.5, 50.0], [1.6, 40.0], [1.7, 30.0]])), "corners nd", "refractive index")
    probe("TableMaterials wavelengths in nm", lambda: M.TableMaterials(jnp.array([486.1, 587.6, 656.3])), "wavelengths", "µm", "nm")
    probe("TableMaterials wavelengths nan", lambda: M.TableMaterials(jnp.array([np.nan, 0.5876])), "wavelengths", "µm")
    probe("RayLoss.make wavelengths in nm", lambda: L.RayLoss.make(3, 2, [486.1, 587.6], (4.0, 6.0)), "wavelengths", "µm")
    probe("RayLoss.make n_fields 0 (an empty loss)", lambda: L.RayLoss.make(0, 2, [0.5876], (4.0, 6.0)), "n_fields", "257")
    long("RayLoss.make n_fields 10**9", lambda: L.RayLoss.make(10**9, 2, [0.5876], (4.0, 6.0)), "n_fields", "257")
    probe("RayLoss.make rings 0 (one ray a field)", lambda: L.RayLoss.make(3, 0, [0.5876], (4.0, 6.0)), "rings", "64")
    probe("random_params key 'x'", lambda: I.random_params(spec, "x"), "random_params", "key")
    probe("random_params dtype int32", lambda: I.random_params(spec, jax.random.PRNGKey(0), jnp.int32), "random_params", "dtype")
    probe("parameterization dtype int32", lambda: I.parameterization(spec, jnp.int32), "dtype")
    probe("parameterization spec None", lambda: I.parameterization(None), "spec", "DesignSpec")
    probe("DesignConfig steps 10**9", lambda: DesignConfig(steps=10**9), "steps", "100000")
    probe("DesignConfig().scaled(inf)", lambda: DesignConfig().scaled(float("inf")), "factor")
    probe("RayLoss.make (control)", lambda: L.RayLoss.make(3, 2, [0.5876], (4.0, 6.0)).n_fields, good=True)


# ----------------------------------------------------------------------------- analysis, report
def analysis():
    from jaxlens import __main__ as M
    from jaxlens.analysis import tolerance as T
    from jaxlens.analysis import zernike as Z
    from jaxlens.imaging import sampling
    long("zernike_nm j 10**30", lambda: Z.zernike_nm(10**30), "j", "65536")
    probe("tolerance.perturb p 1.0", lambda: T.perturb(cooke, 1.0, jnp.ones(6)), "perturb", "Perturbation")
    probe("tolerance.zero_perturbation(None)", lambda: T.zero_perturbation(None), "lens")
    probe("stop_radius wavelength 587.6 (sampling.py: not this round's)", lambda: sampling.stop_radius(cooke, 587.6), "wavelength")
    tmp = tempfile.mkdtemp()
    f = os.path.join(tmp, "c.json")
    jl.save(cooke, f)
    r = cli(lambda *a: M.main(["report", f, *a]))
    long("report --fields with 100000 values", cli(lambda: r("--fields", *["1"] * 100000)), "--fields", "64")
    long("report --wavelengths with 1000 values", cli(lambda: r("--wavelengths", *[f"{0.5 + i * 1e-5:.5f}" for i in range(1000)])), "--wavelengths", "64")
    probe("report --config 0 (a .json lens)", cli(lambda: r("--config", "0")), "--config", "1-based")
    probe("report --config -1", cli(lambda: r("--config", "-1")), "--config", "1-based")
    from jaxlens.experiments import tolerance as tol
    t = cli(lambda *a: tol.main([f, "--out", os.path.join(tmp, "o"), *a]))
    probe("tolerance --threshold 1e300 (no upper bound: reaches the file)", cli(lambda: t("--threshold", "1e300")), "--threshold")


# ----------------------------------------------------------------------------- EDoF CLI
def edof():
    from jaxlens.experiments.edof import cli as E
    tmp = tempfile.mkdtemp()
    e = lambda *a: argv_main(E.main, [*a, "--out", os.path.join(tmp, "e"), "--quiet"])
    for a, words in ((("--steps", str(HUGE)), ("--steps", "100000", "steps")),
                     (("--pupil", "100000"), ("--pupil", "4096", "rays per side")),
                     (("--eval-pupil", "100000"), ("--eval-pupil", "4096")),
                     (("--batch", str(10**9)), ("--batch", "1024", "patches")),
                     (("--n-odd", "0"), ("--n-odd", "[1, 10]")),
                     (("--enc", "1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1", "--dec", "1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1"), ("--enc", "6")),
                     (("--middle", "100000"), ("--middle", "64", "blocks")),
                     (("--seeds", ",".join(map(str, range(2000)))), ("--seeds", "1024")),
                     (("--kernel", "100001"), ("--kernel", "4096", "pixels")),
                     (("--width", "100000"), ("--width", "1024", "channels")),
                     (("--context", str(10**9)), ("--context", "16384", "pixels")),
                     (("--lens-every", str(HUGE)), ("--lens-every", "100000"))):
        long(f"edof {' '.join(a)[:40]}", e(*a), *words)


# ----------------------------------------------------------------------------- benchmarks
def benchmarks():
    import benchmarks.design_step as d
    import benchmarks.fast_path as fp
    import benchmarks.grad_levers as g
    import benchmarks.render_memory as m
    import benchmarks.render_speed as r
    import benchmarks.vjp_probe as v
    for mod, a, words in ((r, ("--size", "1000000"), ("--size", "16384", "pixels")),
                          (r, ("--spp", str(10**9)), ("--spp", "65536")),
                          (r, ("--repeats", str(10**9)), ("--repeats", "1000")),
                          (m, ("--worker", "--trace-rays", str(HUGE)), ("--trace-rays", "100000000", "rays")),
                          (m, ("--checkpoint", "5"), ("--checkpoint", "[0, 1]")),
                          (m, ("--size", "1000000"), ("--size", "16384")),
                          (d, ("--rays", str(HUGE)), ("--rays", "100000000")),
                          (d, ("--seeds", "100000"), ("--seeds", "1024")),
                          (v, ("--rays", str(HUGE)), ("--rays", "100000000")),
                          (v, ("--chunk", str(HUGE)), ("--chunk", "100000000")),
                          (fp, ("--rays", str(HUGE)), ("--rays", "100000000")),
                          (g, ("--rays", str(HUGE)), ("--rays", "100000000"))):
        long(f"benchmarks.{mod.__name__.split('.')[-1]} {' '.join(a)}", cli(lambda: mod.main(list(a))), *words)


run((round20_gaps, solvers, design_helpers, analysis, edof, benchmarks))
