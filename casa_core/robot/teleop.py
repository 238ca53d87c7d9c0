"""``casa teleop``: a person drives the arm from the keyboard in a pybullet window.

The window shows the arm, the table, the goals (green, purple, red) and the pouring
target with its bowl, seen from behind the robot (the scene's window camera,
:mod:`casa_core.robot.camera`), so that the arrow keys move the cup the way they point
on screen. A countdown (3, 2, 1, GO) opens the trial; a banner
tells the time, the held keys and the robot's share of control (1 - alpha); the trial
ends when the person presses Enter (or at ``max_duration``), and the window says
where the log was written. This module holds the window and the keyboard;
:func:`casa_core.study.teleop_session.run_teleop` runs them through the closed loop,
so a window trial and a simulated trial run the same code.

Keys (the window's own keyboard shortcuts are switched off):

=============  =========  ==================================
key            log name   motion
=============  =========  ==================================
Up / Down      x+ / x-    away from / toward the robot base
Left / Right   y+ / y-    left / right on screen
W / S          z+ / z-    up / down
A / D          rot+ / rot- tilt the cup (pour) / back
Enter          --         end the trial
=============  =========  ==================================
"""

from __future__ import annotations

import time

import numpy as np
import pybullet as p

from casa_core.robot.camera import scene_camera
from casa_core.robot.sim import ArmSimulation

#: pybullet key code -> log key name.
KEY_BINDINGS = {
    p.B3G_UP_ARROW: "x+",
    p.B3G_DOWN_ARROW: "x-",
    p.B3G_LEFT_ARROW: "y+",
    p.B3G_RIGHT_ARROW: "y-",
    ord("w"): "z+",
    ord("s"): "z-",
    ord("a"): "rot+",
    ord("d"): "rot-",
}
FINISH_KEYS = (p.B3G_RETURN,)
HELP = "arrow keys: move the cup   W / S: up / down   A / D: tilt to pour / back   Enter: finished"


class KeyLatch:
    """Which keys are held and which were pressed, from successive ``p.getKeyboardEvents``.

    pybullet reports a key pressed and released between two reads as released only
    (``KEY_WAS_RELEASED`` without ``KEY_WAS_TRIGGERED``) when both happen within one of
    its frames: such a release of a key not seen down at the last read counts as a press,
    so that a tap as short as one frame is never lost.

    Examples
    --------
    >>> latch = KeyLatch()
    >>> latch.update({13: p.KEY_WAS_RELEASED})  # a tap whose press pybullet dropped
    (frozenset({13}), frozenset({13}))
    >>> latch.update({65: p.KEY_IS_DOWN | p.KEY_WAS_TRIGGERED})
    (frozenset({65}), frozenset({65}))
    >>> latch.update({65: p.KEY_WAS_RELEASED})  # the end of a held key: no new press
    (frozenset(), frozenset())
    """

    def __init__(self):
        self._down: frozenset[int] = frozenset()

    def update(self, events: dict) -> tuple[frozenset[int], frozenset[int]]:
        """``(held, pressed)`` key codes since the last update."""
        pressed = frozenset(
            code
            for code, state in events.items()
            if state & p.KEY_WAS_TRIGGERED
            or (state & p.KEY_WAS_RELEASED and code not in self._down)
        )
        down = frozenset(code for code, state in events.items() if state & p.KEY_IS_DOWN)
        self._down = down
        return down | pressed, pressed


class KeyboardKeys:
    """Held keys read from a pybullet window with ``p.getKeyboardEvents`` every tick.

    A key counts as held during a tick if it is down or was pressed since the last
    tick (:class:`KeyLatch`: a one-frame tap is not lost). Enter ends the trial
    (``done``); a key of ``pause_keys`` ends it too, with ``paused`` set.
    """

    def __init__(self, client: int, *, pause_keys: tuple[int, ...] = ()):
        self.client = client
        self.done = False
        self.paused = False
        self.pause_keys = pause_keys
        self._latch = KeyLatch()

    def keys(self, t: float, state) -> frozenset[str]:
        events = p.getKeyboardEvents(physicsClientId=self.client)
        held, pressed = self._latch.update(events)
        if pressed.intersection(self.pause_keys):
            self.done = self.paused = True
            return frozenset()
        if pressed.intersection(FINISH_KEYS):
            self.done = True
            return frozenset()
        return frozenset(name for code, name in KEY_BINDINGS.items() if code in held)


