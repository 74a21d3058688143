r"""Sampling from MDM: the ancestral loop, its fast variant (respaced steps, DDIM), classifier-free guidance
and editing by inpainting.

**The ancestral loop** (:func:`sample`; MDM §3, "Sampling"; repository ``p_sample_loop``). From
:math:`x_S \sim \mathcal N(0, I)`, at every step ``t = S - 1, …, 0`` the network predicts the clean motion
:math:`\hat x_0 = G(x_t, t, c)`, and :math:`x_{t-1}` is drawn from the posterior
:math:`q(x_{t-1} \mid x_t, \hat x_0)` of :mod:`.schedule` (its own, "fixed small" variance; no noise at
the last step, whose mean is :math:`\hat x_0` itself). :math:`\hat x_0` is not clamped: the repository's
sampling scripts pass ``clip_denoised=False`` (its clamp to ``[-1, 1]`` is an image-model leftover), and our
channels are standardised, not bounded. The same loop runs on a respaced schedule
(:meth:`~.schedule.NoiseSchedule.respace`): fewer steps, each a bigger jump.

**DDIM** (``method="ddim"``): the same loop with the DDIM step
(:meth:`~.schedule.NoiseSchedule.ddim_step`, deterministic for ``eta = 0``) in place of the posterior draw;
with a respaced schedule this is the fast variant. Every clip of a batch runs through the loop together.

**Classifier-free guidance** (:func:`guided_prediction`; MDM §3 after Ho & Salimans 2022; repository
``model/cfg_sampler.py``): the prediction is extrapolated from the null condition's through the action's,

.. math:: G_s(x_t, t, c) = G(x_t, t, \varnothing) + s\,\big(G(x_t, t, c) - G(x_t, t, \varnothing)\big),

``s = 1`` being the plain conditional model and ``s = 0`` the unconditioned one. Both predictions come
from one batched pass of the network. The repository's sampling scripts default to ``s = 2.5``
(``--guidance_param``, :data:`GUIDANCE_SCALE`).

**Inpainting** (MDM's editing: in-betweening and body-part editing; repository ``sample/edit.py`` with
``p_mean_variance``). Given a motion and a mask of its known channels (:func:`~.data.known_mask`), at *every*
step the repository overwrites the known entries of the prediction :math:`\hat x_0` with the given motion,
before the posterior is formed; at the last step the sample is :math:`\hat x_0`, so the known part comes
out exactly. That is
``inpaint="prediction"``, our default. The image-diffusion way (Song et al. 2021, RePaint) instead replaces
the known part of :math:`x_{t-1}` with the given motion noised to step ``t - 1`` by :math:`q`
(``inpaint="noised"``); at the last step it, too, puts the given motion in place exactly.
"""

from __future__ import annotations

import numbers
from typing import Literal, NamedTuple

import torch
from torch import Tensor

from motionlab.models.diffusion.model import MDM
from motionlab.models.diffusion.schedule import NoiseSchedule
from motionlab.validation import check_choice, check_scalar, check_tensor

#: The step of the loop: ``"ancestral"`` a draw from the posterior ``q(x_{t-1} | x_t, x̂_0)``, ``"ddim"`` the
#: DDIM step.
Method = Literal["ancestral", "ddim"]
METHODS: tuple[str, ...] = ("ancestral", "ddim")

#: What inpainting replaces at every step: ``"prediction"`` the known part of ``x̂_0`` by the given motion
#: (the repository's editing), ``"noised"`` the known part of ``x_{t-1}`` by the given motion noised to step
#: ``t - 1``.
Inpaint = Literal["prediction", "noised"]
INPAINT_MODES: tuple[str, ...] = ("prediction", "noised")

#: The repository's classifier-free guidance scale (``--guidance_param``, ``utils/parser_util.py``).
GUIDANCE_SCALE = 2.5


class Edit(NamedTuple):
    """What an edit gives: ``motion`` ``(B, T, F)`` in the units of :mod:`.data` and ``known`` ``(B, T, F)``
    or ``(T, F)`` bool, True where ``motion`` is kept."""

    motion: Tensor
    known: Tensor


def guided_prediction(
    model: MDM, x_t: Tensor, step: Tensor, action: Tensor | None, guidance: float | None
) -> Tensor:
    """The predicted ``x̂_0`` ``(B, T, F)`` of ``x_t`` at diffusion steps ``step`` ``(B,)``: the conditional
    prediction when ``guidance`` is ``None`` (or ``action`` is ``None``: the unconditioned one), the guided
    one (classifier-free guidance) of scale ``guidance`` otherwise, both predictions in one batched pass."""
    if guidance is None or action is None:
        return model(x_t, step, action)
    check_scalar(guidance, "guidance", "guided_prediction")
    batch = x_t.shape[0]
    null = torch.cat([torch.zeros(batch, dtype=torch.bool), torch.ones(batch, dtype=torch.bool)])
    both = model(torch.cat([x_t, x_t]), torch.cat([step, step]), torch.cat([action, action]), null)
    conditional, unconditional = both[:batch], both[batch:]
    return unconditional + guidance * (conditional - unconditional)


