"""motionlab.validation's declared constraints: config dataclasses carry their fields' limits and
:class:`~motionlab.validation.Checked` checks them when an object is built (with the exception policy:
TypeError for a wrong type, ValueError for a wrong value), through inheritance and ``dataclasses.replace``."""

import dataclasses
import numbers

import numpy as np
import pytest

from motionlab.validation import (
    CHECK,
    Checked,
    InstanceOf,
    Number,
    OneOf,
    TupleOf,
    choice,
    flag,
    instance,
    integer,
    real,
    tuple_of,
)


@dataclasses.dataclass(frozen=True)
class Inner(Checked):
    width: int = integer(4, minimum=1)


@dataclasses.dataclass(frozen=True)
class Example(Checked):
    steps: int = integer(10, minimum=1, maximum=100)
    lr: float = real(1e-3, above=0)
    dropout: float = real(0.0, minimum=0, below=1, note="a probability")
    logvar: float = real(0.0)
    limit: float = real(np.inf, above=0, finite=False)
    cap: int | None = integer(None, minimum=2, optional=True)
    seed: int = integer(0, minimum=0, kind=int)
    kind: str = choice(("conv", "gru"), "gru")
    switch: bool = flag(True)
    inner: Inner = instance(Inner, default_factory=Inner)
    rates: tuple[float, ...] = tuple_of((0.5,), minimum=0, maximum=1, nonempty=True)
    pair: tuple[int, int] = tuple_of((1, 2), kind=numbers.Integral, minimum=0, length=2)
    names: tuple[str, ...] = tuple_of(("a",), kind=str)
    variants: tuple[str, ...] = tuple_of((), choices=("x", "y"))


@dataclasses.dataclass(frozen=True)
class Derived(Example):
    """Changes two defaults (the limits stay the base's), adds a field and a cross-field rule."""

    steps: int = 20
    lr: float = 1e-2
    warmup: int = integer(0, minimum=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.warmup > self.steps:
            raise ValueError(f"Derived: warmup ({self.warmup}) must not exceed steps ({self.steps})")


def test_the_defaults_pass_and_the_fields_keep_their_values():
    example = Example()
    assert (example.steps, example.lr, example.cap, example.inner) == (10, 1e-3, None, Inner())
    assert dataclasses.asdict(example)["rates"] == (0.5,)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"steps": 0}, ValueError, r"Example: steps must be in \[1, 100\], got 0"),
        ({"steps": 2.5}, TypeError, r"Example: steps must be an integer, got 2.5 \(float\)"),
        ({"steps": True}, TypeError, r"Example: steps must be an integer, got True \(bool\)"),
        ({"lr": 0.0}, ValueError, "Example: lr must be greater than 0, got 0.0"),
        ({"lr": "0.1"}, TypeError, r"Example: lr must be a real number, got '0.1' \(str\)"),
        ({"dropout": 1.0}, ValueError, r"Example: dropout \(a probability\) must be in \[0, 1\), got 1.0"),
        ({"logvar": float("nan")}, ValueError, "Example: logvar must be a finite number, got nan"),
        ({"limit": float("nan")}, ValueError, "Example: limit must be a finite number, got nan"),
        ({"cap": 1}, ValueError, "Example: cap must be at least 2, got 1"),
        ({"seed": np.int64(3)}, TypeError, r"Example: seed must be int, got .*3.* \(int64\)"),
        ({"kind": "rnn"}, ValueError, "Example: kind must be one of 'conv', 'gru', got 'rnn'"),
        ({"switch": 1}, TypeError, r"Example: switch must be a bool, got 1 \(int\)"),
        ({"inner": {"width": 4}}, TypeError, r"Example: inner must be an Inner, got \{'width': 4\} \(dict\)"),
        ({"rates": [0.5]}, TypeError, r"Example: rates must be a tuple, got \[0.5\] \(list\)"),
        ({"rates": ()}, ValueError, r"Example: rates must be a non-empty tuple, got \(\)"),
        ({"rates": (0.5, 2.0)}, ValueError, r"Example: rates\[1\] must be in \[0, 1\], got 2.0"),
        ({"pair": (1, 2, 3)}, ValueError, r"Example: pair must be a tuple of 2 entries, got \(1, 2, 3\)"),
        ({"pair": (1, 0.5)}, TypeError, r"Example: pair\[1\] must be an integer, got 0.5 \(float\)"),
        ({"names": ("a", 1)}, TypeError, r"Example: names\[1\] must be a str, got 1 \(int\)"),
        ({"variants": ("x", "z")}, ValueError, r"Example: variants\[1\] must be one of 'x', 'y', got 'z'"),
    ],
)
def test_a_declared_limit_is_checked_with_the_policy_and_a_message_naming_class_field_and_value(
    kwargs, error, message
):
    with pytest.raises(error, match=message):
        Example(**kwargs)


