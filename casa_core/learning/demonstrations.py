"""Demonstrations as IRL sees them: states every ``dt`` over a common horizon.

A demonstration ``(n, 5)`` of ``[t, x, y, z, rot]`` (a trial log's columns) is
resampled every ``dt`` from its first sample; after its last sample the person is
taken to stay where they stopped, up to the horizon (the planner's T or the longest
demonstration, whichever is longer). So every trajectory has the same number of
states, and the states where the person rests count as much as the time they rest.
"""

from __future__ import annotations

import math

import numpy as np

from casa_core.planning import steps_left


def demo_waypoints(demo, *, dt: float, n_steps: int) -> np.ndarray:
    """A demonstration ``(n, 5)`` of ``[t, x, y, z, rot]`` as ``n_steps + 1`` states every dt.

    States are linearly interpolated at ``t0 + k dt``; past the last sample the
    last state is held (the person stays where they stopped).

    Examples
    --------
    >>> demo = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.1, 0.0, 0.0, 0.2]])
    >>> demo_waypoints(demo, dt=0.5, n_steps=3)[:, [0, 3]].tolist()
    [[0.0, 0.0], [0.05, 0.1], [0.1, 0.2], [0.1, 0.2]]
    """
    demo = np.asarray(demo, dtype=float)
    if demo.ndim != 2 or demo.shape[1] != 5 or len(demo) < 2:
        raise ValueError(f"a demonstration must be (n >= 2, 5) [t, x, y, z, rot], got {demo.shape}")
    if not np.isfinite(demo).all():
        raise ValueError("a demonstration contains NaN or infinite values")
    t = demo[:, 0]
    if (np.diff(t) <= 0).any():
        raise ValueError("a demonstration's t must be strictly increasing")
    times = t[0] + dt * np.arange(n_steps + 1)
    return np.column_stack([np.interp(times, t, demo[:, j]) for j in range(1, 5)])


def demo_steps(demos, *, dt: float, horizon: float) -> int:
    """Steps covering the horizon and the longest demonstration.

    Examples
    --------
    >>> demo_steps([np.array([[0.0, 0, 0, 0, 0], [20.0, 0, 0, 0, 0]])], dt=0.5, horizon=15.0)
    40
    """
    for demo in demos:
        if np.ndim(demo) != 2 or np.shape(demo)[1] != 5 or len(demo) < 2:
            raise ValueError(
                f"a demonstration must be (n >= 2, 5) [t, x, y, z, rot], got {np.shape(demo)}"
            )
        if not np.isfinite(demo).all():
            raise ValueError("a demonstration contains NaN or infinite values")
    longest = max(float(d[-1, 0] - d[0, 0]) for d in demos)
    return max(steps_left(horizon, dt), int(math.ceil(longest / dt - 1e-9)))
