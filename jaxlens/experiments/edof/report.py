"""The EDoF experiment's report: the issue-10 table (``table2``), its pass/fail checks, its
Markdown form and the figures, made from the per-crop values that ``cli`` collects."""

from __future__ import annotations

import functools
import math
import os


def base_lens_data(classical) -> dict:
    """The base lens's first-order data for the table (``base_lens``)."""
    from jaxlens.optics import paraxial
    from jaxlens.optics.materials import Air

    pd = paraxial.paraxial_data(classical)
    return {"efl_mm": float(pd.efl), "fov_deg": _fov(classical), "fnum": float(pd.fnum),
            "image_diagonal_mm": float(math.hypot(*[float(v) for v in classical.sensor.size])),
            "elements": int(sum(1 for m in classical.materials if not isinstance(m, Air)))}


def table2(per_image, names, seeds, crop_info, test_names, source, base, light, nsr) -> dict:
    """The issue-10 schema from the per-crop values (means over crops and seeds).

    Args:
        per_image: ``{seed: {lens: {depth: {kind: {metric: [per crop]}}}}}``, seeds as strings.
        base: the base lens's data (:func:`base_lens_data`).
        light: ``{lens: [fraction of light on the sensor, one per seed]}``.
    """
    import numpy as np

    from jaxlens.experiments.edof import evaluate as E
    from jaxlens.experiments.edof import lenses as L

    seeds = [str(s) for s in seeds]
    depths = [E.depth_key(d) for d in L.TEST_DEPTHS_M]

    def mean(lens, d, kind, metric):
        return float(np.mean([per_image[s][lens][d][kind][metric] for s in seeds]))

    lenses = {}
    for n in names:
        lenses[n] = {d: {t: {m: mean(n, d, t, m) for m in ("psnr", "ssim")}
                         for t in ("sim", "rec")} for d in depths}
        lenses[f"wiener_{n}"] = {d: {"sim": {m: mean(n, d, "sim", m) for m in ("psnr", "ssim")},
                                     "rec": {m: mean(n, d, "wiener", m)
                                             for m in ("psnr", "ssim")}} for d in depths}
    gains, per_seed, balanced = {}, {}, {}
    crop_images = [c["image"] for c in crop_info]
    if "classical" in names:
        for n in names:
            if n == "classical":
                continue
            gains[n], per_seed[n], balanced[n] = {}, {}, {}
            for d in depths:
                diff = np.array([np.subtract(per_image[s][n][d]["rec"]["psnr"],
                                             per_image[s]["classical"][d]["rec"]["psnr"])
                                 for s in seeds])  # [seeds, crops]
                gains[n][d] = E.bootstrap_gain(diff)
                balanced[n][d] = E.bootstrap_gain_by_image(diff, crop_images)
                per_seed[n][d] = diff.mean(axis=1).tolist()
    by_image = {}
    for n in names:
        for d in depths:
            for img in test_names:
                idx = [i for i, c in enumerate(crop_info) if c["image"] == img]
                if not idx:
                    continue
                v = [np.mean([per_image[s][n][d]["rec"]["psnr"][i] for s in seeds]) for i in idx]
                by_image.setdefault(n, {}).setdefault(d, {})[img] = float(np.mean(v))
    return {
        "seeds": [int(s) for s in seeds],
        "test": {"crops": int(len(crop_info)), "images": sorted({c["image"] for c in crop_info}),
                 "source": source, "crop_images": crop_images},
        "base_lens": base,
        "lenses": lenses,
        "gain_vs_classical": gains,
        "light_on_sensor": {n: float(np.mean(v)) for n, v in light.items()},
        "gain_per_seed": per_seed,
        "gain_vs_classical_image_balanced": balanced,
        "rec_psnr_by_image": by_image,
        "wiener_reference_nsr": nsr,
    }


