"""Zemax OpticStudio sequential lens files (``.zmx``), read and write.

Conventions:
    Zemax numbers surfaces from 0 (the object) to N (the image); ``Lens.surfaces[i]`` is
    Zemax surface i + 1. Lengths are converted to mm from the file's ``UNIT`` (MM, CM, IN
    or METER), wavelengths are in µm as in Zemax, field angles in degrees.

What is read and written:
    * ``TYPE STANDARD`` (CURV, CONI), ``TYPE EVENASPH`` (PARM 1..8 = A2, A4, …, A16, so
      PARM 1 multiplies r²) and ``TYPE XASPHERE`` (extended asphere: XDAT 1 = number of
      terms, XDAT 2 = normalisation radius, XDAT 3… = the r², r⁴, … coefficients; used
      for even aspheres with more than 8 terms).
    * The hybrid surface (even asphere plus odd terms Σ b_j x^{2j+1} + d_j y^{2j+1}) is
      written as Zemax's extended polynomial, ``TYPE XPOLYNOM``: a conic plus Σ A_i E_i
      with E_i the monomials x^m y^n ordered by degree and, within a degree, by falling
      power of x (x, y, x², xy, y², x³, …); XDAT 1 = the number of terms, XDAT 2 = the
      normalisation radius (written as 1, so the coefficients are the sag coefficients
      in mm). The r^{2i} terms are expanded binomially, (x² + y²)^i. This is exact: Zemax
      computes the same sag. Reading checks that the polynomial has that structure and
      raises otherwise. A surface comment ``jaxlens hybrid even=M odd=P`` keeps the
      number of even and odd coefficients so the round trip restores the same shapes.
    * ``DISZ`` (INFINITY for the object), ``STOP``, ``DIAM`` (the semi-diameter; a value
      with solve flag 0 is Zemax's automatic semi-diameter and is read as no clipping,
      a fixed value clips rays), ``CLAP`` (circular aperture, read as the semi-diameter).
    * ``GLAS``: catalog glasses by name (``GLAS N-BK7 0 0 1.5168 6.417E+001 0 0 0 0 0 0``,
      with the catalog's nd and Vd), model glasses as Zemax writes them
      (``GLAS ___BLANK 1 0 nd Vd 0 0 0 0 0 0``), ``GCAT`` (the catalogs searched, in
      order).
    * Glasses not in Zemax's own catalogs (user AGF glasses, index tables, the model
      dispersion of OKP4, materials of any other class) go into ``.AGF`` catalogs written
      beside the ``.zmx`` and listed first in ``GCAT``. Zemax reads them once copied into
      its ``glasscat`` folder; jaxlens reads them from beside the file. A glass whose
      dispersion no AGF formula holds exactly (an index table, most notably) gets the
      Schott formula through its data points (exact for up to 6 points, least squares
      beyond), and its exact definition in a ``GC jaxlens {...}`` comment record, which
      Zemax ignores and jaxlens reads back, so the round trip loses nothing.
    * ``ENPD`` (entrance pupil diameter), ``FNUM x 0`` (image-space F/# = EFL/EPD), ``FLOA``
      (float by stop size: the stop's DIAM), ``FTYP`` with ``XFLN``/``YFLN`` angle fields,
      ``WAVM`` (or the older ``WAVL``) and ``PWAV``, ``UNIT``, ``NAME``.
    * The sensor (``Lens.sensor``) is kept in the image surface's comment,
      ``COMM jaxlens sensor rows=480 cols=640 pixel=0.005``, which Zemax ignores.
    * Files are read as UTF-16 (with BOM, Zemax's default), UTF-8 (with or without BOM)
      or latin-1, and written as UTF-8.

Malformed files raise ``ValueError`` naming the file, the line number and the line.
Everything else in a file (solves, pickups, tolerances, multi-configuration data,
coatings, drawing settings) is ignored on reading and not written.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

from ..optics import materials as _materials
from ..optics.lens import Lens, Sensor
from ..optics.materials import AbstractMaterial, Air, ModelGlass, Tabulated
from ..optics.surfaces import AbstractSurface, EvenAsphere, Hybrid, Standard
from . import lensfile
from .lensfile import _arr, apply_aperture, catalog_material, material_from_spec

ZEMAX_CATALOGS = frozenset(
    "SCHOTT CDGM OHARA HOYA SUMITA HIKARI HIKARI_CHINA MISC ZEON INFRARED BIREFRINGENT "
    "ARCHER ARTON CORNING HERAEUS ISUZU LIGHTPATH LZOS NHG NIKON OSAKAGASCHEMICAL RPO "
    "SCHOTT_IRG SCHOTT_HT UMICORE MITSUI OPTIMAX KOREA_OGC LIGHTPATH_BD2 SCHOTT_2000 "
    "NSG QIOPTIQ".split()
)
"""Catalog names shipped with Zemax OpticStudio; glasses from them are written by name."""

_UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}
_PLASTIC_CATALOG = {
    "PMMA": "MISC",
    "ACRYLIC": "MISC",
    "POLYCARB": "MISC",
    "POLYSTYR": "MISC",
    "SAN": "MISC",
    "COC": "MISC",
    "330R": "ZEON",
    "480R": "ZEON",
    "E48R": "ZEON",
}
_SHIPPED_FOR_ZEMAX = {
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
}
_SURFACE_KEYS = {
    "TYPE",
    "CURV",
    "DISZ",
    "CONI",
    "PARM",
    "XDAT",
    "GLAS",
    "STOP",
    "DIAM",
    "COMM",
    "CLAP",
}
_HYBRID_COMMENT = re.compile(r"jaxlens hybrid even=(\d+) odd=(\d+)")
_SENSOR_COMMENT = re.compile(r"jaxlens sensor rows=(\d+) cols=(\d+) pixel=(\S+)")
_MARKER = "jaxlens "
_KEYWORD = re.compile(r"^[A-Z][A-Z0-9_]{1,9}$")
_MAX_XPOLY_DEGREE = 20
_MAX_XDAT_TERMS = 230  # Zemax's extended polynomial: all terms up to degree 20


# ---------------------------------------------------------------------------- numbers


def _z(x: float) -> str:
    """Zemax-style number, exact (shortest round trip), e.g. ``6.41655E+001``."""
    x = float(x)
    if x == 0.0:
        return "0"
    if not math.isfinite(x):
        raise ValueError(f"save_zmx: cannot write the non-finite number {x}")
    return np.format_float_scientific(x, unique=True, exp_digits=3, trim="0").upper()


class _Line:
    """One line of a file, for error messages."""

    def __init__(self, path: str, number: int, text: str):
        self.path, self.number, self.text = path, number, text
        self.tokens = text.split()

    def error(self, msg: str) -> ValueError:
        return ValueError(f"{self.path}:{self.number}: {msg}: {self.text.strip()!r}")

    def float(self, i: int, what: str, *, allow_inf: bool = False) -> float:
        try:
            tok = self.tokens[i]
        except IndexError:
            raise self.error(f"missing {what}") from None
        if allow_inf and tok.upper() in ("INFINITY", "INF"):
            return math.inf
        try:
            v = float(tok.replace("D", "E").replace("d", "e"))
        except ValueError:
            raise self.error(f"{what} is not a number ({tok!r})") from None
        if not math.isfinite(v):
            raise self.error(f"{what} must be finite")
        return v

    def int(self, i: int, what: str) -> int:
        v = self.float(i, what)
        if v != int(v):
            raise self.error(f"{what} must be an integer")
        return int(v)


# ---------------------------------------------------------------------------- reading


def decode(raw: bytes, path: str = "<zmx>") -> str:
    """Text of a Zemax file: UTF-16 (BOM or NUL-interleaved), UTF-8 (BOM or not), latin-1."""
    try:
        if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
            return raw.decode("utf-16")
        if raw.startswith(b"\xef\xbb\xbf"):
            return raw[3:].decode("utf-8")
        head = raw[:400]
        if head and head.count(b"\x00") > len(head) // 4:
            return raw.decode("utf-16-le" if head[1:2] == b"\x00" else "utf-16-be")
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a readable UTF-16 text file ({e.reason})") from None
    if b"\x00" in raw:
        raise ValueError(f"{path}: binary data, not a Zemax text file")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


@dataclass
class _Surf:
    number: int
    line: _Line
    type: str = "STANDARD"
    type_line: _Line | None = None
    curv: float = 0.0
    disz: float = 0.0
    disz_line: _Line | None = None
    coni: float = 0.0
    parm: dict = field(default_factory=dict)  # index -> (value, line)
    xdat: dict = field(default_factory=dict)
    glas: _Line | None = None
    stop: bool = False
    diam: tuple[float, int | None] | None = None
    clap: float | None = None
    comment: str = ""


@dataclass
class _File:
    path: str
    name: str = ""
    unit: float = 1.0
    aperture: tuple[str, float, _Line] | None = None
    gcat: list = field(default_factory=list)
    ftyp: _Line | None = None
    xfln: _Line | None = None
    yfln: _Line | None = None
    wavm: dict = field(default_factory=dict)
    wavl: _Line | None = None
    pwav: _Line | None = None
    surfs: list = field(default_factory=list)


def _parse(text: str, path: str) -> _File:
    f = _File(path)
    cur: _Surf | None = None
    for number, raw in enumerate(text.splitlines(), start=1):
        ln = _Line(path, number, raw)
        if not ln.tokens:
            continue
        key = ln.tokens[0]
        if not _KEYWORD.match(key):
            raise ln.error("not a Zemax keyword line")
        if key == "SURF":
            n = ln.int(1, "surface number")
            if n != len(f.surfs):
                raise ln.error(f"surfaces must be numbered 0, 1, 2, …; expected {len(f.surfs)}")
            cur = _Surf(n, ln)
            f.surfs.append(cur)
        elif key in _SURFACE_KEYS:
            if cur is None:
                raise ln.error(f"{key} before the first SURF")
            _surface_line(cur, key, ln)
        else:
            _top_line(f, key, ln, raw)
    if not f.surfs:
        raise ValueError(f"{path}: no SURF lines; not a sequential Zemax lens file")
    return f


def _surface_line(s: _Surf, key: str, ln: _Line) -> None:
    if key == "TYPE":
        if len(ln.tokens) < 2:
            raise ln.error("TYPE needs a surface type")
        s.type, s.type_line = ln.tokens[1].upper(), ln
    elif key == "CURV":
        s.curv = ln.float(1, "curvature")
    elif key == "DISZ":
        s.disz, s.disz_line = ln.float(1, "thickness", allow_inf=True), ln
    elif key == "CONI":
        s.coni = ln.float(1, "conic constant")
    elif key in ("PARM", "XDAT"):
        i = ln.int(1, f"{key} index")
        (s.parm if key == "PARM" else s.xdat)[i] = (ln.float(2, f"{key} {i} value"), ln)
    elif key == "GLAS":
        if len(ln.tokens) < 2:
            raise ln.error("GLAS needs a glass name")
        s.glas = ln
    elif key == "STOP":
        s.stop = True
    elif key == "DIAM":
        v = ln.float(1, "semi-diameter")
        flag = ln.int(2, "semi-diameter solve flag") if len(ln.tokens) > 2 else None
        if v < 0:
            raise ln.error("semi-diameter must be >= 0")
        s.diam = (v, flag)
    elif key == "CLAP":
        s.clap = ln.float(2, "circular aperture maximum radius")
    elif key == "COMM":
        s.comment = ln.text.strip()[4:].strip()


def _top_line(f: _File, key: str, ln: _Line, raw: str) -> None:
    if key == "MODE" and len(ln.tokens) > 1 and ln.tokens[1].upper() != "SEQ":
        raise ln.error("only sequential (MODE SEQ) files are supported")
    if key == "NAME":
        f.name = raw.strip()[4:].strip()
    elif key == "UNIT":
        u = ln.tokens[1].upper() if len(ln.tokens) > 1 else ""
        if u not in _UNITS:
            raise ln.error(f"unknown lens unit {u!r}; use MM, CM, IN or METER")
        f.unit = _UNITS[u]
    elif key == "ENPD":
        f.aperture = ("epd", ln.float(1, "entrance pupil diameter"), ln)
    elif key == "FNUM":
        if len(ln.tokens) > 2 and ln.int(2, "F/# type") != 0:
            raise ln.error("only the image-space F/# (FNUM x 0) is supported")
        f.aperture = ("fnum", ln.float(1, "F/#"), ln)
    elif key == "FLOA":
        f.aperture = ("float", 0.0, ln)
    elif key in ("OBNA", "OBSC", "PUPD"):
        raise ln.error("this aperture type is not supported; use ENPD, FNUM or FLOA")
    elif key == "GCAT":
        f.gcat = [t.upper() for t in ln.tokens[1:]]
    elif key == "FTYP":
        f.ftyp = ln
    elif key == "XFLN":
        f.xfln = ln
    elif key == "YFLN":
        f.yfln = ln
    elif key == "WAVM":
        i = ln.int(1, "wavelength number")
        f.wavm[i] = (ln.float(2, "wavelength"), ln)
    elif key == "WAVL":
        f.wavl = ln
    elif key == "PWAV":
        f.pwav = ln


def _sd(s: _Surf, unit: float) -> float:
    if s.clap is not None:
        return s.clap * unit if s.clap > 0 else math.inf
    if s.diam is None:
        return math.inf
    v, flag = s.diam
    if v == 0 or flag == 0:  # automatic semi-diameter: informational
        return math.inf
    return v * unit


def _term_powers(j: int) -> tuple[int, int]:
    """(power of x, power of y) of Zemax extended-polynomial term j (1-based)."""
    d = int((math.isqrt(8 * j + 1) - 1) // 2)
    while d * (d + 1) // 2 > j:
        d -= 1
    while (d + 1) * (d + 2) // 2 <= j:
        d += 1
    return d - (j - d * (d + 1) // 2), j - d * (d + 1) // 2


def _term_index(mx: int, ny: int) -> int:
    d = mx + ny
    return d * (d + 1) // 2 + ny


def _xdat_terms(s: _Surf, unit: float, what: str):
    where = s.type_line or s.line
    if 1 not in s.xdat or 2 not in s.xdat:
        raise where.error(f"{what} needs XDAT 1 (number of terms) and XDAT 2 (norm radius)")
    n_val, n_line = s.xdat[1]
    if n_val != int(n_val) or not 0 <= n_val <= _MAX_XDAT_TERMS:
        raise n_line.error(f"XDAT 1 must be a whole number of terms, 0..{_MAX_XDAT_TERMS}")
    norm, norm_line = s.xdat[2]
    if not norm > 0:
        raise norm_line.error("the normalisation radius (XDAT 2) must be > 0")
    for i, (v, ln) in s.xdat.items():
        if i > int(n_val) + 2 and v != 0:
            raise ln.error(f"coefficient beyond the {int(n_val)} terms of XDAT 1")
    vals = [s.xdat.get(j + 2, (0.0, None))[0] for j in range(1, int(n_val) + 1)]
    return int(n_val), norm, vals


def _surface(s: _Surf, unit: float) -> AbstractSurface:
    c = s.curv / unit
    sd = _sd(s, unit)
    where = s.type_line or s.line
    if s.type == "STANDARD":
        return Standard(c=_arr(c), k=_arr(s.coni), semi_diameter=_arr(sd))
    if s.type == "EVENASPH":
        for i, (v, ln) in s.parm.items():
            if (i < 1 or i > 8) and v != 0:
                raise ln.error("EVENASPH uses PARM 1..8 (A2..A16) only")
        m = max([i for i in s.parm if 1 <= i <= 8], default=0)
        a = [s.parm.get(i, (0.0, None))[0] * unit ** (1 - 2 * i) for i in range(1, m + 1)]
        return EvenAsphere(
            c=_arr(c), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)), semi_diameter=_arr(sd)
        )
    if s.type == "XASPHERE":
        n, norm, vals = _xdat_terms(s, unit, "XASPHERE")
        a = [v / norm ** (2 * i) * unit ** (1 - 2 * i) for i, v in enumerate(vals, start=1)]
        return EvenAsphere(
            c=_arr(c), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)), semi_diameter=_arr(sd)
        )
    if s.type == "XPOLYNOM":
        return _hybrid_from_xpoly(s, unit, c, sd)
    raise where.error(
        f"surface type {s.type} is not supported (STANDARD, EVENASPH, XASPHERE, XPOLYNOM)"
    )


def _hybrid_from_xpoly(s: _Surf, unit: float, c: float, sd: float) -> Hybrid:
    n, norm, vals = _xdat_terms(s, unit, "XPOLYNOM")
    terms = {}
    for j, v in enumerate(vals, start=1):
        mx, ny = _term_powers(j)
        d = mx + ny
        terms[(mx, ny)] = v / norm**d * unit ** (1 - d)
    top = sum(_term_powers(n)) if n else 0
    m, p = top // 2, max(top - 1, 0) // 2
    hit = _HYBRID_COMMENT.search(s.comment)
    if hit:
        m, p = int(hit.group(1)), int(hit.group(2))
    a = [terms.get((2 * i, 0), 0.0) for i in range(1, m + 1)]
    bx = [terms.get((2 * j + 1, 0), 0.0) for j in range(1, p + 1)]
    by = [terms.get((0, 2 * j + 1), 0.0) for j in range(1, p + 1)]
    expected = _xpoly_terms(a, bx, by)
    for key, v in terms.items():
        e = expected.get(key, 0.0)
        d = sum(key)
        scale = max(abs(a[d // 2 - 1]) if d % 2 == 0 and 0 < d // 2 <= m else 0.0, abs(e))
        if abs(v - e) > 1e-9 * scale:
            where = s.xdat.get(_term_index(*key) + 2, (0, s.type_line or s.line))[1]
            raise where.error(
                f"XPOLYNOM term x^{key[0]} y^{key[1]} = {v!r} does not fit the hybrid surface "
                f"(even asphere in r² plus odd terms in x and y; expected {e!r})"
            )
    return Hybrid(
        c=_arr(c),
        k=_arr(s.coni),
        coeffs=_arr(np.array(a, np.float64)),
        odd_x=_arr(np.array(bx, np.float64)),
        odd_y=_arr(np.array(by, np.float64)),
        semi_diameter=_arr(sd),
    )


def _xpoly_terms(a, bx, by) -> dict:
    """Extended-polynomial coefficients {(px, py): value} of a hybrid surface's polynomial."""
    out = {}
    for i, ai in enumerate(a, start=1):
        for j in range(i + 1):
            out[(2 * i - 2 * j, 2 * j)] = math.comb(i, j) * float(ai)
    for j, (b, d) in enumerate(zip(bx, by, strict=True), start=1):
        out[(2 * j + 1, 0)] = float(b)
        out[(0, 2 * j + 1)] = float(d)
    return out


