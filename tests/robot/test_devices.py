"""The input devices' mappings, deadzones, button edges and traces, without hardware.

Expected numbers are computed by hand from the deadzone's rescaling, (|v| - d) / (1 - d)
with d = 0.15 unless a test says otherwise.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from casa_core.robot.devices import (
    DeviceLost,
    DeviceReading,
    DeviceUnavailable,
    GamepadLayout,
    RawFrame,
    TraceDevice,
    TraceError,
    map_gamepad,
    map_spacemouse,
    open_device,
    read_trace,
    record_trace,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "devices"
PAD_STILL = RawFrame((0.0, 0.0, -1.0, 0.0, 0.0, -1.0), (False,) * 11)  # triggers rest at -1
PUCK_STILL = RawFrame((0.0,) * 6, (False, False))


def pad(*, axes=None, buttons=()) -> RawFrame:
    """An Xbox pad's frame (SDL joystick order) with ``axes`` ({index: value}) moved and
    ``buttons`` held."""
    values = list(PAD_STILL.axes)
    for index, value in (axes or {}).items():
        values[index] = value
    return RawFrame(tuple(values), tuple(i in buttons for i in range(11)))


def puck(*, x=0.0, y=0.0, z=0.0, roll=0.0, pitch=0.0, yaw=0.0, buttons=()) -> RawFrame:
    return RawFrame((x, y, z, roll, pitch, yaw), tuple(i in buttons for i in range(2)))


# ---- the gamepad's mapping -------------------------------------------------------------


@pytest.mark.parametrize(
    ("axes", "expected"),
    [
        # SDL: stick up and stick left are negative; the keyboard's x+ is Up, y+ is Left.
        ({1: -1.0}, (1.0, 0.0, 0.0, 0.0)),  # left stick up: x+
        ({1: 1.0}, (-1.0, 0.0, 0.0, 0.0)),  # left stick down: x-
        ({0: -1.0}, (0.0, 1.0, 0.0, 0.0)),  # left stick left: y+
        ({0: 1.0}, (0.0, -1.0, 0.0, 0.0)),  # left stick right: y-
        ({4: -1.0}, (0.0, 0.0, 1.0, 0.0)),  # right stick up: z+
        ({4: 1.0}, (0.0, 0.0, -1.0, 0.0)),  # right stick down: z-
        ({3: -1.0}, (0.0, 0.0, 0.0, 1.0)),  # right stick left: rot+ (pour), as A is
        ({3: 1.0}, (0.0, 0.0, 0.0, -1.0)),  # right stick right: rot-
        ({2: 1.0, 5: 1.0}, (0.0, 0.0, 0.0, 0.0)),  # the triggers do nothing
    ],
)
def test_each_gamepad_axis_moves_one_reading_axis_with_its_sign(axes, expected):
    assert map_gamepad(pad(axes=axes), PAD_STILL).axes == pytest.approx(expected)


def test_the_gamepad_rescales_past_the_deadzone():
    # Left stick up to 0.575: (0.575 - 0.15) / 0.85 = 0.5; right stick up to 0.32:
    # (0.32 - 0.15) / 0.85 = 0.2.
    reading = map_gamepad(pad(axes={1: -0.575, 4: -0.32}), PAD_STILL)
    assert reading.axes == pytest.approx((0.5, 0.0, 0.2, 0.0))
    # With deadzone 0.25: (0.575 - 0.25) / 0.75 = 0.4333...
    reading = map_gamepad(pad(axes={1: -0.575}), PAD_STILL, deadzone=0.25)
    assert reading.axes[0] == pytest.approx(0.325 / 0.75)


def test_the_left_stick_has_a_radial_deadzone_that_keeps_its_direction():
    # (0.1, 0.1) is 0.1414 from the centre, inside 0.15: exactly 0, though 0.1 + 0.1 > 0.15.
    assert map_gamepad(pad(axes={0: -0.1, 1: -0.1}), PAD_STILL).axes == (0.0, 0.0, 0.0, 0.0)
    # (0.3, 0.4) is 0.5 from the centre: (0.5 - 0.15) / 0.85 = 0.41176 along the same
    # direction, so x = 0.41176 * 0.4 / 0.5 = 0.32941 and y = 0.41176 * 0.3 / 0.5 = 0.24706.
    x, y, z, rot = map_gamepad(pad(axes={0: -0.3, 1: -0.4}), PAD_STILL).axes
    assert (x, y) == pytest.approx((0.35 / 0.85 * 0.8, 0.35 / 0.85 * 0.6))
    # A square gate's corner (1, 1) is capped at 1 along the diagonal: 1/sqrt(2) each.
    x, y, _, _ = map_gamepad(pad(axes={0: -1.0, 1: -1.0}), PAD_STILL).axes
    assert (x, y) == pytest.approx((2**-0.5, 2**-0.5))


def test_the_right_stick_has_one_deadzone_per_axis():
    # Right stick up 0.575 and 0.1 to the left: z = 0.5, the small sideways part is dropped.
    reading = map_gamepad(pad(axes={4: -0.575, 3: -0.1}), PAD_STILL)
    assert reading.axes == pytest.approx((0.0, 0.0, 0.5, 0.0))
    assert reading.axes[3] == 0.0


@pytest.mark.parametrize("mapping", ["gamepad", "spacemouse"])
def test_the_deadzone_is_exactly_zero_inside_continuous_at_its_edge_one_at_full(mapping):
    def forward(value: float) -> float:
        if mapping == "gamepad":
            return map_gamepad(pad(axes={1: -value}), PAD_STILL).axes[0]
        return map_spacemouse(puck(y=value), PUCK_STILL).axes[0]

    assert forward(0.0) == 0.0
    assert forward(0.149) == 0.0
    assert forward(0.15) == 0.0
    assert 0.0 < forward(0.1501) < 1e-3  # (0.1501 - 0.15) / 0.85 = 0.000118
    assert forward(0.1501) == pytest.approx(0.0001 / 0.85)
    assert forward(1.0) == 1.0


def test_a_remapped_gamepad_layout_reads_its_own_axes_and_buttons():
    # A pad whose right stick is axes 2/3 and whose finish is button 7 (start).
    layout = GamepadLayout(z=(3, -1.0), rot=(2, 1.0), finish=(7,), pause=(6,))
    frame = pad(axes={3: -1.0, 2: 1.0}, buttons={7})
    reading = map_gamepad(frame, PAD_STILL, pad_layout=layout)
    assert reading.axes == pytest.approx((0.0, 0.0, 1.0, 1.0))
    assert (reading.finish, reading.pause) == (True, False)


def test_the_gamepad_buttons_fire_once_per_press_on_the_press():
    # Default: A (button 0) finishes, B (button 1) pauses; a held button fires once.
    frames = [pad(), pad(buttons={0}), pad(buttons={0}), pad(), pad(buttons={0, 1})]
    previous, fired = None, []
    for frame in frames:
        reading = map_gamepad(frame, previous)
        fired.append((reading.finish, reading.pause))
        previous = frame
    assert fired == [(False, False), (True, False), (False, False), (False, False), (True, True)]


def test_a_button_held_at_the_first_read_does_not_fire():
    assert not map_gamepad(pad(buttons={0}), None).finish
    assert not map_spacemouse(puck(buttons={0}), None).finish


# ---- the SpaceMouse's mapping ----------------------------------------------------------


@pytest.mark.parametrize(
    ("moved", "expected"),
    [
        # pyspacemouse's HID_Z_UP: x right, y away from the user, z up, yaw counterclockwise.
        ({"y": 1.0}, (1.0, 0.0, 0.0, 0.0)),  # push forward: x+
        ({"y": -1.0}, (-1.0, 0.0, 0.0, 0.0)),
        ({"x": -1.0}, (0.0, 1.0, 0.0, 0.0)),  # push left: y+
        ({"x": 1.0}, (0.0, -1.0, 0.0, 0.0)),
        ({"z": 1.0}, (0.0, 0.0, 1.0, 0.0)),  # lift: z+
        ({"z": -1.0}, (0.0, 0.0, -1.0, 0.0)),
        ({"yaw": 1.0}, (0.0, 0.0, 0.0, 1.0)),  # twist counterclockwise: rot+
        ({"yaw": -1.0}, (0.0, 0.0, 0.0, -1.0)),
        ({"roll": 1.0, "pitch": -1.0}, (0.0, 0.0, 0.0, 0.0)),  # tilting does nothing
    ],
)
def test_each_spacemouse_axis_moves_one_reading_axis_with_its_sign(moved, expected):
    assert map_spacemouse(puck(**moved), PUCK_STILL).axes == pytest.approx(expected)


def test_the_spacemouse_rescales_each_axis_and_caps_a_hard_push():
    # y 0.575 -> 0.5; x -0.32 -> y (0.32 - 0.15) / 0.85 = 0.2; z 1.4 (pressed past the
    # counts' 350) -> 1; yaw 0.1 inside the deadzone -> 0.
    reading = map_spacemouse(puck(y=0.575, x=-0.32, z=1.4, yaw=0.1), PUCK_STILL)
    assert reading.axes == pytest.approx((0.5, 0.2, 1.0, 0.0))
    assert reading.axes[3] == 0.0


def test_the_spacemouse_buttons_are_finish_and_pause_once_per_press():
    readings = [
        map_spacemouse(frame, previous)
        for previous, frame in [
            (puck(), puck(buttons={0})),
            (puck(buttons={0}), puck(buttons={0})),
            (puck(), puck(buttons={1})),
        ]
    ]
    assert [(r.finish, r.pause) for r in readings] == [(True, False), (False, False), (False, True)]
    # A puck with one button pauses never.
    one = RawFrame((0.0,) * 6, (True,))
    assert map_spacemouse(one, RawFrame((0.0,) * 6, (False,))) == DeviceReading(
        (0.0, 0.0, 0.0, 0.0), finish=True
    )


# ---- traces ----------------------------------------------------------------------------


def write(tmp_path: Path, text: str, name: str = "trace.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


PAD_HEADER = "t,axis0,axis1,axis2,axis3,axis4,axis5,button0,button1\n"


def pad_row(t: float, up: float = 0.0, finish: int = 0) -> str:
    return f"{t},0,{-up},-1,0,0,-1,{finish},0\n"


def test_a_trace_read_i_is_the_last_row_at_or_before_i_ticks(tmp_path):
    # Rows at 0, 0.12, 0.2 (up 0.5, 1.0, 0.0). With a 0.05 s tick: reads at 0, 0.05, 0.1
    # see row 0; 0.15 sees row 1 (0.12 <= 0.15); 0.2 sees row 2 (t == 0.2, in floating
    # point 4 * 0.05 = 0.2); 0.25 is past the end.
    text = PAD_HEADER + pad_row(0, 0.575) + pad_row(0.12, 1.0) + pad_row(0.2)
    device = TraceDevice(write(tmp_path, text))
    xs = [device.read().axes[0] for _ in range(5)]
    assert xs == pytest.approx([0.5, 0.5, 0.5, 1.0, 0.0])
    with pytest.raises(DeviceLost, match="trace ended"):
        device.read()


def test_a_trace_tick_is_a_parameter_and_a_clock_can_replace_it(tmp_path):
    path = write(tmp_path, PAD_HEADER + pad_row(0, 0.575) + pad_row(0.12, 1.0) + pad_row(0.2))
    device = TraceDevice(path, tick=0.1)  # reads at 0, 0.1, 0.2
    assert [device.read().axes[0] for _ in range(3)] == pytest.approx([0.5, 0.5, 0.0])
    times = iter([10.0, 10.13, 10.19, 10.3])  # the clock's start is the first read
    device = TraceDevice(path, clock=lambda: next(times))
    assert [device.read().axes[0] for _ in range(3)] == pytest.approx([0.5, 1.0, 1.0])
    with pytest.raises(DeviceLost):
        device.read()


def test_a_gamepad_trace_plays_through_a_layout_of_its_own(tmp_path):
    # Right stick up is axis 4 in the default layout; this one reads axis 5 as z.
    path = write(tmp_path, PAD_HEADER + "0,0,0,-1,0,-1,-0.575,0,0\n")
    assert TraceDevice(path).read().axes == (0.0, 0.0, 1.0, 0.0)
    device = TraceDevice(path, pad_layout=GamepadLayout(z=(5, -1.0)))
    assert device.read().axes == pytest.approx((0.0, 0.0, 0.5, 0.0))
    with pytest.raises(ValueError, match="tick must be above 0"):
        TraceDevice(path, tick=0)


def test_a_tap_between_two_reads_still_fires_once(tmp_path):
    # finish is down in the row at 0.02 only, between the reads at 0 and 0.05.
    text = PAD_HEADER + pad_row(0) + pad_row(0.02, finish=1) + pad_row(0.03) + pad_row(0.1)
    device = TraceDevice(write(tmp_path, text))
    assert [device.read().finish for _ in range(3)] == [False, True, False]


def test_the_example_traces_play_as_scripted():
    # Left stick up (puck forward) from 0.5 s to 2.5 s, then finish pressed at 3.0 s.
    for kind in ("gamepad", "spacemouse"):
        device = open_device(kind, trace=DATA / f"{kind}.csv")
        readings = []
        with pytest.raises(DeviceLost, match="trace ended"):
            while True:
                readings.append(device.read())
        assert len(readings) == 71  # reads at 0, 0.05, ..., 3.5 s
        moving = [i for i, r in enumerate(readings) if r.axes[0] > 0]
        assert (moving[0], moving[-1]) == (10, 49)  # 0.5 s to 2.45 s
        assert all(r.axes == (1.0, 0.0, 0.0, 0.0) for r in readings[10:50])
        assert [i for i, r in enumerate(readings) if r.finish] == [60]
        assert not any(r.pause for r in readings)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "line 1: the file is empty"),
        ("time,axis0\n0,0\n", "line 1: the first column must be t"),
        ("t,axis0,axis2,button0\n0,0,0,0\n", "line 1, column 3: expected axis1, found 'axis2'"),
        ("t,x,y,z,roll,pitch,button0\n0,0,0,0,0,0,0\n", "column 7: expected yaw"),
        ("t,x,y,z,roll,pitch\n0,0,0,0,0,0\n", "line 1: column yaw is missing"),
        ("t,button0\n0,0\n", "line 1: column axis0 is missing"),
        ("t,axis0,speed\n0,0,0\n", "column 3: expected no column, found 'speed'"),
        (PAD_HEADER, "line 2: the trace has a header but no rows"),
        (PAD_HEADER + pad_row(0) + "0.05,0,abc,-1,0,0,-1,0,0\n", "line 3, column axis1: 'abc'"),
        (PAD_HEADER + "0,0,nan,-1,0,0,-1,0,0\n", "line 2, column axis1: 'nan' is not a number"),
        (PAD_HEADER + pad_row(0) + pad_row(0.1) + pad_row(0.05), "line 4: t 0.05 is not after"),
        (PAD_HEADER + pad_row(0) + pad_row(0), "line 3: t 0.0 is not after"),
        (PAD_HEADER + pad_row(0.1), "line 2: t of the first row must be 0"),
        (PAD_HEADER + "0,0,0,-1\n", "line 2: 4 cells, the header has 9"),
        (PAD_HEADER + "0,0,0,-1,0,0,-1,2,0\n", "line 2, column button0: a button is 0 or 1"),
        (PAD_HEADER + "0,0,1.5,-1,0,0,-1,0,0\n", "line 2, column axis1: an SDL axis is in"),
        ("t,axis0,axis1,button0,button1\n0,0,0,0,0\n", "needs 5 axes and 2 buttons"),
    ],
)
def test_a_bad_trace_names_the_file_the_line_and_the_rule(tmp_path, text, message):
    path = write(tmp_path, text, "bad.csv")
    with pytest.raises(TraceError, match=message) as caught:
        open_device("gamepad" if "axis" in text or not text else "spacemouse", trace=path)
    assert str(path) in str(caught.value)
    assert isinstance(caught.value, ValueError | DeviceUnavailable)


def test_a_spacemouse_trace_may_not_exceed_one_and_is_capped(tmp_path):
    path = write(tmp_path, "t,x,y,z,roll,pitch,yaw,button0,button1\n0,0,1.6,0,0,0,0,0,0\n")
    assert open_device("spacemouse", trace=path).read().axes == (1.0, 0.0, 0.0, 0.0)


def test_a_trace_of_the_other_kind_is_refused(tmp_path):
    path = write(tmp_path, PAD_HEADER + pad_row(0))
    with pytest.raises(TraceError, match="is a gamepad trace's, not spacemouse's"):
        open_device("spacemouse", trace=path)


def test_a_missing_trace_file_is_a_trace_error(tmp_path):
    with pytest.raises(TraceError, match="nowhere.csv: cannot be read"):
        TraceDevice(tmp_path / "nowhere.csv")


class Scripted:
    """A raw reader that plays a list of frames, then is lost."""

    def __init__(self, kind: str, frames):
        self.kind, self.name, self._frames = kind, f"{kind} 'scripted'", iter(frames)

    def read(self) -> RawFrame:
        try:
            return next(self._frames)
        except StopIteration:
            raise DeviceLost(f"{self.name} was unplugged") from None

    def close(self) -> None:
        pass


def example_trace(kind: str) -> str:
    """The example trace of ``kind`` (tests/data/devices/): 3.5 s at 10 Hz, pushed forward
    fully from 0.5 s to 2.5 s, finish pressed at 3.0 s for 0.2 s."""
    frames = []
    for row in range(36):
        t = row / 10
        forward = 0.5 <= t < 2.5
        held = {0} if 3.0 <= t < 3.2 else set()
        if kind == "gamepad":
            frames.append(pad(axes={1: -1.0} if forward else {}, buttons=held))
        else:
            frames.append(puck(y=1.0 if forward else 0.0, buttons=held))
    times = iter([0.0] + [i / 10 for i in range(37)])
    reader = Scripted(kind, frames)
    return record_trace(reader, seconds=3.5, tick=0.1, clock=lambda: next(times), sleep=id)


def write_examples() -> None:
    """Write the example traces again: ``python -c "from tests.robot.test_devices import
    write_examples; write_examples()"``."""
    from casa_core.io.atomic import atomic_write_text

    for kind in ("gamepad", "spacemouse"):
        atomic_write_text(DATA / f"{kind}.csv", example_trace(kind))


