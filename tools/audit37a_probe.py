# ruff: noqa: E501, E731
"""Round-37a bad-input probes: the freeform and diffractive surfaces (Toroidal, Biconic,
ZernikeSag, QTypeAsphere, XYPolynomial, Binary2, Grating, CoordinateBreak) given bad
coefficients, shapes and units; ``Aperture`` and ``Sensor``; formula and table materials;
AGF records whose Vd disagrees with their formula; JSON lens files; the analyses' field,
wavelength and sampling arguments; ``DesignSpec``/``DesignConfig``; and a few command-line
options. The table of ``tools/probe_table.py`` (probe | outcome | what happened).

Gaps found and fixed:
1. AGF: an NM record's Vd was kept whatever its CD formula gave (round 36a's item 3): Vd 54.17
   or 65.5 on N-BK7's coefficients (64.17) went to ``glass_info``, the nearest-glass
   suggestions and GLAS lines. Now refused beyond 1 % with the file's line
   (``agf.VD_TOLERANCE``; the shipped catalogs' largest gap is 0.33 %, SUMITA K-LaSFn21);
   Vd 0 (unknown) and records whose LD range leaves out the F or C line are not checked.
2. First the writer: ``save_zmx`` wrote a glass no Zemax formula holds (a ``Tabulated``
   table, …) as a Schott fit whose NM record carried the material's own nd and Vd (a table
   of N-BK7 at 0.45/0.55/0.65 µm: Vd 65.78, linear in 1/λ² between its entries, beside the
   fit's 64.00, 2.7 %); the record and the GLAS lines now carry the fit's nd and Vd
   (``_GlassWriter._cd``).
3. ``glass_info`` of a glass of a registered AGF catalog (records are read lazily) gave the
   NM record's Vd unchecked: it now checks the record first.
4. ``Aperture("rect", "2", 1.0)`` read the string as 2 mm (every surface refuses a string).
5. Vague: a JSON ``primary_wavelength_nm`` that is not one of the wavelengths now lists them.

Found and left: ``design.sensor_field_grid(spec, n=1)`` (and ``evaluate_design(n=1)``) gives
the sensor's corner alone (the grid runs corner to corner), where a 1 × 1 "grid" reads as
the centre; a refusal would change round-audit's documented range [1, 257]. The
nearest-glass suggestions still read unconverted records' nd and Vd unchecked.

The controls (``good=True``) are behaviours judged right: a fractional Binary2 order (a
phase scale, as Zemax takes it), a one-node ``Tabulated`` (documented non-dispersive),
unsorted table wavelengths (sorted with their indices), a negative Sellmeier C (a fit term),
fields beyond the lens's (rays flagged invalid), Q-type polynomials beyond ρ_n (documented).

Before (base de57757, an archive) and after (branch probe37a), the same probes,
``PYTHONPATH=<tree> python tools/audit37a_probe.py`` from the tree's root, 192 probes,
about 5 minutes each way on 2 shared cores:
    before: clear error: 163, ok: 23, silent wrong: 5, vague error: 1
    after:  clear error: 168, ok: 23, silent wrong: 1 (sensor_field_grid n 1, left)

Probe (before -> after):
    agf NM Vd 54.17 (10 units off)                   silent wrong -> clear error
    agf NM Vd 65.5 (2 % off)                         silent wrong -> clear error
    register_catalog AGF, Vd 40, then glass_info     silent wrong -> clear error
    Aperture half_x '2' (a string)                   silent wrong -> clear error
    json primary_wavelength_nm not among them        vague error  -> clear error
The other 187 rows are the same before and after.
"""

import json
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import dataclasses  # noqa: E402

import jax  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import COOKE, cli, edof_check, fresh, patched, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import analysis as A  # noqa: E402
from jaxlens import design as D  # noqa: E402

cooke = jl.load(COOKE)
L = lambda **k: dataclasses.replace(cooke, **k)
PUPIL = jl.sampling.pupil_grid(5)


def with_surface(i, s):
    """The Cooke triplet with its surface i replaced by s."""
    surf = list(cooke.surfaces)
    surf[i] = s
    return L(surfaces=tuple(surf))


