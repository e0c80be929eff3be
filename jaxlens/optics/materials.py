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

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import checks

LAMBDA_D = 0.5875618
LAMBDA_F = 0.4861327
LAMBDA_C = 0.6562725


def _check_coeffs(m, count: int | None = None, field: str = "coeffs") -> None:
    """A formula's coefficients: one 1-D array of ``count`` (JAX would clamp a missing one's
    index and read another coefficient in its place, and ``a[0]`` of a 2-D array is a row:
    Schott ``[[…6…]]`` gave six "indices", two NaN), and finite where concrete."""
    a = getattr(m, field)
    where = f"{type(m).__name__}{f' {m.name!r}' if m.name else ''}"
    if a.ndim != 1 or (count is not None and a.shape[-1] != count):
        want = f"{count} coefficients" if count is not None else "a 1-D array of coefficients"
        one = " (one 1-D array)" if a.ndim != 1 and count is not None else ""
        raise ValueError(f"{where}: {field} must hold {want}, got shape {a.shape}{one}")
    if not checks.is_traced(a):
        checks.values(a, field, where)


class AbstractMaterial(eqx.Module):
    """A medium with a refractive index that depends on wavelength (µm).

    Every subclass has a static ``name`` field (declared last, with a default).
    """

    def __check_init__(self):
        # Every subclass's static name (a number was kept, and written to files as one).
        name = getattr(self, "name", "")
        if not isinstance(name, str):
            raise TypeError(f"{type(self).__name__}: name must be a str, got "
                            f"{type(name).__name__} {name!r}")

    def index(self, wavelength: Float[ArrayLike, "*b"]) -> Float[Array, "*b"]:
        raise NotImplementedError

    def __hash__(self) -> int:
        """A hash of the material's values, consistent with ``==`` (``eqx.tree_equal``).

        ``jax.jit(material.index)`` hashes the bound method, and with it the material:
        equinox hashes a module's fields, and a JAX array is unhashable, so every material
        with coefficients raised "unhashable type". Here concrete arrays hash by shape, dtype
        and values; a traced one (a material built inside a transform) by identity.
        """
        leaves, treedef = jax.tree_util.tree_flatten(self)
        return hash((treedef, tuple(_leaf_key(x) for x in leaves)))

    def extrapolated_index(self, wavelength: Float[ArrayLike, "*b"]) -> Float[Array, "*b"]:
        """The index at any wavelength in µm, outside the material's data range too.

        ``index`` is this for every material but a catalog glass (``CatalogMaterial``),
        whose ``index`` refuses a concrete wavelength outside the catalog's range; here its
        formula is extrapolated, and a formula's beyond its poles (where its ``index``
        refuses a concrete wavelength, ``pole_window``). For the d, F and C line indices
        (nd, Vd) of materials whose data do not cover those lines (infrared glasses), as
        catalogs and Zemax quote them.
        """
        checks.wavelength_unit(wavelength, f"{type(self).__name__}.extrapolated_index")
        index = type(self).index
        return getattr(index, "__wrapped__", index)(self, wavelength)

    def poles(self) -> np.ndarray | None:
        """Wavelengths (µm) where the dispersion formula diverges (its resonances), concrete
        values only; None for a formula without poles or a traced material."""
        return None

    def pole_window(self) -> tuple[float, float] | None:
        """The wavelengths (µm) between the formula's poles that hold the d line: a formula
        without a stated data range (a ``Sellmeier`` built from coefficients, not a catalog
        glass) describes its material there only. Beyond a resonance its index is finite and
        plausible but no longer that of the material (N-BK7's Sellmeier gives n = 3.0 at 11
        µm, past its 10.2 µm resonance). None: no poles, a traced material, or a formula
        whose index at the d line is not a valid index (an infrared material whose formula
        has a resonance above the d line: no window is assumed). A lens's wavelengths must lie
        in it (``checks.material_range``); a ``CatalogMaterial`` (``wavelength_range``)
        states its own range instead, as the shipped SILICON does (1.36–11 µm, beyond its
        formula's 1.13 µm resonance).
        """
        p = self.poles()
        if p is None or p.size == 0:
            return None
        leaves, treedef = jax.tree_util.tree_flatten(self)
        key = (treedef, tuple(_leaf_key(x) for x in leaves))
        if key not in _WINDOWS:  # a lens's checks ask for it at every analysis call
            with jax.ensure_compile_time_eval():
                n = float(np.asarray(type(self).index.__wrapped__(self, jnp.asarray(LAMBDA_D))))
            below, above = p[p < LAMBDA_D], p[p > LAMBDA_D]
            window = (float(below.max()) if below.size else 0.0,
                      float(above.min()) if above.size else math.inf)
            if len(_WINDOWS) > 4096:
                _WINDOWS.clear()
            _WINDOWS[key] = window if np.isfinite(n) and n >= 1.0 else None
        return _WINDOWS[key]

    def __init_subclass__(cls, **kwargs):
        # Every ``index`` refuses a concrete wavelength that cannot be in µm (e.g. 587.6, in
        # nm), which every formula would otherwise turn into a plausible wrong index. Traced
        # wavelengths are checked where they enter (``checks.wavelengths``). In-µm values
        # outside a material's data range are refused by ``CatalogMaterial.index`` (the
        # catalog's range); ``extrapolated_index`` gives nd/Vd of infrared glasses.
        super().__init_subclass__(**kwargs)
        if "index" in cls.__dict__:
            cls.index = _unit_checked(cls.__dict__["index"])


