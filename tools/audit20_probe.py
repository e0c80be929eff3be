# ruff: noqa: E501, B023, E731
"""Round-20 bad-input probes: throw malformed input at what rounds 14-19 did not reach and
print a table: probe | outcome | what happened.

Outcomes:
    clear error   ValueError/TypeError (or a CLI's exit 2 with one line) whose message holds
                  every expected word (the argument's name, the range, the unit).
    vague error   ValueError/TypeError that lacks an expected word.
    crash         another exception (from deep inside JAX, numpy, a MemoryError…).
    silent wrong  bad input returned a value.
    ok            a control (good input) returned a value, as it should.

Areas: the three gaps left by round 19 (the tolerance CLI's --decenter and --tilt ranges,
``footprints``' grid, a ``Sensor``'s pitch), then huge sizes and counts across the public
API (map grids, sample counts, image sides, design configuration, layer sizes of the nets),
NaN, zero and negative values in the design helpers and ``optics.rebase``, and the
benchmarks and classical CLIs' counts. Every "huge" probe stands for a value that exhausted
memory or ran for hours after the checks; the script refuses them, so it runs in a minute.

Before (main at aa40afe, ``AUDIT20_BEFORE=1``: 67 probes) and after (branch round20: 70),
``PYTHONPATH=$PWD python tools/audit20_probe.py`` under ``ulimit -v 16000000`` (so that the
huge allocations before the fixes fail fast), one 2-core machine:
    before: clear error 2, crash 21, ok 8, silent wrong 25, vague error 11
    after:  clear error 60, crash 1, ok 8, vague error 1
(before, the five tolerance-flag probes reached the file check: given a design they were
analysed. Left after: ``rebase_conic`` of a Sphere names the type, not the word "surface";
``half_pupil(rings=10**6)`` is a MemoryError in ``pupil_hexapolar``, imaging/sampling.py,
owned by another helper: see the round-20 report.)

Run: PYTHONPATH=$PWD python tools/audit20_probe.py [filter]
"""

import os
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
cooke = zoo.cooke_triplet()
HUGE = 10**9
# AUDIT20_BEFORE=1 (running against the code before the fixes) leaves out the three probes
# that ran for hours or aborted the process there: footprints grid 5000, benchmarks --counts
# 10**12 and classical --tolerance-trials 10**7.
BEFORE = os.environ.get("AUDIT20_BEFORE") == "1"


def cli(f):
    f.cli = True
    return f


# ----------------------------------------------------------------------------- round 19's gaps
def round19_gaps():
    from jaxlens.experiments import tolerance as tol
    from jaxlens.imaging import render
    tmp = tempfile.mkdtemp()
    missing = os.path.join(tmp, "none.zmx")  # the ranges are checked before the file is read
    t = cli(lambda *a: tol.main([missing, "--out", os.path.join(tmp, "o"), *a]))
    for a, word in ((("--tilt", "60"), "--tilt"), (("--tilt", "5"), "--tilt"), (("--tilt", "1.5"), "--tilt"),
                    (("--decenter", "0.5"), "--decenter"), (("--decenter", "0.2"), "--decenter")):
        probe(f"tolerance {' '.join(a)}", cli(lambda: t(*a)), word, "deg" if a[0] == "--tilt" else "mm")
    probe("tolerance --tilt 0.05 --decenter 0.02 (control: reaches the file check)", cli(lambda: t("--tilt", "0.05", "--decenter", "0.02")), "none.zmx")
    s_ok = jl.Sensor((8, 8), 0.01)
    probe("footprints grid 10**5", lambda: render.footprints(cooke, sensor=s_ok, grid=10**5), "grid", "257")
    if not BEFORE:
        probe("footprints grid 5000", lambda: render.footprints(cooke, sensor=s_ok, grid=5000), "grid", "257")
    probe("Sensor (3000, 4000) pixel_size 5 (µm given as mm: a 20 m sensor)", lambda: jl.Sensor((3000, 4000), 5.0), "pixel_size", "mm")
    probe("Sensor (480, 640) pixel_size 3.45 (µm as mm)", lambda: jl.Sensor((480, 640), 3.45), "pixel_size", "mm")
    probe("Sensor (8, 8) pixel_size 1e6", lambda: jl.Sensor((8, 8), 1e6), "pixel_size", "mm")
    probe("Sensor (12, 18) pixel_size 2 (control: a 24 x 36 mm preview grid)", lambda: float(jl.Sensor((12, 18), 2.0).pixel_size), good=True)
    probe("jit(Sensor)(pixel_size 5) (control: traced, unchecked)", lambda: jax.jit(lambda p: jl.Sensor((3000, 4000), p).pixel_size)(5.0), good=True)


