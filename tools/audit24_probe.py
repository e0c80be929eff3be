# ruff: noqa: E501, B023, E731
"""Round-24 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for what rounds 15-23 did not reach: ``Lens(travel_senses=...)`` and
``jaxlens.optics.travel`` (folds whose coordinate breaks turn the frame round with the light),
``CoordinateBreak`` values (90°/180° tilts, radians, huge decenters), mirrors with
obscurations and apertures, JSON lens files with folds and wrong types per key, the imaging
strategies (``RayRender``/``PSFRender``, ``psf_map``, ``footprints``), afocal analyses and
the tolerancing entry points (``Tolerances``, ``ToleranceModel``, ``monte_carlo``,
``sensitivity``) and the tools a user runs (``make_agf.py``, ``export_reevaluation.py``).

Before (main at 97c30a3) and after (this branch), 147 probes, ``PYTHONPATH=<tree> python
tools/audit24_probe.py`` under ``ulimit -v 16000000``, one 2-core machine shared (50 s; no
probe starts long work on main):
    before: clear error 103, crash 4, ok 21, silent wrong 14, vague error 5
    after:  clear error 116, crash 1, ok 21, silent wrong 8, vague error 1
Fixed: a JSON file's ``travel_senses`` key that disagrees with the frames (it was not read, so
a stale one loaded silently), a JSON ``obscuration`` on a coordinate break (the tracer ignored
it: every ray of a 1e9 mm obscuration got through), ``render``'s ``RayRender(footprints=...)``
of another type (AttributeError) and ``footprint_grid`` past 257 (refused by ``footprints`` as
"grid"), ``footprints(wavelengths=())`` (numpy's zero-size message), ``ToleranceModel``'s
``batch`` (10**9 was kept; each chunk was padded to it), ``monte_carlo``'s ``threshold_um``
given in mm (below the CLIs' 0.01 µm floor: every trial failed), ``tools/make_agf.py``'s
missing database or ``--out`` folder (exit 1 / a traceback after reading the first maker),
and ``tools/export_reevaluation.py``'s missing path (a report line, exit 0), ``--summary``
file or ``--json`` folder (a traceback after every file was evaluated).

Left (files of the lead's today: lens.py, travel.py, coordinates.py): ``Lens`` keeps an
obscuration on a coordinate break (it refuses an aperture there), the public helpers of
``optics.travel`` take a negative surface count, a mirror index past the end, None or a dict,
``CoordinateBreak`` keeps a 1e12 mm decenter, a 1e6-degree tilt and a semi_diameter (its
docstring says inf), and a fold whose break tilts were given in radians loads as an unfolded
mirror with the lens behind it (EFL -50.5 mm for +50.5; see the report of round 24).

Run: PYTHONPATH=$PWD python tools/audit24_probe.py [filter]
"""

import copy
import dataclasses
import json
import os
import sys
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.io import lensfile  # noqa: E402
from jaxlens.optics import travel  # noqa: E402

cooke = zoo.cooke_triplet()
HUGE = 10**12
TMP = tempfile.mkdtemp()
AIR = "air"

# The Quadoa form of a 45-degree fold (tests/test_travel_senses.py): a -45 deg break, the
# mirror with its thickness along its own axis, a +135 deg break with a decenter, a singlet.
FOLD = {
    "format": "jaxlens.lens/1", "name": "fold",
    "units": {"length": "mm", "wavelength": "um", "angle": "deg"},
    "aperture": {"epd": 10.0},
    "fields": {"type": "angle_deg_y", "values": [0.0]},
    "wavelengths_um": [0.55], "primary": 0,
    "surfaces": [
        {"type": "object", "thickness": "inf", "material": AIR},
        {"type": "standard", "curvature": 0.0, "thickness": 10.0, "material": AIR, "is_stop": True},
        {"type": "coordinate_break", "tilt_x_deg": -45.0, "thickness": 0.0, "material": AIR},
        {"type": "standard", "curvature": 0.0, "thickness": -10.0, "material": AIR, "mirror": True},
        {"type": "coordinate_break", "decenter_y": -10.0, "tilt_x_deg": 135.0, "thickness": 0.0, "material": AIR},
        {"type": "standard", "curvature": 0.02, "thickness": 4.0, "material": {"nd": 1.5, "vd": 60.0}},
        {"type": "standard", "curvature": -0.02, "thickness": 50.0, "material": AIR},
        {"type": "image"},
    ],
}


