"""The curriculum: stages along the paper's sine path, and the plain Python design loop.

The paper (Yang, Fu & Heidrich 2024) raises the difficulty of the design task step by step:
stage ``i`` of ``N`` targets

    t_i = t_a + (t_b − t_a) · sin(i / (2N) · π),   i = 0 … N,

for both the FoV (degrees, full diagonal) and the F-number, so the first stages move fast
and the last ones slowly, and then a final fine-tuning stage works at the full spec. With
``N = 3`` (four stages) from 47.5°/F2.8 to 80.8°/F2.0 the F-numbers are the paper's
2.8 → 2.4 → 2.1 → 2.0; the FoVs are 47.5 → 64.2 → 76.3 → 80.8 (the paper lists 62.8° and
74.1° in between: its code interpolates the image height and divides by the lens's evolving
focal length, which no fixed formula reproduces).

The design loop (:func:`run`) is a Python loop over stages and steps; every step is one
jitted, seed-vmapped solver update. The host reads the losses only every ``log_every`` steps
(no sync per step). A non-finite loss stops the run with a ``FloatingPointError`` that names
the stage, the step and the seed.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from ..optics import checks
from .losses import Objective, StageArgs
from .mask import field_weights
from .solvers import (
    LBFGSB,
    Adam,
    DampedLeastSquares,
    LevenbergMarquardt,
    SolverResult,
    result_names,
)
from .spec import DesignSpec, require_spec

STAGE_SOLVERS = ("adam", "lm", "lm-optx", "lbfgsb")
"""Solver names a stage may use (``multistart.design`` makes the solvers)."""
STAGE_LOSSES = ("ray", "image", "polish")
"""Objective names a stage may use (keys of the objectives ``run`` takes)."""


def sine_path(start: float, end: float, n: int) -> np.ndarray:
    """The paper's schedule t_i = start + (end − start)·sin(i/(2n)·π), i = 0 … n."""
    # n = 0 is one stage at the end; a negative or fractional n was taken as 0 or truncated.
    n = checks.number(n, "n", "sine_path", lo=0, hi=checks.MAX_SAMPLES, integer=True,
                      unit="steps")
    start = checks.number(start, "start", "sine_path")
    end = checks.number(end, "end", "sine_path")
    if n < 1:
        return np.array([float(end)])
    i = np.arange(n + 1)
    return start + (end - start) * np.sin(i / (2 * n) * np.pi)


@dataclasses.dataclass(frozen=True)
class Stage:
    """One design stage.

    Attributes:
        name: a label for logs.
        fov: full diagonal FoV (degrees).
        fnum: F-number (EPD = spec focal length / fnum).
        steps: solver steps.
        solver: ``"adam"``, ``"lm"`` or ``"lbfgsb"``.
        beta: spot reference blend (0 ideal image point, 1 centroid).
        pin: weight of the full-field image-height pin (with the centroid reference).
        mask: use the re-weighting mask.
        regularize: use the three regularizers.
        lr: learning-rate multiplier for this stage (Adam).
        loss: ``"ray"`` (RMS spot), ``"image"`` (rendered scene) or ``"polish"`` (RMS spot
            on the polish's own pupil sampling, ``DesignConfig.polish_rings``).
    """

    name: str
    fov: float
    fnum: float
    steps: int
    solver: str = "adam"
    beta: float = 0.0
    pin: float = 0.0
    mask: bool = False
    regularize: bool = True
    lr: float = 1.0
    loss: str = "ray"

    def __post_init__(self):
        # run() would otherwise trace a stage of 200° or F/0 to NaN, or skip -1 steps.
        w = f"Stage {self.name!r}"
        if not isinstance(self.name, str):  # the label of logs and messages (was taken)
            raise TypeError(f"{w}: name must be a str, got {type(self.name).__name__}")
        checks.number(self.fov, "fov", w, lo=0, hi=180, lo_open=True, hi_open=True,
                      unit="deg (full diagonal)")
        checks.number(self.fnum, "fnum", w, lo=0, lo_open=True)
        checks.number(self.steps, "steps", w, lo=0, hi=checks.MAX_STEPS, integer=True,
                      unit="solver steps")  # 10**12 was accepted: a run that never ends
        checks.number(self.beta, "beta", w, lo=0, hi=1)
        checks.number(self.pin, "pin", w, lo=0)
        checks.number(self.lr, "lr", w, lo=0, lo_open=True, unit="(multiplier)")
        if self.solver not in STAGE_SOLVERS:
            raise ValueError(f"{w}: solver must be one of {STAGE_SOLVERS}, got {self.solver!r}")
        if self.loss not in STAGE_LOSSES:
            raise ValueError(f"{w}: loss must be one of {STAGE_LOSSES}, got {self.loss!r}")
        for arg in ("mask", "regularize"):
            checks.switch(getattr(self, arg), arg, w)


