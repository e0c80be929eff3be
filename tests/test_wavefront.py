"""Wavefront error (jaxlens.analysis.wavefront_error) and Zernike fits (jaxlens.analysis.zernike):
against analytic answers (perfect lenses and mirrors, pure defocus, Zernike orthogonality,
the Strehl ratio of defocus), optiland 0.6.3 on the Cooke triplet, a coherent PSF's Strehl
ratio and central differences."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import zernike as zk
from jaxlens.analysis.wavefront_error import marechal_strehl, opd, opd_fan, wavefront
from jaxlens.imaging.psf import CoherentPSF, psf_info
from jaxlens.optics.coordinates import CoordinateBreak
from jaxlens.optics.paraxial_surface import ParaxialSurface

LAMBDA = 0.5875618  # µm, the d line (every lens here is analysed at its primary wavelength)

# optiland 0.6.3 (Cooke triplet at the d line, fields θy = 0, 14, 20 deg, strategy
# "chief_ray"), printed by `/work/optiland_venv/bin/python tools/wavefront_reference.py`:
# OPD (waves) at OPTILAND_POINTS, and on the uniform 33 × 33 grid cut to the disc (797 points)
# its RMS to the chief ray (OPD.rms()), RMS and P-V with the mean removed, and with piston and
# a least-squares plane in (Px, Py) removed (as jaxlens; optiland's own fit_and_remove_tilt
# fits a plane in exit-pupil coordinates: rms_tilt_removed_exit_pupil), and ZernikeFit's 37
# Noll and 36 Fringe coefficients (waves) of that grid's OPD.
OPTILAND_POINTS = ((0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.0, 0.5), (0.0, -0.5), (1.0, 0.0), (0.5,
                   0.0), (0.6, 0.6), (-0.3, 0.7))
OPTILAND = {
    0.0: {
        'opd': [0, -0.693948881834, -0.693948881834, -0.397492775305, -0.397492775305,
            -0.693948881834, -0.397492775305, -0.712151529477, -0.670037503927],
        'count': 797,
        'rms_chief': 0.5719900089616081,
        'rms': 0.20961851164462753,
        'pv': 0.7197940829299779,
        'rms_tilt_removed': 0.20961851164462753,
        'pv_tilt_removed': 0.7197940829299779,
        'rms_tilt_removed_exit_pupil': 0.20961851164462753,
        'noll': [-0.533666128558, -6.93889390391e-18, 3.81768673352e-17, -0.191637133664,
            3.44305305814e-18, -1.40236598628e-17, -3.6426457597e-17, -1.35528652888e-17,
            -7.53408842719e-17, 2.438137797e-17, 0.0838107679961, 2.00345088954e-17,
            8.81819559442e-19, -5.36155483265e-08, 5.60721865463e-18, -9.54707300529e-18,
            9.67352010614e-19, 7.17633682727e-18, -3.41758711824e-17, 4.05970392053e-18,
            4.67372079306e-17, -0.00567702646727, -1.19017301986e-17, 7.58347455249e-17,
            6.22175925411e-18, -2.04996026853e-07, -6.40638006005e-18, 4.68619029115e-17,
            3.35565747482e-17, 1.68521913908e-18, 5.03565185487e-17, -2.67035614179e-17,
            -6.97983247112e-18, -2.1147167273e-17, -6.49955645657e-18, -8.82567673426e-18,
            -0.000237050018351],
        'fringe': [-0.533666356443, -1.38777878078e-16, 2.16519590736e-16, -0.331925914257,
            6.79083653649e-17, 2.45803544094e-17, -6.74194591225e-19, 1.28470675303e-16,
            0.187405540549, -9.64154935775e-18, -9.93157328266e-17, 1.1115506928e-16,
            -9.8743954896e-18, 1.41351823102e-17, 1.29591501949e-16, -0.0150213098614,
            -3.35205543892e-08, 2.50529509781e-17, -1.80609860841e-17, -1.26581587328e-16,
            1.32478232421e-16, -8.61916123007e-18, 4.34396816949e-18, 1.49704385943e-16,
            -0.000712620185134, 3.28274503458e-17, 1.25575773703e-16, -6.11542455323e-08,
            1.85210598774e-17, -9.73591223656e-18, -1.43505894593e-16, 1.46260020674e-16,
            8.24216570261e-19, 2.89878428515e-18, 1.59331330763e-16, -2.70841173314e-05],
    },
    14.0: {
        'opd': [0, -2.19627537075, -1.72979606275, -0.399161802415, -0.383125486698,
            1.29300535372, 0.200949515134, -0.298761855103, -0.790405499852],
        'count': 797,
        'rms_chief': 0.625905293397532,
        'rms': 0.6036674089027741,
        'pv': 3.489280724469486,
        'rms_tilt_removed': 0.6011394863211426,
        'pv_tilt_removed': 3.3784046703343016,
        'rms_tilt_removed_exit_pupil': 0.6011649267526906,
        'noll': [-0.166897770575, -7.6327832943e-17, -0.0565264838523, -0.0897374197374,
            6.87387889484e-17, 0.604538418788, -0.0334031895084, -1.36683179306e-16,
            0.000874816934238, 1.54425471174e-16, -0.00202175248893, 0.0467635203505,
            5.13489971195e-17, 0.00293624945845, -7.5586375273e-17, -3.47791824588e-17,
            -0.00772377923073, 1.17703543585e-16, -0.00147433216048, -3.48944602633e-17,
            -0.000172200694567, -0.00628436867148, 1.94328046582e-17, -0.000130870221311,
            -6.30605250205e-17, -3.24866736972e-05, 8.47180341712e-17, -7.87815909445e-06,
            -0.000275930786969, -1.77380375011e-17, -3.30228840581e-05, -2.62098415986e-17,
            -1.09063135925e-06, -7.95760583568e-17, 4.3399322439e-07, 7.70361320927e-17,
            -0.000220241427198],
        'fringe': [-0.166897976499, -1.38777878078e-17, -0.113053084483, -0.155430368652,
            1.48080722915, 8.06815852597e-16, 2.50743333811e-17, -0.0944787216001,
            -0.00452171029695, -3.45525080204e-16, 0.00247431637964, 0.147874197763,
            2.75963440661e-17, -2.98583183862e-16, -0.0267563104054, -0.0166280600867,
            0.00928535898521, 2.52755522766e-16, -7.19130210858e-18, -0.00510733146306,
            -0.000495368489394, -1.34100280918e-16, 1.13020173359e-16, -0.00110420316792,
            -0.000662052738092, -3.02324694217e-17, -0.000596310212904, -0.000120916155345,
            -3.36293814177e-19, 1.14589431663e-18, -0.000132275000126, -0.000123590224087,
            -3.99948091758e-16, 2.33380426484e-17, -9.42635631423e-06, -2.44740735121e-05],
    },
    20.0: {
        'opd': [0, 0.41182578232, 0.386380119065, 0.482913628145, 0.448086275515, 1.53905401299,
            0.381649326799, 1.03797022091, 0.822872261305],
        'count': 797,
        'rms_chief': 0.7211944927324209,
        'rms': 0.33555489551240897,
        'pv': 1.539054012985221,
        'rms_tilt_removed': 0.32707486506291245,
        'pv_tilt_removed': 1.5396026680101496,
        'rms_tilt_removed_exit_pupil': 0.327053138040818,
        'noll': [0.641145001699, 2.08166817117e-17, 0.0746552249425, 0.273029751979,
            1.15582992189e-17, 0.132739029134, 0.0155005239196, -3.13227895663e-17,
            0.0568825795092, 1.08745295336e-17, -0.083471165136, 0.0777684176998,
            8.50422771968e-18, 0.0192782252641, -2.16640212603e-17, -2.10065112915e-17,
            -0.00634217160778, 3.1714661122e-17, -0.00228167712366, -3.45447525707e-17,
            -0.00130440616621, -0.0072029300184, 1.21664251941e-17, -0.000150517458533,
            -2.45803315849e-17, 0.00013583903496, 3.65889674034e-17, -8.37204243382e-05,
            -0.000272766126351, -2.53133843993e-17, -7.0853104671e-05, 5.23599039339e-17,
            -2.8881682988e-05, 7.15265943694e-20, 2.90827250813e-06, 3.3211022065e-17,
            -0.000225318292744],
        'fringe': [0.641144794171, 5.55111512313e-17, 0.149311228749, 0.472900799417,
            0.325145356621, 2.03200496018e-16, -4.65766868177e-17, 0.043843353442,
            -0.186648140983, -5.46825086276e-17, 0.160887161589, 0.245928374303,
            -1.37914991112e-16, 4.34372735759e-17, -0.0219688197568, -0.0190583541955,
            0.0609632249561, 2.5770090655e-16, -1.85394785721e-17, -0.00790506066066,
            -0.000561341693547, -3.31111429943e-17, -1.98107142293e-17, -0.00109102017457,
            -0.000677293685538, -3.65496569713e-18, -0.00451229386363, 0.000508905945682,
            -2.32069860233e-17, -5.07873951636e-17, -0.000283922480339, -0.000161283193435,
            -2.4082666529e-17, 3.08192898037e-17, -1.76204601284e-05, -2.46647657188e-05],
    },
}
# the object 500.0 mm before surface 1: OPD (waves) at OPTILAND_POINTS
OPTILAND_FINITE = {
    0.0: [0, -42.2421203287, -42.2421203287, -10.7926235784, -10.7926235784, -42.2421203287,
        -10.7926235784, -30.6355353589, -24.7784641253],
    14.0: [0, -40.1589254818, -40.0547759822, -9.91611569413, -9.9459543413, -39.0717864565,
        -9.89775611242, -28.4887301417, -23.0452760227],
    20.0: [0, -34.3160918331, -34.7907608195, -8.20392754168, -8.29302270968, -37.6130058217,
        -9.41243828477, -25.5214092777, -19.7067848256],
}


# --------------------------------------------------------------------------------------
# Zernike polynomials
# --------------------------------------------------------------------------------------
def _disc(n):
    g = np.linspace(-1.0, 1.0, n)
    x, y = np.meshgrid(g, g)
    keep = x * x + y * y <= 1.0
    return x[keep], y[keep]


def test_zernike_orderings_and_formulas():
    """The tables of Noll (Zemax Standard), Fringe and ANSI, and a few polynomials written
    out: Noll Z4 = √3(2ρ²−1), Z7 = √8(3ρ³−2ρ) sinθ, Z11 = √5(6ρ⁴−6ρ²+1); Fringe Z9 =
    6ρ⁴−6ρ²+1, Z37 = R_12^0 (924ρ¹² − … + 1); ANSI Z4 = Noll Z4."""
    assert zk._table("noll", 11) == ((0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2),
                                     (3, -1), (3, 1), (3, -3), (3, 3), (4, 0))
    assert zk._table("fringe", 10) == ((0, 0), (1, 1), (1, -1), (2, 0), (2, 2), (2, -2),
                                       (3, 1), (3, -1), (4, 0), (3, 3))
    assert zk.zernike_nm(36, indexing="fringe") == (10, 0)
    assert zk.zernike_nm(37, indexing="fringe") == (12, 0)
    assert zk._table("ansi", 6) == ((0, 0), (1, -1), (1, 1), (2, -2), (2, 0), (2, 2))
    rho, th = 0.7, 0.4
    x, y = rho * math.cos(th), rho * math.sin(th)
    noll = np.asarray(zk.zernike_terms(x, y, terms=11))
    assert noll[3] == pytest.approx(math.sqrt(3) * (2 * rho**2 - 1), rel=1e-14)
    assert noll[6] == pytest.approx(math.sqrt(8) * (3 * rho**3 - 2 * rho) * math.sin(th),
                                    rel=1e-14)
    assert noll[10] == pytest.approx(math.sqrt(5) * (6 * rho**4 - 6 * rho**2 + 1), rel=1e-14)
    fringe = np.asarray(zk.zernike_terms(x, y, terms=37, indexing="fringe"))
    assert fringe[8] == pytest.approx(6 * rho**4 - 6 * rho**2 + 1, rel=1e-14)
    r12 = sum((-1) ** k * math.factorial(12 - k) / (math.factorial(k) * math.factorial(6 - k)
              ** 2) * rho ** (12 - 2 * k) for k in range(7))
    assert fringe[36] == pytest.approx(r12, rel=1e-12)
    ansi = np.asarray(zk.zernike_terms(x, y, terms=5, indexing="ansi"))
    assert ansi[4] == pytest.approx(noll[3], rel=1e-14)


@pytest.mark.parametrize("indexing", ["noll", "fringe"])
def test_zernike_terms_are_orthogonal_over_the_disc(indexing):
    """The mean of Z_i·Z_j over a fine grid of the disc: the identity for Noll (normalised),
    diagonal 1/(2(n+1)/(1+δ_m0)) for Fringe (peak 1), to the grid's sampling error."""
    x, y = _disc(601)
    z = np.asarray(zk.zernike_terms(x, y, terms=37, indexing=indexing))
    gram = z.T @ z / x.size
    if indexing == "noll":
        expect = np.eye(37)
    else:
        expect = np.diag([(1.0 + (m == 0)) / (2.0 * (n + 1)) for n, m in zk._table("fringe", 37)])
    np.testing.assert_allclose(gram, expect, atol=3e-3)


