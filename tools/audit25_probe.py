# ruff: noqa: E501, B023, E731
"""Round-25 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for what rounds 15-24 reached least: hand-given dispersion formulas and their units
(Sellmeier C in nm², Abbe numbers as fractions, ``CatalogMaterial``'s metadata, ``Laurent``'s
powers, a table's ``wavelength_range`` in nm), JSON material classes, ``.agf`` records whose
formula describes no material, ``.zmx`` glass names with typos and ``unknown_glass``, image
I/O (grey+alpha, palette and 1-bit PNGs, EXR channel lists, missing folders, empty images,
codes given as floats, PSF stacks, PSNR/SSIM on a code range or complex images), backward
tracing's arguments, ``NAFNet``'s key and ``zernike``'s inputs. The CLIs
(``experiments.tolerance``, ``benchmarks``, ``tools/check_corpus.py``) were probed too and
every option tried was already refused clearly (rounds 17-24): those probes are not kept.

Before (main at 3881bed) and after (branch audit25), the same 126 probes,
``PYTHONPATH=<tree> python tools/audit25_probe.py`` under ``ulimit -v 16000000``, one 2-core
machine shared (13 s each; no probe starts long work on main):
    before: clear error 52, crash 6, ok 25, silent wrong 31, vague error 12
    after:  clear error 96, ok 28, silent wrong 2

Probe (before -> after):
    Sellmeier N-BK7 (control)                                                ok           -> ok
    Sellmeier C in nm² (6000.7, 20017.9, 1.0356e8)                           silent wrong -> clear error
    Sellmeier B and C swapped                                                silent wrong -> silent wrong
    Sellmeier 2 B, 3 C                                                       clear error  -> clear error
    Sellmeier B empty ()                                                     silent wrong -> clear error
    Sellmeier B complex                                                      clear error  -> clear error
    Sellmeier B a 2-D array                                                  silent wrong -> clear error
    Sellmeier B strings                                                      clear error  -> clear error
    Tabulated unsorted wavelengths                                           ok           -> ok
    Tabulated one node                                                       ok           -> ok
    Tabulated indices bool                                                   clear error  -> clear error
    ModelGlass vd 0.6417 (a fraction of 64.17?)                              silent wrong -> clear error
    ModelGlass nd 151.68                                                     clear error  -> clear error
    get_material 'N-BK 7' typo (close matches)                               clear error  -> clear error
    get_material nd '1.5' string                                             clear error  -> clear error
    glass_info 'N-BK77'                                                      clear error  -> clear error
    CatalogMaterial wavelength_range (400, 700) nm                           silent wrong -> clear error
    CatalogMaterial formula -3                                               silent wrong -> clear error
    CatalogMaterial catalog_nd 0.5                                           silent wrong -> clear error
    CatalogMaterial model not a material                                     silent wrong -> clear error
    JSON class Sellmeier C in nm²                                            clear error  -> clear error
    JSON class Sellmeier 2 B, 3 C                                            clear error  -> clear error
    JSON class Sellmeier no C                                                clear error  -> clear error
    JSON class Sellmeier 'coefficients' (misspelt field)                     silent wrong -> clear error
    JSON class 'sellmeier' lower case                                        clear error  -> clear error
    JSON class Laurent powers 'abc'                                          vague error  -> clear error
    JSON wavelengths_nm in µm (0.486, ...)                                   clear error  -> clear error
    JSON 'n' table keyed by µm ('0.5876')                                    clear error  -> clear error
    JSON nd/vd with vd 0.6417                                                silent wrong -> clear error
    JSON material 'N-BK 7' typo (close matches)                              clear error  -> clear error
    JSON material {'name': 'N-BK7', 'nd': 1.6, 'vd': 40} (which wins?)       ok           -> ok
    JSON index_at_wavelengths of 2 entries for 3 wavelengths                 clear error  -> clear error
    agf good (control)                                                       ok           -> ok
    agf Sellmeier C in nm² (names the line)                                  vague error  -> clear error
    agf CD with 4 numbers for Sellmeier (names the line)                     clear error  -> clear error
    agf formula 99 (names the line)                                          clear error  -> clear error
    agf NM with no nd/vd (names the line)                                    clear error  -> clear error
    agf glass given twice (documented: the later record wins)                ok           -> ok
    agf CD before NM (names the line)                                        clear error  -> clear error
    agf IT line with 'x' (documented: IT records are skipped)                ok           -> ok
    agf TD with 'nan' (documented: TD records are skipped)                   ok           -> ok
    agf LD in nm 300 2500 (names the line)                                   clear error  -> clear error
    agf binary garbage                                                       clear error  -> clear error
    agf NM name empty field count                                            clear error  -> clear error
    register_catalog name '' empty                                           clear error  -> clear error
    register_catalog name 5                                                  clear error  -> clear error
    register_catalog mapping of a non-material                               clear error  -> clear error
    zmx GLAS 'N-BK7' (control)                                               ok           -> ok
    zmx GLAS 'N-BK8' typo (names line, close matches)                        clear error  -> clear error
    zmx GLAS 'n-bk7' lower case                                              ok           -> ok
    zmx GCAT 'SHOTT' typo (N-BK7 found in the shipped SCHOTT)                ok           -> ok
    zmx GLAS typo unknown_glass='model' keeps GLAS nd/Vd (documented)        ok           -> ok
    zmx GLAS nd 0.5 with unknown_glass='model' (names line)                  vague error  -> clear error
    read_png grey+alpha 8-bit 4x4 (documented: alpha dropped)                silent wrong -> ok
    read_png grey+alpha 16-bit 4x4 (documented: alpha dropped)               silent wrong -> ok
    read_png RGBA 16-bit (control)                                           ok           -> ok
    read_exr channels 'RGB' one string                                       silent wrong -> clear error
    read_exr channels [] empty                                               vague error  -> clear error
    read_exr channels ['R','R'] repeated                                     silent wrong -> clear error
    read_exr channels 'r' lower case                                         clear error  -> clear error
    write_exr complex                                                        clear error  -> clear error
    write_exr bool                                                           clear error  -> clear error
    write_exr (4,4,3,2) 4-D                                                  clear error  -> clear error
    write_exr (0,4,3) empty                                                  crash        -> clear error
    write_exr 1-D                                                            clear error  -> clear error
    write_exr into a missing folder                                          crash        -> clear error
    write_png into a missing folder                                          crash        -> clear error
    write_png (0,4,3) empty                                                  vague error  -> clear error
    write_png (4,4,5)                                                        clear error  -> clear error
    write_png 0…255 floats (codes given as floats)                           silent wrong -> clear error
    read_psf_stack of an RGB exr (not a stack)                               silent wrong -> clear error
    write_psf_stack NaN psf                                                  silent wrong -> clear error
    write_psf_stack 2-D (one psf)                                            clear error  -> clear error
    psnr data_range 255 for [0,1] images                                     silent wrong -> clear error
    ssim complex images                                                      silent wrong -> clear error
    Conrady 4 coefficients                                                   clear error  -> clear error
    Herzberger 5 coefficients                                                clear error  -> clear error
    Sellmeier2 nan coefficient                                               clear error  -> clear error
    Laurent 3 coeffs for 8 powers                                            clear error  -> clear error
    Tabulated wavelength_range (400, 700) nm                                 silent wrong -> clear error
    Tabulated indices 0.5                                                    clear error  -> clear error
    Tabulated repeated wavelength                                            clear error  -> clear error
    Tabulated 2 wavelengths, 3 indices                                       clear error  -> clear error
    Air().index(587.6) nm                                                    clear error  -> clear error
    ModelGlass.extrapolated_index(587.6) nm                                  clear error  -> clear error
    get_material('NOPE', nd=1.5168, vd=0.6417) (a fraction for vd)           clear error  -> clear error
    get_material('N-BK7', catalogs='schott') lower case                      ok           -> ok
    get_material '' (documented: air)                                        ok           -> ok
    Sellmeier name 5 (int)                                                   silent wrong -> clear error
    ModelGlass name None                                                     silent wrong -> clear error
    register_catalog of an .agf with C in nm², then get_material (names the line) vague error  -> clear error
    JSON class ModelGlass vd 0.6                                             silent wrong -> clear error
    JSON class CatalogMaterial wavelength_range [400, 700]                   vague error  -> clear error
    JSON class CatalogMaterial formula 42                                    silent wrong -> clear error
    JSON class Tabulated 'wavelength' (misspelt)                             clear error  -> clear error
    JSON class Sellmeier B [] C []                                           silent wrong -> clear error
    JSON class Sellmeier name 5                                              clear error  -> clear error
    JSON nd only (documented: vd inf, no dispersion)                         ok           -> ok
    read_png 1-bit PNG (white is 1)                                          ok           -> ok
    read_png palette PNG (RGB values)                                        ok           -> ok
    read_png palette PNG with transparency (alpha dropped)                   ok           -> ok
    read_png grey+alpha 4x6 written by Pillow                                silent wrong -> ok
    read_png linear None                                                     clear error  -> clear error
    write_png bits 12                                                        clear error  -> clear error
    write_png grey (4,4,1), read back (documented: grey)                     ok           -> ok
    write_exr channels ('R', 'G') for 3 channels                             clear error  -> clear error
    write_psf_stack int psfs                                                 silent wrong -> clear error
    write_psf_stack into a missing folder                                    crash        -> clear error
    to_linear float16 0.5 (control)                                          ok           -> ok
    to_linear bool image                                                     clear error  -> clear error
    srgb_to_linear -0.1                                                      clear error  -> clear error
    psnr data_range 65535 for [0,1] images                                   silent wrong -> clear error
    psnr complex images                                                      silent wrong -> clear error
    psnr data_range 1 for [0,1] images (control)                             ok           -> ok
    trace_backward upto 99 (names the value given)                           vague error  -> clear error
    trace_backward upto -1                                                   vague error  -> clear error
    reversed_lens image_distance nan                                         vague error  -> clear error
    reversed_lens image_distance inf                                         vague error  -> clear error
    NAFNet key an int 0                                                      crash        -> clear error
    NAFNet key None                                                          crash        -> clear error
    NAFNet middle_blocks -1 (names it)                                       vague error  -> clear error
    zernike_terms terms 37.0 (a whole float)                                 ok           -> ok
    zernike_terms x 5 (mm, not the unit disc)                                silent wrong -> silent wrong
    zernike_fit values all nan                                               clear error  -> clear error
    distortion_map grid (1, 17) (one row)                                    ok           -> ok
    Binary2 order 0.5 (Zemax's order is a real parameter)                    ok           -> ok

Left (the 2 "silent wrong" rows): ``Sellmeier`` with B and C swapped gives NaN from
``index`` at 0.5876 µm (between the swapped formula's poles; a NaN, not a plausible index,
and a lens refuses it with the wavelength); checking every concrete ``index`` result would
cost a device-to-host copy on each call. ``zernike_terms`` evaluates the polynomials at
|r| > 1 (coordinates in mm, not normalised): they are defined there and the fits' callers
may extrapolate, so a refusal needs the lead's decision on a tolerance.

Run: PYTHONPATH=$PWD python tools/audit25_probe.py [filter]
(``AUDIT25_AREAS=materials,agf_cases`` runs some areas only.)
"""

