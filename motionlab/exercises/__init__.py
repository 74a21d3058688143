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

from motionlab.lazy import lazy_exports

#: Each public name with the module that holds it. A chapter imports only its own checkers' modules (and
#: what they check against): ``from motionlab.exercises import check_slerp`` loads the rotations module
#: alone, not the models of every chapter.
_EXPORTS: dict[str, str] = {
    "CheckResult": "motionlab.exercises.checking",
    "check_ancestral_step": "motionlab.exercises.diffusion",
    "check_apd": "motionlab.exercises.metrics",
    "check_bone_length_variation": "motionlab.exercises.mocap",
    "check_chain_positions": "motionlab.exercises.kinematics",
    "check_contrastive_loss": "motionlab.exercises.sequences",
    "check_coupling_forward": "motionlab.exercises.flows",
    "check_coupling_inverse": "motionlab.exercises.flows",
    "check_covariance_prior": "motionlab.exercises.vae",
    "check_dct_matrix": "motionlab.exercises.sequences",
    "check_fid": "motionlab.exercises.metrics",
    "check_foot_skating": "motionlab.exercises.skating",
    "check_gaussian_kl": "motionlab.exercises.vae",
    "check_given_trajectories": "motionlab.exercises.sequences",
    "check_impact_weights": "motionlab.exercises.hierarchy",
    "check_keep_mask": "motionlab.exercises.autoregressive",
    "check_mirror": "motionlab.exercises.mocap",
    "check_motion_cell_step": "motionlab.exercises.vrnn",
    "check_negative_elbo": "motionlab.exercises.vae",
    "check_prior_kl": "motionlab.exercises.sequences",
    "check_quat_mul": "motionlab.exercises.rotations",
    "check_reparameterize": "motionlab.exercises.vae",
    "check_sample_loop": "motionlab.exercises.autoregressive",
    "check_slerp": "motionlab.exercises.rotations",
    "check_subtree_reach": "motionlab.exercises.hierarchy",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
