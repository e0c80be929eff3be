"""JSON lens files: ``jaxlens.lens/1``, documented in ``docs/lens-format.md``.

Conventions:
    Lengths in mm, angles in degrees. Wavelengths are written in µm
    (``wavelengths_um``); files may give them in nm instead (``wavelengths_nm``, and
    ``n`` tables keyed by wavelengths in nm). ``surfaces[0]`` is the object (its
    ``thickness`` is the object distance, ``"inf"`` for an object at infinity), the last
    entry is the image surface, and every entry in between is a lens surface whose
    ``thickness`` is the vertex distance to the next surface and whose ``material`` is
    the medium after it. The last lens surface's material is image space.

The format is a superset of the reference cases in ``tests/refcases`` (object surface,
image surface, ``n`` dicts keyed by nm, ``aperture.EPD``, ``fields.values``,
``wavelengths_nm``, ``primary_wavelength_nm``), so files written that way load as they
are. Informational keys such as ``semi_diameter_real_rays`` are ignored, never used to
clip rays; a near miss or a synonym of a key the reader knows (``"radus"``, ``"glass"``,
``"R"``, ``"k"``) is refused (``lens_keys``), as are a ``fields`` or ``object`` object
without ``values`` or ``distance`` and ``units`` other than mm. ``fields.vignetting``
holds ``Lens.vignetting`` (Zemax's vignetting factors) as one list per factor, one value per
field: ``{"vdx": [...], "vdy": [...], "vcx": [...], "vcy": [...], "van_deg": [...]}`` (pupil
radii; ``van_deg`` in degrees; a missing list is 0). ``"afocal_image_space": true`` marks
an afocal image space (``Lens.afocal_image``; written only when true). ``"ray_aiming"``
is the lens's ray aiming (``Lens.aim``): ``"paraxial"`` (the default: rays through the
paraxial entrance pupil), ``"real"`` (aimed at the real stop, sized paraxially) or
``"real_marginal"`` (the stop sized by the real marginal ray); written only when not
paraxial. ``"object_space_telecentric": true`` marks an object-space telecentric lens
(``Lens.object_na``; written only when true): its aperture is ``aperture.object_na`` (or
``aperture.stop_semi_diameter``) and its fields are object heights in mm (``fields.type``
``"object_height_mm_y"`` or ``"object_height_mm_xy"``), both required; an EPD or F/#
aperture, field angles or an object at infinity are refused.
``"negative_propagation": true`` lets rays go back along their line to any surface after the
first, as Zemax does (``Lens.negative_propagation``, set for lenses read
from ``.zmx`` files); written only when true (a file without it traces by the default rule).

Saving writes every number with Python's shortest round-trip representation, so
``load(save(lens))`` gives the same numbers to the last bit (as float64), the same
surface and material types and the same system data.
"""

from __future__ import annotations

import difflib
import json
import math
import os
import re
import warnings
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..optics import checks, paraxial, travel
from ..optics.coordinates import CoordinateBreak
from ..optics.input_files import input_file
from ..optics.lens import INFINITE_OBJECT_MM, RAY_AIMING, Lens, Sensor
from ..optics.materials import Air
from ..optics.qtype import QTypeAsphere
from ..optics.surfaces import AbstractSurface, EvenAsphere, Hybrid, OddAsphere, Standard
from . import lens_keys, lens_system, surface_json
from .json_values import (
    RepeatedKey,
    curvature,
    loadable,
    nm_to_um,  # noqa: F401  (re-exported: analysis.report reads it here)
    output_file,
    write_whole,
)
from .json_values import float64_array as _arr
from .json_values import json_number as _out
from .json_values import num as _num
from .json_values import nums as _nums
from .json_values import pretty as _pretty
from .json_values import text as _text
from .json_values import unique_keys as _unique_keys
from .json_values import whole as _whole
from .material_spec import (  # noqa: F401  (re-exported: the .zmx modules read them here)
    INDEX_RECORD,
    catalog_material,
    check_index_record,
    index_record,
    is_catalog_glass,
    material_from_spec,
    material_to_spec,
    same_material,
)

MIN_EPD_MM = 1e-9
"""The smallest entrance pupil diameter a lens file may give (mm); a subnormal one traces as
NaN."""

FORMAT = "jaxlens.lens/1"
"""The value of the ``format`` key this module writes (name/version)."""

_SUPPORTED_FORMATS = ("jaxlens.lens/1",)
_STANDARD_TYPES = (
    "standard",
    "sphere",
    "spherical",
    "plane",
    "planar",
    "flat",
    "conic",
    "conicoid",
    "stop",
    "aperture",
    "aperturestop",
)
# The other base types, without case and punctuation. Exact names, not substrings: any type
# holding "asph" was read as an even asphere ("extended asphere", whose Zemax polynomial is
# normalised differently, or a typo such as "asphere9"), and any holding "hybrid" as a hybrid.
_EVEN_ASPHERE_TYPES = ("evenasph", "evenasphere", "evenaspheric", "asph", "asphere", "aspheric")
_ODD_ASPHERE_TYPES = ("oddasph", "oddasphe", "oddasphere", "oddaspheric")
_HYBRID_TYPES = ("hybrid", "hybridasphere")


