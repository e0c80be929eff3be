"""The ``Lens`` pytree: a sequential optical system.

Conventions:
    Lengths in mm, angles in degrees, wavelengths in µm. Light travels toward +z.
    ``surfaces[0]`` is Zemax surface 1; its vertex is at z = 0. ``thickness[i]`` is the
    vertex-to-vertex distance from ``surfaces[i]`` to the next surface, and the last
    entry is the distance to the image surface. ``materials[i]`` is the medium *after*
    ``surfaces[i]`` (so ``materials[-1]`` is image space). ``stop`` is the 0-based index
    of the aperture stop in ``surfaces``. ``object_distance`` is measured from the
    object to surface 1's vertex (``inf``, or 1e10 mm and more, for an object at infinity;
    negative for a virtual object after surface 1, on which the object-space beam converges).
    ``epd`` is the entrance pupil diameter, ``fields`` the field angles in degrees (y
    direction), and ``wavelengths`` the system wavelengths with ``primary`` the index of
    the primary one.
    ``mirrors`` lists the (0-based) indices of reflecting surfaces (Zemax ``GLAS MIRROR``);
    the medium after a mirror, like the medium after a ``CoordinateBreak``, is the medium
    before it (``materials[i]`` must repeat it). After an odd number of mirrors light travels
    toward −z and the thicknesses are negative, as in Zemax. ``travel_senses`` (static) is
    None for such a lens; where coordinate breaks turn a frame round with the light instead
    (Quadoa's fold: a −45° break, the mirror, a +135° break, positive thicknesses after it),
    it holds ±1 per medium (object space first): the direction light travels along that
    medium's local z (``optics.travel``). The readers set it from the frames; ``Lens``
    refuses a value that disagrees with the frames when the tilts are concrete.
    ``obscurations`` lists ``(i, r_min, r_max)``: surface ``i`` blocks the rays that meet it
    at a height r_min ≤ r ≤ r_max (mm; Zemax ``OBSC``, r_min = 0 for a central
    obscuration such as a Cassegrain's secondary mirror).
    ``apertures`` lists ``(i, Aperture)`` pairs (``jaxlens.optics.apertures``): circles,
    ellipses and rectangles, decentered or not, that clip (or, with ``blocks``, obscure) the
    rays at surface ``i``; ``i = len(surfaces)`` is the image surface. They act besides the
    semi-diameters and ``obscurations`` (a surface clipped only by its apertures has
    ``semi_diameter = inf``).
    ``vignetting`` holds Zemax's vignetting factors, one row per field (``[F, 5]``, rows in
    the order of ``fields``): (VDX, VDY, VCX, VCY, VAN). VDX, VDY (pupil decenter) and
    VCX, VCY (pupil compression) are fractions of the entrance-pupil radius, VAN (pupil
    rotation) is in degrees. The sampling of a field's pupil maps each normalised pupil
    point (Px, Py) to ``VDX + Px·(1 − VCX)``, ``VDY + Py·(1 − VCY)``, rotated by VAN
    (``jaxlens.imaging.sampling.vignetting_map``). None (the default) or zeros: no
    vignetting factors, the whole pupil is sampled. They apply to the lens's own fields
    only (``sampling.field_rays`` for a field equal to one of ``fields``): a field between
    them (render, a PSF at a pixel's field) samples the whole pupil. A field's vignetted
    pupil is the image of the unit disc: for a field with factors, the points of an
    overfilled beam outside the unit disc launch no light. The relative illumination
    (``imaging.radiometry``), ``render`` (both methods) and the design losses never apply
    them.
    ``afocal_image`` marks an afocal image space (Zemax's "Afocal Image Space", FTYP's
    seventh value): the lens images to infinity (a telescope, a beam expander), so its image
    is a set of directions, not of points. Tracing and the paraxial data are the same; the
    analyses that measure positions on the image surface in mm (``rms_spot``,
    ``distortion``, ``ray_fan``, ``field_curvature``, ``seidel``, the PSFs,
    ``encircled_energy``, ``relative_illumination``, ``render``, the distortion maps)
    refuse such a lens, ``analysis.angular_spot`` and
    ``analysis.angular_magnification`` give its angular data, ``analysis.wavefront``
    references its wavefront to a plane, and the report is the afocal one.
    ``aim`` is the lens's ray aiming (``RAY_AIMING``): ``"paraxial"`` (the default) launches
    the ray of pupil point (Px, Py) through (Px, Py)·EPD/2 on the paraxial entrance pupil;
    ``"real"`` aims it by Newton's method so that it crosses the real stop at
    (Px, Py)·(paraxial marginal ray's height at the stop); ``"real_marginal"`` aims it at
    (Px, Py)·(real marginal ray's height at the stop: the real on-axis ray through the rim
    of the paraxial entrance pupil, primary wavelength; ``imaging.sampling.stop_radius``).
    Zemax's modes (System Explorer, Ray Aiming; ``.zmx`` RAIM's second value) map as:

    ==================  ===========  =====================
    Zemax ray aiming    RAIM type    ``Lens.aim``
    ==================  ===========  =====================
    Off                 0            ``"paraxial"``
    Paraxial            1            ``"real"``
    Real                2            ``"real_marginal"``
    ==================  ===========  =====================

    The samplers (``imaging.sampling.field_rays``, ``collimated``,
    ``point_source``) and the analyses built on them use it where their ``aim`` is None;
    ``render`` and the relative illumination launch their own rays over the paraxial
    pupil's plane and keep those within the beam the aim fills (its stop bounded at that
    radius, ``imaging.radiometry.beam_bounded``); the design losses launch theirs at the
    paraxial pupil whatever it is (speed).
    ``negative_propagation`` (static) chooses how a ray reaches each surface after the first.
    False (the default): forward along its direction (a ray parameter t ≥ 0), except across a
    negative gap (a vertex before the previous one) or to a dummy surface (same medium on
    both sides) on the previous vertex plane, where it may go back along its line; a ray
    that would have to go back elsewhere is lost (the surfaces cross within the beam; the
    design losses penalise such shapes). True: as in Zemax's sequential trace (and
    optiland's), a ray that meets a surface nowhere ahead of it goes back along its line to
    it (a negative propagation distance, t < 0), on every surface after the first and the
    image surface: the root taken is the first ahead of the ray, else the nearest behind
    it (the first met going back along its line), on the sheet of the surface through its
    vertex; a ray that the default
    traces takes the same root (its values agree to rounding: the compiled program
    differs). The ``.zmx`` reader sets it (a patent lens's edges, or a deep concave surface
    whose rim reaches past the stop, cross within the beam and Zemax traces through); the
    design parameterisation refuses it. Surface 1 (object space) follows the same rule
    either way (the whole line counts). ``dataclasses.replace(lens,
    negative_propagation=...)`` switches it; JSON files carry it (``negative_propagation``).
    ``object_na`` makes the lens object-space telecentric (Zemax's "Telecentric Object Space",
    FTYP's second value 1): None (the default) for a lens whose entrance pupil lies at a
    finite distance (``epd``); a number NA = n·sin(u) (n the object-space index at the
    primary wavelength, u the cone's half-angle) for an entrance pupil at infinity. Every
    chief ray then leaves its object point parallel to the axis, the object must be at a
    finite distance, ``fields`` hold object heights in mm (y, or (x, y): the object point's
    coordinates) instead of angles, ``epd`` is not used, and the ray of pupil point
    (Px, Py) leaves the object point with the slopes (Px, Py)·tan u (optiland's
    convention; ``imaging.telecentric.source``). Ray aiming does not apply (``aim``
    must be "paraxial"). The paraxial marginal ray starts on the axis at slope tan u, the
    chief ray at the object height with slope 0; the entrance pupil's position has no finite
    value (``paraxial.entrance_pupil_z`` refuses such a lens, ``paraxial_data`` gives
    −inf, an infinite diameter and an F/# of NaN), and so do the analyses built on a field
    angle or an entrance pupil at a finite distance (chief-ray aiming, distortion, relative
    illumination, render): they refuse it. ``telecentric_object`` tells which.
    A lens without ``object_na`` whose stop lies in the rear focal plane of the surfaces
    before it has its entrance pupil at infinity too, and an EPD that sets no beam:
    ``paraxial.entrance_pupil_z`` is ±inf and ``magnification`` finite, while
    ``paraxial_data``, ``marginal_ray`` and every analysis refuse it by name; give it
    ``object_na``.

The structure (surface kinds, counts, polynomial orders, stop index, mirrors) is static;
every number is an array so ``jax.grad`` reaches it.
"""