@pytest.mark.parametrize("indexing", ["noll", "fringe"])
def test_zernike_fit_recovers_a_synthetic_wavefront(indexing):
    x, y = _disc(41)
    c = np.random.default_rng(1).normal(size=37) * 0.1
    w = np.asarray(zk.zernike_terms(x, y, terms=37, indexing=indexing)) @ c
    w[::7] = np.nan  # missing points weigh nothing
    fit = zk.zernike_fit(x, y, w, terms=37, indexing=indexing)
    np.testing.assert_allclose(fit.coefficients, c, rtol=0, atol=1e-12)
    assert float(fit.residual_rms) < 1e-12
    np.testing.assert_allclose(fit(x[1:3], y[1:3]), w[1:3], atol=1e-12)
    assert fit.nm[3] == (2, 0)


# --------------------------------------------------------------------------------------
# Against optiland
# --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def triplet():
    return jl.zoo.cooke_triplet()


@pytest.mark.parametrize("field", sorted(OPTILAND))
def test_cooke_triplet_matches_optiland(triplet, field):
    """OPD at given pupil points, RMS/P-V on the same 33 × 33 grid, Zernike coefficients
    fitted over it: optiland 0.6.3 (chief-ray reference sphere, same sign)."""
    ref = OPTILAND[field]
    w = opd(triplet, field, jnp.asarray(OPTILAND_POINTS))
    np.testing.assert_allclose(w, ref["opd"], rtol=0, atol=2e-10)
    wf = wavefront(triplet, field, grid=33)
    assert int(wf.valid.sum()) == ref["count"]
    rms_chief = float(np.sqrt(np.nanmean(np.asarray(wf.map) ** 2)))
    assert rms_chief == pytest.approx(ref["rms_chief"], abs=2e-10)
    for name in ("rms", "pv", "rms_tilt_removed", "pv_tilt_removed"):
        assert float(getattr(wf, name)) == pytest.approx(ref[name], abs=2e-10), name
    # optiland's tilt plane in exit-pupil coordinates differs by pupil distortion only.
    assert float(wf.rms_tilt_removed) == pytest.approx(ref["rms_tilt_removed_exit_pupil"],
                                                       abs=5e-5)
    noll = wf.zernike(terms=37)
    np.testing.assert_allclose(noll.coefficients, ref["noll"], rtol=0, atol=2e-10)
    fringe = wf.zernike(terms=36, indexing="fringe")
    np.testing.assert_allclose(fringe.coefficients, ref["fringe"], rtol=0, atol=2e-10)


