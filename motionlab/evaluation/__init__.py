"""Evaluation shared by every model chapter: classifier inputs, the frozen evaluation classifiers, and the
real-data reference rows. Metrics themselves live in :mod:`motionlab.metrics`.
"""

from motionlab.evaluation.evaluator import Evaluator, EvaluatorConfig, load_evaluator
from motionlab.evaluation.inputs import (
    EVAL_FEATURES,
    body_frame_features,
    body_frame_poses,
    hip_heading,
    joint_speed,
)

__all__ = [
    "EVAL_FEATURES",
    "Evaluator",
    "EvaluatorConfig",
    "body_frame_features",
    "body_frame_poses",
    "hip_heading",
    "joint_speed",
    "load_evaluator",
]
