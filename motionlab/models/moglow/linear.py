"""A least-squares linear predictor of the next pose, the common starting point of MoGlow and its baseline.

On our synthetic locomotion, the next pose is almost a linear function of the conditioning ``c_t`` (five
previous poses and six controls): an ordinary least-squares fit predicts it to about 0.02 standard
deviations. Networks trained for a minute on a CPU get nowhere near that, so both autoregressive models
start from this fit and learn what it misses:

* MoGlow's first layer (on the data side) is the conditional affine map
  ``u_t = (x_t - A c_t - b) * exp(-log_scale)``, an invertible layer with log-determinant
  ``-sum(log_scale)`` per frame; the Glow steps then model the residual ``u_t``.
* The Gaussian baseline's mean is ``A c_t + b`` plus its LSTM's (zero-initialised) correction.

The fit uses the same history dropout as training (masks drawn from a seeded generator, kept poses
rescaled as in training), so with heavy dropout it mostly reads the control and leaves the rest to the
LSTMs. ``A`` and ``b`` are buffers, fixed
after the fit: Adam's first steps move every weight by about the learning rate, which would wreck a
prediction that is accurate to 0.02. ``log_scale`` stays trainable.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor, nn

from motionlab.models.flows.base import FlowLayer, check_cond, check_sequence
from motionlab.models.moglow.conditioning import autoregressive_conditioning, history_keep_mask
from motionlab.validation import check_scalar, check_tensor

#: Ridge penalty of the least-squares fit, relative to the mean diagonal of the normal equations. It is a
#: trade-off: the nearly unpenalised fit (1e-12) predicts the most predictable channels better and is about
#: 70 nats per frame better in held-out likelihood, but its linear dynamics are unstable, and free-running
#: generation from it diverges within seconds; 1e-6 generates stably.
RIDGE = 1e-6


class LinearPredictor(FlowLayer):
    """``u = (x - A c - b) * exp(-log_scale)`` per frame: a conditional affine flow layer.

    Args:
        pose_dim: pose channels ``P``.
        cond_dim: conditioning features ``D`` per frame.

    ``forward(x (B, P, T), cond (B, D, T))`` gives ``(u, logdet)``; :meth:`mean` is ``A c + b``. Starts as
    the identity (``A = 0``, ``b = 0``, ``log_scale = 0``) until :meth:`fit` is called.
    """

    weight: Tensor
    bias: Tensor
    #: The RMS residual of the last :meth:`fit` (standard units), ``None`` before it (not in the state dict).
    fit_rms: float | None

    def __init__(self, pose_dim: int, cond_dim: int) -> None:
        super().__init__()
        for name, value in (("pose_dim", pose_dim), ("cond_dim", cond_dim)):
            check_scalar(value, name, "LinearPredictor", kind=numbers.Integral, minimum=1)
        self.pose_dim, self.cond_dim = pose_dim, cond_dim
        self.register_buffer("weight", torch.zeros(pose_dim, cond_dim))
        self.register_buffer("bias", torch.zeros(pose_dim))
        self.log_scale = nn.Parameter(torch.zeros(pose_dim))
        self.fit_rms = None

    def mean(self, cond: Tensor) -> Tensor:
        """``A c + b`` for conditioning ``(..., D)``, shape ``(..., P)``."""
        return torch.nn.functional.linear(cond, self.weight, self.bias)

    @torch.no_grad()
    def fit(
        self,
        pose: Tensor,
        control: Tensor,
        history: int,
        dropout: float,
        seed: int = 0,
        max_windows: int = 2048,
        rescale: bool = False,
        solve: bool = True,
    ) -> float:
        """Least-squares ``A``, ``b`` and the residual log-std per channel from windows ``(N, T, P)``, ``(N,
        T, C)``.

        Uses at most ``max_windows`` windows, evenly spaced. History dropout flags (probability ``dropout``)
        come from a generator seeded with ``seed``; with ``rescale`` the kept poses are scaled by
        ``1 / (1 - dropout)``, as in the model's training (:func:`~.conditioning.history_keep_mask`).
        Returns the root-mean-square residual (standard units), also kept as :attr:`fit_rms`. With
        ``solve=False`` the layer is left as it is (a model loaded from the checkpoint cache) and only the
        residual of its ``A`` and ``b`` on the same windows is measured: a fifth of the fit's arithmetic.
        """
        where = "LinearPredictor.fit"
        check_tensor(pose, "pose", where, trailing=(self.pose_dim,), ndim=3)
        check_tensor(control, "control", where, ndim=3)
        check_scalar(history, "history", where, kind=numbers.Integral, minimum=1)
        check_scalar(dropout, "dropout", where, minimum=0.0, maximum=1.0, include_maximum=False)
        check_scalar(seed, "seed", where, kind=numbers.Integral, minimum=0)
        check_scalar(max_windows, "max_windows", where, kind=numbers.Integral, minimum=1)
        if pose.shape[0] > max_windows:
            index = torch.linspace(0, pose.shape[0] - 1, max_windows).long()
            pose, control = pose[index], control[index]
        keep = None
        if dropout > 0:
            generator = torch.Generator().manual_seed(seed)
            keep = history_keep_mask(
                pose.shape[0], pose.shape[1] - history, history, dropout, generator, rescale=rescale
            )
        cond = autoregressive_conditioning(pose, control, history, keep).reshape(-1, self.cond_dim).double()
        target = pose[:, history:].reshape(-1, self.pose_dim).double()
        design = torch.cat([cond, torch.ones(cond.shape[0], 1, dtype=torch.float64)], dim=1)
        if solve:
            gram = design.T @ design
            gram += RIDGE * gram.diagonal().mean() * torch.eye(gram.shape[0], dtype=torch.float64)
            solution = torch.linalg.solve(gram, design.T @ target)
            residual = target - design @ solution
            self.weight.copy_(solution[:-1].T)
            self.bias.copy_(solution[-1])
            self.log_scale.copy_(torch.log(residual.std(dim=0).clamp(min=1e-6)))
        else:
            residual = target - design @ torch.cat([self.weight.T, self.bias[None]]).double()
        self.fit_rms = float(residual.pow(2).mean().sqrt())
        return self.fit_rms

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        check_sequence(x, "x", "LinearPredictor.forward", self.pose_dim)
        cond = check_cond(cond, x, self.cond_dim, "LinearPredictor.forward")
        mean = self.mean(cond.transpose(1, 2)).transpose(1, 2)
        u = (x - mean) * torch.exp(-self.log_scale)[:, None]
        return u, (-x.shape[2] * self.log_scale.sum()).expand(x.shape[0])

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        check_sequence(y, "y", "LinearPredictor.inverse", self.pose_dim)
        cond = check_cond(cond, y, self.cond_dim, "LinearPredictor.inverse")
        return y * torch.exp(self.log_scale)[:, None] + self.mean(cond.transpose(1, 2)).transpose(1, 2)
