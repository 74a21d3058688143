"""Evaluation metrics for generated motion, each checked against an independent oracle in the tests.

=====================  =====================================================================================
module                 metrics
=====================  =====================================================================================
:mod:`.fid`            :func:`fid`, :func:`frechet_distance`, :func:`feature_statistics`
:mod:`.inception`      :func:`inception_score`, :func:`recognition_accuracy`
:mod:`.diversity`      :func:`apd`, :func:`diversity`, :func:`multimodality`, :func:`class_apd`, :func:`n_apd`
:mod:`.trajectory`     :func:`min_ade`, :func:`min_fde`, :func:`multimodal_ground_truth`, :func:`mmade`,
                       :func:`mmfde`, :func:`end_point_error`,
                       :func:`end_point_mse`
:mod:`.physical`       :func:`foot_skating`, :func:`infer_foot_contacts`, :func:`ground_penetration`,
                       :func:`jerk`, :func:`speed_spectrum`, :func:`periodic_speed_power`,
                       :func:`bone_lengths`, :func:`bone_length_error`, :func:`bone_length_drift`
:mod:`.modes`          :func:`mode_homogeneity`, :func:`mode_purity`, :func:`adjusted_rand_index`,
                       :func:`contingency_table`
:mod:`.intervals`      :func:`mean_ci`, :func:`repeat_metric`, :class:`Interval`
=====================  =====================================================================================

All metrics take NumPy arrays or torch tensors, compute in float64 and return Python floats. Their inputs are
checked through :mod:`motionlab.validation`: a wrong type or dtype raises ``TypeError``, a wrong value (wrong
shapes, NaN/inf, empty or too-small sets) ``ValueError``, both naming the function and argument.
"""

from motionlab.metrics.diversity import (
    DIVERSITY_PAIRS,
    MULTIMODALITY_PAIRS,
    apd,
    class_apd,
    diversity,
    multimodality,
    n_apd,
)
from motionlab.metrics.fid import feature_statistics, fid, frechet_distance
from motionlab.metrics.inception import inception_score, recognition_accuracy
from motionlab.metrics.intervals import Interval, mean_ci, repeat_metric, repeat_seed
from motionlab.metrics.modes import adjusted_rand_index, contingency_table, mode_homogeneity, mode_purity
from motionlab.metrics.physical import (
    FOOT_JOINTS,
    bone_length_drift,
    bone_length_error,
    bone_lengths,
    foot_skating,
    ground_penetration,
    infer_foot_contacts,
    jerk,
    periodic_speed_power,
    speed_spectrum,
)
from motionlab.metrics.trajectory import (
    end_point_error,
    end_point_mse,
    min_ade,
    min_fde,
    mmade,
    mmfde,
    multimodal_ground_truth,
)

__all__ = [
    "DIVERSITY_PAIRS",
    "FOOT_JOINTS",
    "MULTIMODALITY_PAIRS",
    "Interval",
    "adjusted_rand_index",
    "apd",
    "bone_length_drift",
    "bone_length_error",
    "bone_lengths",
    "class_apd",
    "contingency_table",
    "diversity",
    "end_point_error",
    "end_point_mse",
    "feature_statistics",
    "fid",
    "foot_skating",
    "frechet_distance",
    "inception_score",
    "ground_penetration",
    "infer_foot_contacts",
    "jerk",
    "mean_ci",
    "min_ade",
    "min_fde",
    "mmade",
    "mmfde",
    "mode_homogeneity",
    "mode_purity",
    "multimodal_ground_truth",
    "multimodality",
    "n_apd",
    "periodic_speed_power",
    "recognition_accuracy",
    "repeat_metric",
    "repeat_seed",
    "speed_spectrum",
]
