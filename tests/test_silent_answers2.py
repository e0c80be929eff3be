"""Second audit for silent wrong answers, in the features of the Q-type / grating / element
decenter session: Forbes Q-type aspheres, ruled gratings, element decenter and tilt, and
``depth=None`` as the lens's own object.

The first block names failures of the code before its fix (each test failed there); the
second pins what the audit checked and found right, each against an independent answer
(an expansion by hand, a frame transform written out in numpy, a unit conversion).
"""

import dataclasses
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.analysis import spots, tolerance
from jaxlens.analysis import tolerance_rigid as rigid
from jaxlens.optics.qtype import QTypeAsphere

GLASS = jl.ModelGlass(1.6, 50.0)


def _singlet(front=None, *, back=50.0):
    """A singlet (front surface ``front`` or a sphere), EPD 6 mm, fields 0 and 3 degrees."""
    front = jl.Sphere(0.02) if front is None else front
    return jl.Lens(surfaces=(front, jl.Sphere(-0.01)), thickness=jnp.array([4.0, back]),
                   materials=(GLASS, jl.Air()), epd=6.0, fields=jnp.array([0.0, 3.0]))


# ============================================================== failures before the fix
# ---------------------------------------- element decenter: glass touching object/image
def test_decenter_refuses_glass_that_touches_image_space():
    """A glass block that ends in image space (cemented to the sensor, say) is no
    air-bounded element: ``element_groups`` skipped it, so with ``Tolerances(decenter=…)``
    it stayed in place while the singlet in front moved, and the yield left its decenter
    out without a word (labels: only 'E1 (S1-S2)')."""
    lens = jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.01), jl.Sphere(0.01)),
                   thickness=jnp.array([4.0, 10.0, 40.0]), materials=(GLASS, jl.Air(), GLASS),
                   epd=6.0, fields=jnp.array([0.0, 3.0]))
    assert rigid.element_groups(lens) == ((0, 1),)  # the block is not an element
    with pytest.raises(ValueError, match=r"^zero_perturbation: element decenter and tilt move "
                                         r"air-bounded elements only, and surfaces \[3\] touch "
                                         r"a medium that is not air .*image space: ModelGlass"):
        tolerance.zero_perturbation(lens, elements=True)
    with pytest.raises(ValueError, match=r"^displace: .*surfaces \[3\]"):
        rigid.displace(lens, *(jnp.zeros(1),) * 4)
    # Without element motion the lens is still toleranced as before.
    assert tolerance.zero_perturbation(lens).decenter_x.shape == (0,)


def test_decenter_refuses_an_immersed_front_element():
    """An object in water: the first singlet (water | glass | air) was silently fixed."""
    lens = jl.Lens(surfaces=(jl.Sphere(0.02), jl.Sphere(-0.01), jl.Sphere(0.02),
                             jl.Sphere(-0.01)),
                   thickness=jnp.array([4.0, 5.0, 4.0, 40.0]),
                   materials=(GLASS, jl.Air(), GLASS, jl.Air()), epd=6.0,
                   fields=jnp.array([0.0, 3.0]), object_material=jl.ModelGlass(1.33, 55.0),
                   object_distance=100.0)
    assert rigid.element_groups(lens) == ((2, 3),)
    with pytest.raises(ValueError, match=r"surfaces \[1, 2\] touch a medium that is not air "
                                         r"\(object space: ModelGlass"):
        tolerance.zero_perturbation(lens, elements=True)


# ------------------------------------------------------ Q-type surfaces in tolerancing
def test_tolerancing_refuses_a_qtype_surface():
    """A ``QTypeAsphere`` passed the tolerance model's surface check: its a_m (no even series)
    got no asphere-tolerance row, so the sensitivity table left them out without a word (as
    the odd asphere's β_i, which are refused), and its 'radius' tolerance scaled the base
    conic's c, not the vertex curvature. With the default irregularity the model was built
    and failed only in its first trace ('perturb: … no even series')."""
    q = QTypeAsphere(c=0.03, k=-0.7, coeffs=jnp.array([2e-3, -1e-3, 3e-4]), norm_radius=8.0)
    lens = _singlet(q)
    for where in ("zero_perturbation", "perturb"):
        with pytest.raises(ValueError, match=rf"^{where}: surface 1 is a QTypeAsphere \(Forbes "
                                             r"Q-bfs\); .* untoleranced"):
            if where == "zero_perturbation":
                tolerance.zero_perturbation(lens)
            else:
                tolerance.perturb(lens, tolerance.zero_perturbation(_singlet()),
                                  jnp.ones(2))


