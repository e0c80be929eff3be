# ruff: noqa: E501, B023, E731
"""Round-33a bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for the analysis, imaging and design entry points that round 32a left out: field
angles typed in radians, the tolerance model's fields and compensator, the range checks of
the tiled and distortion helpers, PSF kernel sizes, encircled-energy radii and the design
recipe's catalogs.

A row marked "(warns)" counts a warning as the answer ("clear error" when it names the
slip); "(warns once)" wants exactly one warning ("silent wrong" for none, "vague error" for
two or more). A row "(true: …)" or "against …" compares with the right answer: "silent
wrong" where it differs.

Gaps found and fixed (tests/test_input_probes_round33a.py):
1. relative_illumination, seidel, ToleranceModel, collimated, field_rays and field_direction
   traced np.radians([0, 10, 20]) as fields of at most 0.35° without a word: they warn with
   ``checks.warn_if_radian_fields``, once per call (field_rays → collimated → the direction
   go through unwarned cores; traced fields pass).
2. ToleranceModel kept fields [0, 14] as a [2] array, read as one (θx, θy) field by the MTF's
   directions (evaluate(mtf_frequency=…) failed): stored as [F, 2] pairs.
3. spot_data gave slopes only to rays travelling toward +z: a mirror lens's compensator
   refocused by 0 (the 142 µm spot kept); slopes now whichever way the light goes (−2 mm).
4. Range, shape and type checks: percentile q (percent; a fraction warns), yield_fraction's
   valid_fraction ([0, 1], rms_um's shape), zero_perturbation(elements), the interpolated
   grids of distortion_map / prewarp / relaxed_render / inverse_distortion_map (>= 2 a
   side), inverse_distortion_map iters >= 1 and its pitch (a sensor side <= 1000 mm), the
   tiled Wiener filters' nsr (> 0, finite; traced: error_if) and halo, NaN kernels, integer
   images (convolve_tiles, wiener_tiles, tile_evidence, prewarp), psf_points (center, xy,
   wavelengths in µm), odd kernel_size for psf / psf_map / psf_points (mtf keeps its even
   FFT grid), psf_rgb's 3 wavelengths, vignetting_map (the Lens's check_vignetting, pupil
   pairs), splat / bilinear shapes, pupil_cells, encircled_energy radii in µm (all beyond
   2 image diagonals), radial_area_weights, half_pupil, convex_hull, population_starts,
   draw_perturbations, DesignConfig.material_catalogs (known catalogs) and design's spec,
   config, callback and progress.

Before (main at 72310e1, an archive) and after (branch audit33a), the same 120 probes,
``PYTHONPATH=<tree> python tools/audit33a_probe.py`` from the repository, about 4 min each:
    before: clear error: 15, crash: 7, ok: 22, silent wrong: 65, vague error: 11
    after:  clear error: 94, ok: 26
In review the row of a traced nsr under jit was dropped (119 probes): a traced nsr is a
learned ratio, and its check added a host callback to every EDoF training step.

Run: PYTHONPATH=$PWD python tools/audit33a_probe.py [filter]
"""

import os
import sys
import warnings

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import FILTER, ROWS, probe, run, warned  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.analysis import tolerance as TOL  # noqa: E402
from jaxlens.analysis import tolerance_metric as TM  # noqa: E402
from jaxlens.design import losses as DL  # noqa: E402
from jaxlens.design import materials as DM  # noqa: E402
from jaxlens.design import multistart as DMS  # noqa: E402
from jaxlens.design import robust as DR  # noqa: E402
from jaxlens.imaging import distortion as DI  # noqa: E402
from jaxlens.imaging import grid as G  # noqa: E402
from jaxlens.imaging import psf as P  # noqa: E402
from jaxlens.imaging import radiometry as RAD  # noqa: E402
from jaxlens.imaging import render as R  # noqa: E402
from jaxlens.imaging import sampling as S  # noqa: E402
from jaxlens.imaging import tiled as TI  # noqa: E402

KEY = jax.random.PRNGKey(0)
RAD20 = 0.3490658503988659  # 20° in radians
RADS = np.radians([0.0, 10.0, 20.0])


