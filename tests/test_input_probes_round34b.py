"""Bad input, round 34b (tools/audit34b_probe.py): JSON lens files, image files and the
command lines. One test per class of gap fixed; each names what main did with the input: a
value given under two keys (one dropped without a word), a key of a closed section that no
one reads, a field type that disagrees with its values, weights of another length, an
alpha channel written through the sRGB curve or read as the grey, a value beyond float32
written as inf, a file written in place, an option another option makes unread."""

import glob
import json
import os
import pathlib
import warnings

import numpy as np
import pytest

import jaxlens as jl

ROOT = pathlib.Path(__file__).resolve().parents[1]
COOKE = ROOT / "jaxlens" / "data" / "lenses" / "cooke_triplet.json"


def _lens_file(tmp_path, edit) -> pathlib.Path:
    """cooke_triplet.json (wavelengths_nm 486.1327, 587.5618, 656.2725; primary 587.5618 nm;
    aperture.epd 10; fields 0, 14, 20 deg) with ``edit`` applied to its object."""
    d = json.loads(COOKE.read_text())
    edit(d)
    p = tmp_path / "lens.json"
    p.write_text(json.dumps(d))
    return p


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.update(EPD=50.0), r"EPD 50 and aperture\.epd 10 disagree \(both give the epd"),
    (lambda d: d["aperture"].update(EPD=50.0), r"aperture\.epd 10 and aperture\.EPD 50 disagree"),
    (lambda d: d.update(aperture={"fnum": 4, "FNUM": 8}),
     r"aperture\.fnum 4 and aperture\.FNUM 8 disagree \(both give the fnum"),
    (lambda d: d.update(aperture={"fnum": 4, "f_number": 8}),
     r"aperture\.fnum 4 and aperture\.f_number 8 disagree"),
])
def test_lens_file_aperture_under_two_keys_must_agree(tmp_path, edit, match):
    """Main: the first key of a kind was used and the other dropped without a word (``"EPD":
    50`` beside ``aperture.epd`` 10 gave an EPD of 50), though the format says several
    aperture keys must agree."""
    with pytest.raises(ValueError, match=rf"lens\.json: {match}"):
        jl.load(_lens_file(tmp_path, edit))


def test_lens_file_aperture_under_two_keys_that_agree_loads(tmp_path):
    lens = jl.load(_lens_file(tmp_path, lambda d: d.update(EPD=10.0)))
    assert float(lens.epd) == 10.0


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.update(primary=0), r"primary 0 and primary_wavelength_nm 587\.5618 disagree: "
                                    r"they name wavelengths 0 \(0\.486133 µm\) and 1"),
    (lambda d: d.update(primary_wavelength_um=0.6562725),
     r"primary_wavelength_um 0\.6562725 and primary_wavelength_nm 587\.5618 disagree"),
])
def test_lens_file_primary_keys_must_agree(tmp_path, edit, match):
    """Main: ``primary`` won over ``primary_wavelength_nm`` (and ``_um`` over ``_nm``) without
    a word: the lens's primary was another wavelength than the file's other key named."""
    with pytest.raises(ValueError, match=rf"lens\.json: {match}"):
        jl.load(_lens_file(tmp_path, edit))


def test_lens_file_primary_keys_that_agree_load(tmp_path):
    assert jl.load(_lens_file(tmp_path, lambda d: d.update(primary=1))).primary == 1


@pytest.mark.parametrize("section, value, key", [
    ("units", {"lengths": "in"}, "lengths"), ("units", {"length_unit": "in"}, "length_unit"),
    ("units", {"angle_unit": "rad"}, "angle_unit"),
    ("sensor", {"resolution": [8, 8], "pixel_size": 0.005, "pixel_size_um": 9}, "pixel_size_um"),
    ("sensor", {"resolution": [8, 8], "pixel_size": 0.005, "offset": [1, 2]}, "offset"),
    ("object", {"distance": 1000, "height": 5}, "height"),
    ("fields", {"values": [0, 14, 20], "unit": "rad"}, "unit"),
])
def test_lens_file_closed_section_refuses_a_key_it_does_not_read(tmp_path, section, value, key):
    """Main: a key of ``units``, ``sensor``, ``object`` or ``fields`` that the reader does not
    read passed as a comment: ``"units": {"lengths": "in"}`` read inches as mm, ``"fields":
    {"unit": "rad"}`` radians as degrees."""
    with pytest.raises(ValueError, match=rf"lens\.json: {section}: unknown key '{key}'"):
        jl.load(_lens_file(tmp_path, lambda d: d.update({section: value})))


