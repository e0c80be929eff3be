"""Multi-configuration ``.zmx`` files (zoom positions, focus positions, …): choosing one.

Format, as OpticStudio writes it (and as ``xzos/PyZDDE`` issue #61 and the corpus files show):
``MNUM n [active]`` gives the number of configurations and the one active when the file was
saved. Older files (Zemax 2006, ``VERS 60801``) write ``MNUM n`` alone, with the surfaces
holding whichever configuration was active: there the active one is the configuration whose
``THIC``, ``CRVT`` and ``CONN`` rows all equal what the surfaces hold (1 where it does, or
where no single configuration does, as before). After it, one line per operand and configuration::

    THIC   5   2 42.97 0 0 0 1 1 1 0 0        # operand, param, configuration, value, …

``param`` is the operand's first number (a surface for ``THIC``, a field for ``YFIE``, 0 for
``APER``), ``configuration`` counts from 1 and ``value`` is the operand's value in that
configuration (lens units for lengths). The surfaces of the file hold the active
configuration, so reading it needs none of these lines; another configuration is the
surfaces with its operands' values put in their place.

Applied (lengths in the file's lens units, as on the surfaces): ``THIC`` (surface thickness,
``DISZ``), ``CRVT`` (curvature), ``CONN`` (conic), ``GLSS`` (glass by name; ``""`` is air),
``SDIA`` (semi-diameter, where it clips: a fixed ``DIAM``), ``APER`` (the system aperture
value, in the meaning of the file's ``ENPD``/``FNUM``/``OBNA`` line), ``WAVE`` (wavelength
n, µm), ``XFIE``/``YFIE`` (field n), ``STPS`` (the stop surface), Zemax 2006's ``PARn``
(``PARM n`` of the surface; ``zmx_keywords.PARAMETER_OPERAND``), after which the parameter
pickups (``PPAR``), curvature pickups (``CURV c 4 src scale``) and thickness pickups
(``PZUP``) whose source the configuration changed are solved again, in surface order (the
surfaces hold the solution for the saved configuration only). Ignored: ``MOFF`` (an unused
row), ``LTTL`` and ``MCOM`` (titles, comments), and the weights ``FLWT``/``WLWT`` (a
``Lens`` holds none; a warning where they change). The vignetting factors ``FVDX``,
``FVDY``, ``FVCX``, ``FVCY``, ``FVAN`` of field n replace that field's value on the file's
``VDXN`` … ``VANN`` lines (``Lens.vignetting``). The environment rows ``TEMP`` (°C) and
``PRES`` (atm) read where they equal the file's environment (``ENVD``; without it Zemax's
20 °C and 1 atm) and are refused, naming the line, where they differ (for the active
configuration too): another temperature changes every index (the glasses' and the air's;
the geometry of thermal pickups is in the configuration's own THIC and CRVT rows). Any
other operand whose value in the chosen configuration differs from the active one's
(``PRAM``, …) is refused, naming the line: the lens would silently be another one.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from .zmx_common import ZmxWarning, report
from .zmx_keywords import PARAMETER_OPERAND
from .zmx_parse import ZmxFile, ZmxLine

NO_OPTICS = frozenset({"MOFF", "LTTL", "MCOM"})
"""Operands that change nothing the lens holds (an unused row, a title, a comment)."""
WEIGHTS = frozenset({"FLWT", "WLWT"})
VIGNETTING = {"FVDX": "VDXN", "FVDY": "VDYN", "FVCX": "VCXN", "FVCY": "VCYN", "FVAN": "VANN"}
"""Configuration operand -> the file's line of that vignetting factor (one value a field)."""
REASONS = {
    "PRAM": "a surface parameter (PARM); jaxlens does not know where its line gives the "
            "parameter number",
}
ENVIRONMENT = {"TEMP": (1, "°C", 20.0), "PRES": (2, "atm", 1.0)}
"""Environment operand -> (its value's place on the ENVD line, unit, Zemax's default where the
file has no ENVD line)."""
_OBJECT_INFINITY = 1e10  # lens units; Zemax writes an infinite object distance so in THIC


@dataclasses.dataclass(frozen=True)
class Operand:
    """One multi-configuration operand: its name, first number and value per configuration
    (the value's text and the line)."""

    name: str
    param: int
    values: dict


