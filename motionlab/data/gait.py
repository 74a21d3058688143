"""Walking and jogging: a curving root path, footprints planned on it, feet that roll, arms that swing.

The recipe, per batch of clips:

1. **Path.** Speed and yaw rate are smooth random curves; integrating them gives the pelvis path and
   heading (it curves, so trajectory control means something).
2. **Gait phase.** The stride frequency is speed / stride length, with the stride length growing with
   speed and leg length; integrating it gives the phase ``phi`` (cycles). The left foot is on the floor
   while ``frac(phi) < duty``, the right foot half a cycle later.
3. **Footprints.** Each stance of each foot gets one footprint: the point beside the path (half a step
   width) where the pelvis is at that stance's ``lead`` fraction. Only jogs have a flight phase.
4. **Feet.** During stance the foot rolls over its heel, lies flat, then rolls over its ball, never
   sliding (:func:`motionlab.data.body.foot_pose`); during swing a cubic Hermite curve carries the ankle
   from toe-off to the next heel strike, matching the stance velocities at both ends, lifted by the clearance.
5. **Body.** The pelvis sways over the stance foot, rotates and drops on the swing side; the thorax
   counter-rotates, the head stays level and looks into turns, the arms swing against the legs. The legs
   themselves are solved by :func:`motionlab.data.body.pose`, which also lowers the pelvis wherever a
   supporting leg could not reach its footprint (that gives the walk its vertical rhythm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionlab.data import rig
from motionlab.data.body import BodyBatch, Drive, foot_pose, on_heading
from motionlab.data.curves import bump, ease, gather_rows, hermite, interp_rows, smooth_noise
from motionlab.data.styles import Draws, Range
from motionlab.skeleton import JOINT

WALK_MODES = ("upright", "hunched")
JOG_MODES = ("upright", "lean")

#: Walk parameters: (lo, hi) shared, or one (lo, hi) per mode of WALK_MODES.
WALK: dict[str, Range] = {
    "speed": ((1.1, 1.6), (0.7, 1.05)),  # m/s
    "speed_wobble": (0.0, 0.08),  # relative amplitude of speed changes
    "turn_rate": (0.0, 0.45),  # rad/s amplitude of the random yaw rate
    "stride": ((0.95, 1.06), (0.84, 0.95)),  # stride length relative to the speed-stride law
    "duty": (0.58, 0.64),  # fraction of the cycle a foot is on the floor
    "lead": (0.33, 0.42),  # stance fraction at which the pelvis passes over the footprint
    "step_width": ((0.85, 1.15), (1.05, 1.35)),  # footprint distance from the path / hip width
    "toe_out": (0.02, 0.15),  # rad
    "heel_strike": ((0.22, 0.36), (0.08, 0.18)),  # rad, toes up at touchdown
    "toe_off": ((0.95, 1.2), (0.75, 1.0)),  # rad, heel up at lift-off
    "heel_roll": (0.12, 0.2),  # stance fraction spent rolling over the heel
    "heel_off": (0.45, 0.55),  # stance fraction at which the heel lifts
    "clearance": ((0.04, 0.08), (0.02, 0.045)),  # m, extra ankle lift in mid-swing
    "drop": ((0.0, 0.02), (0.05, 0.09)),  # m, pelvis below its standing height
    "bounce": (0.01, 0.022),  # m, vertical pelvis oscillation
    "sway": (0.012, 0.03),  # m, sideways pelvis oscillation
    "pelvis_rotation": (0.04, 0.1),  # rad
    "pelvis_list": (0.03, 0.07),  # rad
    "lean": ((-0.02, 0.08), (0.4, 0.6)),  # rad, trunk pitch forward (pelvis and spine)
    "thorax_rotation": (0.04, 0.12),  # rad, counter-rotation of the chest
    "arm_swing": ((0.28, 0.5), (0.04, 0.14)),  # rad, shoulder swing amplitude
    "elbow": ((0.12, 0.35), (0.45, 0.75)),  # rad, mean elbow flexion
    "arm_out": (0.06, 0.16),  # rad, shoulder abduction
    "gaze": ((0.6, 0.95), (0.25, 0.5)),  # fraction of the trunk pitch the neck and head undo
}

#: Jog parameters, per mode of JOG_MODES ("lean": forward-leaning with high knees).
JOG: dict[str, Range] = {
    "speed": ((2.2, 3.0), (2.0, 2.8)),
    "speed_wobble": (0.0, 0.06),
    "turn_rate": (0.0, 0.35),
    "stride": (0.95, 1.05),
    "duty": (0.34, 0.4),
    "lead": (0.32, 0.42),
    "step_width": (0.35, 0.7),
    "toe_out": (0.0, 0.1),
    "heel_strike": (0.0, 0.12),
    "toe_off": (0.55, 0.85),
    "heel_roll": (0.04, 0.1),
    "heel_off": (0.42, 0.55),
    "clearance": ((0.08, 0.14), (0.24, 0.34)),
    "drop": (0.03, 0.06),
    "bounce": (0.025, 0.045),
    "sway": (0.005, 0.015),
    "pelvis_rotation": (0.06, 0.12),
    "pelvis_list": (0.03, 0.06),
    "lean": ((0.03, 0.12), (0.28, 0.42)),
    "thorax_rotation": (0.06, 0.15),
    "arm_swing": ((0.5, 0.75), (0.65, 0.95)),
    "elbow": ((1.2, 1.5), (1.35, 1.7)),
    "arm_out": (0.1, 0.22),
    "gaze": ((0.6, 0.9), (0.5, 0.8)),
}

#: Stride length = leg length * (a + b * speed), from the walk and jog speed-stride relations.
STRIDE_LAW = {"walk": (1.15, 0.40), "jog": (1.50, 0.35)}

_EPS = 1e-4  # stance-fraction step for the end slopes of the swing curves


@dataclass(frozen=True)
class _Course:
    """Path, heading and gait phase ``(B, n)`` on a padded time axis, and where the clip's frames lie in
    it."""

    path: np.ndarray  # (B, n, 2)
    heading: np.ndarray  # (B, n)
    yaw_rate: np.ndarray  # (B, n)
    phase: np.ndarray  # (B, n), cycles; the left heel strikes at whole numbers
    clip: slice


def _integral(rate: np.ndarray, fps: int, anchor: int) -> np.ndarray:
    """Cumulative trapezoid integral along axis 1 of a rate sampled at ``fps``, zero at index ``anchor``."""
    steps = 0.5 * (rate[:, 1:] + rate[:, :-1]) / fps
    total = np.concatenate([np.zeros_like(rate[:, :1]), np.cumsum(steps, axis=1)], axis=1)
    return total - total[:, anchor : anchor + 1]


def _course(
    draws: Draws, p: dict[str, np.ndarray], bodies: BodyBatch, n_frames: int, fps: int, jog: bool
) -> _Course:
    """Steps 1-2: speed and yaw rate as smooth random curves, integrated into path, heading and phase."""
    start, heading0 = draws.start(0.5)
    phase0 = draws.unit()
    turn_terms = draws.noise_terms(3, (0.05, 0.3))
    speed_terms = draws.noise_terms(2, (0.1, 0.5))
    pad = int(2.5 * fps)  # footprints of the first and last steps lie before and after the clip
    t = np.arange(-pad, n_frames + pad) / fps
    speed = p["speed"][:, None] * (1 + p["speed_wobble"][:, None] * smooth_noise(t, *speed_terms))
    yaw_rate = p["turn_rate"][:, None] * smooth_noise(t, *turn_terms)
    heading = heading0[:, None] + _integral(yaw_rate, fps, pad)
    velocity = speed[..., None] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    a, b = STRIDE_LAW["jog" if jog else "walk"]
    stride = bodies.leg * (a + b * p["speed"]) * p["stride"]
    phase = phase0[:, None] + _integral(speed / stride[:, None], fps, pad)
    return _Course(
        path=start[:, None, :] + _integral(velocity, fps, pad),
        heading=heading,
        yaw_rate=yaw_rate,
        phase=phase,
        clip=slice(pad, pad + n_frames),
    )


def _stance_pitch(s: np.ndarray, col: dict[str, np.ndarray]) -> np.ndarray:
    """Foot pitch over the stance fraction ``s``: heel roll, flat, then roll over the ball (quadratic
    ease)."""
    heel = -col["heel_strike"] * np.clip(1 - s / col["heel_roll"], 0, 1) ** 2
    toe = col["toe_off"] * np.clip((s - col["heel_off"]) / (1 - col["heel_off"]), 0, 1) ** 2
    return heel + toe


def _foot(drive: Drive, course: _Course, col: dict[str, np.ndarray], bodies: BodyBatch, side: int) -> None:
    """Steps 3-4 for one foot (0 left, 1 right): footprints, stance roll, swing curves, contacts."""
    offset, sign = (0.0, 1.0) if side == 0 else (0.5, -1.0)
    duty = col["duty"]
    cycle = course.phase[:, course.clip] - offset
    k = np.floor(cycle)
    frac = cycle - k

    # one footprint per stance touching the clip, (B, K): beside the path where the pelvis is at `lead`
    k_first = k[:, 0] - 1
    stances = k_first[:, None] + np.arange(int((k[:, -1] - k_first).max()) + 2)
    at = stances + offset + col["lead"] * duty
    print_xy = interp_rows(course.phase, course.path, at)
    print_heading = interp_rows(course.phase, course.heading, at)
    flat_xy = on_heading(print_xy, print_heading, 0.0, sign * col["step_width"] * bodies.hip_width[:, None])
    height = np.broadcast_to(bodies.ankle_height[:, None, None], flat_xy.shape[:-1] + (1,))
    flat = np.concatenate([flat_xy, height], axis=-1)
    print_yaw = print_heading + sign * col["toe_out"]
    index = (k - k_first[:, None]).astype(np.int64)  # each frame's current (or last) stance

    def stance(s: np.ndarray, which: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ankle, foot rotation and pitch at stance fraction ``s`` of stances ``which`` ``(B, T)``."""
        pitch = _stance_pitch(s, col)
        ankle, rotation = foot_pose(
            gather_rows(flat, which),
            gather_rows(print_yaw, which),
            pitch,
            bodies.ball[:, None],
            bodies.heel[:, None],
        )
        return ankle, rotation, pitch

    in_stance = frac < duty
    s = np.clip(frac / duty, 0, 1)
    sigma = np.clip((frac - duty) / (1 - duty), 0, 1)
    stance_ankle, stance_rotation, _ = stance(s, index)

    # swing: from the end of stance k to the start of stance k + 1, matching both ends' velocities
    end, start = np.ones_like(s), np.zeros_like(s)
    off_ankle, _, off_pitch = stance(end, index)
    off_before, _, off_pitch_before = stance(end - _EPS, index)
    on_ankle, _, on_pitch = stance(start, index + 1)
    on_after, _, on_pitch_after = stance(start + _EPS, index + 1)
    to_sigma = (1 - duty) / duty / _EPS  # per unit of stance fraction -> per unit of swing fraction
    swing_ankle = hermite(
        off_ankle,
        (off_ankle - off_before) * to_sigma[..., None],
        on_ankle,
        (on_after - on_ankle) * to_sigma[..., None],
        sigma[..., None],
    )
    swing_ankle[..., 2] += col["clearance"] * bump(sigma)
    swing_pitch = hermite(
        off_pitch,
        (off_pitch - off_pitch_before) * to_sigma,
        on_pitch,
        (on_pitch_after - on_pitch) * to_sigma,
        sigma,
    )

    def blend(values: np.ndarray) -> np.ndarray:
        """A per-stance angle held during stance and eased to the next stance's during swing."""
        now, then = gather_rows(values, index), gather_rows(values, index + 1)
        return np.where(in_stance, now, now + (then - now) * ease(sigma))

    swing_rotation = rig.matmul(rig.yaw_matrix(blend(print_yaw)), rig.pitch_matrix(swing_pitch))
    knee_yaw = blend(print_heading)
    drive.ankle[:, :, side] = np.where(in_stance[..., None], stance_ankle, swing_ankle)
    drive.foot_rotation[:, :, side] = np.where(in_stance[..., None, None], stance_rotation, swing_rotation)
    drive.knee_forward[:, :, side] = np.stack(
        [np.cos(knee_yaw), np.sin(knee_yaw), np.zeros_like(knee_yaw)], axis=-1
    )
    drive.support[:, :, side] = True  # swing feet too: the leg must reach the next footprint
    drive.contacts[:, :, side] = in_stance & (s >= col["heel_roll"]) & (s <= col["heel_off"])
    drive.contacts[:, :, 2 + side] = in_stance & (s >= col["heel_roll"])


