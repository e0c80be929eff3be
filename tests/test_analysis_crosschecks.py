"""Cross-checks of the third-order (Seidel), wavefront/Zernike and encircled-energy analyses
against each other and against the library's ray-based functions (ray fans, field curvature,
real chief rays, spot RMS, the coherent PSF), in the situations their own tests leave out:
image or object space in glass, finite (near 1:1) objects, the stop behind the lens, mirrors
(one, two), an even asphere with an r² term, (θx, θy) fields, several wavelengths, float32.

Third-order checks use small apertures and fields, where the real rays' errors are the
third-order terms to 1e-3 relative or better (measured numbers are in each test).
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.scipy.special import bessel_jn

import jaxlens as jl
from jaxlens.analysis import field_curvature, ray_fan
from jaxlens.analysis.encircled import encircled_energy, radius_for_fraction
from jaxlens.analysis.spots import chief_ray, rms_spot, spot_rays, weighted_centroid
from jaxlens.analysis.third_order import seidel
from jaxlens.analysis.wavefront_error import opd, opd_fan, wavefront
from jaxlens.analysis.zernike import zernike_fit
from jaxlens.imaging.psf import CoherentPSF, psf_info
from jaxlens.imaging.sampling import field_rays, pupil_polar
from jaxlens.optics import paraxial
from jaxlens.optics.paraxial_surface import ParaxialSurface
from jaxlens.tracing.forward import trace

BK7 = jl.get_material("N-BK7")
FDC = jnp.array([0.4861327, 0.5875618, 0.6562725])


def at_focus(lens):
    """The lens with its image surface moved to the paraxial focus."""
    pd = paraxial.paraxial_data(lens)
    return eqx.tree_at(lambda l: l.thickness, lens,
                       lens.thickness.at[-1].add(pd.paraxial_image_z - pd.image_z))


def defocused(lens, dz):
    return eqx.tree_at(lambda l: l.thickness, lens, lens.thickness.at[-1].add(dz))


def glass_image(epd=1.0, fields=(0.0, 0.2)):
    """One refracting surface into N-BK7; the image lies inside the glass (n′ ≈ 1.517)."""
    return at_focus(jl.Lens(surfaces=(jl.Stop(), jl.Sphere(1 / 30.0)),
                            thickness=jnp.array([5.0, 80.0]), materials=(jl.Air(), BK7),
                            stop=0, epd=epd, fields=jnp.array(fields), wavelengths=FDC,
                            primary=1))


def glass_object(epd=1.0, fields=(0.0, 0.2)):
    """Object (at infinity) and stop in N-BK7, one surface out into air."""
    return at_focus(jl.Lens(surfaces=(jl.Stop(), jl.Sphere(-1 / 30.0)),
                            thickness=jnp.array([5.0, 80.0]), materials=(BK7, jl.Air()),
                            object_material=BK7, stop=0, epd=epd, fields=jnp.array(fields),
                            wavelengths=FDC, primary=1))


def near_unit(epd=1.0, fields=(0.0, 0.2)):
    """A biconvex singlet at about 1:1 (object 100 mm away), the stop behind it, the image
    in N-BK7."""
    return at_focus(jl.Lens(surfaces=(jl.Sphere(1 / 50.0), jl.Sphere(-1 / 50.0), jl.Stop()),
                            thickness=jnp.array([5.0, 3.0, 100.0]),
                            materials=(BK7, jl.Air(), BK7), stop=2, epd=epd,
                            fields=jnp.array(fields), object_distance=100.0,
                            wavelengths=FDC, primary=1))


def a2_asphere(epd=1.0, fields=(0.0, 0.2)):
    """An even asphere whose A2 (r²) term changes the paraxial curvature."""
    s = (jl.Stop(), jl.EvenAsphere(c=1 / 80.0, k=-0.5, coeffs=jnp.array([2e-3, 1e-6, 0.0])),
         jl.Sphere(-1 / 200.0))
    return at_focus(jl.Lens(surfaces=s, thickness=jnp.array([5.0, 5.0, 90.0]),
                            materials=(jl.Air(), BK7, jl.Air()), stop=0, epd=epd,
                            fields=jnp.array(fields)))


def mirror(epd=1.0, fields=(0.0, 0.2)):
    """A concave spherical mirror (R = −200 mm), stop on it; light leaves toward −z."""
    return at_focus(jl.Lens(surfaces=(jl.Sphere(-1 / 200.0),), thickness=jnp.array([-100.0]),
                            materials=(jl.Air(),), mirrors=(0,), stop=0, epd=epd,
                            fields=jnp.array(fields)))


def telecentric_mirror(epd=1.0, fields=(0.0, 0.2)):
    """The same mirror with the stop at its front focus: the exit pupil is at infinity."""
    return at_focus(jl.Lens(surfaces=(jl.Stop(), jl.Sphere(-1 / 200.0)),
                            thickness=jnp.array([100.0, -100.0]),
                            materials=(jl.Air(), jl.Air()), mirrors=(1,), stop=0, epd=epd,
                            fields=jnp.array(fields)))


def cassegrain(epd=2.0, fields=(0.0, 0.1)):
    """Two spherical mirrors (light ends toward +z), stop on the primary."""
    return at_focus(jl.Lens(surfaces=(jl.Sphere(-1 / 400.0), jl.Sphere(-1 / 150.0)),
                            thickness=jnp.array([-150.0, 150.0]),
                            materials=(jl.Air(), jl.Air()), mirrors=(0, 1), stop=0, epd=epd,
                            fields=jnp.array(fields)))


LENSES = {"glass_image": glass_image, "glass_object": glass_object, "near_unit": near_unit,
          "a2_asphere": a2_asphere, "mirror": mirror, "cassegrain": cassegrain}


def some(*ci):
    """Every lens, those not named in ``ci`` marked slow (each new lens compiles anew)."""
    return [n if n in ci else pytest.param(n, marks=pytest.mark.slow) for n in sorted(LENSES)]


# --------------------------------------------------------------------------------------
# Bugs found (each test failed on the code before the fix)
# --------------------------------------------------------------------------------------
def test_opd_with_the_exit_pupil_at_infinity():
    """Image-space telecentric: the reference sphere has R = inf. The OPD was 0 everywhere,
    and wrong when R is huge; now it is the limit: W040 ρ⁴ on axis (2.0776e-7 wave at
    EPD 0.5, the real OPD 2.0771e-7), off axis the mirror's coma and astigmatism."""
    lens = telecentric_mirror(epd=0.5)
    assert not np.isfinite(float(paraxial.paraxial_data(lens).exit_pupil_z))
    w040 = float(seidel(lens, field=0.0).wavefront()[0])
    edge = float(opd(lens, 0.0, jnp.array([[0.0, 1.0]]))[0])
    np.testing.assert_allclose(edge, w040, rtol=2e-3)
    pts = jnp.array([[0.0, 1.0], [0.0, -1.0], [1.0, 0.0]])
    off = opd(lens, 0.5, pts)
    assert np.all(np.isfinite(np.asarray(off))) and float(jnp.max(jnp.abs(off))) > 1e-6
    # Nearly telecentric (stop 1 µm off the focus: exit pupil 1e7 mm away): the same OPD.
    # The old b + sqrt(b² − |q|² + R²) − R cancelled catastrophically: (−9.5e-6, 0, −1.27e-5)
    # wave for the right (−7.76e-6, −1.95e-6, −1.50e-5).
    near = at_focus(eqx.tree_at(lambda q: q.thickness, lens, lens.thickness.at[0].add(1e-3)))
    assert abs(float(paraxial.paraxial_data(near).exit_pupil_z)) > 1e6
    np.testing.assert_allclose(np.asarray(opd(near, 0.5, pts)), np.asarray(off), atol=1e-9)


