"""Forbes Q-type aspheres (``jaxlens.optics.qtype``) and Zemax ``QED_TYPE``.

The polynomials against Forbes's closed forms and their defining orthogonality; the sag
against an independent numpy evaluation and against optiland 0.6.3's Forbes geometry
(recorded numbers); the sag's x, y gradient and its gradients in the parameters against
central differences; a traced ray's gradient in a coefficient against central differences;
the Q-bfs paraxial curvature; and a real Thorlabs file (tests/data/zmx/
rayoptics_ASL5040-UV.zmx, a Ø50 mm f = 40 mm UV fused silica asphere written with a Q-bfs
surface on a conic), which focuses far below its Airy radius with jaxlens's convention and
does not with the other readings of a Q-bfs surface with a conic.
"""

import math
import os
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import spots
from jaxlens.io import lensfile
from jaxlens.optics import qtype
from jaxlens.optics.qtype import QTypeAsphere
from jaxlens.tracing.backward import mirror_surface

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
ASL = os.path.join(DATA, "rayoptics_ASL5040-UV.zmx")
X = np.linspace(0.0, 1.2, 13)  # x = u², a little beyond the rim


def _gauss_u(n=80):
    """Nodes u and weights of ∫_0^1 f(u) (1 − u²)^(−1/2) du / (π/2) (u = sin θ)."""
    t, w = np.polynomial.legendre.leggauss(n)
    th = (t + 1) * np.pi / 4
    return np.sin(th), w * (np.pi / 4) / (np.pi / 2)


def _qcon_explicit(n, x):
    """Q_n^con(x) = P_n^(0,4)(2x − 1) from the Jacobi polynomials' explicit sum."""
    return sum(math.comb(n, n - s) * math.comb(n + 4, s) * (x - 1) ** s * x ** (n - s)
               for s in range(n + 1))


def _qbfs_gram_schmidt(n):
    """Monomial coefficients (in x) of Q_0^bfs … Q_(n−1)^bfs by Gram–Schmidt on Forbes's
    slope inner product (independent of the recurrence; fine for a few terms)."""
    P = np.polynomial.polynomial
    u, w = _gauss_u()

    def slope(q):
        return 2 * u * P.polyval(u * u, P.polyder(P.polymul([0, 1, -1], q)))

    def ip(a, b):
        return float(np.sum(w * slope(a) * slope(b)))

    basis = []
    for m in range(n):
        q = np.zeros(m + 1)
        q[m] = 1.0
        for b in basis:
            q = P.polysub(q, ip(q, b) * b)[: m + 1]
        q = q / math.sqrt(ip(q, q))
        basis.append(q if q[0] > 0 else -q)  # Q_m(0) > 0, as Forbes's
    return basis


# --- the polynomials -----------------------------------------------------------------


