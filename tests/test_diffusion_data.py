"""MDM's data: the 6-D rotation representation there and back, forward kinematics against the benchmark's
own joint positions, the preparation of benchmark clips, and the editing masks."""

import numpy as np
import pytest
import torch

from motionlab.data.representations import heading_yaw
from motionlab.evaluation.benchmark import load_benchmark
from motionlab.geometry import quat_geodesic
from motionlab.models.diffusion.data import (
    face_origin,
    from_mdm,
    joint_positions,
    known_mask,
    n_features,
    prepare,
    to_mdm,
    to_positions,
)


@pytest.fixture(scope="module")
def clips():
    test = load_benchmark().test
    return test.subset(np.arange(0, test.n_clips, max(1, test.n_clips // 12)))


def test_round_trip_keeps_every_rotation_and_the_root(clips):
    rotations = torch.as_tensor(clips.rotations, dtype=torch.float64)
    root = torch.as_tensor(clips.positions[:, :, 0], dtype=torch.float64)
    features = to_mdm(rotations, root)
    assert features.shape == clips.rotations.shape[:2] + (n_features(22),) == (clips.n_clips, 120, 135)
    back, back_root = from_mdm(features)
    assert torch.allclose(back_root, root)
    assert quat_geodesic(back, rotations).max() < 1e-6  # the same rotations (q and -q alike)


def test_forward_kinematics_with_the_clips_own_bodies_gives_their_positions(clips):
    positions, rotations = face_origin(
        torch.as_tensor(clips.positions, dtype=torch.float64),
        torch.as_tensor(clips.rotations, dtype=torch.float64),
    )
    features = to_mdm(rotations, positions[..., 0, :])
    rebuilt = joint_positions(features, clips.clip_offsets())
    assert torch.allclose(rebuilt, positions, atol=1e-5)
    # the average body, which the model uses, is close but not exact: the two body types differ
    average = joint_positions(features)
    error = (average - positions).norm(dim=-1).mean()
    assert 1e-4 < error < 0.1


def test_prepare_faces_x_from_the_origin_and_keeps_every_second_frame(clips):
    data = prepare(clips)
    assert data.features.shape == (clips.n_clips, 60, 135) and data.features.dtype == torch.float32
    assert data.frame_stride == 2 and len(data) == clips.n_clips
    assert torch.equal(data.action, torch.as_tensor(clips.action))
    rotations, root = from_mdm(data.features.double())
    assert torch.allclose(
        heading_yaw(rotations[:, 0, 0]), torch.zeros(clips.n_clips, dtype=torch.float64), atol=1e-5
    )
    assert torch.allclose(root[:, 0, :2], torch.zeros(clips.n_clips, 2, dtype=torch.float64), atol=1e-5)
    assert torch.allclose(
        root[:, :, 2], torch.as_tensor(clips.positions[:, ::2, 0, 2], dtype=torch.float64), atol=1e-5
    )
    every_frame = prepare(clips, frame_stride=1)
    assert torch.equal(every_frame.features[:, ::2], data.features)


def test_to_positions_interpolates_back_to_the_data_rate(clips):
    data = prepare(clips)
    positions = to_positions(data.features, data.frame_stride, clips.clip_offsets())
    faced, _ = face_origin(torch.as_tensor(clips.positions), torch.as_tensor(clips.rotations))
    assert positions.shape == (clips.n_clips, 120, 22, 3)
    assert torch.allclose(positions[:, ::2], faced[:, ::2].float(), atol=1e-4)
    # the frames between are interpolated: within a few centimetres of the real ones
    assert (positions[:, 1:-1:2] - faced[:, 1:-1:2].float()).norm(dim=-1).mean() < 0.02


def test_batches_serve_features_and_actions(clips):
    data = prepare(clips)
    features, action = next(iter(data.batches()(0, torch.Generator().manual_seed(0), 4)))
    assert features.shape == (4, 60, 135) and action.shape == (4,)


def test_known_mask_marks_frames_joints_and_root():
    mask = known_mask(10, 3, frames=[0, 1, 9], joints=[2], root_position=True)
    assert mask.shape == (10, 21) and mask.dtype == torch.bool
    assert mask[[0, 1, 9]].all()
    assert mask[:, 12:18].all() and mask[:, 18:].all()
    assert not mask[2:9, :12].any()
    assert not known_mask(4, 2).any()


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda c: prepare(c, frame_stride=0), ValueError, "frame_stride"),
        (lambda c: prepare(c, frame_stride=100), ValueError, "too short"),
        (lambda c: to_mdm(torch.zeros(2, 3, 4), torch.zeros(2, 2, 3)), ValueError, "share"),
        (lambda c: from_mdm(torch.zeros(2, 3, 10)), ValueError, "6 J"),
        (lambda c: from_mdm(np.zeros((2, 3, 135))), TypeError, "features"),
        (lambda c: joint_positions(torch.zeros(1, 2, n_features(5))), ValueError, "22 joints"),
        (lambda c: to_positions(torch.zeros(1, 2, 135), 0), ValueError, "frame_stride"),
        (lambda c: known_mask(5, 2, frames=[5]), ValueError, "frames"),
        (lambda c: known_mask(5, 2, joints=[-1]), ValueError, "joints"),
        (lambda c: known_mask(5, 2, root_position=1), TypeError, "root_position"),
    ],
)
def test_bad_inputs_raise_clear_errors(clips, call, error, match):
    with pytest.raises(error, match=match):
        call(clips)
