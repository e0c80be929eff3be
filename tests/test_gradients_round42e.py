"""Round 42e: gradients against central differences (float64) of the features added since
round 38d: object-space telecentric lenses (``Lens.object_na``) and their immersion object
media, virtual objects, afocal image space, the RPO molded-glass catalog, an image-space
telecentric lens's wavefront (exit pupil at infinity) and real ray aiming.
``tools/grad42e_probe.py`` is the audit these come from (its table: every row within 1e-6
of the best of three central differences, or explained in the docstrings below)."""

import dataclasses
import os
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import afocal, wavefront_error
from jaxlens.optics import paraxial

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def _load(rel):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return jl.load(os.path.join(DATA, rel))


def _central(f, x, h):
    """Central differences of a scalar function of a vector, per element."""
    return np.array([(float(f(x.at[j].add(h[j]))) - float(f(x.at[j].add(-h[j])))) / (2 * h[j])
                     for j in range(x.shape[0])])


def _agree(f, x0, h, rtol):
    x0 = jnp.asarray(x0, jnp.float64)
    g = np.asarray(jax.jit(jax.grad(f))(x0))
    fd = _central(jax.jit(f), x0, np.asarray(h, float))
    assert np.all(np.abs(g) > 0), g  # every parameter acts (a held one would read 0)
    np.testing.assert_allclose(g, fd, rtol=rtol, atol=1e-9 * np.max(np.abs(fd)))


def _tele():
    """The object-space telecentric doublet (object NA 0.08, object 60 mm before surface 1)
    with its front surface an even asphere (k = -0.3, A4 = 1e-6)."""
    lens = _load("zmx38a/tele_doublet_obna.zmx")
    s0 = jl.EvenAsphere(lens.surfaces[0].c, -0.3, jnp.array([0.0, 1e-6, 0.0]))
    return dataclasses.replace(lens, surfaces=(s0,) + tuple(lens.surfaces[1:]))


def _tele_edit(lens, x):
    """x = (object_na, object distance, c0, k0, A4 of surface 0, t2, object height)."""
    s0 = lens.surfaces[0]
    s0 = jl.EvenAsphere(x[2], x[3], s0.coeffs.at[1].set(x[4]))
    return eqx.tree_at(lambda L: (L.object_na, L.object_distance, L.surfaces[0], L.thickness),
                       lens, (x[0], x[1], s0, lens.thickness.at[2].set(x[5])))


TELE_X0 = [0.08, 60.0, None, -0.3, 1e-6, None, 5.0]
TELE_H = [1e-5, 1e-3, 1e-6, 1e-3, 1e-8, 1e-4, 1e-4]


def _tele_x0(lens):
    x = list(TELE_X0)
    x[2], x[5] = float(lens.surfaces[0].c), float(lens.thickness[2])
    return x


def test_telecentric_rms_spot_gradient():
    """rms_spot of an object-space telecentric lens (axis and 5 mm) w.r.t. the object NA,
    the object distance, the front asphere's c, k and A4, a gap and the object height (mm):
    within 1e-6 of central differences (the audit: 2e-8 worst over these and t0, c1, c4)."""
    lens = _tele()

    def f(x):
        L = _tele_edit(lens, x)
        return jl.analysis.rms_spot(L, fields=jnp.stack([0.0 * x[6], x[6]]),
                                    wavelengths=jnp.array([0.55])).polychromatic.sum()

    _agree(f, _tele_x0(lens), TELE_H, 1e-6)


@pytest.mark.parametrize("medium", ["air", "water"])
def test_telecentric_wavefront_rms_gradient(medium):
    """Wavefront RMS (15 × 15 grid) of the telecentric doublet, in air and with a liquid
    object medium (ModelGlass 1.333/55.8, NA scaled by n so the cone is the same), w.r.t.
    the same parameters. The audit's differences were noisier here (spread 2e-3 between
    steps: optical paths of ~1e5 waves), best-step agreement 2e-5 on t2, so the bar is 1e-4."""
    lens = _tele()
    x0 = _tele_x0(lens)
    if medium == "water":
        lens = dataclasses.replace(lens, object_material=jl.ModelGlass(1.333, 55.8))
        x0[0] = 0.08 * 1.333

    def f(x):
        return wavefront_error.wavefront(_tele_edit(lens, x), x[6], wavelength=0.55,
                                         grid=15).rms

    _agree(f, x0, TELE_H, 1e-4)


def test_virtual_object_rms_spot_gradient():
    """A singlet imaging a virtual object 100 mm behind surface 1 (object_distance = -100):
    rms_spot w.r.t. the object distance, both curvatures, the thickness and the field."""
    lens = _load("zmx_corpus7/virtual_singlet_angles.zmx")

    def f(x):
        L = eqx.tree_at(lambda L: (L.object_distance, L.surfaces[0].c, L.surfaces[1].c,
                                   L.thickness), lens, (x[0], x[1], x[2],
                                                        lens.thickness.at[0].set(x[3])))
        return jl.analysis.rms_spot(L, fields=jnp.stack([0.0 * x[4], x[4]]),
                                    wavelengths=jnp.array([0.55])).polychromatic.sum()

    x0 = [-100.0, float(lens.surfaces[0].c), float(lens.surfaces[1].c), 5.0, 2.0]
    _agree(f, x0, [1e-2, 1e-5, 1e-5, 1e-4, 1e-4], 1e-6)


