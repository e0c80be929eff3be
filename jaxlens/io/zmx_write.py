"""Writing Zemax ``.zmx`` lens files and their side AGF catalogs (the format:
``jaxlens.io.zmx``)."""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from dataclasses import dataclass

import numpy as np

from ..optics import materials as _materials
from ..optics.catalog import ND_TOLERANCE, catalog_names
from ..optics.coordinates import CoordinateBreak
from ..optics.input_files import input_file
from ..optics.lens import Lens
from ..optics.materials import AbstractMaterial, Air, ModelGlass, Tabulated
from ..optics.surfaces import (
    AbstractSurface,
    EvenAsphere,
    Hybrid,
    OddAsphere,
    Standard,
    TiltedPlane,
)
from . import lensfile, zmx_glass, zmx_surfaces, zmx_system
from .json_values import loadable, output_file, write_whole
from .zmx_common import (
    MARKER,
    MAX_XPOLY_DEGREE,
    PLASTIC_CATALOG,
    ZEMAX_CATALOGS,
    ZmxWarning,
    term_powers,
    xpoly_terms,
)

# ---------------------------------------------------------------------------- numbers


def _z(x: float) -> str:
    """Zemax-style number, exact (shortest round trip), e.g. ``6.41655E+001``."""
    x = float(x)
    if x == 0.0:
        return "0"
    if not math.isfinite(x):
        raise ValueError(f"save_zmx: cannot write the non-finite number {x}")
    return np.format_float_scientific(x, unique=True, exp_digits=3, trim="0").upper()


# ---------------------------------------------------------------------------- writing


def _zemax_catalog(m: AbstractMaterial) -> str | None:
    """The Zemax catalog that holds ``m`` exactly as jaxlens ships it, or None."""
    if not lensfile.is_catalog_glass(m):
        return None
    if m.catalog == "PLASTICS":
        return PLASTIC_CATALOG.get(m.name.upper())
    return m.catalog if m.catalog in ZEMAX_CATALOGS else None


def _formula(m: AbstractMaterial):
    """(Zemax formula number, coefficients) holding ``m`` exactly, or None."""
    M = _materials
    kinds = [
        (getattr(M, n, None), f)
        for n, f in (
            ("Schott", 1),
            ("Herzberger", 3),
            ("Sellmeier2", 4),
            ("Conrady", 5),
            ("Handbook1", 7),
            ("Handbook2", 8),
            ("Sellmeier4", 9),
        )
    ]
    if type(m).__name__ == "CatalogMaterial":
        return _formula(m.model)
    if isinstance(m, ModelGlass):
        # n = A + B/λ² exactly as the Schott series n² = A² + 2AB/λ² + B²/λ⁴.
        nd, vd = float(m.nd), float(m.vd)
        b = (nd - 1.0) / vd / (M.LAMBDA_F**-2 - M.LAMBDA_C**-2)
        a = nd - b * M.LAMBDA_D**-2
        return 1, [a * a, 0.0, 2 * a * b, b * b, 0.0, 0.0]
    if isinstance(m, M.Sellmeier):
        B, C = np.asarray(m.B, np.float64), np.asarray(m.C, np.float64)
        k = B.size
        if k > 5:
            return None
        form = {4: 6, 5: 11}.get(k, 2)
        terms = max(k, 3) if form == 2 else k
        B, C = np.pad(B, (0, terms - k)), np.pad(C, (0, terms - k))
        return form, [float(v) for pair in zip(B, C, strict=True) for v in pair]
    laurent = getattr(M, "Laurent", None)
    if laurent is not None and isinstance(m, laurent):
        table = {
            tuple(M.EXTENDED_POWERS): 10,
            tuple(M.EXTENDED2_POWERS): 12,
            tuple(M.EXTENDED3_POWERS): 13,
        }
        form = table.get(tuple(m.powers))
        return None if form is None else (form, [float(v) for v in np.asarray(m.coeffs)])
    for cls, form in kinds:
        if cls is not None and isinstance(m, cls):
            return form, [float(v) for v in np.asarray(m.coeffs, np.float64)]
    return None


_SCHOTT_POWERS = (0, -2, -4, 2, -6, -8)  # order in which the fit adds Schott terms