def test_cooke_triplet_with_a_finite_object_matches_optiland(triplet):
    """An object 500 mm before surface 1 (the image surface stays at the infinity focus, so
    tens of waves of defocus): the rays start on the object point's sphere."""
    for field, ref in OPTILAND_FINITE.items():
        w = opd(triplet, field, jnp.asarray(OPTILAND_POINTS), depth=500.0)
        np.testing.assert_allclose(w, ref, rtol=1e-10, atol=1e-9)


# --------------------------------------------------------------------------------------
# Analytic answers
# --------------------------------------------------------------------------------------
F = 50.0  # mm, focal length of the ideal lens


def _ideal(dz=0.0, epd=10.0):
    """An ideal thin lens (Zemax PARAXIAL) 5 mm behind the stop, image surface dz beyond
    its focal plane."""
    return jl.Lens(surfaces=(jl.Stop(), ParaxialSurface(focal_length=F)),
                   thickness=jnp.array([5.0, F + dz]), materials=(jl.Air(), jl.Air()), stop=0,
                   epd=epd, fields=jnp.array([0.0, 10.0]))


def _mirror(k, c, after, obj=None, epd=40.0):
    return jl.Lens((jl.Standard(c=c, k=k),), jnp.array([after]), (jl.Air(),), mirrors=(0,),
                   epd=epd, object_distance=obj)


