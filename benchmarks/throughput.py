"""Throughput: ray·surfaces per second of the forward trace and of forward + gradient.

For each sample lens (``jaxlens.zoo``: Cooke triplet, 6 surfaces; double Gauss, 11; the
6-element cellphone asphere lens, 13 including its stop), each dtype and each ray count, the
same random rays (uniform over the entrance pupil at 70 % of the largest field, primary
wavelength) are traced:

* ``forward``: ``jaxlens.trace(lens, rays)``, every output leaf blocked on.
* ``forward+grad``: value and gradient, with respect to every array of the lens, of the mean
  squared spot radius about the centroid of the valid rays (the RMS-spot loss of lens design),
  traced with ``jaxlens.trace(..., reverse_rule=True)``: a reverse-only gradient, so plane,
  sphere and conic surfaces take the hand-written reverse rule (``tracing.surface_adjoint``;
  identical values, faster gradient; benchmarks/SPEED.md).

ray·surfaces/s = rays × lens surfaces (the image surface not counted) / best run time.
``engine = "jaxlens"`` is ``jaxlens.trace`` with its defaults; ``engine =
"optiland"`` is optiland's numpy trace (float64 only) of the same rays in the same run, with
``ratio_vs_optiland`` on every jaxlens row of the same lens and ray count. The image
intercepts of every engine are compared with ``jaxlens.trace`` (``max_dev_mm``).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxlens
from jaxlens import sampling, zoo

from . import common, optiland_ref

LENSES = ("cooke_triplet", "double_gauss", "cellphone6")


def make_rays(lens: jaxlens.Lens, n: int, dtype, seed: int = 0,
              pupil_scale: float = 0.999) -> jaxlens.Rays:
    """``n`` rays uniform over the pupil at 70 % of the largest field, primary wavelength
    (over ``pupil_scale`` times the entrance pupil; above 1, some rays are clipped)."""
    lens64 = lens.astype(jnp.float64)
    pupil = pupil_scale * sampling.pupil_random(jax.random.PRNGKey(seed), n, jnp.float64)
    field = 0.7 * float(lens.fields[-1])
    r = sampling.collimated(lens64, field, pupil)
    return jaxlens.Rays(
        r.origin.astype(dtype), r.direction.astype(dtype), jnp.asarray(r.wavelength, dtype)
    )


def spot_loss(xy, valid):
    """Mean squared spot radius of the valid rays about their centroid (the design loss)."""
    w = valid.astype(xy.dtype)
    nv = jnp.maximum(jnp.sum(w), 1.0)
    c = jnp.sum(w[:, None] * xy, 0) / nv
    return jnp.sum(w * jnp.sum((xy - c) ** 2, -1)) / nv


@eqx.filter_jit
def forward(lens, rays):
    return jaxlens.trace(lens, rays)


# The reference intercepts use their own jitted function, so that the first call of
# ``forward`` in the timed rows still includes its compilation.
_reference_trace = eqx.filter_jit(lambda lens, rays: jaxlens.trace(lens, rays))


@eqx.filter_jit
def forward_grad(lens, rays):
    def loss(lens):
        out = jaxlens.trace(lens, rays, reverse_rule=True)
        return spot_loss(out.origin[:, :2], out.valid)

    return eqx.filter_value_and_grad(loss)(lens)


def chosen_lenses(smoke: bool, lenses=None) -> tuple[str, ...]:
    """The lenses a run traces: those asked for, all of them also in a smoke run (which
    otherwise takes the first of ``LENSES`` only)."""
    if lenses is not None:
        return tuple(lenses)
    return LENSES[:1] if smoke else LENSES


MAX_RAYS = 100_000_000
"""Most rays per count (``--counts``): ``--full``'s largest is 10**7, which fits because the
trace goes through checkpointed chunks; the rays themselves (origin, direction, wavelength
and validity, float64) are about 60 bytes each, 6 GB at 10**8, and 10**12 aborted in XLA."""


def run(
    smoke: bool = False,
    full: bool = False,
    lenses=None,
    counts=None,
    with_optiland: bool = True,
) -> dict:
    """Run the throughput benchmark and return its result dictionary."""
    if counts is None:
        counts = [1_000] if smoke else [1_000, 10_000, 100_000, 1_000_000]
        if full:
            counts = counts + [10_000_000]
    lenses = chosen_lenses(smoke, lenses)
    have_optiland = with_optiland and optiland_ref.available()
    rows = []
    for name in lenses:
        lens = zoo.ZOO[name]()
        ns = lens.num_surfaces
        op = (
            optiland_ref.build_optic(lens, float(lens.primary_wavelength))
            if have_optiland
            else None
        )
        for n in counts:
            ref64 = None
            opt_rate = None
            if op is not None:
                r64 = make_rays(lens, n, jnp.float64)
                o, d = np.asarray(r64.origin), np.asarray(r64.direction)
                wl = float(lens.primary_wavelength)
                t = common.time_python(
                    optiland_ref.trace,
                    op,
                    o,
                    d,
                    wl,
                    repeats=1 if n >= 1_000_000 else 3,
                    min_total_s=0.0 if n >= 1_000_000 else 0.5,
                )
                ref64 = _reference_trace(lens, r64)
                dev = float(
                    np.max(
                        np.abs(
                            optiland_ref.intercepts(optiland_ref.trace(op, o, d, wl))
                            - np.asarray(ref64.origin)
                        )[np.asarray(ref64.valid)]
                    )
                )
                opt_rate = n * ns / t["run_s"]
                rows.append(
                    dict(
                        lens=name,
                        surfaces=ns,
                        engine="optiland",
                        dtype="float64",
                        mode="forward",
                        rays=n,
                        rate=opt_rate,
                        max_dev_mm=dev,
                        **t,
                    )
                )
                print(f"  {name:14s} optiland  float64 forward      {n:>9d}  {opt_rate:.3g}")
            for dtype in (jnp.float32, jnp.float64):
                rays = make_rays(lens, n, dtype)
                dname = jnp.dtype(dtype).name
                reps = 1 if n >= 10_000_000 else 3 if n >= 1_000_000 else 5
                engines = [("jaxlens", "forward", forward, (lens, rays))]
                # The trace goes through large batches in checkpointed chunks, so the
                # gradient's memory is bounded and 1e7 rays fit.
                if not smoke or dtype == jnp.float64:
                    engines.append(("jaxlens", "forward+grad", forward_grad, (lens, rays)))
                for engine, mode, fn, args in engines:
                    t = common.time_jitted(
                        fn,
                        *args,
                        repeats=reps,
                        min_total_s=0.2 if n >= 1_000_000 else 0.5,
                        warmup=n < 10_000_000,
                    )
                    rate = n * ns / t["run_s"]
                    row = dict(
                        lens=name,
                        surfaces=ns,
                        engine=engine,
                        dtype=dname,
                        mode=mode,
                        rays=n,
                        rate=rate,
                        **t,
                    )
                    if mode == "forward" and ref64 is not None:
                        out = fn(*args)
                        y = out.origin
                        ok = np.asarray(ref64.valid)
                        row["max_dev_mm"] = float(
                            np.max(np.abs(np.asarray(y, np.float64) - np.asarray(ref64.origin))[ok])
                        )
                    if opt_rate is not None and mode == "forward":
                        row["ratio_vs_optiland"] = rate / opt_rate
                    rows.append(row)
                    extra = (
                        f"  {row['ratio_vs_optiland']:.2f}x optiland"
                        if "ratio_vs_optiland" in row
                        else ""
                    )
                    print(
                        f"  {name:14s} {engine:9s} {dname} {mode:12s} {n:>9d}  {rate:.3g} "
                        f"ray·surf/s (compile {t['compile_s']:.2f} s, load "
                        f"{t['load_before']:.1f}){extra}"
                    )
    return {
        "rows": rows,
        "optiland": have_optiland,
        "definition": "rate = rays × lens surfaces (image surface not counted) / best run "
        "time; forward+grad = value and gradient of the mean squared spot "
        "radius w.r.t. every lens array",
        "notes": "cpu_s is the process CPU time of the best run (all threads), so cpu_s/run_s "
        "shows how many cores it used",
    }


def markdown(res: dict) -> str:
    """Markdown tables of a throughput result: a headline table, then every row."""
    rows = res["rows"]

    def per_core(r):
        return r["rays"] * r["surfaces"] / r["cpu_s"] if r.get("cpu_s") else None

    out = []
    head = [r for r in rows if r["lens"] == "cooke_triplet" and r["rays"] == 1_000_000]
    if head:
        out += ["### Issue-2 headline: Cooke triplet, 1e6 rays", ""]
        out.append(
            common.md_table(
                [
                    "engine",
                    "dtype",
                    "mode",
                    "ray·surf/s (wall)",
                    "per core (CPU time)",
                    "vs optiland",
                    "load",
                ],
                [
                    [
                        r["engine"],
                        r["dtype"],
                        r["mode"],
                        float(r["rate"]),
                        per_core(r),
                        f"{r['ratio_vs_optiland']:.2f}x" if "ratio_vs_optiland" in r else "–",
                        f"{r['load_before']:.1f}",
                    ]
                    for r in head
                ],
            )
        )
        out += [
            "",
            "Targets: forward float32 ≥ 1e8 ray·surf/s or ≥ 5x optiland; forward+grad "
            '≥ 3e7. "per core" = rays × surfaces / process CPU seconds, the rate one '
            "core sustains, which a shared machine distorts far less than wall time.",
            "",
        ]
    out += ["### Throughput (ray·surfaces/s, best run; compile time apart)", ""]
    header = [
        "lens",
        "engine",
        "dtype",
        "mode",
        "rays",
        "ray·surf/s",
        "per core",
        "run s",
        "compile s",
        "vs optiland",
        "load",
    ]
    body = []
    for r in rows:
        body.append(
            [
                r["lens"],
                r["engine"],
                r["dtype"],
                r["mode"],
                f"{r['rays']:.0e}",
                float(r["rate"]),
                per_core(r),
                float(r["run_s"]),
                float(r["compile_s"]),
                f"{r['ratio_vs_optiland']:.2f}x" if "ratio_vs_optiland" in r else "–",
                f"{r['load_before']:.1f}",
            ]
        )
    out.append(common.md_table(header, body))
    out += ["", res.get("definition", ""), "", res.get("notes", "")]
    return "\n".join(out)


def plot(res: dict, path) -> None:
    """Rate against ray count, one panel per lens."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = res["rows"]
    lenses = sorted({r["lens"] for r in rows}, key=LENSES.index)
    fig, axes = plt.subplots(1, len(lenses), figsize=(5 * len(lenses), 4), squeeze=False)
    for ax, name in zip(axes[0], lenses, strict=True):
        keys = sorted({(r["engine"], r["dtype"], r["mode"]) for r in rows if r["lens"] == name})
        for key in keys:
            sel = [
                r for r in rows if r["lens"] == name and (r["engine"], r["dtype"], r["mode"]) == key
            ]
            sel.sort(key=lambda r: r["rays"])
            style = {"jaxlens": "-", "optiland": ":"}[key[0]]
            ax.loglog(
                [r["rays"] for r in sel],
                [r["rate"] for r in sel],
                style,
                marker="o",
                label=" ".join(key),
            )
        ax.axhline(1e8, color="k", lw=0.5)
        ax.set_title(name)
        ax.set_xlabel("rays")
        ax.set_ylabel("ray·surfaces/s")
        ax.legend(fontsize=6)
    fig.tight_layout()
    common.save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":  # ran nothing, without a word: the suite's runner, this benchmark
    import sys

    from benchmarks.run import main

    main(["--only", "throughput", *sys.argv[1:]])
