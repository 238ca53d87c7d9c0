"""A 3Dconnexion SpaceMouse through pyspacemouse (hidapi), and its mapping to a reading.

The raw frame is pyspacemouse's state in its ``HID_Z_UP`` convention (x right, y away
from the user, z up; yaw positive counterclockwise seen from above; each about -1 to 1,
the device's counts / 350) and its buttons. The mapping, with the user facing the
screen (the robot seen from behind):

=========  ===============================  ===================
reading    puck                             pyspacemouse
=========  ===============================  ===================
x+         push forward (away from you)     y
y+         push left                        -x
z+         lift                             z
rot+       twist counterclockwise (pour)    yaw
finish     left button                      button 0
pause      right button                     button 1
=========  ===============================  ===================

Each axis has its own deadzone (the puck's six axes are independent springs) and is
capped at 1 (a puck pressed hard goes past 1). Roll and pitch are not used: pushing the
puck tilts it a little too. Pucks with more buttons (SpaceMouse Pro, Enterprise) use
their first two.
"""

from __future__ import annotations

import contextlib
import io

from casa_core.robot.devices._reading import (
    DEADZONE,
    DeviceLost,
    DeviceReading,
    DeviceUnavailable,
    MappedDevice,
    RawFrame,
    axial,
    check_deadzone,
    import_extra,
    went_down,
)

SPACEMOUSE = "spacemouse"
#: The raw frame's axes, in pyspacemouse's names and order.
SPACEMOUSE_AXES = ("x", "y", "z", "roll", "pitch", "yaw")
#: A read takes every report the puck has queued (it sends some 60 a second), at most this
#: many, so that a slow reader does not fall behind.
MAX_REPORTS = 256


def map_spacemouse(
    frame: RawFrame, previous: RawFrame | None, *, deadzone: float = DEADZONE
) -> DeviceReading:
    """A SpaceMouse's frame as a reading (the module docstring's table).

    Examples
    --------
    Pushed forward to 0.575 (x = (0.575 - 0.15) / (1 - 0.15) = 0.5), pushed right to 1.2
    (y = -1, capped) and twisted a little (yaw 0.1, inside the deadzone):

    >>> still = RawFrame((0.0,) * 6, (False, False))
    >>> reading = map_spacemouse(RawFrame((1.2, 0.575, 0, 0, 0, 0.1), (False, True)), still)
    >>> [round(a, 12) for a in reading.axes], reading.finish, reading.pause
    ([0.5, -1.0, 0.0, 0.0], False, True)
    """
    right, forward, up, _roll, _pitch, yaw = frame.axes[:6]
    axes = (axial(forward, deadzone), axial(-right, deadzone), axial(up, deadzone))
    buttons = len(frame.buttons)
    return DeviceReading(
        (*axes, axial(yaw, deadzone)),
        finish=buttons > 0 and went_down(frame, previous, [0]),
        pause=buttons > 1 and went_down(frame, previous, [1]),
    )


def _pyspacemouse():
    """pyspacemouse; its hidapi library is loaded on import."""
    try:
        return import_extra("pyspacemouse", SPACEMOUSE)
    except OSError as error:
        raise DeviceUnavailable(
            f"spacemouse: the hidapi library cannot be loaded ({error}); on Debian or "
            "Ubuntu: apt-get install libhidapi-hidraw0"
        ) from error


class SpaceMouseReader:
    """The raw reader of SpaceMouse number ``index``: a :class:`RawFrame` per read.

    Raises :class:`DeviceUnavailable` when pyspacemouse or hidapi is missing, there is
    no such puck, or it cannot be opened.
    """

    kind = SPACEMOUSE

    def __init__(self, *, index: int = 0):
        pyspacemouse = _pyspacemouse()
        try:
            found = pyspacemouse.get_connected_devices()
        except (AttributeError, RuntimeError, OSError) as error:
            raise DeviceUnavailable(
                f"spacemouse: hidapi cannot list devices ({error}); is the hidapi library "
                "installed? (Debian or Ubuntu: apt-get install libhidapi-hidraw0)"
            ) from error
        if not 0 <= index < len(found):
            raise DeviceUnavailable(
                f"spacemouse: no SpaceMouse number {index} is plugged in ({len(found)} found)"
            )
        model = found[index]
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # it prints "... found"
                self._mouse = pyspacemouse.open(
                    device=model,
                    device_index=found[:index].count(model),
                    nonblocking=True,
                    axis_convention=pyspacemouse.AxisConvention.HID_Z_UP,
                )
        except Exception as error:  # pyspacemouse raises RuntimeError, easyhid its own
            raise DeviceUnavailable(
                f"spacemouse {model!r}: cannot be opened ({error}); on Linux the user needs "
                "read and write access to /dev/hidraw* (a udev rule)"
            ) from error
        self.name = f"spacemouse {self._mouse.product_name or model!r}"

    def read(self) -> RawFrame:
        """The puck's axes and buttons after every queued report."""
        mouse = self._mouse
        try:
            state = mouse.read()
            pressed = [bool(b) for b in state.buttons]
            for _ in range(MAX_REPORTS):
                before = state.t  # reading a report moves the state's time
                state = mouse.read()
                pressed = [p or bool(b) for p, b in zip(pressed, state.buttons, strict=True)]
                if state.t == before:
                    break
        except Exception as error:  # easyhid's HIDException when the puck is gone
            raise DeviceLost(f"{self.name} was unplugged ({error})") from error
        if not mouse.connected:
            raise DeviceLost(f"{self.name} was closed")
        axes = tuple(float(getattr(state, axis)) for axis in SPACEMOUSE_AXES)
        return RawFrame(axes, tuple(pressed))

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._mouse.close()


class SpaceMouseDevice(MappedDevice):
    """A SpaceMouse read through :func:`map_spacemouse`."""

    def __init__(self, *, index: int = 0, deadzone: float = DEADZONE):
        deadzone = check_deadzone(deadzone)
        super().__init__(
            SpaceMouseReader(index=index),
            lambda f, p: map_spacemouse(f, p, deadzone=deadzone),
        )
