"""Reference Seidel numbers from optiland 0.6.3 for ``tests/test_seidel.py``.

Two steps (the first needs jaxlens, the second optiland's own environment):

    PYTHONPATH=$PWD python tools/seidel_reference.py write /tmp/seidel_ref
    /work/optiland_venv/bin/python tools/seidel_reference.py read /tmp/seidel_ref

``write`` saves the test lenses (the zoo Cooke triplet and the conic + even-asphere doublet
of ``tests/test_seidel.py``) to ``.zmx`` with ``jaxlens.save``; ``read`` loads each with
``optiland.fileio.load_zemax_file`` and prints optiland's per-surface third-order terms
(TSC, CC, TAC, TPC, DC, TAchC, TchC; surfaces 1 … n, object and image left out), its
``seidels()`` sums and the image-space marginal slope, as Python literals to paste.
"""

import sys
from pathlib import Path

NAMES = ("cooke_triplet", "asphere_doublet")


def write(folder: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import jax

    jax.config.update("jax_enable_x64", True)
    import jaxlens
    from tests.test_seidel import asphere_doublet

    folder.mkdir(parents=True, exist_ok=True)
    lenses = {"cooke_triplet": jaxlens.zoo.cooke_triplet(clip=False),
              "asphere_doublet": asphere_doublet()}
    for name, lens in lenses.items():
        jaxlens.save(lens, folder / f"{name}.zmx")
        print("wrote", folder / f"{name}.zmx")


def read(folder: Path) -> None:
    import numpy as np
    from optiland.fileio import load_zemax_file

    np.set_printoptions(precision=17, linewidth=200)
    for name in NAMES:
        optic = load_zemax_file(str(folder / f"{name}.zmx"))
        ab = optic.aberrations
        terms = {t: np.asarray(getattr(ab, t)(), float).tolist()
                 for t in ("TSC", "CC", "TAC", "TPC", "DC", "TAchC", "TchC")}
        _, ua = optic.paraxial.marginal_ray()
        print(f"OPTILAND_{name.upper()} = {{")
        for t, v in terms.items():
            print(f"    {t!r}: {v!r},")
        print(f"    'seidels': {np.asarray(ab.seidels(), float).tolist()!r},")
        print(f"    'image_u': {float(np.asarray(ua).reshape(-1)[-1])!r},")
        print("}")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("write", "read"):
        raise SystemExit("usage: seidel_reference.py write|read FOLDER")
    (write if sys.argv[1] == "write" else read)(Path(sys.argv[2]))
