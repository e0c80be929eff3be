"""Round 38d: gradients against central differences, in what rounds 36e and 37e left out.

Sections (pick with arguments; default all):

    render  ``jaxlens.render`` (ray method, checkpointed and not; PSF method) on the Cooke
            triplet. Well-posed check: the PRNG key and the sampling footprints are fixed
            (``RayRender(footprints=...)``, the documented way to hold them), the scene is
            affine in x and y (bilinear interpolation of an affine image is exact, so the
            only kink left is the scene's edge clamp), and the functional is linear in the
            image. What remains piecewise is each ray's validity (the stop edge, the disc
            of directions): a certificate renders a uniform scene with
            ``relative_illumination=True`` at x ± h, which is Σ valid·πr² per pixel, a
            step function of the lens: equal to the image at x (bit for bit) means no ray
            changed validity within the step, so the function is smooth on [x − h, x + h]
            and central differences must agree with ``grad`` to O(h²). Also ``jvp`` against
            ``grad`` (always well-posed), checkpointed against non-checkpointed ``grad``,
            and the default render (footprints recomputed per call, held without gradient:
            a documented disagreement, shown for its size). The PSF method without and
            with relative illumination (with: the map's vignetted pupil area is found by
            bisection and held without gradient, ``radiometry.star_region``; its differences
            are step-like, spread ~1, so that row is DOC).
    glass   dispersion-formula leaves round 37e did not cover (Herzberger, Sellmeier 2,
            Conrady, Handbook 1 and 2, Sellmeier 4, the three Laurent/Extended power sets, a
            five-term Sellmeier, a catalog glass with a stated range (extrapolated_index),
            the design's HullMaterials logits): traced image points (chief and marginal rays
            at two wavelengths) and EFL.
    regs    the classical design objective with its regularizers on (final stage, reg weights
            (40, 1000, 40)) at a random start and at a finished design
            (experiments/classical/designs/seed_0.zmx): total loss and each penalty, per leaf
            group (c, a, k, d); with ``clear_radii`` as the code has it (held without gradient,
            documented) and with the radii frozen at x (then FD and grad are the same function).
    edof    the EDoF loss (ω1·L_sim + ω2·L_raw of the simulated patches) through
            ``patch_psfs`` with respect to the hybrid surface's odd coefficients (and c, k,
            focus) of ``HybridParams``.
    image   ``ImageObjective`` (render after the distortion pre-warp, plus the alignment
            penalty): ``grad`` against ``jvp``, and against central differences with the
            pre-warp and the footprints frozen at x (both held without gradient by design);
            ``alignment_penalty`` alone against differences.

    PYTHONPATH=. python tools/grad38d_probe.py [section ...] [--only substring]

One line per (case, parameter) as in ``tools/grad37e_probe.py`` (``compare``), then a
``group`` line per leaf group with the largest relative error. Status ok / WRONG? / WRONG /
NAN / ERROR; ``DOC`` marks a row whose disagreement is a documented held quantity.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from grad36e_probe import _leaf, _set  # noqa: E402
from grad37e_probe import FUNCS, _hit, compare, run_sections, testbed  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.imaging import render as R  # noqa: E402
from jaxlens.imaging.psf import RGB_WAVELENGTHS  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def grouped(rows, tag=""):
    """The rows, then one ``group`` line per leaf group (name before ``[``): the largest
    relative error of the group."""
    out = list(rows)
    groups: dict = {}
    for r in rows:
        m = re.match(r"(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s.*rel=(\S+)", r)
        if not m:
            continue
        key = (m.group(2), m.group(3), m.group(4).split("[")[0])
        groups.setdefault(key, []).append((float(m.group(5)), m.group(1)))
    for (sec, case, grp), v in groups.items():
        worst = max(x for x, _ in v)
        bad = [s for _, s in v if s != "ok"]
        status = "ok" if not bad else (tag or bad[0])
        out.append(f"{status:6s} group {sec} {case} {grp:8s} n={len(v)} max_rel={worst:.1e}")
    return out


# ---------------------------------------------------------------------------------- render
def render_lens():
    return dataclasses.replace(zoo.cooke_triplet(), sensor=jl.Sensor((6, 6), 2.0))


def affine_scene(n=6):
    yy, xx = np.mgrid[0:n, 0:n] / (n - 1.0)
    return jnp.asarray(np.stack([0.2 + xx, 0.5 + 0.3 * yy, 0.1 + xx + yy], -1))


RENDER_PARAMS = [
    ("c0", lambda P: P[0].surfaces[0].c, None, 1e-6),
    ("c4", lambda P: P[0].surfaces[4].c, None, 1e-6),
    ("t1", lambda P: P[0].thickness, 1, 1e-4),
    ("t5", lambda P: P[0].thickness, 5, 1e-3),
]


def render_fns(lens, spp=4):
    """name -> (fn, documented?): linear functionals of the image with fixed weights."""
    scene = affine_scene()
    key = jax.random.PRNGKey(1)
    wmap = jnp.asarray(np.random.default_rng(0).uniform(0.5, 1.5, (6, 6, 3)))
    fp = R.footprints(lens, wavelengths=RGB_WAVELENGTHS)
    fixed = R.RayRender(footprints=fp)

    def ray(ckpt, method=fixed, ri=True):
        return lambda L, e: jnp.sum(wmap * jl.render(
            L, scene, spp=spp, key=key, method=method, checkpoint=ckpt, patch=8,
            relative_illumination=ri))

    return fp, {
        "ray_ckpt": (ray(True), False),
        "ray_nockpt": (ray(False), False),
        "ray_noRI": (ray(True, ri=False), False),
        "ray_default_fp": (ray(True, R.RAY), True),
        "psf_noRI": (lambda L, e: jnp.sum(wmap * jl.render(
            L, scene, spp=2, key=key, method=R.PSFRender(kernel_size=5), patch=3,
            relative_illumination=False)), False),
        "psf_RI": (lambda L, e: jnp.sum(wmap * jl.render(
            L, scene, spp=2, key=key, method=R.PSFRender(kernel_size=5), patch=3)), True),
    }


def validity_certificate(lens, fp, params, spp=4):
    """Per parameter: does any ray change validity between x − h, x and x + h (largest step)?
    A uniform scene with relative illumination is Σ valid·πr²/(spp·e0): a step function."""
    ones = jnp.ones((6, 6, 3))
    key = jax.random.PRNGKey(1)
    dyn, static = eqx.partition(lens, eqx.is_inexact_array)
    f = jax.jit(lambda d: jl.render(eqx.combine(d, static), ones, spp=spp, key=key,
                                    method=R.RayRender(footprints=fp), patch=8))
    base = np.asarray(f(dyn))
    out = {}
    for name, get, j, h in params:
        x0 = float(_leaf((lens, {}), get, j))
        changed = 0
        for s in (-1, 1):
            Pm = _set((lens, {}), get, j, x0 + s * h)[0]
            img = np.asarray(f(eqx.partition(Pm, eqx.is_inexact_array)[0]))
            changed += int(np.sum(img != base))
        out[name] = changed
    return out


def section_render(only):
    lens = render_lens()
    fp, fns = render_fns(lens)
    cert = validity_certificate(lens, fp, RENDER_PARAMS)
    yield [f"{'ok' if not any(cert.values()) else 'JUMP':6s} render    certificate        "
           + " ".join(f"{k}:{v}px" for k, v in cert.items())
           + "  (pixels whose valid-ray sum changed at x±h: 0 = smooth over the step)"]
    grads = {}
    for name, (fn, doc) in fns.items():
        if not _hit(only, name):
            continue
        rows = compare("render", name, fn, (lens, {}), RENDER_PARAMS, fwd=True)
        if doc:
            rows = [("DOC   " + r[6:]) if not r.startswith("ok") else r for r in rows]
        yield grouped(rows, "DOC" if doc else "")
        if name in ("ray_ckpt", "ray_nockpt"):
            dyn, static = eqx.partition(lens, eqx.is_inexact_array)
            g = jax.jit(jax.grad(lambda d, fn=fn, st=static: fn(eqx.combine(d, st), {})))(dyn)
            grads[name] = np.concatenate([np.ravel(x) for x in jax.tree.leaves(g)])
    if len(grads) == 2:
        a, b = grads["ray_ckpt"], grads["ray_nockpt"]
        err = float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
        yield [f"{'ok' if err <= 1e-12 else 'WRONG':6s} render    ckpt_vs_nockpt     "
               f"max|g_ckpt - g_nockpt|/max|g| = {err:.1e} over {a.size} leaves"]


# ----------------------------------------------------------------------------------- glass
def _cat_model(name):
    return jl.get_material(name).model


GLASSES = {
    "herzberger": lambda: jl.optics.materials.Herzberger(
        jnp.array([1.5, 0.004, 1e-4, -0.002, 1e-4, -1e-6])),
    "sellmeier2": lambda: jl.optics.materials.Sellmeier2(
        jnp.array([0.0, 1.2, 0.1, -0.01, 3.0])),
    "conrady": lambda: jl.optics.materials.Conrady(jnp.array([1.49, 0.005, 4e-4])),
    "handbook1": lambda: jl.optics.materials.Handbook1(jnp.array([2.27, 0.01, 0.02, 0.01])),
    "handbook2": lambda: jl.optics.materials.Handbook2(jnp.array([1.0, 1.25, 0.01, 0.01])),
    "sellmeier4": lambda: jl.optics.materials.Sellmeier4(
        jnp.array([1.0, 1.2, 0.01, 0.05, 100.0])),
    "extended_J-BASF2": lambda: _cat_model("J-BASF2"),
    "extended2_E-LAFH3": lambda: _cat_model("E-LAFH3"),
    "extended3_J-BAF3": lambda: _cat_model("J-BAF3"),
    "sellmeier5": lambda: jl.Sellmeier(
        jnp.array([1.0, 0.2, 0.05, 0.01, 0.5]), jnp.array([0.006, 0.02, 0.05, 0.1, 100.0])),
    "catalog_range": lambda: jl.get_material("N-SF5"),
}


def image_points(L, e):
    """Image-plane (x, y) of the chief and two marginal rays (y fan) at 0.486 and 0.656 µm,
    weighted and summed (lateral colour and focus both show)."""
    th = jnp.deg2rad(e["field"])
    d = jnp.stack([0.0 * th, jnp.sin(th), jnp.cos(th)])
    ys = jnp.array([0.0, 3.5, -3.5])
    o = jnp.stack([0.0 * ys, ys - 5.0 * d[1] / d[2], jnp.full(3, -5.0)], -1)
    tot = 0.0
    for wl, w in ((0.4861327, 1.0), (0.6562725, -0.7)):
        out = jl.trace(L, jl.Rays(o, jnp.broadcast_to(d, o.shape), wl))
        y = out.origin[..., 1]
        tot = tot + w * jnp.sum(jnp.array([1.0, 0.6, 0.3]) * y)
    return tot


def _coeff_params(get_obj, obj):
    out = []
    for fld in dataclasses.fields(obj):
        val = getattr(obj, fld.name)
        if not eqx.is_inexact_array(val):
            continue
        if isinstance(obj, jl.CatalogMaterial):
            continue

        def get(P, n=fld.name):
            return getattr(get_obj(P), n)

        for j in range(val.shape[0]):
            h = max(1e-4 * abs(float(val[j])), 1e-7)
            out.append((f"{fld.name}[{j}]", get, j, h))
    return out


def section_glass(only):
    for name, make in GLASSES.items():
        m = make()
        lens = dataclasses.replace(testbed(jl.Sphere(-1 / 40)), materials=(m, jl.Air()))
        P = (lens, {"field": jnp.asarray(5.0), "wl": jnp.asarray(0.55)})
        if isinstance(m, jl.CatalogMaterial):
            params = _coeff_params(lambda P: P[0].materials[0].model, m.model)
        else:
            params = _coeff_params(lambda P: P[0].materials[0], m)
        for fname, fn in (("image_pts", image_points), ("efl", FUNCS["efl"])):
            if not _hit(only, f"{name} {fname}"):
                continue
            yield grouped(compare("glass", f"{name}:{fname}", fn, P, params))
    # HullMaterials: logits -> (nd, Vd) inside a hull of catalog glasses
    if _hit(only, "hull"):
        from jaxlens.design.materials import HullMaterials

        hull = HullMaterials(jnp.array([[1.49, 70.0], [1.53, 56.0], [1.62, 36.0],
                                        [1.66, 20.0], [1.59, 30.0]]))
        base = testbed(jl.Sphere(-1 / 40))

        def fn(logits, e):
            mat = hull.materials(logits[None])[0]
            return image_points(dataclasses.replace(base, materials=(mat, jl.Air())), e) + \
                0.01 * FUNCS["efl"](dataclasses.replace(base, materials=(mat, jl.Air())), e)

        logits = jnp.log(jnp.array([0.1, 0.3, 0.2, 0.25, 0.15]))
        P = (logits, {"field": jnp.asarray(5.0), "wl": jnp.asarray(0.55)})
        params = [(f"m[{j}]", lambda P: P[0], j, 1e-5) for j in range(5)]
        yield grouped(compare("glass", "hull_logits", fn, P, params))


# ------------------------------------------------------------------------------------ regs
@contextlib.contextmanager
def frozen_radii(value):
    """``regularizers.clear_radii`` returning ``value`` (held at x): the finite differences
    then see the function ``grad`` differentiates."""
    from jaxlens.design import regularizers as reg

    old = reg.clear_radii
    reg.clear_radii = lambda path: jnp.asarray(value, path.origin.dtype)
    try:
        yield
    finally:
        reg.clear_radii = old


def design_setup(finished: bool, seed: int = 0):
    from jaxlens.design import curriculum, init, losses, multistart

    spec, config = jl.design.DesignSpec(), multistart.DesignConfig()
    dt = jnp.float64
    pmap = init.parameterization(spec, dt)
    sampling = losses.RayLoss.make(config.n_fields, 2, spec.wavelengths, spec.sensor_size, dt)
    objective = losses.Objective(pmap, sampling, jnp.asarray(init.gap_bounds(spec), dt))
    if finished:
        lens = jl.load(os.path.join(ROOT, "experiments/classical/designs/seed_0.zmx"))
        surf = tuple(
            jl.EvenAsphere(s.c, s.k, jnp.pad(s.coeffs, (0, pmap.n_terms + 1 - s.coeffs.shape[0])))
            if i in pmap.optical else s for i, s in enumerate(lens.surfaces))
        lens = dataclasses.replace(lens, surfaces=surf)
        params = pmap.from_lens(lens)
        tmpl = dataclasses.replace(pmap.template, materials=lens.materials)
        pmap = dataclasses.replace(pmap, template=tmpl)
        objective = dataclasses.replace(objective, pmap=pmap)
    else:
        params = jax.tree.map(lambda x: x[0], init.random_starts(spec, [seed], dt))
    stage = config.stages(spec)[-1]
    args = curriculum.stage_args(
        spec, stage, jnp.ones((1, config.n_fields), dt), config.reg_weights, dt)
    args = jax.tree.map(lambda x: x[0], args)
    return objective, params, args


def _a_params(params):
    """(name, getter, index, step): c, k, d as vectors; a flattened through a reshaped copy."""
    rows = []
    for name in ("c", "k", "d"):
        for j in range(getattr(params, name).shape[0]):
            # k: the conic's gradients are small (1e-8 of a loss of 4): a step of 1e-6 left
            # the differences at their rounding noise (spread 7e-2); 1e-2 … 1e-4 is smooth
            h = 1e-2 if name == "k" else 1e-6
            rows.append((f"{name}[{j}]", lambda P, name=name: getattr(P[0], name), j, h))
    return rows


def radii_at(objective, params, args):
    """The clear radii the objective holds at ``params`` (``regularizers.clear_radii``)."""
    from jaxlens.design import losses
    from jaxlens.design import regularizers as reg
    from jaxlens.tracing.forward import trace_path

    lens = objective.pmap.to_lens(params)
    path = trace_path(lens, losses.launch(lens, objective.sampling, args), uniform=True)
    return np.asarray(reg.clear_radii(path))


def section_regs(only):
    for label, finished in (("random", False), ("finished", True)):
        yield from _regs_cases(label, finished, only)


def _regs_cases(label, finished, only):
        objective, params, args = design_setup(finished)
        # a (the aspheric terms) as a flat leaf so that every element can be stepped
        shape = params.a.shape
        P = ((dataclasses.replace(params, a=params.a.reshape(-1))), {})

        def unflat(p):
            return dataclasses.replace(p, a=p.a.reshape(shape))

        plist = _a_params(params) + [
            (f"a[{j}]", lambda P: P[0].a, j, 1e-6) for j in range(int(np.prod(shape)))]
        _, aux0 = objective(params, args)
        radii0 = radii_at(objective, params, args)
        yield [f"info   regs      {label:18s} loss={float(aux0.loss):.6e} regs(obl,gap,slope)="
               f"{np.asarray(aux0.regs).round(8).tolist()} radii={radii0.round(3).tolist()}"]
        fns = {
            "loss": lambda p, _: jnp.sum(objective(unflat(p), args)[0] ** 2),
            "reg_obliquity": lambda p, _: objective(unflat(p), args)[1].regs[0],
            "reg_spacing": lambda p, _: objective(unflat(p), args)[1].regs[1],
            "reg_slope": lambda p, _: objective(unflat(p), args)[1].regs[2],
        }
        for name, fn in fns.items():
            for frz in (False, True):
                case = f"{label}:{name}{':frozen' if frz else ''}"
                if not _hit(only, case):
                    continue
                ctx = frozen_radii(radii0) if frz else contextlib.nullcontext()
                with ctx:
                    rows = compare("regs", case, fn, P, plist, fwd=False)
                if not frz:  # radii held without gradient: documented
                    rows = [("DOC   " + r[6:]) if not r.startswith("ok") else r for r in rows]
                yield grouped(rows, "" if frz else "DOC")


# ------------------------------------------------------------------------------------ edof
def edof_setup(kernel_size=9, pupil=8):
    from jaxlens.experiments.edof import lenses as el

    lens = el.to_hybrid(el.classical_lens(binning=16), n_odd=3, cubic=0.0)
    pmap = el.HybridParameterization.of(lens)
    p = pmap.from_lens(lens)
    p = dataclasses.replace(p, odd_x=jnp.array([0.8, -0.2, 0.05]),
                            odd_y=jnp.array([0.7, 0.1, -0.04]))
    return pmap, p, kernel_size, pupil


def edof_loss_fn(pmap, kernel_size, pupil, tile=4):
    from jaxlens.experiments.edof import losses as elo
    from jaxlens.experiments.edof import optics as eo

    n = tile + kernel_size - 1
    rng = np.random.default_rng(3)
    windows = jnp.asarray(rng.uniform(0, 1, (2, n, n, 3)))  # B = 2 patches
    xy = jnp.array([[0.0, 0.0], [1.2, -0.8]])
    depths = jnp.array([300.0, 1500.0])
    key = jax.random.PRNGKey(5)

    def fn(p, e):
        lens = pmap.to_lens(p)
        kern = eo.patch_psfs(lens, jnp.tile(xy, (2, 1)), jnp.repeat(depths, 2),
                             kernel_size=kernel_size, pixel_size=lens.sensor.pixel_size,
                             pupil=pupil, key=key)
        kern = kern.reshape((2, 2) + kern.shape[1:])
        sims = eo.simulate(windows, kern)
        def c(x):  # the central tile × tile pixels (train._centre)
            m = (x.shape[-2] - tile) // 2
            return x[..., m:m + tile, m:m + tile, :]

        total, _ = elo.edof_loss(c(sims), c(sims), c(windows), w_sim=1.0, w_raw=0.5)
        return total

    return fn


def section_edof(only):
    pmap, p, ks, pu = edof_setup()
    fn = edof_loss_fn(pmap, ks, pu)
    params = []
    for name in ("odd_x", "odd_y", "even"):
        for j in range(getattr(p, name).shape[0]):
            params.append((f"{name}[{j}]", lambda P, name=name: getattr(P[0], name), j, 1e-4))
    for name in ("c", "k", "focus"):
        params.append((name, lambda P, name=name: getattr(P[0], name), None, 1e-4))
    if _hit(only, "edof"):
        yield grouped(compare("edof", "loss_psf", fn, (p, {}), params))


# ----------------------------------------------------------------------------------- image
@contextlib.contextmanager
def frozen_image_helpers(prewarped, fp):
    """``prewarp`` and the render's footprints held at their values at x (both are held
    without gradient in ``ImageObjective``): differences then see ``grad``'s function."""
    from jaxlens.imaging import distortion

    old_p, old_f = distortion.prewarp, R._compute_footprints
    distortion.prewarp = lambda *a, **k: prewarped
    R._compute_footprints = lambda *a, **k: fp
    try:
        yield
    finally:
        distortion.prewarp, R._compute_footprints = old_p, old_f


