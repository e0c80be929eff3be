"""Freeform surfaces (``jaxlens.optics.freeform``): Zemax's biconic (``BICONICX``) and the
Zernike sag surfaces (``SZERNSAG``, ``FZERNSAG``).

Checked: the Noll (Zemax Standard) and Fringe index maps and the first terms against tables
written from the definitions; sag and unit normal against optiland 0.6.3 at scattered points
(recorded numbers, ``REF`` below); analytic cases (a biconic with equal sections is a
``Standard`` conic, a defocus term is a sphere to second order, even terms, decenter and the
extrapolate flag); the hand-written surface gradient against automatic differentiation;
real rays through small lenses against optiland's trace (same launch); ``.zmx`` and JSON round
trips, a hand-written ``.zmx`` of each type opened strict, bad values refused with the line;
gradients of a spot loss in every new coefficient against central differences.
"""

import math
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.io import lensfile
from jaxlens.optics import paraxial
from jaxlens.optics.freeform import Biconic, ZernikeSag, fringe_to_nm, noll_to_nm
from jaxlens.tracing.backward import mirror_surface

WL = 0.5875618

# optiland 0.6.3's numbers, printed by
#     /work/optiland_venv/bin/python tools/freeform_reference.py
# (see that script's docstring): sag and unit normal (+z at the vertex) of its
# ZernikePolynomialGeometry (Noll and Fringe coefficients on a conic, R = 40 mm, k = −0.6,
# normalisation radius 6 mm) and BiconicGeometry at ``points``, and image intercepts (mm) of
# three small lenses traced by optiland with Newton tolerance 1e-13 from ``launch``.
REF = {'points': [[0.0, 0.0], [1.3, 0.0], [0.0, -2.1], [2.2, 1.7], [-3.1, 2.6], [3.9, -3.3],
            [-0.4, -4.6], [-4.2, -1.1]],
 'noll': [-0.001148, 0.000805, 0.000538, 0.003226, -0.001687, -0.003259, -0.000805, 0.000209,
          -1.8e-05, -0.00085, -0.001329, 0.003838, 0.000298, -0.002038, -0.001431, 3.3e-05,
          0.003445, -0.002649, 0.001547, 0.001308, -0.001714, 0.0004, -0.000824, -6.2e-05,
          0.000671, 0.002987, -0.001884, 0.003638, -0.000659, 0.000306, -0.003437, -0.001691,
          0.002336, -0.000909, 0.000599, 0.003465, 0.001034, -0.001669, -1.8e-05, -0.00125,
          0.001114, 0.00158, 0.000287, 0.001427, -0.003722],
 'fringe': [-0.003112, -0.002042, -0.001293, 0.003751, 0.000606, -0.002545, -0.00109,
            -0.002115, -0.004428, 0.002236, -0.000289, -0.000946, -0.001221, -0.00093,
            0.000387, 0.000358, -0.001534, -0.000906, 0.003293, 0.00026, -0.00035, -0.000972,
            -0.004945, -0.000746, 0.001142, -0.001699, 0.004816, -0.001085, 0.002924,
            -0.001379, 0.00066, 0.000496, 0.002091, 0.000774, -0.000369, 0.000882],
 'z_base': {'radius': 40.0, 'conic': -0.6, 'norm_radius': 6.0},
 'biconics': {'parabolic': [60.0, 40.0, -1.0, -1.0],
              'cylinder_x_flat': [math.inf, 35.0, 0.0, -0.7],
              'cylinder_y_flat': [-45.0, math.inf, 1.3, 0.0],
              'general': [60.0, 40.0, -0.4, 0.8]},
 'zernike_sag': {'standard': [[-0.007663630771740255, 0.0006875301216782271,
                               -0.008662215931100217, 0.9999622459460631],
                              [0.012312265485198523, -0.030767931165398246,
                               -0.0023164794396542234, 0.9995238708179044],
                              [0.033206617156390464, -0.00424528959893093,
                               0.054162372093432935, 0.9985231168908578],
                              [0.08899313373453643, -0.046831631635911884,
                               -0.05186403552365787, 0.9975554721906542],
                              [0.21035769686838454, 0.0751848805714528, -0.0823901417737167,
                               0.9937600808404226],
                              [0.3224564406509068, -0.07947890060273705, 0.07756457455473738,
                               0.9938142890566238],
                              [0.2847112017166116, 0.012433390165468535, 0.12558176065896245,
                               0.9920053589566885],
                              [0.22103176617573456, 0.09212785909231161, 0.04503492909992746,
                               0.9947282607526698]],
                 'fringe': [[-0.011389, -0.0034996439024236213, -0.0008728276558240073,
                             0.9999934953110643],
                            [0.014012824261393381, -0.034227296583751725,
                             0.0006230587275635261, 0.9994138802149937],
                            [0.046583920263317126, -0.0027658423476834264, 0.05525349916157479,
                             0.9984685277696588],
                            [0.09045435716495283, -0.0547630129500665, -0.04458575133359115,
                             0.9975034452023962],
                            [0.2044052521786037, 0.08025452741940978, -0.062153701733658466,
                             0.9948347240569614],
                            [0.33121247686507416, -0.0978755475004661, 0.08281921196274666,
                             0.9917466185126893],
                            [0.26609725926941796, 0.012328145380786647, 0.11361888455908378,
                             0.9934479180626529],
                            [0.23683907142879967, 0.10138685729731114, 0.024459613381816618,
                             0.994546345064214]]},
 'biconic_sag': {'parabolic': [[0.0, -0.0, -0.0, 1.0],
                               [0.014083333333333335, -0.02166158280839028, -0.0,
                                0.9997653603872436],
                               [0.05512500000000001, -0.0, 0.05242779765904168,
                                0.9986247173150795],
                               [0.07645833333333334, -0.036609040072331116,
                                -0.04243320553838379, 0.9984283656090304],
                               [0.16458333333333336, 0.051489475884589735,
                                -0.06477708256448386, 0.9965705009920593],
                               [0.26287499999999997, -0.06464442352520731, 0.08204869139737851,
                                0.9945295926954971],
                               [0.2658333333333333, 0.0066228705688012755, 0.11424451731182199,
                                0.9934305853201912],
                               [0.162125, 0.06980286713151988, 0.027422554944525668,
                                0.9971838161645696]],
                 'cylinder_x_flat': [[0.0, -0.0, -0.0, 1.0], [0.0, -0.0, -0.0, 1.0],
                                     [0.06301701919160484, -0.0, 0.05992454258460372,
                                      0.9982029098314761],
                                     [0.04129302191568112, -0.0, -0.048531372055014316,
                                      0.9988216587191419],
                                     [0.09661143043638985, -0.0, -0.07414265107608552,
                                      0.997247645919212],
                                     [0.15567529198514854, -0.0, 0.09399371312700576,
                                      0.9955727908558962],
                                     [0.3026783464918644, -0.0, 0.13064112569239916,
                                      0.991429723317706],
                                     [0.017286995029416344, -0.0, 0.031417711753641754,
                                      0.9995063418448955]],
                 'cylinder_y_flat': [[0.0, 0.0, -0.0, 1.0],
                                     [-0.018786797451605795, 0.028904572982838554, -0.0,
                                      0.9995821755417009],
                                     [0.0, 0.0, -0.0, 1.0],
                                     [-0.053851889553550254, 0.048965019158693994, -0.0,
                                      0.9988004940421228],
                                     [-0.10707075038726145, -0.06910237818139923, -0.0,
                                      0.9976095735956401],
                                     [-0.16973626577572018, 0.08709291671630068, -0.0,
                                      0.996200192661017],
                                     [-0.0017778585532931305, -0.008889345439835557, -0.0,
                                      0.9999604889882657],
                                     [-0.19699170200573293, -0.09386633869612375, -0.0,
                                      0.9955848082708899]],
                 'general': [[0.0, -0.0, -0.0, 1.0],
                             [0.014084325174411426, -0.0216646326938541, -0.0,
                              0.9997652943017379],
                             [0.05519354236016093, -0.0, 0.05255797714734478,
                              0.9986178743834798],
                             [0.07649588118630996, -0.03662368729529323, -0.04250220687420751,
                              0.9984248934895998],
                             [0.1647766951777525, 0.051529821912515185, -0.06502362759870858,
                              0.9965523595414187],
                             [0.26337492879429303, -0.06472347067267654, 0.08255207192204515,
                              0.9944827941022713],
                             [0.2674264671225214, 0.006621905162489592, 0.11561068538922248,
                              0.9932725304748204],
                             [0.16223835485147198, 0.06990516616014593, 0.02744102730892656,
                              0.9971761417945946]]},
 'launch': {'origin': [[0.0, 0.0, -5.0], [2.8, 0.0, -5.0], [0.0, -2.8, -5.0], [2.0, 2.4, -5.0],
                       [-3.6, -1.2, -5.0], [0.0, -0.34963405971755207, -5.0],
                       [2.8, -0.34963405971755207, -5.0], [0.0, -3.149634059717552, -5.0],
                       [2.0, 2.0503659402824477, -5.0], [-3.6, -1.549634059717552, -5.0],
                       [-0.262038896415206, 0.0, -5.0], [2.5379611035847938, 0.0, -5.0],
                       [-0.262038896415206, -2.8, -5.0], [1.737961103584794, 2.4, -5.0],
                       [-3.862038896415206, -1.2, -5.0],
                       [-0.21830471454256029, 0.3058131007524215, -5.0],
                       [2.5816952854574398, 0.3058131007524215, -5.0],
                       [-0.21830471454256029, -2.494186899247578, -5.0],
                       [1.7816952854574397, 2.7058131007524215, -5.0],
                       [-3.8183047145425606, -0.8941868992475784, -5.0]],
            'direction': [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0],
                          [0.0, 0.0, 1.0], [0.0, 0.0697564737441253, 0.9975640502598243],
                          [0.0, 0.0697564737441253, 0.9975640502598243],
                          [0.0, 0.0697564737441253, 0.9975640502598243],
                          [0.0, 0.0697564737441253, 0.9975640502598243],
                          [0.0, 0.0697564737441253, 0.9975640502598243],
                          [0.05233595624294382, 0.0, 0.9986295347545737],
                          [0.05233595624294382, 0.0, 0.9986295347545737],
                          [0.05233595624294382, 0.0, 0.9986295347545737],
                          [0.05233595624294382, 0.0, 0.9986295347545737],
                          [0.05233595624294382, 0.0, 0.9986295347545737],
                          [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                          [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                          [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                          [0.043538182780866005, -0.06099065109629843, 0.9971883308176993],
                          [0.043538182780866005, -0.06099065109629843, 0.9971883308176993]]},
 'rays': {'biconic': [[0.0, 0.0, 45.0], [1.7900083883446563, 0.0, 45.0],
                      [0.0, -2.817502441232657, 45.0],
                      [1.2798239453331184, 2.4162364253618054, 45.0],
                      [-2.3031163414338853, -1.2095185886798412, 45.0],
                      [0.0, 3.164166738142338, 45.0],
                      [1.7857780686907296, 3.164844816179424, 45.0],
                      [0.0, 0.34522545770951574, 45.0],
                      [1.2747858294422012, 5.582342667678307, 45.0],
                      [-2.2994929215529156, 1.955102284253761, 45.0],
                      [2.2708706417143927, 0.0, 45.0], [4.056002137405354, 0.0, 45.0],
                      [2.2689867058831283, -2.8175231620114456, 45.0],
                      [3.5458275234265297, 2.4138801821124263, 45.0],
                      [-0.026207079398071542, -1.2116732250823834, 45.0],
                      [1.8920575630540302, -2.7674385671869217, 45.0],
                      [3.675446773028882, -2.7651828175495208, 45.0],
                      [1.8904901396898532, -5.586397603337511, 45.0],
                      [3.1677608102631596, -0.3504973576740391, 45.0],
                      [-0.40112794382487005, -3.9840127189267274, 45.0]],
          'zernike': [[-0.013010571993645898, -0.009150159912745905, 49.0],
                      [-0.29780544961245825, 0.026108560306204065, 49.0],
                      [-0.041567347591645896, 0.5109395462133977, 49.0],
                      [-0.19928180933094497, -0.5117449414453485, 49.0],
                      [0.478329406850857, 0.23232410452682495, 49.0],
                      [-0.012814034830139742, 3.241474822570409, 49.0],
                      [-0.31083497540671257, 3.278970384902466, 49.0],
                      [-0.04196357409641203, 3.804258281102801, 49.0],
                      [-0.2038825961463986, 2.7232191187149963, 49.0],
                      [0.4998414193949512, 3.5029533548521252, 49.0],
                      [2.4246757695127785, -0.009009141242544108, 49.0],
                      [2.1333749348868927, 0.025183102678911565, 49.0],
                      [2.399499527484962, 0.5177842821045102, 49.0],
                      [2.2338194985862487, -0.5153416799475883, 49.0],
                      [2.9482534637169344, 0.23983553088692755, 49.0],
                      [2.017367176574259, -2.8523995671921103, 49.0],
                      [1.7214873666463872, -2.811997327411548, 49.0],
                      [1.9838820167492544, -2.31990017274022, 49.0],
                      [1.8263984370653603, -3.377236534107664, 49.0],
                      [2.5361274982595514, -2.6130885386696345, 49.0]],
          'biconic_general': [[0.0, 0.0, 45.0], [0.5642042755951246, 0.0, 45.0],
                              [0.0, -1.2792544421322087, 45.0],
                              [0.40672061330497566, 1.0958292283606892, 45.0],
                              [-0.7120273815256373, -0.5470625724009904, 45.0],
                              [0.0, 3.029845897001237, 45.0],
                              [0.5552657654144117, 3.0349301191418774, 45.0],
                              [0.0, 1.7627235538372772, 45.0],
                              [0.4029084343297813, 4.116143537459978, 45.0],
                              [-0.6981078758923438, 2.496751941914871, 45.0],
                              [2.192934085736337, 0.0, 45.0], [2.759815437754226, 0.0, 45.0],
                              [2.1933244108619836, -1.2759975036848756, 45.0],
                              [2.5993401398405034, 1.0938132983652156, 45.0],
                              [1.5141362966708334, -0.5449121730750456, 45.0],
                              [1.8267585358883944, -2.6498959387527625, 45.0],
                              [2.3877232035329046, -2.648859042176391, 45.0],
                              [1.823470383066963, -3.9158613015784143, 45.0],
                              [2.2301835163785255, -1.5616759554455864, 45.0],
                              [1.145944503147137, -3.2054043666199394, 45.0]]}}


def _close(a, b, tol):
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=tol)


def _table(s, pts):
    """Sag and unit normal (+z at the vertex) at the points, as in ``REF``."""
    x, y = jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1])
    z, gx, gy, inside = s.sag_and_grad(x, y)
    assert bool(np.all(np.asarray(inside)))
    n = np.stack([-np.asarray(gx), -np.asarray(gy), np.ones(len(pts))], -1)
    return np.column_stack([np.asarray(z), n / np.linalg.norm(n, axis=-1, keepdims=True)])