def _body(drive: Drive, course: _Course, col: dict[str, np.ndarray], bodies: BodyBatch, jog: bool) -> None:
    """Step 5: pelvis, trunk, head and arms from the phase (left heel strike at phase 0)."""
    phase, heading = course.phase[:, course.clip], course.heading[:, course.clip]
    stride_angle = 2 * np.pi * phase
    mid_left = 2 * np.pi * (phase - col["lead"] * col["duty"])  # the pelvis passes the left footprint at 0
    drive.root_position[..., :2] = on_heading(
        course.path[:, course.clip], heading, 0.0, col["sway"] * np.cos(mid_left)
    )
    bounce = col["bounce"] * np.cos(2 * mid_left) * (-1.0 if jog else 1.0)  # a walk peaks at mid-stance
    drive.root_position[..., 2] = bodies.root_height[:, None] - col["drop"] + bounce
    pelvis_list = col["pelvis_list"] * np.cos(mid_left)
    drive.root_rotation = rig.euler_matrix(
        pelvis_list, 0.35 * col["lean"], heading - col["pelvis_rotation"] * np.cos(stride_angle)
    )

    zero = np.zeros_like(phase)
    chest_yaw = (col["thorax_rotation"] + col["pelvis_rotation"]) * np.cos(stride_angle) / 3
    spine = rig.euler_matrix(-0.6 * pelvis_list / 3, 0.65 * col["lean"] / 3 + zero, chest_yaw)
    for name in ("spine1", "spine2", "spine3"):
        drive.local[:, :, JOINT[name]] = spine
    look = np.clip(0.4 * course.yaw_rate[:, course.clip], -0.35, 0.35)  # glance into the turn
    head_yaw = (-col["thorax_rotation"] * np.cos(stride_angle) + look) / 2
    head = rig.euler_matrix(0.3 * pelvis_list / 2, -col["gaze"] * col["lean"] / 2 + zero, head_yaw)
    drive.local[:, :, JOINT["neck"]] = head
    drive.local[:, :, JOINT["head"]] = head

    swing = col["arm_swing"] * np.cos(stride_angle)  # each arm swings with the opposite leg
    carry = -0.7 * col["lean"] - (0.15 if jog else 0.0)  # arms hang (or are carried) ahead of a leaning trunk
    for name, sign in (("left", 1.0), ("right", -1.0)):
        shoulder = rig.euler_matrix(sign * col["arm_out"] + zero, sign * swing + carry, zero)
        drive.local[:, :, JOINT[f"{name}_shoulder"]] = shoulder
        flexion = col["elbow"] * (1 - 0.4 * sign * np.cos(stride_angle))  # more bent while in front
        drive.local[:, :, JOINT[f"{name}_elbow"]] = rig.pitch_matrix(-flexion)


def locomotion(draws: Draws, bodies: BodyBatch, n_frames: int, fps: int, jog: bool) -> Drive:
    """A :class:`Drive` for ``B`` walking (``jog=False``) or jogging clips of ``n_frames`` frames."""
    p = draws.table(JOG if jog else WALK)
    course = _course(draws, p, bodies, n_frames, fps, jog)
    col = {name: value[:, None] for name, value in p.items()}  # (B, 1), broadcasting over frames
    drive = Drive.standing(len(bodies.body), n_frames)
    for side in range(2):
        _foot(drive, course, col, bodies, side)
    _body(drive, course, col, bodies, jog)
    return drive
