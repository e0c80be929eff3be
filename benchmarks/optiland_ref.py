"""optiland as an independent reference tracer for the throughput benchmark (optional).

optiland (https://github.com/HarrisonKramer/optiland) is *not* a jaxlens dependency: it is
imported only here, and every caller checks :func:`available` first. A jaxlens ``Lens`` is
rebuilt as an optiland ``Optic`` at one wavelength: the same curvatures, conics, even
asphere coefficients (optiland's list starts at r², like jaxlens), thicknesses and stop, with
each medium an ``IdealMaterial`` holding jaxlens's index at that wavelength, so both codes
trace the same geometry. Rays are handed over as they are (same origins and directions), and
optiland's numpy backend traces them with ``optic.surfaces.trace(rays, skip=1,
record=False)``: the object surface is skipped because the rays already start in object
space, and nothing is recorded per surface.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

import jaxlens


def available() -> bool:
    """True if optiland can be imported."""
    try:
        import optiland  # noqa: F401
    except Exception:  # noqa: BLE001 - any import failure means "not available"
        return False
    return True


def build_optic(lens: jaxlens.Lens, wavelength: float):
    """An optiland ``Optic`` with the lens's geometry and its indices at ``wavelength`` (µm)."""
    from optiland import optic
    from optiland.materials import IdealMaterial

    if not lens.object_at_infinity:
        raise ValueError("build_optic: only objects at infinity are supported")
    op = optic.Optic()
    op.surfaces.add(index=0, radius=np.inf, thickness=np.inf)
    idx = [float(n) for n in lens.indices(wavelength)]
    for i, s in enumerate(lens.surfaces):
        c = float(s.c)
        radius = math.inf if c == 0 else 1.0 / c
        kw = dict(
            index=i + 1,
            radius=radius,
            thickness=float(lens.thickness[i]),
            conic=float(s.k),
            is_stop=i == lens.stop,
        )
        bx, _ = s.odd_coeffs()
        if bx.shape[0]:
            raise ValueError("build_optic: odd (hybrid) terms are not supported by this bridge")
        a = np.asarray(s.even_coeffs(), float)
        if a.shape[0]:
            kw.update(surface_type="even_asphere", coefficients=[float(v) for v in a])
        n_after = idx[i + 1]
        kw["material"] = "air" if n_after == 1.0 else IdealMaterial(n=n_after)
        op.surfaces.add(**kw)
    op.surfaces.add(index=len(lens.surfaces) + 1)
    op.set_aperture(aperture_type="EPD", value=float(lens.epd))
    op.fields.set_type(field_type="angle")
    op.fields.add(y=0.0)
    op.wavelengths.add(value=float(wavelength), is_primary=True)
    return op


def make_rays(origin: np.ndarray, direction: np.ndarray, wavelength: float):
    """optiland ``RealRays`` from ``[N, 3]`` float64 origins and unit directions."""
    from optiland.rays import RealRays

    o = np.asarray(origin, np.float64)
    d = np.asarray(direction, np.float64)
    n = o.shape[0]
    return RealRays(
        o[:, 0].copy(),
        o[:, 1].copy(),
        o[:, 2].copy(),
        d[:, 0].copy(),
        d[:, 1].copy(),
        d[:, 2].copy(),
        np.ones(n),
        np.full(n, wavelength),
    )


def trace(op, origin: np.ndarray, direction: np.ndarray, wavelength: float):
    """Trace with optiland's numpy backend; returns the rays on the image surface.

    Building the ``RealRays`` (a copy of six arrays) is included, as it would be for any caller.
    """
    rays = make_rays(origin, direction, wavelength)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numba's NumbaIRAssumptionWarning on first compile
        op.surfaces.trace(rays, skip=1, record=False)
    return rays


def intercepts(rays) -> np.ndarray:
    """``[N, 3]`` image-surface intercepts of optiland rays."""
    return np.stack([np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.z)], -1)


if __name__ == "__main__":  # ran nothing, without a word
    raise SystemExit("benchmarks.optiland_ref is a helper of the benchmarks, not one: run "
                     "python -m benchmarks (--only NAME for one benchmark)")
