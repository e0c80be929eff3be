"""Convert glass makers' data of the refractiveindex.info database into Zemax AGF catalogs.

Source: the refractiveindex.info database by M. N. Polyanskiy
(https://github.com/polyanskiy/refractiveindex.info-database), public domain under CC0 1.0.
Its glass files copy the makers' own Zemax catalogs and data sheets (each file's REFERENCES
names which); the AGF files written here name the database and those catalogs in their
header.

Usage::

    python tools/make_agf.py DATABASE [--out jaxlens/data/glass]

``DATABASE`` is a local copy of the database: a folder holding ``data-nk/glass/<maker>/``
(the layout of the database's ``database/`` folder up to 2024, also shipped inside the
``optiland`` wheel as ``optiland/database``) or ``data/specs/<maker>/`` (the later layout).
Nothing is downloaded.

Written: ``OHARA.agf``, ``HOYA.agf``, ``HIKARI.agf`` and ``SUMITA.agf`` whole, and in
``SCHOTT.agf`` and ``CDGM.agf`` a section after ``ADDED_MARKER`` with the database's glasses
that the hand-kept part of the file lacks (rerunning replaces that section).

Formula mapping (refractiveindex.info formula → Zemax AGF formula), λ in µm on both sides:

* formula 1, n² − 1 = C1 + Σ Bᵢ λ²/(λ² − Cᵢ²): Sellmeier with Kᵢ = Bᵢ, Lᵢ = Cᵢ².
* formula 2, n² − 1 = C1 + Σ Bᵢ λ²/(λ² − Cᵢ): Sellmeier with Kᵢ = Bᵢ, Lᵢ = Cᵢ.
  For both, a non-zero C1 becomes one more term K = C1, L = 0 (K λ²/λ² = C1, exact);
  3, 4 or 5 terms give Zemax Sellmeier 1 (2), Sellmeier 3 (6) or Sellmeier 5 (11).
* formula 3, n² = C1 + Σ Cᵢ λ^pᵢ: the first of Schott (1), Extended (10), Extended 2 (12)
  and Extended 3 (13) whose powers of λ include every power used, coefficients placed by
  power.

nd and Vd of the NM record are the database's listed values (its SPECS or PROPERTIES,
copied from the maker's catalog), not recomputed, so tests/test_catalog.py can check the
converted formula against them. Glasses given only as index tables, or without listed nd
and Vd, are left out and listed on stderr.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from dataclasses import dataclass

ADDED_MARKER = "! ---- added by tools/make_agf.py from the refractiveindex.info database ----"

# maker folder -> (catalog file stem, write whole file?)
MAKERS = {
    "ohara": ("OHARA", True),
    "hoya": ("HOYA", True),
    "hikari": ("HIKARI", True),
    "sumita": ("SUMITA", True),
    "schott": ("SCHOTT", False),
    "cdgm": ("CDGM", False),
}

# Sub-folders whose file names are not glass names (schott/BK7/Lane.yml is BK7 measured by
# Lane; hikari/i-line/4786.yml names the glass by a number only).
SKIP_FOLDERS = {"BK7", "i-line"}

SCHOTT_POWERS = (0, 2, -2, -4, -6, -8)
EXTENDED_POWERS = (0, 2, -2, -4, -6, -8, -10, -12)
EXTENDED2_POWERS = (0, 2, -2, -4, -6, -8, 4, 6)
EXTENDED3_POWERS = (0, 2, 4, -2, -4, -6, -8, -10, -12)
POLYNOMIAL_FORMULAS = ((1, SCHOTT_POWERS), (10, EXTENDED_POWERS), (12, EXTENDED2_POWERS),
                       (13, EXTENDED3_POWERS))
SELLMEIER_FORMULAS = {3: 2, 4: 6, 5: 11}  # number of terms -> Zemax formula


@dataclass
class Glass:
    name: str
    formula: int
    coefficients: list[float]
    nd: str
    vd: str
    code: str
    wavelength_range: tuple[str, str] | None
    status: int
    source: str  # the maker's catalog named in REFERENCES


# ----------------------------------------------------------------------- reading the YAML


def _scalar(text: str) -> str:
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] == '"':
        text = text[1:-1].replace('\\"', '"')
    return text


def _top_level(lines: list[str], key: str) -> str:
    """A top-level string value: quoted on one line, or a ``|`` block."""
    for i, line in enumerate(lines):
        if line.startswith(key + ":"):
            value = line[len(key) + 1:].strip()
            if value not in ("|", ">"):
                return _scalar(value)
            block = []
            for nxt in lines[i + 1:]:
                if nxt and not nxt[0].isspace():
                    break
                block.append(nxt.strip())
            return " ".join(b for b in block if b)
    return ""


def _data_entries(lines: list[str]) -> list[dict]:
    """The DATA list: each entry's type, wavelength_range and coefficients (as text)."""
    entries: list[dict] = []
    inside = False
    for line in lines:
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if not line[0].isspace():
            inside = line.startswith("DATA:")
            continue
        if not inside:
            continue
        m = re.match(r"\s*-\s*type:\s*(.*)$", line)
        if m:
            entries.append({"type": _scalar(m.group(1)).strip()})
            continue
        m = re.match(r"\s*(wavelength_range|coefficients):\s*(.*)$", line)
        if m and entries:
            entries[-1][m.group(1)] = _scalar(m.group(2))
    return entries