_WINDOWS: dict = {}
"""``pole_window`` by material values (the d-line index is a JAX evaluation, about 0.5 ms)."""


def _concrete(a) -> np.ndarray | None:
    """A coefficient array as float64 numpy, or None when traced."""
    return None if checks.is_traced(a) else np.asarray(a, float)


def _pole_wavelengths(squares, strengths) -> np.ndarray:
    """The poles (µm) λ = √c of terms s/(λ² − c) with c > 0 and s ≠ 0."""
    c = np.asarray(squares, float).reshape(-1)
    b = np.broadcast_to(np.asarray(strengths, float).reshape(-1), c.shape)
    keep = np.isfinite(c) & (c > 0) & (b != 0)
    return np.sqrt(c[keep])


def _leaf_key(x):
    if checks.is_traced(x):
        return ("traced", id(x))
    if isinstance(x, (jax.Array, np.ndarray, np.generic)):
        a = np.asarray(x)
        if a.dtype.kind == "f":
            a = a + 0.0  # -0.0 == 0.0
        return a.shape, a.dtype.str, a.tobytes()
    return x


def _unit_checked(index):
    def checked(self, wavelength):
        where = f"{type(self).__name__}.index"
        checks.wavelength_unit(wavelength, where)
        # A formula without a stated range (a Sellmeier from coefficients) holds between its
        # poles around the d line only (``pole_window``); past a resonance it gave a finite,
        # meaningless index (N-BK7's Sellmeier: 3.05 at 11 µm). A lens refuses such
        # wavelengths too (``checks.material_range``). Concrete values only.
        if (type(self).poles is not AbstractMaterial.poles and not checks.is_traced(wavelength)
                and self.pole_window() is not None):
            checks.material_wavelengths(
                self, wavelength, where,
                hint="; extrapolated_index gives the formula's value anywhere")
        return index(self, wavelength)

    checked.__name__, checked.__qualname__, checked.__doc__ = (
        index.__name__, index.__qualname__, index.__doc__)
    checked.__wrapped__ = index
    return checked


class Air(AbstractMaterial):
    """Air as glass catalogs use it: n = 1 exactly at every wavelength."""

    name: str = eqx.field(static=True, default="air")

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        return jnp.ones_like(w)


MAX_ND = 4.5
"""Largest d-line index a model glass may have (no optical material reaches 3; an nd of 60
is an Abbe number given in its place)."""