def surfaces():
    from jaxlens.optics.toroidal import Toroidal

    probe("Toroidal cx NaN", lambda: Toroidal(c=0.01, cx=float("nan")), "cx", "finite")
    probe("Toroidal coeffs 2-D", lambda: Toroidal(c=0.01, coeffs=np.zeros((2, 2))), "coeffs", "1-D")
    probe("Toroidal cx 0.5 with semi_diameter 5 (no section)", lambda: jl.efl(with_surface(2, Toroidal(c=-0.03, cx=0.5, semi_diameter=5.0))), "cx", "semi_diameter")
    probe("Biconic cx NaN", lambda: jl.Biconic(c=0.01, cx=float("nan")), "cx", "finite")
    probe("Biconic kx 1e9", lambda: jl.Biconic(c=0.01, cx=0.01, kx=1e9, semi_diameter=5.0), "kx")
    probe("Biconic cx '0.02'", lambda: jl.Biconic(c=0.01, cx="0.02"), "cx")
    probe("Biconic cx [0.01, 0.02] in a Lens", lambda: jl.efl(with_surface(2, jl.Biconic(c=-0.03, cx=np.array([0.01, 0.02]), semi_diameter=4.0))), "cx", "shape")
    probe("ZernikeSag zernike 2-D", lambda: jl.ZernikeSag(zernike=np.zeros((2, 3))), "zernike", "1-D")
    probe("ZernikeSag norm_radius -2", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), norm_radius=-2.0), "norm_radius", "mm")
    probe("ZernikeSag ordering 'noll'", lambda: jl.ZernikeSag(ordering="noll"), "ordering", "standard")
    probe("ZernikeSag extrapolate 'no'", lambda: jl.ZernikeSag(extrapolate="no"), "extrapolate")
    probe("ZernikeSag 1000 fringe terms", lambda: jl.ZernikeSag(zernike=np.zeros(1000), ordering="fringe"), "fringe", "at most")
    probe("ZernikeSag decenter_y inf", lambda: jl.ZernikeSag(zernike=(0.0, 1e-3), decenter_y=float("inf")), "decenter_y", "finite")
    probe("QTypeAsphere qtype 'Qcon '", lambda: jl.QTypeAsphere(qtype="Qcon "), "qtype")
    probe("QTypeAsphere coeffs 2-D", lambda: jl.QTypeAsphere(coeffs=np.zeros((2, 2)), norm_radius=5.0), "coeffs")
    probe("QTypeAsphere norm_radius 0", lambda: jl.QTypeAsphere(coeffs=(1e-3,), norm_radius=0.0), "norm_radius", "(0, inf) mm")
    probe("QTypeAsphere coeffs NaN", lambda: jl.QTypeAsphere(coeffs=(1e-3, float("nan")), norm_radius=5.0), "coeffs", "finite")
    probe("XYPolynomial coeffs 2-D", lambda: jl.XYPolynomial(coeffs=np.zeros((3, 3)), norm_radius=5.0), "coeffs")
    probe("XYPolynomial norm_radius inf", lambda: jl.XYPolynomial(coeffs=(0.0, 1e-3), norm_radius=float("inf")), "norm_radius")
    probe("XYPolynomial coeffs inf", lambda: jl.XYPolynomial(coeffs=(0.0, float("inf"))), "coeffs", "finite")
    probe("Binary2 order 0.5 (control: Zemax takes a fractional M, a phase scale)", lambda: jl.Binary2(order=0.5, phase_coeffs=(100.0,), norm_radius=5.0).order, good=True)
    probe("Binary2 phase_coeffs 2-D", lambda: jl.Binary2(phase_coeffs=np.zeros((2, 2)), norm_radius=5.0), "phase_coeffs")
    probe("Binary2 norm_radius -1", lambda: jl.Binary2(phase_coeffs=(100.0,), norm_radius=-1.0), "norm_radius")
    probe("Binary2 phase_coeffs NaN", lambda: jl.Binary2(phase_coeffs=(float("nan"),), norm_radius=5.0), "phase_coeffs", "finite")
    probe("Grating order 1.5", lambda: jl.Grating(lines_per_um=0.5, order=1.5), "order", "whole number")
    probe("Grating lines_per_um -0.5", lambda: jl.Grating(lines_per_um=-0.5), "lines_per_um")
    probe("Grating lines_per_um NaN", lambda: jl.Grating(lines_per_um=float("nan")), "lines_per_um", "finite")
    probe("Grating order True", lambda: jl.Grating(lines_per_um=0.5, order=True), "order")
    probe("CoordinateBreak order 2", lambda: jl.CoordinateBreak(order=2), "order", "0 (decenter", "1 (tilt")
    probe("CoordinateBreak decenter_x NaN", lambda: jl.CoordinateBreak(decenter_x=float("nan")), "decenter_x", "finite")
    probe("CoordinateBreak tilt_z 1e6 (control: an angle, modulo 360°)", lambda: jl.CoordinateBreak(tilt_z=1e6).tilt_z, good=True)
    probe("CoordinateBreak k 1", lambda: jl.CoordinateBreak(k=1.0), "CoordinateBreak", "k")
    probe("TiltedPlane tan_x NaN", lambda: jl.TiltedPlane(tan_x=float("nan")), "tan_x", "finite")
    probe("OddAsphere coeffs 2-D", lambda: jl.OddAsphere(coeffs=np.zeros((2, 4))), "coeffs")
    probe("Hybrid odd_x 2-D", lambda: jl.Hybrid(odd_x=np.zeros((2, 2))), "odd_x")
    probe("Standard semi_diameter 0", lambda: jl.Standard(c=0.01, semi_diameter=0.0), "semi_diameter", "(0, inf] mm")
    probe("Standard k NaN", lambda: jl.Standard(c=0.01, k=float("nan")), "k", "finite")