def _schott_fit(wl: np.ndarray, n: np.ndarray, exact_wl=(), exact_n=()) -> list[float]:
    """Schott-formula coefficients through (wl, n): exact for ≤ 6 points, else least squares;
    through (exact_wl, exact_n) (the file's wavelengths) exactly where there are at most 6
    of those (the least squares then over the others, in the rest of the formula's freedom)."""
    ew, en = np.asarray(exact_wl, np.float64), np.asarray(exact_n, np.float64)
    # No more terms than the larger set needs: 3 table entries beside 3 file wavelengths
    # took all 6 terms, and the fit through 6 close points put Vd at 18.7 for N-BK7's 64.
    k = min(max(len(wl), len(ew)), 6)
    powers = _SCHOTT_POWERS[:k]
    order = {0: 0, 2: 1, -2: 2, -4: 3, -6: 4, -8: 5}

    def rows(w):
        return np.stack([w**p for p in powers], axis=-1)

    A, b = rows(np.asarray(wl, np.float64)), np.asarray(n, np.float64) ** 2
    if 0 < len(ew) <= k:
        C, d = rows(ew), en**2
        x0 = np.linalg.lstsq(C, d, rcond=None)[0]
        _, sv, vt = np.linalg.svd(C)
        null = vt[int(np.sum(sv > sv[0] * 1e-13)):].T
        z = np.linalg.lstsq(A @ null, b - A @ x0, rcond=None)[0] if null.size else 0.0
        sol = x0 + (null @ z if null.size else 0.0)
    else:
        A, b = (np.concatenate([A, rows(ew)]), np.concatenate([b, en**2])) if len(ew) else (A, b)
        sol, *_ = np.linalg.lstsq(A, b, rcond=None)
    out = [0.0] * 6
    for p, v in zip(powers, sol, strict=True):
        out[order[p]] = float(v)
    return out


def _nd_vd(m: AbstractMaterial) -> tuple[float, float]:
    n = np.asarray(
        m.extrapolated_index(np.array([_materials.LAMBDA_D, _materials.LAMBDA_F,
                                       _materials.LAMBDA_C])),
        np.float64,
    )
    dn = n[1] - n[2]
    return float(n[0]), float((n[0] - 1.0) / dn) if dn != 0 else 0.0


@dataclass
class _AgfGlass:
    name: str
    material: AbstractMaterial
    marker: bool


def _sanitize(name: str) -> str:
    s = re.sub(r"[^A-Z0-9_\-.]", "_", name.upper())
    return s or "GLASS"


