"""``.zmx`` surface types beyond the standard and even-asphere ones: ``ODDASPHE`` and
``TILTSURF`` (read here, written with the others by ``zmx_write``), ``TOROIDAL``,
``PARAXIAL``, ``BICONICX``, ``SZERNSAG`` and ``FZERNSAG`` (and the others below), read and
written (the format: ``jaxlens.io.zmx``; the surfaces:
``jaxlens.optics.surfaces``, ``jaxlens.optics.toroidal``,
``jaxlens.optics.paraxial_surface`` and ``jaxlens.optics.xypolynomial``).

ODDASPHE: CURV and CONI the base conic, PARM 1…8 the coefficients β_1…β_8 on r, r², …, r⁸
(lens units^(1−i), converted to mm).

TILTSURF: the plane z = tan θx·x + tan θy·y, PARM 1 = tan θx and PARM 2 = tan θy
(dimensionless, no unit conversion); CURV and CONI 0 and no other PARM or XDAT. Unlike
COORDBRK it leaves the frame of the surfaces after it unchanged.

TOROIDAL: CURV and CONI are the y–z profile's curvature and conic, PARM 1 the radius of
rotation R (0: a cylinder), PARM 2…9 the coefficients on y², y⁴, …, y¹⁶. Its extra data
(XDAT) hold Zernike terms added to the sag; jaxlens refuses any that is not zero.

BINARY_2: an even asphere (CURV, CONI, PARM 1…8 on r², r⁴, …, lens units^(1−2i)) with the
diffractive phase Φ = M Σ A_i ρ^{2i}, ρ = r/R (``jaxlens.optics.diffractive``): PARM 0 is the
diffraction order M, XDAT 1 the number of terms N (a whole number >= 0), XDAT 2 the
normalisation radius R (lens units, > 0 when N > 0), XDAT 3 … XDAT N+2 the A_i (radians, no
unit conversion). XDAT 1 and 2 must be present, a missing term reads as 0, none beyond it
may be nonzero, and PARM 0 must be given when the phase is not zero (a missing order
reads as 0 in Zemax, which would switch the phase off). It cannot be a mirror.

QED_TYPE: a Forbes Q-type asphere (``jaxlens.optics.qtype``): CURV and CONI the base conic,
XDAT 1 the polynomial type (0: Q-bfs, 1: Q-con), XDAT 2 the number of terms N (a whole number
>= 0), XDAT 3 the normalisation radius (lens units, > 0), XDAT 4 … XDAT N+3 the
coefficients a_0 … a_(N−1) (lens units). XDAT 1, 2 and 3 must be present, a missing term
reads as 0, none beyond it may be nonzero, and it has no PARM.
DGRATING: a conic (CURV, CONI) ruled with lines parallel to the local x axis
(``jaxlens.optics.diffractive.Grating``): PARM 1 the line density T in lines per µm (whatever
the lens units: no unit conversion; >= 0, equally spaced in the projection on the x–y plane),
PARM 2 the diffraction order M (a whole number; positive bends rays toward +y). A missing
PARM reads as 0 (as in Zemax: no lines, or order 0). It may be a mirror (``GLAS MIRROR``: a
reflective grating). No other PARM and no XDAT.

BICONICX: a ``Biconic`` (``jaxlens.optics.freeform``): CURV and CONI the y–z section's
curvature and conic, PARM 1 the x radius Rx (lens units; 0 is flat in x, as in Zemax), PARM 2
the x conic. No other PARM and no XDAT. The writer writes PARM 1 as 1/cx to 25 significant
digits (``radius_text``), so the round trip is exact.

SZERNSAG, FZERNSAG: a ``ZernikeSag`` (Zemax Zernike Standard Sag, Noll order and
normalisation; Zernike Fringe Sag): CURV, CONI and PARM 1…8 the even asphere (A2…A16 on r²…
r¹⁶, lens units^(1−2i)), PARM 0 the extrapolate flag (0: Zernike terms only within the
normalisation radius, 1: everywhere; a missing PARM 0 reads as 0, as in Zemax), PARM 9 and 10
the decenter x, y of the Zernike terms (lens units; the terms are centred at (PARM 9,
PARM 10), ``jaxlens.optics.freeform``), XDAT 1 the number of terms N (whole,
0…231 Standard, 0…37 Fringe), XDAT 2 the normalisation radius (lens units, > 0), XDAT 3 …
XDAT N+2 the coefficients of Z_1 … Z_N (lens units; a missing one reads as 0). A nonzero
XDAT beyond N+2, or PARM 11 and beyond, is refused.

XPOLYNOM (Zemax's Extended Polynomial), read as an ``XYPolynomial`` unless it carries
jaxlens's hybrid comment (``jaxlens hybrid even=M odd=P``: a ``Hybrid`` written by jaxlens,
read by ``zmx_read``): CURV and CONI the base conic, XDAT 1 the number of terms N (a whole
number in 0…230), XDAT 2 the normalisation radius R (lens units, > 0), XDAT 3 … XDAT N+2 the
coefficients A_1 … A_N of x, y, x², xy, y², x³, … of the normalised coordinates (lens
units, converted to mm; the term order: ``jaxlens.optics.xypolynomial``). XDAT 1 and XDAT 2
must be present, a missing term reads as 0, none beyond it may be nonzero, and it has no
PARM. The writer writes R and each A_i exactly (shortest round-trip digits).

PARAXIAL: PARM 1 is the focal length, PARM 2 the OPD mode (0: conjugates from a real
parabasal ray, 1: integrated phase, 2: infinite conjugates, 3: conjugates from a paraxial
ray). The rays do not depend on the mode. jaxlens's optical path is mode 2's; the others
give the same path where the beam reaching the surface is collimated (object at infinity
and no net power before the surface, in the y–z and the x–z section, at every wavelength).
Elsewhere modes 0 and 3 (and none) are read where the difference of the two paths
(``opd_mode_error``, peak to valley over the surface) is at most
``OPD_MODE_TOLERANCE_WAVES`` (0.01 waves), with a warning (an error under ``strict``);
above it, where it cannot be bounded, and for mode 1, they are refused. The writer writes
mode 2.
Extra data are read through ``ExtraData``, one rule for every kind: the header lines (count,
normalisation radius, QED_TYPE's type) must be present (a missing one is refused naming the
surface's line and the XDAT index); a missing term line reads as 0, as a missing PARM does
(a value that is not a number is refused with its line by ``zmx_parse``).
"""

