"""The training loop: determinism, clipping, NaN guard, progress, validation, the cache and resuming."""

from __future__ import annotations

import os
import re
import shutil
import signal
from dataclasses import replace
from pathlib import Path

import pytest
import torch
from torch import nn
from torch.utils.data import DataLoader, TensorDataset

from motionlab import config
from motionlab.checkpoints import checkpoint_path, save_checkpoint
from motionlab.train import (
    KLAnneal,
    LinearRamp,
    NonFiniteLossError,
    TensorBatches,
    TrainConfig,
    resume_path,
    run_identity,
    train,
    train_or_load,
    validation_every,
)
from motionlab.train.state import ResumeFile

FEATURES = 6
MODEL_CONFIG = {"kind": "tiny_autoencoder", "features": FEATURES, "hidden": 16}


@pytest.fixture(autouse=True)
def quick_build(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    config.set_threads(1)


def make_model(seed: int = 0) -> nn.Module:
    """A tiny noisy autoencoder; dropout and the noise in the loss make training depend on the global RNG."""
    torch.manual_seed(seed)
    return nn.Sequential(nn.Linear(FEATURES, 16), nn.Dropout(0.2), nn.Tanh(), nn.Linear(16, FEATURES))


def loss_fn(
    model: nn.Module, batch: torch.Tensor, step: int, coeffs: dict[str, float]
) -> dict[str, torch.Tensor]:
    noisy = batch + 0.1 * torch.randn_like(batch)
    recon = ((model(noisy) - batch) ** 2).mean()
    size = sum((p**2).sum() for p in model.parameters()) / 100
    return {"loss": recon + coeffs.get("beta", 1.0) * size, "recon": recon, "size": size}


def data(n: int = 64) -> torch.Tensor:
    return torch.randn(n, FEATURES, generator=torch.Generator().manual_seed(1))


def dataloader() -> DataLoader:
    return DataLoader(
        TensorDataset(data()), batch_size=16, shuffle=True, drop_last=True, generator=torch.Generator()
    )


def loader_loss_fn(
    model: nn.Module, batch: list[torch.Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, torch.Tensor]:
    return loss_fn(model, batch[0], step, coeffs)


def weights(model: nn.Module) -> dict[str, torch.Tensor]:
    return {k: v.detach().clone() for k, v in model.state_dict().items()}


def assert_bitwise_equal(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> None:
    assert a.keys() == b.keys()
    for key in a:
        assert torch.equal(a[key], b[key]), key


CFG = TrainConfig(
    steps=12,
    batch_size=16,
    lr=1e-2,
    checkpoint_every=5,
    schedules={"beta": KLAnneal(max_value=1.0, warmup=2, anneal=4)},
)


# --- the loop ------------------------------------------------------------------------------------------
def test_same_seed_gives_bitwise_identical_weights_and_a_different_one_does_not() -> None:
    runs = []
    for seed in (0, 0, 1):
        model = make_model()
        train(
            model,
            loss_fn,
            TensorBatches(data()),
            TrainConfig(steps=12, batch_size=16, seed=seed),
            progress=False,
        )
        runs.append(weights(model))
    assert_bitwise_equal(runs[0], runs[1])
    assert not torch.equal(runs[0]["0.weight"], runs[2]["0.weight"])


def test_training_leaves_the_callers_random_state_alone() -> None:
    torch.manual_seed(123)
    before = torch.get_rng_state()
    model = make_model()
    torch.set_rng_state(before)
    train(model, loss_fn, TensorBatches(data()), CFG, progress=False)
    assert torch.equal(torch.get_rng_state(), before)
    assert not model.training


def test_history_shapes_schedules_and_epoch_means() -> None:
    seen: list[tuple[int, dict[str, float], bool]] = []

    def recording_loss(model, batch, step, coeffs):
        seen.append((step, dict(coeffs), model.training))
        return loss_fn(model, batch, step, coeffs)

    cfg = TrainConfig(
        epochs=3,
        batch_size=16,
        val_every=5,
        lr=1e-2,
        lr_schedule=LinearRamp(0, 4, 0.5, 1.0),
        schedules={"beta": KLAnneal(max_value=1.0, warmup=2, anneal=4)},
    )
    val = TensorBatches(data(20), drop_last=False, shuffle=False)
    result = train(make_model(), recording_loss, TensorBatches(data()), cfg, val_data=val, progress=False)
    history = result.history
    assert len(history) == 12 and history.step == list(range(12))
    assert history.epoch == [0] * 4 + [1] * 4 + [2] * 4
    assert set(history.terms) == {"loss", "recon", "size"} and all(
        len(v) == 12 for v in history.terms.values()
    )
    assert history.coeffs["beta"] == pytest.approx([0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1, 1, 1])
    assert history.lr == pytest.approx([1e-2 * f for f in (0.5, 0.625, 0.75, 0.875)] + [1e-2] * 8)
    training_calls = [(s, c) for s, c, training in seen if training]
    assert [s for s, _ in training_calls] == list(range(12))
    assert all(c["beta"] == history.coeffs["beta"][s] for s, c in training_calls)
    assert sorted({s for s, _, training in seen if not training}) == [5, 10, 12]
    assert history.val_step == [5, 10, 12] and all(len(v) == 3 for v in history.val_terms.values())
    means = history.epoch_means()["loss"]
    assert means.shape == (3,)
    assert means[1] == pytest.approx(sum(history.terms["loss"][4:8]) / 4)
    assert result.metrics["steps"] == 12
    assert result.metrics["train.loss"] == pytest.approx(history.terms["loss"][-1])
    assert result.metrics["val.recon"] == history.val_terms["recon"][-1]


def test_validation_does_not_change_the_trained_weights() -> None:
    plain, validated = make_model(), make_model()
    train(plain, loss_fn, TensorBatches(data()), CFG, progress=False)
    cfg = replace(CFG, val_every=2)
    train(validated, loss_fn, TensorBatches(data()), cfg, val_data=TensorBatches(data(32)), progress=False)
    assert_bitwise_equal(weights(plain), weights(validated))


def test_validation_judges_the_objective_the_run_ends_with() -> None:
    """Every pass of a run of known length sees its schedules' last values (KL weight, teacher forcing), so
    the held-out curve moves with the weights only; training sees each step's."""
    seen: list[tuple[float, bool]] = []

    def recording_loss(model, batch, step, coeffs):
        seen.append((coeffs["beta"], model.training))
        return loss_fn(model, batch, step, coeffs)

    cfg = replace(CFG, steps=12, val_every=5, schedules={"beta": LinearRamp(0, 10, 0.0, 1.0)})
    train(
        make_model(),
        recording_loss,
        TensorBatches(data()),
        cfg,
        val_data=TensorBatches(data(32)),
        progress=False,
    )
    assert {beta for beta, training in seen if not training} == {1.0}
    assert sorted({beta for beta, training in seen if training})[:2] == [0.0, 0.1]


def test_every_validation_pass_draws_the_same_noise() -> None:
    """A loss that draws from torch's global generator (a VAE's latent, a diffusion step) sees the same draws
    in every validation pass, so the held-out curve moves with the weights only; training's draws go on."""

    def noisy_loss(model, batch, step, coeffs):
        out = loss_fn(model, batch, step, coeffs)
        return {"loss": out["loss"], "noise": torch.rand(())}

    result = train(
        make_model(),
        noisy_loss,
        TensorBatches(data()),
        replace(CFG, val_every=2),
        val_data=TensorBatches(data(32)),
        progress=False,
    )
    passes, drawn = result.history.val_terms["noise"], result.history.terms["noise"]
    assert len(passes) > 2 and len(set(passes)) == 1, passes
    assert len(set(drawn)) == len(drawn), drawn


def test_gradient_clipping_bounds_the_norm_the_optimiser_sees() -> None:
    clipped_norms: list[float] = []

    def measure(step, model, history):  # gradients are still in place right after the step
        clipped_norms.append(
            float(torch.linalg.vector_norm(torch.cat([p.grad.flatten() for p in model.parameters()])))
        )

    def steep_loss(model, batch, step, coeffs):
        return {"loss": 1000.0 * loss_fn(model, batch, step, coeffs)["loss"]}

    cfg = TrainConfig(steps=6, batch_size=16, grad_clip=0.5)
    result = train(make_model(), steep_loss, TensorBatches(data()), cfg, progress=False, callbacks=[measure])
    assert all(norm > 0.5 for norm in result.history.grad_norm)
    assert clipped_norms == pytest.approx([0.5] * 6, rel=1e-4)

    clipped_norms.clear()
    cfg = TrainConfig(steps=3, batch_size=16, grad_clip=None)
    result = train(make_model(), steep_loss, TensorBatches(data()), cfg, progress=False, callbacks=[measure])
    assert clipped_norms == pytest.approx(result.history.grad_norm, rel=1e-5)
    assert min(clipped_norms) > 100


@pytest.mark.parametrize("bad_value, term", [(float("nan"), "kl"), (float("inf"), "recon")])
def test_non_finite_loss_stops_naming_the_term_and_step(bad_value: float, term: str) -> None:
    def exploding(model, batch, step, coeffs):
        out = loss_fn(model, batch, step, coeffs)
        out["kl"] = torch.tensor(bad_value if step == 3 and term == "kl" else 0.0)
        if step == 3 and term == "recon":
            out["recon"] = out["recon"] * bad_value
        out["loss"] = out["loss"] + out["kl"] + out["recon"]
        return out

    model = make_model()
    snapshots: list[dict[str, torch.Tensor]] = []
    with pytest.raises(NonFiniteLossError, match=rf"'{term}' is {bad_value} at step 3") as info:
        train(
            model,
            exploding,
            TensorBatches(data()),
            CFG,
            progress=False,
            callbacks=[lambda s, m, h: snapshots.append(weights(m))],
        )
    assert info.value.term == term and info.value.step == 3
    assert isinstance(info.value, RuntimeError)
    assert_bitwise_equal(weights(model), snapshots[-1])  # the bad step did not update the weights


def test_non_finite_gradient_is_reported_as_grad_norm() -> None:
    def sqrt_at_zero(model, batch, step, coeffs):
        return {"loss": torch.sqrt((model[0].weight * 0).sum())}

    with pytest.raises(NonFiniteLossError, match="gradient norm") as info:
        train(make_model(), sqrt_at_zero, TensorBatches(data()), CFG, progress=False)
    assert info.value.term == "grad_norm" and info.value.step == 0


@pytest.mark.parametrize(
    "output, error, message",
    [
        ({"recon": torch.tensor(1.0)}, TypeError, "'loss' entry"),
        ({"loss": torch.ones(3)}, TypeError, r"'loss' at step 0 must be a one-element tensor, got \(3,\)"),
        ({"loss": torch.tensor(1.0), "kl": 0.5}, TypeError, "'kl'"),
        ({"loss": torch.tensor(1.0)}, ValueError, "does not depend on any trainable parameter"),
    ],
)
def test_malformed_loss_output_is_rejected(output, error, message: str) -> None:
    with pytest.raises(error, match=message):
        train(make_model(), lambda m, b, s, c: output, TensorBatches(data()), CFG, progress=False)


def test_changing_term_names_is_rejected() -> None:
    def fickle(model, batch, step, coeffs):
        out = loss_fn(model, batch, step, coeffs)
        return out if step == 0 else {"loss": out["loss"]}

    with pytest.raises(ValueError, match="at step 1"):
        train(make_model(), fickle, TensorBatches(data()), CFG, progress=False)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"steps": 3, "epochs": 2}, ValueError, "exactly one"),
        ({}, ValueError, "exactly one"),
        ({"steps": 0}, ValueError, "TrainConfig: steps must be at least 1, got 0"),
        ({"steps": 3, "lr": -1.0}, ValueError, "TrainConfig: lr must be greater than 0, got -1.0"),
        ({"steps": 3, "grad_clip": 0.0}, ValueError, "TrainConfig: grad_clip must be greater than 0"),
        (
            {"steps": 3, "betas": (0.9, 1.0)},
            ValueError,
            r"TrainConfig: betas\[1\] must be in \[0, 1\), got 1.0",
        ),
        ({"steps": 3, "betas": (0.9,)}, ValueError, r"TrainConfig: betas must be a tuple of 2 entries"),
        ({"steps": 3, "betas": [0.9, 0.99]}, TypeError, r"TrainConfig: betas must be a tuple"),
        ({"steps": 3, "schedules": {"beta": lambda s: 1.0}}, TypeError, r"schedules\['beta'\]"),
        ({"steps": 3, "seed": -2}, ValueError, "TrainConfig: seed must be at least 0, got -2"),
        ({"steps": 3.0}, TypeError, r"TrainConfig: steps must be int, got 3.0 \(float\)"),
        ({"epochs": 2, "batch_size": True}, TypeError, "TrainConfig: batch_size must be int, got True"),
        ({"steps": 3, "lr": "0.1"}, TypeError, "TrainConfig: lr must be int or float"),
    ],
)
def test_train_config_validation(kwargs, error, message: str) -> None:
    with pytest.raises(error, match=message):
        TrainConfig(**kwargs)


