"""Round 36e: gradients of public analyses against central differences (float64), in the
parameters their own tests did not vary: a model glass's nd and Vd, a paraboloid's conic
(k = -1), a flat surface's curvature (c = 0), the wavelength (between the nodes of a table
glass), the field angle and a finite object's distance. ``tools/grad36e_probe.py`` is the
audit these cases come from."""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens.analysis import third_order
from jaxlens.imaging import aiming, otf
from jaxlens.optics import paraxial


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def _lens(object_distance=None):
    """Conic and even-asphere triplet with model glasses, a flat surface, a paraboloid and
    the stop on a surface of its own."""
    g1, g2 = jl.ModelGlass(1.62, 60.3), jl.ModelGlass(1.62, 36.4)
    s = (
        jl.EvenAsphere(1 / 22.0, -0.3, jnp.array([0.0, 2e-6, -1e-9])),
        jl.Conic(0.0, 0.0),
        jl.Stop(),
        jl.Conic(-1 / 22.2, -1.0),
        jl.Sphere(1 / 20.3),
        jl.Conic(1 / 79.7, -2.0),
        jl.Conic(-1 / 18.4, 1.5),
    )
    t = jnp.array([3.26, 3.0, 3.01, 1.0, 4.75, 2.95, 42.2])
    mats = (g1, jl.Air(), jl.Air(), g2, jl.Air(), g1, jl.Air())
    return jl.Lens(
        s,
        t,
        mats,
        stop=2,
        epd=10.0,
        fields=jnp.array([0.0, 14.0]),
        wavelengths=jnp.array([0.4861327, 0.5875618, 0.6562725]),
        primary=1,
        object_distance=object_distance,
    )


# name: (getter on (lens, extras), index into the leaf or None, step)
_PARAMS = {
    "c1_flat": (lambda P: P[0].surfaces[1].c, None, 1e-5),
    "k3_parabola": (lambda P: P[0].surfaces[3].k, None, 1e-3),
    "c3": (lambda P: P[0].surfaces[3].c, None, 1e-5),
    "t0": (lambda P: P[0].thickness, 0, 1e-4),
    "t2_stop": (lambda P: P[0].thickness, 2, 1e-4),
    "nd0": (lambda P: P[0].materials[0].nd, None, 1e-5),
    "vd3": (lambda P: P[0].materials[3].vd, None, 1e-3),
    "epd": (lambda P: P[0].epd, None, 1e-4),
    "objd": (lambda P: P[0].object_distance, None, 1e-2),
    "field": (lambda P: P[1]["field"], None, 1e-4),
    "wl": (lambda P: P[1]["wl"], None, 1e-5),
}

_FUNCS = {
    "image_height": lambda L, e: paraxial.image_height(L, e["field"], e["wl"]),
    "entrance_pupil_z": lambda L, e: paraxial.entrance_pupil_z(L, e["wl"]),
    "ep_magnification": lambda L, e: paraxial.entrance_pupil_magnification(L, e["wl"]),
    "exit_pupil_z": lambda L, e: paraxial.paraxial_data(L, e["wl"]).exit_pupil_z,
    "working_fnum": lambda L, e: paraxial.paraxial_data(L, e["wl"]).working_fnum,
    "chief_ray_height": lambda L, e: paraxial.paraxial_chief_ray(L, e["field"], e["wl"])[0][-1],
    "field_to_ideal": lambda L, e: aiming.field_to_ideal(
        L, jnp.stack([0.0 * e["field"], e["field"]]), e["wl"]
    )[1],
    "diffraction_mtf": lambda L, e: otf.diffraction_mtf(
        jnp.array([40.0]), e["wl"] * 1e-3, paraxial.paraxial_data(L, e["wl"]).fnum
    )[0],
    "seidel_W040": lambda L, e: third_order.seidel(
        L, field=e["field"], wavelength=e["wl"]
    ).wavefront()[0],
    "seidel_W222": lambda L, e: third_order.seidel(
        L, field=e["field"], wavelength=e["wl"]
    ).wavefront()[2],
}


