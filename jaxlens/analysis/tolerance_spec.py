"""The tolerance half-ranges of ``jaxlens.analysis.tolerance`` (``Tolerances``) and their limits.

Units: thickness, irregularity, asphere sag and decenter in mm, tilt in degrees, radius and
Abbe number relative, index and conic absolute. Each is a ± half-range; the module docstring of
``jaxlens.analysis.tolerance`` gives their meaning.
"""

from __future__ import annotations

import dataclasses
import math

DECENTER_TILT = ("element decenter x, y (mm) and tilt about x, y (degrees, about the element's "
                 "front vertex) of every air-bounded element (a cemented group moves as one) "
                 "between two coordinate breaks, as Zemax's TEDX/TEDY/TETX/TETY; toleranced "
                 "when Tolerances.decenter or tilt > 0 (default 0: off)")

DISTRIBUTIONS = ("uniform", "normal")

MAX_TILT = 90.0
"""Tolerances.tilt must be below this (degrees): an element tilted by 90° faces sideways."""

MAX_THICKNESS = 10.0
"""Tolerances.thickness must be below this (mm): fabrication and assembly tolerances of
thickness and spacing are 0.01–0.5 mm (ISO 10110-style drawings), and a ±10 mm shift is
a focus or zoom position, which belongs in the lens, not its tolerances. A ToleranceModel
also needs it below the thinnest glass thickness of its lens (a thinner element would be
traced with its surfaces crossed)."""

MAX_FORM_SAG = 0.1
"""Tolerances.irregularity and asphere_sag must be below this (mm of sag at the clear
semi-diameter): optical drawings give surface form in fringes, a few at most (one fringe is
λ/2, about 0.3 µm), so 0.1 mm is some 300 fringes; a sag error that large is another surface,
or a value given in µm where mm are meant."""

MAX_INDEX = 0.1
"""Tolerances.index must be below this (absolute nd): melt tolerance classes are ±0.0002 to
±0.001, and ±0.1 is another glass (±1 would put the index below that of air)."""

MAX_CONIC = 1.0
"""Tolerances.conic must be below this (absolute): ±1 turns a sphere into a paraboloid or a
flat-vertex ellipsoid; conic tolerances of figured aspheres are ~0.001–0.05."""

MAX_TRIALS = 1_000_000
"""Most Monte-Carlo trials (about a day of tracing; their perturbations take trials·P·8 bytes)."""


def _nonneg(value, name: str, unit: str) -> float:
    try:  # float("0.02") would read a string as a number
        v = float("nan") if isinstance(value, (str, bytes, bool)) else float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not math.isfinite(v) or v < 0:
        raise ValueError(f"Tolerances: {name} must be a finite number >= 0{unit}, got "
                         f"{value!r}")
    return v


