"""Ab initio lens design: random starts, the curriculum, losses, regularizers, solvers.

Implements the curriculum design of Yang, Fu & Heidrich, "Curriculum learning for ab initio
deep learned refractive optics", Nat. Commun. 15, 6572 (2024), in JAX:

* :class:`DesignSpec` (``spec``): what to design; impossible specs fail on construction.
* :func:`random_starts` (``init``): seeded, nearly flat random starting points, in the
  order-1 parameterisation of ``params`` (:class:`LensParams`, :class:`Parameterization`).
* :func:`sine_path`, :func:`paper_stages`, :func:`run` (``curriculum``): the sine-path
  schedule of FoV and F-number, and the plain Python design loop (one jitted update a step).
* :class:`Objective`, :class:`ImageObjective` (``losses``): the ray-based RMS spot loss and
  the image-based loss through ``jaxlens.imaging.render`` with distortion relaxation.
* ``regularizers``: ray obliquity, surface spacing and surface slope, zero inside bounds.
* :func:`reweighting_mask` (``mask``): the paper's field re-weighting mask.
* :class:`Adam`, :class:`DampedLeastSquares`, :class:`LevenbergMarquardt`, :class:`LBFGSB`
  (``solvers``): one interface over optax, a jacfwd Levenberg–Marquardt, optimistix and
  jaxopt.
* :func:`design` (``multistart``): many seeds at once, vmapped and sharded over devices.
* :class:`CatalogRegion`, :class:`HullMaterials` (``materials``): material selection, each
  element's (nd, Vd) free inside a catalog's hull, then snapped to a catalog material.
* :func:`evaluate_design` (``evaluate.evaluate``): the honest 256-field evaluation and
  validity check.

Example:
    >>> from jaxlens.design import DesignSpec
    >>> round(DesignSpec().focal_length, 3)
    4.5
"""

from .curriculum import Stage, paper_stages, run, sine_path
from .evaluate import Evaluation, sensor_field_grid
from .evaluate import evaluate as evaluate_design
from .init import parameterization, random_params, random_starts
from .losses import ImageObjective, Objective, RayLoss, StageArgs
from .mask import reweighting_mask
from .materials import CatalogRegion, HullMaterials, TableMaterials
from .multistart import DesignConfig, DesignResult, design
from .params import LensParams, Parameterization
from .solvers import LBFGSB, Adam, DampedLeastSquares, LevenbergMarquardt, SolverResult
from .spec import DesignSpec

__all__ = [
    "LBFGSB",
    "Adam",
    "CatalogRegion",
    "DampedLeastSquares",
    "DesignConfig",
    "DesignResult",
    "DesignSpec",
    "Evaluation",
    "HullMaterials",
    "ImageObjective",
    "LensParams",
    "LevenbergMarquardt",
    "Objective",
    "Parameterization",
    "RayLoss",
    "SolverResult",
    "Stage",
    "StageArgs",
    "TableMaterials",
    "design",
    "evaluate_design",
    "paper_stages",
    "parameterization",
    "random_params",
    "random_starts",
    "reweighting_mask",
    "run",
    "sensor_field_grid",
    "sine_path",
]
