"""The reference models shipped in ``reference/``: what the full profile loads instead of training.

A reference model is a checkpoint-cache entry (:mod:`motionlab.checkpoints`: ``<name>-<hash>.pt``, the
weights with their config, loss history and final metrics; its weight matrices stored as float16,
:func:`half_precision`) committed to the repository, with a manifest ``<name>-<hash>.json`` beside it::

    {"format": 1, "name": "odmo", "file": "odmo-5f55d9e6002e.pt", "sha256": "...", "bytes": 812345,
     "config": {...the run's identity: model, train and data configs...}, "seed": 0, "steps": 2400,
     "train_seconds": 61.2, "trained_on": {"machine": ..., "torch": ..., "commit": ..., "date": ...},
     "metrics": {...}, "levelling": {...}}

In the full profile (:func:`in_use`) a run whose identity has a reference model is loaded from it, not
trained and not taken from the build's cache: every machine then evaluates the same weights. The file is
checked against its manifest first (:func:`verify`); a damaged file, a missing manifest or a config that is
not the run's is refused with a :class:`ReferenceError` that names the file and what differs (never a silent
retraining). ``MOTIONLAB_RETRAIN=1`` (``make course RETRAIN=1``) ignores the references and trains every
model on the machine at hand, through the build's cache as before.

``make reference`` rebuilds them: the course in a fresh build folder with ``MOTIONLAB_RETRAIN=1`` (every full
profile process notes each run it trains or loads in the build's :func:`runs_log`), then
``python -m motionlab.apps.reference export BUILD`` copies those entries here and writes their manifests
and ``reference/README.md``. ``make reference ALL=0`` builds with the references in use instead: it trains
only the runs whose configuration changed, and the export replaces those and keeps the rest.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import platform
import re
import subprocess
import time
from pathlib import Path
from typing import Any

import torch

from motionlab import config, paths
from motionlab.checkpoints import config_dict, config_hash

#: Where the reference models live (the repository's ``reference/``).
REFERENCE_DIR = paths.REPO_ROOT / "reference"

#: The environment variable that makes the full profile retrain instead of loading references.
RETRAIN_VARIABLE = "MOTIONLAB_RETRAIN"

#: The manifest format this code writes and reads.
MANIFEST_FORMAT = 1

#: The most the reference models may weigh in all, files and manifests together: 30 MB (30 million bytes).
SIZE_LIMIT = 30_000_000

#: Float32 tensors with at least this many numbers are shipped as float16 (:func:`half_precision`): it
#: halves the models' size (the 30 MB limit) and rounds each weight by at most 1/2048 of its magnitude.
HALF_MIN_ELEMENTS = 512

#: The runs whose held-out likelihood the course reports, shipped in float32 but for the tensors
#: :data:`LIKELIHOOD_HALF_TENSORS` names: a flow's likelihood sums log-determinants and coupling scales over
#: all its layers, and a Gaussian baseline's divides by the small deviations it predicts, so rounding moves
#: them far. Float16 weights in MoGlow's control encoder and coupling outputs moved its held-out NLL by up to
#: 1,470 nats per frame, and in the Gaussian AR baseline's least-squares predictor (trained 6,000 steps) from
#: -331.1 to -79.7 on the val split (chapter 06's comparison of the two is a difference of about a hundred).
LIKELIHOOD_RUNS = ("moglow", "real_moglow", "toy_flow_moons", "moglow_gaussian_ar", "real_moglow_gaussian_ar")

#: The likelihood runs' tensors that are shipped as float16 all the same: their LSTMs' weights, half of each
#: MoGlow's bytes and most of each baseline's; rounded, they moved the held-out NLL of chapter 06's four
#: MoGlows (trained 20,000 steps) by at most 0.06 nats per frame, and the Gaussian AR's by less than 0.001.
LIKELIHOOD_HALF_TENSORS = re.compile(r"(^|\.)lstm\.weight_(ih|hh)_l\d+$")

#: Runs never shipped: the course trains them in every build. Chapter 05's fixed-length Glow is the largest
#: model (5.9 MB as a flow in float32) and trains in about half a minute, in front of the reader.
TRAINED_IN_EVERY_BUILD = ("fixed_length_glow",)

#: The shipped loss history keeps this many evenly spaced steps (:func:`thinned`): enough for its curve.
HISTORY_POINTS = 120

#: A run "levelled off" when its held-out loss (or, for a run that does not validate, its training loss)
#: fell by less than this share of its whole fall over the last fifth of its steps (:func:`levelling`).
LEVELLED_SHARE = 0.05

#: A run's held-out curve is judged when it has at least this many validation passes.
MIN_VALIDATIONS = 10


class ReferenceError(RuntimeError):
    """A reference model that must not be used: damaged, without a manifest, or not the run it claims."""


def retraining() -> bool:
    """Whether ``MOTIONLAB_RETRAIN`` asks to ignore the references and train everything here."""
    text = os.environ.get(RETRAIN_VARIABLE, "").strip().lower()
    if text in ("", "0", "false", "no"):
        return False
    if text in ("1", "true", "yes"):
        return True
    raise ValueError(f"{RETRAIN_VARIABLE} must be 1 or 0, got {text!r}")


def in_use() -> bool:
    """Whether runs load reference models: in the full profile, unless ``MOTIONLAB_RETRAIN=1``."""
    return not config.is_quick() and not retraining()


#: A data fingerprint in a run's identity: 16 hex digits of the array's bytes, then its shape.
_FINGERPRINT = re.compile(r"^[0-9a-f]{16}-(\(.*\))$")


def portable(identity: Any) -> Any:
    """A run's identity with every data fingerprint reduced to its array's shape.

    The training data's last bits differ between CPUs (forward kinematics, a denoiser's output, a resampling:
    all rounded by the machine's kernels), and so would the fingerprints of :func:`run_identity`, so a
    reference model is found by what defines its data (generator version, seeds, sizes, windows, shapes), not
    by those bits.
    """
    if isinstance(identity, dict):
        return {key: portable(value) for key, value in identity.items()}
    if isinstance(identity, list):
        return [portable(value) for value in identity]
    if isinstance(identity, str) and (match := _FINGERPRINT.match(identity)):
        return f"data of shape {match.group(1)}"
    return identity


def reference_path(name: str, identity: dict[str, Any]) -> Path:
    """``reference/<name>-<hash>.pt``: where the reference model of a run (its :func:`run_identity`) lives;
    the hash is of its :func:`portable` identity."""
    return REFERENCE_DIR / f"{name}-{config_hash(name, portable(config_dict(identity)))}.pt"


def manifest_path(path: Path) -> Path:
    """The manifest ``<name>-<hash>.json`` beside a reference model."""
    return path.with_suffix(".json")


def sha256(path: Path) -> str:
    """The SHA-256 of a file, in hex."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_manifest(path: Path) -> dict[str, Any]:
    """The manifest of the reference model at ``path``; :class:`ReferenceError` when missing or malformed."""
    where = manifest_path(path)
    try:
        manifest = json.loads(where.read_text())
    except FileNotFoundError:
        raise ReferenceError(
            f"{_shown(path)} has no manifest {where.name}: a reference model is used only with its manifest "
            f"(restore both with `git checkout -- reference/`, or retrain with `make course RETRAIN=1`)"
        ) from None
    except (OSError, ValueError) as exc:
        raise ReferenceError(f"cannot read the manifest {_shown(where)}: {exc}") from None
    if not isinstance(manifest, dict) or manifest.get("format") != MANIFEST_FORMAT:
        raise ReferenceError(
            f"{_shown(where)} is not a manifest of format {MANIFEST_FORMAT} (it has "
            f"{manifest.get('format') if isinstance(manifest, dict) else type(manifest).__name__!r})"
        )
    return manifest


