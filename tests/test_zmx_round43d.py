"""Round 43d (real lens files): three more stock-lens files, as OpticStudio saves them (UTF-16LE
with a byte-order mark, CRLF line ends), byte for byte from the rayoptics 0.9.8 wheel
(tests/data/zmx43d/SOURCES.md; the wheel's RECORD hashes match).

* Thorlabs 354710-C (OpticStudio 14, ``VERS 140124``): a molded D-ZK3M even asphere of
  LightPath's catalog at 1.55 µm (``GCAT LIGHTPATH SCHOTT``) and a BK7 window. Its ``GLAS``
  line carries stale numbers (nd 1.601, Vd 50.28) beside LightPath's catalog glass (nd
  1.58642, Vd 60.71): the reader warns and takes the catalog's glass, and with it the EFL at
  1.55 µm is the file's NAME, f = 1.49 mm, to 1e-11.
* Thorlabs ACL3026U (OpticStudio 15, ``VERS 150514``): a B270 aspheric condenser whose stop is
  its second surface behind a flat dummy, EPD 27 mm under a fixed 15 mm semi-diameter.
* Edmund 55278 (``VERS 171115``, written in UTF-16 here where round 42d's Edmund files were
  ASCII): two SF5/BK7 achromats face to face, ``DBDT``, ``MEMA``/``MAZH``/``FLAP`` lines and
  no ``TYPE`` lines; its EFL is the ``DBDT`` line's 52.24 mm.

All three open (strict), with optiland 0.6.3's first-order data and real rays
(tests/data/zmx43d/optiland_reference.json, ``/work/optenv/bin/python tools/zmx43d_reference.py``:
optiland's own .zmx reader, every medium the index of the catalog formula computed in numpy).
"""

import hashlib
import math
import os

import jax
import numpy as np
import pytest
from helpers import check_first_order, image_miss, image_xy, load_recording

import jaxlens as jl
from jaxlens.optics.lens import unclipped

jax.config.update("jax_enable_x64", True)

HERE = os.path.dirname(__file__)
DATA = os.path.join(HERE, "data", "zmx43d")
with open(os.path.join(DATA, "optiland_reference.json")) as fh:
    import json

    REF = json.load(fh)
FILES = sorted(REF["files"])
SHA256 = {  # the files as the rayoptics 0.9.8 wheel holds them (its RECORD agrees)
    "rayoptics_354710-C.zmx": "721ab4b62f3bb9f1fc8192191964240f7e76bca9003c70b8d4bba6ad371293a6",
    "rayoptics_ACL3026U.zmx": "f2f393c1422ced500c37125a9cb441f05982cc6c42acd27d94641a5b08b9f226",
    "rayoptics_zmax_55278.zmx": "c148e9ce20e4216004e5a6f66a9d36da232c277ff4201e7612d01475435fcc07",
}


def _load(name, **kw):
    lens, caught = load_recording(os.path.join(DATA, name), **kw)
    return lens, [str(w.message) for w in caught]


def _image_xy(lens, ref, wl):
    """jaxlens's image intercepts (x, y) of the reference's rays (NaN where lost)."""
    return image_xy(lens, ref["fields_deg"], ref["beam"], REF["pupil"],
                    REF["launch_mm_before_surface_1"], wl)


def test_the_files_are_the_published_bytes_in_utf16():
    for name in FILES:
        with open(os.path.join(DATA, name), "rb") as fh:
            raw = fh.read()
        assert hashlib.sha256(raw).hexdigest() == SHA256[name]
        assert raw[:2] == b"\xff\xfe"  # UTF-16LE byte-order mark
        assert raw.decode("utf-16").startswith("VERS ") and "\r\n" in raw.decode("utf-16")


@pytest.mark.parametrize("name", FILES)
def test_stock_lens_files_open_and_trace_as_optiland_does(name):
    lens, caught = _load(name, strict=True)
    ref = REF["files"][name]
    if name == "rayoptics_354710-C.zmx":  # the GLAS line's stale nd and Vd, said
        assert len(caught) == 1 and "GLAS D-ZK3M gives nd 1.601" in caught[0]
        assert "catalog LIGHTPATH has nd 1.58642" in caught[0]
    else:
        assert caught == []
    assert float(lens.epd) == ref["file_epd"]
    assert lens.stop == ref["stop_surface"] - 1
    assert float(lens.image_z()) == pytest.approx(ref["image_z_from_surface_1"], abs=1e-12)
    for m in lens.materials:
        if getattr(m, "catalog", None) is not None:
            assert ref["glasses"][m.name] == m.catalog
    worst = 0.0
    for wl in ref["wavelengths"]:
        key = repr(float(wl))
        n = [abs(float(v)) for v in lens.indices(wl)][1:]
        np.testing.assert_allclose(n, ref["indices"][key], rtol=2e-15, atol=0)
        check_first_order(jl.paraxial_data(lens, wl), ref["first_order"][key])
        worst = max(worst, image_miss(_image_xy(lens, ref, wl), ref["rays"][key]))
    assert worst <= 1e-12, worst  # mm at the image surface