def _curv(r):
    return 0.0 if math.isinf(r) else 1.0 / r


def _biconic(name, **kw):
    rx, ry, kx, ky = REF["biconics"][name]
    return Biconic(c=_curv(ry), k=ky, cx=_curv(rx), kx=kx, **kw)


# --- the polynomials -----------------------------------------------------------------

# Zemax's published tables (OpticStudio's "Zernike Standard Coefficients" listing and the
# Fringe definitions): (n, m) with m > 0 for cos mφ and m < 0 for sin |m|φ, and the term.
S6, S8, S10 = math.sqrt(6), math.sqrt(8), math.sqrt(10)
STANDARD = {
    1: ((0, 0), lambda p, a: 1.0 + 0 * p),
    2: ((1, 1), lambda p, a: 2 * p * np.cos(a)),
    3: ((1, -1), lambda p, a: 2 * p * np.sin(a)),
    4: ((2, 0), lambda p, a: math.sqrt(3) * (2 * p**2 - 1)),
    5: ((2, -2), lambda p, a: S6 * p**2 * np.sin(2 * a)),
    6: ((2, 2), lambda p, a: S6 * p**2 * np.cos(2 * a)),
    7: ((3, -1), lambda p, a: S8 * (3 * p**3 - 2 * p) * np.sin(a)),
    8: ((3, 1), lambda p, a: S8 * (3 * p**3 - 2 * p) * np.cos(a)),
    9: ((3, -3), lambda p, a: S8 * p**3 * np.sin(3 * a)),
    10: ((3, 3), lambda p, a: S8 * p**3 * np.cos(3 * a)),
    11: ((4, 0), lambda p, a: math.sqrt(5) * (6 * p**4 - 6 * p**2 + 1)),
    12: ((4, 2), lambda p, a: S10 * (4 * p**4 - 3 * p**2) * np.cos(2 * a)),
    13: ((4, -2), lambda p, a: S10 * (4 * p**4 - 3 * p**2) * np.sin(2 * a)),
    14: ((4, 4), lambda p, a: S10 * p**4 * np.cos(4 * a)),
    15: ((4, -4), lambda p, a: S10 * p**4 * np.sin(4 * a)),
}
FRINGE = {
    1: ((0, 0), lambda p, a: 1.0 + 0 * p),
    2: ((1, 1), lambda p, a: p * np.cos(a)),
    3: ((1, -1), lambda p, a: p * np.sin(a)),
    4: ((2, 0), lambda p, a: 2 * p**2 - 1),
    5: ((2, 2), lambda p, a: p**2 * np.cos(2 * a)),
    6: ((2, -2), lambda p, a: p**2 * np.sin(2 * a)),
    7: ((3, 1), lambda p, a: (3 * p**3 - 2 * p) * np.cos(a)),
    8: ((3, -1), lambda p, a: (3 * p**3 - 2 * p) * np.sin(a)),
    9: ((4, 0), lambda p, a: 6 * p**4 - 6 * p**2 + 1),
    10: ((3, 3), lambda p, a: p**3 * np.cos(3 * a)),
    11: ((3, -3), lambda p, a: p**3 * np.sin(3 * a)),
    12: ((4, 2), lambda p, a: (4 * p**4 - 3 * p**2) * np.cos(2 * a)),
    13: ((4, -2), lambda p, a: (4 * p**4 - 3 * p**2) * np.sin(2 * a)),
    14: ((5, 1), lambda p, a: (10 * p**5 - 12 * p**3 + 3 * p) * np.cos(a)),
    15: ((5, -1), lambda p, a: (10 * p**5 - 12 * p**3 + 3 * p) * np.sin(a)),
    16: ((6, 0), lambda p, a: 20 * p**6 - 30 * p**4 + 12 * p**2 - 1),
    36: ((10, 0), lambda p, a: 252 * p**10 - 630 * p**8 + 560 * p**6 - 210 * p**4
         + 30 * p**2 - 1),
    37: ((12, 0), lambda p, a: 924 * p**12 - 2772 * p**10 + 3150 * p**8 - 1680 * p**6
         + 420 * p**4 - 42 * p**2 + 1),
}
PTS = np.array([[0.0, 0.0], [1.2, 0.0], [0.0, 2.5], [-1.7, 0.9], [2.1, -3.3], [-3.9, -2.6],
                [4.8, 1.1]])  # mm; R = 5 mm, so ρ up to 1.02


