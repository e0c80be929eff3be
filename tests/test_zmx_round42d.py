"""Round 42d (real lens files): Edmund Optics stock-lens files in ASCII, and a fixed stop
smaller than the beam of the stated entrance pupil diameter.

* Three real files (tests/data/zmx42d/SOURCES.md): two written by OpticStudio 17.5
  (``VERS 171115``; an N-SF11 plano-convex and an N-BK7 plano-concave lens whose image,
  ``DISZ -52.3``, is virtual), each surface block holding ``FIMP`` and an empty line, and one
  by OpticStudio 21.2 (an N-BK7 even asphere, CRLF line ends, 24 ``WAVM`` lines of which
  ``FTYP`` makes one active, ``BLNK``/``TOL``/``MNUM``/``MOFF`` after the surfaces). All
  three open, without a warning, and trace as optiland 0.6.3 does.
* Two of them state an EPD whose beam is wider than the stop's clear aperture (EPD 12.5 mm,
  ``CLAP 0 5.75`` on the stop: a 6.25 mm beam; EPD 25, ``CLAP 0 12``). Zemax keeps the EPD
  and lets the fixed stop vignette; jaxlens does the same, and now says so: the report's
  notes give the working EPD (``jaxlens.analysis.stop_clip``), and so does a JSON lens whose
  stop has a fixed semi-diameter (the Cooke triplet with a 1 mm stop under its 3.8 mm beam).

References: tests/data/zmx42d/optiland_reference.json, written by ``tools/zmx42d_reference.py``
(optiland's own .zmx reader, every medium set to the index computed from the catalog's
formula in numpy; the paraxial marginal ray's height at the stop).
"""

import copy
import dataclasses
import json
import os
import warnings

import equinox as eqx
import jax
import numpy as np
import pytest
from helpers import image_xy, load_recording

import jaxlens as jl
from jaxlens.analysis import stop_clip
from jaxlens.analysis.report import report_data
from jaxlens.imaging import sampling
from jaxlens.io import lensfile, zmx

jax.config.update("jax_enable_x64", True)

HERE = os.path.dirname(__file__)
DATA = os.path.join(HERE, "data")
with open(os.path.join(DATA, "zmx42d", "optiland_reference.json")) as fh:
    REF = json.load(fh)
FILES = sorted(REF["files"])
COOKE = os.path.join(os.path.dirname(HERE), "jaxlens", "data", "lenses", "cooke_triplet.json")


def _load(name, **kw):
    lens, caught = load_recording(os.path.join(DATA, "zmx42d", name), **kw)
    return lens, [str(w.message) for w in caught]


def _text(name):
    with open(os.path.join(DATA, "zmx42d", name)) as fh:
        return fh.read()


def _image_xy(lens, ref, wl):
    """jaxlens's image intercepts (x, y) of the reference's rays (NaN where lost)."""
    return image_xy(lens, ref["fields_deg"], ref["epd"], REF["pupil"],
                    REF["launch_mm_before_surface_1"], wl)


@pytest.mark.parametrize("name", FILES)
def test_edmund_files_open_and_trace_as_optiland_does(name):
    lens, caught = _load(name, strict=True)
    assert caught == []
    ref = REF["files"][name]
    assert float(lens.epd) == ref["file_epd"]
    assert lens.stop == ref["stop_surface"] - 1
    assert float(lens.image_z()) == pytest.approx(ref["image_z_from_surface_1"], abs=1e-12)
    worst = 0.0
    for wl in ref["wavelengths"]:
        key = repr(float(wl))
        n = [abs(float(v)) for v in lens.indices(wl)][1:]
        np.testing.assert_allclose(n, ref["indices"][key], rtol=2e-15, atol=0)
        efl = float(jl.paraxial_data(lens, wl).efl_image_space)
        assert efl == pytest.approx(ref["efl"][key], rel=1e-12)
        for got, want in zip(_image_xy(lens, ref, wl), ref["rays"][key], strict=True):
            want = np.array([[np.nan, np.nan] if w is None else w for w in want])
            assert np.array_equal(np.isnan(got[:, 0]), np.isnan(want[:, 0]))
            worst = max(worst, float(np.nanmax(np.abs(got - want))))
    assert worst <= 1e-12, worst  # mm at the image surface (measured: 1.1e-14)


