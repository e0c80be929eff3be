"""Shared test helpers: build lenses from the reference-case files without the file loaders."""

from __future__ import annotations

import json
import pathlib

import jax.numpy as jnp
import numpy as np

import jaxlens as jl


def refcase_lens(path) -> tuple[jl.Lens, dict]:
    """A Lens from a refcase JSON (tabulated indices), and the raw case."""
    d = json.loads(pathlib.Path(path).read_text())
    surfs, th, mats, stop = [], [], [], 0
    for s in d["surfaces"][1:-1]:
        co = s.get("even_asphere_coeffs") or []
        c, k = s["curvature"], s.get("conic", 0.0)
        surfs.append(jl.EvenAsphere(c=c, k=k, coeffs=co) if co else jl.Standard(c=c, k=k))
        th.append(s["thickness"])
        n = s["n"]
        mats.append(
            jl.Tabulated(np.array([float(w) / 1000 for w in n]), np.array(list(n.values())))
        )
        if s.get("is_stop"):
            stop = len(surfs) - 1
    img = d["surfaces"][-1]
    wls = np.array(d["wavelengths_nm"]) / 1000
    lens = jl.Lens(
        surfaces=tuple(surfs),
        thickness=jnp.array(th),
        materials=tuple(mats),
        stop=stop,
        epd=d["aperture"]["EPD"],
        wavelengths=wls,
        primary=int(np.argmin(np.abs(wls - d["primary_wavelength_nm"] / 1000))),
        fields=jnp.array(d["fields"]["values"]),
        image=jl.Standard(c=img.get("curvature", 0.0), k=img.get("conic", 0.0)),
    )
    return lens, d


def refcase_rays(d, dtype=jnp.float64):
    """The reference real rays (launch) and their expected image data [N, 6]."""
    o, v, w, ref = [], [], [], []
    for r in d["real_rays"]:
        o.append(r["launch"]["point_on_EP_plane"])
        v.append(r["launch"]["direction_cosines"])
        w.append(r["wavelength_nm"] / 1000)
        im = r["image"]
        ref.append([im["x"], im["y"], im["z"], im["L"], im["M"], im["N"]])
    rays = jl.Rays(jnp.array(o, dtype), jnp.array(v, dtype), jnp.array(w, dtype))
    return rays, np.array(ref)
