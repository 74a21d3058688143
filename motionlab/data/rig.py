"""NumPy rigging maths for the synthetic generator: rotation matrices, batched FK, leg IK, quaternions.

This is the generator's private, vectorised float64 toolbox (thousands of clips at once, no autograd).
Models and tests use the public torch versions in :mod:`motionlab.geometry` and
:func:`motionlab.skeleton.forward_kinematics`; a test checks that the two forward kinematics agree.

Matrices act on column vectors. Angles are radians; ``(roll, pitch, yaw)`` rotate about the
local x (forward), y (left) and z (up) axes and compose as ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
Useful signs in the rest pose: a positive pitch tilts a segment that points up forwards and swings one
that points down (leg, arm) backwards; a positive roll swings a downward segment to the left (+y).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` for stacks of 3x3 matrices ``(..., 3, 3)`` (broadcasting)."""
    return np.matmul(a, b)


def apply(matrix: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``matrix @ vector`` for ``(..., 3, 3)`` and ``(..., 3)`` (broadcasting)."""
    return np.matmul(matrix, vector[..., None])[..., 0]


def transpose(matrix: np.ndarray) -> np.ndarray:
    """The inverse of a stack of rotation matrices."""
    return np.swapaxes(matrix, -1, -2)


def euler_matrix(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` ``(..., 3, 3)`` from broadcastable angle arrays."""
    roll, pitch, yaw = np.broadcast_arrays(roll, pitch, yaw)
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    out = np.empty(roll.shape + (3, 3))
    out[..., 0, 0] = cy * cp
    out[..., 0, 1] = cy * sp * sr - sy * cr
    out[..., 0, 2] = cy * sp * cr + sy * sr
    out[..., 1, 0] = sy * cp
    out[..., 1, 1] = sy * sp * sr + cy * cr
    out[..., 1, 2] = sy * sp * cr - cy * sr
    out[..., 2, 0] = -sp
    out[..., 2, 1] = cp * sr
    out[..., 2, 2] = cp * cr
    return out


def yaw_matrix(yaw: np.ndarray) -> np.ndarray:
    """Rotation ``(..., 3, 3)`` about +z by ``yaw``."""
    zero = np.zeros_like(yaw)
    return euler_matrix(zero, zero, yaw)


def pitch_matrix(pitch: np.ndarray) -> np.ndarray:
    """Rotation ``(..., 3, 3)`` about +y by ``pitch``."""
    zero = np.zeros_like(pitch)
    return euler_matrix(zero, pitch, zero)


def forward_kinematics(
    local: np.ndarray, root_position: np.ndarray, offsets: np.ndarray, parents: Sequence[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Global positions ``(..., J, 3)`` and rotation matrices ``(..., J, 3, 3)`` from local matrices.

    ``local`` is ``(..., J, 3, 3)`` (the root's is its global orientation), ``root_position`` ``(..., 3)``,
    ``offsets`` ``(..., J, 3)`` broadcastable against ``local``'s batch.
    """
    glob = [local[..., 0, :, :]]
    positions = [np.broadcast_to(root_position, local.shape[:-3] + (3,))]
    for j in range(1, local.shape[-3]):
        parent = parents[j]
        glob.append(matmul(glob[parent], local[..., j, :, :]))
        positions.append(positions[parent] + apply(glob[parent], offsets[..., j, :]))
    return np.stack(positions, axis=-2), np.stack(glob, axis=-3)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


#: Fraction of the full leg length (thigh + shank) up to which :func:`leg_ik` reaches a target exactly;
#: beyond it the leg stretches along a smooth saturating curve instead of snapping straight. A leg
#: stretched that far still bends its knee by about 16 degrees: the knee angle changes fastest near full
#: extension, and stopping short of it keeps knee accelerations moderate.
LEG_REACH = 0.99


def leg_ik(
    hip: np.ndarray, ankle: np.ndarray, thigh: np.ndarray, shank: np.ndarray, knee_forward: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Analytic two-bone IK for a leg whose knee is a hinge about the thigh's local y axis.

    Args:
        hip, ankle: ``(..., 3)`` world positions of the hip joint and of the ankle target.
        thigh, shank: bone lengths, broadcastable to ``(...)``.
        knee_forward: ``(..., 3)`` direction the knee should point to (must not be parallel to the leg).
    Returns:
        ``thigh_rotation (..., 3, 3)``: global rotation of the thigh (its -z along the bone, its x towards
        ``knee_forward``), and ``knee (...)``: the knee's flexion, a rotation about the thigh's y axis
        (positive swings the shank backwards), in ``[0, pi)``. Targets up to ``LEG_REACH * (thigh + shank)``
        away are met exactly; farther ones are approached along a smooth saturating curve (``tanh``) that
        reaches the full leg length only far beyond it.
    """
    thigh = np.asarray(thigh, dtype=np.float64)
    shank = np.asarray(shank, dtype=np.float64)
    to_target = ankle - hip
    distance = np.linalg.norm(to_target, axis=-1)
    direction = to_target / distance[..., None]
    full = thigh + shank
    exact = LEG_REACH * full
    soft = exact + (full - exact) * np.tanh((distance - exact) / (full - exact))
    reach = np.clip(np.where(distance <= exact, distance, soft), np.abs(thigh - shank) + 1e-9, full)
    cos_hip = np.clip((thigh**2 + reach**2 - shank**2) / (2 * thigh * reach), -1.0, 1.0)
    sin_hip = np.sqrt(1.0 - cos_hip**2)
    side = _unit(knee_forward - np.sum(knee_forward * direction, axis=-1, keepdims=True) * direction)
    bone = cos_hip[..., None] * direction + sin_hip[..., None] * side
    y_axis = _unit(np.cross(-direction, side))  # the hinge: normal to the plane of the bent leg
    z_axis = -bone
    rotation = np.stack([np.cross(y_axis, z_axis), y_axis, z_axis], axis=-1)
    knee_position = hip + thigh[..., None] * bone
    target = hip + reach[..., None] * direction
    shank_local = apply(transpose(rotation), target - knee_position)
    knee = np.arctan2(-shank_local[..., 0], -shank_local[..., 2])
    return rotation, knee


def matrix_to_quaternion(matrix: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` (w first, ``w >= 0``) of rotation matrices ``(..., 3, 3)``.

    Each component's magnitude comes from the diagonal (``4 x^2 = 1 + m00 - m11 - m22`` and so on); its
    sign comes from its product with the largest component (``4 w x = m21 - m12``, ``4 x y = m01 + m10``,
    ...), which is never small, so half-turns are handled too. Accurate to about 1e-10 in float64.
    """
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = np.ascontiguousarray(matrix.reshape(-1, 9).T)
    size = np.sqrt(
        np.maximum(
            np.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22]),
            0.0,
        )
    )
    wx, wy, wz = m21 - m12, m02 - m20, m10 - m01
    xy, xz, yz = m01 + m10, m02 + m20, m12 + m21
    largest = np.argmax(size, axis=0)
    one = np.ones_like(wx)
    products = (  # rows: component w, x, y, z; columns: reference component w, x, y, z
        (one, wx, wy, wz),
        (wx, one, xy, xz),
        (wy, xy, one, yz),
        (wz, xz, yz, one),
    )
    quat = np.stack([np.copysign(size[i], np.choose(largest, row)) for i, row in enumerate(products)])
    quat *= np.where(quat[0] < 0, -1.0, 1.0) / np.sqrt(np.sum(quat * quat, axis=0))
    return np.ascontiguousarray(quat.T).reshape(matrix.shape[:-2] + (4,))


def continuous_quaternions(quat: np.ndarray, time_axis: int) -> np.ndarray:
    """Flip signs along ``time_axis`` so that consecutive quaternions have a non-negative dot product."""
    quat = np.moveaxis(quat, time_axis, 0)
    dots = np.sum(quat[1:] * quat[:-1], axis=-1)
    flips = np.cumprod(np.where(dots < 0, -1.0, 1.0), axis=0)
    out = quat.copy()
    out[1:] *= flips[..., None]
    return np.moveaxis(out, 0, time_axis)