def counts(f: ZmxFile) -> tuple[int, int]:
    """(number of configurations, the active one, 1-based) of a file; (1, 1) without MNUM."""
    if f.mnum is None:
        return 1, 1
    n = f.mnum.int(1, "number of configurations (MNUM)", lo=1)
    if len(f.mnum.tokens) <= 2:
        return n, _held_configuration(f, n)
    active = f.mnum.int(2, "active configuration (MNUM's second value)")
    if not 1 <= active <= n:
        raise f.mnum.error(f"the active configuration must be 1..{n}, got {active}")
    return n, active


def _held_configuration(f: ZmxFile, n: int) -> int:
    """The configuration the surfaces hold, for an ``MNUM n`` that names none: 1 where its
    THIC, CRVT and CONN rows match the surfaces (or no configuration's do, or the table is
    malformed: ``select`` then reports it), else the one configuration whose rows all do."""
    if n == 1:
        return 1
    try:
        ops = [op for op in operands(f, n) if _held(op.name)]
        held = [c for c in range(1, n + 1) if all(_holds(f, op, c) for op in ops)]
    except ValueError:
        return 1
    return held[0] if len(held) == 1 and ops else 1


_HELD = ("THIC", "CRVT", "CONN")


def _held(name: str) -> bool:
    return name in _HELD or PARAMETER_OPERAND.fullmatch(name) is not None


def _holds(f: ZmxFile, op: Operand, c: int) -> bool:
    """Whether the surfaces hold configuration c's value of a THIC, CRVT or CONN row (a
    configuration without a row for it holds whatever the surfaces do)."""
    if c not in op.values:
        return True
    value, ln = op.values[c]
    v = _number(value, ln)
    s = _surface(f, op, ln)
    m = PARAMETER_OPERAND.fullmatch(op.name)
    if m:
        have = s.parm.get(int(m.group(1)), (0.0, None))[0]
        return math.isclose(v, have, rel_tol=1e-9, abs_tol=1e-12)
    have = {"THIC": s.disz, "CRVT": s.curv, "CONN": s.coni}[op.name]
    if op.name == "THIC" and op.param == 0 and v >= _OBJECT_INFINITY and math.isinf(have):
        return True
    return math.isclose(v, have, rel_tol=1e-9, abs_tol=1e-12)


def operands(f: ZmxFile, n: int) -> list[Operand]:
    """The operand lines after MNUM, one ``Operand`` per (name, param); malformed lines raise
    ``ValueError`` naming the line."""
    table: dict = {}
    for ln in f.config_lines:
        if len(ln.tokens) < 4 and ln.tokens[0] not in NO_OPTICS:
            raise ln.error("a configuration operand line needs the operand, its number, the "
                           "configuration and the value")
        param = ln.int(1, f"{ln.tokens[0]}'s number")
        cfg = ln.int(2, "configuration number")
        if not 1 <= cfg <= n:
            raise ln.error(f"configuration number must be 1..{n} (MNUM), got {cfg}")
        value = ln.tokens[3] if len(ln.tokens) > 3 else ""
        op = table.setdefault((ln.tokens[0], param), Operand(ln.tokens[0], param, {}))
        if cfg in op.values and ln.tokens[0] not in NO_OPTICS:
            # The later line silently won: which of two values Zemax holds is not known.
            first = op.values[cfg][1]
            raise ln.error(f"a second {ln.tokens[0]} {param} line for configuration {cfg} "
                           f"(the first is line {first.number}); each operand has one value "
                           f"per configuration")
        op.values[cfg] = (value, ln)
    return list(table.values())


def describe(f: ZmxFile) -> dict:
    """The configurations of a parsed file: ``count``, ``active`` and ``operands``, a list of
    ``{"operand", "param", "values"}`` with one value text per configuration (``None``
    where the file has no line)."""
    n, active = counts(f)
    ops = operands(f, n) if n > 1 or f.config_lines else []
    return {"count": n, "active": active, "operands": [
        {"operand": op.name, "param": op.param,
         "values": [op.values.get(c, (None, None))[0] for c in range(1, n + 1)]}
        for op in ops if op.name not in NO_OPTICS]}


