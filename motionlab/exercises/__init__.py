"""Checkers for the chapters' "your turn" exercises: the reader writes a key function, a checker says whether
it is right and, if not, *what* is wrong.

Each checker ``check_<name>(fn)`` runs the reader's ``fn`` on random and edge inputs against the package's own
implementation and returns a :class:`CheckResult`, which the notebook displays. It never raises for a wrong or
unfinished function: an exercise left as ``raise NotImplementedError(...)`` shows "not done yet", and the
chapter goes on with the package version. Solutions live outside the chapters, in
``notebooks/solutions/NN_*.py``; ``tests/test_exercises.py`` checks that each passes its checker, that each
skeleton in the chapters raises ``NotImplementedError`` with a message, and that each checker recognises
several typical mistakes.

Modules: :mod:`~motionlab.exercises.rotations` (chapter 01), :mod:`~motionlab.exercises.kinematics` and
:mod:`~motionlab.exercises.skating` (chapter 02), :mod:`~motionlab.exercises.vae` (chapters 03 and 08),
:mod:`~motionlab.exercises.vrnn` (chapter 04), :mod:`~motionlab.exercises.hierarchy` (its appendix),
:mod:`~motionlab.exercises.flows` (chapter 05), :mod:`~motionlab.exercises.autoregressive` (chapter 06),
:mod:`~motionlab.exercises.sequences` (chapters 07 and 08), :mod:`~motionlab.exercises.metrics` (chapter 09),
:mod:`~motionlab.exercises.mocap` (chapter 10), :mod:`~motionlab.exercises.diffusion` (chapter 11);
:mod:`~motionlab.exercises.checking` holds what they share.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Each public name with the module that holds it. A chapter imports only its own checkers' modules (and
#: what they check against): ``from motionlab.exercises import check_slerp`` loads the rotations module
#: alone, not the models of every chapter.
_MODULE_OF: dict[str, str] = {
    "CheckResult": "checking",
    "check_ancestral_step": "diffusion",
    "check_apd": "metrics",
    "check_bone_length_variation": "mocap",
    "check_chain_positions": "kinematics",
    "check_contrastive_loss": "sequences",
    "check_coupling_forward": "flows",
    "check_coupling_inverse": "flows",
    "check_covariance_prior": "vae",
    "check_dct_matrix": "sequences",
    "check_fid": "metrics",
    "check_foot_skating": "skating",
    "check_gaussian_kl": "vae",
    "check_given_trajectories": "sequences",
    "check_impact_weights": "hierarchy",
    "check_keep_mask": "autoregressive",
    "check_mirror": "mocap",
    "check_motion_cell_step": "vrnn",
    "check_negative_elbo": "vae",
    "check_prior_kl": "sequences",
    "check_quat_mul": "rotations",
    "check_reparameterize": "vae",
    "check_sample_loop": "autoregressive",
    "check_slerp": "rotations",
    "check_subtree_reach": "hierarchy",
}

__all__ = sorted(_MODULE_OF)


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_MODULE_OF[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MODULE_OF))
