"""JSON forms of the surface kinds beyond the rotationally symmetric aspheres, and of the
per-surface data a ``Lens`` holds beside its surfaces (mirrors, obscurations, apertures).

Each kind here is a table from its JSON keys to the surface class's fields, so reading and
writing are the same loop; the class itself checks the values (its messages are prefixed
with the surface's place in the file). Units as in the rest of the format: mm, degrees,
lines per µm; phases in radians.

=====================  =====================  ==========================================
JSON ``type``          class                  keys (besides ``thickness``, ``material``)
=====================  =====================  ==========================================
``toroidal``           ``Toroidal``           ``curvature`` (y–z profile, 1/mm),
                                              ``conic``, ``y_coeffs`` (on y², y⁴, …),
                                              ``curvature_x`` (of rotation; 0 a cylinder)
``paraxial``           ``ParaxialSurface``    ``focal_length`` (mm)
``binary2``            ``Binary2``            ``curvature``, ``conic``,
                                              ``even_asphere_coeffs``,
                                              ``diffraction_order``, ``norm_radius`` (mm),
                                              ``phase_coeffs`` (radians, on ρ², ρ⁴, …)
``grating``            ``Grating``            ``curvature``, ``conic``, ``lines_per_um``,
                                              ``diffraction_order``
``tilted_plane``       ``TiltedPlane``        ``tan_x``, ``tan_y`` (slopes dz/dx, dz/dy)
``xy_polynomial``      ``XYPolynomial``       ``curvature``, ``conic``,
                                              ``polynomial_coeffs`` (mm, A_1 … A_N on x, y,
                                              x², xy, y², … of x/R, y/R; Zemax XPOLYNOM),
                                              ``norm_radius`` (R, mm; needed with terms)
``coordinate_break``   ``CoordinateBreak``    ``decenter_x``, ``decenter_y`` (mm),
                                              ``tilt_x_deg``, ``tilt_y_deg``,
                                              ``tilt_z_deg``, ``order`` (0 or 1)
=====================  =====================  ==========================================

The freeform kinds (``jaxlens.optics.freeform``) are read by ``freeform_from_json``:
``"biconic"`` (``curvature``/``radius``, ``conic`` the y–z section; ``curvature_x``/
``radius_x``, ``conic_x`` the x–z one) and ``"zernike_standard"``/``"zernike_fringe"`` (an
even asphere plus ``zernike_coeffs`` (mm) on ``norm_radius`` (mm), ``zernike_decenter_x``/``_y``
(mm), ``extrapolate``).

All but the coordinate break take ``semi_diameter`` (mm). Per surface, any kind:
``"mirror": true`` (it reflects: ``Lens.mirrors``), ``"obscuration": [r_min, r_max]`` (mm,
``Lens.obscurations``) and ``"apertures": [{"shape": "circle" | "ellipse" | "rect",
"half_x", "half_y", "decenter_x", "decenter_y", "blocks"}, …]`` (mm; ``Lens.apertures``).
"""

from __future__ import annotations

import re

import numpy as np

from ..optics import checks
from ..optics.apertures import Aperture
from ..optics.coordinates import CoordinateBreak
from ..optics.diffractive import Binary2, Grating
from ..optics.freeform import Biconic, ZernikeSag
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.surfaces import AbstractSurface, TiltedPlane
from ..optics.toroidal import Toroidal
from ..optics.xypolynomial import XYPolynomial
from .json_values import curvature
from .json_values import float64_array as _arr
from .json_values import json_number as _out
from .json_values import num as _num
from .json_values import nums as _nums
from .json_values import text as _text

