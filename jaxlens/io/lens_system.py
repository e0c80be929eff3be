"""The system data of a JSON lens file: aperture, wavelengths and primary, fields and
their vignetting factors (``docs/lens-format.md``), read from the file's parsed object.

Where the format accepts one value under several keys (``epd``, ``EPD`` and
``aperture.epd``; ``primary`` and ``primary_wavelength_um``/``_nm``), every key given must
agree: the reader takes the first, so another that disagreed was dropped without a word.
The same holds between a declared ``fields.type`` and the shape of ``fields.values``, and
between the field or wavelength weights (not read) and the lists they weigh.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..optics import checks
from ..optics import materials as _materials
from ..optics.lens import check_vignetting
from . import lens_keys
from .json_values import nm_to_um
from .json_values import num as _num
from .json_values import nums as _nums
from .json_values import text as _text

APERTURE_KEYS = {
    "epd": ("epd", "EPD"),
    "fnum": ("fnum", "FNUM", "f_number"),
    "stop_semi_diameter": ("stop_semi_diameter",),
    "object_na": ("object_na",),
}
"""The aperture keys of ``aperture`` by kind (``epd`` and ``EPD`` also at the top level)."""

FIELD_TYPES = {"angle_deg_y": 1, "angle_deg": None, "angle": None, "angle_deg_xy": 2,
               "object_height_mm_y": 1, "object_height_mm_xy": 2}
"""``fields.type``: the number of values per field it declares (None: either). The object
heights (mm) are the fields of an object-space telecentric lens (``Lens.object_na``), and
only of one."""


def fields_are_heights(d: dict) -> bool:
    """Whether ``fields.type`` declares object heights (``object_height_mm_*``)."""
    f = d.get("fields")
    return isinstance(f, dict) and str(f.get("type", "")).startswith("object_height")


def aperture_of(d: dict, where: str) -> dict:
    """The aperture specifications given, by kind: ``{kind: (key, value)}``, the first key
    of each kind (the top level's ``epd``/``EPD`` first). A kind given under two keys with
    values that differ (by more than 1e-6) is refused: one of them was ignored."""
    ap = d.get("aperture", {})
    if not isinstance(ap, dict):  # a bare 5 was read as an EPD of 5 mm (or F/5 meant?)
        raise ValueError(f"{where}: aperture must be an object, {{\"epd\": mm}}, {{\"fnum\": F}} "
                         f"or {{\"stop_semi_diameter\": mm}} (a bare number could be either), "
                         f"got {ap!r}")
    given: dict = {}

    def add(kind, label, v):
        if kind in given and not math.isclose(v, given[kind][1], rel_tol=1e-6):
            first, w = given[kind]
            raise ValueError(f"{where}: {first} {w:g} and {label} {v:g} disagree (both give "
                             f"the {kind}; one would be ignored); give one of them")
        given.setdefault(kind, (label, v))

    for top in ("epd", "EPD"):
        if top in d:
            v = _num(d[top], f"{where}: {top}")
            if not v > 0:
                raise ValueError(f"{where}: {top} (entrance pupil diameter) must be > 0 mm, "
                                 f"got {v}")
            add("epd", top, v)
    for key, names in APERTURE_KEYS.items():  # EPD first: reference cases give it with others
        for n in names:
            if n in ap:
                v = _num(ap[n], f"{where}: aperture.{n}")
                if not v > 0:
                    raise ValueError(f"{where}: aperture.{n} must be > 0, got {v}")
                add(key, f"aperture.{n}", v)
    if not given:
        raise ValueError(f"{where}: no aperture; give aperture.epd, aperture.fnum or "
                         f"aperture.stop_semi_diameter")
    return given


def wavelengths_of(d: dict, where: str) -> tuple[np.ndarray, int]:
    """The wavelengths (µm) and the primary's index. ``primary`` and the
    ``primary_wavelength*`` keys may each be given; all given must name one wavelength."""
    if len(keys := [k for k in ("wavelengths_um", "wavelengths_nm", "wavelengths") if k in d]) > 1:
        raise ValueError(f"{where}: give only one of {' and '.join(keys)} (they may disagree)")
    if "wavelengths_um" in d:
        wl = _nums(d["wavelengths_um"], f"{where}: wavelengths_um")
    elif "wavelengths_nm" in d:
        wl = nm_to_um(_nums(d["wavelengths_nm"], f"{where}: wavelengths_nm"))
    elif "wavelengths" in d:
        wl = _nums(d["wavelengths"], f"{where}: wavelengths")
    else:
        wl = np.array([_materials.LAMBDA_D])
    wl = np.atleast_1d(wl)
    if wl.ndim != 1 or wl.size == 0 or np.any(wl <= 0):
        raise ValueError(f"{where}: wavelengths must be a non-empty list of positive numbers")
    if np.unique(wl).size < wl.size:
        # A warning, not a refusal: Zemax takes a repeated wavelength (a .zmx read with one
        # saves to a JSON that must load), but a typo weighs it twice in every polychromatic
        # figure.
        warnings.warn(f"{where}: a wavelength is given twice ({checks.fmt(wl)} µm); it weighs "
                      f"twice in every polychromatic figure", stacklevel=3)
    named = []  # (key, index): every primary key given
    if "primary" in d:
        p = d["primary"]
        if isinstance(p, bool) or not isinstance(p, int) or not 0 <= p < wl.size:
            raise ValueError(f"{where}: primary must be an index 0..{wl.size - 1}, got {p!r}")
        named.append(("primary", p))
    for key in ("primary_wavelength_um", "primary_wavelength_nm", "primary_wavelength"):
        if key in d:
            target = _num(d[key], f"{where}: {key}")
            target = float(nm_to_um(target)) if key.endswith("_nm") else target
            i = int(np.argmin(np.abs(wl - target)))
            if not math.isclose(wl[i], target, rel_tol=1e-9):
                unit = "nm" if key.endswith("_nm") else "µm"  # (the message listed none)
                given = wl * 1000.0 if key.endswith("_nm") else wl
                raise ValueError(f"{where}: {key} {d[key]!r} is not one of the wavelengths "
                                 f"({checks.fmt(given)} {unit}); give one of them")
            named.append((key, i))
    if len({i for _, i in named}) > 1:
        (a, i), (b, j) = next((x, y) for x in named for y in named if x[1] != y[1])
        raise ValueError(f"{where}: {a} {d[a]!r} and {b} {d[b]!r} disagree: they name "
                         f"wavelengths {i} ({wl[i]:g} µm) and {j} ({wl[j]:g} µm) as the primary "
                         f"(one would be ignored); give one of them")
    return wl, named[0][1] if named else 0


def fields_of(d: dict, where: str) -> np.ndarray:
    """The field angles (deg): ``[n]`` θy, or ``[n, 2]`` (θx, θy) pairs. A ``fields.type``
    of one shape (``angle_deg_y``: one angle per field; ``angle_deg_xy``: pairs) must match
    the values: a list of the other shape was read as that shape without a word."""
    f = d.get("fields", [0.0])
    ftype = None
    if isinstance(f, dict):
        ftype = _text(f.get("type", "angle_deg_y"), f"{where}: fields.type")
        if ftype not in FIELD_TYPES:
            raise ValueError(f"{where}: field type {ftype!r} is not supported; fields.type must "
                             f"be one of {', '.join(FIELD_TYPES)} (angles in deg: convert "
                             f"radians or image heights to degrees; object heights in mm "
                             f"for an object-space telecentric lens)")
        f = f.get("values", [0.0])
    out = np.atleast_1d(_nums(f, f"{where}: fields"))
    if out.size == 0:
        raise ValueError(f"{where}: no fields")
    if out.ndim > 2 or (out.ndim == 2 and out.shape[1] != 2):
        raise ValueError(f"{where}: fields must be a list of angles θy or of [θx, θy] pairs "
                         f"(deg), got an array of shape {out.shape}")
    if ftype is not None and FIELD_TYPES[ftype] not in (None, out.ndim):
        heights = ftype.startswith("object_height")
        one, pair = (("one object height y (mm)", "[x, y] pairs (mm)") if heights
                     else ("one angle θy", "[θx, θy] pairs"))
        form = f"{one} per field" if FIELD_TYPES[ftype] == 1 else pair
        single = "single heights" if heights else "single angles"
        pairs_type = "object_height_mm_xy" if heights else "angle_deg_xy"
        raise ValueError(f"{where}: fields.type {ftype!r} declares {form}, but fields.values "
                         f"holds {'pairs' if out.ndim == 2 else single} (shape "
                         f"{out.shape}); make them agree (type \"{pairs_type}\" for pairs)")
    if np.unique(out, axis=0).shape[0] < out.shape[0]:
        # A warning, as for a repeated wavelength (Zemax takes it; a .zmx read with one
        # saves to a JSON that must load), but a typo weighs the field twice.
        warnings.warn(f"{where}: a field is given twice ({checks.fmt(out)} deg); it "
                      f"weighs twice in every figure averaged over the fields", stacklevel=3)
    return out


def check_weights(d: dict, where: str, n_fields: int, n_wavelengths: int) -> None:
    """Field or wavelength weights (not read: ``lens_keys`` warns when they differ) must be
    a list of one number per field or wavelength, as the ``.zmx`` reader requires of FWGN and
    WAVM: a list of another length belongs to other fields than these."""
    for section, key, what in lens_keys.WEIGHTS:
        holder = d if section is None else d.get(section)
        if not isinstance(holder, dict) or key not in holder:
            continue
        name = key if section is None else f"{section}.{key}"
        n = n_fields if what == "fields" else n_wavelengths
        w = np.atleast_1d(_nums(holder[key], f"{where}: {name}"))
        if w.shape != (n,):
            raise ValueError(f"{where}: {name} must hold one weight per {what[:-1]} ({n}), got "
                             f"{holder[key]!r}")


def vignetting_of(d: dict, where: str, n_fields: int) -> np.ndarray | None:
    """``fields.vignetting``: ``{"vdx": [...], "vdy": [...], "vcx": [...], "vcy": [...],
    "van_deg": [...]}``, one value per field each (pupil radii; ``van_deg`` in degrees), a
    missing list 0; None without it. Checked as ``Lens.vignetting``, naming the file."""
    f = d.get("fields")
    if not isinstance(f, dict) or f.get("vignetting") is None:
        return None
    v, at = f["vignetting"], f"{where}: fields.vignetting"
    form = '{"vdx": [...], "vdy": [...], "vcx": [...], "vcy": [...], "van_deg": [...]}'
    if not isinstance(v, dict):
        raise ValueError(f"{at} must be an object {form}, one value per field each (pupil "
                         f"radii, van_deg in degrees), got {v!r}")
    lens_keys.no_misspelled(v, lens_keys.VIGNETTING, at)
    unknown = [k for k in v if k not in lens_keys.VIGNETTING]
    if unknown:
        raise ValueError(f"{at}: unknown key {unknown[0]!r}; the keys are "
                         f"{', '.join(lens_keys.VIGNETTING)}")
    out = np.zeros((n_fields, 5))
    for j, key in enumerate(lens_keys.VIGNETTING):
        if key in v:
            col = np.atleast_1d(_nums(v[key], f"{at}.{key}"))
            if col.shape != (n_fields,):
                raise ValueError(f"{at}.{key} must hold one value per field ({n_fields}), got "
                                 f"shape {col.shape}")
            out[:, j] = col
    return check_vignetting(out, at, "factors")
