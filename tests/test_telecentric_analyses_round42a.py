"""Round 42a: distortion, field curvature, Seidel sums and relative illumination of
object-space telecentric lenses (``Lens(object_na=...)``: fields are object heights in mm,
every chief ray leaves its object point parallel to the axis).

Before, all four refused such a lens (``paraxial.finite_pupil``: "needs an entrance pupil at
a finite distance"). Reference numbers: tools/tele42a_reference.py (optiland 0.6.3) writes
tests/data/tele42a/*.json for three lenses (a doublet + singlet with its stop at the exact
focus of the front group and its image surface 1.5 mm before the paraxial image; the same
in immersion, its object in N-BK7 at NA 0.12; a triplet at m ≈ −0.67 with 9 % distortion).
Tolerances, against optiland: the paraxial magnification to 1e-13 relative, real chief-ray
heights to 1e-11 mm, distortion to 1e-9 %, foci to 2e-9 mm (optiland's rays, extrapolated
parabasal pairs; 1e-8 mm against its own ``FieldCurvature`` analysis, a ±1e-5 pupil pair),
Seidel terms per surface to 1e-13 mm, relative illumination of the unvignetted lenses to
1e-4 (jaxlens's 64-cell pupil grid). Closed forms: an ideal telecentric relay (two paraxial
lenses, the stop at their common focus) has m = −f2/f1, no distortion, flat foci and a
uniform illumination, or, with its first lens's rim clipping the cones, the share of each
cone that passes it (to 5e-4, the pupil grid's); a plane plate before the object's cone
adds S_I = −t u⁴(n² − 1)/n³ and nothing else (the chief ray parallel to the axis meets both
faces at normal incidence).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import aberrations, spots, third_order
from jaxlens.imaging import radiometry
from jaxlens.optics import paraxial
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.optics.surfaces import Standard, Stop

DATA = pathlib.Path(__file__).parent / "data" / "tele42a"
NAMES = ("tele_doublet_exact", "tele_immersion", "tele_triplet_far")


def _ref(name):
    return json.loads((DATA / f"{name}.json").read_text())


@pytest.fixture(scope="module", params=NAMES)
def case(request):
    return jl.load(DATA / f"{request.param}.zmx", strict=True), _ref(request.param)


def test_the_files_are_the_reference_lenses(case):
    lens, ref = case
    assert lens.telecentric_object
    np.testing.assert_allclose(float(lens.object_na), ref["object_na"], rtol=1e-15)
    np.testing.assert_allclose(float(lens.object_material.index(lens.primary_wavelength)),
                               ref["object_index"], rtol=1e-9)
    np.testing.assert_allclose(float(paraxial.object_slope(lens)), ref["tan_u"], rtol=1e-9)


def test_distortion_matches_optiland(case):
    lens, ref = case
    rows = ref["distortion"]
    h = np.array([r["height"] for r in rows])
    d = spots.distortion(lens, h)
    m = float(paraxial.magnification(lens))
    np.testing.assert_allclose(m, ref["paraxial_magnification"], rtol=1e-13)
    np.testing.assert_allclose(np.asarray(d.field), h, rtol=0, atol=0)
    np.testing.assert_allclose(d.chief_height, [r["chief_height"] for r in rows], rtol=0,
                               atol=1e-11)
    np.testing.assert_allclose(d.f_tan, [r["ideal"] for r in rows], rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(d.paraxial_height, [r["paraxial_height"] for r in rows],
                               rtol=0, atol=1e-11)
    np.testing.assert_allclose(d.percent_ftan, [r["percent_ftan"] for r in rows], rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(d.percent_paraxial, [r["percent_paraxial"] for r in rows],
                               rtol=0, atol=1e-9)
    assert np.all(np.isnan(np.asarray(d.f_theta)))  # no field angle, no f-θ reference
    assert np.all(np.isnan(np.asarray(d.percent_ftheta)))


def test_distortion_of_the_lens_fields_and_of_y_heights():
    """The default fields are the lens's object heights; an [F] field is y, and (x, y) is
    measured along its own direction (the same as the y height of its length)."""
    lens, ref = jl.load(DATA / "tele_doublet_exact.zmx"), _ref("tele_doublet_exact")
    d = spots.distortion(lens)
    want = {tuple(r["height"]): r["percent_ftan"] for r in ref["distortion"]}
    got = [want[tuple(map(float, f))] for f in np.asarray(lens.fields).reshape(-1, 2)] \
        if np.ndim(lens.fields) == 2 else [want[(0.0, float(f))] for f in lens.fields]
    np.testing.assert_allclose(d.percent_ftan, got, atol=1e-9)
    y = spots.distortion(lens, jnp.array([0.0, 5.0, -5.0]))
    np.testing.assert_allclose(y.percent_ftan[1], want[(3.0, -4.0)], atol=1e-9)
    np.testing.assert_allclose(y.percent_ftan[2], y.percent_ftan[1], atol=1e-12)
    np.testing.assert_allclose(y.chief_height[2], -y.chief_height[1], atol=1e-12)


def test_field_curvature_matches_optiland(case):
    lens, ref = case
    fc_ref = ref["field_curvature"]
    h = np.array(fc_ref["heights"])
    fc = aberrations.field_curvature(lens, h, jnp.array(fc_ref["wavelengths"]))
    np.testing.assert_allclose(fc.tangential, fc_ref["tangential"], rtol=0, atol=2e-9)
    np.testing.assert_allclose(fc.sagittal, fc_ref["sagittal"], rtol=0, atol=2e-9)
    own = ref["field_curvature_optiland_analysis"]  # optiland's FieldCurvature, as it is
    fy = aberrations.field_curvature(lens, np.array(own["heights"])[:, 1], own["wavelength"])
    np.testing.assert_allclose(fy.tangential[0], own["tangential"], rtol=0, atol=1e-8)
    np.testing.assert_allclose(fy.sagittal[0], own["sagittal"], rtol=0, atol=1e-8)


def test_field_curvature_defaults_to_heights_up_to_the_largest():
    lens = jl.load(DATA / "tele_triplet_far.zmx")
    fc = aberrations.field_curvature(lens, wavelengths=lens.primary_wavelength)
    np.testing.assert_allclose(fc.fields, np.linspace(0.0, 10.0, 11), atol=1e-12)
    ref = _ref("tele_triplet_far")["field_curvature"]
    np.testing.assert_allclose(fc.tangential[0, [0, 5, 10]],
                               np.array(ref["tangential"][1])[[0, 1, 2]], atol=2e-9)


def _as_optiland(s):
    t = np.asarray(s.transverse(per_surface=True))
    return {"TSC": t[0], "CC": t[1], "TAC": t[3] / 2, "TPC": t[4], "DC": t[7],
            "TAchC": t[8], "TchC": t[9]}


def test_seidel_matches_optiland(case):
    lens, ref = case
    s = third_order.seidel(lens)
    sref = ref["seidel"]
    assert float(s.field) == sref["field"]  # the largest object height (mm)
    rays = [sref["telecentric_rays"]] + ([sref["own_rays"]] if "own_rays" in sref else [])
    for r in rays:
        for key, ours in _as_optiland(s).items():
            np.testing.assert_allclose(ours, r["transverse"][key], rtol=0, atol=1e-13,
                                       err_msg=key)
        # optiland's seidels() are these sums with the opposite sign.
        np.testing.assert_allclose(-np.asarray(s.sums[:5]), r["seidels"], rtol=0, atol=1e-14)
    np.testing.assert_allclose(float(s.image_nu), sref["image_u"], rtol=1e-13)
    # H = n u h at the object: the chief ray parallel to the axis at the largest height
    n0 = float(lens.object_material.index(lens.primary_wavelength))
    np.testing.assert_allclose(float(s.lagrange), n0 * ref["tan_u"] * sref["field"],
                               rtol=1e-12)


def test_seidel_of_a_plate_in_the_objects_cone_is_the_closed_form():
    """A cover plate (t = 3 mm of N-BK7) before the telecentric doublet: its two faces give
    S_I = −t u⁴ (n² − 1)/n³ and no S_II … S_V (Ā = n(ȳ c + ū) = 0 on both faces)."""
    lens = jl.load(DATA / "tele_doublet_exact.zmx")
    glass = lens.materials[4]  # N-BK7 after surface 5
    n = float(glass.index(lens.primary_wavelength))
    assert n == pytest.approx(1.5168, abs=1e-4)
    t, gap = 3.0, 10.0
    plate = dataclasses.replace(
        lens, surfaces=(Standard(c=0.0), Standard(c=0.0)) + lens.surfaces,
        thickness=jnp.concatenate([jnp.array([t, gap]), lens.thickness]),
        materials=(glass, jl.Air()) + lens.materials, stop=lens.stop + 2,
        object_distance=lens.object_distance - t - gap)
    s = third_order.seidel(plate)
    u = float(paraxial.object_slope(lens))
    per = np.asarray(s.per_surface)
    np.testing.assert_allclose(per[0, :2].sum(), -t * u**4 * (n * n - 1) / n**3, rtol=1e-12)
    np.testing.assert_allclose(per[1:5, :2], 0.0, atol=1e-16)


def _open(lens):
    """The lens without semi-diameters: every ray of the NA cone passes."""
    return eqx.tree_at(lambda m: [s.semi_diameter for s in m.surfaces], lens,
                       [jnp.inf for _ in lens.surfaces])


@pytest.mark.parametrize("name", NAMES)
def test_relative_illumination_of_the_open_lens_matches_optiland(name):
    ref = _ref(name)["ri_open"]
    lens = _open(jl.load(DATA / f"{name}.zmx"))
    ri = radiometry.relative_illumination(lens, np.array(ref["heights"]), pupil=64)
    np.testing.assert_allclose(ri.ri, ref["ri"], rtol=0, atol=1e-4)
    np.testing.assert_allclose(ri.field, ref["heights"], atol=0)


def _relay(f1=50.0, f2=25.0, na=0.05, rim=jnp.inf):
    """An ideal object-space (and image-space) telecentric relay: two paraxial lenses f1,
    f2 with the stop at their common focus, the object at the front focus."""
    air = jl.Air()
    return jl.Lens(surfaces=(ParaxialSurface(focal_length=f1, semi_diameter=rim), Stop(),
                             ParaxialSurface(focal_length=f2)),
                   thickness=jnp.array([f1, f2, f2]), materials=(air, air, air), stop=1,
                   object_distance=f1, object_na=na, fields=(0.0, 3.0, 6.0))


def test_an_ideal_relay_has_no_distortion_flat_foci_and_uniform_illumination():
    lens = _relay()
    np.testing.assert_allclose(float(paraxial.magnification(lens)), -0.5, rtol=1e-15)
    d = spots.distortion(lens)
    np.testing.assert_allclose(d.chief_height, [0.0, -1.5, -3.0], atol=1e-13)
    np.testing.assert_allclose(d.percent_ftan, 0.0, atol=1e-10)
    np.testing.assert_allclose(d.percent_paraxial, 0.0, atol=1e-10)
    fc = aberrations.field_curvature(lens, jnp.array([[0.0, 0.0], [0.0, 6.0], [4.0, 3.0]]))
    np.testing.assert_allclose(fc.tangential, 0.0, atol=1e-9)
    np.testing.assert_allclose(fc.sagittal, 0.0, atol=1e-9)
    ri = radiometry.relative_illumination(lens, jnp.array([0.0, 3.0, 6.0]), pupil=32)
    np.testing.assert_allclose(ri.ri, 1.0, atol=1e-9)  # no cos⁴ falloff: parallel chief rays
    np.testing.assert_allclose(ri.image_xy[:, 1], [0.0, -1.5, -3.0], atol=1e-9)


def test_an_ideal_relay_vignetted_by_its_first_lens_passes_the_cones_share():
    """The first lens (rim R) meets the ray of slope s from height h at h + f1·s: the cone
    |s| <= tan u keeps the slopes within R/f1 of −h/f1. Its projected solid angle is the
    integral of cos⁴γ = 1/(1 + |s|²)² over that lens-shaped region (numpy quadrature); the
    image scale is the same everywhere, so the relative illumination is its ratio to the
    axis's."""
    f1, na, rim = 50.0, 0.05, 3.5
    lens = _relay(f1=f1, na=na, rim=rim)
    heights = np.array([0.0, 1.5, 2.5])
    ri = radiometry.relative_illumination(lens, heights, pupil=64)
    tu = na / np.sqrt(1 - na * na)
    g = np.linspace(-tu, tu, 2001)
    sx, sy = np.meshgrid(g, g)
    cone = sx**2 + sy**2 <= tu * tu
    w = 1.0 / (1.0 + sx**2 + sy**2) ** 2

    def omega(h):
        return np.sum(w * (cone & (sx**2 + (sy + h / f1) ** 2 <= (rim / f1) ** 2)))

    want = [omega(h) / omega(0.0) for h in heights]
    assert want[-1] < 0.8  # the test lens is vignetted
    np.testing.assert_allclose(ri.ri, want, rtol=5e-4)  # 64 cells: 1e-4 measured


