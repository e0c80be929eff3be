# ruff: noqa: E501, E731, B023
"""Round-45b probes: held-out bad inputs of kinds the earlier audits did not try, in the
table of ``tools/probe_table.py``. The classes found, each closed by one mechanism:

1. A lens whose primary wavelength lies past a glass formula's resonance (a Sellmeier built
   from coefficients, outside the window between its poles) was refused in the name of a
   function the user never called: ``efl``, ``bfl``, ``magnification``, ``marginal_ray``,
   ``paraxial_data`` and ``system_matrix`` said ``signed_indices``, ``image_height`` said
   ``paraxial_chief_ray``, ``encircled_energy`` and ``image_scale``/``field_to_ideal``/
   ``ideal_to_field`` said ``paraxial_chief_ray`` (``image_height`` after a first fix),
   ``stop_radius`` ``paraxial_data``, ``self_intersection`` and ``semi_diameters_and_fans``
   ``clear_semi_diameters``. Now each entry point checks the lens's primary wavelength
   under its own name (``checks.primary_wavelength``; ``paraxial._given``/``_wavelength``
   for the paraxial ones).
2. Exact-zero tests where rounding leaves a residue: ``FNUM x 1`` (the paraxial working
   F/#) of a lens whose image lies at infinity gave an EPD of 1e14-1e16 mm (refused as "the
   EPD must be in [1e-9, 1e10)", not as what it is); now ``paraxial_data().working_fnum``,
   +inf within its rounding bound. The PARAXIAL OPD-mode check subtracted two lengths of
   5e10 mm and refused a beam collimated to 1e-9 with 0.015 waves of rounding; now the
   difference of lengths is taken without cancellation (and a NaN is refused, not
   swallowed by ``max``).
3. Radii and focal lengths whose reciprocals are no lens's: a focal length of 5e-324 mm
   (subnormal; 1/f overflows) gave efl = +inf, read as an afocal lens; 1e-300 mm a power of
   1e300; a JSON radius of 5e-324 was refused as ``c`` (a key the file did not hold), of
   1e-300 accepted; a surface with c = 1e300 and no semi-diameter accepted. Now
   ``optics.reciprocal``: lengths below 1e-9 mm (the smallest EPD a file may give) refused
   on the line or key that gave them; surfaces' |c| at most 1e9 per mm.
   The same for the other lengths divided by: a freeform's, a Q-type's or a Binary2's
   ``norm_radius`` of 1e-300 mm gave NaN spots and a NaN EFL; a ``Lens`` epd of 5e-324 mm
   an F/# of inf (a lens file's EPD was floored at 1e-9 mm, the Lens's not); a ``Sensor``
   pixel of 5e-324 mm rendered.
4. ``paraxial.object_slope`` and ``telecentric.in_cone`` of a lens without an object NA
   failed as None divided by an array (TypeError in Python's words).
5. Files that are not regular files: a FIFO named ``lens.zmx`` or ``lens.json`` blocked
   ``load`` (and ``load_agf``, ``configurations``) for ever; a link to ``/dev/zero`` read
   until the memory ran out. ``optics.input_files.input_file`` now refuses them.
6. ``tolerance.yield_fraction`` took a negative RMS as a passing trial.
7. The writers below ``save`` (``io.zmx.save_zmx``/``dumps``, ``io.lensfile.save_json``/
   ``dumps``/``lens_to_dict``) refused a lens past its glass's resonance as
   ``Sellmeier.index`` and a str lens with an AttributeError; now ``save``'s check
   (``json_values.loadable``) runs in each under its own name.
8. ``paraxial.marginal_ray``, ``system_matrix``, ``entrance_pupil_z``,
   ``entrance_pupil_magnification`` and ``signed_indices`` of a lens edited with
   ``eqx.tree_at`` (a NaN thickness or curvature, an infinite conic) returned NaN without a
   word (``efl`` and ``paraxial_data`` checked the lens); now every entry point of
   ``paraxial`` checks it once, in the outermost call (``paraxial._entry``).

Run from the tree's root: ``PYTHONPATH=. python tools/audit45b_probe.py [filter]``.
"""

import copy
import json
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, checked, fresh, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.analysis import encircled, spots  # noqa: E402
from jaxlens.imaging import aiming, sampling, telecentric  # noqa: E402
from jaxlens.optics import paraxial as PX  # noqa: E402
from jaxlens.optics.paraxial_surface import ParaxialSurface  # noqa: E402

