"""Input validation shared by the entry points: refuse bad input before any long work.

Every refusal is a ``ValueError`` that names the caller, the argument, the value, the
valid range and the unit. Inside ``jit`` a value is not known, so the same checks attach
``eqx.error_if`` to the array instead (its message names the range, not the value).

Wavelengths are in µm. A material's valid range is its catalog's (the AGF ``LD`` record,
``CatalogMaterial.wavelength_range``); other materials get ``GENERIC_RANGE_UM``, which no
optical glass model is meant for outside. Field angles are in degrees and must lie in
(−90°, 90°): a collimated beam's direction is (tan θx, tan θy, 1), which wraps at 90°.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import math
import re
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .checked_inputs import (  # noqa: F401 (re-exported)
    checked_by_caller,
    checked_core,
    inherit,
    is_traced,
    trusted_within,
)

GENERIC_RANGE_UM = (0.15, 30.0)
"""Wavelengths (µm) accepted for materials without catalog data (model glasses, formulas)."""

UNIT_TOLERANCE = 1e-4
"""Largest accepted deviation of a ray direction's length from 1."""

MAX_KERNEL_SIZE = 4096
"""Most pixels per side of a PSF grid (``psf``, ``mtf``, ``encircled_energy``, ``render``):
4096² float64 values are 128 MiB per wavelength; a kernel_size of 100001 overflowed int32
pixel indices (an ``OverflowError`` from numpy) after the lens had been checked."""

MAX_NEWTON_ITERS = 1000
"""Most Newton iterations per ray–surface intersection: Newton's method converges in a few
(the default is 6); 10**9 ran a ``fori_loop`` of that length on every aspheric surface."""

MAX_MAP_GRID = 257
"""Most points per side of a map traced at a grid of sensor points (``footprints``,
``distortion_map``, ``prewarp``, ``inverse_distortion_map``, ``psf_map``): the maps are smooth
and interpolated between their points (the defaults are 9 to 17 per side); 129 per side took
23 s on one CPU core, and 10**5 per side asked for 80 GB after the lens had been checked."""

MAX_SAMPLES = 65536
"""Most samples along one line (ray-fan pupil points, rim rays, radii or sag points per
surface, fields, points of a path): 10**9 ray-fan points asked for 24 GB after the checks."""

MAX_PUPIL_POINTS = 2**24
"""Most points one pupil sampler returns (``imaging.sampling``: n² of a grid, 3r(r+1) + 1 of
r hexapolar rings, n random points): 16.8 M points are 268 MB of float64 pairs, and a trace
of them many times that; ``pupil_hexapolar(10**6)`` asked for 48 GB."""

MAX_IMAGE_SIDE = 16384
"""Most pixels per side of a sensor, a scene or a rendered frame: the largest single image
sensors (about 150 megapixels) are some 14 200 pixels wide, and a frame of rows × cols × 3
float64 values is 6 GiB at 16384²; 10**6 per side asked for terabytes."""

MAX_SENSOR_SIZE_MM = 1000.0
"""A ``Sensor``'s longer side (resolution × pixel_size) must be at most this (mm): the largest
focal planes built (survey-telescope mosaics) are about 0.64 m across. It bounds a Sensor's own
pixel pitch to 1000 mm / its longer resolution, which refuses a pitch given in µm where mm are
meant (4000 pixels of "5" are 20 m) and leaves coarse preview grids of few large pixels (24 ×
36 mm in 2 mm pixels) alone; ``imaging.grid.pixel_pitch`` bounds PSF grids tighter (1 mm)."""

MAX_STEPS = 100_000
"""Most solver steps of one design stage (``DesignConfig.steps``, ``final_steps``,
``polish_steps``; the classical CLI's ``--polish-steps``): the defaults are 450, 1200 and 80;
10**5 fine-tuning steps of the default recipe take about a day on one CPU core, and
``--steps 1e12`` scaled every stage to 10**12 steps, which would never end."""

MAX_DESIGNS = 1024
"""Most designs (random starts) of one run of the classical CLI (``--seeds``,
``--ablation-seeds``): each is a full design, minutes of work; ``--seeds 10**12`` built a list
of 10**12 seeds (memory) before any check could see it."""

MAX_WORKING_BYTES = 16 * 2**30
"""Most estimated working memory (bytes) of one tile of a render (``render``,
``tiled.psf_points``): the rays a tile traces at once, and, for a gradient, what the backward
pass keeps of them (:func:`working_memory`). A tile of patch² × spp × 3 samples grows without
bound in patch and spp (patch 512 at spp 1024 asked for some 500 GiB); a smaller patch (or
spp) always fits."""

VALUES_PER_RAY_SURFACE = 9
"""Working memory of a traced ray's gradient, in float values per surface of the lens, on top
of ``VALUES_PER_RAY_BASE`` values. Measured with XLA's memory analysis (``temp_size_in_bytes``)
of the gradient of a render tile of 16² pixels × 16 rays × 3 colours on the CPU, float64:
657 bytes a ray for the Cooke triplet (6 surfaces), 903 for the double Gauss (11), 1132 for
the cellphone lens (13), where this model gives 688, 1048 and 1192; float32 about half."""

