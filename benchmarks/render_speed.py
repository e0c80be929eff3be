"""Forward speed of ``jaxlens.imaging.render``: a 512 × 512 RGB image at 16 spp.

The lens is the 6-element plastic asphere cellphone lens (``jaxlens.zoo.cellphone6``:
13 surfaces, 12 even aspheres to A12), the scene ``astronaut`` from skimage.data in linear
float32, the method "ray" (backward tracing with relative illumination). The render is
jitted, called once to compile (reported on its own), then timed ``--repeats`` times with
``block_until_ready``; the best and the median are reported, and rays/s counts
512·512·16·3 rays (three wavelengths) per render. The sampling footprints are computed
once, outside the timing, as an optimisation loop that reuses them would; the time to
compute them is reported too. The machine's load average is recorded (the machine may be
shared).

Run::

    python -m benchmarks.render_speed        # writes benchmarks/results/render_speed.json
"""

from __future__ import annotations

import json
import os
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def main(argv=None) -> None:
    from jaxlens.experiments.runfolder import OneLineParser
    from jaxlens.optics.checks import MAX_IMAGE_SIDE, MAX_SAMPLES

    from .common import MAX_REPEATS, out_path, whole

    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=whole(1, "pixels", MAX_IMAGE_SIDE), default=512)
    ap.add_argument("--spp", type=whole(1, "samples per pixel", MAX_SAMPLES), default=16)
    ap.add_argument("--patch", type=whole(1, "pixels", MAX_IMAGE_SIDE), default=64)
    ap.add_argument("--repeats", type=whole(1, "repeats", MAX_REPEATS), default=3)
    ap.add_argument("--out", type=out_path(result_of="render_speed"),
                    default=RESULTS / "render_speed.json")
    args = ap.parse_args(argv)
    if args.patch > args.size:  # one patch² tile of rays for a size² frame, recorded as --patch
        ap.error(f"--patch {args.patch} must be at most --size {args.size} pixels (a larger "
                 f"tile traces rays for pixels outside the frame)")
    sys.path.insert(0, str(ROOT))
    import jax
    import jax.numpy as jnp

    import jaxlens
    from benchmarks.common import machine_info
    from jaxlens import images

    info = machine_info()
    lens = jaxlens.zoo.cellphone6()
    side = float(lens.sensor.pixel_size) * lens.sensor.resolution[1]
    size, spp = args.size, args.spp
    sensor = jaxlens.Sensor((size, size), side / size)
    scene = jnp.asarray(images.scene("astronaut", (size, size)))
    key = jax.random.PRNGKey(0)

    t0 = time.perf_counter()
    fp = jaxlens.imaging.render.footprints(lens, sensor=sensor, dtype=jnp.float32)
    jax.block_until_ready(fp)
    t_fp_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    jax.block_until_ready(jaxlens.imaging.render.footprints(lens, sensor=sensor, dtype=jnp.float32))
    t_fp = time.perf_counter() - t0

    @jax.jit
    def fwd(scene, key):
        return jaxlens.render(
            lens, scene, spp=spp, key=key, sensor=sensor, patch=args.patch,
            method=jaxlens.imaging.render.RayRender(footprints=fp)
        )

    t0 = time.perf_counter()
    compiled = fwd.lower(scene, key).compile()
    t_compile = time.perf_counter() - t0
    jax.block_until_ready(compiled(scene, key))  # warm-up
    times = []
    for i in range(args.repeats):
        t0 = time.perf_counter()
        img = jax.block_until_ready(compiled(scene, jax.random.fold_in(key, i)))
        times.append(time.perf_counter() - t0)
    rays = size * size * spp * 3
    best, med = min(times), statistics.median(times)
    result = {
        "benchmark": "forward jaxlens.render(method=RayRender()), RGB float32, "
        "jaxlens.zoo.cellphone6 (13 surfaces, 12 even aspheres)",
        "command": "python -m benchmarks.render_speed",
        "size": size,
        "spp": spp,
        "patch": args.patch,
        "rays_per_render": rays,
        "compile_s": round(t_compile, 2),
        "footprints_first_call_s": round(t_fp_first, 2),
        "footprints_s": round(t_fp, 3),
        "run_s_best": round(best, 3),
        "run_s_median": round(med, 3),
        "run_s_all": [round(t, 3) for t in times],
        "rays_per_s_best": round(rays / best),
        "rays_per_s_median": round(rays / med),
        "image_mean": float(jnp.mean(img)),
        "load_average_at_end": os.getloadavg(),
        "machine": info,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    from jaxlens.io.json_values import write_whole

    write_whole(args.out, json.dumps(result, indent=2) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "machine"}, indent=2))


if __name__ == "__main__":
    main()
