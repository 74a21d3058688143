from dataclasses import dataclass

import pytest
import torch
from torch import nn

from motionlab.checkpoints import checkpoint_path, config_hash, load_checkpoint, save_checkpoint


@dataclass(frozen=True)
class TinyConfig:
    width: int = 4
    layers: tuple[int, ...] = (1, 2)


@pytest.fixture(autouse=True)
def build(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    return tmp_path


def test_round_trip_restores_weights_and_extra():
    torch.manual_seed(0)
    cfg = TinyConfig()
    model = nn.Linear(cfg.width, 2)
    save_checkpoint("tiny", cfg, model, extra={"val_loss": 0.5})
    fresh = nn.Linear(cfg.width, 2)
    extra = load_checkpoint("tiny", cfg, fresh)
    assert extra == {"val_loss": 0.5}
    assert torch.equal(fresh.weight, model.weight)


def test_hash_depends_on_config_name_and_profile(monkeypatch):
    base = config_hash("tiny", TinyConfig())
    assert config_hash("tiny", TinyConfig(width=5)) != base
    assert config_hash("other", TinyConfig()) != base
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    assert config_hash("tiny", TinyConfig()) != base


def test_missing_entry_returns_none():
    assert load_checkpoint("tiny", TinyConfig(), nn.Linear(4, 2)) is None


def test_shape_mismatch_is_not_half_loaded():
    cfg = TinyConfig()
    save_checkpoint("tiny", cfg, nn.Linear(4, 2))
    other = nn.Linear(4, 3)
    before = other.weight.detach().clone()
    with pytest.warns(UserWarning, match=r"'bias' has shape \(2,\), the model's \(3,\); 'weight' has shape"):
        assert load_checkpoint("tiny", cfg, other) is None
    assert torch.equal(other.weight, before)


def test_different_parameter_names_are_rejected():
    cfg = TinyConfig()
    save_checkpoint("tiny", cfg, nn.Sequential(nn.Linear(4, 2)))
    with pytest.warns(
        UserWarning, match="the state dict lacks 'bias', 'weight' and has unexpected '0.bias', '0.weight'"
    ):
        assert load_checkpoint("tiny", cfg, nn.Linear(4, 2)) is None


def test_a_long_list_of_names_is_cut_short():
    cfg = TinyConfig()
    save_checkpoint("tiny", cfg, nn.Sequential(*(nn.Linear(4, 4) for _ in range(3))))
    with pytest.warns(
        UserWarning,
        match=r"lacks 'bias', 'weight' and has unexpected "
        r"'0.bias', '0.weight', '1.bias', '1.weight' and 2 more$",
    ):
        assert load_checkpoint("tiny", cfg, nn.Linear(4, 4)) is None


def test_corrupt_file_is_ignored_with_a_warning():
    cfg = TinyConfig()
    path = checkpoint_path("tiny", cfg)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a checkpoint")
    with pytest.warns(UserWarning, match="unreadable checkpoint"):
        assert load_checkpoint("tiny", cfg, nn.Linear(4, 2)) is None


def test_bad_name_and_config_are_rejected():
    with pytest.raises(ValueError, match="name"):
        checkpoint_path("a/b", TinyConfig())
    with pytest.raises(TypeError, match="dataclass"):
        config_hash("tiny", 3)
