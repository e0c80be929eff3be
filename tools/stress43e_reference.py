"""Round 43e: an independent extended-precision single-ray tracer (mpmath, 60 digits in the
work, 40 written) and the reference data of ``tests/test_stress_round43e.py``.

Run with the optional tools environment (mpmath is no jaxlens dependency):

    /work/optenv/bin/python tools/stress43e_reference.py   # writes tests/data/stress43e/

The tracer shares no code with jaxlens. Each case is a sequential system of rotationally
symmetric surfaces (plane, sphere, conic, even asphere; refracting or reflecting) whose
vertices lie on the z axis at the exact (decimal) sums of the gaps, and rays given by their
origin and direction. The inputs are the float64 numbers the jaxlens trace sees (and, for
the float32 reference, those numbers rounded to float32), taken exactly, so that the only
difference between jaxlens and this trace is jaxlens's arithmetic.

Conventions (as jaxlens's): mm; light toward +z; surface 1's vertex at z = 0; sag
z = c r²/(1 + sqrt(1 − (1+k)c²r²)) + Σ_i a_i r^(2i) (a_1 multiplies r²); the intersection
with surface 1 is the root nearest its vertex plane along the whole line, later ones the
first root ahead of the ray on the sheet through the vertex; the optical path is Σ n·(length
travelled), from the ray's origin. A ray that misses a surface or is totally reflected is
written as invalid from there on.

The roots: a conic's quadratic c(x²+y²) + c(1+k)z² − 2z = 0 along the ray, solved in the
60-digit arithmetic (no cancellation can reach 40 digits for these inputs); an asphere's as
a sign change of z(t) − sag(x(t), y(t)), found by sampling it on 2000 points over 20 lens
scales (ahead of the ray, or either side of the vertex plane on surface 1), bisected to
2^-80 of its bracket and polished by Newton's method until the step is below 1e-55 mm (no
Newton start can wander to another root).

Each entry also holds its conditioning floor (``floor``): how far the exact answer moves when
every input number moves by its dtype's unit roundoff (two sign patterns). No trace in that
precision can be held to less; jaxlens's error is judged in units of it (plus the rounding
of the lens scale), which tells a formula that loses digits from an ill-conditioned ray (at
tangency, at the critical angle).
"""

from __future__ import annotations

import json
import math
import os
import sys

import mpmath as mp
import numpy as np

mp.mp.dps = 60
DIGITS = 40
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "tests", "data", "stress43e")


# ----------------------------------------------------------------------- the mp tracer
def sag_and_grad(s, x, y):
    """Sag z and (dz/dx, dz/dy) of surface ``s`` (a dict of mpf) at (x, y); None outside
    the conic's domain."""
    c, k, a = s["c"], s["k"], s["coeffs"]
    r2 = x * x + y * y
    arg = 1 - (1 + k) * c * c * r2
    if arg < 0:
        return None
    root = mp.sqrt(arg)
    z = c * r2 / (1 + root)
    slope = c / root if root != 0 else mp.inf  # (dz/dr)/r
    for i, ai in enumerate(a, start=1):
        z += ai * r2**i
        slope += 2 * i * ai * r2 ** (i - 1)
    return z, x * slope, y * slope


def conic_roots(s, o, d):
    """The real roots t of the base conic along o + t d on the vertex sheet, sorted."""
    c, k = s["c"], s["k"]
    ck = c * (1 + k)
    a = c * (d[0] ** 2 + d[1] ** 2) + ck * d[2] ** 2
    b = c * (o[0] * d[0] + o[1] * d[1]) + ck * o[2] * d[2] - d[2]
    cc = c * (o[0] ** 2 + o[1] ** 2) + ck * o[2] ** 2 - 2 * o[2]
    if a == 0:
        roots = [] if b == 0 else [-cc / (2 * b)]
    else:
        disc = b * b - a * cc
        if disc < 0:
            return []
        r = mp.sqrt(disc)
        roots = [(-b - r) / a, (-b + r) / a]
    out = []
    for t in roots:
        z = o[2] + t * d[2]
        if 1 - ck * z >= 0:  # the sheet through the vertex
            out.append(t)
    return sorted(out)


def residual(s, o, d, t):
    p = [o[i] + t * d[i] for i in range(3)]
    sg = sag_and_grad(s, p[0], p[1])
    if sg is None:
        return None
    z, gx, gy = sg
    return p[2] - z, d[2] - gx * d[0] - gy * d[1]


