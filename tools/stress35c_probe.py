# ruff: noqa: E501, E731
"""Numerical-stability stress round 35c: lenses and rays at the edges of docs/stability.md's
envelope (extreme scales, very fast lenses, fisheye fields, rays at the rim, at the critical
angle and tangent to a sphere, very high indices, huge aspheric terms, nearly concentric
surfaces, folded mirrors), the analyses on them, and batch sizes at the chunk boundary.

Each probe compares against a closed form where there is one (a sphere's intercepts, a
paraboloid's focus, a plate's lateral shift, the aplanatic points of a sphere) and against
float64 for float32, and is classified ok / NaN-Inf / invalid-marked-valid / silent wrong /
float32-beyond-bound / clear error. Run: ``PYTHONPATH=. python tools/stress35c_probe.py [word]``.
"""

import math
import os
import sys

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import probe_table as PT  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import sampling, zoo  # noqa: E402
from jaxlens.optics.materials import ModelGlass  # noqa: E402

WL = 0.5875618
F32_MM, F32_DIR = 1e-4, 2e-5  # docs/stability.md
f32 = jnp.float32


def row(name, fn):
    """fn() -> (outcome, detail); exceptions are classified as by probe_table."""
    if PT.FILTER and PT.FILTER not in name:
        return
    try:
        outcome, detail = fn()
    except ValueError as e:
        outcome, detail = "clear error", f"ValueError: {str(e).splitlines()[0][:140]}"
    except Exception as e:  # noqa: BLE001
        outcome, detail = (
            "crash",
            f"{type(e).__name__}: {str(e).splitlines()[0][:140] if str(e) else ''}",
        )
    PT.ROWS.append((name, outcome, detail))


def finite(*xs):
    return all(np.isfinite(np.asarray(x)).all() for x in xs)


def rays(o, d, wl=WL, dtype=jnp.float64):
    o = jnp.asarray(o, dtype)
    d = jnp.asarray(d, jnp.float64)
    d = (d / jnp.linalg.norm(d, axis=-1, keepdims=True)).astype(dtype)
    return jl.Rays(o, d, dtype(wl) if dtype is f32 else wl)


def single(surfaces, thickness, materials, **kw):
    return jl.Lens(
        surfaces=tuple(surfaces),
        thickness=jnp.asarray(thickness, float),
        materials=tuple(materials),
        **kw,
    )


def compare32(lens, r64, scale=1.0, name=""):
    """Trace in float64 and float32; classify against the documented bound (scaled by
    ``scale`` when the bound is relative to the lens size)."""
    a = jl.trace(lens, r64)
    r32 = jl.Rays(r64.origin.astype(f32), r64.direction.astype(f32), f32(r64.wavelength))
    b = jl.trace(lens, r32)
    if not finite(a.origin, a.direction, b.origin, b.direction):
        return "NaN-Inf", "non-finite output"
    va, vb = np.asarray(a.valid), np.asarray(b.valid)
    both = va & vb
    dp = np.abs(np.asarray(a.origin) - np.asarray(b.origin, np.float64))[both].max(initial=0)
    dd = np.abs(np.asarray(a.direction) - np.asarray(b.direction, np.float64))[both].max(initial=0)
    det = f"valid64 {va.sum()}/{va.size} valid32 {vb.sum()}; dp {dp:.3g} mm, dd {dd:.3g}"
    if (vb & ~va).any():
        return "invalid-marked-valid", det + f"; {int((vb & ~va).sum())} valid in f32 only"
    if dp > F32_MM * scale or dd > F32_DIR:
        return "float32-beyond-bound", det
    if (va & ~vb).any():
        return "ok", det + f"; {int((va & ~vb).sum())} flagged in f32 only"
    return "ok", det


