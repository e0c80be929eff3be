"""Design losses: the fast ray-based RMS spot loss and the image-based loss.

Conventions:
    Lengths in mm (spot errors too), field angles in degrees, wavelengths in µm. The object
    is at infinity. A design stage is described by :class:`StageArgs`: the stage's half
    diagonal field (as ``tan_max = tan(half FoV)``), its entrance pupil diameter, the spot
    reference blend ``beta`` and per-field weights.

Ray loss:
    The lens is rotationally symmetric, so the loss traces fields along +y only: K fields at
    image-height fractions ``u_k`` of the stage's field (``tan θ_k = u_k · tan_max``), each
    weighted by the share of the 16 × 16 evaluation grid at that radius (so the loss is the
    radial stand-in of the 256-field mean), at every design wavelength, over the half pupil
    x ≥ 0 (points on x = 0 count once, the others twice: the spot is symmetric in x),
    launched at the paraxial entrance pupil whatever ``Lens.aim`` says (speed). Per
    field the polychromatic mean square spot error is

        MS_k = Σ_{w,p} ω_p e²_{wp} / Σ_{w,p} ω_p,

    with ω_p the pupil weight and e = |p − ref_k| for a ray that reaches the image, or a
    fixed EPD/2 for a ray that fails (so vignetting or losing rays never pays). The
    reference blends the ideal image point (0, f·tan θ_k) (distortion-free, pinhole; f the
    spec's focal length, or with an EFL target f·tan θ_k·(1 + k·tan²θ_k), see
    ``DesignSpec.image_mapping``) and the polychromatic centroid:
    ``ref = beta·centroid + (1 − beta)·ideal``. With the centroid reference, ``pin`` adds
    the squared miss of the full-field centroid height from the sensor's (stage) half
    diagonal, so the field still fills the sensor while distortion relaxes. The loss is
    ``spot_scale · Σ_k w_k·MS_k`` (w_k normalised to sum 1) plus the pin and the weighted
    regularizers; its residual form (for least squares) has the same sum of squares.

    The loss launches its own rays over the whole (half) pupil at the stage's fields: the
    lens's vignetting factors (``Lens.vignetting``) are never applied, and the design
    variables (``params.LensParams``) do not include them.
"""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..imaging.sampling import grid_axis, pupil_hexapolar
from ..optics import checks, paraxial
from ..optics.lens import Lens, Sensor
from ..optics.rays import Rays
from ..tracing.forward import stacked_surfaces, trace_path


class StageArgs(eqx.Module):
    """Per-stage (and per-epoch) inputs of the losses, all arrays so stages share one compile.

    Attributes:
        tan_max: tan of the stage's half diagonal field.
        epd: entrance pupil diameter of the stage, mm.
        focal: the spec focal length f (mm) that sets the ideal image points.
        distortion_k: the ideal image height is ``focal·tanθ·(1 + distortion_k·tan²θ)``
            (0: distortion-free; see ``DesignSpec.image_mapping``).
        beta: spot reference blend, 0 = ideal image point, 1 = centroid.
        pin: weight of the full-field image-height pin (used with the centroid reference).
        spot_scale: factor (1/mm²) on the spot and pin terms; the design loop sets it to the
            inverse of the weighted mean square spot error at the start of each epoch, so the
            spot term is about 1 and the regularizer weights keep one meaning all run long.
        field_weights: ``[K]`` weight of each loss field (area × mask × re-weighting).
        reg_weights: ``[3]`` weights of the obliquity, spacing and slope regularizers.
    """

    tan_max: Float[Array, ""]
    epd: Float[Array, ""]
    focal: Float[Array, ""]
    beta: Float[Array, ""]
    pin: Float[Array, ""]
    spot_scale: Float[Array, ""]
    field_weights: Float[Array, " K"]
    reg_weights: Float[Array, " 3"]
    distortion_k: Float[Array, ""] = 0.0

    def __check_init__(self):
        # Built by ``curriculum.stage_args`` with a leading batch axis; checked where concrete.
        # Before: beta 2 (a blend past the centroid), NaN, negative weights and two
        # regulariser weights all ran. tan_max has no upper bound (fov < 180°).
        where = "StageArgs"
        if np.shape(self.reg_weights)[-1:] != (3,):
            raise ValueError(f"{where}: reg_weights must end in 3 (obliquity, spacing, slope "
                             f"weights), got shape {np.shape(self.reg_weights)}")
        for arg, lo, hi, unit in (
                ("tan_max", 0, None, "(tan of the half diagonal field, not degrees)"),
                ("epd", 0, None, "mm"), ("focal", None, None, "mm"), ("beta", 0, 1, ""),
                ("pin", 0, None, ""), ("spot_scale", 0, None, "1/mm²"),
                ("field_weights", 0, None, ""), ("reg_weights", 0, None, ""),
                ("distortion_k", None, None, "")):
            v = getattr(self, arg)
            if not checks.is_traced(v):
                checks.real_values(v, arg, where, unit)
                checks.values(v, arg, where, lo=lo, hi=hi, lo_open=arg == "epd", unit=unit)


