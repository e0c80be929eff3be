"""Run a folder of Zemax ``.zmx`` files through jaxlens (and optiland, where installed).

For each file: does jaxlens load it (or refuse it, with the message), its image-space EFL in
mm (|n′|/Φ; optiland reports n′/Φ in the file's lens units, converted here to mm with the
file's UNIT line; n′/Φ is negative after an odd number of mirrors, and the comparison takes
that sign into account), whether ``load → save → load`` is exact, and, with optiland
installed: optiland's EFL of the original file and of the file jaxlens wrote, the relative
EFL difference, and whether optiland reads the written file with jaxlens's clipping (CLAP
radii) and image-space medium. A multi-configuration file's EFL is also given in each
configuration (jaxlens alone; optiland reads no configuration rows). Where a file has Zemax
2006 single-value header lines (which optiland 0.6.3 fails on) or ``GLAS AIR`` lines
(optiland's AIR has index 1.000277, Zemax's and jaxlens's 1), optiland reads a copy without
them, and the table says so; a ``TOROIDAL`` surface's PARM lines move one up in that copy
(optiland 0.6.3 reads Zemax's PARM n from PARM n+1). Two infinite EFLs (no power: a window,
a flat mirror) agree. A file with an afocal image space (FTYP's seventh value 1,
``Lens.afocal_image``) has an EFL that is the inverse of a residual power, not a design
value: its difference is shown but not counted among the agreements. Nor is the EFL of a
file with an r² term (EVENASPH PARM 1, TOROIDAL PARM 2 ≠ 0): Zemax and jaxlens count it in
the paraxial power (c + 2a₁), optiland 0.6.3's paraxial trace leaves it out
(tests/test_paraxial_asphere.py).

    python tools/check_corpus.py /tmp/corpus            # a table
    python tools/check_corpus.py /tmp/corpus --json     # one JSON record a file
    python tools/check_corpus.py /tmp/corpus --strict   # read as `jaxlens report` does
    python tools/check_corpus.py /tmp/corpus --unknown-glass model   # model glasses (nd, Vd)
                                                # for glasses no catalog holds

The ``same n`` column gives optiland's EFL again with jaxlens's index in every medium (at
the primary wavelength), so a difference there is geometry, not glass data: the catalogs
differ (an old SCHOTT glass's index by 1e-6 to 3e-5 between the two), and optiland 0.6.3
takes a substitution-solved glass (``GLAS name 3 …``) from the line's stale nd and Vd.

optiland is optional (it is not a jaxlens dependency); without it its columns are skipped.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import inspect
import io
import json
import math
import os
import sys
import tempfile
import warnings

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.io.zmx import configurations, decode, load_zmx  # noqa: E402
from jaxlens.io.zmx_parse import UNITS  # noqa: E402

try:  # optional
    import optiland  # noqa: F401
    from optiland.fileio import load_zemax_file
except ImportError:
    load_zemax_file = None

EFL_RTOL = 1e-6


def lens_unit_mm(path: str) -> float:
    """The millimetres in one lens unit of a .zmx file (its UNIT line; MM without one)."""
    with open(path, "rb") as fh:
        text = decode(fh.read(), path)
    for line in text.splitlines():
        t = line.split()
        if len(t) > 1 and t[0] == "UNIT":
            return UNITS.get(t[1].upper(), 1.0)
    return 1.0


OLD_LINES = (
    "XFLD",
    "YFLD",
    "FWGT",
    "ZVDX",
    "ZVDY",
    "ZVCX",
    "ZVCY",
    "ZVAN",
    "WAVL",
    "WAVN",
    "WWGT",
    "WWGN",
)
"""Zemax 2006 header lines (one value a field or wavelength, beside the XFLN/YFLN/WAVM lines
that hold the same data) that optiland 0.6.3 fails on (IndexError)."""


def optiland_copy(path: str) -> tuple[str, list[str]]:
    """The text optiland reads for a file, and what was changed: the ``OLD_LINES`` dropped
    where the file has the newer lines (XFLN/WAVM), ``GLAS AIR`` lines dropped (optiland
    takes AIR as air of index 1.000277 relative to vacuum, where Zemax's and jaxlens's AIR is
    1, the index unit; a surface without GLAS is air in all three), and a TOROIDAL surface's
    ``PARM n`` written as ``PARM n+1`` (optiland 0.6.3 reads the radius of rotation, Zemax's
    PARM 1, from PARM 2 and the y coefficients, Zemax's PARM 2..9, from PARM 3..10), and a
    coordinate break with an order flag written as breaks without one
    (``split_order_flag_breaks``)."""
    with open(path, "rb") as fh:
        lines = decode(fh.read(), path).splitlines()
    lines, split = split_order_flag_breaks(lines)
    keys = {ln.split()[0] for ln in lines if ln.split()}
    newer = "XFLN" in keys and "WAVM" in keys
    toroids = _toroidal_surfaces(lines)
    out, changed, surf = [], [], None
    for ln in lines:
        tok = ln.split()
        if tok[:1] == ["SURF"] and len(tok) > 1:
            surf = tok[1]
        if newer and tok and tok[0] in OLD_LINES:
            changed.append("Zemax 2006 single-value lines dropped")
            continue
        if tok[:2] == ["GLAS", "AIR"] and len(tok) == 2:
            changed.append("GLAS AIR dropped")
            continue
        if surf in toroids and tok[:1] == ["PARM"] and len(tok) > 2 and tok[1].isdigit():
            ln = f"  PARM {int(tok[1]) + 1} {' '.join(tok[2:])}"
            changed.append("TOROIDAL PARM n written as PARM n+1")
        out.append(ln)
    return "\n".join(out) + "\n", sorted(set(changed + ([SPLIT_NOTE] if split else [])))


SPLIT_NOTE = "coordinate breaks with PARM 6 ≠ 0 written as order-0 breaks"


def split_order_flag_breaks(lines: list[str]) -> tuple[list[str], bool]:
    """The lines of a .zmx file with every coordinate break whose order flag (``PARM 6``) is
    not 0 written as order-0 breaks that move the axes the same way, and whether any was.

    optiland 0.6.3 reads a ``COORDBRK`` as decenters, then tilts about x, y and z, whatever its
    ``PARM 6`` says. Zemax's order flag 1 tilts first, about z, then the new y, then the new
    x, and then decenters along the tilted axes (``jaxlens.optics.coordinates``): Kraken's
    off-axis laser telescope (round 5 of 2026-12-02) ends each fold mirror so, and optiland's
    reading of it sent the output beam 1° off with 1.2 mrad of angular spread where jaxlens's
    (and Zemax's design) is afocal to 3e-12 rad. Each such break becomes one break per
    nonzero tilt (z, then y, then x; order 0, thickness 0) and a last one with the decenters
    and the thickness; the ``SURF`` numbers after it are renumbered (references to surface
    numbers elsewhere, pickups and operands, are not: optiland reads none of them)."""
    out: list[str] = []
    changed = False
    shift = 0
    i = 0
    while i < len(lines):
        tok = lines[i].split()
        if not (tok[:1] == ["SURF"] and len(tok) > 1 and tok[1].isdigit()):
            out.append(lines[i])
            i += 1
            continue
        j = i + 1  # the block: indented lines up to the next SURF or unindented line
        while j < len(lines) and lines[j][:1].isspace() and lines[j].split()[:1] != ["SURF"]:
            j += 1
        block = lines[i + 1 : j]
        parm, disz, kind = {}, "0", None
        for ln in block:
            t = ln.split()
            if t[:1] == ["TYPE"] and len(t) > 1:
                kind = t[1]
            elif t[:1] == ["PARM"] and len(t) > 2 and t[1].isdigit():
                parm[int(t[1])] = float(t[2])
            elif t[:1] == ["DISZ"] and len(t) > 1:
                disz = t[1]
        number = int(tok[1]) + shift
        if kind != "COORDBRK" or parm.get(6, 0.0) == 0:
            out.append(f"SURF {number}")
            out += block
            i = j
            continue
        changed = True
        steps = [(p, parm.get(p, 0.0)) for p in (5, 4, 3) if parm.get(p, 0.0) != 0]
        parts = [{p: v} for p, v in steps] + [{1: parm.get(1, 0.0), 2: parm.get(2, 0.0)}]
        for k, part in enumerate(parts):
            out += [f"SURF {number + k}", "  TYPE COORDBRK", "  CURV 0"]
            out += [f"  PARM {p} {part.get(p, 0.0)!r}" for p in range(1, 7)]
            out.append(f"  DISZ {disz if k == len(parts) - 1 else '0'}")
        shift += len(parts) - 1
        i = j
    return out, changed


R2_PARM = {"EVENASPH": 1, "TOROIDAL": 2}
"""The PARM holding a surface type's r² (y²) coefficient, which optiland 0.6.3's paraxial
trace leaves out and Zemax's and jaxlens's count."""


def r2_term_surfaces(path: str) -> list[int]:
    """The surfaces (Zemax numbers) with a nonzero r² term (``R2_PARM``)."""
    with open(path, "rb") as fh:
        lines = decode(fh.read(), path).splitlines()
    out, surf, kind = [], None, None
    for ln in lines:
        tok = ln.split()
        if tok[:1] == ["SURF"] and len(tok) > 1:
            surf, kind = tok[1], None
        elif tok[:1] == ["TYPE"] and len(tok) > 1:
            kind = tok[1]
        elif (
            tok[:1] == ["PARM"]
            and len(tok) > 2
            and kind in R2_PARM
            and tok[1] == str(R2_PARM[kind])
            and float(tok[2]) != 0
            and surf.isdigit()
        ):
            out.append(int(surf))
    return sorted(set(out))


def _toroidal_surfaces(lines: list[str]) -> set[str]:
    """The numbers (as written) of the SURF blocks whose TYPE is TOROIDAL."""
    out, surf = set(), None
    for ln in lines:
        tok = ln.split()
        if tok[:1] == ["SURF"] and len(tok) > 1:
            surf = tok[1]
        elif tok[:2] == ["TYPE", "TOROIDAL"] and surf is not None:
            out.add(surf)
    return out


def optiland_efl(path: str):
    """optiland's EFL (f2) of a .zmx file in mm, the optic and a note (an error text, or what
    the copy it read changed: ``optiland_copy``), or (None, None, error text).

    optiland keeps a file's lens units (a file in inches gives its EFL in inches); jaxlens
    works in mm, so the EFL is converted with the file's UNIT line before the comparison."""
    text, changed = optiland_copy(path)
    try:
        with (
            warnings.catch_warnings(),
            contextlib.redirect_stdout(io.StringIO()),
            tempfile.TemporaryDirectory() as d,
        ):
            warnings.simplefilter("ignore")
            if changed:
                p = os.path.join(d, "copy.zmx")
                with open(p, "w", encoding="utf-8") as fh:
                    fh.write(text)
            optic = load_zemax_file(p if changed else path)
            note = f"optiland read a copy ({', '.join(changed)})" if changed else ""
            return float(np.asarray(optic.paraxial.f2())) * lens_unit_mm(path), optic, note
    except Exception as e:  # noqa: BLE001  (report whatever optiland raises)
        return None, None, f"{type(e).__name__}: {str(e)[:120]}"


def optiland_apertures(optic) -> list[float]:
    """optiland's clipping radius of each surface (inf where it has none)."""
    out = []
    for s in optic.surfaces:
        ap = getattr(s, "aperture", None)
        r = getattr(ap, "r_max", None) if ap is not None else None
        out.append(float(r) if r is not None else math.inf)
    return out


def optiland_image_index(optic, wavelength: float) -> float:
    mat = optic.surfaces[-1].material_post
    return float(np.ravel(np.asarray(mat.n(wavelength)))[0])


def _same_lens(a, b) -> bool:
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    if len(la) != len(lb) or jax.tree_util.tree_structure(a) != jax.tree_util.tree_structure(b):
        return False
    return all(
        np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True)
        for x, y in zip(la, lb, strict=True)
    )