import os
import struct
import sys
import tempfile
import zlib

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.io import images, lensfile  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
TMP = tempfile.mkdtemp()
cooke = zoo.cooke_triplet()


def with_mat(spec, i=1):
    """A loader of the Cooke triplet's JSON with surface ``i``'s material replaced by ``spec``."""
    import copy

    d = copy.deepcopy(lensfile.lens_to_dict(cooke))
    d["surfaces"][i]["material"] = spec
    d["surfaces"][i].pop("index_at_wavelengths", None)
    return lambda: lensfile.lens_from_dict(d)


KEPLER = open(os.path.join(ROOT, "tests", "data", "afocal_kepler.zmx")).read()


def probe_value(name, fn, want):
    """A probe whose answer must equal ``want``: "ok" if it does, "silent wrong" if not."""
    try:
        got = fn()
    except Exception:  # noqa: BLE001  (the probe itself reports it)
        got = None
    probe(name, fn, good=got == want)


def write(name, text, mode="w"):
    p = os.path.join(TMP, name)
    with open(p, mode) as f:
        f.write(text)
    return p


# ----------------------------------------------------------------------------- materials
def materials():
    bk7_b, bk7_c = (1.03961212, 0.231792344, 1.01046945), (0.00600069867, 0.0200179144, 103.560653)
    probe("Sellmeier N-BK7 (control)", lambda: float(jl.Sellmeier(bk7_b, bk7_c).index(0.5876)), good=True)
    probe("Sellmeier C in nm² (6000.7, 20017.9, 1.0356e8)", lambda: float(jl.Sellmeier(bk7_b, tuple(c * 1e6 for c in bk7_c)).index(0.5876)), "C", "µm")
    probe("Sellmeier B and C swapped", lambda: float(jl.Sellmeier(bk7_c, bk7_b).index(0.5876)), "index")
    probe("Sellmeier 2 B, 3 C", lambda: jl.Sellmeier(bk7_b[:2], bk7_c), "B", "C")
    probe("Sellmeier B empty ()", lambda: jl.Sellmeier((), ()), "B")
    probe("Sellmeier B complex", lambda: jl.Sellmeier((1.0 + 1j, 0.2, 1.0), bk7_c), "B")
    probe("Sellmeier B a 2-D array", lambda: jl.Sellmeier(np.array([bk7_b, bk7_b]), np.array([bk7_c, bk7_c])), "B")
    probe("Sellmeier B strings", lambda: jl.Sellmeier(("1.04", "0.23", "1.01"), bk7_c), "B")
    probe("Tabulated unsorted wavelengths", lambda: float(jl.Tabulated((0.6563, 0.4861, 0.5876), (1.5143, 1.5224, 1.5168)).index(0.55)), good=True)
    probe("Tabulated one node", lambda: float(jl.Tabulated((0.5876,), (1.5168,)).index(0.5876)), good=True)
    probe("Tabulated indices bool", lambda: jl.Tabulated((0.4861, 0.5876), (True, True)), "indices")
    probe("ModelGlass vd 0.6417 (a fraction of 64.17?)", lambda: jl.ModelGlass(1.5168, 0.6417), "vd")
    probe("ModelGlass nd 151.68", lambda: jl.ModelGlass(151.68, 64.17), "nd")
    probe("get_material 'N-BK 7' typo (close matches)", lambda: jl.get_material("N-BK 7"), "N-BK7")
    probe("get_material nd '1.5' string", lambda: jl.get_material("NOPE", nd="1.5", vd=60.0), "nd")
    probe("glass_info 'N-BK77'", lambda: jl.glass_info("N-BK77"), "N-BK7")
    probe("CatalogMaterial wavelength_range (400, 700) nm", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", wavelength_range=(400.0, 700.0)), "wavelength_range", "µm")
    probe("CatalogMaterial formula -3", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", formula=-3), "formula")
    probe("CatalogMaterial catalog_nd 0.5", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", catalog_nd=0.5), "catalog_nd")
    probe("CatalogMaterial model not a material", lambda: jl.CatalogMaterial(1.5, "X"), "model")


# ----------------------------------------------------------------------------- JSON materials
def json_materials():
    base = lensfile.lens_to_dict(cooke)
    probe("JSON class Sellmeier C in nm²", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01], "C": [6000.7, 20017.9, 1.0356e8]}), "C", "µm")
    probe("JSON class Sellmeier 2 B, 3 C", with_mat({"class": "Sellmeier", "B": [1.04, 0.23], "C": [0.006, 0.02, 103.56]}), "B", "C")
    probe("JSON class Sellmeier no C", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01]}), "C")
    probe("JSON class Sellmeier 'coefficients' (misspelt field)", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01], "C": [0.006, 0.02, 103.56], "coefficents": [1]}), "coefficents")
    probe("JSON class 'sellmeier' lower case", with_mat({"class": "sellmeier", "B": [1.04], "C": [0.006]}), "Sellmeier")
    probe("JSON class Laurent powers 'abc'", with_mat({"class": "Laurent", "coeffs": [2.27, -0.01], "powers": "ab"}), "powers")
    probe("JSON wavelengths_nm in µm (0.486, ...)", with_mat({"wavelengths_nm": [0.4861, 0.5876, 0.6563], "indices": [1.52, 1.517, 1.514]}), "wavelength", "nm")
    probe("JSON 'n' table keyed by µm ('0.5876')", with_mat({"n": {"0.4861": 1.52, "0.5876": 1.517, "0.6563": 1.514}}), "nm")
    probe("JSON nd/vd with vd 0.6417", with_mat({"nd": 1.5168, "vd": 0.6417}), "vd")
    probe("JSON material 'N-BK 7' typo (close matches)", with_mat("N-BK 7"), "N-BK7")
    probe("JSON material {'name': 'N-BK7', 'nd': 1.6, 'vd': 40} (which wins?)", lambda: type(with_mat({"name": "N-BK7", "nd": 1.6, "vd": 40.0})().surfaces[0]).__name__ and float(with_mat({"name": "N-BK7", "nd": 1.6, "vd": 40.0})().materials[0].index(0.5876)), good=True)
    probe("JSON index_at_wavelengths of 2 entries for 3 wavelengths", lambda: lensfile.lens_from_dict({**base, "surfaces": [dict(s, index_at_wavelengths=[1.5, 1.5]) if i == 1 else s for i, s in enumerate(base["surfaces"])]}), "index_at_wavelengths")


