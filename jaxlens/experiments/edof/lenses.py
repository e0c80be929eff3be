"""The lenses of the EDoF experiment: the classical start, the hybrid EDoF lens, the cubic plate.

Conventions:
    Lengths in mm, wavelengths in µm, angles in degrees. Light travels toward +z and
    surface 1's vertex is at z = 0. Object depths in this package are measured from the
    aperture stop (``stop_z``); ``object_depth`` converts them to the distance from
    surface 1 that ``jaxlens.psf`` and ``jaxlens.render`` take (the same for a stop-first lens).

The classical lens (``classical_lens``) is the shipped prescription
``jaxlens/data/lenses/edof_classical.json``: a 5-element plastic aspheric lens with the stop
first, paraxial EFL 5.55 mm, EPD 2.60 mm (F/2.13), a 68.8° diagonal field on a 7.20 mm sensor
diagonal (1024 × 1024 pixels of 4.97 µm; about −5 % barrel distortion at the corner), focused
at 20 cm. ``jaxlens.experiments.edof.design`` made it (record: ``experiments/edof/base_lens.json``).

The EDoF lens replaces the first lens surface by a ``Hybrid`` surface (even asphere plus the
odd polynomial Σ_j b_j x^{2j+1} + d_j y^{2j+1}). The cubic-plate baseline is a thin cubic
phase plate at the aperture: the sag a·(x³ + y³) added to that same surface, which sits
0.01 mm behind the stop, with nothing else changed. All three lenses thus share one
structure (and one compiled training step); the classical lens has all odd terms at zero.

The trainable parameters live apart from the lens (``HybridParams``, with ``gates`` saying
which of them each lens may change), all in one unit: the sag (in units of ``SAG_SCALE``)
that each term adds at the normalisation radius R (for the curvature c its paraxial sag
c·R²/2), so that an optimizer step of a given size changes every term's sag alike.
``HybridParameterization`` maps them to the lens and back, with the same protocol as the
classical design (``jaxlens.design.params.AbstractParameterization``).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ...design.params import AbstractParameterization
from ...optics import checks
from ...optics.lens import Lens, Sensor
from ...optics.surfaces import EvenAsphere, Hybrid

CLASSICAL_FILE = "edof_classical.json"
"""File name of the classical starting lens under ``jaxlens/data/lenses``."""

DEPTHS_M = (0.1, 0.15, 0.2, 0.3, 0.5, 1.0, 3.0, 10.0)
"""The paper's 8 training depths (m, from the aperture stop)."""


FARTHEST_NEAR_DEPTH_M = 50.0
"""The nearest of a set of object depths must be at most this (m): depths (0.15, 0.3) m given
in mm set a cubic plate 3× too strong (a = 0.00543 mm⁻² for 0.00181) without a word."""


def _depths(depths_m, where: str, least: int = 1) -> np.ndarray:
    """Object depths (m): finite, > 0, distinct, at least ``least`` of them (before: one
    depth was an IndexError, a 0 m depth NaN weights, -1 m a weight of its own)."""
    checks.real_values(depths_m, "depths_m", where, "m")
    d = np.asarray(depths_m, float).reshape(-1)
    if d.size < least or not np.all(np.isfinite(d) & (d > 0)) or np.unique(d).size < d.size:
        raise ValueError(f"{where}: depths_m must be at least {least} distinct finite depths "
                         f"> 0 (m, from the stop), got {checks.fmt(d) if d.size else '()'}")
    if d.min() > FARTHEST_NEAR_DEPTH_M:
        raise ValueError(f"{where}: depths_m are in metres, and the nearest, {d.min():g} m, is "
                         f"beyond {FARTHEST_NEAR_DEPTH_M:g} m, where every depth is in focus as "
                         f"at infinity (< 0.02 D apart) for a lens focused at "
                         f"{FOCUS_DEPTH / 1e3:g} m; were they given in mm? {d.min():g} mm is "
                         f"{d.min() / 1e3:g} m")
    return d


