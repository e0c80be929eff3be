"""Command-line plumbing shared by the experiments: one-line option errors and run folders.

A run must never destroy an earlier one or leave a folder that looks finished when it was
interrupted. :class:`RunFolder` checks ``--out`` before any work starts (an earlier run
there is refused unless ``overwrite``; an unwritable place is found at once), the run
writes into a hidden temporary folder beside it, and :meth:`RunFolder.finish` marks it
finished and renames it into place. An interrupted run leaves only the temporary folder
(``.<name>.partial-*``), never ``--out`` itself; the callers remove it with
:meth:`RunFolder.abandon` on any exception, and SIGTERM (``timeout``, ``kill``, a batch
scheduler) becomes one (``SystemExit(143)``) while the folder is open. A run that finishes
while another has filled ``--out`` meanwhile keeps its result in the temporary folder and
does not replace the other's (unless ``overwrite``, and then only a finished run).

Bad options exit with status 2 and one line on stderr (:class:`OneLineParser`,
:func:`fail`), in well under a second: nothing is imported or compiled before the checks.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import sys
import tempfile
import threading

FINISHED = "RUN_FINISHED"
"""File that :meth:`RunFolder.finish` writes into a completed run folder."""


class UsageError(ValueError):
    """A bad command-line option or output folder: exit status 2, one line."""


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr and exit status 2."""

    def error(self, message: str):  # noqa: D102 (argparse's hook)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        sys.exit(2)


def given_options(build_parser, argv) -> frozenset[str]:
    """The option names (dests) that ``argv`` gives, whatever their values: an option given
    at its default value (``--seeds 3``) is given too, which comparing values misses."""
    unset = object()  # not a string: argparse would run a string default through ``type``
    p = build_parser()
    p.set_defaults(**dict.fromkeys(vars(p.parse_args([])), unset))
    return frozenset(k for k, v in vars(p.parse_args(argv)).items() if v is not unset)


def comma_ints(text: str) -> tuple[int, ...]:
    """A comma-separated list of whole numbers written in ASCII digits, each as
    ``checks.cli_int`` reads one (``str.isdigit`` took other digit scripts: ``"١"`` ran as
    seed 1); an empty entry raises ``ValueError`` (``"0,,1"`` lost the seed typed there)."""
    from jaxlens.optics.checks import cli_int

    return tuple(cli_int(v) for v in text.split(","))


def fail(prog: str, error: Exception) -> int:
    """Print one line for a refused option and return exit status 2."""
    print(f"{prog}: error: {' '.join(str(error).split())}", file=sys.stderr)
    return 2


def _terminated(signum, frame):
    """SIGTERM as an exception, so that the run's cleanup (``abandon``) runs."""
    raise SystemExit(128 + signum)  # the shell's exit status for death by that signal


def _nearest_existing(path: str) -> str:
    p = os.path.abspath(path)
    while not os.path.exists(p):
        parent = os.path.dirname(p)
        if parent == p:
            break
        p = parent
    return p


def check_writable(path: str, option: str) -> None:
    """Refuse (UsageError) a folder ``path`` that cannot be created or written: its nearest
    existing ancestor must be a writable folder. An empty name (the working folder, where
    ``--ablation-out ''`` wrote its columns) is refused too."""
    if not os.fspath(path).strip():
        raise UsageError(f"{option} needs a folder name, got {path!r}")
    base = _nearest_existing(os.path.dirname(os.path.abspath(path)))
    if not os.path.isdir(base) or not os.access(base, os.W_OK | os.X_OK):
        raise UsageError(f"{option} {path}: cannot create or write there ({base} is not a "
                         f"writable folder)")


