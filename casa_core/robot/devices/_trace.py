"""Traces: a device's raw frames recorded in a CSV file, played back as the device.

A trace's first line is its header: ``t`` (seconds since the start), then the backend's
raw axes (``axis0, axis1, ...`` for a gamepad, SDL's order; ``x, y, z, roll, pitch,
yaw`` for a SpaceMouse, pyspacemouse's) and its buttons (``button0, button1, ...``);
the header names the kind. Each row is one frame: numbers, buttons 0 or 1, a gamepad's
axes within [-1, 1], ``t`` 0 on the first row and increasing. Played back, read ``i``
gives the last row with ``t <= i * tick`` (or by a clock), a button counting as down if
any row since the last read had it down; after the last row's time the trace has ended
and a read raises :class:`DeviceLost`, as an unplugged device does.
"""

from __future__ import annotations

import bisect
import csv
import itertools
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from casa_core.defaults import TICK
from casa_core.robot.devices._gamepad import GAMEPAD, XBOX_LAYOUT, GamepadLayout, map_gamepad
from casa_core.robot.devices._reading import (
    DEADZONE,
    DeviceLost,
    DeviceUnavailable,
    MappedDevice,
    RawFrame,
    RawReader,
    check_deadzone,
)
from casa_core.robot.devices._spacemouse import SPACEMOUSE, SPACEMOUSE_AXES, map_spacemouse

#: Reads this close (s) past a row's time still see it: ``i * tick`` in floating point.
TIME_SLACK = 1e-9


class TraceError(DeviceUnavailable, ValueError):
    """A trace file that cannot be played: the message names the file, the line and the rule."""


def trace_columns(kind: str, axes: int, buttons: int) -> list[str]:
    """The header of a ``kind`` trace with ``axes`` axes and ``buttons`` buttons.

    Examples
    --------
    >>> trace_columns("gamepad", 2, 1)
    ['t', 'axis0', 'axis1', 'button0']
    >>> trace_columns("spacemouse", 6, 2)
    ['t', 'x', 'y', 'z', 'roll', 'pitch', 'yaw', 'button0', 'button1']
    """
    names = list(SPACEMOUSE_AXES) if kind == SPACEMOUSE else [f"axis{i}" for i in range(axes)]
    return ["t", *names, *(f"button{i}" for i in range(buttons))]


def _header(path: Path, header: Sequence[str]) -> tuple[str, int, int]:
    """The kind, axis count and button count a header names; :class:`TraceError` otherwise."""
    columns = [c.strip() for c in header]
    rule = (
        "the header is t, then axis0, axis1, ... (gamepad) or x, y, z, roll, pitch, yaw "
        "(spacemouse), then button0, button1, ..."
    )
    if not columns or columns[0] != "t":
        raise TraceError(f"{path}: line 1: the first column must be t; {rule}")
    kind = SPACEMOUSE if columns[1:2] == ["x"] else GAMEPAD
    axes = 6 if kind == SPACEMOUSE else sum(1 for c in columns if c.startswith("axis"))
    buttons = sum(1 for c in columns if c.startswith("button"))
    expected = trace_columns(kind, axes, buttons)
    if axes == 0:
        raise TraceError(f"{path}: line 1: column axis0 is missing; {rule}")
    for number, (found, wanted) in enumerate(itertools.zip_longest(columns, expected), 1):
        if found is None:
            raise TraceError(f"{path}: line 1: column {wanted} is missing; {rule}")
        if found != wanted:
            raise TraceError(
                f"{path}: line 1, column {number}: expected {wanted or 'no column'}, "
                f"found {found!r}; {rule}"
            )
    return kind, axes, buttons


