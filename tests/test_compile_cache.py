"""The command lines' persistent compile cache (``jaxlens.compile_cache``): where it goes,
how it is turned off, and that the report's compiled core is one JAX can keep (it held an
``eqx.error_if`` host callback before, so no run ever reused it)."""

import os
import subprocess
import sys

import jax
import pytest

from jaxlens import compile_cache

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture
def restore_config():
    keys = ("jax_compilation_cache_dir", "jax_persistent_cache_min_compile_time_secs")
    before = {k: getattr(jax.config, k) for k in keys}
    yield
    for k, v in before.items():
        jax.config.update(k, v)


def test_where_the_cache_goes(monkeypatch, tmp_path, restore_config):
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    monkeypatch.delenv("JAXLENS_COMPILE_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compile_cache.default_dir() == str(tmp_path / "xdg" / "jaxlens" / "jax")
    assert compile_cache.enable() == str(tmp_path / "xdg" / "jaxlens" / "jax")
    assert jax.config.jax_compilation_cache_dir == str(tmp_path / "xdg" / "jaxlens" / "jax")
    assert os.path.isdir(tmp_path / "xdg" / "jaxlens" / "jax")
    assert compile_cache.enable(str(tmp_path / "run")) == str(tmp_path / "run")
    monkeypatch.setenv("JAX_COMPILATION_CACHE_DIR", str(tmp_path / "mine"))
    assert compile_cache.enable(str(tmp_path / "run")) == str(tmp_path / "mine")


def test_turned_off_or_unwritable(monkeypatch, tmp_path, restore_config):
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    for off in ("0", "off", "False"):
        monkeypatch.setenv("JAXLENS_COMPILE_CACHE", off)
        assert compile_cache.enable(str(tmp_path / "c")) is None
    assert not os.path.exists(tmp_path / "c")
    monkeypatch.delenv("JAXLENS_COMPILE_CACHE")
    (tmp_path / "file").write_text("x")
    with pytest.warns(UserWarning, match="compile cache off: cannot create"):
        assert compile_cache.enable(str(tmp_path / "file" / "c")) is None


def test_a_report_writes_its_core_to_the_cache(tmp_path):
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(tmp_path / "cache"),
               JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0", PYTHONPATH=ROOT)
    env.pop("JAXLENS_COMPILE_CACHE", None)
    lens = os.path.join(ROOT, "jaxlens", "data", "lenses", "cooke_triplet.json")
    p = subprocess.run([sys.executable, "-m", "jaxlens", "report", lens, "--json"], env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    names = os.listdir(tmp_path / "cache")
    assert any(n.startswith("jit__compute") for n in names), sorted(names)[:20]