AIR = jl.Air
# A glass from coefficients whose window between resonances is 0.1414-2 µm.
RESONANT = jl.Sellmeier(B=(1.0, 0.2, 1.0), C=(0.006, 0.02, 4.0))


def resonant_lens(wavelengths=(3.0,)):
    """A singlet of ``RESONANT`` with a stop, its primary wavelength ``wavelengths[0]``."""
    return jl.Lens((jl.Sphere(c=0.02, semi_diameter=10.0), jl.Stop(semi_diameter=4.0),
                    jl.Sphere(c=-0.02, semi_diameter=10.0)), jnp.array([5.0, 1.0, 90.0]),
                   (RESONANT, RESONANT, AIR()), epd=8.0, wavelengths=wavelengths,
                   fields=(0.0, 5.0), stop=1)


def primary_wavelength_names():
    L = resonant_lens()
    calls = {
        "efl": lambda: PX.efl(L), "bfl": lambda: PX.bfl(L),
        "magnification": lambda: PX.magnification(L), "marginal_ray": lambda: PX.marginal_ray(L),
        "paraxial_data": lambda: PX.paraxial_data(L), "system_matrix": lambda: PX.system_matrix(L),
        "paraxial_chief_ray": lambda: PX.paraxial_chief_ray(L, 1.0),
        "image_height": lambda: PX.image_height(L, 1.0),
        "entrance_pupil_z": lambda: PX.entrance_pupil_z(L),
        "entrance_pupil_magnification": lambda: PX.entrance_pupil_magnification(L),
        "encircled_energy": lambda: encircled.encircled_energy(L, 0.0, jnp.array([0.01])),
        "self_intersection": lambda: spots.self_intersection(L),
        "semi_diameters_and_fans": lambda: spots.semi_diameters_and_fans(L, jnp.array([0.0]), jnp.zeros((1, 2))),
        "stop_radius": lambda: sampling.stop_radius(L),
        "image_scale": lambda: aiming.image_scale(L),
        "field_to_ideal": lambda: aiming.field_to_ideal(L, 1.0),
        "ideal_to_field": lambda: aiming.ideal_to_field(L, jnp.array([0.0, 1.0])),
        "seidel": lambda: jl.analysis.seidel(L),
        "rms_spot": lambda: jl.analysis.rms_spot(L),
        "wavefront": lambda: jl.analysis.wavefront(L, 0.0),
    }
    for name, fn in calls.items():
        probe(f"{name}, primary wavelength 3 µm past the glass's resonance at 2 µm", fn, f"{name}:", "3 µm", "resonance")
    for wl in ((2.5, 0.5), (2.0000001,)):
        M = resonant_lens(wl)
        probe(f"efl, primary wavelength {wl[0]!r} µm (just past the pole)", lambda M=M: PX.efl(M), "efl:", "primary wavelength")
    M = resonant_lens((3.0, 0.5))
    probe("efl at a given 0.5 µm of a lens whose primary is 3 µm (control)", lambda: PX.efl(M, 0.5), good=True)
    probe("stop_radius of the Cooke triplet (control)", lambda: sampling.stop_radius(jl.load(COOKE)), good=True)


def afocal_zmx():
    """A .zmx of two ideal lenses f1 + f2 apart (afocal), or one with its object in the front
    focal plane, its aperture ``ap``."""
    from jaxlens.io import files

    def write(lens, ap):
        d = fresh("af")
        p = os.path.join(d, "a.zmx")
        files.save(lens, p)
        text = open(p).read()
        line = next(t for t in text.splitlines() if t.startswith("ENPD"))
        open(p, "w").write(text.replace(line, ap))
        return p

    def pair(f1, f2, gap):
        return jl.Lens((ParaxialSurface(focal_length=f1), ParaxialSurface(focal_length=f2)),
                       jnp.array([gap, 50.0]), (AIR(), AIR()), epd=10.0)

    def thin(f, s):
        return jl.Lens((ParaxialSurface(focal_length=f),), jnp.array([100.0]), (AIR(),),
                       epd=10.0, object_distance=s)

    for label, L in (("afocal pair 0.3 + 0.3, 0.1+0.2+0.3 apart", pair(0.3, 0.3, 0.1 + 0.2 + 0.3)),
                     ("afocal pair 70 + 7", pair(70.0, 7.0, 77.0)),
                     ("thin lens f=0.3, object at 0.1*3", thin(0.3, 0.1 * 3)),
                     ("thin lens f=100, object at 100(1+1e-15)", thin(100.0, 100.0 * (1 + 1e-15)))):
        p = write(L, "FNUM 5 1")
        probe(f"load .zmx FNUM 5 1 (working F/#), {label}", lambda p=p: jl.load(p), "parallel to the axis", "FNUM 5 1")
    p = write(thin(100.0, 300.0), "FNUM 5 1")

    def control():
        lens = jl.load(p)  # 1:2 conjugates: working F/# = 1/(2u') with u' = (EPD/2)/150
        w = float(jl.paraxial_data(lens).working_fnum)
        return abs(w - 5.0) < 1e-12, f"working F/# {w!r} (FNUM 5)"
    checked("load .zmx FNUM 5 1 of a thin lens at 1:2 (control: working F/# 5)", control)


