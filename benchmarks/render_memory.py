"""Peak memory of a render gradient, with and without ``jax.checkpoint``.

Measures the peak resident memory (RSS) of one gradient of an MSE image loss through
``jaxlens.imaging.render`` (method "ray", RGB, float32) with respect to the surfaces and gaps
of the 6-element plastic asphere cellphone lens (``jaxlens.zoo.cellphone6``, 1024 × 1024
sensor; another zoo lens with ``--lens``), each configuration in a fresh Python process so that
one run's memory does not count against another. The parent process samples each worker's RSS
from /proc every 0.1 s and stops a worker that passes ``--cap-gib`` (default 8 GiB, a third of
this shared machine), so the run without checkpointing, which needs far more than the machine
has at 1024², is reported as "exceeded the cap" rather than taking the machine down; it is also
measured at smaller sizes to show how it grows.

It also measures, in a worker of its own, the bare trace's forward+gradient rate on the same
lens (``benchmarks.throughput.forward_grad``: 1e6 rays, float32, best of 3), and reports the
checkpointed render gradient's ray·surfaces/s as a ratio of it (issue 15's target: ≥ 0.4).

Run (about 6 minutes on 2 cores)::

    python -m benchmarks.render_memory            # writes benchmarks/results/render_memory.json
    python -m benchmarks.render_memory --worker --size 256 --spp 16 --checkpoint 0   # one run
    python -m benchmarks.render_memory --worker --trace-rays 1000000   # the trace reference
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def worker(size: int, spp: int, checkpoint: bool, patch: int,
           lens_name: str = "cellphone6") -> dict:
    """One gradient in this process; returns timings and ru_maxrss."""
    import resource

    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import jaxlens
    from jaxlens import images

    lens = jaxlens.zoo.ZOO[lens_name]()
    side = float(lens.sensor.pixel_size) * lens.sensor.resolution[1]
    sensor = jaxlens.Sensor((size, size), side / size)
    scene = jnp.asarray(images.scene("astronaut", (size, size)))  # float32, linear
    key = jax.random.PRNGKey(0)
    params, static = eqx.partition(lens, eqx.is_array)
    # Differentiate with respect to the surfaces and the gaps.
    is_param = jax.tree_util.tree_map(lambda _: False, params)
    is_param = eqx.tree_at(
        lambda p: (p.surfaces, p.thickness),
        is_param,
        replace=(jax.tree_util.tree_map(lambda _: True, params.surfaces), True),
    )
    diff, rest = eqx.partition(params, is_param)
    fp = jaxlens.imaging.render.footprints(lens, sensor=sensor, dtype=jnp.float32)

    @jax.jit
    def loss_grad(diff):
        def loss(diff):
            l_ = eqx.combine(diff, rest, static)
            img = jaxlens.render(
                l_,
                scene,
                spp=spp,
                key=key,
                sensor=sensor,
                patch=patch,
                checkpoint=checkpoint,
                method=jaxlens.imaging.render.RayRender(footprints=fp),
            )
            return jnp.mean((img - scene) ** 2)

        return jax.value_and_grad(loss)(diff)

    t0 = time.perf_counter()
    lowered = loss_grad.lower(diff)
    compiled = lowered.compile()
    t1 = time.perf_counter()
    val, grad = compiled(diff)
    jax.block_until_ready(grad)
    t2 = time.perf_counter()
    finite = bool(all(jnp.all(jnp.isfinite(g)) for g in jax.tree_util.tree_leaves(grad)))
    return {
        "lens": lens_name,
        "size": size,
        "spp": spp,
        "checkpoint": checkpoint,
        "patch": patch,
        "rays": size * size * spp * 3,
        "loss": float(val),
        "gradient_finite": finite,
        # Not rounded: a tiny render on a fast machine runs in milliseconds, and the rates
        # below divide by this time.
        "compile_s": t1 - t0,
        "run_s": t2 - t1,
        "ru_maxrss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        # On a GPU the arrays live in device memory, which RSS does not see.
        "device_peak_bytes": (jax.devices()[0].memory_stats() or {}).get("peak_bytes_in_use"),
        "device": jax.devices()[0].device_kind,
    }


def trace_worker(n: int, lens_name: str = "cellphone6") -> dict:
    """The bare trace's value_and_grad rate on the same lens (``throughput.forward_grad``)."""
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)  # as in the throughput benchmark: float64 setup
    import jaxlens

    from . import common, throughput

    lens = jaxlens.zoo.ZOO[lens_name]()
    rays = throughput.make_rays(lens, n, jnp.float32)
    t = common.time_jitted(throughput.forward_grad, lens, rays, repeats=3, min_total_s=0.2)
    ns = lens.num_surfaces
    return {"lens": lens_name, "trace_rays": n, "surfaces": ns, "run_s": t["run_s"],
            "rate": n * ns / t["run_s"], "timing": t}


