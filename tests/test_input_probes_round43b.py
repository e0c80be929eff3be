"""Round-43b bad-input fixes (tools/audit43b_probe.py): the command lines' comma lists and
output folders, the input files of ``python -m benchmarks.reevaluate``, the
``ablation_table`` module run as a command, the arguments of the telecentric report and
``stop_clipping``, one rule for integer images (NAFNet refuses them as render does) and the
image metrics' scales. Each test says what main did."""

import os
import subprocess
import sys

import jax.numpy as jnp
import numpy as np
import pytest

import jaxlens as jl
from jaxlens import nets
from jaxlens.analysis import report_telecentric as RT
from jaxlens.analysis import stop_clipping
from jaxlens.experiments import classical
from jaxlens.experiments.edof import cli as edof_cli
from jaxlens.io import images

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COOKE = os.path.join(os.path.dirname(jl.__file__), "data", "lenses", "cooke_triplet.json")
TELE = os.path.join(ROOT, "tests", "data", "tele42a", "tele_triplet_far.zmx")


def test_comma_lists_take_ascii_digits_and_no_repeated_column():
    """Main: ``str.isdigit`` took Arabic-Indic digits, so ``--seed-list ١`` and edof's
    ``--seeds ١`` ran seed 1; ``--columns baseline,baseline`` designed one column twice."""
    parse = classical.build_parser().parse_args
    with pytest.raises(ValueError, match="--seed-list must be comma-separated whole numbers"):
        classical.check_args(parse(["--seed-list", "١"]))
    with pytest.raises(ValueError, match="--columns names a column more than once"):
        classical.check_args(parse(["--ablation", "--columns", "baseline,baseline"]))
    classical.check_args(parse(["--seed-list", "3,1"]))  # control
    with pytest.raises(SystemExit):
        edof_cli.build_parser().parse_args(["--seeds", "١"])
    assert edof_cli.build_parser().parse_args(["--seeds", "0,2"]).seeds == (0, 2)


def test_benchmarks_out_under_a_file_is_refused_before_work(monkeypatch, capsys):
    """Main: ``python -m benchmarks --out FILE/x`` passed the checks and failed as a
    NotADirectoryError traceback when the folder was made."""
    import benchmarks.common as common
    from benchmarks.run import main

    def started():
        raise AssertionError("the run started")
    monkeypatch.setattr(common, "machine_info", started)
    with pytest.raises(SystemExit) as e:
        main(["--smoke", "--out", os.path.join(COOKE, "x")])
    assert e.value.code == 2
    assert "--out" in capsys.readouterr().err


def test_reevaluate_reads_every_design_before_work(monkeypatch, capsys, tmp_path):
    """Main: a broken .zmx in the folder stopped the run midway, after the optiland traces
    of the files before it, with a traceback."""
    import benchmarks.optiland_ref as optiland_ref
    import benchmarks.reevaluate as reevaluate

    def started(*a):
        raise AssertionError("the run started")
    monkeypatch.setattr(optiland_ref, "available", lambda: True)
    monkeypatch.setattr(reevaluate, "reevaluate", started)
    (tmp_path / "a.zmx").write_text("VERS 1\nSURF 0\n  CURV abc\n")
    with pytest.raises(SystemExit) as e:
        reevaluate.main([str(tmp_path)])
    assert e.value.code == 2
    assert "a.zmx" in capsys.readouterr().err


def test_ablation_table_module_is_no_silent_command():
    """Main: ``python -m jaxlens.experiments.ablation_table`` ran, printed nothing and
    exited 0 (no table, no word)."""
    p = subprocess.run([sys.executable, "-m", "jaxlens.experiments.ablation_table"],
                       capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, PYTHONPATH=ROOT))
    assert p.returncode == 2
    assert "classical --ablation" in p.stderr


