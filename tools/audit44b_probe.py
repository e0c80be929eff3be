# ruff: noqa: E501, E731, B023
"""Round-44b probes: the classes round 43b (``tools/audit43b_probe.py``) found and left, each
closed by one mechanism, and held-out cases of the same kinds. The table of
``tools/probe_table.py``.

1. Paraxial quantities that are mathematically infinite (an image or a pupil at infinity,
   an afocal lens's focal lengths and F/#) came out as huge finite numbers: the
   magnification of the Cooke triplet's object in its front focal plane was 3.7e15, the EFL
   of two thin lenses f1 + f2 apart -5.8e17 mm. Now ``paraxial._over``: a denominator no
   larger than its rounding bound (4·k·ε times the same sum in absolute values, k its
   operations) is zero, the answer ±inf (efl, F/#, working F/#, magnification +inf). Judged
   by closed forms (``checked``): thin lenses, thin-lens pairs, a stop in a focal plane.
2. No upper (or useful lower) bound on the design numbers: ``DesignSpec`` and ``python -m
   jaxlens.experiments.classical`` take F/# in [0.5, 64], sensor diagonals in [0.1, 1000] mm,
   tracks up to 10 m, at most 30 elements and 8192 pixels (``jaxlens.design.spec`` says why
   each); the edof command line photons in [1, 1e12] photo-electrons at the value 1, learning
   rates in (0, 1] and loss weights in [0, 1000].
3. ``write_psf_stack`` wrote negative PSF values: refused beyond 1e-6 of each PSF's peak
   (float rounding, written as 0).
4. ``python -m benchmarks.reevaluate`` checked that optiland was installed before its
   arguments: the probes run it with optiland reported missing.
5. The reports' cell helpers (``report_cells``, ``ablation_table.fmt``) took a str as a number
   or failed in Python's words: ``report_cells.real_number``, TypeErrors naming the helper.

Run from the tree's root: ``PYTHONPATH=. python tools/audit44b_probe.py [filter]``.
"""

import dataclasses
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import (  # noqa: E402
    COOKE,
    ROOT,
    SEED0,
    TMP,
    checked,
    cli,
    edof_check,
    fresh,
    patched,
    probe,
    run,
)

import jaxlens as jl  # noqa: E402
from jaxlens.analysis import report_cells as RC  # noqa: E402
from jaxlens.design.spec import DesignSpec  # noqa: E402
from jaxlens.optics import paraxial as PX  # noqa: E402
from jaxlens.optics.paraxial_surface import ParaxialSurface  # noqa: E402

cooke = jl.load(COOKE)
KEPLER = os.path.join(ROOT, "tests", "data", "afocal_kepler.zmx")
AIR = jl.Air


def thin(f, s):
    return jl.Lens((ParaxialSurface(focal_length=f),), jnp.array([100.0]), (AIR(),), epd=10.0,
                   object_distance=s)


def pair(f1, f2, gap, s=None):
    return jl.Lens((ParaxialSurface(focal_length=f1), ParaxialSurface(focal_length=f2)),
                   jnp.array([gap, 50.0]), (AIR(), AIR()), epd=10.0, object_distance=s)


def stop_then(f, t):
    return jl.Lens((jl.Stop(), ParaxialSurface(focal_length=f)), jnp.array([t, 2 * t]),
                   (AIR(), AIR()), epd=0.1)


def then_stop(f, t):
    return jl.Lens((ParaxialSurface(focal_length=f), jl.Stop(semi_diameter=0.05)),
                   jnp.array([t, 2 * t]), (AIR(), AIR()), epd=0.1, stop=1)


def front_focus(lens):
    from scipy.optimize import brentq

    at = lambda z: dataclasses.replace(lens, object_distance=jnp.asarray(z, float))
    return at(brentq(lambda z: float(PX.marginal_ray(at(z))[1][-1]), 1.0, 500.0))


def is_inf(fn, sign=None):
    """A judge: ``fn()`` must be infinite (of ``sign`` where given)."""
    def go():
        v = float(fn())
        ok = np.isinf(v) and (sign is None or np.sign(v) == sign)
        return ok, f"{v:.6g}"
    return go


