"""The reference cases traced by the build users run.

tests/conftest.py compiles the suite with XLA:CPU options that compile faster
(``COMPILE_SPEED_FLAGS``: LLVM optimisation level 0 and others; the suite is compile-bound); the
optimised build rounds differently (fused multiply-adds, reduction order: image points of the
zoo lenses differ by up to 4e-14 mm in float64). So the reference intercepts are checked once
more here in a process with XLA's default optimisation level.
"""

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
from conftest import COMPILE_SPEED_FLAGS, find_refcase_dir

TESTS = pathlib.Path(__file__).resolve().parent

SCRIPT = """
import json, sys
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np
sys.path.insert(0, sys.argv[1])
from helpers import refcase_lens, refcase_rays
import jaxlens as jl
flags = __import__("os").environ.get("XLA_FLAGS", "")
out = {"flags": flags}
for path in sys.argv[2:]:
    lens, d = refcase_lens(path)
    rays, ref = refcase_rays(d)
    r = jax.jit(jl.trace)(lens, rays)
    out[path] = [bool(r.valid.all()), float(np.abs(np.asarray(r.origin) - ref[:, :3]).max()),
                 float(np.abs(np.asarray(r.direction) - ref[:, 3:]).max())]
print(json.dumps(out))
"""


def test_refcase_intercepts_with_the_default_optimisation_level():
    cases = sorted(str(p) for p in find_refcase_dir().glob("*.json"))
    speed = {f.split("=")[0] for f in COMPILE_SPEED_FLAGS}
    flags = " ".join(f for f in os.environ.get("XLA_FLAGS", "").split()
                     if f.split("=")[0] not in speed)
    env = {**os.environ, "XLA_FLAGS": flags}
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(TESTS), *cases], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    out = json.loads(r.stdout.strip().splitlines()[-1])
    used = out.pop("flags")
    assert not any(name in used for name in speed), used
    assert len(out) == len(cases) >= 2
    for case, (valid, dp, dd) in out.items():
        assert valid, case
        assert np.isfinite(dp) and dp < 1e-9, (case, dp)
        assert np.isfinite(dd) and dd < 1e-12, (case, dd)
