"""Numerical checks of flow layers against independent computations (used by the tests and chapter 05).

* :func:`autograd_logdet`: ``log |det J|`` from the full Jacobian that autograd builds, one sequence at a
  time, so it does not rely on any of the layers' own log-determinant formulas;
* :func:`logdet_error` and :func:`roundtrip_error`: the largest disagreement of a layer with that oracle,
  and of ``inverse(forward(x))`` with ``x``;
* :func:`perturb_parameters_`: random offsets on every parameter, so that checks do not run on the
  near-identity maps that fresh layers are (zero-initialised couplings, identity ActNorm).
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from motionlab.models.flows.base import FlowLayer


def autograd_logdet(layer: FlowLayer, x: Tensor, cond: Tensor | None = None) -> Tensor:
    """``log |det d forward(x)/dx|`` per sequence ``(batch,)`` from autograd's full Jacobian.

    The Jacobian of one sequence is ``(C*T, C*T)``, so keep inputs small; use float64 for a tight comparison.
    """
    values = []
    for b in range(x.shape[0]):
        row_cond = None if cond is None else cond[b : b + 1]

        def flat_forward(row: Tensor, row_cond: Tensor | None = row_cond) -> Tensor:
            return layer(row[None], row_cond)[0].reshape(-1)

        jacobian = torch.autograd.functional.jacobian(flat_forward, x[b])
        size = x[b].numel()
        values.append(torch.linalg.slogdet(jacobian.reshape(size, size))[1])
    return torch.stack(values)


def logdet_error(layer: FlowLayer, x: Tensor, cond: Tensor | None = None) -> float:
    """Largest ``|logdet - autograd_logdet|`` over the batch."""
    with torch.no_grad():
        _, logdet = layer(x, cond)
    return float((logdet - autograd_logdet(layer, x, cond)).abs().max())


@torch.no_grad()
def roundtrip_error(layer: FlowLayer, x: Tensor, cond: Tensor | None = None) -> float:
    """Largest ``|inverse(forward(x)) - x|`` over all entries."""
    y, _ = layer(x, cond)
    return float((layer.inverse(y, cond) - x).abs().max())


@torch.no_grad()
def perturb_parameters_(module: nn.Module, std: float, generator: torch.Generator) -> nn.Module:
    """Add ``N(0, std**2)`` noise to every parameter of ``module`` in place (draws from ``generator``); return
    it."""
    for parameter in module.parameters():
        noise = torch.randn(parameter.shape, generator=generator, dtype=torch.float64)
        parameter.add_((std * noise).to(parameter.dtype))
    return module
