"""Bad input, round 25 (tools/audit25_probe.py): one test per class of gap fixed. Each names
what main did with the input: a silent answer, a traceback, or a message that named the wrong
value or no line. All checks run where concrete inputs enter, before any tracing.
"""

import copy
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from PIL import Image

import jaxlens as jl
from jaxlens import nets, zoo
from jaxlens.io import images, lensfile
from jaxlens.optics import materials as M
from jaxlens.tracing import backward

BK7_B = (1.03961212, 0.231792344, 1.01046945)
BK7_C = (0.00600069867, 0.0200179144, 103.560653)
AGF = ("CC test catalog\nNM GA 2 0 1.5168 64.17 0 0\n"
       "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
       "LD 0.3 2.5\n")
KEPLER = pathlib.Path(__file__).parent / "data" / "afocal_kepler.zmx"


def _json_with(material):
    d = lensfile.lens_to_dict(zoo.cooke_triplet())
    d = copy.deepcopy(d)
    d["surfaces"][1]["material"] = material
    d["surfaces"][1].pop("index_at_wavelengths", None)
    return d


def test_sellmeier_coefficients_in_nm2_or_without_terms_are_refused():
    # main: C in nm² gave n = 0.99997 at the d line; () was air; a 2-D B was kept.
    assert float(jl.Sellmeier(BK7_B, BK7_C).index(0.5875618)) == pytest.approx(1.5168, abs=1e-4)
    with pytest.raises(ValueError, match=r"no finite index >= 1 at any wavelength in 0\.15–30 "
                                         r"µm.*C in µm²"):
        jl.Sellmeier(BK7_B, tuple(c * 1e6 for c in BK7_C))
    with pytest.raises(ValueError, match=r"Sellmeier: B and C must be 1-D .*shape \(0,\)"):
        jl.Sellmeier((), ())
    with pytest.raises(ValueError, match=r"1-D .*shape \(2, 3\)"):
        jl.Sellmeier(np.array([BK7_B, BK7_B]), np.array([BK7_C, BK7_C]))
    # A traced formula is not evaluated: the check skips it.
    assert jax.jit(lambda b: jl.Sellmeier(b, jnp.asarray(BK7_C)).index(0.55))(
        jnp.asarray(BK7_B)) > 1.5


def test_an_agf_formula_that_describes_no_material_names_the_line(tmp_path):
    # main: "glass GA of catalog BAD: refractive index 0.99997 ..." without file or line.
    p = tmp_path / "bad.agf"
    p.write_text(AGF.replace("0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653",
                             "6000.69867 0.231792344 20017.9144 1.01046945 103560653"))
    with pytest.raises(ValueError, match=r"bad\.agf:2: .*C in µm²"):
        jl.load_agf(p)


def test_a_model_glass_abbe_number_given_as_a_fraction_is_refused():
    # main: vd 0.6417 (for 64.17) was a glass 100 times too dispersive, in Python and JSON.
    with pytest.raises(ValueError, match=r"vd must be an Abbe number >= 5 .*got 0\.6417"):
        jl.ModelGlass(1.5168, 0.6417)
    with pytest.raises(ValueError, match=r"surface 1: .*vd must be an Abbe number >= 5"):
        lensfile.lens_from_dict(_json_with({"nd": 1.5168, "vd": 0.6417}))
    assert float(jl.ModelGlass(1.5168, 64.17).index(0.5875618)) == pytest.approx(1.5168)


@pytest.mark.parametrize("kwargs, match", [
    (dict(wavelength_range=(400.0, 700.0)), r"wavelength_range .*0\.4 µm, not 400 nm"),
    (dict(formula=-3), r"formula must be a Zemax dispersion formula number"),
    (dict(catalog_nd=0.5), r"catalog_nd must be None or a d-line index in \[1, 4\.5\]"),
])
def test_catalog_material_metadata_is_checked(kwargs, match):
    # main: each was kept (a range in nm then refused every wavelength in µm, a catalog nd
    # of 0.5 was written to .zmx GLAS lines).
    with pytest.raises(ValueError, match=match):
        jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", **kwargs)