def apertures_sensor():
    probe("Aperture shape 'hexagon'", lambda: jl.Aperture("hexagon", 1.0, 1.0), "shape", "circle", "rect")
    probe("Aperture half_x 0", lambda: jl.Aperture("rect", 0.0, 1.0), "half_x", "> 0")
    probe("Aperture half_y -1", lambda: jl.Aperture("ellipse", 1.0, -1.0), "half_y", "> 0")
    probe("Aperture half_x NaN", lambda: jl.Aperture("rect", float("nan"), 1.0), "half_x", "finite")
    probe("Aperture decenter_x inf", lambda: jl.Aperture("rect", 1.0, 1.0, decenter_x=float("inf")), "decenter_x", "finite")
    probe("Aperture blocks 'yes'", lambda: jl.Aperture("rect", 1.0, 1.0, blocks="yes"), "blocks")
    probe("Aperture half_x '2' (a string)", lambda: jl.Aperture("rect", "2", 1.0), "half_x", "(mm)", "'2'")
    probe("Sensor resolution (0, 64)", lambda: jl.Sensor((0, 64), 0.005), "resolution")
    probe("Sensor resolution (64.5, 64)", lambda: jl.Sensor((64.5, 64), 0.005), "resolution", "whole numbers")
    probe("Sensor resolution 64 (not a pair)", lambda: jl.Sensor(64, 0.005), "resolution")
    probe("Sensor pixel_size -0.005", lambda: jl.Sensor((64, 64), -0.005), "pixel_size", "mm")
    probe("Sensor pixel_size 5 mm (control: no bound on a pixel)", lambda: jl.Sensor((64, 64), 5.0).pixel_size, good=True)
    probe("Sensor pixel_size NaN", lambda: jl.Sensor((64, 64), float("nan")), "pixel_size")
    probe("Sensor pixel_size (0.005, 0.005) (one pitch)", lambda: jl.Sensor((64, 64), (0.005, 0.005)).pixel_size, "pixel_size", "a finite number")


