"""Round 36e: gradients of the public analyses against central differences (float64).

For each (function, lens, parameter) the reverse-mode derivative of a scalar output is compared
with central differences at three steps (h0, h0/10, h0/100; the best of the three is reported,
with the spread between steps as a measure of the differences' own noise), and forward mode
(``jax.jvp``) with reverse mode. A value or derivative that is NaN or inf, or a function that
raises under ``grad``, is reported as such.

    PYTHONPATH=. python tools/grad36e_probe.py [substring ...]

Prints one line per case: ``status function lens parameter value grad fd rel jvp_rel``.
Status: ok / WRONG / NAN / ERROR (the exception's first line).
"""

from __future__ import annotations

import dataclasses
import sys
import traceback

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.analysis import encircled, spots, third_order, wavefront_error  # noqa: E402
from jaxlens.imaging import aiming, distortion, psf, radiometry  # noqa: E402
from jaxlens.imaging import otf as otf_mod  # noqa: E402
from jaxlens.optics import paraxial  # noqa: E402

REL = 1e-6  # the bar for a smooth function


# --------------------------------------------------------------------------------- lenses
def cooke():
    return zoo.cooke_triplet(clip=False)


def gauss():
    return zoo.double_gauss(clip=False)


def hybrid():
    lens = jl.load("jaxlens/data/lenses/hybrid_singlet.json")
    s = tuple(
        dataclasses.replace(x, semi_diameter=jnp.inf) if hasattr(x, "semi_diameter") else x
        for x in lens.surfaces
    )
    return dataclasses.replace(lens, surfaces=s)


def conic():
    """A conic / even-asphere triplet with model glasses (nd, Vd leaves), a flat surface
    (c = 0), a paraboloid (k = -1) and the stop on a surface of its own."""
    g1, g2 = jl.ModelGlass(1.62, 60.3), jl.ModelGlass(1.62, 36.4)
    s = (
        jl.EvenAsphere(1 / 22.0, -0.3, jnp.array([0.0, 2e-6, -1e-9])),
        jl.Conic(0.0, 0.0),
        jl.Stop(),
        jl.Conic(-1 / 22.2, -1.0),
        jl.Sphere(1 / 20.3),
        jl.Conic(1 / 79.7, -2.0),
        jl.Conic(-1 / 18.4, 1.5),
    )
    t = jnp.array([3.26, 3.0, 3.01, 1.0, 4.75, 2.95, 42.2])
    mats = (g1, jl.Air(), jl.Air(), g2, jl.Air(), g1, jl.Air())
    return jl.Lens(
        s,
        t,
        mats,
        stop=2,
        epd=10.0,
        fields=jnp.array([0.0, 14.0]),
        wavelengths=jnp.array([0.4861327, 0.5875618, 0.6562725]),
        primary=1,
    )


def finite(lens_fn, d):
    def make():
        return dataclasses.replace(lens_fn(), object_distance=d)

    make.__name__ = lens_fn.__name__ + f"@{d:g}"
    return make


LENSES = {
    "cooke": cooke,
    "gauss": gauss,
    "hybrid": hybrid,
    "conic": conic,
    "cooke@500": finite(cooke, 500.0),
}


