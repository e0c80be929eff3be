"""The package's layout as the README describes it, and the module size guide."""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODULES = sorted(p for p in (ROOT / "jaxlens").rglob("*.py")
                 if p.name not in ("__init__.py", "__main__.py"))


def test_readme_layout_names_every_module():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    layout = text[text.index("## Layout"):]
    layout = layout[:layout.index("\n## ", 1)]
    missing = [str(p.relative_to(ROOT)) for p in MODULES
               if not re.search(rf"\b{re.escape(p.stem)}\b", layout)]
    assert MODULES and not missing, f"README's Layout section does not name {missing}"


def test_no_module_is_over_800_lines():
    long = {str(p.relative_to(ROOT)): n for p in MODULES
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 800}
    assert not long, f"modules over the 800-line guide: {long}"