# ----------------------------------------------------------------------------- huge sizes
def huge_sizes():
    from jaxlens.analysis import aberrations as A
    from jaxlens.analysis import spots as S
    from jaxlens.analysis.wavefront_error import opd_fan
    from jaxlens.imaging import distortion, tiled
    from jaxlens.imaging.psf import psf_map
    from jaxlens.io import images as I
    s_ok = jl.Sensor((8, 8), 0.01)
    probe("Sensor resolution (10**7, 10**7)", lambda: jl.Sensor((10**7, 10**7), 1e-6), "resolution", "16384")
    probe("distortion_map grid (10**5, 10**5)", lambda: distortion.distortion_map(cooke, grid=(10**5, 10**5), sensor=s_ok), "grid", "257")
    probe("prewarp grid (10**5, 10**5)", lambda: distortion.prewarp(cooke, np.ones((8, 8, 3)), sensor=s_ok, grid=(10**5, 10**5)), "grid", "257")
    probe("inverse_distortion_map resolution (10**6, 10**6)", lambda: distortion.inverse_distortion_map(cooke, resolution=(10**6, 10**6), pixel_size=1e-5, grid=(2, 2)), "resolution", "16384")
    probe("psf_map grid (10**4, 10**4)", lambda: psf_map(cooke, grid=(10**4, 10**4), sensor=s_ok, kernel_size=9, pixel_size=0.005), "grid", "257")
    probe("tiled.tile_counts resolution (10**9, 10**9)", lambda: tiled.tile_counts((10**9, 10**9), 4), "resolution", "16384")
    probe("tiled.tile_counts resolution (8.5, 8)", lambda: tiled.tile_counts((8.5, 8), 4), "resolution")
    probe("tiled.tile_counts np.array([64, 32]) (control)", lambda: tiled.tile_counts(np.array([64, 32]), 16), good=True)
    probe("render spp 10**9", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor=s_ok, spp=HUGE, key=jax.random.key(0)), "spp", "65536")
    probe("scene size (10**6, 10**6)", lambda: I.scene("astronaut", (10**6, 10**6)), "size", "16384")
    probe("default_fields count 10**9", lambda: A.default_fields(cooke, HUGE), "count", "65536")
    probe("ray_fan n 10**9", lambda: A.ray_fan(cooke, 0.0, n=HUGE), "n", "65536")
    probe("opd_fan n 10**9", lambda: opd_fan(cooke, 0.0, n=HUGE), "n", "65536")
    probe("clear_semi_diameters n_rim 10**9", lambda: S.clear_semi_diameters(cooke, n_rim=HUGE), "n_rim", "65536")
    probe("self_intersection n_radial 10**9", lambda: S.self_intersection(cooke, n_radial=HUGE).ok, "n_radial", "65536")
    probe("self_intersection n_angle 10**9", lambda: S.self_intersection(cooke, n_angle=HUGE).ok, "n_angle", "65536")
    probe("ray_fan n 21 (control)", lambda: A.ray_fan(cooke, 0.0, n=21).tangential.shape, good=True)


# ----------------------------------------------------------------------------- design helpers
def design_helpers():
    from jaxlens.design import DesignSpec
    from jaxlens.design import curriculum as C
    from jaxlens.design import evaluate as E
    from jaxlens.design import losses as L
    from jaxlens.design import mask as M
    from jaxlens.design import robust as R
    from jaxlens.design.multistart import DesignConfig
    spec = DesignSpec()
    probe("sensor_field_grid n 10**6", lambda: E.sensor_field_grid(spec, 10**6), "n", "257")
    probe("evaluate n 10**6", lambda: E.evaluate(cooke, spec, n=10**6), "n", "257")
    probe("radial_area_weights n 0 (NaN weights)", lambda: L.radial_area_weights([0.0, 0.5, 1.0], (4.0, 6.0), n=0), "n")
    probe("radial_area_weights sensor_size (-4, 6)", lambda: L.radial_area_weights([0.0, 0.5, 1.0], (-4.0, 6.0)), "sensor_size", "mm")
    probe("radial_area_weights sensor_size 5", lambda: L.radial_area_weights([0.0, 0.5, 1.0], 5.0), "sensor_size", "mm")
    probe("radial_area_weights (control)", lambda: L.radial_area_weights([0.0, 0.5, 1.0], (4.0, 6.0)), good=True)
    probe("half_pupil rings 10**6 (pupil_hexapolar, sampling.py: not this round's)", lambda: L.half_pupil(10**6)[0].shape, "rings")
    probe("draw_perturbations trials 10**10", lambda: R.draw_perturbations(4, 3, 10**10, radius_rel=0.005, thickness=0.02), "trials", "1e+06")
    probe("draw_perturbations trials 2.5", lambda: R.draw_perturbations(4, 3, 2.5, radius_rel=0.005, thickness=0.02), "trials")
    probe("draw_perturbations seed -1", lambda: R.draw_perturbations(4, 3, 2, radius_rel=0.005, thickness=0.02, seed=-1), "seed")
    probe("sine_path n 10**10", lambda: C.sine_path(0.0, 1.0, 10**10), "n", "65536")
    probe("paper_stages n 10**9", lambda: C.paper_stages(spec, n=HUGE), "n", "65536")
    probe("field_weights floor -1", lambda: M.field_weights(jnp.ones(4), jnp.ones(4), mask=False, irls=True, floor=-1.0), "floor", "mm")
    probe("field_weights floor 0 (division by a zero RMS)", lambda: M.field_weights(jnp.zeros(4), jnp.ones(4), mask=False, irls=True, floor=0.0), "floor", "mm")
    for kw, word in ((dict(tolerance_trials=10**6), "tolerance_trials"), (dict(rings=10**4), "rings"),
                     (dict(n_fields=10**6), "n_fields"), (dict(image_pixels=10**6), "image_pixels"),
                     (dict(image_spp=HUGE), "image_spp"), (dict(polish_rings=10**4), "polish_rings")):
        probe(f"DesignConfig({word}={list(kw.values())[0]})", lambda: DesignConfig(**kw), word)
    probe("DesignConfig(tolerance_trials=4) (control)", lambda: DesignConfig(tolerance_trials=4).tolerance_trials, good=True)


