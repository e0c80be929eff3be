"""Glass names of ``.zmx`` files: which catalog glass a ``GLAS`` line means.

A name is looked up in the catalogs the file's ``GCAT`` line names (side ``.AGF`` files
first, then the shipped catalogs that stand for them; the shipped SCHOTT holds the obsolete
glasses of SCHOTT's 2008 catalog too, so ``SK4`` is SCHOTT's own SK4), then as SCHOTT's
successor of a discontinued SCHOTT glass that it still lacks (its lead-free N- glass, LAF21 →
N-LAF21, or else its "A" version, SSK4 → SSK4A), then in every shipped catalog. The last two
are reported (a ``ZmxWarning``; an error under ``strict``): a glass of the same name from
another maker may be another glass. The nd and Vd that a ``GLAS`` line carries are
cross-checked against the catalog's. A side catalog holding the name a line uses in two
cases (N-BK7 and n-bk7: two records to a lookup that ignores case) is refused with both.
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings

import jax.numpy as jnp
import numpy as np

from ..optics import catalog
from ..optics.agf import read_records
from ..optics.catalog import decode_zemax_text as decode
from ..optics.checks import number_text
from ..optics.materials import AbstractMaterial, Air, ModelGlass
from .lensfile import catalog_material, material_from_spec
from .zmx_common import MARKER, ZmxWarning, report


def _arr(x):
    return jnp.asarray(np.asarray(x, np.float64))


SHIPPED_FOR_ZEMAX = {
    "SCHOTT": ("SCHOTT",),
    "CDGM": ("CDGM",),
    "MISC": ("MISC", "PLASTICS"),
    "ZEON": ("PLASTICS",),
    "OSAKAGASCHEMICAL": ("PLASTICS",),
    "OHARA": ("OHARA",),
    "HOYA": ("HOYA",),
    "HIKARI": ("HIKARI",),
    "NIKON": ("HIKARI",),  # the shipped HIKARI file is NIKON's Zemax catalog (2017-11)
    "SUMITA": ("SUMITA",),
    "CORNING": ("CORNING",),
    "INFRARED": ("INFRARED",),
    "LIGHTPATH": ("LIGHTPATH",),
    "HERAEUS": ("HERAEUS",),
    "UMICORE": ("UMICORE",),
    "TOPAS": ("TOPAS",),
    "ARCHER": ("ARCHER",),
    "ISUZU": ("ISUZU",),
    "LZOS": ("LZOS",),
    "RAD_HARD": ("RAD_HARD",),
    "RPO": ("RPO",),
    "ARTON": ("ARTON",),
}


def shipped_for(cat: str) -> tuple[str, ...]:
    """The shipped catalogs that stand for a GCAT name: its own, or those of its maker for a
    dated or prefixed variant (SUMITA_AUG2011, NIKON-HIKARI)."""
    if cat in SHIPPED_FOR_ZEMAX:
        return SHIPPED_FOR_ZEMAX[cat]
    return SHIPPED_FOR_ZEMAX.get(re.split(r"[_-]", cat, maxsplit=1)[0], ())


def read_agf_markers(path: str) -> dict[str, str]:
    """Glass name (upper case) -> jaxlens JSON material spec from ``GC jaxlens`` records."""
    with open(path, "rb") as fh:
        text = decode(fh.read(), path)
    out, name = {}, None
    for line in text.splitlines():
        t = line.split(maxsplit=1)
        if not t:
            continue
        if t[0] == "NM" and len(t) > 1:
            name = t[1].split()[0].upper()
        elif t[0] == "GC" and name and len(t) > 1 and t[1].startswith(MARKER):
            out[name] = t[1][len(MARKER) :]
    return out


class GlassResolver:
    """Resolves a file's GLAS lines (``get``) in the order of the module docstring."""

    def __init__(self, path: str, gcat: list[str], strict: bool = False,
                 unknown_glass: str = "error"):
        if unknown_glass not in ("error", "model"):
            raise ValueError(f"{path}: unknown_glass must be 'error' or 'model', got "
                             f"{unknown_glass!r}")
        self.dir = os.path.dirname(os.path.abspath(path))
        self.gcat = gcat
        self.strict = strict
        self.unknown_glass = unknown_glass
        self.side: dict[str, tuple[dict, dict, str]] = {}
        # catalog -> upper-case name -> its records, where a side catalog names a glass in
        # two cases (N-BK7 and n-bk7)
        self.cases: dict[str, dict[str, list]] = {}
        try:
            listing = {n.upper(): n for n in os.listdir(self.dir)}
        except OSError:
            listing = {}
        for cat in gcat:
            fname = listing.get(f"{cat}.AGF")
            if fname is not None:
                p = os.path.join(self.dir, fname)
                latest: dict = {}
                for r in read_records(p):
                    up = r.name.upper()
                    if up in latest and latest[up].name != r.name:
                        self.cases.setdefault(cat, {}).setdefault(up, [latest[up]]).append(r)
                    latest[up] = r
                mats = {up: r.to_material() for up, r in latest.items()}
                self.side[cat] = (mats, read_agf_markers(p), p)

    def get(self, ln) -> AbstractMaterial:
        """The material of a GLAS line; what a material class refuses (a model glass of
        nd 1e308, say) is reported with the line."""
        try:
            return self._material(ln)
        except ValueError as e:
            if str(e).startswith(f"{ln.path}:"):
                raise
            raise ln.error(str(e)) from None

    def _material(self, ln) -> AbstractMaterial:
        # Some vendors' files write "family|glass" (Edmund: SCHOTT-BK|N-BK7).
        name = ln.tokens[1].rsplit("|", 1)[-1]
        up = name.upper()
        if up == "___BLANK":
            nd = ln.float(4, "model glass nd")
            vd = ln.float(5, "model glass Vd")
            if not nd >= 1 or vd < 0:
                raise ln.error(f"model glass needs nd >= 1 and Vd >= 0 (0: no dispersion), got "
                               f"nd {nd:g}, Vd {vd:g}")
            if len(ln.tokens) > 6 and ln.float(6, "model glass ΔPgF") != 0:
                # Zemax's model bends the dispersion curve by ΔPgF; jaxlens's ModelGlass is
                # linear in 1/λ² (nd and nF - nC kept): the index off the d line differs.
                warnings.warn(f"{ln.path}:{ln.number}: model glass ΔPgF "
                              f"{ln.tokens[6]} ignored: jaxlens's model glass keeps nd "
                              f"and Vd only (no partial-dispersion deviation): "
                              f"{ln.text.strip()!r}", ZmxWarning, stacklevel=4)
            return ModelGlass(_arr(nd), _arr(math.inf if vd == 0 else vd))
        if up == "MIRROR":
            raise ln.error("GLAS MIRROR belongs on a lens surface (not the object or image)")
        if up == "AIR":
            return Air()
        for cat in self.gcat:
            if cat in self.side:
                mats, markers, p = self.side[cat]
                if up in self.cases.get(cat, {}):
                    # The lookup ignores case (as Zemax's): the later record was used without
                    # a word (the AGF reader's warning aside), whichever the line names.
                    a, b = self.cases[cat][up][:2]
                    raise ln.error(f"glass {name!r}: the side catalog {p} has two glasses of "
                                   f"this name in two cases, {a.name} ({a.source}) and {b.name} "
                                   f"({b.source}); glass names ignore case, so which one the "
                                   f"file means is not known: rename or remove one")
                if up in markers:
                    try:
                        spec = json.loads(markers[up])
                    except json.JSONDecodeError:
                        raise ValueError(f"{p}: bad jaxlens record for glass {name}") from None
                    return material_from_spec(spec, f"{p}: glass {name}")
                if up in mats:
                    return mats[up]
        for cat in self.gcat:
            for shipped in shipped_for(cat):
                try:
                    m = catalog.get_material(name, catalogs=[shipped])
                except ValueError:
                    continue
                return _cross_checked(m, ln)
        code = mil_number(name)
        if code is not None:
            # Zemax reads a six-digit MIL number in the glass column as a glass of that nd
            # and Vd ("Using MIL number glasses"); the line's own nd and Vd are not used.
            return ModelGlass(_arr(code[0]), _arr(code[1]))
        successor = self._successor(ln, name)
        if successor is not None:
            return successor
        nd, vd = _glas_nd_vd(ln)
        try:
            m = catalog_material(name, nd=nd, vd=vd)
        except ValueError as e:
            if self.unknown_glass == "model" and nd is not None:
                warnings.warn(f"{ln.path}:{ln.number}: glass {name!r} is in no catalog jaxlens "
                              f"reads; using a model glass with the line's nd {nd:g}, Vd {vd:g} "
                              f"(exact at the d line, linear in 1/λ² elsewhere; "
                              f"unknown_glass='model'){_stale_note(name, nd, vd)}", ZmxWarning,
                              stacklevel=4)
                return ModelGlass(_arr(nd), _arr(vd))
            missing = [c for c in self.gcat if c not in self.side and not shipped_for(c)]
            if missing:
                e = (f"{e}. The file's GCAT names {', '.join(missing)}, which jaxlens does not "
                     f"ship (GCAT catalogs it reads: {', '.join(SHIPPED_FOR_ZEMAX)}); put "
                     f"{missing[0]}.AGF beside the file or use jaxlens.catalog.register_catalog")
            if nd is not None:
                e = (f"{e}. To open the file anyway with a model glass of the line's nd {nd:g}, "
                     f"Vd {vd:g}, load it with unknown_glass='model'")
            elif ln.text.split()[0].upper() == "GLSS":
                e = (f"{e}. A configuration's GLSS row gives the glass's name only, no nd "
                     f"and Vd, so no model glass can stand in for it; supply the glass's "
                     f"catalog (.AGF) beside the file")
            elif _placeholder_nd_vd(ln):
                e = (f"{e}. Its GLAS line gives nd 1.5, Vd 40, Zemax's defaults for a glass "
                     f"it has not looked up, not this glass's data, so no model glass can "
                     f"stand in for it (a model glass needs the line's real nd and Vd); "
                     f"supply the glass's catalog (.AGF) beside the file")
            elif self.unknown_glass == "model" and len(ln.tokens) > 5:
                # The option was given, and the message said nothing of why it was not used.
                e = (f"{e}. unknown_glass='model' needs the line's nd > 1 and Vd > 0 (its 5th "
                     f"and 6th fields), got nd {ln.tokens[4]}, Vd {ln.tokens[5]}")
            e = f"{e}{_molded_note(name)}"
            raise ln.error(f"glass {name!r}: {e}") from None
        if self.gcat and getattr(m, "catalog", None) is not None:
            # A glass of the same name from another maker may be another glass (CDGM BAF4 is
            # nd 1.583, SCHOTT's BaF4 1.606): never take it silently.
            report(self.strict, f"{ln.path}:{ln.number}: glass {name!r} is not in the file's "
                    f"catalogs ({', '.join(self.gcat)}); using {m.catalog} {m.name}"
                    f"{_nd_vd_text(m)}, a glass of the same name from another catalog: check "
                    f"it, or put the file's catalog (.AGF) beside it")
        return _cross_checked(m, ln)

    def _successor(self, ln, name: str):
        """SCHOTT's lead-free successor N-<name> of a glass that the shipped SCHOTT catalog
        lacks, 2008 obsolete glasses included (LAF21 → N-LAF21, LASF9 → N-LASF9), or else its
        "A" version <name>A (SSK4 → SSK4A, the same nd and Vd), with a
        warning (an error under strict): the successor matches the old glass's nd and Vd to
        about 1e-3 and 0.5, so it is a closer guess than a glass of the same name from another
        maker."""
        if "SCHOTT" not in self.gcat or "SCHOTT" in self.side or name.upper().startswith("N-"):
            return None
        for new, kind in (("N-" + name, "lead-free successor"), (name + "A", "successor")):
            try:
                m = catalog.get_material(new, catalogs=["SCHOTT"])
            except ValueError:
                continue
            report(self.strict, f"{ln.path}:{ln.number}: glass {name!r} is not in the shipped "
                    f"SCHOTT catalog (a discontinued glass); using its {kind} "
                    f"{m.name}{_nd_vd_text(m)}; put the file's SCHOTT.AGF beside it for the "
                    f"original")
            return _cross_checked(m, ln)
        return None


