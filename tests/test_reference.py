"""The shipped reference models (:mod:`motionlab.train.reference`): exported from a build with manifests,
loaded in the full profile instead of training, refused when damaged or not the run, ignored on request;
and the repository's own ``reference/`` is whole and within its size."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
import torch
from torch import nn

from motionlab import config
from motionlab.train import TensorBatches, TrainConfig, reference, train_or_load
from motionlab.train.cache import is_cached

FEATURES = 4
MODEL_CONFIG = {"kind": "reference_test", "features": FEATURES}
CFG = TrainConfig(steps=60, batch_size=8, lr=1e-2, log_every=10, checkpoint_every=None)


def make_model() -> nn.Module:
    torch.manual_seed(0)
    return nn.Linear(FEATURES, FEATURES)


def loss_fn(model: nn.Module, batch: torch.Tensor, step: int, coeffs: dict[str, float]) -> dict:
    return {"loss": ((model(batch) - batch) ** 2).mean()}


def data() -> TensorBatches:
    return TensorBatches(torch.randn(32, FEATURES, generator=torch.Generator().manual_seed(1)))


def run(calls: list[int] | None = None):
    def counted(model, batch, step, coeffs):
        if calls is not None:
            calls.append(step)
        return loss_fn(model, batch, step, coeffs)

    model = make_model()
    return model, train_or_load("tiny_reference", MODEL_CONFIG, model, counted, data(), CFG)


@pytest.fixture
def shipped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A reference folder exported from a first full-profile build; the second build is fresh."""
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    monkeypatch.delenv("MOTIONLAB_RETRAIN", raising=False)
    monkeypatch.setattr(reference, "REFERENCE_DIR", tmp_path / "reference")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "first"))
    config.set_threads(1)
    trained, _ = run()
    manifests = reference.export(tmp_path / "first", tmp_path / "reference")
    assert [m["name"] for m in manifests] == ["tiny_reference"]
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "second"))
    return tmp_path / "reference"


def test_the_full_profile_loads_the_reference_instead_of_training(shipped: Path) -> None:
    calls: list[int] = []
    model, result = run(calls)
    assert calls == [] and result.loaded_from_cache and result.path.parent == shipped
    assert not (config.checkpoint_dir() / result.path.name).exists()  # not copied into the build
    manifest = json.loads(result.path.with_suffix(".json").read_text())
    assert (
        manifest["steps"] == 60
        and manifest["seed"] == CFG.seed  # the base seed (MOTIONLAB_SEED)
        and manifest["sha256"] == reference.sha256(result.path)
    )
    assert manifest["trained_on"]["torch"] == str(torch.__version__)
    assert set(manifest["levelling"]) == {"measure", "last_fifth_share", "levelled"}
    assert "tiny_reference" in (shipped / "README.md").read_text()


def test_an_export_keeps_the_references_a_build_loaded_and_replaces_what_it_trained(shipped: Path) -> None:
    """``make reference ALL=0``: a build with the references in use loads the unchanged run and trains the
    one whose configuration changed; the export adds the new one, keeps the loaded one byte for byte and
    drops the reference no build used."""
    before = {path.name: path.read_bytes() for path in shipped.iterdir()}
    _, loaded = run()
    changed = {**MODEL_CONFIG, "changed": True}
    train_or_load("tiny_changed", changed, make_model(), loss_fn, data(), CFG)
    build = config.checkpoint_dir().parent
    manifests = reference.export(build, shipped)
    assert sorted(m["name"] for m in manifests) == ["tiny_changed", "tiny_reference"]
    assert (shipped / loaded.path.name).read_bytes() == before[loaded.path.name]
    assert "tiny_changed" in (shipped / "README.md").read_text()
    (config.checkpoint_dir() / reference.runs_log().name).write_text("")  # a build that used neither
    train_or_load("tiny_changed", changed, make_model(), loss_fn, data(), CFG)  # loads the new reference
    assert [m["name"] for m in reference.export(build, shipped)] == ["tiny_changed"]
    assert not (shipped / loaded.path.name).exists()


