"""Zemax vignetting factors (VDX, VDY, VCX, VCY, VAN): ``Lens.vignetting``, the pupil map of
``sampling.vignetting_map`` applied by ``sampling.field_rays`` for the lens's own fields, the
JSON and ``.zmx`` forms, and the refusal of bad factors.

The independent check: a 1902 Tessar (US patent 721240, the pyzdde sample
"Tessar_lens_using_vignetting_factors.ZMX", whose VDYN/VCXN/VCYN lines Zemax's Set
Vignetting wrote) against optiland 0.6.3. optiland applies only the compression of the
file's factors (it drops the decenter, saying so), so tools/vignetting_reference.py clears
its factors and traces the unvignetted ray at the point OpticStudio maps (Px, Py) to; the
numbers below are its output.
"""

import dataclasses
import json
import os
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import zoo
from jaxlens.imaging import sampling
from jaxlens.io import lensfile, zmx_parse, zmx_system, zmx_write
from jaxlens.optics.materials import Air, Tabulated
from jaxlens.optics.surfaces import Sphere
from jaxlens.tracing.forward import trace

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
US583336 = os.path.join(DATA, "rayoptics_US00583336-2-scaled.zmx")

# --------------------------------------------------------------------------- the map


def test_map_against_hand_values():
    p = jnp.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [-1.0, -0.5]])
    m = sampling.vignetting_map
    np.testing.assert_array_equal(m(jnp.zeros(5), p), p)
    # Px' = VDX + Px (1 - VCX), Py' = VDY + Py (1 - VCY)
    got = m(jnp.array([0.1, -0.2, 0.25, 0.5, 0.0]), p)
    want = [[0.1, -0.2], [0.1, 0.3], [0.85, 0.3], [0.1 - 0.75, -0.2 - 0.25]]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)
    # then a rotation by VAN degrees, counter-clockwise: 90 deg takes (x, y) to (-y, x)
    got = m(jnp.array([0.1, -0.2, 0.25, 0.5, 90.0]), p)
    np.testing.assert_allclose(got, np.stack([-np.array(want)[:, 1], np.array(want)[:, 0]], -1),
                               rtol=0, atol=1e-15)
    got = m(jnp.array([0.0, 0.0, 0.0, 0.0, 30.0]), jnp.array([[1.0, 0.0]]))
    np.testing.assert_allclose(got, [[np.sqrt(3) / 2, 0.5]], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match=r"vignetting_map: factors must be .*shape \[5\]"):
        m(jnp.zeros(4), p)


def _cooke(rows):
    """The Cooke triplet (fields 0, 14, 20 deg) with vignetting factors ``rows`` [3, 5]."""
    rows = rows if isinstance(rows, jax.Array) else np.asarray(rows, float)
    return dataclasses.replace(zoo.cooke_triplet(clip=False), vignetting=rows)


def test_factors_belong_to_the_lens_fields_only():
    rows = np.array([[0, 0, 0, 0, 0], [0.01, 0.02, 0.03, 0.04, 5.0], [0.1, -0.2, 0.3, 0.4, 0.0]])
    lens = _cooke(rows)
    fv = sampling.field_vignetting
    np.testing.assert_array_equal(fv(lens, 14.0), rows[1])
    np.testing.assert_array_equal(fv(lens, jnp.array([0.0, 20.0])), rows[2])
    np.testing.assert_array_equal(fv(lens, 20.0 + 1e-11), rows[2])  # within FIELD_MATCH_DEG
    np.testing.assert_array_equal(fv(lens, 17.0), np.zeros(5))  # between fields: none
    np.testing.assert_array_equal(fv(lens, jnp.array([1.0, 20.0])), np.zeros(5))
    # traced field and lens
    got = jax.jit(fv)(lens, jnp.asarray(20.0))
    np.testing.assert_array_equal(got, rows[2])
    # no factors: zeros
    np.testing.assert_array_equal(fv(zoo.cooke_triplet(), 20.0), np.zeros(5))


# ------------------------------------------------- the rays: vignetted = unvignetted at (Px', Py')


PUPIL4 = jnp.array([[0.0, 1.0], [0.0, -1.0], [0.0, 0.0], [1.0, 0.0]])
MAPPED = [((0, 0, 0, 0.5, 0), [[0, 0.5], [0, -0.5], [0, 0], [1, 0]]),
          ((0, 0.1, 0, 0, 0), [[0, 1.1], [0, -0.9], [0, 0.1], [1, 0.1]]),
          ((0.05, -0.1, 0.2, 0.3, 0), [[0.05, 0.6], [0.05, -0.8], [0.05, -0.1], [0.85, -0.1]]),
          ((0, 0, 0, 0, 90.0), [[-1, 0], [1, 0], [0, 0], [0, 1]])]


