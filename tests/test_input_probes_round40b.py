"""Round-40b bad-input fixes (tools/audit40b_probe.py): one missing-folder error for every
writer, the encircled-energy building blocks' own checks, the real stop size of an object no
real marginal ray leaves, ``field_rays``' depth, and ``ImageObjective``'s sensor and scene.
One test per gap; each says what main did with the input."""

import dataclasses
import pathlib

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import plot
from jaxlens.analysis import encircled, report
from jaxlens.imaging import sampling
from jaxlens.io import MissingFolderError, images, lensfile, zmx

DATA = pathlib.Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


WRITERS = {
    "save": lambda lens, p: jl.save(lens, p / "a.json"),
    "save .zmx": lambda lens, p: jl.save(lens, p / "a.zmx"),
    "save_json": lambda lens, p: lensfile.save_json(lens, p / "a.json"),
    "save_zmx": lambda lens, p: zmx.save_zmx(lens, p / "a.zmx"),
    "plot.save": lambda lens, p: plot.save(plot.plot_image(np.zeros((4, 4, 3))), p / "a.png"),
    "write_png": lambda lens, p: images.write_png(p / "a.png", np.zeros((4, 4, 3), np.float32)),
}


@pytest.mark.parametrize("name", sorted(WRITERS))
def test_every_writer_refuses_a_missing_folder_with_one_error(cooke, tmp_path, name):
    """Main: ``save`` raised FileNotFoundError ("the folder … does not exist"), the others
    ValueError ("no such folder …"). Now one class, both a ValueError and a
    FileNotFoundError, with one message naming the caller, the folder and the file."""
    where = name.split(" ")[0].removeprefix("plot.")  # plot.save names itself "save"
    with pytest.raises(MissingFolderError) as e:
        WRITERS[name](cooke, tmp_path / "nope")
    assert isinstance(e.value, ValueError) and isinstance(e.value, FileNotFoundError)
    msg = str(e.value)
    assert msg.startswith(f"{where}: no such folder ") and "nope" in msg
    assert "does not exist" in msg and "creates no folders" in msg
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.fixture(scope="module")
def samples(cooke):
    return encircled.energy_samples(cooke, 0.0)


@pytest.mark.parametrize("radii, cls, match", [
    (-0.01, ValueError, r"radii must be finite numbers in \[0, inf\) mm, got -0\.01 mm"),  # 0
    (float("nan"), ValueError, r"radii must be finite .*got nan"),  # 0
    ([], ValueError, r"radii must hold at least one radius \(mm\)"),  # an empty curve
    ("a", TypeError, r"radii must be a real number .*\(mm\), got str 'a'"),
])
def test_energy_within_checks_its_radii(samples, radii, cls, match):
    with pytest.raises(cls, match="energy_within: " + match):
        encircled.energy_within(samples, radii)


@pytest.mark.parametrize("fraction, main", [(1.5, "NaN"), (-0.2, "a radius"), (80.0, "NaN")])
def test_radius_holding_checks_its_fractions(samples, fraction, main):
    with pytest.raises(ValueError, match=r"radius_holding: fraction must be finite numbers in "
                       r"\(0, 1\) \(fraction of the energy\)"):
        encircled.radius_holding(samples, fraction)


def test_energy_within_values_unchanged(cooke, samples):
    """All the arriving rays lie within 1 mm (1.0), none within 0 (0.0), and the function
    equals ``encircled_energy`` on the same samples."""
    ee = encircled.energy_within(samples, [0.0, 1.0])
    assert np.allclose(np.asarray(ee.energy), [0.0, 1.0])
    r80 = float(encircled.radius_holding(samples, 0.8))
    full = jl.analysis.encircled_energy(cooke, 0.0, [r80])
    assert float(full.energy[0]) == pytest.approx(0.8, abs=0.01)


