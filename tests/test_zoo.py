"""The sample lenses in ``jaxlens.zoo``: first-order data against their sources, and a real trace.

One compiled trace per lens (every field and wavelength in one batch) keeps this fast.
"""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens import sampling, zoo


def _all_rays(lens, pupil):
    """Rays for every (field, wavelength) of the lens over ``pupil``: shape [F, W, m]."""
    rays = []
    for f in np.asarray(lens.fields):
        for w in np.asarray(lens.wavelengths):
            rays.append(sampling.collimated(lens, float(f), pupil, float(w)))
    o = jnp.stack([r.origin for r in rays])
    d = jnp.stack([r.direction for r in rays])
    w = jnp.stack([jnp.broadcast_to(r.wavelength, r.shape) for r in rays])
    shape = (lens.fields.shape[0], lens.wavelengths.shape[0], pupil.shape[0])
    return jaxlens.Rays(o, d, w).reshape(*shape)


@pytest.fixture(scope="module", params=sorted(zoo.ZOO))
def traced(request):
    lens = zoo.ZOO[request.param]()
    # Slightly inside the rim: a pupil point at |P| = 1 may round to just outside a stop whose
    # semi-diameter is exactly EPD/2 (the cellphone lens).
    pupil = 0.999 * sampling.pupil_grid(11)
    out = jaxlens.trace(lens, _all_rays(lens, pupil))
    return request.param, lens, out


def test_every_ray_reaches_the_image(traced):
    name, lens, out = traced
    assert bool(jnp.all(out.valid)), f"{name}: {int((~out.valid).sum())} rays lost"
    assert bool(jnp.all(jnp.isfinite(out.origin)))
    # Rays land on the image surface.
    np.testing.assert_allclose(np.asarray(out.origin[..., 2]), float(lens.image_z()), atol=1e-9)


def test_spots_are_sensible(traced):
    name, lens, out = traced
    xy = out.origin[..., :2]
    rms = jnp.sqrt(jnp.mean(jnp.sum((xy - xy.mean(-2, keepdims=True)) ** 2, -1), -1))  # [F, W]
    limit = {"cooke_triplet": 0.05, "double_gauss": 0.06, "cellphone6": 0.02}[name]
    assert float(rms.max()) < limit, f"{name}: RMS spots {np.asarray(rms)} mm"
    assert float(rms.min()) > 1e-4  # real lenses have aberrations
    # The image of the largest field lies on the sensor.
    h = float(jnp.abs(xy[-1, lens.primary, :, 1]).mean())
    assert 0.5 * float(lens.sensor.half_diagonal) < h <= float(lens.sensor.half_diagonal)


def test_structure():
    for make in zoo.ZOO.values():
        lens = make()
        assert lens.wavelengths.shape == (3,) and lens.primary == 1
        assert float(lens.wavelengths[1]) == pytest.approx(0.5875618)
        assert lens.sensor is not None
        unclipped = make(clip=False)
        assert all(math.isinf(float(s.semi_diameter)) for s in unclipped.surfaces)
    cell = zoo.cellphone6()
    assert cell.stop == 0 and len(cell.surfaces) == 13
    assert all(isinstance(s, jaxlens.EvenAsphere) for s in cell.surfaces[1:])
    assert float(cell.sensor.half_diagonal) == pytest.approx(3.83, abs=1e-3)
    assert float(cell.total_track()) == pytest.approx(6.9391000289916995, abs=1e-9)


def test_first_order_data_match_the_sources():
    # Paraxial values from tests/refcases (optiland 0.6.3, cross-checked with rayoptics).
    cooke = jaxlens.paraxial_data(zoo.cooke_triplet())
    assert float(cooke.efl) == pytest.approx(50.021596510291324, rel=1e-12)
    assert float(cooke.bfl) == pytest.approx(42.43669436364181, rel=1e-12)
    assert float(cooke.entrance_pupil_z) == pytest.approx(11.505797154609747, rel=1e-12)
    dg = jaxlens.paraxial_data(zoo.double_gauss())
    assert float(dg.efl) == pytest.approx(100.00372050801043, rel=1e-12)
    assert float(dg.fnum) == pytest.approx(5.0, rel=1e-12)
    assert float(dg.entrance_pupil_z) == pytest.approx(57.912053591784165, rel=1e-12)
    cell = jaxlens.paraxial_data(zoo.cellphone6())
    # Wide-angle phone lens: paraxial EFL about 5.1 mm, F/2.3, entrance pupil at the stop.
    assert 4.5 < float(cell.efl) < 5.5
    assert 2.0 < float(cell.fnum) < 2.6
    assert float(cell.entrance_pupil_z) == 0.0


def test_cooke_spot_matches_refcase():
    """RMS spot about the centroid, d line, 21×21 grid (317 rays), as in the refcase."""
    lens = zoo.cooke_triplet(clip=False)
    pupil = sampling.pupil_grid(21)
    rays = [sampling.collimated(lens, float(f), pupil) for f in np.asarray(lens.fields)]
    rays = jaxlens.Rays(jnp.stack([r.origin for r in rays]), jnp.stack([r.direction for r in rays]),
                        lens.primary_wavelength)
    xy = jaxlens.trace(lens, rays).origin[..., :2]
    rms = jnp.sqrt(jnp.mean(jnp.sum((xy - xy.mean(-2, keepdims=True)) ** 2, -1), -1))
    ref = [0.004831935378526593, 0.015253718477756768, 0.010280210103030754]
    np.testing.assert_allclose(np.asarray(rms), ref, rtol=1e-8)