@pytest.mark.parametrize("depth", [None, 400.0])
def test_rays_of_a_vignetted_field_are_the_rays_at_the_mapped_points(depth):
    """VCY = 0.5: the upper marginal ray (Py = 1) is the unvignetted lens's ray at
    Py' = 0.5; VDY = 0.1 moves the pupil centre's ray to Py' = 0.1; VAN = 90 deg takes
    (0, 1) to (-1, 0). From a finite depth the point-source branch maps the same way."""
    plain = zoo.cooke_triplet(clip=False)
    for row, mapped in MAPPED:
        lens = _cooke([np.zeros(5), np.zeros(5), row])
        got = sampling.field_rays(lens, lens.fields[2], PUPIL4, depth=depth)
        want = sampling.field_rays(plain, plain.fields[2], jnp.array(mapped, float), depth=depth)
        np.testing.assert_allclose(got.origin, want.origin, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.direction, want.direction, rtol=0, atol=1e-15)
        # the unvignetted field 1 of the same lens is untouched
        np.testing.assert_array_equal(
            sampling.field_rays(lens, lens.fields[1], PUPIL4, depth=depth).origin,
            sampling.field_rays(plain, plain.fields[1], PUPIL4, depth=depth).origin)


def test_real_aiming_aims_at_the_mapped_points():
    """With ``aim="real"`` the mapped point is the one aimed at the stop: the rays are
    those aimed at (Px', Py') for the lens without factors (zeros: the same program)."""
    rays = eqx.filter_jit(sampling.field_rays)
    row, mapped = MAPPED[2]
    lens = _cooke([np.zeros(5), np.zeros(5), row])
    none = _cooke(np.zeros((3, 5)))
    got = rays(lens, lens.fields[2], PUPIL4, aim="real")
    want = rays(none, none.fields[2], jnp.array(mapped, float), aim="real")
    np.testing.assert_allclose(got.origin, want.origin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.direction, want.direction, rtol=0, atol=1e-15)
    # and they differ from the paraxially aimed ones (the aiming did act)
    par = sampling.field_rays(lens, lens.fields[2], PUPIL4)
    assert np.max(np.abs(got.origin - par.origin)) > 1e-6


def test_spots_follow_the_factors():
    """The analyses launch their rays with field_rays: a spot of a vignetted field is the
    unvignetted lens's spot at the mapped pupil points (and differs from the full pupil)."""
    from jaxlens.analysis import spots

    plain = zoo.cooke_triplet(clip=False)
    row = jnp.array([0.0, -0.06, 0.08, 0.3, 0.0])
    lens = _cooke([np.zeros(5), np.zeros(5), np.asarray(row)])
    pupil = sampling.pupil_hexapolar(3, jnp.float64)
    got = spots.spot_rays(lens, 20.0, pupil=pupil)
    want = spots.spot_rays(plain, 20.0, pupil=sampling.vignetting_map(row, pupil))
    np.testing.assert_allclose(got.origin, want.origin, rtol=0, atol=1e-12)
    full = spots.spot_rays(plain, 20.0, pupil=pupil)
    assert np.max(np.abs(got.origin - full.origin)) > 1e-3


def test_gradient_through_the_factors():
    """d(image y of the upper marginal ray)/d(VDY) against a central difference."""
    pupil = jnp.array([[0.0, 1.0]])

    def y(vdy):
        lens = _cooke(jnp.zeros((3, 5)).at[2, 1].set(vdy))
        return trace(lens, sampling.field_rays(lens, lens.fields[2], pupil)).origin[0, 1]

    g = jax.grad(y)(0.05)
    h = 1e-5
    fd = (y(0.05 + h) - y(0.05 - h)) / (2 * h)
    assert abs(g - fd) <= 1e-6 * abs(fd) and abs(g) > 1e-3


# ------------------------------------------------------------ the Tessar against optiland

# Curvatures (1/mm) and thicknesses (mm) of the file's surfaces 1..8; the stop is surface 5.
TESSAR_C = [4.670060243777000200E-002, 0.0, -1.347708894879000000E-002, 4.807692307691999900E-002,
            0.0, -8.984725965858000200E-003, 3.968253968254000000E-002, -2.694473634574999800E-002]
