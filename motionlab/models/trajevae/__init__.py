"""TrajeVAE (Kania, Kowalski & Trzciński 2021): full-body motion completed from an initial pose and joint
trajectories.

Modules, in the order the chapter uses them: :mod:`.masks` (structured joint masks, ``Y = X ⊙ M``),
:mod:`.data` (windows, completion tasks and training batches), :mod:`.dct` (the orthonormal DCT-II over
time), :mod:`.model` (TrajeVAE and its config with the ablation switches), :mod:`.baselines` (deterministic
GRU, CVAE-RNN), :mod:`.losses`, :mod:`.evaluate` (DLow metrics against the number of trajectories, borrowed
trajectories, upsampling for the evaluator) and :mod:`.experiment` (the chapter's config, the Table 4 ablation
ladder and every run trained and swept on both cores).
"""

from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.model import TrajeVAE, TrajeVAEConfig

__all__ = ["CVAERNN", "GRUCompletion", "RecurrentConfig", "TrajeVAE", "TrajeVAEConfig"]
