# ruff: noqa: E501, B023, E731
"""Round-23 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for what rounds 9-22 did not reach: the two items round 22 left (a bare dispersion
formula's ``index`` past its poles, ``Lens(...)`` keeping wavelengths outside its glasses'
data), the surfaces no round had probed (``QTypeAsphere``, ``ZernikeSag``, ``XYPolynomial``,
``Binary2``, ``Grating``, ``TiltedPlane``, ``Aperture``), ``Tabulated``/``Schott`` data,
``Rays``' origins, the analyses' less used arguments (``encircled_energy``, ``distortion``,
``seidel``, ``wavefront``, ``zernike_fit``, ``self_intersection``, ``spot_rays``), images
(``write_png``, ``write_exr``, ``ssim``, ``scene``), tolerancing (``yield_fraction``,
``sample_perturbations``), design (``DesignSpec``, ``sine_path``, ``reweighting_mask``,
``random_starts``, ``evaluate``) and the tools a user runs on a folder
(``tools/check_corpus.py``).

Before (main at 2aa9a1a) and after (merged, with the formula pole check), 160 probes, ``PYTHONPATH=<tree> python
tools/audit23_probe.py`` under ``ulimit -v 16000000``, one 2-core machine (42 s; no probe
starts long work on main, so there is no before-mode):
    before: clear error 128, crash 4, ok 12, silent wrong 11, vague error 5
    after:  clear error 145, ok 12, silent wrong 3 (the formula pole check: 4 of the 11)
Fixed: a Grating's lines_per_um in lines per mm (600 was built: every order evanescent), a
Tabulated's hand-given wavelength_range reversed or not finite, ``load_agf`` of a folder and
``tools/check_corpus.py`` on a missing folder or a file (tracebacks), ``reweighting_mask`` of
a NaN RMS (every weight 1), ``vignetting_map`` of a NaN factor (every ray NaN),
``encircled_energy``'s ``pupil_side`` (refused as CoherentPSF's "pupil") and ``subsamples``
(no bound: a 28 PiB allocation), ``sample_perturbations``' key (JAX's error), a JSON file's
field type (the message named no supported type), and a ``DesignSpec``/``--fov`` of a few
degrees, likely radians (the message asked about mm only).

Left (the 3 "silent wrong" rows): ``Lens(...)`` keeping wavelengths outside its glasses'
data. By design, not a silent answer: every analysis refuses a wavelength it uses outside the
data, and an analysis of the primary wavelength alone still runs when another wavelength is
out of range (tests/test_input_probes_round9.py). Refusing them in ``Lens`` was tried and
broke that, and the .zmx reader's per-WAVM-line messages (it builds the Lens first).

Run: PYTHONPATH=$PWD python tools/audit23_probe.py [filter]
"""

import dataclasses
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
def cli(f):
    f.cli = True
    return f


# ----------------------------------------------------------------------------- round 22's items
def round22_items():
    from jaxlens.optics import materials as M
    bk7 = jl.get_material("N-BK7")
    raw = bk7.model
    probe("Sellmeier(N-BK7).index(12 µm) (past its 10.2 µm pole, again)", lambda: raw.index(12.0), "12", "µm", "pole")
    probe("Sellmeier(N-BK7).index([0.5, 11]) (one past the pole)", lambda: raw.index(np.array([0.5, 11.0])), "11", "µm", "pole")
    probe("Sellmeier2 index(6 µm) past its 5 µm pole", lambda: M.Sellmeier2(np.array([0.0, 1.0, 0.1, 0.5, 5.0])).index(6.0), "6", "µm", "pole")
    probe("Handbook2 index(0.2 µm) below its 0.224 µm pole", lambda: M.Handbook2(np.array([2.3, 0.01, 0.05, 0.01])).index(0.2), "µm", "pole")
    probe("Sellmeier(N-BK7).extrapolated_index(11 µm) (documented: the formula anywhere)", lambda: float(raw.extrapolated_index(11.0)), good=True)
    probe("SILICON.index(5 µm) (control: catalog range beyond the formula's pole)", lambda: float(jl.get_material("SILICON").index(5.0)), good=True)
    lens_bk7 = dataclasses.replace(cooke, materials=[bk7 if isinstance(m, M.Tabulated) else m for m in cooke.materials])
    probe("Lens(N-BK7, wavelengths (3.0,)) built", lambda: dataclasses.replace(lens_bk7, wavelengths=(3.0,), primary=0).wavelengths, "3", "µm", "2.5")
    probe("Lens(N-BK7, wavelengths (0.2, 0.5876)) built", lambda: dataclasses.replace(lens_bk7, wavelengths=(0.2, 0.5876), primary=1).wavelengths, "0.2", "µm", "0.3")
    probe("Lens(N-BK7, wavelengths (1.0,)) (control: inside 0.3-2.5)", lambda: float(dataclasses.replace(lens_bk7, wavelengths=(1.0,), primary=0).wavelengths[0]), good=True)
    probe("Lens(raw Sellmeier, wavelengths (11.0,)) built", lambda: dataclasses.replace(lens_bk7, materials=[raw if isinstance(m, jl.CatalogMaterial) else m for m in lens_bk7.materials], wavelengths=(11.0,), primary=0).wavelengths, "11", "µm")