def _read_agf_markers(path: str) -> dict[str, str]:
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
        elif t[0] == "GC" and name and len(t) > 1 and t[1].startswith(_MARKER):
            out[name] = t[1][len(_MARKER) :]
    return out


class _Glasses:
    """Resolves GLAS names: side AGF catalogs, then the shipped catalogs."""

    def __init__(self, path: str, gcat: list[str]):
        self.dir = os.path.dirname(os.path.abspath(path))
        self.gcat = gcat
        self.side: dict[str, tuple[dict, dict, str]] = {}
        try:
            listing = {n.upper(): n for n in os.listdir(self.dir)}
        except OSError:
            listing = {}
        for cat in gcat:
            fname = listing.get(f"{cat}.AGF")
            if fname is not None:
                p = os.path.join(self.dir, fname)
                from ..optics import catalog

                mats = {k.upper(): v for k, v in catalog.load_agf(p).items()}
                self.side[cat] = (mats, _read_agf_markers(p), p)

    def get(self, ln: _Line) -> AbstractMaterial:
        name = ln.tokens[1]
        up = name.upper()
        if up == "___BLANK":
            nd = ln.float(4, "model glass nd")
            vd = ln.float(5, "model glass Vd")
            if not nd > 0 or vd < 0:
                raise ln.error("model glass needs nd > 0 and Vd >= 0")
            return ModelGlass(_arr(nd), _arr(math.inf if vd == 0 else vd))
        if up == "MIRROR":
            raise ln.error("mirrors are not supported")
        if up == "AIR":
            return Air()
        for cat in self.gcat:
            if cat in self.side:
                mats, markers, p = self.side[cat]
                if up in markers:
                    try:
                        spec = json.loads(markers[up])
                    except json.JSONDecodeError:
                        raise ValueError(f"{p}: bad jaxlens record for glass {name}") from None
                    return material_from_spec(spec, f"{p}: glass {name}")
                if up in mats:
                    return mats[up]
        cat_mod = lensfile._catalog()
        if cat_mod is not None:
            for cat in self.gcat:
                for shipped in _SHIPPED_FOR_ZEMAX.get(cat, ()):
                    try:
                        return cat_mod.get_material(name, catalogs=[shipped])
                    except ValueError:
                        continue
        nd, vd = _glas_nd_vd(ln)
        try:
            return catalog_material(name, nd=nd, vd=vd)
        except ValueError as e:
            missing = [c for c in self.gcat if c not in self.side and c not in _SHIPPED_FOR_ZEMAX]
            if missing:
                e = (f"{e}. The file's GCAT names {', '.join(missing)}, which jaxlens does not "
                     f"ship (GCAT catalogs it reads: {', '.join(_SHIPPED_FOR_ZEMAX)}); put "
                     f"{missing[0]}.AGF beside the file or use jaxlens.catalog.register_catalog")
            raise ln.error(f"glass {name!r}: {e}") from None


