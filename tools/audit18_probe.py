# ruff: noqa: E501, B023, E731
"""Round-18 bad-input probes: throw malformed input at the public API (``jaxlens.__init__``)
and the CLIs and print a table: probe | outcome | what happened.

Outcomes:
    clear error   ValueError/TypeError (or a CLI's exit 2 with one line) whose message holds
                  every expected word (the argument's name, the range, the unit).
    vague error   ValueError/TypeError that lacks an expected word.
    crash         another exception (from deep inside JAX, numpy, a KeyError…).
    silent wrong  bad input returned a value.
    ok            a control (good input) returned a value, as it should.

Areas: Tolerances bounds, DesignSpec 0-d arrays, jax.jit of material.index, tables and
catalog glasses outside their data on every path that evaluates an index (trace, psf, render,
analyses, paraxial, .zmx export), analyses with wrong dtypes (bool, complex, str), empty and
mis-shaped arrays, degree/radian and mm/m mix-ups, lens consistency, unknown names, CLIs.

Run: PYTHONPATH=$PWD python tools/audit18_probe.py [filter]
"""

import os
import tempfile

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
cooke = zoo.cooke_triplet()


# ----------------------------------------------------------------------------- known gaps
def tab_lens(mat, wls=(0.55,)):
    return jl.Lens(surfaces=(jl.Sphere(0.02, semi_diameter=8.0), jl.Sphere(-0.02, semi_diameter=8.0)),
                   thickness=jnp.array([5.0, 45.0]), materials=(mat, jl.Air()), epd=10.0,
                   fields=jnp.array([0.0, 5.0]), wavelengths=jnp.array(wls))


