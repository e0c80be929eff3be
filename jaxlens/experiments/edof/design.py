"""Design of the EDoF experiment's classical base lens with the curriculum (``jaxlens.design``).

``python -m jaxlens.experiments.edof.design`` designs the lens from random, nearly flat
starts with ``jaxlens.design.multistart.design`` and writes it as JSON (default: the shipped
``jaxlens/data/lenses/edof_classical.json``), with a record of its paraxial data and RMS
spot maps (``experiments/edof/base_lens.json``) and a figure of them
(``experiments/edof/base_lens_spots.png``).

The spec is the paper's EDoF lens (Yang, Fu & Heidrich, Nat. Commun. 2024): paraxial EFL
5.55 mm, entrance pupil 2.60 mm (EFL/EPD = 2.13, the paper's F/2.1), a 68.8° diagonal field
on the 7.20 mm diagonal of a 1024² sensor of 4.97 µm pixels, focused at 20 cm, plastic
aspheres. As 5.55 mm · tan(34.4°) = 3.80 mm exceeds the 3.60 mm half diagonal, the lens
has about −5 % barrel distortion at the corner.

How the curriculum is told so (``classical_spec``): the spec's ``efl`` (5.55 mm) adds a
paraxial-EFL residual to the design loss, and the nominal focal length of the curriculum's
convention, f = half diagonal / tan(34.4°), sets the EPD (F# = f / 2.60) and the height
that the full-field centroid is pinned to. The curriculum stages use the centroid spot
reference with that pin (``DesignConfig(reference="centroid")``): the distortion-free
reference f·tanθ would fight the EFL target. The design is for an object at infinity;
refocusing to 20 cm moves the sensor back by about f²/200 mm ≈ 0.15 mm, which moves the
corner chief ray outward, so the design's sensor diagonal is ``DESIGN_DIAGONAL`` (7.02 mm)
and the 34.4° chief ray lands just inside the 3.60 mm corner at 20 cm.

The finished lens gets the experiment's system data (EPD 2.60 mm, RGB wavelengths, fields,
object at 20 cm, the 1024² sensor) and is refocused for an object 20 cm in front of the
stop: the sensor distance minimising the mean polychromatic RMS spot over the field.
"""

from __future__ import annotations

import argparse
import math
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...imaging.sampling import grid_axis
from ...optics import checks
from ...optics.lens import Lens, Sensor
from .lenses import FOCUS_DEPTH, SPEC, WAVELENGTHS_RGB

MATERIALS = {
    4: ("E48R", "OKP4HT", "E48R", "E48R"),
    5: ("E48R", "OKP4HT", "E48R", "OKP4HT", "E48R"),
    6: ("E48R", "OKP4HT", "E48R", "OKP4HT", "E48R", "E48R"),
}
"""Default materials per element count: the crown-like E48R (Zeonex, nd 1.531, Vd 56) for
the positive elements, the flint-like OKP4HT (nd 1.632, Vd 23) for the colour correctors."""

DESIGN_DIAGONAL = 7.02
"""Sensor diagonal (mm) of the design at infinity; 20 cm focus fills the 7.20 mm sensor."""

TOTAL_TRACK = 7.6
"""Stop to sensor (mm) of the design at infinity."""

RECORD_DEPTHS = (100.0, 200.0, 1e4)
"""Object depths (mm from the stop) of the recorded RMS spot maps: 10 cm, 20 cm, 10 m."""


def nominal_focal_length(diagonal: float = SPEC["image_height_mm"]) -> float:
    """f = (diagonal / 2) / tan(half FoV) (mm): the curriculum's focal length convention."""
    return 0.5 * diagonal / math.tan(math.radians(0.5 * SPEC["fov_deg"]))


