"""Flow layers: log-determinants against autograd, round trips, initialisation, bad input."""

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from motionlab.models.flows import (
    ActNorm,
    AffineCoupling,
    FlowSequence,
    GlowStep,
    InvertibleConv1x1,
    Squeeze,
    affine_forward,
    affine_inverse,
    autograd_logdet,
    logdet_error,
    perturb_parameters_,
    roundtrip_error,
)


def _layer(kind: str, channels: int, cond_channels: int) -> torch.nn.Module:
    return {
        "actnorm": lambda: ActNorm(channels),
        "invconv": lambda: InvertibleConv1x1(channels),
        "coupling": lambda: AffineCoupling(channels, cond_channels, hidden=8),
        "coupling_k1": lambda: AffineCoupling(channels, 0, hidden=8, kernel_size=1),
        "step": lambda: GlowStep(channels, cond_channels, hidden=8),
        "squeeze": lambda: Squeeze(),
    }[kind]()


KINDS = ["actnorm", "invconv", "coupling", "coupling_k1", "step", "squeeze"]


@pytest.mark.parametrize("kind", KINDS)
def test_logdet_matches_autograd_and_inverse_roundtrips(kind):
    torch.manual_seed(0)
    generator = torch.Generator().manual_seed(1)
    cond_channels = 0 if kind in ("actnorm", "invconv", "squeeze", "coupling_k1") else 2
    layer = perturb_parameters_(_layer(kind, 5, cond_channels).double(), 0.3, generator).eval()
    x = torch.randn(3, 5, 4, dtype=torch.float64, generator=generator)
    cond = torch.randn(3, 2, 4, dtype=torch.float64, generator=generator) if cond_channels else None
    assert logdet_error(layer, x, cond) < 1e-10
    assert roundtrip_error(layer, x, cond) < 1e-12
    y, logdet = layer(x, cond)
    assert logdet.shape == (3,)
    assert y.shape == ((3, 10, 2) if kind == "squeeze" else x.shape)


def test_float32_roundtrip_of_a_deep_sequence():
    torch.manual_seed(0)
    flow = FlowSequence(GlowStep(8, 3, hidden=16) for _ in range(6))
    perturb_parameters_(flow, 0.05, torch.Generator().manual_seed(2))
    flow.eval()
    x, cond = torch.randn(4, 8, 10), torch.randn(4, 3, 10)
    assert roundtrip_error(flow, x, cond) < 1e-5


def test_autograd_logdet_of_a_known_linear_map():
    # an InvertibleConv1x1 on one frame is the matrix W: log|det| must be slogdet(W) (numpy oracle)
    torch.manual_seed(3)
    conv = perturb_parameters_(InvertibleConv1x1(4).double(), 0.4, torch.Generator().manual_seed(0))
    expected = np.linalg.slogdet(conv.weight().detach().numpy())[1]
    x = torch.randn(2, 4, 3, dtype=torch.float64)
    np.testing.assert_allclose(autograd_logdet(conv, x).numpy(), 3 * expected, atol=1e-10)
    np.testing.assert_allclose(conv(x)[1].detach().numpy(), 3 * expected, atol=1e-10)


def test_actnorm_data_dependent_initialisation():
    x = (
        torch.randn(16, 3, 20) * torch.tensor([2.0, 0.5, 7.0])[:, None]
        + torch.tensor([1.0, -3.0, 0.0])[:, None]
    )
    layer = ActNorm(3)
    layer.eval()
    y, _ = layer(x)
    assert torch.equal(y, x), "eval mode before initialisation is the identity"
    layer.train()
    y, logdet = layer(x)
    assert bool(layer.initialized)
    flat = y.transpose(0, 1).reshape(3, -1)
    np.testing.assert_allclose(flat.mean(1).detach().numpy(), 0.0, atol=1e-5)
    np.testing.assert_allclose(flat.std(1, correction=0).detach().numpy(), 1.0, atol=1e-4)
    before = layer.bias.detach().clone()
    layer(x * 10)  # a second batch does not re-initialise
    assert torch.equal(layer.bias.detach(), before)
    state = layer.state_dict()
    fresh = ActNorm(3)
    fresh.load_state_dict(state)
    fresh.train()
    assert torch.allclose(fresh(x)[0], y)


