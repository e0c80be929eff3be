"""Design-loss gradient step and the bare trace: this checkout against an earlier commit.

The default classical spec and recipe (float32, every random start of ``--seeds`` at once, the
curriculum's first stage): ``jit(vmap(value_and_grad(design loss)))``, the loss as the solver
factory hands it to Adam (since the polynomial reverse rule: ``Objective(reverse_rule=True)``),
is compiled and timed for
each version, the versions alternating, and the median of ``--repeats`` calls is reported; so
are the bare trace's forward and forward + gradient on the Cooke triplet (``--rays``). The
earlier commit's ``jaxlens`` package is extracted with ``git archive`` into a temporary folder
and imported under another name, so both run on the same machine at the same load.

    python -m benchmarks.design_step --baseline cf2efb6
"""

from __future__ import annotations

import importlib
import io
import json
import os
import pathlib
import re
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np

from .common import write_json

NAME = "jaxlens_baseline"


def baseline_problem(ref: str) -> str | None:
    """Why ``import_baseline(ref)`` cannot work, in one line (``--baseline``), else None.

    Before: a revision git does not know ended in ``git archive``'s traceback."""
    def git(*args):
        return subprocess.run(["git", *args], capture_output=True, text=True)

    try:
        top = git("rev-parse", "--show-toplevel")
    except OSError as e:  # git is not installed
        return f"--baseline {ref}: git is needed to read an earlier revision ({e})"
    if top.returncode:
        return (f"--baseline {ref}: the current folder is not in a git checkout of jaxlens "
                f"(run from the repository)")
    root = top.stdout.strip()
    if not ref or ref.startswith("-") or git("-C", root, "rev-parse", "--verify", "--quiet",
                                             f"{ref}^{{commit}}").returncode:
        return (f"--baseline {ref!r}: git does not know this revision in {root} (a commit, "
                f"tag or branch: see git log --oneline)")
    if git("-C", root, "cat-file", "-e", f"{ref}:jaxlens").returncode:
        return f"--baseline {ref}: that revision has no jaxlens package to compare against"
    return None


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
                with open(path, "w") as f:  # temporary: an extracted copy
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
    objective = ms.make_solver_factory(config, spec, dtype)("adam", 1.0, objective).residual_fn
    params = init.random_starts(spec, list(range(seeds)), dtype)
    stage = config.stages(spec)[0]
    weights = jnp.ones((seeds, config.n_fields), dtype)
    args = cur.stage_args(spec, stage, weights, config.reg_weights, dtype)

    def loss(p, a):
        res, _ = objective(p, a)
        return jnp.sum(res**2)

    fn = jax.jit(jax.vmap(jax.value_and_grad(loss)))
    return fn, params, args


def trace_fns(pkg, n: int):
    """(forward, forward + gradient, lens, rays): the Cooke triplet, float32, ``n`` rays."""
    import jax
    import jax.numpy as jnp

    lens = pkg.zoo.cooke_triplet().astype(jnp.float32)
    pupil = np.random.default_rng(0).uniform(-0.7, 0.7, (n, 2))
    rays = pkg.sampling.collimated(lens, 10.0, jnp.asarray(pupil, jnp.float32))

    def loss(lens, rays):
        out = pkg.trace(lens, rays)
        return jnp.sum(jnp.where(out.valid, out.origin[:, 1] ** 2, 0.0))

    fwd = jax.jit(lambda lens, rays: pkg.trace(lens, rays).origin)
    return fwd, jax.jit(jax.value_and_grad(loss)), lens, rays


def timed(fn, params, args):
    import jax

    t0 = time.perf_counter()
    jax.block_until_ready(fn(params, args))
    return time.perf_counter() - t0


