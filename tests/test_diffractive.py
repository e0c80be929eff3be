"""Zemax's Binary 2 diffractive surface (``Binary2``, ``TYPE BINARY_2``).

Checked against the scalar grating equation on a flat element (computed by hand in numpy),
the thin-lens focal length of a quadratic phase (paraxially and with real rays), the ideal
focusing phase (spot and optical path at the focus, bounded by the polynomial fit's own
error), finite differences, and the ``.zmx`` reader and writer against each other and the
file's text.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.analysis.tolerance import ToleranceModel
from jaxlens.design.params import Parameterization
from jaxlens.io import lensfile, zmx
from jaxlens.optics.rebase import rebase_conic
from jaxlens.tracing import backward, forward, surface_adjoint

LAM = 0.55  # µm
R = 5.0  # normalisation radius, mm


def flat_doe(phase, order=1.0, after=None, wl=LAM, gap=10.0):
    """A flat Binary 2 in air at z = 0 (glass after it if ``after``), image ``gap`` behind."""
    s = jl.Binary2(order=order, norm_radius=R, phase_coeffs=jnp.asarray(phase))
    return jl.Lens((s,), jnp.array([gap]), (after or jl.Air(),), epd=2.0,
                   wavelengths=jnp.array([wl]))


def meridional_rays(y, sin_t, wl=LAM):
    """Rays in the y–z plane through (0, y, 0) at angle asin(sin_t) to the axis."""
    y, s = np.broadcast_arrays(np.asarray(y, float), np.asarray(sin_t, float))
    d = np.stack([0 * s, s, np.sqrt(1 - s * s)], -1)
    o = np.stack([0 * y, y, 0 * y], -1) - d  # one unit before the surface
    return jl.Rays(jnp.asarray(o), jnp.asarray(d), wl)


# ---------------------------------------------------------------------------- single rays
def test_flat_element_obeys_the_scalar_grating_equation():
    """n′ sin θ′ = n sin θ + (λ/2π) dΦ/dr for rays in a radial plane, into air and into
    glass; a ray whose order would need |sin θ′| > 1 is lost."""
    a = np.array([-300.0, 40.0, -7.0])  # Φ = M Σ A_i ρ^{2i}
    y = np.array([0.0, 0.7, -1.9, 3.3, 4.6, 2.0])
    sin_t = np.array([0.0, 0.1, -0.3, 0.2, -0.05, 0.9])
    for order, after in ((1.0, None), (2.0, None), (1.0, jl.ModelGlass(1.6, 40.0))):
        lens = flat_doe(a, order, after)
        out = jl.trace(lens, meridional_rays(y, sin_t), upto=0)
        rho2 = (y / R) ** 2
        dphi = order * 2 * y / R**2 * (a[0] + 2 * a[1] * rho2 + 3 * a[2] * rho2**2)
        n2 = float(lens.indices(LAM)[1])
        expect = (sin_t + LAM * 1e-3 / (2 * np.pi) * dphi) / n2
        assert np.all(np.abs(expect) < 1) and bool(jnp.all(out.valid))
        np.testing.assert_allclose(np.asarray(out.direction[:, 1]), expect, rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.asarray(out.direction[:, 0]), 0.0, atol=1e-16)
        np.testing.assert_allclose(np.linalg.norm(np.asarray(out.direction), axis=-1), 1.0,
                                   rtol=1e-15)
        assert bool(jnp.all(out.direction[:, 2] > 0))
    # A strong phase: the order goes evanescent at the rim and for the steep ray.
    lens = flat_doe([-40000.0], 1.0)
    y = np.array([1.0, 4.9, 1.0, 1.0])
    sin_t = np.array([0.0, 0.0, -0.95, 0.95])
    s_out = sin_t + LAM * 1e-3 / (2 * np.pi) * 2 * y / R**2 * -40000.0
    out = jl.trace(lens, meridional_rays(y, sin_t), upto=0)
    assert (np.abs(s_out) > 1).tolist() == [False, True, True, False]
    assert np.asarray(out.valid).tolist() == [True, False, False, True]
    ok = np.asarray(out.valid)
    np.testing.assert_allclose(np.asarray(out.direction[ok, 1]), s_out[ok], atol=1e-14)
    assert np.all(np.isfinite(np.asarray(out.direction)))


def test_skew_ray_kick_is_radial_and_tangent_on_a_curved_base():
    """On a sphere the tangential part of n′d′ − n·d is the projection of (λ/2π)∇Φ onto the
    tangent plane (the normal part is free): checked by hand for a skew ray into glass."""
    a = np.array([-250.0, 30.0])
    s = jl.Binary2(c=0.04, norm_radius=R, phase_coeffs=jnp.asarray(a))
    glass = jl.ModelGlass(1.5, 60.0)
    lens = jl.Lens((s,), jnp.array([10.0]), (glass,), epd=2.0)
    d0 = np.array([0.12, -0.2, 0.0])
    d0[2] = math.sqrt(1 - d0 @ d0)
    o = np.array([1.1, 2.3, -1.0])
    out = jl.trace(lens, jl.Rays(jnp.asarray(o[None]), jnp.asarray(d0[None]), LAM), upto=0)
    p = np.asarray(out.origin[0])
    x, y = p[0], p[1]
    c = 0.04
    normal = np.array([-c * x, -c * y, 1 - c * p[2]])
    normal /= np.linalg.norm(normal)
    rho2 = (x * x + y * y) / R**2
    g = 2 / R**2 * (a[0] + 2 * a[1] * rho2) * np.array([x, y, 0.0]) * LAM * 1e-3 / (2 * np.pi)
    n2 = float(glass.index(LAM))
    jump = n2 * np.asarray(out.direction[0]) - d0 - g
    np.testing.assert_allclose(jump - (jump @ normal) * normal, 0.0, atol=1e-15)
    assert abs(float(jnp.linalg.norm(out.direction[0])) - 1) < 1e-15


# ---------------------------------------------------------------------------- thin lens
@pytest.mark.parametrize("order", [1.0, 2.0])
def test_quadratic_phase_is_a_thin_lens_at_every_wavelength(order):
    """Paraxial EFL = −πR²/(MλA_1) at each wavelength (1/λ dispersion), and real collimated
    rays cross the axis at f·sqrt(1 − (h/f)²): that is exact for a quadratic phase, and
    tends to the paraxial EFL as h → 0."""
    a1 = -120.0
    wls = np.array([0.45, 0.55, 0.65])
    lens = eqx.tree_at(lambda m: m.wavelengths, flat_doe([a1], order), jnp.asarray(wls))
    h = np.array([1e-3, 0.01, 0.5, 2.0, 4.0])
    for wl in wls:
        f = -math.pi * R**2 / (order * wl * 1e-3 * a1)
        assert float(jl.efl(lens, wl)) == pytest.approx(f, rel=1e-13)
        assert float(jl.bfl(lens, wl)) == pytest.approx(f, rel=1e-13)
        out = jl.trace(lens, meridional_rays(h, 0.0, wl), upto=0)
        d = np.asarray(out.direction)
        z_cross = -h * d[:, 2] / d[:, 1]
        np.testing.assert_allclose(z_cross, f * np.sqrt(1 - (h / f) ** 2), rtol=1e-12)
        assert abs(z_cross[0] / f - 1) < 1e-9
    # Dispersion of a diffractive lens: f·λ is constant.
    fs = [float(jl.efl(lens, w)) for w in wls]
    np.testing.assert_allclose(np.array(fs) * wls, fs[0] * wls[0], rtol=1e-13)


def test_diffractive_power_adds_to_the_base_surface():
    """On a curved glass surface the paraxial power is c(n′ − n) − MλA_1/(πR²)."""
    glass = jl.ModelGlass(1.5168, 64.17)
    s = jl.Binary2(c=0.02, coeffs=jnp.array([1e-4]), order=1.0, norm_radius=R,
                   phase_coeffs=jnp.array([-80.0]))
    lens = jl.Lens((jl.Plane(), s), jnp.array([3.0, 50.0]), (glass, jl.Air()), epd=4.0)
    n = float(glass.index(LAM))
    p_surface = (0.02 + 2e-4) * (1 - n) - LAM * 1e-3 * -80.0 / (math.pi * R**2)
    assert float(jl.efl(lens, LAM)) == pytest.approx(1 / p_surface, rel=1e-13)
    assert float(jl.paraxial_data(lens, LAM).efl) == pytest.approx(1 / p_surface, rel=1e-13)


# ---------------------------------------------------------------------------- ideal focus
F = 50.0


def ideal_fit(n_terms):
    """A_i (least squares in ρ²) of the phase −(2π/λ)(sqrt(r² + F²) − F) over r ≤ R, and the
    fit's worst error in the phase (rad) and in its slope dΦ/dr (rad/mm)."""
    k = 2 * np.pi / (LAM * 1e-3)
    r = np.linspace(0.0, R, 4001)
    u = (r / R) ** 2
    target = -k * (np.sqrt(r * r + F * F) - F)
    basis = u[:, None] ** np.arange(1, n_terms + 1)
    a = np.linalg.lstsq(basis, target, rcond=None)[0]
    i = np.arange(1, n_terms + 1)
    slope_fit = (2 * r / R**2)[:, None] * (i * a * u[:, None] ** (i - 1))
    slope = -k * r / np.sqrt(r * r + F * F)
    return a, np.max(np.abs(basis @ a - target)), np.max(np.abs(slope_fit.sum(1) - slope))


