"""Round 45c (real lens files): eleven more public .zmx files, none in an earlier round's data
(tests/data/zmx45c/SOURCES.md names each source repository and path).

* Six Thorlabs stock-lens files of Zemax 12 (``VERS 120928``, ASCII, CRLF) from
  wagenadl/octave-wagenaarlab: two achromats (AC254-100-A, visible; AC508-075-B, near-IR
  N-LAK22/N-SF6HT at 0.7065–1.015 µm), a negative achromat whose image is virtual
  (ACN127-030-B, ``DISZ -31.96`` to the image), and two even aspheres at 0.78 µm
  (AL1210-A: OHARA's S-LAH64 found in the third ``GCAT`` catalog, eight ``PARM`` terms, a
  parabolic base ``CONI -1``; AL50100-A: N-BK7, ``CONI -0.575``), both with
  ``ENVD 20 1 1`` (indices adjusted to 20 °C and 1 atm: the catalogs' own conditions);
  and an aspheric condenser whose stop is its flat back face, behind the lens (ACL108-A:
  ``ENPD 9.0`` is the stop's image through the B270 asphere; its ``GLAS B270 0 0 1.5 4.0E+1``
  carries Zemax's placeholder nd and Vd, which claim nothing and draw no warning).
* The same Thorlabs series from DCC-Lab/RayTracing (AC254-125-A, N-BK7/N-SF5,
  ``VERS 120928 106``, a ``MAZH`` line).
* A 19-surface microscope-objective form from tangericm/optical-design written by a
  program, not OpticStudio: ``FNUM 0.9 0`` (image-space F/#) as the system aperture, no
  ``DIAM`` lines, three-value ``XFLN``/``YFLN``, a glass of another catalog than the file's
  (``J-LLF2``, HIKARI, under ``GCAT SCHOTT``: a warning naming it, refused in strict mode),
  and no line end after the last line; and the same program's OCT scan lens (two
  N-BK7/N-SF5 doublets at 0.8–0.9 µm, the stop 27.6 mm before them) with no ``GCAT`` line at
  all: its glasses are SCHOTT's, Zemax's default catalog, with no warning.

* Two program-written sample files from VendettaMask/opticalsystem (``VERS 190513 42 0``,
  ``COMM`` on every surface, ``GLAS AIR`` on air spaces and on the image surface, ``DIAM`` on
  the object): a finite conjugate (``FTYP 1``: object heights 0, 10, 20 mm of an object
  120 mm before the lens, an internal stop) and real image heights with x and y
  (``FTYP 3``, (1.5, 2) and (2.5, 4) mm).

All open; the reference numbers are optiland 0.6.3's own .zmx reading of each file with
every medium set to the catalog index computed in numpy (``tools/zmx45c_reference.py``).
One class was fixed (``jaxlens.io.zmx_system``): a real-image-height field (``FTYP 3``) with
ray aiming off is that of the chief ray Zemax traces then, through the paraxial entrance
pupil's centre (optiland 0.6.3's real-image-height field takes the same ray); jaxlens aimed
it at the stop's centre, 0.02° off for a double Gauss's 12 mm height (``dg50_ftyp3.zmx``).

A public file that only looks like a .zmx (piack97/zemax-lens-analyzer's
``tests/data/sample_lens.zmx``: ``XFLN 1 0``/``XFLN 2 5`` as field rows, no ``SURF 0``) is
refused naming the line, and kept here as text.
"""

import hashlib
import json
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
DATA = os.path.join(HERE, "data", "zmx45c")
with open(os.path.join(DATA, "optiland_reference.json")) as fh:
    REF = json.load(fh)