@pytest.mark.parametrize("ordering, table, to_nm", [("standard", STANDARD, noll_to_nm),
                                                    ("fringe", FRINGE, fringe_to_nm)])
def test_index_maps_and_terms_match_zemax_tables(ordering, table, to_nm):
    """Each term alone (c = 0) is the tabulated polynomial, φ from +x toward +y."""
    rho = np.hypot(PTS[:, 0], PTS[:, 1]) / 5.0
    phi = np.arctan2(PTS[:, 1], PTS[:, 0])
    n = max(table)
    for j, (nm, term) in table.items():
        assert to_nm(j) == nm, j
        s = ZernikeSag(zernike=jnp.zeros(n).at[j - 1].set(1.0), norm_radius=5.0,
                       ordering=ordering)
        _close(s.sag(jnp.asarray(PTS[:, 0]), jnp.asarray(PTS[:, 1]))[0], term(rho, phi), 1e-12)
    assert [noll_to_nm(j) for j in (21, 22, 231)] == [(5, -5), (6, 0), (20, -20)]
    with pytest.raises(ValueError, match=r"fringe_to_nm: j must be a whole number in \[1, 37\]"):
        fringe_to_nm(38)


def test_hand_written_gradient_equals_automatic_differentiation():
    """66 Standard terms (radial orders to 10), a conic, even terms and a decenter, and 37
    Fringe terms; also at the disc's centre and the vertex, where ρ = 0."""
    a = jnp.asarray(np.random.default_rng(3).normal(size=66) * 1e-3)
    s = ZernikeSag(c=0.02, k=-0.4, coeffs=jnp.array([1e-3, -2e-5]), zernike=a, norm_radius=5.0,
                   decenter_x=0.7, decenter_y=-0.4)
    f = ZernikeSag(c=0.01, zernike=jnp.asarray(np.random.default_rng(4).normal(size=37)),
                   norm_radius=4.0, ordering="fringe")
    pts = np.vstack([PTS, [[0.7, -0.4]]])
    for surf in (s, f):
        auto = jax.jit(jax.vmap(jax.grad(lambda x, y, t=surf: t.sag(x, y)[0], argnums=(0, 1))))
        gx, gy = auto(jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1]))
        _, hx, hy, _ = jax.jit(lambda x, y, t=surf: t.sag_and_grad(x, y))(
            jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1]))
        for hand, auto_ in ((hx, gx), (hy, gy)):  # to 1e-12 of the largest slope
            tol = 1e-12 * float(np.max(np.abs(np.asarray(auto_))))
            _close(hand, auto_, tol)
        at_centre = jax.jit(jax.grad(lambda t: t.sag_and_grad(jnp.asarray(0.7),
                                                              jnp.asarray(-0.4))[1]))
        assert np.all(np.isfinite(np.asarray(at_centre(surf).zernike)))
        # The vertex curvatures (computed in closed form) are the sag's second derivatives.
        cx, cy = _second(surf)
        assert float(surf.paraxial_curvature_x) == pytest.approx(float(cx), rel=1e-12)
        assert float(surf.paraxial_curvature) == pytest.approx(float(cy), rel=1e-12)
        traced = jax.jit(lambda t: t.paraxial_curvature)(surf)  # the JAX path, under jit
        assert float(traced) == pytest.approx(float(cy), rel=1e-12)


