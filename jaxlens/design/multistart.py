"""Multi-start design: many seeds designed together (vmapped), sharded over devices.

The random starts are stacked on a leading seed axis and placed on a one-axis device mesh
(``jax.sharding``), so every jitted, vmapped solver update runs the seeds of each device in
parallel (on a CPU, ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` gives N devices,
one per core). The seed count is padded to a multiple of the device count with copies of the
last seed, and the copies are dropped afterwards. On a cluster, ``jax.distributed.initialize``
before calling :func:`design` makes ``jax.devices()`` span every host, and the same mesh
shards the seeds across them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ..optics import catalog, checks
from .curriculum import STAGE_SOLVERS, History, Stage, paper_stages, run, stage_args
from .init import MAX_SEED, check_seeds, gap_bounds, parameterization, random_starts
from .losses import MAX_RINGS, ImageObjective, Objective, RayLoss, reverse_mode
from .materials import (
    DEFAULT_CATALOGS,
    CatalogRegion,
    TableMaterials,
    check_mode,
    initial_logits,
    search,
    snap,
)
from .params import LensParams
from .robust import RobustObjective, draw_perturbations
from .solvers import LBFGSB, Adam, DampedLeastSquares, LevenbergMarquardt
from .spec import DesignSpec, require_spec

MAX_ROBUST_DRAWS = 64
"""Most perturbation draws of tolerance-aware design (``tolerance_trials``, the classical
CLI's ``--tolerance-aware K``): each is one more ray loss per step (the README's run uses 4),
and 10**6 asked XLA for 9 TB."""

MAX_STEP_SCALE = 50.0
"""Largest scale of the default recipe's step counts (the classical CLI's ``--steps``): 50 ×
the 1200 fine-tuning steps are 60 000, within ``checks.MAX_STEPS``; ``--steps 1e12`` asked for
10**15 steps."""


@dataclasses.dataclass(frozen=True)
class DesignConfig:
    """How to design: sampling, schedule, learning rates, switches.

    Attributes:
        n_fields: radial loss fields K (0 … full field).
        rings: hexapolar rings of the (half) pupil sampling.
        curriculum_n: the sine path's N (N + 1 curriculum stages).
        steps: solver steps per curriculum stage.
        final_steps: fine-tuning steps at the full spec.
        polish_steps: polish steps (Levenberg–Marquardt by default).
        curriculum, regularize, mask: the paper's three switches.
        solver: solver of the curriculum and fine-tuning (``adam``, ``lm``, ``lbfgsb``).
        polish: solver of the polish stage.
        lr_c, lr_a, lr_d, lr_k: Adam learning rates of scaled curvatures, scaled aspheric
            coefficients, gaps (mm) and conics.
        reg_weights: obliquity, spacing and slope regularizer weights (the spot term is
            normalised to about 1 at every epoch start).
        pin: weight of the image-height pin in the final stages.
        efl_weight: weight of the paraxial EFL residual when ``spec.efl`` is set
            (``losses.Objective``).
        reference: spot reference of the curriculum stages (``"ideal"`` or ``"centroid"``).
        epoch: steps between re-weightings.
        irls: re-weight fields by 1/RMS.
        log_every: steps between host reads.
        float64: design in float64 (default float32).
        image_pixels, image_spp: sensor pixels per side and rays per pixel of the
            image-based loss.
        materials: material selection (``jaxlens.design.materials``): ``"fixed"`` keeps the
            spec's materials; ``"continuous"`` frees each element's (nd, Vd) inside the hull
            of ``material_catalogs`` until the polish, then snaps it to the nearest catalog
            material, which the polish re-optimises around; ``"search"`` does the same but
            picks each catalog material by the design loss (a discrete search over the
            catalog, geometry held) instead of the nearest on the glass map.
        material_catalogs: catalogs the materials are chosen from.
        lr_m: Adam learning rate of the material logits.
        tolerance_trials: 0, or K > 0 for tolerance-aware design (``jaxlens.design.robust``):
            the ray loss averaged over K fixed radius and gap errors drawn from
            ``analysis.tolerance.Tolerances()`` (±0.5 % radius, ±0.02 mm gaps), with the
            nominal design weighted ``tolerance_nominal_weight``.
        tolerance_nominal_weight: w₀ of the tolerance-aware loss.
        polish_rings: hexapolar rings of the polish's pupil sampling (0: ``rings``). A
            finer pupil in the polish keeps the aspheres from fitting the sampled rays
            only, between which rays can then fail or spread.
        population: random starts per design. All of them run the curriculum and
            fine-tuning; only the best of each design's starts (lowest loss-field RMS)
            continues to material snapping and the polish.
    """

    n_fields: int = 9
    rings: int = 4
    curriculum_n: int = 3
    steps: int = 450
    final_steps: int = 1200
    polish_steps: int = 80
    curriculum: bool = True
    regularize: bool = True
    mask: bool = True
    solver: str = "adam"
    polish: str = "lm"
    lr_c: float = 5e-3
    lr_a: float = 1e-3
    lr_d: float = 2e-3
    lr_k: float = 0.0
    reg_weights: tuple[float, float, float] = (40.0, 1000.0, 40.0)
    pin: float = 1.0
    efl_weight: float = 1.0
    reference: str = "ideal"
    epoch: int = 50
    irls: bool = True
    log_every: int = 25
    float64: bool = False
    image_pixels: int = 64
    image_spp: int = 4
    materials: str = "fixed"
    material_catalogs: tuple[str, ...] = DEFAULT_CATALOGS
    lr_m: float = 1e-2
    tolerance_trials: int = 0
    tolerance_nominal_weight: float = 0.5
    population: int = 1
    polish_rings: int = 0

    def __post_init__(self):
        # A count of 0 fields or rings fails deep inside the jitted loss, a negative step
        # count silently skips a stage, and "no" for a switch would read as True.
        w = "DesignConfig"
        # Sizes of the arrays a step holds are bounded above (before: tolerance_trials=10**6
        # asked XLA for 9 TB after the spec had been built), and so are step counts (10**12
        # steps would never end).
        for arg, lo, hi in (("n_fields", 1, checks.MAX_MAP_GRID), ("rings", 1, MAX_RINGS),
                            ("curriculum_n", 0, checks.MAX_SAMPLES),
                            ("steps", 0, checks.MAX_STEPS), ("final_steps", 0, checks.MAX_STEPS),
                            ("polish_steps", 0, checks.MAX_STEPS),
                            ("epoch", 1, None), ("log_every", 1, None),
                            ("image_pixels", 1, checks.MAX_IMAGE_SIDE),
                            ("image_spp", 1, checks.MAX_SAMPLES),
                            ("tolerance_trials", 0, MAX_ROBUST_DRAWS),
                            ("polish_rings", 0, MAX_RINGS)):
            checks.number(getattr(self, arg), arg, w, lo=lo, hi=hi, integer=True)
        if not (self.steps or self.final_steps or self.polish_steps):
            # design() then returned the random starts as designs, marked "successful".
            raise ValueError(f"{w}: steps, final_steps and polish_steps are all 0: no solver "
                             f"step would run (give at least one step, e.g. final_steps=1)")
        p = self.population
        if isinstance(p, bool) or not isinstance(p, int | np.integer) or p < 1:
            raise ValueError(f"{w}: population must be at least 1 start per design (a whole "
                             f"number in [1, inf)), got {p!r}")
        for arg in ("lr_c", "lr_a", "lr_d", "lr_k", "lr_m", "pin", "efl_weight"):
            checks.number(getattr(self, arg), arg, w, lo=0)
        # w₀ > 1 gave the perturbed lenses a negative weight (a loss that rewards tolerance
        # sensitivity) or a NaN; 0 drops the nominal design (RobustObjective's range).
        checks.number(self.tolerance_nominal_weight, "tolerance_nominal_weight", w, lo=0,
                      hi=1, lo_open=True, unit="(share of the nominal loss)")
        for arg in ("curriculum", "regularize", "mask", "irls", "float64"):
            checks.switch(getattr(self, arg), arg, w)
        # Checked here, not where they are first used: a negative or NaN regularizer weight
        # rewarded what it should penalise (or made the first loss NaN after the set-up),
        # and a wrong solver, polish or reference name surfaced only when the stages or the
        # polish were built.
        rw = self.reg_weights
        if (isinstance(rw, str) or not isinstance(rw, (tuple, list)) or len(rw) != 3):
            raise ValueError(f"{w}: reg_weights must be three weights >= 0 (obliquity, "
                             f"spacing, slope), got {rw!r}")
        for name, v in zip(("obliquity", "spacing", "slope"), rw, strict=True):
            checks.number(v, f"reg_weights ({name})", w, lo=0, unit="(weight)")
        for arg in ("solver", "polish"):
            if getattr(self, arg) not in STAGE_SOLVERS:
                raise ValueError(f"{w}: {arg} must be one of {STAGE_SOLVERS}, got "
                                 f"{getattr(self, arg)!r}")
        if self.reference not in ("ideal", "centroid"):
            raise ValueError(f"{w}: reference must be 'ideal' or 'centroid', got "
                             f"{self.reference!r}")
        check_mode(self.materials, f"{w}: materials")
        cats = self.material_catalogs
        if (isinstance(cats, str) or not isinstance(cats, (tuple, list)) or not cats
                or not all(isinstance(c, str) and c.strip() for c in cats)):
            raise ValueError(f"{w}: material_catalogs must be a non-empty tuple of catalog "
                             f"names (e.g. ('SCHOTT', 'CDGM')), got {cats!r}")
        try:  # 'SCHOT' was found only when the design reached its materials
            catalog.catalog_names(catalogs=list(cats))
        except ValueError as e:
            raise ValueError(f"{w}: material_catalogs {list(cats)!r} names a catalog that is "
                             f"not known: {e} (jaxlens.catalog.register_catalog adds "
                             f"one)") from None

    def scaled(self, factor: float) -> DesignConfig:
        """The same recipe with every step count scaled by ``factor`` (at least 1 step)."""
        # Before: inf raised OverflowError from round(), NaN a ValueError naming nothing.
        checks.number(factor, "factor", "DesignConfig.scaled", lo=0, lo_open=True,
                      unit="(scale of every stage's steps)")
        def sc(n):
            return max(1, round(n * factor)) if n else 0

        return dataclasses.replace(self, steps=sc(self.steps), final_steps=sc(self.final_steps),
                                   polish_steps=sc(self.polish_steps))

    def stages(self, spec: DesignSpec) -> list[Stage]:
        return paper_stages(
            spec, n=self.curriculum_n, steps=self.steps, final_steps=self.final_steps,
            polish_steps=self.polish_steps, curriculum=self.curriculum,
            regularize=self.regularize, mask=self.mask, pin=self.pin, solver=self.solver,
            polish=self.polish, reference=self.reference)


@dataclasses.dataclass
class DesignResult:
    """Designed parameters (leading seed axis), their lenses, and the run history.

    ``status[i]`` is seed ``i``'s :class:`~jaxlens.design.solvers.SolverResult` member name
    after its last stage: ``"nonfinite"`` marks a failed design (frozen at its last finite
    parameters, with the message in ``history.failed``); ``"rejected"`` or
    ``"damping_limit"`` after the least-squares polish mean its last step found no lower
    loss (converged, or stuck); ``"solver_error"`` passes on an optimistix/jaxopt failure.

    With material selection, ``materials`` holds each design's chosen catalog names and
    ``continuous_materials`` the ``[B, E, 2]`` (nd, Vd) points they were snapped from.
    ``starts`` holds each design's chosen random start (``population_starts``).
    """

    spec: DesignSpec
    config: DesignConfig
    seeds: list[int]
    params: LensParams
    pmap: object
    history: History
    materials: list[tuple[str, ...]] | None = None
    continuous_materials: np.ndarray | None = None
    starts: list[int] | None = None

    def material_names(self, i: int) -> tuple[str, ...]:
        """The element materials of the i-th design (catalog names)."""
        return self.spec.materials if self.materials is None else self.materials[i]

    @property
    def status(self) -> list[str]:
        """Each seed's last solver result (see the class docstring)."""
        last = self.history.results[-1] if self.history.results else ["successful"] * len(
            self.seeds)
        # A design that failed in an earlier run of stages stays failed after the polish.
        return ["nonfinite" if s in self.history.failed else r
                for s, r in zip(self.seeds, last[: len(self.seeds)], strict=True)]

    @property
    def failed(self) -> list[bool]:
        """Seeds whose design went non-finite."""
        return [s == "nonfinite" for s in self.status]

    def lens(self, i: int, dtype=jnp.float64):
        """The i-th design as a ``Lens`` (cast to ``dtype``), with catalog materials."""
        p = jax.tree.map(lambda x: jnp.asarray(np.asarray(x)[i]), self.params)
        lens = self.pmap.to_lens(p)
        if self.materials is not None:
            import equinox as eqx

            new = iter(catalog.get_material(n, self.config.material_catalogs)
                       for n in self.materials[i])
            mats = tuple(next(new) if j in self.pmap.glass else m
                         for j, m in enumerate(lens.materials))
            lens = eqx.tree_at(lambda x: x.materials, lens, mats)
        return lens.astype(dtype)