def materials():
    probe("Sellmeier B, C of different lengths", lambda: jl.Sellmeier(B=(1.0, 0.2), C=(0.006,)), "B", "C")
    probe("Sellmeier C -0.01 (control: a fit term, not a pole)", lambda: jl.Sellmeier(B=(1.0,), C=(-0.01,)).index(0.55), good=True)
    probe("Sellmeier B NaN", lambda: jl.Sellmeier(B=(float("nan"),), C=(0.006,)), "B", "finite")
    probe("Sellmeier B 2-D", lambda: jl.Sellmeier(B=np.ones((2, 2)), C=np.ones((2, 2)) * 0.01), "B")
    probe("Schott 7 coefficients", lambda: jl.Schott(coeffs=(2.27, -0.01, 0.01, 0.0, 0.0, 0.0, 0.0)), "coeffs", "6")
    probe("Schott A0 -1 (n² < 0)", lambda: jl.efl(L(materials=(jl.Schott(coeffs=(-1.0, 0, 0, 0, 0, 0)),) + cooke.materials[1:])), "Schott", "index")
    probe("Tabulated wavelengths decreasing (control: sorted, 1.51716 at 0.55)", lambda: jl.Tabulated(wavelengths=(0.7, 0.6, 0.5), indices=(1.51, 1.515, 1.52)).index(0.55), good=True)
    probe("Tabulated wavelengths unsorted (control: sorted with their indices)", lambda: jl.Tabulated(wavelengths=(0.5, 0.7, 0.6), indices=(1.52, 1.51, 1.515)).index(0.65), good=True)
    probe("Tabulated one entry, index at 0.6 (control: documented non-dispersive)", lambda: jl.Tabulated(wavelengths=(0.55,), indices=(1.5,)).index(0.6), good=True)
    probe("Tabulated indices 0.9", lambda: jl.Tabulated(wavelengths=(0.5, 0.6), indices=(0.9, 0.95)), "indices", "1")
    probe("Tabulated lengths differ", lambda: jl.Tabulated(wavelengths=(0.5, 0.6, 0.7), indices=(1.5, 1.49)), "wavelengths", "indices")
    probe("Tabulated wavelengths in nm", lambda: jl.Tabulated(wavelengths=(500.0, 600.0), indices=(1.52, 1.51)), "wavelengths", "µm")
    probe("Tabulated index outside data (0.8 µm of 0.5-0.6)", lambda: jl.Tabulated(wavelengths=(0.5, 0.6), indices=(1.52, 1.51)).index(0.8), "0.8", "0.4995")
    probe("Tabulated wavelength_range (0.3, 2) beyond its table, index at 1 µm", lambda: jl.Tabulated(wavelengths=(0.5, 0.6), indices=(1.52, 1.51), wavelength_range=(0.3, 2.0)).index(1.0), "1 µm", "0.4995")
    probe("ModelGlass nd 15", lambda: jl.ModelGlass(nd=15.0, vd=40.0), "nd")
    probe("ModelGlass vd -5", lambda: jl.ModelGlass(nd=1.5, vd=-5.0), "vd")
    probe("ModelGlass vd 0.5 (n below 1 in the blue)", lambda: jl.efl(L(materials=(jl.ModelGlass(nd=1.5, vd=0.5),) + cooke.materials[1:])), "vd")
    probe("ModelGlass nd 0.9", lambda: jl.ModelGlass(nd=0.9, vd=40.0), "nd", "1")
    probe("get_material nd '1.5'", lambda: jl.get_material("XYZ123", nd="1.5", vd=40.0), "nd")
    probe("glass_info 'nbk-7'", lambda: jl.glass_info("nbk-7"), "N-BK7")
    probe("register_catalog mapping with a number", lambda: jl.register_catalog({"G1": 1.5}, name="R37A"), "G1", "material")
    probe("register_catalog name 'SCHOTT' (control: documented, searched first), N-BK7", lambda: (jl.register_catalog({"G1": jl.ModelGlass(1.5, 50.0)}, name="SCHOTT"), jl.glass_info("N-BK7"), jl.register_catalog({"G1": jl.ModelGlass(1.5, 50.0)}, name="SCHOTT37"))[1], good=True)
    probe("register_catalog name with a space (control), then get_material", lambda: (jl.register_catalog({"G1": jl.ModelGlass(1.5, 50.0)}, name="MY CAT"), jl.get_material("G1", "MY CAT"))[1].nd, good=True)
    probe("register_catalog empty mapping", lambda: jl.register_catalog({}, name="EMPTY37"), "no material")


AGF = """CC test catalog
NM TESTG 2 517642 1.5168 64.17 0 0 0
CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653
LD 0.3 2.5
"""


def agf_file(text, name="T37.agf"):
    path = os.path.join(fresh("agf"), name)
    with open(path, "w") as f:
        f.write(text)
    return path


def agf():
    load = lambda text: lambda: list(jl.load_agf(agf_file(text)).values())[0].catalog_vd
    probe("agf NM Vd 54.17 (10 units off)", load(AGF.replace("1.5168 64.17", "1.5168 54.17")), "Vd 54.17", "64.1", ":2")
    probe("agf NM Vd 65.5 (2 % off)", load(AGF.replace("1.5168 64.17", "1.5168 65.5")), "Vd 65.5", ":2")
    probe("agf NM Vd 64.3 (control: 0.2 %)", load(AGF.replace("1.5168 64.17", "1.5168 64.3")), good=True)
    probe(
        "register_catalog AGF, Vd 40, then glass_info",
        lambda: (jl.register_catalog(agf_file(AGF.replace("1.5168 64.17", "1.5168 40"), "R37V.agf")), jl.glass_info("TESTG", "R37V"))[1],
        "Vd 40",
        "64.1",
    )
    probe("agf CD with 5 of Sellmeier 1's 6 coefficients", load(AGF.replace(" 103.560653", "")), ":2", "nd 1.5168")
    probe("agf NM without Vd", load(AGF.replace("1.5168 64.17 0 0 0", "1.5168")), "NM", ":2")

    def tab_roundtrip():
        bk7 = jl.get_material("N-BK7")
        wl = np.array([0.45, 0.55, 0.65])
        t = jl.Tabulated(wl, np.asarray(bk7.index(wl)), name="TAB")
        mats = tuple(t if not isinstance(m, jl.Air) else m for m in cooke.materials)
        d = fresh("tabzmx")
        lens = L(materials=mats, wavelengths=(0.47, 0.55, 0.63))
        jl.save(lens, os.path.join(d, "t.zmx"))
        agfs = [f for f in os.listdir(d) if f.upper().endswith(".AGF")]
        return [jl.load_agf(os.path.join(d, f))["TAB"].catalog_vd for f in agfs]

    probe("save_zmx Tabulated glass, its side AGF read back (control)", tab_roundtrip, good=True)


