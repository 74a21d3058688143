import numpy as np
import pytest
import torch

from motionlab import config


def test_profile_defaults_to_full(monkeypatch):
    monkeypatch.delenv("MOTIONLAB_PROFILE", raising=False)
    assert config.profile() == "full"
    assert config.choose(quick=1, full=2) == 2


def test_quick_profile_is_case_insensitive(monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", " Quick ")
    assert config.is_quick()
    assert config.choose(quick=1, full=2) == 1
    assert config.course_dir().name == "course-quick"


def test_unknown_profile_is_rejected(monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "fast")
    with pytest.raises(ValueError, match="MOTIONLAB_PROFILE"):
        config.profile()


def test_build_dir_override(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    assert config.checkpoint_dir() == tmp_path / "checkpoints"


def test_seed_everything_is_reproducible():
    gen = config.seed_everything(7)
    a = (torch.rand(3, generator=gen), torch.rand(3), np.random.rand(3))
    gen = config.seed_everything(7)
    b = (torch.rand(3, generator=gen), torch.rand(3), np.random.rand(3))
    for x, y in zip(a, b):
        assert np.array_equal(np.asarray(x), np.asarray(y))


@pytest.mark.parametrize(
    "bad, error", [(-1, ValueError), (1.5, TypeError), ("3", TypeError), (True, TypeError)]
)
def test_seed_must_be_a_non_negative_integer(bad, error):
    with pytest.raises(error, match="seed_everything: seed must be"):
        config.seed_everything(bad)


def test_set_threads():
    assert config.set_threads(1) == 1
    assert torch.get_num_threads() == 1
    with pytest.raises(ValueError, match="thread"):
        config.set_threads(0)
    with pytest.raises(TypeError, match=r"set_threads: n \(the thread count\) must be an integer"):
        config.set_threads(1.5)


def _blas_threads() -> set[int]:
    """The thread counts of the BLAS libraries loaded in this process (NumPy's and SciPy's OpenBLAS)."""
    from threadpoolctl import threadpool_info

    return {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}


def test_the_blas_follows_torchs_thread_count():
    np.ones((4, 4)) @ np.ones((4, 4))  # the BLAS is loaded
    config.set_threads(1)
    assert _blas_threads() == {1}
    with config.threads(2):
        assert _blas_threads() == {2}
    assert _blas_threads() == {1}


def test_threads_sets_the_count_for_a_block_and_restores_it():
    config.set_threads(1)
    with config.threads(2) as n:
        assert n == 2 and torch.get_num_threads() == 2
    assert torch.get_num_threads() == 1
    with pytest.raises(RuntimeError, match="inside"):
        with config.threads(2):
            raise RuntimeError("inside")
    assert torch.get_num_threads() == 1
    with pytest.raises(ValueError, match="thread"):
        with config.threads(0):
            pass
    assert torch.get_num_threads() == 1


def test_a_relative_build_directory_is_taken_from_the_repository_root(monkeypatch, tmp_path) -> None:
    """The course driver runs in the repository and the kernels in notebooks/: both must mean one
    directory."""
    monkeypatch.setenv("MOTIONLAB_BUILD", "build-elsewhere")
    monkeypatch.chdir(tmp_path)
    assert config.build_dir() == config.REPO_ROOT / "build-elsewhere"
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "abs"))
    assert config.build_dir() == tmp_path / "abs"


def test_worker_processes_default_to_two_and_follow_the_environment(monkeypatch):
    monkeypatch.delenv("MOTIONLAB_PROCESSES", raising=False)
    assert config.processes() == 2
    monkeypatch.setenv("MOTIONLAB_PROCESSES", " 1 ")
    assert config.processes() == 1
    for bad in ("0", "two", "-1"):
        monkeypatch.setenv("MOTIONLAB_PROCESSES", bad)
        with pytest.raises(ValueError, match=f"MOTIONLAB_PROCESSES must be an integer >= 1, got '{bad}'"):
            config.processes()


def test_train_many_takes_its_processes_from_the_environment(monkeypatch):
    """A call that names no process count runs everything here when MOTIONLAB_PROCESSES is 1."""
    from motionlab.train import many

    seen = []
    monkeypatch.setattr(many, "run_chains", lambda chains, processes: seen.append(processes) or [])
    monkeypatch.setattr(many, "_load_all", lambda *args: {})
    monkeypatch.setenv("MOTIONLAB_PROCESSES", "1")
    many.train_many({})
    many.train_many({}, processes=2)  # a caller's own choice stands
    assert seen == [1, 2]