from __future__ import annotations

import copy
import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks, travel
from .apertures import Aperture
from .coordinates import CoordinateBreak
from .materials import AbstractMaterial, Air
from .reciprocal import reciprocal_length
from .surfaces import AbstractSurface, Standard

INFINITE_OBJECT_MM = 1e10
"""A concrete object distance at or beyond this (mm) is at infinity, as in Zemax (other
programs write 1e20 for infinity, whose square overflows float32 when rays are aimed)."""


_as_distance = checks.float_array("object_distance", "Lens", "mm")

OBJECT_DISTANCE_RANGE = (
    f"finite, nonzero and below {INFINITE_OBJECT_MM:g} in size (mm from the object to surface "
    f"1: > 0 a real object before it, < 0 a virtual object after it, on which the beam "
    f"converges; inf or None: an object at infinity)")
"""What an object distance may be (the message of ``check_object_distance``)."""


def check_object_distance(d, arg: str, where: str):
    """An object distance (mm from the object to surface 1, concrete or traced, any shape):
    finite, nonzero and below ``INFINITE_OBJECT_MM`` in size. Positive is a real object
    before surface 1; negative a virtual one after it, the point on which the beam in object
    space converges (Zemax's negative object thickness), whose rays are the lines through it
    and the entrance pupil, travelling toward +z. Returns ``d`` (``eqx.error_if`` where
    traced); a bad concrete value raises ``ValueError`` naming ``where``, ``arg`` and it."""
    msg = f"{where}: {arg} must be {OBJECT_DISTANCE_RANGE}"
    if checks.is_traced(d):
        a = jnp.asarray(d)
        return eqx.error_if(d, jnp.any(~jnp.isfinite(a) | (a == 0)
                                       | (jnp.abs(a) >= INFINITE_OBJECT_MM)), msg)
    a = np.asarray(d, dtype=float)
    bad = ~np.isfinite(a) | (a == 0) | (np.abs(a) >= INFINITE_OBJECT_MM)
    if np.any(bad):
        raise ValueError(f"{msg}, got {checks.fmt(a[bad][:1])} mm")
    return d


