"""End-to-end extended-depth-of-field (EDoF) computational lens design.

The paper's second result (Yang, Fu & Heidrich, Nat. Commun. 2024): a large-aperture,
wide-field cellphone-style lens whose first surface becomes a hybrid surface (even asphere
plus odd polynomial terms), learned jointly with a reconstruction network so that the
image can be restored over depths from 10 cm to 10 m. ``python -m jaxlens.experiments.edof``
runs it.

Modules:
    lenses: the classical lens, the hybrid EDoF lens, the cubic-plate baseline, scaled
        trainable parameters, their gates and bounds, manufacturing perturbations.
    optics: image formation through ``jaxlens.imaging`` (PSFs normalised by the light that
        enters the pupil, PSF banks, tiled blur, sensor noise) and PSF measures.
    decoder: the NAFNet decoder, optionally behind a tiled Wiener front end.
    losses: L_sim, L_raw, L_rec and their weighted sum.
    scenes: training, validation and test images from ``skimage.data`` or a folder.
    dead_leaves: procedural dead-leaves training images (``--train-source``).
    train: the two training stages, with checkpoints.
    evaluate: per-crop Table 2 metrics, the Wiener reference, bootstrap gains.
"""

from . import decoder as decoder
from . import evaluate as evaluate
from . import lenses as lenses
from . import losses as losses
from . import optics as optics
from . import scenes as scenes
from . import train as train
