"""Reading a ``.zmx`` file's lines: its keywords, the records of its header and of its SURF
blocks, each value kept with the line it came from for messages (``jaxlens.io.zmx_read``
makes the lens of them)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ..optics.checks import number_text
from .zmx_keywords import IGNORED_KEYWORDS, KNOWN_VALUES, is_config_operand

UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}
SURFACE_KEYS = {
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
    "FLAP",
    "OBSC",
    "OBDC",
    "SQAP",
    "ELAP",
    "SQOB",
    "ELOB",
    "PPAR",
    "PZUP",
    "GDAT",
    "GARR",
}
SHAPES = {"SQAP": ("rect", False), "ELAP": ("ellipse", False), "SQOB": ("rect", True),
          "ELOB": ("ellipse", True)}  # keyword -> (Aperture shape, blocks)
KEYWORD = re.compile(r"^[A-Z][A-Z0-9_]{1,9}$")
MAX_COUNT = 10_000
"""The largest whole number (a count, an index, a flag) a ``.zmx`` line may give: Zemax's
fields, wavelengths, surfaces and terms number far fewer, and a reader looping to 1e15 would
hang."""


class ZmxLine:
    """One line of a file, for error messages."""

    def __init__(self, path: str, number: int, text: str):
        self.path, self.number, self.text = path, number, text
        self.tokens = text.split()

    def error(self, msg: str) -> ValueError:
        return ValueError(f"{self.path}:{self.number}: {msg}: {self.text.strip()!r}")

    def float(self, i: int, what: str, *, allow_inf: bool = False, lo=None) -> float:
        try:
            tok = self.tokens[i]
        except IndexError:
            raise self.error(f"missing {what}") from None
        if allow_inf and tok.upper() in ("INFINITY", "INF"):
            return math.inf
        try:
            v = number_text(tok)
        except ValueError:
            hint = ""
            try:  # a hand edit in a locale that writes decimal commas
                number_text(tok.replace(",", ".", 1))
                hint = f"; a decimal comma? .zmx numbers take a point: {tok.replace(',', '.', 1)}"
            except ValueError:
                pass
            raise self.error(f"{what} is not a number ({tok!r}{hint})") from None
        if not math.isfinite(v):
            raise self.error(f"{what} must be finite")
        if lo is not None and v < lo:
            raise self.error(f"{what} must be >= {lo}, got {tok}")
        return v

    def single(self, what: str, *, indexed: bool = False) -> None:
        """Refuses a line with more than one value where Zemax writes one (DISZ, CONI,
        ENPD; ``indexed``: after an index, PARM): a hand edit's second number was ignored
        ("DISZ 0.8 0.06" read as 0.8). Trailing zeros pass, as another writer's padding
        (the solve columns of CURV, say) would: they cannot be a split number or a value in
        the wrong column."""
        extra = self.tokens[3 if indexed else 2:]
        if any(_nonzero(tok) for tok in extra):
            raise self.error(f"{self.tokens[0]} takes {'an index and ' if indexed else ''}one "
                             f"value ({what}), got {len(self.tokens) - 1}: a value in the "
                             f"wrong column, or a number split by a space?")

    def int(self, i: int, what: str, *, lo=None, hi: int = MAX_COUNT) -> int:
        v = self.float(i, what, lo=lo)
        if v != int(v):
            raise self.error(f"{what} must be an integer")
        if abs(v) > hi:
            raise self.error(f"{what} must be at most {hi} in size, got {self.tokens[i]}")
        return int(v)




@dataclass
class ZmxSurface:
    number: int
    line: ZmxLine
    type: str = "STANDARD"
    type_line: ZmxLine | None = None
    curv: float = 0.0
    curv_line: ZmxLine | None = None
    disz: float = 0.0
    disz_line: ZmxLine | None = None
    coni: float = 0.0
    parm: dict = field(default_factory=dict)  # index -> (value, line)
    ppar: dict = field(default_factory=dict)  # index -> its pickup line (PPAR)
    psolve: dict = field(default_factory=dict)  # index -> a PPAR line reading no surface
    gdat: ZmxLine | None = None  # a grid surface's size line (GDAT nx ny dx dy …)
    garr: list = field(default_factory=list)  # its grid points (GARR i value d/dx d/dy d2 …)
    pzup: ZmxLine | None = None  # a thickness pickup (PZUP src scale offset column)
    xdat: dict = field(default_factory=dict)
    glas: ZmxLine | None = None
    stop: bool = False
    diam: tuple[float, int | None] | None = None
    clap: float | None = None
    clap_min: ZmxLine | None = None  # an annular aperture's CLAP line (minimum radius > 0)
    flap: ZmxLine | None = None  # a floating aperture (FLAP 0 r 0): a circle of radius DIAM
    obsc: ZmxLine | None = None  # a circular obscuration (OBSC min max)
    obdc: ZmxLine | None = None  # the aperture's decenter (OBDC x y), if not 0 0
    shaped: list = field(default_factory=list)  # SQAP/ELAP/SQOB/ELOB lines
    comment: str = ""
    keys: set = field(default_factory=set)  # the keywords this block has


@dataclass
class ZmxFile:
    path: str
    name: str = ""
    unit: float = 1.0
    aperture: tuple[str, float, ZmxLine] | None = None
    pupd: ZmxLine | None = None  # older Zemax writes it beside ENPD/FLOA/…; alone it is refused
    envd: ZmxLine | None = None  # the environment: temperature (°C), pressure (atm), flag
    gcat: list = field(default_factory=list)
    ftyp: ZmxLine | None = None
    xfln: ZmxLine | None = None
    yfln: ZmxLine | None = None
    xfld: ZmxLine | None = None  # older Zemax: the fields, one value each (no padding to 12)
    yfld: ZmxLine | None = None
    wavm: dict = field(default_factory=dict)
    wavl: ZmxLine | None = None
    pwav: ZmxLine | None = None
    fwgn: ZmxLine | None = None  # field weights (FWGN; older Zemax: FWGT)
    wwgt: ZmxLine | None = None  # weights of WAVL's wavelengths (WWGT or WWGN)
    vignetting: list = field(default_factory=list)  # VDXN/VDYN/VCXN/VCYN/VANN lines
    raim: ZmxLine | None = None
    surfs: list = field(default_factory=list)
    unknown: list = field(default_factory=list)  # lines with a keyword nobody knows
    comments: list = field(default_factory=list)  # lines starting with '!' (hand-written)
    mnum: ZmxLine | None = None  # the number of configurations (and the active one)
    config_lines: list = field(default_factory=list)  # operand lines after MNUM, in order
    zemax: bool = False  # written by Zemax (a VERS line): every block is complete


SINGLE_SURFACE_KEYS = frozenset("TYPE CURV DISZ CONI GLAS DIAM CLAP FLAP OBSC OBDC PZUP "
                                 "GDAT".split())
"""Keywords a SURF block holds once (PARM, XDAT and PPAR: once per index). Zemax writes each
once; a second line (an edit or a merge gone wrong) replaced the first without a word."""
INDEXED_SURFACE_KEYS = frozenset(("PARM", "XDAT", "PPAR"))
APERTURE_KEYS = frozenset(("ENPD", "FNUM", "FLOA", "OBNA"))
SINGLE_TOP_KEYS = frozenset("UNIT FTYP XFLN YFLN XFLD YFLD WAVL PWAV GCAT ENVD RAIM MNUM FWGN "
                            "FWGT WWGT WWGN".split())
"""Header keywords a file holds once: the later of two lines replaced the earlier without a
word (which catalogs, environment, aiming, configurations or weights the file meant was a
guess). FWGT beside FWGN (WWGT beside WWGN), as Zemax 2006 writes them, is not a repeat."""


def _nonzero(tok: str) -> bool:
    """Whether a token is anything but the number 0 (text, a nonzero value)."""
    try:
        return number_text(tok) != 0
    except ValueError:
        return True


def _repeat(seen_top: dict, seen_surf: dict, key: str, ln: ZmxLine,
            cur: ZmxSurface | None) -> None:
    """The one rule of lines given twice: a header keyword of ``SINGLE_TOP_KEYS`` (the system
    aperture, a WAVM n) in the file, a surface keyword of ``SINGLE_SURFACE_KEYS`` (a PARM,
    XDAT or PPAR index) in its SURF block."""
    if key in SURFACE_KEYS and cur is not None:
        if key in SINGLE_SURFACE_KEYS:
            _once(seen_surf, key, ln, f" in surface {cur.number}")
        elif key in INDEXED_SURFACE_KEYS:
            _once(seen_surf, f"{key} {ln.tokens[1]}", ln, f" in surface {cur.number}")
    elif key in APERTURE_KEYS:  # one system aperture: ENPD, FNUM, FLOA or OBNA
        _once(seen_top, "the system aperture (ENPD, FNUM, FLOA or OBNA)", ln, "")
    elif key in SINGLE_TOP_KEYS:
        _once(seen_top, key, ln, "")
    elif key == "WAVM":
        _once(seen_top, f"WAVM {ln.tokens[1]}", ln, "")


def _once(seen: dict, what: str, ln: ZmxLine, where: str) -> None:
    """Refuse ``what`` given a second time (``seen`` maps it to its first line)."""
    first = seen.setdefault(what, ln)
    if first is not ln:
        raise ln.error(f"{what} given twice{where} (first on line {first.number}: "
                       f"{first.text.strip()!r}); a .zmx file gives it once")


def parse(text: str, path: str) -> ZmxFile:
    f = ZmxFile(path)
    cur: ZmxSurface | None = None
    seen_top: dict = {}
    seen_surf: dict = {}
    text = text.removeprefix("\ufeff")  # a BOM kept by a text read (utf-8, not utf-8-sig)
    for number, raw in enumerate(text.splitlines(), start=1):
        ln = ZmxLine(path, number, raw)
        if not ln.tokens:
            continue
        key = ln.tokens[0]
        if key.startswith("!"):
            # '!' opens a comment in Zemax's macro (ZPL) files; OpticStudio writes none in a
            # lens file, but hand-written files carry them. Skipped, and reported (_check).
            f.comments.append(ln)
            continue
        if not KEYWORD.match(key):
            raise ln.error("not a Zemax keyword line")
        if key == "SURF":
            n = ln.int(1, "surface number")
            if n != len(f.surfs):
                raise ln.error(f"surfaces must be numbered 0, 1, 2, …; expected {len(f.surfs)}")
            cur = ZmxSurface(n, ln)
            f.surfs.append(cur)
            seen_surf = {}
        elif key in SURFACE_KEYS:
            if cur is None:
                raise ln.error(f"{key} before the first SURF")
            surface_line(cur, key, ln)  # a bad value is named before a repeat
        elif key in TOP_KEYS:
            top_line(f, key, ln, raw)
        elif key == "MNUM":
            f.mnum = ln
        elif is_config_operand(key) and f.mnum is not None:
            f.config_lines.append(ln)
        elif key in KNOWN_VALUES and not KNOWN_VALUES[key](ln.tokens[1:]):
            f.unknown.append(ln)  # a keyword known only with the values seen in real files
        elif key not in IGNORED_KEYWORDS:
            f.unknown.append(ln)
        _repeat(seen_top, seen_surf, key, ln, cur)
        if key in SURFACE_KEYS and cur is not None:
            cur.keys.add(key)
    if not f.surfs:
        raise ValueError(f"{path}: no SURF lines; not a sequential Zemax lens file")
    return f


def surface_line(s: ZmxSurface, key: str, ln: ZmxLine) -> None:
    if key == "TYPE":
        if len(ln.tokens) < 2:
            raise ln.error("TYPE needs a surface type")
        s.type, s.type_line = ln.tokens[1].upper(), ln
    elif key == "CURV":
        s.curv, s.curv_line = ln.float(1, "curvature"), ln
    elif key == "DISZ":
        s.disz, s.disz_line = ln.float(1, "thickness", allow_inf=True), ln
        ln.single("the thickness")
        if math.isinf(s.disz) and s.number > 0:
            raise ln.error("only the object surface may have an infinite thickness")
    elif key == "CONI":
        s.coni = ln.float(1, "conic constant")
        ln.single("the conic constant")
    elif key in ("PARM", "XDAT"):
        i = ln.int(1, f"{key} index")
        (s.parm if key == "PARM" else s.xdat)[i] = (ln.float(2, f"{key} {i} value"), ln)
        if key == "PARM":  # Zemax writes "PARM i value" (XDAT lines carry solve columns)
            ln.single(f"PARM {i}'s value", indexed=True)
    elif key == "PPAR":
        # PPAR n s scale offset column: PARM n = scale * (surface s's PARM n) + offset (a
        # pickup solve; OpticStudio files and Zemax 2006 ones alike). The file's PARM n holds
        # the solved value, so only a configuration that changes surface s re-solves it.
        # A source below 0 reads no surface (Zemax 5.2's "PPAR 3 -1 1 0" on a coordinate
        # break after a grating, whose PARM 3 holds a tilt of -3.5e-4°, the chief ray's
        # diffracted direction: a solve of another kind, kept apart and reported).
        i = ln.int(1, "PPAR parameter index")
        src = ln.int(2, "PPAR source surface")
        ln.float(3, "PPAR scale factor")
        ln.float(4, "PPAR offset")
        (s.ppar if src >= 0 else s.psolve)[i] = ln
    elif key == "PZUP":
        # PZUP s scale offset column: the thickness picked up from surface s (Zemax 2009's
        # Nikon 105 mm: "PZUP 6.0 1 0 0" on a surface whose DISZ equals surface 6's). The
        # file's DISZ holds the solved value; only a configuration changing s re-solves it.
        ln.int(1, "PZUP source surface", lo=0)
        s.pzup = ln
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
        lo = ln.float(1, "circular aperture minimum radius (lens units)", lo=0)
        s.clap = ln.float(2, "circular aperture maximum radius (lens units)", lo=0)
        if lo > 0:  # an annulus: the clipping radius and a central obscuration inside lo
            if not lo < s.clap:
                raise ln.error("an annular aperture needs minimum < maximum radius")
            s.clap_min = ln
    elif key == "FLAP":
        ln.float(2, "floating aperture radius (lens units)", lo=0)
        s.flap = ln
    elif key == "OBSC":
        if ln.float(2, "obscuration maximum radius") > 0:
            if not 0 <= ln.float(1, "obscuration minimum radius") < ln.float(2, ""):
                raise ln.error("OBSC needs 0 ≤ minimum < maximum radius (lens units)")
            s.obsc = ln
    elif key == "OBDC":
        if ln.float(1, "aperture x decenter") != 0 or ln.float(2, "aperture y decenter") != 0:
            s.obdc = ln
    elif key in SHAPES:
        for i, what in ((1, "x"), (2, "y")):
            if not ln.float(i, f"aperture {what} half-width") > 0:
                raise ln.error(f"{key} needs half-widths > 0 (lens units), got {ln.tokens[i]}")
        s.shaped.append(ln)
    elif key == "COMM":
        s.comment = ln.text.strip()[4:].strip()
    elif key == "GDAT":
        for i, what in ((1, "x"), (2, "y")):
            ln.int(i, f"GDAT grid points along {what}", lo=1)
        s.gdat = ln
    elif key == "GARR":
        ln.int(1, "GARR grid point index", lo=0)
        s.garr.append(ln)


TOP_KEYS = frozenset("VERS MODE NAME UNIT ENPD FNUM FLOA OBNA PUPD ENVD GCAT FTYP XFLN YFLN "
                      "XFLD YFLD WAVM WAVL PWAV RAIM VDXN VDYN VCXN VCYN VANN FWGN FWGT WWGT "
                      "WWGN".split())


def top_line(f: ZmxFile, key: str, ln: ZmxLine, raw: str) -> None:
    if key == "VERS":
        f.zemax = True
    if key == "MODE" and len(ln.tokens) > 1 and ln.tokens[1].upper() != "SEQ":
        raise ln.error("only sequential (MODE SEQ) files are supported")
    if key == "NAME":
        f.name = raw.strip()[4:].strip()
    elif key == "UNIT":
        u = ln.tokens[1].upper() if len(ln.tokens) > 1 else ""
        if u not in UNITS:
            raise ln.error(f"unknown lens unit {u!r}; use MM, CM, IN or METER")
        f.unit = UNITS[u]
    elif key == "ENPD":
        f.aperture = ("epd", ln.float(1, "entrance pupil diameter"), ln)
        ln.single("the entrance pupil diameter")
    elif key == "FNUM":  # FNUM x 0: image-space F/#; FNUM x 1: paraxial working F/#
        kind = ln.int(2, "F/# type") if len(ln.tokens) > 2 else 0
        if kind not in (0, 1):
            raise ln.error(f"F/# type must be 0 (image space) or 1 (paraxial working), got {kind}")
        f.aperture = ("wfno" if kind else "fnum", ln.float(1, "F/#"), ln)
    elif key == "FLOA":
        f.aperture = ("float", 0.0, ln)
    elif key == "OBNA":
        kind = ln.int(2, "OBNA type (0: NA, 1: cone angle)") if len(ln.tokens) > 2 else 0
        if kind not in (0, 1):
            raise ln.error(f"OBNA type must be 0 (object-space NA) or 1 (object cone angle), "
                           f"got {kind}")
        what = "object cone angle" if kind else "object-space NA"
        f.aperture = ("cone" if kind else "obna", ln.float(1, what), ln)
    elif key == "PUPD":
        f.pupd = ln
    elif key == "ENVD":
        f.envd = ln
    elif key in ("VDXN", "VDYN", "VCXN", "VCYN", "VANN"):
        f.vignetting.append(ln)
    elif key == "RAIM":
        f.raim = ln
    elif key == "GCAT":
        f.gcat = [t.upper() for t in ln.tokens[1:]]
    elif key == "FTYP":
        f.ftyp = ln
    elif key == "XFLN":
        f.xfln = ln
    elif key == "YFLN":
        f.yfln = ln
    elif key == "XFLD":
        f.xfld = ln
    elif key == "YFLD":
        f.yfld = ln
    elif key == "WAVM":
        i = ln.int(1, "wavelength number")
        f.wavm[i] = (ln.float(2, "wavelength"), ln)
    elif key == "WAVL":
        f.wavl = ln
    elif key == "PWAV":
        f.pwav = ln
    elif key in ("FWGN", "FWGT"):
        f.fwgn = ln
    elif key in ("WWGT", "WWGN"):
        f.wwgt = ln