MIN_VD = 5.0
"""Smallest Abbe number a model glass may have (the shipped catalogs' span 12.7–106; a vd
below 5 is a fraction given for the number, 0.6417 for 64.17)."""


class ModelGlass(AbstractMaterial):
    """A model glass from its d-line index and Abbe number.

    The index is linear in 1/λ² and passes through nd at the d line with
    nF − nC = (nd − 1)/Vd, so ``index(0.5875618)`` returns nd exactly.
    """

    nd: Float[Array, ""] = checks.float_field("nd", "ModelGlass")
    vd: Float[Array, ""] = checks.float_field("vd", "ModelGlass")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        # Concrete values only: an optimiser's traced nd and Vd are checked by its bounds.
        if checks.is_traced((self.nd, self.vd)):
            return
        nd, vd = np.asarray(self.nd, float), np.asarray(self.vd, float)
        if np.any(~np.isfinite(nd) | (nd < 1.0)):
            raise ValueError(f"ModelGlass{self._of()}: nd must be a finite index >= 1, got "
                             f"{checks.fmt(nd)}")
        if np.any(nd > MAX_ND):
            raise ValueError(f"ModelGlass{self._of()}: nd must be a finite index >= 1 and <= "
                             f"{MAX_ND:g} (the d-line index), got {checks.fmt(nd)} (were nd "
                             f"and vd swapped?)")
        if np.any(np.isnan(vd) | (vd <= 0.0)):
            raise ValueError(f"ModelGlass{self._of()}: vd must be an Abbe number > 0 (inf for "
                             f"no dispersion), got {checks.fmt(vd)}")
        if np.any(vd < MIN_VD):  # 0.6417 for 64.17: a 100 times too strong dispersion
            raise ValueError(f"ModelGlass{self._of()}: vd must be an Abbe number >= {MIN_VD:g} "
                             f"(inf for no dispersion; the shipped catalogs' glasses lie in "
                             f"12.7–106), got {checks.fmt(vd)} (was 64.17 given as 0.6417?)")

    def _of(self) -> str:
        return f" {self.name!r}" if self.name else ""

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        slope = (self.nd - 1.0) / self.vd / (LAMBDA_F**-2 - LAMBDA_C**-2)
        return self.nd + slope * (w**-2 - LAMBDA_D**-2)


SELLMEIER_PROBE_UM = np.geomspace(0.15, 30.0, 241)
"""Wavelengths (µm) where a hand-given Sellmeier formula must give an index somewhere."""


def _sellmeier_n2(b, c, wavelengths) -> np.ndarray:
    """n² of the Sellmeier formula (numpy, concrete B and C) at ``wavelengths`` (µm); poles
    and negative values are left as they come (the checks below read them)."""
    w2 = np.asarray(wavelengths, float)[..., None] ** 2
    with np.errstate(all="ignore"):
        return 1.0 + np.sum(b * w2 / (w2 - c), axis=-1)


def _check_sellmeier_units(m, where: str) -> None:
    """A Sellmeier formula of strengths B >= 0 that gives no finite index >= 1 at any
    wavelength in 0.15–30 µm describes no material: C given in nm² (N-BK7's 0.006 µm² as
    6000 nm²) made n < 1 at every wavelength, read by ``index`` as a plausible 0.99997.
    Concrete values only."""
    b, c = _concrete(m.B), _concrete(m.C)
    if b is None or c is None or np.any(b < 0):  # a negative B: the index checks say why
        return
    n2 = _sellmeier_n2(b, c, SELLMEIER_PROBE_UM)
    if not np.any(np.isfinite(n2) & (n2 >= 1.0)):
        raise ValueError(
            f"{where}: the formula gives no finite index >= 1 at any wavelength in "
            f"0.15–30 µm, so it describes no material; B is dimensionless and C in µm² "
            f"(N-BK7: B 1.04, 0.232, 1.01, C 0.00600, 0.0200, 103.6 µm²; C in nm² is "
            f"10**6 times too large), got B {checks.fmt(b)}, C {checks.fmt(c)}")
    _check_sellmeier_swap(b, c, where)
    _check_sellmeier_c_squared(b, c, where)


