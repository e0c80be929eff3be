"""Tolerance analysis: sensitivities, Monte-Carlo yield and a back-focus compensator.

Metric (the one number everything here reports):
    The field-weighted mean of the polychromatic RMS spot radius, in µm: the rays of all
    wavelengths pooled with equal weights about their common centroid, the 21 × 21 square
    pupil grid (317 rays per wavelength) aimed at the paraxial entrance pupil, only valid
    rays counted. Per field this is exactly
    ``jaxlens.analysis.rms_spot(lens, fields, wavelengths, reference="centroid")
    .polychromatic``; with the 16 × 16 sensor grid of ``jaxlens.design.evaluate`` it is
    Table 1's "RMS spot, 256 fields". ``symmetric_fields`` folds such a grid onto its
    distinct fields under the square's symmetry with multiplicities as weights; the mean
    is unchanged (every lens analysed here is rotationally symmetric and the pupil grid is
    symmetric under the square's eight symmetries), for 36 instead of 256 traced fields.

Perturbations (``Perturbation``; surface 1 is ``lens.surfaces[0]``):
    radius_rel    relative radius change, R → R (1 + δ), i.e. c → c / (1 + δ)
    thickness     mm added to ``thickness[i]`` (the last entry moves the image plane)
    conic         added to k
    asphere       added to the even coefficients a_1 … a_m (units mm^(1−2i))
    irregularity  peak sag (mm) of an added r⁴ term at the surface's clear semi-diameter h:
                  Δz = s (r/h)⁴, a low-order (spherical-like) form error
    index         added to the material's nd (each non-air material slot = one element)
    abbe_rel      relative Abbe-number change, Vd → Vd (1 + δ)

    Index and Abbe changes wrap the design's own material (``PerturbedMaterial``):
    n'(λ) = n(λ) + Δnd + (s − 1)(n(λ) − nd) with s = (nd + Δnd − 1)/((nd − 1)(1 + δ)),
    so n'(d) = nd + Δnd and V'd = Vd (1 + δ) while the catalog dispersion curve keeps its
    shape. At zero perturbation this is the design's material to the last bit (no model
    glass substitution, so no difference to state).

    decenter_x, decenter_y   mm, per element (an air-bounded singlet or cemented group)
    tilt_x, tilt_y           degrees about the element's front vertex, right-handed
    Elements move rigidly between two coordinate breaks, as Zemax's TEDX/TEDY/TETX/TETY
    (``jaxlens.analysis.tolerance_rigid`` states the construction and signs). They are
    toleranced only when ``Tolerances.decenter`` or ``tilt`` is > 0 (default 0: off, and
    the perturbation vector and the compiled trace are then those of a coaxial model).
    A moved element breaks the rotational symmetry: ``symmetric_fields`` must not fold the
    fields then (the folded mean is not the full mean, and d metric / d decenter is 0 at
    the nominal lens only over a symmetric field set); give the full field set.

Compensator:
    The back focus (the last thickness, i.e. the image-plane position) is re-optimised per
    trial, as Zemax's default compensator does. Image space is homogeneous, so a ray's
    image-plane point moves linearly with the plane, p(Δz) = p + Δz · (dx/dz, dy/dz):
    each field's mean square spot radius is an exact quadratic in Δz, the metric is a
    sum of square roots of quadratics (convex), and a few damped Newton steps minimise it
    from the closed-form minimiser of the field-weighted mean square. No re-trace.

MTF:
    Geometric polychromatic MTF at one stated frequency (cycles/mm) from the same spot
    rays (the Fourier transform of the ray positions, wavelengths averaged), times the
    diffraction-limited MTF of a circular pupil at the paraxial working F-number — the
    definition of ``jaxlens.imaging.psf.mtf(model="geometric", diffraction=True)`` on a
    coarser pupil. Per field the mean of tangential and sagittal; per lens the
    field-weighted mean.
"""

from __future__ import annotations

import copy
import math
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, Float

from ..imaging.sampling import pupil_grid
from ..optics import checks, paraxial
from ..optics.coordinates import CoordinateBreak
from ..optics.diffractive import DIFFRACTIVE
from ..optics.lens import Lens
from ..optics.materials import LAMBDA_D, AbstractMaterial, Air, abbe_number
from ..optics.paraxial_surface import ParaxialSurface
from ..optics.qtype import QTypeAsphere
from ..optics.surfaces import EvenAsphere, Hybrid, Standard, TiltedPlane
from . import tolerance_rigid as rigid
from .spots import clear_semi_diameters
from .tolerance_metric import (  # noqa: F401  (re-exported: the metric's public names)
    SpotData,
    best_focus,
    field_mtf,
    field_rms,
    mean_rms_um,
    normalised_weights,
    spot_data,
)
from .tolerance_spec import (  # noqa: F401  (re-exported: the tolerances' public names)
    DECENTER_TILT,
    DISTRIBUTIONS,
    MAX_CONIC,
    MAX_FORM_SAG,
    MAX_INDEX,
    MAX_THICKNESS,
    MAX_TILT,
    MAX_TRIALS,
    Tolerances,
)

MIN_THRESHOLD_UM = 0.01
"""The smallest RMS threshold (µm) ``monte_carlo`` takes, the lower end of the tolerance
CLIs' ``THRESHOLD_RANGE_UM``: a requirement below it is far inside any diffraction spot (an
Airy radius is 1.22·λ·F/#, 0.4 µm at λ 0.4 µm, F/0.8) and is most likely one given in mm."""