# ----------------------------------------------------------------------------- .agf catalogs
AGF_HEAD = "CC test catalog\n"
AGF_GOOD = "NM GA 2 0 1.5168 64.17 0 0\nCD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0\nTD 0 0 0 0 0 0 0\nLD 0.3 2.5\n"


def agf(text, name="bad.agf"):
    return lambda: jl.load_agf(write(name, AGF_HEAD + text))


def agf_cases():
    probe("agf good (control)", lambda: float(jl.load_agf(write("good.agf", AGF_HEAD + AGF_GOOD))["GA"].index(0.5876)), good=True)
    probe("agf Sellmeier C in nm² (names the line)", agf(AGF_GOOD.replace("0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653", "6000.69867 0.231792344 20017.9144 1.01046945 103560653")), "bad.agf:2")
    probe("agf CD with 4 numbers for Sellmeier (names the line)", agf(AGF_GOOD.replace("CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0", "CD 1.03961212 0.00600069867 0.231792344 0.0200179144")), "bad.agf:2")
    probe("agf formula 99 (names the line)", agf(AGF_GOOD.replace("NM GA 2 ", "NM GA 99 ")), "bad.agf:2", "formula")
    probe("agf NM with no nd/vd (names the line)", agf("NM GA 2\nCD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"), "bad.agf:2")
    probe("agf glass given twice (documented: the later record wins)", lambda: len(agf(AGF_GOOD + AGF_GOOD)()), good=True)
    probe("agf CD before NM (names the line)", agf("CD 1 2 3\n" + AGF_GOOD), "bad.agf:2")
    probe("agf IT line with 'x' (documented: IT records are skipped)", lambda: len(agf(AGF_GOOD + "IT 0.4 x 10\n")()), good=True)
    probe("agf TD with 'nan' (documented: TD records are skipped)", lambda: len(agf(AGF_GOOD.replace("TD 0 0 0 0 0 0 0", "TD nan 0 0 0 0 0 0"))()), good=True)
    probe("agf LD in nm 300 2500 (names the line)", agf(AGF_GOOD.replace("LD 0.3 2.5", "LD 300 2500")), "bad.agf:5")
    probe("agf binary garbage", lambda: jl.load_agf(write("bin.agf", b"\x00\xff\x10" * 50, "wb")), "bin.agf")
    probe("agf NM name empty field count", agf("NM\n"), "bad.agf:2")
    probe("register_catalog name '' empty", lambda: jl.register_catalog(write("good2.agf", AGF_HEAD + AGF_GOOD), name=""), "name")
    probe("register_catalog name 5", lambda: jl.register_catalog(write("good3.agf", AGF_HEAD + AGF_GOOD), name=5), "name")
    probe("register_catalog mapping of a non-material", lambda: jl.register_catalog({"X": 1.5}, name="MYCAT1"), "X")