from __future__ import annotations

import decimal
import fractions
import math

import jax.numpy as jnp
import numpy as np

from ..optics import paraxial
from ..optics.diffractive import Binary2, Grating
from ..optics.freeform import MAX_ZERNIKE_TERMS, Biconic, ZernikeSag
from ..optics.lens import Lens, Sensor
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.qtype import QTypeAsphere
from ..optics.reciprocal import reciprocal_length
from ..optics.surfaces import OddAsphere, TiltedPlane
from ..optics.toroidal import Toroidal
from ..optics.xypolynomial import MAX_XY_TERMS, XYPolynomial
from .zmx_common import SENSOR_COMMENT, report

OPD_MODES = {0: "real parabasal conjugates", 1: "integrated phase", 2: "infinite conjugates",
             3: "paraxial conjugates"}
"""Zemax's OPD modes of a PARAXIAL surface (PARM 2)."""

COLLIMATED = 1e-9
"""A beam counts as collimated when the power before the surface, times its focal length,
is below this (the beam would converge more than 1e9 focal lengths away)."""


def _arr(x):
    return jnp.asarray(np.asarray(x, np.float64))


def _parms(s, allowed: range, what: str) -> None:
    for i, (v, ln) in s.parm.items():
        if i not in allowed and v != 0:
            raise ln.error(f"{what} uses PARM {allowed.start}..{allowed.stop - 1} only")


def _no_extra_data(s, message: str) -> None:
    for _, (v, ln) in sorted(s.xdat.items()):
        if v != 0:
            raise ln.error(message)


class ExtraData:
    """Checked access to a surface block's extra data (``s.xdat``: index -> (value, line)),
    whose ``header`` names XDAT 1, 2, … before the terms.

    One rule for every kind that reads extra data (BINARY_2, QED_TYPE, SZERNSAG, FZERNSAG,
    XASPHERE, XOSPHERE, XPOLYNOM and jaxlens's hybrid), from what OpticStudio writes and
    holds: it writes every line from XDAT 1 to the last the surface uses, zeros included
    (the header, then all N terms), and an XDAT line sets one value of data whose terms
    start at 0, as a PARM line does. So

    * a missing term line (XDAT beyond the header, up to the N the count gives) reads as 0,
      the value OpticStudio holds there (a hand-written file may leave zero terms out);
    * a missing header line (the count, the normalisation radius, QED_TYPE's polynomial
      type) is refused, naming the TYPE line and the index: OpticStudio fills it with the
      surface type's own default (a TOROIDAL with no Zernike terms is written with XDAT 2 =
      100, its default radius), which the file does not state;
    * a nonzero value beyond the N terms, or below XDAT 1, is refused, naming its line.

    Every error names the file and the line."""

    def __init__(self, s, header: tuple[str, ...], kind: str | None = None):
        self.s, self.header, self.kind = s, header, kind or s.type
        self.where = s.type_line or s.line
        self.counted = (1, 0, "terms", self.where)
        for i, (v, ln) in sorted(s.xdat.items()):
            if i < 1 and v != 0:
                raise ln.error(f"{self.kind} extra data start at XDAT 1 ({header[0]})")

    def get(self, i: int):
        """XDAT i's (value, line); a missing line is refused, naming the TYPE line."""
        if i in self.s.xdat:
            return self.s.xdat[i]
        names = [f"XDAT {j} ({h})" for j, h in enumerate(self.header, start=1)]
        listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        raise self.where.error(f"{self.kind} needs {listed}; XDAT {i} is missing (OpticStudio "
                               f"writes it, and its default is the surface type's own)")

    def required(self) -> list:
        """The header lines' (value, line), each refused where missing."""
        return [self.get(j) for j in range(1, len(self.header) + 1)]

    def count(self, i: int, terms: str, most: int, note: str = "") -> int:
        """XDAT i as a number of ``terms``: a whole number in 0..``most``."""
        v, ln = self.get(i)
        if v != int(v) or not 0 <= v <= most:
            raise ln.error(f"XDAT {i} (the number of {terms}) must be a whole number in "
                           f"0..{most}{note}, got {v:g}")
        self.counted = (i, int(v), terms, ln)
        return int(v)

    def radius(self, i: int, what: str = "the normalisation radius, lens units") -> float:
        """XDAT i as a length (lens units): finite and > 0."""
        v, ln = self.get(i)
        if not (v > 0 and math.isfinite(v)):
            raise ln.error(f"XDAT {i} ({what}) must be > 0, got {v:g}")
        return v

    def terms(self, first: int) -> list[float]:
        """The counted terms from XDAT ``first``; a missing term line reads as 0."""
        ci, n, terms, _ = self.counted
        last = first + n - 1
        span = f"XDAT {first} … XDAT {last}" if n else "none"
        for i, (v, ln) in sorted(self.s.xdat.items()):
            if i > last and v != 0:
                raise ln.error(f"coefficient beyond the {n} {terms} of XDAT {ci} ({span})")
        return [self.s.xdat.get(j, (0.0, None))[0] for j in range(first, last + 1)]


