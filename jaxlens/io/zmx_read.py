"""Reading Zemax ``.zmx`` lens files (the format: ``jaxlens.io.zmx``)."""

from __future__ import annotations

import contextlib
import math
import os
import warnings

import jax.numpy as jnp
import numpy as np

from ..optics import checks, travel
from ..optics.apertures import Aperture
from ..optics.catalog import decode_zemax_text as decode
from ..optics.coordinates import CoordinateBreak
from ..optics.input_files import input_file
from ..optics.lens import INFINITE_OBJECT_MM, Lens
from ..optics.materials import Air
from ..optics.surfaces import (
    MAX_CURVATURE,
    AbstractSurface,
    EvenAsphere,
    Hybrid,
    OddAsphere,
    Standard,
)
from . import zmx_config, zmx_surfaces, zmx_system
from .lensfile import TELECENTRIC_SEED_NA, apply_aperture, apply_object_na, nonfinite_part
from .zmx_common import (
    HYBRID_COMMENT,
    MAX_XPOLY_DEGREE,
    ZmxWarning,
    report,
    term_index,
    term_powers,
    xpoly_terms,
)
from .zmx_glass import GlassResolver
from .zmx_keywords import IGNORED_KEYWORDS, KNOWN_VALUES
from .zmx_parse import SHAPES, ZmxFile, ZmxSurface, parse

_MAX_XDAT_TERMS = 230  # Zemax's extended polynomial: all terms up to degree 20


def _arr(x):
    return jnp.asarray(np.asarray(x, np.float64))


def _sd(s: ZmxSurface, unit: float) -> float:
    """The radius (mm) at which surface ``s`` clips rays, ``inf`` for none, as in Zemax: the
    semi-diameter (DIAM) alone never vignettes; a surface aperture does. A centred circular
    aperture (CLAP) clips at its radius, a floating aperture (FLAP) at the semi-diameter.
    Apertures of other shapes, or decentered ones, are ``Lens.apertures`` (``_apertures``)."""
    if s.shaped or (s.obdc is not None and s.clap):  # clips at its apertures only
        return math.inf
    if s.clap is not None:
        return s.clap * unit if s.clap > 0 else math.inf
    if s.flap is not None:
        return _floating_radius(s) * unit
    return math.inf


def _floating_radius(s: ZmxSurface) -> float:
    """A floating aperture's radius (lens units; ``inf``: it clips nothing): the surface's
    semi-diameter. An automatic one (DIAM solve flag 0) is the height of the file's outermost
    ray, so it passes every ray of the file's fields and pupil (clipping exactly there would
    lose marginal rays to rounding). Without a DIAM line, the radius written on FLAP."""
    if s.diam is None:
        r = s.flap.float(2, "")
    else:
        r, flag = s.diam
        if flag == 0:
            return math.inf
    return r if r > 0 else math.inf


def _surface(s: ZmxSurface, unit: float) -> AbstractSurface:
    """The surface of a SURF block; a value its class refuses (a semi-diameter beyond a
    steep sphere's edge, say) is reported with the block's line."""
    where = s.type_line or s.line
    if s.curv_line is not None and not abs(s.curv / unit) <= MAX_CURVATURE:
        # On its own line: the surface's class refused it under the block's TYPE line.
        raise s.curv_line.error(
            f"curvature {s.curv:g} per lens unit is {s.curv / unit:g} 1/mm, outside "
            f"[-{MAX_CURVATURE:g}, {MAX_CURVATURE:g}] 1/mm (a radius of at least "
            f"{1 / MAX_CURVATURE:g} mm)")
    try:
        with np.errstate(all="ignore"):  # a curvature of 1e308 squared: refused below
            surface = _surface_of(s, unit)
    except ValueError as e:
        if str(e).startswith(f"{s.line.path}:"):
            raise
        raise where.error(str(e)) from None
    except ArithmeticError:  # a normalisation radius of 1e-300 or 1e300, raised to the 20th
        raise where.error(f"surface {s.number}'s coefficients overflow once scaled to mm and "
                          f"the normalisation radius; its values are out of range") from None
    bad = nonfinite_part(surface)
    if bad:
        raise where.error(f"surface {s.number}: {bad} once scaled to mm (values out of range)")
    return surface


