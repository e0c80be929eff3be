"""The ruled diffraction grating (``Grating``, Zemax ``TYPE DGRATING``), transmissive and
reflective.

Checked against the grating equation computed by hand in numpy (a flat grating, several
orders of both signs, rays with an x component, into glass and at a mirror; the tangential
form on curved gratings), against optiland 0.6.3 ray by ray on its three sample files
(intercepts stored in tests/data/zmx/gratings/reference.json by tools/grating_reference.py,
so optiland is not needed here), against finite differences, and the ``.zmx`` reader and
writer against each other and the file's text.
"""

import json
import math
import os
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
from jaxlens.optics.lens import unclipped
from jaxlens.optics.rebase import rebase_conic
from jaxlens.tracing import backward, forward

LAM = 0.587  # µm
DATA = os.path.join(os.path.dirname(__file__), "data", "zmx", "gratings")
FILES = ("optiland_curved_reflective_grating.zmx", "optiland_curved_transmission_grating.zmx",
         "optiland_flat_transmission_grating.zmx")


def directions(lx, my):
    """Unit directions (L, M, N) with N > 0 from their x and y components."""
    lx, my = np.broadcast_arrays(np.asarray(lx, float), np.asarray(my, float))
    return np.stack([lx, my, np.sqrt(1 - lx * lx - my * my)], -1)


def grating_lens(grating, *, mirror=False, glass=None, wl=LAM):
    """One grating at z = 0 in air (glass after it if ``glass``), image 10 mm beyond."""
    after = glass or jl.Air()
    return jl.Lens((grating,), jnp.array([-10.0 if mirror else 10.0]), (after,), epd=2.0,
                   wavelengths=jnp.array([wl]), mirrors=(0,) if mirror else ())


def hit(lens, o, d, wl=LAM):
    """The rays just after surface 1: (points, directions, valid, optical path)."""
    out = jl.trace(lens, jl.Rays(jnp.asarray(o), jnp.asarray(d), wl), upto=0)
    return (np.asarray(out.origin), np.asarray(out.direction), np.asarray(out.valid),
            np.asarray(out.opl))


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # IWDP and EERA: OpticStudio keywords jaxlens ignores
        return jl.load(path)


# ---------------------------------------------------------------------------- single rays
@pytest.mark.parametrize("order", [-2.0, -1.0, 1.0, 3.0])
@pytest.mark.parametrize("mirror", [False, True])
def test_flat_grating_obeys_the_grating_equation_in_3d(order, mirror):
    """Flat grating, T = 0.3 lines/µm: n′M′ = n·M + order·λ·T and n′L′ = n·L (rays with an x
    component too), N′ > 0 into glass, N′ < 0 off the mirror (n′ = n); |d′| = 1."""
    t = 0.3
    glass = None if mirror else jl.ModelGlass(1.6, 40.0)
    lens = grating_lens(jl.Grating(lines_per_um=t, order=order), mirror=mirror, glass=glass)
    d = directions([0.0, 0.2, -0.35, 0.1, 0.0], [0.0, 0.1, -0.2, 0.4, -0.3])
    o = np.array([[0.0, 0.0, -1.0], [0.5, -0.3, -2.0], [-0.4, 0.7, -1.0], [0.2, 0.2, -3.0],
                  [0.0, -0.6, -1.0]])
    p, d2, valid, _ = hit(lens, o, d)
    n2 = 1.0 if mirror else float(lens.indices(LAM)[1])
    m2 = (d[:, 1] + order * LAM * t) / n2
    l2 = d[:, 0] / n2
    live = l2 * l2 + m2 * m2 < 1
    assert valid.tolist() == live.tolist() and live.sum() >= 3
    np.testing.assert_allclose(d2[live, 0], l2[live], rtol=0, atol=2e-16)
    np.testing.assert_allclose(d2[live, 1], m2[live], rtol=0, atol=2e-16)
    n_out = np.sqrt(1 - l2 ** 2 - m2 ** 2)[live]
    np.testing.assert_allclose(d2[live, 2], -n_out if mirror else n_out, rtol=0, atol=1e-15)
    np.testing.assert_allclose(p[:, 2], 0.0, atol=1e-15)