class PerturbedMaterial(AbstractMaterial):
    """A material with its nd shifted and its Abbe number scaled (see module docstring)."""

    base: AbstractMaterial
    delta_nd: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    abbe_rel: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    name: str = eqx.field(static=True, default="")

    def index(self, wavelength):
        return self._perturbed(self.base.index(wavelength))

    def extrapolated_index(self, wavelength):
        return self._perturbed(self.base.extrapolated_index(wavelength))

    def _perturbed(self, n):
        # nd at the d line even where the base's data do not cover it (infrared glasses)
        nd = self.base.extrapolated_index(jnp.asarray(LAMBDA_D, jnp.result_type(n)))
        s = (nd + self.delta_nd - 1.0) / ((nd - 1.0) * (1.0 + self.abbe_rel))
        return n + self.delta_nd + (s - 1.0) * (n - nd)


class Perturbation(eqx.Module):
    """Changes to a lens's numbers, one entry per surface (see module docstring)."""

    radius_rel: Float[Array, " n"]
    thickness: Float[Array, " n"]
    conic: Float[Array, " n"]
    asphere: tuple[Float[Array, " m"], ...]
    irregularity: Float[Array, " n"]
    index: Float[Array, " n"]
    abbe_rel: Float[Array, " n"]
    # per element (``tolerance_rigid.element_groups``), or [0] when not toleranced
    decenter_x: Float[Array, " g"]
    decenter_y: Float[Array, " g"]
    tilt_x: Float[Array, " g"]
    tilt_y: Float[Array, " g"]


def _refuse_surfaces(lens: Lens, where: str) -> None:
    """Refuse odd aspheres: their β_i r^i terms would stay untoleranced without a word (so
    would a diffractive ``Binary2``'s phase or a ``Grating``'s lines);
    paraxial surfaces, which have no shape to perturb (perturbing them failed deep in JAX). And
    tilted planes (on the image too): they break the rotational symmetry that the field
    folding and the back-focus compensator assume, and their c and k are fixed."""
    if not isinstance(lens, Lens):  # before: an AttributeError on .surfaces
        raise TypeError(f"{where}: lens must be a jaxlens.Lens, got {type(lens).__name__}")
    for i, s in enumerate((*lens.surfaces, lens.image)):
        name = f"surface {i + 1}" if i < lens.num_surfaces else "the image surface"
        if isinstance(s, ParaxialSurface):
            raise ValueError(f"{where}: {name} is a ParaxialSurface (an ideal thin lens): it "
                             f"has no radius, conic or aspheric terms to perturb, so tolerance "
                             f"analysis does not support it")
        if isinstance(s, DIFFRACTIVE):
            raise ValueError(f"{where}: {name} is a {type(s).__name__} (diffractive) surface; "
                             f"tolerance analysis perturbs shapes and glasses only, and would "
                             f"leave its phase untoleranced, so it does not support it")
        if isinstance(s, TiltedPlane):
            raise ValueError(f"{where}: {name} is a TiltedPlane; tolerance analysis assumes "
                             f"a rotationally symmetric lens and a flat image normal to the "
                             f"axis, and does not support tilted surfaces")
        if isinstance(s, QTypeAsphere):
            # Its a_m are no even series: the asphere tolerances (sensitivity) passed them by
            # without a row in the table, and the radius tolerance scales the base conic's c,
            # not the vertex curvature c + 2 Σ a_m Q_m(0)/ρ_n² of a Q-bfs surface.
            raise ValueError(f"{where}: {name} is a QTypeAsphere (Forbes Q-{s.qtype}); "
                             f"tolerance analysis perturbs even-asphere terms only and would "
                             f"leave its Q-type terms untoleranced, so it does not support it")
        if i < lens.num_surfaces and s.radial_coeffs().shape[0]:
            raise ValueError(f"{where}: surface {i + 1} is a {type(s).__name__}; tolerance "
                             f"analysis of the radial terms β_i r^i of an odd asphere is not "
                             f"supported (asphere tolerances act on even terms only)")
        if isinstance(s, Hybrid) and not checks.is_traced(s.odd_x) and (
                np.any(np.asarray(s.odd_x) != 0) or np.any(np.asarray(s.odd_y) != 0)):
            raise ValueError(f"{where}: {name} is a Hybrid with odd x³, y³, … terms; tolerance "
                             f"analysis perturbs radius, conic and even terms only and would "
                             f"leave them untoleranced, so it does not support it")
        if type(s) not in _TOLERANCED:
            # Any other kind (a toroid's radius of rotation, a freeform's terms) would keep
            # shape numbers that no tolerance moves, without a word.
            raise ValueError(f"{where}: {name} is a {type(s).__name__}; tolerance analysis "
                             f"perturbs the radius, conic and even aspheric terms of "
                             f"Standard, EvenAsphere and Hybrid surfaces without odd terms "
                             f"(coordinate breaks pass unchanged) and would leave its other "
                             f"shape numbers untoleranced, so it does not support it")


_TOLERANCED = frozenset({Standard, EvenAsphere, Hybrid, CoordinateBreak})
"""Surface kinds whose every shape number a tolerance moves (a break has none; a hybrid
only with its odd terms zero)."""


def zero_perturbation(lens: Lens, *, elements: bool = False) -> Perturbation:
    """The perturbation that changes nothing (float64 when x64 is on); with ``elements``,
    with a decenter and tilt entry per element (otherwise those arrays are empty)."""
    _refuse_surfaces(lens, "zero_perturbation")
    if checks.switch(elements, "elements", "zero_perturbation"):  # "no" was truthy
        rigid.check_lens(lens, "zero_perturbation")
    n = lens.num_surfaces
    z = jnp.zeros(n, lens.thickness.dtype)
    g = jnp.zeros(len(rigid.element_groups(lens)) if elements else 0, lens.thickness.dtype)
    return Perturbation(z, z, z, tuple(jnp.zeros_like(s.even_coeffs()) for s in lens.surfaces),
                        z, z, z, g, g, g, g)


