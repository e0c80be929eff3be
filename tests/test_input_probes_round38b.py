"""Round-38b bad-input fixes (tools/audit38b_probe.py): the diffraction MTF formula's
arguments, ``apply_aperture``'s arguments by name, the lens-file writers' output paths (a
folder, a missing folder, another format's extension), half-precision leaves of a lens,
``perturb``'s arguments against its lens, and the tile-bank refusal naming the kernels. One
test per gap; each says what main did with the input."""

import dataclasses

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import tolerance
from jaxlens.imaging import otf, sampling, tiled
from jaxlens.io import lensfile, zmx
from jaxlens.io.json_values import write_whole


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


@pytest.mark.parametrize("args, match", [
    ((-5.0, 5.5e-4, 4.0), r"nu must be .*\[0, inf\) cycles/mm, got -5"),  # main: 1.0
    ((50.0, 0.55, 4.0), r"lam_mm must be a wavelength in mm.*0\.55 µm is 0\.00055 mm"),  # 0.0
    ((50.0, 550.0, 4.0), r"lam_mm .*550 nm is 0\.00055 mm"),  # 0.0
    ((50.0, 5.5e-4, 0.0), r"fnum .* \(0, inf\), got 0"),  # 1.0
    ((50.0, 5.5e-4, -4.0), r"fnum .*got -4"),  # 1.0
])
def test_diffraction_mtf_refuses_arguments_out_of_range(args, match):
    with pytest.raises(ValueError, match="diffraction_mtf: " + match):
        otf.diffraction_mtf(*args)


def test_diffraction_mtf_values_and_jit_unchanged():
    got = otf.diffraction_mtf(np.array([0.0, 50.0, 500.0]), 5.5e-4, 4.0)
    s = 50 * 5.5e-4 * 4
    assert np.allclose(got, [1.0, 2 / np.pi * (np.arccos(s) - s * np.sqrt(1 - s * s)), 0.0],
                       atol=1e-6)
    assert np.isclose(jax.jit(otf.diffraction_mtf)(50.0, 5.5e-4, 4.0), got[1], atol=1e-6)


@pytest.mark.parametrize("kw, match", [
    ({"fnum": -4.0}, r"fnum must be a finite number in \(0, inf\), got -4"),  # EPD of F/4
    ({"fnum": "4"}, r"fnum .*got '4'"),  # a TypeError from a division
    ({"epd": -5.0}, r"epd .*\(0, inf\) mm, got -5"),  # "comes out as -5.0"
    ({"stop_semi_diameter": 0.0}, r"stop_semi_diameter .*mm, got 0"),
    ({"epd": [5.0, 6.0]}, r"epd must be a finite number"),  # numpy's "truth value ..."
])
def test_apply_aperture_names_the_bad_argument(cooke, kw, match):
    with pytest.raises(ValueError, match="apply_aperture: " + match):
        lensfile.apply_aperture(cooke, **kw)


def test_lens_writers_refuse_a_folder_a_missing_folder_and_another_extension(cooke, tmp_path):
    """Main: save_json/save_zmx to a folder failed with IsADirectoryError on the temporary
    file, into a missing folder with a FileNotFoundError naming '.a.json.<pid>.partial', and
    save_zmx wrote Zemax text into 'a.json' (save_json JSON into 'a.zmx')."""
    for save, ext in ((lensfile.save_json, "json"), (zmx.save_zmx, "zmx")):
        name = save.__name__
        with pytest.raises(ValueError, match=f"{name}: .* is a folder, not a file"):
            save(cooke, tmp_path)
        with pytest.raises(ValueError, match=f"{name}: no such folder .*nope.* 'a.{ext}'"):
            save(cooke, tmp_path / "nope" / f"a.{ext}")
        other = "zmx" if ext == "json" else "json"
        with pytest.raises(ValueError, match=rf"{name}: .*must end in \.{ext}, got .*a\.{other}"):
            save(cooke, tmp_path / f"a.{other}")
    assert not list(tmp_path.iterdir())  # nothing written, no side catalog either
    lensfile.save_json(cooke, tmp_path / "A.JSON")  # any case
    assert (tmp_path / "A.JSON").exists()


def test_write_whole_refuses_a_folder_naming_its_caller(tmp_path):
    with pytest.raises(ValueError, match=r"bench: .* is a folder"):
        write_whole(tmp_path, "{}", where="bench")
    with pytest.raises(ValueError, match=r"write: no such folder"):
        write_whole(tmp_path / "x" / "r.json", "{}")