def _rss(pid: int) -> int:
    try:
        for line in pathlib.Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def run_isolated(size: int, spp: int, checkpoint: bool, patch: int, cap: int,
                 trace_rays: int = 0, lens: str = "cellphone6") -> dict:
    """Run ``worker`` (or ``trace_worker`` if ``trace_rays``) in a fresh process, sampling its
    RSS; stop it above ``cap`` bytes."""
    cmd = [
        sys.executable,
        "-m",
        "benchmarks.render_memory",
        "--worker",
        "--size",
        str(size),
        "--spp",
        str(spp),
        "--checkpoint",
        str(int(checkpoint)),
        "--patch",
        str(patch),
        "--lens",
        lens,
    ] + (["--trace-rays", str(trace_rays)] if trace_rays else [])
    env = dict(os.environ, XLA_FLAGS=os.environ.get("XLA_FLAGS", ""))
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    peak, killed = 0, False
    while proc.poll() is None:
        peak = max(peak, _rss(proc.pid))
        if peak > cap:
            proc.kill()
            killed = True
            break
        time.sleep(0.1)
    out, err = proc.communicate()
    res = {
        "command": " ".join(cmd[1:]),
        "wall_s": round(time.perf_counter() - t0, 1),
        "sampled_peak_rss_bytes": peak,
    }
    # A run that did not report back still records what it was asked to do.
    asked = (dict(trace_rays=trace_rays) if trace_rays else
             dict(size=size, spp=spp, checkpoint=checkpoint, patch=patch,
                  rays=size * size * spp * 3))
    if killed:
        res.update(asked, exceeded_cap=True, cap_bytes=cap)
        return res
    if proc.returncode != 0:
        res.update(
            asked,
            failed=True,
            returncode=proc.returncode,
            stderr_tail=err[-600:],
        )
        m = re.search(r"Out of memory allocating (\d+) bytes", err)
        if m:  # XLA asked for one buffer larger than the machine: record its size
            res["failed_allocation_bytes"] = int(m.group(1))
        return res
    res.update(json.loads(out.strip().splitlines()[-1]))
    res["peak_rss_bytes"] = max(res.get("ru_maxrss_bytes", 0), peak)
    return res


# The worker's RSS cap (GiB): a Python process with JAX loaded already holds about 0.3 GiB.
MIN_CAP_GIB, MAX_CAP_GIB = 0.5, 4096.0


def _outcome(run: dict, cap_gib: float) -> str:
    if "peak_rss_bytes" in run:
        return "completed"
    if run.get("exceeded_cap"):
        return f"stopped when its RSS passed the {cap_gib:g} GiB cap"
    if run.get("failed_allocation_bytes"):
        return (
            f"out of memory: XLA could not allocate one buffer of "
            f"{run['failed_allocation_bytes'] / 1e9:.1f} GB"
        )
    return "failed"


def residual_note(runs: list[dict], size: int, spp: int) -> str:
    """What the gradient without checkpointing stores per ray, from the runs that finished."""
    done = sorted((r["rays"], r["peak_rss_bytes"]) for r in runs
                  if not r.get("checkpoint") and "peak_rss_bytes" in r and "rays" in r)
    note = "peak RSS includes XLA compilation and the Python process (about 1 GB)"
    if len(done) < 2 or done[-1][0] == done[0][0]:
        return note
    (n0, b0), (n1, b1) = done[0], done[-1]
    per_ray = (b1 - b0) / (n1 - n0)
    rays = size * size * spp * 3
    return (f"{note}; without checkpointing the gradient stores every ray's residuals, about "
            f"{per_ray:.0f} bytes per ray (slope between the plain runs of {n0} and {n1} rays), "
            f"so {size}² x {spp} spp x 3 colours ({rays / 1e6:.0f} M rays) would need about "
            f"{per_ray * rays / 1e9:.0f} GB")


