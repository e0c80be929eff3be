"""Round 19 of bad-input and silent-answer probes (``tools/audit19_probe.py``).

The gaps round 18 found in the imaging samplers, the PSF and render pixel pitches, the
``newton_iters`` of the imaging entry points and ``trace``, ``frame_of``'s index, the
paraxial functions and the classical CLI's messages, and what a fresh probe of the same
modules found (``working_fnum`` of an object at infinity, the tolerance CLI's decenter).
"""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import paraxial
from jaxlens.experiments import classical
from jaxlens.experiments import tolerance as tolerance_cli
from jaxlens.imaging import distortion, radiometry, render, sampling, tiled
from jaxlens.imaging.grid import MAX_PIXEL_SIZE_MM
from jaxlens.optics.coordinates import frame_of

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COOKE = jl.zoo.cooke_triplet()
TAB = jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515], name="TAB")
TAB_LENS = jl.Lens((jl.Sphere(0.02, semi_diameter=8.0), jl.Sphere(-0.02, semi_diameter=8.0)),
                   jnp.array([5.0, 45.0]), (TAB, jl.Air()), epd=10.0, wavelengths=[0.55])
PTS = jnp.array([[0.0, 0.0], [0.0, 0.5]])
TABLE_RANGE = r"1 µm is outside 0\.44955–0\.65065 µm, the data range of TAB"

# ------------------------------------------------------------------ samplers' wavelengths


@pytest.mark.parametrize("where, make", [
    ("collimated", lambda w: sampling.collimated(TAB_LENS, 0.0, PTS, w)),
    ("point_source", lambda w: sampling.point_source(TAB_LENS, jnp.array([0.0, 0.0, -100.0]),
                                                     PTS, w)),
    ("field_rays", lambda w: sampling.field_rays(TAB_LENS, 1.0, PTS, w)),
    ("field_rays", lambda w: sampling.field_rays(TAB_LENS, 1.0, PTS, w, depth=200.0)),
])
def test_samplers_check_the_wavelength_against_the_lens_materials(where, make):
    """Before: rays at 1 µm for a table glass that ends at 0.65 µm; ``trace`` then refused
    them from inside its jit (an EquinoxRuntimeError)."""
    with pytest.raises(ValueError, match=rf"^{where}: wavelength {TABLE_RANGE}"):
        make(1.0)
    rays = make(0.55)
    assert float(jnp.max(rays.wavelength)) == 0.55 and rays.origin.shape == (2, 3)


def test_sampler_rays_unchanged_and_traced_wavelengths_pass():
    rays = sampling.collimated(COOKE, 2.0, PTS, 0.5876)
    traced = jax.jit(lambda w: sampling.collimated(COOKE, 2.0, PTS, w).origin)(0.5876)
    np.testing.assert_array_equal(np.asarray(traced), np.asarray(rays.origin))
    with pytest.raises(ValueError, match=r"^collimated: wavelength 587\.6 µm is outside .*"
                                         r"587\.6 nm is 0\.5876 µm"):
        sampling.collimated(COOKE, 2.0, PTS, 587.6)


# ------------------------------------------------------------------ pixel pitches


SENSOR_5 = jl.Sensor(resolution=(8, 8), pixel_size=5.0)
PITCH = r"must be a finite number in \(0, 1\) mm \(a pixel pitch: 5 µm is 0\.005 mm\), got 5"


@pytest.mark.parametrize("where, arg, call", [
    ("psf", "pixel_size", lambda: jl.psf(COOKE, 0.0, kernel_size=9, pixel_size=5.0)),
    ("mtf", "pixel_size", lambda: jl.imaging.psf.mtf(COOKE, 0.0, pixel_size=5.0)),
    ("psf_map", "pixel_size", lambda: jl.imaging.psf.psf_map(
        COOKE, grid=(1, 1), sensor=SENSOR_5, kernel_size=9, pixel_size=5.0)),
    ("psf_points", "pixel_size", lambda: tiled.psf_points(
        COOKE, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=9, pixel_size=5.0)),
    ("tile_centers", "pixel_size", lambda: tiled.tile_centers((8, 8), 5.0, 4)),
])
def test_pixel_pitches_are_below_a_millimetre(where, arg, call):
    """Before: a pitch of 5 (µm given as mm) made a PSF of one lit pixel without a word. A
    ``Sensor``'s own pitch is not bounded (the Sensor checks it; renders of 2 mm pixels are
    in use), nor is the default pitch that a PSF takes from it."""
    with pytest.raises(ValueError, match=rf"^{where}: {arg} {PITCH}"):
        call()
    assert MAX_PIXEL_SIZE_MM == 1.0
    assert tiled.tile_centers((8, 8), 0.005, 4).shape == (2, 2, 2)
    if where == "psf":  # the default pitch, a Sensor's own: not bounded
        big = jl.Lens(COOKE.surfaces, COOKE.thickness, COOKE.materials, epd=COOKE.epd,
                      sensor=jl.Sensor(resolution=(8, 8), pixel_size=2.0))
        assert jl.psf(big, 0.0, kernel_size=3).shape == (3, 3)