# ------------------------------------------------- depth: 1e10 mm and more is infinity
@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


def test_a_depth_beyond_1e10_mm_is_infinity_as_for_the_lens(cooke):
    """``Lens(object_distance=1e12)`` is an object at infinity (Zemax's convention,
    ``INFINITE_OBJECT_MM``), but ``depth=1e12`` was traced as a finite object: rays from
    beyond the tracer's largest ray parameter were all lost, and ``rms_spot(depth=1e300)``
    gave NaN (the PSF at 1e12 mm: all zeros). Now both are the lens at infinity."""
    pupil = jl.sampling.pupil_grid(5, jnp.float64)
    at_inf = spots.spot_rays(cooke, 14.0, pupil=pupil)
    assert bool(np.all(np.asarray(at_inf.valid)))
    for depth in (1e10, 1e300):  # 1e300: every ray lost before
        far = spots.spot_rays(cooke, 14.0, pupil=pupil, depth=depth)
        np.testing.assert_array_equal(np.asarray(far.valid), np.asarray(at_inf.valid))
        np.testing.assert_array_equal(np.asarray(far.origin), np.asarray(at_inf.origin))
    assert jl.sampling.static_depth(1e12) is None
    assert jl.sampling.lens_depth(cooke, 1e12, "x") is None
    # The same rule as the lens's own object distance.
    assert dataclasses.replace(cooke, object_distance=1e12).object_at_infinity


def test_a_depth_array_across_1e10_mm_and_object_point_are_refused(cooke):
    """Mixed finite / at-infinity depths cannot be one trace; ``object_point`` at 1e12 mm
    made a point the tracer cannot start from."""
    with pytest.raises(ValueError, match=r"^rms_spot: depth must be finite numbers in "
                                         r"\(0, 1e\+10\) mm .*got 2e\+10"):
        spots.rms_spot(cooke, depth=[5e9, 2e10])
    with pytest.raises(ValueError, match=r"^object_point: depth must be finite, nonzero and "
                                         r"below 1e\+10"):
        jl.sampling.object_point(cooke, 0.0, 1e12)
    pupil = jl.sampling.pupil_grid(3, jnp.float64)
    np.testing.assert_array_equal(  # field_rays follows the same rule
        np.asarray(jl.sampling.field_rays(cooke, 5.0, pupil, depth=1e12).direction),
        np.asarray(jl.sampling.field_rays(cooke, 5.0, pupil).direction))


@pytest.mark.slow  # two PSFs, about 6 s
def test_psf_at_1e12_mm_is_the_psf_at_infinity(cooke):
    kw = dict(pixel_size=0.002, kernel_size=15, max_truncation=None)
    at_inf = np.asarray(jl.psf(cooke, 14.0, **kw))
    far = np.asarray(jl.psf(cooke, 14.0, depth=1e12, **kw))
    assert at_inf.sum() > 0.5  # the old code gave 0.0 here
    np.testing.assert_array_equal(far, at_inf)


@pytest.mark.slow  # a compile, about 3.5 s
def test_a_traced_depth_beyond_1e10_mm_is_refused(cooke):
    """Under jit the choice of the collimated beam cannot be made: refused at run time."""
    spot = eqx.filter_jit(lambda d: spots.rms_spot(cooke, depth=d).polychromatic)
    with pytest.raises(Exception, match=r"rms_spot: a traced depth must be finite and in "
                                        r"\(0, inf\) mm from the object to surface 1, below "
                                        r"1e\+10 mm"):
        spot(jnp.asarray(2e10))


# ============================================================ checked and found right
# -------------------------------------------------------------------------- Q-type
def _qcon_as_even(a, rn):
    """Q-con a_0 … a_2 as even-asphere coefficients on r², r⁴, r⁶, r⁸ (by hand: Q_0 = 1,
    Q_1 = 6x − 5, Q_2 = 15 − 42x + 28x², δ = x² Σ a_m Q_m, x = r²/ρ²)."""
    a0, a1, a2 = a
    return [0.0, (a0 - 5 * a1 + 15 * a2) / rn**4, (6 * a1 - 42 * a2) / rn**6, 28 * a2 / rn**8]