def close(fn, want, rel=1e-6):
    def go():
        v = float(fn())
        return abs(v - want) <= rel * abs(want), f"{v:.10g} (closed form {want:.10g})"
    return go


def paraxial_infinities():
    m, d = PX.magnification, PX.paraxial_data
    # the magnification class: object in the front focal plane
    checked("magnification thin lens, object at f (image at infinity)", is_inf(lambda: m(thin(100.0, 100.0)), +1))
    checked("magnification thin lens, object at f(1+1e-15) (rounding level)", is_inf(lambda: m(thin(100.0, 100.0 * (1 + 1e-15)))))
    checked("magnification thin lens f=0.3, object at 0.1*3", is_inf(lambda: m(thin(0.3, 0.1 * 3))))
    checked("magnification Cooke, object in its front focal plane (was 3.7e15)", is_inf(lambda: m(front_focus(cooke))))
    checked("magnification Cooke 0.1 mm outside the front focal plane (finite, control)", lambda: (np.isfinite(float(m(dataclasses.replace(front_focus(cooke), object_distance=front_focus(cooke).object_distance + 0.1)))), "finite"))
    for s in (100.0 * (1 + 1e-9), 100.0 * (1 - 1e-9), 100.0 * (1 + 1e-6), 300.0, 40.0):
        checked(f"magnification thin lens, object at {s!r} (closed form f/(f-s); control)", close(lambda s=s: m(thin(100.0, s)), 100.0 / (100.0 - s)))
    checked("working F/# thin lens, object at f", is_inf(lambda: d(thin(100.0, 100.0)).working_fnum, +1))
    checked("paraxial image z thin lens, object at f(1-1e-15)", is_inf(lambda: d(thin(100.0, 100.0 * (1 - 1e-15))).paraxial_image_z))
    checked("working F/# Cooke at its front focus", is_inf(lambda: d(front_focus(cooke)).working_fnum, +1))
    # the afocal class: power zero within rounding
    for f1, f2 in ((100.0, 30.0), (0.1 + 0.2, 0.3), (70.0, 7.0), (100.0, -30.0)):
        L = pair(f1, f2, f1 + f2)
        checked(f"efl afocal pair {f1!r}+{f2!r}", is_inf(lambda L=L: PX.efl(L), +1))
        checked(f"bfl afocal pair {f1!r}+{f2!r}", is_inf(lambda L=L: PX.bfl(L)))
        checked(f"paraxial_data.fnum afocal pair {f1!r}+{f2!r}", is_inf(lambda L=L: d(L).fnum, +1))
        checked(f"paraxial_data.working_fnum afocal pair {f1!r}+{f2!r}", is_inf(lambda L=L: d(L).working_fnum, +1))
        checked(f"paraxial_data.paraxial_image_z afocal pair {f1!r}+{f2!r}", is_inf(lambda L=L: d(L).paraxial_image_z))
        checked(f"efl afocal pair {f1!r}+{f2!r} under jit", is_inf(lambda L=L: jax.jit(PX.efl)(L), +1))
        checked(f"magnification afocal pair {f1!r}+{f2!r} at 1000 mm (-f2/f1; control)", close(lambda L=L: m(dataclasses.replace(L, object_distance=jnp.asarray(1000.0))), -f2 / f1, 1e-9))
    for gap in (129.0, 130.0 + 1e-6, 131.0):
        checked(f"efl pair 100+30 gap {gap!r} (closed form; control)", close(lambda gap=gap: PX.efl(pair(100.0, 30.0, gap)), 1.0 / (1 / 100.0 + 1 / 30.0 - gap / 3000.0)))
    checked("efl Kepler .zmx (1.75e10 mm: the file's rounded radii, a real value; control)", lambda: (abs(float(PX.efl(jl.load(KEPLER))) + 1.7513691909e10) < 1e3, f"{float(PX.efl(jl.load(KEPLER))):.6g}"))
    # pupils at infinity
    for f, t in ((100.0, 100.0), (0.1 * 3, 0.3), (50.0, 25.0 * 2)):
        checked(f"exit pupil z, stop in the front focal plane f={f!r} t={t!r}", is_inf(lambda f=f, t=t: d(stop_then(f, t)).exit_pupil_z))
        checked(f"entrance pupil z, stop in the rear focal plane f={f!r} t={t!r}", is_inf(lambda f=f, t=t: PX.entrance_pupil_z(then_stop(f, t))))
    t = 100.0 * (1 + 1e-9)
    checked("entrance pupil z, stop 1e-9 f past the rear focal plane (closed form; control)", close(lambda: PX.entrance_pupil_z(then_stop(100.0, t)), t * 100.0 / (100.0 - t)))
    checked("grad of efl of a focal lens finite (control)", lambda: (bool(np.all(np.isfinite(np.asarray(jax.grad(lambda L: PX.efl(L))(cooke).thickness)))), "finite"))