def dioptric_weights(depths_m=DEPTHS_M) -> np.ndarray:
    """Sampling weights that spread the training depths evenly in dioptres (1/m).

    Defocus blur grows with the dioptric distance from the focus, so each depth stands for
    the dioptric interval halfway to its neighbours (an end depth mirrors its one gap). For
    the paper's 8 depths the weights fall from 0.29 (10 cm) to 0.02 (10 m) and their
    dioptric mean is 5.7 D (18 cm), near the 20 cm focus; drawing the 8 depths uniformly
    has a mean of 3.6 D (28 cm), which pulls a trainable focus away from the near depths.
    """
    dioptres = 1.0 / _depths(depths_m, "dioptric_weights", least=2)
    near_first = np.argsort(-dioptres)
    d = dioptres[near_first]
    edges = np.concatenate([[2 * d[0] - d[1]], d, [2 * d[-1] - d[-2]]])
    w = np.empty_like(d)
    w[near_first] = 0.5 * (edges[:-2] - edges[2:])
    return w / w.sum()


TEST_DEPTHS_M = (0.1, 0.2, 10.0)
"""The depths of the paper's Table 2 (m)."""

WAVELENGTHS_RGB = (0.656, 0.587, 0.486)
"""One wavelength per colour channel (µm): R, G, B."""

FOCUS_DEPTH = 200.0
"""The classical lens is focused at 20 cm (mm from the stop)."""

SPEC = {
    "efl_mm": 5.55,
    "epd_mm": 2.60,
    "fnum": 5.55 / 2.60,
    "fov_deg": 68.8,
    "image_height_mm": 7.20,
    "pixel_size_mm": 0.00497,
    "sensor_pixels": (1024, 1024),
    "focus_mm": FOCUS_DEPTH,
}
"""The paper's specification of the EDoF lens (full-resolution sensor)."""

SAG_SCALE = 0.01
"""Sag unit (mm) of the scaled polynomial parameters and of the focus shift."""


def _load(path):
    try:
        from ... import load
    except ImportError:  # pragma: no cover - the files module ships with jaxlens
        from ...io.lensfile import load_json as load
    return load(path)


def classical_lens(*, binning: int = 1) -> Lens:
    """The classical starting lens (stop first, focused at 20 cm), with its sensor.

    Args:
        binning: sensor pixel binning; the sensor keeps its size (5.09 mm square) with
            ``1024 // binning`` pixels of ``4.97 µm · binning`` per side.

    Returns:
        The lens, loaded from ``jaxlens/data/lenses/edof_classical.json``.
    """
    ref = importlib.resources.files("jaxlens") / "data" / "lenses" / CLASSICAL_FILE
    with importlib.resources.as_file(ref) as path:
        lens = _load(path)
    return with_binning(lens, binning)


def with_binning(lens: Lens, binning: int) -> Lens:
    """The lens with the paper's 7.20 mm-diagonal sensor binned ``binning`` × ``binning``."""
    if isinstance(binning, bool) or not isinstance(binning, (int, np.integer)) or \
            binning < 1 or SPEC["sensor_pixels"][0] % binning:
        raise ValueError(f"with_binning: binning must be a whole number that divides 1024 "
                         f"(sensor pixels per side of a binned pixel), got {binning!r}")
    n = SPEC["sensor_pixels"][0] // binning
    sensor = Sensor((n, n), jnp.asarray(SPEC["pixel_size_mm"] * binning, lens.epd.dtype))
    return eqx.tree_at(lambda m: m.sensor, lens, sensor, is_leaf=lambda x: x is None)


def stop_z(lens: Lens) -> Array:
    """Global z of the aperture stop (mm)."""
    return lens.vertex_z()[lens.stop]