def test_what_the_files_hold_is_read():
    text = _text("optictrace_edmund_38398.zmx")
    assert "  FIMP \n\n  CURV" in text  # an empty line inside each surface block
    lens, _ = _load("optictrace_edmund_38398.zmx")
    assert lens.materials[0].name == "N-SF11" and lens.materials[0].catalog == "SCHOTT"
    # FTYP announces 1 field and 1 wavelength of the 24 WAVM lines (the rest: 0.55 µm).
    asph, _ = _load("raysim_edmund_16979.zmx")
    assert [float(w) for w in asph.wavelengths] == [0.5876]
    assert [float(f) for f in asph.fields] == [0.0]
    assert type(asph.surfaces[0]).__name__ == "EvenAsphere"
    assert float(asph.surfaces[0].k) == -0.72735066691296302
    # The negative lens's image is virtual: the image surface 48.8 mm before surface 1.
    neg, _ = _load("optictrace_edmund_68001.zmx")
    assert float(neg.image_z()) == pytest.approx(3.5 - 52.307642959813563, abs=1e-12)


# ---------------------------------------------------------------------------- the stop


@pytest.mark.parametrize("name, radius", [("optictrace_edmund_38398.zmx", 5.75),
                                          ("optictrace_edmund_68001.zmx", 12.0)])
def test_a_clear_aperture_smaller_than_the_epd_beam_is_said(name, radius):
    lens, _ = _load(name)
    ref = REF["files"][name]
    beam = ref["marginal_height_at_stop"]  # optiland's: the stop is surface 1, so EPD/2
    assert beam == 0.5 * ref["file_epd"]
    c = stop_clip.stop_clipping(lens)
    assert (c.stop_surface, c.stop_radius) == (1, radius)
    assert c.beam_radius == pytest.approx(beam, rel=1e-14)
    working = ref["file_epd"] * radius / beam  # 11.5 and 24 mm
    assert c.working_epd == pytest.approx(working, rel=1e-14)
    assert float(lens.epd) == ref["file_epd"]  # the stated EPD is kept, as in Zemax
    # The real on-axis rays agree: the stop on surface 1 passes exactly the working beam
    # (surface 2's own clear aperture opened, which clips the diverging beam of 68001).
    h = 0.5 * working
    o = np.array([[0.0, y, -5.0] for y in (0.999 * h, 1.001 * h)])
    only_stop = eqx.tree_at(lambda m: m.surfaces[1].semi_diameter, lens, np.inf)
    res = jl.trace(only_stop, jl.Rays(o, np.tile([0.0, 0.0, 1.0], (2, 1)), 0.5876))
    assert np.asarray(res.valid).tolist() == [True, False]
    note = stop_clip.note(lens)
    assert note == [f"the stop (surface 1, semi-diameter {radius:g} mm) clips the EPD beam "
                    f"({beam:g} mm high at the stop: real rim ray, 0.5876 um): working EPD "
                    f"{working:g} mm, not the stated {ref['file_epd']:g} mm; every field's "
                    f"beam is clipped there (Zemax keeps the EPD and lets a fixed stop "
                    f"vignette)"]


def test_a_stop_as_wide_as_the_beam_clips_nothing():
    # DIAM 12.5 fixed with FLAP on the stop, EPD 25: the beam just fills it.
    lens, _ = _load("raysim_edmund_16979.zmx")
    assert float(lens.surfaces[0].semi_diameter) == 12.5
    assert stop_clip.stop_clipping(lens) is None and stop_clip.note(lens) == []


def _cooke(stop_semi_diameter):
    with open(COOKE) as fh:
        spec = json.load(fh)
    for s in spec["surfaces"]:
        if s.get("is_stop"):
            s["semi_diameter"] = stop_semi_diameter
    return lensfile.lens_from_dict(spec, source="cooke_triplet.json")