@jax.jit
def _second(t):
    """d²z/dx² and d²z/dy² at the vertex by automatic differentiation."""
    zero = jnp.zeros(())
    return (jax.grad(lambda x: t.sag_and_grad(x, zero)[1])(zero),
            jax.grad(lambda y: t.sag_and_grad(zero, y)[2])(zero))


@pytest.mark.parametrize("ordering, key", [("standard", "noll"), ("fringe", "fringe")])
def test_zernike_sag_and_normal_equal_optilands(ordering, key):
    """45 Noll and 36 Fringe terms on a conic (optiland numbers its Fringe term 37
    differently from Zemax, so 36 are compared)."""
    b = REF["z_base"]
    s = ZernikeSag(c=1 / b["radius"], k=b["conic"], zernike=jnp.asarray(REF[key]),
                   norm_radius=b["norm_radius"], ordering=ordering)
    _close(_table(s, np.asarray(REF["points"])), REF["zernike_sag"][ordering], 1e-14)


def test_biconic_sag_and_normal_equal_optilands_where_they_coincide():
    """optiland's biconic is the sum of its two section conics, which is Zemax's biconic
    when a section is parabolic or flat; a general biconic differs (by 4.8e-4 mm here)."""
    pts = np.asarray(REF["points"])
    for name in ("parabolic", "cylinder_x_flat", "cylinder_y_flat"):
        _close(_table(_biconic(name), pts), REF["biconic_sag"][name], 1e-14)
    diff = np.abs(_table(_biconic("general"), pts) - np.asarray(REF["biconic_sag"]["general"]))
    assert 1e-4 < diff[:, 0].max() < 1e-3
    assert diff[pts[:, 0] * pts[:, 1] == 0].max() < 1e-14  # on the axes they agree