SWAP_PLAUSIBLE_ND = (1.0, 3.0)
"""d-line indices of the glasses and crystals a Sellmeier formula is written for in the
visible: a formula with no real index at the d line whose B and C exchanged give one in this
range is read as B and C swapped."""


def _check_sellmeier_swap(b, c, where: str) -> None:
    """B and C swapped (C the strengths, B the resonances, in µm²): N-BK7's puts poles at
    0.48, 1.00 and 1.02 µm, and between them the index at the d line is the square root of a
    negative number (NaN), while beyond 1.02 µm it is a finite 10. A formula meant for the
    infrared only (germanium, a pole at 0.66 µm) also has no real index at the d line, but
    exchanging its B and C gives none in ``SWAP_PLAUSIBLE_ND`` either, so it is kept."""
    n2 = float(_sellmeier_n2(b, c, LAMBDA_D))
    if np.isfinite(n2) and n2 >= 1.0 or np.any(c < 0):
        return
    swapped = float(_sellmeier_n2(c, b, LAMBDA_D))
    lo, hi = SWAP_PLAUSIBLE_ND
    if np.isfinite(swapped) and lo**2 <= swapped <= hi**2:
        raise ValueError(
            f"{where}: B and C look swapped: the formula has no real index at the d line "
            f"(n² = {n2:.4g} at {LAMBDA_D} µm), and with B and C exchanged it gives "
            f"{math.sqrt(swapped):.5f}; B holds the dimensionless strengths (N-BK7: 1.04, "
            f"0.232, 1.01) and C the resonance wavelengths squared in µm² (N-BK7: 0.00600, "
            f"0.0200, 103.6), got B {checks.fmt(b)}, C {checks.fmt(c)}")


PLAUSIBLE_GLASS = ((1.3, 2.6), (15.0, 120.0))
"""(nd, Vd) ranges of the optical glasses and plastics a visible-light Sellmeier formula is
written for."""


def _sellmeier_nd_vd(b, c) -> tuple[float, float]:
    with np.errstate(all="ignore"):
        n = np.sqrt(_sellmeier_n2(b, c, [LAMBDA_D, LAMBDA_F, LAMBDA_C]))
        return float(n[0]), float((n[0] - 1.0) / (n[1] - n[2]))


def _check_sellmeier_c_squared(b, c, where: str) -> None:
    """C given as the resonance wavelengths in µm, not their squares (as some tables list
    them): N-BK7 then has nd 1.642 and Vd 4.1, poles at 0.28 and 0.38 µm. Refused where the
    formula's Vd is below 8 (or it has no index at d, F or C) while squaring C gives a
    plausible glass (``PLAUSIBLE_GLASS``): of the 723 Sellmeier glasses shipped, written so,
    719 are caught, and none of them as given is."""
    if np.any(c < 0):
        return
    nd, vd = _sellmeier_nd_vd(b, c)
    if np.isfinite(nd) and np.isfinite(vd) and vd >= 8.0:
        return
    nd2, vd2 = _sellmeier_nd_vd(b, c * c)
    (nlo, nhi), (vlo, vhi) = PLAUSIBLE_GLASS
    if np.isfinite(nd2) and np.isfinite(vd2) and nlo <= nd2 <= nhi and vlo <= vd2 <= vhi:
        raise ValueError(
            f"{where}: C looks like resonance wavelengths in µm, not their squares: as given "
            f"the formula has nd {nd:.4g} and Vd {vd:.3g} (poles at {checks.fmt(np.sqrt(c))} "
            f"µm), with C squared nd {nd2:.5f} and Vd {vd2:.2f}; C is in µm² (N-BK7: 0.00600, "
            f"0.0200, 103.6 µm², i.e. (0.0775 µm)², …), got C {checks.fmt(c)}")


