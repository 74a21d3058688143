"""Motion data: the synthetic generator and its file format, representations, data sets, BVH files.

================================  =====================================================================
module                            what it holds
================================  =====================================================================
:mod:`.synthetic`                 :func:`generate`, :func:`load_or_generate`, :func:`load_splits`, CLI
:mod:`.store`                     :class:`MotionSet` and its ``.npz`` format
:mod:`.noise`                     :func:`add_position_noise`, :func:`add_rotation_noise` (mocap noise)
:mod:`.bvh`, :mod:`.motion`       :class:`Motion`, :func:`load_bvh`, :func:`save_bvh`
:mod:`.representations`,          feature encodings, windowed torch data sets, augmentations
:mod:`.datasets`, :mod:`.augment`
:mod:`.cmu_mocap`                 :class:`MocapClips`, :func:`load_cmu_mocap`: real CMU motion capture
                                  (Action2Motion's clips, ODMO's "MoCap"), conversions, ODMO's protocol
================================  =====================================================================

The names above are imported on first use. That keeps ``import motionlab.data`` light, and it lets
``python -m motionlab.data.synthetic`` run the generator without importing it twice (once through this
package, once as ``__main__``).
"""

from __future__ import annotations

from motionlab.lazy import lazy_exports

_EXPORTS = {
    "MotionSet": "motionlab.data.store",
    "generate": "motionlab.data.synthetic",
    "load_or_generate": "motionlab.data.synthetic",
    "load_splits": "motionlab.data.synthetic",
    "add_position_noise": "motionlab.data.noise",
    "add_rotation_noise": "motionlab.data.noise",
    "Motion": "motionlab.data.bvh",
    "load_bvh": "motionlab.data.bvh",
    "save_bvh": "motionlab.data.bvh",
    "MocapClips": "motionlab.data.cmu_mocap",
    "load_cmu_mocap": "motionlab.data.cmu_mocap",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