def opd_mode_rounding():
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from test_zmx_paraxial_opd import TWO_LENSES

    def load(f1):
        text = TWO_LENSES.format(f1=f1, sd=1.0, opd="PARM 2 0", flap="", epd=0.02, field=0.0)
        p = os.path.join(fresh("opd"), "t.zmx")
        open(p, "w").write(text)
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            jl.load(p)
        said = [str(x.message) for x in w if "OPD mode" in str(x.message)]
        return said[0] if said else ""

    for f1 in ("5e10", "2e10", "1e10", "-5e10"):
        # the true difference falls as 1/z_O (1.1e-5 waves at f1 = -2000 mm)
        def go(f1=f1):
            import re
            text = load(f1)
            m = re.search(r"at most ([0-9.e+-]+) waves", text)
            v = float(m.group(1)) if m else float("nan")
            return v < 1e-9, f"{v:g} waves"
        checked(f".zmx PARAXIAL in OPD mode 0 behind a lens of f = {f1} mm (nearly collimated)", go)


def reciprocal_lengths():
    for f in (1e-300, 5e-324, -1e-320, 1e-12, float("nan"), -float("inf")):
        probe(f"ParaxialSurface focal_length {f!r}", lambda f=f: ParaxialSurface(focal_length=f), "focal_length", "1e-09 mm")
    probe("ParaxialSurface focal_length [100, 5e-324] (batched)", lambda: ParaxialSurface(focal_length=np.array([100.0, 5e-324])), "focal_length", "5e-324")
    probe("ParaxialSurface focal_length 1e-6 (control)", lambda: ParaxialSurface(focal_length=1e-6), good=True)
    for c in (1e300, -1e300, 1e10):
        probe(f"Standard c={c!r}, no semi-diameter", lambda c=c: jl.Standard(c=c), "c", "1e+09", "1/mm")
        probe(f"Toroidal cx={c!r}", lambda c=c: jl.optics.toroidal.Toroidal(c=0.01, cx=c), "cx", "1e+09")
        probe(f"Biconic cx={c!r}", lambda c=c: jl.Biconic(c=0.01, cx=c), "cx", "1e+09")
    probe("Standard c=1e9 (R = 1 nm; control)", lambda: jl.Standard(c=1e9), good=True)
    cooke = json.load(open(COOKE))

    def js(edit):
        def go():
            c = copy.deepcopy(cooke)
            edit(c)
            p = os.path.join(fresh("js"), "c.json")
            open(p, "w").write(json.dumps(c))
            return jl.load(p)
        return go
    for r in (5e-324, -1e-320, 1e-300, 1e-10):
        probe(f"lens JSON radius {r!r}", js(lambda c, r=r: c["surfaces"][1].__setitem__("radius", r)), "surface 1", "radius", "1e-09 mm")
        probe(f"lens JSON radius {r!r} with its curvature", js(lambda c, r=r: c["surfaces"][1].update(radius=r, curvature=1 / r if abs(r) > 1e-300 else 1e300)), "radius")
    probe("lens JSON curvature 1e300", js(lambda c: c["surfaces"][1].update(curvature=1e300) or c["surfaces"][1].pop("radius")), "c", "1e+09")
    probe("lens JSON radius 1e300 (nearly flat; control)", js(lambda c: c["surfaces"][1].__setitem__("radius", 1e300)), good=True)
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from test_toroid_paraxial import ZMX

    text = ZMX.format(unit="MM", opd="PARM 2 2")

    def zmx(old, new):
        assert old in text, old
        def go():
            p = os.path.join(fresh("zx"), "t.zmx")
            open(p, "w").write(text.replace(old, new))
            return jl.load(p)
        return go
    for v in ("1e-300", "5e-324", "-1e-320", "1e-12"):
        probe(f".zmx PARAXIAL PARM 1 {v}", zmx("  PARM 1 60\n", f"  PARM 1 {v}\n"), f"PARM 1 {v}", "1e-09 mm")
        probe(f".zmx TOROIDAL PARM 1 (radius of rotation) {v}", zmx("  PARM 1 25\n", f"  PARM 1 {v}\n"), f"PARM 1 {v}", "1e-09 mm")
    probe(".zmx TOROIDAL CURV 1e300", zmx("CURV 2.5E-2 0", "CURV 1e300 0"), "t.zmx:", "1e+09")
    probe(".zmx UNIT CM, PARAXIAL PARM 1 5e-11 (5e-10 mm)", lambda: (lambda p: (open(p, "w").write(ZMX.format(unit="CM", opd="PARM 2 2").replace("  PARM 1 60\n", "  PARM 1 5e-11\n")), jl.load(p)))(os.path.join(fresh("zc"), "t.zmx")), "PARM 1", "5e-10 mm")
    probe(".zmx TOROIDAL PARM 1 0 (a cylinder; control)", zmx("  PARM 1 25\n", "  PARM 1 0\n"), good=True)


