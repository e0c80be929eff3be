"""Round 16 of bad-input and silent-answer probes (``tools/audit16_probe.py``).

A lens edited with ``eqx.tree_at`` (its constructor checks skipped), a curriculum that
starts at a faster F-number than its target, design options that were checked only where
they were first used (or never), and the surfaces whose constructor values went unchecked.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import angular_magnification, rms_spot, seidel
from jaxlens.design import DesignConfig, DesignSpec, paper_stages

# ------------------------------------------------------- a lens edited with eqx.tree_at


def _edits():
    lens = jl.zoo.cooke_triplet()
    # (id, the edited lens, message). Before: efl gave NaN for the first two; 50.02 mm
    # (the unedited EFL) for the others, and rms_spot / psf a number (a one-pixel PSF for
    # an EPD of 0) or a shape error from inside lax.scan.
    return [
        ("nan_curvature", eqx.tree_at(lambda m: m.surfaces[1].c, lens, jnp.asarray(jnp.nan)),
         r"surfaces\[1\]: Standard: c must be finite numbers in \[-1e\+09, 1e\+09\].*nan"),
        ("nan_thickness", eqx.tree_at(lambda m: m.thickness, lens,
                                      lens.thickness.at[2].set(jnp.nan)),
         r"Lens: thickness must be finite numbers \(mm\), got nan mm"),
        ("infinite_conic", eqx.tree_at(lambda m: m.surfaces[1].k, lens, jnp.asarray(jnp.inf)),
         r"surfaces\[1\]: Standard: k must be finite numbers, got inf"),
        ("negative_semi_diameter", eqx.tree_at(lambda m: m.surfaces[1].semi_diameter, lens,
                                               jnp.asarray(-2.0)),
         r"semi_diameter must be numbers in \(0, inf\] mm \(inf: no clipping\), got -2 mm"),
        ("zero_epd", eqx.tree_at(lambda m: m.epd, lens, jnp.asarray(0.0)),
         r"Lens: epd \(entrance pupil diameter\) must be finite numbers in \(0, inf\) mm, "
         r"got 0 mm"),
        ("field_95", eqx.tree_at(lambda m: m.fields, lens, jnp.asarray([0.0, 95.0])),
         r"Lens: fields must be finite angles in \(-90, 90\) deg, got 95 deg"),
        ("short_thickness", eqx.tree_at(lambda m: m.thickness, lens, lens.thickness[:-1]),
         r"Lens: 6 surfaces need 6 thicknesses \(mm\), got shape \(5,\)"),
    ]


EDITS = ["nan_curvature", "nan_thickness", "infinite_conic", "negative_semi_diameter",
         "zero_epd", "field_95", "short_thickness"]


def _entry_points():
    return {
        "efl": lambda m: jl.efl(m),
        "paraxial_data": lambda m: jl.paraxial_data(m),
        "rms_spot": lambda m: rms_spot(m),
        "psf": lambda m: jl.psf(m, 0.0, kernel_size=9, pixel_size=0.005),
        "seidel": lambda m: seidel(m),
        "angular_magnification": lambda m: angular_magnification(m),
    }


@pytest.mark.parametrize("edit", EDITS)
def test_an_edited_lens_is_refused_by_efl_naming_the_bad_value(edit):
    _, lens, match = next(e for e in _edits() if e[0] == edit)
    with pytest.raises(ValueError, match=rf"^efl: the lens fails its own checks, .*{match}.*"
                                         rf"edited with eqx\.tree_at"):
        jl.efl(lens)


@pytest.mark.parametrize("where", list(_entry_points()))
def test_every_analysis_refuses_an_edited_lens_before_tracing_it(where):
    _, lens, match = _edits()[0]  # NaN curvature
    with pytest.raises(ValueError, match=rf"^{where}: the lens fails its own checks, {match}"):
        _entry_points()[where](lens)


def test_a_lens_edited_to_good_values_and_a_traced_lens_still_work():
    import jax

    lens = jl.zoo.cooke_triplet()
    thicker = eqx.tree_at(lambda m: m.thickness, lens, lens.thickness.at[1].add(0.5))
    assert float(jl.efl(thicker)) != pytest.approx(float(jl.efl(lens)), abs=1e-6)
    assert np.isfinite(np.asarray(rms_spot(thicker).polychromatic)).all()
    # Under jit the lens is a tracer: nothing is checked (the entry points check before).
    f = eqx.filter_jit(jl.efl)
    assert float(f(lens)) == pytest.approx(float(jl.efl(lens)), abs=1e-9)
    g = jax.grad(lambda t: jl.efl(eqx.tree_at(lambda m: m.thickness, lens, t)))(lens.thickness)
    assert np.isfinite(np.asarray(g)).all()


# ------------------------------------------------------------------------ design
def test_design_spec_curriculum_starts_no_faster_than_the_target():
    """Before: DesignSpec(fnum=2, fnum_start=1.2) was accepted and paper_stages ran
    F/1.2 → 1.6 → 1.88 → 2.0, the hard end first (and F/0.3, faster than any lens)."""
    with pytest.raises(ValueError, match=r"DesignSpec: fnum_start must be a finite number in "
                                         r"\[2, 64\] \(F-number: the curriculum starts no "
                                         r"faster than the target fnum\), got 1\.2"):
        DesignSpec(fnum=2.0, fnum_start=1.2)
    assert DesignSpec(fnum=2.0, fnum_start=2.0).fnum_start == 2.0  # no curriculum in F#
    stages = paper_stages(DesignSpec())
    assert [round(s.fnum, 2) for s in stages[:4]] == [2.8, 2.4, 2.11, 2.0]
    # Left out, the starts are the paper's (47.5°, F/2.8) eased to an easier target: an F/4,
    # 40° spec starts at its own F-number and field (before: refused, as the paper's F/2.8
    # and 47.5° starts are faster and wider than it), as the classical CLI always did.
    assert (DesignSpec().fov_start, DesignSpec().fnum_start) == (47.5, 2.8)
    easy = DesignSpec(fov=40.0, fnum=4.0)
    assert (easy.fov_start, easy.fnum_start) == (40.0, 4.0)
    assert (DesignSpec(fov=60.0).fov_start, DesignSpec(fnum=1.8).fnum_start) == (47.5, 2.8)


@pytest.mark.parametrize(("kw", "match"), [
    (dict(reg_weights=(-1.0, 1000.0, 40.0)),  # before: FloatingPointError after the set-up
     r"DesignConfig: reg_weights \(obliquity\) must be a finite number in \[0, inf\) "
     r"\(weight\), got -1\.0"),
    (dict(reg_weights=(40.0, np.nan, 40.0)),
     r"DesignConfig: reg_weights \(spacing\) must be a finite number"),
    (dict(reg_weights=(40.0, 1000.0)),  # before: a broadcast error inside the first stage
     r"DesignConfig: reg_weights must be three weights >= 0 \(obliquity, spacing, slope\)"),
    (dict(solver="sgd"), r"DesignConfig: solver must be one of \('adam', 'lm'"),
    (dict(polish="sgd"), r"DesignConfig: polish must be one of \('adam', 'lm'"),
    (dict(reference="chief"), r"DesignConfig: reference must be 'ideal' or 'centroid'"),
    (dict(materials="free"), r"DesignConfig: materials: material selection must be one of"),
    (dict(material_catalogs="SCHOTT"),
     r"DesignConfig: material_catalogs must be a non-empty tuple of catalog names"),
    (dict(material_catalogs=()),
     r"DesignConfig: material_catalogs must be a non-empty tuple of catalog names"),
    # w₀ = 2 gave the perturbed lenses the weight (1 − w₀)/K < 0: a reward for sensitivity.
    (dict(tolerance_nominal_weight=2.0),
     r"DesignConfig: tolerance_nominal_weight must be a finite number in \(0, 1\] \(share "
     r"of the nominal loss\), got 2\.0"),
])
def test_design_config_checks_every_option_on_construction(kw, match):
    """Before: each was accepted by DesignConfig (checked later, or never)."""
    with pytest.raises(ValueError, match=match):
        DesignConfig(**kw)


def test_design_config_defaults_and_good_values_pass():
    DesignConfig()
    DesignConfig(reg_weights=[0.0, 0.0, 0.0], solver="lbfgsb", polish="adam",
                 reference="centroid", materials="search", material_catalogs=["SCHOTT"],
                 tolerance_nominal_weight=1.0)


def test_paper_stages_curriculum_is_a_switch():
    """Before: curriculum="no" (truthy) ran the curriculum."""
    with pytest.raises(ValueError, match=r"paper_stages: curriculum must be True or False, "
                                         r"got 'no'"):
        paper_stages(DesignSpec(), curriculum="no")


# ------------------------------------------------------------------------ surfaces
@pytest.mark.parametrize(("kw", "match"), [
    (dict(c=np.nan), r"Toroidal: c must be finite numbers in \[-1e\+09, .*, got nan"),
    (dict(k=np.inf), r"Toroidal: k must be finite numbers, got inf"),
    (dict(cx=np.nan), r"Toroidal: cx must be finite numbers in \[-1e\+09, .*, got nan"),
    (dict(coeffs=[np.nan]), r"Toroidal: coeffs must be finite numbers, got nan"),
    (dict(semi_diameter=-1.0),
     r"Toroidal: semi_diameter must be numbers in \(0, inf\] mm \(inf: no clipping\), got -1"),
    (dict(c=0.5, semi_diameter=5.0), r"Toroidal: the surface .* is defined only out to r = "),
    (dict(cx=0.5, semi_diameter=5.0),
     r"Toroidal: the sweep about the rotation axis \(cx = 0\.5 1/mm, radius of rotation 2 "
     r"mm\) is defined only out to \|x\| = 1/\|cx\| = 2 mm, but the semi_diameter is 5 mm"),
])
def test_toroidal_checks_its_values(kw, match):
    """Before: every one was accepted (Toroidal checked only the shape of coeffs)."""
    from jaxlens.optics.toroidal import Toroidal

    with pytest.raises(ValueError, match=match):
        Toroidal(**kw)
    Toroidal(c=0.05, cx=-0.1, semi_diameter=5.0)  # inside both domains: fine


@pytest.mark.parametrize("call", ["psf", "encircled_energy"])
def test_psf_grids_have_an_upper_bound(call):
    """Before: kernel_size=100001 raised numpy's "Python integer 10000200001 out of bounds
    for int32" (psf), after the checks had passed."""
    from jaxlens.analysis import encircled_energy

    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=rf"{call}: kernel_size must be a whole number in "
                                         rf"\[1, 4096\] pixels per side, got 100001"):
        if call == "psf":
            jl.psf(lens, 0.0, kernel_size=100001, pixel_size=0.005)
        else:
            encircled_energy(lens, 0.0, [0.01], method="diffraction", pixel_size=0.001,
                             kernel_size=100001)


