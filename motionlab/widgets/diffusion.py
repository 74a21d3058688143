r"""Chapter 11's widgets: sample MDM per action, morph a motion between two noise seeds, and complete a
recorded clip by inpainting (in-betweening, or everything but the legs).

Each callback is a plain function of a trained :class:`~motionlab.models.diffusion.model.MDM` and the widget
values (unit-tested without a browser); the ``*_widget`` builders only wire ipywidgets to them and show
their figures.

**Conventions.** A clip is MDM features ``(T, F)``, ``F = 6 J + 3`` (:mod:`motionlab.models.diffusion.data`),
at the model's frame rate ``fps`` (15 on the benchmark: every second frame of 30); it is drawn as joint
positions ``(T, J, 3)`` by forward kinematics with the average skeleton (the course's 22 joints). Every clip
is sampled with the fast sampler: DDIM with ``eta = 0`` on a respaced schedule of ``steps`` steps
(:data:`STEP_CHOICES`), with classifier-free guidance of scale ``guidance`` (1: the plain conditional model).
With ``eta = 0`` the only randomness is the start :math:`x_S` (:func:`start_noise`), so a seed fixes the
clip.
"""

from __future__ import annotations

import numbers
import time
from collections.abc import Sequence
from typing import Literal, NamedTuple

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
import torch
from matplotlib.figure import Figure
from torch import Tensor

from motionlab.models.diffusion.data import MDMData, joint_positions, known_mask
from motionlab.models.diffusion.model import MDM
from motionlab.models.diffusion.sampling import GUIDANCE_SCALE, Edit, sample
from motionlab.skeleton import JOINT, PARENTS
from motionlab.validation import check_choice, check_scalar, check_tensor
from motionlab.viz import GENERATED_COLOR, REAL_COLOR, filmstrip
from motionlab.viz.stick_figure import Scene, common_extent, draw_stick_figure, keyframe_indices, plot_pose
from motionlab.widgets.controls import action_dropdown, wire

#: The step counts offered for the respaced DDIM schedule (those up to the model's diffusion steps).
STEP_CHOICES: tuple[int, ...] = (10, 25, 50, 100)

#: What the in-betweening editor keeps of the reference clip: ``"ends"`` its first and last ``kept`` frames
#: whole, ``"legs"`` the :data:`LEG_JOINTS`' rotations and the root position in every frame.
Keep = Literal["ends", "legs"]
KEEP_CHOICES: tuple[str, ...] = ("ends", "legs")

#: The joints kept by ``keep="legs"``: the pelvis (its rotation is the body's global orientation) and the
#: legs down to the balls of the feet; with the root position they fix where the legs are. They are the
#: repository's lower body for editing (``HML_LOWER_BODY_JOINTS`` in ``data_loaders/humanml_utils.py``,
#: whose mask keeps the root's channels with them too).
LEG_JOINTS: tuple[int, ...] = tuple(
    JOINT[name]
    for name in (
        "pelvis",
        "left_hip",
        "right_hip",
        "left_knee",
        "right_knee",
        "left_ankle",
        "right_ankle",
        "left_foot",
        "right_foot",
    )
)

#: Colour of the given part in the editor's figure (reference and completion alike).
GIVEN_COLOR = "tab:green"


def _check_model(model: MDM, where: str) -> MDM:
    if not isinstance(model, MDM):
        raise TypeError(f"{where}: model must be an MDM, got {type(model).__name__}")
    return model


def _check_action(model: MDM, action: int, where: str) -> int:
    return int(
        check_scalar(
            action, "action", where, kind=numbers.Integral, minimum=0, maximum=model.cfg.n_actions - 1
        )
    )


def _check_seed(seed: int, name: str, where: str) -> int:
    return int(check_scalar(seed, name, where, kind=numbers.Integral, minimum=0))


def _action_name(action: int, action_names: Sequence[str] | None) -> str:
    return action_names[action] if action_names is not None else f"action {action}"