def radial_area_weights(fracs, sensor_size, n: int = 16) -> np.ndarray:
    """Share of the evaluation fields nearest to each radial field fraction (sums to 1).

    The evaluation grid is ``n × n`` points ``linspace(−1, 1, n)`` over the sensor rectangle
    (``jaxlens.design.evaluate``); each point votes for the loss field whose fraction of the
    half diagonal is nearest to its own radius. With the default ``n = 16`` the loss is
    the radial stand-in of the 256-field mean.

    Args:
        fracs: increasing field fractions in [0, 1] of the half diagonal.
        sensor_size: (height, width) in mm.
        n: evaluation grid per side.

    Returns:
        ``[K]`` weights.
    """
    where = "radial_area_weights"
    checks.real_values(fracs, "fracs", where, "fraction of the half diagonal")
    fracs = np.asarray(fracs, float)
    # Before: [] gave NaN weights, 1.5 a field no grid point reached (weight 0, silently),
    # decreasing fracs weights in the wrong order, NaN all weight on one field.
    if fracs.ndim != 1 or fracs.size == 0:
        raise ValueError(f"{where}: fracs must be [K] field fractions with K >= 1, got shape "
                         f"{fracs.shape}")
    checks.values(fracs, "fracs", where, lo=0, hi=1, unit="(fraction of the half diagonal)")
    if np.any(np.diff(fracs) <= 0):
        raise ValueError(f"{where}: fracs must increase strictly (fractions of the half "
                         f"diagonal in [0, 1]), got {checks.fmt(fracs)}")
    # Before: n = 0 gave NaN weights and a negative sensor side plausible ones.
    checks.number(n, "n", "radial_area_weights", lo=1, hi=checks.MAX_MAP_GRID, integer=True,
                  unit="fields per side")
    if np.shape(sensor_size) != (2,):
        raise ValueError(f"radial_area_weights: sensor_size must be (height, width) in mm, got "
                         f"{sensor_size!r}")
    h, w = (checks.number(v, "sensor_size", "radial_area_weights", lo=0, lo_open=True,
                          unit="mm (height, width)") for v in sensor_size)
    y, x = np.meshgrid(grid_axis(n) * h / 2, grid_axis(n) * w / 2)  # evaluate's grid
    r = np.hypot(x, y).ravel() / math.hypot(h / 2, w / 2)
    edges = np.concatenate([[-np.inf], 0.5 * (fracs[1:] + fracs[:-1]), [np.inf]])
    counts = np.histogram(r, bins=edges)[0].astype(float)
    return counts / counts.sum()


