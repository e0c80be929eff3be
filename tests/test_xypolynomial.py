"""Zemax's extended polynomial surface (``XYPolynomial``, ``TYPE XPOLYNOM``).

Checked: the term order against Zemax's table (x, y, x², xy, y², x³, …) and each term alone
against its monomial; sag and unit normal against optiland 0.6.3's ``PolynomialGeometry``
(recorded numbers, ``REF`` below); the hand-written slope and the vertex curvatures against
automatic differentiation; real rays through a lens read from ``tests/data/
xypolynomial_lens.zmx`` against optiland's trace of the same lens; a surface without terms
traces as a ``Standard`` one, and one with only linear terms as the same ``TiltedPlane``;
``.zmx`` (also in inches) and JSON round trips; gradients of the sag and of a spot size in
the coefficients against central differences; bad values refused with the argument, the
range and the unit, or with the file's line.
"""

import pathlib
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.io import lensfile, zmx
from jaxlens.optics.xypolynomial import (
    MAX_XY_TERMS,
    XYPolynomial,
    xy_polynomial_sum,
    xy_term_count,
    xy_term_index,
    xy_term_powers,
)

WL = 0.5875618
DATA = pathlib.Path(__file__).parent / "data" / "xypolynomial_lens.zmx"

# optiland 0.6.3's numbers, printed by
#     /work/optiland_venv/bin/python tools/xypolynomial_reference.py
# (see that script's docstring): sag and unit normal (+z at the vertex) of its
# PolynomialGeometry at ``points`` for the 27 ``terms`` (degree 1 … 6, Zemax's order,
# converted to optiland's unnormalised C_mn = A_i / R^(m+n)) on ``base``, and the image
# intercepts (mm) of the two-surface lens ``surfaces`` traced by optiland with Newton
# tolerance 1e-13 from ``launch`` (the lens of tests/data/xypolynomial_lens.zmx).
REF = {'base': {'conic': -0.6, 'norm_radius': 5.0, 'radius': 40.0},
       'launch': {'direction': [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0],
                                [0.0, 0.0, 1.0], [0.0, 0.0697564737441253, 0.9975640502598243],
                                [0.0, 0.0697564737441253, 0.9975640502598243],
                                [0.0, 0.0697564737441253, 0.9975640502598243],
                                [0.0, 0.0697564737441253, 0.9975640502598243],
                                [0.0, 0.0697564737441253, 0.9975640502598243],
                                [0.05233595624294382, 0.0, 0.9986295347545737],
                                [0.05233595624294382, 0.0, 0.9986295347545737],
                                [0.05233595624294382, 0.0, 0.9986295347545737],
                                [0.05233595624294382, 0.0, 0.9986295347545737],
                                [0.05233595624294382, 0.0, 0.9986295347545737],
                                [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                                [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                                [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                                [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                                [0.043538182780866005, -0.06099065109629843, 0.9971883308176993]],
                  'origin': [[0.0, 0.0, -5.0], [2.8, 0.0, -5.0], [0.0, -2.8, -5.0],
                             [2.0, 2.4, -5.0], [-3.6, -1.2, -5.0],
                             [0.0, -0.34963405971755207, -5.0], [2.8, -0.34963405971755207, -5.0],
                             [0.0, -3.149634059717552, -5.0], [2.0, 2.0503659402824477, -5.0],
                             [-3.6, -1.549634059717552, -5.0], [-0.262038896415206, 0.0, -5.0],
                             [2.5379611035847938, 0.0, -5.0], [-0.262038896415206, -2.8, -5.0],
                             [1.737961103584794, 2.4, -5.0], [-3.862038896415206, -1.2, -5.0],
                             [-0.21830471454256029, 0.3058131007524215, -5.0],
                             [2.5816952854574398, 0.3058131007524215, -5.0],
                             [-0.21830471454256029, -2.494186899247578, -5.0],
                             [1.7816952854574397, 2.7058131007524215, -5.0],
                             [-3.8183047145425606, -0.8941868992475784, -5.0]]},
       'points': [[0.0, 0.0], [1.3, 0.0], [0.0, -2.1], [2.2, 1.7], [-3.1, 2.6], [3.9, -3.3],
                  [-0.4, -4.6], [-4.2, -1.1]],
       'rays': [[-0.005774278637260424, 0.010139800224498226, 49.0],
                [-0.42365433474766867, 0.008267106902211099, 49.0],
                [-0.0029771531078358485, 0.430590023613028, 49.0],
                [-0.3096507758297198, -0.3575667997633327, 49.0],
                [0.5530537599295067, 0.19620682117603905, 49.0],
                [-0.005267113755230661, 3.2520293392258415, 49.0],
                [-0.43464374754426593, 3.2562258630471757, 49.0],
                [-0.0020936048322921846, 3.717827341518091, 49.0],
                [-0.309032788244497, 2.88159918714912, 49.0],
                [0.5766970431969374, 3.463803819594813, 49.0],
                [2.4236595859449617, 0.010559876556693546, 49.0],
                [2.0059458625252304, 0.009218594260741002, 49.0],
                [2.430734024451953, 0.43790716459236645, 49.0],
                [2.1206808395340992, -0.35617928178281444, 49.0],
                [3.0301665928485404, 0.20489386224078476, 49.0],
                [2.0173808198754655, -2.824795148629895, 49.0],
                [1.5921529465683697, -2.82394331017755, 49.0],
                [2.0158386742981316, -2.396454508369214, 49.0],
                [1.708079097733936, -3.219663978873488, 49.0],
                [2.6151680841589444, -2.646262014912703, 49.0]],
       'sag': [[0.0, -0.0023999719204927947, 0.004199950860862391, 0.999988300205331],
               [0.023999248488444265, -0.03450172443109487, 0.003952027039623582,
                0.9993968243363387],
               [0.06384108651041134, -0.0019979966901332866, 0.05656957909902912,
                0.9983966600153393],
               [0.09469730942213299, -0.057024569513544926, -0.03851545227556362,
                0.9976295697340791],
               [0.18306480412239504, 0.07413438077291883, -0.05907495763329382,
                0.9954969829025302],
               [0.34373897544922233, -0.09614315506875115, 0.08521293625334693,
                0.9917132898315466],
               [0.2856064230596828, 0.00837970033176334, 0.11900428762678528, 0.9928583786969776],
               [0.23047191113376037, 0.10320456080014101, 0.032494082798545564,
                0.9941292437168978]],
       'surfaces': [[40.0, -0.6, 6.0, 15, 4.0, 1.6], [-60.0, 0.0, 6.5, 27, 45.0, 1.0]],
       'terms': [0.012, -0.021, -0.003593, 0.0047, -0.001173, -0.000466, 9.1e-05, 0.001348,
                 -0.001167, 0.001062, -0.000847, -0.001666, 0.004124, -0.000175, -0.001575,
                 0.001986, -0.003083, -0.001821, 0.000976, -0.000644, 0.000363, 0.004712, 0.002494,
                 -0.004044, -0.001324, -0.001332, -0.000297]}


def _close(a, b, tol):
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=tol)


def _base_surface(**kw):
    b = REF["base"]
    args = dict(c=1 / b["radius"], k=b["conic"], coeffs=jnp.asarray(REF["terms"]),
                norm_radius=b["norm_radius"]) | kw
    return XYPolynomial(**args)


def _table(s, pts):
    """Sag and unit normal (+z at the vertex) at the points, [P, 4]."""
    z, gx, gy, _ = s.sag_and_grad(jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1]))
    n = np.stack([-np.asarray(gx), -np.asarray(gy), np.ones(len(pts))], -1)
    return np.column_stack([np.asarray(z), n / np.linalg.norm(n, axis=-1, keepdims=True)])