# --------------------------------------------------------------------------------------
# surfaces


def surface_from_dict(d: dict, where: str, *, kind: str | None = None) -> AbstractSurface:
    """A surface from its JSON object; ``kind`` overrides the ``type`` key. What the surface
    class refuses (a semi-diameter beyond a steep sphere's edge, say) names ``where``."""
    try:
        with np.errstate(all="ignore"):  # a curvature of 1e308 squared: refused below
            surface = _surface(d, where, kind)
    except ValueError as e:
        raise ValueError(str(e) if str(e).startswith(where) else f"{where}: {e}") from None
    bad = nonfinite_part(surface)
    if bad:
        raise ValueError(f"{where}: {bad} (values out of range)")
    return surface


def nonfinite_part(surface: AbstractSurface) -> str:
    """What of a surface is not finite ("" if nothing): its shape numbers, or its paraxial
    curvature c + 2·a_1, which a coefficient of 1e308 overflows (a trace would give NaN)."""
    for name in ("c", "k", "coeffs", "odd_x", "odd_y", "cx", "kx", "zernike",
                 "paraxial_curvature", "paraxial_curvature_x"):
        try:
            v = getattr(surface, name, None)
        except (ValueError, TypeError):  # a surface without a paraxial curvature
            continue
        if v is not None and not np.all(np.isfinite(np.asarray(v, np.float64))):
            return f"{name} = {np.asarray(v)} is not finite"
    return ""


def _surface(d: dict, where: str, kind: str | None) -> AbstractSurface:
    raw = _text(kind or d.get("type") or "standard", f"{where}: type")
    other = surface_json.kind_of(raw)
    if other is not None:  # toroidal, paraxial, diffractive, tilted plane, coordinate break
        return surface_json.surface_from_json(other, d, where, lens_keys.SURFACE)
    # (curvature_x is a biconic's key too: the freeform reader below takes it)
    stray = sorted((surface_json.OWN_KEYS - set(surface_json.FREEFORM_KEYS)) & set(d))
    if stray:
        takes = sorted({k for k, (_, pairs) in surface_json.KINDS.items()
                        for key, _ in pairs if key in stray} | (
                        {"coordinate_break"} if "order" in stray else set()))
        raise ValueError(f"{where}: a {raw} surface does not take {', '.join(stray)} (the keys "
                         f"of type {' or '.join(takes)}); give that type, or drop the keys")
    kind = re.sub(r"[^a-z0-9]", "", raw.lower())  # "Even Asphere" == "even_asphere"
    c = curvature(d, where)
    k = _num(d.get("conic", 0.0), f"{where}: conic")
    sd = d.get("semi_diameter")
    sd = math.inf if sd is None else _num(sd, f"{where}: semi_diameter", finite=False)
    if not sd > 0:
        raise ValueError(f"{where}: semi_diameter must be > 0 (or 'inf'), got {sd!r}")
    coeffs = _nums(d.get("even_asphere_coeffs", []), f"{where}: even_asphere_coeffs")
    if coeffs.ndim != 1:
        raise ValueError(f"{where}: even_asphere_coeffs must be a flat list")
    has_odd = "odd_x" in d or "odd_y" in d
    if kind in surface_json.FREEFORM_TYPES or any(k in d for k in surface_json.FREEFORM_KEYS):
        return surface_json.freeform_from_json(d, where, raw, kind, c, k, sd, coeffs)
    qtype = _Q_TYPES.get(kind)
    if qtype is not None or "q_coeffs" in d or "norm_radius" in d:
        return _qtype_surface(d, where, raw, qtype, c, k, sd, coeffs.size or has_odd)
    # "oddasph", "Odd Asphere", "ODDASPHE"
    radial = kind in _ODD_ASPHERE_TYPES
    if radial and (has_odd or coeffs.size):
        raise ValueError(f"{where}: an odd asphere takes its terms as odd_asphere_coeffs "
                         f"(on r, r², r³, …), not even_asphere_coeffs or odd_x/odd_y")
    if "odd_asphere_coeffs" in d and not radial:
        raise ValueError(f"{where}: odd_asphere_coeffs belong to an odd asphere (type "
                         f"\"oddasph\"), not to type {raw!r}")
    if radial:
        b = _nums(d.get("odd_asphere_coeffs", []), f"{where}: odd_asphere_coeffs")
        if b.ndim != 1:
            raise ValueError(f"{where}: odd_asphere_coeffs must be a flat list")
        return OddAsphere(c=_arr(c), k=_arr(k), coeffs=_arr(b), semi_diameter=_arr(sd))
    if kind in _HYBRID_TYPES or (has_odd and kind in _STANDARD_TYPES + _EVEN_ASPHERE_TYPES):
        ox = _nums(d.get("odd_x", []), f"{where}: odd_x")
        oy = _nums(d.get("odd_y", []), f"{where}: odd_y")
        p = max(ox.size, oy.size)
        ox = np.pad(ox.reshape(-1), (0, p - ox.size))
        oy = np.pad(oy.reshape(-1), (0, p - oy.size))
        return Hybrid(
            c=_arr(c),
            k=_arr(k),
            coeffs=_arr(coeffs),
            odd_x=_arr(ox),
            odd_y=_arr(oy),
            semi_diameter=_arr(sd),
        )
    if kind in _EVEN_ASPHERE_TYPES or (kind in _STANDARD_TYPES and coeffs.size):
        return EvenAsphere(c=_arr(c), k=_arr(k), coeffs=_arr(coeffs), semi_diameter=_arr(sd))
    if kind in _STANDARD_TYPES:
        return Standard(c=_arr(c), k=_arr(k), semi_diameter=_arr(sd))
    names = ("standard", "evenasph", "oddasph", "hybrid", "qbfs", "qcon", "biconic",
             "zernike_standard", "zernike_fringe", *surface_json.KINDS)
    spelled = {re.sub(r"[^a-z0-9]", "", n): n for n in names}
    spelled |= {a: "standard" for a in _STANDARD_TYPES} | {a: "evenasph" for a in
                                                          _EVEN_ASPHERE_TYPES}
    spelled |= {a: "oddasph" for a in _ODD_ASPHERE_TYPES} | {a: "hybrid" for a in _HYBRID_TYPES}
    close = difflib.get_close_matches(kind, list(spelled), n=1, cutoff=0.75)
    raise ValueError(f"{where}: unknown surface type {raw!r}"
                     f"{f' (did you mean {spelled[close[0]]!r}?)' if close else ''}; use "
                     f"{', '.join(names)}")


