"""From codes to clips: the sampler, on-demand customisation, the evaluation tables and the chapter's widgets.

A tiny untrained ODMO on a 3-joint skeleton and a stand-in evaluator keep these tests fast; what they check
is the plumbing (shapes, which codes and end points reach the generators, how numbers are aggregated),
against hand computations and scikit-learn.
"""

import dataclasses

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
import pytest
import torch
from matplotlib.figure import Figure
from sklearn.metrics import adjusted_rand_score

from motionlab.data.synthetic import generate
from motionlab.metrics import end_point_mse, mode_homogeneity
from motionlab.models.odmo import evaluate, sampling
from motionlab.models.odmo.data import ODMOData
from motionlab.models.odmo.experiment import (
    VARIANTS,
    ExperimentConfig,
    RealExperimentConfig,
    chapter_model,
    measure_variant,
    odmo_run,
    real_runs,
    runs,
    train_all,
    validation_batches,
)
from motionlab.models.odmo.model import ODMO, ODMOConfig
from motionlab.models.odmo.modes import discover_modes
from motionlab.models.odmo.sampling import ODMOSampler, encode_clips
from motionlab.widgets import odmo as odmo_widgets

CFG = ODMOConfig(
    n_classes=2,
    n_frames=5,
    n_joints=3,
    code_dim=3,
    encoder_hidden=8,
    encoder_mlp=8,
    trajectory_hidden=8,
    motion_hidden=8,
)
PARENTS = [-1, 0, 1]
STRIDE = 2
#: The chapter's experiment on the tiny model: 2 steps, small sample sets.
EXPERIMENT = ExperimentConfig(
    model=CFG,
    frame_stride=STRIDE,
    steps=2,
    batch_size=4,
    n_sets=2,
    n_per_class=4,
    n_per_mode=2,
    n_codes=2,
    n_end_points=2,
    mode_counts=(3, 4),
)


