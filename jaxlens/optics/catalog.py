"""Glass catalogs: a Zemax AGF reader and name lookup in the catalogs shipped with jaxlens.

The package ships these catalogs in ``jaxlens/data/glass`` (each file names its public
source in its ``!`` header lines):

* ``SCHOTT``: the SCHOTT catalog, status April 2013 (preferred, inquiry and obsolete glasses),
  with the glasses of SCHOTT's February 2008 catalog that it lacks: 193 obsolete ones that
  real ``.zmx`` files name (the lead-containing SK4, BAF4, KF9, LAF2, PSK3, BK7, SK16, SK2,
  LAK9, BAK1, SK5, LASFN30…), KZFSN5 and SF57HHT. SCHOTT comes first, so such a name is
  SCHOTT's even where a later catalog has a glass of that name (HIKARI's SK4, CDGM's BAF4
  and F4): ``get_material("BAF4", "CDGM")`` gives CDGM's.
* ``CDGM``: the CDGM (H-K9L, H-ZF…, H-LAK…, H-ZLAF…) catalog, January 2014.
* ``PLASTICS``: molding plastics: PMMA, POLYCARB, POLYSTYR, SAN, COC, ZEONEX 330R/480R/E48R,
  OKP4 and OKP4HT.
* ``MISC``: fused silica, CaF₂, quartz, water and a few legacy glasses.
* ``OHARA``, ``HOYA``, ``HIKARI``, ``SUMITA``: the makers' Zemax catalogs (2017) as held by
  the refractiveindex.info database (CC0), converted by ``tools/make_agf.py``; SCHOTT and CDGM
  also get that database's glasses that their files above lack (and SCHOTT B270).
* ``CORNING``: HPFS 7980 fused silica (``C79-80``).
* ``INFRARED``: Zemax's infrared catalog: ZnSe, ZnS, germanium, silicon, GaAs, sapphire, MgF₂,
  BaF₂, CaF₂, KBr, NaCl, LiF, KRS-5, AMTIR, Cleartran, SCHOTT IRG glasses…
* ``LIGHTPATH``, ``HERAEUS``, ``UMICORE``, ``TOPAS``, ``ARCHER``, ``ISUZU``: Zemax's catalogs of
  LightPath molded-lens glasses (ECO550, D-ZK3M, BD1/BD2), Heraeus silica (Suprasil,
  Infrasil…), Umicore GASIR, TOPAS COC grades, Archer molded glasses and Isuzu IIR-SF1.
* ``LZOS``: Zemax's catalog of the Russian (Soviet GOST) LZOS glasses, named with the prefix
  ``LZ_`` (LZ_K8, LZ_TF1, LZ_LK7, LZ_CTK9…).
* ``RAD_HARD``: Zemax's catalog of SCHOTT radiation-resistant glasses (BK7G18, F2G12, SF8G07…);
  six of its seven names are also SCHOTT's and stay SCHOTT's.

IR materials whose d line Zemax gives no data for carry the catalog's nd 1 and Vd 0 (a
"no data" mark, e.g. ZNSE, GERMANIUM, SILICON); their CD and LD records hold the data.

Lookups are case-insensitive. Catalogs registered with :func:`register_catalog` are
searched first (latest first), then the shipped ones in the order above, so ``"F2"`` is
SCHOTT's F2; pass ``catalogs=["CDGM"]`` to get CDGM's. ``"AIR"`` and ``""`` give
:class:`~jaxlens.optics.materials.Air`. Wavelengths are in µm, as everywhere in jaxlens.

Example:
    >>> from jaxlens.optics.catalog import get_material, glass_info
    >>> bk7 = get_material("n-bk7")
    >>> glass_info("N-BK7")
    ('SCHOTT', 1.5168, 64.17)
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import os
from collections.abc import Iterable, Mapping
from importlib.resources import files

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import checks
from .materials import (
    EXTENDED2_POWERS,
    EXTENDED3_POWERS,
    EXTENDED_POWERS,
    LAMBDA_D,
    MAX_ND,
    AbstractMaterial,
    Air,
    Conrady,
    Handbook1,
    Handbook2,
    Herzberger,
    Laurent,
    Schott,
    Sellmeier,
    Sellmeier2,
    Sellmeier4,
    abbe_number,
)

__all__ = ["CatalogMaterial", "GlassRecord", "SHIPPED_CATALOGS", "catalog_names", "get_material",
           "glass_info", "load_agf", "nearest_glasses", "parse_agf", "register_catalog"]

SHIPPED_CATALOGS = ("SCHOTT", "CDGM", "PLASTICS", "MISC", "OHARA", "HOYA", "HIKARI", "SUMITA",
                    "CORNING", "INFRARED", "LIGHTPATH", "HERAEUS", "UMICORE", "TOPAS", "ARCHER",
                    "ISUZU", "LZOS", "RAD_HARD")
"""Shipped catalogs in search order (files ``jaxlens/data/glass/<NAME>.agf``). The catalogs
from INFRARED on come last, so a name that an earlier catalog already had keeps its meaning
(``BAF2`` is CDGM's glass; the BaF₂ crystal is ``get_material("BAF2", "INFRARED")``;
``BK7G18`` is SCHOTT's, RAD_HARD's is ``get_material("BK7G18", "RAD_HARD")``)."""

FORMULA_NAMES = {
    1: "Schott",
    2: "Sellmeier 1",
    3: "Herzberger",
    4: "Sellmeier 2",
    5: "Conrady",
    6: "Sellmeier 3",
    7: "Handbook of Optics 1",
    8: "Handbook of Optics 2",
    9: "Sellmeier 4",
    10: "Extended",
    11: "Sellmeier 5",
    12: "Extended 2",
    13: "Extended 3",
}
"""Zemax dispersion formula numbers understood by :func:`load_agf`."""

NO_D_LINE_DATA = ((1.0, 0.0), (0.0, 0.0))
"""(nd, Vd) pairs that mark a record without d-line data (IR crystals): no nd to check."""

ND_TOLERANCE = 1e-3
"""Largest accepted gap between an AGF record's nd and its dispersion formula's index at the
d line (the shipped catalogs' largest is 3.8e-5)."""

_ALIASES = {
    "PC": ("PLASTICS", "POLYCARB"),
    "POLYCARBONATE": ("PLASTICS", "POLYCARB"),
    "PS": ("PLASTICS", "POLYSTYR"),
    "POLYSTYRENE": ("PLASTICS", "POLYSTYR"),
    "ZEONEX E48R": ("PLASTICS", "E48R"),
    "ZEONEX-E48R": ("PLASTICS", "E48R"),
    "ZEONEX_E48R": ("PLASTICS", "E48R"),
    "COP-E48R": ("PLASTICS", "E48R"),
    "COC-E48R": ("PLASTICS", "E48R"),
    "FUSED SILICA": ("MISC", "F_SILICA"),
    "FUSED_SILICA": ("MISC", "F_SILICA"),
    "FUSEDSILICA": ("MISC", "F_SILICA"),
    "ECO-550": ("LIGHTPATH", "ECO550"),
}
"""Unambiguous alternative names, used only when the name itself is in no searched catalog.
(BK7 and SK16 are no aliases of N-BK7 and N-SK16: SCHOTT's own BK7 and SK16 are shipped.)"""


@dataclasses.dataclass(frozen=True)
class GlassRecord:
    """One glass of an AGF file: its NM, CD and LD records, not yet turned into a material.

    Attributes:
        name: Glass name as written in the catalog.
        formula: Zemax dispersion formula number (see ``FORMULA_NAMES``).
        coefficients: Dispersion coefficients from the CD record, in catalog order.
        nd: Catalog index at the d line (587.5618 nm).
        vd: Catalog Abbe number Vd.
        catalog: Catalog name (upper case), e.g. ``"SCHOTT"``.
        wavelength_range: (min, max) wavelength of validity in µm from the LD record, or None.
        status: Zemax status code from the NM record (0 standard, 1 preferred, 2 obsolete,
            3 special, 4 melt), or None when absent.
        glass_code: The NM record's MIL / glass code field, verbatim.
        source: ``file:line`` of the NM record, for messages ("" when unknown).
    """

    name: str
    formula: int
    coefficients: tuple[float, ...]
    nd: float
    vd: float
    catalog: str = ""
    wavelength_range: tuple[float, float] | None = None
    status: int | None = None
    glass_code: str = ""
    source: str = ""

    def to_material(self) -> CatalogMaterial:
        """The dispersion model of this record, wrapped with its catalog metadata.

        Raises:
            ValueError: If the formula gives no finite index >= 1 inside the glass's range.
        """
        # Concrete even inside a jit trace (get_material in a jitted function): there the
        # coefficient arrays were tracers, the checks below skipped them and the nd check
        # failed with a ConcretizationTypeError.
        with jax.ensure_compile_time_eval():
            model = _dispersion_model(self.formula, self.coefficients, self.name, self.source)
            m = CatalogMaterial(
                model=model,
                name=self.name,
                catalog=self.catalog,
                catalog_nd=self.nd,
                catalog_vd=self.vd,
                formula=self.formula,
                wavelength_range=self.wavelength_range,
            )
        lo, hi = self.wavelength_range or (LAMBDA_D, LAMBDA_D)
        probe = LAMBDA_D if lo <= LAMBDA_D <= hi else 0.5 * (lo + hi)
        where = f"glass {self.name} of catalog {self.catalog or '?'}"
        # The file's line, as every other refusal of a record names it (C given in nm² made
        # n < 1 and the message named the glass only).
        checks.material(m, probe, f"{self.source}: {where}" if self.source else where)
        if probe == LAMBDA_D and (self.nd, self.vd) not in NO_D_LINE_DATA:
            self._check_nd(m, where)
        return m

    def _check_nd(self, m: CatalogMaterial, where: str) -> None:
        """The NM record's nd must be what the CD record's formula gives at the d line: a
        wrong formula number or garbled coefficients made a plausible index of another
        glass (the shipped catalogs agree to 4e-5)."""
        with jax.ensure_compile_time_eval():
            n = float(m.extrapolated_index(jnp.asarray(LAMBDA_D)))
        if not abs(n - self.nd) <= ND_TOLERANCE:
            at = f"{self.source}: " if self.source else ""
            raise ValueError(
                f"{at}{where}: its NM record gives nd {self.nd:g}, but its CD coefficients "
                f"with formula {self.formula} ({FORMULA_NAMES.get(self.formula, '?')}) give "
                f"n = {n:.6g} at the d line ({LAMBDA_D} µm); the record disagrees with "
                f"itself by more than {ND_TOLERANCE:g} (a wrong formula number or "
                f"coefficients?)")


class CatalogMaterial(AbstractMaterial):
    """A catalog glass: a dispersion model plus the catalog's static metadata.

    ``index`` is the wrapped model's index, so gradients flow to its coefficients.
    ``catalog_nd`` and ``catalog_vd`` are the NM-record values (what a Zemax GLAS line
    needs); they are metadata and do not follow an optimised model.

    Attributes:
        model: The dispersion formula with the catalog coefficients.
        name: Glass name as written in the catalog.
        catalog: Catalog name, e.g. ``"SCHOTT"``.
        catalog_nd: Catalog nd, or None when unknown.
        catalog_vd: Catalog Vd, or None when unknown.
        formula: Zemax dispersion formula number.
        wavelength_range: (min, max) wavelength of validity in µm, or None.
    """

    model: AbstractMaterial
    name: str = eqx.field(static=True)
    catalog: str = eqx.field(static=True, default="")
    catalog_nd: float | None = eqx.field(static=True, default=None)
    catalog_vd: float | None = eqx.field(static=True, default=None)
    formula: int = eqx.field(static=True, default=0)
    wavelength_range: tuple[float, float] | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        # By hand: a range in nm (400, 700) refused every µm wavelength later, a non-material
        # model failed at the first index, catalog nd 0.5 or formula -3 went to GLAS lines.
        where, real = f"CatalogMaterial {self.name!r}", (int, float, np.integer, np.floating)
        num = lambda v: isinstance(v, real) and not isinstance(v, bool) and math.isfinite(v)  # noqa: E731
        if not isinstance(self.model, AbstractMaterial):
            raise TypeError(f"{where}: model must be a material (jaxlens.AbstractMaterial), "
                            f"got {type(self.model).__name__}")
        if self.formula != 0 and self.formula not in FORMULA_NAMES or isinstance(
                self.formula, bool) or not isinstance(self.formula, (int, np.integer)):
            raise ValueError(f"{where}: formula must be a Zemax dispersion formula number "
                             f"({', '.join(map(str, FORMULA_NAMES))}; 0: none), got "
                             f"{self.formula!r}")
        nd, vd = self.catalog_nd, self.catalog_vd
        if not all(v is None or num(v) for v in (nd, vd)) or (vd is not None and vd < 0) or (
                nd is not None and (nd, vd or 0.0) not in NO_D_LINE_DATA and not 1 <= nd <= MAX_ND):
            raise ValueError(f"{where}: catalog_nd must be None or a d-line index in [1, "
                             f"{MAX_ND:g}] and catalog_vd None or an Abbe number >= 0 (nd 1 or "
                             f"0 with Vd 0: no d-line data), got {nd!r}, {vd!r}")
        r = self.wavelength_range
        if r is not None and not (isinstance(r, tuple) and len(r) == 2 and all(map(num, r))
                                  and 0 < r[0] < r[1] and r[0] < 100):
            raise ValueError(f"{where}: wavelength_range must be (min, max) in µm with 0 < min "
                             f"< max and min < 100 µm (0.4 µm, not 400 nm), got {r!r}")

    def index(self, wavelength):
        """The index at wavelengths in µm; a concrete wavelength outside
        ``wavelength_range`` raises ``ValueError`` naming the range (the formula is fitted
        there only, and a lens refuses such wavelengths too). ``extrapolated_index`` gives
        the formula's value anywhere."""
        if self.wavelength_range is not None:
            checks.material_wavelengths(
                self, wavelength, f"CatalogMaterial.index ({self.name})",
                hint="; extrapolated_index gives the formula's value outside it")
        # The model's formula unchecked against its poles: the catalog's range is the one
        # that holds (the shipped SILICON's, 1.36–11 µm, lies beyond its formula's 1.13 µm
        # resonance); without a stated range, the formula's own (``model.index``).
        if self.wavelength_range is None:
            return self.model.index(wavelength)
        return self.model.extrapolated_index(wavelength)

    def extrapolated_index(self, wavelength):
        """The formula's index at any wavelength in µm, outside ``wavelength_range`` too."""
        return self.model.extrapolated_index(wavelength)


# ---------------------------------------------------------------------------- dispersion


def _padded(coefficients: tuple[float, ...], count: int) -> np.ndarray:
    """The first ``count`` coefficients, zero-padded (AGF files drop trailing zeros)."""
    out = np.zeros(count)
    used = coefficients[:count]
    out[: len(used)] = used
    return out


def _sellmeier_terms(coefficients: tuple[float, ...], terms: int, name: str) -> Sellmeier:
    """Sellmeier 1/3/5: coefficients K1, L1, K2, L2, … as B = K, C = L."""
    c = _padded(coefficients, 2 * terms)
    return Sellmeier(B=c[0::2], C=c[1::2], name=name)


_BUILDERS = {
    1: lambda c, n: Schott(_padded(c, 6), name=n),
    2: lambda c, n: _sellmeier_terms(c, 3, n),
    3: lambda c, n: Herzberger(_padded(c, 6), name=n),
    4: lambda c, n: Sellmeier2(_padded(c, 5), name=n),
    5: lambda c, n: Conrady(_padded(c, 3), name=n),
    6: lambda c, n: _sellmeier_terms(c, 4, n),
    7: lambda c, n: Handbook1(_padded(c, 4), name=n),
    8: lambda c, n: Handbook2(_padded(c, 4), name=n),
    9: lambda c, n: Sellmeier4(_padded(c, 5), name=n),
    10: lambda c, n: Laurent(_padded(c, 8), powers=EXTENDED_POWERS, name=n),
    11: lambda c, n: _sellmeier_terms(c, 5, n),
    12: lambda c, n: Laurent(_padded(c, 8), powers=EXTENDED2_POWERS, name=n),
    13: lambda c, n: Laurent(_padded(c, 9), powers=EXTENDED3_POWERS, name=n),
}


def _dispersion_model(formula: int, coefficients: tuple[float, ...], name: str, source=""):
    """The material of a formula number and CD coefficients; a refusal names ``source``."""
    try:
        return _BUILDERS[formula](coefficients, name)
    except ValueError as e:
        raise ValueError(f"{source}: {e}" if source else str(e)) from None


# ---------------------------------------------------------------------------- AGF reader


def decode_zemax_text(raw: bytes, path: str = "<file>") -> str:
    """Text of a Zemax file (.zmx, .agf): UTF-16 (BOM or NUL-interleaved), UTF-8 (BOM or
    not), else latin-1; other binary data is a ValueError naming ``path``."""
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


def _floats(tokens: list[str], where: str, what: str) -> tuple[float, ...]:
    """Finite numbers (a NaN or inf coefficient, nd or bound is no catalog data)."""
    try:
        out = tuple(checks.number_text(t) for t in tokens)
    except ValueError:
        out = None
    if out is None or not all(math.isfinite(v) for v in out):
        raise ValueError(f"{where}: {what} must be finite numbers, got {' '.join(tokens)!r}")
    return out


def _optional_int(tokens: list[str], i: int) -> int | None:
    try:
        return int(float(tokens[i]))
    except (IndexError, ValueError):
        return None


@dataclasses.dataclass
class _Pending:
    """A glass whose NM record has been read and whose CD record may still come."""

    fields: dict
    line: int
    coefficients: tuple[float, ...] | None = None
    wavelength_range: tuple[float, float] | None = None
    seen: dict = dataclasses.field(default_factory=dict)  # record key -> its line number


def _parse_nm(tokens: list[str], where: str) -> dict:
    """Fields of an NM record: name, formula, MIL code, nd, Vd[, exclude, status, …]."""
    if len(tokens) < 6:
        raise ValueError(f"{where}: NM needs name, formula, MIL code, nd and Vd, got {tokens!r}")
    name = tokens[1]
    try:
        number = checks.number_text(tokens[2])
    except ValueError:
        raise ValueError(f"{where}: formula number of {name} is {tokens[2]!r}") from None
    if not number.is_integer():  # 2.7 was read as formula 2
        raise ValueError(f"{where}: formula number of {name} must be a whole number "
                         f"({', '.join(map(str, FORMULA_NAMES))}), got {tokens[2]!r}")
    formula = int(number)
    if formula not in FORMULA_NAMES:
        raise ValueError(f"{where}: {name} uses unsupported dispersion formula {formula}")
    nd, vd = _floats(tokens[4:6], where, f"nd and Vd of {name}")
    if (nd, vd) not in NO_D_LINE_DATA and not (1.0 <= nd <= MAX_ND and vd >= 0.0):
        raise ValueError(f"{where}: {name} needs nd in [1, {MAX_ND:g}] and Vd >= 0 (nd 1 or 0, "
                         f"Vd 0: no d-line data), got nd {tokens[4]}, Vd {tokens[5]}")
    return dict(name=name, formula=formula, nd=nd, vd=vd, glass_code=tokens[3],
                status=_optional_int(tokens, 7))


def _finish(pending: _Pending | None, source: str, catalog: str) -> list[GlassRecord]:
    """The record of a finished glass (none before the first NM); no CD record is an error."""
    if pending is None:
        return []
    if pending.coefficients is None:
        name = pending.fields["name"]
        raise ValueError(f"{source}:{pending.line}: glass {name} has no CD record")
    return [GlassRecord(coefficients=pending.coefficients, catalog=catalog,
                        wavelength_range=pending.wavelength_range,
                        source=f"{source}:{pending.line}", **pending.fields)]


def parse_agf(text: str, source: str = "<string>", catalog: str = "") -> list[GlassRecord]:
    """Glass records of AGF text.

    Reads NM, CD and LD records; CC, GC, ED, TD, OD, MD, IT, ``!`` comments and other
    records are skipped.

    Args:
        text: AGF file contents.
        source: File name used in error messages.
        catalog: Catalog name stored in the records.

    Returns:
        The records in file order.

    Raises:
        ValueError: On a malformed NM, CD or LD record (a number that is not a plain finite
            decimal, a formula number that is not whole, nd outside [1, 4.5] or a negative
            Vd), a CD/LD record before any NM or given twice for one glass, an unsupported
            formula or a glass without CD record; the message names ``source`` and the line
            number. ``GlassRecord.to_material`` (so ``load_agf``) also refuses a record whose
            formula does not give its NM nd at the d line (within ``ND_TOLERANCE``; nd 1
            with Vd 0 marks a material without d-line data).
    """
    records: list[GlassRecord] = []
    pending: _Pending | None = None
    # A BOM kept by a text read made the first line's key unknown: a first NM record was
    # skipped without a word.
    text = text.removeprefix("\ufeff")
    for lineno, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens or tokens[0].startswith("!"):
            continue
        key, where = tokens[0].upper(), f"{source}:{lineno}"
        if key == "NM":
            records += _finish(pending, source, catalog)
            pending = _Pending(fields=_parse_nm(tokens, where), line=lineno)
        elif key in ("CD", "LD") and pending is None:
            raise ValueError(f"{where}: {key} record before any NM record")
        elif key in ("CD", "LD") and key in pending.seen:
            # The second record replaced the first without a word.
            raise ValueError(f"{where}: {key} record given twice for glass "
                             f"{pending.fields['name']} (first on line {pending.seen[key]}); "
                             f"an AGF glass has one")
        elif key == "CD":
            pending.seen[key] = lineno
            pending.coefficients = _floats(tokens[1:], where, "CD coefficients")
            if not pending.coefficients:  # every coefficient 0: n = 1 at every wavelength
                raise ValueError(f"{where}: CD record of glass {pending.fields['name']} holds "
                                 f"no coefficients")
        elif key == "LD":
            pending.seen[key] = lineno
            bounds = _floats(tokens[1:], where, "LD wavelengths")
            if len(bounds) != 2:
                raise ValueError(f"{where}: LD needs min and max wavelength, got {tokens[1:]!r}")
            # Reversed bounds refused every wavelength later; nm failed without the line.
            # A minimum of 100 or more is nm (300 for 0.3 µm); a far-infrared maximum is not.
            if not 0 < bounds[0] < bounds[1] or bounds[0] >= 100:
                raise ValueError(f"{where}: LD needs 0 < min < max with min < 100 µm "
                                 f"(wavelengths in µm), got {bounds[0]:g} {bounds[1]:g}")
            pending.wavelength_range = (bounds[0], bounds[1])
    return records + _finish(pending, source, catalog)


def _read_records(path: str | os.PathLike, catalog: str | None = None) -> list[GlassRecord]:
    """Records of an AGF file; the catalog name defaults to the upper-case file stem."""
    path = os.fspath(path)
    name = catalog or os.path.splitext(os.path.basename(path))[0].upper()
    if os.path.isdir(path):  # open() raised IsADirectoryError (a traceback, not a message)
        raise ValueError(f"{path} is a folder; give a Zemax .agf glass catalog file")
    with open(path, "rb") as f:
        records = parse_agf(decode_zemax_text(f.read(), path), source=path, catalog=name)
    if not records:  # an empty or wrong file would register a catalog without glasses
        raise ValueError(f"{path}: no glass in the file (no NM record); is it a Zemax .agf "
                         f"glass catalog?")
    return records


def load_agf(path: str | os.PathLike) -> dict[str, CatalogMaterial]:
    """Materials of a Zemax AGF glass catalog.

    The encoding is detected: UTF-16 (with or without BOM), UTF-8 or latin-1. When a name
    occurs twice, the later record wins.

    Args:
        path: The ``.agf`` file.

    Returns:
        Glass name (as written in the file) → :class:`CatalogMaterial`, in file order. Each
        material has ``catalog`` set to the upper-case file stem, ``catalog_nd`` and
        ``catalog_vd`` from its NM record and ``wavelength_range`` (µm) from its LD record.

    Raises:
        ValueError: If the file is malformed; the message names the file and the line.
    """
    return {r.name: r.to_material() for r in _read_records(path)}


# ---------------------------------------------------------------------------- registry

_user_catalogs: list[tuple[str, dict[str, GlassRecord | AbstractMaterial]]] = []


def _glass_dir():
    return files("jaxlens") / "data" / "glass"


@functools.cache
def _shipped() -> tuple[tuple[str, dict[str, GlassRecord]], ...]:
    """Shipped catalogs, parsed once: (name, UPPER glass name → record), in search order."""
    folder = _glass_dir()
    paths = {p.name.rsplit(".", 1)[0].upper(): p for p in folder.iterdir()
             if p.name.lower().endswith(".agf")}
    order = [c for c in SHIPPED_CATALOGS if c in paths] + sorted(set(paths) - set(SHIPPED_CATALOGS))
    out = []
    for cat in order:
        text = decode_zemax_text(paths[cat].read_bytes(), str(paths[cat]))
        records = parse_agf(text, source=f"jaxlens/data/glass/{paths[cat].name}", catalog=cat)
        out.append((cat, {r.name.upper(): r for r in records}))
    return tuple(out)


def register_catalog(source: str | os.PathLike | Mapping[str, AbstractMaterial],
                     name: str | None = None) -> str:
    """Add a catalog to the lookup of :func:`get_material`, ahead of the shipped ones.

    Args:
        source: An AGF file, or a mapping glass name → material.
        name: Catalog name; defaults to the file stem for a file and ``"USER"`` for a
            mapping. Registering a name again replaces that catalog; one named as a
            shipped catalog is searched ahead of it (which answers for the rest).

    Returns:
        The catalog name (upper case) under which it was registered.

    Raises:
        ValueError: If the AGF file is malformed.
    """
    if name is not None and not (isinstance(name, str) and name.strip()):
        raise ValueError(f"register_catalog: name must be a non-empty string, got {name!r}")
    if isinstance(source, Mapping):
        cat = (name or "USER").upper()
        # A non-material value would be found by get_material and fail deep in a trace.
        bad = {k: v for k, v in source.items() if not isinstance(v, AbstractMaterial)}
        if bad:
            k, v = next(iter(bad.items()))
            raise ValueError(f"register_catalog: every value must be a material "
                             f"(jaxlens.AbstractMaterial), got {type(v).__name__} for {k!r}")
        if not source:
            raise ValueError("register_catalog: the mapping holds no material")
        entries: dict = {}
        for k, v in source.items():
            if not isinstance(k, str) or not k.strip():
                raise ValueError(f"register_catalog: every key must be a glass name (a "
                                 f"non-empty str), got {k!r}")
            if k.upper() in entries:  # lookups ignore case: one of them was dropped
                raise ValueError(f"register_catalog: glass names {k!r} and another spelling "
                                 f"of it differ only in case; lookups ignore case, so give "
                                 f"one")
            entries[k.upper()] = v
    elif not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"register_catalog: source must be an .agf file (str or os.PathLike) "
                        f"or a mapping glass name -> material, got {type(source).__name__} "
                        f"{source!r}")
    else:
        records = _read_records(source, catalog=name.upper() if name else None)
        cat = records[0].catalog if records else (name or "USER").upper()
        entries = {r.name.upper(): r for r in records}
    _user_catalogs[:] = [(c, e) for c, e in _user_catalogs if c != cat]
    _user_catalogs.insert(0, (cat, entries))
    return cat