@pytest.mark.slow
def test_opd_gradient_with_the_exit_pupil_at_infinity():
    """The telecentric OPD's gradient is finite and matches central differences."""
    lens = telecentric_mirror(epd=0.5)
    pts = jnp.array([[0.0, 1.0], [0.0, -1.0], [1.0, 0.0]])

    def rim(c):
        return opd(eqx.tree_at(lambda q: q.surfaces[1].c, lens, c), 0.5, pts)[2]

    c0, h = lens.surfaces[1].c, 1e-7
    g = jax.grad(rim)(c0)
    np.testing.assert_allclose(float(g), float(rim(c0 + h) - rim(c0 - h)) / (2 * h), rtol=1e-4)


def test_float32_lens_wavefront_matches_float64():
    """Float32 optical paths of ~100 mm carry a few hundredths of a wave of rounding: the
    RMS of this lens at 2° was 0.1219 wave in float32 against 0.1195 in float64 (a spherical
    mirror's 0.0247 against 0.0100). Under x64 a float32 lens is traced in float64 and the
    results cast back: now equal to 1e-5 relative."""
    lens = glass_image(epd=6.0, fields=(0.0, 2.0))
    w64 = wavefront(lens, 2.0, grid=33)
    w32 = wavefront(lens.astype(jnp.float32), 2.0, grid=33)
    assert w32.rms.dtype == jnp.float32 and w32.map.dtype == jnp.float32
    np.testing.assert_allclose(float(w32.rms), float(w64.rms), rtol=1e-4)
    np.testing.assert_allclose(np.asarray(w32.map), np.asarray(w64.map), atol=1e-4)
    o32 = opd(lens.astype(jnp.float32), 2.0, jnp.array([[0.0, 1.0]]))
    assert o32.dtype == jnp.float32
    np.testing.assert_allclose(float(o32[0]), float(opd(lens, 2.0, jnp.array([[0.0, 1.0]]))[0]),
                               atol=1e-4)


