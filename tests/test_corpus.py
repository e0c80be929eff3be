"""Real ``.zmx`` files from optiland's and ray-optics' test folders (tests/data/zmx/, sources
and licences in its README.md): each loads or is refused with its reason and line, the
image-space EFL equals optiland's (recorded numbers, optiland 0.6.3), and ``load → save →
load`` is exact. With optiland installed, optiland reads the files jaxlens writes with the
same EFL, clipping radii and image-space medium."""

import contextlib
import io
import math
import os
import re
import warnings

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx

DATA = os.path.join(os.path.dirname(__file__), "data", "zmx")
D_LINE = 0.5875618

# optiland 0.6.3 ``optic.paraxial.f2()`` of each file (n′/Φ at the primary wavelength), where
# optiland reads the same glasses. Ex27's model glasses (___BLANK) are given at the d line
# only and the two programs extend them to its 0.55 µm differently (index 4e-6 and 6e-5
# apart), so its value is optiland's at the d line, where both take nd exactly.
OPTILAND_EFL = {
    # optiland keeps a file's lens units: this file is in inches (UNIT IN), its f2 is
    # 0.7300916303992044 in, and jaxlens works in mm.
    "optiland_circular_aperture_example_with_aperture.zmx": (0.7300916303992044 * 25.4, None),
    "optiland_lens1.zmx": (24.990670494950276, None),
    "optiland_lens_floa.zmx": (20.210667479300504, None),
    "optiland_lens_thorlabs_iso_8859_1.zmx": (14.995572148674018, None),
    "optiland_thorlabs_lj1598l1.zmx": (3.9086805451437723, None),
    "rayoptics_HoO-V2C18Ex03.zmx": (80.09343065693426, None),
    "rayoptics_HoO-V2C18Ex27.zmx": (24.611594055334773, D_LINE),
    "rayoptics_HoO-V2C18Ex46.zmx": (305.00166666666667, None),
    "rayoptics_HoO-V2C18Ex66.zmx": (90.05187904998931, None),
    "rayoptics_US00583336-2-scaled.zmx": (49.38897584676335, None),
    "rayoptics_US05331467-1.zmx": (999.6369653778445, None),  # mirrors and an OBSC
    # Three off-axis mirrors with OBDC-decentered SQAP apertures (tests/test_zmx_round5.py).
    "rayoptics_US08011793-1_trimmed.zmx": (499.9996204043674, None),
    # Round 6 (tests/test_zmx_round6.py): an OHARA even asphere whose GLAS line names the
    # glass only, and Ex66 as OpticStudio 16 wrote it (PPAR pickups, GLCB lines, MEMA).
    "optiland_lens2.zmx": (22.499368205385874, None),
    "rayoptics_HoO-V2C18Ex66NEW.zmx": (90.05187904998931, None),
}

# What each file that loads is reported for (a ZmxWarning naming the line), if anything.
EXPECTED_WARNINGS = {
    # Its OpticStudio header lines IWDP 0 and EERA 0 0 0 … are read with the values seen in
    # real files (zmx_keywords.KNOWN_VALUES; test_zmx_keywords_more: other values are reported).
    # Its RAIM 1 (line 18) is read into Lens.aim "real" without a word.
    "optiland_lens_floa.zmx": [r":6: FTYP announces 3 fields, YFLN gives 1"],
    # HoO-V2C18Ex66 and US00583336 (RAIM 2) are read into Lens.aim "real_marginal" without a
    # word; US00583336's vignetting factors (line 22) into Lens.vignetting (test_vignetting).
}

# Files jaxlens cannot represent: the line and the reason.
REFUSED = {}  # US08427765-1 (GLAS L-TIM28_MOLD, GCAT RPO) opens from round 40a

# Files that load but optiland's EFL was not recorded for: the known answer instead. The
# off-axis parabola of zmax_37992 (R = 190.6 mm, its aperture decentered by OBDC 0 190.6,
# once refused) has f = R/2 = 95.3 mm.
KNOWN_EFL = {"rayoptics_zmax_37992.zmx": 1 / (2 * 5.246589716684155885E-03),
             # One curved surface and no glass: no power (tests/test_zmx_round5.py).
             "optiland_lens_offset_aperture.zmx": math.inf,
             # Two flat surfaces in air (round 6: FTYP makes 1 of its 5 WAVM lines active).
             "optiland_inactive_wavelengths.zmx": math.inf}