def classical_spec(
    *,
    n_elements: int = 5,
    materials=None,
    total_track: float = TOTAL_TRACK,
    bfl: float = 0.8,
    diagonal: float = DESIGN_DIAGONAL,
):
    """The ``DesignSpec`` of the classical lens (see the module docstring).

    Args:
        n_elements: plastic elements (4, 5 or 6 have default ``MATERIALS``).
        materials: one catalog name per element (default ``MATERIALS[n_elements]``).
        total_track: stop to sensor, mm.
        bfl: smallest clearance from the last surface to the sensor, mm.
        diagonal: the design's sensor diagonal, mm (the field is always 68.8°).
    """
    from ...design.spec import DesignSpec

    if materials is None:
        if n_elements not in MATERIALS:
            raise ValueError(f"classical_spec: no default materials for n_elements="
                             f"{n_elements}; pass materials (one name per element) or use "
                             f"{sorted(MATERIALS)}")
        materials = MATERIALS[n_elements]
    f = nominal_focal_length(diagonal)
    return DesignSpec(
        fov=SPEC["fov_deg"],
        fnum=f / SPEC["epd_mm"],
        sensor_diagonal=diagonal,
        n_elements=n_elements,
        materials=tuple(materials),
        total_track=total_track,
        bfl=bfl,
        stop=0,
        fov_start=40.0,
        fnum_start=2.8,
        name="edof_classical",
        efl=SPEC["efl_mm"],
    )


def design_config(scale: float = 1.0, *, smoke: bool = False):
    """The recipe: ``DesignConfig`` with the centroid reference, step counts × ``scale``.

    ``smoke``: a tiny recipe (3 fields, 2 rings, 2 curriculum stages of 4 steps, no
    polish) that only checks the machinery runs.
    """
    from ...design.multistart import DesignConfig

    if smoke:
        return DesignConfig(n_fields=3, rings=2, curriculum_n=1, steps=4, final_steps=4,
                            polish_steps=0, reference="centroid", epoch=4, log_every=4)
    return DesignConfig(reference="centroid").scaled(scale)


# Field lists of ``_mean_rms`` are padded to a multiple of this (the radial profile's 9
# angles), so the refocus (7 fields), the seeds' 20 cm scores and the record's radial profile
# and focus check share one compiled ``rms_spot`` instead of one program per length.
FIELD_BLOCK = 9


def _mean_rms(lens: Lens, depth_mm: float, fields) -> float:
    """RMS over ``fields`` (deg, [F] or [F, 2]) of the RGB polychromatic RMS spot radius (mm) at
    ``depth_mm``. Fields are independent in ``rms_spot``, so the padding (copies of the last
    field) changes no value of the first F."""
    from ...analysis.spots import rms_spot

    f = np.atleast_1d(np.asarray(fields, np.float64))  # [F] (θy) or [F, 2] (θx, θy)
    pad = -len(f) % FIELD_BLOCK
    padded = np.concatenate([f, np.repeat(f[-1:], pad, axis=0)]) if len(f) else f
    r = rms_spot(lens, jnp.asarray(padded), jnp.asarray(WAVELENGTHS_RGB), depth=depth_mm)
    return float(jnp.sqrt(jnp.mean(r.polychromatic[: len(f)] ** 2)))


def with_back_gap(lens: Lens, dt: float) -> Lens:
    """The lens with its sensor moved ``dt`` mm along +z (the last gap grows by ``dt``)."""
    return eqx.tree_at(lambda m: m.thickness, lens, lens.thickness.at[-1].add(dt))


def refocus(
    lens: Lens, depth_mm: float = FOCUS_DEPTH, *, span: float = 0.3, n: int = 61, fields=None
) -> tuple[Lens, float]:
    """Move the sensor to the best focus for an object ``depth_mm`` in front of surface 1.

    A grid search over the last gap (±``span`` mm, ``n`` points), then a parabola through the
    best three, minimising the RMS over ``fields`` (default 0 … full field) of the
    polychromatic RMS spot radius. Returns the lens and that RMS (mm).
    """
    fields = np.linspace(0.0, 0.5 * SPEC["fov_deg"], 7) if fields is None else fields
    shifts = np.linspace(-span, span, n)
    vals = np.array([_mean_rms(with_back_gap(lens, dt), depth_mm, fields) for dt in shifts])
    i = int(np.clip(np.nanargmin(vals), 1, n - 2))
    y0, y1, y2 = vals[i - 1 : i + 2]
    h = shifts[1] - shifts[0]
    den = y0 - 2 * y1 + y2
    best = shifts[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0)
    out = with_back_gap(lens, best)
    return out, _mean_rms(out, depth_mm, fields)