def seed_mesh(devices=None) -> Mesh:
    """A one-axis mesh ``("seeds",)`` over ``devices`` (default: every device)."""
    return Mesh(np.array(jax.devices() if devices is None else list(devices)), ("seeds",))


def shard_seeds(tree, mesh: Mesh | None = None):
    """Place a pytree with a leading seed axis on the mesh (seed axis split over devices)."""
    mesh = seed_mesh() if mesh is None else mesh
    sharding = NamedSharding(mesh, PartitionSpec("seeds"))
    return jax.tree.map(lambda x: jax.device_put(x, sharding), tree)


def _image_objective(objective: Objective, spec: DesignSpec, config: DesignConfig):
    from ..io.images import scene
    from ..optics.lens import Sensor

    n = config.image_pixels
    img = scene("astronaut", (n, n))  # linear light
    dtype = objective.gap_bounds.dtype
    sensor = Sensor(resolution=(n, n), pixel_size=jnp.asarray(spec.sensor_size[0] / n, dtype))
    return ImageObjective(objective, jnp.asarray(img, dtype), sensor, spp=config.image_spp)


def make_solver_factory(config: DesignConfig, spec: DesignSpec, dtype, materials=None):
    """``(name, stage_lr, objective) -> solver`` for the curriculum loop.

    ``materials``: None when the parameters carry no materials (``LensParams.m`` is None),
    True when they are free (continuous selection), False when they are held.
    """
    require_spec(spec, "make_solver_factory")
    m = spec.asphere_terms
    lower_d = jnp.asarray(gap_bounds(spec)[:-1], dtype)  # element / air / stop minimums
    free = LensParams(c=True, a=True, k=config.lr_k > 0, d=True, m=materials)
    lr_m = None if materials is None else jnp.asarray(config.lr_m, dtype)
    bound_m = None if materials is None else jnp.asarray(jnp.inf, dtype)
    s = spec.num_surfaces - 1

    def make(name: str, lr: float, objective):
        if name == "adam":
            lrs = LensParams(
                c=jnp.asarray(config.lr_c * lr, dtype), a=jnp.full((m,), config.lr_a * lr, dtype),
                k=jnp.asarray(config.lr_k * lr, dtype), d=jnp.asarray(config.lr_d * lr, dtype),
                m=None if lr_m is None else lr_m * lr)
            # Adam and L-BFGS-B take only grad: the trace's hand-written reverse rule.
            return Adam(reverse_mode(objective), lrs, free=free)
        if name == "lm":
            return DampedLeastSquares(objective, free=free)
        if name == "lm-optx":
            return LevenbergMarquardt(objective, free=free)
        if name == "lbfgsb":
            inf = jnp.asarray(jnp.inf, dtype)
            lower = LensParams(c=jnp.full((s,), -inf), a=jnp.full((s, m), -inf),
                               k=jnp.full((s,), -inf), d=lower_d,
                               m=None if bound_m is None else -bound_m)
            upper = LensParams(c=jnp.full((s,), inf), a=jnp.full((s, m), inf),
                               k=jnp.full((s,), inf),
                               d=jnp.full(lower_d.shape, spec.total_track, dtype), m=bound_m)
            return LBFGSB(reverse_mode(objective), lower, upper, free=free)
        raise ValueError(f"design: unknown solver {name!r}; use adam, lm, lm-optx or lbfgsb")

    return make