def _check_edit(edit: Edit | None, shape: tuple[int, ...], model: MDM) -> Edit | None:
    """``edit`` standardised, its mask expanded to ``shape``; ``None`` stays ``None``."""
    if edit is None:
        return None
    where = "sample"
    if not isinstance(edit, Edit):
        raise TypeError(f"{where}: edit must be an Edit(motion, known), got {type(edit).__name__}")
    check_tensor(edit.motion, "edit.motion", where, ndim=3)
    if edit.motion.shape != shape:
        raise ValueError(f"{where}: edit.motion must be {shape}, got {tuple(edit.motion.shape)}")
    if not isinstance(edit.known, Tensor) or edit.known.dtype != torch.bool:
        raise TypeError(
            f"{where}: edit.known must be a bool tensor, got {getattr(edit.known, 'dtype', edit.known)}"
        )
    if edit.known.shape not in (shape, shape[1:]):
        raise ValueError(f"{where}: edit.known must be {shape} or {shape[1:]}, got {tuple(edit.known.shape)}")
    return Edit(model.standardizer.transform(edit.motion), edit.known.expand(shape))


@torch.no_grad()
def sample(
    model: MDM,
    action: Tensor | None,
    *,
    n_samples: int | None = None,
    steps: int | None = None,
    method: Method = "ancestral",
    eta: float = 0.0,
    guidance: float | None = None,
    edit: Edit | None = None,
    inpaint: Inpaint = "prediction",
    generator: torch.Generator | None = None,
    initial_noise: Tensor | None = None,
) -> Tensor:
    """Motions ``(B, T, F)`` in the units of :mod:`.data` (see the module notes).

    Args:
        model: a trained :class:`~.model.MDM` (put in ``eval()`` mode here).
        action: ``(B,)`` int64 actions, or ``None`` for unconditioned samples (``n_samples`` gives ``B``).
        steps: run a respaced schedule of this many steps (``None``: all ``S`` steps).
        method: ``"ancestral"`` or ``"ddim"``; eta: DDIM's noise scale in ``[0, 1]``.
        guidance: classifier-free guidance scale ``s`` (``None``: the conditional prediction alone).
        edit: the given motion and its known channels, to inpaint the rest.
        inpaint: ``"prediction"`` (the repository's) or ``"noised"``, see :data:`Inpaint`.
        generator: draws the noise (the global generator when ``None``).
        initial_noise: the loop's start :math:`x_S` ``(B, T, F)`` in standardised units (``None``: drawn
            from ``generator``). With DDIM at ``eta = 0`` it is the only randomness: the same start gives
            the same motion.
    """
    where = "sample"
    if not isinstance(model, MDM):
        raise TypeError(f"{where}: model must be an MDM, got {type(model).__name__}")
    check_choice(method, "method", where, METHODS)
    check_choice(inpaint, "inpaint", where, INPAINT_MODES)
    check_scalar(eta, "eta", where, minimum=0, maximum=1)
    if action is None:
        check_scalar(n_samples, "n_samples (needed without action)", where, kind=numbers.Integral, minimum=1)
        batch = int(n_samples)
    else:
        check_tensor(action, "action", where, ndim=1, floating=False)
        batch = action.shape[0]
        if n_samples is not None and n_samples != batch:
            raise ValueError(f"{where}: n_samples={n_samples} differs from the {batch} actions")
    schedule: NoiseSchedule = model.schedule
    if steps is not None:
        check_scalar(steps, "steps", where, kind=numbers.Integral, minimum=1, maximum=schedule.n_steps)
        schedule = schedule.respace(steps)
    model.eval()
    shape = (batch, model.cfg.n_frames, model.cfg.n_features)
    edit = _check_edit(edit, shape, model)
    if initial_noise is None:
        x = torch.randn(shape, generator=generator)
    else:
        check_tensor(initial_noise, "initial_noise", where, ndim=3)
        if initial_noise.shape != shape:
            raise ValueError(f"{where}: initial_noise must be {shape}, got {tuple(initial_noise.shape)}")
        x = initial_noise.to(torch.float32)
    for i in reversed(range(schedule.n_steps)):
        t = torch.full((batch,), i, dtype=torch.int64)
        x0 = guided_prediction(model, x, schedule.timesteps[t], action, guidance)
        if edit is not None and inpaint == "prediction":
            x0 = torch.where(edit.known, edit.motion, x0)
        noise = torch.randn(shape, generator=generator) if i > 0 else torch.zeros(shape)
        if method == "ddim":
            x = schedule.ddim_step(x, t, x0, noise, eta)
        else:
            mean, variance = schedule.posterior(x0, x, t)
            x = mean + variance.sqrt() * noise
        if edit is not None and inpaint == "noised":
            given = (
                schedule.q_sample(edit.motion, t - 1, torch.randn(shape, generator=generator))
                if i > 0
                else edit.motion
            )
            x = torch.where(edit.known, given, x)
    return model.standardizer.inverse(x)