def object_depth(lens: Lens, depth) -> Array:
    """Object distance from surface 1 (mm) of an object ``depth`` mm in front of the stop:
    ``depth − stop_z`` (the stop lies ``stop_z`` behind surface 1; 0 for a stop-first lens).

    Raises:
        ValueError: For a concrete depth that is not > 0 mm (NaN, zero or behind the stop;
            +inf, an object at infinity, is taken). Traced depths are not checked.
    """
    if not checks.is_traced(depth):  # -200 gave a virtual object 200 mm behind the stop
        checks.real_values(depth, "depth", "object_depth", "mm")
        checks.values(depth, "depth", "object_depth", lo=0, lo_open=True, unit="mm",
                      inf_ok=True)
    return jnp.asarray(depth) - stop_z(lens)  # was + : 2·stop_z too far behind a front group


def first_lens_surface(lens: Lens) -> int:
    """Index of the first refracting surface after the stop."""
    return lens.stop + 1


def _surface_index(lens: Lens, index, where: str) -> int:
    """A surface index in [0, num_surfaces − 1] (default: the first after the stop): -1 put
    the hybrid surface in front of every surface, a lens of twice the surfaces."""
    if index is None:
        return first_lens_surface(lens)
    last = lens.num_surfaces - 1
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or \
            not 0 <= index <= last:
        raise ValueError(f"{where}: index must be a surface index in [0, {last}] (0-based; "
                         f"None for the first surface after the stop), got {index!r}")
    return int(index)


def to_hybrid(lens: Lens, *, n_odd: int = 3, cubic: float = 0.0, index: int | None = None) -> Lens:
    """Replace a surface (default: the first after the stop) by a ``Hybrid`` surface.

    The even part (c, k, even coefficients, semi-diameter) is kept; the odd polynomial has
    ``n_odd`` terms per axis (x³, x⁵, …), all zero except the cubic terms, set to ``cubic``
    (mm⁻²) on both axes.
    """
    i = _surface_index(lens, index, "to_hybrid")
    checks.number(n_odd, "n_odd", "to_hybrid", lo=1, hi=64, integer=True,
                  unit="odd terms per axis (x³, x⁵, …)")
    s = lens.surfaces[i]
    coeffs = s.even_coeffs()
    dtype = jnp.result_type(s.c)
    odd = jnp.zeros((n_odd,), dtype).at[0].set(cubic)
    hyb = Hybrid(c=s.c, k=s.k, coeffs=coeffs, odd_x=odd, odd_y=odd, semi_diameter=s.semi_diameter)
    surfaces = lens.surfaces[:i] + (hyb,) + lens.surfaces[i + 1 :]
    return eqx.tree_at(lambda m: m.surfaces, lens, surfaces)


def cubic_strength_guess(lens: Lens, *, depths_m=DEPTHS_M, ratio: float = 1.5) -> float:
    """A cubic phase-plate strength a (mm⁻², sag a·(x³ + y³)) from the defocus to hide.

    The defocus wavefront at the pupil edge of an object at distance z (stop-first lens
    focused at ``FOCUS_DEPTH``) is W = ½·(1/z − 1/z_f)·R² with R the entrance-pupil radius.
    The plate's path difference at the pupil edge along x, (n − 1)·a·R³ with n the index of
    the first lens element, is set to ``ratio`` times the largest |W| over the depths (the
    Dowski–Cathey rule of thumb: the cubic term must dominate the defocus it hides).
    """
    depths_m = _depths(depths_m, "cubic_strength_guess")
    checks.number(ratio, "ratio", "cubic_strength_guess", lo=0, lo_open=True,
                  unit="(cubic path over the largest defocus)")
    r = 0.5 * float(lens.epd)
    w = max(abs(0.5 * (1.0 / (1e3 * d) - 1.0 / FOCUS_DEPTH) * r * r) for d in depths_m)
    n = float(lens.materials[first_lens_surface(lens)].index(0.5876))
    return ratio * w / ((n - 1.0) * r**3)


