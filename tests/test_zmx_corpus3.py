"""Zemax files of the third corpus round (/work/zmx_probe/corpus3, SOURCES3.txt).

The snippets are hand-written after three public files found in this round (each named
where it is defined); reference EFLs are optiland 0.6.3's ``paraxial.f2()``, printed by
``/work/optiland_venv/bin/python tools/corpus3_reference.py`` (which reads the snippets
from this file), or an analytic paraxial formula.
"""

import pytest

import jaxlens
from jaxlens.io import zmx

# After the Edmund Optics 65438 achromat as a Ray Optics Simulation test quotes it
# (find_string id 67293649874): no TYPE lines (STANDARD), no GCAT, no wavelength, no
# aperture. ENPD and a 0.55 µm wavelength (Zemax's default) are added so optiland reads it.
EO65438 = """VERS 171115
MODE SEQ
NAME 65438 Achromatic Lens
UNIT MM X W X CM MR CPMM
ENPD 10
WAVM 1 0.55 1
PWAV 1
SURF 0
  CURV 0.0
  DISZ INFINITY
SURF 1
  STOP
  CURV 5.042864346949069848E-02
  DISZ 11
  GLAS N-LAK14
  DIAM 12 1 0 0 1 ""
  CLAP 0 12 0
SURF 2
  CURV -4.938271604938269943E-02
  DISZ 3
  GLAS N-SF66
  DIAM 12 1 0 0 1 ""
  FLAP 0 12 0
SURF 3
  CURV -1.006846556584779957E-02
  DISZ 21.955518323527404
  DIAM 12 1 0 0 1 ""
  CLAP 0 12 0
SURF 4
  CURV 0.0
  DISZ 0
"""

# After the AC254-100-A doublet in a Lumenairy audit script (find_string id 68586073830):
# glass lines with an index and Abbe number, a CURV with its solve fields, BLNK at the end.
AC254_100_A = """VERS 210000 0 123 0 0
MODE SEQ
NAME AC254-100-A
UNIT MM X W X CM MR CPMM
ENPD 25.400000
GCAT SCHOTT MISC
WAVM 1 0.587560 1.0
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ INFINITY
  DIAM 0 0 0 0 1 ""
SURF 1
  STOP
  TYPE STANDARD
  CURV 0.01593625498 0 0 0 0 ""
  DISZ 4.0
  GLAS N-BAF10 0 0 1.67003 47.11 0 0 0 0 0 0
  DIAM 12.7 1 0 0 1 ""
SURF 2
  TYPE STANDARD
  CURV -0.02187705097 0 0 0 0 ""
  DISZ 2.5
  GLAS N-SF6HT 0 0 1.80518 25.36 0 0 0 0 0 0
  DIAM 12.7 1 0 0 1 ""
SURF 3
  TYPE STANDARD
  CURV -0.0077984091 0 0 0 0 ""
  DISZ 95.0
  DIAM 12.7 1 0 0 1 ""
SURF 4
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ 0.0
  DIAM 0 0 0 0 1 ""
BLNK
"""

# After the EVENASPH snippet of the same script, with ENPD and WAVM added and its PARM 1
# (the r² term) removed: optiland's paraxial trace leaves that term out (see below).
EVENASPH_NO_R2 = """VERS 210000 0 123 0 0
MODE SEQ
UNIT MM X W X CM MR CPMM
ENPD 10
WAVM 1 0.55 1
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0
  DISZ INFINITY
SURF 1
  TYPE EVENASPH
  STOP
  CURV 0.02
  DISZ 5.0
  GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0
  PARM 2 -1.234e-6
  PARM 3 5.678e-10
  PARM 8 1.0e-20
  DIAM 12.7
SURF 2
  TYPE STANDARD
  CURV 0
  DISZ 50.0
  DIAM 12.7
SURF 3
  TYPE STANDARD
  CURV 0
  DISZ 0
  DIAM 12.7
"""

# optiland 0.6.3, paraxial.f2() (tools/corpus3_reference.py)
OPTILAND_EFL = {
    "EO65438": 30.060397841634764,
    "AC254_100_A": 72.21557081610634,
    "EVENASPH_NO_R2": 96.42785189935934,
}


def _efl(text):
    return float(jaxlens.paraxial_data(zmx.loads(text)).efl_image_space)


@pytest.mark.parametrize("name", sorted(OPTILAND_EFL))
def test_corpus3_snippets_match_optiland(name):
    text = globals()[name]
    assert _efl(text) == pytest.approx(OPTILAND_EFL[name], rel=1e-7)


def test_no_type_no_catalog_no_wavelength_reads_as_zemax_defaults():
    # No WAVM: Zemax's default 0.55 µm, the wavelength of the reference above.
    text = EO65438.replace("WAVM 1 0.55 1\nPWAV 1\n", "")
    assert _efl(text) == pytest.approx(OPTILAND_EFL["EO65438"], rel=1e-7)