VALUES_PER_RAY_BASE = 32
"""See ``VALUES_PER_RAY_SURFACE``: the float values per ray that do not grow with the surfaces."""

_REL = 1e-6  # wavelength bounds are compared with this relative slack (float32 rounding)


def fmt(v) -> str:
    """A value or the first few values of an array, for messages."""
    a = np.asarray(v)
    if a.dtype.kind not in "iuf":  # None, np.True_, 5+1j, an object: as written
        return repr(v) if len(repr(v)) <= 60 else repr(v)[:57] + "..."
    if a.size == 1:
        return f"{float(a.reshape(-1)[0]):g}"
    return np.array2string(a.reshape(-1)[:8], precision=6, separator=", ") + (
        " …" if a.size > 8 else "")


def interval(lo, hi, lo_open, hi_open) -> str:
    """The interval in the notation of the messages, e.g. "(0, inf)" or "[1, 12]"."""
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    def text(v):  # whole-number bounds in full (16777216, not 1.67772e+07)
        return f"{v:d}" if isinstance(v, int) and not isinstance(v, bool) else f"{v:g}"

    low = "-inf" if lo is None else text(lo)
    high = "inf" if hi is None else text(hi)
    return f"{left}{low}, {high}{right}"


_NUMBER_TEXT = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][+-]?\d+)?", re.ASCII)
_SPECIAL_TEXT = {"inf": math.inf, "+inf": math.inf, "-inf": -math.inf, "infinity": math.inf,
                 "+infinity": math.inf, "-infinity": -math.inf, "nan": math.nan}


def number_text(token: str) -> float:
    """The number a token of a text file (``.zmx``, ``.agf``) writes: decimal digits with an
    optional point, sign and exponent (``E`` or Fortran's ``D``), or inf/infinity/nan (any
    case; the caller refuses what it cannot use). Raises ``ValueError`` otherwise: Python's
    ``float`` also reads ``"1_0"`` as 10 and other digit scripts, which no optics program
    writes (``"1_03961212"``, a garbled ``1.03961212``, became 103961212)."""
    t = token.strip()
    if t.lower() in _SPECIAL_TEXT:
        return _SPECIAL_TEXT[t.lower()]
    if not _NUMBER_TEXT.fullmatch(t):
        raise ValueError(f"not a number: {token!r}")
    return float(t.replace("D", "E").replace("d", "e"))


def cli_float(text: str) -> float:
    """An ``argparse`` type: the number of an option (:func:`number_text`; ``float`` took
    ``--fov 1_0`` as 10). Named ``float`` so argparse's message says "invalid float value"."""
    return number_text(text)


def cli_int(text: str) -> int:
    """An ``argparse`` type: a whole number written in ASCII digits (``int`` took ``1_0``)."""
    if not re.fullmatch(r"\s*[+-]?[0-9]+\s*", text, re.ASCII):
        raise ValueError(f"not a whole number: {text!r}")
    return int(text)


cli_float.__name__, cli_int.__name__ = "float", "int"


def switch(value, arg: str, where: str) -> bool:
    """A Python bool; raises ValueError otherwise: a string such as "no" is truthy, and None
    or 0 would read as False, so a switch is never guessed from another type."""
    if not isinstance(value, bool):
        raise ValueError(f"{where}: {arg} must be True or False, got {value!r}")
    return value


def number(value, arg: str, where: str, *, lo=None, hi=None, lo_open=False, hi_open=False,
           unit: str = "", integer: bool = False) -> float | int:
    """A finite number within [lo, hi] (open ends where asked); raises ValueError otherwise.

    Args:
        value: The value given.
        arg: The argument's name as the user wrote it (``"--steps"``, ``"overfill"``).
        where: The caller (``"psf"``, ``"render"``, ``"design"``).
        lo, hi: Bounds, None for unbounded.
        lo_open, hi_open: Exclude the bound itself.
        unit: Unit named in the message (``"mm"``, ``"µm"``, ``"deg"``, ``""``).
        integer: Require a whole number (bools are refused).

    Returns:
        The value as float (or int when ``integer``). A traced value (inside jit, grad or
        vmap), whose number is not known, is returned with an ``eqx.error_if`` of the same
        range (:func:`values`): use the returned value, or the check is dropped.
    """
    if is_traced(value):  # skipping it let a negative pixel_size through jit
        if integer or jnp.size(value) != 1:
            raise ValueError(f"{where}: {arg} must be one concrete "
                             f"{'whole ' if integer else ''}number, got a traced array of "
                             f"shape {jnp.shape(value)}")
        return values(value, arg, where, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open,
                      unit=unit)
    span = interval(lo, hi, lo_open, hi_open)
    kind = "a whole number" if integer else "a finite number"
    shown = repr(value) if isinstance(value, (str, bool, int, float)) else fmt(value)
    msg = f"{where}: {arg} must be {kind} in {span}{' ' + unit if unit else ''}, got {shown}"
    if isinstance(value, (bool, np.bool_, str)) or np.iscomplexobj(value):  # np.True_: 1,
        raise ValueError(msg)  # 5+1j: 5 (numpy dropped the imaginary part)
    a = np.zeros(0)  # what np.asarray cannot read is refused as not one number
    with contextlib.suppress(TypeError, ValueError):
        a = np.asarray(value, dtype=float)
    if a.size != 1:
        raise ValueError(msg)
    v = float(a.reshape(-1)[0])
    bad = not math.isfinite(v)
    bad |= lo is not None and (v <= lo if lo_open else v < lo)
    bad |= hi is not None and (v >= hi if hi_open else v > hi)
    if integer and not bad:
        bad = v != int(v) or (not isinstance(value, (int, np.integer)) and
                              not float(value).is_integer())
    if bad:
        raise ValueError(msg)
    return int(v) if integer else v