def known_gaps():
    from jaxlens.analysis.tolerance import Tolerances
    from jaxlens.design import DesignSpec
    for k, v in (("irregularity", 1.0), ("irregularity", 0.5), ("asphere_sag", 2.0), ("index", 1.0), ("conic", 5.0)):
        probe(f"Tolerances({k}={v})", lambda: Tolerances(**{k: v}), k, "below")
    probe("Tolerances(irregularity=0.002) (control)", lambda: Tolerances(irregularity=0.002).irregularity, good=True)
    for kw in (dict(fov_start=jnp.asarray(40.0)), dict(fov=np.float32(60.0)), dict(fnum_start=np.array(4.0)),
               dict(n_elements=np.int64(6)), dict(sensor_pixels=jnp.asarray(256)), dict(wavelengths=np.array([0.5, 0.6])),
               dict(total_track=jnp.asarray(7.0)), dict(efl=np.array(5.0))):
        probe(f"DesignSpec({list(kw)[0]}={type(list(kw.values())[0]).__name__}) (control: 0-d array is a number)", lambda: DesignSpec(**kw).fov_start, good=True)
    for kw in (dict(fov_start=jnp.asarray([40.0])), dict(fov=np.array([60.0, 70.0])), dict(n_elements=np.array(6.0)),
               dict(fnum=jnp.asarray(2.0 + 0j))):
        probe(f"DesignSpec({kw})", lambda: DesignSpec(**kw), list(kw)[0])
    mats = {"Air": jl.Air(), "ModelGlass": jl.ModelGlass(1.5, 50.0), "Schott": jl.Schott([2.27, -0.01, 0.01, 0, 0, 0]),
            "Sellmeier": jl.Sellmeier([1.04, 0.23, 1.01], [0.006, 0.02, 103.56]),
            "Tabulated": jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515]), "N-BK7": jl.get_material("N-BK7"),
            "E48R": jl.get_material("E48R")}
    for name, m in mats.items():
        probe(f"jax.jit({name}.index)(0.55) (control)", lambda: jax.jit(m.index)(0.55), good=True)
    probe("jit(lambda: get_material('N-BK7').index(w)) (control)", lambda: jax.jit(lambda w: jl.get_material("N-BK7").index(w))(0.55), good=True)
    tab = jl.Tabulated([0.45, 0.55, 0.65], [1.53, 1.52, 1.515], name="TAB")
    probe("Tabulated.index(1.0) outside 0.45-0.65", lambda: tab.index(1.0), "0.65", "µm")
    probe("Tabulated.extrapolated_index(1.0) (control: held end)", lambda: tab.extrapolated_index(1.0), good=True)
    probe("Tabulated one node index(5.0) (control)", lambda: jl.Tabulated([0.55], [1.5]).index(5.0), good=True)
    lens = tab_lens(tab)
    from jaxlens.analysis import distortion, rms_spot, seidel, wavefront
    from jaxlens.imaging import sampling
    from jaxlens.imaging.psf import mtf
    W = 1.0
    probe("Lens.indices(1.0) with a table to 0.65", lambda: lens.indices(W), "µm")
    probe("efl table lens 1.0", lambda: jl.efl(lens, W), "µm", "TAB")
    probe("rms_spot table lens 1.0", lambda: rms_spot(lens, wavelengths=[W]).polychromatic, "µm", "TAB")
    probe("distortion table lens 1.0", lambda: distortion(lens, wavelength=W).percent_ftan, "µm", "TAB")
    probe("seidel table lens 1.0", lambda: seidel(lens, wavelength=W).per_surface, "µm", "TAB")
    probe("wavefront table lens 1.0", lambda: wavefront(lens, 0.0, wavelength=W, grid=9).rms, "µm", "TAB")
    probe("psf table lens 1.0", lambda: jl.psf(lens, 0.0, wavelength=W, kernel_size=9, pixel_size=0.005), "µm", "TAB")
    probe("mtf table lens 1.0", lambda: mtf(lens, 0.0, wavelengths=[W]), "µm", "TAB")
    probe("collimated table lens 1.0", lambda: sampling.collimated(lens, 0.0, jnp.zeros((1, 2)), W), "µm", "TAB")
    probe("trace rays at 1.0 (wavelength in the Rays)", lambda: jl.trace(lens, jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0.0, 0.0, 1.0]]), wavelength=jnp.array([W]))).origin, "µm", "TAB")
    sensor = jl.Sensor(resolution=(8, 8), pixel_size=0.01)
    probe("render table lens (0.656, 0.588, 0.486) vs table to 0.65", lambda: jl.render(lens, np.zeros((8, 8, 3)), sensor=sensor, spp=1, key=jax.random.key(0)), "µm", "TAB")
    bk7 = jl.get_material("N-BK7")
    bk = tab_lens(bk7, (0.55, 2.6))
    probe("Lens(N-BK7, wavelengths 0.55, 2.6) built (documented: analyses check the materials)", lambda: bk.wavelengths, good=True)
    probe("rms_spot N-BK7 lens at 2.6", lambda: rms_spot(bk).polychromatic, "2.5", "µm")
    probe("field_curvature N-BK7 lens at 2.6", lambda: jl.analysis.field_curvature(bk).sagittal, "2.5", "µm")
    probe("ray_fan N-BK7 lens at 2.6", lambda: jl.analysis.ray_fan(bk, 0.0).ey, "2.5", "µm")
    probe("opd_fan N-BK7 lens at 2.6", lambda: jl.analysis.opd_fan(bk, 0.0).opd, "2.5", "µm")
    from jaxlens.io import zmx_write
    probe("zmx dumps N-BK7 lens at 2.6 (documented: the file holds the lens as given, GLAS by name; no index is evaluated)", lambda: zmx_write.dumps(bk)[0][:20], good=True)
    probe("zmx dumps table lens wavelength 1.0 (documented: the table is fitted over its own nodes, LD gives its range)", lambda: zmx_write.dumps(tab_lens(tab, (0.55, 1.0)))[0][:20], good=True)
    from jaxlens.optics.materials import abbe_number
    probe("abbe_number table 0.6-0.8 (does not hold F or d)", lambda: abbe_number(jl.Tabulated([0.6, 0.7, 0.8], [1.52, 1.515, 1.51])), "F", "µm")


