"""Chapter 10's exercises: the solutions pass the mirror and bone-length checkers, and the checkers name
typical mistakes."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from motionlab.exercises import check_bone_length_variation, check_mirror
from motionlab.paths import REPO_ROOT


def _solutions():
    path = REPO_ROOT / "notebooks" / "solutions" / "10_real_motion_capture.py"
    spec = importlib.util.spec_from_file_location("solutions_10", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _solution():
    return _solutions().my_bone_length_variation


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


def test_the_mirror_solution_passes_and_an_unfinished_one_is_not_done() -> None:
    result = check_mirror(_solutions().my_mirror)
    assert result.passed, result

    def unfinished(positions, mirror):
        raise NotImplementedError("later")

    assert check_mirror(unfinished).status == "not done"


@pytest.mark.parametrize(
    "wrong, says",
    [
        (lambda x, m: x * np.array([1.0, -1.0, 1.0]), "swap left and right too"),
        (lambda x, m: x[:, list(m)], "reflect the positions too"),
        (lambda x, m: (x * np.array([-1.0, 1.0, 1.0]))[:, list(m)], "reflect across the x-z plane"),
        (lambda x, m: (x * np.array([1.0, 1.0, -1.0]))[:, list(m)], "not z"),
        (lambda x, m: (x * np.array([1.0, -1.0, 1.0]))[:, list(m)][:, :-1], "of the input's shape"),
        (lambda x, m: list(x), "NumPy array"),
    ],
)
def test_the_mirror_checker_names_the_mistake(wrong, says: str) -> None:
    result = check_mirror(wrong)
    assert result.status == "wrong" and says in result.message, result