@pytest.mark.parametrize("call", [
    lambda lens: paraxial.entrance_pupil_z(lens),
    lambda lens: jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(3)),
], ids=["entrance_pupil_z", "collimated"])  # render and image_scale take it since round 43a
def test_angle_only_tools_still_refuse_with_what_to_use(call):
    lens = jl.load(DATA / "tele_doublet_exact.zmx")
    with pytest.raises(ValueError, match=r"object-space telecentric.*paraxial\.magnification"):
        call(lens)


def test_heights_are_checked_before_tracing():
    lens = jl.load(DATA / "tele_doublet_exact.zmx")
    with pytest.raises(ValueError, match="mm"):
        spots.distortion(lens, jnp.array([0.0, jnp.nan]))
    with pytest.raises(ValueError, match=r"one object height y in mm"):
        third_order.seidel(lens, field=jnp.array([0.0, 3.0]))
    with pytest.raises(ValueError, match="mm"):
        aberrations.field_curvature(lens, jnp.array([0.0, jnp.inf]))
    with pytest.raises(ValueError, match=r"object heights \(mm\)"):
        radiometry.relative_illumination(lens, jnp.zeros((2, 3)))


def test_report_of_a_telecentric_lens_gives_the_analyses_numbers():
    """The report (before: refused) gives each object height's chief ray, distortion against
    m·h, foci and the Seidel sums at the largest height: optiland's numbers."""
    from jaxlens.analysis import report

    lens, ref = jl.load(DATA / "tele_doublet_exact.zmx"), _ref("tele_doublet_exact")
    data = report.report_data(lens)
    json.dumps(data, allow_nan=False)  # the CLI's --json
    assert data["object_space_telecentric"] and data["units"]["object_height"] == "mm"
    np.testing.assert_allclose(data["magnification"], ref["paraxial_magnification"],
                               rtol=1e-13)
    want = {tuple(r["height"]): r for r in ref["distortion"]}
    fc = ref["field_curvature"]
    k = {tuple(h): i for i, h in enumerate(fc["heights"])}
    for f in data["fields"]:
        h = (0.0, f["height"]) if np.ndim(f["height"]) == 0 else tuple(f["height"])
        np.testing.assert_allclose(f["distortion"], want[h]["percent_ftan"], atol=1e-9)
        np.testing.assert_allclose(f["ideal_image_height"], want[h]["ideal"], atol=1e-13)
        np.testing.assert_allclose(f["focus_tangential"], fc["tangential"][1][k[h]], atol=2e-9)
        np.testing.assert_allclose(f["focus_sagittal"], fc["sagittal"][1][k[h]], atol=2e-9)
    sd = data["seidel"]
    assert sd["field"] == 8.0
    np.testing.assert_allclose(-np.array(list(sd["sums"].values())[:5]),
                               ref["seidel"]["telecentric_rays"]["seidels"], atol=1e-14)
    text = report.format_report(data, lens)
    assert "object height 8.0000 mm" in text and "Dist m*h" in text
    assert "Entrance pupil" not in text and "field of view" not in text
    other = report.with_fields_and_wavelengths(lens, [[0.0, 2.0], [3.0, -4.0]])
    np.testing.assert_allclose(np.asarray(other.fields), [[0.0, 2.0], [3.0, -4.0]])
    with pytest.raises(ValueError, match=r"--fields.*mm"):
        report.with_fields_and_wavelengths(lens, [0.0, np.inf])