def test_telecentric_report_and_stop_clipping_check_their_arguments():
    """Main: ``telecentric_report_data`` of a focal lens failed as float(None), took
    ``wavefront="yes"`` and ``notes="a note"``; ``format_telecentric_report({})`` was a
    KeyError; ``stop_clipping(None)`` an AttributeError, and a primary wavelength outside
    the glasses' data gave None ("no clipping")."""
    cooke, tele = jl.load(COOKE), jl.load(TELE)
    with pytest.raises(ValueError, match="telecentric_report_data: the lens is not object-space"):
        RT.telecentric_report_data(cooke)
    with pytest.raises(ValueError, match="wavefront must be True or False"):
        RT.telecentric_report_data(tele, wavefront="yes")
    with pytest.raises(TypeError, match="notes must be a list of str"):
        RT.telecentric_report_data(tele, notes="a note")
    with pytest.raises(TypeError, match="telecentric_report_data: lens must be a jaxlens.Lens"):
        RT.telecentric_report_data(TELE)
    with pytest.raises(ValueError, match="format_telecentric_report: data must be the dict"):
        RT.format_telecentric_report({})
    with pytest.raises(TypeError, match="stop_clipping: lens must be a jaxlens.Lens"):
        stop_clipping(None)
    import dataclasses

    far = dataclasses.replace(cooke, wavelengths=jnp.array([30.0]), primary=0)
    with pytest.raises(ValueError, match="stop_clipping.*30"):
        stop_clipping(far)
    assert stop_clipping(cooke) is None  # control: its stop passes the beam


def test_nafnet_refuses_an_integer_image_as_render_does():
    """Main: NAFNet ran a uint8 image as radiance 0…255 (render refused it: one rule now,
    decode sRGB codes with to_linear), and a bool image failed naming no dtype."""
    import jax

    net = nets.NAFNet(3, 3, width=4, enc_blocks=(1,), middle_blocks=1, dec_blocks=(1,),
                      key=jax.random.key(0))
    for img in (np.full((8, 8, 3), 128, np.uint8), jnp.full((8, 8, 3), 9, jnp.uint16),
                jnp.ones((8, 8, 3), jnp.int32)):
        with pytest.raises(ValueError, match="NAFNet: image must be a float image.*to_linear"):
            net(img)
    with pytest.raises(ValueError, match="NAFNet: image must be a float image.*bool"):
        net(jnp.ones((8, 8, 3), bool))
    lin = images.to_linear(np.full((8, 8, 3), 128, np.uint8))  # control: the explicit way
    assert net(lin).shape == (8, 8, 3)


def test_image_metrics_compare_images_on_one_scale():
    """Main: uint8 against uint16 codes scored 0.03 dB, two bool images 0 dB, two numbers
    15.6 dB, 0…255 float images with data_range 1 −8.1 dB; 4-d images failed in skimage."""
    u8 = np.full((8, 8), 100, np.uint8)
    with pytest.raises(ValueError, match="psnr: integer images must be of one dtype"):
        images.psnr(u8, np.full((8, 8), 25700, np.uint16))
    with pytest.raises(ValueError, match="psnr: reference and test must be real images.*bool"):
        images.psnr(np.ones((8, 8), bool), np.zeros((8, 8), bool))
    with pytest.raises(ValueError, match="psnr: the images are empty or not arrays"):
        images.psnr(0.5, 0.6)
    a = np.full((8, 8, 3), 0.5 * 255)
    b = a + 2.0
    b[0, 0, 0] = 0.0
    with pytest.raises(ValueError,
                       match="psnr: data_range 1 for images whose values span 129.5, more than"):
        images.psnr(a, b, data_range=1.0)
    with pytest.raises(ValueError, match=r"ssim: images must be \[H, W\] or \[H, W, C\]"):
        images.ssim(np.ones((8, 8, 3, 2)), np.ones((8, 8, 3, 2)) * 0.9)
    # controls: two uint8 images as codes; a restored image overshooting [0, 1] a little
    assert np.isfinite(images.psnr(u8, u8 + 1))
    x = np.full((8, 8), 0.5)
    assert np.isfinite(images.psnr(x, np.where(x > 0, 1.1, 0.0) * np.eye(8)[0], data_range=1.0))