_Q_TYPES = {"qbfs": "bfs", "qcon": "con"}  # the type key without case and punctuation


def _qtype_surface(d: dict, where: str, raw: str, qtype, c, k, sd, other_terms) -> QTypeAsphere:
    """A Forbes Q-type asphere (type "qbfs" or "qcon") from its JSON object."""
    if qtype is None:
        raise ValueError(f"{where}: q_coeffs and norm_radius belong to a Q-type asphere (type "
                         f"\"qbfs\" or \"qcon\"), not to type {raw!r}")
    if other_terms or "odd_asphere_coeffs" in d:
        raise ValueError(f"{where}: a Q-type asphere takes its terms as q_coeffs (a_0, a_1, … "
                         f"in mm), not even_asphere_coeffs, odd_asphere_coeffs or odd_x/odd_y")
    if "norm_radius" not in d:
        raise ValueError(f"{where}: a Q-type asphere needs norm_radius (the normalisation "
                         f"radius, mm)")
    rn = _num(d["norm_radius"], f"{where}: norm_radius")
    if not rn > 0:
        raise ValueError(f"{where}: norm_radius must be > 0 (mm), got {d['norm_radius']!r}")
    a = _nums(d.get("q_coeffs", []), f"{where}: q_coeffs")
    if a.ndim != 1:
        raise ValueError(f"{where}: q_coeffs must be a flat list")
    return QTypeAsphere(c=_arr(c), k=_arr(k), coeffs=_arr(a), norm_radius=_arr(rn),
                        semi_diameter=_arr(sd), qtype=qtype)


def surface_to_dict(s: AbstractSurface) -> dict:
    """The JSON object of a surface (without thickness and material)."""
    other = surface_json.surface_to_json(s)
    if other is not None:
        return other
    if isinstance(s, QTypeAsphere):
        d = {"type": "q" + s.qtype}
    elif isinstance(s, Hybrid):
        d = {"type": "hybrid"}
    elif isinstance(s, EvenAsphere):
        d = {"type": "evenasph"}
    elif isinstance(s, OddAsphere):
        d = {"type": "oddasph"}
    elif isinstance(s, Standard):
        d = {"type": "standard"}
    else:
        raise ValueError(f"save: a {type(s).__name__} surface has no jaxlens JSON form yet; "
                         f"save the lens as .zmx")
    d["curvature"] = _out(s.c)
    d["conic"] = _out(s.k)
    if isinstance(s, EvenAsphere | Hybrid):
        d["even_asphere_coeffs"] = _out(s.coeffs)
    if isinstance(s, OddAsphere):
        d["odd_asphere_coeffs"] = _out(s.coeffs)
    if isinstance(s, QTypeAsphere):
        d["norm_radius"] = _out(s.norm_radius)
        d["q_coeffs"] = _out(s.coeffs)
    if isinstance(s, Hybrid):
        d["odd_x"] = _out(s.odd_x)
        d["odd_y"] = _out(s.odd_y)
    if np.isfinite(np.asarray(s.semi_diameter)):
        d["semi_diameter"] = _out(s.semi_diameter)
    return d


# --------------------------------------------------------------------------------------
# lens


