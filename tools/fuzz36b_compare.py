"""Compare jaxlens with the random reference cases of tools/fuzz36b_reference.py (round 36b).

Run with jaxlens's venv, from the repository root::

    PYTHONPATH=. python tools/fuzz36b_compare.py FOLDER [--loader helpers|load] [--float32] [NAME]

Each ``fuzz36b_*.json`` in FOLDER is read through the loader the tests use
(``tests/helpers.py::refcase_lens``; ``--loader load`` reads it with ``jaxlens.load``
instead) and compared as ``tests/test_trace.py`` compares the reference cases, in float64:
the real rays' image intercepts (mm) and direction cosines (through ``refcase_rays``,
which refracts the stored directions back into image space where optiland refracted at the
image surface), the paraxial EFL, BFL, entrance pupil and F-number (relative), the paraxial
chief-ray height at the image vertex plane (mm), the RMS spot radii about the centroid and
the chief ray per wavelength and polychromatic (relative), and the distortion (chief-ray
height in mm, both percentages absolute). Prints one line per case and the largest error
of each quantity over all cases; writes ``compare_LOADER.json`` in FOLDER. ``--float32``
measures only the float32 intercepts, as ``test_refcase_intercepts_float32`` does (1e-4 mm).
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import analysis  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from helpers import refcase_lens, refcase_rays  # noqa: E402

BAR = {
    "ray_pos": 1e-9,
    "ray_dir": 1e-12,
    "paraxial_rel": 1e-9,
    "parax_height": 1e-9,
    "rms_rel": 1e-9,
    "dist_height": 1e-9,
    "dist_pct": 1e-9,
}


def compare(path, loader="helpers"):
    if loader == "helpers":
        lens, d = refcase_lens(path)
    else:
        lens, d = jl.load(path), json.loads(pathlib.Path(path).read_text())
    err = {}
    rays, ref = refcase_rays(d)
    out = jl.trace(lens, rays)
    err["valid"] = float(np.mean(~np.asarray(out.valid)))
    err["ray_pos"] = float(np.abs(np.asarray(out.origin) - ref[:, :3]).max())
    err["ray_dir"] = float(np.abs(np.asarray(out.direction) - ref[:, 3:]).max())
    p = jl.paraxial_data(lens)
    r = d["paraxial"]
    err["paraxial_rel"] = max(
        abs(float(p.efl) / r["EFL"] - 1),
        abs(float(p.bfl) / r["BFL"] - 1),
        abs(float(p.fnum) / r["FNO"] - 1),
        abs(float(p.entrance_pupil_z) - r["entrance_pupil_z"])
        / max(1.0, abs(r["entrance_pupil_z"])),
    )
    fields = [f["field_angle_deg"] for f in d["rms_spot"]]
    h = np.asarray(jl.paraxial.image_height(lens, np.array(fields)))
    err["parax_height"] = max(
        abs(float(h[i]) - r["paraxial_chief_ray_y_at_image_vertex"][str(f)])
        for i, f in enumerate(fields)
    )
    wl_keys = list(d["rms_spot"][0]["per_wavelength"])
    dist_fields = [x["field_angle_deg"] for x in d["distortion"]]
    spots, dist = jax.jit(
        lambda L: (
            {k: analysis.rms_spot(L, fields, reference=k) for k in ("centroid", "chief")},
            analysis.distortion(L, dist_fields),
        )
    )(lens)
    e = 0.0
    for kind in ("centroid", "chief"):
        s = spots[kind]
        for i, f in enumerate(d["rms_spot"]):
            for j, k in enumerate(wl_keys):
                want = f["per_wavelength"][k][f"rms_vs_{kind}"]
                e = max(e, abs(float(s.per_wavelength[i, j]) / want - 1))
            want = f["polychromatic_equal_weights"][f"rms_vs_{kind}"]
            e = max(e, abs(float(s.polychromatic[i]) / want - 1))
        err["valid"] = max(err["valid"], float(1 - np.min(np.asarray(s.valid_fraction))))
    err["rms_rel"] = e
    err["dist_height"] = err["dist_pct"] = 0.0
    for i, x in enumerate(d["distortion"]):
        err["dist_height"] = max(
            err["dist_height"], abs(float(dist.chief_height[i]) - x["chief_ray_y_real"])
        )
        err["dist_pct"] = max(
            err["dist_pct"],
            abs(float(dist.percent_ftan[i]) - x["distortion_pct_ftan"]),
            abs(float(dist.percent_paraxial[i]) - x["distortion_pct_vs_paraxial_chief_at_image"]),
        )
    return err, d


def float32_intercepts(path):
    """The largest float32 intercept error (mm) of the reference rays, as
    ``test_trace.test_refcase_intercepts_float32`` measures it (its bar: 1e-4 mm), and the
    fraction of those rays flagged invalid."""
    lens, d = refcase_lens(path)
    rays, ref = refcase_rays(d, jnp.float32)
    out = jl.trace(lens, rays)
    assert out.origin.dtype == jnp.float32
    return {
        "ray_pos_f32": float(np.abs(np.asarray(out.origin, np.float64) - ref[:, :3]).max()),
        "valid_f32": float(np.mean(~np.asarray(out.valid))),
    }


def main(argv):
    ap = argparse.ArgumentParser(prog="fuzz36b_compare.py", description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("names", nargs="*")
    ap.add_argument("--loader", choices=("helpers", "load"), default="helpers")
    ap.add_argument(
        "--float32", action="store_true", help="only the float32 intercepts (bar 1e-4 mm)"
    )
    args = ap.parse_args(argv)
    folder = pathlib.Path(args.folder)
    paths = [folder / f"{n}.json" for n in args.names] or sorted(folder.glob("fuzz36b_*.json"))
    if not paths:
        ap.error(f"no fuzz36b_*.json in {folder}")
    worst, rows = {}, {}
    for path in paths:
        t0 = time.time()
        try:
            if args.float32:
                err, d = float32_intercepts(path), json.loads(path.read_text())
            else:
                err, d = compare(path, args.loader)
        except Exception as exc:  # noqa: BLE001  reported, and the others still run
            print(f"{path.stem}: ERROR {exc!r}"[:300], flush=True)
            rows[path.stem] = {"error": repr(exc)[:300]}
            continue
        rows[path.stem] = err
        bar = {**BAR, "ray_pos_f32": 1e-4}
        bad = [
            k
            for k, v in err.items()
            if (k.startswith("valid") and v > 0) or (k in bar and not v <= bar[k])
        ]
        for k, v in err.items():
            if not math.isnan(v) and v >= worst.get(k, (-1, ""))[0]:
                worst[k] = (v, path.stem)
            if math.isnan(v):
                worst[k] = (math.nan, path.stem)
        print(
            f"{path.stem}: {time.time() - t0:5.1f}s "
            + " ".join(f"{k} {v:.1e}" for k, v in err.items())
            + (f"  OVER {bad} {d['features']}" if bad else ""),
            flush=True,
        )
    print("largest:", " ".join(f"{k} {v[0]:.2e} ({v[1]})" for k, v in worst.items()))
    (folder / f"compare_{'float32' if args.float32 else args.loader}.json").write_text(
        json.dumps({"rows": rows, "worst": worst}, indent=1) + "\n"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
