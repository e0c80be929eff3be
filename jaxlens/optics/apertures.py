"""Surface apertures of any shape: circles, ellipses and rectangles, decentered or not.

An ``Aperture`` is static structure (a frozen, hashable dataclass of plain floats), held by
``Lens.apertures`` as ``(i, aperture)`` pairs. Lengths are in mm in the surface's local
frame (x, y measured from its vertex). A clipping aperture (``blocks=False``) passes the
rays that meet the surface inside it; an obscuration (``blocks=True``) blocks them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax.numpy as jnp

from . import checks

SHAPES = ("circle", "ellipse", "rect")


@dataclass(frozen=True)
class Aperture:
    """A surface aperture or obscuration (Zemax CLAP/ELAP/SQAP, OBSC/ELOB/SQOB, with OBDC).

    Args:
        shape: ``"circle"`` (``half_x == half_y``, the radius), ``"ellipse"`` (semi-axes) or
            ``"rect"`` (half-widths).
        half_x, half_y: half-widths along x and y, mm, finite and > 0.
        decenter_x, decenter_y: the aperture's centre in the surface's frame, mm.
        blocks: ``False`` clips (rays inside pass), ``True`` obscures (rays inside stop).
    """

    shape: str
    half_x: float
    half_y: float
    decenter_x: float = 0.0
    decenter_y: float = 0.0
    blocks: bool = False

    def __post_init__(self):
        if self.shape not in SHAPES:
            raise ValueError(f"Aperture: shape must be one of {SHAPES}, got {self.shape!r}")
        for arg, lo in (("half_x", 0.0), ("half_y", 0.0), ("decenter_x", None),
                        ("decenter_y", None)):
            v = getattr(self, arg)
            try:
                f = float(v)
            except (TypeError, ValueError):
                f = math.nan
            # A string was read as its number ('2' as 2 mm), where every surface refuses it.
            if isinstance(v, bool | str | bytes) or not math.isfinite(f) or (
                    lo is not None and not f > lo):
                rng = "a finite number > 0" if lo is not None else "a finite number"
                raise ValueError(f"Aperture: {arg} must be {rng} (mm), got {v!r}")
            object.__setattr__(self, arg, f)
        checks.switch(self.blocks, "blocks", "Aperture")
        if self.shape == "circle" and self.half_x != self.half_y:
            raise ValueError(f"Aperture: a circle has half_x == half_y (its radius, mm), got "
                             f"{self.half_x} and {self.half_y}; use shape='ellipse'")

    @classmethod
    def circle(cls, radius: float, decenter_x: float = 0.0, decenter_y: float = 0.0,
               blocks: bool = False) -> Aperture:
        return cls("circle", radius, radius, decenter_x, decenter_y, blocks)

    @property
    def decentered(self) -> bool:
        return self.decenter_x != 0.0 or self.decenter_y != 0.0

    def inside(self, x, y):
        """Whether points (x, y) of the surface frame lie inside (a ray on the rim is inside
        despite rounding, with the tolerance of the semi-diameter test)."""
        eps = 64 * jnp.finfo(jnp.result_type(x, y, float)).eps
        u, v = x - self.decenter_x, y - self.decenter_y
        if self.shape == "rect":
            lim = 1 + 0.5 * eps
            return (jnp.abs(u) <= self.half_x * lim) & (jnp.abs(v) <= self.half_y * lim)
        u, v = u / self.half_x, v / self.half_y
        return u * u + v * v <= 1 + eps

    def passes(self, x, y):
        """Whether rays meeting the surface at (x, y) get through this aperture."""
        inside = self.inside(x, y)
        return ~inside if self.blocks else inside


def passes_all(apertures, x, y, ok):
    """``ok`` and-ed with every aperture's pass test (``apertures`` static)."""
    for a in apertures:
        ok = ok & a.passes(x, y)
    return ok