FILES = sorted(REF["files"])
SHA256 = {  # the files as shipped: the index's text, CRLF restored (SOURCES.md)
    "dcclab_AC254-125-A.zmx": "c8f77d6df5b8e2b45886238003c7ce0be96b38cdfa53951d4dd3bb88bc018fbf",
    "tangericm_microscope-objective-60x.zmx":
        "d989358e150ab97b683943259affecd9acb27badd9ae605cfde795ccfc0b05ac",
    "tangericm_oct-semi-plossl-scan-lens.zmx":
        "1ae8d67f60524340a5c0c2f38ef31d5b0742ca893886997fc4f73eeb9701e541",
    "thorlabs_AC254-100-A.zmx": "2a4949b2a9b59902fd48888084f310286e6dde7a3277e7db52408021477a736e",
    "thorlabs_ACL108-A.zmx": "58b6a7452c3143872bf495d8cd70df421ef014203f51f7a7e3a640934d27e40f",
    "thorlabs_AC508-075-B.zmx": "0ba7c4a228ef63f9f2e73541e4264d1067088c4cef04dae76d8db0b82b0ec60a",
    "thorlabs_ACN127-030-B.zmx": "bb98879b4636e103d92e1542077d0e4ce236c909037c8da2aaf819037bfc4f57",
    "thorlabs_AL1210-A.zmx": "3a6bc234050d2778afcffd1dcf510f2ab6e8ad898695116c069110863c6ad22d",
    "thorlabs_AL50100-A.zmx": "a4e251224576acd76344353c03e04362cb94cc56730a6f0e6b9b45f076535842",
    "vendettamask_finite-conjugate-macro.zmx":
        "84a88beec6a63e0ecaed479dd7595ba148b0985350ab7f623b31abaeef48de8c",
    "vendettamask_real-image-height-demo.zmx":
        "10b2105239d33df43d20fe779b9d43c59c814712b8cb65090dcc3c8f5ded9352",
}
CONJUGATES = sorted(REF["conjugates"])


def _load(name, **kw):
    lens, caught = load_recording(os.path.join(DATA, name), **kw)
    return lens, [str(w.message) for w in caught]


def _image_xy(lens, ref, wl):
    """jaxlens's image intercepts (x, y) of the reference's rays (NaN where lost)."""
    return image_xy(lens, ref["fields_deg"], ref["beam"], REF["pupil"],
                    REF["launch_mm_before_surface_1"], wl)


def test_the_files_are_the_sources_text():
    assert sorted(SHA256) == sorted(FILES + CONJUGATES)
    for name in SHA256:
        with open(os.path.join(DATA, name), "rb") as fh:
            raw = fh.read()
        assert hashlib.sha256(raw).hexdigest() == SHA256[name]
        text = raw.decode("utf-8")
        assert text.startswith("VERS ")
        # Zemax 12's files end their lines in CRLF; the program-written form in LF, without
        # one after its last line.
        if name.startswith(("tangericm", "vendettamask")):
            assert "\r" not in text
            assert text.endswith("\n") == name.startswith("vendettamask")
        else:
            assert text.count("\n") == text.count("\r\n") and text.endswith("\r\n")


@pytest.mark.parametrize("name", FILES)
def test_files_open_and_trace_as_optiland_does(name):
    ref = REF["files"][name]
    foreign = ref["foreign"]
    lens, caught = _load(name, strict=not foreign)
    if foreign:  # J-LLF2 under GCAT SCHOTT: said, with the catalog taken
        assert len(caught) == 1 and "glass 'J-LLF2' is not in the file's catalogs" in caught[0]
        assert "using HIKARI J-LLF2" in caught[0]
    else:
        assert caught == []
    assert lens.stop == ref["stop_surface"] - 1
    assert float(lens.image_z()) == pytest.approx(ref["image_z_from_surface_1"], abs=1e-12)
    assert float(lens.primary_wavelength) == ref["primary"]
    for m in lens.materials:
        if getattr(m, "catalog", None) is not None:
            assert ref["glasses"][m.name] == m.catalog
    worst = 0.0
    for wl in ref["wavelengths"]:
        key = repr(float(wl))
        n = [abs(float(v)) for v in lens.indices(wl)][1:]
        np.testing.assert_allclose(n, ref["indices"][key], rtol=2e-15, atol=0)
        # FNUM: optiland sizes the pupil at each wavelength (see the tool's notes).
        check_first_order(jl.paraxial_data(lens, wl), ref["first_order"][key],
                          sizes=ref["aperture"] == "EPD" or wl == ref["primary"])
        assert float(lens.epd) == pytest.approx(ref["beam"], rel=1e-12)
        worst = max(worst, image_miss(_image_xy(lens, ref, wl), ref["rays"][key]))
    assert worst <= 1e-9, worst  # mm at the image surface


