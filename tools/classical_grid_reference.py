"""optiland 0.6.3's numbers of an exported classical design at the run's own fields, for
tests/test_classical_grid.py.

Run it with an interpreter that has optiland 0.6.3 and this checkout's jaxlens:

    PYTHONPATH=$PWD /work/optiland_venv/bin/python tools/classical_grid_reference.py \
        experiments/classical/designs/seed_1.zmx 16 tests/data/classical_grid_optiland.json

The design is read by optiland from the ``.zmx`` file (``optiland.fileio.load_zemax_file``)
and traced at the fields of ``jaxlens.design.evaluate`` for the default ``DesignSpec`` (the
paper's 6-element spec: the n × n sensor grid of (θx, θy) fields, tan θx = x/f,
tan θy = y/f), with tools/export_reevaluation.py's ``optiland_grid_numbers``: per field the
RMS radius of the F, d, C rays pooled about their common centroid (21 × 21 pupil grid, 317
rays a wavelength, paraxial aiming), their mean, largest, smallest and median, the on-axis
RMS, EFL, F/#, BFL, total track, and the chief ray's height and f-tanθ distortion at half the
diagonal FoV. Twice: with every medium set to jaxlens's indices (``jaxlens_media``: only
geometry, aperture, fields and tracing are optiland's) and with optiland's own glass data
(``glass``).
"""

from __future__ import annotations

import json
import pathlib
import sys
import warnings

import jax

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import export_reevaluation as ex  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.design.evaluate import sensor_field_grid  # noqa: E402
from jaxlens.design.spec import DesignSpec  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402


def main(argv):
    if len(argv) != 3:
        raise SystemExit("usage: classical_grid_reference.py LENS.zmx N OUT.json")
    zmx, n, out = argv[0], int(argv[1]), argv[2]
    spec = DesignSpec()
    angles, _ = sensor_field_grid(spec, n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(zmx)
    ref = {"computed_by": "optiland 0.6.3 via tools/classical_grid_reference.py",
           "file": zmx, "n": n, "spec": "DesignSpec() (the defaults)"}
    for key, media in (("jaxlens_media", lens), ("glass", None)):
        numbers, grid = ex.optiland_grid_numbers(zmx, spec, angles, lens=media)
        ref[key] = {**numbers, "rms_per_field_um": grid.tolist()}
    write_whole(out, json.dumps(ref, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
