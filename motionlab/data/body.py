"""Posing bodies from a :class:`Drive`: root height limits, leg IK for the feet, FK and quaternions.

Each action (:mod:`~motionlab.data.gait`, :mod:`~motionlab.data.events`, :mod:`~motionlab.data.gestures`)
describes a batch of clips as a :class:`Drive`: where the pelvis goes, how the spine, head and arms turn
(local rotation matrices), and where each foot must be (ankle target and world orientation). Then
:func:`pose` makes it a motion: it caps the pelvis height so that the supporting legs reach their feet,
solves each leg analytically (hip and knee from the ankle target, ankle from the foot's orientation) and
runs forward kinematics. Planted feet therefore stay exactly where the action put them.

A foot's pose is its ankle position and its rotation ``Rz(yaw) @ Ry(pitch)``; ``pitch > 0`` lifts the
heel (rolling over the ball of the foot), ``pitch < 0`` lifts the toes (rolling over the heel).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionlab.data import rig
from motionlab.data.curves import smooth_time
from motionlab.skeleton import BODY_MEASUREMENTS, JOINT, PARENTS

#: The foot joints whose contacts the data records, in this order (left/right ankle, left/right foot).
CONTACT_JOINTS = (JOINT["left_ankle"], JOINT["right_ankle"], JOINT["left_foot"], JOINT["right_foot"])

_HIPS = (JOINT["left_hip"], JOINT["right_hip"])
_KNEES = (JOINT["left_knee"], JOINT["right_knee"])
_ANKLES = (JOINT["left_ankle"], JOINT["right_ankle"])


@dataclass(frozen=True)
class BodyBatch:
    """Per-clip body dimensions ``(B, ...)`` looked up from each clip's body type."""

    body: np.ndarray  # (B,) int body type
    offsets: np.ndarray  # (B, J, 3)
    thigh: np.ndarray  # (B,)
    shank: np.ndarray  # (B,)
    hip_width: np.ndarray  # (B,)
    ankle_height: np.ndarray  # (B,)
    root_height: np.ndarray  # (B,) pelvis height in the rest pose
    ball: np.ndarray  # (B, 3) foot joint relative to the ankle, foot frame
    heel: np.ndarray  # (B, 3) heel contact point relative to the ankle, foot frame

    @classmethod
    def of(cls, body: np.ndarray) -> BodyBatch:
        """Dimensions of the body types ``body`` ``(B,)``."""
        table = [BODY_MEASUREMENTS[int(b)] for b in body]

        def column(name: str) -> np.ndarray:
            return np.array([getattr(m, name) for m in table], dtype=np.float64)

        zero = np.zeros(len(table))
        return cls(
            body=np.asarray(body),
            offsets=np.stack([m.offsets() for m in table]),
            thigh=column("thigh"),
            shank=column("shank"),
            hip_width=column("hip_width"),
            ankle_height=column("ankle_height"),
            root_height=column("root_height"),
            ball=np.stack([column("foot_length"), zero, -column("foot_drop")], axis=-1),
            heel=np.stack([-column("heel_back"), zero, -column("ankle_height")], axis=-1),
        )

    @property
    def leg(self) -> np.ndarray:
        """Thigh plus shank ``(B,)``."""
        return self.thigh + self.shank


