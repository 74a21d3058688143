r"""How well discovered modes group motions: ODMO's mode homogeneity, a majority purity, and the adjusted
Rand index.

**Mode homogeneity** (Lu et al. 2022, "ODMO", §4.3.1 and Table 3) works on the *motions* of each class,
grouped by the modes discovered for that class. With :math:`\mathcal G_c` the sequences of class ``c``,
:math:`\mathcal G(c, m)` those of its mode ``m`` and APD the average pairwise distance of whole flattened
sequences (:func:`motionlab.metrics.apd`),

.. math::
    \text{mode-APD}(\mathcal G_c) = \frac{1}{|\mathcal G_c|} \sum_m |\mathcal G(c, m)|\,
        \mathrm{APD}(\mathcal G(c, m)), \qquad
    \text{mode-homogeneity} = 100 \cdot \frac{1}{|C|} \sum_c
        \frac{\mathrm{APD}(\mathcal G_c) - \text{mode-APD}(\mathcal G_c)}{\mathrm{APD}(\mathcal G_c)} .

It is the percentage by which the modes lower the spread of the class's motions: 0 for one mode per class
(the paper's "real motions" row), higher when each mode holds more similar motions. A mode holding a single
sequence has no pairs; it counts with APD 0, as in the authors' code. The paper computes it on the *real*
clips, grouped by the modes discovered in a model's code space.

**Mode purity** (ours, not ODMO's) compares two labelings of the same ``N`` items: ``discovered`` (for
example the mode each generated clip was drawn from) and ``truth`` (the sub-mode, or style, a classifier
recognises in it). For each discovered mode, the share of its items in the most common true sub-mode; then
the unweighted mean over discovered modes. 1 means every discovered mode is pure. Splitting a true sub-mode
over several discovered modes is *not* penalised (pair it with the ARI, which is).

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

from motionlab.validation import ArrayLike, as_float_array, as_labels


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


def mode_purity(discovered: ArrayLike, truth: ArrayLike) -> float:
    """Mean over discovered modes of the share of the mode's items that fall in its majority true sub-mode.

    Args:
        discovered: discovered mode of each item ``(N,)``.
        truth: ground-truth (or classifier-recognised) sub-mode of each item ``(N,)``.
    """
    table = _table(discovered, truth, "mode_purity")
    return float(np.mean(table.max(axis=1) / table.sum(axis=1)))


def _spread(flat: np.ndarray) -> float:
    """APD of the rows of ``flat``; 0 for a single row (no pairs)."""
    from scipy.spatial.distance import pdist  # scipy.spatial costs 0.2 s to import: on first use

    return float(pdist(flat).mean()) if flat.shape[0] > 1 else 0.0


def mode_homogeneity(sequences: ArrayLike, classes: ArrayLike, modes: ArrayLike) -> float:
    """ODMO's mode homogeneity (Table 3), in per cent: how much the modes lower each class's APD, averaged
    over classes.

    Args:
        sequences: ``(N, T, D)`` (any trailing layout), one motion per row, e.g. real clips.
        classes: class of each sequence ``(N,)``; every class needs at least 2 sequences and a non-zero APD.
        modes: mode of each sequence ``(N,)``; only which sequences of a class share a label matters.
    """
    func = "mode_homogeneity"
    x = as_float_array(sequences, "sequences", func, min_ndim=2, layout="(N, T, D)")
    flat = x.reshape(x.shape[0], -1)
    found = as_labels(classes, "classes", func, length=x.shape[0])
    mode = as_labels(modes, "modes", func, length=x.shape[0])
    decrease = []
    for label in np.unique(found):
        members = found == label
        if members.sum() < 2:
            raise ValueError(f"{func}: class {label.item()!r} has 1 sequence; APD needs at least 2")
        whole = _spread(flat[members])
        if whole == 0.0:
            raise ValueError(f"{func}: the sequences of class {label.item()!r} are identical (APD 0)")
        within = (
            sum(
                (mode[members] == k).sum() * _spread(flat[members][mode[members] == k])
                for k in np.unique(mode[members])
            )
            / members.sum()
        )
        decrease.append((whole - within) / whole)
    return float(100.0 * np.mean(decrease))


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
