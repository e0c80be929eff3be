"""Lens report: system data and per-field chief ray, distortion and RMS spot.

``python -m jaxlens report LENS [--json] [--fields DEG ...] [--wavelengths UM ...]
[--wavefront] [--plot DIR [--overwrite]] [--lenient] [--unknown-glass model]
[--config N] [--list-configs]``

Conventions (also written into the JSON output under ``units``):
    Lengths and heights in mm, angles in degrees, wavelengths in µm, distortion in %.
    RMS spot radii are in µm in ``rms_spot`` and in mm in ``rms_spot_mm``; they use the
    21×21 square grid over the unit entrance pupil kept inside the disc (317 rays,
    aimed at the paraxial entrance pupil), about the centroid of each wavelength's
    spot. ``distortion`` is 100·(y_chief − EFL·tanθ)/(EFL·tanθ) (f-tanθ distortion) and
    ``distortion_paraxial`` uses the paraxial chief-ray height on the image surface as
    the reference. ``efl`` is 1/Φ, the focal length in air; ``efl_image_space`` is n′/Φ
    with n′ the image-space index, the EFL that Zemax ("in image space") and optiland
    report; they differ only when image space is not air. The chief ray is the
    primary-wavelength ray through the centre of the paraxial entrance pupil. Pupil
    positions are global z (surface 1's vertex at 0). ``focus_tangential`` and
    ``focus_sagittal`` (mm) are ``analysis.field_curvature`` at the primary wavelength: where
    the rays next to the chief ray meet it, along z from the image surface (+ behind it);
    for a (θx, θy) field the tangential plane is along the field's azimuth. ``seidel``
    holds ``analysis.seidel``'s sums S_I … S_V, C_L, C_T (mm) and W040 … W111 (waves) at the
    primary wavelength and the largest field, or ``refused`` with the reason for a lens
    outside third-order theory (coordinate breaks, toroids, gratings, …). With
    ``--wavefront`` each field also has ``wavefront``: ``analysis.wavefront`` at the primary
    wavelength (``rms``, ``pv``, and both with tilt removed, in waves; ``strehl``, Maréchal's,
    null where the RMS with tilt removed exceeds 0.1 wave and the approximation fails), or
    ``refused`` with the reason. JSON has no infinity: a first-order distance, size or ratio
    at infinity (an image-space telecentric lens's exit pupil, an F/# of an afocal image) is
    the string ``"inf"`` or ``"-inf"`` (as in the lens files), printed "Infinity"; a value
    that could not be computed is null, printed "failed".
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..imaging import sampling
from ..imaging.telecentric import lens_fields
from ..io.files import load
from ..io.lensfile import nm_to_um
from ..io.zmx import configurations
from ..optics import checks, paraxial
from ..optics.coordinates import CoordinateBreak
from ..optics.diffractive import Binary2, Grating
from ..optics.freeform import Biconic, ZernikeSag
from ..optics.lens import Lens
from ..optics.materials import Air, ModelGlass, Tabulated
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.qtype import QTypeAsphere
from ..optics.surfaces import EvenAsphere, Hybrid, OddAsphere, Standard, TiltedPlane
from ..optics.toroidal import Toroidal
from ..optics.xypolynomial import XYPolynomial, xy_term_powers
from ..tracing.forward import aimed_jit
from . import spots as analysis
from . import stop_clip
from .report_afocal import afocal_report_data, format_afocal_report
from .report_cells import (
    aiming_line,
    bucketed_field_curvature,
    seidel_lines,
    seidel_summary,
    system_lines,
    wavefront_lines,
)
from .report_cells import cell as _num
from .report_cells import json_extent as _x
from .report_cells import json_number as _f
from .report_cells import wavefront_summary as _wavefront_summary
from .report_telecentric import format_telecentric_report, telecentric_report_data

UNITS = {
    "length": "mm",
    "angle": "deg",
    "wavelength": "um",
    "distortion": "%",
    "rms_spot": "um",
    "rms_spot_mm": "mm",
    "focus": "mm",
    "seidel": "mm (sums), waves (wavefront)",
}


def _pct(a, b):
    with np.errstate(invalid="ignore"):  # on the host (see ``report_data``)
        return analysis.distortion_percent(np.asarray(a), np.asarray(b), xp=np)


class _Result(eqx.Module):
    paraxial: paraxial.ParaxialData
    chief_height: jax.Array  # [F] mm, real chief ray (primary wavelength), along the field
    chief_xy: jax.Array  # [F, 2] mm, where it lands
    field_angle: jax.Array  # [F] deg, signed θy for [F] fields, radial for [F, 2]
    chief_valid: jax.Array  # [F]
    f_tan: jax.Array  # [F] mm
    paraxial_height: jax.Array  # [F] mm
    rms: jax.Array  # [F, W] mm
    rms_poly: jax.Array  # [F] mm
    valid_fraction: jax.Array  # [F, W]


@checks.checked_core(aimed_jit)
def _compute(lens: Lens) -> _Result:
    """Everything the report needs from one traced ray set.

    The rays are ``analysis.spot_rays`` on the 21×21 grid for every field and
    wavelength; the chief ray is the grid's centre point at the primary wavelength (the
    same ray as ``analysis.chief_ray``; both aimed as ``lens.aim`` says). The RMS radii
    and distortions follow the definitions of ``analysis.rms_spot`` and
    ``analysis.distortion``; tracing once
    instead of three times (spots, their chief rays, distortion) cuts compile time.
    """
    pd = paraxial.paraxial_data(lens)
    with jax.ensure_compile_time_eval():
        pupil = sampling.pupil_grid(21, lens.epd.dtype)
        centre = int(np.argmin(np.sum(np.asarray(pupil) ** 2, axis=-1)))
    depth = None if lens.object_at_infinity else lens.object_distance

    def field(f):
        def wave(w):
            r = analysis.spot_rays(lens, f, w, pupil=pupil, depth=depth)
            return r.origin[..., :2], r.valid

        return jax.vmap(wave)(lens.wavelengths)

    p, valid = jax.vmap(field)(lens.fields)  # [F, W, M, 2], [F, W, M]
    w = valid.astype(p.dtype)
    rms = analysis.weighted_rms(p, w)
    F = p.shape[0]
    poly = analysis.weighted_rms(p.reshape(F, -1, 2), w.reshape(F, -1))
    chief_xy = p[:, lens.primary, centre]
    tan_radial, radial, chief = analysis.field_heights(lens.fields, chief_xy)
    ftan = analysis.reference_heights(pd.front_focal_length, tan_radial)  # n·EFL·tanθ
    ypar = jax.vmap(lambda th: paraxial.image_height(lens, th))(radial)
    return _Result(
        pd, chief, chief_xy, radial, valid[:, lens.primary, centre], ftan, ypar, rms, poly,
        jnp.mean(w, axis=-1)
    )


MAX_REPORT_ENTRIES = 64
"""Most fields, and most wavelengths, a report takes (``--fields``, ``--wavelengths``)."""


def with_fields_and_wavelengths(lens: Lens, fields=None, wavelengths=None) -> Lens:
    """The lens with other field angles (deg) and wavelengths (µm; values > 100 are nm).

    With new wavelengths the primary is the one closest to the lens's primary wavelength.
    """
    if not isinstance(lens, Lens):  # else an AttributeError on .thickness
        raise TypeError(f"report: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    dtype = lens.thickness.dtype
    # Before np.asarray(..., float64), which reads "5" as 5 and True as 1.
    if fields is not None:
        checks.real_values(fields, "--fields", "report",
                           "mm" if lens.telecentric_object else "deg")
    if wavelengths is not None:
        checks.real_values(wavelengths, "--wavelengths", "report", "µm")
    for arg, v in (("--fields", fields), ("--wavelengths", wavelengths)):
        # Before: 10**5 fields were analysed one by one for hours (Zemax takes 12 fields, 24
        # wavelengths).
        if v is not None and np.shape(v)[:1] and np.shape(v)[0] > MAX_REPORT_ENTRIES:
            raise ValueError(f"report: {arg} holds {np.shape(v)[0]} values; a report takes at "
                             f"most {MAX_REPORT_ENTRIES} (each is analysed in turn)")
    if fields is not None:
        shape = np.shape(fields)
        if len(shape) > 2 or (len(shape) == 2 and shape[1] != 2) or np.size(fields) == 0:
            raise ValueError(f"report: --fields must be θy angles in degrees, one value or "
                             f"[F], or (θx, θy) pairs [F, 2], with F >= 1, got shape {shape}")
        lens_fields(lens, np.asarray(fields, np.float64), "report", "--fields")  # mm or deg
        f = jnp.asarray(np.atleast_1d(np.asarray(fields, np.float64)), dtype)
        rows = np.asarray(f).reshape(f.shape[0], -1)
        if np.unique(rows, axis=0).shape[0] < rows.shape[0]:  # a row reported twice
            raise ValueError(f"report: --fields gives a field more than once, got "
                             f"{checks.fmt(fields)}")
        # The factors of the fields that stay (none for new fields), or none at all.
        lens = dataclasses.replace(lens, fields=f,
                                   vignetting=sampling.vignetting_for_fields(lens, f))
    if wavelengths is not None:
        w = np.atleast_1d(np.asarray(wavelengths, np.float64))
        w = np.where(w > 100.0, nm_to_um(w), w)
        if w.size == 0 or np.any(w <= 0):
            raise ValueError(f"report: --wavelengths must be numbers in (0, inf) µm (values above "
                             f"100 are read as nm), got {checks.fmt(wavelengths)}")
        ws = np.sort(w)
        same = np.diff(ws) <= 1e-12 * ws[1:]  # 0.5876 587.6: one wavelength weighed twice
        if np.any(same):
            raise ValueError(f"report: --wavelengths gives {ws[1:][same][0]:g} µm twice (values "
                             f"above 100 are read as nm), got {checks.fmt(wavelengths)}")
        checks.wavelengths(lens, w, "report", "--wavelengths")
        checks.material_indices(lens, w, "report", "--wavelengths")
        primary = int(np.argmin(np.abs(w - float(lens.primary_wavelength))))
        lens = dataclasses.replace(lens, wavelengths=jnp.asarray(w, dtype), primary=primary)
    return lens


def report_data(lens: Lens, *, fields=None, wavelengths=None, wavefront: bool = False) -> dict:
    """The report as a JSON-ready dict (see the module docstring for units).

    Args:
        lens: the lens.
        fields: field angles in degrees (y); default the lens's fields (object heights in
            mm for an object-space telecentric lens: see ``report_telecentric``).
        wavelengths: µm; default the lens's wavelengths.
        wavefront: also give each field's wavefront error (``analysis.wavefront`` at the
            primary wavelength): RMS and P-V in waves, and Maréchal's Strehl ratio.
    """
    lens = with_fields_and_wavelengths(lens, fields, wavelengths)
    if wavelengths is None and not checks.is_traced(lens.wavelengths):
        # Checked here, not as an EquinoxRuntimeError from inside the compiled trace.
        checks.wavelengths(lens, lens.wavelengths, "report", "the lens's wavelengths")
        checks.material_indices(lens, lens.wavelengths, "report", "the lens's wavelengths")
    if not checks.is_traced(lens.fields):  # its compiled core trusts them (mm or deg)
        lens_fields(lens, lens.fields, "report", "the lens's fields")
    if lens.telecentric_object:  # object heights, chief rays parallel to the axis
        return telecentric_report_data(lens, wavefront=wavefront, notes=_notes(lens))
    paraxial.check_launchable(lens, "report")  # not from inside the compiled trace
    if lens.afocal_image:  # an image at infinity: angles, not heights
        return afocal_report_data(lens, wavefront=wavefront, notes=_notes(lens))
    # On the host once: op by op on the device, the table below compiled a program per
    # operation and slice shape (the same IEEE operations, the same numbers).
    res = jax.tree.map(np.asarray, _compute(lens))
    pd = res.paraxial
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    angles = np.asarray(lens.fields, np.float64)
    radial = np.abs(np.asarray(res.field_angle, np.float64))
    fmax = float(np.max(radial))
    per = np.asarray(res.rms, np.float64)
    ok = np.asarray(res.chief_valid)
    chief = np.where(ok, np.asarray(res.chief_height, np.float64), np.nan)
    d_ftan = np.where(ok, np.asarray(_pct(res.chief_height, res.f_tan)), np.nan)
    d_par = np.where(ok, np.asarray(_pct(res.chief_height, res.paraxial_height)), np.nan)
    out_fields = []
    for i, a in enumerate(angles):
        frac = np.asarray(res.valid_fraction[i], np.float64)
        out_fields.append(
            {
                "angle": float(a) if a.ndim == 0 else [float(v) for v in a],
                "chief_ray_height": _f(chief[i]),
                "chief_ray_xy": [_f(v) for v in np.where(ok[i], res.chief_xy[i], np.nan)],
                "paraxial_image_height": _f(res.paraxial_height[i]),
                "f_tan_theta": _f(res.f_tan[i]),
                "distortion": _f(d_ftan[i]),
                "distortion_paraxial": _f(d_par[i]),
                "rms_spot": [
                    _f(1000.0 * v) if n > 0 else None for v, n in zip(per[i], frac, strict=True)
                ],
                "rms_spot_mm": [
                    _f(v) if n > 0 else None for v, n in zip(per[i], frac, strict=True)
                ],
                "rms_spot_polychromatic": _f(1000.0 * res.rms_poly[i]) if frac.any() else None,
                "valid_fraction": [float(v) for v in frac],
            }
        )
    # Every wavelength, the primary's row taken: the program of the --plot figure's call.
    fc = bucketed_field_curvature(lens, lens.fields, lens.wavelengths)
    foci = (np.asarray(fc.tangential)[lens.primary], np.asarray(fc.sagittal)[lens.primary])
    for i, entry in enumerate(out_fields):
        entry["focus_tangential"] = _f(foci[0][i])
        entry["focus_sagittal"] = _f(foci[1][i])
    if wavefront:
        for entry, angle in zip(out_fields, lens.fields, strict=True):
            entry["wavefront"] = _wavefront_summary(lens, angle)
    imax = int(np.argmax(radial))
    return {
        "name": lens.name,
        "units": UNITS,
        "efl": _x(pd.efl),
        "efl_image_space": _x(pd.efl_image_space),
        "bfl": _x(pd.bfl),
        "fnum": _x(pd.fnum),
        "working_fnum": _x(pd.working_fnum),
        "epd": _f(lens.epd),
        "total_track": _f(pd.total_track),
        "fov": 2.0 * fmax,
        "max_field": fmax,
        "image_height": _f(res.paraxial_height[imax]),
        "real_image_height": _f(chief[imax]),
        "entrance_pupil": {
            "z": _x(pd.entrance_pupil_z),
            "diameter": _x(pd.entrance_pupil_diameter),
        },
        "exit_pupil": {
            "z": _x(pd.exit_pupil_z),
            "diameter": _x(pd.exit_pupil_diameter),
            "from_image": _x(pd.exit_pupil_z - pd.image_z),
        },
        "image_z": _x(pd.image_z),
        "paraxial_image_z": _x(pd.paraxial_image_z),
        "stop_surface": lens.stop + 1,
        "ray_aiming": lens.aim,
        "object_distance": None if lens.object_distance is None else _f(lens.object_distance),
        "wavelengths": [float(w) for w in wl],
        "primary_wavelength": float(wl[lens.primary]),
        "fields": out_fields,
        "seidel": seidel_summary(lens),
        "notes": _notes(lens),
    }


def _notes(lens: Lens) -> list[str]:
    """Caveats the numbers need: a decentered or tilted system has no single optical axis,
    so its first-order data describe the unbroken local axes only; a tilted plane's
    deviation and a grating's lines are seen by real rays only."""
    def numbered(kind, moved):
        return [i + 1 for i, s in enumerate(lens.surfaces) if isinstance(s, kind) and any(
            float(v) != 0.0 for v in moved(s))]

    notes = []
    breaks = numbered(CoordinateBreak, lambda s: (s.decenter_x, s.decenter_y, s.tilt_x,
                                                  s.tilt_y, s.tilt_z))
    if breaks:
        notes.append(f"coordinate breaks decenter or tilt the system at surface(s) "
                     f"{', '.join(map(str, breaks))}: the paraxial data (EFL, BFL, F/#, pupils, "
                     f"paraxial image height and distortion) follow each surface's local axis "
                     f"and ignore those decenters and tilts; the real-ray chief heights and RMS "
                     f"spots are exact")
    tilted = numbered(TiltedPlane, lambda s: (s.tan_x, s.tan_y))
    if tilted:
        notes.append(f"tilted plane(s) (TILTSURF) at surface(s) {', '.join(map(str, tilted))} "
                     f"deviate the beam as a prism face does: the paraxial data treat them as "
                     f"planes normal to the axis; the real-ray chief heights and RMS spots are "
                     f"exact")
    gratings = numbered(Grating, lambda s: (s.lines_per_um * s.order,))
    if gratings:
        notes.append(f"grating(s) at surface(s) {', '.join(map(str, gratings))}: the paraxial "
                     f"data are those of the order-0 system (the lines removed); the real rays "
                     f"see the lines")
    return notes + stop_clip.note(lens)  # a fixed stop smaller than the EPD's beam