def fold_dict(**edits):
    d = copy.deepcopy(FOLD)
    for path, v in edits.items():
        keys = path.split("__")
        tgt = d
        for k in keys[:-1]:
            tgt = tgt[int(k)] if k.isdigit() else tgt[k]
        last = keys[-1]
        if v is DEL:
            del tgt[int(last) if last.isdigit() else last]
        else:
            tgt[int(last) if last.isdigit() else last] = v
    return d


DEL = object()


def load(d, name="x.json"):
    p = os.path.join(TMP, name)
    with open(p, "w") as f:
        json.dump(d, f)
    return jl.load(p)


# ----------------------------------------------------------------------------- folds, senses
def folds():
    fold = lensfile.lens_from_dict(FOLD)
    probe("fold JSON loads (control)", lambda: fold.travel_senses, good=True)
    probe("travel_senses list [1,...] (documented: a tuple; a list converts)", lambda: dataclasses.replace(fold, travel_senses=list(fold.travel_senses)).travel_senses, good=True)
    probe("travel_senses numpy array of ±1", lambda: dataclasses.replace(fold, travel_senses=np.array(fold.travel_senses)).travel_senses, good=True)
    probe("travel_senses floats (1.0, ...)", lambda: dataclasses.replace(fold, travel_senses=tuple(float(v) for v in fold.travel_senses)), "travel_senses")
    probe("travel_senses True entries", lambda: dataclasses.replace(fold, travel_senses=(True,) * 7), "travel_senses")
    probe("travel_senses '+-' string", lambda: dataclasses.replace(fold, travel_senses="+++-+++"), "travel_senses")
    probe("travel_senses () empty", lambda: dataclasses.replace(fold, travel_senses=()), "travel_senses", "7")
    probe("travel_senses 8 entries", lambda: dataclasses.replace(fold, travel_senses=(1, 1, 1, -1, 1, 1, 1, 1)), "travel_senses", "7")
    probe("travel_senses all -1", lambda: dataclasses.replace(fold, travel_senses=(-1,) * 7), "travel_senses")
    probe("travel_senses mirror-count form on Quadoa fold", lambda: dataclasses.replace(fold, travel_senses=(1, 1, 1, -1, -1, -1, -1)), "travel_senses")
    probe("travel_senses 2 (not ±1)", lambda: dataclasses.replace(fold, travel_senses=(1, 1, 1, -2, 1, 1, 1)), "travel_senses")
    probe("travel_senses an int 1", lambda: dataclasses.replace(fold, travel_senses=1), "travel_senses")
    probe("travel.mirror_count_senses(-1, ())", lambda: travel.mirror_count_senses(-1, ()), "num_surfaces")
    probe("travel.mirror_count_senses(3, (7,)) mirror past the end", lambda: travel.mirror_count_senses(3, (7,)), "mirror")
    probe("travel.frame_senses(None, ())", lambda: travel.frame_senses(None, ()), "surfaces")
    probe("travel.axial_thicknesses(a dict)", lambda: travel.axial_thicknesses(FOLD), "lens")
    probe("travel.travel_senses(cooke) (control)", lambda: travel.travel_senses(cooke), good=True)
    probe("fold EFL (control)", lambda: float(jl.paraxial_data(fold).efl), good=True)