def test_order_sign_bends_toward_plus_y_and_its_size_is_the_spacing():
    """Zemax's sign: on-axis light through a flat grating of T lines/µm in air leaves with
    sin θ′ = M λ T toward +y for M > 0 (optiland's tests quote M′ = −0.1174 for order −1,
    λ = 0.587 µm, Λ = 5 µm)."""
    for order, expect in ((-1.0, -0.1174), (1.0, 0.1174), (2.0, 0.2348)):
        lens = grating_lens(jl.Grating(lines_per_um=0.2, order=order))
        _, d2, valid, _ = hit(lens, np.array([[0.0, 1.0, -1.0]]), directions([0.0], [0.0]))
        assert valid[0] and d2[0, 1] == pytest.approx(expect, abs=1e-15)


def test_evanescent_order_is_lost():
    """A ray whose order would need |sin θ′| > 1 is invalid, with finite values; its
    neighbours in the same batch are traced."""
    lens = grating_lens(jl.Grating(lines_per_um=1.2, order=1.0))  # M λ T = 0.7044
    d = directions([0.0, 0.0, 0.0, 0.25], [0.0, 0.2, 0.35, 0.0])
    o = np.zeros((4, 3)) - d
    _, d2, valid, opl = hit(lens, o, d)
    m2 = d[:, 1] + LAM * 1.2
    assert (d[:, 0] ** 2 + m2 ** 2 < 1).tolist() == [True, True, False, True]
    assert valid.tolist() == [True, True, False, True]
    assert np.all(np.isfinite(d2)) and np.all(np.isfinite(opl))
    mirror = grating_lens(jl.Grating(lines_per_um=1.2, order=-2.0), mirror=True)
    assert hit(mirror, o, d)[2].tolist() == [False] * 4  # |M λ T| = 1.41 > 1


@pytest.mark.parametrize("mirror", [False, True])
def test_curved_grating_kicks_along_the_projected_lines(mirror):
    """On a conic the tangential part of n′d′ − n·d equals that of (0, M λ T, 0) (the lines
    equally spaced in the x–y projection, Zemax's definition) for skew rays; the normal part
    goes forward (transmission) or back (mirror)."""
    c, k, t, order = 0.04, -0.6, 0.25, -2.0
    glass = None if mirror else jl.ModelGlass(1.5, 60.0)
    lens = grating_lens(jl.Grating(c=c, k=k, lines_per_um=t, order=order), mirror=mirror,
                        glass=glass)
    d = directions([0.12, -0.2, 0.05], [-0.2, 0.15, 0.3])
    o = np.array([[1.1, 2.3, -1.0], [-3.0, 1.5, -2.0], [2.5, -2.2, -1.0]])
    p, d2, valid, _ = hit(lens, o, d)
    assert valid.all()
    n2 = 1.0 if mirror else float(lens.indices(LAM)[1])
    for pi, di, ei in zip(p, d, d2, strict=True):
        normal = np.array([-c * pi[0], -c * pi[1], 1 - c * (1 + k) * pi[2]])
        normal /= np.linalg.norm(normal)
        jump = n2 * ei - di - np.array([0.0, order * LAM * t, 0.0])
        np.testing.assert_allclose(jump - (jump @ normal) * normal, 0.0, atol=2e-15)
        assert abs(np.linalg.norm(ei) - 1) < 1e-15
        assert np.sign(ei @ normal) == (-1 if mirror else 1) * np.sign(di @ normal)


@pytest.mark.parametrize("mirror", [False, True])
def test_order_zero_is_the_plain_surface(mirror):
    """Order 0 (or no lines) traces exactly as the Standard conic, or as its mirror, with the
    same optical path."""
    base = dict(c=0.03, k=-0.4)
    d = directions([0.1, -0.05, 0.0], [0.2, 0.0, -0.3])
    o = np.array([[0.5, -1.0, -2.0], [1.5, 0.5, -1.0], [-2.0, 2.0, -1.0]])
    plain = hit(grating_lens(jl.Standard(**base), mirror=mirror), o, d)
    for g in (jl.Grating(**base, lines_per_um=0.5, order=0.0),
              jl.Grating(**base, lines_per_um=0.0, order=3.0)):
        got = hit(grating_lens(g, mirror=mirror), o, d)
        for a, b in zip(got, plain, strict=True):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)


