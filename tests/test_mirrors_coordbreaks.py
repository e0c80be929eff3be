"""Issue 12: mirrors (Zemax GLAS MIRROR) and coordinate breaks (COORDBRK), each against a
known answer, their gradients against central differences, the .zmx round trip, and the fast
path (a lens without them never enters their code)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.coordinates import CoordinateBreak, frame_of

AIR = jl.Air()
WL = 0.5875618


def _rays(origins, directions):
    o = jnp.asarray(origins, jnp.float64)
    d = jnp.asarray(directions, jnp.float64)
    d = d / jnp.linalg.norm(d, axis=-1, keepdims=True)
    return jl.Rays(o, d, jnp.asarray(WL))


def _collimated(heights, angle_deg=0.0, z=-10.0):
    """Rays parallel to the y–z plane at ``angle_deg`` through (0, h, 0), started at z."""
    t = np.tan(np.deg2rad(angle_deg))
    h = np.asarray(heights, np.float64)
    o = np.stack([np.zeros_like(h), h + z * t, np.full_like(h, z)], -1)
    d = np.broadcast_to([0.0, np.sin(np.deg2rad(angle_deg)), np.cos(np.deg2rad(angle_deg))],
                        o.shape)
    return _rays(o, d)


def _to_global(lens, out):
    rot, off = frame_of(lens)
    return (np.asarray(out.origin) @ np.asarray(rot).T + np.asarray(off),
            np.asarray(out.direction) @ np.asarray(rot).T)


def _fold(tilt=45.0, after=-20.0):
    """A plane window, then a fold: break (tilt x), flat mirror, break (tilt x), image."""
    return jl.Lens(
        surfaces=(jl.Plane(), CoordinateBreak(tilt_x=tilt), jl.Plane(),
                  CoordinateBreak(tilt_x=45.0)),
        thickness=jnp.array([10.0, 0.0, 0.0, after]),
        materials=(AIR,) * 4, mirrors=(2,), epd=2.0)


# ------------------------------------------------------------------------- known answers


def test_fold_mirror_at_45_degrees_turns_the_chief_ray_by_90_degrees():
    """Coordinate break 45° about x, flat mirror, coordinate break 45°: the chief ray leaves
    along −z of the folded frame, which is +y globally (90° from the axis), and meets the
    image surface 20 mm from the fold. A ray at 5° in the y–z plane leaves at 5° from +y:
    reflection in the plane y = z − 10 maps (0, sin θ, cos θ) to (0, cos θ, sin θ)."""
    lens = _fold()
    theta = 5.0
    axial, tilted = _collimated([0.0]), _collimated([0.0], theta)
    rays = jl.Rays(jnp.concatenate([axial.origin, tilted.origin]),
                   jnp.concatenate([axial.direction, tilted.direction]), axial.wavelength)
    out = jl.trace(lens, rays)
    assert bool(out.valid.all())
    np.testing.assert_allclose(np.asarray(out.direction[0]), [0, 0, -1], atol=1e-15)
    p, d = _to_global(lens, out)
    np.testing.assert_allclose(d[0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(p[0], [0, 20, 10], atol=1e-13)
    t = np.tan(np.deg2rad(theta))
    np.testing.assert_allclose(d[1], [0, np.cos(np.deg2rad(theta)), np.sin(np.deg2rad(theta))],
                               atol=1e-15)
    # The 5° ray (y = z tan θ) meets the mirror plane z = 10 + y at height h = 10 t/(1 − t),
    # then runs to the image plane y = 20 with slope dz/dy = tan θ.
    h = 10 * t / (1 - t)
    np.testing.assert_allclose(p[1], [0, 20, 10 + h + (20 - h) * t], atol=1e-12)


@pytest.mark.parametrize("r", [-100.0, 80.0])
def test_spherical_mirror_focuses_at_half_its_radius(r):
    """A sphere of radius R reflects a collimated beam to R/2 (paraxial: EFL −R/2, so +50 for
    the concave R = −100 and −40 for the convex R = 80 with its virtual focus behind it; BFL
    R/2). A real ray at height h crosses the axis (or its line does) at
    z = R − R/(2 cos α), sin α = h/R (exact), so small apertures focus at R/2."""
    lens = jl.Lens((jl.Sphere(1 / r),), jnp.array([r / 2]), (AIR,), mirrors=(0,), epd=2.0)
    pd = jl.paraxial_data(lens)
    assert float(pd.efl) == pytest.approx(-r / 2, rel=1e-14)
    assert float(pd.bfl) == pytest.approx(r / 2, rel=1e-14)
    assert float(pd.paraxial_image_z) == pytest.approx(r / 2, rel=1e-14)
    h = np.array([1e-3, 5.0, 20.0])
    out = jl.trace(lens, _collimated(h))
    assert bool(out.valid.all())
    o, d = np.asarray(out.origin), np.asarray(out.direction)
    assert np.all(d[:, 2] < 0)  # reflected toward −z
    z_cross = o[:, 2] - o[:, 1] * d[:, 2] / d[:, 1]
    alpha = np.arcsin(h / abs(r))
    np.testing.assert_allclose(z_cross, r - r / (2 * np.cos(alpha)), rtol=1e-12)
    assert z_cross[0] == pytest.approx(r / 2, rel=1e-9)
    # On axis the optical path from z = −10 is 10 to the mirror, then R/2 back to the focus
    # (traversed backward for the virtual focus of the convex mirror: −R/2 counts negative).
    axis = jl.trace(lens, _collimated([0.0]))
    assert float(axis.opl[0]) == pytest.approx(10 - r / 2, rel=1e-14)


@pytest.mark.parametrize("r", [-100.0, 80.0])
def test_a_surface_at_zero_gap_after_a_mirror_is_reached_backward_if_need_be(r):
    """A dummy plane at the mirror's vertex (Zemax DISZ 0, as files put a reference plane or
    a coordinate break there): a reflected ray leaves the mirror at z = sag(h), on either
    side of that plane, and reaches it going back along its line where needed, as in a
    sequential trace. The image points and path lengths equal those without the plane; the
    rays were lost before."""
    bare = jl.Lens((jl.Sphere(1 / r),), jnp.array([-60.0]), (AIR,), mirrors=(0,), epd=40.0)
    with_plane = jl.Lens((jl.Sphere(1 / r), jl.Plane()), jnp.array([0.0, -60.0]), (AIR, AIR),
                         mirrors=(0,), epd=40.0)
    rays = _collimated([0.0, 5.0, -12.0, 19.0])
    a, b = jl.trace(bare, rays), jl.trace(with_plane, rays)
    assert bool(a.valid.all()) and bool(b.valid.all())
    np.testing.assert_allclose(np.asarray(b.origin), np.asarray(a.origin), atol=1e-12)
    np.testing.assert_allclose(np.asarray(b.opl), np.asarray(a.opl), atol=1e-12)


def _cassegrain(c1=-1 / 200.0, c2=-1 / 100.0, d=70.0, epd=0.02):
    """Concave primary (f1 = 100), convex secondary (f2 = −50) 70 mm in front of it, image
    75 mm behind the secondary; the primary is the stop."""
    return jl.Lens((jl.Sphere(c1), jl.Sphere(c2)), jnp.array([-d, d + 5.0]), (AIR, AIR),
                   mirrors=(0, 1), epd=epd)


def test_cassegrain_efl_from_the_two_mirror_formula():
    """1/f = 1/f1 + 1/f2 − d/(f1 f2) with f1 = −R1/2 = 100, f2 = R2/2 = −50 (the secondary
    sees light travelling toward −z, so its power is −2·(−1)·c2), d = 70: f = 250, and the
    focus 75 mm behind the secondary (5 mm behind the primary)."""
    f1, f2, d = 100.0, -50.0, 70.0
    f = 1 / (1 / f1 + 1 / f2 - d / (f1 * f2))
    assert f == pytest.approx(250.0)
    lens = _cassegrain()
    pd = jl.paraxial_data(lens)
    assert float(pd.efl) == pytest.approx(f, rel=1e-13)
    assert float(pd.bfl) == pytest.approx(75.0, rel=1e-13)
    assert float(pd.paraxial_image_z) == pytest.approx(5.0, rel=1e-12)
    # A real marginal ray at small height h: EFL = h / sin U′ (Abbe's sine condition form).
    h = 1e-3
    out = jl.trace(lens, _collimated([h]))
    assert bool(out.valid[0])
    assert float(-h / out.direction[0, 1]) == pytest.approx(f, rel=1e-7)
    assert float(out.direction[0, 2]) > 0  # two reflections: toward +z again
    assert abs(float(out.origin[0, 1])) < 1e-9  # at the paraxial focus


def test_decentered_singlet_equals_the_singlet_with_a_shifted_object():
    """A singlet decentered by δ in y (a coordinate break before it) images a point as the
    centred singlet images the point shifted by −δ; in global coordinates the image is δ
    further, and its paraxial position is δ(1 − m) for an on-axis object."""
    delta, dist = 0.7, 200.0
    glass = jl.ModelGlass(1.5168, 64.17)
    singlet = jl.Lens((jl.Sphere(1 / 50.0), jl.Sphere(-1 / 50.0)), jnp.array([5.0, 60.0]),
                      (glass, AIR), epd=10.0, object_distance=dist)
    decentered = jl.Lens((CoordinateBreak(decenter_y=delta), *singlet.surfaces),
                         jnp.array([0.0, 5.0, 60.0]), (AIR, glass, AIR), stop=1, epd=10.0,
                         object_distance=dist)
    pupil = np.array([[0.0, 0.0], [0.0, 2.0], [1.5, -1.0], [0.0, 4.0], [-3.0, 0.5]])
    src = np.array([0.0, 0.0, -dist])
    tgt = np.concatenate([pupil, np.zeros((len(pupil), 1))], -1)
    rays = _rays(np.broadcast_to(src, tgt.shape), tgt - src)
    shift = np.array([0.0, -delta, 0.0])
    shifted = _rays(np.broadcast_to(src + shift, tgt.shape), tgt - src)
    a, b = jl.trace(decentered, rays), jl.trace(singlet, shifted)
    assert bool(a.valid.all()) and bool(b.valid.all())
    np.testing.assert_allclose(np.asarray(a.origin), np.asarray(b.origin), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(a.direction), np.asarray(b.direction), atol=1e-14)
    np.testing.assert_allclose(np.asarray(a.opl), np.asarray(b.opl), rtol=1e-14)
    p, _ = _to_global(decentered, a)
    np.testing.assert_allclose(p[:, 1], np.asarray(a.origin[:, 1]) + delta, atol=1e-13)
    # Paraxial image of the on-axis point through the decentered lens: y = δ(1 − m), m the
    # paraxial magnification A + L·C (object plane to the paraxial image plane, L behind the
    # last vertex). A tiny cone and a small decenter: the real image differs from the
    # paraxial one by the distortion, relative 3e-4 at δ = 0.7 mm, falling as δ² (8e-8 here).
    pd = jl.paraxial_data(singlet)
    a_, _, c_, _ = jl.paraxial.system_matrix(singlet)
    back = float(pd.paraxial_image_z) - 5.0
    m = float(a_ + back * c_)
    assert -0.5 < m < -0.2
    small_delta = 0.01
    img = eqx.tree_at(lambda L: (L.thickness, L.surfaces[0].decenter_y), decentered,
                      (jnp.array([0.0, 5.0, back]), jnp.asarray(small_delta)))
    small = _rays(np.broadcast_to(src, (3, 3)),
                  np.array([[0, 1e-3, 0], [1e-3, 0, 0], [0, -1e-3, 0]]) - src)
    p, _ = _to_global(img, jl.trace(img, small))
    np.testing.assert_allclose(p[:, 1], small_delta * (1 - m), rtol=3e-7)


def test_a_break_and_its_inverse_leave_every_ray_unchanged():
    """A break followed by the break with the order flag toggled and every parameter negated
    is the identity (both orders, decenters and all three tilts exercised)."""
    lens = jl.zoo.cooke_triplet()
    cb = CoordinateBreak(decenter_x=0.3, decenter_y=-0.2, tilt_x=3.0, tilt_y=-2.0, tilt_z=40.0)
    inv = CoordinateBreak(decenter_x=-0.3, decenter_y=0.2, tilt_x=-3.0, tilt_y=2.0,
                          tilt_z=-40.0, order=1)
    s, t, m = list(lens.surfaces), list(np.asarray(lens.thickness)), list(lens.materials)
    broken = jl.Lens(tuple(s[:3] + [cb, inv] + s[3:]), jnp.array(t[:2] + [0.0, 0.0] + t[2:]),
                     tuple(m[:3] + [m[2], m[2]] + m[3:]), stop=lens.stop + 2, epd=lens.epd,
                     fields=lens.fields, wavelengths=lens.wavelengths)
    rays = jl.sampling.collimated(lens, 10.0, jl.sampling.pupil_hexapolar(2))
    a, b = jl.trace(lens, rays), jl.trace(broken, rays)
    np.testing.assert_array_equal(np.asarray(a.valid), np.asarray(b.valid))
    np.testing.assert_allclose(np.asarray(a.origin), np.asarray(b.origin), atol=1e-12)
    np.testing.assert_allclose(np.asarray(a.direction), np.asarray(b.direction), atol=1e-14)
    rot, off = frame_of(broken)
    np.testing.assert_allclose(np.asarray(rot), np.eye(3), atol=1e-15)
    np.testing.assert_allclose(np.asarray(off), 0, atol=1e-15)


# ------------------------------------------------------------------------------- gradients


def _central(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


def test_gradients_through_a_mirror_and_a_tilt_match_central_differences():
    """float64: d(image intercept)/d(mirror curvature, thickness) for a tilted beam on a
    spherical mirror, and d(global exit direction, intercept)/d(tilt) through the fold."""
    rays = _collimated([3.0, -2.0], 4.0)

    def spot(c, t):
        lens = jl.Lens((jl.Sphere(c),), jnp.stack([t]), (AIR,), mirrors=(0,), epd=2.0)
        out = jl.trace(lens, rays)
        return jnp.sum(out.origin[:, 1] ** 2) + jnp.sum(out.direction[:, 1])

    c0, t0 = -0.01, -48.0
    g = jax.grad(spot, argnums=(0, 1))(c0, t0)
    fc = _central(lambda c: spot(c, t0), c0, 1e-7)
    ft = _central(lambda t: spot(c0, t), t0, 1e-5)
    assert float(g[0]) == pytest.approx(float(fc), rel=1e-6)
    assert float(g[1]) == pytest.approx(float(ft), rel=1e-6)
    assert abs(float(g[0])) > 1 and abs(float(g[1])) > 1e-3  # both gradients are real

    fold_rays = _collimated([0.5, -0.5], 2.0)

    def folded(tilt):
        lens = _fold(tilt)
        out = jl.trace(lens, fold_rays)
        rot, off = frame_of(lens)
        p = out.origin @ rot.T + off
        d = out.direction @ rot.T
        return jnp.sum(p[:, 2]) + jnp.sum(d[:, 2])

    tilt0 = 44.0
    g = jax.grad(folded)(jnp.asarray(tilt0))
    fd = _central(folded, tilt0, 1e-5)
    assert float(g) == pytest.approx(float(fd), rel=1e-6)
    assert abs(float(g)) > 1e-2


# ------------------------------------------------------------------------------------- .zmx

_ZMX = """VERS 190513 80 123457 L123457
MODE SEQ
NAME folded newtonian
UNIT MM X W X CM MR CPMM
ENPD 2.0E+1
GCAT SCHOTT
FTYP 0 0 2 1 0 0 0
XFLN 0 0
YFLN 0 0.2
WAVM 1 0.55 1
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0.0
  DISZ INFINITY
