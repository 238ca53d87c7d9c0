"""The simulated operator's per-tick path geometry, compiled (numba).

:mod:`casa_core.study.participants` asks each tick for the path point nearest a
position and for the point a fixed path length ahead; written in numpy each is a
dozen calls on arrays of 4 numbers, or a cumulative sum of the whole remaining path.
These kernels compute the same numbers with the same floating-point operations in the
same order (no fastmath), so the operator holds the same keys on every tick. Dot
products stay in numpy at the caller: the BLAS behind ``@`` sums in an order of its
own.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def nearest_row(path, start, stop, point):
    """Index in ``path[start:stop]`` of the row nearest ``point`` (the first of equals).

    The distances are ``np.linalg.norm(path[start:stop] - point, axis=1)``: squares
    summed left to right, then the square root, as numpy sums a row of 4.

    Examples
    --------
    >>> path = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> int(nearest_row(path, 0, 3, np.array([1.2, 0.5])))
    1
    """
    stop = min(stop, path.shape[0])
    best = 0
    best_length = np.inf
    for row in range(start, stop):
        total = 0.0
        for column in range(path.shape[1]):
            difference = path[row, column] - point[column]
            total += difference * difference
        length = math.sqrt(total)
        if length < best_length or row == start:
            best, best_length = row - start, length
    return best


@njit(cache=True)
def first_reaching(steps, start, distance):
    """``np.cumsum(steps[start:]).searchsorted(distance)``, without the whole sum.

    Examples
    --------
    >>> int(first_reaching(np.array([1.0, 1.0, 1.0, 1.0]), 1, 2.0))
    1
    >>> int(first_reaching(np.array([1.0, 1.0]), 0, 5.0))
    2
    """
    total = 0.0
    for index in range(start, steps.shape[0]):
        total += steps[index]
        if total >= distance:
            return index - start
    return steps.shape[0] - start


@njit(cache=True)
def track(scaled, steps, progress, perceived, window, lookahead, rot_scale):
    """The operator's new progress along the path and its steering point's index.

    ``perceived`` is ``[x, y, z, rot]``; its rotation is scaled by ``rot_scale`` as
    the path ``scaled`` is. The progress moves to the nearest of the ``window`` path
    points from it; the steering point lies ``lookahead`` of path length further.

    Examples
    --------
    >>> scaled = np.array([[0.0, 0, 0, 0], [0.02, 0, 0, 0], [0.04, 0, 0, 0], [0.06, 0, 0, 0]])
    >>> steps = np.array([0.02, 0.02, 0.02])
    >>> [int(i) for i in track(scaled, steps, 0, np.array([0.021, 0, 0, 0]), 40, 0.04, 0.1)]
    [1, 2]
    """
    here = perceived.copy()
    here[3] *= rot_scale
    progress += nearest_row(scaled, progress, progress + window, here)
    return progress, progress + first_reaching(steps, progress, lookahead)