def test_optical_path_adds_the_phase():
    """The optical path gains (λ/2π)Φ = M λ T y (mm): zero on the local x axis."""
    g = jl.Grating(lines_per_um=0.2, order=-1.0)
    d = directions([0.0, 0.0, 0.1], [0.0, 0.0, 0.0])
    o = np.array([[0.0, 0.0, -1.0], [0.3, 2.0, -1.0], [-0.1, -3.0, -1.0]])
    o = o - 0.0 * d
    _, _, valid, opl = hit(grating_lens(g), o, d)
    _, _, _, opl0 = hit(grating_lens(jl.Plane()), o, d)
    y = o[:, 1] + d[:, 1] / d[:, 2]
    assert valid.all()
    np.testing.assert_allclose(opl - opl0, -1.0 * LAM * 1e-3 * 0.2 * 1e3 * y, rtol=0,
                               atol=1e-15)
    phi, px, py = g.phase(jnp.array([0.0, 4.0]), jnp.array([1.0, 1.0]))
    assert np.asarray(phi).tolist() == pytest.approx([-2 * math.pi * 200.0] * 2, rel=1e-15)
    assert np.asarray(px).tolist() == [0.0, 0.0]
    assert np.asarray(py).tolist() == pytest.approx([-2 * math.pi * 200.0] * 2, rel=1e-15)


# ------------------------------------------------------------------ the optiland samples
with open(os.path.join(DATA, "reference.json")) as _f:
    REFERENCE = json.load(_f)


@pytest.mark.parametrize("name", FILES)
def test_sample_files_match_optiland_ray_by_ray(name):
    """jaxlens's image intercepts of the stored rays (3 fields each) equal optiland's with
    the lines equally spaced in the x–y projection to 1e-9 mm; optiland as shipped takes the
    local spacing as Λ/|f_xy|, which differs from that where the normal has both x and y
    components: there the two differ by up to 2e-4 mm on these files (0 on the flat one)."""
    lens = unclipped(_load(os.path.join(DATA, name)))
    ref = REFERENCE["files"][name]
    o = np.array([r["origin"] for r in ref["rays"]])
    d = np.array([r["direction"] for r in ref["rays"]])
    wl = ref["rays"][0]["wavelength_um"]
    assert {r["wavelength_um"] for r in ref["rays"]} == {wl} and len(o) >= 30
    out = jl.trace(lens, jl.Rays(jnp.asarray(o), jnp.asarray(d), wl))
    assert bool(jnp.all(out.valid))
    p = np.asarray(out.origin)
    exact = np.array([r["optiland_projected_spacing"] for r in ref["rays"]])
    shipped = np.array([r["optiland"] for r in ref["rays"]])
    np.testing.assert_allclose(p, exact, rtol=0, atol=1e-9)
    bound = 1e-9 if "flat" in name else 3e-4
    assert np.max(np.abs(p - shipped)) <= bound
    # The image is 30 mm from the grating: the wrong sign of the order would be millimetres off.
    flipped = eqx.tree_at(lambda m: m.surfaces[-1].order, lens, -lens.surfaces[-1].order)
    q = np.asarray(jl.trace(flipped, jl.Rays(jnp.asarray(o), jnp.asarray(d), wl)).origin)
    assert np.max(np.abs(q - exact)) > 1.0


@pytest.mark.parametrize(("name", "quoted"), [
    ("optiland_curved_transmission_grating.zmx", [0.0229384233, 0.0764682608, 0.9968081229]),
    ("optiland_flat_transmission_grating.zmx", [0.0345602649, 0.0216899611, 0.9991672201]),
])
def test_direction_cosines_quoted_by_optilands_tests(name, quoted):
    """optiland's tests quote, to 10 decimals, the direction leaving its transmission gratings
    of the ray (Hx, Hy, Px, Py) = (0.2, 0.8, −0.15, 0.7); the incident ray below is optiland's
    for it (``ray_tracer.ray_generator.generate_rays``). jaxlens gives the quoted values to
    their rounding; optiland 0.6.3 itself, with its local spacing Λ/|f_xy|, is 3.5e-7 off
    on the curved grating, so the quoted values follow lines equally spaced in the x–y
    projection (Zemax's definition)."""
    lens = unclipped(_load(os.path.join(DATA, name)))
    o = np.array([[-2.1131307462390576, 1.2732056196713617, -15.000000000000002]])
    d = np.array([[0.03456026486007352, 0.1390899611223707, 0.9896764980577133]])
    out = jl.trace(lens, jl.Rays(jnp.asarray(o), jnp.asarray(d), LAM))
    assert bool(out.valid[0])
    np.testing.assert_allclose(np.asarray(out.direction[0]), quoted, rtol=0, atol=1e-10)


