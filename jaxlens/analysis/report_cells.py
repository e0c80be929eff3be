"""Pieces that the lens report and the afocal report share: JSON numbers, table cells, and
each field's wavefront error (summary and table), the Seidel sums; and the field-curvature
call that the report and its ``--plot`` figure share (``bucketed_field_curvature``).

These are the reports' internal helpers (public names only because several report modules
import them): they take the reports' own data, and check only that each argument has the
kind they format (a number, a dict, a str; a TypeError naming the helper otherwise), not
its meaning."""

from __future__ import annotations

import math
import numbers

import jax.numpy as jnp
import numpy as np

from ..optics.lens import Lens
from .aberrations import FieldCurvature, field_curvature
from .third_order import SEIDEL_TERMS, WAVEFRONT_TERMS, seidel
from .wavefront_error import MARECHAL_MAX_RMS
from .wavefront_error import wavefront as wavefront_map


def real_number(x, arg: str, where: str) -> float:
    """``x`` as a float if it is one real number (a Python, NumPy or 0-d JAX int or float);
    a TypeError naming ``where`` and ``arg`` otherwise (before: ``json_number("1.5")`` was
    1.5, a bool a 0/1, a complex or a str failed in Python's words)."""
    kind = np.asarray(x).dtype.kind if hasattr(x, "dtype") and np.ndim(x) == 0 else ""
    if isinstance(x, bool) or not (isinstance(x, numbers.Real) or kind in ("i", "u", "f")
                                   and kind):
        raise TypeError(f"{where}: {arg} must be one real number, got {type(x).__name__} "
                        f"{x!r}"[:200])
    return float(x)


def json_number(x) -> float | None:
    """A finite float, or None (JSON has no NaN or inf; the text says "failed")."""
    v = real_number(x, "x", "json_number")
    return v if math.isfinite(v) else None


INFINITE = {"inf": math.inf, "-inf": -math.inf}
"""``json_extent``'s strings for the infinite values JSON cannot hold (the lens files' too)."""


def json_extent(x) -> float | str | None:
    """A first-order distance, size or ratio for the report's JSON: the float, "inf" or
    "-inf" where the optics puts it at infinity (an exit pupil of an image-space
    telecentric lens, a BFL of an image at infinity), None where it has no value (NaN).
    ``json_number`` gave None for both, and the text said "failed" for a pupil at infinity."""
    v = real_number(x, "x", "json_extent")
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return None if math.isnan(v) else v


def cell(v: float | str | None, width: int = 12, prec: int = 6,
         missing: str = "failed") -> str:
    """A table cell: ``missing`` for None (no valid ray, no paraxial image), "Infinity" for
    an infinite distance (a float, or ``json_extent``'s "inf"/"-inf"), and scientific
    notation where fixed point would not fit."""
    if isinstance(v, str) and v in INFINITE:
        v = INFINITE[v]
    for arg, n, lo in (("width", width, 1), ("prec", prec, 0)):
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < lo:
            raise TypeError(f"cell: {arg} must be a whole number >= {lo} (characters), got "
                            f"{n!r}")
    if not isinstance(missing, str):
        raise TypeError(f"cell: missing must be a str, got {missing!r}")
    v = None if v is None else real_number(v, "v", "cell")
    if v is None or math.isnan(v):
        return f"{missing:>{width}}"
    if math.isinf(v):
        return f"{'Infinity' if v > 0 else '-Infinity':>{width}}"
    text = f"{v:.{prec}f}"
    if len(text) >= width or (v != 0 and abs(v) < 10.0**-prec):
        text = f"{v:.{max(1, min(prec, width - 8))}e}"
    return f"{text:>{width}}"


AIMING_TEXT = {"paraxial": "paraxial (rays through the paraxial entrance pupil)",
               "real": "real (rays aimed at the real stop)",
               "real_marginal": "real marginal (rays aimed at the real stop, sized by the "
                                "real marginal ray)"}
"""The report's words for each ``Lens.aim``."""


def aiming_line(data: dict) -> str:
    """The report line that says which ray aiming its rays used (``data["ray_aiming"]``;
    a report written before the key existed used paraxial aiming)."""
    _dict(data, "data", "aiming_line")
    aim = data.get("ray_aiming", "paraxial")
    return f"  {'Ray aiming':<34}: {AIMING_TEXT.get(aim, aim)}"



def system_lines(data: dict, heading: str, rows: list[tuple], launch: str,
                 surface_table: list[str] | None) -> list[str]:
    """A report's opening, shared by the three report kinds: title and file, the SYSTEM DATA
    block (``rows``: label, value, unit), stop surface, the ray-launch line, wavelengths,
    notes and the prescription's lines."""
    L = [f"jaxlens lens report: {data.get('name') or '(unnamed lens)'}"]
    if data.get("file"):
        L.append(f"File: {data['file']}")
    L += ["", heading]
    for label, v, unit in rows:
        L.append(f"  {label:<34}: {cell(v, 14, 6)} {unit}".rstrip())
    L.append(f"  {'Stop surface':<34}: {data['stop_surface']:>14d}")
    L.append(launch)
    L.append(f"  {'Wavelengths (um)':<34}: " + ", ".join(
        f"{w:.6f}" + (" (primary)" if w == data["primary_wavelength"] else "")
        for w in data["wavelengths"]))
    L += [f"  Note: {note}" for note in data.get("notes", ())]
    if surface_table:
        L += ["", "SURFACE DATA (radius, thickness, semi-diameter in mm; glass: name or nd,Vd)"]
        L += surface_table
    return L