def test_magnification_of_finite_and_infinite_conjugates():
    """``paraxial.magnification`` is n u/(n′ u′) for any finite object: an ideal f = 50 mm
    lens images 75 mm in front of it at 150 mm behind, m = −2; in water (n = 1.333) the
    same holds at a reduced distance 75·1.333 mm; an object at infinity gives 0."""
    air = jl.Air()

    def ideal(d, medium=air):
        return jl.Lens(surfaces=(Stop(), ParaxialSurface(focal_length=50.0)),
                       thickness=jnp.array([0.0, 150.0]), materials=(air, air), stop=0,
                       epd=10.0, object_distance=d, object_material=medium)

    np.testing.assert_allclose(float(paraxial.magnification(ideal(75.0))), -2.0, rtol=1e-14)
    water = jl.ModelGlass(nd=1.333, vd=55.0)  # nd at the lens's d-line wavelength
    np.testing.assert_allclose(float(paraxial.magnification(ideal(75.0 * 1.333, water))),
                               -2.0, rtol=1e-14)
    assert float(paraxial.magnification(ideal(None))) == 0.0


def test_plots_label_object_heights():
    """The field-curvature/distortion figure and the Seidel diagram (the report's --plot) now
    draw a telecentric lens, labelled in object heights (mm), not degrees."""
    import matplotlib

    matplotlib.use("Agg")
    from jaxlens import plot

    lens = jl.load(DATA / "tele_triplet_far.zmx")
    fig = plot.plot_field_curvature(lens, wavelengths=lens.primary_wavelength)
    assert fig.axes[0].get_ylabel() == "object height y (mm)"
    assert fig.axes[1].get_legend().get_texts()[0].get_text() == "against m·h"
    assert "object height 10.00 mm" in plot.plot_seidel(lens).axes[0].get_title()
