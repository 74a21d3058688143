"""MDM's sampling speed: a 4-second clip from noise to 30 fps joint positions, with the full 1,000-step
ancestral loop and with respaced schedules, at batch 1 on one thread, and batched.

The model is the chapter's size (:meth:`~motionlab.models.diffusion.model.MDMConfig.course`: width 128,
4 layers; 60 model frames at 15 fps, interpolated to the 120 frames of 4 s at 30 fps); weights are untrained,
which does not change the cost. Every step runs with classifier-free guidance (the conditional and the null
prediction in one batched pass, scale 2.5), as MDM samples. Keys:

* ``rtf_b1_1thread`` / ``seconds_b1``: the full 1,000-step ancestral loop, one clip, one thread;
* ``rtf_b1_1thread_ancestral_50`` and ``rtf_b1_1thread_ddim_10``: the respaced ancestral loop of 50 steps
  and DDIM with 10 steps;
* ``frames_per_second_batched``: frames per second with DDIM at 10 steps for ``large_batch`` clips at once
  (the 1,000-step loop at a large batch would take minutes on a laptop CPU);
* ``paper_size_rtf_b1_1thread_ddim_10``: the 10-step DDIM clip of the paper's size (width 512, 8 layers) at
  batch 1, and ``paper_size_seconds_per_step_b1`` its time over 10 (decoding to positions included).
"""

from __future__ import annotations

import torch

from motionlab import config
from motionlab.bench._timing import median_seconds
from motionlab.models.diffusion.data import to_positions
from motionlab.models.diffusion.model import MDM, MDMConfig
from motionlab.models.diffusion.sampling import GUIDANCE_SCALE, sample

FPS = 30
FRAME_STRIDE = 2
SECONDS = 4
LARGE_BATCH = 64


def build(cfg: MDMConfig) -> MDM:
    """An untrained MDM of ``cfg`` with a fitted standardiser, in eval mode."""
    torch.manual_seed(0)
    return MDM(cfg).fit_standardizer(torch.randn(8, cfg.n_frames, cfg.n_features)).eval()


def clip_seconds(model: MDM, batch_size: int, steps: int | None, method: str, repeats: int) -> float:
    """Median seconds to sample ``batch_size`` guided clips and turn them into 30 fps joint positions."""
    action = torch.arange(batch_size) % model.cfg.n_actions

    def generate() -> torch.Tensor:
        motion = sample(model, action, steps=steps, method=method, guidance=GUIDANCE_SCALE)
        return to_positions(motion, FRAME_STRIDE)

    return median_seconds(generate, repeats, warmup=1 if steps is not None else 0)


def sampling_speed() -> dict[str, float]:
    """The real-time factors and throughput of the module notes."""
    config.set_threads(1)
    n_frames = SECONDS * FPS // FRAME_STRIDE
    model = build(MDMConfig.course(n_frames=n_frames))
    full = clip_seconds(model, 1, None, "ancestral", repeats=3)
    ancestral_50 = clip_seconds(model, 1, 50, "ancestral", repeats=5)
    ddim_10 = clip_seconds(model, 1, 10, "ddim", repeats=5)
    batched = clip_seconds(model, LARGE_BATCH, 10, "ddim", repeats=3)
    paper = build(MDMConfig(n_frames=n_frames))
    paper_ddim_10 = clip_seconds(paper, 1, 10, "ddim", repeats=3)
    return {
        "rtf_b1_1thread": SECONDS / full,
        "seconds_b1": full,
        "rtf_b1_1thread_ancestral_50": SECONDS / ancestral_50,
        "rtf_b1_1thread_ddim_10": SECONDS / ddim_10,
        "frames_per_second_batched": LARGE_BATCH * SECONDS * FPS / batched,
        "large_batch": float(LARGE_BATCH),
        "paper_size_seconds_per_step_b1": paper_ddim_10 / 10,
        "paper_size_rtf_b1_1thread_ddim_10": SECONDS / paper_ddim_10,
    }
