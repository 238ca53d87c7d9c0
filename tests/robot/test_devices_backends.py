"""The hardware readers against stand-ins of pygame and pyspacemouse: opening, reading,
taps between reads, unplugging, and the messages when a device is missing."""

from __future__ import annotations

import sys
import types
from dataclasses import dataclass, field

import pytest

from casa_core.robot.devices import DeviceLost, DeviceUnavailable, open_device, open_raw_reader

JOYBUTTONDOWN, JOYDEVICEREMOVED = 1539, 1542


@dataclass
class FakeJoystick:
    name: str = "Xbox Wireless Controller"
    axes: list = field(default_factory=lambda: [0.0, 0.0, -1.0, 0.0, 0.0, -1.0])
    buttons: list = field(default_factory=lambda: [0] * 11)
    quit_called: bool = False
    instance_id: int = 7
    dropped: bool = False

    def init(self):
        pass

    def get_instance_id(self):
        return self.instance_id

    def get_name(self):
        return self.name

    def get_numaxes(self):
        return len(self.axes)

    def get_axis(self, i):
        if self.dropped:
            raise RuntimeError("Joystick not initialized")
        return self.axes[i]

    def get_numbuttons(self):
        return len(self.buttons)

    def get_button(self, i):
        return self.buttons[i]

    def quit(self):
        self.quit_called = True


def fake_pygame(joysticks):
    """A module with pygame's joystick and event calls the reader makes."""
    events: list = []
    module = types.SimpleNamespace(
        JOYBUTTONDOWN=JOYBUTTONDOWN,
        JOYDEVICEREMOVED=JOYDEVICEREMOVED,
        error=RuntimeError,
        display=types.SimpleNamespace(init=lambda: None),
        joystick=types.SimpleNamespace(
            init=lambda: None, get_count=lambda: len(joysticks), Joystick=joysticks.__getitem__
        ),
        event=types.SimpleNamespace(
            get=lambda: [events.pop(0) for _ in list(events)], pump=lambda: None
        ),
        queued=events,
    )
    return module


def event(kind, **attributes):
    return types.SimpleNamespace(type=kind, **attributes)


@pytest.fixture
def pad(monkeypatch):
    joystick = FakeJoystick()
    pygame = fake_pygame([joystick])
    monkeypatch.setitem(sys.modules, "pygame", pygame)
    return joystick, pygame


def test_the_gamepad_is_named_and_read_through_its_mapping(pad):
    joystick, _ = pad
    device = open_device("gamepad")
    assert device.name == "gamepad 'Xbox Wireless Controller'"
    joystick.axes[1] = -0.575  # left stick up: (0.575 - 0.15) / 0.85 = 0.5
    assert device.read().axes == pytest.approx((0.5, 0.0, 0.0, 0.0))
    device.close()
    assert joystick.quit_called


def test_a_gamepad_tap_between_two_reads_fires_finish_once(pad):
    joystick, pygame = pad
    device = open_device("gamepad")
    assert not device.read().finish
    # A pressed and released between reads: the state says up, the event says it went down.
    pygame.queued.append(event(JOYBUTTONDOWN, instance_id=7, button=0))
    pygame.queued.append(event(JOYBUTTONDOWN, instance_id=8, button=1))  # another pad's
    reading = device.read()
    assert (reading.finish, reading.pause) == (True, False)
    assert not device.read().finish


def test_two_gamepads_each_get_their_own_presses(monkeypatch):
    pads = [FakeJoystick(name="one", instance_id=7), FakeJoystick(name="two", instance_id=8)]
    pygame = fake_pygame(pads)
    monkeypatch.setitem(sys.modules, "pygame", pygame)
    one, two = open_device("gamepad", index=0), open_device("gamepad", index=1)
    one.read(), two.read()
    pygame.queued.append(event(JOYBUTTONDOWN, instance_id=8, button=1))
    assert not one.read().pause  # pad one took pad two's press off pygame's queue
    assert two.read().pause  # and pad two still sees it
    two.close()
    pygame.queued.append(event(JOYBUTTONDOWN, instance_id=8, button=1))  # a closed pad's
    assert not one.read().pause


def test_an_unplugged_gamepad_is_lost_and_stays_lost(pad):
    _, pygame = pad
    device = open_device("gamepad")
    device.read()
    pygame.queued.append(event(JOYDEVICEREMOVED, instance_id=8))  # another pad left: no matter
    device.read()
    pygame.queued.append(event(JOYDEVICEREMOVED, instance_id=7))
    with pytest.raises(DeviceLost, match="gamepad 'Xbox Wireless Controller' was unplugged"):
        device.read()
    with pytest.raises(DeviceLost):
        device.read()
    device.close()  # closing a lost device is fine


def test_a_gamepad_sdl_dropped_before_saying_so_is_lost(pad):
    joystick, _ = pad
    device = open_device("gamepad")
    joystick.dropped = True  # get_axis raises pygame.error, as on a dropped pad
    with pytest.raises(DeviceLost, match="was unplugged"):
        device.read()


