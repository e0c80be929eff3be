"""Paraxial (first-order) optics by a y–nu trace.

Conventions:
    Lengths in mm. A paraxial ray is (y, nu): height and reduced angle n·u, with u the
    slope dy/dz. Surfaces refract with their paraxial curvature c + 2·a_1, so the
    r² term of an even asphere counts (Zemax does this; optiland and rayoptics do not), and
    so does an odd asphere's β_2 r² (c + 2·β_2; its β_1 cone has no paraxial power).
    ``efl`` is 1/Φ (Φ the power), the focal length in air (Zemax's "effective focal
    length (in air)"); ``efl_image_space`` is n′/Φ with n′ the image-space index, the
    focal length measured in image space, which Zemax ("in image space") and optiland
    report as the EFL. They differ only when image space is not air. ``bfl`` is
    measured from the last surface vertex to the paraxial focus; pupil positions are
    global z (surface 1 at 0); ``exit_pupil_z`` is also global. A quantity that is
    mathematically infinite (an afocal lens's focal lengths and F/#, an image or a pupil at
    infinity, the magnification of an object in the front focal plane) is ±inf, never the
    huge finite number rounding leaves: a denominator within its rounding bound counts as
    zero (``_over``: 4·k·ε times the same sum taken in absolute values, k its operations),
    the result the sign of its numerator over +0 (efl, F/#, working F/# and magnification
    +inf; a position's sign is not meaningful). Everything is a pure
    jnp function, so it is differentiable and jittable. A given wavelength must lie in the
    materials' range and a field angle in (−90°, 90°) (``checks``: ValueError, or
    ``eqx.error_if`` under jit).

    Mirrors: after each mirror the index changes sign (Zemax's convention), so a mirror of
    curvature c in a medium of index n has power −2nc and the transfer t/n stays positive
    with the negative thicknesses after it. ``bfl``, ``rear_focal_length`` and the image
    and exit-pupil positions are then z values (negative where light leaves toward −z);
    ``efl`` is 1/Φ and ``efl_image_space`` |n′|/Φ. Coordinate breaks are dummy surfaces
    here: the trace follows each surface's local axis and ignores decenters and tilts,
    except in a lens whose breaks turn a frame round with the light (``Lens.travel_senses``:
    a fold written as −45°, the mirror, +135° with a decenter, positive thicknesses after
    it): each medium's index is then signed by the light's direction along its frame's z,
    and the trace transfers by the axis ray's path from vertex to vertex
    (``travel.axial_thicknesses``; its z values are along that path). So
    is a ``TiltedPlane`` (Zemax TILTSURF): c = 0, no paraxial power, and its tilt, which
    deviates rays as a prism face does, is seen by real rays only.

    A ``ParaxialSurface`` (ideal thin lens) has power 1/f whatever its media. A ``Binary2``
    (diffractive) surface adds its phase's power −M λ A_1/(π R²) to its base's, whatever its
    media and proportional to the wavelength (``jaxlens.optics.diffractive``). A ``Grating``
    (Zemax DGRATING) has its base conic's power only (c(n′ − n), or −2nc as a mirror): its
    lines deflect every ray by the same M λ T, a constant the linear y–nu trace cannot hold,
    so the paraxial data of a lens with a grating are those of its order-0 system (the
    grating's lines removed; optiland's EFL of its three sample gratings is the same); the
    real rays see the lines. A lens with a
    ``Toroidal`` surface has no single paraxial trace: everything here is its y–z section
    (as in Zemax, whose paraxial data are y–z), and ``x_section(lens)`` is the lens as
    its x–z section sees it, so ``paraxial_data(x_section(lens))`` is the x–z data.
"""

from __future__ import annotations

import contextvars
import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import checks
from .diffractive import Binary2
from .freeform import Biconic, ZernikeSag
from .lens import INFINITE_OBJECT_MM, Lens, check_object_distance
from .paraxial_surface import ParaxialSurface
from .surfaces import AbstractSurface, Standard
from .toroidal import Toroidal
from .travel import axial_thicknesses, travel_senses
from .xypolynomial import XYPolynomial


def _transfer(y, nu, d, n):
    return y + d * nu / n, nu


def _refract(y, nu, power):
    return y, nu - y * power


