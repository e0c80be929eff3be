"""Bad input, round 27 (tools/audit27_probe.py): one test per class of gap fixed. Each names
what main did with the input: a folder the run deleted, a silent answer, or a traceback
that named no argument. The checks run where concrete inputs enter.
"""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
import jaxlens.design as D
from jaxlens.experiments.runfolder import FINISHED, UsageError

ROOT = os.path.join(os.path.dirname(__file__), "..")


def _finished_run(path):
    path.mkdir(parents=True, exist_ok=True)
    (path / FINISHED).write_text("")
    return path


def test_edof_refuses_a_checkpoint_photographs_or_record_inside_out(tmp_path):
    """Main: accepted. ``--out`` is swapped into place when the run ends, so a checkpoint
    in it went with the earlier run (``--overwrite``), or made a new ``--out`` look like a
    foreign folder and the run end refused; photographs there were deleted, and a record
    equal to ``--out`` was copied onto itself (SameFileError) after the whole run."""
    from PIL import Image

    from jaxlens.experiments.edof import cli

    out = _finished_run(tmp_path / "out")
    (out / "photos").mkdir()
    Image.fromarray(np.full((32, 32, 3), 100, np.uint8)).save(out / "photos" / "a.png")

    def check(*argv):
        return cli.check_args(cli.build_parser().parse_args(["--smoke", *argv]))

    for opt, path, extra in (("--checkpoint", out / "ck", ()), ("--test-dir", out / "photos", ()),
                             ("--train-dir", out / "photos", ("--train-source", "mixed"))):
        with pytest.raises(UsageError, match=rf"edof: {opt} .* lies in --out .*outside --out"):
            check("--out", str(out), "--overwrite", opt, str(path), *extra)
    new = tmp_path / "new"
    with pytest.raises(UsageError, match="--checkpoint .* lies in --out"):
        check("--out", str(new), "--checkpoint", str(new / "ck"))
    with pytest.raises(UsageError, match="--record .* lies in --out"):
        check("--out", str(new), "--record", str(new))
    check("--out", str(new), "--checkpoint", str(tmp_path / "ck"))  # beside --out: fine


def test_merge_and_design_and_tolerance_refuse_to_write_over_their_inputs(tmp_path, monkeypatch):
    """Main: ``merge out/a out/b --out out --overwrite`` read the runs (or failed on them)
    and would delete them with ``out``; ``edof.design --out R/base_lens.json --record-dir R``
    saved the lens and then wrote the record over it; the tolerance CLI given
    ``D/tolerance.json --out D --overwrite`` analysed the design and wrote its report over
    it. Each is refused before any work."""
    from jaxlens.experiments import tolerance
    from jaxlens.experiments.edof import design, merge

    out = _finished_run(tmp_path / "m")
    runs = [str(_finished_run(out / n)) for n in ("a", "b")]
    with pytest.raises(UsageError, match=r"edof\.merge: run .*a lies in --out"):
        merge.run([*runs, "--out", str(out), "--overwrite"])

    def started(*a, **k):
        raise AssertionError("the work started before the options were refused")

    monkeypatch.setattr(design, "design_classical", started)
    rec = tmp_path / "rec"
    rec.mkdir()
    (rec / "base_lens.json").write_text("{}")
    with pytest.raises(SystemExit) as e:
        design.main(["--smoke", "--quiet", "--overwrite", "--out", str(rec / "base_lens.json"),
                     "--record-dir", str(rec)])
    assert e.value.code == 2

    monkeypatch.setattr(tolerance, "analyse_design", started)
    (tmp_path / "t").mkdir()
    lens = jl.load(os.path.join(ROOT, "experiments", "classical", "designs", "seed_0.zmx"))
    design_file = str(tmp_path / "t" / "tolerance.json")
    jl.save(lens, design_file)
    assert tolerance.main([design_file, "--out", str(tmp_path / "t"), "--overwrite"]) == 2


def test_object_depth_refuses_a_depth_behind_the_stop():
    """Main: -200 mm gave an object distance of -200 mm (a virtual object behind the
    stop), 0 and NaN passed, and a stop behind surface 1 was added instead of subtracted;
    traced depths stay unchecked."""
    from jaxlens.experiments.edof import lenses as L

    lens = L.classical_lens(binning=8)
    for bad in (-200.0, 0.0, np.nan, jnp.array([200.0, -5.0])):
        with pytest.raises(ValueError, match=r"object_depth: depth must be .* \(0, inf\] mm"):
            L.object_depth(lens, bad)
    with pytest.raises(TypeError, match="object_depth: depth"):
        L.object_depth(lens, "200")
    assert float(L.object_depth(lens, np.inf)) == np.inf
    # Main added stop_z: 100 mm in front of the Cooke triplet's stop (10.27 mm behind its
    # surface 1) came out 110.27 mm from surface 1, not 89.73 mm.
    cooke = jl.zoo.cooke_triplet()
    stop_z = float(cooke.vertex_z()[cooke.stop])
    assert stop_z == pytest.approx(10.26648, abs=1e-4)
    assert float(L.object_depth(cooke, 100.0)) == pytest.approx(100.0 - stop_z)
    assert float(jax.jit(lambda d: L.object_depth(lens, d))(-1.0)) == pytest.approx(-1.0)


