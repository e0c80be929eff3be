"""Bad input, round 33a (tools/audit33a_probe.py: analysis, imaging and design entry points):
one test per class of gap fixed. Each names what main did with the input: a silent answer,
a vague error or a crash."""

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
import jaxlens.analysis as A
import jaxlens.design as D
from jaxlens import zoo
from jaxlens.analysis import tolerance as TOL
from jaxlens.analysis import tolerance_metric as TM
from jaxlens.design import losses as DL
from jaxlens.design import materials as DM
from jaxlens.design import multistart as DMS
from jaxlens.design import robust as DR
from jaxlens.imaging import distortion as DI
from jaxlens.imaging import grid as G
from jaxlens.imaging import psf as P
from jaxlens.imaging import radiometry as RAD
from jaxlens.imaging import render as R
from jaxlens.imaging import sampling as S
from jaxlens.imaging import tiled as TI

COOKE = zoo.cooke_triplet()
PUPIL = S.pupil_grid(5)
RAD20 = float(np.radians(20.0))
RADS = np.radians([0.0, 10.0, 20.0])
KEY = jax.random.PRNGKey(0)


def _warnings(fn):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        fn()
    return [str(x.message) for x in w if issubclass(x.category, UserWarning)]


RADIAN_CALLS = {
    "relative_illumination": lambda f: RAD.relative_illumination(COOKE, f, pupil=16),
    "seidel": lambda f: A.seidel(COOKE, field=f[-1]),
    "ToleranceModel": lambda f: TOL.ToleranceModel(COOKE, fields=f, pupil=PUPIL),
    "collimated": lambda f: S.collimated(COOKE, f[-1], PUPIL),
    "field_rays": lambda f: S.field_rays(COOKE, f[-1], PUPIL),
    "field_direction": lambda f: S.field_direction(f),
    # controls: these warned already; through field_rays they must not warn twice
    "rms_spot": lambda f: A.rms_spot(COOKE, fields=f),
    "psf": lambda f: jl.psf(COOKE, f[-1], pixel_size=0.002, kernel_size=31),
}


@pytest.mark.parametrize("name", list(RADIAN_CALLS))
def test_fields_in_radians_warn_once(name):
    """Main: relative_illumination, seidel, ToleranceModel and the samplers traced 20° typed
    as 0.349 (radians) as 0.349° without a word, where rms_spot and psf warn."""
    said = _warnings(lambda: RADIAN_CALLS[name](RADS))
    assert len(said) == 1 and "look like angles in radians" in said[0], said
    assert _warnings(lambda: RADIAN_CALLS[name](np.array([0.0, 10.0, 20.0]))) == []  # control


def test_field_direction_traced_under_jit_does_not_warn():
    assert _warnings(lambda: jax.jit(S.field_direction)(RAD20)) == []


def test_tolerance_model_stores_theta_y_fields_as_pairs():
    """Main: fields [0, 14] were kept as a [2] array, which the MTF's field directions
    (field_xy) read as one field (θx, θy) = (0°, 14°): evaluate(mtf_frequency=…) failed with
    "Too many indices", and any [2] θy set was ambiguous."""
    pupil = S.pupil_grid(7)
    m = TOL.ToleranceModel(COOKE, fields=[0.0, 14.0], pupil=pupil)
    assert m.fields.shape == (2, 2)
    pairs = TOL.ToleranceModel(COOKE, fields=[[0.0, 0.0], [0.0, 14.0]], pupil=pupil)
    a = m.evaluate(m.zero[None], mtf_frequency=30.0)
    b = pairs.evaluate(pairs.zero[None], mtf_frequency=30.0)
    for k in ("mtf", "rms_um", "rms_compensated_um"):
        np.testing.assert_allclose(a[k], b[k], rtol=0, atol=1e-12)


def _mirror(t):
    return jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0),), thickness=jnp.array([t]),
                   materials=(jl.Air(),), epd=20.0, fields=jnp.array([0.0, 0.5]), mirrors=(0,))


