"""Shared by the ``.zmx`` reader and writer: Zemax catalog names, the extended-polynomial
term order and the ``jaxlens`` comment markers (see ``jaxlens.io.zmx`` for the format)."""

from __future__ import annotations

import math
import re
import warnings

# The extended polynomial's term order is the XYPolynomial surface's (one definition).
from ..optics.xypolynomial import xy_term_index as term_index  # noqa: F401
from ..optics.xypolynomial import xy_term_powers as term_powers  # noqa: F401

ZEMAX_CATALOGS = frozenset(
    "SCHOTT CDGM OHARA HOYA SUMITA HIKARI HIKARI_CHINA MISC ZEON INFRARED BIREFRINGENT "
    "ARCHER ARTON CORNING HERAEUS ISUZU LIGHTPATH LZOS NHG NIKON OSAKAGASCHEMICAL RPO "
    "SCHOTT_IRG SCHOTT_HT UMICORE MITSUI OPTIMAX KOREA_OGC LIGHTPATH_BD2 SCHOTT_2000 "
    "NSG QIOPTIQ".split()
)
"""Catalog names shipped with Zemax OpticStudio; glasses from them are written by name."""

PLASTIC_CATALOG = {
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
HYBRID_COMMENT = re.compile(r"jaxlens hybrid even=(\d+) odd=(\d+)")
SENSOR_COMMENT = re.compile(r"jaxlens sensor rows=(\d+) cols=(\d+) pixel=(\S+)")
MARKER = "jaxlens "
MAX_XPOLY_DEGREE = 20


class ZmxWarning(UserWarning):
    """A ``.zmx`` file has content the reader does not understand (it may be truncated)."""


def report(strict: bool, msg: str) -> None:
    """An error under ``strict``, else a warning."""
    if strict:
        raise ValueError(msg + " (strict mode)")
    warnings.warn(msg, ZmxWarning, stacklevel=4)


def xpoly_terms(a, bx, by) -> dict:
    """Extended-polynomial coefficients {(px, py): value} of a hybrid surface's polynomial."""
    out = {}
    for i, ai in enumerate(a, start=1):
        for j in range(i + 1):
            out[(2 * i - 2 * j, 2 * j)] = math.comb(i, j) * float(ai)
    for j, (b, d) in enumerate(zip(bx, by, strict=True), start=1):
        out[(2 * j + 1, 0)] = float(b)
        out[(0, 2 * j + 1)] = float(d)
    return out