# ------------------------------------------------------------------------ CLIs
@pytest.mark.parametrize(("argv", "old", "new"), [
    (["--smoke"], "python -m benchmarks --only throughput", "smoke"),
    (["--only", "throughput", "--counts", "100"], "python -m benchmarks", "partial"),
    (["--smoke", "--only", "throughput"], "python -m benchmarks --only throughput --counts 10",
     "smoke"),
])
def test_benchmarks_never_replace_a_fuller_run(argv, old, new, tmp_path, capsys):
    """Before: --smoke --out results replaced the committed full results with the smoke
    sizes, and a --counts rerun the full throughput table, without a word."""
    import json

    from benchmarks.run import main

    path = tmp_path / "throughput.json"
    path.write_text(json.dumps({"benchmark": "throughput", "command": old, "rows": []}))
    kind = "partial" if "--counts" in old else "full"
    with pytest.raises(SystemExit) as e:
        main([*argv, "--out", str(tmp_path)])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert (f"throughput.json holds a {kind} run's results, which this {new} run would "
            f"replace; give --tag NAME (writes throughput_NAME.json beside it)") in err
    assert json.loads(path.read_text())["command"] == old  # untouched


def test_benchmark_run_kinds():
    from benchmarks.run import run_kind

    assert run_kind("python -m benchmarks") == "full"
    assert run_kind("python -m benchmarks --only throughput --full") == "full"
    assert run_kind("python -m benchmarks --only throughput --lenses cooke_triplet") == "partial"
    assert run_kind("python -m benchmarks --smoke --counts 10") == "smoke"


