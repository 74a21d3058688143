"""Adjusted Rand index against scikit-learn; mode purity against a counting oracle; ODMO's mode homogeneity
against a hand computation."""

from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.metrics import adjusted_rand_score
from sklearn.metrics.cluster import contingency_matrix

from motionlab.metrics import adjusted_rand_index, contingency_table, mode_homogeneity, mode_purity

labelings = st.integers(2, 60).flatmap(
    lambda n: st.tuples(*[st.lists(st.integers(0, 5), min_size=n, max_size=n)] * 2)
)


def test_ari_hand_value():
    # Rows {0,1},{2,3}; columns {0,2},{1,3}: no pair together in both; E = 2*2/6, max = 2 -> (0 - 2/3)/(2 -
    # 2/3)
    assert adjusted_rand_index([0, 0, 1, 1], [0, 1, 0, 1]) == pytest.approx(-0.5)


@pytest.mark.parametrize(
    "discovered, truth",
    [
        ([0, 0, 0, 0], [1, 1, 1, 1]),  # both one group
        ([0, 1, 2, 3], [3, 2, 1, 0]),  # both all singletons
        ([0, 0, 0, 0], [0, 1, 2, 3]),
        (["a", "a", "b"], ["x", "y", "y"]),
        ([0, 1], [0, 0]),
    ],
)
def test_ari_edge_cases_match_sklearn(discovered, truth):
    assert adjusted_rand_index(discovered, truth) == pytest.approx(
        adjusted_rand_score(truth, discovered), abs=1e-12
    )


@settings(max_examples=60, deadline=None)
@given(labelings)
def test_property_ari_matches_sklearn(pair):
    discovered, truth = pair
    assert adjusted_rand_index(discovered, truth) == pytest.approx(
        adjusted_rand_score(truth, discovered), abs=1e-12
    )


@settings(max_examples=30, deadline=None)
@given(labelings, st.permutations(range(6)))
def test_property_ari_invariant_to_renaming_and_symmetric(pair, permutation):
    discovered, truth = pair
    renamed = [f"mode{permutation[label]}" for label in discovered]
    value = adjusted_rand_index(discovered, truth)
    assert adjusted_rand_index(renamed, truth) == pytest.approx(value, abs=1e-12)
    assert adjusted_rand_index(truth, discovered) == pytest.approx(value, abs=1e-12)


def test_ari_large_sets_are_exact():
    rng = np.random.default_rng(0)
    truth = rng.integers(0, 4, size=200_000)
    noisy = np.where(rng.random(200_000) < 0.8, truth, rng.integers(0, 4, size=200_000))
    assert adjusted_rand_index(noisy, truth) == pytest.approx(adjusted_rand_score(truth, noisy), abs=1e-12)
    assert adjusted_rand_index(truth, truth) == 1.0


def counting_purity(discovered, truth) -> float:
    shares = []
    for mode in set(discovered):
        members = Counter(t for d, t in zip(discovered, truth) if d == mode)
        shares.append(max(members.values()) / sum(members.values()))
    return sum(shares) / len(shares)


def test_mode_purity_hand_value():
    # mode 0 holds a, a, b (2/3 majority); mode 1 holds c, c (pure): mean 5/6
    assert mode_purity([0, 0, 0, 1, 1], ["a", "a", "b", "c", "c"]) == pytest.approx(5 / 6)


def test_mode_purity_pure_modes_and_split_sub_modes():
    assert mode_purity([0, 0, 1, 1], [5, 5, 7, 7]) == 1.0
    assert mode_purity([0, 1, 2, 3], [5, 5, 7, 7]) == 1.0  # splitting is not penalised (the ARI is)
    assert mode_purity([0, 0, 0, 0], [5, 5, 7, 7]) == 0.5


@settings(max_examples=30, deadline=None)
@given(labelings)
def test_property_mode_purity_matches_counting(pair):
    discovered, truth = pair
    assert mode_purity(discovered, truth) == pytest.approx(counting_purity(discovered, truth), rel=1e-12)


def test_mode_homogeneity_hand_value():
    # class 0: four 1-D "sequences" 0, 1, 10, 11 in modes {0, 1} and {10, 11}
    #   APD(G_0) = mean(1, 10, 11, 9, 10, 1) = 42 / 6 = 7; mode-APD = (2 * 1 + 2 * 1) / 4 = 1 -> (7 - 1) / 7
    # class 1: three sequences 0, 2, 4 in modes {0, 2} and {4} (a single sequence counts with APD 0)
    #   APD(G_1) = mean(2, 4, 2) = 8 / 3; mode-APD = (2 * 2 + 1 * 0) / 3 = 4 / 3 -> 1 / 2
    sequences = np.array([0.0, 1.0, 10.0, 11.0, 0.0, 2.0, 4.0])[:, None, None]
    classes = [0, 0, 0, 0, 1, 1, 1]
    modes = ["a", "a", "b", "b", "a", "a", "c"]
    expected = 100 * ((7 - 1) / 7 + 0.5) / 2
    assert mode_homogeneity(sequences, classes, modes) == pytest.approx(expected)


def test_mode_homogeneity_is_zero_for_one_mode_and_uses_whole_sequence_distances():
    rng = np.random.default_rng(0)
    sequences = rng.normal(size=(12, 4, 3))
    classes = np.repeat([0, 1], 6)
    assert mode_homogeneity(sequences, classes, np.zeros(12)) == 0.0  # the paper's "real motions" row
    # distances are between whole flattened sequences (sqrt of the sum over frames and coordinates)
    flat = sequences.reshape(12, -1)
    modes = np.tile([0, 0, 0, 1, 1, 1], 2)

    def spread(rows):
        return np.mean([np.linalg.norm(a - b) for i, a in enumerate(rows) for b in rows[i + 1 :]])

    expected = np.mean(
        [
            1
            - np.mean([spread(flat[(classes == c) & (modes == k)]) for k in (0, 1)])
            / spread(flat[classes == c])
            for c in (0, 1)
        ]
    )
    assert mode_homogeneity(sequences, classes, modes) == pytest.approx(100 * expected)


def test_contingency_table_matches_sklearn():
    rng = np.random.default_rng(1)
    discovered, truth = rng.integers(0, 4, size=100), rng.integers(2, 7, size=100)
    np.testing.assert_array_equal(contingency_table(discovered, truth), contingency_matrix(discovered, truth))


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: adjusted_rand_index([0], [0]), "adjusted_rand_index: needs at least 2 items"),
        (
            lambda: adjusted_rand_index([0, 1, 1], [0, 1]),
            r"adjusted_rand_index: truth must have one entry per item",
        ),
        (lambda: mode_purity([], []), "mode_purity: discovered is empty"),
        (lambda: mode_purity([[0, 1]], [0, 1]), r"mode_purity: discovered must be 1-D \(N,\)"),
        (lambda: mode_purity([0.0, np.nan], [0, 1]), "mode_purity: discovered contains NaN"),
        (lambda: mode_homogeneity(np.eye(3), [0, 0, 1], [0, 0, 0]), "mode_homogeneity: class 1 has 1"),
        (
            lambda: mode_homogeneity(np.zeros((2, 2)), [0, 0], [0, 1]),
            "mode_homogeneity: the sequences of class 0",
        ),
    ],
)
def test_bad_inputs(call, match):
    with pytest.raises(ValueError, match=match):
        call()