# Files checked in a test of their own (optiland 0.6.3 does not read their surface type).
CHECKED_ELSEWHERE = {"rayoptics_ASL5040-UV.zmx": "tests/test_qtype.py (QED_TYPE, Q-bfs)",
                     # Object-space telecentric, real image heights (round 38a): loads; its
                     # EFL has no independent reference yet.
                     "rayoptics_US05831776-1.zmx": "tests/test_zmx_round38a.py",
                     # RPO's molded L-TIM28 (round 40a): optiland has no RPO glass, so its
                     # rays are compared with the catalog's indices set in optiland.
                     "rayoptics_US08427765-1.ZMX": "tests/test_zmx_round40a.py"}


def _load(name, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lens = jl.load(os.path.join(DATA, name), **kw)
    return lens, [str(w.message) for w in caught if issubclass(w.category, zmx.ZmxWarning)]


def test_every_data_file_is_listed():
    names = {f for f in os.listdir(DATA) if f.lower().endswith(".zmx")}
    assert names == set(OPTILAND_EFL) | set(REFUSED) | set(KNOWN_EFL) | set(CHECKED_ELSEWHERE)


def test_off_axis_parabola_with_a_decentered_aperture(tmp_path):
    """zmax_37992: the mirror's CLAP with OBDC is a decentered circle (Lens.apertures); the
    EFL is the parabola's and the round trip keeps the aperture."""
    name = "rayoptics_zmax_37992.zmx"
    lens, caught = _load(name)
    assert caught == [] and lens.aim == "real"  # RAIM 1 (line 12): Lens.aim, no warning
    assert lens.apertures == ((2, jl.Aperture.circle(25.399999999999999, 0.0, 190.6)),)
    ours = float(jl.paraxial_data(lens).efl_image_space)
    assert abs(ours) == pytest.approx(KNOWN_EFL[name], rel=1e-9)
    jl.save(lens, tmp_path / "w.zmx")
    assert _load(tmp_path / "w.zmx")[0].apertures == lens.apertures


@pytest.mark.parametrize("name", sorted(OPTILAND_EFL))
def test_loads_with_optilands_efl(name):
    lens, caught = _load(name)
    expected = EXPECTED_WARNINGS.get(name, [])
    assert len(caught) == len(expected), caught
    for pattern, msg in zip(expected, caught, strict=True):
        assert re.search(pattern, msg), (pattern, msg)
        assert msg.startswith(os.path.join(DATA, name) + ":")
    efl, wavelength = OPTILAND_EFL[name]
    ours = float(jl.paraxial_data(lens, wavelength).efl_image_space)
    assert ours == pytest.approx(efl, rel=1e-9)


@pytest.mark.parametrize("name", sorted(OPTILAND_EFL))
def test_round_trip_is_exact(name, tmp_path):
    lens, _ = _load(name)
    out = tmp_path / "written.zmx"
    jl.save(lens, out)
    again, caught = _load(out)
    assert caught == []  # what jaxlens writes it reads back without a report
    assert jax.tree_util.tree_structure(again) == jax.tree_util.tree_structure(lens)
    for a, b in zip(jax.tree_util.tree_leaves(lens), jax.tree_util.tree_leaves(again), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_refused_with_line_and_reason(name):
    number, reason = REFUSED[name]
    path = os.path.join(DATA, name)
    with warnings.catch_warnings(), pytest.raises(ValueError, match=f"^{path}:{number}: {reason}"):
        warnings.simplefilter("ignore")
        jl.load(path)


def test_strict_refuses_what_is_only_reported():
    warnings.simplefilter("ignore")  # the reports before the one checked
    # Vignetting factors were reported here before jaxlens applied them: now read, strict too.
    lens = jl.load(os.path.join(DATA, "rayoptics_US00583336-2-scaled.zmx"), strict=True)
    assert lens.vignetting is not None and float(lens.vignetting[1, 1]) != 0  # VDYN, field 2
    with pytest.raises(ValueError, match=r":6: FTYP announces 3 fields.*strict"):
        jl.load(os.path.join(DATA, "optiland_lens_floa.zmx"), strict=True)


def test_fields_the_file_does_not_give_are_on_axis():
    lens, _ = _load("optiland_lens_floa.zmx")
    np.testing.assert_array_equal(np.asarray(lens.fields), [0.0, 0.0, 0.0])


def test_older_zemax_pupd_beside_an_aperture_is_ignored(tmp_path):
    """Zemax before 2008 writes PUPD (the pupil data) beside ENPD or FLOA; alone it is an
    aperture type jaxlens does not read."""
    body = ("SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  CURV 0.02\n  DISZ 4\n"
            "  GLAS ___BLANK 1 0 1.5 60\nSURF 2\n  CURV -0.02\n  DISZ 48\nSURF 3\n")
    p = tmp_path / "old.zmx"
    p.write_text("UNIT MM X W X CM MR\nENPD 10\nPUPD 0 10\nWAVM 1 0.5875618 1\n" + body)
    assert float(jl.load(p).epd) == 10.0
    p.write_text("UNIT MM X W X CM MR\nPUPD 0 10\nWAVM 1 0.5875618 1\n" + body)
    with pytest.raises(ValueError, match=f"^{p}:2: this aperture type is not supported"):
        jl.load(p)


def test_merit_function_operands_are_not_reported():
    """Ex27 ends with a REAY operand and Ex66 with GLCB, ACOS, REAX and TRAC lines: read
    silently, while an unknown keyword is still reported (tests/test_bad_input.py)."""
    for name in ("rayoptics_HoO-V2C18Ex27.zmx", "rayoptics_HoO-V2C18Ex03.zmx"):
        assert _load(name)[1] == []


def _optiland_efl(path, wavelength):
    """optiland's f2 (its EFL) of a file at a wavelength, as ``optic.paraxial.f2`` traces."""
    from optiland.fileio import load_zemax_file

    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        optic = load_zemax_file(str(path))
        px = optic.paraxial
        path_ = px.surfaces.build_paraxial_path()
        z0 = path_.axial_positions.reshape(-1, 1)[1] - 1
        y, u = px.trace_generic(1.0, 0.0, z0, wavelength, path=path_)
    return float(np.ravel(np.asarray(-y[0] / u[-1]))[0]), optic


@pytest.mark.parametrize("name", sorted(OPTILAND_EFL))
def test_optiland_reads_what_jaxlens_writes(name, tmp_path):
    pytest.importorskip("optiland")
    lens, _ = _load(name)
    out = tmp_path / "written.zmx"
    jl.save(lens, out)
    wl = OPTILAND_EFL[name][1] or float(lens.wavelengths[lens.primary])
    efl, optic = _optiland_efl(out, wl)
    assert efl == pytest.approx(float(jl.paraxial_data(lens, wl).efl_image_space), rel=1e-9)
    ours = [float(getattr(s, "semi_diameter", math.inf)) for s in lens.surfaces]
    theirs = [getattr(getattr(s, "aperture", None), "r_max", None) for s in optic.surfaces]
    assert [r for r in ours if math.isfinite(r)] == pytest.approx(
        [float(r) for r in theirs if r is not None], rel=1e-12)
    n_theirs = float(np.ravel(np.asarray(optic.surfaces[-1].material_post.n(wl)))[0])
    assert n_theirs == pytest.approx(float(lens.materials[-1].index(wl)), rel=1e-12)


def test_zemax_default_model_values_on_a_catalog_glass_are_no_claim(tmp_path):
    """Zemax writes nd 1.5, Vd 40 (its model-glass defaults) on catalog GLAS lines it never
    modelled (every glass of the ray-optics patent files): no cross-check report. Other
    values that disagree with the catalog are still reported."""
    def text(nd, vd):
        return ("UNIT MM\nENPD 10\nGCAT SCHOTT\nWAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\n"
                f"SURF 1\n  STOP\n  CURV 0.02\n  DISZ 4\n  GLAS N-BK7 0 0 {nd} {vd} 0 0 0 0 0 0\n"
                "SURF 2\n  CURV -0.02\n  DISZ 48\nSURF 3\n")
    p = tmp_path / "g.zmx"
    p.write_text(text("1.50E+00", "4.00E+01"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        jl.load(p)
    p.write_text(text("1.6", "40"))
    with pytest.warns(zmx.ZmxWarning, match=r"g.zmx:11: GLAS N-BK7 gives nd 1.6, Vd 40"):
        jl.load(p)


@pytest.mark.parametrize("aim", [
    "paraxial",
    # The file's own aiming (RAIM 2, "real_marginal"): Newton through nine coordinate breaks.
    # 5 to 10 minutes at the tests' -O0 on XLA's fusion emitters, 7 s on the loop emitters
    # (forward.aimed_jit); a test of them too.
    None,
])
def test_a_mirror_system_with_zero_gap_breaks_traces_its_whole_beam(aim):
    """Ex66 folds with mirrors between coordinate breaks at zero gaps: every ray of every
    field reaches the image (half the on-axis beam was lost where the surface after a
    curved mirror lay behind the reflection point)."""
    lens, _ = _load("rayoptics_HoO-V2C18Ex66.zmx")
    spot = jl.analysis.rms_spot(lens, aim=aim)
    np.testing.assert_array_equal(np.asarray(spot.valid_fraction), 1.0)
