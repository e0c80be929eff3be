"""Round 17 of bad-input and silent-answer probes (``tools/audit17_probe.py``).

A catalog glass read outside its data range, a thickness tolerance larger than the glass
it perturbs, an EDoF floor above its start, JSON surface types matched by substring, and
constructors and entry points that accepted a value their callers refused (or crashed on).
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis.tolerance import MAX_THICKNESS, ToleranceModel, Tolerances
from jaxlens.analysis.wavefront_error import marechal_strehl
from jaxlens.imaging.psf import CoherentPSF, GeometricPSF
from jaxlens.io import images, lensfile
from jaxlens.optics.materials import abbe_number
from jaxlens.optics.paraxial import working_fnum

# ------------------------------------------------------------- biconic domain (regression)


@pytest.mark.parametrize("make", [
    lambda: jl.Standard(c=1 / 3, semi_diameter=5.0),
    lambda: jl.Biconic(cx=1 / 3, semi_diameter=5.0),
    lambda: jl.Biconic(cx=-1 / 3, semi_diameter=5.0),
], ids=["standard", "biconic_x", "biconic_x_concave"])
def test_a_surface_narrower_than_its_semi_diameter_is_refused_alike(make):
    """A biconic whose x radius |1/cx| = 3 mm is below its 5 mm semi-diameter is refused as
    a Standard surface of R = 3 mm is (a pin: this held before round 17 too)."""
    with pytest.raises(ValueError, match=r"defined only out to .*= 3 mm, but .*semi_diameter "
                                         r"is 5 mm; use a semi_diameter <= 3 mm"):
        make()
    assert float(jl.Biconic(cx=1 / 3, semi_diameter=2.9).cx) == pytest.approx(1 / 3)


# ----------------------------------------------------------- catalog wavelengths


@pytest.mark.parametrize("wl", [2.6, 0.2, [0.5, 3.0]])
def test_a_catalog_glass_refuses_a_wavelength_outside_its_range(wl):
    """Before: N-BK7 (data 0.3–2.5 µm) gave its Sellmeier formula's extrapolation, e.g.
    1.4949 at 2.6 µm, where a lens with that glass is refused."""
    bk7 = jl.get_material("N-BK7")
    with pytest.raises(ValueError, match=r"^CatalogMaterial\.index \(N-BK7\): wavelength .* µm "
                                         r"is outside 0\.3–2\.5 µm, the data range of N-BK7 "
                                         r"\(SCHOTT\).*extrapolated_index"):
        bk7.index(jnp.asarray(wl))


def test_a_catalog_glass_inside_its_range_and_its_extrapolation_on_request():
    bk7 = jl.get_material("N-BK7")
    assert float(bk7.index(0.5875618)) == pytest.approx(1.5168, abs=1e-4)
    assert float(bk7.index(2.5)) > 1.0  # the range's end is inside
    # Explicit extrapolation, and traced wavelengths (checked where they enter) pass.
    assert float(bk7.extrapolated_index(2.6)) == pytest.approx(float(bk7.model.index(2.6)))
    assert float(jax.jit(lambda w: bk7.index(w))(2.6)) == pytest.approx(
        float(bk7.model.index(2.6)))
    # nd and Vd of an infrared glass whose data do not cover the d, F and C lines.
    si = jl.get_material("SILICON")
    assert si.wavelength_range[0] > 0.6563
    assert np.isfinite(float(abbe_number(si)))
    assert jl.glass_info("SILICON")[0] == "INFRARED"


# ----------------------------------------------------------- thickness tolerance


@pytest.mark.parametrize("value", [MAX_THICKNESS, 1e6])
def test_a_thickness_tolerance_of_10_mm_or_more_is_refused(value):
    """Before: any value; ±1e6 mm gave a report of enormous spots."""
    with pytest.raises(ValueError, match=r"^Tolerances: thickness must be below 10 mm"):
        Tolerances(thickness=value)
    assert Tolerances(thickness=9.0).thickness == 9.0


def test_a_thickness_tolerance_above_the_thinnest_glass_is_refused_by_the_model():
    """The Cooke triplet's flint is 0.99997 mm thick: ±3 mm would trace it -2 mm thick."""
    lens = jl.zoo.cooke_triplet()
    match = (r"Tolerances\.thickness ±3 mm must be below the lens's thinnest glass thickness, "
             r"0\.99997 mm after surface 2 \(0-based\)")
    with pytest.raises(ValueError, match=rf"^ToleranceModel: {match}"):
        ToleranceModel(lens, tolerances=Tolerances(thickness=3.0))
    model = ToleranceModel(lens, tolerances=Tolerances(thickness=0.5))
    with pytest.raises(ValueError, match=rf"^with_tolerances: {match}"):
        model.with_tolerances(Tolerances(thickness=3.0))