_SD = ("semi_diameter", "semi_diameter")
KINDS: dict[str, tuple[type, tuple[tuple[str, str], ...]]] = {
    "toroidal": (Toroidal, (("curvature", "c"), ("conic", "k"), ("y_coeffs", "coeffs"),
                            ("curvature_x", "cx"), _SD)),
    "paraxial": (ParaxialSurface, (("focal_length", "focal_length"), _SD)),
    "binary2": (Binary2, (("curvature", "c"), ("conic", "k"), ("even_asphere_coeffs", "coeffs"),
                          ("diffraction_order", "order"), ("norm_radius", "norm_radius"),
                          ("phase_coeffs", "phase_coeffs"), _SD)),
    "grating": (Grating, (("curvature", "c"), ("conic", "k"), ("lines_per_um", "lines_per_um"),
                          ("diffraction_order", "order"), _SD)),
    "tilted_plane": (TiltedPlane, (("tan_x", "tan_x"), ("tan_y", "tan_y"), _SD)),
    "xy_polynomial": (XYPolynomial, (("curvature", "c"), ("conic", "k"),
                                     ("polynomial_coeffs", "coeffs"),
                                     ("norm_radius", "norm_radius"), _SD)),
    "coordinate_break": (CoordinateBreak, (
        ("decenter_x", "decenter_x"), ("decenter_y", "decenter_y"),
        ("tilt_x_deg", "tilt_x"), ("tilt_y_deg", "tilt_y"), ("tilt_z_deg", "tilt_z"))),
}
"""JSON type -> (surface class, (JSON key, class field) pairs)."""

_LISTS = frozenset({"y_coeffs", "even_asphere_coeffs", "phase_coeffs", "polynomial_coeffs"})
_NEEDS = {"polynomial_coeffs": "norm_radius"}
"""A list key -> the key that must come with it when the list is not empty (a missing
normalisation radius would silently be the class's default, 1 mm)."""
KEYS = frozenset(k for _, pairs in KINDS.values() for k, _ in pairs) | {"order"}
"""Every surface key this module reads (for the near-miss check of ``lens_keys``)."""
OWN_KEYS = KEYS - {"curvature", "conic", "even_asphere_coeffs", "semi_diameter", "norm_radius"}
"""The keys that only these kinds take (a standard surface with ``tilt_x_deg`` is refused,
not read untilted)."""
SURFACE_DATA = ("mirror", "obscuration", "apertures")
"""Per-surface keys of the data a ``Lens`` holds beside its surfaces."""
_APERTURE_KEYS = ("shape", "half_x", "half_y", "decenter_x", "decenter_y", "blocks")
# The keys every surface object may hold besides its kind's own.
_COMMON = frozenset({"type", "shape", "thickness", "material", "n", "is_stop", "comment",
                     "index_at_wavelengths", *SURFACE_DATA})


def kind_of(raw: str) -> str | None:
    """The key of ``KINDS`` that a ``type`` value names (case, spaces, ``-`` and ``_``
    ignored), or None."""
    squeezed = re.sub(r"[^a-z0-9]", "", raw.lower())
    return next((k for k in KINDS if k.replace("_", "") == squeezed), None)


def surface_from_json(kind: str, d: dict, where: str, known_keys) -> AbstractSurface:
    """The surface of ``KINDS[kind]`` from its JSON object. A key that the format knows but
    this kind does not take (``even_asphere_coeffs`` on a toroid) is refused: it would be
    ignored."""
    cls, pairs = KINDS[kind]
    own = {k for k, _ in pairs} | ({"order"} if cls is CoordinateBreak else set())
    stray = sorted(k for k in d if k in known_keys and k not in own and k not in _COMMON)
    if stray:
        raise ValueError(f"{where}: a {kind} surface does not take {', '.join(stray)}; its "
                         f"keys are {', '.join(sorted(own))}")
    kw = {}
    for key, field in pairs:
        if key not in d:
            continue
        if key in _LISTS:
            v = _nums(d[key], f"{where}: {key}")
            if v.ndim != 1:
                raise ValueError(f"{where}: {key} must be a flat list")
        else:
            v = _num(d[key], f"{where}: {key}", finite=key != "semi_diameter")
        kw[field] = _arr(v)
        if key in _NEEDS and v.size and _NEEDS[key] not in d:
            raise ValueError(f"{where}: a {kind} surface with {key} needs {_NEEDS[key]} (the "
                             f"normalisation radius, mm)")
    if cls is CoordinateBreak and "order" in d:
        order = d["order"]
        if isinstance(order, bool) or order not in (0, 1):
            raise ValueError(f"{where}: order must be 0 (decenter, then tilt) or 1 (tilt, then "
                             f"decenter), got {order!r}")
        kw["order"] = int(order)
    if "semi_diameter" in kw and not kw["semi_diameter"] > 0:
        raise ValueError(f"{where}: semi_diameter must be > 0 (or 'inf'), got "
                         f"{d['semi_diameter']!r}")
    return cls(**kw)


