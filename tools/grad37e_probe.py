"""Round 37e: gradients against central differences, in what round 36e did not cover.

Sections (pick with arguments; default all):

    surfaces   every leaf of Biconic, ZernikeSag, QTypeAsphere (bfs, con), XYPolynomial,
               Toroidal (and the cylinder cx = 0), Binary2, Grating, CoordinateBreak (orders
               0 and 1), a curved (conic) image surface; a ray-grid functional of ``trace``
               (intercepts, directions, OPL of the valid rays), the same with
               ``reverse_rule=True``, and ``rms_spot``
    apertures  a rectangular aperture and an obscuration that vignette part of the grid: the
               gradient must be the masked function's (steps that move no ray across an edge)
    materials  Sellmeier B/C, Schott coefficients, a Tabulated table's indices and nodes, a
               ModelGlass nd/Vd and a catalog glass (N-BK7), through the trace and ``efl``
    precision  float32 gradients against float64 (bar: relative 1e-3 of the gradient's size)
    batch      ``jit(vmap(grad))`` over a batch of lenses against per-lens ``grad``
    forward    ``jacfwd`` against ``jacrev`` and ``hessian`` against differences of ``grad``;
               ``reverse_rule=True`` must refuse forward mode with a TypeError (documented)
    design     the design loss (``Objective``), each regularizer (obliquity, spacing, slope),
               the re-weighting mask, the render and the EDoF PSF bank

    PYTHONPATH=. python tools/grad37e_probe.py [section ...] [--only substring]

One line per case: ``status section case parameter value grad fd rel spread jvp``; status ok /
WRONG? (1e-6 < rel < 1e-3) / WRONG / NAN / ERROR, as in ``tools/grad36e_probe.py``, whose
helpers this reuses.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from grad36e_probe import REL, _leaf, _set  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.optics import paraxial  # noqa: E402
from jaxlens.optics.toroidal import Toroidal  # noqa: E402
from jaxlens.tracing.surface_adjoint import SAG_KINDS  # noqa: E402

GLASS = jl.ModelGlass(1.5168, 64.17)


def _hit(only, case):
    """``--only a,b``: run a case when any of the comma-separated substrings is in its name."""
    return not only or any(p in case for p in only.split(","))


# --------------------------------------------------------------------------- the functional
def grid_rays(lens, field, wl, n=5, dtype=jnp.float64):
    """An n×n grid over 0.9 of the entrance pupil, launched at z = -5 mm, field angle
    ``field`` (deg) in y with a third of it in x (so that x-asymmetric terms are seen)."""
    u = jnp.linspace(-0.9, 0.9, n, dtype=dtype)
    X, Y = jnp.meshgrid(u, u)
    r = lens.epd / 2
    th = jnp.deg2rad(field)
    d = jnp.stack([jnp.sin(th) / 3, jnp.sin(th), jnp.ones_like(th)])
    d = d / jnp.linalg.norm(d)
    o = jnp.stack([X.ravel() * r, Y.ravel() * r, jnp.full(n * n, -5.0, dtype)], -1)
    o = o - 5.0 * jnp.stack([d[0] / d[2], d[1] / d[2], 0.0 * d[2]])
    return jl.Rays(o, jnp.broadcast_to(d, o.shape), wl)


def ray_functional(out):
    m = out.valid
    x, y = out.origin[..., 0], out.origin[..., 1]
    s = x**2 + 0.7 * y**2 + 0.3 * x + 0.2 * y + 1e-3 * out.opl
    s = s + out.direction[..., 0] + 0.5 * out.direction[..., 1]
    return jnp.sum(jnp.where(m, s, 0.0))


def f_trace(L, e, **kw):
    return ray_functional(jl.trace(L, grid_rays(L, e["field"], e["wl"]), **kw))


FUNCS = {
    "trace": f_trace,
    "trace_rr": lambda L, e: f_trace(L, e, reverse_rule=True),
    "rms_spot": lambda L, e: jl.analysis.rms_spot(
        L, fields=e["field"][None], wavelengths=e["wl"][None]
    ).polychromatic.sum(),
    "efl": lambda L, e: paraxial.efl(L, e["wl"]),
}


# ------------------------------------------------------------------------------ the checker
def compare(section, case, fn, P, params, *, rel_bar=REL, fwd=True):
    """Rows comparing ``grad`` of ``fn(P)`` with central differences at three steps (the best
    is reported, with their spread) and with ``jvp`` for each (name, getter, index, step)."""
    dyn, static = eqx.partition(P, eqx.is_inexact_array)

    def f(d):
        return jnp.asarray(fn(*eqx.combine(d, static)), dtype=jnp.float64).reshape(())

    fj = jax.jit(f)
    vg = jax.jit(jax.value_and_grad(f))
    jvp = jax.jit(lambda d, t: jax.jvp(f, (d,), (t,))[1])
    head = f"{section:9s} {case:18s}"
    try:
        v, g = vg(dyn)
    except Exception as ex:  # noqa: BLE001
        msg = (str(ex).strip().splitlines() or [""])[0][:140]
        return [f"ERROR  {head} {'*':10s} {type(ex).__name__}: {msg}"]
    v = float(v)
    G = eqx.combine(g, static)
    rows = []
    for name, get, j, h0 in params:
        x0 = float(_leaf(P, get, j))
        gval = float(_leaf(G, get, j))
        fds = []
        for h in (h0, h0 / 10, h0 / 100):
            hp = fj(eqx.partition(_set(P, get, j, x0 + h), eqx.is_inexact_array)[0])
            hm = fj(eqx.partition(_set(P, get, j, x0 - h), eqx.is_inexact_array)[0])
            fds.append((float(hp) - float(hm)) / (2 * h))
        fds = np.array(fds)
        scale = max(abs(gval), np.max(np.abs(fds)), 1e-12 * max(1.0, abs(v)) / h0)
        errs = np.abs(fds - gval) / scale
        rel = float(np.nanmin(errs)) if np.isfinite(errs).any() else float("nan")
        jtxt = "-"
        if fwd:
            tan = jax.tree_util.tree_map(jnp.zeros_like, dyn)
            Pt = eqx.combine(tan, static)
            Pt = eqx.tree_at(get, Pt, get(Pt) + 1.0 if j is None else get(Pt).at[j].set(1.0))
            try:
                jv = float(jvp(dyn, eqx.partition(Pt, eqx.is_inexact_array)[0]))
                jrel = abs(jv - gval) / max(abs(gval), 1e-300) if gval != 0 else abs(jv)
                jtxt = f"{jrel:.1e}"
            except Exception as ex:  # noqa: BLE001
                jtxt = "fwd-err:" + type(ex).__name__
        if not (np.isfinite(v) and np.isfinite(gval)):
            status = "NAN"
        elif not np.isfinite(rel):
            status = "FDNAN"
        elif rel <= rel_bar:
            status = "ok"
        else:
            status = "WRONG?" if rel < 1e-3 else "WRONG"
        best = fds[np.nanargmin(errs)] if np.isfinite(errs).any() else fds[0]
        spread = np.ptp(fds) / max(abs(fds).max(), 1e-300)
        rows.append(
            f"{status:6s} {head} {name:10s} v={v:+.6e} g={gval:+.8e} fd={best:+.8e} "
            f"rel={rel:.1e} spread={spread:.0e} jvp={jtxt}"
        )
    return rows


# ------------------------------------------------------------------------------- surfaces
STEPS = {
    "c": 1e-5,
    "cx": 1e-5,
    "k": 1e-3,
    "kx": 1e-3,
    "norm_radius": 1e-4,
    "decenter_x": 1e-4,
    "decenter_y": 1e-4,
    "tilt_x": 1e-3,
    "tilt_y": 1e-3,
    "tilt_z": 1e-3,
    "zernike": 1e-5,
    "phase_coeffs": 1e-2,
    "lines_per_um": 1e-5,
    "order": 1e-4,
}
EVEN_COEFFS = (jl.ZernikeSag, Toroidal, jl.Binary2, jl.EvenAsphere)


def leaf_params(get_obj, obj, skip=("semi_diameter",)):
    """(name, getter, index, step) for every element of every float leaf of ``obj``."""
    out = []
    for fld in dataclasses.fields(obj):
        val = getattr(obj, fld.name)
        if fld.name in skip or not eqx.is_inexact_array(val):
            continue

        def get(P, n=fld.name):
            return getattr(get_obj(P), n)

        if val.ndim == 0:
            out.append((fld.name, get, None, STEPS.get(fld.name, 1e-5)))
            continue
        for j in range(val.shape[0]):
            h = STEPS.get(fld.name, 1e-5)
            if fld.name == "coeffs" and isinstance(obj, EVEN_COEFFS):
                h = 1e-4 * 4.0 ** (-2 * (j + 1))
            elif fld.name in ("coeffs", "indices", "B", "C", "wavelengths"):
                h = max(1e-4 * abs(float(val[j])), 1e-6)
            out.append((f"{fld.name}[{j}]", get, j, h))
    return out


def testbed(back, *, image=None, extra=()):
    """A singlet whose back surface is ``back`` (stop on the front, EPD 8, field 8°)."""
    s = (jl.Sphere(1 / 30), *extra, back)
    t = jnp.array([4.0] + [0.0] * len(extra) + [40.0])
    mats = (GLASS,) * (1 + len(extra)) + (jl.Air(),)
    kw = {} if image is None else {"image": image}
    return jl.Lens(
        s,
        t,
        mats,
        stop=0,
        epd=8.0,
        fields=jnp.array([0.0, 8.0]),
        wavelengths=jnp.array([0.5875618]),
        **kw,
    )


def zern():
    z = jnp.array([0.0, 0.01, -0.005, 0.002, 0.003, -0.001, 0.001, 0.0005, -0.0004, 0.0003, 2e-4])
    return jl.ZernikeSag(
        c=-1 / 40,
        k=0.2,
        coeffs=jnp.array([0.0, 1e-5]),
        zernike=z,
        norm_radius=5.0,
        decenter_x=0.1,
        decenter_y=-0.2,
    )


SURFACES = {
    "biconic": lambda: testbed(jl.Biconic(c=-1 / 40, k=-0.5, cx=-1 / 35, kx=0.3)),
    "zernike": lambda: testbed(zern()),
    "zernike_fringe": lambda: testbed(dataclasses.replace(zern(), ordering="fringe")),
    "qbfs": lambda: testbed(
        jl.QTypeAsphere(c=-1 / 40, k=-0.3, coeffs=jnp.array([1e-3, -5e-4, 2e-4]), norm_radius=5.0)
    ),
    "qcon": lambda: testbed(
        jl.QTypeAsphere(
            c=-1 / 40, k=-0.3, coeffs=jnp.array([1e-3, -5e-4, 2e-4]), norm_radius=5.0, qtype="con"
        )
    ),
    "xypoly": lambda: testbed(
        jl.XYPolynomial(
            c=-1 / 40,
            k=0.1,
            norm_radius=5.0,
            coeffs=jnp.array([0.0, 0.001, 0.01, 0.002, 0.012, 1e-3, -5e-4, 2e-4, 1e-4]),
        )
    ),
    "toroid": lambda: testbed(
        Toroidal(c=-1 / 40, k=0.1, coeffs=jnp.array([0.0, 1e-5]), cx=-1 / 35)
    ),
    "cylinder": lambda: testbed(Toroidal(c=-1 / 40, k=0.1, coeffs=jnp.array([0.0, 1e-5]), cx=0.0)),
    "binary2": lambda: testbed(
        jl.Binary2(
            c=-1 / 40,
            coeffs=jnp.array([0.0, 1e-5]),
            order=1.0,
            norm_radius=5.0,
            phase_coeffs=jnp.array([-30.0, 5.0]),
        )
    ),
    "grating": lambda: testbed(jl.Grating(c=-1 / 40, k=0.1, lines_per_um=0.05, order=1.0)),
    "cbreak": lambda: testbed(
        jl.Sphere(-1 / 40),
        extra=(
            jl.CoordinateBreak(decenter_x=0.1, decenter_y=0.2, tilt_x=1.5, tilt_y=-1.0, tilt_z=3.0),
        ),
    ),
    "cbreak_o1": lambda: testbed(
        jl.Sphere(-1 / 40),
        extra=(
            jl.CoordinateBreak(
                decenter_x=0.1, decenter_y=0.2, tilt_x=1.5, tilt_y=-1.0, tilt_z=3.0, order=1
            ),
        ),
    ),
    "curved_image": lambda: testbed(jl.Sphere(-1 / 40), image=jl.Conic(c=-1 / 60, k=0.5)),
}


def extras(lens):
    return {"field": jnp.asarray(0.6 * float(lens.fields[-1])), "wl": jnp.asarray(0.55)}


def common_params():
    return [
        ("t0", lambda P: P[0].thickness, 0, 1e-4),
        ("field", lambda P: P[1]["field"], None, 1e-4),
        ("wl", lambda P: P[1]["wl"], None, 1e-5),
    ]


def section_surfaces(only):
    for name, make in SURFACES.items():
        lens = make()
        P = (lens, extras(lens))
        if name == "curved_image":
            params = leaf_params(lambda P: P[0].image, lens.image)
        else:
            i = len(lens.surfaces) - 1 if not name.startswith("cbreak") else 1
            params = leaf_params(lambda P, i=i: P[0].surfaces[i], lens.surfaces[i])
        params += common_params()
        # the reverse rule only where it takes the surface (surface_adjoint.supported);
        # rms_spot traces the same steps (its own aiming and centroid were round 36e's)
        kind = lens.image if name == "curved_image" else lens.surfaces[-1]
        fnames = ("trace", "trace_rr") if type(kind) in SAG_KINDS else ("trace",)
        for fname in fnames:
            if not _hit(only, f"{name} {fname}"):
                continue
            yield compare(
                "surfaces", f"{name}:{fname}", FUNCS[fname], P, params, fwd=fname != "trace_rr"
            )


# ------------------------------------------------------------------------------ apertures
def section_apertures(only):
    base = testbed(jl.Sphere(-1 / 40))
    cases = {
        "rect": (0, jl.Aperture("rect", 3.0, 2.5, decenter_x=0.17, decenter_y=-0.13)),
        "obscure": (1, jl.Aperture("ellipse", 1.3, 1.1, decenter_x=0.05, blocks=True)),
        "ellipse": (1, jl.Aperture("ellipse", 3.3, 2.9, decenter_y=0.11)),
    }
    for name, (i, ap) in cases.items():
        lens = dataclasses.replace(base, apertures=((i, ap),))
        P = (lens, extras(lens))
        params = [
            ("c0", lambda P: P[0].surfaces[0].c, None, 1e-6),
            ("c1", lambda P: P[0].surfaces[1].c, None, 1e-6),
            ("t0", lambda P: P[0].thickness, 0, 1e-5),
            ("field", lambda P: P[1]["field"], None, 1e-5),
        ]
        for fname in ("trace",):
            if not _hit(only, f"{name} {fname}"):
                continue
            yield compare("apertures", f"{name}:{fname}", FUNCS[fname], P, params)


# ------------------------------------------------------------------------------ materials
MATERIALS = {
    "sellmeier": lambda: jl.Sellmeier(
        jnp.array([1.03961212, 0.231792344, 1.01046945]),
        jnp.array([0.00600069867, 0.0200179144, 103.560653]),
    ),
    "catalog_bk7": lambda: jl.get_material("N-BK7"),
    "schott": lambda: jl.Schott(
        jnp.array(
            [2.2718929, -1.0108077e-2, 1.0592509e-2, 2.0816965e-4, -7.6472538e-6, 4.9240991e-7]
        )
    ),
    "tabulated": lambda: jl.Tabulated(
        jnp.array([0.4861327, 0.5875618, 0.6562725]), jnp.array([1.5224, 1.5168, 1.5143])
    ),
    "modelglass": lambda: jl.ModelGlass(1.62, 36.4),
    "catalog_sf": lambda: jl.get_material("N-SF5"),
}


def section_materials(only):
    for name, make in MATERIALS.items():
        m = make()
        lens = dataclasses.replace(testbed(jl.Sphere(-1 / 40)), materials=(m, jl.Air()))
        P = (lens, extras(lens))
        if hasattr(m, "model"):  # a catalog glass: its formula's coefficients
            params = leaf_params(lambda P: P[0].materials[0].model, m.model)
        else:
            params = leaf_params(lambda P: P[0].materials[0], m)
        params += common_params()[2:]
        for fname in ("trace", "efl"):
            if not _hit(only, f"{name} {fname} {type(m).__name__}"):
                continue
            yield compare("materials", f"{name}:{fname}", FUNCS[fname], P, params)


# ------------------------------------------------------------------------------ precision
def _grads(fn, P):
    dyn, static = eqx.partition(P, eqx.is_inexact_array)
    g = jax.jit(jax.grad(lambda d: fn(*eqx.combine(d, static))))(dyn)
    return np.concatenate([np.ravel(np.asarray(x, np.float64)) for x in jax.tree.leaves(g)])


def _cast(P, dt):
    return jax.tree.map(lambda x: x.astype(dt) if eqx.is_inexact_array(x) else x, P)


def section_precision(only):
    """float32 gradients against float64: per leaf, |g32 − g64| ≤ 1e-3 · max|g64| (a trace
    of 40 mm carries ~1e-7 relative rounding per step; 1e-3 leaves room for cancellation)."""
    lenses = {
        "cooke": lambda: zoo.cooke_triplet(clip=False),
        "gauss": lambda: zoo.double_gauss(clip=False),
        "xypoly": SURFACES["xypoly"],
        "binary2": SURFACES["binary2"],
        "qbfs": SURFACES["qbfs"],
    }
    for lname, make in lenses.items():
        for fname in ("trace", "rms_spot"):
            case = f"{lname}:{fname}"
            if not _hit(only, case):
                continue
            lens = make()
            P = (lens, extras(lens))
            try:
                g64 = _grads(FUNCS[fname], P)
                with jax.enable_x64(False):
                    P32 = _cast(P, jnp.float32)
                    dyn, static = eqx.partition(P32, eqx.is_inexact_array)

                    def f32(d, static=static, fname=fname):
                        L, e = eqx.combine(d, static)
                        e = dict(e)
                        return FUNCS[fname](L, e)

                    g = jax.jit(jax.grad(f32))(dyn)
                    dts = {x.dtype for x in jax.tree.leaves(g)}
                    g32 = np.concatenate(
                        [np.ravel(np.asarray(x, np.float64)) for x in jax.tree.leaves(g)]
                    )
            except Exception as ex:  # noqa: BLE001
                yield [
                    f"ERROR  precision {case:18s} {type(ex).__name__}: "
                    + (str(ex).strip().splitlines() or [""])[0][:140]
                ]
                continue
            scale = np.max(np.abs(g64))
            err = np.abs(g32 - g64) / scale
            worst = int(np.argmax(err))
            status = "ok" if err[worst] <= 1e-3 and np.all(np.isfinite(g32)) else "WRONG"
            dts = sorted(map(str, dts))
            yield [
                f"{status:6s} precision {case:18s} leaves={g64.size} dtypes={dts} "
                f"max|g32-g64|/max|g64|={err[worst]:.1e} at leaf {worst} "
                f"(g64={g64[worst]:+.6e}, g32={g32[worst]:+.6e})"
            ]


# ---------------------------------------------------------------------------------- batch
def section_batch(only):
    """``jit(vmap(grad))`` over three lenses (curvatures and thicknesses varied) against
    each lens's own ``grad``: equal to rounding (relative 1e-10 of the largest)."""
    for lname, make in {
        "cooke": lambda: zoo.cooke_triplet(clip=False),
        "zernike": SURFACES["zernike"],
        "cbreak": SURFACES["cbreak"],
    }.items():
        for fname in ("trace", "trace_rr", "rms_spot"):
            case = f"{lname}:{fname}"
            if not _hit(only, case):
                continue
            base = make()
            lenses = [
                eqx.tree_at(
                    lambda L: (L.surfaces[0].c, L.thickness),
                    base,
                    (base.surfaces[0].c * s, base.thickness * (1 + 0.01 * s)),
                )
                for s in (0.98, 1.0, 1.03)
            ]
            Ps = [(L, extras(L)) for L in lenses]
            try:
                dyns = [eqx.partition(P, eqx.is_inexact_array)[0] for P in Ps]
                static = eqx.partition(Ps[0], eqx.is_inexact_array)[1]
                stacked = jax.tree.map(lambda *x: jnp.stack(x), *dyns)

                def f(d, static=static, fname=fname):
                    return FUNCS[fname](*eqx.combine(d, static))

                gb = jax.jit(jax.vmap(jax.grad(f)))(stacked)
                rows = []
                for b, d in enumerate(dyns):
                    g1 = jax.jit(jax.grad(f))(d)
                    a = np.concatenate([np.ravel(x[b]) for x in jax.tree.leaves(gb)])
                    r = np.concatenate([np.ravel(x) for x in jax.tree.leaves(g1)])
                    rows.append(np.max(np.abs(a - r)) / np.max(np.abs(r)))
                err = max(rows)
                status = "ok" if err <= 1e-10 else "WRONG"
                yield [f"{status:6s} batch     {case:18s} max rel |vmap-grad|={err:.1e}"]
            except Exception as ex:  # noqa: BLE001
                yield [
                    f"ERROR  batch     {case:18s} {type(ex).__name__}: "
                    + (str(ex).strip().splitlines() or [""])[0][:140]
                ]


