"""Material selection: each element's material as a free point of a catalog's glass map.

Conventions:
    A material is placed on the glass map by its d-line index nd and Abbe number Vd (the
    catalogs' NM-record values). The *region* of a set of catalogs is the convex hull of
    their (nd, Vd) points. The design variables of the materials (``LensParams.m``) depend
    on the material model of the ``Parameterization``:

    * :class:`HullMaterials` (continuous selection): ``m[e]`` is a vector of logits, one per
      corner of the hull; element ``e`` is the model glass (``ModelGlass``: index linear in
      1/λ², exact nd and nF − nC) at ``softmax(m[e]) @ corners``. A convex combination of
      the corners lies in the hull for every finite input, and the map is smooth.
    * :class:`TableMaterials` (catalog materials chosen per design): ``m[e]`` is element
      ``e``'s index at each design wavelength, a ``Tabulated`` material, exact at those
      wavelengths; these variables are held fixed by the solvers. It lets every design of a
      vmapped batch carry its own catalog materials with one compiled program.

    :meth:`CatalogRegion.nearest` snaps a point to the catalog material nearest on the glass
    map, with the metric of ``jaxlens.optics.catalog.nearest_glasses``:
    ``hypot((nd − nd′)/ND_PER_VD, Vd − Vd′)`` (an nd step of 0.01 weighs as one Abbe unit).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..optics import catalog, checks
from ..optics.materials import MAX_ND, ModelGlass, Tabulated

SELECTION_MODES = ("fixed", "continuous", "search")
"""Material selection modes of the design (``DesignConfig.materials``)."""

DEFAULT_CATALOGS = ("PLASTICS",)
"""Catalogs the materials are chosen from unless told otherwise (molded lens plastics)."""

_LOGIT_FLOOR = 1e-6  # smallest weight of a corner at the start (its logit is log of it)


def convex_hull(points) -> np.ndarray:
    """Indices of the convex hull's corners of 2-D points, counter-clockwise (monotone chain).

    Collinear points on an edge are not corners. The points are scaled to the glass map's
    metric (nd / ``ND_PER_VD``, Vd) first so that the collinearity test is well conditioned;
    the hull itself does not depend on that scale.
    """
    checks.real_values(points, "points", "convex_hull", "(nd, Vd)")
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3:  # 2 points: a "hull" of 1 corner
        raise ValueError(f"convex_hull: points must be [N, 2] (nd, Vd) pairs with N >= 3, got "
                         f"shape {p.shape}")
    checks.values(p, "points", "convex_hull", unit="(nd, Vd)")  # NaN sorted anywhere
    p = p / np.array([catalog.ND_PER_VD, 1.0])
    order = sorted(range(len(p)), key=lambda i: (p[i, 0], p[i, 1]))

    def cross(o, a, b):
        return (p[a, 0] - p[o, 0]) * (p[b, 1] - p[o, 1]) - (p[a, 1] - p[o, 1]) * (p[b, 0] - p[o, 0])

    def chain(idx):
        out: list[int] = []
        for i in idx:
            while len(out) >= 2 and cross(out[-2], out[-1], i) <= 1e-12:
                out.pop()
            out.append(i)
        return out

    lower, upper = chain(order), chain(order[::-1])
    return np.array(lower[:-1] + upper[:-1], int)


class HullMaterials(eqx.Module):
    """Continuous materials: logits → a model glass inside the convex hull of a catalog.

    Attributes:
        corners: ``[V, 2]`` (nd, Vd) of the hull's corners, counter-clockwise.
        names: the catalog material at each corner (for messages), static.
    """

    # Strings were a JAX TypeError naming no argument; bools and complex numbers numbers.
    corners: Float[Array, "V 2"] = checks.float_field("corners", "HullMaterials", "(nd, Vd)")
    names: tuple[str, ...] = eqx.field(static=True, default=())

    def __check_init__(self):
        # Before: a NaN corner, an nd below 1 or a flat [V] array built a hull whose glasses
        # were NaN or not glasses at all, seen only as a NaN loss after the set-up.
        c = self.corners
        if c.ndim != 2 or c.shape[1] != 2 or c.shape[0] < 3:
            raise ValueError(f"HullMaterials: corners must be [V, 2] (nd, Vd) pairs of a hull "
                             f"with V >= 3 corners, got shape {c.shape}")
        if not checks.is_traced(c):
            checks.real_values(c, "corners", "HullMaterials", "(nd, Vd)")
            checks.values(c[:, 0], "corners nd", "HullMaterials", lo=1.0, hi=MAX_ND,
                          unit="(refractive index)")
            checks.values(c[:, 1], "corners Vd", "HullMaterials", lo=0, lo_open=True,
                          unit="(Abbe number)")
            # Corners on one line (or repeated) made logits() fail on a singular matrix.
            v = np.asarray(c, float) / np.array([catalog.ND_PER_VD, 1.0])
            w = np.roll(v, -1, axis=0)
            area = 0.5 * abs(np.sum(v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]))
            if not area > 1e-9 * max(1.0, float(np.ptp(v, 0).max()) ** 2):
                raise ValueError(f"HullMaterials: corners must span an area on the glass map "
                                 f"(nd, Vd), got {len(v)} corners on one line or repeated: "
                                 f"{np.asarray(c, float).round(5).tolist()}")
        if not (isinstance(self.names, tuple) and all(isinstance(n, str) for n in self.names)
                and len(self.names) in (0, c.shape[0])):  # names label the corners in messages
            raise ValueError(f"HullMaterials: names must be () or a tuple of {c.shape[0]} str, "
                             f"one per corner, got {self.names!r}")

    def nd_vd(self, m: Float[Array, "*b E V"]) -> Float[Array, "*b E 2"]:
        """(nd, Vd) of each element: the softmax-weighted mean of the corners."""
        w = jax.nn.softmax(m, axis=-1)
        return w @ self.corners.astype(w.dtype)

    def materials(self, m: Float[Array, "E V"]) -> tuple[ModelGlass, ...]:
        """One model glass per element (unbatched ``m``)."""
        p = self.nd_vd(m)
        return tuple(ModelGlass(p[e, 0], p[e, 1]) for e in range(p.shape[0]))

    def logits(self, nd: float, vd: float) -> np.ndarray:
        """Logits whose point is (nd, Vd), or the hull point toward it when it lies outside.

        The point is written in the fan of triangles (centre, corner i, corner i+1), centre
        the corners' mean; the centre's share is spread over every corner, so every weight
        is positive when the point is inside the hull (exact then, up to the 1e-6 floor).
        """
        _check_point(nd, vd, "HullMaterials.logits")  # NaN failed as "cannot unpack None"
        v = np.asarray(self.corners, float) / np.array([catalog.ND_PER_VD, 1.0])
        q = np.array([nd / catalog.ND_PER_VD, vd])
        g = v.mean(0)
        n = len(v)
        best = None
        for i in range(n):
            a, b = v[i], v[(i + 1) % n]
            lam = np.linalg.solve(np.stack([a - g, b - g], 1), q - g)  # q = g + l0(a-g) + l1(b-g)
            if lam.min() >= -1e-12 and (best is None or lam.min() > best[1].min()):
                best = (i, lam)
        i, lam = best  # the direction of q from g falls in one fan triangle
        lam = np.clip(lam, 0.0, None)
        if lam.sum() > 1.0:  # outside the hull: go to the boundary toward q
            lam = lam / lam.sum()
        w = np.full(n, (1.0 - lam.sum()) / n)
        w[i] += lam[0]
        w[(i + 1) % n] += lam[1]
        return np.log(np.maximum(w, _LOGIT_FLOOR))


class TableMaterials(eqx.Module):
    """Fixed per-design materials as index tables at the design wavelengths.

    Attributes:
        wavelengths: ``[W]`` the design wavelengths, µm.
    """

    wavelengths: Float[Array, " W"] = eqx.field(converter=jnp.asarray)

    def __check_init__(self):  # before: nm (587.6) or NaN made tables no trace could use
        w = self.wavelengths
        if w.ndim != 1 or w.shape[0] == 0:
            raise ValueError(f"TableMaterials: wavelengths must be a 1-D array [W] (µm), got "
                             f"shape {w.shape}")
        if not checks.is_traced(w):
            checks.real_values(w, "wavelengths", "TableMaterials", "µm")
            checks.wavelengths(checks.NoMaterials, w, "TableMaterials", "wavelengths")
            if len(np.unique(np.asarray(w))) < w.shape[0]:  # Tabulated refused it only later
                raise ValueError(f"TableMaterials: wavelengths must be distinct (one index per "
                                 f"wavelength), got {np.asarray(w).tolist()} µm")

    def materials(self, m: Float[Array, "E W"]) -> tuple[Tabulated, ...]:
        """One tabulated material per element (unbatched ``m``: indices at the wavelengths)."""
        wl = self.wavelengths.astype(m.dtype)
        return tuple(Tabulated(wl, m[e]) for e in range(m.shape[0]))


@dataclasses.dataclass(frozen=True)
class CatalogRegion:
    """The materials of some catalogs, their glass-map points and hull.

    Attributes:
        catalogs: the catalog names searched, in order (``jaxlens.optics.catalog``).
        names: material names still made (a name in an earlier catalog is not repeated;
            obsolete glasses, Zemax status 2, are left out).
        points: ``[N, 2]`` their catalog (nd, Vd).
    """

    catalogs: tuple[str, ...]
    names: tuple[str, ...]
    points: np.ndarray

    def __post_init__(self):  # before: NaN points or a name short were taken as given
        pts = np.asarray(self.points, float)
        if not (isinstance(self.catalogs, tuple) and isinstance(self.names, tuple)) or \
                pts.shape != (len(self.names), 2):
            raise ValueError(f"CatalogRegion: catalogs and names must be tuples and points "
                             f"[{len(self.names)}, 2] (nd, Vd) of the names, got "
                             f"{type(self.catalogs).__name__}, {type(self.names).__name__} and "
                             f"points of shape {pts.shape}")
        if len(pts):
            _check_point(pts[:, 0], pts[:, 1], "CatalogRegion")

    @staticmethod
    def of(catalogs: Sequence[str] = DEFAULT_CATALOGS) -> CatalogRegion:
        """The region of the named catalogs (ValueError for an unknown or too small one)."""
        if isinstance(catalogs, str):  # one name, not its letters ('S', 'C', 'H', ...)
            catalogs = (catalogs,)
        catalogs = tuple(str(c).strip().upper() for c in catalogs)
        if not catalogs or not all(catalogs):
            raise ValueError(f"material catalogs: need at least one catalog name, got "
                             f"{catalogs!r}; shipped: {list(catalog.SHIPPED_CATALOGS)}")
        # Glasses no longer made are left out: a design must be buildable (the SCHOTT
        # catalog keeps its obsolete glasses for the lens files that name them).
        names = tuple(catalog.catalog_names(catalogs=catalogs, obsolete=False))
        pts = np.array([catalog.glass_info(n, catalogs)[1:] for n in names], float)
        ok = np.isfinite(pts).all(1) & (pts[:, 0] > 1.0) & (pts[:, 1] > 0.0)
        names, pts = tuple(n for n, k in zip(names, ok, strict=True) if k), pts[ok]
        if len(names) < 3 or len(convex_hull(pts)) < 3:
            raise ValueError(f"material catalogs {list(catalogs)}: need at least 3 materials "
                             f"that span an area of the (nd, Vd) map, got {list(names)}")
        return CatalogRegion(catalogs, names, pts)

    def hull(self) -> HullMaterials:
        """The continuous material model over this region."""
        idx = convex_hull(self.points)
        return HullMaterials(self.points[idx], tuple(self.names[i] for i in idx))

    def distances(self, nd, vd) -> np.ndarray:
        """Glass-map distance of (nd, Vd) (broadcast, ``[...]``) to every material ``[..., N]``."""
        _check_point(nd, vd, "CatalogRegion.distances")
        return self._distances(nd, vd)

    def _distances(self, nd, vd) -> np.ndarray:
        nd = np.asarray(nd, float)[..., None]
        vd = np.asarray(vd, float)[..., None]
        return np.hypot((nd - self.points[:, 0]) / catalog.ND_PER_VD, vd - self.points[:, 1])

    def nearest(self, nd, vd) -> np.ndarray:
        """Index into ``names`` of the nearest material to each (nd, Vd) (broadcast)."""
        _check_point(nd, vd, "CatalogRegion.nearest")
        return np.argmin(self._distances(nd, vd), axis=-1)

    def material(self, name: str):
        """The catalog material ``name`` from this region's catalogs."""
        return catalog.get_material(name, self.catalogs)

    def table(self, names: Sequence[str], wavelengths) -> np.ndarray:
        """``[E, W]`` indices of the named materials at the wavelengths (µm)."""
        wl = jnp.asarray(np.asarray(wavelengths, float))
        return np.stack([np.asarray(self.material(n).index(wl), float) for n in names])