def main(argv=None) -> None:
    from jaxlens.experiments.runfolder import OneLineParser
    from jaxlens.optics import checks

    from .common import out_path, whole
    from .throughput import MAX_RAYS

    # Bounded above as render and the trace bound them (before: --size 10**6 and --spp 10**9
    # failed in the worker after it had started, --trace-rays 10**12 aborted in XLA), and
    # --checkpoint is 0 or 1 (5 read as on). 0: the worker ignores the render sizes.
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", action="store_true", help="run one configuration here")
    ap.add_argument("--size", type=whole(0, "pixels", checks.MAX_IMAGE_SIDE), default=1024)
    ap.add_argument("--spp", type=whole(0, "rays per pixel", checks.MAX_SAMPLES), default=16)
    ap.add_argument("--patch", type=whole(0, "pixels", checks.MAX_IMAGE_SIDE), default=64)
    ap.add_argument("--checkpoint", type=whole(0, "(0: off, 1: on)", 1), default=None,
                    help="worker: render with checkpointing (1, the default) or without (0); "
                         "the full run measures both")
    ap.add_argument("--trace-rays", type=whole(0, "rays", MAX_RAYS), default=0,
                    help="worker: time the bare trace's gradient on this many rays instead")
    ap.add_argument("--cap-gib", type=checks.cli_float, default=8.0)
    ap.add_argument("--lens", default="cellphone6", choices=("cooke_triplet", "double_gauss",
                                                             "cellphone6"),
                    help="zoo lens (the smoke test uses the smallest)")
    ap.add_argument("--out", type=out_path(result_of="render_memory"),
                    default=RESULTS / "render_memory.json")
    args = ap.parse_args(argv)
    if args.trace_rays > 0 and not args.worker:  # before: ignored without a word
        ap.error(f"--trace-rays {args.trace_rays} sets what one --worker times (the bare "
                 f"trace); the full run times its own 10**6-ray reference: give --worker, or "
                 f"leave --trace-rays out")
    if args.checkpoint is not None and not args.worker:  # before: ignored without a word
        ap.error(f"--checkpoint {args.checkpoint} sets one --worker's render; the full run "
                 f"measures it with and without checkpointing: give --worker, or leave "
                 f"--checkpoint out")
    if args.worker and args.trace_rays > 0:  # the bare-trace worker ignores the render sizes
        print(json.dumps(trace_worker(args.trace_rays, args.lens)))
        return
    for name, lo in (("size", 1), ("spp", 1), ("patch", 1), ("trace_rays", 0)):
        if getattr(args, name) < lo:
            ap.error(f"--{name.replace('_', '-')} must be a whole number >= {lo}, "
                     f"got {getattr(args, name)}")
    smallest = args.size if args.worker else min(args.size, 128)  # the runs' frame sides
    if args.patch > smallest:  # one patch² tile of rays for a smaller frame
        ap.error(f"--patch {args.patch} must be at most the smallest frame side, {smallest} "
                 f"pixels (--size, and the 256- and 128-pixel runs): a larger tile traces rays for "
                 f"pixels outside the frame")
    if not MIN_CAP_GIB <= args.cap_gib <= MAX_CAP_GIB:  # also NaN and inf
        ap.error(f"--cap-gib must be a positive number of GiB, in {MIN_CAP_GIB:g}–"
                 f"{MAX_CAP_GIB:g} GiB (below, the cap stops any worker at once), got "
                 f"{args.cap_gib}")
    if args.worker:
        print(json.dumps(worker(args.size, args.spp, args.checkpoint != 0, args.patch,
                                args.lens)))
        return
    sys.path.insert(0, str(ROOT))
    from benchmarks.common import machine_info

    cap = int(args.cap_gib * 2**30)
    runs = []
    for size, ckpt in (
        (args.size, True),
        (args.size, False),
        (256, True),
        (256, False),
        (128, True),
        (128, False),
    ):
        r = run_isolated(size, args.spp, ckpt, args.patch, cap, lens=args.lens)
        print(json.dumps(r), flush=True)
        runs.append(r)
    ref = run_isolated(0, 0, False, 0, cap, trace_rays=10**6, lens=args.lens)
    print(json.dumps(ref), flush=True)
    main_ck, main_plain = runs[0], runs[1]
    lens_surfaces = ref.get("surfaces")
    render_rate = (main_ck["rays"] * lens_surfaces / main_ck["run_s"]
                   if "run_s" in main_ck and lens_surfaces else None)
    result = {
        "benchmark": "peak RSS of value_and_grad of an MSE loss on jaxlens.imaging.render "
        f"(method=RayRender(), RGB, float32) through jaxlens.zoo.{args.lens}, w.r.t. "
        "its surfaces and gaps",
        "command": "python -m benchmarks.render_memory"
        + ("" if args.lens == "cellphone6" else f" --lens {args.lens}"),
        "size": args.size,
        "spp": args.spp,
        "patch": args.patch,
        "peak_bytes_checkpoint": main_ck.get("peak_rss_bytes"),
        "peak_bytes_no_checkpoint": main_plain.get("peak_rss_bytes"),
        "no_checkpoint_outcome": _outcome(main_plain, args.cap_gib),
        "no_checkpoint_failed_allocation_bytes": main_plain.get("failed_allocation_bytes"),
        "checkpoint_fits_4GB": bool(main_ck.get("peak_rss_bytes", 1 << 62) < 4 * 10**9),
        "render_gradient_s": main_ck.get("run_s"),
        "render_gradient_rate": render_rate,
        "trace_gradient_rate": ref.get("rate"),
        "render_over_trace_gradient": (render_rate / ref["rate"]
                                       if render_rate and ref.get("rate") else None),
        "rate_note": "ray·surfaces/s of value_and_grad: the render's rays (size² × spp × 3 "
        "colours) × the lens's surfaces / its run time, against the bare trace of 1e6 rays "
        "through the same lens (benchmarks.throughput.forward_grad, float32)",
        "trace_reference": ref,
        "note": residual_note(runs, args.size, args.spp),
        "runs": runs,
        "machine": machine_info(),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    from jaxlens.io.json_values import write_whole

    write_whole(args.out, json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
