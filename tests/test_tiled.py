"""Tiled image formation: polar pupil sampling, pupil-normalised PSFs, PSFs at sensor points,
tiled convolution and tiled Wiener deconvolution."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.imaging import sampling, tiled
from jaxlens.imaging.psf import CoherentPSF, GeometricPSF
from jaxlens.tracing.forward import trace


def test_pupil_polar_fills_the_disc_evenly_and_strictly_inside():
    p = np.asarray(sampling.pupil_polar(16))
    r = np.hypot(p[:, 0], p[:, 1])
    assert p.shape == (256, 2) and r.max() < 1.0 and r.max() > 0.98
    # Equal-area cells: half the points inside radius 1/sqrt(2), a quarter inside 1/2.
    assert np.mean(r < 2**-0.5) == pytest.approx(0.5, abs=1 / 16)
    assert np.mean(r < 0.5) == pytest.approx(0.25, abs=1 / 16)
    q = np.asarray(sampling.pupil_polar(16, jax.random.PRNGKey(3), radius=0.5))
    assert np.hypot(q[:, 0], q[:, 1]).max() < 0.5 and not np.allclose(q, 0.5 * p)
    with pytest.raises(ValueError, match=r"pupil_polar: radius must be .* in \(0, 1\]"):
        sampling.pupil_polar(4, radius=1.5)


@pytest.fixture(scope="module")
def triplet():
    return jaxlens.zoo.cooke_triplet()


def test_pupil_normalised_psf_counts_vignetting_as_lost(triplet):
    """With ``normalize="pupil"`` a kernel sums to the flux that reaches the image over the flux
    that enters the entrance pupil (counted here by an independent trace); "transmitted"
    kernels sum to 1."""
    field, wl, k, pix = 20.0, 0.5876, 81, 0.01
    import equinox as eqx
    # A small front element clips the oblique beam (the zoo triplet's apertures do not).
    triplet = eqx.tree_at(lambda m: m.surfaces[0].semi_diameter, triplet,
                          jnp.asarray(0.6 * float(triplet.epd)))
    pup = GeometricPSF(pupil=24, overfill=1.0, grid="polar", normalize="pupil")
    tra = GeometricPSF(pupil=24, overfill=1.0, grid="polar")

    # The two kernels and the independent count in one compiled program: the two models are
    # two programs of their own otherwise, and the trace op by op took twice as long.
    @jax.jit
    def run(lens):
        a = jaxlens.psf(lens, field, wavelength=wl, kernel_size=k, pixel_size=pix, model=pup,
                        max_truncation=None)
        b = jaxlens.psf(lens, field, wavelength=wl, kernel_size=k, pixel_size=pix, model=tra)
        rays = sampling.collimated(lens, field, sampling.pupil_polar(24), wl)
        return a, b, jnp.mean(trace(lens, rays).valid)

    a, b, passed = run(triplet)
    passed = float(passed)
    assert 0.3 < passed < 0.95  # the 20° field of the triplet is vignetted
    assert float(a.sum()) == pytest.approx(passed, abs=2e-3)
    assert float(b.sum()) == pytest.approx(1.0, abs=2e-3)
    np.testing.assert_allclose(np.asarray(a), passed * np.asarray(b) / float(b.sum()),
                               atol=1e-6)
    with pytest.raises(ValueError, match="normalize must be 'transmitted' or 'pupil'"):
        jaxlens.psf(triplet, 0.0, model=GeometricPSF(normalize="entrance"))


def test_psf_points_is_psf_at_the_ideal_field_and_differentiable(triplet):
    import equinox as eqx

    model = GeometricPSF(pupil=16, overfill=1.0, grid="polar", normalize="pupil")
    xy = jnp.array([[0.0, 0.0], [3.0, -5.0]])

    def lens_at(c):
        return eqx.tree_at(lambda m: m.surfaces[1].c, triplet, c)

    def loss(c):
        k = tiled.psf_points(lens_at(c), xy, 1000.0, wavelengths=(0.486, 0.6563),
                             kernel_size=15, pixel_size=0.01, model=model)
        return jnp.sum(k * k), k

    def want(c, p):
        field = jaxlens.imaging.aiming.ideal_to_field(lens_at(c), p)
        return jaxlens.psf(lens_at(c), field, depth=1000.0,
                           wavelength=jnp.array([0.486, 0.6563]), kernel_size=15,
                           pixel_size=0.01, model=model, max_truncation=None)

    # One compiled program gives the kernels, their gradient and ``psf`` at each point's ideal
    # field (a program of its own otherwise).
    @jax.jit
    def run(c):
        (_, got), g = jax.value_and_grad(loss, has_aux=True)(c)
        return got, g, jax.vmap(want, (None, 0))(c, xy)

    got, g, ref = run(triplet.surfaces[1].c)
    assert got.shape == (2, 2, 15, 15) and ref.shape == got.shape
    for i in range(2):
        np.testing.assert_allclose(np.asarray(got[i]), np.asarray(ref[i]), atol=1e-12)
    assert np.isfinite(float(g)) and float(g) != 0.0


def _np_convolve_tiles(img, kern):
    ty, tx, c, k, _ = kern.shape
    h = k // 2
    p = img.shape[0] // ty
    pad = np.pad(img, ((h, h), (h, h), (0, 0)), mode="edge")
    out = np.zeros_like(img)
    for r in range(img.shape[0]):
        for s in range(img.shape[1]):
            kk = kern[r // p, s // p]  # [C, k, k]
            for m in range(k):
                for n in range(k):
                    # out[r, s] = Σ img[r − (m − h), s − (n − h)] · kern[m, n]
                    out[r, s] += pad[r + h - (m - h), s + h - (n - h)] * kk[:, m, n]
    return out


def test_convolve_tiles_applies_each_tiles_kernel():
    rng = np.random.default_rng(0)
    img = rng.random((10, 10, 2))
    kern = rng.random((2, 2, 2, 3, 3))
    kern[0, 1, :, 1, 2] += 3.0  # an asymmetric kernel: a flipped kernel would be caught
    got = np.asarray(tiled.convolve_tiles(jnp.asarray(img), jnp.asarray(kern)))
    np.testing.assert_allclose(got, _np_convolve_tiles(img, kern), rtol=1e-12)
    pad = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    valid = np.asarray(tiled.convolve_tiles(jnp.asarray(pad), jnp.asarray(kern), pad="valid"))
    np.testing.assert_allclose(valid, got, rtol=1e-12)
    with pytest.raises(ValueError, match="does not split into 3x3 square tiles"):
        tiled.convolve_tiles(jnp.asarray(img), jnp.zeros((3, 3, 2, 3, 3)))


def test_wiener_tiles_undoes_a_known_blur_and_a_light_loss():
    rng = np.random.default_rng(1)
    img = rng.random((48, 48, 3))
    k = np.zeros((3, 7, 7))
    k[:, 3, 3] = 0.6
    k[:, 3, 4] = 0.1
    k[:, 2, 3] = 0.1  # sums to 0.8: a fifth of the light is lost
    kern = np.broadcast_to(k, (2, 2, 3, 7, 7)).copy()
    blurred = tiled.convolve_tiles(jnp.asarray(img), jnp.asarray(kern))
    back = np.asarray(tiled.wiener_tiles(blurred, jnp.asarray(kern), 1e-8))
    inner = (slice(8, 40), slice(8, 40))
    np.testing.assert_allclose(back[inner], img[inner], atol=1e-4)
    # A larger noise-to-signal ratio smooths: the error grows, and nsr has a gradient.
    g = jax.grad(lambda n: jnp.sum(tiled.wiener_tiles(blurred, jnp.asarray(kern), n)))(0.1)
    assert np.isfinite(float(g)) and float(g) != 0.0
    # The wrong kernel does not invert the blur.
    wrong = np.asarray(tiled.wiener_tiles(blurred, jnp.asarray(np.swapaxes(kern, -1, -2)), 1e-8))
    assert np.max(np.abs(wrong[inner] - img[inner])) > 0.05


def test_valid_padding_reads_the_margin_instead_of_edge_copies():
    """With ``pad="valid"`` a tile's window is real image: on a 3 × 3-tile frame with the halo
    one tile wide, the centre tile's window in the edge-padded frame reaches no padding, so
    the centre of ``pad="edge"`` equals ``pad="valid"`` on the same frame as one tile with
    its margin, for the Wiener estimate and the evidence; the edge copies of a lone tile
    differ."""
    rng = np.random.default_rng(3)
    p = 12
    img = jnp.asarray(rng.random((3 * p, 3 * p, 3)))
    k = np.broadcast_to(_gauss_kernel(1.2, 7), (3, 7, 7))
    one = jnp.asarray(k[None, None])
    nine = jnp.asarray(np.broadcast_to(k, (3, 3, 3, 7, 7)))
    centre = (slice(p, 2 * p), slice(p, 2 * p))

    @jax.jit  # the five results in one compiled program: op by op took five times as long
    def run(img, one, nine):
        return (tiled.wiener_tiles(img, nine, 0.01, halo=p, prior="gradient"),
                tiled.wiener_tiles(img, one, 0.01, halo=p, prior="gradient", pad="valid"),
                tiled.wiener_tiles(img[centre], one, 0.01, halo=p, prior="gradient"),
                tiled.tile_evidence(img, nine, 0.01, halo=p),
                tiled.tile_evidence(img, one, 0.01, halo=p, pad="valid"))

    edge, valid, lone, ev_edge, ev_valid = run(img, one, nine)
    assert valid.shape == (p, p, 3)
    np.testing.assert_allclose(np.asarray(valid), np.asarray(edge[centre]), atol=1e-12)
    assert float(jnp.max(jnp.abs(lone - valid))) > 1e-3
    np.testing.assert_allclose(np.asarray(ev_valid)[0, 0], np.asarray(ev_edge)[1, 1],
                               rtol=1e-12)
    with pytest.raises(ValueError, match="inside its 12-pixel margin"):
        tiled.wiener_tiles(img[:-1], one, 0.01, halo=p, pad="valid")
    with pytest.raises(ValueError, match="pad must be 'edge' or 'valid'"):
        tiled.wiener_tiles(img, one, 0.01, pad="reflect")


def test_pupil_centre_is_the_chief_ray_of_a_stop_first_lens():
    from jaxlens.experiments.edof.lenses import classical_lens

    lens = classical_lens(binning=8)
    assert lens.stop == 0
    model = GeometricPSF(pupil=12, overfill=1.0, grid="polar", normalize="pupil")
    kw = dict(wavelengths=(0.656, 0.587, 0.486), kernel_size=9, pixel_size=0.02, model=model)
    xy = jnp.array([[1.0, -2.0]])
    # The three references in one compiled program: op by op took about twice as long.
    a, b, c = jax.jit(lambda lens: [tiled.psf_points(lens, xy, 150.0, center=r, **kw)
                                    for r in ("pupil", "chief", "centroid")])(lens)
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), atol=1e-6)
    assert float(jnp.max(jnp.abs(c - b))) > 1e-3  # the reference point matters
    with pytest.raises(ValueError, match="center='pupil' is for the geometric model"):
        jaxlens.psf(lens, 0.0, model=CoherentPSF(pupil=8), center="pupil")


def test_wiener_gradient_prior_damps_high_frequencies_only():
    """The gradient prior's penalty nsr·|∇|² vanishes at zero frequency: a flat image keeps
    its level (a white prior pulls it towards 0 by 1/(1 + nsr)), while noise is damped."""
    kern = np.zeros((1, 1, 1, 3, 3))
    kern[..., 1, 1] = 1.0
    flat = jnp.full((16, 16, 1), 0.5)
    g = np.asarray(tiled.wiener_tiles(flat, jnp.asarray(kern), 1.0, prior="gradient"))
    w = np.asarray(tiled.wiener_tiles(flat, jnp.asarray(kern), 1.0, prior="white"))
    np.testing.assert_allclose(g, 0.5, atol=1e-6)
    np.testing.assert_allclose(w, 0.25, atol=1e-6)
    noise = jnp.asarray(np.random.default_rng(0).normal(0.0, 1.0, (16, 16, 1)))
    smooth = np.asarray(tiled.wiener_tiles(noise, jnp.asarray(kern), 1.0, prior="gradient"))
    assert np.std(smooth) < 0.6 * float(jnp.std(noise))
    with pytest.raises(ValueError, match="prior must be 'white' or 'gradient'"):
        tiled.wiener_tiles(flat, jnp.asarray(kern), 1.0, prior="laplace")


def _gauss_kernel(sigma, k=15):
    r = np.arange(k) - k // 2
    g = np.exp(-(r[:, None] ** 2 + r[None, :] ** 2) / (2 * sigma**2))
    return g / g.sum()


def test_tile_evidence_tells_which_blur_made_each_tile():
    """A Gaussian field with the gradient prior's 1/|∇|² spectrum, each 32² tile blurred by
    one of two kernels (σ 0.7 or 2.5 px) plus white noise: the kernel set with the smaller
    negative log-likelihood is the true one on every tile, on every draw. The overall noise
    scale is profiled out: scaling the image shifts every candidate's value equally."""
    n = 64  # 2 × 2 tiles of 32
    wy = 2 * np.pi * np.fft.fftfreq(n)[:, None]
    wx = 2 * np.pi * np.fft.fftfreq(n)[None, :]
    p = 4 - 2 * np.cos(wy) - 2 * np.cos(wx)
    sharp, soft = _gauss_kernel(0.7), _gauss_kernel(2.5)
    which = np.array([[0, 1], [1, 0]])  # 0: sharp, 1: soft
    truth = np.stack([sharp, soft])[which][:, :, None]  # [2, 2, 1, k, k]
    wrong = np.stack([sharp, soft])[1 - which][:, :, None]
    rng = np.random.default_rng(0)
    sigma_n, sigma_g = 0.01, 0.05
    for _ in range(8):
        spec = np.fft.fft2(rng.normal(size=(n, n))) * sigma_g / np.sqrt(np.where(p > 0, p, 1))
        spec[0, 0] = 0.0
        img = np.real(np.fft.ifft2(spec))[..., None] + 0.5
        y = tiled.convolve_tiles(jnp.asarray(img), jnp.asarray(truth))
        y = y + sigma_n * rng.normal(size=y.shape)
        nsr = sigma_n**2 / sigma_g**2
        good = np.asarray(tiled.tile_evidence(y, jnp.asarray(truth), nsr))
        bad = np.asarray(tiled.tile_evidence(y, jnp.asarray(wrong), nsr))
        assert good.shape == (2, 2) and np.all(good < bad)
    shift_good = np.asarray(tiled.tile_evidence(3 * y, jnp.asarray(truth), nsr)) - good
    shift_bad = np.asarray(tiled.tile_evidence(3 * y, jnp.asarray(wrong), nsr)) - bad
    np.testing.assert_allclose(shift_good, shift_bad, rtol=1e-6)