def normalised_terms(s, terms: str, most: int, note: str = "") -> tuple[int, float, list]:
    """(N, R, [A_1 … A_N]) of the XDAT layout XDAT 1 = N (0..``most``), XDAT 2 = the
    normalisation radius R (> 0, lens units), XDAT 3 … XDAT N+2 the terms (the header
    required, a missing term 0: ``ExtraData``): XPOLYNOM, XASPHERE, XOSPHERE."""
    xd = ExtraData(s, ("the number of terms", "the normalisation radius, lens units"))
    xd.required()
    n = xd.count(1, terms, most, note)
    return n, xd.radius(2), xd.terms(3)


def odd_asphere(s, unit: float, sd: float) -> OddAsphere:
    """An ``OddAsphere`` from an ODDASPHE surface block (the reader's surface record)."""
    _parms(s, range(1, 9), "ODDASPHE")
    q = max([i for i in s.parm if 1 <= i <= 8], default=0)
    b = [s.parm.get(i, (0.0, None))[0] * unit ** (1 - i) for i in range(1, q + 1)]
    return OddAsphere(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(b, np.float64)),
                      semi_diameter=_arr(sd))


def tilted_plane(s, sd: float) -> TiltedPlane:
    """A ``TiltedPlane`` from a TILTSURF surface block (the reader's surface record); the
    slopes PARM 1, 2 have no unit."""
    _parms(s, range(1, 3), "TILTSURF")
    _no_extra_data(s, "TILTSURF has no extra data (XDAT)")
    if s.curv != 0 or s.coni != 0:
        raise (s.curv_line if s.curv != 0 else s.type_line or s.line).error(
            "a TILTSURF surface is a plane; its CURV and CONI must be 0")
    tx, ty = (s.parm.get(i, (0.0, None))[0] for i in (1, 2))
    return TiltedPlane(tan_x=_arr(tx), tan_y=_arr(ty), semi_diameter=_arr(sd))


MAX_BINARY2_TERMS = 240
"""The most phase terms a BINARY_2 holds (Zemax's extra data: 242 values, N and R first)."""

MAX_XOSPHERE_TERMS = 240
"""The most terms an extended odd asphere (XOSPHERE) holds (its extra data: 242 values, the
number of terms and the normalisation radius first)."""


def binary2(s, unit: float, sd: float) -> Binary2:
    """A ``Binary2`` from a BINARY_2 surface block (the reader's surface record)."""
    where = s.type_line or s.line
    _parms(s, range(0, 9), "BINARY_2")
    if s.glas is not None and s.glas.tokens[1].upper() == "MIRROR":
        raise s.glas.error("a BINARY_2 (diffractive) surface cannot be a mirror in jaxlens")
    xd = ExtraData(s, ("the number of terms", "the normalisation radius, lens units"))
    xd.required()
    n = xd.count(1, "phase terms", MAX_BINARY2_TERMS)
    norm, norm_line = xd.get(2)
    a_phase = xd.terms(3)
    if n and not norm > 0:
        raise norm_line.error("the normalisation radius (XDAT 2) must be > 0")
    if 0 not in s.parm and any(v != 0 for v in a_phase):
        raise where.error("this BINARY_2 surface has phase terms but no diffraction order "
                          "(PARM 0), which Zemax reads as 0 (no diffraction); add PARM 0 "
                          "(1 for the first order)")
    order = s.parm.get(0, (1.0, None))[0]
    m = max([i for i in s.parm if 1 <= i <= 8], default=0)
    a = [s.parm.get(i, (0.0, None))[0] * unit ** (1 - 2 * i) for i in range(1, m + 1)]
    return Binary2(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)),
                   order=_arr(order), norm_radius=_arr(norm * unit if norm > 0 else 1.0),
                   phase_coeffs=_arr(np.array(a_phase, np.float64)), semi_diameter=_arr(sd))


def grating(s, sd: float, unit: float) -> Grating:
    """A ``Grating`` from a DGRATING surface block (the reader's surface record): PARM 1 the
    line density (lines/µm, not scaled by the lens unit), PARM 2 the order."""
    _parms(s, range(1, 3), "DGRATING (PARM 1 = lines per µm, PARM 2 = diffraction order)")
    _no_extra_data(s, "DGRATING has no extra data (XDAT)")
    density, d_line = s.parm.get(1, (0.0, None))
    if density < 0:
        raise d_line.error(f"PARM 1 (the grating's line density, lines per µm) must be >= 0, "
                           f"got {density:g}")
    order, o_line = s.parm.get(2, (0.0, None))
    if order != round(order):
        raise o_line.error(f"PARM 2 (the grating's diffraction order) must be a whole number, "
                           f"got {order:g}")
    return Grating(c=_arr(s.curv / unit), k=_arr(s.coni), lines_per_um=_arr(density),
                   order=_arr(order), semi_diameter=_arr(sd))


