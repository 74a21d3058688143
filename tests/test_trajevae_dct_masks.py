"""TrajeVAE's DCT (against scipy) and structured joint masks."""

import numpy as np
import pytest
import scipy.fft
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from motionlab.models.trajevae.dct import dct, dct_matrix, idct
from motionlab.models.trajevae.masks import (
    FULL_ORDER,
    KEEP_PROBABILITY,
    PAPER_ORDER,
    channel_mask,
    first_joints,
    given_trajectories,
    hidden_poses,
    joint_mask,
    sample_joint_masks,
)
from motionlab.skeleton import JOINT, JOINT_NAMES


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 70), d=st.integers(1, 5), seed=st.integers(0, 2**31 - 1))
def test_dct_matches_scipy_ortho(n, d, seed):
    x = np.random.default_rng(seed).normal(size=(2, n, d))
    ours = dct(torch.tensor(x), dim=-2).numpy()
    np.testing.assert_allclose(ours, scipy.fft.dct(x, type=2, norm="ortho", axis=-2), atol=1e-10)


def test_dct_matrix_is_orthonormal_and_idct_inverts():
    matrix = dct_matrix(59, dtype=torch.float64)
    np.testing.assert_allclose((matrix @ matrix.T).numpy(), np.eye(59), atol=1e-12)
    x = torch.randn(3, 59, 4, dtype=torch.float64)
    torch.testing.assert_close(idct(dct(x), 59), x)
    np.testing.assert_allclose(
        idct(dct(x), 59).numpy(), scipy.fft.idct(dct(x).numpy(), norm="ortho", axis=-2), atol=1e-10
    )


def test_truncated_dct_is_the_least_squares_low_pass():
    x = torch.randn(59, 3, dtype=torch.float64)
    basis = dct_matrix(59, 10, torch.float64)  # (10, 59) orthonormal rows
    low = idct(dct(x, dim=0, n_components=10), 59, dim=0)
    torch.testing.assert_close(low, basis.T @ (basis @ x))
    # the residual is orthogonal to the kept frequencies: no better approximation in their span
    torch.testing.assert_close(basis @ (x - low), torch.zeros(10, 3, dtype=torch.float64), atol=1e-12, rtol=0)


def test_dct_of_a_constant_has_only_the_first_component():
    coefficients = dct(torch.full((8, 1), 2.0, dtype=torch.float64), dim=0)
    assert coefficients[0, 0] == pytest.approx(2.0 * np.sqrt(8))
    assert torch.allclose(coefficients[1:], torch.zeros(7, 1, dtype=torch.float64), atol=1e-12)


def test_dct_errors():
    with pytest.raises(ValueError, match="n_components"):
        dct_matrix(5, 6)
    with pytest.raises(ValueError, match="NaN"):
        dct(torch.tensor([[1.0], [float("nan")]]))
    with pytest.raises(TypeError, match="floating"):
        dct(torch.ones(4, 2, dtype=torch.int64))
    with pytest.raises(ValueError, match="n_frames must be at least 1"):
        idct(torch.ones(3, 2), 0)
    with pytest.raises(TypeError, match="dct_matrix: n_frames must be an integer"):
        dct_matrix(4.0)


def test_sample_joint_masks_keep_rate_and_seed():
    masks = sample_joint_masks(20_000, torch.Generator().manual_seed(1))
    assert masks.shape == (20_000, 22) and masks.dtype == torch.bool
    rate = masks.double().mean().item()
    assert abs(rate - KEEP_PROBABILITY) < 4 * np.sqrt(
        KEEP_PROBABILITY * (1 - KEEP_PROBABILITY) / masks.numel()
    )
    again = sample_joint_masks(20_000, torch.Generator().manual_seed(1))
    assert torch.equal(masks, again)
    with pytest.raises(ValueError, match="keep_probability"):
        sample_joint_masks(2, torch.Generator(), keep_probability=1.5)


def test_orders_and_joint_masks():
    assert [JOINT[name] for name in PAPER_ORDER] == [11, 10, 21, 20]
    assert sorted(FULL_ORDER) == sorted(JOINT_NAMES) and FULL_ORDER[:4] == PAPER_ORDER
    assert not first_joints(0).any()
    assert torch.nonzero(first_joints(2)).flatten().tolist() == [10, 11]
    assert first_joints(22).all()
    assert torch.equal(joint_mask(["right_foot", 0]), joint_mask([11, "pelvis"]))
    with pytest.raises(ValueError, match="unknown joint"):
        joint_mask(["tail"])
    with pytest.raises(ValueError, match="first_joints: k must be in"):
        first_joints(23)
    with pytest.raises(TypeError, match="k must be an integer"):
        first_joints(True)


def test_trajectories_keep_given_joints_for_every_frame_and_zero_the_rest():
    poses = torch.randn(2, 7, 66)
    mask = torch.zeros(2, 22, dtype=torch.bool)
    mask[0, 11] = mask[1, [0, 21]] = True
    y = given_trajectories(poses, mask)
    hidden = hidden_poses(poses, mask)
    torch.testing.assert_close(y + hidden, poses)
    assert torch.equal(y[0, :, 33:36], poses[0, :, 33:36])
    assert torch.count_nonzero(y[0]) == 7 * 3
    assert torch.equal(y[1, :, :3], poses[1, :, :3]) and torch.equal(y[1, :, 63:], poses[1, :, 63:])
    assert torch.equal(hidden[1, :, :3], torch.zeros(7, 3))
    assert channel_mask(mask).shape == (2, 66)
    with pytest.raises(ValueError, match="channels"):
        given_trajectories(torch.randn(2, 7, 60), mask)
    with pytest.raises(TypeError, match="hidden_poses: mask must be a bool tensor"):
        hidden_poses(poses, mask.float())
