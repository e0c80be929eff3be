"""Skipping work a scene does not need: the measured saving of each shortcut, and its answer.

Each shortcut is timed against the full computation it replaces, and the two answers are
compared (``max_abs_diff``; ``same_answer`` is True when it is within ``tolerance``):

* ``object_at_infinity``: a collimated beam (no depth sampling) against the same spot computed
  through the finite-depth path at ``DEPTHS`` object distances, the farthest at 1e9 mm: the
  answer compared is the RMS spot of the collimated beam against that of the 1e9 mm point
  source (equal to ~2e-5 relative: the point source focuses f²/depth farther).
* ``single_wavelength``: ``rms_spot`` at one wavelength against three (the three set equal to
  it, so the per-wavelength answers must agree to rounding: XLA may vectorise a batch of one
  and of three differently, and one ulp of a ray's image height is ~1e-15 mm).
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
from jaxlens.analysis.spots import rms_spot

from . import common

DEPTHS = (1e3, 1e4, 1e5, 1e6, 1e8, 1e9)


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
def _spot_fields(lens, fields, pupils):
    """RMS spot (primary wavelength) of each (θx, θy) field with its own pupil points."""
    return jax.vmap(lambda f, p: _rms(jaxlens.trace(lens, sampling.collimated(lens, f, p))))(
        fields, pupils
    )


def _spot_collimated(lens, fields, pupil):
    """RMS spot per y field (degrees) over one pupil; shares ``_spot_fields``'s compilations."""
    fields2d = jnp.stack([jnp.zeros_like(fields), fields], -1)
    return _spot_fields(lens, fields2d, jnp.broadcast_to(pupil, fields.shape + pupil.shape))


@eqx.filter_jit
def _spot_depths(lens, fields, pupil, depths):
    def one(f, z):
        rays = sampling.point_source(lens, sampling.object_point(lens, f, z), pupil)
        # Launch the same lines from their entrance-pupil points instead of the far object
        # point: works around notes/bugs.md #3 (the conic root loses precision for origins
        # far from the surface) without moving any ray.
        zep = jaxlens.optics.paraxial.entrance_pupil_z(lens)
        xy = pupil * (0.5 * lens.epd)
        target = jnp.concatenate([xy, jnp.broadcast_to(zep, xy.shape[:-1])[..., None]], -1)
        rays = jaxlens.Rays(target, rays.direction, rays.wavelength)
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
    # A point source at depth D focuses f²/D behind a collimated beam's focus: at D = 1e9 mm
    # (depths go up to 1e10 mm, jaxlens's infinity) that is 2.5e-6 mm for the triplet's
    # 50 mm, and the RMS spots agree to ~2e-5 relative; allow 1e-4.
    return _row(
        "object_at_infinity",
        full,
        short,
        f"point sources at {len(DEPTHS)} depths",
        "collimated beam",
        float(jnp.max(jnp.abs(a - b) / a)),
        1e-4,
    )


def single_wavelength(lens, pupil):
    wl = lens.wavelengths[lens.primary]

    def fn(lens, w):  # rms_spot is jitted itself; its cache is shared with one_field_radius
        return rms_spot(lens, lens.fields, w, pupil=pupil)

    one = jnp.stack([wl])
    three = jnp.stack([wl, wl, wl])
    short = common.time_jitted(fn, lens, one)
    full = common.time_jitted(fn, lens, three)
    a = fn(lens, one).per_wavelength[:, 0]
    b = fn(lens, three).per_wavelength
    diff = float(jnp.max(jnp.abs(b - a[:, None])))
    # 1e-12 mm, as for the other rows: a 1e-15 bound was one ulp of the image heights and failed
    # on a CI CPU whose XLA build vectorised the two batch sizes differently.
    return _row(
        "single_wavelength",
        full,
        short,
        "rms_spot at 3 wavelengths",
        "rms_spot at 1 wavelength",
        diff,
        1e-12,
    )