# ------------------------------------------------------------------------ images
def _bad_images():
    return {
        "uint8": np.full((2, 2, 3), 255, np.uint8),
        "nan": np.full((2, 2, 3), np.nan),
        "complex": np.ones((2, 2, 3), complex),
        "bool": np.ones((2, 2, 3), bool),
    }


# Before: srgb_to_linear(uint8 255) gave 5.9e5 (255 raised to the power 2.4), write_png of
# a uint8 image a white file, to_linear(float 0…255) radiance 255, a NaN passed through and
# a complex image lost its imaginary part with only a numpy warning.
@pytest.mark.parametrize("fn", ["srgb_to_linear", "linear_to_srgb", "write_png", "write_exr"])
@pytest.mark.parametrize("kind", ["uint8", "nan", "complex", "bool"])
def test_image_functions_refuse_what_is_not_a_float_image(fn, kind, tmp_path):
    from jaxlens.io import images

    img = _bad_images()[kind]
    match = {"uint8": rf"{fn}: \w+ must be a float image .*got an integer image of dtype "
                      rf"uint8 \(sRGB codes 0…255\?\); decode it with jaxlens\.io\.images\."
                      rf"to_linear",
             "nan": rf"{fn}: \w+ must be finite values.*got nan \(12 bad of 12\)",
             "complex": rf"{fn}: \w+ must be a float image .*got dtype complex128",
             "bool": rf"{fn}: \w+ must be a float image .*got dtype bool"}[kind]
    f = getattr(images, fn)
    with pytest.raises(ValueError, match=match):
        if fn.startswith("write"):
            f(tmp_path / f"x.{fn[6:]}", img)
        else:
            f(img)
    assert not list(tmp_path.iterdir())


