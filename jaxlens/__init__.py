"""jaxlens: differentiable lens design in JAX.

Units: mm for lengths, µm for wavelengths, degrees for user-facing angles. Light travels
toward +z and surface 1's vertex is at z = 0. See ``jaxlens.lens`` and ``jaxlens.surfaces``
for the sign conventions.
"""

from . import analysis as analysis
from . import catalog as catalog
from . import distortion_relax as distortion_relax
from . import images as images
from . import nets as nets
from . import paraxial as paraxial
from . import psf as psf  # callable: jaxlens.psf(...) is jaxlens.psf.psf(...)
from . import radiometry as radiometry
from . import render as render  # callable: jaxlens.render(...) is jaxlens.render.render(...)
from . import reverse as reverse
from . import sampling as sampling
from . import zoo as zoo
from .catalog import CatalogMaterial as CatalogMaterial
from .catalog import catalog_names as catalog_names
from .catalog import get_material as get_material
from .catalog import glass_info as glass_info
from .catalog import load_agf as load_agf
from .catalog import register_catalog as register_catalog
from .files import load as load
from .files import save as save
from .lens import Lens as Lens
from .lens import Sensor as Sensor
from .materials import AbstractMaterial as AbstractMaterial
from .materials import Air as Air
from .materials import ModelGlass as ModelGlass
from .materials import Schott as Schott
from .materials import Sellmeier as Sellmeier
from .materials import Tabulated as Tabulated
from .paraxial import ParaxialData as ParaxialData
from .paraxial import bfl as bfl
from .paraxial import efl as efl
from .paraxial import paraxial_data as paraxial_data
from .rays import Rays as Rays
from .surfaces import AbstractSurface as AbstractSurface
from .surfaces import Conic as Conic
from .surfaces import EvenAsphere as EvenAsphere
from .surfaces import Hybrid as Hybrid
from .surfaces import Plane as Plane
from .surfaces import Sphere as Sphere
from .surfaces import Standard as Standard
from .surfaces import Stop as Stop
from .trace import trace as trace
from .trace import trace_path as trace_path

__version__ = "0.1.0"