TESSAR_T = [3.3, 1.9, 1.1, 3.0, 3.0, 1.1, 3.0, 90.907]
# The media after surfaces 1..8 at 0.589 µm: jaxlens's SCHOTT SK4, BAF4, KF9 (given to
# optiland too by tools/vignetting_reference.py).
TESSAR_N = [1.6126428468576401, 1.0, 1.6055197471525104, 1.0, 1.0, 1.5233373744874135,
            1.6126428468576401, 1.0]
TESSAR_FIELDS = [0.0, 10.0, 17.5, 25.0]
# The file's VDYN, VCXN, VCYN (VDXN and VANN are 0).
TESSAR_VDY = [0.0, -5.90366428E-2, -5.49110517E-2, -6.07784421E-2]
TESSAR_VCX = [0.0, 4.99773026E-2, 6.09502792E-2, 8.54997635E-2]
TESSAR_VCY = [0.0, 8.88719559E-2, 1.87924385E-1, 3.05908203E-1]

# optiland 0.6.3: /work/optiland_venv/bin/python tools/vignetting_reference.py
#     <corpus>/pyzdde_Tessar_lens_using_vignetting_factors.ZMX
# (field index, Px, Py, image x mm, image y mm), primary wavelength, paraxial aiming.
OPTILAND = [
    (0, 0.0, 1.0, 0.0, 0.009228386486405782),
    (0, 0.0, -1.0, 0.0, -0.009228386486405782),
    (0, 0.0, 0.0, 0.0, 0.0),
    (0, 1.0, 0.0, 0.009228386486405782, 0.0),
    (0, -1.0, 0.0, -0.009228386486405782, 0.0),
    (0, 0.6, -0.5, -0.017183792513429275, 0.014319827094516846),
    (1, 0.0, 1.0, 0.0, 17.504786852968298),
    (1, 0.0, -1.0, 0.0, 17.535041597896495),
    (1, 0.0, 0.0, 0.0, 17.5708091170563),
    (1, 1.0, 0.0, -0.025442136030574325, 17.56758081999983),
    (1, -1.0, 0.0, 0.025442136030574325, 17.56758081999983),
    (1, 0.6, -0.5, -0.02924023654906982, 17.59493402170698),
    (2, 0.0, 1.0, 0.0, 31.28381627372564),
    (2, 0.0, -1.0, 0.0, 31.352737179713827),
    (2, 0.0, 0.0, 0.0, 31.37136848053046),
    (2, 1.0, 0.0, -0.04798583909577747, 31.36395677871219),
    (2, -1.0, 0.0, 0.04798583909577747, 31.36395677871219),
    (2, 0.6, -0.5, -0.05171800346227329, 31.398173989287038),
    (3, 0.0, 1.0, 0.0, 46.12589567457914),
    (3, 0.0, -1.0, 0.0, 46.12839336690416),
    (3, 0.0, 0.0, 0.0, 46.2239526688262),
    (3, 1.0, 0.0, -0.009139721369015419, 46.20454210255984),
    (3, -1.0, 0.0, 0.009139721369015419, 46.20454210255984),
    (3, 0.6, -0.5, -0.04122700077714292, 46.21386631285118),
]


def _tessar(vignetted: bool = True):
    mats = tuple(Air() if n == 1.0 else Tabulated([0.589], [n]) for n in TESSAR_N)
    v = np.zeros((4, 5))
    v[:, 1], v[:, 2], v[:, 3] = TESSAR_VDY, TESSAR_VCX, TESSAR_VCY
    lens = jl.Lens(surfaces=tuple(Sphere(c) for c in TESSAR_C), thickness=jnp.array(TESSAR_T),
                   materials=mats, stop=4, fields=jnp.array(TESSAR_FIELDS),
                   wavelengths=jnp.array([0.589]), vignetting=v if vignetted else None)
    return lensfile.apply_aperture(lens, fnum=5.5)  # the file's FNUM 5.5


