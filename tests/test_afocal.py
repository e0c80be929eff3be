"""Afocal image space (``Lens.afocal_image``, Zemax FTYP's seventh value): read, written
and kept; angular spot sizes and magnification (``analysis.afocal``) against optiland 0.6.3
and an ideal telescope; the image-plane analyses refuse such a lens; the afocal report."""

import json
import pathlib
import warnings

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.__main__ import main
from jaxlens.analysis.afocal import angular_magnification, angular_spot
from jaxlens.imaging.sampling import field_rays
from jaxlens.imaging.tiled import psf_points
from jaxlens.optics.paraxial_surface import ParaxialSurface

KEPLER = pathlib.Path(__file__).parent / "data" / "afocal_kepler.zmx"

# optiland 0.6.3, the same file, primary wavelength 0.5875618 µm, N-BK7 at jaxlens's index
# 1.5168000345005883 (SCHOTT's) (/work/optiland_venv/bin/python tools/afocal_reference.py
# tests/data/afocal_kepler.zmx).
DIRECTIONS = [  # (field deg, Px, Py, L, M, N)
    (0.0, 0.0, 0.0, 0.0, 0.0, 0.9999999999999993),
    (0.0, 0.0, 1.0, 0.0, 0.0006900770141974322, 0.9999997618968293),
    (0.0, 0.0, -0.7, 0.0, -0.0002346849895787234, 0.9999999724614772),
    (0.0, 1.0, 0.0, 0.0006900770141974322, 0.0, 0.9999997618968293),
    (0.0, 0.5, 0.5, 0.00017108158863675393, 0.00017108158863675393, 0.9999999707310894),
    (0.5, 0.0, 0.0, 0.0, -0.03510349109628212, 0.9993836825328162),
    (0.5, 0.0, 1.0, 0.0, -0.03425912597092898, 0.9994129838498738),
    (0.5, 0.0, -0.7, 0.0, -0.03589282363985838, 0.9993556450089016),
    (0.5, 1.0, 0.0, 0.0008851203694064391, -0.035229620970505124, 0.9993788522718534),
    (0.5, 0.5, 0.5, 0.00020562837037647885, -0.03479223548598272, 0.9993945457460038),
    (1.0, 0.0, 0.0, 0.0, -0.07142536626218404, 0.9974459469336239),
    (1.0, 0.0, 1.0, 0.0, -0.0693287962265836, 0.9975938642622926),
    (1.0, 0.0, -0.7, 0.0, -0.0736038772202865, 0.9972875559527157),
    (1.0, 1.0, 0.0, 0.0014892160328357218, -0.07168911077124579, 0.9974259138564803),
    (1.0, 0.5, 0.5, 0.0004353031074049024, -0.07042143023684798, 0.9975172342744771),
]
RMS_ANGLE = [  # (field, RMS angular radius in rad about the centroid)
    (0.0, 0.00034984943781609854),
    (0.5, 0.000620910816655052),
    (1.0, 0.001513894587432566),
]


def _ideal(f1=100.0, f2=25.0, **kw):
    """Two ideal thin lenses f1 + f2 apart: a telescope of angular magnification −f1/f2."""
    air = jl.Air()
    return jl.Lens(surfaces=(ParaxialSurface(focal_length=f1), ParaxialSurface(focal_length=f2)),
                   thickness=jnp.array([f1 + f2, 10.0]), materials=(air, air), epd=10.0,
                   fields=(0.0, 0.5, 1.0), afocal_image=True, **kw)


def test_a_kepler_file_reads_as_afocal_and_its_rays_leave_as_optilands():
    lens = jl.load(KEPLER, strict=True)
    assert lens.afocal_image and float(angular_magnification(lens)) == pytest.approx(-4.0,
                                                                                     abs=1e-6)
    wl = lens.primary_wavelength
    for field, px, py, *want in DIRECTIONS:
        r = jl.trace(lens, field_rays(lens, field, jnp.array([[px, py]]), wl))
        assert bool(r.valid[0])
        np.testing.assert_allclose(np.asarray(r.direction[0]), want, rtol=0, atol=1e-13)