def test_encircled_energy_refuses_pupil_points_outside_the_disc():
    """A point at radius 3 was traced (an overfilled ray, no part of the beam) and counted."""
    lens = glass_image()
    for fn, arg in ((encircled_energy, jnp.array([0.01])), (radius_for_fraction, 0.5)):
        with pytest.raises(ValueError, match="pupil points must lie in the unit disc"):
            fn(lens, 0.0, arg, pupil=jnp.array([[0.0, 0.5], [0.0, 3.0]]))
        with pytest.raises(ValueError, match="pupil"):
            fn(lens, 0.0, arg, pupil=jnp.array([[0.0, jnp.nan]]))


def test_zernike_fit_takes_a_numeric_mask_as_nonzero_is_fitted():
    """``ok & mask`` with an int mask was bitwise: a mask entry 2 dropped its point."""
    g = jnp.linspace(-0.7, 0.7, 5)
    x, y = (a.ravel() for a in jnp.meshgrid(g, g))
    v = 0.3 * x + 0.1 * y + 0.05 * (2 * (x * x + y * y) - 1)
    v = v.at[0].set(9.0)  # an outlier that the mask keeps in
    as_int = jnp.full(x.shape, 2).at[-1].set(0)
    as_bool = as_int != 0
    a = zernike_fit(x, y, v, terms=4, indexing="fringe", mask=as_int)
    b = zernike_fit(x, y, v, terms=4, indexing="fringe", mask=as_bool)
    np.testing.assert_allclose(np.asarray(a.coefficients), np.asarray(b.coefficients),
                               rtol=1e-12)


# --------------------------------------------------------------------------------------
# Relations checked and right (guards)
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", some("glass_image"))
def test_seidel_transverse_terms_are_the_real_ray_fans(name):
    """Tangential fan e_y(ρ) = TSPH ρ³ + TTCO ρ² + TTFC ρ, sagittal e_x = TSPH ρ³ + TSFC ρ,
    the chief ray's height minus the paraxial one = TDIS, and W040 = the real OPD at the rim
    on axis. Measured worst: 2.2e-3 relative (TTCO of near_unit); the n′ of a glass image
    and the signed indices of mirrors enter all of them."""
    lens = LENSES[name]()
    fld = float(lens.fields[-1])
    s = seidel(lens, field=fld)
    t = np.asarray(s.transverse())
    rf = ray_fan(lens, fld, lens.primary_wavelength, n=21)
    rho = np.asarray(rf.pupil)
    tan = np.polyfit(rho, np.asarray(rf.tangential[0]), 3)
    sag = np.polyfit(rho, np.asarray(rf.sagittal[0]), 3)
    scale = np.max(np.abs(t[[0, 2, 6]]))
    np.testing.assert_allclose(tan[:3], t[[0, 2, 6]], atol=3e-3 * scale)
    np.testing.assert_allclose(sag[[0, 2]], t[[0, 5]], atol=3e-3 * scale)
    dist = float(chief_ray(lens, fld).origin[1] - paraxial.image_height(lens, fld))
    np.testing.assert_allclose(dist, t[7], atol=1e-3 * abs(t[7]) + 1e-12)
    w040 = float(seidel(lens, field=0.0).wavefront()[0])
    edge = float(opd(lens, 0.0, jnp.array([[0.0, 1.0]]))[0])
    np.testing.assert_allclose(edge, w040, rtol=1e-3)