def flat_phase_grid(s) -> None:
    """Check a GRID_PHA block (Zemax's grid phase: the STANDARD surface of its CURV and
    CONI plus a phase interpolated on a grid, ``GDAT nx ny dx dy …`` and one ``GARR i phase
    ∂φ/∂x ∂φ/∂y ∂²φ/∂x∂y …`` line a grid point) whose grid adds nothing: every point's
    phase and derivatives 0, as an empty spatial light modulator is saved (Zemax 5.2's
    ``START SLM (EMPTY)``, krishk97/Zemax-DLA-SLM). Its diffraction order and other
    parameters (PARM) multiply that zero phase, so the surface is its STANDARD one. A grid
    with any nonzero value, or without its GDAT line or its nx·ny points, is refused,
    naming the line: jaxlens has no grid phase to hold it."""
    where = s.type_line or s.line
    if s.gdat is None:
        raise where.error("GRID_PHA without its grid size (GDAT nx ny …): the phase grid "
                          "is not in the file")
    nx, ny = s.gdat.int(1, "GDAT grid points along x"), s.gdat.int(2, "GDAT grid points along y")
    seen = sorted(ln.int(1, "GARR grid point index") for ln in s.garr)
    if seen != list(range(nx * ny)):
        raise s.gdat.error(f"GRID_PHA's {nx} × {ny} grid needs GARR lines 0..{nx * ny - 1} once "
                           f"each, got {len(seen)} GARR lines")
    for ln in s.garr:
        vals = [ln.float(i, "GARR value") for i in range(2, min(len(ln.tokens), 6))]
        if any(v != 0 for v in vals):
            raise ln.error("GRID_PHA with a nonzero phase grid is not supported: jaxlens has "
                           "no surface whose phase is interpolated on a grid (a grid of "
                           "zeros, which adds no phase, reads as the STANDARD surface under "
                           "it)")


def toroidal(s, unit: float, sd: float) -> Toroidal:
    """A ``Toroidal`` from a TOROIDAL surface block (the reader's surface record)."""
    _parms(s, range(1, 10), "TOROIDAL")
    for i, (v, ln) in s.xdat.items():
        if i >= 3 and v != 0:
            raise ln.error("TOROIDAL Zernike terms (extra data) are not supported; jaxlens's "
                           "toroid is the conic-plus-polynomial profile only")
    cx = _x_curvature(s, unit, "TOROIDAL radius of rotation (PARM 1)")
    m = max([i - 1 for i in s.parm if 2 <= i <= 9], default=0)
    a = [s.parm.get(i + 1, (0.0, None))[0] * unit ** (1 - 2 * i) for i in range(1, m + 1)]
    return Toroidal(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)),
                    cx=_arr(cx), semi_diameter=_arr(sd))


def biconic(s, unit: float, sd: float) -> Biconic:
    """A ``Biconic`` from a BICONICX surface block (the reader's surface record)."""
    _parms(s, range(1, 3), "BICONICX (PARM 1 = x radius, PARM 2 = x conic)")
    _no_extra_data(s, "BICONICX has no extra data (XDAT): jaxlens's biconic is the two "
                      "conics (CURV/CONI in y, PARM 1/PARM 2 in x) only")
    cx = _x_curvature(s, unit, "BICONICX x radius (PARM 1)")
    return Biconic(c=_arr(s.curv / unit), k=_arr(s.coni), cx=_arr(cx),
                   kx=_arr(s.parm.get(2, (0.0, None))[0]), semi_diameter=_arr(sd))


_ZERNIKE_TYPES = {"SZERNSAG": "standard", "FZERNSAG": "fringe"}


def zernike_sag(s, unit: float, sd: float) -> ZernikeSag:
    """A ``ZernikeSag`` from an SZERNSAG or FZERNSAG surface block (the reader's record)."""
    where = s.type_line or s.line
    ordering = _ZERNIKE_TYPES[s.type]
    _parms(s, range(0, 11), f"{s.type} (PARM 0 = extrapolate, 1…8 = A2…A16, 9 and 10 = "
                            f"Zernike decenter x, y)")
    ext, ext_line = s.parm.get(0, (0.0, where))
    if ext not in (0.0, 1.0):
        raise ext_line.error(f"PARM 0 (the extrapolate flag) must be 0 (Zernike terms within "
                             f"the normalisation radius only) or 1 (everywhere), got {ext:g}")
    xd = ExtraData(s, ("the number of terms", "the Zernike normalisation radius, lens units"))
    xd.required()
    xd.count(1, "Zernike terms", MAX_ZERNIKE_TERMS[ordering], f" for {s.type}")
    zern = [v * unit for v in xd.terms(3)]
    norm = xd.radius(2, xd.header[1])
    m = max([i for i in s.parm if 1 <= i <= 8], default=0)
    a = [s.parm.get(i, (0.0, None))[0] * unit ** (1 - 2 * i) for i in range(1, m + 1)]
    dx, dy = (s.parm.get(i, (0.0, None))[0] * unit for i in (9, 10))
    return ZernikeSag(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)),
                      zernike=_arr(np.array(zern, np.float64)), norm_radius=_arr(norm * unit),
                      decenter_x=_arr(dx), decenter_y=_arr(dy), semi_diameter=_arr(sd),
                      ordering=ordering, extrapolate=ext == 1.0)


MAX_QTYPE_TERMS = 240
"""The most Q-type (QED_TYPE) terms jaxlens reads or writes."""