# ---------------------------------------------------------------------------- text


def _material_label(m) -> str:
    if isinstance(m, Air):
        return ""
    if isinstance(m, ModelGlass):
        return f"{float(m.nd):.4f},{float(m.vd):.2f}"
    name = getattr(m, "name", "")
    if isinstance(m, Tabulated):
        return name or "TABLE"
    return name or type(m).__name__


_ZEMAX_TYPE = {Standard: "STANDARD", EvenAsphere: "EVENASPH", OddAsphere: "ODDASPHE",
               Hybrid: "HYBRID", Toroidal: "TOROIDAL", ParaxialSurface: "PARAXIAL",
               CoordinateBreak: "COORDBRK", TiltedPlane: "TILTSURF", Binary2: "BINARY_2",
               QTypeAsphere: "QED_TYPE", Grating: "DGRATING", Biconic: "BICONICX",
               XYPolynomial: "XPOLYNOM"}


def _nonzero(prefix_values) -> str:
    return " ".join(f"{p}={float(v):.4g}" for p, v in prefix_values if float(v) != 0)


def _terms(s) -> str:
    """The surface's parameters beyond radius and conic, as Zemax names them."""
    if isinstance(s, CoordinateBreak):
        return _nonzero([("dx", s.decenter_x), ("dy", s.decenter_y), ("tx", s.tilt_x),
                         ("ty", s.tilt_y), ("tz", s.tilt_z)]) + (" order=1" if s.order else "")
    if isinstance(s, ParaxialSurface):
        return f"f={float(s.focal_length):.6g}"
    if isinstance(s, Grating):  # PARM 1, 2: lines per µm, order
        return f"T={float(s.lines_per_um):.6g}/um M={float(s.order):.4g}"
    if isinstance(s, TiltedPlane):  # PARM 1, 2: the slopes dz/dx, dz/dy
        return _nonzero([("tan_x", s.tan_x), ("tan_y", s.tan_y)])
    if isinstance(s, QTypeAsphere):  # Q-bfs or Q-con, normalisation radius, a_0 … a_M
        return f"Q{s.qtype} R={float(s.norm_radius):.6g} " + _nonzero(
            (f"a{i}", v) for i, v in enumerate(np.asarray(s.coeffs)))
    if isinstance(s, XYPolynomial):  # normalisation radius, A_i on (x/R)^m (y/R)^n
        return f"R={float(s.norm_radius):.6g} " + _nonzero(
            ("X{}Y{}".format(*xy_term_powers(i)), v)
            for i, v in enumerate(np.asarray(s.coeffs), 1))
    if isinstance(s, OddAsphere):  # A<i> multiplies r^i
        return _nonzero((f"A{i}", v) for i, v in enumerate(np.asarray(s.coeffs), 1))
    out = []
    if isinstance(s, Toroidal):  # coeffs on y², y⁴, …; the x radius of curvature
        out.append(_nonzero([("Rx", 1.0 / float(s.cx) if float(s.cx) else 0.0)]))
        out.append(_nonzero((f"Y{2 * (i + 1)}", v) for i, v in enumerate(np.asarray(s.coeffs))))
    if isinstance(s, Biconic):  # PARM 1, 2: the x radius and conic
        out.append(_nonzero([("Rx", 1.0 / float(s.cx) if float(s.cx) else 0.0),
                             ("kx", s.kx)]))
    if isinstance(s, EvenAsphere | Hybrid | Binary2 | ZernikeSag):
        out.append(_nonzero((f"A{2 * (i + 1)}", v) for i, v in enumerate(np.asarray(s.coeffs))))
    if isinstance(s, Binary2):  # order, normalisation radius, phase terms on ρ², ρ⁴, …
        out.append(f"M={float(s.order):.4g} R={float(s.norm_radius):.6g}")
        out.append(_nonzero((f"P{2 * (i + 1)}", v)
                            for i, v in enumerate(np.asarray(s.phase_coeffs))))
    if isinstance(s, ZernikeSag):  # Zernike terms on the normalisation radius R
        out.append(f"R={float(s.norm_radius):.6g} " + _nonzero(
            (f"Z{i}", v) for i, v in enumerate(np.asarray(s.zernike), 1)))
        out.append(_nonzero([("dx", s.decenter_x), ("dy", s.decenter_y)]))
    if isinstance(s, Hybrid):
        out.append(_nonzero((f"{ax}{2 * i + 3}", v) for ax, arr in (("X", s.odd_x), ("Y", s.odd_y))
                            for i, v in enumerate(np.asarray(arr))))
    return " ".join(t for t in out if t)


