"""A fixed stop smaller than the beam that the entrance pupil diameter sends to it.

A lens states its aperture as an entrance pupil diameter (``Lens.epd``); its stop surface may
also have a fixed semi-diameter (or a centred circular aperture, ``Lens.apertures``) that is
smaller than the beam's height there. Zemax keeps the EPD then and lets the fixed stop
vignette: every field's beam is clipped at the stop, and the aperture that works is smaller
than the EPD the file states. jaxlens does the same, without an error or a warning (real
files do this: a stock lens whose clear aperture, on its first surface, is a little smaller
than the EPD its file gives), and says so where a user reads the lens's first-order data:
:func:`stop_clipping` and its :func:`note` line in the report's notes
(``jaxlens.analysis.report``).

The beam's height at the stop is that of the on-axis rim ray the lens's ray aiming launches
(``Lens.aim``, primary wavelength): with ``"paraxial"`` aiming (the default) and
``"real_marginal"``, the real ray through the rim of the paraxial entrance pupil
(``imaging.sampling.stop_radius(lens, "real")``); with ``"real"`` aiming, which fills the
paraxial stop, and for an object-space telecentric lens (an NA, no entrance pupil), the
paraxial marginal ray's (``paraxial_data(lens).stop_semi_diameter``). A rim ray that is lost
before the stop falls back to the paraxial height.

Conventions: lengths in mm; the stop surface is numbered as in Zemax (``lens.stop + 1``). The
working EPD is the diameter of the on-axis beam that passes the stop: with paraxial aiming,
twice the pupil radius whose real rim ray meets the stop's rim (found by the secant method,
to 1e-12 of the radius); with ``"real"``/``"real_marginal"`` aiming, which aim pupil
fractions at fractions of the stop height, EPD × stop radius / beam height. Only the stop's
semi-diameter and its centred circular clipping apertures are compared (an elliptical,
rectangular or decentered stop aperture passes no circular beam; it is left to the real rays).
"""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import numpy as np

from ..imaging import sampling
from ..optics import checks, paraxial
from ..optics.lens import Lens

SECANT_STEPS = 12
"""Most secant steps for the working EPD under paraxial aiming (3 to 5 reach 1e-12)."""

RELATIVE_MARGIN = 1e-9
"""A stop radius within this fraction below the beam's height clips nothing (a file's DIAM
equal to the beam's height, written from it, differs in the last digits)."""


@dataclasses.dataclass(frozen=True)
class StopClip:
    """A fixed stop that clips the EPD's beam.

    Attributes:
        stop_surface: the stop's surface number (Zemax numbering, ``lens.stop + 1``).
        stop_radius: its clipping radius, mm (semi-diameter or circular aperture).
        beam_radius: the beam's height at the stop for the lens's EPD, mm (see the module
            docstring: the real rim ray's or the paraxial marginal ray's).
        beam_ray: ``"real"`` or ``"paraxial"``: which ray gave ``beam_radius``.
        epd: the lens's entrance pupil diameter, mm (``inf`` for an object-space
            telecentric lens, whose aperture is an NA).
        working_epd: the diameter of the on-axis beam that the stop passes, mm (see the
            module docstring; ``None`` for an object-space telecentric lens).
        wavelength: the primary wavelength, µm.
    """

    stop_surface: int
    stop_radius: float
    beam_radius: float
    beam_ray: str
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


def _beam(lens: Lens) -> tuple[float, str]:
    """The rim ray's height at the stop (mm) and which ray it is."""
    par = abs(float(np.asarray(paraxial.paraxial_data(lens).stop_semi_diameter)))
    if lens.telecentric_object or lens.aim == "real":
        return par, "paraxial"
    try:
        real = float(np.asarray(_rim_height(lens, _object_z(lens))))
    except ValueError:  # the rim ray is lost before the stop
        return par, "paraxial"
    return (real, "real") if math.isfinite(real) else (par, "paraxial")


@eqx.filter_jit
def _rim_height(lens: Lens, object_z) -> float:
    """The real rim ray's height at the stop (mm; NaN where the ray is lost), as one compiled
    program: op by op it compiled a program per slice each time the report ran."""
    return sampling.stop_radius(lens, "real", object_z=object_z)


