"""Zemax's tilted surface (``TiltedPlane``, ``TYPE TILTSURF``): z = tan θx·x + tan θy·y.

Refraction is checked against Snell's law for the plane's normal computed by hand in numpy,
a tilted image plane against tracing to a flat image and intersecting each final ray with
the tilted plane by hand, and the ``.zmx`` reader and writer against each other and the
file's text.
"""

import math
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.analysis.tolerance import ToleranceModel
from jaxlens.design.params import Parameterization
from jaxlens.io import lensfile
from jaxlens.optics.rebase import rebase_conic
from jaxlens.tracing import backward, forward, surface_adjoint

TX, TY = 0.1, -0.25
XY = np.array([[0.0, 0.0], [0.3, -0.4], [1.2, 0.5], [-1.1, 1.6], [0.0, 2.0]])


def block(tx=TX, ty=TY, image=None):
    """A 5 mm N-BK7 block: flat entrance face, tilted exit face, image 20 mm behind."""
    return jl.Lens(
        surfaces=(jl.Plane(), jl.TiltedPlane(tan_x=tx, tan_y=ty)),
        thickness=jnp.array([5.0, 20.0]),
        materials=(jl.get_material("N-BK7"), jl.Air()),
        epd=4.0, fields=jnp.array([0.0, 5.0]),
        **({} if image is None else {"image": image}),
    )


def singlet(image=None, tan_y=0.05):
    """A plano-convex singlet whose plane back face is tilted about x."""
    return jl.Lens(
        surfaces=(jl.Sphere(0.05, semi_diameter=6.0), jl.TiltedPlane(tan_y=tan_y)),
        thickness=jnp.array([4.0, 36.0]),
        materials=(jl.get_material("N-BK7"), jl.Air()),
        epd=8.0, fields=jnp.array([0.0, 5.0]),
        **({} if image is None else {"image": image}),
    )


def axial_beam(lens, n=7):
    g = np.linspace(-1.5, 1.5, n)
    x, y = (a.ravel() for a in np.meshgrid(g, g))
    origin = np.stack([x, y, -np.ones_like(x)], -1)
    direction = np.broadcast_to([0.0, 0.0, 1.0], origin.shape)
    return jl.Rays(jnp.asarray(origin), jnp.asarray(direction), lens.primary_wavelength)


# ---------------------------------------------------------------------------- the sag
def test_sag_and_slope_are_the_formula():
    s = jl.TiltedPlane(tan_x=TX, tan_y=TY, semi_diameter=3.0)
    x, y = jnp.asarray(XY[:, 0]), jnp.asarray(XY[:, 1])
    z, inside = s.sag(x, y)
    np.testing.assert_allclose(np.asarray(z), TX * XY[:, 0] + TY * XY[:, 1], rtol=1e-15,
                               atol=1e-16)
    assert bool(jnp.all(inside))
    z2, gx, gy, _ = s.sag_and_grad(x, y)
    np.testing.assert_array_equal(np.asarray(z2), np.asarray(z))
    np.testing.assert_array_equal(np.asarray(gx), np.full(len(XY), TX))
    np.testing.assert_array_equal(np.asarray(gy), np.full(len(XY), TY))
    assert (float(s.c), float(s.k), float(s.paraxial_curvature)) == (0.0, 0.0, 0.0)
    assert s.has_polynomial  # traced by the Newton step, not the conic's closed form
    with pytest.raises(ValueError, match="TiltedPlane: tan_y must be finite"):
        jl.TiltedPlane(tan_y=math.inf)
    with pytest.raises(ValueError, match="TiltedPlane: tan_x must be finite"):
        jl.TiltedPlane(tan_x=math.nan)