def _surface_table(lens: Lens) -> list[str]:
    head = (
        f"  {'Surf':<5}{'Type':<10}{'Radius':>13}{'Thickness':>13}  {'Glass':<16}"
        f"{'Semi-dia':>10}{'Conic':>11}  Aspheric"
    )
    lines = [head]

    def row(label, s, t, glass):
        c = float(s.c) if s is not None else 0.0
        r = math.inf if c == 0 else 1.0 / c
        typ = "STANDARD" if s is None else _ZEMAX_TYPE.get(type(s), type(s).__name__.upper())
        if isinstance(s, ZernikeSag):
            typ = "SZERNSAG" if s.ordering == "standard" else "FZERNSAG"
        sd = float(s.semi_diameter) if s is not None else math.inf
        k = float(s.k) if s is not None else 0.0
        asph = _terms(s) if s is not None else ""
        sd_txt = _num(sd, 10, 4) if math.isfinite(sd) else f"{'-':>10}"
        lines.append(
            f"  {label:<5}{typ:<10}{_num(r, 13, 6)}{_num(t, 13, 6, '')}  {glass:<16}"
            f"{sd_txt}{k:>11.4g}  {asph.strip()}"
        )

    dist = math.inf if lens.object_distance is None else float(lens.object_distance)
    row("OBJ", None, dist, _material_label(lens.object_material))
    for i, s in enumerate(lens.surfaces):
        label = "STO" if i == lens.stop else str(i + 1)
        glass = "MIRROR" if i in lens.mirrors else _material_label(lens.materials[i])
        row(label, s, float(lens.thickness[i]), glass)
    row("IMA", lens.image, None, "")
    return lines


