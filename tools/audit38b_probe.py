# ruff: noqa: E501, E731
"""Round-38b bad-input probes: the public functions earlier rounds left unprobed (the
diffraction MTF formula, the tile-wise convolution and Wiener filters, the pupil samplers'
less used arguments, the paraxial helpers, ``nearest_glasses``, ``apply_aperture``,
``save_json``/``save_zmx`` called directly, the image writers, ``plot`` helpers, the
``nets`` layers, ``perturb``), hand-built pytrees (half-precision, complex and bool leaves,
an empty lens), output paths (a folder, a missing folder, another format's extension) and a
few ``.zmx``/JSON edge files. The table of ``tools/probe_table.py`` (probe | outcome | what
happened).

Gaps found and fixed (one mechanism each):
1. ``imaging.otf.diffraction_mtf`` took any arguments: ν −5 or NaN, λ 0.55 (µm) or 550 (nm)
   for 5.5e-4 mm, F# 0 or −4 gave an MTF of 1 or 0. Concrete arguments are now checked
   (ν ≥ 0 cycles/mm, λ in ``WAVELENGTH_RANGE_MM`` with the µm/nm reading, F# > 0); traced
   ones (its callers under jit) pass.
2. ``io.lensfile.apply_aperture``: fnum −4 gave the EPD of F/4 (the EPD's sign is dropped
   for a negative focal length); NaN, 0, a negative EPD, a string or a list read "the
   entrance pupil diameter comes out as …" or numpy's/JAX's own error. Each argument is
   checked by name first (``checks.number``).
3. Output paths of the whole-file writers (``json_values.output_file``, now also the image
   writers' check): ``save_json``/``save_zmx`` to a folder failed with IsADirectoryError on
   the temporary file, into a missing folder with a FileNotFoundError naming
   ``.a.json.<pid>.partial`` (so did ``plot.save``); ``save_zmx`` wrote Zemax text into
   ``a.json`` and ``save_json`` JSON into ``a.zmx``. ``write_whole`` and ``whole_path``
   check the folder (naming their caller), the lens writers also their extension.
4. Half-precision leaves: ``checks.float_array`` (every numeric field of a Lens, surface or
   material) kept float16/bfloat16 (a thickness of 3.25896 as 3.2598: an EFL 1 µm off
   without a word), where ``Lens.astype(float16)`` is refused; so did ``Rays`` (a
   wavelength of 0.55 as 0.5498). Now a TypeError.
5. ``analysis.tolerance.perturb`` did not check its arguments against the lens: a
   ``clear_radius`` or ``add_r4`` of another length (IndexError), a perturbation of another
   lens ("add got incompatible shapes"), a clear radius of 0, NaN or < 0 (an inf/NaN lens).
   ``tolerance_rigid.check_perturb_args``.
6. ``imaging.sampling.stop_radius(stop_size="real", object_z=...)``: NaN failed in ``Rays``
   ("direction must hold unit vectors ... length nan"), 0 (surface 1's vertex) gave 3.83 mm;
   a concrete ``object_z`` is now checked as ``point_source`` checks its point's z.
7. Vague: the tile-bank refusal (``convolve_tiles``, ``wiener_tiles``, ``tile_evidence``)
   named a tile count without saying it came from the kernels' shape.

The controls (``good=True``) are behaviours judged right: pupil points beyond the unit disc
in ``point_source`` (an overfilled beam), a negative object distance or depth (a virtual
object, documented), ``pupil_samples("random")`` without a key (key 0), a D exponent in a
``.zmx`` (Fortran's), a JSON radius of 1e400 (inf: flat), clipping in ``write_png``.

Before (base 9cf432e) and after (branch probe38b), the same 246 probes,
``PYTHONPATH=<tree> python tools/audit38b_probe.py`` from the tree's root, about 30 s:
    before: clear error: 173, crash: 2, ok: 31, silent wrong: 22, vague error: 18
    after:  clear error: 215, ok: 31
"""

import json
import os
import re
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import dataclasses  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import COOKE, SEED0, fresh, probe, run, warned  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import design as D  # noqa: E402
from jaxlens import nets as N  # noqa: E402
from jaxlens import plot as P  # noqa: E402
from jaxlens import zoo as Z  # noqa: E402
from jaxlens.analysis import tolerance as TL  # noqa: E402
from jaxlens.imaging import otf, tiled  # noqa: E402
from jaxlens.imaging import sampling as S  # noqa: E402
from jaxlens.io import images as IM  # noqa: E402
from jaxlens.io import lensfile as LF  # noqa: E402
from jaxlens.io import zmx as ZMX  # noqa: E402
from jaxlens.optics import catalog as CAT  # noqa: E402
from jaxlens.optics import paraxial as PX  # noqa: E402

cooke = jl.load(COOKE)
L = lambda **k: dataclasses.replace(cooke, **k)
K = jax.random.key(0)


def os_error(fn):
    """An ``OSError`` (a missing folder: ``FileNotFoundError``) judged by its message as a
    ValueError is (``probe`` counts other exceptions as crashes)."""
    def go():
        try:
            return fn()
        except (FileNotFoundError, IsADirectoryError, NotADirectoryError) as e:
            raise ValueError(f"{type(e).__name__}: {e}") from None
    return go


