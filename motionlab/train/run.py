"""One training run of one model, described once: what every chapter trains and the training command runs.

A :class:`Run` is a frozen, picklable description: the name and model config that name its checkpoint, how
to build the model, the loss, the batches, the :class:`~motionlab.train.TrainConfig` and what defines the
data (the cache key's data part). Its caching and training are written here once::

    run = Run("vae03_pose_vae", vae_cfg, partial(build_seeded, partial(MLPVAE, vae_cfg)), given(elbo_loss),
              partial(training_batches, poses), train_cfg, data={"x": fingerprint})
    run.is_cached()                    # would train() load it?
    model, result = run.train()        # load it from the cache, or build, train and cache it

``build``, ``loss`` and ``batches`` are picklable callables (module-level functions, ``functools.partial``
of them, bound methods of frozen dataclasses), so a worker process can run the run
(:func:`motionlab.train.many.train_many`). ``loss``, ``batches`` and ``initialize`` are called only when the
run trains: a loss may need a frozen network, batches may need data, and a data-dependent initialisation
(MoGlow's least-squares predictor) costs time, that loading the cached weights does not.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeVar

from torch import nn

from motionlab.train.batches import BatchSource
from motionlab.train.cache import is_cached, load_cached, train_or_load
from motionlab.train.loop import LossFn, TrainResult
from motionlab.train.train_config import TrainConfig

T = TypeVar("T")


def _value(value: T) -> T:
    return value


def given(value: T) -> Callable[[], T]:
    """A picklable maker that returns ``value``: the ``loss`` of a run whose objective needs nothing built
    (``given(elbo_loss)``)."""
    return partial(_value, value)


@dataclass(frozen=True, eq=False)
class Run:
    """One training run of one model (frozen and picklable, so that a worker process can run it).

    Attributes:
        name: the checkpoint cache name, e.g. ``"mcell_mcell"``.
        model: the model's config (a dataclass or a dict): the cache key's model part.
        build: ``build(seed) -> nn.Module``, a fresh model, its initial weights drawn from ``seed`` (the
            training config's, so that one seed names the whole run).
        loss: ``loss() -> loss_fn``, the objective ``loss_fn(model, batch, step, coeffs)`` (made only when
            the run trains).
        batches: ``batches(model) -> BatchSource``, the training batches (made only when the run trains;
            ``model`` is the built model, for batches standardised by the model's own statistics).
        train_config: the :class:`~motionlab.train.TrainConfig`: the cache key's training part; its
            ``seed`` seeds the batches and the training loop's random draws.
        data: what defines the training data (fingerprints, window length, ...): the cache key's data part.
        initialize: ``initialize(model)``, a data-dependent initialisation of the built model before it
            trains (``None``: none); a model loaded from the cache has its result in its weights.
        val_batches: ``val_batches(model) -> BatchSource``, held-out batches the run validates on every
            ``train_config.val_every`` steps (``None``: it does not validate). A validation pass leaves the
            weights as they are (no gradients, random state restored); its curve is what tells whether the
            run has levelled off (:func:`~motionlab.train.reference.levelling`).
    """

    name: str
    model: Any
    build: Callable[[int], nn.Module]
    loss: Callable[[], LossFn]
    batches: Callable[[nn.Module], BatchSource]
    train_config: TrainConfig
    data: Any = None
    initialize: Callable[[nn.Module], Any] | None = None
    val_batches: Callable[[nn.Module], BatchSource] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"Run: name must be a non-empty string, got {self.name!r}")
        if not isinstance(self.train_config, TrainConfig):
            raise TypeError(
                f"Run: train_config must be a TrainConfig, got {type(self.train_config).__name__}"
            )
        for field in ("build", "loss", "batches"):
            if not callable(getattr(self, field)):
                raise TypeError(f"Run {self.name!r}: {field} must be callable, got {getattr(self, field)!r}")
        if (self.val_batches is None) != (self.train_config.val_every is None):
            raise ValueError(
                f"Run {self.name!r}: give both val_batches and train_config.val_every, or neither "
                f"(val_batches {'set' if self.val_batches else 'None'}, "
                f"val_every {self.train_config.val_every})"
            )

    def is_cached(self) -> bool:
        """Whether :meth:`train` would load the model from the checkpoint cache instead of training it."""
        return is_cached(self.name, self.model, self.train_config, self.data)

    def train(self, progress: bool | None = None) -> tuple[nn.Module, TrainResult]:
        """Build the model and load its cached weights, or train it (making its loss and batches) and cache
        it; return it in eval mode with its :class:`TrainResult`."""
        model = self.build(self.train_config.seed)
        cached = load_cached(self.name, self.model, self.train_config, self.data, model)
        if cached is not None:
            return model, cached
        if self.initialize is not None:
            self.initialize(model)
        result = train_or_load(
            self.name,
            self.model,
            model,
            self.loss(),
            self.batches(model),
            self.train_config,
            data_config=self.data,
            val_data=None if self.val_batches is None else self.val_batches(model),
            progress=progress,
        )
        return model, result
