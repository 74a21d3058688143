r"""MDM's noise schedule: the cosine schedule, the forward process, its posterior, respacing and DDIM.

Notation (Ho et al. 2020, which MDM §3 follows): the forward process adds Gaussian noise in ``S`` steps,

.. math:: q(x_t \mid x_{t-1}) = \mathcal N\big(\sqrt{1 - \beta_t}\, x_{t-1},\ \beta_t I\big),

so with :math:`\alpha_t = 1 - \beta_t` and :math:`\bar\alpha_t = \prod_{s \le t} \alpha_s` a clean motion
:math:`x_0` reaches step ``t`` in one draw (:meth:`NoiseSchedule.q_sample`):

.. math:: q(x_t \mid x_0) = \mathcal N\big(\sqrt{\bar\alpha_t}\, x_0,\ (1 - \bar\alpha_t) I\big).

Given :math:`x_0`, the step back is Gaussian too (:meth:`NoiseSchedule.posterior`, Bayes' rule on the two
Gaussians above):

.. math::
    q(x_{t-1} \mid x_t, x_0) = \mathcal N\Big(
        \tfrac{\beta_t \sqrt{\bar\alpha_{t-1}}}{1 - \bar\alpha_t}\, x_0
        + \tfrac{(1 - \bar\alpha_{t-1}) \sqrt{\alpha_t}}{1 - \bar\alpha_t}\, x_t,\
        \tfrac{1 - \bar\alpha_{t-1}}{1 - \bar\alpha_t}\, \beta_t I\Big).

MDM's sampler puts its predicted :math:`\hat x_0` into this posterior (:mod:`.sampling`); the variance is
the posterior's own ("fixed small", the repository's ``sigma_small=True``).

**Indices.** Steps are 0-based here, as in the repository: index ``i`` is the paper's :math:`t = i + 1`,
so :math:`\bar\alpha` at index 0 is already below 1 and the "previous" :math:`\bar\alpha` of index 0 is 1.

**The cosine schedule** (Nichol & Dhariwal 2021, eq. 17; MDM uses it with ``S = 1000``, repository
``utils/parser_util.py``):
:math:`\bar\alpha(s) = \cos^2\big(\tfrac{s + 0.008}{1.008} \cdot \tfrac{\pi}{2}\big)` for
:math:`s \in [0, 1]`, and
:math:`\beta_i = \min\big(1 - \bar\alpha(\tfrac{i+1}{S}) / \bar\alpha(\tfrac{i}{S}), 0.999\big)`
(the cap keeps the last steps from being pure noise with :math:`\beta = 1`).

**Respacing** (the repository's ``diffusion/respace.py``): a schedule of ``K < S`` steps keeps ``K`` evenly
spaced indices of the ``S`` and recomputes each kept step's :math:`\beta` from the kept :math:`\bar\alpha`
so that the cumulative products stay exactly the kept ones; the network is still fed the original step
index (:attr:`NoiseSchedule.timesteps`). The ancestral sampler runs unchanged on a respaced schedule.

**DDIM** (Song, Meng, Ermon 2021, eq. 12; :meth:`NoiseSchedule.ddim_step`) is the deterministic
(``eta = 0``) step that keeps the predicted noise instead of drawing fresh noise; with ``eta = 1`` it has
the posterior's variance. Together with respacing it is the fast sampler.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import torch
from torch import Tensor

from motionlab.validation import check_scalar, check_tensor

#: The cosine schedule's offset ``s`` (Nichol & Dhariwal 2021: 0.008) and the cap on every beta (0.999).
COSINE_OFFSET = 0.008
MAX_BETA = 0.999


def cosine_betas(n_steps: int, offset: float = COSINE_OFFSET, max_beta: float = MAX_BETA) -> Tensor:
    r"""The cosine schedule's betas ``(n_steps,)`` float64 (see the module notes)."""
    check_scalar(n_steps, "n_steps", "cosine_betas", kind=numbers.Integral, minimum=1)
    check_scalar(offset, "offset", "cosine_betas", minimum=0, include_minimum=False)
    check_scalar(max_beta, "max_beta", "cosine_betas", minimum=0, maximum=1, include_minimum=False)
    s = torch.arange(n_steps + 1, dtype=torch.float64) / n_steps
    alpha_bar = torch.cos((s + offset) / (1 + offset) * math.pi / 2) ** 2
    return (1 - alpha_bar[1:] / alpha_bar[:-1]).clamp(max=max_beta)


def evenly_spaced(n_steps: int, count: int) -> list[int]:
    """``count`` indices of ``range(n_steps)``, first and last included, evenly spaced and rounded (the
    repository's ``space_timesteps`` with one section, Python's round-half-to-even included)."""
    check_scalar(n_steps, "n_steps", "evenly_spaced", kind=numbers.Integral, minimum=1)
    check_scalar(count, "count", "evenly_spaced", kind=numbers.Integral, minimum=1, maximum=n_steps)
    stride = (n_steps - 1) / (count - 1) if count > 1 else 1.0
    return [round(k * stride) for k in range(count)]


