"""The report of a lens with an afocal image space (``Lens.afocal_image``): system data and,
per field, the chief ray's output angle, the real angular magnification and the RMS
angular spot radius per wavelength (``analysis.afocal``).

Conventions (also written into the JSON output under ``units``): lengths in mm, field and
output angles in degrees, wavelengths in µm, angular spot radii in mrad in
``rms_angle`` (rad in ``rms_angle_rad``), about the centroid of each wavelength's spot, on
the 21×21 pupil grid (317 rays). ``angular_magnification`` is the paraxial u′/u
(negative: an inverted image), ``magnification`` per field the chief ray's
tan θ′/tan θ along the field's direction. Pupil positions are global z. With
``--wavefront`` each field has ``wavefront``, referenced to a plane.
"""

from __future__ import annotations

import math

import numpy as np

from ..optics import paraxial
from ..optics.lens import Lens
from .afocal import angular_magnification, angular_spot
from .report_cells import (
    aiming_line,
    cell,
    json_extent,
    json_number,
    system_lines,
    wavefront_lines,
    wavefront_summary,
)

UNITS = {
    "length": "mm",
    "angle": "deg",
    "wavelength": "um",
    "rms_angle": "mrad",
    "rms_angle_rad": "rad",
}


def afocal_report_data(lens: Lens, *, wavefront: bool = False, notes=()) -> dict:
    """The afocal report as a JSON-ready dict (see the module docstring for units)."""
    pd = paraxial.paraxial_data(lens)
    spot = angular_spot(lens)
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    angles = np.asarray(lens.fields, np.float64)
    per = np.asarray(spot.per_wavelength, np.float64)
    poly = np.asarray(spot.polychromatic, np.float64)
    frac = np.asarray(spot.valid_fraction, np.float64)
    out_fields = []
    for i, a in enumerate(angles):
        got = [n > 0 for n in frac[i]]
        out_fields.append({
            "angle": float(a) if a.ndim == 0 else [float(v) for v in a],
            "chief_ray_angle": [json_number(v) for v in np.asarray(spot.chief_angle[i])],
            "magnification": json_number(spot.magnification[i]),
            "rms_angle": [json_number(1000.0 * v) if ok else None
                          for v, ok in zip(per[i], got, strict=True)],
            "rms_angle_rad": [json_number(v) if ok else None
                              for v, ok in zip(per[i], got, strict=True)],
            "rms_angle_polychromatic": json_number(1000.0 * poly[i]) if any(got) else None,
            "valid_fraction": [float(v) for v in frac[i]],
        })
        if wavefront:
            out_fields[-1]["wavefront"] = wavefront_summary(lens, lens.fields[i])
    radial = np.abs(angles) if angles.ndim == 1 else np.hypot(angles[:, 0], angles[:, 1])
    fmax = float(np.max(radial))
    return {
        "name": lens.name,
        "afocal_image_space": True,
        "units": UNITS,
        "angular_magnification": json_number(angular_magnification(lens)),
        "epd": json_number(lens.epd),
        "entrance_pupil": {"z": json_extent(pd.entrance_pupil_z),
                           "diameter": json_extent(pd.entrance_pupil_diameter)},
        "exit_pupil": {"z": json_extent(pd.exit_pupil_z),
                       "diameter": json_extent(pd.exit_pupil_diameter)},
        "total_track": json_number(pd.total_track),
        "fov": 2.0 * fmax,
        "max_field": fmax,
        "stop_surface": lens.stop + 1,
        "ray_aiming": lens.aim,
        "object_distance": (None if lens.object_distance is None
                            else json_number(lens.object_distance)),
        "wavelengths": [float(w) for w in wl],
        "primary_wavelength": float(wl[lens.primary]),
        "fields": out_fields,
        "notes": list(notes),
    }


def format_afocal_report(data: dict, surface_table: list[str] | None = None) -> str:
    """The human-readable afocal report; ``surface_table`` the prescription's lines."""
    ep, xp = data["entrance_pupil"], data["exit_pupil"]
    rows = [
        ("Angular magnification (paraxial)", data["angular_magnification"], ""),
        ("Entrance pupil diameter", data["epd"], "mm"),
        ("Entrance pupil position (z)", ep["z"], "mm"),
        ("Exit pupil diameter", xp["diameter"], "mm"),
        ("Exit pupil position (z)", xp["z"], "mm"),
        ("Full field of view", data["fov"], "deg"),
        ("Total track", data["total_track"], "mm"),
        ("Object distance", math.inf if data["object_distance"] is None
         else data["object_distance"], "mm"),
    ]
    L = system_lines(data, "SYSTEM DATA (afocal image space: the image is at infinity)", rows,
                     aiming_line(data), surface_table)
    wl = data["wavelengths"]
    L += ["", "FIELDS (output angles of the chief ray in deg; RMS angular radius about the "
              "centroid in mrad, 21x21 pupil grid)"]
    heads = "".join(f"{f'RMS {1000 * w:.1f}nm':>15}" for w in wl)
    L.append(f"  {'Field':>5}{'Angle x, y':>17}{'Out x, y':>21}{'Magnif.':>11}{heads}"
             f"{'RMS poly':>12}")
    for i, f in enumerate(data["fields"]):
        a = f["angle"] if isinstance(f["angle"], list) else [0.0, f["angle"]]
        ox, oy = f["chief_ray_angle"]
        L.append(f"  {i + 1:>5}{a[0]:>8.3f},{a[1]:>8.3f}{cell(ox, 10, 5)},{cell(oy, 10, 5)}"
                 f"{cell(f['magnification'], 11, 5, '-')}"
                 + "".join(cell(v, 15, 5) for v in f["rms_angle"])
                 + cell(f["rms_angle_polychromatic"], 12, 5))
        lost = [f"{100 * (1 - v):.1f}% at {w:.4f} um"
                for w, v in zip(wl, f["valid_fraction"], strict=True) if v < 1]
        if lost:
            L.append(f"        field {i + 1}: rays clipped or failed: " + ", ".join(lost))
    L += wavefront_lines(data["fields"], "a plane (afocal image space)")
    return "\n".join(L) + "\n"