# ----------------------------------------------------------------------------------------
# Closed forms
# ----------------------------------------------------------------------------------------
def sphere_hit(c, o, d):
    """The first intersection of lines with a sphere of curvature c, vertex at 0 (numpy)."""
    R = 1 / c
    oc = o - np.array([0, 0, R])
    b = np.sum(oc * d, -1)
    cc = np.sum(oc * oc, -1) - R * R
    disc = b * b - cc
    s = np.sqrt(np.maximum(disc, 0))
    t1, t2 = -b - s, -b + s
    # the root on the vertex's hemisphere (z < R for R > 0)
    p1 = o + t1[:, None] * d
    t = np.where((p1[:, 2] - R) * np.sign(R) < 0, t1, t2)
    return o + t[:, None] * d, disc >= 0


def area_scales():
    # A 10 µm ball micro-lens (R = 5 µm) and a 2 m F/4 paraboloid mirror, float64 and float32.
    for R, name in ((0.005, "micro R=5um"), (1000.0, "big R=1m")):
        c = 1 / R
        lens = single([jl.Sphere(c), jl.Plane()], [R, R], [ModelGlass(1.5, 60.0), jl.Air()])
        ys = np.linspace(-0.999, 0.999, 17) * R
        o = np.stack([np.zeros(17), ys, -np.full(17, R)], -1)
        d = np.tile([0.0, math.sin(0.1), math.cos(0.1)], (17, 1))
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)

        def closed(lens=lens, o=o, d=d, c=c, R=R):
            out = jl.trace(lens, rays(o, d), upto=0)
            want, real = sphere_hit(c, o, d)
            ok = np.asarray(out.valid)
            if (ok & ~real).any():
                return "invalid-marked-valid", "valid without a root"
            err = np.abs(np.asarray(out.origin) - want)[ok].max() / R
            return ("ok" if err < 1e-12 else "silent wrong"), f"{ok.sum()} valid; rel err {err:.2g}"

        row(f"scale {name}: sphere intercepts vs closed form (f64)", closed)
        row(
            f"scale {name}: f32 vs f64 (bound x R/10mm)",
            lambda lens=lens, o=o, d=d, R=R: compare32(lens, rays(o, d), scale=max(R / 10, 1)),
        )
    # micro asphere (Newton path) in float32: does the absolute tolerance (64 sqrt(eps) mm) swamp it?
    R = 0.005
    for dt in (jnp.float64, f32):

        def micro_asphere(dt=dt):
            s = jl.EvenAsphere(
                1 / R, 0.0, jnp.array([0.0, 1.0, 0.0])
            )  # A4 = 1 /mm^3: 6e-10 mm at 5 um
            lens = single([s, jl.Plane()], [R, 1.0], [ModelGlass(1.5, 60.0), jl.Air()])
            ys = np.linspace(0, 1.3, 27) * R  # past the rim too: no root there
            o = np.stack([np.zeros(27), ys, -np.full(27, R)], -1)
            d = np.tile([0.0, 0.0, 1.0], (27, 1))
            out = jl.trace(lens, rays(o, d, dtype=dt), upto=0)
            _, real = sphere_hit(1 / R, o, d)
            ok = np.asarray(out.valid)
            p = np.asarray(out.origin, np.float64)
            r2 = p[:, 0] ** 2 + p[:, 1] ** 2
            sag = r2 / R / (1 + np.sqrt(np.maximum(1 - r2 / R**2, 0))) + r2**2
            err = np.abs(p[:, 2] - sag)[ok & real].max(initial=0)
            det = f"{ok.sum()} valid of {real.sum()} real; max err {err:.3g} mm (R = 5 um)"
            if (ok & ~real).any():
                return (
                    "invalid-marked-valid",
                    det
                    + f"; {(ok & ~real).sum()} beyond the rim valid, z {p[ok & ~real][:, 2].max():.3g}",
                )
            bound = 1e-15 if dt is jnp.float64 else 1e-4 * R / 10  # f32: the bound scaled to R
            return ("ok" if err < bound else "silent wrong"), det

        row(f"scale micro asphere R=5um {dt.__name__}: valid rays on surface", micro_asphere)
    # 2 m telescope: F/4 paraboloid, 2000 mm aperture, focus 8000 mm; perfect on axis.
    for dt in (jnp.float64, f32):

        def telescope(dt=dt):
            lens = jl.Lens(
                surfaces=(jl.Conic(-1 / 16000.0, -1.0),),
                thickness=jnp.array([-8000.0]),
                materials=(jl.Air(),),
                mirrors=(0,),
                epd=2000.0,
            )
            pupil = sampling.pupil_grid(33)
            r = sampling.collimated(lens, 0.0, pupil)
            r = jl.Rays(r.origin.astype(dt), r.direction.astype(dt), dt(WL) if dt is f32 else WL)
            out = jl.trace(lens, r)
            ok = np.asarray(out.valid)
            xy = np.asarray(out.origin, np.float64)[ok, :2]
            spot = np.abs(xy).max()
            det = f"{ok.sum()}/{ok.size} valid; max |xy| at focus {spot:.3g} mm"
            bound = 1e-9 if dt is jnp.float64 else F32_MM  # docs/stability.md (absolute)
            return (
                "ok"
                if spot < bound
                else ("silent wrong" if dt is jnp.float64 else "float32-beyond-bound")
            ), det

        row(f"scale 2m paraboloid F/4 perfect focus {dt.__name__}", telescope)