def test_tolerance_compensator_refocuses_a_mirror():
    """Main: spot_data gave slopes only to rays travelling toward +z, so every ray of a
    mirror lens (toward −z after the mirror) had slope 0: the image plane 2 mm short of a
    concave mirror's focus got refocus 0 and kept its 142 µm spot."""
    lens = _mirror(-98.0)  # the focus is at -100 mm: the last thickness must grow by -2 mm
    data = TM.spot_data(lens, jnp.array([0.0]), lens.wavelengths, S.pupil_grid(11))
    dz = float(TM.best_focus(data, jnp.ones(1)))
    assert dz == pytest.approx(-2.0, abs=1e-3)
    assert float(TM.mean_rms_um(data, jnp.ones(1), dz)) < 1e-3
    m = TOL.ToleranceModel(lens, fields=[0.0, 0.5], pupil=S.pupil_grid(9))
    out = m.evaluate(m.zero[None], mtf_frequency=10.0)
    assert float(out["refocus_mm"][0]) == pytest.approx(-2.0, abs=0.01)
    assert float(out["rms_compensated_um"][0]) < 2.0 < float(out["rms_um"][0])
    # Control: the refracting triplet's compensator is unchanged (a small refocus).
    d2 = TM.spot_data(COOKE, jnp.array([0.0]), COOKE.wavelengths, S.pupil_grid(7))
    assert abs(float(TM.best_focus(d2, jnp.ones(1)))) < 0.1