# ----------------------------------------------------------------------------- coordinate breaks
def breaks():
    def fold_with(tilt):
        return lensfile.lens_from_dict(fold_dict(surfaces__2__tilt_x_deg=tilt))
    probe("fold break tilt 90 deg (axis across the frame)", lambda: lensfile.lens_from_dict(fold_dict(surfaces__2__tilt_x_deg=90.0, surfaces__4__tilt_x_deg=0.0)), "90", "surface")
    probe("fold break tilts in radians (-0.785, 2.356)", lambda: float(jl.paraxial_data(lensfile.lens_from_dict(fold_dict(surfaces__2__tilt_x_deg=-0.7854, surfaces__4__tilt_x_deg=2.356))).efl), "tilt", "deg")
    probe("CoordinateBreak tilt_x nan", lambda: jl.CoordinateBreak(tilt_x=np.nan), "tilt_x")
    probe("CoordinateBreak decenter_y 1e12 mm", lambda: jl.CoordinateBreak(decenter_y=1e12), "decenter_y", "mm")
    probe("CoordinateBreak tilt_x 1e6 deg", lambda: jl.CoordinateBreak(tilt_x=1e6), "tilt_x", "deg")
    probe("CoordinateBreak tilt_y complex 1j", lambda: jl.CoordinateBreak(tilt_y=1j), "tilt_y")
    probe("CoordinateBreak tilt_x bool True", lambda: jl.CoordinateBreak(tilt_x=True), "tilt_x")
    probe("CoordinateBreak tilt_x array (2,)", lambda: jl.CoordinateBreak(tilt_x=np.array([1.0, 2.0])), "tilt_x")
    probe("CoordinateBreak order 1.0", lambda: jl.CoordinateBreak(order=1.0), good=True)
    probe("CoordinateBreak order '1'", lambda: jl.CoordinateBreak(order="1"), "order")
    probe("CoordinateBreak semi_diameter 5 (ignored?)", lambda: float(jl.CoordinateBreak(semi_diameter=5.0).semi_diameter), "semi_diameter")
    probe("fold break tilt 180 deg both (frames flip twice)", lambda: lensfile.lens_from_dict(fold_dict(surfaces__2__tilt_x_deg=180.0, surfaces__4__tilt_x_deg=180.0)).travel_senses, good=True)


# ----------------------------------------------------------------------------- mirrors, obscurations, apertures
def mirrors():
    fold = lensfile.lens_from_dict(FOLD)
    # Lens indices count from the first surface after the object: 0 stop, 1 break, 2 mirror, 3 break.
    probe("obscuration on a coordinate break (surface 1)", lambda: dataclasses.replace(fold, obscurations=((1, 0.0, 1.0),)), "obscuration", "coordinate break")
    probe("spot of the fold with an obscuration r_max 1e9 on a coordinate break", lambda: int(jl.analysis.spot_rays(dataclasses.replace(fold, obscurations=((1, 0.0, 1e9),)), 0.0).valid.sum()), "obscuration", "coordinate break")
    probe("JSON obscuration on a coordinate break", lambda: load(fold_dict(surfaces__2__obscuration=[0.0, 1e9])), "obscuration", "coordinate break")
    probe("obscuration r_min > r_max on the mirror", lambda: dataclasses.replace(fold, obscurations=((2, 2.0, 1.0),)), "r_min")
    probe("obscuration r nan on the mirror", lambda: dataclasses.replace(fold, obscurations=((2, 0.0, np.nan),)), "obscuration")
    probe("spot of the fold with an obscuration r_max 1e9 on the mirror (blocks all)", lambda: int(jl.analysis.spot_rays(dataclasses.replace(fold, obscurations=((2, 0.0, 1e9),)), 0.0).valid.sum()), good=True)
    probe("obscuration index -1", lambda: dataclasses.replace(fold, obscurations=((-1, 0.0, 1.0),)), "obscuration", "[0, 5]")
    probe("aperture on a coordinate break", lambda: dataclasses.replace(fold, apertures=((1, jl.Aperture("rect", 1.0, 1.0)),)), "aperture", "coordinate break")
    probe("spot of the fold with a 0.1 mm square aperture on the mirror", lambda: int(jl.analysis.spot_rays(dataclasses.replace(fold, apertures=((2, jl.Aperture("rect", 0.1, 0.1)),)), 0.0).valid.sum()), good=True)
    probe("aperture entry not a pair", lambda: dataclasses.replace(fold, apertures=(jl.Aperture("rect", 1.0, 1.0),)), "apertures")
    probe("aperture index 99", lambda: dataclasses.replace(fold, apertures=((99, jl.Aperture("rect", 1.0, 1.0)),)), "apertures")
    probe("mirrors (3, 3) repeated", lambda: dataclasses.replace(fold, mirrors=(2, 2)), "mirrors")
    probe("mirrors (3.0,) float", lambda: dataclasses.replace(fold, mirrors=(2.0,)), "mirrors")
    probe("mirror on the stop surface (the axis then meets the break's frame across)", lambda: dataclasses.replace(fold, mirrors=(0,)), "across", "surface")