def test_lens_file_closed_sections_as_documented_load(tmp_path):
    def edit(d):
        d.update(units={"length": "mm", "wavelength": "nm", "angle": "deg"},
                 sensor={"resolution": [8, 8], "pixel_size": 0.005}, object={"distance": "inf"})
        d["fields"]["vignetting"] = {"vdy": [0, 0, 0.1]}
    lens = jl.load(_lens_file(tmp_path, edit))
    assert lens.sensor.resolution == (8, 8)


@pytest.mark.parametrize("ftype, values, match", [
    ("angle_deg_y", [[0, 0], [0, 10]], r"fields\.type 'angle_deg_y' declares one angle θy per "
                                       r"field, but fields\.values holds pairs"),
    ("angle_deg_xy", [0, 10, 14], r"fields\.type 'angle_deg_xy' declares \[θx, θy\] pairs, but "
                                  r"fields\.values holds single angles"),
])
def test_lens_file_field_type_must_match_its_values(tmp_path, ftype, values, match):
    """Main: the values' shape won over the declared type without a word (θy angles read as
    θy, pairs declared θy read as (θx, θy))."""
    with pytest.raises(ValueError, match=rf"lens\.json: {match}"):
        jl.load(_lens_file(tmp_path, lambda d: d.update(fields={"type": ftype,
                                                                "values": values})))
    lens = jl.load(_lens_file(tmp_path, lambda d: d.update(fields={"type": "angle_deg",
                                                                   "values": values})))
    assert np.asarray(lens.fields).shape == np.asarray(values).shape


@pytest.mark.parametrize("edit, match", [
    (lambda d: d["fields"].update(weights=[1, 1]),
     r"fields\.weights must hold one weight per field \(3\), got \[1, 1\]"),
    (lambda d: d.update(field_weights=[1, 1, 1, 1, 1]), r"field_weights must hold one weight per "
                                                        r"field \(3\)"),
    (lambda d: d.update(wavelength_weights=[1, 1]), r"wavelength_weights must hold one weight "
                                                    r"per wavelength \(3\)"),
])
def test_lens_file_weights_of_another_length_are_refused(tmp_path, edit, match):
    """Main: ``fields.weights`` of 2 values for 3 fields passed (equal weights are not even
    warned about), where the ``.zmx`` reader refuses FWGN of another count."""
    with pytest.raises(ValueError, match=rf"lens\.json: {match}"):
        jl.load(_lens_file(tmp_path, edit))


def test_lens_files_round_trip_exactly(tmp_path):
    """Control: every shipped JSON lens loads, saves and loads again to the same leaves, and
    saves to the same text."""
    import jax

    for src in sorted(glob.glob(str(ROOT / "jaxlens" / "data" / "lenses" / "*.json"))):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = jl.load(src)
            jl.save(a, tmp_path / "a.json")
            b = jl.load(tmp_path / "a.json")
            jl.save(b, tmp_path / "b.json")
        assert (tmp_path / "a.json").read_text() == (tmp_path / "b.json").read_text(), src
        la, ta = jax.tree_util.tree_flatten(a)
        lb, tb = jax.tree_util.tree_flatten(b)
        assert ta == tb, src
        for x, y in zip(la, lb, strict=True):
            np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=src)


@pytest.mark.parametrize("channels", [2, 4])
def test_write_png_writes_alpha_as_coverage(tmp_path, channels):
    """Main: the sRGB curve was applied to every channel, alpha too: alpha 0.5 was written as
    code 188 (0.735 coverage)."""
    from PIL import Image

    from jaxlens.io import images

    img = np.full((2, 3, channels), 0.5)
    images.write_png(tmp_path / "a.png", img)
    codes = np.asarray(Image.open(tmp_path / "a.png"))
    assert codes.shape == (2, 3, channels)
    assert np.all(codes[..., -1] == 128)  # alpha as given
    assert np.all(codes[..., :-1] == 188)  # the colour sRGB-encoded, as before


def test_read_exr_leaves_alpha_out_by_default(tmp_path):
    """Main: a grey+alpha EXR (channels Y, A) was read as [H, W, 2] in sorted order: alpha
    first, where the image's grey belongs."""
    from jaxlens.io import images

    img = np.dstack([np.full((2, 3), 0.25), np.ones((2, 3))])
    images.write_exr(tmp_path / "ya.exr", img, channels=("Y", "A"))
    got = images.read_exr(tmp_path / "ya.exr")
    assert got.shape == (2, 3) and np.all(got == 0.25)
    assert images.read_exr(tmp_path / "ya.exr", channels=("Y", "A")).shape == (2, 3, 2)
    images.write_exr(tmp_path / "rgba.exr", np.dstack([img[..., :1]] * 3 + [img[..., 1:]]),
                     channels=("R", "G", "B", "A"))
    assert images.read_exr(tmp_path / "rgba.exr").shape == (2, 3, 3)  # control