def _check_against_lens(lens: Lens, tol: Tolerances, clear_radius, where: str) -> None:
    """The thickness tolerance must be below every glass thickness of the lens (an element
    thinner than zero has its surfaces crossed, which the trace does not see: its spots are
    numbers, not a refusal), and the decenter below every clear semi-diameter (mm)."""
    t = np.abs(np.asarray(lens.thickness, float))
    glass = [i for i, m in enumerate(lens.materials) if not isinstance(m, Air)]
    if glass and tol.thickness >= float(np.min(t[glass])):
        i = glass[int(np.argmin(t[glass]))]
        raise ValueError(
            f"{where}: Tolerances.thickness ±{tol.thickness:g} mm must be below the lens's "
            f"thinnest glass thickness, {float(t[i]):g} mm after surface {i} (0-based): the "
            f"perturbed element would be {float(t[i]) - tol.thickness:g} mm thick")
    h = np.asarray(clear_radius, float)
    ref = [i for i, r in enumerate(refracting(lens)) if r and np.isfinite(h[i]) and h[i] > 0]
    if ref and tol.decenter >= float(np.min(h[ref])):
        # An element moved by its own clear radius puts its edge on the axis: 1e6 mm passed.
        i = ref[int(np.argmin(h[ref]))]
        raise ValueError(
            f"{where}: Tolerances.decenter ±{tol.decenter:g} mm must be below the lens's "
            f"smallest clear semi-diameter, {float(h[i]):g} mm at surface {i} (0-based)")


def refracting(lens: Lens) -> list[bool]:
    """Whether each surface separates two media (not air on both sides)."""
    media = [lens.object_material, *lens.materials]
    return [not (isinstance(a, Air) and isinstance(b, Air))
            for a, b in zip(media[:-1], media[1:], strict=True)]


def perturb(lens: Lens, p: Perturbation, clear_radius, *, add_r4: tuple[bool, ...] | None = None
            ) -> Lens:
    """The lens with perturbation ``p`` applied (jittable, differentiable in ``p``).

    Args:
        lens: the nominal lens.
        p: the perturbation.
        clear_radius: ``[n]`` clear semi-diameters (mm) that scale the irregularity.
        add_r4: per surface, give a surface without an r⁴ coefficient one (an
            ``EvenAsphere``) so that irregularity can act on it; static. Default: none.

    When ``p``'s decenter and tilt arrays are not empty (one entry per element), the elements
    are then moved between coordinate breaks (``tolerance_rigid.displace``).
    """
    _refuse_surfaces(lens, "perturb")
    if not isinstance(p, Perturbation):  # before: an AttributeError on .radius_rel
        raise TypeError(f"perturb: p must be a Perturbation (zero_perturbation(lens) or a "
                        f"draw of monte_carlo), got {type(p).__name__}")
    rigid.check_perturb_args(lens, p, clear_radius, add_r4, "perturb")
    add_r4 = add_r4 or (False,) * lens.num_surfaces
    surfaces = []
    for i, s in enumerate(lens.surfaces):
        c = s.c / (1.0 + p.radius_rel[i])
        k = s.k + p.conic[i]
        r4 = p.irregularity[i] / clear_radius[i] ** 4
        a = s.even_coeffs()
        if a.shape[0]:
            a = a + p.asphere[i]
            if a.shape[0] >= 2:
                a = a.at[1].add(r4)
            s2 = eqx.tree_at(lambda x: (x.c, x.k, x.coeffs), s, (c, k, a))
        elif add_r4[i]:
            if not isinstance(s, Standard):
                raise ValueError(f"perturb: surface {i + 1} ({type(s).__name__}) has no even "
                                 "series to carry an irregularity")
            s2 = EvenAsphere(c=c, k=k, coeffs=jnp.stack([jnp.zeros_like(r4), r4]),
                             semi_diameter=s.semi_diameter)
        else:
            s2 = eqx.tree_at(lambda x: (x.c, x.k), s, (c, k))
        surfaces.append(s2)
    materials = tuple(m if isinstance(m, Air) else
                      PerturbedMaterial(m, p.index[i], p.abbe_rel[i], getattr(m, "name", ""))
                      for i, m in enumerate(lens.materials))
    out = eqx.tree_at(lambda x: (x.surfaces, x.thickness, x.materials), lens,
                      (tuple(surfaces), lens.thickness + p.thickness, materials))
    if p.decenter_x.shape[0] == 0:  # static: no element motion, no coordinate breaks
        return out
    return rigid.displace(out, p.decenter_x, p.decenter_y, p.tilt_x, p.tilt_y)


def symmetric_fields(fields) -> tuple[np.ndarray, np.ndarray]:
    """Fold 2-D fields (θx, θy) onto their distinct representatives under the square's
    symmetries (sign flips, x ↔ y): ``(fields [K, 2] deg, weights [K] = multiplicities)``.

    A mean over the representatives weighted by ``weights`` equals the mean over all fields
    for a rotationally symmetric lens traced with a pupil grid that has those symmetries
    (the default 21 × 21 grid has). Not for a model with element decenter or tilt
    (``Tolerances.decenter``/``tilt`` > 0): a moved element breaks that symmetry, and the
    folded mean is then not the full mean; give such a model the full field set.
    """
    f = np.asarray(fields, float)
    if f.ndim == 1:
        f = np.stack([np.zeros_like(f), f], -1)
    if f.ndim != 2 or f.shape[-1] != 2 or f.shape[0] == 0:
        raise ValueError(f"symmetric_fields: fields must be [F] or [F, 2] degrees with F >= 1, "
                         f"got shape {np.shape(fields)}")
    checks.field_angles(f, "symmetric_fields", "fields")
    key = np.sort(np.abs(f), axis=-1)
    rounded = np.round(key, 9)
    _, first, counts = np.unique(rounded, axis=0, return_index=True, return_counts=True)
    return key[first], counts.astype(float)