def test_get_material_says_nd_and_vd_look_swapped_and_lists_the_swapped_glasses():
    """Main: nd 64.17, Vd 1.5168 listed no glass at all and did not say why."""
    with pytest.raises(ValueError, match=r"nd 64\.17 and Vd 1\.5168 look swapped.*N-BK7"):
        jl.get_material("X-UNKNOWN", nd=64.17, vd=1.5168)


def test_reweighting_mask_refuses_area_shares_that_give_no_mean():
    """Main: all-zero or NaN shares gave all weights 1, a negative share dropped fields."""
    rms = jnp.array([1.0, 1.0, 2.0])
    for bad, msg in ((jnp.zeros(3), "share > 0"), (jnp.array([1.0, np.nan, 1.0]), "finite"),
                     (jnp.array([1.0, -1.0, 1.0]), r"\[0, inf\)")):
        with pytest.raises(ValueError, match=f"reweighting_mask: area .*{msg}"):
            D.reweighting_mask(rms, bad)
    assert np.allclose(D.reweighting_mask(rms, jnp.array([1.0, 2.0, 1.0])), [0.8, 0.8, 1.6])


def test_material_models_refuse_degenerate_hulls_names_and_repeated_wavelengths():
    """Main: corners on one line built, then ``logits`` raised LinAlgError (singular
    matrix); 2 names for 3 corners or a str passed; a repeated wavelength was refused only
    when the tables were made."""
    with pytest.raises(ValueError, match="HullMaterials: corners must span an area"):
        D.HullMaterials([[1.5, 60.0], [1.6, 50.0], [1.7, 40.0]])
    tri = [[1.5, 60.0], [1.7, 30.0], [1.7, 55.0]]
    for names in (("a", "b"), "abc"):
        with pytest.raises(ValueError, match="HullMaterials: names must be .* 3 str"):
            D.HullMaterials(tri, names=names)
    assert D.HullMaterials(tri, names=("a", "b", "c")).logits(1.65, 50.0).shape == (3,)
    with pytest.raises(ValueError, match="TableMaterials: wavelengths must be distinct"):
        D.TableMaterials([0.5876, 0.5876, 0.6563])


def test_glass_map_points_and_the_efl_weight_are_checked():
    """Main: ``HullMaterials.logits(nan, 50)`` failed as "cannot unpack non-iterable
    NoneType", (Vd, nd) swapped gave a boundary point; a ``CatalogRegion`` with a NaN point
    or one name for two points was built; ``Objective(efl_weight=-1)`` rewarded missing
    the EFL target."""
    hull = D.HullMaterials([[1.5, 60.0], [1.7, 30.0], [1.7, 55.0]])
    for nd, vd in ((np.nan, 50.0), (50.0, 1.6)):
        with pytest.raises(ValueError, match="HullMaterials.logits: nd must be"):
            hull.logits(nd, vd)
    with pytest.raises(ValueError, match="CatalogRegion: vd"):
        D.CatalogRegion(("SCHOTT",), ("A", "B"), np.array([[1.5, np.nan], [1.6, 40.0]]))
    with pytest.raises(ValueError, match=r"CatalogRegion: .*points \[1, 2\]"):
        D.CatalogRegion(("SCHOTT",), ("A",), np.array([[1.5, 60.0], [1.6, 40.0]]))
    assert len(D.CatalogRegion.of(("PLASTICS",)).names) >= 3
    with pytest.raises(ValueError, match=r"Objective: efl_weight must be .* \[0, inf\)"):
        D.Objective(None, None, jnp.zeros(2), efl=5.0, efl_weight=-1.0)


def test_glass_info_of_air_says_it_is_air():
    """Main: "Unknown material 'AIR'. Closest catalog matches: GASIR2, …" although
    ``get_material("AIR")`` gives Air."""
    for name in ("AIR", "", "air"):
        with pytest.raises(ValueError, match="glass_info: .* is air"):
            jl.glass_info(name)