# ----------------------------------------------------------------------------- dtypes and shapes
def dtypes_and_shapes():
    from jaxlens.analysis import (
        chief_ray,
        distortion,
        encircled_energy,
        rms_spot,
        spot_rays,
        zernike_fit,
        zernike_nm,
    )
    from jaxlens.imaging import sampling
    pts = jnp.zeros((1, 2))
    probe("rms_spot fields [True]", lambda: rms_spot(cooke, [True]).polychromatic, "fields")
    probe("rms_spot fields complex", lambda: rms_spot(cooke, [1j]).polychromatic, "fields")
    probe("rms_spot fields []", lambda: rms_spot(cooke, []).polychromatic, "fields")
    probe("rms_spot wavelengths []", lambda: rms_spot(cooke, wavelengths=[]).polychromatic, "wavelength")
    probe("rms_spot wavelengths bool", lambda: rms_spot(cooke, wavelengths=[True]).polychromatic, "wavelength")
    probe("rms_spot fields 2-D [[0,1,2]]", lambda: rms_spot(cooke, [[0.0, 1.0, 2.0]]).polychromatic, "field")
    probe("rms_spot pupil 3 columns", lambda: rms_spot(cooke, pupil=jnp.zeros((4, 3))).polychromatic, "pupil")
    probe("rms_spot pupil NaN", lambda: rms_spot(cooke, pupil=jnp.full((4, 2), jnp.nan)).polychromatic, "pupil")
    probe("spot_rays field string", lambda: spot_rays(cooke, "10").origin, "field")
    probe("chief_ray field [0, 5, 10] (several)", lambda: chief_ray(cooke, [0.0, 5.0, 10.0]).origin, "field")
    probe("chief_ray wavelength complex", lambda: chief_ray(cooke, 0.0, 0.55 + 0j).origin, "wavelength")
    probe("distortion fields 0.35 (radians? documented: degrees)", lambda: distortion(cooke, [0.35]).percent_ftan, good=True)
    probe("distortion wavelength index 1 (int, 1 µm outside glass)", lambda: distortion(cooke, wavelength=1).percent_ftan, "µm")
    probe("encircled_energy radii []", lambda: encircled_energy(cooke, 0.0, []).energy, "radii")
    probe("encircled_energy radii nan", lambda: encircled_energy(cooke, 0.0, [np.nan]).energy, "radii")
    probe("encircled_energy method 'Geometric'", lambda: encircled_energy(cooke, 0.0, [0.01], method="Geometric").energy, "method")
    probe("encircled_energy shape 'square'", lambda: encircled_energy(cooke, 0.0, [0.01], shape="sqare").energy, "shape")
    probe("radius_for_fraction 1.5", lambda: jl.analysis.radius_for_fraction(cooke, 0.0, 1.5), "fraction")
    probe("radius_for_fraction 0", lambda: jl.analysis.radius_for_fraction(cooke, 0.0, 0.0), "fraction")
    probe("radius_for_fraction 80 (percent?)", lambda: jl.analysis.radius_for_fraction(cooke, 0.0, 80.0), "fraction")
    probe("zernike_fit terms 0", lambda: zernike_fit(jnp.zeros(4), jnp.zeros(4), jnp.zeros(4), terms=0).coefficients, "terms")
    probe("zernike_fit shapes differ", lambda: zernike_fit(jnp.zeros(4), jnp.zeros(5), jnp.zeros(4)).coefficients, "same number")
    probe("zernike_fit indexing 'Noll'", lambda: zernike_fit(jnp.zeros(4), jnp.zeros(4), jnp.zeros(4), indexing="Noll").coefficients, "indexing")
    probe("zernike_fit x = 2 (outside unit disc)", lambda: zernike_fit(jnp.full(40, 2.0), jnp.zeros(40), jnp.zeros(40), terms=4).coefficients, "unit")
    probe("zernike_nm 0 (noll from 1)", lambda: zernike_nm(0), "j")
    probe("zernike_nm 2.5", lambda: zernike_nm(2.5), "j")
    probe("zernike_nm -1 indexing fringe", lambda: zernike_nm(-1, indexing="fringe"), "j")
    probe("seidel field complex", lambda: jl.analysis.seidel(cooke, field=1j).per_surface, "field")
    probe("seidel field [0, 10]", lambda: jl.analysis.seidel(cooke, field=[0.0, 10.0]).per_surface, "field")
    probe("field_rays pupil bool", lambda: sampling.field_rays(cooke, 0.0, jnp.zeros((1, 2), bool), 0.55).origin, "pupil")
    probe("field_rays depth 0", lambda: sampling.field_rays(cooke, 0.0, pts, 0.55, depth=0.0).origin, "depth")
    probe("psf model string", lambda: jl.psf(cooke, 0.0, model="coherent", kernel_size=9, pixel_size=0.005), "model")
    probe("psf center 'centroid '", lambda: jl.psf(cooke, 0.0, center="centroid ", kernel_size=9, pixel_size=0.005), "center")
    probe("psf pixel_size 5 (µm where mm are meant)", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=5.0), "pixel_size")
    probe("psf kernel_size 9.0 (documented: a whole float is a whole number)", lambda: jl.psf(cooke, 0.0, kernel_size=9.0, pixel_size=0.005).shape, good=True)
    probe("psf max_truncation 2", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=0.005, max_truncation=2.0), "max_truncation")
    probe("psf newton_iters -1", lambda: jl.psf(cooke, 0.0, kernel_size=9, pixel_size=0.005, newton_iters=-1), "newton_iters")
    probe("mtf frequencies [] ", lambda: jl.imaging.psf.mtf(cooke, 0.0, frequencies=[]), "frequencies")
    probe("mtf diffraction 'yes'", lambda: jl.imaging.psf.mtf(cooke, 0.0, diffraction="yes"), "diffraction")
    probe("clear_semi_diameters n_rim 0", lambda: jl.analysis.clear_semi_diameters(cooke, n_rim=0), "n_rim")
    probe("clear_semi_diameters reaching 'no'", lambda: jl.analysis.clear_semi_diameters(cooke, reaching="no"), "reaching")
    probe("self_intersection min_gap -1", lambda: jl.analysis.self_intersection(cooke, min_gap=-1.0).ok, "min_gap")
    probe("self_intersection semi_diameters wrong length", lambda: jl.analysis.self_intersection(cooke, semi_diameters=jnp.ones(2)).ok, "semi_diameters")
    probe("angular_spot of a focal lens (documented: any lens's directions can be measured)", lambda: jl.analysis.angular_spot(cooke).polychromatic, good=True)
    probe("frame_of index 99", lambda: jl.optics.coordinates.frame_of(cooke, 99), "index")
    probe("frame_of index -1", lambda: jl.optics.coordinates.frame_of(cooke, -1), "index")
    probe("frame_of index 2.0", lambda: jl.optics.coordinates.frame_of(cooke, 2.0), "index")