def _search_order(catalogs: str | Iterable[str] | None):
    """(catalog, entries) pairs to search, user catalogs first."""
    everything = list(_user_catalogs) + list(_shipped())
    if catalogs is None:
        return everything
    named = [catalogs] if isinstance(catalogs, str) else (
        list(catalogs) if isinstance(catalogs, Iterable) else None)
    if not named or not all(isinstance(c, str) for c in named):  # [] listed no glass
        # Before: catalog_names(3) was "'int' object is not iterable".
        raise TypeError(f"catalogs must be a catalog name (str) or a list of them, e.g. "
                        f"'SCHOTT' or ['SCHOTT', 'CDGM'] (not []), got {type(catalogs).__name__} "
                        f"{catalogs!r}")
    wanted = [c.upper() for c in named]
    # A user catalog named as a shipped one (a newer SCHOTT.AGF) goes first, not instead.
    by_name: dict[str, list] = {}
    for cat, entries in everything:
        by_name.setdefault(cat, []).append(entries)
    unknown = [c for c in wanted if c not in by_name]
    if unknown:
        raise ValueError(f"Unknown catalog(s) {unknown}; available: {sorted(by_name)}")
    return [(c, entries) for c in wanted for entries in by_name[c]]


def _find(name: str, catalogs) -> tuple[str, GlassRecord | AbstractMaterial] | None:
    """(catalog, entry) of a glass name or alias, or None."""
    order = _search_order(catalogs)
    key = name.strip().upper()
    for cat, entries in order:
        if key in entries:
            return cat, entries[key]
    alias = _ALIASES.get(key)
    if alias is not None:
        for cat, entries in order:
            if cat == alias[0] and alias[1] in entries:
                return cat, entries[alias[1]]
    return None