@pytest.mark.parametrize("name", CONJUGATES)
def test_object_and_real_image_heights_as_optiland_traces_them(name):
    """FTYP 1 (object heights of an object 120 mm before the lens) and FTYP 3 (real image
    heights, x and y): jaxlens's field angles are those of the reference (the ray from the
    object point to the paraxial entrance pupil's centre; the real chief ray that lands on the
    stated image point, solved on optiland's trace), and its real rays land where optiland's
    do."""
    ref = REF["conjugates"][name]
    lens, caught = _load(name, strict=True)
    assert caught == []
    assert lens.stop == ref["stop_surface"] - 1
    assert float(lens.image_z()) == pytest.approx(ref["image_z_from_surface_1"], abs=1e-12)
    np.testing.assert_allclose(np.asarray(lens.fields), ref["field_angles_deg"], rtol=0,
                               atol=1e-10)
    fo = ref["first_order_primary"]
    p = jl.paraxial_data(lens)
    assert float(p.efl_image_space) == pytest.approx(fo["f2"], rel=1e-12)
    assert float(p.entrance_pupil_z) == pytest.approx(fo["EPL"], abs=1e-10)
    assert float(p.entrance_pupil_diameter) == pytest.approx(fo["EPD"], rel=1e-12)
    r, launch, pupil = 0.5 * fo["EPD"], REF["launch_mm_before_surface_1"], REF["pupil"]
    worst = 0.0
    for wl in ref["wavelengths"]:
        key = repr(float(wl))
        n = [abs(float(v)) for v in lens.indices(wl)][1:]
        np.testing.assert_allclose(n, ref["indices"][key], rtol=2e-15, atol=0)
        for k, want in enumerate(ref["rays"][key]):
            if ref["kind"] == "object":
                z0 = ref["object_z_from_surface_1"]
                o = np.array([[0.0, ref["fields"][k], z0]] * len(pupil))
                d = np.array([[px * r, py * r, fo["EPL"]] for px, py in pupil]) - o
            else:
                t = np.tan(np.radians(ref["field_angles_deg"][k]))
                d = np.tile([t[0], t[1], 1.0], (len(pupil), 1))
                d = d / np.linalg.norm(d, axis=1, keepdims=True)
                o = np.array([[px * r, py * r, 0.0] for px, py in pupil]) + launch * d
            d = d / np.linalg.norm(d, axis=1, keepdims=True)
            with jax.disable_jit():
                res = jl.trace(unclipped(lens), jl.Rays(o, d, wl))
            got = np.where(np.asarray(res.valid)[:, None], np.asarray(res.origin)[:, :2], np.nan)
            want = np.array([[np.nan, np.nan] if w is None else w for w in want])
            assert np.array_equal(np.isnan(got[:, 0]), np.isnan(want[:, 0]))
            worst = max(worst, float(np.nanmax(np.abs(got - want))))
    assert worst <= 1e-9, worst  # mm at the image surface
    if ref["kind"] == "image":  # the chief rays land on the stated points
        for f, h in zip(np.asarray(lens.fields), ref["fields"], strict=True):
            t = np.tan(np.radians(f))
            d = np.array([[t[0], t[1], 1.0]]) / math.hypot(t[0], t[1], 1.0)
            with jax.disable_jit():
                res = jl.trace(unclipped(lens), jl.Rays(launch * d, d, ref["primary"]))
            np.testing.assert_allclose(np.asarray(res.origin)[0, :2], h, rtol=0, atol=1e-9)


