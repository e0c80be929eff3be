"""End-to-end extended-depth-of-field (EDoF) computational lens design.

The paper's second result (Yang, Fu & Heidrich, Nat. Commun. 2024): a large-aperture,
wide-field cellphone-style lens whose first surface becomes a hybrid surface (even asphere
plus odd polynomial terms), learned jointly with a reconstruction network so that the
image can be restored over depths from 10 cm to 10 m. ``python -m jaxlens.experiments.edof``
runs it.

Modules:
    lenses: the classical lens, the hybrid EDoF lens, the cubic-plate baseline, scaled
        trainable parameters and manufacturing perturbations.
    optics: RGB PSFs, checkpointed patch simulation, whole-image rendering and PSF
        analysis (depth variation, MTF).
    losses: L_sim, L_raw, L_rec and their weighted sum.
    scenes: training and held-out test images from ``skimage.data`` or a folder.
    train: the two training stages and the Table 2 evaluation.
"""

from . import lenses as lenses
from . import losses as losses
from . import optics as optics
from . import scenes as scenes
from . import train as train