def polish(s, o, d, t):
    """Newton's method from a bracketed root until the step is below 1e-55 mm."""
    for _ in range(200):
        r = residual(s, o, d, t)
        if r is None or r[1] == 0:
            return None
        step = r[0] / r[1]
        t -= step
        if abs(step) < mp.mpf(10) ** -55 * (1 + abs(t)):
            r = residual(s, o, d, t)
            return t if r is not None and abs(r[0]) < mp.mpf(10) ** -50 else None
    return None


def sign_changes(s, o, d, lo, hi, n=2000):
    """Brackets (a, b) of the sign changes of the residual on [lo, hi], in order."""
    ts = [lo + (hi - lo) * j / n for j in range(n + 1)]
    fs = [residual(s, o, d, t) for t in ts]
    out = []
    for j in range(n):
        fa, fb = fs[j], fs[j + 1]
        if fa is not None and fb is not None and fa[0] * fb[0] <= 0:
            out.append((ts[j], ts[j + 1]))
    return out


def bracketed_root(s, o, d, a, b):
    f = lambda t: residual(s, o, d, t)[0]  # noqa: E731
    for _ in range(80):  # bisection to 2^-80 of the bracket, then Newton
        m = (a + b) / 2
        if f(a) * f(m) <= 0:
            b = m
        else:
            a = m
    return polish(s, o, d, (a + b) / 2)


def asphere_root(s, o, d, first, reach):
    """The asphere's root: on surface 1 the one nearest the vertex plane along the line,
    later the first ahead of the ray (t > 0), searched within ``reach`` mm."""
    if first:
        t_plane = -o[2] / d[2]
        ahead = sign_changes(s, o, d, t_plane, t_plane + reach)
        behind = sign_changes(s, o, d, t_plane - reach, t_plane)
        cands = ([bracketed_root(s, o, d, *ahead[0])] if ahead else []) + (
            [bracketed_root(s, o, d, *behind[-1])] if behind else [])
        cands = [t for t in cands if t is not None]
        return min(cands, key=lambda t: abs(t - t_plane)) if cands else None
    ahead = sign_changes(s, o, d, mp.mpf(0), mp.mpf(reach))
    return bracketed_root(s, o, d, *ahead[0]) if ahead else None


def intersect(s, o, d, first, reach):
    """The ray parameter of the hit (d is unit, so t is a length), or None."""
    if s["coeffs"]:
        return asphere_root(s, o, d, first, reach)
    roots = conic_roots(s, o, d)
    if first:
        t_plane = -o[2] / d[2]
        return min(roots, key=lambda t: abs(t - t_plane)) if roots else None
    ahead = [t for t in roots if t > -mp.mpf(10) ** -30]
    return ahead[0] if ahead else None


def normal(s, p):
    if s["coeffs"]:
        _, gx, gy = sag_and_grad(s, p[0], p[1])
        n = [-gx, -gy, mp.mpf(1)]
    else:
        c, k = s["c"], s["k"]
        n = [-c * p[0], -c * p[1], 1 - c * (1 + k) * p[2]]
    size = mp.sqrt(sum(v * v for v in n))
    return [v / size for v in n]


def refract(d, n, mu):
    cos_i = sum(a * b for a, b in zip(d, n, strict=True))
    k = 1 - mu * mu * (1 - cos_i * cos_i)
    if k < 0:
        return None
    root = mp.sqrt(k)
    g = (root if cos_i >= 0 else -root) - mu * cos_i
    return [mu * a + g * b for a, b in zip(d, n, strict=True)]


def reflect(d, n):
    dn = sum(a * b for a, b in zip(d, n, strict=True))
    return [a - 2 * dn * b for a, b in zip(d, n, strict=True)]


