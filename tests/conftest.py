"""Test configuration: float64 for accuracy tests, strict rank promotion."""

import os

# Four host devices (the sharded paths run on CPU), and LLVM optimisation level 0: the suite is
# compile-bound, and level 0 compiles about 40 % faster (the classical and benchmark smoke
# files: 428 s against 693 s, one worker, same load). XLA's graph passes are unchanged; the
# optimised build rounds differently (fused multiply-adds: ≤ 4e-14 mm on the zoo lenses' image
# points), and test_optimised_build checks the reference cases with it. XLA_FLAGS already set win.
_flags = os.environ.get("XLA_FLAGS", "")
for _flag in ("--xla_force_host_platform_device_count=4", "--xla_backend_optimization_level=0"):
    if _flag.split("=")[0] not in _flags:
        _flags = f"{_flags} {_flag}".strip()
os.environ["XLA_FLAGS"] = _flags

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


# The test files that take longest (seconds of one worker on 2 cores, from
# `pytest --junitxml`), heaviest first. The two workers take whole files from the front of the
# queue, so starting with these keeps one worker from finishing a long file alone at the end
# (pytest-xdist otherwise orders files by their number of tests: see --no-loadscope-reorder in
# pyproject.toml). The order changes no result.
HEAVIEST_FIRST = (
    "test_classical_smoke.py",  # 247 s
    "test_edof.py",  # 240
    "test_benchmarks_smoke.py",  # 216
    "test_trace.py",  # 178
    "test_render.py",  # 148
    "test_tiled.py",  # 141
    "test_edof_base_lens.py",  # 134
    "test_surface_adjoint.py",  # 133
    "test_stress.py",  # 116
    "test_bad_input.py",  # 109
    "test_toroid_paraxial.py",  # 93
    "test_nets.py",  # 91
)


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(HEAVIEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: files keep
    # their own order of tests, and the other files their order after these