# ----------------------------------------------------------------------------- surfaces
def surfaces():
    probe("QTypeAsphere norm_radius 0", lambda: jl.QTypeAsphere(c=0.01, coeffs=(1e-3,), norm_radius=0.0, semi_diameter=5.0), "norm_radius", "mm")
    probe("QTypeAsphere norm_radius -5", lambda: jl.QTypeAsphere(c=0.01, coeffs=(1e-3,), norm_radius=-5.0, semi_diameter=5.0), "norm_radius", "mm")
    probe("QTypeAsphere qtype 'Q'", lambda: jl.QTypeAsphere(c=0.01, coeffs=(1e-3,), norm_radius=5.0, semi_diameter=5.0, qtype="Q"), "qtype")
    probe("QTypeAsphere coeffs nan", lambda: jl.QTypeAsphere(c=0.01, coeffs=(np.nan,), norm_radius=5.0, semi_diameter=5.0), "coeffs")
    probe("ZernikeSag norm_radius nan", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), norm_radius=np.nan, semi_diameter=5.0), "norm_radius")
    probe("ZernikeSag ordering 'Noll'", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), norm_radius=5.0, semi_diameter=5.0, ordering="Noll"), "ordering")
    probe("ZernikeSag extrapolate 'no'", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), norm_radius=5.0, semi_diameter=5.0, extrapolate="no"), "extrapolate")
    probe("ZernikeSag decenter_x inf", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), norm_radius=5.0, semi_diameter=5.0, decenter_x=np.inf), "decenter_x")
    probe("XYPolynomial norm_radius 0", lambda: jl.XYPolynomial(coeffs=(0.0, 1e-3), norm_radius=0.0, semi_diameter=5.0), "norm_radius")
    probe("XYPolynomial coeffs inf", lambda: jl.XYPolynomial(coeffs=(0.0, np.inf), norm_radius=5.0, semi_diameter=5.0), "coeffs")
    probe("Binary2 norm_radius -1", lambda: jl.Binary2(phase_coeffs=(1.0,), norm_radius=-1.0, semi_diameter=5.0), "norm_radius")
    probe("Binary2 order nan", lambda: jl.Binary2(phase_coeffs=(1.0,), order=np.nan, norm_radius=5.0, semi_diameter=5.0), "order")
    probe("Binary2 phase_coeffs 2-D", lambda: jl.Binary2(phase_coeffs=np.ones((2, 2)), norm_radius=5.0, semi_diameter=5.0), "phase_coeffs")
    probe("Grating lines_per_um 600 (lines/mm given)", lambda: jl.Grating(lines_per_um=600.0, semi_diameter=5.0), "lines_per_um", "µm")
    probe("Grating lines_per_um -1", lambda: jl.Grating(lines_per_um=-1.0, semi_diameter=5.0), "lines_per_um")
    probe("Grating order inf", lambda: jl.Grating(lines_per_um=0.6, order=np.inf, semi_diameter=5.0), "order")
    probe("TiltedPlane tan_x inf", lambda: jl.TiltedPlane(tan_x=np.inf, semi_diameter=5.0), "tan_x")
    probe("TiltedPlane tan_y nan", lambda: jl.TiltedPlane(tan_y=np.nan, semi_diameter=5.0), "tan_y")
    probe("Aperture shape 'square'", lambda: jl.Aperture("square", 1.0, 1.0), "shape")
    probe("Aperture half_x -1", lambda: jl.Aperture("rect", -1.0, 1.0), "half_x", "mm")
    probe("Aperture half_y nan", lambda: jl.Aperture("rect", 1.0, np.nan), "half_y")
    probe("Aperture blocks 'yes'", lambda: jl.Aperture("rect", 1.0, 1.0, blocks="yes"), "blocks")
    probe("Hybrid odd_x nan", lambda: jl.Hybrid(odd_x=(np.nan, 0, 0, 0), semi_diameter=5.0), "odd_x")
    probe("Stop semi_diameter nan", lambda: jl.Stop(np.nan), "semi_diameter")
    probe("Stop semi_diameter 0", lambda: jl.Stop(0.0), "semi_diameter")
    probe("CoordinateBreak tilt_z inf", lambda: jl.CoordinateBreak(tilt_z=np.inf), "tilt_z", "deg")