@pytest.fixture(scope="module")
def focus():
    """On-axis rays through the ideal-focus DOE, traced to the plane z = F."""
    a, phase_err, slope_err = ideal_fit(4)
    lens = flat_doe(a, gap=F)
    h = np.linspace(-R, R, 41) * 0.999
    return lens, a, phase_err, slope_err, jl.trace(lens, meridional_rays(h, 0.0))


def test_ideal_phase_focuses_to_the_fit_error(focus):
    """The transverse miss at the focus is at most F·(λ/2π)·max|ΔΦ′|/cos³θ (the fit's slope
    error); it is far below the Airy radius, where the quadratic term alone misses by more."""
    lens, a, _, slope_err, out = focus
    assert bool(jnp.all(out.valid))
    cos_max = F / math.hypot(R, F)
    bound = F * LAM * 1e-3 / (2 * np.pi) * slope_err / cos_max**3
    spot = float(jnp.max(jnp.abs(out.origin[:, 1])))
    airy = 1.22 * LAM * 1e-3 * F / (2 * R)
    assert spot <= bound + 1e-12 and bound < 1e-3 * airy
    quadratic = jl.trace(flat_doe(a[:1], gap=F), meridional_rays([0.999 * R], 0.0))
    assert abs(float(quadratic.origin[0, 1])) > 5 * airy


