"""Validity penalties and projections (normalisation, Gram–Schmidt) against hand computations."""

import math

import pytest
import torch

from motionlab import geometry as g

DTYPES = [torch.float32, torch.float64]


def random_rotations(n: int, seed: int, dtype=torch.float64) -> torch.Tensor:
    q = torch.randn(n, 4, dtype=dtype, generator=torch.Generator().manual_seed(seed))
    return g.quat_to_matrix(q)


@pytest.mark.parametrize("dtype", DTYPES)
def test_penalties_vanish_on_valid_rotations(dtype):
    tolerance = 1e-10 if dtype == torch.float64 else 1e-5
    rotations = random_rotations(32, 0, dtype)
    assert g.orthogonality_penalty(rotations).max() < tolerance
    assert g.determinant_penalty(rotations).max() < tolerance
    q = torch.randn(32, 4, dtype=dtype, generator=torch.Generator().manual_seed(1))
    assert g.quat_norm_penalty(g.quat_normalize(q)).max() < tolerance


def test_penalties_match_hand_computations():
    eye = torch.eye(3, dtype=torch.float64)
    # 2I: M^T M - I = 3I, squared Frobenius norm 9 * 3 = 27; det 8 -> (8 - 1)^2 = 49
    assert g.orthogonality_penalty(2 * eye).item() == pytest.approx(27.0)
    assert g.determinant_penalty(2 * eye).item() == pytest.approx(49.0)
    # a reflection is orthogonal but has det -1: only the determinant penalty sees it
    reflection = torch.diag(torch.tensor([1.0, 1.0, -1.0], dtype=torch.float64))
    assert g.orthogonality_penalty(reflection).item() == 0.0
    assert g.determinant_penalty(reflection).item() == pytest.approx(4.0)
    # a shear [[1, s, 0], [0, 1, 0], [0, 0, 1]]: M^T M - I has entries s, s (off-diagonal) and s^2 -> 2 s^2 +
    # s^4
    shear = eye.clone()
    shear[0, 1] = 0.5
    assert g.orthogonality_penalty(shear).item() == pytest.approx(2 * 0.25 + 0.0625)
    assert g.determinant_penalty(shear).item() == pytest.approx(0.0)
    q = torch.tensor([[2.0, 0, 0, 0], [0.0, 0.3, 0.4, 0], [0.0, 0, 0, 0]], dtype=torch.float64)
    assert g.quat_norm_penalty(q).tolist() == pytest.approx([1.0, 0.25, 1.0])


@pytest.mark.parametrize("dtype", DTYPES)
def test_normalize_and_standardize(dtype):
    q = torch.tensor([[2.0, 0, 0, 0], [-1.0, 1.0, 1.0, 1.0], [0.0, 0.0, -3.0, 4.0]], dtype=dtype)
    unit = g.quat_normalize(q)
    assert torch.allclose(unit.norm(dim=-1), torch.ones(3, dtype=dtype))
    assert torch.allclose(unit[1], torch.tensor([-0.5, 0.5, 0.5, 0.5], dtype=dtype))
    standard = g.quat_standardize(unit)
    assert (standard[:, 0] >= 0).all()
    assert torch.allclose(g.quat_to_matrix(standard), g.quat_to_matrix(unit))
    identity = g.quat_identity((2, 5), dtype=dtype)
    assert identity.shape == (2, 5, 4) and identity.dtype == dtype
    assert torch.equal(g.quat_to_matrix(identity), torch.eye(3, dtype=dtype).expand(2, 5, 3, 3))


@pytest.mark.parametrize("dtype", DTYPES)
def test_gram_schmidt_of_nearly_parallel_columns_is_still_a_rotation(dtype):
    tolerance = 1e-12 if dtype == torch.float64 else 1e-5
    for angle in (1e-2, 1e-4, 1e-5):
        columns = (
            torch.tensor([[1.0, math.cos(angle)], [0.0, math.sin(angle)], [0.0, 0.0]], dtype=dtype) * 3.0
        )
        rotation = g.gram_schmidt(columns)
        assert (rotation.T @ rotation - torch.eye(3, dtype=dtype)).abs().max() < tolerance
        assert abs(torch.linalg.det(rotation).item() - 1) < tolerance
        assert torch.allclose(rotation[:, 0], torch.tensor([1.0, 0, 0], dtype=dtype))


def test_projections_fix_noisy_outputs_penalties_only_measure_them():
    rotations = random_rotations(64, 2)
    noisy = rotations + 0.05 * torch.randn(
        64, 3, 3, dtype=torch.float64, generator=torch.Generator().manual_seed(3)
    )
    before = g.orthogonality_penalty(noisy)
    assert (before > 0).all()
    projected = g.gram_schmidt(noisy)
    assert g.orthogonality_penalty(projected).max() < 1e-24
    assert g.determinant_penalty(projected).max() < 1e-24
    # the projection stays close to the clean rotation (first column exact in direction)
    assert g.matrix_geodesic(projected, rotations).max() < 0.3
