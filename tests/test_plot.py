"""Figures: what ``plot_layout`` draws is the traced rays, and bad fields are refused."""

import warnings

import jax
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
    # One compiled fan for every field (op by op, each field compiled the trace again).
    fan = jax.jit(lambda f: jaxlens.trace_path(lens, sampling.collimated(lens, f, pupil)))
    for i, f in enumerate(fields):
        path = fan(f)
        drawn = lines[i * (n + 1): i * (n + 1) + n]  # n rays, then the legend's empty line
        for j, line in enumerate(drawn):
            z, y = line.get_data()
            np.testing.assert_allclose(z[1:], np.asarray(path.origin[:, j, 2]), atol=1e-9)
            np.testing.assert_allclose(y[1:], np.asarray(path.origin[:, j, 1]), atol=1e-9)
            assert line.get_linestyle() == ("-" if bool(path.valid[-1, j]) else ":")


def test_layout_of_a_finite_object_draws_rays_from_that_object():
    """A lens with its object at 300 mm: the fans diverge from the object points (they were
    drawn as collimated beams, an object at infinity)."""
    import equinox as eqx

    lens = eqx.tree_at(lambda L: L.object_distance, jaxlens.zoo.cooke_triplet(), 300.0,
                       is_leaf=lambda x: x is None)
    fields, n = [0.0, 10.0], 5
    lines = plot.plot_layout(lens, fields, n_rays=n).axes[0].lines
    pupil = jnp.stack([jnp.zeros(n), jnp.linspace(-1.0, 1.0, n)], -1)
    for i, f in enumerate(fields):
        path = jaxlens.trace_path(lens, sampling.field_rays(lens, f, pupil, depth=300.0))
        obj_y = float(sampling.object_point(lens, f, 300.0)[1])
        for j, line in enumerate(lines[i * (n + 1): i * (n + 1) + n]):
            z, y = line.get_data()
            np.testing.assert_allclose(y[1:], np.asarray(path.origin[:, j, 1]), atol=1e-9)
            # Extended back, each drawn ray meets its object point at z = −300 mm.
            slope = (y[1] - y[0]) / (z[1] - z[0])
            np.testing.assert_allclose(y[0] + slope * (-300.0 - z[0]), obj_y, atol=1e-9)


def test_layout_refuses_a_field_out_of_range_before_tracing():
    lens = jaxlens.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"plot_layout: fields must be finite angles in "
                                         r"\(-90, 90\) deg, got 95 deg"):
        plot.plot_layout(lens, [0.0, 95.0])


def test_layout_of_a_decentered_mirror_is_drawn_in_global_coordinates(recwarn):
    """A 90° off-axis parabola (a coordinate break decenters the mirror by −190.6 mm, its
    focus 95.3 mm in front of the vertex): the collimated beam along the axis is drawn
    hitting the mirror near z = 200 − 95.3 and turning down to the focus at y = −190.6,
    where the image plane is drawn. In the tracer's frames the beam would sit at
    y ≈ +190.6 and never meet the drawn stop."""
    from pathlib import Path

    lens = jaxlens.load(Path(__file__).parent / "data" / "zmx" / "rayoptics_zmax_37992.zmx")
    n = 5
    fig = plot.plot_layout(lens, [0.0], n_rays=n)
    rays = [ln for ln in fig.axes[0].lines[:n] if ln.get_linestyle() == "-"]
    assert len(rays) >= n - 2  # the two rim rays may be clipped at the 25.4 mm apertures
    for line in rays:
        z, y = (np.asarray(v) for v in line.get_data())
        assert abs(y[0]) <= 25.41  # launched inside the 25.4 mm stop, about the axis
        assert z[-1] == pytest.approx(200 - 95.3, abs=1e-6)  # ends on the image plane
        assert y[-1] == pytest.approx(-190.6, abs=1e-3)  # at the parabola's focus
    image = fig.axes[0].lines[-1]
    zi, yi = (np.asarray(v) for v in image.get_data())
    np.testing.assert_allclose(zi, 200 - 95.3, atol=1e-9)
    assert yi.min() < -190.6 < yi.max()


def test_layout_draws_the_on_axis_fan_once():
    """A lens with one on-axis field gets one fan (0, 70 % and 100 % of 0° are one field)."""
    lens = jaxlens.zoo.cooke_triplet()
    lens = jaxlens.Lens(**{**{f: getattr(lens, f) for f in ("surfaces", "thickness",
                                                             "materials", "epd", "stop")},
                           "fields": (0.0,)})
    fig = plot.plot_layout(lens, n_rays=3)
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["0.0°"]