def check_steps(t: Tensor, batch: int, n_steps: int, where: str) -> Tensor:
    """Check diffusion steps ``t``: a ``(batch,)`` integer tensor with entries in ``[0, n_steps)``; return it.

    ``TypeError`` for a non-tensor or a floating or bool dtype, ``ValueError`` for a wrong shape or range.
    """
    if not isinstance(t, Tensor) or t.is_floating_point() or t.dtype == torch.bool:
        raise TypeError(
            f"{where}: t must be an integer tensor of steps, got {getattr(t, 'dtype', type(t).__name__)}"
        )
    if t.shape != (batch,):
        raise ValueError(f"{where}: t must be ({batch},), got {tuple(t.shape)}")
    if t.numel() and (int(t.min()) < 0 or int(t.max()) >= n_steps):
        raise ValueError(f"{where}: steps must lie in [0, {n_steps}), got [{int(t.min())}, {int(t.max())}]")
    return t


def _per_sample(values: Tensor, t: Tensor, like: Tensor) -> Tensor:
    """``values[t]`` ``(B,)`` shaped ``(B, 1, ..., 1)`` to broadcast against ``like`` ``(B, ...)``, in its
    dtype."""
    return values[t].to(like.dtype).view(-1, *([1] * (like.dim() - 1)))


