"""Issue 12 (real lens files): clipping apertures and the image medium in written .zmx files,
real ray aiming through clipping apertures, the image-space focal length, and the reader's
apertures, field types and vignetting factors."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.imaging.aiming import unclipped

DATA = jl.__file__.rsplit("/", 1)[0] + "/data/lenses"


def _clip_front(lens, radius, count):
    """The lens with its first ``count`` surfaces clipped at ``radius`` (mm)."""
    surfaces = tuple(
        eqx.tree_at(lambda s: s.semi_diameter, s, jnp.asarray(radius)) if i < count else s
        for i, s in enumerate(lens.surfaces)
    )
    return eqx.tree_at(lambda m: m.surfaces, lens, surfaces)


def test_real_aiming_through_clipping_apertures():
    """Aimed rays cross the stop at pupil·(stop radius) even where the front apertures clip
    the paraxial launch points; the apertures then decide which rays pass.

    Before the aiming traced the unclipped lens, two of these rays were reported valid while
    crossing the stop up to 0.66 mm from their pupil point.
    """
    clip = 16.0
    lens = _clip_front(jl.load(f"{DATA}/double_gauss.json"), clip, 2)
    pupil = jl.sampling.pupil_hexapolar(3)
    target = np.asarray(pupil * jl.paraxial_data(lens).stop_semi_diameter)
    for field in (14.0, 20.0):
        rays = jl.sampling.collimated(lens, field, pupil, aim="real")
        free = jl.trace_path(unclipped(lens), rays)
        np.testing.assert_allclose(np.asarray(free.origin[lens.stop, :, :2]), target, rtol=0,
                                   atol=1e-9)
        # Known answer for validity: the aimed ray passes iff it stays inside both apertures.
        radius = np.linalg.norm(np.asarray(free.origin[:2, :, :2]), axis=-1).max(0)
        passes = (radius <= clip) & np.asarray(free.valid[-1])
        valid = np.asarray(jl.trace(lens, rays).valid)
        np.testing.assert_array_equal(valid, passes)
        assert 0 < passes.sum() < passes.size  # the apertures clip some rays, not all


def test_efl_in_air_and_in_image_space_for_a_singlet_into_glass():
    """A thick singlet whose image space is glass (n′ = 1.6): 1/Φ and n′/Φ from the
    thick-lens power Φ = Φ1 + Φ2 − (t/n)·Φ1·Φ2."""
    n, n_img, c1, c2, t = 1.5, 1.6, 1 / 40.0, -1 / 60.0, 4.0
    lens = jl.Lens(
        (jl.Sphere(c1), jl.Sphere(c2)),
        jnp.array([t, 50.0]),
        (jl.ModelGlass(n, np.inf), jl.ModelGlass(n_img, np.inf)),
        epd=5.0,
        fields=[0.0, 5.0],
        wavelengths=[0.5875618],
    )
    p1, p2 = (n - 1) * c1, (n_img - n) * c2
    power = p1 + p2 - t / n * p1 * p2
    pd = jl.paraxial_data(lens)
    assert float(pd.efl) == pytest.approx(1 / power, rel=1e-13)
    assert float(pd.efl_image_space) == pytest.approx(n_img / power, rel=1e-13)
    data = report.report_data(lens)
    assert data["efl"] == pytest.approx(1 / power, rel=1e-13)
    assert data["efl_image_space"] == pytest.approx(n_img / power, rel=1e-13)
    text = report.format_report(data)
    row = {line.split(":")[0].strip(): float(line.split(":")[1].split()[0])
           for line in text.splitlines() if line.startswith("  Effective focal")}
    assert row == {"Effective focal length (in air)": pytest.approx(1 / power, rel=1e-6),
                   "Effective focal length (img space)": pytest.approx(n_img / power, rel=1e-6)}