def apply_aperture(lens: Lens, *, epd=None, fnum=None, stop_semi_diameter=None) -> Lens:
    """Set ``lens.epd`` from one aperture specification.

    ``fnum`` is the image-space F-number at infinite conjugates, EFL/EPD, with the EFL at
    the primary wavelength. ``stop_semi_diameter`` (mm) gives the EPD as the paraxial
    image of the stop in object space; it does not clip rays at the stop.
    """
    given = [x is not None for x in (epd, fnum, stop_semi_diameter)]
    if sum(given) != 1:
        raise ValueError("aperture: give exactly one of epd, fnum, stop_semi_diameter")
    # Each by name first: fnum -4 gave the EPD of F/4 (the EPD's sign is dropped for a
    # negative focal length), a string failed in a division, NaN, 0 or a negative EPD read
    # "the entrance pupil diameter comes out as ..." without the argument.
    for arg, v in (("epd", epd), ("fnum", fnum), ("stop_semi_diameter", stop_semi_diameter)):
        if v is not None:
            checks.number(v, arg, "apply_aperture", lo=0, lo_open=True,
                          unit="" if arg == "fnum" else "mm")
    if epd is not None:
        value = jnp.asarray(epd, lens.thickness.dtype)
    elif fnum is not None:
        value = paraxial.efl(lens) / fnum
    else:
        m = paraxial.entrance_pupil_magnification(lens)
        value = 2.0 * stop_semi_diameter / jnp.abs(m)
    value = jnp.abs(value) if fnum is not None else value
    if not bool(jnp.isfinite(value)) or not float(value) > 0:
        raise ValueError(f"aperture: the entrance pupil diameter comes out as {float(value)}")
    if not MIN_EPD_MM <= float(value) < INFINITE_OBJECT_MM:  # 1e-320 mm traces as NaN
        raise ValueError(f"aperture: the entrance pupil diameter must be in [{MIN_EPD_MM:g}, "
                         f"{INFINITE_OBJECT_MM:g}) mm, got {float(value):g} mm")
    lens = eqx.tree_at(lambda l: l.epd, lens, value)
    _check_traceable(lens)
    return lens


TELECENTRIC_SEED_NA = 1e-3
"""The object-space NA a reader builds an object-space telecentric lens with before its
aperture is applied (``apply_object_na``)."""


def telecentric_of(d: dict, aperture: dict, source: str) -> bool:
    """Whether a JSON lens is object-space telecentric (``object_space_telecentric``), its
    aperture and field type checked against it."""
    tele = d.get("object_space_telecentric", False)
    if not isinstance(tele, bool):  # "false" or 0 would be read as a flag silently
        raise ValueError(f"{source}: object_space_telecentric must be true or false, got "
                         f"{tele!r}")
    heights = lens_system.fields_are_heights(d)
    if not tele:
        if "object_na" in aperture:
            raise ValueError(f"{source}: aperture.object_na is the aperture of an object-space "
                             f"telecentric lens only (\"object_space_telecentric\": true); "
                             f"give epd, fnum or stop_semi_diameter")
        if heights:
            raise ValueError(f"{source}: object heights (fields.type "
                             f"{d['fields']['type']!r}) are the fields of an object-space "
                             f"telecentric lens only; give field angles (angle_deg_y)")
        return False
    if set(aperture) - {"object_na", "stop_semi_diameter"} or len(aperture) != 1:
        raise ValueError(f"{source}: an object-space telecentric lens (entrance pupil at "
                         f"infinity) takes one aperture, aperture.object_na (n·sin u) or "
                         f"aperture.stop_semi_diameter (mm), got {sorted(aperture)}")
    if not heights:
        raise ValueError(f"{source}: an object-space telecentric lens's fields are object "
                         f"heights: give fields.type \"object_height_mm_y\" (or _xy) with "
                         f"the heights in mm")
    return True


def apply_object_na(lens: Lens, *, na=None, cone_deg=None, stop_semi_diameter=None) -> Lens:
    """Set ``lens.object_na`` of an object-space telecentric lens from one aperture
    specification: the NA n·sin u itself, the object cone's half-angle u (deg), or the stop's
    semi-diameter (mm; the paraxial marginal ray from the axial object point reaches the
    stop at that height, as Zemax's "float by stop size"). n is the object-space index at
    the primary wavelength."""
    if not lens.telecentric_object:
        raise ValueError("aperture: the lens is not object-space telecentric (object_na None)")
    if sum(x is not None for x in (na, cone_deg, stop_semi_diameter)) != 1:
        raise ValueError("aperture: give exactly one of na, cone_deg, stop_semi_diameter")
    n0 = float(lens.object_material.index(lens.primary_wavelength))
    if na is not None:
        if not 0.0 < na < n0:
            raise ValueError(f"object-space NA must be in (0, n) with n = {n0:.6g} the object "
                             f"space index, got {na:g}")
        value = na
    elif cone_deg is not None:
        if not 0.0 < cone_deg < 90.0:
            raise ValueError(f"object cone angle must be in (0, 90) deg, got {cone_deg:g}")
        value = n0 * math.sin(math.radians(cone_deg))
    else:
        if not stop_semi_diameter > 0:
            raise ValueError(f"stop semi-diameter must be > 0 mm, got {stop_semi_diameter:g}")
        unit = eqx.tree_at(lambda m: m.object_na, lens, jnp.asarray(n0 / math.sqrt(2.0)))
        per_slope = abs(float(paraxial.marginal_ray(unit)[0][lens.stop]))  # at tan u = 1
        if not (per_slope > 0 and math.isfinite(per_slope)):
            raise ValueError(f"the stop's semi-diameter does not set an object-space NA: the "
                             f"paraxial marginal ray from the axial object point meets the "
                             f"stop at height {per_slope:g} mm per unit slope (the stop is "
                             f"imaged onto the object)")
        t = stop_semi_diameter / per_slope
        value = n0 * t / math.sqrt(1.0 + t * t)
    lens = eqx.tree_at(lambda m: m.object_na, lens, jnp.asarray(value, lens.thickness.dtype))
    _check_traceable(lens)
    return lens


