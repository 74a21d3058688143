"""Non-periodic actions: jump and lift. Each clip stands still, performs one event at a random time, and
stands still again (the first and last frames are a neutral standing pose at rest).

Both are keyframed in time (:func:`motionlab.data.curves.keyframes`): the pelvis, trunk, head and arms
follow monotone cubic curves through a few poses; the legs are solved from the feet by
:func:`motionlab.data.body.pose`. The jump's flight is ballistic: between take-off and landing the
pelvis height is the parabola of free fall (g = 9.81 m/s^2) with matching take-off and landing
velocities, and the take-off height is where the legs are fully stretched with the heels up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionlab.data import rig
from motionlab.data.body import BodyBatch, Drive, foot_pose, footprints, on_heading, plant, root_height_limit
from motionlab.data.curves import bump, ease, hermite_keys, keyframes, place_event
from motionlab.data.styles import Draws, Range
from motionlab.skeleton import JOINT

GRAVITY = 9.81

JUMP_MODES = ("vertical", "forward")
LIFT_MODES = ("squat", "stoop")

#: Jump parameters: (lo, hi) shared, or one (lo, hi) per mode of JUMP_MODES. Lengths in metres or
#: fractions of the leg length (``*_leg``), angles in radians, durations in seconds.
JUMP: dict[str, Range] = {
    "prep": (0.45, 0.7),  # standing to the bottom of the countermovement
    "push": (0.2, 0.3),  # bottom to take-off
    "rise": ((0.22, 0.4), (0.1, 0.2)),  # pelvis rise from take-off to the top of the flight
    "distance": ((-0.05, 0.1), (0.6, 1.2)),  # forward travel
    "drift": (-0.08, 0.08),  # sideways travel
    "turn": (-0.3, 0.3),  # change of heading in the air
    "absorb": (0.15, 0.3),  # landing to the lowest point
    "recover": (0.5, 0.8),  # lowest point to standing
    "crouch_leg": (0.2, 0.32),  # pelvis drop at the bottom of the countermovement
    "landing_crouch_leg": (0.12, 0.25),  # pelvis drop after landing
    "hips_back_leg": (0.05, 0.12),  # pelvis behind the feet at the bottom
    "lean_leg": ((0.0, 0.06), (0.15, 0.25)),  # pelvis ahead of the feet at take-off
    "land_reach_leg": ((0.0, 0.05), (0.1, 0.2)),  # feet ahead of the pelvis at landing
    "trunk": ((0.35, 0.6), (0.5, 0.8)),  # trunk pitch at the bottom
    "trunk_takeoff": ((0.0, 0.12), (0.25, 0.45)),
    "trunk_landing": (0.3, 0.55),
    "arm_back": (0.5, 0.9),  # shoulders swung back at the bottom
    "arm_up": ((2.3, 2.9), (1.5, 2.1)),  # shoulders swung forward and up at take-off
    "elbow": (0.15, 0.45),
    "heel_up": (0.7, 1.0),  # foot pitch at take-off
    "land_pitch": (0.3, 0.55),  # foot pitch at touchdown (toes first)
    "tuck_leg": ((0.05, 0.15), (0.15, 0.3)),  # feet drawn up in mid-flight
    "width": (0.9, 1.3),  # half-distance of the feet / hip width
    "toe_out": (0.05, 0.25),
}

#: Lift parameters per mode of LIFT_MODES (squat: knees deep, trunk fairly upright; stoop: legs nearly
#: straight, trunk bent forward over the hips).
LIFT: dict[str, Range] = {
    "descend": (0.7, 1.1),  # standing to the bottom
    "grasp": (0.2, 0.5),  # time at the bottom
    "raise": (0.8, 1.3),  # bottom to standing
    "drop_leg": ((0.44, 0.56), (0.1, 0.2)),  # pelvis drop
    "back_leg": ((0.08, 0.16), (0.12, 0.22)),  # pelvis moves back
    "tilt": ((0.5, 0.75), (1.0, 1.3)),  # pelvis pitch at the bottom
    "spine": ((0.2, 0.4), (0.45, 0.7)),  # spine flexion at the bottom (over three joints)
    "look": ((0.5, 0.8), (0.2, 0.5)),  # fraction of the trunk pitch the neck and head undo
    "reach": ((0.0, 0.2), (-0.1, 0.1)),  # shoulders forward beyond hanging
    "elbow": ((0.05, 0.25), (0.0, 0.15)),
    "width": ((1.3, 1.7), (0.9, 1.2)),
    "toe_out": ((0.2, 0.4), (0.05, 0.15)),
}


@dataclass(frozen=True)
class _JumpPelvis:
    """The pelvis's horizontal path and orientation as keyframe curves of a batch of jumps."""

    keys: np.ndarray  # (B, 6) key times: start, bottom, take-off, landing, lowest, end
    centre: np.ndarray  # (B, 2) between the feet at the start
    heading: np.ndarray  # (B,) facing direction at the start
    forward: np.ndarray  # (B, 6) pelvis ahead of the start centre, along the start heading
    sideways: np.ndarray  # (B, 6) and to its left
    yaw: np.ndarray  # (B, 6)
    trunk: np.ndarray  # (B, 6) trunk pitch, shared 45 / 55 by pelvis and spine

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal position ``(B, M, 2)`` and rotation ``(B, M, 3, 3)`` at ``times`` ``(M,)`` or ``(B,
        M)``."""
        xy = on_heading(
            self.centre[:, None],
            self.heading[:, None],
            keyframes(self.keys, self.forward, times),
            keyframes(self.keys, self.sideways, times),
        )
        pitch = 0.45 * keyframes(self.keys, self.trunk, times)
        return xy, rig.euler_matrix(0 * pitch, pitch, keyframes(self.keys, self.yaw, times))

    def velocity(self, times: np.ndarray) -> np.ndarray:
        """Horizontal velocity ``(B, M, 2)`` at per-clip ``times`` ``(B, M)`` (central difference)."""
        return (self.at(times + 1e-4)[0] - self.at(times - 1e-4)[0]) / 2e-4


def jump(draws: Draws, bodies: BodyBatch, n_frames: int, fps: int) -> Drive:
    """A :class:`Drive` for ``B`` jump clips (countermovement, flight, landing)."""
    p = draws.table(JUMP)
    centre, heading0 = draws.start(0.5)
    where = draws.unit()
    leg, zero = bodies.leg, np.zeros(len(bodies.body))
    t = np.arange(n_frames) / fps

    # timing: a sped-up event (short clips) is a shorter, equally high jump under a stronger gravity
    flight_time = 2 * np.sqrt(2 * p["rise"] / GRAVITY)
    start, scale = place_event(
        p["prep"] + p["push"] + flight_time + p["absorb"] + p["recover"], n_frames, fps, where
    )
    keys = start[:, None] + scale[:, None] * np.cumsum(
        np.stack([zero, p["prep"], p["push"], flight_time, p["absorb"], p["recover"]], axis=1), axis=1
    )
    _, t_bottom, t_off, t_land, t_low, t_end = keys.T
    flight, gravity = t_land - t_off, GRAVITY / scale**2

    heading1 = heading0 + p["turn"]
    half_width = p["width"] * bodies.hip_width
    before, yaw0 = footprints(centre, heading0, half_width, p["toe_out"], bodies)
    after, yaw1 = footprints(
        on_heading(centre, heading0, p["distance"], p["drift"]), heading1, half_width, p["toe_out"], bodies
    )
    landing_x = p["distance"] - p["land_reach_leg"] * leg
    pelvis = _JumpPelvis(
        keys=keys,
        centre=centre,
        heading=heading0,
        forward=np.stack(
            [
                zero,
                -p["hips_back_leg"] * leg,
                p["lean_leg"] * leg,
                landing_x,
                landing_x - 0.5 * p["hips_back_leg"] * leg,
                p["distance"],
            ],
            axis=1,
        ),
        sideways=p["drift"][:, None] * np.array([0, 0, 0, 1, 1, 1.0]),
        yaw=np.stack([heading0, heading0, heading0, heading1, heading1, heading1], axis=1),
        trunk=np.stack([zero, p["trunk"], p["trunk_takeoff"], 0.1 + zero, p["trunk_landing"], zero], axis=1),
    )

    # feet on the floor: the heels rise faster and faster until take-off; the toes land first, then the heels
    ball, heel = bodies.ball[:, None], bodies.heel[:, None]
    rise_start = t_bottom + 0.3 * (t_off - t_bottom)
    heel_down = t_land + 0.35 * (t_low - t_land)

    def pitch_before(times: np.ndarray) -> np.ndarray:
        rising = np.clip((times - rise_start[:, None]) / (t_off - rise_start)[:, None], 0, 1)
        return p["heel_up"][:, None] * rising**2

    def pitch_after(times: np.ndarray) -> np.ndarray:
        lowering = np.clip((times - t_land[:, None]) / (heel_down - t_land)[:, None], 0, 1)
        return p["land_pitch"][:, None] * (1 - lowering) ** 2

    def ankles(footprint: np.ndarray, yaw: np.ndarray, pitch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ankles ``(B, M, 2, 3)`` and foot rotations of both feet rolled by ``pitch`` ``(B, M)``."""
        return foot_pose(footprint[:, None], yaw[:, None], pitch[..., None], ball[:, None], heel[:, None])

    ground_before, ground_after = ankles(before, yaw0, pitch_before(t)), ankles(after, yaw1, pitch_after(t))
    takeoff_ankle = ankles(before, yaw0, pitch_before(t_off[:, None]))[0][:, 0]
    landing_ankle = ankles(after, yaw1, pitch_after(t_land[:, None]))[0][:, 0]

    # pelvis height: nearly stretched legs at take-off and landing, free fall in between
    xy_off, rotation_off = pelvis.at(t_off[:, None])
    xy_land, rotation_land = pelvis.at(t_land[:, None])
    z_off = root_height_limit(xy_off, rotation_off, takeoff_ankle[:, None], bodies).min(axis=-1)[:, 0] - 0.02
    z_land = (
        root_height_limit(xy_land, rotation_land, landing_ankle[:, None], bodies).min(axis=-1)[:, 0] - 0.02
    )
    v_off = (z_land - z_off) / flight + gravity * flight / 2
    v_land = v_off - gravity * flight
    stand = bodies.root_height
    heights = np.stack(
        [stand, stand - p["crouch_leg"] * leg, z_off, z_land, stand - p["landing_crouch_leg"] * leg, stand],
        axis=1,
    )
    drive = Drive.standing(len(bodies.body), n_frames)
    plant(drive, before, yaw0)
    drive.root_position[..., :2], drive.root_rotation = pelvis.at(t)
    drive.root_position[..., 2] = hermite_keys(
        keys, heights, np.stack([zero, zero, v_off, v_land, zero, zero], 1), t
    )

    # in the air the stretched legs first move with the pelvis, tuck, and stretch again to land
    s = np.clip((t - t_off[:, None]) / flight[:, None], 0, 1)
    rel_off = takeoff_ankle - np.concatenate([xy_off, z_off[:, None, None]], -1)
    rel_land = landing_ankle - np.concatenate([xy_land, z_land[:, None, None]], -1)
    rel = rel_off[:, None] + (rel_land - rel_off)[:, None] * ease(s)[..., None, None]
    rel[..., 2] += (p["tuck_leg"] * leg)[:, None, None] * bump(s)[..., None]
    air_yaw = yaw0[:, None] + (yaw1 - yaw0)[:, None] * ease(s)[..., None]
    air_pitch = (
        p["heel_up"][:, None, None] + (p["land_pitch"] - p["heel_up"])[:, None, None] * ease(s)[..., None]
    )

    in_air = (t > t_off[:, None]) & (t < t_land[:, None])
    landed = t >= t_land[:, None]
    drive.ankle[:] = np.where(
        in_air[..., None, None],
        drive.root_position[:, :, None] + rel,
        np.where(landed[..., None, None], ground_after[0], ground_before[0]),
    )
    drive.foot_rotation[:] = np.where(
        in_air[..., None, None, None],
        rig.matmul(rig.yaw_matrix(air_yaw), rig.pitch_matrix(air_pitch)),
        np.where(landed[..., None, None, None], ground_after[1], ground_before[1]),
    )
    knee_yaw = np.where(landed[..., None], yaw1[:, None], np.where(in_air[..., None], air_yaw, yaw0[:, None]))
    drive.knee_forward[:] = np.stack([np.cos(knee_yaw), np.sin(knee_yaw), np.zeros_like(knee_yaw)], axis=-1)
    drive.support[:] = ~in_air[..., None]
    flat = (t <= rise_start[:, None]) | (t >= heel_down[:, None])
    drive.contacts[:, :, :2] = flat[..., None]
    drive.contacts[:, :, 2:] = ~in_air[..., None]

    # trunk, head, and arms swung back in the countermovement and up by mid-flight
    trunk = keyframes(keys, pelvis.trunk, t)
    spine = rig.pitch_matrix(0.55 * trunk / 3)
    for name in ("spine1", "spine2", "spine3"):
        drive.local[:, :, JOINT[name]] = spine
    head = rig.pitch_matrix(-0.6 * trunk / 2)
    drive.local[:, :, JOINT["neck"]] = head
    drive.local[:, :, JOINT["head"]] = head
    arm_keys = np.stack([start, t_bottom, 0.5 * (t_off + t_land), t_low, t_end], axis=1)
    arm = keyframes(arm_keys, np.stack([zero, p["arm_back"], -p["arm_up"], -0.4 * p["arm_up"], zero], 1), t)
    elbow = keyframes(arm_keys, np.stack([zero, p["elbow"], 0.5 * p["elbow"], 1.5 * p["elbow"], zero], 1), t)
    for name, sign in (("left", 1.0), ("right", -1.0)):
        drive.local[:, :, JOINT[f"{name}_shoulder"]] = rig.euler_matrix(
            sign * 0.15 * (1 - np.cos(arm)), arm, 0 * t
        )
        drive.local[:, :, JOINT[f"{name}_elbow"]] = rig.pitch_matrix(-elbow)
    return drive


