"""Forward tracing from object space: runs of same-kind surfaces scanned, large batches chunked.

``trace`` returns the rays on the image surface, ``trace_path`` the rays after every surface
(stacked on a leading axis). Both move rays with ``step.surface_step``; with
``reverse_rule=True``, plane, sphere and conic surfaces and those with polynomial terms with
``surface_adjoint.rule_step`` (the same values, a hand-written reverse rule, no forward mode).
Runs of surfaces of the same kind and shape are traced with one ``lax.scan``; with
``uniform=True`` every surface after the first is first converted to one common kind
(``uniform_surfaces``, coefficients zero-padded, the sag unchanged), so the whole lens is one
scan and compile time does not grow with the surface count. Conventions: see ``step``.

A lens with ``negative_propagation`` (static; set by the ``.zmx`` reader) lets rays go back
along their line to every surface after the first, as Zemax does (``step.intersect``'s
``go_back``); without it the operations are those of the default rule.

Mirrors (``Lens.mirrors``) and coordinate breaks (``optics.coordinates``) are static
structure: each is traced on its own, outside the scans, and a lens without them is traced by
exactly the same operations as before they existed. After a coordinate break the rays are in
the break's frame (``optics.coordinates.frame_of`` maps them to global coordinates).
"""

from __future__ import annotations

from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..optics import checks
from ..optics.coordinates import CoordinateBreak, transform
from ..optics.lens import Lens
from ..optics.rays import Rays
from ..optics.surfaces import AbstractSurface, EvenAsphere, Hybrid, Standard
from ..optics.travel import travel_senses
from . import surface_adjoint
from .step import (
    DEFAULT_NEWTON_ITERS,
    RayState,
    rays_from_state,
    state_from_rays,
    surface_step,
)


def uniform_surfaces(surfaces) -> list[AbstractSurface]:
    """The surfaces converted to one kind with equal coefficient lengths (zero-padded).

    All ``Standard`` if none has polynomial terms, else ``EvenAsphere`` if none has odd
    terms, else ``Hybrid``. Each sag is unchanged, so traces agree to rounding. Other
    kinds (``OddAsphere``, ``TiltedPlane``, ``Toroidal``, ``ParaxialSurface``,
    ``CoordinateBreak``) are kept as they are: they split the scan.
    """
    common = (Standard, EvenAsphere, Hybrid)
    even = [s.even_coeffs() if type(s) in common else None for s in surfaces]
    odd = [s.odd_coeffs()[0] if type(s) in common else None for s in surfaces]
    m = max((a.shape[0] for a in even if a is not None), default=0)
    p = max((b.shape[0] for b in odd if b is not None), default=0)

    def pad(a, n):
        return jnp.concatenate([a, jnp.zeros((n - a.shape[0],), a.dtype)])

    out = []
    for s, a in zip(surfaces, even, strict=True):
        if a is None:
            out.append(s)
            continue
        if m == 0 and p == 0:
            out.append(Standard(c=s.c, k=s.k, semi_diameter=s.semi_diameter))
        elif p == 0:
            out.append(EvenAsphere(c=s.c, k=s.k, coeffs=pad(a, m), semi_diameter=s.semi_diameter))
        else:
            bx, by = s.odd_coeffs()
            out.append(Hybrid(c=s.c, k=s.k, coeffs=pad(a, m), odd_x=pad(bx, p), odd_y=pad(by, p),
                              semi_diameter=s.semi_diameter))
    return out


def stacked_surfaces(surfaces) -> AbstractSurface:
    """``uniform_surfaces`` stacked into one surface pytree with a leading surface axis.

    Raises:
        ValueError: for a ``Toroidal`` or ``ParaxialSurface``, which have no common kind
            with the rotationally symmetric surfaces (design works on those only).
    """
    for i, s in enumerate(surfaces):
        if type(s) not in (Standard, EvenAsphere, Hybrid):
            raise ValueError(f"stacked_surfaces: surface {i} is a {type(s).__name__}; only "
                             f"Standard, EvenAsphere and Hybrid surfaces can be stacked")
    return jax.tree.map(lambda *x: jnp.stack(x), *uniform_surfaces(surfaces))


