# ruff: noqa: E501, B023
"""Round-15 bad-input probes: throw malformed input at the public API, the readers and the
CLIs, and print what each does (OK = returned without error: look for silent answers).

Run: PYTHONPATH=$PWD python tools/audit15_probe.py [filter]
"""

import sys
import traceback

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

PROBES = []


def probe(fn):
    PROBES.append(fn)
    return fn


def show(name, f):
    try:
        r = f()
    except Exception as e:  # noqa: BLE001
        msg = str(e).split("\n")[0][:220]
        print(f"ERR  {name}: {type(e).__name__}: {msg}")
        return
    try:
        s = np.array2string(np.asarray(r), precision=6)[:120] if not isinstance(r, (str, dict, list, tuple)) else repr(r)[:120]
    except Exception:  # noqa: BLE001
        s = type(r).__name__
    print(f"OK   {name}: {s}")


cooke = zoo.cooke_triplet()


@probe
def paraxial():
    for wl in [np.nan, -1.0, 0.0, 10.0, 1 + 0j, True, [], [0.5, 0.6], jnp.array([[0.5]])]:
        show(f"efl wl={wl!r}", lambda: jl.efl(cooke, wl))
        show(f"bfl wl={wl!r}", lambda: jl.bfl(cooke, wl))
    show("paraxial_data wl=0.1", lambda: jl.paraxial_data(cooke, 0.1).efl)
    show("image_height field=95", lambda: jl.paraxial.image_height(cooke, 95.0))
    show("image_height field=nan", lambda: jl.paraxial.image_height(cooke, np.nan))
    show("image_height field=[[1,2,3]]", lambda: jl.paraxial.image_height(cooke, [[1, 2, 3]]))
    show("system_matrix start=5 end=2", lambda: jl.paraxial.system_matrix(cooke, None, 5, 2))
    show("system_matrix start=-1", lambda: jl.paraxial.system_matrix(cooke, None, -1))
    show("system_matrix end=99", lambda: jl.paraxial.system_matrix(cooke, None, 0, 99))
    show("system_matrix start=1.5", lambda: jl.paraxial.system_matrix(cooke, None, 1.5))
    show("jit efl wl=nan", lambda: jax.jit(lambda w: jl.efl(cooke, w))(jnp.nan))
    show("jit efl wl=10", lambda: jax.jit(lambda w: jl.efl(cooke, w))(10.0))
    show("grad efl wl=10", lambda: jax.grad(lambda w: jl.efl(cooke, w))(10.0))
    show("vmap efl wl=[0.5,10]", lambda: jax.vmap(lambda w: jl.efl(cooke, w))(jnp.array([0.5, 10.0])))


@probe
def lens_ctor():
    s = cooke
    import equinox as eqx
    show("Lens thickness nan", lambda: eqx.tree_at(lambda l: l.thickness, s, s.thickness.at[0].set(jnp.nan)))
    show("Lens stop=99", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, stop=99))
    show("Lens stop=-1", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, stop=-1))
    show("Lens fields 95", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, fields=(0, 95)))
    show("Lens epd 0", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, epd=0))
    show("Lens epd complex", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, epd=1j))
    show("Lens wavelengths 2D", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, wavelengths=[[0.5]]))
    show("Lens thickness 2D", lambda: jl.Lens(surfaces=s.surfaces, thickness=jnp.stack([s.thickness, s.thickness]), materials=s.materials))
    show("Lens object_distance -5", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, object_distance=-5))
    show("Lens object_distance 0", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, object_distance=0))
    show("Lens name 5", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, name=5))
    show("Lens primary=True", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, primary=True))
    show("Lens sensor=5", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, sensor=5))
    show("Lens mirrors wrong sign", lambda: jl.Lens(surfaces=s.surfaces, thickness=s.thickness, materials=s.materials, mirrors=(5,)))
    show("Sensor pixel 0", lambda: jl.Sensor((10, 10), 0.0))
    show("Sensor pixel nan", lambda: jl.Sensor((10, 10), np.nan))
    show("Sensor res (10.5,10)", lambda: jl.Sensor((10.5, 10), 0.01))


@probe
def surfaces():
    for cls in [jl.Sphere, jl.Standard, jl.Conic, jl.EvenAsphere, jl.OddAsphere, jl.Plane, jl.Stop]:
        for kw in [dict(c=np.nan), dict(c=1j), dict(semi_diameter=-1.0), dict(semi_diameter=np.nan),
                   dict(semi_diameter=0.0), dict(k=np.inf), dict(c=True), dict(c=[0.1, 0.2]),
                   dict(semi_diameter="5"), dict(ai=[np.nan]), dict(coefficients=[np.nan])]:
            show(f"{cls.__name__}({kw})", lambda: cls(**kw))