# ------------------------------------------------------------------------ the model
def _check_fields(fields, weights, where, heights=False):
    unit = "mm (object heights of an object-space telecentric lens)" if heights else "degrees"
    # Before: np.asarray(["0", "5"], float) read strings as their numbers, bools as 0 and 1.
    checks.real_values(fields, "fields", where, unit)
    if weights is not None:
        checks.real_values(weights, "field_weights", where, "relative weights")
    f = np.asarray(fields, float)
    if f.ndim not in (1, 2) or f.shape[0] == 0 or (f.ndim == 2 and f.shape[1] != 2) \
            or not np.all(np.isfinite(f)):
        raise ValueError(f"{where}: fields must be finite [F] or [F, 2] {unit} with F >= 1, "
                         f"got shape {f.shape}")
    if not heights:  # a telecentric lens's 95 mm height was refused as 95°
        checks.field_angles(f, where, "fields")  # 95° would wrap, found only after the trials
        checks.warn_if_radian_fields(f, where, "fields")  # np.radians([0, 10, 20])
    w = np.ones(f.shape[0]) if weights is None else np.asarray(weights, float)
    if w.shape != (f.shape[0],) or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
        raise ValueError(f"{where}: field_weights must be [{f.shape[0]}] finite numbers >= 0 "
                         f"with a positive sum, got {weights!r}")
    return f, w


