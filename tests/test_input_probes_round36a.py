"""Bad input, round 36a (tools/audit36a_probe.py): constructors given batched values,
formula materials of index below 1, classical options that drop another, and messages
without the range or the argument. One test per gap
fixed; each names what main did with the input."""

import dataclasses
import pathlib

import numpy as np
import pytest

import jaxlens as jl

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


def test_lens_refuses_batched_surface_numbers_and_a_2d_thickness(cooke):
    """Main: surfaces take a batch axis, and a Lens of them was built; ``trace`` then failed
    with "le got incompatible shapes" from inside the tracer (semi_diameter [5, 6]), and
    ``efl`` of a [2, 6] thickness gave 6 numbers."""
    s = list(cooke.surfaces)
    sd = s[:3] + [jl.Standard(c=float(s[3].c), semi_diameter=[5.0, 6.0])] + s[4:]
    with pytest.raises(
        ValueError,
        match=r"surfaces\[3\] \(Standard\): semi_diameter must be "
        r"one number .*shape \(2,\)",
    ):
        dataclasses.replace(cooke, surfaces=tuple(sd))
    c2 = s[:3] + [jl.Standard(c=np.full(2, float(s[3].c)), k=0.0)] + s[4:]
    with pytest.raises(ValueError, match=r"surfaces\[3\] \(Standard\): c must be one number"):
        dataclasses.replace(cooke, surfaces=tuple(c2))
    with pytest.raises(ValueError, match=r"thickness must be a 1-D array .*\(2, 6\)"):
        dataclasses.replace(cooke, thickness=np.stack([cooke.thickness] * 2))
    # Term arrays stay 1-D, and a surface alone may still hold a batch (the tracer's stacks).
    asph = s[:3] + [jl.EvenAsphere(c=float(s[3].c), k=0.0, coeffs=[0.0, 1e-6])] + s[4:]
    assert dataclasses.replace(cooke, surfaces=tuple(asph)).num_surfaces == 6
    assert jl.Standard(c=0.01, semi_diameter=[5.0, 6.0]).semi_diameter.shape == (2,)


def test_paraxial_seidel_and_collimated_refuse_a_material_of_index_below_one(cooke):
    """Main: Schott coefficients giving n = 0.71 gave efl -78 mm, bfl -133 mm, Seidel sums
    and rays that ``trace`` took as valid; n² < 0 gave NaN (``rms_spot`` refused both)."""
    low = jl.Schott(coeffs=(0.5, 0, 0, 0, 0, 0))
    lens = dataclasses.replace(
        cooke, materials=(low, *cooke.materials[1:]), wavelengths=(0.55,), primary=0
    )
    for name, fn in (
        ("efl", lambda: jl.efl(lens)),
        ("bfl", lambda: jl.bfl(lens)),
        ("paraxial_data", lambda: jl.paraxial_data(lens)),
        ("seidel", lambda: jl.analysis.seidel(lens)),
        ("collimated", lambda: jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(3))),
    ):
        with pytest.raises(
            ValueError,
            match=rf"^{name}: Schott after surface 1: refractive "
            rf"index 0\.707107 at .*0\.55 µm",
        ):
            fn()
    neg = dataclasses.replace(
        lens, materials=(jl.Schott(coeffs=(-0.5, 0, 0, 0, 0, 0)), *cooke.materials[1:])
    )
    with pytest.raises(ValueError, match=r"efl: Schott after surface 1: refractive index nan"):
        jl.efl(neg, 0.55)


class Started(Exception):
    """Raised where a command's work would begin: its checks have passed."""


def _started(*a, **k):
    raise Started


@pytest.fixture
def classical(monkeypatch, capsys, tmp_path):
    """``classical.main`` up to its work: (exit code, last stderr line), or "started"."""
    from jaxlens.experiments import classical as C

    monkeypatch.setattr(C, "run_design", _started)
    monkeypatch.setattr(C, "run_ablation", _started)

    def go(*argv):
        try:
            code = C.main(["--out", str(tmp_path / "run"), *argv])
        except Started:
            return "started"
        return code, capsys.readouterr().err.strip().splitlines()[-1]

    return go


@pytest.mark.parametrize(
    "extra, why",
    [
        (["--recipe", "strong", "--polish", "none"], "--polish none"),
        (["--recipe", "paper", "--polish-steps", "100"], "--polish-steps"),
        (["--recipe", "paper", "--loss", "image"], "--loss image"),
        (["--recipe", "paper", "--smoke"], "--smoke"),
    ],
)
def test_classical_refuses_a_recipe_it_would_ignore(classical, extra, why):
    """Main: --recipe (the polish's step count) was dropped without a word."""
    code, err = classical(*extra)
    assert code == 2 and f"--recipe would be ignored with {why}" in err, err
    assert classical("--recipe", "paper") == "started"


def test_messages_name_the_range_and_the_argument(cooke, classical):
    """Main: "primary index 5 outside the wavelengths" (no range), "stop index 9 outside
    0..5", os.fspath's TypeError naming nothing, a seed overflow naming no option, and
    "Unknown material 'OKP5'" naming neither --materials nor the entry."""
    with pytest.raises(
        ValueError,
        match=r"Lens: primary must be an index into the 3 "
        r"wavelengths, in \[0, 2\] \(0-based\), got 5",
    ):
        dataclasses.replace(cooke, primary=5)
    with pytest.raises(
        ValueError,
        match=r"Lens: stop must be a surface index in \[0, 5\] "
        r"\(0-based\), got 9",
    ):
        dataclasses.replace(cooke, stop=9)
    with pytest.raises(TypeError, match=r"load_agf: path must be an \.agf file name .*int 5"):
        jl.load_agf(5)
    with pytest.raises(TypeError, match=r"save: path must be a file name .*int 5"):
        jl.save(cooke, 5)
    code, err = classical("--first-seed", str(2**40))
    assert code == 2 and "--first-seed and --seeds" in err and "4294967295" in err, err
    code, err = classical("--seed-list", "4294967296")
    assert code == 2 and "(--seed-list, largest 4294967296" in err, err
    code, err = classical("--elements", "4", "--materials", "E48R,OKP5,E48R,OKP4")
    assert code == 2 and "--materials entry 2 'OKP5': Unknown material" in err, err
