"""Numbers and strings of a JSON lens file: what ``json`` gives, read strictly.

JSON has no infinity, so the strings "inf", "-inf" and "infinity" stand for it; a bool, a
null or any other string (a number in quotes, "5", included) is refused, naming where in
the file it is. Also the
reader's refusal of a key given twice (``unique_keys``), the writer's layout (``pretty``)
and its whole-file write (``write_whole``, also the ``.zmx`` writer's).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from decimal import Decimal
from typing import Any

import jax.numpy as jnp
import numpy as np

from ..optics import checks
from ..optics.lens import Lens
from ..optics.reciprocal import reciprocal_length

INFINITY_TEXT = {"inf": math.inf, "+inf": math.inf, "infinity": math.inf,
                 "+infinity": math.inf, "-inf": -math.inf, "-infinity": -math.inf}
"""The strings that stand for an infinity (case and surrounding spaces ignored): the only
numbers a JSON lens file may give as strings (docs/lens-format.md)."""


def num(value: Any, where: str, *, finite: bool = True, text_ok: bool = False) -> float:
    """A float from a JSON number or the strings "inf"/"-inf"/"infinity". A number written
    as a string ("5") is refused: the format documents none (a quoted number is a file
    written by hand or by another program, and "5" beside a number 5 was read alike without
    a word). ``text_ok``: a decimal string is the value (an object's keys, which JSON
    makes strings: the ``n`` table's wavelengths)."""
    if isinstance(value, bool) or value is None:
        raise ValueError(f"{where}: expected a number, got {value!r}")
    if isinstance(value, str):
        s = value.strip().lower()
        if s in INFINITY_TEXT:
            v = INFINITY_TEXT[s]
        else:
            try:  # not float(): "1_0" would be 10, "٣" 3
                v = checks.number_text(s)
            except ValueError:
                raise ValueError(f"{where}: expected a number, got {value!r}") from None
            if not text_ok and not math.isnan(v):  # "nan": refused below as not finite
                raise ValueError(f"{where}: expected a number, got the string {value!r}; "
                                 f"write numbers without quotes (only \"inf\", \"-inf\" "
                                 f"and \"infinity\" are strings)")
    elif isinstance(value, int | float):
        try:
            v = float(value)
        except OverflowError:  # an integer of 400 digits
            raise ValueError(f"{where}: expected a finite number, got an integer of "
                             f"{len(str(abs(value)))} digits") from None
    else:
        raise ValueError(f"{where}: expected a number, got {value!r}")
    if math.isnan(v) or (finite and math.isinf(v)):
        raise ValueError(f"{where}: expected a finite number, got {value!r}")
    return v


def whole(value: Any) -> int:
    """A whole JSON number (``8`` or ``8.0``); ``2.5``, ``true`` and strings are refused."""
    if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value):
        raise ValueError(f"not a whole number: {value!r}")
    return int(value)


def text(value: Any, where: str) -> str:
    if not isinstance(value, str):
        raise ValueError(f"{where}: expected a string, got {value!r}")
    return value


def nums(value: Any, where: str, *, finite: bool = True) -> np.ndarray:
    """A float64 array from a (nested) JSON list of numbers."""
    if isinstance(value, list | tuple):
        out = [nums(v, f"{where}[{i}]", finite=finite) for i, v in enumerate(value)]
        if not out:
            return np.zeros((0,), np.float64)
        try:
            return np.stack(out)
        except ValueError:
            raise ValueError(f"{where}: ragged list {value!r}") from None
    return np.asarray(num(value, where, finite=finite), np.float64)


def nm_to_um(nm) -> np.ndarray:
    """Wavelengths in nm to µm, as the double nearest to the decimal value / 1000.

    ``587.5618`` nm gives exactly the float ``0.5875618`` (not ``587.5618 / 1000``, which
    is one ulp off), so files in nm and in µm describe the same wavelengths.
    """
    a = np.asarray(nm, np.float64)
    flat = [
        float(Decimal(repr(float(v))) / 1000) if math.isfinite(v) else v / 1000
        for v in a.reshape(-1)
    ]
    return np.array(flat, np.float64).reshape(a.shape)


