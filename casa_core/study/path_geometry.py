"""Directions along a sampled path, for the simulated operator."""

from __future__ import annotations

import numpy as np

from casa_core.fixed_order import length


def unit_tangents(path: np.ndarray) -> np.ndarray:
    """Unit direction of travel at each sample; a sample that does not move keeps the last.

    Examples
    --------
    >>> unit_tangents(np.array([[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [2.0, 1.0]])).tolist()
    [[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]
    """
    steps = np.diff(path, axis=0)
    tangents = np.zeros_like(path)
    direction = np.zeros(path.shape[1])
    for i, step in enumerate(steps):
        size = length(step)
        if size > 1e-12:
            direction = step / size
        tangents[i] = direction
    tangents[-1] = direction
    # Samples before the first move take the first direction.
    first = next((i for i, step in enumerate(steps) if length(step) > 1e-12), 0)
    tangents[:first] = tangents[first]
    return tangents
