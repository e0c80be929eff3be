"""Trace the same real rays through a folder of Zemax ``.zmx`` files in jaxlens and optiland.

For each file both codes open (``jaxlens.load`` and optiland's ``load_zemax_file``), every
field and wavelength of the file gets a 7 × 7 grid over the paraxial entrance pupil (kept
inside the disc; its centre is the paraxial chief ray) plus the real chief ray (aimed at the
stop centre). The rays are built in jaxlens (``jaxlens.imaging.sampling``), moved back along
themselves to a plane in front of surface 1 (to the object point for a finite object), and
the same float64 origins and directions are traced by ``jaxlens.trace`` and by optiland's
``optic.surfaces.trace(RealRays(...), skip=1)``. Compared, ray by ray:

* the image-surface intercepts (x, y, z) in global coordinates (jaxlens's are mapped with
  ``coordinates.frame_of``), with every aperture removed in both codes, on the rays both
  trace (max |Δ| in mm);
* validity with the apertures each code read (``clip≠``: rays one code passes and the other
  stops) and without them (``miss≠``: missed surfaces, TIR). A mismatch names the Zemax
  surface where each code stopped the ray.

Rays whose difference has a known cause are set apart and counted, not failed: jaxlens clips
at an aperture optiland does not read (OBSC, SQAP, ELAP, SQOB, ELOB); optiland takes a
negative distance to a surface where jaxlens stops the ray (crossed surfaces outside the
clear aperture); the ray runs in a flat image plane; the ray meets the tip of an odd
asphere's cone (β1 ≠ 0), which has no normal.

To compare geometry rather than glass data, optiland's media are replaced by jaxlens's
indices at each wavelength (``Δn`` is the largest difference of optiland's own indices).
optiland ignores ``UNIT`` (it reads lengths as mm), so its rays are scaled by the file's unit.
optiland's Newton tolerance on aspheres is tightened to 1e-13. optiland 0.6.3 reads TOROIDAL
PARM n as PARM n+1; the tool sets its toroids from the file's lines. Where optiland cannot
open a file (an old one-value WAVL line, a surface without CURV, no PWAV) it reads a copy
mended for it (the note says how); so it does where a coordinate break has an order flag
(PARM 6 ≠ 0), which optiland 0.6.3 reads as 0 (``check_corpus.split_order_flag_breaks``).

    python tools/check_rays.py FOLDER            # a table
    python tools/check_rays.py FOLDER --json     # one JSON record a file

optiland is optional (it is not a jaxlens dependency); without it the script says so and stops.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import warnings

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.optics import paraxial  # noqa: E402
from jaxlens.optics.catalog import decode_zemax_text  # noqa: E402
from jaxlens.optics.coordinates import CoordinateBreak, frame_of  # noqa: E402
from jaxlens.optics.lens import unclipped  # noqa: E402
from jaxlens.tracing.forward import trace_path  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_corpus import SPLIT_NOTE, run_folder, split_order_flag_breaks  # noqa: E402

try:  # optional
    from optiland.fileio import load_zemax_file
    from optiland.materials import IdealMaterial
    from optiland.rays import RealRays
except ImportError:
    load_zemax_file = None

TOL_MM = 1e-9  # the agreement expected of two float64 tracers (spheres, conics, aspheres)
UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}


def file_text(path: str) -> str:
    with open(path, "rb") as f:
        return decode_zemax_text(f.read(), path)


def optiland_optic(path: str):
    """optiland's optic of a file, and a note. optiland 0.6.3 fails on an old one-value
    ``WAVL`` line, on a surface without ``CURV`` and without ``PWAV``; it then reads a copy
    without WAVL lines (where the file has WAVM lines), with ``CURV 0`` on such surfaces and
    ``PWAV 1`` (Zemax's default). It reads a coordinate break's order flag as 0: a file with
    one is read from a copy without (``check_corpus.split_order_flag_breaks``)."""

    def load(p):
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("ignore")
            return load_zemax_file(p)

    lines, split = split_order_flag_breaks(file_text(path).splitlines())
    try:
        if not split:
            return load(path), ""
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "copy.zmx")
            with open(p, "w", encoding="utf-8") as f:
                f.write("\n".join(lines) + "\n")
            return load(p), f"optiland read a copy ({SPLIT_NOTE})"
    except Exception as e:  # noqa: BLE001  (report whatever optiland raises)
        err = f"{type(e).__name__}: {str(e)[:120]}"
    keys = {ln.split()[0] for ln in lines if ln.split()}
    wavm = "WAVM" in keys
    out, has_curv, changed = ([], True, []) if "PWAV" in keys else (["PWAV 1"], True, ["PWAV 1"])
    for ln in lines + ["SURF"]:
        key = ln.split()[:1]
        if key == ["SURF"] and not has_curv:
            out.append("  CURV 0")
            changed.append("CURV 0 added")
        if key == ["SURF"]:
            has_curv = False
        has_curv |= key == ["CURV"]
        if key == ["WAVL"] and wavm:
            changed.append("WAVL dropped")
            continue
        out.append(ln)
    if not changed:
        return None, err
    changed += [SPLIT_NOTE] if split else []
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "copy.zmx")
        with open(p, "w", encoding="utf-8") as f:
            f.write("\n".join(out[:-1]) + "\n")
        try:
            return load(p), f"optiland read a copy ({', '.join(sorted(set(changed)))})"
        except Exception:  # noqa: BLE001
            return None, err


def surface_lines(path: str) -> dict[int, list[list[str]]]:
    """The tokens of each line of each ``SURF`` block, by Zemax surface number (read here,
    not by either code)."""
    out: dict[int, list[list[str]]] = {}
    surf = None
    for ln in file_text(path).splitlines():
        t = ln.split()
        if t[:1] == ["SURF"] and len(t) > 1:
            surf = int(t[1])
            out[surf] = []
        elif t and surf is not None:
            out[surf].append(t)
    return out


def correct_optiland_toroids(optic, blocks, numbers: list[int]) -> str:
    """optiland 0.6.3 reads a TOROIDAL surface's radius of rotation from PARM 2 and its y
    coefficients from PARM 3..10 (one PARM late; Zemax: PARM 1 and PARM 2..9). Set them from
    the file's own lines; returns a note ("" when the file has no toroid)."""
    fixed = []
    for n, lines in blocks.items():
        if ["TYPE", "TOROIDAL"] not in [t[:2] for t in lines]:
            continue
        parms = {int(t[1]): float(t[2]) for t in lines if t[0] == "PARM" and len(t) > 2}
        g = optic.surfaces.surfaces[numbers.index(n) + 1].geometry
        r = parms.get(1, 0.0)
        g.R_rot = np.asarray(np.inf if r == 0 else r)
        g.coeffs_poly_y = np.asarray([parms.get(i, 0.0) for i in range(2, 10)])
        fixed.append(str(n))
    return f"optiland's TOROIDAL PARM read corrected (surface {', '.join(fixed)})" if fixed else ""


def apertures_optiland_ignores(lines) -> str:
    """The aperture keyword of a surface that jaxlens clips at and optiland 0.6.3 does not
    read ("" if none): OBSC, SQAP, ELAP, SQOB, ELOB. (A semi-diameter, DIAM, clips in
    neither: jaxlens reads it as Zemax does, and both clip at CLAP and FLAP.)"""
    keys = {t[0] for t in lines}
    for k in ("OBSC", "SQAP", "ELAP", "SQOB", "ELOB"):
        if k in keys:
            return k
    return ""


def unit_of(path: str) -> float:
    for ln in file_text(path).splitlines():
        t = ln.split()
        if t[:1] == ["UNIT"] and len(t) > 1:
            return UNITS.get(t[1].upper(), 1.0)
    return 1.0


def launch(lens, field, wl):
    """``[m, 3]`` origins (global mm, in front of surface 1) and unit directions, and the
    normalised pupil points (the last ray is the real chief ray)."""
    grid = jl.sampling.pupil_grid(7) * (1 - 1e-9)  # a rim ray is not a tie at a rim aperture
    rays = jl.sampling.field_rays(lens, field, grid, wl, depth=lens.object_distance)
    chief = jl.sampling.field_rays(
        lens, field, jnp.zeros((1, 2)), wl, depth=lens.object_distance, aim="real"
    )
    o = np.concatenate([np.asarray(rays.origin), np.asarray(chief.origin)])
    d = np.concatenate([np.asarray(rays.direction), np.asarray(chief.direction)])
    pupil = np.concatenate([np.asarray(grid), np.zeros((1, 2))])
    if not lens.object_at_infinity:
        point = np.asarray(jl.sampling.object_point(lens, field, lens.object_distance))
        return np.broadcast_to(point, o.shape).copy(), d, pupil
    # A plane in front of surface 1's hits (a surface concave toward the object, or tilted,
    # reaches in front of its vertex).
    first = next(i for i, s in enumerate(lens.surfaces) if not isinstance(s, CoordinateBreak))
    hit = trace_path(unclipped(lens), jl.Rays(o, d, wl), upto=first)[-1].origin
    r, t = (np.asarray(a) for a in frame_of(lens, first))
    z_hit = (np.asarray(hit) @ r.T + t)[:, 2]
    zep = float(paraxial.entrance_pupil_z(lens, lens.primary_wavelength))
    z0 = min(0.0, zep, float(np.min(z_hit, initial=0.0, where=np.isfinite(z_hit)))) - 1.0
    s = (z0 - o[:, 2]) / d[:, 2]
    return o + s[:, None] * d, d, pupil


def jaxlens_image(lens, o, d, wl):
    """Global image intercepts, validity, the Zemax surface where each ray stopped (0: it
    did not), the z direction cosine of each ray arriving at the image (image frame), and
    whether the ray meets the tip of an odd asphere's cone (β_1 ≠ 0, r < 1e-9 mm), a point
    with no normal."""
    path = trace_path(lens, jl.Rays(o, d, wl))
    r, t = (np.asarray(a) for a in frame_of(lens))
    p = np.asarray(path.origin[-1]) @ r.T + t
    valid = np.asarray(path.valid)  # [surfaces + 1, m]
    stopped = np.where(valid[-1], 0, np.argmin(valid, axis=0) + 1)
    tip = np.zeros(len(o), bool)
    for i, s in enumerate(lens.surfaces):
        if isinstance(s, jl.OddAsphere) and float(s.coeffs[0]) != 0:
            tip |= np.hypot(*np.asarray(path.origin[i, :, :2]).T) < 1e-9
    return p, valid[-1], stopped, np.asarray(path.direction[-2, :, 2]), tip


def zemax_numbers(lens) -> list[int]:
    """Zemax surface numbers of optiland's surfaces (after the object): optiland folds
    coordinate breaks into the next surface."""
    real = [i + 1 for i, s in enumerate(lens.surfaces) if not isinstance(s, CoordinateBreak)]
    return real + [len(lens.surfaces) + 1]


def set_media(optic, lens, wl, own) -> float:
    """Give optiland jaxlens's index in every medium at ``wl``; returns the largest
    difference from ``own``, optiland's own materials (surface by surface)."""
    idx = [abs(float(n)) for n in lens.indices(wl)]
    after = [idx[0]] + [
        idx[i + 1] for i, s in enumerate(lens.surfaces) if not isinstance(s, CoordinateBreak)
    ]
    after.append(after[-1])  # image space
    dn = 0.0
    for s, n, mine in zip(optic.surfaces.surfaces, after, own, strict=True):
        if mine is not None:
            dn = max(dn, abs(float(np.ravel(np.asarray(mine.n(wl)))[0]) - n))
        s.material_post = IdealMaterial(n=n)
    return dn


def optiland_image(optic, o, d, wl, scale, shift):
    """Global image intercepts (mm), validity, the position (1-based in optiland's surfaces)
    where each ray stopped (0: it did not) and where it first went backward (optiland takes
    negative distances, as jaxlens does for a lens read from ``.zmx``, which sets
    ``Lens.negative_propagation``; a lens without it stops such a ray unless the surface is a
    dummy on the previous vertex plane or the gap is negative). ``shift``: optiland's global
    frame minus jaxlens's (mm)."""
    m = o.shape[0]
    rays = RealRays(*((o + shift) / scale).T.copy(), *d.T.copy(), np.ones(m), np.full(m, wl))
    sg = optic.surfaces
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        sg.trace(rays, skip=1, record=True)

        def rows(a):  # [surfaces after the object, m]
            a = np.asarray(a)
            return a[1:] if a.shape[0] == sg.num_surfaces else a

        p = np.stack([rows(sg.x), rows(sg.y), rows(sg.z)], -1) * scale - shift  # [s, m, 3]
        dirs = np.stack([rows(sg.L), rows(sg.M), rows(sg.N)], -1)
        i = rows(sg.intensity)
        step = np.concatenate([p[:1] - o, p[1:] - p[:-1]])
        back = np.sum(step * np.concatenate([d[None], dirs[:-1]]), -1) < -1e-9
        ok = np.isfinite(i) & (i > 0) & np.all(np.isfinite(p), -1)
    ok = np.cumprod(ok, axis=0).astype(bool)
    stopped = np.where(ok[-1], 0, np.argmin(ok, axis=0) + 1)
    return p[-1], ok[-1], stopped, np.where(back.any(0), np.argmax(back, axis=0) + 1, 0)


def _strip_apertures(optic):
    for s in optic.surfaces.surfaces:
        s.aperture = None


def _tighten_newton(optic):
    for s in optic.surfaces.surfaces:
        g = s.geometry
        if hasattr(g, "tol") and hasattr(g, "max_iter"):
            g.tol, g.max_iter = 1e-13, 200


def check_file(path: str) -> dict:
    rec: dict = {"file": os.path.basename(path)}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lens = jl.load(path)
    except Exception as e:  # noqa: BLE001
        return rec | {"status": "jaxlens refused", "message": f"{type(e).__name__}: {e}"[:300]}
    clipped, note = optiland_optic(path)
    if clipped is None:
        return rec | {"status": "optiland failed", "message": note}
    free, _ = optiland_optic(path)
    _strip_apertures(free)
    numbers = zemax_numbers(lens)
    if clipped.surfaces.num_surfaces != len(numbers) + 1:
        return rec | {
            "status": "surfaces differ",
            "message": f"optiland has {clipped.surfaces.num_surfaces - 1} surfaces after "
            f"the object, jaxlens {len(numbers)} besides coordinate breaks",
        }
    blocks = surface_lines(path)
    for op in (clipped, free):
        _tighten_newton(op)
        fix = correct_optiland_toroids(op, blocks, numbers)
    rec.update(
        status="compared",
        note="; ".join(x for x in (note, fix) if x),
        surfaces=len(lens.surfaces) + 1,
    )
    own = [s.material_post for s in clipped.surfaces.surfaces]
    flat_image = float(lens.image.c) == 0 and not lens.image.has_polynomial
    scale = unit_of(path)
    # Both put surface 1's vertex at 0, except optiland with a finite object and coordinate
    # breaks, which puts the object there.
    shift = np.zeros(3)
    if not lens.object_at_infinity:
        cs = clipped.surfaces.surfaces[0].geometry.cs
        shift = np.array([cs.x, cs.y, cs.z], float) * scale
        shift[2] += float(lens.object_distance)
    n_rays = n_cmp = clip_bad = miss_bad = 0
    worst = dn = 0.0
    explained: dict[str, int] = {}
    examples = []
    for field in np.asarray(lens.fields):
        for wl in np.asarray(lens.wavelengths, float):
            o, d, pupil = launch(lens, jnp.asarray(field), float(wl))
            dn = max(dn, set_media(clipped, lens, wl, own))
            set_media(free, lens, wl, own)
            pj, vj, sj, dz, tip = jaxlens_image(unclipped(lens), o, d, wl)
            po, vo, so, back = optiland_image(free, o, d, wl, scale, shift)
            _, vjc, sjc, _, _ = jaxlens_image(lens, o, d, wl)
            _, voc, soc, _ = optiland_image(clipped, o, d, wl, scale, shift)
            both = vj & vo
            n_rays += len(o)
            n_cmp += int(both.sum())
            diff = np.where(both, np.max(np.abs(pj - po), -1), 0.0)
            at_tip = tip & (diff > TOL_MM)
            if at_tip.any():
                why = "the ray meets an ODDASPHE cone's tip (β1 ≠ 0), where there is no normal"
                explained[why] = explained.get(why, 0) + int(at_tip.sum())
            worst = max(worst, float(np.max(diff[~at_tip], initial=0.0)))
            for k in np.flatnonzero((vj != vo) | (vjc != voc)):
                geometric = bool(vj[k] != vo[k])
                why = ""
                if (
                    geometric
                    and not vj[k]
                    and sj[k] == len(lens.surfaces) + 1
                    and flat_image
                    and abs(dz[k]) < 1e-12
                ):
                    why = "the ray runs in the image plane (no single intercept)"
                elif geometric and not vj[k] and back[k] and numbers[back[k] - 1] == sj[k]:
                    why = (
                        "optiland goes backward (a negative distance) to the surface where "
                        "jaxlens stops the ray (a lens without negative_propagation)"
                    )
                elif not geometric and not vjc[k] and vo[k]:
                    key = apertures_optiland_ignores(blocks.get(int(sjc[k]), []))
                    why = f"optiland ignores {key}" if key else ""
                if why:
                    explained[why] = explained.get(why, 0) + 1
                    continue
                miss_bad += geometric
                clip_bad += not geometric
                if len(examples) < 6:
                    examples.append(
                        {
                            "field": np.atleast_1d(field).tolist(),
                            "wavelength": float(wl),
                            "pupil": pupil[k].round(4).tolist(),
                            "jaxlens_stops_at": int(sjc[k]) or None,
                            "optiland_stops_at": numbers[soc[k] - 1] if soc[k] else None,
                            "without_apertures": [
                                int(sj[k]) or None,
                                numbers[so[k] - 1] if so[k] else None,
                            ],
                        }
                    )
    rec.update(
        rays=n_rays,
        compared=n_cmp,
        max_abs_diff_mm=worst,
        clip_mismatch=clip_bad,
        miss_mismatch=miss_bad,
        explained=explained,
        max_index_diff=dn,
        examples=examples,
        agree=worst <= TOL_MM and clip_bad == 0 and miss_bad == 0,
    )
    return rec


def table(records: list[dict]) -> str:
    head = (
        f"{'file':44s} {'surf':>4s} {'rays':>5s} {'cmp':>5s} {'max |Δ| mm':>10s} "
        f"{'clip≠':>5s} {'miss≠':>5s} {'Δn':>8s}  verdict"
    )
    rows = [head, "-" * len(head)]
    for r in records:
        if r["status"] != "compared":
            rows.append(f"{r['file'][:44]:44s} {r['status']}: {r['message'][:200]}")
            continue
        verdict = "agree" if r["agree"] else "DIFFER"
        rows.append(
            f"{r['file'][:44]:44s} {r['surfaces']:4d} {r['rays']:5d} {r['compared']:5d} "
            f"{r['max_abs_diff_mm']:10.1e} {r['clip_mismatch']:5d} "
            f"{r['miss_mismatch']:5d} {r['max_index_diff']:8.1e}  {verdict}"
        )
        for why, n in r["explained"].items():
            rows.append(f"    {n} ray(s) set apart: {why}")
        if r["note"]:
            rows.append(f"    note: {r['note']}")
        for e in r["examples"] if not r["agree"] else ():
            rows.append(f"    {e}")
    done = [r for r in records if r["status"] == "compared"]
    rows.append(
        f"\ncompared {len(done)}/{len(records)} files; agree to {TOL_MM:g} mm with "
        f"the same validity: {sum(r['agree'] for r in done)}"
    )
    return "\n".join(rows)


def main(argv=None) -> int:
    if load_zemax_file is None:
        print("optiland is not installed: nothing to compare with", file=sys.stderr)
        return 2
    return run_folder(argv, check_file, table, __doc__.splitlines()[0])


if __name__ == "__main__":
    sys.exit(main())