# ----------------------------------------------------------------------------- .zmx glass names
def zmx_glass():
    def z(text, name="g.zmx", **kw):
        return lambda: jl.load(write(name, text), **kw)
    probe("zmx GLAS 'N-BK7' (control)", lambda: float(jl.paraxial_data(jl.load(write("ok.zmx", KEPLER))).efl), good=True)
    probe("zmx GLAS 'N-BK8' typo (names line, close matches)", z(KEPLER.replace("GLAS N-BK7 0 0 1.5168 64.17", "GLAS N-BK8 0 0 1.5168 64.17", 1)), "N-BK7", "g.zmx:51")
    probe("zmx GLAS 'n-bk7' lower case", lambda: float(jl.paraxial_data(jl.load(write("lc.zmx", KEPLER.replace("GLAS N-BK7 0 0", "GLAS n-bk7 0 0")))).efl), good=True)
    probe("zmx GCAT 'SHOTT' typo (N-BK7 found in the shipped SCHOTT)", lambda: jl.load(write("gc.zmx", KEPLER.replace("GCAT SCHOTT", "GCAT SHOTT"))).materials[0].catalog, good=True)
    probe("zmx GLAS typo unknown_glass='model' keeps GLAS nd/Vd (documented)", lambda: float(jl.load(write("m.zmx", KEPLER.replace("GLAS N-BK7 0 0", "GLAS N-BK8 0 0", 1)), unknown_glass="model").materials[0].index(0.5875618)), good=True)
    probe("zmx GLAS nd 0.5 with unknown_glass='model' (names line)", z(KEPLER.replace("GLAS N-BK7 0 0 1.5168", "GLAS N-BK8 0 0 0.5168", 1), unknown_glass="model"), "g.zmx:51", "nd")