def _distance(x):
    """None (or inf, or ≥ ``INFINITE_OBJECT_MM``) means an object at infinity; that is static
    structure, not a number."""
    if x is None:
        return None
    x = _as_distance(x)
    if not isinstance(x, jax.core.Tracer) and bool(np.all(np.asarray(x) >= INFINITE_OBJECT_MM)):
        return None
    return x


_as_na = checks.float_array("object_na", "Lens", "(n·sin u, object space)")


def _object_na(x):
    """None (an entrance pupil at a finite distance) or the object-space NA of an
    object-space telecentric lens (checked in the Lens)."""
    return None if x is None else _as_na(x)


def _index(arg: str):
    """A converter for the static indices ``stop`` and ``primary``: an int (a float or a bool
    would pass ``0 <= i < n`` and fail later as an unrelated indexing error)."""
    def convert(i):
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"Lens: {arg} must be an int (a 0-based index), got "
                            f"{type(i).__name__} {i!r}")
        return int(i)
    return convert


def _sequence(arg: str, what: str):
    """A converter to a tuple for a static list (``mirrors=1`` was "'int' object is not
    iterable" from deep inside equinox)."""
    def convert(x):
        if isinstance(x, (str, bytes)) or not hasattr(x, "__iter__"):
            raise TypeError(f"Lens: {arg} must be a tuple of {what}, got "
                            f"{type(x).__name__} {x!r}")
        return tuple(x)
    return convert


def _senses(x):
    """A converter for ``travel_senses``: None, or a tuple of ±1 ints."""
    if x is None:
        return None
    if isinstance(x, (str, bytes)) or not hasattr(x, "__iter__") or any(
            isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v not in (-1, 1)
            for v in x):
        raise TypeError(f"Lens: travel_senses must be None or a tuple of +1 and -1 (one per "
                        f"medium, object space first), got {x!r}")
    return tuple(int(v) for v in x)


def _flag(arg: str):
    """A converter for a static flag: a bool (a 0/1, a string or an array would pass as
    truthy or not and change the analyses silently)."""
    def convert(v):
        if not isinstance(v, (bool, np.bool_)):
            raise TypeError(f"Lens: {arg} must be True or False, got {type(v).__name__} {v!r}")
        return bool(v)
    return convert


RAY_AIMING = ("paraxial", "real", "real_marginal")
"""The values of ``Lens.aim``: rays through the paraxial entrance pupil (Zemax's ray aiming
"Off"), or aimed at the real stop sized by the paraxial marginal ray (Zemax's "Paraxial") or
by the real one (Zemax's "Real"); see the module doc."""


def _aim(v):
    """A converter for ``Lens.aim``: one of ``RAY_AIMING`` (a typo would aim paraxially)."""
    if not isinstance(v, str) or v not in RAY_AIMING:
        raise ValueError(f"Lens: aim (ray aiming) must be one of {RAY_AIMING}, got "
                         f"{type(v).__name__} {v!r}")
    return v