def format_report(data: dict, lens: Lens | None = None) -> str:
    """The human-readable report (Zemax-like prescription and field tables)."""
    if data.get("afocal_image_space"):
        return format_afocal_report(data, None if lens is None else _surface_table(lens))
    if data.get("object_space_telecentric"):
        return format_telecentric_report(data, None if lens is None else _surface_table(lens))
    ep, xp = data["entrance_pupil"], data["exit_pupil"]
    wl = data["wavelengths"]
    rows = [
        ("Effective focal length (in air)", data["efl"], "mm"),
        ("Effective focal length (img space)", data["efl_image_space"], "mm"),
        ("Back focal length", data["bfl"], "mm"),
        ("Image space F/#", data["fnum"], ""),
        ("Paraxial working F/#", data["working_fnum"], ""),
        ("Entrance pupil diameter", data["epd"], "mm"),
        ("Entrance pupil position (z)", ep["z"], "mm"),
        ("Exit pupil diameter", xp["diameter"], "mm"),
        ("Exit pupil position (from image)", xp["from_image"], "mm"),
        ("Full field of view", data["fov"], "deg"),
        ("Paraxial image height", data["image_height"], "mm"),
        ("Real chief-ray image height", data["real_image_height"], "mm"),
        ("Total track", data["total_track"], "mm"),
        ("Object distance", math.inf if data["object_distance"] is None
         else data["object_distance"], "mm"),
    ]
    L = system_lines(data, "SYSTEM DATA", rows, aiming_line(data),
                     None if lens is None else _surface_table(lens))
    L.append("")
    L.append(
        "FIELDS (heights in mm, distortion in %, RMS spot radius about the centroid in um,"
        " 21x21 pupil grid)"
    )
    spot_heads = "".join(f"{f'RMS {1000 * w:.1f}nm':>15}" for w in wl)
    xy = any(isinstance(f["angle"], list) for f in data["fields"])
    if xy:
        L.append("  (x, y fields: heights and distortion along each field's direction)")
    L.append(
        f"  {'Field':>5}" + (f"{'Angle x, y':>17}{'Chief x, y':>25}{'Parax h':>13}" if xy
                             else f"{'Angle':>9}{'Chief y':>13}{'Parax y':>13}")
        + f"{'Dist f-tan':>12}{'Dist parax':>12}{spot_heads}{'RMS poly':>12}"
    )
    for i, f in enumerate(data["fields"]):
        spots = "".join(_num(v, 15, 4) for v in f["rms_spot"])
        if xy:
            a = f["angle"] if isinstance(f["angle"], list) else [0.0, f["angle"]]
            cx, cy = f["chief_ray_xy"]
            head = (f"{a[0]:>8.3f},{a[1]:>8.3f}{_num(cx, 12, 6)},{_num(cy, 12, 6)}")
        else:
            head = f"{f['angle']:>9.3f}{_num(f['chief_ray_height'], 13, 6)}"
        L.append(
            f"  {i + 1:>5}{head}"
            f"{_num(f['paraxial_image_height'], 13, 6)}{_num(f['distortion'], 12, 5)}"
            f"{_num(f['distortion_paraxial'], 12, 5)}{spots}"
            f"{_num(f['rms_spot_polychromatic'], 12, 4)}"
        )
        lost = [
            f"{100 * (1 - v):.1f}% at {w:.4f} um"
            for w, v in zip(wl, f["valid_fraction"], strict=True)
            if v < 1
        ]
        if lost:
            L.append(f"        field {i + 1}: rays clipped or failed: " + ", ".join(lost))
    L.append("")
    L.append("FIELD CURVATURE (primary wavelength; tangential and sagittal foci in mm from "
             "the image surface along z, + behind it"
             + ("; tangential plane along each field's direction)" if xy else ")"))
    L.append(f"  {'Field':>5}" + (f"{'Angle x, y':>17}" if xy else f"{'Angle':>9}")
             + f"{'Tangential':>13}{'Sagittal':>13}{'Astigmatism':>13}")
    for i, f in enumerate(data["fields"]):
        t, s = f["focus_tangential"], f["focus_sagittal"]
        astig = None if t is None or s is None else t - s
        if xy:
            a = f["angle"] if isinstance(f["angle"], list) else [0.0, f["angle"]]
            head = f"{a[0]:>8.3f},{a[1]:>8.3f}"
        else:
            head = f"{f['angle']:>9.3f}"
        L.append(f"  {i + 1:>5}{head}{_num(t, 13, 6)}{_num(s, 13, 6)}{_num(astig, 13, 6)}")
    L += wavefront_lines(data["fields"], "the exit-pupil reference sphere")
    L += seidel_lines(data.get("seidel"), "field {:.3f} deg")
    return "\n".join(L) + "\n"