def _same_kind(a, b) -> bool:
    """Same surface type and the same array shapes: such surfaces can share one scan body."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    if ta != tb:
        return False
    return all(x.shape == y.shape and x.dtype == y.dtype for x, y in zip(la, lb, strict=True))


def _runs(surfaces, start: int, stop: int, alone=frozenset()) -> list[tuple[int, int]]:
    """Split surfaces[start:stop] into maximal runs of the same kind; indices in ``alone``
    (mirrors, coordinate breaks) are runs of their own."""
    runs, i = [], start
    while i < stop:
        j = i + 1
        while (j < stop and i not in alone and j not in alone
               and _same_kind(surfaces[j], surfaces[i])):
            j += 1
        runs.append((i, j))
        i = j
    return runs


# XLA:CPU's fusion emitters (jaxlib 0.10) run the forward-mode derivative of a trace with many
# surfaces outside the scans (mirrors, coordinate breaks, apertures) in time exponential in
# their number: to surface 6 / 8 / 10 / 11 of the folded rayoptics_HoO-V2C18Ex66.zmx, 2 rays
# took 0.003 / 0.1 / 4.8 / 14 s, to its image over 10 minutes; the older loop emitters take
# 1 ms. They trace the Cooke triplet 1.6x slower (benchmarks/SPEED.md), so only such lenses
# get them, and only in forward-mode analyses (``forward_mode_jit``; ``aimed_jit`` where they aim).
LOOP_EMITTERS = {"xla_cpu_use_fusion_emitters": False}


def has_unscanned_surfaces(lens: Lens) -> bool:
    """Whether some surface besides the first is traced outside the scans (static)."""
    return bool(lens.mirrors or lens.obscurations or lens.apertures
                or any(isinstance(s, CoordinateBreak) for s in lens.surfaces))


def loop_emitters_wanted(lens: Lens, args=(), kwargs=None, *, aimed_only=False) -> bool:
    """Whether a call of a ``forward_mode_jit`` / ``aimed_jit`` function compiles with
    ``LOOP_EMITTERS``: on a CPU, for a lens with unscanned surfaces, at the top level (inside
    another program the outer one's options hold: JAX takes them top-level only) and, with
    ``aimed_only``, where the call aims at the real stop (its ``aim`` keyword, else
    ``Lens.aim``, is not "paraxial")."""
    kwargs = kwargs or {}
    if aimed_only and (kwargs.get("aim") or lens.aim) == "paraxial":
        return False
    if not has_unscanned_surfaces(lens) or jax.default_backend() != "cpu":
        return False
    return not any(isinstance(x, jax.core.Tracer) for x in jax.tree.leaves((lens, args, kwargs)))


def _emitter_jit(fn, aimed_only: bool):
    plain = eqx.filter_jit(fn)
    loops = eqx.filter_jit(fn, compiler_options=LOOP_EMITTERS)

    def call(lens, *args, **kwargs):
        use = loop_emitters_wanted(lens, args, kwargs, aimed_only=aimed_only)
        return (loops if use else plain)(lens, *args, **kwargs)

    call.__doc__, call.__name__, call.__wrapped__ = fn.__doc__, fn.__name__, fn
    call.loop_emitters = "aimed" if aimed_only else "unscanned"  # which rule (tests read it)
    return call


def forward_mode_jit(fn):
    """``eqx.filter_jit(fn)`` for a function of a lens (its first argument) that takes
    forward-mode derivatives of the trace: on a CPU, a lens with unscanned surfaces is
    compiled with ``LOOP_EMITTERS`` (see there); other lenses compile as before."""
    return _emitter_jit(fn, aimed_only=False)


def aimed_jit(fn):
    """``forward_mode_jit`` for a function of a lens that takes forward-mode derivatives only
    where it aims rays at the real stop (its ``aim`` keyword, else ``Lens.aim``, not
    "paraxial"): the aiming's Newton steps. The folded Ex66 file's 709 aimed rays of one
    field took 0.84 s with the fusion emitters, 0.3 ms to trace (benchmarks/SPEED.md)."""
    return _emitter_jit(fn, aimed_only=True)


def _prepare(lens: Lens, rays: Rays, uniform: bool):
    """What every chunk of a trace shares: the surfaces in the rays' dtype (made uniform
    after surface 1 if asked), the vertex positions and the indices at the rays' wavelengths."""
    lens = lens.astype(rays.dtype)
    surfaces = list(lens.surfaces)
    if uniform and len(surfaces) > 2:
        surfaces[1:] = uniform_surfaces(surfaces[1:])
    return surfaces, lens.vertex_z(), lens.indices(rays.wavelength), lens