def finish(lens: Lens, name: str = "edof_classical", *, refocus_points: int = 61) -> Lens:
    """Give a designed lens the experiment's system data (EPD, fields, RGB wavelengths,
    object at 20 cm, the 1024² sensor of 4.97 µm pixels) and refocus it at 20 cm."""
    lens = lens.astype(jnp.float64)
    n = SPEC["sensor_pixels"]
    out = Lens(
        surfaces=lens.surfaces,
        thickness=lens.thickness,
        materials=lens.materials,
        stop=lens.stop,
        epd=SPEC["epd_mm"],
        fields=jnp.asarray([0.0, 12.0, 24.0, 0.5 * SPEC["fov_deg"]]),
        wavelengths=jnp.asarray(sorted(WAVELENGTHS_RGB)),
        primary=1,
        object_distance=FOCUS_DEPTH,
        image=lens.image,
        sensor=Sensor(tuple(n), jnp.asarray(SPEC["pixel_size_mm"])),
        name=name,
    )
    return refocus(out, n=refocus_points)[0]


def corner_heights(lens: Lens) -> dict:
    """Real chief-ray height (mm) of the 34.4° field on the sensor, object at infinity and
    at 20 cm, with the EFL·tanθ height and the distortion (%) at infinity."""
    from ...analysis.spots import chief_ray
    from ...optics import paraxial

    half = 0.5 * SPEC["fov_deg"]
    inf = eqx.tree_at(lambda m: m.object_distance, lens, None, is_leaf=lambda x: x is None)
    h_inf = float(chief_ray(inf, half).origin[1])
    h_20 = float(chief_ray(lens, half, depth=FOCUS_DEPTH).origin[1])
    ftan = float(paraxial.efl(lens)) * math.tan(math.radians(half))
    return {"field_deg": half, "chief_height_infinity_mm": h_inf,
            "chief_height_20cm_mm": h_20, "efl_tan_theta_mm": ftan,
            "distortion_infinity_percent": 100.0 * (h_inf - ftan) / ftan}


def meets_spec(lens: Lens, *, efl_rtol: float = 0.01) -> bool:
    """The spec checks of ``tests/test_edof_base_lens.py``: paraxial EFL within ``efl_rtol``
    of 5.55 mm and the 34.4° chief ray between 3.40 and 3.60 mm (infinity and 20 cm)."""
    from ...optics import paraxial

    c = corner_heights(lens)
    ok_h = all(3.40 <= c[k] <= 3.60 for k in ("chief_height_infinity_mm", "chief_height_20cm_mm"))
    return abs(float(paraxial.efl(lens)) / SPEC["efl_mm"] - 1.0) <= efl_rtol and ok_h