def _glas_nd_vd(ln: _Line) -> tuple[float | None, float | None]:
    """nd and Vd that a GLAS line carries after the name (tokens 4 and 5), if valid."""
    try:
        nd, vd = float(ln.tokens[4]), float(ln.tokens[5])
    except (IndexError, ValueError):
        return None, None
    if not (math.isfinite(nd) and nd > 1.0 and math.isfinite(vd) and vd > 0.0):
        return None, None
    return nd, vd


def _fields(f: _File) -> np.ndarray:
    count = None
    if f.ftyp is not None:
        if f.ftyp.int(1, "field type") != 0:
            raise f.ftyp.error("only angle fields (FTYP 0) are supported")
        if len(f.ftyp.tokens) > 3:
            count = f.ftyp.int(3, "number of fields")
    if f.yfln is None:
        return np.zeros(1)
    ys = [f.yfln.float(i, "y field") for i in range(1, len(f.yfln.tokens))]
    xs = [f.xfln.float(i, "x field") for i in range(1, len(f.xfln.tokens))] if f.xfln else []
    if count is None:
        count = max(1, max((i + 1 for i, v in enumerate(ys) if v != 0), default=1))
    if len(ys) < count:
        raise f.yfln.error(f"FTYP announces {count} fields, YFLN gives {len(ys)}")
    xs = (xs + [0.0] * count)[:count]
    ys = ys[:count]
    if any(x != 0 for x in xs):
        return np.stack([np.array(xs), np.array(ys)], axis=-1)
    return np.array(ys, np.float64)


