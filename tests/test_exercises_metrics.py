"""Chapter 09's checkers: the worked solutions pass, typical mistakes are named, unfinished code is "not
done"."""

from __future__ import annotations

import importlib.util

import numpy as np
import scipy.linalg
import torch

from motionlab.exercises.metrics import check_apd, check_fid
from motionlab.paths import REPO_ROOT

SOLUTIONS = REPO_ROOT / "notebooks" / "solutions" / "09_evaluating_and_comparing.py"


def solutions():
    spec = importlib.util.spec_from_file_location("solutions_09", SOLUTIONS)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_solutions_pass() -> None:
    assert check_apd(solutions().my_apd).passed
    assert check_fid(solutions().my_fid).passed


def _flat(samples):
    return samples.reshape(samples.shape[0], -1)


def test_apd_mistakes_are_named() -> None:
    def with_diagonal(samples):
        flat = _flat(samples)
        return torch.cdist(flat, flat).mean()

    def squared(samples):
        flat = _flat(samples)
        k = flat.shape[0]
        return (torch.cdist(flat, flat) ** 2).sum() / (k * (k - 1))

    def per_frame(samples):
        k = samples.shape[0]
        d = (samples[:, None] - samples[None]).norm(dim=-1).mean(-1)
        return d.sum() / (k * (k - 1))

    for fn, words in ((with_diagonal, "K²"), (squared, "squared"), (per_frame, "per-frame")):
        result = check_apd(fn)
        assert result.status == "wrong" and words in result.message, result
    assert check_apd(lambda samples: [1.0]).status == "wrong"


def test_fid_mistakes_are_named() -> None:
    def parts(a, b):
        x, y = a.numpy(), b.numpy()
        return x.mean(0), y.mean(0), np.cov(x, rowvar=False), np.cov(y, rowvar=False)

    def means_only(a, b):
        m1, m2, _, _ = parts(a, b)
        return float(((m1 - m2) ** 2).sum())

    def square_root(a, b):
        return solutions().my_fid(a, b) ** 0.5

    def biased(a, b):
        m1, m2 = a.numpy().mean(0), b.numpy().mean(0)
        s1, s2 = np.cov(a.numpy(), rowvar=False, bias=True), np.cov(b.numpy(), rowvar=False, bias=True)
        cross = scipy.linalg.sqrtm(s1 @ s2).real
        return float(((m1 - m2) ** 2).sum() + np.trace(s1 + s2 - 2 * cross))

    for fn, words in ((means_only, "only the means"), (square_root, "square root"), (biased, "N - 1")):
        result = check_fid(fn)
        assert result.status == "wrong" and words in result.message, result


def test_unfinished_is_not_done() -> None:
    def my_fid(a, b):
        raise NotImplementedError("fit a Gaussian to each set")

    assert check_fid(my_fid).status == "not done"
