"""Round-41b bad-input fixes (tools/audit41b_probe.py): one rule for a field no ray reaches,
the surface factories' names, a missing file named by its reader, a JSON lens's
``travel_senses`` values and ``field_rays``' depth. Each test says what main did."""

import json
import pathlib

import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis import encircled, wavefront_error
from jaxlens.imaging import light, sampling
from jaxlens.io import lensfile, zmx
from jaxlens.optics import agf

DATA = pathlib.Path(__file__).resolve().parent / "data"
TELE = DATA / "zmx38a" / "tele_doublet_obna.zmx"


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


@pytest.fixture(scope="module")
def tele():
    return jl.load(TELE)


# A 60° field is beyond the Cooke triplet's coverage (every ray is lost: its front surface
# is 11 mm across, and the chief ray at 60° misses it), a 95 mm height beyond the small
# telecentric doublet's (its object-side clear aperture is a few mm).
DARK = [("cooke", 60.0, "deg"), ("tele", 95.0, "mm")]

ONE_FIELD = {
    "wavefront": lambda lens, f: wavefront_error.wavefront(lens, f, grid=9),
    "encircled_energy": lambda lens, f: encircled.encircled_energy(lens, f, [0.01],
                                                                   pupil=sampling.pupil_polar(4)),
    "radius_for_fraction": lambda lens, f: encircled.radius_for_fraction(
        lens, f, 0.8, pupil=sampling.pupil_polar(4)),
}


@pytest.mark.parametrize("name", sorted(ONE_FIELD))
@pytest.mark.parametrize("which, field, unit", DARK)
def test_one_field_analyses_refuse_a_field_no_ray_reaches(request, name, which, field, unit):
    """Main: NaN (wavefront's rms, the energies, the radius) where psf and mtf refused."""
    lens = request.getfixturevalue(which)
    with pytest.raises(light.NoLightError) as e:
        ONE_FIELD[name](lens, field)
    assert isinstance(e.value, ValueError)
    msg = str(e.value)
    assert msg.startswith(f"{name}: no ray of the beam reaches the image surface at field "
                          f"{field:g} {unit}")
    assert "vignetted or beyond the lens's coverage" in msg


def test_psf_no_light_is_the_same_error(cooke):
    """Main: a plain ValueError (mtf's was NoLightError), which named no field."""
    with pytest.raises(light.NoLightError, match=r"^psf: no ray of the beam reaches the image "
                       r"surface at field 60 deg \(the field is vignetted"):
        jl.imaging.psf.psf(cooke, 60.0, pixel_size=0.01, kernel_size=15)


def test_rms_spot_keeps_the_batch_nan_and_names_the_dark_field(cooke):
    """Main: NaN without a word. The batch API keeps the documented NaN (valid_fraction 0)
    and the lit field's radius; a NoLightWarning names the dark field and its unit."""
    pupil = sampling.pupil_grid(7)
    with pytest.warns(light.NoLightWarning, match=r"rms_spot: no ray reaches the image "
                      r"surface at field\(s\) 60 deg"):
        r = jl.analysis.rms_spot(cooke, np.array([0.0, 60.0]), pupil=pupil)
    assert np.isfinite(float(r.polychromatic[0])) and np.isnan(float(r.polychromatic[1]))
    assert np.all(np.asarray(r.valid_fraction[1]) == 0)


def test_one_field_analyses_still_answer_a_lit_field(cooke):
    """The control: the edge of the field (20°) is lit; no error, finite answers."""
    assert np.isfinite(float(wavefront_error.wavefront(cooke, 20.0, grid=9).rms))
    e = encircled.encircled_energy(cooke, 20.0, [1.0], pupil=sampling.pupil_polar(4))
    assert float(e.energy[0]) == pytest.approx(1.0)


@pytest.mark.parametrize("make, name, words", [
    (lambda: jl.Plane(-1.0), "Plane", r"semi_diameter must be numbers in \(0, inf\] mm"),
    (lambda: jl.Stop(float("nan")), "Stop", r"semi_diameter must be .* got nan mm"),
    (lambda: jl.Sphere(1 / 3, 5.0), "Sphere", r"the surface .* is defined only out to r = .* 3 mm"),
    (lambda: jl.Conic(0.1, float("inf")), "Conic", r"k must be finite numbers, got inf"),
])
def test_surface_factories_name_themselves(make, name, words):
    """Main: every message began "Standard:", the class the factory builds."""
    with pytest.raises(ValueError, match=rf"^{name}: {words}"):
        make()