def area_plate():
    # Plane-parallel plate: lateral shift t sin(th) (1 - cos th / sqrt(n^2 - sin^2 th)).
    n, t = 1.5168, 10.0
    for th in (0.0, 30.0, 60.0, 85.0, 89.0, 89.9):

        def plate(th=th):
            lens = single([jl.Plane(), jl.Plane()], [t, 5.0], [ModelGlass(n, 64.17), jl.Air()])
            a = math.radians(th)
            o = np.array([[0.0, 0.0, -1.0]])
            d = np.array([[0.0, math.sin(a), math.cos(a)]])
            out = jl.trace(lens, rays(o, d), upto=1)
            p = np.asarray(out.origin)[0]
            # the undeviated line at z = t
            y_line = -1.0 * 0 + (t + 1.0) * math.tan(a)
            shift = (y_line - p[1]) * math.cos(a)
            want = t * math.sin(a) * (1 - math.cos(a) / math.sqrt(n * n - math.sin(a) ** 2))
            err = abs(shift - want) / want if want else abs(shift)
            ddir = np.abs(np.asarray(out.direction)[0] - d[0]).max()
            return (
                "ok" if err < 1e-9 and ddir < 1e-13 and bool(out.valid[0]) else "silent wrong"
            ), f"shift {shift:.6g} want {want:.6g}; dir err {ddir:.2g}"

        row(f"plate shift th={th}", plate)


def area_critical():
    # Exactly at the critical angle from glass n = 1.5 into air at a plane; and n = 4.
    for n in (1.5, 4.0, 1.0001):
        crit = math.asin(1 / n)

        def crit_probe(n=n, crit=crit):
            lens = single(
                [jl.Plane(), jl.Plane()],
                [1.0, 1.0],
                [jl.Air(), jl.Air()],
                object_material=ModelGlass(n, 1e6),
            )
            angs = np.array([crit - 1e-9, crit, crit + 1e-9, np.nextafter(crit, 0)])
            o = np.zeros((4, 3))
            o[:, 2] = -1
            d = np.stack([np.zeros(4), np.sin(angs), np.cos(angs)], -1)
            out = jl.trace(lens, rays(o, d), upto=0)
            dz = np.asarray(out.direction)[:, 2]
            v = np.asarray(out.valid)
            # exact Snell: n sin = sin'
            s_out = n * np.sin(angs)
            det = f"valid {v.astype(int).tolist()}, out dz {np.array2string(dz, precision=3)}, n sin {np.array2string(s_out, precision=17)}"
            if not finite(out.origin, out.direction):
                return "NaN-Inf", det
            if (v & (s_out > 1)).any():
                return "invalid-marked-valid", det
            return "ok", det

        row(f"critical angle n={n} at a plane", crit_probe)

        def crit_grad(n=n, crit=crit):
            lens = single(
                [jl.Plane(), jl.Plane()],
                [1.0, 1.0],
                [jl.Air(), jl.Air()],
                object_material=ModelGlass(n, 1e6),
            )

            def f(a):
                d = jnp.stack([0.0, jnp.sin(a), jnp.cos(a)])[None]
                out = jl.trace(lens, jl.Rays(jnp.array([[0.0, 0.0, -1.0]]), d, WL))
                return jnp.sum(out.origin)

            g = jax.grad(f)(jnp.float64(crit))
            return ("ok" if np.isfinite(g) else "NaN-Inf"), f"grad {float(g):.3g}"

        row(f"critical angle n={n}: gradient", crit_grad)