def paper_stages(
    spec: DesignSpec,
    *,
    n: int = 3,
    steps: int = 300,
    final_steps: int = 600,
    polish_steps: int = 0,
    curriculum: bool = True,
    regularize: bool = True,
    mask: bool = True,
    pin: float = 1.0,
    solver: str = "adam",
    polish: str = "lm",
    reference: str = "ideal",
    final_loss: str = "ray",
) -> list[Stage]:
    """The paper's stages: ``n + 1`` curriculum stages, then fine-tuning (and a polish).

    Without ``curriculum`` the same number of steps is spent at the full spec. The
    curriculum stages use the ideal-image reference; fine-tuning and the polish use the
    centroid reference with the image-height pin (distortion relaxes). The mask, if on,
    applies to fine-tuning and the polish (the paper's final stage).

    Args:
        spec: the design spec (start and target FoV/F#).
        n: the sine path's N (``n + 1`` stages from the start to the target).
        steps: solver steps per curriculum stage.
        final_steps: fine-tuning steps at the full spec.
        polish_steps: steps of the ``polish`` solver after fine-tuning (0: none).
        curriculum: follow the sine path (else stay at the full spec).
        regularize: switch the regularizers on.
        mask: switch the re-weighting mask on (final stages).
        pin: weight of the image-height pin in the final stages.
        solver: solver of the curriculum and fine-tuning stages.
        polish: solver of the polish stage.
        final_loss: loss of the fine-tuning stage (``"ray"`` or ``"image"``).
        reference: spot reference of the curriculum stages, ``"ideal"`` (the distortion-free
            image point, as the paper's code) or ``"centroid"`` (with the image-height pin).
    """
    w = "paper_stages"
    require_spec(spec, w)
    checks.number(n, "n", w, lo=0, hi=checks.MAX_SAMPLES, integer=True, unit="curriculum steps")
    for arg, v in (("steps", steps), ("final_steps", final_steps),
                   ("polish_steps", polish_steps)):
        checks.number(v, arg, w, lo=0, integer=True, unit="solver steps")
    checks.number(pin, "pin", w, lo=0)
    checks.switch(curriculum, "curriculum", w)  # "no" is truthy: it ran the curriculum
    if curriculum:
        fovs = sine_path(spec.fov_start, spec.fov, n)
        fnums = sine_path(spec.fnum_start, spec.fnum, n)
    else:
        fovs = np.full(n + 1, spec.fov)
        fnums = np.full(n + 1, spec.fnum)
    for arg, v in (("solver", solver), ("polish", polish)):  # polish="bfgs" passed unused
        if v not in STAGE_SOLVERS:  # with polish_steps=0, as DesignConfig refuses it
            raise ValueError(f"paper_stages: {arg} must be one of {STAGE_SOLVERS}, got {v!r}")
    if reference not in ("ideal", "centroid"):
        raise ValueError(f"paper_stages: reference must be 'ideal' or 'centroid', got "
                         f"{reference!r}")
    if final_loss not in ("ray", "image"):  # was refused as the fine-tune Stage's "loss"
        raise ValueError(f"paper_stages: final_loss must be 'ray' or 'image', got "
                         f"{final_loss!r}")
    beta = 0.0 if reference == "ideal" else 1.0
    stages = [
        Stage(f"stage{i} {fov:.1f}°/F{fnum:.2f}", float(fov), float(fnum), steps, solver,
              beta=beta, pin=pin * beta, regularize=regularize)
        for i, (fov, fnum) in enumerate(zip(fovs, fnums, strict=True))
    ]
    if final_steps:
        stages.append(Stage(f"fine-tune {spec.fov:.1f}°/F{spec.fnum:.2f}", spec.fov, spec.fnum,
                            final_steps, solver, beta=1.0, pin=pin, mask=mask,
                            regularize=regularize, loss=final_loss))
    if polish_steps:
        stages.append(Stage(f"polish ({polish})", spec.fov, spec.fnum, polish_steps, polish,
                            beta=1.0, pin=pin, mask=mask, regularize=regularize))
    return stages