class Sellmeier(AbstractMaterial):
    """Sellmeier formula n² − 1 = Σ B_i λ² / (λ² − C_i), λ in µm (Zemax formula 2)."""

    B: Float[Array, " k"] = checks.float_field("B", "Sellmeier")
    C: Float[Array, " k"] = checks.float_field("C", "Sellmeier")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        if self.B.shape != self.C.shape:
            raise ValueError(
                f"Sellmeier{f' {self.name!r}' if self.name else ''}: B and C need one "
                f"coefficient per term (the same length), got shapes {self.B.shape} and "
                f"{self.C.shape}")
        where = f"Sellmeier{f' {self.name!r}' if self.name else ''}"
        if self.B.ndim != 1 or self.B.size == 0:  # no term: n = 1 (air) without a word
            raise ValueError(f"{where}: B and C must be 1-D arrays of at least one term's "
                             f"coefficient, got shape {self.B.shape}")
        _check_coeffs(self, None, "B")
        _check_coeffs(self, None, "C")
        _check_sellmeier_units(self, where)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength)[..., None] ** 2
        return jnp.sqrt(1.0 + jnp.sum(self.B * w2 / (w2 - self.C), axis=-1))

    def poles(self):
        """√C_i (µm) of the terms with B_i ≠ 0."""
        c, b = _concrete(self.C), _concrete(self.B)
        return None if c is None or b is None else _pole_wavelengths(c, b)


class Schott(AbstractMaterial):
    """Schott formula n² = a0 + a1 λ² + a2 λ⁻² + a3 λ⁻⁴ + a4 λ⁻⁶ + a5 λ⁻⁸ (Zemax formula 1)."""

    coeffs: Float[Array, 6] = checks.float_field("coeffs", "Schott")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 6)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        n2 = a[0] + a[1] * w2 + a[2] / w2 + a[3] / w2**2 + a[4] / w2**3 + a[5] / w2**4
        return jnp.sqrt(n2)


TABLE_SLACK = 1e-3
"""Relative margin beyond a table's end nodes where the end value is still used: a rounded
F or C line (0.4861 for 0.4861327 µm) is accepted; the index error there is below ~1e-4."""