def test_dataloader_sources_are_checked_and_deterministic() -> None:
    runs = []
    for _ in range(2):
        model = make_model()
        train(model, loader_loss_fn, dataloader(), TrainConfig(epochs=2, batch_size=16), progress=False)
        runs.append(weights(model))
    assert_bitwise_equal(*runs)
    unseeded = DataLoader(TensorDataset(data()), batch_size=16, shuffle=True)
    with pytest.raises(ValueError, match="generator"):
        train(make_model(), loader_loss_fn, unseeded, CFG, progress=False)
    with pytest.raises(ValueError, match="batch_size 16 differs"):
        train(make_model(), loader_loss_fn, dataloader(), TrainConfig(steps=2, batch_size=8), progress=False)
    with pytest.raises(TypeError, match="DataLoader or a callable"):
        train(make_model(), loss_fn, data(), CFG, progress=False)


def test_empty_epoch_is_an_error() -> None:
    with pytest.raises(ValueError, match="no batches in epoch 0"):
        train(make_model(), loss_fn, lambda epoch, gen, size: iter(()), CFG, progress=False)


def test_progress_output_only_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    train(make_model(), loss_fn, TensorBatches(data()), CFG, progress=False)
    train(make_model(), loss_fn, TensorBatches(data()), CFG)  # quick profile: off by default
    assert capsys.readouterr() == ("", "")
    train(make_model(), loss_fn, TensorBatches(data()), CFG, progress=True, desc="tiny")
    captured = capsys.readouterr()
    assert captured.out == "" and "tiny" in captured.err and "12/12" in captured.err
    train(make_model(), loader_loss_fn, dataloader(), TrainConfig(epochs=2, batch_size=16), progress=True)
    assert "8/8" in capsys.readouterr().err  # 2 epochs of a DataLoader with 4 batches