# -------------------------------------------------------------------------------- forward
def section_forward(only):
    """``jacfwd`` = ``jacrev`` (1e-10); ``hessian`` against central differences of ``grad``
    (best of steps 1e-4, 1e-5, 1e-6 relative, bar 1e-5); ``reverse_rule=True`` raises
    TypeError under ``jacfwd``."""
    for lname, make in {
        "cooke": lambda: zoo.cooke_triplet(clip=False),
        "hybrid": lambda: jl.load("jaxlens/data/lenses/hybrid_singlet.json"),
        "zernike": SURFACES["zernike"],
        "xypoly": SURFACES["xypoly"],
        "qbfs": SURFACES["qbfs"],
        "binary2": SURFACES["binary2"],
        "cbreak": SURFACES["cbreak"],
        "toroid": SURFACES["toroid"],
    }.items():
        case = f"{lname}:trace"
        if not _hit(only, case):
            continue
        lens = make()
        e = extras(lens)

        def f(x, lens=lens, e=e):  # x = (c of every surface with one, thickness)
            cs, t = x
            surfs = list(lens.surfaces)
            k = 0
            for i, s in enumerate(surfs):
                if hasattr(s, "c") and not isinstance(s, jl.CoordinateBreak):
                    surfs[i] = dataclasses.replace(s, c=cs[k])
                    k += 1
            L = eqx.tree_at(lambda L: (L.surfaces, L.thickness), lens, (tuple(surfs), t))
            return f_trace(L, e)

        cs0 = jnp.array(
            [
                float(s.c)
                for s in lens.surfaces
                if hasattr(s, "c") and not isinstance(s, jl.CoordinateBreak)
            ]
        )
        x0 = (cs0, lens.thickness)
        try:
            jf = jax.jit(jax.jacfwd(f))(x0)
            jr = jax.jit(jax.jacrev(f))(x0)
            a = np.concatenate([np.ravel(u) for u in jax.tree.leaves(jf)])
            b = np.concatenate([np.ravel(u) for u in jax.tree.leaves(jr)])
            e1 = np.max(np.abs(a - b)) / np.max(np.abs(b))
            H = jax.jit(jax.hessian(f))(x0)
            Hcc = np.asarray(H[0][0])
            gr = jax.jit(jax.grad(f))
            best = []
            for j in range(cs0.shape[0]):
                errs = []
                for h in (1e-4, 1e-5, 1e-6):
                    hh = h * max(abs(float(cs0[j])), 1e-2)
                    gp = gr((cs0.at[j].add(hh), x0[1]))[0]
                    gm = gr((cs0.at[j].add(-hh), x0[1]))[0]
                    col = (np.asarray(gp) - np.asarray(gm)) / (2 * hh)
                    # relative to the whole Hessian: a column of ~0 (a dummy surface in air, the
                    # hybrid's stop) is the differences' noise alone
                    scale = max(np.max(np.abs(col)), np.max(np.abs(Hcc)), 1e-300)
                    errs.append(np.max(np.abs(col - Hcc[:, j])) / scale)
                best.append(min(errs))
            e2 = max(best)
            sym = np.max(np.abs(Hcc - Hcc.T)) / np.max(np.abs(Hcc))
            status = "ok" if e1 <= 1e-10 and e2 <= 1e-5 and sym <= 1e-10 else "WRONG"
            rr = "?"
            try:
                jax.jacfwd(
                    lambda x, lens=lens, e=e: f_trace(
                        eqx.tree_at(lambda L: L.thickness, lens, x), e, reverse_rule=True
                    )
                )(lens.thickness)
                rr = "no-error"
            except TypeError:
                rr = "TypeError"
            yield [
                f"{status:6s} forward   {case:18s} jacfwd~jacrev={e1:.1e} "
                f"hessian~fd(grad)={e2:.1e} asym={sym:.1e} rr_jacfwd={rr}"
            ]
        except Exception as ex:  # noqa: BLE001
            yield [
                f"ERROR  forward   {case:18s} {type(ex).__name__}: "
                + (str(ex).strip().splitlines() or [""])[0][:140]
            ]


