"""ODMO's networks and joint objective: shapes, conditioning, accumulation, teacher forcing, switches,
determinism."""

import dataclasses

import pytest
import torch

from motionlab.models.odmo.data import BalancedBatches
from motionlab.models.odmo.experiment import VARIANTS, chapter_model, variant_config
from motionlab.models.odmo.losses import joint_objective, sequence_error
from motionlab.models.odmo.model import ODMO, ODMOConfig, accumulate, class_code_condition, heading_frame
from motionlab.train import Constant, TrainConfig, train

TINY = ODMOConfig(
    n_classes=3,
    n_frames=6,
    n_joints=3,
    code_dim=4,
    encoder_hidden=8,
    encoder_mlp=8,
    trajectory_hidden=8,
    motion_hidden=8,
)


def clips(n: int = 6, seed: int = 0) -> tuple[torch.Tensor, torch.Tensor]:
    gen = torch.Generator().manual_seed(seed)
    features = torch.randn(n, TINY.n_frames, TINY.feature_dim, generator=gen)
    features[:, 0, -3:] = 0.0  # clips start at the origin
    return features, torch.arange(n) % TINY.n_classes


def tiny_model(cfg: ODMOConfig = TINY, seed: int = 0) -> ODMO:
    torch.manual_seed(seed)
    return ODMO(cfg).fit_standardizer(clips(12, seed=99)[0])


def test_config_sizes_and_validation():
    cfg = ODMOConfig()
    assert (cfg.lmp_dim, cfg.feature_dim, cfg.condition_dim) == (63, 66, 120)
    with pytest.raises(ValueError, match="code_dim"):
        ODMOConfig(code_dim=0)
    with pytest.raises(ValueError, match="prior"):
        ODMOConfig(prior="other")
    with pytest.raises(ValueError, match="consistency"):
        ODMOConfig(use_trajectory_loss=False)
    with pytest.raises(ValueError, match="margin"):
        ODMOConfig(margin=-1.0)


def test_variants_change_only_their_switches():
    base = chapter_model()
    for name, changes in VARIANTS.items():
        cfg = variant_config(name, base)
        differing = {f.name for f in dataclasses.fields(cfg) if getattr(cfg, f.name) != getattr(base, f.name)}
        assert differing == set(changes), name
    with pytest.raises(ValueError, match="variant_config: name must be one of"):
        variant_config("nope", base)


def test_class_code_condition_is_the_outer_product():
    code = torch.tensor([[1.0, 2.0], [3.0, 4.0]])
    condition = class_code_condition(code, torch.tensor([2, 0]), 3)
    assert torch.equal(condition, torch.tensor([[0, 0, 0, 0, 1.0, 2.0], [3.0, 4.0, 0, 0, 0, 0]]))
    with pytest.raises(ValueError, match="actions"):
        class_code_condition(code, torch.tensor([0, 3]), 3)


def test_accumulate_adds_velocities_from_the_origin():
    velocity = torch.tensor([[[1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, -1.0]]])
    expected = torch.tensor([[[0.0, 0, 0], [1.0, 0, 0], [1.5, 1.0, 0], [1.5, 1.0, -1.0]]])
    assert torch.equal(accumulate(velocity), expected)


def test_shapes_of_every_network():
    model = tiny_model().eval()
    features, action = clips()
    mu, logvar = model.encode(features)
    assert mu.shape == logvar.shape == (6, TINY.code_dim)
    out = model(features, action)
    assert out.trajectory.shape == (6, TINY.n_frames, 3) and out.motion.shape == features.shape
    motion, trajectory = model.generate(mu, action, features[:, -1, -3:])
    assert motion.shape == features.shape and trajectory.shape == (6, TINY.n_frames, 3)
    assert torch.allclose(trajectory[:, 0], torch.zeros(6, 3), atol=1e-5)  # in metres, from the origin


def test_config_checks_the_encoder_frame_decoder_input_and_hips():
    with pytest.raises(ValueError, match="encoder_frame"):
        ODMOConfig(encoder_frame="body")
    with pytest.raises(ValueError, match="decoder_trajectory"):
        ODMOConfig(decoder_trajectory="never")
    for hips in ((0, 2), (1, 1), (1, 22), (1, 2, 3)):
        with pytest.raises(ValueError, match="hips"):
            ODMOConfig(hips=hips)
    with pytest.raises(TypeError, match=r"ODMOConfig: hips must be a tuple, got \[1, 2\]"):
        ODMOConfig(hips=[1, 2])


def test_heading_frame_turns_every_frame_to_face_x():
    # two frames of a 3-joint body (root, left hip, right hip) facing +y, then -x
    lmp = torch.tensor([[[-0.1, 0.0, 0.2, 0.1, 0.0, 0.2], [0.0, -0.1, -0.3, 0.0, 0.1, -0.3]]])
    expected = torch.tensor([[[0.0, 0.1, 0.2, 0.0, -0.1, 0.2], [0.0, 0.1, -0.3, 0.0, -0.1, -0.3]]])
    assert torch.allclose(heading_frame(lmp, (1, 2)), expected, atol=1e-6)
    # a turn of the whole clip about the vertical changes nothing
    turned = lmp.unflatten(-1, (-1, 3)).clone()
    angle = torch.tensor(0.7)
    x, y = turned[..., 0].clone(), turned[..., 1].clone()
    turned[..., 0], turned[..., 1] = x * angle.cos() - y * angle.sin(), x * angle.sin() + y * angle.cos()
    assert torch.allclose(heading_frame(turned.flatten(-2), (1, 2)), expected, atol=1e-6)