def _fd_agrees(fn, P, names, rel=1e-6):
    """d fn / d(each named parameter) (``fn`` gives a vector: one compiled Jacobian for
    every output) against central differences."""
    dyn, static = eqx.partition(P, eqx.is_inexact_array)

    def f(d):
        L, e = eqx.combine(d, static)
        return jnp.atleast_1d(jnp.asarray(fn(L, e)))

    fj = jax.jit(f)
    value = fj(dyn)
    jac = eqx.combine(jax.jit(jax.jacrev(f))(dyn), static)
    assert jnp.all(jnp.isfinite(value))
    for name in names:
        get, j, h = _PARAMS[name]
        x = get(P) if j is None else get(P)[j]
        g = get(jac) if j is None else get(jac)[..., j]
        assert jnp.all(jnp.isfinite(g)), name

        def at(v, get=get, j=j, dtype=x.dtype):
            v = jnp.asarray(v, dtype)
            new = eqx.tree_at(get, P, v if j is None else get(P).at[j].set(v))
            return fj(eqx.partition(new, eqx.is_inexact_array)[0])

        fd = (at(x + h) - at(x - h)) / (2 * h)
        for k in range(fd.shape[0]):
            assert float(g[k]) == pytest.approx(
                float(fd[k]), rel=rel, abs=1e-9 * max(1.0, abs(float(value[k])))
            ), (name, k)


def _all(keys):
    return lambda L, e: jnp.stack([_FUNCS[k](L, e) for k in keys])


def test_untested_parameters_match_central_differences():
    """Every function of ``_FUNCS`` (outputs stacked) in every parameter of ``_PARAMS``."""
    P = (_lens(), {"field": jnp.asarray(9.0), "wl": jnp.asarray(0.55)})
    names = ["c1_flat", "k3_parabola", "c3", "t2_stop", "nd0", "vd3", "epd", "field", "wl"]
    _fd_agrees(_all(sorted(_FUNCS)), P, names)


def test_finite_object_distance_matches_central_differences():
    P = (_lens(500.0), {"field": jnp.asarray(9.0), "wl": jnp.asarray(0.55)})
    _fd_agrees(
        _all(["entrance_pupil_z", "working_fnum", "image_height", "seidel_W040"]),
        P,
        ["objd", "c3", "nd0"],
    )


def test_lens_is_float64():
    lens = _lens()
    assert lens.thickness.dtype == jnp.float64
    assert dataclasses.replace(lens, epd=5.0).epd.dtype == jnp.float64


def _root_slope(c, y):
    """d t/d y of the intersection of the ray from (0, y, −5) along (0, 0.1, 1)/|…| with an
    even asphere of curvature c (Newton-solved): a first derivative of the root."""
    from jaxlens.tracing.step import intersect

    d = jnp.array([0.0, 0.1, 1.0]) / jnp.sqrt(1.01)

    def t(yy):
        surface = jl.EvenAsphere(c, -0.5, jnp.array([0.0, 2e-3, -1e-5]))
        return intersect(surface, (jnp.zeros(()), yy, jnp.asarray(-5.0)), tuple(d))

    return jax.jvp(t, (y,), (jnp.ones(()),))[1]


def test_newton_root_second_derivative_matches_central_differences():
    """d/dc (dt/dy) of a Newton-solved intersection: the root's last step held F' fixed,
    which gives exact first derivatives but dropped terms of the second (off by 3 % here)."""
    c, y = jnp.asarray(0.05), jnp.asarray(1.5)
    g = jax.jit(jax.grad(_root_slope))(c, y)
    h = 1e-5
    fd = (_root_slope(c + h, y) - _root_slope(c - h, y)) / (2 * h)
    assert float(g) == pytest.approx(float(fd), rel=1e-6)
    gy = jax.jit(jax.grad(_root_slope, argnums=1))(c, y)
    fdy = (_root_slope(c, y + h) - _root_slope(c, y - h)) / (2 * h)
    assert float(gy) == pytest.approx(float(fdy), rel=1e-6)


@pytest.mark.slow
def test_field_curvature_gradient_through_newton_surfaces():
    """``field_curvature`` differentiates the trace (``jax.jvp`` along the pupil); its
    gradient is a second derivative of the trace. On the hybrid singlet (a Newton-solved
    surface) the root's last step held F' fixed, so d(focus)/d(stop distance) came out 0.0046
    against 0.0112 mm/mm by central differences, and d/d(field) 8e-4 off."""
    lens = jl.load("jaxlens/data/lenses/hybrid_singlet.json")
    P = (lens, {"field": jnp.asarray(6.0), "wl": jnp.asarray(0.55)})

    def tangential(L, e):
        fc = jl.analysis.field_curvature(L, e["field"][None], e["wl"][None])
        return fc.tangential[0, 0]

    _fd_agrees(tangential, P, ["t0", "field", "wl"])