def _wavelengths(f: _File) -> tuple[np.ndarray, int]:
    count = None
    if f.ftyp is not None and len(f.ftyp.tokens) > 4:
        count = f.ftyp.int(4, "number of wavelengths")
    if f.wavm:
        n = count if count is not None else max(f.wavm)
        missing = [i for i in range(1, n + 1) if i not in f.wavm]
        if missing:
            ln = f.ftyp or next(iter(f.wavm.values()))[1]
            raise ln.error(f"no WAVM line for wavelength {missing[0]}")
        wl = [f.wavm[i][0] for i in range(1, n + 1)]
        lines = [f.wavm[i][1] for i in range(1, n + 1)]
    elif f.wavl is not None:
        wl = [f.wavl.float(i, "wavelength") for i in range(1, len(f.wavl.tokens))]
        wl = wl[:count] if count is not None else [w for w in wl if w != 0]
        lines = [f.wavl] * len(wl)
    else:
        wl, lines = [0.55], [None]  # Zemax's default wavelength
    for w, ln in zip(wl, lines, strict=True):
        if not w > 0:
            raise ln.error("wavelengths must be > 0 (µm)")
    primary = 0
    if f.pwav is not None:
        primary = f.pwav.int(1, "primary wavelength number") - 1
        if not 0 <= primary < len(wl):
            raise f.pwav.error(f"primary wavelength must be 1..{len(wl)}")
    return np.array(wl, np.float64), primary


