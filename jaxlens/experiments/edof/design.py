"""Design of the classical starting lens with the curriculum tools (``jaxlens.design``).

``python -m jaxlens.experiments.edof.design`` designs the EDoF experiment's classical lens
from random,
nearly flat starts and writes it as JSON (default: the shipped
``jaxlens/data/lenses/edof_classical.json``). The spec is the paper's EDoF lens in the
curriculum's convention (``jaxlens.design.spec``): 68.8° diagonal field on a 7.20 mm sensor
diagonal, so f = 3.60 / tan(34.4°) = 5.258 mm, and F/2.022 so that the entrance pupil is
2.60 mm; distortion moves the paraxial EFL to about 5.55 mm. Four plastic aspheric elements
(E48R, OKP4, E48R, E48R), the stop first, 6.6 mm total track, 0.8 mm back clearance.

The curriculum designs for an object at infinity; the finished lens is then refocused for
an object 20 cm in front of the stop (the sensor distance minimising the mean polychromatic
RMS spot over the field) and given the experiment's sensor (1024² pixels of 4.97 µm), RGB
wavelengths and fields.
"""

from __future__ import annotations

import argparse
import math
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...optics.lens import Lens, Sensor
from .lenses import FOCUS_DEPTH, SPEC, WAVELENGTHS_RGB


def classical_spec(
    *,
    n_elements: int = 4,
    materials=("E48R", "OKP4", "E48R", "E48R"),
    total_track: float = 6.6,
    bfl: float = 0.8,
):
    """The ``DesignSpec`` of the classical lens (see the module docstring)."""
    from ...design.spec import DesignSpec

    half = 0.5 * SPEC["fov_deg"]
    f = 0.5 * SPEC["image_height_mm"] / math.tan(math.radians(half))
    return DesignSpec(
        fov=SPEC["fov_deg"],
        fnum=f / SPEC["epd_mm"],
        sensor_diagonal=SPEC["image_height_mm"],
        n_elements=n_elements,
        materials=tuple(materials),
        total_track=total_track,
        bfl=bfl,
        stop=0,
        fov_start=40.0,
        fnum_start=2.8,
        name="edof_classical",
    )


def _mean_rms(lens: Lens, depth_mm: float, fields) -> float:
    from ...analysis.spots import rms_spot

    r = rms_spot(lens, jnp.asarray(fields), jnp.asarray(WAVELENGTHS_RGB), depth=depth_mm)
    return float(jnp.sqrt(jnp.mean(r.polychromatic**2)))


def refocus(
    lens: Lens, depth_mm: float = FOCUS_DEPTH, *, span: float = 0.3, n: int = 61, fields=None
) -> tuple[Lens, float]:
    """Move the sensor to the best focus for an object ``depth_mm`` in front of surface 1.

    A grid search over the last gap (±``span`` mm, ``n`` points), then a parabola through the
    best three, minimising the RMS over ``fields`` (default 0 … full field) of the
    polychromatic RMS spot radius. Returns the lens and that RMS (mm).
    """
    fields = np.linspace(0.0, 0.5 * SPEC["fov_deg"], 7) if fields is None else fields
    t_last = float(lens.thickness[-1])
    shifts = np.linspace(-span, span, n)

    def at(dt):
        return eqx.tree_at(lambda m: m.thickness, lens, lens.thickness.at[-1].set(t_last + dt))

    vals = np.array([_mean_rms(at(dt), depth_mm, fields) for dt in shifts])
    i = int(np.clip(np.nanargmin(vals), 1, n - 2))
    y0, y1, y2 = vals[i - 1 : i + 2]
    h = shifts[1] - shifts[0]
    den = y0 - 2 * y1 + y2
    best = shifts[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0)
    out = at(best)
    return out, _mean_rms(out, depth_mm, fields)


def finish(lens: Lens, name: str = "edof_classical") -> Lens:
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
    return refocus(out)[0]


def design_classical(*, seeds=(0, 1, 2, 3), scale: float = 1.0, progress: bool = True, spec=None):
    """Design the classical lens with the curriculum; returns ``(lens, info)``.

    Args:
        seeds: random starts designed together (the best valid one is kept).
        scale: multiplies every step count of the default recipe
            (``jaxlens.design.multistart.DesignConfig``).
        progress: show progress bars.
        spec: the ``DesignSpec`` (default ``classical_spec()``).

    Returns:
        The finished lens (refocused at 20 cm) and a dict with the chosen seed, the
        curriculum's 256-field evaluation at infinity and the RMS at 20 cm.
    """
    from ...design import evaluate, multistart

    spec = classical_spec() if spec is None else spec
    config = multistart.DesignConfig().scaled(scale)
    res = multistart.design(spec, list(seeds), config, progress=progress)
    evals = [evaluate.evaluate(res.lens(i), spec) for i in range(len(res.seeds))]
    order = sorted(range(len(evals)), key=lambda i: (not evals[i].valid, evals[i].rms_mean_um))
    best = order[0]
    lens = finish(res.lens(best))
    info = {
        "seed": res.seeds[best],
        "evaluation_at_infinity": evals[best].summary(),
        "rms_at_20cm_um": 1e3
        * _mean_rms(lens, FOCUS_DEPTH, np.linspace(0.0, 0.5 * SPEC["fov_deg"], 7)),
        "spec": {
            "fov": spec.fov,
            "fnum": spec.fnum,
            "sensor_diagonal": spec.sensor_diagonal,
            "n_elements": spec.n_elements,
            "materials": list(spec.materials),
            "total_track": spec.total_track,
            "bfl": spec.bfl,
        },
        "recipe_scale": scale,
    }
    return lens, info


def main(argv=None) -> None:
    """Command line: design the classical lens and save it."""
    import json

    from ... import save

    here = os.path.join(
        os.path.dirname(os.path.dirname(__file__)), "data", "lenses", "edof_classical.json"
    )
    p = argparse.ArgumentParser(
        prog="python -m jaxlens.experiments.edof.design",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default=here, help="output JSON (default: the shipped lens)")
    p.add_argument("--seeds", type=int, default=4, help="random starts (default 4)")
    p.add_argument("--scale", type=float, default=1.0, help="step-count multiplier")
    p.add_argument(
        "--record",
        default=os.path.join("experiments", "edof", "classical_design.json"),
        help="where to write the design record (seed, RMS, geometry, spec)",
    )
    p.add_argument("--quiet", action="store_true")
    a = p.parse_args(argv)
    lens, info = design_classical(seeds=range(a.seeds), scale=a.scale, progress=not a.quiet)
    save(lens, a.out)
    os.makedirs(os.path.dirname(a.record) or ".", exist_ok=True)
    with open(a.record, "w") as f:
        json.dump(info, f, indent=2, default=float)
    print(json.dumps(info, indent=2, default=float))


if __name__ == "__main__":
    jax.config.update("jax_enable_x64", True)
    main()