# ----------------------------------------------------------------------------- tracing
def tracing():
    rays = jl.sampling.collimated(cooke, 0.0, jnp.zeros((3, 2)), 0.55)
    n = cooke.num_surfaces
    probe("trace upto 99", lambda: jl.trace(cooke, rays, upto=99).origin, "upto")
    probe("trace upto -1", lambda: jl.trace(cooke, rays, upto=-1).origin, "upto")
    probe(f"trace upto {n - 1} (control: last surface)", lambda: jl.trace(cooke, rays, upto=n - 1).origin, good=True)
    probe(f"trace upto {n} (the image is not a surface index)", lambda: jl.trace(cooke, rays, upto=n).origin, "upto")
    probe("trace upto 2.0", lambda: jl.trace(cooke, rays, upto=2.0).origin, "upto")
    probe("trace newton_iters -1", lambda: jl.trace(cooke, rays, newton_iters=-1).origin, "newton_iters")
    probe("trace chunk 0", lambda: jl.trace(cooke, rays, chunk=0).origin, "chunk")
    probe("trace chunk 'Auto'", lambda: jl.trace(cooke, rays, chunk="Auto").origin, "chunk")
    probe("trace_path upto 99", lambda: jl.trace_path(cooke, rays, upto=99).origin, "upto")
    probe("trace_backward upto 99", lambda: jl.trace_backward(cooke, rays, upto=99).origin, "upto")
    probe("Rays wavelength nm", lambda: jl.trace(cooke, jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0.0, 0.0, 1.0]]), wavelength=jnp.array([550.0]))).origin, "µm")
    probe("Rays direction not unit", lambda: jl.Rays(origin=jnp.zeros((1, 3)), direction=jnp.array([[0.0, 0.0, 2.0]]), wavelength=jnp.array([0.55])), "direction")
    probe("Rays origin shape (1, 2)", lambda: jl.Rays(origin=jnp.zeros((1, 2)), direction=jnp.array([[0.0, 0.0, 1.0]]), wavelength=jnp.array([0.55])), "origin")