def step_choices(model: MDM) -> list[int]:
    """The :data:`STEP_CHOICES` the model's schedule can be respaced to (its diffusion steps at most), or the
    model's full schedule alone when it is shorter than all of them."""
    _check_model(model, "step_choices")
    choices = [steps for steps in STEP_CHOICES if steps <= model.cfg.diffusion_steps]
    return choices or [model.cfg.diffusion_steps]


def start_noise(model: MDM, seed: int) -> Tensor:
    """The sampler's start :math:`x_S` ``(1, T, F)`` for ``seed``: the first draw of a generator seeded with
    ``seed``, so :func:`sample_motion` with ``initial_noise=start_noise(model, seed)`` and with ``seed``
    alone give the same clip."""
    _check_model(model, "start_noise")
    seed = _check_seed(seed, "seed", "start_noise")
    shape = (1, model.cfg.n_frames, model.cfg.n_features)
    return torch.randn(shape, generator=torch.Generator().manual_seed(seed))


def slerp(a: Tensor, b: Tensor, weight: float) -> Tensor:
    r"""Spherical interpolation from ``a`` (``weight = 0``) to ``b`` (``weight = 1``), tensors of one shape
    taken as single vectors: with the weight :math:`w`,

    .. math:: \operatorname{slerp}(a, b; w) = \frac{\sin((1 - w)\,\Omega)}{\sin \Omega}\, a
              + \frac{\sin(w\,\Omega)}{\sin \Omega}\, b,

    :math:`\Omega` the angle between them (from ``2 atan2(|â - b̂|, |â + b̂|)`` on the unit vectors, accurate
    at every angle; written with ``sinc`` so that :math:`\Omega \to 0` is exact).

    **Why not a straight line.** Two independent draws of :math:`\mathcal N(0, I)` in ``D = T F``
    dimensions (8,100 for the benchmark's clips) both have a norm close to :math:`\sqrt D` and are nearly
    orthogonal. Halfway along the straight line, :math:`(a + b) / 2` has a norm close to
    :math:`\sqrt{D / 2}`: it is no typical draw of the start :math:`x_S` (the sampler would start from too
    little noise, and the middle of the morph would come out damped). Along the great circle the norm stays
    near :math:`\sqrt D` (exactly when the two norms are equal), and for orthogonal ``a``, ``b`` each point
    :math:`\cos(w\pi/2)\, a + \sin(w\pi/2)\, b` is itself distributed as :math:`\mathcal N(0,
    I)`. Spherical interpolation of the start noise is what DDIM's interpolation experiments use too (Song,
    Meng and Ermon 2021).
    """
    where = "slerp"
    check_tensor(a, "a", where)
    check_tensor(b, "b", where)
    if a.shape != b.shape:
        raise ValueError(f"{where}: a and b must have one shape, got {tuple(a.shape)} and {tuple(b.shape)}")
    check_scalar(weight, "weight", where, minimum=0.0, maximum=1.0)
    norm_a, norm_b = torch.linalg.vector_norm(a), torch.linalg.vector_norm(b)
    if float(norm_a) == 0.0 or float(norm_b) == 0.0:
        raise ValueError(f"{where}: a and b must be non-zero, got norms {float(norm_a)} and {float(norm_b)}")
    unit_a, unit_b = a / norm_a, b / norm_b
    omega = 2 * torch.atan2(
        torch.linalg.vector_norm(unit_a - unit_b), torch.linalg.vector_norm(unit_a + unit_b)
    )
    sinc_omega = torch.sinc(omega / torch.pi)
    if float(sinc_omega) < 1e-6:
        raise ValueError(f"{where}: a and b point in opposite directions: no single great circle joins them")
    coefficient_a = (1 - weight) * torch.sinc((1 - weight) * omega / torch.pi) / sinc_omega
    coefficient_b = weight * torch.sinc(weight * omega / torch.pi) / sinc_omega
    return coefficient_a * a + coefficient_b * b