def select(f: ZmxFile, config: int | None, strict: bool) -> int:
    """Make ``f`` configuration ``config`` (1-based; ``None``: the active one), in place;
    returns the configuration read.

    Raises:
        ValueError: ``config`` outside 1..N, a malformed operand line (for the active
            configuration: a ``ZmxWarning``, an error under ``strict``), or an operand of
            configuration ``config`` that jaxlens cannot apply (the message names the line).
    """
    if config is not None and (isinstance(config, bool | np.bool_)
                               or not isinstance(config, int | np.integer)):
        raise ValueError(f"{f.path}: config must be a whole configuration number (1-based), "
                         f"got {config!r}")
    config = None if config is None else int(config)  # np.int64(2), as from np.arange, is 2
    n, active = counts(f)
    if config is not None and not 1 <= config <= n:
        have = "one configuration" if n == 1 else f"configurations 1..{n}"
        raise ValueError(f"{f.path}: config must be one of the file's {have} (Zemax's "
                         f"numbering, from 1), got {config}")
    chosen = active if config is None else config
    if n == 1 and (f.mnum is None or not f.config_lines):
        return chosen
    try:
        ops = operands(f, n)
        _numbers(ops)
    except ValueError as e:
        if chosen != active:
            raise
        # MNUM 1 with rows for configuration 2 and on (an MNUM count cut short) was read
        # without a word, while configurations() refused the same file.
        what = (f"a multi-configuration file ({n} configurations)" if n > 1
                else "a file of 1 configuration (MNUM)")
        report(strict, f"{f.path}:{f.mnum.number}: {what} whose operand table jaxlens cannot "
                       f"read ({e}); it reads the lens as its surfaces give it (configuration "
                       f"{active}, the active one)")
        return chosen
    if chosen == active:  # the surfaces hold it; with one configuration its rows repeat them
        _check_active(f, ops, active, strict)
        return chosen
    changed: set = set()  # surfaces whose parameters this configuration sets
    curved: set = set()  # surfaces whose curvature it sets (CRVT)
    thick: set = set()  # surfaces whose thickness it sets (THIC)
    for op in ops:
        if op.name in NO_OPTICS:
            continue
        if chosen not in op.values:
            ln = next(iter(op.values.values()))[1]
            raise ln.error(f"{op.name} {op.param} has no line for configuration {chosen}")
        value, ln = op.values[chosen]
        if op.name in _APPLY:
            _APPLY[op.name](f, op, value, ln, active)
            if op.name == "CRVT":
                curved.add(op.param)
            elif op.name == "THIC":
                thick.add(op.param)
            continue
        if PARAMETER_OPERAND.fullmatch(op.name):
            _parameter(f, op, value, ln)
            changed.add(op.param)
            continue
        if op.name in ENVIRONMENT:
            _environment(f, op, value, ln, chosen)
            continue
        before = op.values.get(active, (None, None))[0]
        if before is not None and _same(value, before):
            continue
        if op.name in WEIGHTS:
            warnings.warn(f"{ln.path}:{ln.number}: configuration {chosen} weighs its "
                          f"{'fields' if op.name == 'FLWT' else 'wavelengths'} otherwise "
                          f"({op.name} {op.param}: {value}); a jaxlens Lens holds no weights",
                          ZmxWarning, stacklevel=4)
            continue
        if op.name == "PRAM" and _grid_phase(f, op.param):
            continue  # a grid phase's parameters shape only its phase, read only when 0
        what = REASONS.get(op.name, "an operand jaxlens does not apply")
        raise ln.error(f"configuration {chosen} sets {op.name} {op.param} to {value} "
                       f"(configuration {active}, the surfaces': {before}); {op.name} is "
                       f"{what}, so jaxlens cannot read configuration {chosen}")
    _parameter_pickups(f, changed)
    _curvature_pickups(f, curved)
    _thickness_pickups(f, thick)
    return chosen


def _grid_phase(f: ZmxFile, number: int) -> bool:
    """Whether surface ``number`` is a GRID_PHA. The reader takes one only where its phase
    grid is all 0 (zmx_surfaces.flat_phase_grid; any other is refused), and a grid phase's
    parameters (its diffraction order and the like) act on that phase alone, not on the
    STANDARD shape under it (CURV, CONI), so a ``PRAM`` row of one changes nothing the lens
    holds, whichever parameter it sets (Zemax 5.2's empty SLM, krishk97/Zemax-DLA-SLM, flips
    its order between -1 and 0 across configurations)."""
    return 0 <= number < len(f.surfs) and f.surfs[number].type == "GRID_PHA"