def not_telecentric():
    cooke = jl.load(COOKE)
    probe("paraxial.object_slope of the Cooke triplet (no object NA)", lambda: PX.object_slope(cooke), "object_slope", "object_na")
    probe("telecentric.in_cone of the Cooke triplet", lambda: telecentric.in_cone(cooke, jnp.array([0.0, 0.0, 1.0])), "in_cone", "object_na")
    probe("paraxial.object_slope of a str", lambda: PX.object_slope("cooke"), "object_slope", "Lens")


def divided_lengths():
    cooke = jl.load(COOKE)
    s0 = cooke.surfaces[0]
    c, sd = float(s0.c), float(s0.semi_diameter)
    makers = {
        "XYPolynomial": lambda r: jl.XYPolynomial(c=c, coeffs=jnp.array([0.0, 0.0, 1e-3]), norm_radius=r, semi_diameter=sd),
        "ZernikeSag": lambda r: jl.ZernikeSag(c=c, zernike=jnp.array([0.0, 0.0, 0.0, 1e-3]), norm_radius=r, semi_diameter=sd),
        "QTypeAsphere": lambda r: jl.QTypeAsphere(c=c, coeffs=jnp.array([1e-3]), norm_radius=r, semi_diameter=sd),
        "Binary2": lambda r: jl.Binary2(c=c, phase_coeffs=jnp.array([-10.0]), norm_radius=r, semi_diameter=sd),
    }
    for name, make in makers.items():
        for r in (1e-300, 5e-324, 1e-10):
            probe(f"{name} norm_radius {r!r}", lambda make=make, r=r: make(r), name, "norm_radius", "1e-09 mm")
        probe(f"{name} norm_radius 1e-9 (control)", lambda make=make: make(1e-9), good=True)
    for e in (5e-324, 1e-300, 1e-10):
        probe(f"Lens epd {e!r}", lambda e=e: jl.Lens(cooke.surfaces, cooke.thickness, cooke.materials, epd=e), "epd", "1e-09 mm")
    for ps in (5e-324, 1e-300):
        probe(f"Sensor pixel_size {ps!r}", lambda ps=ps: jl.Sensor(resolution=(32, 32), pixel_size=ps), "pixel_size", "1e-09 mm")
    probe("Sensor pixel_size 1e-9 (control)", lambda: jl.Sensor(resolution=(32, 32), pixel_size=1e-9), good=True)


