"""The design variables of a lens, scaled to order 1, and their map back to a ``Lens``.

Conventions:
    Each optical surface ``s`` (every surface but the stop) has a normalisation radius
    ``r_s`` (mm, about its expected clear semi-diameter). The optimiser sees

    * ``c``: curvature times ``r_s`` (dimensionless; 1 is a hemisphere of radius ``r_s``);
    * ``a[:, j]``: the even aspheric coefficient of r^(2j+4) times ``r_s^(2j+3)`` (the sag the
      term adds at ``r_s``, in units of ``r_s``). The r² term (Zemax PARM1) is held at zero:
      it duplicates the curvature;
    * ``k``: the conic constant (unscaled; optional);
    * ``d``: the gaps in mm (stop to first surface and every surface to the next), all but the
      last one. The last gap (to the sensor) is ``total_track − Σ d``, so the track is fixed;
    * ``m``: the materials of the elements, or None (the template's materials, fixed); its
      meaning is set by the parameterisation's material model (``jaxlens.design.materials``).

    Units are those of ``jaxlens.optics.lens``: mm, light toward +z, surface 1 at z = 0.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..optics.lens import Lens
from ..optics.materials import Air
from ..optics.surfaces import EvenAsphere


class LensParams(eqx.Module):
    """Scaled design variables for S optical surfaces and G free gaps (leading axes batch)."""

    c: Float[Array, "*b S"]
    a: Float[Array, "*b S m"]
    k: Float[Array, "*b S"]
    d: Float[Array, "*b G"]
    m: Float[Array, "*b E q"] | None = None


class AbstractParameterization(eqx.Module):
    """The parameterisation protocol: design variables (a pytree, scaled to order 1) ⇄ a Lens.

    ``to_lens(params)`` builds the lens (pure, jittable, differentiable in ``params``) and
    ``from_lens(lens)`` gives the variables of a lens of the same structure, so that
    ``to_lens(from_lens(lens))`` is ``lens``. The classical design (``Parameterization``) and
    the EDoF experiment (``experiments.edof.lenses.HybridParameterization``) implement it.
    """

    @abc.abstractmethod
    def to_lens(self, params) -> Lens:
        """The lens for one set of parameters."""

    @abc.abstractmethod
    def from_lens(self, lens: Lens):
        """The parameters of ``lens`` (inverse of ``to_lens``)."""


class Parameterization(AbstractParameterization):
    """Maps ``LensParams`` to a ``Lens`` built on a template (structure, media, system data).

    Args:
        template: a lens whose optical surfaces are ``EvenAsphere`` with ``1 + m`` coefficients.
        r_norm: normalisation radius of every optical surface, mm ``[S]``.
        total_track: the fixed first-vertex-to-sensor distance, mm.
        optical: indices of the optical (non-stop) surfaces, static.
        materials: the material model of ``LensParams.m`` (``HullMaterials`` or
            ``TableMaterials`` of ``jaxlens.design.materials``), or None: the template's.
    """

    template: Lens
    r_norm: Float[Array, " S"] = eqx.field(converter=jnp.asarray)
    total_track: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    optical: tuple[int, ...] = eqx.field(static=True)
    materials: eqx.Module | None = None

    def __check_init__(self):
        _even_aspheres(self.template, self.optical, "Parameterization: template")
        if self.template.negative_propagation:  # static
            # A design whose surfaces cross must be penalised (the spacing regulariser), not
            # traced through as Zemax traces a file's crossed surfaces.
            raise ValueError("Parameterization: the template has negative_propagation=True "
                             "(rays go back along their line to crossed surfaces, as for a "
                             "lens read from .zmx); design traces by the default rule: use "
                             "dataclasses.replace(lens, negative_propagation=False)")

    @property
    def n_terms(self) -> int:
        return self.template.surfaces[self.optical[0]].coeffs.shape[0] - 1

    def to_lens(self, p: LensParams) -> Lens:
        """The lens for one set of parameters (unbatched)."""
        self._check_shapes(p)
        surfaces = list(self.template.surfaces)
        r = self.r_norm.astype(p.c.dtype)
        powers = 2 * jnp.arange(self.n_terms, dtype=p.c.dtype) + 3  # r_s^(2j+3)
        for j, i in enumerate(self.optical):
            s = surfaces[i]
            c = p.c[j] / r[j]
            a = p.a[j] / r[j] ** powers
            coeffs = jnp.concatenate([jnp.zeros((1,), p.c.dtype), a])
            surfaces[i] = EvenAsphere(c=c, k=p.k[j], coeffs=coeffs, semi_diameter=s.semi_diameter)
        last = self.total_track.astype(p.d.dtype) - jnp.sum(p.d)
        thickness = jnp.concatenate([p.d, last[None]])
        materials = self.template.materials
        if self.materials is not None and p.m is not None:
            new = iter(self.materials.materials(p.m))
            materials = tuple(next(new) if i in self.glass else mat
                              for i, mat in enumerate(materials))
        return eqx.tree_at(
            lambda lens: (lens.surfaces, lens.thickness, lens.materials),
            self.template,
            (tuple(surfaces), thickness, materials),
        )

    def _check_shapes(self, p) -> None:
        """Shapes and dtypes are static, so this holds under jit, vmap and grad. A short group
        was read past its end (JAX clamps the index: ``c[:2]`` gave every later surface the
        second curvature), one aspheric term was broadcast over every order, a gap too many
        or too few changed the lens, and an integer dtype truncated ``r_norm``."""
        if not isinstance(p, LensParams):
            raise TypeError(f"Parameterization.to_lens: params must be a LensParams, got "
                            f"{type(p).__name__}")
        s, g = len(self.optical), self.template.thickness.shape[-1] - 1
        want = {"c": (s,), "a": (s, self.n_terms), "k": (s,), "d": (g,)}
        for name, shape in want.items():
            v = getattr(p, name)
            dtype = getattr(v, "dtype", None)
            if dtype is None or not jnp.issubdtype(dtype, jnp.floating):
                what = f"{type(v).__name__} {v!r}" if dtype is None else f"dtype {dtype}"
                raise TypeError(f"Parameterization.to_lens: params.{name} must be a float "
                                f"array of shape {shape}, got {what}")
            if tuple(v.shape) != shape:
                raise ValueError(f"Parameterization.to_lens: params.{name} must have shape "
                                 f"{shape} ({s} optical surfaces, {self.n_terms} aspheric "
                                 f"terms, {g} free gaps), got {tuple(v.shape)}")

    @property
    def glass(self) -> tuple[int, ...]:
        """Indices of the surfaces followed by an element's material (not air), in order."""
        return tuple(i for i, m in enumerate(self.template.materials) if not isinstance(m, Air))

    def from_lens(self, lens: Lens) -> LensParams:
        """Scaled parameters of a lens with this structure (inverse of ``to_lens``)."""
        _even_aspheres(lens, self.optical, "Parameterization.from_lens")
        r = self.r_norm
        powers = 2 * jnp.arange(self.n_terms, dtype=r.dtype) + 3
        c = jnp.stack([lens.surfaces[i].c for i in self.optical]) * r
        a = jnp.stack([lens.surfaces[i].coeffs[1:] for i in self.optical]) * r[:, None] ** powers
        k = jnp.stack([lens.surfaces[i].k for i in self.optical])
        return LensParams(c=c, a=a, k=k, d=lens.thickness[:-1])


def _even_aspheres(lens: Lens, optical, where: str) -> None:
    """The design variables are even-asphere terms: any other surface kind (an
    ``OddAsphere``'s r, r³ … terms, say) would be dropped or misread, so it is refused."""
    for i in optical:
        if not isinstance(lens.surfaces[i], EvenAsphere):
            raise ValueError(f"{where}: surfaces[{i}] is a {type(lens.surfaces[i]).__name__}; "
                             f"the design parameterisation holds EvenAsphere surfaces only")