# ----------------------------------------------------------------------------- materials, rays
def materials_rays():
    probe("Tabulated wavelengths decreasing (documented: any order)", lambda: float(jl.Tabulated(np.array([0.65, 0.55, 0.45]), np.array([1.5, 1.51, 1.52])).index(0.65)), good=True)
    probe("Tabulated wavelengths duplicate", lambda: jl.Tabulated(np.array([0.45, 0.55, 0.55]), np.array([1.52, 1.51, 1.50])), "wavelengths", "distinct")
    probe("Tabulated indices 0.5 (below 1)", lambda: jl.Tabulated(np.array([0.45, 0.55, 0.65]), np.array([0.5, 0.5, 0.5])), "indices", "1")
    probe("Tabulated indices shape differs", lambda: jl.Tabulated(np.array([0.45, 0.55, 0.65]), np.array([1.5, 1.5])), "indices")
    probe("Tabulated wavelength_range reversed", lambda: jl.Tabulated(np.array([0.45, 0.55, 0.65]), np.array([1.52, 1.51, 1.50]), wavelength_range=(0.7, 0.4)), "wavelength_range")
    probe("Schott coeffs nan", lambda: jl.Schott(np.array([2.27, -0.01, 0.01, 0.0, 0.0, np.nan])), "coeffs")
    probe("Sellmeier C negative (no pole)", lambda: float(jl.Sellmeier(np.array([1.0]), np.array([-0.01])).index(0.5876)), good=True)
    probe("ModelGlass nd 5 (no optical glass)", lambda: jl.ModelGlass(5.0, 30.0), "nd")
    probe("get_material '' (documented: air)", lambda: type(jl.get_material("")).__name__, good=True)
    probe("get_material None", lambda: jl.get_material(None), "name")
    probe("get_material 'N-BK7' catalogs 'SHOTT'", lambda: jl.get_material("N-BK7", "SHOTT"), "SHOTT", "SCHOTT")
    probe("glass_info 'NBK7' (close match N-BK7)", lambda: jl.glass_info("NBK7"), "N-BK7")
    probe("register_catalog name ''", lambda: jl.register_catalog({"X": jl.ModelGlass(1.5, 60.0)}, ""), "name")
    agf = os.path.join(TMP, "bad.agf")
    with open(agf, "w") as f:
        f.write("NM GLASSX 2 0 1.5 60 0 0 1\nCD 1.0 abc 0 0 0 0\nLD 0.3 2.5\n")
    probe("load_agf CD with 'abc' (names the line)", lambda: jl.load_agf(agf), "bad.agf:2")
    probe("load_agf a folder", lambda: jl.load_agf(TMP), "folder")
    probe("Rays origin nan", lambda: jl.trace(cooke, jl.Rays(jnp.array([[0.0, np.nan, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([0.5876]))).origin, "origin")
    probe("Rays wavelength bool", lambda: jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([True])), "wavelength")
    probe("Rays valid float 0.5", lambda: jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([0.5876]), valid=jnp.array([0.5])), "valid")
    probe("trace upto 99 (6 surfaces)", lambda: jl.trace(cooke, jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([0.5876])), upto=99), "upto")
    probe("trace chunk 0", lambda: jl.trace(cooke, jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([0.5876])), chunk=0), "chunk")
    probe("trace chunk 'big'", lambda: jl.trace(cooke, jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), jnp.array([0.5876])), chunk="big"), "chunk")