_QTYPE_KINDS = {0.0: "bfs", 1.0: "con"}


def qtype_asphere(s, unit: float, sd: float) -> QTypeAsphere:
    """A ``QTypeAsphere`` from a QED_TYPE surface block (the reader's surface record)."""
    for _, (v, ln) in sorted(s.parm.items()):
        if v != 0:
            raise ln.error("QED_TYPE has no parameters (PARM); its data are extra data (XDAT 1 "
                           "= type, 2 = number of terms, 3 = normalisation radius, 4… = terms)")
    xd = ExtraData(s, ("the polynomial type: 0 Q-bfs, 1 Q-con", "the number of terms",
                       "the normalisation radius, lens units"))
    kind, kind_line = xd.required()[0]
    if kind not in _QTYPE_KINDS:
        raise kind_line.error(f"XDAT 1 (the Q-type polynomial type) must be 0 (Q-bfs) or 1 "
                              f"(Q-con), got {kind:g}")
    xd.count(2, "Q-type terms", MAX_QTYPE_TERMS)
    norm = xd.radius(3)
    a = [v * unit for v in xd.terms(4)]
    return QTypeAsphere(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)),
                        norm_radius=_arr(norm * unit), semi_diameter=_arr(sd),
                        qtype=_QTYPE_KINDS[kind])


def xy_polynomial(s, unit: float, sd: float) -> XYPolynomial:
    """An ``XYPolynomial`` from an XPOLYNOM surface block (the reader's surface record)."""
    for _, (v, ln) in sorted(s.parm.items()):
        if v != 0:
            raise ln.error("XPOLYNOM has no parameters (PARM); its data are extra data (XDAT 1 "
                           "= number of terms, 2 = normalisation radius, 3… = coefficients)")
    _, norm, a = normalised_terms(s, "extended-polynomial terms", MAX_XY_TERMS, " (degree 20)")
    a = [v * unit for v in a]
    return XYPolynomial(c=_arr(s.curv / unit), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)),
                        norm_radius=_arr(norm * unit), semi_diameter=_arr(sd))


def paraxial_surface(s, unit: float, sd: float) -> tuple[ParaxialSurface, int | None]:
    """(``ParaxialSurface``, OPD mode or None when the file gives none) from a PARAXIAL block."""
    where = s.type_line or s.line
    _parms(s, range(1, 3), "PARAXIAL")
    if s.curv != 0 or s.coni != 0:
        raise where.error("a PARAXIAL surface is flat; its CURV and CONI must be 0")
    if 1 not in s.parm or s.parm[1][0] == 0:
        raise (s.parm.get(1, (0, where))[1]).error(
            "a PARAXIAL surface needs a nonzero focal length (PARM 1)")
    try:  # on PARM 1's line (ParaxialSurface named the TYPE line)
        reciprocal_length(s.parm[1][0] * unit, "the PARAXIAL focal length (PARM 1)", "")
    except ValueError as e:
        raise s.parm[1][1].error(str(e)) from None
    mode = None
    if 2 in s.parm:
        v, ln = s.parm[2]
        if v not in OPD_MODES:
            raise ln.error(f"PARAXIAL OPD mode (PARM 2) must be 0, 1, 2 or 3, got {v:g}")
        mode = int(v)
    return ParaxialSurface(focal_length=_arr(s.parm[1][0] * unit), semi_diameter=_arr(sd)), mode


OPD_MODE_TOLERANCE_WAVES = 0.01
"""Largest optical-path error (peak to valley over the surface, in waves at each of the
file's wavelengths) accepted, with a warning, where a PARAXIAL surface in OPD mode 0 or 3
(or none) meets a beam that is not collimated (``check_opd_modes``)."""


def check_opd_modes(lens: Lens, modes: dict, *, strict: bool = False) -> None:
    """Check each PARAXIAL surface's OPD mode against jaxlens's optical path (mode 2's).

    Mode 2, and any mode where the beam reaching the surface is collimated, give jaxlens's
    path. Modes 0 and 3 (no PARM 2 is mode 0) make the lens perfect between the conjugates
    of the beam that reaches it; where that beam is not collimated, the difference to
    jaxlens's path (``opd_mode_error``) is accepted when it is at most
    ``OPD_MODE_TOLERANCE_WAVES`` at every wavelength (a warning; an error under
    ``strict``) and refused above it, or where it cannot be bounded. Mode 1 (integrated
    phase) is refused for a beam that is not collimated.

    Args:
        lens: the lens read from the file.
        modes: surface index (0-based) -> (OPD mode or None, the line to name) or (mode,
            line, the surface's DIAM in mm): the beam's radius where the surface does not
            clip (OpticStudio's automatic DIAM is the file's beam footprint there).
        strict: an error instead of a warning for an accepted difference.
    """
    for i, (mode, ln, *diam) in modes.items():
        if mode == 2:
            continue
        why = _not_collimated(lens, i)
        if not why:
            continue
        named = "no OPD mode (Zemax's default, mode 0)" if mode is None else \
            f"OPD mode {mode} ({OPD_MODES[mode]})"
        error, cannot = (None, "the mode integrates the surface's phase") if mode == 1 else \
            opd_mode_error(lens, i, beam_radius=diam[0] if diam else math.inf)
        head = (f"this PARAXIAL surface has {named}, which computes the optical path from the "
                f"conjugates it is used at, and {why}; jaxlens computes the path of a perfect "
                f"lens at infinite conjugates (OPD mode 2, PARM 2 2)")
        if error is not None and error <= OPD_MODE_TOLERANCE_WAVES:
            report(strict, f"{ln.path}:{ln.number}: {head}: the two paths differ by at most "
                           f"{error:.2g} waves (peak to valley over the surface's "
                           f"semi-diameter, below the {OPD_MODE_TOLERANCE_WAVES:g} waves "
                           f"that a lenient read accepts); the rays are the same in every "
                           f"mode: "
                           f"{ln.text.strip()!r}")
            continue
        size = (f"the two paths differ by {error:.3g} waves (peak to valley over the "
                f"surface's semi-diameter; {OPD_MODE_TOLERANCE_WAVES:g} waves are accepted)"
                if error is not None else f"the difference cannot be bounded ({cannot})")
        raise ln.error(f"{head}, and {size}. Set PARM 2 to 2 to accept jaxlens's path (the "
                       f"rays are the same in every mode)")


