"""Argument guards shared by the equations, intents and assistant: clear ValueErrors, not NaN."""

from __future__ import annotations

import numpy as np


def as_finite_or_inf(name: str, value, *, nonnegative: bool = False) -> np.ndarray:
    """``value`` as a float array, rejecting NaN (and negative values when asked).

    Parameters
    ----------
    name : str
        Name of the argument, for the error message.
    value : float or array_like
        The argument; ``inf`` is allowed.
    nonnegative : bool, default False
        Also reject values below 0.

    Returns
    -------
    ndarray
        ``value`` as a float array.

    Raises
    ------
    ValueError
        Naming the argument, if it contains NaN or (with ``nonnegative``) a negative value.

    Examples
    --------
    >>> as_finite_or_inf("t", [0, 2.5, np.inf])
    array([0. , 2.5, inf])
    >>> as_finite_or_inf("t", -1.0, nonnegative=True)
    Traceback (most recent call last):
    ...
    ValueError: t must be >= 0, got np.float64(-1.0)
    """
    array = np.asarray(value, dtype=float)
    if np.isnan(array).any():
        raise ValueError(f"{name} contains NaN")
    if nonnegative and (array < 0).any():
        raise ValueError(f"{name} must be >= 0, got {array[array < 0].ravel()[0]!r}")
    return array


def require_positive(owner: str | None = None, **values) -> None:
    """Raise ValueError unless every value is a finite number > 0.

    Parameters
    ----------
    owner : str, optional
        What the values belong to (e.g. ``"intent 'green'"``), for the error message.
    **values
        The parameters to check, by name; checked in the order given.

    Raises
    ------
    ValueError
        Naming the first parameter that is not a finite positive number (and the owner).

    Examples
    --------
    >>> require_positive(k=7, dt=0.5)
    >>> require_positive(k=0)
    Traceback (most recent call last):
    ...
    ValueError: k must be a positive number, got 0
    >>> require_positive("intent 'green'", speed=0.05, dt=-0.5)
    Traceback (most recent call last):
    ...
    ValueError: dt of intent 'green' must be a positive number, got -0.5
    """
    for name, value in values.items():
        try:
            positive = bool(np.isfinite(value) and value > 0)
        except TypeError:  # not a number at all (None, a string)
            positive = False
        if not positive:
            where = name if owner is None else f"{name} of {owner}"
            raise ValueError(f"{where} must be a positive number, got {value!r}")


def scalar_or_array(array: np.ndarray):
    """A Python float for a 0-d result, the array otherwise.

    Examples
    --------
    >>> scalar_or_array(np.array(2.0))
    2.0
    >>> scalar_or_array(np.array([2.0]))
    array([2.])
    """
    return float(array) if array.ndim == 0 else array