def test_perfect_lenses_and_a_paraboloid_have_no_wavefront_error():
    """An ideal lens on and off axis, a paraboloid at infinity: OPD 0 to rounding."""
    for field in (0.0, 10.0):
        wf = wavefront(_ideal(), field, grid=17)
        assert float(np.nanmax(np.abs(wf.map))) < 1e-9 and int(wf.valid.sum()) == 197
    fm = 100.0
    wf = wavefront(_mirror(-1.0, -1 / (2 * fm), -fm), 0.0, grid=17)
    assert float(np.nanmax(np.abs(wf.map))) < 1e-9 and int(wf.valid.sum()) == 197


def test_an_ellipsoid_images_its_foci_without_wavefront_error():
    """An ellipsoidal mirror imaging one focus onto the other (a finite object, light back
    toward −z): OPD 0 to rounding; a sphere in its place has more than a wave."""
    d1, d2 = 300.0, 100.0  # object and image distances from the vertex (the two foci)
    e = (d1 - d2) / (d1 + d2)
    r = 2 / (1 / d1 + 1 / d2)
    wf = wavefront(_mirror(-e * e, -1 / r, -d2, obj=d1), 0.0, grid=17)
    assert float(np.nanmax(np.abs(wf.map))) < 1e-9 and int(wf.valid.sum()) == 197
    assert float(wavefront(_mirror(0.0, -1 / r, -d2, obj=d1), 0.0, grid=17).rms) > 1.0