class Tabulated(AbstractMaterial):
    """Indices given at a list of wavelengths.

    The index is interpolated piecewise-linearly in 1/λ² (exact at the nodes). The table's
    span (plus ``TABLE_SLACK``) is its ``wavelength_range``: ``index`` refuses a concrete
    wavelength outside it, as traces, PSFs and renders do; ``extrapolated_index`` (and a
    traced wavelength, checked where it enters) holds the end value beyond the first and last
    node. A table of one node is a non-dispersive material, valid at any wavelength.
    """

    wavelengths: Float[Array, " k"] = checks.float_field("wavelengths", "Tabulated")
    indices: Float[Array, " k"] = checks.float_field("indices", "Tabulated")
    name: str = eqx.field(static=True, default="")
    wavelength_range: tuple[float, float] | None = eqx.field(static=True, default=None)
    """(shortest, longest) wavelength of the table (µm), widened by ``TABLE_SLACK``, set at
    construction (static, so that it is known under jit); None for one node."""

    def __post_init__(self):
        # Runs before the field converters: the wavelengths may still be a list. The range
        # is rounded to float32, so that a table in either precision (``astype``, a file
        # round trip) has the same static range.
        if self.wavelength_range is None:
            self.wavelength_range = self.table_range()

    def table_range(self) -> tuple[float, float] | None:
        """The span of the table as it is now (µm, widened by ``TABLE_SLACK``); None when
        traced or of one node. Checks use it before the static ``wavelength_range``, which
        ``eqx.tree_at`` does not update when it replaces the table."""
        w = self.wavelengths
        if checks.is_traced(w):
            return None
        a = np.asarray(np.asarray(w, np.float32), float)
        if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)):
            return None
        return float(a.min()) * (1 - TABLE_SLACK), float(a.max()) * (1 + TABLE_SLACK)

    def __check_init__(self):
        where = f"Tabulated{f' {self.name!r}' if self.name else ''}"
        w, n = self.wavelengths, self.indices
        if w.ndim != 1 or w.shape != n.shape or w.shape[0] == 0:
            raise ValueError(f"{where}: wavelengths (µm) and indices must be 1-D arrays of the "
                             f"same non-zero length, got shapes {w.shape} and {n.shape}")
        if checks.is_traced((w, n)):
            return
        checks.values(w, "wavelengths", where, lo=0, lo_open=True, unit="µm")
        lo, hi = checks.GENERIC_RANGE_UM
        a = np.asarray(w, float)
        if not np.any((a >= lo) & (a <= hi)):  # a table in nm (or of no usable wavelength)
            checks.wavelengths(checks.NoMaterials, a, where, "wavelengths")
        checks.values(n, "indices", where, lo=1, unit="(refractive index)")
        if np.unique(np.asarray(w)).size != w.shape[0]:
            raise ValueError(f"{where}: wavelengths must be distinct (one index per "
                             f"wavelength), got {checks.fmt(w)} µm")
        r = self.wavelength_range
        if r is not None:  # one given by hand: (0.7, 0.4) made every wavelength "outside"
            try:
                lo_r, hi_r = (float(v) for v in r)
            except (TypeError, ValueError):
                lo_r = hi_r = math.nan
            if not (0 < lo_r < hi_r < math.inf):
                raise ValueError(f"{where}: wavelength_range must be (shortest, longest) "
                                 f"wavelength in µm with 0 < shortest < longest, got {r!r}")
            if not checks.is_traced(w) and (lo_r > float(np.max(w)) or hi_r < float(np.min(w))):
                # (400, 700) in nm for a table in µm: every wavelength of the table "outside".
                raise ValueError(f"{where}: wavelength_range {r!r} µm holds none of the "
                                 f"table's wavelengths ({checks.fmt(np.min(w))}–"
                                 f"{checks.fmt(np.max(w))} µm); give it in µm (0.4, not 400 nm)")

    def index(self, wavelength):
        """The interpolated index at wavelengths in µm; a concrete wavelength outside the
        table (``wavelength_range``) raises ``ValueError`` naming the range (before, the end
        value was returned: a plausible index where the table has no data).
        ``extrapolated_index`` holds the end values beyond the table."""
        if self.wavelengths.shape[0] > 1:
            checks.material_wavelengths(
                self, wavelength, f"Tabulated.index{f' ({self.name})' if self.name else ''}",
                hint="; extrapolated_index holds the table's end values beyond it")
        return self._interpolated(wavelength)

    def extrapolated_index(self, wavelength):
        """The index at any wavelength in µm: the table's end values beyond its range."""
        checks.wavelength_unit(wavelength, "Tabulated.extrapolated_index")
        return self._interpolated(wavelength)

    def _interpolated(self, wavelength):
        w = jnp.asarray(wavelength)
        x = self.wavelengths**-2
        order = jnp.argsort(x)
        if self.wavelengths.shape[0] == 1:
            return jnp.broadcast_to(self.indices[0], w.shape).astype(self.indices.dtype)
        return jnp.interp(w**-2, x[order], self.indices[order])