def test_angular_spot_is_optilands_rays_measured_by_the_documented_definition():
    lens = jl.load(KEPLER, strict=True)
    s = angular_spot(lens, wavelengths=lens.primary_wavelength[None])
    for (field, want), got in zip(RMS_ANGLE, np.asarray(s.per_wavelength[:, 0]), strict=True):
        assert got == pytest.approx(want, rel=1e-9), field
    assert np.all(np.asarray(s.valid_fraction) == 1.0)
    # The chief ray's output angle and its magnification, from the same rays.
    m = [d for d in DIRECTIONS if d[1] == d[2] == 0.0]
    for i, (field, _, _, _, M, N) in enumerate(m):
        assert float(s.chief_angle[i, 1]) == pytest.approx(np.rad2deg(np.arctan(M / N)),
                                                           abs=1e-12)
        if field:
            assert float(s.magnification[i]) == pytest.approx(
                (M / N) / np.tan(np.deg2rad(field)), rel=1e-12)
    assert np.isnan(float(s.magnification[0]))  # on axis: no angle to compare


def test_an_ideal_telescope_has_no_angular_blur_and_magnifies_by_minus_f1_over_f2():
    lens = _ideal()
    assert float(angular_magnification(lens)) == pytest.approx(-4.0, rel=1e-14)
    s = angular_spot(lens)
    assert float(np.max(np.asarray(s.per_wavelength))) < 1e-12
    np.testing.assert_allclose(np.asarray(s.magnification[1:]), -4.0, rtol=1e-12)
    want = np.rad2deg(np.arctan(-4.0 * np.tan(np.deg2rad([0.0, 0.5, 1.0]))))
    np.testing.assert_allclose(np.asarray(s.chief_angle[:, 1]), want, rtol=0, atol=1e-12)
    # A defocused eyepiece blurs the beam: its angular spread is the defocus over f2².
    out = _ideal()
    out = jl.Lens(**{**{k: getattr(out, k) for k in ("surfaces", "materials", "epd", "fields")},
                     "thickness": jnp.array([125.5, 10.0]), "afocal_image": True})
    marginal = 5.0 * 0.5 / (100.0 * 25.0)  # the rim ray's exit angle (rad), to first order
    got = float(angular_spot(out, fields=jnp.array([0.0]), reference="chief").per_wavelength[0, 0])
    assert got == pytest.approx(marginal / np.sqrt(2.0), rel=0.02)  # RMS over a uniform disc


def test_angular_spot_gradient_matches_central_differences():
    """d(RMS angular radius)/d(the telescope's gap) and d/d(eyepiece curvature), float64."""
    import equinox as eqx
    import jax

    lens = jl.load(KEPLER, strict=True)
    wl = lens.primary_wavelength[None]

    def rms(gap, c):
        moved = eqx.tree_at(lambda L: (L.thickness, L.surfaces[3].c), lens,
                            (lens.thickness.at[1].set(gap), c))
        return angular_spot(moved, fields=jnp.array([0.5]), wavelengths=wl).per_wavelength[0, 0]

    gap, c = lens.thickness[1], lens.surfaces[3].c
    g = jax.grad(rms, argnums=(0, 1))(gap, c)
    for i, (x, h) in enumerate(((gap, 1e-4), (c, 1e-7))):
        args = [gap, c]
        args[i] = x + h
        up = rms(*args)
        args[i] = x - h
        fd = (up - rms(*args)) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-5), i


def test_a_mersenne_beam_reducer_is_erect_and_sharp_on_axis():
    """Two confocal paraboloids (concave f = 100 mm, convex f = −25 mm, 75 mm apart): an
    erect 4× telescope (u′/u = +4), without aberration on axis; the beam leaves along +z
    after the two mirrors, where the output angles are measured from."""
    air = jl.Air()
    lens = jl.Lens(surfaces=(jl.Standard(c=-1 / 200, k=-1.0), jl.Standard(c=-1 / 50, k=-1.0)),
                   thickness=jnp.array([-75.0, 100.0]), materials=(air, air), mirrors=(0, 1),
                   epd=40.0, fields=(0.0, 0.01, 0.1), afocal_image=True)
    assert float(angular_magnification(lens)) == pytest.approx(4.0, rel=1e-14)
    s = angular_spot(lens)
    assert float(s.per_wavelength[0, 0]) < 1e-12 and np.all(np.asarray(s.valid_fraction) == 1)
    assert float(s.magnification[1]) == pytest.approx(4.0, rel=1e-5)  # → 4 toward the axis
    assert float(s.chief_angle[2, 1]) == pytest.approx(0.4, rel=1e-4)  # erect: same sign