# --- the polynomial ------------------------------------------------------------------


def test_term_order_is_zemaxs():
    """By degree, then by falling power of x; degree 20 ends at term 230."""
    table = [(1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3), (4, 0),
             (3, 1), (2, 2), (1, 3), (0, 4), (5, 0)]
    assert [xy_term_powers(i) for i in range(1, 16)] == table
    assert all(xy_term_index(*xy_term_powers(i)) == i for i in range(1, MAX_XY_TERMS + 1))
    assert xy_term_powers(MAX_XY_TERMS) == (0, 20) and MAX_XY_TERMS == xy_term_count(20) == 230
    assert xy_term_index(0, 6) == xy_term_count(6) == 27
    with pytest.raises(ValueError, match=r"xy_term_powers: i must be a whole number >= 1"):
        xy_term_powers(0)
    with pytest.raises(ValueError, match=r"no constant term"):
        xy_term_index(0, 0)


def test_each_term_alone_is_its_monomial_of_the_normalised_coordinates():
    pts = np.asarray(REF["points"])
    x, y = jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1])
    rn = 3.5
    for i in (1, 2, 3, 4, 5, 7, 12, 27, 66):
        m, n = xy_term_powers(i)
        s = XYPolynomial(coeffs=jnp.zeros(i).at[i - 1].set(0.25), norm_radius=rn)
        want = 0.25 * (pts[:, 0] / rn) ** m * (pts[:, 1] / rn) ** n
        np.testing.assert_allclose(np.asarray(s.sag(x, y)[0]), want, rtol=1e-14, atol=1e-16)