# --------------------------------------------------------------------------------------
# Trainable parameters, all as sags at R in units of SAG_SCALE
# --------------------------------------------------------------------------------------
class HybridParams(eqx.Module):
    """Scaled parameters of a hybrid surface and of the sensor position (R: the normalisation
    radius of ``HybridParameterization``).

    Attributes:
        c: the base sphere's paraxial sag at R, c·R²/2, over ``SAG_SCALE`` (in the same unit
            as the other terms: as curvature × R, a step of Adam's size was a 66× larger sag
            change and moved the focus by several depths of focus per lens update).
        k: conic constant.
        even: even coefficients from r⁴ on, each as its sag at R over ``SAG_SCALE``
            (the r² coefficient stays at its value: it duplicates the curvature).
        odd_x, odd_y: odd coefficients (x³, x⁵, …), each as its sag at R over ``SAG_SCALE``.
        focus: sensor shift along z over ``SAG_SCALE`` (mm).
    """

    c: Float[Array, ""]
    k: Float[Array, ""]
    even: Float[Array, " m"]
    odd_x: Float[Array, " p"]
    odd_y: Float[Array, " p"]
    focus: Float[Array, ""]


class HybridParameterization(AbstractParameterization):
    """Maps ``HybridParams`` to a lens: its surface ``index`` (a ``Hybrid``) and sensor
    position, the rest of ``template`` held (the protocol of ``jaxlens.design.params``).

    Attributes:
        template: the lens the parameters are written into (a ``Hybrid`` at ``index``).
        radius: normalisation radius R (mm); held, not differentiated.
        index: index of the hybrid surface (static).
    """

    template: Lens
    radius: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    index: int = eqx.field(static=True)

    @classmethod
    def of(cls, lens: Lens, *, index: int | None = None, radius=None) -> HybridParameterization:
        """The parameterisation of ``lens`` at its surface ``index`` (default: the first after
        the stop), with R = ``radius`` (default: the entrance-pupil radius)."""
        i = first_lens_surface(lens) if index is None else index
        s = lens.surfaces[i]
        if not isinstance(s, Hybrid):
            raise ValueError(f"HybridParameterization: surface {i} is a {type(s).__name__}, "
                             f"not Hybrid")
        r = jnp.asarray(0.5 * lens.epd if radius is None else radius)
        return cls(lens, r, i)

    def from_lens(self, lens: Lens) -> HybridParams:
        """Parameters that reproduce ``lens`` (of the template's structure; focus 0 when its
        sensor sits where the template's does)."""
        s = lens.surfaces[self.index]
        r = self.radius
        ev_pow = 2 * jnp.arange(2, s.coeffs.shape[0] + 1)  # r^4, r^6, ...
        od_pow = 2 * jnp.arange(s.odd_x.shape[0]) + 3  # x^3, x^5, ...
        shift = lens.thickness[-1] - self.template.thickness[-1]
        return HybridParams(
            c=s.c * r * r / (2 * SAG_SCALE),
            k=s.k,
            even=s.coeffs[1:] * r**ev_pow / SAG_SCALE,
            odd_x=s.odd_x * r**od_pow / SAG_SCALE,
            odd_y=s.odd_y * r**od_pow / SAG_SCALE,
            focus=shift / SAG_SCALE,
        )

    def to_lens(self, p: HybridParams) -> Lens:
        """The template with the parameters written in."""
        lens = self.template
        s = lens.surfaces[self.index]
        r = jax.lax.stop_gradient(self.radius).astype(p.c.dtype)
        ev_pow = 2 * jnp.arange(2, p.even.shape[0] + 2)
        od_pow = 2 * jnp.arange(p.odd_x.shape[0]) + 3
        coeffs = jnp.concatenate(
            [s.coeffs[:1].astype(p.even.dtype), p.even * SAG_SCALE / r**ev_pow]
        )
        new = Hybrid(
            c=p.c * 2 * SAG_SCALE / (r * r),
            k=p.k,
            coeffs=coeffs,
            odd_x=p.odd_x * SAG_SCALE / r**od_pow,
            odd_y=p.odd_y * SAG_SCALE / r**od_pow,
            semi_diameter=s.semi_diameter,
        )
        t = lens.thickness.at[-1].add(p.focus * SAG_SCALE)
        return eqx.tree_at(lambda m: (m.surfaces[self.index], m.thickness), lens, (new, t))