def stage_args(spec: DesignSpec, stage: Stage, weights, reg_weights, dtype) -> StageArgs:
    """``StageArgs`` of a stage for a batch of designs (``weights``: ``[B, K]``)."""
    b = weights.shape[0]

    def full(x):
        return jnp.full((b,), x, dtype)

    rw = jnp.asarray(reg_weights, dtype) * (1.0 if stage.regularize else 0.0)
    focal, k = spec.image_mapping()
    return StageArgs(
        tan_max=full(math.tan(math.radians(0.5 * stage.fov))),
        epd=full(spec.focal_length / stage.fnum),
        focal=full(focal),
        beta=full(stage.beta),
        pin=full(stage.pin),
        spot_scale=full(1.0),
        field_weights=jnp.asarray(weights, dtype),
        reg_weights=jnp.broadcast_to(rw, (b, 3)),
        distortion_k=full(k),
    )


def _seed_sharding(mesh):
    from jax.sharding import NamedSharding, PartitionSpec

    return NamedSharding(mesh, PartitionSpec("seeds"))


def _over_seeds(fn, mesh, n_batched: int, n_replicated: int):
    """Apply ``fn`` to every device's block of seeds with ``shard_map`` (no communication).

    ``fn(*batched, *replicated)`` is already vmapped over the seeds of its block.
    """
    if mesh is None or mesh.size == 1:
        return fn
    from jax.sharding import PartitionSpec as P

    fn = checks.inherit(fn)  # made on each call: in a checked step its body is trusted too

    specs = (P("seeds"),) * n_batched + (P(),) * n_replicated
    return jax.shard_map(fn, mesh=mesh, in_specs=specs, out_specs=P("seeds"), check_vma=False)


@checks.checked_core(eqx.filter_jit, concrete_checked=False)
def _vinit(solver, params, args, mesh=None):
    dyn, static = eqx.partition(solver, eqx.is_array)

    def local(params, args, dyn):
        return jax.vmap(eqx.combine(dyn, static).init)(params, args)

    return _over_seeds(local, mesh, 2, 1)(params, args, dyn)


@checks.checked_core(eqx.filter_jit, concrete_checked=False)
def _vstep(solver, params, state, args, lr_scale, alive, mesh=None):
    dyn, static = eqx.partition(solver, eqx.is_array)

    def local(params, state, args, alive, dyn, lr):
        step = eqx.combine(dyn, static).step
        new_p, new_s, aux = jax.vmap(step, in_axes=(0, 0, 0, None))(params, state, args, lr)
        # A design whose loss or update is not finite keeps its last finite state and is
        # marked dead (it never poisons the others, and stays frozen).
        ok = jnp.isfinite(aux.loss)
        for leaf in jax.tree.leaves(new_p):
            ok = ok & jnp.all(jnp.isfinite(leaf.reshape(leaf.shape[0], -1)), -1)
        ok = ok & alive

        def keep(new, old):
            m = ok.reshape(ok.shape + (1,) * (new.ndim - 1))
            return jnp.where(m, new, old)

        new_p = jax.tree.map(keep, new_p, params)
        new_s = jax.tree.map(lambda n, o: keep(n, o) if eqx.is_array(n) and n.ndim and
                             n.shape[0] == ok.shape[0] else n, new_s, state)
        mark = jax.vmap(lambda o, r: SolverResult.where(o, r, SolverResult.nonfinite))
        new_s = eqx.tree_at(lambda st: st.result, new_s, mark(ok, new_s.result))
        return new_p, new_s, aux, ok

    return _over_seeds(local, mesh, 4, 2)(params, state, args, alive, dyn, lr_scale)


@checks.checked_core(eqx.filter_jit, concrete_checked=False)
def _vrms(objective, params, args, mesh=None):
    dyn, static = eqx.partition(objective, eqx.is_array)

    def local(params, args, dyn):
        return jax.vmap(eqx.combine(dyn, static).field_rms)(params, args)

    return _over_seeds(local, mesh, 2, 1)(params, args, dyn)