def test_sag_and_normal_equal_optilands():
    """27 terms (a tilt and an xy term among them) on a conic, at 8 points."""
    _close(_table(_base_surface(), np.asarray(REF["points"])), REF["sag"], 1e-14)


def test_hand_written_slope_and_vertex_curvatures_equal_automatic_differentiation():
    s = _base_surface(coeffs=jnp.asarray(np.random.default_rng(1).normal(size=35) * 1e-2))
    pts = np.vstack([np.asarray(REF["points"]), [[0.0, 0.0]]])
    x, y = jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1])
    gx, gy = jax.jit(jax.vmap(jax.grad(lambda x, y: s.sag(x, y)[0], argnums=(0, 1))))(x, y)
    _, hx, hy, _ = jax.jit(lambda x, y: s.sag_and_grad(x, y))(x, y)
    _close(hx, gx, 1e-15)
    _close(hy, gy, 1e-15)
    zero = jnp.zeros(())
    hess = jax.jit(jax.hessian(lambda p: s.sag(p[0], p[1])[0]))(jnp.stack([zero, zero]))
    zxx, zxy, zyy = s.vertex_hessian()
    assert float(zxx) == pytest.approx(float(hess[0, 0]), rel=1e-13)
    assert float(zxy) == pytest.approx(float(hess[0, 1]), rel=1e-13)
    assert float(zyy) == pytest.approx(float(hess[1, 1]), rel=1e-13)
    assert float(s.paraxial_curvature) == float(zyy)
    assert float(s.paraxial_curvature_x) == float(zxx)
    # c + 2A/R²: the x² and y² terms, not the xy one (seen by real rays only)
    a = np.asarray(s.coeffs)
    assert float(zxx) == pytest.approx(1 / 40 + 2 * a[2] / 25, rel=1e-14)
    assert float(zyy) == pytest.approx(1 / 40 + 2 * a[4] / 25, rel=1e-14)
    assert float(zxy) == pytest.approx(a[3] / 25, rel=1e-14)


def test_paraxial_power_of_a_cylinder_term():
    """0.5·(x/R)² on a plane is the cylinder of curvature 1/R² in x, flat in y; a tilt adds
    nothing to either section's curvature. The EFL is the y–z section's (c = 0: none)."""
    rn = 10.0
    s = XYPolynomial(coeffs=jnp.array([0.01, -0.02, 0.5]), norm_radius=rn)
    assert float(s.paraxial_curvature_x) == pytest.approx(1 / rn**2, rel=1e-15)
    assert float(s.paraxial_curvature) == 0.0
    y_only = XYPolynomial(coeffs=jnp.array([0.0, 0.0, 0.0, 0.0, 0.5]), norm_radius=rn)
    lens = jl.Lens(surfaces=(y_only, jl.Plane()), thickness=jnp.array([2.0, 50.0]),
                   materials=(jl.ModelGlass(1.5, 50.0), jl.Air()), epd=4.0)
    assert float(jl.efl(lens)) == pytest.approx(1 / (0.5 / rn**2), rel=1e-13)


