"""Pictures of motion: stick figures, keyframe strips, HTML animations and top-down root paths.

Every function takes global joint positions (``(T, J, 3)`` or one pose ``(J, 3)``, z up) and the
skeleton's ``parents`` list, so it draws any representation once it has been through forward
kinematics. NumPy arrays and torch tensors are both accepted; following :mod:`motionlab.validation`, a wrong
type raises ``TypeError`` and a bad shape or value ``ValueError``.

- :func:`plot_pose`: one pose on a 3D axis (equal aspect, floor grid).
- :func:`filmstrip`: keyframes side by side in one figure.
- :func:`animate` / :func:`compare_animation`: an HTML player (``to_jshtml``) of one or several
  motions, overlaid or side by side; real blue, generated orange in the comparison.
- :func:`plot_root_paths`: root paths in the x-y plane with start and end markers.
- :func:`show_source`: the package's own source of a function or class, shown in the notebook.

The static plots draw with pyplot, so a notebook shows them at the end of the cell (assign the result,
``fig = filmstrip(...)``, to avoid a second copy from the cell's value). Animations use a figure that
pyplot never sees and return only the HTML, so nothing stays open.
"""

from motionlab.viz.animation import animate, build_animation, compare_animation
from motionlab.viz.root_paths import plot_root_paths
from motionlab.viz.source import show_source
from motionlab.viz.stick_figure import GENERATED_COLOR, REAL_COLOR, Scene, StickFigure, filmstrip, plot_pose

__all__ = [
    "GENERATED_COLOR",
    "REAL_COLOR",
    "Scene",
    "StickFigure",
    "animate",
    "build_animation",
    "compare_animation",
    "filmstrip",
    "show_source",
    "plot_pose",
    "plot_root_paths",
]