def seidel_lines(sd: dict | None, field: str) -> list[str]:
    """The report's SEIDEL SUMS block (``sd``: ``seidel_summary``'s dict, or None for no
    block); ``field`` names the field it was computed at, a template for ``sd["field"]``
    with its unit (``"field {:.3f} deg"``)."""
    if sd is not None:
        _dict(sd, "sd", "seidel_lines")
    if not isinstance(field, str):
        raise TypeError(f"seidel_lines: field must be a str (a template such as "
                        f"'field {{:.3f}} deg'), got {field!r}")
    if not sd:
        return []
    if "refused" in sd:
        return ["", f"SEIDEL SUMS: not computed ({sd['refused']})"]
    return ["", f"SEIDEL SUMS (third order, {field.format(sd['field'])}, "
                f"{sd['wavelength']:.6f} um; S in mm, W in waves)",
            "  " + "".join(f"{k:>12}" for k in sd["sums"]),
            "  " + "".join(cell(v, 12, 6) for v in sd["sums"].values()),
            "  " + "".join(f"{k:>12}" for k in sd["wavefront"]),
            "  " + "".join(cell(v, 12, 4) for v in sd["wavefront"].values())]

def wavefront_summary(lens: Lens, field) -> dict:
    """One field's wavefront error (waves, primary wavelength; referenced as the lens's image
    space asks: a sphere, or a plane for an afocal lens), or why there is none."""
    try:
        w = wavefront_map(lens, field)
    except ValueError as e:
        return {"refused": str(e)}
    sigma = json_number(w.rms_tilt_removed)
    strehl = json_number(w.strehl) if sigma is not None and sigma <= MARECHAL_MAX_RMS else None
    return {"rms": json_number(w.rms), "pv": json_number(w.pv), "rms_tilt_removed": sigma,
            "pv_tilt_removed": json_number(w.pv_tilt_removed), "strehl": strehl}


def wavefront_lines(fields: list[dict], reference: str) -> list[str]:
    """The WAVEFRONT ERROR table of the fields that have a ``wavefront`` entry (none: [])."""
    if not isinstance(fields, (list, tuple)) or not all(isinstance(f, dict) for f in fields):
        raise TypeError(f"wavefront_lines: fields must be a list of the report's field dicts, "
                        f"got {fields!r}"[:200])
    if not isinstance(reference, str):
        raise TypeError(f"wavefront_lines: reference must be a str (what the wavefront is "
                        f"referenced to, e.g. 'the exit-pupil sphere'), got {reference!r}")
    if not any("wavefront" in f for f in fields):
        return []
    out = ["", f"WAVEFRONT ERROR (primary wavelength, waves, to {reference}; piston removed; "
               f"Strehl: Marechal, tilt removed, given where RMS -tilt <= "
               f"{MARECHAL_MAX_RMS:g} wave)",
           f"  {'Field':>5}{'RMS':>12}{'P-V':>12}{'RMS -tilt':>12}{'P-V -tilt':>12}"
           f"{'Strehl':>10}"]
    for i, f in enumerate(fields):
        w = f.get("wavefront", {})
        if "refused" in w:
            out.append(f"  {i + 1:>5}  not computed ({w['refused']})")
            continue
        out.append(f"  {i + 1:>5}{cell(w['rms'], 12, 4)}{cell(w['pv'], 12, 4)}"
                   f"{cell(w['rms_tilt_removed'], 12, 4)}{cell(w['pv_tilt_removed'], 12, 4)}"
                   f"{cell(w['strehl'], 10, 4, '-')}")
    return out


def _dict(data, arg: str, where: str) -> None:
    if not isinstance(data, dict):
        raise TypeError(f"{where}: {arg} must be the report's data (a dict), got "
                        f"{type(data).__name__} {data!r}"[:200])


FIELD_BUCKET = 32
"""``bucketed_field_curvature`` pads θy fields to a multiple of this many."""


def bucketed_field_curvature(lens: Lens, fields, wavelengths=None) -> FieldCurvature:
    """``aberrations.field_curvature(lens, fields, wavelengths)``, the same numbers, computed
    on θy fields padded (with the last field) to a multiple of ``FIELD_BUCKET`` and cut back.

    Why: the report's fields (the lens's, primary wavelength) and the field-curvature
    figure's (21 fields, every wavelength) then share one compiled program; with ray aiming
    (rayoptics_US00583336, ``aim="real_marginal"``) each program took about 8 s to trace and
    compile, the 32 chief rays per wavelength a few ms to trace. Each field's rays are
    traced alone (vmap), so the padding changes no value. (θx, θy) fields are not padded.
    """
    f = jnp.asarray(fields, lens.epd.dtype)
    n = f.shape[0] if f.ndim == 1 else 0
    pad = -n % FIELD_BUCKET
    if f.ndim != 1 or pad == 0:
        return field_curvature(lens, f, wavelengths)
    fc = field_curvature(lens, jnp.concatenate([f, jnp.full((pad,), f[-1], f.dtype)]),
                         wavelengths)
    return FieldCurvature(f, fc.wavelengths, fc.tangential[:, :n], fc.sagittal[:, :n])


def seidel_summary(lens: Lens) -> dict:
    """The lens's Seidel sums (mm) and their wavefront terms (waves) at the primary
    wavelength and largest field (angle in deg, or object height in mm), or why third-order
    theory does not apply."""
    try:
        s = seidel(lens)
    except ValueError as e:
        return {"refused": str(e)}
    return {"field": json_number(s.field), "wavelength": json_number(s.wavelength),
            "sums": {k: json_number(v) for k, v in zip(SEIDEL_TERMS, s.sums, strict=True)},
            "wavefront": {k: json_number(v) for k, v in zip(WAVEFRONT_TERMS, s.wavefront(),
                                                            strict=True)}}