def _unknown(name: str, catalogs, nd: float | None = None,
             vd: float | None = None) -> ValueError:
    upper = {n.upper(): n for n in catalog_names(catalogs=catalogs)}
    close = difflib.get_close_matches(name.strip().upper(), list(upper), n=5, cutoff=0.0)
    message = f"Unknown material {name!r}. Closest catalog matches: " + \
        (", ".join(upper[c] for c in close) or "none")
    cat, _, glass = name.strip().partition(":")
    if glass and cat.strip().upper() in {c for c, _ in _search_order(None)}:
        # "SCHOTT:N-BK7" matched no name and listed other glasses than the one meant.
        message += (f". A catalog is its own argument: get_material({glass.strip()!r}, "
                    f"{cat.strip().upper()!r})")
    elif catalogs is not None and (elsewhere := _find(name, None)) is not None:
        message += f". {name.strip()!r} is in catalog {elsewhere[0]}, not searched here"
    if nd is not None and vd is not None and nd > MAX_ND and 1.0 < vd <= MAX_ND:
        message += (f". nd {nd:g} and Vd {vd:g} look swapped (nd, the d-line index, is about "
                    f"1.2–2.6; Vd, the Abbe number, 5–120)")  # the map then listed none
        nd, vd = vd, nd
    if nd is not None and vd is not None and 1.0 < nd <= MAX_ND and 0.0 < vd < np.inf:
        listed = "; ".join(f"{c} {n} (nd {d:.5f}, Vd {v:.2f})"
                           for c, n, d, v in nearest_glasses(nd, vd, catalogs=catalogs))
        message += f". Optically closest to nd {nd:.5f}, Vd {vd:.2f}: {listed or 'none'}"
    return ValueError(message)