def plots():
    probe("plot_rms_map sensor_size negative", lambda: P.plot_rms_map(np.ones((3, 3)), (-3.0, 4.0)), "sensor_size")
    probe("plot_rms_map sensor_size NaN", lambda: P.plot_rms_map(np.ones((3, 3)), (float("nan"), 4.0)), "sensor_size")
    probe("plot_rms_map 5 values (not n²)", lambda: P.plot_rms_map(np.ones(5), (3.0, 4.0)), "rms_um")
    probe("plot_rms_map rms NaN", lambda: P.plot_rms_map(np.full((3, 3), np.nan), (3.0, 4.0)), "rms")
    probe("plot_rms_map sensor_size scalar", lambda: P.plot_rms_map(np.ones((3, 3)), 5.0), "sensor_size")
    probe("plot_rms_map 3x4", lambda: P.plot_rms_map(np.ones((3, 4)), (3.0, 4.0)), "rms_um")
    probe("plot_tolerance_histogram {}", lambda: P.plot_tolerance_histogram({}), "mc")
    probe("plot_tolerance_histogram list", lambda: P.plot_tolerance_histogram([1, 2]), "mc")
    probe("plot_progress []", lambda: P.plot_progress([]), "history")
    probe("plot_progress 'abc'", lambda: P.plot_progress("abc"), "history")
    probe("plot_field_curvature wavelengths [587.6]", lambda: P.plot_field_curvature(cooke, wavelengths=[587.6]), "wavelength", "µm")
    probe("plot_image 2 channels", lambda: P.plot_image(np.zeros((4, 4, 2))), "img")
    probe("plot_image NaN", lambda: P.plot_image(np.full((4, 4, 3), np.nan)), "img")


def mtf_formula():
    probe("diffraction_mtf nu -5", lambda: otf.diffraction_mtf(-5.0, 0.00055, 4.0), "nu", "cycles/mm")
    probe("diffraction_mtf nu NaN", lambda: otf.diffraction_mtf(float("nan"), 0.00055, 4.0), "nu")
    probe("diffraction_mtf lam_mm 550 (nm)", lambda: otf.diffraction_mtf(50.0, 550.0, 4.0), "lam_mm", "mm")
    probe("diffraction_mtf lam_mm 0.55 (µm)", lambda: otf.diffraction_mtf(50.0, 0.55, 4.0), "lam_mm", "mm")
    probe("diffraction_mtf lam_mm 0", lambda: otf.diffraction_mtf(50.0, 0.0, 4.0), "lam_mm")
    probe("diffraction_mtf fnum 0", lambda: otf.diffraction_mtf(50.0, 0.00055, 0.0), "fnum")
    probe("diffraction_mtf fnum -4", lambda: otf.diffraction_mtf(50.0, 0.00055, -4.0), "fnum")
    probe("diffraction_mtf nu [0, 50, 500] (control)", lambda: otf.diffraction_mtf(np.array([0.0, 50.0, 500.0]), 0.00055, 4.0), good=True)
    probe("diffraction_mtf under jit (control)", lambda: jax.jit(otf.diffraction_mtf)(50.0, 0.00055, 4.0), good=True)
    probe("mtf_directions field NaN", lambda: otf.mtf_directions(float("nan")), "field")
    probe("mtf_directions field 95", lambda: otf.mtf_directions(95.0), "field")
    probe("mtf_directions field [[1, 2, 3]] (control: a batch of θy)", lambda: otf.mtf_directions(np.array([[1.0, 2.0, 3.0]]))[0].shape, good=True)


