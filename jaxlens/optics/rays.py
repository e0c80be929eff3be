"""The ``Rays`` pytree: a batch of rays with a validity mask and optical path length.

Conventions:
    Global coordinates in mm, surface 1's vertex at z = 0, light travelling toward +z.
    ``direction`` holds unit direction cosines (L, M, N). ``wavelength`` is in µm,
    a scalar or one value per ray. ``opl`` is the optical path length in mm
    accumulated since the ray was launched (Σ n·distance). Invalid rays stay in the
    arrays with finite values; shapes never change.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from . import checks

_NoMaterials = checks.NoMaterials


def _valid_mask(valid, batch) -> Array:
    """``valid`` as a bool mask of the batch's shape. Integers were kept as they were, and
    ``valid & ok`` of an int mask is a bitwise and (2 & True is 0: a valid ray lost)."""
    v = jnp.asarray(valid)
    if v.dtype != jnp.bool_:
        ok = jnp.issubdtype(v.dtype, jnp.integer) and (
            checks.is_traced(v) or bool(np.all((np.asarray(v) == 0) | (np.asarray(v) == 1))))
        if not ok:
            raise TypeError(f"Rays: valid must be a bool mask (True for a valid ray), got "
                            f"dtype {v.dtype}{'' if checks.is_traced(v) else f' {checks.fmt(v)}'}")
        v = v.astype(bool)
    try:
        return jnp.broadcast_to(v, batch)
    except ValueError:
        raise ValueError(f"Rays: valid must be a scalar or one flag per ray (shape {batch}), "
                         f"got shape {v.shape}") from None


class Rays(eqx.Module):
    """A batch of rays.

    Args:
        origin: ``[*batch, 3]`` points on the rays (mm).
        direction: ``[*batch, 3]`` unit directions.
        wavelength: µm, a scalar or ``[*batch]``.
        valid: ``[*batch]`` bool mask; defaults to all True.
        opl: ``[*batch]`` optical path length (mm); defaults to 0.
    """

    origin: Float[Array, "*batch 3"]
    direction: Float[Array, "*batch 3"]
    wavelength: Float[Array, "*#batch"]
    valid: Bool[Array, "*batch"]
    opl: Float[Array, "*batch"]

    def __init__(
        self,
        origin: Float[ArrayLike, "*batch 3"],
        direction: Float[ArrayLike, "*batch 3"],
        wavelength: Float[ArrayLike, "*#batch"],
        valid: Bool[ArrayLike, "*batch"] | None = None,
        opl: Float[ArrayLike, "*batch"] | None = None,
    ):
        for arg, v, unit in (("origin", origin, "mm"), ("direction", direction, ""),
                             ("wavelength", wavelength, "µm"), ("opl", opl, "mm")):
            if v is not None:  # before jnp.asarray: a string "0.55" would be read as 0.55
                checks.real_values(v, arg, "Rays", unit)
        origin = jnp.asarray(origin)
        direction = jnp.asarray(direction)
        for arg, v in (("origin", origin), ("direction", direction), ("wavelength", wavelength),
                       ("opl", opl)):
            dt = jnp.result_type(v) if v is not None else None
            if dt is not None and jnp.issubdtype(dt, jnp.floating) and jnp.finfo(dt).bits < 32:
                # float16 keeps 3 digits (0.55 µm is 0.5498), as checks.float_array refuses
                raise TypeError(f"Rays: {arg} is {jnp.dtype(dt).name}, which keeps too few "
                                f"digits to trace a lens; give float32 or float64 values")
        if origin.shape[-1:] != (3,) or direction.shape != origin.shape:
            raise ValueError(
                f"Rays: origin and direction must both be [..., 3] of the same shape, got "
                f"{origin.shape} and {direction.shape}"
            )
        dtype = jnp.result_type(origin, direction)
        if not jnp.issubdtype(dtype, jnp.floating):
            dtype = jnp.result_type(float)
        batch = origin.shape[:-1]
        self.origin = origin.astype(dtype)
        self.direction = direction.astype(dtype)
        self.wavelength = jnp.asarray(wavelength, dtype=dtype)
        self.valid = jnp.ones(batch, bool) if valid is None else _valid_mask(valid, batch)
        self.opl = jnp.zeros(batch, dtype) if opl is None else jnp.asarray(opl, dtype)
        for arg, a in (("wavelength", self.wavelength), ("opl", self.opl)):
            try:
                ok = jnp.broadcast_shapes(a.shape, batch) == batch
            except ValueError:
                ok = False
            if not ok:
                raise ValueError(f"Rays: {arg} must be a scalar or one value per ray (shape "
                                 f"{batch}), got shape {a.shape}")
        # Concrete input only (a traced value is checked where it is used, see ``trace``).
        checks.unit_directions(self.direction, self.valid, "Rays")
        if not checks.is_traced((self.origin, self.valid)):
            # Only rays marked valid: invalid rays keep finite values, but a caller may mask
            # rays it has no origin for.
            o = np.asarray(self.origin)
            bad = np.asarray(self.valid) & ~np.all(np.isfinite(o), axis=-1)
            if np.any(bad):
                raise ValueError(f"Rays: origin (mm) of {int(bad.sum())} valid ray(s) holds NaN "
                                 f"or inf, first {checks.fmt(o[bad][0])}; every coordinate "
                                 f"must be finite")
            if not checks.is_traced(self.opl):
                opl = np.broadcast_to(np.asarray(self.opl), self.valid.shape)
                bad = np.asarray(self.valid) & ~np.isfinite(opl)
                if np.any(bad):
                    raise ValueError(f"Rays: opl (optical path length, mm) of {int(bad.sum())} "
                                     f"valid ray(s) is NaN or inf; it must be finite")
        if not checks.is_traced(self.wavelength):
            checks.wavelengths(_NoMaterials, self.wavelength, "Rays", "wavelength")

    @property
    def dtype(self):
        return self.origin.dtype

    @property
    def shape(self) -> tuple[int, ...]:
        return self.origin.shape[:-1]

    def __getitem__(self, idx) -> Rays:
        w = self.wavelength if self.wavelength.ndim == 0 else self.wavelength[idx]
        return Rays(self.origin[idx], self.direction[idx], w, self.valid[idx], self.opl[idx])

    def __iter__(self):
        """Iterate over the leading axis (for example the surfaces of ``trace_path``)."""
        if not self.shape:
            raise TypeError("iteration over a single ray (Rays of shape ())")
        return (self[i] for i in range(self.shape[0]))

    def reshape(self, *shape: int) -> Rays:
        w = self.wavelength if self.wavelength.ndim == 0 else self.wavelength.reshape(shape)
        return Rays(
            self.origin.reshape(*shape, 3),
            self.direction.reshape(*shape, 3),
            w,
            self.valid.reshape(shape),
            self.opl.reshape(shape),
        )

    def propagate_to_z(self, z) -> Rays:
        """Move each ray along its line to the plane z (mm); valid if N > 0.

        The optical path is not updated: the medium is not known here.
        """
        ok = self.direction[..., 2] > 0
        n = jnp.where(ok, self.direction[..., 2], 1.0)
        t = (z - self.origin[..., 2]) / n
        o = self.origin + t[..., None] * self.direction
        return Rays(o, self.direction, self.wavelength, self.valid & ok, self.opl)
