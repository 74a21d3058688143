"""motionlab: probabilistic human-motion synthesis, from rotations to four published models.

Subpackages: :mod:`motionlab.geometry` (rotations and distances), :mod:`motionlab.skeleton` (kinematic tree,
forward kinematics), :mod:`motionlab.data` (synthetic motion, representations, BVH), :mod:`motionlab.metrics`,
:mod:`motionlab.train` (the one training loop), :mod:`motionlab.viz`, plus :mod:`motionlab.config` (profiles,
threads, seeds), :mod:`motionlab.checkpoints` and the course's own tooling in :mod:`motionlab.course`
(executing the chapters, claims and results, the report).
"""

__version__ = "0.1.0"