@pytest.mark.parametrize("call", [
    lambda g: DI.distortion_map(COOKE, grid=g),
    lambda g: DI.prewarp(COOKE, jnp.ones((COOKE.sensor.resolution[0] // 8,
                                          COOKE.sensor.resolution[1] // 8, 3)), grid=g),
    lambda g: R.relaxed_render(COOKE, jnp.ones((COOKE.sensor.resolution[0] // 8,
                                                COOKE.sensor.resolution[1] // 8, 3)),
                               spp=1, key=KEY, grid=g),
    lambda g: DI.inverse_distortion_map(COOKE, resolution=(64, 64), pixel_size=0.01, grid=g),
], ids=["distortion_map", "prewarp", "relaxed_render", "inverse_distortion_map"])
def test_interpolated_grids_need_two_points_per_side(call):
    """Main: a (1, 17) grid made a map of one row, interpolated as constant over the sensor."""
    with pytest.raises(ValueError, match=r"grid must be \(rows, cols\), whole numbers >= 2 "
                                         r"points .*an interpolated grid needs 2 points"):
        call((1, 17))


def test_inverse_distortion_map_iters_and_pitch():
    """Main: iters=0 returned the unaimed first guesses; a pitch of 5 (µm) on 512 pixels
    (a 2.56 m sensor) answered ideal positions of 277 mm."""
    kw = dict(resolution=(512, 512), grid=(3, 3))
    with pytest.raises(ValueError, match=r"inverse_distortion_map: iters must be a whole "
                                         r"number in \[1, 1000\] aiming iterations, got 0"):
        DI.inverse_distortion_map(COOKE, pixel_size=0.001, iters=0, **kw)
    with pytest.raises(ValueError, match=r"pixel_size must be a pitch in mm .* <= 1000 mm .*"
                                         r"got 5 mm × 512 = 2560 mm \(a pitch in µm"):
        DI.inverse_distortion_map(COOKE, pixel_size=5.0, **kw)
    assert DI.inverse_distortion_map(COOKE, pixel_size=0.001, **kw).shape == (3, 3, 2)


IMG = jnp.ones((32, 32, 3))
KERN = jnp.zeros((2, 2, 3, 5, 5)).at[:, :, :, 2, 2].set(1.0)


@pytest.mark.parametrize("fn", [TI.wiener_tiles, TI.tile_evidence], ids=["wiener", "evidence"])
@pytest.mark.parametrize("nsr", [0.0, -0.01, np.nan, np.inf])
def test_tiled_noise_ratio_must_be_positive_and_finite(fn, nsr):
    """Main: nsr 0 gave NaN evidence, -0.01 a sign-flipped filter, NaN NaN tiles, inf 0."""
    with pytest.raises(ValueError, match=r"nsr must be finite numbers in \(0, inf\) "
                                         r"\(noise-to-signal power ratio\)"):
        fn(IMG, KERN, nsr)


def test_tiled_checks_halo_kernels_and_image():
    """Main: halo 2.5 ran as 2; a NaN kernel pixel made its tile NaN; an integer image was
    blurred in integer arithmetic (uint8 and int32 answers)."""
    with pytest.raises(ValueError, match=r"wiener_tiles: halo must be a whole number in "
                                         r"\[0, inf\) pixels, got 2.5"):
        TI.wiener_tiles(IMG, KERN, 0.01, halo=2.5)
    bad = KERN.at[0, 0, 0, 0, 0].set(np.nan)
    for fn in (lambda k: TI.convolve_tiles(IMG, k), lambda k: TI.wiener_tiles(IMG, k, 0.01)):
        with pytest.raises(ValueError, match=r"kernels \(PSF weights\) holds 1 NaN"):
            fn(bad)
    with pytest.raises(ValueError, match=r"convolve_tiles: image must be a float image .*"
                                         r"integer image of dtype uint8"):
        TI.convolve_tiles((IMG * 200).astype(jnp.uint8), KERN)
    with pytest.raises(ValueError, match=r"prewarp: scene must be a float image .*int32"):
        DI.prewarp(COOKE, jnp.ones((COOKE.sensor.resolution[0] // 8,
                                    COOKE.sensor.resolution[1] // 8, 3), jnp.int32))
    with pytest.raises(ValueError, match=r"wiener_tiles: nsr must be finite numbers in"):
        TI.wiener_tiles(IMG, KERN, -0.01)
    # Traced (a training step's learned ratio, image and bank): no host callback is added.
    jaxpr = str(jax.make_jaxpr(lambda i, k, n: TI.wiener_tiles(i, k, n))(IMG, KERN, 0.01))
    assert "callback" not in jaxpr
    np.testing.assert_allclose(TI.convolve_tiles(IMG, KERN), IMG, atol=1e-12)  # control


PSF_CALLS = {
    "psf": lambda k: jl.psf(COOKE, 0.0, pixel_size=0.002, kernel_size=k),
    "psf_map": lambda k: P.psf_map(COOKE, grid=(2, 2), kernel_size=k),
    "psf_points": lambda k: TI.psf_points(COOKE, jnp.zeros((1, 2)), None, wavelengths=[0.55],
                                          kernel_size=k, pixel_size=0.002),
}


@pytest.mark.parametrize("name", list(PSF_CALLS))
def test_psf_kernels_must_be_odd(name):
    """Main: an even kernel has no centre pixel: the PSF sat half a pixel off its point."""
    with pytest.raises(ValueError, match=rf"{name}: kernel_size must be odd \(a kernel "
                                         r"centred on a pixel.* got 8; use 9"):
        PSF_CALLS[name](8)


def test_mtf_keeps_an_even_fft_grid():
    assert P.mtf(COOKE, 0.0, kernel_size=64, pixel_size=0.002)[1].shape[0] > 0


def test_psf_points_checks_concrete_inputs_and_psf_rgb_three_wavelengths():
    """Main: center 'chef' ran as 'chief'; 550 (nm) and a NaN position were EquinoxRuntime
    errors from inside the trace; a [3] xy failed in reshape; psf_rgb of 2 wavelengths gave a
    [2, k, k] "RGB" PSF."""
    kw = dict(kernel_size=9, pixel_size=0.002)
    xy = jnp.zeros((1, 2))
    with pytest.raises(ValueError, match=r"psf_points: center must be one of"):
        TI.psf_points(COOKE, xy, None, wavelengths=[0.55], center="chef", **kw)
    with pytest.raises(ValueError, match=r"psf_points: wavelengths .*nm"):
        TI.psf_points(COOKE, xy, None, wavelengths=[550.0], **kw)
    with pytest.raises(ValueError, match=r"psf_points: xy \(mm\) holds 2 NaN"):
        TI.psf_points(COOKE, jnp.full((1, 2), np.nan), None, wavelengths=[0.55], **kw)
    with pytest.raises(ValueError, match=r"psf_points: xy must be sensor positions \[\.\.\., 2\]"):
        TI.psf_points(COOKE, jnp.zeros(3), None, wavelengths=[0.55], **kw)
    with pytest.raises(ValueError, match=r"psf_rgb: wavelengths must be 3 values \(R, G, B\) "
                                         r"in µm, got shape \(2,\)"):
        P.psf_rgb(COOKE, 0.0, wavelengths=(0.5, 0.6), pixel_size=0.002, kernel_size=31)


@pytest.mark.parametrize("call, match", [
    (lambda: S.vignetting_map(jnp.array([0.0, 0.0, 1.5, 0.0, 0.0]), jnp.zeros((1, 2))),
     r"vignetting_map: factors VCX must be finite numbers in \(-inf, 1\) pupil radii"),
    (lambda: S.vignetting_map(jnp.zeros(5), jnp.zeros(3)),
     r"vignetting_map: pupil must be normalised pupil points \[\.\.\., 2\]"),
    (lambda: G.splat(jnp.zeros((5, 3)), jnp.ones(5), 9, 0.002),
     r"splat: pos must be sensor offsets \[\.\.\., 2\]"),
    (lambda: G.splat(jnp.zeros((5, 2)), jnp.ones(4), 9, 0.002),
     r"splat: weight must have pos's leading shape \(5,\)"),
    (lambda: G.splat(jnp.zeros((5, 2)), jnp.ones(5), 0, 0.002),
     r"splat: kernel_size must be a whole number in \[1, 4096\]"),
    (lambda: G.bilinear(jnp.ones(5), 1.0, 1.0), r"bilinear: img must be \[H, W\] or \[H, W, C\]"),
    (lambda: G.bilinear(jnp.ones((5, 5)), jnp.ones(3), jnp.ones(4)),
     r"bilinear: row and col .* broadcastable shapes"),
    (lambda: G.pupil_cells(0, 1.0, jnp.float64), r"pupil_cells: n must be a whole number"),
    (lambda: G.pupil_cells(4, 0.0, jnp.float64), r"pupil_cells: overfill must be .*\(0, inf\)"),
    (lambda: A.encircled_energy(COOKE, 0.0, [100.0, 200.0, 500.0]),
     r"encircled_energy: radii are in mm, .*smallest 100 mm.* Radii in µm\?"),
    (lambda: TOL.percentile([1.0, 2.0], "95"), r"percentile: q must be a real number"),
    (lambda: TOL.percentile([1.0, 2.0], True), r"percentile: q must be a real number .*"
                                               r"\(percent\), got bool True"),
    (lambda: TOL.yield_fraction([1.0, 2.0], 5.0, [99.0, 100.0]),
     r"yield_fraction: valid_fraction must be finite numbers in \[0, 1\]"),
    (lambda: TOL.yield_fraction([1.0, 2.0], 5.0, [1.0, 1.0, 1.0]),
     r"yield_fraction: valid_fraction must have rms_um's shape \(2,\)"),
    (lambda: TOL.yield_fraction(["1", "2"], 5.0), r"yield_fraction: rms_um must be a real"),
    (lambda: TOL.zero_perturbation(COOKE, elements="no"),
     r"zero_perturbation: elements must be True or False, got 'no'"),
    (lambda: DL.radial_area_weights([], (4.0, 6.0)), r"radial_area_weights: fracs must be \[K\]"),
    (lambda: DL.radial_area_weights([0.0, 0.7, 1.5], (4.0, 6.0)),
     r"radial_area_weights: fracs must be finite numbers in \[0, 1\]"),
    (lambda: DL.radial_area_weights([1.0, 0.5, 0.0], (4.0, 6.0)),
     r"radial_area_weights: fracs must increase strictly"),
    (lambda: DL.half_pupil(0), r"half_pupil: rings must be a whole number in \[1, 64\]"),
    (lambda: DM.convex_hull([[1.5, 60.0], [1.6, 40.0]]),
     r"convex_hull: points must be \[N, 2\] \(nd, Vd\) pairs with N >= 3"),
    (lambda: DM.convex_hull([[1.5, 60.0], [1.6, 40.0], [np.nan, 50.0]]),
     r"convex_hull: points must be finite numbers"),
    (lambda: DMS.population_starts([0, 1], 0), r"population_starts: population must be a whole"),
    (lambda: DMS.population_starts([-1], 2), r"population_starts: seeds must be a whole number"),
    (lambda: DMS.population_starts(3, 2), r"population_starts: seeds must be a sequence"),
    (lambda: DR.draw_perturbations(0, 2, 4, radius_rel=0.01, thickness=0.01),
     r"draw_perturbations: n_surfaces must be a whole number in \[1, "),
    (lambda: DR.draw_perturbations(3, 2.5, 4, radius_rel=0.01, thickness=0.01),
     r"draw_perturbations: n_gaps must be a whole number"),
    (lambda: DR.draw_perturbations(3, 2, 4, radius_rel=0.01, thickness=np.inf),
     r"draw_perturbations: thickness must be a finite number in \[0, inf\) mm"),
    (lambda: D.DesignConfig(material_catalogs=("SCHOT",)),
     r"DesignConfig: material_catalogs \['SCHOT'\] names a catalog that is not known"),
    (lambda: D.design({"fnum": 2.0}, [0], progress=False),
     r"design: spec must be a jaxlens.design.DesignSpec, got dict"),
    (lambda: D.design(D.DesignSpec(), [0], callback=5, progress=False),
     r"design: callback must be None or a function"),
    (lambda: D.design(D.DesignSpec(), [0], progress="no"),
     r"design: progress must be True or False"),
])
def test_range_and_type_checks_name_the_rule(call, match):
    """Main: each gave a silent answer (vignetting VCX 1.5, a [5, 3] splat, pupil_cells 2.5,
    radii in µm read as mm (energy 1 everywhere), 99 % valid read as 99, seeds -1 drawing
    starts -2 and -1, an unknown catalog found only mid-design…), a numpy error naming no
    argument, or a crash (ZeroDivisionError, OverflowError, IndexError)."""
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_controls_and_a_percentile_of_a_fraction():
    """Controls pass; q 0.95 (a fraction for the 95th?) warns, naming percent."""
    assert _warnings(lambda: TOL.percentile([1.0, 2.0, 3.0], 95)) == []
    said = _warnings(lambda: TOL.percentile([1.0, 2.0, 3.0], 0.95))
    assert len(said) == 1 and "q is in percent" in said[0]
    assert TOL.yield_fraction([1.0, 6.0], 5.0, [1.0, 1.0]) == 0.5
    np.testing.assert_allclose(A.encircled_energy(COOKE, 0.0, [0.01, 100.0]).energy[1], 1.0)
    assert DMS.population_starts([0, 1], 2) == [0, 1, 2, 3]
    assert D.DesignConfig(material_catalogs=("SCHOTT", "CDGM")).material_catalogs == (
        "SCHOTT", "CDGM")
    assert DL.radial_area_weights([0.0, 0.7, 1.0], (4.0, 6.0)).sum() == pytest.approx(1.0)
    assert len(DM.convex_hull([[1.5, 60.0], [1.6, 40.0], [1.7, 55.0]])) == 3