@pytest.mark.parametrize("name", [n for n in some() if n != "cassegrain"])
def test_seidel_field_curvature_and_wavefront_slope(name):
    """field_curvature's foci (mm along z) are −TTFC/u′ and −TSFC/u′ with u′ = (n′u′)/n′ the
    image-space slope dy/dz, n′ signed (−1 after one mirror: light goes toward −z);
    measured within 1e-4 relative. The OPD fan's slope gives the ray fan: ε = (1/n′u′) ∂W/∂ρ,
    W = OPD·λ (optiland's sign), within 1e-3."""
    lens = LENSES[name]()
    fld = float(lens.fields[-1])
    wl = lens.primary_wavelength
    s = seidel(lens, field=fld)
    t = np.asarray(s.transverse())
    n_img = paraxial.signed_indices(lens, wl)[-1]
    u = float(s.image_nu / n_img)
    fc = field_curvature(lens, jnp.array([fld]), wl)
    np.testing.assert_allclose(float(fc.tangential[0, 0]), -t[6] / u, rtol=1e-4)
    np.testing.assert_allclose(float(fc.sagittal[0, 0]), -t[5] / u, rtol=1e-4)
    of = opd_fan(lens, fld, wl, n=21)
    rf = ray_fan(lens, fld, wl, n=21)
    rho = np.asarray(of.pupil)
    slope = np.polyval(np.polyder(np.polyfit(rho, np.asarray(of.tangential[0]), 4)), rho)
    eps = slope * float(wl) * 1e-3 / float(s.image_nu)
    np.testing.assert_allclose(eps, np.asarray(rf.tangential[0]),
                               atol=1e-3 * np.max(np.abs(np.asarray(rf.tangential[0]))))


@pytest.mark.slow
def test_seidel_colour_against_real_rays_in_glass():
    """TAXC: marginal-ray height at F minus C on the paraxial image plane (−2.5686e-3 vs real
    −2.5634e-3 mm with the image in glass); TLAC: the F chief ray minus the C one
    (−1.2553e-3 vs −1.2527e-3). Within 0.5 % (second-order colour). W020 = C_L/2 against
    the OPD fans."""
    lens = glass_image(epd=0.5)
    s = seidel(lens, field=0.2)
    t = np.asarray(s.transverse())
    rf = ray_fan(lens, 0.0, FDC[jnp.array([0, 2])], n=3)
    np.testing.assert_allclose(float(rf.tangential[0, -1] - rf.tangential[1, -1]), t[8],
                               rtol=5e-3)

    def chief_y(w):
        return float(trace(lens, field_rays(lens, 0.2, jnp.zeros((1, 2)), w)).origin[0, 1])

    np.testing.assert_allclose(chief_y(FDC[0]) - chief_y(FDC[2]), t[9], rtol=5e-3)
    # The OPD fans (each wavelength to its own reference sphere) on axis: F minus C at the
    # rim, in mm, is C_L/2 (5.533e-6 vs 5.531e-6 mm).
    of = opd_fan(lens, 0.0, FDC[jnp.array([0, 2])], n=3)
    rim = (float(of.tangential[0, -1]) * float(FDC[0]) - float(of.tangential[1, -1])
           * float(FDC[2])) * 1e-3
    np.testing.assert_allclose(rim, float(s.sums[5]) / 2, rtol=2e-3)