def test_catalog_material_model_and_material_names_have_their_types():
    # main: CatalogMaterial(1.5, "X") and Sellmeier(..., name=5) were built.
    with pytest.raises(TypeError, match=r"model must be a material .*got float"):
        jl.CatalogMaterial(1.5, "X")
    with pytest.raises(TypeError, match=r"Sellmeier: name must be a str, got int 5"):
        jl.Sellmeier(BK7_B, BK7_C, name=5)


def test_tabulated_wavelength_range_in_nm_and_laurent_powers_are_refused():
    # main: a table's range (400, 700) was kept; powers "ab" failed at the first index.
    with pytest.raises(ValueError, match=r"wavelength_range \(400\.0, 700\.0\) µm holds none"):
        jl.Tabulated((0.4861, 0.5876, 0.6563), (1.5224, 1.5168, 1.5143),
                     wavelength_range=(400.0, 700.0))
    with pytest.raises(ValueError, match=r"Laurent: powers must be a tuple of whole numbers"):
        M.Laurent((2.27, -0.01), powers="ab")


def test_a_json_material_class_with_a_misspelt_field_is_refused():
    # main: the unknown key was dropped and the class default used without a word.
    spec = {"class": "Tabulated", "wavelength": [0.4861, 0.5876], "indices": [1.52, 1.517]}
    with pytest.raises(ValueError, match=r"material class Tabulated has no field 'wavelength' "
                                         r"\(did you mean 'wavelengths'\?\)"):
        lensfile.lens_from_dict(_json_with(spec))


def test_unknown_glass_model_says_why_the_line_cannot_serve(tmp_path):
    # main: with unknown_glass='model', a GLAS line of nd 0.5168 gave "Unknown material"
    # and nothing on why the option was not used.
    p = tmp_path / "g.zmx"
    p.write_text(KEPLER.read_text().replace("GLAS N-BK7 0 0 1.5168", "GLAS N-BK8 0 0 0.5168", 1))
    with pytest.raises(ValueError, match=r"g\.zmx:51: .*unknown_glass='model' needs the line's "
                                         r"nd > 1 and Vd > 0 .*got nd 0\.5168"):
        jl.load(p, unknown_glass="model")


def test_read_png_drops_the_alpha_of_grey_images(tmp_path):
    # main: an 8-bit grey+alpha 4x6 PNG read as (6, 2, 3) (skimage), a 16-bit one kept its
    # alpha as a second channel.
    p8 = tmp_path / "la8.png"
    Image.fromarray(np.dstack([np.full((4, 6), 128, np.uint8),
                               np.full((4, 6), 255, np.uint8)]), "LA").save(p8)
    a = images.read_png(p8, linear=False)
    assert a.shape == (4, 6) and a[0, 0] == pytest.approx(128 / 255)
    p16 = tmp_path / "la16.png"
    images.write_png(p16, np.dstack([np.full((4, 6), 0.25), np.ones((4, 6))]), bits=16,
                     linear=False)
    b = images.read_png(p16, linear=False)
    assert b.shape == (4, 6) and b[0, 0] == pytest.approx(0.25, abs=1e-4)


def test_read_exr_channels_are_names(tmp_path):
    # main: "RGB" was read letter by letter, [] failed in np.stack, ["R", "R"] was kept.
    p = tmp_path / "a.exr"
    images.write_exr(p, np.ones((4, 4, 3)))
    with pytest.raises(ValueError, match=r"has no channel\(s\) \['RGB'\]"):
        images.read_exr(p, channels="RGB")
    for bad in ([], ["R", "R"]):
        with pytest.raises(ValueError, match=r"read_exr: channels must be distinct"):
            images.read_exr(p, channels=bad)
    assert images.read_exr(p, channels="G").shape == (4, 4)


