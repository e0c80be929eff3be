"""Rectangular, elliptical and decentered apertures and obscurations (``Lens.apertures``):
read from .zmx (SQAP, ELAP, SQOB, ELOB, CLAP/OBSC with OBDC), traced, written back."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.lens import unclipped

WL = 0.5875618


def _text(lines, system="ENPD 10\n"):
    """A plano-convex singlet (model glass n = 1.5) whose flat first surface, the stop,
    carries ``lines``."""
    return (f"UNIT MM\n{system}WAVM 1 {WL} 1\nSURF 0\n  DISZ INFINITY\n"
            f"SURF 1\n  STOP\n  CURV 0\n  DISZ 4\n  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"
            f"{lines}SURF 2\n  CURV -0.02\n  DISZ 90\nSURF 3\n  CURV 0\n")


def _grid():
    """Parallel rays on a 41 × 41 grid (mm) that puts no ray on an aperture's rim."""
    g = np.linspace(-6.0, 6.0, 41) + 0.0123
    x, y = np.meshgrid(g, g)
    return x.ravel(), y.ravel()


def _valid(lens, x, y):
    o = jnp.stack([jnp.asarray(x), jnp.asarray(y), jnp.full(x.shape, -1.0)], -1)
    d = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), o.shape)
    return np.asarray(jl.trace(lens, jl.Rays(o, d, WL)).valid)


def _check(lines, inside, blocks=False):
    lens = zmx.loads(_text(lines), "t.zmx")
    x, y = _grid()
    want = ~inside(x, y) if blocks else inside(x, y)
    assert 0 < want.sum() < want.size
    np.testing.assert_array_equal(_valid(lens, x, y), want)
    return lens


def test_rectangular_aperture_passes_exactly_the_rays_inside():
    lens = _check("  SQAP 3 2 0\n", lambda x, y: (np.abs(x) <= 3) & (np.abs(y) <= 2))
    assert lens.apertures == ((0, jl.Aperture("rect", 3.0, 2.0)),)
    assert float(lens.surfaces[0].semi_diameter) == np.inf


def test_elliptical_aperture_passes_exactly_the_rays_inside():
    _check("  ELAP 4 2.5 0\n", lambda x, y: (x / 4) ** 2 + (y / 2.5) ** 2 <= 1)


def test_decentered_apertures_pass_exactly_the_rays_inside():
    # A decentered circle (CLAP with OBDC) clips alone: the semi-diameter does not.
    _check("  CLAP 0 3 0\n  OBDC 1.5 -2\n", lambda x, y: (x - 1.5) ** 2 + (y + 2) ** 2 <= 9)
    # A decentered rectangle, and a decenter in the file's unit (CM: ×10 mm).
    _check("  SQAP 2 3 0\n  OBDC -1 0.5\n",
           lambda x, y: (np.abs(x + 1) <= 2) & (np.abs(y - 0.5) <= 3))
    lens = zmx.loads(_text("  ELAP 0.4 0.2 0\n  OBDC 0.1 0\n").replace("UNIT MM", "UNIT CM"))
    assert lens.apertures == ((0, jl.Aperture("ellipse", 4.0, 2.0, 1.0, 0.0)),)


def test_rectangular_and_elliptical_obscurations_block_the_inside():
    _check("  SQOB 2 1 0\n", lambda x, y: (np.abs(x) <= 2) & (np.abs(y) <= 1), blocks=True)
    _check("  ELOB 2 3 0\n  OBDC 0 1\n", lambda x, y: (x / 2) ** 2 + ((y - 1) / 3) ** 2 <= 1,
           blocks=True)


def test_decentered_disc_obscuration_and_annulus():
    # A decentered disc obscuration (OBSC with OBDC) and the centre of a decentered annulus.
    _check("  OBSC 0 2 0\n  OBDC 1 1\n", lambda x, y: (x - 1) ** 2 + (y - 1) ** 2 <= 4,
           blocks=True)
    _check("  CLAP 1 5 0\n  OBDC 1 0\n",
           lambda x, y: ((x - 1) ** 2 + y**2 <= 25) & ((x - 1) ** 2 + y**2 > 1))


def test_apertures_in_a_run_of_surfaces_and_on_the_image(tmp_path):
    """Apertures on a surface inside a run of same-kind surfaces (traced one by one) and on
    the image surface (index len(surfaces)); aiming ignores them (``unclipped``)."""
    flat = jl.Standard(c=0.0, k=0.0)
    rect = jl.Aperture("rect", 2.0, 5.0, decenter_x=1.0)
    disc = jl.Aperture.circle(4.0, 0.0, -1.0)
    lens = jl.Lens((flat, flat, flat), jnp.array([1.0, 1.0, 1.0]), (jl.Air(),) * 3, epd=10.0,
                   apertures=((1, rect), (3, disc)))
    x, y = _grid()
    want = (np.abs(x - 1) <= 2) & (np.abs(y) <= 5) & (x**2 + (y + 1) ** 2 <= 16)
    np.testing.assert_array_equal(_valid(lens, x, y), want)
    assert unclipped(lens).apertures == ()
    assert _valid(unclipped(lens), x, y).all()
    assert json_round_trip(lens, tmp_path).apertures == lens.apertures
    with pytest.raises(ValueError, match="apertures"):
        jl.tracing.backward.reversed_lens(lens)