def test_srgb_and_to_linear_ranges():
    from jaxlens.io import images

    with pytest.raises(ValueError, match=r"srgb_to_linear: v must be finite values in \[0, 1\] "
                                         r"\(sRGB-encoded\), got 5"):
        images.srgb_to_linear(np.full(3, 5.0))
    with pytest.raises(ValueError, match=r"to_linear: img must be finite values in \[0, 1\] "
                                         r"\(linear light\), got 255 .*divide it by 255"):
        images.to_linear(np.full((2, 2, 3), 255.0))
    # Good input still works, Python numbers included; linear_to_srgb still clips.
    assert images.srgb_to_linear(0.5) == pytest.approx(0.21404114, abs=1e-8)
    assert float(images.linear_to_srgb(np.array([2.0]))[0]) == pytest.approx(1.0)
    assert images.to_linear(np.full((1, 1, 3), 255, np.uint8))[0, 0, 0] == pytest.approx(1.0)
    assert images.scene("astronaut", (8, 8)).shape == (8, 8, 3)


def test_design_config_with_no_solver_step_is_refused():
    """Before: design() returned the random starts, each marked "successful"."""
    with pytest.raises(ValueError, match=r"DesignConfig: steps, final_steps and polish_steps "
                                         r"are all 0: no solver step would run"):
        DesignConfig(steps=0, final_steps=0, polish_steps=0)
    DesignConfig(steps=0, final_steps=1, polish_steps=0)