# --- the cache -----------------------------------------------------------------------------------------
def counting(calls: list[int]):
    def counted(model, batch, step, coeffs):
        calls.append(step)
        return loss_fn(model, batch, step, coeffs)

    return counted


def test_cache_hit_skips_training_and_restores_weights_and_history() -> None:
    first = make_model()
    trained = train_or_load("tiny", MODEL_CONFIG, first, loss_fn, TensorBatches(data()), CFG)
    assert not trained.loaded_from_cache and trained.path.exists()
    calls: list[int] = []
    second = make_model(seed=99)
    loaded = train_or_load("tiny", MODEL_CONFIG, second, counting(calls), TensorBatches(data()), CFG)
    assert loaded.loaded_from_cache and calls == [] and not second.training
    assert_bitwise_equal(weights(first), weights(second))
    assert loaded.history == trained.history and loaded.metrics == trained.metrics


def test_bookkeeping_intervals_do_not_invalidate_the_cache() -> None:
    train_or_load("tiny", MODEL_CONFIG, make_model(), loss_fn, TensorBatches(data()), CFG)
    relaxed = replace(CFG, log_every=3, checkpoint_every=None)
    assert train_or_load(
        "tiny", MODEL_CONFIG, make_model(), loss_fn, TensorBatches(data()), relaxed
    ).loaded_from_cache