def json_file(mut=None, raw=None):
    with open(COOKE) as f:
        d = json.load(f)
    if mut:
        mut(d)
    path = os.path.join(fresh("json"), "t.json")
    with open(path, "w") as f:
        f.write(raw if raw is not None else json.dumps(d))
    return lambda: jl.load(path).num_surfaces


def lens_json():
    S = lambda i, **k: lambda d: d["surfaces"][i].update(**k)
    SR = lambda i, **k: lambda d: (d["surfaces"][i].pop("radius"), d["surfaces"][i].update(**k))  # curvature for radius
    with open(COOKE) as f:
        d0 = json.load(f)
    probe("json surface type 'toroid' (unknown kind)", json_file(S(1, type="toroid")), "toroid", "toroidal")
    probe("json surfaces a dict", json_file(lambda d: d.update(surfaces={"a": 1})), "surfaces", "list")
    probe("json top level a list", json_file(raw="[1, 2]"), "object")
    probe("json surface a number", json_file(lambda d: d["surfaces"].__setitem__(1, 5)), "surface 1", "object")
    probe("json biconic without curvature_x (control)", json_file(SR(1, type="biconic", curvature=0.045)), good=True)
    probe("json zernike_coeffs a string", json_file(SR(1, type="zernike_standard", curvature=0.045, zernike_coeffs="0 0 1e-3", norm_radius=5.0)), "zernike_coeffs")
    probe("json xy_polynomial coeffs nested", json_file(SR(1, type="xy_polynomial", curvature=0.045, polynomial_coeffs=[[1e-3]], norm_radius=5.0)), "polynomial_coeffs")
    probe("json binary2 diffraction_order 0.5 (control: as Binary2)", json_file(SR(1, type="binary2", curvature=0.045, diffraction_order=0.5, phase_coeffs=[10.0], norm_radius=5.0)), good=True)
    probe("json grating lines_per_um 600 (per mm)", json_file(SR(1, type="grating", lines_per_um=600.0)), "lines_per_um")
    probe("json coordinate_break tilt_x_deg 'NaN'", json_file(SR(1, type="coordinate_break", tilt_x_deg="NaN")), "tilt_x")
    probe("json wavelengths_nm empty", json_file(lambda d: d.update(wavelengths_nm=[])), "wavelengths")
    probe("json primary_wavelength_nm not among them", json_file(lambda d: d.update(primary_wavelength_nm=550.0)), "primary_wavelength_nm", "587.5618")
    probe("json material table wavelengths_um in nm", json_file(S(1, material={"wavelengths_um": [500, 600, 700], "indices": [1.52, 1.515, 1.51]})), "µm")
    probe("json format jaxlens.lens/99", json_file(lambda d: d.update(format="jaxlens.lens/99")), "format")
    probe("json truncated", json_file(raw=json.dumps(d0)[:-20]), "t.json:1", "cut short")
    probe("json semi_diameter -3", json_file(S(2, semi_diameter=-3.0)), "semi_diameter")