def test_surface_factory_type_error_names_the_factory():
    with pytest.raises(TypeError, match=r"^Stop: semi_diameter must be a real number"):
        jl.Stop("5")


@pytest.mark.parametrize("read, where", [
    (lambda p: jl.load(p / "nope.json"), "load"),
    (lambda p: jl.load(p / "nope.zmx"), "load"),
    (lambda p: lensfile.load_json(p / "nope.json"), "load_json"),
    (lambda p: zmx.load_zmx(p / "nope.zmx"), "load_zmx"),
    (lambda p: zmx.configurations(p / "nope.zmx"), "configurations"),
    (lambda p: agf.load_agf(p / "nope.agf"), "load_agf"),
])
def test_missing_file_names_the_reader_and_the_path(tmp_path, read, where):
    """Main: Python's bare "[Errno 2] No such file or directory: '…'"."""
    with pytest.raises(FileNotFoundError) as e:
        read(tmp_path)
    msg = str(e.value)
    assert msg.startswith(f"{where}: no such ") and "nope." in msg and "Errno" not in msg
    assert "does not exist" in msg


@pytest.mark.parametrize("senses", [[1, 1, "x"], [1, 0, 1], [1, 2, 1], [True, True, True],
                                    "1,1", [1.0, 1.0, 1.0]])
def test_json_travel_senses_must_be_plus_or_minus_one(tmp_path, senses):
    """Main: "[1, 1, 'x'] disagrees with the frames", which hid what was wrong."""
    d = json.loads((pathlib.Path(jl.__file__).parent / "data" / "lenses" /
                    "cooke_triplet.json").read_text())
    d["travel_senses"] = senses
    p = tmp_path / "lens.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match=r"travel_senses must be a list of \d+ numbers, each "
                                         r"\+1 or -1"):
        jl.load(p)


def test_json_travel_senses_right_values_still_load(tmp_path, cooke):
    """The control: one +1 per medium (object space first) of a lens without mirrors loads;
    a -1 there is refused as disagreeing with the frames."""
    d = json.loads((pathlib.Path(jl.__file__).parent / "data" / "lenses" /
                    "cooke_triplet.json").read_text())
    p = tmp_path / "lens.json"
    d["travel_senses"] = [1] * (len(cooke.surfaces) + 1)
    p.write_text(json.dumps(d))
    assert len(jl.load(p).surfaces) == len(cooke.surfaces)
    d["travel_senses"][-1] = -1
    p.write_text(json.dumps(d))
    with pytest.raises(ValueError, match="disagrees with the frames"):
        jl.load(p)


@pytest.mark.parametrize("depth", [0.0, float("nan"), -np.inf])
def test_field_rays_names_itself_for_a_bad_depth(cooke, depth):
    """Main: refused as "object_point: depth must be …" (a function the user never called)."""
    with pytest.raises(ValueError, match=r"^field_rays: depth must be finite, nonzero"):
        sampling.field_rays(cooke, 0.0, sampling.pupil_polar(2), depth=depth)


def test_design_helpers_refuse_what_is_not_a_spec():
    """Main: ``template_lens({...})`` an AttributeError ('dict' has no 'asphere_terms')."""
    from jaxlens.design import init

    for fn in (init.template_lens, init.gap_kinds, init.gap_bounds, init.normalisation_radii):
        with pytest.raises(TypeError, match=rf"^{fn.__name__}: spec must be a "
                                            r"jaxlens.design.DesignSpec, got dict"):
            fn({"fov": 60.0})


@pytest.mark.parametrize("n", [0, -2, 2.5])
def test_aperture_field_limits_checks_the_element_count(n):
    """Main: 0 a ZeroDivisionError; -2 gave (0.5, -0.24), a negative aperture-field limit."""
    from jaxlens.design.spec import aperture_field_limits

    with pytest.raises(ValueError, match=r"aperture_field_limits: n_elements must be a whole "
                                         r"number in \[1, inf\) lens elements"):
        aperture_field_limits(n)