def nominal_environment(f: ZmxFile, name: str) -> float:
    """The file's temperature (°C, ``name`` ``"TEMP"``) or pressure (atm, ``"PRES"``): its
    ENVD line's, else Zemax's default (20 °C, 1 atm)."""
    place, _, default = ENVIRONMENT[name]
    ln = f.envd
    if ln is None or len(ln.tokens) <= place:
        return default
    return ln.float(place, "temperature (°C)" if name == "TEMP" else "pressure (atm)")


def _environment(f: ZmxFile, op: Operand, value: str, ln: ZmxLine, chosen: int) -> None:
    """A ``TEMP`` or ``PRES`` row of configuration ``chosen``: the configuration's
    temperature (°C) or air pressure (atm). Equal to the file's environment (``ENVD``, whose
    indices ``zmx_system.environment`` checks) it is that lens and reads so, whatever other
    configurations hold; another value would change every index (dn/dT, the air's index),
    which jaxlens does not model: refused with
    the line (also for the active configuration, which the surfaces hold, where the row
    and ENVD disagree)."""
    v = _number(value, ln)
    nominal = nominal_environment(f, op.name)
    if math.isclose(v, nominal, rel_tol=1e-12, abs_tol=1e-12):
        return
    _, unit, _ = ENVIRONMENT[op.name]
    where = (f"the file's ENVD gives {nominal:g} {unit}" if f.envd is not None else
             f"the file has no ENVD line: {nominal:g} {unit}, Zemax's default")
    what = "temperature" if op.name == "TEMP" else "air pressure"
    raise ln.error(f"configuration {chosen} sets {op.name} {op.param} to {value} (the {what}, "
                   f"{unit}), but {where}; another {what} changes every index (the "
                   f"glasses' and the air's), which jaxlens does not model, so it cannot read "
                   f"configuration {chosen} (configurations at the file's {what} read)")


def _curvature_source(ln: ZmxLine | None) -> int | None:
    """The source surface of a curvature pickup (``CURV c 4 src scale …``: solve type 4),
    else ``None``."""
    if ln is None or len(ln.tokens) < 5:
        return None
    try:
        solve = float(ln.tokens[2])
    except ValueError:
        return None
    return ln.int(3, "curvature pickup's source surface", lo=0) if solve == 4 else None


def _pickups(f: ZmxFile) -> list[tuple[str, int, int, ZmxLine]]:
    """Every pickup of the file: (what it sets, its surface, the source surface, its line);
    ``what`` names the quantity ("thickness", "curvature", "PARM n")."""
    out = []
    for s in f.surfs:
        if s.pzup is not None:
            out.append(("thickness", s.number, s.pzup.int(1, "PZUP source surface", lo=0),
                        s.pzup))
        src = _curvature_source(s.curv_line)
        if src is not None:
            out.append(("curvature", s.number, src, s.curv_line))
        for n, ln in sorted(s.ppar.items()):
            out.append((f"PARM {n}", s.number, ln.int(2, "PPAR source surface", lo=0), ln))
    return out


_PICKUP_NAMES = {"thickness": "thickness pickup (PZUP)", "curvature": "curvature pickup (CURV "
                 "solve 4)"}


def check_pickups(f: ZmxFile) -> None:
    """Refuse, naming the line, a pickup (``PZUP``, ``PPAR``, a ``CURV`` pickup solve) whose
    source is a surface the file lacks, its own surface, or a later surface whose same value
    is itself a pickup: pickups are solved in surface order, so that one would read the
    value before its own solve (a stale one, the previous configuration's). Before, the
    file's solved value was read without a word, and a configuration changing the source
    kept the file's value (surface 40, its own) or read the stale one."""
    last = len(f.surfs) - 1
    picked = {(what, number): ln for what, number, _, ln in _pickups(f)}
    for what, number, src, ln in _pickups(f):
        name = _PICKUP_NAMES.get(what, f"parameter pickup (PPAR {what.split()[-1]})")
        if src > last:
            raise ln.error(f"{name} of surface {number} reads surface {src}, which the file "
                           f"does not have (surfaces 0..{last})")
        if src == number:
            raise ln.error(f"{name} of surface {number} reads its own surface; a pickup "
                           f"copies another surface's value")
        if src > number and (what, src) in picked:
            raise ln.error(f"{name} of surface {number} reads surface {src}, whose {what} "
                           f"is itself a pickup solved after surface {number}'s (line "
                           f"{picked[what, src].number}; pickups are solved in surface order): "
                           f"it would read a value not yet solved")


