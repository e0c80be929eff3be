"""Size and compile time of the report's traced program of a lens file, per ray aiming.

For each aiming mode, the report's one compiled program (``analysis.report._compute``: every
field's and wavelength's spot rays, aimed as the mode says) is lowered and compiled, and its
size printed: lines of the compiled HLO, fusions, while loops, and the compile's CPU time.
Run it on two trees to compare them (each in its own process)::

    F=tests/data/zmx/rayoptics_US00583336-2-scaled.zmx
    PYTHONPATH=. python tools/aim_compile_size.py $F
    PYTHONPATH=/tmp/main_old python tools/aim_compile_size.py $F   # an archive of another commit
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import time
import warnings

import equinox as eqx
import jax

import jaxlens as jl
from jaxlens.analysis import report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", help="a lens file (.zmx or .json)")
    ap.add_argument("--aims", nargs="+", default=list(jl.RAY_AIMING), choices=jl.RAY_AIMING)
    args = ap.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lens = jl.load(args.file)
    for aim in args.aims:
        dyn, static = eqx.partition(dataclasses.replace(lens, aim=aim), eqx.is_array)
        lowered = jax.jit(lambda d, s=static: report._compute(eqx.combine(d, s))).lower(dyn)
        t = time.process_time()
        text = lowered.compile().as_text()
        cpu = time.process_time() - t
        print(f"{aim:>14}: {text.count(chr(10))} lines, {len(re.findall(r'fusion[(]', text))} "
              f"fusions, {text.count(' while(')} while loops, compile {cpu:.2f} s CPU")


if __name__ == "__main__":
    main()