def _trace_states(lens: Lens, rays: Rays, newton_iters: int, upto: int | None, *,
                  keep_path: bool, uniform: bool, prepared=None,
                  reverse_rule: bool = False) -> list[RayState]:
    """Trace and return the states after each surface (only the last unless keep_path).

    Runs of surfaces of the same kind (a stack of even aspheres, say) are traced with
    one ``lax.scan``, so the compiled program, and above all its gradient, does not grow
    with the number of surfaces. Surface 1 is traced on its own (object-space rules).
    With ``reverse_rule``, the surfaces ``surface_adjoint.supported`` takes (plane, sphere,
    conic and polynomial ones) are moved by ``surface_adjoint.rule_step``: ``surface_step``'s
    values with a hand-written reverse rule (faster gradients, no forward mode).
    """
    surfaces, zs, idx, lens = _prepare(lens, rays, uniform) if prepared is None else prepared
    shape = jnp.shape(rays.wavelength)  # indices are per wavelength, not per ray
    st = state_from_rays(rays)
    # Static: Zemax's rule, a ray may go back along its line to any surface after the first.
    back = {"go_back": True} if lens.negative_propagation else {}

    def step(surface, z, st, n1, n2, *, first, refracts=True, gap=None, reflects=False,
             obscured=None, apertures=()):
        if reverse_rule and surface_adjoint.supported(surface, reflects=reflects,
                                                      obscured=obscured, apertures=apertures):
            return surface_adjoint.rule_step(surface, z, st, n1, n2, first=first,
                                             refracts=refracts, newton_iters=newton_iters,
                                             gap=gap, **back)
        # The wavelength is read by a diffractive (Binary2) surface only.
        return surface_step(surface, z, st, n1, n2, first=first, refracts=refracts,
                            newton_iters=newton_iters, gap=gap, reflects=reflects,
                            obscured=obscured, apertures=apertures, wavelength=rays.wavelength,
                            **back)

    last = len(surfaces) - 1 if upto is None else upto
    breaks = frozenset(i for i, s in enumerate(surfaces) if isinstance(s, CoordinateBreak))
    mirrors = frozenset(lens.mirrors)
    obsc = {i: (a, b) for i, a, b in lens.obscurations}
    aps = {}  # surface index -> its apertures (static)
    for i, a in lens.apertures:
        aps[i] = aps.get(i, ()) + (a,)
    gaps = _travel_gaps(lens)
    out = []
    first = 0
    while first in breaks and first <= last:  # breaks before the first surface: object space
        st = _break_step(surfaces[first], zs[first], st)
        out.append(st)
        first += 1
    if first > last:
        return out
    st = step(surfaces[first], zs[first], st, idx[first], idx[first + 1], first=True,
              reflects=first in mirrors, obscured=obsc.get(first), apertures=aps.get(first, ()))
    out.append(st)
    alone = breaks | mirrors | frozenset(obsc) | frozenset(aps)
    for i, j in _runs(surfaces, first + 1, last + 1, alone):
        if i in breaks:
            st = _break_step(surfaces[i], zs[i], st)
            out.append(st)
            continue
        if j - i == 1:
            st = step(surfaces[i], zs[i], st, idx[i], idx[i + 1], first=False,
                      gap=gaps(i - 1), reflects=i in mirrors, obscured=obsc.get(i),
                      apertures=aps.get(i, ()))
            out.append(st)
            continue
        stacked = jax.tree.map(lambda *x: jnp.stack(x), *surfaces[i:j])
        n_in = jnp.stack([jnp.broadcast_to(n, shape) for n in idx[i:j]])
        n_out = jnp.stack([jnp.broadcast_to(n, shape) for n in idx[i + 1 : j + 1]])

        def body(carry, xs):
            surface, z, n1, n2, gap = xs
            new = step(surface, z, carry, n1, n2, first=False, gap=gap)
            return new, (new if keep_path else None)

        # Checkpointed body: the backward pass recomputes a surface from the carry instead
        # of storing every intermediate (2.5-5x faster gradients, benchmarks/SPEED.md). The
        # reverse rule keeps only the root and the gain, and is faster not recomputed (for
        # polynomial surfaces, recomputing would also re-run the Newton iterations).
        if not (reverse_rule and surface_adjoint.supported(surfaces[i])):
            body = jax.checkpoint(body)

        run_gaps = gaps(slice(i - 1, j - 1))
        st, path = jax.lax.scan(body, st, (stacked, zs[i:j], n_in, n_out, run_gaps))
        if keep_path:
            out += [jax.tree.map(lambda x, k=k: x[k], path) for k in range(j - i)]
        else:
            out.append(st)
    if upto is None:
        st = step(lens.image, lens.image_z(), st, idx[-1], idx[-1], first=False,
                  refracts=False, gap=gaps(-1), apertures=aps.get(len(surfaces), ()))
        out.append(st)
    return out


