"""Bad input, round 12: the Q-type asphere, the grating, element tilt tolerances and the
object depth. Refusals found missing are marked; the rest pin refusals the audit probed and
found right (a clear ValueError or TypeError naming the argument, range and unit)."""

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens.analysis.tolerance import Tolerances
from jaxlens.experiments import tolerance as cli
from jaxlens.optics.qtype import QTypeAsphere


# ------------------------------------------------------------ missing before the fix
@pytest.mark.parametrize("tilt", [90.0, 360.0, 1e6])
def test_tolerances_refuse_a_tilt_of_90_degrees_or_more(tilt):
    """A ±360° tilt is no tilt: the sensitivity table showed it as harmless; 90° turns the
    element sideways. Accepted before (only finite and >= 0 was checked)."""
    with pytest.raises(ValueError, match=r"^Tolerances: tilt must be below 90 degrees \(each "
                                         r"element's tilt about x and about y\)"):
        Tolerances(tilt=tilt)
    assert Tolerances(tilt=89.9).tilt == 89.9


def test_cli_refuses_a_tilt_of_90_degrees_before_any_work(tmp_path, capsys):
    """Refused before the design file is even looked for (a missing file is named later).
    (Round 20: the CLI's --tilt range is [0, 1] deg, FLAG_RANGES; it was below 90.)"""
    rc = cli.main([str(tmp_path / "none.json"), "--out", str(tmp_path / "o"), "--tilt", "90"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "--tilt must be a finite number >= 0 and <= 1 deg (" in err
    assert err.rstrip().endswith("got 90")
    assert "not found" not in err


# ------------------------------------------------------------- probed and found right
@pytest.mark.parametrize(("kw", "message"), [
    ({"norm_radius": 0.0}, r"norm_radius must be finite numbers in \(0, inf\) mm"),
    ({"norm_radius": np.inf}, r"norm_radius must be finite numbers in \(0, inf\) mm"),
    ({"norm_radius": np.nan}, r"norm_radius must be finite numbers in \(0, inf\) mm"),
    ({"coeffs": [np.inf]}, r"coeffs must be finite numbers \(mm\)"),
    ({"coeffs": [[1.0, 2.0]]}, r"coeffs must be a 1-D array"),
    ({"qtype": "BFS"}, r"qtype must be 'bfs' .* or 'con'"),
])
def test_qtype_constructor_refusals(kw, message):
    with pytest.raises(ValueError, match=rf"^QTypeAsphere: {message}"):
        QTypeAsphere(**kw)


@pytest.mark.parametrize(("kw", "error", "message"), [
    ({"lines_per_um": -1.0}, ValueError, r"Grating: lines_per_um must be finite numbers in "
                                         r"\[0, inf\) lines per µm"),
    ({"lines_per_um": np.inf}, ValueError, r"Grating: lines_per_um must be finite"),
    ({"order": 0.5}, ValueError, r"Grating: order must be a whole number"),
    ({"order": np.nan}, ValueError, r"Grating: order must be finite"),
    ({"lines_per_um": "0.3"}, TypeError, r"surface: lines_per_um must be a real number"),
    ({"order": True}, TypeError, r"surface: order must be a real number"),
])
def test_grating_constructor_refusals(kw, error, message):
    with pytest.raises(error, match=rf"^{message}"):
        jl.Grating(**kw)


@pytest.mark.parametrize("bad", [-1.0, np.nan, np.inf, "0.02", True])
def test_tolerances_refuse_bad_decenter_and_tilt(bad):
    for name, unit in (("decenter", "mm"), ("tilt", "degrees")):
        with pytest.raises(ValueError, match=rf"^Tolerances: {name} must be a finite number "
                                             rf">= 0 {unit}"):
            Tolerances(**{name: bad})


@pytest.mark.parametrize("depth", [-1.0, 0.0, np.nan, -np.inf])
def test_lens_depth_refuses_non_positive_depths(depth):
    lens = jl.zoo.cooke_triplet()
    with pytest.raises(ValueError, match=r"^probe: depth must be finite numbers in \(0, inf\) "
                                         r"mm from the object to surface 1"):
        jl.sampling.lens_depth(lens, depth, "probe")
    with pytest.raises(TypeError, match=r"^probe: depth must be a real number"):
        jl.sampling.lens_depth(lens, "500", "probe")
    assert jl.sampling.lens_depth(lens, jnp.inf, "probe") is None