class _GlassWriter:
    """Decides how each material is written and collects the side AGF catalogs."""

    def __init__(self, stem: str, model_glass: str, wavelengths: np.ndarray):
        self.wavelengths = wavelengths
        base = _sanitize(stem).replace(".", "_").replace("-", "_")
        self.own = base if base not in ZEMAX_CATALOGS else base + "_JL"
        self.model_glass = model_glass
        self.agf: dict[str, list[_AgfGlass]] = {}
        self.catalogs: list[str] = []
        # Every glass name the file uses (upper case) and its material: Zemax finds a GLAS
        # name by searching the GCAT catalogs in order, so a name must mean one glass in all.
        self.names: dict[str, AbstractMaterial] = {}
        # Zemax catalog glass name (upper) -> (its GCAT catalog, its shipped catalog)
        self.homes: dict[str, tuple[str, str]] = {}

    def reserve(self, materials) -> None:
        """Claim the names of the Zemax catalog glasses first: those cannot be renamed."""
        for m in materials:
            if not isinstance(m, Air) and _zemax_catalog(m) is not None:
                self.names.setdefault(m.name.upper(), m)

    def _clashes(self, name: str, m: AbstractMaterial) -> bool:
        taken = self.names.get(name.upper())
        return taken is not None and not lensfile.same_material(taken, m)

    def _use(self, cat: str) -> None:
        if cat not in self.catalogs:
            self.catalogs.append(cat)

    def _add(self, cat: str, name: str, m: AbstractMaterial, marker: bool) -> str:
        """Put ``m`` in catalog ``cat`` under ``name``, or ``name_2``, … when another glass
        of the file has that name; a glass already written keeps its name."""
        base, i = name, 1
        while self._clashes(name, m):
            i += 1
            name = f"{base}_{i}"
        if name.upper() not in self.names:
            self.names[name.upper()] = m
            self.agf.setdefault(cat, []).append(_AgfGlass(name, m, marker))
        return name

    def glas(self, m: AbstractMaterial) -> str | None:
        """The GLAS line for a material (None for air)."""
        if isinstance(m, Air):
            return None
        if isinstance(m, ModelGlass) and self.model_glass == "blank":
            vd = float(m.vd)
            return (
                f"GLAS ___BLANK 1 0 {float(m.nd)!r} {_z(0.0 if math.isinf(vd) else vd)} 0 0 0 0 0 0"
            )
        cat = _zemax_catalog(m)
        if cat is not None:
            self._use(cat)
            self.homes[m.name.upper()] = (cat, m.catalog)
            return f"GLAS {m.name} 0 0 {float(m.catalog_nd)!r} {_z(m.catalog_vd)} 0 0 0 0 0 0"
        plain = (
            type(m).__name__ == "CatalogMaterial"
            and m.catalog
            and m.catalog not in ZEMAX_CATALOGS
            and re.fullmatch(r"[\w\-.]+", m.name)
            and re.fullmatch(r"\w+", m.catalog)
            and _formula(m) is not None
            and m.formula == _formula(m)[0]
            and not self._clashes(m.name, m)
        )
        if plain:  # a user AGF glass: its own catalog, read back exactly by load_agf
            cat = m.catalog
            name = self._add(cat, m.name, m, marker=False)
        else:  # exact definition kept in a GC record
            cat = self.own
            name = self._add(cat, _sanitize(getattr(m, "name", "") or "JLGLASS"), m, True)
        if cat not in self.catalogs:
            self.catalogs.insert(0, cat)  # side catalogs first: Zemax searches in order
        nd, vd = self._nd_vd_of(m)
        return f"GLAS {name} 0 0 {nd!r} {_z(vd)} 0 0 0 0 0 0"

    def gcat(self) -> list[str]:
        """The GCAT catalogs: the side catalogs first, then the Zemax catalogs in an order
        that reads every glass written by name from its own catalog. Zemax (and the
        reader) take a GLAS name from the first GCAT catalog that has it, and makers share
        names (SF11 is SCHOTT's and NIKON-HIKARI's): a glass's catalog must come before every
        other listed catalog holding another glass of its name. Among catalogs free to go
        anywhere, the order is the lens's (first use). A glass is written by name only where
        its name finds it first in jaxlens's own search order, so an order always exists;
        should none, the glasses are named in a ``ValueError``.
        """
        side = [c for c in self.catalogs if c not in ZEMAX_CATALOGS]
        zemax = [c for c in self.catalogs if c in ZEMAX_CATALOGS]
        names = {c: [{n.upper() for n in catalog_names(catalog=sc)}
                     for sc in zmx_glass.shipped_for(c)] for c in zemax}
        shipped = {c: zmx_glass.shipped_for(c) for c in zemax}
        after = {c: set() for c in zemax}  # catalog -> the catalogs that must follow it
        why = {}
        for name, (home, own) in self.homes.items():
            for c in zemax:
                # The shipped catalog a lookup in c finds the name in, if any.
                found = next((sc for sc, held in zip(shipped[c], names[c], strict=True)
                              if name in held), None)
                if c != home and found is not None and found != own:
                    after[home].add(c)
                    why[(home, c)] = name
        order, left = [], list(zemax)
        while left:
            free = [c for c in left if not any(c in after[o] for o in left if o != c)]
            if not free:
                pairs = sorted(f"{why[(a, b)]} ({a}, also in {b})" for a in left
                               for b in after[a] if b in left)
                raise ValueError(f"save_zmx: no GCAT order reads every glass from its own "
                                 f"catalog: {'; '.join(pairs)}; Zemax takes a name from the "
                                 f"first listed catalog that has it")
            order.append(free[0])
            left.remove(free[0])
        return side + order

    def _cd(self, m) -> tuple[int, list[float], bool]:
        """The CD record of ``m``: (formula, coefficients, exact); a material no Zemax
        formula holds gets a Schott fit, exact at the lens's wavelengths (up to 6) and
        fitted to a table's entries, else to 0.38-1 µm."""
        exact = _formula(m)
        if exact is not None:
            return exact[0], exact[1], True
        if isinstance(m, Tabulated):
            wl, n = np.asarray(m.wavelengths, np.float64), np.asarray(m.indices, np.float64)
        else:
            wl = np.linspace(0.38, 1.0, 32)
            n = np.asarray(m.index(wl), np.float64)
        # Exact at the file's wavelengths (Zemax traces those), the data fitted in what
        # freedom is left.
        at = np.asarray(m.index(self.wavelengths), np.float64)
        return 1, _schott_fit(wl, n, self.wavelengths, at), False

    def _nd_vd_of(self, m):
        """The catalog's nd and Vd while the model still gives that nd; a model whose
        coefficients were changed (optimised) gets its own, which ``load_agf`` checks the
        CD record against. A fitted CD record gets the fit's nd and Vd: a table's own Vd
        (linear in 1/λ² between its entries) differed from its fit's by 2.7 %, and the NM
        record then disagreed with its formula."""
        form, coeffs, exact = self._cd(m)
        if not exact:
            return _nd_vd(_materials.Schott(np.asarray(coeffs, np.float64)))
        nd, vd = _nd_vd(m)
        if (type(m).__name__ == "CatalogMaterial" and m.catalog_nd is not None
                and math.isfinite(m.catalog_nd) and abs(nd - m.catalog_nd) <= ND_TOLERANCE):
            return float(m.catalog_nd), float(m.catalog_vd)
        return nd, vd

    def write_agf(self, folder: str) -> list[str]:
        wavelengths = self.wavelengths
        written, texts = [], []
        lo = min(0.3, float(np.min(wavelengths)))
        hi = max(2.5, float(np.max(wavelengths)))
        for cat, entries in self.agf.items():
            lines = [f"CC {cat}: glasses written by jaxlens"]
            for e in entries:
                m = e.material
                nd, vd = self._nd_vd_of(m)
                form, coeffs, exact = self._cd(m)
                if not exact:
                    fit = _materials.Schott(np.asarray(coeffs, np.float64)).index(wavelengths)
                    off = float(np.max(np.abs(np.asarray(fit, np.float64)
                                              - np.asarray(m.index(wavelengths), np.float64))))
                    if not off <= 1e-9:
                        warnings.warn(
                            f"save_zmx: glass {e.name} ({type(m).__name__}) has no Zemax "
                            f"formula; the Schott formula written to {cat}.AGF for Zemax "
                            f"is {off:.2g} off its index at the file's {len(wavelengths)} "
                            f"wavelengths (exact at up to 6). jaxlens reads it back exactly "
                            f"(the GC record)",
                            ZmxWarning,
                            stacklevel=3,
                        )
                code = f"{round((nd - 1) * 1000):03d}{round(vd * 10) % 1000:03d}"
                lines.append(f"NM {e.name} {form} {code} {nd!r} {vd!r} 0 0 0")
                if e.marker:
                    spec = lensfile.material_to_spec(m, by_name=False)
                    lines.append("GC " + MARKER + json.dumps(spec, separators=(",", ":")))
                lines.append("ED 0 0 0 0 0")
                lines.append("CD " + " ".join(_z(c) for c in coeffs))
                lines.append("TD 0 0 0 0 0 0 20")
                rng = (lo, hi) if e.marker else getattr(m, "wavelength_range", None)
                if rng is not None:
                    lines.append(f"LD {float(rng[0])!r} {float(rng[1])!r}")
            path = os.path.join(folder, f"{cat}.AGF")
            texts.append((path, _merged(path, lines, shared=cat != self.own)))
        for path, lines in texts:  # every catalog checked before any is written
            write_whole(path, "\n".join(lines) + "\n", newline="\r\n")
            written.append(path)
        return written


