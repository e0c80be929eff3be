"""Bad input, round 29 (tools/audit29_probe.py): one test per class of gap fixed. Each names
what main did with the input: a silent answer, or work that started on a slip of units."""

import pathlib
import warnings

import jax
import jax.numpy as jnp
import pytest

import jaxlens.analysis as A
import jaxlens.design as D
from jaxlens import zoo
from jaxlens.experiments.edof import lenses as L

RADIANS = [0.0, 0.2443, 0.3491]  # np.radians([0, 14, 20])


@pytest.fixture(scope="module")
def cooke():
    return zoo.cooke_triplet()


def test_analyses_warn_about_fields_in_radians(cooke):
    """Main: ``field_curvature``, ``ray_fan`` and ``rms_spot`` traced radians as 0.24° and
    0.35° without a word (``Lens`` already warned). The warning comes before any tracing
    (raised here as an error); traced fields are not checked."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        with pytest.raises(UserWarning, match=r"field_curvature: fields .* look like angles "
                                              r"in radians \(\[ 0\., 14\., 20\.\] deg\)"):
            A.field_curvature(cooke, RADIANS)
        with pytest.raises(UserWarning, match=r"ray_fan: field 0\.3491 look like angles in "
                                              r"radians"):
            A.ray_fan(cooke, 0.3491, n=3)
        with pytest.raises(UserWarning, match=r"rms_spot: fields .* radians"):
            A.rms_spot(cooke, RADIANS)
        # Controls: small fields in degrees, and traced fields (not checked), silent.
        jax.jit(lambda f: A.field_curvature(cooke, f).tangential)(jnp.array(RADIANS))
        A.field_curvature(cooke, [0.0, 0.1, 0.5])


def test_edof_depths_given_in_mm_are_refused():
    """Main: depths (150, 300) "m", meant as mm, gave a cubic plate of 0.00543 mm⁻² for
    (0.15, 0.3) m's 0.00181: three times too strong."""
    lens = L.classical_lens(binning=8)
    with pytest.raises(ValueError, match=r"cubic_strength_guess: depths_m are in metres, and "
                                         r"the nearest, 150 m, .* 150 mm is 0\.15 m"):
        L.cubic_strength_guess(lens, depths_m=[150.0, 300.0])
    with pytest.raises(ValueError, match=r"dioptric_weights: depths_m are in metres"):
        L.dioptric_weights([1e3 * d for d in L.DEPTHS_M])
    assert abs(L.cubic_strength_guess(lens, depths_m=[0.15, 0.3]) - 0.00181) < 1e-5
    L.cubic_strength_guess(lens, depths_m=[0.2, 40.0])  # a far depth is fine


def test_design_spec_refuses_a_back_clearance_in_metres():
    """Main: ``bfl=0.0005`` (0.5 mm written in m) was taken: a lens 0.5 µm off the sensor."""
    with pytest.raises(ValueError, match=r"DesignSpec: bfl must be at least 0\.01 mm .* "
                                         r"0\.0005 m is 0\.5 mm"):
        D.DesignSpec(bfl=0.0005)
    assert D.DesignSpec(bfl=0.05).bfl == 0.05


def test_benchmarks_refuse_a_foreign_readme_and_repeated_names(tmp_path, monkeypatch, capsys):
    """Main: ``--out DIR`` ended by writing the summary over ``DIR/README.md`` whatever it was
    (``--out .`` in the repository: the project's README), and a name given twice to
    ``--only``, ``--counts`` or ``--lenses`` ran or tabulated it twice."""
    import benchmarks.common as BC
    import benchmarks.run as BR

    class Started(Exception):
        pass

    def started():
        raise Started

    monkeypatch.setattr(BC, "machine_info", started)  # the first thing after the checks
    (tmp_path / "README.md").write_text("# My project\n")
    for argv, msg in (([], "its README.md is not a benchmark summary"),
                      (["--only", "pareto", "pareto"], "--only names pareto more than once"),
                      (["--counts", "1000", "1000"], "--counts names 1000 more than once"),
                      (["--lenses", "cooke_triplet", "cooke_triplet"], "--lenses names")):
        out = tmp_path if not argv else tmp_path / "fresh"
        with pytest.raises(SystemExit):
            BR.main(["--smoke", *argv, "--out", str(out)])
        assert msg in capsys.readouterr().err
    assert pathlib.Path(tmp_path / "README.md").read_text() == "# My project\n"
    (tmp_path / "README.md").write_text("# jaxlens benchmark results\n")  # an earlier run's
    with pytest.raises(Started):
        BR.main(["--smoke", "--only", "skipping", "--out", str(tmp_path)])


def test_edof_cli_refuses_read_noise_in_electrons_and_a_kernel_wider_than_the_frame(tmp_path):
    """Main: ``--read-noise 4`` (electrons) trained on noise four times the full signal, and
    ``--kernel 1001`` with a 512-pixel frame was taken."""
    from jaxlens.experiments.edof import cli
    from jaxlens.experiments.runfolder import UsageError

    def check(*argv):
        cli.check_args(cli.build_parser().parse_args(["--out", str(tmp_path / "o"), *argv]))

    with pytest.raises(UsageError, match=r"--read-noise must be at most 0\.5 .*\(was it in "
                                         r"electrons\? 4 e⁻ at --photons 2000 is 0\.002"):
        check("--read-noise", "4")
    with pytest.raises(UsageError, match=r"--kernel must be at most the 512-pixel frame side"):
        check("--kernel", "1001")
    check("--read-noise", "0.01", "--kernel", "255", "--binning", "4")  # a 256-pixel frame


def test_lens_file_warns_of_a_repeated_wavelength_and_refuses_two_wavelength_keys(tmp_path):
    """Main: a repeated wavelength was read without a word (it weighs twice in every
    polychromatic figure; a warning, as Zemax takes it and a .zmx with one must round-trip
    through JSON), and with both ``wavelengths_um`` and ``wavelengths_nm`` the second was
    ignored."""
    import json

    import jaxlens as jl

    src = pathlib.Path(jl.__file__).parent / "data" / "lenses" / "cooke_triplet.json"
    base = json.loads(src.read_text())
    repeated = dict(base, wavelengths_nm=[587.5618, 587.5618, 656.2725])
    both = {k: v for k, v in base.items() if k != "primary_wavelength_nm"}
    both["wavelengths_um"] = [0.5876]
    path = tmp_path / "lens.json"
    path.write_text(json.dumps(repeated))
    with pytest.warns(UserWarning, match=r"a wavelength is given twice \(\[0\.587562, 0\.587562"):
        lens = jl.load(path)
    assert lens.wavelengths.shape == (3,)
    path.write_text(json.dumps(both))
    with pytest.raises(ValueError, match=r"give only one of wavelengths_um and wavelengths_nm"):
        jl.load(path)


def test_a_lens_with_a_repeated_wavelength_round_trips_through_json(tmp_path):
    """A .zmx may list one wavelength twice (Zemax takes it): its JSON must load again."""
    import dataclasses

    import jax.numpy as jnp
    import numpy as np

    import jaxlens as jl
    from jaxlens import zoo

    lens = dataclasses.replace(zoo.cooke_triplet(),
                               wavelengths=jnp.array([0.5875618, 0.5875618, 0.6562725]))
    jl.save(lens, tmp_path / "twice.json")
    with pytest.warns(UserWarning, match="a wavelength is given twice"):
        back = jl.load(tmp_path / "twice.json")
    assert np.asarray(back.wavelengths).tolist() == np.asarray(lens.wavelengths).tolist()