# ----------------------------------------------------------------------------- parameters
def params_for(lens):
    """(name, getter on (lens, extra), index or None, base step): the first surface's
    curvature, a flat surface's (c = 0), the surface after the stop; a conic constant (k = -1
    where there is one); an asphere and an odd coefficient; the stop's and the last thickness;
    a model glass's nd and Vd; the EPD; the object distance; the field angle; the wavelength."""
    out = []
    surfs = lens.surfaces
    cs = [0] + [i for i, s in enumerate(surfs) if hasattr(s, "c") and float(s.c) == 0.0][:1]
    cs += [min(lens.stop + 1, len(surfs) - 1)]
    for i in dict.fromkeys(cs):
        if hasattr(surfs[i], "c"):
            out.append((f"c{i}", lambda P, i=i: P[0].surfaces[i].c, None, 1e-5))
    ks = [i for i, s in enumerate(surfs) if hasattr(s, "k") and float(s.k) == -1.0][:1]
    ks += [i for i, s in enumerate(surfs) if hasattr(s, "k") and float(s.k) not in (0.0, -1.0)][:1]
    ks = ks or [0]
    for i in ks:
        out.append((f"k{i}", lambda P, i=i: P[0].surfaces[i].k, None, 1e-3))
    for i, s in enumerate(surfs):
        if hasattr(s, "coeffs") and s.coeffs.shape[0] > 1:
            out.append((f"a{i}_1", lambda P, i=i: P[0].surfaces[i].coeffs, 1, 1e-8))
        if hasattr(s, "odd_x") and s.odd_x.shape[0]:
            out.append((f"ox{i}", lambda P, i=i: P[0].surfaces[i].odd_x, 0, 1e-7))
    n = lens.thickness.shape[0]
    for j in dict.fromkeys((lens.stop, n - 1)):
        out.append((f"t{j}", lambda P, j=j: P[0].thickness, j, 1e-4))
    for i, m in enumerate(lens.materials):
        if isinstance(m, jl.ModelGlass):
            out.append((f"nd{i}", lambda P, i=i: P[0].materials[i].nd, None, 1e-5))
            out.append((f"vd{i}", lambda P, i=i: P[0].materials[i].vd, None, 1e-3))
            break
    out.append(("epd", lambda P: P[0].epd, None, 1e-4))
    if lens.object_distance is not None:
        out.append(("objd", lambda P: P[0].object_distance, None, 1e-2))
    out.append(("field", lambda P: P[1]["field"], None, 1e-4))
    out.append(("wl", lambda P: P[1]["wl"], None, 1e-5))
    return out


def _set(P, get, j, value):
    value = jnp.asarray(value, jnp.float64)
    return eqx.tree_at(get, P, value if j is None else get(P).at[j].set(value))


def _leaf(P, get, j):
    x = get(P)
    return x if j is None else x[j]


# ------------------------------------------------------------------------------ functions
def _f2(field):
    return jnp.stack([jnp.zeros_like(field), field])


