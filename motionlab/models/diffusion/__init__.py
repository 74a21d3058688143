"""MDM (Tevet et al., "Human Motion Diffusion Model", ICLR 2023) on the course benchmark.

Modules, in the order of the chapter: :mod:`.schedule` (the cosine noise schedule, the forward process and
its posterior, respacing, DDIM), :mod:`.data` (per-joint 6-D rotations and the root position, forward
kinematics back to joints, editing masks), :mod:`.model` (the config and the transformer denoiser that
predicts the clean motion), :mod:`.losses` (the simple loss and the geometric losses) and :mod:`.sampling`
(the ancestral loop, its fast variant, classifier-free guidance, inpainting).
"""

from motionlab.lazy import lazy_exports

#: Each public name with the module that holds it, imported on first use: a chapter that needs one module
#: (``from motionlab.models.diffusion.losses import ...``) does not load the others.
_EXPORTS: dict[str, str] = {
    "Edit": "motionlab.models.diffusion.sampling",
    "MDM": "motionlab.models.diffusion.model",
    "MDMConfig": "motionlab.models.diffusion.model",
    "MDMData": "motionlab.models.diffusion.data",
    "NoiseSchedule": "motionlab.models.diffusion.schedule",
    "diffusion_objective": "motionlab.models.diffusion.losses",
    "guided_prediction": "motionlab.models.diffusion.sampling",
    "known_mask": "motionlab.models.diffusion.data",
    "prepare": "motionlab.models.diffusion.data",
    "sample": "motionlab.models.diffusion.sampling",
    "to_positions": "motionlab.models.diffusion.data",
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
