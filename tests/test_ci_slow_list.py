"""conftest's CI_SLOW names tests that exist: a renamed or removed test would leave a stale
entry, and a typo would leave the heavy test in CI without a word."""

import pathlib
import re

from conftest import CI_SLOW


def test_every_ci_slow_entry_names_a_test_function_of_its_file():
    here = pathlib.Path(__file__).parent
    for file, names in CI_SLOW.items():
        source = (here / file).read_text(encoding="utf-8")
        defined = set(re.findall(r"^\s*def (test_\w+)", source, re.M))
        for name in names:
            assert name.split("[")[0] in defined, (file, name)