def test_vertex_and_outside_the_domain_are_finite_with_finite_gradients():
    s = XYPolynomial(c=0.2, k=0.5, coeffs=jnp.array([1e-3, 0.0, 2e-3, 1e-3]), norm_radius=3.0)
    for x, y in ((0.0, 0.0), (9.0, 0.0), (0.0, 9.0)):  # 9 mm: outside the conic
        z, gx, gy, inside = s.sag_and_grad(jnp.asarray(x), jnp.asarray(y))
        assert np.all(np.isfinite(np.asarray([z, gx, gy])))
        if not bool(inside):
            assert float(gx) == 0.0 and float(gy) == 0.0
        g = jax.grad(lambda t, x=x, y=y: sum(t.sag_and_grad(jnp.asarray(x),
                                                             jnp.asarray(y))[:3]))(s)
        assert all(np.all(np.isfinite(np.asarray(v))) for v in jax.tree_util.tree_leaves(g))
    assert not bool(s.sag(9.0, 0.0)[1])
    empty = xy_polynomial_sum(jnp.zeros(0), jnp.ones(3), jnp.ones(3))
    assert all(np.all(np.asarray(v) == 0) for v in empty)


def test_sag_gradients_in_the_coefficients_match_central_differences():
    """d(sag)/d(A_i, R, c, k) at a few points against central differences."""
    s = _base_surface()
    pts = np.asarray(REF["points"])[1:]
    x, y = jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1])

    @jax.jit
    def total(t):
        return jnp.sum(t.sag(x, y)[0] * jnp.arange(1.0, len(pts) + 1))

    g = jax.grad(total)(s)
    for field, idx, h in (("coeffs", (0, 3, 4, 11, 26), 1e-6), ("norm_radius", (None,), 1e-5),
                          ("c", (None,), 1e-7), ("k", (None,), 1e-4)):
        v = getattr(s, field)
        for j in idx:
            def at(d, j=j, v=v, field=field):
                new = v + d if j is None else v.at[j].add(d)
                return float(total(eqx.tree_at(lambda t: getattr(t, field), s, new)))
            fd = (at(h) - at(-h)) / (2 * h)
            gj = float(getattr(g, field) if j is None else getattr(g, field)[j])
            assert gj != 0.0, (field, j)
            assert gj == pytest.approx(fd, rel=1e-7, abs=1e-12), (field, j)


# --- real rays -------------------------------------------------------------------------


def _rays():
    return jl.Rays(jnp.asarray(REF["launch"]["origin"]),
                   jnp.asarray(REF["launch"]["direction"]), WL)


@pytest.fixture(scope="module")
def lens():
    return jl.load(DATA, strict=True)


def test_file_reads_as_the_reference_lens(lens):
    assert all(type(s) is XYPolynomial for s in lens.surfaces)
    for s, (r, k, rn, n_terms, _, _) in zip(lens.surfaces, REF["surfaces"], strict=True):
        assert float(s.c) == 1 / r and float(s.k) == k and float(s.norm_radius) == rn
        np.testing.assert_array_equal(np.asarray(s.coeffs), REF["terms"][:n_terms])
    np.testing.assert_array_equal(np.asarray(lens.thickness), [4.0, 45.0])


def test_real_rays_equal_optilands(lens):
    """20 rays (4 fields, 5 pupil points) through two XPOLYNOM surfaces agree with
    optiland's intercepts to 1e-12 mm (measured 5.1e-15 mm)."""
    out = jl.trace(lens, _rays())
    assert bool(np.all(np.asarray(out.valid)))
    _close(out.origin, REF["rays"], 1e-12)


def _with_first(lens, s):
    return eqx.tree_at(lambda t: t.surfaces[0], lens, s)


