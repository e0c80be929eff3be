"""Second input audit: a lens file that would not load back is not written, and the report's
--wavelengths refusal names the option, the range and the unit."""

from __future__ import annotations

import pathlib

import equinox as eqx
import jax.numpy as jnp
import pytest

import jaxlens as jl
from jaxlens.__main__ import main

DATA = pathlib.Path(jl.__file__).parent / "data" / "lenses"


@pytest.fixture(scope="module")
def cooke():
    return jl.zoo.cooke_triplet()


@pytest.mark.parametrize("edit, match", [
    (lambda l: eqx.tree_at(lambda x: x.fields, l, jnp.array([0.0, 95.0])),
     r"save: Lens: fields must be finite angles in \(-90, 90\) deg, got 95 deg"),
    (lambda l: eqx.tree_at(lambda x: x.wavelengths, l, jnp.array([0.45, 0.5876])),
     r"save: Lens: wavelengths 0.45 µm is outside 0.48\d*–0.65\d* µm, the data range of SK16"),
    (lambda l: eqx.tree_at(lambda x: x.wavelengths, l, jnp.array([587.6])),
     r"save: Lens: wavelengths 587.6 µm is outside .*587.6 nm is 0.5876 µm"),
])
@pytest.mark.parametrize("ext", [".json", ".zmx"])
def test_save_refuses_a_lens_that_would_not_load_back(tmp_path, cooke, edit, match, ext):
    # eqx.tree_at skips Lens's checks: save wrote these files and load then refused them.
    path = tmp_path / f"lens{ext}"
    with pytest.raises(ValueError, match=match + r".*nothing written"):
        jl.save(edit(cooke), path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["cooke_triplet", "double_gauss"])
@pytest.mark.parametrize("ext", [".json", ".zmx"])
def test_zoo_lenses_still_round_trip(tmp_path, name, ext):
    lens = getattr(jl.zoo, name)()
    back = jl.load(jl.save(lens, tmp_path / f"{name}{ext}")[0])
    assert jnp.allclose(back.thickness, lens.thickness)
    assert jnp.allclose(back.wavelengths, lens.wavelengths)


@pytest.mark.parametrize("value", ["0", "-0.5"])
def test_report_wavelengths_not_positive_names_option_range_and_unit(value, capsys):
    assert main(["report", str(DATA / "cooke_triplet.json"), "--wavelengths", value]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert ("report: --wavelengths must be numbers in (0, inf) µm (values above 100 are read "
            f"as nm), got {float(value):g}") in err


def test_report_api_refuses_non_positive_wavelengths(cooke):
    from jaxlens.analysis.report import report_data

    with pytest.raises(ValueError, match=r"report: --wavelengths must be numbers in \(0, inf\) "
                                         r"µm .*got -0.5"):
        report_data(cooke, wavelengths=[-0.5])