def _check_traceable(lens: Lens) -> None:
    """Refuse a lens whose paraxial data are NaN, or whose marginal ray is not finite: values
    each finite but out of range together (a curvature of 1e308 with no aperture) would
    load and trace to NaN. An afocal lens (focal length inf) and a telecentric one (a
    pupil at infinity) are fine."""
    with np.errstate(all="ignore"):
        pd = paraxial.paraxial_data(lens)
    values = {k: float(v) for k, v in vars(pd).items()}
    if lens.telecentric_object:  # the entrance pupil at infinity: no F/# from an EPD
        del values["fnum"], values["entrance_pupil_diameter"]
    bad = [k for k, v in values.items() if math.isnan(v)]
    bad += [k for k in ("entrance_pupil_diameter", "stop_semi_diameter")
            if k in values and math.isinf(values[k])]
    if bad:
        raise ValueError(f"the lens cannot be traced: its paraxial {', '.join(bad)} come out "
                         f"as {', '.join(str(values[k]) for k in bad)} (values out of range: "
                         f"a curvature, thickness or index too large?)")


def _one_aperture(lens: Lens, given: dict, where: str) -> Lens:
    """The lens with the first of ``given`` (epd, then fnum, then stop_semi_diameter) as its
    aperture; any other given must agree with it (to 1e-6), or one of them would be ignored
    without a word."""
    first, *others = given
    lens = apply_aperture(lens, **{first: given[first][1]})
    for key in others:
        epd = float(apply_aperture(lens, **{key: given[key][1]}).epd)
        if not math.isclose(epd, float(lens.epd), rel_tol=1e-6):
            (a, va), (b, vb) = given[first], given[key]
            raise ValueError(f"{where}: {a} {va:g} and {b} {vb:g} disagree: they give "
                             f"entrance pupil diameters of {float(lens.epd):.6g} and {epd:.6g} "
                             f"mm; give one of them")
    return lens


def _warn_inside_out(thick: list, mats: list, source: str, first: int) -> None:
    """A negative thickness in glass where light travels toward +z (no mirror, no break):
    the element's back lies in front of its face, e.g. a sign typed wrong (the Cooke
    triplet's 3.26 as -3: 0.58 mm RMS spots, without a word)."""
    for j, (t, m) in enumerate(zip(thick, mats, strict=True)):
        if t < 0 and not isinstance(m, Air):
            warnings.warn(f"{source}: surface {j + first}: thickness {t:g} mm inside "
                          f"{getattr(m, 'name', '') or type(m).__name__}, with no mirror "
                          f"before it: the next surface lies in front of this one (an element "
                          f"inside out); a negative thickness belongs in air or after a mirror",
                          stacklevel=3)
            return


def _is_kind(s: Any, kind: str) -> bool:
    return isinstance(s, dict) and str(s.get("type", "")).lower() == kind


