"""Re-apply the classical run's export step to committed design files, in place.

    PYTHONPATH=. python tools/reexport_designs.py experiments/classical/designs \
        experiments/classical/designs_paper_method

Each ``seed_<n>.zmx`` is read, given the clear apertures and the evaluation notes that
``jaxlens.experiments.classical_export`` writes today (round 36d: a 1e-2 margin over the
largest evaluated ray height, where the files of the recorded run carried 1e-9), and written
back. The prescription must not move: every line of the new file other than DIAM, CLAP and
NOTE must equal the old file's, and ``design.evaluate`` (Table 1's definition, 16 × 16 fields)
must give the same validity and RMS spots (to 1e-12 relative) before and after; otherwise
the file is left as it was and the script says why. The spec is the recorded run's
(``DesignSpec()``, the default; ``experiments/classical/table1.json`` holds it).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib
import sys
import tempfile

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxlens  # noqa: E402
from jaxlens.design import evaluate  # noqa: E402
from jaxlens.design.spec import DesignSpec  # noqa: E402
from jaxlens.experiments.classical_export import (  # noqa: E402
    evaluation_notes,
    with_clear_apertures,
)

EXPORT_ONLY_KEYS = ("DIAM", "CLAP", "NOTE")


def _prescription_lines(path: pathlib.Path) -> list[str]:
    return [
        ln
        for ln in path.read_text(errors="replace").splitlines()
        if ln.split()[:1] and ln.split()[0] not in EXPORT_ONLY_KEYS
    ]


def _keep_rounding(trial: pathlib.Path, path: pathlib.Path) -> None:
    """Keep the old DIAM and CLAP lines where the new ones differ only by rounding (1e-12,
    relative: the clear apertures recomputed from the file's own numbers), so that a
    re-export changes no line it has no reason to."""
    old, new = path.read_text().splitlines(), trial.read_text().splitlines()
    if len(old) != len(new):
        return
    for k, (a, b) in enumerate(zip(old, new, strict=True)):
        ka, kb = a.split()[:1], b.split()[:1]
        if ka == kb and ka and ka[0] in ("DIAM", "CLAP") and a != b:
            na, nb = a.split()[1:3], b.split()[1:3]
            try:
                close = all(
                    np.isclose(float(x.strip('"')), float(y.strip('"')), rtol=1e-12, atol=0)
                    for x, y in zip(na, nb, strict=True)
                )
            except ValueError:
                close = False
            if close:
                new[k] = a
    trial.write_text("\n".join(new) + "\n", newline="\r\n")  # temporary


def reexport(path: pathlib.Path, spec: DesignSpec) -> str:
    lens = jaxlens.load(str(path))
    new = dataclasses.replace(
        with_clear_apertures(lens, spec), description=evaluation_notes(spec, 16)
    )
    before, after = evaluate.evaluate(lens, spec, n=16), evaluate.evaluate(new, spec, n=16)
    if before.valid != after.valid or not np.allclose(
        after.rms_um, before.rms_um, rtol=1e-12, atol=0
    ):
        return f"{path}: left as it was (evaluation moved: valid {before.valid} -> {after.valid})"
    with tempfile.TemporaryDirectory() as tmp:
        trial = pathlib.Path(tmp) / path.name
        for agf in path.parent.glob("*.AGF"):  # the side catalog the file names
            (pathlib.Path(tmp) / agf.name).write_bytes(agf.read_bytes())
        jaxlens.save(new, str(trial))
        _keep_rounding(trial, path)
        if _prescription_lines(trial) != _prescription_lines(path):
            return f"{path}: left as it was (lines other than {EXPORT_ONLY_KEYS} would change)"
        os.replace(trial, path)
    grew = max(
        float(b.semi_diameter) / float(a.semi_diameter) - 1
        for a, b in zip(lens.surfaces, new.surfaces, strict=True)
    )
    return (
        f"{path}: rewritten (valid {after.valid}, mean RMS {after.rms_mean_um:.6f} um, "
        f"largest aperture change {100 * grew:+.3f} %)"
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=pathlib.Path)
    a = p.parse_args(argv)
    spec = DesignSpec()
    for folder in a.folders:
        for path in sorted(folder.glob("seed_*.zmx"), key=lambda q: int(q.stem.split("_")[1])):
            print(reexport(path, spec), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