@pytest.mark.parametrize(
    "change",
    [
        {"train_config": replace(CFG, lr=5e-3)},
        {"train_config": replace(CFG, schedules={"beta": KLAnneal(1.0, 2, 5)})},
        {"model_config": {**MODEL_CONFIG, "hidden": 17}},
        {"model_config": {**MODEL_CONFIG, "activation": "tanh"}},
        {"model_config": {k: v for k, v in MODEL_CONFIG.items() if k != "hidden"}},
        {"data_config": {"clips": 64}},
    ],
)
def test_a_changed_configuration_retrains(change: dict) -> None:
    train_or_load("tiny", MODEL_CONFIG, make_model(), loss_fn, TensorBatches(data()), CFG)
    kwargs = {"model_config": MODEL_CONFIG, "train_config": CFG, **change}
    data_config = kwargs.pop("data_config", None)
    result = train_or_load(
        "tiny",
        kwargs["model_config"],
        make_model(),
        loss_fn,
        TensorBatches(data()),
        kwargs["train_config"],
        data_config=data_config,
    )
    assert not result.loaded_from_cache
    assert len(list(config.checkpoint_dir().glob("tiny-*.pt"))) == 2


def test_a_corrupt_cache_entry_is_retrained() -> None:
    reference = make_model()
    result = train_or_load("tiny", MODEL_CONFIG, reference, loss_fn, TensorBatches(data()), CFG)
    result.path.write_bytes(b"not a checkpoint")
    model = make_model()
    with pytest.warns(UserWarning, match="unreadable checkpoint"):
        again = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    assert not again.loaded_from_cache
    assert_bitwise_equal(weights(reference), weights(model))