def tiles():
    img = np.zeros((16, 16, 3), np.float32)
    k = np.ones((2, 2, 3, 3, 3), np.float32) / 9
    probe("tile_counts tile 0", lambda: tiled.tile_counts((16, 16), 0), "tile")
    probe("tile_counts tile 5 (not dividing)", lambda: tiled.tile_counts((16, 16), 5), "tile")
    probe("tile_centers pixel_size -1", lambda: tiled.tile_centers((16, 16), -0.005, 8), "pixel_size")
    probe("tile_centers pixel_size 5 (µm)", lambda: tiled.tile_centers((16, 16), 5.0, 8), "pixel_size")
    probe("tile_centers tile 8.0 float", lambda: tiled.tile_centers((16, 16), 0.005, 8.0), "tile")
    probe("convolve_tiles kernels of 3 x 3 tiles on a 16 x 16 frame", lambda: tiled.convolve_tiles(img, np.ones((3, 3, 3, 3, 3), np.float32)), "kernels", "3")
    probe("convolve_tiles kernels even 4", lambda: tiled.convolve_tiles(img, np.ones((2, 2, 3, 4, 4), np.float32)), "kernel")
    probe("convolve_tiles channels mismatch", lambda: tiled.convolve_tiles(img, np.ones((2, 2, 1, 3, 3), np.float32)), "channel")
    probe("convolve_tiles pad 'reflect'", lambda: tiled.convolve_tiles(img, k, pad="reflect"), "pad")
    probe("convolve_tiles image NaN", lambda: tiled.convolve_tiles(np.full_like(img, np.nan), k), "image")
    probe("convolve_tiles kernels NaN", lambda: tiled.convolve_tiles(img, np.full_like(k, np.nan)), "kernel")
    probe("convolve_tiles image 2-D", lambda: tiled.convolve_tiles(img[..., 0], k), "image")
    probe("wiener_tiles kernels of 3 x 3 tiles on a 16 x 16 frame", lambda: tiled.wiener_tiles(img, np.ones((3, 3, 3, 3, 3), np.float32), 0.01), "kernels", "3")
    probe("wiener_tiles nsr -1", lambda: tiled.wiener_tiles(img, k, -1.0), "nsr")
    probe("wiener_tiles nsr NaN", lambda: tiled.wiener_tiles(img, k, float("nan")), "nsr")
    probe("wiener_tiles nsr 0", lambda: tiled.wiener_tiles(img, k, 0.0), "nsr")
    probe("wiener_tiles prior 'flat'", lambda: tiled.wiener_tiles(img, k, 0.01, prior="flat"), "prior")
    probe("wiener_tiles halo -1", lambda: tiled.wiener_tiles(img, k, 0.01, halo=-1), "halo")
    probe("wiener_tiles halo 2.5", lambda: tiled.wiener_tiles(img, k, 0.01, halo=2.5), "halo")
    probe("tile_evidence nsr -1", lambda: tiled.tile_evidence(img, k, -1.0), "nsr")
    probe("tile_evidence prior 'white2'", lambda: tiled.tile_evidence(img, k, 0.01, prior="white2"), "prior")
    probe("tile_evidence kernels of 3 x 3 tiles on a 16 x 16 frame", lambda: tiled.tile_evidence(img, np.ones((3, 3, 3, 3, 3), np.float32), 0.01), "kernels", "3")


def samplers():
    probe("pupil_samples scheme 'hex'", lambda: S.pupil_samples("hex", 3), "scheme", "hexapolar")
    probe("pupil_samples random without key (control: key 0)", lambda: S.pupil_samples("random", 10).shape, good=True)
    probe("pupil_samples grid n 0", lambda: S.pupil_samples("grid", 0), "n")
    probe("pupil_stratified n_side 0", lambda: S.pupil_stratified(K, 0), "n_side")
    probe("pupil_stratified n_side 2.5", lambda: S.pupil_stratified(K, 2.5), "n_side")
    probe("pupil_polar n_side -1", lambda: S.pupil_polar(-1), "n_side")
    probe("pupil_polar radius 1.5", lambda: S.pupil_polar(4, radius=1.5), "radius")
    probe("pupil_polar radius 0", lambda: S.pupil_polar(4, radius=0.0), "radius")
    probe("pupil_polar radius NaN", lambda: S.pupil_polar(4, radius=float("nan")), "radius")
    probe("pupil_hexapolar rings -1", lambda: S.pupil_hexapolar(-1), "rings")
    probe("pupil_hexapolar rings 2.5", lambda: S.pupil_hexapolar(2.5), "rings")
    probe("stop_radius stop_size 'exact'", lambda: S.stop_radius(cooke, "exact"), "stop_size", "paraxial")
    probe("vignetting_map factors 4 values", lambda: S.vignetting_map(np.zeros(4), np.zeros((3, 2))), "factors")
    probe("vignetting_map VCX 1.5", lambda: S.vignetting_map(np.array([0, 0, 1.5, 0, 0.0]), np.zeros((3, 2))), "VCX")
    probe("vignetting_map factors NaN", lambda: S.vignetting_map(np.array([0, 0, np.nan, 0, 0.0]), np.zeros((3, 2))), "factor")
    probe("vignetting_map pupil [3, 3]", lambda: S.vignetting_map(np.zeros(5), np.zeros((3, 3))), "pupil")
    probe("stop_radius 'real' object_z NaN", lambda: S.stop_radius(cooke, "real", object_z=float("nan")), "object_z", "nan")
    probe("stop_radius 'real' object_z 0 (surface 1's vertex)", lambda: S.stop_radius(cooke, "real", object_z=0.0), "object_z", "surface 1")
    probe("stop_radius 'real' object_z -100 (control)", lambda: S.stop_radius(cooke, "real", object_z=-100.0), good=True)
    pt = np.array([0.0, 0.0, -100.0])
    probe("point_source point z 0 (at surface 1)", lambda: S.point_source(cooke, np.array([0.0, 0.0, 0.0]), S.pupil_grid(3)).direction, "point")
    probe("point_source point 2 values", lambda: S.point_source(cooke, np.array([0.0, -100.0]), S.pupil_grid(3)).direction, "point")
    probe("point_source point NaN", lambda: S.point_source(cooke, np.array([0.0, np.nan, -100.0]), S.pupil_grid(3)).direction, "point")
    probe("point_source wavelength 550", lambda: S.point_source(cooke, pt, S.pupil_grid(3), 550.0).direction, "wavelength")
    probe("point_source pupil beyond the unit disc (control: an overfilled beam)", lambda: S.point_source(cooke, pt, np.array([[3.0, 0.0]])).direction, good=True)