def test_a_plane_reference_for_afocal_image_space():
    """A glass plate passes a plane wave as a plane wave: OPD 0 to the plane through the
    chief ray's image point (``reference="plane"``), on and off axis; the reference sphere
    of a focal system is the wrong one there (hundreds of waves)."""
    plate = jl.Lens(surfaces=(jl.Plane(), jl.Plane()), thickness=jnp.array([10.0, 20.0]),
                    materials=(jl.ModelGlass(1.5168, 64.17), jl.Air()), epd=10.0)
    for field in (0.0, 10.0):
        wf = wavefront(plate, field, grid=9, reference="plane")
        assert float(np.nanmax(np.abs(wf.map))) < 1e-9 and int(wf.valid.sum()) == 49
    assert float(wavefront(plate, 10.0, grid=9).rms) > 100.0


def test_defocus_of_a_perfect_lens_is_the_exact_sphere_difference():
    """Image surface dz beyond the focus of a perfect wave: for the ray at angle U,
    OPD = (dz(1 − cos U) + sqrt(R² − dz² sin²U) − R)/λ (R the reference sphere's radius,
    positive: optiland's sign); its Zernike defocus is the paraxial W020 = dz·NA²/2 over
    2√3 (Noll) or 2 (Fringe), to the higher orders of (1 − cos U) ~ NA²."""
    dz = 0.05
    lens = _ideal(dz)
    p = np.linspace(0.0, 1.0, 6)
    w = np.asarray(opd(lens, 0.0, np.stack([0 * p, p], -1)))
    h = p * 5.0  # ray height on the lens (mm)
    sin_u = h / np.hypot(h, F)
    xp = float(jl.paraxial_data(lens).exit_pupil_z)
    r = 5.0 + F + dz - xp  # image point to the exit pupil
    expect = (dz * (1 - np.sqrt(1 - sin_u**2)) + np.sqrt(r * r - dz * dz * sin_u**2) - r)
    np.testing.assert_allclose(w, expect / (LAMBDA * 1e-3), rtol=1e-9, atol=1e-10)
    assert w[-1] > 0.4  # the sign: ahead of the reference sphere at the rim
    wf = wavefront(lens, 0.0, grid=33)
    na = 5.0 / math.hypot(5.0, F)
    w020 = dz * na**2 / 2 / (LAMBDA * 1e-3)
    noll = float(wf.zernike(terms=11).coefficients[3])
    fringe = float(wf.zernike(terms=9, indexing="fringe").coefficients[3])
    assert noll == pytest.approx(w020 / (2 * math.sqrt(3)), rel=1e-2)
    assert fringe == pytest.approx(w020 / 2, rel=1e-2)
    # Rotational symmetry: no tilt, astigmatism or coma, and tilt removal changes nothing.
    c = np.asarray(wf.zernike(terms=11).coefficients)
    np.testing.assert_allclose(c[[1, 2, 4, 5, 6, 7, 8, 9]], 0.0, atol=1e-12)
    assert float(wf.rms_tilt_removed) == pytest.approx(float(wf.rms), rel=1e-12)