# ----------------------------------------------------------------------------- analysis
def analysis():
    from jaxlens import analysis as A
    probe("encircled_energy radii negative", lambda: A.encircled_energy(cooke, 0.0, jnp.array([-0.01, 0.01])), "radii", "mm")
    probe("encircled_energy radii 2-D (documented: any shape)", lambda: A.encircled_energy(cooke, 0.0, jnp.ones((2, 2)) * 0.01).energy, good=True)
    probe("encircled_energy subsamples 10**6", lambda: A.encircled_energy(cooke, 0.0, jnp.array([0.01]), method="diffraction", pixel_size=0.002, subsamples=10**6), "subsamples")
    probe("encircled_energy method 'FFT'", lambda: A.encircled_energy(cooke, 0.0, jnp.array([0.01]), method="FFT"), "method")
    probe("encircled_energy shape 'Square'", lambda: A.encircled_energy(cooke, 0.0, jnp.array([0.01]), shape="Square"), "shape")
    probe("encircled_energy subsamples 0", lambda: A.encircled_energy(cooke, 0.0, jnp.array([0.01]), subsamples=0), "subsamples")
    probe("encircled_energy pupil_side 10**6", lambda: A.encircled_energy(cooke, 0.0, jnp.array([0.01]), method="diffraction", pixel_size=0.002, pupil_side=10**6), "pupil_side")
    probe("radius_for_fraction fraction nan", lambda: A.radius_for_fraction(cooke, 0.0, np.nan), "fraction")
    probe("distortion fields [] (empty)", lambda: A.distortion(cooke, fields=jnp.zeros((0,))), "fields")
    probe("seidel field 90", lambda: A.seidel(cooke, field=90.0), "field", "deg")
    probe("seidel wavelength 0.0005876 (mm)", lambda: A.seidel(cooke, wavelength=0.0005876), "wavelength", "µm")
    probe("wavefront grid 1", lambda: A.wavefront(cooke, 0.0, grid=1), "grid")
    probe("wavefront grid 10**6", lambda: A.wavefront(cooke, 0.0, grid=10**6), "grid")
    probe("wavefront reference 'sphere'", lambda: A.wavefront(cooke, 0.0, reference="chief sphere"), "reference")
    probe("zernike_fit terms 0", lambda: A.zernike_fit(jnp.zeros(4), jnp.zeros(4), jnp.zeros(4), terms=0), "terms")
    probe("zernike_fit terms 10**7", lambda: A.zernike_fit(jnp.zeros(4), jnp.zeros(4), jnp.zeros(4), terms=10**7), "terms")
    probe("zernike_fit x, y shapes differ", lambda: A.zernike_fit(jnp.zeros(4), jnp.zeros(5), jnp.zeros(4)), "same shape")
    probe("zernike_fit values nan", lambda: A.zernike_fit(jnp.linspace(-0.5, 0.5, 9), jnp.zeros(9), jnp.full(9, jnp.nan), terms=4).coefficients, "0 valid points")
    probe("zernike_fit indexing 'ansi '", lambda: A.zernike_fit(jnp.zeros(4), jnp.zeros(4), jnp.zeros(4), indexing="ansi "), "indexing")
    probe("zernike_terms at (2, 0) (documented: continued outside the disc)", lambda: A.zernike_terms(jnp.array([2.0]), jnp.array([0.0]), terms=4), good=True)
    probe("self_intersection min_gap -1", lambda: A.self_intersection(cooke, min_gap=-1.0), "min_gap", "mm")
    probe("self_intersection n_radial 10**9", lambda: A.self_intersection(cooke, n_radial=10**9), "n_radial")
    probe("self_intersection semi_diameters wrong length", lambda: A.self_intersection(cooke, jnp.ones(3)), "semi_diameters")
    probe("spot_rays field 'on-axis'", lambda: A.spot_rays(cooke, "on-axis"), "field")
    probe("field_curvature wavelengths 0.5876e3 nm", lambda: A.field_curvature(cooke, wavelengths=(587.6,)), "587.6", "µm")


