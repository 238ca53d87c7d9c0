"""Input guards shared by the equation modules: clear ValueErrors instead of NaN."""

from __future__ import annotations

import numpy as np


def as_finite_or_inf(name: str, value, *, nonnegative: bool = False) -> np.ndarray:
    """``value`` as a float array; NaN (and negatives when asked) raise ValueError naming it."""
    array = np.asarray(value, dtype=float)
    if np.isnan(array).any():
        raise ValueError(f"{name} contains NaN")
    if nonnegative and (array < 0).any():
        raise ValueError(f"{name} must be >= 0, got {array[array < 0].ravel()[0]!r}")
    return array


def scalar_or_array(array: np.ndarray):
    """Return a Python float for 0-d results, the array otherwise."""
    return float(array) if array.ndim == 0 else array
