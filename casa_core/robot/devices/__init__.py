"""Input devices other than the keyboard: a gamepad and a SpaceMouse, each read as a
normalised command ``[x, y, z, rot]`` in the keyboard's frame (docs/devices.md).

Each backend is a raw reader (the hardware, imported only when opened: the ``devices``
extra) and a pure mapping from its raw frames to a :class:`DeviceReading`; a recorded
trace plays through the same mapping in place of the hardware. The modules:

- :mod:`~casa_core.robot.devices._reading`: the reading, the errors, the deadzone, button
  edges;
- :mod:`~casa_core.robot.devices._gamepad`: a gamepad through pygame (SDL), its layout;
- :mod:`~casa_core.robot.devices._spacemouse`: a SpaceMouse through pyspacemouse (hidapi);
- :mod:`~casa_core.robot.devices._trace`: trace files, played and recorded.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> path = Path(tempfile.mkdtemp()) / "pad.csv"
>>> _ = path.write_text("t,axis0,axis1,axis2,axis3,axis4,button0,button1\\n"
...                     "0,0,-1,0,0,0,0,0\\n")
>>> device = open_device("gamepad", trace=path)
>>> device.read()
DeviceReading(axes=(1.0, 0.0, 0.0, 0.0), finish=False, pause=False)
>>> open_device("joystick")
Traceback (most recent call last):
ValueError: unknown input device 'joystick'; the devices are gamepad, spacemouse
"""

from __future__ import annotations

from pathlib import Path

from casa_core.robot.devices._gamepad import (
    GAMEPAD,
    XBOX_LAYOUT,
    GamepadDevice,
    GamepadLayout,
    GamepadReader,
    map_gamepad,
)
from casa_core.robot.devices._reading import (
    DEADZONE,
    PIP_EXTRA,
    Device,
    DeviceError,
    DeviceLost,
    DeviceReading,
    DeviceUnavailable,
    RawFrame,
    RawReader,
)
from casa_core.robot.devices._spacemouse import SpaceMouseDevice, SpaceMouseReader, map_spacemouse
from casa_core.robot.devices._trace import (
    TraceDevice,
    TraceError,
    TracePlayer,
    read_trace,
    record_trace,
)
from casa_core.vocabulary import CONTINUOUS_INPUTS, INPUTS

#: What a participant is told to use, per device (the session's screens show it).
CONTROLS = {
    "gamepad": "left stick: move the cup   right stick up / down: up / down   "
    "right stick left / right: tilt to pour / back   A: finished   B: pause",
    "spacemouse": "push the cap: move the cup   lift / press: up / down   "
    "twist: tilt to pour / back   left button: finished   right button: pause",
}

__all__ = [
    "CONTINUOUS_INPUTS",
    "CONTROLS",
    "DEADZONE",
    "INPUTS",
    "PIP_EXTRA",
    "XBOX_LAYOUT",
    "Device",
    "DeviceError",
    "DeviceLost",
    "DeviceReading",
    "DeviceUnavailable",
    "GamepadDevice",
    "GamepadLayout",
    "GamepadReader",
    "RawFrame",
    "RawReader",
    "SpaceMouseDevice",
    "SpaceMouseReader",
    "TraceDevice",
    "TraceError",
    "TracePlayer",
    "map_gamepad",
    "map_spacemouse",
    "open_device",
    "open_raw_reader",
    "read_trace",
    "record_trace",
]


def _check_kind(kind: str) -> str:
    if kind not in CONTINUOUS_INPUTS:
        raise ValueError(
            f"unknown input device {kind!r}; the devices are {', '.join(CONTINUOUS_INPUTS)}"
        )
    return kind


def open_device(
    kind: str, *, deadzone: float = DEADZONE, index: int = 0, trace: str | Path | None = None
) -> Device:
    """Device number ``index`` of ``kind`` (``gamepad`` or ``spacemouse``), ready to read.

    With ``trace``, a :class:`TraceDevice` playing that file (one frame per 0.05 s read)
    instead of the hardware.

    Raises
    ------
    ValueError
        On an unknown kind or a deadzone outside [0, 1).
    DeviceUnavailable
        When the device cannot be opened (its message says why and what to do), or the
        trace file is bad (:class:`TraceError`, naming the file, line and rule).
    """
    kind = _check_kind(kind)
    if trace is not None:
        return TraceDevice(trace, kind=kind, deadzone=deadzone)
    if kind == GAMEPAD:
        return GamepadDevice(index=index, deadzone=deadzone)
    return SpaceMouseDevice(index=index, deadzone=deadzone)


def open_raw_reader(kind: str, *, index: int = 0) -> RawReader:
    """The raw reader of device number ``index`` of ``kind``, for :func:`record_trace`.

    Examples
    --------
    >>> open_raw_reader("keyboard")
    Traceback (most recent call last):
    ValueError: unknown input device 'keyboard'; the devices are gamepad, spacemouse
    """
    if _check_kind(kind) == GAMEPAD:
        return GamepadReader(index=index)
    return SpaceMouseReader(index=index)