def _obscurations(o):
    """``(i, r_min, r_max)`` triples: surface index (0-based) and radii in mm."""
    out = []
    for e in _sequence("obscurations", "(i, r_min, r_max) triples")(o):
        try:
            i, a, b = e
            if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
                raise TypeError
            out.append((int(i), float(a), float(b)))
        except (TypeError, ValueError):
            raise ValueError(f"Lens: obscurations must be (i, r_min, r_max) triples: a surface "
                             f"index (int, 0-based) and two radii in mm, got {e!r}") from None
    return tuple(out)


_as_factors = checks.float_array("vignetting", "Lens",
                                 "(VDX, VDY, VCX, VCY: pupil radii; VAN: deg)")

VIGNETTING_COLUMNS = ("VDX", "VDY", "VCX", "VCY", "VAN")
"""The columns of ``Lens.vignetting``: pupil decenter x, y and compression x, y (fractions of
the entrance-pupil radius) and the pupil's rotation angle (degrees), as Zemax names them."""


def _vignetting(v):
    """None (no vignetting factors) or a float array ``[F, 5]`` (checked in the Lens)."""
    return None if v is None else _as_factors(v)


def _floats(arg: str, unit: str, where: str = "Lens", **default):
    return checks.float_field(arg, where, unit, **default)


SURFACE_ARRAYS = ("coeffs", "odd_x", "odd_y", "zernike", "phase_coeffs")
"""The surface fields that hold one value per polynomial term (1-D); every other numeric
field of a surface in a Lens is one number (0-d)."""


def _check_scalar_fields(s, arg: str) -> None:
    """A surface of a Lens holds one surface: scalar parameters, 1-D term arrays. Surfaces
    accept a leading batch axis (the tracer stacks them), but a lens of them was traced as
    a broadcast of every ray against every batch entry: ``Sphere(semi_diameter=[5, 6])``
    gave "le got incompatible shapes" from inside the tracer, a [2] curvature the same."""
    own = type(s).__module__.startswith("jaxlens.")  # a user's surface: its base numbers
    for fld in dataclasses.fields(s):
        v = getattr(s, fld.name, None)
        if (fld.metadata.get("static") or not hasattr(v, "ndim")
                or not (own or fld.name in ("c", "k", "semi_diameter"))):
            continue
        want = 1 if fld.name in SURFACE_ARRAYS else 0
        if v.ndim != want:
            raise ValueError(
                f"Lens: {arg} ({type(s).__name__}): {fld.name} must be "
                f"{'a 1-D array of coefficients' if want else 'one number (a 0-d array)'}, "
                f"got shape {tuple(v.shape)}; a Lens holds one value per surface parameter: "
                f"build one Lens per set of values (or jax.vmap a function that builds it)")


class Sensor(eqx.Module):
    """A rectangular pixel sensor centred on the axis at the image surface.

    Args:
        resolution: (rows, columns), static; each at most ``checks.MAX_IMAGE_SIDE`` (16384).
        pixel_size: pixel pitch in mm (square pixels); the longer side, ``max(resolution) ×
            pixel_size``, at most ``checks.MAX_SENSOR_SIZE_MM`` (1000 mm).
    """

    resolution: tuple[int, int] = eqx.field(static=True)
    pixel_size: Float[Array, ""] = _floats("pixel_size", "mm", where="Sensor")

    def __check_init__(self):
        res = tuple(self.resolution) if isinstance(self.resolution, (tuple, list)) else ()
        if len(res) != 2 or not all(
                isinstance(n, (int, np.integer)) and not isinstance(n, bool)
                and 1 <= n <= checks.MAX_IMAGE_SIDE for n in res):
            raise ValueError(f"Sensor: resolution must be (rows, columns), whole numbers >= 1 "
                             f"pixels (at most {checks.MAX_IMAGE_SIDE} per side), got "
                             f"{self.resolution!r}")
        if not checks.is_traced(self.pixel_size):
            checks.number(self.pixel_size, "pixel_size", "Sensor", lo=0, lo_open=True,
                          unit="mm")
            reciprocal_length(self.pixel_size, "pixel_size", "Sensor",
                              why="image positions are divided by it")
            # Before: no upper bound; a pitch of 5 (µm meant) on 4000 pixels was a 20 m sensor.
            hi = checks.MAX_SENSOR_SIZE_MM / max(res)
            checks.number(self.pixel_size, "pixel_size", "Sensor", lo=0, lo_open=True, hi=hi,
                          unit=f"mm (the longer side, {max(res)} pixels, at most "
                               f"{checks.MAX_SENSOR_SIZE_MM:g} mm; 5 µm is 0.005 mm)")

    @property
    def size(self) -> tuple[Array, Array]:
        """(height, width) in mm."""
        return self.resolution[0] * self.pixel_size, self.resolution[1] * self.pixel_size

    @property
    def half_diagonal(self) -> Array:
        h, w = self.size
        return 0.5 * jnp.sqrt(h * h + w * w)