def working_memory(rays: int, surfaces: int, itemsize: int, where: str, what: str,
                   fix: str) -> int:
    """Refuse a request whose estimated working memory exceeds ``MAX_WORKING_BYTES``.

    The estimate is ``rays × itemsize × (VALUES_PER_RAY_BASE + VALUES_PER_RAY_SURFACE ×
    surfaces)`` bytes: what a gradient through the trace of ``rays`` rays at once keeps (a
    forward pass needs about a fifth of it). Static sizes only (Python ints), so it adds
    nothing to traced code. ``what`` says what the rays are (``"patch² × spp × 3 channels"``)
    and ``fix`` how to make fewer; raises ``ValueError`` naming both, the estimate and the bound
    in GiB. Returns the estimate in bytes.
    """
    per_ray = int(itemsize) * (VALUES_PER_RAY_BASE + VALUES_PER_RAY_SURFACE * int(surfaces))
    need = int(rays) * per_ray
    if need > MAX_WORKING_BYTES:
        raise ValueError(
            f"{where}: {what} = {int(rays):,} rays traced at once need about "
            f"{need / 2**30:.1f} GiB of working memory ({per_ray} bytes a ray for "
            f"{int(surfaces)} surfaces, {8 * int(itemsize)}-bit floats), more than the "
            f"{MAX_WORKING_BYTES / 2**30:g} GiB bound (checks.MAX_WORKING_BYTES); {fix}")
    return need


def newton_iters(value, where: str) -> int:
    """The ``newton_iters`` of an entry point: a whole number in [0, ``MAX_NEWTON_ITERS``]."""
    return number(value, "newton_iters", where, lo=0, hi=MAX_NEWTON_ITERS, integer=True,
                  unit="iterations")


def values(x, arg: str, where: str, *, lo=None, hi=None, lo_open=False, hi_open=False,
           unit: str = "", inf_ok: bool = False):
    """Every entry of an array within [lo, hi] (open ends where asked); returns ``x``.

    The array form of :func:`number`, for arrays of any shape (a batched lens, a list of
    wavelengths). NaN is always refused; ±inf only where ``inf_ok`` (and then only where
    the bound allows it: ``inf_ok`` with ``lo=0`` accepts +inf, not -inf). A concrete bad
    value raises ``ValueError`` naming the caller, the argument, the first bad value, the
    range and the unit; a traced array gets an ``eqx.error_if`` with the same message
    without the value.
    """
    span = interval(lo, hi, lo_open, hi_open)
    span = span[:-1] + "]" if inf_ok and hi is None else span
    u = f" {unit}" if unit else ""
    kind = "numbers" if inf_ok else "finite numbers"
    msg = (f"{where}: {arg} must be {kind} in {span}{u}" if lo is not None or hi is not None
           else f"{where}: {arg} must be {kind}{f' ({unit})' if unit else ''}")

    def bad_of(a, xp):
        bad = xp.isnan(a) if inf_ok else ~xp.isfinite(a)
        if lo is not None:
            bad = bad | ((a <= lo) if lo_open else (a < lo))
        if hi is not None:
            bad = bad | ((a >= hi) if hi_open else (a > hi))
        return bad

    if is_traced(x):
        return eqx.error_if(x, jnp.any(bad_of(jnp.asarray(x), jnp)), msg)
    try:  # strings, bools, complex as number() refuses them: "4" was read as 4.0, True 1
        if np.asarray(x).dtype.kind in "USbc":
            raise TypeError(x)
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{msg}, got {x!r}") from None
    bad = bad_of(a, np)
    if np.any(bad):
        raise ValueError(f"{msg}, got {fmt(a[bad][:1])}{u.split(' (')[0]}"
                         f"{f' (first of {int(bad.sum())} bad values)' if bad.sum() > 1 else ''}")
    return x


