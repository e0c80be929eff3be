"""JSON lens files hold every surface kind and every per-surface datum a ``Lens`` holds.

Checks: every real ``.zmx`` file of tests/data that jaxlens opens saves as JSON and loads
back bit for bit (surface kinds, mirrors, coordinate breaks, apertures, obscurations); a
JSON file written by hand with the documented keys of each kind is the same lens as the
``.zmx`` file of the same data (so the keys mean what docs/lens-format.md says, in its
units); bad values are refused naming the surface and the key.
"""

import dataclasses
import glob
import json
import os
import warnings

import jax
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.io import zmx

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
FILES = [p for p in sorted(glob.glob(os.path.join(DATA, "**", "*"), recursive=True))
         if p.lower().endswith(".zmx")]


def _same(a, b):
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_allclose(np.asarray(x, np.float64), np.asarray(y, np.float64),
                                   rtol=1e-15, atol=0)


@pytest.mark.parametrize("path", FILES, ids=os.path.basename)
def test_every_real_file_round_trips_through_json(path, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            lens = jl.load(path)
        except ValueError:
            pytest.skip("not opened by jaxlens (refused content)")
    fields = np.asarray(lens.fields).reshape(len(lens.fields), -1)
    if len(np.unique(fields, axis=0)) < len(fields):  # optiland_lens_floa: three 0° fields
        with pytest.warns(UserWarning, match="a field is given twice"):
            json_round_trip(lens, tmp_path)
    else:
        json_round_trip(lens, tmp_path)


ZMX = """MODE SEQ
UNIT MM
ENPD 4
FTYP 0 0 1 1 0 0 0
YFLN 0
WAVM 1 0.55 1
SURF 0
  DISZ INFINITY
SURF 1
  STOP
  DISZ 2
SURF 2
{surface}
  DISZ {after}
SURF 3
{third}
  DISZ -30
SURF 4
"""

# (the .zmx lines of surface 2, the thickness after it, surface 3's lines, the JSON object
# of surface 2 and of surface 3 with the documented keys)
CASES = {
    "toroidal": ("  TYPE TOROIDAL\n  CURV 0.02\n  CONI -0.5\n  PARM 1 40\n  PARM 2 1e-4\n"
                 "  GLAS N-BK7", 3, "",
                 {"type": "toroidal", "curvature": 0.02, "conic": -0.5, "curvature_x": 0.025,
                  "y_coeffs": [1e-4], "material": "N-BK7"}, {}),
    "paraxial": ("  TYPE PARAXIAL\n  PARM 1 25\n  PARM 2 2", 3, "",
                 {"type": "paraxial", "focal_length": 25.0}, {}),
    "coordinate_break": ("  TYPE COORDBRK\n  PARM 1 0.5\n  PARM 3 2\n  PARM 5 10\n  PARM 6 1",
                         0, "  GLAS MIRROR",
                         {"type": "coordinate_break", "decenter_x": 0.5, "tilt_x_deg": 2.0,
                          "tilt_z_deg": 10.0, "order": 1},
                         {"mirror": True}),
    "grating": ("  TYPE DGRATING\n  CURV 0.01\n  PARM 1 0.1\n  PARM 2 -1", 3, "",
                {"type": "grating", "curvature": 0.01, "lines_per_um": 0.1,
                 "diffraction_order": -1}, {}),
    "binary2": ("  TYPE BINARY_2\n  CURV 0.01\n  PARM 0 1\n  PARM 1 1e-3\n  XDAT 1 2\n"
                "  XDAT 2 3\n  XDAT 3 -20\n  XDAT 4 1.5", 3, "",
                {"type": "binary2", "curvature": 0.01, "even_asphere_coeffs": [1e-3],
                 "diffraction_order": 1, "norm_radius": 3.0, "phase_coeffs": [-20.0, 1.5]},
                {}),
    "tilted_plane": ("  TYPE TILTSURF\n  PARM 1 0.01\n  PARM 2 -0.02\n  GLAS N-BK7", 3, "",
                     {"type": "tilted_plane", "tan_x": 0.01, "tan_y": -0.02,
                      "material": "N-BK7"}, {}),
}


def _json(second, third, after):
    thick3 = -30.0 if third.get("mirror") else 30.0
    return {"surfaces": [
        {"type": "object", "thickness": "inf"},
        {"is_stop": True, "thickness": 2.0},
        {**second, "thickness": float(after)},
        {**third, "thickness": thick3},
        {"type": "image"}],
        "aperture": {"epd": 4.0}, "fields": {"values": [0.0]}, "wavelengths_um": [0.55]}


@pytest.mark.parametrize("kind", CASES)
def test_hand_written_json_is_the_zmx_lens(kind, tmp_path):
    surface, after, third, second_json, third_json = CASES[kind]
    text = ZMX.format(surface=surface, after=after, third=third)
    if not third_json.get("mirror"):
        text = text.replace("DISZ -30", "DISZ 30")
    from_zmx = zmx.loads(text, "t.zmx")
    p = tmp_path / "l.json"
    p.write_text(json.dumps(_json(second_json, third_json, after)))
    from_json = jl.load(p)
    # The .zmx reader's lens traces by Zemax's rule (negative_propagation); the JSON does not
    # say so, and is the same lens otherwise.
    assert from_zmx.negative_propagation and not from_json.negative_propagation
    _same(dataclasses.replace(from_json, negative_propagation=True), from_zmx)
    assert from_json.mirrors == from_zmx.mirrors
    # And the same rays come out (a real trace, so every key's meaning is in play).
    u = np.linspace(-0.9, 0.9, 7)
    pupil = np.stack(np.meshgrid(u, u), -1).reshape(-1, 2)
    rays = jl.sampling.collimated(from_json, (1.0, 2.0), pupil, wavelength=0.55)
    a, b = jl.trace(from_json, rays), jl.trace(from_zmx, rays)
    np.testing.assert_array_equal(np.asarray(a.valid), np.asarray(b.valid))
    assert np.asarray(a.valid).sum() > 0
    np.testing.assert_allclose(np.asarray(a.origin), np.asarray(b.origin), rtol=0, atol=1e-12)


def _load_with(tmp_path, second, third=None):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(_json(second, third or {}, 3)))
    return jl.load(p)


