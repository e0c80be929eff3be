"""The decentered ``ZernikeSag`` (Zemax SZERNSAG/FZERNSAG PARM 9, 10) against optiland 0.6.3.

optiland's Zernike geometry has no decenter of its terms; tests/data/zernike_decenter_optiland.json
(written by tools/zernike_decenter_reference.py, which says how) holds two independent stand-ins:
``shifted``, optiland's even asphere plus optiland's Zernike sum evaluated at (x − dx, y − dy)
(sag, normal and a traced two-surface lens), and ``moved``, a flat-base Zernike surface placed
at (dx, dy) by optiland's own surface decenter (a traced lens; nothing of the decenter written
by hand). Both pin the convention of ``jaxlens.optics.freeform``: the pattern's centre lies at
(dx, dy). Whether OpticStudio decenters the same way was not checked against its own output
(no OpticStudio sag of a decentered surface was at hand).
"""

import json
import pathlib

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.optics.freeform import ZernikeSag

REF = json.loads((pathlib.Path(__file__).parent / "data" / "zernike_decenter_optiland.json")
                 .read_text())
WL = REF["wavelength"]


def _zernike(s: dict, sign: float = 1.0) -> ZernikeSag:
    return ZernikeSag(c=1.0 / s["radius"], k=s["conic"], coeffs=jnp.asarray(s["asphere"]),
                      zernike=jnp.asarray(s["zernike"]), norm_radius=s["norm_radius"],
                      decenter_x=sign * s["dx"], decenter_y=sign * s["dy"],
                      ordering="standard" if s["kind"] == "noll" else "fringe")


def _table(s, pts):
    """Sag and unit normal (+z at the vertex) at the points, as the reference holds them."""
    z, gx, gy, inside = s.sag_and_grad(jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1]))
    assert bool(np.all(np.asarray(inside)))
    n = np.stack([-np.asarray(gx), -np.asarray(gy), np.ones(len(pts))], -1)
    return np.column_stack([np.asarray(z), n / np.linalg.norm(n, axis=-1, keepdims=True)])


def _lens(surfaces, thickness, n):
    return jl.Lens(surfaces=tuple(surfaces), thickness=jnp.asarray(thickness),
                   materials=(jl.ModelGlass(n, 50.0), jl.Air()), epd=8.0,
                   wavelengths=jnp.asarray([WL]))


def _shifted(sign: float = 1.0) -> jl.Lens:
    s = REF["shifted_surfaces"]
    assert s[1]["n"] == 1.0
    return _lens([_zernike(x, sign) for x in s], [x["thickness"] for x in s], s[0]["n"])


def _moved(sign: float = 1.0) -> jl.Lens:
    m = REF["moved"]
    z = ZernikeSag(zernike=jnp.asarray(m["zernike"]), norm_radius=m["norm_radius"],
                   decenter_x=sign * m["dx"], decenter_y=sign * m["dy"])
    return _lens([z, jl.Standard(c=1.0 / m["radius2"])], [m["thickness"], m["thickness2"]],
                 m["n"])


def _trace(lens):
    rays = jl.Rays(jnp.asarray(REF["launch"]["origin"]), jnp.asarray(REF["launch"]["direction"]),
                   WL)
    out = jl.trace(lens, rays)
    assert bool(np.all(np.asarray(out.valid)))
    return np.asarray(out.origin)


@pytest.mark.parametrize("i", [0, 1])
def test_decentered_sag_and_normal_equal_optilands(i):
    """Noll terms on an even asphere (i = 0) and Fringe terms on a sphere (i = 1), decentered
    in x and y: sag and normal at 9 points within 2e-15 (measured 2.8e-17)."""
    s = REF["shifted_surfaces"][i]
    pts = np.asarray(REF["points"])
    got = _table(_zernike(s), pts)
    np.testing.assert_allclose(got, REF["sag"][i], rtol=0, atol=2e-15)
    # The other sign puts the pattern at (−dx, −dy): off by far more than the tolerance.
    other = _table(_zernike(s, -1.0), pts)
    assert np.max(np.abs(other - np.asarray(REF["sag"][i]))) > 1e-4


@pytest.mark.parametrize("name, build", [
    pytest.param("shifted", _shifted, marks=pytest.mark.slow),  # 8 s: 31 terms to compile
    ("moved", _moved)])
def test_decentered_zernike_rays_equal_optilands(name, build):
    """20 rays (4 (θx, θy) fields × 5 pupil points) through each lens land where optiland's
    land, within 1e-11 mm (measured 3.6e-15 and 2.4e-15 mm); with the decenter's sign flipped
    they miss by over 1 µm (0.14 and 0.031 mm)."""
    np.testing.assert_allclose(_trace(build()), REF["rays"][name], rtol=0, atol=1e-11)
    assert np.max(np.abs(_trace(build(-1.0)) - np.asarray(REF["rays"][name]))) > 1e-3