def test_a_decenter_tolerance_above_the_smallest_clear_radius_is_refused():
    """Before: ±1e6 mm was accepted (every perturbed element left the beam)."""
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"^ToleranceModel: Tolerances\.decenter ±1e\+06 mm "
                                         r"must be below the lens's smallest clear "
                                         r"semi-diameter, 4\.0595\d* mm at surface 3"):
        ToleranceModel(lens, tolerances=Tolerances(decenter=1e6))


# ----------------------------------------------------------- EDoF floors


@pytest.mark.parametrize("args", [["--cubic-floor", "2"], ["--cubic-floor", "1.5"],
                                  ["--hybrid-floor", "3"]])
def test_edof_floors_above_their_start_are_refused(args):
    """A floor is a fraction of the start strength: above 1 the first projection raised the
    strength past its start without a word."""
    from jaxlens.experiments.edof import cli

    with pytest.raises(ValueError, match=rf"^edof: {args[0]} must be a finite number in "
                                         rf"\[0, 1\] \(fraction of the start strength\)"):
        cli.config_from_args(cli.build_parser().parse_args(args))
    assert cli.config_from_args(cli.build_parser().parse_args(
        ["--cubic-floor", "1", "--hybrid-floor", "0.5"])).cubic_floor == 1.0


# ----------------------------------------------------------- JSON surface types


def _with_type(kind, **extra):
    d = lensfile.lens_to_dict(jl.zoo.cooke_triplet())
    d["surfaces"][1].update(type=kind, **extra)
    return d


@pytest.mark.parametrize("kind, close", [("asphere9", "'evenasph'"), ("extended asphere", None),
                                         ("hybridx", "'hybrid'"), ("not_an_oddasph", None)])
def test_a_json_surface_type_is_matched_by_name_not_by_substring(kind, close):
    """Before: any type holding "asph" was an even asphere (Zemax's extended asphere has
    another polynomial), any holding "hybrid" a hybrid, "...odd...asph..." an odd asphere."""
    with pytest.raises(ValueError, match=rf"surface 1: unknown surface type {kind!r}"
                                         rf"{'.*did you mean ' + close if close else ''}"):
        lensfile.lens_from_dict(_with_type(kind, even_asphere_coeffs=[1e-6]))


@pytest.mark.parametrize("kind, cls", [("Even Asphere", jl.EvenAsphere),
                                       ("evenasph", jl.EvenAsphere),
                                       ("odd_asphere", jl.OddAsphere),
                                       ("ODDASPHE", jl.OddAsphere), ("hybrid", jl.Hybrid),
                                       ("standard", jl.EvenAsphere)])
def test_the_json_surface_type_names_still_read(kind, cls):
    key = "odd_asphere_coeffs" if cls is jl.OddAsphere else "even_asphere_coeffs"
    lens = lensfile.lens_from_dict(_with_type(kind, **{key: [1e-6]}))
    assert type(lens.surfaces[0]) is cls


# ----------------------------------------------------------- small entry points


def test_marechal_strehl_refuses_an_infinite_rms():
    """Before: inf waves gave a Strehl ratio of 0."""
    with pytest.raises(ValueError, match=r"^marechal_strehl: rms_waves must be an RMS "
                                         r"wavefront error, >= 0 waves, got inf waves"):
        marechal_strehl(np.inf)
    assert np.isnan(float(marechal_strehl(np.nan)))


def test_png_switches_and_bits_are_checked_before_the_file_is_touched(tmp_path):
    """Before: linear="no" is truthy (the sRGB curve was applied), and bits=8.0 failed in
    struct.pack after the checks."""
    path = tmp_path / "a.png"
    img = np.full((4, 4, 3), 0.5)
    with pytest.raises(ValueError, match=r"^write_png: linear must be True or False, got 'no'"):
        images.write_png(path, img, linear="no")
    with pytest.raises(ValueError, match=r"^write_png: bits must be 8 or 16 .*got 8\.0"):
        images.write_png(path, img, bits=8.0)
    assert not path.exists()
    images.write_png(path, img)
    with pytest.raises(ValueError, match=r"^read_png: linear must be True or False, got 0"):
        images.read_png(path, linear=0)