def _surface_of(s: ZmxSurface, unit: float) -> AbstractSurface:
    c = s.curv / unit
    sd = _sd(s, unit)
    where = s.type_line or s.line
    if s.type == "STANDARD":
        _standard_without_terms(s)
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
        n, norm, vals = zmx_surfaces.normalised_terms(s, "terms", _MAX_XDAT_TERMS)
        a = [v / norm ** (2 * i) * unit ** (1 - 2 * i) for i, v in enumerate(vals, start=1)]
        return EvenAsphere(
            c=_arr(c), k=_arr(s.coni), coeffs=_arr(np.array(a, np.float64)), semi_diameter=_arr(sd)
        )
    if s.type == "ODDASPHE":
        return zmx_surfaces.odd_asphere(s, unit, sd)
    if s.type == "XOSPHERE":  # Σ A_i (r/R)^i, i = 1..N: the odd asphere's β_i = A_i / R^i
        for _, (v, ln) in sorted(s.parm.items()):
            if v != 0:
                raise ln.error("XOSPHERE has no parameters (PARM); its terms are extra data "
                               "(XDAT 1 = number of terms, 2 = normalisation radius, 3… = A_i)")
        n, norm, vals = zmx_surfaces.normalised_terms(
            s, "terms", zmx_surfaces.MAX_XOSPHERE_TERMS)
        b = [v / norm**i * unit ** (1 - i) for i, v in enumerate(vals, start=1)]
        return OddAsphere(c=_arr(c), k=_arr(s.coni), coeffs=_arr(np.array(b, np.float64)),
                          semi_diameter=_arr(sd))
    if s.type == "TILTSURF":
        return zmx_surfaces.tilted_plane(s, sd)
    if s.type == "BINARY_2":
        return zmx_surfaces.binary2(s, unit, sd)
    if s.type == "DGRATING":
        return zmx_surfaces.grating(s, sd, unit)
    if s.type == "XPOLYNOM":  # jaxlens's hybrid (its comment), else Zemax's XY polynomial
        if HYBRID_COMMENT.search(s.comment):
            return _hybrid_from_xpoly(s, unit, c, sd)
        return zmx_surfaces.xy_polynomial(s, unit, sd)
    if s.type == "TOROIDAL":
        return zmx_surfaces.toroidal(s, unit, sd)
    if s.type == "PARAXIAL":
        return zmx_surfaces.paraxial_surface(s, unit, sd)[0]
    if s.type == "QED_TYPE":
        return zmx_surfaces.qtype_asphere(s, unit, sd)
    if s.type == "BICONICX":
        return zmx_surfaces.biconic(s, unit, sd)
    if s.type in ("SZERNSAG", "FZERNSAG"):
        return zmx_surfaces.zernike_sag(s, unit, sd)
    if s.type == "COORDBRK":
        return _coordinate_break(s, unit)
    if s.type == "GRID_PHA":
        zmx_surfaces.flat_phase_grid(s)
        return Standard(c=_arr(c), k=_arr(s.coni), semi_diameter=_arr(sd))
    raise where.error(
        f"surface type {s.type} is not supported (STANDARD, EVENASPH, ODDASPHE, XASPHERE, "
        f"XOSPHERE, XPOLYNOM, TOROIDAL, PARAXIAL, TILTSURF, BINARY_2, QED_TYPE, DGRATING, "
        f"BICONICX, SZERNSAG, FZERNSAG, COORDBRK; GRID_PHA whose grid is all 0)"
    )


def _standard_without_terms(s: ZmxSurface) -> None:
    """A block without a TYPE line is STANDARD, which has no parameters: non-zero PARM/XDAT
    values there mean a surface whose type line is missing (an asphere, most likely), and
    reading it as a sphere would drop them, so it is refused. Under an explicit
    ``TYPE STANDARD`` they are left over from another type (a normalisation radius, old
    terms) and Zemax ignores them, as the reader does."""
    if s.type_line is not None:
        return
    extra = [ln for _, (v, ln) in sorted(s.parm.items()) + sorted(s.xdat.items()) if v != 0]
    if extra:
        ln = extra[0]
        raise ln.error(f"surface {s.number} has no TYPE line, so it would be STANDARD, which "
                       f"has no parameters, but it gives {ln.tokens[0]} {ln.tokens[1]} (an "
                       f"asphere's terms?); add the surface's TYPE line")


def _coordinate_break(s: ZmxSurface, unit: float) -> CoordinateBreak:
    """COORDBRK: PARM 1, 2 decenter x, y (lens units), 3, 4, 5 tilt about x, y, z (degrees),
    6 the order flag (0: decenter then tilt, 1: tilt then decenter)."""
    where = s.type_line or s.line
    for i, (v, ln) in s.parm.items():
        if not 1 <= i <= 6 and v != 0:
            raise ln.error("COORDBRK uses PARM 1..6 (decenter x, y, tilt x, y, z, order)")
    if s.curv != 0 or s.coni != 0:
        raise where.error("a coordinate break (COORDBRK) has no shape; its CURV and CONI must "
                          "be 0")
    order, ln = s.parm.get(6, (0.0, where))
    if order not in (0.0, 1.0):
        raise ln.error(f"COORDBRK order flag (PARM 6) must be 0 (decenter, then tilt) or 1 "
                       f"(tilt, then decenter), got {order:g}")
    p = {i: s.parm.get(i, (0.0, None))[0] for i in range(1, 6)}
    return CoordinateBreak(decenter_x=_arr(p[1] * unit), decenter_y=_arr(p[2] * unit),
                           tilt_x=_arr(p[3]), tilt_y=_arr(p[4]), tilt_z=_arr(p[5]),
                           order=int(order))