def real_values(x, arg: str, where: str, unit: str = "") -> None:
    """Refuse a concrete value that is not real numbers: a string (``np.asarray("10", float)``
    would read it as 10, JAX refuses it deep inside), a bool, a complex number, None or
    another object. Raises ``TypeError`` naming ``where``, ``arg`` and the unit."""
    if is_traced(x):
        return
    dt = getattr(x, "dtype", None)  # an array: no copy to the host
    if dt is None:
        try:
            dt = np.asarray(x).dtype
        except (TypeError, ValueError):
            dt = None
    if dt is None or not (np.dtype(dt).kind in "iuf" or jnp.issubdtype(dt, jnp.floating)):
        u = f" ({unit})" if unit else ""
        shown = repr(x) if len(repr(x)) <= 60 else repr(x)[:57] + "..."
        raise TypeError(f"{where}: {arg} must be a real number or an array of real "
                        f"numbers{u}, got {type(x).__name__} {shown}")


def static_int(value):
    """A field converter: a numpy integer becomes a Python int (``eqx.filter_jit`` traces a
    numpy scalar, so ``np.int64(2)`` would reach Python control flow as a tracer); anything
    else is kept for the field's own check to judge."""
    return int(value) if isinstance(value, np.integer) else value


def numpy_seed(seed, where: str, *, allow_none: bool = False) -> int | None:
    """A NumPy seed: a whole number >= 0 (None, fresh entropy, where ``allow_none``). NumPy's
    own refusal names no argument, and it takes a bool as 0 or 1."""
    if seed is None and allow_none:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"{where}: seed must be a whole number >= 0 (a NumPy seed), got "
                         f"{seed!r}")
    return int(seed)


def float_dtype(dtype, where: str, arg: str = "dtype"):
    """None or a floating dtype (float32, float64): an integer dtype would truncate
    coordinates to whole numbers; returns the dtype."""
    if dtype is None:
        return None
    try:
        dt = np.dtype(dtype)
    except TypeError:
        dt = None
    if dt is None or dt.kind != "f" or dt.itemsize < 4:
        raise ValueError(f"{where}: {arg} must be None, float32 or float64, got {dtype!r}")
    return dtype


def grid(value, where: str, arg: str = "grid", what: str = "points",
         hi: int = MAX_MAP_GRID, lo: int = 1) -> tuple[int, int]:
    """A ``(rows, cols)`` pair of whole numbers in [``lo``, ``hi``] (numpy ints allowed, bools
    and floats refused: ``linspace`` would take 2.5 as 2 and a 0 as one centre point; a huge
    one exhausted memory). ``hi``: ``MAX_MAP_GRID`` for traced maps, ``MAX_IMAGE_SIDE`` for
    pixels; ``lo=2`` for a grid that is interpolated (one point per side has nothing to
    interpolate between: it held the centre's value over the whole side)."""
    ok = (isinstance(value, (tuple, list)) and len(value) == 2 and all(
        isinstance(g, (int, np.integer)) and not isinstance(g, bool) and lo <= g <= hi
        for g in value))
    if not ok:
        why = " (an interpolated grid needs 2 points per side)" if lo == 2 else ""
        raise ValueError(f"{where}: {arg} must be (rows, cols), whole numbers >= {lo} {what} "
                         f"(at most {hi} per side){why}, got {value!r}")
    return int(value[0]), int(value[1])


def float_array(arg: str, where: str, unit: str = ""):
    """A field converter to a real floating JAX array.

    Integers become JAX's default float (an int array would truncate values and block
    ``jax.grad``); strings, bools, complex numbers, other objects and float16/bfloat16 (3.25896
    is 3.2598) raise ``TypeError`` naming ``where``, ``arg`` and the unit.
    """
    u = f" ({unit})" if unit else ""

    def convert(x):
        try:
            a = jnp.asarray(x)
        except (TypeError, ValueError):
            a = None
        if a is None or not (jnp.issubdtype(a.dtype, jnp.floating)
                             or jnp.issubdtype(a.dtype, jnp.integer)):
            shown = repr(x) if len(repr(x)) <= 60 else repr(x)[:57] + "..."
            raise TypeError(f"{where}: {arg} must be a real number or an array of real "
                            f"numbers{u}, got {type(x).__name__} {shown}")
        if jnp.issubdtype(a.dtype, jnp.floating) and jnp.finfo(a.dtype).bits < 32:  # 3.2598
            raise TypeError(f"{where}: {arg}{u} is {a.dtype.name}, which keeps too few digits "
                            f"to trace a lens; give float32 or float64 values (.astype)")
        return a if jnp.issubdtype(a.dtype, jnp.floating) else a.astype(jnp.result_type(float))

    return convert


def prng_key(key, where: str, *, optional: bool = False) -> None:
    """Refuse anything but one PRNG key: typed (``jax.random.key``) or raw uint32[2]
    (``jax.random.PRNGKey``); ``optional`` also lets None through."""
    dt = getattr(key, "dtype", None)
    if (key is None and optional) or (dt is not None and (
            (jax.dtypes.issubdtype(dt, jax.dtypes.prng_key) and jnp.shape(key) == ()) or
            (dt == jnp.uint32 and jnp.shape(key) == (2,)))):
        return
    none = "None or " if optional else ""
    raise ValueError(f"{where}: key must be {none}one PRNG key (jax.random.key(0) or "
                     f"jax.random.PRNGKey(0)), got {key!r}")