# ---------------------------------------------------------------------------- CLI


def register(subparsers) -> None:
    """Add the ``report`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "report",
        help="print system data, distortion and RMS spots of a lens file",
        description="Paraxial system data and, per field, the real chief-ray height, "
        "distortion and RMS spot radius per wavelength of a .json or .zmx lens.",
    )
    p.add_argument("lens", help="lens file (.json or .zmx)")
    p.add_argument("--json", action="store_true", help="print a JSON object instead of tables")
    p.add_argument(
        "--fields",
        type=checks.cli_float,
        nargs="+",
        metavar="DEG",
        help="field angles in degrees, object heights in mm for an object-space telecentric "
        "lens (default: the lens's fields)",
    )
    p.add_argument(
        "--wavelengths",
        type=checks.cli_float,
        nargs="+",
        metavar="UM",
        help="wavelengths in um (values above 100 are read as nm; default: the lens's wavelengths)",
    )
    p.add_argument(
        "--unknown-glass",
        choices=("error", "model"),
        help=".zmx glasses in no catalog: refuse (error, the default) or use a model glass of "
        "the nd and Vd on their GLAS line (with a warning)",
    )
    p.add_argument(
        "--plot",
        metavar="DIR",
        help="also write the layout, spot diagrams, ray fans, field curvature with distortion, "
        "MTF, wavefront map, OPD fans, Seidel diagram and encircled energy as "
        "DIR/<lens>_layout.png, _spots.png, _fans.png, _field.png, _mtf.png, _wavefront.png, "
        "_opd.png, _seidel.png and _ee.png (DIR is created; existing files are kept unless "
        "--overwrite; a lens the wavefront or Seidel analysis refuses gets the others)",
    )
    p.add_argument("--overwrite", action="store_true", help="with --plot: replace the figures")
    p.add_argument(
        "--wavefront",
        action="store_true",
        help="also give each field's wavefront error at the primary wavelength (RMS and P-V "
        "in waves, Marechal Strehl)",
    )
    p.add_argument(
        "--lenient",
        action="store_true",
        help=".zmx: read as jaxlens.load does by default, warning (instead of refusing) about "
        "settings jaxlens does not use (unknown keywords, an environment other than 20 C and "
        "1 atm) and a file cut off mid-line",
    )
    p.add_argument(
        "--config",
        type=checks.cli_int,
        metavar="N",
        help=".zmx multi-configuration file (zoom, focus positions): read configuration N "
        "(1-based, Zemax's numbering; default: the active one, which the file's surfaces hold)",
    )
    p.add_argument(
        "--list-configs",
        action="store_true",
        help=".zmx: list the file's configurations and the operands that differ between them, "
        "then stop",
    )
    p.set_defaults(func=run)


def _load_lens(args: argparse.Namespace) -> Lens:
    """The lens of ``args.lens`` (``--config``: that configuration of a .zmx file)."""
    return load(args.lens, strict=not args.lenient, unknown_glass=args.unknown_glass or "error",
                config=args.config)


def _config_value(v) -> str:
    """A configuration operand's value text for ``--list-configs``: numbers to 10 digits."""
    if v is None:
        return "-"
    try:
        return f"{float(v):.10g}"
    except ValueError:
        return v[:16]