# ----------------------------------------------------------------------------- JSON files, wrong types
def json_files():
    probe("JSON fold: travel_senses key as the frames give it", lambda: load(fold_dict(travel_senses=[1, 1, 1, -1, 1, 1, 1])).travel_senses, good=True)
    probe("JSON fold: travel_senses key in Zemax's mirror-count form (stale)", lambda: load(fold_dict(travel_senses=[1, 1, 1, -1, -1, -1, -1])), "travel_senses", "[1, 1, 1, -1, 1, 1, 1]")
    probe("JSON cooke-like: travel_senses key with a -1 (no fold)", lambda: load(fold_dict(travel_senses=[1, 1, 1, 1, 1, 1, -1], surfaces__2__tilt_x_deg=0.0, surfaces__4__tilt_x_deg=0.0, surfaces__4__decenter_y=0.0, surfaces__3__mirror=False, surfaces__3__thickness=10.0)), "travel_senses")
    probe("JSON fold: negative_propagation 'yes'", lambda: load(fold_dict(negative_propagation="yes")), "negative_propagation")
    probe("JSON mirror: 'true' string", lambda: load(fold_dict(surfaces__3__mirror="true")), "mirror")
    probe("JSON mirror: 1 (int)", lambda: load(fold_dict(surfaces__3__mirror=1)), "mirror")
    probe("JSON is_stop: 'yes'", lambda: load(fold_dict(surfaces__1__is_stop="yes")), "is_stop")
    probe("JSON tilt_x_deg: '-45' string (documented: a number's text reads)", lambda: load(fold_dict(surfaces__2__tilt_x_deg="-45")).travel_senses, good=True)
    probe("JSON tilt_x_deg: null", lambda: load(fold_dict(surfaces__2__tilt_x_deg=None)), "tilt_x_deg")
    probe("JSON tilt_x_deg: [45]", lambda: load(fold_dict(surfaces__2__tilt_x_deg=[-45])), "tilt_x_deg")
    probe("JSON break: 'tilt_x' (no _deg) key", lambda: load(fold_dict(surfaces__2__tilt_x=-45.0)), "tilt_x")
    probe("JSON break: order 2", lambda: load(fold_dict(surfaces__2__order=2)), "order")
    probe("JSON break: order true", lambda: load(fold_dict(surfaces__2__order=True)), "order")
    probe("JSON break: curvature 0.1", lambda: load(fold_dict(surfaces__2__curvature=0.1)), "curvature")
    probe("JSON break: material glass (must be the medium before)", lambda: load(fold_dict(surfaces__2__material="N-BK7")), "material")
    probe("JSON thickness: true", lambda: load(fold_dict(surfaces__1__thickness=True)), "thickness")
    probe("JSON thickness: '10 mm'", lambda: load(fold_dict(surfaces__1__thickness="10 mm")), "thickness")
    probe("JSON curvature: {}", lambda: load(fold_dict(surfaces__5__curvature={})), "curvature")
    probe("JSON primary: 0.0 float", lambda: load(fold_dict(primary=0.0)), "primary")
    probe("JSON primary: '0'", lambda: load(fold_dict(primary="0")), "primary")
    probe("JSON wavelengths_um: 550 (nm given)", lambda: load(fold_dict(wavelengths_um=[550.0])), "wavelength", "µm")
    probe("JSON wavelengths_um: a number, not a list", lambda: load(fold_dict(wavelengths_um=0.55)), good=True)
    probe("JSON units angle 'rad'", lambda: load(fold_dict(units={"length": "mm", "wavelength": "um", "angle": "rad"})), "angle")
    probe("JSON units length 'in'", lambda: load(fold_dict(units={"length": "in", "wavelength": "um", "angle": "deg"})), "length")
    probe("JSON aperture epd: '10'", lambda: float(load(fold_dict(aperture={"epd": "10"})).epd), good=True)
    probe("JSON aperture epd: true", lambda: load(fold_dict(aperture={"epd": True})), "epd")
    probe("JSON fields values: ['0']", lambda: load(fold_dict(fields={"type": "angle_deg_y", "values": ["0"]})).fields, good=True)
    probe("JSON fields: a list (no type)", lambda: load(fold_dict(fields=[0.0, 5.0])).fields, good=True)
    probe("JSON surfaces: a dict", lambda: load(fold_dict(surfaces={"0": {}})), "surfaces")
    probe("JSON surface: a list", lambda: load(fold_dict(surfaces__5=[0.02, 4.0])), "surface")
    probe("JSON material: 7 (a number)", lambda: load(fold_dict(surfaces__5__material=7)), "material")
    probe("JSON material nd: '1.5'", lambda: load(fold_dict(surfaces__5__material={"nd": "1.5", "vd": 60.0})).name, good=True)
    probe("JSON top level: a list", lambda: load([FOLD]), "object")
    probe("JSON name: 5", lambda: load(fold_dict(name=5)), "name")