def design(
    spec: DesignSpec,
    seeds: Sequence[int],
    config: DesignConfig = DesignConfig(),
    *,
    progress: bool = True,
    shard: bool = True,
    devices=None,
    callback=None,
    image_loss: bool = False,
    on_nonfinite: str = "raise",
) -> DesignResult:
    """Design ``len(seeds)`` lenses from random starts, all at once.

    Args:
        spec: the design spec (validated on construction).
        seeds: integer seeds of the random starts.
        config: the recipe.
        progress: show a progress bar.
        shard: shard the seeds over the devices.
        devices: the devices to shard over (default ``jax.devices()``).
        callback: passed to :func:`jaxlens.design.curriculum.run`.
        on_nonfinite: ``"raise"`` or ``"drop"`` (see :func:`jaxlens.design.curriculum.run`);
            dropped seeds are listed in ``result.history.failed``.
        image_loss: fine-tune with the image-based loss (``ImageObjective``: a scikit-image
            test scene rendered at ``config.image_pixels`` per side) instead of the ray loss.

    Returns:
        A :class:`DesignResult`.
    """
    # A dict for the spec or the config failed on an attribute deep in the set-up; a
    # callback of 5 only when the first stage reported, progress="no" showed the bar.
    for arg, v, kind in (("spec", spec, DesignSpec), ("config", config, DesignConfig)):
        if not isinstance(v, kind):
            raise TypeError(f"design: {arg} must be a jaxlens.design.{kind.__name__}, got "
                            f"{type(v).__name__} {v!r}"[:200])
    if callback is not None and not callable(callback):
        raise TypeError(f"design: callback must be None or a function, got "
                        f"{type(callback).__name__} {callback!r}")
    checks.switch(progress, "progress", "design")
    # [int(s) for s in seeds] read "12" as seeds 1 and 2 and a seed of 1.5 as 1.
    seeds = check_seeds(seeds, "design", distinct=True)
    # bool("no") is True: shard="no" sharded, image_loss=5 rendered (after the set-up).
    checks.switch(shard, "shard", "design")
    checks.switch(image_loss, "image_loss", "design")
    if config.population < 1:
        raise ValueError(f"design: population must be at least 1 start per design, got "
                         f"{config.population}")
    if max(seeds) * config.population + config.population - 1 > MAX_SEED:
        raise ValueError(f"design: seed {max(seeds)} with population {config.population} draws "
                         f"starts beyond the largest seed {MAX_SEED} (s·P … s·P + P − 1)")
    if on_nonfinite not in ("raise", "drop"):  # run() would refuse it after the set-up
        raise ValueError(f"design: on_nonfinite must be 'raise' or 'drop', got "
                         f"{on_nonfinite!r}")
    if isinstance(devices, str) or (devices is not None and not hasattr(devices, "__iter__")):
        raise ValueError(f"design: devices must be a non-empty list of JAX devices or None "
                         f"(all), got {devices!r}")
    devices = None if devices is None else list(devices)
    if devices == []:  # a shard over no device divided by zero
        raise ValueError("design: devices must be a non-empty list of JAX devices or None "
                         "(all), got []")
    dtype = jnp.float64 if config.float64 else jnp.float32
    if config.float64 and not jax.config.jax_enable_x64:
        raise ValueError("design: float64 needs jax_enable_x64")
    mode = check_mode(config.materials)
    pmap = parameterization(spec, dtype)
    sampling = RayLoss.make(config.n_fields, config.rings, spec.wavelengths, spec.sensor_size,
                            dtype)
    bounds = jnp.asarray(gap_bounds(spec), dtype)
    devices = list(jax.devices() if devices is None else devices)
    starts = population_starts(seeds, config.population)
    n_dev = min(len(devices), len(starts)) if shard else 1
    mesh = seed_mesh(devices[:n_dev]) if n_dev > 1 else None
    labels = _padded(starts, n_dev)
    params = random_starts(spec, labels, dtype)
    robust_draws = None
    if config.tolerance_trials:
        from ..analysis.tolerance import Tolerances

        tol = Tolerances()
        robust_draws = draw_perturbations(
            params.c.shape[-1], params.d.shape[-1], config.tolerance_trials,
            radius_rel=tol.radius_rel, thickness=tol.thickness, dtype=dtype)
    stages = config.stages(spec)
    if image_loss:
        stages = [dataclasses.replace(s, loss="image") if s.name.startswith("fine-tune") else s
                  for s in stages]

    if config.polish_rings:
        stages = [dataclasses.replace(s, loss="polish") if s.name.startswith("polish") else s
                  for s in stages]
        polish_sampling = RayLoss.make(config.n_fields, config.polish_rings, spec.wavelengths,
                                       spec.sensor_size, dtype)

    def objectives(pm):
        def robust(objective):
            if not config.tolerance_trials:
                return objective
            return RobustObjective(objective, robust_draws, config.tolerance_nominal_weight)

        def ray(sampling):
            return Objective(pm, sampling, bounds, efl=spec.efl, efl_weight=config.efl_weight)

        plain = ray(sampling)
        out = {"ray": robust(plain)}
        if image_loss:
            out["image"] = _image_objective(plain, spec, config)
        if config.polish_rings:
            out["polish"] = robust(ray(polish_sampling))
        return out

    def design_stages(stages, params, pm, materials, labels, first=0, mesh=mesh):
        cb = None if callback is None else (lambda i, st, p: callback(first + i, st, p))
        return run(spec, stages, params if mesh is None else shard_seeds(params, mesh),
                   objectives(pm), make_solver_factory(config, spec, dtype, materials),
                   reg_weights=config.reg_weights, epoch=config.epoch, irls=config.irls,
                   log_every=config.log_every, progress=progress, seeds=labels, callback=cb,
                   mesh=mesh, on_nonfinite=on_nonfinite)

    # Every start runs up to the polish; then the best start of each design continues (with
    # material selection, after its materials are snapped or searched).
    split = len(stages) - 1 if config.polish_steps and len(stages) > 1 else len(stages)
    free_materials = None if mode == "fixed" else True
    pm_first = pmap
    if free_materials:
        params, pm_first = _free_materials(spec, config, params, pmap)
    params, hist = design_stages(stages[:split], params, pm_first, free_materials, labels)
    keep = best_starts(hist, labels, len(seeds), config.population)
    params = jax.tree.map(lambda x: np.asarray(x)[keep], params)
    hist = hist.select(keep, relabel=dict(zip([labels[k] for k in keep], seeds, strict=True)))
    chosen = points = None
    if mode != "fixed":
        params, pmap, chosen, points = _catalog_materials(
            spec, config, mode, stages, params, pmap, objectives)
    if split < len(stages):
        # Least-squares and L-BFGS-B polishes run on one device (``run``): no mesh, so no
        # padded copies to polish.
        sharded = mesh is not None and all(s.solver == "adam" for s in stages[split:])
        padded = _padded(seeds, n_dev) if sharded else list(seeds)
        params = jax.tree.map(lambda x: np.concatenate([x, np.repeat(x[-1:], len(padded) - len(
            seeds), 0)]), params)
        held = None if free_materials is None else False  # catalog materials now held
        params, h2 = design_stages(stages[split:], params, pmap, held, padded, first=split,
                                   mesh=mesh if sharded else None)
        hist.extend(h2.select(list(range(len(seeds)))))
        params = jax.tree.map(lambda x: np.asarray(x)[: len(seeds)], params)
    starts_used = [labels[k] for k in keep]
    return DesignResult(spec, config, seeds, params, pmap, hist, chosen, points, starts_used)