class Window:
    """Text banners and real-time pacing in a pybullet window (no-ops when headless)."""

    def __init__(self, sim: ArmSimulation, realtime: bool):
        self.sim = sim
        self.shown = sim.gui
        self.realtime = realtime and sim.gui
        self._texts: dict[str, int] = {}
        self._clock_start = time.perf_counter()
        if self.shown:
            client = sim.client
            p.configureDebugVisualizer(p.COV_ENABLE_KEYBOARD_SHORTCUTS, 0, physicsClientId=client)
            p.configureDebugVisualizer(p.COV_ENABLE_GUI, 0, physicsClientId=client)
            camera = scene_camera(sim.scene, "window")
            p.resetDebugVisualizerCamera(
                cameraDistance=camera.distance,
                cameraYaw=camera.yaw,
                cameraPitch=camera.pitch,
                cameraTargetPosition=list(camera.target),
                physicsClientId=client,
            )

    def say(self, slot: str, text: str, position, size: float = 1.5, color=(0, 0, 0)) -> None:
        """Show ``text`` in the named slot, replacing what the slot showed before."""
        if not self.shown:
            return
        options = {
            "textColorRGB": list(color),
            "textSize": size,
            "physicsClientId": self.sim.client,
        }
        if slot in self._texts:
            options["replaceItemUniqueId"] = self._texts[slot]
        self._texts[slot] = p.addUserDebugText(text, list(position), **options)

    def intro(self, title: str, countdown: int) -> None:
        """Title, key help, then the countdown: 3, 2, 1, GO, one second each."""
        self.say("title", title, [0.3, 0.55, 0.69], size=1.4)
        self.say("help", HELP, [0.3, 0.55, 0.62], size=1.2)
        self.countdown(countdown)

    def finish(self, message: str) -> None:
        """DONE and ``message``, left on screen for two seconds."""
        self.say("big", "DONE", [0.4, 0.1, 0.65], size=4, color=(0.1, 0.3, 0.8))
        self.say("banner", message, [0.3, 0.55, 0.55], size=1.3)
        self._wait(2.0)

    def countdown(self, seconds: int) -> None:
        """3, 2, 1, GO above the table, one second each when paced in real time."""
        for remaining in range(seconds, 0, -1):
            self.say("big", str(remaining), [0.4, 0.1, 0.65], size=4, color=(0.8, 0.1, 0.1))
            self._wait(1.0)
        self.say("big", "GO", [0.4, 0.1, 0.65], size=4, color=(0.1, 0.6, 0.1))
        self._clock_start = time.perf_counter()

    def on_tick(self, t: float, state: np.ndarray, keys: frozenset, alpha: float) -> None:
        """Banner with time, keys and robot authority; keeps 20 Hz in real time."""
        if t >= 1.0 and "big" in self._texts:
            self.say("big", "", [0.4, 0.1, 0.65])
        if int(round(t / self.sim.settings.dt)) % 5 == 0:
            held = " ".join(sorted(keys)) or "-"
            banner = f"t {t:5.1f} s   keys {held}   robot {100 * (1 - alpha):3.0f}%"
            self.say("banner", banner, [0.3, 0.55, 0.55], size=1.3)
        if self.realtime:
            self._wait_until(self._clock_start + t + self.sim.settings.dt)

    def _wait(self, seconds: float) -> None:
        if self.realtime:
            self._wait_until(time.perf_counter() + seconds)

    @staticmethod
    def _wait_until(deadline: float) -> None:
        delay = deadline - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