def warned_once(fn):
    """Exactly one UserWarning: none is "silent wrong" (returned), two or more raise a
    message without the probe's words (a "vague error")."""
    def go():
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            r = fn()
        w = [x for x in w if issubclass(x.category, UserWarning)]
        if len(w) == 1:
            raise ValueError(f"warned: {w[0].message}")
        if len(w) > 1:
            raise ValueError(f"{len(w)} warnings, first: {str(w[0].message)[:60]}")
        return r
    return go


def expect(name, fn, ok):
    """A row: "ok" where ``ok(fn())`` holds, else "silent wrong" (the value shown)."""
    if FILTER and FILTER not in name:
        return
    try:
        got = fn()
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {e}"[:150]))
        return
    ROWS.append((name, "ok" if ok(got) else "silent wrong", str(got)[:100]))


def mirror(t):
    return jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0),), thickness=jnp.array([t]),
                   materials=(jl.Air(),), epd=20.0, fields=jnp.array([0.0, 0.5]), mirrors=(0,))


# ---------------------------------------------------------------- 1. radians, 2-3. tolerance
def radians():
    c = zoo.cooke_triplet()
    pupil = S.pupil_grid(5)
    probe("relative_illumination fields radians([0, 10, 20]) (warns)", warned(lambda: RAD.relative_illumination(c, RADS, pupil=16).ri), "radians")
    probe("seidel field 0.349 (20° in radians) (warns)", warned(lambda: A.seidel(c, field=RAD20).sums), "radians")
    probe("ToleranceModel fields radians([0, 10, 20]) (warns)", warned(lambda: TOL.ToleranceModel(c, fields=RADS, pupil=pupil).fields), "radians")
    probe("collimated field 0.349 (warns)", warned(lambda: S.collimated(c, RAD20, pupil).origin), "radians")
    probe("field_rays field 0.349 (warns)", warned(lambda: S.field_rays(c, RAD20, pupil).origin), "radians")
    probe("field_direction field 0.349 (warns)", warned(lambda: S.field_direction(RAD20)), "radians")
    probe("field_direction fields radians([0, 10, 20]) (warns)", warned(lambda: S.field_direction(RADS)), "radians")
    probe("rms_spot fields radians([0, 10, 20]) (warns once)", warned_once(lambda: A.rms_spot(c, fields=RADS).polychromatic), "radians")
    probe("field_rays field 0.349 (warns once)", warned_once(lambda: S.field_rays(c, RAD20, pupil).origin), "radians")
    probe("psf field 0.349 (warns once)", warned_once(lambda: jl.psf(c, RAD20, pixel_size=0.002, kernel_size=9)), "radians")
    probe("wavefront field 0.349 (warns once)", warned_once(lambda: A.wavefront(c, RAD20, grid=9).rms), "radians")
    probe("seidel field 0.349 (warns once)", warned_once(lambda: A.seidel(c, field=RAD20).sums), "radians")
    probe("ToleranceModel fields radians (warns once)", warned_once(lambda: TOL.ToleranceModel(c, fields=RADS, pupil=pupil).fields), "radians")
    probe("relative_illumination fields radians (warns once)", warned_once(lambda: RAD.relative_illumination(c, RADS, pupil=16).ri), "radians")
    probe("seidel field 20 (control)", warned(lambda: A.seidel(c, field=20.0).sums), good=True)
    probe("field_rays field 14 (control)", warned(lambda: S.field_rays(c, 14.0, pupil).origin), good=True)
    probe("field_direction under jit (control: traced passes)", lambda: jax.jit(S.field_direction)(RAD20), good=True)


