"""Aberration conventions against optiland 0.6.3 (Zemax OpticStudio's conventions).

The reference numbers in ``tests/data/conventions_optiland.json`` were computed by optiland
0.6.3 with

    /work/optiland_venv/bin/python tools/conventions_reference.py \
        --out tests/data/conventions_optiland.json

on four lenses built from ``tests/refcases/`` (optiland reads the glasses from its own
catalogs under the names the files give, so the indices are the files' tables): the Cooke
triplet, the double Gauss, the double Gauss with its object 300 mm before surface 1, and
the Cooke triplet with even aspheres (conic, r⁴, r⁶) on surfaces 1 and 6. Each test
states the relation it checks: equality where jaxlens follows the same convention, and the
exact conversion where it does not:

- Seidel: optiland's per-surface transverse terms TSC, CC, TPC, DC, TAchC, TchC are
  jaxlens's TSPH, TSCO, TPFC, TDIS, TAXC, TLAC, its TAC is TAST/2, and its ``seidels()``
  are −(S_I … S_V) (jaxlens keeps Welford's sign, which Zemax's Seidel coefficients use:
  S_I > 0 for a positive singlet). optiland leaves out the r⁴ term of an even asphere:
  the difference is Welford's δS = 8 a₄ Δn y⁴ (ȳ/y)^k exactly.
- OPD: the same sign (chief-ray path minus ray path, positive where the wavefront is
  ahead of the reference sphere) and reference sphere.
- Ray fans, field curvature, encircled energy: the same definitions.
- Distortion: optiland's (and Zemax's) "F-Tan" is ``percent_paraxial``, its "F-Theta"
  ``percent_ftheta``; ``percent_ftan`` (against n·EFL·tanθ) is related by the heights.
- Zernike: jaxlens "noll" is Zemax's Standard (optiland "noll"), "ansi" is optiland's
  "standard"; "fringe" agrees over 36 terms, and optiland's Fringe Z37 (R_6^6 cos 6θ, the
  formula continued) is not Zemax's Z37 (R_12^0), which jaxlens uses.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.analysis import aberrations, encircled, spots, third_order, zernike
from jaxlens.analysis import wavefront_error as wfe
from jaxlens.optics.surfaces import EvenAsphere

ROOT = Path(__file__).resolve().parents[1]
REF = json.loads((ROOT / "tests" / "data" / "conventions_optiland.json").read_text())
CASES = REF["cases"]


def cases(*fast: str) -> list:
    """Every case, those not named in ``fast`` marked slow: each lens and analysis compiles
    its own program (3 to 7 s on 2 busy cores), so CI runs the Cooke triplet's Seidel, OPD
    and distortion (the conventions not checked against optiland elsewhere) and the rest
    goes to ``-m slow`` (ray fans and field curvature of the Cooke triplet and the double
    Gauss are also checked in tests/test_aberrations.py)."""
    return [n if n in fast else pytest.param(n, marks=pytest.mark.slow) for n in CASES]


def _lens(name: str, *, polynomial: bool = True) -> jaxlens.Lens:
    """The jaxlens lens of a reference case (``polynomial=False``: the aspheres' r⁴, r⁶
    terms dropped, their conics kept)."""
    c = CASES[name]
    lens = jaxlens.load(ROOT / c["source"])
    if c["object_distance_mm"] is not None:
        lens = dataclasses.replace(lens, object_distance=c["object_distance_mm"])
    if c["aspheres"]:
        surfs = list(lens.surfaces)
        for i, (k, a) in c["aspheres"].items():
            s = surfs[int(i) - 1]
            coeffs = jnp.asarray(a) if polynomial else jnp.zeros(len(a))
            surfs[int(i) - 1] = EvenAsphere(c=s.c, k=k, coeffs=coeffs)
        lens = dataclasses.replace(lens, surfaces=tuple(surfs))
    return lens


_LENSES: dict = {}


def lens_of(name: str, **kw) -> jaxlens.Lens:
    key = (name, tuple(sorted(kw.items())))
    if key not in _LENSES:
        _LENSES[key] = _lens(name, **kw)
    return _LENSES[key]


def _top(name):
    return max(CASES[name]["fields_deg"])


# --------------------------------------------------------------------------------------
# Seidel
# --------------------------------------------------------------------------------------
def _as_optiland(s: third_order.Seidel) -> dict:
    t = np.asarray(s.transverse(per_surface=True))
    return {"TSC": t[0], "CC": t[1], "TAC": t[3] / 2, "TPC": t[4], "DC": t[7],
            "TAchC": t[8], "TchC": t[9]}


@pytest.mark.parametrize("name", cases("cooke_triplet"))
def test_seidel_per_surface(name):
    """Per-surface transverse third-order terms, the sums' sign and n′u′ (spherical lenses,
    and the asphere lens with its polynomial terms dropped: optiland ignores them)."""
    c = CASES[name]["seidel"]
    s = third_order.seidel(lens_of(name, polynomial=False))
    ours = _as_optiland(s)
    for term, v in ours.items():
        ref = np.asarray(c[term])
        np.testing.assert_allclose(v, ref, rtol=0, atol=1e-12 * max(1.0, np.abs(ref).max()),
                                   err_msg=f"{name} {term}")
    # optiland's seidels() = −(S_I … S_V); image space is air here, so n′u′ = u′.
    np.testing.assert_allclose(-np.asarray(s.sums[:5]), c["seidels"], rtol=0, atol=1e-13)
    assert float(s.image_nu) == pytest.approx(c["image_u"], abs=1e-14)


@pytest.mark.slow
def test_seidel_even_asphere_r4_term():
    """With the r⁴ terms, jaxlens minus optiland (which leaves them out) is exactly
    Welford's aspheric contribution 8 a₄ Δn y⁴ (ȳ/y)^k over 2n′u′ (k = 0, 1, 2, 3 for
    TSPH, TSCO, TAST/2, TDIS; nothing for Petzval and colour)."""
    import jaxlens.optics.paraxial as px

    lens = lens_of("cooke_asphere")
    s = third_order.seidel(lens)
    ours = _as_optiland(s)
    c = CASES["cooke_asphere"]["seidel"]
    wl = lens.primary_wavelength
    y, _ = px.marginal_ray(lens, wl)
    yb, _ = px.paraxial_chief_ray(lens, s.field, wl)
    n = np.asarray([float(v) for v in px.signed_indices(lens, wl)])
    a4 = np.zeros(lens.num_surfaces)
    for i, (_, a) in CASES["cooke_asphere"]["aspheres"].items():
        a4[int(i) - 1] = a[1]
    ds1 = 8 * a4 * (n[1:] - n[:-1]) * np.asarray(y) ** 4
    ratio = np.asarray(yb) / np.asarray(y)
    k = 1.0 / (2.0 * float(s.image_nu))
    expect = {"TSC": ds1 * k, "CC": ds1 * ratio * k, "TAC": ds1 * ratio**2 * k,
              "DC": ds1 * ratio**3 * k, "TPC": 0 * ds1, "TAchC": 0 * ds1, "TchC": 0 * ds1}
    assert np.abs(expect["TSC"]).max() > 1e-3  # the r⁴ terms matter here
    for term, e in expect.items():
        np.testing.assert_allclose(ours[term] - np.asarray(c[term]), e, rtol=0, atol=1e-12,
                                   err_msg=term)


# --------------------------------------------------------------------------------------
# OPD, Zernike
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", cases("cooke_triplet"))
def test_opd_points(name):
    """OPD (waves) at the reference pupil points of every field: same sign and sphere."""
    lens, c = lens_of(name), CASES[name]
    pts = jnp.asarray(REF["points"])
    fields = jnp.asarray([float(f) for f in c["opd"]])
    got = np.stack([np.asarray(wfe.opd(lens, f, pts)) for f in fields])
    ref = np.asarray(list(c["opd"].values()))
    np.testing.assert_allclose(got, ref, rtol=0, atol=5e-9)
    assert np.abs(ref).max() > 0.5  # not a trivially small wavefront
    if "opd_F_line_full_field" in c:  # another wavelength: its own chief ray and sphere
        w = wfe.opd(lens, _top(name), pts, wavelength=min(c["wavelengths_um"]))
        np.testing.assert_allclose(w, c["opd_F_line_full_field"], rtol=0, atol=5e-9)


def _hexapolar():
    h = REF["hexapolar"]
    x, y = [0.0], [0.0]
    for i in range(h["rings"]):  # optiland's hexapolar grid: ring i of 6i points
        t = np.linspace(0.0, 2 * np.pi, 6 * (i + 1) + 1)[:-1]
        r = (i + 1) / h["rings"]
        x += list(r * np.cos(t))
        y += list(r * np.sin(t))
    x, y = np.asarray(x), np.asarray(y)
    np.testing.assert_allclose(x, h["x"], atol=1e-15)
    np.testing.assert_allclose(y, h["y"], atol=1e-15)
    return x, y


@pytest.mark.parametrize("name", cases())
def test_zernike_of_wavefront(name):
    """Zernike fits of the full field's OPD over optiland's hexapolar points: Noll (Zemax
    Standard), OSA/ANSI (optiland's "standard") and 36 Fringe terms agree; optiland's
    37-term Fringe set is jaxlens's first 36 plus R_6^6 cos 6θ, not Zemax's Z37 = R_12^0."""
    lens, c = lens_of(name), CASES[name]["zernike"]
    x, y = _hexapolar()
    w = wfe.opd(lens, _top(name), jnp.stack([jnp.asarray(x), jnp.asarray(y)], -1))
    for key, indexing, terms in (("noll", "noll", 37), ("standard", "ansi", 36),
                                 ("fringe36", "fringe", 36)):
        fit = zernike.zernike_fit(x, y, w, terms=terms, indexing=indexing)
        np.testing.assert_allclose(fit.coefficients, c[key], rtol=0, atol=2e-9,
                                   err_msg=key)
    a = np.asarray(zernike.zernike_terms(x, y, terms=36, indexing="fringe"))
    rho6cos6 = np.real((x + 1j * y) ** 6)
    a = np.concatenate([a, rho6cos6[:, None]], -1)
    coef = np.linalg.lstsq(a, np.asarray(w), rcond=None)[0]
    np.testing.assert_allclose(coef, c["fringe37"], rtol=0, atol=2e-9)
    # jaxlens's Fringe Z37 is Zemax's R_12^0, and R_6^6 cos 6θ is none of its 37 terms.
    nm = zernike.zernike_fit(x, y, w, terms=37, indexing="fringe").nm
    assert nm[36] == (12, 0) and (6, 6) not in nm


def test_zemax_standard_and_fringe_tables():
    """The terms as OpticStudio's Zernike Standard and Fringe listings print them (A from
    +x toward +y): Standard Z2 = 4^½ ρ cos A, Z3 = 4^½ ρ sin A, Z5 = 6^½ ρ² sin 2A, Z6 =
    6^½ ρ² cos 2A, Z7 = 8^½ (3ρ³ − 2ρ) sin A, Z11 = 5^½ (6ρ⁴ − 6ρ² + 1); Fringe Z5 = ρ² cos
    2A, Z6 = ρ² sin 2A, Z7 = (3ρ³ − 2ρ) cos A, Z9 = 6ρ⁴ − 6ρ² + 1, Z37 = 924ρ¹² − 2772ρ¹⁰ +
    3150ρ⁸ − 1680ρ⁶ + 420ρ⁴ − 42ρ² + 1."""
    r, a = 0.83, 0.61
    x, y = r * math.cos(a), r * math.sin(a)
    std = np.asarray(zernike.zernike_terms(jnp.asarray(x), jnp.asarray(y), terms=11))
    expect = {2: 2 * r * math.cos(a), 3: 2 * r * math.sin(a),
              5: math.sqrt(6) * r**2 * math.sin(2 * a), 6: math.sqrt(6) * r**2 * math.cos(2 * a),
              7: math.sqrt(8) * (3 * r**3 - 2 * r) * math.sin(a),
              11: math.sqrt(5) * (6 * r**4 - 6 * r**2 + 1)}
    for j, v in expect.items():
        assert std[j - 1] == pytest.approx(v, abs=1e-14), j
    fr = np.asarray(zernike.zernike_terms(jnp.asarray(x), jnp.asarray(y), terms=37,
                                          indexing="fringe"))
    p = r * r
    expect = {5: p * math.cos(2 * a), 6: p * math.sin(2 * a), 7: (3 * r**3 - 2 * r) * math.cos(a),
              9: 6 * p * p - 6 * p + 1,
              37: 924 * p**6 - 2772 * p**5 + 3150 * p**4 - 1680 * p**3 + 420 * p**2 - 42 * p + 1}
    for j, v in expect.items():
        assert fr[j - 1] == pytest.approx(v, abs=1e-12), j


# --------------------------------------------------------------------------------------
# Ray fans, field curvature, distortion, encircled energy
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", cases())
def test_ray_fans(name):
    """Tangential e_y and sagittal e_x (mm) at every wavelength, against the primary
    wavelength's chief ray (lateral colour shows as an offset)."""
    lens, c = lens_of(name), CASES[name]
    wls = jnp.asarray(c["wavelengths_um"])
    for th, per_wl in c["fans"].items():
        rf = aberrations.ray_fan(lens, float(th), wls, n=REF["fan_points"])
        for k, ref in enumerate(per_wl.values()):
            np.testing.assert_allclose(rf.tangential[k], ref["tangential"], rtol=0, atol=1e-11)
            np.testing.assert_allclose(rf.sagittal[k], ref["sagittal"], rtol=0, atol=1e-11)