def test_a_partial_export_keeps_what_it_did_not_use_but_older_versions_of_what_it_trained(
    shipped: Path,
) -> None:
    """A build of one chapter (``export --partial --replace tiny_reference``): the run it trained for longer
    replaces its older version, a reference of another chapter stays although this build did not use it."""
    other = {**MODEL_CONFIG, "chapter": "another"}
    train_or_load("tiny_other", other, make_model(), loss_fn, data(), CFG)
    build = config.checkpoint_dir().parent
    reference.export(build, shipped, partial=True)  # now tiny_reference (not used) and tiny_other
    assert sorted(path.stem.rsplit("-", 1)[0] for path in shipped.glob("*.pt")) == [
        "tiny_other",
        "tiny_reference",
    ]
    (config.checkpoint_dir() / reference.runs_log().name).write_text("")  # the next build: one run, longer
    train_or_load("tiny_reference", MODEL_CONFIG, make_model(), loss_fn, data(), replace(CFG, steps=80))
    manifests = reference.export(build, shipped, partial=True, replace=("tiny_reference",))
    assert sorted((m["name"], m["steps"]) for m in manifests) == [("tiny_other", 60), ("tiny_reference", 80)]
    assert len(list(shipped.glob("*.pt"))) == 2 and "tiny_other" in (shipped / "README.md").read_text()