def trace(case, o, d, exact):
    """The ray after every surface and on the image plane: a list of (p, d, opl) or None."""
    surfaces = [dict(c=exact(s["c"]), k=exact(s["k"]),
                     coeffs=[exact(a) for a in s.get("coeffs", [])]) for s in case["surfaces"]]
    surfaces.append(dict(c=mp.mpf(0), k=mp.mpf(0), coeffs=[]))  # the image plane
    gaps = [exact(t) for t in case["thickness"]]
    index = [exact(n) for n in case["index"]]  # object space, then after each surface
    mirrors = set(case.get("mirrors", []))
    o = [exact(v) for v in o]
    d = [exact(v) for v in d]
    size = mp.sqrt(sum(v * v for v in d))
    d = [v / size for v in d]
    reach = mp.mpf(20 * case["scale"])  # how far an asphere's root is searched (mm)
    zv, opl, out = mp.mpf(0), mp.mpf(0), []
    for i, s in enumerate(surfaces):
        local = [o[0], o[1], o[2] - zv]
        t = intersect(s, local, d, (i == 0), reach)
        if t is None or (i > 0 and t < 0):
            out += [None] * (len(surfaces) - i)
            return out
        p = [local[j] + t * d[j] for j in range(3)]
        opl += index[i] * t
        if i < len(surfaces) - 1:
            nrm = normal(s, p)
            if i in mirrors:
                d = reflect(d, nrm)
            else:
                d = refract(d, nrm, index[i] / index[i + 1])
                if d is None:
                    out += [None] * (len(surfaces) - i)
                    return out
            zv_next = zv + gaps[i]
        o = [p[0], p[1], p[2] + zv]
        out.append((o, list(d), opl))
        if i < len(surfaces) - 1:
            zv = zv_next
    return out


# ----------------------------------------------------------------------------- the cases
def unit(v):
    v = np.asarray(v, float)
    return (v / np.sqrt(np.sum(v * v))).tolist()


def ray_at(y, angle_deg, z=-1.0):
    a = math.radians(angle_deg)
    return dict(o=[0.0, float(y), float(z)], d=unit([0.0, math.sin(a), math.cos(a)]))


def skew(x, y, ax_deg, ay_deg, z=-1.0):
    return dict(o=[float(x), float(y), float(z)],
                d=unit([math.tan(math.radians(ax_deg)), math.tan(math.radians(ay_deg)), 1.0]))


def std(c, k=0.0):
    return dict(c=float(c), k=float(k))


def asph(c, k, coeffs):
    return dict(c=float(c), k=float(k), coeffs=[float(a) for a in coeffs])


def critical_rays(n, y0=0.0):
    """Rays in glass n meeting a flat exit face just below the critical angle."""
    crit = math.asin(1.0 / n)
    rays = []
    for below in (1e-3, 1e-6, 1e-9):
        a = crit - below
        rays.append(dict(o=[0.0, y0, -1.0], d=unit([0.0, math.sin(a), math.cos(a)])))
    return rays


