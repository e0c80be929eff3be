"""Round 42d (glass catalogs): SCHOTT's IRG22–IRG27 infrared chalcogenide glasses.

They are in the shipped INFRARED catalog (jaxlens/data/glass/INFRARED.agf, its section
headed "SCHOTT IRG22-IRG27"), from SCHOTT's product flyers as the refractiveindex.info
database (CC0) holds them: database/data/specs/schott/infrared/IRG2x.yml. The database's
Sellmeier forms (its formula 2, IRG23 its formula 1 with squared poles) are written exactly as
Zemax's formula 9, Sellmeier 4, n² = A + Bλ²/(λ² − C) + Dλ²/(λ² − E).

What can fail here: the conversion (A = 1 + C1, IRG23's squared poles), the wavelength ranges,
the "no d-line data" mark (the d line lies outside every range), and the glasses themselves,
checked against the catalogs of other makers' glasses of the same composition, which the
package ships from other sources (Zemax's INFRARED: AMTIR1; Zemax's RPO: Vitron IG2, IG4, IG5,
IG6): IRG22 is Ge33As12Se55 (AMTIR-1, IG2), IRG24 Ge10As40Se50 (IG4), IRG25 Ge28Sb12Se60
(IG5), IRG26 As40Se60 (IG6).
"""

import math
import warnings

import jax
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.io import zmx
from jaxlens.optics.catalog import get_material, glass_info

jax.config.update("jax_enable_x64", True)

# The database's coefficients C1..C5 and range, copied from its IRG2x.yml files (formula
# number first).
RII = {
    "IRG22": (2, (2.4834, 2.8203, 0.1352, 0.9773, 1420.7), (1.0, 12.0)),
    "IRG23": (1, (3.74971, 3.07065, 0.498392, 0.953206, 40.7557), (1.0, 12.0)),
    "IRG24": (2, (2.8965, 2.9567, 0.1620, 0.9461, 1939.1), (0.8, 12.0)),
    "IRG25": (2, (2.7574, 3.0990, 0.1596, 1.6660, 2045.5), (0.85, 12.0)),
    "IRG26": (2, (3.1934, 3.5854, 0.1852, 2.2337, 3398.08), (0.85, 12.0)),
    "IRG27": (2, (1.4005, 3.4429, 0.0871, 1.0394, 805.5), (0.6, 12.0)),
}


def _rii_index(formula, c, wl):
    """refractiveindex.info's formula 1 (poles squared) or 2, λ in µm."""
    w2 = wl * wl
    p1, p2 = (c[2] ** 2, c[4] ** 2) if formula == 1 else (c[2], c[4])
    return math.sqrt(1.0 + c[0] + c[1] * w2 / (w2 - p1) + c[3] * w2 / (w2 - p2))


@pytest.mark.parametrize("name", sorted(RII))
def test_irg_glasses_are_the_flyers_formula_over_their_range(name):
    formula, c, rng = RII[name]
    m = get_material(name)
    assert (m.catalog, m.formula, m.wavelength_range) == ("INFRARED", 9, rng)
    assert glass_info(name) == ("INFRARED", 1.0, 0.0)  # no d-line data: 0.5876 µm is outside
    wl = np.geomspace(rng[0], rng[1], 9)
    got = np.asarray(m.index(wl))
    want = np.array([_rii_index(formula, c, float(w)) for w in wl])
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)
    with pytest.raises(ValueError, match="range"):
        m.index(0.5875618)


@pytest.mark.parametrize("irg, same, catalog", [
    ("IRG22", "AMTIR1", "INFRARED"), ("IRG22", "IG2", "RPO"), ("IRG24", "IG4", "RPO"),
    ("IRG25", "IG5", "RPO"), ("IRG26", "IG6", "RPO")])
def test_irg_glasses_agree_with_other_makers_glasses_of_their_composition(irg, same, catalog):
    m, other = get_material(irg), get_material(same, catalog)
    for wl in (4.0, 8.0, 10.0, 12.0):
        assert abs(float(m.index(wl)) - float(other.index(wl))) < 1.2e-3, (wl, irg, same)


def test_irg_values_at_10_um():
    # The flyers' fits at 10 µm; As40Se60 (IRG26) as Vitron's IG6 data sheet gives 2.7775.
    at10 = {n: round(float(get_material(n).index(10.0)), 4) for n in RII}
    assert at10 == {"IRG22": 2.4967, "IRG23": 2.7869, "IRG24": 2.6089, "IRG25": 2.6030,
                    "IRG26": 2.7781, "IRG27": 2.3873}


LWIR = """VERS 190513
MODE SEQ
UNIT MM X W X CM MR CPMM
ENPD 20
GCAT {gcat}
FTYP 0 0 1 3 0 0 0
XFLN 0
YFLN 0
WAVM 1 8 1
WAVM 2 10 1
WAVM 3 12 1
PWAV 2
SURF 0
  CURV 0
  DISZ INFINITY
SURF 1
  STOP
  CURV 0.02
  DISZ 5
  GLAS IRG22 0 0 1 0 0 0 0 0 0 0
SURF 2
  CURV 0.005
  DISZ 2
SURF 3
  CURV -0.01
  DISZ 3
  GLAS IRG26 0 0 1 0 0 0 0 0 0 0
SURF 4
  CURV -0.004
  DISZ 40
SURF 5
  CURV 0
  DISZ 0
"""


def test_a_zmx_lens_of_irg_glasses_opens():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lens = zmx.loads(LWIR.format(gcat="INFRARED"))
    assert [str(w.message) for w in caught] == []
    assert [m.name for m in lens.materials if not isinstance(m, jl.Air)] == ["IRG22", "IRG26"]
    assert float(lens.indices(10.0)[1]) == pytest.approx(2.4967017, abs=1e-7)
    # With GCAT SCHOTT the name is found in INFRARED, and that is reported.
    with pytest.warns(zmx.ZmxWarning, match=r"glass 'IRG2[26]' is not in the file's catalogs "
                                            r"\(SCHOTT\); using INFRARED IRG2[26]"):
        zmx.loads(LWIR.format(gcat="SCHOTT"))
