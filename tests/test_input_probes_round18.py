"""Round 18 of bad-input and silent-answer probes (``tools/audit18_probe.py``).

Tolerances without an upper bound, 0-d arrays refused as numbers by DesignSpec, ``jax.jit``
of a material's bound ``index``, tables read beyond their data (an index and an Abbe number
of held end values), and entry points that ran on (or hung, or ran out of memory) with an
argument they could have refused.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import (
    encircled_energy,
    rms_spot,
    self_intersection,
    tolerance,
    wavefront,
    zernike_fit,
)
from jaxlens.analysis.tolerance import Tolerances, normalised_weights
from jaxlens.design import DesignSpec
from jaxlens.optics import catalog
from jaxlens.optics.materials import abbe_number

# ------------------------------------------------------------------ tolerance bounds


@pytest.mark.parametrize("name, value, limit, unit", [
    ("irregularity", 1.0, "0.1", "mm"), ("irregularity", 0.1, "0.1", "mm"),
    ("asphere_sag", 2.0, "0.1", "mm"), ("index", 1.0, "0.1", r"\(absolute nd"),
    ("conic", 5.0, "1", r"\(absolute conic"),
])
def test_form_index_and_conic_tolerances_have_upper_bounds(name, value, limit, unit):
    """Before: any value; irregularity=1 (mm, meant as µm or fringes) bent every surface by a
    millimetre in the Monte-Carlo, and index=1 put glasses below the index of air."""
    with pytest.raises(ValueError, match=rf"^Tolerances: {name} must be below {limit} {unit}"):
        Tolerances(**{name: value})
    assert tolerance.MAX_FORM_SAG == 0.1
    assert getattr(Tolerances(**{name: 0.002}), name) == 0.002


# ------------------------------------------------------------------ DesignSpec numbers


@pytest.mark.parametrize("kw", [dict(fov_start=jnp.asarray(40.0)), dict(fnum_start=np.array(4.0)),
                                dict(sensor_pixels=jnp.asarray(256)),
                                dict(n_elements=np.int64(6)), dict(fov=np.float32(60.0))])
def test_designspec_reads_a_0d_array_or_numpy_scalar_as_its_number(kw):
    """Before: fov_start=jnp.asarray(40.0) was a TypeError ("must be a number")."""
    (name, value), = kw.items()
    spec = DesignSpec(**kw)
    got = getattr(spec, name)
    assert type(got) in (int, float) and got == float(value)


def test_designspec_refuses_a_1d_array_in_a_scalar_field_by_its_shape():
    with pytest.raises(TypeError, match=r"^DesignSpec: fov_start must be a number in "
                                        r"\(0, 80\.8\] deg, one value, got an array of shape "
                                        r"\(1,\)"):
        DesignSpec(fov_start=jnp.asarray([40.0]))
    # A 1-d array is a sequence where the field is one.
    assert DesignSpec(wavelengths=np.array([0.5, 0.6]), primary=0).wavelengths == (0.5, 0.6)


# ------------------------------------------------------------------ jit of material.index


MATERIALS = {
    "model": jl.ModelGlass(1.5, 50.0),
    "schott": jl.Schott([2.27, -0.01, 0.01, 0.0, 0.0, 0.0]),
    "sellmeier": jl.Sellmeier([1.04, 0.23, 1.01], [0.006, 0.02, 103.56]),
    "table": jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515]),
    "catalog": jl.get_material("N-BK7"),
}


@pytest.mark.parametrize("name", list(MATERIALS))
def test_jit_of_a_materials_bound_index(name):
    """Before: TypeError "unhashable type: 'ArrayImpl'" (jax.jit hashes the bound method, and
    with it the material's array fields) for every material with coefficients."""
    m = MATERIALS[name]
    assert float(jax.jit(m.index)(0.55)) == pytest.approx(float(m.index(0.55)), abs=1e-15)
    twin = jax.tree_util.tree_map(lambda x: x + 0.0, m)  # equal values, new arrays
    assert hash(twin) == hash(m) and bool(twin == m)


def test_jit_of_two_glasses_keeps_them_apart_and_catalog_lookup_inside_jit():
    a, b = jl.ModelGlass(1.5, 50.0), jl.ModelGlass(1.7, 50.0)
    assert hash(a) != hash(b) and hash(jl.Air()) == hash(jl.Air())
    assert float(jax.jit(a.index)(0.5875618)) == pytest.approx(1.5)
    assert float(jax.jit(b.index)(0.5875618)) == pytest.approx(1.7)
    # get_material inside a jitted function: its nd check raised ConcretizationTypeError.
    n = jax.jit(lambda w: jl.get_material("N-BK7").index(w))(0.5875618)
    assert float(n) == pytest.approx(1.5168, abs=1e-4)


# ------------------------------------------------------------------ tables beyond their data


def test_a_table_refuses_a_wavelength_beyond_its_data():
    """Before: index(1.0) of a 0.45–0.65 µm table was its end value 1.515, and so was every
    index a lens gave there (``Lens.indices``)."""
    tab = jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515], name="TAB")
    with pytest.raises(ValueError, match=r"^Tabulated\.index \(TAB\): wavelength 1 µm is outside "
                                         r"0\.44955–0\.65065 µm, the data range of TAB.*"
                                         r"extrapolated_index"):
        tab.index(1.0)
    lens = jl.Lens((jl.Sphere(0.02), jl.Sphere(-0.02)), jnp.array([5.0, 45.0]), (tab, jl.Air()),
                   epd=10.0, wavelengths=[0.55])
    with pytest.raises(ValueError, match=r"outside 0\.44955–0\.65065 µm"):
        lens.indices(1.0)
    assert float(tab.extrapolated_index(1.0)) == pytest.approx(1.515)
    assert float(tab.index(0.65)) == pytest.approx(1.515)
    assert float(jl.Tabulated([0.55], [1.5]).index(5.0)) == 1.5  # one node: no dispersion


