"""The window of ``casa session``: one pybullet window, its screens and its keyboard.

One window stays open for a participant's whole session (the steps:
:mod:`casa_core.study.session_run`). Its screens: the next trial's instructions (what to
do and where, the target highlighted), a preview of the reference path, a countdown,
the trial (its time; a warning when the loop runs slower than real time), its end, the
Likert questions, the rest while the robot learns (a progress bar) and the pause. Text
sits at fixed pixels of the window, wrapped to its width; keys are read through
:class:`~casa_core.robot.teleop.KeyLatch`, so a one-frame tap counts. pybullet closes
its window on Escape whatever its settings: :class:`WindowClosed` lets the session
reopen it, paused.
"""

from __future__ import annotations

import textwrap
import time
from collections.abc import Callable

import numpy as np
import pybullet as p

from casa_core.assist.tasks import task_waypoints
from casa_core.robot.sim import ArmSimulation
from casa_core.robot.teleop import HELP, KeyboardKeys, KeyLatch, Window
from casa_core.scene import Scene

ENTER = p.B3G_RETURN
PAUSE, CONTINUE, QUIT, YES, NO = (ord(key) for key in "pcqyn")
DIGITS = {ord(str(score)): score for score in range(1, 8)}
#: Layout in pixels; a character of text size s is about 7.6 s px wide, a line 17 s high.
MARGIN, CHAR_WIDTH, LINE_HEIGHT = 24, 7.6, 17.0
INK, WARN, GO = (0.05, 0.05, 0.1), (0.75, 0.05, 0.05), (0.05, 0.5, 0.1)
HALO_RGBA = (1.0, 0.8, 0.0, 0.45)
PATH_RGB = (1.0, 0.45, 0.0)
#: 1024 x 768, >= 20 ms a frame (pybullet's 4 ms lets a software renderer take whole cores).
GUI_OPTIONS = "--width=1024 --height=768 --minGraphicsUpdateTimeMs=20000"
#: A loop slower than this fraction of real time is warned about.
SLOW = 0.95
SCALE = "1 = strongly disagree     4 = neither agree nor disagree     7 = strongly agree"


class WindowClosed(Exception):
    """The window was closed (Escape, or its close button)."""


def wrap(text: str, size: float, width: int) -> list[str]:
    """``text`` in lines that fit ``width`` pixels at text size ``size``; blank lines kept.

    Examples
    --------
    >>> wrap("one two three four five", 1.0, 140)  # 12 characters a line
    ['one two', 'three four', 'five']
    >>> wrap("first\\n\\nsecond", 1.0, 140)
    ['first', '', 'second']
    """
    chars = max(10, int((width - 2 * MARGIN) / (CHAR_WIDTH * size)))
    lines = []
    for paragraph in text.split("\n"):
        lines += textwrap.wrap(paragraph, chars) or [""]
    return lines