# ------------------------------------------------------------------ newton_iters


RAYS = sampling.collimated(COOKE, 0.0, PTS, 0.5876)
SENSOR = jl.Sensor(resolution=(8, 8), pixel_size=0.01)


@pytest.mark.parametrize("where, call", [
    ("psf", lambda n: jl.psf(COOKE, 0.0, kernel_size=9, pixel_size=0.005, newton_iters=n)),
    ("render", lambda n: jl.render(COOKE, np.ones((8, 8, 3)), sensor=SENSOR, spp=1,
                                   key=jax.random.key(0), newton_iters=n)),
    ("footprints", lambda n: render.footprints(COOKE, sensor=SENSOR, newton_iters=n)),
    ("distortion_map", lambda n: distortion.distortion_map(COOKE, grid=(2, 2), sensor=SENSOR,
                                                           newton_iters=n)),
    ("inverse_distortion_map", lambda n: distortion.inverse_distortion_map(
        COOKE, resolution=(8, 8), pixel_size=0.01, grid=(2, 2), newton_iters=n)),
    ("relative_illumination", lambda n: radiometry.relative_illumination(
        COOKE, [0.0], pupil=8, newton_iters=n)),
    ("psf_points", lambda n: tiled.psf_points(COOKE, jnp.zeros((1, 2)), None,
                                              wavelengths=[0.55], kernel_size=9,
                                              pixel_size=0.005, newton_iters=n)),
    ("trace", lambda n: jl.trace(COOKE, RAYS, newton_iters=n)),
    ("trace_path", lambda n: jl.trace_path(COOKE, RAYS, newton_iters=n)),  # its name (35b)
])
def test_newton_iters_are_bounded(where, call):
    """Before: 10**6 ran a loop of that length on every aspheric surface (relative
    illumination did not check it at all)."""
    with pytest.raises(ValueError, match=rf"^{where}: newton_iters must be a whole number in "
                                         r"\[0, 1000\] iterations, got 1000000"):
        call(10**6)
    if where == "trace":  # the bound itself is taken
        assert bool(jnp.all(jl.trace(COOKE, RAYS, newton_iters=1000).valid))


def test_relative_illumination_pupil_is_bounded():
    with pytest.raises(ValueError, match=r"^relative_illumination: pupil must be a whole number "
                                         r"in \[1, 4096\] cells per side"):
        radiometry.relative_illumination(COOKE, [0.0], pupil=100000)


# ------------------------------------------------------------------ frame_of


@pytest.mark.parametrize("index", [99, 6, -1, 2.0, True, "2"])
def test_frame_of_takes_a_surface_index_in_range(index):
    """Before: 99 was an IndexError, -1 the identity (the frame before surface 1, not after
    the last surface) and 2.0 "'float' object cannot be interpreted as an integer"."""
    with pytest.raises(ValueError, match=r"^frame_of: index must be a surface index in "
                                         r"\[0, 5\] \(0-based; None for the image surface\)"):
        frame_of(COOKE, index)
    for i in (np.int64(5), 5, None):
        rot, off = frame_of(COOKE, i)
        np.testing.assert_array_equal(np.asarray(rot), np.eye(3))


# ------------------------------------------------------------------ paraxial


def test_marginal_ray_of_several_wavelengths_is_one_column_each():
    """Before: "Cannot stack arrays with different numbers of dimensions" (the height at
    surface 1 of a ray from infinity is one value, the later ones one per wavelength)."""
    y, nu = paraxial.marginal_ray(COOKE, [0.5, 0.6])
    assert y.shape == nu.shape == (6, 2)
    for k, w in enumerate((0.5, 0.6)):
        y1, nu1 = paraxial.marginal_ray(COOKE, w)
        np.testing.assert_array_equal(np.asarray(y[:, k]), np.asarray(y1))
        np.testing.assert_array_equal(np.asarray(nu[:, k]), np.asarray(nu1))