@functools.cache
def _verified(path: Path, size: int, mtime_ns: int) -> dict[str, Any]:
    manifest = read_manifest(path)
    if manifest.get("file") != path.name:
        raise ReferenceError(
            f"{_shown(manifest_path(path))} describes {manifest.get('file')!r}, not {path.name}"
        )
    actual = sha256(path)
    if actual != manifest.get("sha256"):
        raise ReferenceError(
            f"{_shown(path)} does not match its manifest: SHA-256 {actual[:12]}..., the manifest says "
            f"{str(manifest.get('sha256'))[:12]}...: the file is damaged or was replaced (restore it with "
            f"`git checkout -- reference/`, or retrain with `make course RETRAIN=1`)"
        )
    return manifest


def verify(path: Path, identity: dict[str, Any] | None = None) -> dict[str, Any]:
    """Check a reference model against its manifest (file name, checksum and, given the run's ``identity``,
    configuration); return the manifest. Raises :class:`ReferenceError` saying what does not match."""
    stat = path.stat()
    manifest = _verified(path, stat.st_size, stat.st_mtime_ns)
    if identity is not None and portable(manifest.get("config")) != portable(config_dict(identity)):
        raise ReferenceError(
            f"{_shown(path)}: its manifest's configuration is not the run's (the file name's hash matches, "
            f"so the manifest was edited by hand): retrain it with `make reference`"
        )
    return manifest