def tolerance():
    c = zoo.cooke_triplet()
    pupil = S.pupil_grid(7)

    def mtf_of(fields):
        m = TOL.ToleranceModel(c, fields=fields, pupil=pupil)
        return float(m.evaluate(m.zero[None], mtf_frequency=30.0)["mtf"][0])

    expect("ToleranceModel fields [0, 14] (θy) MTF against [[0, 0], [0, 14]]",
           lambda: abs(mtf_of([0.0, 14.0]) - mtf_of([[0.0, 0.0], [0.0, 14.0]])), lambda d: d < 1e-9)
    expect("ToleranceModel fields [0, 14] stored as pairs [2, 2]",
           lambda: TOL.ToleranceModel(c, fields=[0.0, 14.0], pupil=pupil).fields.shape, lambda s: s == (2, 2))
    m = mirror(-98.0)  # focus 100 mm before the mirror: 2 mm to go, toward -z
    data = lambda: TM.spot_data(m, jnp.array([0.0]), m.wavelengths, pupil)
    expect("spot_data mirror: best_focus refocus (true: -2 mm)", lambda: float(TM.best_focus(data(), jnp.ones(1))), lambda z: abs(z + 2.0) < 0.05)
    expect("spot_data mirror: refocused RMS (true: ~0 µm)", lambda: float(TM.mean_rms_um(data(), jnp.ones(1), TM.best_focus(data(), jnp.ones(1)))), lambda r: r < 1.0)
    expect("spot_data lens (control): refocus finite", lambda: float(TM.best_focus(TM.spot_data(c, jnp.array([0.0]), c.wavelengths, pupil), jnp.ones(1))), np.isfinite)
    probe("percentile q 0.95 (a fraction? warns)", warned(lambda: TOL.percentile([1.0, 2.0, 3.0], 0.95)), "percent")
    probe("percentile q NaN", lambda: TOL.percentile([1.0, 2.0], np.nan), "q", "0, 100")
    probe("percentile q '95'", lambda: TOL.percentile([1.0, 2.0], "95"), "q")
    probe("percentile q True", lambda: TOL.percentile([1.0, 2.0], True), "q")
    probe("percentile q 95 (control)", lambda: TOL.percentile([1.0, 2.0, 3.0], 95), good=True)
    probe("yield_fraction valid_fraction 99 (percent)", lambda: TOL.yield_fraction([1.0, 2.0], 5.0, [99.0, 100.0]), "valid_fraction", "[0, 1]")
    probe("yield_fraction valid_fraction shape [3] for 2 trials", lambda: TOL.yield_fraction([1.0, 2.0], 5.0, [1.0, 1.0, 1.0]), "valid_fraction")
    probe("yield_fraction valid_fraction NaN", lambda: TOL.yield_fraction([1.0, 2.0], 5.0, [np.nan, 1.0]), "valid_fraction")
    probe("yield_fraction rms_um '1'", lambda: TOL.yield_fraction(["1", "2"], 5.0), "rms_um")
    probe("yield_fraction (control)", lambda: TOL.yield_fraction([1.0, 6.0], 5.0, [1.0, 1.0]), good=True)
    probe("zero_perturbation elements 'no'", lambda: TOL.zero_perturbation(c, elements="no"), "elements")
    probe("zero_perturbation elements 1", lambda: TOL.zero_perturbation(c, elements=1), "elements")
    probe("zero_perturbation elements False (control)", lambda: TOL.zero_perturbation(c, elements=False).thickness, good=True)