def test_no_terms_trace_as_a_standard_surface(lens):
    """XDAT 1 = 0 is the base conic, traced by the same closed form as ``Standard``: the
    same intercepts and directions bit for bit."""
    rays = _rays()
    c, k = lens.surfaces[0].c, lens.surfaces[0].k
    standard = jl.trace(_with_first(lens, jl.Standard(c=c, k=k)), rays)
    text = DATA.read_text()
    start, end = text.index("  XDAT 1 15"), text.index("  DISZ 4.0")
    bare = zmx.loads(text[:start] + '  XDAT 1 0 0 0 0 0 0 ""\n  XDAT 2 1 0 0 0 0 0 ""\n'
                     + text[end:])
    assert type(bare.surfaces[0]) is XYPolynomial and bare.surfaces[0].coeffs.shape == (0,)
    assert not bare.surfaces[0].has_polynomial
    empty = jl.trace(bare, rays)
    np.testing.assert_array_equal(np.asarray(empty.origin), np.asarray(standard.origin))
    np.testing.assert_array_equal(np.asarray(empty.direction), np.asarray(standard.direction))
    np.testing.assert_array_equal(np.asarray(empty.valid), np.asarray(standard.valid))


def test_zero_terms_trace_as_a_standard_surface_and_linear_terms_as_a_tilted_plane(lens):
    """Zero-valued terms (the Newton intersection) agree with ``Standard`` to rounding;
    A_1 x/R + A_2 y/R alone is the tilted plane of slopes A/R (real rays see the tilt)."""
    rays = _rays()
    c, k = lens.surfaces[0].c, lens.surfaces[0].k
    standard = jl.trace(_with_first(lens, jl.Standard(c=c, k=k)), rays)
    zeros = jl.trace(_with_first(lens, XYPolynomial(c=c, k=k, coeffs=jnp.zeros(5),
                                                    norm_radius=6.0)), rays)
    _close(zeros.origin, standard.origin, 1e-12)
    _close(zeros.direction, standard.direction, 1e-15)
    tilt = XYPolynomial(coeffs=jnp.array([0.3, -0.2]), norm_radius=6.0)
    plane = jl.TiltedPlane(tan_x=0.05, tan_y=-0.2 / 6.0)
    a, b = jl.trace(_with_first(lens, tilt), rays), jl.trace(_with_first(lens, plane), rays)
    assert bool(np.all(np.asarray(a.valid)))
    _close(a.origin, b.origin, 1e-12)
    assert float(tilt.paraxial_curvature) == 0.0 == float(tilt.paraxial_curvature_x)


def _spot_loss(lens, rays):
    out = jl.trace(lens, rays)
    w = out.valid.astype(jnp.float64)
    xy = out.origin[:, :2]
    c = jnp.sum(w[:, None] * xy, 0) / jnp.sum(w)
    return jnp.sum(w[:, None] * (xy - c) ** 2) / jnp.sum(w)


def test_spot_gradient_in_the_coefficients_matches_central_differences(lens):
    """Through the trace, under jit: d(RMS spot²)/d(A_i, R) of surface 1 with its first 9
    terms (the second surface a sphere, to compile faster)."""
    one = eqx.tree_at(lambda t: t.surfaces[1], lens, jl.Sphere(-1 / 60))
    one = eqx.tree_at(lambda t: t.surfaces[0].coeffs, one, lens.surfaces[0].coeffs[:9])
    rays = _rays()
    loss = jax.jit(lambda L: _spot_loss(L, rays))
    g = jax.jit(jax.grad(lambda L: _spot_loss(L, rays)))(one)
    for field, idx, h in (("coeffs", (0, 1, 3, 4, 8), 1e-6), ("norm_radius", (None,), 1e-5)):
        get = lambda t, field=field: getattr(t.surfaces[0], field)  # noqa: E731
        v = get(one)
        for j in idx:
            def at(d, j=j, v=v, get=get):
                return float(loss(eqx.tree_at(get, one, v + d if j is None else v.at[j].add(d))))
            fd = (at(h) - at(-h)) / (2 * h)
            gj = float(get(g) if j is None else get(g)[j])
            assert gj != 0.0, (field, j)
            assert gj == pytest.approx(fd, rel=2e-5, abs=1e-12), (field, j)