@functools.cache
def _chief_height():
    """Jitted (lens, field angle) -> (|chief-ray height on the image|, valid): one program
    for every call with lenses of one layout, not one per call."""
    import jax
    import jax.numpy as jnp

    import jaxlens
    from jaxlens.imaging.aiming import stop_chief_ray

    @jax.jit
    def chief(lens, th):
        out = jaxlens.trace(lens, stop_chief_ray(lens, jnp.stack([0.0 * th, th])))
        return jnp.abs(out.origin[0, 1]), out.valid[0]  # (the image is inverted)

    return chief


def _fov(lens) -> float:
    """Diagonal field of view (degrees, object at infinity): twice the field angle whose
    real chief ray lands on the sensor corner (distortion included)."""
    import jax.numpy as jnp

    half = 0.5 * math.hypot(*[float(v) for v in lens.sensor.size])
    lens = lens.astype(jnp.float64)
    lo, hi = 0.0, 89.0
    for _ in range(40):  # bisection: the chief-ray height grows with the field angle
        mid = 0.5 * (lo + hi)
        h, ok = _chief_height()(lens, jnp.asarray(mid))
        lo, hi = (mid, hi) if bool(ok) and float(h) < half else (lo, mid)
    return 2 * lo


def checks(table: dict) -> dict:
    """The issue's pass/fail criteria, evaluated on the results."""
    out = {}
    g = table["gain_vs_classical"].get("hybrid")
    if g:
        out["hybrid_gain_db"] = {d: v["mean"] for d, v in g.items()}
        out["beats_by_1db_at_0.1m_ci_above_0"] = bool(g["0.1"]["mean"] >= 1.0
                                                     and g["0.1"]["ci95"][0] > 0)
        out["beats_by_1db_at_10m_ci_above_0"] = bool(g["10"]["mean"] >= 1.0
                                                    and g["10"]["ci95"][0] > 0)
        out["within_0.5db_at_0.2m"] = bool(g["0.2"]["mean"] >= -0.5)
    c = table["lenses"].get("classical")
    if c:
        out["classical_rec_minus_sim_db"] = {d: c[d]["rec"]["psnr"] - c[d]["sim"]["psnr"]
                                             for d in c}
        out["classical_deblurs_3db_at_0.1m"] = bool(
            out["classical_rec_minus_sim_db"]["0.1"] >= 3.0)
    v = table.get("psf_depth_variation", {})
    if "hybrid" in v and "classical" in v:
        out["psf_l1_hybrid_below_classical"] = bool(v["hybrid"]["l1"] < v["classical"]["l1"])
    return out