def one_field_radius(lens, pupil, n: int):
    """n×n (θx, θy) fields against n fields along the y radius.

    Field (θx, θy) = θ·(sin φ, cos φ) in tangent space is the y-field θ turned by φ about the
    axis; its pupil points are turned with it, so for a rotationally symmetric lens the ray set
    is the turned copy of the radial one and the RMS spot must agree to rounding.
    """
    fmax = float(lens.fields[-1])
    radial = jnp.linspace(0.0, fmax, n)
    phi = jnp.linspace(0.0, 2 * jnp.pi, n, endpoint=False)
    tan_t = jnp.tan(jnp.deg2rad(radial))[:, None]
    tx = jnp.rad2deg(jnp.arctan(tan_t * jnp.sin(phi)))
    ty = jnp.rad2deg(jnp.arctan(tan_t * jnp.cos(phi)))
    grid = jnp.stack([tx, ty], -1).reshape(-1, 2)  # [n*n, 2], radius-major

    def turned(ph):
        c, s_ = jnp.cos(ph), jnp.sin(ph)
        px, py = pupil[:, 0], pupil[:, 1]
        return jnp.stack([px * c + py * s_, -px * s_ + py * c], -1)

    grid_pupils = jnp.tile(jax.vmap(turned)(phi), (n, 1, 1))  # [n*n, m, 2]
    radial_fields = jnp.stack([jnp.zeros_like(radial), radial], -1)
    radial_pupils = jnp.broadcast_to(pupil, (n,) + pupil.shape)
    short = common.time_jitted(_spot_fields, lens, radial_fields, radial_pupils)
    full = common.time_jitted(_spot_fields, lens, grid, grid_pupils)
    a = _spot_fields(lens, radial_fields, radial_pupils)
    b = _spot_fields(lens, grid, grid_pupils).reshape(n, n)
    diff = float(jnp.max(jnp.abs(b - a[:, None])))
    return _row(
        "one_field_radius",
        full,
        short,
        f"{n}x{n} field grid",
        f"{n} fields on one radius",
        diff,
        1e-12,
    )


def masked_fields(lens, pupil, n_fields: int, keep: int, with_grad: bool = True):
    fields = jnp.linspace(0.0, float(lens.fields[-1]), n_fields)
    mask = jnp.zeros(n_fields).at[jnp.linspace(0, n_fields - 1, keep).astype(int)].set(1.0)
    kept = np.flatnonzero(np.asarray(mask))

    def loss_full(lens):
        return jnp.sum(mask * _spot_collimated(lens, fields, pupil) ** 2)

    def loss_kept(lens):
        return jnp.sum(_spot_collimated(lens, fields[kept], pupil) ** 2)

    if with_grad:
        full_fn = eqx.filter_jit(eqx.filter_value_and_grad(loss_full))
        short_fn = eqx.filter_jit(eqx.filter_value_and_grad(loss_kept))
    else:  # value only (smoke run), returned with an empty gradient; shares compilations

        def full_fn(lens):
            return loss_full(lens), ()

        def short_fn(lens):
            return loss_kept(lens), ()

    full = common.time_jitted(full_fn, lens)
    short = common.time_jitted(short_fn, lens)
    (va, ga), (vb, gb) = full_fn(lens), short_fn(lens)
    la = [x for x in jax.tree_util.tree_leaves(ga) if eqx.is_array(x)]
    lb = [x for x in jax.tree_util.tree_leaves(gb) if eqx.is_array(x)]
    # Relative differences: the loss against the loss, each gradient leaf against that leaf's
    # largest entry (the leaves have different units, and a gradient can be 1e2 x the loss).
    loss_diff = abs(float(va) - float(vb)) / max(abs(float(va)), 1e-300)
    grad_diff = max(
        [
            float(jnp.max(jnp.abs(x - y)) / jnp.maximum(jnp.max(jnp.abs(x)), 1e-300))
            for x, y in zip(la, lb, strict=True)
            if x.size
        ],
        default=0.0,
    )
    row = _row(
        "masked_fields",
        full,
        short,
        f"{n_fields} fields traced, loss × mask",
        f"{keep} unmasked fields traced",
        max(loss_diff, grad_diff),
        1e-12,
    )
    return row | dict(loss_rel_diff=loss_diff, grad_rel_diff=grad_diff)


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
        1e-12,
    )


def run(smoke: bool = False) -> dict:
    from .pareto import steep_asphere
    from .throughput import make_rays

    pupil = 0.999 * sampling.pupil_grid(5 if smoke else 21)
    cooke = zoo.cooke_triplet()
    # The smoke run swaps the 13-surface phone lens for a 2-asphere lens (compile time).
    odd_lens = steep_asphere() if smoke else zoo.cellphone6()
    rows = [
        object_at_infinity(cooke, pupil),
        single_wavelength(cooke, pupil),
        one_field_radius(cooke, pupil, 3 if smoke else 16),
        masked_fields(cooke, pupil, 3 if smoke else 32, 1 if smoke else 4, with_grad=not smoke),
        no_odd_terms(odd_lens, make_rays(odd_lens, 1_000 if smoke else 200_000, jnp.float64)),
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


def plot(res: dict, path) -> None:
    """Saving of each shortcut (full time / shortcut time)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = res["rows"]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    names = [r["shortcut"] for r in rows]
    ax.barh(
        names, [r["saving"] for r in rows], color=["C0" if r["same_answer"] else "C3" for r in rows]
    )
    ax.axvline(1.0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_xlabel("saving (full time / shortcut time)")
    same = all(r["same_answer"] for r in rows)
    ax.set_title(
        "skipping unneeded work"
        + (" (every shortcut gives the same answer)" if same else " (red: answer differs)")
    )
    fig.tight_layout()
    common.save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":  # ran nothing, without a word: the suite's runner, this benchmark
    import sys

    from benchmarks.run import main

    main(["--only", "skipping", *sys.argv[1:]])