def find(name: str, identity: dict[str, Any]) -> Path | None:
    """The verified reference model of a run, or ``None`` when references are not in use (quick profile,
    ``MOTIONLAB_RETRAIN=1``) or this run has none."""
    if not in_use():
        return None
    path = reference_path(name, identity)
    if not path.exists():
        return None
    verify(path, identity)
    return path


def provenance(result: Any, seconds: float | None = None, command: str = "make course RETRAIN=1") -> str:
    """One line saying where a chapter's model comes from, for the cell that loads it.

    Args:
        result: the run's :class:`~motionlab.train.loop.TrainResult`.
        seconds: its training seconds when this build trained it (``Trained.seconds``).
        command: the command that retrains it (e.g. the training command's
            ``python -m motionlab.apps.training odmo``; default: the whole course's).

    A reference model reads e.g. ``odmo: the reference model, 1,200 steps (3.1 min on one core of an Intel
    Xeon, commit 0b1b186); its loss fell 2.1 % more of its whole fall over the last fifth. Retrain it: ...``.
    """
    path = result.path
    name = path.stem.rsplit("-", 1)[0] if path is not None else "model"
    steps = int(result.metrics.get("steps", 0))
    if path is None or path.parent != REFERENCE_DIR:
        if seconds is not None or not result.loaded_from_cache:
            took = seconds if seconds is not None else result.metrics.get("train_seconds", float("nan"))
            return f"{name}: trained by this build, {steps:,} steps in {took:.0f} s"
        return f"{name}: {steps:,} steps, loaded from this build's cache"
    manifest = read_manifest(path)
    where = manifest.get("trained_on") or {}
    lev = manifest.get("levelling") or {}
    tail = (
        f"; over its last fifth of steps its {_MEASURED[lev.get('measure', 'training')]} fell a further "
        f"{lev['last_fifth_share']:.1%} of its fall"
        if "last_fifth_share" in lev
        else ""
    )
    return (
        f"{name}: the reference model, {steps:,} steps ({manifest['train_seconds'] / 60:.1f} min on "
        f"{where.get('machine', 'an unrecorded machine')}, commit {where.get('commit', '?')}){tail}. "
        f"Retrain it here: `{command}`"
    )


def runs_log() -> Path:
    """The build's list of the full-profile runs it trained or loaded: one ``<name>-<hash>`` per line (the
    hash of the run's identity), followed by `` <file>`` for a run loaded from that reference model."""
    return config.checkpoint_dir() / "full-profile-runs.txt"


def note_use(name: str, identity: dict[str, Any], shipped: Path | None = None) -> None:
    """Add a full-profile run to :func:`runs_log`, with the reference model it was loaded from (``shipped``),
    if any (one appended write: worker processes can share it)."""
    if config.is_quick():
        return
    log = runs_log()
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("a") as handle:
        handle.write(f"{name}-{config_hash(name, identity)}{'' if shipped is None else ' ' + shipped.name}\n")


def used_runs(build: Path) -> tuple[set[str], set[str]]:
    """The runs a course build in ``build`` used, from its :func:`runs_log`: the ``<name>-<hash>`` of those
    it trained or found in its checkpoint cache, and the file names of the reference models it loaded."""
    log = build / "checkpoints" / runs_log().name
    if not log.exists():
        raise ReferenceError(f"{log} does not exist: build the course there first (see `make reference`)")
    cached, loaded = set(), set()
    for line in log.read_text().splitlines():
        stem, _, shipped = line.strip().partition(" ")
        if shipped:
            loaded.add(shipped)
        elif stem:
            cached.add(stem)
    return cached, loaded


def trained_log() -> Path:
    """The build's list of the runs it trained although the reference models were in use (one name a line):
    runs that have no reference model of their configuration."""
    return config.checkpoint_dir() / "trained-beside-references.txt"


