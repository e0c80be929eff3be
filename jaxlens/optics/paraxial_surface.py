"""The paraxial surface (Zemax ``PARAXIAL``): an ideal thin lens of focal length f on a plane.

Conventions:
    Lengths in mm; the surface is the plane z = 0 of its local frame. A ray arriving at
    (x, y) with direction cosines (L, M, N) in a medium of index n leaves into the medium of
    index n′ with the slopes (tangents) u = L/N, v = M/N changed by

        n′·u′ = n·u − x/f,        n′·v′ = n·v − y/f,

    which is the paraxial refraction equation n′u′ = nu − yΦ with power Φ = 1/f, applied
    exactly to the slopes of every real ray (the Zemax manual gives the same equations).
    It is a perfect lens for every pair of conjugates: the outgoing height after a distance
    z is linear in the incoming ray, so all rays from one object point meet in one image
    point. A collimated beam at slopes (u, v) meets at (n·f·u, n·f·v, n′·f) — in air at
    f·tanθ, a distance f behind the lens. The paraxial power is 1/f (EFL f in air).

    Optical path: the surface adds the path of a perfect lens at infinite conjugates for the
    ray's own incident direction d̂: with P′ = (n f u, n f v, n′ f) the focus of the
    collimated beam the ray belongs to, and Q the point of incidence,

        φ(Q) = sgn(f)·n′·(|P′| − |P′ − Q|) − n·d̂·Q,

    zero at the vertex, so every ray of a collimated beam has the same optical path to P′
    (zero OPD). This is Zemax's OPD mode 2 ("infinite conjugates"). It is also what
    integrating the surface's phase along the surface gives for a collimated beam
    (mode 1) and what the conjugate-based modes 0 and 3 give when the beam reaching the
    surface is collimated; for a finite conjugate those modes differ, and the ``.zmx``
    reader refuses them there (``jaxlens.io.zmx_read``). The rays do not depend on the mode.
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, Float

from . import checks
from .reciprocal import reciprocal_length
from .surfaces import AbstractSurface, number_field


class ParaxialSurface(AbstractSurface):
    """An ideal thin lens of focal length ``focal_length`` (mm) on a plane (Zemax PARAXIAL).

    The sag is that of a plane (c = k = 0); the ray bending and optical path are in
    ``jaxlens.tracing.step.paraxial_bend`` (see the module docstring).

    Args:
        focal_length: f in mm, nonzero; negative for a diverging lens (Zemax PARM 1).
        semi_diameter: clear-aperture radius (mm), ``inf`` for none.
    """

    # c and k are fixed (a plane), not fields: declared ClassVar so that the dataclass drops
    # the base class's fields of those names (its AbstractVar annotations are strings under
    # ``from __future__ import annotations``, which equinox then takes for fields).
    c: ClassVar[property]
    k: ClassVar[property]
    focal_length: Float[Array, ""] = number_field("focal_length", default=100.0)
    semi_diameter: Float[Array, ""] = number_field(
        "semi_diameter", default_factory=lambda: jnp.asarray(jnp.inf))

    def __check_init__(self):
        f = self.focal_length
        if not checks.is_traced(f):  # 5e-324 mm: a power of inf, read as an afocal lens
            reciprocal_length(f, "focal_length", "ParaxialSurface")

    @property
    def c(self) -> Array:
        return jnp.zeros_like(self.focal_length)

    @property
    def k(self) -> Array:
        return jnp.zeros_like(self.focal_length)

    @property
    def has_polynomial(self) -> bool:
        return False

    @property
    def power(self) -> Array:
        """Φ = 1/f (1/mm), whatever the media on either side."""
        return 1.0 / self.focal_length