def _list_configs(path: str) -> int:
    """Print the configurations of a .zmx file (``--list-configs``)."""
    if os.path.splitext(path)[1].lower() != ".zmx":
        raise ValueError(f"--list-configs lists a .zmx file's configurations; {path} is not one")
    info = configurations(path)
    n = info["count"]
    print(f"{path}: {n} configuration{'s' if n > 1 else ''}; active (the surfaces): "
          f"{info['active']}")
    if info["operands"]:
        print(f"  {'operand':<10}" + "".join(f" {'config ' + str(c):>16}" for c in range(1, n + 1)))
        for op in info["operands"]:
            vals = "".join(f" {_config_value(v):>16}" for v in op["values"])
            print(f"  {op['operand'] + ' ' + str(op['param']):<10}{vals}")
    return 0


FIGURES = ("layout", "spots", "fans", "field", "mtf", "wavefront", "opd", "seidel", "ee")
ANALYSIS_FIGURES = ("wavefront", "opd", "seidel")
"""Figures of analyses that refuse some lenses (coordinate breaks, toroids, …): such a lens
gets the others, and a message that names the figure and the reason."""


def figure_paths(lens_path: str, folder: str, overwrite: bool) -> dict[str, str]:
    """Where ``--plot`` writes each figure, checked before any work: the folder must be
    creatable and writable, and no figure may be replaced without ``overwrite``."""
    stem = os.path.splitext(os.path.basename(lens_path))[0]
    paths = {k: os.path.join(folder, f"{stem}_{k}.png") for k in FIGURES}
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise ValueError(f"--plot {folder} is a file, not a folder")
    there = [p for p in paths.values() if os.path.exists(p)]
    if there and not overwrite:
        raise ValueError(f"--plot: {there[0]} exists; give --overwrite to replace the figures, "
                         f"or choose another folder")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        raise ValueError(f"--plot {folder} cannot be created: {e.strerror}") from None
    if not os.access(folder, os.W_OK):
        raise ValueError(f"--plot {folder} is not writable")
    return paths