def test_invconv_starts_orthogonal_and_caches_its_inverse():
    torch.manual_seed(0)
    conv = InvertibleConv1x1(6)
    w = conv.weight().detach().double()
    np.testing.assert_allclose((w @ w.T).numpy(), np.eye(6), atol=1e-6)
    assert abs(abs(np.linalg.det(w.numpy())) - 1) < 1e-6
    with torch.no_grad():
        first = conv.matrices()[1]
        assert conv.matrices()[1] is first  # reused while parameters are unchanged
        conv.log_s.add_(0.1)  # an in-place update (like an optimiser step) invalidates the cache
        second = conv.matrices()[1]
    assert second is not first
    np.testing.assert_allclose(
        (second.double() @ conv.weight().detach().double()).numpy(), np.eye(6), atol=1e-5
    )


def test_coupling_starts_as_a_fixed_contraction_and_keeps_first_half():
    layer = AffineCoupling(6, 2, hidden=8)
    x, cond = torch.randn(2, 6, 5), torch.randn(2, 2, 5)
    y, logdet = layer(x, cond)
    assert torch.equal(y[:, :3], x[:, :3])
    scale = 1 / (1 + math.exp(-2.0))
    np.testing.assert_allclose(y[:, 3:].detach().numpy(), x[:, 3:].numpy() * scale, rtol=1e-6)
    np.testing.assert_allclose(logdet.detach().numpy(), 3 * 5 * math.log(scale), rtol=1e-6)


@settings(max_examples=25, deadline=None)
@given(st.floats(-30, 30), st.floats(-5, 5), st.floats(-5, 5))
def test_affine_transform_is_invertible_and_its_logdet_is_log_scale(raw, shift, x):
    params = torch.tensor([[[shift]], [[raw]]], dtype=torch.float64).reshape(1, 2, 1)
    xb = torch.tensor([[[x]]], dtype=torch.float64)
    yb, logdet = affine_forward(xb, params)
    scale = 1 / (1 + math.exp(-(raw + 2.0)))
    assert abs(float(yb) - (x + shift) * scale) <= 1e-9 * (1 + abs(x + shift))
    assert abs(float(logdet) - math.log(scale)) < 1e-9
    assert abs(float(affine_inverse(yb, params)) - x) < 1e-6 * (1 + abs(x) + abs(shift)) / scale


@pytest.mark.parametrize(
    "bad, error, message",
    [
        (torch.randn(2, 5), ValueError, r"x must be 3-dimensional, got shape \(2, 5\)"),
        (torch.randn(2, 4, 3), ValueError, r"x must have shape \(\.\.\., 5, \*\), got \(2, 4, 3\)"),
        (
            torch.full((2, 5, 3), float("nan")),
            ValueError,
            r"x contains NaN or infinite values \(first at index \(0, 0, 0\)\)",
        ),
        (
            torch.ones(2, 5, 3, dtype=torch.int64),
            TypeError,
            "x must have a floating-point dtype, got torch.int64",
        ),
        ([[[0.0]]], TypeError, "x must be a torch.Tensor, got list"),
    ],
)
def test_bad_inputs_raise_clear_errors(bad, error, message):
    for layer in (ActNorm(5), InvertibleConv1x1(5), AffineCoupling(5)):
        name = type(layer).__name__
        with pytest.raises(error, match=f"{name}.forward: {message}"):
            layer(bad)
        with pytest.raises(error, match=f"{name}.inverse: {message.replace('x ', 'y ', 1)}"):
            layer.inverse(bad)


def test_conditioning_mismatches_raise():
    layer = AffineCoupling(4, cond_channels=2)
    x = torch.randn(2, 4, 3)
    with pytest.raises(ValueError, match="needs cond"):
        layer(x)
    with pytest.raises(ValueError, match="share batch and time"):
        layer(x, torch.randn(2, 2, 4))
    with pytest.raises(ValueError, match="without conditioning"):
        AffineCoupling(4)(x, torch.randn(2, 2, 3))
    with pytest.raises(ValueError, match="even length"):
        Squeeze()(torch.randn(1, 2, 3))
    with pytest.raises(ValueError):
        AffineCoupling(1)
    with pytest.raises(ValueError):
        AffineCoupling(4, kernel_size=2)
    with pytest.raises(TypeError):
        FlowSequence([torch.nn.Linear(2, 2)])
