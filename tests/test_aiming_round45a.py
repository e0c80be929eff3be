"""Round 45a: real-ray-aimed beams in the imaging layer against optiland 0.6.3.

Reference: tools/aim45a_reference.py (optiland's robust ray aiming; tests/data/aim45a/
aim45a_optiland.json). Conventions, the same in both (so nothing is converted but Laikin's
inches): a pupil point (Px, Py) of the unit disc is aimed at (Px, Py)·r_stop on the stop, r_stop
the real on-axis marginal ray's height there (``aim="real_marginal"``, optiland's
``RealReferenceStrategy``, Zemax's "Real") or the paraxial one's (``aim="real"``: the tool
gives optiland its own ``ParaxialReferenceStrategy``, Zemax's "Paraxial"); a field is the
angle θy of the beam's direction (0, sin θ, cos θ), at a finite object the object point
−tan θ·(z_EP − z_object) (optiland's ``AngleField`` and ``sampling.object_point``). The
lenses are traced without their vignetting factors (optiland's iterative aimer sets its
stop targets at (Px, Py)·r_stop whatever the factors, which move only its paraxial seed;
jaxlens maps the pupil points by them first, as OpticStudio: ``sampling.field_rays``) and,
but for three cases, without their apertures (``optics.lens.unclipped``).

Tolerances. Both trace the same pupil points (no Monte-Carlo sampling anywhere here): the spot
grid (``sampling.pupil_grid(21)``, 317 rays) and the geometric PSF's grid (64² cell centres
times the overfill 1.25 cut to the unit disc, 2056 rays; the model is given explicitly, so a
change of the default grid does not move the comparison). Two tracers of the same rays agree
to rounding and to their aiming's convergence: optiland aims to 1e-13 (lens units) at the
stop, jaxlens to 1e-12 of the stop radius (``sampling.AIM_CONVERGED``); measured, the
intercepts agree to 8e-13 mm (at the stop; 1e-13 mm on the image surface), the spots' radii
and centroids to 5e-15 mm, the |OTF| to 4e-12. The tests allow 1e-9 mm for intercepts and
spot centroids (relative 1e-9 for the radii), and 1e-8 for the |OTF|: three orders above the
measured agreement, many below any effect of a different beam (a stop sized for infinity
instead of the 400 mm object moves the aimed rim ray by 6e-3 mm at the stop; each of the
2056 rays weighs 4.9e-4 in the |OTF|).
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.imaging import radiometry, render, sampling
from jaxlens.imaging.psf import GeometricPSF, mtf
from jaxlens.optics import paraxial
from jaxlens.optics.lens import unclipped
from jaxlens.optics.rays import Rays
from jaxlens.tracing.forward import trace_path

ROOT = pathlib.Path(__file__).resolve().parents[1]
REF = json.loads((ROOT / "tests" / "data" / "aim45a" / "aim45a_optiland.json").read_text())
MODEL = GeometricPSF(pupil=REF["mtf_cells"], overfill=REF["mtf_overfill"])
FAST = ("laikin_real_marginal",)  # the widest lens: the rest behind `slow` (CPU time)


def _unit(name):
    return 25.4 if name.startswith("laikin") else 1.0  # Laikin's file is in inches


def _lens(name):
    r = REF["cases"][name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(str(ROOT / r["file"]))
    aim = lens.aim if r["aim"] == "file" else r["aim"]  # "file": as the reader sets it
    lens = dataclasses.replace(lens, aim=aim, vignetting=None)
    return lens if r["apertures"] else unclipped(lens)


def _case_params():
    return [pytest.param(n, marks=() if n in FAST else pytest.mark.slow) for n in REF["cases"]]


def _field_params():
    """(case, field index): in the fast run Laikin's widest field (50°) only."""
    return [pytest.param(n, i, marks=() if (n in FAST and i == len(c["fields"]) - 1)
                         else pytest.mark.slow)
            for n, c in REF["cases"].items() for i in range(len(c["fields"]))]


