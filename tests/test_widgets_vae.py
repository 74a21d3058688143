"""Chapter 03's widget callbacks and the VAE data helpers (poses, clip windows and back to positions)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import torch  # noqa: E402

from motionlab.data.synthetic import generate  # noqa: E402
from motionlab.models.vae.data import clip_windows, pose_features, pose_to_positions  # noqa: E402
from motionlab.models.vae.model import MLPVAE, VAEConfig  # noqa: E402
from motionlab.widgets.vae import decode_clip, prior_code, show_cvae_sample, show_latent_interpolation  # noqa: E402

LENGTH = 20


@pytest.fixture(scope="module")
def clips():
    return generate(0, 1, seconds=1.0)  # 12 clips of 30 frames, one per style mode


@pytest.fixture(scope="module")
def codec_and_windows(clips):
    codec, train, (other,) = clip_windows(clips, (clips,), LENGTH, 10)
    return codec, train, other


def _pairwise(positions: np.ndarray) -> np.ndarray:
    return np.linalg.norm(positions[..., :, None, :] - positions[..., None, :, :], axis=-1)


def _same_up_to_horizontal_motion(a: np.ndarray, b: np.ndarray) -> None:
    """a and b (..., 22, 3) differ by a turn about z and a horizontal shift: same heights, same distances."""
    np.testing.assert_allclose(a[..., 2], b[..., 2], atol=1e-4)
    np.testing.assert_allclose(_pairwise(a), _pairwise(b), atol=1e-4)


def test_pose_round_trip_is_a_rigid_horizontal_move(clips):
    poses = pose_features(clips, every=7)
    positions = pose_to_positions(poses).numpy()
    original = np.asarray(clips.positions)[:, ::7].reshape(-1, 22, 3)
    assert poses.shape == (original.shape[0], 64)
    _same_up_to_horizontal_motion(positions, original)
    np.testing.assert_allclose(positions[:, 0, :2], 0.0, atol=1e-6)  # root above the origin


def test_clip_codec_round_trip(clips, codec_and_windows):
    codec, train, other = codec_and_windows
    assert train.features.shape == (12 * 2, LENGTH, 67)
    assert torch.allclose(train.features.reshape(-1, 67).mean(0), torch.zeros(67), atol=1e-4)
    assert torch.allclose(train.features, other.features)  # same clips, train statistics
    positions = codec.to_positions(train.features).numpy()
    original = np.stack(
        [np.asarray(clips.positions)[c, s : s + LENGTH] for c, s in zip(train.clip, train.start)]
    )
    # a window is placed at the origin facing +x: the same motion moved rigidly (one move for the whole
    # window)
    np.testing.assert_allclose(positions[..., 2], original[..., 2], atol=1e-4)
    flat = lambda p: p.reshape(p.shape[0], -1, 3)  # noqa: E731
    np.testing.assert_allclose(_pairwise(flat(positions)), _pairwise(flat(original)), atol=1e-3)
    with pytest.raises(
        ValueError, match=r"ClipCodec.to_positions: features must have shape \(\.\.\., 20, 67\)"
    ):
        codec.to_positions(torch.zeros(2, LENGTH + 1, 67))


def _cvae() -> MLPVAE:
    torch.manual_seed(0)
    return MLPVAE(VAEConfig((LENGTH, 67), latent_dim=4, hidden=16, n_classes=6))


def _joint_lines(fig):
    """The joint markers (Line3D with markers only) of each panel, as (x, y, z) arrays."""
    lines = []
    for ax in fig.axes:
        joints = [line for line in ax.get_lines() if line.get_linestyle() == "None"]
        lines.append(np.stack(joints[0].get_data_3d(), axis=-1))
    return lines


def test_show_cvae_sample_draws_the_decoded_clip(clips, codec_and_windows):
    codec, _, _ = codec_and_windows
    model = _cvae()
    parents = clips.parents
    expected = codec.to_positions(model.decode(prior_code(model, 3)[None], torch.tensor([2])).detach())[
        0
    ].numpy()
    fig = show_cvae_sample(model, codec, parents, action=2, seed=3, action_names=list("abcdef"), n_frames=3)
    try:
        assert len(fig.axes) == 3
        panels = _joint_lines(fig)
        np.testing.assert_allclose(panels[0], expected[0], atol=1e-5)
        np.testing.assert_allclose(panels[-1], expected[-1], atol=1e-5)
        assert "'c'" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_interpolation_endpoints_are_the_two_samples(clips, codec_and_windows):
    codec, _, _ = codec_and_windows
    model = _cvae()
    parents = clips.parents
    for w, seed in ((0.0, 4), (1.0, 9)):
        fig = show_latent_interpolation(model, codec, parents, action=1, seed_a=4, seed_b=9, w=w, n_frames=2)
        try:
            expected = decode_clip(model, codec, prior_code(model, seed), 1).numpy()
            np.testing.assert_allclose(_joint_lines(fig)[0], expected[0], atol=1e-5)
        finally:
            plt.close(fig)
    assert torch.equal(prior_code(model, 5), prior_code(model, 5))


def test_widget_bad_inputs(clips, codec_and_windows):
    codec, _, _ = codec_and_windows
    model = _cvae()
    with pytest.raises(ValueError, match=r"decode_clip: action must be in \[0, 5\]"):
        decode_clip(model, codec, torch.zeros(4), 6)
    with pytest.raises(ValueError, match=r"show_latent_interpolation: w must be in \[0, 1\]"):
        show_latent_interpolation(model, codec, clips.parents, 0, 1, 2, w=1.5)
    with pytest.raises(ValueError, match="prior_code: seed must be at least 0"):
        prior_code(model, -1)
    with pytest.raises(ValueError, match="pose_features: every must be at least 1"):
        pose_features(clips, every=0)
    with pytest.raises(ValueError, match=r"pose_to_positions: poses must have shape \(\.\.\., 64\)"):
        pose_to_positions(torch.zeros(3, 63))
