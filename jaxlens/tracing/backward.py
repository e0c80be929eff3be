"""Backward tracing, from the image surface toward object space, by mirroring the lens.

The forward tracer only moves light toward +z. To trace from sensor pixels back into
object space, the lens is mirrored about a plane, so that the reversed light also travels
toward +z in the mirrored frame:

    z'' = z_last − z        (x and y unchanged)

where ``z_last`` is the global z of the last surface's vertex. Under this map the last
surface becomes surface 1 at z'' = 0, the sensor lies at z'' = −thickness[-1] (in front
of it), and object space lies at z'' > z_last. A surface z = s(x, y) becomes z'' = −s(x, y)
in its own local frame, so every sag coefficient changes sign: c → −c, a_i → −a_i and the
odd terms b_j, d_j → −b_j, −d_j; the conic constant k and the semi-diameter are unchanged.
The medium after mirrored surface j is the medium before original surface n−1−j.

Directions map as (L, M, N) → (L, M, −N). Optical path lengths are unchanged.

The backward trace is the forward tracer on the mirrored lens, with ``uniform=True``
(one ``lax.scan`` over the surfaces: short compile times for image formation).
"""

from __future__ import annotations

import jax.numpy as jnp

from ..optics import checks
from ..optics.coordinates import CoordinateBreak
from ..optics.diffractive import Binary2, Grating
from ..optics.freeform import Biconic, ZernikeSag
from ..optics.lens import Lens
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.qtype import QTypeAsphere
from ..optics.rays import Rays
from ..optics.surfaces import (
    AbstractSurface,
    EvenAsphere,
    Hybrid,
    OddAsphere,
    Standard,
    TiltedPlane,
)
from ..optics.toroidal import Toroidal
from ..optics.xypolynomial import XYPolynomial
from .forward import DEFAULT_NEWTON_ITERS, check_upto, trace

__all__ = [
    "mirror_surface",
    "reversed_lens",
    "to_mirror_frame",
    "trace_backward",
]



def mirror_surface(surface: AbstractSurface) -> AbstractSurface:
    """The surface with its sag negated (z → −z in its local frame).

    Args:
        surface: a ``Standard``, ``EvenAsphere``, ``OddAsphere``, ``Hybrid``, ``Toroidal``,
            ``TiltedPlane``, ``ParaxialSurface``, ``Binary2``, ``QTypeAsphere``, ``Biconic``,
            ``ZernikeSag``, ``XYPolynomial`` or ``Grating``.

    Returns:
        A surface of the same kind with c, the even, radial, odd and Q-type coefficients (and a
        toroid's cx, a tilted plane's slopes) negated; a paraxial surface is its own mirror
        image (its optical path is then that of infinite conjugates on the image side); a
        ``Binary2`` keeps its phase (a retraced ray gets the same tangential kick, so it
        retraces the forward ray and its optical path gains the same (λ/2π)Φ), and so does a
        ``Grating`` (same lines and order).

    Raises:
        ValueError: for a surface kind that this module does not know how to mirror.
    """
    if isinstance(surface, Standard):
        return Standard(c=-surface.c, k=surface.k, semi_diameter=surface.semi_diameter)
    if isinstance(surface, EvenAsphere):
        return EvenAsphere(
            c=-surface.c, k=surface.k, coeffs=-surface.coeffs, semi_diameter=surface.semi_diameter
        )
    if isinstance(surface, OddAsphere):
        return OddAsphere(
            c=-surface.c, k=surface.k, coeffs=-surface.coeffs, semi_diameter=surface.semi_diameter
        )
    if isinstance(surface, Hybrid):
        return Hybrid(
            c=-surface.c,
            k=surface.k,
            coeffs=-surface.coeffs,
            odd_x=-surface.odd_x,
            odd_y=-surface.odd_y,
            semi_diameter=surface.semi_diameter,
        )
    if isinstance(surface, Toroidal):  # z_y -> -z_y and cx -> -cx negate the whole sag
        return Toroidal(c=-surface.c, k=surface.k, coeffs=-surface.coeffs, cx=-surface.cx,
                        semi_diameter=surface.semi_diameter)
    if isinstance(surface, QTypeAsphere):  # φ depends on c² and k: the departure negates too
        return QTypeAsphere(c=-surface.c, k=surface.k, coeffs=-surface.coeffs,
                            norm_radius=surface.norm_radius,
                            semi_diameter=surface.semi_diameter, qtype=surface.qtype)
    if isinstance(surface, Biconic):  # both sections' curvatures negate the whole sag
        return Biconic(c=-surface.c, k=surface.k, cx=-surface.cx, kx=surface.kx,
                       semi_diameter=surface.semi_diameter)
    if isinstance(surface, ZernikeSag):  # conic, even and Zernike terms all negate
        return ZernikeSag(c=-surface.c, k=surface.k, coeffs=-surface.coeffs,
                          zernike=-surface.zernike, norm_radius=surface.norm_radius,
                          decenter_x=surface.decenter_x, decenter_y=surface.decenter_y,
                          semi_diameter=surface.semi_diameter, ordering=surface.ordering,
                          extrapolate=surface.extrapolate)
    if isinstance(surface, XYPolynomial):  # the conic and every term negate
        return XYPolynomial(c=-surface.c, k=surface.k, coeffs=-surface.coeffs,
                            norm_radius=surface.norm_radius,
                            semi_diameter=surface.semi_diameter)
    if isinstance(surface, TiltedPlane):
        return TiltedPlane(tan_x=-surface.tan_x, tan_y=-surface.tan_y,
                           semi_diameter=surface.semi_diameter)
    if isinstance(surface, Binary2):
        # Same phase: n′d′_t = n·d_t + K_t negated is the retraced ray's rule with the same K
        # (x, y unchanged by the mirror), so the order stays.
        return Binary2(c=-surface.c, k=surface.k, coeffs=-surface.coeffs, order=surface.order,
                       norm_radius=surface.norm_radius, phase_coeffs=surface.phase_coeffs,
                       semi_diameter=surface.semi_diameter)
    if isinstance(surface, Grating):  # as Binary2: the same phase, so the same order
        return Grating(c=-surface.c, k=surface.k, lines_per_um=surface.lines_per_um,
                       order=surface.order, semi_diameter=surface.semi_diameter)
    if isinstance(surface, ParaxialSurface):
        # n′u′ = nu − x/f read backward (slopes negated, media swapped) is the same law.
        return surface
    raise ValueError(f"mirror_surface: cannot mirror a {type(surface).__name__} surface")


