"""Zemax's negative propagation: ``Lens.negative_propagation`` lets a ray go back along its
line to any surface after the first (``tracing.step.intersect``'s ``go_back``).

With the default rule a ray that would have to travel backward (t < 0) to reach a surface is
lost, except across a negative gap or to a dummy surface on the previous vertex plane. Zemax
(and optiland) trace it on; the ``.zmx`` reader sets the flag. Checked here:

* a two-surface lens built by hand (a convex front R = 10 mm, 1 mm thick at the axis, and a
  back surface R = −20 mm): a ray 6 mm off the axis meets the front surface 2 mm past its
  vertex, 1 mm past the back surface's vertex plane, and reaches the back surface only by
  going back. Default: the ray is lost there; with the flag its point and direction on the
  back surface equal an analytic computation (Snell's law at the front, then the
  line–sphere root on the back sphere's vertex sheet) and optiland's;
* the gradient of that ray with respect to a curvature (both tracers: ``surface_step``'s
  derivative and the hand-written reverse rule) against central finite differences;
* the corpus7 Nikon 105 mm f/2 (``/work/zmx_probe/corpus7``, not committed; skipped where it
  is absent): rays at the full pupil, lost beyond surface 6 by the default rule, pass with
  the flag, and every ray's image intercept equals optiland's;
* a lens with the flag is refused by the design parameterisation (which penalises crossed
  surfaces), and the flag survives JSON save and load.

optiland's values are in ``tests/data/zemax_crossing_optiland.json``, written by this module
run as a script with an interpreter that has optiland 0.6.3 (the tests do not need it):

    PYTHONPATH=. /work/optiland_venv/bin/python tests/test_zemax_crossing.py
"""

from __future__ import annotations

import dataclasses
import json
import math
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.materials import Air, ModelGlass

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = os.path.join(HERE, "data", "zemax_crossing_optiland.json")
NIKON = "/work/zmx_probe/corpus7/fusionoptics_Nikonf105mmN2_trimmed.ZMX"
WL = 0.5875618  # µm: the d line, where ModelGlass(1.5, 60) has n = 1.5 exactly
C1, C2, GAP = 0.1, -0.05, 1.0  # front and back curvatures (1/mm), centre thickness (mm)
HEIGHTS = (2.0, 6.0, 7.0)  # ray heights (mm): 2 mm traced forward, 6 and 7 mm go back


def two_surface(go_back: bool, c2=C2, newton=False) -> jl.Lens:
    """The hand-built lens; ``newton``: its back surface an ``EvenAsphere`` with zero
    coefficients (the same sphere, intersected by Newton's method)."""
    back = (jl.EvenAsphere(c=c2, coeffs=jnp.zeros(2)) if newton else jl.Standard(c=c2))
    return jl.Lens(
        surfaces=(jl.Standard(c=C1), back),
        thickness=jnp.asarray([GAP, 30.0]),
        materials=(ModelGlass(1.5, 60.0), Air()),
        epd=jnp.asarray(16.0), wavelengths=jnp.asarray([WL]),
        negative_propagation=go_back)


def two_surface_rays() -> jl.Rays:
    h = jnp.asarray(HEIGHTS)
    o = jnp.stack([jnp.zeros_like(h), h, jnp.full_like(h, -5.0)], -1)
    return jl.Rays(o, jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), o.shape), WL)


