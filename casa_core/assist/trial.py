"""The assistant of one trial in a scene: how often it infers and how it is built.

The closed loop (:mod:`casa_core.study.closed_loop`), its ROS 2 twin
(:mod:`casa_core.ros2.loop`) and the replay of a log (:mod:`casa_core.analysis.replay`)
run the same assistant on the same ticks; this module is where that is said once.
"""

from __future__ import annotations

from collections.abc import Sequence

from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import Intent
from casa_core.defaults import DT
from casa_core.scene import Scene


def inference_ticks(scene: Scene) -> int:
    """Control ticks per inference step; ValueError unless ``teleop.dt`` divides ``DT``.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> inference_ticks(load_scene())  # 0.5 s of 0.05 s ticks
    10
    """
    dt = scene.teleop.dt
    ticks = int(round(DT / dt))
    if ticks < 1 or abs(ticks * dt - DT) > 1e-9:
        raise ValueError(
            f"scene: teleop.dt = {dt} s must divide the inference period {DT} s into whole ticks"
        )
    return ticks


def scene_assistant(
    scene: Scene, intents: Sequence[Intent], *, arbitration: str, **options
) -> Assistant:
    """The :class:`Assistant` of a trial in ``scene``: its inference period ``DT``, the
    scene's key speeds and control tick, ``arbitration`` and the other ``options``."""
    teleop = scene.teleop
    return Assistant(
        intents,
        arbitration=arbitration,
        period=DT,
        speed=teleop.speed,
        rot_speed=teleop.rot_speed,
        tick=teleop.dt,
        **options,
    )
