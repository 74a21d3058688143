"""The training command ``python -m motionlab.apps.training``: every family in the quick config, bad
arguments, a 2-process torchrun against one process with the same global batch, and resuming an interrupted
run."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from motionlab import config, paths
from motionlab.apps.families import FAMILIES, family
from motionlab.apps.training import main
from motionlab.train.runtime import Execution, executing, local_batch, shard_indices

VENV_BIN = Path(sys.executable).parent
#: Seconds for the 2-process torchrun of 3 steps (about 20 s here, torch's start included).
TORCHRUN_SECONDS = 600


def fresh_build(root: Path) -> Path:
    """An empty build folder sharing the course's generated data (so nothing is loaded from the cache)."""
    data = paths.build_dir() / "data"
    data.mkdir(parents=True, exist_ok=True)
    root.mkdir(parents=True)
    (root / "data").symlink_to(data, target_is_directory=True)
    return root


def command_env(build: Path) -> dict[str, str]:
    root = str(Path(__file__).resolve().parents[1])
    return {
        **os.environ,
        "MOTIONLAB_BUILD": str(build),
        "PYTHONPATH": root + os.pathsep + os.environ.get("PYTHONPATH", ""),
        "OMP_NUM_THREADS": "1",
    }


def state_dict(out: Path) -> dict[str, torch.Tensor]:
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    return torch.load(checkpoint, weights_only=True)["state_dict"]