def analytic(h: float, n: float = 1.5):
    """The ray at height h, parallel to the axis, after the front surface and at the back
    surface (vertex sheet), in float64 numpy: (point on the back surface, direction in the
    glass, direction after the back surface)."""
    r1, r2 = 1 / C1, 1 / C2
    p1 = np.array([0.0, h, r1 - math.sqrt(r1 * r1 - h * h)])

    def snell(d, normal, mu):
        nrm = normal / np.linalg.norm(normal)
        if nrm @ d < 0:
            nrm = -nrm
        cos_i = nrm @ d
        return mu * d + (math.sqrt(1 - mu * mu * (1 - cos_i * cos_i)) - mu * cos_i) * nrm

    d1 = snell(np.array([0.0, 0.0, 1.0]), np.array([0.0, -C1 * p1[1], 1 - C1 * p1[2]]), 1 / n)
    centre = np.array([0.0, 0.0, GAP + r2])  # the back sphere: vertex at z = GAP, radius |r2|
    oc = p1 - centre
    b, c = oc @ d1, oc @ oc - r2 * r2
    roots = [-b - math.sqrt(b * b - c), -b + math.sqrt(b * b - c)]
    # The vertex sheet of c2 < 0 is the half z ≥ the centre's z (1 − c2·z_local ≥ 0).
    t = [s for s in roots if (p1 + s * d1)[2] >= centre[2]]
    assert len(t) == 1
    p2 = p1 + t[0] * d1
    d2 = snell(d1, np.array([0.0, -C2 * p2[1], 1 - C2 * (p2[2] - GAP)]), n)
    return p2, d1, d2, t[0]


def _reference():
    if not os.path.exists(REFERENCE):
        pytest.fail(f"{REFERENCE} is missing: run this module as a script with optiland")
    with open(REFERENCE, encoding="utf-8") as f:
        return json.load(f)


# --------------------------------------------------------------- the hand-built lens

@pytest.mark.parametrize("reverse_rule", [False, True])
@pytest.mark.parametrize("newton", [False, True])
def test_default_rule_loses_the_ray_and_the_flag_traces_it_like_zemax(reverse_rule, newton):
    rays = two_surface_rays()
    old = jl.trace_path(two_surface(False, newton=newton), rays, reverse_rule=reverse_rule)
    new = jl.trace_path(two_surface(True, newton=newton), rays, reverse_rule=reverse_rule)
    # Default: the 2 mm ray passes; the 6 and 7 mm rays are lost at the back surface.
    assert np.asarray(old.valid[1]).tolist() == [True, False, False]
    assert np.asarray(new.valid).all()
    # A ray the default traces takes the same root (to rounding: the programs differ).
    for a, b in ((old.origin, new.origin), (old.direction, new.direction), (old.opl, new.opl)):
        np.testing.assert_allclose(np.asarray(b)[:, 0], np.asarray(a)[:, 0], rtol=0, atol=1e-13)
    for k, h in enumerate(HEIGHTS):
        p2, d1, d2, t = analytic(h)
        assert (t < 0) == (h > 2.0)  # the back surface lies behind the rays at 6 and 7 mm
        np.testing.assert_allclose(np.asarray(new.direction[0, k]), d1, rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.asarray(new.origin[1, k]), p2, rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.asarray(new.direction[1, k]), d2, rtol=0, atol=1e-13)
        # The optical path counts the backward leg as negative: n·t with t < 0.
        leg = float(new.opl[1, k] - new.opl[0, k])
        assert leg == pytest.approx(1.5 * t, abs=1e-12)


def test_two_surface_lens_matches_optiland_per_surface():
    ref = _reference()["two_surface"]
    rays = two_surface_rays()
    new = jl.trace_path(two_surface(True), rays)
    assert np.allclose(ref["origins"], np.asarray(rays.origin), atol=0)
    for i, (pts, dirs) in enumerate(zip(ref["points"], ref["directions"], strict=True)):
        np.testing.assert_allclose(np.asarray(new.origin[i]), pts, rtol=0, atol=1e-9)
        np.testing.assert_allclose(np.asarray(new.direction[i]), dirs, rtol=0, atol=1e-12)
    assert np.asarray(ref["valid"]).all()


@pytest.mark.parametrize("reverse_rule, newton", [
    (False, False), (True, False), (False, True),
    pytest.param(True, True, marks=pytest.mark.slow)])