class ToleranceModel:
    """A lens, its evaluation fields and the parameters that tolerancing may change.

    Args:
        lens: the nominal lens (analysed in float64 when x64 is on).
        fields: field angles (deg), ``[F]`` (y) or ``[F, 2]``; default ``lens.fields``
            (object heights in mm for an object-space telecentric lens). Stored as
            ``[F, 2]`` (θx, θy) pairs (``self.fields``).
        field_weights: ``[F]`` weights of the field mean (default equal).
        wavelengths: µm (default ``lens.wavelengths``).
        pupil: ``[M, 2]`` unit-pupil points (default the 21 × 21 grid).
        tolerances: the ``Tolerances``.
        batch: lenses traced together in one vmapped call.
        apertures: "open" (default): every surface but the stop loses its semi-diameter for
            the analysis, as Zemax's automatic (floating) semi-diameters do, so a perturbed
            beam is not clipped by apertures drawn exactly around the nominal beam; "lens":
            keep the lens's semi-diameters (perturbed beams can then be vignetted). The
            irregularity is scaled by the nominal clear semi-diameters either way.
    """

    def __init__(self, lens: Lens, *, fields=None, field_weights=None, wavelengths=None,
                 pupil=None, tolerances: Tolerances | None = None, batch: int = 25,
                 apertures: str = "open"):
        checks.focal_image(lens, "ToleranceModel")  # its metrics are spot sizes in µm
        checks.lens_intact(lens, "ToleranceModel")
        _refuse_surfaces(lens, "ToleranceModel")
        self.tolerances = Tolerances() if tolerances is None else tolerances
        if not isinstance(self.tolerances, Tolerances):
            raise ValueError(f"ToleranceModel: tolerances must be a Tolerances, got "
                             f"{type(tolerances).__name__}")
        f, w = _check_fields(lens.fields if fields is None else fields, field_weights,
                             "ToleranceModel", lens.telecentric_object)
        if isinstance(batch, bool) or not (isinstance(batch, (int, np.integer)) and batch >= 1):
            raise ValueError(f"ToleranceModel: batch must be a whole number >= 1, got {batch!r}")
        batch = int(batch)
        dtype = jnp.result_type(float)
        for arg, v, unit in (("wavelengths", wavelengths, "µm"),
                             ("pupil", pupil, "normalised pupil")):  # "0.55" read as 0.55
            if v is not None:
                checks.real_values(v, arg, "ToleranceModel", unit)
        if wavelengths is not None and (np.ndim(wavelengths) > 1 or np.size(wavelengths) == 0):
            raise ValueError(f"ToleranceModel: wavelengths must be µm, one value or [W] with "
                             f"W >= 1, got shape {np.shape(wavelengths)}")
        self.lens = lens.astype(dtype)
        # Stored as (θx, θy) pairs [F, 2]: a [2] array of θy was read as one (θx, θy) field
        # where the fields are turned into directions (field_xy: the MTF's T and S axes).
        self.fields = jnp.asarray(f if f.ndim == 2 else np.stack([np.zeros_like(f), f], -1),
                                  dtype)
        self.weights = jnp.asarray(w, dtype)
        self.wavelengths = jnp.asarray(
            self.lens.wavelengths if wavelengths is None else jnp.atleast_1d(
                jnp.asarray(wavelengths, dtype)), dtype)
        self.pupil = pupil_grid(21, dtype) if pupil is None else jnp.asarray(pupil, dtype)
        # Checked here: monte_carlo and sensitivity would fail only after compiling the trials.
        checks.wavelengths(self.lens, self.wavelengths, "ToleranceModel", "wavelengths")
        checks.primary_wavelength(self.lens, "ToleranceModel", "the paraxial data's")
        if self.pupil.ndim != 2 or self.pupil.shape[0] == 0 or self.pupil.shape[1] != 2:
            raise ValueError(f"ToleranceModel: pupil must be [M, 2] unit-pupil points with "
                             f"M >= 1, got shape {np.shape(pupil)}")
        checks.values(self.pupil, "pupil", "ToleranceModel", lo=-1, hi=1,
                      unit="(normalised pupil)")
        # batch=10**9 padded every chunk to a billion lenses (hours, or memory exhausted).
        checks.working_memory(batch * self.fields.shape[0] * self.wavelengths.size
                              * self.pupil.shape[0], len(lens.surfaces) + 4,
                              jnp.dtype(dtype).itemsize, "ToleranceModel",
                              "batch × fields × wavelengths × pupil points", "lower batch")
        self.batch = batch
        if apertures not in ("open", "lens"):
            raise ValueError(f"ToleranceModel: apertures must be 'open' or 'lens', got "
                             f"{apertures!r}")
        self.clear_radius = clear_semi_diameters(self.lens)
        if apertures == "open":
            inf = jnp.asarray(jnp.inf, dtype)
            self.lens = eqx.tree_at(lambda x: x.surfaces, self.lens, tuple(
                s if i == self.lens.stop else eqx.tree_at(lambda y: y.semi_diameter, s, inf)
                for i, s in enumerate(self.lens.surfaces)))
        self.apertures = apertures
        tol = self.tolerances
        _check_against_lens(self.lens, tol, self.clear_radius, "ToleranceModel")
        # Static: elements move (two coordinate breaks each) only when toleranced.
        self.elements = bool(tol.decenter > 0 or tol.tilt > 0)
        zero = zero_perturbation(self.lens, elements=self.elements)
        self.zero, self.unravel = ravel_pytree(zero)
        self.num_elements = len(rigid.element_groups(self.lens)) if self.elements else 0
        self.refracting = refracting(self.lens)
        self.add_r4 = tuple(bool(tol.irregularity > 0 and ref and s.even_coeffs().shape[0] < 2)
                            for s, ref in zip(self.lens.surfaces, self.refracting, strict=True))
        self.names, self.units, self.kinds = self._labels()
        # Fields, wavelengths and pupil were checked above: the traced re-checks go.
        trusting = checks.checked_core(eqx.filter_jit)
        self._chunk = trusting(jax.vmap(self._one, in_axes=(0, None)))
        self._grad = trusting(jax.value_and_grad(self._metric_at))

    def with_tolerances(self, tolerances: Tolerances) -> ToleranceModel:
        """The same model (its compiled functions too) under other tolerances.

        Raises ValueError if the change needs another lens structure (irregularity switched on
        for a surface that has no r⁴ term); build a new model then.
        """
        if not isinstance(tolerances, Tolerances):
            raise ValueError(f"with_tolerances: expected Tolerances, got "
                             f"{type(tolerances).__name__}")
        _check_against_lens(self.lens, tolerances, self.clear_radius, "with_tolerances")
        needs = any(tolerances.irregularity > 0 and ref and s.even_coeffs().shape[0] < 2
                    and not add for s, ref, add in zip(self.lens.surfaces, self.refracting,
                                                        self.add_r4, strict=True))
        if needs:
            raise ValueError("with_tolerances: irregularity > 0 needs r^4 terms this model was "
                             "built without; build a new ToleranceModel")
        if (tolerances.decenter > 0 or tolerances.tilt > 0) and not self.elements:
            raise ValueError("with_tolerances: decenter or tilt > 0 needs the coordinate breaks "
                             "this model was built without; build a new ToleranceModel")
        out = copy.copy(self)
        out.tolerances = tolerances
        return out

    def _glass_labels(self) -> dict[int, str]:
        """Label of each glass (``materials`` index): its element numbered as the rigid
        decenter and tilt labels number it (a cemented group is one element), with the
        surfaces it spans where the element holds more than one glass."""
        lens = self.lens
        out = {}
        for j, (a, b) in enumerate(rigid.element_groups(lens)):
            for i in range(a, b):  # materials[i] lies between surfaces i and i + 1 (0-based)
                m = lens.materials[i]
                name = getattr(m, "name", "") or type(m).__name__
                out[i] = (f"E{j + 1} ({name})" if b - a == 1
                          else f"E{j + 1} S{i + 1}-S{i + 2} ({name})")
        for i, m in enumerate(lens.materials):  # glass touching object or image space
            if i not in out and not isinstance(m, Air):
                out[i] = f"S{i + 1}-S{i + 2} ({getattr(m, 'name', '') or type(m).__name__})"
        return out

    # labels of every entry of the flat perturbation vector
    def _labels(self):
        lens = self.lens
        n = lens.num_surfaces
        glass = self._glass_labels()
        per = {
            "radius_rel": [(f"S{i + 1} radius", "relative", "radius") for i in range(n)],
            "thickness": [(f"T{i + 1} thickness" + (" (image distance)" if i == n - 1 else ""),
                           "mm", "thickness") for i in range(n)],
            "conic": [(f"S{i + 1} conic", "1", "conic") for i in range(n)],
            "asphere": [[(f"S{i + 1} A{2 * (j + 1)}", f"mm^{1 - 2 * (j + 1)}", "asphere")
                         for j in range(s.even_coeffs().shape[0])]
                        for i, s in enumerate(lens.surfaces)],
            "irregularity": [(f"S{i + 1} irregularity", "mm", "irregularity") for i in range(n)],
            "index": [(f"{glass.get(i, f'M{i + 1}')} nd", "1", "index") for i in range(n)],
            "abbe_rel": [(f"{glass.get(i, f'M{i + 1}')} Vd", "relative", "abbe")
                         for i in range(n)],
        }
        moved = rigid.labels(lens) if self.elements else [[]] * len(rigid.FIELDS)
        per.update(zip(rigid.FIELDS, moved, strict=True))
        labels = Perturbation(**{k: (tuple(v) if k == "asphere" else v) for k, v in per.items()})
        leaves = jax.tree_util.tree_leaves(labels, is_leaf=lambda x: isinstance(x, tuple)
                                           and len(x) == 3 and isinstance(x[0], str))
        if len(leaves) != self.zero.size:
            raise AssertionError("ToleranceModel: labels do not match the perturbation vector")
        names, units, kinds = zip(*leaves, strict=True) if leaves else ((), (), ())
        return list(names), list(units), list(kinds)

    def tolerance_vector(self, *, sensitivity: bool) -> np.ndarray:
        """Half-range of every perturbation entry (0 = not toleranced).

        Monte-Carlo (``sensitivity=False``): radius, thickness, index, Abbe, irregularity.
        Sensitivity: radius, thickness, conic, every asphere term, index, Abbe.
        Both: element decenter and tilt, when the model moves elements.
        """
        lens, tol = self.lens, self.tolerances
        n = lens.num_surfaces
        curved = [ref and float(s.c) != 0.0 for s, ref in zip(lens.surfaces, self.refracting,
                                                                strict=True)]
        glass = [not isinstance(m, Air) for m in lens.materials]
        dispersive = [g and math.isfinite(float(abbe_number(m, held_ends=True)))
                      for g, m in zip(glass, lens.materials, strict=True)]
        h = np.asarray(self.clear_radius, float)
        f = lambda flags, v: np.where(flags, v, 0.0)  # noqa: E731
        asph = tuple(
            np.asarray([tol.asphere_sag / h[i] ** (2 * (j + 1)) if (sensitivity and
                        self.refracting[i]) else 0.0 for j in range(s.even_coeffs().shape[0])])
            for i, s in enumerate(lens.surfaces))
        p = Perturbation(
            radius_rel=f(curved, tol.radius_rel),
            thickness=np.full(n, tol.thickness),
            conic=f(curved, tol.conic if sensitivity else 0.0),
            asphere=asph,
            irregularity=f(self.refracting, 0.0 if sensitivity else tol.irregularity),
            index=f(glass, tol.index),
            abbe_rel=f(dispersive, tol.abbe_rel),
            **{k: np.full(self.num_elements, tol.decenter if k.startswith("decenter") else tol.tilt)
               for k in rigid.FIELDS},
        )
        return np.asarray(ravel_pytree(jax.tree_util.tree_map(jnp.asarray, p))[0])

    def lens_at(self, pvec) -> Lens:
        """The lens perturbed by the flat vector ``pvec``."""
        return perturb(self.lens, self.unravel(pvec), self.clear_radius, add_r4=self.add_r4)

    def data_at(self, pvec) -> SpotData:
        return spot_data(self.lens_at(pvec), self.fields, self.wavelengths, self.pupil)

    def _metric_at(self, pvec):
        return mean_rms_um(self.data_at(pvec), self.weights)

    def _one(self, pvec, frequency):
        lens = self.lens_at(pvec)
        data = spot_data(lens, self.fields, self.wavelengths, self.pupil)
        dz = best_focus(data, self.weights)
        fnum = paraxial.paraxial_data(lens).working_fnum
        alpha = normalised_weights(self.weights)
        return {
            "rms_um": mean_rms_um(data, self.weights),
            "rms_compensated_um": mean_rms_um(data, self.weights, dz),
            "refocus_mm": dz,
            "mtf": jnp.sum(alpha * field_mtf(data, self.fields, self.wavelengths, frequency,
                                             fnum, 0.0, lens.telecentric_object)),
            "mtf_compensated": jnp.sum(alpha * field_mtf(data, self.fields, self.wavelengths,
                                                         frequency, fnum, dz,
                                                         lens.telecentric_object)),
            "min_valid_fraction": jnp.min(jnp.mean(data.weight, -1)),
        }

    def evaluate(self, pvecs, *, mtf_frequency: float = 0.0) -> dict[str, np.ndarray]:
        """Evaluate ``[B, P]`` perturbation vectors, ``batch`` lenses per vmapped call."""
        v = np.asarray(pvecs, float).reshape(-1, self.zero.size)
        out = []
        freq = jnp.asarray(mtf_frequency, self.zero.dtype)
        for start in range(0, v.shape[0], self.batch):
            chunk = v[start:start + self.batch]
            pad = self.batch - chunk.shape[0]
            full = np.concatenate([chunk, np.zeros((pad, v.shape[1]))]) if pad else chunk
            res = self._chunk(jnp.asarray(full, self.zero.dtype), freq)
            out.append({k: np.asarray(x)[:chunk.shape[0]] for k, x in res.items()})
        return {k: np.concatenate([o[k] for o in out]) for k in out[0]} if out else {}

    def gradient(self) -> tuple[float, np.ndarray]:
        """(nominal metric µm, d metric / d pvec) in one reverse-mode pass."""
        val, g = self._grad(self.zero)
        return float(val), np.asarray(g)

    def nominal_values(self) -> np.ndarray:
        """The nominal value of every entry's parameter (R mm, t mm, k, a_i, nd, Vd)."""
        lens = self.lens
        dtype = np.float64
        c = np.asarray([float(s.c) for s in lens.surfaces], dtype)
        radius = np.where(c != 0, 1.0 / np.where(c != 0, c, 1.0), np.inf)
        nd = [float(m.extrapolated_index(jnp.asarray(LAMBDA_D))) for m in lens.materials]
        vd = [float(abbe_number(m, held_ends=True)) if not isinstance(m, Air) else np.inf
              for m in lens.materials]
        p = Perturbation(
            radius_rel=radius, thickness=np.asarray(lens.thickness, dtype),
            conic=np.asarray([float(s.k) for s in lens.surfaces], dtype),
            asphere=tuple(np.asarray(s.even_coeffs(), dtype) for s in lens.surfaces),
            irregularity=np.zeros(lens.num_surfaces, dtype), index=np.asarray(nd, dtype),
            abbe_rel=np.asarray(vd, dtype),
            **{k: np.zeros(self.num_elements, dtype) for k in rigid.FIELDS})
        return np.asarray(ravel_pytree(jax.tree_util.tree_map(jnp.asarray, p))[0])


