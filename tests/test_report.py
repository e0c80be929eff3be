"""The report CLI: ``python -m jaxlens report LENS [--json]``, run in-process (one compile)."""

import json
import subprocess
import sys
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

from jaxlens.__main__ import main


@pytest.fixture(scope="module")
def cooke(refcase_dir):
    path = refcase_dir / "cooke_triplet.json"
    if not path.exists():
        pytest.skip("no cooke_triplet reference case")
    return path, json.loads(path.read_text())


def _run(capsys, *argv):
    code = main(["report", *map(str, argv)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_report_json_matches_reference(cooke, capsys):
    path, ref = cooke
    code, out, _ = _run(capsys, path, "--json")
    assert code == 0
    data = json.loads(out)
    assert {"efl", "bfl", "fnum", "epd", "total_track", "fields"} <= set(data)
    assert data["units"]["length"] == "mm" and data["units"]["distortion"] == "%"
    assert data["units"]["rms_spot"] == "um" and data["units"]["rms_spot_mm"] == "mm"
    assert data["efl"] == pytest.approx(ref["paraxial"]["EFL"], rel=1e-10)
    assert data["bfl"] == pytest.approx(ref["paraxial"]["BFL"], rel=1e-10)
    assert data["epd"] == ref["aperture"]["EPD"]
    assert data["fnum"] == pytest.approx(ref["paraxial"]["EFL"] / ref["aperture"]["EPD"])
    assert data["total_track"] == pytest.approx(ref["surfaces"][-1]["z_vertex"], rel=1e-14)
    assert data["fov"] == 2 * max(ref["fields"]["values"])
    assert [f["angle"] for f in data["fields"]] == ref["fields"]["values"]
    for f, spot in zip(data["fields"], ref["rms_spot"], strict=True):
        want = [v["rms_vs_centroid"] for v in spot["per_wavelength"].values()]
        assert f["rms_spot_mm"] == pytest.approx(want, rel=1e-9)
        assert f["rms_spot"] == pytest.approx([1000 * v for v in want], rel=1e-9)
        assert f["valid_fraction"] == [1.0, 1.0, 1.0]
    by_angle = {f["angle"]: f for f in data["fields"]}
    for d in ref["distortion"]:
        f = by_angle[d["field_angle_deg"]]
        assert f["chief_ray_height"] == pytest.approx(d["chief_ray_y_real"], abs=1e-9)
        assert f["distortion"] == pytest.approx(d["distortion_pct_ftan"], abs=1e-9)
        assert f["distortion_paraxial"] == pytest.approx(
            d["distortion_pct_vs_paraxial_chief_at_image"], abs=1e-9
        )
    assert by_angle[0.0]["chief_ray_height"] == 0.0 and by_angle[0.0]["distortion"] == 0.0
    # Field curvature at the primary wavelength: analysis.field_curvature's values (checked
    # against optiland in tests/test_aberrations.py), in the JSON and in the text.
    import jaxlens

    lens = jaxlens.load(path)
    fc = jaxlens.analysis.field_curvature(lens, lens.fields, lens.primary_wavelength)
    assert data["units"]["focus"] == "mm"
    np.testing.assert_allclose([f["focus_tangential"] for f in data["fields"]],
                               np.asarray(fc.tangential[0]), rtol=0, atol=1e-12)
    np.testing.assert_allclose([f["focus_sagittal"] for f in data["fields"]],
                               np.asarray(fc.sagittal[0]), rtol=0, atol=1e-12)
    code, text, _ = _run(capsys, path)
    rows = text.split("FIELD CURVATURE")[1].splitlines()[2:2 + len(data["fields"])]
    for row, f in zip(rows, data["fields"], strict=True):
        tan, sag, astig = map(float, row.split()[2:5])
        assert tan == pytest.approx(f["focus_tangential"], abs=1e-6)
        assert astig == pytest.approx(f["focus_tangential"] - f["focus_sagittal"], abs=2e-6)


def test_report_text_and_options(cooke, capsys):
    path, ref = cooke
    code, out, _ = _run(capsys, path)
    assert code == 0
    for head in (
        "SYSTEM DATA",
        "SURFACE DATA",
        "FIELDS",
        "Effective focal length",
        "Back focal length",
        "Total track",
        "Entrance pupil diameter",
    ):
        assert head in out
    assert f"{ref['paraxial']['EFL']:.6f}" in out
    rows = [ln.split() for ln in out.splitlines() if ln.strip().startswith(("OBJ", "STO", "IMA"))]
    assert [r[0] for r in rows] == ["OBJ", "STO", "IMA"]
    # Same shapes as the lens's own fields and wavelengths: no recompilation.
    code, out, _ = _run(
        capsys, path, "--json", "--fields", 0, 7, 10, "--wavelengths", 486.1327, 0.5875618, 656.2725
    )
    assert code == 0
    data = json.loads(out)
    assert [f["angle"] for f in data["fields"]] == [0.0, 7.0, 10.0]
    assert data["wavelengths"] == [0.4861327, 0.5875618, 0.6562725]
    assert data["primary_wavelength"] == 0.5875618
    assert 0 < data["fields"][1]["chief_ray_height"] < data["fields"][2]["chief_ray_height"]


def test_report_errors_are_messages(tmp_path, capsys):
    bad = tmp_path / "bad.zmx"
    bad.write_text("UNIT MM\nENPD 10\nSURF 0\nSURF 1\n  CURV 0.1\n  DISZ 2\n  GLAS N-BK8\nSURF 2\n")
    code, out, err = _run(capsys, bad)
    assert code == 2 and out == ""
    assert f"{bad}:7" in err and "N-BK7" in err
    # With the line's nd and Vd, --unknown-glass model opens it with a model glass.
    bad.write_text(bad.read_text().replace("GLAS N-BK8", "GLAS N-BK8 0 0 1.52 60")
                   .replace("SURF 2\n", "SURF 2\n  DISZ 9\nSURF 3\n"))
    code, out, err = _run(capsys, bad, "--json", "--unknown-glass", "model")
    assert code == 0 and json.loads(out)["efl"] == pytest.approx(19.1623405, rel=1e-7)
    # The loader's warning is one line on stderr, not a Python warning with its source line.
    assert err.startswith("jaxlens report: warning: ") and "load_zmx(" not in err
    assert "model glass with the line's nd 1.52, Vd 60" in err


DATA = __import__("pathlib").Path(__file__).parent / "data" / "zmx"


def test_report_lenient_reads_what_strict_refuses(capsys):
    """A file whose FTYP announces more fields than its YFLN gives: refused by default (with
    the way out named), read under --lenient with the loader's warnings on stderr, and then
    the same numbers as jaxlens.load's default (lenient) reading."""
    import jaxlens
    from jaxlens.analysis.report import report_data

    path = DATA / "optiland_lens_floa.zmx"
    code, out, err = _run(capsys, path)
    assert code == 2 and out == "" and "FTYP announces" in err and "--lenient reads the file" in err
    code, out, err = _run(capsys, path, "--json", "--lenient")
    assert code == 0 and "jaxlens report: warning: " in err and "FTYP announces" in err
    with pytest.warns(UserWarning):
        want = report_data(jaxlens.load(path))
    got = json.loads(out)
    assert got["efl"] == want["efl"] and got["fields"] == json.loads(json.dumps(want["fields"]))


@pytest.mark.slow  # 31 s at the tests' -O0 (aimed, real_marginal: 40 min before aimed_jit)
def test_report_of_x_y_fields_agrees_with_the_analysis_functions(capsys):
    """A tilted, decentered system with (θx, θy) fields: each field's RMS spots, chief-ray
    landing point and radial distortion are those of rms_spot, chief_ray and distortion."""
    import jaxlens
    from jaxlens.imaging.sampling import pupil_grid

    path = DATA / "rayoptics_HoO-V2C18Ex66.zmx"
    code, out, err = _run(capsys, path, "--json")
    assert code == 0, err
    data = json.loads(out)
    with warnings.catch_warnings():  # it warned of its vignetting factors, now read
        warnings.simplefilter("error")
        lens = jaxlens.load(path)
    fields = np.asarray(lens.fields)
    assert fields.shape == (5, 2) and np.any(fields[:, 0] != 0) and np.any(fields[:, 1] != 0)
    assert [f["angle"] for f in data["fields"]] == fields.tolist()
    spots = jaxlens.analysis.rms_spot(lens, pupil=pupil_grid(21))
    dist = jaxlens.analysis.distortion(lens)
    for i, f in enumerate(data["fields"]):
        np.testing.assert_allclose(f["rms_spot_mm"], np.asarray(spots.per_wavelength[i]),
                                   rtol=1e-9)
        np.testing.assert_allclose(f["chief_ray_xy"], np.asarray(spots.chief[i]), atol=1e-9)
        assert f["chief_ray_height"] == pytest.approx(float(dist.chief_height[i]), abs=1e-9)
        t = np.tan(np.deg2rad(fields[i]))  # the height is along the field's direction
        u = t / np.hypot(*t) if t.any() else np.array([0.0, 1.0])
        assert f["chief_ray_height"] == pytest.approx(float(np.dot(f["chief_ray_xy"], u)),
                                                      abs=1e-12)
        assert f["distortion"] == pytest.approx(float(dist.percent_ftan[i]), abs=1e-9)
    # The ±9° x fields land at ±x, mirror images of each other.
    x9, xm9 = data["fields"][3]["chief_ray_xy"], data["fields"][4]["chief_ray_xy"]
    assert x9[0] > 10 and x9[0] == pytest.approx(-xm9[0], rel=1e-9)
    assert data["max_field"] == pytest.approx(9.0, rel=1e-12)
    # Field curvature of (θx, θy) fields: tangential plane along each field's azimuth.
    fc = jaxlens.analysis.field_curvature(lens, lens.fields, lens.primary_wavelength)
    np.testing.assert_allclose([f["focus_tangential"] for f in data["fields"]],
                               np.asarray(fc.tangential[0]), rtol=1e-12)
    np.testing.assert_allclose([f["focus_sagittal"] for f in data["fields"]],
                               np.asarray(fc.sagittal[0]), rtol=1e-12)
    code, out, _ = _run(capsys, path)
    assert code == 0 and "Angle x, y" in out and "Chief x, y" in out
    assert "FIELD CURVATURE" in out and "along each field's direction" in out


def test_cli_subprocess_smoke(tmp_path):
    missing = tmp_path / "missing.zmx"
    run = subprocess.run(
        [sys.executable, "-m", "jaxlens", "report", str(missing), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    assert "missing.zmx" in run.stderr and "Traceback" not in run.stderr
    run = subprocess.run(
        [sys.executable, "-m", "jaxlens", "report", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and "--wavelengths" in run.stdout


def test_weighted_rms_is_the_hand_computed_radius():
    from jaxlens.analysis.spots import weighted_centroid, weighted_rms

    p = jnp.asarray([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [5.0, 5.0]])
    w = jnp.asarray([1.0, 1.0, 1.0, 0.0])  # the last point is an invalid ray
    cen = np.asarray([2 / 3, 2 / 3])
    np.testing.assert_allclose(weighted_centroid(p, w), cen, rtol=1e-12)
    want = np.sqrt(np.mean(np.sum((np.asarray(p[:3]) - cen) ** 2, -1)))
    np.testing.assert_allclose(weighted_rms(p, w), want, rtol=1e-12)
    np.testing.assert_allclose(weighted_rms(p, w, jnp.zeros(2)), np.sqrt(8 / 3), rtol=1e-12)
    assert np.isnan(weighted_rms(p, jnp.zeros(4)))  # no valid ray: NaN, never 0


def test_report_notes_that_paraxial_data_ignore_decenters_and_tilts():
    import jaxlens
    from jaxlens.analysis.report import report_data

    glass = jaxlens.ModelGlass(1.5168, 64.17)

    def lens(decenter):
        return jaxlens.Lens(
            surfaces=(jaxlens.Sphere(0.02), jaxlens.CoordinateBreak(decenter_y=decenter),
                      jaxlens.Sphere(-0.02)),
            thickness=jnp.array([2.5, 2.5, 45.0]), materials=(glass, glass, jaxlens.Air()),
            epd=4.0, fields=(0.0, 1.0))

    assert report_data(lens(0.0))["notes"] == []
    notes = report_data(lens(0.1))["notes"]
    assert len(notes) == 1 and "surface(s) 2" in notes[0] and "ignore those decenters" in notes[0]


def test_report_notes_what_a_tilted_plane_and_a_grating_do_to_the_paraxial_data():
    """A tilted plane deviates the beam and a grating's lines bend every ray: the paraxial
    trace sees neither, and the report says so (only where they do something)."""
    import jaxlens
    from jaxlens.analysis.report import report_data
    from jaxlens.optics.diffractive import Grating
    from jaxlens.optics.surfaces import TiltedPlane

    glass = jaxlens.ModelGlass(1.5168, 64.17)

    def lens(last):
        return jaxlens.Lens(
            surfaces=(jaxlens.Sphere(0.02), jaxlens.Sphere(-0.02), jaxlens.Sphere(0.0), last),
            thickness=jnp.array([2.5, 2.0, 2.0, 45.0]),
            materials=(glass, jaxlens.Air(), glass, jaxlens.Air()), epd=4.0, fields=(0.0, 1.0))

    assert report_data(lens(TiltedPlane()))["notes"] == []
    assert report_data(lens(Grating(lines_per_um=0.1, order=0.0)))["notes"] == []
    notes = report_data(lens(TiltedPlane(tan_y=0.05)))["notes"]
    assert len(notes) == 1 and "surface(s) 4" in notes[0] and "prism" in notes[0]
    notes = report_data(lens(Grating(lines_per_um=0.1)))["notes"]
    assert len(notes) == 1 and "surface(s) 4" in notes[0] and "order-0" in notes[0]


def test_report_prescription_names_each_surface_kind(capsys):
    """Coordinate breaks, toroids and mirrors are listed as such, with their parameters (they
    were all listed as STANDARD surfaces of their media)."""
    code, out, _ = _run(capsys, DATA / "rayoptics_HoO-V2C18Ex46.zmx")
    assert code == 0
    rows = [ln.split() for ln in out.split("SURFACE DATA")[1].split("FIELDS")[0].splitlines()[2:]
            if ln.strip()]
    kinds = {r[0]: r[1] for r in rows}
    assert kinds["2"] == "COORDBRK" and rows[2][-1] == "tx=-3.5"
    assert kinds["7"] == "TOROIDAL" and "Rx=1035" in rows[7] and "MIRROR" in rows[7]
    assert kinds["STO"] == "STANDARD" and "MIRROR" in rows[3]
    assert kinds["10"] == "COORDBRK" and rows[10][-1] == "dy=24.07"


@pytest.mark.slow  # 27 s (CI time): the nine real figures; CI draws the --plot set with
# stand-in figures (the test below) and checks the refusals (test_report_plot_refusals)
def test_report_plot_writes_the_figures_and_keeps_existing_ones(cooke, tmp_path, capsys):
    """--plot DIR writes the layout, spot diagrams and MTF; a second run keeps them unless
    --overwrite, and bad --plot/--overwrite options are refused before any work."""
    path, _ = cooke
    out = tmp_path / "figs"
    code, _, err = _run(capsys, path, "--plot", out)
    assert code == 0, err
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"cooke_triplet_{k}.png" for k in sorted(
        ("ee", "fans", "field", "layout", "mtf", "opd", "seidel", "spots", "wavefront"))]
    assert all((out / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in names)
    _check_plot_refusals(capsys, path, out, out / names[0], tmp_path)


def _check_plot_refusals(capsys, path, out, kept, tmp_path):
    """The --plot/--overwrite refusals (exit 2): figures in ``out`` (``kept`` among them)
    are kept without --overwrite, and bad options are named."""
    stamp = kept.stat().st_mtime_ns
    code, _, err = _run(capsys, path, "--plot", out)
    assert code == 2 and "cooke_triplet_layout.png exists; give --overwrite" in err
    assert kept.stat().st_mtime_ns == stamp
    code, _, err = _run(capsys, path, "--overwrite")
    assert code == 2 and "it needs --plot DIR" in err
    (tmp_path / "file").write_text("")
    code, _, err = _run(capsys, path, "--plot", tmp_path / "file")
    assert code == 2 and "is a file, not a folder" in err
    code, printed, err = _run(capsys, path, "--plot", "")  # was read as no --plot at all
    assert code == 2 and printed == "" and "--plot needs a folder name" in err


def test_report_plot_refusals_come_before_any_work(tmp_path, capsys):
    """The --plot/--overwrite refusals of the test above, without drawing: an existing figure
    (made here by hand) is kept without --overwrite, and bad options exit 2 before the lens
    file is read (it does not exist)."""
    lens = tmp_path / "cooke_triplet.json"  # never read: every case is refused first
    out = tmp_path / "figs"
    out.mkdir()
    (out / "cooke_triplet_layout.png").write_bytes(b"x")
    _check_plot_refusals(capsys, lens, out, out / "cooke_triplet_layout.png", tmp_path)


def test_report_plot_skips_a_figure_its_analysis_refuses(cooke, tmp_path, capsys,
                                                         monkeypatch):
    """A lens the Seidel (or wavefront) analysis refuses gets the other figures and a message
    naming the one not drawn; any other figure's error still stops with exit status 2."""
    from jaxlens import plot

    def small(lens, *a, **k):
        return plot.plot_image(np.zeros((4, 4, 3)))

    def refuse(lens, *a, **k):
        raise ValueError("seidel: surface 1 (CoordinateBreak): a coordinate break …")

    for name in ("plot_layout", "plot_spots", "plot_ray_fans", "plot_field_curvature",
                 "plot_mtf", "plot_wavefront", "plot_opd_fans", "plot_encircled_energy"):
        monkeypatch.setattr(plot, name, small)
    monkeypatch.setattr(plot, "plot_seidel", refuse)
    path, _ = cooke
    code, _, err = _run(capsys, path, "--plot", tmp_path / "a")
    assert code == 0, err
    assert "cooke_triplet_seidel.png not drawn: seidel: surface 1 (CoordinateBreak)" in err
    assert len(list((tmp_path / "a").iterdir())) == 8
    monkeypatch.setattr(plot, "plot_mtf", refuse)  # not an analysis figure: an error
    code, _, err = _run(capsys, path, "--plot", tmp_path / "b")
    assert code == 2 and "--plot: seidel: surface 1" in err


def test_report_is_printed_before_a_figure_that_fails(cooke, tmp_path, capsys, monkeypatch):
    """A figure that cannot be made exits 2 with its message, after the report was printed."""
    from jaxlens.analysis import report

    def fail(lens, paths):
        raise ValueError("psf: more than 0.05 of the PSF energy falls outside the kernel")

    monkeypatch.setattr(report, "_write_figures", fail)
    path, _ = cooke
    code, out, err = _run(capsys, path, "--plot", tmp_path / "f")
    assert code == 2 and "SYSTEM DATA" in out
    assert err.strip() == ("jaxlens report: error: --plot: psf: more than 0.05 of the PSF "
                           "energy falls outside the kernel")


def test_report_carries_the_seidel_sums_or_says_why_not():
    import jaxlens
    from jaxlens.analysis import seidel
    from jaxlens.analysis.report import format_report, report_data

    lens = jaxlens.zoo.cooke_triplet()
    data = report_data(lens)
    want = np.asarray(seidel(lens).sums)
    got = np.array(list(data["seidel"]["sums"].values()))
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert data["seidel"]["field"] == pytest.approx(float(np.max(np.abs(lens.fields))))
    assert "SEIDEL SUMS (third order" in format_report(data, lens)

    glass = jaxlens.ModelGlass(1.5168, 64.17)
    tilted = jaxlens.Lens(
        surfaces=(jaxlens.Sphere(0.02), jaxlens.CoordinateBreak(tilt_x=1.0),
                  jaxlens.Sphere(-0.02)),
        thickness=jnp.array([2.5, 2.5, 45.0]), materials=(glass, glass, jaxlens.Air()),
        epd=4.0, fields=(0.0, 1.0))
    refused = report_data(tilted)["seidel"]
    assert set(refused) == {"refused"} and "coordinate break" in refused["refused"]
    assert "SEIDEL SUMS: not computed" in format_report(report_data(tilted))


def test_report_wavefront_is_the_analysis_and_gives_strehl_only_where_marechal_holds(capsys):
    import equinox as eqx

    import jaxlens
    from jaxlens.analysis import wavefront
    from jaxlens.analysis.report import report_data
    from jaxlens.analysis.wavefront_error import MARECHAL_MAX_RMS

    # The triplet stopped down to EPD 4 has 0.08 wave RMS (tilt removed), at EPD 6 0.15–0.18.
    for epd, marechal_holds in ((4.0, True), (6.0, False)):
        lens = eqx.tree_at(lambda L: (L.epd, L.fields), jaxlens.zoo.cooke_triplet(),
                           (jnp.asarray(epd), jnp.array([0.0, 20.0])))
        data = report_data(lens, wavefront=True)
        for entry, angle in zip(data["fields"], (0.0, 20.0), strict=True):
            w = wavefront(lens, angle)
            got = entry["wavefront"]
            np.testing.assert_allclose([got["rms"], got["pv"], got["rms_tilt_removed"]],
                                       [float(w.rms), float(w.pv), float(w.rms_tilt_removed)],
                                       rtol=1e-12)
            assert (float(w.rms_tilt_removed) <= MARECHAL_MAX_RMS) == marechal_holds
            if marechal_holds:
                assert got["strehl"] == pytest.approx(float(w.strehl), rel=1e-12)
            else:
                assert got["strehl"] is None
    assert "wavefront" not in report_data(lens)["fields"][0]  # off by default

    code, out, _ = _run(capsys, DATA / "rayoptics_HoO-V2C18Ex46.zmx", "--wavefront")
    assert code == 0 and "WAVEFRONT ERROR" in out and "coordinate breaks" in out