def check_file(path: str, strict: bool = False, unknown_glass: str = "error") -> dict:
    rec: dict = {"file": os.path.basename(path)}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            lens = jl.load(path, strict=strict, unknown_glass=unknown_glass)
        rec["warnings"] = [str(w.message) for w in caught]
    except ValueError as e:
        rec.update(status="refused", message=str(e))
    except Exception as e:  # noqa: BLE001  (a crash is what this tool is for finding)
        rec.update(status="crash", message=f"{type(e).__name__}: {e}")
    else:
        rec["status"] = "loaded"
        rec["efl"] = float(jl.paraxial_data(lens).efl_image_space)
        # jaxlens reports |n′|/Φ; optiland n′/Φ with n′ < 0 after an odd number of mirrors.
        rec["odd_mirrors"] = len(lens.mirrors) % 2 == 1
        rec["afocal"] = bool(getattr(lens, "afocal_image", False))
        rec["r2_terms"] = r2_term_surfaces(path)
        rec.update(_configurations(path, strict, unknown_glass))
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "written.zmx")
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                jl.save(lens, out)
                rec["round_trip_exact"] = _same_lens(lens, jl.load(out))
            if load_zemax_file is not None:
                rec.update(_optiland_written(lens, out))
    if load_zemax_file is not None:
        efl, optic, err = optiland_efl(path)
        rec["optiland_efl"], rec["optiland_error"] = efl, err
        if efl is not None and "efl" in rec:
            sign = -1.0 if rec["odd_mirrors"] else 1.0
            efl *= _image_index_ratio(lens, optic)
            rec["rel_diff"] = efl_rel_diff(rec["efl"], sign * efl)
            same = _efl_with_our_media(optic, lens, path)
            if same is not None:
                rec["rel_diff_same_n"] = efl_rel_diff(rec["efl"], sign * same)
    return rec