class Lens(eqx.Module):
    """A sequential lens: surfaces, the gaps and media between them, and the system data."""

    surfaces: tuple[AbstractSurface, ...]
    thickness: Float[Array, " n"] = _floats("thickness", "mm")
    materials: tuple[AbstractMaterial, ...]
    stop: int = eqx.field(static=True, default=0, converter=_index("stop"))
    epd: Float[Array, ""] = _floats("epd", "mm", default=1.0)
    fields: Float[Array, " f"] = _floats("fields", "deg", default=(0.0,))
    wavelengths: Float[Array, " w"] = _floats("wavelengths", "µm", default=(0.5875618,))
    primary: int = eqx.field(static=True, default=0, converter=_index("primary"))
    object_distance: Float[Array, ""] | None = eqx.field(converter=_distance, default=None)
    object_material: AbstractMaterial = eqx.field(default_factory=Air)
    image: AbstractSurface = eqx.field(default_factory=Standard)
    sensor: Sensor | None = None
    name: str = eqx.field(static=True, default="")
    mirrors: tuple[int, ...] = eqx.field(static=True, default=(),
                                         converter=_sequence("mirrors", "surface indices"))
    obscurations: tuple[tuple[int, float, float], ...] = eqx.field(
        static=True, default=(), converter=_obscurations)
    apertures: tuple[tuple[int, Aperture], ...] = eqx.field(
        static=True, default=(), converter=lambda a: tuple(
            tuple(e) if isinstance(e, (list, tuple)) else e for e in a))
    # Free text (provenance, source of the prescription): kept by JSON load and save.
    description: str = eqx.field(static=True, default="")
    # Zemax vignetting factors [F, 5] (VDX, VDY, VCX, VCY, VAN), or None: see the module doc.
    vignetting: Float[Array, "f 5"] | None = eqx.field(converter=_vignetting, default=None)
    # An afocal image space (the image at infinity): see the module doc.
    afocal_image: bool = eqx.field(static=True, default=False, converter=_flag("afocal_image"))
    # Ray aiming, "paraxial", "real" or "real_marginal": see the module doc.
    aim: str = eqx.field(static=True, default="paraxial", converter=_aim)
    # Whether rays may go back along their line to any surface after the first (Zemax's
    # negative propagation): see the module doc.
    negative_propagation: bool = eqx.field(static=True, default=False,
                                           converter=_flag("negative_propagation"))
    # Light's direction along each medium's local z where breaks turn frames round with it:
    # see the module doc and optics.travel.
    travel_senses: tuple[int, ...] | None = eqx.field(static=True, default=None,
                                                      converter=_senses)
    # Object-space NA of an object-space telecentric lens, or None: see the module doc.
    object_na: Float[Array, ""] | None = eqx.field(converter=_object_na, default=None)

    def __check_init__(self):
        n = len(self.surfaces)
        self._check_types()
        if self.thickness.ndim == 0 or self.thickness.shape[-1] != n:
            raise ValueError(f"Lens: {n} surfaces need {n} thicknesses (mm), got shape "
                             f"{self.thickness.shape}")
        if len(self.materials) != n:
            raise ValueError(f"Lens: {n} surfaces need {n} materials, got {len(self.materials)}")
        self._check_shapes()
        self._check_values()
        if not 0 <= self.stop < n:
            raise ValueError(f"Lens: stop must be a surface index in [0, {n - 1}] (0-based), "
                             f"got {self.stop}")
        w = self.wavelengths.shape[-1]
        if not 0 <= self.primary < w:  # before: "outside the wavelengths", no range
            raise ValueError(f"Lens: primary must be an index into the {w} wavelengths, in "
                             f"[0, {w - 1}] (0-based), got {self.primary}")
        self._check_mirrors_and_breaks()
        n = len(self.surfaces)
        seen = [o[0] for o in self.obscurations]
        for i, r_min, r_max in self.obscurations:
            if not 0 <= i < n or seen.count(i) > 1 or not 0.0 <= r_min < r_max:
                raise ValueError(
                    f"Lens: obscuration ({i}, {r_min}, {r_max}) must name one surface in "
                    f"[0, {n - 1}] (0-based) once with 0 ≤ r_min < r_max (mm)")
            if isinstance(self.surfaces[i], CoordinateBreak):  # the tracer would ignore it
                raise ValueError(f"Lens: surface {i} is a coordinate break; it has no aperture, "
                                 f"so its obscuration ({r_min}, {r_max}) mm would block nothing: "
                                 f"put it on the surface it blocks")
        self._check_apertures()

    def _check_apertures(self):
        n = len(self.surfaces)
        for entry in self.apertures:
            i, a = entry if isinstance(entry, tuple) and len(entry) == 2 else (None, None)
            if (isinstance(i, bool) or not isinstance(i, (int, np.integer))
                    or not 0 <= i <= n or not isinstance(a, Aperture)):
                raise ValueError(
                    f"Lens: apertures must be (i, Aperture) pairs with i a surface index in "
                    f"[0, {n}] (0-based; {n} is the image surface), got {entry!r}")
            if i < n and isinstance(self.surfaces[i], CoordinateBreak):
                raise ValueError(f"Lens: surface {i} is a coordinate break; it has no aperture")

    def _check_types(self):
        """Surfaces and materials of the right kind (a bare number or a glass name is not)."""
        parts = [(f"surfaces[{i}]", s, AbstractSurface, "a surface (jaxlens.Sphere, Standard, "
                  "EvenAsphere, …)") for i, s in enumerate(self.surfaces)]
        parts.append(("image", self.image, AbstractSurface, "a surface"))
        mat = "a material (jaxlens.get_material('N-BK7'), jaxlens.Air(), …)"
        parts += [(f"materials[{i}]", m, AbstractMaterial, mat)
                  for i, m in enumerate(self.materials)]
        parts.append(("object_material", self.object_material, AbstractMaterial, mat))
        parts.append(("description", self.description, str, "a string"))
        parts.append(("name", self.name, str, "a string"))
        if self.sensor is not None:  # render and the sensor-sized analyses read it
            parts.append(("sensor", self.sensor, Sensor, "None or a jaxlens.Sensor"))
        for arg, v, cls, what in parts:
            if not isinstance(v, cls):
                raise TypeError(f"Lens: {arg} must be {what}, got {type(v).__name__} {v!r}")

    def _check_shapes(self):
        """Shapes are known even under jit; a wrong one would be reshaped into wrong data."""
        if self.thickness.ndim != 1:  # [2, n] passed: efl gave n numbers, trace a shape error
            raise ValueError(f"Lens: thickness must be a 1-D array [n] of the gaps after each "
                             f"surface (mm), got shape {self.thickness.shape}; a Lens is one "
                             f"lens: build one per set of values (or jax.vmap a function that "
                             f"builds it)")
        for arg, s in [(f"surfaces[{i}]", s) for i, s in enumerate(self.surfaces)] + [
                ("image", self.image)]:
            _check_scalar_fields(s, arg)
        f = self.fields
        if f.size == 0 or f.ndim > 2 or (f.ndim == 2 and f.shape[1] != 2):
            raise ValueError(f"Lens: fields must be angles θy of shape [F] or [θx, θy] pairs "
                             f"of shape [F, 2] (deg), got shape {f.shape}")
        if self.wavelengths.ndim != 1 or self.wavelengths.size == 0:
            raise ValueError(f"Lens: wavelengths must be a 1-D array [W] (µm), got shape "
                             f"{self.wavelengths.shape}")
        for arg, v in (("epd", self.epd), ("object_distance", self.object_distance)):
            if v is not None and v.ndim != 0:
                raise ValueError(f"Lens: {arg} must be a scalar (mm), got shape {v.shape}")
        v = self.vignetting
        if v is not None and v.shape != (f.shape[0], 5):
            raise ValueError(
                f"Lens: vignetting must hold one row (VDX, VDY, VCX, VCY, VAN) per field: shape "
                f"[{f.shape[0]}, 5] for {f.shape[0]} field(s) (VDX, VDY, VCX, VCY in pupil "
                f"radii, VAN in deg), got shape {v.shape}")

    def _check_values(self):
        """Concrete numbers only (a traced lens, inside jit or vmap, is not known here)."""
        if not checks.is_traced(self.thickness):
            checks.values(self.thickness, "thickness", "Lens", unit="mm")
        if not checks.is_traced(self.epd):
            checks.values(self.epd, "epd (entrance pupil diameter)", "Lens", lo=0, lo_open=True,
                          unit="mm")
            reciprocal_length(self.epd, "epd (entrance pupil diameter)", "Lens",
                              why="the pupil is sampled in units of it; F/# = EFL/EPD")
        if self.object_na is not None:
            self._check_telecentric()
        elif not checks.is_traced(self.fields):
            checks.field_angles(self.fields, "Lens", "fields")
            checks.warn_if_radian_fields(self.fields, "Lens")
        if not checks.is_traced(self.wavelengths):
            checks.wavelengths(checks.NoMaterials, self.wavelengths, "Lens", "wavelengths")
        v = self.vignetting
        if v is not None and not checks.is_traced(v):
            check_vignetting(v, "Lens", "vignetting")
        d = self.object_distance
        if d is not None and not checks.is_traced(d):
            check_object_distance(d, "object_distance", "Lens")

    def _check_telecentric(self):
        """An object-space telecentric lens (``object_na`` given): a finite object, object
        heights for fields, paraxial ray aiming and an NA in (0, n)."""
        if self.object_na.ndim != 0:
            raise ValueError(f"Lens: object_na must be a scalar (n·sin u), got shape "
                             f"{self.object_na.shape}")
        if self.object_distance is None:
            raise ValueError("Lens: an object-space telecentric lens (object_na given) needs "
                             "a finite object_distance (mm): with the object at infinity its "
                             "image lies at the stop")
        d = self.object_distance
        if not checks.is_traced(d) and float(d) < 0:
            raise ValueError(f"Lens: an object-space telecentric lens (object_na given) needs a "
                             f"real object before surface 1 (object_distance > 0 mm), got "
                             f"{float(d):g} mm (a virtual object is not supported for it)")
        if self.aim != "paraxial":
            raise ValueError(f"Lens: an object-space telecentric lens (object_na given) "
                             f"launches its chief rays parallel to the axis; ray aiming does "
                             f"not apply, so aim must be 'paraxial', got {self.aim!r}")
        if not checks.is_traced(self.fields):
            checks.values(self.fields, "fields (object heights of an object-space telecentric "
                          "lens)", "Lens", unit="mm")
        if not checks.is_traced((self.object_na, self.wavelengths)):
            n0 = float(self.object_material.index(self.primary_wavelength))
            checks.values(self.object_na, "object_na (object-space NA n·sin u of an "
                          "object-space telecentric lens)", "Lens", lo=0, lo_open=True,
                          hi=n0, hi_open=True, unit=f"(n = {n0:.6g}, the object-space index)")

    @property
    def telecentric_object(self) -> bool:
        """True for an object-space telecentric lens (``object_na`` given; static)."""
        return self.object_na is not None

    def _check_mirrors_and_breaks(self):
        """Mirrors and coordinate breaks keep the medium: materials[i] repeats the one before."""
        n = len(self.surfaces)
        m = self.mirrors
        if (any(isinstance(i, bool) or not isinstance(i, (int, np.integer)) for i in m)
                or list(m) != sorted(set(m)) or (m and not 0 <= m[0] <= m[-1] < n)):
            raise ValueError(f"Lens: mirrors must be increasing surface indices in [0, {n - 1}] "
                             f"(0-based), got {m!r}")
        breaks = [i for i, s in enumerate(self.surfaces) if isinstance(s, CoordinateBreak)]
        for i in m:
            if i in breaks:
                raise ValueError(f"Lens: surface {i} is a coordinate break and cannot be a mirror")
        self._check_travel_senses()
        for i in sorted(set(m) | set(breaks)):
            before = self.object_material if i == 0 else self.materials[i - 1]
            after = self.materials[i]
            if checks.is_traced((before, after)):
                continue
            if not bool(eqx.tree_equal(before, after)):
                what = "mirror" if i in m else "coordinate break"
                name = lambda x: getattr(x, "name", None) or type(x).__name__  # noqa: E731
                raise ValueError(
                    f"Lens: surface {i} is a {what}; the medium after it is the medium before "
                    f"it, so materials[{i}] must be the same material as "
                    f"{'object_material' if i == 0 else f'materials[{i - 1}]'} "
                    f"({name(before)}), got {name(after)}")

    def _check_travel_senses(self):
        """``travel_senses`` must be what the frames give (checked where the tilts are
        concrete): a stale or missing value would make the paraxial data silently wrong."""
        n = len(self.surfaces)
        given = self.travel_senses
        if given is not None and len(given) != n + 1:
            raise ValueError(f"Lens: travel_senses needs {n + 1} entries (object space, then "
                             f"the medium after each surface), got {len(given)}")
        if given is None and not any(isinstance(s, CoordinateBreak) for s in self.surfaces):
            return
        try:
            need = travel.turned_senses(self.surfaces, self.mirrors)
        except ValueError as e:
            raise ValueError(f"Lens: {e}") from None
        if need is None and given is not None and travel.axis_cosines(
                self.surfaces, self.mirrors) is None:
            return  # traced tilts: nothing to check against
        if given != need:
            raise ValueError(
                f"Lens: travel_senses must be {need!r} for these mirrors and coordinate "
                f"breaks (the light's direction along each medium's local z, object space "
                f"first; None where it follows the mirror count), got {given!r}")

    @property
    def num_surfaces(self) -> int:
        return len(self.surfaces)

    def vertex_z(self) -> Float[Array, " n"]:
        """Global z of every surface vertex (surface 1 at 0)."""
        t = self.thickness
        return jnp.concatenate([jnp.zeros_like(t[..., :1]), jnp.cumsum(t[..., :-1], axis=-1)], -1)

    def image_z(self) -> Float[Array, ""]:
        """Global z of the image surface vertex."""
        return jnp.sum(self.thickness, axis=-1)

    def total_track(self) -> Float[Array, ""]:
        """Surface 1 vertex to image surface vertex (mm)."""
        return self.image_z()

    @property
    def primary_wavelength(self) -> Array:
        return self.wavelengths[self.primary]

    @property
    def object_at_infinity(self) -> bool:
        """True if the object is at infinity (static)."""
        return self.object_distance is None

    def indices(self, wavelength) -> list[Array]:
        """Refractive index before surface 1 and after each surface: n+1 arrays."""
        return [self.object_material.index(wavelength)] + [
            m.index(wavelength) for m in self.materials
        ]

    def astype(self, dtype) -> Lens:
        """Cast every floating array in the lens to ``dtype`` (float32 or float64)."""
        # int32 truncated every curvature to 0, float16 keeps too few digits to trace a lens.
        checks.float_dtype(dtype, "Lens.astype")
        check_castable(self, dtype, "Lens.astype")

        def cast(x):
            if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating):
                return x.astype(dtype)
            return x

        return jax.tree_util.tree_map(cast, self)