def table2_markdown(table: dict, command: str, cfg) -> str:
    depths = list(next(iter(table["lenses"].values())).keys())
    t = table["test"]
    lines = [
        "# EDoF lens: Table 2 analogue",
        "",
        f"Command: `{command}`",
        "",
        f"Test: {t['crops']} crops of {cfg.crop}² pixels at native resolution from "
        f"{len(t['images'])} images ({t['source']}); seeds {table['seeds']}. PSNR (dB) / SSIM "
        f"in linear light of the raw simulation (sim: shot noise of {cfg.photons:g} e⁻ at 1, "
        f"read noise σ = {cfg.read_noise:g}) and of the reconstruction (rec: decoder "
        f"'{cfg.decoder}'; for the wiener_* rows, Wiener deconvolution with the lens's "
        "depth-averaged PSF), averaged over crops and seeds, per object distance from the stop.",
        "",
        "| lens | " + " | ".join(f"{d} m sim | {d} m rec" for d in depths) + " |",
        "|---|" + "---|---|" * len(depths),
    ]
    for name, row in table["lenses"].items():
        cells = [f"{row[d][k]['psnr']:.2f} / {row[d][k]['ssim']:.3f}" for d in depths
                 for k in ("sim", "rec")]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    if table["gain_vs_classical"]:
        lines += ["", "Reconstruction PSNR gain over the classical lens (paired per crop, mean "
                  "over seeds; 95 % two-level bootstrap interval over seeds and crops; per-seed "
                  "means):", "", "| lens | " + " | ".join(f"{d} m" for d in depths) + " |",
                  "|---|" + "---|" * len(depths)]
        for n, g in table["gain_vs_classical"].items():
            cells = [f"{g[d]['mean']:+.2f} [{g[d]['ci95'][0]:+.2f}, {g[d]['ci95'][1]:+.2f}] "
                     f"({', '.join(f'{v:+.2f}' for v in table['gain_per_seed'][n][d])})"
                     for d in depths]
            lines.append(f"| {n} | " + " | ".join(cells) + " |")
    if table.get("gain_vs_classical_image_balanced"):
        counts = {}
        for img in table["test"].get("crop_images", []):
            counts[img] = counts.get(img, 0) + 1
        per = ", ".join(f"{k} {v}" for k, v in sorted(counts.items(), key=lambda kv: -kv[1]))
        lines += ["", "The same gain with every test image weighted equally (crops of an image "
                  "averaged first; 95 % bootstrap over seeds, images and crops within images)"
                  + (f"; crops per image: {per}" if per else "") + ":", "",
                  "| lens | " + " | ".join(f"{d} m" for d in depths) + " |",
                  "|---|" + "---|" * len(depths)]
        for n, g in table["gain_vs_classical_image_balanced"].items():
            cells = [f"{g[d]['mean']:+.2f} [{g[d]['ci95'][0]:+.2f}, {g[d]['ci95'][1]:+.2f}]"
                     for d in depths]
            lines.append(f"| {n} | " + " | ".join(cells) + " |")
    lines += ["", "Light on the sensor (fraction of the light entering the entrance pupil that "
              "lands in the PSF kernels, mean over 8 depths × all tiles × RGB): " +
              ", ".join(f"{n} {v:.3f}" for n, v in table["light_on_sensor"].items()) + "."]
    v = table.get("psf_depth_variation")
    if v:
        lines += ["", "PSF variation with depth (8 training depths, 3 × 3 tiles, RGB, PSFs "
                  "rescaled to unit sum): mean L1 distance over depth pairs (0 = identical, "
                  "2 = disjoint) and mean normalised cross-correlation (1 = identical).", "",
                  "| lens | L1 | NCC |", "|---|---|---|"]
        for n, x in v.items():
            lines.append(f"| {n} | {x['l1']:.3f} | {x['ncc']:.3f} |")
    b = table["base_lens"]
    lines += ["", f"Base lens: paraxial EFL {b['efl_mm']:.3f} mm, F/{b['fnum']:.2f}, "
              f"{b['fov_deg']:.1f}° diagonal field on a {b['image_diagonal_mm']:.2f} mm "
              f"diagonal, {b['elements']} elements."]
    return "\n".join(lines) + "\n"