@pytest.mark.slow
def test_strehl_of_defocus_against_the_coherent_psf_and_the_exact_value():
    """W020 = λ/4 of defocus at NA 0.04 (measured 8.8 s): the exact Strehl ratio of pure
    defocus is sinc²(W020) = 0.8116; the coherent PSF gives 0.8108 (pupil 64), Maréchal
    from the RMS 0.8159."""
    lam = LAMBDA * 1e-3
    na = 2.0 / math.hypot(2.0, F)
    lens = _ideal(2 * 0.25 * lam / na**2, epd=4.0)
    wf = wavefront(lens, 0.0, grid=65)
    a = float(wf.zernike(terms=4).coefficients[3]) * 2 * math.sqrt(3)  # W020, waves
    assert a == pytest.approx(0.25, rel=5e-3)
    exact = (math.sin(math.pi * a) / (math.pi * a)) ** 2
    info = psf_info(lens, 0.0, model=CoherentPSF(pupil=64), kernel_size=15,
                    pixel_size=lam * F / 16)
    assert float(info.strehl) == pytest.approx(exact, abs=2e-3)
    assert float(wf.strehl) == pytest.approx(exact, abs=6e-3)


@pytest.mark.slow
def test_marechal_strehl_agrees_with_the_coherent_psf_of_a_well_corrected_lens():
    """The Cooke triplet stopped down to EPD 4 mm (F/12.5, RMS 0.079 wave on axis; measured
    9 s): Maréchal 0.7806, the coherent PSF (pupil 64) 0.7791."""
    lens = eqx.tree_at(lambda m: m.epd, jl.zoo.cooke_triplet(clip=False), jnp.asarray(4.0))
    wf = wavefront(lens, 0.0, grid=65)
    assert float(wf.rms_tilt_removed) == pytest.approx(0.0792, abs=1e-3)
    info = psf_info(lens, 0.0, model=CoherentPSF(pupil=64), kernel_size=31,
                    pixel_size=LAMBDA * 1e-3 * 12.5 / 4)
    assert float(wf.strehl) == pytest.approx(float(info.strehl), abs=5e-3)