def test_tile_evidence_gradient_matches_finite_differences():
    """The training differentiates the depth posterior through ``tile_evidence`` (the NSR
    and, with a live front end, the kernels): central differences in float64."""
    rng = np.random.default_rng(2)
    img = jnp.asarray(rng.random((16, 16, 2)))
    kern = np.broadcast_to(_gauss_kernel(1.2, 5), (2, 2, 2, 5, 5)).copy()

    def f(nsr, scale):
        return jnp.sum(tiled.tile_evidence(img, jnp.asarray(kern) * scale, nsr) *
                       jnp.array([[1.0, -0.5], [0.3, 2.0]]))

    h = 1e-6
    # The four shifted points, [nsr ± h, 1] and [0.05, 1 ± h].
    pts = jnp.array([[0.05 + h, 1.0], [0.05 - h, 1.0], [0.05, 1.0 + h], [0.05, 1.0 - h]])

    @jax.jit  # one compiled program for the gradient and the differences, not op by op
    def grads_and_values(x0, pts):
        return jax.grad(f, argnums=(0, 1))(*x0), jax.vmap(f)(pts[:, 0], pts[:, 1])

    (g_nsr, g_k), v = grads_and_values(jnp.array([0.05, 1.0]), pts)
    fd_nsr = (v[0] - v[1]) / (2 * h)
    fd_k = (v[2] - v[3]) / (2 * h)
    assert float(g_nsr) == pytest.approx(float(fd_nsr), rel=1e-6)
    assert float(g_k) == pytest.approx(float(fd_k), rel=1e-6)
    assert abs(float(g_nsr)) > 1.0 and abs(float(g_k)) > 1.0