def check_castable(lens: Lens, dtype, where: str) -> None:
    """Refuse to cast a concrete float64 lens to float32 (``dtype``) where a finite value
    would become inf: every ray would then miss that surface, silently (an r^24 coefficient
    of a 10 µm micro-lens in mm units is about 1e44, beyond float32's 3.4e38). Traced
    lenses (under ``jit``, so also inside ``trace`` with float32 rays: an ``eqx.error_if``
    there cost the float32 trace 10-20 µs a call) and casts that do not narrow are not
    looked at, so no trace pays anything."""
    if jnp.finfo(dtype).bits >= 64:
        return
    big = float(jnp.finfo(dtype).max)
    for path, x in jax.tree_util.tree_flatten_with_path(lens)[0]:
        if (not eqx.is_array(x) or checks.is_traced(x)
                or not jnp.issubdtype(x.dtype, jnp.floating)
                or jnp.finfo(x.dtype).bits <= jnp.finfo(dtype).bits):
            continue
        a = np.asarray(x)
        bad = np.isfinite(a) & (np.abs(a) > big)
        if bad.any():
            name = jax.tree_util.keystr(path).lstrip(".")
            raise ValueError(
                f"{where}: the lens's {name} holds {a[bad].ravel()[0]:.6g}, beyond "
                f"{jnp.dtype(dtype).name}'s range (|x| <= {big:.4g}): every ray would miss "
                f"that surface; keep the lens and its rays in float64, or give it in units "
                f"where its coefficients are smaller")