@eqx.filter_jit
def _reweight(rms, area, mask, irls):
    w = field_weights(rms, area, mask=mask, irls=irls)
    ms = jnp.sum(w * rms**2, -1)
    return w, 1.0 / jnp.maximum(ms, 1e-12)


def _loss_inputs_checked(objective) -> bool:
    """Whether compiled steps may skip the trace's re-check of ``objective``'s wavelengths
    (``optics.checked_inputs``): only for the ray loss (``Objective``) on fixed materials,
    whose wavelengths are then checked here, concretely, against them (out of their range
    they raised from inside the first step). Other objectives keep the checks."""
    lens = getattr(objective.pmap, "template", None) if type(objective) is Objective else None
    if lens is None or getattr(objective.pmap, "materials", None) is not None \
            or checks.is_traced((lens, objective.sampling.wavelengths)):
        return False
    checks.wavelengths(lens, objective.sampling.wavelengths, "run", "the loss's wavelengths")
    checks.primary_wavelength(lens, "run", "the EFL's")
    return True


def _solver_inputs_checked(solver) -> bool:
    """``_loss_inputs_checked`` for a library solver's objective; any other solver (its
    ``step`` may trace anything) keeps the checks."""
    return (type(solver) in (Adam, LevenbergMarquardt, DampedLeastSquares, LBFGSB)
            and _loss_inputs_checked(solver.residual_fn))


@dataclasses.dataclass
class History:
    """Per-step loss (sum of squares) and spot RMS (mm) of every design, per stage."""

    stages: list[str] = dataclasses.field(default_factory=list)
    loss: list[np.ndarray] = dataclasses.field(default_factory=list)  # [steps, B] per stage
    spot_rms: list[np.ndarray] = dataclasses.field(default_factory=list)  # [steps, B]
    seconds: list[float] = dataclasses.field(default_factory=list)
    failed: dict = dataclasses.field(default_factory=dict)  # seed -> message (non-finite)
    # Per stage, every design's last ``SolverResult`` by member name ("successful", ...).
    results: list[list[str]] = dataclasses.field(default_factory=list)

    def select(self, columns: Sequence[int], relabel: dict | None = None) -> History:
        """The history of designs ``columns`` only. ``relabel`` maps the selected designs'
        seed labels to new ones; given, it also drops every failure whose label it does not
        map (the designs not selected)."""
        cols = list(columns)
        relabel = {} if relabel is None else relabel
        failed = {relabel.get(k, k): v for k, v in self.failed.items()
                  if not relabel or k in relabel}
        return History(list(self.stages), [h[:, cols] for h in self.loss],
                       [h[:, cols] for h in self.spot_rms], list(self.seconds), failed,
                       [[r[c] for c in cols] for r in self.results])

    def extend(self, later: History) -> None:
        """Append the stages of ``later`` (the same designs, run after these stages)."""
        for f in ("stages", "loss", "spot_rms", "seconds", "results"):
            getattr(self, f).extend(getattr(later, f))
        self.failed.update(later.failed)


