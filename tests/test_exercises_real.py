"""Chapter 10's exercise: the solution passes the bone-length checker, and the checker names typical
mistakes."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from motionlab.exercises import check_bone_length_variation
from motionlab.paths import REPO_ROOT


def _solution():
    path = REPO_ROOT / "notebooks" / "solutions" / "10_real_motion_capture.py"
    spec = importlib.util.spec_from_file_location("solutions_10", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.my_bone_length_variation


def _lengths(positions, parents):
    parents = np.asarray(parents)
    children = np.flatnonzero(parents >= 0)
    return np.linalg.norm(positions[:, children] - positions[:, parents[children]], axis=-1)


def test_the_solution_passes() -> None:
    result = check_bone_length_variation(_solution())
    assert result.passed, result


def test_an_unfinished_function_is_not_done() -> None:
    def unfinished(positions, parents):
        raise NotImplementedError("later")

    assert check_bone_length_variation(unfinished).status == "not done"


@pytest.mark.parametrize(
    "wrong, says",
    [
        (lambda x, p: _lengths(x, p).std(0, ddof=1) / _lengths(x, p).mean(0), "ddof=0"),
        (lambda x, p: _lengths(x, p).std(0), "divide the standard deviation by the mean"),
        (lambda x, p: _lengths(x, p).var(0) / _lengths(x, p).mean(0), "not the variance"),
        (lambda x, p: np.array(_lengths(x, p).std(0).mean()), "one number per bone"),
        (
            lambda x, p: np.concatenate([[0.0], _lengths(x, p).std(0) / _lengths(x, p).mean(0)]),
            "the root has no bone",
        ),
        (lambda x, p: list(_lengths(x, p).std(0) / _lengths(x, p).mean(0)), "NumPy array"),
        (lambda x, p: _lengths(x, p).std(0) / _lengths(x, p).mean(0) + 1e-3, "the values are wrong"),
    ],
)
def test_the_checker_names_the_mistake(wrong, says: str) -> None:
    result = check_bone_length_variation(wrong)
    assert result.status == "wrong" and says in result.message, result