def _records(lines: list[str]) -> dict[str, list[str]]:
    """The glass records of an AGF catalog's lines: upper-case name -> its lines (NM …)."""
    out: dict[str, list[str]] = {}
    rec = None
    for ln in lines:
        if ln.startswith("NM "):
            rec = out.setdefault(ln.split()[1].upper(), [])
        if rec is not None:
            rec.append(ln.rstrip())
    return out


def _merged(path: str, lines: list[str], *, shared: bool) -> list[str]:
    """The lines to write at ``path`` for a catalog of ``lines``. A file already there must be
    one jaxlens wrote (a catalog of the user's own is never replaced). A catalog that several
    lens files share (named after a glass's catalog, not after the lens) keeps the glasses
    other lens files of the folder use; a glass of the same name must hold the same data."""
    if not os.path.exists(path):
        return lines
    input_file(path, "save_zmx", "glass catalog (.agf) to merge with")  # a FIFO hung here
    with open(path, encoding="utf-8", errors="replace") as fh:
        old = fh.read().splitlines()
    mark = lines[0]  # "CC <catalog>: glasses written by jaxlens"
    if not old or old[0].rstrip() != mark:
        raise ValueError(f"save_zmx: {path} exists and was not written by jaxlens; writing this "
                         f"lens's glasses there would replace that catalog. Save the lens into "
                         f"another folder, or move the file")
    if not shared:  # the lens's own catalog: replaced, as the lens file is
        return lines
    before, new = _records(old[1:]), _records(lines[1:])
    for name, rec in new.items():
        if name in before and before[name] != rec:
            raise ValueError(f"save_zmx: {path} already holds glass {name} with other data (for "
                             f"another lens file in that folder); replacing it would change that "
                             f"file's glass. Save the lens into another folder")
    keep = [ln for name, rec in before.items() if name not in new for ln in rec]
    return lines[:1] + keep + lines[1:]


