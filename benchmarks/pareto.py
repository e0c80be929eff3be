"""Run time against error: Pareto curves, each ending in a recommended default.

Three studies (the render-side curves, render error against spp and PSF error against kernel
size, belong to the render module's benchmarks; see the suite's README):

* ``rms_spot``: the RMS spot radius estimated from M pupil samples by each sampling scheme of
  ``jaxlens.imaging.sampling`` (grid, hexapolar, random, stratified), against a converged
  reference: a
  polar Gauss quadrature (Gauss–Legendre in r², 128 nodes, times 512 equally spaced angles,
  65 536 weighted rays), which agrees with a 1001×1001 grid to the grid's own error. Error =
  max over the lens's fields of |estimate − reference| / reference (random and stratified: the
  root mean square over 8 seeds). Time = ``jaxlens.analysis.spots.rms_spot`` for one field and one
  wavelength at that ray count (measured at a ladder of ray counts and interpolated). A weighted
  polar Gauss rule (``gauss``, not in the library) is included as a candidate.
* ``newton``: the intersection error (max image-intercept deviation from 40 iterations in
  float64, valid rays) and the fraction of rays flagged valid against ``newton_iters``, in
  float32 and float64, for the aspheric cellphone lens and a steep test asphere; time of a
  forward trace of 1e5 rays.
* ``dtype``: float32 against float64 for every sample lens: time of the forward trace and of
  forward+gradient (1e5 rays), the intercept deviation, the relative deviation of the RMS spot
  and of its gradient.
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

SCHEMES = {
    "grid": [5, 7, 9, 11, 15, 21, 31, 45, 65, 91, 129],
    "hexapolar": [2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64],
    "random": [16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384],
    "stratified": [4, 6, 8, 11, 16, 23, 32, 45, 64, 91, 128],
    "gauss": [(2, 8), (3, 12), (4, 16), (6, 24), (8, 32), (12, 48), (16, 64), (24, 96), (32, 128)],
}
SEEDS = 8
MAX_RAYS = 1 << 16  # the padded size of the one compiled estimator (= the reference rule)


def gauss_pupil(n_r: int, n_a: int):
    """Polar Gauss rule on the unit disc: Gauss–Legendre in u = r² (exact for polynomials in r²
    of degree 2 n_r − 1) times ``n_a`` equally spaced angles. Returns (points [m, 2], weights
    [m], summing to 1)."""
    u, wu = np.polynomial.legendre.leggauss(n_r)
    u = 0.5 * (u + 1.0)
    wu = 0.5 * wu
    a = (np.arange(n_a) + 0.5) * 2 * np.pi / n_a
    r = np.sqrt(u)[:, None]
    pts = np.stack([(r * np.cos(a)).ravel(), (r * np.sin(a)).ravel()], -1)
    w = np.repeat(wu, n_a) / n_a
    return pts, w


def pupil_for(scheme: str, n, seed: int = 0):
    """(points, weights) for a scheme; equal weights except for ``gauss``."""
    if scheme == "gauss":
        return gauss_pupil(*n)
    key = jax.random.PRNGKey(seed)
    pts = np.asarray(sampling.pupil_samples(scheme, n, key, jnp.float64))
    return pts, np.full(pts.shape[0], 1.0 / pts.shape[0])


@eqx.filter_jit
def _weighted_rms(lens, field, pts, w):
    """RMS spot radius about the weighted centroid (valid rays only), primary wavelength."""
    rays = sampling.collimated(lens, field, pts)
    out = jaxlens.trace(lens, rays)
    ww = w * out.valid
    xy = out.origin[:, :2]
    c = jnp.sum(ww[:, None] * xy, 0) / jnp.sum(ww)
    return jnp.sqrt(jnp.sum(ww * jnp.sum((xy - c) ** 2, -1)) / jnp.sum(ww))


def estimate(lens, field, pts, w, max_rays: int = MAX_RAYS):
    """The weighted RMS estimate, padded to ``max_rays`` (zero weight) to share one compilation."""
    m = pts.shape[0]
    pad = max_rays - m
    pts = np.concatenate([pts, np.zeros((pad, 2))])
    w = np.concatenate([w, np.zeros(pad)])
    return float(_weighted_rms(lens, jnp.asarray(field), jnp.asarray(pts), jnp.asarray(w)))


def _reference(lens, field, rule=(128, 512), max_rays: int = MAX_RAYS):
    return estimate(lens, field, *gauss_pupil(*rule), max_rays=max_rays)


def rms_spot_study(smoke: bool = False) -> dict:
    lenses = ("cooke_triplet",) if smoke else ("cooke_triplet", "double_gauss", "cellphone6")
    schemes = {k: (v[:2] if smoke else v) for k, v in SCHEMES.items()}
    seeds = 1 if smoke else SEEDS
    max_rays = 1024 if smoke else MAX_RAYS
    rule = (16, 64) if smoke else (128, 512)
    rows, timing = [], {}
    for name in lenses:
        # Unclipped, so that the pupil alone decides which rays count; 0.9999 keeps the rim
        # inside the stop.
        lens = zoo.ZOO[name](clip=False)
        fields = [float(f) for f in np.asarray(lens.fields)]
        refs = [_reference(lens, f, rule, max_rays) for f in fields]
        grid_check = None
        if not smoke:
            pts, w = pupil_for("grid", 1001)
            grid_check = max(
                abs(
                    float(_weighted_rms(lens, jnp.asarray(f), jnp.asarray(pts), jnp.asarray(w))) - r
                )
                / r
                for f, r in zip(fields, refs, strict=True)
            )
        # Time of the library's rms_spot at a ladder of ray counts (one field, one wavelength).
        ladder = [256] if smoke else [64, 256, 1024, 4096, 16384, 65536]
        ts = []
        for m in ladder:
            pupil = jnp.asarray(np.asarray(sampling.pupil_random(jax.random.PRNGKey(0), m)))
            t = common.time_jitted(
                lambda p, lens=lens: rms_spot(
                    lens, lens.fields[-1:], lens.wavelengths[1:2], pupil=p
                ),
                pupil,
                repeats=3,
                min_total_s=0.2,
            )
            ts.append(t["run_s"])
        timing[name] = {"rays": ladder, "run_s": ts}

        def time_at(m, ladder=ladder, ts=ts):
            if len(ladder) == 1:  # smoke run: proportional to the ray count
                return ts[0] * m / ladder[0]
            return float(np.exp(np.interp(np.log(m), np.log(ladder), np.log(ts))))

        for scheme, sizes in schemes.items():
            for n in sizes:
                errs = []
                n_rays = None
                for s in range(seeds if scheme in ("random", "stratified") else 1):
                    pts, w = pupil_for(scheme, n, seed=s)
                    n_rays = pts.shape[0]
                    if n_rays > max_rays:
                        break
                    e = [
                        abs(estimate(lens, f, pts * 0.9999, w, max_rays) - r) / r
                        for f, r in zip(fields, refs, strict=True)
                    ]
                    errs.append(max(e))
                if not errs:
                    continue
                err = float(np.sqrt(np.mean(np.square(errs))))
                rows.append(
                    dict(
                        lens=name,
                        scheme=scheme,
                        n=n,
                        rays=n_rays,
                        rel_error=err,
                        time_s=time_at(n_rays),
                    )
                )
        rows.append(dict(lens=name, reference=refs, fields=fields, grid1001_rel_dev=grid_check))
    rec = _recommend_rms(rows, target=0.2 if smoke else 0.01)
    return {"rows": rows, "timing": timing, "recommendation": rec}


def _recommend_rms(rows, target: float = 0.01):
    """Cheapest equal-weight scheme/size whose error is below ``target`` on every lens."""
    data = [r for r in rows if "scheme" in r]
    lenses = sorted({r["lens"] for r in data})
    best = None
    for scheme in SCHEMES:
        if scheme == "gauss":
            continue
        for n in SCHEMES[scheme]:
            sel = [r for r in data if r["scheme"] == scheme and r["n"] == n]
            if len(sel) != len(lenses) or any(r["rel_error"] > target for r in sel):
                continue
            rays = max(r["rays"] for r in sel)
            if best is None or rays < best["rays"]:
                best = dict(
                    scheme=scheme, n=n, rays=rays, max_rel_error=max(r["rel_error"] for r in sel)
                )
            break
    gauss = None
    for n in SCHEMES["gauss"]:
        sel = [r for r in data if r["scheme"] == "gauss" and r["n"] == n]
        if sel and len(sel) == len(lenses) and all(r["rel_error"] <= target for r in sel):
            gauss = dict(
                scheme="gauss",
                n=list(n),
                rays=sel[0]["rays"],
                max_rel_error=max(r["rel_error"] for r in sel),
            )
            break
    return {"target_rel_error": target, "equal_weight": best, "weighted_gauss": gauss}


def steep_asphere() -> jaxlens.Lens:
    """A test singlet of two strong even aspheres (conics −3 and 2, A4..A10), clipped at 4 mm."""
    return jaxlens.Lens(
        surfaces=(
            jaxlens.EvenAsphere(0.08, -3.0, jnp.array([0.0, 4e-3, -2e-4, 1e-5, -2e-7]), 4.0),
            jaxlens.EvenAsphere(-0.05, 2.0, jnp.array([0.01, -1e-3, 5e-5, -1e-6, 0.0]), 4.0),
        ),
        thickness=jnp.array([2.5, 20.0]),
        materials=(jaxlens.ModelGlass(1.6, 40.0), jaxlens.Air()),
        epd=7.0,
        fields=jnp.array([0.0, 10.0, 20.0]),
        wavelengths=jnp.array([0.5875618]),
        name="steep_asphere",
    )


def newton_study(smoke: bool = False) -> dict:
    n_rays = 2_000 if smoke else 100_000
    iters = [3] if smoke else [0, 1, 2, 3, 4, 5, 6, 8, 10, 15]
    dtypes = (jnp.float64,) if smoke else (jnp.float32, jnp.float64)
    steep = steep_asphere()
    cases = (
        {"steep_asphere": steep}
        if smoke
        else {"cellphone6": zoo.cellphone6(), "steep_asphere": steep}
    )
    rows = []
    for name, lens in cases.items():
        pupil = 0.999 * sampling.pupil_random(jax.random.PRNGKey(1), n_rays // 2)
        r = [
            sampling.collimated(lens, f, pupil)
            for f in (0.5 * float(lens.fields[-1]), float(lens.fields[-1]))
        ]
        o = jnp.concatenate([x.origin for x in r])
        d = jnp.concatenate([x.direction for x in r])
        ref = jaxlens.trace(lens, jaxlens.Rays(o, d, lens.primary_wavelength), newton_iters=40)
        ok_ref = np.asarray(ref.valid)
        for dtype in dtypes:
            rays = jaxlens.Rays(
                o.astype(dtype), d.astype(dtype), jnp.asarray(lens.primary_wavelength, dtype)
            )
            for it in iters:
                fn = eqx.filter_jit(
                    lambda lens, rays, it=it: jaxlens.trace(lens, rays, newton_iters=it)
                )
                t = common.time_jitted(fn, lens, rays, repeats=3, min_total_s=0.2)
                out = fn(lens, rays)
                ok = np.asarray(out.valid) & ok_ref
                dev = np.abs(np.asarray(out.origin, np.float64) - np.asarray(ref.origin))[ok]
                rows.append(
                    dict(
                        lens=name,
                        dtype=jnp.dtype(dtype).name,
                        newton_iters=it,
                        max_error_mm=float(dev.max()) if dev.size else None,
                        valid_fraction=float(np.mean(np.asarray(out.valid))),
                        reference_valid_fraction=float(ok_ref.mean()),
                        run_s=t["run_s"],
                        compile_s=t["compile_s"],
                        rays=n_rays,
                    )
                )
    return {"rows": rows, "recommendation": _recommend_newton(rows)}


def _recommend_newton(rows):
    """Fewest iterations reaching the dtype's floor on every case, with the valid fraction of
    the reference; floors: 1e-10 mm (float64), 1e-4 mm (float32)."""
    out = {}
    for dtype, floor in (("float32", 1e-4), ("float64", 1e-10)):
        sel = [r for r in rows if r["dtype"] == dtype]
        for it in sorted({r["newton_iters"] for r in sel}):
            rs = [r for r in sel if r["newton_iters"] == it]
            if all(
                r["max_error_mm"] is not None
                and r["max_error_mm"] <= floor
                and r["valid_fraction"] >= r["reference_valid_fraction"] - 1e-9
                for r in rs
            ):
                out[dtype] = dict(newton_iters=it, floor_mm=floor)
                break
    return out


def dtype_study(smoke: bool = False) -> dict:
    n = 1_000 if smoke else 100_000  # the smoke size matches the throughput smoke run
    lenses = ("cooke_triplet",) if smoke else tuple(zoo.ZOO)
    rows = []
    from .throughput import forward, forward_grad, make_rays

    for name in lenses:
        lens = zoo.ZOO[name]()
        res = {}
        for dtype in (jnp.float32, jnp.float64):
            rays = make_rays(lens, n, dtype)
            tf = common.time_jitted(forward, lens, rays, repeats=3, min_total_s=0.3)
            out = forward(lens, rays)
            if smoke:  # forward only: the compilations are shared with the throughput run
                res[jnp.dtype(dtype).name] = dict(out=out, tf=tf)
                continue
            tg = common.time_jitted(forward_grad, lens, rays, repeats=3, min_total_s=0.3)
            val, grad = forward_grad(lens, rays)
            res[jnp.dtype(dtype).name] = dict(out=out, val=val, grad=grad, tf=tf, tg=tg)
        a, b = res["float64"], res["float32"]
        if smoke:
            ok = np.asarray(a["out"].valid) & np.asarray(b["out"].valid)
            dev = np.abs(np.asarray(a["out"].origin) - np.asarray(b["out"].origin, float))[ok]
            rows.append(
                dict(
                    lens=name,
                    rays=n,
                    speedup_forward=a["tf"]["run_s"] / b["tf"]["run_s"],
                    max_intercept_dev_mm=float(dev.max()),
                )
            )
            continue
        ok = np.asarray(a["out"].valid) & np.asarray(b["out"].valid)
        dev = float(
            np.abs(np.asarray(a["out"].origin) - np.asarray(b["out"].origin, float))[ok].max()
        )
        g64 = np.concatenate([np.ravel(np.asarray(x, float)) for x in common_leaves(a["grad"])])
        g32 = np.concatenate([np.ravel(np.asarray(x, float)) for x in common_leaves(b["grad"])])
        # Relative gradient error on the curvatures and thicknesses (the design variables).
        gc64 = np.array(
            [float(s.c) for s in a["grad"].surfaces] + list(np.asarray(a["grad"].thickness))
        )
        gc32 = np.array(
            [float(s.c) for s in b["grad"].surfaces] + list(np.asarray(b["grad"].thickness, float))
        )
        rows.append(
            dict(
                lens=name,
                rays=n,
                forward_s={"float32": b["tf"]["run_s"], "float64": a["tf"]["run_s"]},
                forward_grad_s={"float32": b["tg"]["run_s"], "float64": a["tg"]["run_s"]},
                speedup_forward=a["tf"]["run_s"] / b["tf"]["run_s"],
                speedup_grad=a["tg"]["run_s"] / b["tg"]["run_s"],
                max_intercept_dev_mm=dev,
                valid_mismatch=int(
                    np.sum(np.asarray(a["out"].valid) != np.asarray(b["out"].valid))
                ),
                rel_dev_loss=abs(float(a["val"]) - float(b["val"])) / abs(float(a["val"])),
                rel_dev_grad_design=float(np.linalg.norm(gc32 - gc64) / np.linalg.norm(gc64)),
                rel_dev_grad_all=float(
                    np.linalg.norm(g32 - g64) / max(np.linalg.norm(g64), 1e-300)
                ),
            )
        )
    return {"rows": rows}


def common_leaves(tree):
    return [
        x
        for x in jax.tree_util.tree_leaves(tree)
        if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating)
    ]


def run(smoke: bool = False) -> dict:
    print("  rms spot against rays and pupil scheme")
    spot = rms_spot_study(smoke)
    print(f"    -> {spot['recommendation']}")
    print("  intersection error against Newton iterations")
    newton = newton_study(smoke)
    print(f"    -> {newton['recommendation']}")
    print("  float32 against float64")
    dt = dtype_study(smoke)
    for r in [] if smoke else dt["rows"]:
        print(
            f"    {r['lens']}: float32 {r['speedup_forward']:.2f}x faster forward, "
            f"{r['speedup_grad']:.2f}x grad; intercepts within {r['max_intercept_dev_mm']:.2e} mm,"
            f" design gradient within {r['rel_dev_grad_design']:.1e}"
        )
    return {"rms_spot": spot, "newton": newton, "dtype": dt}


def markdown(res: dict) -> str:
    out = []
    spot = res["rms_spot"]
    rec = spot["recommendation"]
    out += ["### RMS spot estimate against rays and pupil scheme", ""]
    rows = [r for r in spot["rows"] if "scheme" in r]
    for name in sorted({r["lens"] for r in rows}):
        body = [
            [r["scheme"], str(r["n"]), r["rays"], float(r["rel_error"]), float(r["time_s"])]
            for r in rows
            if r["lens"] == name
        ]
        out += [
            f"**{name}**",
            "",
            common.md_table(["scheme", "n", "rays", "rel. error", "time s"], body),
            "",
        ]
    out += [
        f"Recommended (≤ {rec['target_rel_error']:.0%} on every lens and field): "
        f"{rec['equal_weight']}; weighted polar Gauss rule: {rec['weighted_gauss']}",
        "",
    ]
    out += ["### Intersection error against Newton iterations", ""]
    body = [
        [
            r["lens"],
            r["dtype"],
            r["newton_iters"],
            r["max_error_mm"] if r["max_error_mm"] is not None else "–",
            float(r["valid_fraction"]),
            float(r["run_s"]),
        ]
        for r in res["newton"]["rows"]
    ]
    out += [
        common.md_table(["lens", "dtype", "iters", "max error mm", "valid", "time s"], body),
        "",
        f"Recommended: {res['newton']['recommendation']}",
        "",
    ]
    if "speedup_grad" not in (res["dtype"]["rows"] or [{}])[0]:
        return "\n".join(out)
    out += ["### float32 against float64", ""]
    body = [
        [
            r["lens"],
            f"{r['speedup_forward']:.2f}x",
            f"{r['speedup_grad']:.2f}x",
            float(r["max_intercept_dev_mm"]),
            r["valid_mismatch"],
            float(r["rel_dev_loss"]),
            float(r["rel_dev_grad_design"]),
        ]
        for r in res["dtype"]["rows"]
    ]
    out += [
        common.md_table(
            [
                "lens",
                "f32 speed-up fwd",
                "f32 speed-up grad",
                "max |Δ intercept| mm",
                "valid mismatches",
                "rel. Δ loss",
                "rel. Δ grad (c, t)",
            ],
            body,
        )
    ]
    return "\n".join(out)


def plot(res: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in res["rms_spot"]["rows"] if "scheme" in r]
    lenses = sorted({r["lens"] for r in rows})
    fig, axes = plt.subplots(
        1, len(lenses) + 1, figsize=(4.5 * (len(lenses) + 1), 4), squeeze=False
    )
    for ax, name in zip(axes[0], lenses, strict=False):
        for scheme in SCHEMES:
            sel = [r for r in rows if r["lens"] == name and r["scheme"] == scheme]
            if sel:
                ax.loglog(
                    [r["time_s"] for r in sel],
                    [max(r["rel_error"], 1e-16) for r in sel],
                    marker="o",
                    label=scheme,
                )
        ax.axhline(res["rms_spot"]["recommendation"]["target_rel_error"], color="k", lw=0.5)
        ax.set_title(f"RMS spot: {name}")
        ax.set_xlabel("time of rms_spot (s)")
        ax.set_ylabel("relative error")
        ax.legend(fontsize=7)
    ax = axes[0][-1]
    for name in sorted({r["lens"] for r in res["newton"]["rows"]}):
        for dtype in ("float32", "float64"):
            sel = [r for r in res["newton"]["rows"] if r["lens"] == name and r["dtype"] == dtype]
            ax.semilogy(
                [r["newton_iters"] for r in sel],
                [max(r["max_error_mm"] or 1.0, 1e-16) for r in sel],
                marker="o",
                label=f"{name} {dtype}",
            )
    ax.set_title("intersection error vs Newton iterations")
    ax.set_xlabel("newton_iters")
    ax.set_ylabel("max image intercept error (mm)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    common.save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":  # ran nothing, without a word: the suite's runner, this benchmark
    import sys

    from benchmarks.run import main

    main(["--only", "pareto", *sys.argv[1:]])