@pytest.mark.parametrize("name", FILES)
def test_sample_files_load_with_optilands_efl_and_round_trip(name, tmp_path):
    """Each file loads (the grating as a ``Grating``, the mirror one as a mirror), its
    paraxial data are finite or, for the flat afocal system, infinite as for any plane
    system; the EFL is optiland's f2 (n′/Φ, so its sign flips after the mirror, where
    jaxlens's efl_image_space is |n′|/Φ), and load → save → load is exact."""
    lens = _load(os.path.join(DATA, name))
    g = lens.surfaces[-1]
    assert isinstance(g, jl.Grating) and float(g.lines_per_um) == 0.2
    assert float(g.order) == (1.0 if "reflective" in name else -1.0)
    assert lens.mirrors == ((0,) if "reflective" in name else ())
    data = jl.paraxial_data(lens)
    f2 = REFERENCE["files"][name]["optiland_f2"]
    efl = float(data.efl_image_space)
    if "flat" in name:
        assert math.isinf(efl) and math.isinf(f2)
    else:
        assert efl == pytest.approx(-f2 if lens.mirrors else f2, rel=1e-12)
        assert all(math.isfinite(float(v)) for v in (data.efl, data.bfl, data.fnum))
    out = tmp_path / "w.zmx"
    jl.save(lens, out)
    block = out.read_text().split("TYPE DGRATING\n")[1].split("DISZ")[0].split()
    assert float(block[block.index("PARM") + 2]) == 0.2  # PARM 1, lines per µm
    again = jl.load(out)
    assert jax.tree_util.tree_structure(again) == jax.tree_util.tree_structure(lens)
    for a, b in zip(jax.tree_util.tree_leaves(lens), jax.tree_util.tree_leaves(again),
                    strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_paraxial_data_are_the_order_zero_systems():
    """The lines add no paraxial power: paraxial data equal those of the lens with the
    grating's lines removed."""
    lens = _load(os.path.join(DATA, FILES[1]))
    g = lens.surfaces[-1]
    plain = eqx.tree_at(lambda m: m.surfaces[-1], lens,
                        jl.Standard(c=g.c, k=g.k, semi_diameter=g.semi_diameter))
    a, b = jl.paraxial_data(lens), jl.paraxial_data(plain)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


# ------------------------------------------------------------------------------ .zmx
ZMX = """UNIT {unit} X W X CM MR CPMM
ENPD 10
WAVM 1 0.55 1
SURF 0
  DISZ INFINITY
SURF 1
  STOP
  TYPE DGRATING
  CURV 0.02 0 0 0 0 ""
  CONI -0.5
  PARM 1 {density}
  PARM 2 {order}
  DISZ {disz}
{extra}SURF 2
"""


def _zmx(tmp_path, unit="MM", density="0.6", order="-3", disz="20", extra=""):
    p = tmp_path / "g.zmx"
    p.write_text(ZMX.format(unit=unit, density=density, order=order, disz=disz, extra=extra))
    return p


def test_zmx_reads_the_line_density_in_lines_per_um_whatever_the_unit(tmp_path):
    """CURV scales with the lens unit; PARM 1 (lines/µm) does not."""
    for unit, scale in (("MM", 1.0), ("IN", 25.4)):
        lens = jl.load(_zmx(tmp_path, unit=unit))
        g = lens.surfaces[0]
        assert float(g.c) == pytest.approx(0.02 / scale, rel=1e-15)
        assert (float(g.k), float(g.lines_per_um), float(g.order)) == (-0.5, 0.6, -3.0)
    lens = jl.load(_zmx(tmp_path, extra="  GLAS MIRROR 0 0 1.5 40 0 0 0 0 0 0\n", disz="-20"))
    assert lens.mirrors == (0,) and isinstance(lens.surfaces[0], jl.Grating)


def test_zmx_round_trip_is_exact(tmp_path):
    lens = jl.load(_zmx(tmp_path, density="0.123456789012345678", order="7"))
    out = tmp_path / "w.zmx"
    jl.save(lens, out)
    again = jl.load(out)
    for a, b in zip(jax.tree_util.tree_leaves(lens), jax.tree_util.tree_leaves(again),
                    strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize(("kw", "line", "what"), [
    ({"density": "-0.2"}, 11, r"PARM 1 \(the grating's line density, lines per µm\) must be "
                              r">= 0, got -0.2"),
    ({"density": "nan"}, 11, "PARM 1 value must be finite"),
    ({"density": "1e400"}, 11, "PARM 1 value must be finite"),
    ({"order": "1.5"}, 12, r"PARM 2 \(the grating's diffraction order\) must be a whole "
                           r"number, got 1.5"),
    ({"order": "abc"}, 12, r"PARM 2 value is not a number \('abc'\)"),
    ({"extra": "  PARM 3 1\n"}, 14, r"DGRATING \(PARM 1 = lines per µm, PARM 2 = diffraction "
                                    r"order\) uses PARM 1..2 only"),
    ({"extra": "  XDAT 1 2 0 0 1 0 0 \"\"\n"}, 14, r"DGRATING has no extra data \(XDAT\)"),
])
def test_zmx_refuses_bad_gratings_naming_the_file_and_line(tmp_path, kw, line, what):
    p = _zmx(tmp_path, **kw)
    with pytest.raises(ValueError, match=f"^{p}:{line}: {what}"):
        jl.load(p)


def test_zmx_refuses_a_grating_image(tmp_path):
    text = ZMX.format(unit="MM", density="0.6", order="1", disz="20", extra="")
    img = tmp_path / "img.zmx"
    img.write_text(text.replace("SURF 2\n", "SURF 2\n  TYPE DGRATING\n  PARM 1 0.1\n"))
    with pytest.raises(ValueError, match=f"^{img}:15: the image surface must be STANDARD"):
        jl.load(img)


# ------------------------------------------------------------------------ gradients
def test_gradients_match_central_differences():
    """d(loss)/d(c, T) through a curved transmission grating and a reflective one, loss the
    mean squared image y (float64), equals central differences."""
    lens0 = _load(os.path.join(DATA, FILES[1]))
    mirror0 = _load(os.path.join(DATA, FILES[0]))
    for lens in (unclipped(lens0), unclipped(mirror0)):
        i = len(lens.surfaces) - 1
        ref = REFERENCE["files"][FILES[1] if not lens.mirrors else FILES[0]]["rays"]
        rays = jl.Rays(jnp.asarray([r["origin"] for r in ref]),
                       jnp.asarray([r["direction"] for r in ref]), ref[0]["wavelength_um"])

        def loss(theta, lens=lens, i=i, rays=rays):
            g = eqx.tree_at(lambda m: (m.surfaces[i].c, m.surfaces[i].lines_per_um), lens,
                            (theta[0], theta[1]))
            out = jl.trace(g, rays)
            return jnp.mean(jnp.where(out.valid, out.origin[:, 1] ** 2 + out.opl * 1e-3, 0.0))

        s = lens.surfaces[i]
        theta = jnp.array([float(s.c), float(s.lines_per_um)])
        grad = np.asarray(jax.grad(loss)(theta))
        for j, h in ((0, 1e-7), (1, 1e-6)):
            e = np.zeros(2)
            e[j] = h
            fd = (float(loss(theta + e)) - float(loss(theta - e))) / (2 * h)
            assert grad[j] == pytest.approx(fd, rel=1e-6), (j, grad[j], fd)
            assert abs(grad[j]) > 1e-3


# -------------------------------------------------------------------- other consumers
def test_backward_trace_retraces_the_forward_ray():
    """Reciprocity: a ray traced back from where it landed, with its direction reversed,
    leaves the lens along the reverse of the ray that came in (the mirrored grating keeps its
    lines and order)."""
    g = jl.Grating(c=0.02, k=-0.3, lines_per_um=0.15, order=1.0)
    mirrored = backward.mirror_surface(g)
    assert isinstance(mirrored, jl.Grating) and float(mirrored.c) == -0.02
    assert (float(mirrored.order), float(mirrored.lines_per_um)) == (1.0, 0.15)
    lens = jl.Lens((jl.Plane(), g), jnp.array([5.0, 30.0]), (jl.ModelGlass(1.5, 60.0), jl.Air()),
                   epd=4.0, wavelengths=jnp.array([LAM]))
    o = jnp.array([[0.3, 1.0, -1.0], [-0.5, -1.2, -1.0]])
    d = jnp.asarray(directions([0.05, -0.02], [-0.1, 0.08]))
    out = jl.trace(lens, jl.Rays(o, d, LAM))
    back = backward.trace_backward(lens, jl.Rays(out.origin, -out.direction, LAM))
    assert bool(jnp.all(back.valid))
    np.testing.assert_allclose(np.asarray(back.direction), -np.asarray(d), atol=1e-13)


def test_every_other_consumer_handles_or_refuses_it(tmp_path):
    g = jl.Grating(c=0.01, lines_per_um=0.3, order=-1.0)
    lens = jl.Lens((jl.Plane(), g), jnp.array([5.0, 20.0]), (jl.ModelGlass(1.5, 60.0), jl.Air()),
                   epd=4.0, wavelengths=jnp.array([LAM]))
    with pytest.raises(ValueError, match="ToleranceModel: surface 2 is a Grating"):
        ToleranceModel(lens)
    with pytest.raises(ValueError, match="Grating; only Standard"):
        forward.stacked_surfaces(lens.surfaces)
    with pytest.raises(ValueError, match="only an EvenAsphere can be rebased, got a Grating"):
        rebase_conic(g)
    template = eqx.tree_at(lambda m: m.surfaces[0], lens,
                           jl.EvenAsphere(c=0.02, coeffs=jnp.zeros(3)))
    with pytest.raises(ValueError, match=r"surfaces\[1\] is a Grating"):
        Parameterization(template=template, r_norm=jnp.ones(2), total_track=40.0,
                         optical=(0, 1))
    assert json_round_trip(lens, tmp_path).surfaces[1].order == g.order
    mirror = jl.Lens((jl.Plane(), g), jnp.array([5.0, -20.0]), (jl.Air(), jl.Air()), epd=2.0,
                     mirrors=(1,), wavelengths=jnp.array([LAM]))
    out = jl.trace(mirror, jl.Rays(jnp.zeros((1, 3)), jnp.array([[0.0, 0.0, 1.0]]), LAM))
    assert bool(out.valid[0]) and float(out.direction[0, 2]) < 0
    assert lensfile.surface_to_dict(g)["type"] == "grating"
    assert json_round_trip(mirror, tmp_path).mirrors == (1,)
    text = report.format_report(report.report_data(lens), lens)
    rows = [ln for ln in text.splitlines() if "DGRATING" in ln]
    assert len(rows) == 1 and "T=0.3/um M=-1" in rows[0]


def test_surface_checks_its_numbers():
    with pytest.raises(ValueError, match=r"Grating: lines_per_um must be finite numbers in "
                                         r"\[0, inf\) lines per µm, got -0.5"):
        jl.Grating(lines_per_um=-0.5)
    with pytest.raises(ValueError, match="Grating: lines_per_um must be finite"):
        jl.Grating(lines_per_um=float("inf"))
    with pytest.raises(ValueError, match=r"Grating: order must be a whole number \(the "
                                         r"diffraction order\), got 0.5"):
        jl.Grating(order=0.5)
    with pytest.raises(ValueError, match="Grating: order must be finite"):
        jl.Grating(order=float("nan"))
    with pytest.raises(ValueError, match="Grating: c must be finite"):
        jl.Grating(c=float("nan"))
    with pytest.raises(TypeError):
        jl.Grating(lines_per_um="0.2")