def population_starts(seeds: Sequence[int], population: int) -> list[int]:
    """The random-start seeds of designs ``seeds`` with ``population`` starts each.

    Design ``s`` draws starts ``s·P … s·P + P − 1``: disjoint across designs, and with
    ``P = 1`` each design's start is its own seed.
    """
    checks.number(population, "population", "population_starts", lo=1, integer=True,
                  unit="starts per design")  # 0 gave no start, 2.5 a float range error
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Sequence | np.ndarray):
        raise ValueError(f"population_starts: seeds must be a sequence of whole numbers >= 0 "
                         f"(one per design), got {type(seeds).__name__} {seeds!r}")
    for s in seeds:  # -1 gave starts -2, -1 (numpy refuses a negative seed later)
        checks.number(s, "seeds", "population_starts", lo=0, hi=MAX_SEED, integer=True)
    return [s * population + j for s in seeds for j in range(population)]


def best_starts(hist: History, labels: Sequence[int], n_designs: int, population: int):
    """Index of each design's best start: lowest loss-field RMS after the last stage run,
    failed starts last (a design whose starts all failed keeps its first, still failed)."""
    rms = np.asarray(hist.spot_rms[-1][-1], float) if hist.spot_rms and len(
        hist.spot_rms[-1]) else np.zeros(len(labels))
    bad = np.array([labels[i] in hist.failed or not np.isfinite(rms[i])
                    for i in range(len(labels))])
    score = np.where(bad, np.inf, rms)
    keep = []
    for d in range(n_designs):
        block = np.arange(d * population, (d + 1) * population)
        keep.append(int(block[np.argmin(score[block])]) if not bad[block].all()
                    else int(block[0]))
    return keep


