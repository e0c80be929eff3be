"""The fast path with mirrors and coordinate breaks in the tracer: a lens without them must
compile to the same program and run at the same speed as before they existed (issue 12).

In one process, the Cooke triplet (float32, 10°) is traced by this checkout and by the
``jaxlens`` package of an older revision (imported as ``jaxlens_baseline``, see
``design_step.import_baseline``): the jaxprs of the forward trace and of its gradient are
compared as text, the results bit for bit, and the forward and forward + gradient times are
taken interleaved (median of ``--repeats``, after a warm-up call).

    python -m benchmarks.fast_path --baseline 04deecd
"""

from __future__ import annotations

import time

import numpy as np

from . import common
from .design_step import baseline_problem, import_baseline, trace_fns


def main(argv=None) -> dict:
    import jax

    import jaxlens
    from jaxlens.experiments.runfolder import OneLineParser

    from .common import MAX_REPEATS, whole
    from .throughput import MAX_RAYS

    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", default="04deecd", help="git revision to compare against")
    p.add_argument("--rays", type=whole(1, "rays", MAX_RAYS), default=2**19)
    p.add_argument("--repeats", type=whole(1, "repeats", MAX_REPEATS), default=15)
    a = p.parse_args(argv)
    problem = baseline_problem(a.baseline)
    if problem:
        p.error(problem)
    versions = {"new": jaxlens, "baseline": import_baseline(a.baseline)}
    fns = {k: trace_fns(v, a.rays) for k, v in versions.items()}

    def jaxpr_text(k):
        fwd, grad, lens, rays = fns[k]
        text = str(jax.make_jaxpr(fwd)(lens, rays)) + str(jax.make_jaxpr(grad)(lens, rays))
        return text.replace("jaxlens_baseline", "jaxlens")

    same_jaxpr = jaxpr_text("new") == jaxpr_text("baseline")
    results = {k: jax.block_until_ready((f(lens, rays), g(lens, rays)))
               for k, (f, g, lens, rays) in fns.items()}
    bit_equal = all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(
        jax.tree.leaves(results["new"]), jax.tree.leaves(results["baseline"]), strict=True))
    times = {f"{w}_{k}": [] for w in ("forward", "grad") for k in versions}
    for _ in range(a.repeats):  # interleaved, so load from other jobs hits both alike
        for k, (f, g, lens, rays) in fns.items():
            for w, fn in (("forward", f), ("grad", g)):
                t0 = time.perf_counter()
                jax.block_until_ready(fn(lens, rays))
                times[f"{w}_{k}"].append(time.perf_counter() - t0)
    med = {k: float(np.median(v)) for k, v in times.items()}
    surfaces = 6
    payload = {
        "baseline": a.baseline,
        "lens": "Cooke triplet, float32, 10 deg field",
        "rays": a.rays,
        "repeats": a.repeats,
        "same_jaxpr_forward_and_grad": same_jaxpr,
        "bit_equal_results": bit_equal,
        "median_s": med,
        "forward_ray_surfaces_per_s": {
            k: a.rays * surfaces / med[f"forward_{k}"] for k in versions},
        "new_over_baseline_forward_time": med["forward_new"] / med["forward_baseline"],
        "new_over_baseline_grad_time": med["grad_new"] / med["grad_baseline"],
        "machine": common.machine_info(),
    }
    common.write_json("fast_path", payload)
    print({k: v for k, v in payload.items() if k != "machine"})
    return payload


if __name__ == "__main__":
    main()