def analyses():
    probe("rms_spot fields [95] (beyond 90°)", lambda: A.rms_spot(cooke, fields=[95.0]).polychromatic, "field", "90")
    probe("rms_spot wavelengths [587.6] (nm)", lambda: A.rms_spot(cooke, wavelengths=[587.6]).polychromatic, "wavelength", "µm")
    probe("rms_spot fields [NaN]", lambda: A.rms_spot(cooke, fields=[float("nan")]).polychromatic, "field", "finite")
    probe("rms_spot pupil 0", lambda: A.rms_spot(cooke, pupil=0).polychromatic, "pupil")
    probe("rms_spot reference 'chiefray'", lambda: A.rms_spot(cooke, reference="chiefray").polychromatic, "reference", "chief")
    probe("spot_rays field 40 (control: beyond 20°, every ray flagged invalid)", lambda: A.spot_rays(cooke, 40.0).valid.mean(), good=True)
    probe("encircled_energy radii [-0.01]", lambda: A.encircled_energy(cooke, 0.0, [-0.01]).energy, "radii", "[0, inf) mm")
    probe("encircled_energy radii [NaN]", lambda: A.encircled_energy(cooke, 0.0, [float("nan")]).energy, "radii", "finite")
    probe("radius_for_fraction fraction 80 (percent)", lambda: A.radius_for_fraction(cooke, 0.0, 80.0), "fraction", "1")
    probe("radius_for_fraction fraction 0", lambda: A.radius_for_fraction(cooke, 0.0, 0.0), "fraction")
    probe("ray_fan n 1", lambda: A.ray_fan(cooke, 0.0, n=1).tangential, "n")
    probe("ray_fan n 2.5", lambda: A.ray_fan(cooke, 0.0, n=2.5).tangential, "n", "whole number")
    probe("opd_fan n -3", lambda: A.opd_fan(cooke, 0.0, n=-3).tangential, "n")
    probe("opd_fan wavelengths 0.0005875 (mm)", lambda: A.opd_fan(cooke, 0.0, wavelengths=0.0005875).tangential, "wavelength", "µm")
    probe("field_curvature fields [[0, 10]] (x, y pairs)", lambda: A.field_curvature(cooke, fields=[[0.0, 10.0]]).tangential, good=True)
    probe("distortion wavelength 0 µm", lambda: A.distortion(cooke, wavelength=0.0).percent_ftan, "wavelength")
    probe("distortion fields [0, 30] (control: the unclipped chief ray beyond 20°)", lambda: A.distortion(cooke, fields=[0.0, 30.0]).percent_ftan, good=True)
    probe("wavefront grid 1", lambda: A.wavefront(cooke, 0.0, grid=1).rms, "grid")
    probe("wavefront grid 64.5", lambda: A.wavefront(cooke, 0.0, grid=64.5).rms, "grid", "whole number")
    probe("zernike_fit terms 0", lambda: A.zernike_fit(np.zeros(10), np.zeros(10), np.zeros(10), terms=0).coefficients, "terms")
    probe("zernike_fit x, y of different shapes", lambda: A.zernike_fit(np.zeros(10), np.zeros(9), np.zeros(10)).coefficients, "x", "y")
    probe("zernike_fit indexing 'zemax'", lambda: A.zernike_fit(np.zeros(10), np.zeros(10), np.zeros(10), indexing="zemax").coefficients, "indexing", "noll")
    probe("seidel wavelength 550 (nm)", lambda: A.seidel(cooke, wavelength=550.0).per_surface, "wavelength", "µm")
    probe("self_intersection n_radial 0", lambda: A.self_intersection(cooke, n_radial=0).ok, "n_radial")
    probe("self_intersection min_gap -1", lambda: A.self_intersection(cooke, min_gap=-1.0).ok, "min_gap")
    probe("clear_semi_diameters n_rim 0", lambda: A.clear_semi_diameters(cooke, n_rim=0), "n_rim")
    probe("chief_ray wavelength [NaN]", lambda: A.chief_ray(cooke, 0.0, wavelength=float("nan")).valid, "wavelength")
    probe("angular_spot wavelengths [-0.5]", lambda: A.angular_spot(cooke, wavelengths=[-0.5]).polychromatic, "wavelength")
    probe("psf kernel_size 0", lambda: jl.psf(cooke, 0.0, kernel_size=0, pixel_size=0.005), "kernel_size")
    probe("psf pixel_size 5 (µm for mm)", lambda: jl.psf(cooke, 0.0, pixel_size=5.0), "pixel_size", "mm")
    probe("psf wavelength [0.5, 587]", lambda: jl.psf(cooke, 0.0, wavelength=[0.5, 587.0], pixel_size=0.005), "wavelength", "µm")
    from jaxlens.imaging import distortion as dist
    from jaxlens.imaging import radiometry

    probe("relative_illumination pupil 0", lambda: radiometry.relative_illumination(cooke, [0.0], pupil=0), "pupil")
    probe("relative_illumination fields [30] (control: beyond 20°)", lambda: radiometry.relative_illumination(cooke, [30.0]).ri, good=True)
    probe("distortion_map grid (1, 1)", lambda: dist.distortion_map(cooke, grid=(1, 1), sensor=jl.Sensor((64, 64), 0.05)), "grid")
    probe("distortion_map grid (0, 5)", lambda: dist.distortion_map(cooke, grid=(0, 5), sensor=jl.Sensor((64, 64), 0.05)), "grid")
    probe("image_scale wavelength 587.6 (nm)", lambda: dist.image_scale(cooke, wavelength=587.6), "wavelength", "µm")
    probe("marechal_strehl NaN (control: NaN in, NaN out)", lambda: A.marechal_strehl(float("nan")), good=True)
    probe("Tolerances thickness -0.02", lambda: jl.tolerance.Tolerances(thickness=-0.02), "thickness")
    probe("Tolerances distribution 'gauss'", lambda: jl.tolerance.Tolerances(distribution="gauss"), "distribution", "normal")
    probe("yield_fraction threshold_um -1", lambda: jl.tolerance.yield_fraction(np.array([1.0, 2.0]), -1.0), "threshold_um")
    probe("yield_fraction min_valid 1.5", lambda: jl.tolerance.yield_fraction(np.array([1.0, 2.0]), 5.0, np.array([1.0, 1.0]), min_valid=1.5), "min_valid")


