"""Honest evaluation of a design, independent of the design loss and its regularizers.

Conventions:
    The 256 fields are a 16 × 16 grid over the whole sensor rectangle (``linspace(−1, 1,
    16)`` along each side, so the outer rows and columns lie on the sensor's edges and the
    four corner fields are the full diagonal field). Each sensor point (x, y) is the ideal
    image of the field angles tan θx = x/f, tan θy = y/f with f the spec's focal length
    (the paper's convention: f = sensor half-diagonal / tan(half FoV), EPD = f/F#). The RMS
    spot radius of a field pools the rays of all design wavelengths (F, d, C) about their
    common centroid, with the 21 × 21 square pupil grid (317 rays per wavelength) aimed as
    the lens says (``Lens.aim``: the paraxial entrance pupil for a designed lens):
    ``jaxlens.analysis.spots.rms_spot(reference="centroid")``.

    A design counts as *valid* when ``jaxlens.analysis.spots.self_intersection`` finds no
    overlap of neighbouring surfaces (or of the last surface with the sensor) over the
    clear apertures, and at least ``min_valid`` (99 %) of the rays of every field reach
    the sensor. Designs whose rays fail are reported as failures, never as small spots.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..analysis import spots as analysis
from ..imaging import sampling
from ..imaging.light import NoLightWarning
from ..optics import checks, paraxial
from ..optics.lens import Lens
from .spec import DesignSpec, require_spec

MIN_VALID_FRACTION = 0.99


def sensor_field_grid(spec: DesignSpec, n: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """The n × n evaluation fields: ``(angles [n², 2] deg (θx, θy), sensor points [n², 2] mm)``."""
    # n = 0 gave no fields at all and n = 2.5 a TypeError deep in numpy.
    checks.number(n, "n", "sensor_field_grid", lo=1, hi=checks.MAX_MAP_GRID, integer=True,
                  unit="fields per side")
    require_spec(spec, "sensor_field_grid")
    h, w = spec.sensor_size
    f = spec.focal_length
    u = sampling.grid_axis(n)  # corner to corner; n = 1 evaluated the corner alone
    xs, ys = u * w / 2, u * h / 2
    x, y = np.meshgrid(xs, ys)
    pts = np.stack([x.ravel(), y.ravel()], -1)
    ang = np.degrees(np.arctan(pts / f))
    return ang, pts


@dataclasses.dataclass
class Evaluation:
    """Evaluation of one design (lengths in mm unless the name says µm)."""

    rms_um: np.ndarray  # [n²] polychromatic RMS spot radius per field
    valid_fraction: np.ndarray  # [n²] fraction of rays reaching the sensor
    rms_mean_um: float
    rms_max_um: float
    self_intersection: bool
    geometry: str
    min_gap: float
    rays_ok: bool
    valid: bool
    efl: float
    fnum: float
    bfl: float
    total_track: float
    chief_height_full_field: float
    distortion_percent: float

    def summary(self) -> dict:
        d = dataclasses.asdict(self)
        d.pop("rms_um")
        d.pop("valid_fraction")
        d["min_valid_fraction"] = float(np.min(self.valid_fraction))
        return d


def evaluate(lens: Lens, spec: DesignSpec, *, n: int = 16,
             min_valid: float = MIN_VALID_FRACTION) -> Evaluation:
    """Evaluate a design on the n × n sensor grid (see module docstring)."""
    if not isinstance(lens, Lens):
        raise TypeError(f"evaluate: lens must be a jaxlens Lens, got {type(lens).__name__}")
    require_spec(spec, "evaluate")  # a dict failed as an AttributeError (spec.epd)
    # min_valid above 1 would call every design invalid, below 0 every one valid.
    checks.number(min_valid, "min_valid", "evaluate", lo=0, hi=1, unit="(fraction of rays)")
    checks.number(n, "n", "evaluate", lo=1, hi=checks.MAX_MAP_GRID, integer=True,
                  unit="fields per side")
    lens = lens.astype(jnp.float64)
    lens = eqx.tree_at(lambda l: l.epd, lens, jnp.asarray(spec.epd, jnp.float64))
    ang, _ = sensor_field_grid(spec, n)
    with warnings.catch_warnings():  # dark fields are judged below (rays_ok)
        warnings.simplefilter("ignore", NoLightWarning)
        res = analysis.rms_spot(lens, jnp.asarray(ang), jnp.asarray(spec.wavelengths))
    rms = np.asarray(res.polychromatic) * 1e3
    frac = np.asarray(jnp.min(res.valid_fraction, axis=-1))
    geo = analysis.self_intersection(lens)
    si = not bool(geo.ok)
    rays_ok = bool(np.all(frac >= min_valid)) and bool(np.all(np.isfinite(rms)))
    pd = paraxial.paraxial_data(lens)
    full = spec.half_fov
    chief = analysis.chief_ray(lens, full)
    h = float(chief.origin[1])
    ideal = float(pd.efl) * math.tan(math.radians(full))
    dist = 100.0 * (h - ideal) / ideal if ideal else float("nan")
    return Evaluation(
        rms_um=rms, valid_fraction=frac, rms_mean_um=float(np.mean(rms)),
        rms_max_um=float(np.max(rms)), self_intersection=si, geometry=geo.summary(),
        min_gap=float(jnp.min(geo.min_gap)), rays_ok=rays_ok, valid=(not si) and rays_ok,
        efl=float(pd.efl), fnum=float(pd.fnum), bfl=float(pd.bfl),
        total_track=float(pd.total_track), chief_height_full_field=h,
        distortion_percent=dist)