@pytest.mark.parametrize("name", list(FAMILIES))
def test_every_family_trains_and_is_measured_in_the_quick_config(name, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    steps = 10 if name == "motion_cell" else 2  # the Motion Cell's schedules need 10 steps
    out = tmp_path / "out"
    code = main([name, "--config", "quick", "--steps", str(steps), "--device", "cpu", "--out", str(out)])
    assert code == 0
    run = json.loads((out / "run.json").read_text())
    experiment = family(name)
    assert run["family"] == name and run["run"] == experiment.DEFAULT_RUN
    assert run["chapter"] == experiment.CHAPTER
    assert run["steps"] == steps and run["train_config"]["steps"] == steps
    history = json.loads((out / "history.json").read_text())
    assert len(history["step"]) == steps
    evaluation = json.loads((out / "evaluation.json").read_text())
    assert evaluation and all(
        value is not None for value in evaluation.values() if value != evaluation.get("note")
    )
    payload = torch.load(next((out / "checkpoints").glob("*.pt")), weights_only=True)
    assert payload["format"] == 1 and payload["state_dict"]
    assert f"results in {out}" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, message",
    [
        (["gan"], "invalid choice: 'gan'"),
        (["vae", "--set", "no_such_field=3"], "has no field 'no_such_field'"),
        (["vae", "--set", "clip_steps=many"], "expected a value of type int"),
        (["vae", "--set", "lr=-1"], "invalid configuration"),
        (["odmo", "--set", "model=3"], "is a nested config"),
        (["odmo_cmu", "--data", "/no/such/folder"], "no such folder"),
        (["odmo_cmu", "--data", ".", "--config", "quick"], "holds neither"),
        (["odmo", "--data", ".", "--config", "quick"], "not on a folder"),
        (["moglow", "--data", ".", "--config", "quick"], "not on a folder"),
        (["vae", "--data", "."], "not on a folder"),
        (["vae", "--steps", "0"], "expected a positive integer, got 0"),
        (["vae", "--run", "gan", "--config", "quick"], "vae has the runs"),
        (["vae", "--config", "quick", "--out", __file__], "a file, not a folder"),
        (["odmo", "--config", "quick", "--set", "frame_stride=7"], "the config expects clips of 40 frames"),
    ],
)
def test_bad_arguments_get_one_line_and_exit_code_2(argv, message, monkeypatch, capsys):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_odmo_trains_on_a_downloaded_action2motion_folder(tmp_path, monkeypatch):
    """``--data FOLDER``: ODMO on clips in Action2Motion's layout (``pose_clip.csv`` and ``.npy`` files in
    CMU units, y up), as a user downloads them."""
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(fresh_build(tmp_path / "build")))
    from motionlab.data import cmu_mocap as cm

    generator = torch.Generator().manual_seed(0)
    folder = tmp_path / "a2m"
    (folder / "mocap_3djoints").mkdir(parents=True)
    rows = []
    for action in range(len(cm.ACTION_NAMES)):
        for k in range(18):  # enough clips per class for the quick config's stratified 112
            name = f"{action:02d}_{k:02d}"
            clip = torch.randn(30, cm.N_JOINTS, 3, generator=generator) + torch.tensor([0.0, 16.0, 0.0])
            np.save(folder / "mocap_3djoints" / f"{name}.npy", clip.numpy().astype(np.float32))
            rows.append(f"{name},{action}")
    (folder / "pose_clip.csv").write_text("\n".join(["motion,action_type", *rows]) + "\n")
    out = tmp_path / "out"
    argv = ["odmo_cmu", "--data", str(folder), "--config", "quick", "--steps", "2", "--out", str(out)]
    assert main([*argv, "--skip-evaluation"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["data"] == str(folder) and run["steps"] == 2
    (folder / "pose_clip.csv").write_text("motion,action_type\n00_00,Yoga\n")  # a label ODMO's set lacks
    assert main(argv) == 2


def test_help_lists_families_configs_and_data_sets(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--help"])
    assert exit_info.value.code == 0
    text = capsys.readouterr().out
    for word in (*FAMILIES, *FAMILIES.values(), "quick", "full", "long", "--data PATH", "--tensorboard"):
        assert word in text


def test_tensorboard_is_an_optional_extra(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")  # the command sets it: restored after the test
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", None)  # as when tensorboard is not installed
    assert main(["vae", "--config", "quick", "--tensorboard", str(tmp_path)]) == 2
    assert "pip install 'motionlab[tensorboard]'" in capsys.readouterr().err


def test_a_cuda_request_without_a_gpu_is_refused(monkeypatch, capsys):
    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert main(["vae", "--device", "cuda"]) == 2
    assert "no CUDA device" in capsys.readouterr().err


def test_each_process_keeps_the_distributed_samplers_share_of_a_batch():
    x, label = torch.arange(12).view(6, 2), torch.arange(6)
    shares = [local_batch((x, label), Execution(rank=r, world_size=2)) for r in (0, 1)]
    assert torch.equal(shares[0][1], torch.tensor([0, 2, 4])) and torch.equal(
        shares[1][1], torch.tensor([1, 3, 5])
    )
    assert torch.equal(torch.sort(torch.cat([s[0] for s in shares]), dim=0).values, x)
    with pytest.raises(ValueError, match="does not split evenly"):
        shard_indices(5, 0, 2)


def test_two_processes_under_torchrun_match_one_process_with_the_same_global_batch(tmp_path, monkeypatch):
    """A deterministic loss (the pose autoencoder: mean over the batch, no noise), 3 steps of batch 64: each
    of the two gloo processes gets 32 samples of every batch, and the weights end where one process's do."""
    args = ["vae", "--config", "quick", "--run-name", "pose_ae", "--steps", "3", "--device", "cpu"]
    two = subprocess.Popen(
        [
            str(VENV_BIN / "torchrun"),
            "--standalone",
            "--nproc-per-node",
            "2",
            "-m",
            "motionlab.apps.training",
            *args,
        ]
        + ["--out", str(tmp_path / "two")],
        env=command_env(fresh_build(tmp_path / "build_two")),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:  # meanwhile, one process here
        monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
        monkeypatch.setenv("MOTIONLAB_BUILD", str(fresh_build(tmp_path / "build_one")))
        assert main([*args, "--out", str(tmp_path / "one")]) == 0
    finally:
        try:
            _, err = two.communicate(timeout=TORCHRUN_SECONDS)
        except subprocess.TimeoutExpired:
            two.kill()
            _, err = two.communicate()
            pytest.fail(
                f"torchrun did not end within {TORCHRUN_SECONDS} s; the end of its stderr:\n{err[-3000:]}"
            )
    assert two.returncode == 0, err
    assert json.loads((tmp_path / "two" / "run.json").read_text())["processes"] == 2
    one, two_weights = state_dict(tmp_path / "one"), state_dict(tmp_path / "two")
    assert one.keys() == two_weights.keys() and one
    for key, value in one.items():
        torch.testing.assert_close(two_weights[key], value, rtol=1e-5, atol=1e-6)


class StopAt:
    """A callback that fails at ``step``, as a killed run would stop (the state written every 2 steps)."""

    def __init__(self, step: int) -> None:
        self.step = step

    def __call__(self, step, model, history) -> None:
        if step == self.step:
            raise RuntimeError(f"stopped at step {step}")


def test_an_interrupted_run_resumes_to_the_weights_of_an_uninterrupted_one(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    experiment = family("vae")
    cfg = experiment.with_steps(experiment.ExperimentConfig.quick(), "pose_vae", 6)
    run = experiment.runs(cfg, experiment.load_data(cfg))["pose_vae"]  # samples noise: RNG state
    results = {}
    for name in ("straight", "resumed"):
        monkeypatch.setenv("MOTIONLAB_BUILD", str(fresh_build(tmp_path / name)))
        if name == "resumed":
            with pytest.raises(RuntimeError, match="stopped at step 4"):
                with executing(Execution(checkpoint_every=2, callbacks=(StopAt(4),), resume=True)):
                    run.train(progress=False)
            assert list((config.checkpoint_dir()).glob("*.resume.pt"))
        with executing(Execution(checkpoint_every=2, resume=True)):
            results[name] = run.train(progress=False)
    (straight, _), (resumed, result) = results["straight"], results["resumed"]
    assert result.resumed_from_step == 4 and not result.loaded_from_cache
    for key, value in straight.state_dict().items():
        assert torch.equal(resumed.state_dict()[key], value), key


def test_the_chapter_loads_what_the_command_trained(tmp_path, monkeypatch):
    """The command writes the chapter's own cache entry: the chapter's run (same config) loads it."""
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(fresh_build(tmp_path / "build")))
    out = tmp_path / "out"
    assert main(["vae", "--config", "quick", "--run", "pose_ae", "--skip-evaluation", "--out", str(out)]) == 0
    from motionlab.models.vae.experiment import ExperimentConfig, runs

    chapter_run = runs(ExperimentConfig.current(), n_actions=6)["pose_ae"]
    assert chapter_run.is_cached()
    model, result = chapter_run.train(progress=False)
    assert result.loaded_from_cache
    written = state_dict(out)
    for key, value in model.state_dict().items():
        assert torch.equal(written[key], value), key


@pytest.mark.parametrize("name", list(FAMILIES))
def test_every_family_module_has_the_same_few_names(name):
    experiment = family(name)
    assert (Path(__file__).resolve().parents[1] / "notebooks" / f"{experiment.CHAPTER}.ipynb").exists()
    assert isinstance(experiment.DEFAULT_RUN, str)
    for profile in ("quick", "full", "long"):
        assert callable(getattr(experiment.ExperimentConfig, profile))
    for function in ("load_data", "runs", "measure", "with_steps"):
        assert callable(getattr(experiment, function)), function
    with pytest.raises(ValueError, match="unknown family 'gan'"):
        family("gan")