def within(path: str, folder: str) -> bool:
    """Whether ``path`` is ``folder`` or lies inside it (links resolved)."""
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def refuse_inside_out(out: str, paths, prog: str) -> None:
    """Refuse (UsageError) an input or side folder that is ``--out`` or lies inside it.

    ``--out`` is written through a temporary folder and swapped into place at the end, so
    whatever was in it (or is put there during the run) goes: with ``--overwrite`` when the
    earlier run is replaced, and without it the run ends refused by its own files.

    Args:
        out: The ``--out`` folder.
        paths: ``(option, path)`` pairs; a ``None`` path is skipped.
        prog: The command's name for the message.
    """
    for option, path in paths:
        if path is not None and within(path, out):
            raise UsageError(f"{prog}: {option} {path} lies in --out {out} (or is it), which "
                             f"the run replaces when it ends (and --overwrite clears): it "
                             f"would be deleted; keep it outside --out")


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
        # Before: overwrite="no" (or 1) replaced an earlier run, and "" (the current folder),
        # None or a number failed late or ran in the working folder.
        if not isinstance(overwrite, bool):
            raise UsageError(f"{option}: overwrite must be True or False (--overwrite), got "
                             f"{overwrite!r}")
        if not isinstance(path, str | os.PathLike) or not os.fspath(path).strip():
            raise UsageError(f"{option} needs a folder name, got {path!r}")
        path = os.fspath(path)
        self.final = os.path.abspath(path)
        self.option = option
        self.overwrite = overwrite
        self.tmp: str | None = None
        self._sigterm = None  # the SIGTERM handler to restore, while ours is installed
        self._check_final(path)
        check_writable(path, option)

    def _check_final(self, path: str) -> None:
        """Refuse to replace what is at the final folder (before the run, and again at the
        end: another run may have finished there meanwhile)."""
        if not os.path.exists(self.final):
            return
        if not os.path.isdir(self.final):
            raise UsageError(f"{self.option} {path} is a file, not a folder")
        entries = os.listdir(self.final)
        if entries and FINISHED not in entries:
            raise UsageError(
                f"{self.option} {path} is not empty and holds no finished jaxlens run "
                f"({len(entries)} entries); choose an empty or new folder")
        if entries and not self.overwrite:
            raise UsageError(
                f"{self.option} {path} holds an earlier run; give --overwrite to replace it, "
                f"or choose another folder")

    def start(self) -> str:
        """Create the temporary folder and return its path (write everything there).

        From here until :meth:`finish` or :meth:`abandon`, SIGTERM raises ``SystemExit``
        in the main thread, so the caller's cleanup runs as for any exception.
        """
        parent = os.path.dirname(self.final)
        if threading.current_thread() is threading.main_thread():  # signal's own limit
            previous = signal.signal(signal.SIGTERM, _terminated)
            self._sigterm = signal.SIG_DFL if previous is None else previous
        try:
            os.makedirs(parent, exist_ok=True)
            self.tmp = tempfile.mkdtemp(prefix=f".{os.path.basename(self.final)}.partial-",
                                        dir=parent)
        except OSError as e:
            self._release()
            raise UsageError(f"{self.option} {self.final}: cannot write there ({e})") from None
        return self.tmp

    def _release(self) -> None:
        """Give SIGTERM back its handler from before :meth:`start`."""
        if self._sigterm is not None:
            signal.signal(signal.SIGTERM, self._sigterm)
            self._sigterm = None

    def final_path(self, path: str) -> str:
        """Where a path inside the temporary folder will be once the run is finished."""
        if self.tmp and os.path.abspath(path).startswith(self.tmp):
            return self.final + os.path.abspath(path)[len(self.tmp):]
        return path

    def finish(self) -> str:
        """Mark the run finished and move it into place; returns the final folder.

        Raises:
            UsageError: If another run has filled the final folder since this one began
                (and ``overwrite`` is not given, or it holds no finished run). This run's
                result then stays, finished, in the temporary folder the message names.
        """
        if self.tmp is None:
            raise RuntimeError("RunFolder.finish before start")
        with open(os.path.join(self.tmp, FINISHED), "w") as f:
            f.write("finished\n")
        self._release()  # SIGTERM from here on stops the swap without removing either run
        try:
            self._check_final(self.final)
        except UsageError as e:
            kept, self.tmp = self.tmp, None  # not abandon()'s to remove: it is finished
            raise UsageError(f"{e} (it was filled while this run went on; this run is "
                             f"finished in {kept})") from None
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
        self._release()