@pytest.mark.parametrize("make, match", [
    (lambda L, t: L(thickness=t.astype(np.float16)), r"Lens: thickness \(mm\) is float16"),
    (lambda L, t: L(epd=np.float16(10.0)), r"Lens: epd \(mm\) is float16"),
    (lambda L, t: jl.Standard(c=jax.numpy.asarray(0.045, jax.numpy.bfloat16)),
     r"surface: c .* is bfloat16"),
    (lambda L, t: jl.ModelGlass(nd=np.float16(1.5168), vd=64.17), r"ModelGlass: nd is float16"),
])
def test_half_precision_leaves_are_refused(cooke, make, match):
    """Main: a float16 thickness (3.25896 kept as 3.2598) gave an EFL of 50.0223 for
    50.0214 without a word, as ``Lens.astype(float16)`` is refused."""
    L = lambda **k: dataclasses.replace(cooke, **k)  # noqa: E731
    with pytest.raises(TypeError, match=match + ".*too few digits"):
        make(L, np.asarray(cooke.thickness))


def test_half_precision_rays_are_refused():
    """Main: Rays kept float16 (a wavelength of 0.55 µm as 0.5498) and traced them."""
    up = np.tile(np.array([0.0, 0.0, 1.0]), (2, 1))
    with pytest.raises(TypeError, match=r"Rays: origin is float16, .*too few digits"):
        jl.Rays(origin=np.zeros((2, 3), np.float16), direction=up.astype(np.float16),
                wavelength=0.55)
    with pytest.raises(TypeError, match=r"Rays: wavelength is float16"):
        jl.Rays(origin=np.zeros((2, 3)), direction=up, wavelength=np.float16(0.55))


def test_float32_leaves_are_still_taken(cooke):
    lens = dataclasses.replace(cooke, thickness=np.asarray(cooke.thickness, np.float32))
    assert lens.thickness.dtype == np.float32


@pytest.mark.parametrize("args, kw, match", [
    ((np.ones(2),), {}, r"clear_radius must be \[6\] mm .*got shape \(2,\)"),  # IndexError
    ((np.zeros(6),), {}, r"clear_radius must be finite numbers in \(0, inf\) mm, got 0"),
    ((np.full(6, np.nan),), {}, r"clear_radius .*got nan"),  # a NaN lens
    ((np.ones(6),), {"add_r4": (True,)}, r"add_r4 must hold one True/False per surface \(6\)"),
])
def test_perturb_checks_its_arguments_against_the_lens(cooke, args, kw, match):
    z = tolerance.zero_perturbation(cooke)
    with pytest.raises(ValueError, match="perturb: " + match):
        tolerance.perturb(cooke, z, *args, **kw)


def test_perturb_refuses_a_perturbation_of_another_lens(cooke):
    """Main: "add got incompatible shapes for broadcasting: (6,), (11,)"."""
    z = tolerance.zero_perturbation(jl.zoo.double_gauss())
    with pytest.raises(ValueError, match=r"perturb: p\.radius_rel has 11 entries for a lens "
                                         r"of 6 surfaces"):
        tolerance.perturb(cooke, z, np.ones(6))


def test_perturb_under_jit_unchanged(cooke):
    z = tolerance.zero_perturbation(cooke)
    out = jax.jit(lambda p: tolerance.perturb(cooke, p, np.ones(6)))(z)
    assert np.isclose(float(jl.efl(out)), float(jl.efl(cooke)), rtol=1e-6)


@pytest.mark.parametrize("fn", [tiled.convolve_tiles,
                                lambda i, k: tiled.wiener_tiles(i, k, 0.01),
                                lambda i, k: tiled.tile_evidence(i, k, 0.01)])
def test_tile_bank_refusal_names_the_kernels(fn):
    """Main: "a 16x16 frame does not split into 3x3 square tiles" (the 3 from the kernels)."""
    img = np.zeros((16, 16, 3), np.float32)
    with pytest.raises(ValueError, match=r"3x3 square tiles \(kernels is \[ty, tx, C, k, k\] "
                                         r"= \[3, 3, 3, 3, 3\]"):
        fn(img, np.ones((3, 3, 3, 3, 3), np.float32))


@pytest.mark.parametrize("z, match", [(float("nan"), r"object_z must be finite .*got nan"),
                                      (0.0, r"object_z must be in front of surface 1 .*got 0")])
def test_stop_radius_checks_a_concrete_object_z(cooke, z, match):
    """Main: object_z NaN failed in Rays ("direction must hold unit vectors ... length
    nan"), 0 (surface 1's vertex) gave 3.83 mm."""
    with pytest.raises(ValueError, match="stop_radius: " + match):
        sampling.stop_radius(cooke, "real", object_z=z)