def test_figures_of_a_lens_with_x_y_fields_show_its_own_fields():
    """A lens set up for (θx, θy) fields: the spot diagrams and MTF show those fields, not y
    fields up to the largest angle (for a tilted system, such as
    tests/data/zmx/rayoptics_HoO-V2C18Ex66.zmx, a 9° x field is not a 9° y field)."""
    base = jaxlens.zoo.cooke_triplet()
    lens = jaxlens.Lens(**{**{f: getattr(base, f) for f in ("surfaces", "thickness",
                                                            "materials", "epd", "stop")},
                           "fields": ((0.0, 0.0), (12.0, 0.0), (3.0, -5.0))})
    fields = np.asarray(lens.fields)
    titles = [ax.get_title() for ax in plot.plot_spots(lens, rings=3).axes]
    assert [t.split("  RMS")[0] for t in titles] == [f"({x:.1f}°, {y:.1f}°)" for x, y in fields]
    legend = plot.plot_mtf(lens, frequencies=[10.0]).axes[0].get_legend().get_texts()
    assert [t.get_text() for t in legend][::2] == [f"({x:.1f}°, {y:.1f}°) T" for x, y in fields]


def test_layout_draws_the_image_surface_as_it_is():
    """A tilted image plane is drawn tilted (it was a flat line at the vertex), and long
    enough to hold every ray that lands on it."""
    base = jaxlens.zoo.cooke_triplet()
    lens = jaxlens.Lens(**{**{f: getattr(base, f) for f in ("surfaces", "thickness",
                                                            "materials", "epd", "stop",
                                                            "fields")},
                           "image": jaxlens.TiltedPlane(tan_y=0.2)})
    fig = plot.plot_layout(lens, n_rays=3)
    z, y = (np.asarray(v) for v in fig.axes[0].lines[-1].get_data())
    np.testing.assert_allclose(z, float(lens.image_z()) + 0.2 * y, atol=1e-12)
    ends = [np.asarray(ln.get_data()[1])[-1] for ln in fig.axes[0].lines[:-1]
            if ln.get_linestyle() == "-" and len(ln.get_data()[1])]
    assert max(abs(e) for e in ends) > 15 and y.max() >= max(abs(e) for e in ends)


def test_fans_and_field_curves_draw_the_analysis_data():
    """``plot_ray_fans`` draws ``ray_fan`` (µm) per field and wavelength; ``plot_field_curvature``
    draws ``field_curvature`` (T dashed, S solid) against θy, and the distortion."""
    from jaxlens.analysis import aberrations, spots

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fig = plot.plot_ray_fans(lens, [0.0, 20.0], n=7)
    assert len(fig.axes) == 4
    fan = aberrations.ray_fan(lens, 20.0, n=7)
    for i, line in enumerate(fig.axes[2].lines[:3]):  # 20° tangential, three wavelengths
        x, y = line.get_data()
        np.testing.assert_allclose(x, np.asarray(fan.pupil))
        np.testing.assert_allclose(y, np.asarray(fan.tangential[i]) * 1e3, atol=1e-9)
    fig = plot.plot_field_curvature(lens)
    fc = aberrations.field_curvature(lens, aberrations.default_fields(lens, 21))
    t_line, s_line = fig.axes[0].lines[0], fig.axes[0].lines[1]
    assert t_line.get_linestyle() == "--" and s_line.get_linestyle() == "-"
    np.testing.assert_allclose(t_line.get_data()[0], np.asarray(fc.tangential[0]), atol=1e-9)
    np.testing.assert_allclose(s_line.get_data()[0], np.asarray(fc.sagittal[0]), atol=1e-9)
    np.testing.assert_allclose(t_line.get_data()[1], np.asarray(fc.fields))
    d = spots.distortion(lens, fc.fields)
    np.testing.assert_allclose(fig.axes[1].lines[0].get_data()[0],
                               np.asarray(d.percent_ftan)[1:], atol=1e-9)