ND_PER_VD = 0.01
"""Glass-map scale of :func:`nearest_glasses`: an nd step of 0.01 weighs as one unit of Vd."""


def nearest_glasses(nd: float, vd: float, count: int = 5,
                    catalogs: str | Iterable[str] | None = None
                    ) -> list[tuple[str, str, float, float]]:
    """The glasses nearest to (nd, Vd) on the glass map, for substituting an unknown glass.

    The distance is ``hypot((nd − nd′)/ND_PER_VD, Vd − Vd′)`` with the catalogs' nd and Vd.
    A name found in an earlier catalog of the search order is not repeated; materials
    without catalog nd and Vd (Zemax's nd 1, Vd 0 of IR materials) are not on the map.

    Args:
        nd: Index at the d line (587.56 nm), > 1.
        vd: Abbe number Vd, > 0.
        count: How many glasses to return, ≥ 1.
        catalogs: As for :func:`get_material`.

    Returns:
        (catalog, name, nd, Vd) tuples, nearest first.

    Raises:
        ValueError: If nd, vd or count is out of range.
    """
    checks.number(nd, "nd", "nearest_glasses", lo=1, hi=MAX_ND, lo_open=True,
                  unit="(the d-line index; an nd above it is an Abbe number: nd and vd "
                       "swapped?)")
    checks.number(vd, "vd", "nearest_glasses", lo=0, lo_open=True, unit="(Abbe number)")
    checks.number(count, "count", "nearest_glasses", lo=1, integer=True, unit="glasses")
    seen: set[str] = set()
    rows = []
    for cat, entries in _search_order(catalogs):
        for key, entry in entries.items():
            if key in seen:
                continue
            seen.add(key)
            d, v = _nd_vd(entry)
            if not v > 0:  # nd 1, Vd 0: no d-line data
                continue
            rows.append((float(np.hypot((d - nd) / ND_PER_VD, v - vd)), cat,
                         entry.name if entry.name else key, d, v))
    rows.sort(key=lambda r: r[0])
    return [(c, n, d, v) for _, c, n, d, v in rows[:count]]


