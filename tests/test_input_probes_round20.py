"""Bad input, round 20 (tools/audit20_probe.py): one test per class of gap fixed. Each names
what the bad value did before; all are refusals before any tracing, so the file is fast."""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics import checks

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COOKE = jl.zoo.cooke_triplet()
SMALL = jl.Sensor((8, 8), 0.01)


# ------------------------------------------------------- the tolerance CLI's flag ranges
@pytest.mark.parametrize(("flag", "value", "text"), [
    ("--tilt", "60", r"--tilt must be a finite number >= 0 and <= 1 deg \(an element tilt "
                     r"tolerance: .*\), got 60$"),
    ("--tilt", "1.5", r"--tilt must be .* <= 1 deg .*got 1.5$"),
    ("--decenter", "0.5", r"--decenter must be a finite number >= 0 and <= 0.1 mm \(an element "
                          r"decenter tolerance: .*5 µm is 0.005 mm\), got 0.5$"),
])
def test_tolerance_cli_flags_have_physical_ranges(flag, value, text, tmp_path, capsys):
    """Before: --tilt 60 (degrees) was analysed as an element tilt tolerance (only < 90 was
    refused), and --decenter only had to be below the lens's clear radius."""
    from jaxlens.experiments import tolerance

    design = str(tmp_path / "none.zmx")  # refused before the file is looked for
    assert tolerance.main([design, "--out", str(tmp_path / "o"), flag, value]) == 2
    err = capsys.readouterr().err.strip()
    assert __import__("re").search(text, err), err
    assert "not found" not in err
    # The ends of the ranges pass these checks and reach the next one (the missing file).
    assert tolerance.main([design, "--out", str(tmp_path / "o"), "--tilt", "1",
                           "--decenter", "0.1"]) == 2
    assert "none.zmx' not found" in capsys.readouterr().err


# ------------------------------------------------------- map grids (footprints and the rest)
def test_footprints_and_other_map_grids_are_bounded():
    """Before: footprints(grid=10**5) asked for 80 GB after the checks (no upper bound, the
    class of distortion_map, prewarp, psf_map and inverse_distortion_map's grids too)."""
    from jaxlens.imaging import distortion, render
    from jaxlens.imaging.psf import psf_map

    n = checks.MAX_MAP_GRID
    with pytest.raises(ValueError, match=rf"footprints: grid must be a whole number in \[2, "
                                         rf"{n}\] points per side, got 100000"):
        render.footprints(COOKE, sensor=SMALL, grid=10**5)
    big = (n + 1, 2)
    msg = rf"grid must be \(rows, cols\), whole numbers >= [12] \w+ \(at most {n} per side\)"
    for call in (lambda: distortion.distortion_map(COOKE, grid=big, sensor=SMALL),
                 lambda: distortion.prewarp(COOKE, np.ones((8, 8, 3)), sensor=SMALL, grid=big),
                 lambda: distortion.inverse_distortion_map(COOKE, resolution=(8, 8),
                                                           pixel_size=0.01, grid=big),
                 lambda: psf_map(COOKE, grid=big, sensor=SMALL, kernel_size=9,
                                 pixel_size=0.005)):
        with pytest.raises(ValueError, match=msg):
            call()


# ------------------------------------------------------- a Sensor's size and resolution
@pytest.mark.parametrize(("res", "pitch", "hi"), [
    ((3000, 4000), 5.0, "0.25"),  # 5 µm given as mm: a 20 m sensor
    ((480, 640), 3.45, "1.5625"),
    ((8, 8), 1e6, "125"),
])
def test_sensor_pitch_is_bounded_by_a_one_metre_sensor(res, pitch, hi):
    """Before: any pitch > 0 mm. The bound is on the longer side (1000 mm, the largest focal
    planes built), so coarse preview grids of a few large pixels stay legal."""
    with pytest.raises(ValueError, match=rf"^Sensor: pixel_size must be a finite number in "
                                         rf"\(0, {hi}\] mm \(the longer side, {max(res)} "
                                         rf"pixels, at most 1000 mm; 5 µm is 0.005 mm\)"):
        jl.Sensor(res, pitch)
    assert float(jl.Sensor((12, 18), 2.0).pixel_size) == 2.0  # 24 x 36 mm in 2 mm pixels
    assert float(jl.Sensor((100, 100), 10.0).pixel_size) == 10.0  # exactly 1 m
    # A traced pitch is not checked (jit and grad paths unchanged).
    assert float(jax.jit(lambda p: jl.Sensor(res, p).pixel_size)(pitch)) == pitch


