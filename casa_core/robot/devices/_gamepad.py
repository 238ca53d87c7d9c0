"""A gamepad or joystick through pygame's SDL joystick API, and its mapping to a reading.

The default :class:`GamepadLayout` is an Xbox pad as SDL's joystick API numbers it on
Linux (the kernel's evdev order: axes 0/1 left stick, 2 left trigger, 3/4 right stick,
5 right trigger; buttons 0 A, 1 B, 2 X, 3 Y, 4/5 shoulders, 6 back, 7 start); SDL gives
stick left and stick up as negative values:

=========  ==========================  ====================
reading    pad                         SDL joystick
=========  ==========================  ====================
x+         left stick up               axis 1 negative
y+         left stick left             axis 0 negative
z+         right stick up              axis 4 negative
rot+       right stick left (pour)     axis 3 negative
finish     A                           button 0
pause      B                           button 1
=========  ==========================  ====================

The left stick's two axes share one circular deadzone (the stick's direction is kept);
z and rot each have their own, so that raising the cup does not turn the wrist. Other
pads (or SDL's HIDAPI drivers, switched off here on Linux) may number the right stick
otherwise: record a trace to see which column moves, and pass a layout of your own.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

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
    radial,
    went_down,
)

GAMEPAD = "gamepad"
#: The events of each open pad (by SDL instance id): pygame has one queue for all pads,
#: and the reader that reads first hands the others theirs.
_EVENTS: dict[int, list] = {}


@dataclass(frozen=True)
class GamepadLayout:
    """Which SDL joystick axis moves x, y, z and the wrist, and which buttons finish or pause.

    Each of ``x``, ``y``, ``z``, ``rot`` is ``(axis index, sign)``: the reading is
    ``sign * axis`` through the deadzone. ``finish`` and ``pause`` are button indices
    (any of them fires).

    Examples
    --------
    >>> GamepadLayout().axes_needed, GamepadLayout().buttons_needed
    (5, 2)
    >>> swapped = GamepadLayout(z=(3, -1.0), rot=(2, -1.0))  # a pad with 2/3 the right stick
    """

    x: tuple[int, float] = (1, -1.0)
    y: tuple[int, float] = (0, -1.0)
    z: tuple[int, float] = (4, -1.0)
    rot: tuple[int, float] = (3, -1.0)
    finish: tuple[int, ...] = (0,)
    pause: tuple[int, ...] = (1,)
    axes_needed: int = field(init=False)
    buttons_needed: int = field(init=False)

    def __post_init__(self):
        axes = [self.x[0], self.y[0], self.z[0], self.rot[0]]
        object.__setattr__(self, "axes_needed", max(axes) + 1)
        object.__setattr__(self, "buttons_needed", max((*self.finish, *self.pause), default=-1) + 1)

    def check(self, frame: RawFrame, where: str) -> None:
        """``DeviceUnavailable`` naming ``where`` if ``frame`` has too few axes or buttons."""
        if len(frame.axes) < self.axes_needed or len(frame.buttons) < self.buttons_needed:
            raise DeviceUnavailable(
                f"{where}: has {len(frame.axes)} axes and {len(frame.buttons)} buttons; "
                f"the gamepad layout needs {self.axes_needed} axes and "
                f"{self.buttons_needed} buttons"
            )


#: The layout of an Xbox pad under Linux (module docstring).
XBOX_LAYOUT = GamepadLayout()


def map_gamepad(
    frame: RawFrame,
    previous: RawFrame | None,
    *,
    deadzone: float = DEADZONE,
    pad_layout: GamepadLayout = XBOX_LAYOUT,
) -> DeviceReading:
    """A gamepad's frame as a reading (the module docstring's table).

    Examples
    --------
    Left stick half up past the deadzone: SDL axis 1 at -0.575 is x = (0.575 - 0.15) /
    (1 - 0.15) = 0.5; the right stick full left (axis 3 at -1) is rot = 1:

    >>> still = RawFrame((0.0,) * 6, (False,) * 11)
    >>> frame = RawFrame((0.0, -0.575, 0.0, -1.0, 0.0, 0.0), (True,) + (False,) * 10)
    >>> reading = map_gamepad(frame, still)
    >>> [round(a, 12) for a in reading.axes], reading.finish, reading.pause
    ([0.5, 0.0, 0.0, 1.0], True, False)
    """
    axes, pad = frame.axes, pad_layout
    x, y = radial(pad.x[1] * axes[pad.x[0]], pad.y[1] * axes[pad.y[0]], deadzone)
    z = axial(pad.z[1] * axes[pad.z[0]], deadzone)
    rot = axial(pad.rot[1] * axes[pad.rot[0]], deadzone)
    return DeviceReading(
        (x, y, z, rot),
        finish=went_down(frame, previous, pad.finish),
        pause=went_down(frame, previous, pad.pause),
    )


def _pygame():
    """pygame, its SDL set up for a joystick without a window of its own."""
    # No window is opened: SDL's dummy video driver serves pygame's event queue, and the
    # pad is read while the pybullet window has the focus.
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS", "1")
    # SDL's HIDAPI drivers number an Xbox pad's axes otherwise than the kernel does.
    os.environ.setdefault("SDL_JOYSTICK_HIDAPI", "0")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    return import_extra("pygame", GAMEPAD)


class GamepadReader:
    """The raw reader of gamepad number ``index`` (SDL's order): a :class:`RawFrame` per read.

    Raises :class:`DeviceUnavailable` when pygame is missing or there is no such pad.
    """

    kind = GAMEPAD

    def __init__(self, *, index: int = 0):
        pygame = self._pygame = _pygame()
        pygame.display.init()
        pygame.joystick.init()
        pygame.event.pump()  # a pad plugged in since the joysticks were first listed
        count = pygame.joystick.get_count()
        if not 0 <= index < count:
            raise DeviceUnavailable(
                f"gamepad: no gamepad number {index} is plugged in ({count} found); on Linux "
                "the user needs read access to /dev/input/event* (the 'input' group)"
            )
        self._joystick = pygame.joystick.Joystick(index)
        self._joystick.init()
        self._id = self._joystick.get_instance_id()
        _EVENTS[self._id] = []
        self.name = f"gamepad {self._joystick.get_name()!r}"
        self._lost = False

    def read(self) -> RawFrame:
        """The pad's axes and buttons now (a button pressed since the last read reads down)."""
        pygame, joystick = self._pygame, self._joystick
        for event in pygame.event.get():
            _EVENTS.get(getattr(event, "instance_id", -1), []).append(event)
        tapped = set()
        for event in _EVENTS.get(self._id, []):
            if event.type == pygame.JOYDEVICEREMOVED:
                self._lost = True
            elif event.type == pygame.JOYBUTTONDOWN:
                tapped.add(event.button)
        _EVENTS[self._id] = []
        if self._lost:
            raise DeviceLost(f"{self.name} was unplugged")
        try:
            axes = tuple(float(joystick.get_axis(i)) for i in range(joystick.get_numaxes()))
            buttons = tuple(
                bool(joystick.get_button(i)) or i in tapped
                for i in range(joystick.get_numbuttons())
            )
        except pygame.error as error:  # SDL dropped the pad before saying so
            self._lost = True
            raise DeviceLost(f"{self.name} was unplugged ({error})") from error
        return RawFrame(axes, buttons)

    def close(self) -> None:
        _EVENTS.pop(self._id, None)
        if not self._lost:
            self._joystick.quit()


class GamepadDevice(MappedDevice):
    """A gamepad read through :func:`map_gamepad`.

    Raises :class:`DeviceUnavailable` when it cannot be opened or has too few axes or
    buttons for ``pad_layout``.
    """

    def __init__(
        self, *, index: int = 0, deadzone: float = DEADZONE, pad_layout: GamepadLayout = XBOX_LAYOUT
    ):
        deadzone = check_deadzone(deadzone)
        reader = GamepadReader(index=index)
        try:
            pad_layout.check(reader.read(), reader.name)
        except DeviceLost as error:
            raise DeviceUnavailable(str(error)) from error
        except DeviceUnavailable:
            reader.close()
            raise
        super().__init__(
            reader, lambda f, p: map_gamepad(f, p, deadzone=deadzone, pad_layout=pad_layout)
        )
