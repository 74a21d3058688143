"""The interface every flow layer implements, the flow layout's input checks, and :class:`FlowSequence`.

A flow layer is an invertible map of sequences ``x`` of shape ``(batch, channels, time)``:

* ``forward(x, cond=None) -> (y, logdet)``: the data-to-latent direction, with ``logdet`` of shape
  ``(batch,)`` equal to ``log |det dy/dx|`` summed over every channel and time step;
* ``inverse(y, cond=None) -> x``: the latent-to-data direction (sampling).

``cond`` is an optional conditioning sequence ``(batch, cond_channels, time)`` (for example the control
signal); layers that do not use it ignore it. By the change of variables, a flow ``f`` with a base density
``p_Z`` gives ``log p_X(x) = log p_Z(f(x)) + log |det df/dx|``, which is why every layer reports its
log-determinant next to its output.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable

from torch import Tensor, nn

from motionlab.validation import check_tensor


def check_sequence(x: Tensor, name: str, where: str, channels: int | None = None) -> Tensor:
    """Check that ``x`` is a finite floating tensor ``(batch, channels, time)``; return it.

    The flow layout spelled for :func:`motionlab.validation.check_tensor` (``TypeError`` for a wrong type or
    dtype, ``ValueError`` for a wrong shape or a NaN, naming ``where``, ``name`` and the first bad index).
    """
    return check_tensor(x, name, where, ndim=3, trailing=(channels, None))


def check_cond(cond: Tensor | None, x: Tensor, cond_channels: int, where: str) -> Tensor | None:
    """Check a conditioning sequence against the layer's ``cond_channels`` and the input ``x``.

    ``cond_channels == 0`` means the layer takes no conditioning (``cond`` must be ``None``); otherwise
    ``cond`` must be ``(batch, cond_channels, time)`` with the batch and time of ``x``.
    """
    if cond_channels == 0:
        if cond is not None:
            raise ValueError(
                f"{where}: this layer was built without conditioning (cond_channels=0) but got cond"
            )
        return None
    if cond is None:
        raise ValueError(f"{where}: this layer needs cond of shape (batch, {cond_channels}, time), got None")
    check_sequence(cond, "cond", where, cond_channels)
    if cond.shape[0] != x.shape[0] or cond.shape[2] != x.shape[2]:
        raise ValueError(
            f"{where}: cond {tuple(cond.shape)} must share batch and time with the input {tuple(x.shape)}"
        )
    return cond


class FlowLayer(nn.Module, ABC):
    """An invertible layer on ``(batch, channels, time)`` sequences (see the module notes)."""

    @abstractmethod
    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        """Data to latent: ``(y, logdet)`` with ``logdet`` ``(batch,)``."""

    @abstractmethod
    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        """Latent to data: ``x`` with ``forward(x, cond)[0] == y``."""


class FlowSequence(FlowLayer):
    """Layers applied one after another; log-determinants add up, the inverse runs them backwards."""

    def __init__(self, layers: Iterable[FlowLayer]) -> None:
        super().__init__()
        self.layers = nn.ModuleList(layers)
        if len(self.layers) == 0:
            raise ValueError("FlowSequence needs at least one layer")
        for i, layer in enumerate(self.layers):
            if not isinstance(layer, FlowLayer):
                raise TypeError(f"FlowSequence: layer {i} is a {type(layer).__name__}, not a FlowLayer")

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        logdet = x.new_zeros(x.shape[0])
        for layer in self.layers:
            x, step_logdet = layer(x, cond)
            logdet = logdet + step_logdet
        return x, logdet

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        for layer in reversed(self.layers):
            y = layer.inverse(y, cond)
        return y
