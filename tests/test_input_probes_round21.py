"""Bad input, round 21 (tools/audit21_probe.py): one test per class of gap fixed. Each names
what the bad value did before; all are refusals before any tracing or long work, so the file
is fast."""

import re
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import psf as psf_models
from jaxlens.optics import checks

COOKE = jl.zoo.cooke_triplet()
BIG = 10**12


# ------------------------------------------------------- render: working memory of a tile
@pytest.mark.parametrize(("kwargs", "text"), [
    (dict(spp=65536), r"render: patch² × spp × 3 channels = 805,306,368 rays traced at once "
                      r"need about 516\.0 GiB of working memory \(688 bytes a ray for 6 "
                      r"surfaces, 64-bit floats\), more than the 16 GiB bound "
                      r"\(checks\.MAX_WORKING_BYTES\); lower patch \(the tile side, 64 "
                      r"pixels\) to at most 11$"),
    # A patch within the image (a larger one is cut to the image, round 31).
    (dict(spp=16, patch=1024, side=1024),
     r"render: patch² × spp × 3 channels .* to at most 721$"),
    (dict(spp=256, method="psf"), r"render: spp × kernel_size² × 3 channels .*GiB.*lower spp "
                                  r"or kernel_size$"),
])
def test_render_refuses_a_tile_that_would_not_fit(kwargs, text):
    """Before: a tile of patch² × spp × 3 rays had no bound (spp is at most 65536, but at the
    default patch of 64 that asked XLA for some 500 GiB after the footprints were traced)."""
    from jaxlens.imaging.render import PSFRender

    if kwargs.get("method") == "psf":
        kwargs = dict(kwargs, method=PSFRender(kernel_size=4095))
    side = kwargs.pop("side", 64)
    with pytest.raises(ValueError, match=text):
        jl.render(COOKE, np.ones((side, side, 3)),
                  sensor=jl.Sensor((side, side), 0.005 * 64 / side), key=jax.random.key(0),
                  **kwargs)
    # The estimate: rays × itemsize × (32 + 9 per surface) bytes.
    assert checks.working_memory(1, 6, 8, "x", "", "") == 688
    assert checks.working_memory(1, 13, 4, "x", "", "") == 596


def test_psf_points_refuses_too_many_positions_at_once():
    """Before: 10**6 positions were vmapped at once (4·10**9 rays), an XLA allocation error."""
    from jaxlens.imaging import tiled

    with pytest.raises(ValueError, match=r"psf_points: positions × wavelengths × pupil² = "
                                         r"4,096,000,000 rays .*GiB.*pass fewer positions"):
        tiled.psf_points(COOKE, np.zeros((1000, 1000, 2)), None, wavelengths=[0.5876],
                         kernel_size=9, pixel_size=0.005)