def paraxial():
    probe("paraxial_chief_ray field_deg 95", lambda: PX.paraxial_chief_ray(cooke, 95.0), "field")
    probe("paraxial_chief_ray field_deg NaN", lambda: PX.paraxial_chief_ray(cooke, float("nan")), "field")
    probe("image_height field_deg 90", lambda: PX.image_height(cooke, 90.0), "field")
    probe("image_height field_deg [1, 2] (control)", lambda: PX.image_height(cooke, np.array([1.0, 2.0])), good=True)
    probe("image_height field_deg '5'", lambda: PX.image_height(cooke, "5"), "field")
    probe("working_fnum depth -5 (control: a virtual object, documented)", lambda: PX.working_fnum(cooke, -5.0), good=True)
    probe("working_fnum depth 0", lambda: PX.working_fnum(cooke, 0.0), "depth")
    probe("working_fnum depth NaN", lambda: PX.working_fnum(cooke, float("nan")), "depth")
    probe("system_matrix start 9", lambda: PX.system_matrix(cooke, start=9), "start")
    probe("system_matrix start 3 end 1", lambda: PX.system_matrix(cooke, start=3, end=1), "end")
    probe("system_matrix start 1.5", lambda: PX.system_matrix(cooke, start=1.5), "start")
    probe("system_matrix start -1", lambda: PX.system_matrix(cooke, start=-1), "start")
    probe("surface_power n1 0", lambda: PX.surface_power(cooke.surfaces[0], 0.0, 1.5), "n1")
    probe("surface_power n1 NaN", lambda: PX.surface_power(cooke.surfaces[0], float("nan"), 1.5), "n1")
    probe("paraxial_data wavelength 587.6", lambda: PX.paraxial_data(cooke, wavelength=587.6).efl, "wavelength")
    probe("entrance_pupil_z wavelength -1", lambda: PX.entrance_pupil_z(cooke, wavelength=-1.0), "wavelength")
    probe("marginal_ray wavelength NaN", lambda: PX.marginal_ray(cooke, wavelength=float("nan")), "wavelength")
    probe("nearest_glasses count 0", lambda: CAT.nearest_glasses(1.5, 60.0, count=0), "count")
    probe("nearest_glasses nd NaN", lambda: CAT.nearest_glasses(float("nan"), 60.0), "nd")
    probe("nearest_glasses vd -5", lambda: CAT.nearest_glasses(1.5, -5.0), "vd")
    probe("nearest_glasses nd 15", lambda: CAT.nearest_glasses(15.0, 60.0), "nd")
    probe("nearest_glasses catalogs 'NOPE'", lambda: CAT.nearest_glasses(1.5, 60.0, catalogs="NOPE"), "NOPE")
    probe("nearest_glasses count 2.5", lambda: CAT.nearest_glasses(1.5, 60.0, count=2.5), "count")
    probe("reversed_lens image_distance NaN", lambda: jl.tracing.reversed_lens(cooke, image_distance=float("nan")), "image_distance")
    probe("reversed_lens image_distance '5'", lambda: jl.tracing.reversed_lens(cooke, image_distance="5"), "image_distance")
    probe("reversed_lens image_distance [1, 2]", lambda: jl.tracing.reversed_lens(cooke, image_distance=[1.0, 2.0]), "image_distance")


def aperture():
    probe("apply_aperture epd and fnum both", lambda: LF.apply_aperture(cooke, epd=5.0, fnum=4.0), "epd", "fnum")
    probe("apply_aperture none given", lambda: LF.apply_aperture(cooke).epd, "epd")
    probe("apply_aperture fnum -4", lambda: LF.apply_aperture(cooke, fnum=-4.0).epd, "fnum", "-4")
    probe("apply_aperture fnum NaN", lambda: LF.apply_aperture(cooke, fnum=float("nan")).epd, "fnum", "nan")
    probe("apply_aperture fnum '4'", lambda: LF.apply_aperture(cooke, fnum="4").epd, "fnum", "'4'")
    probe("apply_aperture stop_semi_diameter 0", lambda: LF.apply_aperture(cooke, stop_semi_diameter=0.0).epd, "stop_semi_diameter", "mm")
    probe("apply_aperture epd -5", lambda: LF.apply_aperture(cooke, epd=-5.0).epd, "epd", "-5", "mm")
    probe("apply_aperture epd [5, 6]", lambda: LF.apply_aperture(cooke, epd=[5.0, 6.0]).epd, "epd")
    probe("apply_aperture fnum 5 (control)", lambda: LF.apply_aperture(cooke, fnum=5.0).epd, good=True)


