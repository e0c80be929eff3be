"""Reference numbers for tests/test_export_fields.py: a lens with x and oblique fields, saved by
``jaxlens.save`` as ``.zmx`` (XFLN, YFLN) and re-evaluated in optiland 0.6.3 by
tools/export_reevaluation.py's own functions.

Run it with an interpreter that has optiland 0.6.3 and this checkout's jaxlens:

    PYTHONPATH=$PWD /work/optiland_venv/bin/python tools/export_fields_reference.py \
        tests/data/export_fields.zmx tests/data/export_fields_optiland.json

The lens: the Cooke triplet of ``jaxlens.zoo`` (``jaxlens/data/lenses/cooke_triplet.json``)
with the fields of :data:`FIELDS` ((θx, θy) in degrees: on axis, pure x, pure −y and three
oblique ones, the largest 20° from the axis), its own wavelengths (F, d, C) and EPD. It is
written to the ``.zmx`` path given; optiland reads that file (``optiland.fileio.
load_zemax_file``) and traces it twice: with its own glass data (``glass``), and with every
medium replaced by jaxlens's index at each wavelength (``jaxlens_media``; only geometry,
aperture, fields and tracing are optiland's). For each: the system numbers (EFL in image
space, F/#, BFL, total track, FoV = 2 × its largest radial field, the fields it read as
(θx, θy)) and per field the chief ray's (x, y) and its height along the field's azimuth,
the f-tanθ distortion, the RMS spot radius per wavelength about the centroid and pooled over
the wavelengths (317-point pupil grid, paraxial aiming); definitions in
tools/export_reevaluation.py.
"""

from __future__ import annotations

import json
import pathlib
import sys

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import export_reevaluation as ex  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402

FIELDS = [[0.0, 0.0], [9.0, 0.0], [0.0, -14.0], [6.0, 8.0], [-12.0, 16.0], [10.0, -5.0]]


def lens() -> jl.Lens:
    base = jl.zoo.cooke_triplet()
    return eqx.tree_at(lambda x: x.fields, base, jnp.asarray(FIELDS, jnp.float64))


def main(argv):
    if len(argv) != 2:
        raise SystemExit("usage: export_fields_reference.py OUT.zmx OUT.json")
    zmx, out = argv
    built = lens()
    jl.save(built, zmx)
    reread = jl.load(zmx)
    wl = [float(w) for w in reread.wavelengths]
    primary = wl[int(reread.primary)]
    ref = {"computed_by": "optiland 0.6.3 via tools/export_fields_reference.py",
           "file": pathlib.Path(zmx).name, "fields": FIELDS, "wavelengths": wl,
           "primary": primary,
           "glass": ex.optiland_numbers(zmx, wl, primary, FIELDS),
           "jaxlens_media": ex.optiland_numbers(zmx, wl, primary, FIELDS, lens=reread)}
    write_whole(out, json.dumps(ref, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