def float_field(arg: str, where: str, unit: str = "", **kwargs):
    """An ``eqx.field`` whose converter is ``float_array``: one mechanism for every numeric
    field of the lens's parts."""
    return eqx.field(converter=float_array(arg, where, unit), **kwargs)


# ---------------------------------------------------------------------------- wavelengths


class NoMaterials:
    """A stand-in lens without materials: only ``GENERIC_RANGE_UM`` applies to wavelengths."""

    object_material = None
    materials = ()


def _stated_range(material) -> tuple[float, float] | None:
    live = getattr(material, "table_range", None)  # a table's own span, if concrete
    rng = live() if callable(live) else None
    return rng if rng is not None else getattr(material, "wavelength_range", None)


def _pole_window(material) -> tuple[float, float] | None:
    """A formula's window between its resonances (``AbstractMaterial.pole_window``) where
    it narrows ``GENERIC_RANGE_UM``; None otherwise."""
    window = getattr(material, "pole_window", None)
    w = window() if callable(window) and not is_traced(material) else None
    lo, hi = GENERIC_RANGE_UM
    return w if w is not None and (w[0] > lo or w[1] < hi) else None


def material_range(material) -> tuple[float, float]:
    """Wavelength range (µm) over which a material's data holds: a catalog's or a table's
    stated range; for a formula without one (a ``Sellmeier`` built from coefficients),
    ``GENERIC_RANGE_UM`` narrowed to the window between its poles that holds the d line, less
    2·_REL (the checks' slack crossed a pole: at 2.0000001 µm past one at 2 µm, n = 3162)."""
    rng = _stated_range(material)
    if rng is not None:
        return float(rng[0]), float(rng[1])
    lo, hi = GENERIC_RANGE_UM
    w = _pole_window(material)
    return (max(lo, w[0] * (1 + 2 * _REL)), min(hi, w[1] * (1 - 2 * _REL))) if w else (lo, hi)


def range_reason(material, what: str) -> str:
    """Why :func:`material_range` is what it is, naming the material."""
    label = _label(material, what).strip()
    if _stated_range(material) is None and _pole_window(material) is not None:
        lo, hi = _pole_window(material)
        ends = " and ".join(f"{v:.4g} µm" for v in (lo, hi) if 0 < v < math.inf)
        return (f"the range of {label} between the resonances (poles) of its "
                f"{type(material).__name__} formula at {ends}, beyond which the formula gives "
                f"no index of the material (a CatalogMaterial with a wavelength_range states "
                f"another)")
    return f"the data range of {label}"


def _label(material, what: str) -> str:
    name = getattr(material, "name", "") or type(material).__name__
    cat = getattr(material, "catalog", "")
    return f"{name}{f' ({cat})' if cat else ''} {what}"


def _lens_materials(lens) -> list[tuple[object, str]]:
    out = [(lens.object_material, "in object space")]
    out += [(m, f"after surface {i + 1}") for i, m in enumerate(lens.materials)]
    return out


def wavelength_range(lens) -> tuple[float, float, str]:
    """(lo, hi, reason): the wavelengths (µm) every material of the lens has data for."""
    lo, hi = GENERIC_RANGE_UM
    why_lo = why_hi = "jaxlens's range for materials without catalog data"
    for m, what in _lens_materials(lens):
        if m is None or type(m).__name__ == "Air":
            continue
        a, b = material_range(m)
        if a > lo:
            lo, why_lo = a, range_reason(m, what)
        if b < hi:
            hi, why_hi = b, range_reason(m, what)
    reason = why_lo if why_lo == why_hi else f"{why_lo}; {why_hi}"
    return lo, hi, reason


def _nm_hint(wl) -> str:
    a = np.abs(np.asarray(wl, dtype=float).reshape(-1))
    big = a[np.isfinite(a) & (a > 100)]
    if big.size:
        v = float(big[0])
        return f" (wavelengths are in µm: {v:g} nm is {v / 1000:g} µm)"
    small = a[np.isfinite(a) & (a > 0) & (a < 0.01)]
    if small.size:
        v = float(small[0]) * 1000
        return f" (that is {v:g} nm: were µm given where nm are expected?)"
    return " (wavelengths are in µm)"


def wavelength_unit(wl, where: str, arg: str = "wavelength") -> None:
    """Refuse a concrete wavelength that is not a positive number below 100 µm: a value in nm
    (or not a wavelength at all). Traced values pass; ``wavelengths`` checks ranges."""
    if is_traced(wl) or type(wl) in (int, float) and 0 < wl < 100:  # not bools
        return
    real_values(wl, arg, where, "µm")
    a = np.asarray(wl, dtype=float)
    bad = ~np.isfinite(a) | (a <= 0) | (a >= 100)
    if np.any(bad):
        raise ValueError(f"{where}: {arg} {fmt(a[bad])} µm is not a wavelength in µm (0 to "
                         f"100 µm){_nm_hint(a[bad])}")