def surface_lines(s: AbstractSurface, *, image: bool = False) -> list[str]:
    out = zmx_surfaces.surface_lines(s, _z)
    if out is not None:
        if image:
            raise ValueError(f"save_zmx: the image surface must be standard, an even or an "
                             f"odd asphere or a tilted plane, not {type(s).__name__}")
        return out
    out = []
    if isinstance(s, Hybrid):
        a = [float(v) for v in np.asarray(s.coeffs)]
        bx = [float(v) for v in np.asarray(s.odd_x)]
        by = [float(v) for v in np.asarray(s.odd_y)]
        deg = max(2 * len(a), 2 * len(bx) + 1 if bx else 0)
        if deg > MAX_XPOLY_DEGREE:
            raise ValueError(
                f"save_zmx: hybrid surface of degree {deg} exceeds Zemax's "
                f"extended polynomial (degree {MAX_XPOLY_DEGREE})"
            )
        n = (deg + 1) * (deg + 2) // 2 - 1 if deg else 0
        terms = xpoly_terms(a, bx, by)
        out += ["TYPE XPOLYNOM", f"COMM jaxlens hybrid even={len(a)} odd={len(bx)}"]
        out += [
            f'CURV {_z(s.c)} 0 0 0 0 ""',
            f"CONI {_z(s.k)}",
            f'XDAT 1 {n} 0 0 1 0 0 ""',
            'XDAT 2 1.0 0 0 1 0 0 ""',
        ]
        for j in range(1, n + 1):
            v = terms.get(term_powers(j), 0.0)
            out.append(f'XDAT {j + 2} {_z(v)} 0 0 1 0 0 ""')
    elif isinstance(s, EvenAsphere):
        a = [float(v) for v in np.asarray(s.coeffs)]
        if len(a) <= 8:
            out += ["TYPE EVENASPH", f'CURV {_z(s.c)} 0 0 0 0 ""', f"CONI {_z(s.k)}"]
            out += [f"PARM {i} {_z(v)}" for i, v in enumerate(a, start=1)]
        else:
            out += [
                "TYPE XASPHERE",
                f'CURV {_z(s.c)} 0 0 0 0 ""',
                f"CONI {_z(s.k)}",
                f'XDAT 1 {len(a)} 0 0 1 0 0 ""',
                'XDAT 2 1.0 0 0 1 0 0 ""',
            ]
            out += [f'XDAT {i + 2} {_z(v)} 0 0 1 0 0 ""' for i, v in enumerate(a, start=1)]
    elif isinstance(s, OddAsphere):
        b = [float(v) for v in np.asarray(s.coeffs)]
        if len(b) <= 8:
            out += ["TYPE ODDASPHE", f'CURV {_z(s.c)} 0 0 0 0 ""', f"CONI {_z(s.k)}"]
            out += [f"PARM {i} {_z(v)}" for i, v in enumerate(b, start=1)]
        else:  # the extended odd asphere, normalisation radius 1 mm: A_i = β_i
            if len(b) > zmx_surfaces.MAX_XOSPHERE_TERMS:
                raise ValueError(f"save_zmx: an OddAsphere has {len(b)} coefficients; Zemax's "
                                 f"XOSPHERE holds {zmx_surfaces.MAX_XOSPHERE_TERMS}")
            out += ["TYPE XOSPHERE", f'CURV {_z(s.c)} 0 0 0 0 ""', f"CONI {_z(s.k)}",
                    f'XDAT 1 {len(b)} 0 0 1 0 0 ""', 'XDAT 2 1.0 0 0 1 0 0 ""']
            out += [f'XDAT {i + 2} {_z(v)} 0 0 1 0 0 ""' for i, v in enumerate(b, start=1)]
    elif isinstance(s, TiltedPlane):  # PARM 1, 2: the slopes, no unit
        out += ["TYPE TILTSURF", 'CURV 0 0 0 0 0 ""', f"PARM 1 {_z(s.tan_x)}",
                f"PARM 2 {_z(s.tan_y)}"]
    elif isinstance(s, Standard):
        out += ["TYPE STANDARD", f'CURV {_z(s.c)} 0 0 0 0 ""', f"CONI {_z(s.k)}"]
    elif isinstance(s, CoordinateBreak) and not image:
        parms = (s.decenter_x, s.decenter_y, s.tilt_x, s.tilt_y, s.tilt_z)
        out += ["TYPE COORDBRK", 'CURV 0 0 0 0 0 ""']
        out += [f"PARM {i} {_z(v)}" for i, v in enumerate(parms, start=1)]
        out.append(f"PARM 6 {s.order}")
    else:
        raise ValueError(f"save_zmx: surface type {type(s).__name__} has no .zmx form")
    if image and isinstance(s, Hybrid):
        raise ValueError("save_zmx: the image surface must be standard, an even or an odd "
                         "asphere or a tilted plane")
    return out


