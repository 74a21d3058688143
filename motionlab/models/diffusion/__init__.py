"""MDM (Tevet et al., "Human Motion Diffusion Model", ICLR 2023) on the course benchmark.

Modules, in the order of the chapter: :mod:`.schedule` (the cosine noise schedule, the forward process and
its posterior, respacing, DDIM), :mod:`.data` (per-joint 6-D rotations and the root position, forward
kinematics back to joints, editing masks), :mod:`.model` (the config and the transformer denoiser that
predicts the clean motion), :mod:`.losses` (the simple loss and the geometric losses) and :mod:`.sampling`
(the ancestral loop, its fast variant, classifier-free guidance, inpainting).
"""

from motionlab.models.diffusion.data import MDMData, known_mask, prepare, to_positions
from motionlab.models.diffusion.losses import diffusion_objective
from motionlab.models.diffusion.model import MDM, MDMConfig
from motionlab.models.diffusion.sampling import Edit, guided_prediction, sample
from motionlab.models.diffusion.schedule import NoiseSchedule

__all__ = [
    "MDM",
    "Edit",
    "MDMConfig",
    "MDMData",
    "NoiseSchedule",
    "diffusion_objective",
    "guided_prediction",
    "known_mask",
    "prepare",
    "sample",
    "to_positions",
]