def sample_motion(
    model: MDM,
    action: int,
    seed: int,
    steps: int,
    guidance: float,
    *,
    initial_noise: Tensor | None = None,
    edit: Edit | None = None,
) -> Tensor:
    """One clip ``(T, F)`` of ``action``: DDIM (``eta = 0``) with ``steps`` respaced steps and guidance
    ``guidance``, started from ``initial_noise`` ``(1, T, F)`` or from :func:`start_noise` of ``seed``;
    ``edit`` (motion ``(1, T, F)``) inpaints its unknown channels. The same arguments give the same clip."""
    where = "sample_motion"
    _check_model(model, where)
    action = _check_action(model, action, where)
    seed = _check_seed(seed, "seed", where)
    check_scalar(guidance, "guidance", where, minimum=0.0)
    features = sample(
        model,
        torch.tensor([action]),
        steps=steps,
        method="ddim",
        eta=0.0,
        guidance=float(guidance),
        edit=edit,
        generator=torch.Generator().manual_seed(seed),
        initial_noise=initial_noise,
    )
    return features[0]


def clip_positions(features: Tensor) -> np.ndarray:
    """Joint positions ``(T, J, 3)`` in metres of one clip's features ``(T, F)`` (average skeleton)."""
    check_tensor(features, "features", "clip_positions", ndim=2)
    with torch.no_grad():
        return joint_positions(features).numpy()


def _sampler_words(steps: int, guidance: float) -> str:
    return f"{steps} DDIM steps, guidance {float(guidance):g}"


def _clip_strip(features: Tensor, fps: float, title: str) -> Figure:
    """Six keyframes of one sampled clip ``(T, F)`` at ``fps`` frames per second."""
    return filmstrip(
        clip_positions(features), PARENTS, n_frames=6, fps=fps, color=GENERATED_COLOR, title=title
    )


def sample_figure(
    model: MDM,
    action: int,
    seed: int,
    steps: int,
    guidance: float = GUIDANCE_SCALE,
    fps: float = 15.0,
    action_names: Sequence[str] | None = None,
) -> Figure:
    """Keyframes of the clip :func:`sample_motion` draws for ``action`` and ``seed``, titled with the sampler
    and the wall-clock time sampling took (the drawing not included)."""
    check_scalar(fps, "fps", "sample_figure", minimum=0.0, include_minimum=False)
    started = time.perf_counter()
    features = sample_motion(model, action, seed, steps, guidance)
    seconds = time.perf_counter() - started
    title = (
        f"{_action_name(action, action_names)}, seed {seed}: {_sampler_words(steps, guidance)}, "
        f"sampled in {seconds:.2f} s"
    )
    return _clip_strip(features, fps, title)


def interpolated_motion(
    model: MDM, action: int, seed_a: int, seed_b: int, weight: float, steps: int, guidance: float
) -> Tensor:
    """The clip ``(T, F)`` sampled deterministically (DDIM, ``eta = 0``) from the :func:`slerp` of the start
    noises of ``seed_a`` and ``seed_b`` at ``weight``: ``weight = 0`` gives ``seed_a``'s clip of
    :func:`sample_motion`, ``weight = 1`` ``seed_b``'s, and the clips in between change smoothly with
    ``weight``."""
    where = "interpolated_motion"
    _check_seed(seed_b, "seed_b", where)
    noise = slerp(start_noise(model, seed_a), start_noise(model, seed_b), weight)
    return sample_motion(model, action, seed_a, steps, guidance, initial_noise=noise)


def interpolation_figure(
    model: MDM,
    action: int,
    seed_a: int,
    seed_b: int,
    weight: float,
    steps: int,
    guidance: float = GUIDANCE_SCALE,
    fps: float = 15.0,
    action_names: Sequence[str] | None = None,
) -> Figure:
    """Keyframes of :func:`interpolated_motion`."""
    check_scalar(fps, "fps", "interpolation_figure", minimum=0.0, include_minimum=False)
    features = interpolated_motion(model, action, seed_a, seed_b, weight, steps, guidance)
    title = (
        f"{_action_name(action, action_names)}: start noise slerp(seed {seed_a}, seed {seed_b}; "
        f"weight = {weight:.2f}), {_sampler_words(steps, guidance)}"
    )
    return _clip_strip(features, fps, title)


