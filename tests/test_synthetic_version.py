"""The synthetic generator's version (``GENERATOR_VERSION``) changes with its output and only then: what it
makes now must match the sample stored under that version. Cached data sets and trained runs, the shipped
reference models among them, are keyed by the version, so a changed output under an old version would
pair old models with new data, and a new version for an unchanged output would retrain them all for
nothing.

When the output changes on purpose: give ``GENERATOR_VERSION`` a new value, store a new sample with
``python tests/test_synthetic_version.py``, and retrain the reference models (``make reference``)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from motionlab.data.synthetic import GENERATOR_VERSION, generate

SAMPLE = Path(__file__).parent / "data" / "synthetic_sample.npz"
#: The sample: 12 one-second clips at 10 frames per second, one per style mode.
ARGUMENTS = {"seed": 3, "n_per_mode": 1, "seconds": 1.0, "fps": 10, "split": "test"}
#: Arrays compared, and how closely: positions in metres and rotations (unit quaternions) up to the rounding
#: another CPU's kernels may give (1e-5 m is a hundredth of a millimetre); labels and contacts exactly.
TOLERANCES = {"positions": 1e-5, "rotations": 1e-5, "contacts": 0, "action": 0, "mode": 0, "body": 0}


def _sample() -> dict[str, np.ndarray]:
    clips = generate(**ARGUMENTS)
    return {name: np.asarray(getattr(clips, name)) for name in TOLERANCES}


def test_the_generator_makes_the_sample_stored_under_its_version():
    stored = np.load(SAMPLE)
    assert str(stored["version"]) == GENERATOR_VERSION, (
        f"{SAMPLE.name} was stored under version {stored['version']}, the generator is {GENERATOR_VERSION}: "
        "store the sample anew (python tests/test_synthetic_version.py)"
    )
    for name, array in _sample().items():
        want = stored[name]
        assert array.shape == want.shape, f"{name}: shape {array.shape}, stored {want.shape}"
        worst = float(np.abs(array.astype(np.float64) - want).max()) if array.size else 0.0
        assert worst <= TOLERANCES[name], (
            f"the generator's {name} differ from the sample of version {GENERATOR_VERSION} by up to "
            f"{worst:.3g}: its output changed, so give GENERATOR_VERSION a new value, store the sample anew "
            "(python tests/test_synthetic_version.py) and retrain the reference models (make reference)"
        )


if __name__ == "__main__":
    np.savez_compressed(SAMPLE, version=np.asarray(GENERATOR_VERSION), **_sample())
    print(f"wrote {SAMPLE} for generator version {GENERATOR_VERSION}", file=sys.stderr)