def lens_from_dict(d: dict, *, source: str = "<lens>") -> Lens:
    """Build a ``Lens`` from a parsed lens file (see docs/lens-format.md).

    Raises:
        ValueError: naming ``source`` and the offending key or surface.
    """
    if not isinstance(d, dict):
        raise ValueError(f"{source}: a lens file holds a JSON object, got {type(d).__name__}")
    fmt = d.get("format")
    if fmt is not None and fmt not in _SUPPORTED_FORMATS:
        raise ValueError(
            f"{source}: unsupported format {fmt!r}; this jaxlens reads "
            f"{', '.join(_SUPPORTED_FORMATS)}"
        )
    try:
        lens_keys.check_keys(d, source)
    except ValueError as e:  # a JSON file of another kind (a run's record): say so first
        if "surfaces" in d or "surfaces" in str(e):
            raise
        named = d.get("lens_file")
        hint = f"; it names the lens file {named!r}" if isinstance(named, str) else ""
        raise ValueError(f"{source}: no 'surfaces' key: this JSON file is not a lens file (its "
                         f"keys: {', '.join(map(str, list(d)[:8]))}){hint}. Reading it as one: "
                         f"{e}") from e
    surfs = d.get("surfaces")
    if not isinstance(surfs, list) or not surfs:
        raise ValueError(f"{source}: 'surfaces' must be a non-empty list")
    obj = surfs[0] if _is_kind(surfs[0], "object") else None
    img = surfs[-1] if len(surfs) > 1 and _is_kind(surfs[-1], "image") else None
    body = surfs[(obj is not None) : len(surfs) - (img is not None)]
    if not body:
        raise ValueError(f"{source}: no lens surfaces between the object and the image")
    first = 1 if obj is not None else 0
    for s, where in ((obj, "surface 0"), (img, "image surface")):
        lens_keys.no_misspelled(s, lens_keys.SURFACE, f"{source}: {where}")
        if s is not None and s.get("is_stop", False) is not False:  # was ignored
            raise ValueError(f"{source}: {where}: the object or image surface cannot be the "
                             f"stop (is_stop {s['is_stop']!r}); mark a lens surface")
    if img is not None and "thickness" in img and _num(
            img["thickness"], f"{source}: image surface thickness", finite=False) != 0:
        # Nothing follows the image surface: a thickness there was ignored.
        raise ValueError(f"{source}: image surface: thickness {img['thickness']!r} is not "
                         f"read (nothing follows the image); give 0 or leave it out")

    # Object distance: surface 0's thickness, or an "object" block.
    dist = math.inf
    block = d["object"]["distance"] if isinstance(d.get("object"), dict) and \
        "distance" in d["object"] else None
    if obj is not None and "thickness" in obj:
        dist = _num(obj["thickness"], f"{source}: surface 0 thickness", finite=False)
        if block is not None and _num(block, f"{source}: object.distance",
                                      finite=False) != dist:  # one of them was ignored
            raise ValueError(f"{source}: object.distance {block!r} disagrees with surface 0's "
                             f"thickness {obj['thickness']!r} (mm); give one of them")
    elif block is not None:
        dist = _num(block, f"{source}: object.distance", finite=False)
    if dist == 0 or math.isnan(dist) or dist <= -INFINITE_OBJECT_MM:
        raise ValueError(f"{source}: the object distance must be nonzero, below "
                         f"{INFINITE_OBJECT_MM:g} mm in size (negative: a virtual object "
                         f"after surface 1), or 'inf', got {dist}")
    obj_mat = Air()
    if obj is not None:
        obj_mat = material_from_spec(
            obj.get("material"), f"{source}: surface 0", n_table=obj.get("n")
        )

    surfaces, thick, mats, stops = [], [], [], []
    mirrors, obscurations, apertures = [], [], []
    for j, s in enumerate(body):
        i = j + first
        where = f"{source}: surface {i}"
        if not isinstance(s, dict):
            raise ValueError(f"{where}: must be an object, got {s!r}")
        lens_keys.no_misspelled(s, lens_keys.SURFACE, where)
        if _text(s.get("type", ""), f"{where}: type").lower() in ("object", "image"):
            raise ValueError(f"{where}: an {s['type']} surface can only be first/last")
        surfaces.append(surface_from_dict(s, where))
        mirror, obsc, aps = surface_json.surface_data_from_json(s, where)
        mirrors += [j] if mirror else []
        obscurations += [(j, *obsc)] if obsc is not None else []
        apertures += [(j, a) for a in aps]
        if "thickness" not in s:
            raise ValueError(f"{where}: missing 'thickness'")
        t = _num(s["thickness"], f"{where}: thickness")
        if not abs(t) < INFINITE_OBJECT_MM:  # 1e308 passes as finite, then overflows
            raise ValueError(f"{where}: thickness must be below {INFINITE_OBJECT_MM:g} mm in "
                             f"size, got {t:g}")
        thick.append(t)
        mats.append(material_from_spec(s.get("material"), where, n_table=s.get("n")))
        is_stop = s.get("is_stop", False)
        if not isinstance(is_stop, bool):
            raise ValueError(f"{where}: is_stop must be true or false, got {is_stop!r}")
        if is_stop:
            stops.append(j)
    if len(stops) > 1:
        raise ValueError(
            f"{source}: more than one surface has is_stop: {[i + first for i in stops]}"
        )
    if not mirrors and not any(isinstance(s, CoordinateBreak) for s in surfaces):
        _warn_inside_out(thick, mats, source, first)
    stop = stops[0] if stops else None
    if "stop_surface_index" in d:
        idx = d["stop_surface_index"]
        if isinstance(idx, bool) or not isinstance(idx, int):
            raise ValueError(f"{source}: stop_surface_index must be an integer, got {idx!r}")
        si = idx - first
        if not 0 <= si < len(surfaces):
            raise ValueError(f"{source}: stop_surface_index {idx} is not a lens surface")
        if stop is not None and stop != si:
            raise ValueError(
                f"{source}: stop_surface_index {idx} disagrees with is_stop on "
                f"surface {stop + first}"
            )
        stop = si
    stop = 0 if stop is None else stop

    image = Standard()
    if img is not None:
        shape = _text(img.get("shape", "standard"), f"{source}: image surface shape")
        image = surface_from_dict(img, f"{source}: image surface", kind=shape)
        mirror, obsc, aps = surface_json.surface_data_from_json(img, f"{source}: image surface")
        j = len(surfaces)  # the image surface's index in Lens.mirrors, obscurations, apertures
        mirrors += [j] if mirror else []
        obscurations += [(j, *obsc)] if obsc is not None else []
        apertures += [(j, a) for a in aps]

    wl, primary = lens_system.wavelengths_of(d, source)
    fields = lens_system.fields_of(d, source)
    lens_system.check_weights(d, source, fields.shape[0], wl.size)
    sensor = None
    if d.get("sensor") is not None:
        sd = d["sensor"]
        try:
            res = tuple(_whole(v) for v in sd["resolution"])
            pix = _num(sd["pixel_size"], f"{source}: sensor.pixel_size")
        except (KeyError, TypeError, ValueError, OverflowError):
            raise ValueError(
                f"{source}: sensor needs resolution [rows, cols] and pixel_size (mm)"
            ) from None
        if len(res) != 2 or min(res) <= 0 or not pix > 0:
            raise ValueError(f"{source}: bad sensor {sd!r}")
        sensor = Sensor(res, _arr(pix))
    name, description = d.get("name", ""), d.get("description", "")
    for key, text in (("name", name), ("description", description)):
        if not isinstance(text, str):
            raise ValueError(f"{source}: {key} must be a string, got {type(text).__name__}")
    aperture = lens_system.aperture_of(d, source)
    key = next((k for k in ("wavelengths_um", "wavelengths_nm", "wavelengths") if k in d),
               "wavelengths")
    # The Lens checks these too, but here the message names the file and the key.
    checks.wavelengths(checks.NoMaterials, wl, f"{source}: {key}", "wavelength")
    tele = telecentric_of(d, aperture, source)
    if not tele:
        checks.field_angles(fields, f"{source}: fields", "field angles")
    vignetting = lens_system.vignetting_of(d, source, fields.shape[0])
    afocal = d.get("afocal_image_space", False)
    if not isinstance(afocal, bool):  # "false" or 0 would be read as a flag silently
        raise ValueError(f"{source}: afocal_image_space must be true or false, got "
                         f"{afocal!r}")
    aim = d.get("ray_aiming", "paraxial")
    if not isinstance(aim, str) or aim not in RAY_AIMING:  # "Real" would aim paraxially
        raise ValueError(f"{source}: ray_aiming must be one of {list(RAY_AIMING)} (rays "
                         f"through the paraxial entrance pupil, or aimed at the real stop), "
                         f"got {aim!r}")
    back = d.get("negative_propagation", False)
    if not isinstance(back, bool):  # "false" or 0 would be read as a flag silently
        raise ValueError(f"{source}: negative_propagation must be true or false, got {back!r}")
    try:  # the light's direction along frames that coordinate breaks turn (optics.travel)
        # (an image-surface mirror is refused by Lens, with its own message)
        senses = travel.turned_senses(surfaces, [m for m in mirrors if m < len(surfaces)])
    except ValueError as e:
        raise ValueError(f"{source}: {e}") from None
    given = d.get("travel_senses")  # not read (the frames give it), so a stale one is refused
    need = list(senses or travel.mirror_count_senses(
        len(surfaces), [m for m in mirrors if m < len(surfaces)]))
    if "travel_senses" in d and (not isinstance(given, list) or len(given) != len(need) or any(
            type(v) is not int or v not in (1, -1) for v in given)):
        raise ValueError(f"{source}: travel_senses must be a list of {len(need)} numbers, "
                         f"each +1 or -1 (the light's direction along each medium's local z, "
                         f"object space first), got {given!r}; it is optional (the frames "
                         f"give it)")
    if "travel_senses" in d and given != need:
        raise ValueError(f"{source}: travel_senses {given!r} disagrees with the frames: these "
                         f"mirrors and coordinate breaks give {need} (the light's direction "
                         f"along each medium's local z, object space first); leave it out")
    lens = Lens(
        surfaces=tuple(surfaces),
        thickness=_arr(np.array(thick)),
        materials=tuple(mats),
        stop=stop,
        epd=_arr(aperture["epd"][1] if "epd" in aperture else 1.0),
        object_na=_arr(TELECENTRIC_SEED_NA) if tele else None,
        fields=_arr(fields),
        wavelengths=_arr(wl),
        primary=primary,
        object_distance=_arr(dist),
        object_material=obj_mat,
        image=image,
        sensor=sensor,
        name=name,
        description=description,
        vignetting=None if vignetting is None else _arr(vignetting),
        mirrors=tuple(mirrors),
        obscurations=tuple(obscurations),
        apertures=tuple(apertures),
        afocal_image=afocal,
        aim=aim,
        negative_propagation=back,
        travel_senses=senses,
    )
    # Before the paraxial work of the aperture: values the lens cannot be traced with.
    checks.wavelengths(lens, wl, f"{source}: {key}", "wavelength")
    checks.material_indices(lens, wl, source)
    if not tele:
        checks.field_angles(fields, f"{source}: fields", "field angles")
    # After the wavelength checks: a wavelength outside a glass's data is named as such.
    for j, (s, m) in enumerate(zip([obj, *body], [obj_mat, *mats], strict=True)):
        check_index_record(s, m, wl, f"{source}: surface {j + first - 1}")
    if img is not None and (img.get("material") is not None or img.get("n") is not None):
        _warn_image_medium(img, mats[-1], wl, primary, source)
    try:
        if tele:
            (kind, (_, value)), = aperture.items()
            return apply_object_na(lens, **{"na" if kind == "object_na" else kind: value})
        return _one_aperture(lens, aperture, source)
    except ValueError as e:
        raise ValueError(str(e) if str(e).startswith(source) else f"{source}: {e}") from None