def test_afocal_angular_spot_and_magnification_gradients():
    """The Kepler telescope (afocal image space): the chief-referenced RMS angular spot at
    0.6° and the real angular magnification w.r.t. the objective's and eyepiece's rear
    curvatures, the gap and the field angle (test_afocal checks the centroid spot's gap and
    eyepiece c); the paraxial angular magnification w.r.t. the same lens parameters."""
    lens = _load("afocal_kepler.zmx")

    def edit(x):
        return eqx.tree_at(lambda L: (L.surfaces[1].c, L.surfaces[3].c, L.thickness), lens,
                           (x[0], x[1], lens.thickness.at[1].set(x[2])))

    def spot(x, what):
        out = afocal.angular_spot(edit(x), fields=x[3][None], wavelengths=jnp.array([0.55]),
                                  reference="chief")
        return out.per_wavelength[0, 0] if what == "spot" else out.magnification[0]

    x0 = [float(lens.surfaces[1].c), float(lens.surfaces[3].c), float(lens.thickness[1]), 0.6]
    h = [1e-7, 1e-7, 1e-4, 1e-4]
    _agree(lambda x: spot(x, "spot"), x0, h, 1e-6)
    _agree(lambda x: spot(x, "mag"), x0, h, 1e-6)
    _agree(lambda x: afocal.angular_magnification(edit(x), 0.55), x0[:3], h[:3], 1e-6)


def test_rpo_glass_dispersion_gradient():
    """The RPO molded-glass Cooke triplet (tests/data/zmx40a): the longitudinal colour
    bfl(0.486) − bfl(λ) w.r.t. λ and two curvatures, and each RPO glass's dn/dλ."""
    lens = _load("zmx40a/rpo_molded_cooke.zmx")

    def f(x):
        L = eqx.tree_at(lambda L: (L.surfaces[0].c, L.surfaces[2].c), lens, (x[1], x[2]))
        return paraxial.bfl(L, 0.4861327) - paraxial.bfl(L, x[0])

    x0 = [0.6, float(lens.surfaces[0].c), float(lens.surfaces[2].c)]
    _agree(f, x0, [1e-5, 1e-6, 1e-6], 1e-6)
    for m in lens.materials:
        if isinstance(m, jl.CatalogMaterial):
            _agree(lambda x, m=m: m.index(x[0]), [0.6], [1e-4], 1e-7)


def _tele_mirror():
    """A concave mirror (R = -200 mm), the stop at its front focus: the exit pupil at
    infinity (paraxial d2 = 0 exactly)."""
    return jl.Lens(surfaces=(jl.Stop(), jl.Sphere(-1 / 200.0)),
                   thickness=jnp.array([100.0, -100.0]), materials=(jl.Air(), jl.Air()),
                   mirrors=(1,), stop=0, epd=8.0, fields=jnp.array([0.0, 1.0]),
                   wavelengths=jnp.array([0.5875618]))


def test_image_space_telecentric_zernike_gradient():
    """Noll Z4, Z9, Z11 of the wavefront of the image-space telecentric mirror at 0.5°
    w.r.t. the mirror's curvature and the image distance. Moving the stop (t0) leaves the
    exit pupil at a finite distance on either side; the reference sphere's curvature 1/R
    there enters the OPD only at second order in the ray aberrations, so the gradient with
    R held infinite is the derivative (the audit's differences for t0 were at their
    rounding noise, gradient 1e-5 of the others')."""
    lens = _tele_mirror()
    assert not np.isfinite(float(paraxial.paraxial_data(lens).exit_pupil_z))

    def f(x):
        L = eqx.tree_at(lambda L: (L.surfaces[1].c, L.thickness), lens,
                        (x[0], lens.thickness.at[1].set(x[1])))
        z = wavefront_error.wavefront(L, 0.5, grid=15).zernike(terms=11).coefficients
        return jnp.sum(jnp.array([1.0, -0.7, 0.4]) * z[jnp.array([3, 8, 10])])

    _agree(f, [-1 / 200.0, -100.0], [1e-7, 1e-4], 1e-6)


@pytest.mark.slow  # the Newton aiming's compile (~30 s each on 2 cores)
@pytest.mark.parametrize("aim", ["real", "real_marginal"])
def test_real_aimed_wavefront_rms_gradient(aim):
    """The Cooke triplet with real ray aiming: wavefront RMS at 12° w.r.t. a curvature, the
    back focus, the EPD (which moves the aimed stop radius) and the field (test_ray_aiming
    checks rms_spot's c only)."""
    base = dataclasses.replace(jl.zoo.cooke_triplet(), aim=aim)

    def f(x):
        L = eqx.tree_at(lambda L: (L.surfaces[2].c, L.thickness, L.epd), base,
                        (x[0], base.thickness.at[5].set(x[1]), x[2]))
        return wavefront_error.wavefront(L, x[3], wavelength=0.55, grid=15).rms

    x0 = [float(base.surfaces[2].c), float(base.thickness[5]), float(base.epd), 12.0]
    _agree(f, x0, [1e-7, 1e-4, 1e-4, 1e-4], 1e-5)
