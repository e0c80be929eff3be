"""Coordinate breaks: decenters and tilts between surfaces (Zemax ``COORDBRK``).

A ``CoordinateBreak`` is a dummy surface in ``Lens.surfaces``: it neither refracts nor clips,
and its only effect is to give the surfaces after it a new local frame.

Conventions (Zemax's):
    Decenters in mm along the current x and y axes; tilts in degrees about the x, y and z
    axes, right-handed: the coordinate axes turn counterclockwise looking from the +axis
    toward the origin. ``order = 0`` decenters first, then tilts about x, then about the
    new y, then about the new z, so the new axes are the columns of
    R = Rx(tilt_x)·Ry(tilt_y)·Rz(tilt_z). ``order = 1`` tilts first, about z, then the new y,
    then the new x (R = Rz·Ry·Rx), and then decenters along the tilted axes. A break with
    ``order`` toggled and every parameter negated undoes a break. With these signs a tilt
    of +45° about x turns the new +z axis toward −y, so a fold mirror between two such
    breaks sends light travelling toward +z off toward +y.

Frames in the tracer:
    Rays are carried in the frame of the last coordinate break before them, shifted along
    its z axis so that every vertex keeps the z of ``Lens.vertex_z`` (without breaks this
    is the global frame). The image intercepts that ``trace`` returns are in the image
    surface's frame; ``frame_of`` gives that frame in global coordinates. A break moves no
    ray: the rays stay where the previous surface left them, expressed in the new frame.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .surfaces import AbstractSurface, number_field


class CoordinateBreak(AbstractSurface):
    """A new local frame for the surfaces that follow (Zemax ``COORDBRK``, PARM 1..6).

    Args:
        decenter_x, decenter_y: decenters in mm (PARM 1, 2).
        tilt_x, tilt_y, tilt_z: tilts in degrees, right-handed (PARM 3, 4, 5).
        order: 0 decenter then tilt x, y, z; 1 tilt z, y, x then decenter (PARM 6). Static.

    ``c`` and ``k`` are always 0 and ``semi_diameter`` is inf: code that reads any surface's
    curvature or aperture sees a flat dummy surface. The medium after a break is the medium
    before it (``Lens`` checks this).
    """

    c: Float[Array, ""] = number_field("c", default=0.0)
    k: Float[Array, ""] = number_field("k", default=0.0)
    decenter_x: Float[Array, ""] = number_field("decenter_x", default=0.0)
    decenter_y: Float[Array, ""] = number_field("decenter_y", default=0.0)
    tilt_x: Float[Array, ""] = number_field("tilt_x", default=0.0)
    tilt_y: Float[Array, ""] = number_field("tilt_y", default=0.0)
    tilt_z: Float[Array, ""] = number_field("tilt_z", default=0.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))
    order: int = eqx.field(static=True, default=0)

    def __check_init__(self):
        if self.order not in (0, 1) or isinstance(self.order, bool):
            raise ValueError(f"CoordinateBreak: order must be 0 (decenter, then tilt) or 1 "
                             f"(tilt, then decenter), got {self.order!r}")
        for name in ("c", "k"):
            v = getattr(self, name)
            if not checks.is_traced(v) and np.any(np.asarray(v) != 0):
                raise ValueError(f"CoordinateBreak: {name} must be 0 (a coordinate break has "
                                 f"no shape), got {np.asarray(v)!r}")
        for name in ("decenter_x", "decenter_y", "tilt_x", "tilt_y", "tilt_z"):
            v = getattr(self, name)
            if not checks.is_traced(v):
                unit = "mm" if name.startswith("decenter") else "degrees"
                checks.number(v, name, "CoordinateBreak", unit=unit)

    def rotation(self) -> tuple:
        """R as a row-major 3×3 tuple of tuples: the new axes are its columns."""
        rx, ry, rz = (_rot(a, axis) for a, axis in
                      ((self.tilt_x, 0), (self.tilt_y, 1), (self.tilt_z, 2)))
        return _matmul(_matmul(rx, ry), rz) if self.order == 0 else _matmul(_matmul(rz, ry), rx)


def _rot(deg, axis: int):
    """Right-handed rotation by ``deg`` degrees about coordinate axis ``axis``."""
    a = jnp.deg2rad(deg)
    c, s = jnp.cos(a), jnp.sin(a)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    if axis == 0:
        return ((one, zero, zero), (zero, c, -s), (zero, s, c))
    if axis == 1:
        return ((c, zero, s), (zero, one, zero), (-s, zero, c))
    return ((c, -s, zero), (s, c, zero), (zero, zero, one))


def _matmul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3))
                 for i in range(3))


def transform(cb: CoordinateBreak, z_vertex, p, d):
    """Points ``p`` and directions ``d`` ((x, y, z) tuples) in the frame after the break.

    ``z_vertex`` is the break's vertex z in the current (z-shifted) frame; it keeps that z in
    the new frame (see the module notes). Returns (p', d').
    """
    r = cb.rotation()
    dx, dy = cb.decenter_x, cb.decenter_y
    q = (p[0], p[1], p[2] - z_vertex)
    if cb.order == 0:
        q = (q[0] - dx, q[1] - dy, q[2])

    def inv(v):  # Rᵀ v
        return tuple(r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2] for j in range(3))

    q, d = inv(q), inv(d)
    if cb.order == 1:
        q = (q[0] - dx, q[1] - dy, q[2])
    return (q[0], q[1], q[2] + z_vertex), d


def frame_of(lens, index: int | None = None):
    """The frame that ``trace`` reports rays in after ``lens.surfaces[index]`` (``None``:
    the image surface), in global coordinates.

    ``index`` is 0-based, in [0, num_surfaces − 1] as ``trace``'s ``upto``; a negative index
    is refused (−1 gave the frame before surface 1, not after the last surface, and the
    image surface is ``None``), and so is anything but a whole number (``2.0``, a bool).

    Returns:
        (R, t): a ``[3, 3]`` rotation and a ``[3]`` offset such that a point ``p`` reported by
        the tracer is ``R @ p + t`` in global coordinates (surface 1's frame) and a direction
        ``d`` is ``R @ d``. The identity and zero without coordinate breaks.
    """
    last = lens.num_surfaces - 1
    if index is not None and (isinstance(index, bool) or not isinstance(index, (int, np.integer))
                              or not 0 <= index <= last):
        raise ValueError(f"frame_of: index must be a surface index in [0, {last}] (0-based; "
                         f"None for the image surface), got {type(index).__name__} {index!r}")
    n = lens.num_surfaces if index is None else int(index) + 1
    zs = lens.vertex_z()
    dtype = jnp.result_type(lens.thickness)
    rot = jnp.eye(3, dtype=dtype)
    off = jnp.zeros(3, dtype)
    for i in range(n):
        s = lens.surfaces[i]
        if not isinstance(s, CoordinateBreak):
            continue
        # Tracer frame after the break: p_new = Rᵀ(p_old − v) + (0, 0, z) with v the break's
        # vertex (plus the decenter), so p_old = R p_new + v − R (0, 0, z).
        r = jnp.stack([jnp.stack(row) for row in s.rotation()]).astype(dtype)
        ez = jnp.asarray([0.0, 0.0, 1.0], dtype) * zs[i]
        dec = jnp.stack([s.decenter_x, s.decenter_y, jnp.zeros_like(s.decenter_x)]).astype(dtype)
        v = ez + (dec if s.order == 0 else r @ dec)
        # Compose with the frame so far: global = rot @ p_old + off.
        off = rot @ (v - r @ ez) + off
        rot = rot @ r
    return rot, off


AXIS_ACROSS_TOL = 1e-9
"""|cos| of the axis ray's angle to a frame's z axis below which it travels across the axis."""


def _tilted(lens) -> list[CoordinateBreak]:
    return [s for s in lens.surfaces if isinstance(s, CoordinateBreak)
            and any(checks.is_traced(a) or float(a) != 0.0
                    for a in (s.tilt_x, s.tilt_y, s.tilt_z))]


def travel_senses(lens):
    """The direction of travel along the local z axis in each medium: +1 toward +z, −1
    toward −z; object space first, then the medium after each surface (``num_surfaces + 1``
    entries, as ``Lens.indices``).

    The light is followed along the axis ray: down the object's axis, reflected about each
    mirror's vertex normal (its frame's z), each medium's sense taken in the frame its
    thickness is measured in (the surface's; a break's after its rotation). Without tilted
    breaks this is Zemax's rule, −1 after an odd number of mirrors (the negative thicknesses
    after a mirror). A break may also turn the frame past 90°: a fold written as a −45°
    break, the mirror and a +135° break, with positive thicknesses after it (as Quadoa's
    export writes a prism), travels toward +z after its mirror.

    Returns a tuple of Python ints where every tilt is concrete, or where the lens has no
    mirror (a traced tilt of a lens without mirrors is taken as a small one, as the
    tolerancing's breaks are); a ``[num_surfaces + 1]`` array of ±1 where a lens with mirrors
    has traced tilts. Raises ``ValueError`` naming the surface (0-based) where the axis ray
    travels across its frame's z axis (no paraxial trace along that frame exists).
    """
    tilted = _tilted(lens)
    traced = any(checks.is_traced(a) for s in tilted for a in (s.tilt_x, s.tilt_y, s.tilt_z))
    if not tilted or (traced and not lens.mirrors):
        return _parity(lens)
    if traced:
        cos = _follow_axis(lens, traced=True)[0]
        return jnp.stack([jnp.ones_like(cos[1]), *(jnp.sign(c) for c in cos[1:])])
    cos = axis_cosines(lens)
    for i, c in enumerate(cos[1:]):
        if abs(c) <= AXIS_ACROSS_TOL:
            raise ValueError(f"the axis ray travels across surface {i}'s local z axis (a "
                             f"coordinate break before it turns the frame by 90 degrees to "
                             f"the light), so no paraxial trace follows that frame")
    return tuple(1 if c > 0 else -1 for c in cos)


def axis_cosines(lens) -> list[float]:
    """cos of the angle between the axis ray and the local z axis in each medium (object
    space first, as ``travel_senses``), for concrete tilts; 1 without tilted breaks."""
    return [float(c) for c in _follow_axis(lens, traced=False)[0]]


def _parity(lens) -> tuple[int, ...]:
    flips = [sum(1 for m in lens.mirrors if m < i) % 2 for i in range(lens.num_surfaces + 1)]
    return tuple(-1 if f else 1 for f in flips)


def axial_thicknesses(lens):
    """The thicknesses a paraxial trace transfers by.

    ``lens.thickness`` wherever the light travels along each frame as the mirror count says
    (Zemax's rule: ``travel_senses`` is −1 after an odd number of mirrors): the trace then
    follows each surface's local axis, as Zemax's does, tilts and decenters ignored. Where a
    break turns a frame round with the light instead (Quadoa's fold: −45°, the mirror with
    its thickness along its own 45° axis, +135° with a decenter), local axes no longer make
    a path: each gap is then the axis ray's advance from one vertex to the next (the step
    projected on the ray's direction), signed as its medium's ``travel_senses``. Quadoa's
    mirror gap of −7.07 mm along the mirror's axis and the decenter after it make the
    prism's 10 mm path."""
    senses = travel_senses(lens)
    parity = _parity(lens)
    if isinstance(senses, tuple) and senses == parity:
        return lens.thickness
    traced = not isinstance(senses, tuple)
    _, advance = _follow_axis(lens, traced=traced)
    if not traced:
        return jnp.asarray([a * sg for a, sg in zip(advance, senses[1:], strict=True)],
                           jnp.result_type(lens.thickness))
    axial = (jnp.stack(advance) * senses[1:]).astype(lens.thickness.dtype)
    zemax_rule = jnp.all(senses == jnp.asarray(parity, senses.dtype))
    return jnp.where(zemax_rule, lens.thickness, axial)


def _follow_axis(lens, *, traced: bool):
    """(cosines, advances) of the axis ray: cos to each medium's local z (object space first)
    and each gap's vertex-to-vertex step projected on the ray's direction (mm)."""
    if traced:
        xp, val = jnp, (lambda v: v)
    else:
        xp, val = np, float
    t = [val(v) for v in lens.thickness]
    zs = [xp.asarray(0.0)]
    for v in t:
        zs.append(zs[-1] + v)
    rot, off = xp.eye(3), xp.zeros(3)
    d = xp.asarray([0.0, 0.0, 1.0])
    cos, dirs, pos = [xp.asarray(1.0)], [], []
    for i, s in enumerate(lens.surfaces):
        ez = xp.stack([xp.asarray(0.0), xp.asarray(0.0), xp.asarray(zs[i])])
        pos.append(rot @ ez + off)
        if isinstance(s, CoordinateBreak):
            r = xp.stack([xp.stack([xp.asarray(val(v)) for v in row]) for row in s.rotation()])
            dec = xp.stack([xp.asarray(val(s.decenter_x)), xp.asarray(val(s.decenter_y)),
                            xp.asarray(0.0)])
            v = ez + (dec if s.order == 0 else r @ dec)
            off = rot @ (v - r @ ez) + off
            rot = rot @ r
        z = rot[:, 2]
        if i in lens.mirrors:
            d = d - 2.0 * (d @ z) * z
        cos.append(d @ z)
        dirs.append(d)
    pos.append(rot @ xp.stack([xp.asarray(0.0), xp.asarray(0.0), xp.asarray(zs[-1])]) + off)
    advance = [(pos[j + 1] - pos[j]) @ dirs[j] for j in range(len(dirs))]
    return cos, advance
