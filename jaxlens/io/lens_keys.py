"""The keys a JSON lens file may hold, and the refusal of near misses.

The reader ignores unknown keys, so that informational data (``description``, ``paraxial``,
``semi_diameter_real_rays``, …) can live in the same file. A misspelled known key
(``"wavelength_nm"``, ``"radus"``, ``"Thickness"``) would then silently fall back to its
default, so a key within a small edit distance of a known one is refused instead.
"""

from __future__ import annotations

from typing import Any

TOP = ("format", "name", "description", "surfaces", "aperture", "fields", "wavelengths_um",
       "wavelengths_nm", "wavelengths", "primary", "primary_wavelength_um",
       "primary_wavelength_nm", "primary_wavelength", "stop_surface_index", "object",
       "sensor", "units", "epd", "EPD")
SURFACE = ("type", "curvature", "radius", "thickness", "conic", "even_asphere_coeffs",
           "odd_x", "odd_y", "semi_diameter", "is_stop", "material", "n", "shape")
APERTURE = ("epd", "EPD", "fnum", "FNUM", "f_number", "stop_semi_diameter")
SENSOR = ("resolution", "pixel_size")
FIELDS = ("type", "values")
OBJECT = ("distance",)


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance between two short strings."""
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        prev, row[0] = row[0], i
        for j, cb in enumerate(b, 1):
            prev, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, prev + (ca != cb))
    return row[-1]


def _allowed_edits(known: str) -> int:
    # One- and two-letter keys ("n") match only in another case: "nd" or "vd" are
    # informational glass data, not typos of "n".
    return 0 if len(known) <= 2 else 1 if len(known) <= 6 else 2


def no_misspelled(d: Any, known: tuple[str, ...], where: str) -> None:
    """Raise ``ValueError`` for a key of the mapping ``d`` that is a near miss of a known
    key (case ignored), naming the nearest one; other unknown keys pass."""
    if not isinstance(d, dict):
        return
    for key in d:
        if not isinstance(key, str) or key in known:
            continue
        near = sorted((dist, k) for k in known
                      if (dist := edit_distance(k.lower(), key.lower())) <= _allowed_edits(k))
        if near:
            raise ValueError(f"{where}: unknown key {key!r}; did you mean {near[0][1]!r}? (a "
                             f"misspelled key would be ignored and its default used)")


def no_misspelled_keys(d: dict, source: str) -> None:
    """``no_misspelled`` over a lens file's top level and its system sections (the
    surfaces are checked where they are read)."""
    no_misspelled(d, TOP, source)
    for section, known in (("aperture", APERTURE), ("sensor", SENSOR), ("fields", FIELDS),
                           ("object", OBJECT)):
        no_misspelled(d.get(section), known, f"{source}: {section}")