# --------------------------------------------------------------------------------------
# Wavefront map, OPD fans, Seidel diagram, encircled energy
# --------------------------------------------------------------------------------------
def test_wavefront_figure_draws_the_analysis_map_and_its_statistics():
    """The image is ``wavefront(...).map`` (NaN blank) over [−1, 1]² with a colour scale
    centred on 0; the title gives RMS and P-V, and Maréchal's Strehl only where the RMS with
    tilt removed is at most 0.1 wave (the full Cooke triplet: 0.32 wave at 20°, not shown;
    at 0.3× its EPD: 0.047 wave, shown). The default field is the largest (20°)."""
    import equinox as eqx

    from jaxlens.analysis import wavefront

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fig = plot.plot_wavefront(lens, grid=17)
    wf = wavefront(lens, 20.0, grid=17)
    ax = fig.axes[0]
    im = ax.images[0]
    np.testing.assert_array_equal(np.ma.filled(im.get_array().astype(float), np.nan),
                                  np.asarray(wf.map))  # NaN where NaN, else equal
    assert np.isnan(np.asarray(wf.map)).any()  # the corners: there is something blank
    assert im.origin == "lower"  # row i at Py = pupil[i]: +Py up
    lo, hi = im.get_clim()
    assert lo == -hi and hi == pytest.approx(float(np.nanmax(np.abs(np.asarray(wf.map)))))
    np.testing.assert_allclose(im.get_extent(), [-1 - 1 / 16, 1 + 1 / 16] * 2)
    title = ax.get_title()
    assert title.startswith("wavefront map, 20.0°\n")
    assert f"RMS {float(wf.rms):.4f} waves, P-V {float(wf.pv):.4f} waves" in title
    assert "no Strehl: RMS tilt removed 0.325 > 0.1 wave" in title
    assert "waves at 0.5876 µm" in fig.axes[1].get_ylabel()  # the colour bar
    small = eqx.tree_at(lambda L: L.epd, lens, lens.epd * 0.3)
    wf = wavefront(small, 0.0, grid=17)
    title = plot.plot_wavefront(small, 0.0, grid=17, title="small").axes[0].get_title()
    assert title.startswith("small\n")
    assert f"Strehl {float(wf.strehl):.3f} (Maréchal)" in title and "0.918" in title


def test_opd_fan_figure_draws_the_analysis_fans():
    """Per field a row: tangential OPD against Py, sagittal against Px, one line per
    wavelength, in waves (``opd_fan``)."""
    from jaxlens.analysis import opd_fan

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fig = plot.plot_opd_fans(lens, [0.0, 20.0], n=7)
    assert len(fig.axes) == 4
    fan = opd_fan(lens, 20.0, n=7)
    for ax, opd in ((fig.axes[2], fan.tangential), (fig.axes[3], fan.sagittal)):
        assert ax.get_ylabel() == "OPD (waves)"
        for i, line in enumerate(ax.lines[:3]):
            x, y = line.get_data()
            np.testing.assert_allclose(x, np.asarray(fan.pupil))
            np.testing.assert_allclose(y, np.asarray(opd[i]), atol=1e-12)
    assert [ax.get_xlabel() for ax in fig.axes[2:]] == ["Py", "Px"]


