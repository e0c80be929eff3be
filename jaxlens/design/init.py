"""Seeded random starting points for ab initio design: nearly flat surfaces, random gaps.

Conventions:
    Lengths in mm. The lens has ``spec.n_elements`` elements of two ``EvenAsphere`` surfaces
    each and a flat aperture stop with ``spec.stop`` elements in front of it. Curvatures
    start near zero (scaled curvature c·r_s ~ N(0, 0.05²)), aspheric terms tiny (scaled
    N(0, 1e-4²)), conics zero, and the gaps random: element thicknesses U(0.5, 1.0), air
    gaps U(0.1, 0.4), the stop gap U(0.05, 0.15), then all scaled so that the lens fills
    ``total_track − bfl − 0.3``; the back gap is what remains of the fixed track. Every
    start is reproducible from its integer seed.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ..optics import checks
from ..optics.lens import Lens, Sensor
from ..optics.materials import Air
from ..optics.surfaces import EvenAsphere, Stop
from .params import LensParams, Parameterization
from .spec import AIR_MIN_GAP, ELEMENT_MIN_THICKNESS, DesignSpec, get_material, require_spec

# Ranges of the random gaps before scaling to the track (mm).
_ELEMENT = (0.5, 1.0)
_AIR = (0.1, 0.4)
_STOP_GAP = (0.05, 0.15)
_BACK_MARGIN = 0.3


def gap_kinds(spec: DesignSpec) -> tuple[str, ...]:
    """What each gap is, surface i to i+1 (last: to the sensor).

    One of ``"glass"`` (within an element), ``"air"`` (between elements), ``"stop"`` (between
    the stop and a neighbouring surface) and ``"back"`` (last surface to the sensor).
    """
    _spec_and_dtype(spec, None, "gap_kinds")  # a dict was an AttributeError
    kinds = []
    n = spec.num_surfaces
    s = spec.stop_index
    for i in range(n):
        if i == n - 1:
            kinds.append("back")
        elif i == s or i + 1 == s:
            kinds.append("stop")
        else:
            # Element surfaces, counting the stop out: front surfaces are even.
            j = i if i < s else i - 1
            kinds.append("glass" if j % 2 == 0 else "air")
    return tuple(kinds)


def gap_bounds(spec: DesignSpec, stop_gap: float = 0.02) -> np.ndarray:
    """Minimum spacing (mm) of every gap for the spacing regularizer: 0.4 within an element,
    0.2 between elements, ``stop_gap`` next to the stop, ``spec.bfl`` to the sensor."""
    _spec_and_dtype(spec, None, "gap_bounds")  # a dict was an AttributeError
    table = {"glass": ELEMENT_MIN_THICKNESS, "air": AIR_MIN_GAP, "stop": stop_gap,
             "back": spec.bfl}
    return np.array([table[k] for k in gap_kinds(spec)])


def _nominal_gaps(spec: DesignSpec) -> np.ndarray:
    mean = {"glass": np.mean(_ELEMENT), "air": np.mean(_AIR), "stop": np.mean(_STOP_GAP)}
    kinds = gap_kinds(spec)[:-1]
    g = np.array([mean[k] for k in kinds])
    return g * (spec.total_track - spec.bfl - _BACK_MARGIN) / g.sum()


def normalisation_radii(spec: DesignSpec) -> np.ndarray:
    """Normalisation radius of every optical surface (mm), about its clear semi-diameter.

    r_s = EPD/2 + 0.5·tan(half FoV)·|z_s − z_stop| on the nominal layout, capped at the
    sensor half-diagonal.
    """
    _spec_and_dtype(spec, None, "normalisation_radii")  # a dict was an AttributeError
    z = np.concatenate([[0.0], np.cumsum(_nominal_gaps(spec))])
    s = spec.stop_index
    t = np.tan(np.radians(spec.half_fov))
    r = 0.5 * spec.epd + 0.5 * t * np.abs(z - z[s])
    r = np.minimum(r, spec.half_diagonal)
    return np.delete(r, s)


def template_lens(spec: DesignSpec, dtype=None) -> Lens:
    """The design's lens structure with flat surfaces and nominal gaps (no randomness)."""
    _spec_and_dtype(spec, dtype, "template_lens")  # a dict was an AttributeError
    dtype = dtype or jnp.result_type(float)
    m = spec.asphere_terms
    surfaces, materials = [], []
    kinds = gap_kinds(spec)
    element = 0
    for i in range(spec.num_surfaces):
        if i == spec.stop_index:
            surfaces.append(Stop(jnp.asarray(jnp.inf, dtype)))
            materials.append(Air())
            continue
        surfaces.append(EvenAsphere(c=jnp.zeros((), dtype), k=jnp.zeros((), dtype),
                                    coeffs=jnp.zeros((m + 1,), dtype),
                                    semi_diameter=jnp.asarray(jnp.inf, dtype)))
        if kinds[i] == "glass":
            materials.append(get_material(spec.materials[element]))
            element += 1
        else:
            materials.append(Air())
    gaps = _nominal_gaps(spec)
    thickness = np.concatenate([gaps, [spec.total_track - gaps.sum()]])
    rows, cols = spec.sensor_resolution
    pixel = spec.sensor_size[0] / rows
    return Lens(
        surfaces=tuple(surfaces),
        thickness=jnp.asarray(thickness, dtype),
        materials=tuple(materials),
        stop=spec.stop_index,
        epd=jnp.asarray(spec.epd, dtype),
        fields=jnp.asarray(np.linspace(0.0, spec.half_fov, 5), dtype),
        wavelengths=jnp.asarray(spec.wavelengths, dtype),
        primary=spec.primary,
        sensor=Sensor(resolution=(rows, cols), pixel_size=jnp.asarray(pixel, dtype)),
        name=spec.name,
    )


