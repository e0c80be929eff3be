"""Real-ray analysis: spots, RMS, distortion, ray fans, field curvature, encircled energy,
third-order (Seidel) aberrations, clear apertures, geometry checks, tolerancing, the report."""

from . import tolerance as tolerance
from .aberrations import FieldCurvature as FieldCurvature
from .aberrations import RayFan as RayFan
from .aberrations import field_curvature as field_curvature
from .aberrations import ray_fan as ray_fan
from .encircled import EncircledEnergy as EncircledEnergy
from .encircled import encircled_energy as encircled_energy
from .encircled import radius_for_fraction as radius_for_fraction
from .seidel import Seidel as Seidel
from .seidel import seidel as seidel
from .spots import Distortion as Distortion
from .spots import GeometryCheck as GeometryCheck
from .spots import RmsSpot as RmsSpot
from .spots import chief_ray as chief_ray
from .spots import clear_semi_diameters as clear_semi_diameters
from .spots import distortion as distortion
from .spots import rms_spot as rms_spot
from .spots import self_intersection as self_intersection
from .spots import spot_rays as spot_rays