def float64_array(x) -> jnp.ndarray:
    """A float64 JAX array of ``x`` (numbers read from a file)."""
    return jnp.asarray(np.asarray(x, np.float64))


def json_number(x) -> Any:
    """JSON value of an array or scalar: exact floats, "inf"/"-inf" for infinities."""
    a = np.asarray(x)
    if a.ndim == 0:
        v = float(a)
        if math.isnan(v):
            raise ValueError("save: cannot write NaN to a lens file")
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    return [json_number(v) for v in a]


def curvature(d: dict, where: str, suffix: str = "") -> float:
    """The curvature from ``curvature`` or ``radius`` (``curvature_x``/``radius_x`` with
    ``suffix="_x"``, a biconic's x section)."""
    ck, rk = f"curvature{suffix}", f"radius{suffix}"
    for key in (ck, rk):
        if key in d and d[key] is None:  # null was read as absent: a flat surface
            raise ValueError(f"{where}: {key} is null; give a number (a flat surface: "
                             f"{ck} 0 or {rk} \"inf\")")
    c = d.get(ck)
    r = d.get(rk)
    if c is not None:
        cv = num(c, f"{where}: {ck}")
        if r is not None:
            rv = _radius(r, rk, where, ck)
            cr = 0.0 if math.isinf(rv) else 1.0 / rv
            if not math.isclose(cr, cv, rel_tol=1e-9, abs_tol=1e-15):
                raise ValueError(f"{where}: {rk} {r!r} and {ck} {c!r} disagree")
        return cv
    if r is not None:
        rv = _radius(r, rk, where, ck)
        return 0.0 if math.isinf(rv) else 1.0 / rv
    return 0.0


def _radius(r, rk: str, where: str, ck: str) -> float:
    """A radius of curvature (mm; ±inf flat), refused where it is no surface's: 0 (or -0.0),
    or below ``reciprocal.MIN_LENGTH_MM`` in size (5e-324 gave a curvature of inf, refused
    as ``c``, a key the file does not hold; 1e-300 one of 1e300 per mm)."""
    rv = num(r, f"{where}: {rk}", finite=False)
    if rv == 0:
        raise ValueError(f"{where}: {rk} 0 is not a surface; use {ck} 0 for flat")
    if not math.isinf(rv):
        reciprocal_length(rv, rk, where)
    return rv


class RepeatedKey(ValueError):
    """A key given twice in one JSON object (``unique_keys``)."""


def unique_keys(pairs: list) -> dict:
    """An object's pairs as a dict; a repeated key is refused (``json`` keeps the last
    value without a word, so ``"thickness": 3, "thickness": 30`` read as 30)."""
    d: dict = {}
    for k, v in pairs:
        if k in d:
            raise RepeatedKey(f"key {k!r} appears twice in one object ({d[k]!r} and {v!r}); "
                              f"keep one")
        d[k] = v
    return d


def pretty(o: Any, level: int = 0) -> str:
    """JSON text with short objects and number lists on one line."""
    flat = json.dumps(o, ensure_ascii=False, allow_nan=False)
    if not isinstance(o, dict | list) or len(flat) + 2 * level <= 96:
        return flat
    if isinstance(o, list) and not any(isinstance(x, dict | list) for x in o):
        return flat
    pad, inner = "  " * level, "  " * (level + 1)
    if isinstance(o, dict):
        body = [
            f"{inner}{json.dumps(k, ensure_ascii=False)}: {pretty(v, level + 1)}"
            for k, v in o.items()
        ]
        return "{\n" + ",\n".join(body) + "\n" + pad + "}"
    body = [f"{inner}{pretty(v, level + 1)}" for v in o]
    return "[\n" + ",\n".join(body) + "\n" + pad + "]"


class MissingFolderError(FileNotFoundError, ValueError):
    """A file to write whose folder does not exist: the one refusal every writer of jaxlens
    gives (``save``, ``save_json``, ``save_zmx``, ``plot.save``, the image writers; no writer
    creates folders). It is both a ``FileNotFoundError`` and a ``ValueError``, so either
    ``except`` catches it: ``save`` raised ``FileNotFoundError`` and the others
    ``ValueError`` for the same mistake."""


