"""Materials in a JSON lens file: a catalog name, a model glass ``{"nd", "vd"}``, a table of
indices (``{"wavelengths_um", "indices"}``, or a reference case's ``"n": {nm: index}``), or a
material class with its fields; and back."""

from __future__ import annotations

import dataclasses
import difflib
import math
from typing import Any

import jax
import numpy as np

from ..optics import catalog
from ..optics import materials as _materials
from ..optics.materials import AbstractMaterial, Air, ModelGlass, Tabulated
from . import lens_keys
from .json_values import float64_array as _arr
from .json_values import json_number as _out
from .json_values import nm_to_um
from .json_values import num as _num
from .json_values import nums as _nums

_AIR_NAMES = ("", "air", "vacuum")


MAX_INDEX = 10.0
"""The largest refractive index an index table may give."""


def _material_classes() -> dict[str, type]:
    out = {}
    for mod in (_materials, catalog):
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
    try:
        if nd is None or vd is None:
            return catalog.get_material(name)
        return catalog.get_material(name, nd=nd, vd=vd)
    except ValueError as e:
        raise ValueError(f"{where}: {e}" if where else str(e)) from None


def is_catalog_glass(m: AbstractMaterial) -> bool:
    """True if ``m`` is exactly the shipped catalog glass of its name (bit for bit)."""
    name = getattr(m, "name", "")
    if not name or isinstance(m, Air) or not isinstance(m, catalog.CatalogMaterial):
        return False
    if m.catalog not in catalog.SHIPPED_CATALOGS:
        return False
    try:
        ref = catalog.get_material(name, catalogs=[m.catalog])
        first = catalog.get_material(name)
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
    wl = nm_to_um([_num(k, f"{where} key", text_ok=True) for k in table])
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
    if np.any(n > MAX_INDEX):  # 1e308 passes as finite, then overflows n·c in a trace
        raise ValueError(f"{where}: indices must be at most {MAX_INDEX:g} (germanium's is "
                         f"about 4), got {n.max():g}")
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
        known = {"class", "name"} | {f.name for f in dataclasses.fields(cls)}
        extra = sorted(set(spec) - known)
        if extra:  # a misspelt field was dropped and the class's default used without a word
            close = difflib.get_close_matches(extra[0], sorted(known), n=1)
            raise ValueError(f"{where}: material class {spec['class']} has no field "
                             f"{extra[0]!r}{f' (did you mean {close[0]!r}?)' if close else ''}"
                             f"; its fields: {sorted(known - {'class'})}")
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
        try:  # ModelGlass's own refusals (vd 0.6417 for 64.17) without the surface
            return ModelGlass(_arr(nd), _arr(vd), name=name)
        except ValueError as e:
            raise ValueError(f"{where}: {e}") from None
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
    if "catalog" in spec:  # was not read: the glass of the first catalog holding the name
        cat = spec["catalog"]
        if not name or not isinstance(cat, str):
            raise ValueError(f"{where}: material catalog needs a glass name and a catalog "
                             f"name, as in {{\"name\": \"N-BK7\", \"catalog\": "
                             f"\"SCHOTT\"}}, got {spec!r}")
        try:
            return catalog.get_material(name, catalogs=[cat.upper()])
        except ValueError as e:
            raise ValueError(f"{where}: catalog {cat!r}: {e}") from None
    if name:
        return catalog_material(name, where)
    raise ValueError(
        f"{where}: cannot read material {spec!r}; give a catalog name, {{'nd','vd'}}, "
        "{'n': {nm: index}} or {'wavelengths_um', 'indices'}"
    )


INDEX_RECORD = "index_at_wavelengths"
"""The surface key of a JSON lens file that records its medium's refractive index at each of
the file's wavelengths (``wavelengths_um``, in that order), as ``jaxlens.save`` computed it.

A catalog glass is written by name, and a name alone can mean other data to another tool or
to another version of a catalog (optiland's E48R has nd 1.53055; jaxlens's, from Zemax's ZEON
catalog, 1.53117).
The record makes the file say which medium it describes whatever the reader's catalog; the
reader checks it (``check_index_record``)."""

INDEX_RECORD_TOLERANCE = 1e-6
"""How far the reader's indices may be from a file's ``index_at_wavelengths``: above float32
rounding of a lens saved at float32 (about 1e-7), below any two glass data sets that differ
(catalogs quote nd to 1e-5)."""


def index_record(m: AbstractMaterial, wavelengths) -> list[float] | None:
    """The medium's index at each wavelength (µm), for ``INDEX_RECORD``; None for air."""
    if isinstance(m, Air):
        return None
    w = np.atleast_1d(np.asarray(wavelengths, np.float64))
    return [float(v) for v in np.asarray(m.index(_arr(w)), np.float64)]


def check_index_record(entry: Any, m: AbstractMaterial, wavelengths, where: str) -> None:
    """Refuse a surface whose medium ``m`` (as this jaxlens reads the file's material) is not
    the medium the file records in ``INDEX_RECORD`` (if it records one)."""
    if not isinstance(entry, dict) or entry.get(INDEX_RECORD) is None:
        return
    w = np.atleast_1d(np.asarray(wavelengths, np.float64))
    rec = _nums(entry[INDEX_RECORD], f"{where}: {INDEX_RECORD}")
    if rec.shape != w.shape:
        raise ValueError(f"{where}: {INDEX_RECORD} must hold one index per wavelength "
                         f"({w.size}: {[float(v) for v in w]} µm), got {rec.size}")
    n = np.asarray(m.index(_arr(w)), np.float64)
    worst = float(np.max(np.abs(n - rec)))
    if not worst <= INDEX_RECORD_TOLERANCE:
        name = getattr(m, "name", "") or type(m).__name__
        raise ValueError(
            f"{where}: material {name!r} has n = {[float(v) for v in n]} at "
            f"{[float(v) for v in w]} µm here, "
            f"but the file records n = {[float(v) for v in rec]} ({INDEX_RECORD}; off by "
            f"{worst:.3g}, more than {INDEX_RECORD_TOLERANCE:g}): this jaxlens's data for that "
            f"material are not those the file was written with. Give the material by its "
            f"formula ({{\"class\": ...}}) or an index table, or delete {INDEX_RECORD} to use "
            f"this jaxlens's data")