# ----------------------------------------------------------------------------- imaging
def imaging():
    from jaxlens.imaging import psf as P
    from jaxlens.imaging import render as R
    scene = jnp.zeros((16, 16, 3))
    key = jax.random.PRNGKey(0)
    cam = dataclasses.replace(cooke, sensor=jl.Sensor(resolution=(16, 16), pixel_size=0.01))
    rr = lambda m, **kw: R.render(cam, scene, spp=4, key=key, method=m, **kw)
    probe("render RayRender(footprint_grid=0)", lambda: rr(R.RayRender(footprint_grid=0)), "footprint_grid")
    probe("render RayRender(footprint_grid=10**6)", lambda: rr(R.RayRender(footprint_grid=10**6)), "footprint_grid")
    probe("render RayRender(footprint_grid=9.5)", lambda: rr(R.RayRender(footprint_grid=9.5)), "footprint_grid")
    probe("render RayRender(footprints='auto')", lambda: rr(R.RayRender(footprints="auto")), "footprints")
    probe("render PSFRender(kernel_size=0)", lambda: rr(R.PSFRender(kernel_size=0)), "kernel_size")
    probe("render PSFRender(kernel_size=10**6)", lambda: rr(R.PSFRender(kernel_size=10**6)), "kernel_size")
    probe("render PSFRender(kernel_size=32) even", lambda: rr(R.PSFRender(kernel_size=32)), "kernel_size")
    probe("render wavelengths () with a 0-channel scene", lambda: R.render(cam, jnp.zeros((16, 16, 0)), spp=4, key=key, wavelengths=()), "empty")
    probe("psf wavelength [] (empty)", lambda: P.psf(cooke, 0.0, wavelength=jnp.zeros((0,))), "wavelength")
    probe("mtf wavelengths [] (empty)", lambda: P.mtf(cooke, 0.0, wavelengths=jnp.zeros((0,))), "wavelength")
    probe("psf_map wavelength [] (empty)", lambda: P.psf_map(cam, wavelength=jnp.zeros((0,))), "wavelength")
    probe("render method 'ray' string", lambda: R.render(cooke, scene, spp=4, key=key, method="ray"), "method")
    probe("render spp 10**9", lambda: R.render(cooke, scene, spp=10**9, key=key), "spp")
    probe("render spp True", lambda: R.render(cooke, scene, spp=True, key=key), "spp")
    probe("render patch 0", lambda: R.render(cooke, scene, spp=4, key=key, patch=0), "patch")
    probe("render patch -64", lambda: R.render(cooke, scene, spp=4, key=key, patch=-64), "patch")
    probe("render newton_iters -1", lambda: R.render(cooke, scene, spp=4, key=key, newton_iters=-1), "newton_iters")
    probe("render wavelengths (656, 588, 486) nm", lambda: R.render(cooke, scene, spp=4, key=key, wavelengths=(656.0, 588.0, 486.0)), "wavelength", "µm")
    probe("render scene int8 dtype", lambda: R.render(cooke, jnp.zeros((16, 16, 3), jnp.int8), spp=4, key=key), "scene")
    probe("render scene (16,16,3) complex", lambda: R.render(cooke, jnp.zeros((16, 16, 3), jnp.complex64), spp=4, key=key), "scene")
    probe("footprints grid 1", lambda: R.footprints(cooke, grid=1), "grid")
    probe("footprints grid 10**5", lambda: R.footprints(cooke, grid=10**5), "grid")
    probe("footprints wavelengths ()", lambda: R.footprints(cooke, wavelengths=()), "wavelengths")
    probe("psf_map grid (0, 5)", lambda: P.psf_map(cooke, grid=(0, 5)), "grid")
    probe("psf_map grid (10**5, 10**5)", lambda: P.psf_map(cooke, grid=(10**5, 10**5)), "grid")
    probe("psf_map grid 5 (an int)", lambda: P.psf_map(cooke, grid=5), "grid")
    probe("psf_map grid (5.5, 5)", lambda: P.psf_map(cooke, grid=(5.5, 5)), "grid")
    probe("psf kernel_size 10**6", lambda: P.psf(cooke, 0.0, kernel_size=10**6), "kernel_size")
    probe("psf center 'Chief'", lambda: P.psf(cooke, 0.0, center="Chief"), "center")
    probe("psf max_truncation 5 (percent?)", lambda: P.psf(cooke, 0.0, max_truncation=5.0), "max_truncation")
    probe("mtf frequencies negative", lambda: P.mtf(cooke, 0.0, frequencies=jnp.array([-10.0, 10.0])), "frequencies")
    probe("GeometricPSF() on the fold (control)", lambda: float(P.psf(lensfile.lens_from_dict(FOLD), 0.0, pixel_size=0.002, max_truncation=None).sum()), good=True)