def check_vignetting(v, where: str, arg: str = "vignetting"):
    """Concrete vignetting factors ``[..., 5]`` (VDX, VDY, VCX, VCY, VAN): all finite, and the
    compressions VCX, VCY below 1 (1 shrinks the pupil to a line, more turns it over; a
    negative one expands the pupil, as for a wide-angle lens whose real pupil grows off axis,
    and the rays beyond the paraxial pupil are the apertures' to clip).
    Raises ``ValueError`` naming ``where``, ``arg``, the column, the range and the unit;
    returns ``v``."""
    a = np.asarray(v, float)
    for j, col in enumerate(VIGNETTING_COLUMNS):
        unit = "deg" if col == "VAN" else "pupil radii"
        hi = 1.0 if col in ("VCX", "VCY") else None
        checks.values(a[..., j], f"{arg} {col}", where, hi=hi, hi_open=True, unit=unit)
    return v


def unclipped(lens: Lens) -> Lens:
    """The lens with every semi-diameter set to inf and no ``apertures`` or ``obscurations``,
    for aiming rays and for reference rays such as the chief ray (an aperture that clips an
    intermediate Newton iterate would otherwise stop it where it was clipped, and a central
    obscuration blocks the chief ray of a reflecting telescope)."""
    surfaces = tuple(
        eqx.tree_at(lambda s: s.semi_diameter, s, jnp.full_like(s.semi_diameter, jnp.inf))
        for s in lens.surfaces
    )
    free = eqx.tree_at(lambda m: m.surfaces, lens, surfaces)
    if free.apertures or free.obscurations:  # static structure, which tree_at does not reach
        free = copy.copy(free)
        object.__setattr__(free, "apertures", ())
        object.__setattr__(free, "obscurations", ())
    return free