def _padded(labels: list[int], n_dev: int) -> list[int]:
    """``labels`` padded to a multiple of the device count with copies of the last one."""
    return labels + [labels[-1]] * (-len(labels) % n_dev)


def _free_materials(spec, config, params, pmap):
    """Parameters and parameterisation with each element's (nd, Vd) free inside the hull."""
    import equinox as eqx

    dtype = params.c.dtype
    b = params.c.shape[0]
    hull = CatalogRegion.of(config.material_catalogs).hull()
    m0 = jnp.asarray(initial_logits(hull, spec.materials), dtype)
    params = LensParams(params.c, params.a, params.k, params.d,
                        jnp.broadcast_to(m0, (b,) + m0.shape))
    pm = eqx.tree_at(lambda p: p.materials, pmap, hull, is_leaf=lambda x: x is None)
    return params, pm


def _catalog_materials(spec, config, mode, stages, params, pmap, objectives):
    """Each design's free materials snapped to the catalog (or searched on the design loss).

    Returns the parameters with the catalog materials' index tables, the parameterisation
    that reads them, the chosen names and the continuous (nd, Vd) points.
    """
    import equinox as eqx

    dtype = params.c.dtype
    b = params.c.shape[0]
    region = CatalogRegion.of(config.material_catalogs)
    hull = region.hull()
    points, names = snap(region, hull, np.asarray(params.m))
    pm_t = eqx.tree_at(lambda p: p.materials, pmap, TableMaterials(spec.wavelengths),
                       is_leaf=lambda x: x is None)

    def with_tables(p, names):
        t = np.stack([region.table(n, spec.wavelengths) for n in names])
        return LensParams(*(jnp.asarray(np.asarray(x)) for x in (p.c, p.a, p.k, p.d)),
                          jnp.asarray(t, dtype))

    params = with_tables(params, names)
    if mode == "search":
        objective = objectives(pm_t)["ray"]
        area = objective.sampling.area
        weights = jnp.broadcast_to(area, (b, area.shape[0]))
        args = stage_args(spec, stages[-1], weights, config.reg_weights, dtype)
        names = search(region, objective, params, args, names, spec.wavelengths)
        params = with_tables(params, names)
    params = jax.tree.map(np.asarray, params)
    return params, pm_t, names, points