def _outside(wl, lo: float, hi: float):
    """Concrete wavelengths as a float array, and where they are not finite or fall outside
    [lo, hi] µm (with the relative slack of catalog ranges)."""
    a = np.asarray(wl, dtype=float)
    return a, ~np.isfinite(a) | (a < lo * (1 - _REL)) | (a > hi * (1 + _REL))


def wavelengths(lens, wl, where: str, arg: str = "wavelength"):
    """Check wavelengths (µm) against the lens's materials; returns ``wl``.

    A concrete value out of range raises ``ValueError`` at once; a traced one gets an
    ``eqx.error_if`` that fires when the computation runs.
    """
    real_values(wl, arg, where, "µm")
    lo, hi, why = wavelength_range(lens)
    if is_traced(wl):
        if checked_by_caller(wl):
            return wl
        w = jnp.asarray(wl)
        bad = ~jnp.isfinite(w) | (w < lo * (1 - _REL)) | (w > hi * (1 + _REL))
        return eqx.error_if(
            wl, jnp.any(bad),
            f"{where}: {arg} outside {lo:g}–{hi:g} µm, {why}; wavelengths are in µm "
            f"(587.6 nm is 0.5876 µm)")
    a, bad = _outside(wl, lo, hi)
    if np.any(bad):
        raise ValueError(
            f"{where}: {arg} {fmt(a[bad])} µm is outside {lo:g}–{hi:g} µm, {why}"
            f"{_nm_hint(a[bad])}")
    return wl


def primary_wavelength(lens, where: str, role: str = "") -> None:
    """Check a concrete lens's primary wavelength (µm) against its materials, for an entry
    point given other wavelengths whose compiled core also traces the primary one (the chief
    ray); ``role`` says what for (``"the chief ray's"``)."""
    if not is_traced(lens.wavelengths):
        wavelengths(lens, lens.primary_wavelength, where,
                    f"the lens's primary wavelength{f' ({role})' if role else ''}")


def material_wavelengths(m, wl, where: str, arg: str = "wavelength", hint: str = "") -> None:
    """Refuse concrete wavelengths (µm) outside one material's data range
    (:func:`material_range`), as :func:`wavelengths` does for a lens's materials. Traced
    values pass (the entry points check them before tracing)."""
    if is_traced(wl) or is_traced(m):
        return
    lo, hi = material_range(m)
    a, bad = _outside(wl, lo, hi)
    if np.any(bad):
        raise ValueError(
            f"{where}: {arg} {fmt(a[bad])} µm is outside {lo:g}–{hi:g} µm, "
            f"{range_reason(m, '')}{_nm_hint(a[bad])}{hint}")


def lens_intact(lens, where: str) -> None:
    """Re-run a concrete lens's own constructor checks, and those of its surfaces.

    ``eqx.tree_at`` (and ``jax.tree.map``) build a new lens without ``Lens.__init__``, so an
    edited lens can hold a NaN curvature, an infinite conic, a negative semi-diameter or
    EPD, a field of 95° or a thickness array of the wrong length: the analyses then gave
    NaN, a PSF of one bright pixel, or a shape error from deep inside ``lax.scan``. The
    surfaces (and the image surface) and the sensor are checked too. A
    ``ValueError`` (``TypeError`` for a wrong type) names ``where`` and the bad value. A
    traced lens (inside jit, grad or vmap) is not checked: its numbers are not known, and the
    entry points check the lens before they trace it. About 3 ms for a six-surface lens.
    """
    if is_traced(lens) or not callable(getattr(lens, "__check_init__", None)):
        return
    parts = [(lens, "")]
    surfaces = getattr(lens, "surfaces", ())
    parts += [(s, f"surfaces[{i}]: ") for i, s in enumerate(surfaces)]
    for arg in ("image", "sensor"):  # render reads the sensor's pixel size
        part = getattr(lens, arg, None)
        parts += [(part, f"{arg}: ")] if part is not None else []
    for part, label in parts:
        if not dataclasses.is_dataclass(part):
            continue
        try:
            # A copy through the constructor: its converters first (an edit may hold a Python
            # float where the checks expect an array, as ``tree_at(..., object_distance,
            # 300.0)`` does), then its checks.
            dataclasses.replace(part)
        except (ValueError, TypeError) as e:
            raise type(e)(f"{where}: the lens fails its own checks, {label}{e} (a lens edited "
                          f"with eqx.tree_at skips them: build it with Lens(...) or "
                          f"dataclasses.replace to have them run)") from None


def material_indices(lens, wl, where: str, arg: str = "wavelength", *,
                     intact: bool = False) -> None:
    """Refuse materials whose index at the (concrete) wavelengths is not finite or below 1,
    after the lens's own checks (:func:`lens_intact`: an analysis's input checks are the
    one place a lens edited with ``eqx.tree_at`` is seen before it is traced; ``intact``:
    the caller has run them)."""
    if is_traced(wl) or is_traced(lens):
        return
    if not intact:
        lens_intact(lens, where)
    w = np.atleast_1d(np.asarray(wl, dtype=float))
    for m, what in _lens_materials(lens):
        material(m, w, f"{where}: {_label(m, what)}", arg=arg)


