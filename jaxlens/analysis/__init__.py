"""Real-ray analysis: spots, RMS, distortion, ray fans, field curvature, encircled energy,
angular spots and magnification (afocal image space),
third-order (Seidel) aberrations, wavefront error and Zernike fits, clear apertures, geometry
checks, tolerancing, a fixed stop that clips the EPD's beam, the report."""

from . import tolerance as tolerance
from .aberrations import FieldCurvature as FieldCurvature
from .aberrations import RayFan as RayFan
from .aberrations import field_curvature as field_curvature
from .aberrations import ray_fan as ray_fan
from .afocal import AngularSpot as AngularSpot
from .afocal import angular_magnification as angular_magnification
from .afocal import angular_spot as angular_spot
from .encircled import EncircledEnergy as EncircledEnergy
from .encircled import encircled_energy as encircled_energy
from .encircled import radius_for_fraction as radius_for_fraction
from .spots import Distortion as Distortion
from .spots import GeometryCheck as GeometryCheck
from .spots import RmsSpot as RmsSpot
from .spots import chief_ray as chief_ray
from .spots import clear_semi_diameters as clear_semi_diameters
from .spots import distortion as distortion
from .spots import rms_spot as rms_spot
from .spots import self_intersection as self_intersection
from .spots import spot_rays as spot_rays
from .stop_clip import StopClip as StopClip
from .stop_clip import stop_clipping as stop_clipping
from .third_order import Seidel as Seidel
from .third_order import seidel as seidel
from .wavefront_error import OPDFan as OPDFan
from .wavefront_error import Wavefront as Wavefront
from .wavefront_error import marechal_strehl as marechal_strehl
from .wavefront_error import opd as opd
from .wavefront_error import opd_fan as opd_fan
from .wavefront_error import wavefront as wavefront
from .zernike import ZernikeFit as ZernikeFit
from .zernike import zernike_fit as zernike_fit
from .zernike import zernike_nm as zernike_nm
from .zernike import zernike_terms as zernike_terms