def area_high_index():
    # Germanium-like n = 4 lens and an aplanatic sphere (Abbe): a ray aimed at the inner
    # aplanatic point R(1 + n'/n)... : a sphere of radius R in glass n, point at R/n inside
    # images to n R outside with no aberration at any aperture.
    for n in (1.5, 4.0, 10.0):

        def aplanatic(n=n):
            R = 10.0
            # Object in glass n at distance R/n... use light from air toward the glass:
            # virtual object point at z = R + nR (center at R), rays converge to it, refract into
            # glass n, then converge exactly to z = R + R/n.
            c = 1 / R
            lens = single(
                [jl.Sphere(c), jl.Plane()],
                [R + R / n, 0.0],
                [ModelGlass(n, 1e6), ModelGlass(n, 1e6)],
            )
            target = np.array([0.0, 0.0, R + n * R])
            ang = np.linspace(0.01, 0.6, 12)  # convergence half-angles up to 34 deg
            # ray from a point on the sphere backward
            d = np.stack([np.zeros(12), np.sin(ang), np.cos(ang)], -1)
            o = target - 60.0 * d
            out = jl.trace(lens, rays(o, d))
            ok = np.asarray(out.valid)
            yimg = np.abs(np.asarray(out.origin)[ok, 1]).max(initial=0)
            # sine condition: n' sin u' / (n sin u) = const
            d2 = np.asarray(out.direction)[ok]
            sin_in = np.sin(ang[ok])
            sin_out = np.hypot(d2[:, 0], d2[:, 1])
            ratio = sin_out / sin_in
            det = f"{ok.sum()}/12 valid; |y| at aplanatic point {yimg:.2g}; sin ratio spread {np.ptp(ratio):.2g} (want n = {n}, got {ratio.mean():.15g})"
            good = yimg < 1e-10 and np.ptp(ratio) < 1e-12 and abs(ratio.mean() - n) < 1e-12
            return ("ok" if good else "silent wrong"), det

        row(f"aplanatic sphere n={n}", aplanatic)


def area_tangent():
    # Rays exactly tangent to a sphere (|y| = R), and at exactly the rim semi-diameter.
    for dt in (jnp.float64, f32):

        def tangent(dt=dt):
            R = 7.0
            lens = single([jl.Sphere(1 / R), jl.Plane()], [R, 1.0], [ModelGlass(1.5, 60), jl.Air()])
            ys = np.array([R, -R, R * (1 - 1e-7), R * (1 + 1e-7)])
            o = np.stack([np.zeros(4), ys, -np.ones(4)], -1)
            d = np.tile([0.0, 0.0, 1.0], (4, 1))
            out = jl.trace(lens, rays(o, d, dtype=dt))
            v = np.asarray(out.valid)
            return (
                (
                    "NaN-Inf"
                    if not finite(out.origin, out.direction)
                    else ("invalid-marked-valid" if v[3] else "ok")
                ),
                f"valid {v.astype(int).tolist()} dir {np.array2string(np.asarray(out.direction)[:, 2], precision=3)}",
            )

        row(f"tangent to sphere {dt.__name__}", tangent)
    for dt in (jnp.float64, f32):

        def rim(dt=dt):
            sd = 3.0
            lens = single(
                [jl.Sphere(0.05, semi_diameter=sd), jl.Plane()],
                [2.0, 5.0],
                [ModelGlass(1.5, 60), jl.Air()],
            )
            ys = np.array([sd, -sd, np.nextafter(sd, 0), sd * (1 + 1e-5), sd * (1 + 1e-3)])
            o = np.stack([np.zeros(5), ys, -np.ones(5)], -1)
            d = np.tile([0.0, 0.0, 1.0], (5, 1))
            out = jl.trace(lens, rays(o, d, dtype=dt))
            v = np.asarray(out.valid)
            want = [True, True, True, False, False]
            return (
                "ok"
                if v.tolist() == want
                else ("invalid-marked-valid" if (v & ~np.array(want)).any() else "silent wrong")
            ), f"valid {v.astype(int).tolist()}"

        row(f"ray at exactly the rim {dt.__name__}", rim)