def surface_to_json(s: AbstractSurface) -> dict | None:
    """The JSON object of a surface of a ``KINDS`` class or a freeform one (None for other
    classes)."""
    if isinstance(s, Biconic | ZernikeSag):
        d = _freeform_to_json(s)
        if np.isfinite(np.asarray(s.semi_diameter)):
            d["semi_diameter"] = _out(s.semi_diameter)
        return d
    kind = next((k for k, (cls, _) in KINDS.items() if type(s) is cls), None)
    if kind is None:
        return None
    d = {"type": kind}
    for key, field in KINDS[kind][1]:
        v = getattr(s, field)
        if key == "semi_diameter" and not np.isfinite(np.asarray(v)):
            continue
        d[key] = _out(v)
    if isinstance(s, CoordinateBreak):
        d["order"] = s.order
    return d


def surface_data_from_json(d: dict, where: str) -> tuple[bool, tuple | None, tuple]:
    """(mirror, (r_min, r_max) or None, apertures) of a surface's JSON object."""
    mirror = d.get("mirror", False)
    if not isinstance(mirror, bool):
        raise ValueError(f"{where}: mirror must be true or false, got {mirror!r}")
    obsc = None
    if "obscuration" in d:
        o = _nums(d["obscuration"], f"{where}: obscuration")
        if o.shape != (2,):
            raise ValueError(f"{where}: obscuration must be [r_min, r_max] (mm), got "
                             f"{d['obscuration']!r}")
        obsc = (float(o[0]), float(o[1]))
        if str(d.get("type", "")).lower() == "coordinate_break":  # the tracer ignored it
            raise ValueError(f"{where}: a coordinate break has no aperture, so its "
                             f"obscuration {d['obscuration']!r} would block nothing; put it on "
                             f"the surface it blocks")
    raw = d.get("apertures", [])
    if not isinstance(raw, list):
        raise ValueError(f"{where}: apertures must be a list of aperture objects, got {raw!r}")
    apertures = []
    for j, a in enumerate(raw):
        at = f"{where}: apertures[{j}]"
        if not isinstance(a, dict):
            raise ValueError(f"{at}: must be an object with {', '.join(_APERTURE_KEYS)}")
        extra = sorted(set(a) - set(_APERTURE_KEYS))
        if extra:
            raise ValueError(f"{at}: unknown key(s) {', '.join(extra)}; an aperture has "
                             f"{', '.join(_APERTURE_KEYS)}")
        if "half_x" not in a or "half_y" not in a:
            raise ValueError(f"{at}: needs half_x and half_y (mm; a circle's radius twice)")
        kw = {k: _num(a[k], f"{at}: {k}") for k in _APERTURE_KEYS[1:5] if k in a}
        blocks = a.get("blocks", False)
        if not isinstance(blocks, bool):
            raise ValueError(f"{at}: blocks must be true or false, got {blocks!r}")
        try:
            apertures.append(Aperture(_text(a.get("shape", "circle"), f"{at}: shape"),
                                      blocks=blocks, **kw))
        except ValueError as e:
            raise ValueError(f"{at}: {e}") from None
    return mirror, obsc, tuple(apertures)


def surface_data_to_json(lens, i: int) -> dict:
    """The ``mirror``, ``obscuration`` and ``apertures`` keys of lens surface ``i`` (only
    those it has)."""
    d = {}
    if i in lens.mirrors:
        d["mirror"] = True
    for j, r_min, r_max in lens.obscurations:
        if j == i:
            d["obscuration"] = [_out(r_min), _out(r_max)]
    aps = [a for j, a in lens.apertures if j == i]
    if aps:
        d["apertures"] = [{"shape": a.shape, "half_x": _out(a.half_x), "half_y": _out(a.half_y),
                           "decenter_x": _out(a.decenter_x), "decenter_y": _out(a.decenter_y),
                           "blocks": a.blocks} for a in aps]
    return d