@pytest.mark.parametrize("name", ["glass_image", pytest.param("mirror", marks=pytest.mark.slow)])
def test_defocus_and_spherical_in_zernike_terms(name):
    """Defocus dz (along the light) adds n′·dz·(1 − cos U′)/λ at the rim (OPD difference
    against the focus; 8.32e-3 wave with n′ = 1.517 at EPD 2, within 1e-3 relative); the
    fitted Noll Z4 moves by that /(2√3). At focus on axis, Noll Z11 = W040/(6√5)
    (1.3207e-4 vs 1.3192e-4 in glass: 0.2 %); off axis the coma, astigmatism and focus
    terms follow from W131, W222, W220P (signs of the fit against Seidel's)."""
    lens = LENSES[name](epd=2.0)
    wl = float(lens.primary_wavelength)
    n_img = float(lens.materials[-1].index(wl))
    out = trace(lens, field_rays(lens, 0.0, jnp.array([[0.0, 1.0]]), wl))
    cos_u = abs(float(out.direction[0, 2]))
    dz = 0.05
    moved = defocused(lens, -dz if name == "mirror" else dz)  # beyond the focus
    rim = jnp.array([[0.0, 1.0]])
    w020 = float(opd(moved, 0.0, rim)[0] - opd(lens, 0.0, rim)[0])
    np.testing.assert_allclose(w020, n_img * dz * (1 - cos_u) / (wl * 1e-3), rtol=1e-3)
    z0 = wavefront(lens, 0.0, grid=33).zernike(terms=11).coefficients
    z1 = wavefront(moved, 0.0, grid=33).zernike(terms=11).coefficients
    np.testing.assert_allclose(float(z1[3] - z0[3]), w020 / (2 * np.sqrt(3)), rtol=3e-3)
    w040 = float(seidel(lens, field=0.0).wavefront()[0])
    np.testing.assert_allclose(float(z0[10]), w040 / (6 * np.sqrt(5)), rtol=3e-3)
    # Off axis (field along +y): Noll Z7 (y coma) = W131/(3√8), Z6 (cos 2θ) = −W222/(2√6),
    # Z4 = (W040 + W222 + W220P)/(2√3) (ρ⁴ = 1/3 + (2ρ² − 1)/2 + …; ρ² cos²φ = ρ²/2 + …).
    fld = float(lens.fields[-1])
    w = np.asarray(seidel(lens, field=fld).wavefront())
    z = np.asarray(wavefront(lens, fld, grid=33).zernike(terms=11).coefficients)
    big = np.max(np.abs(z[3:11]))
    np.testing.assert_allclose(z[6], w[1] / (3 * np.sqrt(8)), atol=3e-3 * big)
    np.testing.assert_allclose(z[5], -w[2] / (2 * np.sqrt(6)), atol=3e-3 * big)
    np.testing.assert_allclose(z[3], (w[0] + w[2] + w[3]) / (2 * np.sqrt(3)), atol=3e-3 * big)


@pytest.mark.slow
def test_wavefront_tilt_and_the_spot_centroid():
    """Off axis, (θx, θy) and x-only fields, image in glass: the spot centroid minus the chief
    ray is (1/n′u′)·λ·(mean ∂W/∂P) (4 % here, the map's finite differences at the rim), and
    the least-squares (Zernike) tilt is 2/3 of it where coma leads (ρ³ cos φ = (3ρ³ − 2ρ)
    cos φ/3 + 2ρ cos φ/3): the tilt removed is the Z-tilt, not the centroid (G-tilt)."""
    lens = glass_image(epd=3.0, fields=(0.0, 2.0))
    wl = float(lens.primary_wavelength)
    nu = float(seidel(lens, field=0.0).image_nu)
    pts = pupil_polar(32)
    for fld in (jnp.array([1.0, 1.5]), jnp.array([2.0, 0.0])):
        wf = wavefront(lens, fld, grid=65)
        r = spot_rays(lens, fld, wl, pupil=pts)
        cen = np.asarray(weighted_centroid(r.origin[..., :2], r.valid.astype(float))
                         - chief_ray(lens, fld).origin[:2])
        step = float(wf.pupil[1] - wf.pupil[0])
        m = np.asarray(wf.map)
        gx, gy = np.gradient(m, step, axis=1), np.gradient(m, step, axis=0)
        ok = np.isfinite(gx) & np.isfinite(gy)
        mean_grad = np.array([gx[ok].mean(), gy[ok].mean()]) * wl * 1e-3 / nu
        np.testing.assert_allclose(mean_grad, cen, rtol=0.06, atol=1e-9)
        ztilt = np.asarray(wf.tilt[1:]) * wl * 1e-3 / nu
        np.testing.assert_allclose(ztilt, 2 / 3 * cen, rtol=0.03, atol=1e-9)