def design_classical(*, seeds=(0, 1, 2), scale: float = 1.0, progress: bool = True,
                     spec=None, config=None, refocus_points: int = 61):
    """Design the classical lens with the curriculum; returns ``(lens, info)``.

    Args:
        seeds: random starts designed together; the kept one is valid, meets the spec
            (``meets_spec``) if any does, and has the smallest mean RMS at 20 cm.
        scale: multiplies every step count of the recipe (``design_config``).
        progress: show progress bars.
        spec: the ``DesignSpec`` (default ``classical_spec()``).
        config: the ``DesignConfig`` (default ``design_config(scale)``).
        refocus_points: sensor positions of the refocus grid search.

    Returns:
        The finished lens (refocused at 20 cm) and a dict with the chosen seed, every
        seed's scores and the curriculum's evaluation at infinity.
    """
    import dataclasses

    from ...design import evaluate, multistart

    spec = classical_spec() if spec is None else spec
    config = design_config(scale) if config is None else config
    # Every seed runs the curriculum and fine-tuning; only the best one gets the (costly)
    # Levenberg–Marquardt polish.
    res = multistart.design(spec, list(seeds), dataclasses.replace(config, polish_steps=0),
                            progress=progress, shard=False, on_nonfinite="drop")
    alive = [i for i, s in enumerate(res.seeds) if s not in res.history.failed]
    if not alive:
        raise FloatingPointError("design_classical: every seed failed: "
                                 + "; ".join(res.history.failed.values()))
    evals = {i: evaluate.evaluate(res.lens(i), spec) for i in alive}
    order = sorted(alive, key=lambda i: (not evals[i].valid, evals[i].rms_mean_um))
    polished = polish(res, order[0], config, progress=progress) if config.polish_steps else None
    fields = np.linspace(0.0, 0.5 * SPEC["fov_deg"], 7)
    rows = []
    for i in order:
        seed = res.seeds[i]
        designed = res.lens(i) if polished is None or i != order[0] else polished
        ev = evaluate.evaluate(designed, spec)
        lens = finish(designed, refocus_points=refocus_points)
        rms20 = _mean_rms(lens, FOCUS_DEPTH, fields)
        rows.append({"seed": seed, "lens": lens, "valid": ev.valid, "meets_spec": meets_spec(lens),
                     "polished": designed is polished, "rms_20cm_um": 1e3 * rms20,
                     "evaluation_at_infinity": ev.summary()})
    best = min(rows, key=lambda r: (not r["valid"], not r["meets_spec"], r["rms_20cm_um"]))
    info = {
        "seed": best["seed"],
        "valid": best["valid"],
        "meets_spec": best["meets_spec"],
        "evaluation_at_infinity": best["evaluation_at_infinity"],
        "seeds": [{k: v for k, v in r.items() if k not in ("lens", "evaluation_at_infinity")}
                  | {"efl": r["evaluation_at_infinity"]["efl"],
                     "rms_mean_infinity_um": r["evaluation_at_infinity"]["rms_mean_um"]}
                  for r in rows],
        "failed_seeds": {str(k): v for k, v in res.history.failed.items()},
        "spec": {
            "fov": spec.fov, "fnum_nominal": spec.fnum, "efl_target": spec.efl,
            "design_sensor_diagonal": spec.sensor_diagonal,
            "nominal_focal_length": spec.focal_length, "epd": spec.epd,
            "n_elements": spec.n_elements, "materials": list(spec.materials),
            "total_track": spec.total_track, "bfl": spec.bfl,
        },
        "recipe": {"scale": scale, "reference": config.reference, "steps": config.steps,
                   "final_steps": config.final_steps, "polish_steps": config.polish_steps,
                   "efl_weight": config.efl_weight, "float64": config.float64},
        "design_seconds": float(sum(res.history.seconds)),
    }
    return best["lens"], info


def polish(res, i: int, config, *, progress: bool = True) -> Lens:
    """Polish design ``i`` of a ``multistart.DesignResult`` with ``config.polish_steps`` steps
    of the ``config.polish`` solver at the full spec (centroid reference, image-height pin,
    mask), the multistart's last stage run on that one design."""
    from ...design import curriculum, init, losses, multistart

    spec = res.spec
    params = jax.tree.map(lambda x: jnp.asarray(np.asarray(x)[i : i + 1]), res.params)
    dtype = params.c.dtype
    sampling = losses.RayLoss.make(config.n_fields, config.rings, spec.wavelengths,
                                   spec.sensor_size, dtype)
    objective = losses.Objective(res.pmap, sampling, jnp.asarray(init.gap_bounds(spec), dtype),
                                 efl=spec.efl, efl_weight=config.efl_weight)
    stage = curriculum.Stage(f"polish ({config.polish})", spec.fov, spec.fnum,
                             config.polish_steps, config.polish, beta=1.0, pin=config.pin,
                             mask=config.mask, regularize=config.regularize)
    make = multistart.make_solver_factory(config, spec, dtype)
    params, _ = curriculum.run(spec, [stage], params, objective, make,
                               reg_weights=config.reg_weights, epoch=config.epoch,
                               irls=config.irls, log_every=config.log_every, progress=progress,
                               seeds=[res.seeds[i]])
    return res.pmap.to_lens(jax.tree.map(lambda x: x[0], params)).astype(jnp.float64)