def material(m, wl, where: str, arg: str = "wavelength") -> None:
    """Refuse a material whose index at the wavelengths (µm) is NaN, infinite or below 1."""
    if is_traced(m) or is_traced(wl):
        return
    w = np.atleast_1d(np.asarray(wl, dtype=float))
    # Only where the material has data: a wavelength outside its range is the range checks'
    # to refuse (``wavelengths``: they name the surface), and its formula may raise there.
    w = w[~_outside(w, *material_range(m))[1]]
    if not w.size:
        return
    # Evaluated now even inside a jit trace (a concrete lens closed over by a jitted function):
    # there m.index gave a tracer, and np.asarray a TracerArrayConversionError.
    with jax.ensure_compile_time_eval():
        n = np.asarray(m.index(jnp.asarray(w)), dtype=float)
    bad = ~np.isfinite(n) | (n < 1.0 - 1e-9)
    if np.any(bad):
        raise ValueError(
            f"{where}: refractive index {fmt(n[bad])} at {arg} {fmt(w[bad])} µm; a material "
            f"needs a finite index >= 1 (check its dispersion coefficients or nd)")


# ---------------------------------------------------------------------------- rays and fields


def field_angles(field, where: str, arg: str = "field"):
    """Field angles (degrees) must be finite and inside (−90°, 90°); returns ``field``."""
    msg = f"{where}: {arg} must be finite angles in (-90, 90) deg"
    real_values(field, arg, where, "deg")
    if is_traced(field):
        if checked_by_caller(field):
            return field
        f = jnp.asarray(field)
        return eqx.error_if(field, jnp.any(~(jnp.abs(f) < 90.0)), msg)
    a = np.asarray(field, dtype=float)
    bad = ~(np.abs(a) < 90.0)
    if np.any(bad):
        raise ValueError(f"{msg}, got {fmt(a[bad])} deg (tan θ wraps at 90°: 120° would "
                         f"be traced as -60°)")
    return field


RADIAN_FIELD_TOL = 1e-4
"""A set of field angles (degrees) whose nonzero values all lie within this (in radians) of
whole degrees written in radians, the largest at least ``RADIAN_FIELD_MIN_DEG``, is warned
about as fields given in radians (``np.radians([0, 10, 20])`` traced as 0.17° and 0.35°)."""
RADIAN_FIELD_MIN_DEG = 5


_FIELDS_WARNED_BY = contextvars.ContextVar("jaxlens_fields_warned_by", default=None)


@contextlib.contextmanager
def fields_warned_by(where: str):
    """Within it, :func:`warn_if_radian_fields` is quiet: ``where``, the function the user
    called, has warned about its fields already, and the analyses it calls with the same
    fields would each warn again under their own names (``spot_rays`` for
    ``encircled_energy``)."""
    token = _FIELDS_WARNED_BY.set(where)
    try:
        yield
    finally:
        _FIELDS_WARNED_BY.reset(token)


def warn_if_radian_fields(fields, where: str, arg: str = "fields") -> None:
    """Warn when concrete field angles look like radians (see ``RADIAN_FIELD_TOL``): a
    warning, not a refusal, since 0.1745° may be meant. Traced angles pass, and so do
    fields inside :func:`fields_warned_by` (the caller has warned)."""
    if is_traced(fields) or _FIELDS_WARNED_BY.get() is not None:
        return
    a = np.abs(np.asarray(fields, dtype=float)).ravel()
    a = a[a > 0]
    if a.size == 0 or a.max() >= math.pi / 2:
        return
    whole = np.round(np.degrees(a))
    if whole.max() < RADIAN_FIELD_MIN_DEG or np.any(whole < 1) or \
            np.any(np.abs(a - np.radians(whole)) >= RADIAN_FIELD_TOL):
        return
    meant = np.round(np.degrees(np.asarray(fields, dtype=float)), 2)
    warnings.warn(f"{where}: {arg} {fmt(np.asarray(fields))} look like angles in radians "
                  f"({fmt(meant)} deg); field angles are in degrees, so these trace as "
                  f"fields of at most {a.max():.4g} deg", stacklevel=2)


def one_field(field, where: str, hint: str = "analyse several fields one at a time"):
    """One field θy or (θx, θy) in degrees, checked (real, finite, inside (−90°, 90°)) before
    any tracing; a ``[1]`` array is θy. A list of fields would otherwise be broadcast against
    the pupil points (a shape error deep in JAX, or a wrong pairing). Returns the field with
    shape ``()`` or ``(2,)``."""
    real_values(field, "field", where, "deg")  # before jnp.asarray ("5" is not 5°)
    shape = np.shape(field)
    if shape not in ((), (1,), (2,)):
        raise ValueError(f"{where}: field must be one field, θy or (θx, θy) in degrees, got "
                         f"shape {shape} ({hint})")
    field = field_angles(field, where, "field")
    return jnp.reshape(jnp.asarray(field), ()) if shape == (1,) else field