def test_geometric_encircled_energy_against_the_spot():
    """With the same pupil, EE reaches 1 at the farthest ray's distance and beyond, and
    Σ r² ΔEE is rms_spot² (exactly: the same rays, equal weights)."""
    lens = glass_image(epd=6.0, fields=(0.0, 2.0))
    wl = lens.primary_wavelength
    pts = pupil_polar(16)
    for fld in (2.0,):
        r = spot_rays(lens, fld, wl, pupil=pts)
        p = r.origin[..., :2]
        d = np.sort(np.asarray(jnp.linalg.norm(p - weighted_centroid(p, r.valid * 1.0), axis=-1)))
        # Just beyond each ray (ties of a symmetric pupil round either way), then far out.
        ee = encircled_energy(lens, fld, jnp.concatenate([jnp.asarray(d) + 1e-12,
                                                          jnp.array([1e3])]),
                              wavelength=wl, pupil=pts)
        e = np.asarray(ee.energy)
        assert e[-2] == 1.0 and e[-1] == 1.0
        de = np.diff(np.concatenate([[0.0], e[:-1]]))
        rs = rms_spot(lens, jnp.array([fld]), jnp.array([wl]), pupil=pts)
        np.testing.assert_allclose(np.sqrt(np.sum(d**2 * de)), float(rs.per_wavelength[0, 0]),
                                   rtol=1e-9)


@pytest.mark.slow
def test_diffraction_ee_and_strehl_with_the_image_in_glass():
    """A perfect lens focusing into N-BK7: the coherent EE is Airy's with NA = n′ sin U′
    (|EE − Airy| ≤ 2.4e-3, as in air); Maréchal's Strehl from the wavefront RMS matches the
    coherent PSF's for defocus in glass (0.9002 vs 0.8987 at 0.0516 wave), and the PSF's is
    the exact defocus value sinc²(π W020) = 0.8987 (W020 = 0.1792 wave, n′ = 1.5185)."""
    wl, f = 0.55, 50.0
    lens = at_focus(jl.Lens(surfaces=(ParaxialSurface(focal_length=f),),
                            thickness=jnp.array([f]), materials=(BK7,), stop=0, epd=5.0,
                            wavelengths=jnp.array([wl])))
    n = float(BK7.index(wl))
    d = trace(lens, field_rays(lens, 0.0, jnp.array([[0.0, 1.0]]), wl)).direction[0]
    na = n * float(jnp.sqrt(d[0] ** 2 + d[1] ** 2))
    r = np.linspace(0.0, 0.012, 13)
    v = jnp.asarray(2 * np.pi * na * r / (wl * 1e-3))
    j = bessel_jn(jnp.where(v > 0, v, 1.0), v=1, n_iter=60)
    airy = np.where(np.asarray(v) > 0, np.asarray(1 - j[0] ** 2 - j[1] ** 2), 0.0)
    ee = encircled_energy(lens, 0.0, r, method="diffraction", pixel_size=0.0005,
                          kernel_size=81)
    np.testing.assert_allclose(np.asarray(ee.energy), airy, atol=3e-3)
    moved = defocused(lens, 0.12)
    wf = wavefront(moved, 0.0, grid=65)
    res = psf_info(moved, 0.0, wavelength=wl, kernel_size=31, pixel_size=0.0005,
                   model=CoherentPSF(pupil=64))
    assert 0.03 < float(wf.rms_tilt_removed) < 0.08
    np.testing.assert_allclose(float(wf.strehl), float(res.strehl), atol=0.005)
    w020 = float(opd(moved, 0.0, jnp.array([[0.0, 1.0]]))[0])
    np.testing.assert_allclose(float(res.strehl), np.sinc(w020) ** 2, atol=1e-3)


def test_seidel_under_jit_and_in_float32_and_for_pair_fields():
    """The sums agree under filter_jit (exactly) and in float32 (4e-7 relative); a lens with
    (θx, θy) fields takes its largest radial field by default."""
    lens = glass_image(epd=6.0, fields=(0.0, 2.0))
    s = seidel(lens).sums
    np.testing.assert_allclose(np.asarray(eqx.filter_jit(lambda l: seidel(l).sums)(lens)),
                               np.asarray(s), rtol=1e-12, atol=1e-18)
    s32 = seidel(lens.astype(jnp.float32)).sums
    np.testing.assert_allclose(np.asarray(s32), np.asarray(s), rtol=1e-5,
                               atol=1e-5 * float(jnp.max(jnp.abs(s))))
    pairs = dataclasses.replace(lens, fields=jnp.array([[0.0, 0.0], [1.2, 1.6]]))
    tr = np.hypot(np.tan(np.deg2rad(1.2)), np.tan(np.deg2rad(1.6)))
    np.testing.assert_allclose(float(seidel(pairs).field), np.rad2deg(np.arctan(tr)),
                               rtol=1e-12)