def _configurations(path: str, strict: bool, unknown_glass: str) -> dict:
    """A multi-configuration file's EFL in each configuration (jaxlens alone: optiland reads
    no configuration rows), or the refusal; {} for a file of one configuration."""
    try:
        info = configurations(path)
    except ValueError as e:
        return {"active_config": None, "configs": [(None, None, str(e))]}
    if info["count"] < 2:
        return {}
    out = []
    for c in range(1, info["count"] + 1):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                lens = load_zmx(path, strict=strict, unknown_glass=unknown_glass, config=c)
            out.append((c, float(jl.paraxial_data(lens).efl_image_space), None))
        except ValueError as e:
            out.append((c, None, str(e)))
    return {"active_config": info["active"], "configs": out}


def _efl_with_our_media(optic, lens, path: str):
    """optiland's EFL (mm) with jaxlens's index in every medium at the primary wavelength
    (optiland folds coordinate breaks into the next surface; its last medium is image
    space's); None where optiland does not take the media or fails."""
    from optiland.materials import IdealMaterial

    wl = float(lens.wavelengths[lens.primary])
    idx = [abs(float(n)) for n in lens.indices(wl)]
    after = [idx[0]] + [
        idx[i + 1] for i, s in enumerate(lens.surfaces) if type(s).__name__ != "CoordinateBreak"
    ]
    after.append(after[-1])
    surfaces = optic.surfaces.surfaces
    if len(surfaces) != len(after):
        return None
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("ignore")
            for srf, n in zip(surfaces, after, strict=True):
                srf.material_post = IdealMaterial(n=n)
            return float(np.asarray(optic.paraxial.f2())) * lens_unit_mm(path)
    except Exception:  # noqa: BLE001  (optiland's failure is a missing value here)
        return None