def _thickness_pickups(f: ZmxFile, thick: set) -> None:
    """Re-solve the thickness pickups (``PZUP src scale offset …``) of surfaces whose source
    this configuration gave another thickness (``THIC``), in surface order. Only the plain
    copy (scale 1, offset 0, the one layout seen in a real file) is applied: for others the
    order of scale and offset on the line is not known here, and the pickup is refused with
    its line where it must be solved."""
    for s in f.surfs:
        ln = s.pzup
        if ln is None or s.number in thick:
            continue
        src = ln.int(1, "PZUP source surface", lo=0)
        if src not in thick:
            continue
        rest = [ln.float(i, "PZUP value") for i in range(2, min(len(ln.tokens), 5))]
        if rest[:3] != [1.0, 0.0, 0.0][:len(rest)]:
            raise ln.error(f"a thickness pickup from surface {src} other than a plain copy "
                           f"(scale 1, offset 0), whose thickness this configuration changes "
                           f"(THIC); jaxlens cannot tell how Zemax applies its values")
        s.disz = f.surfs[src].disz
        s.disz_line = ZmxLine(ln.path, ln.number, f"DISZ {s.disz!r}")
        thick.add(s.number)


def _curvature_pickups(f: ZmxFile, curved: set) -> None:
    """Solve the curvature pickups (``CURV c 4 src scale …``: solve type 4) of surfaces whose
    source surface this configuration gave another curvature (``CRVT``), in surface order.
    With a scale of ±1 the picked-up curvature is scale × the source's (a radius pickup and a
    curvature pickup agree then; the files seen use -1, a lens's two faces kept symmetric).
    Another scale is refused: whether Zemax scales the radius or the curvature is not known
    here, and the two differ."""
    for s in f.surfs:
        ln = s.curv_line
        src = _curvature_source(ln)
        if src is None or s.number in curved or src not in curved:
            continue
        scale = ln.float(4, "curvature pickup's scale factor")
        if abs(scale) != 1:
            raise ln.error(f"a curvature pickup of scale {ln.tokens[4]} from surface {src}, "
                           f"whose curvature this configuration changes (CRVT); jaxlens "
                           f"cannot tell whether Zemax scales the radius or the curvature")
        s.curv = scale * f.surfs[src].curv
        curved.add(s.number)


def _parameter(f, op, value, ln):
    """``PARn s c value``: surface s's ``PARM n`` in this configuration."""
    s = _surface(f, op, ln)
    n = int(PARAMETER_OPERAND.fullmatch(op.name).group(1))
    s.parm[n] = (_number(value, ln), ZmxLine(ln.path, ln.number, f"PARM {n} {value}"))


def _parameter_pickups(f: ZmxFile, changed: set) -> None:
    """Solve the parameter pickups (``PPAR n src scale offset column``: ``PARM n`` = scale ×
    surface src's ``PARM n`` + offset) again after a configuration set parameters of the
    surfaces in ``changed``, in surface order (a pickup of a pickup follows its source). The
    file's values hold the saved configuration's solution; a pickup whose source nothing
    changed keeps it. A pickup from another column (last value ≠ 0) of a changed surface is
    refused: which parameter it reads is not known."""
    for s in f.surfs:
        for n, ln in sorted(s.ppar.items()):
            src = ln.int(2, "PPAR source surface", lo=0)
            if src not in changed:
                continue
            if len(ln.tokens) > 5 and ln.float(5, "PPAR column") != 0:
                raise ln.error(f"a parameter pickup from another column ({ln.tokens[5]}) of a "
                               f"surface this configuration changes; jaxlens cannot tell "
                               f"which parameter it reads")
            base = f.surfs[src].parm.get(n, (0.0, None))[0]
            v = ln.float(3, "PPAR scale factor") * base + ln.float(4, "PPAR offset")
            s.parm[n] = (v, ZmxLine(ln.path, ln.number, f"PARM {n} {v!r}"))
            changed.add(s.number)


def _same(a: str, b: str) -> bool:
    try:
        return float(a) == float(b)
    except ValueError:
        return a.strip('"').upper() == b.strip('"').upper()