@pytest.mark.parametrize("stages", [[], "one", None], ids=["empty", "str", "none"])
def test_curriculum_run_needs_a_list_of_stages(stages):
    """Before: [] returned the starting parameters as the result, without a step."""
    import types

    from jaxlens.design import run

    params = types.SimpleNamespace(c=jnp.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"run: stages must be a non-empty list of Stage "
                                         r"objects \(e\.g\. paper_stages\(spec\)\)"):
        run(DesignSpec(), stages, params, object(), None, progress=False)


@pytest.mark.parametrize("degree", [-1, 2.5, 21, True])
def test_xy_term_count_takes_a_degree_of_the_extended_polynomial(degree):
    """Before: -1 gave -1 terms, 2.5 gave 6.0, 21 gave 252 (a surface holds 230), True 2."""
    from jaxlens.optics.xypolynomial import xy_term_count

    with pytest.raises(ValueError, match=r"xy_term_count: degree must be a whole number in "
                                         r"\[0, 20\] \(total degree\)"):
        xy_term_count(degree)
    assert [xy_term_count(d) for d in (0, 1, 2, 20)] == [0, 2, 5, 230]


@pytest.mark.parametrize(("n", "ordering"), [(0, "standard"), (2.5, "standard"),
                                             (38, "fringe"), (232, "standard")])
def test_zernike_basis_term_count(n, ordering):
    """Before: 0 raised "max() arg is an empty sequence", 2.5 a TypeError from range, and
    38 Fringe terms (Fringe has 37) a basis of terms that do not exist."""
    from jaxlens.optics.freeform import zernike_basis

    with pytest.raises(ValueError, match=r"zernike_basis: n_terms must be a whole number in "
                                         r"\[1, (37|231)\] terms"):
        zernike_basis(n, ordering)


def test_zernike_fit_refuses_a_nan_coordinate_at_a_fitted_point():
    """Before: the point's row of the design matrix was NaN, and so was every coefficient."""
    from jaxlens.analysis import zernike_fit

    x = jnp.array([0.1, 0.2, jnp.nan, 0.3])
    y = jnp.zeros(4)
    with pytest.raises(ValueError, match=r"zernike_fit: x and y must be finite at every "
                                         r"fitted point .*got \(nan, 0\) at point 2"):
        zernike_fit(x, y, jnp.ones(4), terms=2)
    # A point without a value (NaN) weighs nothing: its coordinates are not read.
    fit = zernike_fit(x, y, jnp.array([1.0, 1.0, jnp.nan, 1.0]), terms=1)
    assert float(fit.coefficients[0]) == pytest.approx(1.0)


def test_marechal_strehl_refuses_a_negative_or_non_numeric_rms():
    """Before: a negative RMS was squared like a positive one (−1 wave gave 7.2e-18)."""
    from jaxlens.analysis.wavefront_error import marechal_strehl

    with pytest.raises(ValueError, match=r"marechal_strehl: rms_waves must be an RMS "
                                         r"wavefront error, >= 0 waves, got -1 waves"):
        marechal_strehl(-1.0)
    with pytest.raises(TypeError, match="marechal_strehl: rms_waves must be a real number"):
        marechal_strehl("0.1")
    assert float(marechal_strehl(0.0)) == 1.0
    assert np.isnan(float(marechal_strehl(float("nan"))))  # no rays, no Strehl ratio


def test_report_of_a_missing_file_names_the_file_without_errno(tmp_path, capsys):
    """Before: "jaxlens report: error: [Errno 2] No such file or directory: '…'"."""
    from jaxlens.__main__ import main

    missing = tmp_path / "missing.zmx"
    assert main(["report", str(missing)]) == 2
    err = capsys.readouterr().err
    # Round 41b: the reader names itself and the path (optics.input_files).
    assert f"jaxlens report: error: load: no such lens file: '{missing}'" in err
    assert "Errno" not in err