def _stale_note(name: str, nd: float, vd: float) -> str:
    """A warning's note where a GLAS line's nd and Vd are those of another catalog glass to
    the digits written: Zemax keeps the nd and Vd of the glass a line last held, so they may
    be stale (a line naming LASFN30 with SK16's 1.6204 and 60.32)."""
    c, other, d, v = catalog.nearest_glasses(nd, vd, 1)[0]
    if other.upper() == name.upper() or abs(d - nd) > 1e-4 or abs(v - vd) > 0.01:
        return ""
    return (f". These are the nd and Vd of {c} {other}: a GLAS line keeps those of the glass "
            f"it last held, so check that they are {name}'s")


def _nd_vd_text(m) -> str:
    nd, vd = getattr(m, "catalog_nd", None), getattr(m, "catalog_vd", None)
    return "" if nd is None or vd is None else f" (nd {nd:.5f}, Vd {vd:.2f})"


ND_TOLERANCE, VD_TOLERANCE = 2e-3, 0.5
"""Largest accepted difference between a GLAS line's nd and Vd and the catalog's."""


def _cross_checked(m: AbstractMaterial, ln) -> AbstractMaterial:
    """Warn when the nd and Vd a GLAS line carries differ from the catalog glass found."""
    nd, vd = _glas_nd_vd(ln)
    cat_nd, cat_vd = getattr(m, "catalog_nd", None), getattr(m, "catalog_vd", None)
    if nd is None or cat_nd is None or cat_vd is None or not cat_vd > 0:
        return m  # cat_vd 0: the catalog has no d-line data (IR materials: nd 1, Vd 0)
    if abs(nd - cat_nd) > ND_TOLERANCE or abs(vd - cat_vd) > VD_TOLERANCE:
        warnings.warn(
            f"{ln.path}:{ln.number}: GLAS {m.name} gives nd {nd:g}, Vd {vd:g}, but catalog "
            f"{getattr(m, 'catalog', '')} has nd {cat_nd:g}, Vd {cat_vd:g}; using the "
            f"catalog's glass (a different glass of the same name, or numbers the line kept "
            f"from the glass it held before, as after a substitution solve?)", ZmxWarning,
            stacklevel=5)
    return m


