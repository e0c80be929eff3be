"""Material selection (jaxlens.design.materials): the hull map, the snap, gradients, options."""

import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jaxlens.design import curriculum, init, losses, multistart
from jaxlens.design.materials import CatalogRegion, check_mode, convex_hull, snap
from jaxlens.design.params import LensParams
from jaxlens.design.spec import DesignSpec
from jaxlens.optics import catalog
from jaxlens.optics.materials import ModelGlass

REGION = CatalogRegion.of(("PLASTICS",))
HULL = REGION.hull()
SMALL = DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0,
                   fov_start=30.0, fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=3)


def _inside(points, corners, tol=1e-9):
    """Every point on the inner side of every counter-clockwise edge (glass-map scale)."""
    s = np.array([catalog.ND_PER_VD, 1.0])
    p, v = np.asarray(points) / s, np.asarray(corners) / s
    e = np.roll(v, -1, 0) - v  # [V, 2] edges
    rel = p[:, None, :] - v[None]  # [N, V, 2]
    cross = e[None, :, 0] * rel[..., 1] - e[None, :, 1] * rel[..., 0]
    return np.all(cross >= -tol, axis=1)


def test_hull_of_the_plastics():
    # The corners of the shipped plastics' glass map, counter-clockwise from the lowest nd.
    assert set(HULL.names) == {"ACRYLIC", "POLYCARB", "OKP4HT", "COC", "PMMA"}
    # Every shipped plastic lies inside (or on) the hull; a glass far off it does not.
    assert np.all(_inside(REGION.points, HULL.corners))
    assert not _inside(np.array([[1.5168, 64.17]]), HULL.corners)[0]  # N-BK7
    # The monotone chain on a square with an edge point and an inner point.
    sq = np.array([[1.5, 30.0], [1.6, 30.0], [1.6, 50.0], [1.5, 50.0], [1.55, 30.0],
                   [1.55, 40.0]])
    assert sorted(convex_hull(sq).tolist()) == [0, 1, 2, 3]


_hull_nd_vd = jax.jit(lambda m: HULL.nd_vd(m))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=5, max_size=5))
def test_any_logits_stay_in_the_catalog_region(logits):
    p = np.asarray(_hull_nd_vd(jnp.asarray([logits], jnp.float64)))
    assert np.all(np.isfinite(p))
    assert _inside(p, HULL.corners, tol=1e-7)[0]
    lo, hi = REGION.points.min(0), REGION.points.max(0)
    assert np.all(p >= lo - 1e-9) and np.all(p <= hi + 1e-9)


@pytest.mark.parametrize("name", ["E48R", "OKP4", "SAN", "POLYSTYR", "480R"])
def test_logits_start_at_the_named_material(name):
    _, nd, vd = catalog.glass_info(name)
    p = np.asarray(HULL.nd_vd(jnp.asarray(HULL.logits(nd, vd))))
    assert abs(p[0] - nd) < 1e-9 and abs(p[1] - vd) < 1e-9


def test_logits_of_a_point_outside_go_to_the_boundary():
    p = np.asarray(HULL.nd_vd(jnp.asarray(HULL.logits(1.5168, 64.17))))  # N-BK7, off the map
    assert _inside(p[None], HULL.corners, tol=1e-6)[0]
    assert p[1] > 55.0  # toward it: the high-Abbe edge


@pytest.mark.parametrize("point, name", [
    ((1.60, 27.5), "OKP4"),
    ((1.59, 31.0), "POLYSTYR"),
    ((1.5335, 56.2), "COC"),
    ((1.492, 57.3), "PMMA"),
    ((1.531, 56.0), "E48R"),
    # By Abbe number alone POLYSTYR (|ΔVd| 0.37) would win; with nd weighted 0.01 per Abbe
    # unit POLYCARB is nearer (0.59 against 0.62).
    ((1.5855, 30.5), "POLYCARB"),
])
def test_snap_picks_the_nearest_catalog_material(point, name):
    assert REGION.names[int(REGION.nearest(*point))] == name
    # The same choice as the catalog's own nearest-glass search with this metric.
    assert catalog.nearest_glasses(*point, count=1, catalogs="PLASTICS")[0][1] == name
    # Through the hull map: logits for the point snap to the same material.
    m = jnp.asarray(HULL.logits(*point))[None, None]
    _, names = snap(REGION, HULL, m)
    assert names == [(name,)]


class _PointMaterials(eqx.Module):
    """Test model: ``m[e]`` is element e's (nd, Vd) itself (no hull)."""

    def materials(self, m):
        return tuple(ModelGlass(m[e, 0], m[e, 1]) for e in range(m.shape[0]))


def _loss_setup():
    dt = jnp.float64
    pm = init.parameterization(SMALL, dt)
    p = init.random_params(SMALL, jax.random.PRNGKey(3), dt)
    c = 0.3 * jnp.asarray([1.0, -0.5, -0.8, 0.6], dt)
    p = LensParams(c=c, a=p.a.at[:, 0].set(0.02 * jnp.sign(c)), k=p.k, d=p.d)
    samp = losses.RayLoss.make(3, 2, SMALL.wavelengths, SMALL.sensor_size, dt)
    stage = curriculum.Stage("t", SMALL.fov, SMALL.fnum, 1)
    # The spacing regularizer holds the clear radii without gradient (by design), so its
    # weight is 0 here: the loss is then a smooth function of the materials.
    args = curriculum.stage_args(SMALL, stage, samp.area[None], (1.0, 0.0, 1.0), dt)
    args = jax.tree.map(lambda x: x[0], args)
    return pm, p, samp, args, jnp.asarray(init.gap_bounds(SMALL), dt)