def test_seidel_diagram_bars_are_the_wavefront_terms_and_their_sums(tmp_path):
    """A group of seven bars per surface and a "Sum" group: the heights are
    ``seidel(lens).wavefront(per_surface=True)`` and ``.wavefront()`` (waves), in the order
    of ``WAVEFRONT_TERMS``; ``save`` writes a PNG."""
    from jaxlens.analysis import seidel
    from jaxlens.analysis.third_order import WAVEFRONT_TERMS

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fig = plot.plot_seidel(lens)
    s = seidel(lens)
    per, sums = np.asarray(s.wavefront(per_surface=True)), np.asarray(s.wavefront())
    ax = fig.axes[0]
    assert len(ax.containers) == 7
    for k, bars in enumerate(ax.containers):
        heights = [b.get_height() for b in bars]
        np.testing.assert_allclose(heights[:-1], per[k], atol=1e-9)
        np.testing.assert_allclose(heights[-1], sums[k], atol=1e-9)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert [x.split()[0] for x in labels] == list(WAVEFRONT_TERMS)
    assert [t.get_text() for t in ax.get_xticklabels()][-1] == "Sum"
    assert ax.get_ylabel() == "waves at 0.5876 µm"
    path = plot.save(fig, tmp_path / "seidel.png")
    with open(path, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_seidel_diagram_of_a_lens_seidel_refuses_raises_its_error(recwarn, monkeypatch):
    """A lens with a coordinate break: ``seidel``'s ValueError, unchanged, and nothing
    drawn."""
    from pathlib import Path

    from jaxlens.analysis import seidel

    lens = jaxlens.load(Path(__file__).parent / "data" / "zmx" / "rayoptics_zmax_37992.zmx")
    with pytest.raises(ValueError) as direct:
        seidel(lens)
    monkeypatch.setattr(plot, "_figure", lambda *a: pytest.fail("drew before refusing"))
    with pytest.raises(ValueError) as drawn:
        plot.plot_seidel(lens)
    assert str(drawn.value) == str(direct.value)
    assert str(drawn.value).startswith("seidel: surface 1 (CoordinateBreak)")


def test_encircled_energy_figure_draws_the_analysis_curves_and_d80():
    """Each field's line is ``encircled_energy`` at the drawn radii (x in µm); the dotted
    marker stands at ``radius_for_fraction(…, 0.8)``, the legend gives D80 = twice it; the
    default axis ends at 1.5 times the largest 99 % radius."""
    from jaxlens.analysis import encircled_energy, radius_for_fraction

    lens = jaxlens.zoo.cooke_triplet().astype(jnp.float64)
    fields = [0.0, 20.0]
    ax = plot.plot_encircled_energy(lens, fields).axes[0]
    r = [np.asarray(radius_for_fraction(lens, f, jnp.asarray([0.8, 0.99]))) for f in fields]
    assert ax.get_xlim()[1] == pytest.approx(1.5e3 * max(x[1] for x in r), rel=1e-12)
    assert ax.get_xlabel() == "radius from the energy centroid (µm)"
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    for i, f in enumerate(fields):
        curve, marker = ax.lines[2 * i], ax.lines[2 * i + 1]
        x, y = (np.asarray(v) for v in curve.get_data())
        assert x[-1] == pytest.approx(ax.get_xlim()[1]) and len(x) > 100
        ee = encircled_energy(lens, f, jnp.asarray(x * 1e-3)).energy
        np.testing.assert_allclose(y, np.asarray(ee), atol=1e-12)
        assert y[0] < 0.8 and y[-1] == 1.0  # the whole rise is inside the axis
        np.testing.assert_allclose(marker.get_data()[0], [r[i][0] * 1e3] * 2, rtol=1e-12)
        assert texts[i] == f"{f:.1f}°: D80 {2e3 * r[i][0]:.2f} µm"


def test_new_figures_refuse_bad_fields_before_tracing(monkeypatch):
    """A field out of range (or not one field) is refused, naming the figure, before any
    analysis runs (the analyses are replaced by ones that fail the test if called)."""
    from jaxlens.analysis import encircled, wavefront_error

    for mod, name in ((wavefront_error, "wavefront"), (wavefront_error, "opd_fan"),
                      (encircled, "encircled_energy"), (encircled, "radius_for_fraction")):
        monkeypatch.setattr(mod, name, lambda *a, **k: pytest.fail("traced"))
    lens = jaxlens.zoo.cooke_triplet()
    msg = r"must be finite angles in \(-90, 90\) deg, got 95 deg"
    with pytest.raises(ValueError, match=r"plot_wavefront: field " + msg):
        plot.plot_wavefront(lens, 95.0)
    with pytest.raises(ValueError, match=r"plot_wavefront: field must be one field"):
        plot.plot_wavefront(lens, [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match=r"plot_opd_fans: fields " + msg):
        plot.plot_opd_fans(lens, [0.0, 95.0])
    with pytest.raises(ValueError, match=r"plot_encircled_energy: fields " + msg):
        plot.plot_encircled_energy(lens, [0.0, 95.0])
    with pytest.raises(ValueError, match=r"plot_opd_fans: fields must hold at least one"):
        plot.plot_opd_fans(lens, [])
    with pytest.raises(ValueError, match=r"plot_encircled_energy: max_radius must be"):
        plot.plot_encircled_energy(lens, [0.0], max_radius=-1.0)


def test_wavefront_figure_of_a_lens_with_x_y_fields():
    """A lens set up for (θx, θy) fields: the wavefront map defaults to the largest pair
    (12°, 0°), given to the analysis as an array (a tuple made it warn)."""
    from jaxlens.analysis import wavefront

    base = jaxlens.zoo.cooke_triplet()
    lens = jaxlens.Lens(**{**{f: getattr(base, f) for f in ("surfaces", "thickness",
                                                            "materials", "epd", "stop")},
                           "fields": ((0.0, 0.0), (12.0, 0.0), (3.0, -5.0))})
    with warnings.catch_warnings():  # pyproject ignores them; a future JAX will raise
        warnings.simplefilter("error", DeprecationWarning)
        ax = plot.plot_wavefront(lens, grid=9).axes[0]
    assert ax.get_title().startswith("wavefront map, (12.0°, 0.0°)\n")
    np.testing.assert_array_equal(np.ma.filled(ax.images[0].get_array().astype(float), np.nan),
                                  np.asarray(wavefront(lens, jnp.asarray([12.0, 0.0]),
                                                       grid=9).map))


@pytest.mark.slow
def test_opd_fans_and_encircled_energy_of_x_y_fields():
    """(θx, θy) pairs reach ``opd_fan`` and ``encircled_energy`` as arrays (no warning) and
    are labelled as pairs."""
    lens = jaxlens.zoo.cooke_triplet()
    with warnings.catch_warnings():  # pyproject ignores them; a future JAX will raise
        warnings.simplefilter("error", DeprecationWarning)
        fig = plot.plot_opd_fans(lens, [(3.0, -5.0)], n=5)
        ax = plot.plot_encircled_energy(lens, [(3.0, -5.0)]).axes[0]
    assert [a.get_title() for a in fig.axes] == ["(3.0°, -5.0°) tangential",
                                                 "(3.0°, -5.0°) sagittal"]
    assert ax.get_legend().get_texts()[0].get_text().startswith("(3.0°, -5.0°): D80 ")