def test_file_without_an_aperture_is_refused_by_name():
    # The vendor file as quoted (its header cut to NAME/NOTE/UNIT) has no aperture line.
    with pytest.raises(ValueError, match=r"no aperture \(ENPD, FNUM, FLOA or OBNA line\)"
                                         r".*Add one after the UNIT line: 'ENPD d'"):
        zmx.loads(EO65438.replace("ENPD 10\n", ""))
    # What the message proposes opens it (FLOA: the stop's DIAM 12 sets the pupil).
    text = EO65438.replace("ENPD 10\n", "FLOA\n")
    assert jaxlens.paraxial_data(zmx.loads(text)).entrance_pupil_diameter == pytest.approx(24.0)


def test_evenasph_r2_term_adds_to_the_paraxial_power():
    # PARM 1 = a1 (r² coefficient) adds 2·a1 to the vertex curvature: a thin plano lens of
    # power (n-1)(c + 2 a1). optiland's paraxial f2() leaves a1 out, so its EFL without a1
    # gives (n-1)c, and with a1 = 1e-3, c = 0.02 the EFL scales by c / (c + 2 a1) = 1/1.1.
    text = EVENASPH_NO_R2.replace("  PARM 2 -1.234e-6\n", "  PARM 1 1.0e-3\n  PARM 2 -1.234e-6\n")
    assert _efl(text) == pytest.approx(OPTILAND_EFL["EVENASPH_NO_R2"] / 1.1, rel=1e-7)


def test_missing_curv_names_the_cut_and_not_the_thickness():
    text = AC254_100_A.replace('  CURV -0.0077984091 0 0 0 0 ""\n', "")
    with pytest.raises(ValueError, match=r"surface 3 has no CURV line") as err:
        zmx.loads(text)
    assert "thickness" not in str(err.value)
    assert "VERS line" in str(err.value)
    text = AC254_100_A.replace("  DISZ 2.5\n", "")
    with pytest.raises(ValueError, match=r"surface 2 has no DISZ line \(every surface needs "
                                         r"its thickness"):
        zmx.loads(text)


# After the "LensVa3Style" test of a StarOpt C# project (find_string id 58575561119), itself
# modelled on an OpticStudio 2024 file (VERS 241210): FCOM field comments (UTF-8 text),
# merit rows with text, and a two-configuration MCE of CRVT and THIC rows (active: 2). Field
# type 0 (angles) here; the original's FTYP 3 asks for a 4.5 mm image height that no real
# ray reaches through this toy lens (refused, rightly, by name).
LENS_VA3 = """VERS 241210 1439 20120530 20120530
MODE SEQ
NAME
FNUM 2.7 0
GCAT CDGM
FTYP 0 0 2 3 0 0 0 2
XFLN 0 0
YFLN 0 4.5
FWGN 1 1
FCOM 1 轴上视场
FCOM 2 最大Y视场
WAVM 1 0.42 1
WAVM 2 0.44 1
WAVM 3 0.46 1
PWAV 2
SURF 0
  TYPE STANDARD
  CURV 0
  DISZ 2500
SURF 1
  TYPE STANDARD
  CURV 0.025
  DISZ 3
  GLAS H-K9L 0 0 1.5 40
  STOP
  DIAM 1000
SURF 2
  TYPE STANDARD
  CURV 0
  DISZ 0
EFFL 0 2 0 0 0 0 10.7 1 0 0
DMFS 0 0 0 0 0 0 0 0 0 0
BLNK 对比度于185 lp/MM
MECS 0 1 1 185 0.33571068701972878 0 0 0.058177641733144006 0 0
MNUM 2 2
CRVT 1 1 0.02 0 0 0 1 1 1 0 0 "" 0
CRVT 1 2 0.025 0 0 0 1 1 1 0 0 "" 0
THIC 0 1 500 0 0 0 1 1 1 0 0 "" 0
THIC 0 2 2500 0 0 0 1 1 1 0 0 "" 0
"""


def test_field_comments_are_read_past_in_strict_mode():
    lens = zmx.loads(LENS_VA3, strict=True)  # FCOM was an unknown keyword: refused
    assert len(lens.fields) == 2


def test_two_configurations_of_curvature_read_as_one_refracting_surface():
    # The image lies in the glass: one surface of radius R, n′/Φ = n′R/(n′-1), 1/Φ = R/(n′-1).
    for config, radius in ((1, 50.0), (2, 40.0)):
        lens = zmx.loads(LENS_VA3, config=config)
        n = float(lens.materials[-1].index(0.44))
        p = jaxlens.paraxial_data(lens)
        assert float(p.efl_image_space) == pytest.approx(n * radius / (n - 1), rel=1e-12)
        assert float(p.efl) == pytest.approx(radius / (n - 1), rel=1e-12)