def area_asphere_huge():
    # Huge A4 at large heights: sag 1e4 mm at r = 10; Newton either converges or flags.
    for a4 in (1.0, 1e2, 1e4):

        def huge(a4=a4):
            s = jl.EvenAsphere(0.0, 0.0, jnp.array([0.0, a4]))
            lens = single([s, jl.Plane()], [1e6, 1.0], [ModelGlass(1.5, 60), jl.Air()])
            ys = np.linspace(0, 10, 21)
            o = np.stack([np.zeros(21), ys, -np.ones(21)], -1)
            d = np.tile([0.0, 0.05, 1.0], (21, 1))
            out = jl.trace(lens, rays(o, d), upto=0)
            v = np.asarray(out.valid)
            p = np.asarray(out.origin)
            r2 = p[:, 0] ** 2 + p[:, 1] ** 2
            res = np.abs(p[:, 2] - a4 * r2**2)
            rel = res / np.maximum(1, np.abs(p[:, 2]))
            det = f"{v.sum()}/21 valid; max residual {res[v].max(initial=0):.3g} mm (rel {rel[v].max(initial=0):.2g}); z max {p[v, 2].max(initial=0):.3g}"
            if not finite(p):
                return "NaN-Inf", det
            if (rel[v] > 1e-9).any():
                return "invalid-marked-valid", det
            return "ok", det

        row(f"huge A4={a4:g} at r<=10", huge)


def area_concentric():
    # Nearly concentric meniscus: R1 = 10, R2 = 10 + eps, t small; the rays through the common
    # centre are undeviated.
    for dr in (1e-3, 1e-9, 0.0):

        def conc(dr=dr):
            R1, t = 10.0, 0.5
            R2 = R1 - t + dr  # concentric when R2 = R1 - t
            lens = single(
                [jl.Sphere(1 / R1), jl.Sphere(1 / R2)], [t, 20.0], [ModelGlass(1.8, 30), jl.Air()]
            )
            ang = np.linspace(-0.8, 0.8, 9)
            centre = np.array([0.0, 0.0, R1])
            d = np.stack([np.zeros(9), np.sin(ang), np.cos(ang)], -1)
            o = centre - 12 * d
            out = jl.trace(lens, rays(o, d), upto=1)
            dd = np.abs(np.asarray(out.direction) - d).max()
            v = np.asarray(out.valid)
            bound = 1e-13 if dr == 0 else 1e-3
            return (
                "ok" if v.all() and dd < bound else "silent wrong"
            ), f"{v.sum()}/9 valid; direction change {dd:.2g}"

        row(f"concentric meniscus dR={dr:g}: centre rays undeviated", conc)