@dataclasses.dataclass(frozen=True)
class Tolerances:
    """Tolerance half-ranges (± each value). See the module docstring for their meaning.

    Attributes:
        radius_rel: relative radius tolerance (0.005 = ±0.5 % of R); flat surfaces get none.
        thickness: mm, every thickness including the image distance; below
            ``MAX_THICKNESS`` (10 mm) and, in a ``ToleranceModel``, below the lens's thinnest
            glass thickness.
        index: absolute nd, below ``MAX_INDEX`` (0.1).
        abbe_rel: relative Abbe-number tolerance (0.005 = ±0.5 % of Vd).
        irregularity: mm, peak sag of an r⁴ form error at the clear semi-diameter; below
            ``MAX_FORM_SAG`` (0.1 mm).
        conic: absolute conic constant (sensitivity table only), below ``MAX_CONIC`` (1).
        asphere_sag: mm; each asphere coefficient a_i gets the tolerance asphere_sag / h^(2i),
            the change that moves the sag at the clear semi-diameter h by that much
            (sensitivity table only); below ``MAX_FORM_SAG`` (0.1 mm).
        decenter: mm, each element's decenter in x and in y (0: off; see the module docstring);
            in a ``ToleranceModel`` below the lens's smallest clear semi-diameter.
        tilt: degrees, each element's tilt about x and about y (0: off; below 90).
        distribution: Monte-Carlo law: "uniform" over ±tolerance, or "normal" with σ =
            tolerance/2 truncated at ±tolerance.
    """

    radius_rel: float = 0.005
    thickness: float = 0.02
    index: float = 0.0005
    abbe_rel: float = 0.005
    irregularity: float = 0.5e-3
    conic: float = 0.01
    asphere_sag: float = 0.5e-3
    decenter: float = 0.0
    tilt: float = 0.0
    distribution: str = "uniform"

    def __post_init__(self):
        units = {"radius_rel": " (relative)", "thickness": " mm", "index": "",
                 "abbe_rel": " (relative)", "irregularity": " mm", "conic": "",
                 "asphere_sag": " mm", "decenter": " mm", "tilt": " degrees"}
        for name, unit in units.items():
            object.__setattr__(self, name, _nonneg(getattr(self, name), name, unit))
        if self.tilt >= MAX_TILT:
            # A tilt of 90° turns an element sideways, and one of 360° is no tilt at all: the
            # sensitivity table showed a ±360° tilt as harmless.
            raise ValueError(f"Tolerances: tilt must be below {MAX_TILT:g} degrees (each "
                             f"element's tilt about x and about y), got {self.tilt!r}")
        if self.thickness >= MAX_THICKNESS:
            # Before: any value; a ±1e6 mm thickness tolerance gave a report of huge spots.
            raise ValueError(f"Tolerances: thickness must be below {MAX_THICKNESS:g} mm (a "
                             f"fabrication or assembly tolerance, each thickness ± it), got "
                             f"{self.thickness!r}")
        for name, limit, what in (
                ("irregularity", MAX_FORM_SAG, "mm (peak sag of an r^4 form error at the "
                 "clear semi-diameter; 1 fringe is about 0.0003 mm)"),
                ("asphere_sag", MAX_FORM_SAG, "mm (sag change at the clear semi-diameter)"),
                ("index", MAX_INDEX, "(absolute nd; melt tolerances are 0.0002-0.001)"),
                ("conic", MAX_CONIC, "(absolute conic constant)")):
            if getattr(self, name) >= limit:
                # Before: any value; irregularity=1 (mm, meant as µm or fringes) gave a
                # Monte-Carlo of surfaces bent by a millimetre.
                raise ValueError(f"Tolerances: {name} must be below {limit:g} {what}, got "
                                 f"{getattr(self, name)!r}")
        if self.radius_rel >= 0.5 or self.abbe_rel >= 0.5:
            raise ValueError(f"Tolerances: radius_rel and abbe_rel must be below 0.5 "
                             f"(relative), got {self.radius_rel!r} and {self.abbe_rel!r}")
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"Tolerances: distribution must be one of {DISTRIBUTIONS}, got "
                             f"{self.distribution!r}")

    def describe(self) -> dict:
        """The tolerances with their units, for reports."""
        return {
            "radius": {"value": self.radius_rel, "unit": "relative (dR/R)"},
            "thickness": {"value": self.thickness, "unit": "mm"},
            "index": {"value": self.index, "unit": "nd"},
            "abbe": {"value": self.abbe_rel, "unit": "relative (dVd/Vd)"},
            "irregularity": {"value": self.irregularity,
                             "unit": "mm peak sag of r^4 at the clear semi-diameter"},
            "conic": {"value": self.conic, "unit": "absolute k (sensitivity only)"},
            "asphere": {"value": self.asphere_sag,
                        "unit": "mm sag at the clear semi-diameter (sensitivity only)"},
            "decenter": {"value": self.decenter, "unit": "mm, each element in x and in y"},
            "tilt": {"value": self.tilt,
                     "unit": "degrees, each element about x and about y (front vertex)"},
            "decenter_tilt": DECENTER_TILT,
            "distribution": (self.distribution + (" over +-tolerance" if self.distribution
                                                  == "uniform" else
                                                  ", sigma = tolerance/2, truncated")),
        }
