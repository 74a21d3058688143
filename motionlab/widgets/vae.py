"""Widget callbacks of chapter 03: sample a conditional VAE, and walk between two latent codes.

Both are plain functions that draw a figure, so they are unit-tested without a browser; the notebook binds
the trained model, its :class:`~motionlab.models.vae.data.ClipCodec` and the skeleton with
``functools.partial`` and wires the remaining arguments to ipywidgets controls.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import torch
from matplotlib.figure import Figure

from motionlab.models.vae.data import ClipCodec
from motionlab.models.vae.model import MLPVAE
from motionlab.models.vae.sampling import interpolate_codes
from motionlab.validation import check_scalar
from motionlab.viz import GENERATED_COLOR, filmstrip


def _check_action(model: MLPVAE, action: int, where: str) -> int:
    if model.cfg.n_classes == 0:
        raise ValueError(f"{where}: the model is not conditional: it has no actions to pick from")
    check_scalar(action, "action", where, kind=numbers.Integral, minimum=0, maximum=model.cfg.n_classes - 1)
    return int(action)


def _action_name(action: int, action_names: Sequence[str] | None) -> str:
    return action_names[action] if action_names is not None else f"action {action}"


def prior_code(model: MLPVAE, seed: int) -> torch.Tensor:
    """The latent code ``(latent_dim,)`` drawn from the model's prior with ``seed`` (same seed, same code)."""
    check_scalar(seed, "seed", "prior_code", kind=numbers.Integral, minimum=0)
    return model.prior_sample(1, torch.Generator().manual_seed(int(seed)))[0]


@torch.no_grad()
def decode_clip(model: MLPVAE, codec: ClipCodec, z: torch.Tensor, action: int) -> torch.Tensor:
    """Global positions ``(L, 22, 3)`` of the clip the CVAE decodes from code ``z`` ``(latent_dim,)`` for
    ``action``."""
    action = _check_action(model, action, "decode_clip")
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
    title = f"sample of '{_action_name(action, action_names)}' (seed {seed})"
    return filmstrip(positions, parents, n_frames, fps=fps, color=GENERATED_COLOR, title=title)


def show_latent_interpolation(
    model: MLPVAE,
    codec: ClipCodec,
    parents: Sequence[int],
    action: int,
    seed_a: int,
    seed_b: int,
    w: float,
    action_names: Sequence[str] | None = None,
    n_frames: int = 5,
    fps: float = 30.0,
) -> Figure:
    """Keyframes of the clip decoded at ``(1 - w) z_a + w z_b`` for ``action``, with ``w`` the interpolation
    weight and ``z_a``, ``z_b`` from ``seed_a``, ``seed_b``."""
    check_scalar(w, "w", "show_latent_interpolation", minimum=0.0, maximum=1.0)
    z = interpolate_codes(prior_code(model, seed_a), prior_code(model, seed_b), float(w))[0]
    positions = decode_clip(model, codec, z, action)
    title = f"'{_action_name(action, action_names)}': w = {float(w):.2f} between seeds {seed_a} and {seed_b}"
    return filmstrip(positions, parents, n_frames, fps=fps, color=GENERATED_COLOR, title=title)
