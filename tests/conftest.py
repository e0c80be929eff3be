"""Test configuration: float64 for accuracy tests, strict rank promotion."""

import os

os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=4")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import pathlib  # noqa: E402

import pytest  # noqa: E402

REFCASES = pathlib.Path(__file__).resolve().parents[2] / "shared" / "refcases"


def find_refcase_dir():
    """Folder of reference cases from independent tracers: $JAXLENS_REFCASES, then
    ../shared/refcases beside the checkout, then the copy shipped in tests/refcases."""
    env = os.environ.get("JAXLENS_REFCASES")
    shipped = pathlib.Path(__file__).parent / "refcases"
    for p in ([pathlib.Path(env)] if env else []) + [REFCASES, shipped]:
        if p.is_dir() and any(p.glob("*.json")):
            return p
    return None


@pytest.fixture(scope="session")
def refcase_dir():
    """Folder of reference cases (skips if absent)."""
    p = find_refcase_dir()
    if p is None:
        pytest.skip("no reference cases found")
    return p


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop JAX's compiled programs after each test file: the whole suite in one process
    otherwise keeps every executable it ever built (hundreds of large traces and designs)."""
    yield
    import gc

    jax.clear_caches()
    gc.collect()
