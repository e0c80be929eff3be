"""Keywords that Zemax writes in ``.zmx`` files and the reader knows but does not use.

Drawing, tolerancing, solves, multi-configuration, optimisation and environment data, and the
operands of a merit function (written one a line after the surfaces). Any other keyword is
reported by the reader: a warning, or an error with ``strict=True`` (a cut-off keyword means
a truncated file).
"""

from __future__ import annotations

import re

SETTINGS = frozenset("""
    VERS NOTE PFIL LANG ENVD GFAC SDMA PUSH ROPD PICB HYPR POLS GLRS GSTD NSCD COFN COFJ
    ZVDX ZVDY ZVCX ZVCY ZVAN WAVN
    FLDM MNCA MXCA MNEA MXEA MNCG MXCG MNEG MXEG MNPD MXPD TCEM TMIN TMAX BLNK TOL TOLE MNUM
    MOFF MOPS MAZH EFFL DMFS SCOL SCTH SCON CONF OPDX PWRH VPAR PRAM IGNR PZUP TELE AFOC
    APMN APMX APCX APCY APDX APDY APTP OBSF MEMA OEMA POPS HIDE MIRR SLAB
    COAT FIMP CTHK EDGE THSO TRAC VARI VDSZ WAVL XFLN YFLN PPAR BLKS BLNK CAMA GLCZ HIDX
    TCEX MAZH MIND MXWL MNWL OPTI NSCS NSOA NSOD NSOO NSOP NSOQ NSOS NSOU NSOV NSOW GCAT
    OMMA SCBD TCED XDVA MOD2 RWRE TOLP CSUM DBDT AUTH LUID SSID RCMF XAIM YAIM ZAIM TCMM
    IWDP STUD EERA FCOM
    """.split())
"""Lens-data settings the reader ignores (``OMMA``: the optimisation method; ``SCBD``: a
surface's coordinate-break-after-surface data written as all zeros by OpticStudio; ``CSUM``:
a checksum; ``TCMM``: a tolerance operand's comment; ``DBDT``: the stock-lens database record
of a vendor's file; ``AUTH``, ``LUID``, ``SSID``, ``RCMF``: OpticStudio's author, lens and
surface ids and a file flag; ``XAIM``, ``YAIM``, ``ZAIM``: ray-aiming pupil shifts, a
starting point of OpticStudio's aiming that jaxlens's Newton aiming (``RAIM``, ``Lens.aim``)
does not need; ``FCOM n text``: the comment of field n, a column of OpticStudio's Field
Data Editor, text only). ``IWDP``, ``STUD``, ``EERA``: header lines of OpticStudio
2024 files (beside ``AUTH`` and ``LUID``) that no public format note explains; they are
ignored only with the values seen in real files (``KNOWN_VALUES``)."""


def _zeros(tokens: list, n: int) -> bool:
    try:
        return len(tokens) >= n and all(float(t) == 0 for t in tokens[:n])
    except ValueError:
        return False


KNOWN_VALUES = {
    # Seen only as ``IWDP 0`` (8 OpticStudio 2024 files of optiland's tests, whose EFLs
    # jaxlens and optiland agree on); another value is reported as an unknown keyword.
    "IWDP": lambda t: t == ["0"],
    # Seen only as ``STUD 1`` (2 of those files).
    "STUD": lambda t: t == ["1"],
    # Seen as ``EERA 0 0 0 10 10`` and ``EERA 0 0 0 10``: three zero flags, then counts.
    "EERA": lambda t: _zeros(t, 3),
    # The names say telecentric object space and afocal image space, which FTYP also sets
    # and jaxlens refuses there: ignored only when off (0), else reported.
    "TELE": lambda t: _zeros(t, len(t)),
    "AFOC": lambda t: _zeros(t, len(t)),
}
"""Keywords ignored only with the values seen in real files (a predicate on the tokens after
the keyword). What they do is not documented, so a value never seen may change the lens: it is
reported like an unknown keyword (an error under ``strict``)."""

CONFIG_OPERANDS = frozenset("""
    THIC CRVT CONN GLSS SDIA APER XFIE YFIE FLWT WAVE WLWT TEMP PRES
    MOFF LTTL MCOM STPS PRAM FVCX FVCY FVDX FVDY FVAN SATP CWGT PRWV RAAM UDAF ZPHS
    """.split())