def test_gradient_of_a_backward_ray_matches_finite_differences(reverse_rule, newton):
    rays = two_surface_rays()

    def image_y(c2):
        out = jl.trace(two_surface(True, c2, newton), rays, reverse_rule=reverse_rule)
        return out.origin[:, 1], out.valid

    y, valid = image_y(jnp.asarray(C2))
    assert np.asarray(valid).all()
    g = jax.jacrev(lambda c: image_y(c)[0])(jnp.asarray(C2))
    e = 1e-6
    fd = (np.asarray(image_y(jnp.asarray(C2 + e))[0]) - np.asarray(image_y(jnp.asarray(C2 - e))[0]))
    fd = fd / (2 * e)
    np.testing.assert_allclose(np.asarray(g), fd, rtol=1e-6, atol=1e-6)
    assert np.all(np.abs(np.asarray(g)[1:]) > 1.0)  # the backward rays do depend on c2


@pytest.mark.slow
def test_the_flag_changes_nothing_in_a_lens_whose_rays_all_go_forward():
    # The same rays valid, the same roots: equal to rounding (1.8e-15 mm measured; the
    # compiled programs differ, so XLA may round differently).
    lens = jl.zoo.cooke_triplet()
    pupil = jl.sampling.pupil_grid(5)
    rays = jl.sampling.field_rays(lens, jnp.asarray(14.0), pupil, WL)
    old = jl.trace(lens, rays)
    new = jl.trace(dataclasses.replace(lens, negative_propagation=True), rays)
    assert np.array_equal(np.asarray(old.valid), np.asarray(new.valid))
    assert np.asarray(old.valid).all()
    for a, b in ((old.origin, new.origin), (old.direction, new.direction), (old.opl, new.opl)):
        np.testing.assert_allclose(np.asarray(b), np.asarray(a), rtol=0, atol=1e-12)


def test_the_flag_is_a_checked_static_bool():
    lens = two_surface(True)
    assert lens.negative_propagation is True and two_surface(False).negative_propagation is False
    assert jl.Lens(surfaces=lens.surfaces, thickness=lens.thickness,
                   materials=lens.materials).negative_propagation is False
    with pytest.raises(TypeError, match="negative_propagation must be True or False"):
        dataclasses.replace(lens, negative_propagation=1)
    # Static: not a leaf of the pytree.
    assert len(jax.tree.leaves(lens)) == len(jax.tree.leaves(two_surface(False)))
    # The backward (sensor to object) trace's mirrored lens keeps it.
    from jaxlens.tracing.backward import reversed_lens
    assert reversed_lens(lens).negative_propagation is True


def test_backward_trace_retraces_a_ray_that_went_back():
    # The 6 and 7 mm rays, reversed at the image, go back through the mirrored lens to
    # where they met surface 1 (the backward trace honours the flag); by the default rule
    # the mirrored lens loses them too.
    from jaxlens.tracing.backward import trace_backward
    rays = two_surface_rays()
    for go_back in (True, False):
        lens = two_surface(go_back)
        path = jl.trace_path(two_surface(True), rays)
        img = jl.Rays(path.origin[-1], -path.direction[-1], WL)
        back = trace_backward(lens, img)
        if go_back:
            assert np.asarray(back.valid).all()
            np.testing.assert_allclose(np.asarray(back.origin), np.asarray(path.origin[0]),
                                       rtol=0, atol=1e-11)
            np.testing.assert_allclose(np.asarray(back.direction), -np.asarray(rays.direction),
                                       rtol=0, atol=1e-12)
        else:
            assert np.asarray(back.valid).tolist() == [True, False, False]


# ----------------------------------------------------------------- design and files

def test_design_parameterisation_refuses_the_flag():
    from jaxlens.design import init
    from jaxlens.design.params import Parameterization
    from jaxlens.design.spec import DesignSpec
    spec = DesignSpec()
    pmap = init.parameterization(spec)
    lens = dataclasses.replace(pmap.template, negative_propagation=True)
    with pytest.raises(ValueError, match="negative_propagation"):
        Parameterization(template=lens, r_norm=pmap.r_norm, total_track=pmap.total_track,
                         optical=pmap.optical)


def test_json_round_trip_keeps_the_flag_and_old_files_load_without_it(tmp_path):
    for flag in (False, True):
        p = tmp_path / f"lens_{flag}.json"
        jl.save(two_surface(flag), p)
        text = p.read_text()
        assert ('"negative_propagation": true' in text) == flag
        assert jl.load(p).negative_propagation is flag
    # A file written before the key existed (the key absent) loads with the default rule.
    assert "negative_propagation" not in (tmp_path / "lens_False.json").read_text()