@dataclass
class Drive:
    """What an action asks of a batch of ``B`` clips of ``T`` frames (world frame, metres, radians).

    ``root_position[..., 2]`` is the desired pelvis height; :func:`pose` lowers it where a supporting leg
    could not reach its foot. ``local`` holds every joint's local rotation except the root (which is
    ``root_rotation``) and the legs (hips, knees, ankles: solved from the feet).
    """

    root_position: np.ndarray  # (B, T, 3)
    root_rotation: np.ndarray  # (B, T, 3, 3)
    local: np.ndarray  # (B, T, J, 3, 3)
    ankle: np.ndarray  # (B, T, 2, 3) ankle targets, left then right
    foot_rotation: np.ndarray  # (B, T, 2, 3, 3) world orientation of each foot
    knee_forward: np.ndarray  # (B, T, 2, 3) direction each knee points to
    support: np.ndarray  # (B, T, 2) bool: the leg must reach its target exactly (caps the pelvis height)
    contacts: np.ndarray  # (B, T, 4) bool, joints CONTACT_JOINTS: planted on the floor

    @classmethod
    def standing(cls, n_clips: int, n_frames: int) -> Drive:
        """An all-identity drive to fill in (zeros for positions, identity rotations, no support)."""
        eye = np.broadcast_to(np.eye(3), (n_clips, n_frames, len(PARENTS), 3, 3)).copy()
        feet_eye = np.broadcast_to(np.eye(3), (n_clips, n_frames, 2, 3, 3)).copy()
        return cls(
            root_position=np.zeros((n_clips, n_frames, 3)),
            root_rotation=eye[:, :, 0].copy(),
            local=eye,
            ankle=np.zeros((n_clips, n_frames, 2, 3)),
            foot_rotation=feet_eye,
            knee_forward=np.zeros((n_clips, n_frames, 2, 3)),
            support=np.zeros((n_clips, n_frames, 2), bool),
            contacts=np.zeros((n_clips, n_frames, 4), bool),
        )