def test_abbe_number_of_a_table_without_the_f_and_c_lines(monkeypatch):
    """Before: 168 for a table from 0.6 µm (nF held at the 0.6 µm index)."""
    part = jl.Tabulated([0.6, 0.7, 0.8], [1.52, 1.515, 1.51], name="PART")
    with pytest.raises(ValueError, match=r"^abbe_number: the table of Tabulated 'PART' spans "
                                         r"0\.5994–0\.8008 µm, which does not hold the F and C "
                                         r"lines"):
        abbe_number(part)
    # The number of the held values, on request: nd = nF = n(0.6 µm) = 1.52, and nC
    # interpolated in 1/λ² between the 0.6 and 0.7 µm nodes.
    x = lambda w: w ** -2  # noqa: E731
    n_c = 1.515 + 0.005 * (x(0.6562725) - x(0.7)) / (x(0.6) - x(0.7))
    assert float(abbe_number(part, held_ends=True)) == pytest.approx(0.52 / (1.52 - n_c),
                                                                     rel=1e-5)
    fdc = jl.zoo.cooke_triplet().materials[0]  # a table at F, d and C
    assert float(abbe_number(fdc)) == pytest.approx(60.3, abs=0.1)
    # glass_info refuses it by name; nearest_glasses leaves it off the glass map.
    monkeypatch.setattr(catalog, "_user_catalogs", [])
    jl.register_catalog({"PART": part}, name="R18")
    with pytest.raises(ValueError, match=r"does not hold the F and C lines"):
        jl.glass_info("PART")
    assert all(n != "PART" for _, n, _, _ in catalog.nearest_glasses(1.52, 100.0, count=50))


# ------------------------------------------------------------------ small entry points


@pytest.mark.parametrize("bad", [3, [1]])
def test_catalog_names_refuses_a_catalog_that_is_not_a_name(bad):
    """Before: TypeError "'int' object is not iterable"."""
    with pytest.raises(TypeError, match=r"^catalogs must be a catalog name \(str\) or a list "
                                        r"of them"):
        jl.catalog_names(bad) if bad == 3 else jl.catalog_names(catalogs=bad)


def test_self_intersection_refuses_a_negative_clearance():
    """Before: min_gap=-1 passed surfaces crossed by up to 1 mm (``ok`` True)."""
    with pytest.raises(ValueError, match=r"^self_intersection: min_gap must be a finite number "
                                         r"in \[0, inf\) mm"):
        self_intersection(jl.zoo.cooke_triplet(), min_gap=-1.0)


@pytest.mark.parametrize("kw, arg", [(dict(pupil_side=1), "pupil_side"),
                                     (dict(subsamples=0), "subsamples"),
                                     (dict(kernel_size=0), "kernel_size")])
def test_encircled_energy_checks_its_diffraction_settings_with_any_method(kw, arg):
    """Before: with the geometric method they passed without a word."""
    with pytest.raises(ValueError, match=rf"^encircled_energy: {arg} must be a whole number"):
        encircled_energy(jl.zoo.cooke_triplet(), 0.0, [0.01], **kw)


def test_wavefront_grid_and_newton_iters_are_bounded():
    """Before: grid=100000 ran out of memory (80 GB) after the trace set-up, and
    newton_iters=10**9 ran a loop of that length on every aspheric surface."""
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"^wavefront: grid must be a whole number in "
                                         r"\[3, 4096\] pupil samples per side"):
        wavefront(lens, 0.0, grid=100000)
    with pytest.raises(ValueError, match=r"^rms_spot: newton_iters must be a whole number in "
                                         r"\[0, 1000\] iterations"):
        rms_spot(jl.zoo.cellphone6(), newton_iters=10**9)


@pytest.mark.parametrize("x, y", [(np.zeros(40), np.zeros(40)),
                                  (np.linspace(-1, 1, 40), np.zeros(40))],
                         ids=["one spot", "one line"])
def test_zernike_fit_refuses_points_that_cannot_tell_the_terms_apart(x, y):
    """Before: NaN coefficients (a singular normal matrix), or noise."""
    with pytest.raises(ValueError, match=r"^zernike_fit: the 40 fitted points cannot determine "
                                         r"4 terms"):
        zernike_fit(x, y, np.zeros(40), terms=4)
    g = np.linspace(-0.7, 0.7, 9)
    xx, yy = np.meshgrid(g, g)
    fit = zernike_fit(xx, yy, 0.3 + 0.0 * xx, terms=4)
    assert float(fit.coefficients[0]) == pytest.approx(0.3, abs=1e-12)


def test_normalised_weights_refuses_no_weight():
    """Before: a list was a TypeError from jnp.sum, and [0, 0] gave NaN weights."""
    with pytest.raises(ValueError, match=r"^normalised_weights: weights must hold a positive"):
        normalised_weights([0.0, 0.0])
    with pytest.raises(ValueError, match=r"^normalised_weights: weights must be"):
        normalised_weights([-1.0, 2.0])
    assert np.asarray(normalised_weights([1, 3])).tolist() == [0.25, 0.75]