def opd_mode_error(lens: Lens, i: int, *, beam_radius: float = math.inf
                   ) -> tuple[float | None, str]:
    """(The largest difference, in waves, between jaxlens's optical path at PARAXIAL surface
    i and the path of OPD modes 0 and 3, or None; why it is None).

    Modes 0 and 3 add the path φ₀(Q) = C + sgn(z_O)·n·|Q − O| − sgn(z_I)·n′·|I − Q| at the
    point of incidence Q, which makes every ray from the conjugate object point O meet the
    paraxial image point I with the same optical path (z_O, z_I from the surface, + after
    it; a real object lies before it). jaxlens adds the infinite-conjugate path φ(Q, d̂) of
    ``tracing.step.paraxial_bend`` for the ray's own direction d̂. O is found paraxially:
    for an object at infinity and the system matrix (A, B; C, D) up to the surface,
    z_O = −n·A/C and, for a field of reduced slope nu₀, height (B + z_O·D/n)·nu₀. The
    difference, less its value at the vertex, is taken over a grid on the disc of the
    surface's semi-diameter (where it is infinite: ``beam_radius``, mm), for the axis and
    every field of the lens (angles), in the y–z and the x–z section and at every
    wavelength; its peak to valley, in waves, is returned.
    None where the object is at a finite distance, a mirror precedes the surface, or the
    surface has no finite semi-diameter and no finite ``beam_radius``.
    """
    if not lens.object_at_infinity:
        return None, "the object is at a finite distance"
    if any(m < i for m in lens.mirrors):
        return None, "a mirror precedes the surface"
    surf = lens.surfaces[i]
    r = float(surf.semi_diameter)
    r = r if math.isfinite(r) else float(beam_radius)
    if not (math.isfinite(r) and r > 0):
        return None, "no finite semi-diameter bounds the beam on the surface"
    f = float(surf.focal_length)
    g = np.linspace(-r, r, 41)
    qx, qy = (a.ravel() for a in np.meshgrid(g, g))
    keep = qx * qx + qy * qy <= r * r
    qx, qy = qx[keep], qy[keep]
    fields = np.tan(np.deg2rad(np.asarray(lens.fields, np.float64)))
    tans = np.append(np.hypot(*fields.T) if fields.ndim == 2 else np.abs(fields), 0.0)
    worst = 0.0
    for section in (lens, paraxial.x_section(lens)):
        for wl in np.atleast_1d(np.asarray(lens.wavelengths, np.float64)):
            n = paraxial.signed_indices(section, wl)
            n0, n1, n2 = float(n[0]), float(n[i]), float(n[i + 1])
            a, b, c, d = (float(v) for v in paraxial.system_matrix(section, wl, 0, i - 1))
            if c == 0.0:
                continue  # collimated in this section: the same path
            t = float(section.thickness[i - 1]) / n1
            a, b = a + t * c, b + t * d
            if a == 0.0:
                return None, "the beam's conjugate point lies on the surface"
            z_o = -n1 * a / c
            for tan in tans:
                h_o = (b + z_o * d / n1) * n0 * tan
                pv = _path_difference(qx, qy, f, n1, n2, z_o, h_o)
                if not math.isfinite(pv):  # max(0.0, nan) is 0.0: "at most 0 waves"
                    return None, (f"the path difference is {pv:g} mm (a conjugate point at "
                                  f"z = {z_o:.6g} mm from the surface)")
                worst = max(worst, pv / (wl * 1e-3))
    return worst, ""


def _path_difference(qx, qy, f, n1, n2, z_o, h_o) -> float:
    """Peak to valley (mm) of jaxlens's path minus the conjugate path φ₀ over the points
    (qx, qy) of the surface, for the object point (0, h_o, z_o) (``opd_mode_error``)."""
    from ..tracing.step import paraxial_bend  # the ideal lens's path, as traced

    vz = z_o if z_o != 0 else 1.0
    # The image of O: n′/z_I = n/z_O + 1/f (reduced vergences), at height z_I·n·h_O/(z_O·n′).
    z_i = n2 / (n1 / z_o + 1.0 / f)
    h_i = z_i * n1 * h_o / (vz * n2)
    pts = np.stack([qx, qy, np.zeros_like(qx)])
    obj = np.array([0.0, h_o, z_o])[:, None]
    img = np.array([0.0, h_i, z_i])[:, None]
    to_q = (pts - obj) * -np.sign(z_o)  # along the ray, toward +z
    d = to_q / np.linalg.norm(to_q, axis=0)
    _, _, path = paraxial_bend(tuple(d), qx, qy, f, n1, n2)
    # φ₀(Q) − φ₀(0) as sgn(z_O)·n·(|Q − O| − |O|) − sgn(z_I)·n′·(|I − Q| − |I|), each
    # difference of lengths taken as (|Q|² − 2 Q·P)/(|Q − P| + |P|): subtracted as written, a
    # conjugate 5e10 mm away (a beam collimated to 1e-9) left 0.015 waves of rounding.
    conj = (np.sign(z_o) * n1 * _length_change(pts, obj)
            - np.sign(z_i) * n2 * _length_change(pts, img))
    diff = np.asarray(path) - conj
    return float(diff.max() - diff.min())


