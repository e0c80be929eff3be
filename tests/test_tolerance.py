"""Tolerancing (``jaxlens.tolerance``): sensitivities against finite differences, the
Monte-Carlo at zero tolerance, the back-focus compensator against an analytic focus,
percentiles and yield by hand, bad input.

Two small models are compiled once per session (a Cooke triplet with one aspheric surface,
three 2-D fields folded by symmetry, a 9 × 9 pupil; a plano-hyperbolic singlet on axis).
"""

import dataclasses
import pathlib
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl

T = jl.tolerance
PUPIL = jl.sampling.pupil_grid(9, jnp.float64)


def _triplet():
    lens = jl.load("jaxlens/data/lenses/cooke_triplet.json").astype(jnp.float64)
    s = lens.surfaces[0]
    asph = jl.EvenAsphere(c=s.c, k=jnp.asarray(-0.3), coeffs=jnp.asarray([0.0, 2e-6, -1e-9]),
                          semi_diameter=s.semi_diameter)
    return eqx.tree_at(lambda x: x.surfaces, lens, (asph, *lens.surfaces[1:]))


# A 3 × 3 grid of (θx, θy) fields; folding leaves (0,0), (0,14), (14,14) with weights 1, 4, 4.
GRID = np.stack(np.meshgrid([-14.0, 0.0, 14.0], [-14.0, 0.0, 14.0]), -1).reshape(-1, 2)


@pytest.fixture(scope="module")
def triplet_model():
    fields, weights = T.symmetric_fields(GRID)
    return T.ToleranceModel(_triplet(), fields=fields, field_weights=weights, pupil=PUPIL,
                            batch=8)


def test_symmetric_fields_fold_the_grid():
    fields, weights = T.symmetric_fields(GRID)
    assert sorted(map(tuple, fields)) == [(0.0, 0.0), (0.0, 14.0), (14.0, 14.0)]
    assert sorted(weights) == [1.0, 4.0, 4.0]


def test_zero_perturbation_is_the_nominal_metric(triplet_model):
    """The folded-field metric of the unperturbed lens is Table 1's mean over all 9 fields
    from ``rms_spot``, and a Monte-Carlo with zero tolerances reproduces it in every trial."""
    m = triplet_model
    ref = 1e3 * float(jnp.mean(jl.analysis.rms_spot(m.lens, jnp.asarray(GRID),
                                                    pupil=PUPIL).polychromatic))
    nominal, _ = m.gradient()
    assert abs(nominal - ref) <= 1e-12 * ref
    zero = dataclasses.replace(m.tolerances, radius_rel=0, thickness=0, index=0, abbe_rel=0,
                               irregularity=0)
    m0 = m.with_tolerances(zero)  # the same compiled model under zero tolerances
    assert not np.any(m0.tolerance_vector(sensitivity=False))
    mc = T.monte_carlo(m0, trials=5, key=jax.random.PRNGKey(1), threshold_um=1e3,
                       mtf_frequency=20.0)
    assert np.all(np.abs(mc["per_trial"]["rms_um"] - ref) <= 1e-12 * ref)
    assert mc["rms_p50_um"] == mc["rms_p90_um"] == mc["nominal"]["rms_compensated_um"]
    assert mc["yield"] == 1.0