def test_a_zmx_file_sets_the_flag_and_zmx_write_round_trips_it(tmp_path):
    from jaxlens.io import zmx
    text = ("VERS 90609\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 16\nFTYP 0 0 1 1 0 0 0\n"
            "XFLN 0\nYFLN 0\nWAVM 1 0.5875618 1\nPWAV 1\n"
            "SURF 0\n  CURV 0\n  DISZ INFINITY\n"
            "SURF 1\n  STOP\n  CURV 0.1\n  DISZ 1\n  GLAS ___BLANK 1 0 1.5 60 0 0 0 0 0 0\n"
            "SURF 2\n  CURV -0.05\n  DISZ 30\nSURF 3\n  CURV 0\n  DISZ 0\n")
    lens = zmx.loads(text, "two.zmx", strict=True)
    assert lens.negative_propagation is True
    p = tmp_path / "two.zmx"
    jl.save(lens, p)
    assert jl.load(p).negative_propagation is True
    out = jl.trace(lens, two_surface_rays())
    assert np.asarray(out.valid).all()


# ------------------------------------------------------------- the corpus7 Nikon 105 mm

@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists(NIKON), reason="the corpus7 files are not committed")
def test_nikon_105_full_pupil_rays_pass_and_match_optiland():
    from jaxlens.io.zmx import ZmxWarning
    from jaxlens.optics.lens import unclipped
    ref = _reference()["nikon105"]
    with pytest.warns(ZmxWarning, match="weighs its 2 fields"):  # the file's field weights
        lens = jl.load(NIKON)
    assert lens.negative_propagation is True
    default = dataclasses.replace(lens, negative_propagation=False)
    rim_old = rim_new = rim_all = 0
    for rec in ref["fields"]:
        rays = jl.Rays(jnp.asarray(rec["origins"]), jnp.asarray(rec["directions"]), rec["wl"])
        new = jl.trace(unclipped(lens), rays)
        old = jl.trace(unclipped(default), rays)
        ok = np.asarray(rec["valid"])
        assert np.asarray(new.valid).tolist() == ok.tolist()
        both = ok & np.asarray(new.valid)
        diff = np.abs(np.asarray(new.origin)[both] - np.asarray(rec["image"])[both])
        assert diff.max() < 1e-9
        rim = np.asarray(rec["rim"])
        rim_all += int(rim.sum())
        rim_new += int((np.asarray(new.valid) & rim).sum())
        rim_old += int((np.asarray(old.valid) & rim).sum())
        # A ray the default rule traces takes the same root (to rounding).
        same = np.asarray(old.valid)
        assert np.all(np.asarray(new.valid)[same])
        np.testing.assert_allclose(np.asarray(new.origin)[same], np.asarray(old.origin)[same],
                                   rtol=0, atol=1e-12)
    # Full pupil (the rim rays): the default rule lost a part of them; with the flag every
    # rim ray optiland passes passes.
    assert rim_new == ref["rim_valid_optiland"] and rim_new > rim_old
    assert rim_old / rim_all == pytest.approx(ref["rim_valid_fraction_default"], abs=1e-12)


# ------------------------------------------------------------ the reference (optiland)