def _warn_image_medium(img: dict, image_space, wl, primary: int, source: str) -> None:
    """A medium after the image surface is not traced: say so where it differs."""
    after = material_from_spec(img.get("material"), f"{source}: image surface",
                               n_table=img.get("n"))
    n_after, n_space = (np.asarray(m.index(jnp.asarray(wl))) for m in (after, image_space))
    if not np.allclose(n_after, n_space, rtol=0.0, atol=1e-12):
        warnings.warn(
            f"{source}: the medium after the image surface (n = {n_after[primary]:.6g}) is "
            f"not image space (n = {n_space[primary]:.6g}); a trace ends in image space, so "
            f"its directions are those before the image surface (intercepts are unchanged)",
            stacklevel=3)


def lens_to_dict(lens: Lens) -> dict:
    """The JSON object of a lens (format ``jaxlens.lens/1``)."""
    loadable(lens, "lens_to_dict")
    dist = math.inf if lens.object_distance is None else lens.object_distance
    obj = {
        "type": "object",
        "thickness": _out(dist),
        "material": material_to_spec(lens.object_material),
    }
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    if (n := index_record(lens.object_material, wl)) is not None:
        obj[INDEX_RECORD] = n
    surfs = [obj]
    for i, s in enumerate(lens.surfaces):
        e = surface_to_dict(s)
        e["thickness"] = _out(lens.thickness[i])
        e["material"] = material_to_spec(lens.materials[i])
        if (n := index_record(lens.materials[i], wl)) is not None:
            e[INDEX_RECORD] = n  # the medium whatever a reader's catalog holds
        if i == lens.stop:
            e["is_stop"] = True
        e.update(surface_json.surface_data_to_json(lens, i))
        surfs.append(e)
    img = surface_to_dict(lens.image)
    surfs.append({"type": "image", "shape": img.pop("type"), **img,
                  **surface_json.surface_data_to_json(lens, len(lens.surfaces))})
    fields = np.asarray(lens.fields)
    out = {
        "format": FORMAT,
        "name": lens.name,
        **({"description": lens.description} if lens.description else {}),
        "units": {"length": "mm", "wavelength": "um", "angle": "deg"},
        "aperture": ({"object_na": _out(lens.object_na)} if lens.telecentric_object
                     else {"epd": _out(lens.epd)}),
        "fields": {
            "type": ("object_height_mm" if lens.telecentric_object else "angle_deg")
            + ("_y" if fields.ndim <= 1 else "_xy"),
            "values": _out(np.atleast_1d(fields)),
        },
        "wavelengths_um": _out(np.atleast_1d(lens.wavelengths)),
        "primary": lens.primary,
        "surfaces": surfs,
    }
    if lens.afocal_image:
        out["afocal_image_space"] = True
    if lens.telecentric_object:
        out["object_space_telecentric"] = True
    if lens.aim != "paraxial":
        out["ray_aiming"] = lens.aim
    if lens.negative_propagation:
        out["negative_propagation"] = True
    if lens.vignetting is not None:
        v = np.asarray(lens.vignetting, np.float64)
        out["fields"]["vignetting"] = {k: _out(v[:, j])
                                       for j, k in enumerate(lens_keys.VIGNETTING)}
    if lens.sensor is not None:
        out["sensor"] = {
            "resolution": list(lens.sensor.resolution),
            "pixel_size": _out(lens.sensor.pixel_size),
        }
    return out