_APERTURE_KEYS = {("rect", False): "SQAP", ("ellipse", False): "ELAP", ("rect", True): "SQOB",
                  ("ellipse", True): "ELOB"}


def aperture_lines(i: int, aps: list, obscured: bool) -> list[str]:
    """The lines of surface i's apertures (``Lens.apertures``): SQAP/ELAP/SQOB/ELOB, CLAP for
    a clipping circle, OBSC for a blocking one, and their common decenter as ``OBDC``
    (Zemax has one decenter per surface). A centred circle reads back as the semi-diameter
    (or ``Lens.obscurations``): the same clipping."""
    if not aps:
        return []
    dec = {(a.decenter_x, a.decenter_y) for a in aps}
    if len(dec) > 1:
        raise ValueError(f"save_zmx: the apertures of surface {i} have different decenters "
                         f"{sorted(dec)} (mm); a .zmx surface has one aperture decenter (OBDC)")
    (dx, dy), = dec
    if obscured and (dx, dy) != (0.0, 0.0):
        raise ValueError(f"save_zmx: surface {i} has an obscuration (Lens.obscurations) and "
                         f"decentered apertures; the file's decenter (OBDC) would move both")
    circles = [a.blocks for a in aps if a.shape == "circle"] + [True] * obscured
    if len(circles) != len(set(circles)):
        raise ValueError(f"save_zmx: surface {i} has more than one clipping or more than one "
                         f"blocking circle (apertures and obscurations); a .zmx surface has "
                         f"one CLAP and one OBSC")
    out = []
    for a in aps:
        if a.shape == "circle":
            out.append(f"  OBSC 0 {_z(a.half_x)}" if a.blocks else f"  CLAP 0 {_z(a.half_x)} 0")
        else:
            out.append(f"  {_APERTURE_KEYS[a.shape, a.blocks]} {_z(a.half_x)} {_z(a.half_y)} 0")
    if (dx, dy) != (0.0, 0.0):
        out.append(f"  OBDC {_z(dx)} {_z(dy)}")
    return out