def cases():
    """(name, what it stresses, lens scale in mm, the system, the rays)."""
    out = []

    def add(name, note, scale, surfaces, thickness, index, rays, mirrors=()):
        out.append(dict(name=name, note=note, scale=scale, surfaces=surfaces,
                        thickness=[float(t) for t in thickness], index=[float(n) for n in index],
                        mirrors=list(mirrors), rays=rays))

    for c in (1e-9, -1e-11, 1e-14):
        add(f"near_flat_{c:g}", f"a biconvex element with |c| = {abs(c):g} /mm (R = {1/c:g} mm)"
            " at heights to 10 mm", 10.0, [std(c), std(-c)], [5.0, 20.0], [1.0, 1.5, 1.0],
            [ray_at(y, a) for y in (0.0, 3.0, 10.0) for a in (0.0, 5.0, -20.0)]
            + [skew(7.0, -4.0, 10.0, 12.0)])
    add("radius_1e6", "R = 1e6 mm and -1e6 mm, rays at heights to 300 mm", 300.0,
        [std(1e-6), std(-1e-6)], [10.0, 500.0], [1.0, 1.5, 1.0],
        [ray_at(y, a) for y in (1.0, 100.0, 300.0) for a in (0.0, 3.0)])
    for frac in (0.999, 1 - 1e-6):
        add(f"hemisphere_rim_{frac:g}", "a ball lens R = 5 mm, collimated rays at "
            f"{frac:g}·R (near tangency) and a skew ray near the rim", 5.0,
            [std(0.2), std(-0.2)], [10.0, 10.0], [1.0, 1.5, 1.0],
            [ray_at(5.0 * frac, 0.0, z=-20.0), ray_at(-5.0 * frac * 0.7, 0.0, z=-20.0),
             skew(5.0 * frac * 0.6, 5.0 * frac * 0.8, 0.0, 0.0, z=-20.0)])
    add("paraboloid_2m", "an F/2 paraboloid mirror (R = -8000 mm, k = -1) with heights to "
        "1000 mm, to its focus at -4000 mm", 1000.0, [std(-1 / 8000.0, -1.0)], [-4000.0],
        [1.0, 1.0], [ray_at(y, a, z=-100.0) for y in (0.0, 10.0, 500.0, 999.0)
                     for a in (0.0, 0.1)], mirrors=[0])
    add("paraboloid_fast", "an F/0.25 paraboloid mirror (R = -100 mm, k = -1) with heights to "
        "100 mm", 100.0, [std(-1 / 100.0, -1.0)], [-50.0], [1.0, 1.0],
        [ray_at(y, 0.0, z=-10.0) for y in (1.0, 50.0, 99.0)], mirrors=[0])
    add("steep_asphere", "c = 0.2, k = -0.5 with a_2 … a_6 = 1e-3 … 1e-7 (sag to several mm "
        "at r = 4 mm)", 5.0, [asph(0.2, -0.5, [0.0, 1e-3, -2e-4, 3e-5, -1e-6, 1e-7]), std(-0.05)],
        [4.0, 15.0], [1.0, 1.6, 1.0],
        [ray_at(y, a, z=-2.0) for y in (0.5, 2.0, 3.5, 4.2) for a in (0.0, 8.0)])
    add("high_order_asphere", "a_1 … a_8 up to r^16 with large high-order terms on a flat "
        "base", 3.0, [asph(0.0, 0.0, [0.05, 2e-3, -1e-4, 1e-5, 3e-6, -4e-7, 5e-8, 2e-9]),
                      std(0.0)], [3.0, 10.0], [1.0, 1.5, 1.0],
        [ray_at(y, 0.0) for y in (0.3, 1.5, 2.5, 3.0)])
    add("grazing", "rays at 89.9° … 89.999° to the normal of a plane into glass and a "
        "sphere at grazing incidence", 10.0, [std(0.0), std(-0.1)], [1.0, 20.0],
        [1.0, 1.5, 1.0],
        [dict(o=[0.0, -0.01, -1e-5], d=unit([0.0, math.sin(math.radians(a)),
                                                math.cos(math.radians(a))]))
         for a in (89.9, 89.99, 89.999)])
    add("sphere_grazing", "collimated rays meeting a sphere R = 10 mm at 85° … 89.9° "
        "incidence (near its equator)", 10.0, [std(0.1), std(0.0)], [20.0, 5.0],
        [1.0, 1.2, 1.0],
        [ray_at(10.0 * math.sin(math.radians(a)), 0.0, z=-5.0) for a in (85.0, 89.0, 89.9)])
    add("critical_angle", "glass n = 1.5 to air at a flat face just below the critical angle "
        "(1e-3, 1e-6, 1e-9 rad)", 10.0, [std(0.0), std(0.0)], [5.0, 5.0], [1.5, 1.5, 1.0],
        critical_rays(1.5))
    add("long_propagation", "a 1e5 mm gap between a weak window and a concave mirror R = 2e5 "
        "mm, then back 1e5 mm", 1e5, [std(1e-7), std(0.0), std(-1 / 2e5)],
        [2.0, 1e5, -1e5], [1.0, 1.5, 1.0, 1.0],
        [ray_at(y, a) for y in (10.0, 300.0) for a in (0.0, 0.05)] + [skew(100.0, -50.0,
                                                                             0.1, 0.2)],
        mirrors=[2])
    add("long_refracting", "a 1e5 mm gap then a strong singlet (R = 50 mm)", 1e5,
        [std(0.0), std(0.02), std(-0.02)], [1e5, 5.0, 40.0], [1.0, 1.0, 1.6, 1.0],
        [ray_at(y, a) for y in (0.0, 5.0) for a in (0.0, 0.002)])
    add("microlens", "a 0.01 mm ball micro-lens (R = 5 µm) with an r^4 term", 0.005,
        [asph(200.0, 0.0, [0.0, 1e4]), std(-200.0)], [0.01, 0.02], [1.0, 1.5, 1.0],
        [ray_at(y, a, z=-0.01) for y in (0.0, 0.001, 0.003, 0.0045) for a in (0.0, 5.0)])
    add("near_perfect_opd", "an f = 1e4 mm paraboloid (R = -2e4 mm) at its focus: the OPL of "
        "every ray agrees to rounding (OPD of a perfect mirror)", 1e4,
        [std(-1 / 2e4, -1.0)], [-1e4], [1.0, 1.0],
        [ray_at(y, 0.0, z=-1.0) for y in (0.0, 1.0, 50.0, 200.0, 400.0)], mirrors=[0])
    return out


