"""optiland 0.6.3 EFLs for the .zmx snippets of tests/test_zmx_corpus3.py.

Run with optiland's own interpreter (optiland is not a jaxlens dependency):

    /work/optiland_venv/bin/python tools/corpus3_reference.py

It writes each snippet (imported from the test file's text, without importing jaxlens) to a
temporary file and prints ``paraxial.f2()`` (image-space EFL, lens units = mm here).
"""

import ast
import pathlib
import tempfile
import warnings

from optiland.fileio import load_zemax_file

warnings.filterwarnings("ignore")
TEST = pathlib.Path(__file__).resolve().parents[1] / "tests" / "test_zmx_corpus3.py"
SNIPPETS = ("EO65438", "AC254_100_A", "EVENASPH_NO_R2")

tree = ast.parse(TEST.read_text())
texts = {
    node.targets[0].id: ast.literal_eval(node.value)
    for node in tree.body
    if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", None) in SNIPPETS
}
with tempfile.TemporaryDirectory() as d:
    for name in SNIPPETS:
        p = pathlib.Path(d) / f"{name}.zmx"
        p.write_text(texts[name])  # temporary folder
        print(name, repr(float(load_zemax_file(str(p)).paraxial.f2())))