def lift(draws: Draws, bodies: BodyBatch, n_frames: int, fps: int) -> Drive:
    """A :class:`Drive` for ``B`` clips of lifting an object from the floor (squat or stoop)."""
    p = draws.table(LIFT)
    centre, heading = draws.start(0.5)
    where = draws.unit()
    leg = bodies.leg
    t = np.arange(n_frames) / fps
    start, scale = place_event(p["descend"] + p["grasp"] + p["raise"], n_frames, fps, where)
    t_bottom = start + scale * p["descend"]
    t_grasp = t_bottom + scale * p["grasp"]
    keys = np.stack([start, t_bottom, t_grasp, t_grasp + scale * p["raise"]], axis=1)

    def held(value: np.ndarray) -> np.ndarray:
        """Keys ``(B, 4)``: 0 standing, ``value`` at the bottom and while grasping, 0 standing again."""
        zero = np.zeros_like(value)
        return np.stack([zero, value, value, zero], axis=1)

    drive = Drive.standing(centre.shape[0], n_frames)
    ankles, yaw = footprints(centre, heading, p["width"] * bodies.hip_width, p["toe_out"], bodies)
    plant(drive, ankles, yaw)

    back = keyframes(keys, held(p["back_leg"] * leg), t)
    drive.root_position[..., :2] = on_heading(centre[:, None], heading[:, None], -back, 0.0)
    drive.root_position[..., 2] = bodies.root_height[:, None] - keyframes(keys, held(p["drop_leg"] * leg), t)
    tilt = keyframes(keys, held(p["tilt"]), t)
    bend = keyframes(keys, held(p["spine"]), t)
    drive.root_rotation = rig.euler_matrix(0 * t, tilt, heading[:, None] + 0 * t)
    spine = rig.pitch_matrix(bend / 3)
    for name in ("spine1", "spine2", "spine3"):
        drive.local[:, :, JOINT[name]] = spine
    head = rig.pitch_matrix(-p["look"][:, None] * (tilt + bend) / 2)
    drive.local[:, :, JOINT["neck"]] = head
    drive.local[:, :, JOINT["head"]] = head
    reach = keyframes(keys, held(p["reach"]), t)
    elbow = keyframes(keys, held(p["elbow"]), t)
    for name, sign in (("left", 1.0), ("right", -1.0)):
        hanging = rig.euler_matrix(
            sign * 0.1 * reach, -(tilt + bend + reach), 0 * t
        )  # vertical, plus the reach
        drive.local[:, :, JOINT[f"{name}_shoulder"]] = hanging
        drive.local[:, :, JOINT[f"{name}_elbow"]] = rig.pitch_matrix(-elbow)
    return drive
