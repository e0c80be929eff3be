"""Optical materials: dispersion models that give the refractive index at a wavelength.

Conventions:
    Wavelengths are in micrometres (µm), as in Zemax. The d line is 0.5875618 µm, F is
    0.4861327 µm and C is 0.6562725 µm. Indices are relative to air at the same
    wavelength, as glass catalogs give them ("air" is exactly 1).

Every material is a small, final ``eqx.Module`` with a static ``name`` and an
``index(wavelength)`` method that broadcasts over a wavelength array. Coefficients are
arrays, so a model glass's (nd, Vd) can be optimised.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

LAMBDA_D = 0.5875618
LAMBDA_F = 0.4861327
LAMBDA_C = 0.6562725


class AbstractMaterial(eqx.Module):
    """A medium with a refractive index that depends on wavelength (µm).

    Every subclass has a static ``name`` field (declared last, with a default).
    """

    def index(self, wavelength: Float[ArrayLike, "*b"]) -> Float[Array, "*b"]:
        raise NotImplementedError


class Air(AbstractMaterial):
    """Air as glass catalogs use it: n = 1 exactly at every wavelength."""

    name: str = eqx.field(static=True, default="air")

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        return jnp.ones_like(w)


class ModelGlass(AbstractMaterial):
    """A model glass from its d-line index and Abbe number.

    The index is linear in 1/λ² and passes through nd at the d line with
    nF − nC = (nd − 1)/Vd, so ``index(0.5875618)`` returns nd exactly.
    """

    nd: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    vd: Float[Array, ""] = eqx.field(converter=jnp.asarray)
    name: str = eqx.field(static=True, default="")

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        slope = (self.nd - 1.0) / self.vd / (LAMBDA_F**-2 - LAMBDA_C**-2)
        return self.nd + slope * (w**-2 - LAMBDA_D**-2)


class Sellmeier(AbstractMaterial):
    """Sellmeier formula n² − 1 = Σ B_i λ² / (λ² − C_i), λ in µm (Zemax formula 2)."""

    B: Float[Array, " k"] = eqx.field(converter=jnp.asarray)
    C: Float[Array, " k"] = eqx.field(converter=jnp.asarray)
    name: str = eqx.field(static=True, default="")

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength)[..., None] ** 2
        return jnp.sqrt(1.0 + jnp.sum(self.B * w2 / (w2 - self.C), axis=-1))


class Schott(AbstractMaterial):
    """Schott formula n² = a0 + a1 λ² + a2 λ⁻² + a3 λ⁻⁴ + a4 λ⁻⁶ + a5 λ⁻⁸ (Zemax formula 1)."""

    coeffs: Float[Array, "6"] = eqx.field(converter=jnp.asarray)
    name: str = eqx.field(static=True, default="")

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        n2 = a[0] + a[1] * w2 + a[2] / w2 + a[3] / w2**2 + a[4] / w2**3 + a[5] / w2**4
        return jnp.sqrt(n2)


class Tabulated(AbstractMaterial):
    """Indices given at a list of wavelengths.

    The index is interpolated piecewise-linearly in 1/λ² (exact at the nodes) and held
    constant beyond the first and last node.
    """

    wavelengths: Float[Array, " k"] = eqx.field(converter=jnp.asarray)
    indices: Float[Array, " k"] = eqx.field(converter=jnp.asarray)
    name: str = eqx.field(static=True, default="")

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        x = self.wavelengths**-2
        order = jnp.argsort(x)
        if self.wavelengths.shape[0] == 1:
            return jnp.broadcast_to(self.indices[0], w.shape).astype(self.indices.dtype)
        return jnp.interp(w**-2, x[order], self.indices[order])


def abbe_number(material: AbstractMaterial) -> Array:
    """Vd = (nd − 1)/(nF − nC)."""
    n = material.index(jnp.asarray([LAMBDA_D, LAMBDA_F, LAMBDA_C]))
    return (n[0] - 1.0) / (n[1] - n[2])