def test_retrain_ignores_the_references(shipped: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONLAB_RETRAIN", "1")
    calls: list[int] = []
    _, result = run(calls)
    assert len(calls) == 60 and not result.loaded_from_cache and result.path.parent == config.checkpoint_dir()


def test_the_quick_profile_ignores_the_references(shipped: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert not is_cached("tiny_reference", MODEL_CONFIG, CFG)


def test_a_damaged_reference_is_refused_with_its_name(shipped: Path) -> None:
    path = next(shipped.glob("*.pt"))
    path.write_bytes(path.read_bytes()[:-10] + b"0123456789")
    with pytest.raises(reference.ReferenceError, match=rf"{path.stem}.*does not match its manifest: SHA-256"):
        run()


def test_a_reference_without_its_manifest_is_refused(shipped: Path) -> None:
    path = next(shipped.glob("*.pt"))
    path.with_suffix(".json").unlink()
    with pytest.raises(reference.ReferenceError, match="has no manifest"):
        is_cached("tiny_reference", MODEL_CONFIG, CFG)


def test_a_reference_for_another_configuration_is_refused(shipped: Path) -> None:
    """A file whose name is the run's but whose content is another run's (its manifest and checksum made to
    agree): loading refuses it, naming the config key that differs, and does not retrain."""
    path = next(shipped.glob("*.pt"))
    payload = torch.load(path, weights_only=True)
    payload["config"]["model"]["features"] = 5
    torch.save(payload, path)
    manifest = json.loads(path.with_suffix(".json").read_text())
    manifest["sha256"] = reference.sha256(path)
    path.with_suffix(".json").write_text(json.dumps(manifest))
    calls: list[int] = []
    with pytest.raises(reference.ReferenceError, match="model.features"):
        run(calls)
    assert calls == []


def test_a_bad_retrain_switch_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONLAB_RETRAIN", "maybe")
    with pytest.raises(ValueError, match="MOTIONLAB_RETRAIN must be 1 or 0"):
        reference.retraining()


def test_levelling_tells_a_flat_end_from_a_falling_one() -> None:
    flat = {"terms": {"loss": [1.0 / (1 + i) for i in range(20)] + [0.05] * 80}}
    falling = {"terms": {"loss": [1.0 - i / 100 for i in range(100)]}}
    assert reference.levelling(flat)["levelled"] and not reference.levelling(falling)["levelled"]
    assert reference.levelling({"terms": {"loss": [1.0] * 10}}) is None
    # a KL weight that ramps up makes the loss rise; the objective it leads to (the negative ELBO) is judged
    ramped = {"terms": {"loss": [i / 100 for i in range(100)], "objective": flat["terms"]["loss"]}}
    assert reference.levelling(ramped)["levelled"]
    assert reference.levelling(flat)["measure"] == "training"


def test_levelling_judges_the_held_out_curve_where_the_run_validated() -> None:
    """A training loss still falling with a held-out loss that levelled off (or rose: past its best) is
    levelled; a held-out curve still falling is not, whatever the training loss does."""
    falling = [1.0 - i / 100 for i in range(100)]
    flat = [1.0 / (1 + i) for i in range(4)] + [0.2] * 16
    rising = [1.0 / (1 + i) for i in range(4)] + [0.2 + i / 100 for i in range(16)]
    still = [1.0 - i / 40 for i in range(20)]
    # never improved on held-out data: training longer will not help
    worse = [1.0 + i / 40 for i in range(20)]
    for held_out, levelled in ((flat, True), (rising, True), (still, False), (worse, True)):
        judged = reference.levelling({"terms": {"loss": falling}, "val_terms": {"loss": held_out}})
        assert judged["measure"] == "held-out" and judged["levelled"] is levelled, (held_out, judged)
    never_fell = reference.levelling({"terms": {"loss": falling}, "val_terms": {"loss": worse}})
    assert never_fell["last_fifth_share"] < 0
    # too few passes to judge: the training loss is
    few = reference.levelling({"terms": {"loss": falling}, "val_terms": {"loss": flat[:5]}})
    assert few["measure"] == "training" and not few["levelled"]
    # a training loss that rises the same way is not levelled (its curve is the thing optimised)
    assert not reference.levelling({"terms": {"loss": [0.2 + i / 100 for i in range(100)]}})["levelled"]


def test_the_shipped_reference_models_match_their_manifests_and_fit_in_30_mb() -> None:
    files = sorted(reference.REFERENCE_DIR.glob("*.pt"))
    assert files, "reference/ holds no models"
    total = 0
    for path in files:
        manifest = reference.verify(path)
        assert manifest["bytes"] == path.stat().st_size and manifest["name"] == path.stem.rsplit("-", 1)[0]
        total += path.stat().st_size + path.with_suffix(".json").stat().st_size
    assert total <= reference.SIZE_LIMIT, f"reference/ weighs {total / 1e6:.1f} MB"
    manifests = {path.stem for path in reference.REFERENCE_DIR.glob("*.json")}
    assert manifests == {path.stem for path in files}, "a model without its manifest, or the reverse"


def test_provenance_names_the_reference_its_steps_and_the_command(shipped: Path) -> None:
    _, loaded = run()
    line = reference.provenance(loaded, command="python -m motionlab.apps.training vae")
    assert line.startswith("tiny_reference: the reference model, 60 steps") and "apps.training vae" in line
    assert reference.provenance(replace(loaded, path=None, loaded_from_cache=False), 1.5).endswith("in 2 s")


def test_weight_matrices_ship_as_float16_and_load_back_into_float32() -> None:
    big = nn.Sequential(nn.Linear(64, 128), nn.Linear(128, 3))
    shipped, stored = reference.half_precision(big.state_dict())
    assert shipped["0.weight"].dtype == torch.float16 and shipped["0.bias"].dtype == torch.float32
    assert stored["float16_tensors"] == 1 and stored["float16_numbers"] == 64 * 128
    assert 0 < stored["largest_relative_rounding"] <= 2**-11
    again = nn.Sequential(nn.Linear(64, 128), nn.Linear(128, 3))
    again.load_state_dict(shipped)
    assert again[0].weight.dtype == torch.float32
    assert torch.equal(again[0].weight, big[0].weight.half().float()) and torch.equal(
        again[1].bias, big[1].bias
    )


def test_a_likelihood_model_ships_only_its_lstm_weights_in_half_precision() -> None:
    """MoGlow's and the Gaussian baselines' likelihoods are sensitive to rounding everywhere but in their LSTM
    weights: a coupling's (under a prefix) and a baseline's own (at the top level)."""
    flow = nn.ModuleDict({"lstm": nn.LSTM(64, 32), "out": nn.Linear(96, 64), "linear": nn.Linear(64, 64)})
    for prefix in ("flow.layers.2.", ""):
        state = {f"{prefix}{key}": value for key, value in flow.state_dict().items()}
        shipped, stored = reference.half_precision(state, reference.LIKELIHOOD_HALF_TENSORS)
        halved = sorted(key for key, value in shipped.items() if value.dtype == torch.float16)
        assert halved == [f"{prefix}lstm.weight_hh_l0", f"{prefix}lstm.weight_ih_l0"]
        assert stored["float16_numbers"] == 128 * 64 + 128 * 32
    assert {"moglow", "moglow_gaussian_ar", "real_moglow_gaussian_ar"} <= set(reference.LIKELIHOOD_RUNS)


def test_a_reference_is_found_by_its_data_shape_not_its_data_bits(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Another CPU rounds the training data differently, so its fingerprints differ: the reference model is
    still the run's; data of another shape is another run."""
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    monkeypatch.delenv("MOTIONLAB_RETRAIN", raising=False)
    monkeypatch.setattr(reference, "REFERENCE_DIR", tmp_path / "reference")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "first"))
    here = {"x": "0123456789abcdef-(32, 4)", "window": 8}
    train_or_load("tiny_reference", MODEL_CONFIG, make_model(), loss_fn, data(), CFG, data_config=here)
    reference.export(tmp_path / "first", tmp_path / "reference")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "second"))
    elsewhere = {"x": "fedcba9876543210-(32, 4)", "window": 8}
    assert is_cached("tiny_reference", MODEL_CONFIG, CFG, elsewhere)
    result = train_or_load(
        "tiny_reference", MODEL_CONFIG, make_model(), loss_fn, data(), CFG, data_config=elsewhere
    )
    assert result.loaded_from_cache and result.path.parent == tmp_path / "reference"
    assert not is_cached("tiny_reference", MODEL_CONFIG, CFG, {"x": "fedcba9876543210-(33, 4)", "window": 8})
    assert not is_cached("tiny_reference", MODEL_CONFIG, CFG, {**here, "window": 9})