def test_surface_power_checks_its_indices_and_wavelength():
    """Before: n1 = 0 and a wavelength of 587.6 (nm) gave plausible powers."""
    s = COOKE.surfaces[0]
    with pytest.raises(ValueError, match=r"^surface_power: n1 must be finite refractive indices "
                                         r"with \|n\| >= 1 \(negative after a mirror"):
        paraxial.surface_power(s, 0.0, 1.5)
    with pytest.raises(ValueError, match=r"^surface_power: n2 must be"):
        paraxial.surface_power(s, 1.0, np.nan)
    with pytest.raises(ValueError, match=r"^surface_power: wavelength 587\.6 µm is outside "
                                         r"0\.15–30 µm"):
        paraxial.surface_power(s, 1.0, 1.5, 587.6)
    with pytest.raises(TypeError, match=r"^surface_power: surface must be a jaxlens surface"):
        paraxial.surface_power("S1", 1.0, 1.5)
    c = float(s.paraxial_curvature)
    assert float(paraxial.surface_power(s, 1.0, 1.5, 0.55)) == pytest.approx(0.5 * c)
    assert float(paraxial.surface_power(s, -1.0, -1.5)) == pytest.approx(-0.5 * c)  # mirror


@pytest.mark.parametrize("fn", ["efl", "bfl", "marginal_ray", "signed_indices",
                                "entrance_pupil_z", "system_matrix"])
def test_paraxial_functions_refuse_no_wavelength_and_a_lens_of_another_type(fn):
    """Before: ``[]`` gave empty results, and a string for the lens an AttributeError."""
    f = getattr(paraxial, fn)
    with pytest.raises(ValueError, match=rf"^{fn}: wavelength must hold at least one value"):
        f(COOKE, [])
    with pytest.raises(TypeError, match=rf"^{fn}: lens must be a jaxlens\.Lens, got str"):
        f("cooke", None)


def test_working_fnum_of_an_object_at_infinity():
    """Before: depth=inf, which its check names as an object at infinity, gave NaN."""
    at_infinity = float(paraxial.working_fnum(COOKE, None))
    assert np.isfinite(at_infinity)
    assert float(paraxial.working_fnum(COOKE, np.inf)) == at_infinity
    assert float(paraxial.working_fnum(COOKE, 1e12)) == at_infinity
    assert float(paraxial.working_fnum(COOKE, 1000.0)) > at_infinity


# ------------------------------------------------------------------ the CLIs


@pytest.mark.parametrize("argv, text", [
    (["--track", "7000"], r"design: --track 7000 mm is 1\.56e\+03 times the focal length 4\.5 "
                          r"mm \(--sensor-diagonal / \(2·tan\(--fov/2\)\)\)"),
    (["--materials", "E48R"], r"design: --elements 6 needs 6 --materials, got 1"),
    (["--materials", "E48R,OKP4,E48R,OKP4,E48R,AIR"], r"design: --materials entry 6 'AIR' is "
                                                      r"air"),
    (["--fnum", "0.5"], r"design: F/0\.5 \(--fnum\) is faster than 6 element\(s\) "
                        r"\(--elements\)"),
    (["--track", "7", "--bfl", "7"], r"design: --track 7\.0 mm is not longer than the back "
                                     r"focal length --bfl 7\.0 mm"),
])
def test_classical_cli_names_its_flags(argv, text, tmp_path, capsys):
    """Before: "DesignSpec: total_track 7000 mm ... (sensor_diagonal / ...)": the spec's
    field names, not the options the user typed."""
    assert classical.main([*argv, "--out", str(tmp_path / "c"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "DesignSpec" not in err and "total_track" not in err
    assert __import__("re").search(r"^python -m jaxlens\.experiments\.classical: error: " + text,
                                   err), err


def test_tolerance_cli_refuses_a_decenter_beyond_the_clear_radius(tmp_path, capsys):
    """Before: a ValueError traceback naming ``Tolerances.decenter`` (5 mm given where
    0.005 mm was meant)."""
    design = os.path.join(ROOT, "experiments/classical/designs/seed_0.zmx")
    assert tolerance_cli.main([design, "--decenter", "5", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    # Round 20: refused by the CLI's --decenter range, [0, 0.1] mm, before the file is read.
    assert "--decenter must be a finite number >= 0 and <= 0.1 mm (" in err
    assert err.rstrip().endswith("got 5")
    assert not os.listdir(tmp_path)
