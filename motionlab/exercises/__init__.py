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

from motionlab.exercises.autoregressive import check_keep_mask, check_sample_loop
from motionlab.exercises.checking import CheckResult
from motionlab.exercises.diffusion import check_ancestral_step
from motionlab.exercises.flows import check_coupling_forward, check_coupling_inverse
from motionlab.exercises.hierarchy import check_impact_weights, check_subtree_reach
from motionlab.exercises.kinematics import check_chain_positions
from motionlab.exercises.metrics import check_apd, check_fid
from motionlab.exercises.mocap import check_bone_length_variation, check_mirror
from motionlab.exercises.rotations import check_quat_mul, check_slerp
from motionlab.exercises.sequences import (
    check_contrastive_loss,
    check_dct_matrix,
    check_given_trajectories,
    check_prior_kl,
)
from motionlab.exercises.skating import check_foot_skating
from motionlab.exercises.vae import (
    check_covariance_prior,
    check_gaussian_kl,
    check_negative_elbo,
    check_reparameterize,
)
from motionlab.exercises.vrnn import check_motion_cell_step

__all__ = [
    "CheckResult",
    "check_ancestral_step",
    "check_apd",
    "check_bone_length_variation",
    "check_chain_positions",
    "check_contrastive_loss",
    "check_coupling_forward",
    "check_coupling_inverse",
    "check_covariance_prior",
    "check_dct_matrix",
    "check_fid",
    "check_foot_skating",
    "check_gaussian_kl",
    "check_given_trajectories",
    "check_impact_weights",
    "check_keep_mask",
    "check_mirror",
    "check_motion_cell_step",
    "check_negative_elbo",
    "check_prior_kl",
    "check_quat_mul",
    "check_reparameterize",
    "check_sample_loop",
    "check_slerp",
    "check_subtree_reach",
]