def _check_data(model: MDM, data: MDMData, where: str) -> MDMData:
    if not isinstance(data, MDMData):
        raise TypeError(f"{where}: data must be MDMData, got {type(data).__name__}")
    expected = (model.cfg.n_frames, model.cfg.n_features)
    if tuple(data.features.shape[1:]) != expected:
        raise ValueError(
            f"{where}: the model makes clips of {expected[0]} frames x {expected[1]} features, the data has "
            f"{tuple(data.features.shape[1:])}"
        )
    return data


def editing_mask(n_frames: int, n_joints: int, keep: Keep, kept: int) -> Tensor:
    """Which channels of a clip the editor keeps ``(n_frames, 6 J + 3)`` bool: the first and last ``kept``
    frames (``keep="ends"``, ``1 <= kept <= n_frames // 2``), or the :data:`LEG_JOINTS`' rotations and the
    root position in every frame (``keep="legs"``, ``kept`` unused)."""
    where = "editing_mask"
    check_choice(keep, "keep", where, KEEP_CHOICES)
    check_scalar(n_frames, "n_frames", where, kind=numbers.Integral, minimum=2)
    if keep == "legs":
        return known_mask(n_frames, n_joints, joints=LEG_JOINTS, root_position=True)
    check_scalar(kept, "kept", where, kind=numbers.Integral, minimum=1, maximum=n_frames // 2)
    frames = [*range(kept), *range(n_frames - kept, n_frames)]
    return known_mask(n_frames, n_joints, frames=frames)


def fixed_joints(known: Tensor) -> Tensor:
    """Which joints' positions the known channels ``(T, 6 J + 3)`` fix, per frame ``(T, J)`` bool.

    A joint's position follows from the root position and the rotations of its ancestors (not its own), so
    it is fixed in a frame when all of those are known there (the root: when its position is).
    """
    where = "fixed_joints"
    if not isinstance(known, Tensor) or known.dtype != torch.bool or known.dim() != 2:
        raise TypeError(f"{where}: known must be a (T, 6 J + 3) bool tensor, got {known!r:.60}")
    n_joints = len(PARENTS)
    if known.shape[1] != 6 * n_joints + 3:
        raise ValueError(f"{where}: known must be (T, {6 * n_joints + 3}), got {tuple(known.shape)}")
    rotation = known[:, : 6 * n_joints].unflatten(1, (n_joints, 6)).all(dim=-1)
    fixed = torch.zeros(known.shape[0], n_joints, dtype=torch.bool)
    fixed[:, 0] = known[:, -3:].all(dim=-1)
    for joint in range(1, n_joints):  # parents come before their children
        parent = PARENTS[joint]
        fixed[:, joint] = fixed[:, parent] & rotation[:, parent]
    return fixed


class Completion(NamedTuple):
    """What the editor shows: the ``reference`` clip ``(T, F)``, the ``known`` channels ``(T, F)`` bool kept
    from it, and the ``completion`` ``(T, F)`` (equal to the reference where ``known``)."""

    reference: Tensor
    known: Tensor
    completion: Tensor


def complete_clip(
    model: MDM,
    data: MDMData,
    clip: int,
    keep: Keep,
    kept: int,
    action: int,
    seed: int,
    steps: int,
    guidance: float,
) -> Completion:
    r"""Keep part of clip ``clip`` of ``data`` (:func:`editing_mask`) and sample the rest for ``action`` by
    inpainting (MDM's editing: the known part of every prediction :math:`\hat x_0` replaced by the given
    motion, :func:`~motionlab.models.diffusion.sampling.sample`)."""
    where = "complete_clip"
    _check_model(model, where)
    _check_data(model, data, where)
    check_scalar(clip, "clip", where, kind=numbers.Integral, minimum=0, maximum=len(data) - 1)
    reference = data.features[int(clip)]
    known = editing_mask(model.cfg.n_frames, model.cfg.n_joints, keep, kept)
    completion = sample_motion(model, action, seed, steps, guidance, edit=Edit(reference[None], known))
    return Completion(reference, known, completion)


def editor_keyframes(n_frames: int, keep: Keep, kept: int) -> np.ndarray:
    """The frames the editor's figure shows (sorted indices): for ``keep="ends"`` the first and last frame,
    the given frames next to the gap (``kept - 1`` and ``n_frames - kept``) and two frames evenly inside it,
    so the seams show; for ``keep="legs"`` six frames evenly over the clip."""
    check_choice(keep, "keep", "editor_keyframes", KEEP_CHOICES)
    if keep == "legs":
        return keyframe_indices(n_frames, 6)
    inside = np.linspace(kept - 1, n_frames - kept, 4)[1:3].round()
    return np.unique(np.r_[0, kept - 1, inside, n_frames - kept, n_frames - 1].astype(np.int64))


def _draw_rows(
    rows: Sequence[tuple[str, np.ndarray, str]], fixed: np.ndarray, frames: np.ndarray, fps: float
) -> Figure:
    """One row of the keyframes ``frames`` per ``(label, positions (T, J, 3), colour)``, all at one scale, the
    joints fixed in a frame (``fixed`` ``(T, J)``) drawn over each in :data:`GIVEN_COLOR`."""
    scenes = [Scene.following(motion[frames], motion[frames, 0, :2]) for _, motion, _ in rows]
    extent = common_extent(scenes)
    panel = 2.0
    fig = plt.figure(figsize=(panel * len(frames), panel * 1.1 * len(rows)))
    for r, (label, motion, color) in enumerate(rows):
        for c, t in enumerate(frames):
            ax = fig.add_subplot(len(rows), len(frames), r * len(frames) + c + 1, projection="3d")
            scene = scenes[r].with_extent(extent).moved(motion[t, 0, :2])
            plot_pose(ax, motion[t], PARENTS, color, scene=scene)
            if fixed[t].any():
                given = np.where(
                    fixed[t][:, None], motion[t], np.nan
                )  # NaN joints and their bones are not drawn
                draw_stick_figure(ax, given, np.asarray(PARENTS), GIVEN_COLOR, linewidth=3.0)
            ax.set_title(f"{label}, t = {t / fps:.2f} s", fontsize=8)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.9, wspace=0, hspace=0.1)
    return fig