@pytest.mark.parametrize("name", _case_params())
def test_aimed_spot_and_mtf_are_optilands(name):
    """The aimed stop radius; per field the spot's RMS radius, centroid and passing rays,
    and the geometric |OTF| of the aimed beam."""
    r = REF["cases"][name]
    lens, u = _lens(name), _unit(name)
    wl = r["primary_um"]
    depth = sampling.lens_depth(lens, None, "test")
    fields = np.array([f["field_deg"] for f in r["fields"]])
    aim_size = sampling.AIM_STOP_SIZE[lens.aim]
    r_stop = sampling.stop_radius(lens, aim_size, object_z=None if depth is None else -depth)
    assert abs(float(r_stop) - r["stop_radius"] * u) <= 1e-9
    spot = jl.analysis.rms_spot(lens, fields=jnp.asarray(fields), wavelengths=jnp.array([wl]))
    for i, f in enumerate(r["fields"]):
        at = f"{name} {f['field_deg']}°"
        ref = f["spot"]
        if r["rim_on_stop_edge"]:  # the spot grid's rim rays pass the stop's edge or not
            continue  # by rounding (the FLOA case); its |OTF| grid has no rim point

        np.testing.assert_allclose(float(spot.per_wavelength[i, 0]), ref["rms"] * u, rtol=1e-9,
                                   atol=1e-12, err_msg=at)
        np.testing.assert_allclose(np.asarray(spot.centroid[i, 0]),
                                   np.asarray(ref["centroid"]) * u, rtol=0, atol=1e-9,
                                   err_msg=at)
        assert round(float(spot.valid_fraction[i, 0]) * 317) == ref["rays"], at
    for f in r["fields"]:
        at = f"{name} {f['field_deg']}°"
        _, t, s = mtf(lens, f["field_deg"], wavelengths=[wl], model=MODEL, diffraction=False,
                      frequencies=np.asarray(r["freqs"]) / u)
        np.testing.assert_allclose(np.asarray(t), f["otf"]["tangential"], rtol=0, atol=1e-8,
                                   err_msg=at)
        np.testing.assert_allclose(np.asarray(s), f["otf"]["sagittal"], rtol=0, atol=1e-8,
                                   err_msg=at)


@pytest.mark.parametrize(("name", "i"), _field_params())
def test_aimed_chief_and_marginal_rays_are_optilands(name, i):
    """The chief ray, the four marginal rays and a skew one of the aimed beam: their
    object-space directions, which of them pass, and where they cross surface 1, the stop
    and the image surface."""
    r = REF["cases"][name]
    f = r["fields"][i]
    lens, u = _lens(name), _unit(name)
    depth = sampling.lens_depth(lens, None, "test")
    at = f"{name} {f['field_deg']}°"
    rays = sampling.field_rays(lens, f["field_deg"], jnp.asarray(REF["points"]),
                               r["primary_um"], depth=depth)
    alive = np.asarray(f["rays"]["alive"])
    if r["rim_on_stop_edge"]:  # the marginal rays land on the stop's edge: traced through
        lens, alive = unclipped(lens), np.ones_like(alive)
    path = trace_path(lens, rays)
    np.testing.assert_array_equal(np.asarray(path[-1].valid), alive, err_msg=at)
    np.testing.assert_allclose(np.asarray(rays.direction), f["rays"]["direction"], rtol=0,
                               atol=1e-12, err_msg=at)
    for key, k in (("surface1", 0), ("stop", lens.stop), ("image", -1)):
        got = np.asarray(path[k].origin[:, :2])[alive]
        np.testing.assert_allclose(got, np.asarray(f["rays"][key])[alive] * u, rtol=0,
                                   atol=1e-9, err_msg=f"{at} {key}")


def test_float_by_stop_file_fills_its_stop():
    """A FLOA file's aperture is its stop's semi-diameter: with RAIM's type 2 (Zemax's "Real")
    it is read as aim "real", which fills that stop (4 mm), as OpticStudio and optiland aim;
    read as "real_marginal" (before), the real marginal ray sized the stop at 4.06 mm, the
    stop clipped the aimed beam at pupil radius 0.985 and its |OTF| left optiland's by up to
    0.019 (0.0025 on axis).
    A file with another aperture keeps RAIM 2's "real_marginal"."""
    lens = _lens("triplet_floa_raim2")
    assert lens.aim == "real"
    r = REF["cases"]["triplet_floa_raim2"]
    assert r["stop_radius"] == pytest.approx(4.0, abs=1e-12)
    assert float(sampling.stop_radius(lens, "paraxial")) == pytest.approx(4.0, abs=1e-9)
    real = float(sampling.stop_radius(lens, "real"))
    assert real - 4.0 > 0.05  # the real marginal ray's stop: another beam
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert jl.load(str(ROOT / REF["cases"]["dgauss_real"]["file"])).aim == "real_marginal"


def test_reference_cases_tell_the_stop_sizes_apart():
    """The references distinguish the rules the test above holds: Laikin's stop sized by the
    real and by the paraxial marginal ray differs (1.8 %), and so does the triplet's for its
    400 mm object and for infinity (0.15 %), far beyond the tolerances."""
    c = REF["cases"]
    assert c["laikin_real_marginal"]["stop_radius"] / c["laikin_real"]["stop_radius"] > 1.01
    fin, inf = c["triplet_finite_real_marginal"], c["triplet_real_marginal"]
    assert inf["stop_radius"] - fin["stop_radius"] > 1e-3
    rim = np.array(fin["fields"][0]["rays"]["stop"][1])
    assert abs(rim[1] - fin["stop_radius"]) < 1e-9  # the marginal ray fills that stop


