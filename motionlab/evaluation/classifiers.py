"""The two evaluation classifiers of the course, one architecture each from the papers we reproduce.

* ``kind="conv"`` — the Motion Cell paper's classifier architecture (its Table 1): 3 × [Conv1D + ReLU] over
  time, adaptive average pooling, a fully connected layer. Its per-layer activations are what the paper's
  classifier loss (eq. 24, feature matching) compares. The paper trains one such classifier per attribute
  (§3.4); ours shares the convolutions between the labels (below).
* ``kind="gru"`` — the Action2Motion / ODMO recognition model: a 2-layer GRU(128), its last hidden state
  through FC + tanh to a 30-d feature vector (the vector FID, Diversity and Multimodality are computed on),
  then FC to the classes. Action2Motion's code starts the GRU from random noise, which makes features
  random; ours starts from zeros, so features are a deterministic function of the motion.

Both read frames ``(B, T, F)`` (already standardised by the caller) of any length ``T >= 1`` and have one
output head per label (``action``, ``mode``, ``body``) on a shared trunk.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Literal

import torch
from torch import Tensor, nn

from motionlab.validation import Checked, check_scalar, check_tensor, choice, instance, integer

HEADS = ("action", "mode", "body")


@dataclass(frozen=True)
class ClassifierConfig(Checked):
    """Architecture of an evaluation classifier.

    Attributes:
        kind: ``"conv"`` (Motion Cell paper) or ``"gru"`` (Action2Motion / ODMO).
        in_features: features per frame ``F``.
        classes: number of classes per head, e.g. ``{"action": 6, "mode": 12, "body": 2}``.
        hidden: conv channels, or GRU hidden size (128 in Action2Motion).
        feature_dim: size of the GRU's tanh feature vector before the heads (30 in Action2Motion); the conv
            classifier's features are its pooled channels (``hidden``).
        kernel_size: temporal kernel of the conv layers (odd).
    """

    kind: Literal["conv", "gru"] = choice(("conv", "gru"))
    in_features: int = integer(minimum=1)
    classes: dict[str, int] = instance(dict, default_factory=dict)
    hidden: int = integer(128, minimum=1)
    feature_dim: int = integer(30, minimum=1)
    kernel_size: int = integer(5, minimum=1)

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "ClassifierConfig"
        if not self.classes:
            raise ValueError(f"{where}: classes needs at least one head, got {self.classes}")
        for head, count in self.classes.items():
            check_scalar(count, f"classes[{head!r}]", where, kind=numbers.Integral, minimum=2)
        if self.kernel_size % 2 != 1:
            raise ValueError(f"ClassifierConfig.kernel_size must be odd, got {self.kernel_size}")


class MotionClassifier(nn.Module):
    """A multi-head motion classifier: ``forward(x (B, T, F)) -> {head: logits (B, C_head)}``."""

    def __init__(self, cfg: ClassifierConfig) -> None:
        super().__init__()
        self.cfg = cfg
        if cfg.kind == "conv":
            pad = cfg.kernel_size // 2
            self.convs = nn.ModuleList(
                nn.Conv1d(cfg.in_features if i == 0 else cfg.hidden, cfg.hidden, cfg.kernel_size, padding=pad)
                for i in range(3)
            )
            width = cfg.hidden
        else:
            self.gru = nn.GRU(cfg.in_features, cfg.hidden, num_layers=2, batch_first=True)
            self.to_features = nn.Linear(cfg.hidden, cfg.feature_dim)
            width = cfg.feature_dim
        self.feature_dim = width
        self.heads = nn.ModuleDict({name: nn.Linear(width, n) for name, n in cfg.classes.items()})

    def layer_activations(self, x: Tensor) -> list[Tensor]:
        """The trunk's intermediate activations, in order; the last one is the feature vector.

        For ``conv``: the three conv outputs ``(B, hidden, T)`` then their time average ``(B, hidden)``
        (the input of the paper's final FC layer); for ``gru``: the GRU outputs ``(B, T, hidden)`` then the
        30-d tanh features ``(B, feature_dim)``. (Inputs to the Motion Cell's feature-matching loss.)
        """
        check_tensor(x, "x", "MotionClassifier", ndim=3, trailing=(self.cfg.in_features,), finite=False)
        if x.shape[1] < 1:
            raise ValueError(f"MotionClassifier: x must hold at least one frame, got shape {tuple(x.shape)}")
        if self.cfg.kind == "conv":
            acts, h = [], x.transpose(1, 2)
            for conv in self.convs:
                h = torch.relu(conv(h))
                acts.append(h)
            acts.append(h.mean(dim=-1))
            return acts
        out, _ = self.gru(x)  # zero initial state: deterministic features
        return [out, torch.tanh(self.to_features(out[:, -1]))]

    def features(self, x: Tensor) -> Tensor:
        """The feature vector ``(B, self.feature_dim)`` used for FID, Diversity and Multimodality."""
        return self.layer_activations(x)[-1]

    def forward(self, x: Tensor) -> dict[str, Tensor]:
        features = self.features(x)
        return {name: head(features) for name, head in self.heads.items()}