def test_sensor_scene_and_frame_sides_are_bounded():
    """Before: Sensor((10**7, 10**7), …) was accepted, scene((10**6, 10**6)) asked numpy for
    10.9 TiB, tile_counts took (10**9, 10**9) and truncated 8.5 pixels to 8."""
    from jaxlens.imaging import tiled
    from jaxlens.io import images

    n = checks.MAX_IMAGE_SIDE
    with pytest.raises(ValueError, match=rf"Sensor: resolution .* \(at most {n} per side\)"):
        jl.Sensor((n + 1, 8), 1e-6)
    with pytest.raises(ValueError, match=rf"scene: size .* \(at most {n} per side\)"):
        images.scene("astronaut", (10**6, 10**6))
    for res in ((10**9, 10**9), (8.5, 8)):
        with pytest.raises(ValueError, match=r"tile_counts: resolution must be \(rows, cols\)"):
            tiled.tile_counts(res, 4)
    assert tiled.tile_counts(np.array([64, 32]), 16) == (4, 2)
    with pytest.raises(ValueError, match=r"render: spp must be a positive int, at most 65536 "
                                         r"rays per pixel"):
        jl.render(COOKE, np.ones((8, 8, 3)), sensor=SMALL, spp=10**9, key=jax.random.key(0))


# ------------------------------------------------------- sample counts of the analyses
def test_sample_counts_are_bounded():
    """Before: ray_fan(n=10**9) asked XLA for 24 GB, clear_semi_diameters(n_rim=10**9) numpy
    for 7.45 GiB, default_fields(count=10**9) returned an 8 GB array, sine_path(n=10**10)
    asked for 74.5 GiB; rebase_conic(n=0) returned the surface unchanged as if rebased."""
    from jaxlens.analysis import aberrations, spots
    from jaxlens.analysis.wavefront_error import opd_fan
    from jaxlens.design import DesignSpec, curriculum
    from jaxlens.optics import rebase

    big = checks.MAX_SAMPLES + 1
    asph = jl.EvenAsphere(0.05, 0.0, [1e-4, 1e-6, 1e-8], semi_diameter=4.0)
    for where, arg, call in (
            ("ray_fan", "n", lambda: aberrations.ray_fan(COOKE, 0.0, n=big)),
            ("opd_fan", "n", lambda: opd_fan(COOKE, 0.0, n=big)),
            ("default_fields", "count", lambda: aberrations.default_fields(COOKE, big)),
            ("clear_semi_diameters", "n_rim", lambda: spots.clear_semi_diameters(COOKE,
                                                                                n_rim=big)),
            ("self_intersection", "n_radial", lambda: spots.self_intersection(COOKE,
                                                                             n_radial=big)),
            ("self_intersection", "n_angle", lambda: spots.self_intersection(COOKE,
                                                                            n_angle=big)),
            ("sine_path", "n", lambda: curriculum.sine_path(0.0, 1.0, big)),
            ("paper_stages", "n", lambda: curriculum.paper_stages(DesignSpec(), n=big)),
            ("rebase_conic", "n", lambda: rebase.rebase_conic(asph, n=big))):
        with pytest.raises(ValueError, match=rf"^{where}: {arg} must be a whole number in "
                                             rf"\[\d+, {checks.MAX_SAMPLES}\]"):
            call()
    with pytest.raises(ValueError, match=r"rebase_conic: n must be a whole number in \[16, "):
        rebase.rebase_conic(asph, n=0)
    for bad in (-1.0, np.nan):
        with pytest.raises(ValueError, match=r"rebase_conic: semi_diameter must be a finite "
                                             r"number in \(0, inf\) mm"):
            rebase.rebase_conic(asph, bad)
    assert aberrations.default_fields(COOKE, 3).shape == (3,)  # within the bounds
    assert curriculum.sine_path(0.0, 1.0, 4).shape == (5,)