def test_a_cache_entry_without_history_is_retrained_from_the_fresh_model() -> None:
    identity = run_identity(MODEL_CONFIG, CFG)
    save_checkpoint("tiny", identity, make_model(seed=5), extra={"metrics": {}})
    reference, model = make_model(), make_model()
    train(reference, loss_fn, TensorBatches(data()), CFG, progress=False)
    with pytest.warns(UserWarning, match="malformed"):
        result = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    assert not result.loaded_from_cache
    assert_bitwise_equal(weights(reference), weights(model))


# How an entry written by an older version of the code differs, and the reason the warning gives.
STALE_ENTRIES = {
    "config key removed since": (
        lambda p: p["config"]["model"].update(activation="tanh"),
        "its config has keys the code no longer has \\('model.activation'\\)",
    ),
    "config key added since": (
        lambda p: p["config"]["model"].pop("hidden"),
        "its config lacks 'model.hidden'",
    ),
    "config value changed": (
        lambda p: p["config"]["train"].update(lr=0.5),
        "its config differs at 'train.lr'",
    ),
    "tensor missing": (lambda p: p["state_dict"].pop("3.bias"), "the state dict lacks '3.bias'"),
    "tensor unexpected": (
        lambda p: p["state_dict"].update({"4.weight": torch.zeros(2)}),
        "the state dict has unexpected '4.weight'",
    ),
    "tensor renamed": (
        lambda p: p["state_dict"].update({"3.b": p["state_dict"].pop("3.bias")}),
        "the state dict lacks '3.bias' and has unexpected '3.b'",
    ),
    "tensor reshaped": (
        lambda p: p["state_dict"].update({"0.weight": torch.zeros(16, 7)}),
        "'0.weight' has shape \\(16, 7\\), the model's \\(16, 6\\)",
    ),
    "not a tensor": (
        lambda p: p["state_dict"].update({"0.bias": [0.0] * 16}),
        "'0.bias' is a list, not a tensor",
    ),
    "older format": (lambda p: p.update(format=0), "its format is 0, this code reads 1"),
    "other name": (lambda p: p.update(name="tiny_v0"), "it was written for 'tiny_v0'"),
    "extra not a dict": (lambda p: p.update(extra=[1, 2]), "its extra is a list, not a dict"),
}


@pytest.mark.parametrize("stale", sorted(STALE_ENTRIES))
def test_an_entry_written_by_older_code_is_retrained_saying_why(stale: str) -> None:
    """An entry under the same key whose config or tensors no longer fit: one warning line, then a fresh
    training from the untouched model (no half-load, no crash), whose result replaces the entry."""
    edit, why = STALE_ENTRIES[stale]
    reference = make_model()
    first = train_or_load("tiny", MODEL_CONFIG, reference, loss_fn, TensorBatches(data()), CFG)
    payload = torch.load(first.path, weights_only=True)
    edit(payload)
    torch.save(payload, first.path)
    model = make_model()
    with pytest.warns(UserWarning) as caught:
        again = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1 and "\n" not in messages[0]
    assert re.fullmatch(f"ignoring checkpoint {re.escape(first.path.name)}: {why}", messages[0]), messages[0]
    assert not again.loaded_from_cache and again.path == first.path and again.history == first.history
    assert_bitwise_equal(weights(reference), weights(model))
    assert train_or_load(
        "tiny", MODEL_CONFIG, make_model(seed=3), loss_fn, TensorBatches(data()), CFG
    ).loaded_from_cache


# --- resuming ------------------------------------------------------------------------------------------
class Interrupt(Exception):
    pass


def interrupt_at(step: int):
    def callback(completed: int, model: nn.Module, history) -> None:
        if completed == step:
            raise Interrupt(f"stop at {completed}")

    return callback


def jittered_source():
    """A source that (against the advice) draws its augmentation noise from the global RNG."""
    tensors = TensorBatches(data())

    def batches(epoch, generator, batch_size):
        for batch in tensors(epoch, generator, batch_size):
            yield batch + 0.01 * torch.randn_like(batch)

    return batches


SOURCES = {
    "tensors": (lambda: TensorBatches(data()), loss_fn),
    "dataloader": (dataloader, loader_loss_fn),
    "global_rng": (jittered_source, loss_fn),
}