def test_a_json_stop_smaller_than_the_beam_keeps_the_epd_and_the_report_says_so():
    ref = REF["cooke_triplet"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: real files do this
        lens = _cooke(1.0)
        data = report_data(lens)
    assert float(lens.epd) == ref["epd"] == data["epd"]
    c = stop_clip.stop_clipping(lens)
    assert c.stop_surface == ref["stop_surface"] == data["stop_surface"] == 4
    # Paraxial aiming (the default) launches the rim ray through the paraxial entrance
    # pupil's rim: optiland's real ray meets the stop 3.8611 mm high (paraxially 3.8046).
    assert (lens.aim, c.beam_ray) == ("paraxial", "real")
    assert c.beam_radius == pytest.approx(ref["real_rim_ray_height_at_stop"], rel=1e-12)
    # The working EPD: the pupil radius whose real ray meets the stop's rim (optiland's rays,
    # bisected): 2.6260 mm, between 10 · 1/3.8611 = 2.5899 and 10 · 1/3.8046 = 2.6284.
    working = ref["working_epd_1mm_stop_real_rays"]
    assert c.working_epd == pytest.approx(working, rel=1e-12)
    assert round(working, 4) == 2.6260
    said = [n for n in data["notes"] if n.startswith("the stop (surface 4")]
    assert said == [f"the stop (surface 4, semi-diameter 1 mm) clips the EPD beam (3.8611 mm "
                    f"high at the stop: real rim ray, 0.587562 um): working EPD "
                    f"{working:.6g} mm, not the stated 10 mm; every field's beam is clipped "
                    f"there (Zemax keeps the EPD and lets a fixed stop vignette)"]
    # The text report prints it among its notes.
    from jaxlens.analysis.report import format_report
    assert f"Note: {said[0]}" in format_report(data, lens)
    # Real aiming fills the paraxial stop height: optiland's paraxial marginal ray, 3.8046.
    aimed = stop_clip.stop_clipping(dataclasses.replace(lens, aim="real"))
    assert aimed.beam_ray == "paraxial"
    assert aimed.beam_radius == pytest.approx(ref["marginal_height_at_stop"], rel=1e-12)
    assert aimed.working_epd == pytest.approx(10.0 / ref["marginal_height_at_stop"], rel=1e-12)
    # A stop between the two heights clips the paraxially aimed beam only.
    between = _cooke(3.83)
    w = stop_clip.stop_clipping(between).working_epd
    rim = sampling.stop_radius(dataclasses.replace(between, epd=np.asarray(w)), "real")
    assert float(rim) == pytest.approx(3.83, rel=1e-12) and 9.9 < w < 10.0
    assert stop_clip.note(dataclasses.replace(between, aim="real")) == []
    # A stop wider than the beam, or none: no note.
    assert stop_clip.note(_cooke(4.0)) == [] and stop_clip.note(_cooke("inf")) == []


def test_a_centred_circular_aperture_on_the_stop_counts_and_a_traced_lens_is_left_alone():
    lens = _cooke("inf")
    ap = jl.Aperture("circle", 1.9, 1.9)
    clipped = _with_aperture(lens, ap)
    c = stop_clip.stop_clipping(clipped)
    assert c.stop_radius == 1.9
    rim = sampling.stop_radius(dataclasses.replace(lens, epd=np.asarray(c.working_epd)), "real")
    assert float(rim) == pytest.approx(1.9, rel=1e-12)
    # A decentered one passes no centred beam: not compared.
    off = _with_aperture(lens, jl.Aperture("circle", 1.9, 1.9, decenter_y=0.5))
    assert stop_clip.stop_clipping(off) is None
    # Under jit (a design loop) nothing is computed.
    seen = []

    def inside(m):
        seen.append(stop_clip.stop_clipping(m))
        return m.epd

    jax.jit(inside)(_cooke(1.0))
    assert seen == [None]


def _with_aperture(lens, ap):
    out = copy.copy(lens)  # apertures are static structure
    object.__setattr__(out, "apertures", ((lens.stop, ap),))
    return out


def test_an_epd_whose_beam_just_fills_the_stop_clap_is_not_noted():
    text = _text("optictrace_edmund_38398.zmx")
    lens = zmx.loads(text.replace("ENPD 12.5", "ENPD 11.5"))  # the beam now fills the stop
    assert stop_clip.note(lens) == []