# ----------------------------------------------------------------------------- afocal
def afocal():
    from jaxlens.analysis import afocal as AF
    here = os.path.dirname(os.path.abspath(__file__))
    kep = jl.load(os.path.join(here, "..", "tests", "data", "afocal_kepler.zmx"))
    probe("angular_magnification wavelength 550 (nm)", lambda: AF.angular_magnification(kep, wavelength=550.0), "wavelength", "µm")
    probe("angular_magnification wavelength nan", lambda: AF.angular_magnification(kep, wavelength=np.nan), "wavelength")
    probe("angular_magnification of a focal lens (documented: defined for any lens)", lambda: float(AF.angular_magnification(cooke)), good=True)
    probe("angular_spot reference 'Chief'", lambda: AF.angular_spot(kep, reference="Chief"), "reference")
    probe("angular_spot fields [90] deg", lambda: AF.angular_spot(kep, fields=jnp.array([90.0])), "field", "deg")
    probe("angular_spot fields [] empty", lambda: AF.angular_spot(kep, fields=jnp.zeros((0,))), "fields")
    probe("angular_spot wavelengths [] empty", lambda: AF.angular_spot(kep, wavelengths=jnp.zeros((0,))), "wavelengths")
    probe("angular_spot pupil 'grid'", lambda: AF.angular_spot(kep, pupil="grid"), "pupil")
    probe("angular_spot of cooke (documented: any lens's directions)", lambda: AF.angular_spot(cooke).polychromatic, good=True)