def _qbfs_as_even(b, rn):
    """Q-bfs b_0, b_1 on a flat base (φ = 1) as even-asphere coefficients (by hand:
    δ = x(1 − x)(b_0 + b_1 (13 − 16x)/√19))."""
    b0, b1 = b
    s = np.sqrt(19.0)
    return [(b0 + 13 * b1 / s) / rn**2, -(b0 + 29 * b1 / s) / rn**4, 16 * b1 / s / rn**6]


X = jnp.asarray(np.linspace(0.0, 4.0, 9) * 0.6)
Y = jnp.asarray(np.linspace(0.0, 4.0, 9) * 0.8)


@pytest.mark.parametrize("kind", ["con", "bfs"])
def test_qtype_equals_its_even_asphere_expansion(kind):
    """Sag, gradient and paraxial curvature equal those of the even asphere expanded by
    hand (Q-con on a conic; Q-bfs on a plane, where φ = 1)."""
    rn = 5.0
    if kind == "con":
        a, c, k, even = [1e-3, -2e-4, 3e-5], 0.05, -0.7, _qcon_as_even([1e-3, -2e-4, 3e-5], rn)
    else:
        a, c, k, even = [2e-3, -1e-3], 0.0, 0.0, _qbfs_as_even([2e-3, -1e-3], rn)
    q = QTypeAsphere(c=c, k=k, coeffs=jnp.array(a), norm_radius=rn, qtype=kind)
    e = jl.EvenAsphere(c=c, k=k, coeffs=jnp.array(even))
    for u, v in zip(q.sag_and_grad(X, Y)[:3], e.sag_and_grad(X, Y)[:3], strict=True):
        np.testing.assert_allclose(np.asarray(u), np.asarray(v), rtol=1e-12, atol=1e-17)
    assert float(q.paraxial_curvature) == pytest.approx(float(e.paraxial_curvature),
                                                        rel=1e-13, abs=1e-18)


def test_qtype_with_no_or_zero_terms_is_its_conic():
    cz = jl.Conic(0.05, -0.7)
    for kind in ("bfs", "con"):
        for coeffs in ((), (0.0, 0.0, 0.0)):
            q = QTypeAsphere(c=0.05, k=-0.7, coeffs=jnp.array(coeffs, float), norm_radius=5.0,
                             qtype=kind)
            for u, v in zip(q.sag_and_grad(X, Y)[:3], cz.sag_and_grad(X, Y)[:3], strict=True):
                np.testing.assert_array_equal(np.asarray(u), np.asarray(v))


def test_qbfs_on_a_conic_paraxial_curvature_is_the_sag_fit():
    """c + 2 Σ a_m Q_m(0)/ρ² equals 2 z/r² at r = 1e-3 mm (the surface's own vertex)."""
    q = QTypeAsphere(c=0.05, k=-0.7, coeffs=jnp.array([2e-3, -1e-3, 3e-4, -1e-4]),
                     norm_radius=5.0)
    r = 1e-3
    fit = 2 * float(q.sag(jnp.asarray(r), jnp.asarray(0.0))[0]) / r**2
    assert float(q.paraxial_curvature) == pytest.approx(fit, rel=1e-8)


