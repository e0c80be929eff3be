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

from ..optics.materials import LAMBDA_C, LAMBDA_D, LAMBDA_F, AbstractMaterial, ModelGlass

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
    return max(0.5, 4.0 / n_elements), 0.12 * n_elements


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
        fov_start: full diagonal FoV (deg) where the curriculum starts.
        fnum_start: F-number where the curriculum starts.
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
    fov_start: float = 47.5
    fnum_start: float = 2.8
    name: str = "classical6p"
    efl: float | None = None

    def __post_init__(self):
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

    def focal_length_at(self, fov: float) -> float:
        """Focal length implied by a (stage) FoV on this sensor, mm."""
        return self.half_diagonal / math.tan(math.radians(0.5 * fov))

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
        """Raise ``ValueError`` naming the bad value if no lens can meet this spec."""
        where = "DesignSpec"
        if not 0.0 < self.fov < 180.0:
            raise ValueError(f"{where}: fov must lie in (0, 180) degrees, got {self.fov}")
        if self.fnum <= 0 or self.fnum_start <= 0:
            raise ValueError(f"{where}: F-numbers must be positive, got fnum={self.fnum}, "
                             f"fnum_start={self.fnum_start}")
        if self.sensor_diagonal <= 0:
            raise ValueError(f"{where}: sensor_diagonal must be positive, got "
                             f"{self.sensor_diagonal}")
        if min(self.sensor_aspect) <= 0 or len(self.sensor_aspect) != 2:
            raise ValueError(f"{where}: sensor_aspect must be two positive numbers, got "
                             f"{self.sensor_aspect}")
        if self.n_elements < 1:
            raise ValueError(f"{where}: n_elements must be at least 1, got {self.n_elements}")
        if len(self.materials) != self.n_elements:
            raise ValueError(f"{where}: {self.n_elements} elements need {self.n_elements} "
                             f"materials, got {len(self.materials)}: {self.materials}")
        if not 0 <= self.stop <= self.n_elements:
            raise ValueError(f"{where}: stop must lie in 0..{self.n_elements} (elements in "
                             f"front of the stop), got {self.stop}")
        if not self.wavelengths or min(self.wavelengths) <= 0:
            raise ValueError(f"{where}: wavelengths must be positive µm, got {self.wavelengths}")
        if not 0 <= self.primary < len(self.wavelengths):
            raise ValueError(f"{where}: primary index {self.primary} outside the wavelengths")
        if self.asphere_terms < 0:
            raise ValueError(f"{where}: asphere_terms must be ≥ 0, got {self.asphere_terms}")
        if not 0.0 < self.fov_start <= self.fov:
            raise ValueError(f"{where}: fov_start must lie in (0, fov={self.fov}], got "
                             f"{self.fov_start}")
        if self.efl is not None and not self.efl > 0:
            raise ValueError(f"{where}: efl must be a positive focal length in mm (or None), "
                             f"got {self.efl}")
        if self.bfl <= 0:
            raise ValueError(f"{where}: bfl must be positive, got {self.bfl}")
        if self.total_track <= self.bfl:
            raise ValueError(f"{where}: total_track {self.total_track} mm is not longer than "
                             f"the back focal length bfl {self.bfl} mm")
        if self.total_track < self.min_track():
            raise ValueError(
                f"{where}: total_track {self.total_track} mm cannot hold {self.n_elements} "
                f"elements of ≥ {ELEMENT_MIN_THICKNESS} mm with air gaps ≥ {AIR_MIN_GAP} mm and "
                f"bfl {self.bfl} mm (needs ≥ {self.min_track():.3f} mm)")
        min_fnum, max_product = aperture_field_limits(self.n_elements)
        if self.fnum < min_fnum:
            raise ValueError(f"{where}: F/{self.fnum} is faster than {self.n_elements} element(s) "
                             f"can reach (F/{min_fnum:.2f} or slower)")
        product = math.tan(math.radians(self.half_fov)) / self.fnum
        if product > max_product:
            raise ValueError(
                f"{where}: a {self.fov}° field at F/{self.fnum} (tan(half FoV)/F# = "
                f"{product:.3f}) is more than {self.n_elements} element(s) can reach "
                f"(≤ {max_product:.3f}); use more elements, a smaller field or a slower lens")
        for m in self.materials:
            get_material(m)  # raises ValueError for an unknown name