# ------------------------------------------------------------------------- 4-5. imaging
def imaging():
    c = zoo.cooke_triplet()
    s = c.sensor
    scene = jnp.ones((s.resolution[0] // 8, s.resolution[1] // 8, 3)) if s is not None else None
    probe("distortion_map grid (1, 17)", lambda: DI.distortion_map(c, grid=(1, 17)).real, "grid", "2")
    probe("distortion_map grid (17, 17) (control)", lambda: DI.distortion_map(c, grid=(5, 5)).real, good=True)
    probe("prewarp grid (1, 1)", lambda: DI.prewarp(c, scene, grid=(1, 1)), "grid", "2")
    probe("relaxed_render grid (17, 1)", lambda: R.relaxed_render(c, scene, spp=1, key=KEY, grid=(17, 1)), "grid", "2")
    probe("inverse_distortion_map grid (1, 1)", lambda: DI.inverse_distortion_map(c, resolution=(64, 64), pixel_size=0.01, grid=(1, 1)), "grid", "2")
    probe("inverse_distortion_map iters 0", lambda: DI.inverse_distortion_map(c, resolution=(64, 64), pixel_size=0.01, grid=(3, 3), iters=0), "iters", "1")
    probe("inverse_distortion_map pixel_size 5 (µm) at 512x512", lambda: DI.inverse_distortion_map(c, resolution=(512, 512), pixel_size=5.0, grid=(3, 3)), "pixel_size", "mm")
    probe("inverse_distortion_map pixel_size inf", lambda: DI.inverse_distortion_map(c, resolution=(64, 64), pixel_size=np.inf, grid=(3, 3)), "pixel_size", "mm")
    probe("inverse_distortion_map pixel_size 0.01 (control)", lambda: DI.inverse_distortion_map(c, resolution=(64, 64), pixel_size=0.01, grid=(3, 3)), good=True)
    probe("prewarp scene uint8", lambda: DI.prewarp(c, (scene * 200).astype(jnp.uint8), grid=(5, 5)), "scene", "integer")
    probe("prewarp scene int32", lambda: DI.prewarp(c, (scene * 2).astype(jnp.int32), grid=(5, 5)), "scene", "integer")
    kern = jnp.zeros((2, 2, 3, 5, 5)).at[:, :, :, 2, 2].set(1.0)
    img = jnp.ones((32, 32, 3))
    probe("wiener_tiles nsr 0", lambda: TI.wiener_tiles(img, kern, 0.0), "nsr", "(0, inf)")
    probe("wiener_tiles nsr -0.01", lambda: TI.wiener_tiles(img, kern, -0.01), "nsr")
    probe("wiener_tiles nsr NaN", lambda: TI.wiener_tiles(img, kern, np.nan), "nsr")
    probe("wiener_tiles nsr inf", lambda: TI.wiener_tiles(img, kern, np.inf), "nsr")
    # Not probed under jit: a traced nsr (a learned ratio) is not checked, as a check would
    # add a host callback to every training step.
    probe("tile_evidence nsr 0", lambda: TI.tile_evidence(img, kern, 0.0), "nsr")
    probe("wiener_tiles halo 2.5", lambda: TI.wiener_tiles(img, kern, 0.01, halo=2.5), "halo")
    probe("wiener_tiles halo -1", lambda: TI.wiener_tiles(img, kern, 0.01, halo=-1), "halo")
    probe("wiener_tiles halo True", lambda: TI.wiener_tiles(img, kern, 0.01, halo=True), "halo")
    probe("wiener_tiles kernels with NaN", lambda: TI.wiener_tiles(img, kern.at[0, 0, 0, 0, 0].set(np.nan), 0.01), "kernels", "NaN")
    probe("convolve_tiles kernels with NaN", lambda: TI.convolve_tiles(img, kern.at[0, 0, 0, 0, 0].set(np.nan)), "kernels", "NaN")
    probe("convolve_tiles image uint8", lambda: TI.convolve_tiles((img * 200).astype(jnp.uint8), kern), "image", "integer")
    probe("wiener_tiles image int32", lambda: TI.wiener_tiles((img * 3).astype(jnp.int32), kern, 0.01), "image", "integer")
    probe("convolve_tiles image NaN", lambda: TI.convolve_tiles(img.at[0, 0, 0].set(np.nan), kern), "image", "NaN")
    probe("wiener_tiles (control)", lambda: TI.wiener_tiles(img, kern, 0.01), good=True)
    probe("psf_points center 'chef'", lambda: TI.psf_points(c, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=9, pixel_size=0.002, center="chef"), "center")
    probe("psf_points wavelengths [550] (nm)", lambda: TI.psf_points(c, jnp.zeros((1, 2)), None, wavelengths=[550.0], kernel_size=9, pixel_size=0.002), "wavelength", "µm")
    probe("psf_points xy NaN", lambda: TI.psf_points(c, jnp.full((1, 2), np.nan), None, wavelengths=[0.55], kernel_size=9, pixel_size=0.002), "xy")
    probe("psf_points xy shape [3]", lambda: TI.psf_points(c, jnp.zeros(3), None, wavelengths=[0.55], kernel_size=9, pixel_size=0.002), "xy")
    probe("psf_points kernel_size 8 (even)", lambda: TI.psf_points(c, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=8, pixel_size=0.002), "kernel_size", "odd")
    probe("psf_points (control)", lambda: TI.psf_points(c, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=9, pixel_size=0.002), good=True)
    probe("psf kernel_size 8 (even)", lambda: jl.psf(c, 0.0, pixel_size=0.002, kernel_size=8), "kernel_size", "odd")
    probe("psf_map kernel_size 8 (even)", lambda: P.psf_map(c, grid=(2, 2), kernel_size=8).psf, "kernel_size", "odd")
    probe("mtf kernel_size 64 (control: even allowed)", lambda: P.mtf(c, 0.0, kernel_size=64, pixel_size=0.002)[1], good=True)
    probe("psf_rgb wavelengths 2", lambda: P.psf_rgb(c, 0.0, wavelengths=(0.5, 0.6), pixel_size=0.002, kernel_size=31), "wavelengths", "3")
    probe("psf_rgb wavelengths 0.55 (one)", lambda: P.psf_rgb(c, 0.0, wavelengths=0.55, pixel_size=0.002, kernel_size=31), "wavelengths", "3")
    probe("psf_rgb (control)", lambda: P.psf_rgb(c, 0.0, pixel_size=0.002, kernel_size=31), good=True)
    probe("vignetting_map VCX 1.5", lambda: S.vignetting_map(jnp.array([0.0, 0.0, 1.5, 0.0, 0.0]), jnp.zeros((1, 2))), "VCX")
    probe("vignetting_map pupil [3] (not pairs)", lambda: S.vignetting_map(jnp.zeros(5), jnp.zeros(3)), "pupil")
    probe("splat pos [5, 3]", lambda: G.splat(jnp.zeros((5, 3)), jnp.ones(5), 9, 0.002), "pos")
    probe("splat weight [4] for 5 points", lambda: G.splat(jnp.zeros((5, 2)), jnp.ones(4), 9, 0.002), "weight")
    probe("splat kernel_size 0", lambda: G.splat(jnp.zeros((5, 2)), jnp.ones(5), 0, 0.002), "kernel_size")
    probe("splat (control)", lambda: G.splat(jnp.zeros((5, 2)), jnp.ones(5), 9, 0.002), good=True)
    probe("bilinear img 1-D", lambda: G.bilinear(jnp.ones(5), 1.0, 1.0), "img")
    probe("bilinear row/col shapes [3] and [4]", lambda: G.bilinear(jnp.ones((5, 5)), jnp.ones(3), jnp.ones(4)), "row")
    probe("bilinear (control)", lambda: G.bilinear(jnp.ones((5, 5)), 1.5, 1.5), good=True)
    probe("pupil_cells n 0", lambda: G.pupil_cells(0, 1.0, jnp.float64), "n")
    probe("pupil_cells n 2.5", lambda: G.pupil_cells(2.5, 1.0, jnp.float64), "n")
    probe("pupil_cells overfill 0", lambda: G.pupil_cells(4, 0.0, jnp.float64), "overfill")
    probe("encircled_energy radii [100, 200, 500] (µm as mm)", lambda: A.encircled_energy(c, 0.0, [100.0, 200.0, 500.0]).energy, "radii", "mm")
    probe("encircled_energy radii [0.005, 0.01, 100] (control)", lambda: A.encircled_energy(c, 0.0, [0.005, 0.01, 100.0]).energy, good=True)
    probe("radius_for_fraction (control)", lambda: A.radius_for_fraction(c, 0.0, 0.8), good=True)


# ------------------------------------------------------------------------------ design
def design():
    probe("radial_area_weights fracs [] (none)", lambda: DL.radial_area_weights([], (4.0, 6.0)), "fracs")
    probe("radial_area_weights fracs [0, 0.7, 1.5]", lambda: DL.radial_area_weights([0.0, 0.7, 1.5], (4.0, 6.0)), "fracs", "[0, 1]")
    probe("radial_area_weights fracs [1, 0.5, 0] (decreasing)", lambda: DL.radial_area_weights([1.0, 0.5, 0.0], (4.0, 6.0)), "fracs")
    probe("radial_area_weights fracs NaN", lambda: DL.radial_area_weights([0.0, np.nan], (4.0, 6.0)), "fracs")
    probe("radial_area_weights (control)", lambda: DL.radial_area_weights([0.0, 0.7, 1.0], (4.0, 6.0)), good=True)
    probe("half_pupil rings 0", lambda: DL.half_pupil(0), "rings")
    probe("half_pupil rings 2.5", lambda: DL.half_pupil(2.5), "rings")
    probe("half_pupil rings True", lambda: DL.half_pupil(True), "rings")
    probe("convex_hull points [2, 2] (two points)", lambda: DM.convex_hull([[1.5, 60.0], [1.6, 40.0]]), "points", "3")
    probe("convex_hull points [3] (not pairs)", lambda: DM.convex_hull([1.5, 1.6, 1.7]), "points")
    probe("convex_hull points NaN", lambda: DM.convex_hull([[1.5, 60.0], [1.6, 40.0], [np.nan, 50.0]]), "points")
    probe("convex_hull (control)", lambda: DM.convex_hull([[1.5, 60.0], [1.6, 40.0], [1.7, 55.0]]), good=True)
    probe("population_starts population 0", lambda: DMS.population_starts([0, 1], 0), "population")
    probe("population_starts population 2.5", lambda: DMS.population_starts([0, 1], 2.5), "population")
    probe("population_starts seeds [-1]", lambda: DMS.population_starts([-1], 2), "seeds")
    probe("population_starts seeds 3 (an int)", lambda: DMS.population_starts(3, 2), "seeds")
    probe("population_starts (control)", lambda: DMS.population_starts([0, 1], 2), good=True)
    probe("draw_perturbations n_surfaces 0", lambda: DR.draw_perturbations(0, 2, 4, radius_rel=0.01, thickness=0.01), "n_surfaces")
    probe("draw_perturbations n_gaps 2.5", lambda: DR.draw_perturbations(3, 2.5, 4, radius_rel=0.01, thickness=0.01), "n_gaps")
    probe("draw_perturbations radius_rel NaN", lambda: DR.draw_perturbations(3, 2, 4, radius_rel=np.nan, thickness=0.01), "radius_rel")
    probe("draw_perturbations thickness inf", lambda: DR.draw_perturbations(3, 2, 4, radius_rel=0.01, thickness=np.inf), "thickness")
    probe("draw_perturbations (control)", lambda: DR.draw_perturbations(3, 2, 4, radius_rel=0.01, thickness=0.01).gap, good=True)
    probe("DesignConfig material_catalogs ('SCHOT',)", lambda: D.DesignConfig(material_catalogs=("SCHOT",)), "material_catalogs", "SCHOT")
    probe("DesignConfig material_catalogs ('PLASTICS', 'nope')", lambda: D.DesignConfig(material_catalogs=("PLASTICS", "nope")), "material_catalogs")
    probe("DesignConfig curriculum 'no'", lambda: D.DesignConfig(curriculum="no"), "curriculum")
    probe("DesignConfig float64 1", lambda: D.DesignConfig(float64=1), "float64")
    probe("DesignConfig irls None", lambda: D.DesignConfig(irls=None), "irls")
    probe("design spec a dict", lambda: D.design({"fnum": 2.0}, [0], progress=False), "spec", "DesignSpec")
    probe("design config a dict", lambda: D.design(D.DesignSpec(), [0], {"steps": 1}, progress=False), "config", "DesignConfig")
    probe("design callback 5", lambda: D.design(D.DesignSpec(), [0], callback=5, progress=False), "callback")
    probe("design progress 'no'", lambda: D.design(D.DesignSpec(), [0], progress="no"), "progress")
    probe("DesignConfig material_catalogs ('SCHOTT', 'CDGM') (control)", lambda: D.DesignConfig(material_catalogs=("SCHOTT", "CDGM")).material_catalogs, good=True)


run([radians, tolerance, imaging, design])