def test_tessar_intercepts_against_optiland():
    lens = _tessar()
    for i in range(4):
        rows = [r for r in OPTILAND if r[0] == i]
        pupil = jnp.array([[r[1], r[2]] for r in rows])
        out = trace(lens, sampling.field_rays(lens, lens.fields[i], pupil))
        assert bool(jnp.all(out.valid))
        np.testing.assert_allclose(out.origin[:, :2], [[r[3], r[4]] for r in rows],
                                   rtol=0, atol=1e-9)
    # the factors matter here by far more than the tolerance
    plain = _tessar(vignetted=False)
    out = trace(plain, sampling.field_rays(plain, 25.0, jnp.array([[0.0, 1.0]])))
    assert abs(float(out.origin[0, 1]) - OPTILAND[18][4]) > 0.01


# ------------------------------------------------------------------------ files


def test_json_round_trip(tmp_path):
    rows = np.array([[0, 0, 0, 0, 0], [0.01, -0.02, 0.03, 0.04, 5.0], [0.1, -0.2, 0.3, -0.4, 0.0]])
    lens = _cooke(rows)
    d = lensfile.lens_to_dict(lens)
    assert d["fields"]["vignetting"]["vcy"] == [0.0, 0.04, -0.4]
    assert d["fields"]["vignetting"]["van_deg"] == [0.0, 5.0, 0.0]
    back = lensfile.lens_from_dict(json.loads(json.dumps(d)))
    np.testing.assert_array_equal(back.vignetting, rows)
    path = tmp_path / "v.json"
    jl.save(lens, path)
    np.testing.assert_array_equal(jl.load(path).vignetting, rows)
    # without factors: no key, and None back
    d0 = lensfile.lens_to_dict(zoo.cooke_triplet())
    assert "vignetting" not in d0["fields"] and lensfile.lens_from_dict(d0).vignetting is None
    # a missing column is 0
    d["fields"]["vignetting"] = {"vdy": [0.0, 0.0, 0.1]}
    np.testing.assert_array_equal(lensfile.lens_from_dict(d).vignetting[:, 1], [0, 0, 0.1])


@pytest.mark.parametrize("bad, match", [
    ({"vdy": [0.0, 0.1]}, r"fields.vignetting.vdy must hold one value per field \(3\)"),
    ({"vcy": [0.0, 0.0, 1.0]}, r"fields.vignetting: factors VCY must be finite numbers in "
                               r"\(-inf, 1\) pupil radii, got 1"),
    ({"vdyy": [0.0, 0.0, 0.1]}, r"unknown key 'vdyy'; did you mean 'vdy'"),
    ({"tilt": [0.0, 0.0, 0.1]}, r"unknown key 'tilt'; the keys are vdx, vdy, vcx, vcy, van_deg"),
    ([0.0, 0.1], r"fields.vignetting must be an object"),
    ({"van_deg": [0.0, "inf", 0.0]}, r"van_deg"),
])
def test_json_bad_factors(bad, match):
    d = lensfile.lens_to_dict(zoo.cooke_triplet())
    d["fields"]["vignetting"] = bad
    with pytest.raises(ValueError, match=match):
        lensfile.lens_from_dict(d, source="f.json")


def test_zmx_lines_read_and_written():
    """The file's lines as ``Lens.vignetting`` rows; save_zmx writes them back exactly."""
    with open(US583336, "rb") as fh:
        raw = fh.read()
    f = zmx_parse.parse(raw.decode("utf-8", "replace"), US583336)
    v = zmx_system.vignetting(f.vignetting, 3)
    want = np.zeros((3, 5))
    want[1:, 1] = [6.208442661354E-2, 5.473246586901E-2]
    want[1:, 2] = [2.455956935883E-3, 2.0477435112E-3]
    want[1:, 3] = [1.556542586327E-1, 3.64762539196E-1]
    np.testing.assert_array_equal(v, want)
    lens = _cooke(want)
    text, _ = zmx_write.dumps(lens)
    assert "VDYN 0 6.208442661354E-002 5.473246586901E-002" in text
    back = zmx_parse.parse(text, "w.zmx")
    np.testing.assert_array_equal(zmx_system.vignetting(back.vignetting, 3), want)
    # no factors: no lines
    assert "VDYN" not in zmx_write.dumps(zoo.cooke_triplet())[0]


def _zmx_with(tmp_path, line):
    text, _ = zmx_write.dumps(zoo.cooke_triplet())
    text = text.replace("FWGN", line + "\nFWGN", 1)
    f = zmx_parse.parse(text, "t.zmx")
    return f