def test_qbfs_first_polynomials_are_forbes_closed_forms():
    Q = np.asarray(qtype.qbfs_polynomials(3, jnp.asarray(X)))
    np.testing.assert_allclose(Q[0], 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(Q[1], (13 - 16 * X) / math.sqrt(19), rtol=0, atol=1e-14)
    np.testing.assert_allclose(Q[2], 2 * (29 - 4 * X * (25 - 19 * X)) / math.sqrt(190),
                               rtol=0, atol=1e-13)


def test_qbfs_slopes_are_orthonormal_and_the_sum_is_the_series():
    """⟨S_m′ S_n′⟩ = δ_mn for S_m = u²(1 − u²) Q_m(u²), m, n < 12 (the derivative from
    ``qbfs_sum`` with a unit coefficient vector), and Σ a_m Q_m equals the polynomials
    summed one by one and the Gram–Schmidt ones."""
    n = 12
    u, w = _gauss_u()
    x = jnp.asarray(u * u)
    eye = jnp.eye(n)
    S = np.array([np.asarray(qtype.qbfs_sum(eye[m], x)[0]) for m in range(n)])
    dS = np.array([np.asarray(qtype.qbfs_sum(eye[m], x)[1]) for m in range(n)])
    xx = u * u
    slope = 2 * u * ((1 - 2 * xx) * S + xx * (1 - xx) * dS)
    gram = (slope * w) @ slope.T
    np.testing.assert_allclose(gram, np.eye(n), rtol=0, atol=1e-11)
    gs = _qbfs_gram_schmidt(6)
    Q = np.asarray(qtype.qbfs_polynomials(6, jnp.asarray(X)))
    for m in range(6):
        np.testing.assert_allclose(Q[m], np.polynomial.polynomial.polyval(X, gs[m]),
                                   rtol=0, atol=1e-10)
    a = jnp.asarray(np.random.default_rng(1).normal(size=n))
    np.testing.assert_allclose(qtype.qbfs_sum(a, jnp.asarray(X))[0],
                               np.asarray(a) @ np.asarray(qtype.qbfs_polynomials(n, X)),
                               rtol=0, atol=1e-12)


def test_qcon_polynomials_are_jacobi_and_orthogonal():
    Q = np.asarray(qtype.qcon_polynomials(9, jnp.asarray(X)))
    np.testing.assert_allclose(Q[0], 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(Q[1], -(5 - 6 * X), rtol=0, atol=1e-14)
    np.testing.assert_allclose(Q[2], 15 - 14 * X * (3 - 2 * X), rtol=0, atol=1e-13)
    np.testing.assert_allclose(Q[3], -(35 - 12 * X * (14 - X * (21 - 10 * X))), rtol=0,
                               atol=1e-12)
    for m in range(9):
        np.testing.assert_allclose(Q[m], _qcon_explicit(m, X), rtol=1e-12, atol=1e-10)
    t, w = np.polynomial.legendre.leggauss(40)
    x, w = (t + 1) / 2, w / 2
    Qg = np.asarray(qtype.qcon_polynomials(9, jnp.asarray(x)))
    gram = (Qg * w * x**4) @ Qg.T
    np.testing.assert_allclose(gram * (2 * np.arange(9) + 5)[:, None], np.eye(9), rtol=0,
                               atol=1e-11)
    a = jnp.asarray(np.random.default_rng(2).normal(size=9))
    s, ds = qtype.qcon_sum(a, jnp.asarray(X))
    np.testing.assert_allclose(s, np.asarray(a) @ Q, rtol=1e-13, atol=1e-11)
    np.testing.assert_allclose(ds, jax.vmap(jax.grad(lambda x: qtype.qcon_sum(a, x)[0]))(
        jnp.asarray(X)), rtol=1e-12, atol=1e-10)


# --- the sag -------------------------------------------------------------------------


def _numpy_sag(kind, c, k, a, rn, r):
    """The module docstring's sag, in numpy, with the polynomials from other definitions."""
    q = c * c * r * r
    base = c * r * r / (1 + np.sqrt(1 - (1 + k) * q))
    x = (r / rn) ** 2
    if kind == "bfs":
        gs = _qbfs_gram_schmidt(len(a))
        s = sum(am * np.polynomial.polynomial.polyval(x, g) for am, g in zip(a, gs, strict=True))
        return base + x * (1 - x) * np.sqrt((1 - k * q) / (1 - (1 + k) * q)) * s
    return base + x * x * sum(am * _qcon_explicit(m, x) for m, am in enumerate(a))


SURFACES = {
    "bfs_sphere": QTypeAsphere(c=0.02, k=0.0, coeffs=jnp.array([0.3, -0.1, 0.05, 0.02]),
                               norm_radius=12.0),
    "bfs_conic": QTypeAsphere(c=-0.03, k=-1.7, coeffs=jnp.array([-0.2, 0.08, -0.03, 0.01,
                                                                 0.004]), norm_radius=10.0),
    "con": QTypeAsphere(c=0.025, k=-0.6, coeffs=jnp.array([1e-2, -4e-3, 2e-3, 5e-4]),
                        norm_radius=11.0, qtype="con"),
}


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_sag_equals_an_independent_evaluation(name):
    s = SURFACES[name]
    r = np.linspace(0.0, 11.0, 12)
    z, inside = s.sag(jnp.asarray(r * 0.6), jnp.asarray(r * 0.8))
    want = _numpy_sag(s.qtype, float(s.c), float(s.k), np.asarray(s.coeffs),
                      float(s.norm_radius), r)
    assert bool(np.all(np.asarray(inside)))
    np.testing.assert_allclose(np.asarray(z), want, rtol=1e-12, atol=1e-13)
    z2, _, _, _ = s.sag_and_grad(jnp.asarray(r * 0.6), jnp.asarray(r * 0.8))
    np.testing.assert_array_equal(np.asarray(z2), np.asarray(z))


# optiland 0.6.3, ``ForbesQNormalSlopeGeometry(CoordinateSystem(), ForbesSurfaceConfig(
# radius=1/5.756078762782423225E-02, conic=-0.67609120640407927, norm_radius=27.0,
# terms={m: a_m}))`` with a_m the six XDAT 4…9 of rayoptics_ASL5040-UV.zmx, ``.sag(r, 0)``:
OPTILAND_R = [0.0, 2.5, 5.0, 10.0, 15.0, 17.5, 20.0, 22.86]
OPTILAND_SAG = [0.0, 0.16672638897283182, 0.6712195277083992, 2.7582022656796106,
                6.521560217423334, 9.202442861777373, 12.58821891916678, 17.635533649398045]


@pytest.mark.slow  # 14 s; the sag against numpy runs in CI
def test_asl5040_sag_equals_optilands_forbes_geometry():
    s = jl.load(ASL).surfaces[0]
    r = jnp.asarray(OPTILAND_R)
    z, inside = s.sag(r, jnp.zeros_like(r))
    assert bool(np.all(np.asarray(inside)))
    np.testing.assert_allclose(np.asarray(z), OPTILAND_SAG, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_sag_gradient_matches_central_differences(name):
    s = SURFACES[name]
    pts = [(0.0, 0.0), (1e-3, -2e-3), (3.0, 4.0), (-6.0, 2.5), (0.5, -9.5), (8.0, 8.0)]
    h = 1e-6
    for x, y in pts:
        _, gx, gy, _ = s.sag_and_grad(jnp.asarray(x), jnp.asarray(y))
        fx = (s.sag(x + h, y)[0] - s.sag(x - h, y)[0]) / (2 * h)
        fy = (s.sag(x, y + h)[0] - s.sag(x, y - h)[0]) / (2 * h)
        assert float(gx) == pytest.approx(float(fx), rel=1e-7, abs=1e-9)
        assert float(gy) == pytest.approx(float(fy), rel=1e-7, abs=1e-9)
        # and JAX's own derivative of the sag agrees with the hand-written one
        ax, ay = jax.grad(lambda p, q: s.sag(p, q)[0], argnums=(0, 1))(jnp.asarray(x),
                                                                       jnp.asarray(y))
        assert float(ax) == pytest.approx(float(gx), rel=1e-12, abs=1e-14)
        assert float(ay) == pytest.approx(float(gy), rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_parameter_gradients_match_central_differences(name):
    """d(sag)/d(a_m, c, k, ρ_n) and d(slope)/d(a_m, c, k), at a point inside the rim."""
    s = SURFACES[name]
    x, y = jnp.asarray(4.0), jnp.asarray(-5.0)

    def out(surf):
        z, gx, gy, _ = surf.sag_and_grad(x, y)
        return jnp.stack([z, gx, gy])

    jac = jax.jacrev(out)(s)
    for get, j, h in ((lambda t: t.coeffs, 0, 1e-6), (lambda t: t.coeffs, 2, 1e-6),
                      (lambda t: t.c, None, 1e-7), (lambda t: t.k, None, 1e-6),
                      (lambda t: t.norm_radius, None, 1e-5)):
        def at(dx, get=get, j=j):
            new = get(s) + dx if j is None else get(s).at[j].add(dx)
            return np.asarray(out(eqx.tree_at(get, s, new)))

        fd = (at(h) - at(-h)) / (2 * h)
        ad = np.asarray(get(jac) if j is None else get(jac)[:, j])
        assert np.any(ad != 0)
        np.testing.assert_allclose(ad, fd, rtol=2e-6, atol=1e-9)


def test_paraxial_curvature_is_the_vertex_curvature():
    """Q-bfs: c + 2 Σ a_m Q_m(0)/ρ_n², the limit of 2 z/r² at the vertex; Q-con: c."""
    for name, s in SURFACES.items():
        r = 1e-4
        vertex = 2 * float(s.sag(jnp.asarray(r), jnp.asarray(0.0))[0]) / r**2
        cp = float(s.paraxial_curvature)
        assert cp == pytest.approx(vertex, rel=1e-6), name
        if s.qtype == "bfs":
            q0 = np.asarray(qtype.qbfs_polynomials(s.coeffs.shape[0], jnp.asarray(0.0)))
            want = float(s.c) + 2 * float(np.asarray(s.coeffs) @ q0) / float(s.norm_radius) ** 2
            assert cp == pytest.approx(want, rel=1e-14)
            assert abs(cp - float(s.c)) > 1e-4 * abs(cp)  # 100× the tolerance above
        else:
            assert cp == float(s.c)


def _singlet(surface):
    glass = jl.ModelGlass(1.6, 50.0)
    return jl.Lens(surfaces=(surface, jl.Sphere(-0.01)), thickness=jnp.array([5.0, 45.0]),
                   materials=(glass, jl.Air()), epd=16.0, fields=jnp.array([0.0, 5.0]))


@pytest.mark.parametrize("name, reverse_rule", [("bfs_conic", False), ("bfs_conic", True),
                                                ("con", False)])
def test_trace_gradient_in_a_coefficient_matches_central_differences(name, reverse_rule):
    s = eqx.tree_at(lambda t: t.c, SURFACES[name], jnp.asarray(0.03))
    lens = _singlet(s)
    pupil = jl.sampling.pupil_grid(9, jnp.float64)
    rays = jl.sampling.collimated(lens, 5.0, pupil)

    def spot(a):
        L = eqx.tree_at(lambda t: t.surfaces[0].coeffs, lens, a)
        out = jl.trace(L, rays, reverse_rule=reverse_rule)
        w = out.valid.astype(jnp.float64)
        y = out.origin[:, 1]
        yc = jnp.sum(w * y) / jnp.sum(w)
        return jnp.sum(w * (y - yc) ** 2) / jnp.sum(w)

    a = s.coeffs
    assert bool(np.all(np.asarray(jl.trace(lens, rays).valid)))
    g = jax.grad(spot)(a)
    h = 1e-6
    for j in (0, 1):
        fd = (float(spot(a.at[j].add(h))) - float(spot(a.at[j].add(-h)))) / (2 * h)
        assert float(g[j]) != 0.0
        assert float(g[j]) == pytest.approx(fd, rel=1e-6, abs=1e-12)


def test_mirror_surface_negates_the_sag():
    for s in SURFACES.values():
        m = mirror_surface(s)
        assert type(m) is QTypeAsphere and m.qtype == s.qtype
        for x, y in ((0.0, 0.0), (3.0, -4.0), (7.0, 2.0)):
            np.testing.assert_allclose(np.asarray(m.sag(x, y)[0]), -np.asarray(s.sag(x, y)[0]),
                                       rtol=1e-14, atol=1e-15)


# --- the Thorlabs ASL5040-UV file ----------------------------------------------------


class _ConicFactor(QTypeAsphere):
    """Wrong reading: the Q-bfs factor 1/sqrt(1 − (1+k) c² r²) (the conic in Forbes's
    sphere factor, not its obliquity)."""

    def departure_factor(self, r2):
        w2 = 1.0 - (1.0 + self.k) * self.c**2 * r2
        w = jnp.sqrt(jnp.where(w2 > 0, w2, 1.0))
        return 1.0 / w, (1.0 + self.k) * self.c**2 / (w * w * w)


class _SphereFactor(QTypeAsphere):
    """Wrong reading: Forbes's sphere factor 1/sqrt(1 − c² r²) kept on a conic base (not
    defined beyond r = 1/c; there the factor is taken as 1)."""

    def departure_factor(self, r2):
        w2 = 1.0 - self.c**2 * r2
        w = jnp.sqrt(jnp.where(w2 > 0, w2, 1.0))
        return 1.0 / w, self.c**2 / (w * w * w)


def _asl_variant(lens, cls):
    s = lens.surfaces[0]
    v = cls(c=s.c, k=s.k, coeffs=s.coeffs, norm_radius=s.norm_radius,
            semi_diameter=s.semi_diameter, qtype=s.qtype)
    return eqx.tree_at(lambda t: t.surfaces, lens, (v,) + lens.surfaces[1:])


@pytest.fixture(scope="module")
def asl():
    return jl.load(ASL)


def test_asl5040_loads_as_a_qbfs_surface_in_fused_silica(asl):
    s = asl.surfaces[0]
    assert type(s) is QTypeAsphere and s.qtype == "bfs"
    assert float(s.norm_radius) == 27.0 and s.coeffs.shape == (6,)
    assert float(s.coeffs[0]) == -8.148370167576e-01 and float(s.coeffs[5]) == -2.2e-3
    assert float(s.k) == -0.67609120640407927
    m = asl.materials[0]
    assert m.name == "C79-80" and m.catalog == "CORNING"  # Corning 7980 fused silica
    assert float(m.index(0.5875618)) == pytest.approx(1.4585, abs=2e-4)
    assert np.asarray(asl.wavelengths).tolist() == [0.405]


def test_asl5040_efl_is_40_mm_and_its_focus_the_paraxial_one(asl):
    """EFL 40 mm (Thorlabs's f), only with the Q-bfs terms' r² part in the paraxial
    curvature: without it the conic alone gives 37.0 mm."""
    assert float(jl.efl(asl)) == pytest.approx(40.0, abs=2e-3)  # 39.99890
    assert float(jl.bfl(asl)) == pytest.approx(float(asl.thickness[1]), abs=1e-3)
    flat = eqx.tree_at(lambda t: t.surfaces[0].coeffs, asl, jnp.zeros(6))
    assert float(jl.efl(flat)) == pytest.approx(36.996, abs=1e-3)


def test_asl5040_focuses_far_below_its_airy_radius(asl):
    """On axis at 405 nm, at the file's image plane: RMS spot 0.10 µm against an Airy radius
    0.61 λ/NA = 0.38 µm (NA 0.650 from the traced marginal ray, the file's title says "NA=0.65");
    the other readings of a
    Q-bfs surface on a conic give 125 µm (factor 1/sqrt(1 − (1+k)c²r²)) and 1.5 mm (Forbes's
    sphere factor), i.e. thousands of Airy radii."""
    pupil = jl.sampling.pupil_grid(41, jnp.float64)
    wl = jnp.asarray([0.405])
    r = spots.rms_spot(asl, wavelengths=wl, pupil=pupil)
    rms = float(r.per_wavelength[0, 0])
    assert float(r.valid_fraction[0, 0]) == 1.0
    edge = jl.sampling.collimated(asl, 0.0, jnp.array([[0.0, 1.0 - 1e-9]]), 0.405)
    d = jl.trace(asl, edge).direction[0]
    na = float(jnp.hypot(d[0], d[1]))
    assert na == pytest.approx(0.650, abs=1e-3)
    airy = 0.61 * 0.405e-3 / na
    assert rms < 0.3 * airy, (rms, airy)  # 1.0e-4 mm against 3.8e-4 mm
    for cls, at_least in ((_ConicFactor, 0.1), (_SphereFactor, 1.0)):
        wrong = spots.rms_spot(_asl_variant(asl, cls), wavelengths=wl, pupil=pupil)
        assert float(wrong.per_wavelength[0, 0]) > at_least, cls.__name__  # mm


def test_asl5040_round_trips_exactly_through_zmx_and_json(asl, tmp_path):
    for ext in ("zmx", "json"):
        out = tmp_path / f"again.{ext}"
        jl.save(asl, out)
        again = jl.load(out)
        assert jax.tree_util.tree_structure(again.surfaces) == \
            jax.tree_util.tree_structure(asl.surfaces)
        for a, b in zip(jax.tree_util.tree_leaves(asl.surfaces),
                        jax.tree_util.tree_leaves(again.surfaces), strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    text = (tmp_path / "again.zmx").read_text()
    assert "TYPE QED_TYPE" in text and re.search(r"XDAT 3 2\.7E\+0*1 ", text)


def test_qcon_round_trips_through_zmx_and_json(tmp_path):
    lens = _singlet(eqx.tree_at(lambda t: t.c, SURFACES["con"], jnp.asarray(0.03)))
    for ext in ("zmx", "json"):
        out = tmp_path / f"con.{ext}"
        jl.save(lens, out)
        s = jl.load(out).surfaces[0]
        assert type(s) is QTypeAsphere and s.qtype == "con"
        np.testing.assert_array_equal(np.asarray(s.coeffs), np.asarray(lens.surfaces[0].coeffs))
        assert float(s.norm_radius) == 11.0
    assert 'XDAT 1 1 0 0 1 0 0 ""' in (tmp_path / "con.zmx").read_text()


# --- bad input -----------------------------------------------------------------------


def _asl_text():
    with open(ASL, "rb") as fh:
        return fh.read().decode("utf-16")


def _line_of(text, start):
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.strip().startswith(start))


@pytest.mark.parametrize("old, new, at, message", [
    ("XDAT 1 0.000000000000E+00", "XDAT 1 2", "XDAT 1 ",
     r"XDAT 1 \(the Q-type polynomial type\) must be 0 \(Q-bfs\) or 1 \(Q-con\), got 2"),
    ("XDAT 2 6.000000000000E+00", "XDAT 2 5", "XDAT 9 ",
     r"coefficient beyond the 5 Q-type terms of XDAT 2"),
    ("XDAT 2 6.000000000000E+00", "XDAT 2 5.5", "XDAT 2 ", r"must be a whole number"),
    ("XDAT 3 2.700000000000E+01", "XDAT 3 0", "XDAT 3 ",
     r"XDAT 3 \(the normalisation radius, lens units\) must be > 0, got 0"),
    ("XDAT 3 2.700000000000E+01", "XDAT 3 -27", "XDAT 3 ", r"must be > 0, got -27"),
    ("XDAT 3 2.700000000000E+01 0 0 1.000000000000E+00 0.000000000000E+00 0 \"\"", "",
     "TYPE QED_TYPE", r"XDAT 3 is missing"),
])
def test_bad_qed_type_data_name_the_file_and_line(tmp_path, old, new, at, message):
    text = _asl_text()
    assert old in text
    text = text.replace(old, new)
    path = tmp_path / "bad.zmx"
    path.write_bytes(text.encode("utf-16"))
    line = _line_of(text, at)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}:{line}: .*{message}"):
        jl.load(path)


@pytest.mark.parametrize("kw, message", [
    (dict(norm_radius=0.0), r"norm_radius.*\(0, inf\).* mm"),
    (dict(norm_radius=-3.0), r"norm_radius"),
    (dict(coeffs=jnp.array([0.1, jnp.nan])), r"coeffs"),
    (dict(c=jnp.inf), r"\bc\b"),
    (dict(qtype="bfz"), r"qtype must be 'bfs' .* or 'con'"),
])
def test_constructor_refuses_bad_numbers(kw, message):
    args = dict(c=0.02, k=0.0, coeffs=jnp.array([0.1]), norm_radius=10.0) | kw
    with pytest.raises(ValueError, match=message):
        QTypeAsphere(**args)


@pytest.mark.parametrize("surface, message", [
    ({"type": "qbfs", "curvature": 0.02, "q_coeffs": [0.1]}, r"needs norm_radius"),
    ({"type": "qcon", "curvature": 0.02, "norm_radius": -1, "q_coeffs": [0.1]},
     r"norm_radius must be > 0 \(mm\), got -1"),
    ({"type": "standard", "curvature": 0.02, "norm_radius": 5, "q_coeffs": [0.1]},
     r"belong to a Q-type asphere"),
    ({"type": "qbfs", "norm_radius": 5, "even_asphere_coeffs": [1e-4]},
     r"takes its terms as q_coeffs"),
    ({"type": "qbfs", "norm_radius": 5, "qbfs_coeffs": [1e-4]}, r"did you mean 'q_coeffs'"),
])
def test_json_refuses_bad_qtype_surfaces(surface, message):
    lens = jl.load(ASL)
    d = lensfile.lens_to_dict(lens)
    d["surfaces"][1] = {**surface, "thickness": 29.85, "material": "C79-80"}
    with pytest.raises(ValueError, match=message):
        lensfile.lens_from_dict(d, source="bad.json")