def area_fast_and_wide():
    cooke = zoo.cooke_triplet()

    # F/0.6: the Cooke triplet scaled to EPD = EFL/0.6 (rays vignetted; analysis must count).
    def fast_rms():
        efl = float(jl.efl(cooke))
        import dataclasses

        lens = dataclasses.replace(cooke, epd=jnp.asarray(efl / 0.6))
        s = jl.analysis.rms_spot(lens)
        det = f"rms {np.array2string(np.asarray(s.polychromatic), precision=3)}, valid {np.array2string(np.asarray(s.valid_fraction), precision=3)}"
        return (
            "ok"
            if finite(s.polychromatic) or (np.asarray(s.valid_fraction) == 0).any()
            else "NaN-Inf"
        ), det

    row("F/0.6 cooke: rms_spot", fast_rms)
    # Fisheye-like fields on a single lens: 85 deg, 89.9 deg.
    for fld in (85.0, 89.0, 89.99):

        def wide(fld=fld):
            lens = single(
                [jl.Sphere(0.02), jl.Sphere(-0.02)],
                [5.0, 45.0],
                [ModelGlass(1.5168, 64.17), jl.Air()],
                epd=2.0,
                fields=jnp.array([0.0, fld]),
                stop=0,
            )
            r = sampling.collimated(lens, fld, sampling.pupil_grid(5))
            out = jl.trace(lens, r)
            return (
                ("ok" if finite(out.origin, out.direction, out.opl, r.origin) else "NaN-Inf"),
                f"{int(out.valid.sum())}/{out.valid.size} valid; origin z {float(r.origin[0, 2]):.3g}",
            )

        row(f"field {fld} collimated trace", wide)

        def wide_dist(fld=fld):
            lens = single(
                [jl.Sphere(0.02), jl.Sphere(-0.02)],
                [5.0, 45.0],
                [ModelGlass(1.5168, 64.17), jl.Air()],
                epd=2.0,
                fields=jnp.array([0.0, fld]),
                stop=0,
            )
            dd = jl.analysis.distortion(lens)
            return (
                "ok"
                if finite(*[x for x in jax.tree_util.tree_leaves(dd) if hasattr(x, "dtype")])
                else "NaN-Inf"
            ), str(dd)[:140]

        row(f"field {fld} distortion", wide_dist)


def area_batch():
    lens = zoo.cooke_triplet()
    key = jax.random.PRNGKey(0)
    pupil = 0.99 * sampling.pupil_random(key, 65537)
    r = sampling.collimated(lens, 14.0, pupil)
    full = jl.trace(lens, r, chunk=None)
    for n in (1, 2, 17, 65537):

        def batch(n=n):
            sub = jl.Rays(r.origin[:n], r.direction[:n], r.wavelength)
            a = jl.trace(lens, sub)
            b = jl.trace(lens, sub, chunk=16)
            err = max(
                float(jnp.abs(a.origin - full.origin[:n]).max()),
                float(jnp.abs(b.origin - full.origin[:n]).max()),
            )
            same = bool((a.valid == full.valid[:n]).all() & (b.valid == full.valid[:n]).all())
            return (
                "ok" if err < 2e-14 and same else "silent wrong"
            ), f"max diff {err:.2g} (docs: 2e-14 since round 35c, was 1e-14), same mask {same}"

        row(f"batch {n} vs one piece (chunk auto and 16)", batch)

    def batch32():
        r32 = jl.Rays(r.origin.astype(f32), r.direction.astype(f32), f32(WL))
        a = jl.trace(lens, r32)
        b = jl.trace(lens, r32, chunk=None)
        err = float(jnp.abs(a.origin - b.origin).max())
        return (
            "ok" if err < 2e-5 else "float32-beyond-bound"
        ), f"float32 65537 chunked vs whole: {err:.2g} mm (a few ulps; docs since round 35c)"

    row("batch 65537 float32 chunked vs whole", batch32)


def scaled(lens, s):
    """``lens`` with every length times ``s`` (curvatures / s)."""
    import dataclasses

    surfs = tuple(
        dataclasses.replace(q, c=q.c / s, semi_diameter=q.semi_diameter * s) for q in lens.surfaces
    )
    return dataclasses.replace(
        lens, surfaces=surfs, thickness=lens.thickness * s, epd=lens.epd * s, sensor=None
    )