def writers():
    d = fresh("w")
    img = np.zeros((4, 4, 3), np.float32)
    probe("save_json to a folder", os_error(lambda: LF.save_json(cooke, d)), "save_json", "folder")
    probe("save_zmx to a folder", os_error(lambda: ZMX.save_zmx(cooke, d)), "save_zmx", "folder")
    probe("save_json into a missing folder", os_error(lambda: LF.save_json(cooke, os.path.join(d, "nope", "a.json"))), "save_json", "nope", "no such folder")
    probe("save_zmx into a missing folder", os_error(lambda: ZMX.save_zmx(cooke, os.path.join(d, "nope", "a.zmx"))), "save_zmx", "nope", "no such folder")
    probe("plot.save into a missing folder", os_error(lambda: P.save(P.plot_image(img), os.path.join(d, "nope", "a.png"))), "save", "nope", "no such folder")
    probe("write_png into a missing folder", os_error(lambda: IM.write_png(os.path.join(d, "nope", "a.png"), img)), "nope")
    probe("save_zmx path a.json (Zemax text in a .json)", lambda: ZMX.save_zmx(cooke, os.path.join(d, "a.json")), "save_zmx", ".zmx", "a.json")
    probe("save_json path a.zmx (JSON in a .zmx)", lambda: LF.save_json(cooke, os.path.join(d, "a.zmx")), "save_json", ".json", "a.zmx")
    probe("save_json path a.txt", lambda: LF.save_json(cooke, os.path.join(d, "a.txt")), "save_json", ".json")
    probe("save_json path A.JSON (control)", lambda: LF.save_json(cooke, os.path.join(d, "A.JSON")), good=True)
    probe("write_exr to a folder", lambda: IM.write_exr(d, img), "write_exr", "folder")
    probe("write_png to a folder", lambda: IM.write_png(d, img), "write_png", "folder")
    probe("plot.save to a folder", lambda: P.save(P.plot_image(img), d), "file name")
    probe("plot.save to .xyz", lambda: P.save(P.plot_image(img), os.path.join(d, "a.xyz")), "xyz")
    probe("write_psf_stack to a folder", lambda: IM.write_psf_stack(d, np.ones((2, 5, 5), np.float32)), "write_psf_stack", "folder")


def images():
    img = np.random.default_rng(0).random((8, 8, 3)).astype(np.float32)
    png = lambda: os.path.join(fresh("png"), "a.png")
    probe("psnr data_range 0", lambda: IM.psnr(img, img * 0.9, data_range=0.0), "data_range")
    probe("psnr data_range -1", lambda: IM.psnr(img, img * 0.9, data_range=-1.0), "data_range")
    probe("psnr shapes differ", lambda: IM.psnr(img, img[:4]), "shape")
    probe("ssim 2x2 image (smaller than the window)", lambda: IM.ssim(img[:2, :2], img[:2, :2] * 0.9), "ssim")
    probe("ssim NaN", lambda: IM.ssim(img, np.full_like(img, np.nan)), "test")
    probe("psnr identical (control: inf)", lambda: IM.psnr(img, img), good=True)
    probe("write_png bits 12", lambda: IM.write_png(png(), img, bits=12), "bits")
    probe("write_png NaN image", lambda: IM.write_png(png(), np.full_like(img, np.nan)), "img")
    probe("write_png 4-D", lambda: IM.write_png(png(), img[None]), "image", "(1, 8, 8, 3)")
    probe("write_png 2 channels (control: grey + alpha)", lambda: IM.write_png(png(), img[..., :2]), good=True)
    probe("write_png values below 0 (control: clipped, documented)", lambda: IM.write_png(png(), img - 2), good=True)
    probe("srgb_to_linear -0.5", lambda: IM.srgb_to_linear(-0.5), "v")
    probe("to_linear uint16 (control)", lambda: IM.to_linear(np.full((2, 2, 3), 65535, np.uint16)).max(), good=True)
    probe("write_psf_stack names count", lambda: IM.write_psf_stack(os.path.join(fresh("exr"), "a.exr"), np.ones((2, 5, 5), np.float32), names=["a"]), "names")
    probe("write_psf_stack 2-D", lambda: IM.write_psf_stack(os.path.join(fresh("exr"), "a.exr"), np.ones((5, 5), np.float32)), "psfs")
    probe("scene 'nope'", lambda: IM.scene("nope"), "nope")
    probe("scene size (0, 5)", lambda: IM.scene(size=(0, 5)), "size")
    probe("scene size (5.5, 5)", lambda: IM.scene(size=(5.5, 5)), "size")