def load_json(path: str | os.PathLike) -> Lens:
    """Read a JSON lens file."""
    path = input_file(path, "load_json", "lens file")
    try:
        with open(path, encoding="utf-8-sig") as f:
            d = json.load(f, object_pairs_hook=_unique_keys)
    except RepeatedKey as e:
        raise ValueError(f"{path}: {e}") from None
    except json.JSONDecodeError as e:
        end = ("; the file is empty" if not e.doc.strip() else "; the file does not end in "
               "'}' (cut short?)" if not e.doc.rstrip().endswith("}") else "")  # interrupted
        raise ValueError(f"{path}:{e.lineno}: not valid JSON: {e.msg}{end}") from None
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start}); save the "
                         f"lens file as UTF-8") from None
    except RecursionError:
        raise ValueError(f"{path}: JSON nested too deeply to be a lens file") from None
    except ValueError as e:  # an integer of more than 4300 digits
        raise ValueError(f"{path}: not valid JSON: {e}") from None
    try:
        return lens_from_dict(d, source=path)
    except RecursionError:
        raise ValueError(f"{path}: JSON nested too deeply to be a lens file") from None
    except ValueError as e:  # a check of a class the reader calls (ModelGlass, Lens)
        if str(e).startswith(path):
            raise
        raise ValueError(f"{path}: {e}") from None
    except ArithmeticError as e:  # a value that overflows once converted
        raise ValueError(f"{path}: a value out of range ({e})") from None


def dumps(lens: Lens) -> str:
    """The JSON text of a lens."""
    loadable(lens, "dumps")
    return _pretty(lens_to_dict(lens)) + "\n"


def save_json(lens: Lens, path: str | os.PathLike) -> None:
    """Write a JSON lens file (``path`` ends in ``.json``, any case; its folder must exist:
    else ``json_values.MissingFolderError``, a ``ValueError`` and a ``FileNotFoundError``)."""
    loadable(lens, "save_json")
    path = output_file(path, "save_json", ".json")
    write_whole(path, dumps(lens), where="save_json")