# ----------------------------------------------------------------------------- images
def images():
    from jaxlens.io import images as I
    probe("write_png bits 12", lambda: I.write_png(os.path.join(TMP, "a.png"), np.zeros((4, 4, 3)), bits=12), "bits", "8", "16")
    probe("write_png into a folder path", lambda: I.write_png(TMP, np.zeros((4, 4, 3))), "path")
    probe("write_png nan image", lambda: I.write_png(os.path.join(TMP, "b.png"), np.full((4, 4, 3), np.nan)), "img")
    probe("write_exr complex image", lambda: I.write_exr(os.path.join(TMP, "c.exr"), np.zeros((4, 4, 3), complex)), "img")
    probe("write_exr channels 2 names for 3", lambda: I.write_exr(os.path.join(TMP, "d.exr"), np.zeros((4, 4, 3)), channels=["R", "G"]), "channels")
    f = os.path.join(TMP, "notimage.png")
    with open(f, "w") as fh:
        fh.write("hello")
    probe("read_png of a text file", lambda: I.read_png(f), "PNG")
    probe("ssim shapes differ", lambda: I.ssim(np.zeros((8, 8)), np.zeros((8, 9))), "shape")
    probe("ssim data_range nan", lambda: I.ssim(np.zeros((8, 8)), np.zeros((8, 8)), data_range=np.nan), "data_range")
    probe("scene 'astronautt'", lambda: I.scene("astronautt"), "astronaut")
    probe("scene size (0, 64)", lambda: I.scene("astronaut", size=(0, 64)), "size")
    probe("scene size (10**6, 10**6)", lambda: I.scene("astronaut", size=(10**6, 10**6)), "size")
    probe("write_psf_stack names short", lambda: I.write_psf_stack(os.path.join(TMP, "p.exr"), np.ones((3, 5, 5)), names=["a"]), "names")


# ----------------------------------------------------------------------------- tolerancing, design
def tolerancing_design():
    from jaxlens import design as D
    from jaxlens import tolerance as T
    from jaxlens.design.evaluate import evaluate
    probe("yield_fraction threshold_um nan", lambda: T.yield_fraction(np.ones(4), np.nan), "threshold_um")
    probe("yield_fraction rms_um empty", lambda: T.yield_fraction(np.zeros(0), 5.0), "rms_um")
    probe("yield_fraction min_valid 99 (percent?)", lambda: T.yield_fraction(np.ones(4), 5.0, min_valid=99.0), "min_valid")
    probe("DesignSpec fov -80", lambda: D.DesignSpec(fov=-80.0), "fov", "deg")
    probe("DesignSpec fov 1.41 (radians?)", lambda: D.DesignSpec(fov=1.41), "total_track", "fov in degrees")
    probe("DesignSpec sensor_diagonal 7660 (µm)", lambda: D.DesignSpec(sensor_diagonal=7660.0), "sensor_diagonal", "mm")
    probe("DesignSpec n_elements 0", lambda: D.DesignSpec(n_elements=0, materials=()), "n_elements")
    probe("DesignSpec materials one short", lambda: D.DesignSpec(materials=("E48R",) * 5), "materials")
    probe("DesignSpec stop 99", lambda: D.DesignSpec(stop=99), "stop")
    probe("DesignSpec efl nan", lambda: D.DesignSpec(efl=np.nan), "efl")
    probe("DesignSpec sensor_pixels 0", lambda: D.DesignSpec(sensor_pixels=0), "sensor_pixels")
    probe("DesignSpec asphere_terms -1", lambda: D.DesignSpec(asphere_terms=-1), "asphere_terms")
    probe("DesignSpec total_track < bfl", lambda: D.DesignSpec(total_track=0.5, bfl=0.8), "total_track", "bfl")
    probe("sine_path n 0 (documented: one stage at the end)", lambda: D.sine_path(0.0, 1.0, 0), good=True)
    probe("sine_path n 10**12", lambda: D.sine_path(0.0, 1.0, HUGE), "n")
    probe("sine_path end nan", lambda: D.sine_path(0.0, np.nan, 5), "end")
    probe("reweighting_mask threshold 80 (percent?)", lambda: D.reweighting_mask(jnp.ones((3,)), threshold=80.0), "threshold")
    probe("reweighting_mask rms nan", lambda: D.reweighting_mask(jnp.array([1.0, np.nan, 2.0])), "rms")
    probe("random_starts seeds []", lambda: D.random_starts(D.DesignSpec(), []), "seeds")
    probe("random_starts seeds [1.5]", lambda: D.random_starts(D.DesignSpec(), [1.5]), "seeds")
    probe("evaluate n 0", lambda: evaluate(cooke, D.DesignSpec(), n=0), "n")
    probe("evaluate min_valid 2", lambda: evaluate(cooke, D.DesignSpec(), min_valid=2.0), "min_valid")