# ----------------------------------------------------------------------------- lens consistency
def lens_consistency():
    s, t, m = cooke.surfaces, cooke.thickness, cooke.materials
    probe("Lens stop 6 of 6 surfaces", lambda: jl.Lens(s, t, m, stop=len(s), wavelengths=cooke.wavelengths), "stop")
    probe("Lens primary 3 of 3", lambda: jl.Lens(s, t, m, wavelengths=cooke.wavelengths, primary=3), "primary")
    probe("Lens thickness one short", lambda: jl.Lens(s, t[:-1], m), "thickness")
    probe("Lens materials one short", lambda: jl.Lens(s, t, m[:-1]), "materials")
    probe("Lens materials names", lambda: jl.Lens(s, t, ("N-BK7",) * len(s)), "material")
    probe("Lens epd 0", lambda: jl.Lens(s, t, m, epd=0.0), "epd")
    probe("Lens epd complex", lambda: jl.Lens(s, t, m, epd=10 + 0j), "epd")
    probe("Lens thickness bool", lambda: jl.Lens(s, jnp.ones(len(s), bool), m), "thickness")
    probe("Lens wavelengths []", lambda: jl.Lens(s, t, m, wavelengths=[]), "wavelengths")
    probe("Lens fields []", lambda: jl.Lens(s, t, m, fields=[]), "fields")
    probe("Lens fields 2-D [F,3]", lambda: jl.Lens(s, t, m, fields=jnp.zeros((2, 3))), "fields")
    probe("Lens object_distance -100", lambda: jl.Lens(s, t, m, object_distance=-100.0), "object_distance")
    probe("Lens object_distance 0", lambda: jl.Lens(s, t, m, object_distance=0.0), "object_distance")
    probe("Lens mirrors [99]", lambda: jl.Lens(s, t, m, mirrors=[99]), "mirrors")
    probe("Lens obscurations surface 99", lambda: jl.Lens(s, t, m, obscurations=[(99, 0.0, 1.0)]), "obscuration")
    # surfaces crossing: a biconvex element 0.1 mm thick, radius 10 mm, semi-diameter 8 mm
    thin = jl.Lens((jl.Sphere(0.1, semi_diameter=8.0), jl.Sphere(-0.1, semi_diameter=8.0)), jnp.array([0.1, 10.0]), (jl.get_material("N-BK7"), jl.Air()), epd=4.0, wavelengths=[0.5876])
    probe("self_intersection of a crossed element", lambda: bool(jl.analysis.self_intersection(thin).ok), good=True)
    probe("rms_spot of a crossed element (its edge is crossed; rays near the axis)", lambda: jl.analysis.rms_spot(thin).polychromatic, good=True)
    probe("Lens negative thickness without mirrors (documented: as Zemax, surfaces may step back; self_intersection checks crossings)", lambda: jl.Lens(s, t.at[2].set(-5.0), m, wavelengths=cooke.wavelengths).thickness, good=True)
    probe("Sphere semi_diameter -1", lambda: jl.Sphere(0.1, semi_diameter=-1.0), "semi_diameter")
    probe("Sphere c 'x'", lambda: jl.Sphere("0.1"), "c")
    probe("Sphere c complex", lambda: jl.Sphere(0.1 + 0j), "c")
    probe("Sphere c nan", lambda: jl.Sphere(np.nan), "c")
    probe("EvenAsphere coeffs 2-D", lambda: jl.EvenAsphere(c=0.01, coeffs=jnp.zeros((2, 2))), "coeffs")
    probe("Standard k inf", lambda: jl.Standard(c=0.01, k=np.inf), "k")
    probe("Sensor pixel_size 0", lambda: jl.Sensor(resolution=(8, 8), pixel_size=0.0), "pixel_size")
    probe("Sensor resolution (8,)", lambda: jl.Sensor(resolution=(8,), pixel_size=0.01), "resolution")
    probe("Sensor pixel_size 5 (µm?) (documented: mm; plausible for big pixels)", lambda: jl.Sensor(resolution=(8, 8), pixel_size=5.0).pixel_size, good=True)
    probe("Lens.astype int32", lambda: cooke.astype(jnp.int32), "dtype")
    probe("Lens.astype 'float64' (control)", lambda: cooke.astype("float64").epd.dtype, good=True)
    probe("ModelGlass vd nan", lambda: jl.ModelGlass(1.5, np.nan), "vd")
    probe("ModelGlass nd 60 vd 1.5 (swapped)", lambda: jl.ModelGlass(60.0, 1.5), "nd")
    probe("ModelGlass nd complex", lambda: jl.ModelGlass(1.5 + 0j, 50.0), "nd")
    probe("Sellmeier B shape (2,) C (3,)", lambda: jl.Sellmeier([1.0, 0.2], [0.01, 0.02, 100.0]), "B")
    probe("Schott 5 coeffs", lambda: jl.Schott([2.27, -0.01, 0.01, 0, 0]), "coeffs")
    probe("Tabulated wavelengths in nm", lambda: jl.Tabulated([450.0, 550.0, 650.0], [1.53, 1.52, 1.515]), "µm")
    probe("Tabulated index 0.9", lambda: jl.Tabulated([0.45, 0.55], [0.9, 1.5]), "indices")