def unit_directions(direction, valid, where: str = "Rays") -> None:
    """Refuse (concrete) ray directions that are not unit vectors."""
    if is_traced(direction) or is_traced(valid):
        return
    d = np.asarray(direction, dtype=float)
    if d.size == 0:
        return
    norm = np.sqrt(np.sum(d * d, axis=-1))
    v = np.broadcast_to(np.asarray(valid, bool), norm.shape)
    bad = v & ~(np.abs(norm - 1.0) <= UNIT_TOLERANCE)
    if np.any(bad):
        raise ValueError(
            f"{where}: direction must hold unit vectors (length 1 ± {UNIT_TOLERANCE:g}), got "
            f"length {fmt(norm[bad][:1])} for {int(bad.sum())} ray(s); normalise with "
            f"d / jnp.linalg.norm(d, axis=-1, keepdims=True)")


def finite_array(x, arg: str, where: str, unit: str = ""):
    """Refuse NaN or infinite entries (ValueError, or ``eqx.error_if`` under jit)."""
    u = f" ({unit})" if unit else ""
    if is_traced(x):
        if checked_by_caller(x):
            return x
        return eqx.error_if(x, jnp.any(~jnp.isfinite(x)), f"{where}: {arg}{u} holds NaN or inf")
    a = np.asarray(x)
    bad = ~np.isfinite(a)
    if np.any(bad):
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{where}: {arg}{u} holds {int(bad.sum())} NaN or infinite value(s), "
                         f"first at index {first}: {a[first]!r}; every value must be finite")
    return x


def image_dtype(img, where: str, arg: str = "img", unit: str = "") -> None:
    """Refuse an image array of integer dtype (uint8, uint16: sRGB codes, which as linear
    values were clipped to white or truncated the answer to whole numbers) with a hint to
    ``jaxlens.io.images.to_linear``, and a bool, complex, string or object one; Python
    numbers and lists of them pass. Static (the dtype only), so traced images too."""
    what = f" ({unit})" if unit else ""
    dt = getattr(img, "dtype", None)
    try:
        kind = np.dtype(dt).kind if dt is not None else np.asarray(img).dtype.kind
    except (TypeError, ValueError):
        kind = "O"
    if dt is not None and kind in "iu":
        raise ValueError(f"{where}: {arg} must be a float image{what}, got an integer image "
                         f"of dtype {np.dtype(dt)} (sRGB codes 0…{np.iinfo(np.dtype(dt)).max}"
                         f"?); decode it with jaxlens.io.images.to_linear, or divide by "
                         f"{np.iinfo(np.dtype(dt)).max} for the encoded values")
    if kind not in "iuf" and not (dt is not None and jnp.issubdtype(dt, jnp.floating)):
        raise ValueError(f"{where}: {arg} must be a float image{what}, got dtype "
                         f"{np.dtype(dt) if dt is not None else type(img).__name__}")


def float_image(img, where: str, arg: str = "img", *, lo=None, hi=None,
                unit: str = "", hint: str = "") -> np.ndarray:
    """An image of real float values as a float64 numpy array; raises ``ValueError``.

    An integer image array (uint8, uint16: 0…255 or 0…65535 sRGB codes) is refused with a
    hint to ``jaxlens.io.images.to_linear``: as values in [0, 1] a uint8 image was clipped
    to white, or raised to the power 2.4 (255 became 5.9e5). Bool, complex (numpy dropped
    the imaginary part with a warning), string or object arrays are refused too, and so
    are NaN, ±inf and, where ``lo``/``hi`` are given, values outside [lo, hi]. Python
    numbers and lists of them are read as floats. ``hint`` ends the message of a bad value.
    """
    what = f" ({unit})" if unit else ""
    image_dtype(img, where, arg, unit)
    a = np.asarray(img, np.float64)
    bad = ~np.isfinite(a)
    bad |= (a < lo) if lo is not None else False
    bad |= (a > hi) if hi is not None else False
    if np.any(bad):
        span = f" in {interval(lo, hi, False, False)}" if lo is not None or hi is not None else ""
        raise ValueError(f"{where}: {arg} must be finite values{span}{what}, got "
                         f"{fmt(a[bad][:1])} ({int(bad.sum())} bad of {a.size}){hint}")
    return a


def focal_image(lens, where: str) -> None:
    """Refuse a lens with an afocal image space (``Lens.afocal_image``) where the answer is a
    position on the image surface (mm): its image is at infinity, so those positions depend
    only on where the image surface happens to be and describe nothing."""
    if getattr(lens, "afocal_image", False):
        raise ValueError(
            f"{where}: the lens has an afocal image space (Lens.afocal_image; Zemax FTYP's "
            f"'afocal image space'): it images to infinity, so positions on its image "
            f"surface (mm) describe nothing. Use jaxlens.analysis.angular_spot (angular spot "
            f"sizes), angular_magnification, or wavefront (referenced to a plane), or pass "
            f"dataclasses.replace(lens, afocal_image=False) to measure at the image surface")