@probe
def materials():
    show("get_material('N-BK7x')", lambda: jl.get_material("N-BK7x"))
    show("get_material('')", lambda: jl.get_material(""))
    show("get_material(5)", lambda: jl.get_material(5))
    show("get_material(None)", lambda: jl.get_material(None))
    show("get_material(' N-BK7 ')", lambda: jl.get_material(" N-BK7 ").name)
    show("get_material('n-bk7')", lambda: jl.get_material("n-bk7").name)
    m = jl.get_material("N-BK7")
    show("N-BK7.index(5.0)", lambda: m.index(5.0))
    show("N-BK7.index(-1)", lambda: m.index(-1.0))
    show("N-BK7.index(nan)", lambda: m.index(np.nan))
    show("N-BK7.index(0)", lambda: m.index(0.0))
    show("N-BK7.index('0.5')", lambda: m.index("0.5"))
    show("N-BK7.index(1j)", lambda: m.index(0.5 + 1j))
    show("ModelGlass(nd=nan)", lambda: jl.ModelGlass(nd=np.nan, vd=60.0))
    show("ModelGlass(nd=0.5)", lambda: jl.ModelGlass(nd=0.5, vd=60.0))
    show("ModelGlass(vd=0)", lambda: jl.ModelGlass(nd=1.5, vd=0.0))
    show("ModelGlass(vd=-30)", lambda: jl.ModelGlass(nd=1.5, vd=-30.0))
    show("ModelGlass(vd=inf)", lambda: jl.ModelGlass(nd=1.5, vd=np.inf))
    show("ModelGlass(nd=True)", lambda: jl.ModelGlass(nd=True, vd=60.0))
    show("ModelGlass(nd=1.5).index(5)", lambda: jl.ModelGlass(nd=1.5, vd=60.0).index(5.0))
    show("Sellmeier(B=nan)", lambda: jl.Sellmeier(B=(np.nan, 0, 0), C=(0.1, 0.2, 0.3)))
    show("Sellmeier(B=(1,2),C=(1,2,3))", lambda: jl.Sellmeier(B=(1.0, 2.0), C=(0.1, 0.2, 0.3)))
    show("Sellmeier(B=1j)", lambda: jl.Sellmeier(B=(1j, 0, 0), C=(0.1, 0.2, 0.3)))
    show("Sellmeier(C neg)", lambda: jl.Sellmeier(B=(1.0, 0, 0), C=(-0.1, 0.2, 0.3)).index(0.5))
    show("Sellmeier at pole", lambda: jl.Sellmeier(B=(1.0, 0, 0), C=(0.25, 0.2, 0.3)).index(0.5))
    show("Tabulated unsorted", lambda: jl.Tabulated(wavelengths=(0.6, 0.5, 0.7), n=(1.5, 1.51, 1.49)))
    show("Tabulated dup", lambda: jl.Tabulated(wavelengths=(0.5, 0.5, 0.7), n=(1.5, 1.51, 1.49)))
    show("Tabulated len mismatch", lambda: jl.Tabulated(wavelengths=(0.5, 0.6, 0.7), n=(1.5, 1.51)))
    show("Tabulated n<1", lambda: jl.Tabulated(wavelengths=(0.5, 0.6), n=(0.5, 0.51)))
    show("Tabulated one point", lambda: jl.Tabulated(wavelengths=(0.5,), n=(1.5,)))
    show("Tabulated empty", lambda: jl.Tabulated(wavelengths=(), n=()))
    show("Tabulated.index(0.9)", lambda: jl.Tabulated(wavelengths=(0.5, 0.6), n=(1.5, 1.49)).index(0.9))
    show("Schott(nan)", lambda: jl.Schott(coefficients=(np.nan, 0, 0, 0, 0, 0)))
    show("glass_info('XX')", lambda: jl.glass_info("XX"))
    show("catalog_names('NOPE')", lambda: jl.catalog_names("NOPE"))
    show("register_catalog(5)", lambda: jl.register_catalog(5))
    show("register_catalog({'A': 5})", lambda: jl.register_catalog({"A": 5}))
    show("register_catalog({}, name)", lambda: jl.register_catalog({}))


@probe
def trace():
    import equinox as eqx
    show("field_rays grid kw", lambda: jl.sampling.field_rays(cooke, 0.0, jnp.zeros((1, 2)), 0.5876).origin)
    show("Rays(nan origin)", lambda: jl.Rays(origin=jnp.array([[np.nan, 0, 0]]), direction=jnp.array([[0, 0, 1.0]]), wavelength=0.5))
    show("Rays(shape mismatch)", lambda: jl.Rays(origin=jnp.zeros((3, 3)), direction=jnp.array([[0, 0, 1.0]] * 2), wavelength=0.5))
    show("Rays(origin 2 comps)", lambda: jl.Rays(origin=jnp.zeros((3, 2)), direction=jnp.zeros((3, 2)).at[:, 1].set(1), wavelength=0.5))
    show("Rays(wl=-1)", lambda: jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0, 0, 1.0]]), wavelength=-1.0))
    show("Rays(wl=600)", lambda: jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0, 0, 1.0]]), wavelength=600.0))
    show("Rays(wl=[0.5,0.6] for 3 rays)", lambda: jl.Rays(origin=jnp.zeros((3, 3)), direction=jnp.array([[0, 0, 1.0]] * 3), wavelength=jnp.array([0.5, 0.6])))
    show("Rays(empty)", lambda: jl.Rays(origin=jnp.zeros((0, 3)), direction=jnp.zeros((0, 3)), wavelength=0.5))
    rays = jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0, 0, 1.0]]), wavelength=0.5)
    show("trace(cooke, rays)", lambda: jl.trace(cooke, rays).origin)
    rays10 = jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0, 0, 1.0]]), wavelength=10.0)
    show("trace(cooke, rays wl=10)", lambda: jl.trace(cooke, rays10).origin)
    show("trace(5, rays)", lambda: jl.trace(5, rays))
    show("trace(cooke, 5)", lambda: jl.trace(cooke, 5))
    show("trace(cooke, rays, bad kw)", lambda: jl.trace(cooke, rays, foo=1))
    show("trace_path(cooke, rays wl=10)", lambda: jl.trace_path(cooke, rays10))
    show("jit trace wl=10", lambda: eqx.filter_jit(jl.trace)(cooke, rays10).origin)




