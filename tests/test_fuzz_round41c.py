"""Round 41c: random lenses of the classes rounds 36b and 37b did not draw, against optiland
0.6.3 ray for ray (tools/fuzz41c_reference.py writes them, tools/fuzz41c_compare.py runs
``case_errors`` below over a folder and prints the table).

tests/data/fuzz41c holds the accepted draws of seed 41 (draws 0 to 55 of all classes, 56
to 79 of virtual objects; ``summary*.json`` count the refused ones by reason): object-space
telecentric lenses (``Lens(object_na=...)``, fields as (x, y) object heights in mm), the
same with an immersion object medium (n_d 1.33 to 1.52), virtual objects (a negative object
distance: the object point after surface 1, the entrance pupil before it or, in two draws,
behind it) and afocal image space (``Lens(afocal_image=True)``, the last power solved so
that the paraxial beam of an object at infinity leaves collimated). The prescriptions are
fuzz36b's (spheres, conics, even aspheres A4..A12, Cauchy index tables, cemented pairs,
glass image space, curved image surfaces), in its refcase schema, without A2: optiland's
paraxial engine leaves A2 out of the power, and aims its EPD rays at that entrance pupil
(with A2 drawn, 6 of 33 cases differed by that alone; jaxlens's c + 2·A2 is the paraxial
curvature of the sag c r²/2 + A2 r², checked against optiland on A2-folded copies in round 36b).

jaxlens generates its own rays (``sampling.field_rays`` from the field value and the
normalised pupil point, the lens's own object distance) and traces them; optiland generated
its own (``trace_generic`` from the normalised field and pupil): so the comparison covers
the ray generation of each class (the telecentric cone n·sin u, the virtual object's
converging beam, the afocal lens's collimated input) as well as the trace.

Tolerances (float64 on both sides):
* intercepts 1e-9 mm + 1e-12 of the case's largest coordinate, directions 1e-11: both tracers
  solve the same intersections to about 1e-13 (optiland's asphere Newton tolerance is set to
  1e-12 mm by the writer); the cases reach ~100 mm and up to 9 surfaces, so rounding stays
  under 1e-11 mm; 1e-9 leaves room for the Newton tolerance and nothing for a wrong ray;
* paraxial data relative 1e-10: both are y-nu traces of the same numbers (optiland's f2, EPL
  and paraxial magnification; the afocal angular magnification from fuzz36b's y-nu trace in
  the writer), agreeing to rounding.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib

import jax
import numpy as np
import pytest
from helpers import refcase_lens

from jaxlens.analysis import afocal
from jaxlens.imaging import sampling
from jaxlens.optics import paraxial
from jaxlens.tracing import forward

jax.config.update("jax_enable_x64", True)

FOLDER = pathlib.Path(__file__).parent / "data" / "fuzz41c"
CASES = sorted(p.stem for p in FOLDER.glob("fuzz41c_*.json"))
KINDS = ("telecentric", "telecentric_immersion", "virtual", "afocal")
POS_ABS, POS_REL, DIR_ABS, PARAX_REL = 1e-9, 1e-12, 1e-11, 1e-10


def _first_of_each_kind():
    seen = {}
    for c in CASES:
        kind = json.loads((FOLDER / f"{c}.json").read_text())["kind"]
        seen.setdefault(kind, c)
    return set(seen.values())


IN_CI = _first_of_each_kind()


def case_lens(path):
    """The jaxlens Lens of a round-41c case, and the raw case."""
    lens, d = refcase_lens(path)
    extra = {}
    if d["aperture"].get("object_na") is not None:
        extra["object_na"] = d["aperture"]["object_na"]
    if d.get("afocal_image"):
        extra["afocal_image"] = True
    return (dataclasses.replace(lens, **extra) if extra else lens), d


def case_errors(path):
    """The largest differences of one case: ``ray_pos`` (mm), ``ray_pos_rel`` (over the
    case's largest coordinate), ``ray_dir``, ``valid`` (the fraction of jaxlens's rays lost),
    ``parax_rel`` (each stored paraxial quantity, relative)."""
    lens, d = case_lens(path)
    depth = None if lens.object_at_infinity else lens.object_distance
    pupil = np.array(d["pupil"])
    got, want, lost = [], [], 0
    rays = d["real_rays"]
    k = len(pupil)
    for i in range(0, len(rays), k):
        r = rays[i]
        f = np.asarray(r["field"], float)
        rs = sampling.field_rays(lens, f, pupil, r["wavelength_nm"] / 1000, depth=depth)
        out = forward.trace(lens, rs)
        lost += int(np.sum(~np.asarray(out.valid)))
        got.append(np.concatenate([np.asarray(out.origin), np.asarray(out.direction)], 1))
        want.append([[q["image"][a] for a in "x y z L M N".split()] for q in rays[i:i + k]])
    got, want = np.concatenate(got), np.concatenate(want, dtype=float)
    size = float(np.abs(want[:, :3]).max())
    err = dict(
        ray_pos=float(np.abs(got[:, :3] - want[:, :3]).max()),
        ray_dir=float(np.abs(got[:, 3:] - want[:, 3:]).max()),
        valid=lost / len(got),
    )
    err["ray_pos_rel"] = err["ray_pos"] / size
    err["size"] = size
    p, par = d["paraxial"], []
    if p.get("f2") is not None:
        par.append(float(paraxial.paraxial_data(lens).efl_image_space) / p["f2"] - 1)
    if "paraxial_magnification" in p:
        par.append(float(paraxial.image_height(lens, 1.0)) / p["paraxial_magnification"] - 1)
    if "entrance_pupil_z" in p:
        zep = float(paraxial.entrance_pupil_z(lens, lens.primary_wavelength))
        par.append((zep - p["entrance_pupil_z"]) / max(1.0, abs(p["entrance_pupil_z"])))
    if "angular_magnification" in p:
        par.append(float(afocal.angular_magnification(lens)) / p["angular_magnification"] - 1)
    err["parax_rel"] = float(np.abs(par).max()) if par else 0.0
    return err, d


def check(err):
    assert err["valid"] == 0, err
    assert err["ray_pos"] <= POS_ABS + POS_REL * err["size"], err
    assert err["ray_dir"] <= DIR_ABS, err
    assert err["parax_rel"] <= PARAX_REL, err


def test_cases_present():
    assert len(CASES) >= 20, CASES
    kinds = {json.loads((FOLDER / f"{c}.json").read_text())["kind"] for c in CASES}
    assert kinds == set(KINDS)


@pytest.mark.parametrize(
    "case", [pytest.param(c, id=c, marks=() if c in IN_CI else pytest.mark.slow) for c in CASES]
)
def test_fuzz41c_rays_and_paraxial_data(case):
    err, d = case_errors(FOLDER / f"{case}.json")
    assert isinstance(d, dict)
    check(err)


def test_case_lenses_are_of_their_class():
    """The reader of the cases builds what they say: a telecentric lens with its NA, a
    virtual object, an afocal image space, an immersion object medium."""
    for c in IN_CI:
        lens, d = case_lens(FOLDER / f"{c}.json")
        kind = d["kind"]
        assert lens.telecentric_object == kind.startswith("telecentric")
        assert lens.afocal_image == (kind == "afocal")
        if kind == "virtual":
            assert float(lens.object_distance) < 0
        n0 = float(lens.object_material.index(lens.primary_wavelength))
        assert (n0 > 1.3) == (kind == "telecentric_immersion")