def write_figures(out, names, trained, banks, examples, windows, histories, cfg, pix, *,
                  smoke=False) -> dict:
    """PSF grids, MTF curves, odd-polynomial profile, reconstructions and loss curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from jaxlens.experiments.edof import lenses as L
    from jaxlens.experiments.edof import optics as O

    files = {}
    dpi = 60 if smoke else 110
    depths = L.DEPTHS_M

    def save(fig, stem):
        fig.tight_layout()
        path = os.path.join(out, f"{stem}.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        files[stem] = path

    for name in names:
        b = banks[name]  # [D, ty, tx, 3, k, k]
        ty = b.shape[1]
        diag = [(0, 0), (ty // 4, ty // 4), (ty // 2, ty // 2)]  # corner, between, near centre
        fig, axes = plt.subplots(len(depths), len(diag),
                                 figsize=(1.6 * len(diag) + 1, 1.5 * len(depths)))
        for i, d in enumerate(depths):
            for j, (r, c) in enumerate(diag):
                ax = axes[i, j]
                img = np.transpose(b[i, r, c], (1, 2, 0))
                ax.imshow(np.sqrt(np.clip(img, 0, None) / max(img.max(), 1e-12)),
                          interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                if j == 0:
                    ax.set_ylabel(f"{d:g} m", fontsize=8)
                if i == 0:
                    ax.set_title(f"tile {r},{c}", fontsize=8)
        fig.suptitle(f"{name}: RGB PSFs by depth and tile, √ scale", fontsize=9)
        save(fig, f"psf_grid_{name}")

    fig, axes = plt.subplots(1, len(names), figsize=(4 * len(names), 3.4), squeeze=False)
    cmap = plt.get_cmap("viridis")
    for j, name in enumerate(names):
        b = banks[name]
        mid = b.shape[1] // 2
        f, mx, my = O.bank_mtf(b[:, mid, mid], pix)
        ax = axes[0, j]
        for k, d in enumerate(depths):
            ax.plot(f, 0.5 * (mx[k] + my[k]), color=cmap(k / (len(depths) - 1)),
                    label=f"{d:g} m")
        ax.set_ylim(0, 1.02)
        ax.set_title(f"{name}, centre tile", fontsize=9)
        ax.set_xlabel("cycles/mm")
        ax.set_ylabel("MTF (mean of x and y)")
    axes[0, -1].legend(fontsize=7)
    save(fig, "mtf_by_depth")

    odd = [n for n in names if n in ("hybrid", "cubic")]
    if odd:
        fig, axes = plt.subplots(1, len(odd), figsize=(4.2 * len(odd), 3.6), squeeze=False)
        for j, name in enumerate(odd):
            x, h = L.odd_profile(trained[name][0])
            im = axes[0, j].imshow(1e3 * h, extent=(x[0], x[-1], x[0], x[-1]), origin="lower",
                                   cmap="RdBu_r")
            fig.colorbar(im, ax=axes[0, j], label="µm")
            axes[0, j].set_title(f"{name}: odd-polynomial height", fontsize=9)
            axes[0, j].set_xlabel("x (mm)")
            axes[0, j].set_ylabel("y (mm)")
        save(fig, "odd_profile")

    if examples and all(examples.get(n) for n in names):
        m = cfg.kernel_size // 2
        gt = windows[0][m:m + cfg.crop, m:m + cfg.crop]
        keys = list(examples[names[0]].keys())
        enc = lambda im: np.clip(im, 0, 1) ** (1 / 2.2)  # noqa: E731 (display only)
        fig, axes = plt.subplots(len(names), 1 + 3 * len(keys),
                                 figsize=(1.7 * (1 + 3 * len(keys)), 1.9 * len(names)),
                                 squeeze=False)
        for i, name in enumerate(names):
            axes[i, 0].imshow(enc(gt))
            axes[i, 0].set_ylabel(name)
            axes[i, 0].set_title("ground truth", fontsize=7)
            for k, d in enumerate(keys):
                for t, (im, lab) in enumerate(zip(examples[name][d], ("sim", "rec", "wiener"),
                                                  strict=True)):
                    axes[i, 1 + 3 * k + t].imshow(enc(im))
                    axes[i, 1 + 3 * k + t].set_title(f"{lab} {d} m", fontsize=7)
        for ax in axes.ravel():
            ax.set_xticks([])
            ax.set_yticks([])
        save(fig, "reconstructions")

    fig, ax = plt.subplots(1, 2, figsize=(10, 3.5))
    for tag, h in histories.items():
        h1 = h["stage1"]
        ax[0].plot([r["step"] for r in h1], [r["loss"] for r in h1], label=f"{tag} L")
        h2 = h["stage2"]
        ax[1].plot([r["step"] for r in h2], [r["rec"] for r in h2], label=tag)
    ax[0].set_title("stage 1 (joint)", fontsize=9)
    ax[1].set_title("stage 2 (perturbed lenses), L_rec", fontsize=9)
    for x in ax:
        x.set_xlabel("step")
        x.legend(fontsize=6)
    save(fig, "loss")
    return files