def test_design_values_the_files_state():
    # Each Thorlabs NAME states the focal length (mm) at its design wavelength.
    for name, f in (("thorlabs_AC254-100-A.zmx", 100.0), ("dcclab_AC254-125-A.zmx", 125.0),
                    ("thorlabs_AC508-075-B.zmx", 75.0), ("thorlabs_ACN127-030-B.zmx", -30.0),
                    ("thorlabs_AL1210-A.zmx", 10.0), ("thorlabs_AL50100-A.zmx", 100.0),
                    ("thorlabs_ACL108-A.zmx", 8.0)):
        lens, _ = _load(name)
        efl = float(jl.paraxial_data(lens).efl_image_space)
        assert abs(efl - f) < 0.3, (name, efl)
    # AL1210-A: NA 0.545 in the NAME, over the file's 11.25 mm EPD at f = 10 mm.
    asph, _ = _load("thorlabs_AL1210-A.zmx")
    assert type(asph.surfaces[0]).__name__ == "EvenAsphere"
    assert float(asph.surfaces[0].k) == -1.0
    p = jl.paraxial_data(asph)
    assert 5.625 / float(p.efl_image_space) == pytest.approx(0.5624, abs=1e-3)
    assert asph.materials[0].name == "S-LAH64" and asph.materials[0].catalog == "OHARA"
    # ACN127-030-B: a virtual image 31.96 mm before the last surface.
    neg, _ = _load("thorlabs_ACN127-030-B.zmx")
    assert float(neg.image_z()) == pytest.approx(1.5 + 2.5 - 31.95775200249, abs=1e-12)
    # ACL108-A: the stop (surface 3) 5.8 mm behind the asphere; the entrance pupil, its
    # image, is 9 mm across (ENPD) and lies behind surface 1.
    cond, _ = _load("thorlabs_ACL108-A.zmx")
    p = jl.paraxial_data(cond)
    assert cond.stop == 2 and float(cond.epd) == 9.0
    assert float(p.entrance_pupil_diameter) == pytest.approx(9.0, rel=1e-12)
    assert float(p.entrance_pupil_z) > 5.0
    assert cond.materials[1].name == "B270" and cond.materials[1].catalog == "SCHOTT"
    # The microscope form: FNUM 0.9 0 is EFL/EPD at the primary wavelength.
    mo, _ = _load("tangericm_microscope-objective-60x.zmx")
    p = jl.paraxial_data(mo)
    assert float(p.efl_image_space) / float(mo.epd) == pytest.approx(0.9, rel=1e-12)
    assert [float(f) for f in np.ravel(mo.fields)][-1] == 1.0


def test_the_look_alike_file_is_refused_naming_the_line(tmp_path):
    # piack97/zemax-lens-analyzer tests/data/sample_lens.zmx (92cae1a6…): 279 characters.
    text = ("! Minimal sequential lens\nENPD 20\nWAVL 0.4861 0.5876 0.6563\nXFLN 1 0\n"
            "YFLN 1 0\nXFLN 2 5\nYFLN 2 0\nSTOP 2\nSURF 1\nTYPE STANDARD\nCURV 0.02\nDISZ 5\n"
            "GLAS BK7\nDIAM 12\nCONI 0\nSURF 2\nTYPE STANDARD\nCURV -0.02\nDISZ 40\nGLAS AIR\n"
            "DIAM 12\nCONI 0\nSURF 3\nTYPE STANDARD\nCURV 0\nDISZ 0\nDIAM 15\nCONI 0\n")
    assert len(text) == 279
    path = tmp_path / "sample_lens.zmx"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"sample_lens\.zmx:6: XFLN given twice"):
        jl.load(str(path))


@pytest.mark.parametrize("name", sorted(FILES + CONJUGATES))
def test_files_round_trip_through_json_and_zmx(name, tmp_path):
    """Each file's lens written as JSON and as .zmx and read back is the same lens, bit for
    bit (the J-LLF2 glass of another catalog is written with its catalog, and read back
    without a warning)."""
    from helpers import json_round_trip

    lens, _ = _load(name)
    json_round_trip(lens, tmp_path)
    path = tmp_path / "round_trip.zmx"
    jl.save(lens, path)
    again, caught = _load(str(path))
    assert caught == []
    assert jax.tree_util.tree_structure(again) == jax.tree_util.tree_structure(lens)
    for a, b in zip(jax.tree_util.tree_leaves(again), jax.tree_util.tree_leaves(lens),
                    strict=True):
        np.testing.assert_array_equal(np.asarray(a, np.float64), np.asarray(b, np.float64))


