"""The chapter 04 widget's callback and wiring."""

import ipywidgets as widgets
import pytest
import torch
from test_motion_cell_common import motion_cell, perturb

from motionlab.widgets.motion_cell import motion_cell_widget, sample_motions


def _moving_model():
    model = motion_cell()
    perturb(model.word_decoder.net[-1].weight, 0.1)
    return model


def test_sample_motions_shape_and_seed():
    model = _moving_model()
    a = sample_motions(model, action=2, body=1, n_frames=10, seed=3, n_samples=2)
    assert a.shape == (2, 10, 22, 3)
    assert torch.equal(a, sample_motions(model, 2, 1, 10, 3, 2))
    assert not torch.equal(a, sample_motions(model, 2, 1, 10, 4, 2))
    assert not torch.equal(a[0], a[1])  # samples of one setting differ


def test_sample_motions_rejects_bad_arguments():
    model = _moving_model()
    with pytest.raises(ValueError, match="n_samples"):
        sample_motions(model, 0, 0, 10, 0, n_samples=0)
    with pytest.raises(ValueError, match="seed"):
        sample_motions(model, 0, 0, 10, -1)
    with pytest.raises(ValueError, match="action"):
        sample_motions(model, 6, 0, 10, 0)


def test_widget_builds_and_renders_its_first_samples():
    box = motion_cell_widget(
        _moving_model(),
        ["walk", "jog", "jump", "lift", "wave", "kick"],
        ["broad", "slender"],
        step=10,
        max_frames=60,
    )
    assert isinstance(box, widgets.VBox)
    output = box.children[-1]
    assert isinstance(output, widgets.Output) and len(output.outputs) == 1