"""Multi-configuration operands: after ``MNUM`` (the number of configurations, the active
one), one line per operand and configuration, ``OPER param configuration value …``
(``jaxlens.io.zmx_config`` applies them). Names that are also lens-data keywords (``APDX``,
``TELE``, …) are not taken for operands."""

MERIT_OPERANDS = frozenset("""
    ABCD ABGT ABLT ABSO ACOS ACOT AMAG ANAC ANAR ANAX ANAY ANCX ANCY ASIN ATAN AXCL BLTH
    BSER CENX CENY CONS COSI COVA CTGT CTLT CTVA CVGT CVLT CVVA DENC DENF DIFF DIMX DISA
    DISC DISG DIST DIVB DIVI DLTN DMGT DMLT DMVA DXDX DXDY DYDX DYDY EFFL EFLX EFLY ENPP
    ENDX EQUA ETGT ETLT ETVA EXPD EXPP FCGS FCGT FCUR FICL FICP FOUC GAOP GCOS GLCA GLCB
    GLCR GLCX GLCY GLCZ GMTA GMTS GMTT GPIM GTCE HHCN IMAE IMSF INDX ISFN LACL LINV LOGE
    LOGT LONA LPTD MAXX MCOG MCOL MCOS MECA MECS MECT MINN MNAB MNCA MNCG MNCT MNCV MNDT
    MNEA MNEG MNET MNIN MNPD MNRE MNRI MNSD MSWA MSWS MSWT MTFA MTFS MTFT MTHA MTHS MTHT
    MXAB MXCA MXCG MXCT MXCV MXDT MXEA MXEG MXET MXIN MXPD MXRE MXRI MXSD NPGT NPLT NPVA
    NPXG NPXL NPXV NPYG NPYL NPYV NPZG NPZL NPZV NSDC NSDD NSDE NSDP NSTR OBSN OPDC OPDM
    OPDX OPGT OPLT OPTH OSCD OSGT OSLT OSUM PANA PANB PANC PARA PARB PARC PARR PARX PARY
    PARZ PATX PATY PETC PETZ PIMH PLEN PMAG PMGT PMLT PMVA POWF POWP POWR
    PRIM PROB PROD QOAC QSUM RAED RAGA RAGB RAGC RAGX RAGY RAGZ RAIN RANG REAA REAB REAC
    REAR REAX REAY REAZ RECI RELI RENA RENB RENC RETX RETY RGLA RSCE RSCH RSRE RSRH RWCE
    RWCH RWRE RWRH SAGX SAGY SCUR SDRV SFNO SIGN SINE SKIS SKIN SMIA SPCH SPHA SQRT SSAG
    STHI SUMM SVIG TANG TFNO TGTH TMAS TOLR TOTR TRAC TRAD TRAE TRAI TRAR TRAX TRAY TRCX
    TRCY TTGT TTHI TTLT TTVA UDOC UDOP USYM VOLU WFNO WLEN XDGT XDLT XDVA XENC XENF XNEG
    XPOS YNIP ZERN ZPLM ZTHI ACOS ASIN ATAN BSER CVIG DLTN EXPP FDMO FDRE FREZ GBPD GBPP
    GBPR GBPS GBPW GBSD GBSP GBSR GBSS GBSW GENC GENF GOTO HACG INDX LINV MNDT OPGT PMGT
    ISFN IMAE MSWA POPD POPI SPLO TOTR CMFV DMVA USYM ZTHI BLNK
    """.split())
"""Zemax merit-function operand names: the operand lines that follow a lens's surfaces."""

PARAMETER_OPERAND = re.compile(r"PAR(\d{1,2})")
"""Zemax 2006's configuration operand of a surface parameter: ``PARn s c value …`` sets
``PARM n`` of surface ``s`` in configuration ``c`` (the parameter number in the name; later
versions write ``PRAM``, whose line jaxlens cannot place the parameter number on). Read so
from the files themselves: in a Zemax 2006 course file (round 8's ``kraken_F-Theta_j.ZMX``,
a scan mirror's tilt in 4 configurations) ``PAR3 3 4 -5`` is the value surface 3's
``PARM 3`` holds, and no other configuration's row matches any surface's parameter."""


def is_config_operand(key: str) -> bool:
    """Whether ``key`` names a multi-configuration operand (``CONFIG_OPERANDS`` or ``PARn``)."""
    return key in CONFIG_OPERANDS or PARAMETER_OPERAND.fullmatch(key) is not None


IGNORED_KEYWORDS = SETTINGS | MERIT_OPERANDS | CONFIG_OPERANDS