def surface_power(surface, n1, n2, wavelength=None):
    """Paraxial power (1/mm) of a surface between indices n1 and n2 (y–z section); a
    ``Binary2`` adds its phase's power at ``wavelength`` (µm), which it then needs.

    n1 and n2 are refractive indices, |n| >= 1, negative after a mirror (as
    ``signed_indices`` gives them); concrete values are checked (0 or NaN gave a plausible
    power), and so is a concrete wavelength (587.6, in nm, was taken as µm)."""
    if not isinstance(surface, AbstractSurface):
        raise TypeError(f"surface_power: surface must be a jaxlens surface, got "
                        f"{type(surface).__name__} {surface!r}")
    for arg, n in (("n1", n1), ("n2", n2)):
        if checks.is_traced(n):
            continue
        checks.real_values(n, arg, "surface_power", "refractive index")
        a = np.asarray(n, dtype=float)
        if np.any(~np.isfinite(a) | (np.abs(a) < 1.0 - 1e-9)):
            raise ValueError(f"surface_power: {arg} must be finite refractive indices with "
                             f"|n| >= 1 (negative after a mirror, as signed_indices gives "
                             f"them), got {checks.fmt(a)}")
    if wavelength is not None and not checks.is_traced(wavelength):
        checks.wavelengths(checks.NoMaterials, wavelength, "surface_power")
    return _surface_power(surface, n1, n2, wavelength)


def _surface_power(surface, n1, n2, wavelength):
    if isinstance(surface, ParaxialSurface):
        return surface.power
    if isinstance(surface, Binary2):
        if wavelength is None:
            raise ValueError("surface_power: a Binary2 (diffractive) surface's power depends "
                             "on the wavelength; pass it (µm)")
        return surface.paraxial_curvature * (n2 - n1) + surface.paraxial_power(wavelength)
    return surface.paraxial_curvature * (n2 - n1)


def x_section(lens: Lens) -> Lens:
    """The lens as its x–z section sees it, for paraxial work: each ``Toroidal``, ``Biconic``,
    ``ZernikeSag`` or ``XYPolynomial`` surface becomes the sphere of its x–z vertex curvature (same
    semi-diameter). Surfaces with
    the same vertex curvature in x and y are unchanged. Not for real-ray tracing."""
    _lens_and_size(lens, None, "x_section")
    surfaces = tuple(
        Standard(c=s.paraxial_curvature_x, k=0.0, semi_diameter=s.semi_diameter)
        if isinstance(s, Toroidal | Biconic | ZernikeSag | XYPolynomial) else s
        for s in lens.surfaces)
    return eqx.tree_at(lambda m: m.surfaces, lens, surfaces)


def _lens_and_size(lens, wavelength, where: str) -> None:
    """A string for the lens was an AttributeError deep inside; no wavelength (``[]``)
    gave empty results. Several wavelengths broadcast (one result per wavelength)."""
    if not isinstance(lens, Lens):
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    if wavelength is not None and not checks.is_traced(wavelength):
        checks.real_values(wavelength, "wavelength", where, "µm")
        if np.size(wavelength) == 0:
            raise ValueError(f"{where}: wavelength must hold at least one value (µm), got "
                             f"shape {np.shape(wavelength)}")


_DEPTH = contextvars.ContextVar("paraxial_depth", default=0)
"""How many of this module's entry points (``_entry``) are running: the lens's own checks
(``checks.lens_intact``) run in the outermost only."""


def _entry(fn):
    """An entry point: nested calls (``paraxial_data`` calls ``marginal_ray``, which calls
    ``entrance_pupil_z``, ...) know they are nested, so the lens is checked once, by the
    function the user called."""
    @functools.wraps(fn)
    def go(*args, **kwargs):
        token = _DEPTH.set(_DEPTH.get() + 1)
        try:
            return fn(*args, **kwargs)
        finally:
            _DEPTH.reset(token)
    return go


def _given(lens: Lens, wavelength, where: str):
    """The wavelength (µm) for the helpers that internal (often traced) code calls with the
    primary one: the primary one for None, a given concrete one checked against the lens's
    materials (587.6 in nm gave a plausible but wrong pupil), a traced one as it is (no
    ``error_if`` on the traced hot path: ``paraxial_data`` and ``efl`` check theirs)."""
    _lens_and_size(lens, wavelength, where)
    if _DEPTH.get() <= 1:  # a lens edited with eqx.tree_at (a NaN thickness): NaN before
        checks.lens_intact(lens, where)
    if wavelength is None:
        # Checked here, under the name the user called: past a formula's resonance it was
        # refused by ``signed_indices``, a function the user never called.
        checks.primary_wavelength(lens, where)
        return lens.primary_wavelength
    if checks.is_traced(wavelength):
        return wavelength
    return checks.wavelengths(lens, wavelength, where)


@_entry
def signed_indices(lens: Lens, wavelength) -> list[Array]:
    """``lens.indices`` signed by the light's direction along each medium's local z
    (``travel.travel_senses``: negative after an odd number of mirrors, unless coordinate
    breaks turn the frame round with the light): the y–nu trace's indices."""
    wl = _given(lens, wavelength, "signed_indices")  # before lens.indices: lens checked
    n = lens.indices(wl)
    if not lens.mirrors and lens.travel_senses is None:
        return n
    return [-x if s < 0 else x for x, s in zip(n, travel_senses(lens), strict=True)]