def abbe_number(material: AbstractMaterial, *, held_ends: bool = False) -> Array:
    """Vd = (nd − 1)/(nF − nC) (``extrapolated_index``: defined for infrared glasses too).

    A ``Tabulated`` material whose table does not hold the F and C lines (0.4861–0.6563 µm)
    is refused (``ValueError``): beyond its ends its index is held constant, so its Vd was a
    number of the held values (168 for a table from 0.6 µm, inf for an infrared one). With
    ``held_ends=True`` that number is returned (the tolerance model's anchor of its Abbe
    perturbation, where a constant end gives a non-dispersive material).
    """
    checks.switch(held_ends, "held_ends", "abbe_number")
    if not held_ends and isinstance(material, Tabulated):
        rng = material.table_range()
        if rng is not None and not (rng[0] <= LAMBDA_F and LAMBDA_C <= rng[1]):
            name = f" {material.name!r}" if material.name else ""
            raise ValueError(
                f"abbe_number: the table of Tabulated{name} spans {rng[0]:g}–{rng[1]:g} µm, "
                f"which does not hold the F and C lines ({LAMBDA_F}–{LAMBDA_C} µm): its index "
                f"is held constant beyond its ends, which gives no Abbe number (pass "
                f"held_ends=True for the number of the held values)")
    n = material.extrapolated_index(jnp.asarray([LAMBDA_D, LAMBDA_F, LAMBDA_C]))
    if not (held_ends or checks.is_traced(n) or np.all(np.isfinite(np.asarray(n)))):
        # Before: NaN (a formula with a resonance between the F and C lines, or n² < 0).
        raise ValueError(f"abbe_number: {type(material).__name__}"
                         f"{f' {material.name!r}' if getattr(material, 'name', '') else ''} "
                         f"gives no finite index at the d, F and C lines ({LAMBDA_D}, "
                         f"{LAMBDA_F}, {LAMBDA_C} µm): got {checks.fmt(np.asarray(n))}, so it "
                         f"has no Abbe number")
    return (n[0] - 1.0) / (n[1] - n[2])


# Further Zemax glass-catalog dispersion formulas (wavelength λ in µm). ``Schott`` is formula
# 1 and ``Sellmeier`` covers formulas 2 (Sellmeier 1, three terms), 6 (Sellmeier 3, four
# terms) and 11 (Sellmeier 5, five terms).


class Herzberger(AbstractMaterial):
    """Herzberger formula (Zemax formula 3).

    n = A + B L + C L² + D λ² + E λ⁴ + F λ⁶ with L = 1/(λ² − 0.028), λ in µm; ``coeffs`` is
    (A, B, C, D, E, F).
    """

    coeffs: Float[Array, " 6"] = checks.float_field("coeffs", "Herzberger")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 6)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        big_l = 1.0 / (w2 - 0.028)
        return a[0] + a[1] * big_l + a[2] * big_l**2 + a[3] * w2 + a[4] * w2**2 + a[5] * w2**3

    def poles(self):
        """√0.028 µm (0.167 µm), where L diverges, unless B and C are 0."""
        c = _concrete(self.coeffs)
        return None if c is None else _pole_wavelengths(0.028, abs(c[1]) + abs(c[2]))


class Sellmeier2(AbstractMaterial):
    """Sellmeier 2 formula (Zemax formula 4).

    n² − 1 = A + B1 λ²/(λ² − λ1²) + B2/(λ² − λ2²), λ, λ1 and λ2 in µm; ``coeffs`` is
    (A, B1, λ1, B2, λ2).
    """

    coeffs: Float[Array, " 5"] = checks.float_field("coeffs", "Sellmeier2")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 5)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a, b1, l1, b2, l2 = (self.coeffs[i] for i in range(5))
        return jnp.sqrt(1.0 + a + b1 * w2 / (w2 - l1**2) + b2 / (w2 - l2**2))

    def poles(self):
        """|λ1| and |λ2| (µm) of the terms with B1, B2 ≠ 0."""
        c = _concrete(self.coeffs)
        return None if c is None else _pole_wavelengths(c[[2, 4]] ** 2, c[[1, 3]])


class Conrady(AbstractMaterial):
    """Conrady formula (Zemax formula 5): n = n0 + A/λ + B/λ^3.5, λ in µm; ``coeffs`` is
    (n0, A, B)."""

    coeffs: Float[Array, " 3"] = checks.float_field("coeffs", "Conrady")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 3)

    def index(self, wavelength):
        w = jnp.asarray(wavelength)
        return self.coeffs[0] + self.coeffs[1] / w + self.coeffs[2] / w**3.5


