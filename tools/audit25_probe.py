# ruff: noqa: E501, B023, E731
"""Round-25 bad-input probes (table of ``tools/audit22_probe.py``).

RESULTS

Run: PYTHONPATH=$PWD python tools/audit25_probe.py [filter]
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
KEPLER = open(os.path.join(ROOT, "tests", "data", "afocal_kepler.zmx")).read()


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
    probe("Sellmeier B nan", lambda: jl.Sellmeier((np.nan, 0.2, 1.0), bk7_c), "B")
    probe("Sellmeier B complex", lambda: jl.Sellmeier((1.0 + 1j, 0.2, 1.0), bk7_c), "B")
    probe("Sellmeier B a 2-D array", lambda: jl.Sellmeier(np.array([bk7_b, bk7_b]), np.array([bk7_c, bk7_c])), "B")
    probe("Sellmeier B strings", lambda: jl.Sellmeier(("1.04", "0.23", "1.01"), bk7_c), "B")
    probe("Sellmeier name 5", lambda: jl.Sellmeier(bk7_b, bk7_c, name=5), "name")
    probe("Schott 5 coefficients", lambda: jl.Schott((2.27, -0.01, 0.01, 0.0, 0.0)), "coeffs", "6")
    probe("Tabulated wavelengths in nm (486, 588, 656)", lambda: float(jl.Tabulated((486.1, 587.6, 656.3), (1.5224, 1.5168, 1.5143)).index(0.5876)), "wavelength", "µm")
    probe("Tabulated unsorted wavelengths", lambda: float(jl.Tabulated((0.6563, 0.4861, 0.5876), (1.5143, 1.5224, 1.5168)).index(0.55)), good=True)
    probe("Tabulated one node", lambda: float(jl.Tabulated((0.5876,), (1.5168,)).index(0.5876)), good=True)
    probe("Tabulated indices bool", lambda: jl.Tabulated((0.4861, 0.5876), (True, True)), "indices")
    probe("ModelGlass vd 0.6417 (a fraction of 64.17?)", lambda: jl.ModelGlass(1.5168, 0.6417), "vd")
    probe("ModelGlass nd 151.68", lambda: jl.ModelGlass(151.68, 64.17), "nd")
    probe("ModelGlass vd 6417", lambda: jl.ModelGlass(1.5168, 6417.0), "vd")
    probe("get_material 'N-BK 7' typo (close matches)", lambda: jl.get_material("N-BK 7"), "N-BK7")
    probe("get_material 'nbk7' (no dash)", lambda: jl.get_material("nbk7"), "N-BK7")
    probe("get_material '' empty", lambda: jl.get_material(""), "name")
    probe("get_material 7 (int)", lambda: jl.get_material(7), "name")
    probe("get_material catalogs 'SHOTT' typo", lambda: jl.get_material("N-BK7", catalogs="SHOTT"), "SCHOTT")
    probe("get_material nd '1.5' string", lambda: jl.get_material("NOPE", nd="1.5", vd=60.0), "nd")
    probe("glass_info 'N-BK77'", lambda: jl.glass_info("N-BK77"), "N-BK7")
    probe("CatalogMaterial wavelength_range (400, 700) nm", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", wavelength_range=(400.0, 700.0)), "wavelength_range", "µm")
    probe("CatalogMaterial formula -3", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", formula=-3), "formula")
    probe("CatalogMaterial catalog_nd 0.5", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "X", catalog_nd=0.5), "catalog_nd")
    probe("CatalogMaterial model not a material", lambda: jl.CatalogMaterial(1.5, "X"), "model")


# ----------------------------------------------------------------------------- JSON materials
def json_materials():
    import copy
    base = lensfile.lens_to_dict(cooke)
    def with_mat(spec, i=1):
        d = copy.deepcopy(base)
        d["surfaces"][i]["material"] = spec
        d["surfaces"][i].pop("index_at_wavelengths", None)
        return lambda: lensfile.lens_from_dict(d)
    probe("JSON class Sellmeier C in nm²", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01], "C": [6000.7, 20017.9, 1.0356e8]}), "C", "µm")
    probe("JSON class Sellmeier 2 B, 3 C", with_mat({"class": "Sellmeier", "B": [1.04, 0.23], "C": [0.006, 0.02, 103.56]}), "B", "C")
    probe("JSON class Sellmeier no C", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01]}), "C")
    probe("JSON class Sellmeier 'coefficients' (misspelt field)", with_mat({"class": "Sellmeier", "B": [1.04, 0.23, 1.01], "C": [0.006, 0.02, 103.56], "coefficents": [1]}), "coefficents")
    probe("JSON class 'sellmeier' lower case", with_mat({"class": "sellmeier", "B": [1.04], "C": [0.006]}), "Sellmeier")
    probe("JSON class Schott 5 coeffs", with_mat({"class": "Schott", "coeffs": [2.27, -0.01, 0.01, 0.0, 0.0]}), "coeffs", "6")
    probe("JSON class Laurent powers 'abc'", with_mat({"class": "Laurent", "coeffs": [2.27, -0.01], "powers": "ab"}), "powers")
    probe("JSON wavelengths_um in nm (486, 588, 656)", with_mat({"wavelengths_um": [486.1, 587.6, 656.3], "indices": [1.52, 1.517, 1.514]}), "wavelength", "µm")
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
    probe("agf Sellmeier C in nm² (names the line)", agf(AGF_GOOD.replace("0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653", "6000.69867 0.231792344 20017.9144 1.01046945 103560653")), "bad.agf:3")
    probe("agf CD with 4 numbers for Sellmeier (names the line)", agf(AGF_GOOD.replace("CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0", "CD 1.03961212 0.00600069867 0.231792344 0.0200179144")), "bad.agf:3")
    probe("agf formula 99 (names the line)", agf(AGF_GOOD.replace("NM GA 2 ", "NM GA 99 ")), "bad.agf:2", "formula")
    probe("agf NM with no nd/vd (names the line)", agf("NM GA 2\nCD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"), "bad.agf:2")
    probe("agf glass given twice (names the line)", agf(AGF_GOOD + AGF_GOOD), "bad.agf:6", "GA")
    probe("agf CD before NM (names the line)", agf("CD 1 2 3\n" + AGF_GOOD), "bad.agf:2")
    probe("agf IT line with 'x' (names the line)", agf(AGF_GOOD + "IT 0.4 x 10\n"), "bad.agf:6")
    probe("agf TD with 'nan' (names the line)", agf(AGF_GOOD.replace("TD 0 0 0 0 0 0 0", "TD nan 0 0 0 0 0 0")), "bad.agf:4")
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
    probe("zmx GLAS 'N-BK8' typo (names line, close matches)", z(KEPLER.replace("GLAS N-BK7 0 0 1.5168 64.17", "GLAS N-BK8 0 0 1.5168 64.17", 1)), "N-BK7", "line")
    probe("zmx GLAS 'NBK7' no dash (close matches)", z(KEPLER.replace("GLAS N-BK7 0 0", "GLAS NBK7 0 0", 1)), "N-BK7")
    probe("zmx GLAS 'n-bk7' lower case", lambda: float(jl.paraxial_data(jl.load(write("lc.zmx", KEPLER.replace("GLAS N-BK7 0 0", "GLAS n-bk7 0 0")))).efl), good=True)
    probe("zmx GCAT 'SHOTT' typo", z(KEPLER.replace("GCAT SCHOTT", "GCAT SHOTT")), "SHOTT")
    probe("zmx GLAS typo unknown_glass='model' keeps GLAS nd/Vd (documented)", lambda: float(jl.load(write("m.zmx", KEPLER.replace("GLAS N-BK7 0 0", "GLAS N-BK8 0 0", 1)), unknown_glass="model").materials[0].index(0.5875618)), good=True)
    probe("zmx GLAS typo unknown_glass='Model' (case)", z(KEPLER.replace("GLAS N-BK7 0 0", "GLAS N-BK8 0 0", 1), unknown_glass="Model"), "unknown_glass")
    probe("zmx GLAS nd 0.5 with unknown_glass='model' (names line)", z(KEPLER.replace("GLAS N-BK7 0 0 1.5168", "GLAS N-BK8 0 0 0.5168", 1), unknown_glass="model"), "line")
    probe("zmx WAVM in nm (587.6)", z(KEPLER.replace("WAVM 2 5.875618E-1 1", "WAVM 2 587.5618 1")), "line", "µm")
    probe("zmx ENPD negative", z(KEPLER.replace("ENPD 1.0E+1", "ENPD -10")), "ENPD")
    probe("zmx DISZ 'abc' (names line)", z(KEPLER.replace("DISZ 120.385013", "DISZ abc")), "line")
    probe("zmx CURV inf", z(KEPLER.replace("CURV -7.739938080495356E-2", "CURV inf")), "line")
    probe("zmx YFLN 1e6 deg field", z(KEPLER.replace("YFLN 0 0.5 1.0", "YFLN 0 0.5 1e6")), "field")


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
    probe("read_png grey+alpha 8-bit (documented: alpha dropped)", lambda: images.read_png(p_ga8).shape, good=True)
    probe("read_png grey+alpha 16-bit (documented: alpha dropped)", lambda: images.read_png(p_ga16).shape, good=True)
    probe("read_png RGBA 16-bit (control)", lambda: images.read_png(p_rgba16).shape, good=True)
    p_exr = os.path.join(TMP, "a.exr")
    images.write_exr(p_exr, np.ones((4, 4, 3)))
    probe("read_png of an .exr file", lambda: images.read_png(p_exr), "PNG")
    p_png = os.path.join(TMP, "a.png")
    images.write_png(p_png, np.ones((4, 4, 3)) * 0.5)
    probe("read_exr of a .png file", lambda: images.read_exr(p_png), "OpenEXR")
    probe("read_exr missing file", lambda: images.read_exr(os.path.join(TMP, "none.exr")), "no such file")
    probe("read_exr channels 'RGB' one string", lambda: images.read_exr(p_exr, channels="RGB").shape, "channels")
    probe("read_exr channels [] empty", lambda: images.read_exr(p_exr, channels=[]), "channels")
    probe("read_exr channels ['R','R'] repeated", lambda: images.read_exr(p_exr, channels=["R", "R"]), "channels")
    probe("read_exr channels 'r' lower case", lambda: images.read_exr(p_exr, channels=["r"]), "R")
    p_nan = os.path.join(TMP, "nan.exr")
    images.write_exr(p_nan, np.ones((4, 4, 3)))
    probe("write_exr NaN pixels", lambda: images.write_exr(os.path.join(TMP, "n.exr"), np.full((4, 4, 3), np.nan)), "nan")
    probe("write_exr complex", lambda: images.write_exr(os.path.join(TMP, "c.exr"), np.ones((4, 4, 3), complex)), "img")
    probe("write_exr bool", lambda: images.write_exr(os.path.join(TMP, "b.exr"), np.ones((4, 4, 3), bool)), "img")
    probe("write_exr uint8 codes", lambda: images.write_exr(os.path.join(TMP, "u.exr"), np.full((4, 4, 3), 200, np.uint8)), "img")
    probe("write_exr (4,4,3,2) 4-D", lambda: images.write_exr(os.path.join(TMP, "d.exr"), np.ones((4, 4, 3, 2))), "img")
    probe("write_exr (0,4,3) empty", lambda: images.write_exr(os.path.join(TMP, "e.exr"), np.ones((0, 4, 3))), "img")
    probe("write_exr 1-D", lambda: images.write_exr(os.path.join(TMP, "f.exr"), np.ones(5)), "img")
    probe("write_exr into a missing folder", lambda: images.write_exr(os.path.join(TMP, "no", "x.exr"), np.ones((4, 4))), "folder")
    probe("write_png into a missing folder", lambda: images.write_png(os.path.join(TMP, "no", "x.png"), np.ones((4, 4))), "folder")
    probe("write_png (0,4,3) empty", lambda: images.write_png(os.path.join(TMP, "e.png"), np.ones((0, 4, 3))), "img")
    probe("write_png (4,4,5)", lambda: images.write_png(os.path.join(TMP, "g.png"), np.ones((4, 4, 5))), "C<=4")
    probe("write_png 0…255 floats (codes given as floats)", lambda: images.write_png(os.path.join(TMP, "h.png"), np.full((4, 4, 3), 200.0)), "img")
    probe("write_png image of 70000 x 70000 x 0? (1,10**9) shape", lambda: images.write_png(os.path.join(TMP, "w.png"), np.broadcast_to(np.float64(0.5), (1, 3 * 10**8))), "img")
    probe("read_psf_stack of an RGB exr (not a stack)", lambda: images.read_psf_stack(p_exr)[1], "stack")
    probe("write_psf_stack NaN psf", lambda: images.write_psf_stack(os.path.join(TMP, "s.exr"), np.full((2, 5, 5), np.nan)), "nan")
    probe("write_psf_stack 2-D (one psf)", lambda: images.write_psf_stack(os.path.join(TMP, "s2.exr"), np.ones((5, 5))), "psfs")
    probe("psnr shapes (4,4,3) vs (4,4)", lambda: images.psnr(np.ones((4, 4, 3)) * 0.5, np.ones((4, 4)) * 0.5), "shape")
    probe("psnr data_range -1", lambda: images.psnr(np.ones((4, 4)) * 0.5, np.ones((4, 4)) * 0.4, data_range=-1.0), "data_range")
    probe("psnr data_range 255 for [0,1] images", lambda: images.psnr(np.ones((4, 4)) * 0.5, np.ones((4, 4)) * 0.4, data_range=255), "data_range")
    probe("ssim complex images", lambda: images.ssim(np.ones((16, 16), complex), np.ones((16, 16), complex)), "complex")
    probe("scene size (10**5, 10**5)", lambda: images.scene("astronaut", (10**5, 10**5)), "size")
    probe("scene size 64 (an int)", lambda: images.scene("astronaut", 64), "size")
    probe("scene 'astronot' typo (close match)", lambda: images.scene("astronot"), "astronaut")


# ----------------------------------------------------------------------------- analysis and imaging
def analysis():
    from jaxlens.analysis import zernike
    x = jnp.linspace(-0.5, 0.5, 5)
    probe("zernike_terms terms 0", lambda: zernike.zernike_terms(x, x, terms=0), "terms")
    probe("zernike_terms terms -5", lambda: zernike.zernike_terms(x, x, terms=-5), "terms")
    probe("zernike_terms terms 10**6", lambda: zernike.zernike_terms(x, x, terms=10**6), "terms")
    probe("zernike_terms terms 37.0 float", lambda: zernike.zernike_terms(x, x, terms=37.0), "terms")
    probe("zernike_terms x and y shapes (5,) vs (4,)", lambda: zernike.zernike_terms(x, x[:4]), "shape")
    probe("zernike_terms x 5 (beyond the unit disc)", lambda: zernike.zernike_terms(x * 10, x * 10), "unit")
    probe("zernike_terms indexing 'Noll'", lambda: zernike.zernike_terms(x, x, indexing="Noll"), "indexing")
    probe("zernike_fit values nan", lambda: zernike.zernike_fit(x, x, jnp.full(5, jnp.nan), terms=3), "values")
    probe("zernike_fit 5 points for 37 terms", lambda: zernike.zernike_fit(x, x, x, terms=37), "terms")
    probe("zernike_fit mask all False", lambda: zernike.zernike_fit(x, x, x, terms=3, mask=jnp.zeros(5, bool)), "mask")
    probe("zernike_fit mask floats 0.5", lambda: zernike.zernike_fit(x, x, x, terms=3, mask=jnp.full(5, 0.5)), "mask")
    probe("zernike_nm j 0 (Noll starts at 1)", lambda: zernike.zernike_nm(0), "j")
    probe("zernike_nm j 2.5", lambda: zernike.zernike_nm(2.5), "j")
    probe("zernike_nm j True", lambda: zernike.zernike_nm(True), "j")
    probe("wavefront grid 10**5", lambda: jl.analysis.wavefront(cooke, 0.0, grid=10**5), "grid")
    probe("wavefront grid 4.5", lambda: jl.analysis.wavefront(cooke, 0.0, grid=4.5), "grid")
    probe("opd_fan n 10**8", lambda: jl.analysis.opd_fan(cooke, 0.0, n=10**8), "n")
    probe("ray_fan n 0", lambda: jl.analysis.ray_fan(cooke, 0.0, n=0), "n")
    probe("clear_semi_diameters n_rim 10**9", lambda: jl.analysis.clear_semi_diameters(cooke, n_rim=10**9), "n_rim")
    probe("clear_semi_diameters n_rim 0", lambda: jl.analysis.clear_semi_diameters(cooke, n_rim=0), "n_rim")
    probe("self_intersection n_radial 10**8", lambda: jl.analysis.self_intersection(cooke, n_radial=10**8), "n_radial")
    probe("self_intersection min_gap -1 mm", lambda: jl.analysis.self_intersection(cooke, min_gap=-1.0), "min_gap")
    probe("self_intersection min_gap nan", lambda: jl.analysis.self_intersection(cooke, min_gap=np.nan), "min_gap")
    probe("seidel field 1.2 rad (deg?)  -> control: degrees", lambda: float(jl.analysis.seidel(cooke, field=1.2).sum_spherical if hasattr(jl.analysis.seidel(cooke, field=1.2), 'sum_spherical') else 0.0), good=True)
    probe("seidel wavelength 587.6 nm", lambda: jl.analysis.seidel(cooke, wavelength=587.6), "wavelength", "µm")
    probe("relative_illumination pupil 10**6", lambda: jl.imaging.radiometry.relative_illumination(cooke, jnp.array([0.0]), pupil=10**6), "pupil")
    probe("relative_illumination pupil 0", lambda: jl.imaging.radiometry.relative_illumination(cooke, jnp.array([0.0]), pupil=0), "pupil")
    probe("distortion_map grid (10**5, 10**5)", lambda: jl.imaging.distortion.distortion_map(cooke, grid=(10**5, 10**5)), "grid")
    probe("distortion_map grid (1, 17)", lambda: jl.imaging.distortion.distortion_map(cooke, grid=(1, 17)), "grid")
    probe("encircled_energy radii in µm (10, 20) -> mm", lambda: jl.analysis.encircled_energy(cooke, 0.0, jnp.array([-0.01, 0.02])), "radii")
    probe("encircled_energy pupil_side 10**5 diffraction", lambda: jl.analysis.encircled_energy(cooke, 0.0, jnp.array([0.01]), method="diffraction", pupil_side=10**5), "pupil_side")
    probe("encircled_energy subsamples 0", lambda: jl.analysis.encircled_energy(cooke, 0.0, jnp.array([0.01]), subsamples=0), "subsamples")


# ----------------------------------------------------------------------------- surfaces, tracing, nets, design
def surfaces():
    probe("Binary2 norm_radius 0", lambda: jl.Binary2(norm_radius=0.0, phase_coeffs=(1.0,)), "norm_radius")
    probe("Binary2 norm_radius -5", lambda: jl.Binary2(norm_radius=-5.0, phase_coeffs=(1.0,)), "norm_radius")
    probe("Binary2 norm_radius nan", lambda: jl.Binary2(norm_radius=np.nan, phase_coeffs=(1.0,)), "norm_radius")
    probe("Binary2 order 0.5", lambda: jl.Binary2(order=0.5, phase_coeffs=(1.0,)), "order")
    probe("Binary2 phase_coeffs nan", lambda: jl.Binary2(phase_coeffs=(np.nan,)), "phase_coeffs")
    probe("Binary2 phase_coeffs 2-D", lambda: jl.Binary2(phase_coeffs=np.ones((2, 2))), "phase_coeffs")
    probe("Grating lines_per_um 600 (lines/mm given)", lambda: jl.Grating(lines_per_um=600.0), "lines_per_um")
    probe("Grating lines_per_um -1", lambda: jl.Grating(lines_per_um=-1.0), "lines_per_um")
    probe("Grating lines_per_um nan", lambda: jl.Grating(lines_per_um=np.nan), "lines_per_um")
    probe("Grating order 1.5", lambda: jl.Grating(lines_per_um=0.6, order=1.5), "order")
    probe("Sensor resolution (0, 10)", lambda: jl.Sensor(resolution=(0, 10), pixel_size=0.005), "resolution")
    probe("Sensor resolution (10**6, 10**6)", lambda: jl.Sensor(resolution=(10**6, 10**6), pixel_size=0.005), "resolution")
    probe("Sensor pixel_size 5.0 (µm given; 5 mm)", lambda: jl.Sensor(resolution=(1000, 1000), pixel_size=5.0), "pixel_size", "mm")
    probe("Sensor resolution 512 (an int)", lambda: jl.Sensor(resolution=512, pixel_size=0.005), "resolution")
    probe("reversed_lens image_distance -1e9", lambda: jl.tracing.backward.reversed_lens(cooke, image_distance=np.nan), "image_distance")
    r = jl.Rays(origin=jnp.zeros((2, 3)), direction=jnp.array([[0.0, 0.0, 1.0]] * 2), wavelength=jnp.full((2,), 0.55)) if "wavelength" in jl.Rays.__dataclass_fields__ else None
    probe("trace_backward newton_iters -1", lambda: jl.trace_backward(cooke, r, newton_iters=-1), "newton_iters")
    probe("trace_backward upto 99", lambda: jl.trace_backward(cooke, r, upto=99), "upto")
    probe("trace_path upto -99", lambda: jl.trace_path(cooke, r, upto=-99), "upto")
    probe("trace newton_iters 10**9", lambda: jl.trace(cooke, r, newton_iters=10**9), "newton_iters")


def nets_design():
    from jaxlens import design, nets
    key = jax.random.PRNGKey(0)
    probe("NAFNet width 0", lambda: nets.NAFNet(width=0, key=key), "width")
    probe("NAFNet width 10**6", lambda: nets.NAFNet(width=10**6, key=key), "width")
    probe("NAFNet enc_blocks (1, -1, 1)", lambda: nets.NAFNet(enc_blocks=(1, -1, 1), key=key), "enc_blocks")
    probe("NAFNet enc_blocks and dec_blocks of different lengths", lambda: nets.NAFNet(enc_blocks=(1, 1), dec_blocks=(1, 1, 1), key=key), "dec_blocks")
    probe("NAFNet in_channels 0", lambda: nets.NAFNet(in_channels=0, key=key), "in_channels")
    probe("NAFNet key an int", lambda: nets.NAFNet(key=0), "key")
    spec = design.DesignSpec()
    probe("sensor_field_grid n 0", lambda: design.sensor_field_grid(spec, n=0), "n")
    probe("sensor_field_grid n 10**6", lambda: design.sensor_field_grid(spec, n=10**6), "n")
    probe("reweighting_mask threshold 80 (percent)", lambda: design.reweighting_mask(jnp.ones((4,)), threshold=80.0), "threshold")
    probe("reweighting_mask rms nan", lambda: design.reweighting_mask(jnp.full((4,), jnp.nan)), "rms")
    probe("random_starts seeds [] empty", lambda: design.random_starts(spec, []), "seeds")
    probe("random_starts seeds -1", lambda: design.random_starts(spec, [-1]), "seeds")
    probe("random_starts seeds 1.5", lambda: design.random_starts(spec, [1.5]), "seeds")
    probe("sine_path steps 0", lambda: design.sine_path(spec, steps=0) if "steps" in design.sine_path.__code__.co_varnames else design.sine_path(0), "steps")


# ----------------------------------------------------------------------------- CLIs
def clis():
    import runpy
    def cli(argv, module=None, path=None):
        def f():
            old = sys.argv
            sys.argv = [module or path] + argv
            try:
                if module:
                    runpy.run_module(module, run_name="__main__")
                else:
                    runpy.run_path(path, run_name="__main__")
                return 0
            finally:
                sys.argv = old
        f.cli = True
        return f
    design_file = os.path.join(ROOT, "jaxlens", "data", "lenses", "cooke_triplet.json")
    T = "jaxlens.experiments.tolerance"
    probe("tolerance CLI missing design file", cli([os.path.join(TMP, "none.json")], T), "design", "no such file")
    probe("tolerance CLI design a folder", cli([TMP], T), "design")
    probe("tolerance CLI --trials 0", cli([design_file, "--trials", "0"], T), "--trials")
    probe("tolerance CLI --trials 10**9", cli([design_file, "--trials", str(10**9)], T), "--trials")
    probe("tolerance CLI --threshold 0.006 (mm given)", cli([design_file, "--threshold", "0.006"], T), "--threshold", "µm")
    probe("tolerance CLI --threshold nan", cli([design_file, "--threshold", "nan"], T), "--threshold")
    probe("tolerance CLI --seed -1", cli([design_file, "--seed", "-1"], T), "--seed")
    probe("tolerance CLI --decenter 10 µm given as 10", cli([design_file, "--decenter", "10"], T), "--decenter", "mm")
    probe("tolerance CLI --tilt 0.01 rad? ok; --tilt nan", cli([design_file, "--tilt", "nan"], T), "--tilt")
    probe("tolerance CLI --out a file", cli([design_file, "--out", __file__], T), "--out")
    C = os.path.join(HERE, "check_corpus.py")
    probe("check_corpus --unknown-glass Model", cli([TMP, "--unknown-glass", "Model"], path=C), "unknown-glass")
    probe("check_corpus a .zmx file (not a folder)", cli([write("c.zmx", KEPLER)], path=C), "folder")
    B = "benchmarks"
    probe("benchmarks --counts 0", cli(["--counts", "0", "--only", "throughput", "--out", os.path.join(TMP, "b0")], B), "--counts")
    probe("benchmarks --counts 10**12", cli(["--counts", str(10**12), "--only", "throughput", "--out", os.path.join(TMP, "b1")], B), "--counts")
    probe("benchmarks --lenses nosuch", cli(["--lenses", "nosuch", "--only", "throughput", "--out", os.path.join(TMP, "b2")], B), "--lenses")
    probe("benchmarks --tag '../x' (path in a tag)", cli(["--tag", "../x", "--only", "throughput", "--smoke", "--out", os.path.join(TMP, "b3")], B), "--tag")
    probe("benchmarks --smoke --full together", cli(["--smoke", "--full", "--only", "throughput", "--out", os.path.join(TMP, "b4")], B), "--full")
    probe("benchmarks --out a file", cli(["--out", __file__, "--only", "throughput", "--smoke"], B), "--out")


AREAS = [materials, json_materials, agf_cases, zmx_glass, image_cases, analysis, surfaces, nets_design, clis]
if os.environ.get("AUDIT25_AREAS"):
    AREAS = [a for a in AREAS if a.__name__ in os.environ["AUDIT25_AREAS"].split(",")]
run(AREAS)