def _placeholder_nd_vd(ln) -> bool:
    """The GLAS line's nd and Vd are Zemax's untouched defaults (1.5, 40): no claim."""
    try:
        return (number_text(ln.tokens[4]), number_text(ln.tokens[5])) == (1.5, 40.0)
    except (IndexError, ValueError):
        return False


def _molded_note(name: str) -> str:
    """A note for ``<glass>_MOLD`` (a molded-lens catalog's entry, such as RPO's): the
    catalog glass of the base name is a different index, so it is not substituted."""
    if not name.upper().endswith("_MOLD"):
        return ""
    base = name[: -len("_MOLD")]
    try:
        m = catalog_material(base)
    except ValueError:
        return ""
    return (f". {name} is {base} as a molded lens (a molding catalog's entry); jaxlens has "
            f"{getattr(m, 'catalog', '')} {m.name}, but a molded glass's index differs from "
            f"the catalog glass's by the molding, so it is not taken in its place")


MIL_NUMBER = re.compile(r"([0-9]{3})([0-9]{3})")
"""A six-digit MIL number (MIL-G-174 glass code): 847238 is nd 1.847, Vd 23.8."""


def mil_number(name: str) -> tuple[float, float] | None:
    """(nd, Vd) of a glass named by a six-digit MIL number (``847238`` → (1.847, 23.8)), else
    None. Zemax takes such a name in the glass column as a glass of that nd and Vd (its
    "MIL number glass", computed from the number, not from a catalog); jaxlens reads it as a
    ``ModelGlass`` of that nd and Vd, exact at the d line like a ``___BLANK`` model glass
    (whose dispersion away from the d line is jaxlens's, linear in 1/λ²). A Vd of 0
    (``517000``) is no glass."""
    hit = MIL_NUMBER.fullmatch(name)
    if hit is None or int(hit.group(2)) == 0:
        return None
    vd = hit.group(2)
    return float(f"1.{hit.group(1)}"), float(f"{vd[:2]}.{vd[2]}")  # the decimals, rounded once


def _glas_nd_vd(ln) -> tuple[float | None, float | None]:
    """nd and Vd that a GLAS line carries after the name (tokens 4 and 5), if valid."""
    try:
        nd, vd = number_text(ln.tokens[4]), number_text(ln.tokens[5])
    except (IndexError, ValueError):
        return None, None
    if not (math.isfinite(nd) and nd > 1.0 and math.isfinite(vd) and vd > 0.0):
        return None, None
    if (nd, vd) == (1.5, 40.0):  # Zemax's untouched model-glass defaults: no claim
        return None, None
    return nd, vd