def test_biconic_with_equal_sections_is_a_standard_conic_and_its_sections_are_conics():
    pts = np.asarray(REF["points"])
    x, y = jnp.asarray(pts[:, 0]), jnp.asarray(pts[:, 1])
    b = Biconic(c=0.03, k=-0.5, cx=0.03, kx=-0.5)
    _close(jnp.stack(b.sag_and_grad(x, y)[:3]),
           jnp.stack(jl.Standard(c=0.03, k=-0.5).sag_and_grad(x, y)[:3]), 1e-15)
    g = Biconic(c=0.03, k=-0.5, cx=-0.02, kx=2.0)
    zero = jnp.zeros_like(x)
    _close(g.sag(x, zero)[0], jl.Standard(c=-0.02, k=2.0).sag(x, zero)[0], 1e-15)
    _close(g.sag(zero, y)[0], jl.Standard(c=0.03, k=-0.5).sag(zero, y)[0], 1e-15)
    # Zemax's formula, written out: one root over both sections.
    xs, ys = pts[:, 0], pts[:, 1]
    zemax = (-0.02 * xs**2 + 0.03 * ys**2) / (
        1 + np.sqrt(1 - 3.0 * 0.02**2 * xs**2 - 0.5 * 0.03**2 * ys**2))
    _close(g.sag(x, y)[0], zemax, 1e-15)
    assert float(g.paraxial_curvature) == 0.03 and float(g.paraxial_curvature_x) == -0.02


def test_defocus_term_is_a_sphere_to_second_order():
    """Standard Z4 = √3(2ρ² − 1): c = 0 plus A4·Z4 is the paraboloid 2√3 A4 r²/R² shifted by
    −√3 A4, the sphere of curvature 4√3 A4/R² to second order, and its paraxial power."""
    a4, rn = 0.05, 10.0
    s = ZernikeSag(zernike=jnp.array([0.0, 0.0, 0.0, a4]), norm_radius=rn)
    c_eff = 4 * math.sqrt(3) * a4 / rn**2
    assert float(s.paraxial_curvature) == pytest.approx(c_eff, rel=1e-14)
    assert float(s.paraxial_curvature_x) == pytest.approx(c_eff, rel=1e-14)
    r = jnp.array([0.0, 0.1, 0.3, 1.0, 2.0])
    z = s.sag(r, 0 * r)[0] + math.sqrt(3) * a4  # the vertex offset removed
    sphere = jl.Sphere(c_eff).sag(r, 0 * r)[0]
    assert np.all(np.abs(np.asarray(z - sphere)) <= c_eff**3 * np.asarray(r) ** 4 / 8 * 1.001)
    lens = jl.Lens(surfaces=(s, jl.Plane()), thickness=jnp.array([2.0, 50.0]),
                   materials=(jl.ModelGlass(1.5, 50.0), jl.Air()), epd=4.0)
    assert float(jl.efl(lens)) == pytest.approx(1 / (0.5 * c_eff), rel=1e-13)  # plano-convex
    # Astigmatism Z6 = √6 ρ² cos 2φ: +2√6 A6/R² in x, −2√6 A6/R² in y.
    astig = ZernikeSag(zernike=jnp.zeros(6).at[5].set(a4), norm_radius=rn)
    assert float(astig.paraxial_curvature) == pytest.approx(-2 * S6 * a4 / rn**2, rel=1e-14)
    assert float(astig.paraxial_curvature_x) == pytest.approx(2 * S6 * a4 / rn**2, rel=1e-14)
    xs = paraxial.x_section(eqx.tree_at(lambda t: t.surfaces, lens, (astig, jl.Plane())))
    assert float(xs.surfaces[0].c) == pytest.approx(2 * S6 * a4 / rn**2, rel=1e-14)


def test_even_terms_decenter_and_extrapolate():
    x, y = jnp.asarray(PTS[:, 0]), jnp.asarray(PTS[:, 1])
    a = jnp.array([1e-3, -2e-5, 3e-7])
    even = ZernikeSag(c=0.02, k=-1.3, coeffs=a)
    _close(jnp.stack(even.sag_and_grad(x, y)[:3]),
           jnp.stack(jl.EvenAsphere(c=0.02, k=-1.3, coeffs=a).sag_and_grad(x, y)[:3]), 1e-15)
    z = jnp.asarray(np.random.default_rng(5).normal(size=28) * 1e-3)
    centred = ZernikeSag(zernike=z, norm_radius=5.0)
    moved = ZernikeSag(zernike=z, norm_radius=5.0, decenter_x=0.8, decenter_y=-1.5)
    _close(jnp.stack(moved.sag_and_grad(x + 0.8, y - 1.5)[:3]),
           jnp.stack(centred.sag_and_grad(x, y)[:3]), 1e-15)
    inside = ZernikeSag(zernike=z, norm_radius=3.0, extrapolate=False)
    every = ZernikeSag(zernike=z, norm_radius=3.0)
    rho = np.hypot(PTS[:, 0], PTS[:, 1]) / 3.0
    zi, ze = np.asarray(inside.sag(x, y)[0]), np.asarray(every.sag(x, y)[0])
    _close(zi[rho <= 1], ze[rho <= 1], 0)
    assert np.all(zi[rho > 1] == 0) and np.any(ze[rho > 1] != 0)


def test_vertex_flat_and_outside_the_domain_are_finite_with_finite_gradients():
    """At r = 0, with c = 0 (flat sections) and beyond the conic's domain: finite sag, slope
    and parameter gradients (zero slope outside, as for the other surfaces)."""
    surfaces = (Biconic(c=0.0, cx=0.0), Biconic(c=0.2, k=0.5, cx=-0.1, kx=2.0),
                ZernikeSag(c=0.2, k=0.5, zernike=jnp.array([0.0, 1e-3, 0.0, 2e-3]),
                           norm_radius=3.0))
    for s in surfaces:
        for x, y in ((0.0, 0.0), (9.0, 0.0), (0.0, 9.0)):  # 9 mm: outside the conics
            z, gx, gy, inside = s.sag_and_grad(jnp.asarray(x), jnp.asarray(y))
            assert np.all(np.isfinite(np.asarray([z, gx, gy])))
            if not bool(inside):
                assert float(gx) == 0.0 and float(gy) == 0.0
            g = jax.grad(lambda t, x=x, y=y: sum(t.sag_and_grad(jnp.asarray(x),
                                                                 jnp.asarray(y))[:3]))(s)
            assert all(np.all(np.isfinite(np.asarray(v))) for v in jax.tree_util.tree_leaves(g))
    assert not bool(surfaces[1].sag(9.0, 0.0)[1]) and not bool(surfaces[2].sag(9.0, 0.0)[1])