def tiny_clips(n: int, gen: torch.Generator, val: ODMOData | None = None) -> ODMOData:
    """``n`` random clips of the tiny skeleton, of the 2 actions in turn, 2 modes each."""
    features = torch.randn(n, CFG.n_frames, CFG.feature_dim, generator=gen) * 0.1
    features[..., 2:6:3] -= 0.5  # the two non-root joints hang below the root
    features[..., -3:] = torch.cumsum(torch.rand(n, CFG.n_frames, 3, generator=gen) * 0.2, dim=1)
    features[:, 0, -3:] = 0.0
    action = torch.arange(n) % 2
    mode = 2 * action + (torch.arange(n) // 2) % 2
    return ODMOData(features, action, mode, torch.zeros(n, dtype=torch.int64), STRIDE, 0.05, val)


@pytest.fixture(scope="module")
def data() -> ODMOData:
    """40 training clips with 10 validation clips."""
    gen = torch.Generator().manual_seed(0)
    return tiny_clips(40, gen, val=tiny_clips(10, gen))


@pytest.fixture(scope="module")
def sampler(data) -> ODMOSampler:
    torch.manual_seed(0)
    model = ODMO(CFG).fit_standardizer(data.features).eval()
    codes = encode_clips(model, data)
    modes = discover_modes(codes, data.action.numpy(), data.end_point.numpy(), 2, k_values=[3], min_share=0.0)
    return ODMOSampler(model, modes, data.frame_stride, data.floor_clearance)


class StandInEvaluator:
    """Features: per-clip mean and spread of the joint positions; "action" = whether the root ends at x >
    0.2."""

    def features(self, positions):
        p = torch.as_tensor(positions, dtype=torch.float64).flatten(2)
        return torch.cat([p.mean(1), p.std(1)], dim=-1)

    def predict(self, positions, head="action"):
        return (torch.as_tensor(positions)[:, -1, 0, 0] > 0.2).long()

    def probs(self, positions, head="action"):
        return torch.nn.functional.one_hot(self.predict(positions, head), 2).double() * 0.8 + 0.1

    def features_and_probs(self, positions, head="action"):
        return self.features(positions), self.probs(positions, head)


def test_encode_and_sample_shapes_and_determinism(data, sampler):
    codes = encode_clips(sampler.model, data)
    assert codes.shape == (len(data), CFG.code_dim) and not sampler.model.training
    a = sampler.sample(1, 6, np.random.default_rng(3))
    b = sampler.sample(1, 6, np.random.default_rng(3))
    assert a.positions.shape == (6, CFG.n_frames * STRIDE, 3, 3) and a.features.shape == (
        6,
        CFG.n_frames,
        CFG.feature_dim,
    )
    assert torch.equal(a.positions, b.positions) and (a.action == 1).all()
    assert ODMOSampler.from_data(sampler.model, data, kind="conventional").modes.classes[0].n_modes == 1
    both = sampler.sample_classes(4, np.random.default_rng(0))
    assert both.action.tolist() == [0] * 4 + [1] * 4
    per_mode = sampler.sample_modes(2, np.random.default_rng(0))
    assert np.bincount(sampler.modes.global_ids(per_mode.action, per_mode.mode)).tolist() == [2] * 6
    with pytest.raises(ValueError, match="kind"):
        ODMOSampler.from_data(sampler.model, data, kind="other")


def test_customisation_sends_the_requested_codes_and_end_points(sampler):
    weights = np.array([0.0, 0.5, 1.0])
    mixed = sampling.mode_interpolation(sampler, 0, 0, 1, weights)
    centres = sampler.modes.classes[0].means
    assert np.allclose(mixed.codes[[0, 2]], centres[[0, 1]]) and np.allclose(
        mixed.codes[1], centres[:2].mean(0)
    )
    target = np.array([1.0, -0.5, 0.0])
    styles = sampling.styles_to_end_point(sampler, 1, target, np.random.default_rng(0), per_mode=2)
    assert sorted(set(styles.mode.tolist())) == list(range(sampler.modes.classes[1].n_modes))
    assert np.allclose(styles.end_points, target)
    again = sampling.to_end_point(sampler, 1, styles.codes, styles.end_points)
    assert torch.equal(again.features, styles.features)
    assert np.allclose(sampling.end_point_sweep([0, 0, 0], [2, 4, 0], 3), [[0, 0, 0], [1, 2, 0], [2, 4, 0]])
    with pytest.raises(ValueError, match="modes"):
        sampling.mode_interpolation(sampler, 0, 0, 99, weights)


def test_mode_recovery_matches_scikit_learn(data, sampler):
    ari = evaluate.mode_recovery(sampler.modes, data.mode.numpy())
    labels, action, mode = sampler.modes.labels, sampler.modes.action, data.mode.numpy()
    assert np.allclose(ari, [adjusted_rand_score(mode[action == a], labels[action == a]) for a in range(2)])


def test_end_point_control_measures_the_generated_root(sampler):
    reference = evaluate.Reference(
        StandInEvaluator(), torch.zeros(4, 12), torch.zeros(4, 10, 3, 3), np.array([0, 0, 1, 1])
    )
    table = evaluate.end_point_control(reference, sampler, n_codes=3, n_end_points=4, seed=0)
    assert len(table["dist_e"].values) == 6 and 0.0 <= table["accuracy"].mean <= 1.0
    assert set(table) == {"accuracy", "dist_e", "dist_e_trajectory"}
    # recompute the first code group by hand
    rng = np.random.default_rng(0)
    members = np.flatnonzero(sampler.modes.action == 0)
    source, other = rng.choice(members, size=3), rng.choice(members, size=3)
    targets = sampling.end_point_sweep(
        sampler.modes.end_points[source[0]], sampler.modes.end_points[other[0]], 4
    )
    clips = sampling.to_end_point(sampler, 0, np.repeat(sampler.modes.codes[source[:1]], 4, axis=0), targets)
    assert table["dist_e"].values[0] == pytest.approx(
        end_point_mse(clips.features[..., -3:].numpy(), targets)
    )
    assert table["dist_e_trajectory"].values[0] == pytest.approx(
        end_point_mse(clips.trajectory.numpy(), targets)
    )


def test_metric_and_homogeneity_tables(sampler):
    real = torch.randn(8, CFG.n_frames * STRIDE, 3, 3)
    reference = evaluate.Reference(
        StandInEvaluator(), StandInEvaluator().features(real), real, np.array([0, 1] * 4)
    )
    row = evaluate.metric_row(reference, sampler, n_per_class=4, n_sets=2, seed=1)
    assert list(row) == list(evaluate.METRICS)
    assert all(len(interval.values) == 2 for interval in row.values())
    assert row == evaluate.metric_row(
        reference, sampler, n_per_class=4, n_sets=2, seed=1
    )  # seeded by its arguments
    purity = evaluate.style_purity_interval(reference, sampler, n_per_mode=2, n_sets=2)
    assert all(0.0 <= v <= 1.0 for v in purity.values)


def test_mode_homogeneity_table_uses_the_real_clips_grouped_by_their_modes(sampler):
    modes = sampler.modes
    real = torch.randn(len(modes.labels), 4, 3, 3)
    whole = evaluate.mode_homogeneity_interval(modes, real, n_sets=2, share=1.0)
    # with every clip kept, each repeat is the metric on all real clips
    expected = mode_homogeneity(real.numpy(), modes.action, modes.labels)
    assert whole.values == pytest.approx((expected, expected))
    half = evaluate.mode_homogeneity_interval(modes, real, n_sets=3, share=0.5, seed=1)
    assert half == evaluate.mode_homogeneity_interval(modes, real, n_sets=3, share=0.5, seed=1)
    assert len(set(half.values)) > 1  # the repeats keep different clips
    with pytest.raises(ValueError, match="mode_homogeneity_interval: 3 clips"):
        evaluate.mode_homogeneity_interval(modes, real[:3], n_sets=2)


def test_measure_variant_follows_the_config(data, sampler):
    real = torch.randn(8, CFG.n_frames * STRIDE, 3, 3)
    reference = evaluate.Reference(
        StandInEvaluator(), StandInEvaluator().features(real), real, np.array([0, 1] * 4)
    )
    modes = ODMOSampler.from_data(sampler.model, data, kind="modes", mode_counts=EXPERIMENT.mode_counts)
    odmo = measure_variant("ODMO", sampler.model, data, reference, EXPERIMENT)
    assert (
        set(odmo.samplers) == {"table", "modes", "conventional"}
        and odmo.samplers["table"] is odmo.samplers["modes"]
    )
    assert list(odmo.rows) == ["ODMO", "ODMO_conv"]
    assert odmo.rows["ODMO"] == evaluate.metric_row(reference, modes, 4, 2)
    conventional = ODMOSampler.from_data(sampler.model, data, kind="conventional")
    assert odmo.rows["ODMO_conv"] == evaluate.metric_row(reference, conventional, 4, 2)
    real_clips = evaluate.to_positions(data.features, data.frame_stride, data.floor_clearance)
    assert odmo.homogeneity == evaluate.mode_homogeneity_interval(modes.modes, real_clips, 2, 0.5)
    assert odmo.purity == evaluate.style_purity_interval(reference, modes, 2, 2)
    assert odmo.end_point == evaluate.end_point_control(reference, modes, 2, 2)
    vae = measure_variant("standard VAE", sampler.model, data, reference, EXPERIMENT)
    assert list(vae.rows) == ["standard VAE"] and vae.end_point is None
    assert vae.rows["standard VAE"] == evaluate.metric_row(
        reference, ODMOSampler.from_data(sampler.model, data, kind="prior"), 4, 2
    )
    assert vae.homogeneity == odmo.homogeneity  # the same model's discovered modes
    assert vae.purity == odmo.purity
    ablation = measure_variant("-L_es", sampler.model, data, reference, EXPERIMENT)
    assert list(ablation.rows) == ["-L_es"] and ablation.end_point is None
    assert ablation.homogeneity is None and ablation.purity is None
    with pytest.raises(ValueError, match="measure_variant: variant must be one of"):
        measure_variant("odmo", sampler.model, data, reference, EXPERIMENT)


def test_experiment_config_profiles_and_runs(data, monkeypatch):
    quick, full = ExperimentConfig.quick(), ExperimentConfig.full()
    assert (quick.steps, quick.batch_size, full.steps, full.batch_size) == (4, 30, 300, 60)
    assert full.model == chapter_model() and quick.model.motion_hidden == 16
    assert (full.model.encoder_frame, full.model.decoder_trajectory) == ("heading", "every_frame")
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert ExperimentConfig.current() == quick
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    assert ExperimentConfig.current() == full
    assert full.train_config().schedules["teacher_forcing"](150) == pytest.approx(0.65)
    chapter = runs(EXPERIMENT, data)
    assert list(chapter) == [name for name in VARIANTS if name != "-L_es"] + ["-L_es"]
    assert [run.name for run in chapter.values()][:3] == [
        "odmo",
        "odmo_odmo_prior_on_mu_extension",
        "odmo_r_e",
    ]
    assert chapter["-L_traj"].model.use_trajectory_loss is False
    with pytest.raises(ValueError, match="frame_stride"):
        runs(ExperimentConfig(model=CFG), data)
    with pytest.raises(ValueError, match=r"ExperimentConfig: homogeneity\[0\] must be one of"):
        ExperimentConfig(homogeneity=("odmo",))
    with pytest.raises(TypeError, match="ExperimentConfig: steps must be an integer"):
        ExperimentConfig(steps=2.5)


def test_runs_validate_on_the_val_clips_without_changing_the_weights(
    data, tmp_path, monkeypatch, check_validation_leaves_weights
):
    """A run validates every ``val_every`` steps on class-balanced batches of the validation clips, each
    class's in their stored order, every clip once (5 per class, batches of 3 per class: one full batch and
    one of the last 2 per class); the trained weights are those of the same run without validation, bit for
    bit (the codes' noise, the teacher forcing and the pairs draw from the random state a validation pass
    must leave alone)."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")  # the benchmark it compares the data with
    cfg = dataclasses.replace(EXPERIMENT, steps=6, batch_size=6)
    run = runs(cfg, data)["ODMO"]
    assert run.train_config.val_every == 4 and run.val_batches is not None  # 6 steps: at step 4 and the end
    batches = list(run.val_batches(ODMO(CFG))(0, torch.Generator(), cfg.batch_size))
    assert [y.tolist() for _, y in batches] == [[0, 0, 0, 1, 1, 1], [0, 0, 1, 1]]
    assert torch.equal(torch.cat([x for x, _ in batches]), data.val.features[[0, 2, 4, 1, 3, 5, 6, 8, 7, 9]])
    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 6] and len(result.history.val_terms["loss"]) == 2
    assert set(result.history.val_terms) == {
        "loss",
        "motion",
        "trajectory",
        "consistency",
        "contrastive",
        "prior",
    }

    check_validation_leaves_weights(run, validated)

    without_val = dataclasses.replace(data, val=None)
    with pytest.raises(ValueError, match=r"no validation clips \(data.val is None\)"):
        validation_batches(without_val, validated)
    with pytest.raises(ValueError, match="odmo_run: odmo validates, but the data has no validation clips"):
        odmo_run("odmo", CFG, run.train_config, without_val)
    with pytest.raises(ValueError, match="odmo_run: odmo validates, but the data has no validation clips"):
        runs(cfg, without_val)
    # real motion capture has no validation split: its runs do not validate
    real_cfg = RealExperimentConfig(model=CFG, frame_stride=STRIDE, window=CFG.n_frames * STRIDE, steps=6)
    assert real_cfg.train_config().val_every is None
    assert real_runs(real_cfg, without_val)["ODMO"].val_batches is None


def test_train_all_trains_in_workers_and_measures_like_in_process(data, tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))  # the workers get it with every call
    real = torch.randn(8, CFG.n_frames * STRIDE, 3, 3)
    reference = evaluate.Reference(
        StandInEvaluator(), StandInEvaluator().features(real), real, np.array([0, 1] * 4)
    )
    trained = train_all(EXPERIMENT, data, reference, processes=2)
    assert list(trained) == list(VARIANTS)
    assert all(t.seconds is not None and t.result.loaded_from_cache for t in trained.values())
    for name in ("ODMO", "standard VAE", "-L_es"):  # one of each kind of measurement
        t = trained[name]
        here = measure_variant(name, t.model, data, reference, EXPERIMENT)
        assert t.measured == dataclasses.replace(here, samplers=t.measured.samplers)  # the same numbers
    assert all(run.is_cached() for run in runs(EXPERIMENT, data).values())  # a second call trains nothing


def test_train_all_trains_only_the_chosen_variants(data, tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    real = torch.randn(8, CFG.n_frames * STRIDE, 3, 3)
    reference = evaluate.Reference(
        StandInEvaluator(), StandInEvaluator().features(real), real, np.array([0, 1] * 4)
    )
    chosen = dataclasses.replace(EXPERIMENT, rows=("ODMO",), conventional=())
    trained = train_all(chosen, data, reference, processes=1, variants=("-L_es", "ODMO"))
    assert list(trained) == ["ODMO", "-L_es"]  # in the order of VARIANTS
    assert list(trained["ODMO"].measured.rows) == ["ODMO"] and trained["-L_es"].measured.rows == {}
    assert not runs(EXPERIMENT, data)["standard VAE"].is_cached()  # the others were not trained
    with pytest.raises(ValueError, match="train_all: variants must be one of"):
        train_all(EXPERIMENT, data, reference, variants=("odmo",))


def test_widget_callbacks_and_builders(sampler):
    for fig in (
        odmo_widgets.mode_sample_figure(sampler, PARENTS, 0, 0, seed=1),
        odmo_widgets.interpolation_figure(sampler, PARENTS, 1, 0, 1, 0.5),
        odmo_widgets.end_point_figure(sampler, 0, 1.0, 0.5, seed=0, per_mode=1),
    ):
        assert isinstance(fig, Figure) and fig.axes
        plt.close(fig)
    with pytest.raises(ValueError, match="discovered modes"):
        odmo_widgets.mode_sample_figure(sampler, PARENTS, 0, 42, seed=0)
    with pytest.raises(ValueError, match="weight"):
        odmo_widgets.interpolation_figure(sampler, PARENTS, 0, 0, 1, 1.5)
    names = ["a", "b"]
    built = [
        odmo_widgets.mode_sampler_widget(sampler, PARENTS, names),
        odmo_widgets.interpolation_widget(sampler, PARENTS, names),
        odmo_widgets.end_point_widget(sampler, names),
    ]
    for widget in built:
        controls, output = widget.children
        [image] = output.outputs
        slider = next(c for c in controls.children if isinstance(c, widgets.IntSlider | widgets.FloatSlider))
        slider.value = slider.max if slider.value != slider.max else slider.min
        [redrawn] = output.outputs
        assert redrawn["data"]["image/png"] != image["data"]["image/png"], (
            f"{slider.description} did not redraw"
        )
    assert not plt.get_fignums()  # each figure closed once shown


def test_real_row_equals_set_metrics_on_the_canonical_test_clips():
    test = generate(seed=5, n_per_mode=1, seconds=1.0, split="test")
    positions = evaluate.canonical_positions(test, 0.0)
    reference = evaluate.Reference(
        StandInEvaluator(), StandInEvaluator().features(positions), positions, np.asarray(test.action)
    )
    row = evaluate.real_row(reference, test, 0.0, n_sets=3, seed=2)
    by_hand = evaluate.repeat_metric(
        lambda rng: evaluate.set_metrics(reference, positions, np.asarray(test.action), rng),
        lambda generator: np.random.default_rng(generator.initial_seed()),
        3,
        2,
    )
    assert all(row[name].values == by_hand[name].values for name in evaluate.METRICS)
