"""The MotionSet file format, the command line and the committed reference data set."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motionlab.data import MotionSet
from motionlab.data.store import SCHEMA
from motionlab.data.synthetic import generate

REFERENCE = Path(__file__).resolve().parents[1] / "data_synthetic"


@pytest.fixture(scope="module")
def data():
    return generate(seed=4, n_per_mode=1, seconds=2.0)


def test_save_load_round_trip_is_bitwise(data, tmp_path):
    for compress in (False, True):
        path = data.save(tmp_path / f"set_{compress}.npz", compress=compress)
        loaded = MotionSet.load(path)
        assert loaded.checksums() == data.checksums()
    assert sorted(data.arrays()) == sorted(SCHEMA)


def _write(path: Path, arrays: dict) -> Path:
    with open(path, "wb") as handle:
        np.savez(handle, **arrays)
    return path


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda a: a.pop("contacts"), "missing keys \\['contacts'\\]"),
        (lambda a: a.update(extra=np.zeros(2)), "unknown keys \\['extra'\\]"),
        (
            lambda a: a.update(positions=a["positions"].astype(np.float64)),
            "'positions' must have dtype float32",
        ),
        (lambda a: a.update(mode=a["mode"][:-1]), "'mode' axis 0 \\(N\\)"),
        (lambda a: a.update(rotations=a["rotations"][..., :3]), "'rotations' axis 3"),
        (lambda a: a["positions"].__setitem__((0, 0, 0, 0), np.nan), "'positions' contains NaN"),
        (lambda a: a.update(rotations=2 * a["rotations"]), "unit quaternions"),
        (lambda a: a["mode"].__setitem__(0, 12), "'mode' values must lie in \\[0, 12\\)"),
        (lambda a: a["action"].__setitem__(0, 3), "disagrees with 'mode_action"),
        (lambda a: a["parents"].__setitem__(3, 5), "'parents'"),
        (lambda a: a.update(fps=np.array(0)), "'fps' must be positive"),
    ],
)
def test_load_names_the_bad_file_and_key(data, tmp_path, change, message):
    arrays = {key: value.copy() for key, value in data.arrays().items()}
    change(arrays)
    path = _write(tmp_path / "bad.npz", arrays)
    with pytest.raises(ValueError, match=message) as info:
        MotionSet.load(path)
    assert "bad.npz" in str(info.value)


def test_wrong_dtype_is_a_type_error_in_memory_and_a_value_error_in_a_file(data):
    arrays = data.arrays() | {"positions": data.positions.astype(np.float64)}
    with pytest.raises(TypeError, match="MotionSet: 'positions' must have dtype float32, got float64"):
        MotionSet(**arrays)


def test_load_rejects_files_that_are_not_archives(tmp_path):
    path = tmp_path / "broken.npz"
    path.write_text("hello")
    with pytest.raises(ValueError, match="broken.npz is not a readable .npz archive"):
        MotionSet.load(path)
    with pytest.raises(FileNotFoundError, match="no such file"):
        MotionSet.load(tmp_path / "missing.npz")


def test_subset(data):
    walk = data.subset(data.action == 0)
    assert walk.n_clips == 2 and set(walk.mode_names) == set(data.mode_names)
    np.testing.assert_array_equal(walk.positions, data.positions[:2])
    picked = data.subset(np.array([5, 0]))
    np.testing.assert_array_equal(picked.mode, data.mode[[5, 0]])
    with pytest.raises(ValueError, match="mask must have shape"):
        data.subset(np.ones(3, bool))
    with pytest.raises(TypeError, match="boolean mask or integer indices"):
        data.subset(np.array([0.5]))


def test_command_line_writes_the_documented_keys_and_shapes(tmp_path):
    out, sums = tmp_path / "cli.npz", tmp_path / "sums.json"
    completed = subprocess.run(
        [
            sys.executable,
            "-m",
            "motionlab.data.synthetic",
            "--out",
            str(out),
            "--seed",
            "3",
            "--n-per-mode",
            "1",
            "--seconds",
            "1.5",
            "--checksums",
            str(sums),
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "wrote 12 clips x 45 frames" in completed.stdout
    with np.load(out) as archive:
        shapes = {key: archive[key].shape for key in archive.files}
        dtypes = {key: archive[key].dtype for key in archive.files}
    assert shapes == {
        "positions": (12, 45, 22, 3),
        "rotations": (12, 45, 22, 4),
        "action": (12,),
        "mode": (12,),
        "body": (12,),
        "contacts": (12, 45, 4),
        "action_names": (6,),
        "mode_names": (12,),
        "mode_action": (12,),
        "parents": (22,),
        "offsets": (2, 22, 3),
        "fps": (),
    }
    assert (
        dtypes["positions"] == np.float32
        and dtypes["rotations"] == np.float32
        and dtypes["contacts"] == np.bool_
    )
    assert all(dtypes[k] == np.int64 for k in ("action", "mode", "body", "mode_action", "parents", "fps"))
    record = json.loads(sums.read_text())
    assert record["sha256"] == generate(seed=3, n_per_mode=1, seconds=1.5).checksums()


def test_reference_set_regenerates():
    """The committed file matches its checksums bitwise; regenerating it is bitwise on this machine and, on
    another CPU (whose SIMD sin/cos may differ in the last bit, see the data card), equal up to float32
    rounding: labels, skeletons and every other non-float array bitwise, positions and rotations to 1e-6."""
    record = json.loads((REFERENCE / "checksums.json").read_text())
    arguments = (record["seed"], record["n_per_mode"], record["seconds"], record["fps"], record["split"])
    regenerated = generate(*arguments)
    assert regenerated.checksums() == generate(*arguments).checksums()
    committed = MotionSet.load(REFERENCE / "reference_seed0.npz")
    assert committed.checksums() == record["sha256"]
    ours, theirs = regenerated.checksums(), record["sha256"]
    floats = {"positions", "rotations", "offsets"}
    assert {k: v for k, v in ours.items() if k not in floats} == {
        k: v for k, v in theirs.items() if k not in floats
    }
    for name in floats:
        np.testing.assert_allclose(
            getattr(regenerated, name), getattr(committed, name), rtol=0, atol=1e-6, err_msg=name
        )
    assert (REFERENCE / "reference_seed0.npz").stat().st_size < 2_000_000
