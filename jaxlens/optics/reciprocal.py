"""Lengths the optics divides by: a radius of curvature (c = 1/R), a focal length (power
1/f), a normalisation radius (the polynomial's coordinates r/R), a pupil diameter, a pixel
pitch.

A test for zero alone (``R == 0``, ``f != 0``, ``> 0``) let through lengths whose
reciprocals are not numbers of a lens: 1e-300 mm gave a power of 1e300 per mm, and a
subnormal 5e-324 mm an infinite one (1/5e-324 overflows; 5e-324² underflows to 0), which
the paraxial trace read as an afocal lens (efl +inf), and a freeform surface's sag turned
NaN (every ray lost, an RMS spot of NaN) without a word. A length is refused below
``MIN_LENGTH_MM`` in size, the smallest entrance pupil a lens file may give
(``io.lensfile.MIN_EPD_MM``): nothing in a lens is shaped or sampled below a nanometre.
"""

from __future__ import annotations

import numpy as np

MIN_LENGTH_MM = 1e-9
"""Smallest size (mm) of a length the optics divides by."""

RECIPROCAL = "its reciprocal, a curvature or power, is what the optics uses"
NORMALISING = "the surface's coordinates are divided by it"


def reciprocal_length(value, arg: str, where: str, *, why: str = RECIPROCAL) -> None:
    """Refuse a concrete length (mm, any shape) that is not finite or whose size is below
    ``MIN_LENGTH_MM``: a ``ValueError`` naming ``where`` (if any), ``arg``, the bound,
    ``why`` it is there and the first bad value."""
    a = np.asarray(value, dtype=float)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(a) | (np.abs(a) < MIN_LENGTH_MM)
    if np.any(bad):
        v = float(a[bad].reshape(-1)[0]) if a.ndim else float(a)
        head = f"{where}: " if where else ""
        raise ValueError(f"{head}{arg} must be finite and at least {MIN_LENGTH_MM:g} mm in "
                         f"size ({why}), got {v!r} mm")