def _length_change(q, p):
    """|q − p| − |p| for the points q (``[3, N]``) and the point p (``[3, 1]``), without the
    cancellation of the two lengths' subtraction."""
    return (np.sum(q * q, axis=0) - 2.0 * np.sum(q * p, axis=0)) / (
        np.linalg.norm(q - p, axis=0) + np.linalg.norm(p))


def _not_collimated(lens: Lens, i: int) -> str:
    """Why the beam that reaches surface i is not collimated ('' if it is)."""
    if lens.object_at_infinity is False:
        return "the object is at a finite distance"
    if i == 0:
        return ""
    f = abs(float(lens.surfaces[i].focal_length))
    for section, name in ((lens, "y–z"), (paraxial.x_section(lens), "x–z")):
        for wl in np.atleast_1d(np.asarray(lens.wavelengths)):
            _, _, c, _ = paraxial.system_matrix(section, wl, 0, i - 1)
            if not abs(float(c)) * f <= COLLIMATED:
                return (f"the surfaces before it have power {float(-c):.6g}/mm in the {name} "
                        f"section at {float(wl):g} µm (the beam reaching it is not collimated)")
    return ""


def radius_text(cx: float) -> str:
    """PARM 1 for the curvature of rotation cx: 1/cx to 25 significant digits ("0" for a
    cylinder). ``toroidal`` reads it back as the correctly rounded 1/R, which is cx bit for
    bit (a double R would not do: about one double in ten is no double's reciprocal)."""
    if cx == 0:
        return "0"
    short = np.format_float_scientific(1.0 / cx, unique=True, exp_digits=3, trim="0").upper()
    if curvature_of_rotation(short, 1.0) == cx:
        return short  # the shortest form of the double 1/cx reads back exactly (most cases)
    with decimal.localcontext() as ctx:
        ctx.prec = 25
        r = decimal.Decimal(1) / decimal.Decimal(cx)
    return f"{r.normalize():E}"


def _x_curvature(s, unit: float, what: str) -> float:
    """The x curvature (1/mm) of PARM 1's radius: 0 for R = 0 (flat in x, as Zemax reads
    it); a radius below ``reciprocal.MIN_LENGTH_MM`` refused on its line (1e-300 gave
    1e300 per mm, 5e-324 an overflow named after the surface's coefficients)."""
    if 1 not in s.parm:
        return 0.0
    v, ln = s.parm[1]
    if v != 0:
        try:
            reciprocal_length(v * unit, what, "")
        except ValueError as e:
            raise ln.error(str(e)) from None
    return curvature_of_rotation(ln.tokens[2], unit)


def curvature_of_rotation(token: str, unit: float) -> float:
    """1/(R·unit) correctly rounded from PARM 1's text (0 for R = 0)."""
    r = fractions.Fraction(token.replace("D", "E").replace("d", "e")) * fractions.Fraction(unit)
    return 0.0 if r == 0 else float(1 / r)


def surface_lines(s, z) -> list[str] | None:
    """The TYPE/CURV/CONI/PARM (and XDAT) lines of a ``Toroidal``, ``ParaxialSurface``,
    ``Binary2``, ``QTypeAsphere``, ``Biconic``, ``ZernikeSag``, ``XYPolynomial`` or
    ``Grating`` (None for other kinds); ``z`` formats a number exactly."""
    if isinstance(s, Toroidal):
        a = [float(v) for v in np.asarray(s.coeffs)]
        if len(a) > 8:
            raise ValueError(f"save_zmx: a Toroidal surface has {len(a)} profile coefficients; "
                             f"Zemax's TOROIDAL holds 8 (y² … y¹⁶)")
        out = ["TYPE TOROIDAL", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
               f"PARM 1 {radius_text(float(s.cx))}"]
        return out + [f"PARM {i + 1} {z(v)}" for i, v in enumerate(a, start=1)]
    if isinstance(s, ParaxialSurface):
        return ["TYPE PARAXIAL", 'CURV 0 0 0 0 0 ""', f"PARM 1 {z(s.focal_length)}", "PARM 2 2"]
    if isinstance(s, Binary2):
        return _binary2_lines(s, z)
    if isinstance(s, QTypeAsphere):
        return _qtype_lines(s, z)
    if isinstance(s, Biconic):
        return ["TYPE BICONICX", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
                f"PARM 1 {radius_text(float(s.cx))}", f"PARM 2 {z(s.kx)}"]
    if isinstance(s, ZernikeSag):
        return _zernike_lines(s, z)
    if isinstance(s, XYPolynomial):
        return _xy_polynomial_lines(s, z)
    if isinstance(s, Grating):
        return ["TYPE DGRATING", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
                f"PARM 1 {z(s.lines_per_um)}", f"PARM 2 {z(s.order)}"]
    return None


