"""The report of an object-space telecentric lens (``Lens.object_na``): system data and, per
field (an object height), the real chief ray, distortion against the paraxial magnification,
the RMS spot radii, the astigmatic foci and the Seidel sums.

Conventions (also written into the JSON output under ``units``): lengths and heights in mm,
object heights in mm (``height``: y, or (x, y)), wavelengths in µm, distortion in %, RMS
spot radii in µm in ``rms_spot`` and in mm in ``rms_spot_mm`` (about the centroid of each
wavelength's spot, on the 21×21 pupil grid of ray slopes (Px, Py)·tan u: 317 rays). The
chief ray leaves each object point parallel to the axis (the entrance pupil lies at
infinity, so there is no entrance pupil, F/# or field angle). ``magnification`` is the
paraxial lateral magnification m (``paraxial.magnification``); ``ideal_image_height`` is
m·h, ``distortion`` 100·(y_chief − m·h)/(m·h) and ``distortion_paraxial`` against the
paraxial chief ray's height on the image surface (``analysis.distortion``). For (x, y)
heights the image heights are along each field's direction. ``focus_tangential`` and
``focus_sagittal`` are ``analysis.field_curvature`` at the primary wavelength (mm along z
from the image surface); ``seidel`` holds ``analysis.seidel``'s sums at the largest height.
"""

from __future__ import annotations

import math

import numpy as np

from ..optics import checks, paraxial
from ..optics.lens import Lens
from .report_cells import (
    bucketed_field_curvature,
    cell,
    json_extent,
    json_number,
    seidel_lines,
    seidel_summary,
    system_lines,
    wavefront_lines,
    wavefront_summary,
)
from .spots import distortion, rms_spot

UNITS = {
    "length": "mm",
    "object_height": "mm",
    "wavelength": "um",
    "distortion": "%",
    "rms_spot": "um",
    "rms_spot_mm": "mm",
    "focus": "mm",
    "seidel": "mm (sums), waves (wavefront)",
}

NOTE = ("object-space telecentric (object NA given): the fields are object heights in mm, "
        "every chief ray leaves its object point parallel to the axis, the entrance pupil "
        "lies at infinity; distortion is measured against m·h, m the paraxial magnification")


def _check_arguments(lens, wavefront, notes) -> None:
    """Refuse what the report cannot describe: before, a focal lens failed as float(None), an
    afocal one in the distortion analysis, and ``wavefront="no"`` or ``notes="text"`` (a line
    a character) were taken."""
    where = "telecentric_report_data"
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    if not lens.telecentric_object:
        raise ValueError(f"{where}: the lens is not object-space telecentric (object_na is "
                         f"None: its entrance pupil is at a finite distance); use "
                         f"jaxlens.analysis.report.report_data")
    checks.switch(wavefront, "wavefront", where)
    if isinstance(notes, str) or not all(isinstance(n, str) for n in notes):
        raise TypeError(f"{where}: notes must be a list of str (one line each), got {notes!r}")


def telecentric_report_data(lens: Lens, *, wavefront: bool = False, notes=()) -> dict:
    """The report of an object-space telecentric lens as a JSON-ready dict (see the module
    docstring for units)."""
    _check_arguments(lens, wavefront, notes)
    pd = paraxial.paraxial_data(lens)
    d = distortion(lens)
    spot = rms_spot(lens)
    fc = bucketed_field_curvature(lens, lens.fields, lens.wavelengths)
    tan, sag = (np.asarray(v)[lens.primary] for v in (fc.tangential, fc.sagittal))
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    heights = np.asarray(lens.fields, np.float64)
    per = np.asarray(spot.per_wavelength, np.float64)
    frac = np.asarray(spot.valid_fraction, np.float64)
    out_fields = []
    for i, h in enumerate(heights):
        got = [n > 0 for n in frac[i]]
        out_fields.append({
            "height": float(h) if h.ndim == 0 else [float(v) for v in h],
            "chief_ray_height": json_number(d.chief_height[i]),
            "chief_ray_xy": [json_number(v) for v in np.asarray(spot.chief[i])],
            "paraxial_image_height": json_number(d.paraxial_height[i]),
            "ideal_image_height": json_number(d.f_tan[i]),
            "distortion": json_number(d.percent_ftan[i]),
            "distortion_paraxial": json_number(d.percent_paraxial[i]),
            "rms_spot": [json_number(1000.0 * v) if ok else None
                         for v, ok in zip(per[i], got, strict=True)],
            "rms_spot_mm": [json_number(v) if ok else None
                            for v, ok in zip(per[i], got, strict=True)],
            "rms_spot_polychromatic": (json_number(1000.0 * spot.polychromatic[i])
                                       if any(got) else None),
            "valid_fraction": [float(v) for v in frac[i]],
            "focus_tangential": json_number(tan[i]),
            "focus_sagittal": json_number(sag[i]),
        })
        if wavefront:
            out_fields[-1]["wavefront"] = wavefront_summary(lens, lens.fields[i])
    radial = np.abs(heights) if heights.ndim == 1 else np.hypot(heights[:, 0], heights[:, 1])
    imax = int(np.argmax(radial))
    return {
        "name": lens.name,
        "object_space_telecentric": True,
        "units": UNITS,
        "object_na": json_number(lens.object_na),
        "object_index": json_number(lens.object_material.index(lens.primary_wavelength)),
        "magnification": json_extent(paraxial.magnification(lens)),
        "efl": json_extent(pd.efl),
        "efl_image_space": json_extent(pd.efl_image_space),
        "bfl": json_extent(pd.bfl),
        "working_fnum": json_extent(pd.working_fnum),
        "total_track": json_number(pd.total_track),
        "max_object_height": float(radial[imax]),
        "image_height": json_number(d.paraxial_height[imax]),
        "real_image_height": json_number(d.chief_height[imax]),
        "exit_pupil": {"z": json_extent(pd.exit_pupil_z),
                       "diameter": json_extent(pd.exit_pupil_diameter),
                       "from_image": json_extent(pd.exit_pupil_z - pd.image_z)},
        "image_z": json_extent(pd.image_z),
        "paraxial_image_z": json_extent(pd.paraxial_image_z),
        "stop_surface": lens.stop + 1,
        "ray_aiming": lens.aim,
        "object_distance": json_number(lens.object_distance),
        "wavelengths": [float(w) for w in wl],
        "primary_wavelength": float(wl[lens.primary]),
        "fields": out_fields,
        "seidel": seidel_summary(lens),
        "notes": [NOTE, *notes],
    }