def efl_rel_diff(ours: float, theirs: float) -> float:
    """|theirs − ours| / |ours|; 0 where both are infinite (no power in either code: the sign
    of an infinite EFL is that of a zero power's rounding, not a property of the lens); inf
    where only one is infinite."""
    if math.isinf(ours) or math.isinf(theirs):
        return 0.0 if math.isinf(ours) and math.isinf(theirs) else math.inf
    return abs(theirs - ours) / abs(ours)


def _image_index_ratio(lens, optic) -> float:
    """|n′ jaxlens| / |n′ optiland| at the primary wavelength, to put optiland's f2 on jaxlens's
    n′/Φ: optiland takes the image medium from the image surface's own GLAS (air when it has
    none), where Zemax and jaxlens take the medium after the last lens surface, so for a file
    whose image lies in glass (an eye model, a test lens) optiland's f2 is 1/Φ, not n′/Φ."""
    wl = float(lens.wavelengths[lens.primary])
    n_ours = abs(float(np.asarray(lens.materials[-1].index(wl))))
    return n_ours / abs(optiland_image_index(optic, wl))


def _optiland_written(lens, out: str) -> dict:
    """optiland on the file jaxlens wrote: EFL, clipping radii and image medium."""
    efl, optic, err = optiland_efl(out)
    if efl is None:
        return {"written_optiland_error": err}
    # The finite clipping radii in surface order (optiland may fold coordinate breaks into
    # the next surface, so surfaces are not matched one to one).
    ours = [r for r in clipping_radii(lens) if math.isfinite(r)]
    theirs = [r for r in optiland_apertures(optic) if math.isfinite(r)]
    clip_ok = len(ours) == len(theirs) and all(
        math.isclose(a, b, rel_tol=1e-12) for a, b in zip(ours, theirs, strict=True)
    )
    wl = float(lens.wavelengths[lens.primary])
    n_ours = float(np.asarray(lens.materials[-1].index(wl)))
    n_theirs = optiland_image_index(optic, wl)
    ours_efl = float(jl.paraxial_data(lens).efl_image_space)
    sign = -1.0 if len(lens.mirrors) % 2 else 1.0  # optiland's n′/Φ has n′ < 0 (odd mirrors)
    scaled = efl * _image_index_ratio(lens, optic)
    return {
        "written_optiland_efl": efl,
        "written_rel_diff": efl_rel_diff(ours_efl, sign * scaled),
        "written_clipping_same": clip_ok,
        "written_image_index_same": math.isclose(n_ours, n_theirs, rel_tol=1e-9),
    }


