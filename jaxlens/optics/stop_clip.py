"""A fixed stop smaller than the beam that the entrance pupil diameter sends to it.

A lens states its aperture as an entrance pupil diameter (``Lens.epd``); its stop surface may
also have a fixed semi-diameter (or a centred circular aperture, ``Lens.apertures``) that is
smaller than the paraxial marginal ray's height there. Zemax keeps the EPD then and lets the
fixed stop vignette: every field's beam is clipped at the stop, and the aperture that works is
smaller than the EPD the file states. jaxlens does the same, without an error or a warning
(real files do this: a stock lens whose clear aperture, on its first surface, is a little
smaller than the EPD its file gives), and says so where a user reads the lens's first-order
data: :func:`stop_clipping` and its :func:`note` line in the report's notes
(``jaxlens.analysis.report``).

Conventions: lengths in mm, the wavelength in µm (default the lens's primary one); the stop
surface is numbered as in Zemax (``lens.stop + 1``). The working EPD is paraxial: the EPD
scaled by (stop radius / marginal-ray height at the stop), the diameter of the on-axis beam
that the stop passes. Only the stop's semi-diameter and its centred circular clipping
apertures are compared (an elliptical, rectangular or decentered stop aperture passes no
circular beam; it is left to the real rays).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import checks, paraxial
from .lens import Lens

RELATIVE_MARGIN = 1e-9
"""A stop radius within this fraction below the beam's height clips nothing (a file's DIAM
equal to the marginal ray's height, written from it, differs in the last digits)."""


@dataclasses.dataclass(frozen=True)
class StopClip:
    """A fixed stop that clips the EPD's beam.

    Attributes:
        stop_surface: the stop's surface number (Zemax numbering, ``lens.stop + 1``).
        stop_radius: its clipping radius, mm (semi-diameter or circular aperture).
        beam_radius: the paraxial marginal ray's height at the stop for the lens's EPD, mm.
        epd: the lens's entrance pupil diameter, mm (``inf`` for an object-space
            telecentric lens, whose aperture is an NA).
        working_epd: ``epd · stop_radius / beam_radius``, mm: the diameter of the on-axis
            beam that the stop passes (``None`` for an object-space telecentric lens).
        wavelength: the wavelength of the marginal ray, µm.
    """

    stop_surface: int
    stop_radius: float
    beam_radius: float
    epd: float
    working_epd: float | None
    wavelength: float


def _stop_radius(lens: Lens) -> float:
    """The stop's clipping radius (mm): its semi-diameter and centred circular apertures."""
    radii = [float(np.asarray(lens.surfaces[lens.stop].semi_diameter))]
    for i, ap in lens.apertures:
        if (i == lens.stop and ap.shape == "circle" and not ap.blocks
                and float(ap.decenter_x) == 0.0 and float(ap.decenter_y) == 0.0):
            radii.append(float(ap.half_x))
    return min(radii)


def stop_clipping(lens: Lens, wavelength=None) -> StopClip | None:
    """The stop's clipping of the EPD's beam, or None where it passes the whole beam.

    Args:
        lens: the lens (concrete values: under ``jax.jit`` nothing is computed and None
            comes back).
        wavelength: µm; default the lens's primary wavelength.
    """
    leaves = (lens.epd, lens.surfaces[lens.stop].semi_diameter, lens.thickness)
    if any(checks.is_traced(v) for v in leaves):
        return None
    radius = _stop_radius(lens)
    if not math.isfinite(radius):
        return None
    wl = lens.primary_wavelength if wavelength is None else wavelength
    y, _ = paraxial.marginal_ray(lens, wl)
    beam = abs(float(np.asarray(y[lens.stop]).ravel()[0]))
    if not math.isfinite(beam) or radius >= beam * (1.0 - RELATIVE_MARGIN):
        return None
    epd = math.inf if lens.telecentric_object else float(np.asarray(lens.epd))
    working = None if lens.telecentric_object else epd * radius / beam
    return StopClip(stop_surface=lens.stop + 1, stop_radius=radius, beam_radius=beam, epd=epd,
                    working_epd=working, wavelength=float(np.asarray(wl)))


def note(lens: Lens) -> list[str]:
    """The report's line for a stop that clips the EPD's beam (none where it does not)."""
    c = stop_clipping(lens)
    if c is None:
        return []
    head = (f"the stop (surface {c.stop_surface}, semi-diameter {c.stop_radius:.6g} mm) clips "
            f"the {'object-space NA' if c.working_epd is None else 'EPD'} beam "
            f"({c.beam_radius:.6g} mm high at the stop, paraxial, {c.wavelength:.6g} um)")
    if c.working_epd is None:
        return [f"{head}: the stop, not the NA, limits the aperture, to "
                f"{c.stop_radius / c.beam_radius:.4g} of the beam's radius"]
    return [f"{head}: working EPD {c.working_epd:.6g} mm, not the stated {c.epd:.6g} mm; "
            f"every field's beam is clipped there (Zemax keeps the EPD and lets a fixed stop "
            f"vignette)"]
