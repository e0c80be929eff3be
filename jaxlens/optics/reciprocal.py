"""Lengths the optics uses through their reciprocals: a radius of curvature (c = 1/R) and a
focal length (power 1/f).

A test for zero alone (``R == 0``, ``f != 0``) let through the lengths whose reciprocals are
not numbers of a lens: 1e-300 mm gave a power of 1e300 per mm, and a subnormal 5e-324 mm
an infinite one (1/5e-324 overflows), which the paraxial trace then read as an afocal lens
(efl +inf) without a word. A length is refused below ``MIN_LENGTH_MM`` in size, the
smallest entrance pupil a lens file may give (``io.lensfile.MIN_EPD_MM``): no surface
of a lens bends light over a nanometre. −0.0 and NaN are refused with it.
"""

from __future__ import annotations

import numpy as np

MIN_LENGTH_MM = 1e-9
"""Smallest size (mm) of a radius of curvature or a focal length."""


def reciprocal_length(value, arg: str, where: str, *, unit: str = "mm") -> None:
    """Refuse a concrete radius or focal length (any shape, in ``unit``, mm unless a lens
    file's unit says otherwise) that is not finite or whose size is below
    ``MIN_LENGTH_MM``: a ``ValueError`` naming ``where``, ``arg`` and the range."""
    a = np.asarray(value, dtype=float)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(a) | (np.abs(a) < MIN_LENGTH_MM)
    if np.any(bad):
        v = a[bad].reshape(-1)[0] if a.ndim else float(a)
        head = f"{where}: " if where else ""
        raise ValueError(f"{head}{arg} must be finite and at least {MIN_LENGTH_MM:g} mm in "
                         f"size (its reciprocal, a curvature or power, is what the optics "
                         f"uses), got {v!r} {unit}")