def test_real_image_heights_with_ray_aiming_off_take_zemax_s_chief_ray():
    """FTYP 3 with ray aiming off (no RAIM line) and the stop between the groups of a double
    Gauss (tests/data/zmx45c/dg50_ftyp3.zmx, written by the reference tool after
    VendettaMask's double-gauss-50mm): the field of each real image height is that of the
    chief ray Zemax traces with aiming off, through the paraxial entrance pupil's centre,
    as optiland 0.6.3's own real-image-height field takes it. jaxlens aimed that chief ray
    at the stop's centre: 3.2336° and 6.2991° for 6 and 12 mm where optiland has 3.2361°
    and 6.3186°, and at jaxlens's own fields (its rays aimed as the file says) the chief
    ray landed 5 and 40 µm short of the stated heights."""
    ref = REF["dg50_ftyp3"]
    lens, caught = _load("dg50_ftyp3.zmx", strict=True)
    assert caught == [] and lens.aim == "paraxial" and lens.stop == 4
    p = jl.paraxial_data(lens)
    assert float(p.entrance_pupil_z) == pytest.approx(ref["EPL"], abs=1e-10)
    assert float(p.efl_image_space) == pytest.approx(ref["f2"], rel=1e-12)
    np.testing.assert_allclose(np.asarray(lens.fields), ref["angles_deg"], rtol=0, atol=1e-9)
    # The chief rays (through the paraxial pupil's centre) land on the stated heights and
    # cross the stop off its centre where optiland's do (the pupil aberration).
    from jaxlens.tracing.forward import trace_path

    for f, h, y_stop in zip(np.asarray(lens.fields), ref["heights"], ref["stop_y"],
                            strict=True):
        t = math.tan(math.radians(f))
        d = np.array([[0.0, t, 1.0]]) / math.hypot(t, 1.0)
        o = np.array([[0.0, 0.0, float(p.entrance_pupil_z)]]) - 30.0 * d
        with jax.disable_jit():
            path = trace_path(unclipped(lens), jl.Rays(o, d, 0.5875618))
        xyz = np.asarray(path.origin)[:, 0]
        assert abs(xyz[-1, 1] - h) < 1e-9 and abs(xyz[-1, 0]) < 1e-12
        assert xyz[4, 1] == pytest.approx(y_stop, abs=1e-9)


def test_real_image_heights_of_a_finite_object_with_ray_aiming_off(tmp_path):
    """The finite-conjugate file with its fields made real image heights (0, −1.5, −3 mm;
    no RAIM line): each field's object point, the one whose ray through the paraxial
    entrance pupil's centre lands on the height, is optiland's (its real-image-height field
    of the same copy, whose heights +1.5 and +3 mm mirror the file's)."""
    ref = REF["fc_ftyp3"]
    with open(os.path.join(DATA, "vendettamask_finite-conjugate-macro.zmx")) as fh:
        text = fh.read()
    for old, new in ref["lines"]:
        text = text.replace(old, new)
    path = tmp_path / "fc_ftyp3.zmx"
    path.write_text(text)
    lens, caught = _load(str(path), strict=True)
    assert caught == [] and lens.aim == "paraxial"
    zep = float(jl.paraxial_data(lens).entrance_pupil_z)
    depth = float(lens.object_distance)
    # The object point of field θ: −tan θ·(z_ep + depth) (sampling.object_point).
    heights = -np.tan(np.radians(np.asarray(lens.fields)[1:])) * (zep + depth)
    np.testing.assert_allclose(heights, -np.asarray(ref["object_y"]), rtol=0, atol=1e-9)
