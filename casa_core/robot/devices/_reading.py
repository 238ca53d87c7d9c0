"""What every input device gives: a reading, its errors, the deadzone and button edges.

A backend is a raw reader (the hardware, or a trace) giving a :class:`RawFrame` per
read, and a pure mapping from that frame (and the one before it) to a
:class:`DeviceReading`; :class:`MappedDevice` joins the two.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Protocol

#: The deadzone (a fraction of full deflection): sticks and pucks rest a little off 0.
DEADZONE = 0.15
#: How the optional packages of the backends are installed.
PIP_EXTRA = "pip install 'casa[devices]'"


@dataclass(frozen=True)
class DeviceReading:
    """One read of a device, in the keyboard's frame.

    ``axes`` is ``[x, y, z, rot]``, each in [-1, 1], after the deadzone (0 inside it):
    x+ away from the robot base (Up arrow), y+ left on screen (Left arrow), z+ up (W),
    rot+ tilts the cup to pour (A); 1 is what a held key commands. ``finish`` and
    ``pause`` say that such a button went down since the last read.

    Examples
    --------
    >>> DeviceReading((0.5, 0.0, 0.0, -1.0)).finish
    False
    >>> DeviceReading((2.0, 0.0, 0.0, 0.0))
    Traceback (most recent call last):
    ValueError: a reading's axes are 4 numbers in [-1, 1], got (2.0, 0.0, 0.0, 0.0)
    """

    axes: tuple[float, float, float, float]
    finish: bool = False
    pause: bool = False

    def __post_init__(self):
        if len(self.axes) != 4 or not all(-1.0 <= a <= 1.0 for a in self.axes):
            raise ValueError(f"a reading's axes are 4 numbers in [-1, 1], got {self.axes}")


class DeviceError(Exception):
    """An input device failed; the message names the device and what happened."""


class DeviceUnavailable(DeviceError):
    """A device cannot be opened: its package is missing, none is plugged in, no permission."""


class DeviceLost(DeviceError):
    """A device that was open is gone: unplugged, or its trace ended."""


class Device(Protocol):
    """What the control loop reads: a name, a non-blocking ``read`` and ``close``."""

    name: str

    def read(self) -> DeviceReading: ...

    def close(self) -> None: ...


@dataclass(frozen=True)
class RawFrame:
    """What a raw reader gives per read: the device's own axis values and button states.

    A gamepad's axes are SDL's joystick axes in its order; a SpaceMouse's are
    pyspacemouse's ``x, y, z, roll, pitch, yaw``. A button reads as down if it was down
    at any moment since the previous frame, so that a tap between two reads is kept.
    """

    axes: tuple[float, ...]
    buttons: tuple[bool, ...]


class RawReader(Protocol):
    """A device's hardware side (or a trace): frames in the backend's own terms."""

    kind: str
    name: str

    def read(self) -> RawFrame: ...

    def close(self) -> None: ...


#: The mapping of a backend: this frame and the previous one (None at the first read).
FrameMapping = Callable[[RawFrame, "RawFrame | None"], DeviceReading]


class MappedDevice:
    """A :class:`Device` from a raw reader and its mapping.

    Examples
    --------
    >>> class Still:
    ...     kind, name = "gamepad", "gamepad 'still'"
    ...     def read(self):
    ...         return RawFrame((0.0,), (True,))
    ...     def close(self):
    ...         pass
    >>> device = MappedDevice(Still(), lambda f, p: DeviceReading((f.axes[0], 0, 0, 0)))
    >>> device.name, device.read().axes
    ("gamepad 'still'", (0.0, 0, 0, 0))
    """

    def __init__(self, reader: RawReader, mapping: FrameMapping):
        self.name = reader.name
        self._reader = reader
        self._mapping = mapping
        self._previous: RawFrame | None = None

    def read(self) -> DeviceReading:
        """The reading since the last one; raises :class:`DeviceLost` once the device is gone."""
        frame = self._reader.read()
        reading = self._mapping(frame, self._previous)
        self._previous = frame
        return reading

    def close(self) -> None:
        self._reader.close()


def check_deadzone(deadzone: float) -> float:
    """``deadzone`` as a float; ``ValueError`` unless it is in [0, 1).

    Examples
    --------
    >>> check_deadzone(1.0)
    Traceback (most recent call last):
    ValueError: the deadzone must be at least 0 and below 1, got 1.0
    """
    deadzone = float(deadzone)
    if not 0.0 <= deadzone < 1.0:
        raise ValueError(f"the deadzone must be at least 0 and below 1, got {deadzone}")
    return deadzone


def axial(value: float, deadzone: float) -> float:
    """One axis through its own deadzone: 0 inside, then 0 to 1 linearly up to full deflection.

    Examples
    --------
    >>> axial(0.1, 0.15), round(axial(0.575, 0.15), 12), axial(-1.3, 0.15)
    (0.0, 0.5, -1.0)
    """
    size = min(abs(value), 1.0)
    if size <= deadzone:
        return 0.0
    return math.copysign((size - deadzone) / (1.0 - deadzone), value) + 0.0


def radial(x: float, y: float, deadzone: float) -> tuple[float, float]:
    """A stick's two axes through one circular deadzone, keeping the stick's direction.

    The distance from the centre is rescaled as :func:`axial` rescales one axis (and
    capped at 1: a square gate's corners go past the circle).

    Examples
    --------
    >>> radial(0.1, 0.1, 0.15)
    (0.0, 0.0)
    >>> [round(v, 12) for v in radial(0.0, -0.575, 0.15)]
    [0.0, -0.5]
    """
    size = math.hypot(x, y)
    if size <= deadzone:
        return 0.0, 0.0
    scale = min((size - deadzone) / (1.0 - deadzone), 1.0) / size
    return x * scale + 0.0, y * scale + 0.0


def went_down(frame: RawFrame, previous: RawFrame | None, buttons: Sequence[int]) -> bool:
    """Whether one of ``buttons`` is down in ``frame`` and was up in ``previous``.

    At the first read (no previous frame) a button already held does not count: it went
    down before the device was read.

    Examples
    --------
    >>> up, down = RawFrame((), (False,)), RawFrame((), (True,))
    >>> went_down(down, up, [0]), went_down(down, down, [0]), went_down(down, None, [0])
    (True, False, False)
    """
    if previous is None:
        return False
    return any(frame.buttons[b] and not previous.buttons[b] for b in buttons)


def import_extra(module: str, kind: str) -> ModuleType:
    """Import a backend's optional package, or raise :class:`DeviceUnavailable` saying how
    to install it.

    Examples
    --------
    >>> import_extra("no_such_package_casa", "gamepad")
    Traceback (most recent call last):
    casa_core.robot.devices._reading.DeviceUnavailable: gamepad: the Python package \
'no_such_package_casa' is not installed; install the devices extra: pip install 'casa[devices]'
    """
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise DeviceUnavailable(
            f"{kind}: the Python package {module!r} is not installed; "
            f"install the devices extra: {PIP_EXTRA}"
        ) from error