# ------------------------------------------------------------------------- analyses
def percentile(values, q: float) -> float:
    """The q-th percentile (0–100) with linear interpolation between order statistics
    (numpy's default); NaN counts as +inf (a failed trial is the worst trial). A q in
    (0, 1) is warned about: a fraction (0.95 for the 95th) reads as the 0.95th percentile."""
    checks.real_values(q, "q", "percentile", "percent")  # "95" compared as a string
    q = checks.number(q, "q", "percentile", lo=0, hi=100, unit="percent")
    if 0 < q < 1:
        warnings.warn(f"percentile: q = {q:g} is the {q:g}th percentile (q is in percent, "
                      f"0–100); for a fraction, pass {q * 100:g}", stacklevel=2)
    checks.real_values(values, "values", "percentile")
    v = np.sort(np.where(np.isnan(np.asarray(values, float)), np.inf,
                         np.asarray(values, float)).ravel())
    if v.size == 0:
        raise ValueError("percentile: values must hold at least one number")
    x = q / 100 * (v.size - 1)
    lo, hi = int(math.floor(x)), int(math.ceil(x))
    frac = x - lo
    if frac == 0 or v[lo] == v[hi]:
        return float(v[lo])
    return float(v[lo] + frac * (v[hi] - v[lo]))


def yield_fraction(rms_um, threshold_um: float, valid_fraction=None,
                   min_valid: float = 0.99) -> float:
    """Fraction of trials with RMS ≤ threshold (µm) and, when given, ≥ ``min_valid`` of
    every field's rays reaching the image; non-finite RMS fails."""
    checks.number(threshold_um, "threshold_um", "yield_fraction", lo=0, lo_open=True, unit="µm")
    checks.number(min_valid, "min_valid", "yield_fraction", lo=0, hi=1,
                  unit="(fraction of a field's rays)")
    checks.real_values(rms_um, "rms_um", "yield_fraction", "µm")  # "1" read as 1
    r = np.asarray(rms_um, float)
    if r.size == 0:  # np.mean of nothing: NaN and a RuntimeWarning
        raise ValueError("yield_fraction: rms_um must hold at least one trial's RMS (µm)")
    if np.any(r < 0):  # -1 passed every threshold
        raise ValueError(f"yield_fraction: rms_um must be RMS radii >= 0 µm, got {r.min():g} µm")
    ok = np.isfinite(r) & (r <= threshold_um)
    if valid_fraction is not None:
        # 99 (percent) passed every trial; a [3] for 2 trials broadcast or failed in numpy.
        checks.real_values(valid_fraction, "valid_fraction", "yield_fraction",
                           "fraction of a field's rays")
        vf = np.asarray(valid_fraction, float)
        if vf.shape != r.shape:
            raise ValueError(f"yield_fraction: valid_fraction must have rms_um's shape "
                             f"{r.shape} (one fraction a trial), got shape {vf.shape}")
        checks.values(vf, "valid_fraction", "yield_fraction", lo=0, hi=1,
                      unit="(fraction of a field's rays)")
        ok &= vf >= min_valid
    return float(np.mean(ok))


