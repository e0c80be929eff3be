"""Test configuration: float64 for accuracy tests, strict rank promotion."""

import os

# Four host devices (the sharded paths run on CPU), and XLA:CPU options that compile faster: the
# suite is compile-bound. LLVM optimisation level 0 (the classical and benchmark smoke files:
# 428 s against 693 s, one worker, same load). XLA's graph passes are unchanged; the optimised
# build rounds differently (fused multiply-adds: ≤ 4e-14 mm on the zoo lenses' image points),
# and test_optimised_build checks the reference cases without these options. Measured and not
# taken (2026-11-30): LLVM's expensive passes off (test_classical_smoke 164 → 189 s of CPU,
# test_trace 93 → 105 s, one process, same sitting: the slower code costs more than the
# compile saves) and the legacy loop emitters (a NaN where the default build gives a number).
# XLA_FLAGS already set win.
COMPILE_SPEED_FLAGS = (
    "--xla_backend_optimization_level=0",
)


def _accepted(flags):
    """The flags this jaxlib's XLA accepts: an unknown flag aborts XLA at start-up, and XLA
    renames its options between releases. Probed in a subprocess, once (pytest-xdist's workers
    inherit the result through the environment)."""
    import subprocess
    import sys

    def starts(fl):
        env = {**os.environ, "XLA_FLAGS": " ".join(fl), "JAX_PLATFORMS": "cpu"}
        code = "import jax.numpy as jnp; jnp.zeros(1).block_until_ready()"
        run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True)
        return run.returncode == 0

    if not flags or starts(flags):
        return flags
    return [f for f in flags if starts([f])]


_flags = os.environ.get("XLA_FLAGS", "")
_missing = [f for f in ("--xla_force_host_platform_device_count=4", *COMPILE_SPEED_FLAGS)
            if f.split("=")[0] not in _flags]
os.environ["XLA_FLAGS"] = " ".join([_flags, *_accepted(_missing)]).strip()

# JAX's persistent compilation cache, one folder for the run, shared by the worker processes
# (they inherit the environment) and the command lines the tests start: each test file's
# programs are dropped after it (below), and many files compile the same programs again (the
# same lenses, pupils and analyses). A program found there is loaded instead of compiled; it is
# the same executable, so no result changes. Measured 2026-12-02, 34 of the test files in one
# process: 354 -> 283 s of CPU. A folder the user names in JAX_COMPILATION_CACHE_DIR is used
# as it is; the run's own folder is removed at its end.
_OWN_CACHE = None
if not os.environ.get("JAX_COMPILATION_CACHE_DIR"):
    import tempfile

    _OWN_CACHE = tempfile.mkdtemp(prefix="jaxlens-tests-compiled-")
    os.environ["JAX_COMPILATION_CACHE_DIR"] = _OWN_CACHE
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")

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


# The test files that take longest (seconds of CPU in one process, per file, measured
# 2026-11-30 by helper citime4 under load; test_afocal and the smaller files not measured),
# heaviest first. The two workers take whole files from the front of the queue, so starting
# with these keeps one worker from finishing a long file alone at the end (pytest-xdist
# otherwise orders files by their number of tests: see --no-loadscope-reorder in
# pyproject.toml). The order changes no result.
HEAVIEST_FIRST = (
    "test_classical_smoke.py",  # 194 s
    "test_surface_adjoint.py",  # 96
    "test_trace.py",  # 95
    "test_benchmarks_smoke.py",  # 94
    "test_edof_base_lens.py",  # 93
    "test_edof.py",  # 79
    "test_stress.py",  # 62
    "test_tiled.py",  # 58
    "test_render.py",  # 58
    "test_aberrations.py",  # 53
    "test_toroid_paraxial.py",  # 50
    "test_bad_input.py",  # 47
    "test_nets.py",  # 28
    "test_gradients_round36e.py",  # 32 (2026-12-02, under load)
)


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(HEAVIEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: files keep
    # their own order of tests, and the other files their order after these


def pytest_unconfigure(config):
    """Remove the run's compile cache (only the process that made it: the workers share it)."""
    if _OWN_CACHE is not None:
        import shutil

        shutil.rmtree(_OWN_CACHE, ignore_errors=True)
