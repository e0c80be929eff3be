"""Design specifications for ab initio lens design, checked before any compute.

Conventions (the paper's, Yang, Fu & Heidrich, Nat. Commun. 15, 6572 (2024)):
    A lens is specified by its diagonal field of view ``fov`` (degrees, full angle), its
    F-number and its sensor diagonal (mm). The focal length is defined from the field and the
    sensor, ``f = (sensor_diagonal / 2) / tan(fov / 2)``, and the entrance pupil diameter is
    ``epd = f / fnum``. Distortion is then free to move the paraxial EFL away from ``f``; the
    design reports the paraxial EFL and F-number beside these nominal values.

    Lengths are in mm. ``total_track`` is the distance from the first surface vertex (the stop
    when the stop comes first) to the sensor and is held fixed during design; ``bfl`` is the
    smallest allowed clearance between the last lens surface and the sensor (it also sets the
    back gap of the random starts). ``stop`` is the number of elements in front of the
    aperture stop (0: stop first).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import types

import jax
import numpy as np

from ..optics import checks
from ..optics.materials import (
    LAMBDA_C,
    LAMBDA_D,
    LAMBDA_F,
    AbstractMaterial,
    Air,
    ModelGlass,
)

# Stand-in (nd, Vd) of common lens plastics, used only if ``jaxlens.optics.catalog`` is unavailable.
_PLASTICS = {
    "E48R": (1.5312, 56.0),
    "OKP4": (1.607, 27.0),
    "OKP4HT": (1.632, 23.0),
    "PMMA": (1.4917, 57.4),
    "POLYCARB": (1.585, 29.9),
    "PC": (1.585, 29.9),
    "POLYSTYR": (1.5905, 30.9),
    "COC": (1.5337, 56.2),
}

# Thickness bounds of the paper's spacing regularizer (mm): within an element (centre and
# edge thickness) and between neighbouring elements (air gaps).
ELEMENT_MIN_THICKNESS = 0.4
AIR_MIN_GAP = 0.2
MIN_BFL = 0.01
"""Smallest back clearance (mm) a ``DesignSpec`` takes: below 10 µm it is a length in m."""

TRACK_PER_FOCAL = (0.1, 100.0)
"""Accepted range of total_track over the focal length (and over ``efl`` when set): refractive
lenses lie far inside it (telephotos near 0.6, fisheye retrofocus designs near 20), so a spec
outside it has lengths in different units (a sensor diagonal in µm, a track in m) or a field
near 0° whose focal length no track can hold."""

FNUM_RANGE = (0.5, 64.0)
"""Accepted F-numbers (``fnum`` and ``fnum_start``; also the CLI's ``--fnum``): F/0.5 is the
aplanatic limit NA = 1 in air (``aperture_field_limits`` narrows the fast end with the
element count); beyond F/64 (the slowest stop camera lenses mark) the Airy disk
2.44·λ·N is over 90 µm at 0.59 µm, many pixels of any sensor, so the image is set by
diffraction whatever the lens and the geometric losses the design minimizes mean nothing
(``--fnum 1e300`` designed an EPD of 1e-300 mm without a word)."""

SENSOR_DIAGONAL_RANGE = (0.1, 1000.0)
"""Accepted sensor diagonals (mm): from a few pixels of the smallest camera module to 1 m
(8×10-inch film is 325 mm); outside it the diagonal is in another unit (µm, m)."""

MAX_TRACK = 10000.0
"""Longest total_track a ``DesignSpec`` takes (mm): 10 m, longer than any refractive camera
lens; a longer one is a length in µm (``TRACK_PER_FOCAL`` then bounds the focal length)."""

MAX_ELEMENTS = 30
"""Most lens elements a ``DesignSpec`` takes (also the CLI's ``--elements``): more than any
camera lens holds (zooms reach about 25); each element adds two surfaces to every trace."""

MAX_SENSOR_PIXELS = 8192
"""Most pixels along the sensor's longer side (``sensor_pixels``, the rendered scene's size):
an 8192² RGB image in float32 is 0.8 GB."""

MAX_ASPHERE_TERMS = 12
"""Most even aspheric terms per surface (r⁴ … r²⁶), the CLI's ``--asphere-terms`` bound: more
than lens designs use, and the parameterization's scale r_norm^(2j+3) of term j stays
inside float32's range up to a full-frame half-diagonal (21.6 mm; 1000 terms overflow even
float64)."""


def get_material(name: str) -> AbstractMaterial:
    """A lens material by catalog name (``jaxlens.optics.catalog``), or a model-glass stand-in."""
    try:
        from ..optics.catalog import get_material as _catalog_get
    except ImportError:  # pragma: no cover - the catalog ships with jaxlens
        _catalog_get = None
    if _catalog_get is not None:
        return _catalog_get(name)
    key = name.upper()
    if key not in _PLASTICS:
        raise ValueError(f"get_material: unknown material {name!r}; known: {sorted(_PLASTICS)}")
    nd, vd = _PLASTICS[key]
    return ModelGlass(nd, vd, name=key)


def aperture_field_limits(n_elements: int) -> tuple[float, float]:
    """The fastest F-number and the largest aperture–field product an N-element lens reaches.

    A conservative screen, not a design rule: it rejects specs that no lens with this many
    elements has been shown to reach, so that an impossible request fails before any compute.
    The limits follow the classical lens types (Smith, *Modern Lens Design*, ch. 1 charts of
    field against aperture): a singlet reaches about F/4 with tan(half field)/F# ≈ 0.1
    (a landscape lens), a triplet about F/1.4 to F/2 and a six-element lens F/1 (the double
    Gauss family) and 80–100° fields at F/2 (mobile-phone 6P lenses, tan/F# ≈ 0.6). The
    returned values are ``(min_fnum, max_tan_over_fnum)`` with
    ``min_fnum = max(0.5, 4 / n)`` (F/0.5 is the aplanatic limit NA = 1 in air) and
    ``max_tan_over_fnum = 0.12 · n``.

    Args:
        n_elements: number of lens elements (≥ 1).

    Returns:
        ``(min_fnum, max_tan_over_fnum)``.
    """
    # 0 was a ZeroDivisionError, -2 an F/0.5 limit and a negative field product.
    n_elements = checks.number(n_elements, "n_elements", "aperture_field_limits", lo=1,
                               integer=True, unit="lens elements")
    return max(0.5, 4.0 / n_elements), 0.12 * n_elements


FOV_START, FNUM_START = 47.5, 2.8
"""The paper's curriculum start: full diagonal FoV (deg) and F-number."""


@dataclasses.dataclass(frozen=True)
class DesignSpec:
    """What to design: field, aperture, sensor, element count, materials and packaging.

    Args:
        fov: full diagonal field of view in degrees.
        fnum: F-number in the paper's convention (``epd = f / fnum``).
        sensor_diagonal: sensor diagonal in mm.
        sensor_aspect: sensor (height, width) ratio; (1, 1) is a square sensor.
        sensor_pixels: pixels along the sensor's longer side (for rendering).
        n_elements: number of lens elements.
        materials: one material name per element (``jaxlens.optics.catalog`` names).
        total_track: first vertex to sensor, mm (fixed during design).
        bfl: minimum clearance from the last lens surface to the sensor, mm.
        stop: number of elements in front of the aperture stop (0 = stop first).
        wavelengths: design wavelengths in µm (F, d, C by default).
        primary: index of the primary wavelength.
        asphere_terms: even aspheric terms per surface beyond the curvature (r⁴, r⁶, …).
        fov_start: full diagonal FoV (deg) where the curriculum starts (<= ``fov``; None:
            the paper's ``FOV_START``, 47.5°, or ``fov`` where that is narrower).
        fnum_start: F-number where the curriculum starts (>= ``fnum``: the curriculum goes
            from the easier slow lens to the target, as the FoV goes from ``fov_start`` up
            to ``fov``; None: the paper's ``FNUM_START``, F/2.8, or ``fnum`` where that is
            slower).
        name: a label for files and plots.
        efl: paraxial EFL target in mm, or None (free, the paper's convention). When set,
            the design loss holds the paraxial EFL there (``design.losses.Objective``) while
            ``focal_length`` still sets the sensor-filling image height and the EPD, so the
            difference is taken up by distortion (e.g. barrel when ``efl > focal_length``).
    """

    fov: float = 80.8
    fnum: float = 2.0
    sensor_diagonal: float = 7.66
    sensor_aspect: tuple[float, float] = (1.0, 1.0)
    sensor_pixels: int = 512
    n_elements: int = 6
    materials: tuple[str, ...] = ("E48R", "OKP4", "E48R", "OKP4", "E48R", "OKP4")
    total_track: float = 7.0
    bfl: float = 0.8
    stop: int = 0
    wavelengths: tuple[float, ...] = (LAMBDA_F, LAMBDA_D, LAMBDA_C)
    primary: int = 1
    asphere_terms: int = 6
    fov_start: float | None = None
    fnum_start: float | None = None
    name: str = "classical6p"
    efl: float | None = None

    def __post_init__(self):
        # A 0-d NumPy or JAX array, or a NumPy scalar, is the number it holds (before: a
        # TypeError for fov_start=jnp.asarray(40.0)); a 1-d array in a scalar field is
        # refused by validate(), and one in a sequence field is that sequence.
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name in _SEQUENCES and _is_array(v) and np.ndim(v) == 1:
                v = tuple(np.asarray(v).tolist())
            if f.name in _SEQUENCES and isinstance(v, (tuple, list)):
                v = tuple(_plain(x) for x in v)
            object.__setattr__(self, f.name, _plain(v))
        # The paper's start, eased to the target where the target is easier (a frozen
        # dataclass: set once, here, before the checks see the values).
        for name, target, eased in (("fov_start", "fov", min), ("fnum_start", "fnum", max)):
            if getattr(self, name) is None:
                paper = FOV_START if name == "fov_start" else FNUM_START
                try:  # a bad target is named by validate()
                    start = eased(paper, float(getattr(self, target)))
                except (TypeError, ValueError):
                    start = paper
                object.__setattr__(self, name, start)
        self.validate()

    # --- derived quantities ---------------------------------------------------------
    @property
    def half_fov(self) -> float:
        """Half the diagonal FoV, degrees."""
        return 0.5 * self.fov

    @property
    def half_diagonal(self) -> float:
        """Sensor half-diagonal, mm."""
        return 0.5 * self.sensor_diagonal

    @property
    def focal_length(self) -> float:
        """f = (sensor half-diagonal) / tan(half FoV), mm (the paper's convention)."""
        return self.half_diagonal / math.tan(math.radians(self.half_fov))

    @property
    def epd(self) -> float:
        """Entrance pupil diameter f / F#, mm."""
        return self.focal_length / self.fnum

    def image_mapping(self) -> tuple[float, float]:
        """``(f, k)`` of the ideal image height ``f·tanθ·(1 + k·tan²θ)`` the design aims at.

        Without an ``efl`` target, ``(focal_length, 0)``: distortion-free. With one,
        ``f = efl`` (the paraxial slope) and k puts the full field on the sensor
        half-diagonal, ``efl·tanθ·(1 + k·tan²θ) = half_diagonal``: a barrel (k < 0) or
        pincushion (k > 0) that grows as tan²θ, the leading term of smooth distortion.
        """
        if self.efl is None:
            return self.focal_length, 0.0
        t2 = math.tan(math.radians(self.half_fov)) ** 2
        return self.efl, (self.focal_length / self.efl - 1.0) / t2

    @property
    def sensor_size(self) -> tuple[float, float]:
        """(height, width) in mm."""
        h, w = self.sensor_aspect
        s = self.sensor_diagonal / math.hypot(h, w)
        return h * s, w * s

    @property
    def sensor_resolution(self) -> tuple[int, int]:
        """(rows, columns) with ``sensor_pixels`` along the longer side."""
        h, w = self.sensor_aspect
        m = max(h, w)
        return max(1, round(self.sensor_pixels * h / m)), max(1, round(self.sensor_pixels * w / m))

    @property
    def num_surfaces(self) -> int:
        """Stop plus two surfaces per element."""
        return 1 + 2 * self.n_elements

    @property
    def stop_index(self) -> int:
        """0-based index of the stop among the lens surfaces."""
        return 2 * self.stop

    def min_track(self) -> float:
        """Shortest track that fits the minimum thicknesses and the back clearance, mm."""
        n = self.n_elements
        return self.bfl + n * ELEMENT_MIN_THICKNESS + (n - 1) * AIR_MIN_GAP

    # --- validation -----------------------------------------------------------------
    def validate(self) -> None:
        """Raise ``ValueError`` (``TypeError`` for a wrong type) naming the bad value if no
        lens can meet this spec."""
        where = "DesignSpec"
        fov = _number(self.fov, "fov", lo=0, hi=180, lo_open=True, hi_open=True, unit="deg")
        _number(self.fov_start, "fov_start", lo=0, hi=fov, lo_open=True, unit="deg")
        fnum = _number(self.fnum, "fnum", lo=FNUM_RANGE[0], hi=FNUM_RANGE[1],
                       unit="(F-number f/EPD)")
        # The curriculum eases in: it starts at a field no wider and an F-number no faster
        # than the target's (a start of F/1.2 for an F/2 lens ran the stages from the
        # harder end, through F-numbers the lens was never meant for).
        _number(self.fnum_start, "fnum_start", lo=fnum, hi=FNUM_RANGE[1], unit="(F-number: "
                "the curriculum starts no faster than the target fnum)")
        _number(self.sensor_diagonal, "sensor_diagonal", lo=SENSOR_DIAGONAL_RANGE[0],
                hi=SENSOR_DIAGONAL_RANGE[1], unit="mm")
        aspect = _sequence(self.sensor_aspect, "sensor_aspect", "(height, width)")
        if len(aspect) != 2:
            raise ValueError(f"{where}: sensor_aspect must be two positive numbers (height, "
                             f"width), got {self.sensor_aspect}")
        for a in aspect:
            _number(a, "sensor_aspect", lo=0, lo_open=True)
        _number(self.sensor_pixels, "sensor_pixels", lo=1, hi=MAX_SENSOR_PIXELS, integer=True,
                unit="pixels")
        n = _number(self.n_elements, "n_elements", lo=1, hi=MAX_ELEMENTS, integer=True,
                    unit="lens elements")
        names = _sequence(self.materials, "materials", "catalog names, one per element")
        if not all(isinstance(m, str) for m in names):
            raise TypeError(f"{where}: materials must be catalog names (str), got "
                            f"{self.materials!r}")
        if len(names) != n:
            raise ValueError(f"{where}: {n} elements need {n} materials, got "
                             f"{len(names)}: {self.materials}")
        bfl = _number(self.bfl, "bfl", lo=0, lo_open=True, unit="mm")
        if bfl < MIN_BFL:  # before: 0.0005 (0.5 mm in m) designed a lens 0.5 µm off the sensor
            raise ValueError(f"{where}: bfl must be at least {MIN_BFL:g} mm (the clearance from "
                             f"the last lens surface to the sensor), got {bfl:g} mm (was it "
                             f"given in m? {bfl:g} m is {bfl * 1e3:g} mm)")
        track = _number(self.total_track, "total_track", lo=0, hi=MAX_TRACK, lo_open=True,
                        unit="mm")
        _number(self.stop, "stop", lo=0, hi=n, integer=True, unit="elements in front of it")
        wl = _sequence(self.wavelengths, "wavelengths", "µm")
        for w in wl:
            _number(w, "wavelengths", lo=0, lo_open=True, unit="µm")
        if not wl:
            raise ValueError(f"{where}: wavelengths must hold at least one wavelength (µm)")
        _number(self.primary, "primary", lo=0, hi=len(wl) - 1, integer=True,
                unit="(index into wavelengths)")
        _number(self.asphere_terms, "asphere_terms", lo=0, hi=MAX_ASPHERE_TERMS, integer=True,
                unit="terms per surface")
        if self.efl is not None:
            _number(self.efl, "efl", lo=0, lo_open=True, unit="mm (or None)")
        if not isinstance(self.name, str):
            raise TypeError(f"{where}: name must be a str, got {type(self.name).__name__} "
                            f"{self.name!r}")
        # Materials are known here: refuse wavelengths outside their data (or given in nm)
        # with the Lens's own check, on the lens's sequence of media (air after the stop
        # and after each element).
        media = []
        for i, m in enumerate(names):
            try:  # before: "Unknown material 'OKP5'" named neither the field nor its entry
                media += [get_material(m), None]
            except ValueError as e:
                raise ValueError(f"{where}: materials[{i}] {m!r}: {e}") from None
        for i, m in enumerate(media[::2]):  # "" and "AIR" name air: an element without power
            if isinstance(m, Air):
                raise ValueError(f"{where}: materials[{i}] {names[i]!r} is air; each element "
                                 f"needs a glass or plastic (a catalog name such as 'E48R')")
        media.insert(2 * self.stop, None)
        lens = types.SimpleNamespace(object_material=None, materials=tuple(media))
        checks.wavelengths(lens, np.asarray(wl, dtype=float), where, "wavelengths")
        if track <= bfl:
            raise ValueError(f"{where}: total_track {track} mm is not longer than "
                             f"the back focal length bfl {bfl} mm")
        if track < self.min_track():
            raise ValueError(
                f"{where}: total_track {track} mm cannot hold {n} "
                f"elements of ≥ {ELEMENT_MIN_THICKNESS} mm with air gaps ≥ {AIR_MIN_GAP} mm and "
                f"bfl {bfl} mm (needs ≥ {self.min_track():.3f} mm)")
        lo, hi = TRACK_PER_FOCAL
        for arg, f, what in (("focal length", self.focal_length,
                              "sensor_diagonal / (2·tan(fov/2))"), ("efl", self.efl, "target")):
            if f is not None and not lo <= track / f <= hi:
                # A full FoV of a few degrees is more likely radians (1.41 rad is 80.8°).
                rad = (f" and fov in degrees ({self.fov:g} rad would be "
                       f"{math.degrees(self.fov):.4g}°)" if arg == "focal length"
                       and self.fov <= 2 * math.pi and track / f < lo else "")
                raise ValueError(
                    f"{where}: total_track {track:g} mm is {track / f:.3g} times the {arg} "
                    f"{f:.4g} mm ({what}); it must be {lo:g} to {hi:g} times it (mm): are all "
                    f"lengths in mm (sensor_diagonal {self.sensor_diagonal:g} mm){rad}?")
        min_fnum, max_product = aperture_field_limits(n)
        if self.fnum < min_fnum:
            raise ValueError(f"{where}: F/{self.fnum} is faster than {n} element(s) "
                             f"can reach (F/{min_fnum:.2f} or slower)")
        product = math.tan(math.radians(self.half_fov)) / self.fnum
        if product > max_product:
            raise ValueError(
                f"{where}: a {self.fov}° field at F/{self.fnum} (tan(half FoV)/F# = "
                f"{product:.3f}) is more than {n} element(s) can reach "
                f"(≤ {max_product:.3f}); use more elements, a smaller field or a slower lens")


_SEQUENCES = ("sensor_aspect", "materials", "wavelengths")


def _is_array(value) -> bool:
    """A concrete NumPy or JAX array, or a NumPy scalar."""
    return (isinstance(value, (np.ndarray, np.generic, jax.Array))
            and not checks.is_traced(value))


def _plain(value):
    """A 0-d NumPy or JAX array of booleans, ints or floats (or such a NumPy scalar) as the
    Python value it holds; anything else as it is."""
    if _is_array(value) and np.ndim(value) == 0 and np.asarray(value).dtype.kind in "biuf":
        return np.asarray(value).item()
    return value


def _number(value, arg: str, *, lo=None, hi=None, lo_open=False, hi_open=False, unit="",
            integer=False):
    """``checks.number`` for a DesignSpec field, after its type check (TypeError): a number,
    or an int where ``integer`` (a bool is neither: True would pass as 1)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral if integer
                                                 else numbers.Real):
        span = checks.interval(lo, hi, lo_open, hi_open)
        got = (f"one value, got an array of shape {np.shape(value)}"
               if _is_array(value) and np.ndim(value) else
               f"got {type(value).__name__} {value!r}")
        raise TypeError(f"DesignSpec: {arg} must be {'an int' if integer else 'a number'} in "
                        f"{span}{f' {unit}' if unit else ''}, {got}")
    return checks.number(value, arg, "DesignSpec", lo=lo, hi=hi, lo_open=lo_open,
                         hi_open=hi_open, unit=unit, integer=integer)


def _sequence(value, arg: str, what: str) -> tuple:
    """A tuple or list field as a tuple (TypeError for a str, an array or a scalar)."""
    if not isinstance(value, (tuple, list)):
        raise TypeError(f"DesignSpec: {arg} must be a tuple of {what}, got "
                        f"{type(value).__name__} {value!r}")
    return tuple(value)


def require_spec(spec, where: str) -> DesignSpec:
    """``spec`` if it is a ``DesignSpec``; raises ``TypeError`` naming ``where`` otherwise (a
    dict or a Lens failed as an AttributeError deep inside)."""
    if not isinstance(spec, DesignSpec):
        raise TypeError(f"{where}: spec must be a jaxlens.design.DesignSpec, got "
                        f"{type(spec).__name__} {spec!r}"[:300])
    return spec