def reversed_lens(lens: Lens, *, image_distance=None) -> Lens:
    """The lens mirrored about the plane of its last surface (see the module docstring).

    Args:
        lens: the lens.
        image_distance: distance (mm) from the mirrored last surface (the original surface 1)
            to the mirrored image plane; default 0 (backward traces normally stop at the last
            surface, with ``trace_path(..., upto=n - 1)``).

    Returns:
        A ``Lens`` whose surface 1 is the original last surface, with the stop index and media
        mirrored, a flat image surface and no sensor. Field, wavelength and pupil data are
        copied unchanged (they do not describe the mirrored system), and so is
        ``negative_propagation`` (a ray's line is the same either way).
    """
    if lens.mirrors or lens.obscurations or lens.apertures or any(
            isinstance(s, CoordinateBreak) for s in lens.surfaces):
        raise ValueError("reversed_lens: lenses with mirrors, obscurations, apertures "
                         "(Lens.apertures) or coordinate breaks cannot be "
                         "traced backward (nor rendered) yet; trace them forward with trace")
    if image_distance is not None and not checks.is_traced(image_distance):
        # NaN was refused by the mirrored Lens as its "thickness", an argument not given here.
        checks.number(image_distance, "image_distance", "reversed_lens", unit="mm")
    n = lens.num_surfaces
    t = lens.thickness
    last = jnp.zeros_like(t[-1]) if image_distance is None else jnp.asarray(image_distance, t.dtype)
    thickness = jnp.concatenate([t[:-1][::-1], last[None]])
    surfaces = tuple(mirror_surface(s) for s in lens.surfaces[::-1])
    before = (lens.object_material,) + tuple(lens.materials[:-1])
    materials = tuple(before[::-1])
    return Lens(
        surfaces=surfaces,
        thickness=thickness,
        materials=materials,
        stop=n - 1 - lens.stop,
        epd=lens.epd,
        fields=lens.fields,
        wavelengths=lens.wavelengths,
        primary=lens.primary,
        object_distance=t[-1],
        object_material=lens.materials[-1],
        image=Standard(),
        sensor=None,
        name=f"{lens.name}:reversed" if lens.name else "reversed",
        negative_propagation=lens.negative_propagation,
    )


def to_mirror_frame(lens: Lens, origin, direction):
    """Map points and directions between the global and the mirrored frame (an involution)."""
    z_last = lens.vertex_z()[-1]
    o = jnp.concatenate([origin[..., :2], z_last - origin[..., 2:]], -1)
    d = jnp.concatenate([direction[..., :2], -direction[..., 2:]], -1)
    return o, d


def trace_backward(
    lens: Lens,
    rays: Rays,
    *,
    newton_iters: int = DEFAULT_NEWTON_ITERS,
    upto: int | None = None,
) -> Rays:
    """Trace rays that leave the image side toward −z back through the lens into object space.

    Args:
        lens: the lens.
        rays: rays in global coordinates in image space (for example starting on the sensor),
            travelling toward −z (direction N < 0).
        newton_iters: Newton iterations for polynomial surfaces.
        upto: stop after (original) surface ``upto``, 0-based, for example ``lens.stop``;
            None goes through surface 1 (index 0).

    Returns:
        The rays just after they leave surface 1 (or ``upto``), in global coordinates,
        still travelling toward −z (into object space). ``valid`` flags rays that passed
        every surface and aperture; ``opl`` is the optical path accumulated along the way.
    """
    # Named here: a bad newton_iters (or a non-Lens) was refused as trace's.
    check_upto(lens, rays, None, newton_iters, "trace_backward")
    if upto is not None:  # 99 was refused as the mirrored lens's index -94, not given here
        checks.number(upto, "upto", "trace_backward", lo=0, hi=lens.num_surfaces - 1,
                      integer=True, unit="(0-based index of an original surface)")
    rev = reversed_lens(lens)
    o, d = to_mirror_frame(lens, rays.origin, rays.direction)
    out = trace(
        rev,
        Rays(o, d, rays.wavelength, rays.valid, rays.opl),
        newton_iters=newton_iters,
        upto=lens.num_surfaces - 1 - (0 if upto is None else upto),
        uniform=True,
        chunk=None,
    )
    o, d = to_mirror_frame(lens, out.origin, out.direction)
    return Rays(o, d, out.wavelength, out.valid, out.opl)

