r"""Agreement between discovered modes and ground-truth sub-modes: mode homogeneity and the adjusted Rand
index.

Both compare two labelings of the same ``N`` items: ``discovered`` (for example clusters found in a
model's latent space) and ``truth`` (the data's sub-modes, or the sub-mode a classifier recognises in
each generated motion). Labels may be integers or strings; only which items share a label matters.

**Mode homogeneity** (after ODMO's evaluation of mode discovery): for each discovered mode, the fraction
of its items that belong to the most common true sub-mode within it; then the unweighted mean over
discovered modes. 1 means every discovered mode is pure. Splitting a true sub-mode over several discovered
modes is *not* penalised (pair it with the ARI, which is).

**Adjusted Rand index** (Hubert & Arabie 1985), from the contingency table :math:`n_{ij}` with row sums
:math:`a_i`, column sums :math:`b_j` and :math:`\binom{\cdot}{2}` the number of pairs:

.. math::
    \mathrm{ARI} = \frac{\sum_{ij}\binom{n_{ij}}{2} - E}
                        {\tfrac12\bigl[\sum_i\binom{a_i}{2} + \sum_j\binom{b_j}{2}\bigr] - E},
    \qquad E = \frac{\sum_i\binom{a_i}{2}\,\sum_j\binom{b_j}{2}}{\binom{N}{2}} .

1 for identical partitions (up to renaming), about 0 for independent ones, negative when worse than
chance. When the denominator is 0 both labelings are the same trivial partition (one group, or all
singletons) and the index is 1, as in scikit-learn.
"""

from __future__ import annotations

import numpy as np

from motionlab.validation import ArrayLike, as_labels


def contingency_table(discovered: ArrayLike, truth: ArrayLike) -> np.ndarray:
    """Counts ``(n_discovered_labels, n_true_labels)``: entry ``[i, j]`` is how many items have the i-th
    discovered label and the j-th true label (labels in sorted order)."""
    return _table(discovered, truth, "contingency_table")


def _table(discovered: ArrayLike, truth: ArrayLike, func: str) -> np.ndarray:
    found = as_labels(discovered, "discovered", func)
    real = as_labels(truth, "truth", func, length=found.shape[0])
    _, rows = np.unique(found, return_inverse=True)
    _, cols = np.unique(real, return_inverse=True)
    table = np.zeros((rows.max() + 1, cols.max() + 1), dtype=np.int64)
    np.add.at(table, (rows, cols), 1)
    return table


def mode_homogeneity(discovered: ArrayLike, truth: ArrayLike) -> float:
    """Mean over discovered modes of the share of the mode's items that fall in its majority true sub-mode.

    Args:
        discovered: discovered mode of each item ``(N,)``.
        truth: ground-truth (or classifier-recognised) sub-mode of each item ``(N,)``.
    """
    table = _table(discovered, truth, "mode_homogeneity")
    return float(np.mean(table.max(axis=1) / table.sum(axis=1)))


def _pairs(counts: np.ndarray) -> int:
    """Number of unordered pairs within each count, summed, as an exact Python integer."""
    return int((counts * (counts - 1) // 2).sum())


def adjusted_rand_index(discovered: ArrayLike, truth: ArrayLike) -> float:
    """Adjusted Rand index between two labelings ``(N,)`` of the same ``N >= 2`` items, in ``[-1, 1]``.

    Symmetric in its arguments and unchanged by renaming labels; agrees with
    ``sklearn.metrics.adjusted_rand_score``. The pair counts are exact integers: the formula above,
    multiplied through by :math:`2\binom{N}{2}`, is evaluated without round-off before one final division.
    """
    table = _table(discovered, truth, "adjusted_rand_index")
    n = int(table.sum())
    if n < 2:
        raise ValueError(f"adjusted_rand_index: needs at least 2 items to count pairs, got {n}")
    all_pairs = n * (n - 1) // 2
    together = _pairs(table)
    rows, cols = _pairs(table.sum(axis=1)), _pairs(table.sum(axis=0))
    numerator = 2 * (together * all_pairs - rows * cols)
    denominator = (rows + cols) * all_pairs - 2 * rows * cols
    if denominator == 0:
        return 1.0
    return numerator / denominator
