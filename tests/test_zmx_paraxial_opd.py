"""A PARAXIAL surface in OPD mode 0/3 (or none) reached by a beam that is not collimated:
jaxlens's optical path (the perfect lens at infinite conjugates, OPD mode 2) differs from
the conjugate path OpticStudio's mode 0 adds (the lens perfect between the conjugates of the
beam that reaches it). ``zmx_surfaces.opd_mode_error`` bounds that difference; the reader
accepts it up to ``OPD_MODE_TOLERANCE_WAVES`` with a warning (an error under ``strict``)
and refuses it above, or where it cannot be bounded.

The reference: two ideal lenses (a weak one in mode 2, collimated input, then f = 100 mm),
traced by jaxlens to the common focus. In Zemax every ray then has the same optical path to
that focus (mode 2 is perfect for the collimated input, mode 0 for its conjugates), so the
peak to valley of jaxlens's optical path to the focus is the difference itself.
"""

from __future__ import annotations

import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx_surfaces
from jaxlens.io.zmx_common import ZmxWarning
from jaxlens.tracing.forward import trace_path

TWO_LENSES = """VERS 190513 80 123457 L123457
MODE SEQ
UNIT MM X W X CM MR CPMM
ENPD {epd}
FTYP 0 0 2 1 0 0 0
XFLN 0 0
YFLN 0 {field}
WAVM 1 0.5 1
SURF 0
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ INFINITY
SURF 1
  STOP
  TYPE PARAXIAL
  CURV 0 0 0 0 0 ""
  PARM 1 {f1}
  PARM 2 2
  DISZ 10
SURF 2
  TYPE PARAXIAL
  CURV 0 0 0 0 0 ""
  PARM 1 100
  {opd}
  DISZ 100
  DIAM {sd} 1 0 0 1 ""
{flap}SURF 3
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ 0
"""


def _text(f1=-2000.0, sd=10.0, opd="PARM 2 0", clipped=True, epd=20.0, field=0.0):
    flap = f"  FLAP 0 {sd} 0\n" if clipped else ""
    return TWO_LENSES.format(f1=f1, sd=sd, opd=opd, flap=flap, epd=epd, field=field)


def _load(tmp_path, text, **kw):
    p = tmp_path / "two.zmx"
    p.write_text(text)
    return jl.load(p, **kw)


def _traced_pv_waves(lens, field_deg, radius):
    """Peak to valley (waves) of jaxlens's optical path from a plane before surface 1 to the
    point where the rays meet behind surface 2 (rays landing within ``radius`` of it)."""
    wl = float(lens.wavelengths[0])
    g = np.linspace(-1, 1, 41)
    x, y = (a.ravel() for a in np.meshgrid(g, g))
    keep = x * x + y * y <= 1
    t = np.tan(np.deg2rad(field_deg))
    d = np.array([0.0, t, 1.0]) / np.hypot(t, 1.0)
    # Heights on surface 1 that land inside the disc of radius `radius` on surface 2.
    scale = radius / (1.0 - 10.0 / float(lens.surfaces[0].focal_length))
    base = np.stack([x[keep] * scale, y[keep] * scale, np.zeros(keep.sum())], -1)
    o = base - (base @ d + 1.0)[:, None] * d  # on a plane wavefront (normal d), before it
    rays = jl.Rays(jnp.asarray(o), jnp.asarray(np.broadcast_to(d, o.shape)), wl)
    after = trace_path(lens, rays, upto=1)[-1]
    p, u = np.asarray(after.origin), np.asarray(after.direction)
    assert bool(np.all(np.asarray(after.valid)))
    # The common point of the rays (least squares): they meet exactly (an ideal lens).
    a = np.zeros((3, 3))
    b = np.zeros(3)
    for pi, ui in zip(p, u, strict=True):
        m = np.eye(3) - np.outer(ui, ui)
        a += m
        b += m @ pi
    focus = np.linalg.solve(a, b)
    opl = np.asarray(after.opl) + np.sign(focus[2] - p[:, 2]) * np.linalg.norm(focus - p, axis=1)
    return (opl.max() - opl.min()) / (wl * 1e-3)


