"""Tolerancing an object-space telecentric lens: its fields are object heights in mm.

``ToleranceModel`` checked them as field angles (a height of 90 mm or more refused, small
ones warned of as radians) and its MTF metric took the tangential direction along
(tan x°, tan y°) instead of the height itself."""

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import tolerance
from jaxlens.analysis.tolerance_metric import field_mtf, spot_data

X20 = "tests/data/acc40c/tele_doublet_x20.zmx"  # heights up to (60, 100) mm


def test_heights_of_90_mm_and_more_are_taken():
    lens = jl.load(X20)
    model = tolerance.ToleranceModel(lens, batch=2)  # the file's fields: up to 100 mm
    np.testing.assert_allclose(np.asarray(model.fields), [[0, 0], [0, 100], [60, 100]])
    with pytest.raises(ValueError, match=r"mm \(object heights of an object-space telecentric"):
        tolerance.ToleranceModel(lens, fields=[[0.0, 1.0, 2.0]])


def test_mtf_tangential_direction_is_the_height():
    lens = jl.load(X20)
    fields = np.array([[60.0, 100.0]])
    wl = lens.wavelengths
    g = np.stack(np.meshgrid(np.linspace(-0.9, 0.9, 7), np.linspace(-0.9, 0.9, 7)),
                 -1).reshape(-1, 2)
    pupil = g[np.sum(g * g, -1) <= 0.81]
    data = spot_data(lens, fields, wl, pupil)
    nu, fnum = 1.0, 10.0
    got = float(field_mtf(data, fields, wl, nu, fnum, heights=True)[0])
    # By hand: T along the height (60, 100)/|.|, S turned by −90°, on the rays about their
    # common centroid, times the diffraction MTF of each wavelength (the function's own).
    from jaxlens.imaging.otf import diffraction_mtf
    q = np.asarray(data.position)[0]  # [W, M, 2]
    w = np.asarray(data.weight)[0]
    ref = (w[..., None] * q).sum((0, 1)) / w.sum()
    e_t = fields[0] / np.linalg.norm(fields[0])
    e_s = np.array([e_t[1], -e_t[0]])
    diff = np.asarray(diffraction_mtf(nu, np.asarray(wl) * 1e-3, fnum))
    parts = []
    for e in (e_t, e_s):
        proj = ((q - ref) * e).sum(-1)
        o = (w / w.sum(-1, keepdims=True) * np.exp(-2j * np.pi * nu * proj)).sum(-1)
        parts.append(abs(np.mean(o * diff)))
    np.testing.assert_allclose(got, 0.5 * sum(parts), rtol=1e-12)