# --- files -------------------------------------------------------------------------------


def _same(a, b):
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    assert ta == tb
    for x, y in zip(la, lb, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def test_zmx_round_trip_is_exact_and_writes_xpolynom(lens, tmp_path):
    s = eqx.tree_at(lambda t: t.surfaces[0].semi_diameter, lens, jnp.asarray(5.5))
    s = eqx.tree_at(lambda t: t.surfaces[1].coeffs, s, lens.surfaces[1].coeffs / 3.0)
    out = tmp_path / "again.zmx"
    jl.save(s, out)
    again = jl.load(out, strict=True)
    _same(again.surfaces, s.surfaces)
    _same(again.thickness, s.thickness)
    text = out.read_text()
    assert text.count("TYPE XPOLYNOM") == 2 and "jaxlens hybrid" not in text
    assert 'XDAT 1 27 0 0 1 0 0 ""' in text and 'XDAT 2 6.5E+000 0 0 1 0 0 ""' in text
    # lengths x25.4 in inches: R and every A_i (mm of sag on dimensionless coordinates)
    inch = zmx.loads(DATA.read_text().replace("UNIT MM", "UNIT IN"))
    t = inch.surfaces[1]
    assert float(t.norm_radius) == 6.5 * 25.4 and float(t.c) == pytest.approx(1 / (-60 * 25.4))
    _close(t.coeffs, np.asarray(REF["terms"]) * 25.4, 1e-17)
    pts = np.asarray(REF["points"]) * 25.4
    _close(_table(t, pts)[:, 0], _table(lens.surfaces[1], pts / 25.4)[:, 0] * 25.4, 1e-13)


def test_jaxlens_hybrid_still_reads_as_a_hybrid(tmp_path):
    """XPOLYNOM with jaxlens's hybrid comment is a ``Hybrid`` (as before); without it, the
    same polynomial is an ``XYPolynomial`` with the same sag."""
    h = jl.Hybrid(c=0.02, k=-1.5, coeffs=[1e-3, 2e-5], odd_x=[1e-4], odd_y=[-3e-5])
    lens = jl.Lens(surfaces=(h, jl.Plane()), thickness=jnp.array([3.0, 30.0]),
                   materials=(jl.ModelGlass(1.5, 50.0), jl.Air()), epd=4.0)
    jl.save(lens, tmp_path / "h.zmx")
    text = (tmp_path / "h.zmx").read_text()
    assert type(zmx.loads(text).surfaces[0]) is jl.Hybrid
    xy = zmx.loads(re.sub(r"\n *COMM jaxlens hybrid[^\n]*", "", text)).surfaces[0]
    assert type(xy) is XYPolynomial and xy.coeffs.shape == (xy_term_count(4),)
    pts = np.asarray(REF["points"])
    _close(_table(xy, pts), _table(h, pts), 1e-15)


def test_json_round_trip(lens, tmp_path):
    s = eqx.tree_at(lambda t: t.surfaces[0].semi_diameter, lens, jnp.asarray(5.5))
    again = json_round_trip(s, tmp_path)
    assert type(again.surfaces[1]) is XYPolynomial
    d = lensfile.lens_to_dict(s)["surfaces"][1]
    assert d["type"] == "xy_polynomial" and d["norm_radius"] == 6.0
    assert d["polynomial_coeffs"][:2] == [0.012, -0.021] and d["semi_diameter"] == 5.5


# --- bad input ---------------------------------------------------------------------------


@pytest.mark.parametrize("kw, message", [
    (dict(norm_radius=0.0), r"XYPolynomial: norm_radius must be finite numbers in \(0, inf\) "
                            r"mm, got 0"),
    (dict(norm_radius=-2.0), r"norm_radius .* mm, got -2"),
    (dict(norm_radius=jnp.inf), r"norm_radius must be finite numbers in \(0, inf\) mm, got inf"),
    (dict(coeffs=jnp.zeros(231)), r"231 coefficients given; the extended polynomial holds at "
                                  r"most 230 \(degree 20\)"),
    (dict(coeffs=jnp.array([0.1, jnp.nan])), r"XYPolynomial: coeffs must be finite numbers "
                                             r"\(mm\), got nan"),
    (dict(coeffs=jnp.zeros((2, 3))), r"coeffs must be a 1-D array of the coefficients"),
    (dict(c=0.1, semi_diameter=12.0), r"defined only out to r = .* = 10 mm, but its "
                                      r"semi_diameter is 12 mm"),
])
def test_constructor_refuses_bad_values(kw, message):
    args = dict(c=0.02, coeffs=jnp.array([0.0, 1e-3]), norm_radius=5.0) | kw
    with pytest.raises(ValueError, match=message):
        XYPolynomial(**args)


def _line_of(text, start):
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.strip().startswith(start))