def area_scale_invariance():
    # A lens scaled by s: lengths x s, angles, distortion %, RI unchanged; the wavefront in
    # waves x s. The Cooke triplet at s = 1e-3 (EFL 50 um) and s = 40 (EFL 2 m).
    base = zoo.cooke_triplet()
    ref = {}
    checks = {
        "paraxial efl": lambda L: jl.paraxial_data(L).efl,
        "paraxial bfl": lambda L: jl.paraxial_data(L).bfl,
        "rms_spot": lambda L: jl.analysis.rms_spot(L).polychromatic,
        "distortion %": lambda L: jl.analysis.distortion(L).percent_paraxial,
        "seidel sums": lambda L: jl.analysis.seidel(L).sums,
        "wavefront rms (waves)": lambda L: jl.analysis.wavefront(L, 14.0).rms,
        "zernike Z4..Z11 (waves)": lambda L: (
            jl.analysis.wavefront(L, 14.0).zernike(terms=11).coefficients[3:]
        ),
        "relative illumination": lambda L: (
            jl.imaging.radiometry.relative_illumination(L, jnp.array([10.0, 20.0])).ri
            if hasattr(
                jl.imaging.radiometry.relative_illumination(L, jnp.array([10.0, 20.0])), "ri"
            )
            else jl.imaging.radiometry.relative_illumination(L, jnp.array([10.0, 20.0]))
        ),
        "chief ray y": lambda L: jl.analysis.chief_ray(L, 14.0).origin[..., 1],
        "radius_for_fraction D80": lambda L: jl.analysis.radius_for_fraction(L, 14.0, 0.8),
    }
    # expected power of s for each
    power = {
        "paraxial efl": 1,
        "paraxial bfl": 1,
        "rms_spot": 1,
        "distortion %": 0,
        "seidel sums": 1,
        "wavefront rms (waves)": 1,
        "zernike Z4..Z11 (waves)": 1,
        "relative illumination": 0,
        "chief ray y": 1,
        "radius_for_fraction D80": 1,
    }
    for name, fn in checks.items():
        try:
            ref[name] = np.asarray(jax.tree_util.tree_leaves(fn(base))[0], np.float64)
        except Exception as e:  # noqa: BLE001
            ref[name] = e
    for s in (1e-3, 40.0):
        lens = scaled(base, s)
        for name, fn in checks.items():

            def go(name=name, fn=fn, lens=lens, s=s):
                if isinstance(ref[name], Exception):
                    raise ref[name]
                got = np.asarray(jax.tree_util.tree_leaves(fn(lens))[0], np.float64)
                want = ref[name] * s ** power[name]
                if not finite(got):
                    return "NaN-Inf", f"{got}"
                rel = np.abs(got - want).max() / max(np.abs(want).max(), 1e-300)
                return (
                    ("ok" if rel < 1e-6 else "silent wrong"),
                    f"rel diff {rel:.2g}; got {np.array2string(got.ravel()[:3], precision=5)} want {np.array2string(want.ravel()[:3], precision=5)}",
                )

            row(f"scale x{s:g} cooke: {name}", go)


