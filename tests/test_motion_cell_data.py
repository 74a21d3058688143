"""Pose vectors, the codec, motion words, output heads and training windows."""

import math

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation
from test_motion_cell_common import clips, codec, features

from motionlab.data.representations import root_start
from motionlab.geometry import quat_to_matrix
from motionlab.models.motion_cell.data import PoseCodec, WindowBatches
from motionlab.models.motion_cell.heads import OutputHead, assemble_pose, split_raw_pose
from motionlab.models.motion_cell.model import from_words, to_words
from motionlab.skeleton import body_skeleton


def test_codec_standardises_the_root_channels_only_and_round_trips():
    c = codec()
    x = features()
    poses = c.encode(x)
    torch.testing.assert_close(poses[..., :84], x[..., :84])
    root = poses[..., 84:].reshape(-1, 6)
    torch.testing.assert_close(root.mean(0), torch.zeros(6), atol=1e-5, rtol=0)
    torch.testing.assert_close(root.std(0, correction=0), torch.ones(6), atol=1e-4, rtol=0)
    torch.testing.assert_close(c.decode(poses), x, atol=1e-5, rtol=1e-5)


def test_codec_positions_reproduce_the_clips():
    data = clips()
    c = codec()
    start = root_start(torch.as_tensor(data.positions), torch.as_tensor(data.rotations))
    positions = c.positions(c.encode(features()), torch.as_tensor(data.body), start)
    torch.testing.assert_close(positions, torch.as_tensor(data.positions), atol=2e-4, rtol=0)


def test_local_positions_put_the_root_at_the_origin_and_follow_the_skeleton():
    c = codec()
    rest = c.encode(features())[:2, :1].clone()
    rest[..., :84] = torch.tensor([1.0, 0, 0, 0]).repeat(21)
    body = torch.tensor([0, 1])
    local = c.local_positions(rest, body)
    for i in range(2):
        np.testing.assert_allclose(local[i, 0].numpy(), body_skeleton(i).rest_positions(), atol=1e-6)


def test_codec_rejects_bad_input():
    c = codec()
    poses = c.encode(features())
    with pytest.raises(ValueError, match="body types"):
        c.positions(poses, torch.full((12,), 2))
    with pytest.raises(ValueError, match="body"):
        c.positions(poses, torch.zeros(3, dtype=torch.int64))
    with pytest.raises(ValueError, match="90"):
        c.encode(poses[..., :80])
    with pytest.raises(ValueError, match="offsets"):
        PoseCodec(np.zeros((2, 21, 3)), list(range(-1, 21)))
    with pytest.raises(RuntimeError, match="not fitted"):
        PoseCodec(clips().offsets, clips().parents.tolist()).encode(features())


def test_words_round_trip_and_layout():
    x = torch.arange(2 * 6 * 5, dtype=torch.float32).reshape(2, 6, 5)
    words = to_words(x, 3)
    assert words.shape == (2, 2, 15)
    torch.testing.assert_close(words[0, 1], x[0, 3:6].flatten())
    torch.testing.assert_close(from_words(words, 3), x)
    with pytest.raises(ValueError, match="words of 4"):
        to_words(x, 4)


def test_output_heads_map_zero_to_the_identity():
    for kind in ("quaternion", "matrix", "axis_angle"):
        head = OutputHead(kind)
        q = head.quaternions(head.identity_offset(torch.zeros(5, head.params_per_joint)))
        torch.testing.assert_close(q, torch.tensor([1.0, 0, 0, 0]).expand(5, 4))
    with pytest.raises(ValueError, match="kind"):
        OutputHead("euler")