class Handbook1(AbstractMaterial):
    """Handbook of Optics 1 formula (Zemax formula 7).

    n² = A + B/(λ² − C) − D λ², λ in µm; ``coeffs`` is (A, B, C, D).
    """

    coeffs: Float[Array, " 4"] = checks.float_field("coeffs", "Handbook1")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 4)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        return jnp.sqrt(a[0] + a[1] / (w2 - a[2]) - a[3] * w2)

    def poles(self):
        """√C (µm) unless B is 0."""
        c = _concrete(self.coeffs)
        return None if c is None else _pole_wavelengths(c[2], c[1])


class Handbook2(AbstractMaterial):
    """Handbook of Optics 2 formula (Zemax formula 8).

    n² = A + B λ²/(λ² − C) − D λ², λ in µm; ``coeffs`` is (A, B, C, D).
    """

    coeffs: Float[Array, " 4"] = checks.float_field("coeffs", "Handbook2")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 4)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        return jnp.sqrt(a[0] + a[1] * w2 / (w2 - a[2]) - a[3] * w2)

    def poles(self):
        """√C (µm) unless B is 0."""
        c = _concrete(self.coeffs)
        return None if c is None else _pole_wavelengths(c[2], c[1])


class Sellmeier4(AbstractMaterial):
    """Sellmeier 4 formula (Zemax formula 9).

    n² = A + B λ²/(λ² − C) + D λ²/(λ² − E), λ in µm; ``coeffs`` is (A, B, C, D, E).
    """

    coeffs: Float[Array, " 5"] = checks.float_field("coeffs", "Sellmeier4")
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        _check_coeffs(self, 5)

    def index(self, wavelength):
        w2 = jnp.asarray(wavelength) ** 2
        a = self.coeffs
        return jnp.sqrt(a[0] + a[1] * w2 / (w2 - a[2]) + a[3] * w2 / (w2 - a[4]))

    def poles(self):
        """√C and √E (µm) of the terms with B, D ≠ 0."""
        c = _concrete(self.coeffs)
        return None if c is None else _pole_wavelengths(c[[2, 4]], c[[1, 3]])


EXTENDED_POWERS = (0, 2, -2, -4, -6, -8, -10, -12)
"""Powers of λ (µm) in Zemax's Extended formula (10)."""
EXTENDED2_POWERS = (0, 2, -2, -4, -6, -8, 4, 6)
"""Powers of λ (µm) in Zemax's Extended 2 formula (12)."""
EXTENDED3_POWERS = (0, 2, 4, -2, -4, -6, -8, -10, -12)
"""Powers of λ (µm) in Zemax's Extended 3 formula (13)."""


class Laurent(AbstractMaterial):
    """Power series in λ for n²: n² = Σ_k a_k λ^p_k, λ in µm.

    With ``powers`` set to ``EXTENDED_POWERS``, ``EXTENDED2_POWERS`` or ``EXTENDED3_POWERS``
    this is Zemax's Extended (10), Extended 2 (12) or Extended 3 (13) formula, the
    coefficients in catalog order.
    """

    coeffs: Float[Array, " k"] = checks.float_field("coeffs", "Laurent")
    powers: tuple[int, ...] = eqx.field(static=True, default=EXTENDED_POWERS)
    name: str = eqx.field(static=True, default="")

    def __check_init__(self):
        if not isinstance(self.powers, tuple) or not all(
                isinstance(p, (int, np.integer)) and not isinstance(p, bool) for p in self.powers):
            # A string "ab" passed the count check and failed at the first index.
            raise ValueError(f"Laurent: powers must be a tuple of whole numbers (the exponents "
                             f"of λ), got {self.powers!r}")
        if self.coeffs.shape != (len(self.powers),):
            raise ValueError(
                f"Laurent needs one coefficient per power: {len(self.powers)} powers, "
                f"coefficients of shape {self.coeffs.shape}"
            )
        _check_coeffs(self, len(self.powers))

    def index(self, wavelength):
        w = jnp.asarray(wavelength)[..., None]
        p = jnp.asarray(self.powers, dtype=self.coeffs.dtype)
        return jnp.sqrt(jnp.sum(self.coeffs * w**p, axis=-1))
