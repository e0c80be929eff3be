"""Run time against error for image formation: PSF kernel size and pupil sampling, render spp.

The render *speed* and *memory* benchmarks belong to the render module
(``benchmarks/render_speed.py``, ``benchmarks/render_memory.py``); this module gives the
time-against-error curves that end in recommended defaults, on the 6-element phone lens
(``jaxlens.zoo.cellphone6``, the lens the renders use), primary wavelength, at the lens's
sensor pitch (5.29 µm):

* ``psf_kernel``: geometric PSF (``jaxlens.imaging.psf``) at 0, 70 % and 100 % of the field against
  ``kernel_size``. Error = the energy fraction outside the kernel (``truncated``), worst field.
  Time = one ``jaxlens.imaging.psf`` call. Recommended: the smallest kernel losing ≤ 1 % everywhere.
* ``psf_pupil``: the same PSF, at the recommended kernel, against the pupil sampling (rays per
  side); error = L1 distance to a 512-per-side reference (sum over the kernel of |Δ|, i.e. the
  fraction of energy misplaced), worst field. Recommended: the smallest pupil with L1 ≤ 2 %.
* ``render_spp``: ``jaxlens.imaging.render`` (method "ray") of the skimage ``astronaut`` scene on a
  192 × 192 sensor of the lens's full sensor side against spp; error = RMS difference from a
  reference (the mean of two 1024-spp renders with other seeds, whose own noise is subtracted
  in quadrature) over the RMS of the reference. spp that are perfect squares are stratified.
  Recommended: the smallest spp with error ≤ 2 % (and, for previews, ≤ 5 %).

The smoke run skips this module's heavy parts (it runs one tiny PSF point).
"""

from __future__ import annotations

import math
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxlens
from jaxlens import zoo

from . import common

KERNELS = (5, 7, 9, 11, 13, 15, 21, 31, 41)
PUPILS = (8, 16, 24, 32, 48, 64, 96, 128, 192, 256)
SPPS = (1, 2, 4, 8, 16, 32, 64, 144, 256, 400)
SPP_TARGETS = (0.02, 0.05)  # per-pixel relative RMSE; the first gives the recommended spp


def _psf(lens, field, kernel, pupil):
    return jaxlens.imaging.psf.psf_info(
        lens,
        field,
        kernel_size=kernel,
        model=jaxlens.imaging.psf.GeometricPSF(pupil=pupil),
        center="chief",
        max_truncation=None,
    )


def psf_study(smoke: bool = False) -> dict:
    lens = zoo.cellphone6()
    fmax = float(lens.fields[-1])
    fields = [0.0, 0.7 * fmax, fmax]
    kernels = (7, 11) if smoke else KERNELS
    rows_k = []
    for k in kernels:
        trunc = []
        t0 = time.perf_counter()
        for f in fields:
            r = _psf(lens, f, k, 64)
            trunc.append(float(r.truncated))
        first = time.perf_counter() - t0  # includes the compilation for this kernel size
        t = common.time_jitted(
            lambda f, k=k: _psf(lens, f, k, 64).psf,
            jnp.asarray(fields[-1]),
            repeats=3,
            min_total_s=0.2,
        )
        rows_k.append(
            dict(
                kernel_size=k,
                truncated_worst=max(trunc),
                truncated=trunc,
                time_s=t["run_s"],
                compile_s=first,
            )
        )
    rec_k = next((r["kernel_size"] for r in rows_k if r["truncated_worst"] <= 0.01), None)
    out = {"fields": fields, "kernel": rows_k, "recommended_kernel_size": rec_k}
    if smoke:
        return out
    k = rec_k or KERNELS[-1]
    refs = [np.asarray(_psf(lens, f, k, 512).psf) for f in fields]
    rows_p = []
    for p in PUPILS:
        t0 = time.perf_counter()
        errs = [
            float(np.abs(np.asarray(_psf(lens, f, k, p).psf) - ref).sum())
            for f, ref in zip(fields, refs, strict=True)
        ]
        first = time.perf_counter() - t0  # includes the compilation for this pupil size
        t = common.time_jitted(
            lambda f, p=p: _psf(lens, f, k, p).psf,
            jnp.asarray(fields[-1]),
            repeats=3,
            min_total_s=0.2,
        )
        rows_p.append(
            dict(
                pupil=p,
                rays=int(round(math.pi / 4 * p * p)),
                l1_worst=max(errs),
                l1=errs,
                time_s=t["run_s"],
                compile_s=first,
            )
        )
    out["pupil"] = rows_p
    out["pupil_kernel_size"] = k
    out["recommended_pupil"] = next((r["pupil"] for r in rows_p if r["l1_worst"] <= 0.02), None)
    return out