def test_axis_angle_and_matrix_heads_agree_with_scipy():
    rng = np.random.default_rng(0)
    rotvec = rng.normal(size=(50, 3))
    q = OutputHead("axis_angle").quaternions(torch.tensor(rotvec))
    np.testing.assert_allclose(
        quat_to_matrix(q).numpy(), Rotation.from_rotvec(rotvec).as_matrix(), atol=1e-10
    )
    raw = rng.normal(size=(50, 3, 3))
    head = OutputHead("matrix")
    q = head.quaternions(torch.tensor(raw).flatten(-2))
    # Gram-Schmidt by hand: first column normalised, second made orthogonal, third their cross product
    c0 = raw[..., :, 0] / np.linalg.norm(raw[..., :, 0], axis=-1, keepdims=True)
    c1 = raw[..., :, 1] - (c0 * raw[..., :, 1]).sum(-1, keepdims=True) * c0
    c1 /= np.linalg.norm(c1, axis=-1, keepdims=True)
    expected = np.stack([c0, c1, np.cross(c0, c1)], axis=-1)
    np.testing.assert_allclose(quat_to_matrix(q).numpy(), expected, atol=1e-10)


def test_split_raw_pose_and_assemble():
    head = OutputHead("quaternion")
    raw = torch.randn(2, 3, head.raw_dim(22))
    params, root = split_raw_pose(raw, head, 22)
    assert params.shape == (2, 3, 21, 4) and root.shape == (2, 3, 6)
    torch.testing.assert_close(params[..., 0] - 1, raw[..., :84].unflatten(-1, (21, 4))[..., 0])
    assert assemble_pose(head.quaternions(params), root).shape == (2, 3, 90)
    with pytest.raises(ValueError, match="raw quaternion pose"):
        split_raw_pose(raw[..., :-1], head, 22)


def test_window_batches_are_random_windows_reproducible_by_generator():
    poses = codec().encode(features())
    data = clips()
    source = WindowBatches(poses, data.action, data.body, length=9)
    a = list(source(0, torch.Generator().manual_seed(1), 4))
    b = list(source(0, torch.Generator().manual_seed(1), 4))
    assert len(a) == 3 and a[0].poses.shape == (4, 9, 90)
    for x, y in zip(a, b):
        assert all(torch.equal(u, v) for u, v in zip(x, y))
    first = a[0]
    # every window is a contiguous piece of its clip
    for i in range(4):
        clip = int(torch.nonzero((poses[:, :, :84] == first.poses[i, :1, :84]).all(-1).any(-1))[0])
        assert int(first.action[i]) == int(data.action[clip])
    with pytest.raises(ValueError, match="length"):
        WindowBatches(poses, data.action, data.body, length=31)
    with pytest.raises(ValueError, match="fill a batch"):
        next(source(0, torch.Generator(), 13))


def test_window_batches_in_order_keep_every_clip():
    """``shuffle=False, drop_last=False`` (validation): every clip once, in its order, the last batch short;
    the window starts come from the generator, so a fixed one gives the same windows every time."""
    poses = codec().encode(features())
    data = clips()
    source = WindowBatches(poses, data.action, data.body, length=9, shuffle=False, drop_last=False)
    a = list(source(0, torch.Generator().manual_seed(1), 5))
    b = list(source(0, torch.Generator().manual_seed(1), 5))
    assert [len(x.action) for x in a] == [5, 5, 2] and a[-1].poses.shape == (2, 9, 90)
    assert torch.equal(torch.cat([x.action for x in a]), torch.as_tensor(data.action))
    assert torch.equal(torch.cat([x.body for x in a]), torch.as_tensor(data.body))
    for x, y in zip(a, b):
        assert all(torch.equal(u, v) for u, v in zip(x, y))
    assert len(list(source(0, torch.Generator(), 13))) == 1  # fewer clips than a batch: one short batch
    with pytest.raises(TypeError, match="shuffle must be a bool"):
        WindowBatches(poses, data.action, data.body, length=9, shuffle=0)


def test_pose_vectors_hold_unit_quaternions():
    norms = codec().split(codec().encode(features()))[0].norm(dim=-1)
    assert math.isclose(float(norms.min()), 1.0, abs_tol=1e-5) and math.isclose(
        float(norms.max()), 1.0, abs_tol=1e-5
    )