def clipping_radii(lens) -> list[float]:
    """jaxlens's clipping radius of each surface: its semi-diameter, or where that is
    infinite the radius of a clipping circle of ``Lens.apertures`` on it (a CLAP moved by an
    OBDC is one: jaxlens keeps it there, with its decenter, and writes it back as CLAP)."""
    circles = {}
    for i, a in getattr(lens, "apertures", ()):
        if a.shape == "circle" and not a.blocks:
            circles[i] = float(a.half_x)
    out = []
    for i, s in enumerate(lens.surfaces):
        r = float(getattr(s, "semi_diameter", math.inf))
        out.append(r if math.isfinite(r) else circles.get(i, math.inf))
    return out


def _fmt(x, spec=".10g"):
    return "-" if x is None else format(x, spec)


def _compared(rec: dict) -> bool:
    """Whether a file's EFL is comparable with optiland's (not afocal, no r² terms)."""
    return not rec.get("afocal") and not rec.get("r2_terms")


def table(records: list[dict]) -> str:
    have_optiland = load_zemax_file is not None
    head = f"{'file':42s} {'jaxlens':8s} {'EFL |n′|/Φ':>16s} {'rt':3s}"
    if have_optiland:
        head += (
            f" {'optiland EFL':>16s} {'rel diff':>9s} {'same n':>8s} {'written: EFL/clip/n′':>22s}"
        )
    rows = [head, "-" * len(head)]
    for r in records:
        line = (
            f"{r['file'][:42]:42s} {r['status']:8s} {_fmt(r.get('efl')):>16s} "
            f"{('yes' if r.get('round_trip_exact') else 'NO') if 'efl' in r else '-':3s}"
        )
        if have_optiland:
            rd = r.get("rel_diff")
            flag = "" if rd is None or rd <= EFL_RTOL or not _compared(r) else " !"
            w = (
                "-"
                if "written_rel_diff" not in r
                else f"{r['written_rel_diff']:.1e}/{'ok' if r['written_clipping_same'] else 'NO'}/"
                f"{'ok' if r['written_image_index_same'] else 'NO'}"
            )
            if "written_optiland_error" in r:
                w = "optiland failed"
            sn = r.get("rel_diff_same_n")
            line += (
                f" {_fmt(r.get('optiland_efl')):>16s} {_fmt(rd, '.1e'):>9s}{flag:2s}"
                f"{_fmt(sn, '.1e'):>8s} {w:>20s}"
            )
        rows.append(line)
        if r["status"] != "loaded":
            rows.append(f"    {r['message'][:300]}")
        if have_optiland and r.get("optiland_error"):
            rows.append(f"    optiland: {r['optiland_error']}")
        if r.get("afocal"):
            rows.append(
                "    afocal image space (FTYP): the EFL is a residual power's inverse, not compared"
            )
        if r.get("configs"):
            each = "; ".join(
                f"{c}: {_fmt(e)}" if e is not None else f"{c}: refused ({m[:80]})"
                for c, e, m in r["configs"]
            )
            rows.append(f"    configurations (the surfaces hold {r['active_config']}), EFL: {each}")
        if r.get("r2_terms") and have_optiland:
            rows.append(
                f"    r² terms on surface {', '.join(map(str, r['r2_terms']))}: optiland's "
                "paraxial trace leaves them out, EFL not compared"
            )
    n = len(records)
    loaded = sum(r["status"] == "loaded" for r in records)
    rows.append(
        f"\njaxlens loads {loaded}/{n}; refused "
        f"{sum(r['status'] == 'refused' for r in records)}; crashed "
        f"{sum(r['status'] == 'crash' for r in records)}"
    )
    if have_optiland:
        both = [r for r in records if r.get("rel_diff") is not None]
        focal = [r for r in both if _compared(r)]
        agree = sum(r["rel_diff"] <= EFL_RTOL for r in focal)
        same = sum(r.get("rel_diff_same_n", math.inf) <= EFL_RTOL for r in focal)
        rows.append(
            f"both load {len(both)} ({len(both) - len(focal)} not compared: afocal, or "
            f"r² terms); EFL agrees to {EFL_RTOL:g} relative in {agree} of {len(focal)}, "
            f"with jaxlens's indices in optiland (same n) in {same}"
        )
    else:
        rows.append("optiland not installed: its columns are skipped")
    return "\n".join(rows)