def gates(params: HybridParams, kind: str) -> tuple[HybridParams, Array]:
    """Which parameters a lens may change: a gate pytree (1 trainable, 0 frozen) and a tie.

    ``kind`` is "frozen" (nothing moves), "classical" (only the sensor position: the
    classical lens with a trainable focus), "hybrid" (everything moves), "hybrid-held-focus"
    (everything but the base curvature and the sensor position) or "cubic" (the cubic phase
    plate at the aperture: only the x³ and y³ terms, tied to one strength a of the sag
    a·(x³ + y³), and the sensor position move; ``project`` keeps a above its floor). All
    lenses are thus the same ``HybridParams`` (and share one compiled training step); a lens
    starts as ``to_hybrid(classical, cubic=a)``. With ``tie = 1`` the gradients of the x³
    and y³ coefficients are replaced by their mean (``apply_gates``), so Adam moves them
    together.
    """
    ones = jax.tree_util.tree_map(jnp.ones_like, params)
    zeros = jax.tree_util.tree_map(jnp.zeros_like, params)
    dtype = params.c.dtype
    if kind == "hybrid":
        gate, tie = ones, 0.0
    elif kind == "hybrid-held-focus":
        # The paraxial focus stays at the classical lens's 20 cm: no sensor shift, no change
        # of the base curvature (the r² term is not a parameter), so depth of field can only
        # come from the aspheric and odd terms, not from refocusing.
        gate = eqx.tree_at(lambda p: (p.c, p.focus), ones, (zeros.c, zeros.focus))
        tie = 0.0
    elif kind == "frozen":
        gate, tie = zeros, 0.0
    elif kind == "classical":
        gate = eqx.tree_at(lambda p: p.focus, zeros, jnp.ones_like(params.focus))
        tie = 0.0
    elif kind == "cubic":
        first = jnp.zeros_like(params.odd_x).at[0].set(1.0)
        gate = eqx.tree_at(
            lambda p: (p.odd_x, p.odd_y, p.focus),
            zeros,
            (first, first, jnp.ones_like(params.focus)),
        )
        tie = 1.0
    else:
        raise ValueError(f"gates: kind must be frozen, classical, cubic, hybrid or "
                         f"hybrid-held-focus, got {kind!r}")
    return gate, jnp.asarray(tie, dtype)


def project(params: HybridParams, floor) -> HybridParams:
    """The parameters with the cubic strength (the x³ and y³ terms) held at or above ``floor``
    (scaled units; ``-inf`` for no bound): the cubic plate stays a cubic plate."""
    fx = jnp.maximum(params.odd_x[0], floor)
    fy = jnp.maximum(params.odd_y[0], floor)
    return eqx.tree_at(lambda p: (p.odd_x, p.odd_y), params,
                       (params.odd_x.at[0].set(fx), params.odd_y.at[0].set(fy)))


def apply_gates(grads: HybridParams, gate: HybridParams, tie) -> HybridParams:
    """Gradients masked by ``gate``, with the cubic x³/y³ pair averaged where ``tie`` is 1."""
    gx, gy = grads.odd_x, grads.odd_y
    mean = 0.5 * (gx[0] + gy[0])
    gx = gx.at[0].set((1 - tie) * gx[0] + tie * mean)
    gy = gy.at[0].set((1 - tie) * gy[0] + tie * mean)
    grads = eqx.tree_at(lambda p: (p.odd_x, p.odd_y), grads, (gx, gy))
    return jax.tree_util.tree_map(lambda g, m: g * m.astype(g.dtype), grads, gate)


