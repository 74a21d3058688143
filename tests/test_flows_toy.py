"""The 2D toy: two moons, a toy flow whose density integrates to one, and its training loss."""

import numpy as np
import pytest
import torch

from motionlab.models.flows import (
    ToyFlow,
    ToyFlowConfig,
    grid_density,
    perturb_parameters_,
    toy_nll_loss,
    train_toy_flow,
    two_moons,
)
from motionlab.models.flows.toy import TOY_POINTS, TOY_VAL_POINTS
from motionlab.train import TensorBatches, TrainConfig, build_seeded, train


def test_two_moons_is_seeded_and_standardised():
    a, b = two_moons(2000, seed=3), two_moons(2000, seed=3)
    assert torch.equal(a, b) and not torch.equal(a, two_moons(2000, seed=4))
    assert a.shape == (2000, 2) and a.dtype == torch.float32
    assert a.mean(0).abs().max() < 0.1 and ((a.std(0) - 1).abs() < 0.2).all()
    with pytest.raises(ValueError):
        two_moons(0)


def test_density_of_a_random_flow_integrates_to_one():
    torch.manual_seed(0)
    flow = perturb_parameters_(
        ToyFlow(ToyFlowConfig(steps=3, hidden=8)), 0.1, torch.Generator().manual_seed(0)
    ).eval()
    grid = grid_density(flow, extent=12.0, resolution=300)
    assert abs(grid.integral - 1.0) < 1e-3
    assert grid.density.shape == (300, 300) and (grid.density >= 0).all()


def test_a_few_training_steps_lower_the_nll_and_sampling_is_seeded():
    torch.manual_seed(0)
    data = two_moons(512, seed=0)
    flow = ToyFlow(ToyFlowConfig(steps=2, hidden=16))
    with torch.no_grad():
        before = float(-flow.log_prob(data).mean())
    result = train(
        flow,
        toy_nll_loss,
        TensorBatches((data,)),
        TrainConfig(steps=40, batch_size=128, lr=1e-2),
        progress=False,
    )
    assert result.metrics["train.nll"] < before
    a = flow.sample(10, 0.8, torch.Generator().manual_seed(1))
    assert torch.equal(a, flow.sample(10, 0.8, torch.Generator().manual_seed(1)))
    assert np.isfinite(a.numpy()).all()


def test_toy_inputs_are_checked():
    flow = ToyFlow(ToyFlowConfig(steps=1, hidden=4))
    with pytest.raises(
        ValueError, match=r"ToyFlow.log_prob: points must have shape \(\.\.\., 2\), got \(3, 3\)"
    ):
        flow.log_prob(torch.zeros(3, 3))
    with pytest.raises(
        ValueError, match=r"ToyFlow.log_prob: points contains NaN .* \(first at index \(0, 0\)\)"
    ):
        flow.log_prob(torch.tensor([[float("nan"), 0.0]]))
    with pytest.raises(ValueError, match="grid_density: resolution must be at least 2, got 1"):
        grid_density(flow, resolution=1)
    with pytest.raises(ValueError, match="ToyFlowConfig: steps must be at least 1, got 0"):
        ToyFlowConfig(steps=0)
    with pytest.raises(TypeError, match="ToyFlow.sample: n must be an integer, got 2.5"):
        flow.sample(2.5)


def test_toy_temperature_widget_callback_draws_seeded_samples():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from motionlab.widgets.flows import show_toy_temperature

    torch.manual_seed(0)
    flow = ToyFlow(ToyFlowConfig(steps=1, hidden=4)).eval()
    grid = grid_density(flow, extent=3.0, resolution=20)
    figure = show_toy_temperature(flow, grid, temperature=0.5, n=200, seed=1)
    offsets = figure.axes[0].collections[0].get_offsets()
    assert offsets.shape == (200, 2)
    np.testing.assert_allclose(
        np.asarray(offsets), flow.sample(200, 0.5, torch.Generator().manual_seed(1)).numpy()
    )
    plt.close("all")


def test_the_chapters_toy_flow_trains_once_then_loads(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    flow, result = train_toy_flow(hidden=4, steps=3)
    assert not result.loaded_from_cache and result.metrics["steps"] == 3
    again, cached = train_toy_flow(hidden=4, steps=3)
    assert cached.loaded_from_cache
    points = two_moons(8, seed=1)
    assert torch.equal(again.log_prob(points), flow.log_prob(points))


def test_the_toy_flow_validates_on_fresh_moons_without_changing_the_weights(monkeypatch, tmp_path):
    """The chapter's toy flow validates every ``val_every`` steps on its own draw of moons (seed 2, not the
    training points nor the chapter's test points); its weights are those of the same training without
    validation, bit for bit."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    flow, result = train_toy_flow(hidden=4, steps=6)
    assert result.history.val_step == [4, 6]
    val_points = two_moons(TOY_VAL_POINTS, seed=2)
    with torch.no_grad():
        final_nll = float(-flow.log_prob(val_points).mean())  # 4 full batches: their mean is the mean
    assert result.history.val_terms["nll"][-1] == pytest.approx(final_nll, rel=1e-5)

    plain_cfg = TrainConfig(steps=6, batch_size=256, lr=5e-3, grad_clip=5.0)
    plain = build_seeded(lambda: ToyFlow(ToyFlowConfig(steps=6, hidden=4)), plain_cfg.seed)
    plain_result = train(
        plain, toy_nll_loss, TensorBatches((two_moons(TOY_POINTS, seed=0),)), plain_cfg, progress=False
    )
    assert plain_result.history.val_step == []
    for key, value in flow.state_dict().items():
        assert torch.equal(value, plain.state_dict()[key]), key