def test_sensitivity_matches_central_differences(triplet_model):
    """Every toleranced parameter (radii, thicknesses, conic, asphere terms, nd, Vd): the one
    reverse-mode gradient against central differences of the re-traced metric."""
    m = triplet_model
    nominal, g = m.gradient()
    tol = m.tolerance_vector(sensitivity=True)
    idx = np.nonzero(tol)[0]
    kinds = {m.kinds[i] for i in idx}
    assert kinds == {"radius", "thickness", "conic", "asphere", "index", "abbe"}
    h = 1e-4 * tol[idx]
    steps = np.zeros((idx.size, tol.size))
    steps[np.arange(idx.size), idx] = h
    r = m.evaluate(np.concatenate([steps, -steps]))["rms_um"]
    fd = (r[:idx.size] - r[idx.size:]) / (2 * h)
    # compare in µm per tolerance: the quantity reported
    np.testing.assert_allclose(g[idx] * tol[idx], fd * tol[idx], rtol=1e-5, atol=1e-8)
    assert np.max(np.abs(g[idx] * tol[idx])) > 1e-2  # the comparison is not all zeros
    rows = T.sensitivity(m, check=3)["rows"]
    assert len(rows) == idx.size
    checked = [x for x in rows if x["delta_rms_plus_um"] is not None]
    assert len(checked) == 3
    top = sorted(rows, key=lambda x: -abs(x["delta_rms_um"]))[:3]
    assert {x["parameter"] for x in checked} == {x["parameter"] for x in top}
    for x in checked:  # the re-traced ± tolerance columns are consistent with each other
        t, dp, dm = x["tolerance"], x["delta_rms_plus_um"], x["delta_rms_minus_um"]
        assert abs(x["fd_gradient_um_per_unit"] * t - 0.5 * (dp - dm)) < 1e-9
        assert abs(x["second_order_um"] - 0.5 * (dp + dm)) < 1e-9


def test_perturbed_material_and_irregularity_are_what_they_say():
    glass = jl.get_material("N-SK16")
    p = T.PerturbedMaterial(glass, jnp.asarray(5e-4), jnp.asarray(-0.01))
    nd = float(glass.index(jnp.asarray(0.5875618)))
    vd = float(jl.optics.materials.abbe_number(glass))
    assert abs(float(p.index(jnp.asarray(0.5875618))) - (nd + 5e-4)) < 1e-15
    assert abs(float(jl.optics.materials.abbe_number(p)) - 0.99 * vd) < 1e-10 * vd
    lens = _triplet()
    zero = T.zero_perturbation(lens)
    h = jnp.full(lens.num_surfaces, 4.0)
    pert = eqx.tree_at(lambda x: x.irregularity, zero, zero.irregularity.at[0].set(5e-4)
                       .at[1].set(-5e-4))
    out = T.perturb(lens, pert, h, add_r4=(False, True) + (False,) * 4)
    for i, s in ((0, 5e-4), (1, -5e-4)):  # peak sag s at r = h, on an asphere and a sphere
        dz = out.surfaces[i].sag(jnp.asarray(0.0), h[i])[0] - lens.surfaces[i].sag(
            jnp.asarray(0.0), h[i])[0]
        assert abs(float(dz) - s) < 1e-15
    assert isinstance(out.surfaces[1], jl.EvenAsphere)


def test_compensator_finds_the_analytic_focus():
    """Plano-hyperbolic singlet: collimated light in the glass, rear surface k = −n², a
    perfect on-axis focus at f' = R/(n − 1) behind it. Scaling R by (1 + δ) keeps it perfect
    and moves the focus by R δ/(n − 1): the refocus must find exactly that."""
    n, radius = 1.5, 20.0
    glass = jl.ModelGlass(nd=n, vd=jnp.inf)
    lens = jl.Lens(surfaces=(jl.Plane(), jl.Conic(-1 / radius, -n * n)),
                   thickness=jnp.asarray([3.0, radius / (n - 1)]), materials=(glass, jl.Air()),
                   epd=8.0, fields=jnp.asarray([0.0]),
                   wavelengths=jnp.asarray([0.5875618])).astype(jnp.float64)
    m = T.ToleranceModel(lens, fields=[0.0], pupil=PUPIL, batch=2)
    delta = 0.01
    v = np.zeros((2, m.zero.size))
    v[0, m.names.index("S2 radius")] = delta
    v[1, m.names.index("T1 thickness")] = 0.05  # glass thicker: focus moves with the vertex
    res = m.evaluate(v)
    assert abs(res["refocus_mm"][0] - radius * delta / (n - 1)) < 1e-9
    assert res["rms_um"][0] > 1.0 and res["rms_compensated_um"][0] < 1e-6
    assert abs(res["refocus_mm"][1]) < 1e-9