def notes(lens: Lens, wl: np.ndarray) -> list[str]:
    """``NOTE 0`` lines (file notes, which Zemax, optiland and jaxlens's reader do not
    interpret) that make the file say what it describes to a reader that resolves names its
    own way: the units and conventions, the stop, and each medium's refractive index at the
    file's wavelengths (WAVM 1, 2, …) as jaxlens computes it, so a glass that another tool's
    catalog holds with other data (optiland's E48R: nd 1.53055; jaxlens's, from Zemax's ZEON
    catalog: 1.53117) shows up. The lens's description follows, one note per line."""
    out = [f"NOTE 0 jaxlens: lengths mm, wavelengths um, fields are angles in degrees in object "
           f"space (XFLN, YFLN), the stop is SURF {lens.stop + 1}, ENPD is the entrance pupil "
           f"diameter"]
    if lens.telecentric_object:
        out = [f"NOTE 0 jaxlens: lengths mm, wavelengths um, object-space telecentric (FTYP's "
               f"second value 1), fields are object heights in mm (XFLN, YFLN), the stop is "
               f"SURF {lens.stop + 1}, OBNA is the object-space NA"]
    media = [lens.object_material, *lens.materials]
    for k, m in enumerate(media):
        n = lensfile.index_record(m, wl)  # the JSON file's record of the same medium
        if n is None:  # air
            continue
        name = getattr(m, "name", "") or type(m).__name__
        out.append(f"NOTE 0 jaxlens: the medium after SURF {k} ({name}) has n = "
                   f"{' '.join(repr(v) for v in n)} at WAVM 1..{len(wl)}")
    out += [f"NOTE 0 {ln}".rstrip() for ln in lens.description.splitlines()]
    return out


def dumps(lens: Lens, path: str = "lens.zmx", *, model_glass: str = "blank"):
    """Text of a ``.zmx`` file and the glass writer holding its side AGF catalogs.

    ``Lens.negative_propagation`` is not written: Zemax always lets a ray go back along its
    line to a surface (a negative distance), and the reader sets the flag on every lens it
    reads. A lens traced by the default rule (the flag off) whose surfaces cross within the
    beam is therefore read back with rays passing there that it lost."""
    if model_glass not in ("blank", "agf"):
        raise ValueError(f"save_zmx: model_glass must be 'blank' or 'agf', got {model_glass!r}")
    loadable(lens, "dumps")
    stem = os.path.splitext(os.path.basename(os.fspath(path)))[0]
    gw = _GlassWriter(stem, model_glass, np.atleast_1d(np.asarray(lens.wavelengths, np.float64)))
    gw.reserve((lens.object_material,) + tuple(lens.materials))
    fields = np.asarray(lens.fields, np.float64)
    fields = fields.reshape(-1, 2) if fields.ndim == 2 else fields.reshape(-1)
    xs = fields[:, 0] if fields.ndim == 2 else np.zeros_like(fields)
    ys = fields[:, 1] if fields.ndim == 2 else fields
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    surf_lines = []

    obscured = {i: (a, b) for i, a, b in lens.obscurations}
    apertures = {}
    for i, a in lens.apertures:
        apertures.setdefault(i, []).append(a)

    def block(number, lines, t, glas, sd, stop=False):
        surf_lines.append(f"SURF {number}")
        if stop:
            surf_lines.append("  STOP")
        surf_lines.extend("  " + x for x in lines)
        surf_lines.append(f"  DISZ {'INFINITY' if math.isinf(t) else _z(t)}")
        if glas:
            surf_lines.append("  " + glas)
        sd = float(sd)
        aps = apertures.get(number - 1, [])
        if aps and math.isfinite(sd):
            raise ValueError(f"save_zmx: surface {number - 1} has apertures (Lens.apertures) and "
                             f"a finite semi-diameter ({sd} mm); a .zmx surface clips at its "
                             f"apertures only: set its semi_diameter to inf (add a circle "
                             f"Aperture for it)")
        if math.isfinite(sd):
            # DIAM is only the drawn size; Zemax and optiland clip rays at an aperture, so a
            # clipping semi-diameter is also written as a circular aperture (CLAP min max 0).
            surf_lines.append(f'  DIAM {_z(sd)} 1 0 0 1 ""')
            surf_lines.append(f"  CLAP 0 {_z(sd)} 0")
        else:
            surf_lines.append('  DIAM 0 0 0 0 1 ""')
        if number - 1 in obscured:  # rays meeting r_min ≤ r ≤ r_max are blocked
            surf_lines.append(f"  OBSC {_z(obscured[number - 1][0])} {_z(obscured[number - 1][1])}")
        surf_lines.extend(aperture_lines(number - 1, aps, number - 1 in obscured))

    dist = math.inf if lens.object_distance is None else float(lens.object_distance)
    block(0, ["TYPE STANDARD", 'CURV 0 0 0 0 0 ""'], dist, gw.glas(lens.object_material), np.inf)
    for i, s in enumerate(lens.surfaces):
        # A mirror and a coordinate break keep the medium before them (Lens checks it).
        glas = gw.glas(lens.materials[i])
        if i in lens.mirrors:
            glas = "GLAS MIRROR 0 0 1.5 4.0E+1 0 0 0 0 0 0"
        elif isinstance(s, CoordinateBreak):
            glas = None
        block(
            i + 1,
            surface_lines(s),
            float(lens.thickness[i]),
            glas,
            s.semi_diameter,
            stop=i == lens.stop,
        )
    img = surface_lines(lens.image, image=True)
    if lens.sensor is not None:
        rows, cols = lens.sensor.resolution
        img.append(
            f"COMM jaxlens sensor rows={rows} cols={cols} pixel={float(lens.sensor.pixel_size)!r}"
        )
    # Image space is the last surface's medium. The image surface names it too: optiland
    # gives every surface the medium after it and takes image space from the image surface.
    block(lens.num_surfaces + 1, img, 0.0, gw.glas(lens.materials[-1]), lens.image.semi_diameter)
    head = [
        "VERS 190513 80 123457 L123457",
        "MODE SEQ",
        # One line; the reader strips the ends but keeps inner spacing (a round trip is exact).
        f"NAME {' '.join(lens.name.splitlines()).strip()}".rstrip(),
        *notes(lens, wl),
        "UNIT MM X W X CM MR CPMM",
        # An object-space telecentric lens: its aperture is the object-space NA (OBNA x 0).
        f"OBNA {_z(lens.object_na)} 0" if lens.telecentric_object else f"ENPD {_z(lens.epd)}",
        "ENVD 2.0E+1 1 0",
        "GFAC 0 0",
        "GCAT " + " ".join(gw.gcat() or ["SCHOTT"]),
        # Field type 1 (object heights) and the telecentric flag, or angles (0 0).
        f"FTYP {int(lens.telecentric_object)} {int(lens.telecentric_object)} {len(ys)} "
        f"{len(wl)} 0 0 {int(lens.afocal_image)}",
        "XFLN " + " ".join(_z(v) for v in xs),
        "YFLN " + " ".join(_z(v) for v in ys),
        "FWGN " + " ".join("1" for _ in ys),
    ]
    if lens.aim != "paraxial":  # RAIM type 1 (Zemax's "Paraxial" ray aiming) or 2 ("Real");
        raim = {v: k for k, v in zmx_system.RAIM_AIM.items()}[lens.aim]  # no line: aiming off
        head.append(f"RAIM 0 {raim} 1 1 0 0 0 0 0")
    if lens.vignetting is not None:  # one line per factor, one value per field
        v = np.asarray(lens.vignetting, np.float64).reshape(len(ys), 5)
        head += [f"{key} " + " ".join(_z(x) for x in v[:, j])
                 for j, key in enumerate(zmx_system.VIGNETTING_KEYS)]
    head += [f"WAVM {i} {_z(w)} 1" for i, w in enumerate(wl, start=1)]
    head.append(f"PWAV {lens.primary + 1}")
    return "\n".join(head + surf_lines) + "\n", gw


