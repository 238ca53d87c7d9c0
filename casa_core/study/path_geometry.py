"""Lengths and directions along a sampled path, for the simulated operator.

:func:`row_lengths` is ``np.linalg.norm(rows, axis=-1)`` with the same sums (so the same
bits) without numpy's argument handling, which costs more than the arithmetic on the
few dozen rows the operator measures every tick.
"""

from __future__ import annotations

import numpy as np


def row_lengths(rows: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(rows, axis=-1)``, the same sums, without its argument handling.

    Examples
    --------
    >>> row_lengths(np.array([[3.0, 4.0], [0.0, 0.0]])).tolist()
    [5.0, 0.0]
    """
    return np.sqrt(np.add.reduce(rows * rows, axis=-1))


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
        length = np.linalg.norm(step)
        if length > 1e-12:
            direction = step / length
        tangents[i] = direction
    tangents[-1] = direction
    # Samples before the first move take the first direction.
    first = next((i for i, step in enumerate(steps) if np.linalg.norm(step) > 1e-12), 0)
    tangents[:first] = tangents[first]
    return tangents
