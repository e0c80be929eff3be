"""No silent wrong answers (issue 11): bad input gets a clear error before the work starts,
every lost ray is accounted for, and no run destroys an earlier one.

Each test names the issue item it covers. A refusal must name the argument, the value, the
valid range and the unit.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import re
import subprocess
import sys
import time
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.experiments import runfolder
from jaxlens.imaging.psf import CoherentPSF, GeometricPSF
from jaxlens.imaging.render import PSFRender, RayRender
from jaxlens.io import zmx
from jaxlens.optics import checks

DATA = pathlib.Path(jl.__file__).parent / "data" / "lenses"
COOKE_ZMX = (DATA / "cooke_triplet.zmx").read_bytes()
ROOT = pathlib.Path(__file__).parent.parent


@pytest.fixture(scope="module")
def cooke():
    return jl.load(DATA / "cooke_triplet.zmx")


def _vignetting():
    """A singlet with a 1 mm aperture 25 mm behind it: 20° misses it entirely."""
    return jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.02), jl.Plane(1.0)),
                   thickness=jnp.array([5.0, 20.0, 25.0]),
                   materials=(jl.get_material("N-BK7"), jl.Air(), jl.Air()), epd=10.0)


def _singlet(t2=45.0, stop_sd=None):
    sd = jnp.inf if stop_sd is None else stop_sd
    return jl.Lens(surfaces=(jl.Sphere(0.02, sd), jl.Sphere(-0.02)),
                   thickness=jnp.array([5.0, t2]),
                   materials=(jl.get_material("N-BK7"), jl.Air()), epd=10.0,
                   fields=jnp.array([0.0, 5.0]))


# ---------------------------------------------------------------- 1. rms_spot without rays


def test_rms_spot_field_without_rays_is_nan_with_finite_gradient():
    lens = _vignetting()
    fields = jnp.array([0.0, 20.0])
    # The batch API keeps the dark field's NaN and names it in a NoLightWarning (round 41b).
    with pytest.warns(jl.imaging.light.NoLightWarning, match=r"rms_spot: .*field\(s\) 20 deg"):
        r = jl.analysis.rms_spot(lens, fields)
    assert np.all(np.asarray(r.valid_fraction[1]) == 0)
    assert np.all(np.isnan(np.asarray(r.per_wavelength[1])))
    assert np.isnan(float(r.polychromatic[1]))
    assert np.isfinite(float(r.polychromatic[0])) and float(r.polychromatic[0]) > 0
    # No chief ray reaches the image either: no intercept (it was where the ray failed).
    assert np.all(np.isnan(np.asarray(r.chief[1]))) and np.all(np.isfinite(np.asarray(r.chief[0])))

    def loss(c):
        s = eqx.tree_at(lambda L: L.surfaces[0].c, lens, c)
        return jnp.nansum(jl.analysis.rms_spot(s, fields).polychromatic)

    g = jax.jit(jax.grad(loss))(jnp.asarray(0.02))  # one compile, not op by op
    assert np.isfinite(float(g)) and float(g) != 0
    # A single valid ray (RMS exactly 0) has a finite gradient too (the value and the
    # gradient from one compiled program).
    one, g1 = jax.jit(jax.value_and_grad(lambda c: jl.analysis.rms_spot(
        eqx.tree_at(lambda L: L.surfaces[0].c, lens, c), jnp.array([0.0]),
        pupil=jnp.zeros((1, 2))).polychromatic[0]))(jnp.asarray(0.02))
    assert float(one) == 0.0
    assert np.isfinite(float(g1))


# ---------------------------------------------------------------- 2, 11. truncated .zmx


@pytest.mark.parametrize("cut", [600, 750, 900, 1100, 1300, len(COOKE_ZMX) - 200])
def test_truncated_zmx_is_refused(cut):
    text = zmx.decode(COOKE_ZMX[:cut])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", zmx.ZmxWarning)
        with pytest.raises(ValueError, match=r"<zmx>:\d+: .*(truncated|not a Zemax keyword)"):
            zmx.loads(text)


def test_zmx_cut_mid_line_and_unknown_keywords_warn_or_refuse_in_strict_mode():
    text = zmx.decode(COOKE_ZMX).replace("GFAC 0 0", "GFAC 0 0\nFOOBAR 1 2")
    with pytest.warns(zmx.ZmxWarning, match=r"<zmx>:8: unknown keyword 'FOOBAR'"):
        zmx.loads(text)
    with pytest.raises(ValueError, match=r"unknown keyword 'FOOBAR'.*strict"):
        zmx.loads(text, strict=True)
    cut = zmx.decode(COOKE_ZMX).rstrip("\r\n")[:-3]  # the last DIAM line, cut
    with pytest.raises(ValueError, match=r"does not end with a line break.*strict"):
        zmx.loads(cut, strict=True)
    # A last line jaxlens ignores (a vendor's file ending on MOFF) cannot change the lens,
    # and OpticStudio's AUTH/LUID/SSID/RCMF/XAIM lines are known: neither is reported.
    ends_on_moff = zmx.decode(COOKE_ZMX).rstrip("\r\n") + '\nMOFF 0 1 "" 0 0 0 1 1 0 0.0 ""'
    with_ids = zmx.decode(COOKE_ZMX).replace("GFAC 0 0", "GFAC 0 0\nAUTH \nLUID 3\nXAIM 0\n"
                                             "RCMF 1 0")
    with warnings.catch_warnings():
        warnings.simplefilter("error", zmx.ZmxWarning)
        for text in (ends_on_moff, with_ids):
            assert zmx.loads(text, strict=True).num_surfaces == 6


def _minimal(surface1="  CURV 0.02\n", head="ENPD 10\nWAVM 1 0.55 1\n", glass="GLAS N-BK7",
             disz1="  DISZ 5\n"):
    return (f"UNIT MM\n{head}SURF 0\n  DISZ INFINITY\nSURF 1\n{surface1}{disz1}  {glass}\n"
            f"SURF 2\n  CURV -0.02\n  DISZ 45\nSURF 3\n")


def test_zmx_missing_disz_is_refused_not_zero():
    with pytest.raises(ValueError, match=r"<zmx>:6: surface 1 has no DISZ line"):
        zmx.loads(_minimal(disz1=""))


def test_zmx_image_with_thickness_means_a_cut_file():
    text = _minimal().replace("SURF 3\n", "SURF 3\n  DISZ 12\n")
    with pytest.raises(ValueError, match=r"last surface.*thickness 12.*truncated"):
        zmx.loads(text)


# ---------------------------------------------------------------- 3. XPOLYNOM cylinder


def test_xpolynom_x2_alone_is_a_cylinder_but_not_a_hybrid():
    """Zemax's XPOLYNOM with an x² term alone is the XYPolynomial cylinder; marked as
    jaxlens's hybrid (its comment) it is refused: a hybrid's even part is in r²."""
    text = _minimal("  TYPE XPOLYNOM\n  XDAT 1 3\n  XDAT 2 1\n  XDAT 3 0\n  XDAT 4 0\n"
                    "  XDAT 5 1e-3\n")
    s = zmx.loads(text).surfaces[0]
    assert type(s) is jl.XYPolynomial
    assert float(s.paraxial_curvature_x) == 2e-3 and float(s.paraxial_curvature) == 0.0
    hybrid = _minimal("  TYPE XPOLYNOM\n  COMM jaxlens hybrid even=1 odd=0\n  XDAT 1 3\n"
                      "  XDAT 2 1\n  XDAT 5 1e-3\n")
    with pytest.raises(ValueError, match=r"x\^0 y\^2 = 0\.0 does not fit the hybrid surface"):
        zmx.loads(hybrid)


# ---------------------------------------------------------------- 4. wavelengths


def test_wavelength_in_nm_or_beyond_the_glass_is_refused(cooke, tmp_path):
    o, d = jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match=r"Rays: wavelength 587\.6 µm is outside .* 587\.6 "
                                         r"nm is 0\.5876 µm"):
        jl.Rays(o, d, 587.6)
    # 5 µm is a valid wavelength, but beyond the data of N-SK16 and F2 (0.31-2.5 µm).
    with pytest.raises(Exception, match=r"trace: rays\.wavelength outside 0\.3.*µm, the data "
                                        r"range of"):
        jl.trace(cooke, jl.Rays(o, d, 5.0))
    with pytest.raises(ValueError, match=r"psf: wavelength 5 µm is outside 0\.3\d*–2\.5 µm"):
        jl.psf(cooke, 0.0, wavelength=5.0, pixel_size=0.005)
    with pytest.raises(ValueError, match=r"render: wavelengths .* µm is outside"):
        jl.render(dataclasses.replace(cooke, sensor=jl.Sensor((8, 8), 0.01)),
                  jnp.ones((8, 8, 3)), spp=1, key=jax.random.PRNGKey(0),
                  wavelengths=(0.6563, 0.5876, 4.0))
    # A JSON file with µm under wavelengths_nm.
    d = json.loads(jl.io.lensfile.dumps(cooke))
    d["wavelengths_nm"] = d.pop("wavelengths_um")
    d.pop("units")  # its "wavelength": "um" against wavelengths_nm is refused first (round 14)
    p = tmp_path / "nm.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"nm\.json: wavelengths_nm: wavelength .* µm is "
                                         r"outside .*were µm given where nm are expected"):
        jl.load(p)


def test_index_at_zero_wavelength_is_refused_at_the_entry_point():
    with pytest.raises(ValueError, match=r"Rays: wavelength 0 µm is outside 0\.15–30 µm"):
        jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), 0.0)


def test_wavelength_check_under_jit_uses_error_if(cooke):
    o, d = jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]])
    f = jax.jit(lambda w: jl.trace(cooke, jl.Rays(o, d, w)).origin)
    assert np.all(np.isfinite(f(0.55)))
    with pytest.raises(Exception, match=r"outside 0\.3"):
        f(0.2)


# ---------------------------------------------------------------- 5. broken materials


def test_broken_materials_are_refused(tmp_path, cooke):
    with pytest.raises(ValueError, match=r"Sellmeier.*B and C need one coefficient per term"):
        jl.Sellmeier(jnp.array([1.0, 0.2, 1.0]), jnp.array([0.006, 0.02]))
    with pytest.raises(ValueError, match=r"ModelGlass: nd must be a finite index >= 1, got 0\.9"):
        jl.ModelGlass(0.9, 50.0)
    # A Sellmeier with a negative term: no real index in the visible.
    d = json.loads(jl.io.lensfile.dumps(cooke))
    d["surfaces"][1]["material"] = {"class": "Sellmeier", "B": [-3.0, 0.0, 0.0],
                                    "C": [0.01, 0.02, 100.0]}
    p = tmp_path / "neg.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"neg\.json: .*after surface 1: refractive index \[nan, "
                                         r".* at wavelength"):
        jl.load(p)
    d["surfaces"][1]["material"] = {"nd": 0.9, "vd": 50}
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"model glass needs nd >= 1"):
        jl.load(p)
    with pytest.raises(ValueError, match=r"model glass needs nd >= 1 .*nd 0\.9"):
        zmx.loads(_minimal(glass="GLAS ___BLANK 1 0 0.9 50"))


def test_broken_agf_glass_is_refused(tmp_path):
    p = tmp_path / "BAD.agf"
    p.write_text("NM BADGLASS 2 0 1.5 60 0 0 0\nCD -5 0.01 0 0 0 0\nLD 0.3 2.5\n")
    with pytest.raises(ValueError, match=r"glass BADGLASS of catalog BAD: refractive index nan"):
        jl.load_agf(p)


# ---------------------------------------------------------------- 6. rays and field angles


def test_non_unit_directions_and_wrapping_field_angles_are_refused():
    o = jnp.array([[0.0, 1.0, -1.0]])
    with pytest.raises(ValueError, match=r"Rays: direction must hold unit vectors .*length 3"):
        jl.Rays(o, jnp.array([[0.0, 0.0, 3.0]]), 0.55)
    for bad in (90.0, 120.0, -95.0, float("nan")):
        with pytest.raises(ValueError, match=r"field must be finite angles in \(-90, 90\) deg"):
            jl.sampling.field_direction(bad)
    with pytest.raises(ValueError, match=r"field must be finite angles.*120"):
        jl.sampling.field_direction(jnp.array([0.0, 120.0]))
    with pytest.raises(Exception, match=r"field must be finite angles"):
        jax.jit(jl.sampling.field_direction)(120.0)


def test_report_fields_out_of_range(capsys):
    from jaxlens.__main__ import main

    for v in ("120", "nan"):
        assert main(["report", str(DATA / "cooke_triplet.zmx"), "--fields", v]) == 2
        err = capsys.readouterr().err
        assert "--fields must be finite angles in (-90, 90) deg" in err


# ---------------------------------------------------------------- 7. psf


def test_psf_no_ray_is_not_truncation_and_overfill_is_checked():
    lens = _vignetting()
    with pytest.raises(Exception, match=r"no ray of the beam reaches the image surface"):
        jl.psf(lens, 20.0, pixel_size=0.01, kernel_size=9, model=GeometricPSF(pupil=8))
    info = jl.imaging.psf.psf_info(lens, 20.0, pixel_size=0.01, kernel_size=9,
                                   model=GeometricPSF(pupil=8))
    assert np.isnan(float(info.truncated))
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match=r"(psf|GeometricPSF): overfill must be a finite "
                                             r"number in "
                                             r"\(0, inf\)"):
            jl.psf(lens, 0.0, pixel_size=0.01, model=GeometricPSF(overfill=bad))


def test_psf_kernel_holding_too_much_energy_is_refused(cooke):
    # A coarse pupil sampling against a wide kernel: the coherent sum over-counts the
    # energy (1.48), which the truncation check (1 - sum > 0.05) let through.
    kw = dict(model=CoherentPSF(pupil=12), pixel_size=1e-3, kernel_size=45)
    info = jl.imaging.psf.psf_info(cooke, 0.0, **kw)
    assert float(np.sum(info.psf)) > 1.4
    with pytest.raises(Exception, match=r"kernel holds more than 1 \+ 0\.05"):
        jl.psf(cooke, 0.0, **kw)


# ---------------------------------------------------------------- 8. render


def test_render_arguments_are_checked(cooke):
    lens = dataclasses.replace(cooke, sensor=jl.Sensor((8, 8), 0.01))
    key = jax.random.PRNGKey(0)
    scene = jnp.ones((8, 8, 3))
    cases = [
        (dict(key=None), r"render: key must be one PRNG key"),
        (dict(key=key, method=PSFRender(kernel_size=0)), r"kernel_size must be a whole number "
                                                         r"in \[1, 4096\] pixels, got 0"),
        (dict(key=key, method=PSFRender(kernel_size=8)), r"kernel_size must be odd"),
        (dict(key=key, method=RayRender(footprint_grid=1)),
         r"footprint_grid must be a whole number in \[2"),
    ]
    for kw, match in cases:
        with pytest.raises(ValueError, match=match):
            jl.render(lens, scene, spp=1, **kw)
    with pytest.raises(ValueError, match=r"render: scene is empty"):
        jl.render(lens, jnp.ones((0, 0, 3)), spp=1, key=key)
    nan_scene = scene.at[3, 4, 1].set(jnp.nan)
    with pytest.raises(ValueError, match=r"render: scene \(linear pixel values\) holds 1 NaN "
                                         r"or infinite value\(s\), first at index \(3, 4, 1\)"):
        jl.render(lens, nan_scene, spp=1, key=key)
    # Radiance is never negative: an image left in [-1, 1] is refused, not rendered.
    with pytest.raises(ValueError, match=r"render: scene must be finite numbers in \[0, inf\) "
                                         r"\(linear radiance\), got -0.5"):
        jl.render(lens, scene.at[2, 2, 0].set(-0.5), spp=1, key=key)
    assert jnp.all(jnp.isfinite(jl.render(lens, scene.at[2, 2, 0].set(0.0), spp=1, key=key)))
    with pytest.raises(ValueError, match=r"Sensor: pixel_size must be a finite number in "
                                         r"\(0, inf\) mm, got"):
        jl.Sensor((8, 8), 0.0)
    with pytest.raises(ValueError, match=r"Sensor: resolution must be \(rows, columns\), whole "
                                         r"numbers >= 1 pixels \(at most 16384 per side\), "
                                         r"got \(0, 0\)"):
        jl.Sensor((0, 0), 0.01)


# ---------------------------------------------------------------- 9. negative thickness


def test_negative_gap_is_traced_not_lost():
    """A dummy plane 10 mm after the lens and a gap of -10 mm back: the same lens."""
    bk7 = jl.get_material("N-BK7")
    plain = _singlet()
    folded = jl.Lens(
        surfaces=(jl.Sphere(0.02), jl.Sphere(-0.02), jl.Plane()),
        thickness=jnp.array([5.0, 55.0, -10.0]),
        materials=(bk7, jl.Air(), jl.Air()), epd=10.0)
    tiny = jl.Lens(  # a solve's -1e-8 between two surfaces
        surfaces=(jl.Sphere(0.02), jl.Plane(), jl.Sphere(-0.02)),
        thickness=jnp.array([5.0, -1e-8, 45.0 + 1e-8]),
        materials=(bk7, bk7, jl.Air()), epd=10.0)
    pupil = jl.sampling.pupil_grid(7)
    rays = jl.sampling.collimated(plain, 3.0, pupil)
    ref = jl.trace(plain, rays)

    def traced(t, lens):
        out = jl.trace(eqx.tree_at(lambda x: x.thickness, lens, t), rays)
        return jnp.sum(out.origin[:, 1] ** 2), out

    # The trace and its gradient in one compiled program per lens (op by op, the gradient
    # compiled two programs of its own).
    trace_and_grad = eqx.filter_jit(jax.value_and_grad(traced, has_aux=True))
    for lens in (folded, tiny):
        (_, out), g = trace_and_grad(lens.thickness, lens)
        assert bool(jnp.all(out.valid))
        np.testing.assert_allclose(np.asarray(out.origin), np.asarray(ref.origin), atol=1e-9)
        assert np.all(np.isfinite(np.asarray(g)))
    # A ray that would have to go back across a positive gap is still lost: start it
    # on surface 1's vertex plane but aim it away from the axis so it leaves surface 1
    # beyond the vertex of surface 2 (a 0.5 mm gap, steep surfaces).
    thin = jl.Lens(surfaces=(jl.Sphere(0.2), jl.Sphere(-0.2)), thickness=jnp.array([0.5, 5.0]),
                   materials=(bk7, jl.Air()), epd=1.0)
    edge = jl.Rays(jnp.array([[0.0, 4.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.55)
    assert not bool(jl.trace(thin, edge).valid[0])


# ---------------------------------------------------------------- 10. the CLIs


REFUSAL_BOUND_S = 30
"""Seconds a refusal may take: it comes before any compile or training (each run takes
minutes), but a fresh interpreter imports JAX first: about 4 s alone, over 10 s (the bound
this replaced, which failed) with two other jobs on the 2 cores; one CI run ran 3x slower."""


def _cli(module, *args, cwd=None):
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT)},
                       cwd=cwd, timeout=120)
    return r, time.perf_counter() - t0


def _cli_in_process(main, args, monkeypatch, capsys):
    """(exit status, stderr, seconds) of a command line's ``main()`` run in this process with
    ``args`` as its options: the option checks without a new interpreter and JAX import
    (about 4 s each). One case per command line also runs as a real subprocess
    (``test_*_cli_refusal_is_one_line_from_a_fresh_interpreter``)."""
    monkeypatch.setattr(sys, "argv", ["python -m ...", *args])
    # The design command may set the device count in XLA_FLAGS before a later check refuses.
    monkeypatch.setenv("XLA_FLAGS", os.environ.get("XLA_FLAGS", ""))
    capsys.readouterr()
    t0 = time.perf_counter()
    try:
        code = main()
    except SystemExit as e:
        code = e.code
    return code, capsys.readouterr().err, time.perf_counter() - t0


@pytest.mark.parametrize("args, match", [
    (["--steps", "0"], r"--steps must be a finite number in \(0, 50\]"),
    (["--steps", "-1"], r"--steps must be"),
    (["--fnum", "inf"], r"--fnum must be a finite number in \[0.5, 64\] \(F-number f/EPD\), "
                        r"got inf"),
    (["--asphere-terms", "1000"], r"--asphere-terms must be a whole number in \[0, 12\]"),
    (["--seeds", "0"], r"--seeds must be a whole number in \[1, 1024\] designs, got 0"),
    (["--seed-list", "a,b"], r"--seed-list must be comma-separated whole numbers"),
    (["--devices", "0"], r"--devices must be a whole number in \[1, 256\] host devices, got 0"),
    (["--fov", "nan"], r"--fov must be a finite number in \(0, 180\) deg"),
])
def test_design_cli_refuses_bad_options_fast(args, match, tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    from jaxlens.experiments import classical

    code, err, dt = _cli_in_process(classical.main, [*args, "--out", str(out)], monkeypatch,
                                    capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert re.search(match, lines[0]), lines[0]
    assert dt < REFUSAL_BOUND_S, dt
    assert not out.exists()


def test_design_cli_refusal_is_one_line_from_a_fresh_interpreter(tmp_path):
    """The real command line (new process: the device-count setup, JAX's import and its
    warnings included) also refuses with status 2 and one stderr line, before any work."""
    out = tmp_path / "run"
    r, dt = _cli("jaxlens.experiments.classical", "--fov", "nan", "--out", str(out))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(r"--fov must be a finite number", lines[0]), r.stderr
    assert dt < REFUSAL_BOUND_S, dt
    assert not out.exists()


def test_run_folder_protects_earlier_runs(tmp_path):
    out = tmp_path / "run"
    f = runfolder.RunFolder(str(out))
    tmp = f.start()
    (pathlib.Path(tmp) / "lens.json").write_text("{}")
    assert not out.exists()  # nothing looks finished while the run is on
    assert f.finish() == str(out)
    assert (out / runfolder.FINISHED).exists() and (out / "lens.json").exists()
    with pytest.raises(runfolder.UsageError, match=r"holds an earlier run; give --overwrite"):
        runfolder.RunFolder(str(out))
    # --overwrite: the earlier run stays untouched until the new one is complete.
    g = runfolder.RunFolder(str(out), overwrite=True)
    tmp2 = g.start()
    (pathlib.Path(tmp2) / "new.json").write_text("{}")
    assert (out / "lens.json").exists()
    g.finish()
    assert (out / "new.json").exists() and not (out / "lens.json").exists()
    # An interrupted run leaves --out as it was.
    h = runfolder.RunFolder(str(out), overwrite=True)
    h.start()
    h.abandon()
    assert (out / "new.json").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    other = tmp_path / "notes"
    other.mkdir()
    (other / "mine.txt").write_text("x")
    with pytest.raises(runfolder.UsageError, match=r"not empty and holds no finished"):
        runfolder.RunFolder(str(other), overwrite=True)


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes anywhere")
def test_unwritable_out_is_found_first(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        for module in ("jaxlens.experiments.classical", "jaxlens.experiments.edof"):
            r, dt = _cli(module, "--smoke", "--out", str(locked / "run"))
            assert r.returncode == 2 and "cannot create or write there" in r.stderr, r.stderr
            assert dt < REFUSAL_BOUND_S, dt
    finally:
        locked.chmod(0o700)


def test_cli_refuses_an_earlier_run_without_overwrite(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / runfolder.FINISHED).write_text("finished\n")
    (out / "summary.json").write_text("{}")
    for module in ("jaxlens.experiments.classical", "jaxlens.experiments.edof"):
        r, _ = _cli(module, "--smoke", "--out", str(out))
        assert r.returncode == 2 and "holds an earlier run" in r.stderr, r.stderr
        assert (out / "summary.json").read_text() == "{}"


def test_ablation_refuses_to_replace_a_column_or_write_into_a_file(tmp_path, capsys):
    """Columns run separately share ``--ablation-out``: a column already there is kept unless
    ``--overwrite`` is given, and a file as the folder is refused, both before any work."""
    from jaxlens.experiments import classical

    out = tmp_path / "ablation"
    (out / "columns").mkdir(parents=True)
    earlier = out / "columns" / "plus_recipe.json"
    earlier.write_text("{}")
    common = ["--ablation", "--smoke", "--ablation-seeds", "1", "--quiet", "--devices", "1"]
    t0 = time.perf_counter()
    assert classical.main(common + ["--columns", "+both,+recipe", "--ablation-out",
                                    str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds the column(s) +recipe of an earlier run" in err and "--overwrite" in err
    assert earlier.read_text() == "{}"
    (tmp_path / "file").write_text("x")
    assert classical.main(common + ["--ablation-out", str(tmp_path / "file")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
    assert time.perf_counter() - t0 < 10


def test_an_out_folder_the_file_system_refuses_is_one_line(tmp_path, capsys, monkeypatch):
    """``--out`` whose temporary folder cannot be made when the run starts (e.g. under /proc,
    which passes the writability check) is a one-line error, not a traceback."""
    import tempfile

    from jaxlens.experiments import classical

    def refuse(*a, **k):
        raise FileNotFoundError(2, "No such file or directory")

    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    assert classical.main(["--smoke", "--quiet", "--devices", "1", "--out",
                           str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write there" in err[0], err


@pytest.mark.parametrize("args, match", [
    (["--steps", "0"], r"--steps must be a whole number in \[1, 100000\] steps, got 0"),
    (["--kernel", "8"], r"--kernel must be an odd whole number"),
    (["--lr-net", "inf"], r"--lr-net must be a finite number in \(0, 1\] \(Adam step size\)"),
    (["--lenses", "zoom"], r"--lenses takes distinct names from"),
    (["--binning", "3"], r"--binning must divide"),
    (["--hybrid-floor", "-1"], r"--hybrid-floor must be a finite number in \[0, 1\]"),
    (["--live-front-end", "--decoder", "nafnet"], r"--live-front-end needs a Wiener"),
])
def test_edof_cli_refuses_bad_options_fast(args, match, tmp_path, monkeypatch, capsys):
    from jaxlens.experiments.edof import cli

    code, err, dt = _cli_in_process(cli.main, [*args, "--out", str(tmp_path / "run")],
                                    monkeypatch, capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and re.search(match, lines[0]), err
    assert dt < REFUSAL_BOUND_S, dt
    assert not (tmp_path / "run").exists()


def test_edof_cli_refusal_is_one_line_from_a_fresh_interpreter(tmp_path):
    r, dt = _cli("jaxlens.experiments.edof", "--kernel", "8", "--out", str(tmp_path / "run"))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(r"--kernel must be an odd whole number", lines[0]), \
        r.stderr
    assert dt < REFUSAL_BOUND_S, dt
    assert not (tmp_path / "run").exists()


# ---------------------------------------------------------------- 11. minor items


def test_utf16_and_deeply_nested_json_name_the_file(tmp_path, capsys):
    p = tmp_path / "u16.json"
    p.write_bytes(jl.io.lensfile.dumps(jl.load(DATA / "cooke_triplet.zmx")).encode("utf-16"))
    with pytest.raises(ValueError, match=r"u16\.json: not UTF-8 text"):
        jl.load(p)
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(ValueError, match=r"deep\.json: .*nested too deeply"):
        jl.load(deep)
    from jaxlens.__main__ import main

    assert main(["report", str(deep)]) == 2
    assert "nested too deeply" in capsys.readouterr().err


def test_glas_nd_vd_cross_checked_against_the_catalog():
    with pytest.warns(zmx.ZmxWarning, match=r"GLAS N-BK7 gives nd 1\.7, Vd 30.*catalog SCHOTT "
                                            r"has nd 1\.5168"):
        zmx.loads(_minimal(glass="GLAS N-BK7 0 0 1.7 30 0 0 0 0 0 0"))


def test_report_prints_no_infinity_or_endless_digits():
    from jaxlens.analysis.report import _num

    assert _num(None, 12, 4).strip() == "failed"
    assert _num(float("inf"), 14, 6).strip() == "Infinity"
    wide = _num(1e300, 14, 6)
    assert len(wide) == 14 and "e+300" in wide
    assert len(_num(-123456789.0, 12, 4)) == 12


def test_checks_number_names_argument_value_range_and_unit():
    with pytest.raises(ValueError, match=r"^f: x must be a finite number in \(0, 5\] mm, got "
                                         r"-1$"):
        checks.number(-1, "x", "f", lo=0, hi=5, lo_open=True, unit="mm")
    with pytest.raises(ValueError, match=r"whole number"):
        checks.number(2.5, "n", "f", lo=0, integer=True)
    with pytest.raises(ValueError, match=r"whole number"):
        checks.number(True, "n", "f", lo=0, integer=True)
    assert checks.number(3, "n", "f", lo=0, integer=True) == 3


def test_clear_semi_diameters_refuses_a_reaching_that_is_not_a_bool():
    with pytest.raises(TypeError, match="reaching must be True or False, got 'yes'"):
        jl.analysis.clear_semi_diameters(jl.zoo.cooke_triplet(), reaching="yes")