# ----------------------------------------------------------------------------- tolerancing
def tolerancing():
    from jaxlens.analysis import tolerance as T
    probe("Tolerances thickness -0.02", lambda: T.Tolerances(thickness=-0.02), "thickness")
    probe("Tolerances radius_rel 5 (percent)", lambda: T.Tolerances(radius_rel=5.0), "radius_rel")
    probe("Tolerances tilt 0.5 (rad? deg?) nan", lambda: T.Tolerances(tilt=np.nan), "tilt")
    probe("Tolerances tilt 90 deg", lambda: T.Tolerances(tilt=90.0), "tilt", "deg")
    probe("ToleranceModel decenter 1e3 mm (beyond the clear aperture)", lambda: T.ToleranceModel(cooke, tolerances=T.Tolerances(decenter=1e3)), "decenter", "mm")
    probe("Tolerances distribution 'Normal'", lambda: T.Tolerances(distribution="Normal"), "distribution")
    probe("Tolerances index '5e-4'", lambda: T.Tolerances(index="5e-4"), "index")
    probe("ToleranceModel batch 0", lambda: T.ToleranceModel(cooke, batch=0), "batch")
    probe("ToleranceModel batch 10**9", lambda: T.ToleranceModel(cooke, batch=10**9), "batch")
    probe("ToleranceModel apertures 'closed'", lambda: T.ToleranceModel(cooke, apertures="closed"), "apertures")
    probe("ToleranceModel tolerances a dict", lambda: T.ToleranceModel(cooke, tolerances={"thickness": 0.02}), "tolerances")
    probe("ToleranceModel field_weights negative", lambda: T.ToleranceModel(cooke, fields=jnp.array([0.0, 10.0]), field_weights=jnp.array([1.0, -1.0])), "field_weights")
    probe("ToleranceModel field_weights wrong length", lambda: T.ToleranceModel(cooke, fields=jnp.array([0.0, 10.0]), field_weights=jnp.array([1.0, 1.0, 1.0])), "field_weights")
    probe("ToleranceModel of the fold lens", lambda: T.ToleranceModel(lensfile.lens_from_dict(FOLD)), good=True)
    m = T.ToleranceModel(cooke)
    probe("monte_carlo trials 0", lambda: T.monte_carlo(m, trials=0, threshold_um=10.0, mtf_frequency=30.0), "trials")
    probe("monte_carlo trials 10**9", lambda: T.monte_carlo(m, trials=10**9, threshold_um=10.0, mtf_frequency=30.0), "trials")
    probe("monte_carlo threshold_um 0.006 (mm given)", lambda: T.monte_carlo(m, trials=2, threshold_um=0.006, mtf_frequency=30.0), "threshold_um", "µm")
    probe("monte_carlo mtf_frequency -30", lambda: T.monte_carlo(m, trials=2, threshold_um=10.0, mtf_frequency=-30.0), "mtf_frequency")
    probe("monte_carlo min_valid 99 (percent)", lambda: T.monte_carlo(m, trials=2, threshold_um=10.0, mtf_frequency=30.0, min_valid=99.0), "min_valid")
    probe("monte_carlo key an int 0", lambda: T.monte_carlo(m, trials=2, key=0, threshold_um=10.0, mtf_frequency=30.0), "key")
    probe("sensitivity check -1", lambda: T.sensitivity(m, check=-1), "check")
    probe("sensitivity check 10**9 (documented: the k largest; all of them)", lambda: T.sensitivity(m, check=10**9)["nominal_rms_um"], good=True)


# ----------------------------------------------------------------------------- tools
def tools():
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    import make_agf
    def cli(argv, mod):
        def f():
            old = sys.argv
            sys.argv = [mod.__name__] + argv
            try:
                return mod.main()
            finally:
                sys.argv = old
        f.cli = True
        return f
    import export_reevaluation as ER
    lens_json = os.path.join(here, "..", "jaxlens", "data", "lenses", "cooke_triplet.json")
    probe("tools/export_reevaluation.py a missing path", cli([os.path.join(TMP, "none.zmx")], ER), "paths", "no such file")
    probe("tools/export_reevaluation.py --json into a missing folder", cli([lens_json, "--json", os.path.join(TMP, "no", "out.json")], ER), "--json", "no such folder")
    probe("tools/export_reevaluation.py --summary a missing file", cli([lens_json, "--summary", os.path.join(TMP, "none.json")], ER), "--summary", "no such file")
    probe("tools/make_agf.py no args", cli([], make_agf), "required", "database")
    probe("tools/make_agf.py a missing database folder", cli([os.path.join(TMP, "no", "such")], make_agf), "database", "no such folder")
    probe("tools/make_agf.py --out a missing folder", cli([TMP, "--out", os.path.join(TMP, "no", "out")], make_agf), "--out", "no such folder")


run([folds, breaks, mirrors, json_files, imaging, afocal, tolerancing, tools])
