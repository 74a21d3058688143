"""The common benchmark's pieces: resampling in time and per-clip APD, against numpy and
motionlab.metrics.apd."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from motionlab.apps.comparison import FRAMES, measure_sets, measured_part, per_clip_apd, resample
from motionlab.metrics import apd


def test_resample_interpolates_linearly_in_time():
    rng = np.random.default_rng(0)
    clips = torch.as_tensor(rng.normal(size=(2, 60, 3, 3)))
    out = resample(clips, 15, 30)
    assert out.shape == (2, 119, 3, 3)
    t_out = np.arange(119) / 30
    want = np.interp(t_out, np.arange(60) / 15, clips[1, :, 2, 0].numpy())
    np.testing.assert_allclose(out[1, :, 2, 0].numpy(), want, atol=1e-12)
    assert torch.equal(resample(clips, 30, 30), clips)
    with pytest.raises(ValueError, match="resample"):
        resample(clips, 0, 30)


def test_per_clip_apd_matches_apd_of_each_clips_samples():
    g = torch.Generator().manual_seed(1)
    sets = [torch.randn(4, 5, 22, 3, generator=g) for _ in range(3)]
    got = per_clip_apd(sets)
    want = [apd(torch.stack([s[i] for s in sets])) for i in range(4)]
    np.testing.assert_allclose(got, want, rtol=1e-6)


def test_measured_part_keeps_the_last_frames():
    clips = torch.arange(2 * 120 * 22 * 3, dtype=torch.float64).reshape(2, 120, 22, 3)
    part = measured_part(clips)
    assert part.shape == (2, FRAMES, 22, 3) and part.dtype == torch.float32
    assert torch.equal(part[:, -1], clips[:, -1].float())
    with pytest.raises(ValueError, match="at least"):
        measured_part(clips[:, :10])


class _Evaluator:
    """Features and action probabilities made from the clips' own numbers (enough for the metrics)."""

    def features_and_probs(self, positions, head):
        flat = torch.as_tensor(positions).flatten(1)[:, :8].double()
        return flat, torch.softmax(flat[:, :2], dim=-1)


def test_a_set_whose_feet_never_stand_still_leaves_skating_out_of_its_row():
    """Samples that are noise plant no foot on two consecutive frames: their row has every other column and
    no skating (undefined there), where walking-still clips have it."""
    parents = np.array([-1] + [0] * 21)
    test = SimpleNamespace(action=np.array([0, 0, 1, 1]), clips=SimpleNamespace(parents=parents))
    still = torch.zeros(4, FRAMES, 22, 3)  # every joint on the floor and still: planted throughout
    noise = torch.randn(4, FRAMES, 22, 3, generator=torch.Generator().manual_seed(0))  # fast everywhere
    reference = torch.randn(6, 8, generator=torch.Generator().manual_seed(1)).double()
    kept = measure_sets([still, still + 0.01], _Evaluator(), test, reference)
    assert kept["skating"].mean == 0.0 and "fid" in kept
    noisy = measure_sets([still, noise], _Evaluator(), test, reference)
    assert "skating" not in noisy and {"accuracy", "fid", "jerk", "apd"} <= set(noisy)


def test_mdm_is_a_method_of_the_comparison_given_each_test_clips_action():
    """Chapter 11's quick MDM goes through the comparison like the other generators: one 30 fps sample per
    test clip, of at least FRAMES frames, drawn for that clip's action and seeded by the generator alone."""
    from motionlab.apps import comparison
    from motionlab.evaluation.benchmark import load_benchmark
    from motionlab.models.diffusion import experiment as diffusion

    assert comparison.diffusion_methods in comparison.METHODS
    benchmark = load_benchmark()
    test = comparison.common_test(benchmark)
    method = comparison.diffusion_methods(benchmark, test)["MDM"]
    assert method.chapter == "11" and method.given == "action label"
    assert method.model.cfg == diffusion.ExperimentConfig.quick().model
    clips = method.generate(torch.Generator().manual_seed(3))
    assert clips.shape == (len(test.action), test.clips.positions.shape[1], 22, 3)
    assert clips.shape[1] >= FRAMES and torch.isfinite(clips).all()
    again = method.generate(torch.Generator().manual_seed(3))
    assert torch.equal(clips, again)
    one = method.generate_one(torch.Generator().manual_seed(3))
    assert one.shape == (1, *clips.shape[1:])
    # the clips answer the test clips' actions: the same draw for those actions through the experiment
    action = torch.as_tensor(test.clips.action, dtype=torch.int64)
    cfg = diffusion.ExperimentConfig.quick()
    assert cfg.sample_steps <= comparison.MDM_SAMPLE_STEPS  # the quick profile samples as chapter 11
    want = diffusion.generate_positions(method.model, cfg, action, torch.Generator().manual_seed(3))
    assert torch.equal(clips, want)
