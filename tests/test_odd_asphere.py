"""Zemax's odd asphere (``OddAsphere``, ``TYPE ODDASPHE``): sag, tracing, gradients, files.

The sag z = c r²/(1 + sqrt(1 − (1+k) c² r²)) + Σ β_i r^i is checked against the formula in
numpy, the traced intercepts and refracted directions against that numpy sag and a
finite-difference normal (not the library's gradient), and the even terms against the
``EvenAsphere`` they equal.
"""

import dataclasses
import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.analysis.tolerance import ToleranceModel
from jaxlens.design.params import Parameterization
from jaxlens.io import lensfile
from jaxlens.optics.rebase import rebase_conic
from jaxlens.tracing import backward, forward, surface_adjoint

C, K = 0.2, -0.5
# β_1, β_3, β_5 of phone-lens size: 20 + 8 − 3 µm of sag at r = 2 mm.
BETA = np.array([1e-2, 0.0, 1e-3, 0.0, -1e-4])
FIELDS = [(0.0, 0.0), (5.0, 12.0), (0.0, 20.0)]


def sag_np(x, y, c=C, k=K, beta=BETA):
    r2 = x * x + y * y
    r = np.sqrt(r2)
    z = c * r2 / (1 + np.sqrt(1 - (1 + k) * c * c * r2))
    return z + sum(b * r ** (i + 1) for i, b in enumerate(beta))


def odd_lens(beta=BETA, sd=2.0, image=None):
    return jl.Lens(
        surfaces=(jl.OddAsphere(c=C, k=K, coeffs=jnp.asarray(beta), semi_diameter=sd),
                  jl.Sphere(-0.05)),
        thickness=jnp.array([1.5, 8.0]),
        materials=(jl.get_material("N-BK7"), jl.Air()),
        epd=3.6, fields=jnp.array([0.0, 15.0]),
        **({} if image is None else {"image": image}),
    )


def beams(lens, n=9):
    return [jl.sampling.collimated(lens, f, jl.sampling.pupil_grid(n)) for f in FIELDS]


# ---------------------------------------------------------------------------- the sag
XY = np.array([[0.0, 0.0], [1e-3, 0.0], [0.3, -0.4], [1.2, 0.5], [-1.1, 1.6], [0.0, 2.0]])


def test_sag_is_the_formula():
    s = jl.OddAsphere(c=C, k=K, coeffs=BETA)
    z, inside = s.sag(jnp.asarray(XY[:, 0]), jnp.asarray(XY[:, 1]))
    np.testing.assert_allclose(np.asarray(z), sag_np(XY[:, 0], XY[:, 1]), rtol=1e-14,
                               atol=1e-17)
    assert bool(jnp.all(inside))
    z2, gx, gy, _ = s.sag_and_grad(jnp.asarray(XY[:, 0]), jnp.asarray(XY[:, 1]))
    np.testing.assert_array_equal(np.asarray(z2), np.asarray(z))
    # the slope at r = 2 mm along y: conic + β_1 + 3 β_3 r² + 5 β_5 r⁴
    r = 2.0
    slope = C * r / np.sqrt(1 - (1 + K) * C * C * r * r) + 1e-2 + 3e-3 * r**2 - 5e-4 * r**4
    assert float(gy[-1]) == pytest.approx(slope, rel=1e-14) and float(gx[-1]) == 0.0