def run(
    spec: DesignSpec,
    stages: Sequence[Stage],
    params,
    objective,
    make_solver: Callable[[str, float, object], object],
    *,
    reg_weights=(40.0, 1000.0, 40.0),
    epoch: int = 50,
    irls: bool = True,
    log_every: int = 25,
    warmup: float = 0.05,
    end_lr: float = 0.05,
    progress: bool = True,
    seeds: Sequence[int] | None = None,
    callback: Callable | None = None,
    mesh=None,
    on_nonfinite: str = "raise",
):
    """Run the stages on a batch of designs; returns ``(params, History)``.

    Args:
        spec: the design spec.
        stages: the stages to run in order.
        params: ``LensParams`` with a leading seed axis (may be sharded).
        objective: the ``Objective`` (``objective(params, args) -> (residuals, aux)``), or a
            dict of objectives by ``Stage.loss`` (``"ray"`` must be there).
        make_solver: ``(solver_name, stage_lr, objective) -> solver``.
        reg_weights: weights of the obliquity, spacing and slope regularizers.
        epoch: steps between re-weightings (mask and 1/RMS field weights).
        irls: re-weight fields by 1/RMS so the loss tracks the mean RMS.
        log_every: steps between host reads (progress, finiteness check).
        warmup, end_lr: Adam schedule per stage: linear warm-up over this fraction of the
            stage, then cosine decay to ``end_lr`` × the peak.
        progress: show a tqdm bar with stage, loss and RMS.
        seeds: seed labels for error messages.
        mesh: a one-axis ``("seeds",)`` device mesh; in Adam stages each device then updates
            its block of seeds independently (``shard_map``, no cross-device communication);
            least-squares and L-BFGS-B stages run on the mesh's first device (their dense
            linear algebra can deadlock XLA's CPU runtime when host devices run it at once).
        callback: called as ``callback(stage_index, stage, params)`` after every stage.
        on_nonfinite: ``"raise"`` stops the run when a loss (or an update) becomes
            non-finite; ``"drop"`` freezes that design at its last finite parameters, keeps
            going with the others and records it in ``History.failed`` (for multi-start
            studies, where a failed start is a result, not an error); the run still stops
            once every design has failed.

    Raises:
        FloatingPointError: a loss became non-finite (names stage, step and seed), with
            ``on_nonfinite="raise"``.
    """
    from tqdm.auto import tqdm

    require_spec(spec, "run")  # before params: a dict was an AttributeError below
    dtype = params.c.dtype
    b = params.c.shape[0]
    seeds = list(range(b)) if seeds is None else list(seeds)
    objectives = objective if isinstance(objective, dict) else {"ray": objective}
    # Checked before the first stage: a later stage's missing objective was found only after
    # the stages before it had run, and seed labels of another count mislabelled the designs.
    if isinstance(stages, Stage | str) or not isinstance(stages, Sequence) or not stages:
        # [] returned the starting parameters as the result; one Stage was not iterable.
        raise ValueError(f"run: stages must be a non-empty list of Stage objects (e.g. "
                         f"paper_stages(spec)), got {stages!r}")
    for stage in stages:
        if not isinstance(stage, Stage):
            raise TypeError(f"run: stages must be Stage objects, got {type(stage).__name__} "
                            f"{stage!r}")
        if stage.loss not in objectives:
            raise ValueError(f"run: stage {stage.name!r} needs a {stage.loss!r} objective")
    if len(seeds) != b:
        raise ValueError(f"run: seeds must label the {b} designs of params, got {len(seeds)} "
                         f"labels: {seeds!r}")
    # The schedule and switches, before the first stage (DesignConfig checks its own, but
    # run() is public): warmup=5 (5 %) ramped the rate over the whole stage and never reached
    # the peak, end_lr=5 raised it fivefold, irls="no" read as True, epoch=0 divided by 0.
    w = "run"
    checks.number(warmup, "warmup", w, lo=0, hi=1, unit="(a fraction of each stage's steps, "
                  "not a percent)")
    checks.number(end_lr, "end_lr", w, lo=0, hi=1, unit="(a fraction of the peak rate, not "
                  "a percent)")
    for arg, v in (("epoch", epoch), ("log_every", log_every)):
        checks.number(v, arg, w, lo=1, integer=True, unit="steps")
    checks.switch(irls, "irls", w)
    checks.switch(progress, "progress", w)
    if isinstance(reg_weights, str) or np.shape(reg_weights) != (3,):
        raise ValueError(f"{w}: reg_weights must be three weights >= 0 (obliquity, spacing, "
                         f"slope), got {reg_weights!r}")
    for name, v in zip(("obliquity", "spacing", "slope"), np.asarray(reg_weights), strict=True):
        checks.number(float(v), f"reg_weights ({name})", w, lo=0, unit="(weight)")
    if callback is not None and not callable(callback):
        raise TypeError(f"{w}: callback must be callable (stage_index, stage, params) or "
                        f"None, got {callback!r}")
    # Before: make_solver="adam" failed as "'str' object is not callable", objective=None
    # as an AttributeError, and mesh="cpu" passed to the first sharded stage.
    if not callable(make_solver):
        raise TypeError(f"{w}: make_solver must be callable (solver_name, stage_lr, "
                        f"objective) -> solver, e.g. multistart.make_solver_factory(config, "
                        f"spec, dtype), got {make_solver!r}")
    if "ray" not in objectives or not hasattr(objectives["ray"], "sampling"):
        raise TypeError(f"{w}: objective must be an Objective (or a dict of them by "
                        f"Stage.loss, with \"ray\"), got {objective!r}")
    if mesh is not None and not isinstance(mesh, jax.sharding.Mesh):
        raise TypeError(f"{w}: mesh must be a jax.sharding.Mesh (one axis, \"seeds\") or None, "
                        f"got {mesh!r}")
    objective = objectives["ray"]
    vrms = _vrms.inputs_checked if _loss_inputs_checked(objective) else _vrms
    area = objective.sampling.area
    total = sum(s.steps for s in stages)
    bar = tqdm(total=total, disable=not progress, dynamic_ncols=True, leave=True)
    hist = History()
    ones = jnp.broadcast_to(area, (b, area.shape[0]))
    if on_nonfinite not in ("raise", "drop"):
        raise ValueError(f"run: on_nonfinite must be 'raise' or 'drop', got {on_nonfinite!r}")
    alive = jnp.ones((b,), bool)
    dead = np.zeros(b, bool)
    for si, stage in enumerate(stages):
        t0 = time.perf_counter()
        if stage.loss not in objectives:
            raise ValueError(f"run: stage {stage.name!r} needs a {stage.loss!r} objective")
        solver = make_solver(stage.solver, stage.lr, objectives[stage.loss])
        checked = _solver_inputs_checked(solver)
        vinit, vstep = (f.inputs_checked if checked else f for f in (_vinit, _vstep))
        # Least-squares and quasi-Newton stages run on one device: their dense linear algebra
        # can deadlock XLA's CPU runtime when several host devices run it at once.
        smesh = mesh if stage.solver == "adam" else None
        if mesh is not None:
            target = mesh.devices.flat[0] if smesh is None else None
            if target is not None:
                    params, alive = jax.device_put((params, alive), target)
            else:
                params, alive = jax.device_put((params, alive), _seed_sharding(mesh))
        args = stage_args(spec, stage, ones, reg_weights, dtype)
        sched = optax.warmup_cosine_decay_schedule(
            0.0, 1.0, max(1, int(warmup * stage.steps)), max(2, stage.steps), end_lr)
        state = None
        losses, rmss, oks = [], [], []
        done = 0
        for step in range(stage.steps):
            if step % epoch == 0:
                rms = vrms(objective, params, args, smesh)
                w, scale = _reweight(rms, area, stage.mask, irls)
                args = eqx.tree_at(lambda a: (a.field_weights, a.spot_scale), args, (w, scale))
                if state is None or stage.solver not in ("adam", "lm"):
                    state = vinit(solver, params, args, smesh)
            lr = jnp.asarray(float(sched(step)), dtype)
            params, state, aux, alive = vstep(solver, params, state, args, lr, alive, smesh)
            losses.append(aux.loss)
            rmss.append(jnp.sqrt(aux.spot))
            oks.append(alive)
            if (step + 1) % log_every == 0 or step + 1 == stage.steps:
                lo = np.asarray(jnp.stack(losses[done:]))
                ro = np.asarray(jnp.stack(rmss[done:]))
                ok = np.asarray(jnp.stack(oks[done:]))
                newly = ~ok & ~dead[None]
                if newly.any():
                    for j in np.flatnonzero(newly.any(0)):
                        k = int(np.argmax(newly[:, j]))
                        msg = (f"non-finite loss or update in stage {si} ({stage.name}) at "
                               f"step {done + k} for seed {seeds[j]}")
                        if on_nonfinite == "raise":
                            bar.close()
                            raise FloatingPointError(msg)
                        hist.failed[seeds[j]] = msg
                        bar.write(msg + "; that design is frozen and counted as failed")
                    dead |= newly.any(0)
                    if dead.all():
                        bar.close()
                        raise FloatingPointError(
                            "every design went non-finite: " + "; ".join(hist.failed.values()))
                bar.set_description(f"{stage.name}")
                live = ~dead
                if live.any():
                    bar.set_postfix(loss=f"{np.nanmin(lo[-1][live]):.3g}",
                                    rms_um=f"{1e3 * np.nanmin(ro[-1][live]):.2f}")
                bar.update(len(lo))
                done = step + 1
        hist.stages.append(stage.name)
        hist.loss.append(np.asarray(jnp.stack(losses)) if losses else np.zeros((0, b)))
        hist.spot_rms.append(np.asarray(jnp.stack(rmss)) if rmss else np.zeros((0, b)))
        hist.seconds.append(time.perf_counter() - t0)
        hist.results.append(["successful"] * b if state is None else result_names(state.result))
        if callback is not None:
            callback(si, stage, params)
    bar.close()
    return params, hist