# ------------------------------------------------------- design helpers and configuration
def test_design_sizes_and_numbers_are_checked():
    """Before: radial_area_weights(n=0) gave NaN weights and a negative sensor side plausible
    ones; field_weights(floor=-1) divided by a zero RMS; draw_perturbations(trials=10**10)
    asked numpy for 298 GiB and seed=-1 was numpy's 'expected non-negative integer';
    DesignConfig(tolerance_trials=10**6) asked XLA for 9 TB after the spec was built."""
    from jaxlens.design import DesignSpec, evaluate, losses, mask, robust
    from jaxlens.design.multistart import DesignConfig

    with pytest.raises(ValueError, match=r"sensor_field_grid: n must be a whole number in "
                                         r"\[1, 257\] fields per side"):
        evaluate.sensor_field_grid(DesignSpec(), 10**6)
    with pytest.raises(ValueError, match=r"radial_area_weights: n must be a whole number"):
        losses.radial_area_weights([0.0, 0.5, 1.0], (4.0, 6.0), n=0)
    with pytest.raises(ValueError, match=r"radial_area_weights: sensor_size must be a finite "
                                         r"number in \(0, inf\) mm"):
        losses.radial_area_weights([0.0, 0.5, 1.0], (-4.0, 6.0))
    with pytest.raises(ValueError, match=r"radial_area_weights: sensor_size must be \(height, "
                                         r"width\) in mm, got 5.0"):
        losses.radial_area_weights([0.0, 0.5, 1.0], 5.0)
    w = losses.radial_area_weights([0.0, 0.5, 1.0], (4.0, 6.0))
    assert np.isclose(w.sum(), 1.0) and np.all(w > 0)
    for floor in (-1.0, 0.0):
        with pytest.raises(ValueError, match=r"field_weights: floor must be a finite number in "
                                             r"\(0, inf\) mm"):
            mask.field_weights(jnp.zeros(4), jnp.ones(4), mask=False, irls=True, floor=floor)
    with pytest.raises(ValueError, match=r"draw_perturbations: trials must be a whole number "
                                         r"in \[1, 1000000\] draws"):
        robust.draw_perturbations(4, 3, 10**10, radius_rel=0.005, thickness=0.02)
    with pytest.raises(ValueError, match=r"draw_perturbations: seed must be a whole number"):
        robust.draw_perturbations(4, 3, 2, radius_rel=0.005, thickness=0.02, seed=-1)
    for kw, text in ((dict(tolerance_trials=10**6), r"tolerance_trials .* \[0, 64\]"),
                     (dict(rings=10**4), r"rings .* \[1, 64\]"),
                     (dict(n_fields=10**6), r"n_fields .* \[1, 257\]"),
                     (dict(image_pixels=10**6), r"image_pixels .* \[1, 16384\]"),
                     (dict(image_spp=10**9), r"image_spp .* \[1, 65536\]")):
        with pytest.raises(ValueError, match=rf"^DesignConfig: {text}"):
            DesignConfig(**kw)
    assert DesignConfig(tolerance_trials=4).tolerance_trials == 4


# ------------------------------------------------------- layer sizes of the nets
def test_net_layers_check_their_sizes():
    """Before: Conv(kernel=0) was a ZeroDivisionError, stride=0 built a layer, a negative eps
    of LayerNorm2d was kept (NaN for flat pixels), NAFNet(width=10**6) went for terabytes."""
    from jaxlens import nets

    key = jax.random.key(0)
    for call, text in (
            (lambda: nets.Conv(3, 3, 0, key=key), r"Conv: kernel must be a whole number in "
                                                  r"\[1, 65536\], got 0"),
            (lambda: nets.Conv(3, 3, 3, stride=0, key=key), r"Conv: stride must be 1 or the "
                                                            r"kernel size 3"),
            (lambda: nets.Pointwise(3, -4, key=key), r"Pointwise: c_out must be"),
            (lambda: nets.Depthwise(2.5, key=key), r"Depthwise: channels must be"),
            (lambda: nets.LayerNorm2d(3, eps=-1.0), r"LayerNorm2d: eps must be a finite number "
                                                    r"in \(0, 1\]"),
            (lambda: nets.NAFNet(width=10**6, key=key), r"NAFNet: width must be a whole number "
                                                        r"in \[1, 1024\]")):
        with pytest.raises(ValueError, match=text):
            call()
    assert nets.Conv(3, 4, 2, stride=2, key=key).stride == 2