def _model(model, where: str) -> None:
    """Refuse anything but a ToleranceModel (a Lens failed as an AttributeError inside)."""
    if not isinstance(model, ToleranceModel):
        raise TypeError(f"{where}: model must be a ToleranceModel (ToleranceModel(lens, ...)), "
                        f"got {type(model).__name__}")


def sensitivity(model: ToleranceModel, *, check: int | None = None) -> dict:
    """d(metric)/d(parameter) for every toleranced parameter from one reverse-mode pass,
    with a finite-difference check at ± each tolerance.

    Returns a dict with ``nominal_rms_um`` and ``rows``: for each parameter its name, unit,
    nominal value, tolerance, ``gradient_um_per_unit`` (autodiff), ``delta_rms_um`` =
    gradient × tolerance (first order), ``delta_rms_plus_um`` / ``delta_rms_minus_um``
    (re-traced change at ± tolerance), ``second_order_um`` = (r₊ + r₋ − 2 r₀)/2, the
    curvature term the first order leaves out, ``fd_gradient_um_per_unit`` = (r₊ − r₋)/(2
    tolerance) and ``delta_rms_compensated_um`` (worst of ± after refocusing, against the
    refocused nominal). With ``check`` = k only the k parameters with the largest
    |gradient × tolerance| are re-traced (the others' check fields are None); None checks all.
    Element decenters and tilts are always re-traced: on a symmetric lens and field set the
    metric is even in them, so their gradient is 0 and the change is second order
    (``second_order_um``), which a ranking by gradient would never pick.
    """
    _model(model, "sensitivity")
    if check is not None and (isinstance(check, bool)
                              or not isinstance(check, (int, np.integer)) or check < 0):
        raise ValueError(f"sensitivity: check must be None or a whole number >= 0 of "
                         f"parameters, got {check!r}")
    nominal, g = model.gradient()
    tol = model.tolerance_vector(sensitivity=True)
    listed = np.nonzero(tol)[0]
    idx = listed
    if check is not None:
        moved = [i for i in listed if model.kinds[i] in ("decenter", "tilt")]
        coaxial = np.asarray([i for i in listed if i not in set(moved)], int)
        ranked = coaxial[np.argsort(-np.abs(g[coaxial] * tol[coaxial]))[:check]]
        idx = np.sort(np.concatenate([ranked, np.asarray(moved, int)]))
    steps = np.zeros((idx.size, tol.size))
    steps[np.arange(idx.size), idx] = tol[idx]
    res = model.evaluate(np.concatenate([steps, -steps, np.zeros((1, tol.size))]))
    k = idx.size
    r_p, r_m = res["rms_um"][:k], res["rms_um"][k:2 * k]
    c_p, c_m = res["rms_compensated_um"][:k], res["rms_compensated_um"][k:2 * k]
    c0 = res["rms_compensated_um"][-1]
    values = model.nominal_values()
    at = {int(i): j for j, i in enumerate(idx)}
    rows = []
    for i in listed:
        t = float(tol[i])
        row = {"parameter": model.names[i], "unit": model.units[i], "nominal": float(values[i]),
               "tolerance": t, "gradient_um_per_unit": float(g[i]),
               "delta_rms_um": float(g[i] * t)}
        j = at.get(int(i))
        row.update({
            "delta_rms_plus_um": None if j is None else float(r_p[j] - nominal),
            "delta_rms_minus_um": None if j is None else float(r_m[j] - nominal),
            "second_order_um": None if j is None else float(0.5 * (r_p[j] + r_m[j]
                                                                   - 2 * nominal)),
            "fd_gradient_um_per_unit": None if j is None else float((r_p[j] - r_m[j])
                                                                    / (2 * t)),
            "delta_rms_compensated_um": None if j is None else float(max(c_p[j], c_m[j]) - c0),
        })
        rows.append(row)
    return {"nominal_rms_um": nominal, "nominal_rms_compensated_um": float(c0), "rows": rows}