def test_optical_path_adds_the_phase(focus):
    """Every ray of the ideal focusing DOE has the same optical path to the focus (0, 0, F),
    to the fit's phase error; without the (λ/2π)Φ term the spread would be
    sqrt(R² + F²) − F ≈ 0.25 mm. The path to the focus is the path to the plane z = F less
    d·(P − focus) (∇S = n·d, n = 1), exact to second order in the tiny miss P − focus."""
    _, _, phase_err, _, out = focus
    p = np.asarray(out.origin) - np.array([0.0, 0.0, F])
    opl = np.asarray(out.opl) - np.sum(np.asarray(out.direction) * p, -1)
    spread = opl.max() - opl.min()
    assert spread <= 2 * LAM * 1e-3 / (2 * np.pi) * phase_err + 1e-13
    geometric = np.hypot(np.linspace(-R, R, 41) * 0.999, F)
    assert np.ptp(geometric) > 0.2  # the path the phase makes up for


# ---------------------------------------------------------------------------- gradients
def test_gradients_match_central_differences():
    """d(spot loss)/dA_i and d/dc of the diffractive surface's base, against central
    differences (float64)."""
    glass = jl.ModelGlass(1.5168, 64.17)
    s = jl.Binary2(c=-0.01, coeffs=jnp.array([2e-5]), norm_radius=R,
                   phase_coeffs=jnp.array([-150.0, 12.0, -3.0]), semi_diameter=6.0)
    lens = jl.Lens((jl.Sphere(0.015), s), jnp.array([4.0, 45.0]), (glass, jl.Air()), epd=6.0)
    h = jnp.linspace(-2.8, 2.8, 7)
    d = jnp.stack([0 * h, 0 * h + 0.05, jnp.sqrt(1 - 0.05**2) + 0 * h], -1)
    o = jnp.stack([0.3 + 0 * h, h, -1 + 0 * h], -1)
    rays = jl.Rays(o, d, LAM)

    def loss(p):
        c, a = p
        surf = eqx.tree_at(lambda m: (m.surfaces[1].c, m.surfaces[1].phase_coeffs), lens,
                           (c, a))
        out = jl.trace(surf, rays)
        y = out.origin[:, :2]
        return jnp.mean(jnp.sum((y - jnp.mean(y, 0)) ** 2, -1)) + 1e-3 * jnp.mean(out.opl)

    p0 = (jnp.asarray(-0.01), jnp.array([-150.0, 12.0, -3.0]))
    g = jax.jit(jax.grad(loss))(p0)
    f = jax.jit(loss)
    assert bool(jnp.all(jl.trace(lens, rays).valid))
    eps_c = 1e-6
    fd_c = (f((p0[0] + eps_c, p0[1])) - f((p0[0] - eps_c, p0[1]))) / (2 * eps_c)
    assert float(g[0]) == pytest.approx(float(fd_c), rel=1e-6)
    for i in range(3):
        e = jnp.zeros(3).at[i].set(1e-3)
        fd = (f((p0[0], p0[1] + e)) - f((p0[0], p0[1] - e))) / 2e-3
        assert float(g[1][i]) == pytest.approx(float(fd), rel=1e-6, abs=1e-12)
    assert all(bool(jnp.all(jnp.isfinite(x))) for x in jax.tree.leaves(g))


