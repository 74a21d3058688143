"""Motion Words: a sequence of poses cut into words of ``l`` consecutive poses, each encoded to a code.

The Motion Cell runs its recurrence once per word instead of once per frame (the paper: ``l = 3``), which
shortens the recurrence threefold and lets one latent variable describe a short movement. ``f_enc^w``
maps the ``l`` pose vectors of a word to a code; ``f_dec^w`` maps a code back to ``l`` raw poses (the
output head turns them into rotations). With ``l = 1`` a word is a single pose (the SL ablation).
"""

from __future__ import annotations

from torch import Tensor, nn


def to_words(poses: Tensor, length: int) -> Tensor:
    """Words ``(B, T / l, l * D)`` from poses ``(B, T, D)``; ``T`` must be a multiple of ``l``."""
    if poses.dim() != 3:
        raise ValueError(f"to_words: poses must be (B, T, D), got {tuple(poses.shape)}")
    if poses.shape[1] % length:
        raise ValueError(f"to_words: {poses.shape[1]} frames do not split into words of {length}")
    return poses.reshape(poses.shape[0], poses.shape[1] // length, length * poses.shape[2])


def from_words(words: Tensor, length: int) -> Tensor:
    """Poses ``(B, N * l, D)`` from words ``(B, N, l * D)`` (the inverse of :func:`to_words`)."""
    if words.dim() != 3 or words.shape[-1] % length:
        raise ValueError(
            f"from_words: words must be (B, N, l * D) with l = {length}, got {tuple(words.shape)}"
        )
    return words.reshape(words.shape[0], words.shape[1] * length, words.shape[2] // length)


def mlp(sizes: list[int]) -> nn.Sequential:
    """Linear layers of ``sizes`` with ELU between them (none after the last)."""
    layers: list[nn.Module] = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:]):
        layers += [nn.Linear(fan_in, fan_out), nn.ELU()]
    return nn.Sequential(*layers[:-1])


class WordEncoder(nn.Module):
    """``f_enc^w``: a word of ``l`` pose vectors ``(..., l * pose_dim)`` -> its code ``(..., word_dim)``."""

    def __init__(self, pose_dim: int, word_length: int, word_dim: int) -> None:
        super().__init__()
        self.net = mlp([pose_dim * word_length, 2 * word_dim, word_dim])

    def forward(self, words: Tensor) -> Tensor:
        return self.net(words)


class WordDecoder(nn.Module):
    """``f_dec^w``: a code ``(..., word_dim)`` -> ``l`` raw poses ``(..., l * raw_dim)``."""

    def __init__(self, word_dim: int, word_length: int, raw_dim: int) -> None:
        super().__init__()
        self.net = mlp([word_dim, 2 * word_dim, raw_dim * word_length])
        nn.init.zeros_(self.net[-1].weight)  # start at the rest pose (zero raw = identity rotations)
        nn.init.zeros_(self.net[-1].bias)

    def forward(self, codes: Tensor) -> Tensor:
        return self.net(codes)
