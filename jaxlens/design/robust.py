"""Tolerance-aware design: the objective averaged over a fixed set of manufacturing errors.

A design that is sharp only at its nominal prescription may lose most of its quality to the
radius and thickness errors of a real build (``jaxlens.analysis.tolerance`` measures that).
:class:`RobustObjective` designs against the expected loss instead:

    L = w₀ · L(p) + (1 − w₀) · (1/K) Σ_k L(p ⊕ δ_k),

where ``δ_k`` are K perturbations drawn once (common random numbers, so the loss is smooth and
the same at every step) from the tolerances of ``jaxlens.analysis.tolerance.Tolerances``:
every optical surface's radius changes by a relative error (its curvature by the factor
1/(1 + ε), |ε| ≤ ``radius_rel``) and every free gap by an absolute error (|δ| ≤ ``thickness``
mm; the last gap, to the sensor, takes up the sum, since the track is fixed). Index,
dispersion and form errors are not design variables and are left to the Monte-Carlo analysis.
The residuals are those of the base objective stacked and scaled, so least-squares solvers see
the same sum of squares.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import checks
from .losses import Aux, StageArgs


class Perturbations(eqx.Module):
    """K draws of relative radius errors ``[K, S]`` and absolute gap errors ``[K, G]`` (mm)."""

    radius_rel: Float[Array, "K S"]
    gap: Float[Array, "K G"]


def draw_perturbations(n_surfaces: int, n_gaps: int, trials: int, *, radius_rel: float,
                       thickness: float, seed: int = 0, dtype=jnp.float64) -> Perturbations:
    """``trials`` uniform draws over ±``radius_rel`` (relative) and ±``thickness`` (mm).

    Raises:
        ValueError: a count below 1 or a negative tolerance.
    """
    from ..analysis.tolerance_spec import MAX_TRIALS
    from .init import MAX_SEED

    # Before: no upper bound (10**10 trials asked numpy for 298 GiB) and a seed of -1 was
    # numpy's "expected non-negative integer".
    checks.number(trials, "trials", "draw_perturbations", lo=1, hi=MAX_TRIALS, integer=True,
                  unit="draws")
    checks.number(seed, "seed", "draw_perturbations", lo=0, hi=MAX_SEED, integer=True)
    # n_surfaces 0 drew [K, 0] (no radius perturbed, silently), 2.5 was numpy's "cannot be
    # interpreted as an integer", and thickness=inf numpy's OverflowError.
    for arg, v in (("n_surfaces", n_surfaces), ("n_gaps", n_gaps)):
        checks.number(v, arg, "draw_perturbations", lo=1, hi=MAX_TRIALS, integer=True,
                      unit="(count)")
    checks.number(radius_rel, "radius_rel", "draw_perturbations", lo=0, hi=0.5, hi_open=True,
                  unit="(relative radius error)")
    checks.number(thickness, "thickness", "draw_perturbations", lo=0, unit="mm")
    rng = np.random.default_rng(seed)
    r = rng.uniform(-radius_rel, radius_rel, (trials, n_surfaces))
    g = rng.uniform(-thickness, thickness, (trials, n_gaps))
    return Perturbations(jnp.asarray(r, dtype), jnp.asarray(g, dtype))


def perturbed(params, draw: Perturbations):
    """``params`` with one draw applied: c → c/(1 + ε) (R → R(1 + ε)), d → d + δ."""
    c = params.c / (1.0 + draw.radius_rel.astype(params.c.dtype))
    d = params.d + draw.gap.astype(params.d.dtype)
    return eqx.tree_at(lambda p: (p.c, p.d), params, (c, d))


class RobustObjective(eqx.Module):
    """The base objective's loss averaged over fixed perturbations (module docstring).

    Attributes:
        base: the nominal objective, ``base(params, args) -> (residuals, Aux)``.
        draws: the perturbations (leading axis K).
        nominal_weight: w₀, the share of the nominal loss (0 < w₀ ≤ 1).
    """

    base: eqx.Module
    draws: Perturbations
    nominal_weight: float = eqx.field(static=True, default=0.5)

    def __check_init__(self):
        if not 0.0 < self.nominal_weight <= 1.0:
            raise ValueError(f"RobustObjective: nominal_weight must lie in (0, 1], got "
                             f"{self.nominal_weight!r}")

    @property
    def sampling(self):
        return self.base.sampling

    def field_rms(self, params, args: StageArgs):
        """Nominal RMS per loss field (the re-weighting acts on the nominal design)."""
        return self.base.field_rms(params, args)

    def __call__(self, params, args: StageArgs) -> tuple[Array, Aux]:
        res0, aux = self.base(params, args)
        k = self.draws.gap.shape[0]
        res_k = jax.vmap(lambda dr: self.base(perturbed(params, dr), args)[0])(self.draws)
        w0 = self.nominal_weight
        res = jnp.concatenate([jnp.sqrt(w0) * res0,
                               jnp.sqrt((1.0 - w0) / k) * res_k.reshape(-1)])
        return res, eqx.tree_at(lambda a: a.loss, aux, jnp.sum(res**2))
