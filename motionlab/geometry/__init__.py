"""Rotation geometry in torch: conversions, interpolation, distances and validity penalties.

Conventions (course-wide):

- quaternions ``(..., 4)``, scalar first ``(w, x, y, z)``; ``q`` and ``-q`` are the same rotation;
  ``quat_mul(q1, q2)`` applies ``q2`` first;
- rotation matrices ``(..., 3, 3)`` act on column vectors; rotation vectors (axis-angle) ``(..., 3)``;
  the 6D representation ``(..., 6)`` is the first two matrix columns; angles are radians;
- Euler orders use scipy's names: ``"XYZ"`` intrinsic, ``"xyz"`` extrinsic, all 12 orders.

Every function is batched over any leading dimensions, works in float32 and float64 and is
differentiable with finite gradients, including at the singular points (identical or opposite
rotations, gimbal lock, the zero rotation vector). Functions that turn a quaternion into a rotation
accept any non-zero quaternion and use ``q / |q|``. Bad input raises: a wrong shape or dtype raises
``ValueError``/``TypeError`` naming the function and the expected shape, and a zero quaternion (where a
rotation is needed) or a NaN/infinity raises ``ValueError`` naming the first bad index.
"""

from motionlab.geometry.axis_angle import axis_angle_to_quat, quat_to_axis_angle
from motionlab.geometry.distances import matrix_geodesic, quat_d2, quat_d3, quat_geodesic
from motionlab.geometry.euler import euler_to_quat, quat_to_euler
from motionlab.geometry.interpolation import InterpolationPaths, interpolation_paths, quat_nlerp, quat_slerp
from motionlab.geometry.matrix import matrix_to_quat, quat_to_matrix
from motionlab.geometry.quaternion import (
    quat_apply,
    quat_conjugate,
    quat_from_two_vectors,
    quat_identity,
    quat_mul,
    quat_normalize,
    quat_standardize,
)
from motionlab.geometry.sixd import gram_schmidt, matrix_to_sixd, sixd_to_matrix
from motionlab.geometry.validity import determinant_penalty, orthogonality_penalty, quat_norm_penalty

__all__ = [
    "InterpolationPaths",
    "axis_angle_to_quat",
    "determinant_penalty",
    "euler_to_quat",
    "gram_schmidt",
    "interpolation_paths",
    "matrix_geodesic",
    "matrix_to_quat",
    "matrix_to_sixd",
    "orthogonality_penalty",
    "quat_apply",
    "quat_conjugate",
    "quat_d2",
    "quat_d3",
    "quat_from_two_vectors",
    "quat_geodesic",
    "quat_identity",
    "quat_mul",
    "quat_nlerp",
    "quat_norm_penalty",
    "quat_normalize",
    "quat_slerp",
    "quat_standardize",
    "quat_to_axis_angle",
    "quat_to_euler",
    "quat_to_matrix",
    "sixd_to_matrix",
]