@pytest.mark.parametrize("model", ["nd_vd", "logits"])
def test_loss_gradient_wrt_materials_matches_finite_differences(model):
    pm, p, samp, args, gb = _loss_setup()
    if model == "nd_vd":
        mats, m0 = _PointMaterials(), jnp.asarray([[1.55, 45.0], [1.60, 28.0]])
        steps = jnp.asarray([1e-6, 1e-3])  # per column: nd, Vd
    else:
        mats = HULL
        m0 = jnp.asarray(np.stack([HULL.logits(1.55, 45.0), HULL.logits(1.60, 28.0)]))
        steps = jnp.full((m0.shape[1],), 1e-5)
    pm = eqx.tree_at(lambda x: x.materials, pm, mats, is_leaf=lambda x: x is None)
    objective = losses.Objective(pm, samp, gb)

    def loss(m):
        return objective(LensParams(p.c, p.a, p.k, p.d, m), args)[1].loss

    f = jax.jit(loss)
    aux = eqx.filter_jit(objective)(LensParams(p.c, p.a, p.k, p.d, m0), args)[1]
    assert float(jnp.min(aux.valid_fraction)) == 1.0
    g = np.asarray(jax.jit(jax.grad(loss))(m0))
    assert np.all(np.isfinite(g)) and np.any(np.abs(g) > 0)
    fd = np.zeros_like(g)
    for idx in np.ndindex(*g.shape):
        h = float(steps[idx[1]])
        e = jnp.zeros_like(m0).at[idx].set(h)
        fd[idx] = (float(f(m0 + e)) - float(f(m0 - e))) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-5, atol=1e-7 * np.max(np.abs(g)))


def test_bad_selection_values_are_refused():
    with pytest.raises(ValueError, match=r"material selection must be one of.*'bogus'"):
        check_mode("bogus")
    with pytest.raises(ValueError, match="material selection must be one of"):
        multistart.DesignConfig(materials="nearest", float64=True)  # refused on construction
    with pytest.raises(ValueError, match=r"Unknown catalog\(s\) \['NOPE'\]"):
        CatalogRegion.of(("NOPE",))
    with pytest.raises(ValueError, match="at least one catalog"):
        CatalogRegion.of(())


def test_cli_refuses_bad_material_options(tmp_path, capsys):
    from jaxlens.experiments import classical

    with pytest.raises(SystemExit) as e:
        classical.main(["--select-materials", "nearest", "--out", str(tmp_path / "a")])
    assert e.value.code == 2
    assert "--select-materials" in capsys.readouterr().err
    code = classical.main(["--select-materials", "continuous", "--material-catalogs", "NOPE",
                           "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err
    assert code == 2 and "--material-catalogs" in err and "NOPE" in err
    assert not os.path.exists(tmp_path / "b")


# The command-line smoke with --select-materials continuous (catalog names in the summary
# and the GLAS lines, the file read back) shares the classical smoke run:
# tests/test_classical_smoke.py::test_cli_smoke_selects_catalog_materials.


@pytest.mark.slow
def test_search_then_polish_gives_catalog_lenses():
    """The whole path: continuous stages, the loss search, the polish around the choice."""
    from jaxlens.optics.catalog import CatalogMaterial

    cfg = multistart.DesignConfig(n_fields=3, rings=2, steps=3, final_steps=3, polish_steps=1,
                                  epoch=3, log_every=3, float64=True, materials="search")
    res = multistart.design(SMALL, [0, 1], cfg, progress=False, shard=False)
    assert res.history.stages[-1].startswith("polish")
    names = set(catalog.catalog_names("PLASTICS"))
    for i in range(2):
        lens = res.lens(i)
        glass = [m for m in lens.materials if isinstance(m, CatalogMaterial)]
        assert [m.name for m in glass] == list(res.materials[i]) and set(res.materials[i]) <= names
        # The polished geometry traced with the real catalog materials: the same indices at
        # the design wavelengths as the tables the polish used.
        wl = jnp.asarray(SMALL.wavelengths)
        np.testing.assert_allclose(np.stack([np.asarray(m.index(wl)) for m in glass]),
                                   np.asarray(res.params.m[i]), rtol=1e-12)
    assert res.continuous_materials.shape == (2, 2, 2)


def test_design_regions_leave_out_obsolete_glasses():
    """SCHOTT's catalog keeps the obsolete glasses that lens files name (SK4, BK7, …, Zemax
    status 2); glass selection chooses among glasses still made. BAF4 is obsolete at SCHOTT,
    the first catalog searched, so the name is left out even though CDGM also has a BAF4."""
    everything = catalog.catalog_names(catalog="SCHOTT")
    made = catalog.catalog_names(catalog="SCHOTT", obsolete=False)
    assert {"SK4", "BK7", "N-BK7", "N-SF6"} <= set(everything)
    assert "N-BK7" in made and "SK4" not in made and "BK7" not in made
    assert len(made) < len(everything)
    region = CatalogRegion.of(("SCHOTT", "CDGM"))
    assert "SK4" not in region.names and "BAF4" not in region.names
    assert "N-BK7" in region.names and "H-K9L" in region.names
    assert set(region.names) == set(catalog.catalog_names(catalogs=("SCHOTT", "CDGM"),
                                                          obsolete=False))
    with pytest.raises(ValueError, match="obsolete must be True or False"):
        catalog.catalog_names(catalog="SCHOTT", obsolete="no")