# ----------------------------------------------------------------------------- images
def png_bytes(a, color_type, bits):
    h, w = a.shape[:2]
    q = a.astype(">u2" if bits == 16 else np.uint8)
    rows = q.reshape(h, -1).view(np.uint8).reshape(h, -1)
    data = b"".join(b"\x00" + r.tobytes() for r in rows)
    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)
    ihdr = struct.pack(">IIBBBBB", w, h, bits, color_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(data)) + chunk(b"IEND", b"")


def image_cases():
    ga8 = np.dstack([np.full((4, 4), 128), np.full((4, 4), 255)])
    p_ga8 = write("ga8.png", png_bytes(ga8, 4, 8), "wb")
    ga16 = np.dstack([np.full((4, 4), 30000), np.full((4, 4), 65535)])
    p_ga16 = write("ga16.png", png_bytes(ga16, 4, 16), "wb")
    rgba16 = np.dstack([np.full((4, 4), 30000)] * 3 + [np.full((4, 4), 65535)])
    p_rgba16 = write("rgba16.png", png_bytes(rgba16, 6, 16), "wb")
    probe_value("read_png grey+alpha 8-bit 4x4 (documented: alpha dropped)", lambda: images.read_png(p_ga8).shape, (4, 4))
    probe_value("read_png grey+alpha 16-bit 4x4 (documented: alpha dropped)", lambda: images.read_png(p_ga16).shape, (4, 4))
    probe_value("read_png RGBA 16-bit (control)", lambda: images.read_png(p_rgba16).shape, (4, 4, 3))
    p_exr = os.path.join(TMP, "a.exr")
    images.write_exr(p_exr, np.ones((4, 4, 3)))
    p_png = os.path.join(TMP, "a.png")
    images.write_png(p_png, np.ones((4, 4, 3)) * 0.5)
    probe("read_exr channels 'RGB' one string", lambda: images.read_exr(p_exr, channels="RGB").shape, "RGB")
    probe("read_exr channels [] empty", lambda: images.read_exr(p_exr, channels=[]), "channels")
    probe("read_exr channels ['R','R'] repeated", lambda: images.read_exr(p_exr, channels=["R", "R"]), "channels")
    probe("read_exr channels 'r' lower case", lambda: images.read_exr(p_exr, channels=["r"]), "R")
    p_nan = os.path.join(TMP, "nan.exr")
    images.write_exr(p_nan, np.ones((4, 4, 3)))
    probe("write_exr complex", lambda: images.write_exr(os.path.join(TMP, "c.exr"), np.ones((4, 4, 3), complex)), "img")
    probe("write_exr bool", lambda: images.write_exr(os.path.join(TMP, "b.exr"), np.ones((4, 4, 3), bool)), "img")
    probe("write_exr (4,4,3,2) 4-D", lambda: images.write_exr(os.path.join(TMP, "d.exr"), np.ones((4, 4, 3, 2))), "image")
    probe("write_exr (0,4,3) empty", lambda: images.write_exr(os.path.join(TMP, "e.exr"), np.ones((0, 4, 3))), "img")
    probe("write_exr 1-D", lambda: images.write_exr(os.path.join(TMP, "f.exr"), np.ones(5)), "image")
    probe("write_exr into a missing folder", lambda: images.write_exr(os.path.join(TMP, "no", "x.exr"), np.ones((4, 4))), "folder")
    probe("write_png into a missing folder", lambda: images.write_png(os.path.join(TMP, "no", "x.png"), np.ones((4, 4))), "folder")
    probe("write_png (0,4,3) empty", lambda: images.write_png(os.path.join(TMP, "e.png"), np.ones((0, 4, 3))), "img")
    probe("write_png (4,4,5)", lambda: images.write_png(os.path.join(TMP, "g.png"), np.ones((4, 4, 5))), "C<=4")
    probe("write_png 0…255 floats (codes given as floats)", lambda: images.write_png(os.path.join(TMP, "h.png"), np.full((4, 4, 3), 200.0)), "img")
    probe("read_psf_stack of an RGB exr (not a stack)", lambda: images.read_psf_stack(p_exr)[1], "stack")
    probe("write_psf_stack NaN psf", lambda: images.write_psf_stack(os.path.join(TMP, "s.exr"), np.full((2, 5, 5), np.nan)), "nan")
    probe("write_psf_stack 2-D (one psf)", lambda: images.write_psf_stack(os.path.join(TMP, "s2.exr"), np.ones((5, 5))), "psfs")
    probe("psnr data_range 255 for [0,1] images", lambda: images.psnr(np.ones((4, 4)) * 0.5, np.ones((4, 4)) * 0.4, data_range=255), "data_range")
    probe("ssim complex images", lambda: images.ssim(np.ones((16, 16), complex), np.ones((16, 16), complex)), "complex")