def _object_z(lens: Lens):
    return None if lens.object_at_infinity else -float(np.asarray(lens.object_distance))


def _real_working_epd(lens: Lens, radius: float, beam: float) -> float:
    """Paraxial aiming: the EPD whose real rim ray meets the stop at ``radius`` (secant on
    the rim ray's height as a function of the pupil radius, from EPD × radius / beam)."""
    epd = float(np.asarray(lens.epd))

    def height(rho):
        m = dataclasses.replace(lens, epd=np.asarray(2.0 * rho, np.asarray(lens.epd).dtype))
        return float(np.asarray(_rim_height(m, _object_z(lens))))

    x0, h0 = 0.5 * epd, beam
    x1 = x0 * radius / beam
    try:
        h1 = height(x1)
        for _ in range(SECANT_STEPS):
            if abs(h1 - radius) <= 1e-12 * radius or h1 == h0:
                break
            x0, h0, x1 = x1, h1, x1 + (radius - h1) * (x1 - x0) / (h1 - h0)
            h1 = height(x1)
    except ValueError:  # a rim ray lost on the way: the first-order value
        return epd * radius / beam
    return 2.0 * x1 if math.isfinite(x1) and abs(h1 - radius) <= 1e-9 * radius else (
        epd * radius / beam)


def stop_clipping(lens: Lens) -> StopClip | None:
    """The stop's clipping of the EPD's beam, or None where it passes the whole beam.

    Args:
        lens: the lens (concrete values: under ``jax.jit`` nothing is computed and None
            comes back).
    """
    if not isinstance(lens, Lens):  # before: an AttributeError on .epd
        raise TypeError(f"stop_clipping: lens must be a jaxlens.Lens, got "
                        f"{type(lens).__name__}")
    leaves = (lens.epd, lens.surfaces[lens.stop].semi_diameter, lens.thickness,
              lens.wavelengths)
    if any(checks.is_traced(v) for v in leaves):
        return None
    # A primary wavelength outside a glass's data made the rim ray NaN: "no clipping".
    checks.primary_wavelength(lens, "stop_clipping", "the rim ray's")
    radius = _stop_radius(lens)
    if not math.isfinite(radius):
        return None
    beam, ray = _beam(lens)
    if not math.isfinite(beam) or radius >= beam * (1.0 - RELATIVE_MARGIN):
        return None
    epd = math.inf if lens.telecentric_object else float(np.asarray(lens.epd))
    if lens.telecentric_object:
        working = None
    elif ray == "real" and lens.aim == "paraxial":  # rays through the paraxial pupil
        working = _real_working_epd(lens, radius, beam)
    else:  # aimed at pupil fractions of the stop height: the fraction radius / beam
        working = epd * radius / beam
    return StopClip(stop_surface=lens.stop + 1, stop_radius=radius, beam_radius=beam,
                    beam_ray=ray, epd=epd, working_epd=working,
                    wavelength=float(np.asarray(lens.primary_wavelength)))


def note(lens: Lens) -> list[str]:
    """The report's line for a stop that clips the EPD's beam (none where it does not)."""
    c = stop_clipping(lens)
    if c is None:
        return []
    ray = "real rim ray" if c.beam_ray == "real" else "paraxial marginal ray"
    head = (f"the stop (surface {c.stop_surface}, semi-diameter {c.stop_radius:.6g} mm) clips "
            f"the {'object-space NA' if c.working_epd is None else 'EPD'} beam "
            f"({c.beam_radius:.6g} mm high at the stop: {ray}, {c.wavelength:.6g} um)")
    if c.working_epd is None:
        return [f"{head}: the stop, not the NA, limits the aperture, to "
                f"{c.stop_radius / c.beam_radius:.4g} of the beam's radius"]
    return [f"{head}: working EPD {c.working_epd:.6g} mm, not the stated {c.epd:.6g} mm; "
            f"every field's beam is clipped there (Zemax keeps the EPD and lets a fixed stop "
            f"vignette)"]