def _sensor(img: _Surf, unit: float) -> Sensor | None:
    """The sensor recorded in the image surface's comment by ``save_zmx``, if any."""
    hit = _SENSOR_COMMENT.search(img.comment)
    if hit is None:
        return None
    try:
        pixel = float(hit.group(3))
    except ValueError:
        pixel = math.nan
    rows, cols = int(hit.group(1)), int(hit.group(2))
    if not pixel > 0 or not math.isfinite(pixel) or rows <= 0 or cols <= 0:
        raise img.line.error(f"bad sensor in the image surface comment {img.comment!r}")
    return Sensor((rows, cols), _arr(pixel * unit))


def loads(text: str, path: str = "<zmx>") -> Lens:
    """A ``Lens`` from the text of a ``.zmx`` file (``path`` locates side AGF catalogs)."""
    f = _parse(text, path)
    if len(f.surfs) < 3:
        raise ValueError(
            f"{path}: a lens needs an object, at least one surface and an image "
            f"(found {len(f.surfs)} SURF blocks)"
        )
    u = f.unit
    glasses = _Glasses(path, f.gcat)
    obj, body, img = f.surfs[0], f.surfs[1:-1], f.surfs[-1]
    surfaces, thick, mats = [], [], []
    for s in body:
        surfaces.append(_surface(s, u))
        if math.isinf(s.disz):
            raise s.disz_line.error("only the object surface may have an infinite thickness")
        thick.append(s.disz * u)
        mats.append(glasses.get(s.glas) if s.glas is not None else Air())
    stops = [i for i, s in enumerate(body) if s.stop]
    for s in (obj, img):
        if s.stop:
            raise s.line.error("the object or image surface cannot be the stop")
    if len(stops) > 1:
        raise body[stops[1]].line.error("more than one STOP surface")
    stop = stops[0] if stops else 0
    if img.type not in ("STANDARD", "EVENASPH"):
        raise (img.type_line or img.line).error("the image surface must be STANDARD or EVENASPH")
    dist = obj.disz * u if obj.disz_line is not None else math.inf
    if not dist > 0:
        raise (obj.disz_line or obj.line).error("object distance must be > 0 or INFINITY")
    wl, primary = _wavelengths(f)
    lens = Lens(
        surfaces=tuple(surfaces),
        thickness=_arr(np.array(thick, np.float64)),
        materials=tuple(mats),
        stop=stop,
        epd=_arr(1.0),
        fields=_arr(_fields(f)),
        wavelengths=_arr(wl),
        primary=primary,
        object_distance=_arr(dist),
        object_material=glasses.get(obj.glas) if obj.glas is not None else Air(),
        image=_surface(img, u),
        sensor=_sensor(img, u),
        name=f.name,
    )
    if f.aperture is None:
        raise ValueError(f"{path}: no aperture (ENPD, FNUM or FLOA line)")
    kind, value, ln = f.aperture
    try:
        if kind == "epd":
            if not value > 0:
                raise ln.error("entrance pupil diameter must be > 0")
            return apply_aperture(lens, epd=value * u)
        if kind == "fnum":
            if not value > 0:
                raise ln.error("F/# must be > 0")
            return apply_aperture(lens, fnum=value)
        sd = body[stop].diam
        if sd is None or not sd[0] > 0:
            raise ln.error("FLOA needs a DIAM (stop semi-diameter) on the STOP surface")
        return apply_aperture(lens, stop_semi_diameter=sd[0] * u)
    except ValueError as e:
        if str(e).startswith(path):
            raise
        raise ln.error(str(e)) from None