def design_ranges():
    for kw, words in ((dict(fnum=1e300), ("fnum", "64")), (dict(fnum=100.0), ("fnum", "64")),
                      (dict(fnum_start=1e300), ("fnum_start", "64")),
                      (dict(sensor_diagonal=1e300), ("sensor_diagonal", "mm")), (dict(sensor_diagonal=1e-300), ("sensor_diagonal", "mm")),
                      (dict(sensor_diagonal=5000.0), ("sensor_diagonal", "1000")),
                      (dict(total_track=1e300), ("total_track", "mm")), (dict(total_track=1e5), ("total_track", "10000")),
                      (dict(sensor_pixels=10**9), ("sensor_pixels", "8192")),
                      (dict(n_elements=1000, materials=("E48R",) * 1000), ("n_elements", "30"))):
        probe(f"DesignSpec {kw if 'materials' not in kw else {'n_elements': kw['n_elements']}}", lambda kw=kw: DesignSpec(**kw), *words)
    probe("DesignSpec fnum 64 (the slow end; control)", lambda: DesignSpec(fnum=64.0, fnum_start=64.0), good=True)
    probe("DesignSpec n_elements 30 (control)", lambda: DesignSpec(n_elements=30, materials=("E48R",) * 30, total_track=30.0), good=True)

    from jaxlens.experiments import classical as CL

    def c(*a):
        return cli(patched(CL, ["run_design", "run_ablation"], lambda: CL.main(["--out", os.path.join(fresh("c"), "o"), *a])))

    for a in (("--fnum", "1e300"), ("--fnum", "65"), ("--fnum-start", "1e300"), ("--sensor-diagonal", "1e300"),
              ("--sensor-diagonal", "1e-300"), ("--track", "1e300"), ("--elements", "31")):
        probe(f"classical {' '.join(a)}", c(*a), a[0])
    probe("classical --fnum 64 --fnum-start 64 --fov 10 (control)", c("--fnum", "64", "--fnum-start", "64", "--fov", "10", "--fov-start", "10", "--track", "40"), good=True)
    e = edof_check
    for a in (("--photons", "1e-300"), ("--photons", "0.5"), ("--photons", "1e300"), ("--lr-net", "1e300"), ("--lr-net", "2"),
              ("--lr-lens", "1e300"), ("--w-sim", "1e300"), ("--w-raw", "1e5")):
        probe(f"edof {' '.join(a)}", e(*a), a[0])
    probe("edof --photons 1 (control)", e("--photons", "1"), good=True)
    probe("edof --photons 1e12 (control)", e("--photons", "1e12"), good=True)
    from jaxlens.experiments.edof.train import Config

    probe("edof Config(photons=1e-300)", lambda: Config(photons=1e-300), "photons")


