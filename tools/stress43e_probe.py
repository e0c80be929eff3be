"""Round 43e: jaxlens's float64 and float32 traces against the 40-digit reference of
``tools/stress43e_reference.py`` (``tests/data/stress43e/reference.json``).

    PYTHONPATH=. python tools/stress43e_probe.py [case substring ...]

For every case and ray, after every surface: the largest error of the intercept (mm), of
the direction cosines, and of the optical path from the ray's origin (mm), each also
relative to the case's lens scale L (mm), and in units of what the precision allows (the
reference's conditioning floor plus one rounding of L; for directions one rounding of 1 and
the turn of a normal moved by a rounding of L, u·(1 + L·max|c|)). A ray the reference
loses must be flagged invalid from that surface on, and a ray it keeps must stay valid.
``measure`` is what ``tests/test_stress_round43e.py`` checks.
"""

from __future__ import annotations

import json
import os
import sys
from decimal import Decimal, getcontext

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.optics.materials import ModelGlass  # noqa: E402

getcontext().prec = 60
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REFERENCE = os.path.join(ROOT, "tests", "data", "stress43e", "reference.json")
WAVELENGTH = 0.5875618


def load_cases():
    with open(REFERENCE) as fh:
        return json.load(fh)["cases"]


def _material(n):
    return jl.Air() if n == 1.0 else ModelGlass(n, float("inf"))


def build(case, dtype):
    """(lens, rays) of a case in ``dtype``: float32 from the float32-rounded inputs."""
    spec = case if dtype == jnp.float64 else case["inputs_float32"]
    surfaces = tuple(
        jl.EvenAsphere(s["c"], s["k"], jnp.asarray(s["coeffs"], jnp.float64)) if s.get("coeffs")
        else jl.Conic(s["c"], s["k"]) for s in spec["surfaces"])
    index = spec["index"]
    lens = jl.Lens(surfaces=surfaces, thickness=jnp.asarray(spec["thickness"], jnp.float64),
                   materials=tuple(_material(n) for n in index[1:]),
                   object_material=_material(index[0]), mirrors=tuple(spec["mirrors"]),
                   epd=1.0, wavelengths=jnp.array([WAVELENGTH]))
    o = np.array([r["o"] for r in spec["rays"]], np.float64)
    d = np.array([r["d"] for r in spec["rays"]], np.float64)
    if dtype == jnp.float32:
        lens = lens.astype(jnp.float32)
    rays = jl.Rays(jnp.asarray(o, dtype), jnp.asarray(d, dtype), jnp.asarray(WAVELENGTH, dtype))
    return lens, rays


def _err(x, ref):
    return abs(float(Decimal(float(x)) - Decimal(ref)))


def measure(case, dtype, newton_iters=jl.tracing.DEFAULT_NEWTON_ITERS):
    """Per ray and surface: dict(pos, dir, opl) of absolute errors (mm, -, mm), and the
    validity disagreements as (ray, surface, jaxlens valid, reference valid)."""
    lens, rays = build(case, dtype)
    path = jl.tracing.trace_path(lens, rays, newton_iters=newton_iters)
    p, dd = np.asarray(path.origin, np.float64), np.asarray(path.direction, np.float64)
    opl, valid = np.asarray(path.opl, np.float64), np.asarray(path.valid)
    key = "float64" if dtype == jnp.float64 else "float32"
    errors, disagree = [], []
    for j, row in enumerate(case["reference"][key]):
        for i, ref in enumerate(row):
            if (ref is not None) != bool(valid[i, j]):
                disagree.append((j, i, bool(valid[i, j]), ref is not None))
                continue
            if ref is None:
                continue
            e = dict(ray=j, surface=i,
                     pos=max(_err(p[i, j, a], ref["p"][a]) for a in range(3)),
                     dir=max(_err(dd[i, j, a], ref["d"][a]) for a in range(3)),
                     opl=_err(opl[i, j], ref["opl"]))
            # In units of what the precision allows: the conditioning floor plus one
            # rounding of the lens scale L (positions, path), or for directions one rounding
            # of 1 and the turn of a normal moved by a rounding of L, u·(1 + L·max|c|).
            u = float(jnp.finfo(dtype).eps) / 2
            c_max = max(abs(s_["c"]) for s_ in case["surfaces"])
            allow = dict(pos=u * case["scale"], dir=u * (1 + case["scale"] * c_max),
                         opl=u * case["scale"])
            for q in ("pos", "dir", "opl"):
                e[q + "_units"] = e[q] / (ref["floor"][q] + allow[q])
            errors.append(e)
    return errors, disagree


def opd_spread(case, dtype):
    """For a case whose rays should all have the same OPL on the last plane (a perfect
    mirror at its focus): the largest |OPL − OPL of ray 0| of jaxlens's and of the
    reference's (mm)."""
    lens, rays = build(case, dtype)
    opl = np.asarray(jl.tracing.trace_path(lens, rays).opl[-1], np.float64)
    key = "float64" if dtype == jnp.float64 else "float32"
    ref = [Decimal(row[-1]["opl"]) for row in case["reference"][key]]
    return (float(np.max(np.abs(opl - opl[0]))),
            float(max(abs(r - ref[0]) for r in ref)))


def summary(case, dtype):
    errors, disagree = measure(case, dtype)
    worst = {q: max((e[q] for e in errors), default=0.0) for q in
             ("pos", "dir", "opl", "pos_units", "dir_units", "opl_units")}
    return worst, disagree


def main(argv):
    picks = argv[1:]
    print(f"{'case':24s} {'dtype':7s} {'scale':>7s} {'pos mm':>9s} {'pos/scale':>9s} "
          f"{'dir':>9s} {'opl mm':>9s} {'opl/scale':>9s} {'units p/d/o':>17s} validity")
    for case in load_cases():
        if picks and not any(p in case["name"] for p in picks):
            continue
        for dtype in (jnp.float64, jnp.float32):
            worst, disagree = summary(case, dtype)
            sc = case["scale"]
            print(f"{case['name']:24s} {jnp.dtype(dtype).name:7s} {sc:7.0e} {worst['pos']:9.1e} "
                  f"{worst['pos'] / sc:9.1e} {worst['dir']:9.1e} {worst['opl']:9.1e} "
                  f"{worst['opl'] / sc:9.1e} {worst['pos_units']:5.0f} {worst['dir_units']:5.0f} "
                  f"{worst['opl_units']:5.0f} {disagree or 'agrees'}")
        if case["name"].startswith(("near_perfect", "paraboloid")):
            for dtype in (jnp.float64, jnp.float32):
                got, ref = opd_spread(case, dtype)
                print(f"  OPD spread {jnp.dtype(dtype).name}: jaxlens {got:.2e} mm, "
                      f"reference {ref:.2e} mm")


if __name__ == "__main__":
    main(sys.argv)
