"""Skipping work a scene does not need: the measured saving of each shortcut, and its answer.

Each shortcut is timed against the full computation it replaces, and the two answers are
compared (``max_abs_diff``; ``same_answer`` is True when it is within ``tolerance``):

* ``object_at_infinity``: a collimated beam (no depth sampling) against the same spot computed
  through the finite-depth path at ``DEPTHS`` object distances, the farthest at 1e9 mm: the
  answer compared is the RMS spot of the collimated beam against that of the 1e9 mm point
  source (equal to ~EPD/depth).
* ``single_wavelength``: ``rms_spot`` at one wavelength against three (the three set equal to
  it, so the per-wavelength answers must agree exactly).
* ``one_field_radius``: a rotationally symmetric lens's RMS spot over an n×n grid of (θx, θy)
  field points against n field angles along one radius, mapped to the grid by |θ| (the
  answer compared: the grid values against the radial values at the same |θ|, exact).
* ``masked_fields``: a re-weighted spot loss over F fields with a 0/1 mask that zeroes most of
  them, computed by tracing every field and multiplying by the mask, against tracing only the
  fields the mask keeps; loss and gradient compared.
* ``no_odd_terms``: the cellphone lens with every surface a ``Hybrid`` whose odd terms are all
  zero (they are evaluated) against the same lens with ``EvenAsphere`` surfaces (they are
  not): same answer exactly.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxlens
from jaxlens import sampling, zoo
from jaxlens.analysis import rms_spot

from . import common

DEPTHS = (1e3, 1e4, 1e5, 1e6, 1e7, 1e9)


def _row(name, full, short, full_desc, short_desc, diff, tol):
    return dict(
        shortcut=name,
        full=full_desc,
        shortcut_desc=short_desc,
        full_s=full["run_s"],
        shortcut_s=short["run_s"],
        saving=full["run_s"] / short["run_s"],
        full_compile_s=full["compile_s"],
        shortcut_compile_s=short["compile_s"],
        max_abs_diff=float(diff),
        tolerance=tol,
        same_answer=bool(diff <= tol),
        load=(full["load_before"] + short["load_before"]) / 2,
    )


@eqx.filter_jit
def _spot_collimated(lens, fields, pupil):
    def one(f):
        out = jaxlens.trace(lens, sampling.collimated(lens, f, pupil))
        return _rms(out)

    return jax.vmap(one)(fields)


@eqx.filter_jit
def _spot_depths(lens, fields, pupil, depths):
    def one(f, z):
        rays = sampling.point_source(lens, sampling.object_point(lens, f, z), pupil)
        return _rms(jaxlens.trace(lens, rays))

    return jax.vmap(lambda z: jax.vmap(lambda f: one(f, z))(fields))(depths)


def _rms(out):
    w = out.valid.astype(out.origin.dtype)
    xy = out.origin[..., :2]
    c = jnp.sum(w[:, None] * xy, 0) / jnp.sum(w)
    return jnp.sqrt(jnp.sum(w * jnp.sum((xy - c) ** 2, -1)) / jnp.sum(w))


def object_at_infinity(lens, pupil):
    f = lens.fields
    short = common.time_jitted(_spot_collimated, lens, f, pupil)
    depths = jnp.asarray(DEPTHS)
    full = common.time_jitted(_spot_depths, lens, f, pupil, depths)
    a = _spot_collimated(lens, f, pupil)
    b = _spot_depths(lens, f, pupil, depths)[-1]
    # A point source at depth D differs from a collimated beam by ~ (EPD/2)²/D in path and
    # ~ EPD/D in angle: allow 1e-6 relative at D = 1e9 mm.
    return _row(
        "object_at_infinity",
        full,
        short,
        f"point sources at {len(DEPTHS)} depths",
        "collimated beam",
        float(jnp.max(jnp.abs(a - b) / a)),
        1e-6,
    )


def single_wavelength(lens, pupil):
    wl = lens.wavelengths[lens.primary]
    fn = eqx.filter_jit(lambda lens, w: rms_spot(lens, lens.fields, w, pupil=pupil))
    one = jnp.stack([wl])
    three = jnp.stack([wl, wl, wl])
    short = common.time_jitted(fn, lens, one)
    full = common.time_jitted(fn, lens, three)
    a = fn(lens, one).per_wavelength[:, 0]
    b = fn(lens, three).per_wavelength
    diff = float(jnp.max(jnp.abs(b - a[:, None])))
    return _row(
        "single_wavelength",
        full,
        short,
        "rms_spot at 3 wavelengths",
        "rms_spot at 1 wavelength",
        diff,
        1e-15,
    )


def one_field_radius(lens, pupil, n: int):
    fmax = float(lens.fields[-1])
    radial = jnp.linspace(0.0, fmax, n)
    # The n×n grid of (θx, θy) built from the radial values and n angles: every grid point's
    # |θ| is one of the radial samples, so the symmetric answer is known exactly.
    ang = jnp.linspace(0.0, 2 * jnp.pi, n, endpoint=False)
    th = jnp.deg2rad(radial)[:, None]
    # Field (θx, θy) with tan θx, tan θy chosen so the beam makes the angle θ with the axis.
    tx = jnp.rad2deg(jnp.arctan(jnp.tan(th) * jnp.sin(ang)))
    ty = jnp.rad2deg(jnp.arctan(jnp.tan(th) * jnp.cos(ang)))
    grid = jnp.stack([tx, ty], -1).reshape(-1, 2)
    fn = eqx.filter_jit(lambda lens, f: rms_spot(lens, f, lens.wavelengths[1:2], pupil=pupil))
    short = common.time_jitted(fn, lens, radial)
    full = common.time_jitted(fn, lens, grid)
    a = fn(lens, radial).per_wavelength[:, 0]
    b = fn(lens, grid).per_wavelength[:, 0].reshape(n, n)
    diff = float(jnp.max(jnp.abs(b - a[:, None])))
    return _row(
        "one_field_radius",
        full,
        short,
        f"{n}x{n} field grid",
        f"{n} fields on one radius",
        diff,
        1e-9,
    )


def masked_fields(lens, pupil, n_fields: int, keep: int):
    fields = jnp.linspace(0.0, float(lens.fields[-1]), n_fields)
    mask = jnp.zeros(n_fields).at[jnp.linspace(0, n_fields - 1, keep).astype(int)].set(1.0)
    kept = np.flatnonzero(np.asarray(mask))

    def loss_full(lens):
        return jnp.sum(mask * _spot_collimated(lens, fields, pupil) ** 2)

    def loss_kept(lens):
        return jnp.sum(_spot_collimated(lens, fields[kept], pupil) ** 2)

    full_fn = eqx.filter_jit(eqx.filter_value_and_grad(loss_full))
    short_fn = eqx.filter_jit(eqx.filter_value_and_grad(loss_kept))
    full = common.time_jitted(full_fn, lens)
    short = common.time_jitted(short_fn, lens)
    (va, ga), (vb, gb) = full_fn(lens), short_fn(lens)
    la = [x for x in jax.tree_util.tree_leaves(ga) if eqx.is_array(x)]
    lb = [x for x in jax.tree_util.tree_leaves(gb) if eqx.is_array(x)]
    diff = max(
        [abs(float(va) - float(vb))]
        + [float(jnp.max(jnp.abs(x - y))) if x.size else 0.0 for x, y in zip(la, lb, strict=True)]
    )
    scale = max(abs(float(va)), 1e-300)
    return _row(
        "masked_fields",
        full,
        short,
        f"{n_fields} fields traced, loss × mask",
        f"{keep} unmasked fields traced",
        diff / scale,
        1e-12,
    )


def no_odd_terms(lens, rays):
    def to_hybrid(s):
        if isinstance(s, jaxlens.EvenAsphere):
            z = jnp.zeros(4, s.coeffs.dtype)
            return jaxlens.Hybrid(s.c, s.k, s.coeffs, z, z, s.semi_diameter)
        return s

    hybrid = eqx.tree_at(lambda l: l.surfaces, lens, tuple(to_hybrid(s) for s in lens.surfaces))
    fn = eqx.filter_jit(lambda lens, rays: jaxlens.trace(lens, rays).origin)
    short = common.time_jitted(fn, lens, rays)
    full = common.time_jitted(fn, hybrid, rays)
    diff = float(jnp.max(jnp.abs(fn(lens, rays) - fn(hybrid, rays))))
    return _row(
        "no_odd_terms",
        full,
        short,
        "Hybrid surfaces, odd terms all zero",
        "EvenAsphere surfaces (odd terms absent)",
        diff,
        0.0,
    )


def run(smoke: bool = False) -> dict:
    from .throughput import make_rays

    pupil = 0.999 * sampling.pupil_grid(11 if smoke else 21)
    cooke = zoo.cooke_triplet()
    cell = zoo.cellphone6()
    rows = [
        object_at_infinity(cooke, pupil),
        single_wavelength(cooke, pupil),
        one_field_radius(cooke, pupil, 4 if smoke else 16),
        masked_fields(cooke, pupil, 8 if smoke else 32, 2 if smoke else 4),
        no_odd_terms(cell, make_rays(cell, 10_000 if smoke else 200_000, jnp.float64)),
    ]
    for r in rows:
        print(
            f"  {r['shortcut']:20s} saving {r['saving']:6.2f}x  same answer: {r['same_answer']} "
            f"(max diff {r['max_abs_diff']:.2e})"
        )
    return {"rows": rows}


def markdown(res: dict) -> str:
    body = [
        [
            r["shortcut"],
            r["full"],
            r["shortcut_desc"],
            float(r["full_s"]),
            float(r["shortcut_s"]),
            f"{r['saving']:.2f}x",
            float(r["max_abs_diff"]),
            "yes" if r["same_answer"] else "NO",
        ]
        for r in res["rows"]
    ]
    return "\n".join(
        [
            "### Skipping unneeded work",
            "",
            common.md_table(
                [
                    "shortcut",
                    "full computation",
                    "shortcut",
                    "full s",
                    "shortcut s",
                    "saving",
                    "max diff",
                    "same answer",
                ],
                body,
            ),
        ]
    )