def inbetween_figure(
    model: MDM,
    data: MDMData,
    clip: int,
    keep: Keep,
    kept: int,
    action: int,
    seed: int,
    steps: int,
    guidance: float = GUIDANCE_SCALE,
    fps: float = 15.0,
    action_names: Sequence[str] | None = None,
) -> Figure:
    """Keyframes of the reference clip (top) and of :func:`complete_clip`'s completion (bottom), the part
    given to the sampler drawn over both in :data:`GIVEN_COLOR`."""
    check_scalar(fps, "fps", "inbetween_figure", minimum=0.0, include_minimum=False)
    reference, known, completion = complete_clip(model, data, clip, keep, kept, action, seed, steps, guidance)
    fixed = fixed_joints(known).numpy()
    fig = _draw_rows(
        [
            ("reference", clip_positions(reference), REAL_COLOR),
            ("completion", clip_positions(completion), GENERATED_COLOR),
        ],
        fixed,
        editor_keyframes(len(known), keep, kept),
        fps,
    )
    given = f"first and last {kept} frames" if keep == "ends" else "legs and root"
    fig.suptitle(
        f"clip {clip}: {given} given, the rest sampled for {_action_name(action, action_names)} "
        f"(seed {seed}, {_sampler_words(steps, guidance)})",
        fontsize=10,
    )
    return fig


def _steps_dropdown(model: MDM) -> widgets.Dropdown:
    choices = step_choices(model)
    return widgets.Dropdown(options=choices, value=choices[0], description="DDIM steps")