def _check_point(nd, vd, where: str) -> None:
    """Refuse a glass-map point that is not real numbers, nd in (1, MAX_ND] and Vd > 0: a NaN
    point's distances are NaN and ``argmin`` of them is 0, the first material, silently."""
    checks.real_values(nd, "nd", where, "d-line index")
    checks.real_values(vd, "vd", where, "Abbe number")
    checks.values(nd, "nd", where, lo=1, hi=MAX_ND, lo_open=True,
                  unit="(the d-line index; an nd above it is an Abbe number: nd and vd swapped?)")
    checks.values(vd, "vd", where, lo=0, lo_open=True, unit="(Abbe number)")


def check_mode(mode: str, where: str = "design") -> str:
    """``mode`` if it is a selection mode, else a ValueError naming the valid ones."""
    if mode not in SELECTION_MODES:
        raise ValueError(f"{where}: material selection must be one of {list(SELECTION_MODES)}, "
                         f"got {mode!r}")
    return mode


def initial_logits(hull: HullMaterials, names: Sequence[str]) -> np.ndarray:
    """``[E, V]`` logits that start each element at its named material's (nd, Vd)."""
    return np.stack([hull.logits(*catalog.glass_info(n)[1:]) for n in names])


def snap(region: CatalogRegion, hull: HullMaterials, m) -> tuple[np.ndarray, list]:
    """Continuous materials ``m`` ``[B, E, V]`` → their points ``[B, E, 2]`` and the nearest
    catalog material names per design (``B`` tuples of ``E`` names)."""
    pts = np.asarray(hull.nd_vd(jnp.asarray(np.asarray(m, float))))
    # Unchecked: a diverged design's NaN point must not stop the others' snapping.
    idx = np.argmin(region._distances(pts[..., 0], pts[..., 1]), axis=-1)
    return pts, [tuple(region.names[j] for j in row) for row in idx]