FUNCS = {
    # paraxial
    "efl": lambda L, e: paraxial.efl(L, e["wl"]),
    "bfl": lambda L, e: paraxial.bfl(L, e["wl"]),
    "image_height": lambda L, e: paraxial.image_height(L, e["field"], e["wl"]),
    "entrance_pupil_z": lambda L, e: paraxial.entrance_pupil_z(L, e["wl"]),
    "pd.exit_pupil_z": lambda L, e: paraxial.paraxial_data(L, e["wl"]).exit_pupil_z,
    "pd.fnum": lambda L, e: paraxial.paraxial_data(L, e["wl"]).fnum,
    "pd.working_fnum": lambda L, e: paraxial.paraxial_data(L, e["wl"]).working_fnum,
    "pd.exit_pupil_d": lambda L, e: paraxial.paraxial_data(L, e["wl"]).exit_pupil_diameter,
    "pd.stop_sd": lambda L, e: paraxial.paraxial_data(L, e["wl"]).stop_semi_diameter,
    "pd.paraxial_image_z": lambda L, e: paraxial.paraxial_data(L, e["wl"]).paraxial_image_z,
    "ep_magnification": lambda L, e: paraxial.entrance_pupil_magnification(L, e["wl"]),
    "paraxial_chief_ray": lambda L, e: jnp.sum(
        jnp.stack(paraxial.paraxial_chief_ray(L, e["field"], e["wl"])[:2]) ** 2
    ),
    # analysis
    "rms_spot": lambda L, e: jl.analysis.rms_spot(
        eqx.tree_at(lambda x: x.fields, L, jnp.stack([e["field"], L.fields[-1]])),
        wavelengths=e["wl"][None],
    ).polychromatic.sum(),
    "rms_spot@0": lambda L, e: jl.analysis.rms_spot(
        eqx.tree_at(lambda x: x.fields, L, e["field"][None] * 0.0), wavelengths=e["wl"][None]
    ).polychromatic.sum(),
    "chief_ray.y": lambda L, e: jl.analysis.chief_ray(L, e["field"], e["wl"]).origin[..., 1],
    "distortion": lambda L, e: jl.analysis.distortion(
        L, jnp.stack([e["field"], L.fields[-1]]), e["wl"]
    ).percent_ftan[-1],
    "distortion@0": lambda L, e: jl.analysis.distortion(
        L, jnp.stack([e["field"] * 0.0, L.fields[-1]]), e["wl"]
    ).percent_ftan.sum(),
    "ray_fan": lambda L, e: jnp.sum(
        jl.analysis.ray_fan(L, e["field"], e["wl"][None], n=7).tangential ** 2
    ),
    "field_curvature": lambda L, e: jnp.sum(
        jl.analysis.field_curvature(
            L, jnp.stack([e["field"] * 0.0, e["field"]]), e["wl"][None]
        ).tangential
        ** 2
    ),
    "seidel.W040": lambda L, e: third_order.seidel(
        L, field=e["field"], wavelength=e["wl"]
    ).wavefront()[0],
    "seidel.sum": lambda L, e: jnp.sum(
        third_order.seidel(L, field=e["field"], wavelength=e["wl"]).wavefront() ** 2
    ),
    "opd": lambda L, e: jnp.sum(
        wavefront_error.opd(
            L, e["field"], jnp.array([[0.0, 0.7], [0.5, -0.3], [0.0, 0.0]]), wavelength=e["wl"]
        )
        ** 2
    ),
    "wavefront.rms": lambda L, e: (
        wavefront_error.wavefront(L, e["field"], wavelength=e["wl"], grid=16).rms
    ),
    "wavefront.rms@0": lambda L, e: (
        wavefront_error.wavefront(L, e["field"] * 0.0, wavelength=e["wl"], grid=16).rms
    ),
    "wavefront.strehl": lambda L, e: (
        wavefront_error.wavefront(L, e["field"], wavelength=e["wl"], grid=16).strehl
    ),
    "opd_fan": lambda L, e: jnp.sum(
        wavefront_error.opd_fan(L, e["field"], e["wl"][None], n=7).tangential ** 2
    ),
    "encircled_energy": lambda L, e: encircled.encircled_energy(
        L, e["field"], jnp.array([0.01]), wavelength=e["wl"]
    ).energy.sum(),
    "radius_for_fraction": lambda L, e: encircled.radius_for_fraction(
        L, e["field"], 0.8, wavelength=e["wl"]
    ),
    "clear_semi_diameters": lambda L, e: jnp.sum(
        spots.clear_semi_diameters(L, jnp.stack([e["field"] * 0.0, e["field"]]), n_rim=16)
    ),
    # imaging
    "stop_chief_ray": lambda L, e: aiming.stop_chief_ray(
        L, _f2(e["field"]), wavelength=e["wl"]
    ).origin[..., 1],
    "image_scale": lambda L, e: aiming.image_scale(L, e["wl"]),
    "field_to_ideal": lambda L, e: aiming.field_to_ideal(L, _f2(e["field"]), e["wl"])[1],
    "psf": lambda L, e: jnp.sum(
        psf.psf(L, e["field"], wavelength=e["wl"], kernel_size=15, key=jax.random.PRNGKey(0)) ** 2
    ),
    "mtf": lambda L, e: jnp.sum(
        psf.mtf(L, e["field"], wavelengths=e["wl"][None], kernel_size=16)[1]
    ),
    "diffraction_mtf": lambda L, e: otf_mod.diffraction_mtf(
        jnp.array([10.0, 40.0]), e["wl"] * 1e-3, paraxial.paraxial_data(L, e["wl"]).fnum
    ).sum(),
    "relative_illumination": lambda L, e: radiometry.relative_illumination(
        L, jnp.stack([e["field"] * 0.0, e["field"]]), wavelength=e["wl"], pupil=32
    ).ri[-1],
    "distortion_map": lambda L, e: jnp.sum(distortion.distortion_map(L, grid=(3, 3)).real ** 2),
}


def _field_extra(lens):
    f = float(lens.fields[-1]) * 0.6 if float(lens.fields[-1]) > 0 else 0.5
    # 0.55 µm: between table nodes (a Tabulated glass is piecewise linear in 1/λ², with a
    # kink at each node, as its docstring says)
    return {"field": jnp.asarray(f), "wl": jnp.asarray(0.55)}