def area_float32_limits():
    # A coefficient finite in float64 but beyond float32's range (a 10 um micro-lens's r^24 term).
    def overflow():
        s = jl.EvenAsphere(1 / 0.005, 0.0, jnp.array([0.0] * 11 + [1e45]))
        lens = single([s, jl.Plane()], [0.005, 1.0], [ModelGlass(1.5, 60.0), jl.Air()], epd=0.005)
        lens32 = lens.astype(f32)
        return (
            "silent wrong",
            f"cast to float32: coefficient {float(lens32.surfaces[0].coeffs[-1])} (every ray then misses)",
        )

    row("float32 cast of an r^24 coefficient 1e45 (micro-lens)", overflow)

    # A biconvex element of centre thickness 1e-6 mm: edge thickness < 0 off axis; float32
    # accepts a step back of up to 1e3 eps (1 + |dz|) mm = 1.2e-4 mm (step.py's forward test).
    def thin():
        T = single(
            [jl.Sphere(0.05), jl.Sphere(-0.05)],
            [1e-6, 20.0],
            [ModelGlass(1.5, 60.0), jl.Air()],
            epd=4.0,
        )
        ys = np.array([0.0, 1e-2, 0.03, 0.1])
        o = np.stack([np.zeros(4), ys, -np.ones(4)], -1)
        d = np.tile([0.0, 0.0, 1.0], (4, 1))
        a, b = jl.trace(T, rays(o, d)), jl.trace(T, rays(o, d, dtype=f32))
        va, vb = np.asarray(a.valid), np.asarray(b.valid)
        det = f"v64 {va.astype(int).tolist()} v32 {vb.astype(int).tolist()}; edge thickness {np.array2string(1e-6 - 2 * (20 - np.sqrt(400 - ys**2)), precision=2)} mm"
        return (
            "invalid-marked-valid" if (vb & ~va).any() else "ok"
        ), det + " (within the documented float32 slack)"

    row("float32 negative edge thickness 4e-6 mm", thin)


def area_mirror_analyses():
    # A paraboloid mirror at F/4 (2 m) and F/0.6, and an F/0.6 micro-mirror (20 um): on axis a
    # point (rms 0, wavefront 0, Strehl 1, S_I = 0); every analysis finite.
    for D, f in ((2000.0, 8000.0), (2000.0, 1200.0), (0.02, 0.012)):
        lens = jl.Lens(
            surfaces=(jl.Conic(-1 / (2 * f), -1.0),),
            thickness=jnp.array([-f]),
            materials=(jl.Air(),),
            mirrors=(0,),
            epd=D,
            fields=jnp.array([0.0, 0.1]),
        )

        def axis(lens=lens, f=f):
            rms = float(jl.analysis.rms_spot(lens).polychromatic[0])
            wf = jl.analysis.wavefront(lens, 0.0)
            s1 = float(jl.analysis.seidel(lens).sums[0])
            good = rms < 1e-12 * f and float(wf.rms) < 1e-6 and abs(s1) < 1e-12 * f
            return ("ok" if good else "silent wrong"), (
                f"rms {rms:.2g} mm, wavefront rms {float(wf.rms):.2g} waves, Strehl "
                f"{float(wf.strehl):.6g}, S_I {s1:.2g} mm"
            )

        row(f"paraboloid D={D:g} f={f:g}: on-axis point (rms, wavefront, S_I)", axis)

        def off(lens=lens):
            leaves = [
                jl.analysis.rms_spot(lens).polychromatic,
                jl.analysis.wavefront(lens, 0.1).zernike(terms=11).coefficients,
                jl.analysis.seidel(lens).sums,
                jl.analysis.distortion(lens).percent_paraxial,
                jl.imaging.radiometry.relative_illumination(lens, jnp.array([0.05, 0.1])).ri,
            ]
            return ("ok" if finite(*leaves) else "NaN-Inf"), (
                f"W131 Seidel {float(jl.analysis.seidel(lens).wavefront()[1]):.4g} waves"
            )

        row(f"paraboloid D={D:g} f={f:g}: 0.1 deg analyses finite", off)

    def below_one():
        return single([jl.Plane(), jl.Plane()], [1.0, 1.0], [ModelGlass(0.9, 60.0), jl.Air()])

    row("index 0.9 medium", below_one)


if __name__ == "__main__":
    jax.config.update("jax_enable_x64", True)
    PT.run(
        [
            area_scales,
            area_plate,
            area_critical,
            area_high_index,
            area_tangent,
            area_asphere_huge,
            area_concentric,
            area_fast_and_wide,
            area_batch,
            area_scale_invariance,
            area_float32_limits,
            area_mirror_analyses,
        ]
    )
