"""Lens files by extension: ``load(path)`` and ``save(lens, path)``.

``.json`` is jaxlens's own format (``jaxlens.io.lensfile``, documented in
``docs/lens-format.md``); ``.zmx`` is Zemax OpticStudio's sequential format
(``jaxlens.io.zmx``). Lengths are in mm and wavelengths in µm once loaded.
"""

from __future__ import annotations

import inspect
import os

import numpy as np

from ..optics import checks
from ..optics.input_files import input_file
from ..optics.lens import Lens
from .json_values import loadable, output_file
from .lensfile import load_json, save_json
from .zmx import load_zmx, save_zmx

_EXTENSIONS = (".json", ".zmx")


def _ext(path: str, what: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in _EXTENSIONS:
        raise ValueError(f"{what}: {path!r} has extension {ext!r}; use one of {_EXTENSIONS}")
    return ext


def load(path: str | os.PathLike, *, dtype=None, strict: bool = False,
         unknown_glass: str = "error", config: int | None = None) -> Lens:
    """Read a lens file (``.json`` or ``.zmx``).

    Args:
        path: the file.
        dtype: cast every floating array to this dtype, float32 or float64 (default: JAX's
            default float, float64 when ``jax_enable_x64`` is on; numbers are read as
            float64).
        strict: for ``.zmx``, refuse unknown keywords and a file cut off mid-line
            (default: a warning); see ``jaxlens.io.zmx.loads``.
        unknown_glass: for ``.zmx``, ``"model"`` opens a file whose glass is in no catalog
            with a model glass of the nd and Vd its GLAS line gives (a ``ZmxWarning``); the
            default ``"error"`` refuses it. ``"model"`` is refused for ``.json``.
        config: for a multi-configuration ``.zmx`` (zoom or focus positions), the
            configuration to read, 1-based as in Zemax; default the active one, which the
            file's surfaces hold (see ``jaxlens.io.zmx.loads``). Refused for ``.json``.

    Returns:
        The ``Lens``.

    Raises:
        ValueError: an unknown extension, or a malformed file (the message names the
            file and, for ``.zmx`` and JSON syntax errors, the line), or an unknown glass
            (the message lists the closest catalog names).
        FileNotFoundError: no file at ``path`` (the message names ``load`` and the path).
    """
    if not isinstance(path, str | os.PathLike):
        raise TypeError(f"load: path must be a file name (str or os.PathLike), got "
                        f"{type(path).__name__} {path!r}")
    path = os.fspath(path)
    if os.path.isdir(path):  # before: "has extension ''", which did not say what was wrong
        raise ValueError(f"load: {path!r} is a folder; give a lens file (.json or .zmx) in it")
    ext = _ext(path, "load")  # first: a missing lens.txt is named by its extension
    path = input_file(path, "load", "lens file")
    if dtype is not None:
        dtype = _float_dtype(dtype)
    # "yes" would read as True, a misspelt choice as "error": refused rather than guessed.
    checks.switch(strict, "strict", "load")
    if unknown_glass not in ("error", "model"):
        raise ValueError(f"load: unknown_glass must be 'error' or 'model', got "
                         f"{unknown_glass!r}")
    if ext == ".json":
        if config is not None:
            raise ValueError(f"load: config selects a configuration of a multi-configuration "
                             f".zmx file; a .json lens has one, got config={config!r} for "
                             f"{path}")
        if unknown_glass == "model":  # before: ignored, as report --unknown-glass model was
            raise ValueError(f"load: unknown_glass='model' opens a .zmx whose GLAS line names "
                             f"a glass in no catalog; a .json material is a catalog name, a "
                             f"model glass {{\"nd\", \"vd\"}} or an index table, so it does "
                             f"not apply to {path}")
        lens = load_json(path)
    else:
        lens = load_zmx(path, strict=strict, unknown_glass=unknown_glass, config=config)
    return lens if dtype is None else lens.astype(dtype)


def _float_dtype(dtype) -> np.dtype:
    """float32 or float64 (by name or dtype): an integer dtype would truncate every number,
    and float16 has too few digits to trace a lens."""
    try:
        dt = np.dtype(dtype)
    except TypeError:
        dt = None
    if dt not in (np.float32, np.float64):
        raise ValueError(f"load: dtype must be float32 or float64 (a name or a dtype), got "
                         f"{dtype!r}")
    return dt


def save(lens: Lens, path: str | os.PathLike, **options) -> list[str]:
    """Write a lens file (``.json`` or ``.zmx``); ``load(save(...))`` gives the same lens.

    Args:
        lens: the lens.
        path: the file; the extension picks the format.
        **options: format options (``.zmx``: ``model_glass="blank"|"agf"``, see
            ``jaxlens.io.zmx.save_zmx``).

    Raises:
        ValueError: an unknown extension, a bad option, or a lens that ``load`` would
            refuse (fields, wavelengths, primary); nothing is written.
        MissingFolderError: the path's folder does not exist (no folder is created); both
            a ``ValueError`` and a ``FileNotFoundError``, as every jaxlens writer raises
            (``jaxlens.io.json_values.output_file``).

    Returns:
        The paths written: the file itself, and for ``.zmx`` any ``.AGF`` glass catalogs
        written beside it for glasses that Zemax's own catalogs do not hold.
    """
    if not isinstance(lens, Lens):  # else an AttributeError from deep in the writer
        raise TypeError(f"save: lens must be a jaxlens Lens, got {type(lens).__name__}")
    if not isinstance(path, str | os.PathLike):  # was os.fspath's TypeError, naming nothing
        raise TypeError(f"save: path must be a file name (str or os.PathLike), got "
                        f"{type(path).__name__} {path!r}")
    path = os.fspath(path)
    if os.path.isdir(path):  # was "has extension ''", or an IsADirectoryError after the checks
        raise ValueError(f"save: {path!r} is a folder; give a file name ending in .json or "
                         f".zmx")
    ext = _ext(path, "save")
    loadable(lens, "save")
    output_file(path, "save")  # a missing folder: before a .zmx's catalogs are written beside it
    if ext == ".json":
        if options:
            raise ValueError(f"save: .json takes no options, got {sorted(options)}")
        save_json(lens, path)
        return [path]
    known = [p.name for p in inspect.signature(save_zmx).parameters.values()
             if p.kind is p.KEYWORD_ONLY]
    if unknown := sorted(set(options) - set(known)):
        raise ValueError(f"save: .zmx takes the options {known}, got {unknown}")
    return [path] + save_zmx(lens, path, **options)