def run_folder(argv, check_file, table, description: str) -> int:
    """``TOOL FOLDER [--json]``: ``check_file`` on every ``.zmx`` in FOLDER, printed as
    ``table`` or one JSON record a file (shared with tools/check_rays.py)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("folder")
    ap.add_argument("--json", action="store_true", help="one JSON record a file")
    ap.add_argument(
        "--strict",
        action="store_true",
        help="read as `python -m jaxlens report` does: strict=True (settings "
        "jaxlens does not use are refused, not warned about)",
    )
    ap.add_argument(
        "--unknown-glass",
        choices=("error", "model"),
        default="error",
        help="jaxlens.load's unknown_glass: 'model' reads a glass no catalog holds "
        "as a model glass of its GLAS line's nd and Vd",
    )
    args = ap.parse_args(argv)
    params = inspect.signature(check_file).parameters
    if args.strict:
        if "strict" not in params:
            ap.error("--strict: this tool's check takes no strict option")
        check_file = functools.partial(check_file, strict=True)
    if args.unknown_glass != "error":
        if "unknown_glass" not in params:
            ap.error("--unknown-glass: this tool's check takes no unknown_glass option")
        check_file = functools.partial(check_file, unknown_glass=args.unknown_glass)
    if not os.path.isdir(args.folder):  # os.listdir raised with a traceback
        what = "a file" if os.path.exists(args.folder) else "missing"
        ap.error(f"folder {args.folder!r} is {what}; give a folder of .zmx files")
    files = sorted(
        os.path.join(args.folder, f) for f in os.listdir(args.folder) if f.lower().endswith(".zmx")
    )
    if not files:
        print(f"{args.folder}: no .zmx files", file=sys.stderr)
        return 2
    records = [check_file(f) for f in files]
    if args.json:
        for r in records:
            print(json.dumps(r))
    else:
        print(table(records))
    return 0


def main(argv=None) -> int:
    return run_folder(argv, check_file, table, __doc__.splitlines()[0])


if __name__ == "__main__":
    sys.exit(main())
