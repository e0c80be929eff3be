"""The jaxlens command line: ``python -m jaxlens <command> ...`` (also installed as ``jaxlens``).

Commands are argparse subcommands. A module adds one by defining ``register(subparsers)``,
which calls ``subparsers.add_parser(...)`` and sets ``func`` (taking the parsed
``argparse.Namespace`` and returning an exit status) with ``set_defaults``; list the module
in ``_COMMANDS`` below.

The CLI computes in float64 (``jax_enable_x64``) unless ``--float32`` is given.
"""

from __future__ import annotations

import argparse
import importlib
import sys

_COMMANDS = ("jaxlens.analysis.report",)


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every registered subcommand."""
    parser = argparse.ArgumentParser(
        prog="python -m jaxlens", description="jaxlens: differentiable lens design in JAX"
    )
    parser.add_argument(
        "--float32", action="store_true", help="compute in float32 (default: float64)"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in _COMMANDS:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``), run the command, return its exit status.
    From the command line (``argv`` None) compiled programs are kept for the next run
    (``jaxlens.compile_cache``)."""
    args = build_parser().parse_args(argv)
    if argv is None:
        from jaxlens import compile_cache

        compile_cache.enable()
    if not args.float32:
        import jax

        jax.config.update("jax_enable_x64", True)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
