"""The one rule for a field whose beam puts no ray on the image surface (vignetted, or beyond
the lens's coverage: a 60° field on the Cooke triplet, a 95 mm object height on a small
telecentric doublet).

- The one-field analyses (``psf``, ``mtf``, ``wavefront``, ``encircled_energy``,
  ``radius_for_fraction``) have no answer for such a field: with concrete inputs they raise
  :class:`NoLightError` (a ``ValueError``) naming the analysis, the field and its unit
  (degrees, or mm for an object-space telecentric lens). Under ``jax.jit`` they return NaN
  (or raise from ``eqx.error_if`` where they check traced values).
- The many-field ``rms_spot`` is a batch API (the design loop's and the tolerance model's):
  a dark field keeps its documented NaN radius with ``valid_fraction`` 0, so the other
  fields' answers stay usable, and with concrete inputs a :class:`NoLightWarning` names the
  dark fields.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..optics import checks
from ..optics.lens import Lens


class NoLightError(ValueError):
    """An analysis of a field whose beam puts no ray on the image surface (it has no answer)."""


class NoLightWarning(UserWarning):
    """``rms_spot``: some fields put no ray on the image surface (their radii are NaN)."""


def field_unit(lens: Lens) -> str:
    """The unit of ``lens``'s fields: "mm" (object heights, telecentric object) or "deg"."""
    return "mm" if lens.telecentric_object else "deg"


def message(where: str, lens: Lens, field, what: str) -> str:
    """The refusal's text: the analysis, the field (its unit) and why there is no ``what``."""
    return (f"{where}: no ray of the beam reaches the image surface at field "
            f"{checks.fmt(field)} {field_unit(lens)} (the field is vignetted or beyond the "
            f"lens's coverage), so there is no {what}")


def refuse_dark(lit, where: str, lens: Lens, field, what: str) -> None:
    """Raise :class:`NoLightError` when the concrete ``lit`` (did any ray arrive) is False;
    a traced ``lit`` passes (the caller's NaN stands)."""
    if checks.is_traced(lit):
        return
    if not bool(np.all(np.asarray(lit))):
        raise NoLightError(message(where, lens, field, what))


def warn_dark(valid_fraction, fields, where: str, lens: Lens) -> None:
    """Warn (:class:`NoLightWarning`) naming each field of ``fields [F]`` or ``[F, 2]`` whose
    ``valid_fraction [F, W]`` is 0 at every wavelength, when both are concrete."""
    if checks.is_traced((valid_fraction, fields)):
        return
    dark = ~np.any(np.asarray(valid_fraction) > 0, axis=-1)
    if np.any(dark):
        f = np.asarray(fields)
        f = f.reshape(1) if f.ndim == 0 else f
        names = ", ".join(checks.fmt(f[i]) for i in np.flatnonzero(dark)[:8])
        warnings.warn(f"{where}: no ray reaches the image surface at field(s) {names} "
                      f"{field_unit(lens)} (vignetted or beyond the lens's coverage); their "
                      f"radii are NaN with valid_fraction 0", NoLightWarning, stacklevel=3)