def test_image_plane_analyses_refuse_an_afocal_lens():
    lens = _ideal()
    calls = {
        "rms_spot": lambda: jl.analysis.rms_spot(lens),
        "distortion": lambda: jl.analysis.distortion(lens),
        "ray_fan": lambda: jl.analysis.ray_fan(lens, 0.5),
        "field_curvature": lambda: jl.analysis.field_curvature(lens),
        "ToleranceModel": lambda: jl.analysis.tolerance.ToleranceModel(lens),
        "psf_points": lambda: psf_points(lens, jnp.zeros((1, 2)), jnp.inf,
                                         wavelengths=lens.wavelengths, kernel_size=5,
                                         pixel_size=0.005),
        "relative_illumination": lambda: jl.imaging.radiometry.relative_illumination(lens,
                                                                                      [0.0]),
        "seidel": lambda: jl.analysis.seidel(lens),
        "encircled_energy": lambda: jl.analysis.encircled_energy(lens, 0.0, [0.01]),
        "psf": lambda: jl.psf(lens, 0.0, pixel_size=0.005),
        "wavefront": lambda: jl.analysis.wavefront(lens, 0.0, reference="sphere"),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match=rf"{name}.*afocal image space"):
            call()
    # The wavefront of the lens's own image space is referenced to a plane: flat here.
    assert float(jl.analysis.wavefront(lens, 0.0, grid=9).rms) < 0.05
    with pytest.raises(TypeError, match="afocal_image must be True or False"):
        jl.Lens(**{k: getattr(lens, k) for k in ("surfaces", "thickness", "materials")},
                afocal_image=1)


def test_angular_spot_refuses_bad_input_before_tracing():
    lens = _ideal()
    for kw, match in ((dict(pupil=np.array([[np.nan, 0.0]])), r"pupil .*holds 1 NaN"),
                      (dict(fields=[95.0]), r"fields must be finite angles in \(-90, 90\)"),
                      (dict(wavelengths=[]), r"wavelengths must be \[W\] µm with W >= 1"),
                      (dict(reference="best"), "reference must be one of"),
                      (dict(depth=-5.0), r"depth must be finite numbers in \(0, inf\) mm")):
        with pytest.raises(ValueError, match=match):
            angular_spot(lens, **kw)


def test_the_flag_survives_zmx_and_json(tmp_path):
    lens = jl.load(KEPLER, strict=True)
    jl.save(lens, tmp_path / "k.zmx")
    assert "FTYP 0 0 3 3 0 0 1" in (tmp_path / "k.zmx").read_text()
    assert jl.load(tmp_path / "k.zmx", strict=True).afocal_image
    assert json_round_trip(lens, tmp_path).afocal_image
    plain = jl.Lens(**{k: getattr(lens, k) for k in ("surfaces", "thickness", "materials")})
    assert not json_round_trip(plain, tmp_path).afocal_image
    jl.save(lens, tmp_path / "a.json")
    d = json.loads((tmp_path / "a.json").read_text())
    assert d["afocal_image_space"] is True
    for bad, match in (("yes", "afocal_image_space must be true or false"),
                       (1, "afocal_image_space must be true or false")):
        d["afocal_image_space"] = bad
        (tmp_path / "b.json").write_text(json.dumps(d))
        with pytest.raises(ValueError, match=match):
            jl.load(tmp_path / "b.json")
    d.pop("afocal_image_space")
    d["afocal"] = True
    (tmp_path / "c.json").write_text(json.dumps(d))
    with pytest.raises(ValueError, match="afocal_image_space"):
        jl.load(tmp_path / "c.json")


def test_the_report_of_an_afocal_lens_gives_angles(capsys, tmp_path):
    lens = jl.load(KEPLER, strict=True)
    assert main(["report", str(KEPLER), "--json", "--wavefront"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["afocal_image_space"] is True and "efl" not in data
    assert data["angular_magnification"] == pytest.approx(-4.0, abs=1e-6)
    s = angular_spot(lens)
    for f, per in zip(data["fields"], np.asarray(s.per_wavelength), strict=True):
        np.testing.assert_allclose(f["rms_angle"], 1000.0 * per, rtol=1e-12)
        assert f["wavefront"]["rms"] > 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["report", str(KEPLER)]) == 0
    out = capsys.readouterr().out
    assert "afocal image space" in out and "Angular magnification" in out
    assert "RMS angular radius" in out and "to a plane" not in out
    # --plot draws what has a meaning and names the rest, with the reason.
    assert main(["report", str(KEPLER), "--plot", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert (tmp_path / "afocal_kepler_layout.png").exists()
    assert not (tmp_path / "afocal_kepler_spots.png").exists()
    assert "spots.png not drawn: plot_spots: the lens has an afocal image space" in err