def _number(path: Path, line: int, column: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise TraceError(f"{path}: line {line}, column {column}: {text!r} is not a number")
    return value


def _frame(path: Path, line: int, row: list[str], columns: list[str], kind: str, axes: int):
    """One row as ``(t, frame)``, each cell checked."""
    if len(row) != len(columns):
        raise TraceError(f"{path}: line {line}: {len(row)} cells, the header has {len(columns)}")
    values = [_number(path, line, c, text) for c, text in zip(columns, row, strict=True)]
    for column, value in zip(columns[1 + axes :], values[1 + axes :], strict=True):
        if value not in (0.0, 1.0):
            raise TraceError(f"{path}: line {line}, column {column}: a button is 0 or 1")
    for column, value in zip(columns[1 : 1 + axes], values[1 : 1 + axes], strict=True):
        if kind == GAMEPAD and not -1.0 <= value <= 1.0:
            raise TraceError(f"{path}: line {line}, column {column}: an SDL axis is in [-1, 1]")
    frame = RawFrame(tuple(values[1 : 1 + axes]), tuple(v == 1.0 for v in values[1 + axes :]))
    return values[0], frame


def read_trace(path: str | Path) -> tuple[str, list[float], list[RawFrame]]:
    """A trace file's kind, row times and frames; :class:`TraceError` on a bad file.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "pad.csv"
    >>> _ = path.write_text("t,axis0,button0\\n0,0.5,0\\n0.05,0.5,x\\n")
    >>> read_trace(path)
    Traceback (most recent call last):
    casa_core.robot.devices._trace.TraceError: ...pad.csv: line 3, column button0: 'x' is not...
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise TraceError(f"{path}: cannot be read as a CSV trace ({error})") from error
    if not rows:
        raise TraceError(f"{path}: line 1: the file is empty; a trace starts with its header")
    kind, axes, _buttons = _header(path, rows[0])
    columns = [c.strip() for c in rows[0]]
    times: list[float] = []
    frames: list[RawFrame] = []
    for line, row in enumerate(rows[1:], 2):
        t, frame = _frame(path, line, row, columns, kind, axes)
        if not times and t != 0.0:
            raise TraceError(f"{path}: line {line}: t of the first row must be 0, got {t}")
        if times and t <= times[-1]:
            raise TraceError(
                f"{path}: line {line}: t {t} is not after the row before ({times[-1]})"
            )
        times.append(t)
        frames.append(frame)
    if not frames:
        raise TraceError(f"{path}: line 2: the trace has a header but no rows")
    return kind, times, frames


class TracePlayer:
    """A trace file as a raw reader (:class:`RawReader`): its frames, read by read.

    Without ``clock``, read ``i`` (from 0) is at ``i * tick`` seconds; with it, at
    ``clock()`` less its value at the first read.
    """

    def __init__(
        self, path: str | Path, *, tick: float = TICK, clock: Callable[[], float] | None = None
    ):
        if not tick > 0:
            raise ValueError(f"a trace's tick must be above 0 s, got {tick}")
        self.kind, self._times, self._frames = read_trace(path)
        self.name = f"{self.kind} trace {Path(path).name!r}"
        self._tick = float(tick)
        self._clock = clock
        self._start: float | None = None
        self._reads = 0
        self._row = -1  # the row of the last read

    def _now(self) -> float:
        if self._clock is None:
            return self._reads * self._tick
        now = self._clock()
        if self._start is None:
            self._start = now
        return now - self._start

    def read(self) -> RawFrame:
        """The frame now; :class:`DeviceLost` once past the last row's time."""
        now = self._now()
        self._reads += 1
        if now > self._times[-1] + TIME_SLACK:
            raise DeviceLost(f"{self.name}: the trace ended at t = {self._times[-1]} s")
        row = bisect.bisect_right(self._times, now + TIME_SLACK) - 1
        frame = self._frames[row]
        # A press in a row skipped between two reads still counts.
        since = self._frames[self._row + 1 : row + 1] or [frame]
        buttons = tuple(any(f.buttons[b] for f in since) for b in range(len(frame.buttons)))
        self._row = row
        return RawFrame(frame.axes, buttons)

    @property
    def first_frame(self) -> RawFrame:
        return self._frames[0]

    def close(self) -> None:
        pass


class TraceDevice(MappedDevice):
    """A trace played through its kind's mapping, as the device that recorded it.

    ``kind`` (if given) must be the kind the trace's header names; a gamepad trace plays
    through ``pad_layout``. Raises :class:`TraceError` on a bad file.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "puck.csv"
    >>> rows = ["t,x,y,z,roll,pitch,yaw,button0", "0,0,1,0,0,0,0,0", "0.1,0,0,0,0,0,0,1"]
    >>> _ = path.write_text("\\n".join(rows))
    >>> device = TraceDevice(path)
    >>> [device.read() for _ in range(3)][-1]
    DeviceReading(axes=(0.0, 0.0, 0.0, 0.0), finish=True, pause=False)
    >>> device.read()
    Traceback (most recent call last):
    casa_core.robot.devices._reading.DeviceLost: spacemouse trace 'puck.csv': the trace ended at...
    """

    def __init__(
        self,
        path: str | Path,
        *,
        kind: str | None = None,
        deadzone: float = DEADZONE,
        tick: float = TICK,
        clock: Callable[[], float] | None = None,
        pad_layout: GamepadLayout = XBOX_LAYOUT,
    ):
        deadzone = check_deadzone(deadzone)
        player = TracePlayer(path, tick=tick, clock=clock)
        if kind is not None and kind != player.kind:
            raise TraceError(f"{path}: line 1: the header is a {player.kind} trace's, not {kind}'s")
        if player.kind == GAMEPAD:
            try:
                pad_layout.check(player.first_frame, f"{path}: line 1")
            except DeviceUnavailable as error:
                raise TraceError(str(error)) from None
            super().__init__(
                player, lambda f, p: map_gamepad(f, p, deadzone=deadzone, pad_layout=pad_layout)
            )
        else:
            super().__init__(player, lambda f, p: map_spacemouse(f, p, deadzone=deadzone))


def record_trace(
    reader: RawReader,
    *,
    seconds: float,
    tick: float = TICK,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> str:
    """A device's raw frames for ``seconds``, one per ``tick``, as a trace's CSV text.

    Write it with :func:`casa_core.io.atomic.atomic_write_text` (the one writer of
    outputs, which the robot's modules do not import). Stops early, keeping what it has,
    when the device is lost (re-raised if it was lost before the first frame).

    Examples
    --------
    >>> class Pad:
    ...     kind, name = "gamepad", "gamepad 'fake'"
    ...     def read(self):
    ...         return RawFrame((0.25, -1.0), (True,))
    >>> ticks = iter([0.0, 0.0, 0.05, 0.1, 0.15])
    >>> print(record_trace(Pad(), seconds=0.1, clock=lambda: next(ticks), sleep=lambda s: None))
    t,axis0,axis1,button0
    0.0,0.25,-1.0,1
    0.05,0.25,-1.0,1
    0.1,0.25,-1.0,1
    <BLANKLINE>
    """
    rows: list[tuple[float, RawFrame]] = []
    start = clock()
    while (now := clock() - start) <= seconds + TIME_SLACK:
        try:
            frame = reader.read()
        except DeviceLost:
            if not rows:
                raise
            break
        rows.append((now, frame))
        sleep(max(0.0, len(rows) * tick - now))
    first, frame = rows[0]
    lines = [trace_columns(reader.kind, len(frame.axes), len(frame.buttons))]
    for now, frame in rows:
        buttons = ("1" if b else "0" for b in frame.buttons)
        lines.append([repr(round(now - first, 6)), *map(repr, frame.axes), *buttons])
    return "".join(",".join(line) + "\n" for line in lines)