# ------------------------------------------------------- counts of the CLIs
def test_cli_counts_are_bounded_before_any_work(tmp_path, capsys):
    """Before: ``python -m benchmarks --counts 10**12`` aborted inside XLA, classical
    ``--tolerance-aware 1000000`` ran out of memory and ``--tolerance-trials 10000000`` was
    refused only after the designs had run."""
    from benchmarks.run import main as bench
    from jaxlens.experiments import classical

    with pytest.raises(SystemExit) as e:
        bench(["--only", "throughput", "--counts", str(10**12), "--out", str(tmp_path / "b")])
    assert e.value.code == 2
    assert "--counts must be whole numbers in [1, 100000000] rays, got 1000000000000" in \
        capsys.readouterr().err
    for flag, value, hi in (("--tolerance-aware", "1000000", "64"),
                            ("--tolerance-trials", "10000000", "1000000")):
        assert classical.main([flag, value, "--out", str(tmp_path / "c"), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"design: {flag} must be a whole number in [0, {hi}], got {value}" in err
    assert not (tmp_path / "c").exists() and not (tmp_path / "b").exists()


@pytest.mark.parametrize("make, match", [
    (lambda: jl.sampling.pupil_hexapolar(10**6), r"rings must be a whole number in \[0, 2364\]"),
    (lambda: jl.sampling.pupil_grid(5000), r"n must be a whole number in \[1, 4096\]"),
    (lambda: jl.sampling.pupil_random(jax.random.PRNGKey(0), 2**24 + 1),
     r"n must be a whole number in \[1, 16777216\] points"),
    (lambda: jl.sampling.pupil_stratified(jax.random.PRNGKey(0), 4097), r"\[1, 4096\]"),
    (lambda: jl.sampling.pupil_polar(4097), r"\[1, 4096\]"),
    (lambda: jl.sampling.pupil_samples("hexapolar", 10**6), r"pupil_hexapolar: rings"),
])
def test_pupil_samplers_are_bounded(make, match):
    """Every pupil sampler returns at most checks.MAX_PUPIL_POINTS points (before:
    ``half_pupil(rings=10**6)``, i.e. pupil_hexapolar, was a MemoryError after minutes of a
    Python loop)."""
    with pytest.raises(ValueError, match=match):
        make()


def test_hexapolar_points_and_bounds():
    """The largest allowed hexapolar pattern fits the bound and the next does not; the
    vectorised pattern is the ring definition: ring i has 6i points at radius i/rings, the
    first on +y, spaced 2π/(6i) towards +x."""
    r = 2364
    assert 3 * r * (r + 1) + 1 <= checks.MAX_PUPIL_POINTS < 3 * (r + 1) * (r + 2) + 1
    pts = np.asarray(jl.sampling.pupil_hexapolar(3))
    assert pts.shape == (1 + 6 + 12 + 18, 2)
    np.testing.assert_array_equal(pts[0], [0.0, 0.0])
    ring3 = pts[19:]
    np.testing.assert_allclose(np.hypot(*ring3.T), 1.0, rtol=0, atol=1e-15)
    ang = np.arctan2(ring3[:, 0], ring3[:, 1])  # from +y towards +x
    np.testing.assert_allclose(np.mod(ang, 2 * np.pi), 2 * np.pi * np.arange(18) / 18,
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.hypot(*pts[1:7].T), 1 / 3, rtol=0, atol=1e-15)
