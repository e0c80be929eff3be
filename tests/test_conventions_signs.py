"""Two sign conventions of Zemax data, pinned by cases whose answer the convention predicts
(each fails for the opposite sign):

* the vignetting angle VAN (``sampling.vignetting_map``): the compressed, decentered pupil is
  turned by VAN counter-clockwise, from +x toward +y; an elliptical pupil (VCX = 0.5) turned
  by 30° has its short axis at +30° and its long one at 120°, and its centre (VDX, 0) at
  VDX·(cos 30°, sin 30°). No OpticStudio text at hand states the direction (see the
  docstring of ``vignetting_map``); this is jaxlens's documented reading.
* the decenter of the Zernike terms of a Zernike Standard Sag surface (PARM 9, 10): the
  terms are evaluated at (x − dx, y − dy), i.e. the Zernike pattern moves to (dx, dy)
  (OpticStudio's help: the decenter "of the Zernike terms relative to the base asphere"; ρ
  and φ are the decentered coordinates). A defocus term read from a file with
  PARM 9 = 0.6, PARM 10 = −0.4 has its vertex (zero slope) at (0.6, −0.4) mm.
"""

from __future__ import annotations

import dataclasses
import math

import jax.numpy as jnp
import numpy as np

import jaxlens as jl
from jaxlens import zoo
from jaxlens.imaging import sampling
from jaxlens.optics import paraxial
from jaxlens.optics.freeform import ZernikeSag


def _axes(points):
    """(centre, angle of the long axis in degrees in [0, 180), long and short semi-axes) of
    points spread evenly around an ellipse."""
    c = points.mean(0)
    w, v = np.linalg.eigh(np.cov((points - c).T, bias=True))
    long = v[:, 1]
    ang = math.degrees(math.atan2(long[1], long[0])) % 180.0
    return c, ang, math.sqrt(2 * w[1]), math.sqrt(2 * w[0])


def test_van_turns_the_vignetted_pupil_counter_clockwise():
    phi = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)
    ring = jnp.asarray(np.stack([np.cos(phi), np.sin(phi)], -1))
    # the map alone: VCX = 0.5 and VDX = 0.2, then VAN = 30 deg
    got = np.asarray(sampling.vignetting_map(jnp.array([0.2, 0.0, 0.5, 0.0, 30.0]), ring))
    c, ang, a, b = _axes(got)
    np.testing.assert_allclose(c, 0.2 * np.array([math.cos(math.pi / 6), 0.5]), atol=1e-12)
    assert abs(ang - 120.0) < 1e-9 and abs(a - 1.0) < 1e-9 and abs(b - 0.5) < 1e-9
    # ... and the rays field_rays launches for the lens's own on-axis field: with paraxial
    # aiming, the ray at pupil point P crosses the entrance-pupil plane at P'·EPD/2.
    base = zoo.cooke_triplet(clip=False)
    rows = np.zeros((base.fields.shape[0], 5))
    rows[0] = [0.2, 0.0, 0.5, 0.0, 30.0]
    lens = dataclasses.replace(base, vignetting=rows)
    assert float(lens.fields[0]) == 0.0
    rays = sampling.field_rays(lens, 0.0, ring, aim="paraxial")
    zep = float(paraxial.entrance_pupil_z(lens))
    at_ep = np.asarray(rays.propagate_to_z(zep).origin)[:, :2] / (float(lens.epd) / 2)
    np.testing.assert_allclose(at_ep, got, rtol=0, atol=1e-12)
    c, ang, a, b = _axes(at_ep)
    assert abs(ang - 120.0) < 1e-6 and c[1] > 0.09  # -30 deg would put them at 60 deg, y < 0


def test_the_zernike_decenter_moves_the_terms_to_it(tmp_path):
    text = """VERS 190513 80 123457 L123457
MODE SEQ
UNIT MM X W X CM MR CPMM
ENPD 8
FTYP 0 0 1 1 0 0 0
XFLN 0
YFLN 0
WAVM 1 0.5875618 1
SURF 0
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ INFINITY
SURF 1
  STOP
  TYPE SZERNSAG
  CURV 0 0 0 0 0 ""
  PARM 0 1
  PARM 9 0.6
  PARM 10 -0.4
  XDAT 1 4 0 0 0 0 0 ""
  XDAT 2 5 0 0 0 0 0 ""
  XDAT 6 0.01 0 0 0 0 0 ""
  DISZ 5
  GLAS ___BLANK 1 0 1.5 50 0 0 0 0 0 0
SURF 2
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ 40
SURF 3
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ 0
"""
    p = tmp_path / "zdec.zmx"
    p.write_text(text)
    s = jl.load(p, strict=True).surfaces[0]
    assert isinstance(s, ZernikeSag)
    assert float(s.decenter_x) == 0.6 and float(s.decenter_y) == -0.4
    # Noll Z4 = sqrt(3)(2 rho^2 - 1) on R = 5 mm around (0.6, -0.4): a paraboloid with its
    # vertex there, z = A4 sqrt(3) (2 ((x - 0.6)^2 + (y + 0.4)^2)/25 - 1).
    x = jnp.array([0.6, 0.0, 1.2, -2.0, 3.0])
    y = jnp.array([-0.4, 0.0, -0.4, 1.5, -2.5])
    z, gx, gy, _ = s.sag_and_grad(x, y)
    want = 0.01 * math.sqrt(3) * (2 * ((np.asarray(x) - 0.6) ** 2
                                       + (np.asarray(y) + 0.4) ** 2) / 25 - 1)
    np.testing.assert_allclose(np.asarray(z), want, rtol=0, atol=1e-15)
    assert float(gx[0]) == 0.0 and float(gy[0]) == 0.0  # the vertex of the term: (dx, dy)
    assert float(gx[1]) < 0 and float(gy[1]) > 0  # the origin lies at −x, +y of it
