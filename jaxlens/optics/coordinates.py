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

import fractions
import math
import warnings

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
    order: int = eqx.field(static=True, default=0, converter=checks.static_int)

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
                if unit == "degrees":
                    _warn_if_radians(name, float(np.asarray(v)))
        sd = self.semi_diameter
        if not checks.is_traced(sd) and np.any(np.isfinite(np.asarray(sd))):
            raise ValueError(f"CoordinateBreak: a coordinate break clips no ray, so a "
                             f"semi_diameter of {np.asarray(sd)!r} mm would pass every ray "
                             f"unseen; leave it inf and put the aperture on the surface it "
                             f"belongs to")

    def rotation(self, xp=jnp) -> tuple:
        """R as a row-major 3×3 tuple of tuples: the new axes are its columns (``xp=np``:
        numpy floats of concrete tilts, computed outside any trace)."""
        rx, ry, rz = (_rot(a if xp is jnp else float(a), axis, xp) for a, axis in
                      ((self.tilt_x, 0), (self.tilt_y, 1), (self.tilt_z, 2)))
        return _matmul(_matmul(rx, ry), rz) if self.order == 0 else _matmul(_matmul(rz, ry), rx)


RADIAN_LOOKALIKE_TOL = 1e-4
"""A tilt (degrees) within this of a nonzero multiple of π/4 up to 2π (0.7854, 1.5708, 3.1416,
…) is warned about as a value given in radians."""


def _warn_if_radians(name: str, deg: float) -> None:
    """Warn when a tilt in degrees is a common angle written in radians (π/4 typed as
    0.7854 is a 0.79° tilt, not 45°): a fold that silently does not fold."""
    m = round(deg / (math.pi / 4))
    if 1 <= abs(m) <= 8 and abs(deg - m * math.pi / 4) < RADIAN_LOOKALIKE_TOL:
        q = fractions.Fraction(abs(m), 4)
        angle = ("-" if m < 0 else "") + (f"{q.numerator}" if q.numerator > 1 else "") + "π" + (
            f"/{q.denominator}" if q.denominator > 1 else "")
        warnings.warn(f"CoordinateBreak: {name} = {deg:g} degrees is {angle} in radians; "
                      f"tilts are in degrees ({m * 45} for {angle})", stacklevel=4)


def _rot(deg, axis: int, xp=jnp):
    """Right-handed rotation by ``deg`` degrees about coordinate axis ``axis``."""
    a = xp.deg2rad(deg)
    c, s = xp.cos(a), xp.sin(a)
    one, zero = xp.ones_like(c), xp.zeros_like(c)
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


def _check_lens(lens, where: str) -> None:
    # Duck-typed: the Lens module imports this one. A string was an AttributeError.
    if not (hasattr(lens, "num_surfaces") and hasattr(lens, "vertex_z")):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")


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
    _check_lens(lens, "frame_of")
    last = lens.num_surfaces - 1
    if index is not None and (isinstance(index, bool) or not isinstance(index, (int, np.integer))
                              or not 0 <= index <= last):
        raise ValueError(f"frame_of: index must be a surface index in [0, {last}] (0-based; "
                         f"None for the image surface), got {type(index).__name__} {index!r}")
    n = lens.num_surfaces if index is None else int(index) + 1
    return frames_after(lens, n)[-1]


def frames_after(lens, n: int | None = None) -> list:
    """``[(R, t)]``: the tracer's frame (as ``frame_of``) before surface 1, then after each
    of the first ``n`` surfaces (all of them by default)."""
    _check_lens(lens, "frames_after")
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer))
                          or not 0 <= n <= lens.num_surfaces):
        # -1 gave the frame before surface 1 alone, past the end an IndexError.
        raise ValueError(f"frames_after: n must be a surface count in [0, "
                         f"{lens.num_surfaces}] (None: all), got {type(n).__name__} {n!r}")
    n = lens.num_surfaces if n is None else int(n)
    zs = lens.vertex_z()
    dtype = jnp.result_type(lens.thickness)
    rot = jnp.eye(3, dtype=dtype)
    off = jnp.zeros(3, dtype)
    out = [(rot, off)]
    for i in range(n):
        s = lens.surfaces[i]
        if isinstance(s, CoordinateBreak):
            # Tracer frame after the break: p_new = Rᵀ(p_old − v) + (0, 0, z) with v the
            # break's vertex (plus the decenter), so p_old = R p_new + v − R (0, 0, z).
            r = jnp.stack([jnp.stack(row) for row in s.rotation()]).astype(dtype)
            ez = jnp.asarray([0.0, 0.0, 1.0], dtype) * zs[i]
            dec = jnp.stack([s.decenter_x, s.decenter_y,
                             jnp.zeros_like(s.decenter_x)]).astype(dtype)
            v = ez + (dec if s.order == 0 else r @ dec)
            # Compose with the frame so far: global = rot @ p_old + off.
            off = rot @ (v - r @ ez) + off
            rot = rot @ r
        out.append((rot, off))
    return out