def test_design_values_the_files_state():
    # 354710-C: NAME "f=1.49mm" at the file's 1.55 µm, with LightPath's D-ZK3M.
    asph, _ = _load("rayoptics_354710-C.zmx")
    assert [float(w) for w in asph.wavelengths] == [1.55]
    assert float(jl.paraxial_data(asph, 1.55).efl_image_space) == pytest.approx(1.49, abs=1e-9)
    assert type(asph.surfaces[0]).__name__ == "EvenAsphere"
    # 55278: DBDT 0 55278 5.224E+01 (the EFL, mm) at the primary wavelength (PWAV 2).
    pair, _ = _load("rayoptics_zmax_55278.zmx")
    assert float(pair.primary_wavelength) == 0.5876
    efl = float(jl.paraxial_data(pair).efl_image_space)
    assert round(efl, 2) == 52.24
    # ACL3026U: the stop is surface 2 (a fixed 15 mm semi-diameter), a dummy plane before.
    cond, _ = _load("rayoptics_ACL3026U.zmx")
    assert cond.stop == 1 and float(cond.surfaces[1].semi_diameter) == 15.0
    assert float(cond.surfaces[0].c) == 0.0 and cond.materials[0].name == "air"


# ------------------------------------------- crossing rims: US08427765's surfaces 7 and 8


def _crossing_path(lens, f, heights, wl):
    from jaxlens.tracing.forward import trace_path

    t = math.tan(math.radians(f))
    d = np.array([0.0, t, 1.0]) / math.sqrt(1 + t * t)
    h = np.asarray(heights, float)
    o = np.stack([0 * h, h, np.full_like(h, REF["crossing_us08427765"]
                                         ["launch_mm_before_surface_1"])], -1)
    rays = jl.Rays(o, np.tile(d, (len(h), 1)), wl)
    with jax.disable_jit():
        return trace_path(unclipped(lens), rays), jl.trace(lens, rays)


def test_crossing_rims_go_back_to_the_nearest_root():
    """US08427765-1 (tests/data/zmx): surfaces 7 (R −53.6, semi-diameter 7.0) and 8 (R −37.5,
    7.53), 0.22 mm apart, cross 7.325 mm off the axis, between their clear apertures.

    With the file's apertures the crossing never matters: every ray that passes surface 7 is
    inside 7.0 mm, where surface 8 lies ahead of it, and meets it ahead (t > 0); jaxlens's
    and optiland's traces pass the same rays. Without apertures (the unclipped lens used to
    aim rays and trace reference rays), a ray that meets surface 7 beyond the crossing finds
    surface 8 only behind it, on Zemax's negative propagation; going back along its line it
    meets surface 8 first at the nearer root. jaxlens took the first root along the whole
    line, up to 53 mm back and across the axis (y = −36.8 mm for a 20° ray); it now takes
    the nearer one, as optiland does, except on a ray that leaves surface 7 almost
    perpendicular to the axis (optiland's fallback then takes the root nearer the vertex
    plane, 21 mm back; jaxlens the one 1.2 mm back)."""
    ref = REF["crossing_us08427765"]
    lens = jl.load(os.path.join(HERE, "data", "zmx", "rayoptics_US08427765-1.ZMX"))
    went_back = both = 0
    for wl in ref["wavelengths"]:
        rows = ref["rays"][repr(float(wl))]
        for f, want, passes in zip(ref["fields_deg"], rows["free"], rows["clipped_passes"],
                                   strict=True):
            path, clipped = _crossing_path(lens, f, ref["heights"], wl)
            assert np.asarray(clipped.valid).tolist() == passes
            p, v = np.asarray(path.origin), np.asarray(path.valid)
            for k, w in enumerate(want):
                if w is None:
                    assert not v[-1, k]
                    continue
                leave = np.asarray(path.direction)[6, k]
                if abs(leave[2]) < 0.05:  # the near-perpendicular ray (see the docstring)
                    continue
                both += 1
                # Surface 8 is surface index 7; t < 0 there: the ray went back to it.
                went_back += float((p[7, k] - p[6, k]) @ leave) < 0
                np.testing.assert_allclose(p[7, k, 1:], w["surface_8"], rtol=0, atol=1e-9)
                np.testing.assert_allclose(p[-1, k, :2], w["image"], rtol=0, atol=1e-9)
    assert both >= 60 and went_back >= 30, (both, went_back)
