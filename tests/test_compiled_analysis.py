"""Eager analysis calls reuse their compiled programs: a second call on a lens of the same
structure (other values) compiles nothing.

The count is of XLA backend compilations (a ``jax.monitoring`` listener), and of the
primitives dispatched one by one from Python (``Primitive.bind`` counted while the block
runs: a call of a compiled program that is cached binds none). Before the
compiled cores, ``aiming.stop_chief_ray`` (and ``chief_point``) built the aiming loop's body
as a new closure at every call and compiled it again each time (2.3 s a call on the Cooke
triplet); ``seidel``, ``zernike_fit`` (``Wavefront.zernike``) and ``self_intersection``
dispatched op by op (60-120 ms a call). The results of an eager call equal those of the
same call under the caller's ``jax.jit``.
"""

from __future__ import annotations

import contextlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.extend.core import Primitive

import jaxlens as jl
from jaxlens.analysis import seidel, self_intersection, zernike_fit
from jaxlens.imaging import aiming

_COMPILE_EVENT = "/jax/core/compile/backend_compile_duration"
_count = [0]


def _listener(event, duration, **kwargs):
    if event == _COMPILE_EVENT:
        _count[0] += 1


jax.monitoring.register_event_duration_secs_listener(_listener)


@contextlib.contextmanager
def compilations():
    """Yields a one-element list that holds, on exit, the compilations inside the block."""
    out = [0]
    start = _count[0]
    try:
        yield out
    finally:
        out[0] = _count[0] - start


@contextlib.contextmanager
def dispatches():
    """Yields a one-element list that holds, on exit, the primitives bound from Python in
    the block (an op-by-op computation binds each of its operations)."""
    out = [0]
    bind = Primitive.bind

    def counted(self, *args, **params):
        out[0] += 1
        return bind(self, *args, **params)

    Primitive.bind = counted
    try:
        yield out
    finally:
        Primitive.bind = bind


def scaled(lens, factor):
    """The lens with every curvature times ``factor``: the same pytree structure."""
    surfaces = tuple(eqx.tree_at(lambda s: s.c, s, s.c * factor) for s in lens.surfaces)
    return eqx.tree_at(lambda m: m.surfaces, lens, surfaces)


@pytest.fixture(scope="module")
def singlets():
    """A biconvex N-BK7 singlet with the stop 5 mm behind it (the chief ray is aimed through
    both surfaces), and the same lens with its curvatures 1 % larger."""
    a = jl.Lens(surfaces=(jl.Sphere(1 / 50), jl.Sphere(-1 / 50), jl.Stop()),
                thickness=jnp.array([5.0, 5.0, 40.0]),
                materials=(jl.get_material("N-BK7"), jl.Air(), jl.Air()),
                stop=2, epd=8.0, fields=jnp.array([0.0, 7.0, 10.0]),
                wavelengths=jnp.array([0.4861327, 0.5875618, 0.6562725]), primary=1)
    return a, scaled(a, 1.01)


def test_the_counter_sees_a_compilation():
    """The listener counts: a function jitted here for the first time compiles once."""
    x = jnp.arange(7.0)
    with compilations() as n:
        jax.jit(lambda v: v * 3.0 + 1.0)(x).block_until_ready()
    assert n[0] == 1


def test_stop_chief_ray_compiles_once_per_lens_structure(singlets):
    a, b = singlets
    ra = aiming.stop_chief_ray(a, 10.0)  # may compile (the first call of this structure)
    with compilations() as n, dispatches() as d:
        rb = aiming.stop_chief_ray(b, 10.0)  # other values
        rc = aiming.stop_chief_ray(b, 7.0)  # another field, a Python number too
        jax.block_until_ready((rb, rc))
    assert n[0] == 0  # main: 1 compilation (2.3 s) a call
    assert d[0] <= 8
    assert bool(rb.valid[0]) and bool(rc.valid[0])
    # b's own chief ray, not a's: the 1 % stronger lens is aimed elsewhere.
    assert abs(float(rb.origin[0, 1] - ra.origin[0, 1])) > 1e-4
    # The arguments are still checked before the compiled core, naming the entry point.
    with pytest.raises(ValueError, match=r"stop_chief_ray: field must be finite angles"):
        aiming.stop_chief_ray(b, 95.0)
    with pytest.raises(ValueError, match=r"stop_chief_ray: depth must be finite, nonzero"):
        aiming.stop_chief_ray(b, 5.0, 0.0)  # -10: a virtual object
    with pytest.raises(ValueError, match=r"stop_chief_ray: wavelength"):
        aiming.stop_chief_ray(b, 5.0, wavelength=587.6)


def test_seidel_and_zernike_fit_reuse_their_programs(singlets):
    a, b = singlets
    seidel(a)
    sa = seidel(b)
    gx, gy = np.meshgrid(np.linspace(-1.0, 1.0, 15), np.linspace(-1.0, 1.0, 15))
    disc = np.hypot(gx, gy) <= 1.0
    x, y = jnp.asarray(gx[disc]), jnp.asarray(gy[disc])
    zernike_fit(x, y, x * x + y * y, terms=15)
    other = x * x + 0.5 * y * y * y
    with compilations() as n, dispatches() as d:
        sb = seidel(b)
        fit = zernike_fit(x, y, other, terms=15)
        jax.block_until_ready((sb, fit))
    assert n[0] == 0
    # main: 700 operations dispatched one by one (60-120 ms); since round 36a seidel also
    # evaluates each medium's index at its wavelengths (an index below 1 is refused).
    assert d[0] <= 16
    np.testing.assert_array_equal(np.asarray(sb.per_surface), np.asarray(sa.per_surface))
    assert abs(float(fit.coefficients[0])) > 0.1  # the fit of the other values
    # ρ² = (Z1 + Z4/√3)/2 in Noll's order: the fit is the polynomial's.
    f2 = zernike_fit(x, y, x * x + y * y, terms=15)
    np.testing.assert_allclose(np.asarray(f2.coefficients)[[0, 3]], [0.5, 0.5 / np.sqrt(3.0)],
                               rtol=1e-12)


def test_self_intersection_reuses_its_program(singlets):
    a, b = singlets
    sd = jnp.full(a.num_surfaces, 4.5)
    self_intersection(a, sd)
    with compilations() as n, dispatches() as d:
        gb = self_intersection(b, sd)
        g2 = self_intersection(b, sd, min_gap=0.1)  # another clearance: the same program
        jax.block_until_ready((gb, g2))
    assert n[0] == 0
    assert d[0] <= 8  # main: about 200 operations a call, one by one
    assert bool(gb.ok) and np.all(np.asarray(gb.min_gap) > 0)
    np.testing.assert_array_equal(np.asarray(gb.min_gap), np.asarray(g2.min_gap))