# --------------------------------------------------------------------------- the writer
def s(x):
    return mp.nstr(x, DIGITS, min_fixed=-mp.inf, max_fixed=mp.inf) if x != 0 else "0"


def f32(v):
    return float(np.float32(v))


def as_f32(case):
    """The case with every input rounded to float32 (c, k, coefficients, gaps, indices,
    origins, directions)."""
    c = json.loads(json.dumps(case))
    for srf in c["surfaces"]:
        for key in ("c", "k"):
            srf[key] = f32(srf[key])
        if "coeffs" in srf:
            srf["coeffs"] = [f32(a) for a in srf["coeffs"]]
    c["thickness"] = [f32(t) for t in c["thickness"]]
    c["index"] = [f32(n) for n in c["index"]]
    for r in c["rays"]:
        r["o"] = [f32(v) for v in r["o"]]
        r["d"] = [f32(v) for v in r["d"]]
    return c


def perturbed(case, r, u, pattern):
    """The case and ray with every input number x taken as x·(1 ± u) (signs from a fixed
    pseudo-random ``pattern``): u is the dtype's unit roundoff."""
    rng = np.random.default_rng(pattern)

    def bump(x):
        return mp.mpf(x) * (1 + int(rng.choice([-1, 1])) * u)

    c = dict(case, surfaces=[dict(c=bump(q["c"]), k=bump(q["k"]),
                                  coeffs=[bump(a) for a in q.get("coeffs", [])])
                             for q in case["surfaces"]],
             thickness=[bump(t) for t in case["thickness"]], index=[bump(n) for n in
                                                                   case["index"]])
    return c, [bump(v) for v in r["o"]], [bump(v) for v in r["d"]]


def floor(case, r, path, u):
    """The conditioning floor of each entry of ``path``: the largest change of the intercept
    (mm), the direction and the optical path (mm) when every input moves by a relative u (two
    sign patterns): what a backward-stable trace in that precision may differ by."""
    out = [dict(pos=0.0, dir=0.0, opl=0.0) if e is not None else None for e in path]
    for pattern in (1, 2):
        c, o, d = perturbed(case, r, u, pattern)
        other = trace(c, o, d, mp.mpf)
        for e, f, fl in zip(path, other, out, strict=True):
            if e is None or f is None or fl is None:
                continue
            fl["pos"] = max(fl["pos"], float(max(abs(a - b) for a, b in zip(e[0], f[0],
                                                                            strict=True))))
            fl["dir"] = max(fl["dir"], float(max(abs(a - b) for a, b in zip(e[1], f[1],
                                                                            strict=True))))
            fl["opl"] = max(fl["opl"], float(abs(e[2] - f[2])))
    return out


def reference(case, u):
    rows = []
    for r in case["rays"]:
        path = trace(case, r["o"], r["d"], mp.mpf)
        fl = floor(case, r, path, u)
        rows.append([None if e is None else dict(p=[s(v) for v in e[0]], d=[s(v) for v in e[1]],
                                                 opl=s(e[2]), floor=f)
                     for e, f in zip(path, fl, strict=True)])
    return rows


def main(argv):
    os.makedirs(OUT, exist_ok=True)
    doc = []
    for case in cases():
        entry = dict(case)
        entry["reference"] = {"float64": reference(case, mp.mpf(2) ** -53)}
        c32 = as_f32(case)
        entry["inputs_float32"] = c32
        entry["reference"]["float32"] = reference(c32, mp.mpf(2) ** -24)
        lost = sum(row[-1] is None for row in entry["reference"]["float64"])
        print(f"{case['name']:24s} rays {len(case['rays']):2d}  lost {lost}", file=sys.stderr)
        doc.append(entry)
    path = os.path.join(OUT, "reference.json")
    with open(path, "w") as fh:
        json.dump(dict(generator="tools/stress43e_reference.py (mpmath "
                       f"{mp.__version__}, {mp.mp.dps} digits)", cases=doc), fh, indent=1)
    print(path, file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv)
