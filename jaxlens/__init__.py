"""jaxlens: differentiable lens design in JAX.

Units: mm for lengths, µm for wavelengths, degrees for user-facing angles. Light travels
toward +z and surface 1's vertex is at z = 0. See ``jaxlens.optics.lens`` and
``jaxlens.optics.surfaces`` for the sign conventions.


Layout (each layer imports only from the layers above it):
    optics     surfaces, materials, glass catalogs, the lens, rays, paraxial optics
    tracing    the one tracer: surface step, forward and backward traces
    imaging    ray sources and aiming, PSFs, MTF, radiometry, distortion, rendering
    analysis   spots, RMS, distortion, geometry checks, tolerancing (``jaxlens.tolerance``),
               the report
    io         lens files (JSON, .zmx) and images
    design     ab initio lens design (spec, parameters, losses, solvers, curriculum)
    nets       reconstruction networks
    experiments  ``python -m jaxlens.experiments.classical`` / ``.edof``
"""

from . import analysis as analysis
from . import imaging as imaging
from . import io as io
from . import nets as nets
from . import optics as optics
from . import tracing as tracing
from . import zoo as zoo
from .analysis import tolerance as tolerance
from .imaging import sampling as sampling
from .imaging.psf import psf as psf
from .imaging.render import render as render
from .io import images as images
from .io.files import load as load
from .io.files import save as save
from .optics import catalog as catalog
from .optics import paraxial as paraxial
from .optics.apertures import Aperture as Aperture
from .optics.catalog import CatalogMaterial as CatalogMaterial
from .optics.catalog import catalog_names as catalog_names
from .optics.catalog import get_material as get_material
from .optics.catalog import glass_info as glass_info
from .optics.catalog import load_agf as load_agf
from .optics.catalog import register_catalog as register_catalog
from .optics.coordinates import CoordinateBreak as CoordinateBreak
from .optics.diffractive import Binary2 as Binary2
from .optics.diffractive import Grating as Grating
from .optics.freeform import Biconic as Biconic
from .optics.freeform import ZernikeSag as ZernikeSag
from .optics.lens import RAY_AIMING as RAY_AIMING
from .optics.lens import Lens as Lens
from .optics.lens import Sensor as Sensor
from .optics.materials import AbstractMaterial as AbstractMaterial
from .optics.materials import Air as Air
from .optics.materials import ModelGlass as ModelGlass
from .optics.materials import Schott as Schott
from .optics.materials import Sellmeier as Sellmeier
from .optics.materials import Tabulated as Tabulated
from .optics.paraxial import ParaxialData as ParaxialData
from .optics.paraxial import bfl as bfl
from .optics.paraxial import efl as efl
from .optics.paraxial import paraxial_data as paraxial_data
from .optics.qtype import QTypeAsphere as QTypeAsphere
from .optics.rays import Rays as Rays
from .optics.surfaces import AbstractSurface as AbstractSurface
from .optics.surfaces import Conic as Conic
from .optics.surfaces import EvenAsphere as EvenAsphere
from .optics.surfaces import Hybrid as Hybrid
from .optics.surfaces import OddAsphere as OddAsphere
from .optics.surfaces import Plane as Plane
from .optics.surfaces import Sphere as Sphere
from .optics.surfaces import Standard as Standard
from .optics.surfaces import Stop as Stop
from .optics.surfaces import TiltedPlane as TiltedPlane
from .optics.xypolynomial import XYPolynomial as XYPolynomial
from .tracing.backward import trace_backward as trace_backward
from .tracing.forward import trace as trace
from .tracing.forward import trace_path as trace_path

__version__ = "0.1.0"