def load_zmx(path: str | os.PathLike) -> Lens:
    """Read a Zemax ``.zmx`` lens file (UTF-16 or UTF-8)."""
    path = os.fspath(path)
    with open(path, "rb") as fh:
        raw = fh.read()
    return loads(decode(raw, path), path)


# ---------------------------------------------------------------------------- writing


def _zemax_catalog(m: AbstractMaterial) -> str | None:
    """The Zemax catalog that holds ``m`` exactly as jaxlens ships it, or None."""
    if not lensfile.is_catalog_glass(m):
        return None
    if m.catalog == "PLASTICS":
        return _PLASTIC_CATALOG.get(m.name.upper())
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


def _schott_fit(wl: np.ndarray, n: np.ndarray) -> list[float]:
    """Schott-formula coefficients through (wl, n): exact for ≤ 6 points, else least squares."""
    k = min(len(wl), 6)
    powers = _SCHOTT_POWERS[:k]
    A = np.stack([wl**p for p in powers], axis=-1)
    sol, *_ = np.linalg.lstsq(A, n**2, rcond=None)
    order = {0: 0, 2: 1, -2: 2, -4: 3, -6: 4, -8: 5}
    out = [0.0] * 6
    for p, v in zip(powers, sol, strict=True):
        out[order[p]] = float(v)
    return out