@dataclass(frozen=True, eq=False)
class NoiseSchedule:
    """A diffusion process of ``S`` steps, and the one-step formulas every sampler uses.

    Attributes:
        betas: ``(S,)`` float64, each in ``(0, 1]``.
        timesteps: ``(S,)`` int64, the step of the original process each step is (what the network is fed):
            ``0 .. S - 1`` for a schedule that was not respaced.

    Every method takes ``t`` as ``(B,)`` int64 indices into this schedule (``0 .. S - 1``) and tensors
    ``(B, ...)`` (e.g. motions ``(B, T, F)``); the coefficients are computed in float64 and cast to the
    tensors' dtype.
    """

    betas: Tensor
    timesteps: Tensor

    def __post_init__(self) -> None:
        where = "NoiseSchedule"
        betas = check_tensor(self.betas, "betas", where, ndim=1).to(torch.float64)
        if betas.numel() == 0 or bool((betas <= 0).any()) or bool((betas > 1).any()):
            raise ValueError(f"{where}: betas must be a non-empty (S,) tensor with every beta in (0, 1]")
        timesteps = self.timesteps
        if (
            not isinstance(timesteps, Tensor)
            or timesteps.is_floating_point()
            or timesteps.dtype == torch.bool
        ):
            raise TypeError(
                f"{where}: timesteps must be an integer tensor, got {getattr(timesteps, 'dtype', timesteps)}"
            )
        if timesteps.shape != betas.shape or bool((timesteps < 0).any()):
            raise ValueError(
                f"{where}: timesteps must be {tuple(betas.shape)} non-negative steps, "
                f"got {tuple(timesteps.shape)}"
            )
        if betas.numel() > 1 and bool((timesteps.diff() <= 0).any()):
            raise ValueError(f"{where}: timesteps must increase strictly")
        object.__setattr__(self, "betas", betas)
        object.__setattr__(self, "timesteps", self.timesteps.to(torch.int64))

    @classmethod
    def cosine(cls, n_steps: int = 1000) -> NoiseSchedule:
        """The cosine schedule of ``n_steps`` steps (MDM: 1,000)."""
        return cls(cosine_betas(n_steps), torch.arange(n_steps))

    @property
    def n_steps(self) -> int:
        """Number of steps ``S``."""
        return int(self.betas.numel())

    @property
    def alphas_cumprod(self) -> Tensor:
        r""":math:`\bar\alpha` ``(S,)`` float64."""
        return torch.cumprod(1 - self.betas, dim=0)

    @property
    def alphas_cumprod_prev(self) -> Tensor:
        r""":math:`\bar\alpha` of the step before each step ``(S,)``: 1 before the first."""
        return torch.cat([torch.ones(1, dtype=torch.float64), self.alphas_cumprod[:-1]])

    def respace(self, count: int) -> NoiseSchedule:
        """The schedule of ``count`` evenly spaced steps of this one (see the module notes)."""
        check_scalar(
            count, "count", "NoiseSchedule.respace", kind=numbers.Integral, minimum=1, maximum=self.n_steps
        )
        kept = torch.tensor(evenly_spaced(self.n_steps, count))
        alpha_bar = self.alphas_cumprod[kept]
        previous = torch.cat([torch.ones(1, dtype=torch.float64), alpha_bar[:-1]])
        return NoiseSchedule(1 - alpha_bar / previous, self.timesteps[kept])

    def check_step(self, t: Tensor, batch: int, where: str) -> Tensor:
        """Check step indices ``t`` ``(batch,)`` (integers in ``[0, S)``) of this schedule; return them."""
        return check_steps(t, batch, self.n_steps, where)

    def q_sample(self, x0: Tensor, t: Tensor, noise: Tensor) -> Tensor:
        r"""A draw of :math:`q(x_t \mid x_0)`: :math:`\sqrt{\bar\alpha_t}\, x_0 + \sqrt{1 - \bar\alpha_t}\,
        \epsilon` for clean ``x0`` ``(B, ...)`` and standard normal ``noise`` of the same shape."""
        where = "NoiseSchedule.q_sample"
        check_tensor(x0, "x0", where, min_leading=1)
        self.check_step(t, x0.shape[0], where)
        if noise.shape != x0.shape:
            raise ValueError(
                f"{where}: noise must have x0's shape {tuple(x0.shape)}, got {tuple(noise.shape)}"
            )
        alpha_bar = self.alphas_cumprod
        return _per_sample(alpha_bar.sqrt(), t, x0) * x0 + _per_sample((1 - alpha_bar).sqrt(), t, x0) * noise

    def posterior(self, x0: Tensor, xt: Tensor, t: Tensor) -> tuple[Tensor, Tensor]:
        r"""Mean ``(B, ...)`` and variance ``(B, 1, ..., 1)`` of :math:`q(x_{t-1} \mid x_t, x_0)` (see the
        module notes); the variance is 0 at ``t = 0``, where the mean is ``x0`` itself."""
        where = "NoiseSchedule.posterior"
        check_tensor(x0, "x0", where, min_leading=1)
        if xt.shape != x0.shape:
            raise ValueError(f"{where}: xt must have x0's shape {tuple(x0.shape)}, got {tuple(xt.shape)}")
        self.check_step(t, x0.shape[0], where)
        alpha_bar, alpha_bar_prev = self.alphas_cumprod, self.alphas_cumprod_prev
        coef_x0 = self.betas * alpha_bar_prev.sqrt() / (1 - alpha_bar)
        coef_xt = (1 - alpha_bar_prev) * (1 - self.betas).sqrt() / (1 - alpha_bar)
        variance = self.betas * (1 - alpha_bar_prev) / (1 - alpha_bar)
        mean = _per_sample(coef_x0, t, x0) * x0 + _per_sample(coef_xt, t, x0) * xt
        return mean, _per_sample(variance, t, x0)

    def predict_noise(self, xt: Tensor, t: Tensor, x0: Tensor) -> Tensor:
        r"""The noise :math:`\epsilon` that takes ``x0`` to ``xt`` in :meth:`q_sample` (``(B, ...)``)."""
        alpha_bar = self.alphas_cumprod
        return (xt - _per_sample(alpha_bar.sqrt(), t, xt) * x0) / _per_sample((1 - alpha_bar).sqrt(), t, xt)

    def ddim_step(self, xt: Tensor, t: Tensor, x0: Tensor, noise: Tensor, eta: float = 0.0) -> Tensor:
        r"""One DDIM step to :math:`x_{t-1}` ``(B, ...)`` from ``xt`` and a predicted ``x0``:

        .. math:: x_{t-1} = \sqrt{\bar\alpha_{t-1}}\, \hat x_0 + \sqrt{1 - \bar\alpha_{t-1} - \sigma_t^2}\,
                  \hat\epsilon + \sigma_t\, z,\quad
                  \sigma_t = \eta \sqrt{\tfrac{1 - \bar\alpha_{t-1}}{1 - \bar\alpha_t}}
                  \sqrt{1 - \tfrac{\bar\alpha_t}{\bar\alpha_{t-1}}}

        with :math:`\hat\epsilon` from :meth:`predict_noise` and ``noise`` the standard normal ``z``
        (unused at ``t = 0``, where the step returns ``x0``)."""
        where = "NoiseSchedule.ddim_step"
        check_tensor(xt, "xt", where, min_leading=1)
        self.check_step(t, xt.shape[0], where)
        check_scalar(eta, "eta", where, minimum=0, maximum=1)
        for name, value in (("x0", x0), ("noise", noise)):
            if value.shape != xt.shape:
                raise ValueError(
                    f"{where}: {name} must have xt's shape {tuple(xt.shape)}, got {tuple(value.shape)}"
                )
        alpha_bar, alpha_bar_prev = self.alphas_cumprod, self.alphas_cumprod_prev
        sigma = eta * ((1 - alpha_bar_prev) / (1 - alpha_bar) * (1 - alpha_bar / alpha_bar_prev)).sqrt()
        eps = self.predict_noise(xt, t, x0)
        direction = (1 - alpha_bar_prev - sigma**2).clamp(min=0).sqrt()
        return (
            _per_sample(alpha_bar_prev.sqrt(), t, xt) * x0
            + _per_sample(direction, t, xt) * eps
            + _per_sample(sigma, t, xt) * noise
        )