def test_mirror_surface_negates_the_sag():
    z = jnp.asarray(np.random.default_rng(6).normal(size=15) * 1e-3)
    for s in (_biconic("general"), ZernikeSag(c=0.02, k=-0.3, coeffs=jnp.array([1e-4]),
                                              zernike=z, norm_radius=4.0, decenter_y=0.3,
                                              ordering="fringe", extrapolate=False)):
        m = mirror_surface(s)
        assert type(m) is type(s)
        for x, y in ((0.0, 0.0), (3.0, -4.0), (-2.0, 1.5)):
            _close(m.sag(x, y)[0], -s.sag(x, y)[0], 1e-15)


# --- real rays -----------------------------------------------------------------------


def _lens(surfaces, thickness, n):
    return jl.Lens(surfaces=surfaces, thickness=jnp.asarray(thickness),
                   materials=(jl.ModelGlass(n, 50.0), jl.Air()), epd=8.0)


def _lenses():
    """The lenses of tools/freeform_reference.py (an index nd exactly at the d line)."""
    return {
        "biconic": _lens((_biconic("parabolic"), _biconic("cylinder_x_flat")), [5.0, 40.0],
                         1.5),
        "biconic_general": _lens((_biconic("general"), _biconic("cylinder_y_flat")),
                                 [5.0, 40.0], 1.5),
        "zernike": _lens((ZernikeSag(c=1 / 40, k=-0.6, zernike=jnp.asarray(REF["noll"][:15]),
                                     norm_radius=6.0),
                          ZernikeSag(c=-1 / 60, zernike=jnp.asarray(REF["fringe"][:16]),
                                     norm_radius=6.5, ordering="fringe")), [4.0, 45.0], 1.6),
    }


def _rays():
    return jl.Rays(jnp.asarray(REF["launch"]["origin"]),
                   jnp.asarray(REF["launch"]["direction"]), WL)


@pytest.mark.parametrize("name", ["biconic", "biconic_general", "zernike"])
def test_real_rays_equal_optilands(name):
    """20 rays (4 fields, 5 pupil points) agree with optiland's intercepts to 1e-12 mm
    (measured 3.6e-15 mm); ``biconic_general`` was traced by optiland with Zemax's
    formula put in its geometry (see tools/freeform_reference.py)."""
    out = jl.trace(_lenses()[name], _rays())
    assert bool(np.all(np.asarray(out.valid)))
    _close(out.origin, REF["rays"][name], 1e-12)


def _spot_loss(lens, rays, reverse_rule):
    out = jl.trace(lens, rays, reverse_rule=reverse_rule)
    w = out.valid.astype(jnp.float64)
    xy = out.origin[:, :2]
    c = jnp.sum(w[:, None] * xy, 0) / jnp.sum(w)
    return jnp.sum(w[:, None] * (xy - c) ** 2) / jnp.sum(w)


# (surface, field) pairs whose gradient is checked, with central-difference steps.
PARAMS = {
    "biconic": [(0, "c", 1e-6), (0, "cx", 1e-6), (0, "kx", 1e-4), (0, "k", 1e-4),
                (1, "kx", 1e-4)],
    "zernike": [(0, "zernike", 1e-6), (1, "zernike", 1e-6), (0, "norm_radius", 1e-5),
                (0, "decenter_x", 1e-5), (1, "decenter_y", 1e-5), (0, "coeffs", 1e-7)],
    "zernike_small": [(0, "zernike", 1e-6), (0, "norm_radius", 1e-5), (0, "decenter_x", 1e-5),
                      (0, "decenter_y", 1e-5), (0, "coeffs", 1e-7)],
}


def _gradient_lens(name):
    if name == "biconic":
        return _lenses()["biconic_general"]
    if name == "zernike_small":  # one Zernike surface of 6 terms: cheaper to compile
        s = ZernikeSag(c=1 / 40, k=-0.6, coeffs=jnp.array([2e-4, -1e-6]),
                       zernike=jnp.asarray(REF["noll"][:6]), norm_radius=6.0,
                       decenter_x=0.3, decenter_y=-0.2)
        return _lens((s, jl.Sphere(-1 / 60)), [4.0, 45.0], 1.6)
    # even terms too, so that their gradients are not trivial
    return eqx.tree_at(lambda t: t.surfaces[0].coeffs, _lenses()["zernike"],
                       jnp.array([2e-4, -1e-6]))


@pytest.mark.parametrize("name, reverse_rule", [
    ("biconic", False), ("zernike_small", False),
    pytest.param("biconic", True, marks=pytest.mark.slow),
    pytest.param("zernike", False, marks=pytest.mark.slow),
    pytest.param("zernike", True, marks=pytest.mark.slow)])
def test_spot_gradients_in_the_new_coefficients_match_central_differences(name, reverse_rule):
    """d(RMS spot²)/d(parameter) against central differences, with JAX's derivative of the
    trace and (slow) with the hand-written reverse rule (``surface_adjoint``); the two-surface
    Zernike lens compiles in about 20 s, so CI takes a one-surface lens."""
    lens = _gradient_lens(name)
    rays = _rays()
    loss = jax.jit(lambda L: _spot_loss(L, rays, reverse_rule))
    g = jax.jit(jax.grad(lambda L: _spot_loss(L, rays, reverse_rule)))(lens)
    for i, field, h in PARAMS[name]:
        get = lambda t, i=i, field=field: getattr(t.surfaces[i], field)  # noqa: E731
        v = get(lens)
        idx = [0, 3, 10] if field == "zernike" and v.shape[0] > 10 else \
            list(range(v.shape[0])) if v.ndim else [None]
        for j in idx:
            def at(d, j=j, v=v, get=get):
                return loss(eqx.tree_at(get, lens, v + d if j is None else v.at[j].add(d)))
            fd = (float(at(h)) - float(at(-h))) / (2 * h)
            gj = float(get(g) if j is None else get(g)[j])
            assert gj != 0.0, (field, j)
            assert gj == pytest.approx(fd, rel=2e-5, abs=1e-12), (field, j)


