"""Per-clip style parameters: ranges per style mode, filled from each clip's own random stream.

Every clip gets a fixed-length vector of uniform draws from its own seeded stream (see
:mod:`motionlab.data.synthetic`). An action reads its parameters from those draws, one column per
parameter, through a :class:`Draws`; a parameter's range may differ between the action's style modes,
which is what makes the modes separable while each varies continuously inside.

A range is written ``(lo, hi)`` (the same for every mode of the action) or as one ``(lo, hi)`` per mode,
in the order of the action's modes, e.g. ``((1.1, 1.6), (0.7, 1.1))``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

#: How many uniform draws each clip's stream provides.
DRAWS_PER_CLIP = 96

Range = tuple[float, float] | tuple[tuple[float, float], ...]


class Draws:
    """Hands out columns of per-clip uniforms ``(B, DRAWS_PER_CLIP)`` as parameters of a batch of clips.

    Args:
        uniforms: ``(B, n)`` draws in ``[0, 1)``, one row per clip.
        style: ``(B,)`` index of each clip's mode within its action.
    """

    def __init__(self, uniforms: np.ndarray, style: np.ndarray) -> None:
        self._uniforms = uniforms
        self._style = np.asarray(style)
        self._next = 0

    @property
    def style(self) -> np.ndarray:
        """``(B,)`` index of each clip's mode within its action."""
        return self._style

    def unit(self) -> np.ndarray:
        """The next column of uniforms ``(B,)`` in ``[0, 1)``."""
        if self._next >= self._uniforms.shape[1]:
            raise RuntimeError(
                f"an action asked for more than {self._uniforms.shape[1]} random draws per clip"
            )
        column = self._uniforms[:, self._next]
        self._next += 1
        return column

    def between(self, spec: Range) -> np.ndarray:
        """A parameter ``(B,)`` uniform in its mode's ``(lo, hi)`` (see the module notes for ``spec``)."""
        bounds = np.asarray(spec, dtype=np.float64)
        if bounds.ndim == 2:
            bounds = bounds[self._style]
        lo, hi = bounds[..., 0], bounds[..., 1]
        return lo + (hi - lo) * self.unit()

    def table(self, ranges: Mapping[str, Range]) -> dict[str, np.ndarray]:
        """Every parameter of ``ranges``, in order, as ``name -> (B,)``."""
        return {name: self.between(spec) for name, spec in ranges.items()}

    def angle(self) -> np.ndarray:
        """A uniform angle ``(B,)`` in ``[-pi, pi)``."""
        return np.pi * (2 * self.unit() - 1)

    def sign(self) -> np.ndarray:
        """``+1`` or ``-1`` ``(B,)`` with equal odds."""
        return np.where(self.unit() < 0.5, 1.0, -1.0)

    def noise_terms(self, n_terms: int, band: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (Hz, uniform in ``band``) and phases of ``n_terms`` sinusoids, each ``(B,
        n_terms)``."""
        freqs = np.stack([self.between(tuple(band)) for _ in range(n_terms)], axis=-1)
        phases = np.stack([self.angle() for _ in range(n_terms)], axis=-1)
        return freqs, phases

    def start(self, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """A start position ``(B, 2)`` uniform in a disc of ``radius`` metres, and a heading ``(B,)``."""
        r = radius * np.sqrt(self.unit())
        a = self.angle()
        return np.stack([r * np.cos(a), r * np.sin(a)], axis=-1), self.angle()