@pytest.mark.parametrize("name", cases())
def test_field_curvature(name):
    """Tangential and sagittal foci (mm along z from the image surface), every wavelength.
    optiland takes parabasal rays at ±1e-5 of the pupil (its tangential foci carry
    ~4e-8 mm of that difference); jaxlens differentiates exactly."""
    lens, c = lens_of(name), CASES[name]
    fc = c["field_curvature"]
    got = aberrations.field_curvature(lens, jnp.asarray(fc["fields_deg"]),
                                      jnp.asarray(c["wavelengths_um"]))
    np.testing.assert_allclose(got.tangential, fc["tangential"], rtol=0, atol=1e-7)
    np.testing.assert_allclose(got.sagittal, fc["sagittal"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", cases("cooke_triplet"))
def test_distortion(name):
    """optiland's (Zemax's) F-Tan is ``percent_paraxial``, its F-Theta ``percent_ftheta``;
    ``percent_ftan`` follows from the heights."""
    lens, c = lens_of(name), CASES[name]["distortion"]
    fields = jnp.asarray(c["hy"]) * _top(name)
    d = spots.distortion(lens, fields)
    np.testing.assert_allclose(d.percent_paraxial, c["f-tan"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(d.percent_ftheta, c["f-theta"], rtol=0, atol=1e-9)
    ratio = np.asarray(d.paraxial_height)[1:] / np.asarray(d.f_tan)[1:]
    np.testing.assert_allclose(1 + np.asarray(d.percent_ftan)[1:] / 100,
                               (1 + np.asarray(c["f-tan"])[1:] / 100) * ratio, rtol=1e-12)


@pytest.mark.parametrize("name", cases())
def test_geometric_encircled_energy(name):
    """Zemax's geometric encircled energy (equal-energy rays, about their centroid) over
    optiland's hexapolar rays: the same fractions."""
    lens, c = lens_of(name), CASES[name]["encircled"]
    pts = [(0.0, 0.0)]
    for i in range(c["rings"]):
        t = np.linspace(0.0, 2 * np.pi, 6 * (i + 1) + 1)[:-1]
        r = (i + 1) / c["rings"]
        pts += list(zip(r * np.cos(t), r * np.sin(t), strict=True))
    assert len(pts) == c["rays"]
    ee = encircled.encircled_energy(lens, _top(name), jnp.asarray(c["radii_mm"]),
                                    pupil=jnp.asarray(pts))
    np.testing.assert_allclose(ee.energy, c["energy"], rtol=0, atol=1e-12)


@pytest.mark.slow
def test_ftheta_distortion_of_field_pairs():
    """(θx, θy) fields give the radial F-Theta distortion of the same radial angle along y."""
    lens = lens_of("cooke_triplet")
    t = np.tan(np.deg2rad(9.0))
    diag = float(np.rad2deg(np.arctan(np.hypot(t, t))))
    d1 = spots.distortion(lens, jnp.array([0.0, 9.0, 14.0, diag]))
    d2 = spots.distortion(lens, jnp.array([[0.0, 0.0], [9.0, 0.0], [0.0, -14.0], [9.0, 9.0]]))
    np.testing.assert_allclose(d2.percent_ftheta, d1.percent_ftheta, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(d2.f_theta, d1.f_theta, rtol=1e-9, atol=1e-12)
    neg = spots.distortion(lens, jnp.array([-14.0]))  # a field below the axis: same percent
    assert float(neg.percent_ftheta[0]) == pytest.approx(float(d1.percent_ftheta[2]), abs=1e-12)
    assert float(neg.f_theta[0]) == pytest.approx(-float(d1.f_theta[2]), abs=1e-12)