def _xy_polynomial_lines(s: XYPolynomial, z) -> list[str]:
    a = [float(v) for v in np.asarray(s.coeffs)]
    out = ["TYPE XPOLYNOM", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
           f'XDAT 1 {len(a)} 0 0 1 0 0 ""', f'XDAT 2 {z(s.norm_radius)} 0 0 1 0 0 ""']
    return out + [f'XDAT {i + 2} {z(v)} 0 0 1 0 0 ""' for i, v in enumerate(a, start=1)]


def _zernike_lines(s: ZernikeSag, z) -> list[str]:
    a = [float(v) for v in np.asarray(s.coeffs)]
    if len(a) > 8:
        raise ValueError(f"save_zmx: a ZernikeSag has {len(a)} even-asphere coefficients; "
                         f"Zemax's Zernike sag surfaces hold 8 (r² … r¹⁶)")
    kind = {v: k for k, v in _ZERNIKE_TYPES.items()}[s.ordering]
    zern = [float(v) for v in np.asarray(s.zernike)]
    out = [f"TYPE {kind}", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
           f"PARM 0 {int(s.extrapolate)}"]
    out += [f"PARM {i} {z(v)}" for i, v in enumerate(a, start=1)]
    out += [f"PARM 9 {z(s.decenter_x)}", f"PARM 10 {z(s.decenter_y)}",
            f'XDAT 1 {len(zern)} 0 0 1 0 0 ""', f'XDAT 2 {z(s.norm_radius)} 0 0 1 0 0 ""']
    return out + [f'XDAT {j + 2} {z(v)} 0 0 1 0 0 ""' for j, v in enumerate(zern, start=1)]


def _qtype_lines(s: QTypeAsphere, z) -> list[str]:
    a = [float(v) for v in np.asarray(s.coeffs)]
    if len(a) > MAX_QTYPE_TERMS:
        raise ValueError(f"save_zmx: a QTypeAsphere has {len(a)} terms; jaxlens writes at most "
                         f"{MAX_QTYPE_TERMS}")
    kind = {v: k for k, v in _QTYPE_KINDS.items()}[s.qtype]
    out = ["TYPE QED_TYPE", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
           f'XDAT 1 {int(kind)} 0 0 1 0 0 ""', f'XDAT 2 {len(a)} 0 0 1 0 0 ""',
           f'XDAT 3 {z(s.norm_radius)} 0 0 1 0 0 ""']
    return out + [f'XDAT {i + 4} {z(v)} 0 0 1 0 0 ""' for i, v in enumerate(a)]


def _binary2_lines(s: Binary2, z) -> list[str]:
    a = [float(v) for v in np.asarray(s.coeffs)]
    ph = [float(v) for v in np.asarray(s.phase_coeffs)]
    if len(a) > 8 or len(ph) > MAX_BINARY2_TERMS:
        raise ValueError(f"save_zmx: a Binary2 surface has {len(a)} asphere and {len(ph)} phase "
                         f"coefficients; Zemax's BINARY_2 holds 8 (r² … r¹⁶) and "
                         f"{MAX_BINARY2_TERMS}")
    out = ["TYPE BINARY_2", f'CURV {z(s.c)} 0 0 0 0 ""', f"CONI {z(s.k)}",
           f"PARM 0 {z(s.order)}"]
    out += [f"PARM {i} {z(v)}" for i, v in enumerate(a, start=1)]
    out += [f'XDAT 1 {len(ph)} 0 0 1 0 0 ""', f'XDAT 2 {z(s.norm_radius)} 0 0 1 0 0 ""']
    return out + [f'XDAT {i + 2} {z(v)} 0 0 1 0 0 ""' for i, v in enumerate(ph, start=1)]


def sensor(img, unit: float) -> Sensor | None:
    """The sensor recorded in the image surface's comment by ``save_zmx``, if any."""
    hit = SENSOR_COMMENT.search(img.comment)
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


def check_object_plane(obj, distance: float) -> None:
    """Refuse a finite object whose surface is not a plane normal to the axis (a curved
    object, a TILTSURF's tilted plane, aspheric terms): a jaxlens object is such a plane, and
    reading the file as one would move its object points. At infinity the shape is moot."""
    if math.isinf(distance):
        return
    where = obj.type_line or obj.line
    # Under an explicit TYPE STANDARD, PARM and XDAT values are unused (as in Zemax).
    unused = obj.type == "STANDARD" and obj.type_line is not None
    terms = [] if unused else [ln for _, (v, ln) in sorted(obj.parm.items())
                               + sorted(obj.xdat.items()) if v != 0]
    plane_types = ("STANDARD", "EVENASPH", "ODDASPHE", "TILTSURF")  # planes without terms
    if obj.type not in plane_types or obj.curv != 0 or terms:
        what = (f"TYPE {obj.type}" if obj.type not in plane_types
                else f"CURV {obj.curv:g}" if obj.curv != 0 else " ".join(terms[0].tokens[:3]))
        at = obj.curv_line if obj.curv != 0 else terms[0] if terms else where
        raise at.error(
            f"the object surface at a finite distance must be a plane normal to the axis "
            f"(CURV 0, no tilt or terms); it has {what}, which jaxlens cannot represent: its "
            f"points off the axis lie off the vertex plane (for a TILTSURF z = tan θx·x + "
            f"tan θy·y, PARM 1 and 2), while a jaxlens Lens puts every object point on one "
            f"plane normal to the axis, object_distance before surface 1, so each off-axis "
            f"field would be imaged from the wrong distance")
