"""The keyboard map: 8 keys to a Cartesian velocity ``[vx, vy, vz, vrot]``.

Six keys move the end effector along +-x, +-y, +-z of the robot base frame at
``speed`` (0.05 m/s); two keys turn the last joint at ``rot_speed`` (0.5 rad/s). This
is the paper's direct teleoperation function T (docs/paper-to-code.md), with the
original implementation's speeds. Two opposite keys held together cancel. Keys are
named as in the casa-trial/1 log's ``keys`` column (:data:`casa_core.vocabulary.KEYS`,
docs/data-contracts.md).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable

import numpy as np

from casa_core.defaults import ROT_SPEED, SPEED
from casa_core.vocabulary import KEYS

#: The ``(plus, minus)`` key of each axis of ``[x, y, z, rot]``, in the keys' order.
AXIS_KEYS = tuple(zip(KEYS[::2], KEYS[1::2], strict=True))
#: Unit direction of each key in ``[x, y, z, rot]``.
KEY_DIRECTIONS = {
    "x+": (1, 0, 0, 0),
    "x-": (-1, 0, 0, 0),
    "y+": (0, 1, 0, 0),
    "y-": (0, -1, 0, 0),
    "z+": (0, 0, 1, 0),
    "z-": (0, 0, -1, 0),
    "rot+": (0, 0, 0, 1),
    "rot-": (0, 0, 0, -1),
}


def check_keys(keys: Iterable[str]) -> frozenset[str]:
    """The held keys as a frozenset; raises ``ValueError`` naming any unknown key."""
    held = frozenset(keys)
    unknown = sorted(held.difference(KEYS))
    if unknown:
        raise ValueError(f"unknown key(s) {unknown}; the keys are {' '.join(KEYS)}")
    return held


def keys_to_action(
    keys: Iterable[str], speed: float = SPEED, rot_speed: float = ROT_SPEED
) -> np.ndarray:
    """Cartesian velocity ``[vx, vy, vz, vrot]`` (m/s, rad/s) commanded by the held keys.

    Parameters
    ----------
    keys : iterable of str
        Held keys, from :data:`KEYS`.
    speed, rot_speed : float
        Speed of a translation key (m/s) and of a rotate key (rad/s).
    """
    held = check_keys(keys)
    return _action(held, float(speed), float(rot_speed)).copy()


@functools.lru_cache(maxsize=1024)
def _action(held: frozenset[str], speed: float, rot_speed: float) -> np.ndarray:
    """:func:`keys_to_action` of checked keys, computed once per key set (a control loop
    asks for the same few sets every tick); callers get a copy."""
    direction = np.zeros(4)
    for key in held:
        direction += KEY_DIRECTIONS[key]
    return direction * np.array([speed, speed, speed, rot_speed])


def format_keys(keys: Iterable[str]) -> str:
    """Held keys as the log writes them: space-separated, canonical order, '' when none."""
    return _formatted(check_keys(keys))


@functools.lru_cache(maxsize=1024)
def _formatted(held: frozenset[str]) -> str:
    return " ".join(key for key in KEYS if key in held)


def parse_keys(text: str) -> frozenset[str]:
    """Inverse of :func:`format_keys`."""
    return check_keys(text.split())