FREEFORM_TYPES = {"biconic": None, "biconicx": None, "zernikestandard": "standard",
                   "zernikestandardsag": "standard", "szernsag": "standard",
                   "zernikefringe": "fringe", "zernikefringesag": "fringe", "fzernsag": "fringe"}
_BICONIC_KEYS = ("curvature_x", "radius_x", "conic_x")
_ZERNIKE_KEYS = ("zernike_coeffs", "zernike_decenter_x", "zernike_decenter_y", "extrapolate")
FREEFORM_KEYS = _BICONIC_KEYS + _ZERNIKE_KEYS


def freeform_from_json(d: dict, where: str, raw: str, kind: str, c, k, sd, coeffs):
    """A ``Biconic`` (type "biconic") or ``ZernikeSag`` (type "zernike_standard" or
    "zernike_fringe") from its JSON object."""
    if kind not in FREEFORM_TYPES:
        given = next(key for key in FREEFORM_KEYS if key in d)
        raise ValueError(f"{where}: {given} belongs to a biconic (type \"biconic\": "
                         f"curvature_x/radius_x, conic_x) or a Zernike sag surface (type "
                         f"\"zernike_standard\" or \"zernike_fringe\": zernike_coeffs, "
                         f"norm_radius, zernike_decenter_x/_y, extrapolate), not to type {raw!r}")
    ordering = FREEFORM_TYPES[kind]
    other = ("odd_asphere_coeffs", "q_coeffs", "odd_x", "odd_y") + (
        _ZERNIKE_KEYS + ("norm_radius", "even_asphere_coeffs") if ordering is None
        else _BICONIC_KEYS)
    extra = next((key for key in other if key in d), None)
    if extra is not None:
        raise ValueError(f"{where}: a {'biconic' if ordering is None else 'Zernike sag'} "
                         f"surface (type {raw!r}) takes no {extra}")
    if ordering is None:
        kx = _num(d.get("conic_x", 0.0), f"{where}: conic_x")
        return Biconic(c=_arr(c), k=_arr(k), cx=_arr(curvature(d, where, "_x")), kx=_arr(kx),
                       semi_diameter=_arr(sd))
    a = _nums(d.get("zernike_coeffs", []), f"{where}: zernike_coeffs")
    if a.ndim != 1 or coeffs.ndim != 1:
        raise ValueError(f"{where}: zernike_coeffs and even_asphere_coeffs must be flat lists")
    if a.size and "norm_radius" not in d:
        raise ValueError(f"{where}: a Zernike sag surface with zernike_coeffs needs norm_radius "
                         f"(the normalisation radius, mm)")
    rn = _num(d.get("norm_radius", 1.0), f"{where}: norm_radius")
    if not rn > 0:
        raise ValueError(f"{where}: norm_radius must be > 0 (mm), got {d['norm_radius']!r}")
    dx, dy = (_num(d.get(f"zernike_decenter_{ax}", 0.0), f"{where}: zernike_decenter_{ax}")
              for ax in "xy")
    ext = checks.switch(d.get("extrapolate", True), "extrapolate", where)
    return ZernikeSag(c=_arr(c), k=_arr(k), coeffs=_arr(coeffs), zernike=_arr(a),
                      norm_radius=_arr(rn), decenter_x=_arr(dx), decenter_y=_arr(dy),
                      semi_diameter=_arr(sd), ordering=ordering, extrapolate=ext)


def _freeform_to_json(s) -> dict:
    """The type-specific entries of a ``Biconic`` or ``ZernikeSag``."""
    if isinstance(s, Biconic):
        return {"type": "biconic", "curvature": _out(s.c), "conic": _out(s.k),
                "curvature_x": _out(s.cx), "conic_x": _out(s.kx)}
    return {"type": f"zernike_{s.ordering}", "curvature": _out(s.c), "conic": _out(s.k),
            "even_asphere_coeffs": _out(s.coeffs), "zernike_coeffs": _out(s.zernike),
            "norm_radius": _out(s.norm_radius), "zernike_decenter_x": _out(s.decenter_x),
            "zernike_decenter_y": _out(s.decenter_y), "extrapolate": s.extrapolate}