def foot_pose(
    ankle_flat: np.ndarray, yaw: np.ndarray, pitch: np.ndarray, ball: np.ndarray, heel: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Ankle position and foot rotation of a foot that rolls on the floor from a flat footprint.

    Args:
        ankle_flat: ``(..., 3)`` ankle position when the foot lies flat; yaw, pitch: ``(...)``.
        ball, heel: ``(..., 3)`` foot joint and heel point relative to the ankle in the foot frame.
    Returns:
        ``ankle (..., 3)`` and ``rotation (..., 3, 3)``: for ``pitch >= 0`` the ball stays where the flat
        foot had it, for ``pitch < 0`` the heel does.
    """
    heading = rig.yaw_matrix(yaw)
    rotation = rig.matmul(heading, rig.pitch_matrix(pitch))
    pivot = np.where((pitch >= 0)[..., None], ball, heel)
    ankle = ankle_flat + rig.apply(heading, pivot) - rig.apply(rotation, pivot)
    return ankle, rotation


def root_height_limit(
    root_xy: np.ndarray, root_rotation: np.ndarray, ankle: np.ndarray, bodies: BodyBatch
) -> np.ndarray:
    """Highest pelvis height ``(B, T, 2)`` at which each leg reaches its ankle target exactly
    (:data:`rig.LEG_REACH`).

    Args:
        root_xy: ``(B, T, 2)``; root_rotation: ``(B, T, 3, 3)``; ankle: ``(B, T, 2, 3)`` targets.
    """
    hip_offsets = bodies.offsets[:, None, list(_HIPS), :]  # (B, 1, 2, 3)
    hip = rig.apply(root_rotation[:, :, None], hip_offsets)  # relative to the root
    horizontal = ankle[..., :2] - root_xy[:, :, None, :] - hip[..., :2]
    reach = (rig.LEG_REACH * bodies.leg)[:, None, None]
    room = np.sqrt(np.maximum(reach**2 - np.sum(horizontal**2, axis=-1), 0.0))
    return ankle[..., 2] - hip[..., 2] + room


def capped_root_height(drive: Drive, bodies: BodyBatch, fps: int) -> np.ndarray:
    """The desired pelvis height, lowered smoothly wherever a supporting leg could not reach, ``(B, T)``.

    The shortfall ``d = max(0, desired - limit)`` is widened by a running maximum over ``w`` frames each
    side (``w`` about 0.13 s) and then smoothed by a kernel of the same support, so the result is smooth
    and still at least ``d`` everywhere (each frame's kernel only sees maxima over windows that contain it).
    """
    half_width = max(1, round(0.133 * fps))
    limit = root_height_limit(drive.root_position[..., :2], drive.root_rotation, drive.ankle, bodies)
    limit = np.where(drive.support, limit, np.inf).min(axis=-1)
    desired = drive.root_position[..., 2]
    shortfall = np.maximum(desired - limit, 0.0)
    padded = np.pad(shortfall, ((0, 0), (half_width, half_width)), mode="edge")
    n_frames = shortfall.shape[1]
    widened = np.max([padded[:, i : i + n_frames] for i in range(2 * half_width + 1)], axis=0)
    return desired - smooth_time(widened, passes=half_width)


def pose(drive: Drive, bodies: BodyBatch, fps: int) -> tuple[np.ndarray, np.ndarray]:
    """Local quaternions ``(B, T, J, 4)`` (w first, continuous in time) and positions ``(B, T, J, 3)``."""
    root = drive.root_position.copy()
    root[..., 2] = capped_root_height(drive, bodies, fps)
    local = drive.local.copy()
    local[:, :, 0] = drive.root_rotation
    for side in range(2):
        hip = root + rig.apply(drive.root_rotation, bodies.offsets[:, None, _HIPS[side], :])
        thigh, knee = rig.leg_ik(
            hip,
            drive.ankle[:, :, side],
            bodies.thigh[:, None],
            bodies.shank[:, None],
            drive.knee_forward[:, :, side],
        )
        knee_rotation = rig.pitch_matrix(knee)
        local[:, :, _HIPS[side]] = rig.matmul(rig.transpose(drive.root_rotation), thigh)
        local[:, :, _KNEES[side]] = knee_rotation
        shank = rig.matmul(thigh, knee_rotation)
        local[:, :, _ANKLES[side]] = rig.matmul(rig.transpose(shank), drive.foot_rotation[:, :, side])
    positions, _ = rig.forward_kinematics(local, root, bodies.offsets[:, None], PARENTS)
    quaternions = rig.continuous_quaternions(rig.matrix_to_quaternion(local), time_axis=1)
    return quaternions, positions


def on_heading(origin: np.ndarray, heading: np.ndarray, forward: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Points ``(..., 2)`` at ``forward`` metres along ``heading`` and ``left`` metres to its left of
    ``origin``.

    ``origin`` is ``(..., 2)``; the other arguments broadcast against ``origin[..., 0]``.
    """
    c, s = np.cos(heading), np.sin(heading)
    x = origin[..., 0] + forward * c - left * s
    y = origin[..., 1] + forward * s + left * c
    return np.stack(np.broadcast_arrays(x, y), axis=-1)


def footprints(
    centre: np.ndarray, heading: np.ndarray, half_width: np.ndarray, toe_out: np.ndarray, bodies: BodyBatch
) -> tuple[np.ndarray, np.ndarray]:
    """Flat-foot ankle positions ``(B, 2, 3)`` and foot yaws ``(B, 2)`` (left, right) of a standing stance.

    Args:
        centre: ``(B, 2)`` point between the feet; heading: ``(B,)`` facing direction;
        half_width: ``(B,)`` sideways distance of each ankle from the centre; toe_out: ``(B,)`` rad.
    """
    sides = np.array([1.0, -1.0])
    xy = on_heading(centre[:, None], heading[:, None], 0.0, half_width[:, None] * sides)
    z = np.broadcast_to(bodies.ankle_height[:, None, None], xy.shape[:-1] + (1,))
    return np.concatenate([xy, z], axis=-1), heading[:, None] + sides * toe_out[:, None]


def plant(drive: Drive, ankle_flat: np.ndarray, yaw: np.ndarray) -> None:
    """Put both feet flat on their footprints for every frame: supporting, in contact, knees over the toes.

    ``ankle_flat`` ``(B, 2, 3)`` and ``yaw`` ``(B, 2)`` as returned by :func:`footprints`; actions then
    override the frames where a foot moves.
    """
    n_frames = drive.ankle.shape[1]
    drive.ankle[:] = ankle_flat[:, None]
    drive.foot_rotation[:] = rig.yaw_matrix(yaw)[:, None]
    knee_yaw = np.broadcast_to(yaw[:, None], (yaw.shape[0], n_frames, 2))
    drive.knee_forward[:] = np.stack([np.cos(knee_yaw), np.sin(knee_yaw), np.zeros_like(knee_yaw)], axis=-1)
    drive.support[:] = True
    drive.contacts[:] = True
