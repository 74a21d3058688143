"""The catalogue of the synthetic data: six actions, each with two style modes, and their generators.

Action ids and mode ids are fixed (they are the labels of the data): actions ``walk, jog, jump, lift,
wave, kick`` are 0..5; modes are numbered across actions in this order, so every mode id is unique:

=====  ======  ==========================================================================================
mode   action  what distinguishes it
=====  ======  ==========================================================================================
0      walk    ``walk_upright``: upright trunk, brisk (1.1-1.6 m/s), clear arm swing
1      walk    ``walk_hunched``: trunk bent forward (pelvis-to-neck 16-24 degrees from vertical), head
               forward, slow (0.6-1.05 m/s), short steps, bent and nearly still arms
2      jog     ``jog_upright``: upright, 2.1-3.0 m/s, moderate knee lift
3      jog     ``jog_lean``: leaning forward (pelvis-to-neck 12-17 degrees), high knees
4      jump    ``jump_vertical``: straight up (pelvis rises 0.27-0.44 m), arms swung overhead
5      jump    ``jump_forward``: 0.6-1.2 m forward, lower flight, arms swung forward
6      lift    ``lift_squat``: deep knee bend (pelvis drops 0.35-0.46 m), trunk fairly upright
7      lift    ``lift_stoop``: legs nearly straight (pelvis drops 0.08-0.16 m), trunk bent over the hips
8      wave    ``wave_left``: left hand raised and waving
9      wave    ``wave_right``: right hand raised and waving
10     kick    ``kick_front``: leg swung forward and up, trunk leaning back
11     kick    ``kick_side``: leg swung out sideways, trunk leaning away, sole towards the target
=====  ======  ==========================================================================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from motionlab.data.body import BodyBatch, Drive
from motionlab.data.events import JUMP_MODES, LIFT_MODES, jump, lift
from motionlab.data.gait import JOG_MODES, WALK_MODES, locomotion
from motionlab.data.gestures import KICK_MODES, WAVE_MODES, kick, wave
from motionlab.data.styles import Draws

Generator = Callable[[Draws, BodyBatch, int, int], Drive]
"""``make(draws, bodies, n_frames, fps) -> Drive`` for a batch of clips of one action."""


@dataclass(frozen=True)
class Action:
    """One action: its name, its style modes (in mode-id order) and the function that drives it."""

    name: str
    modes: tuple[str, ...]
    make: Generator


CATALOGUE: tuple[Action, ...] = (
    Action("walk", WALK_MODES, partial(locomotion, jog=False)),
    Action("jog", JOG_MODES, partial(locomotion, jog=True)),
    Action("jump", JUMP_MODES, jump),
    Action("lift", LIFT_MODES, lift),
    Action("wave", WAVE_MODES, wave),
    Action("kick", KICK_MODES, kick),
)

#: Action names, indexed by action id.
ACTION_NAMES: tuple[str, ...] = tuple(a.name for a in CATALOGUE)

#: Mode names ``"<action>_<style>"``, indexed by mode id.
MODE_NAMES: tuple[str, ...] = tuple(f"{a.name}_{m}" for a in CATALOGUE for m in a.modes)

#: Action id of every mode ``(n_modes,)``.
MODE_ACTION: np.ndarray = np.array([i for i, a in enumerate(CATALOGUE) for _ in a.modes], dtype=np.int64)

#: Index of every mode within its action's modes ``(n_modes,)`` (the style a generator sees).
MODE_STYLE: np.ndarray = np.array([j for a in CATALOGUE for j in range(len(a.modes))], dtype=np.int64)