def _break_step(cb: CoordinateBreak, z_vertex, st: RayState) -> RayState:
    """The rays, unmoved, in the frame after a coordinate break (``optics.coordinates``)."""
    p, d = transform(cb, z_vertex, st.p, st.d)
    return RayState(p, d, st.valid, st.opl)


def _travel_gaps(lens: Lens):
    """``gaps(key)``: ``thickness[key]`` (an index or a slice) along the direction of travel.

    After an odd number of mirrors light travels toward −z and a Zemax thickness is
    negative (unless coordinate breaks turn the frame round with the light:
    ``Lens.travel_senses``); the surface step needs the gap along the travel direction (a
    negative one means the next surface lies behind the rays). Without mirrors or turned
    frames this is the thickness slice itself, so such a lens is traced by the same
    operations.
    """
    t = lens.thickness
    if not lens.mirrors and lens.travel_senses is None:
        return lambda key: t[key]
    sign = jnp.asarray([float(s) for s in travel_senses(lens)[1:]], t.dtype)
    return lambda key: (t * sign)[key]


def _checked(lens: Lens, rays: Rays, where: str) -> Rays:
    """The rays with their wavelengths checked against the lens's materials (µm)."""
    wl = checks.wavelengths(lens, rays.wavelength, where, "rays.wavelength")
    return Rays(rays.origin, rays.direction, wl, rays.valid, rays.opl)


def check_upto(lens: Lens, rays: Rays, upto: int | None, newton_iters: int,
               where: str = "trace") -> None:
    """The arguments every trace shares, checked before tracing (a string for the lens was an
    AttributeError deep inside, ``upto=True`` traced to surface 1); ``where``: the function
    called (``trace_path``'s were refused as ``trace``'s)."""
    for arg, v, cls in (("lens", lens, Lens), ("rays", rays, Rays)):
        if not isinstance(v, cls):
            raise TypeError(f"{where}: {arg} must be a jaxlens.{cls.__name__}, got "
                            f"{type(v).__name__}")
    checks.number(newton_iters, "newton_iters", where, lo=0, integer=True, unit="iterations")
    checks.newton_iters(newton_iters, where)
    if upto is not None and (isinstance(upto, bool) or not isinstance(upto, (int, np.integer))
                             or not 0 <= upto < lens.num_surfaces):
        raise ValueError(f"{where}: upto must be a surface index in [0, "
                         f"{lens.num_surfaces - 1}] (0-based), got {upto!r}")


def _check_switches(where: str, **switches) -> None:
    """``reverse_rule`` and ``uniform`` are static switches: a traced or non-boolean value is
    refused (``uniform="no"`` traced as True)."""
    for arg, v in switches.items():
        if not isinstance(v, (bool, np.bool_)):
            raise TypeError(f"{where}: {arg} must be True or False, got {v!r}")