# --------------------------------------------------------------------------------------
# render.footprints: the beam render traces
# --------------------------------------------------------------------------------------
def _marginal_focus_lens():
    """The 400 mm triplet with its image plane where optiland's aimed marginal ray (0, 1) of
    the axial point crosses the axis, and that ray's image-space direction."""
    name = "triplet_finite_real_marginal"
    f0 = REF["cases"][name]["fields"][0]["rays"]
    (_, y), (_, m, n) = f0["image"][1], f0["image_direction"][1]
    lens = _lens(name)
    dz = -y * n / m  # from the image surface to the axis crossing
    lens = dataclasses.replace(lens, thickness=lens.thickness.at[-1].add(dz),
                               sensor=jl.Sensor((5, 5), 0.01))
    return lens, abs(m), REF["cases"][name]["primary_um"]


def test_footprint_is_the_aimed_beam_of_the_lens_object():
    """Seen from the marginal focus on the axis, the aimed beam's edge is the marginal ray:
    the footprint's radius in (L, M) is its direction cosine |M| (the footprint reports the
    bisected boundary radius r as 1.001·r + 1e-6, its margin). Before, footprints sized the
    stop for an object at infinity (4.0686 mm, against 4.0624 mm for the lens's 400 mm
    object): a footprint 1.5e-4 too wide, rays spent beyond the beam that render traces."""
    lens, m, wl = _marginal_focus_lens()
    fp = render.footprints(lens, wavelengths=[wl], grid=3)
    r = (float(fp.radius[1, 1]) - 1e-6) / 1.001
    assert abs(r - m) <= 2e-7, (r, m)
    np.testing.assert_allclose(np.asarray(fp.center[1, 1]), 0.0, atol=1e-9)
    # The object at infinity is another beam: the stop sized by the ray parallel to the axis.
    far = render.footprints(lens, wavelengths=[wl], grid=3, depth=math.inf)
    assert float(far.radius[1, 1]) - float(fp.radius[1, 1]) > 1e-4


def test_render_traces_the_footprints_of_its_depth(monkeypatch):
    """render's RayRender computes its footprints for the depth it renders (its own beam):
    the footprints it traces with are footprints(lens, depth=...) of that depth."""
    lens, _, wl = _marginal_focus_lens()
    seen = {}

    def capture(lens_, scene, key, depth, wls, pixel_size, footprints, **kw):
        seen["fp"] = footprints
        return jnp.zeros((5, 5, 1))

    monkeypatch.setattr(render, "_render_ray", capture)
    scene = jnp.ones((5, 5, 1))
    for depth in (None, 250.0):
        render.render(lens, scene, spp=1, key=jax.random.PRNGKey(0), wavelengths=[wl],
                      depth=depth, method=render.RayRender(footprint_grid=3))
        want = render.footprints(lens, wavelengths=[wl], grid=3, depth=depth)
        np.testing.assert_allclose(np.asarray(seen["fp"].radius), np.asarray(want.radius),
                                   rtol=0, atol=1e-12)
    # and the two depths' beams differ
    own = render.footprints(lens, wavelengths=[wl], grid=3)
    assert abs(float(own.radius[1, 1]) - float(seen["fp"].radius[1, 1])) > 1e-5