def _optiland_two_surface():
    """optiland's points and directions after each surface of ``two_surface``."""
    from optiland.materials import IdealMaterial
    from optiland.optic import Optic
    from optiland.rays import RealRays

    lens = two_surface(True)
    n = [abs(float(x)) for x in lens.indices(jnp.asarray(WL))]
    op = Optic()
    op.add_surface(index=0, thickness=np.inf, material=IdealMaterial(n=n[0]))
    op.add_surface(index=1, radius=1 / C1, thickness=GAP, material=IdealMaterial(n=n[1]),
                   is_stop=True)
    op.add_surface(index=2, radius=1 / C2, thickness=30.0, material=IdealMaterial(n=n[2]))
    op.add_surface(index=3)
    op.set_aperture(aperture_type="EPD", value=16.0)
    op.set_field_type(field_type="angle")
    op.add_field(y=0.0)
    op.add_wavelength(value=WL, is_primary=True)
    rays = two_surface_rays()
    o, d = np.asarray(rays.origin), np.asarray(rays.direction)
    m = len(o)
    rr = RealRays(*o.T.copy(), *d.T.copy(), np.ones(m), np.full(m, WL))
    sg = op.surfaces
    sg.trace(rr, skip=1, record=True)

    def rows(a):  # [surfaces after the object, rays] (as tools/check_rays.py reads them)
        a = np.asarray(a)
        return a[1:] if a.shape[0] == sg.num_surfaces else a

    pts = np.stack([rows(sg.x), rows(sg.y), rows(sg.z)], -1)
    dirs = np.stack([rows(sg.L), rows(sg.M), rows(sg.N)], -1)
    ok = np.isfinite(pts).all(-1).all(0) & (rows(sg.intensity)[-1] > 0)
    return {"origins": o.tolist(), "points": pts.tolist(), "directions": dirs.tolist(),
            "valid": ok.tolist()}


def _optiland_nikon():
    """Rays at each field of the Nikon file (primary wavelength): a 7 × 7 pupil grid and a
    ring of 24 at the full pupil, started 50 mm before surface 1; optiland's image
    intercepts (apertures removed in both codes, as in tools/check_rays.py)."""
    import sys
    sys.path.insert(0, os.path.join(HERE, "..", "tools"))
    import check_rays as cr

    lens = jl.load(NIKON)
    optic, note = cr.optiland_optic(NIKON)
    assert optic is not None, note
    cr._strip_apertures(optic)
    cr._tighten_newton(optic)
    own = [s.material_post for s in optic.surfaces.surfaces]
    wl = float(lens.wavelengths[lens.primary])
    ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = (1 - 1e-9) * np.stack([np.cos(ang), np.sin(ang)], -1)
    pupil = np.concatenate([np.asarray(jl.sampling.pupil_grid(7)) * (1 - 1e-9), ring])
    rim = np.r_[np.zeros(len(pupil) - len(ring), bool), np.ones(len(ring), bool)]
    fields, rim_ok, rim_old, rim_all = [], 0, 0, 0
    from jaxlens.optics.lens import unclipped
    default = dataclasses.replace(lens, negative_propagation=False)
    for field in np.asarray(lens.fields):
        r = jl.sampling.field_rays(lens, jnp.asarray(field), jnp.asarray(pupil), wl)
        o, d = np.asarray(r.origin), np.asarray(r.direction)
        o = o + ((-50.0 - o[:, 2]) / d[:, 2])[:, None] * d
        cr.set_media(optic, lens, wl, own)
        p, ok, _, _ = cr.optiland_image(optic, o, d, wl, 1.0, np.zeros(3))
        old = np.asarray(jl.trace(unclipped(default), jl.Rays(o, d, wl)).valid)
        rim_ok += int((ok & rim).sum())
        rim_old += int((old & rim).sum())
        rim_all += int(rim.sum())
        fields.append({"field": np.atleast_1d(field).tolist(), "wl": wl, "origins": o.tolist(),
                       "directions": d.tolist(), "image": np.where(ok[:, None], p, 0).tolist(),
                       "valid": ok.tolist(), "rim": rim.tolist()})
    return {"fields": fields, "rim_valid_optiland": rim_ok,
            "rim_valid_fraction_default": rim_old / rim_all}


if __name__ == "__main__":
    jax.config.update("jax_enable_x64", True)
    out = {"two_surface": _optiland_two_surface(), "nikon105": _optiland_nikon()}
    with open(REFERENCE, "w", encoding="utf-8") as f:
        json.dump(out, f, indent=0)
        f.write("\n")
    print("wrote", REFERENCE, "rim rays passing (optiland):", out["nikon105"]["rim_valid_optiland"],
          "default rule's fraction:", out["nikon105"]["rim_valid_fraction_default"])