def get_material(name: str, catalogs: str | Iterable[str] | None = None, *,
                 nd: float | None = None, vd: float | None = None) -> AbstractMaterial:
    """A material by name from the registered and shipped catalogs.

    Args:
        name: Glass name, case-insensitive (``"N-BK7"``, ``"h-k9l"``, ``"E48R"``), an
            alias (``"PC"``, ``"PS"``, ``"FUSED SILICA"``…), or ``"AIR"``/``""`` for air.
        catalogs: Catalog name(s) to search, in order (e.g. ``"CDGM"``); default: all, user
            catalogs first, then ``SHIPPED_CATALOGS``.
        nd, vd: The glass's nd and Vd where known (a Zemax GLAS line carries them); used
            only in the error for an unknown name, to list optically close glasses.

    Returns:
        A :class:`CatalogMaterial` for AGF glasses, :class:`~jaxlens.optics.materials.Air` for air,
        or the registered object for catalogs given as mappings.

    Raises:
        ValueError: If the name is in no searched catalog; the message lists the 5 closest
            catalog names and, given nd and vd, the 5 nearest glasses (:func:`nearest_glasses`).
    """
    if not isinstance(name, str):
        raise TypeError(f"get_material: name must be a glass name (str), got "
                        f"{type(name).__name__} {name!r}")
    if name.strip().upper() in ("", "AIR"):
        return Air()
    for arg, v in (("nd", nd), ("vd", vd)):
        if v is not None:  # a string failed as "'<' not supported" in the error message
            checks.real_values(v, arg, "get_material")
    found = _find(name, catalogs)
    if found is None:
        raise _unknown(name, catalogs, nd, vd)
    entry = found[1]
    return entry.to_material() if isinstance(entry, GlassRecord) else entry


