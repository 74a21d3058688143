"""Actions performed standing in place: wave (periodic) and kick (one kick at a random time).

The feet stay planted on a random stance (the kicking foot leaves the floor for the kick only), the
pelvis sways a little, and the legs are solved from the feet by :func:`motionlab.data.body.pose`.
"""

from __future__ import annotations

import numpy as np

from motionlab.data import rig
from motionlab.data.body import BodyBatch, Drive, footprints, on_heading, plant
from motionlab.data.curves import keyframes, place_event, smooth_noise
from motionlab.data.styles import Draws, Range
from motionlab.skeleton import JOINT

WAVE_MODES = ("left", "right")
KICK_MODES = ("front", "side")

#: Wave parameters (the same for both hands; the mode picks the hand). Angles in radians.
WAVE: dict[str, Range] = {
    "raise": (1.7, 2.3),  # shoulder abduction of the waving arm
    "forward": (0.1, 0.45),  # the waving arm slightly in front of the body
    "elbow": (1.1, 1.6),  # mean elbow flexion (forearm up)
    "swing": (0.3, 0.6),  # amplitude of the wave (elbow flexion)
    "frequency": (1.4, 2.6),  # Hz
    "lean": (0.02, 0.1),  # trunk leans away from the waving arm
    "sway": (0.01, 0.03),  # m, slow sideways sway of the pelvis
    "turn": (0.0, 0.25),  # amplitude of slow turns of the chest and head
    "width": (0.9, 1.4),
    "toe_out": (0.05, 0.25),
}

#: Kick parameters per mode of KICK_MODES. Target positions are fractions of the leg length relative to
#: the kicking foot's footprint, in the character's frame (forward, out to the kicking side, up).
KICK: dict[str, Range] = {
    "shift": (0.3, 0.5),  # s, weight onto the supporting leg
    "chamber": (0.18, 0.3),  # s, knee up
    "extend": (0.12, 0.22),  # s, leg out
    "hold": (0.05, 0.2),  # s
    "retract": (0.15, 0.25),  # s
    "down": (0.2, 0.35),  # s, foot back on the floor
    "settle": (0.3, 0.5),  # s, weight back on both feet
    "forward_leg": ((0.8, 1.0), (-0.05, 0.15)),
    "out_leg": ((0.0, 0.1), (0.55, 0.8)),
    "up_leg": ((0.5, 0.9), (0.35, 0.7)),
    "foot_pitch": ((-1.2, -0.6), (0.0, 0.3)),  # toes up for a front kick
    "foot_roll": ((0.0, 0.0), (1.1, 1.5)),  # sole turned towards the target for a side kick
    "hip_shift": (0.8, 1.05),  # pelvis moves over the supporting foot, fraction of the hip width
    "lean": ((0.12, 0.28), (0.25, 0.45)),  # trunk leans back (front) or away (side)
    "guard_shoulder": (0.3, 0.7),
    "guard_elbow": (1.3, 1.9),
    "width": (0.9, 1.2),
    "toe_out": (0.05, 0.2),
}


def wave(draws: Draws, bodies: BodyBatch, n_frames: int, fps: int) -> Drive:
    """A :class:`Drive` for ``B`` clips of waving with one hand (mode 0 left, 1 right) while standing."""
    p = draws.table(WAVE)
    centre, heading = draws.start(0.5)
    phase = draws.angle()
    sway_terms = draws.noise_terms(2, (0.1, 0.3))
    turn_terms = draws.noise_terms(2, (0.1, 0.3))
    t = np.arange(n_frames) / fps
    hand = np.where(draws.style == 0, 1.0, -1.0)[:, None]  # +1 waves the left hand (+y side)
    col = {name: value[:, None] for name, value in p.items()}

    drive = Drive.standing(centre.shape[0], n_frames)
    ankles, yaw = footprints(centre, heading, p["width"] * bodies.hip_width, p["toe_out"], bodies)
    plant(drive, ankles, yaw)
    sway = col["sway"] * smooth_noise(t, *sway_terms) - 0.01 * hand
    drive.root_position[..., :2] = on_heading(centre[:, None], heading[:, None], 0.0, sway)
    drive.root_position[..., 2] = bodies.root_height[:, None]
    drive.root_rotation = rig.euler_matrix(0 * t + 0.3 * hand * col["lean"], 0 * t, heading[:, None] + 0 * t)

    turn = col["turn"] * smooth_noise(t, *turn_terms)
    chest = rig.euler_matrix(0.7 * hand * col["lean"] / 3 + 0 * t, 0 * t, turn / 3)
    for name in ("spine1", "spine2", "spine3"):
        drive.local[:, :, JOINT[name]] = chest
    head = rig.euler_matrix(-hand * col["lean"] / 2 + 0 * t, 0 * t, 0.5 * hand * col["turn"] - turn / 2)
    drive.local[:, :, JOINT["neck"]] = head
    drive.local[:, :, JOINT["head"]] = head

    flexion = col["elbow"] + col["swing"] * np.sin(2 * np.pi * col["frequency"] * t + phase[:, None])
    for name, sign in (("left", 1.0), ("right", -1.0)):
        waving = (hand == sign)[..., None, None]
        # twist the raised arm about its length so that the elbow bends in the frontal plane (forearm up)
        raised = rig.matmul(
            rig.euler_matrix(sign * col["raise"], col["forward"] + 0 * t, 0 * t),
            rig.yaw_matrix(sign * np.pi / 2 + 0 * t),
        )
        hanging = rig.euler_matrix(
            sign * 0.08 - hand * col["lean"] + 0 * t, 0 * t, 0 * t
        )  # vertical under the lean
        drive.local[:, :, JOINT[f"{name}_shoulder"]] = np.where(waving, raised, hanging)
        elbow = np.where(waving[..., 0, 0], flexion, 0.15)
        drive.local[:, :, JOINT[f"{name}_elbow"]] = rig.pitch_matrix(-elbow)
    return drive