def test_marechal_formula():
    assert float(marechal_strehl(0.0)) == 1.0
    assert float(marechal_strehl(1 / 14)) == pytest.approx(math.exp(-(2 * math.pi / 14) ** 2))


# --------------------------------------------------------------------------------------
# Vignetting, fans, jit and gradients
# --------------------------------------------------------------------------------------
def test_vignetted_rays_are_nan_and_left_out_of_the_statistics(triplet):
    """A first surface clipped to 4 mm: the rim rays are lost (NaN, not valid); the
    statistics are those of the rays that pass."""
    lens = eqx.tree_at(lambda m: m.surfaces[0].semi_diameter, triplet, jnp.asarray(4.0))
    w = opd(lens, 0.0, jnp.array([[0.0, 0.0], [0.0, 0.5], [0.0, 1.0]]))
    assert np.isnan(w[2]) and np.isfinite(w[:2]).all()
    wf = wavefront(lens, 0.0, grid=33)
    kept = np.asarray(wf.valid)
    assert 0 < kept.sum() < OPTILAND[0.0]["count"]
    assert np.isnan(np.asarray(wf.map)[~kept]).all()
    vals = np.asarray(wf.map)[kept]
    assert float(wf.rms) == pytest.approx(float(np.std(vals)), rel=1e-12)
    assert float(wf.pv) == pytest.approx(float(np.ptp(vals)), rel=1e-12)


def test_opd_fan_is_the_opd_along_the_pupil_axes(triplet):
    fan = opd_fan(triplet, 14.0, n=5)
    assert fan.tangential.shape == fan.sagittal.shape == (3, 5)
    t = np.linspace(-1.0, 1.0, 5)
    pts = np.stack([0 * t, t], -1)
    np.testing.assert_allclose(fan.tangential[1], opd(triplet, 14.0, pts), atol=1e-12)
    np.testing.assert_allclose(fan.sagittal[1], opd(triplet, 14.0, pts[:, ::-1]), atol=1e-12)
    np.testing.assert_allclose(fan.sagittal[:, ::-1], fan.sagittal, atol=1e-9)  # x symmetry
    np.testing.assert_allclose(fan.tangential[:, 2], 0.0, atol=1e-9)  # each chief ray


def test_a_field_along_x_is_the_field_along_y_turned(triplet):
    """Field (θx, θy) = (14, 0) at pupil point (Py, −Px) is field θy = 14 at (Px, Py): the
    lens is turned by 90° about its axis."""
    p = np.array([[0.3, 0.7], [-0.5, 0.2], [0.0, -1.0]])
    turned = opd(triplet, jnp.array([14.0, 0.0]), np.stack([p[:, 1], -p[:, 0]], -1))
    np.testing.assert_allclose(turned, opd(triplet, 14.0, p), atol=1e-10)
    np.testing.assert_allclose(opd(triplet, jnp.array([0.0, 14.0]), p), opd(triplet, 14.0, p),
                               atol=1e-12)


def _rms_of_curvature(lens, c):
    return wavefront(eqx.tree_at(lambda m: m.surfaces[1].c, lens, c), 5.0, grid=9).rms