def test_footprint_bound_is_in_pupil_rule():
    """One aperture rule: an aimed lens's footprints are bounded at the stop radius the aim
    fills (``beam_bounded``), a paraxially aimed one's by the EPD's disc on the entrance
    pupil's plane (``in_entrance_pupil``); ``in_entrance_pupil`` passes every ray of an aimed
    lens, and beam_bounded leaves a paraxial lens as it is."""
    lens, _, _ = _marginal_focus_lens()
    depth = sampling.lens_depth(lens, None, "test")
    bounded = radiometry.beam_bounded(lens, depth)
    r_aim = float(sampling.stop_radius(lens, "real", object_z=-depth))
    assert float(bounded.surfaces[lens.stop].semi_diameter) == pytest.approx(r_aim, abs=1e-12)
    par = dataclasses.replace(lens, aim="paraxial")
    assert radiometry.beam_bounded(par, depth) is par
    rays = Rays(jnp.array([[0.0, 100.0, 0.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.55)
    assert bool(radiometry.in_entrance_pupil(lens, rays)[0])
    assert not bool(radiometry.in_entrance_pupil(par, rays)[0])


# --------------------------------------------------------------------------------------
# paraxial_chief_ray: an entrance pupil at infinity
# --------------------------------------------------------------------------------------
def _pupil_at_infinity(gap_offset=0.0):
    """A singlet (N-BK7, R1 = 50 mm, flat back, 5 mm thick), a stop in its back focal plane
    (so the entrance pupil, the stop's image through the singlet, lies at infinity), then a
    biconvex singlet: object-space telecentric by its geometry, with angle fields."""
    bk7 = jl.get_material("N-BK7")
    n = float(bk7.index(0.5875618))
    bfd = 50.0 / (n - 1.0) - 5.0 / n  # the singlet's back focal distance (thin plate after)
    return jl.Lens(
        surfaces=(jl.Sphere(1 / 50.0), jl.Sphere(0.0), jl.Sphere(0.0), jl.Sphere(1 / 60.0),
                  jl.Sphere(-1 / 60.0)),
        thickness=jnp.array([5.0, bfd + gap_offset, 30.0, 5.0, 40.0]),
        materials=(bk7, jl.Air(), jl.Air(), bk7, jl.Air()),
        stop=2, epd=4.0, fields=jnp.array([0.0, 2.0]), wavelengths=jnp.array([0.5875618]))


def test_chief_ray_on_axis_with_pupil_at_infinity_is_the_axis():
    lens = _pupil_at_infinity()
    assert not np.isfinite(float(paraxial.entrance_pupil_z(lens)))
    y, nu = paraxial.paraxial_chief_ray(lens, 0.0)
    np.testing.assert_array_equal(np.asarray(y), 0.0)  # was NaN everywhere
    np.testing.assert_array_equal(np.asarray(nu), 0.0)


def test_chief_ray_off_axis_with_pupil_at_infinity_is_refused():
    """No ray of a nonzero field angle reaches the stop's centre (every ray of the beam
    crosses the stop at f₁·tanθ): a clear error, for the callers too (image_height, and so
    image_scale and render's mapping; seidel), where they gave NaN."""
    lens = _pupil_at_infinity()
    for call in (lambda: paraxial.paraxial_chief_ray(lens, 2.0),
                 lambda: paraxial.image_height(lens, 2.0),
                 lambda: jl.analysis.seidel(lens, field=2.0)):
        with pytest.raises(Exception, match="entrance pupil lies at infinity"):
            call()


def test_chief_ray_near_pupil_at_infinity_is_finite_and_linear():
    """Just off the focal plane (the pupil far but finite) the chief ray is finite, and the
    form −z_EP·u is unchanged: height at surface 1 −z_EP·tanθ, linear in tanθ."""
    lens = _pupil_at_infinity(gap_offset=0.5)
    zep = float(paraxial.entrance_pupil_z(lens))
    assert np.isfinite(zep) and abs(zep) > 1e3
    y, nu = paraxial.paraxial_chief_ray(lens, 2.0)
    t = math.tan(math.radians(2.0))
    assert float(y[0]) == pytest.approx(-zep * t, rel=1e-12)
    assert np.all(np.isfinite(np.asarray(y))) and np.all(np.isfinite(np.asarray(nu)))
    # the chief ray crosses the stop at its centre
    assert abs(float(y[lens.stop])) <= 1e-9 * abs(float(y[0]))


def test_rays_through_a_pupil_at_infinity_are_refused_by_name():
    """The samplers launch rays on the entrance pupil's plane: at infinity that was an
    origin of inf, refused by ``Rays`` without saying why (field 0 included); now each
    sampler names the pupil at infinity. Its pupil's position stays available."""
    lens = _pupil_at_infinity()
    for where, call in (
            ("collimated", lambda: sampling.field_rays(lens, 0.0, jnp.zeros((1, 2)))),
            ("object_point", lambda: sampling.field_rays(lens, 0.0, jnp.zeros((1, 2)),
                                                         depth=500.0)),
            ("point_source", lambda: sampling.point_source(lens, jnp.array([0.0, 0.0, -500.0]),
                                                           jnp.zeros((1, 2))))):
        with pytest.raises(ValueError, match=f"{where}: the lens's entrance pupil lies at "
                                             f"infinity"):
            call()
    assert not np.isfinite(float(paraxial.entrance_pupil_z(lens)))
    # Round 46a: its EPD sets no marginal ray (the axis), so paraxial_data refuses it by name.
    with pytest.raises(ValueError, match="^paraxial_data: .*entrance pupil lies at infinity"):
        jl.paraxial_data(lens)
