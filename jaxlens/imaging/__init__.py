"""Image formation on top of the tracer: ray sources and aiming, PSFs and MTF, relative
illumination, distortion maps and the checkpointed renderer (``jaxlens.psf`` and
``jaxlens.render`` are the entry points)."""

from . import aiming as aiming
from . import distortion as distortion
from . import grid as grid
from . import light as light
from . import newton as newton
from . import psf as psf
from . import radiometry as radiometry
from . import render as render
from . import sampling as sampling