def _is_mirror(s: ZmxSurface) -> bool:
    return s.glas is not None and s.glas.tokens[1].upper() == "MIRROR"


def _keeps_medium(s: ZmxSurface) -> bool:
    """Mirrors and coordinate breaks: the medium after them is the medium before."""
    return _is_mirror(s) or s.type == "COORDBRK"


def _hybrid_from_xpoly(s: ZmxSurface, unit: float, c: float, sd: float) -> Hybrid:
    n, norm, vals = zmx_surfaces.normalised_terms(s, "extended-polynomial terms",
                                                  _MAX_XDAT_TERMS)
    terms = {}
    for j, v in enumerate(vals, start=1):
        mx, ny = term_powers(j)
        d = mx + ny
        terms[(mx, ny)] = v / norm**d * unit ** (1 - d)
    top = sum(term_powers(n)) if n else 0
    m, p = top // 2, max(top - 1, 0) // 2
    hit = HYBRID_COMMENT.search(s.comment)
    if hit:
        m, p = int(hit.group(1)), int(hit.group(2))
        if m > MAX_XPOLY_DEGREE // 2 or p > MAX_XPOLY_DEGREE // 2:
            raise s.line.error(f"the hybrid comment {hit.group(0)!r} gives more terms than "
                               f"the extended polynomial's degree {MAX_XPOLY_DEGREE} holds")
    a = [terms.get((2 * i, 0), 0.0) for i in range(1, m + 1)]
    bx = [terms.get((2 * j + 1, 0), 0.0) for j in range(1, p + 1)]
    by = [terms.get((0, 2 * j + 1), 0.0) for j in range(1, p + 1)]
    expected = xpoly_terms(a, bx, by)
    # Terms absent from the file count as 0: an x² term alone (a cylinder) misses its y².
    for key in sorted(set(terms) | set(expected)):
        v = terms.get(key, 0.0)
        e = expected.get(key, 0.0)
        d = sum(key)
        scale = max(abs(a[d // 2 - 1]) if d % 2 == 0 and 0 < d // 2 <= m else 0.0, abs(e))
        if abs(v - e) > 1e-9 * scale:
            where = s.xdat.get(term_index(*key) + 2, (0, s.type_line or s.line))[1]
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


def _fields(f: ZmxFile, strict: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """The field values as written: angles (deg) or paraxial image heights (lens units),
    and the fields' vignetting factors ``[F, 5]`` (``Lens.vignetting``) or None."""
    count = None
    if f.ftyp is not None and len(f.ftyp.tokens) > 3:
        count = f.ftyp.int(3, "number of fields (FTYP's fourth value)", lo=1)
    # Older Zemax (before XFLN/YFLN, which list 12 values padded with zeros) wrote the
    # fields as XFLD/YFLD, exactly one value a field: a file with only those has them all.
    yln = f.yfln if f.yfln is not None else f.yfld
    xln = f.xfln if f.yfln is not None or f.xfld is None else f.xfld
    if yln is None:
        if xln is not None:
            raise xln.error(f"{xln.tokens[0]} (x fields) without the y fields "
                            f"(YFLN or YFLD) of the same fields")
        return np.zeros(1), zmx_system.vignetting(f.vignetting, 1)
    ys = [yln.float(i, "y field") for i in range(1, len(yln.tokens))]
    xs = [xln.float(i, "x field") for i in range(1, len(xln.tokens))] if xln else []
    if count is None and yln is f.yfld:
        count = max(1, len(ys))
    if count is None:
        count = max(1, max((i + 1 for i, v in enumerate(ys) if v != 0), default=1))
    # Zemax writes one value a field (or 12, a field each, padded with zeros) on every
    # field line: a line with fewer values than the fields the y line defines is cut short,
    # and its missing values are not known (refused, naming the line).
    defined = min(count, len(ys))
    if xln is not None:
        zmx_system.values_for_fields(xln, len(xs), defined, "x field angles or heights")
    if len(ys) < count:
        report(strict, f"{f.path}:{yln.number}: FTYP announces {count} fields, "
                        f"{yln.tokens[0]} gives {len(ys)}; the fields it does not give are "
                        f"read as 0 (on axis)")
        ys += [0.0] * (count - len(ys))
    vignetting = zmx_system.vignetting(f.vignetting, count, defined=defined)
    xs = (xs + [0.0] * count)[:count]
    ys = ys[:count]
    if f.fwgn is not None:
        given = [f.fwgn.float(i, "field weight", lo=0) for i in range(1, len(f.fwgn.tokens))]
        zmx_system.values_for_fields(f.fwgn, len(given), defined, "field weights")
        zmx_system.unequal_weights(f.fwgn, "fields", given[:count])
    if any(x != 0 for x in xs):
        return np.stack([np.array(xs), np.array(ys)], axis=-1), vignetting
    return np.array(ys, np.float64), vignetting


def _check_field_angles(f: ZmxFile, fields) -> None:
    """The ``Lens`` checks these too, but here the message names the file and line."""
    yln = f.yfln if f.yfln is not None else f.yfld
    xln = f.xfln if f.yfln is not None or f.xfld is None else f.xfld
    a = np.asarray(fields)
    for values, ln in ([(a, yln)] if a.ndim == 1 else [(a[:, 0], xln), (a[:, 1], yln)]):
        with _at_line(ln):
            checks.field_angles(values, ln.tokens[0] if ln else f"{f.path}: fields",
                                "field angles")


def _wavelengths(f: ZmxFile) -> tuple[np.ndarray, int, list]:
    count = None
    if f.ftyp is not None and len(f.ftyp.tokens) > 4:
        count = f.ftyp.int(4, "number of wavelengths (FTYP's fifth value)", lo=1)
    if f.wavm:
        n = count if count is not None else max(f.wavm)
        missing = [i for i in range(1, n + 1) if i not in f.wavm]
        if missing:
            ln = f.ftyp or next(iter(f.wavm.values()))[1]
            raise ln.error(f"no WAVM line for wavelength {missing[0]}")
        wl = [f.wavm[i][0] for i in range(1, n + 1)]
        lines = [f.wavm[i][1] for i in range(1, n + 1)]
        weights = [ln.float(3, "wavelength weight", lo=0) for ln in lines if len(ln.tokens) > 3]
        if len(weights) == n:
            zmx_system.unequal_weights(lines[0], "wavelengths", weights)
    elif f.wavl is not None:
        wl = [f.wavl.float(i, "wavelength") for i in range(1, len(f.wavl.tokens))]
        wl = wl[:count] if count is not None else [w for w in wl if w != 0]
        lines = [f.wavl] * len(wl)
        if f.wwgt is not None:
            given = [f.wwgt.float(i, "wavelength weight", lo=0)
                     for i in range(1, len(f.wwgt.tokens))]
            zmx_system.unequal_weights(f.wwgt, "wavelengths", given[:len(wl)])
    else:
        wl, lines = [0.55], [None]  # Zemax's default wavelength
    for w, ln in zip(wl, lines, strict=True):
        if not w > 0:
            raise ln.error("wavelengths must be > 0 (µm)")
        with _at_line(ln):
            checks.wavelengths(checks.NoMaterials, np.array([w]),
                               ln.tokens[0] if ln else "WAVM", "wavelength")
    primary = 0
    if f.pwav is not None:
        primary = f.pwav.int(1, "primary wavelength number") - 1
        if not 0 <= primary < len(wl):
            raise f.pwav.error(f"primary wavelength must be 1..{len(wl)}")
    return np.array(wl, np.float64), primary, lines


@contextlib.contextmanager
def _at_line(ln):
    """A ValueError raised inside names the file and ``ln`` (if any)."""
    try:
        yield
    except ValueError as e:
        raise (e if ln is None else ln.error(str(e))) from None


def _check_structure(f: ZmxFile, text: str, strict: bool) -> None:
    """Refuse a file that is cut off or has incomplete surface blocks; report unknown keywords.

    Zemax writes CURV and DISZ in every SURF block and ends each line with a line break, so
    a file with a ``VERS`` line missing any of those was cut off. (Its TYPE line may be
    missing: a STANDARD surface, as some vendors' files write it.) Any file needs a
    DISZ for every lens surface (a missing one is not read as 0; the object's means
    infinity), and its last block is the image, whose thickness is 0: a last block with a
    DISZ other than 0 is a lens surface of a file that was cut short. A last line without a
    line break is reported unless jaxlens ignores it (a vendor's file ending on MOFF).
    """
    path = f.path
    if len(f.surfs) < 3:
        raise ValueError(
            f"{path}: a lens needs an object, at least one surface and an image "
            f"(found {len(f.surfs)} SURF blocks)"
        )
    img = f.surfs[-1]
    for s in f.surfs:
        body = s is not img and s is not f.surfs[0]  # a missing object DISZ means infinity
        need = ("CURV", "DISZ") if f.zemax else ("DISZ",) if body else ()
        missing = [k for k in need if k not in s.keys]
        if missing:
            what = "the image surface" if s is img else f"surface {s.number}"
            why = []
            if "DISZ" in missing:
                why.append("every surface needs its thickness")
            if f.zemax:
                why.append("Zemax writes CURV and DISZ in every block, so a file with a VERS "
                           "line that lacks one was cut off")
            raise s.line.error(
                f"{what} has no {' or '.join(missing)} line ({'; '.join(why)}); the file "
                f"may be truncated")
    if img.disz_line is not None and img.disz != 0:
        raise img.disz_line.error(
            f"the last surface, which a .zmx file makes the image, has thickness {img.disz:g}; "
            f"the image surface's is 0. The file may be truncated after surface {img.number}")
    lines = text.splitlines() or [""]
    # A last line jaxlens ignores cannot change the lens if cut; nor can the image surface's
    # DISZ (0 or refused above; every prefix of its number that parses is 0 too, and no ray
    # crosses it), where writers that join lines without a final break end (VERS 240000
    # files of a lens-form generator, tangericm/optical-design).
    last_is_image_disz = img.disz_line is not None and img.disz_line.number == len(lines)
    # Spaces after the last line break (a writer's indentation, '    ' in a DeepLens fork's
    # files) end the file at a line boundary as surely as the break itself.
    if (not text.rstrip(" \t").endswith(("\n", "\r")) and not last_is_image_disz
            and (lines[-1].split() or [""])[0] not in IGNORED_KEYWORDS):
        report(strict, f"{path}:{len(lines)}: the file does not end with a line break; it "
                        f"may be truncated: {lines[-1].strip()!r}")
    for s in f.surfs:
        for n, ln in sorted(s.psolve.items()):
            v = s.parm.get(n, (0.0, None))[0]
            report(strict, f"{path}:{ln.number}: {ln.text.strip()!r} on surface {s.number} is a "
                            f"solve of its PARM {n} that reads no surface (source "
                            f"{ln.tokens[2]}: not a pickup; jaxlens cannot tell which solve): "
                            f"the file's PARM {n} = {v!r}, solved for the configuration saved, "
                            f"is kept and not solved again")
    for ln in f.comments:
        report(strict, f"{path}:{ln.number}: a comment line ('!', as in a Zemax macro) "
                        f"skipped; OpticStudio writes none in a .zmx file, so the file was "
                        f"written by hand or by another program: {ln.text.strip()!r}")
    for ln in f.unknown:
        if ln.tokens[0] in KNOWN_VALUES:
            report(strict, f"{path}:{ln.number}: {ln.tokens[0]} with a value jaxlens has not "
                            f"seen in real files (an OpticStudio setting whose effect is not "
                            f"documented; it may change the lens): {ln.text.strip()!r}")
            continue
        report(strict, f"{path}:{ln.number}: unknown keyword {ln.tokens[0]!r} ignored (not "
                        f"one jaxlens reads; a keyword cut off mid-word means a truncated "
                        f"file): {ln.text.strip()!r}")


def _obscurations(body, u) -> tuple:
    """``Lens.obscurations`` from OBSC lines and annular CLAP lines (the centre of an annular
    aperture, inside its minimum radius, blocks like a central obscuration)."""
    out = []
    for i, s in enumerate(body):
        if s.obsc is not None and s.clap_min is not None:
            raise s.clap_min.error("an annular aperture (CLAP) and an obscuration (OBSC) on one "
                                   "surface are not supported (one blocked zone per surface)")
        if s.type == "COORDBRK" and (s.obsc is not None or s.clap_min is not None):
            raise (s.obsc or s.clap_min).error(
                "a coordinate break has no aperture, so this obscuration would block nothing "
                "(jaxlens traces no aperture on a COORDBRK); put it on the surface it blocks")
        if s.obdc is not None:  # decentered: Lens.apertures (_apertures)
            continue
        if s.obsc is not None:
            out.append((i, s.obsc.float(1, "") * u, s.obsc.float(2, "") * u))
        elif s.clap_min is not None:
            out.append((i, 0.0, s.clap_min.float(1, "") * u))
    return tuple(out)


def _apertures(surfs, u) -> tuple:
    """``Lens.apertures`` from SQAP/ELAP/SQOB/ELOB lines and decentered (OBDC) CLAP and OBSC
    lines, for ``surfs`` = the lens surfaces and the image. The decenter moves every
    aperture of its surface; a surface with such apertures clips at them only."""
    out = []
    for i, s in enumerate(surfs):
        dx, dy = ((s.obdc.float(1, "") * u, s.obdc.float(2, "") * u) if s.obdc is not None
                  else (0.0, 0.0))
        for ln in s.shaped:
            shape, blocks = SHAPES[ln.tokens[0]]
            out.append((i, Aperture(shape, ln.float(1, "") * u, ln.float(2, "") * u, dx, dy,
                                    blocks)))
        moved = bool(s.shaped)
        if s.clap and (moved or s.obdc is not None):  # the semi-diameter does not clip
            out.append((i, Aperture.circle(s.clap * u, dx, dy)))
            moved = True
        if s.obdc is None:  # centred obscurations stay in Lens.obscurations
            continue
        if s.clap and s.clap_min is not None:  # the blocked centre of an annulus
            out.append((i, Aperture.circle(s.clap_min.float(1, "") * u, dx, dy, True)))
        if s.obsc is not None:
            if s.obsc.float(1, "") != 0:
                raise s.obsc.error("a decentered (OBDC) annular obscuration (OBSC with minimum "
                                   "radius > 0) is not supported; decentered obscurations are "
                                   "discs (OBSC 0 r)")
            out.append((i, Aperture.circle(s.obsc.float(2, "") * u, dx, dy, True)))
            moved = True
        # A floating aperture (FLAP) is the centred semi-diameter; refuse a decenter of it
        # rather than guess. A surface that clips nothing has nothing for it to move.
        if not moved and math.isfinite(_sd(s, 1.0)):
            raise s.obdc.error("a decenter (OBDC) of a floating aperture (FLAP, the "
                               "semi-diameter) is not supported; give the surface a CLAP, "
                               "SQAP or ELAP for it to move")
    return tuple(out)


def _check_image_medium(f: ZmxFile, body: list) -> None:
    """Warn when the image surface names a medium other than image space's (the last
    surface's GLAS): image space is what the rays cross, so that is what jaxlens uses."""
    img = f.surfs[-1]
    if img.glas is None:
        return
    def named(ln):  # a model glass is its nd and Vd
        t = [x.upper() for x in ln.tokens[1:]]
        return " ".join(t[:1] + t[3:5]) if t[0] == "___BLANK" else t[0]

    medium = [s for s in body if not _keeps_medium(s)]  # mirrors, breaks: the medium before
    src = medium[-1] if medium else f.surfs[0]
    last = named(src.glas) if src.glas is not None else "AIR"
    if named(img.glas) != last:
        warnings.warn(f"{f.path}:{img.glas.number}: the image surface names {named(img.glas)}"
                      f" but image space (the GLAS of surface {src.number}) is {last}; "
                      f"jaxlens uses {last}", ZmxWarning, stacklevel=3)


def loads(text: str, path: str = "<zmx>", *, strict: bool = False,
          unknown_glass: str = "error", config: int | None = None) -> Lens:
    """A ``Lens`` from the text of a ``.zmx`` file (``path`` locates side AGF catalogs).

    Args:
        text: The file's text.
        path: The file name, for messages and side AGF catalogs.
        strict: Refuse unknown keywords, ``!`` comment lines (which OpticStudio never
            writes) and a last line without a line break (a truncated file); by default
            they give a ``ZmxWarning``. Incomplete surface blocks are always refused.
        unknown_glass: ``"error"`` refuses a glass in no catalog; ``"model"`` uses a
            ``ModelGlass`` of its GLAS line's nd and Vd instead (a ``ZmxWarning``).
        config: For a multi-configuration file (``MNUM``), the configuration to read,
            1-based as in Zemax; ``None`` (default) reads the active one, which is what the
            file's surfaces hold. Another one applies its operands (``jaxlens.io.zmx_config``
            lists which); an operand jaxlens cannot apply is refused, naming its line.

    Raises:
        ValueError: On a malformed, incomplete or truncated file (the message names the
            file and the line), an unknown glass, or wavelengths, fields or materials out
            of range.
    """
    f = parse(text, path)
    try:
        zmx_config.check_pickups(f)
        zmx_config.select(f, config, strict)
        return _lens(f, text, path, strict, unknown_glass)
    except ValueError as e:
        if str(e).startswith(path):
            raise
        raise ValueError(f"{path}: {e}") from None
    except ArithmeticError as e:  # a value that overflows once scaled: a file, not a bug
        raise ValueError(f"{path}: a value out of range ({e})") from None


def _lens(f: ZmxFile, text: str, path: str, strict: bool, unknown_glass: str) -> Lens:
    _check_structure(f, text, strict)
    u = f.unit
    glasses = GlassResolver(path, f.gcat, strict, unknown_glass)
    obj, body, img = f.surfs[0], f.surfs[1:-1], f.surfs[-1]
    surfaces, thick, mats, mirrors = [], [], [], []
    for s in (obj, img):
        if _is_mirror(s):
            raise s.glas.error("the object or image surface cannot be a mirror")
    obj_mat = glasses.get(obj.glas) if obj.glas is not None else Air()
    for i, s in enumerate(body):
        surfaces.append(_surface(s, u))
        if math.isinf(s.disz):
            raise s.disz_line.error("only the object surface may have an infinite thickness")
        if not abs(s.disz * u) < INFINITE_OBJECT_MM:
            raise s.disz_line.error(f"a thickness must be below {INFINITE_OBJECT_MM:g} mm "
                                    f"in size (Zemax's infinity), got {s.disz * u:g} mm")
        thick.append(s.disz * u)
        if _is_mirror(s):
            if s.type == "COORDBRK":
                raise s.glas.error("a coordinate break cannot be a mirror")
            mirrors.append(i)
        if _keeps_medium(s):
            if s.glas is not None and not _is_mirror(s):
                raise s.glas.error("a coordinate break keeps the medium before it; it takes no "
                                   "GLAS")
            mats.append(mats[-1] if mats else obj_mat)
        else:
            mats.append(glasses.get(s.glas) if s.glas is not None else Air())
    zmx_system.environment(f.envd, [obj_mat, *mats], strict)
    stops = [i for i, s in enumerate(body) if s.stop]
    for s in (obj, img):
        if s.stop:
            raise s.line.error("the object or image surface cannot be the stop")
    if len(stops) > 1:
        raise body[stops[1]].line.error("more than one STOP surface")
    stop = stops[0] if stops else 0
    if img.type not in ("STANDARD", "EVENASPH", "ODDASPHE", "TILTSURF"):
        raise (img.type_line or img.line).error(
            "the image surface must be STANDARD, EVENASPH, ODDASPHE or TILTSURF")
    dist = obj.disz * u if obj.disz_line is not None else math.inf
    if dist >= INFINITE_OBJECT_MM:
        dist = math.inf  # Zemax's convention; a finite 1e20 mm would need ray directions of
        # relative size 1e-20, which no float can aim
    # Below 0: a virtual object, the point that the object-space beam converges on, -dist
    # after surface 1 (Zemax 5.2's pulse-front-tilt bench, krishk97/Zemax-DLA-SLM: DISZ -1000).
    if dist != math.inf and not (dist != 0 and abs(dist) < INFINITE_OBJECT_MM):
        raise (obj.disz_line or obj.line).error(
            f"the object thickness must be nonzero and below {INFINITE_OBJECT_MM:g} mm in "
            f"size, or INFINITY (negative: a virtual object after surface 1), got "
            f"{obj.disz:g} lens units")
    zmx_surfaces.check_object_plane(obj, dist)
    wl, primary, wl_lines = _wavelengths(f)
    _check_image_medium(f, body)
    aim = zmx_system.ray_aiming(f.raim)
    if f.aperture is not None and f.aperture[0] == "float":  # the stop's size is the aperture
        aim = zmx_system.float_by_stop_aim(aim)
    field_type = zmx_system.field_type(f.ftyp)
    telecentric = zmx_system.object_telecentric(f.ftyp)
    if telecentric:
        aim = zmx_system.check_telecentric(f.ftyp, field_type, f.aperture, dist, aim)
    fields, vignetting = _fields(f, strict)
    if field_type == 0:  # angles (deg); heights are converted to angles later
        _check_field_angles(f, fields)
    lens = Lens(
        surfaces=tuple(surfaces),
        thickness=_arr(np.array(thick, np.float64)),
        materials=tuple(mats),
        stop=stop,
        epd=_arr(1.0),
        fields=_arr(fields if field_type == 0 else fields * u if telecentric
                    else np.zeros_like(fields)),
        object_na=_arr(TELECENTRIC_SEED_NA) if telecentric else None,
        wavelengths=_arr(wl),
        primary=primary,
        object_distance=_arr(dist),
        object_material=obj_mat,
        image=_surface(img, u),
        sensor=zmx_surfaces.sensor(img, u),
        name=f.name,
        mirrors=tuple(mirrors),
        obscurations=_obscurations(body, u),
        apertures=_apertures(body + [img], u),
        vignetting=None if vignetting is None else _arr(vignetting),
        afocal_image=zmx_system.afocal_image_space(f.ftyp),
        aim=aim,
        # Zemax reaches every surface after the first along the ray's line, going back where
        # it must (surfaces that cross within the beam, a stop inside a deep concave surface).
        negative_propagation=True,
        travel_senses=_travel_senses(surfaces, mirrors, body),
    )
    # Before the paraxial work of the aperture: values the lens cannot be traced with.
    for w, ln in zip(wl, wl_lines, strict=True):
        with _at_line(ln):
            checks.wavelengths(lens, np.array([w]), ln.tokens[0] if ln else f"{path}: WAVM",
                               "wavelength")
    checks.material_indices(lens, wl, path)
    if telecentric and field_type in (2, 3):
        try:
            lens = (zmx_system.heights_from_paraxial_image_heights if field_type == 2 else
                    zmx_system.heights_from_real_image_heights)(lens, fields * u)
        except ValueError as e:
            raise f.ftyp.error(str(e)) from None
    elif field_type in (1, 2, 3) and not telecentric:
        to_angles = {1: zmx_system.angles_from_object_heights,
                     2: zmx_system.angles_from_paraxial_image_heights,
                     3: zmx_system.angles_from_real_image_heights}[field_type]
        try:
            lens = to_angles(lens, fields * u)
        except ValueError as e:
            raise f.ftyp.error(str(e)) from None
    if not telecentric:
        checks.field_angles(np.asarray(lens.fields), f"{path}: XFLN/YFLN", "field angles")
    # After the fields are angles (image-height fields were on axis before); the beam's
    # radius on a PARAXIAL surface is its DIAM (OpticStudio's automatic one is the beam's).
    zmx_surfaces.check_opd_modes(lens, {
        i: (zmx_surfaces.paraxial_surface(s, u, math.inf)[1], s.type_line or s.line,
            s.diam[0] * u if s.diam and s.diam[0] > 0 else math.inf)
        for i, s in enumerate(body) if s.type == "PARAXIAL"}, strict=strict)
    if f.aperture is None and f.pupd is not None:
        raise f.pupd.error("this aperture type is not supported; use ENPD, FNUM, FLOA or OBNA")
    if f.aperture is None:
        raise ValueError(
            f"{path}: no aperture (ENPD, FNUM, FLOA or OBNA line); OpticStudio writes one in "
            f"every file's header, so a file without one was written by hand or another tool. "
            f"Add one after the UNIT line: 'ENPD d' (entrance-pupil diameter in lens units), "
            f"'FNUM N' (image-space F-number) or 'FLOA' (the stop surface's semi-diameter)")
    kind, value, ln = f.aperture
    try:
        if telecentric and kind != "float":
            return apply_object_na(lens, **{"na" if kind == "obna" else "cone_deg": value})
        if kind in ("obna", "cone", "wfno"):
            epd = (zmx_system.epd_from_working_fnum(lens, value) if kind == "wfno" else
                   zmx_system.epd_from_object_na(lens, value, kind == "cone"))
            return apply_aperture(lens, epd=epd)
        if kind == "epd":
            if not value > 0:
                raise ln.error("entrance pupil diameter must be > 0 (OpticStudio's new, empty "
                               "lens has ENPD 0: it opens, but no ray passes a pupil of size "
                               "0); give the pupil's diameter in lens units, or FNUM or FLOA")
            return apply_aperture(lens, epd=value * u)
        if kind == "fnum":
            if not value > 0:
                raise ln.error("F/# must be > 0")
            return apply_aperture(lens, fnum=value)
        if body[stop].shaped or body[stop].obdc is not None:
            raise ln.error("FLOA (pupil set by the stop size) needs a centred circular stop "
                           "aperture; the STOP surface has a decentered (OBDC) or rectangular/"
                           "elliptical one. Give the pupil with ENPD, FNUM or OBNA")
        sd = body[stop].clap if body[stop].clap else (body[stop].diam or (0.0,))[0]
        if not sd > 0:
            raise ln.error(
                f"FLOA needs a DIAM or CLAP (stop semi-diameter) on the STOP surface "
                f"(surface {stop + 1}, line {body[stop].line.number}): its semi-diameter sets "
                f"the pupil, and the file gives none, so the pupil's size is not in the file "
                f"(DeepLens's .zmx writer, for one, writes its aperture stop so; the size is in "
                f"the lens file it was written from); add 'DIAM r 1 0 0 1' (r in lens units) "
                f"to the STOP surface, or give ENPD or FNUM")
        if telecentric:
            return apply_object_na(lens, stop_semi_diameter=sd * u)
        return apply_aperture(lens, stop_semi_diameter=sd * u)
    except ValueError as e:
        if str(e).startswith(path):
            raise
        raise ln.error(str(e)) from None


def _travel_senses(surfaces: list, mirrors: list, body: list):
    """``Lens.travel_senses`` from the frames (``optics.travel``): None where they follow the
    mirror count, as Zemax writes a fold (+45°, the mirror, +45°, negative thicknesses
    after it); the senses where breaks turn a frame round with the light (Quadoa's export
    of a prism: −45°, the mirror with its thickness along its own axis, +135° with a
    decenter, positive thicknesses after it). Where the axis ray (down the object's axis,
    reflected about each mirror's vertex normal) travels across a surface's frame, no
    paraxial trace follows it and the file is refused naming that surface's line."""
    for i, c in enumerate(travel.axis_cosines(surfaces, mirrors)[1:]):
        if abs(c) <= travel.AXIS_ACROSS_TOL:
            raise body[i].line.error(
                "light leaves this surface travelling across its axis: a coordinate break "
                "turns the frame by 90 degrees to the light, so EFL, image heights and F/# "
                "have no paraxial axis to follow (turn the frame with the light: for a "
                "45-degree fold, a 45-degree break on each side of the mirror)")
    return travel.turned_senses(surfaces, mirrors)


def load_zmx(path: str | os.PathLike, *, strict: bool = False,
             unknown_glass: str = "error", config: int | None = None) -> Lens:
    """Read a Zemax ``.zmx`` lens file (UTF-16 or UTF-8); options as for :func:`loads`."""
    path = input_file(path, "load_zmx", "lens file")
    with open(path, "rb") as fh:
        raw = fh.read()
    return loads(decode(raw, path), path, strict=strict, unknown_glass=unknown_glass,
                 config=config)


def configurations(path: str | os.PathLike) -> dict:
    """The configurations of a ``.zmx`` file: ``count``, ``active`` (1-based; what its
    surfaces hold) and ``operands``, one ``{"operand", "param", "values"}`` per operand with
    its value text in each configuration (see ``jaxlens.io.zmx_config``). A file without
    ``MNUM`` has one configuration and no operands."""
    path = input_file(path, "configurations", "lens file")
    with open(path, "rb") as fh:
        raw = fh.read()
    return zmx_config.describe(parse(decode(raw, path), path))