def design_spec():
    probe("DesignSpec fov 200", lambda: D.DesignSpec(fov=200.0), "fov", "180")
    probe("DesignSpec fnum 0", lambda: D.DesignSpec(fnum=0.0), "fnum")
    probe("DesignSpec n_elements 0", lambda: D.DesignSpec(n_elements=0, materials=()), "n_elements")
    probe("DesignSpec materials 5 for 6 elements", lambda: D.DesignSpec(materials=("E48R",) * 5), "materials", "6")
    probe("DesignSpec bfl 8 > total_track 7", lambda: D.DesignSpec(bfl=8.0), "bfl", "total_track")
    probe("DesignSpec stop 9 of 6 elements", lambda: D.DesignSpec(stop=9), "stop")
    probe("DesignSpec sensor_aspect (0, 1)", lambda: D.DesignSpec(sensor_aspect=(0.0, 1.0)), "sensor_aspect")
    probe("DesignSpec wavelengths in nm", lambda: D.DesignSpec(wavelengths=(486.1, 587.6, 656.3)), "wavelengths", "µm")
    probe("DesignSpec primary 3 of 3", lambda: D.DesignSpec(primary=3), "primary")
    probe("DesignSpec fov_start 100 > fov 80.8", lambda: D.DesignSpec(fov_start=100.0), "fov_start")
    probe("DesignSpec fnum_start 1.0 < fnum 2.0", lambda: D.DesignSpec(fnum_start=1.0), "fnum_start")
    probe("DesignSpec efl -5", lambda: D.DesignSpec(efl=-5.0), "efl")
    probe("DesignSpec sensor_diagonal 7.66 m (7660)", lambda: D.DesignSpec(sensor_diagonal=7660.0), "sensor_diagonal")
    probe("DesignConfig steps -1", lambda: D.DesignConfig(steps=-1), "steps")
    probe("DesignConfig solver 'sgd'", lambda: D.DesignConfig(solver="sgd"), "solver", "adam")
    probe("DesignConfig lr_c NaN", lambda: D.DesignConfig(lr_c=float("nan")), "lr_c")
    probe("DesignConfig rings 0", lambda: D.DesignConfig(rings=0), "rings")
    probe("evaluate_design n 0", lambda: D.evaluate_design(cooke, D.DesignSpec(), n=0), "n")
    probe("sensor_field_grid n 1 (the corner alone; left)", lambda: D.sensor_field_grid(D.DesignSpec(), n=1)[0], "n")