@pytest.mark.parametrize(("f1", "field"), [(-2000.0, 0.0), (3000.0, 0.0), (-2000.0, 2.0)])
def test_the_bound_is_the_traced_path_difference(tmp_path, f1, field):
    """opd_mode_error (diverging and converging beams, on axis and 2° off it) against the
    peak to valley of jaxlens's own traced optical path to the common focus."""
    lens = _load(tmp_path, _text(f1=f1, opd="PARM 2 2", field=field))
    bound, why = zmx_surfaces.opd_mode_error(lens, 1)
    assert why == ""
    traced = _traced_pv_waves(lens, field, 10.0 if field == 0.0 else 9.5)  # inside the rim
    # The bound also covers the axis and the other sections: at least the traced field's.
    assert bound >= traced * (1 - 2e-2)
    if field == 0.0:
        assert bound == pytest.approx(traced, rel=2e-2)
    # The analytic fourth-order term on axis, r⁴·a·(3fa − 1)/(8f²), a = 1/s the object's
    # vergence (s = 10 − f1 mm before surface 2): a third check of the size.
    if field == 0.0:
        a, f, r = 1.0 / (10.0 - f1), 100.0, 10.0
        analytic = abs(r**4 * a * (3 * f * a - 1) / (8 * f * f)) / 0.5e-3
        assert traced == pytest.approx(analytic, rel=5e-2)


def test_a_small_difference_is_accepted_with_a_warning_and_refused_under_strict(tmp_path):
    """f1 = −20 m: the beam diverges from 20 m away; over r = 2 mm the two paths differ by
    about 2e-5 waves, below the 0.01 accepted."""
    text = _text(f1=-20000.0, sd=2.0, epd=4.0)
    with pytest.warns(ZmxWarning, match=r"two\.zmx:\d+: this PARAXIAL surface has OPD mode 0 "
                                        r".*differ by at most .* waves"):
        lens = _load(tmp_path, text)
    bound, _ = zmx_surfaces.opd_mode_error(lens, 1)
    assert 0 < bound < zmx_surfaces.OPD_MODE_TOLERANCE_WAVES
    modes = {1: (0, _Line(tmp_path))}
    with pytest.raises(ValueError, match=r"differ by at most .*\(strict mode\)"):
        zmx_surfaces.check_opd_modes(lens, modes, strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _load(tmp_path, text.replace("PARM 2 0", "PARM 2 2"))  # mode 2: nothing to say


def test_a_large_difference_mode_1_or_no_bound_is_refused(tmp_path):
    big = _text(f1=-200.0, sd=10.0)  # a strongly diverging beam: ~4 waves
    with pytest.raises(ValueError, match=r"differ by [0-9.]+ waves \(peak to valley .*0\.01 "
                                         r"waves are accepted\)"):
        _load(tmp_path, big)
    with pytest.raises(ValueError, match=r"OPD mode 1 .*cannot be bounded \(the mode integrates"):
        _load(tmp_path, _text(f1=-20000.0, sd=2.0, epd=4.0, opd="PARM 2 1"))
    # Neither an aperture nor a DIAM bounds the beam.
    no_diam = _text(f1=-20000.0, sd=2.0, epd=4.0, clipped=False).replace(
        '  DIAM 2.0 1 0 0 1 ""\n', "")
    with pytest.raises(ValueError, match=r"cannot be bounded \(no finite semi-diameter"):
        _load(tmp_path, no_diam)


def test_an_unclipped_surface_is_bounded_by_the_diam_passed_by_the_reader(tmp_path):
    """Where the surface does not clip, the DIAM the reader passes bounds the beam."""
    text = _text(f1=-20000.0, sd=2.0, epd=4.0, opd="PARM 2 2", clipped=False)
    lens = _load(tmp_path, text)
    assert float(lens.surfaces[1].semi_diameter) == np.inf
    assert zmx_surfaces.opd_mode_error(lens, 1)[0] is None
    bound, _ = zmx_surfaces.opd_mode_error(lens, 1, beam_radius=2.0)
    clipped = _load(tmp_path, _text(f1=-20000.0, sd=2.0, epd=4.0, opd="PARM 2 2"))
    assert bound == zmx_surfaces.opd_mode_error(clipped, 1)[0]
    with pytest.warns(ZmxWarning, match="differ by at most"):
        zmx_surfaces.check_opd_modes(lens, {1: (0, _Line(tmp_path), 2.0)})
    # The reader passes the surface's DIAM (2 mm) and its strict switch.
    mode0 = text.replace("PARM 2 2", "PARM 2 0")
    with pytest.warns(ZmxWarning, match=r"two\.zmx:\d+: this PARAXIAL surface .*differ by at most"):
        _load(tmp_path, mode0)
    with pytest.raises(ValueError, match=r"differ by at most .*\(strict mode\)"):
        _load(tmp_path, mode0, strict=True)


class _Line:
    """The reader's line object, as far as check_opd_modes uses it."""

    def __init__(self, tmp_path):
        self.path, self.number, self.text = str(tmp_path / "two.zmx"), 19, "  TYPE PARAXIAL"

    def error(self, msg):
        return ValueError(f"{self.path}:{self.number}: {msg}: {self.text.strip()!r}")
