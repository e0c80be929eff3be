"""The optical system as data: surfaces, materials, glass catalogs, the lens, rays, paraxial.

Everything here is a pytree (``equinox.Module``) or a pure function of one; nothing traces rays
except the paraxial y–nu trace. Conventions: lengths in mm, wavelengths in µm, light toward +z,
curvature c = 1/R, a surface carries the medium after it (see ``lens``).
"""

from . import catalog as catalog
from . import coordinates as coordinates
from . import diffractive as diffractive
from . import freeform as freeform
from . import materials as materials
from . import paraxial as paraxial
from . import qtype as qtype
from . import surfaces as surfaces
from . import xypolynomial as xypolynomial
from .coordinates import CoordinateBreak as CoordinateBreak
from .diffractive import Binary2 as Binary2
from .diffractive import Grating as Grating
from .freeform import Biconic as Biconic
from .freeform import ZernikeSag as ZernikeSag
from .lens import RAY_AIMING as RAY_AIMING
from .lens import Lens as Lens
from .lens import Sensor as Sensor
from .qtype import QTypeAsphere as QTypeAsphere
from .rays import Rays as Rays
from .xypolynomial import XYPolynomial as XYPolynomial