# ----------------------------------------------------------------------------- more formulas and tables
def formulas():
    from jaxlens.optics import materials as M
    probe("Conrady 4 coefficients", lambda: M.Conrady((1.5, 0.01, 0.001, 0.0)), "coeffs", "3")
    probe("Herzberger 5 coefficients", lambda: M.Herzberger((1.5, 0.01, 0.0, 0.0, 0.0)), "coeffs", "6")
    probe("Sellmeier2 nan coefficient", lambda: M.Sellmeier2((1.0, np.nan, 0.01, 0.1, 100.0)), "coeffs")
    probe("Laurent 3 coeffs for 8 powers", lambda: M.Laurent((2.27, -0.01, 0.01)), "coefficient", "8")
    probe("Tabulated wavelength_range (400, 700) nm", lambda: jl.Tabulated((0.4861, 0.5876, 0.6563), (1.5224, 1.5168, 1.5143), wavelength_range=(400.0, 700.0)), "wavelength_range")
    probe("Tabulated indices 0.5", lambda: jl.Tabulated((0.4861, 0.5876), (0.5, 0.5)), "indices")
    probe("Tabulated repeated wavelength", lambda: jl.Tabulated((0.5876, 0.5876), (1.5, 1.51)), "wavelength")
    probe("Tabulated 2 wavelengths, 3 indices", lambda: jl.Tabulated((0.4861, 0.5876), (1.52, 1.517, 1.514)), "indices")
    probe("Air().index(587.6) nm", lambda: jl.Air().index(587.6), "µm")
    probe("ModelGlass.extrapolated_index(587.6) nm", lambda: jl.ModelGlass(1.5168, 64.17).extrapolated_index(587.6), "µm")
    probe("get_material('NOPE', nd=1.5168, vd=0.6417) (a fraction for vd)", lambda: jl.get_material("NOPE", nd=1.5168, vd=0.6417), "vd")
    probe("get_material('N-BK7', catalogs='schott') lower case", lambda: jl.get_material("N-BK7", catalogs="schott").name, good=True)
    probe("get_material '' (documented: air)", lambda: jl.get_material(""), good=True)
    probe("Sellmeier name 5 (int)", lambda: jl.Sellmeier((1.0,), (0.01,), name=5), "name")
    probe("ModelGlass name None", lambda: jl.ModelGlass(1.5, 60.0, name=None), "name")
    nm_agf = write("NMCAT.agf", AGF_HEAD + AGF_GOOD.replace("0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653", "6000.69867 0.231792344 20017.9144 1.01046945 103560653"))
    probe("register_catalog of an .agf with C in nm², then get_material (names the line)", lambda: jl.register_catalog(nm_agf) and jl.get_material("GA", catalogs="NMCAT"), "NMCAT.agf:2")
    probe("JSON class ModelGlass vd 0.6", with_mat({"class": "ModelGlass", "nd": 1.5, "vd": 0.6}), "vd")
    probe("JSON class CatalogMaterial wavelength_range [400, 700]", with_mat({"class": "CatalogMaterial", "model": {"nd": 1.5, "vd": 60.0}, "name": "X", "wavelength_range": [400.0, 700.0]}), "wavelength_range")
    probe("JSON class CatalogMaterial formula 42", with_mat({"class": "CatalogMaterial", "model": {"nd": 1.5, "vd": 60.0}, "name": "X", "formula": 42}), "formula")
    probe("JSON class Tabulated 'wavelength' (misspelt)", with_mat({"class": "Tabulated", "wavelength": [0.4861, 0.5876], "indices": [1.52, 1.517]}), "wavelength")
    probe("JSON class Sellmeier B [] C []", with_mat({"class": "Sellmeier", "B": [], "C": []}), "B")
    probe("JSON class Sellmeier name 5", with_mat({"class": "Sellmeier", "B": [1.04], "C": [0.006], "name": 5}), "name")
    probe("JSON nd only (documented: vd inf, no dispersion)", lambda: float(with_mat({"nd": 1.5})().materials[0].index(0.4861)), good=True)