@pytest.mark.parametrize("line, match", [
    ("VCYN 0 0 1.0", r"t.zmx:\d+: VCYN of field 3 must be below 1 \(fractions of the "
                     r"entrance-pupil radius"),
    ("VDYN 0 NAN 0", r"t.zmx:\d+: VDYN value must be finite"),
    ("VDYN 0 0 0.1\nVDYN 0 0 0.2", r"VDYN given twice"),
])
def test_zmx_bad_factors_name_the_line(tmp_path, line, match):
    f = _zmx_with(tmp_path, line)
    with pytest.raises(ValueError, match=match):
        zmx_system.vignetting(f.vignetting, 3)


def test_zmx_factors_beyond_the_used_fields_are_ignored(tmp_path):
    f = _zmx_with(tmp_path, "VCYN 0 0.2 0.3 1.5 7")  # FTYP counts 3 fields
    np.testing.assert_array_equal(zmx_system.vignetting(f.vignetting, 3)[:, 3], [0, 0.2, 0.3])
    assert zmx_system.vignetting(_zmx_with(tmp_path, "VCYN 0 0 0 0").vignetting, 3) is None


def test_load_zmx_fills_the_factors(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # RAIM
        lens = jl.load(US583336)
    assert lens.vignetting is not None
    np.testing.assert_array_equal(lens.vignetting[2, 3], 3.64762539196E-1)
    rows = np.array([[0, 0, 0, 0, 0], [0.01, -0.02, 0.03, 0.04, 5.0], [0.1, -0.2, 0.3, -0.4, 0]])
    path = tmp_path / "v.zmx"
    jl.save(_cooke(rows), path)
    np.testing.assert_array_equal(jl.load(path).vignetting, rows)


# ------------------------------------------------------------------------ bad input


@pytest.mark.parametrize("rows, match", [
    ([[0, 0, 0, 0, 0], [0, 0, 0, 1.0, 0], [0, 0, 0, 0, 0]],
     r"Lens: vignetting VCY must be finite numbers in \(-inf, 1\) pupil radii, got 1"),
    ([[0, 0, 0, 0, 0], [0, 0, 2.0, 0, 0], [0, 0, 0, 0, 0]],
     r"Lens: vignetting VCX must be finite numbers in \(-inf, 1\) pupil radii, got 2"),
    ([[0, 0, 0, 0, 0], [0, np.nan, 0, 0, 0], [0, 0, 0, 0, 0]],
     r"Lens: vignetting VDY must be finite numbers \(pupil radii\), got nan"),
    ([[0, 0, 0, 0, np.inf]] * 3, r"Lens: vignetting VAN must be finite numbers \(deg\)"),
    ([[0, 0, 0, 0, 0]] * 2, r"Lens: vignetting must hold one row .* shape \[3, 5\] for 3 "
                            r"field\(s\) .*pupil radii, VAN in deg\), got shape \(2, 5\)"),
    ([0, 0, 0, 0, 0], r"shape \[3, 5\].*got shape \(5,\)"),
])
def test_bad_factors_refused(rows, match):
    with pytest.raises(ValueError, match=match):
        _cooke(rows)


def test_bad_factor_types_refused():
    with pytest.raises(TypeError, match=r"Lens: vignetting must be a real number"):
        dataclasses.replace(zoo.cooke_triplet(), vignetting="none")


def test_fields_replaced_without_their_factors_are_refused():
    """eqx.tree_at skips the Lens's checks; field_rays then refuses the stale factors (they
    would be read for the wrong fields)."""
    lens = _cooke(np.zeros((3, 5)))
    lens = eqx.tree_at(lambda m: m.fields, lens, jnp.array([0.0, 20.0]))
    with pytest.raises(ValueError, match=r"field_vignetting: the lens has 2 field\(s\) but "
                                         r"vignetting factors of shape \(3, 5\)"):
        sampling.field_rays(lens, 20.0, jnp.zeros((1, 2)))
    # vignetting_for_fields gives the rows for new fields: kept where a field stays
    rows = np.array([[0, 0, 0, 0, 0], [0.01, -0.02, 0.03, 0.04, 5.0], [0.1, -0.2, 0.3, -0.4, 0]])
    lens = _cooke(rows)
    new = jnp.array([20.0, 7.0, 14.0])
    got = sampling.vignetting_for_fields(lens, new)
    np.testing.assert_array_equal(got, [rows[2], np.zeros(5), rows[1]])
    moved = dataclasses.replace(lens, fields=new, vignetting=got)
    np.testing.assert_array_equal(sampling.field_vignetting(moved, 14.0), rows[1])
    assert sampling.vignetting_for_fields(zoo.cooke_triplet(), new) is None