# ----------------------------------------------------------------------------- names
def names():
    probe("get_material 'NBK7'", lambda: jl.get_material("NBK7"), "N-BK7")
    probe("get_material 'n-bk7 ' (control: trailing space)", lambda: jl.get_material("n-bk7 ").name, good=True)
    probe("get_material catalogs 'SCHOT'", lambda: jl.get_material("N-BK7", catalogs="SCHOT"), "SCHOTT")
    probe("get_material nd='1.5'", lambda: jl.get_material("XXX", nd="1.5", vd=60.0), "nd")
    probe("glass_info 'N-SF6X'", lambda: jl.glass_info("N-SF6X"), "N-SF6")
    probe("catalog_names 'SHOTT'", lambda: jl.catalog_names("SHOTT"), "SCHOTT")
    probe("catalog_names 3", lambda: jl.catalog_names(3), "catalog")
    probe("nearest_glasses count 0", lambda: jl.catalog.nearest_glasses(1.5, 60.0, count=0), "count")
    probe("nearest_glasses nd nan", lambda: jl.catalog.nearest_glasses(np.nan, 60.0), "nd")
    probe("nearest_glasses nd 60 vd 1.5 (swapped)", lambda: jl.catalog.nearest_glasses(60.0, 1.5), "nd")
    probe("load_agf missing (FileNotFoundError naming the path)", lambda: jl.load_agf("/nonexistent/x.agf"), "x.agf")
    probe("register_catalog {'X': 1.5}", lambda: jl.register_catalog({"X": 1.5}, "MINE"), "material")
    tmp = tempfile.mkdtemp()
    probe("load .zmx missing (FileNotFoundError naming the path)", lambda: jl.load(os.path.join(tmp, "x.zmx")), "x.zmx")
    probe("load unknown_glass 'Error'", lambda: jl.load(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx"), unknown_glass="Error"), "unknown_glass")
    probe("load dtype int32", lambda: jl.load(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx"), dtype=jnp.int32), "dtype")
    probe("load config 0", lambda: jl.load(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx"), config=0), "config")
    probe("load strict 'yes'", lambda: jl.load(os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx"), strict="yes"), "strict")
    probe("save .txt", lambda: jl.save(cooke, os.path.join(tmp, "a.txt")), "extension")
    probe("save unknown option", lambda: jl.save(cooke, os.path.join(tmp, "a.json"), indnt=2), "indnt")
    bad = os.path.join(tmp, "bad.zmx")
    with open(bad, "w") as fh:
        fh.write("VERS 190513 80 123457 L123457\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 1.0E+1\nSURF 0\n  CURV abc\n  DISZ INFINITY\n")
    probe("load .zmx CURV abc (names the line)", lambda: jl.load(bad), "bad.zmx:6")
    probe("images.scene 'Astronaut' (case)", lambda: jl.images.scene("Astronaut", (8, 8)).shape, "astronaut")


# ----------------------------------------------------------------------------- CLIs
def clis():
    from jaxlens import __main__ as cli_main
    from jaxlens.experiments import classical
    lens_path = os.path.join(ROOT, "jaxlens/data/lenses/cooke_triplet.zmx")
    tmp = tempfile.mkdtemp()

    def cli(f):
        f.cli = True
        return f

    probe("python -m jaxlens (no command)", cli(lambda: cli_main.main([])), "command")
    probe("python -m jaxlens reprot", cli(lambda: cli_main.main(["reprot", lens_path])), "report")
    rep = cli(lambda *a: cli_main.main(["report", *a]))
    probe("report --fields ''", cli(lambda: rep(lens_path, "--fields", "")), "--fields")
    probe("report --fields 1,,2", cli(lambda: rep(lens_path, "--fields", "1,,2")), "--fields")
    probe("report --wavelengths 0.5876,abc", cli(lambda: rep(lens_path, "--wavelengths", "0.5876,abc")), "--wavelengths")
    probe("report --wavelengths 5e-4 (mm?)", cli(lambda: rep(lens_path, "--wavelengths", "5e-4")), "µm")
    probe("report --wavelengths 2.6 (outside N-SK16?)", cli(lambda: rep(lens_path, "--wavelengths", "2.6")), "µm")
    probe("report --fields -95", cli(lambda: rep(lens_path, "--fields", "-95")), "--fields")
    probe("report --config -1", cli(lambda: rep(lens_path, "--config", "-1")), "config", "from 1")
    probe("report --unknown-glass model (typo of a choice)", cli(lambda: rep(lens_path, "--unknown-glass", "modle")), "--unknown-glass")
    probe("report .zmx with CURV abc", cli(lambda: rep(os.path.join(tmp, "..", os.path.basename(tmp), "x.zmx"))), "x.zmx")
    c = cli(lambda *a: classical.main([*a, "--out", os.path.join(tmp, "c"), "--quiet"]))
    for a in (("--fov", "1.4"), ("--fov", "nan"), ("--fnum", "-2"), ("--fnum", "inf"), ("--elements", "2.5"),
              ("--track", "7000"), ("--sensor-diagonal", "7660"), ("--stop", "-1"), ("--stop", "1.5"),
              ("--materials", "E48R"), ("--materials", "E48R,OKP4,E48R,OKP4,E48R,AIR"), ("--materials", "E48R,OKP4,E48R,OKP4,E48R,OKP5"),
              ("--materials", "E48R,,E48R,OKP4,E48R,OKP4"), ("--bfl", "0"), ("--bfl", "-1"),
              ("--asphere-terms", "13"), ("--asphere-terms", "2.5"), ("--fov-start", "0"), ("--fnum-start", "nan"),
              ("--polish-steps", "-1"), ("--first-seed", "-1"), ("--first-seed", "1.5"), ("--ablation-seeds", "0"),
              ("--columns", "nope"), ("--material-catalogs", "SCHOT"), ("--select-materials", "Fixed"),
              ("--solver", "Adam"), ("--tolerance-threshold", "nan"), ("--devices", "-1"), ("--seed-list", ""),
              ("--seed-list", "1,1")):
        word = {"--fov": "fov", "--track": "total_track", "--sensor-diagonal": "sensor_diagonal",
                "--materials": "material"}.get(a[0], a[0])
        probe(f"classical {' '.join(a) or repr(a)}", cli(lambda: c(*a)), word)


# ----------------------------------------------------------------------------- more analyses
def analyses_more():
    from jaxlens.analysis import field_curvature, opd, opd_fan, ray_fan, wavefront
    A = jl.analysis
    probe("ray_fan n 0", lambda: ray_fan(cooke, 0.0, n=0).tangential, "n")
    probe("ray_fan n 2.5", lambda: ray_fan(cooke, 0.0, n=2.5).tangential, "n")
    probe("ray_fan field [0, 10] (documented: one (θx, θy) pair)", lambda: ray_fan(cooke, [0.0, 10.0]).tangential, good=True)
    probe("ray_fan aim 'Real'", lambda: ray_fan(cooke, 0.0, aim="Real").tangential, "aim")
    probe("field_curvature fields []", lambda: field_curvature(cooke, fields=[]).sagittal, "fields")
    probe("field_curvature fields [95]", lambda: field_curvature(cooke, fields=[95.0]).sagittal, "field", "90")
    probe("opd pupil shape (3,)", lambda: opd(cooke, 0.0, jnp.zeros(3)), "pupil")
    probe("opd pupil [[2, 0]] (outside the pupil)", lambda: opd(cooke, 0.0, jnp.array([[2.0, 0.0]])), "pupil")
    probe("opd reference 'Sphere'", lambda: opd(cooke, 0.0, jnp.zeros((1, 2)), reference="Sphere"), "reference")
    probe("opd_fan n 1", lambda: opd_fan(cooke, 0.0, n=1).opd, "n")
    probe("wavefront grid 65.5", lambda: wavefront(cooke, 0.0, grid=65.5).rms, "grid")
    probe("wavefront grid 100000", lambda: wavefront(cooke, 0.0, grid=100000).rms, "grid")
    probe("wavefront reference 'chief '", lambda: wavefront(cooke, 0.0, reference="chief ", grid=9).rms, "reference")
    probe("wavefront field [0,1,2]", lambda: wavefront(cooke, [0.0, 1.0, 2.0], grid=9).rms, "field")
    probe("encircled_energy pupil_side 1", lambda: A.encircled_energy(cooke, 0.0, [0.01], pupil_side=1).energy, "pupil_side")
    probe("encircled_energy subsamples 0", lambda: A.encircled_energy(cooke, 0.0, [0.01], subsamples=0).energy, "subsamples")
    probe("encircled_energy radii 2-D (documented: any shape, returned flattened)", lambda: A.encircled_energy(cooke, 0.0, [[0.01]]).energy, good=True)
    probe("distortion fields complex", lambda: A.distortion(cooke, [5j]).percent_ftan, "fields")
    probe("chief_ray depth nan", lambda: A.chief_ray(cooke, 0.0, depth=np.nan).origin, "depth")
    probe("spot_rays pupil 3-D (documented: a batch of pupil points)", lambda: A.spot_rays(cooke, 0.0, pupil=jnp.zeros((2, 2, 2))).origin.shape, good=True)
    probe("rms_spot reference 'chief ray'", lambda: A.rms_spot(cooke, reference="chief ray").polychromatic, "reference")
    probe("rms_spot cellphone6 (aspheres) newton_iters 1e9", lambda: A.rms_spot(jl.zoo.cellphone6(), newton_iters=10**9).polychromatic, "newton_iters", "1000")
    probe("wavefront newton_iters 5000", lambda: wavefront(cooke, 0.0, grid=9, newton_iters=5000).rms, "newton_iters", "1000")
    probe("seidel of an afocal lens?", lambda: A.seidel(cooke, field=0.0, wavelength=0.5876).per_surface.shape, good=True)
    probe("zernike_terms terms 0", lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(3), terms=0), "terms")
    probe("zernike_fit all points at the centre", lambda: A.zernike_fit(jnp.zeros(40), jnp.zeros(40), jnp.zeros(40), terms=4).coefficients, "cannot determine")
    probe("zernike_fit points on a line (y = 0)", lambda: A.zernike_fit(jnp.linspace(-1, 1, 40), jnp.zeros(40), jnp.zeros(40), terms=4).coefficients, "cannot determine")
    probe("zernike_fit mask float 0/1 (documented: nonzero = fit)", lambda: A.zernike_fit(*jnp.meshgrid(jnp.linspace(-0.7, 0.7, 9), jnp.linspace(-0.7, 0.7, 9)), jnp.ones((9, 9)), terms=4, mask=jnp.ones((9, 9))).coefficients, good=True)
    probe("zernike_fit values nan", lambda: A.zernike_fit(jnp.linspace(-0.5, 0.5, 40), jnp.zeros(40), jnp.full(40, jnp.nan), terms=4).coefficients, "valid points")
    probe("marechal_strehl complex", lambda: A.marechal_strehl(0.1 + 0j), "rms_waves")


# ----------------------------------------------------------------------------- tolerance API
def tolerance_api():
    T = jl.tolerance
    probe("ToleranceModel tolerances dict", lambda: T.ToleranceModel(cooke, tolerances={"thickness": 0.02}), "tolerances")
    probe("ToleranceModel batch 0", lambda: T.ToleranceModel(cooke, batch=0), "batch")
    probe("ToleranceModel apertures 'Open'", lambda: T.ToleranceModel(cooke, apertures="Open"), "apertures")
    probe("ToleranceModel fields [95]", lambda: T.ToleranceModel(cooke, fields=[95.0]), "field")
    probe("ToleranceModel field_weights [-1, 1, 1]", lambda: T.ToleranceModel(cooke, field_weights=[-1.0, 1.0, 1.0]), "weights")
    probe("ToleranceModel field_weights wrong length", lambda: T.ToleranceModel(cooke, field_weights=[1.0]), "weights")
    probe("ToleranceModel wavelengths 587.6", lambda: T.ToleranceModel(cooke, wavelengths=[587.6]), "µm")
    probe("yield_fraction threshold -1", lambda: T.yield_fraction(np.ones(4), -1.0), "threshold")
    probe("yield_fraction min_valid 2", lambda: T.yield_fraction(np.ones(4), 10.0, np.ones(4), min_valid=2.0), "min_valid")
    probe("yield_fraction []", lambda: T.yield_fraction(np.ones(0), 10.0), "rms")
    probe("percentile q 150", lambda: T.percentile(np.ones(4), 150.0), "q")
    probe("percentile q 0.9 (fraction where percent meant? documented: percent)", lambda: T.percentile(np.arange(10.0), 0.9), good=True)
    probe("percentile []", lambda: T.percentile(np.ones(0), 50.0), "values")
    probe("symmetric_fields []", lambda: T.symmetric_fields([]), "fields")
    probe("normalised_weights [0, 0]", lambda: T.normalised_weights([0.0, 0.0]), "weights")
    probe("normalised_weights [-1, 2]", lambda: T.normalised_weights([-1.0, 2.0]), "weights")
    model = T.ToleranceModel(cooke, fields=[0.0], wavelengths=[0.5876])
    probe("monte_carlo trials 0", lambda: T.monte_carlo(model, trials=0, threshold_um=10.0, mtf_frequency=50.0), "trials")
    probe("monte_carlo threshold_um nan", lambda: T.monte_carlo(model, trials=2, threshold_um=np.nan, mtf_frequency=50.0), "threshold")
    probe("monte_carlo mtf_frequency -1", lambda: T.monte_carlo(model, trials=2, threshold_um=10.0, mtf_frequency=-1.0), "mtf_frequency")
    probe("monte_carlo key int", lambda: T.monte_carlo(model, trials=2, key=3, threshold_um=10.0, mtf_frequency=50.0), "key")
    probe("sensitivity check -1", lambda: T.sensitivity(model, check=-1), "check")
    probe("sample_perturbations trials 0", lambda: T.sample_perturbations(model, 0, jax.random.PRNGKey(0)), "trials")


# ----------------------------------------------------------------------------- paraxial API
def paraxial_api():
    P = jl.paraxial
    probe("image_height field 95", lambda: P.image_height(cooke, 95.0), "field", "90")
    probe("image_height field '10'", lambda: P.image_height(cooke, "10"), "field")
    probe("paraxial_chief_ray field 95", lambda: P.paraxial_chief_ray(cooke, 95.0), "field", "90")
    probe("system_matrix start 99", lambda: P.system_matrix(cooke, start=99), "start")
    probe("system_matrix end 99", lambda: P.system_matrix(cooke, end=99), "end")
    probe("system_matrix start 3 end 1", lambda: P.system_matrix(cooke, start=3, end=1), "start")
    probe("system_matrix start 1.0", lambda: P.system_matrix(cooke, start=1.0), "start")
    probe("system_matrix start -1", lambda: P.system_matrix(cooke, start=-1), "start")
    probe("entrance_pupil_z wavelength 587.6", lambda: P.entrance_pupil_z(cooke, 587.6), "µm")
    probe("marginal_ray wavelength [0.5, 0.6]", lambda: P.marginal_ray(cooke, [0.5, 0.6]), "wavelength")
    probe("working_fnum depth '100'", lambda: P.working_fnum(cooke, "100"), "depth")
    probe("surface_power wavelength 587.6", lambda: P.surface_power(cooke.surfaces[0], 1.0, 1.5, 587.6), "µm")
    probe("surface_power n1 0", lambda: P.surface_power(cooke.surfaces[0], 0.0, 1.5), "n1")


run((known_gaps, dtypes_and_shapes, tracing, lens_consistency, names, clis, analyses_more,
     tolerance_api, paraxial_api))
