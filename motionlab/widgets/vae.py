"""Widget callbacks of chapter 03: sample a conditional VAE, and walk between two latent codes.

Both are plain functions that draw a figure, so they are unit-tested without a browser; the notebook binds
the trained model, its :class:`~motionlab.models.vae_data.ClipCodec` and the skeleton with
``functools.partial`` and wires the remaining arguments to ipywidgets controls.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch
from matplotlib.figure import Figure

from motionlab.models.vae import MLPVAE, interpolate_codes
from motionlab.models.vae_data import ClipCodec
from motionlab.viz import GENERATED_COLOR, filmstrip


def _check_action(model: MLPVAE, action: int) -> int:
    if model.cfg.n_classes == 0:
        raise ValueError("the model is not conditional: it has no actions to pick from")
    if (
        isinstance(action, bool)
        or not isinstance(action, (int, np.integer))
        or not 0 <= action < model.cfg.n_classes
    ):
        raise ValueError(f"action must be an integer in [0, {model.cfg.n_classes}), got {action!r}")
    return int(action)


def prior_code(model: MLPVAE, seed: int) -> torch.Tensor:
    """The latent code ``(latent_dim,)`` drawn from the model's prior with ``seed`` (same seed, same code)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return model.prior_sample(1, torch.Generator().manual_seed(int(seed)))[0]


@torch.no_grad()
def decode_clip(model: MLPVAE, codec: ClipCodec, z: torch.Tensor, action: int) -> torch.Tensor:
    """Global positions ``(L, 22, 3)`` of the clip the CVAE decodes from code ``z`` ``(latent_dim,)`` for
    ``action``."""
    action = _check_action(model, action)
    was_training = model.training
    model.eval()
    try:
        features = model.decode(z[None], torch.tensor([action]))
    finally:
        model.train(was_training)
    return codec.to_positions(features)[0]


def show_cvae_sample(
    model: MLPVAE,
    codec: ClipCodec,
    parents: Sequence[int],
    action: int,
    seed: int,
    action_names: Sequence[str] | None = None,
    n_frames: int = 5,
    fps: float = 30.0,
) -> Figure:
    """Keyframes of one CVAE sample: the code drawn from the prior with ``seed``, decoded for ``action``."""
    positions = decode_clip(model, codec, prior_code(model, seed), action)
    name = action_names[action] if action_names is not None else f"action {action}"
    return filmstrip(
        positions,
        parents,
        n_frames,
        fps=fps,
        color=GENERATED_COLOR,
        title=f"sample of '{name}' (seed {seed})",
    )


def show_latent_interpolation(
    model: MLPVAE,
    codec: ClipCodec,
    parents: Sequence[int],
    action: int,
    seed_a: int,
    seed_b: int,
    t: float,
    action_names: Sequence[str] | None = None,
    n_frames: int = 5,
    fps: float = 30.0,
) -> Figure:
    """Keyframes of the clip decoded at ``(1 - t) z_a + t z_b`` for ``action``; ``z_a``, ``z_b`` from
    ``seed_a``, ``seed_b``."""
    if not 0.0 <= float(t) <= 1.0:
        raise ValueError(f"t must lie in [0, 1], got {t!r}")
    z = interpolate_codes(prior_code(model, seed_a), prior_code(model, seed_b), float(t))[0]
    positions = decode_clip(model, codec, z, action)
    name = action_names[action] if action_names is not None else f"action {action}"
    return filmstrip(
        positions,
        parents,
        n_frames,
        fps=fps,
        color=GENERATED_COLOR,
        title=f"'{name}': t = {float(t):.2f} between seeds {seed_a} and {seed_b}",
    )