def kick(draws: Draws, bodies: BodyBatch, n_frames: int, fps: int) -> Drive:
    """A :class:`Drive` for ``B`` clips with one kick (mode 0 front, 1 side) with a random leg."""
    p = draws.table(KICK)
    centre, heading = draws.start(0.5)
    where = draws.unit()
    side = draws.sign()[:, None]  # +1 kicks with the left leg
    t = np.arange(n_frames) / fps
    n_clips = centre.shape[0]
    leg, zero, one = bodies.leg, np.zeros(n_clips), np.ones(n_clips)
    phases = np.stack(
        [p[name] for name in ("shift", "chamber", "extend", "hold", "retract", "down", "settle")], 1
    )
    start, scale = place_event(phases.sum(axis=1), n_frames, fps, where)
    keys = start[:, None] + scale[:, None] * np.concatenate(
        [zero[:, None], np.cumsum(phases, axis=1)], axis=1
    )

    def held(chamber: np.ndarray, extended: np.ndarray) -> np.ndarray:
        """Keys ``(B, 8)``: rest, rest after the shift, chamber, extended (twice), chamber, rest, rest."""
        return np.stack([zero, zero, chamber, extended, extended, chamber, zero, zero], axis=1)

    drive = Drive.standing(n_clips, n_frames)
    ankles, yaw = footprints(centre, heading, p["width"] * bodies.hip_width, p["toe_out"], bodies)
    plant(drive, ankles, yaw)
    rows, kicking = np.arange(n_clips), np.where(side[:, 0] > 0, 0, 1)  # the kicking foot (0 left, 1 right)
    home = ankles[rows, kicking]  # (B, 3) its flat footprint

    # the kicking foot: lifted to the chamber, driven out to the target and back, in the character's frame
    front = (draws.style == 0)[:, None]
    chamber_forward = np.where(front[:, 0], 0.2, 0.1) * leg
    forward = keyframes(keys, held(chamber_forward, p["forward_leg"] * leg), t)
    out = keyframes(keys, held(0.1 * leg, p["out_leg"] * leg), t)
    up = keyframes(keys, held(0.45 * leg, p["up_leg"] * leg), t)
    lifted = keyframes(keys, held(one, one), t)  # 0 on the floor, 1 from the chamber on
    target_xy = on_heading(home[:, None, :2], heading[:, None], forward, side * out)
    drive.ankle[rows, :, kicking] = np.concatenate([target_xy, (home[:, None, 2] + up)[..., None]], axis=-1)
    pitch = keyframes(keys, held(0.7 + zero, p["foot_pitch"]), t)
    roll = side * keyframes(keys, held(zero, p["foot_roll"]), t)
    drive.foot_rotation[rows, :, kicking] = rig.euler_matrix(roll, pitch, yaw[rows, kicking][:, None] + 0 * t)
    knee = np.stack(
        [
            np.cos(heading)[:, None] + 0 * t,
            np.sin(heading)[:, None] + 0 * t,
            np.where(front, 0.8, 0.3) * lifted,
        ],
        axis=-1,
    )  # the knee turns up as the leg rises
    drive.knee_forward[rows, :, kicking] = knee / np.linalg.norm(knee, axis=-1, keepdims=True)
    on_floor = (t <= keys[:, 1, None]) | (t >= keys[:, 6, None])
    drive.support[rows, :, kicking] = on_floor
    drive.contacts[rows, :, kicking] = on_floor
    drive.contacts[rows, :, kicking + 2] = on_floor

    # weight over the supporting foot, trunk leaning back (front kick) or away (side kick), arms on guard
    engaged = keyframes(keys, np.stack([zero, *[one] * 6, zero], axis=1), t)
    shift = (p["hip_shift"] * p["width"] * bodies.hip_width)[:, None] * engaged
    drive.root_position[..., :2] = on_heading(centre[:, None], heading[:, None], 0.0, -side * shift)
    drive.root_position[..., 2] = bodies.root_height[:, None] - 0.03 * leg[:, None] * engaged
    lean = keyframes(keys, held(0.5 * p["lean"], p["lean"]), t)
    back, away = np.where(front, lean, 0.0), np.where(front, 0.0, side * lean)
    drive.root_rotation = rig.euler_matrix(0.4 * away, -0.4 * back, heading[:, None] + 0 * t)
    chest = rig.euler_matrix(0.6 * away / 3, -0.6 * back / 3, 0 * t)
    for name in ("spine1", "spine2", "spine3"):
        drive.local[:, :, JOINT[name]] = chest
    head = rig.euler_matrix(-away / 2, back / 2, 0 * t)  # the head stays level
    drive.local[:, :, JOINT["neck"]] = head
    drive.local[:, :, JOINT["head"]] = head
    for name, sign in (("left", 1.0), ("right", -1.0)):
        guard = rig.euler_matrix(sign * 0.3 * engaged, -p["guard_shoulder"][:, None] * engaged, 0 * t)
        drive.local[:, :, JOINT[f"{name}_shoulder"]] = guard
        drive.local[:, :, JOINT[f"{name}_elbow"]] = rig.pitch_matrix(-p["guard_elbow"][:, None] * engaged)
    return drive
