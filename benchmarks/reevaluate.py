"""Re-evaluate exported designs with an independent tracer (optiland), beside jaxlens.

``python -m benchmarks.reevaluate experiments/classical/designs`` reads every ``.zmx`` in the
folder, evaluates it with ``jaxlens.design.evaluate`` (Table 1's definition) and traces the
same evaluation rays with optiland's numpy backend (``benchmarks.optiland_ref``): the 16 × 16
sensor fields, the 21 × 21 pupil grid (317 rays) aimed at the paraxial entrance pupil, at
every design wavelength. Ray generation and the statistic are shared; the intersections and
refractions are optiland's own. Per field the RMS spot radius pools the wavelengths about
their common centroid; a ray counts when optiland returns it finite with non-zero
intensity. optiland is not a jaxlens dependency: without it the script says so and stops.

The optiland bridge carries no clear apertures, so it tests the optical prescription; the
apertures and the self-intersection check are jaxlens's (``Evaluation.valid``). Where a ray
passes in jaxlens and fails in optiland, :func:`first_crossings` checks jaxlens's path by
brute force (a sag scan along every segment, no root finder), so a disagreement can be
traced to one tracer: optiland 0.6.3 starts Newton at the base conic's root and, on
aspheres far from their base conic, can stop at a point off the surface.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

import jax
import numpy as np


def first_crossings(lens, rays, n_scan: int = 4001) -> np.ndarray:
    """Per ray: every intersection jaxlens found is the ray's first crossing of that surface.

    A brute-force check, independent of any root finder: along each segment of the traced
    path the sag residual F(t) = z − sag(x, y) is sampled at ``n_scan`` points before the
    intersection and must keep one sign there (no earlier crossing), and F must vanish at
    the intersection. Rays must be valid in jaxlens.
    """
    import jax.numpy as jnp

    from jaxlens.tracing.forward import trace_path

    path = trace_path(lens, rays)
    zv = np.asarray(lens.vertex_z())
    u = jnp.linspace(0.0, 1.0, n_scan)[:-1]
    ok = np.ones(rays.origin.shape[:-1], bool)
    for i in range(1, len(lens.surfaces)):
        o0, d0 = path.origin[i - 1], path.direction[i - 1]
        t_hit = jnp.sum((path.origin[i] - o0) * d0, -1)
        pts = o0[..., None, :] + (u * t_hit[..., None])[..., None] * d0[..., None, :]
        z, *_ = lens.surfaces[i].sag_and_grad(pts[..., 0], pts[..., 1])
        f = np.asarray(pts[..., 2] - zv[i] - z)
        one_sign = np.all(f[..., 1:] * f[..., :1] > 0, -1)
        zh, *_ = lens.surfaces[i].sag_and_grad(path.origin[i, ..., 0], path.origin[i, ..., 1])
        on_surface = np.abs(np.asarray(path.origin[i, ..., 2] - zv[i] - zh)) < 1e-9
        ok &= one_sign & on_surface
    return ok & np.asarray(path.valid[-1])


def _optiland_field_stats(lens, spec, pupil, fields):
    """``(rms_um [F], valid_fraction [F], disputed, confirmed)`` from optiland traces of the
    evaluation rays; ``disputed`` counts rays that jaxlens passes and optiland loses,
    ``confirmed`` those of them whose jaxlens path :func:`first_crossings` confirms."""
    import jax.numpy as jnp

    from jaxlens.analysis.spots import weighted_rms
    from jaxlens.imaging.sampling import field_rays
    from jaxlens.optics.rays import Rays
    from jaxlens.tracing.forward import trace

    from . import optiland_ref

    pts, ok = [], []
    disputed = confirmed = 0
    for wl in spec.wavelengths:
        rays = jax.vmap(lambda f, wl=wl: field_rays(lens, f, pupil, wl))(jnp.asarray(fields))
        o = np.asarray(rays.origin, float).reshape(-1, 3)
        d = np.asarray(rays.direction, float).reshape(-1, 3)
        op = optiland_ref.build_optic(lens, float(wl))
        out = optiland_ref.trace(op, o, d, float(wl))
        p = optiland_ref.intercepts(out)
        good = np.all(np.isfinite(p), -1) & (np.asarray(out.i) > 0)
        flat = Rays(jnp.asarray(o), jnp.asarray(d), jnp.full(o.shape[0], float(wl)))
        ours = np.asarray(trace(lens, flat).valid)
        odd = np.flatnonzero(ours & ~good)
        if len(odd):
            sub = Rays(flat.origin[odd], flat.direction[odd], flat.wavelength[odd])
            disputed += len(odd)
            confirmed += int(np.sum(first_crossings(lens, sub)))
        pts.append(p[:, :2].reshape(len(fields), -1, 2))
        ok.append(good.reshape(len(fields), -1))
    v = np.concatenate(ok, 1)  # [F, W·M]
    p = np.where(v[..., None], np.concatenate(pts, 1), 0.0)
    rms = weighted_rms(jnp.asarray(p), jnp.asarray(v, p.dtype))  # the library's definition
    return 1e3 * np.asarray(rms), v.mean(1), disputed, confirmed


def reevaluate(folder: pathlib.Path, spec) -> dict:
    import equinox as eqx
    import jax.numpy as jnp

    import jaxlens
    from jaxlens.design.evaluate import MIN_VALID_FRACTION, evaluate, sensor_field_grid
    from jaxlens.imaging.sampling import pupil_grid

    files = sorted(folder.glob("*.zmx"), key=lambda f: (len(f.stem), f.stem))
    if not files:
        raise SystemExit(f"reevaluate: no .zmx files in {folder}")
    ang, _ = sensor_field_grid(spec)
    pupil = pupil_grid(21, jnp.float64)
    rows = []
    for f in files:
        lens = jaxlens.load(f).astype(jnp.float64)
        ev = evaluate(lens, spec)
        at_spec = eqx.tree_at(lambda x: x.epd, lens, jnp.asarray(spec.epd, jnp.float64))
        rms, frac, disputed, confirmed = _optiland_field_stats(at_spec, spec, pupil, ang)
        rows.append(dict(
            design=f.name, jaxlens_rms_mean_um=ev.rms_mean_um, jaxlens_valid=ev.valid,
            jaxlens_min_valid_fraction=float(np.min(ev.valid_fraction)),
            optiland_rms_mean_um=float(np.mean(rms)),
            optiland_min_valid_fraction=float(np.min(frac)),
            optiland_rays_ok=bool(np.all(frac >= MIN_VALID_FRACTION)),
            rays_lost_by_optiland_only=disputed, of_which_first_crossings_confirmed=confirmed,
            relative_difference=float(np.mean(rms) / ev.rms_mean_um - 1.0)))
        print(f"{f.name:14s} jaxlens {ev.rms_mean_um:7.3f} µm valid {ev.valid!s:5s} | optiland "
              f"{np.mean(rms):7.3f} µm min ray share {np.min(frac):.4f}"
              + (f" ({disputed} rays lost by optiland only; jaxlens's first crossings "
                 f"confirmed by a sag scan for {confirmed})" if disputed else ""), flush=True)
    ok = [r for r in rows if r["jaxlens_valid"] and r["optiland_rays_ok"]]
    o = np.array([r["optiland_rms_mean_um"] for r in ok])
    j = np.array([r["jaxlens_rms_mean_um"] for r in ok])
    return dict(
        folder=str(folder), designs=len(rows), valid_both=len(ok),
        optiland_rms_mean_um=float(o.mean()) if len(o) else None,
        optiland_rms_min_um=float(o.min()) if len(o) else None,
        optiland_rms_max_um=float(o.max()) if len(o) else None,
        jaxlens_rms_mean_um=float(j.mean()) if len(j) else None,
        rays_lost_by_optiland_only=sum(r["rays_lost_by_optiland_only"] for r in rows),
        of_which_first_crossings_confirmed=sum(
            r["of_which_first_crossings_confirmed"] for r in rows),
        max_abs_relative_difference=float(max(abs(r["relative_difference"]) for r in rows)),
        per_design=rows)


def main(argv=None):
    from jaxlens.experiments.runfolder import OneLineParser

    p = OneLineParser(prog="python -m benchmarks.reevaluate", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", type=pathlib.Path, help="folder of exported .zmx designs")
    p.add_argument("--out", type=pathlib.Path, default=None,
                   help="JSON file for the results (default: <folder>/../reevaluation.json)")
    a = p.parse_args(argv)
    # The arguments first, then whether optiland is installed (before: without optiland a
    # missing folder or a broken .zmx was reported only as "optiland is not installed").
    if not a.folder.is_dir():  # refused here, not after the optiland runs
        p.error(f"folder {a.folder} is not a folder")
    if not any(a.folder.glob("*.zmx")):
        p.error(f"folder {a.folder} holds no .zmx files")
    dest = a.out or a.folder.parent / "reevaluation.json"
    if dest.is_dir() or not dest.parent.is_dir():
        p.error(f"--out {dest} must be a file in an existing folder")
    from .common import foreign_result

    if dest.is_file() and (why := foreign_result(dest, "reevaluate")):  # was written over
        p.error(f"--out {dest} is not a reevaluate result ({why}), and this run would write "
                f"over it; move it away or give another path")
    jax.config.update("jax_enable_x64", True)
    import jaxlens

    for f in sorted(a.folder.glob("*.zmx")):  # before: a broken file stopped the run midway
        try:
            jaxlens.load(f)
        except (ValueError, OSError) as e:
            p.error(f"{f}: {e}" if str(f) not in str(e) else str(e))
    from . import optiland_ref

    if not optiland_ref.available():
        print("reevaluate: optiland is not installed (pip install optiland); it is an "
              "optional, independent reference and not a jaxlens dependency", file=sys.stderr)
        return 2
    from jaxlens.design.spec import DesignSpec

    t0 = time.perf_counter()
    out = reevaluate(a.folder, DesignSpec())
    out["seconds"] = time.perf_counter() - t0
    out["command"] = "python -m benchmarks.reevaluate " + str(a.folder)
    from jaxlens.io.json_values import write_whole

    write_whole(dest, json.dumps(out, indent=1) + "\n")
    print(f"{out['valid_both']}/{out['designs']} valid in both; optiland mean "
          f"{out['optiland_rms_mean_um']:.3f} µm, min {out['optiland_rms_min_um']:.3f}, max "
          f"{out['optiland_rms_max_um']:.3f}; jaxlens mean {out['jaxlens_rms_mean_um']:.3f}; "
          f"largest per-design difference {100 * out['max_abs_relative_difference']:.3f} % "
          f"-> {dest}")
    if out["rays_lost_by_optiland_only"]:
        print(f"{out['rays_lost_by_optiland_only']} rays pass in jaxlens and fail in optiland; "
              f"for {out['of_which_first_crossings_confirmed']} of them a sag scan confirms "
              f"that jaxlens's intersections are the rays' first crossings")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
