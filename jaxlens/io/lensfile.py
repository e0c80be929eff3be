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
without ``values`` or ``distance`` and ``units`` other than mm.

Saving writes every number with Python's shortest round-trip representation, so
``load(save(lens))`` gives the same numbers to the last bit (as float64), the same
surface and material types and the same system data.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
from decimal import Decimal
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..optics import checks, paraxial
from ..optics import materials as _materials
from ..optics.lens import Lens, Sensor
from ..optics.materials import AbstractMaterial, Air, ModelGlass, Tabulated
from ..optics.surfaces import AbstractSurface, EvenAsphere, Hybrid, OddAsphere, Standard
from . import lens_keys
from .json_values import num as _num
from .json_values import nums as _nums
from .json_values import text as _text
from .json_values import whole as _whole

FORMAT = "jaxlens.lens/1"
"""The value of the ``format`` key this module writes (name/version)."""

_SUPPORTED_FORMATS = ("jaxlens.lens/1",)
_AIR_NAMES = ("", "air", "vacuum")
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


def nm_to_um(nm) -> np.ndarray:
    """Wavelengths in nm to µm, as the double nearest to the decimal value / 1000.

    ``587.5618`` nm gives exactly the float ``0.5875618`` (not ``587.5618 / 1000``, which
    is one ulp off), so files in nm and in µm describe the same wavelengths.
    """
    a = np.asarray(nm, np.float64)
    flat = [
        float(Decimal(repr(float(v))) / 1000) if math.isfinite(v) else v / 1000
        for v in a.reshape(-1)
    ]
    return np.array(flat, np.float64).reshape(a.shape)


def _arr(x: np.ndarray):
    return jnp.asarray(np.asarray(x, np.float64))


def _out(x) -> Any:
    """JSON value of an array or scalar: exact floats, "inf"/"-inf" for infinities."""
    a = np.asarray(x)
    if a.ndim == 0:
        v = float(a)
        if math.isnan(v):
            raise ValueError("save: cannot write NaN to a lens file")
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    return [_out(v) for v in a]


# --------------------------------------------------------------------------------------
# materials


def _catalog():
    try:
        from ..optics import catalog
    except ImportError:  # the catalog module lands separately
        return None
    return catalog


def _material_classes() -> dict[str, type]:
    out = {}
    mods = [_materials]
    cat = _catalog()
    if cat is not None:
        mods.append(cat)
    for mod in mods:
        for name in dir(mod):
            obj = getattr(mod, name)
            if isinstance(obj, type) and issubclass(obj, AbstractMaterial):
                out.setdefault(name, obj)
    return out


def same_material(a: AbstractMaterial, b: AbstractMaterial) -> bool:
    """True if two materials have the same type, static data and numbers (bit for bit)."""
    leaves_a, tree_a = jax.tree_util.tree_flatten(a)
    leaves_b, tree_b = jax.tree_util.tree_flatten(b)
    if tree_a != tree_b:
        return False
    return all(
        np.asarray(x).shape == np.asarray(y).shape
        and np.array_equal(np.asarray(x, np.float64), np.asarray(y, np.float64))
        for x, y in zip(leaves_a, leaves_b, strict=True)
    )


def catalog_material(name: str, where: str = "", nd: float | None = None,
                     vd: float | None = None) -> AbstractMaterial:
    """A glass by catalog name (``jaxlens.optics.catalog.get_material``); air names give ``Air()``.

    ``nd`` and ``vd``, where the file gives them, only feed the error's list of optically
    close glasses.

    Raises:
        ValueError: unknown glass; the message carries the catalog's close matches.
    """
    if name.strip().lower() in _AIR_NAMES:
        return Air()
    cat = _catalog()
    if cat is None:
        raise ValueError(
            f"{where}: glass {name!r} needs the glass catalog (jaxlens.optics.catalog), which is "
            "not available; give the material as {'nd':..,'vd':..} or an index table"
        )
    try:
        if nd is None or vd is None:
            return cat.get_material(name)
        return cat.get_material(name, nd=nd, vd=vd)
    except ValueError as e:
        raise ValueError(f"{where}: {e}" if where else str(e)) from None