def compile_all(fns: dict) -> tuple[dict, list]:
    """Compile every function of ``fns`` ({name: (jitted fn, x, y)}) and replace it by its
    executable; returns (seconds to lower, compile and run once, by name; shared names).

    A baseline program whose lowered text (without source locations) is the new version's,
    e.g. ``--baseline HEAD`` on a clean checkout, is not compiled a second time: it runs the
    new version's executable on its own inputs (the same leaves in the same order), and its
    name is listed as shared."""
    import jax

    texts, compile_s, shared = {}, {}, []
    for k, (fn, x, y) in list(fns.items()):
        t0 = time.perf_counter()
        low = fn.lower(x, y)
        texts[k] = low.as_text()
        twin = k.replace("baseline", "new")
        if twin != k and texts.get(twin) == texts[k]:
            exe = fns[twin][0]
            x, y = (jax.tree.unflatten(jax.tree.structure(a), jax.tree.leaves(b))
                    for a, b in zip(fns[twin][1:], (x, y), strict=True))
            shared.append(k)
        else:
            exe = low.compile()
        fns[k] = (exe, x, y)
        jax.block_until_ready(exe(x, y))
        compile_s[k] = time.perf_counter() - t0
    return compile_s, shared


def main(argv=None) -> dict:
    from jaxlens.experiments.runfolder import OneLineParser
    from jaxlens.optics.checks import MAX_DESIGNS

    from .common import MAX_REPEATS, out_path, whole
    from .throughput import MAX_RAYS

    p = OneLineParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--baseline", default="cf2efb6", help="git revision to compare against")
    p.add_argument("--seeds", type=whole(1, "seeds", MAX_DESIGNS), default=4)
    p.add_argument("--repeats", type=whole(1, "repeats", MAX_REPEATS), default=20)
    p.add_argument("--rays", type=whole(1, "rays", MAX_RAYS), default=1_000_000,
                   help="rays of the bare-trace timing")
    p.add_argument("--tag", default="", help="suffix of the result file name")
    p.add_argument("--out-dir", type=out_path("folder"), default=None,
                   help="folder of the result (default: results/)")
    a = p.parse_args(argv)
    if a.seeds < 1 or a.repeats < 1:
        p.error("--seeds and --repeats must be at least 1")
    if a.tag and not re.fullmatch(r"[A-Za-z0-9_-]+", a.tag):  # "../x" wrote outside --out-dir
        p.error(f"--tag: letters, digits, '_' and '-' only (a file name's suffix), got {a.tag!r}")
    problem = baseline_problem(a.baseline)
    if problem:
        p.error(problem)
    import jaxlens

    versions = {"new": jaxlens, "baseline": import_baseline(a.baseline)}
    fns = {k: step_fn(v, a.seeds) for k, v in versions.items()}
    for k, v in versions.items():
        fwd, grad, lens, rays = trace_fns(v, a.rays)
        fns[f"trace_forward_{k}"] = (fwd, lens, rays)
        fns[f"trace_grad_{k}"] = (grad, lens, rays)
    compile_s, shared = compile_all(fns)
    runs = {k: [] for k in fns}
    for _ in range(a.repeats):
        for k, f in fns.items():
            runs[k].append(timed(*f))
    med = {k: float(np.median(v)) for k, v in runs.items()}
    best = {k: float(np.min(v)) for k, v in runs.items()}
    vals = {k: float(np.sum(np.asarray(fns[k][0](fns[k][1], fns[k][2])[0])))
            for k in versions}
    result = {
        "benchmark": "design-loss value_and_grad, default spec and recipe, first curriculum "
                     f"stage, float32, {a.seeds} seeds vmapped",
        "baseline": a.baseline,
        "median_s": med,
        "best_s": best,
        "compile_s": compile_s,
        "speedup_new_over_baseline": med["baseline"] / med["new"],
        "speedup_best_new_over_baseline": best["baseline"] / best["new"],
        "trace": f"Cooke triplet, float32, {a.rays} rays, 10 deg, forward and value_and_grad",
        "trace_grad_over_forward_rate": {
            k: med[f"trace_forward_{k}"] / med[f"trace_grad_{k}"] for k in versions},
        "loss_sum": vals,
        "shared_compile": shared,
        "load": os.getloadavg()[0],
        "cpu_count": os.cpu_count(),
    }
    name = "design_step" + (f"_{a.tag}" if a.tag else "")
    if a.out_dir is None:
        write_json(name, result)
    else:
        write_json(name, result, pathlib.Path(a.out_dir))
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