def _write_figures(lens: Lens, paths: dict[str, str]) -> None:
    """Draw and save the figures, with a bar on stderr where someone watches it (not into a
    file or pipe): each figure takes seconds to tens of seconds, mostly compiling its program
    of traced rays."""
    from tqdm.auto import tqdm

    from .. import plot

    makers = {"layout": plot.plot_layout, "spots": plot.plot_spots, "fans": plot.plot_ray_fans,
              "field": plot.plot_field_curvature, "mtf": plot.plot_mtf,
              "wavefront": plot.plot_wavefront, "opd": plot.plot_opd_fans,
              "seidel": plot.plot_seidel, "ee": plot.plot_encircled_energy}
    with tqdm(total=len(paths), desc="figures", unit="figure", file=sys.stderr,
              disable=not sys.stderr.isatty(), leave=False, dynamic_ncols=True) as bar:
        for key, path in paths.items():
            bar.set_postfix_str(key)
            try:
                fig = makers[key](lens)
            except ValueError as e:
                if key not in ANALYSIS_FIGURES and not lens.afocal_image:  # afocal: angles
                    raise
                bar.write(f"jaxlens report: --plot: {os.path.basename(path)} not drawn: {e}",
                          file=sys.stderr)
                bar.update()
                continue
            plot.save(fig, path)
            bar.update()


