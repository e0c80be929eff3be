"""Element decenter and tilt tolerances (``jaxlens.analysis.tolerance_rigid``): zero motion is
the nominal lens, a decentered singlet and a tilted plate against their analytic answers,
autodiff sensitivities against central differences, the mirror symmetry of the metric, and
the Monte-Carlo with a key.
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import tolerance_rigid as rigid

T = jl.tolerance
WL = 0.5875618
PUPIL = jl.sampling.pupil_grid(7, jnp.float64)
GRID = np.stack(np.meshgrid([-14.0, 0.0, 14.0], [-14.0, 0.0, 14.0]), -1).reshape(-1, 2)
ON = T.Tolerances(decenter=0.02, tilt=0.05)


def _triplet():
    return jl.load("jaxlens/data/lenses/cooke_triplet.json").astype(jnp.float64)


def _singlet(c=0.02, t=4.0, back=50.0, obj=None, epd=1.0):
    glass = jl.get_material("N-BK7")
    return jl.Lens(surfaces=(jl.Sphere(c), jl.Sphere(-c)), thickness=jnp.asarray([t, back]),
                   materials=(glass, jl.Air()), epd=epd, wavelengths=(WL,),
                   object_distance=obj).astype(jnp.float64)


def _vec(model, **entries):
    """A perturbation vector with the named rigid entries set (name -> {element: value})."""
    p = model.unravel(model.zero)
    for name, values in entries.items():
        arr = getattr(p, name)
        for j, v in values.items():
            arr = arr.at[j].set(v)
        p = dataclasses.replace(p, **{name: arr})
    return np.asarray(jax.flatten_util.ravel_pytree(p)[0])


@pytest.fixture(scope="module")
def triplet_full():
    """The triplet on the full 3 × 3 grid (no folding), elements moved."""
    return T.ToleranceModel(_triplet(), fields=GRID, pupil=PUPIL, tolerances=ON, batch=4)


def test_elements_of_a_triplet_and_a_cemented_group():
    assert rigid.element_groups(_triplet()) == ((0, 1), (2, 3), (4, 5))
    g1, g2 = jl.get_material("N-BK7"), jl.get_material("N-SF5")
    doublet = jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.03), jl.Sphere(-0.01)),
                      thickness=jnp.asarray([4.0, 2.0, 50.0]), materials=(g1, g2, jl.Air()))
    assert rigid.element_groups(doublet) == ((0, 2),)  # a cemented group moves as one


def test_off_by_default_leaves_the_coaxial_model_unchanged():
    """Default tolerances: no rigid entries, no breaks, the vector and labels of before."""
    m = T.ToleranceModel(_triplet(), fields=GRID[:2], pupil=PUPIL)
    assert not m.elements and T.Tolerances().decenter == 0 and T.Tolerances().tilt == 0
    assert not any(k in ("decenter", "tilt") for k in m.kinds)
    assert m.zero.size == T.ToleranceModel(_triplet(), fields=GRID[:2]).zero.size
    assert m.lens_at(m.zero).num_surfaces == 6


@pytest.mark.slow  # 25 s (CI time; the breaks' placement and a decentered singlet run in CI)
def test_zero_motion_traces_as_the_nominal_lens(triplet_full):
    """Zero decenter and tilt: two zero breaks per element and unchanged thicknesses; every
    ray lands where it lands on the nominal lens (to rounding: a break re-expresses the rays
    about its vertex), the metric agrees to 1e-13 relative, and the 12 rigid entries are
    labelled per element."""
    m = triplet_full
    lens = m.lens_at(m.zero)
    j = max(j for j, (a, _) in enumerate(rigid.element_groups(m.lens)) if a <= m.lens.stop)
    assert lens.num_surfaces == 12 and lens.stop == m.lens.stop + 2 * j + 1
    assert float(jnp.sum(lens.thickness)) == pytest.approx(float(jnp.sum(m.lens.thickness)),
                                                           abs=1e-13)
    fields = jnp.asarray(GRID)
    a = T.spot_data(lens, fields, m.wavelengths, m.pupil)
    b = T.spot_data(m.lens, fields, m.wavelengths, m.pupil)
    assert np.array_equal(np.asarray(a.weight), np.asarray(b.weight))
    assert np.max(np.abs(np.asarray(a.position) - np.asarray(b.position))) < 1e-12
    nominal = float(T.mean_rms_um(b, m.weights))
    assert abs(m.gradient()[0] - nominal) <= 1e-13 * nominal
    assert [n for n, k in zip(m.names, m.kinds, strict=True) if k == "decenter"][:2] == [
        "E1 (S1-S2) decenter x", "E2 (S3-S4) decenter x"]
    assert m.units[m.names.index("E3 (S5-S6) tilt y")] == "deg"


def test_breaks_place_the_element_and_restore_the_axis(triplet_full):
    """The convention in global coordinates (``frame_of``): with the middle element moved by
    d = (0.1, −0.07) mm and tilted by (0.5°, −0.3°), its front vertex (the pivot) is at
    (0.1, −0.07, z_a), its axis is R ẑ with R = Rx(0.5°)·Ry(−0.3°), its back vertex at
    pivot + L R ẑ; every other vertex, and the image, are where they were with the axes
    unrotated (to 1e-12 mm)."""
    from jaxlens.optics.coordinates import frame_of

    m = triplet_full
    nominal_z = np.asarray(m.lens.vertex_z())
    lens = m.lens_at(_vec(m, decenter_x={1: 0.1}, decenter_y={1: -0.07}, tilt_x={1: 0.5},
                          tilt_y={1: -0.3}))
    z = np.asarray(lens.vertex_z())
    new = [i for i, s in enumerate(lens.surfaces) if not isinstance(s, jl.CoordinateBreak)]

    def vertex(k):
        r, off = (np.asarray(a) for a in frame_of(lens, k))
        return r, r @ np.asarray([0.0, 0.0, z[k]]) + off

    ax, ay = np.deg2rad(0.5), np.deg2rad(-0.3)
    rx = np.asarray([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.asarray([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    rot = rx @ ry
    for i, k in enumerate(new):
        r, v = vertex(k)
        if i in (2, 3):  # the middle element
            pivot = np.asarray([0.1, -0.07, nominal_z[2]])
            expect = pivot + (nominal_z[i] - nominal_z[2]) * rot[:, 2]
            assert np.max(np.abs(r - rot)) < 1e-14
        else:
            expect = np.asarray([0.0, 0.0, nominal_z[i]])
            assert np.max(np.abs(r - np.eye(3))) < 1e-14
        assert np.max(np.abs(v - expect)) < 1e-12, (i, v, expect)
    r, off = (np.asarray(a) for a in frame_of(lens))
    image = r @ np.asarray([0.0, 0.0, float(lens.image_z())]) + off
    assert np.max(np.abs(image - [0.0, 0.0, float(m.lens.image_z())])) < 1e-12


def _centroid(lens, pupil):
    d = T.spot_data(lens, jnp.zeros((1, 2)), jnp.asarray([WL]), pupil)
    w = np.asarray(d.weight)[0, 0]
    assert w.all()
    return np.asarray(d.position)[0, 0].mean(0)


def _paraxial_conjugate(lens):
    """(back focal distance, s): the object distance s (from the front vertex) imaged at s
    behind the back vertex, from a y–nu trace: for a symmetric lens these are the unit
    conjugates, m = −1."""
    n = float(lens.materials[0].index(jnp.asarray(WL)))
    c1, c2 = float(lens.surfaces[0].c), float(lens.surfaces[1].c)
    t = float(lens.thickness[0])

    def image_distance(s):
        y, nu = (1.0, 0.0) if s is None else (s * 1.0, 1.0)  # from the axial object point
        nu = nu - y * (n - 1) * c1
        y = y + t * nu / n
        nu = nu - y * (1 - n) * c2
        return -y / nu

    lo, hi = 60.0, 400.0  # image_distance(s) − s changes sign between them
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (image_distance(mid) - mid) * (image_distance(lo) - lo) > 0:
            lo = mid
        else:
            hi = mid
    return image_distance(None), 0.5 * (lo + hi)


@pytest.mark.parametrize("axis", [0, 1])
def test_decentered_singlet_moves_the_image_by_delta_one_minus_m(axis):
    """A lens decentered by δ images an on-axis point at δ (1 − m): in the lens's frame the
    object sits at −δ and its image at −m δ; add δ back. Object at infinity (m = 0): the
    paraxial beam's centroid moves by δ; symmetric biconvex lens at its unit conjugates
    (m = −1): by 2 δ; each image plane at the paraxial image (the rays stay aimed at the
    nominal pupil, so with defocus the beam's centroid would walk). A 0.1 mm beam
    (paraxial) keeps the aberration terms below 1e-4 δ."""
    delta = 0.05
    pupil = jl.sampling.pupil_grid(5, jnp.float64)
    name = ("decenter_x", "decenter_y")[axis]
    bfd, s = _paraxial_conjugate(_singlet())
    inf = _singlet(epd=0.1, back=bfd)
    finite = _singlet(epd=0.1, obj=s, back=s)
    for lens, shift in ((inf, delta), (finite, 2 * delta)):
        m = T.ToleranceModel(lens, fields=[0.0], pupil=pupil, tolerances=ON, batch=1)
        base = _centroid(m.lens_at(m.zero), pupil)
        moved = _centroid(m.lens_at(_vec(m, **{name: {0: delta}})), pupil)
        assert abs(moved[axis] - base[axis] - shift) < 1e-4 * delta
        assert abs(moved[1 - axis] - base[1 - axis]) < 1e-12


def test_tilted_plate_shifts_a_ray_by_the_plate_formula():
    """A plane-parallel plate (t = 5 mm, N-BK7) tilted by θ about x at its front vertex: the
    axial ray leaves parallel to z, displaced by D = t sin θ (1 − cos θ / √(n² − sin² θ)),
    toward −y for θ > 0 (+tilt_x turns the plate's normal from +z toward −y and the ray
    bends toward the normal). Checked at 1°, 5° and −10° to 1e-12 mm."""
    glass = jl.get_material("N-BK7")
    t = 5.0
    plate = jl.Lens(surfaces=(jl.Plane(), jl.Plane()), thickness=jnp.asarray([t, 10.0]),
                    materials=(glass, jl.Air()), epd=1.0, wavelengths=(WL,)).astype(jnp.float64)
    n = float(glass.index(jnp.asarray(WL, jnp.float64)))
    pupil = jnp.zeros((1, 2), jnp.float64)
    m = T.ToleranceModel(plate, fields=[0.0], pupil=pupil, tolerances=ON, batch=1)
    for deg in (1.0, 5.0, -10.0):
        th = np.deg2rad(deg)
        expect = -t * np.sin(th) * (1 - np.cos(th) / np.sqrt(n * n - np.sin(th) ** 2))
        d = T.spot_data(m.lens_at(_vec(m, tilt_x=({0: deg}))), jnp.zeros((1, 2)),
                        jnp.asarray([WL]), pupil)
        y, slope = float(d.position[0, 0, 0, 1]), np.asarray(d.slope[0, 0, 0])
        assert abs(y - expect) < 1e-12 and np.all(np.abs(slope) < 1e-14)
        assert abs(float(d.position[0, 0, 0, 0])) < 1e-15
        # tilt about y moves the ray along +x by the same amount (Ry turns +z toward +x)
        d = T.spot_data(m.lens_at(_vec(m, tilt_y=({0: deg}))), jnp.zeros((1, 2)),
                        jnp.asarray([WL]), pupil)
        assert abs(float(d.position[0, 0, 0, 0]) + expect) < 1e-12


@pytest.mark.slow  # 29 s (run with -m slow)
def test_sensitivities_match_central_differences():
    """On a one-sided field set (the gradient of a decenter is not zero by symmetry there)
    the reverse-mode gradient through the breaks matches central differences of the
    re-traced metric (step 1e-4 of the tolerance) to 1e-6 relative, for every rigid entry;
    ``sensitivity`` lists them with their tolerances."""
    fields = np.asarray([[0.0, 0.0], [0.0, 14.0], [8.0, 10.0]])
    m = T.ToleranceModel(_triplet(), fields=fields, pupil=PUPIL, tolerances=ON, batch=8)
    _, g = m.gradient()
    tol = m.tolerance_vector(sensitivity=True)
    idx = np.asarray([i for i, k in enumerate(m.kinds) if k in ("decenter", "tilt")])
    assert idx.size == 12 and np.all(tol[idx] == np.where(
        np.asarray(m.kinds)[idx] == "decenter", 0.02, 0.05))
    h = 1e-4 * tol[idx]
    steps = np.zeros((idx.size, tol.size))
    steps[np.arange(idx.size), idx] = h
    r = m.evaluate(np.concatenate([steps, -steps]))["rms_um"]
    fd = (r[:idx.size] - r[idx.size:]) / (2 * h)
    scale = np.max(np.abs(fd))
    assert scale > 1.0  # µm per mm or per degree: these entries matter
    assert np.max(np.abs(g[idx] - fd)) < 1e-6 * scale
    rows = {row["parameter"]: row for row in T.sensitivity(m, check=0)["rows"]}
    assert rows["E2 (S3-S4) decenter y"]["tolerance"] == 0.02
    assert rows["E2 (S3-S4) tilt x"]["unit"] == "deg"
    # check=0 re-traces no coaxial entry but every element motion (see the next test)
    assert rows["S1 radius"]["delta_rms_plus_um"] is None
    assert all(r["delta_rms_plus_um"] is not None for r in rows.values() if r["unit"] == "deg")


@pytest.mark.slow  # 15 s (run with -m slow)
def test_mirror_symmetry_and_why_the_fields_are_not_folded(triplet_full):
    """On the symmetric 3 × 3 grid, decentering an element by +δ or −δ (x or y), or tilting it
    by ±θ, gives the same metric (to 1e-12 relative), so the gradient at the nominal lens is
    0 and ``sensitivity`` re-traces them whatever ``check`` says. The folded grid (3 fields
    with weights) gives the nominal metric exactly but not the decentered one: folding
    assumes a rotationally symmetric lens."""
    m = triplet_full
    cases = [{"decenter_x": {1: 0.05}}, {"decenter_x": {1: -0.05}},
             {"decenter_y": {0: 0.05}}, {"decenter_y": {0: -0.05}},
             {"tilt_y": {2: 0.3}}, {"tilt_y": {2: -0.3}}]
    r = m.evaluate(np.stack([_vec(m, **c) for c in cases]))["rms_um"]
    for a, b in zip(r[::2], r[1::2], strict=True):
        assert abs(a - b) <= 1e-12 * a
    nominal, g = m.gradient()
    assert np.all(r > nominal + 1e-3)
    rigid_idx = [i for i, k in enumerate(m.kinds) if k in ("decenter", "tilt")]
    assert np.max(np.abs(g[rigid_idx])) < 1e-9
    # so the sensitivity table's first-order change is 0 and the re-traced one is not
    rows = [r for r in T.sensitivity(m, check=0)["rows"] if r["unit"] in ("mm", "deg")
            and ("decenter" in r["parameter"] or "tilt" in r["parameter"])]
    assert len(rows) == 12 and all(abs(r["delta_rms_um"]) < 1e-9 for r in rows)
    assert all(r["second_order_um"] > 1e-4 for r in rows)
    fields, weights = T.symmetric_fields(GRID)
    folded = T.ToleranceModel(_triplet(), fields=fields, field_weights=weights, pupil=PUPIL,
                              tolerances=ON, batch=4)
    rf = folded.evaluate(np.stack([folded.zero, _vec(folded, **cases[0])]))["rms_um"]
    assert abs(rf[0] - nominal) <= 1e-12 * nominal
    assert abs(rf[1] - r[0]) > 1e-3 * r[0]


def test_monte_carlo_moves_elements_and_is_reproducible(triplet_full):
    """Monte-Carlo draws every decenter within ±0.02 mm and tilt within ±0.05°, the same key
    gives the same trials to the bit, another key others; with zero tolerances every trial
    is the nominal lens."""
    m = triplet_full
    x = T.sample_perturbations(m, 50, jax.random.PRNGKey(3))
    idx = np.asarray([i for i, k in enumerate(m.kinds) if k == "decenter"])
    assert np.all(np.abs(x[:, idx]) <= 0.02) and np.std(x[:, idx]) > 0.005
    kw = {"trials": 6, "threshold_um": 20.0, "mtf_frequency": 30.0}
    a = T.monte_carlo(m, key=jax.random.PRNGKey(1), **kw)
    b = T.monte_carlo(m, key=jax.random.PRNGKey(1), **kw)
    c = T.monte_carlo(m, key=jax.random.PRNGKey(2), **kw)
    assert np.array_equal(a["per_trial"]["rms_compensated_um"],
                          b["per_trial"]["rms_compensated_um"])
    assert not np.array_equal(a["per_trial"]["rms_um"], c["per_trial"]["rms_um"])
    assert np.all(a["per_trial"]["rms_compensated_um"] <= a["per_trial"]["rms_um"] + 1e-9)
    zero = dataclasses.replace(ON, radius_rel=0, thickness=0, index=0, abbe_rel=0,
                               irregularity=0, decenter=0, tilt=0)
    z = T.monte_carlo(m.with_tolerances(zero), key=jax.random.PRNGKey(1), **kw)
    assert np.all(z["per_trial"]["rms_um"] == z["nominal"]["rms_um"])


def test_refusals():
    m = T.ToleranceModel(_triplet(), fields=GRID[:2], pupil=PUPIL)
    with pytest.raises(ValueError, match="coordinate breaks this model was built without"):
        m.with_tolerances(ON)
    with pytest.raises(ValueError, match="decenter must be a finite number >= 0 mm"):
        T.Tolerances(decenter=-0.01)
    with pytest.raises(ValueError, match="tilt must be"):
        T.Tolerances(tilt=float("nan"))


def test_cli_refuses_a_negative_decenter_before_any_work(tmp_path, capsys):
    from jaxlens.experiments import tolerance as cli

    for flag in ("--decenter", "--tilt"):
        assert cli.main(["missing.zmx", "--out", str(tmp_path), flag, "-0.01"]) == 2
        assert f"{flag} must be a finite number >= 0" in capsys.readouterr().err


def test_glass_labels_number_elements_as_the_rigid_labels_do():
    """A cemented doublet and a singlet: the doublet's two glasses are both element E1 (with
    their surfaces), the singlet's glass E2, as in the decenter and tilt labels."""
    g1, g2 = jl.get_material("N-BK7"), jl.get_material("N-SF5")
    lens = jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.03), jl.Sphere(-0.01),
                             jl.Sphere(0.01), jl.Sphere(-0.01)),
                   thickness=jnp.asarray([4.0, 2.0, 1.0, 3.0, 40.0]),
                   materials=(g1, g2, jl.Air(), g1, jl.Air()), epd=4.0,
                   wavelengths=(WL,)).astype(jnp.float64)
    m = T.ToleranceModel(lens, fields=GRID[:1], pupil=PUPIL, tolerances=ON)
    index = [n for n, k in zip(m.names, m.kinds, strict=True) if k == "index"]
    assert index[:5] == ["E1 S1-S2 (N-BK7) nd", "E1 S2-S3 (N-SF5) nd", "M3 nd",
                         "E2 (N-BK7) nd", "M5 nd"]
    assert [n for n, k in zip(m.names, m.kinds, strict=True) if k == "decenter"][:2] == [
        "E1 (S1-S3) decenter x", "E2 (S4-S5) decenter x"]
    triplet = T.ToleranceModel(_triplet(), fields=GRID[:1], pupil=PUPIL)
    assert [n for n, k in zip(triplet.names, triplet.kinds, strict=True)
            if k == "abbe"][::2] == ["E1 (N-SK16) Vd", "E2 (F2) Vd", "E3 (N-SK16) Vd"]