@pytest.mark.parametrize("source", sorted(SOURCES))
@pytest.mark.parametrize("stop", [3, 4, 9])
def test_resumed_training_equals_uninterrupted_bitwise(source: str, stop: int) -> None:
    make_source, fn = SOURCES[source]
    reference = make_model()
    expected = train(reference, fn, make_source(), CFG, progress=False)

    with pytest.raises(Interrupt):
        train_or_load(
            "tiny", MODEL_CONFIG, make_model(), fn, make_source(), CFG, callbacks=[interrupt_at(stop)]
        )
    state_file = resume_path("tiny", run_identity(MODEL_CONFIG, CFG))
    assert state_file.name == checkpoint_path("tiny", run_identity(MODEL_CONFIG, CFG)).stem + ".resume.pt"
    assert state_file.exists()

    model = make_model(seed=42)  # a different start: everything must come from the saved state
    result = train_or_load("tiny", MODEL_CONFIG, model, fn, make_source(), CFG)
    assert result.resumed_from_step == stop and not result.loaded_from_cache
    assert_bitwise_equal(weights(reference), weights(model))
    assert result.history == expected.history
    assert not state_file.exists() and result.path.exists()


def test_resume_from_the_last_periodic_state_after_a_hard_crash(tmp_path: Path) -> None:
    reference = make_model()
    train(reference, loss_fn, TensorBatches(data()), CFG, progress=False)
    state_file = resume_path("tiny", run_identity(MODEL_CONFIG, CFG))
    kept = tmp_path / "kept.pt"

    def keep_periodic(completed, model, history):
        if completed == 5:
            shutil.copy(state_file, kept)

    with pytest.raises(Interrupt):
        train_or_load(
            "tiny",
            MODEL_CONFIG,
            make_model(),
            loss_fn,
            TensorBatches(data()),
            CFG,
            callbacks=[keep_periodic, interrupt_at(8)],
        )
    shutil.copy(kept, state_file)  # as if the process had died at step 8 without saving
    model = make_model()
    result = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    assert result.resumed_from_step == 5
    assert_bitwise_equal(weights(reference), weights(model))


def test_ctrl_c_is_held_to_the_step_boundary_then_saved() -> None:
    handler = signal.getsignal(signal.SIGINT)  # the default one, or SIG_IGN in a background job
    reference = make_model()
    train(reference, loss_fn, TensorBatches(data()), CFG, progress=False)

    def press_ctrl_c(completed, model, history):
        if completed == 7:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt, match="after step 7"):
        train_or_load(
            "tiny", MODEL_CONFIG, make_model(), loss_fn, TensorBatches(data()), CFG, callbacks=[press_ctrl_c]
        )
    assert signal.getsignal(signal.SIGINT) is handler  # restored
    model = make_model()
    result = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    assert result.resumed_from_step == 7
    assert_bitwise_equal(weights(reference), weights(model))


def test_unusable_resume_files_are_ignored_with_a_warning(tmp_path: Path) -> None:
    state = ResumeFile(tmp_path / "run.resume.pt", {"model": {"a": 1}})
    state.save({"step": 3})
    assert state.load() == {"step": 3}
    with pytest.warns(UserWarning, match="another configuration"):
        assert ResumeFile(state.path, {"model": {"a": 2}}).load() is None
    state.path.write_bytes(b"garbage")
    with pytest.warns(UserWarning, match="unreadable"):
        assert state.load() is None

    identity = run_identity(MODEL_CONFIG, CFG)
    ResumeFile(resume_path("tiny", identity), identity).save({"step": 3, "model": {}})
    reference, model = make_model(), make_model()
    train(reference, loss_fn, TensorBatches(data()), CFG, progress=False)
    with pytest.warns(UserWarning, match="ignoring"):
        result = train_or_load("tiny", MODEL_CONFIG, model, loss_fn, TensorBatches(data()), CFG)
    assert result.resumed_from_step is None
    assert_bitwise_equal(weights(reference), weights(model))


def test_validation_every_spreads_the_passes_over_the_run() -> None:
    assert validation_every(20_000) == 500 and validation_every(240) == 6 and validation_every(100, 10) == 10
    # a short run validates no closer than every 4 steps: 3 passes in 12 steps, one at the end of 3 steps
    assert validation_every(12) == 4 and validation_every(160) == 4 and validation_every(3) == 3
    with pytest.raises(ValueError, match="validation_every: steps must be an integer >= 1, got 0"):
        validation_every(0)