# ----------------------------------------------------------------------------- more images
def more_images():
    from PIL import Image
    p1 = os.path.join(TMP, "bit1.png")
    Image.fromarray(np.eye(4, dtype=bool)).save(p1)
    probe_value("read_png 1-bit PNG (white is 1)", lambda: float(images.read_png(p1, linear=False).max()), 1.0)
    pp = os.path.join(TMP, "pal.png")
    Image.fromarray(np.full((4, 4, 3), 128, np.uint8)).convert("P").save(pp)
    probe_value("read_png palette PNG (RGB values)", lambda: images.read_png(pp, linear=False).shape, (4, 4, 3))
    pt = os.path.join(TMP, "palt.png")
    Image.fromarray(np.full((4, 4, 3), 128, np.uint8)).convert("P").save(pt, transparency=0)
    probe_value("read_png palette PNG with transparency (alpha dropped)", lambda: images.read_png(pt, linear=False).shape, (4, 4, 3))
    pl = os.path.join(TMP, "la8.png")
    Image.fromarray(np.dstack([np.full((4, 6), 128, np.uint8), np.full((4, 6), 255, np.uint8)]), "LA").save(pl)
    probe_value("read_png grey+alpha 4x6 written by Pillow", lambda: images.read_png(pl).shape, (4, 6))
    probe("read_png linear None", lambda: images.read_png(pl, linear=None), "linear")
    probe("write_png bits 12", lambda: images.write_png(os.path.join(TMP, "b12.png"), np.ones((4, 4)), bits=12), "bits")
    probe_value("write_png grey (4,4,1), read back (documented: grey)", lambda: images.write_png(os.path.join(TMP, "g1.png"), np.ones((4, 4, 1)) * 0.5) or images.read_png(os.path.join(TMP, "g1.png")).shape, (4, 4))
    probe("write_exr channels ('R', 'G') for 3 channels", lambda: images.write_exr(os.path.join(TMP, "ch.exr"), np.ones((4, 4, 3)), channels=("R", "G")), "channels")
    probe("write_psf_stack int psfs", lambda: images.write_psf_stack(os.path.join(TMP, "si.exr"), np.ones((2, 5, 5), np.int64)), "psfs")
    probe("write_psf_stack into a missing folder", lambda: images.write_psf_stack(os.path.join(TMP, "no", "s.exr"), np.ones((2, 5, 5))), "folder")
    probe("to_linear float16 0.5 (control)", lambda: float(images.to_linear(np.full((2, 2), 0.5, np.float16))[0, 0]), good=True)
    probe("to_linear bool image", lambda: images.to_linear(np.ones((2, 2), bool)), "img")
    probe("srgb_to_linear -0.1", lambda: images.srgb_to_linear(np.array([-0.1])), "v")
    probe("psnr data_range 65535 for [0,1] images", lambda: images.psnr(np.full((4, 4), 0.5), np.full((4, 4), 0.4), data_range=65535), "data_range")
    probe("psnr complex images", lambda: images.psnr(np.ones((4, 4), complex), np.ones((4, 4), complex) * 0.5), "complex")
    probe("psnr data_range 1 for [0,1] images (control)", lambda: images.psnr(np.full((4, 4), 0.5), np.full((4, 4), 0.4), data_range=1.0), good=True)


