"""A tiny MDM trained by the course's training loop on a toy of two classes: its loss falls and its
guided samples belong to the class they were asked for."""

import torch

from motionlab.models.diffusion.losses import diffusion_objective
from motionlab.models.diffusion.model import MDM, MDMConfig
from motionlab.models.diffusion.sampling import sample
from motionlab.train import TensorBatches, TrainConfig, train


def toy_clips(n_per_class: int, frames: int, features: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Two classes of smooth curves ``(2 n, frames, features)``: a rising sine and a falling cosine, each
    channel with its own phase, plus a little noise."""
    generator = torch.Generator().manual_seed(0)
    time = torch.linspace(0, 3.14, frames)[:, None]
    phase = torch.linspace(0, 1.5, features)[None, :]
    patterns = torch.stack([torch.sin(time + phase), -torch.cos(2 * time + phase)])
    action = torch.arange(2).repeat_interleave(n_per_class)
    clips = patterns[action] + 0.05 * torch.randn(2 * n_per_class, frames, features, generator=generator)
    return clips, action


def test_a_tiny_model_learns_a_toy_and_samples_its_classes():
    cfg = MDMConfig(
        n_joints=1,
        n_frames=8,
        n_actions=2,
        latent_dim=32,
        ff_size=64,
        layers=1,
        heads=2,
        dropout=0.0,
        diffusion_steps=100,
        lambda_pos=0.0,
        lambda_vel=0.0,
        lambda_foot=0.0,
    )
    clips, action = toy_clips(16, cfg.n_frames, cfg.n_features)
    torch.manual_seed(0)
    model = MDM(cfg).fit_standardizer(clips)

    def held_out_loss() -> float:
        with torch.random.fork_rng(), torch.no_grad():
            torch.manual_seed(123)
            return float(
                sum(diffusion_objective(model, (clips, action), 0, {})["loss"] for _ in range(10)) / 10
            )

    model.eval()
    before = held_out_loss()
    result = train(
        model,
        diffusion_objective,
        TensorBatches((clips, action)),
        TrainConfig(steps=250, batch_size=16, lr=2e-3),
    )
    after = held_out_loss()
    assert result.metrics["steps"] == 250
    assert after < 0.3 * before
    generated = sample(
        model,
        torch.tensor([0] * 8 + [1] * 8),
        method="ddim",
        steps=20,
        generator=torch.Generator().manual_seed(1),
    )
    patterns = torch.stack([clips[action == c].mean(dim=0) for c in (0, 1)])
    distance = (generated[:, None] - patterns[None]).pow(2).mean(dim=(2, 3))  # (16, 2)
    assert (distance.argmin(dim=1) == torch.tensor([0] * 8 + [1] * 8)).all()