def trace_path(
    lens: Lens,
    rays: Rays,
    *,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    upto: int | None = None,
    uniform: bool = False,
    reverse_rule: bool = False,
) -> Rays:
    """Trace rays and return them after every surface, stacked on a new leading axis.

    Args:
        lens: the lens.
        rays: rays in object space, ``[*batch]``.
        newton_iters: Newton iterations for surfaces with polynomial terms.
        upto: stop after ``surfaces[upto]`` (0-based); ``None`` traces to the image.
        uniform: trace every surface after the first as one kind (one ``lax.scan``:
            short compile times for many surfaces; see the module notes).
        reverse_rule: as in ``trace``.

    Returns:
        ``Rays`` of shape ``[m, *batch]``: after each surface (after refraction) and, last,
        on the image surface when ``upto`` is None (m = num_surfaces + 1), else
        m = upto + 1. ``path[i]`` is the rays after surface i; the wavelength is broadcast
        to the full shape. After a coordinate break each entry is in its surface's frame
        (``optics.coordinates.frame_of(lens, i)``); at a break the rays have not moved.
    """
    check_upto(lens, rays, upto, newton_iters, "trace_path")
    _check_switches("trace_path", reverse_rule=reverse_rule, uniform=uniform)
    rays = _checked(lens, rays, "trace_path")
    states = _trace_states(lens, rays, newton_iters, upto, keep_path=True, uniform=uniform,
                           reverse_rule=reverse_rule)
    stacked = jax.tree.map(lambda *x: jnp.stack(x), *states)
    wl = jnp.broadcast_to(rays.wavelength, (len(states),) + rays.shape)
    return rays_from_state(stacked, wl)


# Rays per chunk for large batches on a CPU. One chunk's working set (the state and the
# temporaries of a surface, ~10 arrays) then stays in the CPU caches, which doubles forward
# throughput at 1e6 rays, and a gradient holds one chunk's intermediates at a time
# (benchmarks/SPEED.md). Small batches are traced in one piece.
CHUNK = 2**16
# On a GPU the chunks run one after another and each fills only a part of the device: on an
# H100, 1e6 rays through the Cooke triplet took 1.5-2.3 ms forward and 10.6-12.1 ms forward +
# gradient in chunks of 2**16, and 0.6-0.8 ms and 2.2 ms in one piece (SPEED.md). Chunks of
# 2**20 bound the gradient's memory for larger batches.
CHUNK_ACCELERATOR = 2**20


def default_chunk() -> int:
    """Rays per chunk that ``trace(chunk="auto")`` uses: ``CHUNK`` when JAX's default backend
    is the CPU, ``CHUNK_ACCELERATOR`` on a GPU or TPU."""
    return CHUNK if jax.default_backend() == "cpu" else CHUNK_ACCELERATOR