def save_zmx(lens: Lens, path: str | os.PathLike, *, model_glass: str = "blank") -> list[str]:
    """Write a Zemax ``.zmx`` file (UTF-8, CRLF line ends) and its side ``.AGF`` catalogs.

    Args:
        lens: the lens.
        path: the ``.zmx`` file; its folder must exist (else ``MissingFolderError``, a
            ``ValueError`` and a ``FileNotFoundError``, as every writer raises).
        model_glass: ``"blank"`` writes a ``ModelGlass`` as Zemax's own model glass
            (``GLAS ___BLANK 1 0 nd Vd …``, exact nd and Vd; Zemax's model dispersion away
            from the d line differs slightly from jaxlens's); ``"agf"`` writes it into the
            side AGF catalog with the Schott formula that reproduces jaxlens's dispersion
            exactly.

    Returns:
        The paths of the AGF catalogs written beside the file (possibly none).
    """
    # Before any work, and before the side catalogs are written beside it.
    loadable(lens, "save_zmx")
    path = output_file(path, "save_zmx", ".zmx")
    text, gw = dumps(lens, path, model_glass=model_glass)
    folder = os.path.dirname(os.path.abspath(path))
    agfs = gw.write_agf(folder)
    write_whole(path, text, newline="\r\n", where="save_zmx")
    return agfs