def note_trained(name: str) -> None:
    """Add run ``name`` to :func:`trained_log` when the reference models are in use (one appended write:
    worker processes can share it)."""
    if not in_use():
        return
    log = trained_log()
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("a") as handle:
        handle.write(f"{name}\n")


def trained_here() -> list[str]:
    """The runs in :func:`trained_log`, sorted, each once."""
    log = trained_log()
    return sorted(set(log.read_text().split())) if log.exists() else []


def trained_on() -> dict[str, Any]:
    """Where and when a model is being trained: machine, threads, library versions, commit, date."""
    return {
        "machine": _cpu_model(),
        "cores": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "python": platform.python_version(),
        "torch": str(torch.__version__),
        "commit": _commit(),
        "date": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
        "numerics": config.numerical_path(),
        "base_seed": config.base_seed(),
    }


#: How :func:`levelling`'s ``measure`` reads in a sentence.
_MEASURED = {"held-out": "held-out loss", "training": "training loss"}


def levelling(history: dict[str, Any]) -> dict[str, Any] | None:
    """How much a run's objective still fell at the end: the fall over the last fifth of the curve as a share
    of its whole fall (first tenth's mean to last tenth's mean), and whether it levelled off.

    The curve is the held-out one (``measure`` ``"held-out"``) when the run validated at least
    :data:`MIN_VALIDATIONS` times, else the training objective (``"training"``): the loss term
    ``objective`` where the loss function reports one (a VAE's negative ELBO, whose loss weights the KL by
    a ramp), else the loss. A held-out curve levelled off when its share is below :data:`LEVELLED_SHARE`,
    also when it rose (the run has passed its best, or its held-out measure never improved: training longer
    would not help it; the share is then negative, its fall over the last fifth over the size of its whole
    change); a training curve when the share is that small either way, and a training curve that rose
    overall did not. ``None`` for a run too short to tell (under 50 steps).
    """

    def objective(terms: dict[str, Any]) -> list[float]:
        return [float(v) for v in terms.get("objective", terms.get("loss", []))]

    held_out = objective(history.get("val_terms") or {})
    validated = len(held_out) >= MIN_VALIDATIONS
    curve = held_out if validated else objective(history.get("terms") or {})
    if not validated and len(curve) < 50:
        return None

    def mean(part: list[float]) -> float:
        return sum(part) / len(part)

    n = len(curve)
    tenth, fifth = max(n // 10, 1), max(n // 5, 1)
    whole = mean(curve[:tenth]) - mean(curve[-tenth:])
    last = mean(curve[-fifth - tenth : -fifth]) - mean(curve[-tenth:])
    if validated:
        share = last / abs(whole) if whole != 0 else math.inf
        levelled = share < LEVELLED_SHARE
    else:
        share = last / whole if whole > 0 else math.inf
        levelled = abs(share) < LEVELLED_SHARE
    return {
        "measure": "held-out" if validated else "training",
        "last_fifth_share": round(share, 4),
        "levelled": bool(levelled),
    }


def levelling_phrase(verdict: dict[str, Any]) -> str:
    """A :func:`levelling` verdict in words, to follow "it": "fell a further 3.5% of its fall over the last
    fifth: levelled off", or for a held-out curve that went up at the end, "rose ... past its best"."""
    share = verdict["last_fifth_share"]
    if share < 0:  # the held-out measure went up at the end: training longer would not help
        return f"rose over the last fifth by {-share:.1%} of its whole change: past its best"
    state = "levelled off" if verdict["levelled"] else "still falling"
    return f"fell a further {share:.1%} of its fall over the last fifth: {state}"


def export(
    build: Path, out: Path = REFERENCE_DIR, partial: bool = False, replace: tuple[str, ...] = ()
) -> list[dict[str, Any]]:
    """Copy the full-profile runs a course build trained (:func:`used_runs`) into ``out`` with a manifest
    each, keep the reference models it loaded as they are, remove the others, write ``out/README.md``;
    return the manifests of all that ``out`` then holds.

    A build with ``MOTIONLAB_RETRAIN=1`` trains every run, so every model is exported afresh (``make
    reference``); a build with the reference models in use trains only the runs whose configuration none of
    them matches, and only those are replaced (``make reference ALL=0``). A ``partial`` build ran some
    chapters only (``python -m motionlab.course --only 03``): the references it did not use stay, but for
    those of the runs named in ``replace`` (the runs whose configuration changed: their older versions go)."""
    cached, loaded = used_runs(build)
    stems = sorted(stem for stem in cached if stem.rsplit("-", 1)[0] not in TRAINED_IN_EVERY_BUILD)
    missing = [stem for stem in stems if not (build / "checkpoints" / f"{stem}.pt").exists()]
    if missing:
        raise ReferenceError(f"{build / 'checkpoints'} lacks {len(missing)} used runs, e.g. {missing[0]}.pt")
    gone = sorted(name for name in loaded if not (out / name).exists())
    if gone:
        raise ReferenceError(f"the build loaded {gone[0]}, which {out} no longer holds: build it again")
    kept = [read_manifest(out / name) for name in sorted(loaded)]
    out.mkdir(parents=True, exist_ok=True)
    exported = [_export_one(build / "checkpoints" / f"{stem}.pt", out) for stem in stems]
    manifests = exported + kept
    shipped = {Path(m["file"]).stem for m in manifests}
    if len(shipped) < len(manifests):
        raise ReferenceError("two used runs differ only in their data's bits: they cannot share reference/")
    for old in out.glob("*.pt"):
        if old.stem in shipped:
            continue
        if partial and old.stem.rsplit("-", 1)[0] not in replace:
            manifests.append(read_manifest(old))
            continue
        old.unlink()
        manifest_path(old).unlink(missing_ok=True)
    manifests.sort(key=lambda m: m["file"])
    total = sum(m["bytes"] for m in manifests) + sum(
        manifest_path(out / m["file"]).stat().st_size for m in manifests
    )
    if total > SIZE_LIMIT:
        raise ReferenceError(
            f"the reference models weigh {total / 1e6:.1f} MB, over {SIZE_LIMIT / 1e6:.0f} MB"
        )
    (out / "README.md").write_text(_readme(manifests, total))
    return manifests


def half_precision(
    state_dict: dict[str, torch.Tensor], only: re.Pattern[str] | None = None
) -> tuple[dict[str, torch.Tensor], dict[str, Any]]:
    """The state dict as shipped: float32 tensors of at least :data:`HALF_MIN_ELEMENTS` numbers (the weight
    matrices, nearly all the bytes) stored as float16, the rest (biases, norms, data statistics, noise
    schedules) as they are; and what that did (tensors halved, numbers, the largest rounding relative to
    its tensor's largest magnitude). ``only``: halve just the tensors whose name it matches (a likelihood
    run's, :data:`LIKELIHOOD_HALF_TENSORS`). Loading casts them back to the model's float32."""
    shipped, halved, numbers, worst = {}, 0, 0, 0.0
    for key, tensor in state_dict.items():
        if (
            tensor.dtype == torch.float32
            and tensor.numel() >= HALF_MIN_ELEMENTS
            and (only is None or only.search(key))
        ):
            half = tensor.half()
            scale = float(tensor.abs().max()) or 1.0
            worst = max(worst, float((half.float() - tensor).abs().max()) / scale)
            shipped[key], halved, numbers = half, halved + 1, numbers + tensor.numel()
        else:
            shipped[key] = tensor
    return shipped, {
        "float16_tensors": halved,
        "float16_numbers": numbers,
        "largest_relative_rounding": worst,
    }


def thinned(history: dict[str, Any], points: int) -> dict[str, Any]:
    """A :meth:`History.to_dict <motionlab.train.history.History.to_dict>` with its per-step records kept at
    ``points`` evenly spaced steps (the first and the last among them); validation records stay whole."""
    n = len(history.get("step", []))
    if n <= points:
        return history
    keep = sorted({round(i * (n - 1) / (points - 1)) for i in range(points)})

    def pick(values: list[Any]) -> list[Any]:
        return [values[i] for i in keep]

    per_step = ("step", "epoch", "lr", "grad_norm")
    return {
        **history,
        **{key: pick(history[key]) for key in per_step},
        "terms": {key: pick(values) for key, values in history["terms"].items()},
        "coeffs": {key: pick(values) for key, values in history["coeffs"].items()},
    }


def _export_one(source: Path, out: Path) -> dict[str, Any]:
    payload = torch.load(source, map_location="cpu", weights_only=True)
    extra = payload.get("extra") or {}
    metrics = {str(k): float(v) for k, v in (extra.get("metrics") or {}).items()}
    identity = payload["config"]
    target = out / reference_path(payload["name"], identity).name
    only = LIKELIHOOD_HALF_TENSORS if payload["name"] in LIKELIHOOD_RUNS else None
    payload["state_dict"], stored = half_precision(payload["state_dict"], only)
    history = extra.get("history") or {}
    extra["history"] = thinned(history, HISTORY_POINTS)
    torch.save(payload, target)
    manifest = {
        "format": MANIFEST_FORMAT,
        "name": payload["name"],
        "file": target.name,
        "sha256": sha256(target),
        "bytes": target.stat().st_size,
        "parameters": sum(t.numel() for t in payload["state_dict"].values() if t.is_floating_point()),
        "stored": stored,
        "config": identity,
        "seed": (identity.get("train") or {}).get("seed"),
        "steps": int(metrics.get("steps", 0)),
        "train_seconds": round(metrics.get("train_seconds", float("nan")), 1),
        "trained_on": extra.get("trained_on"),
        "metrics": metrics,
        "levelling": levelling(history),
    }
    manifest_path(target).write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return manifest


def _readme(manifests: list[dict[str, Any]], total: int) -> str:
    machines = sorted({(m.get("trained_on") or {}).get("machine", "unknown") for m in manifests})
    lines = [
        "# Reference models",
        "",
        "The models whose numbers the course reports, loaded by `make course` (the full profile) instead",
        "of trained. Each `<name>-<hash>.pt` is a checkpoint-cache entry (weights, config, loss history,",
        "final metrics; `torch.load(..., weights_only=True)`; weight matrices of 512 numbers or more",
        f"(of the likelihood models {', '.join(LIKELIHOOD_RUNS)}: only their LSTMs' weights)",
        f"stored as float16, loaded back into float32; the loss history at {HISTORY_POINTS} evenly spaced",
        "steps) and `<name>-<hash>.json` its manifest:",
        "configuration, seed, steps, training time and machine, commit, SHA-256, metrics, and how much its",
        "loss still fell over its last fifth of steps, as a share of its whole fall (`levelled` below",
        f"{LEVELLED_SHARE:.0%}): its held-out loss where the run validated (on the benchmark's val split,",
        "a pass every 1/40 of the run; a held-out curve that rises at the end, or never fell, has passed its",
        "best and counts as levelled: its share is negative), else its training loss (a VAE's: its negative",
        f"ELBO; levelled when it moved under {LEVELLED_SHARE:.0%} either way).",
        "",
        "Rebuild them all with `make reference` (a course build with `MOTIONLAB_RETRAIN=1` in a fresh",
        "folder, then `python -m motionlab.apps.reference export`), or only those whose configuration",
        "changed with `make reference ALL=0`; train any one again with the",
        "training command. `seeds/claims.json` holds every claim's value for course builds trained with",
        "base seeds 0, 1 and 2 (`python -m motionlab.apps.reference seeds 0=BUILD 1=BUILD 2=BUILD`),",
        "shown in each chapter's Paper vs. us.",
        "This file is written by the export.",
        "",
        f"{len(manifests)} models, {total / 1e6:.1f} MB in all, trained on: {'; '.join(machines)}.",
        "",
        "| model | file | size (kB) | seed | steps | training (s) | loss | fall in last fifth | levelled |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for m in sorted(manifests, key=lambda m: m["file"]):
        lev = m.get("levelling") or {}
        share = f"{lev['last_fifth_share']:.1%}" if "last_fifth_share" in lev else "-"
        measure = lev.get("measure", "training") if lev else "-"
        lines.append(
            f"| {m['name']} | {m['file']} | {m['bytes'] / 1000:.0f} | {m['seed']} | {m['steps']} | "
            f"{m['train_seconds']} | {measure} | {share} | "
            f"{'yes' if lev.get('levelled') else 'no' if lev else '-'} |"
        )
    return "\n".join(lines) + "\n"


def _shown(path: Path) -> str:
    try:
        return str(path.relative_to(paths.REPO_ROOT))
    except ValueError:
        return str(path)


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _git(*args: str) -> str:
    """The output of ``git -C <repository> ARGS`` (raises ``OSError`` or ``SubprocessError`` on failure)."""
    command = ["git", "-C", str(paths.REPO_ROOT), *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=10, check=True).stdout.strip()


def _commit() -> str | None:
    """The repository's commit (12 digits), ``+changes`` when tracked files differ from it; ``None`` without
    git."""
    try:
        head = _git("rev-parse", "--short=12", "HEAD")
        dirty = _git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("+changes" if dirty else "")