def format_telecentric_report(data: dict, surface_table: list[str] | None = None) -> str:
    """The human-readable report of an object-space telecentric lens; ``surface_table`` the
    prescription's lines."""
    if not isinstance(data, dict) or data.get("object_space_telecentric") is not True:
        # before: a KeyError ('exit_pupil', 'object_na') or "not subscriptable"
        raise ValueError("format_telecentric_report: data must be the dict of "
                         "telecentric_report_data (an object-space telecentric lens's report), "
                         f"got {type(data).__name__}"
                         + (" without 'object_space_telecentric': True" if isinstance(data, dict)
                            else ""))
    xp = data["exit_pupil"]
    rows = [
        ("Object-space NA", data["object_na"], ""),
        ("Paraxial magnification", data["magnification"], ""),
        ("Effective focal length (in air)", data["efl"], "mm"),
        ("Paraxial working F/#", data["working_fnum"], ""),
        ("Exit pupil diameter", xp["diameter"], "mm"),
        ("Exit pupil position (from image)", xp["from_image"], "mm"),
        ("Largest object height", data["max_object_height"], "mm"),
        ("Paraxial image height", data["image_height"], "mm"),
        ("Real chief-ray image height", data["real_image_height"], "mm"),
        ("Total track", data["total_track"], "mm"),
        ("Object distance", math.inf if data["object_distance"] is None
         else data["object_distance"], "mm"),
    ]
    launch = (f"  {'Ray launch':<34}: from each object point, slopes (Px, Py)*tan u (no "
              f"aiming)")
    L = system_lines(data, "SYSTEM DATA (object-space telecentric: entrance pupil at infinity)",
                     rows, launch, surface_table)
    wl = data["wavelengths"]
    L += ["", "FIELDS (object heights and image heights in mm along each field's direction, "
              "distortion in % against m*h, RMS spot radius about the centroid in um, 21x21 "
              "pupil grid)"]
    heads = "".join(f"{f'RMS {1000 * w:.1f}nm':>15}" for w in wl)
    L.append(f"  {'Field':>5}{'Height x, y':>19}{'Chief h':>13}{'m*h':>13}{'Parax h':>13}"
             f"{'Dist m*h':>12}{'Dist parax':>12}{heads}{'RMS poly':>12}")
    for i, f in enumerate(data["fields"]):
        h = f["height"] if isinstance(f["height"], list) else [0.0, f["height"]]
        L.append(f"  {i + 1:>5}{h[0]:>9.4f},{h[1]:>9.4f}{cell(f['chief_ray_height'], 13, 6)}"
                 f"{cell(f['ideal_image_height'], 13, 6)}"
                 f"{cell(f['paraxial_image_height'], 13, 6)}{cell(f['distortion'], 12, 5)}"
                 f"{cell(f['distortion_paraxial'], 12, 5)}"
                 + "".join(cell(v, 15, 4) for v in f["rms_spot"])
                 + cell(f["rms_spot_polychromatic"], 12, 4))
        lost = [f"{100 * (1 - v):.1f}% at {w:.4f} um"
                for w, v in zip(wl, f["valid_fraction"], strict=True) if v < 1]
        if lost:
            L.append(f"        field {i + 1}: rays clipped or failed: " + ", ".join(lost))
    L += ["", "FIELD CURVATURE (primary wavelength; tangential and sagittal foci in mm from "
              "the image surface along z, + behind it; tangential plane along each field's "
              "direction)",
          f"  {'Field':>5}{'Height x, y':>19}{'Tangential':>13}{'Sagittal':>13}"
          f"{'Astigmatism':>13}"]
    for i, f in enumerate(data["fields"]):
        h = f["height"] if isinstance(f["height"], list) else [0.0, f["height"]]
        t, s = f["focus_tangential"], f["focus_sagittal"]
        astig = None if t is None or s is None else t - s
        L.append(f"  {i + 1:>5}{h[0]:>9.4f},{h[1]:>9.4f}{cell(t, 13, 6)}{cell(s, 13, 6)}"
                 f"{cell(astig, 13, 6)}")
    L += wavefront_lines(data["fields"], "the exit-pupil reference sphere")
    L += seidel_lines(data.get("seidel"), "object height {:.4f} mm")
    return "\n".join(L) + "\n"