def _numbers(ops: list[Operand]) -> None:
    """Every row of the numeric operands jaxlens reads, of every configuration, is a finite
    number (``ValueError`` naming the line): a row that no reading parsed (``THIC 2 1 abc``
    read as configuration 2) let the file open without a word."""
    for op in ops:
        if op.name in ENVIRONMENT or op.name in WEIGHTS or PARAMETER_OPERAND.fullmatch(
                op.name) or (op.name in _APPLY and op.name != "GLSS"):
            for value, ln in op.values.values():
                _number(value, ln)


def _number(value: str, ln: ZmxLine) -> float:
    try:
        v = float(value.replace("D", "E"))
    except ValueError:
        raise ln.error(f"{ln.tokens[0]}'s value must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ln.error(f"{ln.tokens[0]}'s value must be finite")
    return v


def _surface(f: ZmxFile, op: Operand, ln: ZmxLine):
    if not 0 <= op.param < len(f.surfs):
        raise ln.error(f"{op.name} names surface {op.param}; the file has surfaces "
                       f"0..{len(f.surfs) - 1}")
    return f.surfs[op.param]


def _thic(f, op, value, ln, active):
    s = _surface(f, op, ln)
    v = _number(value, ln)
    s.disz = math.inf if op.param == 0 and v >= _OBJECT_INFINITY else v
    s.disz_line = ZmxLine(ln.path, ln.number, f"DISZ {value}")


def _crvt(f, op, value, ln, active):
    s = _surface(f, op, ln)
    s.curv, s.curv_line = _number(value, ln), ZmxLine(ln.path, ln.number, f"CURV {value}")


def _conn(f, op, value, ln, active):
    _surface(f, op, ln).coni = _number(value, ln)


def _glss(f, op, value, ln, active):
    s = _surface(f, op, ln)
    name = value.strip('"')
    if not name:
        s.glas = None  # no glass: air
        return
    try:
        float(name)
    except ValueError:
        # Read as a GLAS line of the name alone; messages quote the GLSS row itself.
        s.glas = ZmxLine(ln.path, ln.number, ln.text)
        s.glas.tokens = ["GLAS", name]
        return
    raise ln.error(f"GLSS's value is a glass name, got the number {value}")


def _sdia(f, op, value, ln, active):
    s = _surface(f, op, ln)
    v = _number(value, ln)
    if not v >= 0:
        raise ln.error("a semi-diameter (SDIA) must be >= 0")
    floats = f.aperture is not None and f.aperture[0] == "float" and s.stop
    clips = (s.flap is not None and s.clap is None) or (floats and not s.clap)
    flag = s.diam[1] if s.diam is not None else None
    if clips and flag == 0 and not _same(value, op.values.get(active, (value, None))[0]):
        raise ln.error(f"SDIA {op.param} changes the semi-diameter of surface {op.param}, "
                       f"which clips there (a floating aperture or FLOA), but its DIAM is "
                       f"automatic in the file; jaxlens cannot tell what Zemax clips at")
    s.diam = (v, flag)


def _aper(f, op, value, ln, active):
    v = _number(value, ln)
    if f.aperture is None:
        raise ln.error("APER without the file's aperture line (ENPD, FNUM, OBNA)")
    kind, old, _ = f.aperture
    if kind == "float":
        if v != old and not _same(value, op.values.get(active, (value, None))[0]):
            raise ln.error("APER under FLOA (the pupil set by the stop size) is not applied")
        return
    f.aperture = (kind, v, ln)


def _wave(f, op, value, ln, active):
    if not f.wavm:
        raise ln.error("WAVE needs the file's wavelengths as WAVM lines (this file has WAVL)")
    if op.param not in f.wavm:
        raise ln.error(f"WAVE names wavelength {op.param}, which the file's WAVM lines lack")
    _, old = f.wavm[op.param]
    weight = old.tokens[3:4]
    text = " ".join(["WAVM", str(op.param), value, *weight])
    f.wavm[op.param] = (_number(value, ln), ZmxLine(ln.path, ln.number, text))


def _field(f, op, value, ln, active):
    y = op.name == "YFIE"
    names = ("yfln", "yfld") if y else ("xfln", "xfld")
    attr = next((a for a in names if getattr(f, a) is not None), None)
    if attr is None:
        if _number(value, ln) == 0:
            return
        raise ln.error(f"{op.name} without the file's {'y' if y else 'x'} fields "
                       f"({names[0].upper()})")
    old = getattr(f, attr)
    tokens = list(old.tokens)
    if not 1 <= op.param < len(tokens):
        raise ln.error(f"{op.name} names field {op.param}; {old.tokens[0]} gives "
                       f"{len(tokens) - 1}")
    _number(value, ln)
    tokens[op.param] = value
    setattr(f, attr, ZmxLine(ln.path, ln.number, " ".join(tokens)))


def _vignetting(f, op, value, ln, active):
    key = VIGNETTING[op.name]
    _number(value, ln)
    if op.param < 1:
        raise ln.error(f"{op.name} names field {op.param}; fields count from 1")
    old = next((v for v in f.vignetting if v.tokens[0].upper() == key), None)
    tokens = list(old.tokens[1:]) if old is not None else []
    tokens += ["0"] * (op.param - len(tokens))
    tokens[op.param - 1] = value
    new = ZmxLine(ln.path, ln.number, " ".join([key, *tokens]))
    f.vignetting = [new if v is old else v for v in f.vignetting] if old is not None else [
        *f.vignetting, new]


def _stps(f, op, value, ln, active):
    v = _number(value, ln)
    if v != int(v) or not 1 <= v <= len(f.surfs) - 2:
        raise ln.error(f"STPS (the stop surface) must be a lens surface, 1..{len(f.surfs) - 2}, "
                       f"got {value}")
    for i, s in enumerate(f.surfs):
        s.stop = i == int(v)


_APPLY = {"THIC": _thic, "CRVT": _crvt, "CONN": _conn, "GLSS": _glss, "SDIA": _sdia,
          "APER": _aper, "WAVE": _wave, "XFIE": _field, "YFIE": _field, "STPS": _stps,
          **dict.fromkeys(VIGNETTING, _vignetting)}


def _check_active(f: ZmxFile, ops: list[Operand], active: int, strict: bool) -> None:
    """The surfaces hold the active configuration: where a THIC, CRVT or CONN row of it (or
    a vignetting row, FVDX … FVAN, against the file's VDXN … VANN lines) says otherwise,
    the active number (MNUM's second value) is not what it seems.

    A vignetting row whose factor the file has no line for at all (no VCXN line beside
    FVCX rows: OpTaliX's export writes the factors in its operand rows only) gives the
    active configuration's factor, as it does for any other configuration: nothing else in
    the file states it, and the default 0 would widen a vignetted pupil without a word."""
    absent = {key for key in VIGNETTING.values()
              if not any(x.tokens[0].upper() == key for x in f.vignetting)}
    for op in ops:
        if op.name in ENVIRONMENT and active in op.values:
            _environment(f, op, *op.values[active], active)
            continue
        if (not _held(op.name) and op.name not in VIGNETTING) or active not in op.values:
            continue
        value, ln = op.values[active]
        v = _number(value, ln)
        if op.name in VIGNETTING:  # the file's VDXN … VANN lines hold the active factors
            if op.param < 1:
                continue
            key = VIGNETTING[op.name]
            if key in absent:
                _vignetting(f, op, value, ln, active)
                continue
            line = next((x for x in f.vignetting if x.tokens[0].upper() == key), None)
            have = line.float(op.param, f"{key} value") if (
                line is not None and op.param < len(line.tokens)) else 0.0
            if not math.isclose(v, have, rel_tol=1e-9, abs_tol=1e-12):
                report(strict, f"{ln.path}:{ln.number}: {op.name} {op.param} of configuration "
                               f"{active}, the active one (MNUM), is {value}, but the file's "
                               f"{key} gives field {op.param} {have:g}; jaxlens reads {key}")
                return
            continue
        if not _holds(f, op, active):
            m = PARAMETER_OPERAND.fullmatch(op.name)
            sf = _surface(f, op, ln)
            have = sf.parm.get(int(m.group(1)), (0.0, None))[0] if m else getattr(
                sf, {"THIC": "disz", "CRVT": "curv", "CONN": "coni"}[op.name])
            report(strict, f"{ln.path}:{ln.number}: {op.name} {op.param} of configuration "
                           f"{active}, the active one (MNUM), is {value}, but surface "
                           f"{op.param} holds {have:g}; jaxlens reads the surfaces")
            return