@pytest.mark.parametrize("write, arg", [
    (lambda m, p, v: m.write_exr(p, np.full((2, 2), v)), "img"),
    (lambda m, p, v: m.write_psf_stack(p, np.full((1, 3, 3), v)), "psfs"),
])
def test_exr_writers_refuse_values_beyond_float32(tmp_path, write, arg):
    """Main: 1e300 (finite in float64) was cast to float32's inf and written as inf."""
    from jaxlens.io import images

    with pytest.raises(ValueError, match=rf"{arg} must be finite values within float32's range "
                                         rf"\(\|v\| <= 3\.403e\+38\).*got 1e\+300"):
        write(images, tmp_path / "x.exr", 1e300)
    assert not (tmp_path / "x.exr").exists()
    write(images, tmp_path / "x.exr", 3e38)  # control: within range


def _figure():
    from jaxlens import plot

    return plot.plot_layout(jl.load(COOKE))


@pytest.mark.parametrize("name, write", [
    ("a.png", lambda p: __import__("jaxlens.io.images", fromlist=["x"]).write_png(
        p, np.full((4, 4), 0.5))),
    ("a.exr", lambda p: __import__("jaxlens.io.images", fromlist=["x"]).write_exr(
        p, np.full((4, 4), 0.5))),
    ("a.exr", lambda p: __import__("jaxlens.io.images", fromlist=["x"]).write_psf_stack(
        p, np.full((2, 3, 3), 0.5))),
    ("fig.png", lambda p: __import__("jaxlens.plot", fromlist=["x"]).save(_figure(), p)),
    ("tolerance.json", lambda p: __import__("jaxlens.experiments.tolerance", fromlist=["x"])
     .write_report({"command": "x", "trials": list(range(1000))}, os.path.dirname(p))),
])
def test_image_figure_and_report_writers_write_whole(tmp_path, monkeypatch, name, write):
    """Main: ``write_png``, ``write_exr``, ``write_psf_stack``, ``plot.save`` (every figure
    of ``report --plot``, ``classical``, ``tolerance``) and ``tolerance.json`` (replaced by
    ``--overwrite``) were written in place: a run stopped mid-write left a cut file where the
    earlier one was. Now each goes to a temporary file renamed into place."""
    old = tmp_path / name
    old.write_bytes(b"the earlier file")
    fig = _figure() if name == "fig.png" else None  # built before os.replace is cut

    def cut(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(os, "replace", cut)
    with pytest.raises(KeyboardInterrupt):
        if fig is not None:
            from jaxlens import plot
            plot.save(fig, old)
        else:
            write(str(old))
    assert old.read_bytes() == b"the earlier file"
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no partial file left
    monkeypatch.undo()
    write(str(old))
    assert old.read_bytes() != b"the earlier file"


def test_classical_refuses_material_catalogs_with_fixed_materials(monkeypatch, capsys,
                                                                  tmp_path):
    """Main: ``--material-catalogs CDGM`` without ``--select-materials continuous`` (or
    ``search``) designed with the fixed ``--materials`` and dropped the catalogs without a
    word."""
    from jaxlens.experiments import classical as C

    class Started(Exception):
        pass

    def started(*a, **k):
        raise Started
    monkeypatch.setattr(C, "run_design", started)
    code = C.main(["--out", str(tmp_path / "run"), "--material-catalogs", "CDGM"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and "--material-catalogs would be ignored with --select-materials fixed" \
        in err, err
    assert not (tmp_path / "run").exists()
    with pytest.raises(Started):  # control
        C.main(["--out", str(tmp_path / "run"), "--material-catalogs", "CDGM",
                "--select-materials", "continuous"])


def test_benchmark_figures_are_written_whole():
    """Main: the benchmarks' figures (imaging, pareto, throughput, skipping) were written in
    place with ``fig.savefig(path)``: a run stopped mid-write left a cut PNG where the earlier
    run's was. Each now goes through ``common.save_figure`` (a temporary file renamed)."""
    files = [p for p in sorted((ROOT / "benchmarks").glob("*.py")) if p.name != "common.py"]
    bad = [f"{p.name}:{k}" for p in files
           for k, ln in enumerate(p.read_text().splitlines(), 1) if ".savefig(" in ln]
    assert not bad, bad