def half_pupil(rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Hexapolar points of the half pupil x ≥ 0 and their weights (1 on x = 0, else 2)."""
    checks.number(rings, "rings", "half_pupil", lo=1, hi=MAX_RINGS, integer=True,
                  unit="pupil rings")
    p = np.asarray(pupil_hexapolar(rings))
    keep = p[:, 0] >= -1e-9
    p = p[keep]
    on_axis = np.abs(p[:, 0]) < 1e-9
    p[on_axis, 0] = 0.0
    return p, np.where(on_axis, 1.0, 2.0)


MAX_RINGS = 64
"""Most hexapolar pupil rings of the ray loss (``RayLoss.make``, ``DesignConfig.rings``,
``polish_rings``): 64 rings are 12 481 rays per field and wavelength, and the loss holds every
one of them per step."""


class RayLoss(eqx.Module):
    """Sampling of the ray-based spot loss (static sizes, array values).

    Attributes:
        fracs: ``[K]`` field fractions of the stage's half diagonal.
        area: ``[K]`` sensor-area weight of each field.
        pupil: ``[P, 2]`` unit-pupil points (half pupil).
        pupil_weights: ``[P]``.
        wavelengths: ``[W]`` µm.
    """

    fracs: Float[Array, " K"]
    area: Float[Array, " K"]
    pupil: Float[Array, "P 2"]
    pupil_weights: Float[Array, " P"]
    wavelengths: Float[Array, " W"]

    @staticmethod
    def make(n_fields: int, rings: int, wavelengths, sensor_size, dtype=None) -> RayLoss:
        """K fields from 0 to 1 (equal steps), a ``rings``-ring hexapolar half pupil."""
        # Before: n_fields 0 gave an empty loss, 10**9 ran for minutes in linspace, rings 0
        # one ray per field, and wavelengths in nm a loss no trace could compute.
        checks.number(n_fields, "n_fields", "RayLoss.make", lo=1, hi=checks.MAX_MAP_GRID,
                      integer=True, unit="fields")
        checks.number(rings, "rings", "RayLoss.make", lo=1, hi=MAX_RINGS, integer=True,
                      unit="pupil rings")
        checks.real_values(wavelengths, "wavelengths", "RayLoss.make", "µm")
        checks.wavelengths(checks.NoMaterials, wavelengths, "RayLoss.make", "wavelengths")
        checks.float_dtype(dtype, "RayLoss.make")
        dtype = dtype or jnp.result_type(float)
        fracs = np.linspace(0.0, 1.0, n_fields)
        p, pw = half_pupil(rings)
        return RayLoss(
            fracs=jnp.asarray(fracs, dtype),
            area=jnp.asarray(radial_area_weights(fracs, sensor_size), dtype),
            pupil=jnp.asarray(p, dtype),
            pupil_weights=jnp.asarray(pw, dtype),
            wavelengths=jnp.asarray(wavelengths, dtype),
        )

    def __check_init__(self):
        # Built directly (not by ``make``), nothing was checked: fractions past the corner,
        # wavelengths in nm, pupil points outside the pupil, and a weight list of another
        # length (broadcast, or clamped by indexing) all ran.
        where = "RayLoss"
        k, p = np.shape(self.fracs), np.shape(self.pupil)
        for arg, want in (("fracs", k[:1]), ("area", k[:1]), ("pupil", (p[:1] + (2,))),
                          ("pupil_weights", p[:1]), ("wavelengths", None)):
            shape = np.shape(getattr(self, arg))
            if len(shape) != (2 if arg == "pupil" else 1) or (want is not None and shape != want):
                n_k, n_p = (k[0] if k else "?"), (p[0] if p else "?")
                raise ValueError(f"{where}: {arg} must have shape "
                                 f"{want if want is not None else '(W,)'} (K = {n_k} fields, "
                                 f"P = {n_p} pupil points), got {shape}")
        for arg, lo, hi, unit in (("fracs", 0, 1, "(fraction of the half diagonal)"),
                                  ("area", 0, None, ""), ("pupil", -1, 1, "(unit pupil)"),
                                  ("pupil_weights", 0, None, "")):
            v = getattr(self, arg)
            if not checks.is_traced(v):
                checks.real_values(v, arg, where, unit)
                checks.values(v, arg, where, lo=lo, hi=hi, unit=unit)
        if not checks.is_traced(self.pupil):
            r = np.hypot(*np.asarray(self.pupil, float).T)
            if np.any(r > 1 + 1e-9):
                raise ValueError(f"{where}: pupil points must lie in the unit disc (normalised "
                                 f"to the entrance pupil), got radius {checks.fmt(r.max())}")
        if not checks.is_traced(self.wavelengths):
            checks.wavelengths(checks.NoMaterials, self.wavelengths, where, "wavelengths")

    @property
    def n_fields(self) -> int:
        return self.fracs.shape[0]


def launch(lens: Lens, sampling: RayLoss, args: StageArgs) -> Rays:
    """Collimated rays ``[K, W, P]`` at the stage's fields, aimed at the paraxial entrance pupil."""
    dtype = sampling.pupil.dtype
    tan = sampling.fracs * args.tan_max  # [K]
    direction = jnp.stack([jnp.zeros_like(tan), tan, jnp.ones_like(tan)], -1)
    direction = direction / jnp.linalg.norm(direction, axis=-1, keepdims=True)
    zep = paraxial.entrance_pupil_z(lens)
    xy = sampling.pupil * (0.5 * args.epd)  # [P, 2]
    # Shift the launch plane so every beam's centre ray passes the entrance pupil centre.
    origin = jnp.concatenate([xy, jnp.broadcast_to(zep, xy.shape[:1])[:, None]], -1)
    K, W, P = sampling.n_fields, sampling.wavelengths.shape[0], xy.shape[0]
    o = jnp.broadcast_to(origin[None, None], (K, W, P, 3)).astype(dtype)
    d = jnp.broadcast_to(direction[:, None, None, :], (K, W, P, 3)).astype(dtype)
    wl = jnp.broadcast_to(sampling.wavelengths[None, :, None], (K, W, P)).astype(dtype)
    return Rays(o, d, wl)


class SpotResult(eqx.Module):
    """Spot errors of one lens: residuals and per-field statistics."""

    residuals: Float[Array, "K W P 2"]  # weighted so that Σ residuals² = the spot loss
    ms: Float[Array, " K"]  # mean square spot error per field (mm²)
    valid_fraction: Float[Array, " K"]
    centroid_y: Float[Array, " K"]
    pin: Float[Array, ""]  # weighted pin residual


def spot_errors(path: Rays, sampling: RayLoss, args: StageArgs) -> SpotResult:
    """Spot residuals on the image surface from a traced path (see module docstring)."""
    img = jax.tree.map(lambda x: x[-1] if x.ndim else x, path)
    p = img.origin[..., :2]  # [K, W, P, 2]
    valid = img.valid
    pw = jnp.broadcast_to(sampling.pupil_weights, valid.shape).astype(p.dtype)
    v = valid.astype(p.dtype) * pw  # [K, W, P]
    safe = jnp.maximum(jnp.sum(v, axis=(1, 2)), 1e-12)  # [K]
    total = jnp.sum(pw, axis=(1, 2))  # [K]
    cen = jnp.sum(v[..., None] * p, axis=(1, 2)) / safe[:, None]  # [K, 2]
    tan = sampling.fracs * args.tan_max
    ideal_y = args.focal * tan * (1.0 + args.distortion_k * tan**2)
    ideal = jnp.stack([jnp.zeros_like(tan), ideal_y], -1)
    ref = args.beta * cen + (1.0 - args.beta) * ideal
    err = jnp.where(valid[..., None], p - ref[:, None, None, :], 0.0)
    # A ray that fails is charged a fixed error of half the entrance pupil diameter, so that
    # losing rays never lowers the loss (it carries no gradient).
    miss = 0.5 * args.epd
    err = jnp.where(valid[..., None], err, jnp.stack([miss, 0.0 * miss]).astype(p.dtype))
    ms = jnp.sum(pw * jnp.sum(err**2, -1), axis=(1, 2)) / total
    w = args.field_weights / jnp.maximum(jnp.sum(args.field_weights), 1e-12)
    scale = jnp.sqrt(args.spot_scale * w / total)[:, None, None] * jnp.sqrt(pw)
    residuals = err * scale[..., None]
    # The stage's full-field image height (the sensor half diagonal in the last stages).
    height = args.focal * args.tan_max * (1.0 + args.distortion_k * args.tan_max**2)
    pin = jnp.sqrt(args.pin * args.spot_scale) * (cen[-1, 1] - height)
    frac = jnp.sum(v, axis=(1, 2)) / total
    return SpotResult(residuals, ms, frac, cen[:, 1], pin)


class Aux(eqx.Module):
    """Diagnostics returned with the design residuals."""

    loss: Float[Array, ""]  # total sum of squares
    spot: Float[Array, ""]  # sensor-area mean of the per-field mean square spot error (mm²)
    rms: Float[Array, " K"]  # RMS spot error per loss field (mm)
    valid_fraction: Float[Array, " K"]
    regs: Float[Array, " 3"]  # unweighted obliquity, spacing, slope penalties


def design_residuals(params, pmap, sampling: RayLoss, args: StageArgs, gap_bounds, *,
                     reverse_rule: bool = False):
    """All residuals of a design (spot, pin and the three weighted regularizers).

    Args:
        params: ``LensParams`` of one design.
        pmap: the ``Parameterization``.
        sampling: the ray-loss sampling.
        args: the stage inputs.
        gap_bounds: ``[n]`` spacing bounds (mm), see ``design.init.gap_bounds``.
        reverse_rule: (static) trace with the hand-written reverse rule
            (``trace_path(reverse_rule=True)``): the same values, a faster ``grad``, but no
            forward mode (``jacfwd`` raises a TypeError).

    Returns:
        ``(residuals [R], Aux)``; the design loss is ``Σ residuals²``.
    """
    from . import regularizers as reg

    lens = pmap.to_lens(params)
    rays = launch(lens, sampling, args)
    path = trace_path(lens, rays, uniform=True, reverse_rule=reverse_rule)
    spot = spot_errors(path, sampling, args)
    stack = stacked_surfaces(lens.surfaces)
    radii = reg.clear_radii(path)
    h_obl = reg.obliquity(stack, lens.vertex_z(), lens.stop, rays, path)
    h_gap = reg.spacing(lens, stack, radii, jnp.asarray(gap_bounds, radii.dtype))
    h_slope = reg.slope(stack, lens.stop, radii)
    w = jnp.sqrt(args.reg_weights)
    res = jnp.concatenate([
        spot.residuals.reshape(-1), spot.pin[None], w[0] * h_obl, w[1] * h_gap, w[2] * h_slope,
    ])
    regs = jnp.stack([jnp.sum(h_obl**2), jnp.sum(h_gap**2), jnp.sum(h_slope**2)])
    total = jnp.sum(res**2)
    aux = Aux(total, jnp.sum(sampling.area * spot.ms), jnp.sqrt(spot.ms), spot.valid_fraction,
              regs)
    return res, aux


class Objective(eqx.Module):
    """The design objective as a pytree: ``objective(params, args) -> (residuals, Aux)``.

    Attributes:
        pmap: the ``Parameterization``.
        sampling: the ray-loss sampling.
        gap_bounds: ``[n]`` spacing bounds (mm).
        efl: paraxial EFL target (mm, ``DesignSpec.efl``), or None for a free EFL. When set,
            one more residual ``sqrt(efl_weight · beta · spot_scale) · (EFL − efl)`` is
            appended (last): with the centroid reference (beta = 1) an EFL miss of δ mm
            costs as much as a mean square spot error of ``efl_weight · δ²`` mm². With the
            ideal reference (beta = 0) it is off: the ideal image points already carry the
            EFL (``DesignSpec.image_mapping``), and from a nearly flat start an EFL residual
            would outweigh the spots and crowd the elements.
        efl_weight: weight of that residual.
        reverse_rule: trace with the hand-written reverse rule (``design_residuals``): for
            solvers that take only reverse-mode gradients (``reverse_mode`` sets it).
    """

    pmap: object
    sampling: RayLoss
    gap_bounds: Float[Array, " n"]
    efl: float | None = eqx.field(static=True, default=None)
    efl_weight: float = eqx.field(static=True, default=1.0)
    reverse_rule: bool = eqx.field(static=True, default=False)

    def __check_init__(self):  # before: a negative weight rewarded missing the EFL target
        checks.number(self.efl_weight, "efl_weight", "Objective", lo=0,
                      unit="(weight of the EFL residual)")
        if self.efl is not None:
            # As DesignSpec.efl: -50 steered the design toward a negative (diverging) lens.
            checks.number(self.efl, "efl", "Objective", lo=0, lo_open=True,
                          unit="mm (None for a free EFL)")

    def __call__(self, params, args: StageArgs):
        res, aux = design_residuals(params, self.pmap, self.sampling, args, self.gap_bounds,
                                    reverse_rule=self.reverse_rule)
        if self.efl is None:
            return res, aux
        f = paraxial.efl(self.pmap.to_lens(params))
        r = jnp.sqrt(self.efl_weight * args.beta * args.spot_scale) * (f - self.efl)
        aux = eqx.tree_at(lambda a: a.loss, aux, aux.loss + r**2)
        return jnp.concatenate([res, r[None]]), aux

    def field_rms(self, params, args: StageArgs) -> Float[Array, " K"]:
        """RMS spot error per loss field (mm) at the current parameters."""
        return self(params, args)[1].rms


def reverse_mode(objective):
    """``objective`` with every ``Objective`` in it (also inside a robust or image objective)
    tracing with the hand-written reverse rule: for solvers that only take ``grad`` (Adam,
    L-BFGS-B), never for ``jacfwd`` (Levenberg–Marquardt)."""
    def on(x):
        return dataclasses.replace(x, reverse_rule=True) if isinstance(x, Objective) else x

    return jax.tree.map(on, objective, is_leaf=lambda x: isinstance(x, Objective))


class ImageObjective(eqx.Module):
    """The paper's image-based loss: render a scene through the lens, compare with the scene.

    The scene (linear RGB, one value per sensor pixel) is rendered by backward ray tracing
    (``jaxlens.imaging.render``, ``relative_illumination=False``) after the distortion relaxation of
    ``jaxlens.imaging.distortion``: the object is pre-warped by the lens's own distortion
    (``prewarp``, held fixed for the gradient), so the loss sees blur and not distortion,
    and the alignment penalty (``alignment_penalty``, weight ``alpha``, in pixels²) keeps
    distortion bounded. (Differentiating through the pre-warp, as
    ``distortion_relax.relaxed_render`` does, gave NaN gradients on a 32 × 32 sensor.) The
    residuals are the pixel differences scaled by ``sqrt(weight / n)`` (n = H·W·3 values:
    their squares sum to ``weight`` times the mean squared error), the
    penalty's square root, and the ray objective's regularizer residuals (so the
    regularizers act as with the ray loss). The stop's semi-diameter is set to the stage's
    EPD/2, as rendering needs a real aperture. The mask and the per-epoch field weights
    still come from the ray loss (``field_rms``).

    Attributes:
        ray: the ray ``Objective`` (parameterisation, sampling, regularizers).
        scene: ``[H, W, 3]`` linear scene, (H, W) the sensor's resolution (the render is
            compared with it pixel by pixel).
        sensor: the ``Sensor`` to render on (its pitch in mm; the penalty is in its pixels).
        spp: rays per pixel and wavelength.
        alpha: distortion alignment penalty weight.
        weight: weight of the mean squared pixel error.
    """

    ray: Objective
    scene: Float[Array, "H W 3"]
    sensor: object
    spp: int = eqx.field(static=True, default=4)
    alpha: float = eqx.field(static=True, default=1e-4)
    weight: float = eqx.field(static=True, default=1e3)

    def __check_init__(self):
        # Before: spp=0 built an objective whose renders had no rays (a zero image, a loss
        # of the scene's mean square), and a NaN scene a NaN loss at the first step.
        w = "ImageObjective"
        if not all(hasattr(self.ray, a) for a in ("pmap", "sampling", "field_rms")):
            raise TypeError(f"{w}: ray must be a ray Objective (jaxlens.design.Objective), got "
                            f"{type(self.ray).__name__}")
        checks.number(self.spp, "spp", w, lo=1, hi=checks.MAX_SAMPLES, integer=True,
                      unit="rays per pixel and wavelength")
        checks.number(self.alpha, "alpha", w, lo=0, unit="(alignment penalty weight)")
        checks.number(self.weight, "weight", w, lo=0, lo_open=True, unit="(pixel error weight)")
        if self.scene.ndim != 3 or self.scene.shape[-1] != 3 or self.scene.size == 0:
            raise ValueError(f"{w}: scene must be an [H, W, 3] linear image, got shape "
                             f"{self.scene.shape}")
        if not checks.is_traced(self.scene):
            checks.float_image(self.scene, w, "scene")
        # Before: any sensor was taken, and a scene of another size than the sensor failed
        # at the first step of the run, in the difference of the render and the scene.
        if not isinstance(self.sensor, Sensor):
            raise TypeError(f"{w}: sensor must be a jaxlens.Sensor, got "
                            f"{type(self.sensor).__name__}")
        if tuple(self.scene.shape[:2]) != tuple(self.sensor.resolution):
            raise ValueError(f"{w}: scene must have the sensor's resolution (rows, columns) "
                             f"{tuple(self.sensor.resolution)} pixels, the render it is "
                             f"compared with, got {tuple(self.scene.shape[:2])}")

    @property
    def sampling(self) -> RayLoss:
        return self.ray.sampling

    def field_rms(self, params, args: StageArgs):
        return self.ray.field_rms(params, args)

    def __call__(self, params, args: StageArgs):
        from ..imaging.distortion import alignment_penalty, prewarp
        from ..imaging.render import render

        res_ray, aux = self.ray(params, args)
        s = self.ray.sampling
        n_spot = s.n_fields * s.wavelengths.shape[0] * s.pupil.shape[0] * 2 + 1
        regs = res_ray[n_spot:]
        lens = self.ray.pmap.to_lens(params)
        stop = eqx.tree_at(lambda x: x.semi_diameter, lens.surfaces[lens.stop], 0.5 * args.epd)
        surfaces = tuple(stop if i == lens.stop else x for i, x in enumerate(lens.surfaces))
        lens = eqx.tree_at(lambda x: (x.surfaces, x.epd), lens, (surfaces, args.epd))
        # Distortion relaxation: render the scene pre-warped by the lens's current
        # distortion, held fixed for the gradient (the pre-warp is not differentiated: the
        # loss then sees blur, and the alignment penalty alone acts on distortion).
        warped = prewarp(jax.lax.stop_gradient(lens), self.scene, sensor=self.sensor)
        img = render(lens, warped, spp=self.spp, key=jax.random.PRNGKey(0),
                     sensor=self.sensor, relative_illumination=False)
        pen = alignment_penalty(lens, alpha=self.alpha, sensor=self.sensor)
        d = (img - self.scene).reshape(-1)
        d = d * jnp.sqrt(self.weight / d.shape[0])
        ok = pen > 0
        root = jnp.where(ok, jnp.sqrt(jnp.where(ok, pen, 1.0)), 0.0)
        res = jnp.concatenate([d.astype(regs.dtype), root[None].astype(regs.dtype), regs])
        return res, eqx.tree_at(lambda a: a.loss, aux, jnp.sum(res**2))