STATUS_OBSOLETE = 2
"""Zemax's NM-record status of a glass its maker no longer melts."""


def catalog_names(catalog: str | None = None,
                  catalogs: str | Iterable[str] | None = None, *,
                  obsolete: bool = True) -> list[str]:
    """Names of the available glasses.

    Args:
        catalog: Only this catalog (shortcut for ``catalogs=[catalog]``).
        catalogs: Catalogs to list, in order; default: all, in search order.
        obsolete: Also list glasses of status ``STATUS_OBSOLETE`` (no longer made). A name
            whose glass in the first catalog that has it is obsolete is left out entirely,
            since ``get_material`` of that name gives that glass.

    Returns:
        Glass names as written in their catalogs, in search order; a name found in an
        earlier catalog is not repeated.
    """
    if catalog is not None and catalogs is not None:  # catalogs was ignored
        raise ValueError(f"catalog_names: give catalog or catalogs, not both; got "
                         f"{catalog!r} and {catalogs!r}")
    checks.switch(obsolete, "obsolete", "catalog_names")
    seen: dict[str, tuple[str, bool]] = {}
    for _, entries in _search_order(catalog if catalog is not None else catalogs):
        for key, entry in entries.items():
            old = isinstance(entry, GlassRecord) and entry.status == STATUS_OBSOLETE
            seen.setdefault(key, (entry.name if entry.name else key, old))
    return [name for name, old in seen.values() if obsolete or not old]


