"""ODMO's data preparation: facing +x, the ODMO layout, frame stride, and the way back to joint positions."""

import math

import numpy as np
import pytest
import torch

from motionlab.data.augment import rotate_yaw
from motionlab.data.representations import heading_yaw
from motionlab.evaluation.benchmark import load_benchmark
from motionlab.models.odmo.data import face_forward, prepare, to_positions, upsample_frames


@pytest.fixture(scope="module")
def clips():
    test = load_benchmark().test
    return test.subset(np.arange(0, test.n_clips, max(1, test.n_clips // 12)))


def test_prepare_layout_and_origin(clips):
    data = prepare(clips, frame_stride=1)
    assert data.features.shape == (clips.n_clips, clips.n_frames, 66)
    assert torch.allclose(data.features[:, 0, -3:], torch.zeros(clips.n_clips, 3))
    assert torch.equal(data.end_point, data.features[:, -1, -3:])
    assert torch.equal(data.action, torch.as_tensor(clips.action)) and torch.equal(
        data.body, torch.as_tensor(clips.body)
    )
    every_third = prepare(clips, frame_stride=3, floor_clearance=data.floor_clearance)
    assert torch.equal(every_third.features, data.features[:, ::3]) and every_third.val is None
    with_val = prepare(clips, frame_stride=3, val=clips)  # validation clips: prepared alike
    assert torch.equal(with_val.val.features, every_third.features) and with_val.val.val is None
    assert with_val.val.floor_clearance == with_val.floor_clearance == data.floor_clearance


def test_face_forward_turns_every_clip_to_heading_zero(clips):
    positions, rotations = torch.as_tensor(clips.positions), torch.as_tensor(clips.rotations)
    turned = face_forward(positions, rotations)
    yaw = heading_yaw(rotations[:, 0, 0])
    _, turned_rotations = rotate_yaw(positions, rotations, -yaw)
    assert torch.allclose(heading_yaw(turned_rotations[:, 0, 0]), torch.zeros(clips.n_clips), atol=1e-5)
    # the turn keeps heights and distances
    assert torch.allclose(turned[..., 2], positions[..., 2])
    assert torch.allclose(
        (turned[:, :, 1] - turned[:, :, 0]).norm(dim=-1),
        (positions[:, :, 1] - positions[:, :, 0]).norm(dim=-1),
        atol=1e-5,
    )


def test_to_positions_inverts_prepare(clips):
    data = prepare(clips, frame_stride=1)
    positions = to_positions(data.features, 1, data.floor_clearance)
    expected = face_forward(torch.as_tensor(clips.positions), torch.as_tensor(clips.rotations))
    expected[..., :2] -= expected[:, :1, :1, :2].clone()
    offset = positions - expected
    assert torch.allclose(offset[..., :2], torch.zeros_like(offset[..., :2]), atol=1e-4)
    height_error = offset[..., 2].mean(dim=(1, 2))  # one vertical shift per clip: the start height
    assert torch.allclose(offset[..., 2], height_error[:, None, None].expand_as(offset[..., 2]), atol=1e-4)
    assert height_error.abs().mean() < 0.01


def test_upsample_frames_by_hand():
    x = torch.tensor([[0.0, 3.0, 9.0]])[..., None]
    assert torch.allclose(upsample_frames(x, 3)[0, :, 0], torch.tensor([0.0, 1, 2, 3, 5, 7, 9, 11, 13]))
    assert torch.equal(upsample_frames(x, 1), x)


def test_prepare_and_decode_reject_bad_input(clips):
    with pytest.raises(ValueError, match="frame_stride"):
        prepare(clips, frame_stride=0)
    with pytest.raises(ValueError, match="features"):
        to_positions(torch.zeros(2, 4, 65), 1, 0.02)
    with pytest.raises(ValueError, match="NaN"):
        to_positions(torch.full((1, 4, 66), math.nan), 1, 0.02)