def render_study(size: int = 192, ref_spp: int = 1024) -> dict:
    """Render error against spp, with the reference's own noise taken out.

    Two independent ``ref_spp`` renders (other keys) give the reference (their mean) and its
    noise: the mean square of their difference is twice one render's noise variance, so the
    mean's is a quarter of it. The error of an spp render is then
    ``sqrt(max(rmse(img, ref)² − var_ref, 0)) / rms(ref)`` (``rel_rmse``), its raw value
    beside it (``rel_rmse_raw``). ``noise_1spp = rel_rmse · sqrt(spp)`` is the constant of
    the 1/√spp law, separately for perfect squares (stratified samples) and the rest.
    """
    from jaxlens import images

    lens = zoo.cellphone6()
    side = float(lens.sensor.pixel_size) * lens.sensor.resolution[1]
    sensor = jaxlens.Sensor((size, size), side / size)
    scene = jnp.asarray(images.scene("astronaut", (size, size)))
    fp = jaxlens.imaging.render.footprints(lens, sensor=sensor, dtype=jnp.float32)
    key = jax.random.PRNGKey(0)

    def go(spp, key=key):
        return jaxlens.render(lens, scene, spp=spp, key=key, sensor=sensor,
                              method=jaxlens.imaging.render.RayRender(footprints=fp))

    r1 = np.asarray(go(ref_spp, jax.random.PRNGKey(123)), np.float64)
    r2 = np.asarray(go(ref_spp, jax.random.PRNGKey(124)), np.float64)
    ref = 0.5 * (r1 + r2)
    var_ref = float(np.mean((r1 - r2) ** 2)) / 4.0
    scale = float(np.sqrt(np.mean(ref**2)))
    rows = []
    for spp in SPPS:
        t = common.time_jitted(go, spp, repeats=2, min_total_s=0.0)
        img = np.asarray(go(spp), np.float64)
        mse = float(np.mean((img - ref) ** 2))
        err = math.sqrt(max(mse - var_ref, 0.0)) / scale
        rows.append(
            dict(
                spp=spp,
                stratified=math.isqrt(spp) ** 2 == spp,
                rel_rmse=err,
                rel_rmse_raw=math.sqrt(mse) / scale,
                noise_1spp=err * math.sqrt(spp),
                time_s=t["run_s"],
                compile_s=t["compile_s"],
                load=t["load_before"],
            )
        )
        print(f"    spp {spp:3d}: rel. RMSE {err:.3e}, {t['run_s']:.2f} s")
    rec = {
        f"{target:.0%}": next((r["spp"] for r in rows if r["rel_rmse"] <= target), None)
        for target in SPP_TARGETS
    }
    return {
        "size": size,
        "reference_spp": ref_spp,
        "reference_rel_noise": math.sqrt(var_ref) / scale,
        "rows": rows,
        "recommended_spp": rec[f"{SPP_TARGETS[0]:.0%}"],
        "recommended_spp_by_target": rec,
        "note": f"reference = mean of two {ref_spp}-spp renders; its own noise "
        f"({math.sqrt(var_ref) / scale:.2%} of the image RMS) is subtracted in quadrature",
    }


def run(smoke: bool = False) -> dict:
    print("  PSF error against kernel size and pupil sampling")
    psf = psf_study(smoke)
    print(f"    -> kernel {psf['recommended_kernel_size']}, pupil {psf.get('recommended_pupil')}")
    res = {"psf": psf}
    if not smoke:
        print("  render error against spp")
        res["render"] = render_study()
        print(f"    -> spp {res['render']['recommended_spp']}")
    return res