@pytest.mark.parametrize("old, new, at, message", [
    ("  XDAT 1 15 ", "  PARM 1 2\n  XDAT 1 15 ", "PARM 1 2",
     r"XPOLYNOM has no parameters \(PARM\)"),
    ("  XDAT 1 15 ", "  XDAT 0 1\n  XDAT 1 15 ", "XDAT 0 1",
     r"XPOLYNOM extra data start at XDAT 1"),
    ("  XDAT 1 15 0 0 0 0 0 \"\"\n", "", "TYPE XPOLYNOM",
     r"XPOLYNOM needs XDAT 1 \(the number of terms\) and XDAT 2 .*; XDAT 1 is missing"),
    ("  XDAT 2 6.0 0 0 0 0 0 \"\"\n", "", "TYPE XPOLYNOM", r"XDAT 2 is missing"),
    ("XDAT 1 15 ", "XDAT 1 231 ", "XDAT 1 231",
     r"XDAT 1 \(the number of extended-polynomial terms\) must be a whole number in 0\.\.230 "
     r"\(degree 20\), got 231"),
    ("XDAT 1 15 ", "XDAT 1 2.5 ", "XDAT 1 2.5", r"must be a whole number in 0\.\.230"),
    ("XDAT 1 15 ", "XDAT 1 -1 ", "XDAT 1 -1", r"got -1"),
    ("XDAT 2 6.0 ", "XDAT 2 0 ", "XDAT 2 0",
     r"XDAT 2 \(the normalisation radius, lens units\) must be > 0, got 0"),
    ("XDAT 2 6.0 ", "XDAT 2 -6 ", "XDAT 2 -6", r"must be > 0, got -6"),
    ("XDAT 1 15 ", "XDAT 1 14 ", "XDAT 17 ",
     r"coefficient beyond the 14 extended-polynomial terms of XDAT 1 \(XDAT 3 … XDAT 16\)"),
])
def test_bad_zmx_data_name_the_file_and_line(tmp_path, old, new, at, message):
    text = DATA.read_text()
    assert old in text
    text = text.replace(old, new, 1)
    path = tmp_path / "bad.zmx"
    path.write_text(text)
    line = _line_of(text, at)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}:{line}: .*{message}"):
        jl.load(path)


@pytest.mark.parametrize("surface, message", [
    ({"type": "xy_polynomial", "polynomial_coeffs": [0.1]},
     r"a xy_polynomial surface with polynomial_coeffs needs norm_radius"),
    ({"type": "xy_polynomial", "norm_radius": -1, "polynomial_coeffs": [0.1]},
     r"norm_radius must be finite numbers in \(0, inf\) mm, got -1"),
    ({"type": "xy_polynomial", "norm_radius": 5, "polynomial_coeffs": [[0.1]]},
     r"polynomial_coeffs must be a flat list"),
    ({"type": "xy_polynomial", "norm_radius": 5, "even_asphere_coeffs": [0.1]},
     r"a xy_polynomial surface does not take even_asphere_coeffs"),
    ({"type": "standard", "polynomial_coeffs": [0.1]},
     r"does not take polynomial_coeffs \(the keys of type xy_polynomial\)"),
])
def test_json_refuses_bad_surfaces(lens, surface, message):
    d = lensfile.lens_to_dict(lens)
    d["surfaces"][1] = {**surface, "thickness": 4.0}
    with pytest.raises(ValueError, match=message):
        lensfile.lens_from_dict(d, source="bad.json")