def image_setup(n=6, seed=0):
    from jaxlens.design import losses
    from jaxlens.imaging.distortion import prewarp

    objective, params, args = design_setup(False, seed)
    spec = jl.design.DesignSpec()
    sensor = jl.Sensor((n, n), jnp.asarray(spec.sensor_size[0] / n, jnp.float64))
    yy, xx = np.mgrid[0:n, 0:n] / (n - 1.0)
    scene = jnp.asarray(np.stack([0.2 + 0.5 * xx, 0.3 + 0.4 * yy, 0.5 + 0.2 * (xx - yy)], -1))
    io = losses.ImageObjective(objective, scene, sensor, spp=4)
    lens = objective.pmap.to_lens(params)
    stop = eqx.tree_at(lambda x: x.semi_diameter, lens.surfaces[lens.stop], 0.5 * args.epd)
    surfaces = tuple(stop if i == lens.stop else x for i, x in enumerate(lens.surfaces))
    lens = eqx.tree_at(lambda x: (x.surfaces, x.epd), lens, (surfaces, args.epd))
    warped = prewarp(lens, scene, sensor=sensor)
    fp = R.footprints(lens, sensor=sensor, wavelengths=RGB_WAVELENGTHS)
    return io, params, args, warped, fp, lens


def section_image(only):
    from jaxlens.imaging.distortion import alignment_penalty

    io, params, args, warped, fp, lens0 = image_setup()
    shape = params.a.shape
    P = (dataclasses.replace(params, a=params.a.reshape(-1)), {})

    def unflat(p):
        return dataclasses.replace(p, a=p.a.reshape(shape))

    plist = _a_params(params) + [(f"a[{j}]", lambda P: P[0].a, j, 1e-6)
                                 for j in range(0, int(np.prod(shape)), 3)]
    fn = lambda p, _: jnp.sum(io(unflat(p), args)[0] ** 2)  # noqa: E731
    radii0 = radii_at(io.ray, params, args)
    if _hit(only, "image_loss:frozen"):
        with frozen_image_helpers(warped, fp), frozen_radii(radii0):
            yield grouped(compare("image", "image_loss:frozen", fn, P, plist, fwd=True))
    if _hit(only, "image_loss:live"):
        rows = compare("image", "image_loss:live", fn, P, plist, fwd=True)
        yield grouped([("DOC   " + r[6:]) if not r.startswith("ok") else r for r in rows], "DOC")
    if _hit(only, "alignment"):
        pen = lambda p, _: alignment_penalty(  # noqa: E731
            io.ray.pmap.to_lens(unflat(p)), alpha=1.0, sensor=io.sensor)
        yield grouped(compare("image", "alignment_penalty", pen, P, plist, fwd=True))


SECTIONS = {
    "render": section_render,
    "glass": section_glass,
    "regs": section_regs,
    "edof": section_edof,
    "image": section_image,
}


def main(argv):
    run_sections(SECTIONS, argv)


if __name__ == "__main__":
    main(sys.argv)
