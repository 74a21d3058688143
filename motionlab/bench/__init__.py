"""``make bench``: speed and memory measurements written to ``build/bench.json``.

:data:`ENTRIES` is the one registry of what is measured: each entry names a function (in the module of its
area) that returns a flat ``dict`` of numbers. :mod:`motionlab.bench.__main__` runs the entries, each in a
fresh process (so peak memory is per entry), and merges their dictionaries.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Entry:
    """One benchmark entry: what it measures and where its function is (``"module:function"`` under
    :mod:`motionlab.bench`)."""

    what: str
    function: str

    def load(self) -> Callable[[], dict]:
        """The entry's measuring function (imported now, so that only the entry that runs pays for it)."""
        module, name = self.function.split(":")
        return getattr(importlib.import_module(f"motionlab.bench.{module}"), name)


#: Every benchmark entry by name, in the order ``make bench`` runs them.
ENTRIES: dict[str, Entry] = {
    "data": Entry(
        "synthetic data generation: the generator's command line writing 1,008 clips", "data:generation_speed"
    ),
    "diffusion": Entry(
        "MDM sampling of a 4-second clip: 1,000 ancestral steps, 50 respaced, 10 DDIM; batched",
        "diffusion:sampling_speed",
    ),
    "geometry": Entry(
        "rotation kernels on one thread: quaternion to matrix, geodesic distance", "geometry:kernel_speed"
    ),
    "mcell": Entry("Motion Cell sampling: a 4-second clip at batch 1, and batched", "mcell:sampling_speed"),
    "metrics": Entry("metric timings: FID on 2,000 x 30 features, APD on 50 clips", "metrics:metric_timings"),
    "moglow": Entry("MoGlow frame-by-frame generation of a 4-second clip", "moglow:generation_speed"),
    "odmo": Entry("ODMO generation: code -> trajectory -> motion -> positions", "odmo:generation_speed"),
    "threads": Entry(
        "one training step of the course's models on 1 vs. 2 torch threads", "threads:thread_scaling"
    ),
    "train": Entry("training-step throughput of the one training loop", "train:step_throughput"),
    "trajevae": Entry(
        "TrajeVAE completion of a 4-second window, and 50 samples", "trajevae:completion_speed"
    ),
    "vae": Entry("the chapter 03 CVAE's generation: prior code -> joint positions", "vae:generation_speed"),
    "viz": Entry("rendering a 4-second clip to an animation and a filmstrip", "viz:render_timings"),
}
