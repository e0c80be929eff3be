# ruff: noqa: E501, B023, E731
"""Round-19 bad-input probes: throw malformed input at the imaging modules, optics.coordinates,
optics.paraxial and the classical and tolerance CLIs and print a table: probe | outcome | what happened.

Outcomes:
    clear error   ValueError/TypeError (or a CLI's exit 2 with one line) whose message holds
                  every expected word (the argument's name, the range, the unit).
    vague error   ValueError/TypeError that lacks an expected word.
    crash         another exception (from deep inside JAX, numpy, a KeyError…).
    silent wrong  bad input returned a value.
    ok            a control (good input) returned a value, as it should.

Areas: round 18's gaps in these modules (sampler wavelengths against the materials, PSF
pixel pitches, newton_iters bounds, frame_of indices, paraxial wavelength shapes and
surface_power's indices, the classical CLI's flag names), then fresh probes of the public
functions of imaging/*.py, optics/coordinates.py and optics/paraxial.py and of the two CLIs:
NaN/inf, zero or negative sizes, unit mix-ups that give plausible numbers, wrong shapes and
dtypes, indices out of range.

Run: PYTHONPATH=$PWD python tools/audit19_probe.py [filter]
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


# ----------------------------------------------------------------------------- round 18's gaps
def tab_lens(mat, wls=(0.55,)):
    return jl.Lens(surfaces=(jl.Sphere(0.02, semi_diameter=8.0), jl.Sphere(-0.02, semi_diameter=8.0)),
                   thickness=jnp.array([5.0, 45.0]), materials=(mat, jl.Air()), epd=10.0,
                   fields=jnp.array([0.0, 5.0]), wavelengths=jnp.array(wls))


def cli(f):
    f.cli = True
    return f


def round18_gaps():
    from jaxlens.imaging import sampling
    tab = jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515], name="TAB")
    lens = tab_lens(tab)
    pts = jnp.zeros((1, 2))
    probe("collimated table lens 1.0", lambda: sampling.collimated(lens, 0.0, pts, 1.0), "µm", "TAB")
    probe("collimated table lens 0.55 (control)", lambda: sampling.collimated(lens, 0.0, pts, 0.55).origin, good=True)
    probe("point_source table lens 1.0", lambda: sampling.point_source(lens, jnp.array([0.0, 0.0, -100.0]), pts, 1.0), "µm", "TAB")
    probe("field_rays table lens 1.0", lambda: sampling.field_rays(lens, 0.0, pts, 1.0), "µm", "TAB")
    probe("field_rays depth 100 table lens 1.0", lambda: sampling.field_rays(lens, 0.0, pts, 1.0, depth=100.0), "µm", "TAB")
    probe("collimated wavelength 587.6 (nm)", lambda: sampling.collimated(cooke, 0.0, pts, 587.6), "µm", "587.6 nm")
    probe("collimated wavelength '0.55'", lambda: sampling.collimated(cooke, 0.0, pts, "0.55"), "wavelength")
    probe("jit(collimated)(wavelength) (control: traced, checked by trace)", lambda: jax.jit(lambda w: sampling.collimated(cooke, 0.0, pts, w).origin)(0.55), good=True)
    probe("psf pixel_size 5 (µm where mm are meant)", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=5.0), "pixel_size", "1", "mm")
    probe("psf pixel_size 0.005 (control)", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=0.005).shape, good=True)
    probe("psf newton_iters 5000", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=0.005, newton_iters=5000), "newton_iters", "1000")
    s5 = jl.Sensor(resolution=(8, 8), pixel_size=5.0)
    s_ok = jl.Sensor(resolution=(8, 8), pixel_size=0.01)
    probe("render sensor pixel_size 5 (documented: a Sensor's pitch is the Sensor's; 2 mm renders are in use)", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor=s5, spp=1, key=jax.random.key(0)).shape, good=True)
    probe("render newton_iters 10**6", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor=s_ok, spp=1, key=jax.random.key(0), newton_iters=10**6), "newton_iters", "1000")
    probe("psf_map sensor pixel_size 5, pixel_size 0.005 (documented: the sensor sets the extent)", lambda: jl.imaging.psf.psf_map(cooke, grid=(1, 1), sensor=jl.Sensor(resolution=(2, 2), pixel_size=5.0), kernel_size=9, pixel_size=0.005).psf.shape, good=True)
    probe("psf_map pixel_size 5", lambda: jl.imaging.psf.psf_map(cooke, grid=(1, 1), sensor=s5, kernel_size=9, pixel_size=5.0), "pixel_size", "mm")
    from jaxlens.imaging import distortion, tiled
    probe("distortion_map newton_iters 5000", lambda: distortion.distortion_map(cooke, grid=(2, 2), sensor=s_ok, newton_iters=5000), "newton_iters", "1000")
    probe("distortion_map sensor of 5 mm pixels (documented: a 40 mm sensor, the Sensor's pitch)", lambda: distortion.distortion_map(cooke, grid=(2, 2), sensor=s5).real, good=True)
    probe("inverse_distortion_map pixel_size 5", lambda: distortion.inverse_distortion_map(cooke, resolution=(8, 8), pixel_size=5.0, grid=(2, 2)), "pixel_size", "mm")
    probe("tiled.psf_points pixel_size 5", lambda: tiled.psf_points(cooke, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=9, pixel_size=5.0), "pixel_size", "mm")
    probe("tiled.tile_centers pixel_size 5", lambda: tiled.tile_centers((8, 8), 5.0, 4), "pixel_size", "mm")
    rays = sampling.collimated(cooke, 0.0, jnp.zeros((2, 2)), 0.55)
    probe("trace newton_iters 10**9", lambda: jl.trace(cooke, rays, newton_iters=10**9).origin, "newton_iters", "1000")
    probe("trace_path newton_iters 5000", lambda: jl.trace_path(cooke, rays, newton_iters=5000).origin, "newton_iters", "1000")
    probe("trace newton_iters 1000 (control)", lambda: jl.trace(cooke, rays, newton_iters=1000).origin, good=True)
    fo = jl.optics.coordinates.frame_of
    probe("frame_of index 99", lambda: fo(cooke, 99), "index", "[0, 5]")
    probe("frame_of index -1 (refused: 0-based, None is the image)", lambda: fo(cooke, -1), "index", "[0, 5]")
    probe("frame_of index 2.0", lambda: fo(cooke, 2.0), "index")
    probe("frame_of index True", lambda: fo(cooke, True), "index")
    probe("frame_of index np.int64(5) (control)", lambda: fo(cooke, np.int64(5))[1], good=True)
    P = jl.paraxial
    probe("marginal_ray wavelength [0.5, 0.6] (documented: one column per wavelength)", lambda: P.marginal_ray(cooke, [0.5, 0.6])[0].shape, good=True)
    probe("marginal_ray wavelength []", lambda: P.marginal_ray(cooke, []), "wavelength", "µm")
    probe("surface_power wavelength 587.6", lambda: P.surface_power(cooke.surfaces[0], 1.0, 1.5, 587.6), "µm", "587.6 nm")
    probe("surface_power n1 0", lambda: P.surface_power(cooke.surfaces[0], 0.0, 1.5), "n1", "|n| >= 1")
    probe("surface_power n2 nan", lambda: P.surface_power(cooke.surfaces[0], 1.0, np.nan), "n2")
    probe("surface_power n2 -1.5 (control: after a mirror)", lambda: P.surface_power(cooke.surfaces[0], -1.0, -1.5), good=True)
    probe("surface_power surface 'S1'", lambda: P.surface_power("S1", 1.0, 1.5), "surface")
    from jaxlens.experiments import classical
    tmp = tempfile.mkdtemp()
    c = cli(lambda *a: classical.main([*a, "--out", os.path.join(tmp, "c"), "--quiet"]))
    for a, word in ((("--fov", "1.4"), "--track"), (("--track", "7000"), "--track"), (("--sensor-diagonal", "7660"), "--sensor-diagonal"),
                    (("--materials", "E48R"), "--materials"), (("--materials", "E48R,OKP4,E48R,OKP4,E48R,AIR"), "--materials entry 6"),
                    (("--fnum", "0.5"), "--fnum"), (("--fov", "170"), "--fov"), (("--track", "2"), "--track"),
                    (("--bfl", "7"), "--bfl"), (("--elements", "1"), "--elements")):
        probe(f"classical {' '.join(a)} (names the flag)", cli(lambda: c(*a)), word)


# ----------------------------------------------------------------------------- imaging, fresh
def imaging_fresh():
    from jaxlens.imaging import distortion, radiometry, render, sampling, tiled
    from jaxlens.imaging.psf import mtf, psf_info
    pts = jnp.zeros((1, 2))
    s_ok = jl.Sensor(resolution=(8, 8), pixel_size=0.01)
    probe("psf pixel_size nan", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=np.nan), "pixel_size")
    probe("psf pixel_size -0.005", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=-0.005), "pixel_size")
    probe("psf pixel_size [0.005, 0.005]", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=[0.005, 0.005]), "pixel_size")
    probe("psf field nan", lambda: jl.psf(cooke, np.nan, kernel_size=9, pixel_size=0.005), "field")
    probe("psf field 0.35 rad? (documented: degrees)", lambda: jl.psf(cooke, 0.35, kernel_size=9, pixel_size=0.005).shape, good=True)
    probe("psf depth -100", lambda: jl.psf(cooke, 0.0, depth=-100.0, kernel_size=9, pixel_size=0.005), "depth")
    probe("psf kernel_size 0", lambda: jl.psf(cooke, 0.0, kernel_size=0, pixel_size=0.005), "kernel_size")
    probe("psf wavelength [] ", lambda: jl.psf(cooke, 0.0, wavelength=[], kernel_size=9, pixel_size=0.005), "wavelength")
    probe("psf_info newton_iters 2.5", lambda: psf_info(cooke, 0.0, kernel_size=9, pixel_size=0.005, newton_iters=2.5), "newton_iters")
    probe("mtf pixel_size 5", lambda: mtf(cooke, 0.0, pixel_size=5.0), "pixel_size", "mm")
    probe("mtf frequencies nan", lambda: mtf(cooke, 0.0, frequencies=[np.nan]), "frequencies")
    probe("mtf newton_iters 5000", lambda: mtf(cooke, 0.0, newton_iters=5000), "newton_iters", "1000")
    probe("render spp 0", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor=s_ok, spp=0, key=jax.random.key(0)), "spp")
    probe("render scene nan", lambda: jl.render(cooke, np.full((8, 8, 3), np.nan), sensor=s_ok, spp=1, key=jax.random.key(0)), "scene")
    probe("render wavelengths nm", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor=s_ok, spp=1, key=jax.random.key(0), wavelengths=[656.3, 587.6, 486.1]), "µm")
    probe("render sensor 'S'", lambda: jl.render(cooke, np.ones((8, 8, 3)), sensor="S", spp=1, key=jax.random.key(0)), "sensor")
    probe("footprints sensor 'S'", lambda: render.footprints(cooke, sensor="S"), "sensor")
    probe("footprints newton_iters 5000", lambda: render.footprints(cooke, sensor=s_ok, newton_iters=5000), "newton_iters", "1000")
    probe("footprints sensor pixel_size 5 (documented: the Sensor's pitch)", lambda: render.footprints(cooke, sensor=jl.Sensor(resolution=(8, 8), pixel_size=5.0)).margin, good=True)
    probe("prewarp sensor of 5 mm pixels (documented: the Sensor's pitch)", lambda: distortion.prewarp(cooke, np.ones((8, 8, 3)), sensor=jl.Sensor(resolution=(8, 8), pixel_size=5.0)).shape, good=True)
    probe("alignment_penalty sensor 'S' (names itself)", lambda: distortion.alignment_penalty(cooke, alpha=1.0, sensor="S"), "alignment_penalty", "sensor")
    probe("inverse_distortion_map iters 10**6", lambda: distortion.inverse_distortion_map(cooke, resolution=(8, 8), pixel_size=0.01, grid=(2, 2), iters=10**6), "iters", "1000")
    probe("relative_illumination newton_iters 5000", lambda: radiometry.relative_illumination(cooke, [0.0], pupil=8, newton_iters=5000), "newton_iters", "1000")
    probe("relative_illumination pupil 100000", lambda: radiometry.relative_illumination(cooke, [0.0], pupil=100000), "pupil", "4096")
    probe("relative_illumination fields nan", lambda: radiometry.relative_illumination(cooke, [np.nan], pupil=8), "fields")
    probe("relative_illumination wavelength 587.6", lambda: radiometry.relative_illumination(cooke, [0.0], pupil=8, wavelength=587.6), "µm")
    probe("tiled.psf_points kernel_size 10**6", lambda: tiled.psf_points(cooke, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=10**6, pixel_size=0.005), "kernel_size", "4096")
    probe("tiled.psf_points newton_iters -1", lambda: tiled.psf_points(cooke, jnp.zeros((1, 2)), None, wavelengths=[0.55], kernel_size=9, pixel_size=0.005, newton_iters=-1), "newton_iters")
    probe("tiled.tile_counts tile 0", lambda: tiled.tile_counts((8, 8), 0), "tile")
    probe("tiled.convolve_tiles pad 'same'", lambda: tiled.convolve_tiles(jnp.ones((8, 8, 1)), jnp.ones((2, 2, 1, 3, 3)), pad="same"), "pad")
    probe("tiled.convolve_tiles even k", lambda: tiled.convolve_tiles(jnp.ones((8, 8, 1)), jnp.ones((2, 2, 1, 4, 4))), "kernels")
    probe("pupil_grid n 0", lambda: sampling.pupil_grid(0), "n")
    probe("pupil_hexapolar rings 2.5", lambda: sampling.pupil_hexapolar(2.5), "rings")
    probe("pupil_polar radius 1.5", lambda: sampling.pupil_polar(4, radius=1.5), "radius")
    probe("pupil_samples 'Grid'", lambda: sampling.pupil_samples("Grid", 3), "scheme")
    probe("collimated pupil (3,)", lambda: sampling.collimated(cooke, 0.0, jnp.zeros(3), 0.55), "pupil")
    probe("collimated field 95", lambda: sampling.collimated(cooke, 95.0, pts, 0.55), "field")
    probe("point_source point behind the lens", lambda: sampling.point_source(cooke, jnp.array([0.0, 0.0, 10.0]), pts, 0.55), "z")
    probe("object_point depth -5", lambda: sampling.object_point(cooke, 0.0, -5.0), "depth")
    probe("field_rays aim 'Real'", lambda: sampling.field_rays(cooke, 0.0, pts, 0.55, aim="Real"), "aim")
    probe("stop_radius stop_size 'Paraxial'", lambda: sampling.stop_radius(cooke, "Paraxial"), "stop_size")
    probe("aim_at_stop iters -1", lambda: sampling.aim_at_stop(cooke, sampling.collimated(cooke, 0.0, pts, 0.55), pts, iters=-1), "iters")
    probe("vignetting_for_fields (lens without factors: documented None)", lambda: str(sampling.vignetting_for_fields(cooke, [0.0])), good=True)


# ----------------------------------------------------------------------------- coordinates, paraxial
def coordinates_paraxial():
    from jaxlens.optics.coordinates import CoordinateBreak, frame_of
    probe("CoordinateBreak tilt_x nan", lambda: CoordinateBreak(tilt_x=np.nan), "tilt_x")
    probe("CoordinateBreak order 2", lambda: CoordinateBreak(order=2), "order")
    probe("CoordinateBreak decenter_x '1'", lambda: CoordinateBreak(decenter_x="1"), "decenter_x")
    probe("frame_of None (control: image surface)", lambda: frame_of(cooke)[1], good=True)
    probe("frame_of index '2'", lambda: frame_of(cooke, "2"), "index")
    P = jl.paraxial
    probe("efl wavelength []", lambda: P.efl(cooke, []), "wavelength")
    probe("efl wavelengths [0.5, 0.6] (documented: one per wavelength)", lambda: P.efl(cooke, [0.5, 0.6]), good=True)
    probe("efl lens 'cooke'", lambda: P.efl("cooke"), "lens")
    probe("bfl wavelength nan", lambda: P.bfl(cooke, np.nan), "wavelength")
    probe("system_matrix wavelength 587.6", lambda: P.system_matrix(cooke, 587.6), "µm")
    probe("system_matrix end 2 start 3", lambda: P.system_matrix(cooke, start=3, end=2), "end")
    probe("signed_indices wavelength []", lambda: P.signed_indices(cooke, []), "wavelength")
    probe("entrance_pupil_magnification wavelength 0 ", lambda: P.entrance_pupil_magnification(cooke, 0.0), "wavelength")
    probe("paraxial_chief_ray field_deg 90", lambda: P.paraxial_chief_ray(cooke, 90.0), "field")
    probe("image_height field nan", lambda: P.image_height(cooke, np.nan), "field")
    probe("paraxial_data wavelength [0.5, 0.6]", lambda: P.paraxial_data(cooke, [0.5, 0.6]), "wavelength")
    probe("working_fnum depth inf (control)", lambda: P.working_fnum(cooke, np.inf), good=True)
    probe("working_fnum depth -1", lambda: P.working_fnum(cooke, -1.0), "depth")
    probe("working_fnum lens 'x'", lambda: P.working_fnum("x", None), "lens")
    probe("x_section lens 'x'", lambda: P.x_section("x"), "lens")


# ----------------------------------------------------------------------------- the tolerance CLI
def tolerance_cli():
    from jaxlens.experiments import tolerance as tol
    tmp = tempfile.mkdtemp()
    design = os.path.join(ROOT, "experiments/classical/designs/seed_0.zmx")
    cooke_file = os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx")
    t = cli(lambda *a: tol.main([*a, "--out", tempfile.mkdtemp()]))
    for a, word in ((("--trials", "0"), "--trials"), (("--trials", "2.5"), "--trials"), (("--threshold", "nan"), "--threshold"),
                    (("--threshold", "-1"), "--threshold"), (("--seed", "-1"), "--seed"), (("--decenter", "-0.01"), "--decenter"),
                    (("--decenter", "inf"), "--decenter"), (("--tilt", "95"), "--tilt"), (("--decenter", "5"), "--decenter"), (("--decenter", "2"), "--decenter")):
        probe(f"tolerance {design.split('/')[-1]} {' '.join(a)}", cli(lambda: t(design, *a)), word)
    probe("tolerance missing.zmx", cli(lambda: t(os.path.join(tmp, "missing.zmx"))), "missing.zmx")
    bad = os.path.join(tmp, "bad.json")
    with open(bad, "w") as fh:
        fh.write("{not json")
    probe("tolerance bad.json", cli(lambda: t(bad)), "bad.json")
    probe("tolerance the cooke triplet (not a classical design)", cli(lambda: t(cooke_file, "--trials", "1")), "cooke_triplet.zmx")


run((round18_gaps, imaging_fresh, coordinates_paraxial, tolerance_cli))