def _property(lines: list[str], key: str) -> str | None:
    """nd, Vd or glass_code from the SPECS (or, later layout, PROPERTIES) block."""
    inside = False
    for line in lines:
        if line and not line[0].isspace():
            inside = line.startswith(("SPECS:", "PROPERTIES:"))
            continue
        m = re.match(rf"\s+{key}:\s*(\S+)\s*$", line)
        if inside and m:
            return _scalar(m.group(1))
    return None


def _source(lines: list[str]) -> str:
    """Text of the first link in REFERENCES: the maker's Zemax catalog or data sheet."""
    refs = _top_level(lines, "REFERENCES")
    m = re.search(r"<a [^>]*>([^<]*)</a>", refs)
    return (m.group(1) if m else re.sub(r"<[^>]+>", "", refs)).strip()


def _status(comments: str) -> int:
    """Zemax status: 1 preferred, 2 obsolete, 3 inquiry, else 0 standard."""
    c = comments.lower()
    if "discontinu" in c or "obsolete" in c:
        return 2
    if "recommended" in c or "preferred" in c:
        return 1
    if "inquiry" in c:
        return 3
    return 0


# ------------------------------------------------------------------------- formula mapping


def _sellmeier(c: list[float], squared: bool, where: str) -> tuple[int, list[float]]:
    const, rest = (c[0], c[1:]) if c else (0.0, [])
    if len(rest) % 2:
        rest = rest + [0.0]
    terms = [(rest[i], rest[i + 1] ** 2 if squared else rest[i + 1])
             for i in range(0, len(rest), 2)]
    terms = [t for t in terms if t[0] != 0.0]
    if const != 0.0:
        terms.append((const, 0.0))
    count = max(len(terms), 3)
    if count not in SELLMEIER_FORMULAS:
        raise ValueError(f"{where}: {len(terms)} Sellmeier terms; AGF takes at most 5")
    terms += [(0.0, 0.0)] * (count - len(terms))
    return SELLMEIER_FORMULAS[count], [x for t in terms for x in t]


def _polynomial(c: list[float], where: str) -> tuple[int, list[float]]:
    if len(c) % 2 == 0:
        raise ValueError(f"{where}: polynomial needs C1 and (coefficient, power) pairs")
    terms = {0.0: c[0]}
    for k, p in zip(c[1::2], c[2::2], strict=True):
        terms[p] = terms.get(p, 0.0) + k
    used = {p for p, k in terms.items() if k != 0.0}
    for formula, powers in POLYNOMIAL_FORMULAS:
        if used <= set(powers):
            return formula, [terms.get(float(p), 0.0) for p in powers]
    raise ValueError(f"{where}: powers {sorted(used)} fit no AGF polynomial formula")


