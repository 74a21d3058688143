"""Inception Score against torch.distributions and known extremes; accuracy against scikit-learn."""

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import entropy
from sklearn.metrics import accuracy_score

from motionlab.metrics import inception_score, recognition_accuracy


def random_probs(seed: int, n: int, classes: int, sharpness: float = 1.0) -> np.ndarray:
    logits = np.random.default_rng(seed).normal(size=(n, classes)) * sharpness
    return torch.softmax(torch.from_numpy(logits), dim=1).numpy()


@pytest.mark.parametrize("classes", [2, 5, 12])
def test_confident_uniform_predictions_score_the_number_of_classes(classes):
    probs = np.tile(np.eye(classes), (3, 1))
    assert inception_score(probs) == pytest.approx(classes, rel=1e-12)


def test_identical_predictions_score_one():
    row = random_probs(0, 1, 6)
    assert inception_score(np.repeat(row, 40, axis=0)) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_matches_torch_kl_divergence(seed):
    probs = torch.from_numpy(random_probs(seed, 64, 7, sharpness=3.0))
    marginal = probs.mean(dim=0).expand_as(probs)
    kl = torch.distributions.kl_divergence(
        torch.distributions.Categorical(probs=probs), torch.distributions.Categorical(probs=marginal)
    )
    assert inception_score(probs) == pytest.approx(float(torch.exp(kl.mean())), rel=1e-6)


def test_splits_score_contiguous_chunks_with_their_own_marginals():
    probs = random_probs(4, 50, 5, sharpness=2.0)
    chunks = np.array_split(probs, 3)
    scores = [np.exp(np.mean([entropy(row, chunk.mean(axis=0)) for row in chunk])) for chunk in chunks]
    mean, std = inception_score(probs, splits=3)
    assert mean == pytest.approx(np.mean(scores), rel=1e-12)
    assert std == pytest.approx(np.std(scores), rel=1e-9)
    assert inception_score(probs, splits=1) == (pytest.approx(inception_score(probs), rel=1e-15), 0.0)


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    n=st.integers(1, 30),
    classes=st.integers(1, 8),
    sharpness=st.floats(0.0, 20.0),
)
def test_property_between_one_and_the_number_of_classes(seed, n, classes, sharpness):
    score = inception_score(random_probs(seed, n, classes, sharpness))
    assert 1.0 - 1e-9 <= score <= classes + 1e-9


def test_zero_probabilities_are_fine():
    probs = np.array([[1.0, 0.0, 0.0], [0.0, 0.5, 0.5]])
    # p(y) = (0.5, 0.25, 0.25); KL rows: log 2 and 0.5 log 2 + 0.5 log 2 = log 2.
    assert inception_score(probs) == pytest.approx(2.0, rel=1e-12)


@pytest.mark.parametrize(
    "probs, kwargs, match",
    [
        (np.array([[2.0, -1.0]]), {}, "probs must lie in"),
        (np.array([[0.2, 0.2]]), {}, "every row of probs must sum to 1"),
        (np.ones(3) / 3, {}, "probs must be 2-D"),
        (np.eye(3), {"splits": 4}, "splits .4. cannot exceed"),
        (np.eye(3), {"splits": 0}, "splits must be at least 1"),
    ],
)
def test_bad_inputs(probs, kwargs, match):
    with pytest.raises(ValueError, match=f"inception_score: {match}"):
        inception_score(probs, **kwargs)


def test_wrong_types_raise_type_error():
    with pytest.raises(TypeError, match=r"inception_score: splits must be an integer, got 1.5 \(float\)"):
        inception_score(np.eye(3), splits=1.5)
    with pytest.raises(TypeError, match="inception_score: splits must be an integer, got True"):
        inception_score(np.eye(3), splits=True)
    with pytest.raises(TypeError, match="recognition_accuracy: labels must be integer class indices"):
        recognition_accuracy(np.eye(3)[:2], ["a", "b"])


def test_accuracy_matches_sklearn_for_logits_and_probabilities():
    rng = np.random.default_rng(5)
    logits = rng.normal(size=(200, 6))
    labels = rng.integers(0, 6, size=200)
    expected = accuracy_score(labels, logits.argmax(axis=1))
    assert recognition_accuracy(logits, labels) == pytest.approx(expected)
    probs = torch.softmax(torch.from_numpy(logits), dim=1)
    assert recognition_accuracy(probs, torch.from_numpy(labels)) == pytest.approx(expected)


def test_accuracy_hand_case():
    scores = [[0.9, 0.1], [0.4, 0.6], [0.3, 0.7], [0.8, 0.2]]
    assert recognition_accuracy(scores, [0, 1, 0, 1]) == 0.5


@pytest.mark.parametrize(
    "labels, match",
    [
        ([0, 3], r"labels must lie in \[0, 3\)"),
        ([0], r"labels must have one entry per item \(2\), got 1"),
        ([0.5, 1.0], "labels must hold integer labels"),
    ],
)
def test_accuracy_bad_labels(labels, match):
    with pytest.raises(ValueError, match=f"recognition_accuracy: {match}"):
        recognition_accuracy(np.eye(3)[:2], labels)