def _nd_vd(entry: GlassRecord | AbstractMaterial, strict: bool = False) -> tuple[float, float]:
    """Catalog nd and Vd, or values computed from the index for plain materials. A table
    without data at the F and C lines has no Vd: refused where ``strict``, else Vd 0 (off
    the glass map, as Zemax's IR materials)."""
    if isinstance(entry, GlassRecord):
        return entry.nd, entry.vd
    if isinstance(entry, CatalogMaterial) and entry.catalog_nd is not None:
        return entry.catalog_nd, entry.catalog_vd
    nd = float(entry.extrapolated_index(jnp.asarray(LAMBDA_D)))
    try:
        return nd, float(abbe_number(entry))
    except ValueError:
        if strict:
            raise
        return nd, 0.0


def glass_info(name: str, catalogs: str | Iterable[str] | None = None) -> tuple[str, float, float]:
    """Catalog, nd and Vd of a glass.

    Args:
        name: As for :func:`get_material` (not air).
        catalogs: As for :func:`get_material`.

    Returns:
        (catalog name, nd, Vd); nd and Vd are the catalog's NM-record values, or computed at
        the d, F and C lines for materials registered as objects without catalog data.

    Raises:
        ValueError: If the name is in no searched catalog.
    """
    if not isinstance(name, str):
        raise TypeError(f"glass_info: name must be a glass name (str), got "
                        f"{type(name).__name__} {name!r}")
    if name.strip().upper() in ("", "AIR"):  # was "Unknown material 'AIR'" (GASIR2, …)
        raise ValueError(f"glass_info: {name!r} is air (get_material gives Air), not a catalog "
                         f"glass; it has no catalog nd and Vd")
    found = _find(name, catalogs)
    if found is None:
        raise _unknown(name, catalogs)
    nd, vd = _nd_vd(found[1], strict=True)
    return found[0], nd, vd
