"""MoGlow's coupling layer: the affine coupling of Glow with an LSTM over time as its network.

For frame ``t`` the network reads the untouched half ``x_a[t]`` and the conditioning ``c_t`` (previous
poses and controls), updates its LSTM state and outputs the shift and raw scale of ``x_b[t]``. The
state carries information from all earlier frames, so the flow of frame ``t`` depends on the whole past
while each frame's transform stays a plain, exactly invertible affine coupling.

Over a whole sequence (training, likelihoods) the LSTM runs from a zero state in one call; inverting a
whole sequence is parallel as well, since ``x_a = y_a`` is known for every frame. Generation is
different: the conditioning of frame ``t`` contains the pose generated at ``t - 1``, so it inverts one
frame at a time, carrying the LSTM state (:meth:`LSTMAffineCoupling.inverse_frame`, which the plain loop
of :mod:`.sampling` calls; the fused loop reads the weights that :meth:`LSTMAffineCoupling.frame_weights`
hands out).
"""

import numbers
from typing import (
    NamedTuple,
)  # TorchScript reads FrameCoupling's annotations: no ``from __future__ import annotations``

import torch
from torch import Tensor, nn

from motionlab.models.flows.coupling import SCALE_OFFSET, CouplingLayer, affine_inverse, zero_init
from motionlab.validation import check_scalar, check_tensor

LSTMState = tuple[Tensor, Tensor]


class FrameCoupling(NamedTuple):
    """An :class:`LSTMAffineCoupling`'s weights split by what they read (``U`` LSTM units, ``C_a`` untouched
    and ``C_b`` transformed channels, ``C_c`` conditioning features).

    For one frame, the LSTM's gates are ``x_a @ lstm_input_a.T + cond @ lstm_input_cond.T + h @ lstm_hidden.T
    + lstm_bias`` and the shift and raw scale are ``h' @ out_hidden + x_a @ out_input_a + cond @
    out_input_cond + out_bias`` (``h'`` the updated LSTM output), the sigmoid's offset being folded into
    ``out_bias``: the layer's arithmetic, rearranged so that a generator can compute the conditioning's parts
    of all couplings at once. The tensors are copies (a snapshot of the weights), contiguous.
    """

    lstm_input_a: Tensor  # (4U, C_a)
    lstm_input_cond: Tensor  # (4U, C_c)
    lstm_hidden: Tensor  # (4U, U)
    lstm_bias: Tensor  # (4U,)
    out_hidden: Tensor  # (U, 2 C_b)
    out_input_a: Tensor  # (C_a, 2 C_b)
    out_input_cond: Tensor  # (C_c, 2 C_b)
    out_bias: Tensor  # (2 C_b,)


class LSTMAffineCoupling(CouplingLayer):
    """Affine coupling on ``(batch, channels, time)`` whose network is a one-layer LSTM over time.

    Args:
        channels: channels ``C >= 2``; ``x_a`` is the first ``C // 2``.
        cond_channels: conditioning features per frame.
        hidden: LSTM units.
        scale_offset: the offset inside the sigmoid of the scale.

    The LSTM reads ``[x_a[t], cond[t]]``; a linear layer, zero-initialised, maps its output and, through a
    skip connection, its input to the shift and raw scale of ``x_b[t]`` (the skip lets the coupling use
    linear relations between the halves from the first steps of training, before the LSTM has learned).
    """

    def __init__(
        self, channels: int, cond_channels: int, hidden: int, scale_offset: float = SCALE_OFFSET
    ) -> None:
        super().__init__()
        check_scalar(channels, "channels", "LSTMAffineCoupling", kind=numbers.Integral, minimum=2)
        check_scalar(cond_channels, "cond_channels", "LSTMAffineCoupling", kind=numbers.Integral, minimum=1)
        check_scalar(hidden, "hidden", "LSTMAffineCoupling", kind=numbers.Integral, minimum=1)
        check_scalar(scale_offset, "scale_offset", "LSTMAffineCoupling")
        self.channels, self.cond_channels, self.hidden = channels, cond_channels, hidden
        self.n_a = channels // 2
        self.scale_offset = float(scale_offset)
        self.lstm = nn.LSTM(self.n_a + cond_channels, hidden, batch_first=True)
        self.out = zero_init(nn.Linear(hidden + self.n_a + cond_channels, 2 * (channels - self.n_a)))

    def extra_repr(self) -> str:
        return f"channels={self.channels}, cond_channels={self.cond_channels}, hidden={self.hidden}"

    def _params(self, x_a: Tensor, cond: Tensor) -> Tensor:
        """Shift and raw scale ``(B, 2 * C_b, T)`` from ``x_a`` ``(B, C_a, T)`` and ``cond`` ``(B, C_c,
        T)``."""
        inputs = torch.cat([x_a, cond], dim=1).transpose(1, 2)
        output, _ = self.lstm(inputs)
        return self.out(torch.cat([output, inputs], dim=2)).transpose(1, 2)

    def inverse_frame(
        self, y: Tensor, cond: Tensor, state: LSTMState | None = None
    ) -> tuple[Tensor, LSTMState]:
        """Invert one frame ``y`` ``(B, C)`` given its conditioning ``cond`` ``(B, C_c)`` and the LSTM
        state after the frames before it (``None``: the zero state of the first frame).

        Returns ``(x (B, C), state)``: the frame before the coupling and the state to hand to the next
        frame. Frame after frame, this is :meth:`inverse` of the whole sequence.
        """
        check_tensor(y, "y", "LSTMAffineCoupling.inverse_frame", trailing=(self.channels,), ndim=2)
        check_tensor(cond, "cond", "LSTMAffineCoupling.inverse_frame", trailing=(self.cond_channels,), ndim=2)
        y_a, y_b = y[:, : self.n_a], y[:, self.n_a :]
        inputs = torch.cat([y_a, cond], dim=1)[:, None]  # (B, 1, C_a + C_c): one time step
        output, state = self.lstm(inputs, state)
        params = self.out(torch.cat([output, inputs], dim=2))[:, 0]  # (B, 2 C_b)
        x_b = affine_inverse(y_b[:, :, None], params[:, :, None], self.scale_offset)[:, :, 0]
        return torch.cat([y_a, x_b], dim=1), state

    def frame_weights(self) -> FrameCoupling:
        """This coupling's weights split by what they read, for the fused generation loop
        (:func:`.sampling.generate_frames`)."""
        n_a, hidden = self.n_a, self.hidden
        lstm_input = self.lstm.weight_ih_l0.detach()
        out_weight = self.out.weight.detach().T
        out_bias = self.out.bias.detach().clone()
        out_bias[out_bias.shape[0] // 2 :] += (
            self.scale_offset
        )  # the sigmoid's offset, folded into the raw-scale bias
        parts = (
            lstm_input[:, :n_a],
            lstm_input[:, n_a:],
            self.lstm.weight_hh_l0.detach(),
            (self.lstm.bias_ih_l0 + self.lstm.bias_hh_l0).detach(),
            out_weight[:hidden],
            out_weight[hidden : hidden + n_a],
            out_weight[hidden + n_a :],
            out_bias,
        )
        return FrameCoupling(*(part.clone(memory_format=torch.contiguous_format) for part in parts))