# ------------------------------------------------------- the classical CLI's counts
@pytest.mark.parametrize(("args", "text"), [
    (["--steps", "1e12"], r"--steps must be a finite number in \(0, 50\] \(scale of every "
                          r"stage's steps, at most 100000 steps a stage\), got 1000000000000\.0$"),
    (["--seeds", str(BIG)], r"--seeds must be a whole number in \[1, 1024\] designs, got "
                            r"1000000000000$"),
    (["--polish-steps", str(10**9)], r"--polish-steps must be a whole number in \[0, 100000\] "
                                     r"steps"),
    (["--ablation", "--ablation-seeds", str(10**8)], r"--ablation-seeds must be a whole number "
                                                     r"in \[1, 1024\] designs per column"),
])
def test_classical_cli_bounds_its_counts(args, text, tmp_path, capsys):
    """Before: --steps 1e12 scaled every stage to 10**15 steps, --seeds 10**12 built a list of
    that many seeds, and --polish-steps 10**9 or --ablation-seeds 10**8 started the run."""
    from jaxlens.experiments import classical

    assert classical.main([*args, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(text, err[0]), err
    assert not (tmp_path / "o").exists()


def test_design_config_bounds_step_counts():
    from jaxlens.design.multistart import DesignConfig

    with pytest.raises(ValueError, match=r"DesignConfig: steps must be a whole number in "
                                         r"\[0, 100000\], got 1000000000"):
        DesignConfig(steps=10**9)
    with pytest.raises(ValueError, match=r"DesignConfig.scaled: factor must be a finite number "
                                         r"in \(0, inf\)"):
        DesignConfig().scaled(float("inf"))  # before: OverflowError from round()


# ------------------------------------------------------- the design solvers
def _lrs(c=0.05):
    from jaxlens.design.params import LensParams
    return LensParams(c=jnp.asarray(c), a=jnp.asarray(0.05), k=jnp.asarray(0.0),
                      d=jnp.asarray(0.05))


@pytest.mark.parametrize(("make", "error", "text"), [
    (lambda S, f: S.Adam(f, _lrs(-1.0)), ValueError,
     r"Adam: lrs\.c must be finite numbers in \[0, inf\) \(learning rate per step\), got -1"),
    (lambda S, f: S.Adam(f, _lrs(), b1=1.0), ValueError,
     r"Adam: b1 must be a finite number in \[0, 1\) \(moment decay per step\), got 1\.0"),
    (lambda S, f: S.Adam(f, _lrs(), eps=0.0), ValueError, r"Adam: eps must be .* \(0, inf\)"),
    (lambda S, f: S.Adam(None, _lrs()), TypeError, r"Adam: residual_fn must be a callable"),
    (lambda S, f: S.Adam(f, 0.1), TypeError, r"Adam: lrs must be a LensParams"),
    (lambda S, f: S.DampedLeastSquares(f, inner=10**9), ValueError,
     r"DampedLeastSquares: inner must be a whole number in \[1, 100000\] iterations per step"),
    (lambda S, f: S.DampedLeastSquares(f, lam0=-1.0), ValueError,
     r"DampedLeastSquares: lam0 must be a finite number in \[1e-09, 1e\+09\] \(initial damping"),
    (lambda S, f: S.LevenbergMarquardt(f, rtol=float("nan")), ValueError,
     r"LevenbergMarquardt: rtol must be a finite number in \[0, inf\)"),
    (lambda S, f: S.LevenbergMarquardt(f, inner=0), ValueError, r"inner must be a whole number"),
    (lambda S, f: S.LBFGSB(f, _lrs(), _lrs(), history=0), ValueError,
     r"LBFGSB: history must be a whole number in \[1, 1000\] \(L-BFGS memory pairs\)"),
    (lambda S, f: S.LBFGSB(f, _lrs(np.nan), _lrs()), ValueError,
     r"LBFGSB: lower\.c must be numbers \(bound\), got nan"),
])
def test_solvers_check_their_options_when_built(make, error, text):
    """Before: none was checked; a negative learning rate climbed the loss, inner=10**9 ran a
    scan of that length in every step, a NaN bound or b1 = 1 gave NaN steps."""
    from jaxlens.design import solvers as S

    with pytest.raises(error, match=text):
        make(S, lambda p, a: (p.c, None))
    assert isinstance(S.LBFGSB(lambda p, a: (p.c, None), _lrs(-np.inf), _lrs(np.inf)),
                      S.LBFGSB)  # ±inf: unbounded


# ------------------------------------------------------- design helpers
def test_design_helpers_check_their_input():
    """Before: each of these returned an object (or a loss) built on NaN, nm or zero sizes,
    or failed deep inside (an OverflowError for int32, an AttributeError for None)."""
    from jaxlens.design import DesignSpec
    from jaxlens.design import init as I
    from jaxlens.design import losses as L
    from jaxlens.design import materials as M

    with pytest.raises(ValueError, match=r"HullMaterials: corners Vd must be finite numbers in "
                                         r"\(0, inf\) \(Abbe number\), got nan"):
        M.HullMaterials(jnp.array([[1.5, np.nan], [1.6, 40.0], [1.7, 30.0]]))
    with pytest.raises(ValueError, match=r"HullMaterials: corners must be \[V, 2\] \(nd, Vd\) "
                                         r"pairs .*got shape \(3,\)"):
        M.HullMaterials(jnp.array([1.5, 1.6, 1.7]))
    with pytest.raises(ValueError, match=r"corners nd must be finite numbers in \[1, 4\.5\]"):
        M.HullMaterials(jnp.array([[0.5, 50.0], [1.6, 40.0], [1.7, 30.0]]))
    with pytest.raises(ValueError, match=r"TableMaterials: wavelengths \[486\.1, 587\.6, "
                                         r"656\.3\] µm is outside 0\.15–30 µm.*in µm"):
        M.TableMaterials(jnp.array([486.1, 587.6, 656.3]))
    with pytest.raises(ValueError, match=r"RayLoss\.make: wavelengths .* µm is outside"):
        L.RayLoss.make(3, 2, [486.1, 587.6], (4.0, 6.0))
    with pytest.raises(ValueError, match=r"RayLoss\.make: n_fields must be a whole number in "
                                         r"\[1, 257\] fields, got 0"):
        L.RayLoss.make(0, 2, [0.5876], (4.0, 6.0))
    with pytest.raises(ValueError, match=r"RayLoss\.make: rings must be a whole number in "
                                         r"\[1, 64\] pupil rings, got 0"):
        L.RayLoss.make(3, 0, [0.5876], (4.0, 6.0))
    spec = DesignSpec()
    with pytest.raises(ValueError, match=r"random_params: key must be one PRNG key"):
        I.random_params(spec, "x")
    with pytest.raises(ValueError, match=r"parameterization: dtype must be None, float32 or "
                                         r"float64"):
        I.parameterization(spec, jnp.int32)
    with pytest.raises(TypeError, match=r"parameterization: spec must be a "
                                        r"jaxlens\.design\.DesignSpec, got NoneType"):
        I.parameterization(None)
    assert L.RayLoss.make(3, 2, [0.5876], (4.0, 6.0)).n_fields == 3  # the control


# ------------------------------------------------------- analysis
def test_zernike_nm_and_the_tolerance_helpers_check_their_input():
    """Before: zernike_nm(10**30) built a table of 10**30 terms (for ever); perturb and
    zero_perturbation failed with an AttributeError on a wrong type."""
    from jaxlens.analysis import tolerance as T
    from jaxlens.analysis import zernike as Z

    with pytest.raises(ValueError, match=r"zernike_nm: j must be a whole number in "
                                         r"\[1, 65536\] term number \(noll\)"):
        Z.zernike_nm(10**30)
    assert Z.zernike_nm(65536) == Z.zernike_nm(65536)  # the bound itself is a term
    with pytest.raises(TypeError, match=r"perturb: p must be a Perturbation"):
        T.perturb(COOKE, 1.0, jnp.ones(6))
    with pytest.raises(TypeError, match=r"zero_perturbation: lens must be a jaxlens\.Lens, got "
                                        r"NoneType"):
        T.zero_perturbation(None)


def test_report_cli_bounds_its_field_and_wavelength_counts(tmp_path, capsys):
    """Before: 100 000 --fields were analysed one by one (hours); --config 0 with a .json
    lens was refused by the loader without naming the option or its range."""
    from jaxlens import __main__ as M

    f = str(tmp_path / "c.json")
    jl.save(COOKE, f)
    assert M.main(["report", f, "--fields", *["1"] * 65]) == 2
    err = capsys.readouterr().err
    assert "report: --fields holds 65 values; a report takes at most 64" in err, err
    assert M.main(["report", f, "--config", "0"]) == 2
    err = capsys.readouterr().err
    assert ("report: --config must be a whole number in [1, inf) (Zemax's 1-based "
            "configuration number), got 0") in err, err


# ------------------------------------------------------- the EDoF CLI
@pytest.mark.parametrize(("args", "text"), [
    (["--steps", str(BIG)], r"--steps must be a whole number in \[1, 100000\] steps"),
    (["--pupil", "100000"], r"--pupil must be a whole number in \[2, 4096\] rays per side"),
    (["--batch", str(10**9)], r"--batch must be a whole number in \[1, 1024\] patches"),
    (["--n-odd", "0"], r"--n-odd must be a whole number in \[1, 10\] odd terms per axis"),
    (["--enc", ",".join(["1"] * 20), "--dec", ",".join(["1"] * 20)],
     r"--enc must be 1 to 6 comma-separated whole numbers in \[0, 64\] \(blocks per level\)"),
    (["--middle", "100000"], r"--middle must be a whole number in \[0, 64\] blocks"),
    (["--seeds", ",".join(map(str, range(2000)))], r"--seeds count must be a whole number in "
                                                     r"\[1, 1024\] training runs, got 2000"),
    (["--kernel", "100001"], r"--kernel must be a whole number in \[1, 4096\] pixels"),
    (["--width", "100000"], r"--width must be a whole number in \[1, 1024\] channels"),
])
def test_edof_cli_bounds_its_sizes_and_counts(args, text, tmp_path, capsys, monkeypatch):
    """Before: only lower bounds; --steps 10**12 trained for ever, --pupil 10**5, --batch
    10**9 or 20 NAFNet levels ran out of memory after the lens work, and --n-odd 0 dropped
    the cubic term without a word."""
    from jaxlens.experiments.edof import cli

    monkeypatch.setattr(sys, "argv", ["edof", *args, "--out", str(tmp_path / "o"), "--quiet"])
    with pytest.raises(SystemExit) as e:
        cli.main()
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(text, err[0]), err
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------- benchmark CLIs
@pytest.mark.parametrize(("module", "args", "text"), [
    ("render_speed", ["--size", "1000000"], r"--size: must be a whole number in \[1, 16384\] "
                                            r"pixels"),
    ("render_speed", ["--repeats", str(10**9)], r"--repeats: must be a whole number in "
                                                r"\[1, 1000\] repeats"),
    ("render_memory", ["--worker", "--trace-rays", str(BIG)], r"--trace-rays: must be a whole "
                                                               r"number in \[0, 100000000\] rays"),
    ("render_memory", ["--checkpoint", "5"], r"--checkpoint: must be a whole number in \[0, 1\]"),
    ("design_step", ["--rays", str(BIG)], r"--rays: must be a whole number in \[1, 100000000\]"),
    ("vjp_probe", ["--chunk", str(BIG)], r"--chunk: must be a whole number in \[1, 100000000\]"),
    ("fast_path", ["--rays", str(BIG)], r"--rays: must be a whole number in \[1, 100000000\]"),
    ("grad_levers", ["--rays", str(BIG)], r"--rays: must be a whole number in \[1, 100000000\]"),
])
def test_benchmark_clis_bound_their_counts(module, args, text, capsys):
    """Before: --trace-rays and --rays 10**12 aborted in XLA, --repeats 10**9 ran for ever,
    --checkpoint 5 read as on and --size 10**6 failed in a worker after it had started."""
    import importlib

    mod = importlib.import_module(f"benchmarks.{module}")
    with pytest.raises(SystemExit) as e:
        mod.main(args)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(text, err[0]), err


@pytest.mark.parametrize("model", [psf_models.GeometricPSF, psf_models.CoherentPSF])
def test_a_psf_model_pupil_is_bounded_above(model):
    """A PSF traces pupil² rays at once: GeometricPSF(pupil=10**6) was built, and a psf with it
    asked for 10**12 rays."""
    with pytest.raises(ValueError, match=rf"^{model.__name__}: pupil \(rays per side\) must be "
                                         r"an int >= 2, got 4097 \(at most 4096: pupil² rays"):
        model(pupil=4097)
    assert model(pupil=4096).pupil == 4096


@pytest.mark.parametrize("kw, match", [
    (dict(enc_blocks=(1,) * 20, dec_blocks=(1,) * 20),
     r"levels \(len\(enc_blocks\)\) must be .*\[0, 8\]"),
    (dict(middle_blocks=10**6), r"middle_blocks must be .*\[0, 256\]"),
    (dict(enc_blocks=(1, 10**6), dec_blocks=(1, 1)), r"enc_blocks must be .*\[0, 256\] blocks"),
])
def test_nafnet_depth_is_bounded(kw, match):
    """20 levels of width 16 asked for 16·2**20 channels (a MemoryError); a million blocks
    built for hours."""
    from jaxlens.nets import NAFNet

    with pytest.raises(ValueError, match=r"^NAFNet: " + match):
        NAFNet(key=np.random.default_rng(0), **kw)