# ----------------------------------------------------------------------------- tools and CLIs
def tools_cli():
    import check_corpus

    from jaxlens.experiments import classical
    f = os.path.join(TMP, "afile.txt")
    open(f, "w").close()
    probe("check_corpus.py on a missing folder", cli(lambda: check_corpus.main([os.path.join(TMP, "missing")])), "folder")
    probe("check_corpus.py on a file", cli(lambda: check_corpus.main([f])), "folder")
    probe("classical --out an existing file", cli(lambda: classical.main(["--smoke", "--out", f, "--quiet"])), "--out")
    probe("classical --fov 1.41 (radians?)", cli(lambda: classical.main(["--fov", "1.41", "--out", os.path.join(TMP, "cf"), "--quiet"])), "--fov", "deg")
    probe("classical --sensor-diagonal 7660 (µm)", cli(lambda: classical.main(["--sensor-diagonal", "7660", "--out", os.path.join(TMP, "cs"), "--quiet"])), "--sensor-diagonal", "mm")
    probe("classical --materials N-BK7 (one for six)", cli(lambda: classical.main(["--materials", "N-BK7", "--out", os.path.join(TMP, "cm"), "--quiet"])), "--materials")
    probe("classical --elements 0", cli(lambda: classical.main(["--elements", "0", "--out", os.path.join(TMP, "ce"), "--quiet"])), "--elements")
    probe("classical --elements 10**6", cli(lambda: classical.main(["--elements", "1000000", "--out", os.path.join(TMP, "ce2"), "--quiet"])), "--elements")


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


# ----------------------------------------------------------------------------- second runs
def second_runs():
    """A second run into the folder of a first (finished) run, or into a folder of the
    user's own files: refused before any work, and the folder left as it was."""
    from jaxlens.experiments import classical
    from jaxlens.experiments import tolerance as tol
    from jaxlens.experiments.edof import cli as edof
    from jaxlens.experiments.runfolder import FINISHED
    run_dir = os.path.join(TMP, "first_run")
    os.makedirs(run_dir, exist_ok=True)
    for name, text in ((FINISHED, "finished\n"), ("summary.json", "{}")):
        with open(os.path.join(run_dir, name), "w") as fh:
            fh.write(text)
    mine = os.path.join(TMP, "my_files")
    os.makedirs(mine, exist_ok=True)
    with open(os.path.join(mine, "thesis.tex"), "w") as fh:
        fh.write("keep me")
    design = os.path.join(os.path.dirname(__file__), "..", "experiments", "classical", "designs", "seed_13.zmx")
    kept = lambda f: cli(lambda: (f(), sorted(os.listdir(run_dir)), sorted(os.listdir(mine)))[0])
    probe("classical --out <a finished run> (no --overwrite)", kept(lambda: classical.main(["--smoke", "--out", run_dir, "--quiet"])), "--out", "earlier run")
    probe("classical --out <my files> --overwrite", kept(lambda: classical.main(["--smoke", "--out", mine, "--overwrite", "--quiet"])), "--out", "not empty")
    probe("classical --ablation --ablation-out <a file>", cli(lambda: classical.main(["--ablation", "--ablation-out", os.path.join(mine, "thesis.tex"), "--out", os.path.join(TMP, "ab"), "--quiet"])), "--ablation-out", "file")
    # The tolerance CLI writes tolerance.json beside a classical run by design (its example:
    # --out experiments/classical); what it must not replace is its own earlier report.
    tol_dir = os.path.join(TMP, "tol_run")
    os.makedirs(tol_dir, exist_ok=True)
    with open(os.path.join(tol_dir, "tolerance.json"), "w") as fh:
        fh.write("{}")
    probe("tolerance --out <its earlier report> (no --overwrite)", cli(lambda: tol.main([design, "--out", tol_dir])), "--out", "earlier run")
    probe("edof --out <a finished run> (no --overwrite)", argv_main(lambda: kept(edof.main)(), ["--smoke", "--out", run_dir, "--quiet"]), "--out", "earlier run")
    probe("edof --out <my files> --overwrite", argv_main(lambda: kept(edof.main)(), ["--smoke", "--out", mine, "--overwrite", "--quiet"]), "--out", "not empty")
    probe("first run and my files still there (control)", lambda: (sorted(os.listdir(run_dir)), sorted(os.listdir(mine))), good=True)