# ------------------------------------------------------------------ readers
import os  # noqa: E402
import tempfile  # noqa: E402

from jaxlens.io import zmx as zmxmod  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COOKE = open(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx")).read()


def zl(text, name="t.zmx", **kw):
    lens = zmxmod.loads(text, name, **kw)
    return f"efl={float(jl.efl(lens)):.4f} n={lens.num_surfaces} stop={lens.stop} fields={np.asarray(lens.fields).tolist()} wl={np.asarray(lens.wavelengths).tolist()}"


def variants():
    t = COOKE
    yield "baseline", t
    yield "truncated mid SURF 3", t[: t.index("SURF 3") + 40]
    yield "truncated after SURF 4 header", t[: t.index("SURF 4") + 7]
    yield "truncated right after DISZ line of SURF 5 (no image)", t[: t.index("SURF 6")]
    yield "duplicate SURF 3", t.replace("SURF 4\n", "SURF 3\n", 1)
    yield "SURF numbers skip", t.replace("SURF 4\n", "SURF 9\n", 1)
    yield "SURF out of order", t.replace("SURF 4\n", "SURF 2\n", 1)
    yield "UNIT IN", t.replace("UNIT MM", "UNIT IN")
    yield "UNIT CM", t.replace("UNIT MM", "UNIT CM")
    yield "UNIT XX", t.replace("UNIT MM", "UNIT XX")
    yield "UNIT missing", t.replace("UNIT MM X W X CM MR CPMM\n", "")
    yield "CRLF", t.replace("\n", "\r\n")
    yield "CR only", t.replace("\n", "\r")
    yield "tabs", t.replace("  ", "\t")
    yield "BOM", "\ufeff" + t
    yield "two STOP", t.replace("SURF 2\n", "SURF 2\n  STOP\n", 1)
    yield "no STOP", t.replace("  STOP\n", "")
    yield "STOP on object", t.replace("SURF 0\n", "SURF 0\n  STOP\n", 1)
    yield "STOP on image", t.replace("SURF 7\n", "SURF 7\n  STOP\n", 1)
    yield "CURV nan", t.replace("CURV 4.5426484276303865E-002", "CURV nan")
    yield "CURV inf", t.replace("CURV 4.5426484276303865E-002", "CURV inf")
    yield "CURV 1e400", t.replace("CURV 4.5426484276303865E-002", "CURV 1e400")
    yield "CURV 0x10", t.replace("CURV 4.5426484276303865E-002", "CURV 0x10")
    yield "CURV 1_0", t.replace("CURV 4.5426484276303865E-002", "CURV 4_5e-2")
    yield "CURV ,", t.replace("CURV 4.5426484276303865E-002", "CURV 4,5e-2")
    yield "DISZ negative in glass", t.replace("DISZ 3.25896E+000", "DISZ -3.25896E+000")
    yield "DISZ nan", t.replace("DISZ 3.25896E+000", "DISZ NAN")
    yield "DISZ missing value", t.replace("DISZ 3.25896E+000", "DISZ")
    yield "DISZ INFINITY mid", t.replace("DISZ 3.25896E+000", "DISZ INFINITY")
    yield "ENPD 0", t.replace("ENPD 1.0E+001", "ENPD 0")
    yield "ENPD -10", t.replace("ENPD 1.0E+001", "ENPD -10")
    yield "ENPD nan", t.replace("ENPD 1.0E+001", "ENPD nan")
    yield "no ENPD", t.replace("ENPD 1.0E+001\n", "")
    yield "YFLN 95", t.replace("YFLN 0 1.4E+001 2.0E+001", "YFLN 0 1.4E+001 9.5E+001")
    yield "YFLN nan", t.replace("YFLN 0 1.4E+001 2.0E+001", "YFLN 0 nan 2.0E+001")
    yield "YFLN fewer than FTYP", t.replace("YFLN 0 1.4E+001 2.0E+001", "YFLN 0 1.4E+001")
    yield "FTYP count 0", t.replace("FTYP 0 0 3 3 0 0 0", "FTYP 0 0 0 3 0 0 0")
    yield "FTYP type 9", t.replace("FTYP 0 0 3 3 0 0 0", "FTYP 9 0 3 3 0 0 0")
    yield "FTYP count 2.5", t.replace("FTYP 0 0 3 3 0 0 0", "FTYP 0 0 2.5 3 0 0 0")
    yield "WAVM 600 nm", t.replace("WAVM 2 5.875618E-001 1", "WAVM 2 587.5618 1")
    yield "WAVM neg", t.replace("WAVM 2 5.875618E-001 1", "WAVM 2 -0.5 1")
    yield "WAVM 0 weight", t.replace("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 0")
    yield "WAVM nan weight", t.replace("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 nan")
    yield "WAVM neg weight", t.replace("WAVM 2 5.875618E-001 1", "WAVM 2 5.875618E-001 -1")
    yield "PWAV 0", t.replace("PWAV 2", "PWAV 0")
    yield "PWAV 4", t.replace("PWAV 2", "PWAV 4")
    yield "PWAV 1.5", t.replace("PWAV 2", "PWAV 1.5")
    yield "WAVM 5 without others", t.replace("WAVM 3 6.562725E-001 1", "WAVM 5 6.562725E-001 1")
    yield "WAVM 0", t.replace("WAVM 3 6.562725E-001 1", "WAVM 0 6.562725E-001 1")
    yield "GLAS unknown", t.replace("GLAS F2 ", "GLAS F2X ")
    yield "GLAS lowercase", t.replace("GLAS F2 ", "GLAS f2 ")
    yield "GCAT unknown", t.replace("GCAT SCHOTT", "GCAT NOPE")
    yield "GCAT empty", t.replace("GCAT SCHOTT", "GCAT")
    yield "GLAS MIRROR pos thickness", t.replace("GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0", "GLAS MIRROR")
    yield "DIAM negative", t.replace('DIAM 0 0 0 0 1 ""', 'DIAM -5 0 0 0 1 ""', 2)
    yield "DIAM nan", t.replace('DIAM 0 0 0 0 1 ""', 'DIAM nan 0 0 0 1 ""', 2)
    yield "CONI nan", t.replace("CONI 0", "CONI nan", 1)
    yield "TYPE unknown", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE FOOBAR")
    yield "EVENASPH PARM nan", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE EVENASPH\n  PARM 2 nan")
    yield "EVENASPH PARM 99", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE EVENASPH\n  PARM 99 1e-5")
    yield "EVENASPH PARM -1", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE EVENASPH\n  PARM -1 1e-5")
    yield "PARM on STANDARD", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE STANDARD\n  PARM 2 1e-5")
    yield "keyword unknown", t.replace("SURF 2\n  TYPE STANDARD", "SURF 2\n  FOOB 1\n  TYPE STANDARD")
    yield "line outside SURF after", t + "CURV 0.1\n"
    yield "empty", ""
    yield "only VERS", "VERS 1\n"
    yield "binary junk", "\x00\x01\x02SURF 0\n"
    yield "MODE NSC", t.replace("MODE SEQ", "MODE NSC")
    yield "MODE missing", t.replace("MODE SEQ\n", "")
    yield "NAME long/unicode", t.replace("NAME cooke_triplet", "NAME coöke ☃")
    yield "object DISZ 0", t.replace("DISZ INFINITY", "DISZ 0")
    yield "object DISZ -10", t.replace("DISZ INFINITY", "DISZ -10")
    yield "object DISZ 1e20", t.replace("DISZ INFINITY", "DISZ 1e20")
    yield "FNUM instead", t.replace("ENPD 1.0E+001", "FNUM 5 0")
    yield "FNUM 0", t.replace("ENPD 1.0E+001", "FNUM 0 0")
    yield "FNUM neg", t.replace("ENPD 1.0E+001", "FNUM -5 0")
    yield "OBNA", t.replace("ENPD 1.0E+001", "OBNA 0.1 0")
    yield "FLOA", t.replace("ENPD 1.0E+001", "FLOA")
    yield "surface with GLAS + MIRROR mix?", t.replace("GLAS N-SK16 0 0 1.62041 6.032E+001 0 0 0 0 0 0", "GLAS N-SK16 9 0 1.62041 6.032E+001 0 0 0 0 0 0", 1)
    yield "GLAS model", t.replace("GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0", "GLAS ___BLANK 1 0 1.62 36.37 0 0 0 0 0 0")
    yield "GLAS model nd nan", t.replace("GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0", "GLAS ___BLANK 1 0 nan 36.37 0 0 0 0 0 0")
    yield "GLAS model vd 0", t.replace("GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0", "GLAS ___BLANK 1 0 1.62 0 0 0 0 0 0 0")
    yield "GLAS model nd 0.5", t.replace("GLAS F2 0 0 1.62004 3.637E+001 0 0 0 0 0 0", "GLAS ___BLANK 1 0 0.5 36 0 0 0 0 0 0")
    yield "SURF 1 repeat header only", t.replace("SURF 2\n", "SURF 2\nSURF 2\n", 1)
    yield "SURF -1", t.replace("SURF 0\n", "SURF -1\n", 1)
    yield "SURF 1.5", t.replace("SURF 2\n", "SURF 1.5\n", 1)
    yield "SURF no number", t.replace("SURF 2\n", "SURF\n", 1)
    yield "SURF x", t.replace("SURF 2\n", "SURF x\n", 1)
    yield "XFLN 95 with YFLN", t.replace("XFLN 0 0 0", "XFLN 0 0 95")
    yield "FTYP height type", t.replace("FTYP 0 0 3 3 0 0 0", "FTYP 1 0 3 3 0 0 0")
    yield "FWGN 0 weights", t.replace("FWGN 1 1 1", "FWGN 0 0 0")
    yield "FWGN neg", t.replace("FWGN 1 1 1", "FWGN -1 1 1")
    yield "VDXN bad", t.replace("FWGN 1 1 1", "FWGN 1 1 1\nVCXN 0 1.5 0\nVCYN 0 1.5 0")
    yield "VCYN >1", t.replace("FWGN 1 1 1", "FWGN 1 1 1\nVCYN 0 1.0 0")
    yield "VDXN nan", t.replace("FWGN 1 1 1", "FWGN 1 1 1\nVDXN 0 nan 0")
    yield "VDXN too few", t.replace("FWGN 1 1 1", "FWGN 1 1 1\nVDXN 0 0.1")
    yield "DISZ overlap (negative air gap)", t.replace("DISZ 6.00755E+000", "DISZ -20")
    yield "CURV huge (radius < sd)", t.replace("CURV 4.5426484276303865E-002", "CURV 10")


@probe
def zmx_reader():
    for name, text in variants():
        show(f"zmx {name}", lambda: zl(text))
    for enc in ["utf-16", "utf-16-le", "latin-1", "cp1252", "utf-32"]:
        d = tempfile.mkdtemp()
        p = os.path.join(d, "t.zmx")
        with open(p, "wb") as fh:
            fh.write(COOKE.replace("NAME cooke_triplet", "NAME coöke").encode(enc))
        show(f"load_zmx {enc}", lambda: float(jl.efl(jl.load(p))))
    d = tempfile.mkdtemp()
    p = os.path.join(d, "t.zmx")
    with open(p, "wb") as fh:
        fh.write(b"\xff\xfe\x00\xd8" + COOKE.encode())
    show("load_zmx bad bytes", lambda: float(jl.efl(jl.load(p))))
    for p in [os.path.join(d, "none.zmx"), d, os.path.join(d, "x.txt"), 5, None]:
        show(f"load {p!r}", lambda: jl.load(p))


AGF_OK = """CC test
NM GA 2 517642.251 1.5168 64.17 0 1
CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653
LD 0.3 2.5
"""


def agf_try(text, name="X.agf", glass="GA"):
    d = tempfile.mkdtemp()
    p = os.path.join(d, name)
    with open(p, "w", newline="") as fh:
        fh.write(text)
    cat = jl.load_agf(p)
    m = cat[glass]
    return (f"n(0.5876)={float(m.index(0.5876)):.6f} nd={m.catalog_nd} vd={m.catalog_vd} "
            f"range={m.wavelength_range} formula={m.formula} keys={list(cat)}")


@probe
def agf_reader():
    t = AGF_OK
    for name, text in [
        ("baseline", t),
        ("formula 2.7", t.replace("NM GA 2 ", "NM GA 2.7 ")),
        ("formula 99", t.replace("NM GA 2 ", "NM GA 99 ")),
        ("formula 0", t.replace("NM GA 2 ", "NM GA 0 ")),
        ("formula -2", t.replace("NM GA 2 ", "NM GA -2 ")),
        ("nd nan", t.replace("1.5168 64.17", "nan 64.17")),
        ("nd 0.5", t.replace("1.5168 64.17", "0.5 64.17")),
        ("vd -5", t.replace("1.5168 64.17", "1.5168 -5")),
        ("nd disagree", t.replace("1.5168 64.17", "1.9 20")),
        ("CD nan", t.replace("CD 1.03961212", "CD nan")),
        ("CD 4_0", t.replace("CD 1.03961212", "CD 1_03961212")),
        ("CD empty", t.replace(t.splitlines()[2], "CD")),
        ("CD twice", t.replace("LD 0.3", "CD 2 0.1 0 0 0 0\nLD 0.3")),
        ("LD twice", t + "LD 0.4 1.0\n"),
        ("LD nan", t.replace("LD 0.3 2.5", "LD nan 2.5")),
        ("LD inf", t.replace("LD 0.3 2.5", "LD 0.3 inf")),
        ("LD 3 vals", t.replace("LD 0.3 2.5", "LD 0.3 2.5 3")),
        ("LD excludes d", t.replace("LD 0.3 2.5", "LD 0.7 2.5")),
        ("no LD", t.replace("LD 0.3 2.5\n", "")),
        ("CRLF", t.replace("\n", "\r\n")),
        ("tabs", t.replace(" ", "\t")),
        ("lowercase nm", t.replace("NM ", "nm ").replace("CD ", "cd ")),
        ("dup name", t + t.replace("1.5168 64.17", "1.6 40")),
        ("name with spaces?", t.replace("NM GA ", "NM \"G A\" ")),
        ("NM missing fields", t.replace("NM GA 2 517642.251 1.5168 64.17 0 1", "NM GA 2")),
        ("only CC", "CC nothing\n"),
        ("binary", "\x00\x01"),
        ("formula 1 (Schott) huge coeffs", t.replace("NM GA 2 ", "NM GA 1 ")),
        ("formula 12 ext2", t.replace("NM GA 2 ", "NM GA 12 ")),
        ("formula 13 ext3", t.replace("NM GA 2 ", "NM GA 13 ")),
        ("status x", t.replace("64.17 0 1", "64.17 0 x")),
    ]:
        show(f"agf {name}", lambda: agf_try(text))
    d = tempfile.mkdtemp()
    for enc in ["utf-16", "utf-8-sig", "latin-1"]:
        p = os.path.join(d, "Y.agf")
        with open(p, "wb") as fh:
            fh.write(t.replace("CC test", "CC tést").encode(enc))
        show(f"agf {enc}", lambda: list(jl.load_agf(p)))
    show("register_catalog(path nonexist)", lambda: jl.register_catalog(os.path.join(d, "Z.agf")))
    show("register_catalog(dir)", lambda: jl.register_catalog(d))


def json_try(d):
    import json

    from jaxlens.io import lensfile
    lens = lensfile.lens_from_dict(json.loads(json.dumps(d)), source="t.json")
    return f"efl={float(jl.efl(lens)):.4f} n={lens.num_surfaces} stop={lens.stop} fields={np.asarray(lens.fields).tolist()} wl={np.asarray(lens.wavelengths).tolist()} epd={float(lens.epd)}"


@probe
def json_reader():
    import copy
    import json
    base = json.load(open(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.json")))

    def mod(f):
        d = copy.deepcopy(base)
        f(d)
        return d

    cases = [
        ("baseline", lambda d: None),
        ("extra top key", lambda d: d.update(foo=1)),
        ("extra surface key", lambda d: d["surfaces"][1].update(foo=1)),
        ("missing format", lambda d: d.pop("format")),
        ("format v2", lambda d: d.update(format="jaxlens.lens/2")),
        ("missing surfaces", lambda d: d.pop("surfaces")),
        ("surfaces empty", lambda d: d.update(surfaces=[])),
        ("surfaces only object+image", lambda d: d.update(surfaces=[d["surfaces"][0], d["surfaces"][-1]])),
        ("radius string num", lambda d: d["surfaces"][1].update(radius="22.0")),
        ("radius bool", lambda d: d["surfaces"][1].update(radius=True)),
        ("radius 0", lambda d: d["surfaces"][1].update(radius=0)),
        ("radius -inf", lambda d: d["surfaces"][1].update(radius="-inf")),
        ("radius nan str", lambda d: d["surfaces"][1].update(radius="nan")),
        ("radius list", lambda d: d["surfaces"][1].update(radius=[1, 2])),
        ("radius null", lambda d: d["surfaces"][1].update(radius=None)),
        ("thickness null", lambda d: d["surfaces"][1].update(thickness=None)),
        ("thickness missing", lambda d: d["surfaces"][1].pop("thickness")),
        ("thickness str", lambda d: d["surfaces"][1].update(thickness="3")),
        ("material 5", lambda d: d["surfaces"][1].update(material=5)),
        ("material ''", lambda d: d["surfaces"][1].update(material="")),
        ("material unknown", lambda d: d["surfaces"][1].update(material="N-SK16X")),
        ("material dict", lambda d: d["surfaces"][1].update(material={"nd": 1.6, "vd": 60})),
        ("material dict nd str", lambda d: d["surfaces"][1].update(material={"nd": "1.6", "vd": 60})),
        ("material dict extra", lambda d: d["surfaces"][1].update(material={"nd": 1.6, "vd": 60, "foo": 1})),
        ("is_stop 'true'", lambda d: d["surfaces"][4].update(is_stop="true")),
        ("is_stop 1", lambda d: d["surfaces"][4].update(is_stop=1)),
        ("two stops", lambda d: d["surfaces"][2].update(is_stop=True)),
        ("no stop", lambda d: d["surfaces"][4].pop("is_stop")),
        ("is_stop on object", lambda d: d["surfaces"][0].update(is_stop=True)),
        ("type unknown", lambda d: d["surfaces"][1].update(type="foo")),
        ("type missing", lambda d: d["surfaces"][1].pop("type")),
        ("epd 0", lambda d: d.update(aperture={"epd": 0})),
        ("epd str", lambda d: d.update(aperture={"epd": "10"})),
        ("aperture extra", lambda d: d.update(aperture={"epd": 10, "foo": 1})),
        ("aperture empty", lambda d: d.update(aperture={})),
        ("aperture fnum", lambda d: d.update(aperture={"fnum": 5})),
        ("aperture list", lambda d: d.update(aperture=[10])),
        ("fields type unknown", lambda d: d.update(fields={"type": "height", "values": [0, 1]})),
        ("fields 95", lambda d: d.update(fields={"type": "angle_deg_y", "values": [0, 95]})),
        ("fields empty", lambda d: d.update(fields={"type": "angle_deg_y", "values": []})),
        ("fields extra key", lambda d: d.update(fields={"type": "angle_deg_y", "values": [0], "foo": 1})),
        ("fields as list", lambda d: d.update(fields=[0, 14])),
        ("fields values str", lambda d: d.update(fields={"type": "angle_deg_y", "values": "0 14"})),
        ("fields 2D", lambda d: d.update(fields={"type": "angle_deg_y", "values": [[0, 1], [2, 3]]})),
        ("wavelengths_nm um", lambda d: d.update(wavelengths_nm=[0.4861327, 0.5875618, 0.6562725], primary_wavelength_nm=0.5875618)),
        ("wavelengths_nm empty", lambda d: d.update(wavelengths_nm=[])),
        ("wavelengths_nm dup", lambda d: d.update(wavelengths_nm=[587.5618, 587.5618])),
        ("primary not in list", lambda d: d.update(primary_wavelength_nm=500)),
        ("primary missing", lambda d: d.pop("primary_wavelength_nm")),
        ("wavelengths_nm 2D", lambda d: d.update(wavelengths_nm=[[486.1327, 587.5618]])),
        ("wavelengths_nm scalar", lambda d: d.update(wavelengths_nm=587.5618)),
        ("name 5", lambda d: d.update(name=5)),
        ("description list", lambda d: d.update(description=["a"])),
        ("object thickness -5", lambda d: d["surfaces"][0].update(thickness=-5)),
        ("object thickness 0", lambda d: d["surfaces"][0].update(thickness=0)),
        ("image thickness 5", lambda d: d["surfaces"][-1].update(thickness=5)),
        ("image material glass", lambda d: d["surfaces"][-1].update(material="N-BK7")),
        ("image radius 50", lambda d: d["surfaces"][-1].update(radius=50)),
        ("object not first", lambda d: d["surfaces"].reverse()),
        ("conic str", lambda d: d["surfaces"][1].update(conic="0")),
        ("conic nan", lambda d: d["surfaces"][1].update(conic="nan")),
        ("semi_diameter -1", lambda d: d["surfaces"][1].update(semi_diameter=-1)),
        ("semi_diameter 0", lambda d: d["surfaces"][1].update(semi_diameter=0)),
        ("mirror pos thick", lambda d: d["surfaces"][3].update(material="mirror")),
        ("aspheric even coeffs nan", lambda d: d["surfaces"][1].update(type="even_asphere", coefficients=["nan"])),
        ("surface as list", lambda d: d["surfaces"].__setitem__(1, [1, 2])),
        ("vignetting wrong", lambda d: d.update(vignetting=[[0, 0, 0, 0]])),
    ]
    for name, f in cases:
        show(f"json {name}", lambda: json_try(mod(f)))



@probe
def analyses():
    import equinox as eqx

    from jaxlens.analysis import spots
    from jaxlens.analysis.encircled import encircled_energy, radius_for_fraction
    c = cooke
    show("rms_spot fields=[]", lambda: spots.rms_spot(c, fields=[]).rms)
    show("rms_spot wl=[]", lambda: spots.rms_spot(c, wavelengths=[]).rms)
    show("rms_spot wl=[[0.5]]", lambda: spots.rms_spot(c, wavelengths=[[0.5876]]).rms)
    show("rms_spot fields [[1,2,3]]", lambda: spots.rms_spot(c, fields=[[1.0, 2.0, 3.0]]).rms)
    show("rms_spot reference=Chief", lambda: spots.rms_spot(c, reference="Chief").rms)
    show("rms_spot pupil empty", lambda: spots.rms_spot(c, pupil=jnp.zeros((0, 2))).rms)
    show("rms_spot pupil outside disc", lambda: spots.rms_spot(c, pupil=jnp.array([[2.0, 0.0], [0, 1.5]])).rms)
    show("rms_spot depth=-5", lambda: spots.rms_spot(c, depth=-5.0).rms)
    show("rms_spot depth=0", lambda: spots.rms_spot(c, depth=0.0).rms)
    show("rms_spot newton_iters=-1", lambda: spots.rms_spot(c, newton_iters=-1).rms)
    show("rms_spot newton_iters=2.5", lambda: spots.rms_spot(c, newton_iters=2.5).rms)
    show("rms_spot newton_iters=True", lambda: spots.rms_spot(c, newton_iters=True).rms)
    show("vmap rms over fields 95", lambda: jax.vmap(lambda f: spots.rms_spot(c, fields=f[None]).rms)(jnp.array([0.0, 95.0])))
    show("jit rms fields 95", lambda: eqx.filter_jit(lambda f: spots.rms_spot(c, fields=f).rms)(jnp.array([95.0])))
    show("jit rms wl 10", lambda: eqx.filter_jit(lambda w: spots.rms_spot(c, wavelengths=w).rms)(jnp.array([10.0])))
    show("grad rms depth -5", lambda: jax.grad(lambda d: spots.rms_spot(c, depth=d).rms.sum())(-5.0))
    show("jit rms depth -5", lambda: eqx.filter_jit(lambda d: spots.rms_spot(c, depth=d).rms)(jnp.asarray(-5.0)))
    show("jit rms depth 0", lambda: eqx.filter_jit(lambda d: spots.rms_spot(c, depth=d).rms)(jnp.asarray(0.0)))
    show("jit rms depth nan", lambda: eqx.filter_jit(lambda d: spots.rms_spot(c, depth=d).rms)(jnp.asarray(jnp.nan)))
    show("distortion fields 95", lambda: spots.distortion(c, fields=[95.0]))
    show("chief_ray field (1,2,3)", lambda: spots.chief_ray(c, (1.0, 2.0, 3.0)).origin)
    show("encircled radii -1", lambda: encircled_energy(c, 0.0, [-1.0, 0.01]).fraction)
    show("encircled radii nan", lambda: encircled_energy(c, 0.0, [np.nan]).fraction)
    show("encircled radii []", lambda: encircled_energy(c, 0.0, []).fraction)
    show("encircled shape 'sq'", lambda: encircled_energy(c, 0.0, [0.01], shape="sq").fraction)
    show("radius_for_fraction 1.5", lambda: radius_for_fraction(c, 0.0, 1.5))
    show("radius_for_fraction 0", lambda: radius_for_fraction(c, 0.0, 0.0))
    show("radius_for_fraction 1.0", lambda: radius_for_fraction(c, 0.0, 1.0))
    show("radius_for_fraction nan", lambda: radius_for_fraction(c, 0.0, np.nan))
    show("radius_for_fraction [0.5,0.8]", lambda: radius_for_fraction(c, 0.0, [0.5, 0.8]))
    show("jit radius_for_fraction 1.5", lambda: eqx.filter_jit(lambda f: radius_for_fraction(c, 0.0, f))(jnp.asarray(1.5)))
    show("self_intersection min_gap -1", lambda: spots.self_intersection(c, min_gap=-1.0))
    show("self_intersection min_gap nan", lambda: spots.self_intersection(c, min_gap=np.nan))
    show("self_intersection n_radial 0", lambda: spots.self_intersection(c, n_radial=0))
    show("self_intersection sds wrong len", lambda: spots.self_intersection(c, [1.0, 2.0]))
    show("self_intersection sds negative", lambda: spots.self_intersection(c, [-1.0] * 6))
    show("clear_semi_diameters n_rim 0", lambda: spots.clear_semi_diameters(c, n_rim=0))
    show("clear_semi_diameters fields 95", lambda: spots.clear_semi_diameters(c, [95.0]))


@probe
def imaging():
    import equinox as eqx
    c = cooke
    show("psf kernel_size 0", lambda: jl.psf(c, 0.0, kernel_size=0).shape)
    show("psf kernel_size 30 (even)", lambda: jl.psf(c, 0.0, kernel_size=30).shape)
    show("psf kernel_size 31.0", lambda: jl.psf(c, 0.0, kernel_size=31.0).shape)
    show("psf pixel_size -1", lambda: jl.psf(c, 0.0, pixel_size=-1.0).shape)
    show("psf pixel_size 0", lambda: jl.psf(c, 0.0, pixel_size=0.0).shape)
    show("psf center 'foo'", lambda: jl.psf(c, 0.0, center="foo").shape)
    show("psf max_truncation 2", lambda: jl.psf(c, 0.0, max_truncation=2.0).shape)
    show("psf max_truncation -1", lambda: jl.psf(c, 0.0, max_truncation=-1.0).shape)
    show("psf newton_iters 0", lambda: float(jl.psf(c, 0.0, newton_iters=0).sum()))
    show("psf field [0,1,2]", lambda: jl.psf(c, [0.0, 1.0, 2.0]).shape)
    show("psf wavelength [[0.5]]", lambda: jl.psf(c, 0.0, wavelength=[[0.5876]]).shape)
    show("psf wavelength []", lambda: jl.psf(c, 0.0, wavelength=[]).shape)
    show("psf depth -100", lambda: jl.psf(c, 0.0, depth=-100.0).shape)
    show("psf key=5", lambda: jl.psf(c, 0.0, key=5).shape)
    show("jit psf field 95", lambda: eqx.filter_jit(lambda f: jl.psf(c, f))(jnp.asarray(95.0)).shape)
    show("vmap psf field [0,95]", lambda: jax.vmap(lambda f: jl.psf(c, f))(jnp.array([0.0, 95.0])).shape)
    show("jit psf depth -100", lambda: eqx.filter_jit(lambda d: jl.psf(c, 0.0, depth=d))(jnp.asarray(-100.0)).shape)
    show("jit psf pixel_size -1", lambda: float(eqx.filter_jit(lambda p: jl.psf(c, 0.0, pixel_size=p))(jnp.asarray(-0.001)).sum()))
    show("jit psf pixel_size 0", lambda: float(eqx.filter_jit(lambda p: jl.psf(c, 0.0, pixel_size=p))(jnp.asarray(0.0)).sum()))
    show("jit psf pixel_size nan", lambda: float(eqx.filter_jit(lambda p: jl.psf(c, 0.0, pixel_size=p))(jnp.asarray(jnp.nan)).sum()))
    show("jit efl lens thickness nan", lambda: eqx.filter_jit(jl.efl)(eqx.tree_at(lambda l: l.thickness, c, c.thickness.at[1].set(jnp.nan))))
    show("efl lens (tree_at) thickness nan", lambda: jl.efl(eqx.tree_at(lambda l: l.thickness, c, c.thickness.at[1].set(jnp.nan))))
    show("efl lens (tree_at) c nan", lambda: jl.efl(eqx.tree_at(lambda l: l.surfaces[0].c, c, jnp.asarray(jnp.nan))))
    show("rms lens (tree_at) epd -1", lambda: jl.analysis.spots.rms_spot(eqx.tree_at(lambda l: l.epd, c, jnp.asarray(-1.0))).rms)
    show("psf lens (tree_at) epd 0", lambda: float(jl.psf(eqx.tree_at(lambda l: l.epd, c, jnp.asarray(0.0)), 0.0).sum()))
    sensor = jl.Sensor((16, 16), 0.01)
    scene = jnp.ones((16, 16, 3))
    key = jax.random.key(0)
    show("render spp 0", lambda: jl.render(c, scene, spp=0, key=key, sensor=sensor).shape)
    show("render spp 1.5", lambda: jl.render(c, scene, spp=1.5, key=key, sensor=sensor).shape)
    show("render patch 0", lambda: jl.render(c, scene, spp=1, key=key, sensor=sensor, patch=0).shape)
    show("render patch 7 (not dividing)", lambda: jl.render(c, scene, spp=1, key=key, sensor=sensor, patch=7).shape)
    show("render scene neg", lambda: float(jl.render(c, -scene, spp=1, key=key, sensor=sensor).min()))
    show("render scene 2ch", lambda: jl.render(c, jnp.ones((16, 16, 2)), spp=1, key=key, sensor=sensor).shape)
    show("render scene int", lambda: jl.render(c, jnp.ones((16, 16, 3), int), spp=1, key=key, sensor=sensor).shape)
    show("render scene uint8 255", lambda: float(jl.render(c, jnp.full((16, 16, 3), 255, jnp.uint8), spp=1, key=key, sensor=sensor).max()))
    show("render wavelengths 2", lambda: jl.render(c, scene, spp=1, key=key, sensor=sensor, wavelengths=(0.5, 0.6)).shape)
    show("render depth 0", lambda: jl.render(c, scene, spp=1, key=key, sensor=sensor, depth=0.0).shape)
    show("render no sensor", lambda: jl.render(c, scene, spp=1, key=key).shape)


if __name__ == "__main__":
    for p in PROBES:
        if len(sys.argv) < 2 or sys.argv[1] in p.__name__:
            print(f"== {p.__name__}")
            try:
                p()
            except Exception:  # noqa: BLE001
                traceback.print_exc()