# ---------------------------------------------------------------------------- .zmx
def _zmx(surface2, unit="MM", image_glass=""):
    return (f"UNIT {unit}\nENPD 4\nWAVM 1 0.55 1\nSURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n"
            f"  CURV 0.02\n  DISZ 3\n  GLAS N-BK7\nSURF 2\n{surface2}  DISZ 45\n{image_glass}"
            f"SURF 3\n")


B2 = ('  TYPE BINARY_2\n  CURV -0.01\n  CONI -0.5\n  PARM 0 1\n  PARM 1 1E-5\n'
      '  PARM 2 -2E-8\n  XDAT 1 3 0 0 1 0 0 ""\n  XDAT 2 4.5 0 0 1 0 0 ""\n'
      '  XDAT 3 -120.5 0 0 1 0 0 ""\n  XDAT 4 6.25 0 0 1 0 0 ""\n  XDAT 5 -0.75 0 0 1 0 0 ""\n')


def test_zmx_reads_binary2_in_mm_and_inches():
    lens = zmx.loads(_zmx(B2), "t.zmx")
    s = lens.surfaces[1]
    assert type(s) is jl.Binary2
    assert (float(s.c), float(s.k), float(s.order), float(s.norm_radius)) == (-0.01, -0.5, 1, 4.5)
    np.testing.assert_array_equal(np.asarray(s.coeffs), [1e-5, -2e-8])
    np.testing.assert_array_equal(np.asarray(s.phase_coeffs), [-120.5, 6.25, -0.75])
    inch = zmx.loads(_zmx(B2, "IN"), "t.zmx").surfaces[1]
    assert float(inch.c) == pytest.approx(-0.01 / 25.4, rel=1e-15)
    assert float(inch.norm_radius) == pytest.approx(4.5 * 25.4, rel=1e-15)
    np.testing.assert_allclose(np.asarray(inch.coeffs), [1e-5 / 25.4, -2e-8 / 25.4**3],
                               rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(inch.phase_coeffs), [-120.5, 6.25, -0.75])
    # The paraxial power is the refractive one plus −MλA_1/(πR²).
    n = float(lens.indices(LAM)[1])
    p2 = (-0.01 + 2e-5) * (1 - n) - LAM * 1e-3 * -120.5 / (math.pi * 4.5**2)
    a, _, c, _ = jl.optics.paraxial.system_matrix(lens, LAM, 1, 1)
    assert float(-c) == pytest.approx(p2, rel=1e-14)