@pytest.mark.parametrize("kind", ["gamepad", "spacemouse"])
def test_the_example_traces_are_what_their_script_records(kind):
    assert (DATA / f"{kind}.csv").read_text() == example_trace(kind)


def test_a_recorded_trace_reads_back_as_the_frames_recorded(tmp_path):
    frames = [pad(axes={1: -0.25}), pad(axes={0: 0.5}, buttons={1}), pad()]
    times = iter([0.0, 0.001, 0.051, 0.101, 0.151])
    reader = Scripted("gamepad", frames)
    text = record_trace(reader, seconds=1.0, clock=lambda: next(times), sleep=id)
    kind, rows, read = read_trace(write(tmp_path, text))
    assert (kind, rows, read) == ("gamepad", [0.0, 0.05, 0.1], frames)  # stopped when lost


def test_recording_a_device_lost_at_once_raises():
    with pytest.raises(DeviceLost):
        record_trace(Scripted("gamepad", []), seconds=1.0)


# ---- the face ---------------------------------------------------------------------------


def test_an_unknown_kind_names_the_kinds():
    with pytest.raises(ValueError, match="unknown input device 'keyboard'; .* gamepad, spacemouse"):
        open_device("keyboard")


def test_a_deadzone_outside_zero_to_one_is_refused(tmp_path):
    with pytest.raises(ValueError, match="deadzone"):
        open_device("gamepad", deadzone=1.0, trace=write(tmp_path, PAD_HEADER + pad_row(0)))


@pytest.mark.parametrize(
    ("kind", "module"), [("gamepad", "pygame"), ("spacemouse", "pyspacemouse")]
)
def test_a_missing_extra_is_unavailable_naming_the_pip_command(monkeypatch, kind, module):
    monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
    with pytest.raises(DeviceUnavailable) as caught:
        open_device(kind)
    message = str(caught.value)
    assert message.startswith(f"{kind}: ")
    assert f"'{module}' is not installed" in message
    assert "pip install 'casa[devices]'" in message


def test_the_face_needs_none_of_the_extras():
    # With the hardware packages unimportable, the package still imports and says its kinds.
    code = (
        "import sys\n"
        "for name in ('pygame', 'pyspacemouse', 'evdev', 'easyhid'): sys.modules[name] = None\n"
        "from casa_core.robot import devices\n"
        "print(devices.INPUTS, devices.CONTINUOUS_INPUTS)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout == "('keyboard', 'gamepad', 'spacemouse') ('gamepad', 'spacemouse')\n"
