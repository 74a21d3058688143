"""The capture noise pipeline and the denoising autoencoder."""

import pytest
import torch
from test_motion_cell_common import clips, codec, features

from motionlab.models.motion_cell.denoise import (
    DenoiserConfig,
    DenoisingAutoencoder,
    denoiser_loss,
    noisy_features,
)
from motionlab.models.motion_cell.losses import LossConfig
from motionlab.train import build_seeded


def _denoiser():
    return build_seeded(lambda: DenoisingAutoencoder(DenoiserConfig(channels=8, bottleneck=4), codec()), 0)


def test_noisy_features_are_seeded_and_close_to_the_clean_ones():
    data = clips()
    a = noisy_features(data.rotations, data.positions, 0)
    b = noisy_features(data.rotations, data.positions, 0)
    c = noisy_features(data.rotations, data.positions, 1)
    assert a.shape == features().shape
    assert torch.equal(a, b) and not torch.equal(a, c)
    clean_q, noisy_q = features()[..., :84], a[..., :84]
    assert 0 < float((clean_q - noisy_q).abs().mean()) < 0.05


def test_untrained_denoiser_starts_close_to_changing_nothing():
    model = _denoiser()
    noisy = codec().encode(noisy_features(clips().rotations, clips().positions, 0))
    out = model(noisy)
    quaternions, root = model.codec.split(noisy)
    unchanged = torch.cat([(quaternions / quaternions.norm(dim=-1, keepdim=True)).flatten(-2), root], dim=-1)
    assert float((out.poses - unchanged).detach().abs().max()) < 0.05
    torch.testing.assert_close(
        model.codec.split(out.poses)[0].norm(dim=-1), torch.ones(quaternions.shape[:-1])
    )
    torch.testing.assert_close(model.denoise(noisy), out.poses)


def test_denoiser_loss_is_small_on_clean_input_and_larger_on_noisy():
    model = _denoiser()
    clean = codec().encode(features())
    noisy = codec().encode(noisy_features(clips().rotations, clips().positions, 0))
    loss_fn = denoiser_loss(LossConfig())
    on_clean = float(loss_fn(model, (clean, clean), 0, {})["pose"].detach())
    terms = loss_fn(model, (noisy, clean), 0, {})
    assert on_clean < 0.5 * float(terms["pose"].detach())
    terms["loss"].backward()
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in model.parameters())


def test_capture_noise_spares_the_root_orientation():
    data = clips()
    noisy = noisy_features(data.rotations, data.positions, 3)
    clean = features()
    # yaw rate, pitch and roll come from the root orientation alone
    torch.testing.assert_close(noisy[..., -3:], clean[..., -3:], atol=1e-5, rtol=0)


def test_denoiser_rejects_bad_shapes_and_config():
    with pytest.raises(ValueError, match="90"):
        _denoiser()(torch.zeros(2, 10, 89))
    with pytest.raises(ValueError, match="kernel_size"):
        DenoiserConfig(kernel_size=4)
    with pytest.raises(ValueError, match="rng"):
        noisy_features(clips().rotations, clips().positions, -1)