# --- files ---------------------------------------------------------------------------

ZMX = """VERS 190513 80 123457 L123457
MODE SEQ
UNIT {unit} X W X CM MR CPMM
ENPD 8
FTYP 0 0 2 1 0 0 0
XFLN 0 0
YFLN 0 3
WAVM 1 0.5875618 1
SURF 0
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ INFINITY
SURF 1
  STOP
  TYPE BICONICX
  CURV 2.5E-2 0 0 0 0 ""
  CONI 0.8
  PARM 1 60
  PARM 2 -0.4
  DISZ 5
  GLAS ___BLANK 1 0 1.5 50 0 0 0 0 0 0
SURF 2
  TYPE SZERNSAG
  CURV -1.6666666666666666E-2 0 0 0 0 ""
  CONI -0.3
  PARM 0 1
  PARM 1 1E-4
  PARM 2 -2E-6
  PARM 9 0.25
  PARM 10 -0.5
  XDAT 1 6 0 0 0 0 0 ""
  XDAT 2 6.5 0 0 0 0 0 ""
  XDAT 3 0.001 0 0 0 0 0 ""
  XDAT 4 -0.002 0 0 0 0 0 ""
  XDAT 5 0.003 0 0 0 0 0 ""
  XDAT 6 0.004 0 0 0 0 0 ""
  XDAT 7 -0.001 0 0 0 0 0 ""
  XDAT 8 0.0005 0 0 0 0 0 ""
  DISZ 3
  GLAS ___BLANK 1 0 1.6 40 0 0 0 0 0 0
SURF 3
  TYPE FZERNSAG
  CURV 0 0 0 0 0 ""
  XDAT 1 37 0 0 0 0 0 ""
  XDAT 2 7 0 0 0 0 0 ""
  XDAT 6 0.002 0 0 0 0 0 ""
  XDAT 39 -0.0001 0 0 0 0 0 ""
  DISZ 40
SURF 4
  TYPE STANDARD
  CURV 0 0 0 0 0 ""
  DISZ 0
"""


def _write(tmp_path, text, name="f.zmx"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _same(a, b):
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    assert ta == tb
    for x, y in zip(la, lb, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def test_hand_written_zmx_opens_strict_and_round_trips(tmp_path):
    lens = jl.load(_write(tmp_path, ZMX.format(unit="MM")), strict=True)
    b, zs, zf = lens.surfaces
    assert type(b) is Biconic and float(b.c) == 0.025 and float(b.k) == 0.8
    assert float(b.cx) == 1 / 60 and float(b.kx) == -0.4
    assert type(zs) is ZernikeSag and zs.ordering == "standard" and zs.extrapolate
    assert float(zs.decenter_x) == 0.25 and float(zs.decenter_y) == -0.5
    assert float(zs.norm_radius) == 6.5
    np.testing.assert_array_equal(np.asarray(zs.coeffs), [1e-4, -2e-6])
    np.testing.assert_array_equal(np.asarray(zs.zernike),
                                  [0.001, -0.002, 0.003, 0.004, -0.001, 0.0005])
    assert zf.ordering == "fringe" and not zf.extrapolate  # no PARM 0: Zemax reads 0
    assert zf.zernike.shape == (37,) and float(zf.zernike[3]) == 0.002
    assert float(zf.zernike[36]) == -0.0001 and float(zf.zernike[4]) == 0.0
    # read -> save -> read is exact, in .zmx and in JSON
    for ext in ("zmx", "json"):
        out = tmp_path / f"again.{ext}"
        jl.save(lens, out)
        again = jl.load(out, strict=True)
        _same(again.surfaces, lens.surfaces)
        _same(again.thickness, lens.thickness)
    text = (tmp_path / "again.zmx").read_text()
    assert "TYPE BICONICX" in text and "TYPE SZERNSAG" in text and "TYPE FZERNSAG" in text
    # inches: lengths ×25.4, A_i ×25.4^(1−2i), Zernike coefficients ×25.4, 1/Rx exact
    inch = jl.load(_write(tmp_path, ZMX.format(unit="IN"), "in.zmx"))
    assert float(inch.surfaces[0].cx) == 1 / (60 * 25.4)
    assert float(inch.surfaces[0].kx) == -0.4 and float(inch.surfaces[0].k) == 0.8  # no unit
    assert float(inch.surfaces[1].norm_radius) == 6.5 * 25.4
    assert float(inch.surfaces[1].zernike[2]) == pytest.approx(0.003 * 25.4, rel=1e-15)
    assert float(inch.surfaces[1].coeffs[1]) == pytest.approx(-2e-6 * 25.4**-3, rel=1e-15)
    assert float(inch.surfaces[1].decenter_y) == -0.5 * 25.4


def test_new_lenses_round_trip_through_zmx_and_json(tmp_path):
    for name, lens in _lenses().items():
        for ext in ("zmx", "json"):
            out = tmp_path / f"{name}.{ext}"
            jl.save(lens, out)
            _same(jl.load(out).surfaces, lens.surfaces)


def _line_of(text, start):
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.strip().startswith(start))


@pytest.mark.parametrize("old, new, at, message", [
    ("PARM 2 -0.4", "PARM 2 -0.4\n  PARM 3 1", "PARM 3 ", r"BICONICX .* uses PARM 1\.\.2 only"),
    ("PARM 2 -0.4", "PARM 2 -0.4\n  XDAT 1 2 0 0 0 0 0 \"\"", "XDAT 1 2",
     r"BICONICX has no extra data \(XDAT\)"),
    ("PARM 0 1", "PARM 0 2", "PARM 0 ", r"PARM 0 \(the extrapolate flag\) must be 0 .* or 1"),
    ("XDAT 2 6.5", "XDAT 2 0", "XDAT 2 0", r"XDAT 2 \(the Zernike normalisation radius, lens "
                                           r"units\) must be > 0, got 0"),
    ("XDAT 2 6.5", "XDAT 2 -1", "XDAT 2 -1", r"must be > 0, got -1"),
    ("XDAT 1 6 ", "XDAT 1 232 ", "XDAT 1 232", r"XDAT 1 \(the number of Zernike terms\) must "
                                               r"be a whole number in 0\.\.231 for SZERNSAG"),
    ("XDAT 1 37 ", "XDAT 1 38 ", "XDAT 1 38", r"0\.\.37 for FZERNSAG, got 38"),
    ("XDAT 1 6 ", "XDAT 1 2.5 ", "XDAT 1 2.5", r"must be a whole number"),
    ("XDAT 1 6 ", "XDAT 1 5 ", "XDAT 8 ", r"coefficient beyond the 5 Zernike terms of XDAT 1"),
    ("PARM 10 -0.5", "PARM 10 -0.5\n  PARM 11 1", "PARM 11", r"SZERNSAG .* uses PARM 0\.\.10"),
])
def test_bad_freeform_zmx_data_name_the_file_and_line(tmp_path, old, new, at, message):
    text = ZMX.format(unit="MM")
    assert old in text
    text = text.replace(old, new, 1)
    path = _write(tmp_path, text, "bad.zmx")
    line = _line_of(text, at)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}:{line}: .*{message}"):
        jl.load(path)