def lens_trees():
    s = cooke.surfaces
    t = np.asarray(cooke.thickness)
    probe("Lens surfaces () (empty lens)", lambda: jl.efl(L(surfaces=(), thickness=np.zeros(0), materials=())), "surface")
    probe("Lens thickness complex", lambda: L(thickness=t + 0j), "thickness")
    probe("Lens thickness bool", lambda: L(thickness=np.ones(len(s), bool)), "thickness")
    probe("Lens thickness int (control)", lambda: jl.efl(L(thickness=np.round(t).astype(int))), good=True)
    probe("Lens thickness 2 short", lambda: L(thickness=t[:-2]), "thickness")
    probe("Lens thickness inf at the end", lambda: L(thickness=np.r_[t[:-1], np.inf]), "thickness")
    probe("Lens materials a list (control)", lambda: jl.efl(L(materials=list(cooke.materials))), good=True)
    probe("Lens materials a str 'N-BK7'", lambda: L(materials=("N-BK7",) * len(cooke.materials)), "material")
    probe("Lens surfaces holding None", lambda: L(surfaces=(None,) + tuple(s[1:])), "surface")
    probe("Lens surfaces holding a Lens", lambda: L(surfaces=(cooke,) + tuple(s[1:])), "surface")
    probe("Standard c complex", lambda: jl.Standard(c=0.01 + 1j), "c")
    probe("Standard c [1] in a Lens", lambda: jl.efl(L(surfaces=(jl.Standard(c=np.array([float(s[0].c)]), semi_diameter=float(s[0].semi_diameter)),) + tuple(s[1:]))), "c")
    probe("Standard k bool True", lambda: jl.Standard(c=0.01, k=True), "k")
    probe("Standard semi_diameter inf (control: unclipped)", lambda: jl.Standard(c=0.01, semi_diameter=np.inf).semi_diameter, good=True)
    probe("EvenAsphere coeffs complex", lambda: jl.EvenAsphere(c=0.01, coeffs=np.array([1e-5 + 1j])), "coeffs")
    probe("Lens wavelengths complex", lambda: L(wavelengths=np.asarray(cooke.wavelengths) + 0j), "wavelength")
    probe("Lens wavelengths 2-D", lambda: L(wavelengths=np.asarray(cooke.wavelengths)[None]), "wavelength")
    probe("Lens epd [1] (not 0-d)", lambda: jl.efl(L(epd=np.array([float(cooke.epd)]))), "epd")
    probe("Lens fields [[0, 10], [0, 20]] (control: x, y pairs)", lambda: L(fields=np.array([[0.0, 10.0], [0.0, 20.0]])).fields, good=True)
    probe("Lens object_distance -100 (control: a virtual object, documented)", lambda: L(object_distance=-100.0).object_distance, good=True)
    probe("Lens object_distance NaN", lambda: L(object_distance=float("nan")), "object_distance")
    probe("Lens thickness float16 (3.25896 -> 3.2598)", lambda: jl.efl(L(thickness=t.astype(np.float16))), "thickness", "float16")
    probe("Standard c bfloat16", lambda: jl.Standard(c=jnp.asarray(0.045, jnp.bfloat16)), "c", "bfloat16")
    probe("Sellmeier B float16", lambda: jl.Sellmeier(B=np.array([1.04, 0.23, 1.01], np.float16), C=np.array([0.006, 0.02, 103.6])), "B", "float16")
    probe("ModelGlass nd float16", lambda: jl.ModelGlass(nd=np.float16(1.5168), vd=64.17), "nd", "float16")
    probe("Lens epd float16", lambda: L(epd=np.float16(10.0)), "epd", "float16")
    up = np.tile(np.array([0.0, 0.0, 1.0]), (2, 1))
    probe("Rays origin and direction float16", lambda: jl.Rays(origin=np.zeros((2, 3), np.float16), direction=up.astype(np.float16), wavelength=0.55), "origin", "float16")
    probe("Rays wavelength float16 (0.55 -> 0.5498)", lambda: jl.Rays(origin=np.zeros((2, 3)), direction=up, wavelength=np.float16(0.55)), "wavelength", "float16")
    probe("Rays of Python numbers (control)", lambda: jl.Rays(origin=[0.0, 0.0, 0.0], direction=[0, 0, 1.0], wavelength=0.55).dtype, good=True)
    probe("Lens mixed float32 thickness, float64 rest (control)", lambda: jl.trace(L(thickness=t.astype(np.float32)), S.field_rays(cooke, 0.0, S.pupil_grid(3))).valid.mean(), good=True)


def zmx_edge():
    t = open(SEED0, encoding="utf-8").read().replace("\r\n", "\n")
    curv = re.search(r"CURV (\S+)", t.split("\nSURF 2\n")[1]).group(1)

    def zf(text, raw=None):
        p = os.path.join(fresh("zmx"), "t.zmx")
        with open(p, "wb") as f:
            f.write(raw if raw is not None else text.encode("utf-8"))
        return lambda: jl.load(p).num_surfaces

    probe("zmx CURV with a D exponent (control: Fortran's)", zf(t.replace("CURV " + curv, "CURV " + curv.replace("E", "D"), 1)), good=True)
    probe("zmx SURF 2 before SURF 1", zf(t.replace("SURF 1\n", "SURF X1\n").replace("SURF 2\n", "SURF 1\n").replace("SURF X1\n", "SURF 2\n")), "SURF", "expected 1")
    probe("zmx SURF 1 twice", zf(t.replace("SURF 2\n", "SURF 1\n")), "SURF", "expected 2")
    probe("zmx Latin-1 byte in a comment (control)", zf(None, raw=t.replace("SURF 1\n", "SURF 1\n  COMM caf\xe9\n").encode("latin-1")), good=True)
    probe("zmx trailing garbage after CURV", zf(t.replace("CURV " + curv, "CURV " + curv + "xyz", 1)), "curvature", ":")
    probe("zmx tab separated (control)", zf(t.replace("CURV ", "CURV\t")), good=True)
    probe("zmx NUL byte", zf(t.replace("SURF 2\n", "SURF 2\x00\n")), "binary")
    probe("zmx empty file", zf(""), "no SURF", "t.zmx")
    probe("zmx only a BOM", zf("\ufeff"), "no SURF", "t.zmx")
    probe("zmx binary garbage", zf(None, raw=bytes(range(256)) * 4), "binary", "t.zmx")