def test_compensator_minimises_the_retraced_metric(triplet_model):
    """Polychromatic, three fields: moving the image plane by the refocus in the lens itself
    gives the compensated metric, and ± 5 µm around it is worse."""
    m = triplet_model
    v = np.zeros(m.zero.size)
    v[m.names.index("S3 radius")] = 0.004
    v[m.names.index("T2 thickness")] = -0.03
    dz = float(m.evaluate(v[None])["refocus_mm"][0])
    assert abs(dz) > 1e-3
    last = m.names.index(f"T{m.lens.num_surfaces} thickness (image distance)")
    trial = np.repeat(v[None], 3, 0)
    trial[:, last] += dz + np.asarray([0.0, 5e-3, -5e-3])
    res = m.evaluate(trial)
    r0 = res["rms_um"]
    assert abs(r0[0] - res["rms_compensated_um"][0]) < 1e-9 * r0[0]
    assert r0[1] > r0[0] and r0[2] > r0[0]
    assert abs(res["refocus_mm"][0]) < 1e-8  # already at best focus


def test_percentiles_and_yield_by_hand():
    v = np.arange(1.0, 11.0)  # 1 … 10
    assert T.percentile(v, 50) == 5.5
    assert abs(T.percentile(v, 90) - 9.1) < 1e-12
    assert T.percentile(v, 0) == 1.0 and T.percentile(v, 100) == 10.0
    w = np.array([3.0, np.nan, 1.0, 2.0])  # NaN = a failed trial = worst
    assert T.percentile(w, 50) == 2.5 and T.percentile(w, 90) == np.inf
    rng = np.random.default_rng(0).random(37)
    for q in (10, 50, 90):
        assert abs(T.percentile(rng, q) - np.percentile(rng, q)) < 1e-15
    assert T.yield_fraction(v, 4.5) == 0.4
    assert T.yield_fraction(w, 2.0) == 0.5
    assert T.yield_fraction(v, 4.5, valid_fraction=[1, 0.5] + [1] * 8) == 0.3


def test_bad_input_raises(triplet_model):
    with pytest.raises(ValueError, match="thickness must be a finite number >= 0 mm"):
        T.Tolerances(thickness=-0.01)
    with pytest.raises(ValueError, match="irregularity"):
        T.Tolerances(irregularity=float("nan"))
    with pytest.raises(ValueError, match="distribution"):
        T.Tolerances(distribution="gauss")
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="trials must be a whole number >= 1"):
            T.monte_carlo(triplet_model, trials=bad, threshold_um=5.0, mtf_frequency=10.0)
    with pytest.raises(ValueError, match="threshold_um must be a finite number > 0"):
        T.monte_carlo(triplet_model, trials=10, threshold_um=-1.0, mtf_frequency=10.0)
    with pytest.raises(ValueError, match="mtf_frequency"):
        T.monte_carlo(triplet_model, trials=10, threshold_um=1.0, mtf_frequency=-1.0)
    with pytest.raises(ValueError, match="field_weights"):
        T.ToleranceModel(_triplet(), fields=[0.0, 5.0], field_weights=[1.0, -1.0])
    with pytest.raises(ValueError, match="check"):
        T.sensitivity(triplet_model, check=-1)