# --------------------------------------------------------------------------------------
# Manufacturing and registration errors
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Tolerances:
    """Standard deviations of the random lens perturbations of the second training stage.

    Attributes:
        curvature: relative error of every curvature (e.g. 0.005 = 0.5 %).
        thickness: error of every gap and centre thickness (mm).
        sensor: error of the sensor position (mm), the focus registration.
        odd: relative error of the odd (non-symmetric) coefficients.
        asphere: relative error of the even aspheric coefficients.
    """

    curvature: float = 0.005
    thickness: float = 0.01
    sensor: float = 0.005
    odd: float = 0.02
    asphere: float = 0.01


def perturb(lens: Lens, key, tol: Tolerances = Tolerances(), *, scale=1.0) -> Lens:
    """A random copy of the lens with manufacturing and registration errors (``tol``).

    Curvatures, even and odd coefficients get relative Gaussian errors, every thickness an
    absolute one, and the sensor (last gap) its own; the stop and the system data are kept.
    ``scale`` (a number or an array) multiplies every standard deviation (0: no change).
    """
    dt = lens.thickness.dtype
    tol = Tolerances(
        *(jnp.asarray(scale, dt) * jnp.asarray(v, dt) for v in dataclasses.astuple(tol))
    )
    keys = jax.random.split(key, 4 * len(lens.surfaces) + 2)
    surfaces = []
    for i, s in enumerate(lens.surfaces):
        k1, k2, k3, k4 = keys[4 * i : 4 * i + 4]
        new = s
        if i != lens.stop:
            new = eqx.tree_at(
                lambda x: x.c,
                new,
                s.c * (1 + tol.curvature * jax.random.normal(k1, s.c.shape, s.c.dtype)),
            )
        if isinstance(s, EvenAsphere | Hybrid) and s.coeffs.shape[0]:
            n = jax.random.normal(k2, s.coeffs.shape, s.coeffs.dtype)
            new = eqx.tree_at(lambda x: x.coeffs, new, s.coeffs * (1 + tol.asphere * n))
        if isinstance(s, Hybrid) and s.odd_x.shape[0]:
            nx = jax.random.normal(k3, s.odd_x.shape, s.odd_x.dtype)
            ny = jax.random.normal(k4, s.odd_y.shape, s.odd_y.dtype)
            new = eqx.tree_at(
                lambda x: (x.odd_x, x.odd_y),
                new,
                (s.odd_x * (1 + tol.odd * nx), s.odd_y * (1 + tol.odd * ny)),
            )
        surfaces.append(new)
    t = lens.thickness
    dt = tol.thickness * jax.random.normal(keys[-2], t.shape, t.dtype)
    dt = dt.at[-1].set(tol.sensor * jax.random.normal(keys[-1], (), t.dtype))
    return eqx.tree_at(
        lambda m: (m.surfaces, m.thickness), lens, (tuple(surfaces), jnp.maximum(t + dt, 0.05 * t))
    )


def odd_profile(lens: Lens, *, index: int | None = None, n: int = 101, radius=None):
    """Height (mm) of the odd polynomial of a hybrid surface over its aperture.

    Returns:
        ``(x [n] mm, height [n, n] mm)`` with ``height[i, j]`` at (x[j], y[i]); NaN outside
        the disc of ``radius`` (default the entrance-pupil radius).
    """
    i = _surface_index(lens, index, "odd_profile")
    n = checks.number(n, "n", "odd_profile", lo=2, hi=checks.MAX_IMAGE_SIDE, integer=True,
                      unit="points per side")
    s = lens.surfaces[i]
    if not isinstance(s, Hybrid):
        raise ValueError(f"odd_profile: surface {i} is not a Hybrid surface")
    r = float(0.5 * lens.epd if radius is None else radius)
    x = np.linspace(-r, r, n)
    xx, yy = np.meshgrid(x, x, indexing="xy")
    bx, by = np.asarray(s.odd_x, float), np.asarray(s.odd_y, float)
    h = np.zeros_like(xx)
    for j in range(bx.shape[0]):
        h += bx[j] * xx ** (2 * j + 3) + by[j] * yy ** (2 * j + 3)
    h[xx**2 + yy**2 > r * r] = math.nan
    return x, h
