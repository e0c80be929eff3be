"""Whether a lens is rotationally symmetric about its axis (z), from its static structure.

Such a lens takes an on-axis object point to an on-axis image point, and its chief ray of
field 0 is the axis itself: callers use this to skip a solve whose answer symmetry gives
(the ``.zmx`` reader's real-image-height fields of 0 mm).
"""

from __future__ import annotations

import numpy as np

from . import checks
from .diffractive import Binary2
from .lens import Lens
from .paraxial_surface import ParaxialSurface
from .qtype import QTypeAsphere
from .surfaces import AbstractSurface, EvenAsphere, Hybrid, OddAsphere, Standard

ROTATIONAL_KINDS = (Standard, EvenAsphere, OddAsphere, QTypeAsphere, Binary2, ParaxialSurface)
"""Surface kinds whose sag (and, for ``Binary2``, phase; for ``ParaxialSurface``, power)
depends on the radius r alone. A ``Hybrid`` is one of them only while its odd x³, y³, …
terms are all zero; toroids, biconics, XY polynomials, Zernike sags, gratings, tilted planes
and coordinate breaks never are (even where their values happen to make them round: the
check reads the kind, not the numbers)."""


def _round_surface(s: AbstractSurface) -> bool:
    if type(s) in ROTATIONAL_KINDS:
        return True
    if type(s) is Hybrid and not checks.is_traced((s.odd_x, s.odd_y)):
        return not (np.any(np.asarray(s.odd_x) != 0) or np.any(np.asarray(s.odd_y) != 0))
    return False


def rotationally_symmetric(lens: Lens) -> bool:
    """True when every surface, the image surface included, is of a ``ROTATIONAL_KINDS`` kind
    (or a ``Hybrid`` with zero odd terms) and every aperture is a centred circle: then the
    lens, its clipping included, is symmetric about the z axis. False otherwise (a coordinate
    break, a freeform, a decentered or non-circular aperture), and for traced odd terms."""
    if not all(_round_surface(s) for s in (*lens.surfaces, lens.image)):
        return False
    return all(a.shape == "circle" and a.decenter_x == 0 and a.decenter_y == 0
               for _, a in lens.apertures)