def test_image_writers_refuse_missing_folders_and_empty_images(tmp_path):
    # main: OpenEXR's RuntimeError, open()'s FileNotFoundError, or a reshape error.
    missing = tmp_path / "no"
    with pytest.raises(ValueError, match=r"write_exr: no such folder"):
        images.write_exr(missing / "x.exr", np.ones((4, 4)))
    with pytest.raises(ValueError, match=r"write_png: no such folder"):
        images.write_png(missing / "x.png", np.ones((4, 4)))
    with pytest.raises(ValueError, match=r"write_psf_stack: no such folder"):
        images.write_psf_stack(missing / "s.exr", np.ones((2, 5, 5)))
    with pytest.raises(ValueError, match=r"write_exr: img is empty"):
        images.write_exr(tmp_path / "e.exr", np.ones((0, 4, 3)))
    with pytest.raises(ValueError, match=r"write_png: img is empty"):
        images.write_png(tmp_path / "e.png", np.ones((0, 4, 3)))


def test_write_png_refuses_codes_given_as_floats(tmp_path):
    # main: 200.0 everywhere was clipped to 1: a white file.
    with pytest.raises(ValueError, match=r"whole numbers up to 200: 0…255"):
        images.write_png(tmp_path / "h.png", np.full((4, 4, 3), 200.0))
    images.write_png(tmp_path / "ok.png", np.full((4, 4, 3), 1.5))  # HDR: clipped, documented


def test_psf_stacks_refuse_nan_integer_and_plain_images(tmp_path):
    # main: NaN and int64 PSFs were written; an RGB image read as one PSF named ''.
    with pytest.raises(ValueError, match=r"write_psf_stack: psfs must be finite"):
        images.write_psf_stack(tmp_path / "s.exr", np.full((2, 5, 5), np.nan))
    with pytest.raises(ValueError, match=r"write_psf_stack: psfs must be a float image"):
        images.write_psf_stack(tmp_path / "s.exr", np.ones((2, 5, 5), np.int64))
    p = tmp_path / "rgb.exr"
    images.write_exr(p, np.ones((4, 4, 3)))
    with pytest.raises(ValueError, match=r"not a PSF stack .*channel '[RGB]' has no layer"):
        images.read_psf_stack(p)


def test_psnr_ssim_refuse_a_code_range_and_complex_images():
    # main: data_range 255 for [0, 1] images scored 68 dB; complex images scored 1.0 (SSIM).
    a, b = np.full((8, 8), 0.5), np.full((8, 8), 0.4)
    assert images.psnr(a, b, data_range=1.0) == pytest.approx(20.0)
    with pytest.raises(ValueError, match=r"psnr: data_range 255 for images whose values lie"):
        images.psnr(a, b, data_range=255)
    with pytest.raises(ValueError, match=r"ssim: reference and test must be real images"):
        images.ssim(np.ones((16, 16), complex), np.ones((16, 16), complex))


def test_backward_tracing_names_the_values_given():
    # main: upto=99 was refused as "got -94" (the mirrored index), image_distance nan as
    # the mirrored lens's "thickness".
    cooke = zoo.cooke_triplet()
    r = jl.Rays(jnp.zeros((2, 3)), jnp.array([[0.0, 0.0, -1.0]] * 2), jnp.full((2,), 0.55),
                jnp.ones(2, bool), jnp.zeros(2))
    with pytest.raises(ValueError, match=r"trace_backward: upto must be .*\[0, 5\].*got 99"):
        jl.trace_backward(cooke, r, upto=99)
    with pytest.raises(ValueError, match=r"reversed_lens: image_distance must be a finite"):
        backward.reversed_lens(cooke, image_distance=np.nan)


def test_nafnet_key_and_block_count_messages():
    # main: key=0 was an AttributeError; middle_blocks=-1 said "got 16" (the width).
    with pytest.raises(TypeError, match=r"NAFNet: key must be a JAX PRNG key"):
        nets.NAFNet(key=0)
    with pytest.raises(ValueError, match=r"middle_blocks -1"):
        nets.NAFNet(middle_blocks=-1, key=jax.random.PRNGKey(0))