def _values_of(key: str, tree: object) -> list[object]:
    if isinstance(tree, dict):
        return [v for k, v in tree.items() if k == key] + [
            x for v in tree.values() for x in _values_of(key, v)
        ]
    if isinstance(tree, list):
        return [x for v in tree for x in _values_of(key, v)]
    return []


def test_the_shipped_models_trained_on_synthetic_data_name_the_generator_version_of_today() -> None:
    """A run on the synthetic benchmark whose identity names the generator's version is found only under
    today's version: a manifest with another one would be passed over, and the course would retrain that
    model quietly."""
    from motionlab.data.synthetic import GENERATOR_VERSION

    named = {
        path.name: versions
        for path in sorted(reference.REFERENCE_DIR.glob("*.json"))
        if (versions := _values_of("generator", json.loads(path.read_text())["config"]))
    }
    assert named, "no shipped model names the generator's version (the MoGlow runs of chapter 06 do)"
    stale = {name: versions for name, versions in named.items() if set(versions) != {GENERATOR_VERSION}}
    assert not stale, f"trained under another generator version than {GENERATOR_VERSION}: {stale}"


def test_a_run_without_a_reference_is_trained_and_named_as_trained_here(
    shipped: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    other = replace(CFG, steps=50)  # a configuration no reference model has
    trained = train_or_load("tiny_other", MODEL_CONFIG, make_model(), loss_fn, data(), other)
    assert not trained.loaded_from_cache
    run()  # loaded from its reference: not listed
    assert reference.trained_here() == ["tiny_other"]
    monkeypatch.setenv("MOTIONLAB_RETRAIN", "1")  # a build that retrains everything lists nothing
    reference.trained_log().unlink()
    run()
    assert reference.trained_here() == []


def test_levelling_phrase_says_which_way_the_curve_went() -> None:
    from motionlab.train.reference import levelling_phrase

    assert levelling_phrase({"last_fifth_share": 0.035, "levelled": True}).endswith(
        "3.5% of its fall over the last fifth: levelled off"
    )
    assert levelling_phrase({"last_fifth_share": 0.2, "levelled": False}).endswith("still falling")
    assert levelling_phrase({"last_fifth_share": -0.1, "levelled": True}).startswith(
        "rose over the last fifth by 10.0%"
    )
