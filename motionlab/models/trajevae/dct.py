r"""The orthonormal DCT-II over time, written as a matrix, and its inverse.

For a signal :math:`h_0, \dots, h_{T-1}` over ``T`` frames the orthonormal DCT-II is (chapter 07's notation)

.. math::
    a_u = s_u \sum_{t=0}^{T-1} h_t \cos\Big(\frac{\pi (2t + 1) u}{2T}\Big), \qquad
    s_0 = \sqrt{1/T},\; s_{u>0} = \sqrt{2/T},

for the frequencies :math:`u = 0, \dots, T - 1`; the same numbers as ``scipy.fft.dct(h, type=2,
norm="ortho")``: :math:`a = U h` with the matrix :math:`U_{ut}`, which is orthogonal (:math:`U U^\top = I`),
so the inverse is its transpose. Keeping only the first ``C`` rows gives the ``C`` lowest frequencies; the
inverse from them is the least-squares smooth approximation of the signal.

TrajeVAE takes the DCT of a sequence of frame embeddings over the time axis, so each latent variable
belongs to one frequency instead of one frame.
"""

from __future__ import annotations

import math
import numbers

import torch
from torch import Tensor

from motionlab.validation import check_scalar, check_tensor


def dct_matrix(n_frames: int, n_components: int | None = None, dtype: torch.dtype = torch.float32) -> Tensor:
    """Rows of the orthonormal DCT-II matrix: ``(n_components, n_frames)`` (all ``n_frames`` rows by default).

    ``dct_matrix(n) @ x`` for ``x`` of shape ``(n,)`` equals ``scipy.fft.dct(x, norm="ortho")``.
    """
    where = "dct_matrix"
    check_scalar(n_frames, "n_frames", where, kind=numbers.Integral, minimum=1)
    if n_components is None:
        n_components = n_frames
    check_scalar(n_components, "n_components", where, kind=numbers.Integral, minimum=1, maximum=n_frames)
    u = torch.arange(n_components, dtype=torch.float64)[:, None]  # frequency
    t = torch.arange(n_frames, dtype=torch.float64)[None, :]  # frame
    matrix = torch.cos(math.pi * (2 * t + 1) * u / (2 * n_frames)) * math.sqrt(2.0 / n_frames)
    matrix[0] = math.sqrt(1.0 / n_frames)
    return matrix.to(dtype)


def dct(x: Tensor, dim: int = -2, n_components: int | None = None) -> Tensor:
    """Orthonormal DCT-II of ``x`` along ``dim`` (default: the frame axis of ``(..., T, D)``).

    Returns the ``n_components`` lowest-frequency coefficients (all ``T`` by default) in place of the
    frames: ``(..., C, D)`` for ``dim=-2``.
    """
    check_tensor(x, "x", "dct", min_leading=1)
    matrix = dct_matrix(x.shape[dim], n_components, x.dtype).to(x.device)
    moved = x.movedim(dim, -1)
    return (moved @ matrix.T).movedim(-1, dim)


def idct(coefficients: Tensor, n_frames: int, dim: int = -2) -> Tensor:
    """Inverse of :func:`dct`: ``n_frames`` frames from the ``C <= n_frames`` lowest coefficients along
    ``dim``.

    Missing high frequencies count as zero, so ``idct(dct(x, n_components=C), T)`` is ``x`` low-pass
    filtered to ``C`` components, and ``idct(dct(x), T)`` is ``x``.
    """
    check_tensor(coefficients, "coefficients", "idct", min_leading=1)
    matrix = dct_matrix(n_frames, coefficients.shape[dim], coefficients.dtype).to(coefficients.device)
    moved = coefficients.movedim(dim, -1)
    return (moved @ matrix).movedim(-1, dim)