def markdown(res: dict) -> str:
    psf = res["psf"]
    out = ["### PSF error against kernel size (cellphone6, geometric, worst of 3 fields)", ""]
    out.append(
        common.md_table(
            ["kernel", "energy outside", "time s"],
            [
                [r["kernel_size"], float(r["truncated_worst"]), float(r["time_s"])]
                for r in psf["kernel"]
            ],
        )
    )
    out += ["", f"Recommended kernel_size (≤ 1 % outside): {psf['recommended_kernel_size']}", ""]
    if "pupil" in psf:
        out += [f"### PSF error against pupil sampling (kernel {psf['pupil_kernel_size']})", ""]
        out.append(
            common.md_table(
                ["rays per side", "rays", "L1 error", "time s"],
                [
                    [r["pupil"], r["rays"], float(r["l1_worst"]), float(r["time_s"])]
                    for r in psf["pupil"]
                ],
            )
        )
        out += ["", f"Recommended pupil (L1 ≤ 2 %): {psf['recommended_pupil']}", ""]
    if "render" in res:
        r = res["render"]
        out += [
            f"### Render error against spp ({r['size']}², reference {r['reference_spp']} spp)",
            "",
        ]
        out.append(
            common.md_table(
                ["spp", "stratified", "rel. RMSE", "raw", "× √spp", "time s", "compile s"],
                [
                    [
                        x["spp"],
                        "yes" if x.get("stratified") else "no",
                        float(x["rel_rmse"]),
                        float(x.get("rel_rmse_raw", x["rel_rmse"])),
                        float(x["noise_1spp"]) if "noise_1spp" in x else None,
                        float(x["time_s"]),
                        float(x["compile_s"]),
                    ]
                    for x in r["rows"]
                ],
            )
        )
        by = r.get("recommended_spp_by_target", {"2%": r["recommended_spp"]})
        out += [
            "",
            "Recommended spp: "
            + ", ".join(f"{v} for ≤ {k}" for k, v in by.items())
            + f" ({r['note']})",
            "",
        ]
    return "\n".join(out)


def plot(res: dict, path) -> None:
    """Time against error: PSF kernel size, PSF pupil sampling and render spp."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    psf = res["psf"]
    panels = 1 + ("pupil" in psf) + ("render" in res)
    fig, axes = plt.subplots(1, panels, figsize=(4.5 * panels, 4), squeeze=False)
    ax = axes[0][0]
    ks = [r["kernel_size"] for r in psf["kernel"]]
    ax.semilogy(ks, [max(r["truncated_worst"], 1e-17) for r in psf["kernel"]], marker="o")
    ax.axhline(0.01, color="k", lw=0.5)
    ax.set_title("PSF kernel size (cellphone6)")
    ax.set_xlabel("kernel_size (pixels)")
    ax.set_ylabel("energy outside the kernel, worst field")
    i = 1
    if "pupil" in psf:
        ax = axes[0][i]
        i += 1
        ax.loglog(
            [r["time_s"] for r in psf["pupil"]], [r["l1_worst"] for r in psf["pupil"]], marker="o"
        )
        for r in psf["pupil"]:
            ax.annotate(str(r["pupil"]), (r["time_s"], r["l1_worst"]), fontsize=7)
        ax.axhline(0.02, color="k", lw=0.5)
        ax.set_title(f"PSF pupil rays per side (kernel {psf['pupil_kernel_size']})")
        ax.set_xlabel("time of one PSF (s)")
        ax.set_ylabel("L1 error, worst field")
    if "render" in res:
        ax = axes[0][i]
        rows = res["render"]["rows"]
        for strat, style in ((True, "o-"), (False, "s--")):
            sel = [r for r in rows if r.get("stratified", True) == strat]
            if sel:
                ax.loglog(
                    [r["time_s"] for r in sel],
                    [r["rel_rmse"] for r in sel],
                    style,
                    label="stratified (square spp)" if strat else "random (other spp)",
                )
                for r in sel:
                    ax.annotate(str(r["spp"]), (r["time_s"], r["rel_rmse"]), fontsize=7)
        ax.axhline(0.02, color="k", lw=0.5)
        ax.axhline(0.05, color="k", lw=0.5, ls=":")
        ax.set_title(f"render spp ({res['render']['size']}²)")
        ax.set_xlabel("time of one render (s)")
        ax.set_ylabel("per-pixel relative RMSE")
        ax.legend(fontsize=7)
    fig.tight_layout()
    common.save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":  # ran nothing, without a word: the suite's runner, this benchmark
    import sys

    from benchmarks.run import main

    main(["--only", "imaging", *sys.argv[1:]])