def _guidance_slider() -> widgets.FloatSlider:
    return widgets.FloatSlider(
        value=GUIDANCE_SCALE, min=0.0, max=5.0, step=0.5, description="guidance", continuous_update=False
    )


def _seed_slider(description: str = "seed", value: int = 0) -> widgets.IntSlider:
    return widgets.IntSlider(value=value, min=0, max=20, description=description, continuous_update=False)


def sample_widget(model: MDM, action_names: Sequence[str], fps: float = 15.0) -> widgets.VBox:
    """Pick an action, a seed, the number of DDIM steps and the guidance scale; see the sampled clip and the
    time sampling took. ``fps``: the model's frame rate."""
    _check_model(model, "sample_widget")
    controls = {
        "action": action_dropdown(action_names),
        "seed": _seed_slider(),
        "steps": _steps_dropdown(model),
        "guidance": _guidance_slider(),
    }
    output = widgets.Output()

    def draw(**values) -> Figure:
        return sample_figure(model, fps=fps, action_names=action_names, **values)

    wire(output, draw, controls)
    parts = list(controls.values())
    return widgets.VBox([widgets.HBox(parts[:2]), widgets.HBox(parts[2:]), output])


def interpolation_widget(model: MDM, action_names: Sequence[str], fps: float = 15.0) -> widgets.VBox:
    """Two seeds and a slider ``weight``: the clip sampled from the :func:`slerp` of their start noises."""
    _check_model(model, "interpolation_widget")
    controls = {
        "action": action_dropdown(action_names),
        "seed_a": _seed_slider("seed A", 0),
        "seed_b": _seed_slider("seed B", 1),
        "weight": widgets.FloatSlider(
            value=0.0, min=0.0, max=1.0, step=0.1, description="weight", continuous_update=False
        ),
        "steps": _steps_dropdown(model),
    }
    output = widgets.Output()

    def draw(**values) -> Figure:
        return interpolation_figure(
            model, guidance=GUIDANCE_SCALE, fps=fps, action_names=action_names, **values
        )

    wire(output, draw, controls)
    parts = list(controls.values())
    return widgets.VBox([widgets.HBox(parts[:3]), widgets.HBox(parts[3:]), output])


def inbetween_widget(
    model: MDM, data: MDMData, action_names: Sequence[str], fps: float = 15.0
) -> widgets.VBox:
    """Pick a reference clip of ``data``, keep its first and last ``kept`` frames or its legs, and sample the
    rest for an action (the clip's own when the clip is picked). Clip slider over ``data``'s clips."""
    where = "inbetween_widget"
    _check_model(model, where)
    _check_data(model, data, where)
    clip = widgets.IntSlider(value=0, min=0, max=len(data) - 1, description="clip", continuous_update=False)
    action = action_dropdown(action_names)
    action.value = int(data.action[0])
    controls = {
        "clip": clip,
        "keep": widgets.ToggleButtons(options=list(KEEP_CHOICES), value="ends", description="keep"),
        "kept": widgets.IntSlider(
            value=5, min=1, max=model.cfg.n_frames // 2, description="kept", continuous_update=False
        ),
        "action": action,
        "seed": _seed_slider(),
        "steps": _steps_dropdown(model),
    }
    output = widgets.Output()

    def draw(**values) -> Figure:
        return inbetween_figure(
            model, data, guidance=GUIDANCE_SCALE, fps=fps, action_names=action_names, **values
        )

    redraw = wire(output, draw, controls)
    clip.unobserve(redraw, names="value")

    def change_clip(change: dict) -> None:
        """Offer the new clip's own action, and draw once."""
        action.unobserve(redraw, names="value")
        action.value = int(data.action[change["new"]])
        action.observe(redraw, names="value")
        redraw()

    clip.observe(change_clip, names="value")
    parts = list(controls.values())
    return widgets.VBox([widgets.HBox(parts[:3]), widgets.HBox(parts[3:]), output])