def test_decoder_reads_the_trajectory_at_every_frame_when_asked():
    code, action = torch.randn(2, TINY.code_dim), torch.tensor([0, 1])
    trajectory = torch.randn(2, TINY.n_frames, 3)
    later = trajectory.clone()
    later[:, -1] += 1.0  # the last frame of the trajectory: only the every-frame input reads it at step T - 1
    for how in ("initial_state", "every_frame"):
        generator = tiny_model(dataclasses.replace(TINY, decoder_trajectory=how)).eval().motion_generator
        extra = 3 if how == "every_frame" else 0
        assert generator.condition_embed.in_features == TINY.condition_dim + 1 + extra
        a, b = generator(trajectory, code, action), generator(later, code, action)
        assert a.shape == (2, TINY.n_frames, TINY.feature_dim) and not torch.allclose(a[:, -1], b[:, -1])


def test_encoder_reads_the_lmp_in_the_axes_of_its_frame():
    features, _ = clips()
    turned = features.clone()
    joints = turned[..., :-3].unflatten(-1, (-1, 3))
    x, y = joints[..., 0].clone(), joints[..., 1].clone()
    joints[..., 0], joints[..., 1] = -y, x  # every frame of every clip turned by 90 degrees
    turned[..., :-3] = joints.flatten(-2)
    world = tiny_model().eval()
    heading = tiny_model(dataclasses.replace(TINY, encoder_frame="heading")).eval()
    assert not torch.allclose(world.encode(features)[0], world.encode(turned)[0])
    assert torch.allclose(heading.encode(features)[0], heading.encode(turned)[0], atol=1e-5)


def test_end_point_switch_removes_the_end_point_input():
    code, action = torch.randn(2, TINY.code_dim), torch.tensor([0, 1])
    for use_end_point, should_change in ((True, True), (False, False)):
        model = tiny_model(dataclasses.replace(TINY, use_end_point=use_end_point)).eval()
        a = model.trajectory_generator(code, action, torch.zeros(2, 3))
        b = model.trajectory_generator(code, action, torch.ones(2, 3))
        assert (not torch.allclose(a, b)) == should_change


def test_teacher_forcing_feeds_the_real_previous_frame():
    model = tiny_model().eval()
    features, action = clips(3)
    trajectory, code = torch.randn(3, TINY.n_frames, 3), torch.randn(3, TINY.code_dim)
    generator = model.motion_generator
    forced = generator(trajectory, code, action, features, teacher_forcing=1.0)
    changed_last = features.clone()
    changed_last[:, -1] += 1.0  # the last real frame is never an input
    assert torch.equal(forced, generator(trajectory, code, action, changed_last, teacher_forcing=1.0))
    changed_first = features.clone()
    changed_first[:, 0] += 1.0
    moved = generator(trajectory, code, action, changed_first, teacher_forcing=1.0)
    assert torch.equal(moved[:, 0], forced[:, 0]) and not torch.allclose(moved[:, 1], forced[:, 1])
    free = generator(trajectory, code, action)
    assert torch.equal(free, generator(trajectory, code, action, changed_first, teacher_forcing=0.0))
    with pytest.raises(ValueError, match="target"):
        generator(trajectory, code, action, teacher_forcing=0.5)


def test_sequence_error_by_hand():
    prediction = torch.zeros(1, 2, 2)
    target = torch.tensor([[[1.0, 3.0], [2.0, 0.0]]])
    assert torch.allclose(sequence_error(prediction, target), torch.tensor([(1 + 9) / 2 + (4 + 0) / 2]))


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_joint_objective_sums_the_switched_on_terms(variant):
    cfg = variant_config(variant, dataclasses.replace(TINY, prior_weight=2.5, contrastive_weight=0.5))
    model = tiny_model(cfg)
    torch.manual_seed(3)
    out = joint_objective(model, clips(), 0, {"teacher_forcing": 0.5})
    expected = out["motion"] + cfg.prior_weight * out["prior"]
    expected = (
        expected
        + (out["trajectory"] if cfg.use_trajectory_loss else 0)
        + (out["consistency"] if cfg.use_consistency else 0)
    )
    expected = expected + (cfg.contrastive_weight * out["contrastive"] if cfg.use_contrastive else 0)
    assert torch.allclose(out["loss"], expected)
    assert set(out) == {"loss", "motion", "trajectory", "consistency", "contrastive", "prior"}


def test_training_and_generation_are_deterministic():
    def trained() -> torch.Tensor:
        model = tiny_model()
        cfg = TrainConfig(
            steps=3,
            batch_size=6,
            lr=1e-2,
            schedules={"teacher_forcing": Constant(0.5)},
            checkpoint_every=None,
        )
        train(model, joint_objective, BalancedBatches(*clips(12), TINY.n_classes), cfg, progress=False)
        torch.manual_seed(5)
        return model.generate(torch.randn(2, TINY.code_dim), torch.tensor([0, 2]), torch.zeros(2, 3))[0]

    assert torch.equal(trained(), trained())


def test_bad_inputs_raise_clear_errors():
    model = tiny_model().eval()
    features, action = clips()
    with pytest.raises(ValueError, match="features"):
        model.encode(features[..., :-1])
    nan = features.clone()
    nan[0, 0, 0] = float("nan")
    with pytest.raises(ValueError, match="NaN"):
        model.encode(nan)
    with pytest.raises(ValueError, match="end_point"):
        model.generate(torch.zeros(2, TINY.code_dim), torch.tensor([0, 1]), torch.zeros(2, 2))
    with pytest.raises(ValueError, match="BatchNorm"):
        model.train().encode(features[:1])
