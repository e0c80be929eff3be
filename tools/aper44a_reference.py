"""Reference geometric |OTF| (round 44a) from optiland 0.6.3's real rays, for
tests/test_apertures_round44a.py: the beam of a lens whose stop has no semi-diameter.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/aper44a_reference.py

writes tests/data/aper44a/aper44a_optiland.json. optiland (as Zemax) samples the unit circle of
normalised pupil coordinates (Px² + Py² <= 1: under paraxial aiming the EPD's disc on the
paraxial entrance pupil's plane) and clips a ray only at a surface that has an aperture; a
stop without one clips nothing (psf/fft.py fills its pupil where R² <= 1; surfaces clip in
``aperture.clip`` only where ``aperture`` is set). Each lens is traced here with every
aperture removed (jaxlens's ``optics.lens.unclipped``), so the only bound on the beam is the
system aperture.

For each field: the |OTF| (tangential along y, sagittal along x, no pixel grid, no
diffraction) of optiland's rays at the primary wavelength on jaxlens's geometric-PSF pupil
grid (acc40c_reference's ``Cells``: 64² cell centres times the overfill 1.25, cut to the unit
pupil), ``ray_otf``; and, for the record, ``stop_clipped``: the same with the stop given the
paraxial marginal ray's height and the unit pupil's cut left out (the overfilled beam clipped
at the stop, jaxlens's rule before round 44a, ``aiming.apertured``).

Two more lenses keep their files' apertures (CLAP on every surface, optiland's
``RadialAperture``s; jaxlens's semi-diameters): tests/data/ri43c/triplet_stopsmall.zmx (the
stop's 3.4 mm narrower than the EPD's beam: it bounds the beam) and triplet_stopwide.zmx (the
stop wider than the beam: the unit pupil bounds it).

The lenses: tests/data/ri43c/triplet_stopwide.zmx (a Cooke triplet, EPD 10, f ≈ 50 mm; real
rim ray at the stop off the paraxial one) and Laikin's 100° retrofocus lens (tests/data/zmx/
optiland_circular_aperture_example_with_aperture.zmx, inches; strong pupil aberration),
both under paraxial aiming.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import warnings
from importlib.metadata import version

import numpy as np
from optiland.fileio import load_zemax_file

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import acc40c_reference as acc  # noqa: E402

OUT = ROOT / "tests" / "data" / "aper44a"
LENSES = {
    "triplet": dict(file="tests/data/ri43c/triplet_stopwide.zmx", fields=[0.0, 14.0, 20.0],
                    freqs=[10.0, 20.0, 40.0, 80.0]),
    "laikin": dict(file="tests/data/zmx/optiland_circular_aperture_example_with_aperture.zmx",
                   fields=[0.0, 20.0, 35.0], freqs=[5.0, 10.0, 20.0, 40.0]),
    # Given stop semi-diameters (the files' CLAP apertures kept, on every surface): a stop
    # narrower than the EPD's beam (3.4 mm; it bounds the beam, which must not change) and
    # one wider (the unit pupil bounds the beam, as optiland's).
    "triplet_stopsmall": dict(file="tests/data/ri43c/triplet_stopsmall.zmx",
                              fields=[0.0, 14.0, 20.0], freqs=[10.0, 20.0, 40.0, 80.0],
                              apertures=True),
    "triplet_stopwide": dict(file="tests/data/ri43c/triplet_stopwide.zmx",
                             fields=[0.0, 14.0, 20.0], freqs=[10.0, 20.0, 40.0, 80.0],
                             apertures=True),
}


class Overfilled(acc.Cells):
    """jaxlens's grid times the overfill, not cut to the unit pupil (the old rule's beam)."""

    def generate_points(self, num_points):
        g = (np.arange(num_points) + 0.5) / num_points * 2.0 - 1.0
        px, py = np.meshgrid(g, g, indexing="xy")
        keep = px * px + py * py <= 1.0
        self.x = px[keep] * acc.MTF_OVERFILL
        self.y = py[keep] * acc.MTF_OVERFILL


def main() -> None:
    warnings.filterwarnings("ignore")
    OUT.mkdir(parents=True, exist_ok=True)
    out = {"source": "optiland 0.6.3 (tools/aper44a_reference.py)", "optiland": version("optiland"),
           "mtf_cells": acc.MTF_CELLS, "mtf_overfill": acc.MTF_OVERFILL, "lenses": {}}
    for name, spec in LENSES.items():
        op = load_zemax_file(str(ROOT / spec["file"]))
        op.ray_tracer.set_aiming("paraxial")
        if not spec.get("apertures"):
            for s in op.surface_group.surfaces:
                s.aperture = None
        acc.tight(op)
        prim = float(op.primary_wavelength)
        stop = int(op.surface_group.stop_index)
        stop_r = abs(float(np.ravel(op.paraxial.marginal_ray()[0][stop])[0]))
        hmax = float(op.fields.max_field)
        res = {"file": spec["file"], "apertures": bool(spec.get("apertures")),
               "primary_um": prim, "stop_surface": stop,
               "paraxial_stop_radius": stop_r, "freqs": spec["freqs"], "fields": []}
        for f in spec["fields"]:
            field = (0.0, f / hmax)
            one = {"field_deg": f, "unit_pupil": acc.ray_otf(op, field, (0.0, f), prim,
                                                            spec["freqs"], stop, math.inf,
                                                            False)}
            if spec.get("apertures"):  # the file's stop aperture is the clip
                res["fields"].append(one)
                continue
            cells = acc.Cells
            acc.Cells = Overfilled
            try:
                one["stop_clipped"] = acc.ray_otf(op, field, (0.0, f), prim, spec["freqs"],
                                                  stop, stop_r, False)
            finally:
                acc.Cells = cells
            res["fields"].append(one)
        out["lenses"][name] = res
    (OUT / "aper44a_optiland.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
