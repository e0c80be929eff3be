"""Zemax .zmx files: round trips, encodings, glasses and AGF catalogs, the hybrid surface,
and errors that name the line."""

import dataclasses
import math
import pathlib
import re
import warnings

import jax.numpy as jnp
import numpy as np
import pytest
from test_lensfile import assert_same_lens, every_kind_of_lens

import jaxlens
from jaxlens.io import zmx
from jaxlens.io.zmx_common import ZmxWarning
from jaxlens.optics.catalog import load_agf
from jaxlens.optics.materials import Air, ModelGlass, Tabulated
from jaxlens.optics.surfaces import EvenAsphere, Hybrid, Standard


def _as_read(lens):
    """The lens as the .zmx reader gives it back: every lens read from a .zmx file traces by
    Zemax's rule (``Lens.negative_propagation``), which a .zmx file does not write."""
    return dataclasses.replace(lens, negative_propagation=True)

DATA = pathlib.Path(jaxlens.__file__).parent / "data" / "lenses"

# A hand-written file in the layout OpticStudio saves (tokens after the values, automatic
# semi-diameters, HIDE/MIRR/SLAB/POPS lines that jaxlens ignores).
COOKE_ZMX = """VERS 190513 80 123457 L123457
MODE SEQ
NAME Cooke triplet
PFIL 0 0 0
LANG 0
UNIT MM X W X CM MR CPMM
ENPD 1.0E+1
ENVD 2.0E+1 1 0
GFAC 0 0
GCAT SCHOTT
RAIM 0 0 1 1 0 0 0 0 0
FTYP 0 0 3 3 0 0 0
ROPD 2
PICB 1
XFLN 0 0 0 0 0 0 0 0 0 0 0 0
YFLN 0 1.4E+1 2.0E+1 0 0 0 0 0 0 0 0 0
FWGN 1 1 1 1 1 1 1 1 1 1 1 1
WAVM 1 4.861327E-1 1
WAVM 2 5.875618E-1 1
WAVM 3 6.562725E-1 1
WAVM 4 5.5E-1 1
PWAV 2
GLRS 1 0
SURF 0
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  HIDE 0 0 0 0 0 0 0 0 0 0
  MIRR 2 0
  SLAB 1
  DISZ INFINITY
  DIAM 0 0 0 0 1 ""
  POPS 0 0 0 0 0 0 0 0 1 1 1 1 0 0 0 0
SURF 1
  TYPE STANDARD
  CURV 4.542648427630386E-002 0 0 0 0 ""
  HIDE 0 0 0 0 0 0 0 0 0 0
  MIRR 2 0
  SLAB 2
  DISZ 3.25896
  GLAS N-SK16 0 0 1.62041 6.033E+001 0 0 0 0 0 0
  DIAM 8.557578525439 0 0 0 1 ""
SURF 2
  TYPE STANDARD
  CURV -2.294838879821215E-003 0 0 0 0 ""
  DISZ 6.00755
  DIAM 7.99 0 0 0 1 ""
SURF 3
  TYPE STANDARD
  CURV -4.501811528959253E-002 0 0 0 0 ""
  DISZ 0.99997
  GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0
  DIAM 4.0 0 0 0 1 ""
SURF 4
  STOP
  TYPE STANDARD
  CURV 4.928069891858434E-002 0 0 0 0 ""
  DISZ 4.75041
  DIAM 3.87 0 0 0 1 ""
SURF 5
  TYPE STANDARD
  CURV 1.254963380168567E-002 0 0 0 0 ""
  DISZ 2.95208
  GLAS N-SK16 0 0 1.62041 6.033E+001 0 0 0 0 0 0
  DIAM 7.5 0 0 0 1 ""
SURF 6
  TYPE STANDARD
  CURV -5.436162330330578E-002 0 0 0 0 ""
  DISZ 42.20778
  DIAM 7.9 0 0 0 1 ""
SURF 7
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ 0
  DIAM 18.2 0 0 0 1 ""
"""


def test_reads_zemax_layout_utf16_and_utf8(tmp_path):
    ref = jaxlens.load(DATA / "cooke_triplet.json")
    for enc, bom in (
        ("utf-16", b""),
        ("utf-8", b""),
        ("utf-8", b"\xef\xbb\xbf"),
        ("utf-16-le", b"\xff\xfe"),
    ):
        p = tmp_path / f"cooke_{enc}_{len(bom)}.zmx"
        p.write_bytes(bom + COOKE_ZMX.replace("\n", "\r\n").encode(enc))
        lens = jaxlens.load(p)
        assert lens.name == "Cooke triplet"
        assert lens.stop == 3 and lens.primary == 1
        np.testing.assert_array_equal(
            np.asarray(lens.wavelengths), [0.4861327, 0.5875618, 0.6562725]
        )
        np.testing.assert_array_equal(np.asarray(lens.fields), [0.0, 14.0, 20.0])
        assert [m.name for m in lens.materials] == ["N-SK16", "air", "F2", "air", "N-SK16", "air"]
        # Automatic semi-diameters (solve flag 0) do not clip.
        assert all(math.isinf(float(s.semi_diameter)) for s in lens.surfaces)
        assert float(jaxlens.efl(lens)) == pytest.approx(float(jaxlens.efl(ref)), rel=1e-14)


def test_round_trips_lose_nothing(tmp_path):
    lens = every_kind_of_lens(tmp_path)
    p1, p2 = tmp_path / "a" / "lens.zmx", tmp_path / "b" / "lens.zmx"
    p1.parent.mkdir()
    p2.parent.mkdir()
    written = jaxlens.save(lens, p1)
    one = jaxlens.load(p1)
    assert not lens.negative_propagation and one.negative_propagation
    assert_same_lens(_as_read(lens), one)  # Lens -> zmx -> Lens
    jaxlens.save(one, p2)
    two = jaxlens.load(p2)
    assert_same_lens(one, two)  # zmx -> Lens -> zmx -> Lens
    assert p1.read_text() == p2.read_text()
    for w in written[1:]:
        other = p2.parent / pathlib.Path(w).name
        assert pathlib.Path(w).read_text() == other.read_text()
    # The sample file too.
    sample = jaxlens.load(DATA / "cooke_triplet.zmx")
    jaxlens.save(sample, tmp_path / "c.zmx")
    assert_same_lens(sample, jaxlens.load(tmp_path / "c.zmx"))


def test_glas_lines_and_gcat(tmp_path):
    lens = every_kind_of_lens(tmp_path)
    text, _ = zmx.dumps(lens, "mylens.zmx")
    glas = [ln.strip() for ln in text.splitlines() if ln.strip().startswith("GLAS")]
    assert "GLAS N-BK7 0 0 1.5168 6.417E+001 0 0 0 0 0 0" in glas
    assert "GLAS E48R 0 0 1.53117 5.6E+001 0 0 0 0 0 0" in glas
    assert "GLAS ___BLANK 1 0 1.55 5.0E+001 0 0 0 0 0 0" in glas
    for g in glas:
        t = g.split()
        assert len(t) == 12 and t[2:4] in (["0", "0"], ["1", "0"]) and t[6:] == ["0"] * 6
        assert re.fullmatch(r"-?\d\.\d+E[+-]\d{3}", t[5])
    gcat = next(ln for ln in text.splitlines() if ln.startswith("GCAT")).split()[1:]
    # Side catalogs first (Zemax searches in order), then Zemax's own.
    assert set(gcat[:3]) == {"MYLENS", "PLASTICS", "MYCAT"} and gcat[3:] == ["SCHOTT", "ZEON"]