# ----------------------------------------------------------------------------- JSON files
def json_files():
    import copy
    import json
    base = os.path.join(TMP, "cooke.json")
    jl.save(cooke, base)
    with open(base) as fh:
        good = json.load(fh)

    def edited(name, edit):
        d = copy.deepcopy(good)
        edit(d)
        path = os.path.join(TMP, f"{name}.json")
        with open(path, "w") as fh:
            json.dump(d, fh)
        return lambda: jl.load(path)

    def surf(i, **kw):
        return lambda d: d["surfaces"][i].update(kw)

    def top(**kw):
        return lambda d: d.update(kw)

    probe("JSON units length 'inch'", edited("inch", lambda d: d["units"].update(length="inch")), "length", "mm")
    probe("JSON units wavelength 'nm' with µm values", edited("unm", lambda d: d["units"].update(wavelength="nm")), "wavelength")
    probe("JSON wavelengths_nm holding µm values", edited("wlnm", lambda d: d.update(wavelengths_nm=d.pop("wavelengths_um"))), "wavelengths_nm", "nm")
    probe("JSON primary 3 of 3 wavelengths", edited("prim", top(primary=3)), "primary")
    probe("JSON primary 1.5", edited("prim15", top(primary=1.5)), "primary")
    probe("JSON fields type 'angle_rad_y'", edited("frad", lambda d: d["fields"].update(type="angle_rad_y")), "type", "angle_deg_y")
    probe("JSON fields values [0, 95]", edited("f95", lambda d: d["fields"].update(values=[0.0, 95.0])), "95", "deg")
    probe("JSON aperture epd -10", edited("epdneg", top(aperture={"epd": -10.0})), "epd")
    probe("JSON aperture epd and fnum both", edited("epdf", top(aperture={"epd": 10.0, "fnum": 4.0})), "aperture")
    probe("JSON aperture {} (none)", edited("apnone", top(aperture={})), "aperture")
    probe("JSON surfaces [] (none)", edited("nosurf", top(surfaces=[])), "surfaces")
    probe("JSON curvature '0.05' (documented: a number's text is read as it)", lambda: float(edited("cstr", surf(1, curvature="0.05"))().surfaces[0].c), good=True)
    probe("JSON curvature true", edited("cbool", surf(1, curvature=True)), "curvature")
    probe("JSON surface type 'Standard ' (documented: case and punctuation ignored)", lambda: type(edited("tsp", surf(1, type="Standard "))().surfaces[0]).__name__, good=True)
    probe("JSON material 'N-BK77' (close: N-BK7)", edited("mat", surf(1, material="N-BK77")), "N-BK7")
    probe("JSON format 'jaxlens.lens/2'", edited("fmt2", top(format="jaxlens.lens/2")), "format")
    probe("JSON semi_diameter -1", edited("sdneg", surf(1, semi_diameter=-1.0)), "semi_diameter")
    probe("JSON thickness nan (string 'nan')", edited("tnan", surf(2, thickness="nan")), "thickness")
    probe("JSON unknown key 'curvatur'", edited("typo", surf(1, curvatur=0.05)), "curvatur")


# ----------------------------------------------------------------------------- sampling
def sampling():
    S = jl.sampling
    from jaxlens import tolerance as T
    key = jax.random.PRNGKey(0)
    probe("pupil_random n 0", lambda: S.pupil_random(key, 0), "n")
    probe("pupil_random n 10**12", lambda: S.pupil_random(key, HUGE), "n")
    probe("pupil_random key 0 (int)", lambda: S.pupil_random(0, 16), "key")
    probe("pupil_random dtype int32", lambda: S.pupil_random(key, 16, dtype=jnp.int32), "dtype")
    probe("pupil_stratified n_side 0", lambda: S.pupil_stratified(key, 0), "n_side")
    probe("pupil_stratified n_side 10**6", lambda: S.pupil_stratified(key, 10**6), "n_side")
    probe("vignetting_map factors shape (4,)", lambda: S.vignetting_map(jnp.zeros(4), jnp.zeros((3, 2))), "factors")
    probe("vignetting_map factors nan", lambda: S.vignetting_map(jnp.full(5, jnp.nan), jnp.zeros((3, 2))), "factors")
    model = T.ToleranceModel(cooke) if hasattr(T, "ToleranceModel") else None
    probe("sample_perturbations trials 10**12", lambda: T.sample_perturbations(model, HUGE, key), "trials")
    probe("sample_perturbations key 'x'", lambda: T.sample_perturbations(model, 4, "x"), "sample_perturbations", "key")


run((round22_items, surfaces, materials_rays, analysis, images, tolerancing_design, tools_cli, second_runs, json_files, sampling))