def test_no_gamepad_plugged_in_is_unavailable_saying_what_to_check(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", fake_pygame([]))
    with pytest.raises(DeviceUnavailable, match=r"no gamepad number 0 is plugged in \(0 found\)"):
        open_device("gamepad")
    monkeypatch.setitem(sys.modules, "pygame", fake_pygame([FakeJoystick()]))
    with pytest.raises(DeviceUnavailable, match="no gamepad number 1 .* /dev/input"):
        open_device("gamepad", index=1)


def test_a_gamepad_with_too_few_axes_is_unavailable(monkeypatch):
    small = FakeJoystick(name="Tiny", axes=[0.0, 0.0], buttons=[0, 0])
    monkeypatch.setitem(sys.modules, "pygame", fake_pygame([small]))
    with pytest.raises(DeviceUnavailable, match="gamepad 'Tiny': has 2 axes .* needs 5 axes"):
        open_device("gamepad")
    assert small.quit_called


# ---- SpaceMouse ------------------------------------------------------------------------


class FakeMouse:
    """pyspacemouse's SpaceMouseDevice: read() handles one queued report."""

    def __init__(self):
        self.state = types.SimpleNamespace(
            t=-1.0, x=0.0, y=0.0, z=0.0, roll=0.0, pitch=0.0, yaw=0.0, buttons=[0, 0]
        )
        self.reports: list[dict] = []
        self.product_name = "SpaceMouse Compact"
        self.connected = True
        self.unplugged = False
        self.clock = 0.0

    def read(self):
        if self.unplugged:
            raise OSError("Failed to read from HID device: -1")
        if self.reports:
            self.clock += 1.0
            for name, value in self.reports.pop(0).items():
                setattr(self.state, name, value)
            self.state.t = self.clock
        return self.state

    def close(self):
        self.connected = False


def fake_pyspacemouse(mice, opened):
    def open_(*, device, device_index, nonblocking, axis_convention):
        opened.append((device, device_index, axis_convention))
        return mice[len(opened) - 1]

    return types.SimpleNamespace(
        get_connected_devices=lambda: ["SpaceMouseCompact"] * len(mice),
        open=open_,
        AxisConvention=types.SimpleNamespace(HID_Z_UP="hid_z_up"),
    )


def test_the_spacemouse_opens_in_the_z_up_convention_and_drains_its_reports(monkeypatch):
    mouse, opened = FakeMouse(), []
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake_pyspacemouse([mouse], opened))
    device = open_device("spacemouse")
    assert device.name == "spacemouse 'SpaceMouse Compact'"
    assert opened == [("SpaceMouseCompact", 0, "hid_z_up")]
    device.read()
    # Three reports queued since the last read: the last axes count, the tap counts.
    mouse.reports += [{"y": 0.3}, {"buttons": [1, 0]}, {"y": 0.575, "buttons": [0, 0]}]
    reading = device.read()
    assert reading.axes == pytest.approx((0.5, 0.0, 0.0, 0.0))
    assert (reading.finish, reading.pause) == (True, False)
    assert mouse.reports == []


def test_an_unplugged_spacemouse_is_lost(monkeypatch):
    mouse = FakeMouse()
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake_pyspacemouse([mouse], []))
    device = open_device("spacemouse")
    device.read()
    mouse.unplugged = True
    with pytest.raises(DeviceLost, match="spacemouse 'SpaceMouse Compact' was unplugged"):
        device.read()


def test_the_second_of_two_spacemice_is_opened_by_index(monkeypatch):
    opened: list = []
    mice = [FakeMouse(), FakeMouse()]
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake_pyspacemouse(mice[1:], opened))
    monkeypatch.setattr(
        sys.modules["pyspacemouse"], "get_connected_devices", lambda: ["SpaceMouseCompact"] * 2
    )
    open_raw_reader("spacemouse", index=1)
    assert opened == [("SpaceMouseCompact", 1, "hid_z_up")]
    with pytest.raises(DeviceUnavailable, match=r"no SpaceMouse number 2 .* \(2 found\)"):
        open_device("spacemouse", index=2)


def test_a_spacemouse_that_cannot_be_opened_says_why(monkeypatch):
    def refuse(**_):
        raise RuntimeError("Failed to open device")

    module = fake_pyspacemouse([FakeMouse()], [])
    module.open = refuse
    monkeypatch.setitem(sys.modules, "pyspacemouse", module)
    with pytest.raises(DeviceUnavailable, match="Failed to open device.*/dev/hidraw"):
        open_device("spacemouse")


def test_a_missing_hidapi_library_names_the_debian_package(monkeypatch):
    def import_module(name):
        raise OSError("cannot load library 'libhidapi-hidraw.so.0'")

    monkeypatch.setattr("importlib.import_module", import_module)
    with pytest.raises(DeviceUnavailable, match="hidapi library .* libhidapi-hidraw0"):
        open_device("spacemouse")


# ---- the real packages, where installed (the devices extra) ----------------------------


def test_the_real_pygame_lists_no_such_gamepad(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    pytest.importorskip("pygame", reason="pygame is not installed: pip install 'casa[devices]'")
    with pytest.raises(
        DeviceUnavailable, match=r"no gamepad number 99 is plugged in \(\d+ found\)"
    ):
        open_device("gamepad", index=99)


def test_the_real_pyspacemouse_lists_no_such_puck():
    pytest.importorskip("pyspacemouse", reason="not installed: pip install 'casa[devices]'")
    # Without the system's hidapi library pyspacemouse cannot list devices at all.
    with pytest.raises(DeviceUnavailable, match=r"no SpaceMouse number 99 |libhidapi-hidraw0"):
        open_device("spacemouse", index=99)