# ----------------------------------------------------------------------------- rebase, nets
def rebase_nets():
    from jaxlens import nets
    from jaxlens.optics import rebase
    asph = jl.EvenAsphere(0.05, 0.0, [1e-4, 1e-6, 1e-8], semi_diameter=4.0)
    probe("rebase_conic n 0", lambda: rebase.rebase_conic(asph, n=0), "n")
    probe("rebase_conic n 10**9", lambda: rebase.rebase_conic(asph, n=HUGE), "n", "65536")
    probe("rebase_conic semi_diameter -1", lambda: rebase.rebase_conic(asph, -1.0), "semi_diameter", "mm")
    probe("rebase_conic semi_diameter nan", lambda: rebase.rebase_conic(asph, np.nan), "semi_diameter", "mm")
    probe("rebase_conic Sphere", lambda: rebase.rebase_conic(jl.Sphere(0.02), 5.0), "surface")
    probe("rebase_conic (control)", lambda: float(rebase.rebase_conic(asph).k), good=True)
    key = jax.random.key(0)
    probe("Conv kernel 0 (ZeroDivisionError)", lambda: nets.Conv(3, 3, 0, key=key), "kernel")
    probe("Conv stride 0", lambda: nets.Conv(3, 3, 3, stride=0, key=key), "stride")
    probe("Conv c_out -4", lambda: nets.Conv(3, -4, 3, key=key), "c_out")
    probe("Pointwise c_in 10**9", lambda: nets.Pointwise(HUGE, 3, key=key), "c_in", "65536")
    probe("Depthwise channels 2.5", lambda: nets.Depthwise(2.5, key=key), "channels")
    probe("LayerNorm2d eps -1", lambda: nets.LayerNorm2d(3, eps=-1.0), "eps")
    probe("LayerNorm2d eps nan", lambda: nets.LayerNorm2d(3, eps=np.nan), "eps")
    probe("NAFNet width 10**6", lambda: nets.NAFNet(width=10**6, key=key), "width", "1024")
    probe("NAFNet width 8 (control)", lambda: nets.num_parameters(nets.NAFNet(width=8, key=key)), good=True)


# ----------------------------------------------------------------------------- CLIs
def clis():
    from benchmarks import run as bench
    from jaxlens.experiments import classical
    tmp = tempfile.mkdtemp()
    b = cli(lambda *a: bench.main([*a, "--out", os.path.join(tmp, "b")]))
    if not BEFORE:
        probe("benchmarks --counts 10**12 (aborted in XLA)", cli(lambda: b("--only", "throughput", "--counts", str(10**12))), "--counts", "rays")
    probe("benchmarks --counts 100000001", cli(lambda: b("--only", "throughput", "--counts", "100000001")), "--counts", "rays")
    c = cli(lambda *a: classical.main([*a, "--out", os.path.join(tmp, "c"), "--quiet"]))
    probe("classical --tolerance-aware 1000000 (out of memory)", cli(lambda: c("--tolerance-aware", "1000000")), "--tolerance-aware")
    if not BEFORE:
        probe("classical --tolerance-trials 10000000 (refused after the designs)", cli(lambda: c("--tolerance-trials", "10000000")), "--tolerance-trials")


run((round19_gaps, huge_sizes, design_helpers, rebase_nets, clis))