# ----------------------------------------------------------------------------- tracing, nets, zernike
def other():
    from jaxlens import nets
    from jaxlens.analysis import zernike
    x = jnp.linspace(-0.5, 0.5, 5)
    r = jl.Rays(jnp.zeros((2, 3)), jnp.array([[0.0, 0.0, -1.0]] * 2), jnp.full((2,), 0.55), jnp.ones(2, bool), jnp.zeros(2))
    probe("trace_backward upto 99 (names the value given)", lambda: jl.trace_backward(cooke, r, upto=99), "upto", "99")
    probe("trace_backward upto -1", lambda: jl.trace_backward(cooke, r, upto=-1), "upto", "-1")
    probe("reversed_lens image_distance nan", lambda: jl.tracing.backward.reversed_lens(cooke, image_distance=np.nan), "image_distance")
    probe("reversed_lens image_distance inf", lambda: jl.tracing.backward.reversed_lens(cooke, image_distance=np.inf), "image_distance")
    probe("NAFNet key an int 0", lambda: nets.NAFNet(key=0), "key")
    probe("NAFNet key None", lambda: nets.NAFNet(key=None), "key")
    probe("NAFNet middle_blocks -1 (names it)", lambda: nets.NAFNet(middle_blocks=-1, key=jax.random.PRNGKey(0)), "middle_blocks")
    probe("zernike_terms terms 37.0 (a whole float)", lambda: zernike.zernike_terms(x, x, terms=37.0).shape, good=True)
    probe("zernike_terms x 5 (mm, not the unit disc)", lambda: zernike.zernike_terms(x * 10, x * 10), "unit")
    probe("zernike_fit values all nan", lambda: zernike.zernike_fit(x, x, jnp.full(5, jnp.nan), terms=3), "valid points")
    probe("distortion_map grid (1, 17) (one row)", lambda: jl.imaging.distortion.distortion_map(cooke, grid=(1, 17)).real.shape, good=True)
    probe("Binary2 order 0.5 (Zemax's order is a real parameter)", lambda: float(jl.Binary2(order=0.5, phase_coeffs=(1.0,)).order), good=True)


AREAS = [materials, json_materials, agf_cases, zmx_glass, image_cases, formulas, more_images, other]
if os.environ.get("AUDIT25_AREAS"):
    AREAS = [a for a in AREAS if a.__name__ in os.environ["AUDIT25_AREAS"].split(",")]
run(AREAS)
