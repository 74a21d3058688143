"""All generators on one benchmark (chapter 09): the same test clips, evaluator, sample count and frame rate.

Each model family was measured in its own chapter on its own terms (MoGlow on locomotion at 30 fps, TrajeVAE
at 15 fps, ODMO at 10 fps upsampled to 30, MDM at 15 fps). Here every generator gets the *same* held-out
clips, the benchmark's test clips of :data:`COMMON_ACTIONS` (locomotion, which every model was trained on),
and produces one sample per clip from what that clip gives it (:attr:`Method.given`): the Motion Cell its
action and body type, MoGlow the clip's root-velocity control and its first frames, TrajeVAE its first pose
and the pelvis trajectory, ODMO its action and end point, MDM its action. Every output is resampled to
:data:`FPS` (linear interpolation in time, :func:`resample`) and its last :data:`FRAMES` frames are
measured, so a seed of real frames never counts.

The models are the chapters' own, loaded from the checkpoint cache through each family's ``runs`` (trained
with their chapters' settings when the cache does not hold them: MDM's chapter, 11, runs after chapter 09).
:func:`method_row` measures a method on ``n_repeats`` sample sets and returns means with 95 % intervals.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import torch
from torch import Tensor, nn

from motionlab.data.store import MotionSet
from motionlab.evaluation.benchmark import Benchmark, feature_metrics
from motionlab.evaluation.evaluator import Evaluator
from motionlab.metrics import (
    Interval,
    bone_length_drift,
    foot_skating,
    ground_penetration,
    jerk,
    mean_ci,
)
from motionlab.models.diffusion import experiment as diffusion
from motionlab.models.diffusion.data import prepare as prepare_mdm
from motionlab.models.moglow import experiment as moglow
from motionlab.models.moglow.data import clip_features, select_actions
from motionlab.models.moglow.sampling import generate_motion, seed_features
from motionlab.models.motion_cell import experiment as motion_cell
from motionlab.models.odmo import experiment as odmo
from motionlab.models.odmo.data import prepare
from motionlab.models.odmo.sampling import ODMOSampler
from motionlab.models.trajevae import experiment as trajevae
from motionlab.models.trajevae.data import FPS as TRAJEVAE_FPS
from motionlab.models.trajevae.data import completion_windows, decimate
from motionlab.models.trajevae.masks import given_trajectories, joint_mask
from motionlab.train.many import train_meanwhile
from motionlab.train.run import Run
from motionlab.validation import check_scalar, check_tensor

#: The actions of the common test set: locomotion, MoGlow's task (its chapter adds only wave), which every
#: generator was trained on.
COMMON_ACTIONS = ("walk", "jog")

#: The common frame rate (the data's).
FPS = 30

#: Frames measured per clip: the last 3.5 s of every output (MoGlow's first frames are a real seed).
FRAMES = 105

#: Columns of the comparison, with the direction that is better ("→ real": closest to the real row).
COLUMNS: dict[str, str] = {
    "accuracy": "↑",
    "fid": "↓",
    "diversity": "→ real",
    "multimodality": "→ real",
    "apd": "m, spread per condition",
    "skating": "→ real",
    "penetration": "↓",
    "jerk": "→ real",
    "bone_drift": "↓",
}


def resample(positions: Tensor, source_fps: float, target_fps: float) -> Tensor:
    """Clips ``(N, T, J, 3)`` at ``source_fps`` resampled to ``target_fps`` by linear interpolation in time.

    The output covers the same time span, ``floor((T - 1) * target / source) + 1`` frames.
    """
    check_tensor(positions, "positions", "resample", ndim=4, trailing=(None, 3))
    check_scalar(source_fps, "source_fps", "resample", minimum=0, include_minimum=False)
    check_scalar(target_fps, "target_fps", "resample", minimum=0, include_minimum=False)
    n_frames = positions.shape[1]
    out_frames = int(np.floor((n_frames - 1) * target_fps / source_fps + 1e-9)) + 1
    t = torch.arange(out_frames, dtype=torch.float64) * source_fps / target_fps
    lower = t.floor().long().clamp(max=n_frames - 1)
    upper = (lower + 1).clamp(max=n_frames - 1)
    weight = (t - lower).to(positions.dtype)[None, :, None, None]
    return positions[:, lower] * (1 - weight) + positions[:, upper] * weight


@dataclass(frozen=True)
class CommonTest:
    """The common test set: clips ``(N, 120, J, 3)`` at 30 fps, their ``action`` and ``body`` ``(N,)``, and
    the evaluator's features ``(M, D)`` of the training clips of the same actions (FID's reference)."""

    clips: MotionSet
    train_clips: MotionSet

    @property
    def positions(self) -> Tensor:
        return torch.from_numpy(self.clips.positions)

    @property
    def action(self) -> np.ndarray:
        return np.asarray(self.clips.action)


def common_test(benchmark: Benchmark) -> CommonTest:
    """The test and training clips of :data:`COMMON_ACTIONS` (labels keep the benchmark's action ids)."""
    return CommonTest(
        select_actions(benchmark.test, COMMON_ACTIONS), select_actions(benchmark.train, COMMON_ACTIONS)
    )


@dataclass
class Method:
    """One generator on the common benchmark.

    Attributes:
        name: the method; given: what it is given per test clip; model: the trained network.
        train_seconds: how long its chapter's training took (from the cached training result).
        generate: ``generate(generator) -> (N, T, J, 3)`` one sample per test clip at :data:`FPS` (at least
            :data:`FRAMES` frames).
        generate_one: ``generate_one(generator)`` one sample of the first test clip (batch 1, for speed).
        chapter: where the model comes from.
        seed_frames: leading output frames that are given, not generated (MoGlow's seed of real frames).
    """

    name: str
    given: str
    model: nn.Module
    train_seconds: float
    generate: Callable[[torch.Generator], Tensor]
    generate_one: Callable[[torch.Generator], Tensor]
    chapter: str
    seed_frames: int = 0

    @property
    def parameters(self) -> int:
        return sum(p.numel() for p in self.model.parameters())


def _select(n: int | None, count: int) -> slice:
    return slice(0, count if n is None else min(n, count))


def motion_cell_methods(benchmark: Benchmark, test: CommonTest) -> dict[str, Method]:
    """Chapter 04's Motion Cell, given each test clip's action and body type."""
    cfg = motion_cell.ExperimentConfig.current()
    data = motion_cell.prepare_training_data(benchmark.train, benchmark.val, cfg, progress=False)
    model, result = motion_cell.runs(cfg, data)["mcell"].train(progress=False)
    model.eval()
    action = torch.as_tensor(test.clips.action, dtype=torch.int64)
    body = torch.as_tensor(test.clips.body, dtype=torch.int64)
    n_frames = test.clips.positions.shape[1]

    @torch.no_grad()
    def generate(generator: torch.Generator, n: int | None = None) -> Tensor:
        pick = _select(n, len(action))
        poses = model.generate(action[pick], body[pick], n_frames, generator)
        return model.codec.positions(poses, body[pick])

    method = Method(
        "Motion Cell",
        "action label, body type",
        model,
        result.metrics["train_seconds"],
        generate,
        lambda g: generate(g, 1),
        "04",
    )
    return {"Motion Cell": method}


def moglow_methods(benchmark: Benchmark, test: CommonTest, temperature: float = 0.5) -> dict[str, Method]:
    """Chapter 06's MoGlow with the paper's history dropout 0.95 (``"MoGlow"``) and without dropout
    (``"MoGlow p=0"``, the chapter's better variant on our data), each given every test clip's root-velocity
    control and its first ``history`` frames as the seed; sampled at the chapter's ``temperature``."""
    ex = moglow.ExperimentConfig.current()
    data = moglow.load_data(ex, benchmark)
    named = moglow.runs(ex, data)
    raw = clip_features(test.clips, replace(ex.data, actions=COMMON_ACTIONS), augment=False)

    def method(name: str, dropout: float) -> Method:
        model, result = named[moglow.moglow_name(dropout)].train(progress=False)
        model.eval()
        history = model.cfg.history
        seed = seed_features(raw, range(raw.pose.shape[0]), history)
        control = raw.control[:, 1 + history :]
        if control.shape[1] < FRAMES:  # the measured frames must all be generated ones
            raise ValueError(
                f"moglow_methods: {control.shape[1]} generated frames, fewer than FRAMES = {FRAMES}"
            )

        @torch.no_grad()
        def generate(generator: torch.Generator, n: int | None = None) -> Tensor:
            pick = _select(n, control.shape[0])
            part = type(seed)(seed.pose[pick], seed.control[pick])
            return generate_motion(model, data.scalers, control[pick], part, temperature, generator).positions

        return Method(
            name,
            "control (root velocity) every frame, seed frames",
            model,
            result.metrics["train_seconds"],
            generate,
            lambda g: generate(g, 1),
            "06",
            history,
        )

    return {"MoGlow": method("MoGlow", 0.95), "MoGlow p=0": method("MoGlow p=0", 0.0)}


def trajevae_methods(benchmark: Benchmark, test: CommonTest) -> dict[str, Method]:
    """Chapter 07's TrajeVAE (the last rung), given each test clip's first pose and its pelvis trajectory
    (k = 1 joint), at its 15 fps; its completions are resampled to 30 fps."""
    cfg = trajevae.ExperimentConfig.current()
    name = trajevae.RUNGS[-1]
    run = trajevae.completion_run(
        trajevae.CACHE_NAMES[name],
        trajevae.ladder(cfg.trajevae)[name],
        cfg.train,
        decimate(benchmark.train.positions),
        decimate(benchmark.train.rotations),
        (decimate(benchmark.val.positions), decimate(benchmark.val.rotations)),
    )
    model, result = run.train(progress=False)
    model.eval()
    windows = completion_windows(decimate(test.clips.positions))
    mask = joint_mask(("pelvis",)).expand(windows.shape[0], -1)
    trajectories = given_trajectories(windows[:, 1:], mask)

    @torch.no_grad()
    def generate(generator: torch.Generator, n: int | None = None) -> Tensor:
        pick = _select(n, windows.shape[0])
        # K = 1 would decode the prior's mean (the deterministic completion): draw two, keep the first
        completed = model.sample(windows[pick, 0], trajectories[pick], 2, generator=generator)[:, 0]
        clip = torch.cat([windows[pick, :1], completed], dim=1)
        return resample(clip.reshape(clip.shape[0], clip.shape[1], -1, 3), TRAJEVAE_FPS, FPS)

    method = Method(
        "TrajeVAE",
        "initial pose, pelvis trajectory (k = 1)",
        model,
        result.metrics["train_seconds"],
        generate,
        lambda g: generate(g, 1),
        "07",
    )
    return {"TrajeVAE": method}


def odmo_methods(benchmark: Benchmark, test: CommonTest) -> dict[str, Method]:
    """Chapter 08's ODMO with mode-preserving sampling, given each test clip's action and end point (its
    root's last position, in the clip's own start frame)."""
    cfg = odmo.ExperimentConfig.current()
    train_data = prepare(benchmark.train, cfg.frame_stride, val=benchmark.val)
    model, result = odmo.runs(cfg, train_data)["ODMO"].train(progress=False)
    model.eval()
    sampler = ODMOSampler.from_data(model, train_data, kind="modes")
    end_points = prepare(test.clips, cfg.frame_stride, train_data.floor_clearance).end_point.numpy()
    action = test.action

    def generate(generator: torch.Generator, n: int | None = None) -> Tensor:
        pick = _select(n, len(action))
        rng = np.random.default_rng(generator.initial_seed())
        codes = np.zeros((len(action[pick]), model.cfg.code_dim))
        for a in np.unique(action[pick]):
            where = np.flatnonzero(action[pick] == a)
            codes[where] = sampler.modes.sample(int(a), len(where), rng)[0]
        with torch.no_grad():
            return sampler.generate(codes, action[pick], end_points[pick])[0]

    method = Method(
        "ODMO",
        "action label, end point",
        model,
        result.metrics["train_seconds"],
        generate,
        lambda g: generate(g, 1),
        "08",
    )
    return {"ODMO": method}


#: DDIM steps of MDM's samples here, fewer than chapter 11's 25: this comparison draws five sample sets of
#: every test clip for every generator.
MDM_SAMPLE_STEPS = 10


def diffusion_runs(benchmark: Benchmark) -> dict[str, Run]:
    """Chapter 11's run ``"mdm"`` (its settings, the benchmark's training clips) ``{"mdm": Run}``."""
    cfg = diffusion.ExperimentConfig.current()
    train, val = (prepare_mdm(split, cfg.frame_stride) for split in (benchmark.train, benchmark.val))
    return {diffusion.DEFAULT_RUN: diffusion.variant_runs(cfg, train, val)[diffusion.DEFAULT_RUN]}


def diffusion_methods(benchmark: Benchmark, test: CommonTest) -> dict[str, Method]:
    """Chapter 11's MDM (its run ``"mdm"``, with the geometric losses), given each test clip's action and
    sampled with its chapter's fast sampler (``diffusion.experiment.generate_positions``:
    DDIM on a respaced schedule, classifier-free guidance) at :data:`MDM_SAMPLE_STEPS` steps (at most the
    chapter's); its 15 fps frames are interpolated to 30 fps and posed on the average skeleton (MDM is not
    told the body type)."""
    chapter_cfg = diffusion.ExperimentConfig.current()
    cfg = replace(chapter_cfg, sample_steps=min(chapter_cfg.sample_steps, MDM_SAMPLE_STEPS))
    model, result = diffusion_runs(benchmark)[diffusion.DEFAULT_RUN].train(progress=False)
    model.eval()
    action = torch.as_tensor(test.clips.action, dtype=torch.int64)

    def generate(generator: torch.Generator, n: int | None = None) -> Tensor:
        return diffusion.generate_positions(model, cfg, action[_select(n, len(action))], generator)

    method = Method(
        "MDM",
        "action label",
        model,
        result.metrics["train_seconds"],
        generate,
        lambda g: generate(g, 1),
        "11",
    )
    return {"MDM": method}


#: Each family's methods ``{name: Method}``, in the course's order.
METHODS: tuple[Callable[[Benchmark, CommonTest], dict[str, Method]], ...] = (
    motion_cell_methods,
    moglow_methods,
    trajevae_methods,
    odmo_methods,
    diffusion_methods,
)


def load_methods(benchmark: Benchmark, test: CommonTest, processes: int | None = None) -> dict[str, Method]:
    """Every method of the comparison by name, in :data:`METHODS`' order (the models from the checkpoint
    cache). MDM's chapter (11) comes after this one, so a first run of the course trains MDM here: its run
    trains in a worker while the other families load (:func:`~motionlab.train.many.train_meanwhile`)."""

    def earlier_chapters() -> dict[str, Method]:
        families = [family for family in METHODS if family is not diffusion_methods]
        return {name: method for family in families for name, method in family(benchmark, test).items()}

    methods = train_meanwhile(diffusion_runs(benchmark), earlier_chapters, processes)
    return methods | diffusion_methods(benchmark, test)


def measured_part(positions: Tensor) -> Tensor:
    """The last :data:`FRAMES` frames of clips ``(N, T, J, 3)`` (float32)."""
    if positions.shape[1] < FRAMES:
        raise ValueError(f"measured_part: clips need at least {FRAMES} frames, got {positions.shape[1]}")
    return torch.as_tensor(positions, dtype=torch.float32)[:, -FRAMES:]


def set_metrics(
    evaluator: Evaluator,
    positions: Tensor,
    action: np.ndarray,
    reference: Tensor,
    parents: np.ndarray,
    rng: np.random.Generator,
) -> dict[str, float]:
    """The per-set columns of :data:`COLUMNS` (all but APD) for clips ``(N, FRAMES, J, 3)`` of ``action``;
    ``"skating"`` is left out when no foot of the set is planted on two consecutive frames (the metric is
    undefined: the samples' feet never stand still, as a generator's that samples noise)."""
    features, probs = evaluator.features_and_probs(positions, "action")
    row = feature_metrics(features, probs, action, reference, rng)
    row.pop("is")
    skating = foot_skating(positions, fps=FPS, never_planted="nan")
    if not math.isnan(skating):
        row["skating"] = skating
    row["penetration"] = ground_penetration(positions)
    row["jerk"] = jerk(positions, fps=FPS)
    row["bone_drift"] = bone_length_drift(positions, parents)
    return row


def per_clip_apd(sets: list[Tensor]) -> np.ndarray:
    """APD of each test clip over the sample sets: the mean distance (m, whole pose sequence flattened)
    between the samples that different repeats drew for the same clip, ``(N,)``."""
    stacked = torch.stack([s.flatten(2).flatten(1) for s in sets], dim=1).double()  # (N, R, T*J*3)
    distances = torch.cdist(stacked, stacked)
    n_sets = len(sets)
    return (distances.sum(dim=(1, 2)) / (n_sets * (n_sets - 1))).numpy()


@dataclass(frozen=True)
class MethodRow:
    """One method's measurements: ``{column: Interval}`` and its sample sets ``(N, FRAMES, J, 3)``."""

    intervals: dict[str, Interval]
    sets: tuple[Tensor, ...]
    seconds: float


def _interval(values: np.ndarray | list[float]) -> Interval:
    mean, half = mean_ci(np.asarray(values, dtype=np.float64))
    return Interval(mean, half, tuple(float(v) for v in values), 0.95)


def measure_sets(
    sets: list[Tensor], evaluator: Evaluator, test: CommonTest, reference: Tensor, seed: int = 0
) -> dict[str, Interval]:
    """``{column: Interval}`` over sample sets (each ``(N, FRAMES, J, 3)``, one sample per test clip); APD's
    interval is over test clips, the others over the sets. The real row passes the test clips once per
    repeat (the repeats redraw the Diversity and Multimodality pairs): it has no APD (one clip per
    condition). A column that some set leaves undefined (skating, :func:`set_metrics`) is left out."""
    parents = test.clips.parents
    rows = [
        set_metrics(evaluator, s, test.action, reference, parents, np.random.default_rng([seed, r]))
        for r, s in enumerate(sets)
    ]
    intervals = {key: _interval([row[key] for row in rows]) for key in rows[0] if all(key in r for r in rows)}
    if any(s is not sets[0] for s in sets[1:]):
        intervals["apd"] = _interval(per_clip_apd(sets))
    return {key: intervals[key] for key in COLUMNS if key in intervals}


def method_row(
    method: Method, evaluator: Evaluator, test: CommonTest, reference: Tensor, n_repeats: int, seed: int = 0
) -> MethodRow:
    """Draw ``n_repeats`` sample sets from ``method`` (seeds ``seed + r``) and measure them."""
    start = time.perf_counter()
    sets = [measured_part(method.generate(torch.Generator().manual_seed(seed + r))) for r in range(n_repeats)]
    seconds = time.perf_counter() - start
    return MethodRow(measure_sets(sets, evaluator, test, reference, seed), tuple(sets), seconds)