def test_agf_for_glasses_zemax_does_not_ship(tmp_path):
    lens = every_kind_of_lens(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    written = jaxlens.save(lens, out / "mylens.zmx")
    names = sorted(pathlib.Path(w).name for w in written[1:])
    assert names == ["MYCAT.AGF", "MYLENS.AGF", "PLASTICS.AGF"]
    cat = load_agf(out / "MYLENS.AGF")  # valid AGF for the catalog reader (and Zemax)
    assert set(cat) == {"TAB_1", "HAND_MADE"}
    # Zemax sees a Schott series through jaxlens's index at the file's wavelengths, which
    # Zemax traces (round 37d: the three-term series through the table alone was 2.9e-4 off
    # at F).
    tab = lens.materials[6]
    assert cat["TAB_1"].formula == 1
    np.testing.assert_allclose(np.asarray(cat["TAB_1"].index(lens.wavelengths)),
                               np.asarray(tab.index(lens.wavelengths)), rtol=0, atol=1e-12)
    # Three terms for three wavelengths: a six-term series through those and the table's
    # three points as well swung between them (Vd 18.7 for a table of N-BK7, round 37a).
    # The table's own points stay within its interpolation's reach.
    wl = np.asarray(tab.wavelengths)
    np.testing.assert_allclose(
        np.asarray(cat["TAB_1"].index(wl)), np.asarray(tab.indices), rtol=0, atol=5e-4
    )
    assert int(np.count_nonzero(np.asarray(cat["TAB_1"].model.coeffs))) == 3
    text = (out / "MYLENS.AGF").read_text()
    assert re.search(r'^GC jaxlens \{"wavelengths_um":\[0\.45,0\.55,0\.66\]', text, re.M)
    # OKP4's shipped data is a model dispersion: written exactly, not referenced.
    okp4 = load_agf(out / "PLASTICS.AGF")["OKP4"]
    assert_same_lens(okp4, lens.materials[4])
    # model_glass="agf": the jaxlens model dispersion exactly, as a Schott series.
    jaxlens.save(lens, out / "m.zmx", model_glass="agf")
    mg = load_agf(out / "M.AGF")
    model = next(v for v in mg.values() if v.catalog_nd == 1.55)
    w = np.linspace(0.4, 0.8, 9)
    np.testing.assert_allclose(
        np.asarray(model.index(w)), np.asarray(ModelGlass(1.55, 50.0).index(w)), rtol=0, atol=2e-15
    )
    assert_same_lens(jaxlens.load(out / "m.zmx"), _as_read(lens))


def _xpoly_sag(lines, x, y):
    xdat = {}
    for ln in lines:
        t = ln.split()
        if t[0] == "XDAT":
            xdat[int(t[1])] = float(t[2])
    c = float(next(ln for ln in lines if ln.startswith("CURV")).split()[1])
    k = float(next(ln for ln in lines if ln.startswith("CONI")).split()[1])
    r2 = x * x + y * y
    z = c * r2 / (1 + np.sqrt(1 - (1 + k) * c * c * r2))
    norm = xdat[2]
    for j in range(1, int(xdat[1]) + 1):
        d = int((math.isqrt(8 * j + 1) - 1) // 2)
        ny = j - d * (d + 1) // 2
        z = z + xdat[j + 2] * (x / norm) ** (d - ny) * (y / norm) ** ny
    return z


def test_hybrid_is_zemax_extended_polynomial():
    s = Hybrid(
        c=0.02,
        k=-1.5,
        coeffs=[1e-3, 2e-5, -3e-7, 1e-9, 2e-11],
        odd_x=[1e-4, 2e-6],
        odd_y=[-3e-5, 4e-7],
        semi_diameter=5.0,
    )
    lines = zmx.surface_lines(s)
    assert lines[0] == "TYPE XPOLYNOM"
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-4, 4, (2, 200))
    np.testing.assert_allclose(
        _xpoly_sag(lines, x, y), np.asarray(s.sag(x, y)[0]), rtol=1e-13, atol=1e-15
    )
    # XDAT 1 is the number of terms up to the surface's degree d, (d + 1)(d + 2)/2 − 1 (no
    # constant term): d = 10 from r¹⁰ here; an odd x¹¹ term or the even part alone set it
    # elsewhere; degree 20 is Zemax's limit.
    def count(lines):
        return int(next(ln for ln in lines if ln.startswith("XDAT 1 ")).split()[2])

    assert count(lines) == 11 * 12 // 2 - 1
    xdat = [int(ln.split()[1]) for ln in lines if ln.startswith("XDAT")]
    assert xdat == list(range(1, count(lines) + 3))  # XDAT 1, 2 (the norm radius), terms
    odd11 = Hybrid(c=0.0, k=0.0, coeffs=[1e-3, 1e-5], odd_x=[1e-4, 0, 0, 0, 1e-12],
                   odd_y=[0, 0, 0, 0, 0])
    assert count(zmx.surface_lines(odd11)) == 12 * 13 // 2 - 1
    even_only = Hybrid(c=0.0, k=0.0, coeffs=[1e-3, 1e-5], odd_x=[], odd_y=[])
    assert count(zmx.surface_lines(even_only)) == 5 * 6 // 2 - 1
    assert count(zmx.surface_lines(Hybrid(c=0.0, k=0.0, coeffs=[1e-9] * 10, odd_x=[1e-5],
                                          odd_y=[0.0]))) == 21 * 22 // 2 - 1
    with pytest.raises(ValueError, match="degree 22 exceeds"):
        zmx.surface_lines(Hybrid(c=0.0, k=0.0, coeffs=[1e-9] * 11, odd_x=[1e-5], odd_y=[0.0]))
    # Zemax's ordering: x, y, x², xy, y², x³, x²y, ...
    assert [zmx.term_powers(j) for j in range(1, 8)] == [
        (1, 0),
        (0, 1),
        (2, 0),
        (1, 1),
        (0, 2),
        (3, 0),
        (2, 1),
    ]


def _minimal(surface1_lines, head="ENPD 10\nWAVM 1 0.55 1\n", extra=""):
    return (
        f"UNIT MM\n{head}SURF 0\n  DISZ INFINITY\nSURF 1\n{surface1_lines}"
        f"  DISZ 5\n  GLAS N-BK7\nSURF 2\n  CURV -0.02\n  DISZ 45\n{extra}SURF 3\n"
    )


def test_even_asphere_parm1_is_a2_and_units(tmp_path):
    lens = zmx.loads(_minimal("  TYPE EVENASPH\n  CURV 0.02\n  PARM 1 1E-3\n  PARM 3 2E-7\n"))
    s = lens.surfaces[0]
    assert isinstance(s, EvenAsphere)
    np.testing.assert_array_equal(np.asarray(s.coeffs), [1e-3, 0.0, 2e-7])
    assert float(s.paraxial_curvature) == 0.02 + 2e-3
    cm = zmx.loads(
        _minimal("  TYPE EVENASPH\n  CURV 0.2\n  PARM 2 1E-3\n").replace("UNIT MM", "UNIT CM")
    )
    assert float(cm.surfaces[0].c) == pytest.approx(0.02, rel=1e-15)
    assert float(cm.thickness[0]) == 50.0 and float(cm.epd) == 100.0
    assert float(cm.surfaces[0].coeffs[1]) == pytest.approx(1e-3 * 10.0**-3, rel=1e-15)


def test_apertures():
    lens = zmx.loads(_minimal("  STOP\n  CURV 0.02\n", head="FNUM 4 0\nWAVM 1 0.55 1\n"))
    assert float(lens.epd) == pytest.approx(float(jaxlens.efl(lens)) / 4, rel=1e-15)
    lens = zmx.loads(
        _minimal('  STOP\n  CURV 0.02\n  DIAM 3 1 0 0 1 ""\n  FLAP 0 3 0\n',
                 head="FLOA\nWAVM 1 0.55 1\n")
    )
    assert float(lens.epd) == pytest.approx(6.0, rel=1e-15)
    assert float(lens.surfaces[0].semi_diameter) == 3.0  # its floating aperture clips
    lens = zmx.loads(
        _minimal('  STOP\n  CURV 0.02\n  DIAM 3 1 0 0 1 ""\n', head="FLOA\nWAVM 1 0.55 1\n")
    )
    assert float(lens.epd) == pytest.approx(6.0, rel=1e-15)
    assert float(lens.surfaces[0].semi_diameter) == math.inf  # as in Zemax: DIAM alone



def _thin_lenses(head, *focal_lengths, gap=100.0, obj="  DISZ 100\n"):
    """Ideal thin lenses (PARAXIAL), the first the stop, ``gap`` mm apart, then the image."""
    surfs = "".join(f"SURF {i}\n{'  STOP' + chr(10) if i == 1 else ''}  TYPE PARAXIAL\n"
                    f"  PARM 1 {f}\n  PARM 2 2\n  DISZ {gap}\n"
                    for i, f in enumerate(focal_lengths, start=1))
    return (f"UNIT MM\n{head}WAVM 1 0.55 1\nSURF 0\n{obj}{surfs}"
            f"SURF {len(focal_lengths) + 1}\n  DISZ 0\n")


def test_paraxial_working_fnum():
    """FNUM x 1 is the paraxial working F/# 1/(2 n′ u′). A thin lens of f = 50 mm imaging
    an object 100 mm away at 1:1, stop at the lens: u′ = (D/2)/100, so F/5 means D = 20 mm.
    At infinity u′ = (D/2)/f: the same EPD as the image-space F/# (FNUM x 0)."""
    lens = zmx.loads(_thin_lenses("FNUM 5 1\n", 50.0))
    assert float(lens.epd) == pytest.approx(20.0, rel=1e-12)
    far = _minimal("  STOP\n  CURV 0.02\n", head="FNUM 4 1\nWAVM 1 0.55 1\n")
    assert float(zmx.loads(far).epd) == pytest.approx(
        float(zmx.loads(far.replace("FNUM 4 1", "FNUM 4 0")).epd), rel=1e-12)
    with pytest.raises(ValueError, match=r"t.zmx:2: F/# type must be 0 \(image space\) or 1"):
        zmx.loads(_thin_lenses("FNUM 5 2\n", 50.0), "t.zmx")
    # A telescope (f = 50 mm twice, 100 mm apart) leaves the marginal ray parallel.
    with pytest.raises(ValueError, match=r"t.zmx:2: .*afocal lens.*'FNUM 5 1'"):
        zmx.loads(_thin_lenses("FNUM 5 1\n", 50.0, 50.0, obj="  DISZ INFINITY\n"), "t.zmx")


@pytest.mark.parametrize("obj, line, what", [
    ("  CURV 0.01\n", 6, r"CURV 0.01"),
    ("  TYPE TILTSURF\n  PARM 2 -1\n", 7, r"PARM 2 -1"),
    ("  TYPE COORDBRK\n", 6, r"TYPE COORDBRK"),
])
def test_a_finite_object_must_be_a_plane(obj, line, what):
    """jaxlens objects are planes normal to the axis: a curved or tilted object surface at a
    finite distance is refused with its line, not read as a plane; at infinity its shape does
    not matter."""
    text = _thin_lenses("ENPD 10\n", 50.0, obj=f"  DISZ 100\n{obj}")
    with pytest.raises(ValueError, match=rf"t.zmx:{line}: the object surface at a finite "
                                         rf"distance must be a plane.*{what}"):
        zmx.loads(text, "t.zmx")
    far = zmx.loads(text.replace("DISZ 100\n", "DISZ INFINITY\n", 1), "t.zmx")
    assert far.object_distance is None


def test_a_finite_standard_object_ignores_its_unused_parameters():
    """Under an explicit TYPE STANDARD, PARM values are unused (as in Zemax): a finite plane
    object with a stale PARM loads, at its distance."""
    text = _thin_lenses("ENPD 10\n", 50.0, obj="  DISZ 100\n  TYPE STANDARD\n  PARM 2 -1\n")
    assert float(zmx.loads(text, "t.zmx").object_distance) == pytest.approx(100.0)


def test_environment_other_than_20_c_and_1_atm():
    """ENVD t p 1 (indices adjusted to t °C, p atm) is refused with its line: jaxlens's indices
    are the catalogs', relative to air at 20 °C and 1 atm. With the flag 0 the environment is
    reported (an error under strict); 20 °C and 1 atm, or a lens of mirrors in air, pass."""
    def text(envd, glass="N-BK7"):
        return _minimal("  STOP\n  CURV 0.02\n", head=f"ENPD 10\n{envd}WAVM 1 0.55 1\n"
                        ).replace("GLAS N-BK7", f"GLAS {glass}")
    with pytest.raises(ValueError, match=r"t.zmx:3: glass indices adjusted to -40 °C and 0 atm"):
        zmx.loads(text("ENVD -40 0 1\n"), "t.zmx")
    with pytest.warns(zmx.ZmxWarning, match=r"t.zmx:3: the file's environment \(-40 °C, 0 atm\)"):
        zmx.loads(text("ENVD -40 0 0\n"), "t.zmx")
    with pytest.raises(ValueError, match=r"environment.*strict"):
        zmx.loads(text("ENVD -40 0 0\n"), "t.zmx", strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        zmx.loads(text("ENVD 2.0E+1 1 0\n"), "t.zmx")
        zmx.loads(text("ENVD 20 1 1\n"), "t.zmx")
        zmx.loads(text("ENVD -40 0 1\n", glass="MIRROR"), "t.zmx")

def test_tolerance_comments_are_known():
    """TCMM (a tolerance operand's comment) is a keyword Zemax writes; strict mode accepts it."""
    zmx.loads(_minimal("  STOP\n  CURV 0.02\n", extra="TOL TRAD 1 0 -0.1 0.1 0 0 0\n"
                       "TCMM Default radius tolerances.\n"), strict=True)

BAD = [
    ("  CURV abc\n", "", 7, r"curvature is not a number"),
    ("  CURV 1e999\n", "", 7, r"curvature must be finite"),
    ("  CURV nan\n", "", 7, r"curvature must be finite"),
    ("  TYPE GRID_SAG\n", "", 7, r"surface type GRID_SAG is not supported"),
    ("  PARM x 1\n", "", 7, r"PARM index is not a number"),
    ("", "  DISZ INFINITY\n", 12, r"only the object surface may have an infinite thickness"),
    ("  TYPE EVENASPH\n  PARM 9 1e-3\n", "", 8, r"PARM 1\.\.8"),
    ("  GLAS\n", "", 7, r"GLAS needs a glass name"),
    ("", "  GLAS ___BLANK 1 0 abc 50\n", 12, r"model glass nd is not a number"),
    ("  @@@ garbage\n", "", 7, r"not a Zemax keyword line"),
    ("  STOP\nSURF 1\n", "", 8, r"expected 2"),
    (  # jaxlens's hybrid comment: the polynomial must be a hybrid's
        "  TYPE XPOLYNOM\n  COMM jaxlens hybrid even=1 odd=0\n  XDAT 1 4\n  XDAT 2 1\n"
        "  XDAT 6 1e-3\n",
        "",
        11,
        r"x\^1 y\^1 .* does not fit the hybrid surface",
    ),
]


@pytest.mark.parametrize(("lines", "extra", "lineno", "match"), BAD)
def test_malformed_names_file_and_line(tmp_path, lines, extra, lineno, match):
    p = tmp_path / "bad.zmx"
    text = _minimal(lines, extra=extra)
    p.write_bytes(text.encode("utf-16"))
    with pytest.raises(ValueError, match=match) as e:
        jaxlens.load(p)
    msg = str(e.value)
    assert msg.startswith(f"{p}:{lineno}: ")
    bad_line = text.splitlines()[lineno - 1].strip()
    assert repr(bad_line) in msg


def test_other_bad_files(tmp_path):
    cases = {
        "empty.zmx": b"",
        "nosurf.zmx": b"UNIT MM\nENPD 10\n",
        "binary.zmx": bytes(range(256)) * 4,
        "noap.zmx": _minimal("  CURV 0.02\n", head="WAVM 1 0.55 1\n").encode(),
        "units.zmx": _minimal("  CURV 0.02\n").replace("UNIT MM", "UNIT FURLONG").encode(),
        "fields.zmx": _minimal("  CURV 0.02\n", head="ENPD 10\nFTYP 1 0 1 1\nYFLN 3\n").encode(),
    }
    for name, raw in cases.items():
        (tmp_path / name).write_bytes(raw)
        with pytest.raises(ValueError, match=re.escape(str(tmp_path / name))):
            jaxlens.load(tmp_path / name)


def test_unknown_glass_lists_close_matches(tmp_path):
    p = tmp_path / "glass.zmx"
    p.write_text(_minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS N-BK8 0 0 1.5 60"))
    with pytest.raises(ValueError) as e:
        jaxlens.load(p)
    msg = str(e.value)
    assert msg.startswith(f"{p}:9: glass 'N-BK8'") and "N-BK7" in msg


def test_unknown_glass_names_unshipped_gcat_and_optically_close_glasses():
    text = _minimal("  CURV 0.02\n").replace(
        "GLAS N-BK7", "GLAS D-ZK3Q 0 0 1.58913 61.27 0 0 0 0 0 0"
    )
    with pytest.raises(ValueError) as e:
        zmx.loads("GCAT NHG SCHOTT\n" + text)  # NHG: a Zemax catalog jaxlens does not ship
    msg = str(e.value)
    assert msg.startswith("<zmx>:10: glass 'D-ZK3Q'")
    assert "Closest catalog matches: D-ZK3," in msg
    assert "Optically closest to nd 1.58913, Vd 61.27: SCHOTT N-SK5 (nd 1.58913" in msg
    assert "GCAT names NHG, which jaxlens does not ship" in msg
    assert "SCHOTT, CDGM" in msg and "OHARA" in msg and "NHG.AGF" in msg
    with pytest.raises(ValueError) as e:
        zmx.loads("GCAT SCHOTT OHARA\n" + text)
    assert "does not ship" not in str(e.value) and "Optically closest" in str(e.value)
    # A GLAS line without nd and Vd still gets the close names.
    with pytest.raises(ValueError) as e:
        zmx.loads(text.replace(" 0 0 1.58913 61.27 0 0 0 0 0 0", ""))
    assert "D-ZK3" in str(e.value) and "Optically" not in str(e.value)


def test_unknown_glass_model_opens_the_file_with_the_lines_nd_and_vd():
    text = _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS S-LAL7Q 0 0 1.6516 58.54 0 0 0")
    with pytest.raises(ValueError, match="unknown_glass='model'"):
        zmx.loads(text)
    with pytest.warns(ZmxWarning, match=r"<zmx>:9: glass 'S-LAL7Q' is in no catalog.*nd 1.6516"):
        lens = zmx.loads(text, unknown_glass="model")
    glass = lens.materials[0]
    assert isinstance(glass, ModelGlass)
    n_d, n_f, n_c = (float(glass.index(w)) for w in (0.5875618, 0.4861327, 0.6562725))
    assert n_d == pytest.approx(1.6516, abs=1e-12)
    assert (n_d - 1) / (n_f - n_c) == pytest.approx(58.54, rel=1e-9)
    # Nothing to model from: no nd/Vd, or Zemax's untouched defaults 1.5/40.
    for bare in ("GLAS S-LAL7Q", "GLAS S-LAL7Q 0 0 1.5 40"):
        with pytest.raises(ValueError, match="S-LAL7Q") as e:
            zmx.loads(text.replace("GLAS S-LAL7Q 0 0 1.6516 58.54 0 0 0", bare),
                      unknown_glass="model")
        assert "unknown_glass" not in str(e.value)
    with pytest.raises(ValueError, match="unknown_glass must be 'error' or 'model'"):
        zmx.loads(text, unknown_glass="yes")


def test_unknown_glass_model_names_another_glass_whose_nd_and_vd_the_line_holds():
    """Zemax keeps the nd and Vd of the glass a GLAS line last held: a line naming an
    obsolete glass with N-SK16's data is said to, so the user can check the model glass."""
    # (LASFN30, the glass of the real file this case comes from, is now a shipped SCHOTT
    # glass: LASF9 is in no catalog.)
    text = _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS LASF9 0 0 1.6204 60.32 0 0 0")
    with pytest.warns(ZmxWarning, match=r"<zmx>:9: glass 'LASF9' is in no catalog.*These are "
                                        r"the nd and Vd of SCHOTT N-SK16: .* check that they "
                                        r"are LASF9's"):
        zmx.loads(text, unknown_glass="model")
    other = text.replace("1.6204 60.32", "1.8 41.0")  # no catalog glass has exactly these
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        zmx.loads(other, unknown_glass="model")
    assert caught and not any("These are" in str(w.message) for w in caught)


@pytest.mark.parametrize("gcat, glass", [
    ("OHARA", "S-LAH64"), ("HOYA", "TAFD30"), ("HIKARI", "E-LAFH3"), ("SUMITA", "K-SFLD6"),
    ("CDGM", "H-ZK3A"), ("SCHOTT", "B270"), ("CORNING", "C79-80"),
])
def test_maker_catalog_glasses_load_and_round_trip(gcat, glass):
    text = f"GCAT {gcat}\n" + _minimal("  CURV 0.02\n").replace("GLAS N-BK7", f"GLAS {glass}")
    lens = zmx.loads(text)
    m = lens.materials[0]
    assert (m.name, m.catalog) == (glass, gcat)
    written, _ = zmx.dumps(lens)
    assert f"GCAT {gcat}" in written and f"GLAS {glass}" in written
    assert_same_lens(lens, zmx.loads(written))


@pytest.mark.parametrize("gcat, catalog", [
    ("SCHOTT", "SCHOTT"), ("HIKARI", "HIKARI"), ("NIKON", "HIKARI"), ("CDGM", "CDGM"),
    ("SUMITA_AUG2011 SCHOTT_2000", "SCHOTT"),  # dated catalogs are their maker's
    ("LIGHTPATH SUMITA", "SCHOTT"),  # neither holds an F2: found elsewhere, with a warning
])
def test_gcat_picks_the_catalog_of_a_shared_name(gcat, catalog):
    text = f"GCAT {gcat}\n" + _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS F2")
    if not gcat.startswith("LIGHTPATH"):
        assert zmx.loads(text).materials[0].catalog == catalog
        return
    with pytest.warns(ZmxWarning, match=r":\d+: glass 'F2' is not in the file's catalogs "
                      r"\(LIGHTPATH, SUMITA\); using SCHOTT F2 \(nd 1.620"):
        assert zmx.loads(text).materials[0].catalog == catalog
    with pytest.raises(ValueError, match="not in the file's catalogs.*strict mode"):
        zmx.loads(text, strict=True)


def test_a_discontinued_schott_glass_becomes_its_successor_with_a_warning():
    """LAF21 is not in the shipped SCHOTT catalog (neither its 2013 nor its 2008 glasses):
    N-LAF21 (its lead-free successor) stands in, with a warning, rather than a glass of the
    same name from another maker; strict mode refuses."""
    text = "GCAT SCHOTT\n" + _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS LAF21")
    with pytest.warns(ZmxWarning, match=r"glass 'LAF21' is not in the shipped SCHOTT catalog "
                      r"\(a discontinued glass\); using its lead-free successor N-LAF21"):
        m = zmx.loads(text).materials[0]
    assert (m.name, m.catalog) == ("N-LAF21", "SCHOTT")
    with pytest.raises(ValueError, match="N-LAF21.*strict mode"):
        zmx.loads(text, strict=True)
    # KZFS4 exists in HIKARI: SCHOTT's successor wins for a file that names SCHOTT.
    text = "GCAT SCHOTT\n" + _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS KZFS4")
    with pytest.warns(ZmxWarning, match="N-KZFS4"):
        m = zmx.loads(text).materials[0]
    assert (m.name, m.catalog) == ("N-KZFS4", "SCHOTT")
    # BAF4 exists in CDGM as another glass (nd 1.583 against SCHOTT's 1.606): a file that
    # names SCHOTT gets SCHOTT's own (obsolete) BAF4, without a report.
    text = "GCAT SCHOTT\n" + _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS BAF4")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = zmx.loads(text, strict=True).materials[0]
    assert (m.name, m.catalog, m.catalog_nd) == ("BAF4", "SCHOTT", 1.605621)


def test_model_glass_and_tabulated_read_back_exactly(tmp_path):
    lens = zmx.loads(
        _minimal("  CURV 0.02\n").replace(
            "GLAS N-BK7", "GLAS ___BLANK 1 0 1.5168 6.417E+001 0 0 0 0 0 0"
        )
    )
    m = lens.materials[0]
    assert isinstance(m, ModelGlass) and float(m.index(0.5875618)) == 1.5168
    assert float(m.vd) == 64.17
    lens = jaxlens.load(DATA / "cooke_triplet.json")
    tables = tuple(
        m
        if m.name == "air"
        else Tabulated(lens.wavelengths, m.index(lens.wavelengths), name=m.name)
        for m in lens.materials
    )
    lens = dataclasses.replace(lens, materials=tables, description="")  # (not in a .zmx)
    jaxlens.save(lens, tmp_path / "t.zmx")
    assert_same_lens(_as_read(lens), jaxlens.load(tmp_path / "t.zmx"))


def test_header_follows_zemax_system_lines(tmp_path):
    """FTYP, XFLN/YFLN, FWGN, WAVM, PWAV, UNIT and ENPD as OpticStudio defines them, on a lens
    with 2 fields and 5 wavelengths (unequal counts: a swap cannot pass).

    The system lines of a .zmx file (OpticStudio's "ZMX file format" conventions, also how
    independent readers such as rayoptics parse them): ``UNIT MM …`` (lens units first),
    ``ENPD d`` (entrance pupil diameter, lens units), ``FTYP type telecentric n_fields
    n_wavelengths normalisation …`` with type 0 = angle in degrees, ``XFLN``/``YFLN`` the
    field values, ``FWGN`` one weight per field, ``WAVM i λ_µm weight`` per wavelength and
    ``PWAV i`` the 1-based primary wavelength.
    """
    wl = (0.4861327, 0.5875618, 0.6562725, 0.4358343, 0.7065188)
    lens = jaxlens.Lens(
        surfaces=(jaxlens.Sphere(1 / 30.0), jaxlens.Stop(4.0), jaxlens.Sphere(-1 / 45.0)),
        thickness=jnp.array([3.0, 2.0, 40.0]),
        materials=(jaxlens.get_material("N-BK7"), jaxlens.Air(), jaxlens.Air()),
        stop=1, epd=8.0, fields=jnp.array([0.0, 12.5]), wavelengths=jnp.array(wl), primary=1,
    )
    text, _ = zmx.dumps(lens, tmp_path / "two_five.zmx")
    head = {ln.split()[0]: ln.split()[1:] for ln in text.splitlines()
            if ln and not ln.startswith(" ") and ln.split()[0] not in ("WAVM", "SURF")}
    assert head["UNIT"][0] == "MM"
    assert float(head["ENPD"][0]) == 8.0
    ftyp = [int(v) for v in head["FTYP"]]
    assert ftyp[:5] == [0, 0, 2, 5, 0]  # angles, not telecentric, 2 fields, 5 wavelengths
    assert [float(v) for v in head["YFLN"][:2]] == [0.0, 12.5]
    assert [float(v) for v in head["XFLN"][:2]] == [0.0, 0.0]
    assert [float(v) for v in head["FWGN"][:2]] == [1.0, 1.0]
    # XFLN, YFLN and FWGN are parallel lists, one entry per field slot.
    assert len(head["XFLN"]) == len(head["YFLN"]) == len(head["FWGN"]) >= 2
    wavm = [ln.split() for ln in text.splitlines() if ln.startswith("WAVM")]
    assert [int(w[1]) for w in wavm] == [1, 2, 3, 4, 5]
    np.testing.assert_allclose([float(w[2]) for w in wavm], wl, rtol=1e-12)  # µm
    assert all(float(w[3]) == 1.0 for w in wavm)
    assert head["PWAV"] == ["2"]
    stop_surf = text.split("SURF 2\n")[1].split("SURF 3")[0]
    assert "  STOP" in stop_surf  # Zemax numbers surfaces from 0 (the object)
    back = zmx.loads(text)
    np.testing.assert_allclose(np.asarray(back.fields), [0.0, 12.5])
    np.testing.assert_allclose(np.asarray(back.wavelengths), wl)
    assert back.primary == 1 and back.stop == 1


# Zemax's AGF dispersion formula numbers (OpticStudio manual, "Glass catalog" chapter) and a
# direct numpy evaluation of each formula, λ in µm: independent of jaxlens's own tables.
def _l(w):
    return 1.0 / (w * w - 0.028)


FORMULAS = {
    "Schott": (1, [2.27, -0.0101, 0.0107, 2.2e-4, -7.6e-6, 4.9e-7],
               lambda a, w: np.sqrt(a[0] + a[1] * w**2 + a[2] / w**2 + a[3] / w**4
                                    + a[4] / w**6 + a[5] / w**8)),
    "Sellmeier1": (2, [1.04, 0.006, 0.23, 0.02, 1.01, 103.6],
                   lambda a, w: np.sqrt(1 + sum(a[2 * i] * w**2 / (w**2 - a[2 * i + 1])
                                                for i in range(3)))),
    "Herzberger": (3, [1.50, 0.004, 1e-4, -3e-3, 2e-5, -1e-7],
                   lambda a, w: a[0] + a[1] * _l(w) + a[2] * _l(w) ** 2 + a[3] * w**2
                   + a[4] * w**4 + a[5] * w**6),
    "Sellmeier2": (4, [1.2, 0.1, 0.12, 0.01, 0.15],
                   lambda a, w: np.sqrt(1 + a[0] + a[1] * w**2 / (w**2 - a[2] ** 2)
                                        + a[3] / (w**2 - a[4] ** 2))),
    "Conrady": (5, [1.49, 0.005, 1e-4], lambda a, w: a[0] + a[1] / w + a[2] / w**3.5),
    "Sellmeier3": (6, [1.0, 0.006, 0.2, 0.02, 0.9, 100.0, 0.01, 0.05],
                   lambda a, w: np.sqrt(1 + sum(a[2 * i] * w**2 / (w**2 - a[2 * i + 1])
                                                for i in range(4)))),
    "Handbook1": (7, [2.2, 0.011, 0.012, 0.01],
                  lambda a, w: np.sqrt(a[0] + a[1] / (w**2 - a[2]) - a[3] * w**2)),
    "Handbook2": (8, [2.2, 0.011, 0.012, 0.01],
                  lambda a, w: np.sqrt(a[0] + a[1] * w**2 / (w**2 - a[2]) - a[3] * w**2)),
    "Sellmeier4": (9, [2.0, 0.2, 0.02, 0.9, 100.0],
                   lambda a, w: np.sqrt(a[0] + a[1] * w**2 / (w**2 - a[2])
                                        + a[3] * w**2 / (w**2 - a[4]))),
    "Sellmeier1_2terms": (2, [1.04, 0.006, 0.23, 0.02],
                          lambda a, w: np.sqrt(1 + sum(a[2 * i] * w**2 / (w**2 - a[2 * i + 1])
                                                       for i in range(len(a) // 2)))),
    "Extended": (10, [2.27, -0.01, 0.0107, 2e-4, -7e-6, 5e-7, 1e-8, -1e-9],
                 lambda a, w: np.sqrt(sum(c * w**p for c, p in zip(
                     a, (0, 2, -2, -4, -6, -8, -10, -12), strict=True)))),
    "Extended2": (12, [2.27, -0.01, 0.0107, 2e-4, -7e-6, 5e-7, 1e-5, -1e-6],
                  lambda a, w: np.sqrt(sum(c * w**p for c, p in zip(
                      a, (0, 2, -2, -4, -6, -8, 4, 6), strict=True)))),
    "Extended3": (13, [2.27, -0.01, 1e-5, 0.0107, 2e-4, -7e-6, 5e-7, 1e-8, -1e-9],
                  lambda a, w: np.sqrt(sum(c * w**p for c, p in zip(
                      a, (0, 2, 4, -2, -4, -6, -8, -10, -12), strict=True)))),
    "Sellmeier5": (11, [1.0, 0.006, 0.2, 0.02, 0.9, 100.0, 0.01, 0.05, 0.001, 0.1],
                   lambda a, w: np.sqrt(1 + sum(a[2 * i] * w**2 / (w**2 - a[2 * i + 1])
                                                for i in range(5)))),
}


def _material_of(kind, coeffs, name):
    from jaxlens.optics import materials as M

    if kind.startswith("Sellmeier") and kind not in ("Sellmeier2", "Sellmeier4"):
        return M.Sellmeier(coeffs[0::2], coeffs[1::2], name=name)
    if kind.startswith("Extended"):
        powers = {"Extended": M.EXTENDED_POWERS, "Extended2": M.EXTENDED2_POWERS,
                  "Extended3": M.EXTENDED3_POWERS}[kind]
        return M.Laurent(coeffs, powers=powers, name=name)
    return getattr(M, kind)(coeffs, name=name)


def _singlet(glass):
    """A biconvex singlet of ``glass`` in air, for writing one glass to an AGF."""
    return jaxlens.Lens(surfaces=(Standard(c=0.02), Standard(c=-0.02), Standard(c=0.0)),
                        thickness=[3.0, 40.0, 0.0], materials=(glass, Air(), Air()), epd=5.0)


def _assert_same_indices(a, b, w):
    """Every medium of lenses ``a`` and ``b`` has the same index at wavelengths ``w``."""
    for m0, m1 in zip(a.materials, b.materials, strict=True):
        np.testing.assert_allclose(np.asarray(m1.index(w)), np.asarray(m0.index(w)), rtol=0,
                                   atol=1e-12)


def _agf_record(path):
    """(formula number, CD coefficients) of the one glass in an AGF file, read as Zemax would
    (the NM and CD lines; jaxlens's own GC record is not looked at)."""
    lines = pathlib.Path(path).read_text().splitlines()
    # Only AGF record keywords (comment, name, jaxlens's own record, extra, dispersion,
    # thermal and range data), and a glass's NM/ED/CD/TD records in the catalog's order.
    assert {ln.split()[0] for ln in lines} <= {"CC", "NM", "GC", "ED", "CD", "TD", "LD"}
    keys = [ln.split()[0] for ln in lines if ln.split()[0] in ("NM", "ED", "CD", "TD")]
    assert keys == ["NM", "ED", "CD", "TD"]
    (nm,) = [ln.split() for ln in lines if ln.startswith("NM ")]
    (cd,) = [ln.split() for ln in lines if ln.startswith("CD ")]
    return int(nm[2]), np.array([float(v) for v in cd[1:]])


@pytest.mark.parametrize("kind", sorted(FORMULAS))
def test_hand_made_glass_is_written_with_zemaxs_formula_number(kind, tmp_path):
    """A glass of each dispersion formula goes to the lens's AGF under the formula number of
    the Zemax manual, with coefficients that give the same index as the formula by hand."""
    number, coeffs, by_hand = FORMULAS[kind]
    glass = _material_of(kind, coeffs, f"MY {kind}")
    w = np.linspace(0.45, 0.70, 6)
    np.testing.assert_allclose(np.asarray(glass.index(w)), by_hand(np.asarray(coeffs), w),
                               rtol=0, atol=1e-13)
    lens = _singlet(glass)
    written = jaxlens.save(lens, tmp_path / "one.zmx")
    form, cd = _agf_record(next(p for p in written if str(p).endswith("ONE.AGF")))
    assert form == number
    # The CD line holds the formula's coefficients: Sellmeier 1 always three (K, L) pairs.
    assert cd.size == (6 if number == 2 else len(coeffs))
    cd = cd[: len(coeffs)]
    np.testing.assert_allclose(by_hand(cd, w), np.asarray(glass.index(w)), rtol=0, atol=1e-12)


def test_sellmeier_with_more_terms_than_zemax_has_goes_as_a_fitted_schott_series(tmp_path):
    """Six Sellmeier terms have no Zemax formula: the writer falls back to a fitted series."""
    from jaxlens.optics.materials import Sellmeier

    glass = Sellmeier([1.0, 0.006, 0.2, 0.02, 0.9, 0.001],
                      [0.006, 0.02, 100.0, 0.05, 0.01, 0.03], name="SIX")
    lens = _singlet(glass)
    written = jaxlens.save(lens, tmp_path / "six.zmx")
    form, cd = _agf_record(next(p for p in written if str(p).endswith("SIX.AGF")))
    assert form == 1 and cd.size == 6
    w = np.linspace(0.45, 0.70, 6)
    np.testing.assert_allclose(FORMULAS["Schott"][2](cd, w), np.asarray(glass.index(w)),
                               rtol=0, atol=1e-6)  # the fit is good to 1e-7 here


def test_a_glass_without_dispersion_is_written_with_vd_0(tmp_path):
    """Zemax reads Vd = 0 as no dispersion; (nd − 1)/(nF − nC) would divide by zero."""
    from jaxlens.optics.materials import Sellmeier

    glass = Sellmeier([1.25], [0.0], name="FLAT")  # n² = 2.25 at every wavelength
    lens = _singlet(glass)
    written = jaxlens.save(lens, tmp_path / "flat.zmx")
    text = pathlib.Path(written[1]).read_text()
    nm = next(ln.split() for ln in text.splitlines() if ln.startswith("NM "))
    assert float(nm[4]) == pytest.approx(1.5, abs=1e-15) and float(nm[5]) == 0.0


def test_side_catalog_and_glass_names(tmp_path):
    """The lens's own AGF is named after the file (Zemax catalog names: letters, digits, _),
    gets "_JL" when that name is a Zemax catalog, and two different glasses of one name are
    kept apart as NAME and NAME_2; the NM line carries each glass's nd and Vd."""
    from jaxlens.optics.materials import Sellmeier

    a = Sellmeier([1.04, 0.23], [0.006, 0.02], name="mine")
    b = Sellmeier([1.10, 0.20], [0.006, 0.02], name="MINE")
    lens = jaxlens.Lens(
        surfaces=(Standard(c=0.02), Standard(c=-0.02), Standard(c=0.01), Standard(c=-0.01),
                  Standard(c=0.0)),
        thickness=[3.0, 2.0, 3.0, 30.0, 0.0], materials=(a, Air(), b, Air(), Air()), epd=5.0)
    written = jaxlens.save(lens, tmp_path / "my-lens.v2.zmx")
    agf = pathlib.Path(written[1])
    assert agf.name == "MY_LENS_V2.AGF"
    text = agf.read_text()
    nm = [ln.split() for ln in text.splitlines() if ln.startswith("NM ")]
    assert [t[1] for t in nm] == ["MINE", "MINE_2"]
    zmx_text = pathlib.Path(written[0]).read_text()
    assert "GCAT MY_LENS_V2" in zmx_text
    assert [ln.split()[1] for ln in zmx_text.splitlines() if ln.strip().startswith("GLAS")] \
        == ["MINE", "MINE_2"]
    for t, glass in zip(nm, (a, b), strict=True):
        nd, nf, nc = (float(glass.index(w)) for w in (0.5875618, 0.4861327, 0.6562725))
        assert float(t[4]) == pytest.approx(nd, abs=1e-12)
        assert float(t[5]) == pytest.approx((nd - 1) / (nf - nc), rel=1e-10)
        # The six-digit glass code: 1000·(nd − 1) and 10·Vd, rounded (N-BK7 is 517642).
        assert t[3] == f"{round(1000 * (nd - 1)):03d}{round(10 * (nd - 1) / (nf - nc)):03d}"
    back = jaxlens.load(written[0])
    assert_same_lens(back, _as_read(lens))
    # A file named after a Zemax catalog does not shadow it.
    (tmp_path / "s").mkdir()
    written = jaxlens.save(lens, tmp_path / "s" / "schott.zmx")
    assert pathlib.Path(written[1]).name == "SCHOTT_JL.AGF"


def test_user_catalog_glasses_share_their_catalog_and_unnamed_glasses_get_a_name(tmp_path):
    """Two glasses of one user AGF catalog, one of them used twice, go to that catalog once
    each. A glass with the name of one of them but other data goes to the lens's own catalog
    under another name: Zemax finds a GLAS name in the first GCAT catalog that has it, so a
    name must mean one glass in the whole file. An unnamed hand-made glass is JLGLASS. The
    own catalog's LD line spans 0.3–2.5 µm and every system wavelength."""
    from jaxlens.optics.materials import Sellmeier

    agf = tmp_path / "MYCAT.agf"
    agf.write_text(
        "CC test catalog\n"
        "NM ONE 2 517642 1.5168 64.17 0 1\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
        "LD 0.3 3.2\n"
        "NM TWO 2 523648 1.52299 64.8 0 1\n"  # nd, Vd: the CD record's at the d, F, C lines
        "CD 1.06 0.006 0.23 0.02 1.01 103.5\n"
        "LD 0.3 3.2\n"
    )
    cat = load_agf(agf)
    other = tmp_path / "other"
    other.mkdir()
    (other / "MYCAT.agf").write_text(
        "NM ONE 2 569680 1.56907 68.03 0 1\nCD 1.2 0.006 0.23 0.02 1.01 103.5\nLD 0.3 3.2\n")
    clash = load_agf(other / "MYCAT.agf")["ONE"]  # same catalog and name, other data
    mats = (cat["ONE"], Air(), cat["TWO"], Air(), cat["ONE"], Air(), clash, Air(),
            Sellmeier([1.04, 0.23], [0.006, 0.02]), Air(), Air())
    n = len(mats)
    lens = jaxlens.Lens(
        surfaces=tuple(Standard(c=0.01 * (-1) ** i) for i in range(n - 1)) + (Standard(c=0.0),),
        thickness=[2.0] * (n - 1) + [0.0], materials=mats, epd=4.0,
        wavelengths=[0.45, 0.55, 2.8], primary=1)
    paths = jaxlens.save(lens, tmp_path / "u.zmx")
    written = {pathlib.Path(p).name: pathlib.Path(p) for p in paths}
    assert set(written) == {"u.zmx", "MYCAT.AGF", "U.AGF"}

    def names(p):
        return [ln.split()[1] for ln in p.read_text().splitlines() if ln.startswith("NM ")]

    assert names(written["MYCAT.AGF"]) == ["ONE", "TWO"]
    assert names(written["U.AGF"]) == ["ONE_2", "JLGLASS"]
    glas = [ln.split()[1] for ln in written["u.zmx"].read_text().splitlines()
            if ln.strip().startswith("GLAS")]
    assert glas == ["ONE", "TWO", "ONE", "ONE_2", "JLGLASS"]
    ld = [ln.split() for ln in written["U.AGF"].read_text().splitlines() if ln.startswith("LD")]
    assert all((float(t[1]), float(t[2])) == (0.3, 2.8) for t in ld)
    back = jaxlens.load(written["u.zmx"])
    w = np.array([0.45, 0.55, 2.8])
    _assert_same_indices(lens, back, w)


def test_a_hand_made_glass_never_shadows_a_catalog_glass_of_its_name(tmp_path):
    from jaxlens.optics.catalog import get_material
    from jaxlens.optics.materials import Sellmeier

    fake = Sellmeier([1.2, 0.2], [0.006, 0.02], name="N-BK7")  # before the real one
    lens = jaxlens.Lens(
        surfaces=(Standard(c=0.02), Standard(c=-0.02), Standard(c=0.01), Standard(c=-0.01),
                  Standard(c=0.0)),
        thickness=[3.0, 2.0, 3.0, 30.0, 0.0],
        materials=(fake, Air(), get_material("N-BK7"), Air(), Air()), epd=5.0)
    written = jaxlens.save(lens, tmp_path / "f.zmx")
    glas = [ln.split()[1] for ln in pathlib.Path(written[0]).read_text().splitlines()
            if ln.strip().startswith("GLAS")]
    assert glas == ["N-BK7_2", "N-BK7"]
    back = jaxlens.load(written[0])
    w = np.array([0.48, 0.59, 0.66])
    _assert_same_indices(lens, back, w)


def test_even_asphere_type_follows_the_term_count_and_the_image_takes_no_break():
    """Zemax's EVENASPH holds 8 terms (PARM 1–8, r² … r¹⁶); more go to the extended
    asphere. A coordinate break cannot be the image surface."""
    eight = zmx.surface_lines(EvenAsphere(c=0.01, k=0.0, coeffs=[1e-9] * 8))
    assert eight[0] == "TYPE EVENASPH"
    assert [ln.split()[1] for ln in eight if ln.startswith("PARM")] == [str(i) for i in range(1, 9)]
    assert zmx.surface_lines(EvenAsphere(c=0.01, k=0.0, coeffs=[1e-9] * 9))[0] == "TYPE XASPHERE"
    with pytest.raises(ValueError, match="no .zmx form"):
        zmx.surface_lines(jaxlens.CoordinateBreak(tilt_x=5.0), image=True)


@pytest.mark.parametrize("disz, at_infinity", [("1E+20", True), ("1.0E10", True),
                                               ("9.9E9", False)])
def test_object_distance_of_1e10_or_more_is_infinity(disz, at_infinity):
    """Zemax reads object thicknesses of 1e10 and more as infinite (OpTaliX writes 1e20);
    a finite 1e20 mm object gave rays that no float can aim (NaN spots)."""
    lens = zmx.loads(_minimal("  CURV 0.02\n").replace("DISZ INFINITY", f"DISZ {disz}"))
    assert lens.object_at_infinity is at_infinity
    if at_infinity:
        spot = jaxlens.analysis.rms_spot(lens)
        assert np.all(np.isfinite(np.asarray(spot.polychromatic)))  # the rays trace
        assert np.all(np.asarray(spot.valid_fraction) == 1.0)


def test_vendor_files_without_type_lines_and_with_family_glass_names():
    """An Edmund-style file: no TYPE line (a STANDARD surface) and GLAS family|glass."""
    text = "VERS 130404\n" + _minimal("  CURV 0.02\n").replace(
        "GLAS N-BK7", "GLAS SCHOTT-BK|N-BK7").replace("SURF 0\n", "SURF 0\n  CURV 0.0\n")
    text = text.replace("SURF 3\n", "SURF 3\n  CURV 0.0\n  DISZ 0\n")
    text = re.sub(r"(SURF [12]\n)", r"\1", text)
    lens = zmx.loads(text)
    assert lens.materials[0].name == "N-BK7"
    assert float(lens.surfaces[0].c) == 0.02
    # A block cut before its DISZ is still a truncated file.
    with pytest.raises(ValueError, match=r"surface 2 has no DISZ line"):
        zmx.loads(text.replace("  DISZ 45\n", ""))


def test_a_multi_configuration_file_is_reported_once_and_its_operands_are_known():
    """A zoom lens's MNUM and its THIC operands: one report that the other configurations
    are ignored (an error under strict), not one 'unknown keyword' per operand line."""
    extra = "MNUM 2 1\nTHIC 2 0 0 0 0 0 0 0\nTHIC 2 0 0 0 0 0 0 0\nCSUM 1693307950\n"
    text = _minimal("  CURV 0.02\n").replace("ENPD 10\n", "ENPD 10\n" + extra)
    with pytest.warns(ZmxWarning) as caught:
        zmx.loads(text)
    msgs = [str(w.message) for w in caught]
    assert len(msgs) == 1 and re.search(r"<zmx>:3: a multi-configuration file \(2 "
                                        r"configurations", msgs[0]), msgs
    with pytest.raises(ValueError, match="multi-configuration.*strict mode"):
        zmx.loads(text, strict=True)
    # One configuration as OpticStudio writes it (MNUM 1 1 and a MOFF row): nothing to say.
    # (The rows above give configuration 0, malformed in the operand layout read since,
    # ``OPER param configuration value``: under MNUM 1 they are reported too.)
    single = text.replace("MNUM 2 1", "MNUM 1 1")
    zmx.loads(single.replace("THIC 2 0 0 0 0 0 0 0\nTHIC 2 0 0 0 0 0 0 0\n",
                             'MOFF   0   1 "" 0 0 0 1 1 0 0.0 "" 0\n'))
    with pytest.warns(ZmxWarning, match=r"<zmx>:3: a file of 1 configuration \(MNUM\)"):
        zmx.loads(single)


# ---------------------------------------------------------------------------- IR catalogs


def test_gcat_infrared_znse_singlet_opens_and_traces_at_10_6_um(tmp_path):
    # A CO2-laser singlet as Zemax writes it: the INFRARED catalog, ZnSe with the catalog's
    # "no d-line data" nd 1, Vd 0 on the GLAS line, wavelength 10.6 µm.
    text = (
        "UNIT MM\nENPD 10\nGCAT INFRARED\nWAVM 1 10.6 1\nSURF 0\n  DISZ INFINITY\n"
        "SURF 1\n  CURV 0.01\n  DISZ 4\n  GLAS ZNSE 0 0 1 0 0 0 0 0 0 0\n  DIAM 8\n"
        "SURF 2\n  DISZ 70\n  DIAM 8\nSURF 3\n"
    )
    p = tmp_path / "co2.zmx"
    p.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: the name is in the file's catalog
        lens = jaxlens.load(p)
    m = lens.materials[0]
    assert (m.name, m.catalog, m.wavelength_range) == ("ZNSE", "INFRARED", (0.55, 18.0))
    assert float(m.index(10.6)) == pytest.approx(2.4028, abs=1e-3)
    rays = jaxlens.analysis.spot_rays(lens, 0.0, 10.6)
    assert bool(np.all(rays.valid))
    # f = 1 / ((n - 1) c) for a thin plano-convex lens: about 71 mm; the rays meet near there.
    assert float(np.max(np.abs(np.asarray(rays.origin)[:, :2]))) < 0.5
    written, _ = zmx.dumps(lens)
    assert "GCAT INFRARED" in written and "GLAS ZNSE" in written


def test_gcat_infrared_takes_its_own_baf2_and_other_files_keep_cdgms():
    text = _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS BAF2")
    assert zmx.loads("GCAT INFRARED\n" + text).materials[0].catalog == "INFRARED"
    assert zmx.loads("GCAT CDGM\n" + text).materials[0].catalog == "CDGM"
    assert zmx.loads("GCAT INFRARED CDGM\n" + text).materials[0].catalog == "INFRARED"
    # GCAT LIGHTPATH: LightPath's molded glass, no warning.
    lp = _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS ECO550 0 0 1.605503 50.28")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert zmx.loads("GCAT LIGHTPATH\n" + lp).materials[0].catalog == "LIGHTPATH"
    # A GLAS line's nd and Vd are not cross-checked against a catalog without d-line data.
    ge = _minimal("  CURV 0.02\n", head="ENPD 10\nWAVM 1 10 1\n").replace(
        "GLAS N-BK7", "GLAS GERMANIUM 0 0 4.0 100.0")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert zmx.loads("GCAT INFRARED\n" + ge).materials[0].name == "GERMANIUM"


# ------------------------------------------------------------------ LZOS and RAD_HARD catalogs


def test_gcat_lzos_soviet_glass_opens_and_gcat_rad_hard_takes_its_own_bk7g18(tmp_path):
    # A singlet as Zemax writes it with the LZOS catalog: LZ_K8 is in no other catalog.
    text = (
        "UNIT MM\nENPD 10\nGCAT LZOS\nWAVM 1 0.5875618 1\nSURF 0\n  DISZ INFINITY\n"
        "SURF 1\n  CURV 0.02\n  DISZ 4\n  GLAS LZ_K8 0 0 1.516367 63.840333 0 0 0 0 0 0\n"
        "  DIAM 8\nSURF 2\n  DISZ 95\n  DIAM 8\nSURF 3\n"
    )
    p = tmp_path / "k8.zmx"
    p.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: the name and nd/Vd are LZOS's
        lens = jaxlens.load(p)
    m = lens.materials[0]
    assert (m.name, m.catalog) == ("LZ_K8", "LZOS")
    assert float(m.index(0.5875618)) == pytest.approx(1.516367, abs=1e-5)
    assert "GCAT LZOS" in zmx.dumps(lens)[0]
    # BK7G18 is in SCHOTT and RAD_HARD: GCAT RAD_HARD takes RAD_HARD's record.
    bk = _minimal("  CURV 0.02\n").replace("GLAS N-BK7", "GLAS BK7G18")
    assert zmx.loads("GCAT RAD_HARD\n" + bk).materials[0].catalog == "RAD_HARD"
    assert zmx.loads("GCAT SCHOTT\n" + bk).materials[0].catalog == "SCHOTT"
    assert zmx.loads("GCAT RAD_HARD SCHOTT\n" + bk).materials[0].catalog == "RAD_HARD"


@pytest.mark.parametrize("old, new, line, match", [
    ("WAVM 2 5.875618E-1 1", "WAVM 2 5.875618E-1 2", 18, r"weighs its 3 wavelengths \(1, 2, 1\)"),
    ("FWGN 1 1 1 1", "FWGN 1 0.5 1 1", 17, r"weighs its 3 fields \(1, 0.5, 1\)"),
    # Older Zemax: WAVL and its weights in WWGT.
    ("WAVM 1 4.861327E-1 1\nWAVM 2 5.875618E-1 1\nWAVM 3 6.562725E-1 1\nWAVM 4 5.5E-1 1\n",
     "WAVL 0.4861327 0.5875618 0.6562725\nWWGT 1 3 1\n", 19,
     r"weighs its 3 wavelengths \(1, 3, 1\)"),
])
def test_unequal_field_and_wavelength_weights_are_reported(old, new, line, match):
    """A Lens holds no weights, so a file that weighs its wavelengths or fields unequally
    gets a warning naming the line; equal weights, and weights of unused fields (beyond
    FTYP's count), say nothing."""
    assert old in COOKE_ZMX
    with pytest.warns(zmx.ZmxWarning, match=rf"<zmx>:{line}: .*{match}"):
        lens = zmx.loads(COOKE_ZMX.replace(old, new))
    assert lens.wavelengths.shape == (3,)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        zmx.loads(COOKE_ZMX.replace("FWGN 1 1 1 1 1 1 1 1 1 1 1 1",
                                    "FWGN 1 1 1 0 0 0 0 0 0 0 0 0"))