def _chunking(n: int, chunk: int, lanes: int = 16) -> tuple[int, int]:
    """(number of chunks, rays per chunk) for n rays and chunks of at most ``chunk``.

    Chunks of equal size that is a multiple of ``lanes`` (the float32 SIMD width of
    AVX-512) run fastest (an odd size measured 2-4x slower), so the count is raised until
    one divides n that way, up to twice the minimum; otherwise the last chunk is padded.
    """
    m0 = -(-n // chunk)
    for m in range(m0, 2 * m0 + 1):
        if n % (m * lanes) == 0:
            return m, n // m
    size = -(-n // m0)
    return m0, -(-size // lanes) * lanes


@checks.checked_core(eqx.filter_jit, concrete_checked=False)
def trace(
    lens: Lens,
    rays: Rays,
    *,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    chunk: int | Literal["auto"] | None = "auto",
    upto: int | None = None,
    uniform: bool = False,
    reverse_rule: bool = False,
) -> Rays:
    """Trace rays from object space to the image surface (or to ``surfaces[upto]``).

    Pure, jittable, vmappable and differentiable. The result follows the dtype of
    ``rays`` (the lens is cast to it).

    Args:
        lens: the lens.
        rays: rays in object space (global coordinates, surface 1 vertex at z = 0).
        newton_iters: Newton iterations for aspheric and hybrid surfaces.
        chunk: a batch ``[N, 3]`` with N above this is traced ``chunk`` rays at a time
            (``jax.lax.map``; the gradient recomputes each chunk instead of storing it).
            ``"auto"``: ``default_chunk()``, 2**16 on a CPU and 2**20 on a GPU.
            ``None`` traces every batch in one piece. Results agree to a few ulps.
        upto: stop after ``surfaces[upto]`` (0-based); ``None`` traces to the image.
        uniform: trace every surface after the first as one kind (one ``lax.scan``;
            see the module notes). Results agree to rounding.
        reverse_rule: (static) differentiate plane, sphere and conic surfaces and those with
            polynomial terms (``surface_adjoint.SAG_KINDS``; not mirrors, nor with
            obscurations or apertures) with a hand-written reverse rule
            (``surface_adjoint``): identical values, the same gradients to rounding, a faster
            ``grad``; but ``jax.jvp``/``jax.jacfwd`` through such a trace raise a TypeError
            (a ``custom_vjp`` has no forward mode). Other surfaces take ``surface_step``.

    Returns:
        The rays on the image surface (or after ``surfaces[upto]``): intercepts in
        ``origin``, direction cosines after the last surface in ``direction``, ``valid``
        and ``opl``.

    Example:
        >>> import jaxlens, jax.numpy as jnp
        >>> lens = jaxlens.Lens(surfaces=(jaxlens.Sphere(0.02), jaxlens.Sphere(-0.02)),
        ...     thickness=jnp.array([5.0, 45.0]),
        ...     materials=(jaxlens.ModelGlass(1.5168, 64.17), jaxlens.Air()))
        >>> rays = jaxlens.Rays(jnp.array([[0.0, 1.0, -1.0]]), jnp.array([[0.0, 0.0, 1.0]]), 0.5876)
        >>> bool(jaxlens.trace(lens, rays).valid[0])
        True
    """

    check_upto(lens, rays, upto, newton_iters)
    _check_switches("trace", reverse_rule=reverse_rule, uniform=uniform)
    if isinstance(chunk, str) and chunk == "auto":
        chunk = default_chunk()
    if chunk is not None:
        chunk = checks.number(chunk, "chunk", "trace", lo=1, integer=True,
                              unit='rays ("auto": by backend; None: one piece)')

    def whole(r: Rays, prepared=None) -> Rays:
        states = _trace_states(lens, r, newton_iters, upto, keep_path=False, uniform=uniform,
                               prepared=prepared, reverse_rule=reverse_rule)
        return rays_from_state(states[-1], r.wavelength)

    rays = _checked(lens, rays, "trace")
    n = rays.origin.shape[0]
    if chunk is None or rays.origin.ndim != 2 or n <= chunk:
        return whole(rays)
    per_ray = jnp.ndim(rays.wavelength) == 1
    m, size = _chunking(n, chunk)

    def split(x):  # [N, ...] -> [m, size, ...], padded with copies of the last ray
        if m * size != n:
            x = jnp.pad(x, [(0, m * size - n)] + [(0, 0)] * (x.ndim - 1), mode="edge")
        return x.reshape(m, size, *x.shape[1:])

    leaves = (rays.origin, rays.direction, rays.valid, rays.opl)
    leaves = leaves + ((rays.wavelength,) if per_ray else ())
    # Lens data shared by all chunks is computed once (with per-ray wavelengths the indices
    # are per ray and are computed in each chunk).
    prepared = None if per_ray else _prepare(lens, rays, uniform)

    @jax.checkpoint
    def one(xs):
        o, d, v, opl = xs[:4]
        w = xs[4] if per_ray else rays.wavelength
        return whole(Rays(o, d, w, v, opl), prepared)

    out = jax.lax.map(one, tuple(split(x) for x in leaves))
    join = lambda x: x.reshape(m * size, *x.shape[2:])[:n]  # noqa: E731
    return Rays(
        join(out.origin), join(out.direction), rays.wavelength, join(out.valid), join(out.opl)
    )