def test_zmx_round_trip_is_exact(tmp_path):
    lens = zmx.loads(_zmx(B2), "t.zmx")
    lens = eqx.tree_at(lambda m: m.surfaces[1].order, lens, jnp.asarray(-2.0))
    path = tmp_path / "doe.zmx"
    jl.save(lens, path)
    text = path.read_text()
    assert "TYPE BINARY_2" in text and "PARM 0 -2.0E+000" in text
    back = jl.load(path)
    for a, b in zip(jax.tree.leaves(lens.surfaces), jax.tree.leaves(back.surfaces), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert type(back.surfaces[1]) is jl.Binary2


def test_zmx_order_zero_traces_as_the_plain_asphere():
    off = zmx.loads(_zmx(B2.replace("PARM 0 1", "PARM 0 0")), "t.zmx")
    s = off.surfaces[1]
    asphere = jl.EvenAsphere(c=s.c, k=s.k, coeffs=s.coeffs, semi_diameter=s.semi_diameter)
    plain = eqx.tree_at(lambda m: m.surfaces[1], off, asphere)
    h = jnp.linspace(-1.9, 1.9, 9)
    rays = jl.Rays(jnp.stack([0.2 + 0 * h, h, -1 + 0 * h], -1),
                   jnp.stack([0 * h, 0 * h + 0.03, jnp.sqrt(1 - 0.03**2) + 0 * h], -1), LAM)
    a, b = jl.trace(off, rays), jl.trace(plain, rays)
    np.testing.assert_allclose(np.asarray(a.origin), np.asarray(b.origin), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(a.direction), np.asarray(b.direction), atol=1e-15)
    np.testing.assert_allclose(np.asarray(a.opl), np.asarray(b.opl), rtol=1e-15)
    assert float(jl.efl(off)) == pytest.approx(float(jl.efl(plain)), rel=1e-15)
    on = zmx.loads(_zmx(B2), "t.zmx")
    assert abs(float(jl.efl(on)) - float(jl.efl(off))) > 1.0


@pytest.mark.parametrize("old, new, line, what", [
    ("XDAT 1 3 ", "XDAT 1 2.5 ", 18, r"XDAT 1 \(the number of phase terms\) must be a whole"),
    ("XDAT 1 3 ", "XDAT 1 -1 ", 18, r"XDAT 1 \(the number of phase terms\) must be a whole"),
    ("XDAT 1 3 ", "XDAT 1 2 ", 22, r"coefficient beyond the 2 phase terms"),
    ("XDAT 2 4.5 ", "XDAT 2 0 ", 19, r"the normalisation radius \(XDAT 2\) must be > 0"),
    ("  PARM 0 1\n", "", 12, r"this BINARY_2 surface has phase terms but no diffraction order "
                             r"\(PARM 0\)"),
    ("  PARM 2 -2E-8\n", "  PARM 9 1\n", 17, r"BINARY_2 uses PARM 0\.\.8 only"),
])
def test_zmx_refuses_malformed_binary2_naming_the_line(old, new, line, what):
    text = _zmx(B2.replace(old, new))
    with pytest.raises(ValueError, match=rf"^t\.zmx:{line}: {what}"):
        zmx.loads(text, "t.zmx")


def test_zmx_refuses_a_diffractive_mirror_and_image():
    with pytest.raises(ValueError, match=r"^t\.zmx:\d+: a BINARY_2 .* cannot be a mirror"):
        zmx.loads(_zmx(B2 + "  GLAS MIRROR\n"), "t.zmx")
    img = _zmx("  CURV -0.02\n").replace("SURF 3\n", "SURF 3\n  TYPE BINARY_2\n")
    with pytest.raises(ValueError, match=r"the image surface must be"):
        zmx.loads(img, "t.zmx")


# ---------------------------------------------------------------------------- the rest
def test_backward_trace_retraces_the_forward_ray():
    """Reciprocity: a ray traced back from where it landed, with its direction reversed,
    leaves the lens along the reverse of the ray that came in, with the same optical path."""
    lens = zmx.loads(_zmx(B2), "t.zmx")
    o = jnp.array([[0.0, 1.5, -1.0], [0.4, -1.0, -1.0]])
    d = jnp.array([[0.0, 0.05, 1.0], [-0.02, 0.0, 1.0]])
    d = d / jnp.linalg.norm(d, axis=-1, keepdims=True)
    out = jl.trace(lens, jl.Rays(o, d, LAM))
    back = backward.trace_backward(lens, jl.Rays(out.origin, -out.direction, LAM))
    assert bool(jnp.all(back.valid))
    np.testing.assert_allclose(np.asarray(back.direction), -np.asarray(d), atol=1e-13)
    # Back on the line the ray came in on.
    start = np.asarray(o) + np.asarray(d) * ((np.asarray(back.origin[:, 2]) - np.asarray(o[:, 2]))
                                             / np.asarray(d[:, 2]))[:, None]
    np.testing.assert_allclose(np.asarray(back.origin), start, atol=1e-11)
    path = np.linalg.norm(np.asarray(back.origin) - np.asarray(o), axis=-1)  # in air
    np.testing.assert_allclose(np.asarray(back.opl), np.asarray(out.opl) - path, rtol=1e-13)


def test_every_other_consumer_handles_or_refuses_it(tmp_path):
    lens = zmx.loads(_zmx(B2), "t.zmx")
    s = lens.surfaces[1]
    assert not surface_adjoint.supported(s)
    assert forward.uniform_surfaces(lens.surfaces)[1] is s
    with pytest.raises(ValueError, match="Binary2; only Standard"):
        forward.stacked_surfaces(lens.surfaces)
    with pytest.raises(ValueError, match="only an EvenAsphere can be rebased, got a Binary2"):
        rebase_conic(s)
    with pytest.raises(ValueError, match="ToleranceModel: surface 2 is a Binary2"):
        ToleranceModel(lens)
    template = eqx.tree_at(lambda m: m.surfaces[0], lens,
                           jl.EvenAsphere(c=0.02, coeffs=jnp.zeros(3)))
    with pytest.raises(ValueError, match=r"surfaces\[1\] is a Binary2"):
        Parameterization(template=template, r_norm=jnp.ones(2), total_track=40.0,
                         optical=(0, 1))
    assert lensfile.surface_to_dict(s)["type"] == "binary2"
    assert json_round_trip(lens, tmp_path).surfaces[1].phase_coeffs.shape == s.phase_coeffs.shape
    mirror = jl.Lens((jl.Plane(), s), jnp.array([5.0, -20.0]), (jl.Air(), jl.Air()), epd=2.0,
                     mirrors=(1,))
    with pytest.raises(ValueError, match=r"Binary2 \(diffractive\) surface cannot be a mirror"):
        jl.trace(mirror, jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), LAM))
    text = report.format_report(report.report_data(lens), lens)
    rows = [ln for ln in text.splitlines() if "BINARY_2" in ln]
    assert len(rows) == 1 and "M=1 R=4.5" in rows[0] and "P2=-120.5" in rows[0]


def test_surface_checks_its_numbers():
    with pytest.raises(ValueError, match="Binary2: norm_radius must be finite numbers in "
                                         r"\(0, inf\) mm"):
        jl.Binary2(norm_radius=0.0)
    with pytest.raises(ValueError, match="Binary2: phase_coeffs must be finite"):
        jl.Binary2(phase_coeffs=jnp.array([1.0, jnp.nan]))
    with pytest.raises(ValueError, match="Binary2: phase_coeffs must be a 1-D array"):
        jl.Binary2(phase_coeffs=jnp.ones((2, 2)))
    s = jl.Binary2(phase_coeffs=jnp.array([-5.0]))
    phi, px, py = s.phase(jnp.array([0.0, 0.5]), jnp.array([0.0, 0.0]))
    assert np.asarray(phi).tolist() == [0.0, -5.0 * 0.25] and float(px[0]) == 0.0
    # The phase's gradient is finite on the axis under grad.
    g = jax.grad(lambda a: eqx.tree_at(lambda m: m.phase_coeffs, s, a).phase(0.0, 0.0)[1])(
        jnp.array([-5.0]))
    assert bool(jnp.all(jnp.isfinite(g)))