def _spec_and_dtype(spec, dtype, where: str) -> None:
    """A ``DesignSpec`` and None or a float dtype (before: None failed as an AttributeError
    deep inside, int32 as an OverflowError from an infinite bound)."""
    require_spec(spec, where)
    checks.float_dtype(dtype, where)


def parameterization(spec: DesignSpec, dtype=None) -> Parameterization:
    """The order-1 parameterisation of the spec's lens structure."""
    _spec_and_dtype(spec, dtype, "parameterization")
    lens = template_lens(spec, dtype)
    optical = tuple(i for i in range(spec.num_surfaces) if i != spec.stop_index)
    return Parameterization(
        template=lens,
        r_norm=jnp.asarray(normalisation_radii(spec), lens.epd.dtype),
        total_track=jnp.asarray(spec.total_track, lens.epd.dtype),
        optical=optical,
    )


def random_params(spec: DesignSpec, key, dtype=None) -> LensParams:
    """One random start (jittable and vmappable over ``key``)."""
    _spec_and_dtype(spec, dtype, "random_params")
    checks.prng_key(key, "random_params")  # shape and dtype: known under jit and vmap too
    dtype = dtype or jnp.result_type(float)
    kinds = gap_kinds(spec)[:-1]
    lo = np.array([{"glass": _ELEMENT, "air": _AIR, "stop": _STOP_GAP}[k][0] for k in kinds])
    hi = np.array([{"glass": _ELEMENT, "air": _AIR, "stop": _STOP_GAP}[k][1] for k in kinds])
    s = spec.num_surfaces - 1
    kc, ka, kd = jax.random.split(key, 3)
    c = 0.05 * jax.random.normal(kc, (s,), dtype)
    a = 1e-4 * jax.random.normal(ka, (s, spec.asphere_terms), dtype)
    u = jax.random.uniform(kd, (len(kinds),), dtype)
    d = jnp.asarray(lo, dtype) + u * jnp.asarray(hi - lo, dtype)
    d = d * (spec.total_track - spec.bfl - _BACK_MARGIN) / jnp.sum(d)
    return LensParams(c=c, a=a, k=jnp.zeros((s,), dtype), d=d)


MAX_SEED = 2**32 - 1
"""Largest seed: JAX without x64 takes a seed modulo 2³² (seed 2³² repeated seed 0's start),
and with x64 a seed of 2⁶³ or more overflowed."""


def check_seeds(seeds, where: str, *, distinct: bool = False) -> list[int]:
    """A non-empty list of whole-number seeds in [0, ``MAX_SEED``] (``distinct``: no repeat,
    which would design the same lens twice); returns them as ints."""
    # int() would truncate a seed of 1.5 to 1 and read "12" as two seeds 1 and 2.
    # A set (or a dict's keys) has no order: seed labels and starts would not pair up.
    if isinstance(seeds, str | bytes | set | frozenset | dict) or not hasattr(
            seeds, "__len__") or len(seeds) == 0:
        raise ValueError(f"{where}: seeds must be a non-empty list of whole numbers "
                         f">= 0, got {seeds!r} (a list or tuple, in order: not a set)")
    out = [checks.number(s, "seeds", where, lo=0, integer=True) for s in seeds]
    if max(out) > MAX_SEED:
        raise ValueError(f"{where}: seeds must be whole numbers in [0, {MAX_SEED}] (seeds of "
                         f"JAX's PRNG), got {max(out)}")
    if distinct and len(set(out)) < len(out):
        raise ValueError(f"{where}: seeds must be distinct (a repeated seed designs the same "
                         f"lens twice), got {list(seeds)!r}")
    return out


def random_starts(spec: DesignSpec, seeds, dtype=None) -> LensParams:
    """Random starts for a list of integer seeds, stacked on a leading axis."""
    require_spec(spec, "random_starts")
    seeds = check_seeds(seeds, "random_starts")
    checks.float_dtype(dtype, "random_starts")
    keys = jnp.stack([jax.random.PRNGKey(int(s)) for s in seeds])
    return jax.vmap(lambda k: random_params(spec, k, dtype))(keys)
