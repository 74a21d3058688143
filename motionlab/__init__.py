"""motionlab: probabilistic human-motion synthesis, from rotations to four published models.

Subpackages: :mod:`motionlab.geometry` (rotations and distances), :mod:`motionlab.skeleton`
(kinematic tree, forward kinematics), :mod:`motionlab.data` (synthetic motion, representations,
BVH), :mod:`motionlab.metrics`, :mod:`motionlab.train` (the one training loop),
:mod:`motionlab.evaluation`, :mod:`motionlab.models`, :mod:`motionlab.viz`, the applications
(:mod:`motionlab.apps`: the training command, chapter 09's comparison), the set-up (:mod:`motionlab.config`,
:mod:`motionlab.checkpoints`) and the course's own tooling (:mod:`motionlab.course`).
ARCHITECTURE.md draws the layers; ``lint-imports`` keeps the imports pointing down them.
"""

__version__ = "0.1.0"