def test_stop_radius_refuses_a_lost_real_marginal_ray(cooke):
    """A virtual object point 5 mm after the Cooke triplet's surface 1, with the entrance
    pupil at 11.5 mm: the line through it and the pupil's rim crosses the lens at 37° and
    misses surface 4 (checked: the same ray, traced by ``trace_path``, is lost there).
    Main: NaN, and ``field_rays(..., aim="real_marginal")`` returned every ray invalid."""
    from jaxlens.optics.lens import unclipped

    zep = float(jl.paraxial.entrance_pupil_z(cooke))
    rim = np.array([0.0, 0.5 * float(cooke.epd), zep])
    d = (rim - [0.0, 0.0, 5.0]) / np.linalg.norm(rim - [0.0, 0.0, 5.0])
    path = jl.trace_path(unclipped(cooke), jl.Rays(rim[None], d[None], 0.5876),
                         upto=cooke.stop, uniform=True)
    assert list(np.asarray(path.valid[:, 0])) == [True, True, True, False]
    match = (r"stop_radius: the real marginal ray from \(0, 0, 5\) mm .*misses "
             r"surface 4 .*use stop_size='paraxial' \(Lens.aim='real'\)")
    with pytest.raises(ValueError, match=match):
        sampling.stop_radius(cooke, "real", object_z=5.0)
    with pytest.raises(ValueError, match=match):
        sampling.field_rays(cooke, 10.0, sampling.pupil_polar(2), depth=-5.0,
                            aim="real_marginal")
    # A virtual point farther away leaves a real marginal ray: a radius, near the paraxial.
    r = float(sampling.stop_radius(cooke, "real", object_z=50.0))
    assert abs(r - float(sampling.stop_radius(cooke, "paraxial"))) < 0.2


def test_field_rays_takes_one_depth(cooke):
    """Main: a TypeError from jnp.concatenate naming no argument."""
    with pytest.raises(ValueError, match=r"field_rays: depth must be one distance \(mm\), "
                       r"got shape \(2,\)"):
        sampling.field_rays(cooke, 5.0, sampling.pupil_polar(2), depth=np.array([-5.0, 5.0]))


def test_image_objective_checks_its_sensor_and_scene_size():
    """Main: built, then failed at the run's first step (a shape error in the render's
    difference, or a string's missing attribute)."""
    from jaxlens.design import DesignSpec, ImageObjective, RayLoss, parameterization
    from jaxlens.design.losses import Objective

    spec = DesignSpec()
    ray = Objective(parameterization(spec), RayLoss.make(3, 2, [0.5876], spec.sensor_size),
                    jnp.ones((12, 2)))
    with pytest.raises(ValueError, match=r"ImageObjective: scene must have the sensor's "
                       r"resolution \(rows, columns\) \(4, 4\) pixels.*got \(8, 8\)"):
        ImageObjective(ray, jnp.ones((8, 8, 3)), jl.Sensor((4, 4), 0.01))
    for bad in ("abc", None):
        with pytest.raises(TypeError, match=r"ImageObjective: sensor must be a jaxlens.Sensor, "
                           rf"got {type(bad).__name__}"):
            ImageObjective(ray, jnp.ones((8, 8, 3)), bad)
    assert ImageObjective(ray, jnp.ones((8, 6, 3)), jl.Sensor((8, 6), 0.01)).spp == 4


def test_report_refusal_of_a_telecentric_lens_names_what_to_use():
    """The report refused a telecentric lens (round 38a), naming the analyses that take
    object heights; since round 42a it reports it (object heights, distortion against
    m·h), and what still refuses such a lens (``entrance_pupil_z``; ``image_scale`` until
    round 43a, now its magnification) names what to use."""
    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    data = report.report_data(lens)
    assert data["object_space_telecentric"]
    assert [f["height"] for f in data["fields"]] == [0.0, 4.0, 8.0]
    with pytest.raises(ValueError, match=r"entrance_pupil_z: the lens is object-space "
                       r"telecentric .*paraxial.magnification.*rms_spot.*render"):
        jl.optics.paraxial.entrance_pupil_z(lens)
    assert float(jl.imaging.aiming.image_scale(lens)) == float(
        jl.optics.paraxial.magnification(lens))
    spot = jl.analysis.rms_spot(lens, float(np.max(np.abs(np.asarray(lens.fields)))))
    assert np.all(np.isfinite(np.asarray(spot.polychromatic)))