def test_rms_gradient_against_central_differences_under_jit():
    """d(RMS)/dc of a singlet's rear curvature: jit(grad) against a central difference."""
    lens = jl.Lens(surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
                   thickness=jnp.array([6.0, 45.0]),
                   materials=(jl.get_material("N-BK7"), jl.Air()), epd=10.0)
    c0 = lens.surfaces[1].c
    g = jax.jit(jax.grad(lambda c: _rms_of_curvature(lens, c)))(c0)
    h = 1e-6
    fd = (_rms_of_curvature(lens, c0 + h) - _rms_of_curvature(lens, c0 - h)) / (2 * h)
    assert np.isfinite(float(g)) and abs(float(g)) > 1.0
    assert float(g) == pytest.approx(float(fd), rel=1e-5)


# --------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------
def test_bad_input_is_refused_with_the_argument_named(triplet):
    pts = jnp.zeros((1, 2))
    with pytest.raises(ValueError, match="opd: pupil points must lie in the unit disc"):
        opd(triplet, 0.0, jnp.array([[0.0, 1.01]]))
    with pytest.raises(ValueError, match="opd: pupil must be"):
        opd(triplet, 0.0, jnp.zeros((3,)))
    with pytest.raises(ValueError, match="opd: field must be one field"):
        opd(triplet, [0.0, 1.0, 2.0], pts)
    with pytest.raises(TypeError, match="opd: field must be a real number"):
        opd(triplet, "5", pts)
    with pytest.raises(ValueError, match="field"):
        opd(triplet, 95.0, pts)
    for wl in (0.0, -0.5):
        with pytest.raises(ValueError, match="opd: wavelength must be a finite number in "
                                             r"\(0, inf\) µm"):
            opd(triplet, 0.0, pts, wavelength=wl)
    with pytest.raises(ValueError, match="wavelength"):
        opd(triplet, 0.0, pts, wavelength=587.6)  # nm, not µm
    with pytest.raises(ValueError, match="wavefront: wavelength must be one value"):
        wavefront(triplet, 0.0, wavelength=[0.5, 0.6])
    for grid in (2, 16.5, True, "33"):
        with pytest.raises(ValueError, match="wavefront: grid must be a whole number"):
            wavefront(triplet, 0.0, grid=grid)
    with pytest.raises(ValueError, match="reference must be one of"):
        wavefront(triplet, 0.0, reference="centroid")
    with pytest.raises(ValueError, match="aim must be one of"):
        opd(triplet, 0.0, pts, aim="chief")
    with pytest.raises(ValueError, match="depth"):
        wavefront(triplet, 0.0, depth=-5.0)
    with pytest.raises(TypeError, match="lens must be a jaxlens.Lens"):
        wavefront("lens", 0.0)
    broken = jl.Lens(surfaces=(jl.Sphere(0.01), CoordinateBreak(), jl.Sphere(-0.01)),
                     thickness=jnp.array([2.0, 0.0, 50.0]),
                     materials=(jl.ModelGlass(1.5, 60.0), jl.ModelGlass(1.5, 60.0), jl.Air()),
                     epd=5.0)
    with pytest.raises(ValueError, match="coordinate breaks are not supported"):
        wavefront(broken, 0.0)
    with pytest.raises(ValueError, match="opd_fan: wavelengths must be finite numbers in"):
        opd_fan(triplet, 0.0, [0.5, -0.1])
    x, y = _disc(9)
    with pytest.raises(ValueError, match="zernike_fit: points must lie in the unit disc"):
        zk.zernike_fit(x * 1.1, y * 1.1, x)
    with pytest.raises(ValueError, match="cannot determine 37 terms"):
        zk.zernike_fit(x[:10], y[:10], x[:10])
    with pytest.raises(ValueError, match="terms must be a whole number in"):
        zk.zernike_terms(x, y, terms=38, indexing="fringe")
    with pytest.raises(ValueError, match="indexing must be one of"):
        zk.zernike_terms(x, y, indexing="zemax")
    with pytest.raises(ValueError, match="same shape"):
        zk.zernike_fit(x, y[:-1], x)