def convert(path: str) -> Glass | str:
    """The glass of one database file, or the reason it cannot be converted."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    name = os.path.splitext(os.path.basename(path))[0]
    formulas = [e for e in _data_entries(lines) if e["type"].startswith("formula")]
    if not formulas:
        return "index table only, no dispersion formula"
    nd, vd = _property(lines, "nd"), _property(lines, "Vd")
    if nd is None or vd is None:
        return "no listed nd and Vd"
    if _property(lines, "n_is_absolute") == "true" or \
            _property(lines, "wavelength_is_vacuum") == "true":
        return "absolute index or vacuum wavelengths (AGF is relative to air)"
    entry = formulas[0]
    kind = int(entry["type"].split()[1])
    coeffs = [float(x) for x in entry.get("coefficients", "").split()]
    if kind in (1, 2):
        formula, cd = _sellmeier(coeffs, squared=kind == 1, where=path)
    elif kind == 3:
        formula, cd = _polynomial(coeffs, where=path)
    else:
        return f"refractiveindex.info formula {kind} has no AGF counterpart here"
    rng = entry.get("wavelength_range", "").split()
    code = _property(lines, "glass_code") or "0"
    return Glass(name=name, formula=formula, coefficients=cd, nd=nd, vd=vd, code=code,
                 wavelength_range=(rng[0], rng[1]) if len(rng) == 2 else None,
                 status=_status(_top_level(lines, "COMMENTS")), source=_source(lines))


# ------------------------------------------------------------------------------- writing


def maker_folder(database: str, maker: str) -> str:
    for sub in ("data-nk/glass", "data/specs", "database/data-nk/glass", "database/data/specs"):
        folder = os.path.join(database, sub, maker)
        if os.path.isdir(folder):
            return folder
    raise SystemExit(f"no folder for {maker!r} under {database!r} (data-nk/glass or data/specs)")


def read_maker(folder: str) -> tuple[list[Glass], list[str]]:
    glasses: dict[str, Glass] = {}
    skipped = []
    for root, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_FOLDERS)
        for fname in sorted(names):
            if not fname.endswith(".yml") or fname == "about.yml":
                continue
            path = os.path.join(root, fname)
            got = convert(path)
            if isinstance(got, str):
                skipped.append(f"{os.path.relpath(path, folder)}: {got}")
            elif got.name.upper() in glasses:
                skipped.append(f"{os.path.relpath(path, folder)}: duplicate name {got.name}")
            else:
                glasses[got.name.upper()] = got
    return sorted(glasses.values(), key=lambda g: g.name), skipped


def agf_records(glass: Glass) -> list[str]:
    out = [f"NM {glass.name} {glass.formula} {glass.code} {glass.nd} {glass.vd} 0 {glass.status}",
           "CD " + " ".join(repr(float(x)) for x in glass.coefficients)]
    if glass.wavelength_range:
        out.append(f"LD {glass.wavelength_range[0]} {glass.wavelength_range[1]}")
    return out


def header(catalog: str, glasses: list[Glass]) -> list[str]:
    sources = sorted({g.source for g in glasses if g.source})
    lines = [
        f"! {catalog} glass catalog for Zemax (AGF), converted by tools/make_agf.py.",
        "! Source: the refractiveindex.info database (M. N. Polyanskiy,",
        "!   https://github.com/polyanskiy/refractiveindex.info-database), CC0 1.0 (public",
        "!   domain). Its files copy these maker catalogs and data sheets:",
    ]
    lines += [f"!   - {s}" for s in sources]
    lines += [
        "! Records: NM (name, formula, glass code, nd, Vd, exclude, status), CD (coefficients,",
        "!   λ in µm), LD (wavelength range in µm). nd and Vd are the values the source lists.",
        "!   Status: 1 recommended, 2 discontinued, 3 inquiry, 0 other.",
    ]
    return lines


def _write_lines(path: str, lines: list[str]) -> None:
    """Write a catalog whole or not at all (a temporary file renamed): a run interrupted
    mid-write left a catalog cut at a glass's end, which reads as a smaller catalog."""
    tmp = path + ".partial"
    with open(tmp, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)


def write_whole(path: str, catalog: str, glasses: list[Glass]) -> None:
    lines = header(catalog, glasses) + [f"CC {catalog} catalog from the refractiveindex.info "
                                        "database"]
    for g in glasses:
        lines += agf_records(g)
    _write_lines(path, lines)


def write_added(path: str, catalog: str, glasses: list[Glass]) -> list[Glass]:
    """Append the glasses the hand-kept part of ``path`` lacks; returns them."""
    with open(path, encoding="utf-8") as f:
        kept = f.read().split(ADDED_MARKER)[0].rstrip("\n").splitlines()
    have = {line.split()[1].upper() for line in kept if line.startswith("NM ")}
    added = [g for g in glasses if g.name.upper() not in have]
    lines = kept + ["", ADDED_MARKER] + header(catalog, added)[1:]
    for g in added:
        lines += agf_records(g)
    _write_lines(path, lines)
    return added


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("database", help="local copy of the refractiveindex.info database")
    parser.add_argument("--out", default=os.path.join("jaxlens", "data", "glass"))
    args = parser.parse_args(argv)
    # Checked before reading: a missing --out failed with a traceback after the first maker.
    for arg, folder in (("database", args.database), ("--out", args.out)):
        if not os.path.isdir(folder):
            parser.error(f"{arg}: no such folder {folder!r}")
    # Also before the first catalog is written: a maker missing from the database, or a
    # hand-kept catalog missing from --out, stopped the run with some catalogs rewritten.
    for maker, (catalog, whole) in MAKERS.items():
        try:
            maker_folder(args.database, maker)
        except SystemExit as e:
            parser.error(f"database: {e}")
        kept = os.path.join(args.out, f"{catalog}.agf")
        if not whole and not os.path.isfile(kept):
            parser.error(f"--out {args.out} has no {catalog}.agf: its {catalog} glasses are "
                         f"added to the hand-kept catalog there (give jaxlens/data/glass)")
    for maker, (catalog, whole) in MAKERS.items():
        glasses, skipped = read_maker(maker_folder(args.database, maker))
        path = os.path.join(args.out, f"{catalog}.agf")
        if whole:
            write_whole(path, catalog, glasses)
            print(f"{path}: {len(glasses)} glasses")
        else:
            added = write_added(path, catalog, glasses)
            print(f"{path}: {len(added)} glasses added of {len(glasses)}")
        for s in skipped:
            print(f"  skipped {maker}/{s}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
