"""Design-loss gradient step: this checkout against an earlier commit, in one process.

The default classical spec and recipe (float32, every random start of ``--seeds`` at once, the
curriculum's first stage): ``jit(vmap(value_and_grad(design loss)))`` is compiled and timed for
each version, the versions alternating, and the median of ``--repeats`` calls is reported. The
earlier commit's ``jaxlens`` package is extracted with ``git archive`` into a temporary folder
and imported under another name, so both run on the same machine at the same load.

    python -m benchmarks.design_step --baseline cf2efb6
"""

from __future__ import annotations

import argparse
import importlib
import io
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np

from .common import write_json

NAME = "jaxlens_baseline"


def import_baseline(ref: str):
    """Import the ``jaxlens`` package of git revision ``ref`` as ``jaxlens_baseline``."""
    top = subprocess.check_output(["git", "rev-parse", "--show-toplevel"], text=True).strip()
    tar = subprocess.check_output(["git", "-C", top, "archive", ref, "jaxlens"])
    tmp = tempfile.mkdtemp(prefix="jaxlens_baseline_")
    with tarfile.open(fileobj=io.BytesIO(tar)) as tf:
        tf.extractall(tmp, filter="data")
    os.rename(os.path.join(tmp, "jaxlens"), os.path.join(tmp, NAME))
    # Earlier versions looked one module up by its absolute name.
    for root, _, names in os.walk(os.path.join(tmp, NAME)):
        for n in names:
            if n.endswith(".py"):
                path = os.path.join(root, n)
                with open(path) as f:
                    text = f.read()
                with open(path, "w") as f:
                    f.write(text.replace('sys.modules["jaxlens.', f'sys.modules["{NAME}.'))
    sys.path.insert(0, tmp)
    return importlib.import_module(NAME)


def step_fn(pkg, seeds: int):
    """(jitted loss-and-gradient over the seeds, params, args) of package ``pkg``."""
    import jax
    import jax.numpy as jnp

    design = importlib.import_module(pkg.__name__ + ".design")
    ms = importlib.import_module(pkg.__name__ + ".design.multistart")
    cur = importlib.import_module(pkg.__name__ + ".design.curriculum")
    losses = importlib.import_module(pkg.__name__ + ".design.losses")
    init = importlib.import_module(pkg.__name__ + ".design.init")
    spec = design.DesignSpec()
    config = ms.DesignConfig()
    dtype = jnp.float32
    pmap = init.parameterization(spec, dtype)
    sampling = losses.RayLoss.make(config.n_fields, config.rings, spec.wavelengths,
                                   spec.sensor_size, dtype)
    objective = losses.Objective(pmap, sampling, jnp.asarray(init.gap_bounds(spec), dtype))
    params = init.random_starts(spec, list(range(seeds)), dtype)
    stage = config.stages(spec)[0]
    weights = jnp.ones((seeds, config.n_fields), dtype)
    args = cur.stage_args(spec, stage, weights, config.reg_weights, dtype)

    def loss(p, a):
        res, _ = objective(p, a)
        return jnp.sum(res**2)

    fn = jax.jit(jax.vmap(jax.value_and_grad(loss)))
    return fn, params, args


def timed(fn, params, args):
    import jax

    t0 = time.perf_counter()
    jax.block_until_ready(fn(params, args))
    return time.perf_counter() - t0


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--baseline", default="cf2efb6", help="git revision to compare against")
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--repeats", type=int, default=20)
    p.add_argument("--tag", default="", help="suffix of the result file name")
    a = p.parse_args(argv)
    if a.seeds < 1 or a.repeats < 1:
        p.error("--seeds and --repeats must be at least 1")
    import jaxlens

    versions = {"new": jaxlens, "baseline": import_baseline(a.baseline)}
    fns = {k: step_fn(v, a.seeds) for k, v in versions.items()}
    compile_s = {k: timed(*f) for k, f in fns.items()}
    runs = {k: [] for k in fns}
    for _ in range(a.repeats):
        for k, f in fns.items():
            runs[k].append(timed(*f))
    med = {k: float(np.median(v)) for k, v in runs.items()}
    vals = {k: float(np.sum(np.asarray(f[0](f[1], f[2])[0]))) for k, f in fns.items()}
    result = {
        "benchmark": "design-loss value_and_grad, default spec and recipe, first curriculum "
                     f"stage, float32, {a.seeds} seeds vmapped",
        "baseline": a.baseline,
        "median_s": med,
        "compile_s": compile_s,
        "speedup_new_over_baseline": med["baseline"] / med["new"],
        "loss_sum": vals,
        "load": os.getloadavg()[0],
        "cpu_count": os.cpu_count(),
    }
    write_json("design_step" + (f"_{a.tag}" if a.tag else ""), result)
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
