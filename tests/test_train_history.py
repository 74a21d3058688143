"""History records, the training figure and the batch sources, checked against hand computations."""

from __future__ import annotations

import io

import numpy as np
import pytest
import torch
from matplotlib.figure import Figure

from motionlab.train import History, TensorBatches, plot_history
from motionlab.train.batches import epoch_batches, epoch_seed
from motionlab.train.plot import running_mean


def _history() -> History:
    history = History()
    for step, (epoch, loss) in enumerate([(0, 4.0), (0, 2.0), (1, 3.0), (1, 1.0), (2, 5.0)]):
        history.record_step(
            step, epoch, {"loss": loss, "kl": loss / 2}, {"beta": step / 10}, 1e-3, 10.0 - step
        )
    history.record_validation(2, {"loss": 2.5, "kl": 1.25})
    history.record_validation(5, {"loss": 1.5, "kl": 0.75})
    return history


def test_epoch_and_final_means_by_hand() -> None:
    history = _history()
    means = history.epoch_means()
    np.testing.assert_allclose(means["loss"], [3.0, 2.0, 5.0])
    np.testing.assert_allclose(means["kl"], [1.5, 1.0, 2.5])
    assert history.final_means() == {"loss": 5.0, "kl": 2.5}
    assert len(history) == 5 and history.coeffs["beta"] == pytest.approx([0, 0.1, 0.2, 0.3, 0.4])


def test_term_names_must_not_change() -> None:
    history = _history()
    with pytest.raises(ValueError, match="step 5"):
        history.record_step(5, 2, {"loss": 1.0}, {}, 1e-3, 1.0)
    with pytest.raises(ValueError, match="validation"):
        history.record_validation(6, {"loss": 1.0})


def test_round_trip_through_a_weights_only_checkpoint() -> None:
    history = _history()
    buffer = io.BytesIO()
    torch.save({"history": history.to_dict()}, buffer)
    buffer.seek(0)
    assert History.from_dict(torch.load(buffer, weights_only=True)["history"]) == history


@pytest.mark.parametrize(
    "corrupt, message",
    [
        (lambda d: d.pop("lr"), "fields"),
        (lambda d: d["terms"]["loss"].pop(), "terms\\['loss'\\]"),
        (lambda d: d["val_terms"]["kl"].append(0.0), "val_terms\\['kl'\\]"),
        (lambda d: d.__setitem__("grad_norm", (1.0,) * 5), "list"),
        (lambda d: d["terms"]["loss"].__setitem__(0, float("nan")), "non-finite"),
    ],
)
def test_from_dict_names_the_malformed_field(corrupt, message: str) -> None:
    data = _history().to_dict()
    corrupt(data)
    with pytest.raises(ValueError, match=message):
        History.from_dict(data)


def test_plot_history_draws_terms_validation_and_coefficients() -> None:
    fig = plot_history(_history(), logy=True, title="demo")
    assert isinstance(fig, Figure)
    main, twin = fig.axes
    labels = [line.get_label() for line in main.get_lines()]
    assert {"loss", "kl", "val loss", "val kl"} <= set(labels)
    assert [line.get_label() for line in twin.get_lines()] == ["coeff beta"]
    assert main.get_yscale() == "symlog"
    with pytest.raises(ValueError, match="empty"):
        plot_history(History())


def test_running_mean_matches_a_direct_computation() -> None:
    values = np.random.default_rng(0).normal(size=37)
    expected = [values[max(0, i - 4) : i + 1].mean() for i in range(37)]
    np.testing.assert_allclose(running_mean(values, 5), expected)
    with pytest.raises(ValueError, match="window"):
        running_mean(values, 0)


def test_tensor_batches_cover_every_sample_once_per_epoch() -> None:
    x = torch.arange(10.0)
    y = torch.arange(10) * 2
    batches = list(TensorBatches((x, y), drop_last=False)(0, torch.Generator().manual_seed(3), 4))
    assert [len(b[0]) for b in batches] == [4, 4, 2]
    seen = torch.cat([b[0] for b in batches])
    assert sorted(seen.tolist()) == x.tolist()
    assert torch.equal(torch.cat([b[1] for b in batches]), seen.long() * 2)
    dropped = list(TensorBatches(x)(0, torch.Generator().manual_seed(3), 4))
    assert [len(b) for b in dropped] == [4, 4]
    ordered = list(TensorBatches(x, drop_last=False, shuffle=False)(0, torch.Generator(), 4))
    assert torch.equal(torch.cat(ordered), x)


def test_tensor_batches_reject_bad_input() -> None:
    with pytest.raises(ValueError, match="first dimension"):
        TensorBatches((torch.zeros(3), torch.zeros(4)))
    with pytest.raises(TypeError, match="tensors"):
        TensorBatches(([1, 2],))
    with pytest.raises(ValueError, match="cannot fill"):
        next(TensorBatches(torch.zeros(3))(0, torch.Generator(), 4))


def test_epoch_order_depends_only_on_seed_and_epoch() -> None:
    source = TensorBatches(torch.arange(32.0))
    first = torch.cat(list(epoch_batches(source, seed=5, epoch=2, batch_size=8)))
    again = torch.cat(list(epoch_batches(source, seed=5, epoch=2, batch_size=8)))
    other_epoch = torch.cat(list(epoch_batches(source, seed=5, epoch=3, batch_size=8)))
    assert torch.equal(first, again) and not torch.equal(first, other_epoch)
    assert len({epoch_seed(5, e, s) for e in range(50) for s in (0, 1)}) == 100
