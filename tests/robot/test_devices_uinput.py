"""A virtual gamepad (Linux uinput, through python-evdev) read by the real pygame backend.

SDL opens it as it opens a pad on a USB port: the stick moved on the virtual pad comes
back through ``open_device("gamepad")``, and destroying the virtual pad unplugs it.
Skipped where /dev/uinput is not writable or evdev or pygame is not installed.
"""

from __future__ import annotations

import os
import sys
import time

import pytest

from casa_core.robot.devices import DeviceLost, DeviceUnavailable, open_device

NAME = "casa virtual pad"
#: How long SDL may take to see a device come or go (inotify on /dev/input, or its
#: fallback of looking every 3 s).
PATIENCE = 5.0


def virtual_pad():
    """A uinput pad with an Xbox pad's evdev codes (the kernel's xpad driver's)."""
    if not sys.platform.startswith("linux"):
        pytest.skip("uinput is Linux's")
    if not os.access("/dev/uinput", os.W_OK):
        pytest.skip("/dev/uinput is not writable (no uinput module, or no permission)")
    evdev = pytest.importorskip(
        "evdev", reason="evdev is not installed: pip install 'casa[devices]'"
    )
    pytest.importorskip("pygame", reason="pygame is not installed: pip install 'casa[devices]'")
    e = evdev.ecodes
    stick = evdev.AbsInfo(value=0, min=-32768, max=32767, fuzz=0, flat=0, resolution=0)
    trigger = evdev.AbsInfo(value=0, min=0, max=255, fuzz=0, flat=0, resolution=0)
    buttons = [e.BTN_SOUTH, e.BTN_EAST, e.BTN_NORTH, e.BTN_WEST, e.BTN_TL, e.BTN_TR]
    buttons += [e.BTN_SELECT, e.BTN_START, e.BTN_MODE, e.BTN_THUMBL, e.BTN_THUMBR]
    axes = [(e.ABS_X, stick), (e.ABS_Y, stick), (e.ABS_Z, trigger)]
    axes += [(e.ABS_RX, stick), (e.ABS_RY, stick), (e.ABS_RZ, trigger)]
    try:
        pad = evdev.UInput(
            {e.EV_KEY: buttons, e.EV_ABS: axes}, name=NAME, vendor=0x1209, product=0xCA5A
        )
    except OSError as error:
        pytest.skip(f"/dev/uinput refused a virtual gamepad: {error}")
    node = getattr(pad.device, "path", None)
    if node is None or not os.access(node, os.R_OK):
        pad.close()
        pytest.skip(f"the virtual gamepad's node {node} is not readable (the 'input' group)")
    return evdev, pad


def open_virtual(deadline: float):
    """The virtual pad through ``open_device``, whatever other pads are plugged in."""
    while True:
        for index in range(16):
            try:
                device = open_device("gamepad", index=index)
            except DeviceUnavailable:
                break
            if device.name == f"gamepad {NAME!r}":
                return device
            device.close()
        if time.monotonic() > deadline:
            pytest.fail(f"SDL did not list {NAME!r} within {PATIENCE} s")
        time.sleep(0.05)


def read_until(device, accept, deadline: float):
    """The first reading ``accept`` takes, reading every 10 ms until ``deadline``."""
    while time.monotonic() < deadline:
        reading = device.read()
        if accept(reading):
            return reading
        time.sleep(0.01)
    pytest.fail("the virtual gamepad's input did not come back in time")


def test_a_virtual_gamepad_moves_the_reading_and_unplugging_it_is_lost(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    # Containers often run no udev: SDL then finds pads by watching /dev/input itself.
    monkeypatch.setenv("SDL_JOYSTICK_DISABLE_UDEV", "1")
    monkeypatch.setenv("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    evdev, pad = virtual_pad()
    e = evdev.ecodes
    device = None
    try:
        device = open_virtual(time.monotonic() + PATIENCE)
        # Left stick fully up (evdev's minimum, SDL's -1): x = 1.
        pad.write(e.EV_ABS, e.ABS_Y, -32768)
        pad.syn()
        reading = read_until(device, lambda r: r.axes[0] > 0.9, time.monotonic() + PATIENCE)
        assert reading.axes == pytest.approx((1.0, 0.0, 0.0, 0.0), abs=1e-3)
        # Half up (SDL -0.5): (0.5 - 0.15) / 0.85 = 0.4118.
        pad.write(e.EV_ABS, e.ABS_Y, -16384)
        pad.syn()
        reading = read_until(device, lambda r: r.axes[0] < 0.9, time.monotonic() + PATIENCE)
        assert reading.axes[0] == pytest.approx(0.35 / 0.85, abs=2e-3)
        # A (BTN_SOUTH, SDL's button 0) pressed and held: finish once.
        pad.write(e.EV_KEY, e.BTN_SOUTH, 1)
        pad.syn()
        read_until(device, lambda r: r.finish, time.monotonic() + PATIENCE)
        assert not device.read().finish
        pad.close()
        with pytest.raises(DeviceLost, match=f"gamepad {NAME!r} was unplugged"):
            read_until(device, lambda r: False, time.monotonic() + PATIENCE)
    finally:
        if device is not None:
            device.close()
        pad.close()