def not_regular_files():
    """FIFOs and devices under a lens file's name: each probe in a child with a time limit
    (a blocked open() cannot be interrupted from the same thread)."""
    import subprocess

    d = fresh("ff")
    TREE = os.path.dirname(os.path.dirname(jl.__file__))  # the jaxlens this process probes
    for ext in ("zmx", "json", "agf"):
        os.mkfifo(os.path.join(d, f"fifo.{ext}"))
        os.symlink("/dev/zero", os.path.join(d, f"zero.{ext}"))
    calls = {"load": ("zmx", "json"), "jaxlens.io.zmx.configurations": ("zmx",),
             "jaxlens.io.lensfile.load_json": ("json",), "jaxlens.io.zmx.load_zmx": ("zmx",),
             "load_agf": ("agf",)}

    def child(call, path):
        def go():
            code = (f"import jaxlens, jaxlens.io.zmx, jaxlens.io.lensfile\n"
                    f"try:\n    jaxlens.{call.removeprefix('jaxlens.')}({path!r})\n"
                    f"except (ValueError, TypeError) as e:\n    print('REFUSED', e)\n")
            def cap():  # /dev/zero read without end: a MemoryError at 3 GiB, not a full machine
                import resource

                resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
            try:
                p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                   timeout=30, env=dict(os.environ, PYTHONPATH=TREE), preexec_fn=cap)
            except subprocess.TimeoutExpired:
                raise RuntimeError("hang: no answer in 30 s") from None
            out = p.stdout.strip()
            if out.startswith("REFUSED"):
                raise ValueError(out.removeprefix("REFUSED "))
            raise RuntimeError(f"exit {p.returncode}: {(p.stderr.strip().splitlines() or [''])[-1]}")
        return go
    for call, exts in calls.items():
        for ext in exts:
            probe(f"{call.split('.')[-1]} of a FIFO named fifo.{ext}", child(call, os.path.join(d, f"fifo.{ext}")), "not a regular file", "fifo")
        ext = exts[0]
        probe(f"{call.split('.')[-1]} of a link to /dev/zero named zero.{ext}", child(call, os.path.join(d, f"zero.{ext}")), "not a regular file")


def writer_names():
    from jaxlens.io import lensfile, zmx

    L = resonant_lens()
    d = fresh("wr")
    calls = {"save_zmx": lambda: zmx.save_zmx(L, os.path.join(d, "a.zmx")),
             "save_json": lambda: lensfile.save_json(L, os.path.join(d, "a.json")),
             "dumps": lambda: lensfile.dumps(L), "lens_to_dict": lambda: lensfile.lens_to_dict(L),
             "zmx dumps": lambda: zmx.dumps(L)}
    for name, fn in calls.items():
        probe(f"{name} of a lens whose wavelength 3 µm lies past its glass's resonance", fn, f"{name.split()[-1]}:", "3 µm")
    probe("save_zmx of a str", lambda: zmx.save_zmx("lens", os.path.join(d, "b.zmx")), "save_zmx", "Lens")
    probe("lensfile.dumps of None", lambda: lensfile.dumps(None), "dumps", "Lens")
    probe("save of the same lens (control: named save before)", lambda: jl.save(L, os.path.join(d, "c.json")), "save:", "3 µm")


def edited_lens():
    import equinox as eqx

    cooke = jl.load(COOKE)
    edits = {"NaN thickness": eqx.tree_at(lambda m: m.thickness, cooke, cooke.thickness.at[2].set(jnp.nan)),
             "NaN curvature": eqx.tree_at(lambda m: m.surfaces[1].c, cooke, jnp.asarray(jnp.nan)),
             "inf conic": eqx.tree_at(lambda m: m.surfaces[2].k, cooke, jnp.asarray(jnp.inf))}
    calls = {"marginal_ray": lambda L: PX.marginal_ray(L), "system_matrix": lambda L: PX.system_matrix(L),
             "entrance_pupil_z": lambda L: PX.entrance_pupil_z(L),
             "entrance_pupil_magnification": lambda L: PX.entrance_pupil_magnification(L),
             "signed_indices": lambda L: PX.signed_indices(L, 0.55)}
    for name, fn in calls.items():
        for what, L in edits.items():
            probe(f"paraxial.{name} of the Cooke triplet edited with eqx.tree_at: {what}", lambda fn=fn, L=L: fn(L), f"{name}:", "fails its own checks")
    probe("paraxial.marginal_ray of the Cooke triplet (control)", lambda: PX.marginal_ray(cooke), good=True)


def negative_rms():
    from jaxlens.analysis import tolerance as TL

    probe("yield_fraction rms [-1, 2] threshold 1", lambda: TL.yield_fraction([-1.0, 2.0], 1.0), "rms_um", ">= 0")
    probe("yield_fraction rms [-0.0, 2] threshold 1 (control: 0.5)", lambda: TL.yield_fraction([-0.0, 2.0], 1.0), good=True)
    probe("yield_fraction rms [nan, 2] threshold 3 (control: NaN fails, 0.5)", lambda: TL.yield_fraction([np.nan, 2.0], 3.0), good=True)


if __name__ == "__main__":
    run([primary_wavelength_names, afocal_zmx, opd_mode_rounding, reciprocal_lengths, not_telecentric,
         divided_lengths, not_regular_files, negative_rms, writer_names, edited_lens])