@pytest.mark.parametrize("kw, message", [
    (dict(norm_radius=0.0), r"ZernikeSag: norm_radius must be finite numbers in \(0, inf\) mm"),
    (dict(norm_radius=-2.0), r"norm_radius .* mm, got -2"),
    (dict(zernike=jnp.zeros(232)), r"232 Zernike terms given; the standard ordering holds at "
                                   r"most 231"),
    (dict(zernike=jnp.zeros(38), ordering="fringe"), r"the fringe ordering holds at most 37"),
    (dict(zernike=jnp.array([0.1, jnp.nan])), r"zernike must be finite numbers \(mm\)"),
    (dict(decenter_x=jnp.inf), r"decenter_x must be finite numbers \(mm\)"),
    (dict(coeffs=jnp.array([jnp.nan])), r"coeffs"),
    (dict(ordering="noll"), r"ordering must be 'standard' .* or 'fringe'"),
    (dict(extrapolate=1), r"extrapolate must be True or False, got 1"),
    (dict(zernike=jnp.zeros((2, 3))), r"zernike must be a 1-D array"),
])
def test_zernike_constructor_refuses_bad_values(kw, message):
    args = dict(c=0.02, zernike=jnp.array([0.0, 1e-3]), norm_radius=5.0) | kw
    with pytest.raises(ValueError, match=message):
        ZernikeSag(**args)


def test_biconic_constructor_refuses_bad_values():
    with pytest.raises(ValueError, match=r"Biconic: kx must be finite numbers"):
        Biconic(c=0.02, cx=0.01, kx=jnp.nan)
    with pytest.raises(ValueError, match=r"Biconic: cx must be finite numbers in \[-1e\+09, "):
        Biconic(c=0.02, cx=jnp.inf)
    with pytest.raises(ValueError, match=r"x–z section .* defined only out to r = .* = 10 mm, "
                                         r"but the semi_diameter is 12 mm"):
        Biconic(c=0.01, cx=0.1, semi_diameter=12.0)
    with pytest.raises(ValueError, match=r"defined only out to r = .* = 20 mm"):
        Biconic(c=0.05, cx=0.0, semi_diameter=25.0)


@pytest.mark.parametrize("surface, message", [
    ({"type": "zernike_standard", "zernike_coeffs": [0.1]}, r"needs norm_radius"),
    ({"type": "zernike_fringe", "norm_radius": -1, "zernike_coeffs": [0.1]},
     r"norm_radius must be > 0 \(mm\), got -1"),
    ({"type": "zernike_standard", "norm_radius": 5, "zernike_coeffs": [0.0] * 232},
     r"232 Zernike terms given; the standard ordering holds at most 231"),
    ({"type": "zernike_standard", "norm_radius": 5, "extrapolate": "yes"},
     r"extrapolate must be True or False"),
    ({"type": "standard", "curvature_x": 0.01}, r"curvature_x belongs to a biconic"),
    ({"type": "biconic", "curvature": 0.02, "zernike_coeffs": [0.1]},
     r"a biconic surface \(type 'biconic'\) takes no zernike_coeffs"),
    ({"type": "biconic", "even_asphere_coeffs": [1e-4]}, r"takes no even_asphere_coeffs"),
    ({"type": "zernike_fringe", "conic_x": 1.0}, r"Zernike sag surface .* takes no conic_x"),
    ({"type": "biconic", "radius_x": 0}, r"radius_x 0 is not a surface"),
    ({"type": "biconic", "kx": 1.0}, r"did you mean 'conic_x'"),
    ({"type": "biconic", "radius_y": 30}, r"did you mean 'radius'"),
    ({"type": "zernike_standard", "norm_radius": 5, "zernikes": [0.1]},
     r"did you mean 'zernike_coeffs'"),
])
def test_json_refuses_bad_freeform_surfaces(surface, message):
    d = lensfile.lens_to_dict(_lenses()["zernike"])
    d["surfaces"][1] = {**surface, "thickness": 4.0}
    with pytest.raises(ValueError, match=message):
        lensfile.lens_from_dict(d, source="bad.json")


def test_report_names_the_zemax_types_and_their_terms():
    glass = jl.ModelGlass(1.5168, 64.17)
    lens = jl.Lens((jl.Biconic(c=0.02, cx=0.03, kx=-0.5),
                    jl.ZernikeSag(c=-0.02, zernike=jnp.array([0.0, 0.0, 0.0, 1e-3, 2e-4]),
                                  norm_radius=5.0, ordering="fringe")),
                   jnp.array([3.0, 45.0]), (glass, jl.Air()), epd=6.0)
    rows = report._surface_table(lens)
    assert "BICONICX" in rows[2] and "Rx=33.33 kx=-0.5" in rows[2]
    assert "FZERNSAG" in rows[3] and "R=5 Z4=0.001 Z5=0.0002" in rows[3]
