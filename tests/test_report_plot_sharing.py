"""``report --plot`` computes the field curvature once per program: the report's call (the
lens's fields, primary wavelength) and the figure's (21 fields, every wavelength) share one
compiled program, with the numbers of the unshared calls."""

import logging

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens import plot
from jaxlens.analysis.aberrations import default_fields, field_curvature
from jaxlens.analysis.report import report_data


def test_report_and_its_field_curvature_figure_compile_one_field_curvature(caplog):
    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    with jax.log_compiles(True), caplog.at_level(logging.WARNING):
        data = report_data(lens)
        plot.plot_field_curvature(lens)
    compiled = [r.getMessage() for r in caplog.records if "Compiling" in r.getMessage()]
    # Before: one program for the report's [3] fields × 1 wavelength, one for the figure's
    # [21] × 3 (each about 8 s to trace and compile with ray aiming).
    assert sum("_field_curvature" in m for m in compiled) <= 1, compiled
    direct = field_curvature(lens, lens.fields, lens.primary_wavelength)
    got = [[f["focus_tangential"], f["focus_sagittal"]] for f in data["fields"]]
    want = np.stack([np.asarray(direct.tangential[0]), np.asarray(direct.sagittal[0])], -1)
    assert np.array_equal(np.asarray(got, float), want)  # bit for bit


def test_bucketed_field_curvature_is_the_unpadded_one_bit_for_bit():
    from jaxlens.analysis.report_cells import bucketed_field_curvature

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fields = default_fields(lens, 21)  # the figure's fields, padded to 32
    got, want = bucketed_field_curvature(lens, fields), field_curvature(lens, fields)
    assert got.tangential.shape == want.tangential.shape == (3, 21)
    for a, b in ((got.tangential, want.tangential), (got.sagittal, want.sagittal),
                 (got.fields, want.fields), (got.wavelengths, want.wavelengths)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_layout_semi_diameters_and_fans_from_one_program_are_the_separate_ones(monkeypatch):
    from jaxlens.analysis import spots

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    with monkeypatch.context() as m:  # plot_layout traces its rays in one program
        for where, name in ((spots, "clear_semi_diameters"), (plot, "_fans")):
            m.setattr(where, name, lambda *a, name=name, **k: pytest.fail(f"{name} called"))
        plot.plot_layout(lens, [0.0, 14.0, 20.0], n_rays=5)
    from jaxlens.analysis.spots import clear_semi_diameters, semi_diameters_and_fans

    fields = jnp.asarray([0.0, 14.0, 20.0])
    u = np.linspace(-1.0, 1.0, 5)
    pupil = jnp.asarray(np.stack([np.zeros_like(u), u], -1))
    sd, starts, dirs, path = semi_diameters_and_fans(lens, fields, pupil)
    want = [clear_semi_diameters(lens), *plot._fans(lens, fields, pupil)]
    for a, b in zip(jax.tree.leaves([sd, starts, dirs, path]), jax.tree.leaves(want),
                    strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))  # bit for bit


def test_layout_indexes_its_traced_rays_on_the_host(caplog):
    """``plot_layout`` takes its rays to NumPy once: indexing the device arrays field by field
    compiled a slicing program per shape (10 of a double Gauss layout's 50 compilations)."""
    import re

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    plot.plot_layout(lens, n_rays=11)  # the rays' program, compiled and kept
    jax.clear_caches()  # the eager programs, left by earlier calls, compiled anew
    with jax.log_compiles(True), caplog.at_level(logging.WARNING):
        plot.plot_layout(lens, n_rays=11)
    compiled = [r.getMessage() for r in caplog.records if "Compiling" in r.getMessage()]
    # A program of an array [fields, (surfaces,) 11 rays, …]: the rays, sliced on the device.
    on_rays = [m for m in compiled if any(len(d) >= 3 and "11" in d for d in
                                          (s.split(",") for s in re.findall(r"\[([\d,]+)\]", m)))]
    assert compiled and not on_rays, on_rays


def test_report_table_is_made_on_the_host(caplog):
    """``report_data`` takes the traced results to NumPy once: its per-field table (slices,
    percentages against f·tanθ) compiled a one-operation program per operation and shape,
    8 of the Cooke triplet report's 27 compilations; the numbers are the same IEEE ones."""
    import re

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)  # 3 fields, 3 wavelengths
    want = report_data(lens)  # the report's programs, compiled and kept
    jax.clear_caches()  # the eager programs, left by earlier calls, compiled anew
    with jax.log_compiles(True), caplog.at_level(logging.WARNING):
        got = report_data(lens)
    compiled = [r.getMessage() for r in caplog.records if "Compiling" in r.getMessage()]
    # The percentages' operations on [3] fields, the rows sliced from [3, 2] and [3, 3].
    table = [m for m in compiled
             if re.match(r"Compiling jit\((not_equal|_where|subtract|multiply)\)", m)
             and "float64[3]" in m
             or re.match(r"Compiling jit\((dynamic_slice|squeeze)\)", m)
             and re.search(r"float64\[(3,2|3,3|1,2|1,3)\]", m)]
    assert compiled and not table, table
    assert got == want