@_entry
def system_matrix(lens: Lens, wavelength=None, start: int = 0, end: int | None = None):
    """ABCD matrix in (y, nu) from just before ``surfaces[start]`` to just after ``surfaces[end]``.

    Returns the four entries (A, B, C, D) with [y', nu'] = [[A, B], [C, D]] [y, nu].
    """
    wl = _given(lens, wavelength, "system_matrix")
    n = signed_indices(lens, wl)
    last = lens.num_surfaces - 1
    end = last if end is None else end
    for arg, v, lo in (("start", start, 0), ("end", end, start)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= last:
            raise ValueError(f"system_matrix: {arg} must be a surface index in [{lo}, {last}] "
                             f"(0-based; start <= end), got {v!r}")
    return _product(lens, wl, n, start, end)[0]


def _product(lens: Lens, wl, n, start: int, end: int):
    """The (y, nu) matrix from just before ``surfaces[start]`` to just after ``surfaces[end]``
    and the same product taken with every entry's absolute value (``_over``'s rounding scale)."""
    thickness = axial_thicknesses(lens)
    one = jnp.ones_like(lens.thickness[0])
    a, b, c, d = one, 0 * one, 0 * one, one
    aa, ab, ac, ad = one, 0 * one, 0 * one, one
    for i in range(start, end + 1):
        if i > start:
            t = thickness[i - 1] / n[i]
            a, b = a + t * c, b + t * d
            aa, ab = aa + jnp.abs(t) * ac, ab + jnp.abs(t) * ad
        p = _surface_power(lens.surfaces[i], n[i], n[i + 1], wl)
        c, d = c - p * a, d - p * b
        ac, ad = ac + jnp.abs(p) * aa, ad + jnp.abs(p) * ab
    return (a, b, c, d), (aa, ab, ac, ad), 2 * (end - start + 1)


def _over(num, den, scale, steps: int):
    """num / den, where a denominator no larger than its rounding bound is zero: the answer
    is then infinite (the sign of num over +0.0; NaN for num = 0), never the huge finite
    number that rounding leaves there (an afocal lens's EFL of -5.8e17 mm, a magnification
    of 3.7e15 for an object in the front focal plane).

    ``scale`` is the same sum taken with absolute values (the trace or matrix product with
    |t/n|, |power| and |ray|), ``steps`` its number of multiply-adds: the bound is
    4·steps·ε·scale (ε the dtype's machine epsilon), a few times the worst rounding of such
    a sum, so that a denominator within it has no significant digit. The infinite branch
    carries no gradient (as a telecentric exit pupil's)."""
    den = jnp.asarray(den)
    eps = jnp.finfo(jnp.result_type(den, float)).eps
    zero = jnp.abs(den) <= 4 * (steps + 2) * eps * jnp.abs(scale)
    safe = jnp.where(zero, 1.0, den)
    return jnp.where(zero, jax.lax.stop_gradient(num / jnp.zeros_like(den)), num / safe)


class ParaxialData(eqx.Module):
    """First-order properties of a lens at one wavelength (mm; see module docstring).

    ``efl`` = 1/Φ (in air) and ``efl_image_space`` = n′/Φ (in image space, Zemax's and
    optiland's EFL); ``front_focal_length`` = n·efl and ``rear_focal_length`` = n′·efl
    with n, n′ the object- and image-space indices. For an object-space telecentric lens
    (``Lens.object_na``) ``entrance_pupil_z`` is −inf, ``entrance_pupil_diameter`` +inf and
    ``fnum`` (EFL/EPD) NaN; ``working_fnum`` and the rest follow its NA. A lens whose EPD
    sets no marginal ray (its entrance pupil at infinity without ``object_na``, or its object
    on the pupil's plane) is refused by name (``check_marginal_pupil``): its stop size,
    working F/# and exit pupil diameter have no value (efl, bfl and ``magnification`` do).
    """

    efl: Float[Array, ""]
    efl_image_space: Float[Array, ""]
    bfl: Float[Array, ""]
    front_focal_length: Float[Array, ""]
    rear_focal_length: Float[Array, ""]
    entrance_pupil_z: Float[Array, ""]
    entrance_pupil_diameter: Float[Array, ""]
    exit_pupil_z: Float[Array, ""]
    exit_pupil_diameter: Float[Array, ""]
    fnum: Float[Array, ""]
    working_fnum: Float[Array, ""]
    image_z: Float[Array, ""]
    paraxial_image_z: Float[Array, ""]
    total_track: Float[Array, ""]
    stop_semi_diameter: Float[Array, ""]


def telecentric_only(lens: Lens, where: str) -> None:
    """Refuse anything but an object-space telecentric lens (``Lens.object_na`` given) in
    ``where``, whose numbers are of its object cone."""
    _lens_and_size(lens, None, where)
    if not lens.telecentric_object:
        raise ValueError(f"{where}: the lens is not object-space telecentric (Lens.object_na "
                         f"is None): {where} is of an object-space telecentric lens's object "
                         f"cone; give the lens an object_na (an object at a finite distance)")


def finite_pupil(lens: Lens, where: str, instead: str = "") -> None:
    """Refuse an object-space telecentric lens (``Lens.object_na``), whose entrance pupil lies
    at infinity, in ``where``, which needs one at a finite distance (its position, or field
    angles toward its centre); ``instead`` names what to use for such a lens. Anything but a
    Lens passes, for its caller's type check."""
    if isinstance(lens, Lens) and lens.telecentric_object:
        raise ValueError(
            f"{where}: the lens is object-space telecentric (Lens.object_na given): its "
            f"entrance pupil lies at infinity and its fields are object heights (mm), so "
            f"{where}, which needs an entrance pupil at a finite distance and field angles, "
            f"does not apply{'; ' + instead if instead else ''}; paraxial_data gives its "
            f"first-order data, paraxial.magnification its image scale, and rms_spot, "
            f"chief_ray, distortion, field_curvature, seidel, relative_illumination, "
            f"ray_fan, wavefront, psf, mtf, render (an object-plane scene) and report take "
            f"its object heights")


@_entry
def object_slope(lens: Lens) -> Array:
    """tan u: the object-space slope of the paraxial marginal ray of an object-space
    telecentric lens, u = asin(NA / n) with n the object-space index at the primary
    wavelength (``Lens.object_na``). Any other lens is a ``ValueError`` (a lens without an
    object NA failed as None divided by an array)."""
    telecentric_only(lens, "object_slope")
    s = lens.object_na / lens.object_material.index(lens.primary_wavelength)
    return s / jnp.sqrt(1.0 - s * s)


@_entry
def entrance_pupil_z(lens: Lens, wavelength=None) -> Array:
    """Global z of the paraxial entrance pupil (image of the stop in object space). An
    object-space telecentric lens (``Lens.object_na``), whose pupil lies at infinity, is
    refused."""
    finite_pupil(lens, "entrance_pupil_z")
    wl = _given(lens, wavelength, "entrance_pupil_z")
    n0 = lens.object_material.index(wl)
    if lens.stop == 0:
        return jnp.zeros_like(lens.thickness[0])
    # Matrix from surface 1 to just before the stop: after surfaces[stop-1], then transfer.
    n = signed_indices(lens, wl)
    (a, b, c, d), (aa, _, ac, _), steps = _product(lens, wl, n, 0, lens.stop - 1)
    t = axial_thicknesses(lens)[lens.stop - 1] / n[lens.stop]
    a, b = a + t * c, b + t * d
    # Chief ray reaches the stop centre: a*y0 + b*nu0 = 0 with y0 = -z_ep*u0, nu0 = n0*u0.
    # A = 0 (within rounding): the stop at the front group's focus, the pupil at infinity.
    return _over(b * n0, a, aa + jnp.abs(t) * ac, steps + 1)


@_entry
def entrance_pupil_magnification(lens: Lens, wavelength=None) -> Array:
    """Paraxial magnification from the entrance pupil to the stop (stop height / EP height)."""
    finite_pupil(lens, "entrance_pupil_magnification")
    wl = _given(lens, wavelength, "entrance_pupil_magnification")
    if lens.stop == 0:
        return jnp.ones_like(lens.thickness[0])
    a, _, c, _ = system_matrix(lens, wl, 0, lens.stop - 1)
    t = axial_thicknesses(lens)[lens.stop - 1] / signed_indices(lens, wl)[lens.stop]
    # Imaging EP -> stop has B = 0, so the magnification is the A entry.
    return a + t * c


@_entry
def marginal_ray(lens: Lens, wavelength=None):
    """Paraxial marginal ray (y, nu) after every surface, for the lens's EPD and object (an
    object-space telecentric lens: from the axial object point at slope tan u, u the
    cone's half-angle of its ``object_na``). A lens whose EPD sets no marginal ray (its
    entrance pupil at infinity, or its object on the pupil's plane) is refused
    (``check_marginal_pupil``).

    Each is ``[num_surfaces]`` for one wavelength (µm), ``[num_surfaces, W]`` for ``[W]``."""
    wl = _given(lens, wavelength, "marginal_ray")
    n = signed_indices(lens, wl)
    return _trace_ray(lens, *_marginal_start(lens, wl, n), n, wl)


def _axial_start(lens: Lens, n):
    """A paraxial ray (y, nu) from the finite axial object point arriving at surface 1, at
    slope 1 whatever the aperture (an object-space telecentric lens's, an EPD whose pupil
    lies at infinity): the image's position and magnification do not depend on its slope."""
    one = jnp.ones_like(lens.thickness[0])
    return lens.object_distance * one, n[0] * one


def _marginal_start(lens: Lens, wl, n, where: str = "marginal_ray"):
    """The paraxial marginal ray (y, nu) arriving at surface 1 (see ``marginal_ray``); a lens
    whose EPD sets none is refused (``check_marginal_pupil``, naming ``where``)."""
    if lens.telecentric_object:
        u = object_slope(lens)
        return lens.object_distance * u, n[0] * u
    zep = entrance_pupil_z(lens, wl)
    h = 0.5 * lens.epd
    if lens.object_at_infinity:
        check_marginal_pupil(zep, None, where)
        return h, 0.0 * h
    check_marginal_pupil(zep, lens.object_distance, where)
    u = h / (lens.object_distance + zep)
    return lens.object_distance * u, n[0] * u


def check_marginal_pupil(zep, object_distance, where: str) -> None:
    """Refuse, naming ``where``, a lens whose EPD sets no paraxial marginal ray: its entrance
    pupil (``zep``, global mm, concrete) at infinity (the stop in the focal plane of the
    surfaces before it: the ray from the axial object point to the pupil's rim had slope 0,
    the axis itself, and a stop semi-diameter, working F/# and exit pupil diameter of 0 or
    inf followed), or a finite object (``object_distance``, mm, None at infinity) on the
    pupil's plane (slope ±inf). Traced, nothing is checked (the design losses' hot path)."""
    if checks.is_traced((zep, object_distance)):
        return
    z = np.asarray(zep, dtype=float)
    if not np.all(np.isfinite(z)):
        raise ValueError(
            f"{where}: the lens's entrance pupil lies at infinity (z_EP = {checks.fmt(z)}: its "
            f"stop in the focal plane of the surfaces before it), so its EPD sets no paraxial "
            f"marginal ray (the ray from the axial object point to the pupil's rim is the "
            f"axis), and the stop's paraxial size, the working F/#, the exit pupil's diameter "
            f"and the image position from it have no value; efl, bfl and "
            f"paraxial.magnification do not depend on the aperture; for an object-space "
            f"telecentric lens give object heights and its NA (Lens(object_na=...)), or move "
            f"the stop")
    if object_distance is not None:
        d = float(object_distance)
        if np.any(np.abs(d + z) <= 1e-12 * np.maximum(np.abs(d), np.abs(z))):
            raise ValueError(
                f"{where}: the lens's object (object_distance {d:g} mm) lies on its entrance "
                f"pupil's plane (z_EP = {checks.fmt(z)}), so the paraxial marginal ray to the "
                f"pupil's rim has an infinite slope and the EPD sets no beam; move the object "
                f"or the stop")


def _image_slope_scale(lens: Lens, wl, n, start=None):
    """The rounding scale and steps (``_over``) of the marginal ray's image-space nu: a ray
    leaving parallel to the axis within rounding (the object in the front focal plane, an
    afocal lens) has its image at infinity."""
    y0, nu0 = _marginal_start(lens, wl, n) if start is None else start
    _, (_, _, ac, ad), steps = _product(lens, wl, n, 0, lens.num_surfaces - 1)
    return ac * jnp.abs(y0) + ad * jnp.abs(nu0), steps


def _trace_ray(lens: Lens, y, nu, n, wl):
    ys, nus = [], []
    thickness = axial_thicknesses(lens)
    for i, s in enumerate(lens.surfaces):
        if i > 0:
            y, nu = _transfer(y, nu, thickness[i - 1], n[i])
        y, nu = _refract(y, nu, _surface_power(s, n[i], n[i + 1], wl))
        ys.append(y)
        nus.append(nu)
    # Broadcast: with several wavelengths the first heights of a marginal ray from infinity
    # are one value and the later ones one per wavelength ("Cannot stack arrays").
    return jnp.stack(jnp.broadcast_arrays(*ys)), jnp.stack(jnp.broadcast_arrays(*nus))


def _wavelength(lens: Lens, wavelength, where: str):
    """The wavelength (µm) to use: the primary one, or the given one checked against the
    lens's materials (an error_if under jit, so these stay usable in jitted losses)."""
    _lens_and_size(lens, wavelength, where)
    checks.lens_intact(lens, where)  # edited with eqx.tree_at: a NaN curvature gave NaN
    if wavelength is None:  # named by the caller (``_given``)
        checks.primary_wavelength(lens, where)
    wl = lens.primary_wavelength if wavelength is None else checks.wavelengths(
        lens, wavelength, where)
    # A formula material whose index there is below 1 or not finite (Schott coefficients
    # that give n = 0.71, or n² < 0) gave a plausible focal length, or NaN, without a word.
    checks.material_indices(lens, wl, where, "wavelength" if wavelength is not None else
                            "the lens's primary wavelength", intact=True)
    return wl


@_entry
def paraxial_chief_ray(lens: Lens, field_deg, wavelength=None):
    """Paraxial chief ray (y, nu) after every surface for a field angle (degrees); for an
    object-space telecentric lens (``Lens.object_na``) for an object height (mm), the ray
    parallel to the axis at that height."""
    wl = _wavelength(lens, wavelength, "paraxial_chief_ray")
    if lens.telecentric_object:
        h = checks.values(jnp.asarray(field_deg, lens.thickness.dtype), "field (object "
                          "height)", "paraxial_chief_ray", unit="mm")
        n = signed_indices(lens, wl)
        return _trace_ray(lens, h, 0.0 * h, n, wl)
    field_deg = checks.field_angles(field_deg, "paraxial_chief_ray", "field_deg")
    n = signed_indices(lens, wl)
    zep = entrance_pupil_z(lens, wl)
    u = _pupil_reachable(zep, jnp.tan(jnp.deg2rad(jnp.asarray(field_deg))), "paraxial_chief_ray")
    # The chief ray crosses the axis at the entrance pupil: height −z_ep·u at surface 1
    # (z = 0). Where the pupil lies at infinity only the axis (u = 0) has one, the axis
    # itself: −z_ep·u was inf·0 = NaN there.
    y0 = -jnp.where(jnp.isfinite(zep), zep, 0.0) * u
    return _trace_ray(lens, y0, n[0] * u, n, wl)


PUPIL_AT_INFINITY = (
    "the lens's entrance pupil lies at infinity (its stop in the focal plane of the surfaces "
    "before it), so no paraxial chief ray of a nonzero field angle reaches the stop's "
    "centre: every ray of the field's beam crosses the stop at one point off the axis, "
    "and only the axis (field 0) has a chief ray. For an object-space telecentric lens give "
    "object heights (Lens(object_na=...)), or move the stop")


def check_pupil_plane(zep, where: str) -> None:
    """Refuse a concrete entrance-pupil position ``zep`` (global mm) that is not finite: the
    stop in the focal plane of the surfaces before it puts the pupil at infinity, where no
    ray can be launched through (Px, Py)·EPD/2 on its plane (the rays' origins were inf,
    refused by ``Rays`` without naming why). Traced, nothing is checked."""
    if not checks.is_traced(zep) and not np.all(np.isfinite(np.asarray(zep))):
        raise ValueError(
            f"{where}: the lens's entrance pupil lies at infinity (its stop in the focal plane "
            f"of the surfaces before it, z_EP = {checks.fmt(np.asarray(zep))}), so the "
            f"EPD's disc on its plane launches no ray; for an object-space telecentric lens "
            f"give object heights and its NA (Lens(object_na=...)), or move the stop")


def entrance_pupil_plane(lens: Lens, where: str) -> Array:
    """``entrance_pupil_z`` at the primary wavelength, the plane the samplers launch rays on,
    refused (``check_pupil_plane``, naming ``where``) where it lies at infinity."""
    zep = entrance_pupil_z(lens, lens.primary_wavelength)
    check_pupil_plane(zep, where)
    return zep


def check_launchable(lens: Lens, where: str) -> None:
    """Refuse, naming ``where``, a concrete lens whose beams cannot be launched: every
    analysis launches them on the entrance pupil's plane, which lies at infinity where the
    stop sits in the focal plane of the surfaces before it (spots, fans and the relative
    illumination were NaN or empty, a report an EquinoxRuntimeError from inside its
    compiled trace). An object-space telecentric lens (``Lens.object_na``) launches from its
    object points instead and passes."""
    if not lens.telecentric_object and not checks.is_traced(lens):
        zep = compiled_entrance_pupil_z(lens, lens.primary_wavelength)
        if checks.is_traced(zep):  # called inside a user's jit: nothing is known yet
            return
        if np.isnan(np.asarray(zep)).any():  # a lens edited with eqx.tree_at: its checks say why
            checks.lens_intact(lens, where)
        check_pupil_plane(zep, where)


@checks.checked_core(eqx.filter_jit)
def compiled_entrance_pupil_z(lens: Lens, wavelength) -> Array:
    """``entrance_pupil_z`` as one compiled program, for the entry points' checks of a
    concrete lens: op by op it dispatched some twenty operations (4.7 ms on the phone lens,
    a third of an ``rms_spot`` call)."""
    return entrance_pupil_z(lens, wavelength)


def _pupil_reachable(zep, u, where: str):
    """``u`` (tanθ of field angles), refused where it is nonzero and the entrance pupil lies
    at infinity (``PUPIL_AT_INFINITY``): a ValueError for concrete values, an error_if where
    traced."""
    if checks.checked_by_caller((zep, u)):  # its entry point refused it (``check_launchable``)
        return u  # an error_if is a host callback: no persistent cache for the core
    bad = ~jnp.isfinite(zep) & (u != 0)
    if not checks.is_traced((zep, u)):
        if np.any(np.asarray(bad)):
            raise ValueError(f"{where}: {PUPIL_AT_INFINITY} (got tanθ = "
                             f"{checks.fmt(np.asarray(u))})")
        return u
    return eqx.error_if(u, jnp.any(bad), f"{where}: {PUPIL_AT_INFINITY}")


@_entry
def efl(lens: Lens, wavelength=None) -> Array:
    """Effective focal length 1/power (mm) at ``wavelength`` (default: primary); +inf for an
    afocal lens (zero power, or a power within its rounding bound: ``_over``)."""
    wl = _wavelength(lens, wavelength, "efl")
    (_, _, c, _), (_, _, ac, _), steps = _product(lens, wl, signed_indices(lens, wl), 0,
                                                  lens.num_surfaces - 1)
    return _over(1.0, _power(c), ac, steps)


def _power(c):
    # 0.0 − c, not −c: a zero power is +0.0, so an afocal lens's focal length is +inf
    # (−c of a +0.0 entry is −0.0, and 1/−0.0 = −inf).
    return 0.0 - c


@_entry
def bfl(lens: Lens, wavelength=None) -> Array:
    """Back focal length: last vertex to the paraxial focus of an object at infinity (mm);
    infinite for an afocal lens (the sign of −A·n′ over +0: ``_over``)."""
    wl = _wavelength(lens, wavelength, "bfl")
    n = signed_indices(lens, wl)
    (a, _, c, _), (_, _, ac, _), steps = _product(lens, wl, n, 0, lens.num_surfaces - 1)
    return _over(-a * n[-1], c, ac, steps)


@_entry
def image_height(lens: Lens, field_deg, wavelength=None) -> Array:
    """Paraxial chief-ray height on the image surface (mm) of a field angle (deg), or of an
    object height (mm) for an object-space telecentric lens (``Lens.object_na``)."""
    wl = _wavelength(lens, wavelength, "image_height")
    if not lens.telecentric_object:
        field_deg = checks.field_angles(field_deg, "image_height", "field_deg")
    y, nu = paraxial_chief_ray(lens, field_deg, wl)
    n_img = signed_indices(lens, wl)[-1]
    return y[-1] + axial_thicknesses(lens)[-1] * nu[-1] / n_img


@_entry
def magnification(lens: Lens, wavelength=None) -> Array:
    """The paraxial lateral magnification m = n u / (n′ u′) of the lens's finite object (its
    paraxial image height per unit object height, at the paraxial image plane), from the
    marginal ray at ``wavelength`` (µm, default primary); 0 for an object at infinity, and
    infinite for an image at infinity (the object in the front focal plane: the
    image-space nu zero within rounding, ``_over``; +inf for a real
    object: m tends to −inf just outside the focal plane and +inf just inside it). For
    an object-space telecentric lens (``Lens.object_na``) the distortion-free image of the
    object height h (mm) is m·h: the paraxial chief ray, parallel to the axis at h, meets
    the paraxial image plane there. It is traced by an axial ray of slope 1, not the
    marginal ray, so it does not depend on the aperture (an entrance pupil at infinity
    without ``object_na`` still has one)."""
    wl = _wavelength(lens, wavelength, "magnification")
    n = signed_indices(lens, wl)
    if lens.object_at_infinity:
        return jnp.zeros_like(lens.thickness[0] * wl)
    # An axial ray of slope 1, not the marginal ray: m = n u / (n′ u′) does not depend on
    # the aperture, so an entrance pupil at infinity (the marginal ray the axis) still has one.
    start = _axial_start(lens, n)
    nu = _trace_ray(lens, *start, n, wl)[1][-1]
    return _over(start[1], nu, *_image_slope_scale(lens, wl, n, start))


@_entry
def paraxial_data(lens: Lens, wavelength=None) -> ParaxialData:
    """All first-order data at one wavelength (default: primary)."""
    if wavelength is not None and jnp.ndim(wavelength) != 0:
        # Its fields are scalars: a list of wavelengths failed in np.stack deep inside.
        raise ValueError(f"paraxial_data: wavelength must be one value (µm), got shape "
                         f"{jnp.shape(wavelength)}; call it once per wavelength")
    wl = _wavelength(lens, wavelength, "paraxial_data")
    n = signed_indices(lens, wl)
    n0, n_img = n[0], n[-1]
    (a, b, c, d), (_, _, ac, _), steps = _product(lens, wl, n, 0, lens.num_surfaces - 1)
    f = _over(1.0, _power(c), ac, steps)
    back = _over(-a * n_img, c, ac, steps)
    t_axial = axial_thicknesses(lens)
    zs = lens.vertex_z() if lens.travel_senses is None else jnp.concatenate(
        [jnp.zeros_like(t_axial[:1]), jnp.cumsum(t_axial[:-1])])
    z_last = zs[-1]
    if lens.telecentric_object:  # the entrance pupil at infinity
        zep, epd = jnp.full_like(f, -jnp.inf), jnp.full_like(f, jnp.inf)
    else:
        zep = entrance_pupil_z(lens, wl)
        # Strongly typed, as the other fields are: a lens's scalars are weakly typed (a
        # Python float given to Lens), and this field alone followed the other operand's
        # dtype (bfloat16 × entrance_pupil_diameter was bfloat16, × efl float32).
        epd = jnp.asarray(lens.epd, f.dtype)
    # Stop semi-diameter from the marginal ray height at the stop.
    ym, num = _trace_ray(lens, *_marginal_start(lens, wl, n, "paraxial_data"), n, wl)
    stop_sd = jnp.abs(ym[lens.stop])
    # Exit pupil: image of the stop through the surfaces after it.
    if lens.stop == lens.num_surfaces - 1:
        xp_z = zs[lens.stop]
        xp_mag = jnp.ones_like(f)
    else:
        (a2, b2, c2, d2), (_, _, ac2, ad2), steps2 = _product(
            lens, wl, n, lens.stop + 1, lens.num_surfaces - 1)
        t = t_axial[lens.stop] / n[lens.stop + 1]
        # From the stop plane (after refraction at the stop surface) to after the last surface.
        a2, b2 = a2, b2 + t * a2
        d2, ad2 = d2 + t * c2, ad2 + jnp.abs(t) * ac2
        # Ray from stop centre, nu=1: y=b2, nu=d2 after the last surface; crosses axis at:
        # (d2 = 0 within rounding: telecentric in image space, the exit pupil at infinity. Its
        # infinite value carries no gradient: 0·inf in the backward pass was NaN wherever the
        # caller's double where gave it a zero cotangent; LLVM's optimiser had hidden that.)
        xp_z = z_last - _over(b2 * n_img, d2, ad2, steps2 + 1)
        # Magnification stop -> exit pupil: ray from stop edge parallel to chief ray.
        xp_mag = a2 - _over(c2 * b2, d2, ad2, steps2 + 1)
    xpd = 2.0 * stop_sd * jnp.abs(xp_mag)
    # An object-space telecentric lens's aperture is an NA: no infinite-conjugate F/#.
    fnum = jnp.full_like(f, jnp.nan) if lens.telecentric_object else f / epd
    scale, steps = _image_slope_scale(lens, wl, n)
    working = _over(1.0, 2.0 * jnp.abs(num[-1]), 2.0 * scale, steps)
    paraxial_image_z = z_last - _over(ym[-1] * n_img, num[-1], scale, steps)
    return ParaxialData(
        efl=f,
        efl_image_space=jnp.abs(n_img) * f,
        bfl=back,
        front_focal_length=n0 * f,
        rear_focal_length=n_img * f,
        entrance_pupil_z=zep,
        entrance_pupil_diameter=epd,
        exit_pupil_z=xp_z,
        exit_pupil_diameter=xpd,
        fnum=fnum,
        working_fnum=working,
        image_z=lens.image_z(),
        paraxial_image_z=paraxial_image_z,
        total_track=lens.total_track(),
        stop_semi_diameter=stop_sd,
    )


@_entry
def working_fnum(lens: Lens, depth) -> Array:
    """The paraxial working F-number 1/(2n′u′) for an object at ``depth`` (mm from surface 1,
    as ``sampling.lens_depth`` gives it; None for infinity), whatever the lens's own object:
    ``mtf(lens, depth=...)`` took the lens's own, so a lens made for infinity imaged at 1:1
    had its diffraction MTF (and default cut-off) at half the working F-number."""
    _lens_and_size(lens, None, "working_fnum")
    if depth is not None and not checks.is_traced(depth):
        # A depth of 0 mm was refused as "a lens edited with eqx.tree_at".
        checks.real_values(depth, "depth", "working_fnum", "mm")
        if np.all(np.asarray(depth, dtype=float) >= INFINITE_OBJECT_MM):
            depth = None  # as a Lens's object_distance: inf gave a working F-number of NaN
        else:  # negative: a virtual object
            check_object_distance(depth, "depth", "working_fnum")
    at = eqx.tree_at(lambda m: m.object_distance, lens, depth, is_leaf=lambda x: x is None)
    return paraxial_data(at).working_fnum