@pytest.mark.parametrize("make, match", [
    (lambda: GeometricPSF(pupil=0), r"^GeometricPSF: pupil \(rays per side\) must be an int "
                                    r">= 2, got 0"),
    (lambda: CoherentPSF(pupil=-4), r"^CoherentPSF: pupil \(rays per side\) must be an int "
                                    r">= 2, got -4"),
    (lambda: GeometricPSF(overfill=0.0), r"^GeometricPSF: overfill must be a finite number in "
                                         r"\(0, inf\)"),
    (lambda: GeometricPSF(grid="hex"), r"^GeometricPSF: grid must be 'square' or 'polar'"),
])
def test_psf_models_are_checked_at_construction(make, match):
    """Before: built without a word; psf refused them only when called."""
    with pytest.raises(ValueError, match=match):
        make()


def test_paraxial_data_refuses_a_list_of_wavelengths():
    """Before: ValueError "Cannot stack arrays with different numbers of dimensions" from
    deep inside (efl and bfl broadcast; paraxial_data's fields are scalars)."""
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"^paraxial_data: wavelength must be one value \(µm\),"
                                         r" got shape \(2,\)"):
        jl.paraxial_data(lens, [0.5, 0.6])
    assert float(jl.paraxial_data(lens, 0.55).efl) == pytest.approx(float(jl.efl(lens, 0.55)))


@pytest.mark.parametrize("depth", [0.0, -np.inf])  # -5: a virtual object (round 37c)
def test_working_fnum_names_a_bad_depth(depth):
    """Before: refused as "the lens fails its own checks ... edited with eqx.tree_at"."""
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"^working_fnum: depth must be finite, nonzero"):
        working_fnum(lens, depth)
    assert float(working_fnum(lens, None)) == pytest.approx(
        float(jl.paraxial_data(lens).working_fnum))


def test_default_fields_refuses_no_fields():
    """Before: count 0 gave an empty array, -2 a numpy error about samples."""
    from jaxlens.analysis.aberrations import default_fields

    lens = jl.zoo.cooke_triplet()
    for count in (0, -2, 2.5):
        with pytest.raises(ValueError, match=r"^default_fields: count must be a whole number "
                                             r"in \[1, 65536\] fields"):
            default_fields(lens, count)
    assert default_fields(lens, 3).tolist() == pytest.approx([0.0, 10.0, 20.0])


def test_lens_aim_is_one_of_two_names():
    """Lens(aim=...) refuses a typo (a pin for the round-17 sweep of the new keyword)."""
    lens = jl.zoo.cooke_triplet()
    for bad in ("Real", "off", None, True):
        with pytest.raises(ValueError, match=r"^Lens: aim \(ray aiming\) must be one of"):
            dataclasses.replace(lens, aim=bad)


def test_a_lens_in_a_user_infrared_glass_is_written_to_zmx_with_its_extrapolated_nd_vd():
    """The ``.zmx`` writer gives a glass it does not find in Zemax's catalogs its nd and Vd
    (d, F, C lines); for a user's infrared glass those lie outside the data range, where
    ``index`` now refuses, so the writer takes ``extrapolated_index`` (a regression of this
    round, caught at the merge)."""
    from jaxlens.io import zmx_write
    from jaxlens.optics.catalog import CatalogMaterial

    ir = CatalogMaterial(model=jl.ModelGlass(1.5, 50.0), name="MY_IR", catalog="MYCAT",
                         wavelength_range=(1.0, 5.0))
    with pytest.raises(ValueError, match="outside 1–5 µm"):
        ir.index(0.5876)
    lens = jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.02)), thickness=jnp.array([5.0, 45.0]),
                   materials=(ir, jl.Air()), epd=10.0, wavelengths=jnp.array([3.0]))
    text, *_ = zmx_write.dumps(lens)
    nd = float(ir.extrapolated_index(0.5875618))
    glas = next(ln for ln in text.splitlines() if ln.strip().startswith("GLAS"))
    assert f"{nd!r}"[:6] in glas, glas
