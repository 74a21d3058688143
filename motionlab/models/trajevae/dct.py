r"""The orthonormal DCT-II over time, written as a matrix, and its inverse.

For a signal :math:`x_0, \dots, x_{N-1}` the orthonormal DCT-II is

.. math::
    X_k = s_k \sum_{n=0}^{N-1} x_n \cos\Big(\frac{\pi (2n + 1) k}{2N}\Big), \qquad
    s_0 = \sqrt{1/N},\; s_{k>0} = \sqrt{2/N},

the same numbers as ``scipy.fft.dct(x, type=2, norm="ortho")``. The matrix :math:`D_{kn}` is orthogonal
(:math:`D D^\top = I`), so the inverse is its transpose. Keeping only the first ``C`` rows gives the ``C``
lowest frequencies; the inverse from them is the least-squares smooth approximation of the signal.

TrajeVAE takes the DCT of a sequence of frame embeddings over the time axis, so each latent variable
belongs to one frequency instead of one frame.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor


def _count(value: int, name: str, func: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{func}: {name} must be a positive integer, got {value!r}")
    return value


def dct_matrix(n_frames: int, n_components: int | None = None, dtype: torch.dtype = torch.float32) -> Tensor:
    """Rows of the orthonormal DCT-II matrix: ``(n_components, n_frames)`` (all ``n_frames`` rows by default).

    ``dct_matrix(n) @ x`` for ``x`` of shape ``(n,)`` equals ``scipy.fft.dct(x, norm="ortho")``.
    """
    func = "dct_matrix"
    n_frames = _count(n_frames, "n_frames", func)
    n_components = n_frames if n_components is None else _count(n_components, "n_components", func)
    if n_components > n_frames:
        raise ValueError(f"{func}: n_components ({n_components}) cannot exceed n_frames ({n_frames})")
    k = torch.arange(n_components, dtype=torch.float64)[:, None]
    n = torch.arange(n_frames, dtype=torch.float64)[None, :]
    matrix = torch.cos(math.pi * (2 * n + 1) * k / (2 * n_frames)) * math.sqrt(2.0 / n_frames)
    matrix[0] = math.sqrt(1.0 / n_frames)
    return matrix.to(dtype)


def _check_input(x: Tensor, name: str, func: str) -> Tensor:
    if not isinstance(x, Tensor) or not x.is_floating_point():
        raise TypeError(f"{func}: {name} must be a floating-point torch.Tensor, got {type(x).__name__}")
    if x.dim() < 1:
        raise ValueError(f"{func}: {name} must have a time axis (at least 1 dimension), got a scalar")
    if not bool(torch.isfinite(x).all()):
        raise ValueError(f"{func}: {name} contains NaN or inf")
    return x


def dct(x: Tensor, dim: int = -2, n_components: int | None = None) -> Tensor:
    """Orthonormal DCT-II of ``x`` along ``dim`` (default: the frame axis of ``(..., T, D)``).

    Returns the ``n_components`` lowest-frequency coefficients (all ``T`` by default) in place of the
    frames: ``(..., C, D)`` for ``dim=-2``.
    """
    _check_input(x, "x", "dct")
    matrix = dct_matrix(x.shape[dim], n_components, x.dtype).to(x.device)
    moved = x.movedim(dim, -1)
    return (moved @ matrix.T).movedim(-1, dim)


def idct(coefficients: Tensor, n_frames: int, dim: int = -2) -> Tensor:
    """Inverse of :func:`dct`: ``n_frames`` frames from the ``C <= n_frames`` lowest coefficients along
    ``dim``.

    Missing high frequencies count as zero, so ``idct(dct(x, n_components=C), T)`` is ``x`` low-pass
    filtered to ``C`` components, and ``idct(dct(x), T)`` is ``x``.
    """
    _check_input(coefficients, "coefficients", "idct")
    matrix = dct_matrix(n_frames, coefficients.shape[dim], coefficients.dtype).to(coefficients.device)
    moved = coefficients.movedim(dim, -1)
    return (moved @ matrix).movedim(-1, dim)