def json_edge():
    d0 = json.load(open(COOKE))
    s = json.dumps(d0)
    th = json.dumps(d0["surfaces"][1]["thickness"])

    def jf(raw=None, mut=None):
        if mut:
            d = json.loads(s)
            mut(d)
            raw = json.dumps(d)
        p = os.path.join(fresh("json"), "t.json")
        with open(p, "w", encoding="utf-8") as f:
            f.write(raw)
        return lambda: jl.load(p).num_surfaces

    probe("json NaN literal thickness", jf(s.replace(th, "NaN", 1)), "thickness")
    probe("json Infinity epd", jf(json.dumps({**d0, "aperture": {"epd": 1}}).replace('"epd": 1', '"epd": Infinity')), "epd")
    probe("json thickness true", jf(s.replace(th, "true", 1)), "thickness")
    probe("json thickness 1e400", jf(s.replace(th, "1e400", 1)), "thickness")
    probe("json radius 1e400 (control: flat)", jf(s.replace(json.dumps(d0["surfaces"][1]["radius"]), "1e400", 1)), good=True)
    probe("json radius as a string '22.01'", jf(s.replace(json.dumps(d0["surfaces"][1]["radius"]), '"22.01"', 1)), "radius")
    probe("json thickness 10**400 (an integer)", jf(s.replace(th, "1" + "0" * 400, 1)), "thickness")
    probe("json nested 10000 deep", jf('{"a":' * 10000 + "1" + "}" * 10000), "t.json")
    probe("json BOM (control)", jf("\ufeff" + s), good=True)
    probe("json trailing garbage", jf(s + "xyz"), "t.json")
    probe("json two objects", jf(s + s), "t.json")
    probe("json surfaces null", jf(json.dumps({**d0, "surfaces": None})), "surfaces")
    # Round 42b: a bare number (EPD in mm, or an F-number as photographers say "aperture"?) is refused.
    probe("json aperture a number (refused since round 42b: EPD or F-number?)", jf(mut=lambda d: d.update(aperture=10.0)), "aperture", "epd", "fnum")
    probe("json aperture {}", jf(mut=lambda d: d.update(aperture={})), "aperture")
    probe("json aperture fnum -5", jf(mut=lambda d: d.update(aperture={"fnum": -5.0})), "fnum")
    probe("json aperture stop_semi_diameter 0", jf(mut=lambda d: d.update(aperture={"stop_semi_diameter": 0.0})), "stop_semi_diameter")
    probe("json aperture fnum '5'", jf(mut=lambda d: d.update(aperture={"fnum": "5"})), "fnum")
    probe("json fields values nested [[0], [14]]", jf(mut=lambda d: d["fields"].update(values=[[0.0], [14.0]])), "fields")
    probe("json fields type 'object_height_mm'", jf(mut=lambda d: d["fields"].update(type="object_height_mm")), "type")
    probe("json fields values strings", jf(mut=lambda d: d["fields"].update(values=["0", "14"])), "fields")
    probe("json wavelengths_nm a number", jf(mut=lambda d: d.update(wavelengths_nm=587.6)), "wavelengths")
    probe("json wavelengths_nm [[486.1]]", jf(mut=lambda d: d.update(wavelengths_nm=[[486.1]])), "wavelengths")
    probe("json surface key 'Radius'", jf(mut=lambda d: d["surfaces"][1].update(Radius=d["surfaces"][1].pop("radius"))), "Radius")
    probe("json material {'name': 5}", jf(mut=lambda d: d["surfaces"][1].update(material={"name": 5})), "material")
    probe("json material a list", jf(mut=lambda d: d["surfaces"][1].update(material=["N-SK16"])), "material")
    probe("json material 'N-SK16 ' (control: spaces stripped)", jf(mut=lambda d: d["surfaces"][1].update(material="N-SK16 ")), good=True)
    probe("json two stops", jf(mut=lambda d: [x.update(stop=True) for x in d["surfaces"][1:3]]), "stop")
    probe("json stop 'yes'", jf(mut=lambda d: d["surfaces"][3].update(stop="yes")), "stop")
    probe("json name 5", jf(mut=lambda d: d.update(name=5)), "name")
    probe("json description a list", jf(mut=lambda d: d.update(description=["a"])), "description")


