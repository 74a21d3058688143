"""The build's measurement store (:mod:`motionlab.train.measurements`): the same measurement of the same
weights is read back; another argument, other weights or a damaged entry mean measuring again."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import pytest
import torch
from torch import nn

from motionlab.train.measurements import measure_once, measurement_path


def _count(log: Path, scale: float, name: str, model: nn.Module) -> dict[str, float]:
    """A measurement that leaves a line in ``log`` each time it really runs."""
    with log.open("a") as file:
        file.write(f"{name}\n")
    return {"weight_sum": scale * float(model.weight.detach().sum())}


@pytest.fixture
def build(monkeypatch, tmp_path: Path) -> Path:
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    return tmp_path / "build"


def _model(seed: int) -> nn.Module:
    torch.manual_seed(seed)
    return nn.Linear(3, 2)


def test_a_measurement_is_made_once_and_read_back(build: Path, tmp_path: Path) -> None:
    log = tmp_path / "log.txt"
    model = _model(0)
    first = measure_once(partial(_count, log, 2.0), "mcell", model)
    again = measure_once(partial(_count, log, 2.0), "mcell", _model(0))  # the same weights, another object
    assert first == again == {"weight_sum": 2.0 * float(model.weight.detach().sum())}
    assert log.read_text().splitlines() == ["mcell"]
    assert measurement_path(partial(_count, log, 2.0), "mcell", model).parent.parent == build / "measurements"


def test_another_argument_other_weights_or_another_name_are_measured_afresh(
    build: Path, tmp_path: Path
) -> None:
    log = tmp_path / "log.txt"
    measure_once(partial(_count, log, 2.0), "mcell", _model(0))
    assert measure_once(partial(_count, log, 3.0), "mcell", _model(0))["weight_sum"] == pytest.approx(
        3.0 * float(_model(0).weight.detach().sum())
    )
    measure_once(partial(_count, log, 2.0), "mcell", _model(1))
    measure_once(partial(_count, log, 2.0), "erd", _model(0))
    assert log.read_text().splitlines() == ["mcell", "mcell", "mcell", "erd"]


def test_a_damaged_entry_is_measured_again_and_replaced(build: Path, tmp_path: Path) -> None:
    log = tmp_path / "log.txt"
    then, model = partial(_count, log, 2.0), _model(0)
    expected = measure_once(then, "mcell", model)
    path = measurement_path(then, "mcell", model)
    path.write_bytes(path.read_bytes()[:5])  # truncated, as a killed write would leave it without the rename
    assert measure_once(then, "mcell", model) == expected
    assert measure_once(then, "mcell", model) == expected
    assert len(log.read_text().splitlines()) == 2  # measured again once, then read
    assert not list(path.parent.glob(".*.tmp"))  # no temporary file left behind


def test_the_key_is_the_same_in_another_process(tmp_path: Path) -> None:
    """Tensors enter the key by their bytes: torch's own pickles differ from process to process."""
    import subprocess
    import sys

    from motionlab.train.measurements import measurement_key

    statements = (
        "torch.manual_seed(0)\ndata = {'clips': torch.randn(4, 3), 'judge': nn.Linear(3, 2)}\n"
        "key = measurement_key(partial(print, data), 'run', nn.Linear(3, 2))"
    )
    here: dict = {"torch": torch, "nn": nn, "partial": partial, "measurement_key": measurement_key}
    exec(statements, here)  # this process, whose torch has pickled other objects before
    program = (
        "import torch\nfrom functools import partial\nfrom torch import nn\n"
        "from motionlab.train.measurements import measurement_key\n"
        f"torch.set_num_threads({torch.get_num_threads()})\n{statements}\nprint(key)"  # threads enter the key
    )
    there = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=True).stdout
    assert there.strip() == here["key"] and len(here["key"]) == 20


def test_another_version_of_the_code_starts_afresh_and_drops_the_old_entries(
    build: Path, tmp_path: Path, monkeypatch
) -> None:
    from motionlab.train import measurements

    log = tmp_path / "log.txt"
    then, model = partial(_count, log, 2.0), _model(0)
    old = measurement_path(then, "mcell", model)
    measure_once(then, "mcell", model)
    monkeypatch.setattr(measurements, "source_digest", lambda: "f" * 64)  # the package's source edited
    new = measurement_path(then, "mcell", model)
    assert new.parent != old.parent and new.parent.parent == old.parent.parent == build / "measurements"
    measure_once(then, "mcell", model)
    assert len(log.read_text().splitlines()) == 2  # measured again under the new code
    assert new.is_file() and not old.parent.exists()  # the old version's entries are gone