def test_virtual_object_depth_is_documented_where_it_is_taken(cooke):
    """``field_rays`` takes a negative depth as a virtual object (documented now); the
    analyses refuse it as a likely slip of sign."""
    assert "virtual object" in sampling.field_rays.__doc__
    rays = sampling.field_rays(cooke, 5.0, sampling.pupil_polar(2), depth=-50.0)
    # The chief ray (pupil centre) heads for the virtual point 50 mm after surface 1.
    o, d = np.asarray(rays.origin[0]), np.asarray(rays.direction[0])
    t = (50.0 - o[2]) / d[2]
    assert abs(o[1] + t * d[1] - float(sampling.object_point(cooke, 5.0, -50.0)[1])) < 1e-9
    with pytest.raises(ValueError, match=r"rms_spot: depth must be finite numbers in \(0, inf\)"):
        jl.analysis.rms_spot(dataclasses.replace(cooke), 5.0, depth=-50.0)


def test_a_string_is_not_a_number_anywhere_values_are_checked():
    """``checks.values`` read ``np.asarray("4", float)`` as 4.0: a telecentric lens's field
    '4' traced the object height 4 mm (main: a chief ray, without a word)."""
    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    with pytest.raises(ValueError, match=r"chief_ray: field \(object heights of an object-space "
                       r"telecentric lens\) must be finite numbers \(mm\), got '4'"):
        jl.analysis.chief_ray(lens, "4")
    with pytest.raises(ValueError, match=r"stop_radius: object_z must be finite numbers \(mm\), "
                       r"got '50'"):
        sampling.stop_radius(jl.zoo.cooke_triplet(), "real", object_z="50")


def test_a_telecentric_source_refuses_a_virtual_object():
    """``Lens`` refuses a virtual object for a telecentric lens; ``field_rays(depth=-5)``
    launched its rays at z = +5 mm, after surface 1, which they then skipped (main: four
    valid rays)."""
    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    with pytest.raises(ValueError, match=r"telecentric.source: an object-space telecentric lens "
                       r"\(object_na given\) needs a real object before surface 1 \(depth > 0 "
                       r"mm\), got -5 mm"):
        sampling.field_rays(lens, 4.0, sampling.pupil_polar(2), depth=-5.0)
    rays = sampling.field_rays(lens, 4.0, sampling.pupil_polar(2), depth=50.0)
    assert np.allclose(np.asarray(rays.origin)[:, 1:], [[4.0, -50.0]] * 4)  # the object point


def test_a_malformed_row_of_another_configuration_is_refused(tmp_path):
    """Main: ``THIC 2 1 abc`` was read only when configuration 1 was chosen, so
    ``load(config=2)`` opened the file without a word. Now every numeric row is parsed:
    another configuration is refused naming the line, the active one reads with the
    warning of an unreadable table (as before for a malformed table)."""
    text = (DATA / "zmx_config" / "zoom.zmx").read_text().replace("THIC 2 1 20 ", "THIC 2 1 abc ")
    p = tmp_path / "z.zmx"
    p.write_text(text)
    with pytest.raises(ValueError, match=r"z.zmx:\d+: THIC's value must be a number, got 'abc'"):
        jl.load(p, config=2)
    with pytest.warns(UserWarning, match=r"operand table jaxlens cannot read .*THIC's value"):
        jl.load(p, config=1)


def test_a_lens_whose_virtual_object_lies_on_its_entrance_pupil_is_refused_before_tracing(cooke):
    """Main: an EquinoxRuntimeError from inside the compiled trace (rms_spot)."""
    zep = float(jl.paraxial.entrance_pupil_z(cooke))
    lens = dataclasses.replace(cooke, object_distance=-zep)
    with pytest.raises(ValueError, match=r"rms_spot: the lens's object must be in front of "
                       r"surface 1 .*puts it on the entrance pupil's plane"):
        jl.analysis.rms_spot(lens, 0.0)


@pytest.mark.parametrize("name", ["psf", "mtf", "encircled_energy", "wavefront", "ray_fan",
                                  "opd_fan"])
def test_one_field_analyses_check_a_telecentric_lens_field_as_a_height(name):
    """Main: each checked the field as an angle: NaN was refused as "finite angles in (-90,
    90) deg", and a height of 95 mm refused as 95°."""
    from jaxlens.imaging import psf

    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    fn = {"psf": lambda f: psf.psf(lens, f, pixel_size=0.1, kernel_size=31),
          "mtf": lambda f: psf.mtf(lens, f, kernel_size=32),
          "encircled_energy": lambda f: jl.analysis.encircled_energy(lens, f, [0.5]),
          "wavefront": lambda f: jl.analysis.wavefront(lens, f),
          "ray_fan": lambda f: jl.analysis.ray_fan(lens, f),
          "opd_fan": lambda f: jl.analysis.opd_fan(lens, f)}[name]
    with pytest.raises(ValueError, match=rf"{name}: field \(object heights of an object-space "
                       r"telecentric lens\) must be finite numbers \(mm\), got nan mm"):
        fn(float("nan"))
    with pytest.raises(ValueError, match=r"field must be one object height, y or \(x, y\) in "
                       r"mm .*got shape \(3,\)"):
        fn(np.array([1.0, 2.0, 3.0]))


