"""Normalising flows from scratch (chapter 05): layers, multi-scale Glow, prior, 2D toy flow, checks.

Every layer maps ``(batch, channels, time)`` sequences: ``forward(x, cond=None) -> (y, logdet)`` with
``logdet`` ``(batch,)``, and ``inverse(y, cond=None) -> x`` (see :mod:`~motionlab.models.flows.base`).

Modules: :mod:`~.base` (the interface, :class:`FlowSequence`), :mod:`~.actnorm`, :mod:`~.invconv`,
:mod:`~.coupling`, :mod:`~.glow` (Glow step, squeeze, multi-scale conditional Glow), :mod:`~.prior`
(standard normal with temperature), :mod:`~.gaussian` (the diagonal-Gaussian baseline), :mod:`~.toy`
(two moons and a 2D flow), :mod:`~.checks` (autograd log-determinants, round trips).
"""

from motionlab.models.flows.actnorm import ActNorm
from motionlab.models.flows.base import FlowLayer, FlowSequence, check_cond, check_sequence
from motionlab.models.flows.baseline import DiagonalGaussian
from motionlab.models.flows.checks import autograd_logdet, logdet_error, perturb_parameters_, roundtrip_error
from motionlab.models.flows.coupling import AffineCoupling, affine_forward, affine_inverse
from motionlab.models.flows.glow import (
    Glow,
    GlowConfig,
    GlowLevel,
    GlowStep,
    Squeeze,
    squeeze_time,
    unsqueeze_time,
)
from motionlab.models.flows.invconv import InvertibleConv1x1
from motionlab.models.flows.prior import StandardNormal
from motionlab.models.flows.toy import (
    ToyFlow,
    ToyFlowConfig,
    grid_density,
    toy_nll_loss,
    train_toy_flow,
    two_moons,
)

__all__ = [
    "ActNorm",
    "AffineCoupling",
    "DiagonalGaussian",
    "FlowLayer",
    "FlowSequence",
    "Glow",
    "GlowConfig",
    "GlowLevel",
    "GlowStep",
    "InvertibleConv1x1",
    "Squeeze",
    "StandardNormal",
    "ToyFlow",
    "ToyFlowConfig",
    "affine_forward",
    "affine_inverse",
    "autograd_logdet",
    "check_cond",
    "check_sequence",
    "grid_density",
    "logdet_error",
    "perturb_parameters_",
    "roundtrip_error",
    "squeeze_time",
    "toy_nll_loss",
    "train_toy_flow",
    "two_moons",
    "unsqueeze_time",
]