def test_none_passes_only_where_declared_optional_and_infinity_only_where_not_finite():
    assert Example(cap=None).cap is None
    assert Example(limit=float("inf")).limit == float("inf")
    with pytest.raises(TypeError, match=r"Example: steps must be an integer, got None \(NoneType\)"):
        Example(steps=None)


def test_a_nested_config_checks_itself():
    with pytest.raises(ValueError, match="Inner: width must be at least 1, got 0"):
        Example(inner=Inner(width=0))


def test_a_subclass_keeps_the_base_limits_when_it_changes_defaults_and_adds_its_own_rules():
    derived = Derived()
    assert (derived.steps, derived.lr, derived.warmup) == (20, 1e-2, 0)
    with pytest.raises(ValueError, match=r"Derived: steps must be in \[1, 100\], got 0"):
        Derived(steps=0)
    with pytest.raises(ValueError, match="Derived: lr must be greater than 0"):
        Derived(lr=-1.0)
    with pytest.raises(ValueError, match="Derived: warmup must be at least 0, got -1"):
        Derived(warmup=-1)
    with pytest.raises(ValueError, match=r"Derived: warmup \(30\) must not exceed steps \(20\)"):
        Derived(warmup=30)


def test_replace_checks_the_new_object_and_leaves_the_old_one():
    example = Example()
    assert dataclasses.replace(example, steps=50).steps == 50
    with pytest.raises(ValueError, match="Example: steps must be in"):
        dataclasses.replace(example, steps=500)
    with pytest.raises(ValueError, match="Derived: warmup"):
        dataclasses.replace(Derived(), warmup=25)
    assert example.steps == 10


def test_the_constraint_rides_in_the_field_metadata():
    spec = {f.name: f for f in dataclasses.fields(Example)}
    assert spec["steps"].metadata[CHECK] == Number(numbers.Integral, 1, 100)
    assert spec["lr"].metadata[CHECK] == Number(numbers.Real, 0, None, include_minimum=False)
    assert spec["kind"].metadata[CHECK] == OneOf(("conv", "gru"))
    assert spec["switch"].metadata[CHECK] == InstanceOf(bool)
    assert spec["pair"].metadata[CHECK] == TupleOf(Number(numbers.Integral, 0), length=2)
    assert spec["cap"].metadata["optional"] and not spec["steps"].metadata["optional"]


def test_a_bound_is_inclusive_or_exclusive_not_both():
    with pytest.raises(ValueError, match="either inclusive"):
        real(1.0, minimum=0, above=0)


def test_the_real_motion_config_of_chapter_10_inherits_chapter_08s_limits():
    from motionlab.models.odmo.experiment import RealExperimentConfig

    with pytest.raises(ValueError, match="RealExperimentConfig: steps must be at least 1, got 0"):
        RealExperimentConfig(steps=0)
    with pytest.raises(TypeError, match="RealExperimentConfig: model must be an ODMOConfig"):
        RealExperimentConfig(model=None)
    with pytest.raises(ValueError, match=r"RealExperimentConfig: variants\[0\] must be one of"):
        RealExperimentConfig(variants=("ODMO + prior on mu (extension)",))
    assert RealExperimentConfig(n_clips=None).n_clips is None