@eqx.filter_jit
def _candidate_losses(objective, params, args, tables):
    """Loss of every design ``[B]`` with every candidate material table ``[B, C, E, W]``."""

    def one(p, a, t):
        def loss(tt):
            aux = objective(eqx.tree_at(lambda q: q.m, p, tt), a)[1]
            return aux.loss, aux.spot

        return jax.vmap(loss)(t)

    return jax.vmap(one)(params, args, tables)


def search(region: CatalogRegion, objective, params, args, names: list, wavelengths,
           sweeps: int = 2) -> list:
    """Discrete search: each element's catalog material by the design loss, geometry held.

    Coordinate descent from ``names`` (per design, e.g. the nearest snap): for each element
    in turn every material of the region is tried in its place and the one with the lowest
    design loss kept; ``sweeps`` passes over the elements.

    Args:
        region: the catalog region.
        objective: a design objective whose parameterisation has ``TableMaterials``.
        params: ``LensParams`` ``[B, …]`` (``m`` is replaced here).
        args: ``StageArgs`` ``[B]`` of the loss to compare with; its ``spot_scale`` is set
            here to 1 / the spot term of the starting materials (as the design loop does).
        names: ``B`` tuples of ``E`` starting names.
        wavelengths: the design wavelengths (µm) of the tables.
        sweeps: passes over the elements.

    Returns:
        ``B`` tuples of the chosen names.
    """
    allt = region.table(region.names, wavelengths)  # [N, W]
    index = {n: i for i, n in enumerate(region.names)}
    choice = np.array([[index[n] for n in row] for row in names])  # [B, E]
    b, e_count = choice.shape
    dtype = params.c.dtype
    start = jnp.asarray(allt[choice][:, None], dtype)  # [B, 1, E, W]
    spot = _candidate_losses(objective, params, args, start)[1][:, 0]
    args = eqx.tree_at(lambda a: a.spot_scale, args, 1.0 / jnp.maximum(spot, 1e-12))
    for _ in range(sweeps):
        for e in range(e_count):
            tables = np.broadcast_to(allt[choice][:, None], (b, len(allt)) + allt[choice].shape[1:])
            tables = tables.copy()
            tables[:, :, e] = allt[None]  # candidate c in element e
            losses = np.asarray(_candidate_losses(objective, params, args,
                                                  jnp.asarray(tables, dtype))[0])
            losses = np.where(np.isfinite(losses), losses, np.inf)
            choice[:, e] = np.argmin(losses, axis=1)
    return [tuple(region.names[j] for j in row) for row in choice]
