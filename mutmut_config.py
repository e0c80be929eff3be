"""mutmut 2 hook (``tests/mutation.sh``): mutate only the functions named in $MUTATE_ONLY.

``MUTATE_ONLY="dumps,save_zmx"`` limits the mutants of a large module to the top-level
functions and classes that define a result (e.g. the .zmx writer, not the reader); the
others are reported as skipped. Without it every line is mutated.
"""

import ast
import functools
import os


@functools.cache
def _ranges(filename, names):
    tree = ast.parse(open(filename, encoding="utf-8").read())
    return [(n.lineno, n.end_lineno) for n in tree.body
            if getattr(n, "name", None) in names]


def pre_mutation(context):
    only = os.environ.get("MUTATE_ONLY")
    if not only:
        return
    line = context.current_line_index + 1
    spans = _ranges(context.filename, frozenset(only.split(",")))
    if not any(a <= line <= b for a, b in spans):
        context.skip = True