@pytest.mark.parametrize(("second", "third", "match"), [
    ({"type": "toroidal", "curvature": 0.02, "even_asphere_coeffs": [1e-4]}, None,
     r"surface 2: a toroidal surface does not take even_asphere_coeffs; its keys are"),
    ({"type": "coordinate_break", "order": 2}, None, r"surface 2: order must be 0 .* or 1"),
    ({"type": "grating", "lines_per_um": -1.0}, None, r"surface 2: .*lines_per_um"),
    ({"type": "paraxial", "focal_length": 0.0}, None, r"surface 2: .*focal_length"),
    ({"type": "toroidal", "semi_diameter": 0}, None, r"surface 2: semi_diameter must be > 0"),
    ({"type": "tilted_plane", "tan_x": "steep"}, None, r"surface 2: tan_x"),
    ({"type": "standard", "curvature": 0.01, "tilt_x_deg": 5.0}, None,
     r"surface 2: a standard surface does not take tilt_x_deg \(the keys of type "
     r"coordinate_break\)"),
    ({"curvature": 0.01, "focal_length": 50.0}, None,
     r"surface 2: a standard surface does not take focal_length \(the keys of type paraxial"),
    ({}, {"obscuration": [1.0]}, r"surface 3: obscuration must be \[r_min, r_max\] \(mm\)"),
    ({}, {"mirror": "yes"}, r"surface 3: mirror must be true or false"),
    ({}, {"apertures": [{"shape": "circle", "half_x": 1.0, "half_y": 1.0, "blocked": True}]},
     r"surface 3: apertures\[0\]: unknown key\(s\) blocked"),
    ({}, {"apertures": [{"shape": "hexagon", "half_x": 1.0, "half_y": 1.0}]},
     r"surface 3: apertures\[0\]: .*shape must be one of"),
    ({}, {"apertures": [{"half_x": 1.0}]}, r"surface 3: apertures\[0\]: needs half_x and half_y"),
    ({}, {"apertures": {"half_x": 1.0}}, r"surface 3: apertures must be a list"),
])
def test_bad_values_name_the_surface_and_the_key(tmp_path, second, third, match):
    with pytest.raises(ValueError, match=match):
        _load_with(tmp_path, second, third)