def test_a_telecentric_height_beyond_90_mm_is_traced_not_refused_as_an_angle():
    """95 mm is beyond this doublet's coverage: the PSF says no ray reaches the image (main:
    "field must be finite angles in (-90, 90) deg, got 95 deg")."""
    from jaxlens.imaging import psf

    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    with pytest.raises(ValueError, match=r"psf: no ray of the beam reaches the image surface"):
        psf.psf(lens, 95.0, pixel_size=0.1, kernel_size=31)


def test_a_tolerance_model_of_a_telecentric_lens_takes_its_fields_as_heights():
    """Main: ``ToleranceModel`` checked the fields as angles: a height of 95 mm was refused
    as 95°, and heights of 0.0873 and 0.1745 mm warned about as radians."""
    import warnings

    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = jl.tolerance.ToleranceModel(lens, fields=np.array([0.0, 0.0873, 0.1745]))
    assert np.allclose(np.asarray(model.fields)[:, 1], [0.0, 0.0873, 0.1745])
    model = jl.tolerance.ToleranceModel(lens, fields=np.array([0.0, 95.0]))
    assert np.allclose(np.asarray(model.fields)[:, 1], [0.0, 95.0])
    with pytest.raises(ValueError, match=r"ToleranceModel: fields must be finite \[F\] or \[F, 2\] "
                       r"mm \(object heights of an object-space telecentric lens\)"):
        jl.tolerance.ToleranceModel(lens, fields=np.array([np.nan]))


def test_field_sets_of_a_telecentric_lens_are_checked_as_heights():
    """``semi_diameters_and_fans`` (the layout's fans) and ``vignetting_for_fields`` checked
    the fields as angles: NaN named "angles in (-90, 90) deg" (main), a 95 mm height 95°."""
    from jaxlens.analysis import spots

    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    with pytest.raises(ValueError, match=r"semi_diameters_and_fans: fan_fields \(object heights "
                       r"of an object-space telecentric lens\) must be finite numbers \(mm\)"):
        spots.semi_diameters_and_fans(lens, np.array([0.0, np.nan]), np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"vignetting_for_fields: fields \(object heights"):
        sampling.vignetting_for_fields(dataclasses.replace(lens, vignetting=np.zeros((3, 5))),
                                       np.array([np.inf]))


def test_mtf_directions_of_object_heights():
    """An object height (x, y) = (3, 4) mm lies along (0.6, 0.8): its tangential direction;
    as angles (3°, 4°) it gave (tan 3°, tan 4°)/norm = (0.6, 0.8) to 3e-4 only, and a height
    of 95 mm was refused as 95° (the tolerance model's MTF and ``mtf`` of such a lens)."""
    from jaxlens.imaging import otf

    e_t, e_s = otf.mtf_directions(np.array([3.0, 4.0]), heights=True)
    assert np.allclose(np.asarray(e_t), [0.6, 0.8], atol=1e-15)
    assert np.allclose(np.asarray(e_s), [0.8, -0.6], atol=1e-15)
    e_t, _ = otf.mtf_directions(np.array([0.0, 95.0]), heights=True)
    assert np.allclose(np.asarray(e_t), [0.0, 1.0])
    lens = jl.load(DATA / "zmx38a" / "tele_doublet_obna.zmx")
    model = jl.tolerance.ToleranceModel(lens, fields=np.array([0.0, 95.0]), batch=2)
    out = jl.tolerance.monte_carlo(model, trials=2, threshold_um=500.0, mtf_frequency=10.0)
    # The 95 mm field carries no ray: every trial fails it (main: an angle refused as 95°).
    assert float(out["yield"]) == 0.0 and np.isfinite(float(out["mtf_p50"]))
