"""Figures: what ``plot_layout`` draws is the traced rays, and bad fields are refused."""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens import plot
from jaxlens.imaging import sampling


def test_layout_draws_each_fields_traced_fan():
    """Each drawn ray passes through the points of ``trace_path`` of its field's fan (the
    fans are traced in one compiled program), dotted where the ray is lost."""
    lens = jaxlens.zoo.cooke_triplet()
    fields, n = [0.0, 14.0, 24.0], 5
    fig = plot.plot_layout(lens, fields, n_rays=n)
    lines = fig.axes[0].lines
    pupil = jnp.stack([jnp.zeros(n), jnp.linspace(-1.0, 1.0, n)], -1)
    for i, f in enumerate(fields):
        path = jaxlens.trace_path(lens, sampling.collimated(lens, f, pupil))
        drawn = lines[i * (n + 1): i * (n + 1) + n]  # n rays, then the legend's empty line
        for j, line in enumerate(drawn):
            z, y = line.get_data()
            np.testing.assert_allclose(z[1:], np.asarray(path.origin[:, j, 2]), atol=1e-9)
            np.testing.assert_allclose(y[1:], np.asarray(path.origin[:, j, 1]), atol=1e-9)
            assert line.get_linestyle() == ("-" if bool(path.valid[-1, j]) else ":")


def test_layout_refuses_a_field_out_of_range_before_tracing():
    lens = jaxlens.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"plot_layout: fields must be finite angles in "
                                         r"\(-90, 90\) deg, got 95 deg"):
        plot.plot_layout(lens, [0.0, 95.0])