def _nd_vd(m: AbstractMaterial) -> tuple[float, float]:
    n = np.asarray(
        m.index(np.array([_materials.LAMBDA_D, _materials.LAMBDA_F, _materials.LAMBDA_C])),
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

    def __init__(self, stem: str, model_glass: str):
        base = _sanitize(stem).replace(".", "_").replace("-", "_")
        self.own = base if base not in ZEMAX_CATALOGS else base + "_JL"
        self.model_glass = model_glass
        self.agf: dict[str, list[_AgfGlass]] = {}
        self.catalogs: list[str] = []

    def _use(self, cat: str) -> None:
        if cat not in self.catalogs:
            self.catalogs.append(cat)

    def _add(self, cat: str, name: str, m: AbstractMaterial, marker: bool) -> str:
        entries = self.agf.setdefault(cat, [])
        base, i = name, 1
        while True:
            same = [e for e in entries if e.name.upper() == name.upper()]
            if not same:
                entries.append(_AgfGlass(name, m, marker))
                return name
            if lensfile.same_material(same[0].material, m):
                return name
            i += 1
            name = f"{base}_{i}"

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
            return f"GLAS {m.name} 0 0 {float(m.catalog_nd)!r} {_z(m.catalog_vd)} 0 0 0 0 0 0"
        plain = (
            type(m).__name__ == "CatalogMaterial"
            and m.catalog
            and m.catalog not in ZEMAX_CATALOGS
            and re.fullmatch(r"[\w\-.]+", m.name)
            and re.fullmatch(r"\w+", m.catalog)
            and _formula(m) is not None
            and m.formula == _formula(m)[0]
            and not any(
                e.name.upper() == m.name.upper() and not lensfile.same_material(e.material, m)
                for e in self.agf.get(m.catalog, [])
            )
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

    @staticmethod
    def _nd_vd_of(m):
        if type(m).__name__ == "CatalogMaterial" and math.isfinite(m.catalog_nd):
            return float(m.catalog_nd), float(m.catalog_vd)
        return _nd_vd(m)

    def write_agf(self, folder: str, wavelengths: np.ndarray) -> list[str]:
        written = []
        lo = min(0.3, float(np.min(wavelengths)))
        hi = max(2.5, float(np.max(wavelengths)))
        for cat, entries in self.agf.items():
            lines = [f"CC {cat}: glasses written by jaxlens"]
            for e in entries:
                m = e.material
                nd, vd = self._nd_vd_of(m)
                exact = _formula(m)
                if exact is not None:
                    form, coeffs = exact
                elif isinstance(m, Tabulated):
                    form = 1
                    coeffs = _schott_fit(
                        np.asarray(m.wavelengths, np.float64), np.asarray(m.indices, np.float64)
                    )
                else:
                    w = np.unique(np.concatenate([np.linspace(0.38, 1.0, 32), wavelengths]))
                    form, coeffs = 1, _schott_fit(w, np.asarray(m.index(w), np.float64))
                code = f"{round((nd - 1) * 1000):03d}{round(vd * 10) % 1000:03d}"
                lines.append(f"NM {e.name} {form} {code} {nd!r} {vd!r} 0 0 0")
                if e.marker:
                    spec = lensfile.material_to_spec(m, by_name=False)
                    lines.append("GC " + _MARKER + json.dumps(spec, separators=(",", ":")))
                lines.append("ED 0 0 0 0 0")
                lines.append("CD " + " ".join(_z(c) for c in coeffs))
                lines.append("TD 0 0 0 0 0 0 20")
                rng = (lo, hi) if e.marker else getattr(m, "wavelength_range", None)
                if rng is not None:
                    lines.append(f"LD {float(rng[0])!r} {float(rng[1])!r}")
            path = os.path.join(folder, f"{cat}.AGF")
            with open(path, "w", encoding="utf-8", newline="\r\n") as fh:
                fh.write("\n".join(lines) + "\n")
            written.append(path)
        return written


def _surface_lines(s: AbstractSurface, *, image: bool = False) -> list[str]:
    out = []
    if isinstance(s, Hybrid):
        a = [float(v) for v in np.asarray(s.coeffs)]
        bx = [float(v) for v in np.asarray(s.odd_x)]
        by = [float(v) for v in np.asarray(s.odd_y)]
        deg = max(2 * len(a), 2 * len(bx) + 1 if bx else 0)
        if deg > _MAX_XPOLY_DEGREE:
            raise ValueError(
                f"save_zmx: hybrid surface of degree {deg} exceeds Zemax's "
                f"extended polynomial (degree {_MAX_XPOLY_DEGREE})"
            )
        n = (deg + 1) * (deg + 2) // 2 - 1 if deg else 0
        terms = _xpoly_terms(a, bx, by)
        out += ["TYPE XPOLYNOM", f"COMM jaxlens hybrid even={len(a)} odd={len(bx)}"]
        out += [
            f'CURV {_z(s.c)} 0 0 0 0 ""',
            f"CONI {_z(s.k)}",
            f'XDAT 1 {n} 0 0 1 0 0 ""',
            'XDAT 2 1.0 0 0 1 0 0 ""',
        ]
        for j in range(1, n + 1):
            v = terms.get(_term_powers(j), 0.0)
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
    elif isinstance(s, Standard):
        out += ["TYPE STANDARD", f'CURV {_z(s.c)} 0 0 0 0 ""', f"CONI {_z(s.k)}"]
    else:
        raise ValueError(f"save_zmx: surface type {type(s).__name__} has no .zmx form")
    if image and isinstance(s, Hybrid):
        raise ValueError("save_zmx: the image surface must be standard or an even asphere")
    return out


def dumps(lens: Lens, path: str = "lens.zmx", *, model_glass: str = "blank"):
    """Text of a ``.zmx`` file and the glass writer holding its side AGF catalogs."""
    if model_glass not in ("blank", "agf"):
        raise ValueError(f"save_zmx: model_glass must be 'blank' or 'agf', got {model_glass!r}")
    stem = os.path.splitext(os.path.basename(os.fspath(path)))[0]
    gw = _GlassWriter(stem, model_glass)
    fields = np.asarray(lens.fields, np.float64)
    fields = fields.reshape(-1, 2) if fields.ndim == 2 else fields.reshape(-1)
    xs = fields[:, 0] if fields.ndim == 2 else np.zeros_like(fields)
    ys = fields[:, 1] if fields.ndim == 2 else fields
    wl = np.atleast_1d(np.asarray(lens.wavelengths, np.float64))
    surf_lines = []

    def block(number, lines, t, glas, sd, stop=False):
        surf_lines.append(f"SURF {number}")
        if stop:
            surf_lines.append("  STOP")
        surf_lines.extend("  " + x for x in lines)
        surf_lines.append(f"  DISZ {'INFINITY' if math.isinf(t) else _z(t)}")
        if glas:
            surf_lines.append("  " + glas)
        sd = float(sd)
        surf_lines.append(
            f'  DIAM {_z(sd)} 1 0 0 1 ""' if math.isfinite(sd) else '  DIAM 0 0 0 0 1 ""'
        )

    dist = math.inf if lens.object_distance is None else float(lens.object_distance)
    block(0, ["TYPE STANDARD", 'CURV 0 0 0 0 0 ""'], dist, gw.glas(lens.object_material), np.inf)
    for i, s in enumerate(lens.surfaces):
        block(
            i + 1,
            _surface_lines(s),
            float(lens.thickness[i]),
            gw.glas(lens.materials[i]),
            s.semi_diameter,
            stop=i == lens.stop,
        )
    img = _surface_lines(lens.image, image=True)
    if lens.sensor is not None:
        rows, cols = lens.sensor.resolution
        img.append(
            f"COMM jaxlens sensor rows={rows} cols={cols} pixel={float(lens.sensor.pixel_size)!r}"
        )
    block(lens.num_surfaces + 1, img, 0.0, None, lens.image.semi_diameter)
    head = [
        "VERS 190513 80 123457 L123457",
        "MODE SEQ",
        f"NAME {' '.join(lens.name.split())}".rstrip(),
        "UNIT MM X W X CM MR CPMM",
        f"ENPD {_z(lens.epd)}",
        "ENVD 2.0E+1 1 0",
        "GFAC 0 0",
        "GCAT " + " ".join(gw.catalogs or ["SCHOTT"]),
        f"FTYP 0 0 {len(ys)} {len(wl)} 0 0 0",
        "XFLN " + " ".join(_z(v) for v in xs),
        "YFLN " + " ".join(_z(v) for v in ys),
        "FWGN " + " ".join("1" for _ in ys),
    ]
    head += [f"WAVM {i} {_z(w)} 1" for i, w in enumerate(wl, start=1)]
    head.append(f"PWAV {lens.primary + 1}")
    return "\n".join(head + surf_lines) + "\n", gw


def save_zmx(lens: Lens, path: str | os.PathLike, *, model_glass: str = "blank") -> list[str]:
    """Write a Zemax ``.zmx`` file (UTF-8, CRLF line ends) and its side ``.AGF`` catalogs.

    Args:
        lens: the lens.
        path: the ``.zmx`` file.
        model_glass: ``"blank"`` writes a ``ModelGlass`` as Zemax's own model glass
            (``GLAS ___BLANK 1 0 nd Vd …``, exact nd and Vd; Zemax's model dispersion away
            from the d line differs slightly from jaxlens's); ``"agf"`` writes it into the
            side AGF catalog with the Schott formula that reproduces jaxlens's dispersion
            exactly.

    Returns:
        The paths of the AGF catalogs written beside the file (possibly none).
    """
    path = os.fspath(path)
    text, gw = dumps(lens, path, model_glass=model_glass)
    folder = os.path.dirname(os.path.abspath(path))
    agfs = gw.write_agf(folder, np.atleast_1d(np.asarray(lens.wavelengths, np.float64)))
    with open(path, "w", encoding="utf-8", newline="\r\n") as fh:
        fh.write(text)
    return agfs
