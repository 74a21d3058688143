"""Building blocks of TrajeVAE: the frame MLP, sinusoidal position codes and the self-attention block."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn


def frame_mlp(n_in: int, n_out: int) -> nn.Sequential:
    """The paper's encoder MLP, applied to every frame: (Linear → LayerNorm → LeakyReLU(0.1)) twice.

    ``(..., n_in) -> (..., n_out)``.
    """
    return nn.Sequential(
        nn.Linear(n_in, n_out),
        nn.LayerNorm(n_out),
        nn.LeakyReLU(0.1),
        nn.Linear(n_out, n_out),
        nn.LayerNorm(n_out),
        nn.LeakyReLU(0.1),
    )


def output_mlp(n_in: int, n_hidden: int, n_out: int) -> nn.Sequential:
    """Linear → LayerNorm → LeakyReLU(0.1) → Linear: ``(..., n_in) -> (..., n_out)`` with an unbounded
    output."""
    return nn.Sequential(
        nn.Linear(n_in, n_hidden), nn.LayerNorm(n_hidden), nn.LeakyReLU(0.1), nn.Linear(n_hidden, n_out)
    )


def sinusoidal_encoding(n_positions: int, dim: int) -> Tensor:
    r"""Fixed position codes ``(n_positions, dim)`` of "Attention is all you need".

    Channel pairs ``(2i, 2i + 1)`` hold :math:`\sin(p\,\omega_i)` and :math:`\cos(p\,\omega_i)` with
    :math:`\omega_i = 10000^{-2i/\mathrm{dim}}`; ``dim`` must be even.
    """
    if dim % 2:
        raise ValueError(f"sinusoidal_encoding: dim must be even, got {dim}")
    position = torch.arange(n_positions, dtype=torch.float64)[:, None]
    frequency = torch.exp(-math.log(10000.0) * torch.arange(0, dim, 2, dtype=torch.float64) / dim)
    codes = torch.zeros(n_positions, dim, dtype=torch.float64)
    codes[:, 0::2] = torch.sin(position * frequency)
    codes[:, 1::2] = torch.cos(position * frequency)
    return codes.float()


def attention_block(dim: int, heads: int, layers: int) -> nn.TransformerEncoder:
    """``layers`` pre-norm transformer encoder layers (self-attention + MLP of width ``2 dim``, no dropout),
    closed by a LayerNorm.

    ``(B, N, dim) -> (B, N, dim)``, attending over all ``N`` tokens (frames or DCT components). The final norm
    matters after the DCT: the first coefficient is ``sqrt(F)`` times the mean frame, and without it that
    scale would reach the Gaussian heads unnormalised.
    """
    layer = nn.TransformerEncoderLayer(
        dim, heads, dim_feedforward=2 * dim, dropout=0.0, batch_first=True, norm_first=True
    )
    return nn.TransformerEncoder(layer, layers, norm=nn.LayerNorm(dim), enable_nested_tensor=False)


class GaussianBranch(nn.Module):
    """An unshared branch: self-attention, then per-token mean and log-variance of the latent.

    ``(B, N, dim) -> (mu, logvar)``, each ``(B, N, latent_dim)``.
    """

    def __init__(self, dim: int, latent_dim: int, heads: int, layers: int) -> None:
        super().__init__()
        self.attention = attention_block(dim, heads, layers)
        self.mean = nn.Linear(dim, latent_dim)
        self.log_variance = nn.Linear(dim, latent_dim)

    def forward(self, tokens: Tensor) -> tuple[Tensor, Tensor]:
        hidden = self.attention(tokens)
        return self.mean(hidden), self.log_variance(hidden)
