"""Command-line plumbing shared by the experiments: one-line option errors and run folders.

A run must never destroy an earlier one or leave a folder that looks finished when it was
interrupted. :class:`RunFolder` checks ``--out`` before any work starts (an earlier run
there is refused unless ``overwrite``; an unwritable place is found at once), the run
writes into a hidden temporary folder beside it, and :meth:`RunFolder.finish` marks it
finished and renames it into place. An interrupted run leaves only the temporary folder
(``.<name>.partial-*``), never ``--out`` itself.

Bad options exit with status 2 and one line on stderr (:class:`OneLineParser`,
:func:`fail`), in well under a second: nothing is imported or compiled before the checks.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile

FINISHED = "RUN_FINISHED"
"""File that :meth:`RunFolder.finish` writes into a completed run folder."""


class UsageError(ValueError):
    """A bad command-line option or output folder: exit status 2, one line."""


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr and exit status 2."""

    def error(self, message: str):  # noqa: D102 (argparse's hook)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        sys.exit(2)


def fail(prog: str, error: Exception) -> int:
    """Print one line for a refused option and return exit status 2."""
    print(f"{prog}: error: {' '.join(str(error).split())}", file=sys.stderr)
    return 2


def _nearest_existing(path: str) -> str:
    p = os.path.abspath(path)
    while not os.path.exists(p):
        parent = os.path.dirname(p)
        if parent == p:
            break
        p = parent
    return p


class RunFolder:
    """The output folder of one run, written through a temporary folder beside it.

    Args:
        path: The final folder (``--out``).
        overwrite: Replace an earlier run there (``--overwrite``).
        option: The option's name for messages.

    Raises:
        UsageError: If ``path`` is a file, holds an earlier run and ``overwrite`` is not
            given, holds other files, or cannot be created or written.
    """

    def __init__(self, path: str, *, overwrite: bool = False, option: str = "--out"):
        self.final = os.path.abspath(path)
        self.option = option
        self.tmp: str | None = None
        if os.path.exists(self.final):
            if not os.path.isdir(self.final):
                raise UsageError(f"{option} {path} is a file, not a folder")
            entries = os.listdir(self.final)
            if entries and FINISHED not in entries:
                raise UsageError(
                    f"{option} {path} is not empty and holds no finished jaxlens run "
                    f"({len(entries)} entries); choose an empty or new folder")
            if entries and not overwrite:
                raise UsageError(
                    f"{option} {path} holds an earlier run; give --overwrite to replace it, or "
                    f"choose another folder")
        base = _nearest_existing(os.path.dirname(self.final))
        if not os.path.isdir(base) or not os.access(base, os.W_OK | os.X_OK):
            raise UsageError(f"{option} {path}: cannot create or write there ({base} is not a "
                             f"writable folder)")

    def start(self) -> str:
        """Create the temporary folder and return its path (write everything there)."""
        parent = os.path.dirname(self.final)
        try:
            os.makedirs(parent, exist_ok=True)
            self.tmp = tempfile.mkdtemp(prefix=f".{os.path.basename(self.final)}.partial-",
                                        dir=parent)
        except OSError as e:
            raise UsageError(f"{self.option} {self.final}: cannot write there ({e})") from None
        return self.tmp

    def final_path(self, path: str) -> str:
        """Where a path inside the temporary folder will be once the run is finished."""
        if self.tmp and os.path.abspath(path).startswith(self.tmp):
            return self.final + os.path.abspath(path)[len(self.tmp):]
        return path

    def finish(self) -> str:
        """Mark the run finished and move it into place; returns the final folder."""
        if self.tmp is None:
            raise RuntimeError("RunFolder.finish before start")
        with open(os.path.join(self.tmp, FINISHED), "w") as f:
            f.write("finished\n")
        old = None
        if os.path.exists(self.final):
            if os.listdir(self.final):
                old = self.final + f".replaced-{os.getpid()}"
                os.rename(self.final, old)
            else:
                os.rmdir(self.final)
        os.rename(self.tmp, self.final)
        self.tmp = None
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.final

    def abandon(self) -> None:
        """Remove the temporary folder of a failed run (``--out`` is left as it was)."""
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            self.tmp = None