def psf_stacks():
    from jaxlens.io import images as I

    def w(a):
        return lambda: I.write_psf_stack(os.path.join(fresh("ps"), "p.exr"), a)

    one = np.zeros((2, 5, 5))
    one[:, 2, 2] = 1.0
    probe("write_psf_stack -ones", w(-np.ones((2, 5, 5))), "non-negative")
    probe("write_psf_stack one pixel -0.5 of the peak", w(one - 0.5 * (np.arange(50).reshape(2, 5, 5) == 0)), "psfs[0]")
    probe("write_psf_stack one pixel -1e-5 of the peak", w(one - 1e-5 * (np.arange(50).reshape(2, 5, 5) == 49)), "psfs[1]")
    rgb = np.zeros((1, 3, 5, 5))
    rgb[0, :, 2, 2] = 1.0
    rgb[0, 1, 0, 0] = -0.01
    probe("write_psf_stack RGB, G with -0.01", w(rgb), "channel 1")
    probe("write_psf_stack a PSF map difference (a - b)", w(one - np.roll(one, 1, axis=2)), "non-negative")

    def rounding():
        a = one.copy()
        a[0, 0, 0] = -1e-8
        p = os.path.join(fresh("ps"), "p.exr")
        I.write_psf_stack(p, a)
        back, _ = I.read_psf_stack(p)
        return bool(back.min() == 0.0), f"min read back {back.min()!r}"
    checked("write_psf_stack -1e-8 of the peak (rounding: written as 0; control)", rounding)


def reevaluate_args():
    import benchmarks.optiland_ref as OR
    import benchmarks.reevaluate as RE

    def r(*a):
        def go():
            real = OR.available
            OR.available = lambda: False  # as in an environment without optiland
            try:
                return RE.main(list(a))
            finally:
                OR.available = real
        return cli(patched(RE, ["reevaluate"], go))

    broken = fresh("rb")
    open(os.path.join(broken, "x.zmx"), "w").write("SURF 0\n  CURV abc\n")
    probe("reevaluate (no optiland) folder missing", r(os.path.join(TMP, "nope")), "nope")
    probe("reevaluate (no optiland) folder a file", r(COOKE), "folder")
    probe("reevaluate (no optiland) folder without .zmx", r(fresh("re")), ".zmx")
    probe("reevaluate (no optiland) --out a folder", r(os.path.dirname(SEED0), "--out", TMP), "--out")
    probe("reevaluate (no optiland) a broken .zmx", r(broken), "x.zmx")
    probe("reevaluate (no optiland) valid arguments: optiland named last", r(os.path.dirname(SEED0), "--out", os.path.join(fresh("ro"), "r.json")), "optiland")


def report_helpers():
    from jaxlens.experiments import ablation_table as AT

    probe("json_number '1.5'", lambda: RC.json_number("1.5"), "json_number")
    probe("json_number True", lambda: RC.json_number(True), "json_number")
    probe("json_number 1+2j", lambda: RC.json_number(1 + 2j), "json_number")
    probe("json_number [1, 2]", lambda: RC.json_number([1.0, 2.0]), "json_number")
    probe("json_number np.float32 (control)", lambda: RC.json_number(np.float32(2.5)), good=True)
    probe("json_number 0-d jax array (control)", lambda: RC.json_number(jnp.asarray(2.5)), good=True)
    probe("cell 'abc'", lambda: RC.cell("abc"), "cell")
    probe("cell width 2.5", lambda: RC.cell(1.0, width=2.5), "width")
    probe("cell width -1", lambda: RC.cell(1.0, width=-1), "width")
    probe("cell prec -1", lambda: RC.cell(1.0, prec=-1), "prec")
    probe("cell missing 5", lambda: RC.cell(None, missing=5), "missing")
    probe("cell np.bool_", lambda: RC.cell(np.True_), "cell")
    probe("seidel_lines sd 5", lambda: RC.seidel_lines(5, "x"), "seidel_lines")
    probe("seidel_lines field 5", lambda: RC.seidel_lines({"refused": "x"}, 5), "field")
    probe("wavefront_lines reference 5", lambda: RC.wavefront_lines([], 5), "reference")
    probe("wavefront_lines fields 'abc'", lambda: RC.wavefront_lines("abc", "s"), "fields")
    probe("aiming_line None", lambda: RC.aiming_line(None), "aiming_line")
    probe("aiming_line {} (documented: paraxial, reports before the key; control)", lambda: RC.aiming_line({}), good=True)
    probe("fmt 'a'", lambda: AT.fmt("a"), "fmt")
    probe("fmt nd 2.5", lambda: AT.fmt(1.0, 2.5), "nd")
    probe("fmt None (a dash; control)", lambda: AT.fmt(None), good=True)


if __name__ == "__main__":
    run([paraxial_infinities, design_ranges, psf_stacks, reevaluate_args, report_helpers])
