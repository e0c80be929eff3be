"""Files: jaxlens JSON and Zemax ``.zmx`` lenses, images (OpenEXR, PNG)."""

from . import images as images
from .files import load as load
from .files import save as save
from .json_values import MissingFolderError as MissingFolderError
