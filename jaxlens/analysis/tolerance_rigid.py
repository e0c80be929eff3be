"""Element decenter and tilt for tolerancing: rigid motions of lens elements built from
coordinate breaks (``jaxlens.optics.coordinates``), as Zemax's TEDX/TEDY/TETX/TETY do.

Elements:
    An element is a run of consecutive surfaces S_a … S_b (0-based, ``lens.surfaces[a:b+1]``)
    with air (``Air``) before S_a, a non-air medium after each of S_a … S_(b−1) and air after
    S_b: a singlet (two surfaces) or a cemented group, which moves as one part (its glasses
    cannot move apart without opening the cement). ``element_groups`` lists them.

Motion (per element, four numbers):
    decenter_x, decenter_y  mm, the element moves by +δ along the lens's x, y axes
    tilt_x, tilt_y          degrees, right-handed about the x and y axes through the pivot,
                            Zemax's signs: +tilt_x turns the element's axis from +z toward −y
    Pivot: the element's front vertex (S_a's vertex, after the decenter), Zemax's default
    for TETX/TETY. Decenter first, then tilt about x, then about the new y (a break of
    ``order = 0``), so with both a decenter and a tilt the pivot is the decentered vertex.

Construction (static structure; the same for every trial, so one compiled program):
    CB1, S_a, …, S_b, CB2, S_(b+1), … where CB1 holds the motion (thickness 0) and CB2
    restores the lens's axis: ``order = 1``, tilts −tilt_x, −tilt_y, and decenters and a
    thickness change chosen so that every surface after the element lies exactly where it
    did. With R the rotation of CB1 (new axes its columns), L the element's axial length
    (vertex S_a to vertex S_b) and d = (δx, δy, 0): S_b keeps thickness 0, CB2 gets the
    decenter −d − L (R ẑ − ẑ) in x and y and the thickness t_b + L (1 − R_zz). This is the
    geometry Zemax builds with a dummy surface that returns to the front vertex (thickness
    −L) before its return break; a break cannot hold a z decenter, so the z part moves into
    the next thickness instead. Zero motion gives zero-parameter breaks and unchanged
    thicknesses: the same lens up to rounding (a break re-expresses the rays about its
    vertex, (z − z_v) + z_v, which is not bitwise z).
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp

from ..optics import checks
from ..optics.coordinates import CoordinateBreak
from ..optics.lens import Lens
from ..optics.materials import Air

FIELDS = ("decenter_x", "decenter_y", "tilt_x", "tilt_y")


def element_groups(lens: Lens) -> tuple[tuple[int, int], ...]:
    """``(a, b)`` per element, 0-based first and last surface (see module docstring)."""
    media = [lens.object_material, *lens.materials]  # media[i] is before surfaces[i]
    groups, start = [], None
    for i in range(lens.num_surfaces):
        before, after = isinstance(media[i], Air), isinstance(media[i + 1], Air)
        if before and not after:
            start = i
        elif start is not None and not before and after:
            groups.append((start, i))
            start = None
        elif before and after:
            start = None
    return tuple(groups)


def check_lens(lens: Lens, where: str) -> None:
    """Refuse lenses whose elements cannot be moved by a pair of breaks."""
    if lens.mirrors:
        raise ValueError(f"{where}: element decenter and tilt tolerances do not support lenses "
                         f"with mirrors (surfaces {[i + 1 for i in lens.mirrors]}); set "
                         f"Tolerances.decenter and tilt to 0")
    groups = element_groups(lens)
    media = [lens.object_material, *lens.materials]  # media[i] is before surfaces[i]
    moved = {i for a, b in groups for i in range(a, b + 1)}
    left = [i + 1 for i in range(lens.num_surfaces) if i not in moved
            and not (isinstance(media[i], Air) and isinstance(media[i + 1], Air))]
    if left:
        # A glass run that starts in object space or ends in image space (an immersion
        # object, a block cemented to the image) is no air-bounded element: it stayed in
        # place while the others moved, and the yield left out its decenter without a word.
        raise ValueError(f"{where}: element decenter and tilt move air-bounded elements "
                         f"only, and surfaces {left} touch a medium that is not air (object "
                         f"space: {type(lens.object_material).__name__}, image space: "
                         f"{type(lens.materials[-1]).__name__}), so they would stay in place "
                         f"untoleranced; set Tolerances.decenter and tilt to 0")
    for a, b in groups:
        inside = [i + 1 for i in range(a, b + 1) if isinstance(lens.surfaces[i], CoordinateBreak)]
        if inside:
            raise ValueError(f"{where}: the element of surfaces {a + 1}-{b + 1} holds coordinate "
                             f"breaks (surfaces {inside}); element decenter and tilt need "
                             f"coaxial elements")


PER_SURFACE = ("radius_rel", "thickness", "conic", "asphere", "irregularity", "index",
               "abbe_rel")
"""The entries of a ``Perturbation`` that hold one value per surface of its lens."""


def check_perturb_args(lens: Lens, p, clear_radius, add_r4, where: str) -> None:
    """Refuse ``perturb``'s arguments that do not fit ``lens``: a perturbation of another
    lens (its per-surface entries were indexed to the shorter length, or broadcast to "add got
    incompatible shapes"), a ``clear_radius`` or ``add_r4`` of another length (an IndexError
    from the loop) and a concrete clear radius that is not a finite number > 0 mm (0, NaN or
    a negative one made the irregularity term inf, NaN or of the wrong scale, silently)."""
    n = lens.num_surfaces
    for name in PER_SURFACE:
        got = len(getattr(p, name))
        if got != n:
            raise ValueError(f"{where}: p.{name} has {got} entries for a lens of {n} surfaces: "
                             f"p must be a perturbation of this lens (zero_perturbation(lens) "
                             f"or a draw of its ToleranceModel)")
    if len(p.decenter_x) not in (0, len(groups := element_groups(lens))):
        raise ValueError(f"{where}: p moves {len(p.decenter_x)} elements, the lens has "
                         f"{len(groups)}: p must be a perturbation of this lens")
    if jnp.shape(clear_radius) != (n,):
        raise ValueError(f"{where}: clear_radius must be [{n}] mm (one clear semi-diameter per "
                         f"surface), got shape {jnp.shape(clear_radius)}")
    if not checks.is_traced(clear_radius):
        checks.real_values(clear_radius, "clear_radius", where, "mm")
        checks.values(clear_radius, "clear_radius", where, lo=0, lo_open=True, unit="mm")
    if add_r4 is not None and len(add_r4) != n:
        raise ValueError(f"{where}: add_r4 must hold one True/False per surface ({n}), got "
                         f"{len(add_r4)}")


def labels(lens: Lens) -> list[list[tuple[str, str, str]]]:
    """Per field of ``FIELDS``, a (name, unit, kind) label per element."""
    groups = element_groups(lens)
    out = []
    for f in FIELDS:
        unit, kind = ("mm", "decenter") if f.startswith("decenter") else ("deg", "tilt")
        what = f.replace("_", " ")
        out.append([(f"E{j + 1} (S{a + 1}-S{b + 1}) {what}", unit, kind)
                    for j, (a, b) in enumerate(groups)])
    return out


def displace(lens: Lens, decenter_x, decenter_y, tilt_x, tilt_y) -> Lens:
    """The lens with every element moved rigidly (jittable, differentiable).

    Args:
        lens: the lens (its elements as ``element_groups`` finds them).
        decenter_x, decenter_y: ``[G]`` mm, one per element.
        tilt_x, tilt_y: ``[G]`` degrees about the element's front vertex.

    Returns:
        A lens with two coordinate breaks per element (see the module docstring); the stop,
        obscuration and aperture indices follow their surfaces.
    """
    groups = element_groups(lens)
    if jnp.shape(decenter_x)[0] != len(groups):
        raise ValueError(f"displace: {len(groups)} elements need {len(groups)} motions, got "
                         f"{jnp.shape(decenter_x)[0]}")
    check_lens(lens, "displace")
    t = lens.thickness
    media = [lens.object_material, *lens.materials]
    start = {a: j for j, (a, _) in enumerate(groups)}
    end = {b: j for j, (_, b) in enumerate(groups)}
    surfaces, thick, materials, new_index = [], [], [], {}
    cb1 = {}
    for i, s in enumerate(lens.surfaces):
        if i in start:
            j = start[i]
            cb1[j] = CoordinateBreak(decenter_x=decenter_x[j], decenter_y=decenter_y[j],
                                     tilt_x=tilt_x[j], tilt_y=tilt_y[j])
            surfaces.append(cb1[j])
            thick.append(jnp.zeros_like(t[i]))
            materials.append(media[i])
        new_index[i] = len(surfaces)
        surfaces.append(s)
        materials.append(lens.materials[i])
        if i not in end:
            thick.append(t[i])
            continue
        j = end[i]
        a = groups[j][0]
        length = jnp.sum(t[a:i])
        r = cb1[j].rotation()  # new axes are the columns: R ẑ = (r[0][2], r[1][2], r[2][2])
        thick.append(jnp.zeros_like(t[i]))
        surfaces.append(CoordinateBreak(decenter_x=-decenter_x[j] - length * r[0][2],
                                        decenter_y=-decenter_y[j] - length * r[1][2],
                                        tilt_x=-tilt_x[j], tilt_y=-tilt_y[j], order=1))
        thick.append(t[i] + length * (1.0 - r[2][2]))
        materials.append(lens.materials[i])
    n = lens.num_surfaces
    new_index[n] = len(surfaces)  # the image surface
    return dataclasses.replace(
        lens, surfaces=tuple(surfaces), thickness=jnp.stack(thick), materials=tuple(materials),
        stop=new_index[lens.stop],
        obscurations=tuple((new_index[i], lo, hi) for i, lo, hi in lens.obscurations),
        apertures=tuple((new_index[i], ap) for i, ap in lens.apertures))