def spot_record(lens: Lens, *, n: int = 16, depths=RECORD_DEPTHS) -> dict:
    """Paraxial data and polychromatic (RGB) RMS spot maps of the finished lens.

    The maps are on an ``n × n`` grid over the 7.20 mm-diagonal sensor, each point the
    field tanθ = (x, y) / f with f = 3.60 / tan(34.4°) (so the corners are the 34.4° field;
    the barrel distortion moves the real image points slightly inward); the radial profile
    is at 9 field angles 0 … 34.4°. Spots are about each field's centroid, 317 rays per
    wavelength, with the sensor where the lens file puts it (best focus at 20 cm).
    """
    from ...analysis.spots import rms_spot
    from ...optics import paraxial

    pd = paraxial.paraxial_data(lens)
    f = nominal_focal_length()
    side = SPEC["sensor_pixels"][0] * SPEC["pixel_size_mm"]
    xs = grid_axis(n) * side / 2
    x, y = np.meshgrid(xs, xs)
    angles = np.degrees(np.arctan(np.stack([x.ravel(), y.ravel()], -1) / f))
    radial = np.linspace(0.0, 0.5 * SPEC["fov_deg"], 9)
    wl = jnp.asarray(WAVELENGTHS_RGB)
    maps, prof = {}, {}
    for d in depths:
        key = f"{d / 1e3:g}"
        r = rms_spot(lens, jnp.asarray(angles), wl, depth=d)
        maps[key] = (1e3 * np.asarray(r.polychromatic)).reshape(n, n)
        rp = rms_spot(lens, jnp.asarray(radial), wl, depth=d)
        prof[key] = {"rms_um": (1e3 * np.asarray(rp.polychromatic)).tolist(),
                     "min_valid_fraction": float(jnp.min(rp.valid_fraction))}
    # Focus check: mean RMS at 20 cm against sensor shifts (the minimum should be at 0).
    shifts = np.linspace(-0.05, 0.05, 11)
    focus = [1e3 * _mean_rms(with_back_gap(lens, dt), FOCUS_DEPTH, radial) for dt in shifts]
    return {
        "paraxial": {
            "efl_mm": float(pd.efl), "fnum": float(pd.fnum), "epd_mm": float(lens.epd),
            "bfl_mm": float(pd.bfl), "back_gap_mm": float(lens.thickness[-1]),
            "total_track_mm": float(jnp.sum(lens.thickness)),
            "entrance_pupil_z_mm": float(pd.entrance_pupil_z),
            "exit_pupil_z_mm": float(pd.exit_pupil_z),
            "wavelength_um": float(lens.primary_wavelength),
        },
        "corner": corner_heights(lens),
        "elements": (lens.num_surfaces - 1) // 2,
        "materials": [m.name for m in lens.materials[1:-1:2]],
        "sensor": {"pixels": list(SPEC["sensor_pixels"]), "pixel_size_mm": SPEC["pixel_size_mm"],
                   "diagonal_mm": math.hypot(side, side)},
        "rms_map": {"grid": n, "depths_m": [f"{d / 1e3:g}" for d in depths],
                    "wavelengths_um": list(WAVELENGTHS_RGB),
                    "mean_um": {k: float(v.mean()) for k, v in maps.items()},
                    "max_um": {k: float(v.max()) for k, v in maps.items()},
                    "values_um": {k: np.round(v, 3).tolist() for k, v in maps.items()}},
        "rms_radial": {"field_deg": radial.tolist(), "by_depth_m": prof},
        "focus_check_20cm": {"sensor_shift_mm": shifts.tolist(), "mean_rms_um": focus},
    }