def more():
    s2 = cooke.surfaces[2]
    bic = with_surface(2, jl.Biconic(c=float(s2.c), cx=float(s2.c) * 0.5, semi_diameter=float(s2.semi_diameter)))
    probe("seidel on a biconic lens (not rotationally symmetric)", lambda: A.seidel(bic).per_surface, "seidel", "Biconic", "not handled")
    probe("field_curvature on a biconic lens (control: y section)", lambda: A.field_curvature(bic).tangential, good=True)
    q = with_surface(2, jl.QTypeAsphere(c=float(s2.c), coeffs=(1e-3, 1e-4), norm_radius=2.0, semi_diameter=float(s2.semi_diameter)))
    probe("QTypeAsphere norm_radius 2 < semi_diameter, then rms_spot (control: documented, polynomials beyond u = 1)", lambda: A.rms_spot(q).polychromatic, good=True)
    x = np.linspace(-0.5, 0.5, 10)
    probe("zernike_fit 10 points, 37 terms", lambda: A.zernike_fit(x, x * 0, x**2, terms=37).coefficients, "terms", "points")
    probe("zernike_fit mask all False", lambda: A.zernike_fit(x, x * 0, x**2, terms=4, mask=np.zeros(10, bool)).coefficients, "0 valid points", "4 terms")
    g = np.linspace(-2, 2, 9)
    X, Y = np.meshgrid(g, g)
    probe("zernike_fit points outside the unit disc (x up to 2)", lambda: A.zernike_fit(X, Y, X**2 + Y**2, terms=4).coefficients, "unit disc")
    probe("yield_fraction rms NaN (a failed trial)", lambda: jl.tolerance.yield_fraction(np.array([float("nan"), 1.0]), 5.0), good=True)
    probe("rms_spot wavelengths [2.6] (beyond N-SK16's data)", lambda: A.rms_spot(cooke, wavelengths=[2.6]).polychromatic, "2.6", "N-SK16")
    probe("wavefront reference 'spherical'", lambda: A.wavefront(cooke, 0.0, reference="spherical").rms, "reference", "sphere")
    probe("encircled_energy diffraction pixel_size -0.001", lambda: A.encircled_energy(cooke, 0.0, [0.01], method="diffraction", pixel_size=-0.001).energy, "pixel_size")
    probe("encircled_energy kernel_size 64 (even)", lambda: A.encircled_energy(cooke, 0.0, [0.01], method="diffraction", kernel_size=64, pixel_size=0.001).energy, "kernel_size")
    probe("psf center 'centroid2'", lambda: jl.psf(cooke, 0.0, center="centroid2", pixel_size=0.005), "center", "chief")
    probe("psf field 100 (beyond 90°)", lambda: jl.psf(cooke, 100.0, pixel_size=0.005), "field", "(-90, 90) deg")
    probe("render spp 0", lambda: jl.render(cooke, np.zeros((8, 8, 3), np.float32), spp=0, key=None), "spp")
    probe("render scene 2-D", lambda: jl.render(cooke, np.zeros((8, 8), np.float32), spp=1, key=jax.random.key(0), sensor=jl.Sensor((8, 8), 0.005)), "scene")
    probe("save to .txt", lambda: jl.save(cooke, os.path.join(fresh("save"), "lens.txt")), ".txt", ".json")
    probe("load config 3 of a one-configuration .json", lambda: jl.load(COOKE, config=3), "config")
    probe("load unknown_glass 'guess'", lambda: jl.load(COOKE, unknown_glass="guess"), "unknown_glass", "model")
    probe("DesignSpec name '../x' (control: a label, no file is named after it)", lambda: D.DesignSpec(name="../x").name, good=True)
    probe("DesignSpec asphere_terms 40", lambda: D.DesignSpec(asphere_terms=40), "asphere_terms")
    probe("DesignSpec sensor_pixels 0", lambda: D.DesignSpec(sensor_pixels=0), "sensor_pixels")
    probe("DesignConfig material_catalogs ('NOPE',)", lambda: D.DesignConfig(materials="search", material_catalogs=("NOPE",)), "NOPE")
    probe("DesignConfig tolerance_trials -1", lambda: D.DesignConfig(tolerance_trials=-1), "tolerance_trials")
    probe("DesignConfig image_pixels 1 (control: in its documented [1, …])", lambda: D.DesignConfig(image_pixels=1).image_pixels, good=True)
    probe("evaluate_design min_valid 99 (percent)", lambda: D.evaluate_design(cooke, D.DesignSpec(), min_valid=99.0), "min_valid")


def clis():
    from jaxlens.experiments import classical as C

    c = lambda *a, out=None: cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", out or fresh("c"), *a])))
    probe("classical --fov 0", c("--fov", "0"), "--fov")
    probe("classical --bfl 9 (beyond --track 7)", c("--bfl", "9"), "--bfl", "--track")
    probe("classical --sensor-diagonal -1", c("--sensor-diagonal", "-1"), "--sensor-diagonal")
    probe("classical --tolerance-threshold 0", c("--tolerance-threshold", "0"), "--tolerance-threshold")
    probe("classical --stop 7 of 6 elements", c("--stop", "7"), "--stop")
    d = fresh("prev")
    with open(os.path.join(d, "summary.json"), "w") as f:
        f.write("{}")
    probe("classical --out a previous run's folder", c(out=d), "--out", "not empty")
    probe("classical --out a file", c(out=os.path.join(d, "summary.json")), "--out")
    probe("edof --test-dir missing", edof_check("--test-dir", "/nonexistent/x"), "--test-dir")
    probe("edof --test-dir a file", edof_check("--test-dir", COOKE), "--test-dir")


if __name__ == "__main__":
    run([surfaces, apertures_sensor, materials, agf, lens_json, analyses, design_spec, more, clis])