def test_cli_refuses_to_replace_an_earlier_run_before_any_work(tmp_path, capsys):
    from jaxlens.experiments import tolerance as cli

    design = pathlib.Path(jl.__file__).parent / "data" / "lenses" / "cooke_triplet.zmx"
    earlier = tmp_path / "tolerance.json"
    earlier.write_text('{"earlier": true}')
    t0 = time.perf_counter()
    assert cli.main([str(design), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "tolerance.json" in err and "--overwrite" in err
    assert earlier.read_text() == '{"earlier": true}'
    assert time.perf_counter() - t0 < 5  # refused before the analysis, not after


def test_cli_refuses_a_lens_it_would_misdescribe_before_any_work(tmp_path, capsys):
    """The classical-design analysis runs at the spec's entrance pupil and folds the sensor
    grid by rotational symmetry: another lens (its pupil was silently replaced by the spec's)
    or a lens without that symmetry is refused with one line, before any work."""
    from jaxlens.design.spec import DesignSpec
    from jaxlens.experiments import tolerance as cli

    root = pathlib.Path(jl.__file__).parent
    t0 = time.perf_counter()
    assert cli.main([str(root / "data" / "lenses" / "cooke_triplet.zmx"), "--out",
                     str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "entrance pupil is 10 mm and the classical spec's 2.25012 mm" in err
    assert err.count("\n") == 1 and not (tmp_path / "a").exists()
    design = jl.load(root.parent / "experiments" / "classical" / "designs" / "seed_13.zmx")
    cli.check_design(design, DesignSpec())  # a design of the spec passes
    s = design.surfaces[1]
    hybrid = eqx.tree_at(lambda L: L.surfaces[1], design,
                         jl.Hybrid(c=s.c, k=s.k, coeffs=s.coeffs, odd_x=jnp.asarray([1e-4]),
                                   odd_y=jnp.asarray([0.0]), semi_diameter=s.semi_diameter))
    jl.save(hybrid, tmp_path / "hybrid.zmx")
    assert cli.main([str(tmp_path / "hybrid.zmx"), "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "the design has Hybrid: the analysis folds the sensor grid" in err
    assert time.perf_counter() - t0 < 20


def test_a_paraxial_surface_is_refused_by_name():
    """An ideal thin lens has no shape to perturb: perturbing it failed deep in JAX
    ("zeros_like requires ndarray ... _LeafWrapper")."""
    from jaxlens.optics.paraxial_surface import ParaxialSurface

    lens = jl.Lens((jl.Sphere(0.02, semi_diameter=5.0), ParaxialSurface(focal_length=50.0)),
                   jnp.array([2.0, 50.0]), (jl.ModelGlass(1.5, 60.0), jl.Air()), epd=4.0,
                   fields=(0.0, 2.0))
    for call in (lambda: T.zero_perturbation(lens), lambda: T.ToleranceModel(lens)):
        with pytest.raises(ValueError, match="surface 2 is a ParaxialSurface \\(an ideal thin "
                                             "lens\\): it has no radius, conic or aspheric"):
            call()


@pytest.mark.parametrize(("surface", "match"), [
    (jl.Hybrid(c=0.02, k=0.0, coeffs=jnp.zeros(2), odd_x=jnp.array([1e-4]),
               odd_y=jnp.array([0.0])), r"surface 1 is a Hybrid with odd x³, y³, … terms"),
    ("toroidal", r"surface 1 is a Toroidal; tolerance analysis perturbs the radius, conic "
                 r"and even aspheric terms of Standard, EvenAsphere and Hybrid surfaces"),
    (jl.Biconic(c=0.02, cx=0.03), r"surface 1 is a Biconic; tolerance analysis perturbs"),
    (jl.ZernikeSag(c=0.02, zernike=jnp.array([0.0, 0.0, 0.0, 1e-3]), norm_radius=5.0),
     r"surface 1 is a ZernikeSag; tolerance analysis perturbs"),
])
def test_a_surface_with_untoleranced_shape_numbers_is_refused(surface, match):
    """A toroid (its radius of rotation) and a hybrid's odd terms were accepted and left
    untoleranced without a word; a hybrid without odd terms is an even asphere and passes."""
    from jaxlens.optics.toroidal import Toroidal

    if surface == "toroidal":
        surface = Toroidal(c=0.02, cx=0.01, coeffs=jnp.zeros(1))
    glass = jl.ModelGlass(1.5168, 64.17)

    def lens(s):
        return jl.Lens((s, jl.Sphere(-0.02)), jnp.array([3.0, 45.0]), (glass, jl.Air()),
                       epd=8.0, fields=jnp.array([0.0, 5.0]))

    for call in (T.zero_perturbation, T.ToleranceModel):
        with pytest.raises(ValueError, match=match):
            call(lens(surface))
    even = jl.Hybrid(c=0.02, k=0.0, coeffs=jnp.zeros(2), odd_x=jnp.zeros(1), odd_y=jnp.zeros(1))
    T.ToleranceModel(lens(even))