# --- the analyses (these need the lead's edits outside this task's files: paraxial.x_section,
# backward.mirror_surface, surface_adjoint.SAG_KINDS, report, third_order, lens_keys and the
# jaxlens re-export) ---------------------------------------------------------------------


def test_x_section_mirror_report_and_refusals_know_the_surface(lens):
    from jaxlens.analysis import report
    from jaxlens.analysis.tolerance import zero_perturbation
    from jaxlens.optics import paraxial
    from jaxlens.tracing import surface_adjoint
    from jaxlens.tracing.backward import mirror_surface

    assert jl.XYPolynomial is XYPolynomial
    assert surface_adjoint.supported(lens.surfaces[0])  # the reverse rule's sag step takes it
    assert not surface_adjoint.supported(XYPolynomial(c=0.01))  # no terms: the conic step
    xs = paraxial.x_section(lens)
    for s, t in zip(lens.surfaces, xs.surfaces, strict=True):
        assert type(t) is jl.Standard and float(t.c) == float(s.paraxial_curvature_x)
    assert float(xs.surfaces[0].c) != float(lens.surfaces[0].paraxial_curvature)
    pts = np.asarray(REF["points"])
    for s in lens.surfaces:
        m = mirror_surface(s)
        assert type(m) is XYPolynomial
        _close(_table(m, pts)[:, 0], -_table(s, pts)[:, 0], 1e-15)
    rows = report._surface_table(lens)
    assert "XPOLYNOM" in rows[2] and "R=6 X1Y0=0.012 X0Y1=-0.021 X2Y0=-0.003593" in rows[2]
    with pytest.raises(ValueError, match=r"XY polynomial \(Zemax XPOLYNOM\) is not "
                                         r"rotationally symmetric"):
        jl.analysis.seidel(lens)
    with pytest.raises(ValueError, match=r"surface 1 is a XYPolynomial; tolerance analysis"):
        zero_perturbation(lens)
    d = lensfile.lens_to_dict(lens)
    d["surfaces"][1]["xy_coeffs"] = d["surfaces"][1].pop("polynomial_coeffs")
    with pytest.raises(ValueError, match=r"unknown key 'xy_coeffs'; did you mean "
                                         r"'polynomial_coeffs'"):
        lensfile.lens_from_dict(d, source="bad.json")


@pytest.mark.slow
def test_hand_written_reverse_rule_gives_the_same_gradient(lens):
    """``trace(..., reverse_rule=True)`` (``surface_adjoint``'s sag step) and JAX's own
    derivative of the trace agree (8 s: slow)."""
    one = eqx.tree_at(lambda t: t.surfaces[1], lens, jl.Sphere(-1 / 60))
    one = eqx.tree_at(lambda t: t.surfaces[0].coeffs, one, lens.surfaces[0].coeffs[:9])
    rays = _rays()

    def loss(L, rule):
        out = jl.trace(L, rays, reverse_rule=rule)
        return jnp.sum(jnp.where(out.valid[:, None], out.origin[:, :2], 0.0) ** 2)

    auto = jax.jit(jax.grad(lambda L: loss(L, False)))(one).surfaces[0]
    rule = jax.jit(jax.grad(lambda L: loss(L, True)))(one).surfaces[0]
    for field in ("coeffs", "norm_radius", "c", "k"):
        a, r = np.asarray(getattr(auto, field)), np.asarray(getattr(rule, field))
        assert np.all(a != 0), field
        np.testing.assert_allclose(r, a, rtol=1e-9, atol=1e-12, err_msg=field)