def test_gradient_matches_autodiff_and_central_differences():
    s = jl.OddAsphere(c=C, k=K, coeffs=jnp.asarray([1e-2, 3e-3, 1e-3, -2e-4, -1e-4, 1e-5]))
    b = np.asarray(s.coeffs)
    x, y = jnp.asarray(XY[1:, 0]), jnp.asarray(XY[1:, 1])
    _, gx, gy, _ = s.sag_and_grad(x, y)
    auto = jax.vmap(jax.grad(lambda u, v: s.sag(u, v)[0], argnums=(0, 1)))(x, y)
    np.testing.assert_allclose(np.asarray(gx), np.asarray(auto[0]), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.asarray(gy), np.asarray(auto[1]), rtol=1e-12, atol=1e-15)
    h = 1e-6
    xn, yn = XY[1:, 0], XY[1:, 1]
    fx = (sag_np(xn + h, yn, beta=b) - sag_np(xn - h, yn, beta=b)) / (2 * h)
    fy = (sag_np(xn, yn + h, beta=b) - sag_np(xn, yn - h, beta=b)) / (2 * h)
    far = np.hypot(xn, yn) > 10 * h  # the cone tip's kink is within h of the axis
    np.testing.assert_allclose(np.asarray(gx)[far], fx[far], rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(np.asarray(gy)[far], fy[far], rtol=1e-7, atol=1e-9)


def test_cone_tip_has_finite_gradients_and_the_conic_normal():
    s = jl.OddAsphere(c=C, k=K, coeffs=jnp.asarray([5e-2, 1e-2, 1e-3]))
    zero = jnp.zeros(())
    z, gx, gy, _ = s.sag_and_grad(zero, zero)
    assert (float(z), float(gx), float(gy)) == (0.0, 0.0, 0.0)
    assert np.all(np.isfinite(jax.grad(lambda u, v: s.sag(u, v)[0], (0, 1))(zero, zero)))
    # Derivatives of the slope (the normal) at the tip, in the position and the coefficients.
    d_pos = jax.jacfwd(lambda u: jnp.stack(s.sag_and_grad(u, zero)[:3]))(zero)
    d_coef = jax.jacrev(lambda q: jnp.stack(
        eqx.tree_at(lambda t: t.coeffs, s, q).sag_and_grad(zero, zero)[:3]))(s.coeffs)
    assert np.all(np.isfinite(d_pos)) and np.all(np.isfinite(d_coef))
    assert float(d_pos[1]) == pytest.approx(C + 2e-2, rel=1e-15)  # d gx/dx = c + 2 β_2
    # An on-axis ray keeps its direction through the tip, with finite gradients.
    lens = odd_lens(beta=[5e-2, 1e-2, 1e-3])
    ray = jl.Rays(jnp.asarray([[0.0, 0.0, -1.0]]), jnp.asarray([[0.0, 0.0, 1.0]]), 0.5875618)
    out = jl.trace(lens, ray)
    assert bool(out.valid[0]) and np.array_equal(np.asarray(out.direction[0]), [0.0, 0.0, 1.0])
    g = jax.grad(lambda L: jnp.sum(jl.trace(L, ray).origin))(lens)
    assert np.all(np.isfinite(np.asarray(g.surfaces[0].coeffs)))


def test_paraxial_curvature_counts_beta2_not_the_cone():
    s = jl.OddAsphere(c=C, k=K, coeffs=jnp.asarray([0.3, 1e-2, 4.0]))
    assert float(s.paraxial_curvature) == C + 2e-2
    assert float(jl.OddAsphere(c=C, coeffs=jnp.asarray([0.3])).paraxial_curvature) == C
    assert s.has_polynomial and not jl.OddAsphere(c=C, coeffs=jnp.zeros(0)).has_polynomial


# ---------------------------------------------------------------------------- tracing
def test_even_terms_trace_as_the_even_asphere():
    """β_2, β_4, β_6 are the even asphere's a_1, a_2, a_3: same rays, same EFL."""
    a = np.array([1e-2, -2e-3, 1e-4])
    odd = odd_lens(beta=[0.0, a[0], 0.0, a[1], 0.0, a[2]])
    even = eqx.tree_at(lambda L: L.surfaces[0], odd,
                       jl.EvenAsphere(c=C, k=K, coeffs=jnp.asarray(a), semi_diameter=2.0))
    for rays in beams(odd):
        o, e = jl.trace(odd, rays), jl.trace(even, rays)
        assert bool(jnp.all(o.valid == e.valid)) and int(o.valid.sum()) > 40
        np.testing.assert_allclose(np.asarray(o.origin), np.asarray(e.origin), rtol=0,
                                   atol=1e-12)
        np.testing.assert_allclose(np.asarray(o.direction), np.asarray(e.direction), rtol=0,
                                   atol=1e-12)
    assert float(jl.efl(odd)) == pytest.approx(float(jl.efl(even)), rel=1e-14)
    assert float(jl.efl(odd)) != pytest.approx(float(jl.efl(odd_lens(beta=[0.0]))), rel=1e-3)


def test_intercepts_lie_on_the_surface_and_obey_snell():
    """Independent of the library's sag and gradient: the numpy sag, a finite-difference
    normal and n₁ d × N = n₂ d′ × N."""
    lens = odd_lens()
    wl = float(lens.primary_wavelength)
    n1 = float(lens.object_material.index(jnp.asarray(wl)))
    n2 = float(lens.materials[0].index(jnp.asarray(wl)))
    h = 1e-6
    checked = 0
    for rays in beams(lens):
        after = jl.trace_path(lens, rays, upto=0)
        p, d2 = np.asarray(after.origin[0]), np.asarray(after.direction[0])
        ok = np.asarray(after.valid[0])
        assert ok.sum() > 40
        p, d2, d1 = p[ok], d2[ok], np.asarray(rays.direction)[ok]
        x, y, z = p.T
        assert np.max(np.abs(z - sag_np(x, y))) < 1e-10
        gx = (sag_np(x + h, y) - sag_np(x - h, y)) / (2 * h)
        gy = (sag_np(x, y + h) - sag_np(x, y - h)) / (2 * h)
        normal = np.stack([-gx, -gy, np.ones_like(gx)], -1)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        far = (np.hypot(x, y) > 10 * h) | (np.hypot(x, y) == 0)  # FD is exact at the tip
        np.testing.assert_allclose(
            (n1 * np.cross(d1, normal))[far], (n2 * np.cross(d2, normal))[far], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(d2, axis=-1), 1.0, atol=1e-14)
        assert np.all(np.sum(d2 * normal, -1) > 0)  # refracted, not reflected
        checked += far.sum()
    assert checked > 120


def test_spot_gradient_matches_central_differences():
    lens = odd_lens(sd=jnp.inf)
    rays = jl.sampling.collimated(lens, 10.0, jl.sampling.pupil_grid(7))

    @jax.jit
    def loss(beta):
        out = jl.trace(eqx.tree_at(lambda L: L.surfaces[0].coeffs, lens, beta), rays)
        w = out.valid.astype(beta.dtype)
        p = out.origin[:, :2]
        centre = jnp.sum(w[:, None] * p, 0) / jnp.sum(w)
        return jnp.sum(w * jnp.sum((p - centre) ** 2, -1)) / jnp.sum(w), jnp.sum(w)

    beta = jnp.asarray(BETA)
    (value, n_valid), grad = jax.value_and_grad(loss, has_aux=True)(beta)
    assert int(n_valid) == rays.shape[0] and np.all(np.isfinite(np.asarray(grad)))
    fd = []
    for i in range(beta.shape[0]):
        step = 1e-6 / 1.8 ** (i + 1)  # about 1 nm of sag at the rim
        up, dn = loss(beta.at[i].add(step))[0], loss(beta.at[i].add(-step))[0]
        fd.append((float(up) - float(dn)) / (2 * step))
    np.testing.assert_allclose(np.asarray(grad), fd, rtol=1e-8)  # measured: 1e-10
    assert float(value) > 0


# ---------------------------------------------------------------------------- files
def _zmx(surface1, unit="MM"):
    return (f"UNIT {unit}\nENPD 3.6\nWAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\nSURF 1\n"
            f"  STOP\n{surface1}  DISZ 1.5\n  GLAS N-BK7\nSURF 2\n  CURV -0.05\n  DISZ 8\n"
            f"SURF 3\n")


ODD_LINES = ("  TYPE ODDASPHE\n  CURV 0.2\n  CONI -0.5\n  PARM 1 1E-2\n  PARM 2 0\n"
             "  PARM 3 1E-3\n  PARM 5 -1E-4\n")


def test_zmx_reads_the_coefficients_in_lens_units():
    mm = jl.io.zmx.loads(_zmx(ODD_LINES))
    s = mm.surfaces[0]
    assert isinstance(s, jl.OddAsphere) and float(s.c) == 0.2 and float(s.k) == -0.5
    np.testing.assert_array_equal(np.asarray(s.coeffs), BETA)
    inch = jl.io.zmx.loads(_zmx(ODD_LINES, unit="IN")).surfaces[0]
    assert float(inch.c) == pytest.approx(0.2 / 25.4, rel=1e-15)
    # β_i is in (lens unit)^(1−i): z = β_i r^i in inches is β_i 25.4^(1−i) r^i in mm.
    np.testing.assert_allclose(np.asarray(inch.coeffs), BETA * 25.4 ** (1 - np.arange(1, 6)),
                               rtol=1e-15)


def test_zmx_parm_beyond_8_is_refused_with_its_line(tmp_path):
    p = tmp_path / "nine.zmx"
    p.write_text(_zmx(ODD_LINES + "  PARM 9 1e-9\n"), encoding="utf-8")
    with pytest.raises(ValueError, match=r"ODDASPHE uses PARM 1\.\.8 only: 'PARM 9 1e-9'") as e:
        jl.load(p)
    assert str(e.value).startswith(f"{p}:15: ")


def test_more_than_8_terms_are_written_as_an_extended_odd_asphere(tmp_path):
    """ODDASPHE holds β_1 … β_8; a longer series is written as XOSPHERE (normalisation
    radius 1 mm, A_i = β_i) and reads back term for term; 241 terms are refused."""
    beta = np.array([2e-4, -1e-3, 3e-5, 1e-6, -2e-7, 4e-9, 1e-10, -3e-12, 5e-13, -7e-15])
    lens = odd_lens(beta=beta)
    path = tmp_path / "ten.zmx"
    jl.save(lens, path)
    text = path.read_text(encoding="utf-8")
    assert "TYPE XOSPHERE" in text and 'XDAT 1 10 ' in text
    back = jl.load(path)
    lens = dataclasses.replace(lens, negative_propagation=back.negative_propagation)
    s = back.surfaces[0]
    assert isinstance(s, jl.OddAsphere)
    np.testing.assert_array_equal(np.asarray(s.coeffs), beta)
    rays = jl.sampling.collimated(lens, 5.0, jl.sampling.pupil_hexapolar(4))
    np.testing.assert_array_equal(np.asarray(jl.trace(back, rays).origin),
                                  np.asarray(jl.trace(lens, rays).origin))
    with pytest.raises(ValueError, match="XOSPHERE holds 240"):
        jl.save(odd_lens(beta=np.full(241, 1e-30)), tmp_path / "long.zmx")


@pytest.mark.parametrize("ext", ["zmx", "json"])
def test_round_trip_traces_identically(tmp_path, ext):
    image = jl.OddAsphere(c=-0.01, k=0.0, coeffs=jnp.asarray([0.0, 0.0, 1e-5]))
    lens = odd_lens(image=image)
    path = tmp_path / f"odd.{ext}"
    jl.save(lens, path)
    back = jl.load(path)
    # A .zmx lens traces by Zemax's rule (negative_propagation): compare like with like.
    lens = dataclasses.replace(lens, negative_propagation=back.negative_propagation)
    for a, b in ((lens.surfaces[0], back.surfaces[0]), (lens.image, back.image)):
        assert type(b) is jl.OddAsphere
        np.testing.assert_array_equal(np.asarray(b.coeffs), np.asarray(a.coeffs))
        assert (float(b.c), float(b.k)) == (float(a.c), float(a.k))
    for rays in beams(lens, 5):
        np.testing.assert_array_equal(np.asarray(jl.trace(back, rays).origin),
                                      np.asarray(jl.trace(lens, rays).origin))


def test_json_names_the_keys_of_each_type():
    d = lensfile.surface_to_dict(jl.OddAsphere(c=C, coeffs=jnp.asarray([1e-2, 0.0, 1e-3])))
    assert d["type"] == "oddasph" and d["odd_asphere_coeffs"] == [1e-2, 0.0, 1e-3]
    again = lensfile.surface_from_dict({**d, "type": "Odd Asphere"}, "s")
    assert type(again) is jl.OddAsphere
    with pytest.raises(ValueError, match="odd_asphere_coeffs .*not even_asphere_coeffs"):
        lensfile.surface_from_dict({**d, "even_asphere_coeffs": [1e-3]}, "s")
    with pytest.raises(ValueError, match="belong to an odd asphere"):
        lensfile.surface_from_dict({**d, "type": "evenasph"}, "s")
    with pytest.raises(ValueError, match="did you mean 'odd_asphere_coeffs'"):
        jl.io.lensfile.lens_from_dict(json.loads(json.dumps({
            "surfaces": [{"type": "oddasph", "radial_coeffs": [1e-3], "thickness": 5}]})))


def test_bad_coefficients_are_refused_like_the_even_asphere():
    for cls in (jl.EvenAsphere, jl.OddAsphere):
        name = cls.__name__
        with pytest.raises(ValueError, match=rf"{name}: coeffs must be a 1-D array"):
            cls(c=0.1, coeffs=[[1e-3, 2e-3]])
        with pytest.raises(ValueError, match=rf"{name}: coeffs must be finite"):
            cls(c=0.1, coeffs=[1e-3, float("nan")])


# ---------------------------------------------------------------------------- the rest
def test_every_other_consumer_handles_or_refuses_it():
    lens = odd_lens()
    s = lens.surfaces[0]
    assert surface_adjoint.supported(s)  # the polynomial reverse rule (test_surface_adjoint)
    m = backward.mirror_surface(s)
    x, y = jnp.asarray(XY[:, 0]), jnp.asarray(XY[:, 1])
    np.testing.assert_array_equal(np.asarray(m.sag(x, y)[0]), -np.asarray(s.sag(x, y)[0]))
    with pytest.raises(ValueError, match="OddAsphere; only Standard"):
        forward.stacked_surfaces(lens.surfaces)
    with pytest.raises(ValueError, match="only an EvenAsphere can be rebased"):
        rebase_conic(s)
    kept = jl.optics.rebase.rebase_conics(lens).surfaces[0]  # left as it is
    assert type(kept) is jl.OddAsphere and np.array_equal(kept.coeffs, s.coeffs)
    with pytest.raises(ValueError, match="ToleranceModel: surface 1 is a OddAsphere"):
        ToleranceModel(lens)
    with pytest.raises(ValueError, match="holds EvenAsphere surfaces only"):
        Parameterization(template=lens, r_norm=jnp.ones(2), total_track=9.5, optical=(0, 1))
    table = "\n".join(report._surface_table(lens))
    assert "ODDASPHE" in table and "A1=0.01 A3=0.001 A5=-0.0001" in table
