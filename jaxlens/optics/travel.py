"""Which way light travels along each medium's local z axis, and the paraxial path of a fold.

Zemax's rule: light travels toward +z in object space and turns round at each mirror, so
after an odd number of mirrors it travels toward −z and the thicknesses are negative
(``mirror_count_senses``). A coordinate break can also turn a frame round with the light:
Quadoa's export writes a prism's fold as a −45° break, the mirror with its thickness along
its own 45° axis, a +135° break with a decenter, and positive thicknesses after it, so the
light travels toward +z after one mirror. Such a lens carries its senses in the static
``Lens.travel_senses`` (the readers set it from the frames: ``turned_senses``; ``Lens``
checks it against the frames whenever the tilts are concrete). The tracer's gaps, the
paraxial indices' signs and the afocal image axis follow ``travel_senses``; the paraxial
trace of such a lens transfers by the axis ray's path from vertex to vertex
(``axial_thicknesses``). A lens whose frames follow the mirror count, the usual case, has
``travel_senses = None`` and is traced by the same operations as before this existed.

Senses list object space first, then the medium after each surface (``num_surfaces + 1``
entries, as ``Lens.indices``).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from . import checks
from .coordinates import CoordinateBreak, frames_after

AXIS_ACROSS_TOL = 1e-9
"""|cos| of the axis ray's angle to a frame's z axis below which it travels across it."""


def _check_mirrors(num_surfaces, mirrors, where: str) -> None:
    if isinstance(num_surfaces, bool) or not isinstance(num_surfaces, (int, np.integer)) \
            or num_surfaces < 1:
        raise ValueError(f"{where}: the number of surfaces must be a whole number >= 1, got "
                         f"{num_surfaces!r}")
    if isinstance(mirrors, (str, bytes)) or not hasattr(mirrors, "__iter__") or any(
            isinstance(m, bool) or not isinstance(m, (int, np.integer))
            or not 0 <= m < num_surfaces for m in mirrors):
        raise ValueError(f"{where}: mirrors must be surface indices in [0, {num_surfaces - 1}] "
                         f"(0-based), got {mirrors!r}")


def mirror_count_senses(num_surfaces: int, mirrors) -> tuple[int, ...]:
    """Zemax's rule: +1 (toward +z) in object space, −1 after an odd number of mirrors."""
    _check_mirrors(num_surfaces, mirrors, "mirror_count_senses")
    return tuple(-1 if sum(1 for m in mirrors if m < i) % 2 else 1
                 for i in range(num_surfaces + 1))


def axis_cosines(surfaces, mirrors) -> list[float] | None:
    """cos of the angle between the axis ray and each medium's local z axis, object space
    first; ``None`` where a coordinate break's tilt is traced.

    The axis ray runs down the object's axis and reflects about each mirror's vertex normal
    (its frame's z); each medium's cosine is taken in the frame its thickness is measured in
    (the surface's; a break's after its rotation)."""
    if isinstance(surfaces, (str, bytes)) or not hasattr(surfaces, "__len__"):
        raise TypeError(f"axis_cosines: surfaces must be a sequence of surfaces (a Lens's "
                        f"surfaces), got {type(surfaces).__name__}")
    _check_mirrors(len(surfaces), mirrors, "axis_cosines")
    rot = np.eye(3)
    d = np.array([0.0, 0.0, 1.0])
    cos = [1.0]
    for i, s in enumerate(surfaces):
        if isinstance(s, CoordinateBreak):
            if checks.is_traced((s.tilt_x, s.tilt_y, s.tilt_z)):
                return None
            rot = rot @ np.asarray(s.rotation(np), np.float64)
        z = rot[:, 2]
        if i in mirrors:
            d = d - 2.0 * (d @ z) * z
        cos.append(float(d @ z))
    return cos


def frame_senses(surfaces, mirrors) -> tuple[int, ...] | None:
    """Each medium's direction of travel along its local z (±1) from the frames; ``None``
    where a tilt is traced. Raises ``ValueError`` naming the surface (0-based) after which
    the axis ray travels across its frame's z axis (no paraxial trace follows that frame)."""
    cos = axis_cosines(surfaces, mirrors)
    if cos is None:
        return None
    for i, c in enumerate(cos[1:]):
        if abs(c) <= AXIS_ACROSS_TOL:
            raise ValueError(
                f"the axis ray travels across the local z axis after surface {i} (0-based): a "
                f"coordinate break turns the frame by 90 degrees to the light, so EFL, image "
                f"heights and F/# have no paraxial axis to follow (turn the frame with the "
                f"light: for a 45-degree fold, a 45-degree break on each side of the mirror)")
    return tuple(1 if c > 0 else -1 for c in cos)


def turned_senses(surfaces, mirrors) -> tuple[int, ...] | None:
    """The ``Lens.travel_senses`` that a lens of these surfaces and mirrors needs: ``None``
    where its frames follow the mirror count (or a tilt is traced), else ``frame_senses``."""
    senses = frame_senses(surfaces, mirrors)
    if senses is None or senses == mirror_count_senses(len(surfaces), mirrors):
        return None
    return senses


def travel_senses(lens) -> tuple[int, ...]:
    """``lens.travel_senses`` where set, else Zemax's rule (``mirror_count_senses``)."""
    if lens.travel_senses is not None:
        return lens.travel_senses
    return mirror_count_senses(lens.num_surfaces, lens.mirrors)


def axial_thicknesses(lens):
    """The thicknesses the paraxial trace transfers by (mm, signed as ``travel_senses``).

    ``lens.thickness`` where the frames follow the mirror count: the trace follows each
    surface's local axis, as Zemax's does, tilts and decenters ignored. A lens with
    ``travel_senses`` turns frames round with the light, so local axes no longer make a
    path: each gap is the axis ray's advance from one vertex to the next (the step
    projected on the ray's direction). Quadoa's mirror gap of −7.07 mm along the mirror's
    axis and the decenter after it make a prism's 10 mm path."""
    if not hasattr(lens, "travel_senses"):
        raise TypeError(f"axial_thicknesses: expected a Lens, got {type(lens).__name__}")
    senses = lens.travel_senses
    if senses is None:
        return lens.thickness
    dtype = jnp.result_type(lens.thickness)
    zs = jnp.concatenate([lens.vertex_z(), lens.image_z()[None]])
    frames = frames_after(lens)
    d = jnp.asarray([0.0, 0.0, 1.0], dtype)
    pos, dirs = [], []
    for i in range(lens.num_surfaces + 1):
        rot, off = frames[i]  # the frame surface i's vertex is placed in
        pos.append(rot @ (jnp.asarray([0.0, 0.0, 1.0], dtype) * zs[i]) + off)
        if i in lens.mirrors:
            d = d - 2.0 * (d @ rot[:, 2]) * rot[:, 2]
        dirs.append(d)
    advance = jnp.stack([(pos[j + 1] - pos[j]) @ dirs[j] for j in range(lens.num_surfaces)])
    return advance * jnp.asarray(senses[1:], dtype)