SHIPPED_FOR_NAMES = ("SCHOTT", "CDGM", "PLASTICS", "MISC", "OHARA", "HOYA", "HIKARI", "SUMITA",
                     "CORNING")
"""Catalogs whose glasses a file may name (``jaxlens.optics.catalog.SHIPPED_CATALOGS``)."""


def is_catalog_glass(m: AbstractMaterial) -> bool:
    """True if ``m`` is exactly the shipped catalog glass of its name (bit for bit)."""
    name = getattr(m, "name", "")
    cat = _catalog()
    if not name or cat is None or isinstance(m, Air) or not isinstance(m, cat.CatalogMaterial):
        return False
    if m.catalog not in getattr(cat, "SHIPPED_CATALOGS", SHIPPED_FOR_NAMES):
        return False
    try:
        ref = cat.get_material(name, catalogs=[m.catalog])
        first = cat.get_material(name)
    except ValueError:
        return False
    # The name must resolve to this very glass when read back (first match wins).
    return same_material(ref, m) and same_material(first, m)


def _static_out(v: Any) -> Any:
    if isinstance(v, tuple | list):
        return [_static_out(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return {"float": repr(v)}
    return v


def _static_in(v: Any) -> Any:
    if isinstance(v, list):
        return tuple(_static_in(x) for x in v)
    if isinstance(v, dict) and set(v) == {"float"}:
        return float(v["float"])
    return v


def material_to_spec(m: AbstractMaterial, *, by_name: bool = True) -> Any:
    """The JSON value describing a material (see docs/lens-format.md).

    Shipped catalog glasses are written by name (when ``by_name``); model glasses as
    ``{"nd", "vd"}``; index tables as ``{"wavelengths_um", "indices"}``; anything else as
    ``{"class": <material class>, <its fields>...}`` so it reads back exactly.
    """
    if isinstance(m, Air):
        return "air"
    if by_name and is_catalog_glass(m):
        return m.name
    if isinstance(m, ModelGlass):
        spec = {"nd": _out(m.nd), "vd": _out(m.vd)}
    elif isinstance(m, Tabulated):
        spec = {"wavelengths_um": _out(m.wavelengths), "indices": _out(m.indices)}
    else:
        spec = {"class": type(m).__name__}
        for f in dataclasses.fields(m):
            if f.name == "name":
                continue
            v = getattr(m, f.name)
            if isinstance(v, AbstractMaterial):
                spec[f.name] = material_to_spec(v, by_name=False)
            elif f.metadata.get("static", False):
                spec[f.name] = _static_out(v)
            else:
                spec[f.name] = _out(v)
    if getattr(m, "name", ""):
        spec["name"] = m.name
    return spec


def _table_from_nm(table: dict, where: str) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(table, dict) or not table:
        raise ValueError(f"{where}: 'n' must be a non-empty {{wavelength_nm: index}} object")
    wl = nm_to_um([_num(k, f"{where} key") for k in table])
    n = np.array([_num(v, f"{where}[{k!r}]") for k, v in table.items()], np.float64)
    return wl, n


def _tabulated(wl, n, name, where) -> AbstractMaterial:
    wl, n = np.asarray(wl, np.float64), np.asarray(n, np.float64)
    if wl.ndim != 1 or wl.shape != n.shape or wl.size == 0:
        raise ValueError(
            f"{where}: index table needs equal-length lists, got {wl.shape}, {n.shape}"
        )
    if np.any(wl <= 0):
        raise ValueError(f"{where}: wavelengths must be positive")
    if np.any(n <= 0):
        raise ValueError(f"{where}: indices must be positive")
    if len(np.unique(wl)) != wl.size:
        raise ValueError(f"{where}: repeated wavelength in the index table")
    if name.strip().lower() in _AIR_NAMES and np.all(n == 1.0):
        return Air()
    try:
        return Tabulated(_arr(wl), _arr(n), name=name)
    except ValueError as e:
        raise ValueError(f"{where}: {e}") from None


def material_from_spec(spec: Any, where: str, *, n_table: Any = None) -> AbstractMaterial:
    """Build a material from its JSON value (string, dict) and an optional ``n`` table."""
    name = spec if isinstance(spec, str) else ""
    if isinstance(spec, dict):
        name = spec.get("name", "")
        if not isinstance(name, str):
            raise ValueError(f"{where}: material name must be a string, got {name!r}")
    if n_table is not None:  # reference-case style: the table wins over the name
        wl, n = _table_from_nm(n_table, f"{where}: n")
        return _tabulated(wl, n, name, where)
    if spec is None:
        return Air()
    if isinstance(spec, str):
        return catalog_material(spec, where)
    if not isinstance(spec, dict):
        raise ValueError(f"{where}: material must be a name or an object, got {spec!r}")
    if "class" not in spec:  # a class's own fields are checked by the class
        lens_keys.no_misspelled(spec, lens_keys.MATERIAL, f"{where}: material")
    if "class" in spec:
        classes = _material_classes()
        cls = classes.get(spec["class"])
        if cls is None:
            raise ValueError(
                f"{where}: unknown material class {spec['class']!r}; known: {sorted(classes)}"
            )
        kwargs = {}
        for f in dataclasses.fields(cls):
            if f.name == "name" or f.name not in spec:
                continue
            v = spec[f.name]
            if isinstance(v, dict) and "float" not in v:
                kwargs[f.name] = material_from_spec(v, f"{where}: {f.name}")
            elif f.metadata.get("static", False):
                kwargs[f.name] = _static_in(v)
            else:
                kwargs[f.name] = _arr(_nums(v, f"{where}: {f.name}", finite=False))
        try:
            return cls(**kwargs, name=name)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{where}: cannot build {spec['class']}: {e}") from None
    if "nd" in spec:
        nd = _num(spec["nd"], f"{where}: nd")
        vd = _num(spec.get("vd", "inf"), f"{where}: vd", finite=False)
        if nd < 1 or vd <= 0:
            raise ValueError(f"{where}: model glass needs nd >= 1 and vd > 0 (inf: no "
                             f"dispersion), got nd {nd}, vd {vd}")
        return ModelGlass(_arr(nd), _arr(vd), name=name)
    if "n" in spec:
        wl, n = _table_from_nm(spec["n"], f"{where}: n")
        return _tabulated(wl, n, name, where)
    if "indices" in spec:
        if "wavelengths_um" in spec:
            wl = _nums(spec["wavelengths_um"], f"{where}: wavelengths_um")
        elif "wavelengths_nm" in spec:
            wl = nm_to_um(_nums(spec["wavelengths_nm"], f"{where}: wavelengths_nm"))
        else:
            raise ValueError(f"{where}: an index table needs wavelengths_um or wavelengths_nm")
        return _tabulated(wl, _nums(spec["indices"], f"{where}: indices"), name, where)
    if name:
        return catalog_material(name, where)
    raise ValueError(
        f"{where}: cannot read material {spec!r}; give a catalog name, {{'nd','vd'}}, "
        "{'n': {nm: index}} or {'wavelengths_um', 'indices'}"
    )


# --------------------------------------------------------------------------------------
# surfaces


def _curvature(d: dict, where: str) -> float:
    c = d.get("curvature")
    r = d.get("radius")
    if c is not None:
        cv = _num(c, f"{where}: curvature")
        if r is not None:
            rv = _num(r, f"{where}: radius", finite=False)
            cr = 0.0 if math.isinf(rv) else (math.inf if rv == 0 else 1.0 / rv)
            if not math.isclose(cr, cv, rel_tol=1e-9, abs_tol=1e-15):
                raise ValueError(f"{where}: radius {r!r} and curvature {c!r} disagree")
        return cv
    if r is not None:
        rv = _num(r, f"{where}: radius", finite=False)
        if rv == 0:
            raise ValueError(f"{where}: radius 0 is not a surface; use curvature 0 for flat")
        return 0.0 if math.isinf(rv) else 1.0 / rv
    return 0.0


def surface_from_dict(d: dict, where: str, *, kind: str | None = None) -> AbstractSurface:
    """A surface from its JSON object; ``kind`` overrides the ``type`` key. What the surface
    class refuses (a semi-diameter beyond a steep sphere's edge, say) names ``where``."""
    try:
        return _surface(d, where, kind)
    except ValueError as e:
        raise ValueError(str(e) if str(e).startswith(where) else f"{where}: {e}") from None


def _surface(d: dict, where: str, kind: str | None) -> AbstractSurface:
    raw = _text(kind or d.get("type") or "standard", f"{where}: type")
    kind = re.sub(r"[^a-z0-9]", "", raw.lower())  # "Even Asphere" == "even_asphere"
    c = _curvature(d, where)
    k = _num(d.get("conic", 0.0), f"{where}: conic")
    sd = d.get("semi_diameter")
    sd = math.inf if sd is None else _num(sd, f"{where}: semi_diameter", finite=False)
    if not sd > 0:
        raise ValueError(f"{where}: semi_diameter must be > 0 (or 'inf'), got {sd!r}")
    coeffs = _nums(d.get("even_asphere_coeffs", []), f"{where}: even_asphere_coeffs")
    if coeffs.ndim != 1:
        raise ValueError(f"{where}: even_asphere_coeffs must be a flat list")
    has_odd = "odd_x" in d or "odd_y" in d
    # "oddasph", "Odd Asphere", "ODDASPHE"
    radial = "odd" in kind and "asph" in kind and "hybrid" not in kind
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
    if "hybrid" in kind or has_odd:
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
    if "asph" in kind or (kind in _STANDARD_TYPES and coeffs.size):
        return EvenAsphere(c=_arr(c), k=_arr(k), coeffs=_arr(coeffs), semi_diameter=_arr(sd))
    if kind in _STANDARD_TYPES:
        return Standard(c=_arr(c), k=_arr(k), semi_diameter=_arr(sd))
    raise ValueError(f"{where}: unknown surface type {raw!r}; use standard, evenasph, oddasph "
                     f"or hybrid")


def surface_to_dict(s: AbstractSurface) -> dict:
    """The JSON object of a surface (without thickness and material)."""
    if isinstance(s, Hybrid):
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
    return eqx.tree_at(lambda l: l.epd, lens, value)


def _aperture_of(d: dict, where: str) -> dict:
    ap = d.get("aperture", {})
    if isinstance(ap, int | float) and not isinstance(ap, bool):
        ap = {"epd": ap}
    if not isinstance(ap, dict):
        raise ValueError(f"{where}: aperture must be an object, got {ap!r}")
    keys = {
        "epd": ("epd", "EPD"),
        "fnum": ("fnum", "FNUM", "f_number"),
        "stop_semi_diameter": ("stop_semi_diameter",),
    }
    for top in ("epd", "EPD"):
        if top in d:
            v = _num(d[top], f"{where}: {top}")
            if not v > 0:
                raise ValueError(f"{where}: {top} (entrance pupil diameter) must be > 0 mm, "
                                 f"got {v}")
            return {"epd": v}
    for key, names in keys.items():  # EPD first: the reference cases give it besides others
        for n in names:
            if n in ap:
                v = _num(ap[n], f"{where}: aperture.{n}")
                if not v > 0:
                    raise ValueError(f"{where}: aperture.{n} must be > 0, got {v}")
                return {key: v}
    raise ValueError(
        f"{where}: no aperture; give aperture.epd, aperture.fnum or aperture.stop_semi_diameter"
    )


def _wavelengths_of(d: dict, where: str) -> tuple[np.ndarray, int]:
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
    if "primary" in d:
        p = d["primary"]
        if isinstance(p, bool) or not isinstance(p, int) or not 0 <= p < wl.size:
            raise ValueError(f"{where}: primary must be an index 0..{wl.size - 1}, got {p!r}")
        return wl, p
    for key in ("primary_wavelength_um", "primary_wavelength_nm", "primary_wavelength"):
        if key in d:
            target = _num(d[key], f"{where}: {key}")
            target = float(nm_to_um(target)) if key.endswith("_nm") else target
            i = int(np.argmin(np.abs(wl - target)))
            if not math.isclose(wl[i], target, rel_tol=1e-9):
                raise ValueError(f"{where}: {key} {d[key]!r} is not one of the wavelengths")
            return wl, i
    return wl, 0


def _fields_of(d: dict, where: str) -> np.ndarray:
    f = d.get("fields", [0.0])
    if isinstance(f, dict):
        ftype = _text(f.get("type", "angle_deg_y"), f"{where}: fields.type")
        if ftype not in ("angle_deg_y", "angle_deg", "angle", "angle_deg_xy"):
            raise ValueError(f"{where}: field type {ftype!r} is not supported (angles in deg)")
        f = f.get("values", [0.0])
    out = np.atleast_1d(_nums(f, f"{where}: fields"))
    if out.size == 0:
        raise ValueError(f"{where}: no fields")
    if out.ndim > 2 or (out.ndim == 2 and out.shape[1] != 2):
        raise ValueError(f"{where}: fields must be a list of angles θy or of [θx, θy] pairs "
                         f"(deg), got an array of shape {out.shape}")
    return out


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
    lens_keys.check_keys(d, source)
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
    if dist <= 0:
        raise ValueError(f"{source}: the object distance must be > 0 or 'inf', got {dist}")
    obj_mat = Air()
    if obj is not None:
        obj_mat = material_from_spec(
            obj.get("material"), f"{source}: surface 0", n_table=obj.get("n")
        )

    surfaces, thick, mats, stops = [], [], [], []
    for j, s in enumerate(body):
        i = j + first
        where = f"{source}: surface {i}"
        if not isinstance(s, dict):
            raise ValueError(f"{where}: must be an object, got {s!r}")
        lens_keys.no_misspelled(s, lens_keys.SURFACE, where)
        if _text(s.get("type", ""), f"{where}: type").lower() in ("object", "image"):
            raise ValueError(f"{where}: an {s['type']} surface can only be first/last")
        surfaces.append(surface_from_dict(s, where))
        if "thickness" not in s:
            raise ValueError(f"{where}: missing 'thickness'")
        thick.append(_num(s["thickness"], f"{where}: thickness"))
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

    wl, primary = _wavelengths_of(d, source)
    fields = _fields_of(d, source)
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
    aperture = _aperture_of(d, source)
    key = next((k for k in ("wavelengths_um", "wavelengths_nm", "wavelengths") if k in d),
               "wavelengths")
    # The Lens checks these too, but here the message names the file and the key.
    checks.wavelengths(checks.NoMaterials, wl, f"{source}: {key}", "wavelength")
    checks.field_angles(fields, f"{source}: fields", "field angles")
    lens = Lens(
        surfaces=tuple(surfaces),
        thickness=_arr(np.array(thick)),
        materials=tuple(mats),
        stop=stop,
        epd=_arr(aperture.get("epd", 1.0)),
        fields=_arr(fields),
        wavelengths=_arr(wl),
        primary=primary,
        object_distance=_arr(dist),
        object_material=obj_mat,
        image=image,
        sensor=sensor,
        name=name,
        description=description,
    )
    # Before the paraxial work of the aperture: values the lens cannot be traced with.
    checks.wavelengths(lens, wl, f"{source}: {key}", "wavelength")
    checks.material_indices(lens, wl, source)
    checks.field_angles(fields, f"{source}: fields", "field angles")
    if "epd" not in aperture:
        lens = apply_aperture(lens, **aperture)
    return lens


def lens_to_dict(lens: Lens) -> dict:
    """The JSON object of a lens (format ``jaxlens.lens/1``)."""
    held = [f"{name} (Lens.{name} = {getattr(lens, name)})"
            for name in ("mirrors", "obscurations", "apertures") if getattr(lens, name)]
    if held:
        raise ValueError(f"save: {', '.join(held)} have no jaxlens JSON form yet; save the "
                         f"lens as .zmx")
    dist = math.inf if lens.object_distance is None else lens.object_distance
    obj = {
        "type": "object",
        "thickness": _out(dist),
        "material": material_to_spec(lens.object_material),
    }
    surfs = [obj]
    for i, s in enumerate(lens.surfaces):
        e = surface_to_dict(s)
        e["thickness"] = _out(lens.thickness[i])
        e["material"] = material_to_spec(lens.materials[i])
        if i == lens.stop:
            e["is_stop"] = True
        surfs.append(e)
    img = surface_to_dict(lens.image)
    surfs.append({"type": "image", "shape": img.pop("type"), **img})
    fields = np.asarray(lens.fields)
    out = {
        "format": FORMAT,
        "name": lens.name,
        **({"description": lens.description} if lens.description else {}),
        "units": {"length": "mm", "wavelength": "um", "angle": "deg"},
        "aperture": {"epd": _out(lens.epd)},
        "fields": {
            "type": "angle_deg_y" if fields.ndim <= 1 else "angle_deg_xy",
            "values": _out(np.atleast_1d(fields)),
        },
        "wavelengths_um": _out(np.atleast_1d(lens.wavelengths)),
        "primary": lens.primary,
        "surfaces": surfs,
    }
    if lens.sensor is not None:
        out["sensor"] = {
            "resolution": list(lens.sensor.resolution),
            "pixel_size": _out(lens.sensor.pixel_size),
        }
    return out


def _unique_keys(pairs: list) -> dict:
    """An object's pairs as a dict; a repeated key is refused (``json`` keeps the last
    value without a word, so ``"thickness": 3, "thickness": 30`` read as 30)."""
    d: dict = {}
    for k, v in pairs:
        if k in d:
            raise _RepeatedKey(f"key {k!r} appears twice in one object ({d[k]!r} and {v!r}); "
                               f"keep one")
        d[k] = v
    return d


class _RepeatedKey(ValueError):
    pass


def load_json(path: str | os.PathLike) -> Lens:
    """Read a JSON lens file."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8-sig") as f:
            d = json.load(f, object_pairs_hook=_unique_keys)
    except _RepeatedKey as e:
        raise ValueError(f"{path}: {e}") from None
    except json.JSONDecodeError as e:
        raise ValueError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start}); save the "
                         f"lens file as UTF-8") from None
    except RecursionError:
        raise ValueError(f"{path}: JSON nested too deeply to be a lens file") from None
    try:
        return lens_from_dict(d, source=path)
    except RecursionError:
        raise ValueError(f"{path}: JSON nested too deeply to be a lens file") from None


def _pretty(o: Any, level: int = 0) -> str:
    """JSON text with short objects and number lists on one line."""
    flat = json.dumps(o, ensure_ascii=False, allow_nan=False)
    if not isinstance(o, dict | list) or len(flat) + 2 * level <= 96:
        return flat
    if isinstance(o, list) and not any(isinstance(x, dict | list) for x in o):
        return flat
    pad, inner = "  " * level, "  " * (level + 1)
    if isinstance(o, dict):
        body = [
            f"{inner}{json.dumps(k, ensure_ascii=False)}: {_pretty(v, level + 1)}"
            for k, v in o.items()
        ]
        return "{\n" + ",\n".join(body) + "\n" + pad + "}"
    body = [f"{inner}{_pretty(v, level + 1)}" for v in o]
    return "[\n" + ",\n".join(body) + "\n" + pad + "]"


def dumps(lens: Lens) -> str:
    """The JSON text of a lens."""
    return _pretty(lens_to_dict(lens)) + "\n"


def save_json(lens: Lens, path: str | os.PathLike) -> None:
    """Write a JSON lens file."""
    text = dumps(lens)
    with open(os.fspath(path), "w", encoding="utf-8") as f:
        f.write(text)