class SessionWindow:
    """The session's pybullet window: the arm, the scene and the screens.

    Parameters
    ----------
    scene : Scene
    notify : callable, optional
        ``notify(kind)`` once a screen is drawn (``instructions``, ``preview``, ``trial``,
        ``likert``, ``learning``, ``pause``...): the console, or a test driving the window.
    """

    def __init__(self, scene: Scene, *, notify: Callable[[str], None] | None = None):
        self.scene = scene
        self.notify = notify or (lambda kind: None)
        self.rate = self.slowest = 1.0
        self.controls = f"Keys: {HELP}"  # a device's own, when the session drives with one
        self._open()

    def _open(self) -> None:
        self.sim = ArmSimulation(self.scene, gui=True, gui_options=GUI_OPTIONS)
        Window(self.sim, realtime=True)  # the camera behind the robot, no pybullet panels
        self.client = self.sim.client
        self.latch = KeyLatch()
        shape = p.createVisualShape(
            p.GEOM_SPHERE, radius=0.06, rgbaColor=HALO_RGBA, physicsClientId=self.client
        )
        self._halo = p.createMultiBody(
            baseVisualShapeIndex=shape, basePosition=[0, 0, -1], physicsClientId=self.client
        )
        ghost = p.createVisualShape(
            p.GEOM_SPHERE, radius=0.02, rgbaColor=(1, 0.45, 0, 1), physicsClientId=self.client
        )
        self._ghost = p.createMultiBody(
            baseVisualShapeIndex=ghost, basePosition=[0, 0, -1], physicsClientId=self.client
        )
        time.sleep(0.3)  # the camera is set by the window's own thread
        width, height, view, projection = p.getDebugVisualizerCamera(physicsClientId=self.client)[
            :4
        ]
        self.width, self.height = width, height
        self._to_clip = np.asarray(projection).reshape(4, 4).T @ np.asarray(view).reshape(4, 4).T
        self._unproject = np.linalg.inv(self._to_clip)
        self._resting: str | None = None

    def reopen(self) -> None:
        """A new window after the old one was closed."""
        self.close()
        self._open()

    def close(self) -> None:
        self.sim.close()  # idempotent

    def _call(self, function, *args, **kwargs):
        """A pybullet call on this window; :class:`WindowClosed` if it is gone."""
        try:
            return function(*args, physicsClientId=self.client, **kwargs)
        except p.error:
            if not p.isConnected(self.client):
                raise WindowClosed from None
            raise

    def pixel(self, point) -> tuple[float, float]:
        """Where the world ``point`` is drawn, in pixels from the top left."""
        clip = self._to_clip @ np.r_[np.asarray(point, dtype=float), 1.0]
        x, y = clip[:2] / clip[3]
        return (x + 1) / 2 * self.width, (1 - y) / 2 * self.height

    def at(self, u: float, v: float) -> list[float]:
        """The world point drawn at pixel ``(u, v)`` (from the top left), near the camera."""
        point = self._unproject @ np.array([2 * u / self.width - 1, 1 - 2 * v / self.height, 0, 1])
        return list(point[:3] / point[3])

    def clear(self) -> None:
        """Remove every text and line; hide the highlight and the preview marker."""
        self._call(p.removeAllUserDebugItems)
        self._resting = None
        for body in (self._halo, self._ghost):
            self._call(p.resetBasePositionAndOrientation, body, [0, 0, -1], [0, 0, 0, 1])

    def write(self, text: str, top: float, *, size: float = 1.4, color=INK) -> float:
        """Wrapped ``text`` from pixel row ``top``; returns the row below it."""
        height = LINE_HEIGHT * size
        for line in wrap(text, size, self.width):
            top += height
            if line:
                self._call(
                    p.addUserDebugText,
                    line,
                    self.at(MARGIN, top),
                    textColorRGB=color,
                    textSize=size,
                )
        return top + 0.4 * height

    def big(self, text: str, color=WARN) -> int:
        """A large word in the middle of the window (countdown, GO, DONE); its item id."""
        left = self.width / 2 - len(text) * CHAR_WIDTH * 2
        return self._call(
            p.addUserDebugText,
            text,
            self.at(left, self.height * 0.45),
            textColorRGB=color,
            textSize=4.0,
        )

    def highlight(self, task: str) -> None:
        """A halo and a label on the task's target, in the scene."""
        target = task_waypoints(task, self.scene)[-1, :3]
        self._call(p.resetBasePositionAndOrientation, self._halo, list(target), [0, 0, 0, 1])
        u, v = self.pixel(target)
        # Drawn near the camera, so that the arm never hides the label.
        label = self.at(u - 30, v - 48)
        self._call(p.addUserDebugText, "TARGET", label, textColorRGB=[0.7, 0.3, 0], textSize=1.6)
        self._call(p.addUserDebugLine, self.at(u, v - 42), self.at(u, v - 14), [0.9, 0.6, 0], 3)

    def poll(self) -> frozenset[int]:
        """The keys pressed since the last poll."""
        _, pressed = self.latch.update(self._call(p.getKeyboardEvents))
        return pressed

    def wait_key(self, keys, *, seconds: float | None = None) -> int | None:
        """The first of ``keys`` pressed; None after ``seconds`` without one."""
        end = None if seconds is None else time.perf_counter() + seconds
        while end is None or time.perf_counter() < end:
            hit = [key for key in self.poll() if key in keys]
            if hit:
                return hit[0]
            time.sleep(1 / 60)
        return None

    def keyboard(self) -> KeyboardKeys:
        """The trial's key source: the arm's keys, Enter to finish, P to pause."""
        self.poll()  # keys pressed before the trial started do not count
        return KeyboardKeys(self.client, pause_keys=(PAUSE,))

    def instructions(self, title: str, body: str, task: str) -> str:
        """The next trial's instructions; ``"start"`` on Enter, ``"pause"`` on P."""
        self.sim.reset_to_start()
        self.clear()
        self.highlight(task)
        top = self.write(title, 0, size=2.0)
        top = self.write(body, top)
        top = self.write(self.controls, top, size=1.2)
        self.write("Press Enter to see the path and start.   P: pause", top, color=GO)
        self.poll()
        self.notify("instructions")
        return "start" if self.wait_key({ENTER, PAUSE}) == ENTER else "pause"

    def preview(self, task: str, reference: np.ndarray, seconds: float) -> None:
        """The task's reference path as a line, a marker travelling along it in ``seconds``.

        ``reference`` is :func:`casa_core.assist.tasks.intended_trajectory`'s ``[t, x, y, z, rot]``.
        """
        if seconds <= 0:
            return
        self._call(p.removeAllUserDebugItems)
        self.highlight(task)
        self.write("Watch the orange marker: one way to do this task.", 0, size=1.6)
        # The reference is straight between the task's waypoints: one line each.
        corners = task_waypoints(task, self.scene)[:, :3]
        for a, b in zip(corners[:-1], corners[1:], strict=True):
            if np.linalg.norm(b - a) > 1e-6:
                self._call(p.addUserDebugLine, list(a), list(b), PATH_RGB, lineWidth=4)
        positions = reference[:, 1:4]
        self.notify("preview")
        tilting = False
        began = time.perf_counter()
        while (elapsed := time.perf_counter() - began) < seconds:
            row = min(len(reference) - 1, int(elapsed / seconds * len(reference)))
            self._call(
                p.resetBasePositionAndOrientation, self._ghost, list(positions[row]), [0, 0, 0, 1]
            )
            if not tilting and abs(reference[row, 4] - reference[0, 4]) > 0.05:
                tilting = True
                self.write("... then tilt the cup to pour (A).", 40, size=1.6, color=WARN)
            self.poll()
            time.sleep(1 / 30)

    def countdown(self, seconds: int) -> None:
        """3, 2, 1 in the middle of the window, one second each."""
        for remaining in range(seconds, 0, -1):
            self._call(p.removeAllUserDebugItems)
            self.write("Get ready: the trial starts after the countdown.", 0, size=1.6)
            self.big(str(remaining))
            if remaining == seconds:
                self.notify("countdown")
            time.sleep(1.0)
        self._call(p.removeAllUserDebugItems)

    def start_trial(self, task: str) -> None:
        """GO, and the key help during the trial; starts the real-time clock."""
        self.clear()
        self.highlight(task)
        self._go = self.big("GO", GO)
        self.write(self.controls, self.height - 80, size=1.2)
        self._warning: int | None = None
        self._banner = self._replace(None, self._banner_text(0.0), 30, INK)
        self._clock = time.perf_counter()  # after drawing: the first tick is not late
        self._walls: list[float] = []
        self.rate = self.slowest = 1.0
        self.notify("trial")

    def on_tick(self, t: float, state, keys: frozenset, alpha: float) -> None:
        """The trial's time; keeps real time and measures it.

        ``rate``: simulated over wall time since GO (late ticks are caught up, never run
        ahead); ``slowest``: the slowest 2 s (40 ticks), warned about below :data:`SLOW`.
        """
        dt = self.sim.settings.dt
        now = time.perf_counter()
        self._walls.append(now)
        recent = self._walls[-40:]
        recent_rate = (len(recent) - 1) * dt / max(recent[-1] - recent[0], 1e-9)
        if len(recent) == 40:
            self.slowest = min(self.slowest, recent_rate)
        slow = len(recent) == 40 and recent_rate < SLOW
        # Few drawing calls: each waits for a frame of the window.
        tick = int(round(t / dt))
        if tick == 20:
            self._call(p.removeUserDebugItem, self._go)
        if tick % 20 == 0 and tick > 0:
            self._banner = self._replace(self._banner, self._banner_text(t), 30, INK)
            if slow:
                warning = f"This computer runs slower than real time ({100 * recent_rate:.0f}%)."
                self._warning = self._replace(self._warning, warning, 56, WARN)
        delay = self._clock + t + dt - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        self.rate = (t + dt) / (time.perf_counter() - self._clock)
        if len(self._walls) < 40:  # no 2 s yet: the trial so far is its slowest stretch
            self.slowest = self.rate

    @staticmethod
    def _banner_text(t: float) -> str:
        return f"time {t:3.0f} s          Enter: finished          P: pause"

    def _replace(self, item: int | None, text: str, top: float, color) -> int:
        """One line at pixel row ``top`` in place of ``item``; the new item's id."""
        options = {} if item is None else {"replaceItemUniqueId": item}
        return self._call(
            p.addUserDebugText,
            text,
            self.at(MARGIN, top),
            textColorRGB=color,
            textSize=1.4,
            **options,
        )

    def end_trial(self, message: str) -> None:
        """DONE and ``message`` for a second."""
        self.clear()
        self.big("DONE", GO)
        self.write(message, 0, size=1.6)
        self.notify("end-of-trial")
        time.sleep(1.0)

    def likert(self, statement: str, number: int, total: int) -> int | None:
        """One 7-point question: a number key chooses, Enter confirms; None on P (pause)."""
        self.clear()
        top = self.write(f"Question {number} of {total}", 0, size=1.6)
        top = self.write(statement, top, size=2.0)
        top = self.write("How much do you agree?", top, size=1.4)
        top = self.write(SCALE, top, size=1.2)
        self.write("Press a number from 1 to 7, then Enter.   P: pause", top, color=GO)
        self.poll()
        self.notify("likert")
        chosen, shown = None, None
        while True:
            key = self.wait_key({ENTER, PAUSE, *DIGITS})
            if key == PAUSE:
                return None
            if key == ENTER and chosen is not None:
                return chosen
            if key in DIGITS:
                chosen = DIGITS[key]
                text = f"Your answer: {chosen}   (Enter: confirm; another number: change it)"
                shown = self._replace(shown, text, self.height - 120, GO)

    def resting(self, message: str, fraction: float) -> None:
        """The rest screen while the robot learns: ``message`` and a progress bar.

        Drawn whole when ``message`` changes; else only the bar and its percentage move.
        """
        fresh = self._resting != message
        if fresh:
            self.clear()
            top = self.write("Please rest for a moment.", 0, size=2.0)
            self._bar_top = self.write(message, top) + 30
            self._bar: list[int | None] = [None, None, None]
            self._resting = message
            self._bar[0] = self._line(None, MARGIN, self.width - MARGIN, (1.0, 1.0, 1.0))
        right = MARGIN + (self.width - 2 * MARGIN) * float(np.clip(fraction, 0.005, 1))
        self._bar[1] = self._line(self._bar[1], MARGIN, right, GO)
        self._bar[2] = self._replace(
            self._bar[2], f"{100 * fraction:3.0f}%", self._bar_top + 24, INK
        )
        self.poll()
        if fresh:
            self.notify("learning")

    def _line(self, item: int | None, left: float, right: float, color) -> int:
        """A thick line at the progress bar's row, in place of ``item``."""
        options = {} if item is None else {"replaceItemUniqueId": item}
        top = self._bar_top
        return self._call(
            p.addUserDebugLine, self.at(left, top), self.at(right, top), color, 14, **options
        )

    def pause(self) -> str:
        """The pause screen: ``"continue"`` (C) or, confirmed, ``"abort"`` (Q then Y)."""
        while True:
            self.clear()
            top = self.write("Paused.", 0, size=2.0)
            self.write(
                "C: continue (an interrupted trial starts again from its instructions).\n"
                "Q: stop the session. Everything recorded so far is kept; running the same "
                "command again continues where it stopped.",
                top,
            )
            self.poll()
            self.notify("pause")
            if self.wait_key({CONTINUE, QUIT}) == CONTINUE:
                return "continue"
            self.clear()
            top = self.write("Stop the session now?", 0, size=2.0)
            self.write("Y: yes, stop (what is recorded is kept).   N: no, go back.", top)
            self.poll()
            self.notify("confirm-abort")
            if self.wait_key({YES, NO}) == YES:
                return "abort"

    def message(self, title: str, body: str, kind: str, seconds: float | None = 2.0) -> None:
        """A screen of text for ``seconds``, or until Enter when ``seconds`` is None."""
        self.clear()
        self.write(body, self.write(title, 0, size=2.0))
        self.poll()
        self.notify(kind)
        self.wait_key({ENTER} if seconds is None else set(), seconds=seconds)
