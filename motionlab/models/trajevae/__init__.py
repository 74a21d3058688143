"""TrajeVAE (Kania, Kowalski & Trzciński 2021): full-body motion completed from an initial pose and joint
trajectories.

Modules, in the order the chapter uses them: :mod:`.masks` (structured joint masks, ``Y = X ⊙ M``),
:mod:`.dct` (the orthonormal DCT-II over time), :mod:`.config` (the model config with the ablation switches),
:mod:`.layers` and :mod:`.model` (TrajeVAE), :mod:`.baselines` (deterministic GRU, CVAE-RNN), :mod:`.losses`,
:mod:`.data` (windows and training batches), :mod:`.training` (build, train or load; the chapter's settings),
:mod:`.ablations` (the Table 4 ladder), :mod:`.evaluate` (DLow metrics against the number of trajectories,
borrowed trajectories, evaluator accuracy helpers) and :mod:`.experiment` (every model trained and swept on
both cores).
"""

from motionlab.models.trajevae.ablations import RUNGS, ladder
from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.config import TrajeVAEConfig
from motionlab.models.trajevae.model import TrajeVAE

__all__ = ["CVAERNN", "GRUCompletion", "RUNGS", "RecurrentConfig", "TrajeVAE", "TrajeVAEConfig", "ladder"]