SURF 1
  STOP
  TYPE STANDARD
  CURV -2.5E-3
  CONI -1
  DISZ -150
  GLAS MIRROR 0 0 1.5 4.0E+1 0 0 0 0 0 0
  DIAM 12 1 0 0 1 ""
SURF 2
  TYPE COORDBRK
  CURV 0.0
  PARM 1 0
  PARM 2 0.5
  PARM 3 45
  PARM 4 0
  PARM 5 0
  PARM 6 0
  DISZ 0
SURF 3
  TYPE STANDARD
  CURV 0.0
  DISZ 0
  GLAS MIRROR 0 0 1.5 4.0E+1 0 0 0 0 0 0
SURF 4
  TYPE COORDBRK
  CURV 0.0
  PARM 1 0
  PARM 2 0
  PARM 3 45
  PARM 4 0
  PARM 5 0
  PARM 6 1
  DISZ 50
SURF 5
  TYPE STANDARD
  CURV 0.0
  DISZ 0
"""


def test_zmx_with_mirrors_and_coordinate_breaks_round_trips(tmp_path):
    """A folded Newtonian (paraboloid f = 200, 45° flat 150 mm in front of it, image 50 mm
    to the side; a file in Zemax's form written for this test): read, traced (the on-axis
    beam focuses: paraboloids are perfect on axis), written and read back exactly."""
    path = tmp_path / "newt.zmx"
    path.write_text(_ZMX)
    lens = jl.load(path)
    assert lens.mirrors == (0, 2)
    cb = lens.surfaces[1]
    assert isinstance(cb, CoordinateBreak) and cb.order == 0
    assert (float(cb.decenter_y), float(cb.tilt_x)) == (0.5, 45.0)
    assert lens.surfaces[3].order == 1
    np.testing.assert_array_equal(np.asarray(lens.thickness), [-150, 0, 0, 50])
    assert float(jl.paraxial_data(lens).efl) == pytest.approx(200.0, rel=1e-14)
    pupil = jl.sampling.pupil_hexapolar(3)
    out = jl.trace(lens, jl.sampling.collimated(lens, 0.0, pupil))
    assert bool(out.valid.all())
    spot = np.asarray(out.origin[:, :2])
    assert np.ptp(spot, axis=0).max() < 1e-10  # a point: the paraboloid's focus
    # The focus (0, 0, −200) mirrored in the flat, the plane z = y − 150.5 through the
    # decentred break vertex (0, 0.5, −150) at 45°: (0, −49.5, −150.5), which lies on the
    # image plane 50 mm from the break along the folded axis (0, −1, 0).
    p, d = _to_global(lens, out)
    np.testing.assert_allclose(p, np.broadcast_to([0.0, -49.5, -150.5], p.shape), atol=1e-10)
    assert np.all(d[:, 1] < 0)
    out_path = tmp_path / "out.zmx"
    jl.save(lens, out_path)
    again = jl.load(out_path)
    assert again.mirrors == lens.mirrors
    assert bool(eqx.tree_equal(again, lens))
    jl.save(again, tmp_path / "out2.zmx")
    assert (tmp_path / "out2.zmx").read_text() == out_path.read_text()
    text = out_path.read_text()
    assert text.count("GLAS MIRROR") == 2 and text.count("TYPE COORDBRK") == 2


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("  PARM 6 1\n", "  PARM 6 2\n", r"newt\.zmx:\d+: COORDBRK order flag .PARM 6. must be 0"),
        ("  PARM 5 0\n  PARM 6 0\n", "  PARM 5 0\n  PARM 6 0\n  PARM 7 3\n",
         r"newt\.zmx:\d+: COORDBRK uses PARM 1\.\.6"),
        ("  PARM 1 0\n  PARM 2 0.5\n", "  PARM 1 0\n  PARM 2 0.5\n  GLAS N-BK7\n",
         r"newt\.zmx:\d+: a coordinate break keeps the medium before it"),
        ("  PARM 1 0\n  PARM 2 0.5\n", "  PARM 1 0\n  PARM 2 0.5\n  GLAS MIRROR\n",
         r"newt\.zmx:\d+: a coordinate break cannot be a mirror"),
        ("SURF 2\n  TYPE COORDBRK\n  CURV 0.0", "SURF 2\n  TYPE COORDBRK\n  CURV 0.01",
         r"newt\.zmx:\d+: a coordinate break .COORDBRK. has no shape"),
        ("SURF 5\n  TYPE STANDARD\n  CURV 0.0\n", "SURF 5\n  TYPE STANDARD\n  CURV 0.0\n"
         "  GLAS MIRROR\n", r"newt\.zmx:\d+: the object or image surface cannot be a mirror"),
    ],
)
def test_zmx_refuses_what_it_cannot_represent(tmp_path, old, new, message):
    assert old in _ZMX
    path = tmp_path / "newt.zmx"
    path.write_text(_ZMX.replace(old, new, 1))
    with pytest.raises(ValueError, match=message):
        jl.load(path)


def test_lens_refuses_bad_mirror_and_break_structure():
    glass = jl.ModelGlass(1.5, 60.0)
    with pytest.raises(ValueError, match=r"mirrors must be increasing surface indices in "
                                         r"\[0, 1\]"):
        jl.Lens((jl.Plane(), jl.Plane()), jnp.array([1.0, 1.0]), (AIR, AIR), mirrors=(2,))
    with pytest.raises(ValueError, match=r"surface 1 is a mirror; .* materials\[1\] must be "
                                         r"the same material as materials\[0\]"):
        jl.Lens((jl.Plane(), jl.Plane()), jnp.array([1.0, -1.0]), (glass, AIR), mirrors=(1,))
    with pytest.raises(ValueError, match=r"surface 0 is a coordinate break"):
        jl.Lens((CoordinateBreak(), jl.Plane()), jnp.array([0.0, 1.0]), (glass, AIR))
    with pytest.raises(ValueError, match=r"CoordinateBreak: order must be 0"):
        CoordinateBreak(order=2)
    with pytest.raises(ValueError, match=r"CoordinateBreak: tilt_x must be a finite number"):
        CoordinateBreak(tilt_x=np.nan)
    assert jl.io.lensfile.lens_to_dict(_fold())["surfaces"][3].get("mirror") is True
    with pytest.raises(ValueError, match=r"reversed_lens: lenses with mirrors"):
        jl.tracing.reversed_lens(_fold())


# ------------------------------------------------------------------------------- fast path


def test_a_lens_without_mirrors_or_breaks_never_enters_their_code(monkeypatch):
    """The Cooke triplet is traced (value and gradient) with the reflection and the frame
    change made to fail: neither runs, the program has no trigonometry in it, and the
    results are bit-equal to the unpatched trace."""
    from jaxlens.tracing import forward, step

    lens = jl.zoo.cooke_triplet()
    rays = jl.sampling.collimated(lens, 14.0, jl.sampling.pupil_hexapolar(3))

    def loss(L):
        out = jl.trace.__wrapped__(L, rays)
        return jnp.sum(jnp.where(out.valid, out.origin[:, 1], 0.0))

    def run():  # a fresh jit: traced again, so patched functions would be called
        return eqx.filter_jit(lambda L: (jl.trace.__wrapped__(L, rays),
                                         eqx.filter_grad(loss)(L)))(lens)

    reference = run()

    def fail(*_, **__):
        raise AssertionError("mirror/break code entered for a lens without them")

    monkeypatch.setattr(step, "reflect", fail)
    monkeypatch.setattr(forward, "transform", fail)
    for a, b in zip(jax.tree.leaves(reference), jax.tree.leaves(run()), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    text = str(jax.make_jaxpr(lambda L: jl.trace.__wrapped__(L, rays))(lens))
    assert " sin " not in text and " cos " not in text