def test_save_and_load_keep_the_apertures(tmp_path):
    text = _text("  SQAP 3 2 0\n  ELOB 1 0.5 0\n  OBDC 0.5 -0.25\n")
    lens = zmx.loads(text, "t.zmx")
    jl.save(lens, tmp_path / "a.zmx")
    again = jl.load(tmp_path / "a.zmx")
    assert again.apertures == lens.apertures == (
        (0, jl.Aperture("rect", 3.0, 2.0, 0.5, -0.25)),
        (0, jl.Aperture("ellipse", 1.0, 0.5, 0.5, -0.25, blocks=True)))
    x, y = _grid()
    np.testing.assert_array_equal(_valid(again, x, y), _valid(lens, x, y))
    for lines in ("  CLAP 1 5 0\n  OBDC 1 0\n", "  OBSC 0 2 0\n  OBDC 1 1\n",
                  "  SQOB 2 1 0\n", "  ELAP 4 2.5 0\n"):
        lens = zmx.loads(_text(lines), "t.zmx")
        jl.save(lens, tmp_path / "b.zmx")
        assert jl.load(tmp_path / "b.zmx").apertures == lens.apertures != ()
    # Different decenters on one surface have no .zmx form (one OBDC per surface).
    flat = jl.Standard(c=0.0, k=0.0)
    two = jl.Lens((flat,), jnp.array([1.0]), (jl.Air(),), epd=1.0, apertures=(
        (0, jl.Aperture.circle(1.0, 0.1)), (0, jl.Aperture("rect", 1.0, 1.0, 0.2))))
    with pytest.raises(ValueError, match="different decenters"):
        jl.save(two, tmp_path / "c.zmx")
    # JSON holds each aperture's own decenter.
    assert json_round_trip(two, tmp_path).apertures == two.apertures


def test_bad_aperture_values_are_refused():
    with pytest.raises(ValueError, match=r"half_x must be a finite number > 0 \(mm\), got -1"):
        jl.Aperture("rect", -1.0, 2.0)
    with pytest.raises(ValueError, match=r"half_y must be a finite number > 0 \(mm\), got inf"):
        jl.Aperture("ellipse", 1.0, float("inf"))
    with pytest.raises(ValueError, match=r"decenter_y must be a finite number \(mm\), got nan"):
        jl.Aperture("rect", 1.0, 1.0, 0.0, float("nan"))
    with pytest.raises(ValueError, match="shape must be one of"):
        jl.Aperture("square", 1.0, 1.0)
    with pytest.raises(ValueError, match="a circle has half_x == half_y"):
        jl.Aperture("circle", 1.0, 2.0)
    flat = jl.Standard(c=0.0, k=0.0)
    ap = jl.Aperture.circle(1.0)
    with pytest.raises(ValueError, match=r"surface index in \[0, 1\] .*1 is the image"):
        jl.Lens((flat,), jnp.array([1.0]), (jl.Air(),), apertures=((2, ap),))
    with pytest.raises(ValueError, match="coordinate break; it has no aperture"):
        jl.Lens((jl.CoordinateBreak(), flat), jnp.array([1.0, 1.0]), (jl.Air(),) * 2,
                apertures=((0, ap),))
    with pytest.raises(ValueError, match="needs half-widths > 0"):
        zmx.loads(_text("  SQAP 0 2 0\n"), "t.zmx")


def test_floating_stop_needs_a_centred_circular_stop_aperture():
    """FLOA takes the pupil from the stop's radius: a rectangular, elliptical or decentered
    stop aperture is refused there (it is read with ENPD, FNUM or OBNA)."""
    assert float(zmx.loads(_text("  CLAP 0 3 0\n", "FLOA\n")).epd) == pytest.approx(6.0)
    for lines in ("  CLAP 0 3 0\n  OBDC 0 1\n", "  SQAP 3 3 0\n  CLAP 0 3 0\n"):
        with pytest.raises(ValueError, match="FLOA .* needs a centred circular stop aperture"):
            zmx.loads(_text(lines, "FLOA\n"), "t.zmx")
        zmx.loads(_text(lines), "t.zmx")


def test_a_blocked_chief_ray_still_marks_the_psf_reference():
    # A central obscuration (a Cassegrain's secondary) blocks the chief ray; as a reference
    # point it is traced unobscured, so the PSF is centred where it lands, not where it stopped.
    from jaxlens.imaging.aiming import chief_point

    def singlet(obscurations):
        return jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.02)),
                       thickness=jnp.array([5.0, 47.0]),
                       materials=(jl.get_material("N-BK7"), jl.Air()), epd=10.0,
                       fields=jnp.array([0.0, 3.0]), obscurations=obscurations)

    chief = eqx.filter_jit(lambda lens: chief_point(lens, 3.0, None, 6))
    clear = chief(singlet(()))
    for surface in (0, 1):
        blocked = singlet(((surface, 0.0, 2.0),))
        assert not bool(jl.trace(blocked, jl.sampling.collimated(blocked, 3.0,
                                                                 jnp.zeros((1, 2)))).valid[0])
        assert not unclipped(blocked).obscurations
        np.testing.assert_allclose(chief(blocked), clear, rtol=0, atol=1e-12)
    psf = jl.psf(blocked, 3.0, kernel_size=41, pixel_size=0.02, center="chief")
    assert float(jnp.sum(psf)) > 0.99