def test_qed_type_in_inches_is_the_lens_scaled(tmp_path):
    """UNIT IN: CURV, the normalisation radius (XDAT 3) and the a_m (XDAT 4…) are lens units;
    the surface read is the mm surface scaled by 25.4 (sag at 25.4 r is 25.4 × the sag)."""
    q = QTypeAsphere(c=0.03, k=-0.7, coeffs=jnp.array([2e-3, -1e-3, 3e-4]), norm_radius=8.0)
    lens = jl.Lens(surfaces=(q, jl.Sphere(-0.01)), thickness=jnp.array([5.0, 45.0]),
                   materials=(GLASS, jl.Air()), epd=16.0, fields=jnp.array([0.0, 5.0]))
    mm = tmp_path / "mm.zmx"
    jl.save(lens, mm)
    inch = tmp_path / "in.zmx"
    inch.write_text(mm.read_text().replace("UNIT MM", "UNIT IN"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = jl.load(inch).surfaces[0]
    assert float(s.norm_radius) == pytest.approx(8.0 * 25.4, rel=1e-15)
    np.testing.assert_allclose(np.asarray(s.coeffs), np.asarray(q.coeffs) * 25.4, rtol=1e-15)
    r = jnp.linspace(0.0, 7.0, 5)
    np.testing.assert_allclose(np.asarray(s.sag(25.4 * r, 0 * r)[0]) / 25.4,
                               np.asarray(q.sag(r, 0 * r)[0]), rtol=1e-13, atol=1e-16)


# ------------------------------------------------------------------------- grating
@pytest.mark.slow  # three compiles, about 6 s
def test_grating_trace_float32_and_jit_agree_with_float64_eager():
    """A Q-bfs front and a curved grating (order −1) back: float32 within 5 µm at the image,
    same valid rays; jit bit-identical to eager."""
    q = QTypeAsphere(c=0.03, k=-0.7, coeffs=jnp.array([2e-3, -1e-3, 3e-4]), norm_radius=8.0)
    g = jl.Grating(c=-0.01, lines_per_um=0.05, order=-1.0)
    lens = jl.Lens(surfaces=(q, g), thickness=jnp.array([5.0, 45.0]),
                   materials=(GLASS, jl.Air()), epd=16.0, fields=jnp.array([0.0, 5.0]))
    rays = jl.sampling.collimated(lens, 5.0, jl.sampling.pupil_grid(9, jnp.float64))
    o64 = jl.trace(lens, rays)
    r32 = jax.tree_util.tree_map(
        lambda v: v.astype(jnp.float32) if getattr(v, "dtype", None) == jnp.float64 else v,
        rays)
    o32 = jl.trace(lens.astype(jnp.float32), r32)
    assert o32.origin.dtype == jnp.float32
    np.testing.assert_array_equal(np.asarray(o32.valid), np.asarray(o64.valid))
    assert np.max(np.abs(np.asarray(o32.origin, float) - np.asarray(o64.origin))) < 5e-6
    oj = eqx.filter_jit(jl.trace)(lens, rays)
    np.testing.assert_array_equal(np.asarray(oj.origin), np.asarray(o64.origin))


def test_a_grating_lens_is_saved_as_json_with_its_lines(tmp_path):
    lens = jl.Lens(surfaces=(jl.Grating(lines_per_um=0.3, order=-2.0),),
                   thickness=jnp.array([10.0]), materials=(jl.Air(),), epd=2.0)
    g = json_round_trip(lens, tmp_path).surfaces[0]
    assert (float(g.lines_per_um), float(g.order)) == (0.3, -2.0)


# ------------------------------------------------------------------ element motion
def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


@pytest.mark.parametrize("motion", [(0.05, -0.1, 1.5, -2.5),
                                    pytest.param((0.0, 0.0, 30.0, 20.0),
                                                 marks=pytest.mark.slow)])
def test_displace_equals_the_frame_transform_written_out(motion):
    """Independent of the coordinate breaks: rays expressed in the moved element's frame
    (origin (δx, δy, 0), axes Rx(tilt_x)·Ry(tilt_y), Zemax's signs), traced through the
    unmoved singlet, carried back and on to the image plane z = 54 mm, land where the trace
    of ``displace`` puts them (1e-13 mm) with the same directions; the same rays pass."""
    dx, dy, tx, ty = motion
    lens = _singlet()
    moved = rigid.displace(lens, *(jnp.array([v]) for v in motion))
    rays = jl.sampling.collimated(lens, 3.0, jl.sampling.pupil_grid(7, jnp.float64))
    out = jl.trace(moved, rays)
    rot, o = _rx(np.deg2rad(tx)) @ _ry(np.deg2rad(ty)), np.array([dx, dy, 0.0])
    p, d = np.asarray(rays.origin), np.asarray(rays.direction)
    local = jl.trace(lens, jl.Rays(jnp.asarray((p - o) @ rot), jnp.asarray(d @ rot),
                                   rays.wavelength), upto=1)
    p2 = np.asarray(local.origin) @ rot.T + o
    d2 = np.asarray(local.direction) @ rot.T
    at_image = p2 + ((54.0 - p2[:, 2]) / d2[:, 2])[:, None] * d2
    np.testing.assert_array_equal(np.asarray(out.valid), np.asarray(local.valid))
    v = np.asarray(out.valid)
    assert v.sum() > 20
    np.testing.assert_allclose(np.asarray(out.origin)[v, :2], at_image[v, :2], atol=1e-13)
    np.testing.assert_allclose(np.asarray(out.direction)[v], d2[v], atol=1e-15)