ZMX_OPTIONS = (("--lenient", "lenient", "reads a .zmx file past what jaxlens does not model"),
               ("--unknown-glass", "unknown_glass", "chooses what a .zmx GLAS line naming a "
                "glass in no catalog becomes"),
               ("--config", "config", "selects a configuration of a multi-configuration .zmx "
                "file"))
"""The options that only a .zmx lens reads: (option, argument, what it does)."""


def _zmx_options_only_with_zmx(args: argparse.Namespace) -> None:
    """Refuse an option of ``ZMX_OPTIONS`` given with a lens that is no .zmx file: it did
    nothing there (``--unknown-glass error``, ``--lenient``), or the error named the load
    function's argument (``unknown_glass='model'``, ``config=1``), not the option."""
    if args.lens.lower().endswith(".zmx"):
        return
    for option, name, what in ZMX_OPTIONS:
        value = getattr(args, name)
        if value is not None and value is not False:
            raise ValueError(f"{option} {what}, so it applies to a .zmx lens only; "
                             f"{args.lens} is no .zmx file: leave it out")


def run(args: argparse.Namespace) -> int:
    """Run the ``report`` subcommand; returns the exit status."""
    try:
        if args.overwrite and args.plot is None:
            raise ValueError("--overwrite replaces --plot figures; it needs --plot DIR")
        if args.plot is not None and not args.plot.strip():
            raise ValueError("--plot needs a folder name, got an empty one")
        if args.list_configs:
            ignored = [o for o, v in (("--json", args.json), ("--fields", args.fields),
                                      ("--wavelengths", args.wavelengths),
                                      ("--wavefront", args.wavefront), ("--plot", args.plot),
                                      ("--config", args.config),
                                      ("--unknown-glass", args.unknown_glass),
                                      ("--lenient", args.lenient))
                       if v is not None and v is not False]  # --config 0 too
            if ignored:  # the listing is text about every configuration: they would do nothing
                raise ValueError(f"--list-configs lists the configurations and stops; "
                                 f"{', '.join(ignored)} would be ignored: leave "
                                 f"{'it' if len(ignored) == 1 else 'them'} out")
            return _list_configs(args.lens)
        if args.config is not None:  # before the file is read (a .json file named "config=0")
            checks.number(args.config, "--config", "report", lo=1, integer=True,
                          unit="(Zemax's 1-based configuration number)")
        _zmx_options_only_with_zmx(args)
        paths = figure_paths(args.lens, args.plot, args.overwrite) if args.plot else None
        # strict by default: a report must not describe a truncated file, nor rays that a
        # setting jaxlens does not use would have changed, without being asked
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            lens = _load_lens(args)
        for w in caught:
            print(f"jaxlens report: warning: {w.message}", file=sys.stderr)
        shown = with_fields_and_wavelengths(lens, args.fields, args.wavelengths)
        data = report_data(shown, wavefront=args.wavefront)
    except (ValueError, OSError) as e:
        hint = "" if args.lenient or "(strict mode)" not in str(e) else (
            " (--lenient reads the file anyway, with a warning)")
        if isinstance(e, OSError) and e.filename is not None:  # not "[Errno 2] …"
            e = f"{e.filename}: {e.strerror.lower() if e.strerror else e}"
        print(f"jaxlens report: error: {e}{hint}", file=sys.stderr)
        return 2
    data["file"] = args.lens
    if args.json:
        print(json.dumps(data, indent=2, allow_nan=False))
    else:
        print(format_report(data, shown), end="")
    if paths:  # after the report, so that a figure that cannot be made does not lose it
        try:
            _write_figures(shown, paths)
        except (ValueError, OSError) as e:
            print(f"jaxlens report: error: --plot: {e}", file=sys.stderr)
            return 2
    return 0
