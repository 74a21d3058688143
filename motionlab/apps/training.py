"""``python -m motionlab.apps.training FAMILY ...``: train one run of a chapter's model family, longer or
elsewhere.

The command trains a chapter's run (``--run``, default the chapter's main model) from the chapter's own
``ExperimentConfig`` (``--config quick|full|long``, changed by ``--set key=value`` and ``--steps``), through
the course's one training loop and its checkpoint cache, then measures the model as the chapter does. It
writes into ``--out``: ``run.json`` (what was trained, how, how long), ``history.json`` (the loss history),
``evaluation.json`` (the chapter's measurements) and ``checkpoints/<name>-<hash>.pt`` (the cache entry).

Devices and processes: ``--device auto`` takes CUDA when there is one (bf16 mixed precision where the GPU
supports it); ``torchrun --nproc-per-node N -m motionlab.apps.training ...`` trains data-parallel
(:mod:`motionlab.train.runtime`; gloo on the CPU, nccl on CUDA), the first process logging and writing.

Bad arguments end the command with one line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import sys
import time
import typing
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from motionlab import arguments
from motionlab.apps.families import FAMILIES, family, jsonable
from motionlab.data.streaming import clip_files

CONFIGS = ("quick", "full", "long")
PROG = "python -m motionlab.apps.training"


class UsageError(ValueError):
    """A bad argument: reported in one line, exit code 2 (like every ``ValueError`` the command meets, e.g. a
    configuration the data cannot serve; :func:`motionlab.arguments.run`)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> typing.NoReturn:
        raise UsageError(message)


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def _non_negative(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def _help_epilog() -> str:
    lines = ["families (each a chapter's experiment module; --run defaults to the module's DEFAULT_RUN):"]
    lines += [f"  {name:12s} {module}" for name, module in FAMILIES.items()]
    lines += [
        "",
        "configs: quick (the tests' sizes: seconds), full (the chapter's reported runs), long (longer and",
        "  larger: see each family's ExperimentConfig.long()).",
        "",
        "--data PATH: a folder of clips for a family that reads folders (the _cmu families: a downloaded",
        "Action2Motion folder); without it every family trains on its chapter's data (the course benchmark,",
        "or the CMU clips of data_real/ for the _cmu families).",
        "The model goes into the course's checkpoint cache ($MOTIONLAB_BUILD/checkpoints, default build/),",
        "where the chapter looks for it, and a copy into --out (README: 'Training longer or on your own",
        "data').",
    ]
    return "\n".join(lines)


def parser() -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = _Parser(
        prog=PROG,
        description="Train one run of a chapter's model family and measure it as the chapter does.",
        epilog=_help_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("family", choices=list(FAMILIES), metavar="FAMILY", help=", ".join(FAMILIES))
    p.add_argument("--config", choices=CONFIGS, default="full", help="the experiment configuration (full)")
    p.add_argument(
        "--run",
        "--run-name",
        dest="run",
        help="which of the chapter's runs (default: the chapter's main model); under torchrun write "
        "--run-name, as torchrun reads --run as an abbreviation of its own --run-path",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change a field of the ExperimentConfig (dotted for nested configs, e.g. model.code_dim=32)",
    )
    p.add_argument("--data", type=Path, help="a folder of clips, for a family that reads folders (see below)")
    p.add_argument("--steps", type=_positive, help="optimiser steps of the run (overrides the config)")
    p.add_argument("--device", choices=("cpu", "cuda", "auto"), default="auto")
    p.add_argument("--out", type=Path, help="output folder (default build/train/FAMILY-CONFIG-RUN)")
    p.add_argument("--resume", action="store_true", help="continue an interrupted run of this configuration")
    p.add_argument(
        "--checkpoint-every",
        type=_positive,
        help="write the resumable state (weights, optimiser, RNG states) every N steps",
    )
    p.add_argument("--tensorboard", type=Path, metavar="DIR", help="also log the loss terms for TensorBoard")
    p.add_argument("--seed", type=_non_negative, help="seed of the initial weights and the batches")
    p.add_argument(
        "--skip-evaluation", action="store_true", help="train only (no evaluation.json; e.g. to time a run)"
    )
    return p


# --- --set key=value ---------------------------------------------------------------------------------------
def _convert(text: str, current: Any, key: str) -> Any:
    """``text`` as a value of the type of ``current`` (the field's present value)."""
    try:
        if isinstance(current, bool):
            if text.lower() in ("true", "1", "yes"):
                return True
            if text.lower() in ("false", "0", "no"):
                return False
            raise ValueError
        if isinstance(current, int):
            return int(text)
        if isinstance(current, float):
            return float(text)
        if isinstance(current, tuple):
            parts = [part.strip() for part in text.split(",") if part.strip()]
            return tuple(_convert(part, current[0], key) if current else part for part in parts)
        if current is None:
            return None if text.lower() == "none" else json.loads(text)
        if isinstance(current, str):
            return text
    except (ValueError, json.JSONDecodeError):
        raise UsageError(
            f"--set {key}={text}: expected a value of type {type(current).__name__}"
            + (" (comma-separated)" if isinstance(current, tuple) else "")
        ) from None
    raise UsageError(
        f"--set {key}: a field of type {type(current).__name__} cannot be set from the command line"
    )


def set_field(cfg: Any, key: str, text: str) -> Any:
    """``cfg`` (a frozen dataclass) with the dotted field ``key`` set from ``text``."""
    head, _, rest = key.partition(".")
    names = [f.name for f in dataclasses.fields(cfg)]
    if head not in names:
        raise UsageError(
            f"--set {key}: {type(cfg).__name__} has no field {head!r} (fields: {', '.join(names)})"
        )
    current = getattr(cfg, head)
    if rest:
        if not dataclasses.is_dataclass(current):
            raise UsageError(f"--set {key}: {head!r} is not a nested config")
        value = set_field(current, rest, text)
    elif dataclasses.is_dataclass(current):
        raise UsageError(f"--set {key}: {head!r} is a nested config; set one of its fields ({head}.NAME=...)")
    else:
        value = _convert(text, current, key)
    return dataclasses.replace(cfg, **{head: value})


def build_config(experiment: ModuleType, args: argparse.Namespace, run: str) -> Any:
    """The family's ExperimentConfig of ``--config``, ``--set`` and ``--steps`` applied."""
    cfg = getattr(experiment.ExperimentConfig, args.config)()
    try:
        for item in args.set:
            key, sep, text = item.partition("=")
            if not sep or not key:
                raise UsageError(f"--set expects KEY=VALUE, got {item!r}")
            cfg = set_field(cfg, key.strip(), text.strip())
        if args.steps is not None:
            cfg = experiment.with_steps(cfg, run, args.steps)
    except UsageError:
        raise
    except (ValueError, TypeError) as error:  # the config's own checks
        raise UsageError(f"invalid configuration: {error}") from None
    return cfg


# --- data, device, processes -------------------------------------------------------------------------------
def check_folder(name: str, experiment: ModuleType, path: Path | None) -> None:
    """``--data PATH``: the family reads folders, and the folder exists and holds clips."""
    if path is None:
        return
    if not getattr(experiment, "READS_FOLDER", False):
        raise UsageError(f"--data {path}: {name} trains on its chapter's data, not on a folder")
    if not path.exists():
        raise UsageError(f"--data {path}: no such folder")
    try:
        clip_files(path)
    except (FileNotFoundError, ValueError) as error:
        raise UsageError(f"--data {path}: {error}") from None


def choose_device(name: str) -> Any:
    import torch

    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise UsageError("--device cuda: no CUDA device is available (torch.cuda.is_available() is False)")
    return torch.device(name)


def start_processes(device: Any) -> tuple[int, int, Any]:
    """``(rank, world_size, device)``: under torchrun (``WORLD_SIZE`` > 1) the process group is initialised,
    gloo on the CPU and nccl on CUDA (one GPU per process, ``LOCAL_RANK``)."""
    import torch
    import torch.distributed as dist

    world_size = int(os.environ.get("WORLD_SIZE", "1"))
    if world_size <= 1:
        return 0, 1, device
    if device.type == "cuda":
        device = torch.device("cuda", int(os.environ.get("LOCAL_RANK", "0")))
        torch.cuda.set_device(device)
    dist.init_process_group("nccl" if device.type == "cuda" else "gloo")
    return dist.get_rank(), world_size, device


# --- progress ----------------------------------------------------------------------------------------------
class LogLines:
    """Plain progress lines (for a log file rather than a terminal): step, loss, steps/s and ETA."""

    def __init__(self, total: int | None, every: int, stream: Any = sys.stderr) -> None:
        self.total, self.every, self.stream = total, max(1, every), stream
        self.started = time.perf_counter()
        self.first: int | None = None

    def __call__(self, step: int, model: Any, history: Any) -> None:
        if self.first is None:
            self.first, self.started = step - 1, time.perf_counter()
        if step % self.every and step != self.total:
            return
        rate = (step - self.first) / max(time.perf_counter() - self.started, 1e-9)
        eta = f", ETA {(self.total - step) / rate:.0f} s" if self.total and rate > 0 else ""
        loss = history.terms["loss"][-1]
        of = f"/{self.total}" if self.total else ""
        print(f"step {step}{of}  loss {loss:.5g}  {rate:.2f} steps/s{eta}", file=self.stream, flush=True)


class TensorBoardLog:
    """Every loss term, coefficient and the learning rate of every step, for TensorBoard."""

    def __init__(self, folder: Path) -> None:
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError:
            raise UsageError(
                "--tensorboard needs the tensorboard package: pip install 'motionlab[tensorboard]'"
            ) from None
        self.writer = SummaryWriter(log_dir=str(folder))

    def __call__(self, step: int, model: Any, history: Any) -> None:
        for name, values in history.terms.items():
            self.writer.add_scalar(f"loss/{name}", values[-1], step)
        for name, values in history.coeffs.items():
            self.writer.add_scalar(f"coefficient/{name}", values[-1], step)
        self.writer.add_scalar("lr", history.lr[-1], step)

    def close(self) -> None:
        self.writer.close()


# --- the command -------------------------------------------------------------------------------------------
def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in text.lower()).strip("_") or "run"


def _write_json(path: Path, payload: Any) -> None:
    path.write_text(json.dumps(jsonable(payload), indent=2, allow_nan=True) + "\n")


def train_command(args: argparse.Namespace) -> dict[str, Any]:
    """Train and measure as ``args`` say; returns what ``run.json`` holds (``{}`` on the other processes)."""
    os.environ["MOTIONLAB_PROFILE"] = "quick" if args.config == "quick" else "full"
    experiment = family(args.family)
    run_name = args.run or experiment.DEFAULT_RUN
    check_folder(args.family, experiment, args.data)
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        raise UsageError(f"--out {args.out}: a file, not a folder")
    device = choose_device(args.device)
    cfg = build_config(experiment, args, run_name)
    tensorboard = TensorBoardLog(args.tensorboard) if args.tensorboard else None

    import torch

    from motionlab import config
    from motionlab.train.runtime import Execution, executing

    config.setup(seed=0)
    rank, world_size, device = start_processes(device)
    if args.data is None:
        data = experiment.load_data(cfg)
    else:
        try:
            data = experiment.load_data(cfg, args.data)
        except (FileNotFoundError, ValueError) as error:  # a folder the family cannot read: say why
            raise UsageError(f"--data {args.data}: {error}") from None
    runs = experiment.runs(cfg, data)
    if run_name not in runs:
        raise UsageError(f"--run {run_name}: {args.family} has the runs {', '.join(map(repr, runs))}")
    run = runs[run_name]
    if args.seed is not None:
        run = dataclasses.replace(run, train_config=dataclasses.replace(run.train_config, seed=args.seed))
    training = run.train_config
    out = args.out or config.build_dir() / "train" / f"{args.family}-{args.config}-{_slug(run_name)}"
    main = rank == 0
    interactive = main and sys.stderr.isatty()
    callbacks: list[Any] = []
    if main and not interactive:
        callbacks.append(LogLines(training.steps, every=max(1, (training.steps or 100) // 20)))
    if main and tensorboard is not None:
        callbacks.append(tensorboard)
    execution = Execution(
        device=device,
        mixed_precision=device.type == "cuda" and torch.cuda.is_bf16_supported(),
        rank=rank,
        world_size=world_size,
        callbacks=tuple(callbacks),
        checkpoint_every=args.checkpoint_every,
        resume=args.resume,
    )
    if main:
        print(
            f"{args.family}: run {run_name!r}, config {args.config}, data {args.data or 'of the chapter'}, "
            f"{training.steps} steps of batch {training.batch_size}, device {device}"
            + (f", {world_size} processes" if world_size > 1 else "")
            + (", bf16 autocast" if execution.mixed_precision else ""),
            file=sys.stderr,
            flush=True,
        )
    started = time.perf_counter()
    with executing(execution):
        model, result = run.train(progress=interactive)
    seconds = time.perf_counter() - started
    if tensorboard is not None:
        tensorboard.close()
    if not main:
        return {}
    out.mkdir(parents=True, exist_ok=True)
    checkpoint = None
    if result.path is not None:
        (out / "checkpoints").mkdir(exist_ok=True)
        checkpoint = out / "checkpoints" / result.path.name
        shutil.copy2(result.path, checkpoint)
    _write_json(out / "history.json", result.history.to_dict())
    evaluation_seconds = None
    if not args.skip_evaluation:
        evaluation_started = time.perf_counter()
        _write_json(out / "evaluation.json", experiment.measure(cfg, data, run_name, model))
        evaluation_seconds = time.perf_counter() - evaluation_started
    steps = int(result.metrics["steps"])
    summary = {
        "family": args.family,
        "chapter": experiment.CHAPTER,
        "run": run_name,
        "config_profile": args.config,
        "data": "the chapter's" if args.data is None else str(args.data),
        "experiment_config": cfg,
        "train_config": training.identity(),
        "device": str(device),
        "processes": world_size,
        "mixed_precision": execution.mixed_precision,
        "loaded_from_cache": result.loaded_from_cache,
        "resumed_from_step": result.resumed_from_step,
        "steps": steps,
        "train_seconds": result.metrics["train_seconds"],
        "steps_per_second": steps / result.metrics["train_seconds"] if not result.loaded_from_cache else None,
        "wall_seconds": seconds,
        "evaluation_seconds": evaluation_seconds,
        "final_metrics": result.metrics,
        "cache_entry": None if result.path is None else str(result.path),
        "checkpoint": None if checkpoint is None else str(checkpoint),
    }
    _write_json(out / "run.json", summary)
    how = "loaded from the checkpoint cache" if result.loaded_from_cache else f"trained in {seconds:.1f} s"
    print(f"{args.family} {run_name!r}: {how}; results in {out}", file=sys.stderr, flush=True)
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """The command; returns its exit code (2 for bad arguments)."""

    def command() -> int:
        train_command(parser().parse_args(argv))
        return 0

    try:
        return arguments.run(PROG, command)
    finally:
        _end_processes()


def _end_processes() -> None:
    import torch.distributed as dist

    if dist.is_available() and dist.is_initialized():
        dist.destroy_process_group()


if __name__ == "__main__":
    sys.exit(main())
