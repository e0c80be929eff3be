"""What the seventh round of public .zmx files (/work/zmx_probe/corpus7, not committed: their
sources are in its SOURCES.txt) showed.

Twelve files: Thorlabs stock lenses of 2012 (achromats, a negative achromat with a virtual
image, aspheres, condensers with the stop after the lens) and three Zemax 2009 camera lenses
from patents (FusionOptics). Eleven opened, lenient and strict, and agreed with optiland
0.6.3 (EFL with the same indices to 1e-15; real rays to 1e-13 mm). Two classes of problem:

* ``GLAS 847238 0 0 1.5 4.0E+1`` (the Nikon 28-200 mm zoom): a glass named by its six-digit
  MIL number. OpticStudio reads such a name as a glass of that nd and Vd ("Using MIL number
  glasses" in its manual; the line's own nd 1.5, Vd 40 are its untouched defaults); jaxlens
  refused it as an unknown glass. It is now a ``ModelGlass`` of nd 1.847, Vd 23.8, exact at
  the d line like a ``___BLANK`` model glass. The zoom's EFL then equals optiland's with the
  same indices to 1e-15 (193.31 mm, its long end).
* The Nikon 105 mm f/2: surface 6 (R 26.2 mm, concave toward the stop) reaches 3.17 mm past
  its vertex at the height Zemax's automatic DIAM gives (12.48 mm), and the stop is 3 mm
  behind it. Zemax traces the rim rays back to the stop plane (a negative distance);
  jaxlens's tracer stopped them, so every ray beyond about 0.95 of the pupil was lost without
  a word. The reader first reported such a pair (a ``ZmxWarning``); the same check found it
  in two files of earlier rounds: Kraken's BE Gallel (a flat surface and a concave one 0 mm
  apart: every ray off the axis) and VendettaMask's double Gauss (surfaces 7 and 8). Now
  every lens read from a ``.zmx`` file has ``Lens.negative_propagation`` set and is traced as
  Zemax traces it (tests/test_zemax_crossing.py): such rays pass, equal to optiland's, and
  there is nothing left to report.

The snippets below are hand-written after those files (the numbers of a surface pair, not
the files); reference values are analytic or the files' own DIAMs.
"""

import math
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.materials import ModelGlass


def _efl(lens):
    return float(jl.paraxial_data(lens).efl_image_space)


def _singlet_efl(n, c1, c2, t):
    """Thick-lens focal length in air."""
    return 1 / ((n - 1) * (c1 - c2) + (n - 1) ** 2 * t * c1 * c2 / n)


