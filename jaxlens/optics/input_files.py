"""The one check of a file a reader opens: it exists (``load``, ``load_json``, ``load_zmx``,
``configurations``, ``load_agf``, ``read_image``). A missing file was Python's bare
``[Errno 2] No such file or directory``, which named neither the function nor what it wanted;
a FIFO named ``lens.zmx`` blocked ``open`` for ever, and a link to ``/dev/zero`` read until
the memory ran out."""

from __future__ import annotations

import os


def input_file(path: str | os.PathLike, where: str, what: str = "file") -> str:
    """``path`` as a string, if a file is there; else ``FileNotFoundError`` naming ``where``
    (the function the user called), ``what`` it reads and the path."""
    p = os.fspath(path)
    if not os.path.exists(p):
        raise FileNotFoundError(f"{where}: no such {what}: {p!r} (the file does not exist)")
    if os.path.isdir(p):
        raise ValueError(f"{where}: {p!r} is a folder; give a {what} in it")
    if not os.path.isfile(p):  # a FIFO blocked open() for ever, /dev/zero filled the memory
        raise ValueError(f"{where}: {p!r} is not a regular file (a FIFO, socket or device, "
                         f"which a reader waits on or reads without end); give a {what}")
    return p
