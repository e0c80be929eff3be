"""Levers for the forward + gradient rate that need no change to the tracer (SPEED.md).

Cooke triplet, float32, the throughput benchmark's rays and spot loss. Each XLA:CPU flag
setting runs in a process of its own (``XLA_FLAGS`` is read once, when the backend starts),
and each prints its forward and forward + gradient times, their ratio, and CPU time over
wall time of the best run (2.0 = both cores busy). Then, with no flag, ``trace(chunk=)``
is varied for both passes.

    python -m benchmarks.grad_levers                 # every setting below, ~5 min on 2 cores
    python -m benchmarks.grad_levers --rays 20000 --flag= --chunks 4096   # a smoke run
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys

FLAGS = (
    "",
    "--xla_cpu_use_fusion_emitters=false",
    "--xla_cpu_experimental_xnn_fusion_type=eltwise,reduce",
    "--xla_cpu_experimental_xnn_graph_fusion_mode=XNN_GRAPH_FUSION_MODE_GREEDY",
    "--xla_cpu_opt_preset=CPU_OPT_PRESET_FAST_RUNTIME",
    "--xla_cpu_experimental_enable_tiling_propagation=true",
)
CHUNKS = (8192, 16384, 32768, 65536, 131072)


def measure(rays_n: int, chunks: list[int]) -> list[dict]:
    """Forward and forward + gradient at each chunk size (None: the default), in this process."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)  # as in the throughput benchmark: float64 setup

    import jaxlens
    from jaxlens import zoo

    from . import common, throughput

    lens = zoo.cooke_triplet()
    rays = throughput.make_rays(lens, rays_n, jnp.float32)
    rows = []
    for chunk in chunks:
        kw = {} if chunk is None else {"chunk": chunk}
        fwd = eqx.filter_jit(lambda lens, rays, kw=kw: jaxlens.trace(lens, rays, **kw))

        @eqx.filter_jit
        def grad(lens, rays, kw=kw):
            def loss(lens):
                out = jaxlens.trace(lens, rays, **kw)
                return throughput.spot_loss(out.origin[:, :2], out.valid)

            return eqx.filter_value_and_grad(loss)(lens)

        f = common.time_jitted(fwd, lens, rays, repeats=5)
        g = common.time_jitted(grad, lens, rays, repeats=5)
        rows.append(dict(chunk=chunk, forward_ms=1e3 * f["run_s"], grad_ms=1e3 * g["run_s"],
                         ratio=f["run_s"] / g["run_s"], forward_cores=f["cpu_s"] / f["run_s"],
                         grad_cores=g["cpu_s"] / g["run_s"], load=g["load_after"]))
    return rows


def main(argv=None) -> list[dict]:
    from jaxlens.experiments.runfolder import OneLineParser

    from .common import whole
    from .throughput import MAX_RAYS

    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--rays", type=whole(1, "rays", MAX_RAYS), default=1_000_000)
    p.add_argument("--flag", action="append", dest="flags",
                   help="an XLA_FLAGS setting (repeatable; --flag= for none); default: FLAGS")
    p.add_argument("--chunks", nargs="*", type=whole(1, "rays per chunk", MAX_RAYS),
                   default=list(CHUNKS))
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    for flags in a.flags or ():  # a typo failed in its child process, minutes in
        bad = [t for t in flags.split() if not t.startswith("--xla_")]
        if bad:
            p.error(f"--flag {flags!r}: {bad[0]!r} is not an XLA flag (XLA_FLAGS settings "
                    f"read --xla_<name>=<value>, e.g. {FLAGS[1]!r}; --flag= for none)")
    if a.child:  # one flag setting: default chunk only, JSON on the last line
        print(json.dumps(measure(a.rays, [None])[0]))
        return []
    out = []
    for flags in FLAGS if a.flags is None else a.flags:
        env = dict(os.environ, XLA_FLAGS=flags)
        run = subprocess.run([sys.executable, "-m", "benchmarks.grad_levers", "--child",
                              "--rays", str(a.rays)], env=env, capture_output=True, text=True,
                             cwd=pathlib.Path(__file__).resolve().parents[1])
        if run.returncode:
            print(f"{flags or '(no flag)'}: failed: {run.stderr.strip().splitlines()[-1:]}")
            continue
        row = dict(json.loads(run.stdout.strip().splitlines()[-1]), flags=flags)
        out.append(row)
        print(f"{flags or '(no flag)'}: forward {row['forward_ms']:.1f} ms "
              f"({row['forward_cores']:.2f} cores), f+g {row['grad_ms']:.1f} ms "
              f"({row['grad_cores']:.2f} cores), ratio {row['ratio']:.3f}", flush=True)
    for row in measure(a.rays, a.chunks):
        out.append(row)
        print(f"chunk {row['chunk']}: forward {row['forward_ms']:.1f} ms, f+g "
              f"{row['grad_ms']:.1f} ms, ratio {row['ratio']:.3f}", flush=True)
    return out


if __name__ == "__main__":
    main()