def sample_perturbations(model: ToleranceModel, trials: int, key) -> np.ndarray:
    """``[trials, P]`` random perturbation vectors under the Monte-Carlo tolerances."""
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or not (
            1 <= trials <= MAX_TRIALS):  # 1e10 failed allocating [trials, P] perturbations
        raise ValueError(f"monte_carlo: trials must be a whole number >= 1 and <= "
                         f"{MAX_TRIALS}, got {trials!r}")
    checks.prng_key(key, "sample_perturbations")  # JAX's own error named no argument
    _model(model, "sample_perturbations")
    tol = model.tolerance_vector(sensitivity=False)
    shape = (int(trials), tol.size)
    if model.tolerances.distribution == "uniform":
        x = jax.random.uniform(key, shape, minval=-1.0, maxval=1.0)
    else:
        x = 0.5 * jax.random.truncated_normal(key, -2.0, 2.0, shape)
    return np.asarray(x, float) * tol


def monte_carlo(model: ToleranceModel, *, trials: int = 200, key=None,
                threshold_um: float, mtf_frequency: float, min_valid: float = 0.99) -> dict:
    """Monte-Carlo tolerancing with the back-focus compensator.

    Args:
        model: the ``ToleranceModel``.
        trials: number of random lenses (>= 1).
        key: ``jax.random`` key (default ``PRNGKey(0)``).
        threshold_um: RMS (µm, the module's metric after refocusing) a lens must meet.
        mtf_frequency: cycles/mm at which the MTF is reported.
        min_valid: a trial also fails when a field gets fewer than this fraction of its rays
            to the image.

    Returns:
        A dict: ``trials``, per-trial arrays (``rms_um``, ``rms_compensated_um``,
        ``refocus_mm``, ``mtf``, ``mtf_compensated``, ``min_valid_fraction``), and the
        summary (``rms_p50_um``, ``rms_p90_um`` after refocusing, the same without it,
        ``mtf_p50``/``mtf_p10`` after refocusing, ``yield``, ``threshold_um``).
    """
    threshold_um = _positive(threshold_um, "threshold_um", "µm")
    if threshold_um < MIN_THRESHOLD_UM:  # 0.006 (mm) meant 6 µm: every trial would fail
        raise ValueError(f"monte_carlo: threshold_um {threshold_um:g} µm is below "
                         f"{MIN_THRESHOLD_UM:g} µm, far inside any diffraction spot; it is in "
                         f"µm (was it given in mm? {threshold_um:g} mm is "
                         f"{threshold_um * 1e3:g} µm)")
    # Checked before the trials: yield_fraction refused a bad min_valid after all of them.
    checks.number(min_valid, "min_valid", "monte_carlo", lo=0, hi=1,
                  unit="(fraction of a field's rays)")
    checks.prng_key(key, "monte_carlo", optional=True)
    checks.real_values(mtf_frequency, "mtf_frequency", "monte_carlo", "cycles/mm")
    if not (math.isfinite(float(mtf_frequency)) and float(mtf_frequency) >= 0):
        raise ValueError(f"monte_carlo: mtf_frequency must be a finite number >= 0 cycles/mm, "
                         f"got {mtf_frequency!r}")
    _model(model, "monte_carlo")  # after the options (their checks need no model)
    key = jax.random.PRNGKey(0) if key is None else key
    x = sample_perturbations(model, trials, key)
    res = model.evaluate(np.concatenate([np.zeros((1, x.shape[1])), x]),
                         mtf_frequency=float(mtf_frequency))
    nom = {k: float(v[0]) for k, v in res.items()}
    per = {k: v[1:] for k, v in res.items()}
    rc, r0 = per["rms_compensated_um"], per["rms_um"]
    return {
        "trials": int(trials),
        "nominal": nom,
        "per_trial": per,
        "rms_p50_um": percentile(rc, 50), "rms_p90_um": percentile(rc, 90),
        "rms_mean_um": float(np.mean(rc)),
        "rms_uncompensated_p50_um": percentile(r0, 50),
        "rms_uncompensated_p90_um": percentile(r0, 90),
        "mtf_frequency_cycles_per_mm": float(mtf_frequency),
        "mtf_p50": -percentile(-per["mtf_compensated"], 50),
        "mtf_p10": -percentile(-per["mtf_compensated"], 90),
        "refocus_p50_mm": percentile(per["refocus_mm"], 50),
        "refocus_abs_p90_mm": percentile(np.abs(per["refocus_mm"]), 90),
        "threshold_um": threshold_um,
        "min_valid": min_valid,
        "yield": yield_fraction(rc, threshold_um, per["min_valid_fraction"], min_valid),
        "yield_uncompensated": yield_fraction(r0, threshold_um, per["min_valid_fraction"],
                                              min_valid),
    }


def _positive(value, name, unit):
    try:  # float("5") would read a string as a number, float(True) as 1
        v = float("nan") if isinstance(value, (str, bytes, bool)) else float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"monte_carlo: {name} must be a finite number > 0 {unit}, got "
                         f"{value!r}")
    return v