# ---------------------------------------------------------------------------- tracing
def test_exit_face_refracts_by_snell_for_the_planes_normal():
    lens = block()
    rays = axial_beam(lens)
    wl = float(lens.primary_wavelength)
    n_glass = float(lens.materials[0].index(jnp.asarray(wl)))
    path = jl.trace_path(lens, rays)
    p, d = np.asarray(path.origin[1]), np.asarray(path.direction[1])
    assert bool(jnp.all(path.valid))
    # Intercepts on the plane z = 5 + tx·x + ty·y (global: its vertex at z = 5).
    np.testing.assert_allclose(p[:, 2], 5.0 + TX * p[:, 0] + TY * p[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(p[:, :2], np.asarray(rays.origin)[:, :2], rtol=0, atol=1e-12)
    # Snell by hand: d′ = μ d + (sqrt(1 − μ²(1 − cos²)) − μ cos) N, N the unit normal.
    normal = np.array([-TX, -TY, 1.0]) / math.sqrt(1 + TX * TX + TY * TY)
    mu = n_glass / 1.0
    cos = normal[2]
    expected = mu * np.array([0.0, 0.0, 1.0]) + (math.sqrt(1 - mu * mu * (1 - cos * cos))
                                                  - mu * cos) * normal
    np.testing.assert_allclose(d, np.broadcast_to(expected, d.shape), rtol=0, atol=1e-12)
    assert abs(expected[1]) > 0.1  # the beam is really deviated (a prism)
    # The image-plane spot of a collimated beam through a wedge stays the beam's shape.
    img = np.asarray(path.origin[2])
    np.testing.assert_allclose(img[:, 2], 25.0, rtol=0, atol=1e-12)


def test_tilted_image_is_the_flat_image_intersected_by_hand():
    alpha = math.radians(10.0)
    flat = singlet(tan_y=0.0)
    tilted = singlet(image=jl.TiltedPlane(tan_y=math.tan(alpha)), tan_y=0.0)
    z_img = float(flat.image_z())
    moved = 0.0
    for field in (0.0, 3.0, (2.0, -4.0)):
        rays = jl.sampling.collimated(flat, field, jl.sampling.pupil_grid(7))
        a, b = jl.trace(flat, rays), jl.trace(tilted, rays)
        assert bool(jnp.all(a.valid)) and bool(jnp.all(b.valid))
        p, d = np.asarray(a.origin), np.asarray(a.direction)
        t = math.tan(alpha) * p[:, 1] / (d[:, 2] - math.tan(alpha) * d[:, 1])
        q = p + t[:, None] * d
        np.testing.assert_allclose(q[:, 2], z_img + math.tan(alpha) * q[:, 1], atol=1e-12)
        np.testing.assert_allclose(np.asarray(b.origin), q, rtol=0, atol=1e-11)
        moved = max(moved, float(np.max(np.abs(t))))
    assert moved > 0.1  # the tilt moves the intercepts off-axis


def test_every_trace_mode_agrees():
    lens = singlet(image=jl.TiltedPlane(tan_x=0.03, tan_y=0.2))
    rays = jl.sampling.collimated(lens, 3.0, jl.sampling.pupil_grid(5))
    ref = np.asarray(jl.trace(lens, rays).origin)
    for kw in ({"uniform": True}, {"reverse_rule": True}, {"chunk": 4}):
        np.testing.assert_allclose(np.asarray(jl.trace(lens, rays, **kw).origin), ref,
                                   rtol=0, atol=1e-12)


def test_spot_gradient_in_tan_y_matches_central_differences():
    lens = singlet(image=jl.TiltedPlane(tan_x=0.02, tan_y=-0.1))
    rays = jl.sampling.collimated(lens, (1.0, 4.0), jl.sampling.pupil_grid(7))

    @jax.jit
    def loss(tan_y):
        tilted = eqx.tree_at(lambda L: (L.surfaces[1].tan_y, L.image.tan_y), lens,
                             (tan_y, 2 * tan_y))
        out = jl.trace(tilted, rays)
        w = out.valid.astype(tan_y.dtype)
        p = out.origin
        centre = jnp.sum(w[:, None] * p, 0) / jnp.sum(w)
        return jnp.sum(w * jnp.sum((p - centre) ** 2, -1)) / jnp.sum(w), jnp.sum(w)

    t0 = jnp.asarray(0.05)
    (value, n_valid), grad = jax.value_and_grad(loss, has_aux=True)(t0)
    assert int(n_valid) == rays.shape[0] and float(value) > 0
    h = 1e-6
    fd = (float(loss(t0 + h)[0]) - float(loss(t0 - h)[0])) / (2 * h)
    assert abs(fd) > 1e-3
    assert float(grad) == pytest.approx(fd, rel=1e-7)


# ---------------------------------------------------------------------------- files
def _zmx(lens_surface, image="", obj="  DISZ INFINITY\n", unit="MM"):
    return (f"UNIT {unit}\nENPD 4\nWAVM 1 0.5875618 1\nSURF 0\n{obj}SURF 1\n  STOP\n"
            f"  DISZ 5\n  GLAS N-BK7\nSURF 2\n{lens_surface}  DISZ 20\nSURF 3\n{image}")


def test_zmx_round_trip_of_a_tilted_face_and_image(tmp_path):
    lens = block(image=jl.TiltedPlane(tan_x=-0.04, tan_y=0.3))
    path = tmp_path / "tilt.zmx"
    jl.save(lens, path)
    text = path.read_text(encoding="utf-8")
    assert text.count("TYPE TILTSURF") == 2
    back = jl.load(path)
    for a, b in ((lens.surfaces[1], back.surfaces[1]), (lens.image, back.image)):
        assert type(b) is jl.TiltedPlane
        assert (float(b.tan_x), float(b.tan_y)) == (float(a.tan_x), float(a.tan_y))
    rays = axial_beam(lens, 5)
    np.testing.assert_array_equal(np.asarray(jl.trace(back, rays).origin),
                                  np.asarray(jl.trace(lens, rays).origin))


def test_zmx_reads_the_slopes_without_unit_conversion():
    lines = "  TYPE TILTSURF\n  PARM 1 0.1\n  PARM 2 -0.25\n"
    for unit in ("MM", "IN"):
        lens = jl.io.zmx.loads(_zmx(lines, image=lines, unit=unit))
        for s in (lens.surfaces[1], lens.image):
            assert type(s) is jl.TiltedPlane
            assert (float(s.tan_x), float(s.tan_y)) == (0.1, -0.25)


@pytest.mark.parametrize("lines, line, what", [
    ("  TYPE TILTSURF\n  PARM 1 0.1\n  PARM 3 0.5\n", 13, r"TILTSURF uses PARM 1\.\.2 only"),
    ("  TYPE TILTSURF\n  CURV 0.01\n", 12, r"a TILTSURF surface is a plane"),
])
def test_zmx_refuses_what_a_tilted_plane_lacks(lines, line, what):
    with pytest.raises(ValueError, match=rf"^t\.zmx:{line}: {what}"):
        jl.io.zmx.loads(_zmx(lines), "t.zmx")
    with pytest.raises(ValueError, match=rf"^t\.zmx:{line + 2}: {what}"):  # on the image too
        jl.io.zmx.loads(_zmx("", image=lines), "t.zmx")


def test_zmx_tilted_object_is_still_refused():
    obj = "  TYPE TILTSURF\n  PARM 2 0.1\n  DISZ 100\n"
    with pytest.raises(ValueError, match=r"t\.zmx:6: the object surface at a finite distance "
                                         r"must be a plane.*PARM 2 0\.1"):
        jl.io.zmx.loads(_zmx("", obj=obj), "t.zmx")
    flat = jl.io.zmx.loads(_zmx("", obj=obj.replace("0.1", "0")), "t.zmx")
    assert float(flat.object_distance) == 100.0


# ---------------------------------------------------------------------------- the rest
def test_every_other_consumer_handles_or_refuses_it(tmp_path):
    lens = singlet()
    s = lens.surfaces[1]
    assert surface_adjoint.supported(s)  # the polynomial reverse rule (test_surface_adjoint)
    m = backward.mirror_surface(s)
    x, y = jnp.asarray(XY[:, 0]), jnp.asarray(XY[:, 1])
    assert type(m) is jl.TiltedPlane
    np.testing.assert_array_equal(np.asarray(m.sag(x, y)[0]), -np.asarray(s.sag(x, y)[0]))
    assert forward.uniform_surfaces(lens.surfaces)[1] is s
    with pytest.raises(ValueError, match="TiltedPlane; only Standard"):
        forward.stacked_surfaces(lens.surfaces)
    with pytest.raises(ValueError, match="only an EvenAsphere can be rebased"):
        rebase_conic(s)
    with pytest.raises(ValueError, match="ToleranceModel: surface 2 is a TiltedPlane"):
        ToleranceModel(lens)
    tilted_image = eqx.tree_at(lambda L: L.surfaces[1], lens, jl.Plane())
    tilted_image = eqx.tree_at(lambda L: L.image, tilted_image, jl.TiltedPlane(tan_y=0.1))
    with pytest.raises(ValueError, match="ToleranceModel: the image surface is a TiltedPlane"):
        ToleranceModel(tilted_image)
    with pytest.raises(ValueError, match="holds EvenAsphere surfaces only"):
        Parameterization(template=lens, r_norm=jnp.ones(2), total_track=40.0, optical=(0, 1))
    assert lensfile.surface_to_dict(s) == {"type": "tilted_plane", "tan_x": float(s.tan_x),
                                           "tan_y": float(s.tan_y)}  # no semi-diameter: inf
    json_round_trip(tilted_image, tmp_path)
    # No paraxial power: the EFL of the plano-convex singlet, tilt or not.
    assert float(jl.efl(lens)) == float(jl.efl(singlet(tan_y=0.0)))
    table = "\n".join(report._surface_table(block(image=jl.TiltedPlane(tan_y=0.3))))
    assert table.count("TILTSURF") == 2
    assert "tan_x=0.1 tan_y=-0.25" in table and "tan_y=0.3" in table


@pytest.mark.parametrize("slope, meant", [(45.0, "tan_y = tan\\(45°\\) = 1\\b"),
                                          (-30.0, "tan\\(-30°\\) = -0.57735"), (90.0, "89.36°")])
def test_a_slope_that_is_a_whole_angle_in_degrees_is_warned_about(slope, meant):
    """``tan_y = 45`` is an 88.7° tilt that rays barely meet, not the 45° it looks like."""
    with pytest.warns(UserWarning, match=f"is a slope \\(tan θ\\).*{meant}"):
        jl.TiltedPlane(tan_y=slope)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for fine in (0.3, 1.0, 5.5, 7.0, -2.0):
            jl.TiltedPlane(tan_x=fine, tan_y=fine)