def plot_spot_record(rec: dict):
    """Figure: the RMS spot maps at each recorded depth and the radial profiles."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    maps = rec["rms_map"]
    keys = maps["depths_m"]
    vals = [np.asarray(maps["values_um"][k]) for k in keys]
    vmax = max(float(np.nanmax(v)) for v in vals)
    half = 0.5 * rec["sensor"]["diagonal_mm"] / math.sqrt(2)
    fig = Figure(figsize=(4.2 * (len(keys) + 1), 3.8), dpi=110)
    FigureCanvasAgg(fig)
    for i, (k, v) in enumerate(zip(keys, vals, strict=True)):
        ax = fig.add_subplot(1, len(keys) + 1, i + 1)
        im = ax.imshow(v, origin="lower", extent=(-half, half, -half, half), cmap="viridis",
                       vmin=0, vmax=vmax, interpolation="nearest")
        ax.set_title(f"object at {k} m: mean {v.mean():.1f} µm, max {v.max():.1f} µm",
                     fontsize=8)
        ax.set_xlabel("x on sensor (mm)")
        if i == 0:
            ax.set_ylabel("y on sensor (mm)")
    fig.colorbar(im, ax=fig.axes, label="RMS spot radius (µm)", shrink=0.8)
    ax = fig.add_subplot(1, len(keys) + 1, len(keys) + 1)
    rad = rec["rms_radial"]
    for k in keys:
        ax.plot(rad["field_deg"], rad["by_depth_m"][k]["rms_um"], "o-", ms=3, label=f"{k} m")
    ax.axhline(rec["sensor"]["pixel_size_mm"] * 1e3, color="k", lw=0.8, ls="--",
               label="pixel 4.97 µm")
    ax.set_yscale("log")
    ax.set_xlabel("field (deg)")
    ax.set_ylabel("RMS spot radius (µm)")
    p = rec["paraxial"]
    ax.set_title(f"EFL {p['efl_mm']:.3f} mm, F/{p['fnum']:.3f}, "
                 f"{rec['elements']} elements", fontsize=8)
    ax.legend(fontsize=7)
    return fig


def _check_cli(p, a) -> list[int]:
    """Refuse (``p.error``: exit 2, one line) a bad option of ``main`` before the design;
    returns the seeds."""
    from ...optics import checks
    from ..runfolder import UsageError, check_writable

    record_files = ("base_lens.json", "base_lens_spots.png", "base_lens_command.txt")
    w = "edof.design"
    try:
        if os.path.isdir(a.out):
            raise ValueError(f"--out {a.out} is a folder; give the lens file's path (.json or "
                             f".zmx)")
        if os.path.splitext(a.out)[1].lower() not in (".json", ".zmx"):
            raise ValueError(f"--out {a.out} must end in .json or .zmx (the lens file's format)")
        if not os.path.isdir(os.path.dirname(os.path.abspath(a.out))):
            raise ValueError(f"--out {a.out}: the folder "
                             f"{os.path.dirname(os.path.abspath(a.out))} does not exist")
        if os.path.exists(a.record_dir) and not os.path.isdir(a.record_dir):
            raise ValueError(f"--record-dir {a.record_dir} is a file, not a folder")
        check_writable(os.path.join(a.record_dir, "x"), "--record-dir")
        clash = [n for n in record_files
                 if os.path.realpath(a.out) == os.path.realpath(os.path.join(a.record_dir, n))]
        if clash:  # the record was written over the lens just saved there
            raise ValueError(f"--out {a.out} is the record's {clash[0]} in --record-dir "
                             f"{a.record_dir}, which the record writes over; choose another "
                             f"--out or --record-dir")
        there = [x for x in (a.out, *(os.path.join(a.record_dir, n) for n in record_files))
                 if os.path.exists(x)]
        if there and not a.overwrite:
            raise ValueError(f"{', '.join(there)} already exist(s); give --overwrite to replace "
                             f"them, or choose --out and --record-dir")
        parts = [s.strip() for s in a.seeds.split(",")]
        if not all(s.isdigit() for s in parts) or len(set(map(int, parts))) < len(parts):
            raise ValueError(f"--seeds must be distinct comma-separated whole numbers >= 0, "
                             f"got {a.seeds!r}")
        from ...design.init import MAX_SEED  # the design package, imported where used

        if max(map(int, parts)) > MAX_SEED:  # design() refused it after the CLI's checks
            raise ValueError(f"--seeds must be whole numbers in [0, {MAX_SEED}] (seeds of "
                             f"JAX's PRNG), got {a.seeds!r}")
        checks.number(a.elements, "--elements", w, lo=4, hi=6, integer=True,
                      unit="elements (the default materials)")
        checks.number(a.total_track, "--total-track", w, lo=0, lo_open=True, unit="mm")
        checks.number(a.scale, "--scale", w, lo=0, hi=1000, lo_open=True,
                      unit="(step-count multiplier)")
        if a.polish_steps is not None:
            checks.number(a.polish_steps, "--polish-steps", w, lo=0, integer=True, unit="steps")
    except (ValueError, UsageError) as e:
        p.error(" ".join(str(e).split()))
    return [int(s) for s in parts]



def main(argv=None) -> None:
    """Command line: design the classical lens, save it and record it."""
    import dataclasses
    import json
    import shlex
    import sys

    from ... import plot, save
    from ..runfolder import OneLineParser

    here = os.path.join(
        os.path.dirname(os.path.dirname(os.path.dirname(__file__))), "data", "lenses",
        "edof_classical.json",
    )
    p = OneLineParser(
        prog="python -m jaxlens.experiments.edof.design",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default=here, help="output lens JSON (default: the shipped lens)")
    p.add_argument("--record-dir", default=os.path.join("experiments", "edof"),
                   help="folder of base_lens.json, base_lens_spots.png, base_lens_command.txt")
    p.add_argument("--seeds", default="0,1,2", help="comma-separated seeds (default 0,1,2)")
    p.add_argument("--elements", type=checks.cli_int,
                   default=5, help="plastic elements (default 5)")
    p.add_argument("--total-track", type=checks.cli_float, default=TOTAL_TRACK,
                   help=f"stop to sensor at infinity, mm (default {TOTAL_TRACK})")
    p.add_argument("--scale", type=checks.cli_float, default=1.0, help="step-count multiplier")
    p.add_argument("--polish-steps", type=checks.cli_int, default=None,
                   help="Levenberg–Marquardt steps on the best seed (default: the recipe's "
                        "80 × scale)")
    p.add_argument("--smoke", action="store_true",
                   help="a tiny recipe and a coarse refocus (checks the command runs)")
    p.add_argument("--quiet", action="store_true")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing --out lens and record in --record-dir (default: "
                        "refuse; the default --out is the lens jaxlens ships)")
    a = p.parse_args(argv)
    # Refused before the design (minutes): the defaults are the shipped lens and its record.
    seeds = _check_cli(p, a)
    try:
        spec = classical_spec(n_elements=a.elements, total_track=a.total_track)
    except ValueError as e:  # in the options' words: "total_track 7000 mm" named no option
        text = " ".join(str(e).split()).replace("DesignSpec: ", "")
        p.error(text.replace("total_track", "--total-track").replace("n_elements", "--elements"))
    config = design_config(a.scale, smoke=a.smoke)
    if a.polish_steps is not None:
        config = dataclasses.replace(config, polish_steps=a.polish_steps)
    lens, info = design_classical(
        seeds=seeds, scale=a.scale, progress=not a.quiet, spec=spec, config=config,
        refocus_points=7 if a.smoke else 61)
    save(lens, a.out)
    rec = spot_record(lens, n=4 if a.smoke else 16)
    record = {"lens_file": os.path.basename(a.out), "design": info} | rec
    os.makedirs(a.record_dir, exist_ok=True)
    with open(os.path.join(a.record_dir, "base_lens.json"), "w") as f:
        json.dump(record, f, indent=1, default=float)
    plot.save(plot_spot_record(rec), os.path.join(a.record_dir, "base_lens_spots.png"))
    cmd = "python -m jaxlens.experiments.edof.design " + " ".join(
        shlex.quote(x) for x in (sys.argv[1:] if argv is None else argv))
    with open(os.path.join(a.record_dir, "base_lens_command.txt"), "w") as f:
        f.write(cmd.strip() + "\n")
    summary = {k: record[k] for k in ("paraxial", "corner", "elements", "materials")}
    summary["rms_mean_um"] = rec["rms_map"]["mean_um"]
    summary["seed"] = info["seed"]
    summary["meets_spec"] = info["meets_spec"]
    print(json.dumps(summary, indent=1, default=float))


if __name__ == "__main__":
    jax.config.update("jax_enable_x64", True)
    main()
