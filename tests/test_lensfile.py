"""JSON lens files: reference cases, bit-exact round trips, materials, errors."""

import dataclasses
import json
import pathlib
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens
from jaxlens.io import lensfile
from jaxlens.optics.catalog import get_material, load_agf
from jaxlens.optics.lens import Sensor
from jaxlens.optics.materials import Air, ModelGlass, Sellmeier, Tabulated
from jaxlens.optics.surfaces import EvenAsphere, Hybrid, Standard

DATA = pathlib.Path(jaxlens.__file__).parent / "data" / "lenses"
DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "lens-format.md"


def assert_same_lens(a, b):
    """Same pytree structure (types, static data) and bit-identical numbers."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    assert ta == tb
    for x, y in zip(la, lb, strict=True):
        assert np.asarray(x).shape == np.asarray(y).shape
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def _refcases(refcase_dir):
    return sorted(refcase_dir.glob("*.json"))


def test_refcases_paraxial(refcase_dir):
    for path in _refcases(refcase_dir):
        ref = json.loads(path.read_text())
        lens = jaxlens.load(path)
        assert lens.thickness.dtype == jnp.float64
        assert lens.object_at_infinity
        assert lens.stop == ref["stop_surface_index"] - 1
        assert float(lens.epd) == ref["aperture"]["EPD"]
        np.testing.assert_array_equal(np.asarray(lens.fields), ref["fields"]["values"])
        wl = np.asarray(lens.wavelengths)
        assert wl[lens.primary] == pytest.approx(ref["primary_wavelength_nm"] / 1000, rel=1e-15)
        assert float(jaxlens.efl(lens)) == pytest.approx(ref["paraxial"]["EFL"], rel=1e-10)
        assert float(jaxlens.bfl(lens)) == pytest.approx(ref["paraxial"]["BFL"], rel=1e-10)
        # The tabulated indices are exact at the system wavelengths.
        for i, s in enumerate(ref["surfaces"][1:-1]):
            n = np.asarray(lens.materials[i].index(lens.wavelengths))
            np.testing.assert_array_equal(n, [s["n"][k] for k in s["n"]])


def test_refcases_real_rays(refcase_dir):
    for path in _refcases(refcase_dir):
        ref = json.loads(path.read_text())
        lens = jaxlens.load(path)
        rr = ref["real_rays"]
        origin = np.array([r["launch"]["point_on_EP_plane"] for r in rr])
        direction = np.array([r["launch"]["direction_cosines"] for r in rr])
        wl = np.array([r["wavelength_nm"] for r in rr]) / 1000.0
        out = jaxlens.trace(lens, jaxlens.Rays(origin, direction, wl))
        assert bool(jnp.all(out.valid))
        xyz = np.array([[r["image"][k] for k in "xyz"] for r in rr])
        lmn = np.array([[r["image"][k] for k in "LMN"] for r in rr])
        np.testing.assert_allclose(np.asarray(out.origin), xyz, rtol=0, atol=1e-9)
        np.testing.assert_allclose(np.asarray(out.direction), lmn, rtol=0, atol=1e-12)


def test_refcase_round_trip(refcase_dir, tmp_path):
    for path in _refcases(refcase_dir):
        lens = jaxlens.load(path)
        out = tmp_path / path.name
        jaxlens.save(lens, out)
        assert_same_lens(lens, jaxlens.load(out))
        # Writing is deterministic.
        again = tmp_path / ("again_" + path.name)
        jaxlens.save(jaxlens.load(out), again)
        assert out.read_text() == again.read_text()


def _user_glass(tmp_path):
    agf = tmp_path / "MYCAT.agf"
    agf.write_text(
        "CC test catalog\n"
        "NM MYGLASS 2 517642 1.5168 64.17 0 1\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
        "LD 0.3 2.5\n"
    )
    return load_agf(agf)["MYGLASS"]


def every_kind_of_lens(tmp_path):
    """A lens using every surface type, material kind and system setting."""
    return jaxlens.Lens(
        surfaces=(
            Hybrid(
                c=0.02,
                k=-1.5,
                coeffs=[1e-3, 2e-5, -3e-7, 1e-9],
                odd_x=[1e-4, 2e-6],
                odd_y=[-3e-5, 4e-7],
                semi_diameter=5.0,
            ),
            Standard(c=-0.01),
            EvenAsphere(c=-0.01, k=2.0, coeffs=np.arange(1, 11) * 1e-9, semi_diameter=6.0),
            EvenAsphere(c=-0.011, k=-30.0, coeffs=[0.0, 1e-5], semi_diameter=6.0),
            Standard(c=0.0, k=0.0, semi_diameter=3.0),
            Standard(c=0.03, k=0.5),
            Standard(c=-0.02),
            EvenAsphere(c=0.001, k=0.0, coeffs=[]),
        ),
        thickness=[3.0, 2.0, 4.0, 1.0, 2.0, 3.0, 5.0, 15.0],
        materials=(
            get_material("N-BK7"),
            Air(),
            ModelGlass(1.55, 50.0),
            get_material("E48R"),
            get_material("OKP4"),
            _user_glass(tmp_path),
            Tabulated([0.45, 0.55, 0.66], [1.6, 1.59, 1.585], name="TAB 1"),
            Sellmeier([1.0, 0.2], [0.01, 100.0], name="hand made"),
        ),
        stop=4,
        epd=4.0,
        fields=[0.0, 10.0, 20.0],
        wavelengths=[0.4861327, 0.5875618, 0.6562725],
        primary=1,
        object_distance=500.0,
        object_material=ModelGlass(1.333, 55.0),
        image=Standard(c=-0.01, k=0.0, semi_diameter=12.0),
        sensor=Sensor((480, 640), 0.005),
        name="every kind",
    )


def test_json_round_trip_every_kind(tmp_path):
    lens = every_kind_of_lens(tmp_path)
    path = tmp_path / "lens.json"
    jaxlens.save(lens, path)
    back = jaxlens.load(path)
    assert_same_lens(lens, back)
    assert back.materials[0] is not lens.materials[0]
    spec = json.loads(path.read_text())
    assert spec["format"] == lensfile.FORMAT
    assert spec["surfaces"][1]["material"] == "N-BK7"  # shipped glasses by name
    assert spec["surfaces"][6]["material"]["class"] == "CatalogMaterial"  # user AGF glass
    assert spec["surfaces"][0]["material"] == {"nd": 1.333, "vd": 55.0}
    assert spec["surfaces"][-1] == {
        "type": "image",
        "shape": "standard",
        "curvature": -0.01,
        "conic": 0.0,
        "semi_diameter": 12.0,
    }
    # float32 lenses are written exactly too (read back as float64).
    lens32 = lens.astype(jnp.float32)
    jaxlens.save(lens32, path)
    back32 = jaxlens.load(path, dtype=jnp.float32)
    assert_same_lens(lens32, back32)


def test_sample_lenses_load():
    paths = sorted(DATA.glob("*.json")) + sorted(DATA.glob("*.zmx"))
    assert len(paths) >= 4
    for p in paths:
        lens = jaxlens.load(p)
        assert np.isfinite(float(jaxlens.efl(lens)))
    # The .zmx samples are the .json samples written by save() (a .zmx has no description).
    # A .zmx lens traces by Zemax's rule (negative_propagation), which a .zmx file does not
    # write and the JSON samples do not set.
    for p in DATA.glob("*.zmx"):
        twin = dataclasses.replace(jaxlens.load(p.with_suffix(".json")), description="",
                                   negative_propagation=True)
        assert_same_lens(twin, jaxlens.load(p))
    dg = jaxlens.load(DATA / "double_gauss.json")  # aperture given as F/5
    assert float(jaxlens.efl(dg) / dg.epd) == pytest.approx(5.0, rel=1e-14)


def test_description_is_kept_by_load_and_save(tmp_path):
    """A JSON file's free-text description survives load → save → load; a non-string one
    is refused naming the file."""
    lens = jaxlens.load(DATA / "cooke_triplet.json")
    assert lens.description.startswith("Cooke triplet, f = 50 mm, F/5.")
    path = tmp_path / "lens.json"
    jaxlens.save(lens, path)
    assert json.loads(path.read_text())["description"] == lens.description
    assert_same_lens(jaxlens.load(path), lens)
    jaxlens.save(dataclasses.replace(lens, description=""), path)
    assert "description" not in json.loads(path.read_text())
    d = json.loads((DATA / "cooke_triplet.json").read_text())
    d["description"] = ["not", "text"]
    with pytest.raises(ValueError, match=r"x.json: description must be a string, got list"):
        lensfile.lens_from_dict(d, source="x.json")


def _doc_lenses():
    text = DOCS.read_text(encoding="utf-8")
    blocks = re.findall(r"```json\n(.*?)```", text, flags=re.S)
    return [json.loads(b) for b in blocks if '"surfaces"' in b]


def test_docs_examples_load():
    docs = _doc_lenses()
    assert len(docs) >= 2
    for d in docs:
        lens = lensfile.lens_from_dict(d, source="docs")
        assert np.isfinite(float(jaxlens.efl(lens)))
    singlet, plastic = docs[0], docs[1]
    lens = lensfile.lens_from_dict(singlet)
    assert lens.sensor.resolution == (480, 640)
    assert float(jaxlens.efl(lens)) == pytest.approx(51.68 / (0.5168), rel=1e-3)
    lens = lensfile.lens_from_dict(plastic)
    assert float(lens.epd) == pytest.approx(float(jaxlens.efl(lens)) / 2.4, rel=1e-14)
    assert isinstance(lens.materials[-1], ModelGlass)  # image space is not air
    assert float(lens.image.c) == -1 / 20.0


def test_materials_and_apertures():
    base = {
        "surfaces": [
            {"type": "object", "thickness": 1000.0},
            {"radius": 50, "thickness": 5, "material": None, "is_stop": True},
            {"radius": -50, "thickness": 45},
            {"type": "image"},
        ],
        "aperture": {"epd": 10},
    }

    def lens_with(material, **top):
        d = json.loads(json.dumps(base))
        d["surfaces"][1]["material"] = material
        d.update(top)
        return lensfile.lens_from_dict(d)

    m = lens_with("n-bk7").materials[0]
    assert m.name == "N-BK7"
    m = lens_with({"nd": 1.5168, "vd": 64.17}).materials[0]
    assert float(m.index(0.5875618)) == 1.5168
    m = lens_with({"n": {"486.1327": 1.5224, "587.5618": 1.5168}}).materials[0]
    assert float(m.index(0.5875618)) == 1.5168  # nm keys land exactly on µm wavelengths
    m = lens_with({"wavelengths_um": [0.5, 0.6], "indices": [1.51, 1.50]}).materials[0]
    assert isinstance(m, Tabulated) and float(m.index(0.6)) == 1.50
    lens = lens_with("air", wavelengths_nm=[486.1327, 587.5618], primary_wavelength_nm=587.5618)
    assert lens.primary == 1 and float(lens.wavelengths[1]) == 0.5875618
    assert float(lens.object_distance) == 1000.0
    lens = lens_with("N-BK7", aperture={"stop_semi_diameter": 5.0})
    assert float(lens.epd) == pytest.approx(10.0, rel=1e-15)  # stop on surface 1
    assert not np.isfinite(float(lens.surfaces[0].semi_diameter))
    lens = lens_with("N-BK7", aperture={"fnum": 4.0})
    assert float(lens.epd) == pytest.approx(float(jaxlens.efl(lens)) / 4, rel=1e-15)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda d: d["surfaces"][1].update(material="N-BK8"), r"surface 1.*N-BK7"),
        (lambda d: d["surfaces"][1].pop("thickness"), r"surface 1: missing 'thickness'"),
        (lambda d: d["surfaces"][2].update(is_stop=True), r"more than one surface has is_stop"),
        (lambda d: d["surfaces"][1].update(radius=10, curvature=0.2), r"disagree"),
        (lambda d: d["surfaces"][1].update(thickness="nan"), r"finite number"),
        (lambda d: d["surfaces"][1].update(conic=[1]), r"conic: expected a number"),
        (lambda d: d["surfaces"][1].update(type="gradient_index"), r"unknown surface type"),
        (lambda d: d.update(format="jaxlens.optics.lens/99"), r"unsupported format"),
        (lambda d: d.pop("aperture"), r"no aperture"),
        (lambda d: d.update(primary_wavelength_nm=500.0), r"not one of the wavelengths"),
        (lambda d: d["surfaces"][1].update(material={"nd": 1.5, "vd": -3}), r"model glass"),
        (lambda d: d["surfaces"][1].update(material={"class": "Unobtainium"}), r"unknown"),
        (lambda d: d["surfaces"][1].update(n={"500": 1.5, "600": "x"}), r"expected a number"),
    ],
)
def test_bad_files(change, match):
    d = {
        "surfaces": [
            {"type": "object", "thickness": "inf"},
            {"radius": 50, "thickness": 5, "material": "N-BK7", "is_stop": True},
            {"radius": -50, "thickness": 45},
            {"type": "image"},
        ],
        "aperture": {"epd": 10},
        "wavelengths_nm": [587.5618],
    }
    change(d)
    with pytest.raises(ValueError, match=match):
        lensfile.lens_from_dict(d, source="bad.json")


def test_unknown_glass_lists_close_matches():
    with pytest.raises(ValueError) as e:
        lensfile.material_from_spec("N-BK8", "x.json: surface 1")
    msg = str(e.value)
    assert "x.json: surface 1" in msg and "N-BK7" in msg and "N-BK8" in msg


def test_json_syntax_error_names_line(tmp_path):
    p = tmp_path / "broken.json"
    p.write_text('{\n  "surfaces": [\n    {"radius": 5,,}\n  ]\n}\n')
    with pytest.raises(ValueError, match=r"broken\.json:3: not valid JSON"):
        jaxlens.load(p)
    with pytest.raises(ValueError, match=r"extension"):
        jaxlens.load(tmp_path / "lens.txt")


def test_saved_lens_is_differentiable(tmp_path):
    """A loaded lens is an ordinary pytree: gradients reach its numbers."""
    lens = jaxlens.load(DATA / "cooke_triplet.json")
    g = jax.grad(lambda l: jaxlens.efl(l))(lens)
    assert float(jnp.abs(g.surfaces[0].c)) > 0
    lens2 = eqx.tree_at(lambda l: l.thickness, lens, lens.thickness * 1.01)
    jaxlens.save(lens2, tmp_path / "l.json")
    assert_same_lens(lens2, jaxlens.load(tmp_path / "l.json"))


def test_refcase_style_held_out_features():
    """Aspheres to A12 with conics, plastics, a curved image, image space not air."""
    n = {"486.1327": 1.5, "587.5618": 1.49, "656.2725": 1.485}
    d = {
        "wavelengths_nm": [486.1327, 587.5618, 656.2725],
        "primary_wavelength_nm": 587.5618,
        "aperture": {"EPD": 2.0},
        "fields": {"type": "angle_deg_y", "values": [0.0, 20.0]},
        "surfaces": [
            {
                "index": 0,
                "type": "object",
                "radius": "inf",
                "thickness": "inf",
                "n": {k: 1.0 for k in n},
                "material": "air",
            },
            {
                "index": 1,
                "type": "Even Asphere",
                "radius": 2.5,
                "curvature": 0.4,
                "thickness": 1.0,
                "conic": -12.5,
                "material": "E48R",
                "n": n,
                "is_stop": True,
                "even_asphere_coeffs": [1e-3, -2e-3, 3e-4, -4e-5, 5e-6, -6e-7],
                "semi_diameter_real_rays": 1.0,
            },
            {
                "index": 2,
                "type": "sphere",
                "radius": -4.0,
                "curvature": -0.25,
                "thickness": 3.0,
                "conic": 0.0,
                "even_asphere_coeffs": [],
                "material": "OIL",
                "n": {k: v + 0.02 for k, v in n.items()},
            },
            {
                "index": 3,
                "type": "image",
                "radius": -30.0,
                "curvature": -1 / 30.0,
                "material": "air",
                "n": {k: 1.0 for k in n},
                "z_vertex": 4.0,
            },
        ],
    }
    # Air after the image surface, oil before it: the trace ends in the oil, and says so.
    with pytest.warns(UserWarning, match=r"after the image surface \(n = 1\) is not image "
                                         r"space \(n = 1\.51\)"):
        lens = lensfile.lens_from_dict(d)
    s = lens.surfaces[0]
    assert isinstance(s, EvenAsphere) and float(s.k) == -12.5 and s.coeffs.shape == (6,)
    assert float(s.paraxial_curvature) == 0.4 + 2e-3
    assert isinstance(lens.surfaces[1], Standard)
    assert isinstance(lens.materials[1], Tabulated) and lens.materials[1].name == "OIL"
    assert float(lens.materials[1].index(0.5875618)) == 1.51  # image space is the oil
    assert float(lens.image.c) == -1 / 30.0
    assert isinstance(lens.object_material, Air)
    assert np.isfinite(float(jaxlens.efl(lens)))
    d["surfaces"][1]["type"] = "odd_asphere"  # its even_asphere_coeffs do not fit that type
    with pytest.raises(ValueError, match="surface 1: an odd asphere takes its terms as "
                                         "odd_asphere_coeffs"):
        lensfile.lens_from_dict(d)


def test_a_surface_the_class_refuses_names_the_file_and_surface(tmp_path):
    """A semi-diameter wider than a sphere's radius is refused by the surface class; the
    reader reports it with the file and the surface's index."""
    lens = jaxlens.zoo.cooke_triplet()
    path = tmp_path / "wide.json"
    jaxlens.save(lens, path)
    d = json.loads(path.read_text())
    d["surfaces"][1]["semi_diameter"] = 3 / abs(d["surfaces"][1]["curvature"])
    path.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: surface 1: .*defined only"):
        jaxlens.load(path)
