"""A pytest plugin that records each test's CPU time (this process and the command lines it
started and waited for) and wall time, to find where the suite spends its time on a machine
whose load varies (wall times then vary with the load; CPU times much less).

    PYTHONPATH=tools CPU_TIMES_OUT=/tmp/cpu.json pytest -n 0 -p cpu_time_plugin tests/test_x.py

writes ``[[node id, CPU s, wall s], ...]`` to ``CPU_TIMES_OUT`` (default ``cpu_times.json``).
Run it with ``-n 0``: each xdist worker would write its own file over the others'. Used on
2026-12-02 to measure the tests' shared compile cache (``tests/conftest.py``): 34 test files,
354 s of CPU without it, 283 s with it (``JAX_COMPILATION_CACHE_DIR`` set to a fresh folder
and ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0``, as the conftest does).
"""

import json
import os
import resource
import time

import pytest

_rows = []


def _cpu_seconds() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    cpu, wall = _cpu_seconds(), time.perf_counter()
    yield
    _rows.append((item.nodeid, _cpu_seconds() - cpu, time.perf_counter() - wall))


def pytest_sessionfinish(session):
    from jaxlens.io.json_values import write_whole  # whole or not at all

    write_whole(os.environ.get("CPU_TIMES_OUT", "cpu_times.json"), json.dumps(_rows))
