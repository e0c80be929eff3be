"""Round 43e: settle round 42e's four unconfirmed gradient rows (``tools/grad42e_probe.py``
section ``aim``): the Cooke triplet with real ray aiming, d/dx of Σ OPD² over four pupil
points at 12° for x = the EPD, the field angle and the wavelength (``aim="real"``) and the
field (``"real_marginal"``), where ``jax.grad`` and central differences at three steps
disagreed by 1.6e-6 … 1e-5 relative.

For each row: grad, jvp, and central differences D(h) on a ladder h = h0·2^-j (j = 0 … 11)
with two Richardson extrapolations (R1 = (4 D(h/2) − D(h))/3 removes the h² error, R2 the h⁴
one), once with the library's aiming tolerance (``sampling.AIM_CONVERGED``) and once with it
tightened 1000-fold (``--tight``, a process of its own): whether the solver's convergence is
what the differences see.

    PYTHONPATH=. python tools/grad43e_probe.py [--tight] [--aim=real_marginal] [name ...]

Findings (2026-12-03): see ``docs/stability.md`` ("Gradients through ray aiming").
"""

from __future__ import annotations

import dataclasses
import os
import sys

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.analysis import wavefront_error  # noqa: E402
from jaxlens.imaging import sampling  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

PTS = jnp.array([[0.0, 0.7], [0.5, -0.3], [-0.6, 0.6], [0.0, 0.0]])  # grad42e_probe's
FIELD, WL = 12.0, 0.55


def objective(aim, name):
    """x -> Σ OPD² (waves²) with x the EPD (mm), the field (deg) or the wavelength (µm)."""
    lens = dataclasses.replace(jl.zoo.cooke_triplet(), aim=aim)

    def f(x):
        L, field, wl = lens, FIELD, WL
        if name == "epd":
            L = eqx.tree_at(lambda m: m.epd, lens, x)
        elif name == "field":
            field = x
        else:
            wl = x
        w = wavefront_error.opd(L, jnp.asarray(field), PTS, wavelength=jnp.asarray(wl))
        return jnp.sum(w**2)

    x0 = {"epd": float(lens.epd), "field": FIELD, "wl": WL}[name]
    return f, x0


STEPS = {"epd": 1e-2, "field": 1e-1, "wl": 1e-3}


def ladder(f, x0, h0, n=12):
    fj = jax.jit(f)
    hs = h0 * 2.0 ** -np.arange(n)
    d = np.array([(float(fj(x0 + h)) - float(fj(x0 - h))) / (2 * h) for h in hs])
    r1 = (4 * d[1:] - d[:-1]) / 3
    r2 = (16 * r1[1:] - r1[:-1]) / 15
    return hs, d, r1, r2


def settle(aim, name, out=print):
    f, x0 = objective(aim, name)
    g = float(jax.jit(jax.grad(f))(x0))
    jv = float(jax.jit(lambda x: jax.jvp(f, (x,), (jnp.ones_like(x),))[1])(jnp.asarray(x0)))
    hs, d, r1, r2 = ladder(f, jnp.asarray(x0), STEPS[name])
    out(f"{aim:14s} {name:6s} grad={g:+.12e} jvp={jv:+.12e} (jvp-grad)/grad="
        f"{(jv - g) / g:.1e}")
    for j, h in enumerate(hs):
        cells = [f"h={h:.3e}", f"D={d[j]:+.12e} ({(d[j] - g) / g:+.1e})"]
        if j >= 1:
            cells.append(f"R1={r1[j - 1]:+.12e} ({(r1[j - 1] - g) / g:+.1e})")
        if j >= 2:
            cells.append(f"R2={r2[j - 2]:+.12e} ({(r2[j - 2] - g) / g:+.1e})")
        out("    " + "  ".join(cells))
    best = float(np.min(np.abs(np.concatenate([r1, r2]) - g)) / abs(g))
    return g, best


def main(argv):
    names = [a for a in argv[1:] if not a.startswith("--")] or ["epd", "field", "wl"]
    # One mode per process: compiled programs cached inside jaxlens would keep the old value.
    modes = [("tight", 1e-3)] if "--tight" in argv else [("library", 1.0)]
    base = dict(sampling.AIM_CONVERGED)
    for label, factor in modes:
        sampling.AIM_CONVERGED[True] = base[True] * factor
        print(f"== aiming tolerance {label}: AIM_CONVERGED = {sampling.AIM_CONVERGED[True]:g}")
        for aim in [a.split("=", 1)[1] for a in argv if a.startswith("--aim=")] or ["real"]:
            for name in names:
                _, best = settle(aim, name)
                print(f"   -> closest Richardson estimate to grad: {best:.1e} relative")
    sampling.AIM_CONVERGED.update(base)


if __name__ == "__main__":
    main(sys.argv)