def nets():
    probe("Pointwise c_in 0", lambda: N.Pointwise(0, 4, key=K), "c_in")
    probe("Pointwise c_out -1", lambda: N.Pointwise(4, -1, key=K), "c_out")
    probe("Pointwise c_in 2.5", lambda: N.Pointwise(2.5, 4, key=K), "c_in")
    probe("Upsample c_in 3 (odd: the shuffle)", lambda: N.Upsample(3, key=K)(jnp.zeros((4, 4, 3))).shape, "c_in")
    probe("Depthwise channels 0", lambda: N.Depthwise(0, key=K), "channels")
    probe("LayerNorm2d eps -1", lambda: N.LayerNorm2d(4, eps=-1.0), "eps")
    probe("LayerNorm2d eps NaN", lambda: N.LayerNorm2d(4, eps=float("nan")), "eps")
    probe("LayerNorm2d channels 0", lambda: N.LayerNorm2d(0), "channels")
    probe("simple_gate odd channels", lambda: N.simple_gate(jnp.zeros((2, 2, 3))), "channels")
    probe("Pointwise applied to 3 channels (made for 4)", lambda: N.Pointwise(4, 2, key=K)(jnp.zeros((4, 4, 3))), "channel")
    probe("Depthwise applied to 3 channels (made for 4)", lambda: N.Depthwise(4, key=K)(jnp.zeros((4, 4, 3))), "channel")
    probe("LayerNorm2d applied to 3 channels (made for 4)", lambda: N.LayerNorm2d(4)(jnp.zeros((4, 4, 3))), "channel")
    probe("Pointwise dtype int32", lambda: N.Pointwise(4, 2, key=K, dtype=jnp.int32), "dtype")
    probe("Pointwise key None", lambda: N.Pointwise(4, 2, key=None), "key")
    probe("num_parameters of a list", lambda: N.num_parameters([1.0, 2.0]), "model")


def design_tol():
    probe("sine_path n 0 (control: one stage at the end)", lambda: D.sine_path(0.0, 1.0, 0), good=True)
    probe("sine_path n -3", lambda: D.sine_path(0.0, 1.0, -3), "n")
    probe("sine_path n 2.5", lambda: D.sine_path(0.0, 1.0, 2.5), "n")
    probe("sine_path start NaN", lambda: D.sine_path(float("nan"), 1.0, 4), "start")
    probe("HullMaterials corners 2 points", lambda: D.HullMaterials(np.array([[1.5, 60.0], [1.6, 40.0]])), "corners")
    probe("HullMaterials corners [V, 3]", lambda: D.HullMaterials(np.ones((4, 3))), "corners")
    probe("HullMaterials corners NaN", lambda: D.HullMaterials(np.array([[1.5, 60.0], [1.6, 40.0], [np.nan, 50.0]])), "corners")
    probe("HullMaterials corners clockwise (control: logits reach the point)", lambda: D.HullMaterials(np.array([[1.5, 60.0], [1.7, 40.0], [1.6, 30.0]])[::-1]).logits(1.6, 45.0), good=True)
    probe("TableMaterials wavelengths in nm", lambda: D.TableMaterials(np.array([486.1, 587.6, 656.3])), "wavelength")
    probe("TableMaterials wavelengths empty", lambda: D.TableMaterials(np.array([])), "wavelength")
    probe("double_gauss clip 'no'", lambda: Z.double_gauss(clip="no"), "clip")
    z = TL.zero_perturbation(cooke)
    n = cooke.num_surfaces
    probe("perturb clear_radius of 2 for 6 surfaces", lambda: TL.perturb(cooke, z, np.ones(2)), "clear_radius", "6")
    probe("perturb clear_radius -1", lambda: TL.perturb(cooke, z, -np.ones(n)), "clear_radius", "mm")
    probe("perturb clear_radius 0", lambda: TL.perturb(cooke, z, np.zeros(n)), "clear_radius", "mm")
    probe("perturb clear_radius NaN", lambda: TL.perturb(cooke, z, np.full(n, np.nan)), "clear_radius")
    probe("perturb add_r4 of 1 for 6 surfaces", lambda: TL.perturb(cooke, z, np.ones(n), add_r4=(True,)), "add_r4", "6")
    probe("perturb p of the double Gauss (11 surfaces)", lambda: TL.perturb(cooke, TL.zero_perturbation(Z.double_gauss()), np.ones(n)), "perturb", "p.", "11", "6 surfaces")
    probe("perturb under jit (control)", lambda: jl.efl(jax.jit(lambda p: TL.perturb(cooke, p, np.ones(n)))(z)), good=True)
    probe("zero_perturbation elements 'yes'", lambda: TL.zero_perturbation(cooke, elements="yes"), "elements")
    probe("percentile q 0.95 (warned)", warned(lambda: TL.percentile(np.array([1.0, 2.0, 3.0]), 0.95)), "0.95")
    probe("percentile q 150", lambda: TL.percentile(np.array([1.0, 2.0]), 150), "q")
    probe("percentile values []", lambda: TL.percentile(np.array([]), 50), "values")


if __name__ == "__main__":
    run([plots, mtf_formula, tiles, samplers, paraxial, aperture, writers, images, lens_trees,
         zmx_edge, json_edge, nets, design_tol])
