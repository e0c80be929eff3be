"""The Zemax AGF glass-catalog format: glass records, their dispersion models, and the reader.

An AGF file lists glasses as NM (name, formula, nd, Vd, …), CD (dispersion coefficients) and
LD (wavelength range, µm) records. :func:`parse_agf` turns the text into
:class:`GlassRecord` s (with the file's line for every message), :meth:`GlassRecord.to_material`
into a :class:`CatalogMaterial`; :func:`load_agf` does both for a file. Name lookup in the
shipped and registered catalogs is :mod:`jaxlens.optics.catalog`.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import checks
from .input_files import input_file
from .materials import (
    EXTENDED2_POWERS,
    EXTENDED3_POWERS,
    EXTENDED_POWERS,
    LAMBDA_C,
    LAMBDA_D,
    LAMBDA_F,
    MAX_ND,
    AbstractMaterial,
    Conrady,
    Handbook1,
    Handbook2,
    Herzberger,
    Laurent,
    Schott,
    Sellmeier,
    Sellmeier2,
    Sellmeier4,
)

__all__ = ["FORMULA_NAMES", "ND_TOLERANCE", "NO_D_LINE_DATA", "CatalogMaterial", "GlassRecord",
           "decode_zemax_text", "load_agf", "parse_agf", "read_records"]

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

VD_TOLERANCE = 0.01
"""Largest accepted relative gap between an AGF record's Vd and its dispersion formula's
(nd - 1)/(nF - nC): the shipped catalogs' largest is 0.33 % (a Vd written to 0.1)."""


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
        with jax.ensure_compile_time_eval():  # one evaluation: a catalog makes thousands
            n, nf, nc = (float(v) for v in m.extrapolated_index(
                jnp.asarray([LAMBDA_D, LAMBDA_F, LAMBDA_C])))
        at = f"{self.source}: " if self.source else ""
        formula = f"formula {self.formula} ({FORMULA_NAMES.get(self.formula, '?')})"
        if not abs(n - self.nd) <= ND_TOLERANCE:
            raise ValueError(
                f"{at}{where}: its NM record gives nd {self.nd:g}, but its CD coefficients "
                f"with {formula} give n = {n:.6g} at the d line ({LAMBDA_D} µm); the record "
                f"disagrees with itself by more than {ND_TOLERANCE:g} (a wrong formula number "
                f"or coefficients?)")
        # Vd too (it went to glass_info, the nearest-glass suggestions and GLAS lines
        # whatever the formula gave); 0 is "unknown", and F or C outside the record's range
        # (LD) leaves the formula's Vd unknown.
        lo, hi = self.wavelength_range or (0.0, math.inf)
        if self.vd == 0 or not (lo <= LAMBDA_F and LAMBDA_C <= hi):
            return
        vd = (n - 1.0) / (nf - nc) if nf != nc else math.inf
        if not abs(vd - self.vd) <= VD_TOLERANCE * abs(self.vd):
            raise ValueError(
                f"{at}{where}: its NM record gives Vd {self.vd:g}, but its CD coefficients "
                f"with {formula} give Vd = (nd - 1)/(nF - nC) = {vd:.6g} (F, C lines "
                f"{LAMBDA_F}, {LAMBDA_C} µm); the record disagrees with itself by more than "
                f"{VD_TOLERANCE:.0%} (a wrong Vd, formula number or coefficients?)")


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
    """Text of a Zemax file (.zmx, .agf): UTF-32 (BOM), UTF-16 (BOM or NUL-interleaved),
    UTF-8 (BOM or not), else latin-1; other binary data is a ValueError naming ``path``.
    The BOMs are tried longest first: UTF-32 LE's (FF FE 00 00) begins with UTF-16 LE's,
    which read it as UTF-16 with a NUL after every character."""
    try:
        if raw.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
            return raw.decode("utf-32")
        if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
            return raw.decode("utf-16")
        if raw.startswith(b"\xef\xbb\xbf"):
            return raw[3:].decode("utf-8")
        head = raw[:400]
        if head and head.count(b"\x00") > len(head) // 4:
            return raw.decode("utf-16-le" if head[1:2] == b"\x00" else "utf-16-be")
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a readable {e.encoding.upper()} text file "
                         f"({e.reason})") from None
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

    Reads NM, CD and LD records; the numbers of ED, TD, IT and OD records are checked (text
    in one was skipped without a word; an OD record holds at most 6), then these records,
    CC, GC, MD, ``!`` comments and other records are skipped. A glass named twice (case
    ignored) warns; the later record wins.

    Args:
        text: AGF file contents.
        source: File name used in error messages.
        catalog: Catalog name stored in the records.

    Returns:
        The records in file order.

    Raises:
        ValueError: On a malformed NM, CD or LD record (a number that is not a plain finite
            decimal, a formula number that is not whole, nd outside [1, 4.5] or a negative
            Vd), an ED, TD, IT or OD record holding anything but numbers (or an OD record
            more than 6), a CD/LD record before any NM or given twice for one glass, an
            unsupported formula or a glass without CD record; the message names ``source``
            and the line number.
            ``GlassRecord.to_material`` (so ``load_agf``) also refuses a record whose
            formula does not give its NM nd at the d line (within ``ND_TOLERANCE``; nd 1
            with Vd 0 marks a material without d-line data).
    """
    records: list[GlassRecord] = []
    pending: _Pending | None = None
    first_line: dict[str, int] = {}
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
            # Lookups ignore case, so the later record replaced the earlier without a word.
            name = pending.fields["name"].upper()
            if name in first_line:
                warnings.warn(f"{where}: glass {pending.fields['name']} is given again (first "
                              f"on line {first_line[name]}; names ignore case): the later "
                              f"record is used", stacklevel=2)
            first_line.setdefault(name, lineno)
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
        elif key in NUMERIC_RECORDS:
            values = _floats(tokens[1:], where, f"{key} values ({NUMERIC_RECORDS[key]})")
            if key in MAX_VALUES and len(values) > MAX_VALUES[key]:
                raise ValueError(f"{where}: {key} holds at most {MAX_VALUES[key]} values "
                                 f"({NUMERIC_RECORDS[key]}), got {len(values)}: "
                                 f"{' '.join(tokens[1:])!r} (two records on one line?)")
    return records + _finish(pending, source, catalog)


NUMERIC_RECORDS = {"TD": "thermal data: D0 D1 D2 E0 E1 λtk Tref",
                   "ED": "extra data: TCE, density, ΔPgF, …",
                   "IT": "internal transmission: λ, τ, thickness",
                   "OD": "other data: relative cost, CR, FR, SR, AR, PR; -1 where unknown"}
"""AGF records that jaxlens does not use but whose values are numbers: one of text (a hand
edit gone wrong, a comma decimal) is refused with its line rather than skipped."""
MAX_VALUES = {"OD": 6}
"""The most values of a record of fixed length (Zemax writes all six of OD, -1 where
unknown; fewer, as other readers take them, are read): more is two records run together."""


def read_records(path: str | os.PathLike, catalog: str | None = None) -> list[GlassRecord]:
    """Records of an AGF file; the catalog name defaults to the upper-case file stem."""
    if not isinstance(path, str | os.PathLike):  # was os.fspath's TypeError, naming nothing
        raise TypeError(f"load_agf: path must be an .agf file name (str or os.PathLike), got "
                        f"{type(path).__name__} {path!r}")
    path = os.fspath(path)
    name = catalog or os.path.splitext(os.path.basename(path))[0].upper()
    if os.path.isdir(path):  # open() raised IsADirectoryError (a traceback, not a message)
        raise ValueError(f"{path} is a folder; give a Zemax .agf glass catalog file")
    input_file(path, "load_agf", ".agf glass catalog")
    with open(path, "rb") as f:
        records = parse_agf(decode_zemax_text(f.read(), path), source=path, catalog=name)
    if not records:  # an empty or wrong file would register a catalog without glasses
        raise ValueError(f"{path}: no glass in the file (no NM record); is it a Zemax .agf "
                         f"glass catalog?")
    return records


def load_agf(path: str | os.PathLike) -> dict[str, CatalogMaterial]:
    """Materials of a Zemax AGF glass catalog.

    The encoding is detected: UTF-16 (with or without BOM), UTF-32 (BOM), UTF-8 or latin-1.
    When a name occurs twice (case ignored), a warning names both lines and the later record
    wins.

    Args:
        path: The ``.agf`` file.

    Returns:
        Glass name (as written in the file) → :class:`CatalogMaterial`, in file order. Each
        material has ``catalog`` set to the upper-case file stem, ``catalog_nd`` and
        ``catalog_vd`` from its NM record and ``wavelength_range`` (µm) from its LD record.

    Raises:
        ValueError: If the file is malformed; the message names the file and the line.
    """
    latest = {r.name.upper(): r for r in read_records(path)}
    return {r.name: r.to_material() for r in latest.values()}
