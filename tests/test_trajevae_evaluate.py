"""Trajectory-completion evaluation: DLow metrics by hand, borrowed trajectories, upsampling, the k sweep."""

import numpy as np
import pytest
import torch

from motionlab.models.trajevae.baselines import GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.evaluate import (
    borrowed_trajectories,
    complete,
    dlow_metrics,
    follow_error,
    given_joints_metrics,
    multimodal_futures,
    ratio_and_worst_step,
    summarise,
    sweep_given_joints,
    upsample_frames,
)
from motionlab.models.trajevae.masks import first_joints, joint_mask
from motionlab.models.trajevae.model import TrajeVAE, TrajeVAEConfig


def test_dlow_metrics_by_hand():
    windows = torch.zeros(2, 4, 6, dtype=torch.float64)
    windows[1] += 10.0  # far apart: each window is its own multimodal ground truth
    shifts = torch.tensor([0.5, -1.0, 2.0], dtype=torch.float64)
    samples = windows[:, None] + shifts[None, :, None, None]
    values = dlow_metrics(samples, windows, multimodal_futures(windows))
    per_frame = np.sqrt(6) * np.abs(shifts.numpy())  # L2 over the 6 channels of a frame
    assert values["ade"] == pytest.approx([per_frame.min()] * 2)
    assert values["fde"] == pytest.approx([per_frame.min()] * 2)
    assert values["mmade"] == pytest.approx(values["ade"])
    pairs = [abs(a - b) for i, a in enumerate(shifts.numpy()) for b in shifts.numpy()[i + 1 :]]
    assert values["apd"] == pytest.approx(
        [np.mean(pairs) * np.sqrt(3 * 6)] * 2
    )  # 3 future frames x 6 channels
    summary = summarise(values)
    assert summary["ade"][0] == pytest.approx(per_frame.min()) and summary["ade"][1] == pytest.approx(0.0)


def test_multimodal_futures_group_close_starts():
    windows = torch.zeros(3, 3, 6)
    windows[1, 0] += 0.01
    windows[2] += 5.0
    groups = multimodal_futures(windows, threshold=0.5)
    assert [g.shape[0] for g in groups] == [2, 2, 1]


def test_ratio_and_worst_step():
    ratio, worst = ratio_and_worst_step([2.0, 1.5, 1.53, 1.0])
    assert ratio == pytest.approx(0.5) and worst == pytest.approx(1.02)
    with pytest.raises(ValueError, match="positive"):
        ratio_and_worst_step([1.0, 0.0])


def test_borrowed_trajectories_start_at_the_own_joints():
    g = torch.Generator().manual_seed(0)
    windows = torch.randn(5, 6, 66, generator=g)
    mask = joint_mask(["right_foot", "left_wrist"])
    trajectories, donor, gap = borrowed_trajectories(windows, mask)
    assert trajectories.shape == (5, 5, 66) and donor.shape == gap.shape == (5,)
    assert (donor != torch.arange(5)).all()
    channels = mask.repeat_interleave(3)
    # motion relative to the start is the donor's; zeros elsewhere
    for i in range(5):
        j = int(donor[i])
        expected = windows[j, 1:, channels] - windows[j, 0, channels] + windows[i, 0, channels]
        torch.testing.assert_close(trajectories[i][:, channels], expected)
        assert gap[i].item() == pytest.approx(
            (windows[i, 0, channels] - windows[j, 0, channels]).norm().item(), rel=1e-5
        )
    assert torch.count_nonzero(trajectories[:, :, ~channels]) == 0
    with pytest.raises(ValueError, match="at least 2 windows"):
        borrowed_trajectories(windows[:1], mask)


def test_follow_error_is_the_mean_joint_distance():
    mask = joint_mask(["pelvis"])
    samples = torch.zeros(1, 2, 3, 66)
    samples[0, 1, 1:, 0] = 2.0  # the second sample's pelvis is 2 m off in x
    trajectories = torch.zeros(1, 2, 66)
    assert follow_error(samples, trajectories, mask) == pytest.approx([1.0])


def test_upsample_frames_interpolates_and_keeps_duration():
    x = torch.tensor([[0.0], [2.0], [3.0]])
    up = upsample_frames(x, 2)
    torch.testing.assert_close(up[:, 0], torch.tensor([0.0, 1.0, 2.0, 2.5, 3.0, 3.5]))
    assert upsample_frames(torch.zeros(4, 60, 66), 2).shape == (4, 120, 66)
    with pytest.raises(ValueError, match="factor"):
        upsample_frames(x, 0)


def test_sweep_runs_for_every_model_and_is_seeded():
    windows = torch.randn(4, 9, 66, generator=torch.Generator().manual_seed(1))
    model = TrajeVAE(TrajeVAEConfig(n_frames=9, width=8, latent_dim=3, dct_components=4, heads=2)).eval()
    table = sweep_given_joints(model, windows, ks=(0, 2), n_samples=3, seed=0)
    assert set(table) == {0, 2} and set(table[0]) == {"apd", "ade", "fde", "mmade", "mmfde"}
    assert table == sweep_given_joints(model, windows, ks=(0, 2), n_samples=3, seed=0)
    per_window = given_joints_metrics(model, windows, 2, n_samples=3, seed=0)
    assert per_window["apd"].shape == (4,)
    assert table[2]["apd"][0] == pytest.approx(float(per_window["apd"].mean()))
    gru = GRUCompletion(RecurrentConfig(n_frames=9, hidden=8)).eval()
    assert sweep_given_joints(gru, windows, ks=(4,), n_samples=3)[4]["apd"][0] == 0.0
    start, given = windows[:, 0], windows[:, 1:] * first_joints(4).repeat_interleave(3)
    full = complete(model, start, given, 2, torch.Generator().manual_seed(0))
    assert full.shape == (4, 2, 9, 66) and torch.equal(full[:, :, 0], start[:, None].expand(-1, 2, -1))