def _caught(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn()
    return out, [str(w.message) for w in caught if issubclass(w.category, zmx.ZmxWarning)]


# ------------------------------------------------------------------- six-digit MIL numbers

def _mil_singlet(glass):
    # After the Nikon 28-200 mm file (VERS 90609): GLAS <MIL number> 0 0 1.5 4.0E+1.
    return ("VERS 90609 316 27347\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 1.0E+1\n"
            "GCAT SCHOTT\nFTYP 0 0 1 1 0 0 0\nXFLN 0\nYFLN 0\nWAVM 1 5.875618E-1 1\nPWAV 1\n"
            "SURF 0\n  TYPE STANDARD\n  CURV 0.0\n  DISZ INFINITY\n"
            "SURF 1\n  STOP\n  TYPE STANDARD\n  CURV 2.0E-2\n  DISZ 5\n"
            f"  GLAS {glass} 0 0 1.5 4.0E+1 0 0 0 0 0 0 \n"
            "SURF 2\n  TYPE STANDARD\n  CURV -1.0E-2\n  DISZ 50\n"
            "SURF 3\n  TYPE STANDARD\n  CURV 0.0\n  DISZ 0\n")


@pytest.mark.parametrize("name, nd, vd", [("847238", 1.847, 23.8), ("498825", 1.498, 82.5),
                                          ("620603", 1.620, 60.3)])
def test_mil_number_glass_is_a_model_glass_of_its_nd_and_vd(name, nd, vd):
    lens, warned = _caught(lambda: zmx.loads(_mil_singlet(name), "mil.zmx", strict=True))
    assert warned == []
    m = lens.materials[0]
    assert isinstance(m, ModelGlass)
    assert float(m.nd) == pytest.approx(nd, abs=1e-15)
    assert float(m.vd) == pytest.approx(vd, abs=1e-13)
    # Not the line's placeholder nd 1.5: the EFL is the thick lens's of n = nd at the d line.
    assert _efl(lens) == pytest.approx(_singlet_efl(nd, 0.02, -0.01, 5.0), rel=1e-12)


def test_mil_number_parsing():
    from jaxlens.io.zmx_glass import mil_number

    assert mil_number("847238") == pytest.approx((1.847, 23.8))
    assert mil_number("517642") == pytest.approx((1.517, 64.2))
    for other in ("517000", "84723", "8472385", "847238.5", "N-BK7", "S-LAH64", "-47238"):
        assert mil_number(other) is None, other


def test_a_glass_name_that_is_no_mil_number_is_still_refused():
    with pytest.raises(ValueError, match=r"mil\.zmx:20: glass 'X847238'"):
        zmx.loads(_mil_singlet("X847238"), "mil.zmx")


def test_a_catalog_glass_wins_over_a_mil_reading():
    # N-BK7 by name and 517642 (its MIL number) agree at the d line to the code's digits.
    named = zmx.loads(_mil_singlet("N-BK7"), "mil.zmx")
    coded = zmx.loads(_mil_singlet("517642"), "mil.zmx")
    assert not isinstance(named.materials[0], ModelGlass)
    n_named = float(named.materials[0].index(jnp.asarray(0.5875618)))
    n_coded = float(coded.materials[0].index(jnp.asarray(0.5875618)))
    assert n_coded == pytest.approx(1.517, abs=1e-12)
    assert abs(n_named - 1.517) < 5e-4


# ------------------------------------------------- surfaces that cross within the file's beam

def _pair(gap, diam_flag="0", stop_glass="", c6="3.822483850005733300E-002"):
    # After the Nikon 105 mm f/2 (patent 4,908,639): lens 3 (surfaces 5 and 6, a meniscus
    # whose rear is concave toward the stop), then the stop `gap` mm behind its vertex, then
    # lens 4. DIAMs are the file's (automatic, flag 0).
    return ("VERS 90609 397 27347\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 2.5E+1\n"
            "GCAT SCHOTT\nFTYP 0 0 1 1 0 0 0\nXFLN 0\nYFLN 0\nWAVM 1 5.5E-1 1\nPWAV 1\n"
            "SURF 0\n  TYPE STANDARD\n  CURV 0.0\n  DISZ INFINITY\n"
            "SURF 1\n  TYPE STANDARD\n  CURV 3.906890974300471600E-003\n  DISZ 3.0\n"
            "  GLAS ___BLANK 1 0 1.68893 3.108E+1 0 0 0 0 0 0 \n"
            f"  DIAM 1.408386069757E+1 {diam_flag} 0 0 1 \"\"\n"
            f"SURF 2\n  TYPE STANDARD\n  CURV {c6}\n  DISZ {gap}\n"
            f"  DIAM 1.248279631097E+1 {diam_flag} 0 0 1 \"\"\n"
            f"SURF 3\n  STOP\n  TYPE STANDARD\n  CURV 0.0\n  DISZ 3.0\n{stop_glass}"
            f"  DIAM 1.250112856315E+1 {diam_flag} 0 0 1 \"\"\n"
            "SURF 4\n  TYPE STANDARD\n  CURV -3.173897863966737600E-002\n  DISZ 3.0\n"
            "  GLAS ___BLANK 1 0 1.71736 2.946E+1 0 0 0 0 0 0 \n"
            "SURF 5\n  TYPE STANDARD\n  CURV -8.955758552749418600E-003\n  DISZ 60\n"
            "SURF 6\n  TYPE STANDARD\n  CURV 0.0\n  DISZ 0\n")


# optiland 0.6.3's points of the two rays of ``test_the_rim_ray_now_passes_as_in_optiland`` on
# each surface after the object (y, z in mm; x = 0), the snippet's media given jaxlens's
# indices (``tools/check_rays.py``'s ``set_media``), its DIAMs not clipping.
OPTILAND_HALF = [(6.25, 0.07631784201511582), (6.213266209961034, 3.7485376241467607),
                 (6.567957819242388, 6.0), (6.919396001567004, 8.230810721869872),
                 (7.571602531990286, 11.74299114071201), (24.127187044440088, 72.0)]
OPTILAND_RIM = [(12.5, 0.3054080632077776), (12.383659870327369, 6.116632158463459),
                (12.335934289717793, 6.0), (12.50464011273497, 6.412284649710469),
                (14.451834083710361, 11.06082049739745), (56.26545645534226, 72.0)]


def test_a_surface_reaching_past_the_stop_within_the_beam_is_traced_not_reported():
    # Before: "n105.zmx:21: surface 2 reaches past surface 3 …" (an error under strict). The
    # crossing is real (the sag at the smaller DIAM is 3.17 mm, the stop 3 mm behind the
    # vertex), and the lens now traces it as Zemax does: no report, strict or not.
    r = 1 / 3.822483850005733300e-2
    h = 1.248279631097e1
    assert r - math.sqrt(r * r - h * h) == pytest.approx(3.17018, abs=1e-5)
    for strict in (False, True):
        lens, warned = _caught(lambda s=strict: zmx.loads(_pair("3.0"), "n105.zmx", strict=s))
        assert warned == []
        assert lens.negative_propagation is True


@pytest.mark.slow
def test_the_rim_ray_now_passes_as_in_optiland():
    # Before: the rim ray (12.38 mm high on surface 2, inside its DIAM) was lost going back to
    # the stop plane. Now it goes back along its line (z from 6.117 to 6.0 mm) and both rays
    # equal optiland's on every surface. (A trace's compile: marked slow.)
    from jaxlens.imaging.sampling import field_rays
    from jaxlens.tracing.forward import trace_path
    lens, _ = _caught(lambda: zmx.loads(_pair("3.0"), "n105.zmx"))
    rays = field_rays(lens, jnp.asarray(0.0), jnp.asarray([[0.0, 0.5], [0.0, 1.0]]))
    path = trace_path(lens, rays)
    assert np.asarray(path.valid).all()
    p = np.asarray(path.origin)
    assert p[1, 1, 1] == pytest.approx(12.3837, abs=1e-4)
    assert p[2, 1, 2] < p[1, 1, 2]  # the stop plane lies behind the rim ray on surface 2
    for k, ref in enumerate((OPTILAND_HALF, OPTILAND_RIM)):
        np.testing.assert_allclose(p[:, k, 1:], np.asarray(ref), rtol=0, atol=1e-9)
        np.testing.assert_allclose(p[:, k, 0], 0.0, rtol=0, atol=1e-12)
    # The default rule (no longer the reader's) still loses the rim ray there.
    import dataclasses
    old = trace_path(dataclasses.replace(lens, negative_propagation=False), rays)
    assert np.asarray(old.valid[2]).tolist() == [True, False]


@pytest.mark.parametrize("case", ["wider gap", "fixed DIAMs", "negative gap", "flatter"])
def test_no_report_where_the_beam_does_not_cross(case):
    # Kept from when crossings were reported: these never were, and nothing is now.
    text = {"wider gap": _pair("3.2"),
            # Fixed DIAMs may be a mount's, larger than the beam: not taken for its height.
            "fixed DIAMs": _pair("3.0", diam_flag="1"),
            # A negative gap is traced backward on purpose (as Zemax does).
            "negative gap": _pair("-1.0"),
            "flatter": _pair("3.0", c6="3.0E-002")}[case]
    _, warned = _caught(lambda: zmx.loads(text, "n105.zmx", strict=case != "negative gap"))
    assert [w for w in warned if "reaches past" in w] == []


def _gallel(dummy=False):
    # After Kraken's BE Gallel: a flat surface, then 0 mm on, a surface concave toward it
    # that starts a lens (SF11): every ray off the axis meets it behind the flat one.
    text = ("VERS 60801\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 0.7\nGCAT SCHOTT\n"
            "FTYP 0 0 1 1 0 0 0\nXFLN 0\nYFLN 0\nWAVM 1 0.6328 1\nPWAV 1\n"
            "SURF 0\n  CURV 0\n  DISZ INFINITY\n"
            "SURF 1\n  STOP\n  CURV 0\n  DISZ 20\n  DIAM 0.35 0 0 0 1\n"
            "SURF 2\n  CURV 0\n  DISZ 0\n  DIAM 2.7 1 0 0 1\n"
            "SURF 3\n  CURV -1.026694045175E-001\n  DISZ 1.5\n  GLAS SF11\n  DIAM 3 1 0 0 1\n"
            "SURF 4\n  CURV 0\n  DISZ 10\nSURF 5\n  CURV 0\n  DISZ 0\n")
    return text.replace("  GLAS SF11\n", "") if dummy else text


def test_zero_gap_before_a_refracting_surface_is_traced_back_not_reported():
    # Before: "surface 2 reaches past surface 3 … height of 0.0027 mm" (every ray off the
    # axis was lost). Now neither the pair nor its dummy variant is reported, and a ray off
    # the axis goes back from the flat surface 2 to surface 3, at the height it had there.
    from jaxlens.tracing.forward import trace_path
    for dummy in (False, True):
        lens, warned = _caught(lambda d=dummy: zmx.loads(_gallel(d), "gallel.zmx", strict=True))
        assert warned == [] and lens.negative_propagation is True
    lens = zmx.loads(_gallel(), "gallel.zmx")
    o = jnp.asarray([[0.0, 0.3, -1.0], [0.0, 0.0, -1.0]])
    rays = jl.Rays(o, jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), o.shape), 0.6328)
    path = trace_path(lens, rays, upto=2)
    assert np.asarray(path.valid).all()
    p = np.asarray(path.origin)
    # Parallel to the axis through the flats: surface 3 (R = −9.74 mm, vertex at z = 20) is
    # met where its sag is, behind the flat surface 2 at z = 20.
    r = -1 / 1.026694045175e-1
    sag = r + math.sqrt(r * r - 0.3 * 0.3)  # r < 0: the sag is negative
    assert p[2, 0, 2] == pytest.approx(20.0 + sag, abs=1e-12) and sag < 0
    assert p[2, 0, 1] == pytest.approx(0.3, abs=1e-12)