def probe(fname, lname):
    fn = FUNCS[fname]
    lens = LENSES[lname]()
    P = (lens, _field_extra(lens))
    dyn, static = eqx.partition(P, eqx.is_inexact_array)

    def f(d):
        L, e = eqx.combine(d, static)
        return jnp.asarray(fn(L, e), dtype=jnp.float64).reshape(())

    fj = jax.jit(f)
    jvp = jax.jit(lambda d, t: jax.jvp(f, (d,), (t,))[1])
    vg = jax.jit(jax.value_and_grad(f))
    rows = []
    try:
        v, g = vg(dyn)
    except Exception as ex:  # noqa: BLE001
        msg = str(ex).strip().splitlines()[0][:110] if str(ex).strip() else type(ex).__name__
        return [f"ERROR {fname:22s} {lname:9s} {'*':8s} {type(ex).__name__}: {msg}"]
    v = float(v)
    for name, get, j, h0 in params_for(lens):
        x0 = float(_leaf(P, get, j))
        gval = float(_leaf((lambda d: eqx.combine(d, static))(g), get, j))
        fds = []
        for h in (h0, h0 / 10, h0 / 100):
            hp = fj(eqx.partition(_set(P, get, j, x0 + h), eqx.is_inexact_array)[0])
            hm = fj(eqx.partition(_set(P, get, j, x0 - h), eqx.is_inexact_array)[0])
            fds.append((float(hp) - float(hm)) / (2 * h))
        fds = np.array(fds)
        scale = max(abs(gval), np.max(np.abs(fds)), 1e-12 * max(1.0, abs(v)) / h0)
        errs = np.abs(fds - gval) / scale
        rel = float(np.nanmin(errs)) if np.isfinite(errs).any() else float("nan")
        # forward mode
        tan = jax.tree_util.tree_map(jnp.zeros_like, dyn)
        Pt = eqx.combine(tan, static)
        Pt = eqx.tree_at(get, Pt, get(Pt) + 1.0 if j is None else get(Pt).at[j].set(1.0))
        tdyn = eqx.partition(Pt, eqx.is_inexact_array)[0]
        try:
            jv = float(jvp(dyn, tdyn))
            jrel = abs(jv - gval) / max(abs(gval), 1e-300) if gval != 0 else abs(jv)
            jtxt = f"{jrel:.1e}"
        except Exception as ex:  # noqa: BLE001
            jv, jtxt = None, "fwd-err:" + type(ex).__name__
        if not (np.isfinite(v) and np.isfinite(gval)):
            status = "NAN"
        elif rel <= REL or not np.isfinite(rel):
            status = "ok" if np.isfinite(rel) else "FDNAN"
        else:
            status = "WRONG?" if rel < 1e-3 else "WRONG"
        rows.append(
            f"{status:6s} {fname:22s} {lname:9s} {name:8s} v={v:+.6e} g={gval:+.8e} "
            f"fd={fds[np.nanargmin(errs)] if np.isfinite(errs).any() else fds[0]:+.8e} "
            f"rel={rel:.1e} spread={np.ptp(fds) / max(abs(fds).max(), 1e-300):.0e} "
            f"jvp={jtxt}"
        )
    return rows


def main(argv):
    """Arguments: function names (exact; default all), and ``--lenses a,b`` (default all)."""
    args = argv[1:]
    lenses = list(LENSES)
    if "--lenses" in args:
        i = args.index("--lenses")
        lenses = args[i + 1].split(",")
        del args[i : i + 2]
    for fname in FUNCS:
        if args and fname not in args:
            continue
        for lname in lenses:
            try:
                rows = probe(fname, lname)
            except Exception:  # noqa: BLE001
                rows = [
                    f"ERROR {fname:22s} {lname:9s} probe: "
                    + traceback.format_exc().strip().splitlines()[-1][:300]
                ]
            for r in rows:
                print(r, flush=True)


if __name__ == "__main__":
    main(sys.argv)