# --------------------------------------------------------------------------------- design
def _design_setup():
    from jaxlens.design import curriculum, init, losses, multistart

    spec, config = jl.design.DesignSpec(), multistart.DesignConfig()
    dt = jnp.float64
    pmap = init.parameterization(spec, dt)
    sampling = losses.RayLoss.make(config.n_fields, 2, spec.wavelengths, spec.sensor_size, dt)
    objective = losses.Objective(pmap, sampling, jnp.asarray(init.gap_bounds(spec), dt))
    params = jax.tree.map(lambda x: x[0], init.random_starts(spec, [3], dt))
    stage = config.stages(spec)[0]
    args = curriculum.stage_args(
        spec, stage, jnp.ones((1, config.n_fields), dt), config.reg_weights, dt
    )
    args = jax.tree.map(lambda x: x[0], args)
    return spec, config, pmap, sampling, objective, params, args


def _leaf_params_tree(tree, prefix, per_leaf=3, h=1e-5):
    out = []
    leaves, treedef = jax.tree.flatten(tree)
    for li, leaf in enumerate(leaves):
        if not eqx.is_inexact_array(leaf):
            continue

        def get(P, li=li):
            return jax.tree.leaves(P[0])[li]

        n = int(np.size(leaf))
        for j in sorted({0, n // 2, n - 1})[:per_leaf]:
            if leaf.ndim == 0:
                out.append((f"{prefix}{li}", get, None, h))
                break
            if leaf.ndim == 1:
                out.append((f"{prefix}{li}[{j}]", get, j, h))
    return out


def section_design(only):
    spec, config, pmap, sampling, objective, params, args = _design_setup()
    from jaxlens.design import losses, mask

    P = (params, {})
    params_list = _leaf_params_tree(params, "p")
    fns = {
        "loss": lambda p, _: jnp.sum(objective(p, args)[0] ** 2),
        "loss_rr": lambda p, _: jnp.sum(losses.reverse_mode(objective)(p, args)[0] ** 2),
        "reg_obliquity": lambda p, _: objective(p, args)[1].regs[0],
        "reg_spacing": lambda p, _: objective(p, args)[1].regs[1],
        "reg_slope": lambda p, _: objective(p, args)[1].regs[2],
        "mask": lambda p, _: jnp.sum(
            mask.reweighting_mask(objective(p, args)[1].rms, sampling.area) ** 2
        ),
    }
    for name, fn in fns.items():
        if not _hit(only, name):
            continue
        yield compare("design", name, fn, P, params_list, fwd=False)


def section_imaging(only):
    """The render (ray method, checkpointed tiles) and the EDoF PSF bank's patch PSFs, with
    respect to lens parameters of the Cooke triplet (fixed key: the same samples each call)."""
    from jaxlens.experiments.edof import optics as edof_optics

    cooke = dataclasses.replace(zoo.cooke_triplet(), sensor=jl.Sensor((8, 8), 0.06))
    yy, xx = np.mgrid[0:8, 0:8] / 7.0
    scene = jnp.asarray(np.stack([np.sin(3 * xx) ** 2, np.cos(2 * yy) ** 2, xx * yy], -1))
    key = jax.random.PRNGKey(1)
    params = [
        ("c0", lambda P: P[0].surfaces[0].c, None, 1e-6),
        ("c3", lambda P: P[0].surfaces[3].c, None, 1e-6),
        ("t5", lambda P: P[0].thickness, 5, 1e-5),
    ]
    fns = {
        "render": lambda L, e: jnp.sum(jl.render(L, scene, spp=4, key=key) ** 2),
        "render_nockpt": lambda L, e: jnp.sum(
            jl.render(L, scene, spp=4, key=key, checkpoint=False) ** 2
        ),
        "edof_patch_psfs": lambda L, e: jnp.sum(
            edof_optics.patch_psfs(
                L,
                jnp.array([[0.0, 0.0], [0.5, 0.3]]),
                jnp.array([1e3, 3e3]),
                kernel_size=9,
                pixel_size=0.004,
                pupil=8,
            )
            ** 2
        ),
    }
    for name, fn in fns.items():
        if not _hit(only, name):
            continue
        yield compare("imaging", name, fn, (cooke, {}), params)


SECTIONS = {
    "surfaces": section_surfaces,
    "apertures": section_apertures,
    "materials": section_materials,
    "precision": section_precision,
    "batch": section_batch,
    "forward": section_forward,
    "design": section_design,
    "imaging": section_imaging,
}


def run_sections(sections, argv):
    """Run the named sections of a probe (default all), ``--only NAME,...`` passed to each,
    printing one row a line; a section that fails prints one ERROR row and its traceback.
    Rounds 38d and 42e run their own sections with it."""
    args = argv[1:]
    only = ""
    if "--only" in args:
        i = args.index("--only")
        only = args[i + 1]
        del args[i : i + 2]
    for sec in args or list(sections):
        try:
            for rows in sections[sec](only):
                for r in rows:
                    print(r, flush=True)
        except Exception:  # noqa: BLE001
            print(
                f"ERROR  {sec} probe: " + traceback.format_exc().strip().splitlines()[-1][:300],
                flush=True,
            )
            traceback.print_exc()


def main(argv):
    run_sections(SECTIONS, argv)


if __name__ == "__main__":
    main(sys.argv)