def output_file(path: str | os.PathLike, where: str, suffix: str | None = None) -> str:
    """``path`` as a file to write: not a folder, in a folder that exists, and ending in
    ``suffix`` (any case) where one is given, so that the bytes match the name (``save_zmx``
    wrote Zemax text into ``lens.json``, ``save_json`` JSON into ``lens.zmx``). Raises
    ``ValueError`` naming ``where`` and the path (``MissingFolderError``, also a
    ``FileNotFoundError``, for a missing folder; ``TypeError`` for None); a writer that
    writes through a temporary file beside its target failed with ``IsADirectoryError`` or a
    ``FileNotFoundError`` naming that temporary file (``.lens.json.123.partial``)."""
    if not isinstance(path, str | bytes | os.PathLike):  # None: os.fspath's bare TypeError
        raise TypeError(f"{where}: path must be a file name (a str or os.PathLike), got "
                        f"{type(path).__name__} {path!r}")
    p = os.fspath(path)
    ext = os.path.splitext(p)[1]
    if os.path.isdir(p):
        raise ValueError(f"{where}: {p!r} is a folder, not a file")
    if suffix is not None and ext.lower() != suffix:
        raise ValueError(f"{where}: writes {suffix[1:].upper()} files; the path must end in "
                         f"{suffix}, got {p!r}")
    folder = os.path.dirname(os.path.abspath(p))
    if not os.path.isdir(folder):
        raise MissingFolderError(f"{where}: no such folder {folder!r} to write "
                                 f"{os.path.basename(p)!r} in (the folder does not exist; "
                                 f"{where} creates no folders)")
    return p


def write_whole(path: str | os.PathLike, text: str | bytes, *,
                newline: str | None = None, where: str = "write") -> None:
    """Write ``text`` (UTF-8; ``bytes`` as they are, an ``.npz`` say) to ``path`` whole or
    not at all: into a temporary file beside it, renamed over ``path`` when complete. A save
    interrupted mid-write (Ctrl-C) left a file cut short, which destroyed the lens it
    replaced, and a ``.zmx`` cut at a surface's end read as a shorter lens; a results file
    (a benchmark's, a reference tool's) cut short failed the run or test reading it.
    ``path`` is checked first (``output_file``, any suffix; ``where`` names the caller)."""
    folder, name = os.path.split(os.path.abspath(output_file(path, where)))
    tmp = os.path.join(folder, f".{name}.{os.getpid()}.partial")
    try:
        if isinstance(text, bytes):
            with open(tmp, "wb") as f:
                f.write(text)
        else:
            with open(tmp, "w", encoding="utf-8", newline=newline) as f:
                f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


@contextlib.contextmanager
def whole_path(path: str | os.PathLike, where: str = "write"):
    """A temporary path beside ``path`` (same extension) for a writer that takes a path (a
    figure's ``savefig``, OpenEXR), renamed over ``path`` when the block ends without an
    error, removed when it does not: the file is written whole or not at all, as
    ``write_whole`` writes text (in place, a stop mid-write left a cut file where the
    earlier one was). ``path`` is checked first (``output_file``)."""
    folder, name = os.path.split(os.path.abspath(output_file(path, where)))
    tmp = os.path.join(folder, f".{name}.{os.getpid()}.partial{os.path.splitext(name)[1]}")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def loadable(lens, where: str) -> None:
    """Refuse a lens that ``load`` would refuse (a lens edited with ``eqx.tree_at`` skips
    ``Lens``'s own checks): a field of 95°, wavelengths beyond a glass's data, a primary
    index past the wavelengths. Else a writer (``where``: ``save``, ``save_json``,
    ``save_zmx``, the ``dumps``) would write a file that does not read back, or fail inside
    (a wavelength past a glass's resonance was refused by ``Sellmeier.index``)."""
    if not isinstance(lens, Lens):  # else an AttributeError from deep in the writer
        raise TypeError(f"{where}: lens must be a jaxlens Lens, got {type(lens).__name__}")
    if checks.is_traced(lens):
        return
    try:
        lens.__check_init__()
        checks.wavelengths(lens, lens.wavelengths, "Lens", "wavelengths")
        checks.material_indices(lens, lens.wavelengths, "Lens", "wavelengths")
    except ValueError as e:
        raise ValueError(f"{where}: {e}; nothing written (load would refuse the file)") from None
